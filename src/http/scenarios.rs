//! `/v1/scenarios`: list, register, read, delete scenarios, and read their
//! per-cell statistics.

use std::sync::Arc;

use axum::extract::State;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use axum::Extension;

use super::doc::{self, examples};
use super::error::ApiError;
use super::extract::{Json, Path};
use super::middleware::RequestStart;
use super::planning::CancelOnDrop;
use super::state::AppState;
use crate::cancel::Progress;
use crate::catalog::{
    Entry, JobStatus, Listed, entry_id, precompute_cancellable, predicted_precompute_ms,
};
use crate::planner::Planner;
use crate::scenario::{DEFAULT_TYPE, ObstacleSpec, Scenario, ScenarioSpec};

/// Size of a scenario's lattice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
pub struct Grid {
    /// Columns.
    pub cols: i32,
    /// Rows.
    pub rows: i32,
}

/// Scalar results of a scenario's precomputation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SummaryStats {
    /// Stationary expected number of targets inside the zone.
    pub expected_targets_in_zone: f64,
    /// Time the precomputation took, milliseconds.
    pub precompute_ms: f64,
}

/// Where a scenario is in its lifecycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum ScenarioStatus {
    /// Waiting for a precomputation slot (`queue_position` says its place).
    Queued,
    /// Being precomputed (`progress` rises to 1).
    Precomputing,
    /// Precomputed: plans and statistics are served.
    Ready,
    /// Only in a list, with `--database-url`: registered in the shared
    /// database and not yet used on this replica; its first plan or read
    /// here precomputes it (or starts its job, if large).
    Stored,
}

/// A registered scenario, as `GET /v1/scenarios/{id}` returns it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ScenarioSummary {
    /// Scenario id.
    pub id: String,
    /// Canonical spec (headings and horizon filled in).
    pub spec: ScenarioSpec,
    /// Lattice size.
    pub grid: Grid,
    /// `ready`, or `queued` / `precomputing` while a job precomputes it
    /// (`stored` in a list: not yet used on this replica).
    pub status: ScenarioStatus,
    /// Share of the precomputation done, 0..1 (1 when ready).
    #[schema(minimum = 0.0, maximum = 1.0)]
    pub progress: f64,
    /// Estimated seconds until it is ready; only while pending.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eta_s: Option<f64>,
    /// Place in the precomputation queue (1 = next); only while queued.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(minimum = 1)]
    pub queue_position: Option<usize>,
    /// The precomputation's predicted wall time on this server,
    /// milliseconds (above `--sync-precompute-ms` it runs as a job).
    pub predicted_precompute_ms: f64,
    /// Precomputation results; only when ready.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub summary: Option<SummaryStats>,
}

impl ScenarioSummary {
    /// The summary of a registered scenario in whatever state.
    pub fn of(entry: &Entry, job: Option<JobStatus>) -> Self {
        let scenario = match entry {
            Entry::Ready(p) => &p.scenario,
            Entry::Pending(j) => &j.scenario,
        };
        let (status, progress) = match (entry, job) {
            (Entry::Ready(_), _) => (ScenarioStatus::Ready, 1.0),
            (Entry::Pending(_), Some(j)) if j.queue_position.is_some() => {
                (ScenarioStatus::Queued, j.progress)
            }
            (Entry::Pending(_), j) => (ScenarioStatus::Precomputing, j.map_or(0.0, |j| j.progress)),
        };
        Self {
            id: scenario.id.clone(),
            spec: scenario.spec.clone(),
            grid: Grid {
                cols: scenario.cols,
                rows: scenario.rows,
            },
            status,
            progress,
            eta_s: job.map(|j| (j.eta_s * 10.0).round() / 10.0),
            queue_position: job.and_then(|j| j.queue_position),
            predicted_precompute_ms: (predicted_precompute_ms(scenario) * 100.0).round() / 100.0,
            summary: match entry {
                Entry::Ready(p) => Some(SummaryStats {
                    expected_targets_in_zone: p.stats[0].expected_targets_in_zone,
                    precompute_ms: p.precompute_ms,
                }),
                Entry::Pending(_) => None,
            },
        }
    }
}

impl ScenarioSummary {
    /// The summary of a scenario stored in the database and not yet used
    /// on this replica.
    pub fn stored(scenario: &Scenario) -> Self {
        Self {
            id: scenario.id.clone(),
            spec: scenario.spec.clone(),
            grid: Grid {
                cols: scenario.cols,
                rows: scenario.rows,
            },
            status: ScenarioStatus::Stored,
            progress: 0.0,
            eta_s: None,
            queue_position: None,
            predicted_precompute_ms: (predicted_precompute_ms(scenario) * 100.0).round() / 100.0,
            summary: None,
        }
    }
}

