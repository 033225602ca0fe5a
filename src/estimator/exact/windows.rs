//! Step windows: the unseen mass at step `t` of each elementary rectangle
//! near the sensors, accumulated once per step from the seen sets, and the
//! prefix sums that turn a cell's value into four lookups.

use std::sync::OnceLock;

use rayon::prelude::*;

use super::rays::{ClassRays, Crossings, SourceRays, max, min};
use super::seen::RayHits;
use crate::estimator::elementary::{Block, ElementaryGrid, Segment, trace};
use crate::geometry::Region;
use crate::scenario::{Cell, Look, Scenario};

/// Classes whose seen mass is added into one buffer of a window; the
/// buffers are filled in parallel. Fixed, never the thread count, since the
/// grouping decides the order of the sums. Four keeps the answers recorded
/// on two cores for the paper's eight sources.
const CLASSES_PER_BUFFER: usize = 4;

/// A grid of at most this many elementary rectangles gets one window over
/// all of it, and so does the reaches' bounding box when it is at most this
/// large (or twice the reaches): one window is the fastest to fill. The cost
/// model predicts with it.
pub const ONE_WINDOW_RECTANGLES: usize = 1 << 16;

/// Prefix sums over a block of rectangles.
pub(super) struct BlockSums {
    a0: usize,
    b0: usize,
    w: usize,
    prefix: Vec<f64>,
}

impl BlockSums {
    /// The sum over a sub-block (global indices).
    #[inline]
    pub(super) fn sum(&self, (a0, a1, b0, b1): Block) -> f64 {
        let p = |a: usize, b: usize| self.prefix[(b - self.b0) * self.w + (a - self.a0)];
        p(a1, b1) - p(a0, b1) - p(a1, b0) + p(a0, b0)
    }
}

/// The windows of one step: one shared by every sensor when their reaches
/// lie close together (each seen interval is walked once), otherwise one
/// per sensor (memory bounded by the reaches on a large lattice).
pub(super) struct StepWindows {
    pub(super) blocks: Vec<Block>,
    pub(super) built: Vec<OnceLock<Window>>,
    pub(super) slot: Vec<usize>,
}

impl StepWindows {
    pub(super) fn new(
        grid: &ElementaryGrid,
        s: &Scenario,
        starts: &[Cell],
        types: &[usize],
        t: usize,
    ) -> Self {
        let reach: Vec<Block> = starts
            .iter()
            .zip(types)
            .map(|(start, &ty)| {
                let slot = s.types[ty].fov_slot;
                let (lo, hi) = s.reach_corners(*start, (s.types[ty].speed * t) as i32);
                let (a0, _, b0, _) = grid.span(slot, lo);
                let (_, a1, _, b1) = grid.span(slot, hi);
                (a0, a1, b0, b1)
            })
            .collect();
        let size = |b: &Block| (b.1 - b.0) * (b.3 - b.2);
        let bbox = reach.iter().fold((usize::MAX, 0, usize::MAX, 0), |acc, b| {
            (
                acc.0.min(b.0),
                acc.1.max(b.1),
                acc.2.min(b.2),
                acc.3.max(b.3),
            )
        });
        let total: usize = reach.iter().map(size).sum();
        let (nx, ny) = grid.dims();
        if nx * ny <= ONE_WINDOW_RECTANGLES {
            // A small grid: one window over all of it (the fastest to fill).
            Self {
                blocks: vec![(0, nx, 0, ny)],
                built: vec![OnceLock::new()],
                slot: vec![0; reach.len()],
            }
        } else if !reach.is_empty() && size(&bbox) <= ONE_WINDOW_RECTANGLES.max(2 * total) {
            Self {
                blocks: vec![bbox],
                built: vec![OnceLock::new()],
                slot: vec![0; reach.len()],
            }
        } else {
            Self {
                built: reach.iter().map(|_| OnceLock::new()).collect(),
                slot: (0..reach.len()).collect(),
                blocks: reach,
            }
        }
    }
}

/// `u_t(E)` over a block of elementary rectangles: the expected targets in
/// each at step `t` that no sensor can have seen.
#[derive(Clone)]
pub(super) struct Window {
    pub(super) a0: usize,
    pub(super) b0: usize,
    pub(super) na: usize,
    pub(super) nb: usize,
    unseen: Vec<f64>,
}

