//! The simulated world and the step loop of one run.
//!
//! Each step: observe (the targets the sensors detected now) → ask the
//! policy for moves → move every sensor within its speed through free cells
//! → advance the targets one step → detect and count. The targets come from
//! [`vigil::world::World`] driven by an RNG of their own, seeded from the
//! run's seed, so every policy sees the same target stream for the same
//! seed. A sensor detects a target inside its field of view with its type's
//! `p_detect`; those Bernoulli draws come from a third stream of their own
//! (and are skipped when `p_detect` is 1), so they never disturb the
//! targets either.
//!
//! A minimum separation ([`Sim::min_separation`], the scenario's by
//! default) keeps the sensors apart: planner policies send it with every
//! plan request, and the local policies' moves go through
//! [`keep_apart`].

use std::collections::{HashMap, HashSet, VecDeque};

use rand::{SeedableRng, rngs::StdRng};
use vigil::coordination::{Bound, Coordination, Objective};
use vigil::geometry::Point;
use vigil::planner::{
    EstimatorKind, Id, PlanRequest, PlanResponse, PositionIn, SensorIn, TargetIn,
};
use vigil::scenario::{Cell, Scenario};
use vigil::session::{SessionSettings, StepRequest};
use vigil::world::World;

use crate::metrics::{Entries, StepCount};
use crate::policy::{Policy, keep_apart, legal_moves, local_force_move, random_move};

/// A plan's certificate, checked against the planner's contract: with the
/// exact estimator a [`Bound`] no lower than the plan's own expected
/// detections, with `gap = (upper − value) / upper` in `[0, 1]`; with the
/// paper estimator, whose total is not a coverage, none. A joint plan with
/// the exact estimator also says what its rounds did. Returns the bound.
pub fn checked_bound(plan: &PlanResponse) -> Result<Option<Bound>, String> {
    let exact = plan.estimator == EstimatorKind::Exact;
    match plan.bound {
        None if exact => Err("an exact plan without its certificate".into()),
        Some(_) if !exact => Err("a paper plan with a certificate".into()),
        None => Ok(None),
        Some(b) => {
            let value = plan.expected_detections;
            // Rounding may not put the bound below the plan: the server
            // raises it to the plan's value then.
            if b.upper.is_nan() || b.upper < value {
                return Err(format!("bound {} below the plan's {value}", b.upper));
            }
            let gap = if b.upper > 0.0 {
                (b.upper - value) / b.upper
            } else {
                0.0
            };
            if !(0.0..=1.0).contains(&b.gap) || (b.gap - gap).abs() > 1e-9 {
                return Err(format!(
                    "gap {} for bound {} and value {value} (expected {gap})",
                    b.gap, b.upper
                ));
            }
            if plan.coordination == Coordination::Joint && plan.joint.is_none() {
                return Err("a joint exact plan without its report".into());
            }
            Ok(Some(b))
        }
    }
}

/// Where the sensors start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Start {
    /// Spread over the zone on a near-square grid of cells.
    Grid,
    /// Uniformly random cells (from the sensors' RNG).
    Random,
}

/// Steps the slowest target needs to cross the zone's diagonal: the default
/// warm-up, after which the zone holds its stationary population.
pub fn default_warmup(s: &Scenario) -> usize {
    (s.width.hypot(s.height) / s.min_speed()).ceil() as usize
}

/// Near-square grid positions for `n` sensors: `cols = ⌈√n⌉` columns and
/// enough rows, each sensor at the centre of its share of the zone, moved
/// to the nearest cell free for its type `types[i]` when that one is
/// blocked ([`nearest_free`]).
pub fn grid_starts(s: &Scenario, types: &[usize]) -> Vec<Cell> {
    let n = types.len();
    let cols = (n as f64).sqrt().ceil().max(1.0) as usize;
    let rows = n.div_ceil(cols);
    (0..n)
        .map(|i| {
            let (c, r) = (i % cols, i / cols);
            nearest_free(
                s,
                types[i],
                s.snap(Point::new(
                    (c as f64 + 0.5) * s.width / cols as f64,
                    (r as f64 + 0.5) * s.height / rows as f64,
                )),
            )
        })
        .collect()
}