/// Body of `GET /v1/scenarios`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ScenarioList {
    /// Every registered scenario, sorted by id.
    pub scenarios: Vec<ScenarioSummary>,
}

/// Body of `GET /v1/scenarios/{id}/stats`: per-cell statistics, row-major
/// (`row·cols + col`). Borrows from the planner, so large lattices are not
/// copied before serialization.
#[derive(Debug, Clone, Copy, Serialize, ToSchema)]
#[schema(
    description = "Per-cell statistics of a scenario, each array row-major (`row·cols + col`)."
)]
pub struct ScenarioStats<'a> {
    /// The sensor type whose field of view they are for.
    #[serde(rename = "type")]
    pub sensor_type: &'a str,
    /// Columns.
    pub cols: i32,
    /// Rows.
    pub rows: i32,
    /// Side of a cell.
    pub cell_size: f64,
    /// Expected rate of target entry into each cell's field of view.
    pub lambda_hat: &'a [f64],
    /// Expected stay of an entering target in each cell's field of view.
    pub escape_time: &'a [f64],
    /// Stationary expected number of targets in each cell's field of view.
    pub d_hat: &'a [f64],
    /// The scenario's obstacles (absent when it has none), to draw over
    /// the statistics: with obstacles, each cell's statistics count only
    /// the part of its field of view it sees (all of it for an elevated
    /// type) and the targets no building has stopped.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    pub obstacles: &'a [ObstacleSpec],
}

impl<'a> ScenarioStats<'a> {
    /// The statistics of sensor type `ty`'s field of view.
    fn of(p: &'a Planner, ty: usize) -> Self {
        let stats = p.stats_of(ty);
        Self {
            sensor_type: &p.scenario.types[ty].name,
            cols: p.scenario.cols,
            rows: p.scenario.rows,
            cell_size: p.scenario.cell_size,
            lambda_hat: &stats.lambda_hat,
            escape_time: &stats.escape_time,
            d_hat: &stats.d_hat,
            obstacles: p.scenario.spec.obstacles.as_deref().unwrap_or(&[]),
        }
    }
}

/// Query of `GET /v1/scenarios/{id}/stats`.
#[derive(Debug, Clone, Default, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
#[into_params(parameter_in = Query)]
pub struct StatsQuery {
    /// The sensor type whose field of view the statistics are for;
    /// `default` by default.
    #[serde(rename = "type")]
    #[param(rename = "type", example = "default")]
    pub sensor_type: Option<String>,
}

/// `GET /v1/scenarios` → 200 [`ScenarioList`].
#[utoipa::path(
    get,
    path = "/v1/scenarios",
    operation_id = "listScenarios",
    tag = "scenarios",
    summary = "List scenarios",
    description = "Every registered scenario, built-in and client-registered, sorted by id. \
        With a shared database (`--database-url`) this is the database's catalogue: a scenario \
        not yet used on this replica is listed with `status` `stored`.",
    responses(
        (status = 200, description = "The registered scenarios.", body = ScenarioList,
            example = json!(examples::scenario_list())),
    )
)]
pub async fn list(State(state): State<AppState>) -> Result<Json<ScenarioList>, ApiError> {
    let scenarios = state
        .registry
        .catalogue()
        .await?
        .iter()
        .map(|listed| match listed {
            Listed::Held(entry, job) => ScenarioSummary::of(entry, *job),
            Listed::Stored(scenario) => ScenarioSummary::stored(scenario),
        })
        .collect();
    Ok(Json(ScenarioList { scenarios }))
}

