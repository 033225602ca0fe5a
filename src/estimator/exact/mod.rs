//! The exact estimator: the conditional expectation of the count under the
//! model, given what the sensors saw now and in the history.
//!
//! Split by stage: [`rays`] (the angular grid of each source), [`seen`]
//! (seen sets along rays), [`windows`] (per-step unseen mass over the
//! elementary grid) and, here, the per-cell values.

mod carry;
mod cell_sights;
mod first;
mod rays;
mod seen;
mod sight_index;
mod sighted;
mod stored;
#[cfg(test)]
mod tests;
mod windows;

use rayon::prelude::*;

pub use carry::{Carry, CarryUse};
pub use first::{FirstDetections, PathCover};
use rays::{ClassRays, LookKey, look_key};
pub use rays::{
    INDEX_CROSSINGS_PER_CELL, MIN_INDEX_CROSSINGS, RAYS_PER_PI, RAYS_PER_PI_SQUARE, SourceRays,
};
use seen::RayHits;
pub use sight_index::SightIndex;
pub use windows::ONE_WINDOW_RECTANGLES;
use windows::{SeenRays, StepWindows, Window};

use super::elementary::ElementaryGrid;
use super::{Elements, Estimator, Target};
use crate::geometry::{Point, Region, detection_within, union_within};
use crate::obstacle::Sight;
use crate::scenario::{Cell, Look, Scenario};
use crate::search::ValueGrid;
use crate::stats::Stats;

/// The most rectangles [`Estimator::elements`] lists at one step: a fleet
/// spread over a larger block of a large grid gets no relaxation (its
/// certificate falls back to the marginal bound), so the memory and the
/// time of one step of it stay small.
const MAX_ELEMENTS: usize = 1 << 16;

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
/// Detection probabilities: a look detects a target inside it with its
/// type's `p_detect`, independently of every other look. A target that was
/// inside looks and never reported is still unseen with probability
/// `Π (1 − p)` over them, so each ray's seen set carries, piece by piece,
/// `1 − Π (1 − p)` instead of 1 (see `seen`). At the sensor's own cell
/// a target counts `p_detect` of the sensor, times `Π (1 − p)` over the
/// excluded looks that hold it: summed in rank order these marginals give
/// `1 − Π (1 − p)` over the sensors, the chance that at least one detects
/// it, in any order. Certain looks (`p = 1`) reduce every product to the
/// union and the exclusion of the paper's sensors.
///
/// Two evaluations of the same integral:
/// - for square fields of view (and cells near a sensor), the seen part is
///   accumulated once per sensor and step into the elementary rectangles of
///   its reach ([`ElementaryGrid`]), by walking each ray's seen intervals
///   through them; a cell is then a block sum, and exclusions (unions of
///   rectangles) are masked exactly. Where the rays' crossings are indexed,
///   each ray's length in a rectangle is scaled by the rectangle's area
///   correction (its exact measure from the source over the rays'
///   sample of it), which halves the rule's mean error;
/// - otherwise, per cell, by integrating every ray that crosses it (the
///   plain rule: the windows give the same values to rounding with
///   [`SourceRays::plain_midpoint`]).
pub struct ExactEstimator<'a> {
    scenario: &'a Scenario,
    /// Per field of view (the scenario's `fovs`).
    stats: &'a [Stats],
    rays: &'a [SourceRays],
    grid: Option<&'a ElementaryGrid>,
    known: Vec<Target>,
    /// With obstacles, per known target, its speed and how far it flies
    /// before a building ends its flight ([`crate::obstacle::Obstacles::flight`]).
    flights: Vec<(f64, f64)>,
    /// With obstacles, per sensor, what the plan keeps of its looks over
    /// its reach.
    ground: Vec<cell_sights::GroundReach>,
    /// With obstacles, what each group of overlapping excluded looks that
    /// obstacles cut detects, kept for the plan's fills.
    cut_detections: cell_sights::CutDetections,
    /// With obstacles, the scenario's index of what ground looks cannot
    /// see, when it has one (read before `ground`'s caches).
    sight_index: Option<&'a SightIndex>,
    /// The target classes, each on its source's rays.
    classes: Vec<ClassRays>,
    /// Per class (aligned with `classes`), where its rays crossed what was
    /// seen.
    seen: Vec<RayHits>,
    /// Sensors' starts, whose windows the fast path uses.
    starts: Vec<Cell>,
    /// Sensors' types.
    types: Vec<usize>,
    /// Per step 1..=T: the blocks to accumulate, the window of each (built
    /// on first use), and which block serves each sensor.
    windows: Vec<StepWindows>,
}

