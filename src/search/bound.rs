//! The best path of one sensor when a path's value is not a sum over its
//! steps: branch and bound over the paths, bounded by the dynamic
//! programme of per-step upper bounds.
//!
//! An objective with diminishing returns along a path (a coverage, such as
//! the first detections of [`crate::estimator::FirstDetections`]) gives each
//! stop of a path a *gain*: what it adds on top of the path's earlier
//! stops. The gain of ending step `t` at an offset is at most its gain with
//! no earlier stop, which the grid holds as that step's value. So the
//! grid's programme (as [`super::best_path`] runs it, backwards) bounds what
//! any completion of a prefix can add, and a depth-first search over the
//! prefixes, in the [`super::step_displacements`] order of each step,
//! prunes every prefix whose exact value plus that bound cannot beat the
//! best path found. The search starts from the programme's own path,
//! scored exactly.
//!
//! The result is the exact optimum whenever the search finishes within its
//! budget of gains evaluated; otherwise it is the best path found (never
//! below the programme's path, scored exactly), flagged as such, with an
//! upper bound on the optimum.
//!
//! With violation counts on the grid (see [`crate::separation`]) the score
//! is (violations, value) in lexicographic order, as in the programme; the
//! programme's bound is then the fewest violations of a completion and the
//! most value among completions with that few, which prunes exactly.

use super::{BestPath, Lex, Score, ValueGrid};

/// The exact gain of a path's last stop.
pub trait PathGain {
    /// What ending step `stops.len()` at its last offset adds to a path
    /// whose earlier steps end at `stops[..len−1]` (offsets from the start,
    /// steps 1, 2, …). Never more than the grid's value there, which is the
    /// gain with no earlier stop.
    fn gain(&self, stops: &[(i32, i32)]) -> f64;
}

/// What [`best_path_bounded`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct Bounded {
    /// The best path found, its `value` the exact sum of its gains.
    pub best: BestPath,
    /// True when the search finished: `best` is optimal.
    pub exhaustive: bool,
    /// No legal path has more value than this, violation counts ignored
    /// (`best.value` when exhaustive on a grid without them).
    pub upper: f64,
    /// Gains evaluated.
    pub evaluated: usize,
}

/// The path of most exact value (see the module docs) through `grid`, whose
/// values are each stop's gain with no earlier stop, for the gains of
/// `gain`; at most `budget` gains are evaluated.
pub fn best_path_bounded(grid: &ValueGrid, gain: &dyn PathGain, budget: usize) -> Bounded {
    let mo = &*grid.motion;
    let (h, side) = (mo.horizon, mo.side);
    let n = side * side;
    let lex = |t: usize, o: usize| -> Option<Lex> {
        let i = (t - 1) * n + o;
        grid.values[i].map(|value| Lex {
            neg_violations: -f64::from(grid.violations.get(i).copied().unwrap_or(0)),
            value,
        })
    };
    // togo[t·n + o]: the best additive score of steps t+1..=T from offset o
    // at step t (zero at T, `NONE` where no completion exists).
    let mut togo = vec![Lex::NONE; (h + 1) * n];
    for o in 0..n {
        togo[h * n + o] = Lex {
            neg_violations: 0.0,
            value: 0.0,
        };
    }
    for t in (0..h).rev() {
        for o in 0..n {
            if mo.first[o] > t as u32 {
                continue;
            }
            let mut best = Lex::NONE;
            for &s in mo.successors(o) {
                if let Some(v) = lex(t + 1, s as usize) {
                    best = best.max(v.add(togo[(t + 1) * n + s as usize]));
                }
            }
            togo[t * n + o] = best;
        }
    }
    let start = mo.start();
    let root = togo[start];
    let offset = |o: usize| {
        (
            (o % side) as i32 - (start % side) as i32,
            (o / side) as i32 - (start / side) as i32,
        )
    };
    let mut search = Search {
        grid,
        gain,
        togo: &togo,
        n,
        budget,
        evaluated: 0,
        cut: false,
        stops: Vec::with_capacity(h),
        cells: Vec::with_capacity(h),
        best_cells: Vec::new(),
        best: Lex::NONE,
        offset: &offset,
    };
    if root.neg_violations == f64::NEG_INFINITY {
        return Bounded {
            best: BestPath {
                moves: vec![(0, 0); h],
                value: f64::NEG_INFINITY,
                violations: 0,
            },
            exhaustive: true,
            upper: f64::NEG_INFINITY,
            evaluated: 0,
        };
    }
    // The programme's own path first, scored exactly: the incumbent.
    let mut o = start;
    let mut cells = Vec::with_capacity(h);
    for t in 0..h {
        let mut choice = None;
        let mut top = Lex::NONE;
        for &s in mo.successors(o) {
            if let Some(v) = lex(t + 1, s as usize) {
                let b = v.add(togo[(t + 1) * n + s as usize]);
                if b.better(top) {
                    (top, choice) = (b, Some(s as usize));
                }
            }
        }
        o = choice.expect("a completion exists where togo is finite");
        cells.push(o);
    }
    search.best = search.score(&cells);
    search.best_cells = cells;
    search.descend(
        start,
        0,
        Lex {
            neg_violations: 0.0,
            value: 0.0,
        },
    );
    let exhaustive = !search.cut;
    let best = search.best;
    let moves = {
        let mut prev = start;
        search
            .best_cells
            .iter()
            .map(|&c| {
                let (a, b) = (offset(c), offset(prev));
                prev = c;
                (a.0 - b.0, a.1 - b.1)
            })
            .collect()
    };
    let upper = if exhaustive && grid.violations.is_empty() {
        best.value
    } else {
        // The programme's value alone, violations ignored.
        super::programme::<f64>(grid).value.max(best.value)
    };
    Bounded {
        best: BestPath {
            moves,
            value: best.value,
            violations: -best.neg_violations as u32,
        },
        exhaustive,
        upper,
        evaluated: search.evaluated,
    }
}

