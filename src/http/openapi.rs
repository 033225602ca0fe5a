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
use utoipa::{Modify, OpenApi};

use super::doc::bounds::Bounds;

use super::doc::{
    BadPath, BuiltinScenario, InvalidEvaluateRequest, InvalidFitRequest,
    InvalidInlineEvaluateRequest, InvalidInlinePlanRequest, InvalidPlanRequest, InvalidScenario,
    InvalidSession, InvalidStep, MalformedBody, MalformedStep, NotReady, Overloaded,
    PayloadTooLarge, QueueFull, ScenarioNotFound, SessionBodies, SessionConflict, SessionNotFound,
    Timeout, Unauthorized,
};
use super::error::Problem;
use super::{evaluate, fit, health, middleware, plan, scenarios, sessions};

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
        fit::fit,
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
            InvalidStep,
            InvalidInlinePlanRequest,
            InvalidEvaluateRequest,
            InvalidInlineEvaluateRequest,
            InvalidFitRequest,
            InvalidSession,
            SessionNotFound,
            MalformedStep,
            SessionConflict,
            Unauthorized,
            Overloaded,
            NotReady,
            QueueFull,
            Timeout,
        )
    ),
    modifiers(&V1Stack, &Closed, &SessionBodies, &Bounds),
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

/// What the derives cannot say and the server enforces: the variants of
/// `FovSpec` admit no other fields.
struct Closed;

impl Modify for Closed {
    fn modify(&self, doc: &mut utoipa::openapi::OpenApi) {
        use utoipa::openapi::schema::{AdditionalProperties, Schema};
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
    }
}