/// `POST /v1/scenarios`, body [`ScenarioSpec`] → 201 with the
/// [`ScenarioSummary`] and a `Location` header when the scenario is new and
/// precomputed at once, 202 with `Location` when it is precomputed as a job
/// (or its job is still running), 200 with the registered one when it is
/// ready already; 422 for an invalid spec, 503 when the job queue is full.
#[utoipa::path(
    post,
    path = "/v1/scenarios",
    operation_id = "createScenario",
    tag = "scenarios",
    summary = "Register a scenario",
    description = concat!("Validates the spec, precomputes its per-cell statistics and registers it under \
        an id derived from the canonical spec (`s-` and 16 hex digits), so posting the same spec \
        again is idempotent: 201 the first time, 200 with the registered scenario after.\n\n\
        A scenario whose precomputation is predicted to take longer than the server's \
        synchronous budget (`--sync-precompute-ms`, 1 s by default; the prediction is the \
        summary's `predicted_precompute_ms`) is precomputed as a background job instead: the \
        answer is 202 at once with its `Location`, the spec is stored durably (a restart \
        resumes the job), and `GET` on that location shows `status` `queued` (with its \
        `queue_position`), then `precomputing` (with `progress` rising to 1 and `eta_s`), then \
        `ready`. Meanwhile plans and statistics on it answer 503 with `Retry-After`, and \
        `DELETE` cancels the job. Jobs run one at a time by default (`--precompute-jobs`); \
        past `--precompute-queue` waiting jobs a registration gets 503.", spec_rules!()),
    request_body(content = ScenarioSpec, description = "The scenario.",
        examples(
            ("small" = (summary = "Precomputed at once (201)", value = json!(examples::small_spec()))),
            ("large" = (summary = "4 million cells: precomputed as a job (202)", value = json!(examples::large_spec()))),
        )),
    responses(
        (status = 201, description = "Registered and precomputed: the new scenario.", body = ScenarioSummary,
            headers(("Location" = String, description = "`/v1/scenarios/{id}` of the new scenario.")),
            example = json!(examples::small_summary())),
        (status = 202, description = "Accepted as a precomputation job (new, or already pending): \
            poll the `Location` until `status` is `ready`.", body = ScenarioSummary,
            headers(("Location" = String, description = "`/v1/scenarios/{id}` of the scenario.")),
            examples(
                ("precomputing" = (summary = "Running", value = json!(examples::large_precomputing()))),
                ("queued" = (summary = "Waiting behind another job", value = json!(examples::large_queued()))),
            )),
        (status = 200, description = "A scenario with this canonical spec was already registered and is ready: that one.",
            body = ScenarioSummary, example = json!(examples::small_summary())),
        (status = 400, response = doc::MalformedBody),
        (status = 413, response = doc::PayloadTooLarge),
        (status = 422, response = doc::InvalidScenario),
        (status = 503, response = doc::QueueFull),
    )
)]
pub async fn create(
    State(state): State<AppState>,
    start: Option<Extension<RequestStart>>,
    Json(spec): Json<ScenarioSpec>,
) -> Result<Response, ApiError> {
    let (entry, job, created) = register(&state, start, Scenario::new(spec)?).await?;
    registered(&entry, job, created)
}

/// Registers `scenario` (or finds it registered): precomputed at once, or
/// as a job when predicted above the synchronous budget. Returns its
/// entry, its job's status if pending, and whether this call created it.
pub(super) async fn register(
    state: &AppState,
    start: Option<Extension<RequestStart>>,
    scenario: Scenario,
) -> Result<(Entry, Option<JobStatus>, bool), ApiError> {
    if let Some((entry, job)) = state.registry.entry(&scenario.id) {
        return Ok((entry, job, false));
    }
    let registry = state.registry.clone();
    if predicted_precompute_ms(&scenario) > registry.limits().sync_precompute_ms {
        // Stored durably before the 202, so a restart resumes it.
        let (entry, created) = registry.submit(scenario).await?;
        let job = state
            .registry
            .entry(entry_id(&entry))
            .and_then(|(_, job)| job);
        return Ok((entry, job, created));
    }
    // Precompute off the async workers, then store; a 2xx means it is
    // stored. Cancelled (and not stored) if nobody waits for the answer.
    let guard = CancelOnDrop::new("precompute", start, state);
    let token = guard.token();
    let planner = tokio::task::spawn_blocking(move || {
        let planner = precompute_cancellable(scenario, &token, &Progress::default())
            .map_err(|_| ApiError::Timeout)?;
        token.check().map_err(|_| ApiError::Timeout)?;
        Ok::<_, ApiError>(planner)
    })
    .await??;
    // A concurrent identical request (here, or through another replica
    // sharing the database) may have registered it meanwhile; the first
    // one stays, and this answer is 200.
    let (entry, created) = registry.insert(Arc::new(planner)).await?;
    guard.finish();
    Ok((entry, None, created))
}

/// The status of a registration: 201 for a new ready scenario, 202 for a
/// pending one (new or not), 200 for one that was ready already.
pub(super) fn registration_status(entry: &Entry, created: bool) -> StatusCode {
    match entry {
        Entry::Pending(_) => StatusCode::ACCEPTED,
        Entry::Ready(_) if created => StatusCode::CREATED,
        Entry::Ready(_) => StatusCode::OK,
    }
}

/// `Location` of a registered scenario.
pub(super) fn location(entry: &Entry) -> Result<HeaderValue, ApiError> {
    HeaderValue::try_from(format!("/v1/scenarios/{}", entry_id(entry)))
        .map_err(|e| ApiError::Internal(format!("bad Location header: {e}")))
}