/// `c` if it is free for a sensor of type `ty`, else the first such free
/// cell on the nearest Chebyshev ring around it, rings scanned in the
/// planner's tie order (by row, then column, from the south-west). `c`
/// itself when no cell is free.
pub fn nearest_free(s: &Scenario, ty: usize, c: Cell) -> Cell {
    if s.is_free(ty, c) {
        return c;
    }
    for k in 1..s.cols.max(s.rows) {
        for dr in -k..=k {
            for dc in -k..=k {
                if dc.abs().max(dr.abs()) != k {
                    continue;
                }
                let n = Cell {
                    col: c.col + dc,
                    row: c.row + dr,
                };
                if s.is_free(ty, n) {
                    return n;
                }
            }
        }
    }
    c
}

/// Sensor types for `n` sensors from a fleet such as `drone:4,robot:6`
/// (the counts must add up to `n`): the first four `drone`, the next six
/// `robot`. `None` gives every sensor the type `default`.
pub fn fleet_types(s: &Scenario, fleet: Option<&str>, n: usize) -> Result<Vec<usize>, String> {
    let Some(fleet) = fleet else {
        return Ok(vec![0; n]);
    };
    let mut types = Vec::with_capacity(n);
    for part in fleet.split(',') {
        let (name, count) = part
            .split_once(':')
            .ok_or_else(|| format!("fleet entry {part:?} is not NAME:COUNT"))?;
        let ty = s.type_index(name.trim()).ok_or_else(|| {
            let known: Vec<&str> = s.types.iter().map(|t| t.name.as_str()).collect();
            format!(
                "the scenario has no sensor type {:?} (it has {})",
                name.trim(),
                known.join(", ")
            )
        })?;
        let count: usize = count
            .trim()
            .parse()
            .map_err(|_| format!("fleet entry {part:?}: {count:?} is not a count"))?;
        types.extend(std::iter::repeat_n(ty, count));
    }
    if types.len() != n {
        return Err(format!(
            "the fleet {fleet:?} has {} sensors, the run {n}",
            types.len()
        ));
    }
    Ok(types)
}

/// The number of sensors of a fleet such as `drone:4,robot:6`, if it parses.
pub fn fleet_size(fleet: &str) -> Option<usize> {
    fleet
        .split(',')
        .map(|part| part.split_once(':')?.1.trim().parse::<usize>().ok())
        .sum()
}

/// What the sensors know of a target in the zone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TargetStatus {
    /// Inside some sensor's field of view now.
    Detected,
    /// Not in view now, but seen within the history window: the planner
    /// policies report it (a track).
    Tracked,
    /// Seen once, longer ago than the history window: no longer reported.
    Lost,
    /// Never seen by any sensor.
    Unseen,
}

/// One run's world, sensors and tracks.
pub struct Sim {
    /// The scenario, validated locally.
    pub scenario: Scenario,
    /// The targets.
    pub world: World,
    world_rng: StdRng,
    sensor_rng: StdRng,
    detect_rng: StdRng,
    /// Sensors' cells now.
    pub sensors: Vec<Cell>,
    /// Sensors' types (indices into the scenario's `types`).
    pub types: Vec<usize>,
    /// The targets in the zone now, with how many sensors detected each.
    now: Vec<(u64, Point, usize)>,
    /// Sensors' cells 1, 2, … steps ago (most recent first).
    pub history: VecDeque<Vec<Cell>>,
    history_len: usize,
    /// Step number now.
    pub step: usize,
    /// Last step each target was seen by some sensor.
    last_seen: HashMap<u64, usize>,
    /// Targets that entered the zone after `window_start` (not in it then,
    /// in it at the end of a later step), each with its entry step: the
    /// first step at whose end it was in the zone.
    entered: HashMap<u64, usize>,
    /// Of those, the ones detected at least once, each with the step at
    /// which some sensor first detected it.
    detected: HashMap<u64, usize>,
    in_zone_before: HashSet<u64>,
    window_start: Option<usize>,
    /// Each sensor's cell after every step, for pictures.
    pub trace: Vec<Vec<Cell>>,
    /// Minimum separation between sensors, cells; `None`: the scenario's.
    /// Sent with plan requests when set, and kept by the local policies
    /// ([`Sim::local_moves`]).
    pub min_separation: Option<usize>,
    /// Plans come from a model told no obstacles: a planned move the world
    /// forbids becomes the legal move nearest to it instead of an error.
    pub blind: bool,
}

