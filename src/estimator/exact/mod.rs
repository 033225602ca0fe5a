//! The exact estimator: the conditional expectation of the count under the
//! model, given what the sensors saw now and in the history.
//!
//! Split by stage: [`rays`] (the angular grid of each source), [`seen`]
//! (seen sets along rays), [`windows`] (per-step unseen mass over the
//! elementary grid) and, here, the per-cell values.

mod rays;
mod seen;
mod windows;

use rayon::prelude::*;

pub use rays::{RAYS_PER_PI, RAYS_PER_PI_SQUARE, SourceRays};
use seen::RayHits;
use windows::{StepWindows, Window};

use super::elementary::ElementaryGrid;
use super::{Estimator, Target, for_reach};
use crate::geometry::{Point, Region, union_within};
use crate::scenario::{Cell, FovSpec, Scenario};
use crate::search::ValueGrid;
use crate::stats::Stats;

/// The exact conditional expectation of the count in `F_k` at step `t`:
/// the reported targets whose straight-line position is in `F_k`, plus
/// `U(k,t)`, the expected targets in `F_k` that no sensor can have seen.
///
/// With `O_s` the union of the fields of view `s` steps ago, a point `q` on
/// the ray of angle `α` from source `j` at distance `r` holds at step `t` a
/// target of class `c` (speed `v_c`) that was at distance `r − v_c(t+s)` at
/// step `−s` (not yet emitted if that is negative, and then unseen). It is
/// unseen when none of those backtracked points lies in `O_s`. The class's
/// stationary density in polar coordinates around its source is
/// `λ_c/(spread_j v_c)·dr·dα` over the cone, so
/// `U(k,t) = d̂_k − Σ_c λ_c/(spread_j v_c) ∫ |R_k(α) ∩ ⋃_s (O_s(α) + v_c(t+s))| dα`:
/// the closed-form stationary count less the seen part, measured on each
/// ray by interval arithmetic and integrated over `α` by the midpoint rule
/// on a fixed grid of rays per π over the cone ([`RAYS_PER_PI_SQUARE`] or
/// [`RAYS_PER_PI`]). The classes of a source share its rays; each has its
/// own seen set, since the backtracking distance depends on the speed.
/// Excluded regions are removed the same way (unshifted), and known targets
/// (with their own reported velocities) inside them are not counted.
///
/// Two evaluations of the same integral:
/// - for square fields of view (and cells near a sensor), the seen part is
///   accumulated once per sensor and step into the elementary rectangles of
///   its reach ([`ElementaryGrid`]), by walking each ray's seen intervals
///   through them; a cell is then a block sum, and exclusions (unions of
///   rectangles) are masked exactly;
/// - otherwise, per cell, by integrating every ray that crosses it.
pub struct ExactEstimator<'a> {
    scenario: &'a Scenario,
    stats: &'a Stats,
    rays: &'a [SourceRays],
    grid: Option<&'a ElementaryGrid>,
    known: Vec<Target>,
    /// The target classes, each on its source's rays.
    classes: Vec<ClassRays>,
    /// Per class (aligned with `classes`), where its rays crossed what was
    /// seen.
    seen: Vec<RayHits>,
    /// Sensors' starts, whose windows the fast path uses.
    starts: Vec<Cell>,
    /// Per step 1..=T: the blocks to accumulate, the window of each (built
    /// on first use), and which block serves each sensor.
    windows: Vec<StepWindows>,
}

