//! The OpenAPI 3.1 description of the API, generated from the handlers'
//! `#[utoipa::path]` attributes and the wire types' `ToSchema` derives.
//!
//! [`spec`] builds it, [`serve`] answers `GET /openapi.json` with it, and the
//! same document is checked in at `openapi/openapi.json` (the API tests fail
//! when the two differ; `VIGIL_UPDATE_OPENAPI=1 cargo test --test api openapi`
//! rewrites the file). The `info` block is pinned here, not taken from the
//! crate's metadata, so a version bump alone does not change the document.

use std::sync::LazyLock;

use axum::http::{HeaderValue, header};
use axum::response::IntoResponse;
use utoipa::openapi::security::{HttpAuthScheme, HttpBuilder, SecurityRequirement, SecurityScheme};
use utoipa::openapi::{Ref, RefOr};
use utoipa::{Modify, OpenApi, ToResponse, ToSchema};

use super::error::{ApiError, Problem};
use super::{evaluate, health, middleware, plan, scenarios, sessions};
use crate::catalog::JobStatus;
use crate::coordination::Coordination;
use crate::evaluate::SensorPathIn;
use crate::limits::{MAX_HISTORY_POSITIONS, MAX_SENSOR_TYPES};
use crate::planner::{EstimatorKind, Observed, PositionIn, SensorIn, TargetIn};
use crate::scenario::{Integer, ScenarioSpec, ValidationError};

/// Description of the whole API, the `info.description` of the document.
const DESCRIPTION: &str = "\
Plans where mobile surveillance sensors should move over the next T steps to \
detect the most targets, after Krishna, Hexmoor and Sogani, *A T-Step Ahead \
Optimal Target Detection Algorithm for a Multi Sensor Surveillance System*.

A **scenario** is the model: a rectangular zone divided into square cells, \
point sources of targets outside it, the sensors' field of view and the \
targets' speed. Registering one precomputes its per-cell statistics; the \
built-in scenarios `paper-v10` and `paper-v15` are the paper's setting with \
target speeds 10 and 15, and `site-gates` a site whose walkers, cyclists and \
vehicles come through directed gates. A **plan** request gives the sensors' positions and \
the targets they report now, and gets back coordinated T-step paths.

Every error is an RFC 9457 problem (`application/problem+json`, schema \
`Problem`) whose `type` names the kind of error.";

/// The API's OpenAPI document.
#[derive(OpenApi)]
#[openapi(
    info(
        title = "Vigil planning API",
        version = "1",
        description = DESCRIPTION,
        license(name = "MIT OR Apache-2.0"),
    ),
    paths(
        health::healthz,
        serve,
        middleware::render,
        scenarios::list,
        scenarios::create,
        scenarios::get,
        scenarios::delete,
        scenarios::stats,
        plan::plan,
        plan::plan_inline,
        evaluate::evaluate,
        evaluate::evaluate_inline,
        sessions::create,
        sessions::step,
        sessions::get,
        sessions::delete,
    ),
    components(
        schemas(Problem),
        responses(
            MalformedBody,
            BadPath,
            PayloadTooLarge,
            ScenarioNotFound,
            BuiltinScenario,
            InvalidScenario,
            InvalidPlanRequest,
            InvalidInlinePlanRequest,
            InvalidEvaluateRequest,
            InvalidInlineEvaluateRequest,
            InvalidSession,
            SessionNotFound,
            Unauthorized,
            Overloaded,
            NotReady,
            QueueFull,
            Timeout,
        )
    ),
    modifiers(&V1Stack, &Closed),
    tags(
        (name = "health", description = "Liveness."),
        (name = "scenarios", description = "Register, read and delete scenarios."),
        (name = "planning", description = "Plan sensors' paths."),
        (name = "sessions", description = "Plan step by step: the server keeps the history and the tracks."),
        (name = "meta", description = "This document and the server's metrics."),
    )
)]
pub struct ApiDoc;

/// What the `/v1` stack adds to each of its operations: the optional bearer
/// key (401) and the overload (503) and time limit (504) errors.
struct V1Stack;

