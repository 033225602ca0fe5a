//! Values in a scenario with obstacles: every integral of the exact
//! estimator restricted to what each look sees and to the targets whose
//! flight no building has ended.
//!
//! A look at cell `k` counts, on each ray of each class crossing `F_k`, the
//! part of the ray inside `F_k`, before the ray's stop (where a building
//! ends the flights along it) and visible from `k` ([`Sight::visible`]);
//! on that part a target is still unseen with probability
//! `(1 − d(r))·(1 − q(r))`: `d` the detection profile of the seen set
//! (which holds only what each past look saw), `q` that of the excluded
//! looks' visible pieces. So
//! `U(k,t) = Σ_c w_c Σ_rays [∫ (1 − d) − ∫ q (1 − d)]` over those parts:
//! the first integral by the seen set's prefix sums
//! ([`RayHits::detected_upto`](super::seen::RayHits::detected_upto), a
//! binary search), the second over the few pieces where excluded looks
//! hold the ray. The same interval arithmetic and midpoint rule as without
//! obstacles, evaluated per cell.
//!
//! A look that sees its whole square (elevated, or a ground look no
//! obstacle meets) takes the windows instead: its square is then a union
//! of elementary rectangles, each holding its unseen mass (the grid's
//! stationary mass is measured on the same rays, up to their stops, and
//! the seen pieces are clipped there too), so its value is a block sum,
//! the same to rounding. An excluded look that sees its whole square masks
//! whole rectangles; one that an obstacle cuts is taken off each
//! rectangle of a fill's reach once, by the rays, before the block sums
//! (`less_what_cut_looks_detect`), since what it detects of a rectangle
//! does not depend on the cell asking. Blocked sight lines cut a look's
//! own rectangles, so a look an obstacle cuts stays per cell; the parts of
//! the rays it does not see are read from the scenario's `sight_index`
//! when it has one.

use std::sync::Arc;

use super::cell_sights::{CellSight, CutDetection, CutDetections, cell_sight};
use super::sight_index::{CellView, hidden_parts};
use super::windows::{BlockSums, Window};
use super::{BLOCKS_FROM, ExactEstimator, KnownInViews};
use crate::estimator::elementary::{ElementaryGrid, Segment, trace};
use crate::geometry::{Point, detection_pieces};
use crate::limits::MAX_SPEED_CLASSES;
use crate::obstacle::Sight;
use crate::scenario::{Cell, Look};
use crate::search::ValueGrid;

/// A look that excludes part of the targets, with what it cannot see.
type Excluded<'a> = (&'a Look, Option<Sight>);

/// The windows' prefix sums over a block, less what every excluded look
/// detects: the unseen mass of every field of view in the block that sees
/// its whole square.
type Windowed<'a> = Option<(&'a ElementaryGrid, BlockSums)>;

