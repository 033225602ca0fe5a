//! The intrusion objective over HTTP: `"objective": "first_detections"` on
//! scenario and inline plans, evaluate and sessions, and its error cases.

use reqwest::{StatusCode, header};
use serde_json::{Value, json};

use crate::helpers::{
    assert_problem, assert_validation, close, json_body, paths_of, plan_request, small_spec,
    spawn_app,
};
fn total(v: &Value) -> f64 {
    v["expected_detections"].as_f64().unwrap()
}

fn by_step(v: &Value) -> Vec<f64> {
    let steps = v["expected_by_step"].as_array().unwrap();
    steps.iter().map(|x| x.as_f64().unwrap()).collect()
}

#[tokio::test]
async fn first_detection_plans_score_their_value_and_stay_within_their_bound() {
    let app = spawn_app().await;
    // Plans leave out of their values the pieces a certain history
    // detected (their searches never build them); evaluate builds every
    // piece: the values agree step by step, with and without a history.
    let history = json!([
        [{"x": 55.0, "y": 45.0}, {"x": 150.0, "y": 140.0}, {"x": 235.0, "y": 60.0}],
        [{"x": 55.0, "y": 35.0}, {"x": 150.0, "y": 130.0}, {"x": 225.0, "y": 60.0}]
    ]);
    for (coordination, with_history) in [
        ("none", false),
        ("priority", false),
        ("iterated", false),
        ("joint", false),
        ("priority", true),
        ("iterated", true),
    ] {
        let mut req = plan_request();
        if with_history {
            req["history"] = history.clone();
        }
        req["coordination"] = json!(coordination);
        req["objective"] = json!("first_detections");
        let plan = json_body(app.plan(&req).await, StatusCode::OK).await;
        assert_eq!(plan["objective"], "first_detections");
        let planned = by_step(&plan);
        assert!(close(planned.iter().sum(), total(&plan), 1e-12));
        let upper = plan["bound"]["upper"].as_f64().unwrap();
        assert!(total(&plan) > 0.0 && total(&plan) <= upper + 1e-9);
        // Each target counts once: never more than the detections objective
        // counts over the same paths.
        let mut ev = req.clone();
        ev["paths"] = paths_of(&plan);
        let scored = json_body(
            app.post_json("/v1/scenarios/paper-v10/evaluate", &ev).await,
            StatusCode::OK,
        )
        .await;
        assert_eq!(scored["objective"], "first_detections");
        assert!(
            close(total(&scored), total(&plan), 1e-9),
            "{coordination}: {} vs {}",
            total(&scored),
            total(&plan)
        );
        let evaluated = by_step(&scored);
        assert_eq!(planned.len(), evaluated.len());
        for (p, e) in planned.iter().zip(&evaluated) {
            assert!(
                (p - e).abs() <= 1e-9 * total(&plan),
                "{coordination}: {planned:?} vs {evaluated:?}"
            );
        }
        ev["objective"] = json!("detections");
        let as_detections = json_body(
            app.post_json("/v1/scenarios/paper-v10/evaluate", &ev).await,
            StatusCode::OK,
        )
        .await;
        assert_eq!(as_detections["objective"], "detections");
        assert!(total(&as_detections) > total(&plan));
    }
    // The default is the paper's J, and says so.
    let plan = json_body(app.plan(&plan_request()).await, StatusCode::OK).await;
    assert_eq!(plan["objective"], "detections");
}

#[tokio::test]
async fn an_inline_scenario_plans_first_detections() {
    let app = spawn_app().await;
    let body = json!({
        "scenario": small_spec(),
        "sensors": [{"id": "a", "x": 25.0, "y": 25.0}, {"id": "b", "x": 75.0, "y": 75.0}],
        "horizon": 4,
        "coordination": "iterated",
        "objective": "first_detections",
    });
    let plan = json_body(app.post_json("/v1/plan", &body).await, StatusCode::OK).await;
    assert_eq!(plan["objective"], "first_detections");
    assert_eq!(plan["expected_by_step"].as_array().unwrap().len(), 4);
    assert!(total(&plan) > 0.0);
}

#[tokio::test]
async fn the_paper_estimator_refuses_first_detections_naming_objective() {
    let app = spawn_app().await;
    let mut req = plan_request();
    req["estimator"] = json!("paper");
    req["objective"] = json!("first_detections");
    assert_validation(app.plan(&req).await, "objective").await;
    let mut ev = req.clone();
    ev["paths"] = json!([]);
    assert_validation(
        app.post_json("/v1/scenarios/paper-v10/evaluate", &ev).await,
        "objective",
    )
    .await;
    // A session refuses it at creation, before any step.
    let res = app
        .post_json(
            "/v1/sessions",
            &json!({"scenario_id": "paper-v10", "estimator": "paper", "objective": "first_detections"}),
        )
        .await;
    assert_validation(res, "objective").await;
    // An unknown objective is a malformed body that lists the known ones.
    let mut req = plan_request();
    req["objective"] = json!("first");
    assert_problem(
        app.plan(&req).await,
        StatusCode::BAD_REQUEST,
        "first_detections",
    )
    .await;
}

#[tokio::test]
async fn a_session_plans_first_detections_and_a_step_may_override_it() {
    let app = spawn_app().await;
    let res = app
        .post_json(
            "/v1/sessions",
            &json!({"scenario_id": "paper-v10", "objective": "first_detections"}),
        )
        .await;
    assert!(res.headers().contains_key(header::LOCATION));
    let info = json_body(res, StatusCode::CREATED).await;
    let id = info["id"].as_str().unwrap();
    let sensors = json!([{"id": "a", "x": 55.0, "y": 55.0}, {"id": "b", "x": 245.0, "y": 60.0}]);
    let step = json_body(
        app.post_json(
            &format!("/v1/sessions/{id}/step"),
            &json!({"sensors": sensors}),
        )
        .await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(step["objective"], "first_detections");
    // The same state, stateless: the same plan.
    let stateless = json_body(
        app.plan(&json!({"sensors": sensors, "objective": "first_detections"}))
            .await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(step["plans"], stateless["plans"]);
    let step = json_body(
        app.post_json(
            &format!("/v1/sessions/{id}/step"),
            &json!({"sensors": sensors, "objective": "detections"}),
        )
        .await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(step["objective"], "detections");
}
