//! Learning source rates: the exposure against a Monte Carlo of the
//! detection process, the credible intervals' coverage over worlds whose
//! rates differ from the spec, the attribution of shared detections, and
//! the tracks that no source explains.

#![allow(clippy::unwrap_used)]

use std::sync::Arc;

use rand::{RngExt, SeedableRng, rngs::StdRng};
use rayon::prelude::*;
use serde_json::{Value, json};
use vigil::fit::{
    Attribution, DetectionIn, FitRequest, FitStep, FitTolerance, FitWindow, Prior, WindowLooks,
};
use vigil::planner::{Id, PlanResponse, Planner, SensorIn, TargetIn};
use vigil::scenario::{Scenario, ScenarioSpec};
use vigil::session::{Session, SessionSettings, StepRequest};
use vigil::world::World;

/// A 200 m yard of 10 m cells with four gates (cones, a speed mixture),
/// ground cameras (p 0.8) and drones (p 0.6, elevated); with `obstacles`,
/// a building in the middle and a hedge (screen).
fn yard(obstacles: bool) -> Value {
    let mut spec = json!({
        "zone": {"width": 200.0, "height": 200.0},
        "cell_size": 10.0,
        "fov": {"shape": "square", "half_width": 25.0},
        "p_detect": 0.8,
        "sensor_types": {
            "drone": {"fov": {"shape": "square", "half_width": 20.0}, "speed": 2,
                      "p_detect": 0.6, "elevated": true}
        },
        "sources": [
            {"x": -1.0, "y": 100.0, "rate": 0.3, "direction": 0.0, "spread": 90.0,
             "speeds": [{"speed": 6.0, "weight": 2.0}, {"speed": 14.0, "weight": 1.0}]},
            {"x": 100.0, "y": -1.0, "rate": 0.3, "direction": 90.0, "spread": 120.0,
             "speeds": [{"speed": 8.0, "weight": 1.0}]},
            {"x": 201.0, "y": 60.0, "rate": 0.3, "direction": 180.0, "spread": 60.0,
             "speeds": [{"speed": 10.0, "weight": 1.0}]},
            {"x": 60.0, "y": 201.0, "rate": 0.3, "direction": 270.0, "spread": 90.0,
             "speeds": [{"speed": 7.0, "weight": 1.0}]}
        ]
    });
    if obstacles {
        spec["obstacles"] = json!([
            {"polygon": [[80.0, 80.0], [125.0, 80.0], [125.0, 120.0], [80.0, 120.0]]},
            {"polygon": [[30.0, 30.0], [60.0, 40.0], [45.0, 60.0]], "kind": "screen"}
        ]);
    }
    spec
}

