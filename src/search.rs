//! The best T-step path of one sensor: dynamic programming over the
//! space-time lattice.
//!
//! # Motion model
//!
//! A sensor of speed `m` (1 ≤ `m` ≤ [`MAX_SENSOR_SPEED`]) makes, in one step, up to
//! `m` king moves (each to one of its 8 neighbours); every intermediate and
//! final cell must be *free*, that is on the lattice and not blocked. The
//! offsets reachable in one step from offset `o` are therefore those within
//! breadth-first distance `m` of `o` in the 8-connected graph of free cells;
//! the displacement is at most `m` in each coordinate. The sensor's start,
//! offset `(0, 0)`, is always free, and so is every offset it can reach, so
//! staying put is always a legal step. [`ValueGrid::new`] is the paper's
//! case: speed 1, every cell free; [`ValueGrid::with_motion`] takes the speed
//! and the free cells.
//!
//! A path is a sequence of `T` legal steps whose final cells all have a value
//! in the [`ValueGrid`]; its value is the sum of those values, in step order.
//! Intermediate cells of a multi-move step only need to be free: they need
//! no value.
//!
//! # Algorithm
//!
//! The paper runs a depth-limited search over the `9^T` move sequences
//! ([`brute_force`] is that search, generalised to `(2m+1)²` displacements
//! per step). The value of a path is a sum of per-(cell, step) values, so
//! dynamic programming over the space-time lattice of (offset, step) pairs
//! finds the same optimum in `O(T·(2mT+1)²·(2m+1)²)`:
//! `best[t][o] = v[t][o] + max over the legal one-step successors o' of o of
//! best[t+1][o']`, then one forward pass picks the steps. The grid
//! precomputes, once per horizon, speed and free mask, which offsets are
//! reachable at each step and each offset's successor list. When every
//! offset is free (the planner's case), those tables are cached per thread,
//! so building a grid costs one allocation, and the successors of an offset
//! are a whole square, so the maximum is taken separably (rows, then
//! columns) in `O(T·(2mT+1)²·(2m+1))`.
//!
//! # Separation
//!
//! A grid may also carry *violation counts* per (step, offset): how many
//! other sensors a path ending a step there would be too close to (see
//! [`crate::separation`]). With any count set, a path's score is the pair
//! (violations, value), compared lexicographically: fewer violations first,
//! then more value. The same programme finds that optimum, since both parts
//! add along a path; without counts it is the plain value, as before.
//!
//! # Tie-breaking
//!
//! Ties are broken deterministically: among optimal paths, the one whose
//! displacement sequence comes first in [`step_displacements`] order (stay
//! first, then by Chebyshev ring, then `dr`, then `dc`; [`MOVES`] for speed
//! 1), compared step by step from step 1. [`brute_force`] enumerates in the
//! same order and keeps the first strictly better path, so both return the
//! same path (moves and value) whenever sums are exact.
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

use std::sync::Arc;

use crate::limits::MAX_SENSOR_SPEED;

mod bound;
mod motion;

pub use bound::{Bounded, PathGain, Stop, best_path_bounded};
use motion::Motion;
pub use motion::{MOVES, step_displacements};

/// Values of the cells a sensor can occupy, by step and offset from its
/// start, together with its motion model (speed and free cells; see the
/// module docs). A missing value (`None`) marks a cell the sensor may not
/// end a step on.
#[derive(Debug, Clone, PartialEq)]
pub struct ValueGrid {
    motion: Arc<Motion>,
    /// `values[(t−1)·side² + index]`.
    values: Vec<Option<f64>>,
    /// Violation counts, indexed as `values`; empty when none is set.
    violations: Vec<u16>,
}

impl ValueGrid {
    /// An empty grid (every value missing) for horizon `horizon ≥ 1`, speed
    /// 1 and every offset free: the paper's model.
    pub fn new(horizon: usize) -> Self {
        Self::from_motion(Motion::open(1, horizon))
    }

