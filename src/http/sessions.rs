//! `/v1/sessions`: step-by-step clients. A session keeps its client's
//! history and tracks ([`crate::session`]); each step sends only the
//! sensors now and the detections now.
//!
//! Sessions are kept by a [`super::session_store::SessionStore`]: in this
//! replica's memory, or in the database shared by every replica. Steps of
//! one session run one at a time on a replica; across replicas, a step is
//! stored only over the state it was made from, and made again (up to
//! [`STEP_ATTEMPTS`] times, then 409) when another step was stored first.

use std::sync::Arc;

use axum::Extension;
use axum::body::Bytes;
use axum::extract::State;
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::doc::{self, examples};
use super::error::ApiError;
use super::extract::{Json, Path, QueuedJson};
use super::middleware::RequestStart;
use super::planning::{Admitted, admit, plan_admitted_carried, resolve_scenario};
use super::session_store::{Refreshed, StepKey};
use super::state::AppState;
use crate::fit::{LearntStep, SourceRate};
use crate::limits::{MAX_HORIZON, MAX_IDEMPOTENCY_KEY_CHARS, MAX_MIN_SEPARATION, MAX_TARGETS};
use crate::metric_names;
use crate::planner::{PlanResponse, Planner, check_estimator};
use crate::scenario::{ScenarioSpec, ValidationError};
use crate::session::{PreparedStep, Session, SessionSettings, StepRequest, Track};

/// A session, as `POST /v1/sessions` and `GET /v1/sessions/{id}` return it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SessionInfo {
    /// Session id.
    pub id: String,
    /// Its scenario's id.
    pub scenario: String,
    /// Steps made so far: the number of the next step.
    pub step: u64,
    /// Steps of history kept.
    pub history_steps: usize,
    /// Steps of history held now.
    pub history_held: usize,
    /// The defaults of its steps.
    pub settings: SessionSettings,
    /// The targets it follows after the last step.
    pub tracks: Vec<Track>,
    /// Approximate memory it holds, bytes (the scenario's statistics,
    /// shared, aside).
    pub memory_bytes: usize,
    /// With `learn_rates`: each source's rate learnt so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rates: Option<Vec<SourceRate>>,
}

impl SessionInfo {
    fn of(id: String, s: &Session) -> Self {
        Self {
            id,
            scenario: s.planner().scenario.id.clone(),
            step: s.step(),
            history_steps: s.history_len(),
            history_held: s.history_held(),
            settings: s.settings().clone(),
            tracks: s.tracks().to_vec(),
            memory_bytes: s.memory_bytes(),
            rates: s.learner().map(|l| l.rates()),
        }
    }
}

/// Body of `POST /v1/sessions/{id}/step`: the plan, and the step's number.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct StepResponse {
    /// The number of this step (0 for the first).
    pub step: u64,
    /// The plan, as `POST /v1/scenarios/{id}/plan` gives it.
    #[serde(flatten)]
    pub plan: PlanResponse,
    /// With `learn_rates`: each source's rate learnt up to this step, as
    /// `POST /v1/scenarios/{id}/fit` gives them (the plan used the
    /// posterior means).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rates: Option<Vec<SourceRate>>,
}

