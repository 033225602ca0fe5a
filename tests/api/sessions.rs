//! Sessions over HTTP: the lifecycle, a step equal to the stateless plan of
//! its state, a failed step that records nothing, and the bounds (idle time
//! to live, count) with their 404s.

use std::time::Duration;

use reqwest::{StatusCode, header};
use serde_json::{Value, json};
use vigil::http::config::Settings;
use vigil::limits::MAX_HISTORY_STEPS;

use crate::helpers::{
    TestApp, assert_problem, assert_validation, json_body, metric, spawn_app, spawn_with,
};

async fn open(app: &TestApp, body: &Value) -> (String, Value) {
    let res = app.post_json("/v1/sessions", body).await;
    let location = res
        .headers()
        .get(header::LOCATION)
        .map(|v| v.to_str().unwrap().to_owned());
    let info = json_body(res, StatusCode::CREATED).await;
    let id = info["id"].as_str().unwrap().to_owned();
    assert_eq!(
        location.as_deref(),
        Some(format!("/v1/sessions/{id}").as_str())
    );
    (id, info)
}

fn sensors(shift: f64) -> Value {
    json!([{"id": "a", "x": 55.0 + shift, "y": 55.0}, {"id": "b", "x": 245.0, "y": 60.0 + shift}])
}

#[tokio::test]
async fn a_session_records_steps_and_plans_as_the_stateless_request() {
    let app = spawn_app().await;
    let (id, info) = open(
        &app,
        &json!({"scenario_id": "paper-v10", "history_steps": 4}),
    )
    .await;
    assert_eq!(info["step"], 0);
    assert_eq!(info["scenario"], "paper-v10");
    assert_eq!(info["history_steps"], 4);
    assert_eq!(info["tracks"], json!([]));

    // Step 0: one target detected.
    let first = json!({"sensors": sensors(0.0),
        "detections": [{"id": 17, "x": 60.0, "y": 40.0, "vx": 10.0, "vy": 0.0}]});
    let res = app
        .post_json(&format!("/v1/sessions/{id}/step"), &first)
        .await;
    let step0 = json_body(res, StatusCode::OK).await;
    assert_eq!(step0["step"], 0);
    let stateless = app
        .plan(&json!({"sensors": sensors(0.0),
            "targets": [{"id": 17, "x": 60.0, "y": 40.0, "vx": 10.0, "vy": 0.0}]}))
        .await;
    let stateless = json_body(stateless, StatusCode::OK).await;
    assert_same_plans(&step0, &stateless);

    // Step 1: nothing detected; the track moved on, the history holds step 0.
    let second = json!({"sensors": sensors(10.0)});
    let res = app
        .post_json(&format!("/v1/sessions/{id}/step"), &second)
        .await;
    let step1 = json_body(res, StatusCode::OK).await;
    assert_eq!(step1["step"], 1);
    let stateless = app
        .plan(&json!({"sensors": sensors(10.0),
            "targets": [{"id": 17, "x": 70.0, "y": 40.0, "vx": 10.0, "vy": 0.0}],
            "history": [[{"x": 55.0, "y": 55.0}, {"x": 245.0, "y": 60.0}]]}))
        .await;
    let stateless = json_body(stateless, StatusCode::OK).await;
    assert_same_plans(&step1, &stateless);

    let info = json_body(app.get(&format!("/v1/sessions/{id}")).await, StatusCode::OK).await;
    assert_eq!(info["step"], 2);
    assert_eq!(info["history_held"], 2);
    assert_eq!(info["tracks"][0]["x"], 70.0);
    assert_eq!(info["tracks"][0]["last_detected"], 0);
    assert!(info["memory_bytes"].as_u64().unwrap() > 0);

    // Bad detections are named as such.
    let far = json!({"sensors": sensors(10.0),
        "detections": (0..20_001).map(|i| json!({"x": 1.0, "y": f64::from(i) * 0.01, "vx": 0.0, "vy": 0.0})).collect::<Vec<_>>()});
    let res = app
        .post_json(&format!("/v1/sessions/{id}/step"), &far)
        .await;
    assert_validation(res, "detections").await;

    // A step that fails records nothing: the step may be sent again.
    let outside = json!({"sensors": [{"id": "a", "x": 400.0, "y": 10.0}]});
    let res = app
        .post_json(&format!("/v1/sessions/{id}/step"), &outside)
        .await;
    assert_validation(res, "sensors[0]").await;
    let info = json_body(app.get(&format!("/v1/sessions/{id}")).await, StatusCode::OK).await;
    assert_eq!(info["step"], 2);
    assert_eq!(info["tracks"][0]["x"], 70.0);

    assert_eq!(
        app.delete(&format!("/v1/sessions/{id}")).await.status(),
        StatusCode::NO_CONTENT
    );
    let res = app.get(&format!("/v1/sessions/{id}")).await;
    assert_problem(res, StatusCode::NOT_FOUND, "POST /v1/sessions").await;
    let res = app
        .post_json(&format!("/v1/sessions/{id}/step"), &second)
        .await;
    assert_problem(res, StatusCode::NOT_FOUND, "create a new one").await;
}