    /// An empty grid for horizon `horizon`, speed `speed` (king moves per
    /// step, `1..=MAX_SENSOR_SPEED`) and the free cells given by `free(dc, dr)`:
    /// whether the cell at offset `(dc, dr)` from the start is on the lattice
    /// and unblocked. `free` is called only for `|dc|, |dr| ≤ speed·horizon`
    /// (at most once per offset); the start `(0, 0)` is always free.
    ///
    /// ```
    /// use vigil::search::{ValueGrid, best_path};
    /// // Speed 2, one step; a wall at dc = 1 (|dr| ≤ 1) hides the sensor's
    /// // best cell (2, 0): it cannot jump over the wall in one step.
    /// let wall = |dc: i32, dr: i32| !(dc == 1 && dr.abs() <= 1);
    /// let mut grid = ValueGrid::with_motion(1, 2, wall);
    /// assert_eq!(grid.side(), 5);
    /// assert!(!grid.reachable(1, 2, 0) && !grid.reachable(1, 1, 0));
    /// assert!(grid.reachable(1, 1, -2)); // past the wall's end
    /// let cells: Vec<(i32, i32)> = {
    ///     let mut v = Vec::new();
    ///     grid.for_each_reachable(1, |dc, dr| v.push((dc, dr)));
    ///     v
    /// };
    /// for (dc, dr) in cells {
    ///     grid.set(1, dc, dr, f64::from(dc));
    /// }
    /// let best = best_path(&grid);
    /// assert_eq!(best.moves, vec![(1, -2)]);
    /// assert_eq!(best.value, 1.0);
    /// ```
    ///
    /// # Panics
    ///
    /// If `speed` is not in `1..=MAX_SENSOR_SPEED`.
    pub fn with_motion(horizon: usize, speed: usize, free: impl Fn(i32, i32) -> bool) -> Self {
        assert!(
            (1..=MAX_SENSOR_SPEED).contains(&speed),
            "speed {speed} is not in 1..={MAX_SENSOR_SPEED}"
        );
        let e = (speed * horizon) as i32;
        let side = 2 * speed * horizon + 1;
        let mut mask = Vec::with_capacity(side * side);
        let mut all = true;
        for dr in -e..=e {
            for dc in -e..=e {
                let f = (dc == 0 && dr == 0) || free(dc, dr);
                all &= f;
                mask.push(f);
            }
        }
        let motion = if all {
            Motion::open(speed, horizon)
        } else {
            Arc::new(Motion::build(speed, horizon, &mask))
        };
        Self::from_motion(motion)
    }

    fn from_motion(motion: Arc<Motion>) -> Self {
        let len = motion.horizon * motion.side * motion.side;
        Self {
            motion,
            values: vec![None; len],
            violations: Vec::new(),
        }
    }

    /// The horizon T.
    pub fn horizon(&self) -> usize {
        self.motion.horizon
    }

    /// The speed m: king moves per step.
    pub fn speed(&self) -> usize {
        self.motion.speed
    }

    /// The side `2·m·T + 1` of the square of offsets, and of each step of
    /// [`ValueGrid::to_nested`].
    pub fn side(&self) -> usize {
        self.motion.side
    }

    /// Whether offset `(dc, dr)` is reachable at step `t` (`1..=T`; step 0
    /// is the start alone): `t` legal steps through free cells lead there.
    pub fn reachable(&self, t: usize, dc: i32, dr: i32) -> bool {
        t <= self.horizon()
            && self
                .motion
                .index(dc, dr)
                .is_some_and(|i| self.motion.first[i] <= t as u32)
    }

    /// Calls `f(dc, dr)` for every offset reachable at step `t`, in
    /// row-major order (`dr` ascending, then `dc` ascending).
    pub fn for_each_reachable(&self, t: usize, mut f: impl FnMut(i32, i32)) {
        if t > self.horizon() {
            return;
        }
        let mo = &*self.motion;
        let (e, k) = (mo.extent(), (mo.speed * t) as i32);
        for dr in -k..=k {
            let row = (dr + e) as usize * mo.side;
            for dc in -k..=k {
                if mo.first[row + (dc + e) as usize] <= t as u32 {
                    f(dc, dr);
                }
            }
        }
    }

