//! The live view in a real browser: a headless Chromium driven through
//! WebDriver (chromedriver, started here on a free port) opens the page of
//! a live run served on a loopback port 0, and the DOM is checked: the step
//! counter advances, every sensor is drawn, the metrics update (`delay`
//! and `missed` among them, once the run defines them), the plan's
//! certified gap is shown, pause stops the counter, step advances it by
//! one, and the `explain` switch draws. Without obstacles the page gets an
//! empty obstacle list and frames without `view` outlines. On
//! `site-campus` (buildings, screens, ground robots and drones) the init
//! lists the obstacles, each robot's frame outline is what the scenario
//! says it sees (cut by the obstacles, inside its field of view), drones
//! have none, and the canvas paints buildings and screens in their colours.
//! Screenshots go to the target directory (`live-view.png`,
//! `live-obstacles.png`, the latter copied to `docs/obstacles.png`).
//!
//! Without a browser this test installs Debian's `chromium` and
//! `chromium-driver` (see `vigil_testenv::chromium`), and FAILS when it
//! cannot. `CHROMEDRIVER` and `CHROMIUM` name other executables.

use std::net::TcpListener as StdListener;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use fantoccini::{ClientBuilder, Locator};
use serde_json::Value;
use vigil::geometry::Point;
use vigil::obstacle::ObstacleKind;
use vigil::scenario::{Cell, Scenario};
use vigil_sim::client::{Client, spawn_local_server};
use vigil_sim::driver::Start;
use vigil_sim::experiment::RunConfig;
use vigil_sim::live::{Live, LiveOptions, VIEW_RAYS};
use vigil_sim::policy::Policy;

const SENSORS: usize = 6;

/// Kills chromedriver when the test ends, however it ends.
struct Driver(Child);