/// The answer to a registration: 201 with `Location` for a new ready
/// scenario, 202 with `Location` for a pending one (new or not), 200 for
/// one that was ready already.
fn registered(entry: &Entry, job: Option<JobStatus>, created: bool) -> Result<Response, ApiError> {
    let body = Json(ScenarioSummary::of(entry, job));
    let status = registration_status(entry, created);
    if status == StatusCode::OK {
        return Ok(body.into_response());
    }
    Ok((status, [(header::LOCATION, location(entry)?)], body).into_response())
}

/// `GET /v1/scenarios/{id}` → 200 [`ScenarioSummary`]; 404 if unknown.
#[utoipa::path(
    get,
    path = "/v1/scenarios/{id}",
    operation_id = "getScenario",
    tag = "scenarios",
    summary = "Read a scenario",
    params(("id" = String, Path, description = doc::SCENARIO_ID, example = "paper-v10")),
    responses(
        (status = 200, description = "The scenario, ready or still pending.", body = ScenarioSummary,
            examples(
                ("ready" = (summary = "Ready", value = json!(examples::paper_v10_summary()))),
                ("precomputing" = (summary = "A job precomputing it", value = json!(examples::large_precomputing()))),
                ("queued" = (summary = "Its job waiting", value = json!(examples::large_queued()))),
            )),
        (status = 400, response = doc::BadPath),
        (status = 404, response = doc::ScenarioNotFound),
    )
)]
pub async fn get(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<ScenarioSummary>, ApiError> {
    let (entry, job) = state.registry.lookup(&id).await?;
    Ok(Json(ScenarioSummary::of(&entry, job)))
}

/// `DELETE /v1/scenarios/{id}` → 204; 409 for a built-in, 404 if unknown.
#[utoipa::path(
    delete,
    path = "/v1/scenarios/{id}",
    operation_id = "deleteScenario",
    tag = "scenarios",
    summary = "Delete a scenario",
    description = "Removes a client-registered scenario; if it is still being precomputed, its job \
        is cancelled at once. Built-in scenarios cannot be deleted.",
    params(("id" = String, Path, description = doc::SCENARIO_ID, example = "paper-v10")),
    responses(
        (status = 204, description = "Deleted."),
        (status = 400, response = doc::BadPath),
        (status = 404, response = doc::ScenarioNotFound),
        (status = 409, response = doc::BuiltinScenario),
    )
)]
pub async fn delete(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    state.registry.remove(&id).await?;
    Ok(StatusCode::NO_CONTENT)
}

/// `GET /v1/scenarios/{id}/stats` → 200 [`ScenarioStats`]; 404 if unknown.
/// Serialized on the blocking pool, as a large lattice gives a large body.
#[utoipa::path(
    get,
    path = "/v1/scenarios/{id}/stats",
    operation_id = "getScenarioStats",
    tag = "scenarios",
    summary = "Per-cell statistics of a scenario",
    description = "The precomputed statistics of every cell, row-major (`row·cols + col`). \
        The body has `3·cols·rows` numbers: large for a fine lattice.",
    params(("id" = String, Path, description = doc::SCENARIO_ID, example = "paper-v10"), StatsQuery),
    responses(
        (status = 200, description = "The statistics.", body = ScenarioStats,
            example = json!(examples::stats())),
        (status = 400, response = doc::BadPath),
        (status = 404, response = doc::ScenarioNotFound),
        (status = 503, response = doc::NotReady),
    )
)]
pub async fn stats(
    State(state): State<AppState>,
    Path(id): Path<String>,
    uri: axum::http::Uri,
) -> Result<Response, ApiError> {
    let query = axum::extract::Query::<StatsQuery>::try_from_uri(&uri)
        .map_err(|e| ApiError::BadQuery(e.body_text()))?
        .0;
    let planner = state.registry.resolve(&id).await?;
    let name = query.sensor_type.as_deref().unwrap_or(DEFAULT_TYPE);
    let ty = planner
        .scenario
        .type_index(name)
        .ok_or_else(|| ApiError::SensorTypeNotFound {
            scenario: planner.scenario.id.clone(),
            name: name.to_owned(),
            known: planner
                .scenario
                .types
                .iter()
                .map(|t| t.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        })?;
    let body = tokio::task::spawn_blocking(move || {
        serde_json::to_vec(&ScenarioStats::of(planner.as_ref(), ty))
    })
    .await?
    .map_err(|e| ApiError::Internal(format!("serializing statistics: {e}")))?;
    Ok((
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/json"),
        )],
        body,
    )
        .into_response())
}
