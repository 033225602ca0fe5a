//! A window of observations, validated once: each step's looks, and each
//! target's first detection.

use std::collections::{HashMap, HashSet, VecDeque};

use super::posterior::Prior;
use super::traceback::Tolerance;
use super::wire::{DetectionIn, FitRequest, FitTolerance, PriorKind};
use crate::geometry::{Point, Region};
use crate::limits::{
    DEFAULT_FIT_DISTANCE_TOLERANCE, DEFAULT_FIT_SPEED_TOLERANCE, MAX_FIT_DETECTIONS, MAX_FIT_STEPS,
    MAX_SENSORS,
};
use crate::planner::{Id, SensorIn, place, step_looks};
use crate::scenario::{Look, Scenario, ValidationError};

/// A target's first detection in a window (or a session's life).
#[derive(Debug, Clone, PartialEq)]
pub struct FirstDetection {
    /// Its track id.
    pub id: Id,
    /// Where it was detected.
    pub pos: Point,
    /// Its velocity, per step.
    pub vel: Point,
}

/// The tolerances of a fit, resolved against a scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// Of the traceback.
    pub traceback: Tolerance,
    /// How far outside every look a detection may lie, zone units.
    pub look: f64,
}

impl Tolerances {
    /// The tolerances asked for, with the defaults for the others.
    pub fn new(s: &Scenario, spec: Option<&FitTolerance>) -> Result<Self, ValidationError> {
        let spec = spec.copied().unwrap_or_default();
        let scale = s.width.max(s.height);
        let check = |field: &str, v: Option<f64>, default: f64| match v {
            None => Ok(default),
            Some(v) if v.is_finite() && v >= 0.0 => Ok(v),
            Some(v) => Err(ValidationError::new(
                format!("tolerance.{field}"),
                format!("must be finite and ≥ 0, got {v}"),
            )),
        };
        Ok(Tolerances {
            traceback: Tolerance {
                distance: check(
                    "traceback",
                    spec.traceback,
                    DEFAULT_FIT_DISTANCE_TOLERANCE * scale,
                )?,
                speed: check("speed", spec.speed, DEFAULT_FIT_SPEED_TOLERANCE)?,
            },
            look: check("look", spec.look, DEFAULT_FIT_DISTANCE_TOLERANCE * scale)?,
        })
    }
}

/// The track ids seen so far, with where each was last detected: each
/// target counts once, and an id whose detections jump further than a
/// target can fly is refused. Remembers at most `capacity` ids, forgetting
/// the oldest.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrackBook {
    last: HashMap<String, (u64, Point)>,
    order: VecDeque<String>,
    capacity: usize,
}

impl TrackBook {
    /// An empty book.
    pub fn new(capacity: usize) -> Self {
        TrackBook {
            last: HashMap::new(),
            order: VecDeque::new(),
            capacity,
        }
    }

    /// Ids remembered.
    pub fn len(&self) -> usize {
        self.last.len()
    }

    /// True when no id is remembered.
    pub fn is_empty(&self) -> bool {
        self.last.is_empty()
    }

