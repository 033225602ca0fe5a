//! The angular grid of each source: the rays along which the exact
//! estimator measures what was seen, and where each ray crosses the
//! elementary grid.

use rayon::prelude::*;

use crate::estimator::elementary::{ElementaryGrid, Segment, trace};
use crate::geometry::{Point, Rect, Region, wedge_inv_r_integral};
use crate::limits::{DEFAULT_RAYS_PER_PI_CIRCLE, DEFAULT_RAYS_PER_PI_SQUARE};
use crate::scenario::{Cell, FovSpec, Scenario, Source};
use crate::stats::angular_span;

/// Rays per π of the angular grids of scenarios with square fields of view
/// that ask for no other ([`DEFAULT_RAYS_PER_PI_SQUARE`]).
pub const RAYS_PER_PI_SQUARE: f64 = DEFAULT_RAYS_PER_PI_SQUARE as f64;

/// The largest share of a source's measure over the zone that may lie in
/// rectangles no ray of it crosses for its windows to take the area
/// correction ([`Crossings::area_correction`]); past it they keep the
/// plain midpoint rule.
const MAX_UNCROSSED_MEASURE: f64 = 5e-3;

/// Crossings of the ray index allowed per lattice cell (about 100 bytes a
/// cell): past it and [`MIN_INDEX_CROSSINGS`], plans walk the grid instead.
pub const INDEX_CROSSINGS_PER_CELL: usize = 5;
/// Crossings the ray index may always have, whatever the lattice.
pub const MIN_INDEX_CROSSINGS: usize = 1 << 20;

/// Square fields of view (over the `fovs` slots indexed) up to which each
/// source indexes where its rays cross them ([`SourceRays::index_looks`]):
/// about 25 rays of 16 bytes each, so a few MB per source at most.
pub const MAX_INDEXED_LOOKS: usize = 1 << 14;

/// Rays per π of the angular grids of scenarios with a circular field of
/// view that ask for no other ([`DEFAULT_RAYS_PER_PI_CIRCLE`]).
pub const RAYS_PER_PI: f64 = DEFAULT_RAYS_PER_PI_CIRCLE as f64;

/// The fixed angular grid of one source: midpoints of `n` equal steps over
/// the takeoff angles of its cone that reach the zone. Depends on the
/// scenario only; the source's target classes share it.
#[derive(Debug, Clone)]
pub struct SourceRays {
    pub(super) source: Source,
    pub(super) lo: f64,
    pub(super) step: f64,
    /// Unit direction and its componentwise inverse, per ray.
    pub(super) dirs: Vec<(Point, Point)>,
    /// Per ray, a distance past which it is out of the zone for good: where
    /// it leaves the zone, plus a margin for rounding (`+∞` for a ray that
    /// misses the zone). A seen interval that starts past it is out of the
    /// zone at every step, so the seen sets leave it out (see
    /// [`RayHits`](super::seen::RayHits)).
    pub(super) beyond: Vec<f64>,
    /// Per ray, where a building ends the flight of a target on it (see
    /// [`crate::obstacle::Obstacles::stop`]); empty without buildings.
    pub(super) stops: Vec<f64>,
    /// Index of the source in the scenario.
    pub(super) source_index: usize,
    /// Where each ray crosses the elementary grid, when indexed.
    pub(super) crossings: Option<Crossings>,
    /// Where the rays cross every cell's square field of view, when indexed.
    pub(super) looks: Option<LookCrossings>,
}

/// Where the rays of a source cross the square field of view of every cell,
/// for every square field of view of the scenario (its `fovs`): from the
/// first ray that meets it to the last, each one's slab
/// interval ([`slab`]; `p > q` for a ray that misses), as the seen sets
/// compute them for a look there. The looks of a plan are such fields of
/// view, so the seen sets read their intervals here instead, to the same
/// bits, for a few MB held per scenario (the saving is measured in
/// `docs/performance.md`, *Rays per π*).
#[derive(Debug, Clone)]
pub(super) struct LookCrossings {
    /// Per [`LookKey`]: the first ray of the range, and where its intervals
    /// start in `pq` (one entry more: the end of the last).
    pub(super) first: Vec<u32>,
    pub(super) start: Vec<u32>,
    pub(super) pq: Vec<(f64, f64)>,
    /// Per [`LookKey`]: how far its intervals must be pushed (at least,
    /// less a margin for rounding) to start past the exit of every ray
    /// they lie on ([`SourceRays::beyond`]); `+∞` when never (a ray that
    /// never leaves the zone), 0 for a look that meets no ray.
    pub(super) past: Vec<f64>,
}

