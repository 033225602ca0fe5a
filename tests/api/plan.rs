//! Planning on the built-in `paper-v10` scenario (30×30 cells of 10 units).

use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::helpers::{close, json_body, plan_request, spawn_app};

const SIDE: i64 = 30;
const CELL: f64 = 10.0;

fn cell_of(v: &Value) -> (i64, i64) {
    let (col, row) = (v["col"].as_i64().unwrap(), v["row"].as_i64().unwrap());
    // Each cell carries its centre.
    assert_eq!(v["x"].as_f64().unwrap(), (col as f64 + 0.5) * CELL);
    assert_eq!(v["y"].as_f64().unwrap(), (row as f64 + 0.5) * CELL);
    (col, row)
}

fn on_lattice((col, row): (i64, i64)) -> bool {
    (0..SIDE).contains(&col) && (0..SIDE).contains(&row)
}

/// Checks every invariant of a plan response for `req` with horizon `t`.
fn check_plan(res: &Value, req: &Value, t: usize, explain: bool) {
    assert_eq!(res["scenario"], "paper-v10");
    assert_eq!(res["horizon"], t);
    let sensors = req["sensors"].as_array().unwrap();
    let plans = res["plans"].as_array().unwrap();
    assert_eq!(plans.len(), sensors.len());

    let mut priorities = Vec::new();
    for (plan, sensor) in plans.iter().zip(sensors) {
        // Request order, ids echoed as given (string or number).
        assert_eq!(plan["sensor"], sensor["id"]);
        priorities.push(plan["priority"].as_u64().unwrap());
        assert!(plan["expected_detections"].as_f64().unwrap().is_finite());

        let start = cell_of(&plan["start"]);
        let x = sensor["x"].as_f64().unwrap();
        let y = sensor["y"].as_f64().unwrap();
        let snap = |v: f64| ((v / CELL).floor() as i64).clamp(0, SIDE - 1);
        assert_eq!(start, (snap(x), snap(y)));
        let path = plan["path"].as_array().unwrap();
        assert_eq!(path.len(), t);
        let mut prev = start;
        for step in path {
            let c = cell_of(step);
            assert!(on_lattice(c), "{c:?} off the lattice");
            let cheb = (c.0 - prev.0).abs().max((c.1 - prev.1).abs());
            assert!(cheb <= 1, "jump from {prev:?} to {c:?}");
            prev = c;
        }

        match plan.get("explain") {
            None => assert!(!explain, "explain missing"),
            Some(e) => {
                assert!(explain, "explain present but not requested");
                check_explain(&e["values"], start, t);
            }
        }
    }
    priorities.sort_unstable();
    let expected: Vec<u64> = (1..=sensors.len() as u64).collect();
    assert_eq!(priorities, expected);

    let by_step: Vec<f64> = res["expected_by_step"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(by_step.len(), t);
    assert!(by_step.iter().all(|v| v.is_finite() && *v >= 0.0));
    let total = res["expected_detections"].as_f64().unwrap();
    assert!(
        close(by_step.iter().sum(), total, 1e-9),
        "{by_step:?} vs {total}"
    );
    assert!(res["compute_micros"].as_u64().is_some());
}

/// `values[t−1][dr+T][dc+T]` is null exactly where the offset is farther
/// than `t` or off the lattice.
fn check_explain(values: &Value, start: (i64, i64), t: usize) {
    let side = 2 * t + 1;
    let h = t as i64;
    let steps = values.as_array().unwrap();
    assert_eq!(steps.len(), t);
    for (ti, rows) in steps.iter().enumerate() {
        let step = ti as i64 + 1;
        let rows = rows.as_array().unwrap();
        assert_eq!(rows.len(), side);
        for (ri, cols) in rows.iter().enumerate() {
            let cols = cols.as_array().unwrap();
            assert_eq!(cols.len(), side);
            for (ci, v) in cols.iter().enumerate() {
                let (dc, dr) = (ci as i64 - h, ri as i64 - h);
                let reachable = dc.abs() <= step && dr.abs() <= step;
                let cell = (start.0 + dc, start.1 + dr);
                if reachable && on_lattice(cell) {
                    assert!(
                        v.as_f64().is_some_and(f64::is_finite),
                        "t={step} dc={dc} dr={dr}: {v}"
                    );
                } else {
                    assert!(v.is_null(), "t={step} dc={dc} dr={dr}: {v}");
                }
            }
        }
    }
}

#[tokio::test]
async fn every_estimator_and_coordination_plans_valid_paths() {
    let app = spawn_app().await;
    for estimator in ["exact", "paper"] {
        for coordination in ["none", "priority", "iterated"] {
            let mut req = plan_request();
            req["estimator"] = json!(estimator);
            req["coordination"] = json!(coordination);
            let res = json_body(app.plan(&req).await, StatusCode::OK).await;
            assert_eq!(res["estimator"], estimator);
            assert_eq!(res["coordination"], coordination);
            check_plan(&res, &req, 3, false);
        }
    }
}

#[tokio::test]
async fn defaults_are_exact_priority_and_the_scenario_horizon() {
    let app = spawn_app().await;
    let req = plan_request();
    let res = json_body(app.plan(&req).await, StatusCode::OK).await;
    assert_eq!(res["estimator"], "exact");
    assert_eq!(res["coordination"], "priority");
    check_plan(&res, &req, 3, false);
}

#[tokio::test]
async fn explain_has_nulls_exactly_off_reach_and_off_lattice() {
    let app = spawn_app().await;
    for estimator in ["exact", "paper"] {
        for coordination in ["none", "priority", "iterated"] {
            let mut req = plan_request();
            // A sensor in the south-west corner cell, and one at the far edge.
            req["sensors"][0] = json!({"id": "corner", "x": 1.0, "y": 1.0});
            req["sensors"][2] = json!({"id": "edge", "x": 300.0, "y": 150.0});
            req["estimator"] = json!(estimator);
            req["coordination"] = json!(coordination);
            req["explain"] = json!(true);
            let res = json_body(app.plan(&req).await, StatusCode::OK).await;
            check_plan(&res, &req, 3, true);
            assert_eq!(res["plans"][0]["start"]["col"], 0);
            assert_eq!(res["plans"][2]["start"]["col"], 29);

            req["explain"] = json!(false);
            let res = json_body(app.plan(&req).await, StatusCode::OK).await;
            check_plan(&res, &req, 3, false);
        }
    }
}

#[tokio::test]
async fn horizon_override_is_honoured() {
    let app = spawn_app().await;
    for (horizon, coordination) in [
        (1, "iterated"),
        (5, "priority"),
        (5, "iterated"),
        (12, "none"),
    ] {
        let mut req = plan_request();
        req["horizon"] = json!(horizon);
        req["coordination"] = json!(coordination);
        req["explain"] = json!(horizon == 5);
        let res = json_body(app.plan(&req).await, StatusCode::OK).await;
        check_plan(&res, &req, horizon, horizon == 5);
    }
}

#[tokio::test]
async fn sensor_positions_snap_to_their_cell() {
    let app = spawn_app().await;
    let req = json!({"sensors": [{"id": "s", "x": 14.2, "y": 5.0}]});
    let res = json_body(app.plan(&req).await, StatusCode::OK).await;
    assert_eq!(
        res["plans"][0]["start"],
        json!({"col": 1, "row": 0, "x": 15.0, "y": 5.0})
    );
    check_plan(&res, &req, 3, false);
}

#[tokio::test]
async fn history_and_observed_zone_are_accepted() {
    let app = spawn_app().await;
    let mut req = plan_request();
    req["history"] = json!([
        [{"x": 45.0, "y": 55.0}, {"x": 150.0, "y": 140.0}, {"x": 245.0, "y": 70.0}],
        [{"x": 35.0, "y": 55.0}, {"x": 150.0, "y": 130.0}, {"x": 245.0, "y": 80.0}]
    ]);
    for observed in ["sensors", "zone"] {
        req["observed"] = json!(observed);
        let res = json_body(app.plan(&req).await, StatusCode::OK).await;
        check_plan(&res, &req, 3, false);
    }
}

#[tokio::test]
async fn no_targets_and_many_sensors_plan() {
    let app = spawn_app().await;
    let sensors: Vec<Value> = (0..8)
        .map(|i| json!({"id": i, "x": 5.0 + 37.0 * i as f64, "y": 300.0 - 37.0 * i as f64}))
        .collect();
    let req = json!({"sensors": sensors, "coordination": "iterated"});
    let res = json_body(app.plan(&req).await, StatusCode::OK).await;
    check_plan(&res, &req, 3, false);
}

#[tokio::test]
async fn extreme_but_finite_targets_do_not_fail_the_server() {
    let app = spawn_app().await;
    let mut req = plan_request();
    req["targets"] = json!([
        {"x": 1e308, "y": -1e308, "vx": 1e308, "vy": -1e308},
        {"x": -1e308, "y": 150.0, "vx": 1e308, "vy": 0.0},
        {"x": 150.0, "y": 150.0, "vx": 0.0, "vy": 0.0},
        {"x": 150.0, "y": 150.0, "vx": 1e-300, "vy": -1e-300},
        {"x": 0.0, "y": 0.0, "vx": 300.0, "vy": 300.0}
    ]);
    for estimator in ["exact", "paper"] {
        for coordination in ["none", "priority", "iterated"] {
            req["estimator"] = json!(estimator);
            req["coordination"] = json!(coordination);
            let res = app.plan(&req).await;
            let status = res.status();
            let text = res.text().await.unwrap();
            assert!(
                status == StatusCode::OK || status == StatusCode::UNPROCESSABLE_ENTITY,
                "{estimator}/{coordination}: {status} {text}"
            );
        }
    }
}