#[tokio::test]
async fn a_session_takes_an_inline_scenario_and_refuses_bad_settings() {
    let app = spawn_app().await;
    let (_, info) = open(
        &app,
        &json!({"scenario": crate::helpers::small_spec(), "estimator": "paper"}),
    )
    .await;
    assert!(info["scenario"].as_str().unwrap().starts_with("s-"));
    assert_eq!(info["settings"]["estimator"], "paper");
    assert_eq!(info["history_steps"], 16);

    let res = app
        .post_json(
            "/v1/sessions",
            &json!({"scenario_id": "paper-v10", "history_steps": MAX_HISTORY_STEPS + 1}),
        )
        .await;
    assert_validation(res, "history_steps").await;
    let res = app
        .post_json(
            "/v1/sessions",
            &json!({"scenario_id": "paper-v10", "horizon": 13}),
        )
        .await;
    assert_validation(res, "horizon").await;
    let res = app
        .post_json("/v1/sessions", &json!({"history_steps": 4}))
        .await;
    assert_problem(res, StatusCode::UNPROCESSABLE_ENTITY, "exactly one of").await;
    let res = app
        .post_json("/v1/sessions", &json!({"scenario_id": "nope"}))
        .await;
    assert_problem(res, StatusCode::NOT_FOUND, "nope").await;
    let res = app
        .post_json(
            "/v1/sessions",
            &json!({"scenario_id": "paper-v10", "colour": "red"}),
        )
        .await;
    assert_problem(res, StatusCode::BAD_REQUEST, "colour").await;
}

#[tokio::test]
async fn sessions_are_bounded_by_count_and_idle_time() {
    let app = spawn_with(Settings {
        max_sessions: 2,
        session_ttl: Duration::from_millis(400),
        ..Settings::default()
    })
    .await;
    let body = json!({"scenario_id": "paper-v10"});
    let (first, _) = open(&app, &body).await;
    let (second, _) = open(&app, &body).await;
    // Using the first makes the second the least recently used.
    assert_eq!(
        app.get(&format!("/v1/sessions/{first}")).await.status(),
        StatusCode::OK
    );
    let (third, _) = open(&app, &body).await;
    assert_eq!(
        app.get(&format!("/v1/sessions/{second}")).await.status(),
        StatusCode::NOT_FOUND
    );
    assert_eq!(
        app.get(&format!("/v1/sessions/{first}")).await.status(),
        StatusCode::OK
    );
    assert_eq!(
        metric(
            &app.address,
            "vigil_sessions_evicted_total",
            &["reason=\"capacity\""]
        )
        .await,
        1.0
    );
    // Idle past the time to live: gone.
    tokio::time::sleep(Duration::from_millis(600)).await;
    let res = app.get(&format!("/v1/sessions/{third}")).await;
    assert_problem(res, StatusCode::NOT_FOUND, "idle").await;
    assert_eq!(
        metric(
            &app.address,
            "vigil_sessions_evicted_total",
            &["reason=\"idle\""]
        )
        .await,
        2.0
    );
}

