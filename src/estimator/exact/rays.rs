//! The angular grid of each source: the rays along which the exact
//! estimator measures what was seen, and where each ray crosses the
//! elementary grid.

use rayon::prelude::*;

use crate::estimator::elementary::{ElementaryGrid, trace};
use crate::geometry::{Point, Region};
use crate::scenario::{Scenario, Source};
use crate::stats::angular_span;

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
/// the takeoff angles of its cone that reach the zone. Depends on the
/// scenario only; the source's target classes share it.
#[derive(Debug, Clone)]
pub struct SourceRays {
    pub(super) source: Source,
    pub(super) lo: f64,
    pub(super) step: f64,
    /// Unit direction and its componentwise inverse, per ray.
    pub(super) dirs: Vec<(Point, Point)>,
    /// Index of the source in the scenario.
    pub(super) source_index: usize,
    /// Where each ray crosses the elementary grid, when indexed.
    pub(super) crossings: Option<Crossings>,
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
    offsets: Vec<u32>,
    r: Vec<f64>,
    cells: Vec<[u32; 2]>,
    /// `cells[k]` as an index into the whole grid, `b·nx + a`.
    lin: Vec<u32>,
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
}

impl SourceRays {
    /// The grids of every source of a scenario with a non-zero rate, at
    /// [`RAYS_PER_PI_SQUARE`] when every type's field of view is a square,
    /// else [`RAYS_PER_PI`].
    pub fn for_scenario(s: &Scenario) -> Vec<SourceRays> {
        Self::with_density(s, Self::density(s))
    }

    /// Rays per π of the grids on `s`: [`RAYS_PER_PI_SQUARE`] when every
    /// type's field of view is a square, else [`RAYS_PER_PI`].
    pub fn density(s: &Scenario) -> f64 {
        if s.all_square() {
            RAYS_PER_PI_SQUARE
        } else {
            RAYS_PER_PI
        }
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
                    source_index: j,
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
