//! What a plan request's sensors reach and see, read off the scenario and
//! the request: the counts the plan models' terms are built from.

use crate::coordination::MAX_REPAIR_SEARCHES_PER_SENSOR;
use crate::estimator::SourceRays;
use crate::planner::PlanInput;
use crate::scenario::{Cell, FovSpec, Scenario};
use crate::stats::angular_span;

/// The share of the cells from `lo` to `hi` (a block) whose square field
/// of view of half width `h` meets an obstacle's bounding box, from the
/// boxes grown by `h` (overlaps counted twice, at most 1). O(obstacles).
pub(super) fn obstructed_share(s: &Scenario, lo: Cell, hi: Cell, h: f64) -> f64 {
    obstacles_per_view(s, lo, hi, h).min(1.0)
}

/// The obstacles whose bounding box meets the square field of view of half
/// width `h` of a cell from `lo` to `hi` (a block), on average over the
/// block: the shadows a look there casts. O(obstacles).
pub(super) fn obstacles_per_view(s: &Scenario, lo: Cell, hi: Cell, h: f64) -> f64 {
    let cs = s.cell_size;
    let reach = crate::geometry::Rect {
        x0: f64::from(lo.col) * cs,
        y0: f64::from(lo.row) * cs,
        x1: f64::from(hi.col + 1) * cs,
        y1: f64::from(hi.row + 1) * cs,
    };
    let covered: f64 = s
        .obstacles
        .list()
        .iter()
        .map(|ob| {
            let b = ob.polygon.bbox();
            crate::geometry::Rect {
                x0: b.x0 - h,
                y0: b.y0 - h,
                x1: b.x1 + h,
                y1: b.y1 + h,
            }
            .intersect(&reach)
            .area()
        })
        .sum();
    covered / reach.area()
}

/// Rays per π of the exact estimator's angular grid on `s`.
fn density(s: &Scenario) -> f64 {
    SourceRays::density(s)
}

/// Per source with targets: its index, its rays and its classes.
pub(super) fn source_rays(s: &Scenario) -> Vec<(usize, f64, f64)> {
    let zone = s.zone_region();
    let mut buf = Vec::new();
    s.sources
        .iter()
        .enumerate()
        .filter(|(_, src)| src.rate > 0.0)
        .filter_map(|(j, src)| {
            let (lo, hi) = angular_span(src, &zone, &mut buf)?;
            let rays = SourceRays::count(lo, hi, density(s)) as f64;
            Some((j, rays, s.classes_of(j).len() as f64))
        })
        .collect()
}

/// A field of view's half width (a square) or radius (a circle).
pub(super) fn half(fov: FovSpec) -> f64 {
    match fov {
        FovSpec::Square { half_width } => half_width,
        FovSpec::Circle { radius } => radius,
    }
}

/// Rays (over classes) that meet one look, averaged over up to eight of
/// `input`'s sensors' fields of view now (their history lies close by);
/// `rays` from [`source_rays`].
pub(super) fn rays_per_look(s: &Scenario, input: &PlanInput, rays: &[(usize, f64, f64)]) -> f64 {
    let n = input.starts.len();
    let mut buf = Vec::new();
    let sample = n.clamp(1, 8);
    let mut per_look = 0.0;
    for k in 0..sample.min(n) {
        let i = k * n / sample;
        let region = s.fov_region_of(input.types[i], input.starts[i]);
        for &(j, _, cl) in rays {
            if let Some((lo, hi)) = angular_span(&s.sources[j], &region, &mut buf) {
                per_look += cl * ((hi - lo) * density(s) / std::f64::consts::PI + 2.0);
            }
        }
    }
    per_look / sample as f64
}

/// Each sensor's start, its field of view's half width in cells and its
/// speed in cells per step.
pub(super) fn sensor_reach(s: &Scenario, input: &PlanInput) -> Vec<(Cell, f64, f64)> {
    (input.starts.iter().zip(&input.types))
        .map(|(&c, &ty)| {
            let t = &s.types[ty];
            (c, half(t.fov) / s.cell_size, t.speed as f64)
        })
        .collect()
}

/// `near[i·(T+1) + t]`: the sensors whose looks can first meet sensor
/// `i`'s reach box at step `t` (starts within both halves and both
/// reaches).
pub(super) fn near_by_step(s: &Scenario, input: &PlanInput) -> Vec<u32> {
    let (n, big_t) = (input.starts.len(), input.horizon);
    let stride = big_t + 1;
    let mut near = vec![0u32; n * stride];
    let me = sensor_reach(s, input);
    for (i, &(a, ha, va)) in me.iter().enumerate() {
        for (q, &(b, hb, vb)) in me.iter().enumerate().skip(i + 1) {
            let d = (a.col - b.col).abs().max((a.row - b.row).abs()) as f64;
            // The first step t ≥ 1 with d ≤ ha + hb + (va + vb)·t; a cast
            // truncates (`ceil` is a libm call without SSE4.1).
            let steps = (d - ha - hb) / (va + vb);
            let first = if steps <= 1.0 {
                1
            } else {
                steps as usize + usize::from((steps as usize as f64) < steps)
            };
            if first <= big_t {
                near[i * stride + first] += 1;
                near[q * stride + first] += 1;
            }
        }
    }
    near
}

