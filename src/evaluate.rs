//! Scoring given paths: the expected detections of one path per sensor,
//! whoever planned them, with the estimator a plan would use.
//!
//! The body is a plan request plus `paths`, one per sensor. The paths are
//! checked as the planner's own would be (a legal move at each step at the
//! sensor type's speed, through free cells, on the lattice), then scored:
//! the total and its steps as a plan reports them, each sensor's marginal
//! (what the total loses without it) and the breaches of the minimum
//! separation. A plan's own paths score its `expected_detections`.
//!
//! With the `paper` estimator, whose total depends on the order in which
//! sensors exclude each other, the paths count in the order given: the
//! first as the highest priority.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use crate::cancel::{CancelToken, Cancelled};
use crate::coordination::{Fleet, Objective, path_moves, sensor_motion};
use crate::planner::{Chosen, EstimatorKind, Id, PlanInput, PlanRequest, Planner};
use crate::scenario::{Cell, Integer, ValidationError};
use crate::separation;

/// A cell of a path.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CellIn {
    /// Column, from 0 at the west edge.
    #[schema(value_type = i32)]
    pub col: Integer,
    /// Row, from 0 at the south edge.
    #[schema(value_type = i32)]
    pub row: Integer,
}

/// One sensor's path to score.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SensorPathIn {
    /// The sensor's id, as in `sensors`.
    pub sensor: Id,
    /// Its cells at steps 1..=T.
    pub path: Vec<CellIn>,
}

/// Body of `POST /v1/scenarios/{id}/evaluate`: a plan request (its
/// `coordination`, `explain`, `gap_target`, `budget_ms` and `certify` are
/// checked as a plan checks them and play no part) plus the paths to
/// score.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvaluateRequest {
    /// The sensors, targets, history and options, as in a plan request.
    #[serde(flatten)]
    pub plan: PlanRequest,
    /// One path per sensor.
    pub paths: Vec<SensorPathIn>,
}

/// By hand: `paths` taken out, the rest read as a plan request, which
/// refuses unknown fields (serde's `flatten` would accept any).
impl<'de> Deserialize<'de> for EvaluateRequest {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut fields = serde_json::Map::<String, serde_json::Value>::deserialize(deserializer)?;
        let paths = fields
            .remove("paths")
            .ok_or_else(|| D::Error::missing_field("paths"))?;
        let paths = crate::json_path::from_value(&paths, "paths").map_err(D::Error::custom)?;
        let plan = crate::json_path::from_value(&serde_json::Value::Object(fields), "")
            .map_err(D::Error::custom)?;
        Ok(Self { plan, paths })
    }
}

/// One sensor's share of a scored set of paths.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SensorScore {
    /// The sensor's id.
    pub sensor: Id,
    /// What the total loses without this sensor's path.
    pub marginal: f64,
    /// The (step, other sensor) pairs at which its path is closer to
    /// another sensor's than `min_separation` allows.
    pub separation_violations: u32,
}

/// Response of an evaluate request.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct EvaluateResponse {
    /// Scenario id.
    pub scenario: String,
    /// Horizon T of the paths.
    pub horizon: usize,
    /// Estimator used.
    pub estimator: EstimatorKind,
    /// Objective scored.
    pub objective: Objective,
    /// Minimum separation counted, cells (0: none).
    pub min_separation: usize,
    /// Expected distinct targets detected over steps 1..=T (for
    /// `first_detections`: targets not yet detected that the paths detect
    /// at least once).
    pub expected_detections: f64,
    /// The same per step (for `first_detections`: detected for the first
    /// time at that step).
    pub expected_by_step: Vec<f64>,
    /// The (step, pair of sensors) at which two paths are closer than
    /// `min_separation` allows.
    pub separation_violations: u32,
    /// Per sensor, in the order of `sensors`.
    pub sensors: Vec<SensorScore>,
}

/// A validated evaluate request: the plan input and one legal path per
/// sensor, in the order of `sensors`.
#[derive(Debug, Clone)]
pub struct EvaluateInput {
    /// The plan request's part.
    pub plan: PlanInput,
    /// Per sensor (request order), its cells at steps 1..=T.
    pub paths: Vec<Vec<Cell>>,
    /// The order in which the paths count for the paper estimator: the
    /// sensors in the order of `paths`.
    pub order: Vec<usize>,
}