impl<'a> ExactEstimator<'a> {
    /// Prepares the estimator for sensors starting at `starts` and paths of
    /// up to `horizon` steps. `observed[s]` are the regions seen `s` steps
    /// ago (index 0: now). Targets outside the zone are ignored: they have
    /// left it, or have not entered and cannot have been seen. With `grid`
    /// (square fields of view) values near the sensors use the fast path.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        scenario: &'a Scenario,
        stats: &'a Stats,
        rays: &'a [SourceRays],
        grid: Option<&'a ElementaryGrid>,
        observed: &[Vec<Region>],
        targets: &[Target],
        starts: &[Cell],
        horizon: usize,
    ) -> Self {
        let classes: Vec<ClassRays> = rays
            .iter()
            .enumerate()
            .flat_map(|(ri, sr)| {
                scenario
                    .classes_of(sr.source_index)
                    .iter()
                    .map(move |class| ClassRays {
                        rays: ri,
                        speed: class.speed,
                        weight: class.rate / (sr.source.spread * class.speed) * sr.step,
                    })
            })
            .collect();
        let seen = classes
            .par_iter()
            .map(|c| RayHits::new(&rays[c.rays], observed, c.speed))
            .collect();

        let grid = grid.filter(|_| matches!(scenario.fov, FovSpec::Square { .. }));
        Self {
            scenario,
            stats,
            rays,
            grid,
            known: targets
                .iter()
                .copied()
                .filter(|tg| scenario.in_zone(tg.pos))
                .collect(),
            classes,
            seen,
            starts: starts.to_vec(),
            windows: match grid {
                Some(grid) => (1..=horizon)
                    .map(|t| StepWindows::new(grid, scenario, starts, t))
                    .collect(),
                None => Vec::new(),
            },
        }
    }

    /// Builds every window now, in parallel (otherwise each is built on
    /// first use).
    pub fn prepare(&self) {
        let Some(grid) = self.grid else { return };
        let jobs: Vec<(usize, usize)> = self
            .windows
            .iter()
            .enumerate()
            .flat_map(|(t, w)| (0..w.blocks.len()).map(move |slot| (t, slot)))
            .collect();
        jobs.par_iter().for_each(|&(t, slot)| {
            let step = &self.windows[t];
            step.built[slot].get_or_init(|| self.window(grid, step.blocks[slot], t + 1));
        });
    }

    /// The window serving `sensor` at step `t`, if the fast path applies.
    fn window_of(&self, sensor: usize, t: usize) -> Option<(&ElementaryGrid, &Window)> {
        let grid = self.grid?;
        let step = self.windows.get(t.checked_sub(1)?)?;
        let slot = *step.slot.get(sensor)?;
        let win = step.built[slot].get_or_init(|| self.window(grid, step.blocks[slot], t));
        Some((grid, win))
    }

    /// Known targets at step `t` inside `fk` and outside every excluded region.
    fn known_in(&self, fk: &Region, t: usize, excluded: &[&Region]) -> f64 {
        self.known
            .iter()
            .filter(|tg| {
                let p = tg.at(t);
                fk.contains(p) && !excluded.iter().any(|x| x.contains(p))
            })
            .count() as f64
    }

    /// `U` by integrating every ray that crosses `fk` (the general path).
    fn unseen_by_rays(&self, k: Cell, fk: &Region, t: usize, excluded: &[&Region]) -> f64 {
        let mut buf = Vec::new();
        let mut intervals: Vec<(f64, f64)> = Vec::new();
        let mut seen = 0.0;
        for (class, hits) in self.classes.iter().zip(&self.seen) {
            let sr = &self.rays[class.rays];
            let lift = class.speed * t as f64;
            let Some((a, b)) = sr.range(fk, &mut buf) else {
                continue;
            };
            let mut sum = 0.0;
            for m in a..b {
                let seen = hits.of(m);
                if excluded.is_empty() && seen.is_empty() {
                    continue;
                }
                let (d, inv) = sr.dirs[m];
                let Some((lo, hi)) = fk.ray(sr.source.pos, d, inv) else {
                    continue;
                };
                intervals.clear();
                intervals.extend(
                    seen.iter()
                        .map(|&(p, q)| (p + lift, q + lift))
                        .filter(|&(p, q)| q > lo && p < hi),
                );
                for x in excluded {
                    if let Some(iv) = x.ray(sr.source.pos, d, inv) {
                        intervals.push(iv);
                    }
                }
                if !intervals.is_empty() {
                    sum += union_within(&mut intervals, lo, hi);
                }
            }
            seen += class.weight * sum;
        }
        // Not clamped at 0: the midpoint rule may overshoot d̂ by ~1e-6 in a
        // fully seen cell, and clamping would break the additivity that
        // makes marginals sum to the total.
        self.stats.d_hat[self.scenario.index(k)] - seen
    }

    /// The same value by the general path, for checks.
    pub fn value_by_rays(&self, k: Cell, t: usize, excluded: &[Region]) -> f64 {
        let fk = self.scenario.fov_region(k);
        let excluded: Vec<&Region> = excluded.iter().filter(|x| x.may_overlap(&fk)).collect();
        self.known_in(&fk, t, &excluded) + self.unseen_by_rays(k, &fk, t, &excluded)
    }

    /// The sensor's window at step `t`, when it holds `k`'s block.
    fn block(&self, sensor: usize, k: Cell, t: usize) -> Option<&Window> {
        let (grid, win) = self.window_of(sensor, t)?;
        let (a0, a1, b0, b1) = grid.span(k);
        (a0 >= win.a0 && b0 >= win.b0 && a1 <= win.a0 + win.na && b1 <= win.b0 + win.nb)
            .then_some(win)
    }
}

