//! The exact estimator: the conditional expectation of the count under the
//! model, given what the sensors saw now and in the history.

use std::sync::OnceLock;

use rayon::prelude::*;

use super::elementary::ElementaryGrid;
use super::{Estimator, Target, for_reach};
use crate::geometry::{Point, Region, union_within};
use crate::scenario::{Cell, FovSpec, Scenario, Source};
use crate::search::ValueGrid;
use crate::stats::{Stats, angular_span};

/// Rays per π radians of takeoff angle in the angular grid of each source,
/// for scenarios with square fields of view (the fast path).
///
/// The midpoint rule's error comes from the kinks of the integrand (corners
/// of the fields of view); the cost of a plan is about linear in this number.
/// Measured on the reference workload (`paper-v10`, 10 sensors, 16 steps of
/// history, every cell a sensor can reach at T = 3) against 4096 rays per π,
/// with values averaging 1.80 targets (`cargo run --release -p vigil-loadtest
/// --example accuracy`): 96 → max 1.7e-2, mean 3.6e-3; 128 → max 1.2e-2,
/// mean 2.2e-3 (0.12 %); 192 → 5.7e-3, 1.1e-3; 384 → 1.7e-3, 3.0e-4.
/// 128 keeps the error under the statistical error of any realistic check
/// (`tests/model.rs` checks against Monte Carlo) at a third of the cost of 384.
pub const RAYS_PER_PI_SQUARE: f64 = 128.0;

/// Rays per π for other fields of view (circles), which the general path
/// evaluates: there the excluded areas of coordination are integrated by
/// the same rule, whose error next to a source is several times larger.
pub const RAYS_PER_PI: f64 = 384.0;

/// The fixed angular grid of one source: midpoints of `n` equal steps over
/// the takeoff angles that reach the zone. Depends on the scenario only.
#[derive(Debug, Clone)]
pub struct SourceRays {
    source: Source,
    lo: f64,
    step: f64,
    /// Unit direction and its componentwise inverse, per ray.
    dirs: Vec<(Point, Point)>,
    /// `λ_j/(π v)·step`: targets per unit of ray length, per ray.
    weight: f64,
    /// Where each ray crosses the elementary grid, when indexed.
    crossings: Option<Crossings>,
}

/// The elementary rectangles each ray of a source crosses on its way
/// through the zone, in order: ray `m` enters `cells[k]` at distance `r[k]`
/// from the source, for `k` in `offsets[m]..offsets[m+1]`, and leaves the
/// last one at the ray's next `r` (each ray's `r` has one entry more than
/// its cells, so ray `m`'s distances start at `offsets[m] + m`). With it a
/// seen interval is spread over rectangles by a merge of two sorted lists
/// instead of a grid walk, at every step of every request.
#[derive(Debug, Clone)]
struct Crossings {
    offsets: Vec<u32>,
    r: Vec<f64>,
    cells: Vec<[u32; 2]>,
    /// `cells[k]` as an index into the whole grid, `b·nx + a`.
    lin: Vec<u32>,
}

impl Crossings {
    /// Ray `m`'s entry distances (and final exit) and rectangles.
    #[inline]
    fn of(&self, m: usize) -> (&[f64], &[[u32; 2]], &[u32]) {
        let (a, b) = (self.offsets[m] as usize, self.offsets[m + 1] as usize);
        (
            &self.r[a + m..b + m + 1],
            &self.cells[a..b],
            &self.lin[a..b],
        )
    }
}

impl SourceRays {
    /// The grids of every source of a scenario with a non-zero rate, at
    /// [`RAYS_PER_PI_SQUARE`] or [`RAYS_PER_PI`] by its field of view.
    pub fn for_scenario(s: &Scenario) -> Vec<SourceRays> {
        let density = match s.fov {
            FovSpec::Square { .. } => RAYS_PER_PI_SQUARE,
            FovSpec::Circle { .. } => RAYS_PER_PI,
        };
        Self::with_density(s, density)
    }