impl Sim {
    /// A run of `sensors` sensors of the type `default`: see
    /// [`Sim::with_types`].
    pub fn new(
        scenario: Scenario,
        sensors: usize,
        start: Start,
        seed: u64,
        history_len: usize,
    ) -> Self {
        Self::with_types(scenario, vec![0; sensors], start, seed, history_len)
    }

    /// A run: targets from `seed`, one sensor per entry of `types` (its
    /// type), placed by `start` on free cells (random starts and the random
    /// policy use a separate RNG, so they never disturb the target stream).
    /// `history_len` steps of history are kept.
    pub fn with_types(
        scenario: Scenario,
        types: Vec<usize>,
        start: Start,
        seed: u64,
        history_len: usize,
    ) -> Self {
        let world_rng = StdRng::seed_from_u64(seed);
        let mut sensor_rng = StdRng::seed_from_u64(seed ^ 0x5e45_0125_u64.rotate_left(17));
        let detect_rng = StdRng::seed_from_u64(seed ^ 0xde7e_c7ed_u64.rotate_left(29));
        let starts = match start {
            Start::Grid => grid_starts(&scenario, &types),
            Start::Random => {
                use rand::RngExt;
                types
                    .iter()
                    .map(|&ty| {
                        loop {
                            let c = Cell {
                                col: sensor_rng.random_range(0..scenario.cols),
                                row: sensor_rng.random_range(0..scenario.rows),
                            };
                            if scenario.is_free(ty, c) {
                                break c;
                            }
                        }
                    })
                    .collect()
            }
        };
        Sim {
            types,
            detect_rng,
            now: Vec::new(),
            world: World::empty(&scenario),
            scenario,
            world_rng,
            sensor_rng,
            trace: starts.iter().map(|&c| vec![c]).collect(),
            sensors: starts,
            history: VecDeque::new(),
            history_len,
            step: 0,
            last_seen: HashMap::new(),
            entered: HashMap::new(),
            detected: HashMap::new(),
            in_zone_before: HashSet::new(),
            window_start: None,
            min_separation: None,
            blind: false,
        }
    }

    /// Replaces the (still empty) world by one drawn from its stationary
    /// distribution ([`World::stationary`]): targets emitted over a window
    /// long enough for any to have crossed the zone, as if the sources had
    /// always emitted. Drawn from the targets' own RNG, so every policy of
    /// a seed still sees the same targets. Call it before the first step.
    pub fn start_stationary(&mut self) {
        self.world = World::stationary(&self.scenario, &mut self.world_rng);
        self.sense();
    }

    /// Starts counting the targets that enter the zone from now
    /// ([`Sim::entries`]); those in it now are never counted.
    pub fn start_window(&mut self) {
        self.window_start = Some(self.step);
        self.in_zone_before = self.world.in_zone(&self.scenario).map(|t| t.id).collect();
    }

    /// The fraction of the targets that entered since [`Sim::start_window`]
    /// that were detected at least once ([`Entries::detected_once`]).
    pub fn detected_once(&self) -> f64 {
        self.entries().detected_once()
    }

    /// Of the targets that entered since [`Sim::start_window`] and were
    /// detected, the mean steps from entry to first detection
    /// ([`Entries::delay`]).
    pub fn delay(&self) -> Option<f64> {
        self.entries().delay()
    }

    /// Of the targets that entered since [`Sim::start_window`] and have
    /// left the zone, the fraction never detected ([`Entries::missed`]).
    pub fn missed(&self) -> Option<f64> {
        self.entries().missed()
    }

