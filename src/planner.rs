//! The planner of one scenario: its statistics, computed once, and
//! [`Planner::plan`], which turns a plan request into coordinated T-step
//! paths. Also the request and response types of the planning API, which the
//! HTTP layer and in-process callers share.

use std::collections::HashSet;
use std::time::Instant;

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use crate::cancel::{CancelToken, Cancelled, Progress};
use crate::coordination::{Bound, Coordination, Fleet, JointReport, JointSettings, coordinate};
use crate::estimator::{
    ElementaryGrid, Estimator, ExactEstimator, PaperEstimator, SourceRays, Target,
};
use crate::geometry::Point;
use crate::limits::{
    MAX_BUDGET_MS, MAX_HISTORY_POSITIONS, MAX_HISTORY_STEPS, MAX_SENSORS, MAX_TARGETS,
};
use crate::scenario::{
    Cell, DEFAULT_TYPE, Integer, Look, Scenario, ValidationError, check_horizon,
    check_min_separation,
};
use crate::stats::Stats;

/// Which estimator of `n̂(k,t)` to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum EstimatorKind {
    /// The conditional expectation under the model (ours).
    #[default]
    Exact,
    /// Equations (1) and (2) of the paper.
    Paper,
}

/// What the reported targets cover.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum Observed {
    /// The targets inside the sensors' fields of view (now and in the history).
    #[default]
    Sensors,
    /// Every target in the zone (a clairvoyant reference).
    Zone,
}

/// A sensor or target id: a string or a number, echoed back as given.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
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

impl Id {
    /// A key that tells ids apart: `"7"` and `7` are two ids.
    pub(crate) fn key(&self) -> String {
        match self {
            Id::Text(s) => format!("s:{s}"),
            Id::Number(n) => format!("n:{n}"),
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
    #[schema(max_length = 32)]
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
    #[schema(max_length = 32)]
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
    #[schema(min_items = 1, max_items = 256)]
    pub sensors: Vec<SensorIn>,
    /// Targets reported now.
    #[serde(default)]
    #[schema(max_items = 20000)]
    pub targets: Vec<TargetIn>,
    /// Sensors' positions 1, 2, … steps ago (at most 256 a step).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(max_items = 32)]
    pub history: Option<Vec<Vec<PositionIn>>>,
    /// Horizon T; the scenario's by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 1, maximum = 12)]
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
    /// Include the search values in the response.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub explain: Option<bool>,
    /// Minimum separation between sensors at every step of the plan,
    /// cells (Chebyshev distance; 0..=16, 0 = no rule); the scenario's by
    /// default. Kept wherever it can be: a sensor that cannot keep it (it
    /// starts too close to another, or is cornered) takes the path with the
    /// fewest violations, which the response counts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 0, maximum = 16)]
    pub min_separation: Option<Integer>,
    /// With `coordination: joint`: the certified gap at which it stops, in
    /// `[0, 1]`; 0.001 by default. Other coordinations ignore it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(minimum = 0.0, maximum = 1.0)]
    pub gap_target: Option<f64>,
    /// With `coordination: joint`: the most time the plan may take,
    /// milliseconds (1..=1000, 20 by default), counted from its start and
    /// within the server's time limit. Other coordinations ignore it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<u32>, minimum = 1, maximum = 1000)]
    pub budget_ms: Option<Integer>,
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
    /// unreachable by step t, blocked or off the lattice.
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
    /// The value its final search maximised.
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
    /// Minimum separation kept, cells (0: none).
    pub min_separation: usize,
    /// The (step, pair of sensors) at which two paths are closer than
    /// `min_separation` allows, each pair once per step (half the sum of
    /// the plans' counts).
    pub separation_violations: u32,
    /// Plans in request order.
    pub plans: Vec<PlanOut>,
    /// Expected distinct targets detected over steps 1..=T.
    pub expected_detections: f64,
    /// The same per step.
    pub expected_by_step: Vec<f64>,
    /// With the `exact` estimator: an upper bound on what the best joint
    /// plan could expect, and how far this plan may be from it (see the
    /// README's "certified plan quality"). Absent for `paper`, whose total
    /// is not a coverage.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bound: Option<Bound>,
    /// With `coordination: joint` and the `exact` estimator: its rounds
    /// after `iterated`, why it stopped and the time it used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<JointReport>,
    /// Planning time, microseconds.
    pub compute_micros: u64,
}

/// A validated plan request.
#[derive(Debug, Clone)]
pub struct PlanInput {
    pub(crate) ids: Vec<Id>,
    pub(crate) starts: Vec<Cell>,
    pub(crate) types: Vec<usize>,
    pub(crate) targets: Vec<Target>,
    /// Past looks: cells and sensor types, newest first.
    pub(crate) history: Vec<Vec<(Cell, usize)>>,
    pub(crate) horizon: usize,
    pub(crate) estimator: EstimatorKind,
    pub(crate) coordination: Coordination,
    pub(crate) observed: Observed,
    explain: bool,
    pub(crate) min_separation: usize,
    pub(crate) joint: JointSettings,
}

fn finite(field: impl Fn() -> String, v: f64) -> Result<f64, ValidationError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ValidationError::new(field(), "must be a finite number"))
    }
}

