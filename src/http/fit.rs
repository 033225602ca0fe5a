//! `POST /v1/scenarios/{id}/fit`: source rates fitted from a window of
//! observations (see [`crate::fit`]).

use std::sync::Arc;

use axum::Extension;
use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};

use super::doc::{self, examples};
use super::error::ApiError;
use super::extract::{Json, Path, QueuedJson};
use super::middleware::RequestStart;
use super::planning::{CancelOnDrop, refuse_if_costly};
use super::scenarios::{location, register, registration_status};
use super::state::AppState;
use crate::catalog::entry_id;
use crate::cost;
use crate::fit::{self, FitRequest, FitResponse, FitWindow, WindowLooks};
use crate::planner::Planner;
use crate::scenario::Scenario;

/// Validates `req`, refuses it past the plan cost limit, and fits it on
/// rayon, dropped as soon as nobody waits for it.
async fn fit_admitted(
    state: &AppState,
    start: Option<Extension<RequestStart>>,
    planner: Arc<Planner>,
    req: FitRequest,
) -> Result<(FitResponse, FitWindow), ApiError> {
    // A window of 500 steps takes milliseconds to check and to size: off
    // the async workers.
    let checked = planner.clone();
    let (window, crossings) = tokio::task::spawn_blocking(move || {
        let s = &checked.scenario;
        let window = FitWindow::new(s, &req)?;
        let crossings = WindowLooks::new(s, &window.looks).work();
        Ok::<_, ApiError>((window, crossings))
    })
    .await??;
    refuse_if_costly(state, cost::fit_ms(&planner.scenario, crossings))?;
    let guard = CancelOnDrop::new("fit", start, state);
    let res = super::queue::on_rayon(move || {
        let fitted = fit::fit(&planner.scenario, &window);
        (fitted, window)
    })
    .await;
    guard.finish();
    res
}

/// `POST /v1/scenarios/{id}/fit`, body [`FitRequest`] → 200 [`FitResponse`]
/// (201 with `Location` when it registers the fitted scenario).
#[utoipa::path(
    post,
    path = "/v1/scenarios/{id}/fit",
    operation_id = "fitScenario",
    tag = "scenarios",
    summary = "Fit the sources' rates to what the sensors saw",
    description = "Estimates each source's Poisson rate from a window of consecutive steps \
        (oldest first, 1 to 500): each step's sensors (their looks, at cell centres, as in a \
        plan) and the targets they detected, each with a track id that follows it across \
        steps (each target counts once). A source's distinct detected targets are Poisson \
        with mean `rate × exposure`, where `exposure` (steps) counts every target in the zone \
        during the window that the looks could have detected, those inside at its first step \
        included; each detected target is traced back along its velocity to the sources whose \
        position, takeoff cone and speeds explain it (shared in proportion to their rates and \
        densities when several do), within `tolerance`. The answer is each source's posterior \
        mean `rate` and 95% credible `interval` under a Gamma prior (`scenario`: shape 1, mean \
        the spec's rate; `flat`: uniform, Gamma(N + 1, E)); the targets no source explains are \
        listed with where their track entered the zone (a gate the scenario is missing?). With \
        `register: true` the same spec with the fitted rates is registered as a new scenario \
        (201 with `Location`, 202 when it is precomputed as a job, 200 when it was registered \
        already) and the answer adds its `id`. See `docs/learning.md`. A detection outside \
        every field of view of its step, a track id that jumps further than a target flies, \
        steps whose `step` numbers are not consecutive, an unknown sensor type, a sensor on \
        ground its type may not stand on: 422 naming the field. A window predicted above \
        `--max-plan-ms` is refused with 422, as a plan is.",
    params(("id" = String, Path, description = doc::SCENARIO_ID, example = "paper-v10")),
    request_body(content = FitRequest, description = "The window of observations.",
        example = json!(examples::fit_request())),
    responses(
        (status = 200, description = "The fitted rates.", body = FitResponse,
            example = json!(examples::fit_response())),
        (status = 201, description = "The fitted rates, and the fitted scenario registered and \
            precomputed (`id`).", body = FitResponse,
            headers(("Location" = String, description = "`/v1/scenarios/{id}` of the fitted scenario."))),
        (status = 202, description = "The fitted rates; the fitted scenario is being \
            precomputed as a job (`id`): poll its `Location`.", body = FitResponse,
            headers(("Location" = String, description = "`/v1/scenarios/{id}` of the fitted scenario."))),
        (status = 400, response = doc::MalformedBody),
        (status = 404, response = doc::ScenarioNotFound),
        (status = 413, response = doc::PayloadTooLarge),
        (status = 422, response = doc::InvalidFitRequest),
        (status = 503, response = doc::NotReady),
    )
)]
pub async fn fit(
    State(state): State<AppState>,
    start: Option<Extension<RequestStart>>,
    Path(id): Path<String>,
    body: Result<QueuedJson<FitRequest>, ApiError>,
) -> Result<Response, ApiError> {
    let planner = state.registry.resolve(&id).await?;
    let QueuedJson(req) = body?;
    let (mut fitted, window) = fit_admitted(&state, start, planner.clone(), req).await?;
    if !window.register {
        return Ok(Json(fitted).into_response());
    }
    let mut spec = planner.scenario.spec.clone();
    for (src, rate) in spec.sources.iter_mut().zip(&fitted.sources) {
        src.rate = rate.rate;
    }
    let (entry, _, created) = register(&state, start, Scenario::new(spec)?).await?;
    fitted.id = Some(entry_id(&entry).to_owned());
    let status = registration_status(&entry, created);
    if status == StatusCode::OK {
        return Ok(Json(fitted).into_response());
    }
    Ok((
        status,
        [(header::LOCATION, location(&entry)?)],
        Json(fitted),
    )
        .into_response())
}
