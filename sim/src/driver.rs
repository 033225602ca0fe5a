//! The simulated world and the step loop of one run.
//!
//! Each step: observe (the targets inside any sensor's field of view now) →
//! ask the policy for moves → move every sensor at most one cell → advance
//! the targets one step → count. The targets come from
//! [`vigil::world::World`] driven by an RNG of their own, seeded from the
//! run's seed, so every policy sees the same target stream for the same seed.

use std::collections::{HashMap, HashSet, VecDeque};

use rand::{SeedableRng, rngs::StdRng};
use vigil::geometry::Point;
use vigil::planner::{Id, PlanRequest, PlanResponse, PositionIn, SensorIn, TargetIn};
use vigil::scenario::{Cell, Scenario};
use vigil::world::World;

use crate::metrics::StepCount;
use crate::policy::{Policy, local_force_move, random_move};

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
/// enough rows, each sensor at the centre of its share of the zone.
pub fn grid_starts(s: &Scenario, n: usize) -> Vec<Cell> {
    let cols = (n as f64).sqrt().ceil().max(1.0) as usize;
    let rows = n.div_ceil(cols);
    (0..n)
        .map(|i| {
            let (c, r) = (i % cols, i / cols);
            s.snap(Point::new(
                (c as f64 + 0.5) * s.width / cols as f64,
                (r as f64 + 0.5) * s.height / rows as f64,
            ))
        })
        .collect()
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
    /// Sensors' cells now.
    pub sensors: Vec<Cell>,
    /// Sensors' cells 1, 2, … steps ago (most recent first).
    pub history: VecDeque<Vec<Cell>>,
    history_len: usize,
    /// Step number now.
    pub step: usize,
    /// Last step each target was seen by some sensor.
    last_seen: HashMap<u64, usize>,
    /// Targets first seen in the zone at or after `window_start`.
    entered: HashSet<u64>,
    /// Of those, the ones detected at least once.
    detected: HashSet<u64>,
    in_zone_before: HashSet<u64>,
    window_start: Option<usize>,
    /// Each sensor's cell after every step, for pictures.
    pub trace: Vec<Vec<Cell>>,
}

impl Sim {
    /// A run: targets from `seed`, sensors placed by `start` (random starts
    /// and the random policy use a separate RNG, so they never disturb the
    /// target stream). `history_len` steps of history are kept.
    pub fn new(
        scenario: Scenario,
        sensors: usize,
        start: Start,
        seed: u64,
        history_len: usize,
    ) -> Self {
        let world_rng = StdRng::seed_from_u64(seed);
        let mut sensor_rng = StdRng::seed_from_u64(seed ^ 0x5e45_0125_u64.rotate_left(17));
        let starts = match start {
            Start::Grid => grid_starts(&scenario, sensors),
            Start::Random => {
                use rand::RngExt;
                (0..sensors)
                    .map(|_| Cell {
                        col: sensor_rng.random_range(0..scenario.cols),
                        row: sensor_rng.random_range(0..scenario.rows),
                    })
                    .collect()
            }
        };
        Sim {
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
            entered: HashSet::new(),
            detected: HashSet::new(),
            in_zone_before: HashSet::new(),
            window_start: None,
        }
    }

    /// Starts counting `detected_once` from now.
    pub fn start_window(&mut self) {
        self.window_start = Some(self.step);
        self.in_zone_before = self.world.in_zone(&self.scenario).map(|t| t.id).collect();
    }

    /// The fraction of the targets that entered since [`Sim::start_window`]
    /// that were detected at least once.
    pub fn detected_once(&self) -> f64 {
        if self.entered.is_empty() {
            return 0.0;
        }
        self.entered
            .iter()
            .filter(|id| self.detected.contains(id))
            .count() as f64
            / self.entered.len() as f64
    }

    /// How many sensors see each target in the zone now, by target id.
    fn detections(&self) -> Vec<(u64, Point, usize)> {
        let fovs: Vec<_> = self
            .sensors
            .iter()
            .map(|&c| self.scenario.fov_region(c))
            .collect();
        self.world
            .in_zone(&self.scenario)
            .map(|t| {
                (
                    t.id,
                    t.pos,
                    fovs.iter().filter(|r| r.contains(t.pos)).count(),
                )
            })
            .collect()
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
        let sensors = self
            .sensors
            .iter()
            .enumerate()
            .map(|(i, &c)| SensorIn {
                id: Id::Number(i.into()),
                x: centre(c).x,
                y: centre(c).y,
                sensor_type: None,
            })
            .collect();
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
                    .map(|&c| PositionIn::at(centre(c).x, centre(c).y))
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
            explain: None,
        }
    }

    /// Next cells of a local policy.
    pub fn local_moves(&mut self, policy: Policy) -> Vec<Cell> {
        let s = &self.scenario;
        match policy {
            Policy::Random => {
                let rng = &mut self.sensor_rng;
                self.sensors
                    .iter()
                    .map(|&c| random_move(s, c, rng))
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
                    .map(|i| local_force_move(s, i, &self.sensors, &seen))
                    .collect()
            }
            _ => self.sensors.clone(),
        }
    }

    /// The first cell of each sensor's path in a plan, checked to be a legal
    /// move (the planner's contract).
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
            .zip(&self.sensors)
            .map(|(p, &c)| {
                let first = p.path.first().ok_or("an empty path")?;
                let next = Cell {
                    col: first.col,
                    row: first.row,
                };
                let legal = (next.col - c.col).abs() <= 1
                    && (next.row - c.row).abs() <= 1
                    && self.scenario.on_lattice(next);
                legal
                    .then_some(next)
                    .ok_or_else(|| format!("illegal move {c:?} → {next:?}"))
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
        let detections = self.detections();
        let mut count = StepCount {
            in_zone: detections.len(),
            ..StepCount::default()
        };
        for &(id, _, n) in &detections {
            if n > 0 {
                count.detected += 1;
                if let Some(slot) = count.by_exactly.get_mut(n - 1) {
                    *slot += 1;
                }
            }
            if self.window_start.is_some() && !self.in_zone_before.contains(&id) {
                self.entered.insert(id);
                if n > 0 {
                    self.detected.insert(id);
                }
            }
        }
        count
    }
}