    /// The counts of the targets that entered the zone since
    /// [`Sim::start_window`]: how many, how many were detected and after
    /// how many steps, how many have left and how many of those were never
    /// detected. A target is counted from the end of the first step at
    /// which it is in the zone (its entry step); one that has entered is
    /// gone once it is out of the zone (a straight path leaves the zone
    /// once), so those not in the zone now are the ones that left.
    pub fn entries(&self) -> Entries {
        let in_zone: HashSet<u64> = self.now.iter().map(|&(id, _, _)| id).collect();
        let mut e = Entries {
            entered: self.entered.len(),
            detected: self.detected.len(),
            ..Entries::default()
        };
        for (id, &entry) in &self.entered {
            let first = self.detected.get(id);
            if let Some(&first) = first {
                e.delay_steps += first - entry;
            }
            if !in_zone.contains(id) {
                e.left += 1;
                e.left_undetected += usize::from(first.is_none());
            }
        }
        e
    }

    /// The targets in the zone now, each with its id, position and how many
    /// sensors detected it this step (drawn once per step by `sense`).
    pub fn detections(&self) -> Vec<(u64, Point, usize)> {
        self.now.clone()
    }

    /// Draws this step's detections: each sensor detects each target inside
    /// its field of view that it sees (no obstacle on the sight line, for a
    /// ground type) with its type's `p_detect` (no draw when it is 1).
    fn sense(&mut self) {
        let s = &self.scenario;
        let looks: Vec<_> = self
            .sensors
            .iter()
            .zip(&self.types)
            .map(|(&c, &ty)| s.look(ty, c))
            .collect();
        let rng = &mut self.detect_rng;
        self.now = self
            .world
            .in_zone(s)
            .map(|t| {
                let n = looks
                    .iter()
                    .filter(|l| {
                        use rand::RngExt;
                        s.detects(l, t.pos)
                            && (l.p_detect >= 1.0 || rng.random::<f64>() < l.p_detect)
                    })
                    .count();
                (t.id, t.pos, n)
            })
            .collect();
    }

    /// Every target in the zone now, with its position and what the sensors
    /// know of it (see [`TargetStatus`]).
    pub fn target_states(&self) -> Vec<(Point, TargetStatus)> {
        let oldest = self.step.saturating_sub(self.history_len);
        self.detections()
            .into_iter()
            .map(|(id, pos, n)| {
                let status = if n > 0 {
                    TargetStatus::Detected
                } else {
                    match self.last_seen.get(&id) {
                        Some(&when) if when >= oldest => TargetStatus::Tracked,
                        Some(_) => TargetStatus::Lost,
                        None => TargetStatus::Unseen,
                    }
                };
                (pos, status)
            })
            .collect()
    }

    /// Records which targets the sensors see now.
    pub fn observe(&mut self) {
        for (id, _, n) in self.detections() {
            if n > 0 {
                self.last_seen.insert(id, self.step);
            }
        }
    }

    /// The plan request of a planner policy: the sensors now, their
    /// positions over the history window, and every target seen within the
    /// window and still in the zone, with its true position and velocity (a
    /// perfect tracker). The clairvoyant policy reports every target in the
    /// zone. Tracks older than the window are left out: the estimator would
    /// count them twice, as known and among the unseen.
    pub fn plan_request(&self, policy: Policy, horizon: Option<usize>) -> PlanRequest {
        let s = &self.scenario;
        let settings = policy.planner();
        let centre = |c: Cell| s.centre(c);
        let sensors = self.plan_request_sensors();
        let clairvoyant = policy == Policy::Clairvoyant;
        let oldest = self.step.saturating_sub(self.history_len);
        let targets = self
            .world
            .in_zone(s)
            .filter(|t| {
                clairvoyant
                    || self
                        .last_seen
                        .get(&t.id)
                        .is_some_and(|&when| when >= oldest)
            })
            .map(|t| TargetIn {
                id: Some(Id::Number(t.id.into())),
                x: t.pos.x,
                y: t.pos.y,
                vx: t.vel.x,
                vy: t.vel.y,
            })
            .collect();
        let history = self
            .history
            .iter()
            .map(|step| {
                step.iter()
                    .enumerate()
                    .map(|(i, &c)| PositionIn {
                        sensor_type: self.type_name(i),
                        ..PositionIn::at(centre(c).x, centre(c).y)
                    })
                    .collect()
            })
            .collect::<Vec<_>>();
        PlanRequest {
            sensors,
            targets,
            history: (!history.is_empty()).then_some(history),
            horizon: horizon.map(Into::into),
            estimator: settings.map(|p| p.estimator),
            coordination: settings.map(|p| p.coordination),
            observed: settings.map(|p| p.observed),
            // Only when not the default, as `min_separation` below.
            objective: settings
                .map(|p| p.objective)
                .filter(|&o| o != Objective::Detections),
            explain: None,
            // Only when set: requests otherwise stay as they were, and the
            // server applies the scenario's.
            min_separation: self.min_separation.map(Into::into),
            gap_target: None,
            budget_ms: None,
            certify: None,
        }
    }