/// A cell's field of view in [`LookCrossings`]: `slot · cells + index`.
pub(super) type LookKey = u32;

impl LookCrossings {
    /// The first ray and the intervals of the rays from it on, of the field
    /// of view `key` (empty when no ray can meet it).
    #[inline]
    pub(super) fn of(&self, key: LookKey) -> (usize, &[(f64, f64)]) {
        let k = key as usize;
        (
            self.first[k] as usize,
            &self.pq[self.start[k] as usize..self.start[k + 1] as usize],
        )
    }

    /// True when the look `key`, its intervals pushed by `shift`, starts
    /// past the exit of every ray it lies on: the seen sets would leave
    /// each one out, so they skip it whole (a look seen long ago, far
    /// downstream of a source: many of a long history's).
    #[inline]
    pub(super) fn past_exit(&self, key: LookKey, shift: f64) -> bool {
        shift > self.past[key as usize]
    }
}

/// The key of `region` in [`LookCrossings`], if it is the field of view of
/// an indexed slot at some cell (the looks of sensors with square fields
/// of view are; a whole-zone look is not). Checked by rebuilding that field of view: a key
/// is only given for a region equal to the indexed one.
pub(super) fn look_key(s: &Scenario, region: &Region) -> Option<LookKey> {
    if region.disk.is_some() {
        return None;
    }
    let r = &region.rect;
    let cs = s.cell_size;
    for (slot, fov) in s.fovs.iter().enumerate() {
        let FovSpec::Square { half_width: h } = *fov else {
            continue;
        };
        if !indexes(s, slot) {
            continue;
        }
        // The centre, from an edge the zone did not clip.
        let cx = if r.x0 > 0.0 { r.x0 + h } else { r.x1 - h };
        let cy = if r.y0 > 0.0 { r.y0 + h } else { r.y1 - h };
        // Casts saturate; `on_lattice` rejects what is off.
        let cell = Cell {
            col: (cx / cs).floor() as i32,
            row: (cy / cs).floor() as i32,
        };
        if s.on_lattice(cell) && s.fov_with(*fov, s.centre(cell)) == *region {
            return LookKey::try_from(slot * s.cell_count() + s.index(cell)).ok();
        }
    }
    None
}

/// True when [`LookCrossings`] index the field of view `slot`: a square
/// (the looks of every type with a square field of view read the index,
/// certain and uncertain alike).
fn indexes(s: &Scenario, slot: usize) -> bool {
    matches!(s.fovs[slot], FovSpec::Square { .. })
}

/// The slab interval `[p, q]` of the ray from `o` with inverse direction
/// `inv` through the rectangle `r` (`p > q`: it misses). Branch-free; no
/// component of `inv` is infinite. The one formula of the seen sets, so an
/// interval read from [`LookCrossings`] is the one computed.
#[inline(always)]
pub(super) fn slab(r: &Rect, o: Point, inv: Point) -> (f64, f64) {
    let (x0, x1, y0, y1) = (r.x0 - o.x, r.x1 - o.x, r.y0 - o.y, r.y1 - o.y);
    let (tx0, tx1) = (x0 * inv.x, x1 * inv.x);
    let (ty0, ty1) = (y0 * inv.y, y1 * inv.y);
    let p = max(max(min(tx0, tx1), min(ty0, ty1)), 0.0);
    let q = min(max(tx0, tx1), max(ty0, ty1));
    (p, q)
}

/// The elementary rectangles each ray of a source crosses on its way
/// through the zone, in order: ray `m` enters `cells[k]` at distance `r[k]`
/// from the source, for `k` in `offsets[m]..offsets[m+1]`, and leaves the
/// last one at the ray's next `r` (each ray's `r` has one entry more than
/// its cells, so ray `m`'s distances start at `offsets[m] + m`). With it a
/// seen interval is spread over rectangles by a merge of two sorted lists
/// instead of a grid walk, at every step of every request.
#[derive(Debug, Clone)]
pub(super) struct Crossings {
    pub(super) offsets: Vec<u32>,
    pub(super) r: Vec<f64>,
    pub(super) cells: Vec<[u32; 2]>,
    /// `cells[k]` as an index into the whole grid, `b·nx + a`.
    pub(super) lin: Vec<u32>,
    /// Per crossing, its rectangle's area correction: the rectangle's
    /// exact measure `∫∫ dr dα` from this source (within its cone) over the
    /// measure the rays sample there, `step · Σ` of their lengths inside it
    /// (see [`Crossings::area_correction`]).
    pub(super) kappa: Vec<f64>,
}

