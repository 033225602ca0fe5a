//! Fitting source rates over HTTP (`POST /v1/scenarios/{id}/fit`).

use reqwest::StatusCode;
use serde_json::{Value, json};

use vigil::http::config::Settings;

use crate::helpers::{assert_problem, assert_validation, json_body, spawn_app, spawn_with};

fn fit_request() -> Value {
    vigil::http::doc::examples::fit_request()
}

#[tokio::test]
async fn a_window_gets_each_sources_rate_with_its_interval() {
    let app = spawn_app().await;
    let res = app
        .post_json("/v1/scenarios/paper-v10/fit", &fit_request())
        .await;
    let body = json_body(res, StatusCode::OK).await;
    assert_eq!(body["scenario"], "paper-v10");
    assert_eq!(body["steps"], 2);
    let sources = body["sources"].as_array().unwrap();
    assert_eq!(sources.len(), 8);
    for (i, s) in sources.iter().enumerate() {
        assert_eq!(s["index"], i);
        let rate = s["rate"].as_f64().unwrap();
        let [lo, hi] = [
            s["interval"][0].as_f64().unwrap(),
            s["interval"][1].as_f64().unwrap(),
        ];
        assert!(lo <= rate && rate <= hi, "{s}");
        assert!(s["exposure"].as_f64().unwrap() >= 0.0, "{s}");
    }
    // Target 17 flies east along y = 100 from the source at (-1, 100): it
    // counts once, for that source, which the looks expose.
    assert_eq!(sources[0]["detected"], 1.0);
    assert!(sources[0]["exposure"].as_f64().unwrap() > 0.0);
    let total: f64 = sources
        .iter()
        .map(|s| s["detected"].as_f64().unwrap())
        .sum();
    assert_eq!(total, 1.0);
    assert_eq!(body["unexplained"], json!([]));
    assert!(body.get("id").is_none());
    // A flat prior: Gamma(N + 1, E), mean (N + 1)/E.
    let mut req = fit_request();
    req["prior"] = json!("flat");
    let flat = json_body(
        app.post_json("/v1/scenarios/paper-v10/fit", &req).await,
        StatusCode::OK,
    )
    .await;
    let s0 = &flat["sources"][0];
    let e = s0["exposure"].as_f64().unwrap();
    assert!((s0["rate"].as_f64().unwrap() - 2.0 / e).abs() < 1e-9 * (2.0 / e));
}

