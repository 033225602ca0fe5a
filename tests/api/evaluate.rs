//! Scoring paths over HTTP (`/v1/scenarios/{id}/evaluate`, `/v1/evaluate`)
//! and the certificate every exact plan carries.

use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::helpers::{
    assert_problem, assert_validation, close, json_body, paths_of, plan_request, spawn_app,
};

#[tokio::test]
async fn a_plans_own_paths_score_its_value_and_marginals_add_up() {
    let app = spawn_app().await;
    for coordination in ["none", "priority", "iterated", "joint"] {
        let mut req = plan_request();
        req["coordination"] = json!(coordination);
        req["min_separation"] = json!(2);
        let plan = json_body(app.plan(&req).await, StatusCode::OK).await;
        let mut ev = req.clone();
        ev["paths"] = paths_of(&plan);
        let scored = json_body(
            app.post_json("/v1/scenarios/paper-v10/evaluate", &ev).await,
            StatusCode::OK,
        )
        .await;
        let (a, b) = (
            scored["expected_detections"].as_f64().unwrap(),
            plan["expected_detections"].as_f64().unwrap(),
        );
        assert!(close(a, b, 1e-9), "{coordination}: {a} vs {b}");
        assert_eq!(
            scored["separation_violations"],
            plan["separation_violations"]
        );
        assert_eq!(scored["horizon"], plan["horizon"]);
        let sensors = scored["sensors"].as_array().unwrap();
        assert_eq!(sensors.len(), 3);
        for (s, p) in sensors.iter().zip(plan["plans"].as_array().unwrap()) {
            assert_eq!(s["sensor"], p["sensor"]);
            let m = s["marginal"].as_f64().unwrap();
            assert!(m >= -1e-9 && m <= a + 1e-9, "{m}");
        }
        // The certificate bounds the value; joint says what it did.
        let bound = &plan["bound"];
        let upper = bound["upper"].as_f64().unwrap();
        assert!(upper >= b, "{bound}");
        let gap = bound["gap"].as_f64().unwrap();
        assert!(
            close(gap, (upper - b) / upper, 1e-9) || gap == 0.0,
            "{bound}"
        );
        assert_eq!(
            plan.get("joint").is_some(),
            coordination == "joint",
            "{plan}"
        );
    }
    // The same by id in the body, and with the paper estimator (no bound).
    let mut req = plan_request();
    req["estimator"] = json!("paper");
    let plan = json_body(app.plan(&req).await, StatusCode::OK).await;
    assert!(plan.get("bound").is_none(), "{plan}");
    let mut ev = req.clone();
    // Paper totals count in the order given: highest priority first.
    let mut paths: Vec<(u64, Value)> = plan["plans"]
        .as_array()
        .unwrap()
        .iter()
        .zip(paths_of(&plan).as_array().unwrap())
        .map(|(p, path)| (p["priority"].as_u64().unwrap(), path.clone()))
        .collect();
    paths.sort_by_key(|(rank, _)| *rank);
    ev["paths"] = Value::Array(paths.into_iter().map(|(_, p)| p).collect());
    ev["scenario_id"] = json!("paper-v10");
    let scored = json_body(app.post_json("/v1/evaluate", &ev).await, StatusCode::OK).await;
    assert!(close(
        scored["expected_detections"].as_f64().unwrap(),
        plan["expected_detections"].as_f64().unwrap(),
        1e-9
    ));
    assert_eq!(scored["estimator"], "paper");
}

