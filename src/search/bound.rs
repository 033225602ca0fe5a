//! The best path of one sensor when a path's value is not a sum over its
//! steps: branch and bound over the paths, bounded by a dynamic programme
//! over pairs of consecutive steps.
//!
//! An objective with diminishing returns along a path (a coverage, such as
//! the first detections of [`crate::estimator::FirstDetections`]) gives each
//! stop of a path a *gain*: what it adds on top of the path's earlier
//! stops, never more than on top of fewer of them. So the gain of a stop
//! given only the stop before it bounds its gain given the whole prefix,
//! and the best sum of those *pair gains* from a stop to the horizon (one
//! dynamic programme over the (step, offset) lattice, as [`super::best_path`]
//! runs over single values) bounds what any completion of a prefix can
//! add. A depth-first search over the prefixes, in the
//! [`super::step_displacements`] order of each step, prunes every prefix
//! whose exact value plus that bound cannot beat the best path found. It
//! starts from the pair programme's own path, scored exactly. Along most
//! paths the pair gains hold most of the overlap (a target seen at one step
//! is mostly still in view at the next), so the bound is tight and the
//! pair programme's path is close to the best.
//!
//! The pair gains are the search's main cost, and many are never needed:
//! a stop's gain is at most its lone value, so the best sum of lone values
//! through an edge bounds every path through it. Before the pairs, the
//! path of most lone value (one programme over single values) is scored
//! exactly, and an edge whose lone bound falls below that score is left
//! out: no path through it can be the best.
//!
//! The result is the exact optimum whenever the search finishes within its
//! budget of gains evaluated past the pairs; otherwise it is the best path
//! found (never below the pair programme's path, scored exactly), flagged
//! as such, with the pair programme's value as an upper bound on the
//! optimum.
//!
//! With violation counts on the grid (see [`crate::separation`]) the score
//! is (violations, value) in lexicographic order, as in the programme; the
//! programme's bound is then the fewest violations of a completion and the
//! most value among completions with that few, which prunes exactly.

use super::{BestPath, Lex, Score, ValueGrid};

/// A stop of a path: its step (1-based) and its offset from the start.
pub type Stop = (usize, (i32, i32));

/// The exact gain of a path's stops.
pub trait PathGain {
    /// What ending step `t` at offset `at` adds on top of the stops
    /// `earlier` (at earlier steps). Never more than on top of a subset of
    /// them; with none, the grid's value there.
    fn gain(&self, t: usize, at: (i32, i32), earlier: &[Stop]) -> f64;
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
    /// Gains evaluated: the lone-value path's, the pairs', then the
    /// search's.
    pub evaluated: usize,
}

/// The relative margin below the lone-value path's exact score under which
/// an edge's lone bound prunes it: far above the rounding of a sum of gains.
const PRUNE_MARGIN: f64 = 1e-9;

const ZERO: Lex = Lex {
    neg_violations: 0.0,
    value: 0.0,
};

