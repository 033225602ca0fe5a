//! The API's one error type, rendered as RFC 9457 problem details
//! (`application/problem+json`).

use axum::Json;
use axum::extract::rejection::{BytesRejection, JsonRejection, PathRejection};
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use crate::catalog::{CatalogError, JobStatus};
use crate::scenario::ValidationError;

/// Seconds a client should wait after [`ApiError::DatabaseUnavailable`].
pub const DATABASE_RETRY_S: u64 = 2;

/// Media type of error bodies.
pub const PROBLEM_JSON: &str = "application/problem+json";

/// Base of the `type` URIs of our problems.
const PROBLEM_BASE: &str = "https://vigil.dev/problems/";

/// Everything a handler can fail with. Each variant maps to one status code
/// and one problem `type`.
#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// The request body is not acceptable JSON for the endpoint (syntax
    /// error, wrong or missing `Content-Type`, missing field, wrong type). 400.
    #[error("{0}")]
    MalformedBody(String),
    /// A path parameter could not be decoded. 400.
    #[error("{0}")]
    BadPath(String),
    /// The request body exceeds the size limit. 413.
    #[error("{0}")]
    PayloadTooLarge(String),
    /// No scenario has this id. 404.
    #[error("no scenario with id `{0}`")]
    ScenarioNotFound(String),
    /// The scenario has no sensor type of this name. 404.
    #[error("scenario `{scenario}` has no sensor type `{name}` (it has {known})")]
    SensorTypeNotFound {
        /// The scenario's id.
        scenario: String,
        /// The type asked for.
        name: String,
        /// The scenario's type names, comma-separated.
        known: String,
    },
    /// A query parameter could not be decoded. 400.
    #[error("{0}")]
    BadQuery(String),
    /// No route matches the path. 404.
    #[error("no resource at `{0}`")]
    RouteNotFound(String),
    /// The route exists but not for this method. 405.
    #[error("method {method} is not allowed on `{path}`")]
    MethodNotAllowed {
        /// The method used.
        method: String,
        /// The request path.
        path: String,
    },
    /// A built-in scenario cannot be deleted. 409.
    #[error("scenario `{0}` is built in and cannot be deleted")]
    BuiltinScenario(String),
    /// A value of the request is outside its bounds. 422.
    #[error(transparent)]
    Validation(#[from] ValidationError),
    /// No or a wrong API key. 401.
    #[error("a valid `Authorization: Bearer <key>` header is required")]
    Unauthorized,
    /// Shed under load. 503 with Retry-After.
    #[error("the server is at capacity; retry shortly")]
    Overloaded,
    /// The request ran out of time. 504.
    #[error("the request took longer than the server's time limit")]
    Timeout,
    /// A request-level bound other than a field's. 422.
    #[error("{0}")]
    Unprocessable(String),
    /// No session has this id (never created, expired or evicted). 404.
    #[error(
        "no session with id `{id}`: it was never created, or was dropped after {ttl_s} s idle or to make room; create a new one with POST /v1/sessions"
    )]
    SessionNotFound {
        /// The id asked for.
        id: String,
        /// The sessions' idle time to live, seconds.
        ttl_s: u64,
    },
    /// Another step of the session was stored while this one was made, and
    /// making it again from that step's state kept losing the race. 409.
    #[error(
        "session `{0}` was stepped by other requests while this step was made, and again each time it was made anew; send it again (with the same Idempotency-Key, a step already made is answered, not made twice)"
    )]
    SessionConflict(String),
    /// A step's `Idempotency-Key` is the session's last step's, but its
    /// body is not that step's: a new step sent with an old key, which a
    /// replay would silently drop. 422.
    #[error(
        "Idempotency-Key: `{0}` named the session's last step, whose body was not this one; a retry sends the same body, and a new step a new key"
    )]
    IdempotencyKeyReused(String),
    /// A request header is not acceptable (e.g. an `Idempotency-Key` over
    /// its length). 400.
    #[error("{0}")]
    BadHeader(String),
    /// The scenario is still being precomputed. 503 with Retry-After.
    #[error("scenario `{id}` is still {}; retry in about {} s", if status.queue_position.is_some() { "queued for precomputation" } else { "precomputing" }, status.retry_after_s())]
    ScenarioNotReady {
        /// The scenario's id.
        id: String,
        /// Its job's status.
        status: JobStatus,
    },
    /// The precomputation queue is full. 503 with Retry-After.
    #[error("{limit} precomputation jobs are already waiting; retry in about {retry_after_s} s")]
    QueueFull {
        /// The queue's bound.
        limit: usize,
        /// Seconds until a slot is likely to free.
        retry_after_s: u64,
    },
    /// A plan predicted to cost more than the server allows. 422.
    #[error(
        "this plan is predicted to take {predicted_ms:.0} ms of CPU, above this server's limit of {limit_ms:.0} ms (--max-plan-ms); plan fewer sensors, a shorter horizon, fewer targets or less history, or `priority` coordination"
    )]
    PlanTooCostly {
        /// Predicted CPU time, milliseconds.
        predicted_ms: f64,
        /// The limit, milliseconds.
        limit_ms: f64,
    },
    /// An inline scenario whose precomputation would exceed the synchronous
    /// budget. 422.
    #[error(
        "scenario: its precomputation is predicted to take {predicted_ms:.0} ms, above this server's synchronous budget of {budget_ms:.0} ms (--sync-precompute-ms); register it with POST /v1/scenarios (it is precomputed as a job) and plan with its `scenario_id` once it is ready"
    )]
    PrecomputeTooCostly {
        /// Predicted wall time, milliseconds.
        predicted_ms: f64,
        /// The budget, milliseconds.
        budget_ms: f64,
    },
    /// The database holding the scenario catalogue (`--database-url`) is
    /// unreachable or too slow. 503 with Retry-After.
    #[error(
        "the scenario catalogue's database cannot be reached; retry in about {DATABASE_RETRY_S} s (plans on built-in, inline and already used scenarios still work)"
    )]
    DatabaseUnavailable,
    /// A bug: a background task failed or a response could not be built. 500.
    #[error("internal error: {0}")]
    Internal(String),
}