/// The excluded looks of `near` that see their whole squares.
fn whole_squares(near: &[Excluded<'_>]) -> Vec<Look> {
    near.iter()
        .filter(|(_, v)| v.is_none())
        .map(|(x, _)| **x)
        .collect()
}

/// Pushes onto `pieces`, cleared first, the parts of `[lo, hi]` on the
/// ray `o + r·d` (`inv` its inverse) that each look of `looks` sees, with
/// its detection probability: what an excluded look takes off the ray.
fn seen_by(
    looks: &[&Excluded<'_>],
    (o, d, inv): (Point, Point, Point),
    (lo, hi): (f64, f64),
    visible: &mut Vec<(f64, f64)>,
    pieces: &mut Vec<(f64, f64, f64)>,
) {
    pieces.clear();
    for (x, v) in looks {
        let Some((p, q)) = x.region.ray(o, d, inv) else {
            continue;
        };
        let (p, q) = (p.max(lo), q.min(hi));
        if q <= p {
            continue;
        }
        match v {
            Some(v) => {
                visible.clear();
                v.visible(o, d, p, q, visible);
                pieces.extend(visible.iter().map(|&(p, q)| (p, q, x.p_detect)));
            }
            None => pieces.push((p, q, x.p_detect)),
        }
    }
}

/// Scratch space of one value, kept across the cells of a fill.
#[derive(Default)]
struct Scratch {
    buf: Vec<Point>,
    parts: Vec<(f64, f64)>,
    cut: Vec<(f64, f64)>,
    pieces: Vec<(f64, f64, f64)>,
    segments: Vec<(f64, f64, f64)>,
    events: Vec<(f64, f64, bool)>,
}

impl ExactEstimator<'_> {
    /// True when the `i`-th reported target still flies at step `t`: its
    /// straight path from now has not entered a building.
    #[inline]
    fn known_alive(&self, i: usize, t: usize) -> bool {
        let (speed, stop) = self.flights[i];
        stop > speed * t as f64
    }

    /// The reported targets still flying at step `t` inside `region`, each
    /// with the chance that every look of `near` that sees it misses it
    /// (none that a certain look sees): what a cell of `region` counts of
    /// each, if it sees it.
    fn known_at(
        &self,
        t: usize,
        region: &crate::geometry::Rect,
        near: &[Excluded<'_>],
    ) -> Vec<(Point, f64)> {
        let sees = |sight: &Option<Sight>, p: Point| sight.as_ref().is_none_or(|v| v.sees(p));
        self.known
            .iter()
            .enumerate()
            .filter(|&(i, _)| self.known_alive(i, t))
            .map(|(_, tg)| tg.at(t))
            .filter(|&p| region.contains(p))
            .map(|p| {
                let miss = near
                    .iter()
                    .filter(|(x, v)| x.region.contains(p) && sees(v, p))
                    .map(|(x, _)| x.miss())
                    .product::<f64>();
                (p, miss)
            })
            .filter(|&(_, miss)| miss > 0.0)
            .collect()
    }

    /// Each source's rays (an index into `rays`) and its classes (a range
    /// of `classes`, which are consecutive and share the rays).
    fn sources(&self) -> impl Iterator<Item = (usize, std::ops::Range<usize>)> + '_ {
        let mut first = 0;
        std::iter::from_fn(move || {
            let ri = self.classes.get(first)?.rays;
            let last = first
                + self.classes[first..]
                    .iter()
                    .take_while(|c| c.rays == ri)
                    .count();
            let classes = first..last;
            first = last;
            Some((ri, classes))
        })
    }

    /// The looks of `excluded` that may meet `region`'s, each with what it
    /// cannot see.
    fn excluded_sights<'x>(
        &self,
        excluded: &'x [Look],
        region: &crate::geometry::Region,
    ) -> Vec<Excluded<'x>> {
        excluded
            .iter()
            .filter(|x| x.region.may_overlap(region))
            .map(|x| (x, self.scenario.sight(x)))
            .collect()
    }

    /// The value of `sensor` at `k` at step `t` against `excluded`, with
    /// obstacles: `p_detect ×` (the reported targets it sees, each weighed
    /// by the chance that every excluded look that sees it misses it, plus
    /// the unseen targets in the part of `F_k` it sees).
    pub(super) fn value_sighted(&self, sensor: usize, k: Cell, t: usize, excluded: &[Look]) -> f64 {
        let fk = self.scenario.fov_region_of(self.types[sensor], k);
        let near = self.excluded_sights(excluded, &fk);
        let refs: Vec<&Excluded<'_>> = near.iter().collect();
        let known = self.known_at(t, &fk.rect, &near);
        // An excluded look that an obstacle cuts: per cell (one value).
        let windowed = self
            .block(sensor, k, t)
            .filter(|_| near.iter().all(|(_, v)| v.is_none()))
            .and_then(|win| {
                let grid = self.grid?;
                let block = grid.span(self.scenario.types[self.types[sensor]].fov_slot, k);
                Some((grid, win.block_sums(grid, block, &whole_squares(&near))))
            });
        self.sighted_at(
            sensor,
            k,
            t,
            &refs,
            &known,
            &windowed,
            &mut Scratch::default(),
        )
    }

    /// [`Estimator::fill`](crate::estimator::Estimator::fill) with
    /// obstacles: the excluded looks' sights once for the whole reach.
    pub(super) fn fill_sighted(
        &self,
        sensor: usize,
        start: Cell,
        t: usize,
        excluded: &[Look],
        out: &mut ValueGrid,
    ) {
        let s = self.scenario;
        let ty = self.types[sensor];
        // Every look that may meet a field of view of the reach.
        let reach = crate::geometry::Region {
            rect: self.reach(sensor, start, t),
            disk: None,
        };
        let near = self.excluded_sights(excluded, &reach);
        let known = self.known_at(t, &reach.rect, &near);
        let mut scratch = Scratch::default();
        let windowed = self
            .window_of(sensor, t)
            .filter(|_| self.starts.get(sensor) == Some(&start))
            .map(|(grid, win)| {
                let block = self.reach_block(grid, sensor, start, t);
                let cut: Vec<&Excluded<'_>> = near.iter().filter(|(_, v)| v.is_some()).collect();
                let whole = whole_squares(&near);
                if cut.is_empty() {
                    return (grid, win.block_sums(grid, block, &whole));
                }
                let mut part = win.part(block);
                self.less_what_cut_looks_detect(grid, &mut part, t, &cut, &mut scratch);
                (grid, part.block_sums(grid, block, &whole))
            });
        // A look that sees over every obstacle, with the windows: its whole
        // square by a block sum, and the reported targets in it (what
        // `sighted_at` gives it), without a sight or the excluded looks
        // near each cell to look up.
        let slot = s.types[ty].fov_slot;
        if let (true, Some((grid, sums))) = (s.sees_over[slot], &windowed) {
            let p_detect = s.types[ty].p_detect;
            // Many targets: each one's weight added over the block of
            // cells whose views hold it, in the targets' order, as the
            // per-cell sum below takes them (the same values to the bit).
            let reach = (s.types[ty].speed * t) as i32;
            let cells = ((2 * reach + 1) * (2 * reach + 1)) as usize;
            if known.len() * cells > BLOCKS_FROM {
                let blocks = KnownInViews::new(s, ty, start, reach, &[], &known);
                out.fill_step(t, |dc, dr| {
                    let k = s.lattice_cell(start, dc, dr)?;
                    Some(p_detect * (blocks.at(dc, dr) + sums.sum(grid.span(slot, k))))
                });
                return;
            }
            // The reported targets level with a row of cells' views (the
            // cells come row by row): a cell tests only those, in the same
            // order, so it sums the same ones.
            let mut row: Option<(f64, f64)> = None;
            let mut level: Vec<(Point, f64)> = Vec::new();
            out.fill_step(t, |dc, dr| {
                let k = s.lattice_cell(start, dc, dr)?;
                let fk = s.fov_region_of(ty, k);
                let (y0, y1) = (fk.rect.y0, fk.rect.y1);
                if row != Some((y0, y1)) {
                    row = Some((y0, y1));
                    level.clear();
                    level.extend(known.iter().filter(|(p, _)| p.y >= y0 && p.y <= y1));
                }
                let known: f64 = level
                    .iter()
                    .filter(|&&(p, _)| fk.contains(p))
                    .map(|&(_, miss)| miss)
                    .sum();
                Some(p_detect * (known + sums.sum(grid.span(slot, k))))
            });
            return;
        }
        let mut refs = Vec::with_capacity(near.len());
        out.fill_step(t, |dc, dr| {
            let k = s.lattice_cell(start, dc, dr)?;
            let fk = s.fov_region_of(ty, k);
            refs.clear();
            refs.extend(near.iter().filter(|(x, _)| x.region.may_overlap(&fk)));
            Some(self.sighted_at(sensor, k, t, &refs, &known, &windowed, &mut scratch))
        });
    }

    /// The value of `sensor` at `k` at step `t` against the excluded looks
    /// `near` (those that may meet its field of view), with `known` the
    /// reported targets that may lie in it ([`ExactEstimator::known_at`]),
    /// by the windows when `windowed` holds `k`'s block and the looks see
    /// whole squares.
    #[allow(clippy::too_many_arguments)]
    fn sighted_at(
        &self,
        sensor: usize,
        k: Cell,
        t: usize,
        near: &[&Excluded<'_>],
        known: &[(Point, f64)],
        windowed: &Windowed<'_>,
        scratch: &mut Scratch,
    ) -> f64 {
        let s = self.scenario;
        let ty = &s.types[self.types[sensor]];
        let look = s.look(self.types[sensor], k);
        let fk = look.region;
        self.with_cell_sight(sensor, k, &look, |sight, hidden, view| {
            let known: f64 = known
                .iter()
                .filter(|&&(p, _)| fk.contains(p) && sight.is_none_or(|v| v.sees(p)))
                .map(|&(_, miss)| miss)
                .sum();
            let unseen = match (windowed, sight) {
                // The whole square by the windows, less what the look does
                // not see by the rays.
                (Some((grid, sums)), _) => {
                    let whole = sums.sum(grid.span(ty.fov_slot, k));
                    match (sight, hidden) {
                        // From inside a screen: nothing, exactly (not the
                        // square less itself, which rounds).
                        (Some(v), _) if v.blind() => 0.0,
                        (Some(v), Some(hidden)) => {
                            let cell = (sensor, k, &look);
                            whole - self.unseen_hidden(cell, (v, hidden), view, t, near, scratch)
                        }
                        _ => whole,
                    }
                }
                (None, sight) => self.unseen_sighted(&look, sight, t, near, scratch),
            };
            ty.p_detect * (known + unseen)
        })
    }

    /// Calls `f` with what `sensor`'s `look` at `k` cannot see, a box
    /// holding the part of its field of view that it misses (`None` for
    /// both when it sees all of it) and the scenario's index of the rays'
    /// hidden parts there, if it has one: from the index, or else from
    /// the sensor's cache when `k` is in its reach.
    fn with_cell_sight<R>(
        &self,
        sensor: usize,
        k: Cell,
        look: &Look,
        f: impl FnOnce(Option<&Sight>, Option<&crate::geometry::Rect>, Option<&CellView>) -> R,
    ) -> R {
        let slot = self.scenario.types[self.types[sensor]].fov_slot;
        if let Some(view) = self
            .sight_index
            .and_then(|index| index.view(self.scenario, slot, k))
        {
            return match &view.sight {
                Some((v, hidden)) => f(Some(v), hidden.as_ref(), Some(view)),
                None => f(None, None, None),
            };
        }
        let compute = || cell_sight(self.scenario, look);
        let call = |cs: &CellSight| match cs {
            Some((v, hidden)) => f(Some(v), hidden.as_ref(), None),
            None => f(None, None, None),
        };
        let cache = self.ground.get(sensor).and_then(|g| g.sights.as_ref());
        match cache.and_then(|c| c.slot(k, 0)) {
            Some(slot) => call(slot.get_or_init(compute)),
            None => call(&compute()),
        }
    }

    /// `U` of `look` at step `t` (see the module docs) over the part of its
    /// field of view that `sight` lets it see.
    fn unseen_sighted(
        &self,
        look: &Look,
        sight: Option<&Sight>,
        t: usize,
        excluded: &[&Excluded<'_>],
        scratch: &mut Scratch,
    ) -> f64 {
        let fk = &look.region;
        let mut unseen = 0.0;
        let mut parts = std::mem::take(&mut scratch.parts);
        for (ri, classes) in self.sources() {
            let sr = &self.rays[ri];
            let Some((a, b)) = sr.range(fk, &mut scratch.buf) else {
                continue;
            };
            // A source has at most MAX_SPEED_CLASSES classes.
            let mut sums = [0.0; MAX_SPEED_CLASSES];
            for m in a..b {
                let Some((lo, hi)) = sr.alive_in(m, fk) else {
                    continue;
                };
                parts.clear();
                match sight {
                    Some(v) => v.visible(sr.source.pos, sr.dirs[m].0, lo, hi, &mut parts),
                    None => parts.push((lo, hi)),
                }
                if !parts.is_empty() {
                    let ray = (ri, classes.clone(), m);
                    let on = (lo, hi, &parts[..]);
                    self.unseen_on_ray(ray, on, t, (excluded, true), scratch, &mut sums);
                }
            }
            for (slot, c) in classes.enumerate() {
                unseen += self.classes[c].weight * sums[slot];
            }
        }
        scratch.parts = parts;
        unseen
    }

    /// `U` of `sensor`'s `look` at `k` at step `t` over the part of its
    /// field of view that its sight `v` hides, which `hidden` holds: on the
    /// rays that cross `hidden` only, their hidden parts read from `view`
    /// when the scenario indexed them, the same parts otherwise worked out
    /// here. The seen set's part is the same in every search of a plan, so
    /// it is kept per cell and step; the excluded looks' part is taken off
    /// it.
    fn unseen_hidden(
        &self,
        (sensor, k, look): (usize, Cell, &Look),
        (v, hidden): (&Sight, &crate::geometry::Rect),
        view: Option<&CellView>,
        t: usize,
        excluded: &[&Excluded<'_>],
        scratch: &mut Scratch,
    ) -> f64 {
        let crossed = crate::geometry::Region {
            rect: *hidden,
            disk: None,
        };
        let hidden = (look, v, &crossed, view);
        let kept = t
            .checked_sub(1)
            .and_then(|layer| self.ground.get(sensor)?.hidden_unseen.slot(k, layer));
        let mut seen_set = || self.on_hidden_rays(hidden, t, (&[], true), scratch);
        let unseen = match kept {
            Some(slot) => *slot.get_or_init(seen_set),
            None => seen_set(),
        };
        // Only the excluded looks that may meet the hidden rays' box.
        let near: Vec<&Excluded<'_>> = excluded
            .iter()
            .copied()
            .filter(|(x, _)| x.region.may_overlap(&crossed))
            .collect();
        if near.is_empty() {
            return unseen;
        }
        unseen + self.on_hidden_rays(hidden, t, (&near, false), scratch)
    }

    /// [`ExactEstimator::unseen_on_ray`] summed over the hidden parts of
    /// the rays that cross `crossed`, `v` being the sight of `look` and
    /// `view` its index entry (if any), weighted by class.
    fn on_hidden_rays(
        &self,
        (look, v, crossed, view): (&Look, &Sight, &crate::geometry::Region, Option<&CellView>),
        t: usize,
        excluded: (&[&Excluded<'_>], bool),
        scratch: &mut Scratch,
    ) -> f64 {
        let mut unseen = 0.0;
        let mut buf = std::mem::take(&mut scratch.buf);
        for (ri, classes) in self.sources() {
            // A source has at most MAX_SPEED_CLASSES classes.
            let mut sums = [0.0; MAX_SPEED_CLASSES];
            let mut on_ray = |m: usize, lo: f64, hi: f64, parts: &[(f64, f64)]| {
                let ray = (ri, classes.clone(), m);
                self.unseen_on_ray(ray, (lo, hi, parts), t, excluded, scratch, &mut sums);
            };
            match view {
                Some(view) => {
                    for (ray, parts) in view.rays_of(ri) {
                        on_ray(ray.m as usize, ray.lo, ray.hi, parts);
                    }
                }
                None => hidden_parts(&self.rays[ri], &look.region, crossed, v, &mut buf, on_ray),
            }
            for (slot, c) in classes.enumerate() {
                unseen += self.classes[c].weight * sums[slot];
            }
        }
        scratch.buf = buf;
        unseen
    }

    /// Adds to `sums` (per class of the ray's source) the unseen mass at
    /// step `t` on `parts` of ray `m` of source `ri` (`classes` its
    /// classes), whose part in the field of view is `[lo, hi]`: the seen
    /// set's and the `excluded` looks' detections taken off. Without
    /// `base`, only what the excluded looks take off, negated.
    #[inline]
    fn unseen_on_ray(
        &self,
        (ri, classes, m): (usize, std::ops::Range<usize>, usize),
        (lo, hi, parts): (f64, f64, &[(f64, f64)]),
        t: usize,
        (excluded, base): (&[&Excluded<'_>], bool),
        scratch: &mut Scratch,
        sums: &mut [f64; MAX_SPEED_CLASSES],
    ) {
        let Scratch {
            cut,
            pieces,
            segments,
            events,
            ..
        } = scratch;
        let sr = &self.rays[ri];
        let (d, inv) = sr.dirs[m];
        // Where the excluded looks hold this ray, cut into pieces of one
        // detection probability each.
        seen_by(excluded, (sr.source.pos, d, inv), (lo, hi), cut, pieces);
        segments.clear();
        if !pieces.is_empty() {
            detection_pieces(pieces, lo, hi, events, |u, v, q| segments.push((u, v, q)));
        } else if !base {
            return;
        }
        for (slot, c) in classes.enumerate() {
            let (class, hits) = (&self.classes[c], &self.seen[c]);
            let lift = class.speed * t as f64;
            let seen =
                |u: f64, v: f64| hits.detected_upto(m, v - lift) - hits.detected_upto(m, u - lift);
            let mut sum = 0.0;
            for &(p, q) in parts {
                if base {
                    sum += (q - p) - seen(p, q);
                }
                for &(u, v, qx) in segments.iter() {
                    let (u, v) = (u.max(p), v.min(q));
                    if v > u {
                        sum -= qx * ((v - u) - seen(u, v));
                    }
                }
            }
            sums[slot] += sum;
        }
    }

    /// Takes off each rectangle of `win` (a window over a block) what the
    /// excluded looks `cut`, each of which an obstacle cuts, detect there
    /// at step `t` of the unseen targets: `∫ ρ (1 − d)(1 − Π (1 − p))`
    /// over the parts of the rays they see, the product over the cut looks
    /// that see a point. The excluded looks that see whole squares mask
    /// whole rectangles afterwards ([`Window::block_sums`]), which makes
    /// the product over all of them.
    ///
    /// The cut looks fall into groups whose fields of view overlap (linked
    /// through each other). No point lies in two groups, so what they take
    /// off adds up, and what each group detects is kept for the plan
    /// ([`CutDetections`]): the fills of every sensor exclude the same
    /// looks (the certificate's, all of them), in each search.
    fn less_what_cut_looks_detect(
        &self,
        grid: &ElementaryGrid,
        win: &mut Window,
        t: usize,
        cut: &[&Excluded<'_>],
        scratch: &mut Scratch,
    ) {
        // Groups of looks whose fields of view overlap (linked through
        // each other): the groups' detections add up.
        let mut group: Vec<usize> = (0..cut.len()).collect();
        for i in 0..cut.len() {
            for j in 0..i {
                if cut[i].0.region.may_overlap(&cut[j].0.region) {
                    let (gi, gj) = (group[i], group[j]);
                    group.iter_mut().filter(|g| **g == gi).for_each(|g| *g = gj);
                }
            }
        }
        let mut members = Vec::with_capacity(cut.len());
        for (i, &g) in group.iter().enumerate() {
            if group[..i].contains(&g) {
                continue;
            }
            members.clear();
            members.extend(
                cut.iter()
                    .zip(&group)
                    .filter(|(_, h)| **h == g)
                    .map(|(x, _)| *x),
            );
            self.cut_detection(grid, &members, t, scratch)
                .take_from(win);
        }
    }

    /// What the cut looks `group` detect at step `t` of each rectangle of
    /// the block around their fields of view: from the plan's memo, or
    /// worked out and kept there.
    fn cut_detection(
        &self,
        grid: &ElementaryGrid,
        group: &[&Excluded<'_>],
        t: usize,
        scratch: &mut Scratch,
    ) -> Arc<CutDetection> {
        // Sorted by key, so that the same group sums in the same order
        // whichever fill asks first.
        let mut group: Vec<_> = group
            .iter()
            .map(|&x| (CutDetections::look_key(x.0), x))
            .collect();
        group.sort_unstable_by_key(|(k, _)| *k);
        let key = (group.iter().map(|(k, _)| *k).collect(), t);
        if let Some(kept) = self.cut_detections.get(&key) {
            return kept;
        }
        let group: Vec<&Excluded<'_>> = group.into_iter().map(|(_, x)| x).collect();
        let detected = self.detect_on_rays(grid, t, &group, scratch);
        self.cut_detections.keep(key, detected)
    }

    /// What the looks `cut` detect at step `t` of each rectangle of the
    /// block covering their fields of view: on each part of a ray in a
    /// rectangle that they see, the unseen mass there times the chance
    /// that some look of `cut` detects it (see
    /// [`ExactEstimator::less_what_cut_looks_detect`]).
    fn detect_on_rays(
        &self,
        grid: &ElementaryGrid,
        t: usize,
        cut: &[&Excluded<'_>],
        scratch: &mut Scratch,
    ) -> CutDetection {
        let mut hull = cut[0].0.region.rect;
        for (x, _) in cut {
            hull = hull.hull(&x.region.rect);
        }
        let block = grid.covering(&hull);
        let (a0, a1, b0, b1) = block;
        let na = a1 - a0;
        let mut by_rect = vec![0.0; na * (b1 - b0)];
        let rect = crate::geometry::Rect {
            x0: grid.xs[a0],
            x1: grid.xs[a1],
            y0: grid.ys[b0],
            y1: grid.ys[b1],
        };
        // The rays that may meet a cut look inside the block.
        let region = crate::geometry::Region {
            rect: hull.intersect(&rect),
            disk: None,
        };
        if region.rect.is_empty() {
            return CutDetection::new(block, by_rect);
        }
        let within = crate::geometry::Region { rect, disk: None };
        let Scratch {
            buf,
            cut: visible,
            pieces,
            segments,
            events,
            ..
        } = scratch;
        for (ri, classes) in self.sources() {
            let sr = &self.rays[ri];
            let o = sr.source.pos;
            let Some((ma, mb)) = sr.range(&region, buf) else {
                continue;
            };
            for m in ma..mb {
                let (d, inv) = sr.dirs[m];
                let Some((lo, hi)) = sr.alive_in(m, &within) else {
                    continue;
                };
                seen_by(cut, (o, d, inv), (lo, hi), visible, pieces);
                if pieces.is_empty() {
                    continue;
                }
                segments.clear();
                detection_pieces(pieces, lo, hi, events, |u, v, q| segments.push((u, v, q)));
                for &(u, v, q) in segments.iter() {
                    let segment = Segment {
                        origin: o,
                        dir: d,
                        inv,
                        from: u,
                        to: v,
                    };
                    // The seen mass up to the start of each rectangle's
                    // part, per class: the trace's parts follow on from
                    // each other, so each end is searched for once.
                    let mut upto = [0.0; MAX_SPEED_CLASSES];
                    for (slot, c) in classes.clone().enumerate() {
                        let lift = self.classes[c].speed * t as f64;
                        upto[slot] = self.seen[c].detected_upto(m, u - lift);
                    }
                    trace(grid, block, segment, |a, b, from, to| {
                        let mut detected = 0.0;
                        for (slot, c) in classes.clone().enumerate() {
                            let (class, hits) = (&self.classes[c], &self.seen[c]);
                            let lift = class.speed * t as f64;
                            let end = hits.detected_upto(m, to - lift);
                            detected += class.weight * ((to - from) - (end - upto[slot]));
                            upto[slot] = end;
                        }
                        by_rect[(b - b0) * na + (a - a0)] += q * detected;
                    });
                }
            }
        }
        CutDetection::new(block, by_rect)
    }
}