impl Crossings {
    /// Ray `m`'s entry distances (and final exit) and rectangles.
    #[inline]
    pub(super) fn of(&self, m: usize) -> (&[f64], &[[u32; 2]], &[u32]) {
        let (a, b) = (self.offsets[m] as usize, self.offsets[m + 1] as usize);
        (
            &self.r[a + m..b + m + 1],
            &self.cells[a..b],
            &self.lin[a..b],
        )
    }

    /// Ray `m`'s area corrections, aligned with its rectangles.
    ///
    /// The midpoint rule measures a rectangle's seen part as the rays'
    /// lengths in it times the angular step. Scaled by its rectangle's
    /// correction, each ray's length stands for its share of the
    /// rectangle's exact measure instead: a rectangle all seen (or all
    /// unseen) then has no quadrature error left, and a partly seen one
    /// only that of where the seen part's edges cross it. Measured against
    /// 4,096 rays per π, this halves the mean error of the paper's values
    /// and divides the sites' by two to three (`docs/performance.md`,
    /// *Accuracy*).
    #[inline]
    pub(super) fn area_correction(&self, m: usize) -> &[f64] {
        let (a, b) = (self.offsets[m] as usize, self.offsets[m + 1] as usize);
        &self.kappa[a..b]
    }
}

impl SourceRays {
    /// Where a building ends the flights along ray `m` (`+∞` when none
    /// does).
    #[inline]
    pub(super) fn stop(&self, m: usize) -> f64 {
        self.stops.get(m).copied().unwrap_or(f64::INFINITY)
    }

    /// The part `[lo, hi]` of ray `m` inside `region` and before where a
    /// building ends its flights, if it has length.
    #[inline]
    pub(super) fn alive_in(&self, m: usize, region: &Region) -> Option<(f64, f64)> {
        let (d, inv) = self.dirs[m];
        let (lo, hi) = region.ray(self.source.pos, d, inv)?;
        let hi = hi.min(self.stop(m));
        (hi > lo).then_some((lo, hi))
    }

    /// The grids of every source of a scenario with a non-zero rate, at
    /// its rays per π ([`Scenario::rays_per_pi`]).
    pub fn for_scenario(s: &Scenario) -> Vec<SourceRays> {
        Self::with_density(s, Self::density(s))
    }

    /// Rays per π of the grids on `s` ([`Scenario::rays_per_pi`]).
    pub fn density(s: &Scenario) -> f64 {
        s.rays_per_pi() as f64
    }

    /// Rays of a grid over takeoff angles `[lo, hi]` at `rays_per_pi`
    /// (at least one).
    pub fn count(lo: f64, hi: f64, rays_per_pi: f64) -> usize {
        (((hi - lo) / std::f64::consts::PI) * rays_per_pi)
            .ceil()
            .max(1.0) as usize
    }

