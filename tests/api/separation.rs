//! The minimum separation over HTTP: its bounds (422 naming the field), the
//! scenario's default and a request's override, and the counts in the
//! response.

use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::helpers::{TestApp, assert_validation, json_body, plan_request, small_spec, spawn_app};

/// Two sensors on one cell of `paper-v10` and one far away, T = 3.
fn crowded(min_separation: Option<Value>) -> Value {
    let mut req = json!({
        "sensors": [
            {"id": "a", "x": 150.0, "y": 150.0},
            {"id": "b", "x": 151.0, "y": 152.0},
            {"id": "c", "x": 25.0, "y": 275.0}
        ],
        "horizon": 3
    });
    if let Some(d) = min_separation {
        req["min_separation"] = d;
    }
    req
}

fn cells(plan: &Value) -> Vec<(i64, i64)> {
    plan["path"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c["col"].as_i64().unwrap(), c["row"].as_i64().unwrap()))
        .collect()
}

async fn plan_on(app: &TestApp, id: &str, body: &Value) -> Value {
    let res = app
        .post_json(&format!("/v1/scenarios/{id}/plan"), body)
        .await;
    json_body(res, StatusCode::OK).await
}

#[tokio::test]
async fn out_of_bounds_separations_are_422() {
    let app = spawn_app().await;
    for bad in [json!(17), json!(-1), json!(2.5), json!(1e30)] {
        let mut req = plan_request();
        req["min_separation"] = bad.clone();
        assert_validation(app.plan(&req).await, "min_separation").await;
        let mut spec = small_spec();
        spec["min_separation"] = bad.clone();
        let res = app.post_json("/v1/scenarios", &spec).await;
        assert_validation(res, "min_separation").await;
        let body = json!({"scenario": spec, "sensors": [{"id": 1, "x": 5.0, "y": 5.0}]});
        let res = app.post_json("/v1/plan", &body).await;
        assert_validation(res, "scenario.min_separation").await;
    }
    // A string is no number: a malformed body.
    let mut req = plan_request();
    req["min_separation"] = json!("3");
    assert_eq!(app.plan(&req).await.status(), StatusCode::BAD_REQUEST);
    // The bounds are inclusive.
    for ok in [json!(0), json!(16), json!(3.0)] {
        let mut req = plan_request();
        req["min_separation"] = ok;
        assert_eq!(app.plan(&req).await.status(), StatusCode::OK);
    }
}

#[tokio::test]
async fn a_plan_keeps_its_sensors_apart_and_counts_what_it_cannot() {
    let app = spawn_app().await;
    // Without the rule the two crowded sensors may share cells; the
    // response says the rule is off and counts nothing.
    let free = plan_on(&app, "paper-v10", &crowded(None)).await;
    assert_eq!(free["min_separation"], 0);
    assert_eq!(free["separation_violations"], 0);
    // With separation 3 they start on one cell (step 0 is not counted) and
    // move apart: one step at distance 2 at most, then apart.
    let apart = plan_on(&app, "paper-v10", &crowded(Some(json!(3)))).await;
    assert_eq!(apart["min_separation"], 3);
    let plans = apart["plans"].as_array().unwrap();
    let (a, b, c) = (cells(&plans[0]), cells(&plans[1]), cells(&plans[2]));
    let mut too_close = 0;
    for t in 0..3 {
        let d = (a[t].0 - b[t].0).abs().max((a[t].1 - b[t].1).abs());
        if d < 3 {
            too_close += 1;
            assert_eq!(t, 0, "only the first step can be too close: {a:?} {b:?}");
        }
    }
    assert_eq!(apart["separation_violations"], too_close);
    assert_eq!(plans[0]["separation_violations"], too_close);
    assert_eq!(plans[1]["separation_violations"], too_close);
    assert_eq!(plans[2]["separation_violations"], 0);
    assert!(c.iter().all(|&(col, row)| col <= 6 && row >= 23));
    // Every coordination and estimator keeps the rule the same way.
    for (estimator, coordination) in [("paper", "none"), ("exact", "iterated")] {
        let mut req = crowded(Some(json!(3)));
        req["estimator"] = json!(estimator);
        req["coordination"] = json!(coordination);
        let body = plan_on(&app, "paper-v10", &req).await;
        assert!(
            body["separation_violations"].as_u64().unwrap() <= 1,
            "{estimator}/{coordination}: {body}"
        );
    }
}

#[tokio::test]
async fn a_scenario_sets_the_default_and_a_request_overrides_it() {
    let app = spawn_app().await;
    // 0 is the default: a spec that spells it out keeps its id.
    let plain = json_body(
        app.post_json("/v1/scenarios", &small_spec()).await,
        StatusCode::CREATED,
    )
    .await;
    let mut spec = small_spec();
    spec["min_separation"] = json!(0);
    let zero = json_body(app.post_json("/v1/scenarios", &spec).await, StatusCode::OK).await;
    assert_eq!(zero["id"], plain["id"]);
    assert!(zero["spec"].get("min_separation").is_none());
    spec["min_separation"] = json!(2);
    let two = json_body(
        app.post_json("/v1/scenarios", &spec).await,
        StatusCode::CREATED,
    )
    .await;
    assert_ne!(two["id"], plain["id"]);
    assert_eq!(two["spec"]["min_separation"], 2);
    let id = two["id"].as_str().unwrap();
    let req =
        json!({"sensors": [{"id": 1, "x": 55.0, "y": 55.0}, {"id": 2, "x": 55.0, "y": 55.0}]});
    let body = plan_on(&app, id, &req).await;
    assert_eq!(body["min_separation"], 2);
    let plans = body["plans"].as_array().unwrap();
    let (a, b) = (cells(&plans[0]), cells(&plans[1]));
    assert!(
        a.iter()
            .zip(&b)
            .skip(1)
            .all(|(p, q)| (p.0 - q.0).abs().max((p.1 - q.1).abs()) >= 2)
    );
    let mut req = req;
    req["min_separation"] = json!(0);
    assert_eq!(plan_on(&app, id, &req).await["min_separation"], 0);
}
