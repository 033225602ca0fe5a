//! Tests of the simulation client: the world model against the scenario's
//! statistics, common random numbers, legal moves, and an end-to-end run
//! over HTTP.

use vigil::scenario::{Cell, builtins};
use vigil::stats::Stats;
use vigil_sim::client::{Client, spawn_local_server};
use vigil_sim::driver::{Sim, Start, default_warmup};
use vigil_sim::experiment::{RunConfig, run_all, run_one};
use vigil_sim::metrics::Entries;
use vigil_sim::policy::{ALL_POLICIES, Policy, local_force_move};
use vigil_sim::report;

fn assert_legal(sim: &Sim) {
    for trace in &sim.trace {
        for w in trace.windows(2) {
            let (a, b) = (w[0], w[1]);
            assert!(
                (a.col - b.col).abs() <= 1 && (a.row - b.row).abs() <= 1,
                "{a:?} → {b:?}"
            );
            assert!(sim.scenario.on_lattice(b), "{b:?} off the lattice");
        }
    }
}

/// Emissions are Poisson with the scenario's total rate, and after the
/// warm-up the zone holds `expected_targets_in_zone` on average: each
/// within four standard errors. On `paper-v10`, and on `site-gates`, whose
/// targets come from cones at mixed speeds.
#[test]
fn world_matches_the_scenario_statistics() {
    for s in [builtins().remove(0), builtins().remove(2)] {
        let stats = Stats::compute(&s);
        let rate: f64 = s.sources.iter().map(|src| src.rate).sum();
        // Past the warm-up (the slowest target's crossing of the diagonal),
        // the zone is stationary.
        let (seeds, steps) = (400u64, default_warmup(&s) + 17);
        let mut emitted = Vec::new();
        let mut counts = Vec::new();
        for seed in 0..seeds {
            let mut sim = Sim::new(s.clone(), 1, Start::Grid, seed, 0);
            for _ in 0..steps {
                let stay = sim.sensors.clone();
                sim.advance(stay);
            }
            emitted.push(sim.world.emitted() as f64);
            counts.push(sim.world.in_zone(&s).count() as f64);
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let se = |v: &[f64]| {
            let m = mean(v);
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64 / v.len() as f64)
                .sqrt()
        };
        let expected_emitted = rate * steps as f64;
        assert!(
            (mean(&emitted) - expected_emitted).abs() <= 4.0 * se(&emitted),
            "{}: emitted {} ± {}, expected {expected_emitted}",
            s.id,
            mean(&emitted),
            se(&emitted)
        );
        assert!(
            (mean(&counts) - stats.expected_targets_in_zone).abs() <= 4.0 * se(&counts),
            "{}: in zone {} ± {}, expected {}",
            s.id,
            mean(&counts),
            se(&counts),
            stats.expected_targets_in_zone
        );
    }
}

/// Every policy sees the same targets for the same seed, however its
/// sensors move (their RNG is separate).
#[test]
fn policies_share_the_target_stream() {
    let s = builtins().remove(1);
    let run = |policy: Policy, start: Start| {
        let mut sim = Sim::new(s.clone(), 6, start, 42, 16);
        for _ in 0..80 {
            sim.observe();
            let next = sim.local_moves(policy);
            sim.advance(next);
        }
        sim.world
            .targets
            .iter()
            .map(|t| (t.id, t.pos.x.to_bits(), t.pos.y.to_bits()))
            .collect::<Vec<_>>()
    };
    let reference = run(Policy::Stationary, Start::Grid);
    assert!(!reference.is_empty());
    assert_eq!(reference, run(Policy::Random, Start::Random));
    assert_eq!(reference, run(Policy::LocalForce, Start::Grid));
    // A different seed gives a different stream.
    let mut other = Sim::new(s.clone(), 6, Start::Grid, 43, 16);
    for _ in 0..80 {
        let stay = other.sensors.clone();
        other.advance(stay);
    }
    let other: Vec<_> = other
        .world
        .targets
        .iter()
        .map(|t| (t.id, t.pos.x.to_bits(), t.pos.y.to_bits()))
        .collect();
    assert_ne!(reference, other);
}

#[test]
fn local_policies_move_legally() {
    let s = builtins().remove(0);
    for policy in [Policy::Stationary, Policy::Random, Policy::LocalForce] {
        for seed in 0..5 {
            let mut sim = Sim::new(s.clone(), 12, Start::Random, seed, 0);
            for _ in 0..120 {
                sim.observe();
                let next = sim.local_moves(policy);
                sim.advance(next);
            }
            assert_legal(&sim);
            if policy == Policy::Stationary {
                assert!(sim.trace.iter().all(|t| t.iter().all(|&c| c == t[0])));
            }
        }
    }
}

