//! Sensor policies: local baselines and the planner in its configurations.

use std::fmt;

use rand::RngExt;
use serde::{Deserialize, Serialize};
use vigil::coordination::{Coordination, Objective};
use vigil::geometry::Point;
use vigil::planner::{EstimatorKind, Observed};
use vigil::scenario::{Cell, FovSpec, Scenario};
use vigil::search::{MOVES, step_displacements};
use vigil::separation::too_close;

/// How the sensors move.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Policy {
    /// Never move.
    Stationary,
    /// A uniform legal move each step.
    Random,
    /// A-CMOMMT-style local force control (attraction to observed targets,
    /// repulsion from nearby sensors).
    LocalForce,
    /// Paper estimator, no coordination (Table 1's 'b' rows).
    PaperUncoordinated,
    /// Paper estimator, priority coordination (Table 1's 'a' rows).
    Paper,
    /// Exact estimator, priority coordination.
    Exact,
    /// Exact estimator, iterated coordination.
    ExactIterated,
    /// Exact estimator, joint coordination: iterated, then restarts until
    /// the plan's certified gap reaches its target or the time budget (the
    /// server's defaults) runs out. Experiments run it only when named.
    ExactJoint,
    /// Exact, iterated, with every target in the zone reported: a reference
    /// ceiling, not something a real system can run.
    Clairvoyant,
    /// Exact estimator, iterated coordination, maximising first detections
    /// (the intrusion objective): each target not yet detected counts once.
    ExactIntrusion,
    /// Exact estimator, iterated coordination, planned through a learning
    /// session (`learn_rates: true`) whatever `--session` says: the server
    /// learns the sources' rates from the detections (each with its
    /// target's id) and plans with the posterior means. Experiments run it
    /// only when named.
    ExactLearn,
}

/// The policies the experiments run by default, in report order: every
/// policy but [`Policy::ExactJoint`] and [`Policy::ExactLearn`]. Joint
/// plans take up to their time budget each, several times an iterated
/// plan, so a grid of every policy would take several times as long; a
/// learning session precomputes its scenario again as its rates move. Each
/// is run by naming it (`--policy exact-joint`, `--policy exact-learn`),
/// after these in an experiment's rows.
pub const ALL_POLICIES: [Policy; 9] = [
    Policy::Paper,
    Policy::PaperUncoordinated,
    Policy::Exact,
    Policy::ExactIterated,
    Policy::Clairvoyant,
    Policy::LocalForce,
    Policy::Random,
    Policy::Stationary,
    Policy::ExactIntrusion,
];

/// How a planner policy calls the planner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlannerSettings {
    /// Estimator.
    pub estimator: EstimatorKind,
    /// Coordination.
    pub coordination: Coordination,
    /// What the reported targets cover.
    pub observed: Observed,
    /// What the plans maximise.
    pub objective: Objective,
}

impl Policy {
    /// The planner configuration, or `None` for a local policy.
    pub fn planner(self) -> Option<PlannerSettings> {
        use Coordination as C;
        use EstimatorKind as E;
        let (estimator, coordination, observed) = match self {
            Policy::Stationary | Policy::Random | Policy::LocalForce => return None,
            Policy::PaperUncoordinated => (E::Paper, C::None, Observed::Sensors),
            Policy::Paper => (E::Paper, C::Priority, Observed::Sensors),
            Policy::Exact => (E::Exact, C::Priority, Observed::Sensors),
            Policy::ExactIterated => (E::Exact, C::Iterated, Observed::Sensors),
            Policy::ExactJoint => (E::Exact, C::Joint, Observed::Sensors),
            Policy::Clairvoyant => (E::Exact, C::Iterated, Observed::Zone),
            Policy::ExactIntrusion => (E::Exact, C::Iterated, Observed::Sensors),
            Policy::ExactLearn => (E::Exact, C::Iterated, Observed::Sensors),
        };
        let objective = if self == Policy::ExactIntrusion {
            Objective::FirstDetections
        } else {
            Objective::Detections
        };
        Some(PlannerSettings {
            estimator,
            coordination,
            observed,
            objective,
        })
    }

