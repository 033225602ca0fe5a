//! Error responses as the document describes them, each with examples
//! built from the [`ApiError`] the server really answers with.

use utoipa::ToResponse;

use crate::catalog::JobStatus;
use crate::http::error::{ApiError, Problem};
use crate::limits::MAX_IDEMPOTENCY_KEY_CHARS;
use crate::scenario::ValidationError;

/// Description of the `{id}` path parameter.
pub const SCENARIO_ID: &str = "Scenario id: a built-in (`paper-v10`, `paper-v15`, `site-gates`, `site-fleet`, \
    `site-campus`) or one returned by `POST /v1/scenarios`.";

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

/// Malformed step: its body is not acceptable JSON for the endpoint (see
/// the other endpoints' 400), or its `Idempotency-Key` header is not 1 to
/// 128 visible ASCII characters.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("syntax" = (summary = "Not JSON", value = json!(problem(ApiError::MalformedBody(
            "Failed to parse the request body as JSON: EOF while parsing an object at line 1 column 1".to_owned()
        ))))),
        ("idempotency-key" = (summary = "An Idempotency-Key too long", value = json!(problem(
            ApiError::BadHeader(format!("Idempotency-Key: must have 1 to {MAX_IDEMPOTENCY_KEY_CHARS} characters, not 200"))
        )))),
    )
)]
pub struct MalformedStep(pub Problem);

/// Other steps of the session were stored (through other replicas) while
/// this one was made, each time it was made anew from their state: nothing
/// of this step was stored. Send it again; with the same
/// `Idempotency-Key`, a step that was stored after all is answered, not
/// made twice.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    example = json!(problem(ApiError::SessionConflict("ss-0c5d2f6e8a9b4c3d9e7f1a2b3c4d5e6f".to_owned())))
)]
pub struct SessionConflict(pub Problem);

/// A session's defaults are out of bounds, or the body gives both or
/// neither of `scenario_id` and `scenario`, or its inline scenario is
/// invalid or too large to precompute synchronously.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("history-steps" = (summary = "Too much history", value = json!(invalid(
            "history_steps", "must be an integer in 0..=128, got 200"
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

/// The step is well-formed but a value is outside its bounds or the
/// scenario's zone (as for a plan: `detail` starts with the JSON path of
/// the offending field and a colon), or it has the `Idempotency-Key` of
/// the session's last step with another body: a new step sent with an old
/// key, refused rather than answered with the old step's answer.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("outside" = (summary = "A sensor outside the zone", value = json!(invalid(
            "sensors[0]", "(400, 10) is outside the zone [0,300]×[0,300]"
        )))),
        ("key-reused" = (summary = "The last step's Idempotency-Key with another body", value = json!(problem(
            ApiError::IdempotencyKeyReused("step-41".to_owned())
        )))),
    )
)]
pub struct InvalidStep(pub Problem);

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

/// A fit request the scenario cannot take: `detail` starts with the JSON
/// path of the offending field and a colon.
#[derive(Debug, ToResponse)]
#[response(
    content_type = "application/problem+json",
    examples(
        ("outside" = (summary = "A detection no look of its step can have made", value = json!(invalid(
            "steps[3].detections[0]",
            "(250, 40) lies outside every field of view of this step: none of its looks can have detected it"
        )))),
        ("jump" = (summary = "A track id that jumps", value = json!(invalid(
            "steps[4].detections[1].id",
            "track id 17 jumps 180.000 from where it was 1 step(s) before; the fastest target flies 10.000 in that time"
        )))),
        ("order" = (summary = "Steps out of order", value = json!(invalid(
            "steps[2].step", "steps must be consecutive, oldest first: step 7 follows step 9"
        )))),
        ("empty" = (summary = "An empty window", value = json!(invalid(
            "steps", "at least one step: an empty window says nothing about the rates"
        )))),
    )
)]
pub struct InvalidFitRequest(pub Problem);

#[cfg(test)]
mod tests {
    /// The `{id}` parameter's description names every built-in.
    #[test]
    fn the_scenario_id_lists_every_builtin() {
        for s in crate::scenario::builtins() {
            assert!(
                super::SCENARIO_ID.contains(&format!("`{}`", s.id)),
                "{} is not listed",
                s.id
            );
        }
    }
}