/// The spec with source `j`'s rate times `scales[j]`.
fn scaled(mut spec: Value, scales: &[f64]) -> Value {
    for (src, k) in spec["sources"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .zip(scales)
    {
        src["rate"] = json!(src["rate"].as_f64().unwrap() * k);
    }
    spec
}

fn scenario(spec: Value) -> Scenario {
    Scenario::new(serde_json::from_value::<ScenarioSpec>(spec).unwrap()).unwrap()
}

/// Three cameras and two drones.
const FLEET: [&str; 5] = ["default", "default", "default", "drone", "drone"];

/// The sensors of each step of a run whose plans come from a session of
/// `planner` (told the spec) while targets come from `world_s` (the true
/// rates): a planner-driven sequence of looks.
fn driven(
    planner: &Arc<Planner>,
    world_s: &Scenario,
    steps: usize,
    seed: u64,
) -> Vec<Vec<SensorIn>> {
    let s = &planner.scenario;
    let mut rng = StdRng::seed_from_u64(seed);
    let mut world = World::stationary(world_s, &mut rng);
    let mut session = Session::new(planner.clone(), SessionSettings::default());
    let mut sensors: Vec<SensorIn> = FLEET
        .iter()
        .enumerate()
        .map(|(i, ty)| SensorIn {
            id: Id::Number((i as u64).into()),
            x: 25.0 + 40.0 * i as f64,
            y: if i % 2 == 0 { 45.0 } else { 155.0 },
            sensor_type: Some(ty.to_string()),
        })
        .collect();
    let mut out = Vec::new();
    for _ in 0..steps {
        let step = step_request(&sensors, detect(world_s, &world, &sensors, &mut rng));
        let next = session.prepare(&step);
        let plan = planner.plan_request(&next.request).unwrap();
        session.commit(next);
        out.push(sensors.clone());
        follow(s, &mut sensors, &plan);
        world.step(world_s, &mut rng);
    }
    out
}

/// A session step: the sensors now and their detections, with ids.
fn step_request(sensors: &[SensorIn], detections: Vec<DetectionIn>) -> StepRequest {
    StepRequest {
        sensors: sensors.to_vec(),
        detections: detections
            .into_iter()
            .map(|d| TargetIn {
                id: Some(d.id),
                x: d.x,
                y: d.y,
                vx: d.vx,
                vy: d.vy,
            })
            .collect(),
        ..StepRequest::default()
    }
}

/// Moves each sensor to the first cell of its plan.
fn follow(s: &Scenario, sensors: &mut [SensorIn], plan: &PlanResponse) {
    for (sensor, p) in sensors.iter_mut().zip(&plan.plans) {
        let c = s.centre(vigil::scenario::Cell {
            col: p.path[0].col,
            row: p.path[0].row,
        });
        (sensor.x, sensor.y) = (c.x, c.y);
    }
}

/// What the looks of `sensors` detect in `world` now: each target in the
/// zone that a look sees, with that look's `p_detect`, independently.
fn detect(s: &Scenario, world: &World, sensors: &[SensorIn], rng: &mut StdRng) -> Vec<DetectionIn> {
    let mut looks: Vec<_> = sensors
        .iter()
        .map(|x| {
            let ty = s
                .type_index(x.sensor_type.as_deref().unwrap_or("default"))
                .unwrap();
            s.look(ty, s.snap(vigil::geometry::Point::new(x.x, x.y)))
        })
        .collect();
    looks.dedup();
    let mut found = Vec::new();
    for t in world.in_zone(s) {
        let mut seen = false;
        for l in &looks {
            if s.detects(l, t.pos) && rng.random::<f64>() < l.p_detect {
                seen = true;
            }
        }
        if seen {
            found.push(DetectionIn {
                id: Id::Number(t.id.into()),
                x: t.pos.x,
                y: t.pos.y,
                vx: t.vel.x,
                vy: t.vel.y,
            });
        }
    }
    found
}

/// The fit request of a world with the given looks, and how many distinct
/// targets of each source it detected.
fn observe(world_s: &Scenario, looks: &[Vec<SensorIn>], seed: u64) -> (FitRequest, Vec<f64>) {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut world = World::stationary(world_s, &mut rng);
    let mut counted = std::collections::HashSet::new();
    let mut per_source = vec![0.0; world_s.sources.len()];
    let mut steps = Vec::new();
    for sensors in looks {
        let detections = detect(world_s, &world, sensors, &mut rng);
        for d in &detections {
            let Id::Number(n) = &d.id else { unreachable!() };
            let id = n.as_u64().unwrap();
            if counted.insert(id) {
                let t = world.targets.iter().find(|t| t.id == id).unwrap();
                per_source[t.source] += 1.0;
            }
        }
        steps.push(FitStep {
            step: None,
            sensors: sensors.clone(),
            detections,
        });
        world.step(world_s, &mut rng);
    }
    (
        FitRequest {
            steps,
            ..FitRequest::default()
        },
        per_source,
    )
}

fn mean_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

#[test]
fn exposure_matches_a_monte_carlo_of_the_detections() {
    for obstacles in [false, true] {
        let spec = yard(obstacles);
        let s = scenario(spec.clone());
        let planner = Arc::new(Planner::new(s.clone()));
        let looks = driven(&planner, &s, 60, 7);
        let window = FitWindow::new(&s, &observe(&s, &looks, 1).0).unwrap();
        let exposure = WindowLooks::new(&s, &window.looks).exposure(0);
        // Many targets per world, so the mean count is precise.
        let scales = [5.0; 4];
        let world_s = scenario(scaled(spec, &scales));
        let counts: Vec<Vec<f64>> = (0..800u64)
            .into_par_iter()
            .map(|seed| observe(&world_s, &looks, 1000 + seed).1)
            .collect();
        for j in 0..4 {
            let per: Vec<f64> = counts.iter().map(|c| c[j]).collect();
            let (m, se) = mean_se(&per);
            let rate = world_s.sources[j].rate;
            let z = (m - rate * exposure[j]) / se;
            assert!(
                z.abs() < 4.0,
                "obstacles {obstacles}, source {j}: Monte Carlo {m:.3} ± {se:.3} detections against λE = {:.3} (z = {z:.2})",
                rate * exposure[j]
            );
            assert!(
                exposure[j] > 1.0,
                "source {j} is barely exposed: {}",
                exposure[j]
            );
        }
    }
}

#[test]
fn exposure_counted_step_by_step_adds_up() {
    let s = scenario(yard(true));
    let planner = Arc::new(Planner::new(s.clone()));
    let looks = driven(&planner, &s, 30, 3);
    let window = FitWindow::new(&s, &observe(&s, &looks, 1).0).unwrap();
    let whole = WindowLooks::new(&s, &window.looks).exposure(0);
    let mut summed = [0.0; 4];
    for t in 0..window.looks.len() {
        let e = WindowLooks::new(&s, &window.looks[..=t]).exposure(t);
        for j in 0..4 {
            summed[j] += e[j];
        }
    }
    for j in 0..4 {
        assert!(
            (summed[j] - whole[j]).abs() < 1e-9 * whole[j].max(1.0),
            "source {j}: {} step by step against {} at once",
            summed[j],
            whole[j]
        );
    }
}

/// Per source, the share of worlds whose 95% interval holds its true
/// rate, and the largest upper end of its interval.
fn coverage(obstacles: bool, scales: &[f64], prior: Prior, worlds: u64) -> Vec<(f64, f64)> {
    let spec = yard(obstacles);
    let s = scenario(spec.clone());
    let world_s = scenario(scaled(spec, scales));
    let planner = Arc::new(Planner::new(s.clone()));
    let looks = driven(&planner, &world_s, 150, 11);
    let exposure = WindowLooks::new(&s, &looks_of(&s, &looks)).exposure(0);
    let held: Vec<Vec<(bool, f64)>> = (0..worlds)
        .into_par_iter()
        .map(|seed| {
            let (req, _) = observe(&world_s, &looks, 5000 + seed);
            let window = FitWindow::new(&s, &req).unwrap();
            let mut a = Attribution::new(&s);
            a.add(&s, &window.firsts, &window.tolerances.traceback);
            assert!(a.unexplained.is_empty(), "exact data is always explained");
            a.rates(&s, &exposure, prior)
                .iter()
                .map(|r| {
                    let [lo, hi] = r.interval.unwrap();
                    ((lo..=hi).contains(&world_s.sources[r.index].rate), hi)
                })
                .collect()
        })
        .collect();
    (0..scales.len())
        .map(|j| {
            (
                held.iter().filter(|h| h[j].0).count() as f64 / worlds as f64,
                held.iter().map(|h| h[j].1).fold(0.0, f64::max),
            )
        })
        .collect()
}

fn looks_of(s: &Scenario, steps: &[Vec<SensorIn>]) -> Vec<Vec<vigil::scenario::Look>> {
    let req = FitRequest {
        steps: steps
            .iter()
            .map(|sensors| FitStep {
                step: None,
                sensors: sensors.clone(),
                detections: Vec::new(),
            })
            .collect(),
        ..FitRequest::default()
    };
    FitWindow::new(s, &req).unwrap().looks
}

#[test]
fn intervals_cover_the_true_rates() {
    // 3× higher, 3× lower, as given, and silent.
    let scales = [3.0, 1.0 / 3.0, 1.0, 0.0];
    let worlds = 300;
    for obstacles in [false, true] {
        let spec_rate = scenario(yard(obstacles)).sources[3].rate;
        let se = (0.95 * 0.05 / (3.0 * worlds as f64)).sqrt();
        for prior in [Prior::Flat, Prior::Scenario] {
            let found = coverage(obstacles, &scales, prior, worlds);
            // Pooled over the sources that emit: 3 × worlds intervals.
            let pooled = found[..3].iter().map(|c| c.0).sum::<f64>() / 3.0;
            assert!(
                (pooled - 0.95).abs() < 4.0 * se,
                "obstacles {obstacles}, {prior:?} prior: covers {pooled:.3} (per source {found:?}), not 0.95 ± {:.3}",
                4.0 * se
            );
            // An equal-tailed interval never holds a silent source's 0,
            // but its upper end learns that the source is quiet.
            assert_eq!(found[3].0, 0.0);
            assert!(
                found[3].1 < spec_rate,
                "obstacles {obstacles}, {prior:?} prior: the silent source's upper end reaches {}",
                found[3].1
            );
            eprintln!("obstacles {obstacles}: coverage, {prior:?} prior: {found:?}");
        }
    }
}

/// Two gates 6 m apart on the west fence with wide cones (so many tracks
/// pass near both), and a third on the south fence.
fn twin_gates() -> Value {
    json!({
        "zone": {"width": 200.0, "height": 200.0},
        "cell_size": 10.0,
        "fov": {"shape": "square", "half_width": 25.0},
        "p_detect": 0.9,
        "sensor_types": {
            "drone": {"fov": {"shape": "square", "half_width": 20.0}, "speed": 2}
        },
        "target_speed": 8.0,
        "sources": [
            {"x": -1.0, "y": 97.0, "rate": 0.3, "direction": 0.0, "spread": 120.0},
            {"x": -1.0, "y": 103.0, "rate": 0.3, "direction": 0.0, "spread": 120.0},
            {"x": 100.0, "y": -1.0, "rate": 0.3, "direction": 90.0, "spread": 90.0}
        ]
    })
}

/// `observe`, with a tracker whose tracks are shifted sideways by an
/// offset drawn once per target, uniform in `[-noise, noise]`.
fn observe_noisy(world_s: &Scenario, looks: &[Vec<SensorIn>], seed: u64, noise: f64) -> FitRequest {
    let (mut req, _) = observe(world_s, looks, seed);
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5eed);
    let mut offsets = std::collections::HashMap::new();
    for step in &mut req.steps {
        for d in &mut step.detections {
            let o = *offsets
                .entry(d.id.clone().to_string())
                .or_insert_with(|| (2.0 * rng.random::<f64>() - 1.0) * noise);
            let v = d.vx.hypot(d.vy);
            let (x, y) = (d.x - d.vy / v * o, d.y + d.vx / v * o);
            // A track is not shifted out of the zone (behind its gate).
            if world_s.in_zone(vigil::geometry::Point::new(x, y)) {
                (d.x, d.y) = (x, y);
            }
        }
    }
    req
}