#[tokio::test]
async fn illegal_paths_are_422_naming_the_field() {
    let app = spawn_app().await;
    // Sensors at (5,5), (15,15), (24,6) on paper-v10; T = 3.
    let good = || {
        let mut ev = plan_request();
        ev["paths"] = json!([
            {"sensor": "a", "path": [{"col": 6, "row": 4}, {"col": 7, "row": 3}, {"col": 8, "row": 2}]},
            {"sensor": 7, "path": [{"col": 15, "row": 15}, {"col": 15, "row": 15}, {"col": 15, "row": 15}]},
            {"sensor": "c", "path": [{"col": 23, "row": 5}, {"col": 22, "row": 4}, {"col": 22, "row": 3}]}
        ]);
        ev
    };
    let url = "/v1/scenarios/paper-v10/evaluate";
    json_body(app.post_json(url, &good()).await, StatusCode::OK).await;
    // (change to a good body, the field named, what the detail says).
    type Change = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(Change, &str, &str)> = vec![
        (
            Box::new(|ev| ev["paths"][0]["path"][1] = json!({"col": 8, "row": 4})),
            "paths[0].path[1]",
            "beyond the speed",
        ),
        (
            Box::new(|ev| ev["paths"][2]["path"][0] = json!({"col": 30, "row": 5})),
            "paths[2].path[0]",
            "off the lattice",
        ),
        (
            Box::new(|ev| ev["paths"][0]["path"][0] = json!({"col": -1, "row": 4})),
            "paths[0].path[0]",
            "off the lattice",
        ),
        (
            Box::new(|ev| {
                ev["paths"][1]["path"].as_array_mut().unwrap().pop();
            }),
            "paths[1].path",
            "steps 1..=3",
        ),
        (
            Box::new(|ev| ev["paths"][1]["sensor"] = json!("z")),
            "paths[1].sensor",
            "no sensor \"z\"",
        ),
        (
            Box::new(|ev| {
                ev["sensors"][1]["id"] = json!(7);
                ev["paths"][1]["sensor"] = json!("7");
            }),
            "paths[1].sensor",
            "no sensor \"7\" in `sensors` (it has 7: a string id and a number id differ)",
        ),
        (
            Box::new(|ev| ev["paths"][1]["sensor"] = json!("a")),
            "paths[1].sensor",
            "a second path",
        ),
        (
            Box::new(|ev| {
                ev["paths"].as_array_mut().unwrap().pop();
            }),
            "paths",
            "sensor \"c\" has no path",
        ),
        (
            Box::new(|ev| ev["paths"][0]["path"][0]["col"] = json!(2.5)),
            "paths[0].path[0].col",
            "whole number",
        ),
    ];
    for (change, field, mentions) in cases {
        let mut ev = good();
        change(&mut ev);
        let res = app.post_json(url, &ev).await;
        let body = assert_problem(res, StatusCode::UNPROCESSABLE_ENTITY, mentions).await;
        assert!(
            body["detail"]
                .as_str()
                .unwrap()
                .starts_with(&format!("{field}: ")),
            "{body}"
        );
    }
    // A plan request's own errors, an unknown field, an unknown scenario.
    let mut ev = good();
    ev["sensors"][0]["x"] = json!(-5.0);
    assert_validation(app.post_json(url, &ev).await, "sensors[0]").await;
    let mut ev = good();
    ev["paths"][0]["extra"] = json!(1);
    assert_problem(
        app.post_json(url, &ev).await,
        StatusCode::BAD_REQUEST,
        "extra",
    )
    .await;
    let mut ev = good();
    ev["nonsense"] = json!(1);
    assert_problem(
        app.post_json(url, &ev).await,
        StatusCode::BAD_REQUEST,
        "nonsense",
    )
    .await;
    let mut ev = good();
    ev.as_object_mut().unwrap().remove("paths");
    assert_problem(
        app.post_json(url, &ev).await,
        StatusCode::BAD_REQUEST,
        "paths",
    )
    .await;
    assert_problem(
        app.post_json("/v1/scenarios/nope/evaluate", &good()).await,
        StatusCode::NOT_FOUND,
        "nope",
    )
    .await;
    // Inline: exactly one of scenario_id and scenario.
    assert_problem(
        app.post_json("/v1/evaluate", &good()).await,
        StatusCode::UNPROCESSABLE_ENTITY,
        "exactly one",
    )
    .await;
}