#[test]
fn local_force_attracts_and_repels() {
    let s = builtins().remove(0);
    let me = Cell { col: 10, row: 10 };
    let p = s.centre(me);
    // A target to the north-east inside the field of view pulls that way.
    let target = vigil::geometry::Point::new(p.x + 20.0, p.y + 20.0);
    assert_eq!(
        local_force_move(&s, 0, &[me], &[0], &[target]),
        Cell { col: 11, row: 11 }
    );
    // A sensor just west pushes east; nothing to do when alone.
    assert_eq!(
        local_force_move(&s, 0, &[me, Cell { col: 9, row: 10 }], &[0, 0], &[]),
        Cell { col: 11, row: 10 }
    );
    assert_eq!(local_force_move(&s, 0, &[me], &[0], &[]), me);
}

/// A short run of every policy over HTTP against an in-process server:
/// moves are legal (the driver checks each plan too), metrics are sane,
/// planner policies report calibration and round trips, and the table and
/// the JSON report carry `delay` and `missed`.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn end_to_end_over_http() {
    let base = spawn_local_server().await.expect("server");
    let client = Client::new(&base);
    let info = client.scenario("paper-v10").await.expect("built-in");
    let scenario = vigil::scenario::Scenario::new(info.spec).expect("valid");
    let configs: Vec<RunConfig> = ALL_POLICIES
        .iter()
        .map(|&policy| RunConfig {
            label: policy.name().into(),
            policy,
            scenario_id: info.id.clone(),
            scenario: scenario.clone(),
            sensors: 4,
            fleet: None,
            steps: 15,
            warmup: 20,
            horizon: Some(2),
            history: 4,
            start: Start::Grid,
            min_separation: None,
            session: false,
            blind: false,
            world_rates: None,
            stationary_start: false,
        })
        .collect();
    let rows = run_all(&client, &configs, 7, 2, 4).await.expect("runs");
    assert_eq!(rows.len(), ALL_POLICIES.len());
    for row in &rows {
        let m = &row.metrics;
        assert_eq!(row.seeds, 2);
        assert!(m.ad + m.zd > 0.0, "{}: an empty zone", row.policy);
        assert!((0.0..=1.0).contains(&m.af) && (0.0..=1.0).contains(&m.detected_once));
        // A run has a delay exactly when it detected an entering target,
        // so the mean over seeds has one exactly when `once` is positive.
        // Entry and first detection both fall within the 15 measured
        // steps.
        assert_eq!(m.delay.is_some(), m.detected_once > 0.0, "{}", row.policy);
        assert!(
            m.delay.is_none_or(|d| (0.0..=14.0).contains(&d)),
            "{}: delay {:?}",
            row.policy,
            m.delay
        );
        assert!(
            m.missed.is_none_or(|x| (0.0..=1.0).contains(&x)),
            "{}: missed {:?}",
            row.policy,
            m.missed
        );
        // Every detected target is seen by one, two, three, or four or more.
        assert!((m.d1s + m.d2s + m.d3s + m.d4s - m.ad).abs() < 1e-9);
        assert!(
            (1.0..=4.0).contains(&m.cells),
            "{}: cells {}",
            row.policy,
            m.cells
        );
        assert_eq!(row.min_separation, 0);
        let policy = ALL_POLICIES
            .iter()
            .find(|p| p.name() == row.policy)
            .expect("a known policy");
        let planner = policy.planner().is_some();
        assert_eq!(m.plan_ms_p50.is_some(), planner, "{}", row.policy);
        assert_eq!(m.calibration.is_some(), planner, "{}", row.policy);
        // No separation asked for, none to violate.
        assert_eq!(m.violating_plans, planner.then_some(0.0), "{}", row.policy);
    }
    // Some policy detects a target that entered within the 15 steps, so
    // the checks of `delay` above, and of the JSON below, bite.
    assert!(rows.iter().any(|r| r.metrics.delay.is_some()));

    // The table has `delay` and `missed` right after `once`.
    let table = report::table(&rows);
    let header: Vec<&str> = table
        .lines()
        .next()
        .expect("header")
        .split_whitespace()
        .collect();
    let once = header.iter().position(|&c| c == "once").expect("once");
    assert_eq!(header[once + 1..once + 3], ["delay", "missed"], "{table}");
    // The JSON report has both in every row's means and intervals: a
    // number, or null where no run defines it.
    let json: serde_json::Value =
        serde_json::from_str(&report::json(&rows).expect("JSON")).expect("parses");
    for (run, row) in json["runs"].as_array().expect("runs").iter().zip(&rows) {
        for (key, value) in [("delay", row.metrics.delay), ("missed", row.metrics.missed)] {
            assert_eq!(run["metrics"].get(key).map(|v| v.as_f64()), Some(value));
            let ci = run["ci95"].get(key).expect("an interval");
            assert_eq!(ci.is_null(), value.is_none(), "{}: {key}", row.policy);
        }
    }

    for cfg in &configs {
        let (_, sim) = run_one(&client, cfg, 3, true).await.expect("run");
        assert_legal(&sim.expect("kept"));
    }
}

