//! A plan request validated against its scenario, once: [`PlanInput`]
//! (parse, don't validate). Every bound a request can break is checked
//! here, with a [`ValidationError`] that names the field.

use std::collections::HashSet;

use super::wire::*;
use crate::coordination::{Coordination, JointSettings, Objective};
use crate::estimator::Target;
use crate::geometry::Point;
use crate::limits::{
    MAX_BUDGET_MS, MAX_HISTORY_POSITIONS, MAX_HISTORY_STEPS, MAX_SENSORS, MAX_TARGETS,
};
use crate::scenario::{
    Cell, DEFAULT_TYPE, Look, Scenario, ValidationError, check_horizon, check_min_separation,
};

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
    pub(crate) objective: Objective,
    pub(crate) observed: Observed,
    pub(crate) explain: bool,
    pub(crate) min_separation: usize,
    pub(crate) joint: JointSettings,
    /// Compute the certificate (exact plans).
    pub(crate) certify: bool,
}

fn finite(field: impl Fn() -> String, v: f64) -> Result<f64, ValidationError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ValidationError::new(field(), "must be a finite number"))
    }
}

/// The objective asked for (`detections` by default), refused for the
/// paper estimator when it is `first_detections`: its values are per step
/// and per cell, with no notion of a target detected before.
pub(crate) fn check_objective(
    field: &str,
    objective: Option<Objective>,
    estimator: EstimatorKind,
) -> Result<Objective, ValidationError> {
    let objective = objective.unwrap_or_default();
    if objective == Objective::FirstDetections && estimator == EstimatorKind::Paper {
        return Err(ValidationError::new(
            field,
            "first_detections needs the exact estimator (the paper estimator has no notion of a target detected before)",
        ));
    }
    Ok(objective)
}

/// The estimator asked for, refused for `paper` in a scenario with
/// obstacles: eqs. (1)–(2) have no notion of a blocked sight line or of a
/// flight that a building ends.
pub(crate) fn check_estimator(
    field: &str,
    estimator: EstimatorKind,
    scenario: &Scenario,
) -> Result<EstimatorKind, ValidationError> {
    if estimator == EstimatorKind::Paper && scenario.has_obstacles() {
        return Err(ValidationError::new(
            field,
            "the paper estimator has no notion of sight lines that obstacles block: this scenario has obstacles, so use the exact estimator",
        ));
    }
    Ok(estimator)
}

/// Whether to certify the plan (true by default), refused `false` with
/// `joint` coordination: its rounds tighten the certificate and stop on
/// its gap.
pub(crate) fn check_certify(
    field: &str,
    certify: Option<bool>,
    coordination: Coordination,
) -> Result<bool, ValidationError> {
    let certify = certify.unwrap_or(true);
    if !certify && coordination == Coordination::Joint {
        return Err(ValidationError::new(
            field,
            "joint coordination improves its plan until its certificate's gap is small: it cannot skip the certificate",
        ));
    }
    Ok(certify)
}

/// The cell and type of a sensor at `(x, y)` of type `name` (`default` when
/// `None`): in the zone, of a known type, on a cell its type may stand on.
/// `field` names it in errors; it is formatted only on error, since a
/// history holds thousands of positions.
pub(crate) fn place(
    s: &Scenario,
    field: &dyn Fn() -> String,
    x: f64,
    y: f64,
    name: Option<&str>,
) -> Result<(Cell, usize), ValidationError> {
    let name = name.unwrap_or(DEFAULT_TYPE);
    let ty = s.type_index(name).ok_or_else(|| {
        let known: Vec<&str> = s.types.iter().map(|t| t.name.as_str()).collect();
        ValidationError::new(
            format!("{}.type", field()),
            format!(
                "unknown sensor type {name:?}; the scenario has {}",
                known.join(", ")
            ),
        )
    })?;
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
    let c = s.snap(p);
    match s.blocked_for(ty, c) {
        Some(why) => Err(ValidationError::new(
            field(),
            format!("cell (col {}, row {}) {why}", c.col, c.row),
        )),
        None => Ok((c, ty)),
    }
}

/// The looks of one step's sensors at `places` (cell and type), in their
/// order (the estimator reads the i-th look of each step as one sensor's
/// track). Every look detects independently of the others, so two sensors
/// of one type on one cell take two looks, unless the type is certain
/// (`p_detect` 1): the second then detects nothing the first does not,
/// and is left out.
pub(crate) fn step_looks(s: &Scenario, places: impl Iterator<Item = (Cell, usize)>) -> Vec<Look> {
    // As many as come, as a rule: one allocation, not one per doubling.
    let mut kept: Vec<(Cell, usize)> = Vec::with_capacity(places.size_hint().0);
    let mut seen = HashSet::new();
    for place in places {
        let repeat = s.types[place.1].p_detect >= 1.0
            && if kept.len() < 64 {
                // A scan for a fleet's few looks (cheaper than hashing
                // each), a set past that.
                kept.contains(&place)
            } else {
                if seen.is_empty() {
                    seen.extend(kept.iter().copied());
                }
                !seen.insert(place)
            };
        if !repeat {
            kept.push(place);
        }
    }
    kept.into_iter().map(|(c, ty)| s.look(ty, c)).collect()
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

    /// The horizon T, steps.
    pub fn horizon(&self) -> usize {
        self.horizon
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
            let (cell, ty) = place(s, &field, sensor.x, sensor.y, sensor.sensor_type.as_deref())?;
            types.push(ty);
            starts.push(cell);
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
                        place(s, &field, p.x, p.y, p.sensor_type.as_deref())
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
        let estimator = check_estimator("estimator", req.estimator.unwrap_or_default(), s)?;
        let objective = check_objective("objective", req.objective, estimator)?;
        let coordination = req.coordination.unwrap_or_default();
        let certify = check_certify("certify", req.certify, coordination)?;
        Ok(PlanInput {
            min_separation,
            ids,
            starts,
            types,
            targets,
            history: past,
            horizon,
            estimator,
            coordination,
            objective,
            observed: req.observed.unwrap_or_default(),
            explain: req.explain.unwrap_or(false),
            joint,
            certify,
        })
    }
}
