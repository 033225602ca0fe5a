//! Estimators of `n̂(k,t)`: the expected number of targets a sensor at cell
//! `k` detects at step `t` (1 ≤ t ≤ T), given what the sensors report now.
//!
//! Both answer the same question through [`Estimator::value`] (one cell) and
//! [`Estimator::fill`] (every cell a sensor can reach at a step), optionally
//! leaving out what lies inside `excluded` regions (the fields of view of
//! other sensors at the same step), which is what coordination needs.
//!
//! - [`PaperEstimator`]: equations (1) and (2) of Krishna, Hexmoor and Sogani.
//! - [`ExactEstimator`]: the conditional expectation under the model, by
//!   interval arithmetic along rays from each source.

mod elementary;
mod exact;
mod paper;

pub use elementary::ElementaryGrid;
pub use exact::{ExactEstimator, RAYS_PER_PI, RAYS_PER_PI_SQUARE, SourceRays};
pub use paper::PaperEstimator;

use crate::geometry::{Point, Region};
use crate::scenario::{Cell, Scenario};
use crate::search::ValueGrid;

/// A target as reported: position now (step 0) and velocity per step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// Position at step 0.
    pub pos: Point,
    /// Displacement per step.
    pub vel: Point,
}

impl Target {
    /// Straight-line position at step `t`.
    #[inline]
    pub fn at(&self, t: usize) -> Point {
        Point::new(
            self.pos.x + self.vel.x * t as f64,
            self.pos.y + self.vel.y * t as f64,
        )
    }
}

/// A source of expected detections for the search.
pub trait Estimator: Sync {
    /// The scenario estimated.
    fn scenario(&self) -> &Scenario;

    /// `n̂` for `sensor` (its index in the request) at cell `k` and step `t`,
    /// counting only targets outside every region of `excluded`.
    fn value(&self, sensor: usize, k: Cell, t: usize, excluded: &[Region]) -> f64;

    /// Sets `grid`'s values at step `t` for every on-lattice cell within `t`
    /// moves of `start` (the sensor's start), as [`Estimator::value`] would.
    fn fill(
        &self,
        sensor: usize,
        start: Cell,
        t: usize,
        excluded: &[Region],
        grid: &mut ValueGrid,
    ) {
        for_reach(self.scenario(), start, t, |dc, dr, k| {
            grid.set(t, dc, dr, self.value(sensor, k, t, excluded));
        });
    }

    /// True when the total over several sensors does not depend on the order
    /// in which their exclusions are applied (so a sensor's marginal against
    /// all the others is its contribution to the total).
    fn order_independent(&self) -> bool;
}

/// Calls `f(dc, dr, cell)` for every on-lattice cell within `t` moves of `start`.
pub(crate) fn for_reach(s: &Scenario, start: Cell, t: usize, mut f: impl FnMut(i32, i32, Cell)) {
    let ti = t as i32;
    for dr in -ti..=ti {
        for dc in -ti..=ti {
            let k = Cell {
                col: start.col + dc,
                row: start.row + dr,
            };
            if s.on_lattice(k) {
                f(dc, dr, k);
            }
        }
    }
}