/// The counts behind `once`, `delay` and `missed` over whole runs of the
/// local policies: they only grow, every missed target is one that left
/// and was never detected, each delay fits in the steps measured so far,
/// and the targets counted but not gone are those in the zone now that
/// were not when the window started (counted here from the detections).
#[test]
fn entries_hold_together_over_runs() {
    let s = builtins().remove(0);
    let warmup = default_warmup(&s);
    let (mut left, mut detected) = (0, 0);
    for policy in [Policy::Stationary, Policy::Random, Policy::LocalForce] {
        for seed in 0..4 {
            let mut sim = Sim::new(s.clone(), 6, Start::Grid, seed, 16);
            for _ in 0..warmup {
                let stay = sim.sensors.clone();
                sim.advance(stay);
            }
            sim.start_window();
            let before: std::collections::HashSet<u64> =
                sim.detections().iter().map(|d| d.0).collect();
            let mut last = Entries::default();
            for k in 1..=120 {
                sim.observe();
                let next = sim.local_moves(policy);
                sim.advance(next);
                let e = sim.entries();
                let at = format!("{policy:?} seed {seed} step {k}: {e:?}");
                for (now, was) in [
                    (e.entered, last.entered),
                    (e.detected, last.detected),
                    (e.delay_steps, last.delay_steps),
                    (e.left, last.left),
                    (e.left_undetected, last.left_undetected),
                ] {
                    assert!(now >= was, "{at} after {last:?}");
                }
                assert!(e.detected <= e.entered && e.left <= e.entered, "{at}");
                assert!(e.left_undetected <= e.left, "{at}");
                assert!(e.left_undetected <= e.entered - e.detected, "{at}");
                // Entered after step 0 of the window, detected by step k.
                assert!(e.delay_steps <= e.detected * (k - 1), "{at}");
                let new_in_zone = sim
                    .detections()
                    .iter()
                    .filter(|d| !before.contains(&d.0))
                    .count();
                assert_eq!(e.entered - e.left, new_in_zone, "{at}");
                assert_eq!(sim.detected_once(), e.detected_once(), "{at}");
                assert_eq!((sim.delay(), sim.missed()), (e.delay(), e.missed()));
                last = e;
            }
            left += last.left;
            detected += last.detected;
        }
    }
    // Enough happened for the checks to mean something.
    assert!(
        left > 100 && detected > 100,
        "{left} left, {detected} detected"
    );
}

// Fleets: sensor types, speeds, no-go zones and Bernoulli detections.

/// Within `speed` king moves of `from` through free cells? An independent
/// breadth-first search.
fn legal_step(s: &vigil::scenario::Scenario, from: Cell, to: Cell, ty: usize) -> bool {
    let speed = s.types[ty].speed;
    let mut seen = std::collections::HashSet::from([from]);
    let mut frontier = vec![from];
    for _ in 0..speed {
        let mut next = Vec::new();
        for c in &frontier {
            for dr in -1..=1 {
                for dc in -1..=1 {
                    let n = Cell {
                        col: c.col + dc,
                        row: c.row + dr,
                    };
                    if s.is_free(ty, n) && seen.insert(n) {
                        next.push(n);
                    }
                }
            }
        }
        frontier = next;
    }
    s.is_free(ty, to) && seen.contains(&to)
}

fn assert_fleet_legal(sim: &Sim) {
    for (trace, &ty) in sim.trace.iter().zip(&sim.types) {
        let speed = sim.scenario.types[ty].speed;
        assert!(
            sim.scenario.is_free(ty, trace[0]),
            "start {:?} blocked",
            trace[0]
        );
        for w in trace.windows(2) {
            assert!(
                legal_step(&sim.scenario, w[0], w[1], ty),
                "{:?} → {:?} at speed {speed}",
                w[0],
                w[1]
            );
        }
    }
}