/// What a scenario precomputed once, which every exact estimator of it
/// reads.
#[derive(Debug, Clone, Copy)]
pub struct Precomputed<'a> {
    /// The scenario.
    pub scenario: &'a Scenario,
    /// Its statistics per field of view (its `fovs`).
    pub stats: &'a [Stats],
    /// Its sources' rays.
    pub rays: &'a [SourceRays],
    /// Its elementary grid (square fields of view only).
    pub grid: Option<&'a ElementaryGrid>,
    /// What its ground looks cannot see, cell by cell, on `rays` (see
    /// [`SightIndex::new`]).
    pub sights: Option<&'a SightIndex>,
}

/// What the sensors know and where they are, for one plan.
#[derive(Debug, Clone, Copy)]
pub struct Situation<'a> {
    /// `observed[s]`: the looks taken `s` steps ago (index 0: now).
    pub observed: &'a [Vec<Look>],
    /// The targets detected (tracked) now.
    pub targets: &'a [Target],
    /// The sensors' cells now.
    pub starts: &'a [Cell],
    /// The sensors' types (indices into the scenario's).
    pub types: &'a [usize],
    /// The longest path planned, steps.
    pub horizon: usize,
}

impl<'a> ExactEstimator<'a> {
    /// What the sensors saw along the classes' rays, which windows are
    /// filled from.
    fn seen_rays(&self) -> SeenRays<'_> {
        SeenRays {
            rays: self.rays,
            classes: &self.classes,
            seen: &self.seen,
        }
    }

    /// Prepares the estimator of a scenario's `precomputed` pieces for the
    /// sensors of `now`. Targets outside the zone are ignored: they have
    /// left it, or have not entered and cannot have been seen. With a grid
    /// (square fields of view) values near the sensors use the fast path.
    pub fn new(precomputed: Precomputed<'a>, now: Situation<'_>) -> Self {
        Self::build(precomputed, now, None)
    }

    /// [`ExactEstimator::new`], its seen sets (and, by
    /// [`ExactEstimator::prepare_carried`], its windows) made from `carry`,
    /// which a step of the same session left, and kept in it for the next:
    /// the same values to rounding (see [`Carry`]). `planner` identifies the
    /// planner whose `precomputed` pieces these are: a carry made by another
    /// starts over.
    pub fn carried(
        precomputed: Precomputed<'a>,
        now: Situation<'_>,
        planner: u64,
        carry: &mut Carry,
    ) -> Self {
        Self::build(precomputed, now, Some((planner, carry)))
    }

    fn build(
        precomputed: Precomputed<'a>,
        now: Situation<'_>,
        carry: Option<(u64, &mut Carry)>,
    ) -> Self {
        let Precomputed { scenario, rays, .. } = precomputed;
        let observed = now.observed;
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
        let carried = carry
            .and_then(|(planner, carry)| carry.seen(planner, scenario, rays, &classes, observed));
        let seen = match carried {
            Some(seen) => seen,
            None => Self::seen_sets(scenario, rays, &classes, observed),
        };
        Self::with_seen(precomputed, now, classes, seen)
    }

    /// Each class's seen set of `observed`.
    fn seen_sets(
        scenario: &Scenario,
        rays: &[SourceRays],
        classes: &[ClassRays],
        observed: &[Vec<Look>],
    ) -> Vec<RayHits> {
        // Each look's field of view as indexed by the rays, once for all
        // the classes.
        let keys: Vec<Vec<Option<LookKey>>> =
            if rays.iter().any(|r| r.looks.is_some()) && !scenario.has_obstacles() {
                observed
                    .iter()
                    .map(|step| step.iter().map(|l| look_key(scenario, &l.region)).collect())
                    .collect()
            } else {
                Vec::new()
            };
        // What each look cannot see, once for all the classes.
        let sights: Vec<Vec<Option<Sight>>> = if scenario.has_obstacles() {
            observed
                .iter()
                .map(|step| step.iter().map(|l| scenario.sight(l)).collect())
                .collect()
        } else {
            Vec::new()
        };
        // A source's classes are consecutive and share its rays: their
        // seen sets are made together.
        let sources: Vec<&[ClassRays]> = classes.chunk_by(|a, b| a.rays == b.rays).collect();
        let by_source: Vec<Vec<RayHits>> = sources
            .par_iter()
            .with_min_len(crate::parallel::min_len())
            .map(|cs| {
                let speeds: Vec<f64> = cs.iter().map(|c| c.speed).collect();
                let hits =
                    RayHits::for_classes(&rays[cs[0].rays], observed, &keys, &sights, &speeds);
                // The sighted path measures parts of rays by prefix sums.
                if scenario.has_obstacles() {
                    hits.into_iter().map(RayHits::with_prefix).collect()
                } else {
                    hits
                }
            })
            .collect();
        by_source.into_iter().flatten().collect()
    }

    /// The estimator of `now` with its classes' seen sets.
    fn with_seen(
        precomputed: Precomputed<'a>,
        now: Situation<'_>,
        classes: Vec<ClassRays>,
        seen: Vec<RayHits>,
    ) -> Self {
        let Precomputed {
            scenario,
            stats,
            rays,
            grid,
            sights: sight_index,
        } = precomputed;
        let Situation {
            targets,
            starts,
            types,
            horizon,
            ..
        } = now;

        let grid = grid.filter(|_| scenario.all_square());
        let known: Vec<Target> = targets
            .iter()
            .copied()
            .filter(|tg| scenario.in_zone(tg.pos))
            .collect();
        let flights = if scenario.has_obstacles() {
            known
                .iter()
                .map(|tg| scenario.obstacles.flight(tg.pos, tg.vel))
                .collect()
        } else {
            Vec::new()
        };
        let ground = if scenario.has_obstacles() {
            starts
                .iter()
                .zip(types)
                .map(|(&start, &ty)| {
                    let ty = &scenario.types[ty];
                    // An elevated sensor sees its whole square: no cell.
                    let extent = if ty.elevated {
                        -1
                    } else {
                        (ty.speed * horizon) as i32
                    };
                    cell_sights::GroundReach {
                        // The scenario's index, when it has one, holds every
                        // ground field of view at every cell already.
                        sights: sight_index
                            .is_none()
                            .then(|| cell_sights::SightCache::new(start, extent, 1)),
                        hidden_unseen: cell_sights::ReachCache::new(start, extent, horizon),
                    }
                })
                .collect()
        } else {
            Vec::new()
        };
        Self {
            scenario,
            stats,
            rays,
            grid,
            known,
            flights,
            ground,
            cut_detections: cell_sights::CutDetections::default(),
            sight_index,
            classes,
            seen,
            starts: starts.to_vec(),
            types: types.to_vec(),
            windows: match grid {
                Some(grid) => (1..=horizon)
                    .map(|t| StepWindows::new(grid, scenario, starts, types, t))
                    .collect(),
                None => Vec::new(),
            },
        }
    }

    /// Builds every window now, in parallel (otherwise each is built on
    /// first use).
    pub fn prepare(&self) {
        let Some(grid) = self.grid else { return };
        if let Some(windows) = self.seen_rays().whole_windows(grid, &self.windows) {
            for (step, win) in self.windows.iter().zip(windows) {
                // A window already built on first use keeps its (equal)
                // values.
                let _ = step.built[0].set(win);
            }
            return;
        }
        let jobs: Vec<(usize, usize)> = self
            .windows
            .iter()
            .enumerate()
            .flat_map(|(t, w)| (0..w.blocks.len()).map(move |slot| (t, slot)))
            .collect();
        jobs.par_iter()
            .with_min_len(crate::parallel::min_len())
            .for_each(|&(t, slot)| {
                let step = &self.windows[t];
                step.built[slot]
                    .get_or_init(|| self.seen_rays().window(grid, step.blocks[slot], t + 1));
            });
    }

    /// [`ExactEstimator::prepare`], the windows made from those `carry`
    /// kept when it continues the last step (see [`Carry`]), and kept in
    /// it for the next.
    pub fn prepare_carried(&self, carry: &mut Carry) {
        let Some(grid) = self.grid else { return };
        let windows = match carry.take_windows(self.windows.len()) {
            Some((old, change)) => {
                self.seen_rays()
                    .carried_windows(grid, &self.windows, old, &change)
            }
            None => None,
        };
        let windows = windows.or_else(|| self.seen_rays().whole_windows(grid, &self.windows));
        let Some(windows) = windows else {
            self.prepare();
            return;
        };
        if !carry.is_empty() {
            carry.keep_windows(windows.clone());
        }
        for (step, win) in self.windows.iter().zip(windows) {
            let _ = step.built[0].set(win);
        }
    }

    /// The window serving `sensor` at step `t`, if the fast path applies.
    fn window_of(&self, sensor: usize, t: usize) -> Option<(&ElementaryGrid, &Window)> {
        let grid = self.grid?;
        let step = self.windows.get(t.checked_sub(1)?)?;
        let slot = *step.slot.get(sensor)?;
        let win =
            step.built[slot].get_or_init(|| self.seen_rays().window(grid, step.blocks[slot], t));
        Some((grid, win))
    }

    /// Known targets at step `t` inside `fk`, each weighed by the
    /// probability that every excluded look misses it.
    fn known_in(&self, fk: &Region, t: usize, excluded: &[&Look]) -> f64 {
        self.known
            .iter()
            .map(|tg| {
                let p = tg.at(t);
                if fk.contains(p) {
                    miss_all(excluded, p)
                } else {
                    0.0
                }
            })
            .sum()
    }

    /// `U` by integrating every ray that crosses `fk` (the general path),
    /// for the field of view `slot`.
    fn unseen_by_rays(
        &self,
        k: Cell,
        slot: usize,
        fk: &Region,
        t: usize,
        excluded: &[&Look],
    ) -> f64 {
        let d_hat = self.stats[slot].d_hat[self.scenario.index(k)];
        if !excluded.iter().all(|x| x.p_detect == 1.0) || !self.seen.iter().all(RayHits::certain) {
            return d_hat - self.detected_by_rays(fk, t, excluded);
        }
        let excluded: Vec<&Region> = excluded.iter().map(|x| &x.region).collect();
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
                for x in &excluded {
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
        d_hat - seen
    }

    /// The expected targets in `fk` at step `t` that were detected, or that
    /// an excluded look detects, by the rays: `∫ ρ (1 − Π (1 − p))` with the
    /// product over the seen pieces and the excluded looks that hold a
    /// point.
    fn detected_by_rays(&self, fk: &Region, t: usize, excluded: &[&Look]) -> f64 {
        let mut buf = Vec::new();
        let mut intervals: Vec<(f64, f64, f64)> = Vec::new();
        let mut events = Vec::new();
        let mut seen = 0.0;
        for (class, hits) in self.classes.iter().zip(&self.seen) {
            let sr = &self.rays[class.rays];
            let lift = class.speed * t as f64;
            let Some((a, b)) = sr.range(fk, &mut buf) else {
                continue;
            };
            let mut sum = 0.0;
            for m in a..b {
                let (iv, detected) = (hits.of(m), hits.detected(m));
                if excluded.is_empty() && iv.is_empty() {
                    continue;
                }
                let (d, inv) = sr.dirs[m];
                let Some((lo, hi)) = fk.ray(sr.source.pos, d, inv) else {
                    continue;
                };
                intervals.clear();
                for (i, &(p, q)) in iv.iter().enumerate() {
                    if q + lift > lo && p + lift < hi {
                        let pd = if detected.is_empty() {
                            1.0
                        } else {
                            detected[i]
                        };
                        intervals.push((p + lift, q + lift, pd));
                    }
                }
                for x in excluded {
                    if let Some((p, q)) = x.region.ray(sr.source.pos, d, inv) {
                        intervals.push((p, q, x.p_detect));
                    }
                }
                if !intervals.is_empty() {
                    sum += detection_within(&intervals, lo, hi, &mut events);
                }
            }
            seen += class.weight * sum;
        }
        seen
    }

    /// The same value by the general path, for checks.
    pub fn value_by_rays(&self, sensor: usize, k: Cell, t: usize, excluded: &[Look]) -> f64 {
        if self.scenario.has_obstacles() {
            return self.value_sighted(sensor, k, t, excluded);
        }
        let ty = &self.scenario.types[self.types[sensor]];
        let fk = self.scenario.fov_region_of(self.types[sensor], k);
        let excluded: Vec<&Look> = excluded
            .iter()
            .filter(|x| x.region.may_overlap(&fk))
            .collect();
        ty.p_detect
            * (self.known_in(&fk, t, &excluded)
                + self.unseen_by_rays(k, ty.fov_slot, &fk, t, &excluded))
    }

    /// A box holding every field of view `sensor` may have at step `t`
    /// from `start`: the start's, grown by the cells it may move (and one
    /// more, for rounding).
    fn reach(&self, sensor: usize, start: Cell, t: usize) -> crate::geometry::Rect {
        let s = self.scenario;
        let ty = self.types[sensor];
        let r = s.fov_region_of(ty, start).rect;
        let m = s.cell_size * (s.types[ty].speed * t + 1) as f64;
        crate::geometry::Rect {
            x0: r.x0 - m,
            y0: r.y0 - m,
            x1: r.x1 + m,
            y1: r.y1 + m,
        }
    }

    /// The block of elementary rectangles that every field of view
    /// `sensor` may have at step `t` from `start` makes up.
    fn reach_block(
        &self,
        grid: &ElementaryGrid,
        sensor: usize,
        start: Cell,
        t: usize,
    ) -> super::elementary::Block {
        let s = self.scenario;
        let ty = &s.types[self.types[sensor]];
        let (first, last) = s.reach_corners(start, (ty.speed * t) as i32);
        let (lo, _, blo, _) = grid.span(ty.fov_slot, first);
        let (_, hi, _, bhi) = grid.span(ty.fov_slot, last);
        (lo, hi, blo, bhi)
    }

    /// The sensor's window at step `t`, when it holds `k`'s block.
    fn block(&self, sensor: usize, k: Cell, t: usize) -> Option<&Window> {
        let (grid, win) = self.window_of(sensor, t)?;
        let slot = self.scenario.types[self.types[sensor]].fov_slot;
        let (a0, a1, b0, b1) = grid.span(slot, k);
        (a0 >= win.a0 && b0 >= win.b0 && a1 <= win.a0 + win.na && b1 <= win.b0 + win.nb)
            .then_some(win)
    }
}