    /// Validates step `step`'s sensors and detections (`field` names the
    /// step in errors, e.g. `steps[3]`) without changing the book, and
    /// returns its looks and an [`Observed`] step to [`TrackBook::commit`].
    /// With `whole_zone` the detections cover the zone (a session's
    /// `observed: zone`): the step's one look is the zone, certain.
    #[allow(clippy::too_many_arguments)]
    pub fn observe(
        &self,
        s: &Scenario,
        field: &str,
        step: u64,
        sensors: &[SensorIn],
        detections: &[DetectionIn],
        tol: &Tolerances,
        whole_zone: bool,
    ) -> Result<Observed, ValidationError> {
        // `steps[3].sensors`, or `sensors` for a session's step.
        let field = if field.is_empty() {
            String::new()
        } else {
            format!("{field}.")
        };
        if sensors.len() > MAX_SENSORS {
            return Err(ValidationError::new(
                format!("{field}sensors"),
                format!("at most {MAX_SENSORS} sensors, got {}", sensors.len()),
            ));
        }
        if detections.len() > MAX_FIT_DETECTIONS {
            return Err(ValidationError::new(
                format!("{field}detections"),
                format!(
                    "at most {MAX_FIT_DETECTIONS} detections, got {}",
                    detections.len()
                ),
            ));
        }
        let mut ids = HashSet::new();
        let mut places = Vec::with_capacity(sensors.len());
        for (i, sensor) in sensors.iter().enumerate() {
            if !ids.insert(sensor.id.key()) {
                return Err(ValidationError::new(
                    format!("{field}sensors[{i}].id"),
                    "duplicate sensor id",
                ));
            }
            let name = || format!("{field}sensors[{i}]");
            places.push(place(
                s,
                &name,
                sensor.x,
                sensor.y,
                sensor.sensor_type.as_deref(),
            )?);
        }
        let looks = if whole_zone {
            vec![Look::certain(s.zone_region())]
        } else {
            // As in a plan: a look each, repeats of certain ones left out.
            step_looks(s, places.into_iter())
        };
        let fastest = s.max_speed() * (1.0 + tol.traceback.speed);
        let mut seen = HashSet::new();
        let mut updates = Vec::new();
        let mut firsts = Vec::new();
        for (i, d) in detections.iter().enumerate() {
            let name = || format!("{field}detections[{i}]");
            for (axis, v) in [("x", d.x), ("y", d.y), ("vx", d.vx), ("vy", d.vy)] {
                if !v.is_finite() {
                    return Err(ValidationError::new(
                        format!("{}.{axis}", name()),
                        "must be finite",
                    ));
                }
            }
            let key = d.id.key();
            if !seen.insert(key.clone()) {
                return Err(ValidationError::new(
                    format!("{}.id", name()),
                    format!("track id {} is detected twice at this step", d.id),
                ));
            }
            let q = Point::new(d.x, d.y);
            if !looks.iter().any(|l| near(&l.region, q, tol.look)) {
                return Err(ValidationError::new(
                    name(),
                    format!(
                        "({}, {}) lies outside every field of view of this step: none of its looks can have detected it",
                        d.x, d.y
                    ),
                ));
            }
            if !looks
                .iter()
                .any(|l| near(&l.region, q, tol.look) && in_sight(s, l, q, tol.look))
            {
                return Err(ValidationError::new(
                    name(),
                    format!(
                        "({}, {}) lies behind an obstacle from every look of this step whose field of view holds it: none of its looks can have detected it",
                        d.x, d.y
                    ),
                ));
            }
            match self.last.get(&key) {
                Some(&(then, p)) => {
                    let steps = step.saturating_sub(then).max(1) as f64;
                    let gap = (q.x - p.x).hypot(q.y - p.y);
                    let reach = fastest * steps + 2.0 * tol.traceback.distance;
                    if gap > reach {
                        return Err(ValidationError::new(
                            format!("{}.id", name()),
                            format!(
                                "track id {} jumps {gap:.3} from where it was {steps} step(s) before; the fastest target flies {reach:.3} in that time",
                                d.id
                            ),
                        ));
                    }
                }
                None => firsts.push(FirstDetection {
                    id: d.id.clone(),
                    pos: q,
                    vel: Point::new(d.vx, d.vy),
                }),
            }
            updates.push((key, q));
        }
        Ok(Observed {
            step,
            looks,
            firsts,
            updates,
        })
    }

    /// Records a step that [`TrackBook::observe`] accepted.
    pub fn commit(&mut self, observed: &mut Observed) {
        for (key, q) in observed.updates.drain(..) {
            if self.last.insert(key.clone(), (observed.step, q)).is_none() {
                self.order.push_back(key);
                if self.order.len() > self.capacity
                    && let Some(old) = self.order.pop_front()
                {
                    self.last.remove(&old);
                }
            }
        }
    }
}

