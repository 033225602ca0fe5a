//! HTTP layer: a thin JSON API over the [`planner`](crate::planner).
//!
//! [`router`] builds the whole application from an [`AppState`]; the binary
//! only binds and serves it. Every error is an [`ApiError`], rendered as
//! `application/problem+json`. CPU work runs off the async workers: plans on
//! rayon's global pool, at most one per worker at a time ([`on_rayon`]), and
//! scenario precomputation on a pool of its own
//! ([`precompute`](crate::catalog::precompute)).
//!
//! | Method | Path | Success |
//! |---|---|---|
//! | GET | `/healthz` | 200 `{"status":"ok"}` |
//! | GET | `/v1/scenarios` | 200 `{"scenarios":[…]}` |
//! | POST | `/v1/scenarios` | 201 (new) or 200 (existing) summary |
//! | GET | `/v1/scenarios/{id}` | 200 summary |
//! | DELETE | `/v1/scenarios/{id}` | 204 |
//! | GET | `/v1/scenarios/{id}/stats` | 200 per-cell statistics |
//! | POST | `/v1/scenarios/{id}/plan` | 200 [`PlanResponse`](crate::planner::PlanResponse) |
//! | POST | `/v1/plan` | 200 plan (scenario by id or inline) |
//! | POST | `/v1/scenarios/{id}/evaluate` | 200 [`EvaluateResponse`](crate::evaluate::EvaluateResponse) |
//! | POST | `/v1/evaluate` | 200 scores (scenario by id or inline) |
//! | POST | `/v1/sessions` | 201 session |
//! | GET | `/v1/sessions/{id}` | 200 session |
//! | DELETE | `/v1/sessions/{id}` | 204 |
//! | POST | `/v1/sessions/{id}/step` | 200 plan and step number |

/// The rules of a scenario spec that no JSON Schema can state, for the
/// operations' descriptions (the fuzzer's list is `.ci/schemathesis/hooks.py`).
macro_rules! spec_rules {
    () => {
        " Rules no schema can state (each a 422 whose `detail` names the field): the zone's \
        width and height are whole multiples of `cell_size`, and the lattice has at most \
        4,000,000 cells; every source lies strictly outside the zone, its coordinates within \
        ±1e12; a source without \
        `direction` is beside exactly one edge of the zone or gives a `heading` whose \
        half-plane holds the zone; some direction of each source's cone enters the zone; \
        `target_speed` is required when some source gives no `speeds`; a source's weights sum \
        to a finite number; Σ rate·diagonal/speed over the speed classes is at most 1e9 \
        (the statistics stay finite); each obstacle's polygon is convex, with no repeated \
        vertex and no three consecutive ones collinear, and not wholly outside the zone; no \
        source lies inside a building, and some direction of each source's cone enters the \
        zone before any building."
    };
}

/// The rules of a plan request that no JSON Schema can state.
macro_rules! plan_rules {
    () => {
        " Rules no schema can state (each a 422 whose `detail` names the field): every sensor \
        and history position lies in the scenario's zone, and sensor ids are unique; no ground \
        sensor (a type not `elevated`), now or in the history, stands on a cell whose centre \
        lies in a building; and with obstacles the estimator is `exact`."
    };
}

/// The rules of an evaluate request's paths that no JSON Schema can state.
macro_rules! path_rules {
    () => {
        " The paths' rules (each a 422 whose `detail` names the field): one path per sensor, \
        each naming a sensor of `sensors` once, of exactly T cells (the horizon's steps 1..T), \
        every cell on the lattice and outside the no-go zones (and, for a ground sensor, \
        outside the buildings), each step a move of at most the sensor type's speed (king \
        moves) that free cells allow, from the sensor's own cell."
    };
}

pub mod carries;
pub mod config;
pub mod doc;
pub mod error;
pub mod evaluate;
pub mod extract;
pub mod fit;
pub mod health;
pub mod middleware;
pub mod openapi;
pub mod plan;
pub mod planning;
pub mod queue;
pub mod scenarios;
pub mod serve;
pub mod session_store;
pub mod sessions;
pub mod state;

use axum::Router;
use axum::error_handling::HandleErrorLayer;
use axum::extract::DefaultBodyLimit;
use axum::http::{HeaderValue, Method, Uri, header};
use axum::routing::{get, post};
use tower::ServiceBuilder;
use tower::limit::GlobalConcurrencyLimitLayer;
use tower_http::cors::{Any, CorsLayer};
use tower_http::request_id::{MakeRequestUuid, PropagateRequestIdLayer, SetRequestIdLayer};
use tower_http::trace::{DefaultOnFailure, TraceLayer};
use tracing::Level;