impl Drop for Driver {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn free_port() -> u16 {
    StdListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free loopback port")
        .port()
}

async fn int_attr(el: &fantoccini::elements::Element, name: &str) -> i64 {
    el.attr(name)
        .await
        .expect("attribute")
        .unwrap_or_default()
        .parse()
        .unwrap_or(-1)
}

async fn step_now(c: &fantoccini::Client) -> i64 {
    let el = c.find(Locator::Id("step")).await.expect("#step");
    int_attr(&el, "data-step").await
}

/// One browser at a time: the tests share a small machine.
static BROWSER: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

/// Starts chromedriver on a free port and opens a WebDriver session with
/// headless Chromium in it; the driver dies with the returned guard.
async fn browser() -> (Driver, fantoccini::Client) {
    let vigil_testenv::Browser {
        chromium,
        chromedriver,
    } = vigil_testenv::chromium();
    let port = free_port();
    let driver = Driver(
        Command::new(&chromedriver)
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", chromedriver.display())),
    );
    let webdriver = format!("http://127.0.0.1:{port}");
    let http = reqwest::Client::new();
    until(20, "chromedriver to answer", || async {
        http.get(format!("{webdriver}/status"))
            .send()
            .await
            .is_ok_and(|r| r.status().is_success())
    })
    .await;

    let mut caps = serde_json::Map::new();
    caps.insert(
        "goog:chromeOptions".into(),
        serde_json::json!({
            "binary": chromium,
            "args": ["--headless=new", "--no-sandbox", "--disable-gpu",
                     "--disable-dev-shm-usage", "--window-size=1240,900",
                     "--hide-scrollbars", "--disable-background-networking",
                     "--disable-component-update", "--disable-sync",
                     "--no-first-run"],
        }),
    );
    let c = ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
        .capabilities(caps)
        .connect(&webdriver)
        .await
        .expect("a WebDriver session with headless Chromium");
    (driver, c)
}

/// `GET {url}{path}` as JSON.
async fn get_json(url: &str, path: &str) -> Value {
    reqwest::get(format!("{url}{path}"))
        .await
        .and_then(|r| r.error_for_status())
        .unwrap_or_else(|e| panic!("GET {path}: {e}"))
        .json()
        .await
        .unwrap_or_else(|e| panic!("GET {path}: {e}"))
}

/// Polls `f` every 50 ms until it holds, for at most `secs`.
async fn until<F, Fut>(secs: u64, what: &str, mut f: F)
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = bool>,
{
    let deadline = Instant::now() + Duration::from_secs(secs);
    while !f().await {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn live_view_in_headless_chromium() {
    let _one = BROWSER.lock().await;
    let started = Instant::now();

    // The live view of a short run, on a loopback port 0.
    let base = spawn_local_server().await.expect("in-process planner");
    let client = Client::new(&base);
    let info = client.scenario("paper-v10").await.expect("paper-v10");
    let scenario = Scenario::new(info.spec).expect("valid scenario");
    let run = RunConfig {
        label: "live".into(),
        policy: Policy::Exact,
        scenario_id: info.id,
        scenario,
        sensors: SENSORS,
        fleet: None,
        steps: 400,
        warmup: 20,
        horizon: None,
        history: 16,
        start: Start::Grid,
        min_separation: None,
        session: false,
        blind: false,
        world_rates: None,
        stationary_start: false,
    };
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0")
        .await
        .expect("loopback listener");
    let live = Live::start(
        listener,
        client,
        LiveOptions {
            run,
            seed: 3,
            speed: 25.0,
        },
    )
    .await
    .expect("live view starts");
    let url = live.url();
    let (_driver, c) = browser().await;

    c.goto(&url).await.expect("page opens");
    // Frames arrive and the counter advances.
    until(30, "the first frames", || async { step_now(&c).await >= 3 }).await;
    let first = step_now(&c).await;
    until(10, "the step counter to advance", || async {
        step_now(&c).await >= first + 5
    })
    .await;

    // Every sensor is drawn, and listed.
    let zone = c.find(Locator::Id("zone")).await.expect("#zone");
    assert_eq!(int_attr(&zone, "data-sensors-drawn").await, SENSORS as i64);

    // No obstacles: none listed or drawn, and the frames carry no outlines
    // (they are as they were before obstacles).
    let init = get_json(&url, "init").await;
    assert_eq!(init["obstacles"], serde_json::json!([]));
    let frame = get_json(&url, "frame").await;
    let sensors = frame["sensors"].as_array().expect("sensors");
    assert_eq!(sensors.len(), SENSORS);
    assert!(sensors.iter().all(|s| s.get("view").is_none()), "{frame}");
    for attr in [
        "data-buildings-drawn",
        "data-screens-drawn",
        "data-views-drawn",
    ] {
        assert_eq!(int_attr(&zone, attr).await, 0, "{attr}");
    }
    let rows = c
        .find_all(Locator::Css("#sensor-table tbody tr.sensor"))
        .await
        .expect("sensor rows");
    assert_eq!(rows.len(), SENSORS);

    // The metrics update: their step follows the counter, the charts grow,
    // and the numbers are numbers.
    let metrics = c.find(Locator::Id("metrics")).await.expect("#metrics");
    let chart = c.find(Locator::Id("c-ad")).await.expect("#c-ad");
    let (m0, p0) = (
        int_attr(&metrics, "data-step").await,
        int_attr(&chart, "data-points").await,
    );
    until(10, "the metrics to update", || async {
        int_attr(&metrics, "data-step").await > m0 && int_attr(&chart, "data-points").await > p0
    })
    .await;
    for id in ["m-ad", "m-ad-mean", "m-af-mean", "m-once", "m-plan"] {
        let text = c
            .find(Locator::Id(id))
            .await
            .expect("metric")
            .text()
            .await
            .expect("text");
        let v: f64 = text
            .parse()
            .unwrap_or_else(|_| panic!("#{id} is not a number: {text:?}"));
        assert!(v.is_finite() && v >= 0.0, "#{id} = {v}");
    }

    // `delay` and `missed` show "–" until a counted target has been
    // detected and one has left the zone (within a zone crossing, a few
    // dozen steps), then numbers, and their charts follow.
    let number = |id: &'static str| {
        let c = &c;
        async move {
            let text = c
                .find(Locator::Id(id))
                .await
                .expect("metric")
                .text()
                .await
                .expect("text");
            text.parse::<f64>().ok()
        }
    };
    until(20, "delay and missed to be defined", || async {
        number("m-delay").await.is_some() && number("m-missed").await.is_some()
    })
    .await;
    let delay = number("m-delay").await.expect("a delay");
    let missed = number("m-missed").await.expect("a fraction missed");
    assert!(delay.is_finite() && delay >= 0.0, "#m-delay = {delay}");
    assert!((0.0..=1.0).contains(&missed), "#m-missed = {missed}");
    for id in ["c-delay", "c-missed"] {
        let chart = c.find(Locator::Id(id)).await.expect("chart");
        assert!(int_attr(&chart, "data-points").await >= 1, "#{id}");
    }

    // An exact plan carries its certificate: the page shows each step's
    // certified gap as a percentage, the one in the frame, and charts it.
    for id in ["m-gap", "m-gap-mean"] {
        let text = c
            .find(Locator::Id(id))
            .await
            .expect("gap")
            .text()
            .await
            .expect("text");
        let v: f64 = text
            .strip_suffix('%')
            .and_then(|t| t.parse().ok())
            .unwrap_or_else(|| panic!("#{id} is not a percentage: {text:?}"));
        assert!((0.0..=100.0).contains(&v), "#{id} = {v}%");
    }
    let gap_chart = c.find(Locator::Id("c-gap")).await.expect("#c-gap");
    assert!(int_attr(&gap_chart, "data-points").await >= 2);

    // Pause stops the counter.
    c.find(Locator::Id("pause"))
        .await
        .expect("#pause")
        .click()
        .await
        .expect("click pause");
    until(5, "the page to show paused", || async {
        c.find(Locator::Id("pause"))
            .await
            .expect("#pause")
            .attr("data-paused")
            .await
            .ok()
            .flatten()
            .as_deref()
            == Some("true")
    })
    .await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    let paused_at = step_now(&c).await;
    tokio::time::sleep(Duration::from_millis(1200)).await;
    assert_eq!(
        step_now(&c).await,
        paused_at,
        "the counter moved while paused"
    );

    // Step advances it by exactly one.
    c.find(Locator::Id("step-once"))
        .await
        .expect("#step-once")
        .click()
        .await
        .expect("click step");
    until(5, "one step", || async {
        step_now(&c).await == paused_at + 1
    })
    .await;
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert_eq!(step_now(&c).await, paused_at + 1, "step did more than one");

    // Paused, the page holds still: the gap shown is the frame's, the one
    // the plan response carried (`bound.gap`), as a percentage.
    let gap = c.find(Locator::Id("m-gap")).await.expect("#m-gap");
    let raw: f64 = gap
        .attr("data-gap")
        .await
        .expect("attribute")
        .and_then(|g| g.parse().ok())
        .expect("the frame's gap");
    assert!((0.0..=1.0).contains(&raw), "gap {raw}");
    let shown = gap.text().await.expect("text");
    let pct: f64 = shown
        .strip_suffix('%')
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("#m-gap is not a percentage: {shown:?}"));
    assert!(
        (pct - 100.0 * raw).abs() <= 0.0005 + 1e-9,
        "{shown} for {raw}"
    );

    // The explain switch draws sensor 0's search values.
    c.find(Locator::Id("explain"))
        .await
        .expect("#explain")
        .click()
        .await
        .expect("click explain");
    until(5, "the explain heat map", || async {
        int_attr(&zone, "data-explain-drawn").await == 1
    })
    .await;

    let png = c.screenshot().await.expect("screenshot");
    assert!(png.starts_with(b"\x89PNG"), "not a PNG");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("live-view.png");
    std::fs::write(&out, &png).expect("screenshot written");
    eprintln!("live view screenshot: {}", out.display());

    c.close().await.expect("session closes");
    live.shutdown().await.expect("live view stops cleanly");
    eprintln!("browser test took {:.1} s", started.elapsed().as_secs_f64());
}

/// A polygon's signed area (shoelace), positive counter-clockwise.
fn area(points: &[Point]) -> f64 {
    let n = points.len();
    (0..n)
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % n]);
            a.x * b.y - b.x * a.y
        })
        .sum::<f64>()
        / 2.0
}