    /// The same at `rays_per_pi` rays per π radians (for accuracy studies).
    pub fn with_density(s: &Scenario, rays_per_pi: f64) -> Vec<SourceRays> {
        let zone = s.zone_region();
        let mut buf = Vec::new();
        s.sources
            .iter()
            .enumerate()
            .filter(|(_, src)| src.rate > 0.0)
            .filter_map(|(j, src)| {
                let (lo, hi) = angular_span(src, &zone, &mut buf)?;
                let n = Self::count(lo, hi, rays_per_pi);
                let step = (hi - lo) / n as f64;
                // No component exactly 0, so slab intersections need no
                // special case (a tilt of 1e-12 rad changes nothing).
                let nudge = |c: f64| if c == 0.0 { 1e-12 } else { c };
                let dirs: Vec<(Point, Point)> = (0..n)
                    .map(|m| {
                        let d = src.direction(lo + (m as f64 + 0.5) * step);
                        let d = Point::new(nudge(d.x), nudge(d.y));
                        (d, Point::new(1.0 / d.x, 1.0 / d.y))
                    })
                    .collect();
                // Every distance the estimator clips a seen interval to (a
                // cell's, a block's, the zone's far side) is at most the
                // zone's exit, to rounding: a relative 1e-9 is far more.
                let beyond = dirs
                    .iter()
                    .map(|&(d, inv)| {
                        zone.ray(src.pos, d, inv)
                            .map_or(f64::INFINITY, |(_, r1)| r1 + 1e-9 * (1.0 + r1.abs()))
                    })
                    .collect();
                let stops = if s.obstacles.in_building_anywhere() {
                    dirs.iter()
                        .map(|&(d, _)| s.obstacles.stop(src.pos, d))
                        .collect()
                } else {
                    Vec::new()
                };
                Some(SourceRays {
                    source: *src,
                    lo,
                    step,
                    dirs,
                    beyond,
                    stops,
                    source_index: j,
                    crossings: None,
                    looks: None,
                })
            })
            .collect()
    }

    /// Indexes where every ray crosses `grid`'s rectangles (see
    /// [`ExactEstimator`](super::ExactEstimator)), unless that would take more than about 100 bytes
    /// per lattice cell; without the index, plans walk the grid instead
    /// (the same values, more slowly).
    pub fn index_crossings(rays: &mut [SourceRays], s: &Scenario, grid: &ElementaryGrid) {
        let (nx, ny) = grid.dims();
        let bound: usize = rays.iter().map(|sr| sr.dirs.len() * (nx + ny)).sum();
        if bound > (INDEX_CROSSINGS_PER_CELL * s.cell_count()).max(MIN_INDEX_CROSSINGS)
            || nx * ny > u32::MAX as usize
        {
            return;
        }
        let zone = s.zone_region();
        rays.par_iter_mut().for_each(|sr| {
            let n = sr.dirs.len();
            let mut offsets = Vec::with_capacity(n + 1);
            let mut r = Vec::new();
            let mut cells = Vec::new();
            let mut lin = Vec::new();
            offsets.push(0);
            for &(d, inv) in &sr.dirs {
                if let Some((r0, r1)) = zone.ray(sr.source.pos, d, inv) {
                    let segment = Segment {
                        origin: sr.source.pos,
                        dir: d,
                        inv,
                        from: r0,
                        to: r1,
                    };
                    trace(grid, (0, nx, 0, ny), segment, |a, b, from, _| {
                        r.push(from);
                        cells.push([a as u32, b as u32]);
                        lin.push((b * nx + a) as u32);
                    });
                    r.push(r1);
                } else {
                    r.push(0.0);
                }
                offsets.push(cells.len() as u32);
            }
            // Each crossed rectangle's correction, from the crossings
            // grouped by rectangle (a sort, not a table over the grid: a
            // large lattice's grid has millions of rectangles).
            let len: Vec<f64> = (0..n)
                .flat_map(|m| {
                    let (a, b) = (offsets[m] as usize, offsets[m + 1] as usize);
                    let r = &r;
                    (a..b).map(move |k| r[k + m + 1] - r[k + m])
                })
                .collect();
            let mut order: Vec<u32> = (0..lin.len() as u32).collect();
            order.sort_unstable_by_key(|&k| lin[k as usize]);
            let mut kappa = vec![1.0; lin.len()];
            let src = &sr.source;
            let measure = |rect: &Rect| {
                wedge_inv_r_integral(src.pos, rect, src.frame, src.cone.0, src.cone.1)
            };
            let mut crossed = 0.0;
            for group in order.chunk_by(|&x, &y| lin[x as usize] == lin[y as usize]) {
                let sampled: f64 = group.iter().map(|&k| len[k as usize]).sum::<f64>() * sr.step;
                // A rectangle only touched (length 0) keeps the plain
                // rule: its crossings add nothing either way.
                if sampled > 0.0 {
                    let [a, b] = cells[group[0] as usize];
                    let exact = measure(&Rect {
                        x0: grid.xs[a as usize],
                        x1: grid.xs[a as usize + 1],
                        y0: grid.ys[b as usize],
                        y1: grid.ys[b as usize + 1],
                    });
                    crossed += exact;
                    for &k in group {
                        kappa[k as usize] = exact / sampled;
                    }
                }
            }
            // A rectangle no ray crosses loses its seen part whatever the
            // rule; the plain rule makes up for it on average (its
            // neighbours' rays run longer), the corrected one does not.
            // Rays too sparse for the grid (a coarse `rays_per_pi`, a
            // narrow cone far out) keep the plain rule. So do scenarios
            // with obstacles: their stationary mass is the rays' too
            // ([`SourceRays::alive_mass`]), and the windows then give the
            // per-cell path's values to rounding.
            if s.has_obstacles() || crossed < (1.0 - MAX_UNCROSSED_MEASURE) * measure(&zone.rect) {
                kappa.fill(1.0);
            }
            sr.crossings = Some(Crossings {
                offsets,
                r,
                cells,
                lin,
                kappa,
            });
        });
    }