use crate::limits::{MAX_BODY_BYTES, MAX_FIT_BODY_BYTES};

pub use error::{ApiError, Problem};
pub use queue::{QUEUE_PER_WORKER, on_rayon, on_this_worker};
pub use session_store::SessionStore;
pub use state::AppState;

/// The application: every route; on /v1, the API key check (when set), then
/// load shedding past a global concurrency limit (503) and a time limit
/// (504); problem+json fallbacks for unknown routes (404) and methods (405);
/// a body limit of [`MAX_BODY_BYTES`] (413); request metrics, request ids,
/// tracing and CORS (when configured).
pub fn router(state: AppState) -> Router {
    let settings = state.settings.clone();
    let v1 = Router::new()
        .route(
            "/v1/scenarios",
            get(scenarios::list).post(scenarios::create),
        )
        .route(
            "/v1/scenarios/{id}",
            get(scenarios::get).delete(scenarios::delete),
        )
        .route("/v1/scenarios/{id}/stats", get(scenarios::stats))
        .route(
            "/v1/scenarios/{id}/fit",
            // A window of observations is larger than a plan request.
            post(fit::fit).layer(DefaultBodyLimit::max(MAX_FIT_BODY_BYTES)),
        )
        .route("/v1/scenarios/{id}/plan", post(plan::plan))
        .route("/v1/plan", post(plan::plan_inline))
        .route("/v1/scenarios/{id}/evaluate", post(evaluate::evaluate))
        .route("/v1/evaluate", post(evaluate::evaluate_inline))
        .route("/v1/sessions", post(sessions::create))
        .route(
            "/v1/sessions/{id}",
            get(sessions::get).delete(sessions::delete),
        )
        .route("/v1/sessions/{id}/step", post(sessions::step))
        .layer(
            ServiceBuilder::new()
                .layer(HandleErrorLayer::new(middleware::overload_error))
                .load_shed()
                .layer(GlobalConcurrencyLimitLayer::new(settings.max_in_flight))
                .timeout(settings.request_timeout),
        )
        .layer(axum::middleware::from_fn_with_state(
            state.clone(),
            middleware::require_key,
        ));
    let app = Router::new()
        .route("/healthz", get(health::healthz))
        .route("/openapi.json", get(openapi::serve))
        .route("/metrics", get(middleware::render))
        .merge(v1)
        // Must follow the routes: it applies to those already added.
        .method_not_allowed_fallback(method_not_allowed)
        .fallback(not_found)
        .layer(DefaultBodyLimit::max(MAX_BODY_BYTES))
        .layer(axum::middleware::from_fn(middleware::track))
        // Failures are logged where they are made (`ApiError`), once and
        // at their level; shed requests (503) not at all above debug.
        .layer(TraceLayer::new_for_http().on_failure(DefaultOnFailure::new().level(Level::DEBUG)))
        .layer(PropagateRequestIdLayer::x_request_id())
        .layer(SetRequestIdLayer::x_request_id(MakeRequestUuid));
    let app = match cors(&settings.cors_origins) {
        Some(layer) => app.layer(layer),
        None => app,
    };
    // Install the metrics recorder before the first request records.
    middleware::prometheus();
    app.with_state(state)
}

/// The CORS layer for the configured origins, if any.
fn cors(origins: &[String]) -> Option<CorsLayer> {
    if origins.is_empty() {
        return None;
    }
    let layer = CorsLayer::new()
        .allow_methods([Method::GET, Method::POST, Method::DELETE])
        .allow_headers([header::CONTENT_TYPE, header::AUTHORIZATION]);
    Some(if origins.iter().any(|o| o == "*") {
        layer.allow_origin(Any)
    } else {
        let list: Vec<HeaderValue> = origins
            .iter()
            .filter_map(|o| HeaderValue::from_str(o).ok())
            .collect();
        layer.allow_origin(list)
    })
}

async fn not_found(uri: Uri) -> ApiError {
    ApiError::RouteNotFound(uri.path().to_owned())
}

async fn method_not_allowed(method: Method, uri: Uri) -> ApiError {
    ApiError::MethodNotAllowed {
        method: method.to_string(),
        path: uri.path().to_owned(),
    }
}