    /// The same at `rays_per_pi` rays per π radians (for accuracy studies).
    pub fn with_density(s: &Scenario, rays_per_pi: f64) -> Vec<SourceRays> {
        let zone = s.zone_region();
        let mut buf = Vec::new();
        s.sources
            .iter()
            .filter(|src| src.rate > 0.0)
            .filter_map(|src| {
                let (lo, hi) = angular_span(src, &zone, &mut buf)?;
                let n = (((hi - lo) / std::f64::consts::PI) * rays_per_pi)
                    .ceil()
                    .max(1.0) as usize;
                let step = (hi - lo) / n as f64;
                // No component exactly 0, so slab intersections need no
                // special case (a tilt of 1e-12 rad changes nothing).
                let nudge = |c: f64| if c == 0.0 { 1e-12 } else { c };
                let dirs = (0..n)
                    .map(|m| {
                        let d = src.direction(lo + (m as f64 + 0.5) * step);
                        let d = Point::new(nudge(d.x), nudge(d.y));
                        (d, Point::new(1.0 / d.x, 1.0 / d.y))
                    })
                    .collect();
                Some(SourceRays {
                    source: *src,
                    lo,
                    step,
                    dirs,
                    weight: src.rate / (std::f64::consts::PI * s.speed) * step,
                    crossings: None,
                })
            })
            .collect()
    }