impl Modify for V1Stack {
    fn modify(&self, doc: &mut utoipa::openapi::OpenApi) {
        doc.components
            .get_or_insert_with(Default::default)
            .add_security_scheme(
                BEARER,
                SecurityScheme::Http(
                    HttpBuilder::new()
                        .scheme(HttpAuthScheme::Bearer)
                        .description(Some(
                            "The server's API key, as `Authorization: Bearer <key>`. Required by \
                             every `/v1` endpoint when the server is started with `--api-key` \
                             (`VIGIL_API_KEY`); without a key, none is needed.",
                        ))
                        .build(),
                ),
            );
        let v1 = doc
            .paths
            .paths
            .iter_mut()
            .filter(|(path, _)| path.starts_with("/v1/"));
        for (_, item) in v1 {
            let operations = [
                &mut item.get,
                &mut item.put,
                &mut item.post,
                &mut item.delete,
                &mut item.patch,
            ];
            for op in operations.into_iter().flatten() {
                for (status, response) in [
                    ("401", "Unauthorized"),
                    ("503", "Overloaded"),
                    ("504", "Timeout"),
                ] {
                    op.responses
                        .responses
                        .entry(status.to_owned())
                        .or_insert_with(|| RefOr::Ref(Ref::from_response_name(response)));
                }
                // The key is optional: `{}` is the anonymous alternative.
                op.security = Some(vec![
                    SecurityRequirement::new(BEARER, Vec::<String>::new()),
                    SecurityRequirement::default(),
                ]);
            }
        }
    }
}

/// Name of the bearer security scheme.
const BEARER: &str = "bearer";

/// The OpenAPI document of the API.
pub fn spec() -> utoipa::openapi::OpenApi {
    ApiDoc::openapi()
}

/// The document as served and checked in: pretty-printed JSON with a
/// trailing newline.
pub fn spec_json() -> String {
    // Serializing plain data to a string cannot fail; keep the body JSON
    // regardless.
    let mut json = spec().to_pretty_json().unwrap_or_else(|e| {
        serde_json::json!({"error": format!("cannot serialize the OpenAPI document: {e}")})
            .to_string()
    });
    json.push('\n');
    json
}

static SPEC_JSON: LazyLock<String> = LazyLock::new(spec_json);

/// `GET /openapi.json` → 200, this document.
#[utoipa::path(
    get,
    path = "/openapi.json",
    operation_id = "getOpenApi",
    tag = "meta",
    summary = "This OpenAPI document",
    responses(
        (status = 200, description = "The OpenAPI 3.1 document of the API.",
            body = Object, content_type = "application/json"),
    )
)]
pub async fn serve() -> impl IntoResponse {
    (
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/json"),
        )],
        SPEC_JSON.as_str(),
    )
}