impl Window {
    /// Heap bytes held.
    pub(super) fn memory_bytes(&self) -> usize {
        self.unseen.capacity() * std::mem::size_of::<f64>()
    }

    /// The unseen mass of the window's row `b` (relative to its first).
    pub(super) fn row(&self, b: usize) -> &[f64] {
        &self.unseen[b * self.na..(b + 1) * self.na]
    }

    /// The window over `block` (global indices, inside this one), a copy.
    pub(super) fn part(&self, (a0, a1, b0, b1): Block) -> Window {
        let (na, nb) = (a1 - a0, b1 - b0);
        let mut unseen = Vec::with_capacity(na * nb);
        for b in b0..b1 {
            let row = (b - self.b0) * self.na + (a0 - self.a0);
            unseen.extend_from_slice(&self.unseen[row..row + na]);
        }
        Window {
            a0,
            b0,
            na,
            nb,
            unseen,
        }
    }

    /// The unseen mass of each rectangle, row by row, to take from.
    pub(super) fn unseen_mut(&mut self) -> &mut [f64] {
        &mut self.unseen
    }

    /// Prefix sums of the unseen mass over `block` (global indices, inside
    /// the window), each rectangle times the probability that every
    /// excluded look misses it (fields of view are unions of rectangles:
    /// those whose centre they contain); a certain look leaves it out.
    pub(super) fn block_sums(
        &self,
        grid: &ElementaryGrid,
        block: Block,
        excluded: &[Look],
    ) -> BlockSums {
        let (a0, a1, b0, b1) = block;
        let w = a1 - a0 + 1;
        let mut prefix = vec![0.0; w * (b1 - b0 + 1)];
        let xc: Vec<f64> = (a0..a1)
            .map(|a| 0.5 * (grid.xs[a] + grid.xs[a + 1]))
            .collect();
        // The excluded looks across each row, in their order (one buffer).
        let mut rows: Vec<&Look> = Vec::with_capacity(excluded.len());
        for (j, b) in (b0..b1).enumerate() {
            let yc = 0.5 * (grid.ys[b] + grid.ys[b + 1]);
            rows.clear();
            rows.extend(
                excluded
                    .iter()
                    .filter(|x| yc >= x.region.rect.y0 && yc <= x.region.rect.y1),
            );
            let mut row = 0.0;
            for (i, a) in (a0..a1).enumerate() {
                let mut miss = 1.0;
                for x in &rows {
                    if xc[i] >= x.region.rect.x0 && xc[i] <= x.region.rect.x1 {
                        miss *= x.miss();
                        if miss == 0.0 {
                            break;
                        }
                    }
                }
                if miss == 1.0 {
                    row += self.unseen[(b - self.b0) * self.na + (a - self.a0)];
                } else if miss > 0.0 {
                    row += miss * self.unseen[(b - self.b0) * self.na + (a - self.a0)];
                }
                prefix[(j + 1) * w + i + 1] = prefix[j * w + i + 1] + row;
            }
        }
        BlockSums { a0, b0, w, prefix }
    }
}

/// One target class at one step: its source's rays, along which what was
/// seen at step 0 has moved on by `lift` (`v·t`), each ray carrying
/// `weight` targets per unit of length.
#[derive(Clone, Copy)]
struct LiftedClass<'a> {
    rays: &'a SourceRays,
    lift: f64,
    weight: f64,
}

/// What the sensors saw, along each target class's rays: the part of the
/// exact estimator a window is filled from.
pub(super) struct SeenRays<'a> {
    /// The sources' rays.
    pub rays: &'a [SourceRays],
    /// The target classes, each on its source's rays.
    pub classes: &'a [ClassRays],
    /// Per class (aligned with `classes`), where its rays crossed what was
    /// seen.
    pub seen: &'a [RayHits],
}

