//! `POST /v1/scenarios/{id}/plan`.

use axum::Extension;
use axum::extract::State;

use super::doc::{self, examples};
use super::error::ApiError;
use super::extract::{Json, Path, QueuedJson};
use super::middleware::RequestStart;
use super::planning::{plan_admitted, with_scenario};
use super::state::AppState;

use crate::planner::{PlanRequest, PlanResponse};

/// `POST /v1/scenarios/{id}/plan`, body [`PlanRequest`] → 200
/// [`PlanResponse`]; 404 for an unknown scenario (checked before the body),
/// 400 for a malformed body, 422 for a value out of bounds.
#[utoipa::path(
    post,
    path = "/v1/scenarios/{id}/plan",
    operation_id = "planScenario",
    tag = "planning",
    summary = "Plan the sensors' next T steps",
    description = concat!("Plans coordinated T-step paths for the sensors that maximise the expected \
        number of distinct targets detected, given the targets reported now (and optionally the \
        sensors' past positions). Positions are snapped to the scenario's lattice. The scenario \
        is looked up before the body is read, so an unknown id is 404 whatever the body (and one \
        still being precomputed 503). A plan whose cost the server predicts above its limit \
        (`--max-plan-ms`, 2 s of CPU by default) is refused with 422 before any work starts.", plan_rules!()),
    params(("id" = String, Path, description = doc::SCENARIO_ID, example = "paper-v10")),
    request_body(content = PlanRequest, description = "Sensors, targets and options.",
        examples(
            ("paper-v10" = (summary = "Three sensors and three targets on paper-v10",
                value = json!(examples::plan_request()))),
            ("minimal" = (summary = "One sensor, no targets, every option by default",
                value = json!({"sensors": [{"id": "a", "x": 150.0, "y": 150.0}]}))),
            ("apart" = (summary = "Sensors kept at least 3 cells apart at every step",
                value = json!(examples::plan_request_apart()))),
        )),
    responses(
        (status = 200, description = "One plan per sensor, in request order.", body = PlanResponse,
            example = json!(examples::plan_response())),
        (status = 400, response = doc::MalformedBody),
        (status = 404, response = doc::ScenarioNotFound),
        (status = 413, response = doc::PayloadTooLarge),
        (status = 422, response = doc::InvalidPlanRequest),
        (status = 503, response = doc::NotReady),
    )
)]
pub async fn plan(
    State(state): State<AppState>,
    start: Option<Extension<RequestStart>>,
    Path(id): Path<String>,
    body: Result<QueuedJson<PlanRequest>, ApiError>,
) -> Result<Json<PlanResponse>, ApiError> {
    let planner = state.registry.resolve(&id).await?;
    let QueuedJson(req) = body?;
    Ok(Json(plan_admitted(&state, start, planner, &req).await?))
}

/// `POST /v1/plan`: the body of `/v1/scenarios/{id}/plan` plus either
/// `"scenario_id"` (a registered or cached scenario) or an inline
/// `"scenario"` (a ScenarioSpec). Inline scenarios are precomputed once and
/// kept in a memory-bounded LRU cache, so a replica needs nothing from
/// another to serve any request.
#[utoipa::path(
    post,
    path = "/v1/plan",
    operation_id = "plan",
    tag = "planning",
    summary = "Plan in a scenario named or sent inline",
    description = concat!("The same planning as `POST /v1/scenarios/{id}/plan`, with the scenario in the \
        body: either `scenario_id` (a registered scenario, or one sent inline before) or \
        `scenario` (a spec, precomputed on first use and kept in a memory-bounded LRU cache, \
        not registered). Exactly one of the two is required. An inline scenario whose \
        precomputation is predicted above the server's synchronous budget is refused with 422: \
        register it instead. A plan predicted above `--max-plan-ms` is refused with 422 too.", plan_rules!(), spec_rules!()),
    request_body(content = doc::InlinePlanRequest, description = "Scenario, sensors, targets and options.",
        examples(
            ("by-id" = (summary = "paper-v10 by id", value = json!(examples::plan_request_by_id()))),
            ("inline" = (summary = "A scenario sent inline", value = json!(examples::plan_request_inline()))),
        )),
    responses(
        (status = 200, description = "One plan per sensor, in request order.", body = PlanResponse,
            example = json!(examples::plan_response())),
        (status = 400, response = doc::MalformedBody),
        (status = 404, response = doc::ScenarioNotFound),
        (status = 413, response = doc::PayloadTooLarge),
        (status = 422, response = doc::InvalidInlinePlanRequest),
        (status = 503, response = doc::NotReady),
    )
)]
pub async fn plan_inline(
    State(state): State<AppState>,
    start: Option<Extension<RequestStart>>,
    QueuedJson(body): QueuedJson<serde_json::Value>,
) -> Result<Json<PlanResponse>, ApiError> {
    let (planner, req): (_, PlanRequest) = with_scenario(&state, start, body).await?;
    Ok(Json(plan_admitted(&state, start, planner, &req).await?))
}
