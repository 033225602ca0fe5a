//! Offline per-cell statistics (the paper's step 1), computed once when a
//! scenario is registered.
//!
//! For a cell `c` with clipped field of view `F_c` and a source `j` at `s_j`
//! with rate `λ_j`, a target's takeoff angle `α` is uniform over the
//! source's cone of width `spread_j` (π for the paper's half-planes), so:
//! - `θ_cj`, the span of the cone's angles whose rays cross `F_c`, gives the
//!   entry rate `λ_cj = λ_j·θ_cj/spread_j` and `lambda_hat = Σ_j λ_cj`
//!   (step 1a); it does not depend on the targets' speeds;
//! - a target of speed `v` on a ray crossing `F_c` over the distance
//!   interval `[a(α), b(α)]` stays `(b−a)/v` steps, so over the target
//!   classes `c` (source × speed, rate `λ_c = λ_j·w_c`) the expected stay of
//!   an entering target is `escape_time = Σ_c λ_c/(spread_j v_c)·∫(b−a)dα /
//!   lambda_hat`: the classes' escape times weighted by their entry rates
//!   (step 1b);
//! - `d_hat = lambda_hat·escape_time = ∫_{F_c} ρ` with the stationary density
//!   `ρ(p) = Σ_c λ_c/(spread_j v_c |p − s_j|)` inside each cone (step 1c).
//!   For square fields of view the integral of `1/r` over a rectangle has a
//!   closed form (cut at the cone's edges when the cone does not hold the
//!   whole zone: [`wedge_inv_r_integral`]); circles use Gauss–Legendre
//!   quadrature between the angular breakpoints.
//!
//! With obstacles ([`crate::obstacle`]) each integral is over the part of
//! `F_c` the cell's sensor sees (all of it for a view that sees over them)
//! and before a building ends a target's flight: `lambda_hat` counts the
//! targets that reach that part, `d_hat` the stationary count inside it,
//! and `escape_time = d_hat/lambda_hat` the expected time an entering
//! target spends inside it (a target may enter it more than once).
//!
//! The per-class escape-time distribution (step 1d), which only the paper
//! estimator reads and only at a sensor's own cell, is evaluated on demand by
//! [`paper_statistical_part`] rather than stored for every cell.

use rayon::prelude::*;

use crate::cancel::{CancelToken, Cancelled, Progress};
use crate::codec::{CodecError, Reader, Writer, expect_len};
use crate::geometry::{Point, Region, gauss_legendre, inv_r_integral, wedge_inv_r_integral};
use crate::limits::{MAX_HORIZON, OBSTACLE_STATS_RAYS_PER_PI};
use crate::obstacle::Sight;
use crate::scenario::{FovSpec, Scenario, Source};

/// The statistics of every cell, row-major (`row·cols + col`).
#[derive(Debug, Clone)]
pub struct Stats {
    /// Expected rate of target entry into `F_c`, targets per step.
    pub lambda_hat: Vec<f64>,
    /// Expected number of steps an entering target stays in `F_c`.
    pub escape_time: Vec<f64>,
    /// Stationary expected number of targets inside `F_c`.
    pub d_hat: Vec<f64>,
    /// Stationary expected number of targets inside the zone.
    pub expected_targets_in_zone: f64,
}

/// Each cell's escape time, `d_hat / lambda_hat` (0 where no target
/// enters).
fn escape_times(lambda_hat: &[f64], d_hat: &[f64]) -> Vec<f64> {
    lambda_hat
        .iter()
        .zip(d_hat)
        .map(|(&l, &d)| if l > 0.0 { d / l } else { 0.0 })
        .collect()
}

/// Angular span `[lo, hi]` (takeoff angles of the source's cone) of the
/// rays from `source` that meet `region`, or `None` when it is degenerate.
pub fn angular_span(source: &Source, region: &Region, buf: &mut Vec<Point>) -> Option<(f64, f64)> {
    buf.clear();
    region.breakpoints(source.pos, buf);
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &p in buf.iter() {
        let a = source.angle_to(p);
        lo = lo.min(a);
        hi = hi.max(a);
    }
    // The source's frame sees the zone without wrap-around, so the span is
    // an interval; the cone cuts it.
    source.clip(lo, hi)
}