    /// The policy plans through a session that learns the sources' rates
    /// (`learn_rates: true`), whether or not the run plans through
    /// sessions otherwise.
    pub fn learns_rates(self) -> bool {
        self == Policy::ExactLearn
    }

    /// The policy's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Policy::Stationary => "stationary",
            Policy::Random => "random",
            Policy::LocalForce => "local-force",
            Policy::PaperUncoordinated => "paper-uncoordinated",
            Policy::Paper => "paper",
            Policy::Exact => "exact",
            Policy::ExactIterated => "exact-iterated",
            Policy::ExactJoint => "exact-joint",
            Policy::Clairvoyant => "clairvoyant",
            Policy::ExactIntrusion => "exact-intrusion",
            Policy::ExactLearn => "exact-learn",
        }
    }
}

impl fmt::Display for Policy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The legal moves from `c` of a sensor of speed `speed`: the cells within
/// `speed` king moves through free cells (on the lattice, not blocked), in
/// the planner's tie order ([`step_displacements`]: stay first). At speed 1
/// on an open lattice these are the nine of [`MOVES`] that stay on it.
pub fn legal_moves(s: &Scenario, c: Cell, ty: usize) -> Vec<Cell> {
    let speed = s.types[ty].speed;
    let m = speed as i32;
    let w = (2 * m + 1) as usize;
    let at = |dc: i32, dr: i32| ((dr + m) as usize) * w + (dc + m) as usize;
    // Breadth-first search in the (2m+1)² window around c.
    let mut reach = vec![false; w * w];
    reach[at(0, 0)] = true;
    let mut frontier = vec![(0, 0)];
    for _ in 0..speed {
        let mut next = Vec::new();
        for &(c0, r0) in &frontier {
            for &(dc, dr) in &MOVES[1..] {
                let (nc, nr) = (c0 + dc, r0 + dr);
                let cell = Cell {
                    col: c.col + nc,
                    row: c.row + nr,
                };
                if nc.abs() <= m && nr.abs() <= m && !reach[at(nc, nr)] && s.is_free(ty, cell) {
                    reach[at(nc, nr)] = true;
                    next.push((nc, nr));
                }
            }
        }
        frontier = next;
    }
    step_displacements(speed)
        .iter()
        .filter(|&&(dc, dr)| reach[at(dc, dr)])
        .map(|&(dc, dr)| Cell {
            col: c.col + dc,
            row: c.row + dr,
        })
        .collect()
}

/// A uniform legal move of a sensor of speed `speed`.
pub fn random_move(s: &Scenario, c: Cell, ty: usize, rng: &mut impl rand::Rng) -> Cell {
    let moves = legal_moves(s, c, ty);
    moves[rng.random_range(0..moves.len())]
}

/// The minimum separation rule for the local policies: the cells the
/// sensors take when each intended to move from `current[i]` to
/// `intended[i]` and no two may end the step closer than `d` cells
/// (Chebyshev distance, [`too_close`]); `types[i]` gives sensor `i`'s
/// speed.
///
/// The sensors are resolved one at a time, in sensor order, each against
/// the cells already chosen by the sensors before it (the local policies
/// have no ranking of their own, and a fixed order makes the outcome
/// reproducible). Sensor `i` takes, in order of preference:
/// 1. its intended cell, if it is not too close to any chosen cell;
/// 2. else its current cell (it stays), if that is allowed;
/// 3. else the allowed cell among its [`legal_moves`] nearest its intended
///    cell (Euclidean distance between cells; ties go to the first in
///    `legal_moves`' order);
/// 4. else, cornered, its intended cell anyway: the rule is kept wherever
///    it can be, never at the cost of an illegal move.
///
/// With `d = 0` (no rule) this is `intended` unchanged. The intents are
/// computed (and any random draws made) before the rule applies, so the
/// rule never changes what a policy draws.
pub fn keep_apart(
    s: &Scenario,
    current: &[Cell],
    intended: &[Cell],
    types: &[usize],
    d: usize,
) -> Vec<Cell> {
    if d == 0 {
        return intended.to_vec();
    }
    let mut chosen: Vec<Cell> = Vec::with_capacity(intended.len());
    for ((&here, &want), &ty) in current.iter().zip(intended).zip(types) {
        let allowed = |c: Cell| !chosen.iter().any(|&o| too_close(c, o, d));
        let cell = if allowed(want) {
            want
        } else if allowed(here) {
            here
        } else {
            // Squared distances in cells are exact integers: no float ties.
            let dist2 = |c: Cell| {
                let (dc, dr) = ((c.col - want.col) as i64, (c.row - want.row) as i64);
                dc * dc + dr * dr
            };
            let mut best: Option<(i64, Cell)> = None;
            for c in legal_moves(s, here, ty) {
                if allowed(c) && best.is_none_or(|(b, _)| dist2(c) < b) {
                    best = Some((dist2(c), c));
                }
            }
            best.map_or(want, |(_, c)| c)
        };
        chosen.push(cell);
    }
    chosen
}

