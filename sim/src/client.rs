//! The planner's HTTP client, and an in-process server for one-command runs.

use std::time::{Duration, Instant};

use serde::de::DeserializeOwned;
use vigil::http::sessions::{SessionInfo, StepResponse};
use vigil::planner::{PlanRequest, PlanResponse};
use vigil::scenario::ScenarioSpec;
use vigil::session::{SessionSettings, StepRequest};

/// A failed call to the planner.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// The request did not complete.
    #[error("request to {url} failed: {source}")]
    Transport {
        /// The URL called.
        url: String,
        /// What went wrong.
        source: reqwest::Error,
    },
    /// The server answered with an error status.
    #[error("{url} answered {status}: {body}")]
    Status {
        /// The URL called.
        url: String,
        /// The HTTP status.
        status: u16,
        /// The problem+json body.
        body: String,
    },
}

/// A client of one Vigil server.
#[derive(Debug, Clone)]
pub struct Client {
    base: String,
    http: reqwest::Client,
}

/// A scenario as the server describes it.
#[derive(Debug, Clone, serde::Deserialize)]
pub struct ScenarioInfo {
    /// Its id on the server.
    pub id: String,
    /// Its canonical spec.
    pub spec: ScenarioSpec,
    /// `ready`, or `queued` / `precomputing` while the server precomputes
    /// it as a job (absent from servers that predate jobs: ready).
    #[serde(default)]
    pub status: Option<String>,
    /// Share of the precomputation done.
    #[serde(default)]
    pub progress: Option<f64>,
    /// Estimated seconds until it is ready.
    #[serde(default)]
    pub eta_s: Option<f64>,
}

impl ScenarioInfo {
    /// True once plans on it are served.
    pub fn is_ready(&self) -> bool {
        self.status.as_deref().is_none_or(|s| s == "ready")
    }
}

impl Client {
    /// A client of the server at `base` (e.g. `http://127.0.0.1:8080`).
    pub fn new(base: &str) -> Self {
        Client {
            base: base.trim_end_matches('/').to_owned(),
            http: reqwest::Client::builder()
                .timeout(Duration::from_secs(60))
                .build()
                .unwrap_or_default(),
        }
    }

    async fn send<T: DeserializeOwned>(
        &self,
        url: String,
        req: reqwest::RequestBuilder,
    ) -> Result<T, ClientError> {
        let resp = req.send().await.map_err(|source| ClientError::Transport {
            url: url.clone(),
            source,
        })?;
        let status = resp.status();
        if !status.is_success() {
            let body = resp.text().await.unwrap_or_default();
            return Err(ClientError::Status {
                url,
                status: status.as_u16(),
                body,
            });
        }
        resp.json()
            .await
            .map_err(|source| ClientError::Transport { url, source })
    }

    /// `GET /v1/scenarios/{id}`.
    pub async fn scenario(&self, id: &str) -> Result<ScenarioInfo, ClientError> {
        let url = format!("{}/v1/scenarios/{id}", self.base);
        self.send(url.clone(), self.http.get(&url)).await
    }

    /// `POST /v1/scenarios`: registers a spec (or finds it registered).
    pub async fn register(&self, spec: &ScenarioSpec) -> Result<ScenarioInfo, ClientError> {
        let url = format!("{}/v1/scenarios", self.base);
        self.send(url.clone(), self.http.post(&url).json(spec))
            .await
    }

    /// Polls `GET /v1/scenarios/{id}` until the scenario is ready (a large
    /// one is precomputed as a job), at most once a second, calling
    /// `report` with each pending status.
    pub async fn wait_ready(
        &self,
        mut info: ScenarioInfo,
        mut report: impl FnMut(&ScenarioInfo),
    ) -> Result<ScenarioInfo, ClientError> {
        while !info.is_ready() {
            report(&info);
            let wait = info.eta_s.unwrap_or(1.0).clamp(0.05, 1.0);
            tokio::time::sleep(std::time::Duration::from_secs_f64(wait)).await;
            info = self.scenario(&info.id).await?;
        }
        Ok(info)
    }

    /// `POST /v1/scenarios/{id}/plan`, with its round-trip time in ms.
    pub async fn plan(
        &self,
        id: &str,
        req: &PlanRequest,
    ) -> Result<(PlanResponse, f64), ClientError> {
        let url = format!("{}/v1/scenarios/{id}/plan", self.base);
        let started = Instant::now();
        let resp = self
            .send(url.clone(), self.http.post(&url).json(req))
            .await?;
        Ok((resp, started.elapsed().as_secs_f64() * 1e3))
    }

    /// `POST /v1/sessions` on a registered scenario with `settings`.
    pub async fn open_session(
        &self,
        scenario_id: &str,
        settings: &SessionSettings,
    ) -> Result<SessionInfo, ClientError> {
        let url = format!("{}/v1/sessions", self.base);
        let mut body = serde_json::to_value(settings).unwrap_or_default();
        if let serde_json::Value::Object(fields) = &mut body {
            fields.insert("scenario_id".into(), scenario_id.into());
        }
        self.send(url.clone(), self.http.post(&url).json(&body))
            .await
    }

    /// `POST /v1/sessions/{id}/step`, with its round-trip time in ms.
    pub async fn step(
        &self,
        session: &str,
        req: &StepRequest,
    ) -> Result<(StepResponse, f64), ClientError> {
        let url = format!("{}/v1/sessions/{session}/step", self.base);
        let started = Instant::now();
        let resp = self
            .send(url.clone(), self.http.post(&url).json(req))
            .await?;
        Ok((resp, started.elapsed().as_secs_f64() * 1e3))
    }

    /// `DELETE /v1/sessions/{id}`.
    pub async fn close_session(&self, session: &str) -> Result<(), ClientError> {
        let url = format!("{}/v1/sessions/{session}", self.base);
        let resp =
            self.http
                .delete(&url)
                .send()
                .await
                .map_err(|source| ClientError::Transport {
                    url: url.clone(),
                    source,
                })?;
        if resp.status().is_success() {
            Ok(())
        } else {
            Err(ClientError::Status {
                url,
                status: resp.status().as_u16(),
                body: resp.text().await.unwrap_or_default(),
            })
        }
    }
}

/// Starts a Vigil server on a free loopback port of this process and
/// returns its base URL. It serves until the runtime shuts down.
pub async fn spawn_local_server() -> std::io::Result<String> {
    spawn_local_server_with(vigil::http::config::Settings::default()).await
}

/// [`spawn_local_server`] with the given settings.
pub async fn spawn_local_server_with(
    settings: vigil::http::config::Settings,
) -> std::io::Result<String> {
    let state = tokio::task::spawn_blocking(move || {
        vigil::http::AppState::with_settings(vigil::catalog::Registry::with_builtins(), settings)
    })
    .await
    .map_err(std::io::Error::other)?;
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await?;
    let addr = listener.local_addr()?;
    tokio::spawn(async move {
        if let Err(e) = axum::serve(listener, vigil::http::router(state)).await {
            eprintln!("in-process server stopped: {e}");
        }
    });
    Ok(format!("http://{addr}"))
}
