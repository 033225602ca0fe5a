//! Middleware: the API key check, request metrics, and the overload and
//! timeout errors of the /v1 stack.

use std::sync::OnceLock;
use std::time::Instant;

use axum::extract::{MatchedPath, Request, State};
use axum::http::header;
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use metrics_exporter_prometheus::{PrometheusBuilder, PrometheusHandle};
use subtle::ConstantTimeEq;
use tower::BoxError;

use super::error::ApiError;
use super::state::AppState;
use crate::metric_names;

/// Requires `Authorization: Bearer <key>` when an API key is configured;
/// the key is compared in constant time.
pub async fn require_key(State(state): State<AppState>, req: Request, next: Next) -> Response {
    if let Some(key) = &state.settings.api_key {
        let given = req
            .headers()
            .get(header::AUTHORIZATION)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.strip_prefix("Bearer "))
            .unwrap_or("");
        // Lengths are compared in the open; contents in constant time.
        let ok = given.len() == key.len() && bool::from(given.as_bytes().ct_eq(key.as_bytes()));
        if !ok {
            return ApiError::Unauthorized.into_response();
        }
    }
    next.run(req).await
}

/// Maps the errors of the overload stack: a shed request is 503 with
/// Retry-After, an expired one 504.
pub async fn overload_error(err: BoxError) -> ApiError {
    if err.is::<tower::load_shed::error::Overloaded>() {
        metrics::counter!(metric_names::HTTP_SHED_TOTAL).increment(1);
        ApiError::Overloaded
    } else if err.is::<tower::timeout::error::Elapsed>() {
        ApiError::Timeout
    } else {
        ApiError::Internal(err.to_string())
    }
}

/// The process's Prometheus recorder, installed on first use (`None` if
/// another recorder was installed first).
pub fn prometheus() -> Option<&'static PrometheusHandle> {
    static HANDLE: OnceLock<Option<PrometheusHandle>> = OnceLock::new();
    HANDLE
        .get_or_init(|| {
            let buckets = [
                0.0001, 0.00025, 0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5,
                1.0, 2.5, 5.0, 10.0, 30.0,
            ];
            PrometheusBuilder::new()
                .set_buckets(&buckets)
                .and_then(|b| b.install_recorder())
                .map_err(|e| tracing::warn!(error = %e, "Prometheus metrics unavailable"))
                .ok()
        })
        .as_ref()
}

/// When the request reached the server, before its time limit started: a
/// handler whose work is cancelled reads it to tell a timeout from a
/// client that went away.
#[derive(Debug, Clone, Copy)]
pub struct RequestStart(pub Instant);

/// Counts requests by route and status, tracks those in flight, times
/// plans, and marks each request with its [`RequestStart`].
pub async fn track(mut req: Request, next: Next) -> Response {
    let route = req
        .extensions()
        .get::<MatchedPath>()
        .map_or_else(|| "unmatched".to_owned(), |p| p.as_str().to_owned());
    let method = req.method().to_string();
    let started = Instant::now();
    req.extensions_mut().insert(RequestStart(started));
    metrics::gauge!(metric_names::HTTP_REQUESTS_IN_FLIGHT).increment(1.0);
    let res = next.run(req).await;
    metrics::gauge!(metric_names::HTTP_REQUESTS_IN_FLIGHT).decrement(1.0);
    let status = res.status().as_u16().to_string();
    if route.ends_with("/plan") || route.ends_with("/step") {
        metrics::histogram!(metric_names::PLAN_DURATION_SECONDS, "route" => route.clone())
            .record(started.elapsed().as_secs_f64());
    }
    metrics::counter!(metric_names::HTTP_REQUESTS_TOTAL, "method" => method, "route" => route, "status" => status)
        .increment(1);
    res
}

/// `GET /metrics`: the Prometheus text exposition.
#[utoipa::path(
    get,
    path = "/metrics",
    operation_id = "getMetrics",
    tag = "meta",
    summary = "Prometheus metrics",
    description = "Request counts by route and status, requests in flight, shed requests, plan \
        and precomputation durations, in the Prometheus text exposition format. Never requires \
        authentication.",
    responses(
        (status = 200, description = "The metrics.", body = String,
            content_type = "text/plain; version=0.0.4",
            example = json!("# TYPE vigil_http_requests_total counter\n\
                vigil_http_requests_total{method=\"GET\",route=\"/healthz\",status=\"200\"} 1\n")),
    )
)]
pub async fn render() -> Response {
    let body = prometheus()
        .map(PrometheusHandle::render)
        .unwrap_or_default();
    ([(header::CONTENT_TYPE, "text/plain; version=0.0.4")], body).into_response()
}
