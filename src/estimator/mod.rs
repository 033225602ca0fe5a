//! Estimators of `n̂(k,t)`: the expected number of targets a sensor at cell
//! `k` detects at step `t` (1 ≤ t ≤ T), given what the sensors report now.
//!
//! Both answer the same question through [`Estimator::value`] (one cell) and
//! [`Estimator::fill`] (every cell a sensor can reach at a step), optionally
//! leaving out what `excluded` looks detect (the other sensors' at the same
//! step), which is what coordination needs.
//!
//! - [`PaperEstimator`]: equations (1) and (2) of Krishna, Hexmoor and Sogani.
//! - [`ExactEstimator`]: the conditional expectation under the model, by
//!   interval arithmetic along rays from each source.

mod elementary;
mod exact;
mod paper;

pub use elementary::{ElementaryGrid, MAX_SMALL_GRID};
pub use exact::{
    BLOCKS_FROM, Carry, CarryUse, ExactEstimator, FirstDetections, INDEX_CROSSINGS_PER_CELL,
    MIN_INDEX_CROSSINGS, ONE_WINDOW_RECTANGLES, PathCover, Precomputed, RAYS_PER_PI,
    RAYS_PER_PI_SQUARE, SightIndex, Situation, SourceRays,
};
pub use paper::PaperEstimator;

use crate::geometry::Point;
use crate::scenario::{Cell, Look, Scenario};
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

/// What the exact objective counts at one step, as weights on disjoint
/// pieces that every field of view of a sensor either holds whole or not
/// at all: the elementary rectangles (see [`ElementaryGrid`]) of a block
/// that holds every field of view the sensors can reach, each with its
/// expected unseen targets, and the known targets, one each. A sensor of
/// type `ty` at cell `k` expects `p_detect` times the weight of the pieces
/// in [`Elements::block`] and of the known targets `F_k` holds.
#[derive(Debug, Clone)]
pub struct Elements<'a> {
    grid: &'a ElementaryGrid,
    /// First column of rectangles of the block.
    pub a0: usize,
    /// First row of rectangles of the block.
    pub b0: usize,
    /// Columns of the block.
    pub na: usize,
    /// Rows of the block.
    pub nb: usize,
    /// Per rectangle of the block, row-major: its expected unseen targets
    /// (0 where no reachable field of view lies).
    pub mass: Vec<f64>,
    /// The known targets in the zone at the step.
    pub known: Vec<Point>,
}

impl Elements<'_> {
    /// The rectangles `[a0, a1) × [b0, b1)` (relative to the block) that
    /// make up the field of view `fov_slot` (a scenario's `fovs` index) at
    /// `k`, for a cell some sensor can reach.
    pub fn block(&self, fov_slot: usize, k: Cell) -> (usize, usize, usize, usize) {
        let (a0, a1, b0, b1) = self.grid.span(fov_slot, k);
        (a0 - self.a0, a1 - self.a0, b0 - self.b0, b1 - self.b0)
    }
}

/// A source of expected detections for the search.
pub trait Estimator: Sync {
    /// The scenario estimated.
    fn scenario(&self) -> &Scenario;

    /// `n̂` for `sensor` (its index in the request) at cell `k` and step `t`:
    /// the expected targets it detects there (its `p_detect` times those in
    /// its field of view), counting each target only with the probability
    /// that every look of `excluded` misses it.
    fn value(&self, sensor: usize, k: Cell, t: usize, excluded: &[Look]) -> f64;

    /// Sets `grid`'s values at step `t` for every cell the sensor can reach
    /// by then from `start` (the sensor's start), as [`Estimator::value`]
    /// would.
    fn fill(&self, sensor: usize, start: Cell, t: usize, excluded: &[Look], grid: &mut ValueGrid) {
        grid.fill_step(t, |dc, dr| {
            self.scenario()
                .lattice_cell(start, dc, dr)
                .map(|k| self.value(sensor, k, t, excluded))
        });
    }

    /// The pieces the objective counts at step `t` (see [`Elements`]),
    /// when the estimator can list them (the exact estimator with square
    /// fields of view); `None` otherwise.
    fn elements(&self, _t: usize) -> Option<Elements<'_>> {
        None
    }

    /// True when the total over several sensors does not depend on the order
    /// in which their exclusions are applied (so a sensor's marginal against
    /// all the others is its contribution to the total).
    fn order_independent(&self) -> bool;
}