/// Constants of the local force law.
pub mod force {
    /// Weight of the attraction to each observed target.
    pub const ATTRACTION: f64 = 1.0;
    /// Weight of the repulsion from each nearby sensor, at zero distance.
    pub const REPULSION: f64 = 2.0;
    /// Sensors repel within this many field-of-view half widths (two half
    /// widths: the fields of view touch).
    pub const REPULSION_RANGE: f64 = 2.0;
    /// Below this net force the sensor stays.
    pub const DEADBAND: f64 = 0.25;
}

/// Local force control after Parker's A-CMOMMT (2002), on the lattice:
/// - attraction: a unit vector towards each target inside the sensor's own
///   field of view, times [`force::ATTRACTION`] (so a sensor keeps its
///   targets in view and drifts toward where they cluster);
/// - repulsion: for each other sensor closer than `REPULSION_RANGE`
///   half widths, a unit vector away from it times
///   `REPULSION·(1 − d/range)` (so fields of view spread out).
///
/// Each sensor reads its own type's field of view. The sensor takes the
/// legal move (within its speed, through free cells) whose direction best
/// aligns with the net force (the move maximising `force·move/|move|`), or stays when the force
/// is below [`force::DEADBAND`] or no move points along it.
pub fn local_force_move(
    s: &Scenario,
    me: usize,
    sensors: &[Cell],
    types: &[usize],
    observed: &[Point],
) -> Cell {
    let here = sensors[me];
    let p = s.centre(here);
    let ty = &s.types[types[me]];
    let half = match ty.fov {
        FovSpec::Square { half_width } => half_width,
        FovSpec::Circle { radius } => radius,
    };
    let region = s.fov_region_of(types[me], here);
    let (mut fx, mut fy) = (0.0, 0.0);
    for t in observed.iter().filter(|&&t| region.contains(t)) {
        let (dx, dy) = (t.x - p.x, t.y - p.y);
        let d = dx.hypot(dy);
        if d > 1e-9 {
            fx += force::ATTRACTION * dx / d;
            fy += force::ATTRACTION * dy / d;
        }
    }
    let range = force::REPULSION_RANGE * half;
    for (j, &other) in sensors.iter().enumerate() {
        if j == me {
            continue;
        }
        let q = s.centre(other);
        let (dx, dy) = (p.x - q.x, p.y - q.y);
        let d = dx.hypot(dy);
        if d < range {
            // Co-located sensors push apart along a fixed, per-pair direction.
            let (ux, uy) = if d > 1e-9 {
                (dx / d, dy / d)
            } else {
                let a = (me as f64 - j as f64) * 2.399;
                (a.cos(), a.sin())
            };
            let w = force::REPULSION * (1.0 - d / range);
            fx += w * ux;
            fy += w * uy;
        }
    }
    if fx.hypot(fy) < force::DEADBAND {
        return here;
    }
    let mut best = here;
    let mut best_score = 0.0;
    for n in legal_moves(s, here, types[me]) {
        let (dc, dr) = ((n.col - here.col) as f64, (n.row - here.row) as f64);
        let len = dc.hypot(dr);
        if len == 0.0 {
            continue;
        }
        let score = (fx * dc + fy * dr) / len;
        if score > best_score + 1e-12 {
            best_score = score;
            best = n;
        }
    }
    best
}