#[test]
fn shared_detections_are_split_without_bias() {
    let spec = twin_gates();
    let s = scenario(spec.clone());
    let truth = [0.6, 0.15, 0.3];
    let world_s = scenario(scaled(spec, &[2.0, 0.5, 1.0]));
    let planner = Arc::new(Planner::new(s.clone()));
    let looks = driven(&planner, &world_s, 150, 5);
    let noise = 3.0;
    let tolerance = Some(FitTolerance {
        traceback: Some(noise),
        speed: None,
        look: Some(noise),
    });
    let exposure = WindowLooks::new(&s, &looks_of(&s, &looks)).exposure(0);
    let fits: Vec<(Vec<f64>, usize)> = (0..300u64)
        .into_par_iter()
        .map(|seed| {
            let mut req = observe_noisy(&world_s, &looks, 9000 + seed, noise);
            req.tolerance = tolerance;
            let window = FitWindow::new(&s, &req).unwrap();
            let mut a = Attribution::new(&s);
            a.add(&s, &window.firsts, &window.tolerances.traceback);
            assert!(a.unexplained.is_empty());
            let rates = a.rates(&s, &exposure, Prior::Flat);
            (rates.iter().map(|r| r.rate).collect(), a.shared.len())
        })
        .collect();
    let shared: usize = fits.iter().map(|f| f.1).sum();
    let detected: f64 = (0..300u64)
        .map(|seed| observe(&world_s, &looks, 9000 + seed).1.iter().sum::<f64>())
        .sum();
    assert!(
        shared as f64 > 0.05 * detected,
        "only {shared} of {detected} detections are shared: the test does not test sharing"
    );
    for (j, &t) in truth.iter().enumerate() {
        let (m, se) = mean_se(&fits.iter().map(|f| f.0[j]).collect::<Vec<_>>());
        // The flat prior's mean is (N + 1)/E: unbiased up to 1/E.
        let expected = t + 1.0 / exposure[j];
        assert!(
            ((m - expected) / se).abs() < 4.0,
            "source {j}: fitted {m:.4} ± {se:.4}, true {t} (+1/E = {expected:.4})"
        );
    }
}