/// The fields of `POST /v1/scenarios/{id}/plan`'s body ([`PlanRequest`]
/// for the schema) with one more, required: the two shapes of the body of
/// `POST /v1/plan`.
macro_rules! plan_request_with {
    ($(#[$doc:meta])* $name:ident, $($(#[$field_doc:meta])* $field:ident: $ty:ty),+ $(,)?) => {
        $(#[$doc])*
        #[derive(Debug, ToSchema)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            $(
                $(#[$field_doc])*
                pub $field: $ty,
            )+
            /// Sensors now.
            #[schema(min_items = 1, max_items = 256)]
            pub sensors: Vec<SensorIn>,
            /// Targets reported now.
            #[serde(default)]
            #[schema(max_items = 20000)]
            pub targets: Vec<TargetIn>,
            /// Sensors' positions 1, 2, … steps ago (at most 256 a step).
            #[schema(max_items = 32)]
            pub history: Option<Vec<Vec<PositionIn>>>,
            /// Horizon T; the scenario's by default.
            #[schema(value_type = Option<u32>, minimum = 1, maximum = 12)]
            pub horizon: Option<Integer>,
            /// Estimator; `exact` by default.
            pub estimator: Option<EstimatorKind>,
            /// Coordination; `priority` by default.
            pub coordination: Option<Coordination>,
            /// What the reported targets cover; `sensors` by default.
            pub observed: Option<Observed>,
            /// Include the search values in the response.
            pub explain: Option<bool>,
            /// Minimum separation between sensors at every step, cells
            /// (Chebyshev distance; 0..=16, 0 = no rule); the scenario's by
            /// default. Kept wherever it can be: a sensor that cannot keep
            /// it takes the path with the fewest violations, which the
            /// response counts.
            #[schema(value_type = Option<u32>, minimum = 0, maximum = 16)]
            pub min_separation: Option<Integer>,
            /// With `coordination: joint`: the certified gap at which it
            /// stops, in `[0, 1]`; 0.001 by default.
            #[schema(minimum = 0.0, maximum = 1.0)]
            pub gap_target: Option<f64>,
            /// With `coordination: joint`: the most time the plan may
            /// take, milliseconds (1..=1000, 20 by default).
            #[schema(value_type = Option<u32>, minimum = 1, maximum = 1000)]
            pub budget_ms: Option<Integer>,
        }
    };
}

plan_request_with!(
    /// `POST /v1/plan` naming its scenario.
    PlanRequestById,
    /// Id of a registered scenario, or of one sent inline before.
    #[schema(example = "paper-v10")]
    scenario_id: String
);

plan_request_with!(
    /// `POST /v1/plan` carrying its scenario.
    PlanRequestWithScenario,
    /// The scenario itself; precomputed on first use and cached.
    scenario: ScenarioSpec
);

/// Body of `POST /v1/plan`: the body of `POST /v1/scenarios/{id}/plan` plus
/// exactly one of `scenario_id` and `scenario`.
#[derive(Debug, ToSchema)]
#[serde(untagged)]
pub enum InlinePlanRequest {
    /// The scenario by id.
    ById(PlanRequestById),
    /// The scenario inline.
    WithScenario(PlanRequestWithScenario),
}

plan_request_with!(
    /// Body of `POST /v1/scenarios/{id}/evaluate`: a plan request's fields
    /// (its `coordination`, `explain`, `gap_target` and `budget_ms` play no
    /// part) and the paths to score.
    EvaluateBody,
    /// One path per sensor.
    #[schema(min_items = 1, max_items = 256)]
    paths: Vec<SensorPathIn>
);

plan_request_with!(
    /// `POST /v1/evaluate` naming its scenario.
    EvaluateRequestById,
    /// Id of a registered scenario, or of one sent inline before.
    #[schema(example = "paper-v10")]
    scenario_id: String,
    /// One path per sensor.
    #[schema(min_items = 1, max_items = 256)]
    paths: Vec<SensorPathIn>,
);

plan_request_with!(
    /// `POST /v1/evaluate` carrying its scenario.
    EvaluateRequestWithScenario,
    /// The scenario itself; precomputed on first use and cached.
    scenario: ScenarioSpec,
    /// One path per sensor.
    #[schema(min_items = 1, max_items = 256)]
    paths: Vec<SensorPathIn>,
);

/// Body of `POST /v1/evaluate`: the body of `POST
/// /v1/scenarios/{id}/evaluate` plus exactly one of `scenario_id` and
/// `scenario`.
#[derive(Debug, ToSchema)]
#[serde(untagged)]
pub enum InlineEvaluateRequest {
    /// The scenario by id.
    ById(EvaluateRequestById),
    /// The scenario inline.
    WithScenario(EvaluateRequestWithScenario),
}

macro_rules! session_request_with {
    ($(#[$doc:meta])* $name:ident, $(#[$field_doc:meta])* $field:ident: $ty:ty) => {
        $(#[$doc])*
        #[derive(Debug, ToSchema)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            $(#[$field_doc])*
            pub $field: $ty,
            /// Horizon T of its steps; the scenario's by default.
            #[schema(value_type = Option<u32>, minimum = 1, maximum = 12)]
            pub horizon: Option<Integer>,
            /// Estimator of its steps; `exact` by default.
            pub estimator: Option<EstimatorKind>,
            /// Coordination of its steps; `priority` by default.
            pub coordination: Option<Coordination>,
            /// What the detections cover; `sensors` by default.
            pub observed: Option<Observed>,
            /// Minimum separation of its steps, cells (0..=16); the
            /// scenario's by default.
            #[schema(value_type = Option<u32>, minimum = 0, maximum = 16)]
            pub min_separation: Option<Integer>,
            /// Steps of history kept (0..=32, 16 by default): the sensors'
            /// past positions planned with, and how long a track lives
            /// undetected.
            #[schema(value_type = Option<u32>, minimum = 0, maximum = 32)]
            pub history_steps: Option<Integer>,
        }
    };
}

session_request_with!(
    /// `POST /v1/sessions` naming its scenario.
    SessionRequestById,
    /// Id of a registered scenario, or of one sent inline before.
    #[schema(example = "paper-v10")]
    scenario_id: String
);

session_request_with!(
    /// `POST /v1/sessions` carrying its scenario.
    SessionRequestWithScenario,
    /// The scenario itself; precomputed on first use and cached.
    scenario: ScenarioSpec
);

/// Body of `POST /v1/sessions`: exactly one of `scenario_id` and
/// `scenario`, and the defaults of the session's steps.
#[derive(Debug, ToSchema)]
#[serde(untagged)]
pub enum CreateSessionRequest {
    /// The scenario by id.
    ById(SessionRequestById),
    /// The scenario inline.
    WithScenario(SessionRequestWithScenario),
}

/// What the derives cannot say and the server enforces: the variants of
/// `FovSpec` admit no other fields, and a history step holds at most
/// [`MAX_HISTORY_POSITIONS`] positions.
struct Closed;

impl Modify for Closed {
    fn modify(&self, doc: &mut utoipa::openapi::OpenApi) {
        use utoipa::openapi::schema::{AdditionalProperties, ArrayItems, Schema};
        let Some(components) = doc.components.as_mut() else {
            return;
        };
        if let Some(RefOr::T(Schema::OneOf(one_of))) = components.schemas.get_mut("FovSpec") {
            for item in &mut one_of.items {
                if let RefOr::T(Schema::Object(variant)) = item {
                    variant.additional_properties =
                        Some(Box::new(AdditionalProperties::FreeForm(false)));
                }
            }
        }
        // Sensor type names: a pattern and a count utoipa's derive cannot
        // state on a map.
        if let Some(RefOr::T(Schema::Object(spec))) = components.schemas.get_mut("ScenarioSpec")
            && let Some(RefOr::T(Schema::Object(types))) = spec.properties.get_mut("sensor_types")
        {
            types.max_properties = Some(MAX_SENSOR_TYPES);
            types.property_names = Some(Box::new(Schema::Object(
                utoipa::openapi::schema::ObjectBuilder::new()
                    .schema_type(utoipa::openapi::schema::Type::String)
                    .pattern(Some("^[A-Za-z0-9_-]{1,32}$"))
                    .build(),
            )));
        }
        for name in [
            "PlanRequest",
            "PlanRequestById",
            "PlanRequestWithScenario",
            "EvaluateBody",
            "EvaluateRequestById",
            "EvaluateRequestWithScenario",
        ] {
            let Some(RefOr::T(Schema::Object(object))) = components.schemas.get_mut(name) else {
                continue;
            };
            if let Some(RefOr::T(Schema::Array(history))) = object.properties.get_mut("history")
                && let ArrayItems::RefOrSchema(step) = &mut history.items
                && let RefOr::T(Schema::Array(step)) = step.as_mut()
            {
                step.max_items = Some(MAX_HISTORY_POSITIONS);
            }
        }
    }
}

/// Description of the `{id}` path parameter.
pub const SCENARIO_ID: &str = "Scenario id: a built-in (`paper-v10`, `paper-v15`, `site-gates`) or one returned by \
    `POST /v1/scenarios`.";

fn problem(e: ApiError) -> Problem {
    e.problem()
}

fn invalid(field: &str, message: &str) -> Problem {
    problem(ApiError::Validation(ValidationError::new(field, message)))
}

/// Malformed request: the body is not acceptable JSON for the endpoint (a
/// syntax error, a missing or wrong `Content-Type`, a missing or unknown
/// field, a value of the wrong type), or a path parameter cannot be decoded.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("syntax" = (summary = "Not JSON", value = json!(problem(ApiError::MalformedBody(
            "Failed to parse the request body as JSON: EOF while parsing an object at line 1 column 1".to_owned()
        ))))),
        ("content-type" = (summary = "No JSON content type", value = json!(problem(
            ApiError::MalformedBody("expected a request with `Content-Type: application/json`".to_owned())
        )))),
        ("missing-field" = (summary = "A required field is missing", value = json!(problem(
            ApiError::MalformedBody(
                "Failed to deserialize the JSON body into the target type: missing field `sensors` at line 1 column 2".to_owned()
            )
        )))),
    )
)]
pub struct MalformedBody(pub Problem);