    /// Indexes where every ray crosses `grid`'s rectangles (see
    /// [`ExactEstimator`]), unless that would take more than about 100 bytes
    /// per lattice cell; without the index, plans walk the grid instead
    /// (the same values, more slowly).
    pub fn index_crossings(rays: &mut [SourceRays], s: &Scenario, grid: &ElementaryGrid) {
        let (nx, ny) = grid.dims();
        let bound: usize = rays.iter().map(|sr| sr.dirs.len() * (nx + ny)).sum();
        if bound > (5 * s.cell_count()).max(1 << 20) || nx * ny > u32::MAX as usize {
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
                    trace(
                        grid,
                        (0, nx, 0, ny),
                        sr.source.pos,
                        d,
                        inv,
                        r0,
                        r1,
                        |a, b, from, _| {
                            r.push(from);
                            cells.push([a as u32, b as u32]);
                            lin.push((b * nx + a) as u32);
                        },
                    );
                    r.push(r1);
                } else {
                    r.push(0.0);
                }
                offsets.push(cells.len() as u32);
            }
            sr.crossings = Some(Crossings {
                offsets,
                r,
                cells,
                lin,
            });
        });
    }

    /// Approximate heap memory held, bytes.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<(Point, Point)>() * self.dirs.len()
            + self.crossings.as_ref().map_or(0, |c| {
                4 * c.offsets.len() + 8 * c.r.len() + 8 * c.cells.len()
            })
    }

    /// Ray indices whose directions can meet `region` (a superset: callers
    /// intersect each ray with the region anyway).
    fn range(&self, region: &Region, buf: &mut Vec<Point>) -> Option<(usize, usize)> {
        let (lo, hi, margin) = if region.disk.is_none() {
            // The extreme corners' angles, to within 5e-4 rad, then that and
            // one ray more on each side: cheaper than atan2 for the many
            // squares of a history.
            let h = self.source.heading.unit();
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

/// What the rays of one source saw: per ray, the union of the intervals
/// seen `s` steps ago, each pushed by `v·s` (the distance a target has flown
/// since), merged into sorted disjoint intervals. At step `t` the seen set is
/// the same union pushed a further `v·t`. Stored compactly, ray by ray.
struct RayHits {
    /// `hits[offsets[m]..offsets[m+1]]` are ray `m`'s intervals.
    offsets: Vec<u32>,
    hits: Vec<(f64, f64)>,
}

impl RayHits {
    fn new(sr: &SourceRays, observed: &[Vec<Region>], speed: f64) -> Self {
        let mut buf = Vec::new();
        let n = sr.dirs.len();
        let o = sr.source.pos;
        // Regions go track by track (the i-th region of every step: one
        // sensor's fields of view, newest first). Consecutive ones overlap on
        // most rays, so each ray's intervals from one track are merged as
        // they come, in a buffer over the track's rays; what is left (about
        // one interval per ray and track) is sorted by ray afterwards.
        let tracks = observed.iter().map(Vec::len).max().unwrap_or(0);
        let mut pieces: Vec<(u32, f64, f64)> = Vec::new();
        let mut open: Vec<(f64, f64)> = Vec::new();
        let mut spans = Vec::with_capacity(observed.len());
        for i in 0..tracks {
            spans.clear();
            let (mut lo, mut hi) = (n, 0);
            for (s, regions) in observed.iter().enumerate() {
                let Some(region) = regions.get(i) else {
                    continue;
                };
                if let Some((a, b)) = sr.range(region, &mut buf) {
                    spans.push((a, b, speed * s as f64, region));
                    (lo, hi) = (lo.min(a), hi.max(b));
                }
            }
            if spans.is_empty() {
                continue;
            }
            open.clear();
            open.resize(hi - lo, EMPTY);
            for &(a, b, shift, region) in &spans {
                let open = &mut open[a - lo..b - lo];
                if region.disk.is_none() {
                    // Slab test, branch-free (no direction component is 0).
                    let r = &region.rect;
                    let (x0, x1, y0, y1) = (r.x0 - o.x, r.x1 - o.x, r.y0 - o.y, r.y1 - o.y);
                    for (j, (&(_, inv), cur)) in sr.dirs[a..b].iter().zip(open).enumerate() {
                        let (tx0, tx1) = (x0 * inv.x, x1 * inv.x);
                        let (ty0, ty1) = (y0 * inv.y, y1 * inv.y);
                        let p = max(max(min(tx0, tx1), min(ty0, ty1)), 0.0);
                        let q = min(max(tx0, tx1), max(ty0, ty1));
                        if p <= q {
                            extend(cur, (a + j) as u32, p + shift, q + shift, &mut pieces);
                        }
                    }
                } else {
                    for (j, cur) in open.iter_mut().enumerate() {
                        let (d, inv) = sr.dirs[a + j];
                        if let Some((p, q)) = region.ray(o, d, inv) {
                            extend(cur, (a + j) as u32, p + shift, q + shift, &mut pieces);
                        }
                    }
                }
            }
            for (j, &(p, q)) in open.iter().enumerate() {
                if p <= q {
                    pieces.push(((lo + j) as u32, p, q));
                }
            }
        }
        // By ray (a counting sort), then each ray's few pieces by start,
        // merged into sorted disjoint intervals.
        let mut offsets = vec![0u32; n + 1];
        for &(m, ..) in &pieces {
            offsets[m as usize + 1] += 1;
        }
        for m in 0..n {
            offsets[m + 1] += offsets[m];
        }
        let mut next = offsets.clone();
        let mut sorted = vec![(0.0, 0.0); pieces.len()];
        for &(m, p, q) in &pieces {
            sorted[next[m as usize] as usize] = (p, q);
            next[m as usize] += 1;
        }
        let mut hits: Vec<(f64, f64)> = Vec::with_capacity(sorted.len());
        let mut start = 0;
        for m in 0..n {
            let list = &mut sorted[start..offsets[m + 1] as usize];
            start = offsets[m + 1] as usize;
            list.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            let first = hits.len();
            for &(p, q) in list.iter() {
                match hits[first..].last_mut() {
                    Some(last) if p <= last.1 => last.1 = last.1.max(q),
                    _ => hits.push((p, q)),
                }
            }
            offsets[m + 1] = hits.len() as u32;
        }
        RayHits { offsets, hits }
    }

    /// Ray `m`'s seen intervals (sorted, disjoint) as of step 0.
    #[inline]
    fn of(&self, m: usize) -> &[(f64, f64)] {
        &self.hits[self.offsets[m] as usize..self.offsets[m + 1] as usize]
    }
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

/// No interval yet (`p > q`).
const EMPTY: (f64, f64) = (f64::INFINITY, f64::NEG_INFINITY);

/// Extends `cur`, ray `m`'s interval being merged, by `[p, q]` when they
/// overlap; otherwise moves `cur` to `pieces` and starts again from `[p, q]`.
#[inline]
fn extend(cur: &mut (f64, f64), m: u32, p: f64, q: f64, pieces: &mut Vec<(u32, f64, f64)>) {
    if p <= cur.1 && q >= cur.0 {
        *cur = (min(cur.0, p), max(cur.1, q));
    } else {
        if cur.0 <= cur.1 {
            pieces.push((m, cur.0, cur.1));
        }
        *cur = (p, q);
    }
}

/// A half-open block `[a0, a1) × [b0, b1)` of elementary rectangles.
type Block = (usize, usize, usize, usize);

/// Prefix sums over a block of rectangles.
struct BlockSums {
    a0: usize,
    b0: usize,
    w: usize,
    prefix: Vec<f64>,
}

impl BlockSums {
    /// The sum over a sub-block (global indices).
    #[inline]
    fn sum(&self, (a0, a1, b0, b1): Block) -> f64 {
        let p = |a: usize, b: usize| self.prefix[(b - self.b0) * self.w + (a - self.a0)];
        p(a1, b1) - p(a0, b1) - p(a1, b0) + p(a0, b0)
    }
}

/// The windows of one step: one shared by every sensor when their reaches
/// lie close together (each seen interval is walked once), otherwise one
/// per sensor (memory bounded by the reaches on a large lattice).
struct StepWindows {
    blocks: Vec<Block>,
    built: Vec<OnceLock<Window>>,
    slot: Vec<usize>,
}

impl StepWindows {
    fn new(grid: &ElementaryGrid, s: &Scenario, starts: &[Cell], t: usize) -> Self {
        let ti = t as i32;
        let reach: Vec<Block> = starts
            .iter()
            .map(|start| {
                let lo = Cell {
                    col: (start.col - ti).max(0),
                    row: (start.row - ti).max(0),
                };
                let hi = Cell {
                    col: (start.col + ti).min(s.cols - 1),
                    row: (start.row + ti).min(s.rows - 1),
                };
                let (a0, _, b0, _) = grid.span(lo);
                let (_, a1, _, b1) = grid.span(hi);
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
        if nx * ny <= 1 << 16 {
            // A small grid: one window over all of it (the fastest to fill).
            Self {
                blocks: vec![(0, nx, 0, ny)],
                built: vec![OnceLock::new()],
                slot: vec![0; reach.len()],
            }
        } else if !reach.is_empty() && size(&bbox) <= (1 << 16).max(2 * total) {
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
struct Window {
    a0: usize,
    b0: usize,
    na: usize,
    nb: usize,
    unseen: Vec<f64>,
}

/// The exact conditional expectation of the count in `F_k` at step `t`:
/// the reported targets whose straight-line position is in `F_k`, plus
/// `U(k,t)`, the expected targets in `F_k` that no sensor can have seen.
///
/// With `O_s` the union of the fields of view `s` steps ago, a point `q` on
/// the ray of angle `α` from source `j` at distance `r` holds at step `t` a
/// target that was at distance `r − v(t+s)` at step `−s` (not yet emitted if
/// that is negative, and then unseen). It is unseen when none of those
/// backtracked points lies in `O_s`. The stationary density in polar
/// coordinates around the source is `λ_j/(πv)·dr·dα`, so
/// `U(k,t) = d̂_k − Σ_j λ_j/(πv) ∫ |R_k(α) ∩ ⋃_s (O_s(α) + v(t+s))| dα`:
/// the closed-form stationary count less the seen part, measured on each
/// ray by interval arithmetic and integrated over `α` by the midpoint rule on
/// a fixed grid of rays per π ([`RAYS_PER_PI_SQUARE`] or [`RAYS_PER_PI`]). Excluded regions are removed
/// the same way (unshifted), and known targets inside them are not counted.
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
    /// Per source (aligned with `rays`), where its rays crossed what was seen.
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
        let seen = rays
            .par_iter()
            .map(|sr| RayHits::new(sr, observed, scenario.speed))
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

    /// The unseen mass at step `t` of the elementary rectangles of a block.
    fn window(&self, grid: &ElementaryGrid, (a0, a1, b0, b1): Block, t: usize) -> Window {
        let s = self.scenario;
        let (na, nb) = (a1 - a0, b1 - b0);
        let mut unseen = Vec::with_capacity(na * nb);
        for b in b0..b1 {
            for a in a0..a1 {
                unseen.push(grid.mass(a, a + 1, b, b + 1));
            }
        }
        let lift = s.speed * t as f64;
        let block = (a0, a1, b0, b1);
        let whole = {
            let (nx, ny) = grid.dims();
            block == (0, nx, 0, ny)
        };
        // The sources split among the threads, each adding into its own
        // buffer (one per thread, not per source: the buffers are summed).
        let chunk = self
            .rays
            .len()
            .div_ceil(rayon::current_num_threads())
            .max(1);
        let per_thread: Vec<Vec<f64>> = self
            .rays
            .par_chunks(chunk)
            .zip(self.seen.par_chunks(chunk))
            .map(|(rays, seen)| {
                let mut acc = vec![0.0; na * nb];
                for (sr, seen) in rays.iter().zip(seen) {
                    self.accumulate(grid, block, whole, lift, sr, seen, &mut acc);
                }
                acc
            })
            .collect();
        let mut per_thread = per_thread.into_iter();
        if let Some(first) = per_thread.next() {
            for (u, s) in unseen.iter_mut().zip(&first) {
                *u -= s;
            }
            for acc in per_thread {
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

    /// Adds to `acc` what the rays of one source saw in each rectangle of
    /// `block` at lift `v·t`, times the source's weight.
    #[allow(clippy::too_many_arguments)]
    fn accumulate(
        &self,
        grid: &ElementaryGrid,
        block: Block,
        whole: bool,
        lift: f64,
        sr: &SourceRays,
        seen: &RayHits,
        acc: &mut [f64],
    ) {
        let w = sr.weight;
        if let (true, Some(cr)) = (whole, &sr.crossings) {
            // The block is the grid: every ray, no bounds to check.
            for m in 0..sr.dirs.len() {
                let (rs, _, lin) = cr.of(m);
                let hits = seen.of(m);
                if hits.is_empty() || lin.is_empty() {
                    continue;
                }
                let end = rs[lin.len()] - lift;
                let from = hits.partition_point(|&(_, q)| q + lift <= rs[0]);
                let mut k = usize::MAX;
                for &(p, q) in &hits[from..] {
                    if p >= end {
                        break;
                    }
                    let (p, q) = (p + lift, q + lift);
                    k = next_crossing(rs, k, p);
                    while k < lin.len() && rs[k] < q {
                        acc[lin[k] as usize] += w * (min(rs[k + 1], q) - max(rs[k], p));
                        k += 1;
                    }
                }
            }
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
            let (d, inv) = sr.dirs[m];
            let Some((wa, wb)) = region.ray(sr.source.pos, d, inv) else {
                continue;
            };
            // The seen union at step t, clipped to the block.
            let (wa, wb) = (wa - lift, wb - lift);
            let from = hits.partition_point(|&(_, q)| q <= wa);
            let Some(cr) = &sr.crossings else {
                for &(p, q) in &hits[from..] {
                    if p >= wb {
                        break;
                    }
                    let (p, q) = (max(p, wa) + lift, min(q, wb) + lift);
                    if q > p {
                        walk(grid, block, acc, sr.source.pos, d, inv, p, q, w);
                    }
                }
                continue;
            };
            let (rs, cells, _) = cr.of(m);
            let mut k = usize::MAX;
            for &(p, q) in &hits[from..] {
                if p >= wb {
                    break;
                }
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
                        acc[(b - b0) * na + (a - a0)] += w * len;
                    }
                    k += 1;
                }
            }
        }
    }

    /// `U` by integrating every ray that crosses `fk` (the general path).
    fn unseen_by_rays(&self, k: Cell, fk: &Region, t: usize, excluded: &[&Region]) -> f64 {
        let mut buf = Vec::new();
        let mut intervals: Vec<(f64, f64)> = Vec::new();
        let lift = self.scenario.speed * t as f64;
        let mut seen = 0.0;
        for (sr, hits) in self.rays.iter().zip(&self.seen) {
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
            seen += sr.weight * sum;
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

    /// Prefix sums of the unseen mass over `block` (global indices, inside
    /// the window), leaving out the rectangles of excluded regions (fields
    /// of view are unions of rectangles: those whose centre they contain).
    fn block_sums(
        &self,
        grid: &ElementaryGrid,
        win: &Window,
        block: Block,
        excluded: &[Region],
    ) -> BlockSums {
        let (a0, a1, b0, b1) = block;
        let w = a1 - a0 + 1;
        let mut prefix = vec![0.0; w * (b1 - b0 + 1)];
        let xc: Vec<f64> = (a0..a1)
            .map(|a| 0.5 * (grid.xs[a] + grid.xs[a + 1]))
            .collect();
        for (j, b) in (b0..b1).enumerate() {
            let yc = 0.5 * (grid.ys[b] + grid.ys[b + 1]);
            let rows: Vec<&Region> = excluded
                .iter()
                .filter(|x| yc >= x.rect.y0 && yc <= x.rect.y1)
                .collect();
            let mut row = 0.0;
            for (i, a) in (a0..a1).enumerate() {
                if !rows
                    .iter()
                    .any(|x| xc[i] >= x.rect.x0 && xc[i] <= x.rect.x1)
                {
                    row += win.unseen[(b - win.b0) * win.na + (a - win.a0)];
                }
                prefix[(j + 1) * w + i + 1] = prefix[j * w + i + 1] + row;
            }
        }
        BlockSums { a0, b0, w, prefix }
    }
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
/// the ray segment `[r0, r1]` times `w`, rectangle by rectangle.
#[allow(clippy::too_many_arguments)]
fn walk(
    grid: &ElementaryGrid,
    block: Block,
    acc: &mut [f64],
    o: Point,
    d: Point,
    inv: Point,
    r0: f64,
    r1: f64,
    w: f64,
) {
    let (a_lo, b_lo, na) = (block.0, block.2, block.1 - block.0);
    trace(grid, block, o, d, inv, r0, r1, |a, b, from, to| {
        acc[(b - b_lo) * na + (a - a_lo)] += w * (to - from);
    });
}

/// Calls `f(a, b, from, to)` for each elementary rectangle `(a, b)` of
/// `block` the ray segment `[r0, r1]` crosses, in order, with the part of
/// the segment inside it: a 2-D DDA over the breakpoints. The segment lies
/// inside the block; rounding at its edge is clamped.
#[allow(clippy::too_many_arguments)]
fn trace(
    grid: &ElementaryGrid,
    block: Block,
    o: Point,
    d: Point,
    inv: Point,
    r0: f64,
    r1: f64,
    mut f: impl FnMut(usize, usize, f64, f64),
) {
    let (xs, ys) = (&grid.xs, &grid.ys);
    let (a_lo, a_hi, b_lo, b_hi) = (block.0, block.1 - 1, block.2, block.3 - 1);
    let start = Point::new(o.x + d.x * r0, o.y + d.y * r0);
    let mut a = grid.locate_x(start.x, d.x).clamp(a_lo, a_hi);
    let mut b = grid.locate_y(start.y, d.y).clamp(b_lo, b_hi);
    // Distance to the next boundary on each axis (infinite along an axis
    // the ray runs parallel to).
    let forward_x = d.x >= 0.0;
    let forward_y = d.y >= 0.0;
    let next_x = |a: usize| {
        if d.x == 0.0 {
            f64::INFINITY
        } else {
            (xs[if forward_x { a + 1 } else { a }] - o.x) * inv.x
        }
    };
    let next_y = |b: usize| {
        if d.y == 0.0 {
            f64::INFINITY
        } else {
            (ys[if forward_y { b + 1 } else { b }] - o.y) * inv.y
        }
    };
    let (mut tx, mut ty) = (next_x(a), next_y(b));
    let mut r = r0;
    loop {
        let step_x = tx <= ty;
        let boundary = if step_x { tx } else { ty };
        let end = if boundary < r1 { boundary } else { r1 };
        if end > r {
            f(a, b, r, end);
            r = end;
        }
        if boundary >= r1 {
            break;
        }
        if step_x {
            if (forward_x && a == a_hi) || (!forward_x && a == a_lo) {
                break;
            }
            if forward_x {
                a += 1;
            } else {
                a -= 1;
            }
            tx = next_x(a);
        } else {
            if (forward_y && b == b_hi) || (!forward_y && b == b_lo) {
                break;
            }
            if forward_y {
                b += 1;
            } else {
                b -= 1;
            }
            ty = next_y(b);
        }
    }
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
