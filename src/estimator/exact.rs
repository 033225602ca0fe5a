//! The exact estimator: the conditional expectation of the count under the
//! model, given what the sensors saw now and in the history.

use std::sync::OnceLock;

use super::elementary::ElementaryGrid;
use super::{Estimator, Target, for_reach};
use crate::geometry::{Point, Region, union_within};
use crate::scenario::{Cell, FovSpec, Scenario, Source};
use crate::search::ValueGrid;
use crate::stats::{Stats, angular_span};

/// Rays per π radians of takeoff angle in the angular grid of each source.
///
/// The midpoint rule's error on the seen part is about `δ²/8` per kink of
/// the integrand (δ = π/512): below 1e-4 targets per field of view, far
/// under the statistical error of any check or use.
pub const RAYS_PER_PI: f64 = 512.0;

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
}

impl SourceRays {
    /// The grids of every source of a scenario with a non-zero rate.
    pub fn for_scenario(s: &Scenario) -> Vec<SourceRays> {
        let zone = s.zone_region();
        let mut buf = Vec::new();
        s.sources
            .iter()
            .filter(|src| src.rate > 0.0)
            .filter_map(|src| {
                let (lo, hi) = angular_span(src, &zone, &mut buf)?;
                let n = (((hi - lo) / std::f64::consts::PI) * RAYS_PER_PI)
                    .ceil()
                    .max(1.0) as usize;
                let step = (hi - lo) / n as f64;
                let dirs = (0..n)
                    .map(|m| {
                        let d = src.direction(lo + (m as f64 + 0.5) * step);
                        (d, Point::new(1.0 / d.x, 1.0 / d.y))
                    })
                    .collect();
                Some(SourceRays {
                    source: *src,
                    lo,
                    step,
                    dirs,
                    weight: src.rate / (std::f64::consts::PI * s.speed) * step,
                })
            })
            .collect()
    }

    /// Ray indices whose directions can meet `region`.
    fn range(&self, region: &Region, buf: &mut Vec<Point>) -> Option<(usize, usize)> {
        let (lo, hi) = angular_span(&self.source, region, buf)?;
        let n = self.dirs.len();
        let a = (((lo - self.lo) / self.step).floor().max(0.0) as usize).min(n);
        let b = (((hi - self.lo) / self.step).ceil().max(0.0) as usize).min(n);
        (a < b).then_some((a, b))
    }
}

/// A region seen `s` steps ago, as crossed by the rays of one source.
struct Blob {
    /// `v·s`: how far a target has flown since.
    shift: f64,
    first: usize,
    /// Ray interval per ray from `first`; `(∞, −∞)` where the ray misses.
    intervals: Vec<(f64, f64)>,
    r_min: f64,
    r_max: f64,
}

impl Blob {
    /// The blobs' intervals on ray `m`, pushed `lift` further, into `out`.
    #[inline]
    fn push_interval(&self, m: usize, lift: f64, out: &mut Vec<(f64, f64)>) {
        if m >= self.first
            && let Some(&(p, q)) = self.intervals.get(m - self.first)
            && p <= q
        {
            let l = self.shift + lift;
            out.push((p + l, q + l));
        }
    }

    fn may_reach(&self, a: usize, b: usize, lift: f64, (r0, r1): (f64, f64)) -> bool {
        self.first < b
            && self.first + self.intervals.len() > a
            && self.r_min + self.shift + lift <= r1
            && self.r_max + self.shift + lift >= r0
    }
}