    /// The stationary mass of each rectangle of `grid` (`b·nx + a`) by the
    /// midpoint rule on these rays: each ray's length inside it, up to
    /// where a building ends the flights along the ray, times the
    /// source's targets per unit of length and angle (summed over its
    /// classes) and the angular step. It is the mass that the per-cell
    /// path of a scenario with obstacles integrates
    /// (`sighted`), so windows built on it give the same values.
    pub fn alive_mass(rays: &[SourceRays], s: &Scenario, grid: &ElementaryGrid) -> Vec<f64> {
        let (nx, ny) = grid.dims();
        let zone = s.zone_region();
        // One buffer, the sources in order: a grid may have millions of
        // rectangles, too many for a buffer per source.
        let mut mass = vec![0.0; nx * ny];
        for sr in rays {
            let density: f64 = s
                .classes_of(sr.source_index)
                .iter()
                .map(|class| class.rate / (sr.source.spread * class.speed))
                .sum::<f64>()
                * sr.step;
            for (m, &(d, inv)) in sr.dirs.iter().enumerate() {
                let Some((r0, r1)) = sr.alive_in(m, &zone) else {
                    continue;
                };
                let segment = Segment {
                    origin: sr.source.pos,
                    dir: d,
                    inv,
                    from: r0,
                    to: r1,
                };
                trace(grid, (0, nx, 0, ny), segment, |a, b, from, to| {
                    mass[b * nx + a] += density * (to - from);
                });
            }
        }
        mass
    }

    /// Indexes where every ray crosses every cell's square field of view
    /// (`LookCrossings`), for scenarios of at most
    /// `MAX_INDEXED_LOOKS` (16 384) such fields of view, a few MB per
    /// source; others compute them per plan (the same values, more slowly).
    /// Not with obstacles: the index holds whole squares, and a ground
    /// look sees only part of its square.
    pub fn index_looks(rays: &mut [SourceRays], s: &Scenario) {
        if s.has_obstacles() {
            return;
        }
        let slots: Vec<bool> = (0..s.fovs.len()).map(|slot| indexes(s, slot)).collect();
        let indexed = slots.iter().filter(|&&x| x).count();
        let keys = s.fovs.len() * s.cell_count();
        if indexed == 0 || indexed * s.cell_count() > MAX_INDEXED_LOOKS || keys >= u32::MAX as usize
        {
            return;
        }
        rays.par_iter_mut().for_each(|sr| {
            let mut buf = Vec::new();
            let mut first = Vec::with_capacity(keys);
            let mut start = Vec::with_capacity(keys + 1);
            let mut pq: Vec<(f64, f64)> = Vec::new();
            let mut past = Vec::with_capacity(keys);
            start.push(0);
            for (fov, &indexed) in s.fovs.iter().zip(&slots) {
                for k in 0..s.cell_count() {
                    let region = s.fov_with(*fov, s.centre(s.cell_at(k)));
                    let range = if indexed {
                        sr.range(&region, &mut buf)
                    } else {
                        None
                    };
                    let (mut a, b) = range.unwrap_or((0, 0));
                    let from = pq.len();
                    pq.extend(
                        sr.dirs[a..b]
                            .iter()
                            .map(|&(_, inv)| slab(&region.rect, sr.source.pos, inv)),
                    );
                    // Only the rays that meet it, from the first to the last
                    // (the range has a margin of a ray or two each side).
                    while pq.len() > from && pq.last().is_some_and(|&(p, q)| p > q) {
                        pq.pop();
                    }
                    let lead = pq[from..].iter().take_while(|&&(p, q)| p > q).count();
                    pq.drain(from..from + lead);
                    a += lead;
                    first.push(a as u32);
                    start.push(pq.len() as u32);
                    // A ray's interval pushed by `shift` is left out when
                    // `p + shift > beyond`. Rounding moves either side by far
                    // less than the margin (1e-9 of the distances), so past
                    // `past` every ray's is, whatever the rounding.
                    let pushes = pq[from..]
                        .iter()
                        .zip(&sr.beyond[a..])
                        .filter(|((p, q), _)| p <= q)
                        .map(|(&(p, _), &far)| (far - p) + 1e-9 * (far.abs() + p.abs()));
                    past.push(pushes.fold(0.0, f64::max));
                }
            }
            pq.shrink_to_fit();
            sr.looks = Some(LookCrossings {
                first,
                start,
                pq,
                past,
            });
        });
    }

