//! Request bodies as the document describes them: the shapes the handlers
//! parse by hand (a scenario by id or inline), which no wire type derives.
#![allow(
    clippy::large_enum_variant,
    reason = "schemas the document describes, never built: their size costs nothing"
)]

use utoipa::openapi::schema::Schema;
use utoipa::openapi::{OpenApi, RefOr};
use utoipa::{Modify, ToSchema};

use crate::coordination::{Coordination, Objective};
use crate::evaluate::SensorPathIn;
use crate::planner::{EstimatorKind, Observed, PositionIn, SensorIn, TargetIn};
use crate::scenario::{Integer, ScenarioSpec};

/// The fields of `POST /v1/scenarios/{id}/plan`'s body
/// ([`crate::planner::PlanRequest`] for the schema) with one more,
/// required: the two shapes of the body of `POST /v1/plan`.
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
            #[schema(min_items = 1)]
            pub sensors: Vec<SensorIn>,
            /// Targets reported now.
            #[serde(default)]
            pub targets: Vec<TargetIn>,
            /// Sensors' positions 1, 2, … steps ago (at most 256 a step).
            pub history: Option<Vec<Vec<PositionIn>>>,
            /// Horizon T; the scenario's by default.
            #[schema(value_type = Option<u32>, minimum = 1)]
            pub horizon: Option<Integer>,
            /// Estimator; `exact` by default.
            pub estimator: Option<EstimatorKind>,
            /// Coordination; `priority` by default.
            pub coordination: Option<Coordination>,
            /// What the reported targets cover; `sensors` by default.
            pub observed: Option<Observed>,
            /// What the plan maximises; `detections` (the paper's J) by
            /// default. `first_detections` (the `exact` estimator only)
            /// counts each target not yet detected once, at the first step
            /// the plan detects it.
            pub objective: Option<Objective>,
            /// Include the search values in the response.
            pub explain: Option<bool>,
            /// Minimum separation between sensors at every step, cells
            /// (Chebyshev distance; 0..=16, 0 = no rule); the scenario's by
            /// default. Kept wherever it can be: a sensor that cannot keep
            /// it takes the path with the fewest violations, which the
            /// response counts.
            #[schema(value_type = Option<u32>, minimum = 0)]
            pub min_separation: Option<Integer>,
            /// With `coordination: joint`: the certified gap at which it
            /// stops, in `[0, 1]`; 0.001 by default.
            #[schema(minimum = 0.0, maximum = 1.0)]
            pub gap_target: Option<f64>,
            /// With `coordination: joint`: the time after which its
            /// rounds past `iterated` stop, milliseconds (1..=1000, 20 by
            /// default), counted from the plan's start; the `iterated`
            /// plan they start from is always finished.
            #[schema(value_type = Option<u32>, minimum = 1)]
            pub budget_ms: Option<Integer>,
            /// Certify the plan (`bound`, exact plans; true by default):
            /// `false` skips the certificate's work and leaves `bound`
            /// out; refused with `coordination: joint`.
            pub certify: Option<bool>,
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
    /// (its `coordination`, `explain`, `gap_target`, `budget_ms` and
    /// `certify` are checked as a plan checks them, so a plan's body
    /// scores as sent, and play no part) and the paths to score.
    EvaluateBody,
    /// One path per sensor.
    #[schema(min_items = 1)]
    paths: Vec<SensorPathIn>
);

plan_request_with!(
    /// `POST /v1/evaluate` naming its scenario.
    EvaluateRequestById,
    /// Id of a registered scenario, or of one sent inline before.
    #[schema(example = "paper-v10")]
    scenario_id: String,
    /// One path per sensor.
    #[schema(min_items = 1)]
    paths: Vec<SensorPathIn>,
);

plan_request_with!(
    /// `POST /v1/evaluate` carrying its scenario.
    EvaluateRequestWithScenario,
    /// The scenario itself; precomputed on first use and cached.
    scenario: ScenarioSpec,
    /// One path per sensor.
    #[schema(min_items = 1)]
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

/// The two shapes of the body of `POST /v1/sessions`: the scenario, by
/// id or inline, and every field of [`SessionSettings`](crate::session::SessionSettings), which
/// [`SessionBodies`] copies in from that schema so the three never drift.
macro_rules! session_request_with {
    ($(#[$doc:meta])* $name:ident, $(#[$field_doc:meta])* $field:ident: $ty:ty) => {
        $(#[$doc])*
        #[derive(Debug, ToSchema)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            $(#[$field_doc])*
            pub $field: $ty,
        }
    };
}

/// Copies every property of [`SessionSettings`](crate::session::SessionSettings)' schema into the bodies
/// of `POST /v1/sessions`, after their scenario field.
pub struct SessionBodies;

impl Modify for SessionBodies {
    fn modify(&self, doc: &mut OpenApi) {
        let Some(components) = doc.components.as_mut() else {
            return;
        };
        let Some(RefOr::T(Schema::Object(settings))) =
            components.schemas.get("SessionSettings").cloned()
        else {
            return;
        };
        for name in ["SessionRequestById", "SessionRequestWithScenario"] {
            if let Some(RefOr::T(Schema::Object(body))) = components.schemas.get_mut(name) {
                for (field, schema) in &settings.properties {
                    body.properties
                        .entry(field.clone())
                        .or_insert_with(|| schema.clone());
                }
            }
        }
    }
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
