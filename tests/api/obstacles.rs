//! Buildings and screens over HTTP: specs with obstacles register, plan,
//! evaluate and step sessions; every malformed obstacle, every sensor on a
//! building's cell and the paper estimator get a 422 naming the field.

use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::helpers::{
    TestApp, assert_problem, assert_validation, json_body, small_spec, spawn_app,
};

/// `small_spec` with a building in the middle (cells (4..=5, 4..=5) have
/// their centres in it), a screen in the south-west, a ground type
/// `default` and an elevated `drone`.
fn campus_spec() -> Value {
    let mut spec = small_spec();
    spec["p_detect"] = json!(0.9);
    spec["sensor_types"] = json!({
        "drone": {"fov": {"shape": "square", "half_width": 25.0}, "speed": 2,
                  "p_detect": 0.6, "elevated": true}
    });
    spec["obstacles"] = json!([
        {"polygon": [[40.0, 40.0], [60.0, 40.0], [60.0, 60.0], [40.0, 60.0]], "kind": "building"},
        {"polygon": [[10.0, 10.0], [30.0, 12.0], [20.0, 30.0]], "kind": "screen"}
    ]);
    spec
}

async fn register(app: &TestApp, spec: &Value) -> String {
    let res = app.post_json("/v1/scenarios", spec).await;
    let status = res.status();
    assert!(
        status == StatusCode::CREATED || status == StatusCode::OK,
        "{status}: {}",
        res.text().await.unwrap()
    );
    json_body(res, status).await["id"]
        .as_str()
        .unwrap()
        .to_owned()
}

fn request(sensors: Value) -> Value {
    json!({"sensors": sensors, "targets": [{"x": 25.0, "y": 75.0, "vx": 5.0, "vy": 0.0}],
           "history": [[{"x": 15.0, "y": 55.0}, {"x": 45.0, "y": 65.0, "type": "drone"}]]})
}

fn two_sensors() -> Value {
    json!([{"id": "cam", "x": 25.0, "y": 55.0},
           {"id": "uav", "x": 55.0, "y": 65.0, "type": "drone"}])
}

#[tokio::test]
async fn a_spec_with_obstacles_registers_plans_evaluates_and_steps() {
    let app = spawn_app().await;
    // An empty list is no obstacles: the plain spec's id.
    let plain = register(&app, &small_spec()).await;
    let mut empty = small_spec();
    empty["obstacles"] = json!([]);
    assert_eq!(register(&app, &empty).await, plain);

    let id = register(&app, &campus_spec()).await;
    let got = json_body(
        app.get(&format!("/v1/scenarios/{id}")).await,
        StatusCode::OK,
    )
    .await;
    // Canonical: a building's kind is the default and dropped.
    assert_eq!(got["spec"]["obstacles"][0].get("kind"), None);
    assert_eq!(got["spec"]["obstacles"][1]["kind"], "screen");
    assert_eq!(got["spec"]["sensor_types"]["drone"]["elevated"], true);

    // Statistics list the obstacles; a ground camera next to the building
    // sees less than the same square from above.
    let stats = |ty: &'static str| {
        let app = &app;
        let id = id.clone();
        async move {
            json_body(
                app.get(&format!("/v1/scenarios/{id}/stats?type={ty}"))
                    .await,
                StatusCode::OK,
            )
            .await
        }
    };
    let (ground, drone) = (stats("default").await, stats("drone").await);
    assert_eq!(ground["obstacles"].as_array().unwrap().len(), 2);
    let cell = 5 * 10 + 3; // (col 3, row 5), just west of the building
    assert!(ground["d_hat"][cell].as_f64().unwrap() > 0.0);
    let plain_stats = json_body(
        app.get(&format!("/v1/scenarios/{plain}/stats")).await,
        StatusCode::OK,
    )
    .await;
    assert!(plain_stats.get("obstacles").is_none());
    assert!(
        ground["d_hat"][cell].as_f64().unwrap() < plain_stats["d_hat"][cell].as_f64().unwrap(),
        "the building hides part of the camera's view"
    );
    assert!(drone["d_hat"][cell].as_f64().unwrap() > ground["d_hat"][cell].as_f64().unwrap());

    // Plans: exact, both objectives, every coordination, with a bound.
    for objective in ["detections", "first_detections"] {
        for coordination in ["none", "priority", "iterated", "joint"] {
            let mut body = request(two_sensors());
            body["objective"] = json!(objective);
            body["coordination"] = json!(coordination);
            body["explain"] = json!(true);
            let plan = json_body(
                app.post_json(&format!("/v1/scenarios/{id}/plan"), &body)
                    .await,
                StatusCode::OK,
            )
            .await;
            let value = plan["expected_detections"].as_f64().unwrap();
            assert!(value > 0.0, "{plan}");
            assert!(plan["bound"]["upper"].as_f64().unwrap() >= value - 1e-9);
            // The camera never stands on the building's cells.
            for c in plan["plans"][0]["path"].as_array().unwrap() {
                let (col, row) = (c["col"].as_i64().unwrap(), c["row"].as_i64().unwrap());
                assert!(!((4..=5).contains(&col) && (4..=5).contains(&row)), "{c}");
            }
            // Evaluate scores the plan's own paths at its value.
            let mut eval = request(two_sensors());
            eval["objective"] = json!(objective);
            eval["paths"] = crate::helpers::paths_of(&plan);
            let scored = json_body(
                app.post_json(&format!("/v1/scenarios/{id}/evaluate"), &eval)
                    .await,
                StatusCode::OK,
            )
            .await;
            let total = scored["expected_detections"].as_f64().unwrap();
            assert!(
                (total - value).abs() <= 1e-9 * value.max(1.0),
                "{total} vs {value}"
            );
        }
    }

    // Sessions: created, stepped; a step plans as the stateless request.
    let res = app
        .post_json(
            "/v1/sessions",
            &json!({"scenario_id": id, "history_steps": 4}),
        )
        .await;
    let info = json_body(res, StatusCode::CREATED).await;
    let sid = info["id"].as_str().unwrap();
    let step = json_body(
        app.post_json(
            &format!("/v1/sessions/{sid}/step"),
            &json!({"sensors": two_sensors()}),
        )
        .await,
        StatusCode::OK,
    )
    .await;
    let stateless = json_body(
        app.post_json(
            &format!("/v1/scenarios/{id}/plan"),
            &json!({"sensors": two_sensors()}),
        )
        .await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(step["plans"], stateless["plans"]);

    // The paper estimator has no sight lines: refused, in plans and
    // sessions alike.
    let mut paper = request(two_sensors());
    paper["estimator"] = json!("paper");
    assert_validation(
        app.post_json(&format!("/v1/scenarios/{id}/plan"), &paper)
            .await,
        "estimator",
    )
    .await;
    assert_validation(
        app.post_json(
            "/v1/sessions",
            &json!({"scenario_id": id, "estimator": "paper"}),
        )
        .await,
        "estimator",
    )
    .await;
}

