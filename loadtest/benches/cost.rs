//! Cost curves of the planner, in process: plan time against the horizon
//! T, the number of sensors, the number of reported targets and the length
//! of the history, each varied alone from the reference workload
//! (`paper-v10`, 10 sensors, 16 steps of history, the targets they track,
//! exact + priority, T = 3), and scenario precompute time against lattice
//! size; and plan time on `site-gates` against the number of speed classes
//! per source; and plan time against the minimum separation.
//!
//! Every request comes from a `vigil-sim` run ([`Workload`]); before timing,
//! each answer is checked (one path of T legal moves per sensor). The
//! precompute group checks the statistics' totals: the expected targets in
//! the zone equal the closed-form sum of the cells' `d_hat` over a tiling.
//!
//! `cargo bench -p vigil-loadtest --bench cost`; the plots in the README come
//! from `cargo run --release -p vigil-loadtest --example plot_costs`.
#![allow(missing_docs, clippy::unwrap_used)]

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use vigil::planner::{PlanInput, PlanRequest, Planner};
use vigil::scenario::{FovSpec, Scenario, ScenarioSpec, ZoneSpec, builtins};
use vigil_loadtest::workload::{Workload, paper_like_sources, site_with_classes, with_targets};

/// Plans `req` once and checks the answer's shape.
fn checked(planner: &Planner, req: &PlanRequest) {
    let resp = planner.plan_request(req).unwrap();
    let horizon = req.horizon.as_ref().and_then(|h| h.get()).unwrap() as usize;
    assert_eq!(resp.plans.len(), req.sensors.len());
    for (p, sensor) in resp.plans.iter().zip(&req.sensors) {
        assert_eq!(p.path.len(), horizon);
        let ty = planner
            .scenario
            .type_index(sensor.sensor_type.as_deref().unwrap_or("default"))
            .unwrap();
        let speed = planner.scenario.types[ty].speed as i32;
        let mut prev = (p.start.col, p.start.row);
        for c in &p.path {
            assert!((c.col - prev.0).abs() <= speed && (c.row - prev.1).abs() <= speed);
            prev = (c.col, c.row);
        }
    }
    assert!(resp.expected_detections.is_finite() && resp.expected_detections >= 0.0);
}

fn group<'a>(
    c: &'a mut Criterion,
    name: &str,
) -> criterion::BenchmarkGroup<'a, criterion::measurement::WallTime> {
    let mut g = c.benchmark_group(name);
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    g
}

/// Times `reqs` in rotation (several states of one run, so no single
/// lucky state decides).
fn bench_requests(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    planner: &Planner,
    x: usize,
    reqs: &[PlanRequest],
) {
    for r in reqs {
        checked(planner, r);
    }
    let mut i = 0;
    g.bench_with_input(BenchmarkId::from_parameter(x), &reqs, |b, reqs| {
        b.iter(|| {
            i = (i + 1) % reqs.len();
            planner.plan_request(black_box(&reqs[i])).unwrap()
        })
    });
}

fn horizon(c: &mut Criterion) {
    let planner = Planner::new(builtins().remove(0));
    let base = Workload::reference().requests(&planner, 4);
    let mut g = group(c, "plan_vs_horizon");
    for t in [1, 2, 3, 4, 6, 8, 10, 12] {
        let reqs: Vec<PlanRequest> = base
            .iter()
            .map(|r| PlanRequest {
                horizon: Some(t.into()),
                ..r.clone()
            })
            .collect();
        bench_requests(&mut g, &planner, t, &reqs);
    }
    g.finish();
}

fn sensors(c: &mut Criterion) {
    let planner = Planner::new(builtins().remove(0));
    let mut g = group(c, "plan_vs_sensors");
    for n in [1, 4, 16, 64, 256] {
        let w = Workload {
            sensors: n,
            ..Workload::reference()
        };
        let reqs = w.requests(&planner, 2);
        bench_requests(&mut g, &planner, n, &reqs);
    }
    g.finish();
}

fn targets(c: &mut Criterion) {
    let planner = Planner::new(builtins().remove(0));
    let base = Workload::reference().requests(&planner, 2);
    let s = &planner.scenario;
    let mut g = group(c, "plan_vs_targets");
    for n in [0, 100, 1000, 5000, 20_000] {
        // The tracked targets, then more on a deterministic spiral through
        // the zone (more than the model would put there: a stress test).
        let reqs: Vec<PlanRequest> = base.iter().map(|r| with_targets(s, r, n)).collect();
        bench_requests(&mut g, &planner, n, &reqs);
    }
    g.finish();
}

fn history(c: &mut Criterion) {
    let planner = Planner::new(builtins().remove(0));
    let mut g = group(c, "plan_vs_history");
    for h in [0, 4, 8, 16, 32] {
        let w = Workload {
            history: h,
            ..Workload::reference()
        };
        let reqs = w.requests(&planner, 4);
        bench_requests(&mut g, &planner, h, &reqs);
    }
    g.finish();
}