/// `POST /v1/sessions` → 201 [`SessionInfo`] with `Location`.
#[utoipa::path(
    post,
    path = "/v1/sessions",
    operation_id = "createSession",
    tag = "sessions",
    summary = "Open a session",
    description = "Opens a session for a client that plans every step: the server keeps the \
        sensors' past positions and the targets' tracks, so each step sends only the sensors \
        now and the targets detected now. The body names the scenario (`scenario_id`, or an \
        inline `scenario` as in `POST /v1/plan`) and the defaults of its steps; \
        `history_steps` (0..=128, 16 by default) is how many steps of history it keeps. \
        Without a database a session lives in the memory of the replica that created it: \
        route its requests there. With `--database-url` it is kept in the database, and every \
        replica on it serves it. A session idle for `--session-ttl-s` (600 s), or the least \
        recently used past `--max-sessions` (10 000), is dropped. \
        With `learn_rates: true` the session learns the sources' rates from its detections \
        (each needs an `id`), plans with them and reports them as `rates` at every step \
        (see `docs/learning.md`); only a scenario precomputed within \
        `--sync-precompute-ms` may learn.",
    request_body(content = doc::CreateSessionRequest, description = "Scenario and defaults.",
        example = json!(examples::session_request())),
    responses(
        (status = 201, description = "The new session.", body = SessionInfo,
            headers(("Location" = String, description = "`/v1/sessions/{id}`.")),
            example = json!(examples::session_info())),
        (status = 400, response = doc::MalformedBody),
        (status = 404, response = doc::ScenarioNotFound),
        (status = 413, response = doc::PayloadTooLarge),
        (status = 422, response = doc::InvalidSession),
        (status = 503, response = doc::NotReady),
    )
)]
pub async fn create(
    State(state): State<AppState>,
    start: Option<Extension<RequestStart>>,
    Json(body): Json<serde_json::Value>,
) -> Result<Response, ApiError> {
    let serde_json::Value::Object(mut fields) = body else {
        return Err(ApiError::MalformedBody(
            "the body must be a JSON object".into(),
        ));
    };
    let scenario_id = fields.remove("scenario_id");
    let inline = fields.remove("scenario");
    let settings: SessionSettings =
        crate::json_path::from_value(&serde_json::Value::Object(fields), "")
            .map_err(ApiError::MalformedBody)?;
    settings.history_len()?;
    if let Some(h) = &settings.horizon {
        h.check("horizon", 1..=MAX_HORIZON)?;
    }
    if let Some(d) = &settings.min_separation {
        d.check("min_separation", 0..=MAX_MIN_SEPARATION)?;
    }
    let planner = resolve_scenario(&state, start, scenario_id, inline).await?;
    check_estimator(
        "estimator",
        settings.estimator.unwrap_or_default(),
        &planner.scenario,
    )?;
    settings.tolerances(&planner.scenario)?;
    settings.check_learning(&planner.scenario)?;
    if settings.learn_rates == Some(true) {
        // A learning session precomputes its scenario again as its rates
        // move: only a scenario precomputed at once may learn.
        let limits = state.registry.limits();
        if let Some(predicted_ms) = limits.too_long_inline(&planner.scenario) {
            let budget_ms = limits.sync_precompute_ms;
            return Err(ValidationError::new(
                "learn_rates",
                format!(
                    "a learning session precomputes its scenario again as its rates move; this one is predicted to take {predicted_ms:.0} ms, above this server's synchronous budget of {budget_ms:.0} ms (--sync-precompute-ms)"
                ),
            )
            .into());
        }
    }
    let session = Session::new(planner, settings);
    let info = SessionInfo::of(String::new(), &session);
    let (id, _) = state.sessions.create(session).await?;
    let info = SessionInfo {
        id: id.clone(),
        ..info
    };
    let location = HeaderValue::try_from(format!("/v1/sessions/{id}"))
        .map_err(|e| ApiError::Internal(format!("bad Location header: {e}")))?;
    Ok((
        StatusCode::CREATED,
        [(header::LOCATION, location)],
        Json(info),
    )
        .into_response())
}

