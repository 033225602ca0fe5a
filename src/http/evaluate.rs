//! `POST /v1/scenarios/{id}/evaluate` and `POST /v1/evaluate`: scoring
//! given paths (see [`crate::evaluate`]).

use std::sync::Arc;

use axum::Extension;
use axum::extract::State;

use super::doc::{self, examples};
use super::error::ApiError;
use super::extract::{Json, Path, QueuedJson};
use super::middleware::RequestStart;
use super::planning::{CancelOnDrop, refuse_if_costly, with_scenario};
use super::state::AppState;
use crate::cost;
use crate::evaluate::{EvaluateInput, EvaluateRequest, EvaluateResponse};
use crate::planner::Planner;

/// Validates `req`, refuses it past the plan cost limit, and scores it on
/// rayon, cancelled as soon as nobody waits for it.
async fn evaluate_admitted(
    state: &AppState,
    start: Option<Extension<RequestStart>>,
    planner: Arc<Planner>,
    req: &EvaluateRequest,
) -> Result<EvaluateResponse, ApiError> {
    let input = EvaluateInput::new(&planner, req)?;
    let predicted_ms = cost::evaluate_ms(&planner, &input.plan, &input.paths);
    refuse_if_costly(state, predicted_ms)?;
    let guard = CancelOnDrop::new("evaluate", start, state);
    let token = guard.token();
    let res = super::queue::on_rayon(move || planner.evaluate(&input, &token)).await;
    guard.finish();
    res?.map_err(|_| ApiError::Timeout)
}

/// `POST /v1/scenarios/{id}/evaluate`, body [`EvaluateRequest`] → 200
/// [`EvaluateResponse`].
#[utoipa::path(
    post,
    path = "/v1/scenarios/{id}/evaluate",
    operation_id = "evaluateScenario",
    tag = "planning",
    summary = "Score given paths of the sensors",
    description = concat!("Scores one path per sensor, whoever planned it: the expected number of \
        distinct targets detected over steps 1..T (the total a plan reports as \
        `expected_detections`, and per step), each sensor's marginal (what the total loses \
        without its path) and the breaches of the minimum separation, with the requested \
        estimator. The body is a plan request (its `coordination`, `explain`, `gap_target`, \
        `budget_ms` and `certify` are checked as a plan checks them, so a plan's body scores as \
        sent, and play no part) plus `paths`. A plan's own paths score its \
        `expected_detections`. With the `paper` estimator, whose total depends on the order, \
        the paths count in the order given, the first as the highest priority.", plan_rules!(), path_rules!()),
    params(("id" = String, Path, description = doc::SCENARIO_ID, example = "paper-v10")),
    request_body(content = doc::EvaluateBody, description = "Sensors, targets, options and the paths.",
        example = json!(examples::evaluate_request())),
    responses(
        (status = 200, description = "The paths' scores.", body = EvaluateResponse,
            example = json!(examples::evaluate_response())),
        (status = 400, response = doc::MalformedBody),
        (status = 404, response = doc::ScenarioNotFound),
        (status = 413, response = doc::PayloadTooLarge),
        (status = 422, response = doc::InvalidEvaluateRequest),
        (status = 503, response = doc::NotReady),
    )
)]
pub async fn evaluate(
    State(state): State<AppState>,
    start: Option<Extension<RequestStart>>,
    Path(id): Path<String>,
    body: Result<QueuedJson<EvaluateRequest>, ApiError>,
) -> Result<Json<EvaluateResponse>, ApiError> {
    let planner = state.registry.resolve(&id).await?;
    let QueuedJson(req) = body?;
    Ok(Json(evaluate_admitted(&state, start, planner, &req).await?))
}

/// `POST /v1/evaluate`: the body of `/v1/scenarios/{id}/evaluate` plus
/// either `"scenario_id"` or an inline `"scenario"`, as in `POST /v1/plan`.
#[utoipa::path(
    post,
    path = "/v1/evaluate",
    operation_id = "evaluate",
    tag = "planning",
    summary = "Score given paths in a scenario named or sent inline",
    description = concat!("The same scoring as `POST /v1/scenarios/{id}/evaluate`, with the scenario \
        in the body as in `POST /v1/plan`: exactly one of `scenario_id` and `scenario`.",
        plan_rules!(), path_rules!(), spec_rules!()),
    request_body(content = doc::InlineEvaluateRequest, description = "Scenario, sensors, targets, options and the paths.",
        example = json!(examples::evaluate_request_by_id())),
    responses(
        (status = 200, description = "The paths' scores.", body = EvaluateResponse,
            example = json!(examples::evaluate_response())),
        (status = 400, response = doc::MalformedBody),
        (status = 404, response = doc::ScenarioNotFound),
        (status = 413, response = doc::PayloadTooLarge),
        (status = 422, response = doc::InvalidInlineEvaluateRequest),
        (status = 503, response = doc::NotReady),
    )
)]
pub async fn evaluate_inline(
    State(state): State<AppState>,
    start: Option<Extension<RequestStart>>,
    QueuedJson(body): QueuedJson<serde_json::Value>,
) -> Result<Json<EvaluateResponse>, ApiError> {
    let (planner, req): (_, EvaluateRequest) = with_scenario(&state, start, body).await?;
    Ok(Json(evaluate_admitted(&state, start, planner, &req).await?))
}
