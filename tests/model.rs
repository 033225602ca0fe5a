//! Statistical checks of the model against an independent Monte Carlo of the
//! target process ([`vigil::world`]), and of coordination's guarantees.
//!
//! Tolerances come from the standard error of the Monte Carlo mean, so a
//! correct implementation fails with negligible probability (seeds are
//! fixed, so the runs are also reproducible).
#![allow(clippy::unwrap_used)]

use rand::{SeedableRng, rngs::StdRng};
use rayon::prelude::*;
use vigil::coordination::Coordination;
use vigil::estimator::{
    ElementaryGrid, Estimator, ExactEstimator, Precomputed, RAYS_PER_PI_SQUARE, Situation,
    SourceRays, Target,
};
use vigil::geometry::{Point, Region};
use vigil::planner::{EstimatorKind, Id, PlanRequest, Planner, SensorIn, TargetIn};
use vigil::scenario::{
    Cell, FovSpec, Heading, Look, Scenario, ScenarioSpec, SourceSpec, SpeedSpec, ZoneSpec,
    builtins, paper_spec,
};
use vigil::stats::Stats;
use vigil::world::World;

/// Mean and standard error of the mean.
fn mean_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

fn circle_scenario() -> Scenario {
    let mut spec = paper_spec(12.0);
    spec.name = Some("circle".into());
    spec.fov = FovSpec::Circle { radius: 35.0 };
    spec.sources[2].rate = 0.6;
    Scenario::new(spec).unwrap()
}

/// Stationary counts in several fields of view and in the zone, averaged over
/// independent stationary worlds, match `d_hat` and
/// `expected_targets_in_zone` within 1% plus three standard errors.
#[test]
fn d_hat_matches_monte_carlo() {
    for s in [builtins().remove(0), circle_scenario()] {
        let stats = Stats::compute(&s);
        let cells =
            [(0, 0), (3, 15), (15, 15), (29, 8), (10, 27)].map(|(col, row)| Cell { col, row });
        let regions: Vec<Region> = cells.iter().map(|&c| s.fov_region(c)).collect();
        let worlds = 40_000;
        let counts: Vec<Vec<f64>> = (0..worlds)
            .into_par_iter()
            .map(|i| {
                let mut rng = StdRng::seed_from_u64(1_000 + i as u64);
                let w = World::stationary(&s, &mut rng);
                let mut out: Vec<f64> = regions
                    .iter()
                    .map(|r| w.targets.iter().filter(|t| r.contains(t.pos)).count() as f64)
                    .collect();
                out.push(w.in_zone(&s).count() as f64);
                out
            })
            .collect();
        let mut expected: Vec<f64> = cells.iter().map(|&c| stats.d_hat[s.index(c)]).collect();
        expected.push(stats.expected_targets_in_zone);
        for (j, &e) in expected.iter().enumerate() {
            let col: Vec<f64> = counts.iter().map(|c| c[j]).collect();
            let (m, se) = mean_se(&col);
            eprintln!(
                "{}: quantity {j}: Monte Carlo {m:.4} ± {se:.4}, d_hat {e:.4}",
                s.id
            );
            assert!(
                (m - e).abs() <= 0.01 * e + 3.0 * se,
                "{}: quantity {j}: Monte Carlo {m:.4} ± {se:.4}, d_hat {e:.4}",
                s.id
            );
        }
    }
}

/// `lambda_hat` is the rate of targets whose straight path meets `F_c`:
/// checked by drawing takeoff angles and testing each path against the
/// region's corners (a separate test from the estimator's angular spans).
#[test]
fn lambda_hat_matches_monte_carlo() {
    let s = builtins().remove(0);
    assert_lambda_hat_matches_monte_carlo(&s, &[(0, 0), (15, 15), (29, 8), (4, 22)], 7);
}

