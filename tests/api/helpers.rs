//! Spawning the app and common assertions.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use reqwest::{Response, StatusCode, header};
use serde_json::{Value, json};
use tokio::net::TcpListener;
use vigil::http::config::Settings;
use vigil::http::serve::{ConnLimits, serve};
use vigil::http::{AppState, Registry, router};

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
    vigil::http::openapi::examples::small_spec()
}

/// A valid plan request on `paper-v10`: three sensors, a few targets (the
/// OpenAPI document's example).
pub fn plan_request() -> Value {
    vigil::http::openapi::examples::plan_request()
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