/// The `{id}` path parameter cannot be decoded (percent-encoded bytes that
/// are not UTF-8, e.g. `%FF`).
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    example = json!(problem(ApiError::BadPath(
        "Invalid URL: Invalid UTF-8 in `id`".to_owned()
    )))
)]
pub struct BadPath(pub Problem);

/// The request body is larger than the server's limit.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    example = json!(problem(ApiError::PayloadTooLarge("Failed to buffer the request body: length limit exceeded".to_owned())))
)]
pub struct PayloadTooLarge(pub Problem);

/// No scenario has this id.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    example = json!(problem(ApiError::ScenarioNotFound("nope".to_owned())))
)]
pub struct ScenarioNotFound(pub Problem);

/// No session has this id: it was never created, or it was dropped (idle
/// past the time to live, or evicted to make room). Create a new one.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    example = json!(problem(ApiError::SessionNotFound { id: "ss-0c5d2f6e8a9b4c3d9e7f1a2b3c4d5e6f".to_owned(), ttl_s: 600 }))
)]
pub struct SessionNotFound(pub Problem);

/// A session's defaults are out of bounds, or the body gives both or
/// neither of `scenario_id` and `scenario`, or its inline scenario is
/// invalid or too large to precompute synchronously.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("history-steps" = (summary = "Too much history", value = json!(invalid(
            "history_steps", "must be an integer in 0..=32, got 40"
        )))),
        ("one-of" = (summary = "Neither scenario_id nor scenario", value = json!(problem(
            ApiError::Unprocessable("exactly one of `scenario_id` and `scenario` is required".to_owned())
        )))),
    )
)]
pub struct InvalidSession(pub Problem);

/// The scenario is built in and cannot be deleted.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    example = json!(problem(ApiError::BuiltinScenario("paper-v10".to_owned())))
)]
pub struct BuiltinScenario(pub Problem);