/// `lambda_hat` at `cells` against takeoff angles drawn over each source's
/// cone as its spec gives it, each path tested against the field of view's
/// corners; and `escape_time·lambda_hat = d_hat`.
fn assert_lambda_hat_matches_monte_carlo(s: &Scenario, cells: &[(i32, i32)], seed: u64) {
    use rand::RngExt;
    let stats = Stats::compute(s);
    let mut rng = StdRng::seed_from_u64(seed);
    let draws = 200_000;
    for &(col, row) in cells {
        let c = Cell { col, row };
        let r = s.fov_region(c).rect;
        let corners = [(r.x0, r.y0), (r.x1, r.y0), (r.x1, r.y1), (r.x0, r.y1)];
        let mut rate = 0.0;
        let mut var = 0.0;
        for src in &s.spec.sources {
            let (centre, spread, _) = spec_cone_and_speeds(&s.spec, src);
            let mut hits = 0u32;
            for _ in 0..draws {
                let a = centre + (rng.random::<f64>() - 0.5) * spread;
                let u = (a.cos(), a.sin());
                // The path meets the rectangle iff its corners are not all on
                // one side of the line, and some corner lies ahead.
                let side = |&(x, y): &(f64, f64)| u.0 * (y - src.y) - u.1 * (x - src.x);
                let ahead = corners
                    .iter()
                    .any(|&(x, y)| u.0 * (x - src.x) + u.1 * (y - src.y) > 0.0);
                let pos = corners.iter().any(|c| side(c) >= 0.0);
                let neg = corners.iter().any(|c| side(c) <= 0.0);
                if ahead && pos && neg {
                    hits += 1;
                }
            }
            let p = hits as f64 / draws as f64;
            rate += src.rate * p;
            var += src.rate.powi(2) * p * (1.0 - p) / draws as f64;
        }
        let e = stats.lambda_hat[s.index(c)];
        assert!(
            (rate - e).abs() <= 0.01 * e + 3.0 * var.sqrt() + 1e-12,
            "{}: cell {c:?}: Monte Carlo {rate:.5}, lambda_hat {e:.5}",
            s.id
        );
        let esc = stats.escape_time[s.index(c)];
        assert!((esc * e - stats.d_hat[s.index(c)]).abs() < 1e-9);
    }
}

/// How the sensors and the reporting behave in one unbiasedness experiment.
#[derive(Clone, Copy, Debug)]
enum Reporting {
    /// Report what the sensors see now; no history.
    NowOnly,
    /// Report targets seen now or in the last `steps` steps (still in the
    /// zone), and pass the sensors' past positions as history.
    WithHistory { steps: usize, moving: bool },
    /// As `WithHistory`, but the history is withheld from the estimator:
    /// a negative control that must be caught as biased.
    HistoryWithheld { steps: usize, moving: bool },
}

struct Experiment {
    /// Mean and SE of (actual − n̂) per (cell, t).
    results: Vec<((Cell, usize), f64, f64)>,
}

fn run_unbiasedness(s: &Scenario, reporting: Reporting, worlds: usize) -> Experiment {
    run_unbiasedness_with(s, s, reporting, worlds)
}

