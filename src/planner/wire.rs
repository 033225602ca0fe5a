//! The planning API's request and response types, shared by the HTTP layer
//! and in-process callers: what clients send ([`PlanRequest`]) and what they
//! get back ([`PlanResponse`]).

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use crate::coordination::{Bound, Coordination, JointReport, Objective};
use crate::scenario::Integer;

/// Which estimator of `n̂(k,t)` to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum EstimatorKind {
    /// The conditional expectation under the model (ours).
    #[default]
    Exact,
    /// Equations (1) and (2) of the paper.
    Paper,
}

crate::by_name::by_name!(EstimatorKind {
    "exact" => EstimatorKind::Exact,
    "paper" => EstimatorKind::Paper,
});

/// What the reported targets cover.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum Observed {
    /// The targets inside the sensors' fields of view (now and in the history).
    #[default]
    Sensors,
    /// Every target in the zone (a clairvoyant reference).
    Zone,
}

crate::by_name::by_name!(Observed {
    "sensors" => Observed::Sensors,
    "zone" => Observed::Zone,
});

/// A sensor or target id: a string or a number, echoed back as given. Two
/// ids are the same when they are the same JSON value: `"7"` and `7`
/// differ, `7` and `7.0` do not (JSON has one number type).
#[derive(Debug, Clone, Serialize, ToSchema)]
#[serde(untagged)]
#[schema(examples("a", 7))]
pub enum Id {
    /// A string id.
    Text(String),
    /// A numeric id.
    #[schema(value_type = f64)]
    Number(serde_json::Number),
}

/// By hand rather than `untagged`, which buffers every id and, for a
/// number, first fails (an error message formatted and dropped) as a string.
impl<'de> Deserialize<'de> for Id {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct IdVisitor;
        impl serde::de::Visitor<'_> for IdVisitor {
            type Value = Id;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a string or a number")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Id, E> {
                Ok(Id::Text(v.to_owned()))
            }
            fn visit_string<E: serde::de::Error>(self, v: String) -> Result<Id, E> {
                Ok(Id::Text(v))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Id, E> {
                Ok(Id::Number(v.into()))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Id, E> {
                Ok(Id::Number(v.into()))
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Id, E> {
                serde_json::Number::from_f64(v)
                    .map(Id::Number)
                    .ok_or_else(|| E::custom("an id must be a finite number"))
            }
        }
        deserializer.deserialize_any(IdVisitor)
    }
}

impl std::fmt::Display for Id {
    /// As in JSON: a string quoted, a number as given.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Id::Text(s) => write!(f, "{s:?}"),
            Id::Number(n) => write!(f, "{n}"),
        }
    }
}

impl PartialEq for Id {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Id::Text(a), Id::Text(b)) => a == b,
            (Id::Number(a), Id::Number(b)) => Numeric::of(a) == Numeric::of(b),
            _ => false,
        }
    }
}

/// A numeric id's value: a whole number exactly (`7`, `7.0` and `7e0`
/// alike), else the float.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Numeric {
    Whole(i128),
    Float(f64),
}

impl Numeric {
    fn of(n: &serde_json::Number) -> Self {
        if let Some(i) = n.as_i64() {
            return Numeric::Whole(i128::from(i));
        }
        if let Some(u) = n.as_u64() {
            return Numeric::Whole(i128::from(u));
        }
        // Finite (an id is): a float's whole values fit an i128 up to 1.7e38.
        let f = n.as_f64().unwrap_or(f64::NAN);
        if f.fract() == 0.0 && f.abs() < 1e38 {
            Numeric::Whole(f as i128)
        } else {
            Numeric::Float(f)
        }
    }
}

impl Id {
    /// A key that tells ids apart as [`Id`]'s equality does: `"7"` and `7`
    /// are two ids, `7` and `7.0` one.
    pub(crate) fn key(&self) -> String {
        match self {
            Id::Text(s) => format!("s:{s}"),
            Id::Number(n) => match Numeric::of(n) {
                Numeric::Whole(i) => format!("n:{i}"),
                Numeric::Float(f) => format!("n:{f}"),
            },
        }
    }
}

/// A sensor's current position.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(examples(json!({"id": "d1", "x": 155.0, "y": 145.0, "type": "drone"})))]
pub struct SensorIn {
    /// Unique id.
    pub id: Id,
    /// East coordinate.
    pub x: f64,
    /// North coordinate.
    pub y: f64,
    /// Its sensor type (a name of the scenario's `sensor_types`);
    /// `default` by default.
    #[serde(rename = "type", default, skip_serializing_if = "Option::is_none")]
    pub sensor_type: Option<String>,
}

/// A reported target.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct TargetIn {
    /// Optional id.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub id: Option<Id>,
    /// East coordinate now.
    pub x: f64,
    /// North coordinate now.
    pub y: f64,
    /// East displacement per step.
    pub vx: f64,
    /// North displacement per step.
    pub vy: f64,
}

/// A past sensor position: a look taken then.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct PositionIn {
    /// East coordinate.
    pub x: f64,
    /// North coordinate.
    pub y: f64,
    /// The type of the sensor that stood there (its field of view and
    /// `p_detect`); `default` by default.
    #[serde(rename = "type", default, skip_serializing_if = "Option::is_none")]
    pub sensor_type: Option<String>,
}