/// `∫ (b(α) − a(α)) dα` over the takeoff angles of `source`'s cone, where
/// `[a, b]` is the ray's interval in `region`; equals `∫∫ 1/|p − s| dp` over
/// the part of `region` inside the cone.
pub fn chord_integral(source: &Source, region: &Region, buf: &mut Vec<Point>) -> f64 {
    if region.rect.is_empty() {
        return 0.0;
    }
    if region.disk.is_none() {
        let r = &region.rect;
        let s = source.pos;
        if source.covers_zone {
            return inv_r_integral(r.x0 - s.x, r.x1 - s.x, r.y0 - s.y, r.y1 - s.y);
        }
        return wedge_inv_r_integral(s, r, source.frame, source.cone.0, source.cone.1);
    }
    buf.clear();
    region.breakpoints(source.pos, buf);
    let mut angles: Vec<f64> = buf.iter().map(|&p| source.angle_to(p)).collect();
    if !source.covers_zone {
        // The cone's edges are kinks too; outside it nothing is emitted.
        let (lo, hi) = angles
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &a| {
                (l.min(a), h.max(a))
            });
        for a in angles.iter_mut() {
            *a = a.clamp(source.cone.0.max(lo), source.cone.1.min(hi));
        }
        angles.extend(
            [source.cone.0, source.cone.1]
                .into_iter()
                .filter(|&a| a > lo && a < hi),
        );
    }
    angles.sort_by(f64::total_cmp);
    let (nodes, weights) = gauss_legendre(16);
    let mut total = 0.0;
    for w in angles.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b <= a {
            continue;
        }
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        for (&n, &wt) in nodes.iter().zip(weights) {
            let d = source.direction(mid + half * n);
            let inv = Point::new(1.0 / d.x, 1.0 / d.y);
            if let Some((r0, r1)) = region.ray(source.pos, d, inv) {
                total += wt * half * (r1 - r0);
            }
        }
    }
    total
}

/// Cells per block of the precomputation: the unit of its progress and of
/// its cancellation checks. A block takes at most ~60 ms on one core (256
/// cells × 64 sources of circular fields of view at ~3.7 µs a pair), so
/// cancelled work stops well within a second.
pub const BLOCK_CELLS: usize = 256;

/// `(lambda_hat, d_hat)` of cell `i` for field of view `fov`.
fn cell_rates(s: &Scenario, fov: FovSpec, i: usize, buf: &mut Vec<Point>) -> (f64, f64) {
    let region = s.fov_with(fov, s.centre(s.cell_at(i)));
    let mut lambda_hat = 0.0;
    let mut d_hat = 0.0;
    for (j, src) in s.sources.iter().enumerate() {
        if src.rate == 0.0 {
            continue;
        }
        if let Some((lo, hi)) = angular_span(src, &region, buf) {
            lambda_hat += src.rate * (hi - lo) / src.spread;
            let chord = chord_integral(src, &region, buf);
            for class in s.classes_of(j) {
                d_hat += class.rate * chord / (src.spread * class.speed);
            }
        }
    }
    (lambda_hat, d_hat)
}

/// With obstacles, `(∫ [the ray meets the seen part] dα, ∫ |seen part| dα)`
/// over `source`'s cone, where the seen part of a ray is its part inside
/// `region`, before a building ends its flight, and visible through
/// `sight` (when given). By the midpoint rule on
/// [`OBSTACLE_STATS_RAYS_PER_PI`] rays per π over the angles that meet the
/// region: the obstacles' edges make the integrands discontinuous in `α`,
/// where the closed forms of [`chord_integral`] no longer apply.
fn sighted_chords(
    s: &Scenario,
    source: &Source,
    region: &Region,
    sight: Option<&Sight>,
    buf: &mut Vec<Point>,
) -> (f64, f64) {
    let Some((lo, hi)) = angular_span(source, region, buf) else {
        return (0.0, 0.0);
    };
    let n = (((hi - lo) / std::f64::consts::PI) * OBSTACLE_STATS_RAYS_PER_PI as f64)
        .ceil()
        .max(1.0) as usize;
    let h = (hi - lo) / n as f64;
    let (mut hit, mut chord) = (0usize, 0.0);
    let mut visible = Vec::new();
    for m in 0..n {
        let d = source.direction(lo + (m as f64 + 0.5) * h);
        let inv = Point::new(1.0 / d.x, 1.0 / d.y);
        let Some((a, b)) = region.ray(source.pos, d, inv) else {
            continue;
        };
        let b = b.min(s.obstacles.stop(source.pos, d));
        if b <= a {
            continue;
        }
        let len = match sight {
            None => b - a,
            Some(sight) => {
                visible.clear();
                sight.visible(source.pos, d, a, b, &mut visible);
                visible.iter().map(|(p, q)| q - p).sum()
            }
        };
        if len > 0.0 {
            hit += 1;
            chord += len;
        }
    }
    (hit as f64 * h, chord * h)
}