/// The spec is well-formed but a value is outside its bounds. `detail` starts
/// with the JSON path of the offending field and a colon.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("cell-size" = (summary = "Cells do not tile the zone", value = json!(invalid(
            "zone.width", "100 is not a whole multiple of cell_size 7"
        )))),
        ("source-inside" = (summary = "A source inside the zone", value = json!(invalid(
            "sources[0]",
            "(50, 50) is inside the zone [0,100]×[0,100]; sources must be strictly outside"
        )))),
        ("horizon" = (summary = "Horizon out of range", value = json!(invalid(
            "horizon", "must be in 1..=12, got 13"
        )))),
    )
)]
pub struct InvalidScenario(pub Problem);

/// The request is well-formed but a value is outside its bounds or the
/// scenario's zone. `detail` starts with the JSON path of the offending field
/// and a colon.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("no-sensors" = (summary = "No sensor", value = json!(invalid(
            "sensors", "at least one sensor is required"
        )))),
        ("outside" = (summary = "A sensor outside the zone", value = json!(invalid(
            "sensors[0]", "(400, 10) is outside the zone [0,300]×[0,300]"
        )))),
        ("duplicate" = (summary = "Two sensors with one id", value = json!(invalid(
            "sensors[1].id", "duplicate sensor id"
        )))),
        ("horizon" = (summary = "Horizon out of range", value = json!(invalid(
            "horizon", "must be in 1..=12, got 0"
        )))),
        ("too-costly" = (summary = "Predicted to cost more CPU than the server allows", value = json!(problem(
            ApiError::PlanTooCostly { predicted_ms: 19940.0, limit_ms: 2000.0 }
        )))),
    )
)]
pub struct InvalidPlanRequest(pub Problem);

/// The request is well-formed but a value is outside its bounds (fields of
/// an inline scenario are prefixed with `scenario.`), or it gives both or
/// neither of `scenario_id` and `scenario`, or the plan or the inline
/// scenario's precomputation is predicted to cost more than the server
/// allows.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("one-of" = (summary = "Neither scenario_id nor scenario", value = json!(problem(
            ApiError::Unprocessable("exactly one of `scenario_id` and `scenario` is required".to_owned())
        )))),
        ("scenario" = (summary = "An invalid inline scenario", value = json!(invalid(
            "scenario.zone.width", "100 is not a whole multiple of cell_size 7"
        )))),
        ("register-instead" = (summary = "An inline scenario too large to precompute synchronously", value = json!(problem(
            ApiError::PrecomputeTooCostly { predicted_ms: 20736.0, budget_ms: 1000.0 }
        )))),
        ("too-costly" = (summary = "Predicted to cost more CPU than the server allows", value = json!(problem(
            ApiError::PlanTooCostly { predicted_ms: 19940.0, limit_ms: 2000.0 }
        )))),
        ("outside" = (summary = "A sensor outside the zone", value = json!(invalid(
            "sensors[0]", "(400, 10) is outside the zone [0,300]×[0,300]"
        )))),
    )
)]
pub struct InvalidInlinePlanRequest(pub Problem);

/// The request is well-formed but a value is outside its bounds or the
/// scenario's zone, or a path is not one the sensor could take. `detail`
/// starts with the JSON path of the offending field and a colon.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("speed" = (summary = "A move beyond the sensor's speed", value = json!(invalid(
            "paths[0].path[1]",
            "the move from (col 6, row 4) to (col 8, row 4) is beyond the speed of type \"default\" (1 cells a step)"
        )))),
        ("missing" = (summary = "A sensor without a path", value = json!(invalid(
            "paths", "sensor \"c\" has no path: give one per sensor"
        )))),
        ("length" = (summary = "A path of the wrong length", value = json!(invalid(
            "paths[1].path", "must hold the cells of steps 1..=3 (3 cells), got 2"
        )))),
        ("no-go" = (summary = "A cell in a no-go zone", value = json!(invalid(
            "paths[0].path[2]", "(col 12, row 4) is in a no-go zone: no sensor may stand on it"
        )))),
    )
)]
pub struct InvalidEvaluateRequest(pub Problem);

/// [`InvalidEvaluateRequest`]'s cases, and those of a scenario named or
/// sent in the body as in `POST /v1/plan`.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("one-of" = (summary = "Neither scenario_id nor scenario", value = json!(problem(
            ApiError::Unprocessable("exactly one of `scenario_id` and `scenario` is required".to_owned())
        )))),
        ("unknown-sensor" = (summary = "A path for a sensor not in `sensors`", value = json!(invalid(
            "paths[2].sensor", "no sensor \"z\" in `sensors`"
        )))),
        ("off-lattice" = (summary = "A cell off the lattice", value = json!(invalid(
            "paths[0].path[0]", "(col -1, row 4) is off the lattice of 30 columns and 30 rows"
        )))),
    )
)]
pub struct InvalidInlineEvaluateRequest(pub Problem);

