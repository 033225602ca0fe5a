//! A session's plan at every step equals the stateless plan of the same
//! state, over long runs with moving sensors: on `site-fleet` (sensor types
//! with p_detect < 1 and speeds up to 3), `site-gates` (speed mixtures from
//! cones) and `paper-v10`; and `vigil-sim` gives the same metrics through
//! sessions as through stateless requests (common random numbers).

use std::sync::Arc;

use vigil::planner::{PlanResponse, Planner};
use vigil::scenario::builtins;
use vigil::session::Session;
use vigil_sim::client::{Client, spawn_local_server};
use vigil_sim::driver::{Sim, Start, fleet_types};
use vigil_sim::experiment::{RunConfig, run_one};
use vigil_sim::policy::Policy;

fn assert_same_plan(step: usize, stateless: &PlanResponse, session: &PlanResponse) {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(1.0);
    assert!(
        close(stateless.expected_detections, session.expected_detections),
        "step {step}: {} vs {}",
        stateless.expected_detections,
        session.expected_detections
    );
    for (a, b) in stateless
        .expected_by_step
        .iter()
        .zip(&session.expected_by_step)
    {
        assert!(close(*a, *b), "step {step}: by step {a} vs {b}");
    }
    for (a, b) in stateless.plans.iter().zip(&session.plans) {
        assert_eq!(a.sensor, b.sensor);
        assert_eq!(a.path, b.path, "step {step}: sensor {:?}", a.sensor);
        assert!(close(a.expected_detections, b.expected_detections));
    }
}

/// Runs `steps` steps of `policy` on builtin `index` with `sensors` sensors
/// (of `fleet` types), planning each step both ways and moving by the
/// stateless plan. Returns how many tracks the session held on average.
fn equivalent_run(
    index: usize,
    fleet: Option<&str>,
    sensors: usize,
    policy: Policy,
    history: usize,
    steps: usize,
    seed: u64,
) -> f64 {
    let scenario = builtins().remove(index);
    let planner = Arc::new(Planner::new(scenario.clone()));
    let types = fleet_types(&scenario, fleet, sensors).expect("fleet fits");
    let mut sim = Sim::with_types(scenario, types, Start::Random, seed, history);
    let mut session = Session::new(
        planner.clone(),
        sim.session_settings(policy, Some(3), history),
    );
    let mut tracks = 0usize;
    for step in 0..steps {
        sim.observe();
        let request = sim.plan_request(policy, Some(3));
        let stateless = planner
            .plan_request(&request)
            .expect("valid stateless request");
        let prepared = session.prepare(&sim.step_request(policy, Some(3)));
        // The same targets (the tracks), at the same places.
        let key = |t: &vigil::planner::TargetIn| format!("{:?}", t.id);
        let mut want = request.targets.clone();
        let mut got = prepared.request.targets.clone();
        want.sort_by_key(key);
        got.sort_by_key(key);
        assert_eq!(want.len(), got.len(), "step {step}: tracks");
        for (a, b) in want.iter().zip(&got) {
            assert_eq!(a.id, b.id, "step {step}");
            assert!(
                (a.x - b.x).abs() < 1e-9 && (a.y - b.y).abs() < 1e-9,
                "step {step}"
            );
            assert_eq!((a.vx, a.vy), (b.vx, b.vy), "step {step}");
        }
        assert_eq!(
            request.history, prepared.request.history,
            "step {step}: history"
        );
        let via_session = planner
            .plan_request(&prepared.request)
            .expect("valid session request");
        assert_same_plan(step, &stateless, &via_session);
        session.commit(prepared);
        assert_eq!(session.step(), step as u64 + 1);
        tracks += session.tracks().len();
        let next = sim.moves_from_plan(&stateless).expect("legal moves");
        sim.advance(next);
    }
    tracks as f64 / steps as f64
}

#[test]
fn a_session_plans_as_the_stateless_requests_on_a_fleet() {
    // site-fleet: drones (p_detect 0.6, speed 3) and robots.
    let index = builtins()
        .iter()
        .position(|s| s.id == "site-fleet")
        .unwrap();
    let tracks = equivalent_run(
        index,
        Some("drone:3,robot:5"),
        8,
        Policy::Exact,
        16,
        150,
        11,
    );
    assert!(tracks > 1.0, "too few tracks to test: {tracks}");
}

#[test]
fn a_session_plans_as_the_stateless_requests_on_gates() {
    let index = builtins()
        .iter()
        .position(|s| s.id == "site-gates")
        .unwrap();
    let tracks = equivalent_run(index, None, 6, Policy::Exact, 8, 150, 5);
    assert!(tracks > 1.0, "too few tracks to test: {tracks}");
}

#[test]
fn a_session_plans_as_the_stateless_requests_with_the_paper_estimator() {
    let tracks = equivalent_run(0, None, 10, Policy::Paper, 4, 100, 3);
    assert!(tracks > 1.0, "too few tracks to test: {tracks}");
}

/// `vigil-sim --session` gives the same metrics as stateless requests.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn vigil_sim_through_sessions_gives_the_same_metrics() {
    let base = spawn_local_server().await.expect("server");
    let client = Client::new(&base);
    let info = client.scenario("site-gates").await.expect("built-in");
    let scenario = vigil::scenario::Scenario::new(info.spec).expect("valid");
    let cfg = |session: bool| RunConfig {
        label: "s".into(),
        policy: Policy::Exact,
        scenario_id: info.id.clone(),
        scenario: scenario.clone(),
        sensors: 6,
        fleet: None,
        steps: 40,
        warmup: 15,
        horizon: Some(3),
        history: 8,
        start: Start::Grid,
        min_separation: None,
        session,
        blind: false,
        world_rates: None,
        stationary_start: false,
    };
    for seed in [1, 2] {
        let (stateless, _) = run_one(&client, &cfg(false), seed, false)
            .await
            .expect("run");
        let (sessions, _) = run_one(&client, &cfg(true), seed, false)
            .await
            .expect("run");
        assert_eq!(stateless.ad, sessions.ad, "seed {seed}");
        assert_eq!(stateless.af, sessions.af, "seed {seed}");
        assert_eq!(
            stateless.detected_once, sessions.detected_once,
            "seed {seed}"
        );
        assert_eq!(stateless.delay, sessions.delay, "seed {seed}");
        assert_eq!(stateless.missed, sessions.missed, "seed {seed}");
        assert!(stateless.delay.is_some() && stateless.missed.is_some());
        let (a, b) = (
            stateless.calibration.unwrap(),
            sessions.calibration.unwrap(),
        );
        assert!((a - b).abs() < 1e-9, "seed {seed}: calibration {a} vs {b}");
    }
    // Every session was closed.
    let metrics = reqwest::get(format!("{base}/metrics"))
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    assert!(metrics.contains("vigil_sessions_live 0"), "{metrics}");
}