/// The probability that every look of `looks` that holds `p` misses a
/// target there: 1 when none holds it, 0 when a certain one does.
#[inline]
fn miss_all(looks: &[&Look], p: Point) -> f64 {
    let mut miss = 1.0;
    for x in looks {
        if x.region.contains(p) {
            miss *= x.miss();
            if miss == 0.0 {
                break;
            }
        }
    }
    miss
}

impl Estimator for ExactEstimator<'_> {
    fn scenario(&self) -> &Scenario {
        self.scenario
    }

    fn value(&self, sensor: usize, k: Cell, t: usize, excluded: &[Look]) -> f64 {
        if self.scenario.has_obstacles() {
            return self.value_sighted(sensor, k, t, excluded);
        }
        let ty = &self.scenario.types[self.types[sensor]];
        let fk = self.scenario.fov_region_of(self.types[sensor], k);
        let near: Vec<&Look> = excluded
            .iter()
            .filter(|x| x.region.may_overlap(&fk))
            .collect();
        let known = self.known_in(&fk, t, &near);
        let (Some(grid), Some(win)) = (self.grid, self.block(sensor, k, t)) else {
            return ty.p_detect * (known + self.unseen_by_rays(k, ty.fov_slot, &fk, t, &near));
        };
        let near: Vec<Look> = near.into_iter().copied().collect();
        let block = grid.span(ty.fov_slot, k);
        let unseen = win.block_sums(grid, block, &near).sum(block);
        ty.p_detect * (known + unseen)
    }

    fn fill(&self, sensor: usize, start: Cell, t: usize, excluded: &[Look], out: &mut ValueGrid) {
        let s = self.scenario;
        if s.has_obstacles() {
            self.fill_sighted(sensor, start, t, excluded, out);
            return;
        }
        let Some((grid, win)) = self
            .window_of(sensor, t)
            .filter(|_| self.starts.get(sensor) == Some(&start))
        else {
            out.fill_step(t, |dc, dr| {
                s.lattice_cell(start, dc, dr)
                    .map(|k| self.value(sensor, k, t, excluded))
            });
            return;
        };
        let ty = &s.types[self.types[sensor]];
        // Prefix sums of the (masked) unseen mass over the sensor's reach.
        let sums = win.block_sums(grid, self.reach_block(grid, sensor, start, t), excluded);
        // Known targets at step t, each with the chance that every excluded
        // look misses it: those no look holds are counted (an integer count
        // is the hot loop's cheapest form), the others summed by weight.
        let all: Vec<&Look> = excluded.iter().collect();
        let mut clear: Vec<Point> = Vec::with_capacity(self.known.len());
        let mut partial: Vec<(Point, f64)> = Vec::new();
        // Only targets some field of view of the reach can hold: every one
        // lies within the start's, moved by at most `ti` cells (a cell more
        // for rounding). Most of a zone's targets are far from one sensor.
        let reach = self.reach(sensor, start, t);
        for p in self.known.iter().map(|tg| tg.at(t)) {
            if !s.in_zone(p) || !reach.contains(p) {
                continue;
            }
            match miss_all(&all, p) {
                1.0 => clear.push(p),
                0.0 => {}
                miss => partial.push((p, miss)),
            }
        }
        let k = (ty.speed * t) as i32;
        let cells = ((2 * k + 1) * (2 * k + 1)) as usize;
        // Few targets: testing each cell against each is cheaper than the
        // blocks' buffers, and gives the same values.
        let blocks = ((clear.len() + partial.len()) * cells > BLOCKS_FROM)
            .then(|| KnownInViews::new(s, self.types[sensor], start, k, &clear, &partial));
        out.fill_step(t, |dc, dr| {
            let cell = s.lattice_cell(start, dc, dr)?;
            let unseen = sums.sum(grid.span(ty.fov_slot, cell));
            let known = match &blocks {
                Some(blocks) => blocks.at(dc, dr),
                None => {
                    let fk = s.fov_region_of(self.types[sensor], cell);
                    let mut known = clear.iter().filter(|&&p| fk.contains(p)).count() as f64;
                    if !partial.is_empty() {
                        known += partial
                            .iter()
                            .filter(|(p, _)| fk.contains(*p))
                            .map(|&(_, miss)| miss)
                            .sum::<f64>();
                    }
                    known
                }
            };
            Some(ty.p_detect * (known + unseen))
        });
    }

    fn elements(&self, t: usize) -> Option<Elements<'_>> {
        // A ground look sees part of its rectangles: no relaxation over
        // them (the certificate takes the marginal bound).
        if self.scenario.has_obstacles() {
            return None;
        }
        let grid = self.grid?;
        let step = self.windows.get(t.checked_sub(1)?)?;
        let (mut a0, mut a1, mut b0, mut b1) = (usize::MAX, 0, usize::MAX, 0);
        for &(x0, x1, y0, y1) in &step.blocks {
            (a0, a1, b0, b1) = (a0.min(x0), a1.max(x1), b0.min(y0), b1.max(y1));
        }
        let (na, nb) = (a1.checked_sub(a0)?, b1.checked_sub(b0)?);
        if na == 0 || nb == 0 || na * nb > MAX_ELEMENTS {
            return None;
        }
        let mut mass = vec![0.0; na * nb];
        // Each window once: sensors may share one (a whole grid's).
        let mut slots: Vec<usize> = step.slot.clone();
        slots.sort_unstable();
        slots.dedup();
        for slot in slots {
            let sensor = step.slot.iter().position(|&s| s == slot)?;
            let (_, win) = self.window_of(sensor, t)?;
            for b in 0..win.nb {
                let row = (win.b0 + b - b0) * na + win.a0 - a0;
                mass[row..row + win.na].copy_from_slice(win.row(b));
            }
        }
        Some(Elements {
            grid,
            a0,
            b0,
            na,
            nb,
            mass,
            known: self
                .known
                .iter()
                .map(|tg| tg.at(t))
                .filter(|&p| self.scenario.in_zone(p))
                .collect(),
        })
    }

    fn order_independent(&self) -> bool {
        true
    }
}

