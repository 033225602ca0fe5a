//! `/v1/scenarios`: list, register, read, delete scenarios, and read their
//! per-cell statistics.

use std::sync::Arc;

use axum::extract::State;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::AppState;
use super::error::ApiError;
use super::extract::{Json, Path};
use super::openapi::{self as doc, examples};
use crate::planner::Planner;
use crate::scenario::{DEFAULT_TYPE, Scenario, ScenarioSpec};

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

/// A registered scenario, as `GET /v1/scenarios/{id}` returns it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ScenarioSummary {
    /// Scenario id.
    pub id: String,
    /// Canonical spec (headings and horizon filled in).
    pub spec: ScenarioSpec,
    /// Lattice size.
    pub grid: Grid,
    /// Precomputation results.
    pub summary: SummaryStats,
}

impl From<&Planner> for ScenarioSummary {
    fn from(p: &Planner) -> Self {
        Self {
            id: p.scenario.id.clone(),
            spec: p.scenario.spec.clone(),
            grid: Grid {
                cols: p.scenario.cols,
                rows: p.scenario.rows,
            },
            summary: SummaryStats {
                expected_targets_in_zone: p.stats[0].expected_targets_in_zone,
                precompute_ms: p.precompute_ms,
            },
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

fn lookup(state: &AppState, id: String) -> Result<Arc<Planner>, ApiError> {
    state
        .registry
        .get(&id)
        .ok_or(ApiError::ScenarioNotFound(id))
}

/// `GET /v1/scenarios` → 200 [`ScenarioList`].
#[utoipa::path(
    get,
    path = "/v1/scenarios",
    operation_id = "listScenarios",
    tag = "scenarios",
    summary = "List scenarios",
    description = "Every registered scenario, built-in and client-registered, sorted by id.",
    responses(
        (status = 200, description = "The registered scenarios.", body = ScenarioList,
            example = json!(examples::scenario_list())),
    )
)]
pub async fn list(State(state): State<AppState>) -> Json<ScenarioList> {
    let scenarios = state
        .registry
        .list()
        .iter()
        .map(|p| ScenarioSummary::from(p.as_ref()))
        .collect();
    Json(ScenarioList { scenarios })
}

/// `POST /v1/scenarios`, body [`ScenarioSpec`] → 201 with the
/// [`ScenarioSummary`] and a `Location` header when the scenario is new, 200
/// with the registered one when its id already exists; 422 for an invalid
/// spec.
#[utoipa::path(
    post,
    path = "/v1/scenarios",
    operation_id = "createScenario",
    tag = "scenarios",
    summary = "Register a scenario",
    description = concat!("Validates the spec, precomputes its per-cell statistics and registers it under \
        an id derived from the canonical spec (`s-` and 16 hex digits), so posting the same spec \
        again is idempotent: 201 the first time, 200 with the registered scenario after.", spec_rules!()),
    request_body(content = ScenarioSpec, description = "The scenario.",
        example = json!(examples::small_spec())),
    responses(
        (status = 201, description = "Registered: the new scenario.", body = ScenarioSummary,
            headers(("Location" = String, description = "`/v1/scenarios/{id}` of the new scenario.")),
            example = json!(examples::small_summary())),
        (status = 200, description = "A scenario with this canonical spec was already registered: that one.",
            body = ScenarioSummary, example = json!(examples::small_summary())),
        (status = 400, response = doc::MalformedBody),
        (status = 413, response = doc::PayloadTooLarge),
        (status = 422, response = doc::InvalidScenario),
    )
)]
pub async fn create(
    State(state): State<AppState>,
    Json(spec): Json<ScenarioSpec>,
) -> Result<Response, ApiError> {
    let scenario = Scenario::new(spec)?;
    if let Some(existing) = state.registry.get(&scenario.id) {
        return Ok(Json(ScenarioSummary::from(existing.as_ref())).into_response());
    }
    // Precompute and store off the async workers; a 2xx means it is on disk.
    let registry = state.registry.clone();
    let (planner, created) = tokio::task::spawn_blocking(move || {
        let planner = super::precompute(scenario);
        // A concurrent identical request may have registered it meanwhile;
        // the first one stays.
        registry.insert(Arc::new(planner))
    })
    .await??;
    let body = Json(ScenarioSummary::from(planner.as_ref()));
    if !created {
        return Ok(body.into_response());
    }
    let location = HeaderValue::try_from(format!("/v1/scenarios/{}", planner.scenario.id))
        .map_err(|e| ApiError::Internal(format!("bad Location header: {e}")))?;
    Ok((StatusCode::CREATED, [(header::LOCATION, location)], body).into_response())
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
        (status = 200, description = "The scenario.", body = ScenarioSummary,
            example = json!(examples::paper_v10_summary())),
        (status = 400, response = doc::BadPath),
        (status = 404, response = doc::ScenarioNotFound),
    )
)]
pub async fn get(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<ScenarioSummary>, ApiError> {
    let planner = lookup(&state, id)?;
    Ok(Json(ScenarioSummary::from(planner.as_ref())))
}

/// `DELETE /v1/scenarios/{id}` → 204; 409 for a built-in, 404 if unknown.
#[utoipa::path(
    delete,
    path = "/v1/scenarios/{id}",
    operation_id = "deleteScenario",
    tag = "scenarios",
    summary = "Delete a scenario",
    description = "Removes a client-registered scenario. Built-in scenarios cannot be deleted.",
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
    let registry = state.registry.clone();
    tokio::task::spawn_blocking(move || registry.remove(&id)).await??;
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
    let planner = lookup(&state, id)?;
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