/// The server requires an API key and the request has none, or a wrong one.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    headers(("WWW-Authenticate" = String, description = "`Bearer`.")),
    example = json!(problem(ApiError::Unauthorized))
)]
pub struct Unauthorized(pub Problem);

/// The server is handling as many `/v1` requests as it allows: the request
/// was shed at once, without being handled; or, with a shared database
/// (`--database-url`), the database is unreachable and the request needs
/// it. Retry after the delay given.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    headers(("Retry-After" = String, description = "Seconds to wait before retrying.")),
    examples(
        ("overloaded" = (summary = "Shed under load", value = json!(problem(ApiError::Overloaded)))),
        ("database-unavailable" = (summary = "The scenario database is unreachable",
            value = json!(problem(ApiError::DatabaseUnavailable)))),
    )
)]
pub struct Overloaded(pub Problem);

/// The server is handling as many `/v1` requests as it allows (shed at
/// once, without being handled), or the scenario is still being
/// precomputed (`GET /v1/scenarios/{id}` shows its progress), or, with a
/// shared database, the scenario is not held here and the database is
/// unreachable. Retry after the delay given: for a pending scenario, its
/// estimated time to ready.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    headers(("Retry-After" = String, description = "Seconds to wait before retrying.")),
    examples(
        ("not-ready" = (summary = "The scenario is still precomputing", value = json!(problem(
            ApiError::ScenarioNotReady {
                id: "s-3f6c0a9d2b7e4411".to_owned(),
                status: JobStatus { queue_position: None, progress: 0.38, eta_s: 13.3 },
            }
        )))),
        ("overloaded" = (summary = "Shed under load", value = json!(problem(ApiError::Overloaded)))),
        ("database-unavailable" = (summary = "The scenario database is unreachable",
            value = json!(problem(ApiError::DatabaseUnavailable)))),
    )
)]
pub struct NotReady(pub Problem);

/// The server is handling as many `/v1` requests as it allows (shed at
/// once), or as many precomputation jobs wait as its queue holds
/// (`--precompute-queue`), or, with a shared database, the database is
/// unreachable. Retry after the delay given.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    headers(("Retry-After" = String, description = "Seconds to wait before retrying.")),
    examples(
        ("queue-full" = (summary = "The precomputation queue is full", value = json!(problem(
            ApiError::QueueFull { limit: 16, retry_after_s: 40 }
        )))),
        ("overloaded" = (summary = "Shed under load", value = json!(problem(ApiError::Overloaded)))),
        ("database-unavailable" = (summary = "The scenario database is unreachable",
            value = json!(problem(ApiError::DatabaseUnavailable)))),
    )
)]
pub struct QueueFull(pub Problem);

/// The request took longer than the server's time limit.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    example = json!(problem(ApiError::Timeout))
)]
pub struct Timeout(pub Problem);

/// Example bodies used in the document. Ids and canonical specs come from
/// the code; computed numbers are from a real run, rounded.
pub mod examples {
    use serde_json::{Value, json};

    use crate::scenario::{Scenario, ScenarioSpec, builtins};

    /// A small scenario: a 100×100 zone of 10-unit cells, two sources.
    pub fn small_spec() -> Value {
        json!({
            "name": "small",
            "zone": {"width": 100.0, "height": 100.0},
            "cell_size": 10.0,
            "fov": {"shape": "square", "half_width": 15.0},
            "target_speed": 10.0,
            "sources": [
                {"x": -1.0, "y": 50.0, "rate": 0.5},
                {"x": 50.0, "y": 101.0, "rate": 0.25}
            ]
        })
    }

    /// Id and canonical spec of a spec, as the server derives them.
    fn registered(spec: Value) -> (String, Value) {
        serde_json::from_value::<ScenarioSpec>(spec)
            .ok()
            .and_then(|spec| Scenario::new(spec).ok())
            .map_or_else(
                || ("s-0000000000000000".to_owned(), Value::Null),
                |s| (s.id, json!(s.spec)),
            )
    }

    /// The summary of [`small_spec`] once registered.
    pub fn small_summary() -> Value {
        let (id, spec) = registered(small_spec());
        json!({
            "id": id,
            "spec": spec,
            "grid": {"cols": 10, "rows": 10},
            "status": "ready",
            "progress": 1.0,
            "predicted_precompute_ms": 0.04,
            "summary": {"expected_targets_in_zone": 5.4993, "precompute_ms": 0.13}
        })
    }