/// The body of an error response (RFC 9457).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[schema(examples(json!({
    "type": "https://vigil.dev/problems/scenario-not-found",
    "title": "Scenario not found",
    "status": 404,
    "detail": "no scenario with id `nope`"
})))]
pub struct Problem {
    /// URI identifying the kind of problem.
    #[serde(rename = "type")]
    #[schema(format = "uri")]
    pub kind: String,
    /// Short summary of the kind of problem.
    pub title: String,
    /// HTTP status code.
    #[schema(minimum = 400, maximum = 599)]
    pub status: u16,
    /// What went wrong with this request.
    pub detail: String,
}

impl ApiError {
    /// HTTP status of this error.
    pub fn status(&self) -> StatusCode {
        match self {
            ApiError::MalformedBody(_) | ApiError::BadPath(_) => StatusCode::BAD_REQUEST,
            ApiError::PayloadTooLarge(_) => StatusCode::PAYLOAD_TOO_LARGE,
            ApiError::ScenarioNotFound(_)
            | ApiError::SessionNotFound { .. }
            | ApiError::RouteNotFound(_)
            | ApiError::SensorTypeNotFound { .. } => StatusCode::NOT_FOUND,
            ApiError::BadQuery(_) | ApiError::BadHeader(_) => StatusCode::BAD_REQUEST,
            ApiError::MethodNotAllowed { .. } => StatusCode::METHOD_NOT_ALLOWED,
            ApiError::BuiltinScenario(_) | ApiError::SessionConflict(_) => StatusCode::CONFLICT,
            ApiError::Validation(_) => StatusCode::UNPROCESSABLE_ENTITY,
            ApiError::Unauthorized => StatusCode::UNAUTHORIZED,
            ApiError::Overloaded => StatusCode::SERVICE_UNAVAILABLE,
            ApiError::Timeout => StatusCode::GATEWAY_TIMEOUT,
            ApiError::Unprocessable(_)
            | ApiError::IdempotencyKeyReused(_)
            | ApiError::PlanTooCostly { .. }
            | ApiError::PrecomputeTooCostly { .. } => StatusCode::UNPROCESSABLE_ENTITY,
            ApiError::ScenarioNotReady { .. }
            | ApiError::QueueFull { .. }
            | ApiError::DatabaseUnavailable => StatusCode::SERVICE_UNAVAILABLE,
            ApiError::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }

    /// Last segment of the problem `type` URI, and the title.
    fn kind(&self) -> (&'static str, &'static str) {
        match self {
            ApiError::MalformedBody(_) => ("malformed-body", "Malformed request body"),
            ApiError::BadPath(_) => ("bad-path", "Invalid path parameter"),
            ApiError::PayloadTooLarge(_) => ("payload-too-large", "Request body too large"),
            ApiError::ScenarioNotFound(_) => ("scenario-not-found", "Scenario not found"),
            ApiError::RouteNotFound(_) => ("not-found", "Not found"),
            ApiError::SensorTypeNotFound { .. } => {
                ("sensor-type-not-found", "Sensor type not found")
            }
            ApiError::BadQuery(_) => ("bad-query", "Invalid query parameter"),
            ApiError::MethodNotAllowed { .. } => ("method-not-allowed", "Method not allowed"),
            ApiError::BuiltinScenario(_) => ("builtin-scenario", "Built-in scenario"),
            ApiError::Validation(_) => ("validation", "Invalid request"),
            ApiError::Unauthorized => ("unauthorized", "Unauthorized"),
            ApiError::Overloaded => ("overloaded", "Service overloaded"),
            ApiError::Timeout => ("timeout", "Request timed out"),
            ApiError::Unprocessable(_) => ("validation", "Invalid request"),
            ApiError::SessionNotFound { .. } => ("session-not-found", "Session not found"),
            ApiError::SessionConflict(_) => {
                ("session-step-conflict", "Session stepped concurrently")
            }
            ApiError::BadHeader(_) => ("bad-header", "Bad header"),
            ApiError::IdempotencyKeyReused(_) => {
                ("idempotency-key-reused", "Idempotency-Key reused")
            }
            ApiError::ScenarioNotReady { .. } => ("scenario-not-ready", "Scenario not ready"),
            ApiError::QueueFull { .. } => ("precompute-queue-full", "Precompute queue full"),
            ApiError::PlanTooCostly { .. } => ("plan-too-costly", "Plan too costly"),
            ApiError::PrecomputeTooCostly { .. } => {
                ("precompute-too-costly", "Scenario too large to plan inline")
            }
            ApiError::DatabaseUnavailable => ("database-unavailable", "Database unavailable"),
            ApiError::Internal(_) => ("internal", "Internal server error"),
        }
    }

    /// The problem details of this error.
    pub fn problem(&self) -> Problem {
        let (slug, title) = self.kind();
        let status = self.status();
        let detail = match self {
            // Do not leak internals to clients; they are logged instead.
            ApiError::Internal(_) => "the server failed to handle the request".to_owned(),
            other => other.to_string(),
        };
        Problem {
            kind: format!("{PROBLEM_BASE}{slug}"),
            title: title.to_owned(),
            status: status.as_u16(),
            detail,
        }
    }

    /// A JSON body sent without a JSON content type.
    pub(crate) fn missing_json_content_type() -> Self {
        ApiError::MalformedBody(
            "expected a request with `Content-Type: application/json`".to_owned(),
        )
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let status = self.status();
        match self {
            // Back-pressure, expected under load and counted in the metrics:
            // a line per request would add to the overload it reports.
            ApiError::Overloaded
            | ApiError::QueueFull { .. }
            | ApiError::ScenarioNotReady { .. } => {
                tracing::debug!(error = %self, "request refused");
            }
            _ if status.is_server_error() => tracing::error!(error = %self, "request failed"),
            _ => {}
        }
        let mut res = (status, Json(self.problem())).into_response();
        let headers = res.headers_mut();
        headers.insert(header::CONTENT_TYPE, HeaderValue::from_static(PROBLEM_JSON));
        match self {
            ApiError::Overloaded => {
                headers.insert(header::RETRY_AFTER, HeaderValue::from_static("1"));
            }
            ApiError::ScenarioNotReady { status, .. } => {
                headers.insert(
                    header::RETRY_AFTER,
                    HeaderValue::from(status.retry_after_s()),
                );
            }
            ApiError::DatabaseUnavailable => {
                headers.insert(header::RETRY_AFTER, HeaderValue::from(DATABASE_RETRY_S));
            }
            ApiError::QueueFull { retry_after_s, .. } => {
                headers.insert(header::RETRY_AFTER, HeaderValue::from(retry_after_s));
            }
            ApiError::Unauthorized => {
                headers.insert(header::WWW_AUTHENTICATE, HeaderValue::from_static("Bearer"));
            }
            _ => {}
        }
        res
    }
}

impl From<JsonRejection> for ApiError {
    fn from(rejection: JsonRejection) -> Self {
        match rejection {
            JsonRejection::JsonDataError(e) => ApiError::MalformedBody(e.body_text()),
            JsonRejection::JsonSyntaxError(e) => ApiError::MalformedBody(e.body_text()),
            JsonRejection::MissingJsonContentType(_) => ApiError::missing_json_content_type(),
            JsonRejection::BytesRejection(e) => e.into(),
            other => ApiError::MalformedBody(other.body_text()),
        }
    }
}

impl From<BytesRejection> for ApiError {
    fn from(rejection: BytesRejection) -> Self {
        if rejection.status() == StatusCode::PAYLOAD_TOO_LARGE {
            ApiError::PayloadTooLarge(rejection.body_text())
        } else {
            ApiError::MalformedBody(rejection.body_text())
        }
    }
}

impl From<PathRejection> for ApiError {
    fn from(rejection: PathRejection) -> Self {
        if rejection.status().is_server_error() {
            ApiError::Internal(rejection.body_text())
        } else {
            ApiError::BadPath(rejection.body_text())
        }
    }
}

impl From<tokio::task::JoinError> for ApiError {
    fn from(e: tokio::task::JoinError) -> Self {
        ApiError::Internal(format!("background task failed: {e}"))
    }
}

impl From<CatalogError> for ApiError {
    fn from(e: CatalogError) -> Self {
        match e {
            CatalogError::NotFound(id) => ApiError::ScenarioNotFound(id),
            CatalogError::NotReady { id, status } => ApiError::ScenarioNotReady { id, status },
            CatalogError::Builtin(id) => ApiError::BuiltinScenario(id),
            CatalogError::QueueFull {
                limit,
                retry_after_s,
            } => ApiError::QueueFull {
                limit,
                retry_after_s,
            },
            CatalogError::Internal(message) => ApiError::Internal(message),
            CatalogError::DatabaseUnavailable => ApiError::DatabaseUnavailable,
        }
    }
}

impl From<crate::store::DbError> for ApiError {
    /// Logs the database's error here: the client is only told to retry.
    fn from(e: crate::store::DbError) -> Self {
        tracing::warn!(error = %e, "the database is unavailable");
        ApiError::DatabaseUnavailable
    }
}