#[test]
fn a_target_from_an_unlisted_gate_is_unexplained_near_it() {
    let spec = yard(true);
    let s = scenario(spec.clone());
    // The world has a fifth gate, on the north fence at x = 150.
    let mut world_spec = spec;
    world_spec["sources"].as_array_mut().unwrap().push(json!(
        {"x": 150.0, "y": 201.0, "rate": 0.5, "direction": 270.0, "spread": 20.0,
         "speeds": [{"speed": 9.0, "weight": 1.0}]}
    ));
    let world_s = scenario(world_spec);
    let planner = Arc::new(Planner::new(s.clone()));
    let looks = driven(&planner, &world_s, 120, 21);
    let (req, per_source) = observe(&world_s, &looks, 77);
    let fitted = vigil::fit::fit(&s, &FitWindow::new(&s, &req).unwrap());
    assert!(
        per_source[4] >= 5.0,
        "the hidden gate's targets were hardly seen"
    );
    assert_eq!(fitted.unexplained.len() as f64, per_source[4]);
    for u in &fitted.unexplained {
        assert!(
            (u.entry.y - 200.0).abs() < 1e-6 && (u.entry.x - 150.0).abs() < 1.0,
            "entry ({}, {}) is not at the hidden gate",
            u.entry.x,
            u.entry.y
        );
    }
    assert_eq!(fitted.sources.len(), 4);
}

