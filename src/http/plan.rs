//! `POST /v1/scenarios/{id}/plan`.

use axum::extract::State;

use super::AppState;
use super::error::ApiError;
use super::extract::{Json, Path};
use crate::planner::{PlanRequest, PlanResponse};

/// `POST /v1/scenarios/{id}/plan`, body [`PlanRequest`] → 200
/// [`PlanResponse`]; 404 for an unknown scenario (checked before the body),
/// 400 for a malformed body, 422 for a value out of bounds.
pub async fn plan(
    State(state): State<AppState>,
    Path(id): Path<String>,
    body: Result<Json<PlanRequest>, ApiError>,
) -> Result<Json<PlanResponse>, ApiError> {
    let planner = state
        .registry
        .get(&id)
        .ok_or(ApiError::ScenarioNotFound(id))?;
    let Json(req) = body?;
    let res = tokio::task::spawn_blocking(move || planner.plan_request(&req)).await??;
    Ok(Json(res))
}
