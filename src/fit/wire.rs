//! The fit's request and response types (`POST /v1/scenarios/{id}/fit`),
//! and the rates a learning session reports.

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use crate::planner::{Id, SensorIn};
use crate::scenario::Integer;

/// The prior on each source's rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum PriorKind {
    /// Gamma with shape 1 and mean the spec's rate (flat for a source whose
    /// rate is 0).
    #[default]
    Scenario,
    /// Uniform on the rate: the posterior is Gamma(N + 1, E).
    Flat,
}

crate::by_name::by_name!(PriorKind {
    "scenario" => PriorKind::Scenario,
    "flat" => PriorKind::Flat,
});

/// A target detected at a step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(json!({"id": 17, "x": 60.0, "y": 40.0, "vx": 10.0, "vy": 0.0})))]
pub struct DetectionIn {
    /// The target's track id: the same target has the same id at every
    /// step, and counts once.
    pub id: Id,
    /// East coordinate.
    pub x: f64,
    /// North coordinate.
    pub y: f64,
    /// East displacement per step.
    pub vx: f64,
    /// North displacement per step.
    pub vy: f64,
}

/// One step of a fit window: the looks taken and what they detected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct FitStep {
    /// The step's number (optional): when given, each step's must be the
    /// previous step's plus one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u64>, minimum = 0)]
    pub step: Option<Integer>,
    /// The sensors' positions at this step (snapped to cell centres, as in
    /// a plan): each took a look with its type's field of view.
    #[serde(default)]
    pub sensors: Vec<SensorIn>,
    /// The targets detected at this step (at most 20,000).
    #[serde(default)]
    pub detections: Vec<DetectionIn>,
}

/// Tolerances of a fit, for trackers whose positions and velocities are
/// noisy. Each is optional; the defaults accept exact data.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct FitTolerance {
    /// How far, zone units, a source may lie from a detection's track
    /// traced back (and the track run outside the source's cone or past
    /// a building's edge) and still explain it; default 10⁻⁶ × the zone's
    /// larger side.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(minimum = 0)]
    pub traceback: Option<f64>,
    /// How far a detection's speed may differ from a target class's speed,
    /// relative to it; default 10⁻⁶.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(minimum = 0)]
    pub speed: Option<f64>,
    /// How far, zone units, a detection may lie outside every field of view
    /// of its step; default 10⁻⁶ × the zone's larger side.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(minimum = 0)]
    pub look: Option<f64>,
}

impl FitTolerance {
    /// An optional tolerance read from a JSON object only: a derived struct
    /// also takes an array of its fields (`[]` as all defaults), which the
    /// schema does not allow.
    ///
    /// # Errors
    /// Anything but `null` or an object of the tolerance's fields.
    pub fn from_object<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Self>, D::Error> {
        use serde::de::Error;
        let Some(fields) = Option::<serde_json::Map<String, serde_json::Value>>::deserialize(d)?
        else {
            return Ok(None);
        };
        Self::deserialize(serde_json::Value::Object(fields))
            .map(Some)
            .map_err(D::Error::custom)
    }
}

/// Body of `POST /v1/scenarios/{id}/fit`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct FitRequest {
    /// Consecutive steps, oldest first (1 to 500).
    #[schema(min_items = 1)]
    pub steps: Vec<FitStep>,
    /// The prior on each source's rate; `scenario` by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior: Option<PriorKind>,
    /// Register the fitted spec (the same spec with the fitted rates) as a
    /// new scenario; `false` by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub register: Option<bool>,
    /// Tolerances; exact data by default.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "FitTolerance::from_object"
    )]
    pub tolerance: Option<FitTolerance>,
}

/// A source's fitted rate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SourceRate {
    /// The source's index in the scenario's `sources`.
    pub index: usize,
    /// Targets per step: the posterior mean (the spec's rate when the
    /// posterior is improper: a flat prior that no look exposed).
    pub rate: f64,
    /// The equal-tailed 95% credible interval `[lo, hi]` (the posterior's
    /// 2.5% and 97.5% quantiles); `null` when the posterior is improper.
    pub interval: Option<[f64; 2]>,
    /// Distinct targets detected from the source (fractional when a
    /// detection is shared between sources).
    pub detected: f64,
    /// Expected distinct targets detected per unit rate (steps): the
    /// window's looks detect `rate × exposure` of the source's targets on
    /// average, counting every target in the zone during the window.
    pub exposure: f64,
}

/// A point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PointOut {
    /// East coordinate.
    pub x: f64,
    /// North coordinate.
    pub y: f64,
}

/// A detected target that no source explains.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Unexplained {
    /// Its track id.
    pub id: Id,
    /// Where its track, traced back from its first detection, entered the
    /// zone; the first detection's own position for a track that, traced
    /// back, never crossed the zone (a detection outside it, which a wide
    /// `tolerance.look` admits) or for a target that does not move.
    pub entry: PointOut,
}

/// Response of `POST /v1/scenarios/{id}/fit`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct FitResponse {
    /// The scenario fitted.
    pub scenario: String,
    /// Steps in the window.
    pub steps: usize,
    /// Each source's fitted rate, in the scenario's order.
    pub sources: Vec<SourceRate>,
    /// Detected targets that no source explains.
    pub unexplained: Vec<Unexplained>,
    /// With `register`: the id of the scenario registered with the fitted
    /// rates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub id: Option<String>,
}
