//! `/v1/scenarios`: list, register, read, delete scenarios, and read their
//! per-cell statistics.

use std::sync::Arc;

use axum::extract::State;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};

use super::AppState;
use super::error::ApiError;
use super::extract::{Json, Path};
use crate::planner::Planner;
use crate::scenario::{Scenario, ScenarioSpec};

/// Size of a scenario's lattice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Grid {
    /// Columns.
    pub cols: i32,
    /// Rows.
    pub rows: i32,
}

/// Scalar results of a scenario's precomputation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SummaryStats {
    /// Stationary expected number of targets inside the zone.
    pub expected_targets_in_zone: f64,
    /// Time the precomputation took, milliseconds.
    pub precompute_ms: f64,
}

/// A registered scenario, as `GET /v1/scenarios/{id}` returns it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
                expected_targets_in_zone: p.stats.expected_targets_in_zone,
                precompute_ms: p.precompute_ms,
            },
        }
    }
}

/// Body of `GET /v1/scenarios`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenarioList {
    /// Every registered scenario, sorted by id.
    pub scenarios: Vec<ScenarioSummary>,
}

/// Body of `GET /v1/scenarios/{id}/stats`: per-cell statistics, row-major
/// (`row·cols + col`). Borrows from the planner, so large lattices are not
/// copied before serialization.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ScenarioStats<'a> {
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

impl<'a> From<&'a Planner> for ScenarioStats<'a> {
    fn from(p: &'a Planner) -> Self {
        Self {
            cols: p.scenario.cols,
            rows: p.scenario.rows,
            cell_size: p.scenario.cell_size,
            lambda_hat: &p.stats.lambda_hat,
            escape_time: &p.stats.escape_time,
            d_hat: &p.stats.d_hat,
        }
    }
}

fn lookup(state: &AppState, id: String) -> Result<Arc<Planner>, ApiError> {
    state
        .registry
        .get(&id)
        .ok_or(ApiError::ScenarioNotFound(id))
}

/// `GET /v1/scenarios` → 200 [`ScenarioList`].
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
pub async fn create(
    State(state): State<AppState>,
    Json(spec): Json<ScenarioSpec>,
) -> Result<Response, ApiError> {
    let scenario = Scenario::new(spec)?;
    if let Some(existing) = state.registry.get(&scenario.id) {
        return Ok(Json(ScenarioSummary::from(existing.as_ref())).into_response());
    }
    let planner = tokio::task::spawn_blocking(move || Planner::new(scenario)).await?;
    // A concurrent identical request may have registered it meanwhile; the
    // first one stays.
    let (planner, created) = state.registry.insert(Arc::new(planner));
    let body = Json(ScenarioSummary::from(planner.as_ref()));
    if !created {
        return Ok(body.into_response());
    }
    let location = HeaderValue::try_from(format!("/v1/scenarios/{}", planner.scenario.id))
        .map_err(|e| ApiError::Internal(format!("bad Location header: {e}")))?;
    Ok((StatusCode::CREATED, [(header::LOCATION, location)], body).into_response())
}

/// `GET /v1/scenarios/{id}` → 200 [`ScenarioSummary`]; 404 if unknown.
pub async fn get(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<ScenarioSummary>, ApiError> {
    let planner = lookup(&state, id)?;
    Ok(Json(ScenarioSummary::from(planner.as_ref())))
}

/// `DELETE /v1/scenarios/{id}` → 204; 409 for a built-in, 404 if unknown.
pub async fn delete(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    state.registry.remove(&id)?;
    Ok(StatusCode::NO_CONTENT)
}

/// `GET /v1/scenarios/{id}/stats` → 200 [`ScenarioStats`]; 404 if unknown.
/// Serialized on the blocking pool, as a large lattice gives a large body.
pub async fn stats(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    let planner = lookup(&state, id)?;
    let body = tokio::task::spawn_blocking(move || {
        serde_json::to_vec(&ScenarioStats::from(planner.as_ref()))
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