    /// The targets detected this step (by any sensor), with their ids,
    /// positions and velocities: what a session step reports. The
    /// clairvoyant policy reports every target in the zone.
    pub fn detected_targets(&self, policy: Policy) -> Vec<TargetIn> {
        let clairvoyant = policy == Policy::Clairvoyant;
        let detected: HashSet<u64> = self
            .now
            .iter()
            .filter(|&&(_, _, n)| n > 0)
            .map(|&(id, _, _)| id)
            .collect();
        self.world
            .in_zone(&self.scenario)
            .filter(|t| clairvoyant || detected.contains(&t.id))
            .map(|t| TargetIn {
                id: Some(Id::Number(t.id.into())),
                x: t.pos.x,
                y: t.pos.y,
                vx: t.vel.x,
                vy: t.vel.y,
            })
            .collect()
    }

    /// The session step of a planner policy: the sensors now (as in
    /// [`Sim::plan_request`]) and [`Sim::detected_targets`]. The session
    /// keeps the history and the tracks, so its plan is the plan of
    /// [`Sim::plan_request`] when every step of the run, warm-up included,
    /// went through it.
    pub fn step_request(&self, policy: Policy, horizon: Option<usize>) -> StepRequest {
        StepRequest {
            sensors: self.plan_request_sensors(),
            detections: self.detected_targets(policy),
            horizon: horizon.map(Into::into),
            ..StepRequest::default()
        }
    }

    /// The settings of a session that plans for `policy` with `history`
    /// steps of history, as [`Sim::plan_request`] does; a policy that
    /// learns the rates ([`Policy::learns_rates`]) asks for
    /// `learn_rates: true` (its steps' detections carry their targets' ids,
    /// as every session step's do).
    pub fn session_settings(
        &self,
        policy: Policy,
        horizon: Option<usize>,
        history: usize,
    ) -> SessionSettings {
        let settings = policy.planner();
        SessionSettings {
            horizon: horizon.map(Into::into),
            estimator: settings.map(|p| p.estimator),
            coordination: settings.map(|p| p.coordination),
            observed: settings.map(|p| p.observed),
            objective: settings
                .map(|p| p.objective)
                .filter(|&o| o != Objective::Detections),
            min_separation: self.min_separation.map(Into::into),
            history_steps: Some(history.into()),
            certify: None,
            // Only when learning: other sessions' settings stay as they were.
            learn_rates: policy.learns_rates().then_some(true),
            // The server's defaults for the rest (the simulator's tracks
            // are exact: no tracker tolerances).
            ..SessionSettings::default()
        }
    }

    fn plan_request_sensors(&self) -> Vec<SensorIn> {
        let s = &self.scenario;
        self.sensors
            .iter()
            .enumerate()
            .map(|(i, &c)| SensorIn {
                id: Id::Number(i.into()),
                x: s.centre(c).x,
                y: s.centre(c).y,
                sensor_type: self.type_name(i),
            })
            .collect()
    }

    /// The minimum separation in force, cells: [`Sim::min_separation`] or
    /// else the scenario's (0: no rule).
    pub fn separation(&self) -> usize {
        self.min_separation.unwrap_or(self.scenario.min_separation)
    }

    /// The name of sensor `i`'s type for a request; `None` for `default`
    /// (requests then look as they did before sensor types existed).
    fn type_name(&self, i: usize) -> Option<String> {
        let ty = self.types[i];
        (ty != 0).then(|| self.scenario.types[ty].name.clone())
    }

    /// Next cells of a local policy: each sensor's intended move, then
    /// the minimum separation ([`Sim::separation`]) applied by
    /// [`keep_apart`] (with none, the intended moves unchanged). A
    /// stationary sensor intends to stay, so it moves only to get clear of
    /// a sensor before it.
    pub fn local_moves(&mut self, policy: Policy) -> Vec<Cell> {
        let intended = self.intended_moves(policy);
        keep_apart(
            &self.scenario,
            &self.sensors,
            &intended,
            &self.types,
            self.separation(),
        )
    }