#[test]
fn a_learning_session_counts_what_a_window_fit_counts() {
    let spec = yard(true);
    let s = scenario(spec.clone());
    let world_s = scenario(scaled(spec, &[3.0, 1.0 / 3.0, 1.0, 0.0]));
    let base = Arc::new(Planner::new(s.clone()));
    let settings = SessionSettings {
        learn_rates: Some(true),
        ..SessionSettings::default()
    };
    let mut session = Session::new(base.clone(), settings);
    let memory = session.learner().unwrap().memory();
    let steps = memory + 20;
    let mut rng = StdRng::seed_from_u64(3);
    let mut world = World::stationary(&world_s, &mut rng);
    let mut sensors: Vec<SensorIn> = FLEET
        .iter()
        .enumerate()
        .map(|(i, ty)| SensorIn {
            id: Id::Number((i as u64).into()),
            x: 25.0 + 40.0 * i as f64,
            y: 45.0,
            sensor_type: Some(ty.to_string()),
        })
        .collect();
    let mut window = Vec::new();
    let mut replanned = 0;
    for _ in 0..steps {
        let detections = detect(&world_s, &world, &sensors, &mut rng);
        window.push(FitStep {
            step: None,
            sensors: sensors.clone(),
            detections: detections.clone(),
        });
        let step = step_request(&sensors, detections);
        let learnt = session
            .learner()
            .unwrap()
            .fold(&step.sensors, &step.detections)
            .unwrap();
        let planner = session.planner_for(Some(&learnt));
        if !Arc::ptr_eq(&planner, session.learner().unwrap().planner()) {
            replanned += 1;
        }
        let prepared = session.prepare(&step);
        let plan = planner.plan_request(&prepared.request).unwrap();
        session.commit(prepared);
        session.commit_learnt(learnt);
        follow(&s, &mut sensors, &plan);
        world.step(&world_s, &mut rng);
    }
    // The plans moved to the learnt rates, away from the spec's.
    assert!(replanned > 0);
    let planned = session.learner().unwrap().planner().scenario.sources[0].rate;
    assert!(planned > 1.5 * s.sources[0].rate, "{planned}");
    // Step by step, over a life longer than a target's stay, the session
    // counts what a fit of its whole life counts.
    let learnt = session.learner().unwrap().rates();
    let req = FitRequest {
        steps: window,
        ..FitRequest::default()
    };
    let fitted = vigil::fit::fit(&s, &FitWindow::new(&s, &req).unwrap());
    for (a, b) in learnt.iter().zip(&fitted.sources) {
        assert!(
            (a.exposure - b.exposure).abs() < 1e-9 * b.exposure.max(1.0),
            "{a:?} {b:?}"
        );
        assert_eq!(a.detected, b.detected);
        assert!((a.rate - b.rate).abs() < 1e-9 * b.rate, "{a:?} {b:?}");
    }
    // A detection without an id cannot be counted once: refused.
    let anonymous = StepRequest {
        sensors: sensors.clone(),
        detections: vec![TargetIn {
            id: None,
            x: sensors[0].x,
            y: sensors[0].y,
            vx: 6.0,
            vy: 0.0,
        }],
        ..StepRequest::default()
    };
    let e = session
        .learner()
        .unwrap()
        .fold(&anonymous.sensors, &anonymous.detections)
        .unwrap_err();
    assert_eq!(e.field, "detections[0].id");
}
#[test]
fn exposure_on_the_scenarios_rays_matches_a_fine_grid() {
    for obstacles in [false, true] {
        let s = scenario(yard(obstacles));
        let planner = Arc::new(Planner::new(s.clone()));
        let looks = looks_of(&s, &driven(&planner, &s, 150, 11));
        let fine = WindowLooks::with_rays_per_pi(&s, &looks, 4096).exposure(0);
        let used = WindowLooks::new(&s, &looks).exposure(0);
        for (j, (a, b)) in used.iter().zip(&fine).enumerate() {
            let rel = a / b - 1.0;
            eprintln!(
                "obstacles {obstacles}, source {j}: {} rays per π against 4096: {rel:+.2e}",
                s.rays_per_pi()
            );
            assert!(
                rel.abs() < 5e-3,
                "obstacles {obstacles}, source {j}: {a} against {b}"
            );
        }
    }
}

