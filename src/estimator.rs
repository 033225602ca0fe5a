//! Estimators of `n̂(k,t)`: the expected number of targets a sensor at cell
//! `k` detects at step `t` (1 ≤ t ≤ T), given what the sensors report now.
//!
//! Both answer the same question through [`Estimator::value`], optionally
//! leaving out what lies inside `excluded` regions (the fields of view of
//! other sensors at the same step), which is what coordination needs.
//!
//! - [`PaperEstimator`]: equations (1) and (2) of Krishna, Hexmoor and Sogani.
//! - [`ExactEstimator`]: the conditional expectation under the model, by
//!   interval arithmetic along rays from each source.

use crate::geometry::{Point, Region, union_within};
use crate::scenario::{Cell, MAX_HORIZON, Scenario, Source};
use crate::stats::{Stats, angular_span, paper_statistical_part};

/// A target as reported: position now (step 0) and velocity per step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// Position at step 0.
    pub pos: Point,
    /// Displacement per step.
    pub vel: Point,
}

impl Target {
    /// Straight-line position at step `t`.
    #[inline]
    pub fn at(&self, t: usize) -> Point {
        Point::new(
            self.pos.x + self.vel.x * t as f64,
            self.pos.y + self.vel.y * t as f64,
        )
    }
}

/// A source of expected detections for the search.
pub trait Estimator: Sync {
    /// `n̂` for `sensor` (its index in the request) at cell `k` and step `t`,
    /// counting only targets outside every region of `excluded`.
    fn value(&self, sensor: usize, k: Cell, t: usize, excluded: &[Region]) -> f64;

    /// True when the total over several sensors does not depend on the order
    /// in which their exclusions are applied (so a sensor's marginal against
    /// all the others is its contribution to the total).
    fn order_independent(&self) -> bool;
}

// ---------------------------------------------------------------- paper ----

/// Equations (1) and (2) of the paper, read as follows for the sensor at
/// cell `Pi` (its current cell) estimating cell `Pk` at step `t`:
///
/// - `n_Pi − k` (deterministic part): the reported targets inside `F_Pi` now
///   whose straight-line position at step `t` is inside `F_Pk`. At `Pk = Pi`
///   this is eq. (1)'s "seen now, minus the k that will have left".
/// - statistical part at `Pi`: `λ̂_Pi·t − Σ_j λ̂_Pi,j Σ_{u=1..t} P(te_Pi,j < t−u)`
///   (see [`paper_statistical_part`]).
/// - eq. (2): `κ = |F_Pi ∩ F_Pk| / |F_Pk|` weighs that statistical part and
///   `(1−κ)` weighs `d̂_Pk`, the stationary count, for the part of `F_Pk`
///   the sensor cannot see; `κ = 1` at `Pi` gives eq. (1).
///
/// Coordination (step 6) multiplies by `1 − f`, `f` the fraction of `F_Pk`'s
/// area covered by the excluded fields of view.
pub struct PaperEstimator<'a> {
    scenario: &'a Scenario,
    stats: &'a Stats,
    sensors: Vec<PaperSensor>,
}

struct PaperSensor {
    cell: Cell,
    own: Region,
    statistical: [f64; MAX_HORIZON + 1],
    seen: Vec<Target>,
}

impl<'a> PaperEstimator<'a> {
    /// Prepares the estimator for sensors at `cells` reporting `targets`.
    pub fn new(
        scenario: &'a Scenario,
        stats: &'a Stats,
        cells: &[Cell],
        targets: &[Target],
    ) -> Self {
        let sensors = cells
            .iter()
            .map(|&cell| {
                let own = scenario.fov_region(cell);
                PaperSensor {
                    cell,
                    own,
                    statistical: paper_statistical_part(scenario, &own),
                    seen: targets
                        .iter()
                        .copied()
                        .filter(|tg| own.contains(tg.pos))
                        .collect(),
                }
            })
            .collect();
        Self {
            scenario,
            stats,
            sensors,
        }
    }
}