    /// What each sensor of a local policy would do alone: the random
    /// policy's draws, the local force law's moves, or staying.
    fn intended_moves(&mut self, policy: Policy) -> Vec<Cell> {
        let s = &self.scenario;
        match policy {
            Policy::Random => {
                let rng = &mut self.sensor_rng;
                self.sensors
                    .iter()
                    .zip(&self.types)
                    .map(|(&c, &ty)| random_move(s, c, ty, rng))
                    .collect()
            }
            Policy::LocalForce => {
                let seen: Vec<Point> = self
                    .detections()
                    .into_iter()
                    .filter(|d| d.2 > 0)
                    .map(|d| d.1)
                    .collect();
                (0..self.sensors.len())
                    .map(|i| local_force_move(s, i, &self.sensors, &self.types, &seen))
                    .collect()
            }
            _ => self.sensors.clone(),
        }
    }

    /// The first cell of each sensor's path in a plan, checked to be a legal
    /// move for its type's speed through free cells (the planner's
    /// contract).
    pub fn moves_from_plan(&self, plan: &PlanResponse) -> Result<Vec<Cell>, String> {
        if plan.plans.len() != self.sensors.len() {
            return Err(format!(
                "{} plans for {} sensors",
                plan.plans.len(),
                self.sensors.len()
            ));
        }
        plan.plans
            .iter()
            .zip(self.sensors.iter().zip(&self.types))
            .map(|(p, (&c, &ty))| {
                let first = p.path.first().ok_or("an empty path")?;
                let next = Cell {
                    col: first.col,
                    row: first.row,
                };
                let legal = legal_moves(&self.scenario, c, ty);
                if legal.contains(&next) {
                    return Ok(next);
                }
                if self.blind {
                    // The first legal move at the least distance, in the
                    // planner's tie order (`legal` is never empty: staying
                    // is legal).
                    let d = |m: &Cell| (m.col - next.col).pow(2) + (m.row - next.row).pow(2);
                    return Ok(legal.iter().copied().min_by_key(d).unwrap_or(c));
                }
                Err(format!("illegal move {c:?} → {next:?}"))
            })
            .collect()
    }

    /// Moves the sensors, advances the targets one step and counts.
    pub fn advance(&mut self, next: Vec<Cell>) -> StepCount {
        let before = std::mem::replace(&mut self.sensors, next);
        self.history.push_front(before);
        self.history.truncate(self.history_len);
        for (trace, &c) in self.trace.iter_mut().zip(&self.sensors) {
            trace.push(c);
        }
        self.world.step(&self.scenario, &mut self.world_rng);
        self.step += 1;
        self.sense();
        let detections = self.detections();
        let mut occupied = self.sensors.clone();
        occupied.sort_unstable();
        occupied.dedup();
        let mut count = StepCount {
            in_zone: detections.len(),
            cells: occupied.len(),
            ..StepCount::default()
        };
        for &(id, _, n) in &detections {
            if n > 0 {
                count.detected += 1;
                // `observe` records this step's detections after it.
                if !self.last_seen.contains_key(&id) {
                    count.first_detected += 1;
                }
                match count.by_exactly.get_mut(n - 1) {
                    Some(slot) => *slot += 1,
                    None => count.four_plus += 1,
                }
            }
            if self.window_start.is_some() && !self.in_zone_before.contains(&id) {
                // The first step each is seen in the zone, and detected,
                // is the one kept.
                self.entered.entry(id).or_insert(self.step);
                if n > 0 {
                    self.detected.entry(id).or_insert(self.step);
                }
            }
        }
        count
    }
}

#[cfg(test)]
mod tests {
    use vigil::scenario::paper_spec;
    use vigil::world::SimTarget;

    use super::*;

    /// A target at `(x, y)` flying `(vx, vy)` per step.
    fn target(s: &Scenario, id: u64, (x, y): (f64, f64), (vx, vy): (f64, f64)) -> SimTarget {
        let pos = Point::new(x, y);
        SimTarget {
            id,
            pos,
            vel: Point::new(vx, vy),
            entered: s.in_zone(pos),
            source: 0,
            flown: 0.0,
            stop: f64::INFINITY,
        }
    }

