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
    (covered / reach.area()).min(1.0)
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
