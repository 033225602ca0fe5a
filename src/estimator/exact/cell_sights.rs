//! What the looks of a ground sensor at each cell of its reach cannot
//! see, the unseen mass they miss there, and what groups of excluded
//! looks that obstacles cut detect: worked out once per plan (see
//! `sighted`).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use super::windows::Window;
use crate::estimator::elementary::Block;
use crate::geometry::{Point, Rect};
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

/// What a group of cut looks detects at one step of each rectangle of the
/// block around their fields of view.
pub(super) struct CutDetection {
    block: Block,
    /// Row by row over `block`.
    detected: Vec<f64>,
}

impl CutDetection {
    /// What a group detects over `block`, row by row.
    pub(super) fn new(block: Block, detected: Vec<f64>) -> Self {
        Self { block, detected }
    }

    /// Takes what the group detects off each rectangle of `win` it shares.
    pub(super) fn take_from(&self, win: &mut Window) {
        let (a0, a1, b0, b1) = self.block;
        let (wa0, wb0, wna) = (win.a0, win.b0, win.na);
        let (lo_a, hi_a) = (a0.max(wa0), a1.min(wa0 + wna));
        let (lo_b, hi_b) = (b0.max(wb0), b1.min(wb0 + win.nb));
        if lo_a >= hi_a {
            return;
        }
        let unseen = win.unseen_mut();
        for b in lo_b..hi_b {
            let mine = &self.detected[(b - b0) * (a1 - a0)..][lo_a - a0..hi_a - a0];
            let theirs = &mut unseen[(b - wb0) * wna..][lo_a - wa0..hi_a - wa0];
            for (u, d) in theirs.iter_mut().zip(mine) {
                *u -= d;
            }
        }
    }
}

/// A plan's [`CutDetection`]s, by group of looks and step: each is asked
/// for by the fills of every sensor whose reach the group meets.
#[derive(Default)]
pub(super) struct CutDetections(Mutex<HashMap<CutKey, Arc<CutDetection>>>);

/// The looks of a group (each its field of view, detection probability
/// and viewpoint, by their bits, sorted) and a step.
pub(super) type CutKey = (Vec<[u64; 10]>, usize);

impl CutDetections {
    /// A look's field of view, detection probability and viewpoint, by
    /// their bits.
    pub(super) fn look_key(look: &Look) -> [u64; 10] {
        let nan = Point::new(f64::NAN, f64::NAN);
        let r = &look.region.rect;
        let from = look.from.unwrap_or(nan);
        let (c, radius) = look.region.disk.map_or((nan, f64::NAN), |d| (d.c, d.r));
        [
            r.x0,
            r.x1,
            r.y0,
            r.y1,
            c.x,
            c.y,
            radius,
            look.p_detect,
            from.x,
            from.y,
        ]
        .map(f64::to_bits)
    }

    pub(super) fn get(&self, key: &CutKey) -> Option<Arc<CutDetection>> {
        let kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        kept.get(key).cloned()
    }

    /// Keeps `value` under `key` unless another thread kept one first, and
    /// returns what is kept.
    pub(super) fn keep(&self, key: CutKey, value: CutDetection) -> Arc<CutDetection> {
        let mut kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        Arc::clone(kept.entry(key).or_insert_with(|| Arc::new(value)))
    }
}