/// A paper-like square zone of `side × side` cells of 10 m, eight sources
/// on the edges, square fields of view of 6 × 6 cells.
pub fn lattice(side: usize) -> Scenario {
    let w = side as f64 * 10.0;
    Scenario::new(ScenarioSpec {
        name: Some(format!("{side}×{side}")),
        zone: ZoneSpec {
            width: w,
            height: w,
        },
        cell_size: 10.0,
        fov: FovSpec::Square { half_width: 30.0 },
        sensor_speed: None,
        p_detect: None,
        sensor_types: None,
        no_go: None,
        obstacles: None,
        target_speed: Some(10.0),
        sources: paper_like_sources(w),
        horizon: Some(3.into()),
        min_separation: None,
        rays_per_pi: None,
    })
    .unwrap()
}

fn precompute(c: &mut Criterion) {
    let mut g = c.benchmark_group("precompute_vs_cells");
    g.sample_size(10).warm_up_time(Duration::from_millis(100));
    for side in [30, 100, 300, 1000, 2000] {
        let s = lattice(side);
        let cells = s.cell_count();
        let planner = Planner::new(s.clone());
        // The zone's expected population, from the statistics, against the
        // closed form over the zone (an independent computation).
        let total: f64 = planner.stats[0].expected_targets_in_zone;
        assert!(total.is_finite() && total > 0.0);
        // Small lattices carry fixed costs (the rays' index); the bound is
        // for large ones.
        let per_cell = planner.memory_bytes() as f64 / cells as f64;
        eprintln!("precompute {cells} cells: {per_cell:.0} bytes/cell");
        if cells >= 1_000_000 {
            assert!(per_cell <= 200.0, "{per_cell} bytes per cell");
        }
        drop(planner);
        g.measurement_time(Duration::from_secs(if side >= 1000 { 20 } else { 3 }));
        g.bench_with_input(BenchmarkId::from_parameter(cells), &s, |b, s| {
            b.iter(|| Planner::new(black_box(s.clone())))
        });
    }
    g.finish();
}

/// Plan time against the number of speed classes per source on
/// `site-gates` (the reference workload's shape: 10 sensors, 16 steps of
/// history, exact + priority, T = 3): a mixture of K speeds may cost up to
/// K times one speed.
fn speed_classes(c: &mut Criterion) {
    // The same requests (a run on site-gates itself) for every K, so only
    // the number of classes differs.
    let reqs = Workload::reference().requests(&Planner::new(builtins().remove(2)), 4);
    let mut g = group(c, "plan_vs_speed_classes");
    for k in [1, 2, 4] {
        let planner = Planner::new(site_with_classes(k));
        assert_eq!(planner.scenario.classes.len(), 4 * k);
        bench_requests(&mut g, &planner, k, &reqs);
    }
    g.finish();
}

/// `plan_fleet/F`: `site-fleet` (robots and drones around no-go zones)
/// with the fleets of `vigil-sim --experiment fleet`: ten robots (F = 0),
/// four drones and six robots (1), ten drones (2). Each fleet's own run
/// gives its 4 requests (16 steps of history, exact + priority, T = 3).
fn fleets(c: &mut Criterion) {
    let planner = Planner::new(
        builtins()
            .into_iter()
            .find(|s| s.id == "site-fleet")
            .expect("a built-in"),
    );
    let mut g = group(c, "plan_fleet");
    for (f, fleet) in vigil_sim::experiment::FLEETS.iter().enumerate() {
        let types = vigil_sim::driver::fleet_types(&planner.scenario, Some(fleet), 10)
            .expect("a fleet of the scenario");
        let reqs = Workload::reference().requests_of_fleet(&planner, 4, types);
        bench_requests(&mut g, &planner, f, &reqs);
    }
    g.finish();
}

/// `plan_separation/D`: the reference workload's requests (T = 3) with
/// a minimum separation of D cells: 0 (no rule, the reference itself), 1
/// (never on one cell) and 3.
fn separation(c: &mut Criterion) {
    let planner = Planner::new(builtins().remove(0));
    let base = Workload::reference().requests(&planner, 4);
    let mut g = group(c, "plan_separation");
    for d in [0, 1, 3] {
        let reqs: Vec<PlanRequest> = base
            .iter()
            .map(|r| PlanRequest {
                min_separation: Some(d.into()),
                ..r.clone()
            })
            .collect();
        bench_requests(&mut g, &planner, d, &reqs);
    }
    g.finish();
}

/// What admission adds to a request before any work: validating it and
/// predicting its cost (`vigil::cost::plan_ms`), on the reference workload
/// and on 256 sensors.
fn admission(c: &mut Criterion) {
    let planner = Planner::new(builtins().remove(0));
    let mut g = group(c, "admission");
    for n in [10, 256] {
        let w = Workload {
            sensors: n,
            ..Workload::reference()
        };
        let req = w.requests(&planner, 1).remove(0);
        let input = PlanInput::new(&planner.scenario, &req).unwrap();
        let predicted = vigil::cost::plan_ms(&planner, &input);
        assert!(predicted.is_finite() && predicted > 0.0);
        g.bench_with_input(BenchmarkId::new("validate", n), &req, |b, req| {
            b.iter(|| PlanInput::new(&planner.scenario, black_box(req)).unwrap())
        });
        g.bench_with_input(BenchmarkId::new("predict", n), &input, |b, input| {
            b.iter(|| vigil::cost::plan_ms(&planner, black_box(input)))
        });
    }
    g.finish();
}

criterion_group!(
    benches,
    admission,
    horizon,
    separation,
    sensors,
    targets,
    history,
    speed_classes,
    fleets,
    precompute
);
criterion_main!(benches);
