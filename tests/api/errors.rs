//! Every error over the socket: status, `application/problem+json`, and a
//! detail naming the offending field.

use reqwest::{StatusCode, header};
use serde_json::{Value, json};
use vigil::limits::MAX_HISTORY_STEPS;

use crate::helpers::{
    TestApp, assert_problem, assert_validation, plan_request, small_spec, spawn_app,
};

#[tokio::test]
async fn malformed_json_is_400() {
    let app = spawn_app().await;
    for path in ["/v1/scenarios", "/v1/scenarios/paper-v10/plan"] {
        for body in [
            &b"{"[..],
            b"{\"sensors\": [",
            b"not json",
            b"",
            b"{} trailing",
        ] {
            let res = app
                .post_raw(path, Some("application/json"), body.to_vec())
                .await;
            assert_problem(res, StatusCode::BAD_REQUEST, "JSON").await;
        }
        // Missing or wrong content type.
        let valid = serde_json::to_vec(&plan_request()).unwrap();
        let res = app.post_raw(path, None, valid.clone()).await;
        assert_problem(res, StatusCode::BAD_REQUEST, "Content-Type").await;
        let res = app.post_raw(path, Some("text/plain"), valid).await;
        assert_problem(res, StatusCode::BAD_REQUEST, "Content-Type").await;
    }
    // Any `application/*+json` is JSON.
    let valid = serde_json::to_vec(&plan_request()).unwrap();
    let res = app
        .post_raw(
            "/v1/scenarios/paper-v10/plan",
            Some("application/vnd.vigil+json; charset=utf-8"),
            valid,
        )
        .await;
    assert_eq!(res.status(), StatusCode::OK);
}

#[tokio::test]
async fn missing_fields_and_wrong_types_are_400() {
    let app = spawn_app().await;
    let cases: [(&str, Value, &str); 9] = [
        // The detail gives the path to the offending value.
        (
            "/v1/scenarios/paper-v10/plan",
            json!({"sensors": [{"id": 1, "x": 5.0, "y": 5.0}, {"id": 2, "x": "a", "y": 5.0}]}),
            "sensors[1].x",
        ),
        (
            "/v1/scenarios/paper-v10/plan",
            json!({"sensors": [{"id": true, "x": 5.0, "y": 5.0}]}),
            "sensors[0].id: invalid type: boolean `true`, expected a string or a number",
        ),
        ("/v1/scenarios/paper-v10/plan", json!({}), "sensors"),
        (
            "/v1/scenarios/paper-v10/plan",
            json!({"sensors": [{"id": 1, "x": 5.0}]}),
            "y",
        ),
        (
            "/v1/scenarios/paper-v10/plan",
            json!({"sensors": "three"}),
            "sensors",
        ),
        (
            "/v1/scenarios/paper-v10/plan",
            json!({"sensors": [], "horizon": "three"}),
            "horizon",
        ),
        (
            "/v1/scenarios/paper-v10/plan",
            json!({"sensors": [], "estimator": "magic"}),
            "estimator",
        ),
        (
            "/v1/scenarios",
            json!({"zone": {"width": 1.0, "height": 1.0}}),
            "cell_size",
        ),
        ("/v1/scenarios", json!({"zone": 1}), "zone"),
    ];
    for (path, body, field) in cases {
        let res = app.post_json(path, &body).await;
        assert_problem(res, StatusCode::BAD_REQUEST, field).await;
    }
    // Unknown fields are rejected too.
    let mut spec = small_spec();
    spec["colour"] = json!("red");
    let res = app.post_json("/v1/scenarios", &spec).await;
    assert_problem(res, StatusCode::BAD_REQUEST, "colour").await;
    // A name of the wrong type is refused as such, with the field and the
    // names it may take, not as JSON that fails to parse.
    let plan = "/v1/scenarios/paper-v10/plan";
    let sensors = json!([{"id": "a", "x": 55.0, "y": 55.0}]);
    for (field, value, names) in [
        (
            "coordination",
            json!(3),
            "`none`, `priority`, `iterated`, `joint`",
        ),
        (
            "objective",
            json!(["x"]),
            "`detections`, `first_detections`",
        ),
        ("observed", json!({"all": true}), "`sensors`, `zone`"),
        ("estimator", json!(true), "`exact`, `paper`"),
    ] {
        let res = app
            .post_json(plan, &json!({"sensors": sensors, field: value}))
            .await;
        let problem = assert_problem(res, StatusCode::BAD_REQUEST, field).await;
        let detail = problem["detail"].as_str().unwrap();
        assert!(detail.contains("invalid type"), "{detail}");
        assert!(detail.contains(names), "{detail}");
        assert!(
            !detail.contains("parse the request body as JSON"),
            "{detail}"
        );
    }
}