impl PositionIn {
    /// A position of a `default` sensor.
    pub fn at(x: f64, y: f64) -> Self {
        PositionIn {
            x,
            y,
            sensor_type: None,
        }
    }
}

/// Body of `POST /v1/scenarios/{id}/plan`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct PlanRequest {
    /// Sensors now.
    #[schema(min_items = 1)]
    pub sensors: Vec<SensorIn>,
    /// Targets reported now.
    #[serde(default)]
    pub targets: Vec<TargetIn>,
    /// Sensors' positions 1, 2, … steps ago (at most 256 a step).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub history: Option<Vec<Vec<PositionIn>>>,
    /// Horizon T; the scenario's by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 1)]
    pub horizon: Option<Integer>,
    /// Estimator; `exact` by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator: Option<EstimatorKind>,
    /// Coordination; `priority` by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coordination: Option<Coordination>,
    /// What the reported targets cover; `sensors` by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub observed: Option<Observed>,
    /// What the plan maximises; `detections` (the paper's J) by default.
    /// `first_detections` (the `exact` estimator only) counts each target
    /// not yet detected once, at the first step the plan detects it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objective: Option<Objective>,
    /// Include the search values in the response.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub explain: Option<bool>,
    /// Minimum separation between sensors at every step of the plan,
    /// cells (Chebyshev distance; 0..=16, 0 = no rule); the scenario's by
    /// default. Kept wherever it can be: a sensor that cannot keep it (it
    /// starts too close to another, or is cornered) takes the path with the
    /// fewest violations, which the response counts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 0)]
    pub min_separation: Option<Integer>,
    /// With `coordination: joint`: the certified gap at which it stops, in
    /// `[0, 1]`; 0.001 by default. Other coordinations ignore it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(minimum = 0.0, maximum = 1.0)]
    pub gap_target: Option<f64>,
    /// With `coordination: joint`: the time after which its rounds past
    /// `iterated` stop, milliseconds (1..=1000, 20 by default), counted
    /// from the plan's start and within the server's time limit. The
    /// `iterated` plan they start from is always finished, so a plan whose
    /// `iterated` pass takes longer ends with `"stopped": "budget"` and 0
    /// rounds. Other coordinations ignore it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 1)]
    pub budget_ms: Option<Integer>,
    /// Certify the plan: with the `exact` estimator the response carries
    /// `bound`, an upper bound on the best joint plan (true by default).
    /// `false` skips the certificate's work and leaves `bound` out; the
    /// paths and values are the same. Refused with `coordination: joint`,
    /// whose rounds are the certificate's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub certify: Option<bool>,
}

/// A lattice cell and its centre.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct CellOut {
    /// Column.
    pub col: i32,
    /// Row.
    pub row: i32,
    /// Centre, east.
    pub x: f64,
    /// Centre, north.
    pub y: f64,
}

/// The search values of one sensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Explain {
    /// `values[t−1][dr+m·T][dc+m·T]` (m the sensor's speed); null where
    /// unreachable by step t, blocked or off the lattice. With
    /// `first_detections` each is the first detections of a look there
    /// alone (against the history and the looks the sensor planned
    /// against): a path's stops can hold the same targets, so its value is
    /// at most the sum of its cells' values, not the sum.
    pub values: Vec<Vec<Vec<Option<f64>>>>,
}

/// One sensor's plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PlanOut {
    /// The sensor's id.
    pub sensor: Id,
    /// Rank, 1 = highest.
    pub priority: usize,
    /// The cell it starts from.
    pub start: CellOut,
    /// Cells at steps 1..=T.
    pub path: Vec<CellOut>,
    /// The value its final search maximised (for `first_detections`, the
    /// first detections its path adds to those it planned against).
    pub expected_detections: f64,
    /// The (step, other sensor) pairs at which its path is closer to
    /// another sensor's than `min_separation` allows.
    pub separation_violations: u32,
    /// Search values, when asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub explain: Option<Explain>,
}

/// Response of a plan request.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PlanResponse {
    /// Scenario id.
    pub scenario: String,
    /// Horizon T used.
    pub horizon: usize,
    /// Estimator used.
    pub estimator: EstimatorKind,
    /// Coordination used.
    pub coordination: Coordination,
    /// Objective maximised.
    pub objective: Objective,
    /// Minimum separation kept, cells (0: none).
    pub min_separation: usize,
    /// The (step, pair of sensors) at which two paths are closer than
    /// `min_separation` allows, each pair once per step (half the sum of
    /// the plans' counts).
    pub separation_violations: u32,
    /// Plans in request order.
    pub plans: Vec<PlanOut>,
    /// Expected distinct targets detected over steps 1..=T, summed over the
    /// steps (`detections`), or expected targets not yet detected that the
    /// plan detects at least once (`first_detections`).
    pub expected_detections: f64,
    /// The same per step (for `first_detections`: the targets detected for
    /// the first time at that step).
    pub expected_by_step: Vec<f64>,
    /// With the `exact` estimator: an upper bound on what the best joint
    /// plan could expect, and how far this plan may be from it (see the
    /// README's "certified plan quality"). Absent (never `null`) for
    /// `paper`, whose total is not a coverage, and for a request with
    /// `"certify": false`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bound: Option<Bound>,
    /// With `coordination: joint` and the `exact` estimator: its rounds
    /// after `iterated`, why it stopped and the time it used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<JointReport>,
    /// Planning time, microseconds.
    pub compute_micros: u64,
}