    /// These rays with the plain midpoint rule in the windows, as the
    /// general path integrates (no [`Crossings::area_correction`]): checks
    /// compare the two paths' values to rounding with it.
    pub fn plain_midpoint(&mut self) {
        if let Some(c) = &mut self.crossings {
            c.kappa.iter_mut().for_each(|k| *k = 1.0);
        }
    }

    /// These rays as if no ray left the zone: their seen sets keep what
    /// lies past the exit (to check that leaving it out changes nothing).
    #[cfg(test)]
    pub(super) fn keep_past_the_exit(&mut self) {
        self.beyond.iter_mut().for_each(|b| *b = f64::INFINITY);
        if let Some(looks) = &mut self.looks {
            looks.past.iter_mut().for_each(|p| *p = f64::INFINITY);
        }
    }

    /// Approximate heap memory held, bytes.
    pub fn memory_bytes(&self) -> usize {
        (std::mem::size_of::<(Point, Point)>() + 8) * self.dirs.len()
            + 8 * self.stops.len()
            + self.crossings.as_ref().map_or(0, |c| {
                4 * c.offsets.len()
                    + 8 * c.r.len()
                    + 8 * c.cells.len()
                    + 4 * c.lin.len()
                    + 8 * c.kappa.len()
            })
            + self.looks.as_ref().map_or(0, |l| {
                4 * l.first.len() + 4 * l.start.len() + 16 * l.pq.len() + 8 * l.past.len()
            })
    }

    /// Ray indices whose directions can meet `region` (a superset: callers
    /// intersect each ray with the region anyway).
    pub(super) fn range(&self, region: &Region, buf: &mut Vec<Point>) -> Option<(usize, usize)> {
        let (lo, hi, margin) = if region.disk.is_none() {
            // The extreme corners' angles, to within 5e-4 rad, then that and
            // one ray more on each side: cheaper than atan2 for the many
            // squares of a history.
            let h = self.source.frame;
            let o = self.source.pos;
            let r = &region.rect;
            let angle = |(x, y): (f64, f64)| {
                let (dx, dy) = (x - o.x, y - o.y);
                approx_atan2(h.x * dy - h.y * dx, h.x * dx + h.y * dy)
            };
            // Seen from outside, two corners bound the rectangle's angles:
            // the ones on the diagonal the source does not face.
            let (left, right) = (o.x < r.x0, o.x > r.x1);
            let (below, above) = (o.y < r.y0, o.y > r.y1);
            let pair = match (left, right, below, above) {
                (true, _, true, _) | (_, true, _, true) => Some(((r.x1, r.y0), (r.x0, r.y1))),
                (true, _, _, true) | (_, true, true, _) => Some(((r.x0, r.y0), (r.x1, r.y1))),
                (true, _, false, false) => Some(((r.x0, r.y0), (r.x0, r.y1))),
                (_, true, false, false) => Some(((r.x1, r.y0), (r.x1, r.y1))),
                (false, false, true, _) => Some(((r.x0, r.y0), (r.x1, r.y0))),
                (false, false, _, true) => Some(((r.x0, r.y1), (r.x1, r.y1))),
                (false, false, false, false) => None,
            };
            let (lo, hi) = match pair {
                Some((c0, c1)) => {
                    let (a0, a1) = (angle(c0), angle(c1));
                    (a0.min(a1), a0.max(a1))
                }
                // The source inside the rectangle: every ray.
                None => (f64::NEG_INFINITY, f64::INFINITY),
            };
            (lo, hi, 1.0 + 5e-4 / self.step)
        } else {
            let (lo, hi) = angular_span(&self.source, region, buf)?;
            (lo, hi, 0.0)
        };
        let n = self.dirs.len();
        // Non-negative values, so casts truncate as floor would (without
        // SSE4.1, `floor` is a libm call).
        let from = ((lo - self.lo) / self.step - margin).clamp(0.0, n as f64);
        let to = ((hi - self.lo) / self.step + margin).clamp(0.0, n as f64);
        let a = from as usize;
        let b = ((to as usize) + usize::from((to as usize as f64) < to)).min(n);
        (a < b).then_some((a, b))
    }
}