#[tokio::test]
async fn unknown_scenario_is_404() {
    let app = spawn_app().await;
    let id = "s-0000000000000000";
    let res = app.get(&format!("/v1/scenarios/{id}")).await;
    assert_problem(res, StatusCode::NOT_FOUND, id).await;
    let res = app.get(&format!("/v1/scenarios/{id}/stats")).await;
    assert_problem(res, StatusCode::NOT_FOUND, id).await;
    let res = app.delete(&format!("/v1/scenarios/{id}")).await;
    assert_problem(res, StatusCode::NOT_FOUND, id).await;
    let res = app
        .post_json(&format!("/v1/scenarios/{id}/plan"), &plan_request())
        .await;
    assert_problem(res, StatusCode::NOT_FOUND, id).await;
    // The scenario is looked up before the body is read.
    let res = app
        .post_raw(&format!("/v1/scenarios/{id}/plan"), None, b"{".to_vec())
        .await;
    assert_problem(res, StatusCode::NOT_FOUND, id).await;
}

#[tokio::test]
async fn unknown_routes_and_methods_are_problems() {
    let app = spawn_app().await;
    for path in [
        "/",
        "/v2/scenarios",
        "/v1/scenarios/paper-v10/nope",
        "/v1/scenarios/",
    ] {
        let res = app.get(path).await;
        assert_problem(res, StatusCode::NOT_FOUND, path).await;
    }
    let res = app.delete("/healthz").await;
    assert_problem(res, StatusCode::METHOD_NOT_ALLOWED, "DELETE").await;
    let res = app.get("/v1/scenarios/paper-v10/plan").await;
    let allow = res
        .headers()
        .get(header::ALLOW)
        .map(|v| v.to_str().unwrap().to_owned());
    assert_problem(res, StatusCode::METHOD_NOT_ALLOWED, "GET").await;
    assert_eq!(allow.as_deref(), Some("POST"));
    let res = app
        .client
        .put(app.url("/v1/scenarios/paper-v10"))
        .json(&json!({}))
        .send()
        .await
        .unwrap();
    assert_problem(res, StatusCode::METHOD_NOT_ALLOWED, "PUT").await;
    // A path parameter that is not UTF-8.
    let res = app.get("/v1/scenarios/%FF").await;
    assert_problem(res, StatusCode::BAD_REQUEST, "UTF-8").await;
}

#[tokio::test]
async fn oversized_body_is_413() {
    let app = spawn_app().await;
    // One byte past the 4 MiB limit.
    let body = vec![b' '; 4 * 1024 * 1024 + 1];
    let res = app
        .post_raw(
            "/v1/scenarios/paper-v10/plan",
            Some("application/json"),
            body,
        )
        .await;
    assert_problem(res, StatusCode::PAYLOAD_TOO_LARGE, "").await;
}

/// POSTs `small_spec()` changed by `edit` and expects a 422 naming `field`.
async fn spec_rejected(app: &TestApp, edit: impl FnOnce(&mut Value), field: &str) {
    let mut spec = small_spec();
    edit(&mut spec);
    let res = app.post_json("/v1/scenarios", &spec).await;
    assert_validation(res, field).await;
}

