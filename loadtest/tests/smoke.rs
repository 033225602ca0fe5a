//! Smoke tests of the load generator: short, low-rate, loopback runs
//! against the app in process and against tiny fake servers, plus the
//! binary's output and error handling.

#![allow(clippy::unwrap_used)]

use std::collections::BTreeSet;
use std::process::Output;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use axum::Router;
use axum::http::StatusCode;
use axum::routing::get;
use tokio::net::TcpListener;
use vigil::catalog::Registry;
use vigil::http::config::Settings;
use vigil::http::{AppState, router};
use vigil_loadtest::generator::{RunConfig, RunReport, Summary, Target, run};
use vigil_loadtest::requests;
use vigil_loadtest::schedule::Arrivals;
use vigil_loadtest::workload::Workload;

/// Starts the Vigil app (built-ins, default settings) on `127.0.0.1:0`.
async fn spawn_vigil() -> String {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let state = tokio::task::spawn_blocking(|| {
        AppState::with_settings(Registry::with_builtins(), Settings::default())
    })
    .await
    .unwrap();
    tokio::spawn(async move {
        axum::serve(listener, router(state)).await.unwrap();
    });
    format!("http://{addr}")
}

/// Starts `app` on `127.0.0.1:0`.
async fn spawn_router(app: Router) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    tokio::spawn(async move {
        axum::serve(listener, app).await.unwrap();
    });
    format!("http://{addr}")
}

/// A handful of small generated requests: 4 sensors, 4 steps of history.
fn small_requests() -> Vec<vigil::planner::PlanRequest> {
    let planner = requests::planner_for("paper-v10").unwrap();
    let w = Workload {
        sensors: 4,
        history: 4,
        horizon: 3,
        seed: 5,
    };
    requests::generate(&planner, &w, requests::Fleet::Default, 6).unwrap()
}

fn config(target: Target, rate: f64, arrivals: Arrivals, duration_ms: u64) -> RunConfig {
    RunConfig {
        target,
        rate,
        arrivals,
        duration: Duration::from_millis(duration_ms),
        warmup: Duration::ZERO,
        connections: 4,
        seed: 11,
        timeout: Duration::from_secs(10),
        api_key: None,
    }
}

fn assert_ordered(s: &Summary) {
    assert!(s.p50_ms > 0.0, "{s:?}");
    assert!(s.p50_ms <= s.p90_ms, "{s:?}");
    assert!(s.p90_ms <= s.p99_ms, "{s:?}");
    assert!(s.p99_ms <= s.p999_ms, "{s:?}");
    assert!(s.p999_ms <= s.max_ms, "{s:?}");
}

/// Runs the binary with `args`, off the runtime's threads.
async fn bin(args: Vec<String>) -> Output {
    tokio::task::spawn_blocking(move || {
        std::process::Command::new(env!("CARGO_BIN_EXE_vigil-loadtest"))
            .args(&args)
            .output()
            .unwrap()
    })
    .await
    .unwrap()
}

fn args(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| (*s).to_owned()).collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn constant_run_against_the_app_meets_its_rate_without_errors() {
    let url = spawn_vigil().await;
    let bodies = requests::bodies(&small_requests()).unwrap();
    let mut cfg = config(
        Target::plan(&url, "paper-v10", bodies).unwrap(),
        50.0,
        Arrivals::Constant,
        2000,
    );
    cfg.warmup = Duration::from_millis(500);
    let r: RunReport = run(&cfg).await.unwrap();
    let s = r.summary;
    assert_eq!(s.errors, 0, "{}", r.describe());
    assert_eq!(s.shed, 0, "{}", r.describe());
    // Constant spacing: exactly 50/s × 2 s intended in the window, and the
    // warm-up's 25 sent but not counted.
    assert_eq!(s.requests, 100, "{}", r.describe());
    assert_eq!(r.ok, 100);
    assert_eq!(r.latency.len(), 100);
    assert_eq!(r.sent, 125);
    // The window's duration is stretched only by the last response's
    // latency beyond the last gap (20 ms): a few percent at most.
    assert!(s.duration_s >= 2.0 && s.duration_s < 2.1, "{s:?}");
    assert!(
        s.achieved_rate > 50.0 / 1.05 && s.achieved_rate <= 50.0,
        "{s:?}"
    );
    assert_ordered(&s);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn poisson_run_through_the_binary_writes_exactly_the_required_fields() {
    let url = spawn_vigil().await;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.json");
    let rate = 100.0;
    let secs = 2.0;
    let o = bin(args(&[
        "--url",
        &url,
        "--rate",
        "100",
        "--duration",
        "2s",
        "--warmup",
        "300ms",
        "--connections",
        "4",
        "--arrivals",
        "poisson",
        "--sensors",
        "4",
        "--history",
        "4",
        "--count",
        "6",
        "--seed",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]))
    .await;
    let stderr = String::from_utf8_lossy(&o.stderr);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "stdout: {stdout}\nstderr: {stderr}");
    assert!(stdout.contains("p99"), "{stdout}");

    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let keys: BTreeSet<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    let want: BTreeSet<&str> = [
        "target_rate",
        "achieved_rate",
        "duration_s",
        "requests",
        "errors",
        "shed",
        "p50_ms",
        "p90_ms",
        "p99_ms",
        "p999_ms",
        "max_ms",
    ]
    .into_iter()
    .collect();
    assert_eq!(keys, want);
    let s: Summary = serde_json::from_value(v).unwrap();
    assert_eq!(s.target_rate, rate);
    assert_eq!(s.errors, 0, "{stdout}");
    assert_eq!(s.shed, 0, "{stdout}");
    // The count of a Poisson process over the window: mean rate·secs, sd
    // its square root; 4.5 sd either side.
    let mean = rate * secs;
    let n = s.requests as f64;
    assert!((n - mean).abs() <= 4.5 * mean.sqrt(), "{s:?}");
    assert!(s.duration_s >= secs && s.duration_s < secs * 1.05, "{s:?}");
    assert!((s.achieved_rate - n / s.duration_s).abs() < 1e-9, "{s:?}");
    let sd_rate = mean.sqrt() / secs;
    assert!(
        (s.achieved_rate - rate).abs() <= 4.5 * sd_rate + 0.05 * rate,
        "{s:?}"
    );
    assert_ordered(&s);
}