#[tokio::test]
async fn ground_sensors_keep_off_buildings_and_drones_fly_over() {
    let app = spawn_app().await;
    let id = register(&app, &campus_spec()).await;
    let plan = |body: Value| {
        let app = &app;
        let id = id.clone();
        async move {
            app.post_json(&format!("/v1/scenarios/{id}/plan"), &body)
                .await
        }
    };
    // A camera on the building's cell (4, 4), now and in the history.
    assert_validation(
        plan(json!({"sensors": [{"id": 1, "x": 45.0, "y": 45.0}]})).await,
        "sensors[0]",
    )
    .await;
    assert_validation(
        plan(json!({"sensors": [{"id": 1, "x": 25.0, "y": 25.0}],
                    "history": [[{"x": 55.0, "y": 55.0}]]}))
        .await,
        "history[0][0]",
    )
    .await;
    // A drone may stand there.
    json_body(
        plan(json!({"sensors": [{"id": 1, "x": 45.0, "y": 45.0, "type": "drone"}]})).await,
        StatusCode::OK,
    )
    .await;
    // A camera inside the screen plans (it sees nothing from there).
    let blind = json_body(
        plan(json!({"sensors": [{"id": 1, "x": 25.0, "y": 15.0}], "horizon": 1})).await,
        StatusCode::OK,
    )
    .await;
    assert!(blind["expected_detections"].as_f64().unwrap() >= 0.0);
    // Evaluate refuses a camera's path through the building.
    let body = json!({"sensors": [{"id": 1, "x": 35.0, "y": 45.0}], "horizon": 2,
        "paths": [{"sensor": 1, "path": [{"col": 4, "row": 4}, {"col": 5, "row": 4}]}]});
    assert_validation(
        app.post_json(&format!("/v1/scenarios/{id}/evaluate"), &body)
            .await,
        "paths[0].path[0]",
    )
    .await;
}