/// `POST /v1/sessions/{id}/step` → 200 [`StepResponse`].
#[utoipa::path(
    post,
    path = "/v1/sessions/{id}/step",
    operation_id = "stepSession",
    tag = "sessions",
    summary = "Plan the next step of a session",
    description = concat!("Records this step and plans from the session's state. The session moves \
        every track one step along its straight line, takes each detection as its track's new \
        state (matched by `id`, else by position and velocity, else a new track), drops the \
        tracks that left the zone or were not detected for `history_steps` steps, and plans \
        from the sensors now, the tracks and the sensors' positions over the last \
        `history_steps` steps: the same plan as the stateless request of that state. Only a \
        step whose plan is made is recorded, so a step that failed (4xx, 5xx) may be sent \
        again. Steps of one session run one at a time, each from the state the one before \
        left, whichever replica serves them. A step sent with an `Idempotency-Key` header is \
        answered, to the byte, with the first answer to that key if the session's last \
        step had it and the same body (the same JSON values, whatever their layout), and is \
        not made again: send one to retry safely after a lost answer, a timeout or a 503. \
        The last step's key with another body is refused with 422 \
        (`idempotency-key-reused`).", plan_rules!()),
    params(
        ("id" = String, Path, description = "Session id, from `POST /v1/sessions`."),
        ("Idempotency-Key" = Option<String>, Header, description = "Any string of 1 to 128 \
            visible ASCII characters naming this step (e.g. its number or a UUID): a retry \
            with the key and body of the session's last step gets that step's answer again \
            instead of a new step; that key with another body is refused (422).", min_length = 1,
            pattern = r"^[\x21-\x7E]([\x20-\x7E]*[\x21-\x7E])?$"),
    ),
    request_body(content = StepRequest, description = "Sensors and detections now.",
        example = json!(examples::step_request())),
    responses(
        (status = 200, description = "The plan of this step.", body = StepResponse,
            example = json!(examples::step_response())),
        (status = 400, response = doc::MalformedStep),
        (status = 404, response = doc::SessionNotFound),
        (status = 409, response = doc::SessionConflict),
        (status = 413, response = doc::PayloadTooLarge),
        (status = 422, response = doc::InvalidStep),
        (status = 503, response = doc::NotReady),
    )
)]
pub async fn step(
    State(state): State<AppState>,
    start: Option<Extension<RequestStart>>,
    Path(id): Path<String>,
    headers: HeaderMap,
    body: Result<QueuedJson<StepRequest>, ApiError>,
) -> Result<Response, ApiError> {
    let shared = state.sessions.checkout(&id)?;
    let checked = idempotency_key(&headers).and_then(|key| {
        let QueuedJson(req) = body?;
        req.check()?;
        Ok((key, req))
    });
    let (key, req) = match checked {
        Ok(checked) => checked,
        Err(e) => {
            // An unknown session is not found whatever the request, and a
            // refused step still counts as a use of a live one.
            state.sessions.confirm(&id).await?;
            return Err(e);
        }
    };
    let key = key.map(|key| StepKey {
        key,
        digest: req.digest(),
    });
    let mut held = shared.lock().await;
    for _ in 0..STEP_ATTEMPTS {
        let resolve = async |scenario_id, spec| stored_planner(&state, scenario_id, spec).await;
        let (session, base) = match state
            .sessions
            .refresh(&id, &mut held, key, false, resolve)
            .await?
        {
            Refreshed::Replay(answer) => return Ok(json_bytes(answer)),
            Refreshed::Session(session, base) => (session, base),
        };
        let mut ready = match prepare_step(&state, session, &req).await {
            Ok(ready) => ready,
            Err(e) => {
                state.sessions.touch(&id);
                return Err(e);
            }
        };
        // In the database, the new state is written while the plan is made
        // and committed once it is (rolled back if it fails).
        let early = state.sessions.save_early(
            &id,
            base,
            session,
            &ready.prepared,
            ready.admitted.predicted_ms,
            key,
        );
        let (answer, written) = match early {
            Some(write) => {
                ready.admitted = ready.admitted.on_pool();
                let (answer, written) =
                    tokio::join!(make_step(&state, start, &id, session, ready), write);
                (answer, Some(written))
            }
            None => (make_step(&state, start, &id, session, ready).await, None),
        };
        let answer = match answer {
            Ok(answer) => answer,
            Err(e) => {
                drop(written);
                state.sessions.touch(&id);
                return Err(e);
            }
        };
        let stored = match written {
            Some(written) => {
                state
                    .sessions
                    .finish_early(&id, &mut held, written, &answer)
                    .await?
            }
            None => state.sessions.save(&id, &mut held, key, &answer).await?,
        };
        if stored {
            return Ok(json_bytes(answer));
        }
    }
    Err(ApiError::SessionConflict(id))
}

/// The header naming a step, so that a retry is answered, not made again.
pub const IDEMPOTENCY_KEY: &str = "idempotency-key";

/// Times a step is made anew when another step of its session was stored
/// first, before it is refused with 409.
pub const STEP_ATTEMPTS: usize = 3;

/// The `Idempotency-Key` header, if any.
fn idempotency_key(headers: &HeaderMap) -> Result<Option<&str>, ApiError> {
    let Some(value) = headers.get(IDEMPOTENCY_KEY) else {
        return Ok(None);
    };
    // `to_str` also lets tabs through; the documented pattern does not.
    let key = value
        .to_str()
        .ok()
        .filter(|key| key.bytes().all(|b| (b' '..=b'~').contains(&b)))
        .filter(|key| !key.starts_with(' ') && !key.ends_with(' '))
        .ok_or_else(|| {
            ApiError::BadHeader(
                "Idempotency-Key: must be visible ASCII characters, with spaces only inside".into(),
            )
        })?;
    if key.is_empty() || key.len() > MAX_IDEMPOTENCY_KEY_CHARS {
        return Err(ApiError::BadHeader(format!(
            "Idempotency-Key: must have 1 to {MAX_IDEMPOTENCY_KEY_CHARS} characters, not {}",
            key.len()
        )));
    }
    Ok(Some(key))
}

/// A step of a session, prepared and admitted, its plan not yet made.
struct ReadyStep {
    prepared: PreparedStep,
    learnt: Option<LearntStep>,
    planner: Arc<Planner>,
    admitted: Admitted,
}

/// Prepares a step of `session` (unchanged): its stateless request, this
/// step's fold for a session that learns rates, and the plan's admission.
async fn prepare_step(
    state: &AppState,
    session: &Session,
    req: &StepRequest,
) -> Result<ReadyStep, ApiError> {
    let prepared = session.prepare(req);
    if prepared.request.targets.len() > MAX_TARGETS {
        return Err(ValidationError::new(
            "detections",
            format!(
                "the session would follow {} targets, at most {MAX_TARGETS}",
                prepared.request.targets.len()
            ),
        )
        .into());
    }
    // Learning folds this step in first (off the async workers), so the
    // plan uses the rates that include it.
    let learnt = match session.learner() {
        Some(learner) => {
            let learner = learner.clone();
            let (sensors, detections) = (req.sensors.clone(), req.detections.clone());
            Some(super::queue::on_rayon(move || learner.fold(&sensors, &detections)).await??)
        }
        None => None,
    };
    let planner = session.planner_for(learnt.as_ref());
    let admitted = admit(state, &planner, &prepared.request)?;
    Ok(ReadyStep {
        prepared,
        learnt,
        planner,
        admitted,
    })
}

