#![allow(missing_docs, clippy::unwrap_used)]
//! Error of the exact estimator's values against a fine angular grid.
use vigil::estimator::{
    ElementaryGrid, Estimator, ExactEstimator, Precomputed, Situation, SourceRays, Target,
};
use vigil::geometry::Point;
use vigil::planner::Planner;
use vigil::scenario::{Cell, Look, builtins};
use vigil::stats::Stats;
use vigil_loadtest::workload::Workload;

fn main() {
    let s = builtins().remove(0);
    let planner = Planner::new(s.clone());
    let stats = Stats::compute(&s);
    let grid = ElementaryGrid::new(&s);
    let reqs = Workload::reference().requests(&planner, 6);
    let fine = SourceRays::with_density(&s, 4096.0);
    for density in [96.0, 128.0, 192.0, 256.0, 384.0] {
        let rays = SourceRays::with_density(&s, density);
        let (mut max, mut sum, mut n, mut vsum) = (0.0f64, 0.0, 0usize, 0.0);
        for req in &reqs {
            let snap = |x: f64, y: f64| s.snap(Point::new(x, y));
            let starts: Vec<Cell> = req.sensors.iter().map(|p| snap(p.x, p.y)).collect();
            let mut observed = vec![
                starts
                    .iter()
                    .map(|&c| Look::certain(s.fov_region(c)))
                    .collect::<Vec<_>>(),
            ];
            for step in req.history.as_deref().unwrap_or(&[]) {
                observed.push(
                    step.iter()
                        .map(|p| Look::certain(s.fov_region(snap(p.x, p.y))))
                        .collect(),
                );
            }
            let targets: Vec<Target> = req
                .targets
                .iter()
                .map(|t| Target {
                    pos: Point::new(t.x, t.y),
                    vel: Point::new(t.vx, t.vy),
                })
                .collect();
            let types = vec![0; starts.len()];
            let now = Situation {
                observed: &observed,
                targets: &targets,
                starts: &starts,
                types: &types,
                horizon: 3,
            };
            let coarse = Precomputed {
                scenario: &s,
                stats: std::slice::from_ref(&stats),
                rays: &rays,
                grid: grid.as_ref(),
            };
            let a = ExactEstimator::new(coarse, now);
            let b = ExactEstimator::new(
                Precomputed {
                    rays: &fine,
                    ..coarse
                },
                now,
            );
            for (i, &c) in starts.iter().enumerate() {
                for t in 1..=3 {
                    let ti = t as i32;
                    for dr in -ti..=ti {
                        for dc in -ti..=ti {
                            let k = Cell {
                                col: c.col + dc,
                                row: c.row + dr,
                            };
                            if !s.on_lattice(k) {
                                continue;
                            }
                            let (va, vb) = (a.value(i, k, t, &[]), b.value(i, k, t, &[]));
                            max = max.max((va - vb).abs());
                            sum += (va - vb).abs();
                            vsum += vb;
                            n += 1;
                        }
                    }
                }
            }
        }
        println!(
            "rays/pi {density}: max err {max:.2e}, mean err {:.2e}, mean value {:.3}",
            sum / n as f64,
            vsum / n as f64
        );
    }
}
