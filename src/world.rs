//! A simulation of the target process itself, independent of the estimators:
//! each source emits targets as a Poisson process in continuous time with a
//! uniform takeoff angle over its cone (a half-plane for the paper's
//! sources) and a speed drawn once from its speed distribution; targets fly
//! straight, exist while inside the closed zone, and are gone once they
//! leave it or once their flight enters a building's interior.
//!
//! Used by the Monte Carlo checks of the statistics and the estimators, and
//! by the simulation client.

use rand::RngExt;
use rand_distr::{Distribution, Poisson};

use crate::geometry::Point;
use crate::scenario::Scenario;

/// A target in flight (it may not have reached the zone yet).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimTarget {
    /// Unique id, in order of emission.
    pub id: u64,
    /// Position now.
    pub pos: Point,
    /// Displacement per step.
    pub vel: Point,
    /// Has been inside the zone.
    pub entered: bool,
    /// Index of its source.
    pub source: usize,
    /// Distance flown from its source.
    pub flown: f64,
    /// Distance from its source at which a building ends its flight
    /// (`+∞` when none does).
    pub stop: f64,
}

/// The targets of a scenario at an integer time.
#[derive(Debug, Clone)]
pub struct World {
    /// Targets in flight: inside the zone, or still on their way to it.
    pub targets: Vec<SimTarget>,
    next_id: u64,
    /// How far from a source a target can still meet the zone.
    reach: Vec<f64>,
}

impl World {
    /// An empty world (no target emitted yet).
    pub fn empty(s: &Scenario) -> Self {
        let reach = s
            .sources
            .iter()
            .map(|src| {
                [
                    (0.0, 0.0),
                    (s.width, 0.0),
                    (0.0, s.height),
                    (s.width, s.height),
                ]
                .iter()
                .map(|&(x, y)| (x - src.pos.x).hypot(y - src.pos.y))
                .fold(0.0, f64::max)
            })
            .collect();
        World {
            targets: Vec::new(),
            next_id: 0,
            reach,
        }
    }

    /// A world drawn from the stationary distribution: targets emitted over
    /// a window long enough for any to have crossed the zone, as if the
    /// process had always run.
    pub fn stationary(s: &Scenario, rng: &mut impl rand::Rng) -> Self {
        let mut w = World::empty(s);
        for j in 0..s.sources.len() {
            let slowest = s
                .classes_of(j)
                .iter()
                .map(|c| c.speed)
                .fold(f64::INFINITY, f64::min);
            let window = w.reach[j] / slowest;
            w.emit(s, j, window, rng);
        }
        w
    }

    /// Emits source `j`'s targets of the last `window` steps (continuous
    /// emission times), placed where they are now.
    fn emit(&mut self, s: &Scenario, j: usize, window: f64, rng: &mut impl rand::Rng) {
        let src = &s.sources[j];
        let mean = src.rate * window;
        if mean <= 0.0 {
            return;
        }
        let count = match Poisson::new(mean) {
            Ok(p) => p.sample(rng) as u64,
            Err(_) => 0,
        };
        let classes = s.classes_of(j);
        let centre = 0.5 * (src.cone.0 + src.cone.1);
        for _ in 0..count {
            let age = rng.random::<f64>() * window;
            let alpha = centre + (rng.random::<f64>() - 0.5) * src.spread;
            let speed = if classes.len() == 1 {
                classes[0].speed
            } else {
                // A class with probability rate_c / rate (its weight).
                let mut x = rng.random::<f64>() * src.rate;
                let mut speed = classes[classes.len() - 1].speed;
                for c in classes {
                    if x < c.rate {
                        speed = c.speed;
                        break;
                    }
                    x -= c.rate;
                }
                speed
            };
            let u = src.direction(alpha);
            let dist = speed * age;
            let pos = Point::new(src.pos.x + u.x * dist, src.pos.y + u.y * dist);
            let mut t = SimTarget {
                id: self.next_id,
                pos,
                vel: Point::new(u.x * speed, u.y * speed),
                entered: false,
                source: j,
                flown: dist,
                stop: s.obstacles.stop(src.pos, u),
            };
            self.next_id += 1;
            // A target's history is known exactly: it entered if its path
            // from the source has met the zone already.
            t.entered = s.in_zone(pos) || has_crossed(s, src.pos, u, dist.min(t.stop));
            if self.alive(s, &t) {
                self.targets.push(t);
            }
        }
    }

    fn alive(&self, s: &Scenario, t: &SimTarget) -> bool {
        if t.flown >= t.stop {
            return false;
        }
        if s.in_zone(t.pos) {
            return true;
        }
        if t.entered {
            return false;
        }
        let src = s.sources[t.source].pos;
        (t.pos.x - src.x).hypot(t.pos.y - src.y) <= self.reach[t.source]
    }

    /// Advances one step: every target flies, those that left are removed,
    /// and each source emits its Poisson count for the step.
    pub fn step(&mut self, s: &Scenario, rng: &mut impl rand::Rng) {
        let mut targets = std::mem::take(&mut self.targets);
        for t in &mut targets {
            let before = t.pos;
            t.pos = Point::new(t.pos.x + t.vel.x, t.pos.y + t.vel.y);
            t.flown += t.vel.x.hypot(t.vel.y);
            // Entering the zone counts only before the flight's end.
            if t.flown >= t.stop {
                continue;
            }
            if !t.entered && (s.in_zone(t.pos) || segment_meets_zone(s, before, t.pos)) {
                t.entered = true;
            }
        }
        targets.retain(|t| self.alive(s, t));
        self.targets = targets;
        for j in 0..s.sources.len() {
            self.emit(s, j, 1.0, rng);
        }
    }

    /// Targets emitted so far (by every source, in the zone or not).
    pub fn emitted(&self) -> u64 {
        self.next_id
    }

    /// Targets inside the closed zone now.
    pub fn in_zone<'a>(&'a self, s: &'a Scenario) -> impl Iterator<Item = &'a SimTarget> + 'a {
        self.targets.iter().filter(move |t| s.in_zone(t.pos))
    }
}

/// True when the segment from `p` along `u` for `len` has met the zone.
fn has_crossed(s: &Scenario, p: Point, u: Point, len: f64) -> bool {
    segment_meets_zone(s, p, Point::new(p.x + u.x * len, p.y + u.y * len))
}

fn segment_meets_zone(s: &Scenario, a: Point, b: Point) -> bool {
    let d = Point::new(b.x - a.x, b.y - a.y);
    let inv = Point::new(1.0 / d.x, 1.0 / d.y);
    s.zone().ray(a, d, inv).is_some_and(|(t0, _)| t0 <= 1.0)
}