    /// Sets the value of every offset reachable at step `t` to `f(dc, dr)`,
    /// visiting them as [`ValueGrid::for_each_reachable`] does; `None`
    /// leaves an offset unset (a cell the caller knows is off the lattice).
    pub fn fill_step(&mut self, t: usize, mut f: impl FnMut(i32, i32) -> Option<f64>) {
        if t == 0 || t > self.horizon() {
            return;
        }
        let mo = Arc::clone(&self.motion);
        let (e, k) = (mo.extent(), (mo.speed * t) as i32);
        let base = (t - 1) * mo.side * mo.side;
        for dr in -k..=k {
            let row = (dr + e) as usize * mo.side;
            for dc in -k..=k {
                let i = row + (dc + e) as usize;
                if mo.first[i] <= t as u32
                    && let Some(v) = f(dc, dr)
                {
                    self.values[base + i] = Some(v);
                }
            }
        }
    }

    /// Sets step `t`'s values to `other`'s, a grid of the same motion
    /// (a clone of one, as every search of a sensor is).
    ///
    /// # Panics
    /// If `other` does not share this grid's motion.
    pub fn copy_step(&mut self, t: usize, other: &ValueGrid) {
        assert!(
            Arc::ptr_eq(&self.motion, &other.motion),
            "grids of different motions"
        );
        if t == 0 || t > self.horizon() {
            return;
        }
        let n = self.side() * self.side();
        let steps = (t - 1) * n..t * n;
        self.values[steps.clone()].copy_from_slice(&other.values[steps]);
    }

    fn slot(&self, t: usize, dc: i32, dr: i32) -> Option<usize> {
        if t == 0 || t > self.horizon() {
            return None;
        }
        let i = self.motion.index(dc, dr)?;
        (self.motion.first[i] <= t as u32).then(|| (t - 1) * self.side() * self.side() + i)
    }

    /// Sets the value of offset `(dc, dr)` at step `t` (1-based). Offsets
    /// not reachable at step `t` are ignored.
    pub fn set(&mut self, t: usize, dc: i32, dr: i32, v: f64) {
        if let Some(i) = self.slot(t, dc, dr) {
            self.values[i] = Some(v);
        }
    }

    /// The value at step `t` and offset `(dc, dr)`, if reachable and set.
    pub fn get(&self, t: usize, dc: i32, dr: i32) -> Option<f64> {
        self.slot(t, dc, dr).and_then(|i| self.values[i])
    }

    /// Adds one violation at step `t` (1-based) to every offset `(dc, dr)`
    /// with `dc` in `cols` and `dr` in `rows` (clipped to the square of
    /// offsets): ending step `t` there would be too close to one more
    /// sensor. Steps outside `1..=T` are ignored.
    pub fn add_violations(
        &mut self,
        t: usize,
        cols: std::ops::RangeInclusive<i32>,
        rows: std::ops::RangeInclusive<i32>,
    ) {
        if t == 0 || t > self.horizon() {
            return;
        }
        let e = self.motion.extent();
        let (c0, c1) = ((*cols.start()).max(-e), (*cols.end()).min(e));
        let (r0, r1) = ((*rows.start()).max(-e), (*rows.end()).min(e));
        if c0 > c1 || r0 > r1 {
            return;
        }
        if self.violations.is_empty() {
            self.violations = vec![0; self.values.len()];
        }
        let side = self.side();
        let base = (t - 1) * side * side;
        for dr in r0..=r1 {
            let row = base + (dr + e) as usize * side;
            for v in &mut self.violations[row + (c0 + e) as usize..=row + (c1 + e) as usize] {
                *v = v.saturating_add(1);
            }
        }
    }

    /// Removes every violation count.
    pub fn clear_violations(&mut self) {
        self.violations.clear();
    }

    /// True when some violation count is set (the search is then
    /// lexicographic; see the module docs).
    pub fn has_violations(&self) -> bool {
        !self.violations.is_empty()
    }

    /// The violation count at step `t` and offset `(dc, dr)` (0 outside the
    /// square or the horizon).
    pub fn violations(&self, t: usize, dc: i32, dr: i32) -> u32 {
        if self.violations.is_empty() || t == 0 || t > self.horizon() {
            return 0;
        }
        self.motion.index(dc, dr).map_or(0, |i| {
            u32::from(self.violations[(t - 1) * self.side() * self.side() + i])
        })
    }