impl SeenRays<'_> {
    /// The unseen mass at step `t` of the elementary rectangles of a block.
    pub(super) fn window(
        &self,
        grid: &ElementaryGrid,
        (a0, a1, b0, b1): Block,
        t: usize,
    ) -> Window {
        let (na, nb) = (a1 - a0, b1 - b0);
        let mut unseen = Vec::with_capacity(na * nb);
        for b in b0..b1 {
            for a in a0..a1 {
                unseen.push(grid.mass(a, a + 1, b, b + 1));
            }
        }
        let block = (a0, a1, b0, b1);
        let whole = {
            let (nx, ny) = grid.dims();
            block == (0, nx, 0, ny)
        };
        // The classes in groups of a fixed size, each group adding into its
        // own buffer, the buffers subtracted in order: the same sums in the
        // same order, so the same plan to the last bit, on any number of
        // threads (groups sized by the thread count made a one-core
        // replica answer differently from a two-core one).
        let per_group: Vec<Vec<f64>> = self
            .classes
            .par_chunks(CLASSES_PER_BUFFER)
            .zip(self.seen.par_chunks(CLASSES_PER_BUFFER))
            .with_min_len(crate::parallel::min_len())
            .map(|(classes, seen)| {
                let mut acc = vec![0.0; na * nb];
                for (class, seen) in classes.iter().zip(seen) {
                    let lifted = LiftedClass {
                        rays: &self.rays[class.rays],
                        lift: class.speed * t as f64,
                        weight: class.weight,
                    };
                    Self::accumulate(grid, block, whole, lifted, seen, &mut acc);
                }
                acc
            })
            .collect();
        let mut per_group = per_group.into_iter();
        if let Some(first) = per_group.next() {
            for (u, s) in unseen.iter_mut().zip(&first) {
                *u -= s;
            }
            for acc in per_group {
                for (u, s) in unseen.iter_mut().zip(&acc) {
                    *u -= s;
                }
            }
        }
        Window {
            a0,
            b0,
            na,
            nb,
            unseen,
        }
    }

    /// Every step's window at once, when each is one window over the whole
    /// grid (a small grid): the rays' seen intervals are read once for all
    /// the steps, and the crossing where a ray's first interval starts is
    /// found from the previous step's (a lift later) instead of by a new
    /// bisection. Each window gets the same sums in the same order as
    /// [`SeenRays::window`] would give it: the same values to the
    /// last bit. `None` when the steps' windows are not all the whole grid
    /// or a ray index is missing.
    pub(super) fn whole_windows(
        &self,
        grid: &ElementaryGrid,
        windows: &[StepWindows],
    ) -> Option<Vec<Window>> {
        let (nx, ny) = grid.dims();
        let whole = (0, nx, 0, ny);
        if windows.is_empty()
            || !windows.iter().all(|w| w.blocks == [whole])
            || self
                .classes
                .iter()
                .any(|c| self.rays[c.rays].crossings.is_none())
        {
            return None;
        }
        let steps = windows.len();
        let per_group: Vec<Vec<Vec<f64>>> = self
            .classes
            .par_chunks(CLASSES_PER_BUFFER)
            .zip(self.seen.par_chunks(CLASSES_PER_BUFFER))
            .with_min_len(crate::parallel::min_len())
            .map(|(classes, seen)| {
                let mut accs = vec![vec![0.0; nx * ny]; steps];
                for (class, seen) in classes.iter().zip(seen) {
                    let sr = &self.rays[class.rays];
                    let Some(cr) = &sr.crossings else { continue };
                    let lifts: Vec<f64> = (1..=steps).map(|t| class.speed * t as f64).collect();
                    let mut views: Vec<&mut [f64]> =
                        accs.iter_mut().map(Vec::as_mut_slice).collect();
                    accumulate_whole(sr, cr, class.weight, seen, &lifts, &mut views);
                }
                accs
            })
            .collect();
        let mut mass = Vec::with_capacity(nx * ny);
        for b in 0..ny {
            for a in 0..nx {
                mass.push(grid.mass(a, a + 1, b, b + 1));
            }
        }
        let windows = (0..steps)
            .map(|t| {
                let mut unseen = mass.clone();
                for accs in &per_group {
                    for (u, s) in unseen.iter_mut().zip(&accs[t]) {
                        *u -= s;
                    }
                }
                Window {
                    a0: 0,
                    b0: 0,
                    na: nx,
                    nb: ny,
                    unseen,
                }
            })
            .collect();
        Some(windows)
    }

    /// Every step's window over the whole grid from `carried`, the
    /// windows of plan steps `1..=T` one session step earlier, and `change`,
    /// per class, what the seen sets gained (+1) and lost (−1) since, as of
    /// now (see [`carry`](super::carry)): the window of step `t < T` is the
    /// carried one of step `t + 1` less the seen mass of the change, that of
    /// step `T` is filled whole. `None` under the conditions of
    /// [`SeenRays::whole_windows`].
    pub(super) fn carried_windows(
        &self,
        grid: &ElementaryGrid,
        windows: &[StepWindows],
        mut carried: Vec<Window>,
        change: &[RayHits],
    ) -> Option<Vec<Window>> {
        let (nx, ny) = grid.dims();
        let whole = (0, nx, 0, ny);
        let steps = windows.len();
        if steps == 0
            || carried.len() != steps
            || change.len() != self.classes.len()
            || !windows.iter().all(|w| w.blocks == [whole])
            || !carried.iter().all(|w| (w.na, w.nb) == (nx, ny))
            || self
                .classes
                .iter()
                .any(|c| self.rays[c.rays].crossings.is_none())
        {
            return None;
        }
        let last = self.window(grid, whole, steps);
        carried.remove(0);
        if !carried.is_empty() {
            let mut accs = vec![vec![0.0; nx * ny]; carried.len()];
            for (class, change) in self.classes.iter().zip(change) {
                let sr = &self.rays[class.rays];
                let Some(cr) = &sr.crossings else { continue };
                let lifts: Vec<f64> = (1..steps).map(|t| class.speed * t as f64).collect();
                let mut views: Vec<&mut [f64]> = accs.iter_mut().map(Vec::as_mut_slice).collect();
                accumulate_whole(sr, cr, class.weight, change, &lifts, &mut views);
            }
            for (win, acc) in carried.iter_mut().zip(&accs) {
                for (u, s) in win.unseen.iter_mut().zip(acc) {
                    *u -= s;
                }
            }
        }
        carried.push(last);
        Some(carried)
    }

    /// Adds to `acc` what the rays of one class saw in each rectangle of
    /// `block` (the whole grid when `whole`), lifted and weighted as
    /// `class` says.
    fn accumulate(
        grid: &ElementaryGrid,
        block: Block,
        whole: bool,
        class: LiftedClass<'_>,
        seen: &RayHits,
        acc: &mut [f64],
    ) {
        let LiftedClass {
            rays: sr,
            lift,
            weight: w,
        } = class;
        if let (true, Some(cr)) = (whole, &sr.crossings) {
            // The block is the grid: every ray, no bounds to check.
            accumulate_whole(sr, cr, w, seen, &[lift], &mut [acc]);
            return;
        }
        let (a0, a1, b0, b1) = block;
        let na = a1 - a0;
        let region = Region {
            rect: crate::geometry::Rect {
                x0: grid.xs[a0],
                y0: grid.ys[b0],
                x1: grid.xs[a1],
                y1: grid.ys[b1],
            },
            disk: None,
        };
        let mut buf = Vec::new();
        let Some((ma, mb)) = sr.range(&region, &mut buf) else {
            return;
        };
        for m in ma..mb {
            let hits = seen.of(m);
            if hits.is_empty() {
                continue;
            }
            let detected = seen.detected(m);
            let weight = |i: usize| {
                if detected.is_empty() {
                    w
                } else {
                    w * detected[i]
                }
            };
            let (d, inv) = sr.dirs[m];
            // The seen union at step t, clipped to the block and to where
            // a building ends the flights along the ray.
            let Some((wa, wb)) = sr.alive_in(m, &region) else {
                continue;
            };
            let (wa, wb) = (wa - lift, wb - lift);
            let from = hits.partition_point(|&(_, q)| q <= wa);
            let Some(cr) = &sr.crossings else {
                for (i, &(p, q)) in hits.iter().enumerate().skip(from) {
                    if p >= wb {
                        break;
                    }
                    let w = weight(i);
                    let (p, q) = (max(p, wa) + lift, min(q, wb) + lift);
                    if q > p {
                        let segment = Segment {
                            origin: sr.source.pos,
                            dir: d,
                            inv,
                            from: p,
                            to: q,
                        };
                        walk(grid, block, acc, segment, w);
                    }
                }
                continue;
            };
            let (rs, cells, _) = cr.of(m);
            let kappa = cr.area_correction(m);
            let mut k = usize::MAX;
            for (i, &(p, q)) in hits.iter().enumerate().skip(from) {
                if p >= wb {
                    break;
                }
                let w = weight(i);
                let (p, q) = (max(p, wa) + lift, min(q, wb) + lift);
                if q <= p {
                    continue;
                }
                k = next_crossing(rs, k, p);
                while k < cells.len() && rs[k] < q {
                    let len = min(rs[k + 1], q) - max(rs[k], p);
                    let [a, b] = cells[k];
                    let (a, b) = (a as usize, b as usize);
                    // Rounding at the block's edge: a sliver outside is dropped.
                    if len > 0.0 && (a0..a1).contains(&a) && (b0..b1).contains(&b) {
                        acc[(b - b0) * na + (a - a0)] += w * kappa[k] * len;
                    }
                    k += 1;
                }
            }
        }
    }
}