/// On `site-fleet`, the local policies and the planner (over HTTP) move
/// drones and robots within their speeds and never onto no-go ground.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fleets_move_within_their_speeds_around_no_go_zones() {
    let s = builtins()
        .into_iter()
        .find(|s| s.id == "site-fleet")
        .expect("built-in");
    let types = vigil_sim::driver::fleet_types(&s, Some("drone:4,robot:6"), 10).expect("fleet");
    assert!(s.has_no_go());
    for policy in [Policy::Random, Policy::LocalForce] {
        for start in [Start::Grid, Start::Random] {
            let mut sim = Sim::with_types(s.clone(), types.clone(), start, 3, 4);
            for _ in 0..60 {
                sim.observe();
                let next = sim.local_moves(policy);
                sim.advance(next);
            }
            assert_fleet_legal(&sim);
        }
    }
    let base = spawn_local_server().await.expect("server");
    let client = Client::new(&base);
    let cfg = RunConfig {
        label: "fleet".into(),
        policy: Policy::Exact,
        scenario_id: s.id.clone(),
        scenario: s.clone(),
        sensors: 10,
        fleet: Some("drone:4,robot:6".into()),
        steps: 12,
        warmup: 10,
        horizon: Some(2),
        history: 4,
        start: Start::Grid,
        min_separation: None,
        session: false,
        blind: false,
        world_rates: None,
        stationary_start: false,
    };
    let (metrics, sim) = run_one(&client, &cfg, 5, true).await.expect("run");
    let sim = sim.expect("kept");
    assert_fleet_legal(&sim);
    // The drones moved more than one cell at some step.
    let far = sim.trace[..4]
        .iter()
        .flat_map(|t| t.windows(2))
        .any(|w| (w[0].col - w[1].col).abs().max((w[0].row - w[1].row).abs()) > 1);
    assert!(far, "no drone ever used its speed");
    assert!(metrics.ad > 0.0);
}

/// A sensor detects a target inside its field of view with its type's
/// `p_detect`: over many (target, sensor, step) pairs the fraction
/// detected is within four standard errors of `p` (counted independently
/// from the world and the sensors' fields of view).
#[test]
fn detections_are_bernoulli_with_p_detect() {
    let mut spec = vigil::scenario::paper_spec(10.0);
    spec.p_detect = Some(0.5);
    let s = vigil::scenario::Scenario::new(spec).expect("valid");
    let (mut pairs, mut detected) = (0usize, 0usize);
    for seed in 0..20 {
        let mut sim = Sim::new(s.clone(), 6, Start::Grid, seed, 0);
        for _ in 0..40 {
            let stay = sim.sensors.clone();
            sim.advance(stay);
            let regions: Vec<_> = sim.sensors.iter().map(|&c| s.fov_region(c)).collect();
            for (_, pos, n) in sim.detections() {
                pairs += regions.iter().filter(|r| r.contains(pos)).count();
                detected += n;
            }
        }
    }
    let p = detected as f64 / pairs as f64;
    let se = (0.25 / pairs as f64).sqrt();
    assert!(pairs > 5_000, "{pairs} pairs");
    assert!((p - 0.5).abs() <= 4.0 * se, "p = {p} ± {se}");
}

/// Certain sensors draw nothing: a fleet of a named type identical to
/// `default` (p 1) counts exactly what `default` sensors count, step by
/// step, and the target stream is untouched.
#[test]
fn certain_fleets_count_exactly_as_default_sensors() {
    let mut spec = vigil::scenario::paper_spec(10.0);
    spec.sensor_types = Some(std::collections::BTreeMap::from([(
        "twin".to_owned(),
        vigil::scenario::SensorTypeSpec {
            fov: spec.fov,
            speed: None,
            p_detect: None,
            elevated: None,
        },
    )]));
    let s = vigil::scenario::Scenario::new(spec).expect("valid");
    let twin = vigil_sim::driver::fleet_types(&s, Some("twin:4"), 4).expect("fleet");
    let mut a = Sim::new(s.clone(), 4, Start::Grid, 9, 0);
    let mut b = Sim::with_types(s.clone(), twin, Start::Grid, 9, 0);
    for _ in 0..80 {
        a.observe();
        b.observe();
        let (na, nb) = (
            a.local_moves(Policy::LocalForce),
            b.local_moves(Policy::LocalForce),
        );
        assert_eq!(na, nb);
        assert_eq!(a.advance(na), b.advance(nb));
    }
}

