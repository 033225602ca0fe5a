//! `vigil-server` processes on a shared database, and an HTTP client.

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use reqwest::{Response, StatusCode, header};
use serde_json::{Value, json};

/// A `vigil-server` process on a free port, its log in a file.
pub struct Server {
    /// The process.
    pub child: Child,
    /// `http://127.0.0.1:PORT`.
    pub address: String,
    /// Its stderr.
    pub log: std::path::PathBuf,
    client: reqwest::Client,
}

/// A fresh directory for logs.
pub fn log_dir() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("vigil-pg-logs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("log dir");
    dir
}

impl Server {
    /// Starts `vigil-server --database-url url ARGS` and waits until it
    /// listens.
    pub fn start(name: &str, url: &str, args: &[&str]) -> Server {
        let log = log_dir().join(format!("{name}-{}.log", uuid::Uuid::new_v4().simple()));
        let child = Command::new(env!("CARGO_BIN_EXE_vigil-server"))
            .args(["--bind", "127.0.0.1:0", "--database-url", url])
            .args(args)
            .env("RUST_LOG", "info,sqlx=warn")
            .env_remove("VIGIL_API_KEY")
            .env_remove("VIGIL_DATA_DIR")
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&log).expect("log file"))
            .spawn()
            .expect("vigil-server starts");
        let started = Instant::now();
        let mut server = Server {
            child,
            address: String::new(),
            log,
            client: reqwest::Client::builder()
                .timeout(Duration::from_secs(30))
                .build()
                .expect("client"),
        };
        loop {
            let text = std::fs::read_to_string(&server.log).unwrap_or_default();
            if let Some(addr) = text.split("listening on ").nth(1) {
                let addr = addr.lines().next().unwrap_or_default().trim();
                server.address = format!("http://{addr}");
                return server;
            }
            if let Ok(Some(status)) = server.child.try_wait() {
                panic!("vigil-server {name} exited ({status}):\n{text}");
            }
            assert!(
                started.elapsed() < Duration::from_secs(60),
                "vigil-server {name} did not start:\n{text}"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Its log so far.
    pub fn log_text(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    /// `kill -9`.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// GET `path`.
    pub async fn get(&self, path: &str) -> Response {
        self.client
            .get(format!("{}{path}", self.address))
            .send()
            .await
            .expect("GET answered")
    }

    /// DELETE `path`.
    pub async fn delete(&self, path: &str) -> Response {
        self.client
            .delete(format!("{}{path}", self.address))
            .send()
            .await
            .expect("DELETE answered")
    }

    /// POST `body` to `path`.
    pub async fn post(&self, path: &str, body: &Value) -> Response {
        self.client
            .post(format!("{}{path}", self.address))
            .json(body)
            .send()
            .await
            .expect("POST answered")
    }

    /// POST `body` to `path` with an `Idempotency-Key`.
    pub async fn post_with_key(&self, path: &str, body: &Value, key: &str) -> Response {
        self.client
            .post(format!("{}{path}", self.address))
            .header("Idempotency-Key", key)
            .json(body)
            .send()
            .await
            .expect("POST answered")
    }

    /// A one-sensor plan on scenario `id`.
    pub async fn plan(&self, id: &str) -> Response {
        self.post(
            &format!("/v1/scenarios/{id}/plan"),
            &json!({"sensors": [{"id": "a", "x": 15, "y": 15}]}),
        )
        .await
    }

    /// The value of a Prometheus sample named `name`.
    pub async fn metric(&self, name: &str) -> Option<f64> {
        let text = self.get("/metrics").await.text().await.ok()?;
        text.lines()
            .find(|l| l.split(['{', ' ']).next() == Some(name))
            .and_then(|l| l.rsplit(' ').next())
            .and_then(|v| v.parse().ok())
    }
}

impl Server {
    /// The value of the Prometheus sample named `name` whose labels include
    /// `label` (e.g. `reason="idle"`).
    pub async fn metric_with(&self, name: &str, label: &str) -> Option<f64> {
        let text = self.get("/metrics").await.text().await.ok()?;
        text.lines()
            .find(|l| l.split(['{', ' ']).next() == Some(name) && l.contains(label))
            .and_then(|l| l.rsplit(' ').next())
            .and_then(|v| v.parse().ok())
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.kill();
    }
}

/// A small valid spec, distinct for each `n` (a source's rate).
pub fn spec(n: u32) -> Value {
    json!({
        "name": format!("pg-{n}"),
        "zone": {"width": 100, "height": 100}, "cell_size": 10,
        "fov": {"shape": "square", "half_width": 15}, "target_speed": 6,
        "sources": [{"x": -1, "y": 50, "rate": 0.01 * f64::from(n + 1)}, {"x": 50, "y": 101, "rate": 0.2}]
    })
}

/// Status and JSON body of a response.
pub async fn body(res: Response) -> (StatusCode, Value) {
    let status = res.status();
    let text = res.text().await.expect("a body");
    (
        status,
        serde_json::from_str(&text).unwrap_or(Value::String(text)),
    )
}

/// Checks a 503 problem+json that says when to retry.
pub async fn assert_unavailable(res: Response, what: &str) {
    let status = res.status();
    let ct = res
        .headers()
        .get(header::CONTENT_TYPE)
        .map(|v| v.to_str().unwrap_or_default().to_owned())
        .unwrap_or_default();
    let retry = res.headers().get(header::RETRY_AFTER).cloned();
    let text = res.text().await.unwrap_or_default();
    assert_eq!(status, StatusCode::SERVICE_UNAVAILABLE, "{what}: {text}");
    assert_eq!(ct, "application/problem+json", "{what}: {text}");
    assert!(retry.is_some(), "{what}: no Retry-After");
    assert!(text.contains("database-unavailable"), "{what}: {text}");
}