#[tokio::test]
async fn malformed_obstacles_are_refused_naming_the_field() {
    let app = spawn_app().await;
    let with = |obstacles: Value| {
        let mut spec = small_spec();
        spec["obstacles"] = obstacles;
        spec
    };
    let square = json!([[40.0, 40.0], [60.0, 40.0], [60.0, 60.0], [40.0, 60.0]]);
    let cases: Vec<(Value, &str)> = vec![
        // Non-convex: a dart.
        (
            with(json!([{"polygon": square},
                {"polygon": [[0.0, 0.0], [20.0, 0.0], [10.0, 5.0], [20.0, 20.0], [0.0, 20.0]]}])),
            "obstacles[1].polygon",
        ),
        // Three collinear vertices.
        (
            with(json!([{"polygon": [[0.0, 0.0], [10.0, 0.0], [20.0, 0.0], [10.0, 10.0]]}])),
            "obstacles[0].polygon",
        ),
        // A repeated vertex.
        (
            with(json!([{"polygon": [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 0.0]]}])),
            "obstacles[0].polygon",
        ),
        // A pentagram: convex turns, but it crosses itself.
        (
            with(
                json!([{"polygon": [[50.0, 90.0], [73.5, 17.6], [11.9, 62.4], [88.1, 62.4], [26.5, 17.6]]}]),
            ),
            "obstacles[0].polygon",
        ),
        // Too few and too many vertices.
        (
            with(json!([{"polygon": [[0.0, 0.0], [10.0, 0.0]]}])),
            "obstacles[0].polygon",
        ),
        (
            with(json!([{"polygon": (0..33).map(|i| {
                let a = f64::from(i) * std::f64::consts::TAU / 33.0;
                json!([50.0 + 20.0 * a.cos(), 50.0 + 20.0 * a.sin()])
            }).collect::<Vec<_>>()}])),
            "obstacles[0].polygon",
        ),
        // Wholly outside the zone.
        (
            with(json!([{"polygon": [[110.0, 10.0], [130.0, 10.0], [120.0, 30.0]]}])),
            "obstacles[0].polygon",
        ),
        // Coordinates past the limit (where a cross product of 1e200
        // overflows).
        (
            with(json!([{"polygon": [[40.0, 40.0], [60.0, 40.0], [60.0, 2e9]]}])),
            "obstacles[0].polygon",
        ),
        (
            with(
                json!([{"polygon": [[-1e200, -1e200], [1e200, -1e200], [1e200, 1e200], [-1e200, 1e200]]}]),
            ),
            "obstacles[0].polygon",
        ),
        // An unknown kind.
        (
            with(json!([{"polygon": square}, {"polygon": square, "kind": "wall"}])),
            "obstacles[1].kind",
        ),
        // More than 64.
        (
            with(Value::Array(vec![json!({"polygon": square}); 65])),
            "obstacles",
        ),
        // A source inside a building (one that crosses the zone's edge).
        (
            with(json!([{"polygon": [[-10.0, 40.0], [10.0, 40.0], [10.0, 60.0], [-10.0, 60.0]]}])),
            "sources[0]",
        ),
        // A cone whose every ray meets a building before the zone.
        (
            with(
                json!([{"polygon": [[-50.0, 90.0], [150.0, 90.0], [150.0, 100.5], [-50.0, 100.5]]}]),
            ),
            "sources[1]",
        ),
    ];
    for (spec, field) in cases {
        assert_validation(app.post_json("/v1/scenarios", &spec).await, field).await;
    }
    // A polygon across the zone's edge is valid.
    let across =
        with(json!([{"polygon": [[90.0, 10.0], [120.0, 10.0], [120.0, 30.0], [90.0, 30.0]]}]));
    register(&app, &across).await;
    // A source whose cone enters the zone only through a gap of 1e-3
    // radians between two buildings (no ray of a grid of 2048 per π goes
    // through it) is valid; with the gap closed it is not.
    let gap = |upper: f64| {
        json!({"zone": {"width": 200, "height": 100}, "cell_size": 10,
            "fov": {"shape": "square", "half_width": 25}, "target_speed": 5,
            "sources": [{"x": -1, "y": 50, "rate": 0.4}],
            "obstacles": [
                {"polygon": [[-0.5, -50], [5, -50], [5, 49.997], [-0.5, 49.99975]]},
                {"polygon": [[-0.5, 150], [-0.5, upper], [5, upper + 0.00275], [5, 150]]}]})
    };
    register(&app, &gap(50.00025)).await;
    assert_validation(
        app.post_json("/v1/scenarios", &gap(49.9)).await,
        "sources[0]",
    )
    .await;
    // So is one that reaches as far as the limit; it takes in no cell
    // centre beyond its edges (the one at x = 55 is half a unit out).
    let far = with(json!([{"polygon": [[44.0, -1e9], [54.5, -1e9], [54.5, 25.0], [44.0, 25.0]]}]));
    let id = register(&app, &far).await;
    for (x, status) in [
        (55.0, StatusCode::OK),
        (45.0, StatusCode::UNPROCESSABLE_ENTITY),
    ] {
        let body = json!({"sensors": [{"id": 1, "x": x, "y": 15.0}], "horizon": 1});
        let res = app
            .post_json(&format!("/v1/scenarios/{id}/plan"), &body)
            .await;
        assert_eq!(
            res.status(),
            status,
            "x = {x}: {}",
            res.text().await.unwrap()
        );
    }
    // Non-numeric vertices, and vertices of other than two numbers, are a
    // 400 that names the vertex (not JSON that fails to parse).
    for (vertex, says) in [
        (json!(["a", 0.0]), "invalid type"),
        (
            json!([1.0, 2.0, 3.0]),
            "invalid length 3, expected a vertex [x, y]",
        ),
        (json!([1.0]), "invalid length 1, expected a vertex [x, y]"),
    ] {
        let polygon = json!([vertex, [60.0, 40.0], [60.0, 60.0]]);
        let res = app
            .post_json("/v1/scenarios", &with(json!([{"polygon": polygon}])))
            .await;
        let problem = assert_problem(res, StatusCode::BAD_REQUEST, "obstacles[0].polygon[0]").await;
        let detail = problem["detail"].as_str().unwrap();
        assert!(detail.contains(says), "{detail}");
        assert!(
            !detail.contains("parse the request body as JSON"),
            "{detail}"
        );
    }
    // Inline, the same defects name the field under `scenario.`.
    for (obstacle, field) in [
        (
            json!({"polygon": square, "kind": 3}),
            "scenario.obstacles[1].kind: invalid type",
        ),
        (
            json!({"polygon": square, "height": 3}),
            "scenario.obstacles[1].height: unknown field",
        ),
        (
            json!({"polygon": [[1.0, 2.0, 3.0]]}),
            "scenario.obstacles[1].polygon[0]: invalid length",
        ),
    ] {
        let scenario = with(json!([{"polygon": square}, obstacle]));
        let body = json!({"scenario": scenario, "sensors": [{"id": 1, "x": 15.0, "y": 15.0}]});
        for path in ["/v1/plan", "/v1/evaluate"] {
            let mut body = body.clone();
            if path == "/v1/evaluate" {
                body["paths"] = json!([]);
            }
            assert_problem(
                app.post_json(path, &body).await,
                StatusCode::BAD_REQUEST,
                field,
            )
            .await;
        }
    }
}