impl Estimator for PaperEstimator<'_> {
    fn value(&self, sensor: usize, k: Cell, t: usize, excluded: &[Region]) -> f64 {
        let me = &self.sensors[sensor];
        let fk = self.scenario.fov_region(k);
        let deterministic = me.seen.iter().filter(|tg| fk.contains(tg.at(t))).count() as f64;
        let area = fk.area();
        let kappa = if k == me.cell || area <= 0.0 {
            1.0
        } else {
            (fk.covered_area(std::slice::from_ref(&me.own)) / area).clamp(0.0, 1.0)
        };
        let d_hat = self.stats.d_hat[self.scenario.index(k)];
        let n = deterministic + kappa * me.statistical[t] + (1.0 - kappa) * d_hat;
        if excluded.is_empty() || area <= 0.0 {
            return n;
        }
        let f = (fk.covered_area(excluded) / area).clamp(0.0, 1.0);
        n * (1.0 - f)
    }

    fn order_independent(&self) -> bool {
        false
    }
}

// ---------------------------------------------------------------- exact ----

/// Rays per π radians of takeoff angle in the angular grid of each source.
pub const RAYS_PER_PI: f64 = 1024.0;

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

/// The exact conditional expectation of the count in `F_k` at step `t`:
/// the reported targets whose straight-line position is in `F_k`, plus
/// `U(k,t)`, the expected targets in `F_k` that no sensor can have seen.
///
/// With `O_s` the union of the fields of view `s` steps ago, a point `q` on
/// the ray of angle `α` from source `j` at distance `r` holds at step `t` a
/// target that was at distance `r − v(t+s)` at step `−s`. It is unseen when
/// none of those backtracked points lies in `O_s`. The stationary density in
/// polar coordinates around the source is `λ_j/(πv)·dr·dα`, so
/// `U(k,t) = d̂_k − Σ_j λ_j/(πv) ∫ |R_k(α) ∩ ⋃_s (O_s(α) + v(t+s))| dα`:
/// the closed-form stationary count less the seen part, measured on each
/// ray by interval arithmetic and integrated over `α` by the midpoint rule on
/// a fixed grid of 1024 rays per π. Excluded regions are removed the same way
/// (unshifted), and known targets inside them are not counted.
pub struct ExactEstimator<'a> {
    scenario: &'a Scenario,
    stats: &'a Stats,
    rays: &'a [SourceRays],
    known: Vec<Target>,
    /// Per source (aligned with `rays`), the observed regions.
    blobs: Vec<Vec<Blob>>,
}

impl<'a> ExactEstimator<'a> {
    /// Prepares the estimator. `observed[s]` are the regions seen `s` steps
    /// ago (index 0: now). Targets outside the zone are ignored: they have
    /// left it, or have not entered and cannot have been seen.
    pub fn new(
        scenario: &'a Scenario,
        stats: &'a Stats,
        rays: &'a [SourceRays],
        observed: &[Vec<Region>],
        targets: &[Target],
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
        Self {
            scenario,
            stats,
            rays,
            known: targets
                .iter()
                .copied()
                .filter(|tg| scenario.in_zone(tg.pos))
                .collect(),
            blobs,
        }
    }
}

impl Estimator for ExactEstimator<'_> {
    fn value(&self, _sensor: usize, k: Cell, t: usize, excluded: &[Region]) -> f64 {
        let fk = self.scenario.fov_region(k);
        let excluded: Vec<&Region> = excluded.iter().filter(|x| x.may_overlap(&fk)).collect();
        let known = self
            .known
            .iter()
            .filter(|tg| {
                let p = tg.at(t);
                fk.contains(p) && !excluded.iter().any(|x| x.contains(p))
            })
            .count() as f64;
        let mut buf = Vec::new();
        let mut intervals: Vec<(f64, f64)> = Vec::new();
        let mut seen = 0.0;
        for (sr, blobs) in self.rays.iter().zip(&self.blobs) {
            let Some((a, b)) = sr.range(&fk, &mut buf) else {
                continue;
            };
            let (rk0, rk1) = fk.radial_bounds(sr.source.pos);
            let lift = self.scenario.speed * t as f64;
            let cands: Vec<&Blob> = blobs
                .iter()
                .filter(|bl| {
                    bl.first < b
                        && bl.first + bl.intervals.len() > a
                        && bl.r_min + bl.shift + lift <= rk1
                        && bl.r_max + bl.shift + lift >= rk0
                })
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
                    if m >= bl.first
                        && let Some(&(p, q)) = bl.intervals.get(m - bl.first)
                        && p <= q
                    {
                        let l = bl.shift + lift;
                        intervals.push((p + l, q + l));
                    }
                }
                for x in &excluded {
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
        known + self.stats.d_hat[self.scenario.index(k)] - seen
    }

    fn order_independent(&self) -> bool {
        true
    }
}