/// `(lambda_hat, d_hat)` of cell `i` for field of view `fov` in a scenario
/// with obstacles: the targets that reach the part of `F_c` the cell sees
/// (all of it when `sees_over`) before a building stops them.
fn sighted_cell_rates(
    s: &Scenario,
    fov: FovSpec,
    sees_over: bool,
    i: usize,
    buf: &mut Vec<Point>,
) -> (f64, f64) {
    let centre = s.centre(s.cell_at(i));
    let region = s.fov_with(fov, centre);
    let sight = if sees_over {
        None
    } else {
        s.obstacles.sight(centre, &region)
    };
    let mut lambda_hat = 0.0;
    let mut d_hat = 0.0;
    for (j, src) in s.sources.iter().enumerate() {
        if src.rate == 0.0 {
            continue;
        }
        let (span, chord) = sighted_chords(s, src, &region, sight.as_ref(), buf);
        lambda_hat += src.rate * span / src.spread;
        for class in s.classes_of(j) {
            d_hat += class.rate * chord / (src.spread * class.speed);
        }
    }
    (lambda_hat, d_hat)
}

impl Stats {
    /// Writes these statistics ([`crate::codec`]).
    pub fn encode(&self, w: &mut Writer) {
        // The escape times follow from the other two, to the bit.
        w.f64s(&self.lambda_hat);
        w.f64s(&self.d_hat);
        w.f64(self.expected_targets_in_zone);
    }

    /// Reads statistics [`Stats::encode`] wrote, of `cells` cells.
    ///
    /// # Errors
    /// A [`CodecError`] for bytes that are not such statistics.
    pub fn decode(r: &mut Reader, cells: usize) -> Result<Self, CodecError> {
        let lambda_hat = r.f64s()?;
        let d_hat = r.f64s()?;
        expect_len("lambda_hat", lambda_hat.len(), cells)?;
        expect_len("d_hat", d_hat.len(), cells)?;
        Ok(Stats {
            escape_time: escape_times(&lambda_hat, &d_hat),
            lambda_hat,
            d_hat,
            expected_targets_in_zone: r.f64()?,
        })
    }

    /// Computes the statistics of every cell for the type `default`'s view
    /// (in parallel).
    pub fn compute(s: &Scenario) -> Stats {
        Self::for_slot(s, 0)
    }

    /// The statistics of every cell for the scenario's view `slot` (its
    /// `fovs[slot]` and `sees_over[slot]`), in parallel.
    pub fn for_slot(s: &Scenario, slot: usize) -> Stats {
        match Self::for_slot_cancellable(s, slot, &CancelToken::never(), &Progress::default()) {
            Ok(stats) => stats,
            Err(Cancelled) => unreachable!("work that is never cancelled finishes"),
        }
    }

    /// Blocks of [`BLOCK_CELLS`] cells in the computation of one field of
    /// view's statistics on `s`.
    pub fn blocks(s: &Scenario) -> usize {
        s.cell_count().div_ceil(BLOCK_CELLS)
    }

    /// [`Stats::for_slot`], computed in blocks of [`BLOCK_CELLS`] cells:
    /// each block checks `cancel` before it starts and advances `progress`
    /// by one when it ends ([`Stats::blocks`] in all). Every cell's values
    /// are computed as by [`Stats::for_slot`], so the result is the same bit
    /// for bit.
    ///
    /// # Errors
    /// [`Cancelled`] once `cancel` is cancelled.
    pub fn for_slot_cancellable(
        s: &Scenario,
        slot: usize,
        cancel: &CancelToken,
        progress: &Progress,
    ) -> Result<Stats, Cancelled> {
        let (fov, sees_over) = (s.fovs[slot], s.sees_over[slot]);
        let mut per_cell = vec![(0.0, 0.0); s.cell_count()];
        per_cell
            .par_chunks_mut(BLOCK_CELLS)
            .enumerate()
            .try_for_each_init(Vec::new, |buf, (block, out)| {
                cancel.check()?;
                let first = block * BLOCK_CELLS;
                for (k, slot) in out.iter_mut().enumerate() {
                    *slot = if s.has_obstacles() {
                        sighted_cell_rates(s, fov, sees_over, first + k, buf)
                    } else {
                        cell_rates(s, fov, first + k, buf)
                    };
                }
                progress.advance(1);
                Ok(())
            })?;
        let zone = s.zone_region();
        let mut buf = Vec::new();
        let expected_targets_in_zone = s
            .sources
            .iter()
            .enumerate()
            .flat_map(|(j, src)| {
                let chord = if s.has_obstacles() {
                    sighted_chords(s, src, &zone, None, &mut buf).1
                } else {
                    chord_integral(src, &zone, &mut buf)
                };
                s.classes_of(j)
                    .iter()
                    .map(move |class| class.rate * chord / (src.spread * class.speed))
            })
            .sum();
        let (lambda_hat, d_hat): (Vec<f64>, Vec<f64>) = per_cell.into_iter().unzip();
        let escape_time = escape_times(&lambda_hat, &d_hat);
        Ok(Stats {
            lambda_hat,
            escape_time,
            d_hat,
            expected_targets_in_zone,
        })
    }
}

