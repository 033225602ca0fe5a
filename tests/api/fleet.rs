//! Fleets over HTTP: sensor types and no-go zones in specs and requests,
//! per-type statistics, every new 422, and random requests on `site-fleet`
//! whose paths must respect speeds and blocked cells.

use std::collections::HashSet;

use proptest::prelude::*;
use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::helpers::{assert_problem, assert_validation, json_body, small_spec, spawn_app};

/// `small_spec` with a drone type and a no-go square in the middle
/// (cells (4,4), (4,5), (5,4), (5,5) of the 10×10 lattice).
fn fleet_spec() -> Value {
    let mut spec = small_spec();
    spec["sensor_types"] = json!({
        "drone": {"fov": {"shape": "square", "half_width": 25.0}, "speed": 3, "p_detect": 0.6}
    });
    spec["p_detect"] = json!(0.9);
    spec["no_go"] = json!([{"x0": 40.0, "y0": 40.0, "x1": 60.0, "y1": 60.0}]);
    spec
}

async fn register(app: &crate::helpers::TestApp, spec: &Value) -> String {
    let res = app.post_json("/v1/scenarios", spec).await;
    let status = res.status();
    assert!(status == StatusCode::CREATED || status == StatusCode::OK);
    json_body(res, status).await["id"]
        .as_str()
        .unwrap()
        .to_owned()
}