/// The unbiasedness experiment with the targets drawn from `s` and the
/// estimator built for `model` (the same zone): a wrong model must show.
fn run_unbiasedness_with(
    s: &Scenario,
    model: &Scenario,
    reporting: Reporting,
    worlds: usize,
) -> Experiment {
    let stats = Stats::compute(model);
    let rays = SourceRays::for_scenario(model);
    let grid = ElementaryGrid::new(model);
    let sensors = [(9, 9), (12, 10), (21, 19)].map(|(col, row)| Cell { col, row });
    let (steps, moving, pass_history) = match reporting {
        Reporting::NowOnly => (0, false, false),
        Reporting::WithHistory { steps, moving } => (steps, moving, true),
        Reporting::HistoryWithheld { steps, moving } => (steps, moving, false),
    };
    // Sensor positions `s` steps ago: fixed, or drifting west one cell a step.
    let at = |s_ago: usize| -> Vec<Cell> {
        sensors
            .iter()
            .map(|c| Cell {
                col: if moving { c.col - s_ago as i32 } else { c.col },
                row: c.row,
            })
            .collect()
    };
    let probes: Vec<(Cell, usize)> = [
        ((9, 9), 1),
        ((9, 9), 3),
        ((10, 11), 2),
        ((12, 10), 1),
        ((14, 12), 3),
        ((21, 19), 2),
        ((23, 21), 5),
        ((5, 20), 2),
    ]
    .iter()
    .map(|&((col, row), t)| (Cell { col, row }, t))
    .collect();
    let tmax = probes.iter().map(|p| p.1).max().unwrap_or(1);
    let diffs: Vec<Vec<f64>> = (0..worlds)
        .into_par_iter()
        .map(|i| {
            let mut rng = StdRng::seed_from_u64(99_000 + i as u64);
            let mut w = World::stationary(s, &mut rng);
            let mut seen = std::collections::HashSet::new();
            for s_ago in (0..=steps).rev() {
                let fovs: Vec<Region> = at(s_ago).iter().map(|&c| s.fov_region(c)).collect();
                for t in w.in_zone(s) {
                    if fovs.iter().any(|r| r.contains(t.pos)) {
                        seen.insert(t.id);
                    }
                }
                if s_ago > 0 {
                    w.step(s, &mut rng);
                }
            }
            let reported: Vec<Target> = w
                .in_zone(s)
                .filter(|t| seen.contains(&t.id))
                .map(|t| Target {
                    pos: t.pos,
                    vel: t.vel,
                })
                .collect();
            let history_len = if pass_history { steps } else { 0 };
            let observed: Vec<Vec<Look>> = (0..=history_len)
                .map(|s_ago| {
                    at(s_ago)
                        .iter()
                        .map(|&c| Look::certain(s.fov_region(c)))
                        .collect()
                })
                .collect();
            let est = ExactEstimator::new(
                Precomputed {
                    scenario: model,
                    stats: std::slice::from_ref(&stats),
                    rays: &rays,
                    grid: grid.as_ref(),
                    sights: None,
                },
                Situation {
                    observed: &observed,
                    targets: &reported,
                    starts: &sensors,
                    types: &vec![0; sensors.len()],
                    horizon: tmax,
                },
            );
            let predicted: Vec<f64> = probes
                .iter()
                .map(|&(k, t)| est.value(0, k, t, &[]))
                .collect();
            let mut actual = vec![0.0; probes.len()];
            for t in 1..=tmax {
                w.step(s, &mut rng);
                for (j, &(k, pt)) in probes.iter().enumerate() {
                    if pt == t {
                        let r = s.fov_region(k);
                        actual[j] = w.in_zone(s).filter(|x| r.contains(x.pos)).count() as f64;
                    }
                }
            }
            actual.iter().zip(&predicted).map(|(a, p)| a - p).collect()
        })
        .collect();
    let results = probes
        .iter()
        .enumerate()
        .map(|(j, &p)| {
            let col: Vec<f64> = diffs.iter().map(|d| d[j]).collect();
            let (m, se) = mean_se(&col);
            (p, m, se)
        })
        .collect();
    Experiment { results }
}

fn assert_unbiased(e: &Experiment, label: &str) {
    for &((k, t), m, se) in &e.results {
        eprintln!(
            "{label}: cell ({},{}) t={t}: mean(actual − n̂) = {m:+.4} ± {se:.4}",
            k.col, k.row
        );
        // Four standard errors per probe: with 8 probes the chance that a
        // correct estimator fails is about 5e-4.
        assert!(
            m.abs() <= 4.0 * se,
            "{label}: cell {k:?} t={t}: mean(actual − n̂) = {m:.4} ± {se:.4}"
        );
        assert!(
            se < 0.03,
            "{label}: too few worlds to be informative (se {se:.4})"
        );
    }
}

#[test]
fn exact_estimator_is_unbiased_without_history() {
    let s = builtins().remove(0);
    assert_unbiased(
        &run_unbiasedness(&s, Reporting::NowOnly, 12_000),
        "no history",
    );
}

