//! Joint coordination in closed loop, over HTTP: every step's plan carries
//! a certificate that holds, and joint never plans worse than iterated for
//! the same request.

use vigil::coordination::Coordination;
use vigil::coordination::joint::JointStop;
use vigil::limits::DEFAULT_GAP_TARGET;
use vigil::scenario::Scenario;
use vigil_sim::client::{Client, spawn_local_server};
use vigil_sim::driver::{Start, checked_bound};
use vigil_sim::experiment::{RunConfig, run_all};
use vigil_sim::policy::Policy;

fn config(policy: Policy, id: &str, scenario: &Scenario, steps: usize) -> RunConfig {
    RunConfig {
        label: policy.name().into(),
        policy,
        scenario_id: id.into(),
        scenario: scenario.clone(),
        sensors: 6,
        fleet: None,
        steps,
        warmup: 20,
        horizon: Some(3),
        history: 8,
        start: Start::Grid,
        min_separation: None,
        session: false,
        blind: false,
        world_rates: None,
        stationary_start: false,
    }
}

/// Twelve steps of `exact-joint` on `paper-v10`, the sensors moving along
/// the joint plans. At every step the same state is also planned with
/// `exact-iterated`, and:
/// - both plans carry a bound at least their value, with `0 ≤ gap ≤ 1`
///   (`checked_bound`), and each bound holds for the other's plan too: both
///   bound the same best joint plan;
/// - joint, which starts from iterated's plan and only keeps better ones,
///   expects at least as much, with no more separation violations;
/// - joint's certificate is no looser than iterated's (it takes the
///   smallest of more bounds, from the same first), unless it stopped at
///   the gap target or before its first round.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn joint_plans_are_certified_and_never_below_iterated() {
    let base = spawn_local_server().await.expect("server");
    let client = Client::new(&base);
    let info = client.scenario("paper-v10").await.expect("built-in");
    let scenario = Scenario::new(info.spec).expect("valid");
    let cfg = config(Policy::ExactJoint, &info.id, &scenario, 12);
    let mut sim = cfg.warmed_up(5);
    let mut rounds = 0;
    for step in 0..cfg.steps {
        sim.observe();
        let req = sim.plan_request(Policy::ExactJoint, cfg.horizon);
        let (joint, _) = client.plan(&info.id, &req).await.expect("joint plan");
        let req = sim.plan_request(Policy::ExactIterated, cfg.horizon);
        let (iterated, _) = client.plan(&info.id, &req).await.expect("iterated plan");
        assert_eq!(joint.coordination, Coordination::Joint);
        assert_eq!(iterated.coordination, Coordination::Iterated);
        let jb = checked_bound(&joint)
            .unwrap_or_else(|e| panic!("step {step}, joint: {e}"))
            .expect("an exact plan's bound");
        let ib = checked_bound(&iterated)
            .unwrap_or_else(|e| panic!("step {step}, iterated: {e}"))
            .expect("an exact plan's bound");
        let report = joint.joint.expect("joint's report");
        assert!(iterated.joint.is_none(), "step {step}: iterated has rounds");
        rounds += report.rounds;

        let (vj, vi) = (joint.expected_detections, iterated.expected_detections);
        let tol = 1e-9 * vi.abs().max(1.0);
        let by_step: f64 = joint.expected_by_step.iter().sum();
        assert!(
            (by_step - vj).abs() <= tol,
            "step {step}: {by_step} vs {vj}"
        );
        assert!(vj >= vi - tol, "step {step}: joint {vj} < iterated {vi}");
        assert!(joint.separation_violations <= iterated.separation_violations);
        assert!(
            ib.upper >= vj - tol,
            "step {step}: {} < joint {vj}",
            ib.upper
        );
        assert!(
            jb.upper >= vi - tol,
            "step {step}: {} < iterated {vi}",
            jb.upper
        );
        if report.stopped == JointStop::Gap {
            assert!(jb.gap <= DEFAULT_GAP_TARGET + 1e-12, "step {step}: {jb:?}");
        } else if report.rounds > 0 {
            assert!(
                jb.gap <= ib.gap + 1e-12,
                "step {step}: joint {jb:?} looser than iterated {ib:?} after {report:?}"
            );
        }

        let next = sim.moves_from_plan(&joint).expect("legal moves");
        sim.advance(next);
    }
    eprintln!("joint: {rounds} rounds over {} steps", cfg.steps);

    // The runs' metrics: gaps for the exact estimator only, rounds for
    // joint only.
    let configs: Vec<RunConfig> = [Policy::ExactJoint, Policy::ExactIterated, Policy::Paper]
        .into_iter()
        .map(|p| config(p, &info.id, &scenario, 8))
        .collect();
    let rows = run_all(&client, &configs, 11, 1, 3).await.expect("runs");
    let [joint, iterated, paper] = &rows[..] else {
        panic!("{} rows", rows.len());
    };
    for row in [joint, iterated] {
        let m = &row.metrics;
        for g in [m.gap_mean, m.gap_p50] {
            assert!(
                g.is_some_and(|g| (0.0..=1.0).contains(&g)),
                "{}: {g:?}",
                row.policy
            );
        }
    }
    let m = &joint.metrics;
    assert!(m.joint_rounds.is_some_and(|r| r >= 0.0));
    let stops = m.joint_at_target.unwrap_or(f64::NAN) + m.joint_out_of_budget.unwrap_or(f64::NAN);
    assert!((0.0..=1.0 + 1e-12).contains(&stops), "{stops}");
    assert_eq!(iterated.metrics.joint_rounds, None);
    assert_eq!(
        (paper.metrics.gap_mean, paper.metrics.joint_rounds),
        (None, None)
    );
}