    /// `values[t−1][dr+m·T][dc+m·T]`, `None` where unreachable, not free or
    /// unset; each step is `side × side`.
    pub fn to_nested(&self) -> Vec<Vec<Vec<Option<f64>>>> {
        let e = self.motion.extent();
        (1..=self.horizon())
            .map(|t| {
                (-e..=e)
                    .map(|dr| (-e..=e).map(|dc| self.get(t, dc, dr)).collect())
                    .collect()
            })
            .collect()
    }

    /// Sum of the values along a sequence of per-step displacements, or
    /// `None` if a displacement is not a legal step from the current offset
    /// (see the module docs), a value along the path is missing, or there
    /// are more than T displacements.
    pub fn path_value(&self, moves: &[(i32, i32)]) -> Option<f64> {
        self.path_score(moves).map(|(value, _)| value)
    }

    /// Sum of the violation counts along a sequence of per-step
    /// displacements, or `None` when [`ValueGrid::path_value`] would be.
    pub fn path_violations(&self, moves: &[(i32, i32)]) -> Option<u32> {
        self.path_score(moves).map(|(_, violations)| violations)
    }

    /// The first step (0-based) of `moves` that is not a legal step from
    /// where the path then is (see the module docs), or `None` when every
    /// step is legal. Values play no part.
    pub fn first_illegal_step(&self, moves: &[(i32, i32)]) -> Option<usize> {
        let mut o = self.motion.start();
        for (t, &d) in moves.iter().enumerate() {
            match self.motion.step(o, d) {
                Some(next) if t < self.horizon() => o = next,
                _ => return Some(t),
            }
        }
        None
    }

    /// [`ValueGrid::path_value`] and [`ValueGrid::path_violations`] in one
    /// walk along the path.
    pub fn path_score(&self, moves: &[(i32, i32)]) -> Option<(f64, u32)> {
        if moves.len() > self.horizon() {
            return None;
        }
        let n = self.side() * self.side();
        let mut o = self.motion.start();
        let (mut total, mut violations) = (0.0, 0);
        for (t, &d) in moves.iter().enumerate() {
            o = self.motion.step(o, d)?;
            total += self.values[t * n + o]?;
            if let Some(&k) = self.violations.get(t * n + o) {
                violations += u32::from(k);
            }
        }
        Some((total, violations))
    }
}

/// An optimal path: the moves of steps 1..=T and their total value.
#[derive(Debug, Clone, PartialEq)]
pub struct BestPath {
    /// Displacement `(dc, dr)` taken at each step.
    pub moves: Vec<(i32, i32)>,
    /// Sum of the grid values along the path (`-∞` if there is no path).
    pub value: f64,
    /// Sum of the grid's violation counts along the path (0 when the grid
    /// has none, or there is no path).
    pub violations: u32,
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

/// A path's score in the programme: its value, or with violation counts
/// (see the module docs) the pair (violations, value) in lexicographic
/// order. [`Score::NONE`] is "no path", below every real score.
trait Score: Copy {
    const NONE: Self;
    /// The score of ending a step at offset `o`, from that step's values
    /// and violation counts (empty when the grid has none).
    fn at(vals: &[Option<f64>], violations: &[u16], o: usize) -> Option<Self>;
    fn add(self, other: Self) -> Self;
    /// Strictly better.
    fn better(self, other: Self) -> bool;
    fn max(self, other: Self) -> Self;
}

impl Score for f64 {
    const NONE: Self = f64::NEG_INFINITY;
    #[inline(always)]
    fn at(vals: &[Option<f64>], _: &[u16], o: usize) -> Option<Self> {
        vals[o]
    }
    #[inline(always)]
    fn add(self, other: Self) -> Self {
        self + other
    }
    #[inline(always)]
    fn better(self, other: Self) -> bool {
        self > other
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        f64::max(self, other)
    }
}

/// (violations, value), violations negated so that both parts are
/// maximised; "no path" is `-∞` in both, and stays so under addition.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Lex {
    neg_violations: f64,
    value: f64,
}