/// Angular samples per (cell, source) for the escape-time distribution.
/// The cost model predicts with it.
pub const ESCAPE_SAMPLES: usize = 512;

/// The statistical part of the paper's equation (1) at a sensor's own cell
/// `Pi`, for every horizon: element `t` (1 ≤ t ≤ 12) is
/// `λ̂_Pi·t − Σ_c λ̂_Pi,c Σ_{u=1..t} P(te_Pi,c < t − u)`, the expected number
/// of targets that enter `F_Pi` during the next `t` steps and are still
/// inside at step `t`. Element 0 is 0.
///
/// The paper's sum over sources `j` is read as a sum over target classes
/// `c` (source × speed): `λ̂_Pi,c = λ_j·w_c·θ_Pi,j/spread_j` is the class's
/// entry rate (they add up to `λ̂_Pi`), and `te_Pi,c` its escape time, the
/// chord of `F_Pi` over the class's speed for a takeoff angle uniform over
/// the span `θ_Pi,j` (the paper's `f(te)/η`, per class), sampled at 512
/// evenly spaced angles of the span.
pub fn paper_statistical_part(s: &Scenario, region: &Region) -> [f64; MAX_HORIZON + 1] {
    let mut out = [0.0; MAX_HORIZON + 1];
    let mut buf = Vec::new();
    let mut chords = Vec::with_capacity(ESCAPE_SAMPLES);
    for (j, src) in s.sources.iter().enumerate() {
        let Some((lo, hi)) = angular_span(src, region, &mut buf) else {
            continue;
        };
        chords.clear();
        let step = (hi - lo) / ESCAPE_SAMPLES as f64;
        for m in 0..ESCAPE_SAMPLES {
            let d = src.direction(lo + (m as f64 + 0.5) * step);
            let inv = Point::new(1.0 / d.x, 1.0 / d.y);
            chords.push(region.ray(src.pos, d, inv).map_or(0.0, |(a, b)| b - a));
        }
        for class in s.classes_of(j) {
            let lambda_c = class.rate * (hi - lo) / src.spread;
            if lambda_c == 0.0 {
                continue;
            }
            // still[u] = P(te ≥ u) for u = 0..MAX_HORIZON.
            let mut still = [0.0f64; MAX_HORIZON + 1];
            for &chord in &chords {
                let te = chord / class.speed;
                for (u, slot) in still.iter_mut().enumerate() {
                    if te >= u as f64 {
                        *slot += 1.0;
                    }
                }
            }
            // Σ_{u=1..t} P(te ≥ t − u) = Σ_{τ=0..t−1} P(te ≥ τ); P(te ≥ 0) = 1.
            let mut acc = 0.0;
            for t in 1..=MAX_HORIZON {
                let p = if t == 1 {
                    1.0
                } else {
                    still[t - 1] / ESCAPE_SAMPLES as f64
                };
                acc += p;
                out[t] += lambda_c * acc;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{FovSpec, builtins, paper_spec};

    #[test]
    fn closed_form_and_quadrature_agree_on_squares() {
        let s = &builtins()[0];
        let mut buf = Vec::new();
        for cell in [(0, 0), (5, 17), (29, 3), (15, 15)] {
            let region = s.fov_region(crate::scenario::Cell {
                col: cell.0,
                row: cell.1,
            });
            for src in &s.sources {
                let closed = chord_integral(src, &region, &mut buf);
                // Same region as a "disk" large enough never to bind.
                let mut as_disk = region;
                as_disk.disk = Some(crate::geometry::Disk {
                    c: Point::new(150.0, 150.0),
                    r: 1e4,
                });
                let quad = chord_integral(src, &as_disk, &mut buf);
                assert!(
                    (closed - quad).abs() < 1e-6 * closed.max(1.0),
                    "{closed} vs {quad}"
                );
            }
        }
    }

    #[test]
    fn stationary_statistical_part_tends_to_d_hat() {
        // With T → ∞ the targets that entered and are still inside are the
        // stationary population of the cell.
        let mut spec = paper_spec(40.0);
        spec.fov = FovSpec::Square { half_width: 30.0 };
        let s = Scenario::new(spec).expect("valid");
        let stats = Stats::compute(&s);
        let c = crate::scenario::Cell { col: 15, row: 15 };
        let part = paper_statistical_part(&s, &s.fov_region(c));
        let d = stats.d_hat[s.index(c)];
        // te ≤ 60√2/40 ≈ 2.1 steps, so by t = 12 the sum has converged to
        // Σ_j λ_j·E[⌈te⌉], which bounds d_hat = Σ λ_j E[te] within λ_hat.
        let lam = stats.lambda_hat[s.index(c)];
        assert!(
            part[12] >= d - 1e-9 && part[12] <= d + lam,
            "{} vs {d}",
            part[12]
        );
        assert!((part[12] - part[11]).abs() < 1e-12);
    }
}