/// The path of most exact value (see the module docs) through `grid`, whose
/// values are each stop's gain with no earlier stop, for the gains of
/// `gain`; the search past the pairs evaluates at most `budget` gains.
pub fn best_path_bounded(grid: &ValueGrid, gain: &dyn PathGain, budget: usize) -> Bounded {
    let mo = &*grid.motion;
    let (h, side) = (mo.horizon, mo.side);
    let n = side * side;
    let start = mo.start();
    let offset = |o: usize| {
        (
            (o % side) as i32 - (start % side) as i32,
            (o / side) as i32 - (start / side) as i32,
        )
    };
    let violations =
        |t: usize, o: usize| f64::from(grid.violations.get((t - 1) * n + o).copied().unwrap_or(0));
    // Without violation counts, the path of most lone value, scored
    // exactly, prunes the pairs: a stop's gain is never above its lone
    // value, so no path through an edge whose best lone-value path falls
    // below that score can beat it, and the edge is left out. The margin
    // keeps the edges of paths that tie with it to rounding (its own).
    let mut evaluated = 0;
    let lone = grid.violations.is_empty().then(|| LoneBounds::new(grid));
    let lone = lone
        .filter(|l| l.out[start] > f64::NEG_INFINITY)
        .map(|lone| {
            let cells = lone.best_path(grid);
            evaluated += h;
            let value = score(gain, &offset, &|_, _| 0.0, &cells).value;
            (lone, cells, value)
        });
    // The pair gains: `pairs[first[(t−1)·n + o] + k]` for the k-th successor
    // `s` of `o` (a stop of step t − 1, or the start) is the gain of ending
    // step t at `s` after `o` alone (NaN where `s` has no value, or where
    // the lone values prune the edge).
    let mut first = vec![u32::MAX; h * n];
    let mut pairs: Vec<f64> = Vec::new();
    for t in 1..=h {
        for o in 0..n {
            let stands = if t == 1 {
                o == start
            } else {
                grid.values[(t - 2) * n + o].is_some()
            };
            if !stands || mo.successors(o).is_empty() {
                continue;
            }
            first[(t - 1) * n + o] = pairs.len() as u32;
            for &s in mo.successors(o) {
                let s = s as usize;
                pairs.push(match grid.values[(t - 1) * n + s] {
                    None => f64::NAN,
                    Some(alone) if t == 1 => alone,
                    Some(alone)
                        if lone.as_ref().is_some_and(|(bounds, _, value)| {
                            bounds.through(t, o, s, alone)
                                < value - PRUNE_MARGIN * value.abs().max(1.0)
                        }) =>
                    {
                        f64::NAN
                    }
                    Some(_) => {
                        evaluated += 1;
                        gain.gain(t, offset(s), &[(t - 1, offset(o))])
                    }
                });
            }
        }
    }
    let edges = Edges {
        grid,
        first: &first,
        pairs: &pairs,
        n,
    };
    let togo = edges.programme(|t, o| Lex {
        neg_violations: -violations(t, o),
        value: 0.0,
    });
    let root = togo[start];
    if root.neg_violations == f64::NEG_INFINITY {
        return Bounded {
            best: BestPath {
                moves: vec![(0, 0); h],
                value: f64::NEG_INFINITY,
                violations: 0,
            },
            exhaustive: true,
            upper: f64::NEG_INFINITY,
            evaluated,
        };
    }
    let mut search = Search {
        edges: &edges,
        gain,
        togo: &togo,
        budget: budget.saturating_add(evaluated),
        evaluated,
        cut: false,
        stops: Vec::with_capacity(h),
        cells: Vec::with_capacity(h),
        best_cells: Vec::new(),
        best: Lex::NONE,
        offset: &offset,
        violations: &violations,
    };
    // The pair programme's own path first, scored exactly: the incumbent.
    let mut o = start;
    let mut cells = Vec::with_capacity(h);
    for t in 0..h {
        let mut choice = None;
        let mut top = Lex::NONE;
        for (s, w) in edges.out(t + 1, o) {
            let b = Lex {
                neg_violations: -violations(t + 1, s),
                value: w,
            }
            .add(togo[(t + 1) * n + s]);
            if b.better(top) {
                (top, choice) = (b, Some(s));
            }
        }
        o = choice.expect("a completion exists where togo is finite");
        cells.push(o);
    }
    search.best = search.score(&cells);
    search.best_cells = cells;
    if let Some((_, cells, value)) = lone {
        let score = Lex {
            neg_violations: 0.0,
            value,
        };
        if score.better(search.best) {
            search.best = score;
            search.best_cells = cells;
        }
    }
    search.descend(start, 0, ZERO);
    let exhaustive = !search.cut;
    let best = search.best;
    let evaluated = search.evaluated;
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
        // The pair programme's value alone, violations ignored.
        let plain = edges.programme(|_, _| ZERO);
        plain[start].value.max(best.value)
    };
    Bounded {
        best: BestPath {
            moves,
            value: best.value,
            violations: -best.neg_violations as u32,
        },
        exhaustive,
        upper,
        evaluated,
    }
}

/// The exact score of a whole path of grid indices (steps 1..=T), each
/// stop's violations from `violations(t, o)` and offset from `offset(o)`.
fn score(
    gain: &dyn PathGain,
    offset: &dyn Fn(usize) -> (i32, i32),
    violations: &dyn Fn(usize, usize) -> f64,
    cells: &[usize],
) -> Lex {
    let mut stops: Vec<Stop> = Vec::with_capacity(cells.len());
    let mut total = ZERO;
    for (t, &o) in cells.iter().enumerate() {
        let at = offset(o);
        total = total.add(Lex {
            neg_violations: -violations(t + 1, o),
            value: gain.gain(t + 1, at, &stops),
        });
        stops.push((t + 1, at));
    }
    total
}