/// A server that takes 50 ms per request, served over one connection at
/// 100 requests per second: it can do 20/s, so requests queue in the
/// generator. Measured from when a connection took them they would all be
/// ~50 ms; measured from their intended time, request i waits for the i
/// before it: 50·(i+1) − 10·i ms.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn queueing_in_the_generator_counts_no_coordinated_omission() {
    let app = Router::new().route(
        "/healthz",
        get(|| async {
            tokio::time::sleep(Duration::from_millis(50)).await;
            "ok"
        }),
    );
    let url = spawn_router(app).await;
    let mut cfg = config(Target::healthz(&url), 100.0, Arrivals::Constant, 500);
    cfg.connections = 1;
    let t = Instant::now();
    let r = run(&cfg).await.unwrap();
    let s = r.summary;
    assert_eq!(s.requests, 50, "{}", r.describe());
    assert_eq!(s.errors, 0, "{}", r.describe());
    // Service time 50 ms; the waits push the median to ~1 s and p99 to ~2 s.
    assert!(s.p50_ms > 800.0 && s.p50_ms < 1400.0, "{}", r.describe());
    assert!(s.p99_ms > 1700.0, "{}", r.describe());
    assert!(s.max_ms < 3000.0, "{}", r.describe());
    assert!(r.latency.min() >= 50_000, "{}", r.describe());
    // The waits are in the send-wait histogram too.
    assert!(
        r.send_wait.value_at_quantile(0.99) > 1_500_000,
        "{}",
        r.describe()
    );
    // Throughput is the server's, 20/s, not the offered 100/s.
    assert!(s.achieved_rate > 17.0 && s.achieved_rate < 23.0, "{s:?}");
    assert!(t.elapsed() < Duration::from_secs(4));
}

/// A request that has waited past the timeout is an error, and the run
/// ends about one timeout after the last intended time.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn requests_past_the_timeout_are_errors_and_the_run_is_bounded() {
    let app = Router::new().route(
        "/healthz",
        get(|| async {
            tokio::time::sleep(Duration::from_millis(50)).await;
            "ok"
        }),
    );
    let url = spawn_router(app).await;
    let mut cfg = config(Target::healthz(&url), 100.0, Arrivals::Constant, 500);
    cfg.connections = 1;
    cfg.timeout = Duration::from_millis(300);
    let t = Instant::now();
    let r = run(&cfg).await.unwrap();
    assert!(
        t.elapsed() < Duration::from_millis(1500),
        "{:?}",
        t.elapsed()
    );
    let s = r.summary;
    assert_eq!(s.requests, 50);
    assert!(s.errors >= 30, "{}", r.describe());
    assert_eq!(r.timeouts, s.errors);
    assert_eq!(r.ok + s.errors, 50);
    assert!(s.max_ms <= 300.0 * 1.01, "{}", r.describe());
}