#[tokio::test]
async fn fleet_specs_register_plan_and_keep_old_ids() {
    let app = spawn_app().await;
    // A spec that spells out every default has the id of the plain one.
    let plain = register(&app, &small_spec()).await;
    let mut explicit = small_spec();
    explicit["sensor_speed"] = json!(1);
    explicit["p_detect"] = json!(1.0);
    explicit["sensor_types"] = json!({});
    explicit["no_go"] = json!([]);
    assert_eq!(register(&app, &explicit).await, plain);

    let id = register(&app, &fleet_spec()).await;
    assert_ne!(id, plain);
    let got = json_body(
        app.get(&format!("/v1/scenarios/{id}")).await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(got["spec"]["sensor_types"]["drone"]["speed"], json!(3));
    assert_eq!(got["spec"]["no_go"][0]["x1"], json!(60.0));

    // Statistics per type: the drone's wider view holds more targets.
    let default = json_body(
        app.get(&format!("/v1/scenarios/{id}/stats")).await,
        StatusCode::OK,
    )
    .await;
    let drone = json_body(
        app.get(&format!("/v1/scenarios/{id}/stats?type=drone"))
            .await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(default["type"], json!("default"));
    assert_eq!(drone["type"], json!("drone"));
    let sum = |v: &Value| -> f64 {
        v["d_hat"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .sum()
    };
    assert!(sum(&drone) > sum(&default));
    assert_problem(
        app.get(&format!("/v1/scenarios/{id}/stats?type=tank"))
            .await,
        StatusCode::NOT_FOUND,
        "tank",
    )
    .await;
    assert_problem(
        app.get(&format!("/v1/scenarios/{id}/stats?colour=red"))
            .await,
        StatusCode::BAD_REQUEST,
        "colour",
    )
    .await;

    // A drone at (15, 45) beside the no-go square; explain has side 2·3·T+1.
    let body = json!({
        "sensors": [
            {"id": "d", "x": 35.0, "y": 45.0, "type": "drone"},
            {"id": "r", "x": 85.0, "y": 85.0}
        ],
        "history": [[{"x": 35.0, "y": 35.0, "type": "drone"}, {"x": 85.0, "y": 75.0}]],
        "horizon": 2,
        "explain": true
    });
    let plan = json_body(
        app.post_json(&format!("/v1/scenarios/{id}/plan"), &body)
            .await,
        StatusCode::OK,
    )
    .await;
    let values = plan["plans"][0]["explain"]["values"].as_array().unwrap();
    assert_eq!(values.len(), 2);
    assert_eq!(values[0].as_array().unwrap().len(), 2 * 3 * 2 + 1);
    // The blocked cell (4,4) is offset (+1, 0) from the drone's (3,4):
    // null at every step, as is anything off the lattice.
    for step in values {
        let row = step[3 * 2].as_array().unwrap(); // dr = 0: m·T = 6
        assert_eq!(row[2 * 3 + 1], Value::Null);
    }
    for plan in plan["plans"].as_array().unwrap() {
        for c in plan["path"].as_array().unwrap() {
            let (col, row) = (c["col"].as_i64().unwrap(), c["row"].as_i64().unwrap());
            assert!(!((4..=5).contains(&col) && (4..=5).contains(&row)));
        }
    }
}

#[tokio::test]
async fn fleet_fields_out_of_bounds_are_422_naming_the_field() {
    let app = spawn_app().await;
    let with = |f: &dyn Fn(&mut Value)| {
        let mut s = fleet_spec();
        f(&mut s);
        s
    };
    let cases: Vec<(Value, &str)> = vec![
        (
            with(&|s| s["sensor_types"]["drone"]["speed"] = json!(4)),
            "sensor_types.drone.speed",
        ),
        (
            with(&|s| s["sensor_types"]["drone"]["speed"] = json!(0)),
            "sensor_types.drone.speed",
        ),
        (
            with(&|s| s["sensor_types"]["drone"]["speed"] = json!(1.5)),
            "sensor_types.drone.speed",
        ),
        (
            with(&|s| s["sensor_types"]["drone"]["p_detect"] = json!(0.0)),
            "sensor_types.drone.p_detect",
        ),
        (
            with(&|s| s["sensor_types"]["drone"]["p_detect"] = json!(1.01)),
            "sensor_types.drone.p_detect",
        ),
        (
            with(&|s| {
                s["sensor_types"]["drone"]["fov"] = json!({"shape": "circle", "radius": -1.0})
            }),
            "sensor_types.drone.fov.radius",
        ),
        (
            with(&|s| {
                s["sensor_types"]["bad name!"] =
                    json!({"fov": {"shape": "square", "half_width": 5.0}})
            }),
            "sensor_types",
        ),
        (
            with(&|s| {
                s["sensor_types"]["default"] =
                    json!({"fov": {"shape": "square", "half_width": 5.0}})
            }),
            "sensor_types.default",
        ),
        (
            with(&|s| {
                for i in 0..9 {
                    s["sensor_types"][format!("t{i}")] =
                        json!({"fov": {"shape": "square", "half_width": 5.0}});
                }
            }),
            "sensor_types",
        ),
        (with(&|s| s["sensor_speed"] = json!(7)), "sensor_speed"),
        (with(&|s| s["p_detect"] = json!(-0.5)), "p_detect"),
        (
            with(&|s| s["no_go"] = json!([{"x0": 50.0, "y0": 0.0, "x1": 50.0, "y1": 10.0}])),
            "no_go[0]",
        ),
        (
            with(&|s| s["no_go"] = json!([{"x0": 0.0, "y0": 20.0, "x1": 50.0, "y1": 10.0}])),
            "no_go[0]",
        ),
        (
            with(&|s| {
                s["no_go"] = json!(vec![
                    json!({"x0": 0.0, "y0": 0.0, "x1": 1.0, "y1": 1.0});
                    257
                ])
            }),
            "no_go",
        ),
    ];
    for (spec, field) in cases {
        assert_validation(app.post_json("/v1/scenarios", &spec).await, field).await;
        // Inline, the field is under `scenario.`.
        let body = json!({"scenario": spec, "sensors": [{"id": 1, "x": 5.0, "y": 5.0}]});
        assert_validation(
            app.post_json("/v1/plan", &body).await,
            &format!("scenario.{field}"),
        )
        .await;
    }

    let id = register(&app, &fleet_spec()).await;
    let path = format!("/v1/scenarios/{id}/plan");
    let plan_with =
        |sensors: Value, history: Value| json!({"sensors": sensors, "history": history});
    let ok = json!({"id": 1, "x": 5.0, "y": 5.0});
    let cases: Vec<(Value, &str)> = vec![
        (
            plan_with(
                json!([{"id": 1, "x": 5.0, "y": 5.0, "type": "tank"}]),
                json!([]),
            ),
            "sensors[0].type",
        ),
        (
            plan_with(json!([ok, {"id": 2, "x": 45.0, "y": 45.0}]), json!([])),
            "sensors[1]",
        ),
        (
            plan_with(
                json!([ok, {"id": 2, "x": 55.0, "y": 55.0, "type": "drone"}]),
                json!([]),
            ),
            "sensors[1]",
        ),
        (
            plan_with(json!([ok]), json!([[{"x": 5.0, "y": 5.0, "type": "boat"}]])),
            "history[0][0].type",
        ),
        (
            plan_with(
                json!([ok]),
                json!([[{"x": 5.0, "y": 5.0}], [{"x": 50.0, "y": 50.0}]]),
            ),
            "history[1][0]",
        ),
    ];
    for (body, field) in cases {
        assert_validation(app.post_json(&path, &body).await, field).await;
    }
    // On a built-in with no types, any type but `default` is unknown.
    let body = json!({"sensors": [{"id": 1, "x": 5.0, "y": 5.0, "type": "drone"}]});
    assert_validation(app.plan(&body).await, "sensors[0].type").await;
    let body = json!({"sensors": [{"id": 1, "x": 5.0, "y": 5.0, "type": "default"}]});
    json_body(app.plan(&body).await, StatusCode::OK).await;
}

/// The free cells of the built-in `site-fleet` and its types' speeds,
/// from the server itself.
async fn site_fleet(app: &crate::helpers::TestApp) -> (i64, i64, HashSet<(i64, i64)>) {
    let got = json_body(app.get("/v1/scenarios/site-fleet").await, StatusCode::OK).await;
    let (cols, rows) = (
        got["grid"]["cols"].as_i64().unwrap(),
        got["grid"]["rows"].as_i64().unwrap(),
    );
    let cell = got["spec"]["cell_size"].as_f64().unwrap();
    let rects: Vec<[f64; 4]> = got["spec"]["no_go"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| ["x0", "y0", "x1", "y1"].map(|k| r[k].as_f64().unwrap()))
        .collect();
    let mut blocked = HashSet::new();
    for col in 0..cols {
        for row in 0..rows {
            let (x, y) = ((col as f64 + 0.5) * cell, (row as f64 + 0.5) * cell);
            if rects
                .iter()
                .any(|r| x >= r[0] && x <= r[2] && y >= r[1] && y <= r[3])
            {
                blocked.insert((col, row));
            }
        }
    }
    assert!(!blocked.is_empty());
    (cols, rows, blocked)
}

/// Within `speed` king moves of `from` through cells on the lattice and
/// not blocked?
fn legal_step(
    (cols, rows, blocked): &(i64, i64, HashSet<(i64, i64)>),
    from: (i64, i64),
    to: (i64, i64),
    speed: usize,
) -> bool {
    let free =
        |c: (i64, i64)| c.0 >= 0 && c.1 >= 0 && c.0 < *cols && c.1 < *rows && !blocked.contains(&c);
    let mut seen = HashSet::from([from]);
    let mut frontier = vec![from];
    for _ in 0..speed {
        let mut next = Vec::new();
        for &(c, r) in &frontier {
            for dr in -1..=1 {
                for dc in -1..=1 {
                    let n = (c + dc, r + dr);
                    if free(n) && seen.insert(n) {
                        next.push(n);
                    }
                }
            }
        }
        frontier = next;
    }
    free(to) && seen.contains(&to)
}

#[test]
fn random_site_fleet_plans_respect_speeds_and_no_go_cells() {
    let rt = tokio::runtime::Runtime::new().unwrap();
    let app = rt.block_on(spawn_app());
    let lattice = rt.block_on(site_fleet(&app));
    let free: Vec<(i64, i64)> = (0..lattice.0)
        .flat_map(|c| (0..lattice.1).map(move |r| (c, r)))
        .filter(|c| !lattice.2.contains(c))
        .collect();
    let sensor = (0..free.len(), prop::bool::ANY);
    let config = ProptestConfig {
        cases: 24,
        failure_persistence: None,
        ..ProptestConfig::default()
    };
    proptest!(config, |(
        sensors in prop::collection::vec(sensor, 1..8),
        horizon in 1usize..=4,
        coordination in prop::sample::select(vec!["none", "priority", "iterated"]),
        estimator in prop::sample::select(vec!["exact", "paper"]),
    )| {
        let body = json!({
            "sensors": sensors.iter().enumerate().map(|(i, &(c, drone))| {
                let (col, row) = free[c];
                json!({"id": i, "x": col as f64 * 10.0 + 5.0, "y": row as f64 * 10.0 + 5.0,
                       "type": if drone { "drone" } else { "robot" }})
            }).collect::<Vec<_>>(),
            "horizon": horizon,
            "coordination": coordination,
            "estimator": estimator,
        });
        let plan = rt.block_on(async {
            json_body(app.post_json("/v1/scenarios/site-fleet/plan", &body).await, StatusCode::OK).await
        });
        for (p, &(c, drone)) in plan["plans"].as_array().unwrap().iter().zip(&sensors) {
            let speed = if drone { 3 } else { 1 };
            let mut at = free[c];
            for step in p["path"].as_array().unwrap() {
                let next = (step["col"].as_i64().unwrap(), step["row"].as_i64().unwrap());
                prop_assert!(legal_step(&lattice, at, next, speed), "{at:?} → {next:?} at speed {speed}");
                at = next;
            }
        }
    });
}