#[tokio::test]
async fn a_step_retried_with_its_idempotency_key_is_answered_not_made_again() {
    let app = spawn_app().await;
    let (id, _) = open(&app, &json!({"scenario_id": "paper-v10"})).await;
    let path = format!("/v1/sessions/{id}/step");
    let step = |key: &str, shift: f64| {
        app.client
            .post(app.url(&path))
            .header("Idempotency-Key", key)
            .json(&json!({"sensors": sensors(shift),
                "detections": [{"x": 60.0 + shift, "y": 40.0, "vx": 10.0, "vy": 0.0}]}))
            .send()
    };
    let first = step("k-0", 0.0).await.unwrap();
    assert_eq!(first.status(), StatusCode::OK);
    let first = first.bytes().await.unwrap();
    // The retry gets the first answer, to the byte, and so does one whose
    // body has the same values laid out otherwise; the session did not
    // move.
    let again = step("k-0", 0.0).await.unwrap().bytes().await.unwrap();
    assert_eq!(again, first);
    let relaid = format!(
        "{{ \"detections\": [{{\"vy\": 0, \"vx\": 10.0, \"y\": 40, \"x\": 60.0}}],\n  \"sensors\": {} }}",
        sensors(0.0)
    );
    let again = app
        .client
        .post(app.url(&path))
        .header("Idempotency-Key", "k-0")
        .header("content-type", "application/json")
        .body(relaid)
        .send()
        .await
        .unwrap();
    assert_eq!(again.status(), StatusCode::OK);
    assert_eq!(again.bytes().await.unwrap(), first);
    // The same key with another body is a new step under an old key:
    // refused, not answered with the old step's answer (which would drop
    // this step's detections), and the session did not move.
    let res = step("k-0", 5.0).await.unwrap();
    assert_problem(
        res,
        StatusCode::UNPROCESSABLE_ENTITY,
        "Idempotency-Key: `k-0`",
    )
    .await;
    let info = json_body(app.get(&format!("/v1/sessions/{id}")).await, StatusCode::OK).await;
    assert_eq!(info["step"], 1);
    assert_eq!(info["tracks"].as_array().unwrap().len(), 1);
    // A new key is a new step; without a key, every request is one.
    let second: Value = step("k-1", 5.0).await.unwrap().json().await.unwrap();
    assert_eq!(second["step"], 1);
    let res = app
        .post_json(&path, &json!({"sensors": sensors(0.0), "detections": []}))
        .await;
    assert_eq!(json_body(res, StatusCode::OK).await["step"], 2);
    let res = app
        .post_json(&path, &json!({"sensors": sensors(0.0), "detections": []}))
        .await;
    assert_eq!(json_body(res, StatusCode::OK).await["step"], 3);
    // A key over 128 characters is refused.
    let res = step(&"k".repeat(129), 0.0).await.unwrap();
    assert_problem(res, StatusCode::BAD_REQUEST, "Idempotency-Key").await;
    // So is one with a tab, which the documented pattern excludes; a space
    // inside is allowed.
    let res = step("k\t1", 0.0).await.unwrap();
    assert_problem(res, StatusCode::BAD_REQUEST, "Idempotency-Key").await;
    let res = step("k 1", 0.0).await.unwrap();
    assert_eq!(res.status(), StatusCode::OK);
}

/// A session step's plans are the stateless plan's: the same paths, and
/// the same values to 1e-9 (a step carried from the last one rounds
/// differently).
fn assert_same_plans(step: &Value, stateless: &Value) {
    let close = |a: &Value, b: &Value| {
        let (a, b) = (a.as_f64().unwrap(), b.as_f64().unwrap());
        (a - b).abs() <= 1e-9 * a.abs().max(1.0)
    };
    assert!(close(
        &step["expected_detections"],
        &stateless["expected_detections"]
    ));
    let (a, b) = (
        step["plans"].as_array().unwrap(),
        stateless["plans"].as_array().unwrap(),
    );
    assert_eq!(a.len(), b.len());
    for (a, b) in a.iter().zip(b) {
        assert_eq!(a["sensor"], b["sensor"]);
        assert_eq!(a["path"], b["path"]);
        assert_eq!(a["priority"], b["priority"]);
        assert!(
            close(&a["expected_detections"], &b["expected_detections"]),
            "{a} against {b}"
        );
    }
}
