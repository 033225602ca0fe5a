//! The session workload matches the stateless one: replayed through a
//! session from the run's start, timed step `k` plans exactly as the
//! stateless request `k` of the same run (the reference workload).

use std::sync::Arc;

use vigil::planner::PlanResponse;
use vigil_loadtest::requests;
use vigil_loadtest::session::{session_step, warmed};
use vigil_loadtest::workload::Workload;

fn assert_same_plan(step: usize, stateless: &PlanResponse, session: &PlanResponse) {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(1.0);
    assert!(
        close(stateless.expected_detections, session.expected_detections),
        "step {step}: {} vs {}",
        stateless.expected_detections,
        session.expected_detections
    );
    assert_eq!(stateless.plans.len(), session.plans.len(), "step {step}");
    for (a, b) in stateless.plans.iter().zip(&session.plans) {
        assert_eq!(a.sensor, b.sensor, "step {step}");
        assert_eq!(a.path, b.path, "step {step}: sensor {:?}", a.sensor);
        assert!(
            close(a.expected_detections, b.expected_detections),
            "step {step}: sensor {:?}",
            a.sensor
        );
    }
}

#[test]
fn the_reference_sessions_plans_are_the_stateless_requests_plans() {
    let planner = Arc::new(requests::planner_for("paper-v10").expect("built-in"));
    let w = Workload::reference();
    let count = 6;
    let (reqs, wl) = w.requests_and_session(&planner, count);
    // The same requests as the stateless workload alone.
    assert_eq!(reqs, w.requests(&planner, count));
    assert_eq!(wl.steps.len(), count);
    assert!(wl.warmup.len() >= w.history, "{}", wl.warmup.len());
    let (mut session, mut carry) = warmed(&planner, &wl).expect("warm-up steps are valid");
    assert_eq!(session.history_held(), w.history);
    let mut targets = 0;
    for (k, (step, req)) in wl.steps.iter().zip(&reqs).enumerate() {
        let stateless = planner.plan_request(req).expect("valid request");
        let via_session = session_step(&mut session, &mut carry, step).expect("valid step");
        assert_same_plan(k, &stateless, &via_session);
        targets += req.targets.len();
    }
    // The reference workload follows ~40 targets: a real check.
    assert!(targets / count > 20, "{}", targets / count);
    // A step out of its place (the session already past it) no longer plans
    // as its stateless request: the check above can fail.
    let replayed = session_step(&mut session, &mut carry, &wl.steps[0]).expect("valid step");
    let first = planner.plan_request(&reqs[0]).expect("valid request");
    let differs = (replayed.expected_detections - first.expected_detections).abs() > 1e-9
        || replayed
            .plans
            .iter()
            .zip(&first.plans)
            .any(|(a, b)| a.path != b.path);
    assert!(differs, "a replayed step planned exactly as the first");
}
