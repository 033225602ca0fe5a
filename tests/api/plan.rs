//! Planning on the built-in `paper-v10` scenario (30×30 cells of 10 units).

use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::helpers::{close, json_body, metric, plan_request, spawn_app, spawn_with};

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

/// A plan's answer without its timing.
fn untimed(mut res: Value) -> Value {
    res["compute_micros"] = json!(0);
    res
}

/// A server that plans on its async workers (as one with a single core
/// does) answers every request as one that plans on rayon's pool, to the
/// last bit: every estimator and coordination, history, a fleet's types,
/// a session's steps. A plan predicted above the inline bound still goes
/// to the pool; the metric counts where each ran.
#[tokio::test]
async fn plans_on_the_async_worker_answer_as_on_the_pool() {
    use vigil::http::config::{INLINE_PLAN_MS, Settings};
    let on = |inline| Settings {
        inline_plans: Some(inline),
        ..Settings::default()
    };
    let (pool, worker) = (spawn_with(on(false)).await, spawn_with(on(true)).await);
    let mut requests = Vec::new();
    for estimator in ["exact", "paper"] {
        for coordination in ["none", "priority", "iterated"] {
            let mut req = plan_request();
            req["estimator"] = json!(estimator);
            req["coordination"] = json!(coordination);
            req["history"] = json!([[{"x": 40.0, "y": 60.0}, {"x": 250.0, "y": 150.0}],
                [{"x": 50.0, "y": 60.0}, {"x": 240.0, "y": 150.0}]]);
            req["explain"] = json!(true);
            requests.push(("/v1/scenarios/paper-v10/plan", req));
        }
    }
    requests.push((
        "/v1/scenarios/site-fleet/plan",
        json!({"sensors": [{"id": "r", "x": 55.0, "y": 55.0, "type": "robot"},
            {"id": "d", "x": 305.0, "y": 105.0, "type": "drone"}],
            "targets": [{"x": 60.0, "y": 70.0, "vx": 1.5, "vy": 0.0}],
            "history": [[{"x": 65.0, "y": 55.0, "type": "robot"}]],
            "min_separation": 2}),
    ));
    for (path, req) in &requests {
        let a = json_body(pool.post_json(path, req).await, StatusCode::OK).await;
        let b = json_body(worker.post_json(path, req).await, StatusCode::OK).await;
        assert_eq!(untimed(a), untimed(b), "{path} {req}");
    }
    // The metrics are the process's, shared by every test of this binary;
    // only this one plans on a worker.
    let n = requests.len() as f64;
    let on_worker = || metric(&worker.address, "vigil_plans_total", &["on=\"worker\""]);
    assert_eq!(on_worker().await, n);

    // A plan predicted above the bound runs on the pool even so.
    let planner = vigil::planner::Planner::new(
        vigil::scenario::builtins()
            .into_iter()
            .find(|s| s.id == "paper-v10")
            .unwrap(),
    );
    let sensors: Vec<Value> = (0..48)
        .map(|i| json!({"id": i, "x": 5.0 + f64::from(i % 8) * 40.0, "y": 5.0 + f64::from(i / 8) * 50.0}))
        .collect();
    let long = json!({"sensors": sensors, "horizon": 10, "coordination": "iterated"});
    let input = vigil::planner::PlanInput::new(
        &planner.scenario,
        &serde_json::from_value(long.clone()).unwrap(),
    )
    .unwrap();
    assert!(vigil::cost::plan_ms(&planner, &input) > INLINE_PLAN_MS);
    json_body(worker.plan(&long).await, StatusCode::OK).await;
    assert_eq!(on_worker().await, n);

    // So does a first-detections plan predicted below it: its searches'
    // parallel batches would each hop to the pool from the worker.
    let mut first = plan_request();
    first["objective"] = json!("first_detections");
    let input = vigil::planner::PlanInput::new(
        &planner.scenario,
        &serde_json::from_value(first.clone()).unwrap(),
    )
    .unwrap();
    assert!(vigil::cost::plan_ms(&planner, &input) <= INLINE_PLAN_MS);
    let a = json_body(pool.plan(&first).await, StatusCode::OK).await;
    let b = json_body(worker.plan(&first).await, StatusCode::OK).await;
    assert_eq!(untimed(a), untimed(b));
    assert_eq!(on_worker().await, n);

    // A session's steps alike.
    let mut ids = Vec::new();
    for app in [&pool, &worker] {
        let res = app
            .post_json("/v1/sessions", &json!({"scenario_id": "paper-v10"}))
            .await;
        let info = json_body(res, StatusCode::CREATED).await;
        ids.push(info["id"].as_str().unwrap().to_owned());
    }
    for step in 0..4 {
        let shift = 10.0 * f64::from(step);
        let body = json!({"sensors": [{"id": "a", "x": 55.0 + shift, "y": 55.0},
                {"id": "b", "x": 245.0, "y": 60.0 + shift}],
            "detections": [{"id": step, "x": 60.0 + shift, "y": 40.0, "vx": 10.0, "vy": 0.0}]});
        let a = pool
            .post_json(&format!("/v1/sessions/{}/step", ids[0]), &body)
            .await;
        let b = worker
            .post_json(&format!("/v1/sessions/{}/step", ids[1]), &body)
            .await;
        let (a, b) = (
            json_body(a, StatusCode::OK).await,
            json_body(b, StatusCode::OK).await,
        );
        assert_eq!(untimed(a), untimed(b), "step {step}");
    }
}

