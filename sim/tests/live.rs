//! The live view in a real browser: a headless Chromium driven through
//! WebDriver (chromedriver, started here on a free port) opens the page of
//! a live run served on a loopback port 0, and the DOM is checked: the step
//! counter advances, every sensor is drawn, the metrics update (`delay`
//! and `missed` among them, once the run defines them), the plan's
//! certified gap is shown, pause stops the counter, step advances it by
//! one, and the `explain` switch draws.
//! A screenshot goes to the target directory.
//!
//! Without a browser this test installs Debian's `chromium` and
//! `chromium-driver` (see `vigil_testenv::chromium`), and FAILS when it
//! cannot. `CHROMEDRIVER` and `CHROMIUM` name other executables.

use std::net::TcpListener as StdListener;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use fantoccini::{ClientBuilder, Locator};
use vigil::scenario::Scenario;
use vigil_sim::client::{Client, spawn_local_server};
use vigil_sim::driver::Start;
use vigil_sim::experiment::RunConfig;
use vigil_sim::live::{Live, LiveOptions};
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
    let vigil_testenv::Browser {
        chromium,
        chromedriver,
    } = vigil_testenv::chromium();
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

    // chromedriver on a free port.
    let port = free_port();
    let _driver = Driver(
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
                     "--hide-scrollbars"],
        }),
    );
    let c = ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
        .capabilities(caps)
        .connect(&webdriver)
        .await
        .expect("a WebDriver session with headless Chromium");

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
