//! What the looks of a ground sensor at each cell of its reach cannot
//! see, worked out once per plan (see `sighted`).

use std::sync::OnceLock;

use crate::geometry::Rect;
use crate::obstacle::Sight;
use crate::scenario::{Cell, Look, Scenario};

/// What a ground look at a cell cannot see, and a box holding the part of
/// its field of view that it misses (`None` when it sees all of it).
pub(super) type CellSight = Option<(Sight, Option<Rect>)>;

/// The [`CellSight`] of `look` in `scenario`.
pub(super) fn cell_sight(scenario: &Scenario, look: &Look) -> CellSight {
    let sight = scenario.sight(look)?;
    let hidden = sight.hidden_within(&look.region.rect);
    Some((sight, hidden))
}

/// One sensor's [`CellSight`]s over the cells it may reach, each worked
/// out on first use: a plan asks the same cells at every step and pass.
pub(super) struct SightCache {
    start: Cell,
    extent: i32,
    cells: Vec<OnceLock<CellSight>>,
}

impl SightCache {
    /// The cache of a sensor at `start` that moves at most `extent` cells.
    pub(super) fn new(start: Cell, extent: i32) -> Self {
        // A negative extent (an elevated sensor's): no cell.
        let side = (2 * extent + 1).max(0) as usize;
        SightCache {
            start,
            extent,
            cells: (0..side * side).map(|_| OnceLock::new()).collect(),
        }
    }

    /// `k`'s slot, if it is in reach.
    pub(super) fn slot(&self, k: Cell) -> Option<&OnceLock<CellSight>> {
        let (dc, dr) = (k.col - self.start.col, k.row - self.start.row);
        if dc.abs() > self.extent || dr.abs() > self.extent {
            return None;
        }
        let side = 2 * self.extent + 1;
        self.cells
            .get(((dr + self.extent) * side + dc + self.extent) as usize)
    }
}