/// A target class on its source's rays.
struct ClassRays {
    /// Index of the source's rays.
    rays: usize,
    /// The class's speed.
    speed: f64,
    /// `λ_c/(spread·v_c)` times the angular step: targets per unit of ray
    /// length, per ray.
    weight: f64,
}

/// The smaller of two numbers that are not NaN (one `minsd`: `f64::min`
/// also handles NaN, at three instructions, in the hottest loops).
#[inline(always)]
fn min(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// The larger of two numbers that are not NaN.
#[inline(always)]
fn max(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

impl Estimator for ExactEstimator<'_> {
    fn scenario(&self) -> &Scenario {
        self.scenario
    }

    fn value(&self, sensor: usize, k: Cell, t: usize, excluded: &[Region]) -> f64 {
        let fk = self.scenario.fov_region(k);
        let near: Vec<&Region> = excluded.iter().filter(|x| x.may_overlap(&fk)).collect();
        let known = self.known_in(&fk, t, &near);
        let (Some(grid), Some(win)) = (self.grid, self.block(sensor, k, t)) else {
            return known + self.unseen_by_rays(k, &fk, t, &near);
        };
        let near: Vec<Region> = near.into_iter().copied().collect();
        let block = grid.span(k);
        let unseen = self.block_sums(grid, win, block, &near).sum(block);
        known + unseen
    }

    fn fill(&self, sensor: usize, start: Cell, t: usize, excluded: &[Region], out: &mut ValueGrid) {
        let s = self.scenario;
        let Some((grid, win)) = self
            .window_of(sensor, t)
            .filter(|_| self.starts.get(sensor) == Some(&start))
        else {
            for_reach(s, start, t, |dc, dr, k| {
                out.set(t, dc, dr, self.value(sensor, k, t, excluded))
            });
            return;
        };
        // Prefix sums of the (masked) unseen mass over the sensor's reach.
        let ti = t as i32;
        let (lo, _, blo, _) = grid.span(Cell {
            col: (start.col - ti).max(0),
            row: (start.row - ti).max(0),
        });
        let (_, hi, _, bhi) = grid.span(Cell {
            col: (start.col + ti).min(s.cols - 1),
            row: (start.row + ti).min(s.rows - 1),
        });
        let sums = self.block_sums(grid, win, (lo, hi, blo, bhi), excluded);
        // Known targets at step t that no excluded region holds.
        let moved: Vec<Point> = self
            .known
            .iter()
            .map(|tg| tg.at(t))
            .filter(|&p| s.in_zone(p) && !excluded.iter().any(|x| x.contains(p)))
            .collect();
        for_reach(s, start, t, |dc, dr, k| {
            let unseen = sums.sum(grid.span(k));
            let fk = s.fov_region(k);
            let known = moved.iter().filter(|&&p| fk.contains(p)).count() as f64;
            out.set(t, dc, dr, known + unseen);
        });
    }

    fn order_independent(&self) -> bool {
        true
    }
}
