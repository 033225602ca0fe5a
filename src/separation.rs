//! Sensors that keep apart: the minimum separation rule.
//!
//! With a minimum separation of `d` cells, two sensors break the rule at a
//! step when they end it at Chebyshev distance (the number of king moves
//! between their cells) less than `d`: with `d = 1` they may not share a
//! cell, with `d = 3` at least two cells lie between them along a row,
//! column or diagonal. `d = 0` is no rule. Only the cells the paths hold
//! after each step 1..=T count; the start (step 0) is where the sensors
//! are, not a choice.
//!
//! The rule is a hard constraint wherever it can be met: coordination fixes
//! paths in priority order, and each next sensor's search counts, for every
//! cell and step, the fixed paths it would be too close to
//! ([`mark_too_close`]), then minimises (violations, −value)
//! lexicographically (see [`crate::search`]). [`count`] recounts a finished
//! set of paths.
//!
//! ```
//! use vigil::scenario::Cell;
//! use vigil::separation::count;
//! let at = |col, row| Cell { col, row };
//! // Two sensors, two steps: 2 cells apart, then on one cell.
//! let paths = vec![vec![at(0, 0), at(1, 1)], vec![at(2, 0), at(1, 1)]];
//! let v = count(&paths, 3);
//! assert_eq!((v.per_sensor, v.pairs), (vec![2, 2], 2));
//! assert_eq!(count(&paths, 1).pairs, 1);
//! assert_eq!(count(&paths, 0).pairs, 0);
//! ```

use crate::scenario::Cell;
use crate::search::ValueGrid;

/// True when cells `a` and `b` are closer than `d` (Chebyshev distance,
/// cells); never for `d = 0`.
#[inline]
pub fn too_close(a: Cell, b: Cell, d: usize) -> bool {
    ((a.col - b.col)
        .unsigned_abs()
        .max((a.row - b.row).unsigned_abs()) as usize)
        < d
}

/// The rule's breaches in a set of paths.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Violations {
    /// Per path: the (step, other path) pairs at which it is too close.
    pub per_sensor: Vec<u32>,
    /// The (step, pair of paths) too close, each pair once per step: half
    /// the sum of `per_sensor`.
    pub pairs: u32,
}

/// Counts the breaches of separation `d` among `paths` (each the cells at
/// steps 1..=T; paths of different lengths are compared over the shorter).
pub fn count<P: AsRef<[Cell]>>(paths: &[P], d: usize) -> Violations {
    let mut per_sensor = vec![0u32; paths.len()];
    let mut pairs = 0;
    if d > 0 {
        for (i, a) in paths.iter().enumerate() {
            for (j, b) in paths.iter().enumerate().skip(i + 1) {
                let n = a
                    .as_ref()
                    .iter()
                    .zip(b.as_ref())
                    .filter(|&(&p, &q)| too_close(p, q, d))
                    .count() as u32;
                per_sensor[i] += n;
                per_sensor[j] += n;
                pairs += n;
            }
        }
    }
    Violations { per_sensor, pairs }
}

/// Adds to `grid` (the search of a sensor starting at `start`) one
/// violation at step `t` for every cell closer than `d` to the cell another
/// sensor's fixed path holds at step `t`, for each path of `others` (cells
/// at steps 1..=T). Nothing for `d = 0`.
pub fn mark_too_close<'a>(
    grid: &mut ValueGrid,
    start: Cell,
    d: usize,
    others: impl IntoIterator<Item = &'a [Cell]>,
) {
    if d == 0 {
        return;
    }
    let r = d as i32 - 1;
    for path in others {
        for (t, q) in path.iter().enumerate().take(grid.horizon()) {
            let (dc, dr) = (q.col - start.col, q.row - start.row);
            grid.add_violations(t + 1, dc - r..=dc + r, dr - r..=dr + r);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::best_path;

    #[test]
    fn chebyshev_distance_below_d() {
        let at = |col, row| Cell { col, row };
        assert!(too_close(at(3, 3), at(3, 3), 1));
        assert!(!too_close(at(3, 3), at(4, 3), 1));
        assert!(too_close(at(3, 3), at(5, 1), 3));
        assert!(!too_close(at(3, 3), at(6, 1), 3));
        assert!(!too_close(at(3, 3), at(3, 3), 0));
    }

    #[test]
    fn marked_cells_are_avoided_when_possible() {
        // Speed 1, T = 1; every cell worth 1 but the east one worth 5; a
        // sensor fixed two cells east makes the east column too close at
        // separation 2, so the search takes the best of the rest.
        let mut g = ValueGrid::new(1);
        for dr in -1..=1 {
            for dc in -1..=1 {
                g.set(1, dc, dr, if (dc, dr) == (1, 0) { 5.0 } else { 1.0 });
            }
        }
        g.set(1, -1, 0, 2.0);
        let start = Cell { col: 10, row: 10 };
        let other = [Cell { col: 12, row: 10 }];
        mark_too_close(&mut g, start, 2, [&other[..]]);
        assert_eq!(g.violations(1, 1, 0), 1);
        assert_eq!(g.violations(1, 0, 0), 0);
        let best = best_path(&g);
        assert_eq!(
            (best.moves, best.value, best.violations),
            (vec![(-1, 0)], 2.0, 0)
        );
    }
}
