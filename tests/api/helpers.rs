//! Spawning the app and common assertions.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use reqwest::{Response, StatusCode, header};
use serde_json::{Value, json};
use tokio::net::TcpListener;
use vigil::catalog::Registry;
use vigil::http::config::Settings;
use vigil::http::serve::{ConnLimits, serve};
use vigil::http::{AppState, router};

/// A running server and a client for it.
pub struct TestApp {
    /// Base URL, e.g. `http://127.0.0.1:43127`.
    pub address: String,
    /// HTTP client.
    pub client: reqwest::Client,
}

/// Starts the app with default settings on `127.0.0.1:0` in the background
/// of the test's runtime.
pub async fn spawn_app() -> TestApp {
    spawn_with(Settings::default()).await
}

/// Starts the app with the built-ins and `settings` on `127.0.0.1:0`.
pub async fn spawn_with(settings: Settings) -> TestApp {
    spawn_limited(settings, ConnLimits::default()).await
}

/// The same with connection limits `limits`, served as `vigil-server`
/// serves (its accept loop).
pub async fn spawn_limited(settings: Settings, limits: ConnLimits) -> TestApp {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let state = tokio::task::spawn_blocking(move || {
        AppState::with_settings(Registry::with_builtins(), settings)
    })
    .await
    .unwrap();
    tokio::spawn(async move {
        serve(listener, router(state), limits, std::future::pending())
            .await
            .unwrap();
    });
    TestApp {
        address: format!("http://{addr}"),
        client: reqwest::Client::new(),
    }
}

impl TestApp {
    pub fn url(&self, path: &str) -> String {
        format!("{}{path}", self.address)
    }

    pub async fn get(&self, path: &str) -> Response {
        self.client.get(self.url(path)).send().await.unwrap()
    }

    pub async fn delete(&self, path: &str) -> Response {
        self.client.delete(self.url(path)).send().await.unwrap()
    }

    pub async fn post_json(&self, path: &str, body: &Value) -> Response {
        self.client
            .post(self.url(path))
            .json(body)
            .send()
            .await
            .unwrap()
    }

    /// POSTs raw bytes with the given content type (none if `None`).
    pub async fn post_raw(
        &self,
        path: &str,
        content_type: Option<&str>,
        body: Vec<u8>,
    ) -> Response {
        let mut req = self.client.post(self.url(path)).body(body);
        if let Some(ct) = content_type {
            req = req.header(header::CONTENT_TYPE, ct);
        }
        req.send().await.unwrap()
    }

    /// POSTs a plan request to `paper-v10`.
    pub async fn plan(&self, body: &Value) -> Response {
        self.post_json("/v1/scenarios/paper-v10/plan", body).await
    }
}

/// Reads a JSON body after checking the status and content type.
pub async fn json_body(res: Response, status: StatusCode) -> Value {
    let got = res.status();
    let ct = content_type(&res);
    let text = res.text().await.unwrap();
    assert_eq!(got, status, "body: {text}");
    assert_eq!(ct, "application/json", "body: {text}");
    serde_json::from_str(&text).unwrap()
}

/// Checks a problem+json error: status, content type, the four members, and
/// that `detail` mentions `mentions`. Returns the body.
pub async fn assert_problem(res: Response, status: StatusCode, mentions: &str) -> Value {
    let got = res.status();
    let ct = content_type(&res);
    let text = res.text().await.unwrap();
    assert_eq!(got, status, "body: {text}");
    assert_eq!(ct, "application/problem+json", "body: {text}");
    let body: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(body["status"], json!(status.as_u16()), "body: {text}");
    assert!(
        body["type"].as_str().is_some_and(|t| !t.is_empty()),
        "body: {text}"
    );
    assert!(
        body["title"].as_str().is_some_and(|t| !t.is_empty()),
        "body: {text}"
    );
    let detail = body["detail"].as_str().unwrap();
    assert!(
        detail.contains(mentions),
        "detail {detail:?} does not mention {mentions:?}"
    );
    body
}

/// A 422 naming `field` in its detail, with the validation problem type.
pub async fn assert_validation(res: Response, field: &str) {
    let body = assert_problem(res, StatusCode::UNPROCESSABLE_ENTITY, field).await;
    let detail = body["detail"].as_str().unwrap();
    assert!(
        detail.starts_with(&format!("{field}: ")),
        "detail {detail:?} should start with the field {field:?}"
    );
    assert!(body["type"].as_str().unwrap().ends_with("/validation"));
}

fn content_type(res: &Response) -> String {
    res.headers()
        .get(header::CONTENT_TYPE)
        .map(|v| v.to_str().unwrap().to_owned())
        .unwrap_or_default()
}

/// A small valid scenario spec: a 100×100 zone of 10-unit cells, two
/// sources (the OpenAPI document's example).
pub fn small_spec() -> Value {
    vigil::http::doc::examples::small_spec()
}