/// What the rays `sr` (crossing the grid as `cr` says) of one class saw in
/// each rectangle of the whole grid, at each lift `lifts[i]` (`v·t`) into
/// `accs[i]`, times the class's weight `w`; nothing past where a building
/// ends a ray's flights. With several lifts (every step of a plan) the
/// rays are read once, and the crossing of a ray's first interval is found
/// from the previous lift's; each buffer gets the same sums in the same
/// order as with one lift at a time.
fn accumulate_whole(
    sr: &SourceRays,
    cr: &Crossings,
    w: f64,
    seen: &RayHits,
    lifts: &[f64],
    accs: &mut [&mut [f64]],
) {
    for m in 0..sr.dirs.len() {
        let (rs, _, lin) = cr.of(m);
        let kappa = cr.area_correction(m);
        let hits = seen.of(m);
        if hits.is_empty() || lin.is_empty() {
            continue;
        }
        let detected = seen.detected(m);
        let stop = sr.stop(m);
        let exit = min(rs[lin.len()], stop);
        // Where the previous lift's first interval started.
        let mut hint = usize::MAX;
        for (&lift, acc) in lifts.iter().zip(accs.iter_mut()) {
            // The slice itself, so its start and length stay in registers
            // across the stores below.
            let acc: &mut [f64] = acc;
            let end = exit - lift;
            let from = hits.partition_point(|&(_, q)| q + lift <= rs[0]);
            let mut k = usize::MAX;
            for (i, &(p, q)) in hits.iter().enumerate().skip(from) {
                if p >= end {
                    break;
                }
                let w = if detected.is_empty() {
                    w
                } else {
                    w * detected[i]
                };
                let (p, q) = (p + lift, min(q + lift, stop));
                k = if k == usize::MAX {
                    hint = first_crossing(rs, hint, p);
                    hint
                } else {
                    next_crossing(rs, k, p)
                };
                while k < lin.len() && rs[k] < q {
                    acc[lin[k] as usize] += w * kappa[k] * (min(rs[k + 1], q) - max(rs[k], p));
                    k += 1;
                }
            }
        }
    }
}

