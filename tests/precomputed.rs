//! A precomputation written and read back ([`Planner::encode_precomputed`],
//! [`Planner::from_precomputed`]) is the same planner, to the bit: every
//! byte written again, and every plan the same, on scenarios that use each
//! index (square and circular fields of view, buildings, no-go ground).
#![allow(clippy::unwrap_used)]

use serde_json::{Value, json};
use vigil::planner::{PlanRequest, Planner};
use vigil::scenario::{FovSpec, Scenario, builtins, paper_spec};

/// A plan's answer without its timing.
fn plan(p: &Planner, req: &Value) -> Value {
    let req: PlanRequest = serde_json::from_value(req.clone()).unwrap();
    let mut out = serde_json::to_value(p.plan_request(&req).unwrap()).unwrap();
    out.as_object_mut().unwrap().remove("compute_micros");
    out
}

/// Points of scenario `s` where a sensor may stand (not in a building nor
/// on no-go ground), spread over the zone.
fn standing(p: &Planner) -> Vec<(f64, f64)> {
    let s = &p.scenario;
    (1..10)
        .flat_map(|i| (1..10).map(move |j| (f64::from(i) / 10.0, f64::from(j) / 10.0)))
        .map(|(fx, fy)| (s.width * fx, s.height * fy))
        .filter(|&(x, y)| {
            let req = json!({"sensors": [{"id": "a", "x": x, "y": y}], "horizon": 1});
            p.plan_request(&serde_json::from_value(req).unwrap())
                .is_ok()
        })
        .collect()
}

/// Requests on `p`'s scenario: two sensors, history and a target, for each
/// objective.
fn requests(p: &Planner) -> Vec<Value> {
    let at = standing(p);
    assert!(at.len() >= 4, "{}", p.scenario.id);
    let (w, h) = (p.scenario.width, p.scenario.height);
    let sensors = json!([{"id": "a", "x": at[0].0, "y": at[0].1}, {"id": "b", "x": at[at.len() - 1].0, "y": at[at.len() - 1].1}]);
    let history = json!([[{"x": at[1].0, "y": at[1].1}], [{"x": at[at.len() - 2].0, "y": at[at.len() - 2].1}]]);
    let targets = json!([{"x": w * 0.5, "y": h * 0.5, "vx": 3.0, "vy": 1.0}]);
    ["detections", "first_detections"]
        .into_iter()
        .map(|objective| {
            json!({"sensors": sensors, "history": history, "targets": targets,
                "horizon": 2, "objective": objective})
        })
        .collect()
}

#[test]
fn a_precomputation_read_back_plans_to_the_bit() {
    let mut scenarios = builtins();
    let mut circle = paper_spec(10.0);
    circle.fov = FovSpec::Circle { radius: 25.0 };
    scenarios.push(Scenario::new(circle).unwrap());
    for s in scenarios {
        let fresh = Planner::new(s.clone());
        let bytes = fresh.encode_precomputed();
        let loaded = Planner::from_precomputed(s.clone(), &bytes).unwrap();
        assert!(loaded.encode_precomputed() == bytes, "{}", s.id);
        for req in requests(&fresh) {
            assert_eq!(plan(&loaded, &req), plan(&fresh, &req), "{}: {req}", s.id);
        }
        // Truncated, or of another scenario: refused, never trusted.
        let err = Planner::from_precomputed(s.clone(), &bytes[..bytes.len() - 1]).unwrap_err();
        assert!(err.0.contains("truncated"), "{err}");
        let other = Scenario::new(paper_spec(12.5)).unwrap();
        let err = Planner::from_precomputed(other, &bytes).unwrap_err();
        assert!(err.0.contains("not of"), "{err}");
    }
}