#[test]
fn fleet_strings_are_checked() {
    let s = builtins()
        .into_iter()
        .find(|s| s.id == "site-fleet")
        .expect("built-in");
    let types = |f: &str, n| vigil_sim::driver::fleet_types(&s, Some(f), n);
    assert_eq!(types("drone:1,robot:2", 3).expect("ok").len(), 3);
    assert!(types("tank:3", 3).unwrap_err().contains("tank"));
    assert!(types("drone:3", 4).unwrap_err().contains("4"));
    assert!(types("drone", 1).unwrap_err().contains("NAME:COUNT"));
    assert!(types("drone:x", 1).unwrap_err().contains("count"));
    assert_eq!(vigil_sim::driver::fleet_size("drone:4,robot:6"), Some(10));
    assert_eq!(vigil_sim::driver::fleet_size("drone:4,robot"), None);
}

/// A scenario the server precomputes as a job: registration answers at
/// once with a pending status, and the client waits until it is ready.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_client_waits_for_a_scenario_precomputed_as_a_job() {
    let base = vigil_sim::client::spawn_local_server_with(vigil::http::config::Settings {
        sync_precompute_ms: 0.0,
        ..Default::default()
    })
    .await
    .expect("server");
    let client = Client::new(&base);
    let mut spec = builtins().remove(0).spec;
    spec.cell_size = 2.0;
    let info = client.register(&spec).await.expect("accepted");
    assert!(!info.is_ready(), "a job, not a synchronous registration");
    let mut reports = 0;
    let ready = client
        .wait_ready(info, |_| reports += 1)
        .await
        .expect("ready");
    assert!(ready.is_ready());
    assert!(reports >= 1);
    // Plans are served now.
    let scenario = vigil::scenario::Scenario::new(ready.spec).expect("valid");
    let sim = Sim::new(scenario, 2, Start::Grid, 1, 0);
    let req = sim.plan_request(Policy::Paper, Some(2));
    client.plan(&ready.id, &req).await.expect("planned");
}

/// `site-campus` in closed loop, planned by the occlusion-aware model and
/// by the same model told no obstacles (`blind`): both runs keep every
/// robot off the buildings' cells (the blind plans' forbidden moves are
/// replaced), drones fly over them, and the world counts detections only
/// along clear sight lines: the blind planner forecasts more than its
/// plans detect.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn site_campus_runs_aware_and_blind() {
    let base = spawn_local_server().await.expect("server");
    let client = Client::new(&base);
    let info = client.scenario("site-campus").await.expect("built-in");
    let s = vigil::scenario::Scenario::new(info.spec.clone()).expect("valid");
    let blind_spec = vigil::scenario::ScenarioSpec {
        obstacles: None,
        ..info.spec.clone()
    };
    let blind = client.register(&blind_spec).await.expect("registered");
    let blind = client.wait_ready(blind, |_| {}).await.expect("ready");
    let robot = s.type_index("robot").expect("robot");
    let cfg = |id: &str, blind: bool| RunConfig {
        label: if blind { "blind" } else { "aware" }.into(),
        policy: Policy::Exact,
        scenario_id: id.to_owned(),
        scenario: s.clone(),
        sensors: 6,
        fleet: Some("drone:2,robot:4".into()),
        steps: 30,
        warmup: 20,
        horizon: Some(2),
        history: 4,
        start: Start::Grid,
        min_separation: None,
        session: false,
        blind,
        world_rates: None,
        stationary_start: false,
    };
    let mut calibration = Vec::new();
    for (id, blind) in [(info.id.as_str(), false), (blind.id.as_str(), true)] {
        let (metrics, sim) = run_one(&client, &cfg(id, blind), 3, true)
            .await
            .expect("run");
        let sim = sim.expect("kept");
        assert_fleet_legal(&sim);
        for (trace, &ty) in sim.trace.iter().zip(&sim.types) {
            for &c in trace {
                assert!(
                    !(ty == robot && s.obstacles.in_building(s.centre(c))),
                    "a robot on a building's cell {c:?}"
                );
            }
        }
        assert!(metrics.ad > 0.0);
        calibration.push(
            metrics
                .calibration
                .expect("planner runs report calibration"),
        );
    }
    // Realised over forecast detections: the blind model counts targets
    // behind walls, so it forecasts more than its plans detect.
    assert!(
        calibration[1] < calibration[0],
        "aware {:.3}, blind {:.3}",
        calibration[0],
        calibration[1]
    );
}