/// `atan2(y, x)` to within 5e-4 rad (measured: 2.1e-4): a degree-7 odd
/// polynomial for the arctangent on [0, 1], and the octant symmetries.
#[inline]
fn approx_atan2(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ax < ay { (ax, ay) } else { (ay, ax) };
    if hi == 0.0 {
        return 0.0;
    }
    let a = lo / hi;
    let s = a * a;
    let mut r = (((-0.046_496_474_9 * s + 0.159_314_22) * s - 0.327_622_764) * s) * a + a;
    if ay > ax {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 { -r } else { r }
}

/// A target class on its source's rays.
pub(super) struct ClassRays {
    /// Index of the source's rays.
    pub rays: usize,
    /// The class's speed.
    pub speed: f64,
    /// `λ_c/(spread·v_c)` times the angular step: targets per unit of ray
    /// length, per ray.
    pub weight: f64,
}

/// The smaller of two numbers that are not NaN (one `minsd`: `f64::min`
/// also handles NaN, at three instructions, in the hottest loops).
#[inline(always)]
pub(super) fn min(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// The larger of two numbers that are not NaN.
#[inline(always)]
pub(super) fn max(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

#[cfg(test)]
mod tests {
    use super::{SourceRays, approx_atan2};
    use crate::geometry::{Rect, Region};
    use crate::scenario::builtins;

    #[test]
    fn ray_ranges_hold_every_ray_that_meets_a_rectangle() {
        let s = builtins().remove(0);
        let rays = SourceRays::for_scenario(&s);
        let mut buf = Vec::new();
        // Rectangles on a grid of corners, inside the zone and across its
        // edges, beside and around the sources (at -1 and 301).
        let coords = [
            -40.0, -1.5, -1.0, 0.0, 37.0, 99.0, 100.0, 150.0, 201.0, 299.0, 301.0, 330.0,
        ];
        let mut checked = 0;
        for &x0 in &coords {
            for &x1 in coords.iter().filter(|&&x| x > x0) {
                for &y0 in &coords {
                    for &y1 in coords.iter().filter(|&&y| y > y0) {
                        let region = Region {
                            rect: Rect { x0, y0, x1, y1 },
                            disk: None,
                        };
                        for sr in &rays {
                            let range = sr.range(&region, &mut buf);
                            for (m, &(d, inv)) in sr.dirs.iter().enumerate() {
                                let Some((p, q)) = region.ray(sr.source.pos, d, inv) else {
                                    continue;
                                };
                                if q > p {
                                    checked += 1;
                                    assert!(
                                        range.is_some_and(|(a, b)| (a..b).contains(&m)),
                                        "ray {m} of {:?} meets {:?} outside {range:?}",
                                        sr.source.pos,
                                        region.rect
                                    );
                                }
                            }
                        }
                    }
                }
            }
        }
        assert!(checked > 10_000, "{checked}");
    }

    #[test]
    fn approx_atan2_is_within_its_bound() {
        let mut worst = 0.0f64;
        for i in 0..20_000 {
            let angle = -std::f64::consts::PI + i as f64 * (std::f64::consts::TAU / 20_000.0);
            for r in [1e-3, 1.0, 1e4] {
                let (y, x) = (r * angle.sin(), r * angle.cos());
                worst = worst.max((approx_atan2(y, x) - y.atan2(x)).abs());
            }
        }
        assert!(worst < 5e-4, "worst error {worst}");
        assert_eq!(approx_atan2(0.0, 0.0), 0.0);
    }
}