    /// A large scenario: a 2000×2000 zone of unit cells, a circular field
    /// of view of radius 40, four sources.
    pub fn large_spec() -> Value {
        json!({
            "name": "large",
            "zone": {"width": 2000.0, "height": 2000.0},
            "cell_size": 1.0,
            "fov": {"shape": "circle", "radius": 40.0},
            "target_speed": 10.0,
            "sources": [
                {"x": -1.0, "y": 1000.0, "rate": 0.5},
                {"x": 2001.0, "y": 1000.0, "rate": 0.5},
                {"x": 1000.0, "y": -1.0, "rate": 0.5},
                {"x": 1000.0, "y": 2001.0, "rate": 0.5}
            ]
        })
    }

    /// The summary of [`large_spec`] while its job precomputes it.
    pub fn large_precomputing() -> Value {
        let (id, spec) = registered(large_spec());
        json!({
            "id": id,
            "spec": spec,
            "grid": {"cols": 2000, "rows": 2000},
            "status": "precomputing",
            "progress": 0.38,
            "eta_s": 13.3,
            "predicted_precompute_ms": 20736.0
        })
    }

    /// The summary of [`large_spec`] while its job waits behind another.
    pub fn large_queued() -> Value {
        let (id, spec) = registered(large_spec());
        json!({
            "id": id,
            "spec": spec,
            "grid": {"cols": 2000, "rows": 2000},
            "status": "queued",
            "progress": 0.0,
            "eta_s": 34.0,
            "queue_position": 1,
            "predicted_precompute_ms": 20736.0
        })
    }

    /// The summary of `paper-v10`.
    pub fn paper_v10_summary() -> Value {
        let spec = builtins()
            .into_iter()
            .find(|s| s.id == "paper-v10")
            .map_or(Value::Null, |s| json!(s.spec));
        json!({
            "id": "paper-v10",
            "spec": spec,
            "grid": {"cols": 30, "rows": 30},
            "status": "ready",
            "progress": 1.0,
            "predicted_precompute_ms": 0.94,
            "summary": {"expected_targets_in_zone": 53.0358, "precompute_ms": 1.62}
        })
    }

    /// A list with `paper-v10` and a registered scenario.
    pub fn scenario_list() -> Value {
        json!({"scenarios": [paper_v10_summary(), small_summary(), large_precomputing()]})
    }

    /// Statistics of a 3×2 lattice (a 30×20 zone of 10-unit cells, circular
    /// field of view of radius 10, one source west of it).
    pub fn stats() -> Value {
        json!({
            "type": "default",
            "cols": 3,
            "rows": 2,
            "cell_size": 10.0,
            "lambda_hat": [0.4417, 0.2028, 0.1147, 0.4417, 0.2028, 0.1147],
            "escape_time": [1.9364, 2.6036, 2.3088, 1.9364, 2.6036, 2.3088],
            "d_hat": [0.8553, 0.5279, 0.2647, 0.8553, 0.5279, 0.2647]
        })
    }

    /// A plan request on `paper-v10`: three sensors, three targets.
    pub fn plan_request() -> Value {
        json!({
            "sensors": [
                {"id": "a", "x": 55.0, "y": 55.0},
                {"id": 7, "x": 150.0, "y": 150.0},
                {"id": "c", "x": 245.0, "y": 60.0}
            ],
            "targets": [
                {"id": "t1", "x": 60.0, "y": 40.0, "vx": 10.0, "vy": 0.0},
                {"x": 140.0, "y": 160.0, "vx": -3.0, "vy": 9.0},
                {"id": 3, "x": 250.0, "y": 70.0, "vx": 0.0, "vy": -10.0}
            ]
        })
    }

    /// Two sensors on one cell and a third, kept 3 cells apart at every
    /// step.
    pub fn plan_request_apart() -> Value {
        json!({
            "sensors": [
                {"id": "a", "x": 150.0, "y": 150.0},
                {"id": "b", "x": 155.0, "y": 155.0},
                {"id": "c", "x": 175.0, "y": 150.0}
            ],
            "min_separation": 3
        })
    }

    /// [`plan_request`] for `POST /v1/plan`, naming the scenario.
    pub fn plan_request_by_id() -> Value {
        let mut req = plan_request();
        req["scenario_id"] = json!("paper-v10");
        req
    }

    /// A `POST /v1/plan` request with its scenario inline.
    pub fn plan_request_inline() -> Value {
        json!({
            "scenario": small_spec(),
            "sensors": [{"id": "a", "x": 50.0, "y": 50.0}],
            "targets": [{"x": 20.0, "y": 45.0, "vx": 10.0, "vy": 0.0}],
            "horizon": 2
        })
    }

    fn cell(col: i32, row: i32) -> Value {
        json!({
            "col": col,
            "row": row,
            "x": (f64::from(col) + 0.5) * 10.0,
            "y": (f64::from(row) + 0.5) * 10.0
        })
    }