/// The crossing whose segment holds `p` (as a bisection would find it:
/// the last `k` with `rs[k] ≤ p`, or 0), scanning on from `hint` when
/// `rs[hint] ≤ p`, else by bisection.
#[inline]
fn first_crossing(rs: &[f64], hint: usize, p: f64) -> usize {
    if hint < rs.len() && rs[hint] <= p {
        let mut k = hint;
        while k + 1 < rs.len() && rs[k + 1] <= p {
            k += 1;
        }
        return k;
    }
    rs.partition_point(|&x| x <= p).saturating_sub(1)
}

/// The crossing whose segment holds `p`, for the intervals of one ray in
/// order: `k` is where the previous interval ended (`usize::MAX` before the
/// first). The first is found by bisection, the next by scanning on from the
/// last: the gaps are short, and a scan is cheaper than dependent loads.
#[inline]
fn next_crossing(rs: &[f64], k: usize, p: f64) -> usize {
    if k == usize::MAX {
        return rs.partition_point(|&x| x <= p).saturating_sub(1);
    }
    let mut k = k.saturating_sub(1);
    while k + 1 < rs.len() && rs[k + 1] <= p {
        k += 1;
    }
    k
}

/// Adds to `acc`, the seen mass in each elementary rectangle of `block`,
/// the ray segment times `w`, rectangle by rectangle.
fn walk(grid: &ElementaryGrid, block: Block, acc: &mut [f64], segment: Segment, w: f64) {
    let (a_lo, b_lo, na) = (block.0, block.2, block.1 - block.0);
    trace(grid, block, segment, |a, b, from, to| {
        acc[(b - b_lo) * na + (a - a_lo)] += w * (to - from);
    });
}