/// 503 is shed, other non-2xx statuses are errors, neither is in the
/// latency histogram.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn statuses_are_sorted_into_ok_shed_and_errors() {
    let n = Arc::new(AtomicU64::new(0));
    let app = Router::new().route(
        "/healthz",
        get(move || {
            let i = n.fetch_add(1, Ordering::SeqCst);
            async move {
                match i % 4 {
                    0 => StatusCode::SERVICE_UNAVAILABLE,
                    1 => StatusCode::INTERNAL_SERVER_ERROR,
                    _ => StatusCode::OK,
                }
            }
        }),
    );
    let url = spawn_router(app).await;
    let mut cfg = config(Target::healthz(&url), 100.0, Arrivals::Constant, 500);
    cfg.connections = 1;
    let r = run(&cfg).await.unwrap();
    let s = r.summary;
    assert_eq!(s.requests, 50);
    assert_eq!(s.shed, 13, "{}", r.describe());
    assert_eq!(s.errors, 13, "{}", r.describe());
    assert_eq!(r.status_errors, 13);
    assert_eq!(r.ok, 24);
    assert_eq!(r.latency.len(), 24);
    assert!(r.describe().contains("500"), "{}", r.describe());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sweep_climbs_to_the_max_and_writes_steps_and_knee() {
    let url = spawn_vigil().await;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep.json");
    let o = bin(args(&[
        "--url",
        &url,
        "--endpoint",
        "healthz",
        "--sweep",
        "--sweep-start",
        "50",
        "--sweep-factor",
        "2",
        "--sweep-max",
        "200",
        "--sweep-pause",
        "100ms",
        "--duration",
        "500ms",
        "--warmup",
        "100ms",
        "--arrivals",
        "constant",
        "--slo-ms",
        "1000",
        "--sweep-min-achieved",
        "0.8",
        "--out",
        out.to_str().unwrap(),
    ]))
    .await;
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "stdout: {stdout}\nstderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(stdout.contains("knee: 200.0/s"), "{stdout}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let steps = v["steps"].as_array().unwrap();
    let rates: Vec<f64> = steps
        .iter()
        .map(|s| s["target_rate"].as_f64().unwrap())
        .collect();
    assert_eq!(rates, [50.0, 100.0, 200.0]);
    assert_eq!(v["knee_rate"].as_f64(), Some(200.0));
    assert_eq!(v["knee"]["target_rate"].as_f64(), Some(200.0));
    assert_eq!(v["slo_ms"].as_f64(), Some(1000.0));
    for s in steps {
        let s: Summary = serde_json::from_value(s.clone()).unwrap();
        assert_eq!((s.errors, s.shed), (0, 0));
        assert_ordered(&s);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn gen_and_inproc_share_a_requests_file() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("reqs.jsonl");
    let json = dir.path().join("inproc.json");
    let o = bin(args(&[
        "gen",
        "--sensors",
        "4",
        "--history",
        "4",
        "--count",
        "5",
        "--out",
        file.to_str().unwrap(),
    ]))
    .await;
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let reqs = requests::load(&file).unwrap();
    assert_eq!(reqs.len(), 5);
    assert!(reqs.iter().all(|r| r.sensors.len() == 4));
    assert!(
        reqs.iter()
            .all(|r| r.history.as_ref().map(Vec::len) == Some(4))
    );

    let o = bin(args(&[
        "inproc",
        "--requests",
        file.to_str().unwrap(),
        "--iterations",
        "50",
        "--out",
        json.to_str().unwrap(),
    ]))
    .await;
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["iterations"], 50);
    assert_eq!(v["requests"], 5);
    assert!(v["median_ms"].as_f64().unwrap() > 0.0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_exits_non_zero_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "[{\"sensors\": 3}]").unwrap();
    let missing = dir.path().join("missing.json");
    let url = spawn_vigil().await;
    // A port nobody listens on.
    let closed = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        format!("http://{}", l.local_addr().unwrap())
    };
    let good = dir.path().join("good.json");
    std::fs::write(&good, r#"[{"sensors":[{"id":"a","x":15,"y":15}]}]"#).unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            args(&["--url", &url, "--requests", missing.to_str().unwrap()]),
            "cannot read the requests file",
        ),
        (
            args(&["--url", &url, "--requests", bad.to_str().unwrap()]),
            "element 0 is not a plan request",
        ),
        (
            args(&["--url", &closed, "--endpoint", "healthz"]),
            "cannot reach",
        ),
        (args(&["--url", "not a url"]), "--url"),
        (
            args(&[
                "--url",
                &url,
                "--scenario",
                "nope",
                "--requests",
                good.to_str().unwrap(),
            ]),
            "404",
        ),
        (
            args(&["gen", "--scenario", "nope", "--out", "x.json"]),
            "unknown scenario",
        ),
        (
            args(&["--url", &url, "--endpoint", "healthz", "--rate", "0"]),
            "rate",
        ),
        (
            args(&["--url", &url, "--endpoint", "healthz", "--connections", "0"]),
            "--connections",
        ),
    ];
    for (a, want) in cases {
        let o = bin(a.clone()).await;
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{a:?}: {stderr}");
        assert!(stderr.contains("error"), "{a:?}: {stderr}");
        assert!(stderr.contains(want), "{a:?}: want {want:?} in {stderr}");
        assert!(!stderr.contains("panicked"), "{a:?}: {stderr}");
    }
}