#[tokio::test]
async fn invalid_specs_are_422() {
    let app = spawn_app().await;
    spec_rejected(
        &app,
        |s| s["sources"][0] = json!({"x": 50.0, "y": 50.0, "rate": 1.0}),
        "sources[0]",
    )
    .await;
    spec_rejected(
        &app,
        |s| s["sources"][1] = json!({"x": 0.0, "y": 100.0, "rate": 1.0}),
        "sources[1]",
    )
    .await;
    spec_rejected(
        &app,
        |s| s["sources"][0] = json!({"x": -1.0, "y": -1.0, "rate": 1.0}),
        "sources[0].heading",
    )
    .await;
    spec_rejected(
        &app,
        |s| s["sources"][0]["heading"] = json!("west"),
        "sources[0].heading",
    )
    .await;
    spec_rejected(&app, |s| s["cell_size"] = json!(7.0), "zone.width").await;
    spec_rejected(&app, |s| s["zone"]["height"] = json!(95.0), "zone.height").await;
    spec_rejected(&app, |s| s["zone"]["width"] = json!(0.0), "zone.width").await;
    spec_rejected(&app, |s| s["zone"]["height"] = json!(-100.0), "zone.height").await;
    spec_rejected(&app, |s| s["cell_size"] = json!(0.0), "cell_size").await;
    spec_rejected(&app, |s| s["cell_size"] = json!(-10.0), "cell_size").await;
    spec_rejected(
        &app,
        |s| s["fov"]["half_width"] = json!(0.0),
        "fov.half_width",
    )
    .await;
    spec_rejected(
        &app,
        |s| s["fov"] = json!({"shape": "circle", "radius": -1.0}),
        "fov.radius",
    )
    .await;
    spec_rejected(&app, |s| s["target_speed"] = json!(0.0), "target_speed").await;
    spec_rejected(&app, |s| s["target_speed"] = json!(-5.0), "target_speed").await;
    spec_rejected(
        &app,
        |s| s["sources"][1]["rate"] = json!(-0.1),
        "sources[1].rate",
    )
    .await;
    // So far that the statistics' distances would overflow (every plan's
    // values were NaN, sent as null).
    spec_rejected(
        &app,
        |s| s["sources"][0]["x"] = json!(-1.7e308),
        "sources[0].x",
    )
    .await;
    spec_rejected(&app, |s| s["sources"][1]["y"] = json!(2e12), "sources[1].y").await;
    // At the limit, the values are numbers.
    let mut far = small_spec();
    far["sources"][0]["x"] = json!(-1e12);
    let body = json!({"scenario": far, "sensors": [{"id": "a", "x": 15.0, "y": 45.0}]});
    let res = app.post_json("/v1/plan", &body).await;
    assert_eq!(res.status(), reqwest::StatusCode::OK);
    let plan: Value = res.json().await.unwrap();
    assert!(plan["expected_detections"].is_f64(), "{plan}");
    spec_rejected(&app, |s| s["horizon"] = json!(0), "horizon").await;
    spec_rejected(&app, |s| s["horizon"] = json!(13), "horizon").await;
    spec_rejected(&app, |s| s["name"] = json!("n".repeat(201)), "name").await;
    spec_rejected(
        &app,
        |s| s["sources"] = json!(vec![json!({"x": -1.0, "y": 50.0, "rate": 0.1}); 65]),
        "sources",
    )
    .await;
    // 2001 × 2000 = 4 002 000 cells.
    spec_rejected(
        &app,
        |s| {
            s["zone"] = json!({"width": 2001.0, "height": 2000.0});
            s["cell_size"] = json!(1.0);
        },
        "cell_size",
    )
    .await;
    spec_rejected(
        &app,
        |s| {
            s["zone"] = json!({"width": 5e6, "height": 1.0});
            s["cell_size"] = json!(1.0);
        },
        "zone.width",
    )
    .await;
    spec_rejected(&app, |s| s["cell_size"] = json!(1e-300), "zone.width").await;
    // Bounds are inclusive: 64 sources and horizon 12 are fine.
    let mut spec = small_spec();
    spec["sources"] = json!(vec![json!({"x": -1.0, "y": 50.0, "rate": 0.1}); 64]);
    spec["horizon"] = json!(12);
    let res = app.post_json("/v1/scenarios", &spec).await;
    assert_eq!(res.status(), StatusCode::CREATED);
    // Nothing invalid was registered: the built-ins and that one.
    let list: Value = app.get("/v1/scenarios").await.json().await.unwrap();
    assert_eq!(
        list["scenarios"].as_array().unwrap().len(),
        vigil::scenario::BUILTIN_IDS.len() + 1
    );
}

/// POSTs `plan_request()` changed by `edit` to paper-v10 and expects a 422
/// naming `field`.
async fn plan_rejected(app: &TestApp, edit: impl FnOnce(&mut Value), field: &str) {
    let mut req = plan_request();
    edit(&mut req);
    let res = app.plan(&req).await;
    assert_validation(res, field).await;
}

fn sensors(n: usize) -> Value {
    (0..n)
        .map(|i| json!({"id": i, "x": (i % 300) as f64, "y": (i / 300) as f64}))
        .collect()
}

fn positions(n: usize) -> Value {
    (0..n)
        .map(|i| json!({"x": (i % 300) as f64, "y": 1.0}))
        .collect()
}