/// A half-open block `[a0, a1) × [b0, b1)` of elementary rectangles.
type Block = (usize, usize, usize, usize);

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
/// a fixed grid of [`RAYS_PER_PI`] rays per π. Excluded regions are removed
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
    /// Per source (aligned with `rays`), the observed regions.
    blobs: Vec<Vec<Blob>>,
    /// Sensors' starts, whose windows the fast path uses.
    starts: Vec<Cell>,
    /// Per sensor, per step 1..=T, built on first use (empty without a grid).
    windows: Vec<Vec<OnceLock<Window>>>,
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
        let mut buf = Vec::new();
        let blobs = rays
            .iter()
            .map(|sr| {
                let mut out = Vec::new();
                for (s, regions) in observed.iter().enumerate() {
                    for region in regions {
                        let Some((a, b)) = sr.range(region, &mut buf) else {
                            continue;
                        };
                        let intervals = sr.dirs[a..b]
                            .iter()
                            .map(|&(d, inv)| {
                                region
                                    .ray(sr.source.pos, d, inv)
                                    .unwrap_or((f64::INFINITY, f64::NEG_INFINITY))
                            })
                            .collect();
                        let (r_min, r_max) = region.radial_bounds(sr.source.pos);
                        out.push(Blob {
                            shift: scenario.speed * s as f64,
                            first: a,
                            intervals,
                            r_min,
                            r_max,
                        });
                    }
                }
                out
            })
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
            blobs,
            starts: starts.to_vec(),
            windows: match grid {
                Some(_) => starts
                    .iter()
                    .map(|_| (0..horizon).map(|_| OnceLock::new()).collect())
                    .collect(),
                None => Vec::new(),
            },
        }
    }

    /// The window of `sensor` at step `t`, if the fast path applies.
    fn window_of(&self, sensor: usize, t: usize) -> Option<(&ElementaryGrid, &Window)> {
        let grid = self.grid?;
        let cell = self.windows.get(sensor)?.get(t.checked_sub(1)?)?;
        Some((
            grid,
            cell.get_or_init(|| self.window(grid, self.starts[sensor], t)),
        ))
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

    /// The unseen mass of the elementary rectangles a sensor at `start` can
    /// cover at step `t`.
    fn window(&self, grid: &ElementaryGrid, start: Cell, t: usize) -> Window {
        let s = self.scenario;
        let ti = t as i32;
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
        let (na, nb) = (a1 - a0, b1 - b0);
        let mut unseen = Vec::with_capacity(na * nb);
        for b in b0..b1 {
            for a in a0..a1 {
                unseen.push(grid.mass(a, a + 1, b, b + 1));
            }
        }
        let mut win = Window {
            a0,
            b0,
            na,
            nb,
            unseen,
        };
        let rect = crate::geometry::Rect {
            x0: grid.xs[a0],
            y0: grid.ys[b0],
            x1: grid.xs[a1],
            y1: grid.ys[b1],
        };
        let region = Region { rect, disk: None };
        let lift = s.speed * t as f64;
        let mut buf = Vec::new();
        let mut intervals = Vec::new();
        for (sr, blobs) in self.rays.iter().zip(&self.blobs) {
            let Some((ma, mb)) = sr.range(&region, &mut buf) else {
                continue;
            };
            let radial = region.radial_bounds(sr.source.pos);
            let cands: Vec<&Blob> = blobs
                .iter()
                .filter(|bl| bl.may_reach(ma, mb, lift, radial))
                .collect();
            if cands.is_empty() {
                continue;
            }
            for m in ma..mb {
                let (d, inv) = sr.dirs[m];
                let Some((wa, wb)) = region.ray(sr.source.pos, d, inv) else {
                    continue;
                };
                intervals.clear();
                for bl in &cands {
                    bl.push_interval(m, lift, &mut intervals);
                }
                if intervals.is_empty() {
                    continue;
                }
                intervals.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
                // Walk the union of the seen intervals, clipped to the window.
                let mut reach = wa;
                for &(p, q) in &intervals {
                    let (p, q) = (p.max(reach), q.min(wb));
                    if q > p {
                        walk(grid, &mut win, sr.source.pos, d, inv, p, q, sr.weight);
                        reach = q;
                    }
                }
            }
        }
        win
    }

    /// `U` by integrating every ray that crosses `fk` (the general path).
    fn unseen_by_rays(&self, k: Cell, fk: &Region, t: usize, excluded: &[&Region]) -> f64 {
        let mut buf = Vec::new();
        let mut intervals: Vec<(f64, f64)> = Vec::new();
        let lift = self.scenario.speed * t as f64;
        let mut seen = 0.0;
        for (sr, blobs) in self.rays.iter().zip(&self.blobs) {
            let Some((a, b)) = sr.range(fk, &mut buf) else {
                continue;
            };
            let radial = fk.radial_bounds(sr.source.pos);
            let cands: Vec<&Blob> = blobs
                .iter()
                .filter(|bl| bl.may_reach(a, b, lift, radial))
                .collect();
            if cands.is_empty() && excluded.is_empty() {
                continue;
            }
            let mut sum = 0.0;
            for m in a..b {
                let (d, inv) = sr.dirs[m];
                let Some((lo, hi)) = fk.ray(sr.source.pos, d, inv) else {
                    continue;
                };
                intervals.clear();
                for bl in &cands {
                    bl.push_interval(m, lift, &mut intervals);
                }
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

    /// The sensor's window at step `t` and `k`'s block relative to it, when
    /// the fast path applies.
    fn block(&self, sensor: usize, k: Cell, t: usize) -> Option<(&Window, Block)> {
        let (grid, win) = self.window_of(sensor, t)?;
        let (a0, a1, b0, b1) = grid.span(k);
        (a0 >= win.a0 && b0 >= win.b0 && a1 <= win.a0 + win.na && b1 <= win.b0 + win.nb)
            .then(|| (win, (a0 - win.a0, a1 - win.a0, b0 - win.b0, b1 - win.b0)))
    }

    /// Per rectangle of the window, whether an excluded region covers it.
    fn mask(&self, grid: &ElementaryGrid, win: &Window, excluded: &[Region]) -> Vec<bool> {
        let mut mask = vec![false; win.na * win.nb];
        for x in excluded {
            // Excluded fields of view are unions of rectangles: mark those
            // whose centre they contain.
            for b in 0..win.nb {
                let yc = 0.5 * (grid.ys[win.b0 + b] + grid.ys[win.b0 + b + 1]);
                if yc < x.rect.y0 || yc > x.rect.y1 {
                    continue;
                }
                for a in 0..win.na {
                    let xc = 0.5 * (grid.xs[win.a0 + a] + grid.xs[win.a0 + a + 1]);
                    if xc >= x.rect.x0 && xc <= x.rect.x1 {
                        mask[b * win.na + a] = true;
                    }
                }
            }
        }
        mask
    }
}

/// Subtracts `weight·length` of the ray segment `[r0, r1]` from the unseen
/// mass of each elementary rectangle it crosses.
#[allow(clippy::too_many_arguments)]
fn walk(
    grid: &ElementaryGrid,
    win: &mut Window,
    o: Point,
    d: Point,
    inv: Point,
    r0: f64,
    r1: f64,
    weight: f64,
) {
    let (xs, ys) = (&grid.xs, &grid.ys);
    let start = Point::new(o.x + d.x * r0, o.y + d.y * r0);
    let mut a = ElementaryGrid::locate(xs, start.x, d.x);
    let mut b = ElementaryGrid::locate(ys, start.y, d.y);
    let mut r = r0;
    loop {
        let tx = if d.x > 0.0 {
            (xs[a + 1] - o.x) * inv.x
        } else if d.x < 0.0 {
            (xs[a] - o.x) * inv.x
        } else {
            f64::INFINITY
        };
        let ty = if d.y > 0.0 {
            (ys[b + 1] - o.y) * inv.y
        } else if d.y < 0.0 {
            (ys[b] - o.y) * inv.y
        } else {
            f64::INFINITY
        };
        let next = tx.min(ty).min(r1);
        if next > r && a >= win.a0 && b >= win.b0 && a < win.a0 + win.na && b < win.b0 + win.nb {
            win.unseen[(b - win.b0) * win.na + (a - win.a0)] -= weight * (next - r);
        }
        r = r.max(next);
        if r >= r1 {
            break;
        }
        if tx <= ty {
            if d.x > 0.0 {
                a += 1;
                if a + 1 >= xs.len() {
                    break;
                }
            } else {
                if a == 0 {
                    break;
                }
                a -= 1;
            }
        } else if d.y > 0.0 {
            b += 1;
            if b + 1 >= ys.len() {
                break;
            }
        } else {
            if b == 0 {
                break;
            }
            b -= 1;
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
        let (Some(grid), Some((win, (a0, a1, b0, b1)))) = (self.grid, self.block(sensor, k, t))
        else {
            return known + self.unseen_by_rays(k, &fk, t, &near);
        };
        let near: Vec<Region> = near.into_iter().copied().collect();
        let mask = (!near.is_empty()).then(|| self.mask(grid, win, &near));
        let mut unseen = 0.0;
        for b in b0..b1 {
            for a in a0..a1 {
                let i = b * win.na + a;
                if mask.as_ref().is_none_or(|m| !m[i]) {
                    unseen += win.unseen[i];
                }
            }
        }
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
        // Prefix sums of the (masked) unseen mass over the window.
        let mask = (!excluded.is_empty()).then(|| self.mask(grid, win, excluded));
        let w = win.na + 1;
        let mut prefix = vec![0.0; w * (win.nb + 1)];
        for b in 0..win.nb {
            let mut row = 0.0;
            for a in 0..win.na {
                let i = b * win.na + a;
                if mask.as_ref().is_none_or(|m| !m[i]) {
                    row += win.unseen[i];
                }
                prefix[(b + 1) * w + a + 1] = prefix[b * w + a + 1] + row;
            }
        }
        let sum = |a0: usize, a1: usize, b0: usize, b1: usize| {
            prefix[b1 * w + a1] - prefix[b0 * w + a1] - prefix[b1 * w + a0] + prefix[b0 * w + a0]
        };
        // Known targets at step t that no excluded region holds.
        let moved: Vec<Point> = self
            .known
            .iter()
            .map(|tg| tg.at(t))
            .filter(|&p| s.in_zone(p) && !excluded.iter().any(|x| x.contains(p)))
            .collect();
        for_reach(s, start, t, |dc, dr, k| {
            let (a0, a1, b0, b1) = grid.span(k);
            let unseen = sum(a0 - win.a0, a1 - win.a0, b0 - win.b0, b1 - win.b0);
            let fk = s.fov_region(k);
            let known = moved.iter().filter(|&&p| fk.contains(p)).count() as f64;
            out.set(t, dc, dr, known + unseen);
        });
    }

    fn order_independent(&self) -> bool {
        true
    }
}