/// The best sums of lone values (the grid's) into and out of each stop:
/// `into[t·n + o]` over steps 1..=t of paths ending at `o` at step t,
/// `out[t·n + o]` over steps t+1..=T of paths from there (−∞ where none).
struct LoneBounds {
    n: usize,
    into: Vec<f64>,
    out: Vec<f64>,
}

impl LoneBounds {
    fn new(grid: &ValueGrid) -> Self {
        let mo = &*grid.motion;
        let (h, n) = (mo.horizon, mo.side * mo.side);
        let value = |t: usize, s: u32| grid.values[(t - 1) * n + s as usize];
        let mut into = vec![f64::NEG_INFINITY; (h + 1) * n];
        into[mo.start()] = 0.0;
        for t in 1..=h {
            for o in 0..n {
                let here = into[(t - 1) * n + o];
                if here == f64::NEG_INFINITY {
                    continue;
                }
                for &s in mo.successors(o) {
                    if let Some(v) = value(t, s) {
                        let next = &mut into[t * n + s as usize];
                        *next = next.max(here + v);
                    }
                }
            }
        }
        let mut out = vec![f64::NEG_INFINITY; (h + 1) * n];
        out[h * n..].fill(0.0);
        for t in (0..h).rev() {
            for o in 0..n {
                let mut best = f64::NEG_INFINITY;
                for &s in mo.successors(o) {
                    if let Some(v) = value(t + 1, s) {
                        best = best.max(v + out[(t + 1) * n + s as usize]);
                    }
                }
                out[t * n + o] = best;
            }
        }
        Self { n, into, out }
    }

    /// The most lone value of a path that ends step t at `s` (lone value
    /// `alone`) after `o`.
    fn through(&self, t: usize, o: usize, s: usize, alone: f64) -> f64 {
        self.into[(t - 1) * self.n + o] + alone + self.out[t * self.n + s]
    }

    /// A path of most lone value (grid indices of steps 1..=T), the first
    /// successor in order among equals.
    fn best_path(&self, grid: &ValueGrid) -> Vec<usize> {
        let mo = &*grid.motion;
        let n = self.n;
        let mut o = mo.start();
        let mut cells = Vec::with_capacity(mo.horizon);
        for t in 1..=mo.horizon {
            let mut top = (f64::NEG_INFINITY, usize::MAX);
            for &s in mo.successors(o) {
                let s = s as usize;
                if let Some(v) = grid.values[(t - 1) * n + s] {
                    let total = v + self.out[t * n + s];
                    if total > top.0 {
                        top = (total, s);
                    }
                }
            }
            o = top.1;
            cells.push(o);
        }
        cells
    }
}

/// The pair gains over the grid's motion.
struct Edges<'e> {
    grid: &'e ValueGrid,
    first: &'e [u32],
    pairs: &'e [f64],
    n: usize,
}

impl Edges<'_> {
    /// The successors `s` of `o` (a stop of step t − 1) with a value at
    /// step `t`, each with its pair gain.
    fn out(&self, t: usize, o: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let at = self.first[(t - 1) * self.n + o];
        let succ = if at == u32::MAX {
            &[][..]
        } else {
            self.grid.motion.successors(o)
        };
        succ.iter().enumerate().filter_map(move |(k, &s)| {
            let w = self.pairs[at as usize + k];
            (!w.is_nan()).then_some((s as usize, w))
        })
    }

    /// `togo[t·n + o]`: the best score of steps t+1..=T from `o` at step t
    /// by pair gains, each stop's score `cost(t, s)` plus its pair gain
    /// (`NONE` where no completion exists).
    fn programme(&self, cost: impl Fn(usize, usize) -> Lex) -> Vec<Lex> {
        let (h, n) = (self.grid.horizon(), self.n);
        let mut togo = vec![Lex::NONE; (h + 1) * n];
        togo[h * n..].fill(ZERO);
        for t in (0..h).rev() {
            for o in 0..n {
                let mut best = Lex::NONE;
                for (s, w) in self.out(t + 1, o) {
                    let mut here = cost(t + 1, s);
                    here.value += w;
                    best = best.max(here.add(togo[(t + 1) * n + s]));
                }
                togo[t * n + o] = best;
            }
        }
        togo
    }
}

