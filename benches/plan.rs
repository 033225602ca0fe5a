//! In-process planner benchmarks: `paper-v10`, 10 sensors spread over the
//! zone, the targets they see in a stationary snapshot of the target
//! process, T = 3 and T = 10, for every estimator × coordination.
//!
//! Before timing, each configuration's answer is checked: paths have T
//! steps of at most one cell, and iterated is never below priority. The
//! search group checks the dynamic programme against exhaustive search.
#![allow(missing_docs, clippy::unwrap_used)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use vigil::coordination::Coordination;
use vigil::geometry::{Point, Region};
use vigil::planner::{EstimatorKind, Id, PlanRequest, Planner, SensorIn, TargetIn};
use vigil::scenario::builtins;
use vigil::search::{ValueGrid, best_path, brute_force};
use vigil::world::World;

/// Ten sensors on a near-square grid and the targets inside their fields of
/// view in a stationary world.
fn reference_request(planner: &Planner, horizon: usize) -> PlanRequest {
    let s = &planner.scenario;
    let mut rng = StdRng::seed_from_u64(2024);
    let world = World::stationary(s, &mut rng);
    let sensors: Vec<SensorIn> = (0..10)
        .map(|i| SensorIn {
            id: Id::Number(i.into()),
            x: ((i % 4) as f64 + 0.5) * s.width / 4.0,
            y: ((i / 4) as f64 + 0.5) * s.height / 3.0,
            sensor_type: None,
        })
        .collect();
    let fovs: Vec<Region> = sensors
        .iter()
        .map(|p| s.fov_region(s.snap(Point::new(p.x, p.y))))
        .collect();
    let targets = world
        .in_zone(s)
        .filter(|t| fovs.iter().any(|r| r.contains(t.pos)))
        .map(|t| TargetIn {
            id: None,
            x: t.pos.x,
            y: t.pos.y,
            vx: t.vel.x,
            vy: t.vel.y,
        })
        .collect();
    PlanRequest {
        sensors,
        targets,
        horizon: Some(horizon.into()),
        ..PlanRequest::default()
    }
}

fn plan(c: &mut Criterion) {
    let planner = Planner::new(builtins().remove(0));
    let mut group = c.benchmark_group("plan");
    for horizon in [3, 10] {
        let base = reference_request(&planner, horizon);
        let mut priority_total = std::collections::HashMap::new();
        for estimator in [EstimatorKind::Exact, EstimatorKind::Paper] {
            for coordination in [
                Coordination::None,
                Coordination::Priority,
                Coordination::Iterated,
            ] {
                let mut req = base.clone();
                req.estimator = Some(estimator);
                req.coordination = Some(coordination);
                let resp = planner.plan_request(&req).unwrap();
                for p in &resp.plans {
                    assert_eq!(p.path.len(), horizon);
                    let mut prev = (p.start.col, p.start.row);
                    for c in &p.path {
                        assert!((c.col - prev.0).abs() <= 1 && (c.row - prev.1).abs() <= 1);
                        prev = (c.col, c.row);
                    }
                }
                match coordination {
                    Coordination::Priority => {
                        priority_total.insert(format!("{estimator:?}"), resp.expected_detections);
                    }
                    Coordination::Iterated | Coordination::Joint => {
                        let p = priority_total[&format!("{estimator:?}")];
                        assert!(resp.expected_detections >= p - 1e-9 * p.abs().max(1.0));
                    }
                    Coordination::None => {}
                }
                let name = format!(
                    "{}+{}/T={horizon}",
                    serde_json::to_string(&estimator).unwrap().trim_matches('"'),
                    serde_json::to_string(&coordination)
                        .unwrap()
                        .trim_matches('"'),
                );
                group.bench_function(name, |b| {
                    b.iter(|| planner.plan_request(black_box(&req)).unwrap())
                });
            }
        }
    }
    group.finish();
}

fn search(c: &mut Criterion) {
    let mut group = c.benchmark_group("search");
    let mut rng = StdRng::seed_from_u64(5);
    for horizon in [3, 4, 10] {
        let mut grid = ValueGrid::new(horizon);
        let h = horizon as i32;
        for t in 1..=horizon {
            for dr in -h..=h {
                for dc in -h..=h {
                    grid.set(t, dc, dr, rng.random::<f64>() * 3.0);
                }
            }
        }
        if horizon <= 4 {
            // The known optimum, by exhaustive search of all 9^T paths.
            let bf = brute_force(&grid);
            assert_eq!(best_path(&grid).value, bf.value);
            group.bench_function(format!("brute_force/T={horizon}"), |b| {
                b.iter(|| brute_force(black_box(&grid)))
            });
        }
        group.bench_function(format!("dp/T={horizon}"), |b| {
            b.iter(|| best_path(black_box(&grid)))
        });
    }
    group.finish();
}

criterion_group!(benches, plan, search);
criterion_main!(benches);