/// Cells × known targets past which a windowed fill counts the targets
/// per view block ([`KnownInViews`]) rather than testing every cell
/// against every target (the two give the same values).
pub const BLOCKS_FROM: usize = 2048;

/// The known targets in the square field of view of a sensor's type at
/// every cell within `k` cells of its start: those no excluded look holds
/// counted, and the others summed by the chance that every excluded look
/// misses them. A square's edges move with its cell, so the cells whose
/// view holds a target are a block: a run of columns (decided by `x`
/// alone) times a run of rows. The runs are found with the views' own
/// rectangles, so a cell holds exactly the targets its view's containment
/// test holds. Counts add 1 over each block (by differences and prefix
/// sums, O(cells + targets)); weights are added cell by cell of each block
/// in the targets' order, the order the per-cell sum took, so every value
/// is the same to the bit as testing each cell against every target.
struct KnownInViews {
    k: i32,
    side: usize,
    counts: Vec<u32>,
    /// Empty when no target is partly seen.
    weights: Vec<f64>,
}

impl KnownInViews {
    fn new(
        s: &Scenario,
        ty: usize,
        start: Cell,
        k: i32,
        clear: &[Point],
        partial: &[(Point, f64)],
    ) -> Self {
        let side = (2 * k + 1) as usize;
        let view = s.fov_region_of(ty, start).rect;
        let span = ((view.x1 - view.x0).max(view.y1 - view.y0) / s.cell_size).ceil() as i32 + 1;
        // The run of offsets along one axis whose views hold coordinate
        // `v`, from the cell holding it (`centre`); `edges(d)` is the view's
        // extent along the axis at offset `d` (it depends on no other).
        let run = |centre: i32, v: f64, edges: &dyn Fn(i32) -> (f64, f64)| {
            let holds = |d: i32| {
                let (a, b) = edges(d);
                a <= v && v <= b
            };
            let (lo, hi) = ((centre - span).max(-k), (centre + span).min(k));
            let first = (lo..=hi).find(|&d| holds(d))?;
            let last = (first..=hi).take_while(|&d| holds(d)).last()?;
            Some((first, last))
        };
        let x_edges = |d: i32| {
            let r = s.fov_region_of(ty, start.offset(d, 0)).rect;
            (r.x0, r.x1)
        };
        let y_edges = |d: i32| {
            let r = s.fov_region_of(ty, start.offset(0, d)).rect;
            (r.y0, r.y1)
        };
        let block = |p: Point| {
            let cc = (p.x / s.cell_size).floor() as i32 - start.col;
            let cr = (p.y / s.cell_size).floor() as i32 - start.row;
            Some((run(cc, p.x, &x_edges)?, run(cr, p.y, &y_edges)?))
        };
        // One more row and column for the differences' ends.
        let wide = side + 1;
        let at = |dc: i32, dr: i32, width: usize| (dr + k) as usize * width + (dc + k) as usize;
        let mut diff = vec![0i64; wide * wide];
        for &p in clear {
            if let Some(((a0, a1), (b0, b1))) = block(p) {
                diff[at(a0, b0, wide)] += 1;
                diff[at(a1 + 1, b0, wide)] -= 1;
                diff[at(a0, b1 + 1, wide)] -= 1;
                diff[at(a1 + 1, b1 + 1, wide)] += 1;
            }
        }
        let mut counts = vec![0u32; side * side];
        let mut above = vec![0i64; side];
        for r in 0..side {
            let mut left = 0i64;
            for c in 0..side {
                left += diff[r * wide + c];
                above[c] += left;
                counts[r * side + c] = above[c] as u32;
            }
        }
        let mut weights = Vec::new();
        if !partial.is_empty() {
            weights = vec![0.0; side * side];
            for &(p, miss) in partial {
                if let Some(((a0, a1), (b0, b1))) = block(p) {
                    for dr in b0..=b1 {
                        for dc in a0..=a1 {
                            weights[at(dc, dr, side)] += miss;
                        }
                    }
                }
            }
        }
        KnownInViews {
            k,
            side,
            counts,
            weights,
        }
    }

    /// The known targets at offset `(dc, dr)` (each within `k`).
    fn at(&self, dc: i32, dr: i32) -> f64 {
        let i = (dr + self.k) as usize * self.side + (dc + self.k) as usize;
        let count = f64::from(self.counts[i]);
        match self.weights.get(i) {
            Some(&w) => count + w,
            None => count,
        }
    }
}