/// The built-in campus plans for a fleet of robots and drones.
#[tokio::test]
async fn site_campus_plans_a_mixed_fleet() {
    let app = spawn_app().await;
    let body = json!({
        "sensors": [
            {"id": "r1", "x": 45.0, "y": 145.0, "type": "robot"},
            {"id": "r2", "x": 265.0, "y": 145.0, "type": "robot"},
            {"id": "d1", "x": 215.0, "y": 95.0, "type": "drone"}
        ],
        "coordination": "iterated"
    });
    let plan = json_body(
        app.post_json("/v1/scenarios/site-campus/plan", &body).await,
        StatusCode::OK,
    )
    .await;
    assert!(plan["expected_detections"].as_f64().unwrap() > 0.0);
    // The drone over the office block is fine; a robot there is not.
    let mut robot_on_office = body.clone();
    robot_on_office["sensors"][2]["type"] = json!("robot");
    assert_validation(
        app.post_json("/v1/scenarios/site-campus/plan", &robot_on_office)
            .await,
        "sensors[2]",
    )
    .await;
}

/// `fit` takes a detection only from a look that could have made it: a
/// ground camera's view behind a building detects nothing there, a
/// drone's over it does.
#[tokio::test]
async fn fit_refuses_a_detection_behind_a_building() {
    let app = spawn_app().await;
    let spec = json!({
        "zone": {"width": 200, "height": 100}, "cell_size": 10,
        "fov": {"shape": "square", "half_width": 25}, "p_detect": 0.9, "target_speed": 5,
        "sensor_types": {"drone": {"fov": {"shape": "square", "half_width": 25}, "elevated": true}},
        "obstacles": [{"polygon": [[80, 30], [120, 30], [120, 70], [80, 70]]}],
        "sources": [{"x": -1, "y": 50, "rate": 0.4}, {"x": 201, "y": 50, "rate": 0.4}]});
    let id = register(&app, &spec).await;
    let url = format!("/v1/scenarios/{id}/fit");
    let window = |sensor: Value, x: f64| {
        json!({"steps": [{"sensors": [sensor],
            "detections": [{"id": 1, "x": x, "y": 25.0, "vx": 4.8, "vy": -1.3}]}]})
    };
    let camera = json!({"id": "a", "x": 75.0, "y": 45.0});
    let drone = json!({"id": "a", "x": 75.0, "y": 45.0, "type": "drone"});
    // The sight line from (75, 45) to (95, 25) crosses the building.
    assert_validation(
        app.post_json(&url, &window(camera.clone(), 95.0)).await,
        "steps[0].detections[0]",
    )
    .await;
    for (sensor, x) in [(camera, 60.0), (drone, 95.0)] {
        let res = app.post_json(&url, &window(sensor, x)).await;
        assert_eq!(
            res.status(),
            StatusCode::OK,
            "{}",
            res.text().await.unwrap()
        );
    }
}