#[tokio::test]
async fn invalid_plan_requests_are_422() {
    let app = spawn_app().await;
    plan_rejected(&app, |r| r["sensors"][1]["x"] = json!(300.5), "sensors[1]").await;
    plan_rejected(&app, |r| r["sensors"][2]["y"] = json!(-0.1), "sensors[2]").await;
    plan_rejected(
        &app,
        |r| r["sensors"][2]["id"] = json!("a"),
        "sensors[2].id",
    )
    .await;
    plan_rejected(&app, |r| r["sensors"][2]["id"] = json!(7), "sensors[2].id").await;
    plan_rejected(&app, |r| r["sensors"] = json!([]), "sensors").await;
    plan_rejected(&app, |r| r["sensors"] = sensors(257), "sensors").await;
    plan_rejected(&app, |r| r["horizon"] = json!(0), "horizon").await;
    plan_rejected(&app, |r| r["horizon"] = json!(13), "horizon").await;
    // JSON has one number type: a fraction or a negative is no horizon.
    plan_rejected(&app, |r| r["horizon"] = json!(4.5), "horizon").await;
    plan_rejected(&app, |r| r["horizon"] = json!(-1), "horizon").await;
    plan_rejected(&app, |r| r["horizon"] = json!(1e30), "horizon").await;
    plan_rejected(
        &app,
        |r| {
            r["targets"] = json!(vec![
                json!({"x": 150.0, "y": 150.0, "vx": 1.0, "vy": 0.0});
                20_001
            ])
        },
        "targets",
    )
    .await;
    plan_rejected(
        &app,
        |r| r["history"] = json!(vec![positions(3); MAX_HISTORY_STEPS + 1]),
        "history",
    )
    .await;
    plan_rejected(
        &app,
        |r| r["history"] = json!([positions(3), positions(257)]),
        "history[1]",
    )
    .await;
    plan_rejected(
        &app,
        |r| r["history"] = json!([[{"x": 400.0, "y": 1.0}]]),
        "history[0][0]",
    )
    .await;
    // Bounds are inclusive: 32 history steps, 256 positions in one. (256
    // sensors are not planned here: that takes seconds.)
    let mut req = plan_request();
    let mut history = vec![positions(3); 32];
    history[0] = positions(256);
    req["history"] = json!(history);
    let res = app.plan(&req).await;
    assert_eq!(
        res.status(),
        StatusCode::OK,
        "{}",
        res.text().await.unwrap()
    );
}

/// `spec_rejected`, and the detail also states the bound.
async fn spec_rejected_saying(
    app: &TestApp,
    edit: impl FnOnce(&mut Value),
    field: &str,
    bound: &str,
) {
    let mut spec = small_spec();
    edit(&mut spec);
    let res = app.post_json("/v1/scenarios", &spec).await;
    let body = assert_problem(res, StatusCode::UNPROCESSABLE_ENTITY, field).await;
    let detail = body["detail"].as_str().unwrap();
    assert!(
        detail.starts_with(&format!("{field}: ")) && detail.contains(bound),
        "detail {detail:?} should name {field:?} and say {bound:?}"
    );
}

#[tokio::test]
async fn invalid_target_models_are_422() {
    let app = spawn_app().await;
    let class = |speed: f64, weight: f64| json!({"speed": speed, "weight": weight});
    spec_rejected_saying(
        &app,
        |s| s["sources"][0]["speeds"] = json!([class(5.0, 1.0), class(9.0, 0.0)]),
        "sources[0].speeds[1].weight",
        "> 0, got 0",
    )
    .await;
    spec_rejected_saying(
        &app,
        |s| s["sources"][1]["speeds"] = json!([class(5.0, -2.0)]),
        "sources[1].speeds[0].weight",
        "> 0, got -2",
    )
    .await;
    spec_rejected_saying(
        &app,
        |s| s["sources"][0]["speeds"] = json!([class(0.0, 1.0)]),
        "sources[0].speeds[0].speed",
        "> 0",
    )
    .await;
    spec_rejected_saying(
        &app,
        |s| s["sources"][0]["speeds"] = json!(vec![class(5.0, 1.0); 9]),
        "sources[0].speeds",
        "1 to 8 classes, got 9",
    )
    .await;
    spec_rejected_saying(
        &app,
        |s| s["sources"][0]["speeds"] = json!([]),
        "sources[0].speeds",
        "1 to 8 classes, got 0",
    )
    .await;
    for spread in [0.0, 200.0, -10.0] {
        spec_rejected_saying(
            &app,
            |s| s["sources"][0]["spread"] = json!(spread),
            "sources[0].spread",
            "(0, 180]",
        )
        .await;
    }
    // Aimed away from the zone, and past its corner.
    for (i, direction, spread) in [(0, 180.0, 30.0), (1, 30.0, 10.0)] {
        spec_rejected_saying(
            &app,
            |s| {
                s["sources"][i]["direction"] = json!(direction);
                s["sources"][i]["spread"] = json!(spread);
            },
            &format!("sources[{i}]"),
            "enters the zone",
        )
        .await;
    }
    // A narrow cone around a heading that misses the zone.
    spec_rejected_saying(
        &app,
        |s| {
            s["sources"][0] =
                json!({"x": -1.0, "y": -40.0, "rate": 1.0, "heading": "east", "spread": 20.0})
        },
        "sources[0]",
        "enters the zone",
    )
    .await;
    spec_rejected_saying(
        &app,
        |s| {
            s.as_object_mut().unwrap().remove("target_speed");
            s["sources"][0]["speeds"] = json!([class(4.0, 1.0)]);
        },
        "target_speed",
        "sources[1] gives no speeds",
    )
    .await;
    spec_rejected_saying(
        &app,
        |s| s["sources"] = json!([]),
        "sources",
        "at least one source",
    )
    .await;
    // Every source with speeds: no target_speed needed.
    let mut spec = small_spec();
    spec.as_object_mut().unwrap().remove("target_speed");
    spec["sources"][0]["speeds"] = json!([class(4.0, 1.0), class(12.0, 3.0)]);
    spec["sources"][1]["speeds"] = json!([class(2.0, 1.0)]);
    let res = app.post_json("/v1/scenarios", &spec).await;
    assert_eq!(res.status(), StatusCode::CREATED);
}

