//! The best T-step path of one sensor on the 9-connected space-time lattice.
//!
//! The paper runs a depth-limited search over the `9^T` move sequences. The
//! value of a path is a sum of per-(cell, step) values, so dynamic
//! programming over (offset, step) finds the same optimum in
//! `O(T·(2T+1)²·9)`: `best[t][o] = v[t][o] + max over the 9 moves m of
//! best[t+1][o+m]`, then one forward pass picks the moves.
//!
//! Ties are broken deterministically: among optimal paths the one whose move
//! sequence comes first in [`MOVES`] order (stay first), compared move by
//! move from step 1. [`brute_force`] enumerates in the same order, so both
//! return the same path when sums are exact.
//!
//! ```
//! use vigil::search::{ValueGrid, best_path};
//! // T = 1: nine cells around the start; the north-east one is worth most.
//! let mut grid = ValueGrid::new(1);
//! for dr in -1..=1 { for dc in -1..=1 { grid.set(1, dc, dr, 1.0); } }
//! grid.set(1, 1, 1, 5.0);
//! let best = best_path(&grid);
//! assert_eq!(best.moves, vec![(1, 1)]);
//! assert_eq!(best.value, 5.0);
//! ```

/// The nine moves `(dc, dr)` of one step, in tie-breaking order.
pub const MOVES: [(i32, i32); 9] = [
    (0, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// Values of the cells a sensor can occupy, by step and offset from its
/// start. A missing value (`None`) marks a cell that is off the lattice.
#[derive(Debug, Clone, PartialEq)]
pub struct ValueGrid {
    horizon: usize,
    side: usize,
    values: Vec<Option<f64>>,
    free: Option<Vec<bool>>,
}

impl ValueGrid {
    /// An empty grid (every cell missing) for horizon `horizon ≥ 1`.
    pub fn new(horizon: usize) -> Self {
        let side = 2 * horizon + 1;
        Self {
            horizon,
            side,
            values: vec![None; horizon * side * side],
            free: None,
        }
    }

    /// TEMPORARY (speed 1).
    pub fn with_motion(horizon: usize, _speed: usize, free: impl Fn(i32, i32) -> bool) -> Self {
        let mut g = Self::new(horizon);
        g.free = Some(
            (0..g.side * g.side)
                .map(|i| {
                    let h = horizon as i32;
                    free((i % g.side) as i32 - h, (i / g.side) as i32 - h)
                })
                .collect(),
        );
        g
    }

    /// TEMPORARY.
    pub fn fill_step(&mut self, t: usize, mut f: impl FnMut(i32, i32) -> f64) {
        let ti = t as i32;
        for dr in -ti..=ti {
            for dc in -ti..=ti {
                let ok = self.free.as_ref().is_none_or(|fr| {
                    fr[((dr + self.horizon as i32) as usize) * self.side
                        + (dc + self.horizon as i32) as usize]
                });
                if ok {
                    let v = f(dc, dr);
                    self.set(t, dc, dr, v);
                }
            }
        }
    }

    /// The horizon T.
    pub fn horizon(&self) -> usize {
        self.horizon
    }

    fn slot(&self, t: usize, dc: i32, dr: i32) -> Option<usize> {
        let h = self.horizon as i32;
        if t == 0 || t > self.horizon || dc.abs() > t as i32 || dr.abs() > t as i32 {
            return None;
        }
        let (c, r) = ((dc + h) as usize, (dr + h) as usize);
        Some(((t - 1) * self.side + r) * self.side + c)
    }

    /// Sets the value of offset `(dc, dr)` at step `t` (1-based). Offsets
    /// farther than `t` from the start are unreachable and ignored.
    pub fn set(&mut self, t: usize, dc: i32, dr: i32, v: f64) {
        if let Some(i) = self.slot(t, dc, dr) {
            self.values[i] = Some(v);
        }
    }

    /// The value at step `t` and offset `(dc, dr)`, if reachable and set.
    pub fn get(&self, t: usize, dc: i32, dr: i32) -> Option<f64> {
        self.slot(t, dc, dr).and_then(|i| self.values[i])
    }

    /// `values[t−1][dr+T][dc+T]`, `None` where unreachable or off the lattice.
    pub fn to_nested(&self) -> Vec<Vec<Vec<Option<f64>>>> {
        let h = self.horizon as i32;
        (1..=self.horizon)
            .map(|t| {
                (-h..=h)
                    .map(|dr| (-h..=h).map(|dc| self.get(t, dc, dr)).collect())
                    .collect()
            })
            .collect()
    }

    /// Sum of the values along a move sequence, or `None` if it leaves the
    /// set cells.
    pub fn path_value(&self, moves: &[(i32, i32)]) -> Option<f64> {
        let (mut c, mut r) = (0, 0);
        let mut total = 0.0;
        for (t, &(dc, dr)) in moves.iter().enumerate() {
            c += dc;
            r += dr;
            total += self.get(t + 1, c, r)?;
        }
        Some(total)
    }
}

/// An optimal path: the moves of steps 1..=T and their total value.
#[derive(Debug, Clone, PartialEq)]
pub struct BestPath {
    /// Move `(dc, dr)` taken at each step.
    pub moves: Vec<(i32, i32)>,
    /// Sum of the grid values along the path.
    pub value: f64,
}

impl BestPath {
    /// Offsets from the start after each step.
    pub fn offsets(&self) -> Vec<(i32, i32)> {
        let (mut c, mut r) = (0, 0);
        self.moves
            .iter()
            .map(|&(dc, dr)| {
                c += dc;
                r += dr;
                (c, r)
            })
            .collect()
    }
}

/// The optimal path by dynamic programming (see the module docs).
///
/// The start itself must be on the lattice; cells with no value are never
/// entered. Staying put is always possible, so a path exists whenever the
/// start's own cell has values at every step.
pub fn best_path(grid: &ValueGrid) -> BestPath {
    let h = grid.horizon as i32;
    let side = grid.side;
    let idx = |dc: i32, dr: i32| ((dr + h) as usize) * side + (dc + h) as usize;
    // best[t] for t = T..1; NEG_INFINITY where unreachable.
    let mut best = vec![vec![f64::NEG_INFINITY; side * side]; grid.horizon + 1];
    for t in (1..=grid.horizon).rev() {
        let ti = t as i32;
        for dr in -ti..=ti {
            for dc in -ti..=ti {
                let Some(v) = grid.get(t, dc, dr) else {
                    continue;
                };
                let future = if t == grid.horizon {
                    0.0
                } else {
                    MOVES
                        .iter()
                        .filter_map(|&(mc, mr)| {
                            let (c, r) = (dc + mc, dr + mr);
                            (c.abs() <= ti + 1 && r.abs() <= ti + 1).then(|| best[t + 1][idx(c, r)])
                        })
                        .fold(f64::NEG_INFINITY, f64::max)
                };
                best[t][idx(dc, dr)] = v + future;
            }
        }
    }
    let (mut c, mut r) = (0, 0);
    let mut moves = Vec::with_capacity(grid.horizon);
    for (t, best_t) in best.iter().enumerate().skip(1) {
        let mut choice = (0, 0);
        let mut top = f64::NEG_INFINITY;
        for &(mc, mr) in &MOVES {
            let (nc, nr) = (c + mc, r + mr);
            if nc.abs() > t as i32 || nr.abs() > t as i32 {
                continue;
            }
            let b = best_t[idx(nc, nr)];
            if b > top {
                top = b;
                choice = (mc, mr);
            }
        }
        c += choice.0;
        r += choice.1;
        moves.push(choice);
    }
    let value = grid.path_value(&moves).unwrap_or(f64::NEG_INFINITY);
    BestPath { moves, value }
}

/// Exhaustive enumeration of the `9^T` move sequences in [`MOVES`] order,
/// keeping the first strictly better one: the paper's search, as a reference
/// for tests and benches.
pub fn brute_force(grid: &ValueGrid) -> BestPath {
    let mut best = BestPath {
        moves: vec![(0, 0); grid.horizon],
        value: f64::NEG_INFINITY,
    };
    let mut moves = Vec::with_capacity(grid.horizon);
    fn go(grid: &ValueGrid, moves: &mut Vec<(i32, i32)>, best: &mut BestPath) {
        if moves.len() == grid.horizon {
            if let Some(v) = grid.path_value(moves)
                && v > best.value
            {
                best.value = v;
                best.moves = moves.clone();
            }
            return;
        }
        for &m in &MOVES {
            moves.push(m);
            go(grid, moves, best);
            moves.pop();
        }
    }
    go(grid, &mut moves, &mut best);
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn grid_from(horizon: usize, vals: &[f64], holes: &[bool]) -> ValueGrid {
        let mut g = ValueGrid::new(horizon);
        let h = horizon as i32;
        let mut i = 0;
        for t in 1..=horizon {
            for dr in -h..=h {
                for dc in -h..=h {
                    // A hole models the lattice edge, but the start column
                    // and row stay open so that staying put is legal.
                    let hole = holes[i % holes.len()] && (dc != 0 || dr != 0);
                    if !hole {
                        g.set(t, dc, dr, vals[i % vals.len()]);
                    }
                    i += 1;
                }
            }
        }
        g
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn dp_equals_brute_force_on_integer_grids(
            horizon in 1usize..=4,
            vals in prop::collection::vec(0u8..4, 1..400),
            holes in prop::collection::vec(prop::bool::weighted(0.15), 1..50),
        ) {
            // Small integers: many ties, and exact sums, so the paths must match.
            let vals: Vec<f64> = vals.into_iter().map(f64::from).collect();
            let g = grid_from(horizon, &vals, &holes);
            let dp = best_path(&g);
            let bf = brute_force(&g);
            prop_assert_eq!(dp.value, bf.value);
            prop_assert_eq!(dp.moves, bf.moves);
        }

        #[test]
        fn dp_equals_brute_force_on_real_grids(
            horizon in 1usize..=4,
            vals in prop::collection::vec(-5.0f64..10.0, 1..400),
        ) {
            let g = grid_from(horizon, &vals, &[false]);
            let dp = best_path(&g);
            let bf = brute_force(&g);
            prop_assert!((dp.value - bf.value).abs() <= 1e-9 * bf.value.abs().max(1.0));
            prop_assert!((g.path_value(&dp.moves).unwrap_or(f64::NAN) - bf.value).abs() <= 1e-9 * bf.value.abs().max(1.0));
        }
    }

    #[test]
    fn off_lattice_cells_are_never_entered() {
        // A sensor in a corner: only offsets with dc ≥ 0, dr ≥ 0 exist.
        let mut g = ValueGrid::new(3);
        for t in 1..=3 {
            for dr in 0..=t as i32 {
                for dc in 0..=t as i32 {
                    g.set(t, dc, dr, 1.0);
                }
            }
        }
        g.set(3, 3, 3, 10.0);
        let p = best_path(&g);
        assert_eq!(p.offsets(), vec![(1, 1), (2, 2), (3, 3)]);
        assert_eq!(p.value, 12.0);
    }
}