impl PlanInput {
    /// The sensors' cells now, in request order.
    pub fn starts(&self) -> &[Cell] {
        &self.starts
    }

    /// The sensors' types (indices into the scenario's), in request order.
    pub fn types(&self) -> &[usize] {
        &self.types
    }

    /// Validates a request against a scenario.
    pub fn new(s: &Scenario, req: &PlanRequest) -> Result<Self, ValidationError> {
        if req.sensors.is_empty() {
            return Err(ValidationError::new(
                "sensors",
                "at least one sensor is required",
            ));
        }
        if req.sensors.len() > MAX_SENSORS {
            return Err(ValidationError::new(
                "sensors",
                format!("at most {MAX_SENSORS} sensors, got {}", req.sensors.len()),
            ));
        }
        if req.targets.len() > MAX_TARGETS {
            return Err(ValidationError::new(
                "targets",
                format!("at most {MAX_TARGETS} targets, got {}", req.targets.len()),
            ));
        }
        let history = req.history.as_deref().unwrap_or(&[]);
        if history.len() > MAX_HISTORY_STEPS {
            return Err(ValidationError::new(
                "history",
                format!("at most {MAX_HISTORY_STEPS} steps, got {}", history.len()),
            ));
        }
        // Field names are formatted only on error: a history holds thousands
        // of positions.
        let in_zone =
            |field: &dyn Fn() -> String, x: f64, y: f64| -> Result<Cell, ValidationError> {
                finite(|| format!("{}.x", field()), x)?;
                finite(|| format!("{}.y", field()), y)?;
                let p = Point::new(x, y);
                if !s.in_zone(p) {
                    return Err(ValidationError::new(
                        field(),
                        format!(
                            "({x}, {y}) is outside the zone [0,{}]×[0,{}]",
                            s.width, s.height
                        ),
                    ));
                }
                Ok(s.snap(p))
            };
        let type_of = |field: &dyn Fn() -> String, name: Option<&str>| {
            let name = name.unwrap_or(DEFAULT_TYPE);
            s.type_index(name).ok_or_else(|| {
                let known: Vec<&str> = s.types.iter().map(|t| t.name.as_str()).collect();
                ValidationError::new(
                    format!("{}.type", field()),
                    format!(
                        "unknown sensor type {name:?}; the scenario has {}",
                        known.join(", ")
                    ),
                )
            })
        };
        let free = |field: &dyn Fn() -> String, c: Cell| {
            if s.is_blocked(c) {
                Err(ValidationError::new(
                    field(),
                    format!(
                        "cell (col {}, row {}) is in a no-go zone: no sensor may stand on it",
                        c.col, c.row
                    ),
                ))
            } else {
                Ok(c)
            }
        };
        let mut seen = HashSet::new();
        let mut ids = Vec::with_capacity(req.sensors.len());
        let mut starts = Vec::with_capacity(req.sensors.len());
        let mut types = Vec::with_capacity(req.sensors.len());
        for (i, sensor) in req.sensors.iter().enumerate() {
            if !seen.insert(sensor.id.key()) {
                return Err(ValidationError::new(
                    format!("sensors[{i}].id"),
                    "duplicate sensor id",
                ));
            }
            let field = || format!("sensors[{i}]");
            types.push(type_of(&field, sensor.sensor_type.as_deref())?);
            starts.push(free(&field, in_zone(&field, sensor.x, sensor.y)?)?);
            ids.push(sensor.id.clone());
        }
        let mut targets = Vec::with_capacity(req.targets.len());
        for (i, t) in req.targets.iter().enumerate() {
            for (name, v) in [("x", t.x), ("y", t.y), ("vx", t.vx), ("vy", t.vy)] {
                finite(|| format!("targets[{i}].{name}"), v)?;
            }
            targets.push(Target {
                pos: Point::new(t.x, t.y),
                vel: Point::new(t.vx, t.vy),
            });
        }
        let mut past = Vec::with_capacity(history.len());
        for (si, step) in history.iter().enumerate() {
            if step.len() > MAX_HISTORY_POSITIONS {
                return Err(ValidationError::new(
                    format!("history[{si}]"),
                    format!(
                        "at most {MAX_HISTORY_POSITIONS} positions per step, got {}",
                        step.len()
                    ),
                ));
            }
            past.push(
                step.iter()
                    .enumerate()
                    .map(|(pi, p)| {
                        let field = || format!("history[{si}][{pi}]");
                        let ty = type_of(&field, p.sensor_type.as_deref())?;
                        Ok((free(&field, in_zone(&field, p.x, p.y)?)?, ty))
                    })
                    .collect::<Result<Vec<_>, ValidationError>>()?,
            );
        }
        let horizon = check_horizon("horizon", req.horizon.as_ref(), s.horizon)?;
        let min_separation = check_min_separation("min_separation", req.min_separation.as_ref())?
            .unwrap_or(s.min_separation);
        let mut joint = JointSettings::default();
        if let Some(g) = req.gap_target {
            if !(0.0..=1.0).contains(&g) {
                return Err(ValidationError::new(
                    "gap_target",
                    format!("must be a number in [0, 1], got {g}"),
                ));
            }
            joint.gap_target = g;
        }
        if let Some(b) = &req.budget_ms {
            let ms = b.check("budget_ms", 1..=MAX_BUDGET_MS as usize)?;
            joint.budget = std::time::Duration::from_millis(ms as u64);
        }
        Ok(PlanInput {
            min_separation,
            ids,
            starts,
            types,
            targets,
            history: past,
            horizon,
            estimator: req.estimator.unwrap_or_default(),
            coordination: req.coordination.unwrap_or_default(),
            observed: req.observed.unwrap_or_default(),
            explain: req.explain.unwrap_or(false),
            joint,
        })
    }
}