#[tokio::test]
async fn no_go_cells_and_cut_off_moves_are_refused() {
    let app = spawn_app().await;
    // A fast type (speed 2) beside a wall of no-go cells one cell thick:
    // it cannot stand on it, and a two-cell move across it is legal (king
    // moves go round a one-cell wall), but not into its middle.
    let spec = json!({
        "zone": {"width": 100.0, "height": 100.0},
        "cell_size": 10.0,
        "fov": {"shape": "square", "half_width": 15.0},
        "sensor_types": {"fast": {"fov": {"shape": "square", "half_width": 15.0}, "speed": 2}},
        "no_go": [{"x0": 40.0, "y0": 0.0, "x1": 50.0, "y1": 100.0}],
        "target_speed": 10.0,
        "sources": [{"x": -1.0, "y": 50.0, "rate": 1.0}],
        "horizon": 2
    });
    let mut ev = json!({
        "scenario": spec,
        "sensors": [{"id": "f", "x": 35.0, "y": 55.0, "type": "fast"}],
        "paths": [{"sensor": "f", "path": [{"col": 4, "row": 5}, {"col": 3, "row": 5}]}]
    });
    assert_problem(
        app.post_json("/v1/evaluate", &ev).await,
        StatusCode::UNPROCESSABLE_ENTITY,
        "paths[0].path[0]: (col 4, row 5) is in a no-go zone",
    )
    .await;
    // Across a wall of the whole height: no way round within two cells.
    ev["paths"][0]["path"] = json!([{"col": 5, "row": 5}, {"col": 5, "row": 5}]);
    assert_problem(
        app.post_json("/v1/evaluate", &ev).await,
        StatusCode::UNPROCESSABLE_ENTITY,
        "cannot be reached",
    )
    .await;
    ev["paths"][0]["path"] = json!([{"col": 2, "row": 7}, {"col": 1, "row": 9}]);
    json_body(app.post_json("/v1/evaluate", &ev).await, StatusCode::OK).await;
}

/// A sensor's marginal is what the total loses without its path: scored
/// again without that sensor (the zone observed whole, so that the sensors
/// now are not what is known: the value is in a reported target and the
/// targets entering at the edge they guard), for sensors whose views
/// overlap (so that the marginals sum to less than the total).
#[tokio::test]
async fn a_marginal_is_the_total_less_the_total_without_the_sensor() {
    let app = spawn_app().await;
    let sensors: Vec<Value> = [(5.0, 150.0), (15.0, 150.0), (5.0, 160.0), (25.0, 165.0)]
        .iter()
        .enumerate()
        .map(|(i, (x, y))| json!({"id": i, "x": x, "y": y}))
        .collect();
    // What the zone holds now is reported whole, so that leaving a sensor
    // out changes its paths alone, not what is known.
    let req = json!({"sensors": sensors, "horizon": 3, "coordination": "none",
        "observed": "zone", "targets": [{"x": 12.0, "y": 155.0, "vx": 1.0, "vy": 0.0}]});
    let plan = json_body(app.plan(&req).await, StatusCode::OK).await;
    let paths = paths_of(&plan);
    let score = |keep: Vec<usize>| {
        let mut ev = req.clone();
        ev["sensors"] = Value::Array(keep.iter().map(|&i| sensors[i].clone()).collect());
        ev["paths"] = Value::Array(keep.iter().map(|&i| paths[i].clone()).collect());
        let app = &app;
        async move {
            json_body(
                app.post_json("/v1/scenarios/paper-v10/evaluate", &ev).await,
                StatusCode::OK,
            )
            .await
        }
    };
    let all = score((0..4).collect()).await;
    let total = all["expected_detections"].as_f64().unwrap();
    let mut sum = 0.0;
    for i in 0..4 {
        let without = score((0..4).filter(|&q| q != i).collect()).await;
        let rest = without["expected_detections"].as_f64().unwrap();
        let m = all["sensors"][i]["marginal"].as_f64().unwrap();
        assert!(
            (m - (total - rest)).abs() <= 1e-9 * total,
            "sensor {i}: {m} vs {}",
            total - rest
        );
        sum += m;
    }
    assert!(
        total > 0.1 && sum < total - 1e-3,
        "overlapping views: {sum} against {total}"
    );
}