/// One step's observations, validated.
#[derive(Debug, Clone)]
pub struct Observed {
    step: u64,
    /// The looks taken (distinct).
    pub looks: Vec<Look>,
    /// The detections of targets not detected before.
    pub firsts: Vec<FirstDetection>,
    updates: Vec<(String, Point)>,
}

/// True when `q` lies within `tol` of the region.
/// True when `look` sees `q` (an elevated look, or a clear sight line
/// from a ground look's viewpoint), or a point within `tol` of it in one
/// of the axes' directions: a detection reported on a shadow's edge is
/// not refused for rounding.
fn in_sight(s: &Scenario, look: &Look, q: Point, tol: f64) -> bool {
    let Some(from) = look.from else {
        return true;
    };
    let near_by = [(0.0, 0.0), (tol, 0.0), (-tol, 0.0), (0.0, tol), (0.0, -tol)];
    near_by
        .iter()
        .any(|&(dx, dy)| s.obstacles.clear(from, Point::new(q.x + dx, q.y + dy)))
}

fn near(region: &Region, q: Point, tol: f64) -> bool {
    let r = &region.rect;
    let dx = (r.x0 - q.x).max(0.0).max(q.x - r.x1);
    let dy = (r.y0 - q.y).max(0.0).max(q.y - r.y1);
    dx.hypot(dy) <= tol
        && region
            .disk
            .is_none_or(|d| (q.x - d.c.x).hypot(q.y - d.c.y) <= d.r + tol)
}

/// A fit request, validated against its scenario.
#[derive(Debug, Clone)]
pub struct FitWindow {
    /// Each step's looks, oldest first.
    pub looks: Vec<Vec<Look>>,
    /// Each detected target's first detection, in order.
    pub firsts: Vec<FirstDetection>,
    /// The prior.
    pub prior: Prior,
    /// Register the fitted spec.
    pub register: bool,
    /// The tolerances.
    pub tolerances: Tolerances,
}

impl FitWindow {
    /// Validates `req` against `s`.
    pub fn new(s: &Scenario, req: &FitRequest) -> Result<Self, ValidationError> {
        if req.steps.is_empty() {
            return Err(ValidationError::new(
                "steps",
                "at least one step: an empty window says nothing about the rates",
            ));
        }
        if req.steps.len() > MAX_FIT_STEPS {
            return Err(ValidationError::new(
                "steps",
                format!("at most {MAX_FIT_STEPS} steps, got {}", req.steps.len()),
            ));
        }
        let tolerances = Tolerances::new(s, req.tolerance.as_ref())?;
        let mut book = TrackBook::new(usize::MAX);
        let mut looks = Vec::with_capacity(req.steps.len());
        let mut firsts = Vec::new();
        let mut number: Option<u64> = None;
        for (i, step) in req.steps.iter().enumerate() {
            let field = format!("steps[{i}]");
            if let Some(n) = &step.step {
                // The document says int64.
                let n = n.get().filter(|&n| n <= i64::MAX as u64).ok_or_else(|| {
                    ValidationError::new(
                        format!("{field}.step"),
                        format!("must be a whole number in 0..={}", i64::MAX),
                    )
                })?;
                if let Some(prev) = number
                    && Some(n) != prev.checked_add(1)
                {
                    return Err(ValidationError::new(
                        format!("{field}.step"),
                        format!(
                            "steps must be consecutive, oldest first: step {n} follows step {prev}"
                        ),
                    ));
                }
                number = Some(n);
            } else if let Some(prev) = number {
                number = prev.checked_add(1);
            }
            let mut observed = book.observe(
                s,
                &field,
                i as u64,
                &step.sensors,
                &step.detections,
                &tolerances,
                false,
            )?;
            book.commit(&mut observed);
            looks.push(observed.looks);
            firsts.extend(observed.firsts);
        }
        Ok(FitWindow {
            looks,
            firsts,
            prior: match req.prior.unwrap_or_default() {
                PriorKind::Scenario => Prior::Scenario,
                PriorKind::Flat => Prior::Flat,
            },
            register: req.register.unwrap_or(false),
            tolerances,
        })
    }
}