    /// The response to [`plan_request`].
    pub fn plan_response() -> Value {
        json!({
            "scenario": "paper-v10",
            "horizon": 3,
            "estimator": "exact",
            "coordination": "priority",
            "min_separation": 0,
            "separation_violations": 0,
            "plans": [
                {
                    "sensor": "a",
                    "priority": 1,
                    "start": cell(5, 5),
                    "path": [cell(6, 4), cell(7, 3), cell(8, 2)],
                    "expected_detections": 6.9032,
                    "separation_violations": 0
                },
                {
                    "sensor": 7,
                    "priority": 3,
                    "start": cell(15, 15),
                    "path": [cell(14, 16), cell(13, 17), cell(12, 18)],
                    "expected_detections": 5.8559,
                    "separation_violations": 0
                },
                {
                    "sensor": "c",
                    "priority": 2,
                    "start": cell(24, 6),
                    "path": [cell(23, 5), cell(22, 4), cell(22, 3)],
                    "expected_detections": 6.3405,
                    "separation_violations": 0
                }
            ],
            "expected_detections": 19.0996,
            "expected_by_step": [4.808, 6.538, 7.7535],
            "bound": {"upper": 19.4305, "gap": 0.017},
            "compute_micros": 335
        })
    }

    /// [`plan_request`]'s sensors and targets with the paths of
    /// [`plan_response`], to score.
    pub fn evaluate_request() -> Value {
        let mut req = plan_request();
        req["paths"] = json!([
            {"sensor": "a", "path": [{"col": 6, "row": 4}, {"col": 7, "row": 3}, {"col": 8, "row": 2}]},
            {"sensor": 7, "path": [{"col": 14, "row": 16}, {"col": 13, "row": 17}, {"col": 12, "row": 18}]},
            {"sensor": "c", "path": [{"col": 23, "row": 5}, {"col": 22, "row": 4}, {"col": 22, "row": 3}]}
        ]);
        req
    }

    /// [`evaluate_request`] naming its scenario.
    pub fn evaluate_request_by_id() -> Value {
        let mut req = evaluate_request();
        req["scenario_id"] = json!("paper-v10");
        req
    }

    /// The scores of [`evaluate_request`]'s paths.
    pub fn evaluate_response() -> Value {
        json!({
            "scenario": "paper-v10",
            "horizon": 3,
            "estimator": "exact",
            "min_separation": 0,
            "expected_detections": 19.0996,
            "expected_by_step": [4.808, 6.538, 7.7535],
            "separation_violations": 0,
            "sensors": [
                {"sensor": "a", "marginal": 6.9032, "separation_violations": 0},
                {"sensor": 7, "marginal": 5.8559, "separation_violations": 0},
                {"sensor": "c", "marginal": 6.3405, "separation_violations": 0}
            ]
        })
    }

    /// A session on `paper-v10` keeping 16 steps of history.
    pub fn session_request() -> Value {
        json!({"scenario_id": "paper-v10", "horizon": 3, "history_steps": 16})
    }

    /// The session of [`session_request`] after the steps of
    /// [`step_request`] and a second with the sensors moved on.
    pub fn session_info() -> Value {
        json!({
            "id": "ss-36c3f1f5ddc745349553d4bb0bc86f98",
            "scenario": "paper-v10",
            "step": 2,
            "history_steps": 16,
            "history_held": 2,
            "settings": {"horizon": 3, "history_steps": 16},
            "tracks": [
                {"id": 17, "x": 70.0, "y": 40.0, "vx": 10.0, "vy": 0.0, "last_detected": 0}
            ],
            "memory_bytes": 456
        })
    }

    /// A step: two sensors, one target detected.
    pub fn step_request() -> Value {
        json!({
            "sensors": [{"id": "a", "x": 55.0, "y": 55.0}, {"id": "b", "x": 245.0, "y": 60.0}],
            "detections": [{"id": 17, "x": 60.0, "y": 40.0, "vx": 10.0, "vy": 0.0}]
        })
    }

    /// The plan of [`step_request`] as the first step of a session.
    pub fn step_response() -> Value {
        json!({
            "step": 0,
            "scenario": "paper-v10",
            "horizon": 3,
            "estimator": "exact",
            "coordination": "priority",
            "min_separation": 0,
            "separation_violations": 0,
            "plans": [
                {
                    "sensor": "a",
                    "priority": 1,
                    "start": cell(5, 5),
                    "path": [cell(6, 4), cell(7, 3), cell(8, 2)],
                    "expected_detections": 6.9058,
                    "separation_violations": 0
                },
                {
                    "sensor": "b",
                    "priority": 2,
                    "start": cell(24, 6),
                    "path": [cell(25, 7), cell(26, 8), cell(27, 9)],
                    "expected_detections": 4.1472,
                    "separation_violations": 0
                }
            ],
            "expected_detections": 11.053,
            "expected_by_step": [2.3726, 3.833, 4.8474],
            "compute_micros": 1560
        })
    }
}