#[test]
fn exact_estimator_is_unbiased_with_history() {
    let s = builtins().remove(1);
    assert_unbiased(
        &run_unbiasedness(
            &s,
            Reporting::WithHistory {
                steps: 4,
                moving: false,
            },
            12_000,
        ),
        "fixed sensors, 4 steps of history",
    );
    let s = builtins().remove(0);
    assert_unbiased(
        &run_unbiasedness(
            &s,
            Reporting::WithHistory {
                steps: 3,
                moving: true,
            },
            12_000,
        ),
        "moving sensors, 3 steps of history",
    );
}

#[test]
fn exact_estimator_is_unbiased_with_circular_fov() {
    let s = circle_scenario();
    assert_unbiased(
        &run_unbiasedness(
            &s,
            Reporting::WithHistory {
                steps: 2,
                moving: true,
            },
            12_000,
        ),
        "circle, 2 steps of history",
    );
}

/// The check has power: reporting targets seen in the past without saying
/// where the sensors were counts them twice, and the test sees it.
#[test]
fn withheld_history_is_detected_as_biased() {
    let s = builtins().remove(0);
    let e = run_unbiasedness(
        &s,
        Reporting::HistoryWithheld {
            steps: 4,
            moving: true,
        },
        6_000,
    );
    for &((k, t), m, se) in &e.results {
        eprintln!(
            "withheld: cell ({},{}) t={t}: {m:+.4} ± {se:.4}",
            k.col, k.row
        );
    }
    let worst = e
        .results
        .iter()
        .map(|&(_, m, se)| -m / se)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        worst > 6.0,
        "double counting went unnoticed (largest z = {worst:.1})"
    );
}