/// The depth-first search's state.
struct Search<'s> {
    edges: &'s Edges<'s>,
    gain: &'s dyn PathGain,
    togo: &'s [Lex],
    budget: usize,
    evaluated: usize,
    /// The budget ran out.
    cut: bool,
    /// The prefix's stops, and its grid indices.
    stops: Vec<Stop>,
    cells: Vec<usize>,
    best_cells: Vec<usize>,
    best: Lex,
    offset: &'s dyn Fn(usize) -> (i32, i32),
    violations: &'s dyn Fn(usize, usize) -> f64,
}

impl Search<'_> {
    /// The exact score of a whole path of grid indices.
    fn score(&mut self, cells: &[usize]) -> Lex {
        self.evaluated += cells.len();
        score(self.gain, self.offset, self.violations, cells)
    }

    /// Extends the prefix ending at `o` after step `t` (score `so_far`).
    fn descend(&mut self, o: usize, t: usize, so_far: Lex) {
        let (h, n) = (self.edges.grid.horizon(), self.edges.n);
        if t == h {
            if so_far.better(self.best) {
                self.best = so_far;
                self.best_cells.clone_from(&self.cells);
            }
            return;
        }
        let edges = self.edges;
        for (s, w) in edges.out(t + 1, o) {
            let neg_violations = -(self.violations)(t + 1, s);
            let bound = Lex {
                neg_violations,
                value: w,
            };
            if !so_far
                .add(bound)
                .add(self.togo[(t + 1) * n + s])
                .better(self.best)
            {
                continue;
            }
            let at = (self.offset)(s);
            // Steps 1 and 2: the pair gain is the exact gain.
            let value = if t < 2 {
                w
            } else {
                if self.evaluated >= self.budget {
                    self.cut = true;
                    return;
                }
                self.evaluated += 1;
                self.gain.gain(t + 1, at, &self.stops)
            };
            let score = so_far.add(Lex {
                neg_violations,
                value,
            });
            if score.add(self.togo[(t + 1) * n + s]).better(self.best) {
                self.stops.push((t + 1, at));
                self.cells.push(s);
                self.descend(s, t + 1, score);
                self.stops.pop();
                self.cells.pop();
            }
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
        fn gain(&self, t: usize, at: (i32, i32), earlier: &[Stop]) -> f64 {
            let held = |stops: &[Stop]| {
                let mut seen = std::collections::HashSet::new();
                for &(u, (dc, dr)) in stops {
                    seen.extend(self.holds[&(u, dc, dr)].iter().copied());
                }
                seen
            };
            let before = held(earlier);
            let mut after = before.clone();
            after.extend(self.holds[&(t, at.0, at.1)].iter().copied());
            after.difference(&before).map(|&i| self.weights[i]).sum()
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
    fn a_cut_search_keeps_a_legal_path_scored_exactly_and_a_true_upper_bound() {
        let mut rng = StdRng::seed_from_u64(11);
        let mut cut_cases = 0;
        for case in 0..20 {
            let mut grid = ValueGrid::new(4);
            let cov = Coverage::random(&grid, 8, &mut rng);
            cov.fill(&mut grid);
            let cut = best_path_bounded(&grid, &cov, 0);
            cut_cases += usize::from(!cut.exhaustive);
            let (_, optimum) = exhaustive(&grid, &cov);
            assert!(cut.upper >= optimum - 1e-12, "case {case}");
            assert!(cut.best.value <= optimum + 1e-12, "case {case}");
            assert_eq!(grid.first_illegal_step(&cut.best.moves), None);
            let stops = cut.best.offsets();
            assert!((cov.value(&stops) - cut.best.value).abs() < 1e-12);
            if cut.exhaustive {
                assert!((cut.best.value - optimum).abs() < 1e-12, "case {case}");
            }
        }
        assert!(cut_cases > 0, "no search was cut: the test tests nothing");
    }
}