impl EvaluateInput {
    /// Validates a request against a planner's scenario.
    ///
    /// # Errors
    /// A [`ValidationError`] naming the field: the plan request's, or a
    /// path's that names an unknown sensor or one already given, leaves a
    /// sensor out, has not T cells, leaves the lattice, stands on a no-go
    /// cell, or moves farther than its type's speed (or than free ground
    /// lets it) in one step.
    pub fn new(planner: &Planner, req: &EvaluateRequest) -> Result<Self, ValidationError> {
        let s = &planner.scenario;
        let plan = PlanInput::new(s, &req.plan)?;
        let index: HashMap<String, usize> = plan
            .ids
            .iter()
            .enumerate()
            .map(|(i, id)| (id.key(), i))
            .collect();
        let n = plan.starts.len();
        let mut paths: Vec<Option<Vec<Cell>>> = vec![None; n];
        let mut order = Vec::with_capacity(n);
        for (k, given) in req.paths.iter().enumerate() {
            let field = format!("paths[{k}]");
            let Some(&i) = index.get(&given.sensor.key()) else {
                // `7` and `"7"` are two ids: name the near miss.
                let text = given.sensor.to_string();
                let near = plan
                    .ids
                    .iter()
                    .find(|id| id.to_string().trim_matches('"') == text.trim_matches('"'));
                let hint = near.map_or(String::new(), |id| {
                    format!(" (it has {id}: a string id and a number id differ)")
                });
                return Err(ValidationError::new(
                    format!("{field}.sensor"),
                    format!("no sensor {} in `sensors`{hint}", given.sensor),
                ));
            };
            if paths[i].is_some() {
                return Err(ValidationError::new(
                    format!("{field}.sensor"),
                    format!("a second path for sensor {}", given.sensor),
                ));
            }
            if given.path.len() != plan.horizon {
                return Err(ValidationError::new(
                    format!("{field}.path"),
                    format!(
                        "must hold the cells of steps 1..={} ({} cells), got {}",
                        plan.horizon,
                        plan.horizon,
                        given.path.len()
                    ),
                ));
            }
            let ty = &s.types[plan.types[i]];
            let mut cells = Vec::with_capacity(plan.horizon);
            for (t, c) in given.path.iter().enumerate() {
                let field = || format!("{field}.path[{t}]");
                let coord = |name: &str, v: &Integer| {
                    v.signed()
                        .and_then(|v| i32::try_from(v).ok())
                        .ok_or_else(|| {
                            ValidationError::new(
                                format!("{}.{name}", field()),
                                format!("must be a whole number, got {}", v.raw()),
                            )
                        })
                };
                let cell = Cell {
                    col: coord("col", &c.col)?,
                    row: coord("row", &c.row)?,
                };
                if !s.on_lattice(cell) {
                    return Err(ValidationError::new(
                        field(),
                        format!(
                            "(col {}, row {}) is off the lattice of {} columns and {} rows",
                            cell.col, cell.row, s.cols, s.rows
                        ),
                    ));
                }
                if let Some(why) = s.blocked_for(plan.types[i], cell) {
                    return Err(ValidationError::new(
                        field(),
                        format!("(col {}, row {}) {why}", cell.col, cell.row),
                    ));
                }
                let from = if t == 0 { plan.starts[i] } else { cells[t - 1] };
                let (dc, dr) = (cell.col - from.col, cell.row - from.row);
                if dc.unsigned_abs().max(dr.unsigned_abs()) as usize > ty.speed {
                    return Err(ValidationError::new(
                        field(),
                        format!(
                            "the move from (col {}, row {}) to (col {}, row {}) is beyond the \
                             speed of type {:?} ({} cells a step)",
                            from.col, from.row, cell.col, cell.row, ty.name, ty.speed
                        ),
                    ));
                }
                cells.push(cell);
            }
            // Within the speed, a move may still be cut off by no-go
            // ground: the same motion as the planner's searches decides.
            let motion = sensor_motion(s, plan.starts[i], plan.types[i], plan.horizon);
            if let Some(t) = motion.first_illegal_step(&path_moves(plan.starts[i], &cells)) {
                let (from, to) = (if t == 0 { plan.starts[i] } else { cells[t - 1] }, cells[t]);
                return Err(ValidationError::new(
                    format!("{field}.path[{t}]"),
                    format!(
                        "(col {}, row {}) cannot be reached from (col {}, row {}) in one step \
                         of {} cells through free cells",
                        to.col, to.row, from.col, from.row, ty.speed
                    ),
                ));
            }
            paths[i] = Some(cells);
            order.push(i);
        }
        let paths = paths
            .into_iter()
            .enumerate()
            .map(|(i, p)| {
                p.ok_or_else(|| {
                    ValidationError::new(
                        "paths",
                        format!("sensor {} has no path: give one per sensor", plan.ids[i]),
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { plan, paths, order })
    }
}

/// The scores of one set of paths (see [`Evaluator::score`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Scores {
    /// Expected detections at steps 1..=T.
    pub by_step: Vec<f64>,
    /// Per sensor: what the total loses without its path.
    pub marginals: Vec<f64>,
}

/// An estimator prepared for one request's sensors and targets, scoring
/// any paths of those sensors (many sets of them, for exhaustive checks).
pub struct Evaluator<'p> {
    est: Chosen<'p>,
    planner: &'p Planner,
    plan: &'p PlanInput,
}

impl<'p> Evaluator<'p> {
    /// Prepares the estimator of `plan` (a validated request).
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub fn new(
        planner: &'p Planner,
        plan: &'p PlanInput,
        cancel: &CancelToken,
    ) -> Result<Self, Cancelled> {
        Ok(Self {
            est: planner.estimator(plan, cancel, None)?,
            planner,
            plan,
        })
    }

    /// Runs `f` on the fleet of the request's sensors, maximising its
    /// objective.
    fn with_fleet<R>(&self, f: impl FnOnce(&Fleet) -> R) -> R {
        self.est
            .with_fleet(&self.planner.scenario, self.plan, &CancelToken::never(), f)
    }

    /// The expected detections at steps 1..=T of `paths` (one per sensor,
    /// request order, each legal), counted in `order` (a permutation of
    /// the sensors; it matters only to the paper estimator); for first
    /// detections, the targets detected for the first time at each step.
    pub fn by_step(&self, paths: &[&[Cell]], order: &[usize]) -> Vec<f64> {
        self.with_fleet(|fleet| fleet.by_step(paths, order))
    }

    /// [`Evaluator::by_step`] and each sensor's marginal: its value against
    /// every other path (exact; for first detections, the total less the
    /// total without its path), or the change in the total without it
    /// (paper: its own value and the overlap reductions it causes below
    /// it).
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled (checked before each
    /// sensor's marginal: with the paper estimator one re-scores every
    /// lower sensor whose view it overlaps).
    pub fn score(
        &self,
        paths: &[&[Cell]],
        order: &[usize],
        cancel: &CancelToken,
    ) -> Result<Scores, Cancelled> {
        self.with_fleet(|fleet| {
            let by_step = fleet.by_step(paths, order);
            let marginals = (0..paths.len())
                .map(|i| {
                    cancel.check()?;
                    if fleet.first.is_some() {
                        let others: Vec<usize> =
                            order.iter().copied().filter(|&q| q != i).collect();
                        return Ok(by_step.iter().sum::<f64>()
                            - fleet.by_step(paths, &others).iter().sum::<f64>());
                    }
                    Ok(fleet.marginal(paths, order, i))
                })
                .collect::<Result<_, Cancelled>>()?;
            Ok(Scores { by_step, marginals })
        })
    }
}

impl Planner {
    /// Scores a validated evaluate request (see the module docs).
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub fn evaluate(
        &self,
        input: &EvaluateInput,
        cancel: &CancelToken,
    ) -> Result<EvaluateResponse, Cancelled> {
        let evaluator = Evaluator::new(self, &input.plan, cancel)?;
        cancel.check()?;
        let paths: Vec<&[Cell]> = input.paths.iter().map(Vec::as_slice).collect();
        let Scores { by_step, marginals } = evaluator.score(&paths, &input.order, cancel)?;
        cancel.check()?;
        let d = input.plan.min_separation;
        let violations = separation::count(&input.paths, d);
        Ok(EvaluateResponse {
            scenario: self.scenario.id.clone(),
            horizon: input.plan.horizon,
            estimator: input.plan.estimator,
            objective: input.plan.objective,
            min_separation: d,
            expected_detections: by_step.iter().sum(),
            expected_by_step: by_step,
            separation_violations: violations.pairs,
            sensors: marginals
                .into_iter()
                .enumerate()
                .map(|(i, marginal)| SensorScore {
                    sensor: input.plan.ids[i].clone(),
                    marginal,
                    separation_violations: violations.per_sensor[i],
                })
                .collect(),
        })
    }

    /// Validates and scores an evaluate request.
    ///
    /// # Errors
    /// The outer error for an invalid request, the inner one when the work
    /// was cancelled.
    pub fn evaluate_request(
        &self,
        req: &EvaluateRequest,
        cancel: &CancelToken,
    ) -> Result<Result<EvaluateResponse, Cancelled>, ValidationError> {
        Ok(self.evaluate(&EvaluateInput::new(self, req)?, cancel))
    }
}