fn snapshot_request(s: &Scenario, sensors: usize, seed: u64) -> PlanRequest {
    use rand::RngExt;
    let mut rng = StdRng::seed_from_u64(seed);
    let world = World::stationary(s, &mut rng);
    let sensors: Vec<SensorIn> = (0..sensors)
        .map(|i| SensorIn {
            id: Id::Number(i.into()),
            x: rng.random::<f64>() * s.width,
            y: rng.random::<f64>() * s.height,
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
        ..PlanRequest::default()
    }
}

/// Iterated coordination never ends below priority, for either estimator,
/// and priority is never below planning alone for the exact estimator.
#[test]
fn iterated_is_never_below_priority() {
    let planners = [
        Planner::new(builtins().remove(0)),
        Planner::new(circle_scenario()),
    ];
    for planner in &planners {
        for seed in 0..12u64 {
            for estimator in [EstimatorKind::Exact, EstimatorKind::Paper] {
                let mut req = snapshot_request(&planner.scenario, 4 + (seed as usize % 7), seed);
                req.estimator = Some(estimator);
                req.horizon = Some((1 + seed as usize % 4).into());
                let total = |c: Coordination| {
                    let mut r = req.clone();
                    r.coordination = Some(c);
                    planner.plan_request(&r).unwrap().expected_detections
                };
                let (none, priority, iterated) = (
                    total(Coordination::None),
                    total(Coordination::Priority),
                    total(Coordination::Iterated),
                );
                let tol = 1e-9 * priority.abs().max(1.0);
                assert!(
                    iterated >= priority - tol,
                    "{} seed {seed} {estimator:?}: iterated {iterated} < priority {priority}",
                    planner.scenario.id
                );
                if estimator == EstimatorKind::Exact {
                    assert!(
                        priority >= none - tol,
                        "seed {seed}: priority {priority} < none {none}"
                    );
                }
            }
        }
    }
}

/// For the exact estimator the total is the expected number of distinct
/// targets detected: it equals the sum of marginals in any order, and with
/// the whole zone observed and no sources it is the count of known targets
/// the paths cover.
#[test]
fn exact_total_counts_distinct_known_targets() {
    let mut spec = paper_spec(10.0);
    for src in &mut spec.sources {
        src.rate = 0.0;
    }
    let planner = Planner::new(Scenario::new(spec).unwrap());
    // Two sensors side by side and three targets flying east through both.
    let req = PlanRequest {
        sensors: vec![
            SensorIn {
                id: Id::Text("a".into()),
                x: 155.0,
                y: 155.0,
                sensor_type: None,
            },
            SensorIn {
                id: Id::Text("b".into()),
                x: 165.0,
                y: 155.0,
                sensor_type: None,
            },
        ],
        targets: [(150.0, 150.0), (160.0, 160.0), (140.0, 170.0)]
            .iter()
            .map(|&(x, y)| TargetIn {
                id: None,
                x,
                y,
                vx: 1.0,
                vy: 0.0,
            })
            .collect(),
        horizon: Some(2.into()),
        ..PlanRequest::default()
    };
    for c in [
        Coordination::None,
        Coordination::Priority,
        Coordination::Iterated,
    ] {
        let mut r = req.clone();
        r.coordination = Some(c);
        let resp = planner.plan_request(&r).unwrap();
        // Every target stays within reach of both sensors: 3 per step.
        assert_eq!(resp.expected_by_step, vec![3.0, 3.0], "{c:?}");
    }
    let resp = planner.plan_request(&req).unwrap();
    let plan_b = &resp.plans[1];
    // Under priority the second sensor sees nothing the first does not.
    assert_eq!(plan_b.expected_detections, 0.0);
}

/// The fast evaluation (elementary rectangles) and the general one (rays per
/// cell) compute the same integral: equal to rounding without exclusions,
/// and to the quadrature error of the excluded area with them.
#[test]
fn fast_and_general_exact_paths_agree() {
    use rand::RngExt;
    let mut spec = paper_spec(13.0);
    spec.fov = FovSpec::Square { half_width: 27.0 };
    let scenarios = [
        builtins().remove(0),
        Scenario::new(spec).unwrap(),
        Scenario::new(mixture_spec(FovSpec::Square { half_width: 30.0 })).unwrap(),
        builtins().remove(2),
    ];
    for s in &scenarios {
        let stats = Stats::compute(s);
        let grid = ElementaryGrid::new(s);
        // Without and with the index of crossings: grid walk and merge. The
        // general path's midpoint-rule error on excluded areas grows with
        // the targets' density along a ray (slow classes, narrow cones), so
        // the rays are denser by the same factor over the paper's.
        let paper_density = 0.3 / (std::f64::consts::PI * 10.0);
        let density = s
            .classes
            .iter()
            .map(|c| c.density(&s.sources[c.source]) / paper_density)
            .fold(1.0, f64::max);
        let plain = SourceRays::with_density(s, RAYS_PER_PI_SQUARE * density.ceil());
        let mut indexed = plain.clone();
        SourceRays::index_crossings(&mut indexed, s, grid.as_ref().unwrap());
        // The general path integrates by the plain midpoint rule: so must
        // the windows here, for the two to agree to rounding.
        indexed.iter_mut().for_each(SourceRays::plain_midpoint);
        let mut rng = StdRng::seed_from_u64(11);
        let mut worst = 0.0f64;
        for rays in [&plain, &indexed].into_iter().cycle().take(6) {
            let starts: Vec<Cell> = (0..4)
                .map(|_| Cell {
                    col: rng.random_range(0..s.cols),
                    row: rng.random_range(0..s.rows),
                })
                .collect();
            let history: Vec<Vec<Look>> = (0..4)
                .map(|h| {
                    starts
                        .iter()
                        .map(|c| {
                            Look::certain(s.fov_region(Cell {
                                col: (c.col + h).min(s.cols - 1),
                                row: c.row,
                            }))
                        })
                        .collect()
                })
                .collect();
            let world = World::stationary(s, &mut rng);
            let targets: Vec<Target> = world
                .in_zone(s)
                .map(|t| Target {
                    pos: t.pos,
                    vel: t.vel,
                })
                .collect();
            let horizon = 3;
            let est = ExactEstimator::new(
                Precomputed {
                    scenario: s,
                    stats: std::slice::from_ref(&stats),
                    rays,
                    grid: grid.as_ref(),
                    sights: None,
                },
                Situation {
                    observed: &history,
                    targets: &targets,
                    starts: &starts,
                    types: &[0; 4],
                    horizon,
                },
            );
            for (i, &start) in starts.iter().enumerate() {
                let other = starts[(i + 1) % starts.len()];
                let excluded = [
                    Look::certain(s.fov_region(Cell {
                        col: start.col + 1,
                        row: start.row,
                    })),
                    Look::certain(s.fov_region(other)),
                ];
                for t in 1..=horizon {
                    let mut g = vigil::search::ValueGrid::new(horizon);
                    est.fill(i, start, t, &excluded, &mut g);
                    for dr in -(t as i32)..=(t as i32) {
                        for dc in -(t as i32)..=(t as i32) {
                            let k = Cell {
                                col: start.col + dc,
                                row: start.row + dr,
                            };
                            if !s.on_lattice(k) {
                                assert_eq!(g.get(t, dc, dr), None);
                                continue;
                            }
                            let fast = est.value(i, k, t, &[]);
                            let general = est.value_by_rays(i, k, t, &[]);
                            assert!(
                                (fast - general).abs() < 1e-9,
                                "{k:?} t={t}: {fast} vs {general}"
                            );
                            let fast_x = g.get(t, dc, dr).unwrap();
                            assert!((fast_x - est.value(i, k, t, &excluded)).abs() < 1e-9);
                            // The general path integrates the excluded area by the
                            // midpoint rule on the square scenarios' grid of
                            // δ = π/128 (measured worst 4.1e-2 of a target, next to
                            // a source); the fast path subtracts it exactly.
                            let general_x = est.value_by_rays(i, k, t, &excluded);
                            worst =
                                worst.max((fast_x - general_x).abs() / general_x.abs().max(1.0));
                            assert!(
                                (fast_x - general_x).abs() < 5e-2 * general_x.abs().max(1.0),
                                "{k:?} t={t}: {fast_x} vs {general_x}"
                            );
                        }
                    }
                }
            }
        }
        assert!(worst > 0.0, "the exclusions were exercised");
    }
}

// Targets as they really come: speed mixtures and directed cones.

/// A 300×300 zone (10-unit cells, the paper's lattice) with four sources:
/// cones of 60°, 40°, 120° (around a heading) and 30°, and one to three
/// speed classes each.
fn mixture_spec(fov: FovSpec) -> ScenarioSpec {
    let class = |speed: f64, weight: f64| SpeedSpec { speed, weight };
    ScenarioSpec {
        name: Some("mixture".into()),
        zone: ZoneSpec {
            width: 300.0,
            height: 300.0,
        },
        cell_size: 10.0,
        fov,
        sensor_speed: None,
        p_detect: None,
        sensor_types: None,
        no_go: None,
        obstacles: None,
        target_speed: Some(8.0),
        sources: vec![
            SourceSpec {
                direction: Some(10.0),
                spread: Some(60.0),
                speeds: Some(vec![class(4.0, 1.0), class(12.0, 1.0)]),
                ..SourceSpec::at(-1.0, 150.0, 0.5)
            },
            SourceSpec {
                direction: Some(80.0),
                spread: Some(40.0),
                speeds: Some(vec![class(3.0, 2.0), class(9.0, 1.0), class(15.0, 1.0)]),
                ..SourceSpec::at(150.0, -1.0, 0.4)
            },
            SourceSpec {
                heading: Some(Heading::West),
                spread: Some(120.0),
                ..SourceSpec::at(301.0, 250.0, 0.3)
            },
            SourceSpec {
                direction: Some(-45.0),
                spread: Some(30.0),
                speeds: Some(vec![class(6.0, 1.0), class(10.0, 3.0)]),
                ..SourceSpec::at(-20.0, 320.0, 0.3)
            },
        ],
        horizon: Some(3.into()),
        min_separation: None,
        rays_per_pi: None,
    }
}

/// A source's cone (centre and width, radians) and its speed classes
/// `(speed, probability)`, read from the spec alone.
fn spec_cone_and_speeds(spec: &ScenarioSpec, src: &SourceSpec) -> (f64, f64, Vec<(f64, f64)>) {
    let centre = src.direction.unwrap_or_else(|| match src.heading {
        Some(Heading::East) => 0.0,
        Some(Heading::North) => 90.0,
        Some(Heading::West) => 180.0,
        Some(Heading::South) => 270.0,
        None => panic!("test specs give a heading or a direction"),
    });
    let spread = src.spread.unwrap_or(180.0);
    let speeds = match &src.speeds {
        Some(v) => {
            let total: f64 = v.iter().map(|c| c.weight).sum();
            v.iter().map(|c| (c.speed, c.weight / total)).collect()
        }
        None => vec![(spec.target_speed.unwrap(), 1.0)],
    };
    (centre.to_radians(), spread.to_radians(), speeds)
}

/// Positions of the targets of a stationary world, drawn from the spec by
/// code of its own: per source, emissions over a window long enough for the
/// slowest target to have crossed the zone, each with a uniform age, a
/// uniform angle over the cone and a speed drawn by weight.
fn stationary_positions(spec: &ScenarioSpec, rng: &mut StdRng) -> Vec<Point> {
    use rand::RngExt;
    use rand_distr::{Distribution, Poisson};
    let (w, h) = (spec.zone.width, spec.zone.height);
    let mut out = Vec::new();
    for src in &spec.sources {
        let (centre, spread, speeds) = spec_cone_and_speeds(spec, src);
        let reach = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
            .iter()
            .map(|&(x, y)| (x - src.x).hypot(y - src.y))
            .fold(0.0, f64::max);
        let slowest = speeds.iter().map(|c| c.0).fold(f64::INFINITY, f64::min);
        let window = reach / slowest;
        let count = Poisson::new(src.rate * window).unwrap().sample(rng) as usize;
        for _ in 0..count {
            let age = rng.random::<f64>() * window;
            let angle = centre + (rng.random::<f64>() - 0.5) * spread;
            let mut u = rng.random::<f64>();
            let mut speed = speeds[speeds.len() - 1].0;
            for &(v, p) in &speeds {
                if u < p {
                    speed = v;
                    break;
                }
                u -= p;
            }
            let r = speed * age;
            let p = Point::new(src.x + r * angle.cos(), src.y + r * angle.sin());
            if (0.0..=w).contains(&p.x) && (0.0..=h).contains(&p.y) {
                out.push(p);
            }
        }
    }
    out
}

/// `d_hat` and `expected_targets_in_zone` of scenarios with speed mixtures
/// and cones (square and circular fields of view) match the stationary
/// counts of a Monte Carlo drawn from the spec, within 1% plus three
/// standard errors.
#[test]
fn mixture_d_hat_matches_monte_carlo() {
    for fov in [
        FovSpec::Square { half_width: 30.0 },
        FovSpec::Circle { radius: 35.0 },
    ] {
        let spec = mixture_spec(fov);
        let s = Scenario::new(spec.clone()).unwrap();
        let stats = Stats::compute(&s);
        let cells = [
            (0, 0),
            (3, 15),
            (15, 15),
            (29, 8),
            (10, 27),
            (25, 25),
            (5, 4),
        ]
        .map(|(col, row)| Cell { col, row });
        let regions: Vec<Region> = cells.iter().map(|&c| s.fov_region(c)).collect();
        let worlds = 20_000;
        let counts: Vec<Vec<f64>> = (0..worlds)
            .into_par_iter()
            .map(|i| {
                let mut rng = StdRng::seed_from_u64(7_000_000 + i as u64);
                let targets = stationary_positions(&spec, &mut rng);
                let mut out: Vec<f64> = regions
                    .iter()
                    .map(|r| targets.iter().filter(|&&p| r.contains(p)).count() as f64)
                    .collect();
                out.push(targets.len() as f64);
                out
            })
            .collect();
        let mut expected: Vec<f64> = cells.iter().map(|&c| stats.d_hat[s.index(c)]).collect();
        expected.push(stats.expected_targets_in_zone);
        let mut failed = Vec::new();
        for (j, &e) in expected.iter().enumerate() {
            let col: Vec<f64> = counts.iter().map(|c| c[j]).collect();
            let (m, se) = mean_se(&col);
            let line = format!("{fov:?}: quantity {j}: Monte Carlo {m:.4} ± {se:.4}, model {e:.4}");
            eprintln!("{line}");
            if (m - e).abs() > 0.01 * e + 3.0 * se {
                failed.push(line);
            }
        }
        assert!(failed.is_empty(), "{failed:#?}");
        // Some cells lie outside every cone, some inside: both were tested.
        assert!(expected.iter().any(|&e| e > 1.0));
    }
}

/// `lambda_hat` with cones: takeoff angles drawn over each spec's cone.
#[test]
fn mixture_lambda_hat_matches_monte_carlo() {
    let s = Scenario::new(mixture_spec(FovSpec::Square { half_width: 30.0 })).unwrap();
    assert_lambda_hat_matches_monte_carlo(
        &s,
        &[(0, 0), (15, 15), (29, 8), (4, 22), (20, 3), (27, 27)],
        17,
    );
}

#[test]
fn exact_estimator_is_unbiased_with_speed_mixtures_and_cones() {
    let s = Scenario::new(mixture_spec(FovSpec::Square { half_width: 30.0 })).unwrap();
    assert_unbiased(
        &run_unbiasedness(&s, Reporting::NowOnly, 12_000),
        "mixture, no history",
    );
    assert_unbiased(
        &run_unbiasedness(
            &s,
            Reporting::WithHistory {
                steps: 4,
                moving: false,
            },
            12_000,
        ),
        "mixture, fixed sensors, 4 steps of history",
    );
    assert_unbiased(
        &run_unbiasedness(
            &s,
            Reporting::WithHistory {
                steps: 3,
                moving: true,
            },
            12_000,
        ),
        "mixture, moving sensors, 3 steps of history",
    );
    let c = Scenario::new(mixture_spec(FovSpec::Circle { radius: 35.0 })).unwrap();
    assert_unbiased(
        &run_unbiasedness(
            &c,
            Reporting::WithHistory {
                steps: 2,
                moving: true,
            },
            12_000,
        ),
        "mixture, circles, moving sensors, 2 steps of history",
    );
}

/// The check has power against a wrong speed distribution: the sources'
/// mixtures replaced by single speeds with the same stationary density
/// (the harmonic mean, so `d_hat` is unchanged) backtrack what was seen by
/// the wrong distances, and the test sees it.
#[test]
fn a_wrong_speed_distribution_is_detected_as_biased() {
    let truth = mixture_spec(FovSpec::Square { half_width: 30.0 });
    let mut wrong = truth.clone();
    for src in &mut wrong.sources {
        if let Some(speeds) = src.speeds.take() {
            let total: f64 = speeds.iter().map(|c| c.weight).sum();
            let inv: f64 = speeds.iter().map(|c| c.weight / total / c.speed).sum();
            src.speeds = Some(vec![SpeedSpec {
                speed: 1.0 / inv,
                weight: 1.0,
            }]);
        }
    }
    let (truth, wrong) = (Scenario::new(truth).unwrap(), Scenario::new(wrong).unwrap());
    // The same stationary counts: only the dynamics differ.
    let (a, b) = (Stats::compute(&truth), Stats::compute(&wrong));
    for (x, y) in a.d_hat.iter().zip(&b.d_hat) {
        assert!((x - y).abs() < 1e-9 * x.max(1.0));
    }
    let e = run_unbiasedness_with(
        &truth,
        &wrong,
        Reporting::WithHistory {
            steps: 4,
            moving: true,
        },
        6_000,
    );
    let worst = e
        .results
        .iter()
        .map(|&(_, m, se)| (m / se).abs())
        .fold(0.0, f64::max);
    for &((k, t), m, se) in &e.results {
        eprintln!(
            "wrong speeds: cell ({},{}) t={t}: {m:+.4} ± {se:.4}",
            k.col, k.row
        );
    }
    assert!(
        worst > 6.0,
        "the wrong speeds went unnoticed (largest |z| = {worst:.1})"
    );
}