/// A valid plan request on `paper-v10`: three sensors, a few targets (the
/// OpenAPI document's example).
pub fn plan_request() -> Value {
    vigil::http::doc::examples::plan_request()
}

/// The paths of a plan response, as an evaluate request's `paths`.
pub fn paths_of(plan: &Value) -> Value {
    Value::Array(
        plan["plans"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| {
                json!({
                    "sensor": p["sensor"],
                    "path": p["path"].as_array().unwrap().iter()
                        .map(|c| json!({"col": c["col"], "row": c["row"]}))
                        .collect::<Vec<_>>(),
                })
            })
            .collect(),
    )
}

/// `a` and `b` agree within `rel` relative error.
pub fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

/// A `vigil-server` process on a free port, with its data directory.
pub struct Server {
    pub child: Child,
    pub address: String,
}

impl Server {
    pub fn start(data_dir: &std::path::Path) -> Server {
        Self::start_with(data_dir, &[])
    }

    /// The server with more command-line options.
    pub fn start_with(data_dir: &std::path::Path, args: &[&str]) -> Server {
        let mut child = Command::new(env!("CARGO_BIN_EXE_vigil-server"))
            .args(["--bind", "127.0.0.1:0", "--data-dir"])
            .arg(data_dir)
            .args(args)
            .env("RUST_LOG", "info")
            .env_remove("VIGIL_API_KEY")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("vigil-server starts");
        let stderr = child.stderr.take().expect("stderr");
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut sent = false;
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if !sent && let Some(addr) = line.split("listening on ").nth(1) {
                    let _ = tx.send(addr.trim().to_owned());
                    sent = true;
                }
            }
        });
        let addr = rx
            .recv_timeout(Duration::from_secs(60))
            .expect("the server reports its address");
        Server {
            child,
            address: format!("http://{addr}"),
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A fresh directory under the system's temporary one.
pub fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("vigil-api-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Clock ticks per second of /proc's CPU times (`getconf CLK_TCK`; 100 on
/// Linux).
pub const TICKS_PER_S: f64 = 100.0;

/// The process's CPU time (user + system), seconds, from /proc/PID/stat.
pub fn cpu_seconds(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("/proc/PID/stat");
    // The command name (field 2) may hold spaces: count from after it.
    let rest = &stat[stat.rfind(')').expect("a command name") + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the whole line.
    let ticks: u64 = fields[11].parse::<u64>().unwrap() + fields[12].parse::<u64>().unwrap();
    ticks as f64 / TICKS_PER_S
}

/// Waits until the server has used `busy` seconds of CPU over what it had
/// at `before` (so the plan is running), or panics after 10 s.
pub fn wait_busy(pid: u32, before: f64, busy: f64) {
    let started = Instant::now();
    while cpu_seconds(pid) < before + busy {
        assert!(
            started.elapsed() < Duration::from_secs(10),
            "the plan never ran"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// CPU used between 200 ms and 700 ms after `since`: the work must have
/// stopped by the first reading.
pub fn cpu_after(pid: u32, since: Instant) -> f64 {
    std::thread::sleep(Duration::from_millis(200).saturating_sub(since.elapsed()));
    let a = cpu_seconds(pid);
    std::thread::sleep(Duration::from_millis(500));
    cpu_seconds(pid) - a
}

/// The value of a Prometheus sample of `name` whose labels include every
/// one of `labels` (e.g. `kind="plan"`), 0 if there is none.
pub async fn metric(address: &str, name: &str, labels: &[&str]) -> f64 {
    let text = reqwest::get(format!("{address}/metrics"))
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    text.lines()
        .find(|l| l.split(['{', ' ']).next() == Some(name) && labels.iter().all(|x| l.contains(x)))
        .and_then(|l| l.rsplit(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.0)
}

/// A plan on `paper-v10` that runs for seconds: 256 sensors, horizon 12,
/// iterated coordination, 4 000 targets and 8 steps of history.
pub fn heavy_plan() -> Value {
    let sensors: Vec<Value> = (0..256)
        .map(|i| json!({"id": i, "x": 5.0 + (i % 16) as f64 * 18.0, "y": 5.0 + (i / 16) as f64 * 18.0}))
        .collect();
    let targets: Vec<Value> = (0..4000)
        .map(|i| {
            let f = i as f64;
            json!({"x": (f * 7.3) % 300.0, "y": (f * 13.7) % 300.0, "vx": (f % 7.0) - 3.0, "vy": (f % 5.0) - 2.0})
        })
        .collect();
    let history: Vec<Value> = (1..=8)
        .map(|s| {
            let step: Vec<Value> = (0..256)
                .map(|i| {
                    json!({"x": (5.0 + (i % 16) as f64 * 18.0 + s as f64) % 300.0,
                           "y": 5.0 + (i / 16) as f64 * 18.0})
                })
                .collect();
            json!(step)
        })
        .collect();
    json!({"sensors": sensors, "targets": targets, "history": history, "horizon": 12,
           "coordination": "iterated"})
}
