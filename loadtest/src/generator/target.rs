//! What a run's requests hit: plan requests, a plain `GET`, or the steps
//! of sessions.

use std::sync::Arc;

use anyhow::{Result, bail};
use bytes::Bytes;
use vigil::session::StepRequest;

use crate::workload::SessionWorkload;

/// What the requests hit.
#[derive(Debug, Clone)]
pub enum Target {
    /// `POST` of pre-serialised bodies, cycled in order.
    Post {
        /// The full URL.
        url: String,
        /// The bodies; request `i` sends `bodies[i % len]`.
        bodies: Arc<[Bytes]>,
    },
    /// `GET` with no body.
    Get {
        /// The full URL.
        url: String,
    },
    /// The steps of sessions (`POST {base}/v1/sessions/{id}/step`), opened
    /// and warmed before the run and closed after it.
    Session(Arc<SessionTarget>),
}

/// Session mode: request `i` is the next step of session `i mod sessions`,
/// and a session's steps never overlap.
#[derive(Debug)]
pub struct SessionTarget {
    /// `{base}/v1/sessions`.
    pub sessions_url: String,
    /// `{base}/v1/sessions/{id}/step`, for messages.
    pub step_url: String,
    /// The replicas' base URLs: step `j` of session `i` goes to
    /// `bases[(i + j) % len]`, as a plain load balancer spreads them.
    pub bases: Vec<String>,
    /// Body of `POST /v1/sessions`: the scenario and the settings.
    pub create: Bytes,
    /// Step bodies replayed untimed into every new session, in order.
    pub warmup: Vec<Bytes>,
    /// Step bodies of the run: a session's `j`-th step sends
    /// `steps[j % len]`.
    pub steps: Vec<Bytes>,
    /// Sessions open during the run.
    pub sessions: usize,
    /// Whether each timed step sends an `Idempotency-Key` (its step
    /// number, unique in its session), as the Python client does.
    pub idempotency_keys: bool,
}

impl Target {
    /// `POST {base}/v1/scenarios/{scenario}/plan` with `bodies`.
    ///
    /// # Errors
    /// If `bodies` is empty.
    pub fn plan(base: &str, scenario: &str, bodies: Vec<Bytes>) -> Result<Self> {
        if bodies.is_empty() {
            bail!("no request body to send");
        }
        Ok(Target::Post {
            url: format!(
                "{}/v1/scenarios/{scenario}/plan",
                base.trim_end_matches('/')
            ),
            bodies: bodies.into(),
        })
    }

    /// The steps of `sessions` sessions on `scenario`, created with
    /// `settings`, each warmed by `warmup` then stepping through `steps`
    /// (cycled).
    ///
    /// # Errors
    /// If there is no step or no session.
    pub fn session(
        base: &str,
        also: &[String],
        scenario: &str,
        workload: &SessionWorkload,
        sessions: usize,
        idempotency_keys: bool,
    ) -> Result<Self> {
        let SessionWorkload {
            settings,
            warmup,
            steps,
        } = workload;
        if steps.is_empty() {
            bail!("no session step to send");
        }
        if sessions == 0 {
            bail!("--sessions must be at least 1");
        }
        let mut create = serde_json::to_value(settings)?;
        if let serde_json::Value::Object(fields) = &mut create {
            fields.insert("scenario_id".into(), scenario.into());
        }
        let bodies = |steps: &[StepRequest]| -> Result<Vec<Bytes>> {
            steps
                .iter()
                .map(|s| Ok(Bytes::from(serde_json::to_vec(s)?)))
                .collect()
        };
        let base = base.trim_end_matches('/');
        let bases = std::iter::once(base)
            .chain(also.iter().map(|b| b.trim_end_matches('/')))
            .map(str::to_owned)
            .collect();
        Ok(Target::Session(Arc::new(SessionTarget {
            sessions_url: format!("{base}/v1/sessions"),
            step_url: format!("{base}/v1/sessions/{{id}}/step"),
            bases,
            create: Bytes::from(serde_json::to_vec(&create)?),
            warmup: bodies(warmup)?,
            steps: bodies(steps)?,
            sessions,
            idempotency_keys,
        })))
    }

    /// `GET {base}/healthz`.
    pub fn healthz(base: &str) -> Self {
        Target::Get {
            url: format!("{}/healthz", base.trim_end_matches('/')),
        }
    }

    /// The URL hit.
    pub fn url(&self) -> &str {
        match self {
            Target::Post { url, .. } | Target::Get { url } => url,
            Target::Session(t) => &t.step_url,
        }
    }
}