/// A scenario with its precomputed statistics, ready to plan.
#[derive(Debug)]
pub struct Planner {
    /// The scenario.
    pub scenario: Scenario,
    /// Its per-cell statistics, per field of view (the scenario's `fovs`;
    /// `stats[0]` is the type `default`'s).
    pub stats: Vec<Stats>,
    pub(crate) rays: Vec<SourceRays>,
    pub(crate) grid: Option<ElementaryGrid>,
    /// Time the precomputation took, milliseconds.
    pub precompute_ms: f64,
}

impl Planner {
    /// Precomputes the statistics of a scenario.
    pub fn new(scenario: Scenario) -> Self {
        match Self::precompute(scenario, &CancelToken::never(), &Progress::default()) {
            Ok(planner) => planner,
            Err(Cancelled) => unreachable!("work that is never cancelled finishes"),
        }
    }

    /// [`Planner::new`], in blocks of cells (see
    /// [`Stats::for_fov_cancellable`]) that check `cancel` and advance
    /// `progress`; the indexing of rays that follows is one more block.
    /// The planner is the same as [`Planner::new`]'s.
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub fn precompute(
        scenario: Scenario,
        cancel: &CancelToken,
        progress: &Progress,
    ) -> Result<Self, Cancelled> {
        let started = Instant::now();
        progress.add_total(scenario.fovs.len() * Stats::blocks(&scenario) + 1);
        let stats = scenario
            .fovs
            .iter()
            .map(|&fov| Stats::for_fov_cancellable(&scenario, fov, cancel, progress))
            .collect::<Result<Vec<_>, _>>()?;
        cancel.check()?;
        let mut rays = SourceRays::for_scenario(&scenario);
        let grid = ElementaryGrid::new(&scenario);
        if let Some(grid) = &grid {
            SourceRays::index_crossings(&mut rays, &scenario, grid);
        }
        SourceRays::index_looks(&mut rays, &scenario);
        progress.advance(1);
        Ok(Planner {
            scenario,
            stats,
            rays,
            grid,
            precompute_ms: started.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// The statistics of the sensor type `ty`'s field of view.
    pub fn stats_of(&self, ty: usize) -> &Stats {
        &self.stats[self.scenario.types[ty].fov_slot]
    }

    /// Approximate heap memory held, bytes (for cache bounds).
    pub fn memory_bytes(&self) -> usize {
        let cells = self.scenario.cell_count();
        let blocked = if self.scenario.has_no_go() { cells } else { 0 };
        let stats = 3 * self.stats.len() * cells * std::mem::size_of::<f64>() + blocked;
        let grid = self.grid.as_ref().map_or(0, ElementaryGrid::memory_bytes);
        let rays: usize = self.rays.iter().map(SourceRays::memory_bytes).sum();
        std::mem::size_of::<Self>() + stats + grid + rays
    }

    /// Validates and plans a request.
    pub fn plan_request(&self, req: &PlanRequest) -> Result<PlanResponse, ValidationError> {
        Ok(self.plan(&PlanInput::new(&self.scenario, req)?))
    }

    /// Validates a request and plans it unless `cancel` is cancelled
    /// first (see [`Planner::plan_cancellable`]).
    ///
    /// # Errors
    /// The outer error for an invalid request, the inner one when the work
    /// was cancelled.
    pub fn plan_request_cancellable(
        &self,
        req: &PlanRequest,
        cancel: &CancelToken,
    ) -> Result<Result<PlanResponse, Cancelled>, ValidationError> {
        Ok(self.plan_cancellable(&PlanInput::new(&self.scenario, req)?, cancel))
    }

    /// Plans a validated request.
    ///
    /// Runs on a worker of rayon's global pool (moving there first when
    /// called from outside it), so the plan's parallel parts split among
    /// the workers without handing work back and forth between threads.
    /// With a global pool of one thread (one core) it runs where it is
    /// called instead ([`Planner::plan_here`]): the same answer, without
    /// the two thread switches of the move.
    pub fn plan(&self, input: &PlanInput) -> PlanResponse {
        match self.plan_cancellable(input, &CancelToken::never()) {
            Ok(response) => response,
            Err(Cancelled) => unreachable!("a plan that is never cancelled finishes"),
        }
    }

    /// [`Planner::plan`], checking `cancel` between its stages and within
    /// the search and coordination (see [`coordinate`]), so a cancelled plan
    /// stops within one sensor-step's fill.
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub fn plan_cancellable(
        &self,
        input: &PlanInput,
        cancel: &CancelToken,
    ) -> Result<PlanResponse, Cancelled> {
        if rayon::current_thread_index().is_none() && rayon::current_num_threads() > 1 {
            return rayon::scope(|_| self.plan_here(input, cancel));
        }
        self.plan_here(input, cancel)
    }

    /// [`Planner::plan_cancellable`] on the calling thread: on a worker of
    /// a rayon pool the plan's parallel parts split among its workers; on
    /// any other thread they run there, one after the other. The answer is
    /// the same to the last bit either way. For a pool of one thread this
    /// saves the two thread switches of the hop to it and back.
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub fn plan_here(
        &self,
        input: &PlanInput,
        cancel: &CancelToken,
    ) -> Result<PlanResponse, Cancelled> {
        cancel.check()?;
        let started = Instant::now();
        let s = &self.scenario;
        let est = self.estimator(input, cancel)?;
        cancel.check()?;
        let fleet = Fleet::new(
            s,
            est.as_ref(),
            &input.starts,
            &input.types,
            input.horizon,
            input.min_separation,
            cancel,
        );
        let result = coordinate(&fleet, input.coordination, input.joint, started)?;
        let cell_out = |c: Cell| {
            let p = s.centre(c);
            CellOut {
                col: c.col,
                row: c.row,
                x: p.x,
                y: p.y,
            }
        };
        let mut rank = vec![0; input.starts.len()];
        for (r, &i) in result.order.iter().enumerate() {
            rank[i] = r + 1;
        }
        let plans = result
            .plans
            .iter()
            .enumerate()
            .map(|(i, p)| PlanOut {
                sensor: input.ids[i].clone(),
                priority: rank[i],
                start: cell_out(input.starts[i]),
                path: p.path.iter().map(|&c| cell_out(c)).collect(),
                expected_detections: p.value,
                separation_violations: result.violations.per_sensor[i],
                explain: input.explain.then(|| Explain {
                    values: p.grid.to_nested(),
                }),
            })
            .collect();
        Ok(PlanResponse {
            scenario: s.id.clone(),
            horizon: input.horizon,
            estimator: input.estimator,
            coordination: input.coordination,
            min_separation: input.min_separation,
            separation_violations: result.violations.pairs,
            plans,
            expected_detections: result.by_step.iter().sum(),
            expected_by_step: result.by_step,
            bound: result.bound,
            joint: result.joint,
            compute_micros: started.elapsed().as_micros() as u64,
        })
    }

    /// The estimator `input` asks for, prepared for its sensors, targets
    /// and looks.
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub(crate) fn estimator(
        &self,
        input: &PlanInput,
        cancel: &CancelToken,
    ) -> Result<Box<dyn Estimator + '_>, Cancelled> {
        let s = &self.scenario;
        Ok(match input.estimator {
            EstimatorKind::Paper => Box::new(PaperEstimator::new(
                s,
                &self.stats,
                &input.starts,
                &input.types,
                &input.targets,
                input.horizon,
            )),
            EstimatorKind::Exact => {
                let observed = self.observed_looks(input);
                let est = ExactEstimator::new(
                    s,
                    &self.stats,
                    &self.rays,
                    self.grid.as_ref(),
                    &observed,
                    &input.targets,
                    &input.starts,
                    &input.types,
                    input.horizon,
                );
                cancel.check()?;
                est.prepare();
                Box::new(est)
            }
        })
    }

    /// `O_s` for s = 0, 1, …: the looks taken now and in the history (the
    /// whole zone, certain, now when the caller reports every target in it).
    fn observed_looks(&self, input: &PlanInput) -> Vec<Vec<Look>> {
        let s = &self.scenario;
        let now = match input.observed {
            Observed::Zone => vec![Look::certain(s.zone_region())],
            Observed::Sensors => dedup(
                input
                    .starts
                    .iter()
                    .copied()
                    .zip(input.types.iter().copied()),
            )
            .into_iter()
            .map(|(c, ty)| s.look(ty, c))
            .collect(),
        };
        std::iter::once(now)
            .chain(input.history.iter().map(|step| {
                dedup(step.iter().copied())
                    .into_iter()
                    .map(|(c, ty)| s.look(ty, c))
                    .collect()
            }))
            .collect()
    }
}

/// The looks (cell and type) without repeats, in their order (the
/// estimator reads the i-th position of each step as one sensor's track).
/// Two sensors of the same type on one cell take one look: they see the
/// same targets at once.
fn dedup(looks: impl Iterator<Item = (Cell, usize)>) -> Vec<(Cell, usize)> {
    // As many as come, as a rule: one allocation, not one per doubling.
    let mut kept: Vec<(Cell, usize)> = Vec::with_capacity(looks.size_hint().0);
    let mut seen = HashSet::new();
    for look in looks {
        // A scan for a fleet's few looks (a hash per look cost 2 % of a
        // plan), a set past that.
        let new = if kept.len() < 64 {
            !kept.contains(&look)
        } else {
            if seen.is_empty() {
                seen.extend(kept.iter().copied());
            }
            seen.insert(look)
        };
        if new {
            kept.push(look);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::Id;

    #[test]
    fn ids_are_strings_or_numbers_echoed_as_given() {
        for text in [
            r#""a""#,
            r#""7""#,
            "7",
            "-3",
            "1.5",
            "18446744073709551615",
            "1e3",
        ] {
            let id: Id = serde_json::from_str(text).expect(text);
            let back = serde_json::to_string(&id).expect("serializes");
            let again: Id = serde_json::from_str(&back).expect("parses back");
            assert_eq!(again, id, "{text}");
            // Parsed the way `serde_json` reads the same token.
            assert_eq!(
                serde_json::to_value(&id).expect("value"),
                serde_json::from_str::<serde_json::Value>(text).expect("value"),
                "{text}"
            );
        }
        assert!(matches!(
            serde_json::from_str::<Id>(r#""7""#),
            Ok(Id::Text(_))
        ));
        assert!(matches!(serde_json::from_str::<Id>("7"), Ok(Id::Number(_))));
        for bad in ["true", "null", "[1]", r#"{"a":1}"#] {
            let err = serde_json::from_str::<Id>(bad).expect_err(bad);
            assert!(err.to_string().contains("a string or a number"), "{err}");
        }
    }
}