/// Passes of searches (a pass: one per sensor) that a plan's separation
/// repair may run ([`crate::coordination::MAX_REPAIR_SEARCHES_PER_SENSOR`]
/// and the trial under way when they run out): none without a separation
/// or when no two sensors can come within it of each other in the
/// horizon, as then no pair is ever too close.
pub(super) fn repair_passes(s: &Scenario, input: &PlanInput) -> f64 {
    let d = input.min_separation as i64;
    if d == 0 {
        return 0.0;
    }
    let big_t = input.horizon as i64;
    let starts = &input.starts;
    let speeds = |i: usize| s.types[input.types[i]].speed;
    let crowded = (0..starts.len()).any(|i| {
        (i + 1..starts.len()).any(|q| {
            let (a, b) = (starts[i], starts[q]);
            let apart = i64::from((a.col - b.col).abs().max((a.row - b.row).abs()));
            apart - (speeds(i) + speeds(q)) as i64 * big_t < d
        })
    });
    if crowded {
        (MAX_REPAIR_SEARCHES_PER_SENSOR + 1) as f64
    } else {
        0.0
    }
}

/// Best-response rounds an `iterated` plan is expected to run, from the
/// mean count of sensors whose looks can meet a sensor's reach (`near`,
/// of [`near_by_step`]).
pub(super) fn iterated_rounds(near: &[u32], n: usize, exact: bool) -> f64 {
    let mean_near = near.iter().map(|&c| c as f64).sum::<f64>() / n as f64;
    if exact {
        1.0 + (mean_near / 10.0).min(4.0)
    } else {
        1.0 + (mean_near / 4.0).min(7.0)
    }
}

/// `ov[i·(T+1) + t]`: how many other sensors' looks at step `t` are
/// expected to meet the field of view of sensor `i`'s look at that step,
/// each look placed uniformly over its sensor's reach (clipped to the
/// lattice) and "meet" read off the bounding boxes, axis by axis as for
/// independent coordinates. A fleet spread over the zone gets about its
/// density times the overlap area; a crowded one gets every neighbour.
/// O(n²) pairs, each of the pairs that can meet by step `T` once per step.
pub(super) fn overlaps_by_step(s: &Scenario, input: &PlanInput) -> Vec<f64> {
    let (n, big_t) = (input.starts.len(), input.horizon);
    let stride = big_t + 1;
    let cs = s.cell_size;
    let me = sensor_reach(s, input);
    // A look's centre at step t: uniform over the reach's extent, axis by
    // axis, in the zone's units (at least a cell wide).
    let extent: Vec<_> = (0..n * stride)
        .map(|k| {
            let (start, _, v) = me[k / stride];
            let (lo, hi) = s.reach_corners(start, (v * (k % stride) as f64) as i32);
            let x = (f64::from(lo.col) * cs, f64::from(hi.col + 1) * cs);
            let y = (f64::from(lo.row) * cs, f64::from(hi.row + 1) * cs);
            (x, y)
        })
        .collect();
    let mut ov = vec![0.0; n * stride];
    for i in 0..n {
        let (ci, hi) = (me[i].0, me[i].1 * cs);
        for j in i + 1..n {
            let (cj, hj) = (me[j].0, me[j].1 * cs);
            let w = hi + hj;
            // Too far apart to meet even at the horizon: every step's
            // reach lies within the horizon's.
            let reach = (me[i].2 + me[j].2) * big_t as f64 + 1.0;
            let apart = (ci.col - cj.col).abs().max((ci.row - cj.row).abs()) as f64;
            if (apart - reach) * cs >= w {
                continue;
            }
            for t in 1..=big_t {
                let ((xi, yi), (xj, yj)) = (extent[i * stride + t], extent[j * stride + t]);
                let p = within(xi, xj, w) * within(yi, yj, w);
                ov[i * stride + t] += p;
                ov[j * stride + t] += p;
            }
        }
    }
    ov
}

/// `P(|X − Y| < w)` for `X` and `Y` independent and uniform on the
/// intervals `a` and `b` (each of positive length).
fn within(a: (f64, f64), b: (f64, f64), w: f64) -> f64 {
    // X − Y is uniform on a plus uniform on −b: its CDF is a sum of ramps.
    let (p1, q1, p2, q2) = (a.0, a.1, -b.1, -b.0);
    let ramp = |x: f64| 0.5 * x.max(0.0).powi(2);
    let cdf = |z: f64| {
        (ramp(z - p1 - p2) - ramp(z - q1 - p2) - ramp(z - p1 - q2) + ramp(z - q1 - q2))
            / ((q1 - p1) * (q2 - p2))
    };
    (cdf(w) - cdf(-w)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::within;

    /// Against areas worked by hand: two unit intervals within 1/2 of each
    /// other 1 − (1/2)² = 3/4; `[0, 2]` against `[0, 1]` within 1/2,
    /// 0.875 / 2; intervals too far apart 0, and a width past both 1.
    #[test]
    fn within_is_the_chance_that_two_uniforms_are_close() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(within((0.0, 1.0), (0.0, 1.0), 0.5), 0.75));
        assert!(close(within((0.0, 2.0), (0.0, 1.0), 0.5), 0.4375));
        assert!(close(within((0.0, 1.0), (0.0, 2.0), 0.5), 0.4375));
        assert!(close(
            within((1e5, 1e5 + 10.0), (1e5 + 5.0, 1e5 + 15.0), 5.0),
            0.5
        ));
        assert_eq!(within((0.0, 1.0), (5.0, 6.0), 1.0), 0.0);
        assert!(close(within((0.0, 2.0), (0.0, 1.0), 10.0), 1.0));
    }
}