#[tokio::test]
async fn a_target_from_no_source_is_unexplained_with_its_entry() {
    let app = spawn_app().await;
    let mut req = fit_request();
    // Eastbound along y = 40: no paper source lies on that line.
    for (i, step) in req["steps"].as_array_mut().unwrap().iter_mut().enumerate() {
        step["sensors"][0]["y"] = json!(45.0);
        step["detections"][0]["y"] = json!(40.0);
        step["detections"][0]["x"] = json!(60.0 + 10.0 * i as f64);
    }
    let body = json_body(
        app.post_json("/v1/scenarios/paper-v10/fit", &req).await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(
        body["unexplained"],
        json!([{"id": 17, "entry": {"x": 0.0, "y": 40.0}}])
    );
}

#[tokio::test]
async fn register_adds_the_fitted_scenario() {
    let app = spawn_app().await;
    let mut req = fit_request();
    req["register"] = json!(true);
    let res = app.post_json("/v1/scenarios/paper-v10/fit", &req).await;
    let location = res.headers()["location"].to_str().unwrap().to_owned();
    let body = json_body(res, StatusCode::CREATED).await;
    let id = body["id"].as_str().unwrap();
    assert_eq!(location, format!("/v1/scenarios/{id}"));
    let summary = json_body(app.get(&location).await, StatusCode::OK).await;
    for (src, fitted) in summary["spec"]["sources"]
        .as_array()
        .unwrap()
        .iter()
        .zip(body["sources"].as_array().unwrap())
    {
        assert_eq!(src["rate"], fitted["rate"]);
    }
    // The same fit again finds it registered: 200, the same id.
    let again = json_body(
        app.post_json("/v1/scenarios/paper-v10/fit", &req).await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(again["id"], body["id"]);
}

#[tokio::test]
async fn bad_windows_are_refused_naming_the_field() {
    let app = spawn_app().await;
    let url = "/v1/scenarios/paper-v10/fit";
    assert_validation(app.post_json(url, &json!({"steps": []})).await, "steps").await;
    let mut outside = fit_request();
    outside["steps"][1]["detections"][0]["x"] = json!(250.0);
    assert_validation(app.post_json(url, &outside).await, "steps[1].detections[0]").await;
    let mut jump = fit_request();
    jump["steps"][1]["sensors"][1] = json!({"id": "b", "x": 155.0, "y": 105.0});
    jump["steps"][1]["detections"][0] =
        json!({"id": 17, "x": 160.0, "y": 100.0, "vx": 10.0, "vy": 0.0});
    assert_validation(app.post_json(url, &jump).await, "steps[1].detections[0].id").await;
    let mut order = fit_request();
    order["steps"][0]["step"] = json!(9);
    order["steps"][1]["step"] = json!(7);
    assert_validation(app.post_json(url, &order).await, "steps[1].step").await;
    let mut huge = fit_request();
    huge["steps"][0]["step"] = json!(9_223_372_036_854_775_808u64);
    assert_validation(app.post_json(url, &huge).await, "steps[0].step").await;
    let mut ty = fit_request();
    ty["steps"][0]["sensors"][0]["type"] = json!("blimp");
    assert_validation(app.post_json(url, &ty).await, "steps[0].sensors[0].type").await;
    let mut tol = fit_request();
    tol["tolerance"] = json!({"traceback": -1.0});
    assert_validation(app.post_json(url, &tol).await, "tolerance.traceback").await;
    // An array is no tolerance, not even an empty one (serde would read
    // it as a struct's fields in order).
    let mut listed = fit_request();
    listed["tolerance"] = json!([]);
    let res = app.post_json(url, &listed).await;
    assert_eq!(res.status(), StatusCode::BAD_REQUEST);
    let mut unknown = fit_request();
    unknown["steps"][0]["detections"][0]["z"] = json!(1.0);
    let res = app.post_json(url, &unknown).await;
    assert!(res.status().is_client_error(), "{}", res.status());
    assert_problem(
        app.post_json("/v1/scenarios/nope/fit", &fit_request())
            .await,
        StatusCode::NOT_FOUND,
        "nope",
    )
    .await;
}

#[tokio::test]
async fn a_long_window_fits_past_the_plan_body_limit() {
    let app = spawn_app().await;
    // 500 steps of 64 sensors with long ids: about 6 MB, past the 4 MB a
    // plan may send. `spread` sensors stand on distinct cells.
    let window = |spread: usize| {
        let steps: Vec<Value> = (0..500)
            .map(|_| {
                let sensors: Vec<Value> = (0..64)
                    .map(|i| {
                        let k = i % spread;
                        json!({"id": format!("{i:0>120}"), "x": 55.0 + 10.0 * (k % 8) as f64,
                               "y": 55.0 + 10.0 * (k / 8) as f64})
                    })
                    .collect();
                json!({"sensors": sensors, "detections": []})
            })
            .collect();
        json!({"steps": steps})
    };
    // 64 distinct looks a step over 500 steps is more work than a server
    // allowing 50 ms takes: refused as a costly plan is.
    let strict = spawn_with(Settings {
        max_plan_ms: Some(50.0),
        ..Settings::default()
    })
    .await;
    assert_problem(
        strict
            .post_json("/v1/scenarios/paper-v10/fit", &window(64))
            .await,
        StatusCode::UNPROCESSABLE_ENTITY,
        "--max-plan-ms",
    )
    .await;
    let req = window(2);
    assert!(req.to_string().len() > vigil::limits::MAX_BODY_BYTES);
    let body = json_body(
        app.post_json("/v1/scenarios/paper-v10/fit", &req).await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(body["steps"], 500);
    // Nothing detected over a long watch: every well exposed rate falls.
    let mut exposed = 0;
    for s in body["sources"].as_array().unwrap() {
        if s["exposure"].as_f64().unwrap() > 50.0 {
            exposed += 1;
            assert!(s["rate"].as_f64().unwrap() < 0.3 / 2.0, "{s}");
        }
    }
    assert!(exposed > 0, "{body}");
}

#[tokio::test]
async fn a_learning_session_reports_its_rates_every_step() {
    let app = spawn_app().await;
    let created = json_body(
        app.post_json(
            "/v1/sessions",
            &json!({"scenario_id": "paper-v10", "learn_rates": true}),
        )
        .await,
        StatusCode::CREATED,
    )
    .await;
    let id = created["id"].as_str().unwrap();
    assert_eq!(created["settings"]["learn_rates"], true);
    assert_eq!(created["rates"].as_array().unwrap().len(), 8);
    let url = format!("/v1/sessions/{id}/step");
    let window = fit_request();
    let mut last = Value::Null;
    for step in window["steps"].as_array().unwrap() {
        last = json_body(app.post_json(&url, step).await, StatusCode::OK).await;
    }
    let rates = last["rates"].as_array().unwrap();
    assert_eq!(rates.len(), 8);
    // The same as a fit of the same window: target 17 counts once.
    let fitted = json_body(
        app.post_json("/v1/scenarios/paper-v10/fit", &window).await,
        StatusCode::OK,
    )
    .await;
    for (a, b) in rates.iter().zip(fitted["sources"].as_array().unwrap()) {
        assert_eq!(a["detected"], b["detected"]);
        let (x, y) = (a["rate"].as_f64().unwrap(), b["rate"].as_f64().unwrap());
        assert!((x - y).abs() < 1e-9 * y, "{a} {b}");
    }
    // Each detection needs its track id; the refused step changes nothing.
    let mut anonymous = window["steps"][1].clone();
    anonymous["detections"][0]
        .as_object_mut()
        .unwrap()
        .remove("id");
    assert_validation(app.post_json(&url, &anonymous).await, "detections[0].id").await;
    let info = json_body(app.get(&format!("/v1/sessions/{id}")).await, StatusCode::OK).await;
    assert_eq!(info["step"], 2);
    assert_eq!(info["rates"], last["rates"]);
    // Without learn_rates, no rates.
    let plain = json_body(
        app.post_json("/v1/sessions", &json!({"scenario_id": "paper-v10"}))
            .await,
        StatusCode::CREATED,
    )
    .await;
    let step = json_body(
        app.post_json(
            &format!("/v1/sessions/{}/step", plain["id"].as_str().unwrap()),
            &window["steps"][0],
        )
        .await,
        StatusCode::OK,
    )
    .await;
    assert!(step.get("rates").is_none() && plain.get("rates").is_none());
}

#[tokio::test]
async fn a_learning_session_told_of_every_target_learns_from_the_zone() {
    let app = spawn_app().await;
    let created = json_body(
        app.post_json(
            "/v1/sessions",
            &json!({"scenario_id": "paper-v10", "learn_rates": true, "observed": "zone"}),
        )
        .await,
        StatusCode::CREATED,
    )
    .await;
    let url = format!("/v1/sessions/{}/step", created["id"].as_str().unwrap());
    // Far from the only sensor: with `observed: zone` the detections cover
    // the zone, and so does the exposure.
    let step = json!({"sensors": [{"id": "a", "x": 255, "y": 255}],
                      "detections": [{"id": 5, "x": 60.0, "y": 100.0, "vx": 10.0, "vy": 0.0}]});
    let body = json_body(app.post_json(&url, &step).await, StatusCode::OK).await;
    let rates = body["rates"].as_array().unwrap();
    assert_eq!(rates[0]["detected"], 1.0);
    // Every source's targets in the zone are exposed at once.
    assert!(
        rates.iter().all(|r| r["exposure"].as_f64().unwrap() > 1.0),
        "{body}"
    );
}

/// A learning session keeps the looks of at most 1,000 steps: a scenario
/// whose slowest targets stay longer in the zone (600 units at 0.5 a step:
/// 1,202 steps) would count a target seen again after them as new, so it
/// may not learn (422 naming `learn_rates`); at speed 1 it may.
#[tokio::test]
async fn a_session_learns_only_if_it_can_remember_a_crossing() {
    let app = spawn_app().await;
    let spec = |speed: f64| {
        json!({
            "zone": {"width": 600.0, "height": 20.0},
            "cell_size": 10.0,
            "fov": {"shape": "square", "half_width": 10.0},
            "target_speed": speed,
            "sources": [{"x": -1.0, "y": 10.0, "rate": 0.2, "direction": 0.0, "spread": 1.0}]
        })
    };
    let slow = app
        .post_json(
            "/v1/sessions",
            &json!({"scenario": spec(0.5), "learn_rates": true}),
        )
        .await;
    let body = assert_problem(slow, StatusCode::UNPROCESSABLE_ENTITY, "learn_rates").await;
    let detail = body["detail"].as_str().unwrap();
    assert!(
        detail.starts_with("learn_rates: ") && detail.contains("1202 steps"),
        "{body}"
    );
    // Without learning, the same scenario opens a session.
    json_body(
        app.post_json("/v1/sessions", &json!({"scenario": spec(0.5)}))
            .await,
        StatusCode::CREATED,
    )
    .await;
    json_body(
        app.post_json(
            "/v1/sessions",
            &json!({"scenario": spec(1.0), "learn_rates": true}),
        )
        .await,
        StatusCode::CREATED,
    )
    .await;
}