/// Makes step `ready` on `session` (changed only if its plan is made) and
/// returns its answer, encoded.
async fn make_step(
    state: &AppState,
    start: Option<Extension<RequestStart>>,
    id: &str,
    session: &mut Session,
    ready: ReadyStep,
) -> Result<Bytes, ApiError> {
    let ReadyStep {
        prepared,
        learnt,
        planner,
        admitted,
    } = ready;
    let carry = state.carries.take(id);
    let (plan, carry) = plan_admitted_carried(state, start, planner, admitted, carry).await?;
    metrics::counter!(metric_names::SESSION_STEPS_TOTAL, "carry" => carry.last_use().as_str())
        .increment(1);
    state.carries.keep(id, carry);
    let step = session.step();
    let rates = learnt.as_ref().map(|learnt| learnt.rates().to_vec());
    let answer = serde_json::to_vec(&StepResponse { step, plan, rates })
        .map_err(|e| ApiError::Internal(format!("encoding a step's answer: {e}")))?;
    session.commit(prepared);
    if let Some(learnt) = learnt {
        session.commit_learnt(learnt);
    }
    Ok(Bytes::from(answer))
}

/// The planner of a session loaded from the database: its registered
/// scenario's, else (an inline scenario) one built from the stored spec.
async fn stored_planner(
    state: &AppState,
    scenario_id: String,
    spec: Vec<u8>,
) -> Result<Arc<Planner>, ApiError> {
    let id = serde_json::Value::String(scenario_id.clone());
    let planner = match resolve_scenario(state, None, Some(id), None).await {
        Err(ApiError::ScenarioNotFound(_)) => {
            let spec: ScenarioSpec = ciborium::from_reader(spec.as_slice()).map_err(|e| {
                ApiError::Internal(format!("the stored spec of {scenario_id}: {e}"))
            })?;
            let spec = serde_json::to_value(spec).map_err(|e| {
                ApiError::Internal(format!("the stored spec of {scenario_id}: {e}"))
            })?;
            resolve_scenario(state, None, None, Some(spec)).await?
        }
        other => other?,
    };
    if planner.scenario.id != scenario_id {
        return Err(ApiError::Internal(format!(
            "the stored spec of {scenario_id} makes scenario {}",
            planner.scenario.id
        )));
    }
    Ok(planner)
}

/// A JSON body already encoded.
fn json_bytes(answer: Bytes) -> Response {
    (
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static(mime::APPLICATION_JSON.as_ref()),
        )],
        answer,
    )
        .into_response()
}

/// `GET /v1/sessions/{id}` → 200 [`SessionInfo`].
#[utoipa::path(
    get,
    path = "/v1/sessions/{id}",
    operation_id = "getSession",
    tag = "sessions",
    summary = "Read a session",
    params(("id" = String, Path, description = "Session id, from `POST /v1/sessions`.")),
    responses(
        (status = 200, description = "The session.", body = SessionInfo,
            example = json!(examples::session_info())),
        (status = 400, response = doc::BadPath),
        (status = 404, response = doc::SessionNotFound),
        (status = 503, response = doc::NotReady),
    )
)]
pub async fn get(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<SessionInfo>, ApiError> {
    let shared = state.sessions.checkout(&id)?;
    let mut held = shared.lock().await;
    let resolve = async |scenario_id, spec| stored_planner(&state, scenario_id, spec).await;
    match state
        .sessions
        .refresh(&id, &mut held, None, true, resolve)
        .await?
    {
        Refreshed::Session(session, _) => Ok(Json(SessionInfo::of(id, session))),
        Refreshed::Replay(_) => Err(ApiError::Internal("a read replayed a step".into())),
    }
}

/// `DELETE /v1/sessions/{id}` → 204.
#[utoipa::path(
    delete,
    path = "/v1/sessions/{id}",
    operation_id = "deleteSession",
    tag = "sessions",
    summary = "Close a session",
    params(("id" = String, Path, description = "Session id, from `POST /v1/sessions`.")),
    responses(
        (status = 204, description = "Closed."),
        (status = 400, response = doc::BadPath),
        (status = 404, response = doc::SessionNotFound),
        (status = 503, response = doc::NotReady),
    )
)]
pub async fn delete(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    state.sessions.remove(&id).await?;
    Ok(StatusCode::NO_CONTENT)
}