/// The depth-first search's state.
struct Search<'s> {
    grid: &'s ValueGrid,
    gain: &'s dyn PathGain,
    togo: &'s [Lex],
    n: usize,
    budget: usize,
    evaluated: usize,
    /// The budget ran out.
    cut: bool,
    /// The prefix's offsets from the start, and its grid indices.
    stops: Vec<(i32, i32)>,
    cells: Vec<usize>,
    best_cells: Vec<usize>,
    best: Lex,
    offset: &'s dyn Fn(usize) -> (i32, i32),
}

impl Search<'_> {
    /// The violations of ending step `t` (1-based) at `o`.
    fn violations(&self, t: usize, o: usize) -> f64 {
        f64::from(
            self.grid
                .violations
                .get((t - 1) * self.n + o)
                .copied()
                .unwrap_or(0),
        )
    }

    /// The exact score of a whole path of grid indices.
    fn score(&mut self, cells: &[usize]) -> Lex {
        self.stops.clear();
        let mut total = Lex {
            neg_violations: 0.0,
            value: 0.0,
        };
        for (t, &o) in cells.iter().enumerate() {
            self.stops.push((self.offset)(o));
            self.evaluated += 1;
            total = total.add(Lex {
                neg_violations: -self.violations(t + 1, o),
                value: self.gain.gain(&self.stops),
            });
        }
        self.stops.clear();
        total
    }

    /// Extends the prefix ending at `o` after step `t` (score `so_far`).
    fn descend(&mut self, o: usize, t: usize, so_far: Lex) {
        let grid = self.grid;
        let mo = &*grid.motion;
        if t == mo.horizon {
            if so_far.better(self.best) {
                self.best = so_far;
                self.best_cells.clone_from(&self.cells);
            }
            return;
        }
        for &s in mo.successors(o) {
            let s = s as usize;
            let Some(upper) = grid.values[t * self.n + s] else {
                continue;
            };
            let here = Lex {
                neg_violations: -self.violations(t + 1, s),
                value: upper,
            };
            if !so_far
                .add(here)
                .add(self.togo[(t + 1) * self.n + s])
                .better(self.best)
            {
                continue;
            }
            if self.evaluated >= self.budget {
                self.cut = true;
                return;
            }
            self.stops.push((self.offset)(s));
            self.cells.push(s);
            self.evaluated += 1;
            let exact = Lex {
                neg_violations: here.neg_violations,
                value: self.gain.gain(&self.stops),
            };
            let score = so_far.add(exact);
            if score.add(self.togo[(t + 1) * self.n + s]).better(self.best) {
                self.descend(s, t + 1, score);
            }
            self.stops.pop();
            self.cells.pop();
            if self.cut {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    use super::*;
    use crate::search::step_displacements;

    /// A coverage on `items` weighted items: each (step, offset) stop holds
    /// a random few of them, and a path's value is the weight of the items
    /// its stops hold, each counted once.
    struct Coverage {
        weights: Vec<f64>,
        holds: std::collections::HashMap<(usize, i32, i32), Vec<usize>>,
    }

    impl Coverage {
        fn random(grid: &ValueGrid, items: usize, rng: &mut StdRng) -> Self {
            let weights: Vec<f64> = (0..items).map(|_| rng.random::<f64>()).collect();
            let mut holds = std::collections::HashMap::new();
            for t in 1..=grid.horizon() {
                grid.for_each_reachable(t, |dc, dr| {
                    // Few items per stop, so that stops overlap sometimes.
                    let k = rng.random_range(0..4);
                    let set = (0..k).map(|_| rng.random_range(0..items)).collect();
                    holds.insert((t, dc, dr), set);
                });
            }
            Coverage { weights, holds }
        }

        fn value(&self, stops: &[(i32, i32)]) -> f64 {
            let mut seen = std::collections::HashSet::new();
            let mut v = 0.0;
            for (t, &(dc, dr)) in stops.iter().enumerate() {
                for &i in &self.holds[&(t + 1, dc, dr)] {
                    if seen.insert(i) {
                        v += self.weights[i];
                    }
                }
            }
            v
        }

        fn fill(&self, grid: &mut ValueGrid) {
            for t in 1..=grid.horizon() {
                grid.fill_step(t, |dc, dr| {
                    let mut set = self.holds[&(t, dc, dr)].clone();
                    set.sort_unstable();
                    set.dedup();
                    Some(set.iter().map(|&i| self.weights[i]).sum())
                });
            }
        }
    }

    impl PathGain for Coverage {
        fn gain(&self, stops: &[(i32, i32)]) -> f64 {
            let (_, earlier) = stops.split_last().expect("a stop");
            self.value(stops) - self.value(earlier)
        }
    }

    /// Every legal path's (violations, value), by enumeration.
    fn exhaustive(grid: &ValueGrid, cov: &Coverage) -> (u32, f64) {
        fn go(
            grid: &ValueGrid,
            cov: &Coverage,
            at: (i32, i32),
            stops: &mut Vec<(i32, i32)>,
            best: &mut (u32, f64),
        ) {
            let t = stops.len();
            if t == grid.horizon() {
                let v: u32 = stops
                    .iter()
                    .enumerate()
                    .map(|(i, &(dc, dr))| grid.violations(i + 1, dc, dr))
                    .sum();
                let value = cov.value(stops);
                if v < best.0 || (v == best.0 && value > best.1) {
                    *best = (v, value);
                }
                return;
            }
            for &(dc, dr) in step_displacements(grid.speed()) {
                let next = (at.0 + dc, at.1 + dr);
                let mut moves: Vec<(i32, i32)> = Vec::new();
                let mut prev = (0, 0);
                for &s in stops.iter().chain(std::iter::once(&next)) {
                    moves.push((s.0 - prev.0, s.1 - prev.1));
                    prev = s;
                }
                if grid.first_illegal_step(&moves).is_some()
                    || grid.get(t + 1, next.0, next.1).is_none()
                {
                    continue;
                }
                stops.push(next);
                go(grid, cov, next, stops, best);
                stops.pop();
            }
        }
        let mut best = (u32::MAX, f64::NEG_INFINITY);
        go(grid, cov, (0, 0), &mut Vec::new(), &mut best);
        best
    }

    #[test]
    fn the_bounded_search_finds_the_exhaustive_optimum() {
        let mut rng = StdRng::seed_from_u64(7);
        for case in 0..60 {
            let horizon = 1 + case % 4;
            let speed = if case % 5 == 0 { 2 } else { 1 };
            let horizon = if speed == 2 { horizon.min(2) } else { horizon };
            // Some cases with a wall, some with violation counts.
            let wall = case % 3 == 1;
            let mut grid = ValueGrid::with_motion(horizon, speed, |dc, dr| {
                !(wall && dc == 1 && dr.abs() <= 1)
            });
            let cov = Coverage::random(&grid, 12, &mut rng);
            cov.fill(&mut grid);
            if case % 4 == 3 {
                grid.add_violations(1, -1..=0, -1..=1);
                grid.add_violations(horizon, 0..=2, -2..=0);
            }
            let found = best_path_bounded(&grid, &cov, usize::MAX);
            let (violations, value) = exhaustive(&grid, &cov);
            assert!(found.exhaustive, "case {case}");
            assert_eq!(found.best.violations, violations, "case {case}");
            assert!(
                (found.best.value - value).abs() < 1e-12,
                "case {case}: {} vs {value}",
                found.best.value
            );
            // The value reported is the path's own.
            let mut stops = Vec::new();
            let (mut c, mut r) = (0, 0);
            for &(dc, dr) in &found.best.moves {
                (c, r) = (c + dc, r + dr);
                stops.push((c, r));
            }
            assert!((cov.value(&stops) - found.best.value).abs() < 1e-12);
            assert_eq!(grid.first_illegal_step(&found.best.moves), None);
        }
    }

    #[test]
    fn a_cut_search_keeps_a_path_at_least_the_programmes_and_a_true_upper_bound() {
        let mut rng = StdRng::seed_from_u64(11);
        for case in 0..20 {
            let mut grid = ValueGrid::new(4);
            let cov = Coverage::random(&grid, 8, &mut rng);
            cov.fill(&mut grid);
            let programme = super::super::best_path(&grid);
            let mut stops = Vec::new();
            for (c, r) in programme.offsets() {
                stops.push((c, r));
            }
            let its_value = cov.value(&stops);
            let cut = best_path_bounded(&grid, &cov, 10);
            assert!(
                !cut.exhaustive,
                "case {case}: a budget of 10 gains is short"
            );
            assert!(cut.best.value >= its_value - 1e-12, "case {case}");
            let (_, optimum) = exhaustive(&grid, &cov);
            assert!(cut.upper >= optimum - 1e-12, "case {case}");
            assert!(cut.best.value <= optimum + 1e-12, "case {case}");
        }
    }
}