/// An integral float is the integer it equals, for every integer field
/// (JSON Schema's `integer` says the same): `4.0` is horizon 4.
#[tokio::test]
async fn integral_floats_are_integers() {
    let app = spawn_app().await;
    let mut req = plan_request();
    req["horizon"] = json!(4.0);
    let res = app.plan(&req).await;
    assert_eq!(res.status(), StatusCode::OK);
    let body: Value = res.json().await.unwrap();
    assert_eq!(body["horizon"], 4);
    assert_eq!(body["plans"][0]["path"].as_array().unwrap().len(), 4);
    let mut spec = small_spec();
    spec["horizon"] = json!(5.0);
    let res = app.post_json("/v1/scenarios", &spec).await;
    assert_eq!(res.status(), StatusCode::CREATED);
    let body: Value = res.json().await.unwrap();
    // The canonical spec holds the integer, so `5.0` and `5` are one scenario.
    assert_eq!(body["spec"]["horizon"], 5);
    spec["horizon"] = json!(5);
    let again = app.post_json("/v1/scenarios", &spec).await;
    assert_eq!(again.status(), StatusCode::OK);
    spec["horizon"] = json!(5.5);
    spec_rejected_saying(
        &app,
        |s| *s = spec.clone(),
        "horizon",
        "integer in 1..=12, got 5.5",
    )
    .await;
}

/// Speeds so slow, or rates so high, that the statistics would overflow are
/// refused: found by the OpenAPI fuzzer (`target_speed` 5e-324 gave `null`
/// statistics).
#[tokio::test]
async fn overflowing_target_models_are_422() {
    let app = spawn_app().await;
    spec_rejected_saying(
        &app,
        |s| s["target_speed"] = json!(5e-324),
        "sources",
        "too many targets",
    )
    .await;
    spec_rejected_saying(
        &app,
        |s| s["sources"][0]["rate"] = json!(1e300),
        "sources",
        "at most 1e9",
    )
    .await;
    spec_rejected_saying(
        &app,
        |s| s["sources"][1]["speeds"] = json!([{"speed": 1e-300, "weight": 1.0}]),
        "sources",
        "too many targets",
    )
    .await;
}

/// A body's fields read apart from it (`/v1/plan`'s and `/v1/evaluate`'s
/// request besides its scenario, a session's settings, evaluate's paths)
/// name the failing field's path, as a whole body's do.
#[tokio::test]
async fn type_errors_in_split_bodies_name_the_field() {
    let app = spawn_app().await;
    let sensor = json!([{"id": "a", "x": "75", "y": 75}]);
    let cases = [
        (
            "/v1/plan",
            json!({"scenario_id": "paper-v10", "sensors": sensor}),
            "sensors[0].x: invalid type",
        ),
        (
            "/v1/sessions",
            json!({"scenario_id": "paper-v10", "horizon": "3"}),
            "horizon: invalid type",
        ),
        (
            "/v1/evaluate",
            json!({"scenario_id": "paper-v10", "sensors": [{"id": "a", "x": 75, "y": 75}],
                "paths": [{"sensor": "a", "path": [{"col": "6", "row": 7}]}]}),
            "paths[0].path[0].col: invalid type",
        ),
    ];
    for (url, body, says) in cases {
        assert_problem(
            app.post_json(url, &body).await,
            reqwest::StatusCode::BAD_REQUEST,
            says,
        )
        .await;
    }
}