/// `"certify": false` leaves the bound out and changes nothing else (for
/// both objectives and every coordination but `joint`, which refuses it);
/// sessions take it at creation and per step.
#[tokio::test]
async fn certify_false_skips_the_bound_and_nothing_else() {
    let app = spawn_app().await;
    for objective in ["detections", "first_detections"] {
        for coordination in ["none", "priority", "iterated"] {
            let mut req = plan_request();
            req["objective"] = json!(objective);
            req["coordination"] = json!(coordination);
            let certified = untimed(json_body(app.plan(&req).await, StatusCode::OK).await);
            req["certify"] = json!(false);
            let plain = untimed(json_body(app.plan(&req).await, StatusCode::OK).await);
            assert!(
                certified["bound"]["upper"].as_f64().is_some(),
                "{certified}"
            );
            assert!(plain.get("bound").is_none(), "{plain}");
            let mut without = certified.clone();
            without.as_object_mut().unwrap().remove("bound");
            assert_eq!(plain, without, "{objective}, {coordination}");
        }
    }
    let mut joint = plan_request();
    joint["coordination"] = json!("joint");
    joint["certify"] = json!(false);
    crate::helpers::assert_validation(app.plan(&joint).await, "certify").await;

    // Sessions: off at creation, on again for one step.
    let res = app
        .post_json(
            "/v1/sessions",
            &json!({"scenario_id": "paper-v10", "certify": false}),
        )
        .await;
    let id = json_body(res, StatusCode::CREATED).await["id"]
        .as_str()
        .unwrap()
        .to_owned();
    let step = |certify: Option<bool>| {
        let mut body = json!({"sensors": plan_request()["sensors"]});
        if let Some(c) = certify {
            body["certify"] = json!(c);
        }
        body
    };
    let first = json_body(
        app.post_json(&format!("/v1/sessions/{id}/step"), &step(None))
            .await,
        StatusCode::OK,
    )
    .await;
    assert!(first.get("bound").is_none(), "{first}");
    let second = json_body(
        app.post_json(&format!("/v1/sessions/{id}/step"), &step(Some(true)))
            .await,
        StatusCode::OK,
    )
    .await;
    assert!(second["bound"]["upper"].as_f64().is_some(), "{second}");
    crate::helpers::assert_validation(
        app.post_json(
            "/v1/sessions",
            &json!({"scenario_id": "paper-v10", "coordination": "joint", "certify": false}),
        )
        .await,
        "certify",
    )
    .await;
}