impl Score for Lex {
    const NONE: Self = Lex {
        neg_violations: f64::NEG_INFINITY,
        value: f64::NEG_INFINITY,
    };
    #[inline(always)]
    fn at(vals: &[Option<f64>], violations: &[u16], o: usize) -> Option<Self> {
        vals[o].map(|value| Lex {
            neg_violations: -f64::from(violations[o]),
            value,
        })
    }
    #[inline(always)]
    fn add(self, other: Self) -> Self {
        Lex {
            neg_violations: self.neg_violations + other.neg_violations,
            value: self.value + other.value,
        }
    }
    #[inline(always)]
    fn better(self, other: Self) -> bool {
        self.neg_violations > other.neg_violations
            || (self.neg_violations == other.neg_violations && self.value > other.value)
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        if other.better(self) { other } else { self }
    }
}

/// The optimal path by dynamic programming over the space-time lattice (see
/// the module docs), with the tie-breaking of [`brute_force`]. With
/// violation counts on the grid it minimises (violations, −value)
/// lexicographically.
///
/// Cells with no value are never entered (they may be passed through within
/// a step if free). Staying put is always legal, so a path exists whenever
/// the start's own cell has values at every step. With no path at all, the
/// moves are all `(0, 0)` and the value is `-∞`.
pub fn best_path(grid: &ValueGrid) -> BestPath {
    if grid.violations.is_empty() {
        programme::<f64>(grid)
    } else {
        programme::<Lex>(grid)
    }
}

/// The programme of [`best_path`] over scores `S`.
fn programme<S: Score>(grid: &ValueGrid) -> BestPath {
    let mo = &*grid.motion;
    let (h, side, speed) = (mo.horizon, mo.side, mo.speed);
    let n = side * side;
    let e = speed * h;
    // best[(t−1)·n + o] for t = 1..=T; NONE where there is no path from (o, t).
    let mut best = vec![S::NONE; h * n];
    let mut rowmax = if mo.open && h > 1 {
        vec![S::NONE; n]
    } else {
        Vec::new()
    };
    for t in (1..=h).rev() {
        let (done, later) = best.split_at_mut(t * n);
        let cur = &mut done[(t - 1) * n..];
        let vals = &grid.values[(t - 1) * n..t * n];
        let viols = grid.violations.get((t - 1) * n..t * n).unwrap_or(&[]);
        let k = speed * t;
        let rows = e - k..=e + k;
        let cols = move |r: usize| r * side + e - k..=r * side + e + k;
        if t == h {
            for r in rows {
                for o in cols(r) {
                    if let Some(v) = S::at(vals, viols, o) {
                        cur[o] = v;
                    }
                }
            }
            continue;
        }
        let next = &later[..n];
        if mo.open {
            let scores = StepScores { vals, viols };
            let reach = Reach {
                side,
                lo: e - k,
                hi: e + k,
            };
            match speed {
                1 => open_layer::<1, S>(scores, reach, next, &mut rowmax, cur),
                2 => open_layer::<2, S>(scores, reach, next, &mut rowmax, cur),
                _ => open_layer::<3, S>(scores, reach, next, &mut rowmax, cur),
            }
        } else {
            for r in rows {
                for o in cols(r) {
                    let Some(v) = S::at(vals, viols, o) else {
                        continue;
                    };
                    cur[o] = v.add(
                        mo.successors(o)
                            .iter()
                            .fold(S::NONE, |a, &s| a.max(next[s as usize])),
                    );
                }
            }
        }
    }
    let mut o = mo.start();
    let mut moves = Vec::with_capacity(h);
    // The value is summed in step order, as brute force sums it.
    let mut value = Some(0.0);
    let mut violations = 0;
    for t in 1..=h {
        let row = &best[(t - 1) * n..t * n];
        let mut choice = o;
        let mut top = S::NONE;
        for &s in mo.successors(o) {
            let b = row[s as usize];
            if b.better(top) {
                top = b;
                choice = s as usize;
            }
        }
        moves.push((
            (choice % side) as i32 - (o % side) as i32,
            (choice / side) as i32 - (o / side) as i32,
        ));
        o = choice;
        value = value.zip(grid.values[(t - 1) * n + o]).map(|(a, v)| a + v);
        if let Some(&k) = grid.violations.get((t - 1) * n + o) {
            violations += u32::from(k);
        }
    }
    match value {
        Some(value) => BestPath {
            moves,
            violations,
            value,
        },
        // No path from the start: the walk above may have stepped onto a
        // later step's values through cells with none. Stay put, as
        // documented (and as brute force answers).
        None => BestPath {
            moves: vec![(0, 0); h],
            violations: 0,
            value: f64::NEG_INFINITY,
        },
    }
}