    /// The bookkeeping behind `detected_once`, `delay` and `missed` on a
    /// world made by hand: `paper-v10`'s zone (300 m square, 10 m cells, a
    /// 60 m square field of view) with its sources silenced, one sensor
    /// held at cell (5, 15), which sees x ∈ [25, 85], y ∈ [125, 185], and
    /// four targets whose steps in and out of the zone and the view are
    /// worked out below.
    #[test]
    fn entries_follow_entry_first_detection_and_departure() {
        let mut spec = paper_spec(10.0);
        for src in &mut spec.sources {
            src.rate = 0.0;
        }
        let s = Scenario::new(spec).expect("valid");
        let mut sim = Sim::new(s.clone(), 1, Start::Grid, 1, 0);
        sim.sensors = vec![Cell { col: 5, row: 15 }];
        sim.world.targets = vec![
            // In at step 3 (x = 8), in view at step 5 (x = 28), out at
            // step 33 (x = 308).
            target(&s, 0, (-22.0, 150.0), (10.0, 0.0)),
            // In at step 1 (y = 50) far east of the view, out at step 4.
            target(&s, 1, (290.0, -50.0), (0.0, 100.0)),
            // In at step 1 (x = 0.5), in view at step 14 (x = 26.5), still
            // in the zone at the end (x = 78.5).
            target(&s, 2, (-1.5, 160.0), (2.0, 0.0)),
            // In the zone, and in view, when the window starts: never
            // counted, though detected at every step.
            target(&s, 3, (40.0, 150.0), (0.5, 0.0)),
        ];
        sim.start_window();
        let mut after = vec![Entries::default()];
        let mut first = vec![0];
        // Held in view since before the window: detected before step 1.
        sim.sense();
        sim.observe();
        for _ in 0..40 {
            let stay = sim.sensors.clone();
            let count = sim.advance(stay);
            assert!(count.detected >= 1, "step {}: the held target", sim.step);
            sim.observe();
            after.push(sim.entries());
            first.push(count.first_detected);
        }
        // Detected for the first time: the first target at step 5, the
        // third at step 14, and nothing else ever.
        for (step, &n) in first.iter().enumerate() {
            assert_eq!(n, usize::from(step == 5 || step == 14), "step {step}");
        }
        let e = |entered, detected, delay_steps, left, left_undetected| Entries {
            entered,
            detected,
            delay_steps,
            left,
            left_undetected,
        };
        assert_eq!(after[1], e(2, 0, 0, 0, 0));
        assert_eq!(after[2], e(2, 0, 0, 0, 0));
        assert_eq!(after[3], e(3, 0, 0, 0, 0));
        // The second target left unseen: missed, and no delay yet.
        assert_eq!(after[4], e(3, 0, 0, 1, 1));
        assert_eq!((after[4].delay(), after[4].missed()), (None, Some(1.0)));
        // The first, in at step 3, first detected at step 5: delay 2.
        assert_eq!(after[5], e(3, 1, 2, 1, 1));
        assert_eq!(after[5].delay(), Some(2.0));
        assert_eq!(after[13], e(3, 1, 2, 1, 1));
        assert_eq!(after[14], e(3, 2, 15, 1, 1));
        assert_eq!(after[32], e(3, 2, 15, 1, 1));
        // The first leaves, detected: not missed.
        assert_eq!(after[33], e(3, 2, 15, 2, 1));
        assert_eq!(after[40], e(3, 2, 15, 2, 1));
        assert_eq!(sim.detected_once(), 2.0 / 3.0);
        assert_eq!(sim.delay(), Some(7.5));
        assert_eq!(sim.missed(), Some(0.5));
        // `missed` counts only the targets that left, so it may exceed the
        // fraction never detected (the third target, detected and still in
        // the zone, counts only there); the counts cannot: every missed
        // target is an undetected one.
        assert!(sim.missed() > Some(1.0 - sim.detected_once()));
        let last = after[40];
        assert!(last.left_undetected <= last.entered - last.detected);
    }
}