/// The page's canvas pixels `[r, g, b, a]` at zone points, through the
/// page's own zone-to-canvas mapping, with only its still layer drawn (the
/// heat map, no-go zones, cones, obstacles and sources: nothing that moves
/// covers them); the page then draws its frame again.
async fn still_pixels(c: &fantoccini::Client, points: &[(f64, f64)]) -> Vec<[u8; 4]> {
    let v = c
        .execute(
            "const [points] = arguments;
             drawStatic();
             const g = document.getElementById('zone').getContext('2d');
             const out = points.map(([x, y]) =>
               Array.from(g.getImageData(Math.round(px(x)), Math.round(py(y)), 1, 1).data));
             dirty = true;
             return out;",
            vec![serde_json::json!(points)],
        )
        .await
        .expect("canvas pixels");
    serde_json::from_value(v).expect("four bytes each")
}

const ROBOTS: usize = 5;
const DRONES: usize = 2;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn live_view_draws_obstacles_and_views() {
    let _one = BROWSER.lock().await;
    let started = Instant::now();
    let base = spawn_local_server().await.expect("in-process planner");
    let client = Client::new(&base);
    let info = client.scenario("site-campus").await.expect("site-campus");
    let scenario = Scenario::new(info.spec).expect("valid scenario");
    let sensors = ROBOTS + DRONES;
    let run = RunConfig {
        label: "live-obstacles".into(),
        policy: Policy::Exact,
        scenario_id: info.id,
        scenario: scenario.clone(),
        sensors,
        fleet: Some(format!("robot:{ROBOTS},drone:{DRONES}")),
        steps: 400,
        warmup: 20,
        horizon: None,
        history: 16,
        start: Start::Grid,
        min_separation: None,
        session: false,
        blind: false,
        world_rates: None,
        stationary_start: false,
    };
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0")
        .await
        .expect("loopback listener");
    let live = Live::start(
        listener,
        client,
        LiveOptions {
            run,
            seed: 1,
            speed: 40.0,
        },
    )
    .await
    .expect("live view starts");
    let url = live.url();

    // The init lists the scenario's obstacles: their kinds and vertices.
    let init = get_json(&url, "init").await;
    let listed = init["obstacles"].as_array().expect("obstacles");
    let obstacles = scenario.obstacles.list();
    assert_eq!(listed.len(), 12);
    assert_eq!(listed.len(), obstacles.len());
    let kinds: Vec<&str> = listed.iter().map(|o| o["kind"].as_str().unwrap()).collect();
    assert_eq!(kinds, [["building"; 8].as_slice(), &["screen"; 4]].concat());
    for (o, want) in listed.iter().zip(obstacles) {
        let got: Vec<[f64; 2]> = serde_json::from_value(o["polygon"].clone()).expect("[x, y]s");
        let want: Vec<[f64; 2]> = want.polygon.vertices().iter().map(|v| [v.x, v.y]).collect();
        assert_eq!(got, want);
    }

    let (_driver, c) = browser().await;
    c.goto(&url).await.expect("page opens");
    until(60, "fifteen steps", || async { step_now(&c).await >= 15 }).await;
    c.find(Locator::Id("pause"))
        .await
        .expect("#pause")
        .click()
        .await
        .expect("click pause");
    until(5, "the page to show paused", || async {
        c.find(Locator::Id("pause"))
            .await
            .expect("#pause")
            .attr("data-paused")
            .await
            .ok()
            .flatten()
            .as_deref()
            == Some("true")
    })
    .await;
    // Paused, the frame served is the one the page draws. Where the run
    // paused depends on timing: step on, one at a time, to a frame in
    // which some robot's view is cut by an obstacle.
    tokio::time::sleep(Duration::from_millis(300)).await;
    let mut frame = get_json(&url, "frame").await;
    let cut_view = |frame: &Value| {
        frame["sensors"]
            .as_array()
            .expect("sensors")
            .iter()
            .any(|s| {
                let cell = Cell {
                    col: s["col"].as_i64().unwrap() as i32,
                    row: s["row"].as_i64().unwrap() as i32,
                };
                let ty = scenario.type_index(s["type"].as_str().unwrap()).unwrap();
                let look = scenario.look(ty, cell);
                let r = look.region.rect;
                look.from.is_some()
                    && area(&scenario.view_outline(&look, VIEW_RAYS))
                        < 0.9 * (r.x1 - r.x0) * (r.y1 - r.y0)
            })
    };
    for _ in 0..100 {
        if cut_view(&frame) {
            break;
        }
        let before = frame["step"].as_i64().unwrap();
        reqwest::Client::new()
            .post(format!("{url}control"))
            .json(&serde_json::json!({"action": "step"}))
            .send()
            .await
            .and_then(|r| r.error_for_status())
            .expect("POST control step");
        let deadline = Instant::now() + Duration::from_secs(10);
        while frame["step"].as_i64().unwrap() == before {
            assert!(Instant::now() < deadline, "timed out waiting for a step");
            tokio::time::sleep(Duration::from_millis(20)).await;
            frame = get_json(&url, "frame").await;
        }
    }
    until(5, "the page to draw the last frame", || async {
        step_now(&c).await == frame["step"].as_i64().unwrap()
    })
    .await;

    // Each robot's outline is what it sees from its cell, as the scenario
    // computes it (so inside its field of view and cut by the obstacles);
    // the drones see over everything and have none.
    let out = frame["sensors"].as_array().expect("sensors");
    assert_eq!(out.len(), sensors);
    let mut cut = 0;
    for (i, s) in out.iter().enumerate() {
        let cell = Cell {
            col: s["col"].as_i64().unwrap() as i32,
            row: s["row"].as_i64().unwrap() as i32,
        };
        let ty = scenario
            .type_index(s["type"].as_str().unwrap())
            .expect("a type of the scenario");
        let look = scenario.look(ty, cell);
        if i >= ROBOTS {
            assert!(look.from.is_none(), "drone {i} is elevated");
            assert!(s.get("view").is_none(), "drone {i}: {s}");
            continue;
        }
        assert!(look.from.is_some(), "robot {i} is a ground sensor");
        let flat: Vec<f64> = serde_json::from_value(s["view"].clone())
            .unwrap_or_else(|e| panic!("robot {i} has no view: {e}: {s}"));
        assert_eq!(flat.len(), 2 * VIEW_RAYS, "robot {i}");
        let view: Vec<Point> = flat.chunks(2).map(|p| Point::new(p[0], p[1])).collect();
        let want = scenario.view_outline(&look, VIEW_RAYS);
        let r = look.region.rect;
        for (k, (p, q)) in view.iter().zip(&want).enumerate() {
            assert!(
                (p.x - q.x).abs() <= 0.0051 && (p.y - q.y).abs() <= 0.0051,
                "robot {i}, point {k}: {p:?}, not {q:?}"
            );
            assert!(
                p.x >= r.x0 - 0.006
                    && p.x <= r.x1 + 0.006
                    && p.y >= r.y0 - 0.006
                    && p.y <= r.y1 + 0.006,
                "robot {i}, point {k}: {p:?} outside its field of view {r:?}"
            );
        }
        let a = area(&view);
        let full = (r.x1 - r.x0) * (r.y1 - r.y0);
        assert!(
            a > 0.0 && a <= full * 1.0001,
            "robot {i}: area {a} of {full}"
        );
        cut += usize::from(a < 0.9 * full);
    }
    assert!(cut >= 1, "no robot's view is cut by an obstacle");

    // The canvas: every obstacle and every robot's view drawn; at each
    // obstacle's centre the building grey or the screens' green, which
    // neither the heat map nor the cones are (the zone's middle, in the
    // open, is neither).
    let zone = c.find(Locator::Id("zone")).await.expect("#zone");
    assert_eq!(int_attr(&zone, "data-buildings-drawn").await, 8);
    assert_eq!(int_attr(&zone, "data-screens-drawn").await, 4);
    assert_eq!(int_attr(&zone, "data-views-drawn").await, ROBOTS as i64);
    assert_eq!(int_attr(&zone, "data-sensors-drawn").await, sensors as i64);
    let building = |[r, g, b, a]: [u8; 4]| {
        r.abs_diff(90) <= 3 && g.abs_diff(90) <= 3 && b.abs_diff(100) <= 3 && a == 255
    };
    let green = |[r, g, b, _]: [u8; 4]| g > r.saturating_add(10) && g > b.saturating_add(10);
    let mut points: Vec<(f64, f64)> = obstacles
        .iter()
        .map(|o| {
            let v = o.polygon.vertices();
            let n = v.len() as f64;
            (
                v.iter().map(|p| p.x).sum::<f64>() / n,
                v.iter().map(|p| p.y).sum::<f64>() / n,
            )
        })
        .collect();
    points.push((200.0, 150.0));
    let pixels = still_pixels(&c, &points).await;
    for ((o, p), &px) in obstacles.iter().zip(&points).zip(&pixels) {
        match o.kind {
            ObstacleKind::Building => assert!(building(px), "building at {p:?}: {px:?}"),
            ObstacleKind::Screen => assert!(green(px), "screen at {p:?}: {px:?}"),
        }
    }
    let open = pixels[obstacles.len()];
    assert!(!building(open) && !green(open), "the open ground: {open:?}");

    // Tall enough for the legend, for docs/obstacles.png.
    c.set_window_size(1240, 1010).await.expect("window resized");
    tokio::time::sleep(Duration::from_millis(200)).await;
    let png = c.screenshot().await.expect("screenshot");
    assert!(png.starts_with(b"\x89PNG"), "not a PNG");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("live-obstacles.png");
    std::fs::write(&out, &png).expect("screenshot written");
    eprintln!("live view screenshot: {}", out.display());

    c.close().await.expect("session closes");
    live.shutdown().await.expect("live view stops cleanly");
    eprintln!(
        "obstacle test took {:.1} s",
        started.elapsed().as_secs_f64()
    );
}