/// One step's scores in [`best_path`]'s programme: the values (`None`
/// where the offset cannot be stood on) and the violation counts (empty
/// when none are counted), indexed by offset.
#[derive(Clone, Copy)]
struct StepScores<'a> {
    vals: &'a [Option<f64>],
    viols: &'a [u16],
}

/// The offsets a sensor can reach at one step: the box `lo..=hi` ×
/// `lo..=hi` of a square of offsets `side` wide.
#[derive(Clone, Copy)]
struct Reach {
    side: usize,
    lo: usize,
    hi: usize,
}

/// One layer of [`best_path`]'s programme for an open motion of speed `M`
/// (every offset free): `cur[o] = score(o) + max of next over the (2M+1)²
/// square around o` for `o` in the box `lo..=hi` × `lo..=hi` of step t
/// (scores from the step's `vals` and `viols`). The successors are that whole square,
/// so their maximum is separable: maxima along rows into `rowmax`, then
/// along columns. `hi + M` is inside the square of offsets (t < T), and the
/// maximum is associative and commutative (up to the sign of zeros), so
/// `best` compares exactly as the successor lists' fold would.
#[inline(always)]
fn open_layer<const M: usize, S: Score>(
    scores: StepScores<'_>,
    reach: Reach,
    next: &[S],
    rowmax: &mut [S],
    cur: &mut [S],
) {
    let StepScores { vals, viols } = scores;
    let Reach { side, lo, hi } = reach;
    for r in lo - M..=hi + M {
        let row = r * side;
        let src = &next[row + lo - M..=row + hi + M];
        for (dst, w) in rowmax[row + lo..=row + hi]
            .iter_mut()
            .zip(src.windows(2 * M + 1))
        {
            *dst = w.iter().fold(S::NONE, |a, &b| a.max(b));
        }
    }
    for r in lo..=hi {
        let row = r * side;
        for o in row + lo..=row + hi {
            let Some(v) = S::at(vals, viols, o) else {
                continue;
            };
            let f = (0..=2 * M).fold(S::NONE, |a, i| a.max(rowmax[o + i * side - M * side]));
            cur[o] = v.add(f);
        }
    }
}

/// Exhaustive enumeration of the displacement sequences in
/// [`step_displacements`] order (legal ones only: an illegal prefix is not
/// extended), keeping the first strictly better one (by value, or by
/// (violations, −value) when the grid has violation counts): the paper's
/// search, as a reference for tests and benches. Its cost grows as
/// `(2m+1)^(2T)`.
pub fn brute_force(grid: &ValueGrid) -> BestPath {
    let h = grid.horizon();
    let mut best = (vec![(0, 0); h], Lex::NONE);
    let mut moves = Vec::with_capacity(h);
    fn go(
        grid: &ValueGrid,
        o: usize,
        total: Lex,
        moves: &mut Vec<(i32, i32)>,
        best: &mut (Vec<(i32, i32)>, Lex),
    ) {
        let t = moves.len();
        if t == grid.horizon() {
            if total.better(best.1) {
                *best = (moves.clone(), total);
            }
            return;
        }
        let n = grid.side() * grid.side();
        for &d in step_displacements(grid.speed()) {
            let Some(o2) = grid.motion.step(o, d) else {
                continue;
            };
            let Some(value) = grid.values[t * n + o2] else {
                continue;
            };
            let violations = grid.violations.get(t * n + o2).copied().unwrap_or(0);
            let here = Lex {
                neg_violations: -f64::from(violations),
                value,
            };
            moves.push(d);
            go(grid, o2, total.add(here), moves, best);
            moves.pop();
        }
    }
    let zero = Lex {
        neg_violations: 0.0,
        value: 0.0,
    };
    go(grid, grid.motion.start(), zero, &mut moves, &mut best);
    let (moves, score) = best;
    let found = score.value > f64::NEG_INFINITY;
    BestPath {
        moves,
        value: score.value,
        violations: if found {
            -score.neg_violations as u32
        } else {
            0
        },
    }
}

#[cfg(test)]
mod tests;