/// Two sensors of one uncertain type on one cell take two looks, each
/// detecting independently (docs/model.md), as plans count them: two looks
/// of p 0.4 miss a target with probability 0.36, as one look of p 0.64 with
/// the same field of view does, so a window of such pairs has the exposure
/// of a window of the single sensors. (The pair was once counted as one
/// look, which understated its exposure and overstated the rates.)
#[test]
fn co_located_uncertain_sensors_add_exposure() {
    let mut spec = yard(false);
    let fov = spec["fov"].clone();
    spec["sensor_types"] = json!({
        "p40": {"fov": fov, "p_detect": 0.4},
        "p64": {"fov": fov, "p_detect": 0.64}
    });
    let s = scenario(spec);
    let at = |types: &[&str], x: f64| -> Vec<SensorIn> {
        types
            .iter()
            .enumerate()
            .map(|(i, ty)| SensorIn {
                id: Id::Number((i as u64).into()),
                x,
                y: 95.0,
                sensor_type: Some(ty.to_string()),
            })
            .collect()
    };
    let exposure = |types: &[&str]| {
        let steps: Vec<Vec<SensorIn>> = (0..6).map(|t| at(types, 25.0 + 20.0 * t as f64)).collect();
        WindowLooks::new(&s, &looks_of(&s, &steps)).exposure(0)
    };
    let (pair, one) = (exposure(&["p40", "p40"]), exposure(&["p64"]));
    for (j, (a, b)) in pair.iter().zip(&one).enumerate() {
        assert!(*b > 0.1, "source {j}: {b}");
        assert!((a - b).abs() < 1e-9 * b, "source {j}: pair {a}, one {b}");
    }
}

/// Few rays suffice where the exposure is smooth in the takeoff angle: a
/// narrow cone (10°, 7 rays) and a far source (the zone 6° wide from it, 5
/// rays) into a square zone have the exposure of a 4096-rays-per-π grid
/// to 0.5%. (A cone along a long, thin zone, whose rays' lengths vary as
/// 1/angle, does not: see docs/learning.md.)
#[test]
fn narrow_cones_and_far_sources_into_a_square_zone() {
    let spec = |source: Value| {
        json!({
            "zone": {"width": 200.0, "height": 200.0},
            "cell_size": 10.0,
            "fov": {"shape": "square", "half_width": 25.0},
            "target_speed": 5.0,
            "sensor_types": {
                "drone": {"fov": {"shape": "square", "half_width": 20.0}, "speed": 2,
                          "p_detect": 0.6, "elevated": true}
            },
            "sources": [source]
        })
    };
    for (name, source) in [
        (
            "narrow cone",
            json!({"x": -1.0, "y": 100.0, "rate": 0.2, "direction": 10.0, "spread": 10.0}),
        ),
        ("far source", json!({"x": -2000.0, "y": 150.0, "rate": 0.2})),
    ] {
        let s = scenario(spec(source));
        let planner = Arc::new(Planner::new(s.clone()));
        let looks = looks_of(&s, &driven(&planner, &s, 60, 5));
        let fine = WindowLooks::with_rays_per_pi(&s, &looks, 4096).exposure(0)[0];
        let used = WindowLooks::new(&s, &looks).exposure(0)[0];
        let rel = used / fine - 1.0;
        eprintln!(
            "{name}: {} rays per π against 4096: {rel:+.2e} ({used} against {fine})",
            s.rays_per_pi()
        );
        assert!(
            fine > 1.0 && rel.abs() < 5e-3,
            "{name}: {used} against {fine}"
        );
    }
}
