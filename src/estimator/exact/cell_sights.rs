//! What the looks of a ground sensor at each cell of its reach cannot
//! see, and the unseen mass they miss there, worked out once per plan
//! (see `sighted`).

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

/// One value per cell of a sensor's reach (and per layer: a step, say),
/// each worked out on first use: a plan asks the same cells at every step
/// and in each of its searches.
pub(super) struct ReachCache<T> {
    start: Cell,
    extent: i32,
    layers: usize,
    cells: Vec<OnceLock<T>>,
}

/// One sensor's [`CellSight`]s over the cells it may reach.
pub(super) type SightCache = ReachCache<CellSight>;

impl<T> ReachCache<T> {
    /// The cache of a sensor at `start` that moves at most `extent` cells,
    /// with `layers` values per cell.
    pub(super) fn new(start: Cell, extent: i32, layers: usize) -> Self {
        // A negative extent (an elevated sensor's): no cell.
        let side = (2 * extent + 1).max(0) as usize;
        ReachCache {
            start,
            extent,
            layers,
            cells: (0..side * side * layers).map(|_| OnceLock::new()).collect(),
        }
    }

    /// `k`'s slot in `layer`, if `k` is in reach and `layer` below the
    /// cache's layers.
    pub(super) fn slot(&self, k: Cell, layer: usize) -> Option<&OnceLock<T>> {
        let (dc, dr) = (k.col - self.start.col, k.row - self.start.row);
        if dc.abs() > self.extent || dr.abs() > self.extent || layer >= self.layers {
            return None;
        }
        let side = (2 * self.extent + 1) as usize;
        let at = ((dr + self.extent) as usize * side + (dc + self.extent) as usize) * self.layers;
        self.cells.get(at + layer)
    }
}

/// What a plan keeps of one sensor's looks over its reach, with obstacles
/// (nothing for an elevated sensor, which sees its whole square).
pub(super) struct GroundReach {
    /// Their [`CellSight`]s, when the scenario has no sight index.
    pub(super) sights: Option<SightCache>,
    /// Per step of the horizon (layer `t − 1`), the unseen mass that they
    /// do not see before any exclusion: the same in every search.
    pub(super) hidden_unseen: ReachCache<f64>,
}
