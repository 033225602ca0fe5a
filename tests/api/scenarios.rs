//! Health, listing, reading, registering and deleting scenarios, and their
//! statistics.

use reqwest::{StatusCode, header};
use serde_json::json;
use vigil::scenario::BUILTIN_IDS;

use crate::helpers::{assert_problem, close, json_body, small_spec, spawn_app};

#[tokio::test]
async fn healthz_is_ok() {
    let app = spawn_app().await;
    let body = json_body(app.get("/healthz").await, StatusCode::OK).await;
    assert_eq!(body, json!({"status": "ok"}));
}

#[tokio::test]
async fn list_holds_the_builtins_sorted() {
    let app = spawn_app().await;
    let body = json_body(app.get("/v1/scenarios").await, StatusCode::OK).await;
    let ids: Vec<&str> = body["scenarios"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["id"].as_str().unwrap())
        .collect();
    for id in BUILTIN_IDS {
        assert!(ids.contains(&id), "{id} missing from {ids:?}");
    }
    let mut sorted = ids.clone();
    sorted.sort_unstable();
    assert_eq!(ids, sorted);
}

#[tokio::test]
async fn builtin_summary_has_the_contract_fields() {
    let app = spawn_app().await;
    let body = json_body(app.get("/v1/scenarios/paper-v10").await, StatusCode::OK).await;
    let obj = body.as_object().unwrap();
    let mut keys: Vec<&str> = obj.keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        [
            "grid",
            "id",
            "predicted_precompute_ms",
            "progress",
            "spec",
            "status",
            "summary"
        ]
    );
    assert_eq!(body["id"], "paper-v10");
    assert_eq!(body["status"], "ready");
    assert_eq!(body["progress"], 1.0);
    let predicted = body["predicted_precompute_ms"].as_f64().unwrap();
    assert!(predicted.is_finite() && predicted > 0.0, "{predicted}");
    assert_eq!(body["grid"], json!({"cols": 30, "rows": 30}));
    let expected = body["summary"]["expected_targets_in_zone"]
        .as_f64()
        .unwrap();
    assert!(expected.is_finite() && expected > 0.0, "{expected}");
    let ms = body["summary"]["precompute_ms"].as_f64().unwrap();
    assert!(ms.is_finite() && ms >= 0.0);
    assert_eq!(body["summary"].as_object().unwrap().len(), 2);
    // The canonical spec: headings and horizon filled in.
    let spec = &body["spec"];
    assert_eq!(spec["target_speed"], 10.0);
    assert_eq!(spec["cell_size"], 10.0);
    assert_eq!(spec["horizon"], 3);
    assert_eq!(spec["zone"], json!({"width": 300.0, "height": 300.0}));
    let sources = spec["sources"].as_array().unwrap();
    assert_eq!(sources.len(), 8);
    assert!(sources.iter().all(|s| s["heading"].is_string()));
    assert_eq!(sources[0]["heading"], "east");

    let v15 = json_body(app.get("/v1/scenarios/paper-v15").await, StatusCode::OK).await;
    assert_eq!(v15["spec"]["target_speed"], 15.0);
}

#[tokio::test]
async fn stats_are_row_major_finite_and_consistent() {
    let app = spawn_app().await;
    let body = json_body(
        app.get("/v1/scenarios/paper-v10/stats").await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(body["cols"], 30);
    assert_eq!(body["rows"], 30);
    assert_eq!(body["cell_size"], 10.0);
    let column = |name: &str| -> Vec<f64> {
        body[name]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let (lambda, escape, d) = (column("lambda_hat"), column("escape_time"), column("d_hat"));
    for v in [&lambda, &escape, &d] {
        assert_eq!(v.len(), 900);
        assert!(v.iter().all(|x| x.is_finite() && *x >= 0.0));
    }
    for i in 0..900 {
        assert!(
            close(d[i], lambda[i] * escape[i], 1e-9),
            "cell {i}: d_hat {} vs {} × {}",
            d[i],
            lambda[i],
            escape[i]
        );
    }
    assert!(d.iter().any(|&x| x > 0.0));
    // The paper's setting is symmetric under x ↔ 300 − x: row-major means
    // cell (col, row) and (29 − col, row) agree.
    for row in 0..30 {
        for col in 0..30 {
            let (a, b) = (row * 30 + col, row * 30 + 29 - col);
            assert!(close(d[a], d[b], 1e-9), "({col},{row})");
        }
    }
}

#[tokio::test]
async fn register_read_list_and_delete_a_scenario() {
    let app = spawn_app().await;
    let spec = small_spec();

    let res = app.post_json("/v1/scenarios", &spec).await;
    let location = res
        .headers()
        .get(header::LOCATION)
        .map(|v| v.to_str().unwrap().to_owned());
    let created = json_body(res, StatusCode::CREATED).await;
    let id = created["id"].as_str().unwrap().to_owned();
    assert!(id.starts_with("s-"), "{id}");
    assert_eq!(
        location.as_deref(),
        Some(format!("/v1/scenarios/{id}").as_str())
    );
    assert_eq!(created["grid"], json!({"cols": 10, "rows": 10}));
    assert!(
        created["summary"]["expected_targets_in_zone"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    // Canonical spec: inferred headings, default horizon.
    assert_eq!(created["spec"]["horizon"], 3);
    assert_eq!(created["spec"]["sources"][0]["heading"], "east");
    assert_eq!(created["spec"]["sources"][1]["heading"], "south");

    // The same spec again, and its canonical form: 200, same id, no Location.
    for again in [spec.clone(), created["spec"].clone()] {
        let res = app.post_json("/v1/scenarios", &again).await;
        assert!(res.headers().get(header::LOCATION).is_none());
        let body = json_body(res, StatusCode::OK).await;
        assert_eq!(body, created);
    }

    let read = json_body(
        app.get(&format!("/v1/scenarios/{id}")).await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(read, created);
    let list = json_body(app.get("/v1/scenarios").await, StatusCode::OK).await;
    let listed = list["scenarios"].as_array().unwrap();
    assert_eq!(listed.len(), BUILTIN_IDS.len() + 1);
    assert!(listed.contains(&created));

    let stats = json_body(
        app.get(&format!("/v1/scenarios/{id}/stats")).await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(stats["lambda_hat"].as_array().unwrap().len(), 100);

    let plan = app
        .post_json(
            &format!("/v1/scenarios/{id}/plan"),
            &json!({"sensors": [{"id": 1, "x": 5.0, "y": 95.0}]}),
        )
        .await;
    let plan = json_body(plan, StatusCode::OK).await;
    assert_eq!(plan["scenario"], id.as_str());

    let res = app.delete(&format!("/v1/scenarios/{id}")).await;
    assert_eq!(res.status(), StatusCode::NO_CONTENT);
    assert!(res.bytes().await.unwrap().is_empty());
    let res = app.get(&format!("/v1/scenarios/{id}")).await;
    assert_problem(res, StatusCode::NOT_FOUND, &id).await;
    let res = app.delete(&format!("/v1/scenarios/{id}")).await;
    assert_problem(res, StatusCode::NOT_FOUND, &id).await;

    // Registering it again creates it again.
    let res = app.post_json("/v1/scenarios", &spec).await;
    assert_eq!(json_body(res, StatusCode::CREATED).await["id"], id.as_str());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn racing_identical_posts_register_one_scenario() {
    let app = spawn_app().await;
    let spec = small_spec();
    let handles: Vec<_> = (0..4)
        .map(|_| {
            let (client, url, spec) = (app.client.clone(), app.url("/v1/scenarios"), spec.clone());
            tokio::spawn(async move { client.post(url).json(&spec).send().await.unwrap() })
        })
        .collect();
    let mut created = 0;
    let mut ids = Vec::new();
    for h in handles {
        let res = h.await.unwrap();
        let status = res.status();
        assert!(
            status == StatusCode::CREATED || status == StatusCode::OK,
            "{status}"
        );
        created += usize::from(status == StatusCode::CREATED);
        ids.push(json_body(res, status).await["id"].clone());
    }
    assert_eq!(created, 1);
    assert!(ids.windows(2).all(|w| w[0] == w[1]));
    let list = json_body(app.get("/v1/scenarios").await, StatusCode::OK).await;
    assert_eq!(
        list["scenarios"].as_array().unwrap().len(),
        BUILTIN_IDS.len() + 1
    );
}

#[tokio::test]
async fn builtins_cannot_be_deleted() {
    let app = spawn_app().await;
    for id in BUILTIN_IDS {
        let res = app.delete(&format!("/v1/scenarios/{id}")).await;
        let body = assert_problem(res, StatusCode::CONFLICT, id).await;
        assert_eq!(body["status"], 409);
        let res = app.get(&format!("/v1/scenarios/{id}")).await;
        assert_eq!(res.status(), StatusCode::OK);
    }
}

/// A scenario with speed mixtures and cones registers with its canonical
/// form (direction in [0, 360), a default spread dropped, no heading on a
/// directed source), its statistics see nothing outside the cones, and it
/// plans.
#[tokio::test]
async fn mixtures_and_cones_register_and_plan() {
    let app = spawn_app().await;
    let spec = json!({
        "zone": {"width": 200.0, "height": 100.0}, "cell_size": 10.0,
        "fov": {"shape": "square", "half_width": 15.0},
        "sources": [
            {"x": -1.0, "y": 20.0, "rate": 0.5, "heading": "east", "direction": -350.0,
             "spread": 20.0, "speeds": [{"speed": 1.5, "weight": 3.0}, {"speed": 12.0, "weight": 1.0}]},
            {"x": 150.0, "y": 101.0, "rate": 0.0, "spread": 180.0,
             "speeds": [{"speed": 6.0, "weight": 1.0}]}
        ]
    });
    let res = app.post_json("/v1/scenarios", &spec).await;
    let created = json_body(res, StatusCode::CREATED).await;
    let id = created["id"].as_str().unwrap().to_owned();
    let canonical = &created["spec"];
    assert!(canonical.get("target_speed").is_none());
    assert_eq!(canonical["sources"][0]["direction"], 10.0);
    assert!(canonical["sources"][0].get("heading").is_none());
    assert_eq!(canonical["sources"][0]["spread"], 20.0);
    assert!(canonical["sources"][1].get("spread").is_none());
    assert_eq!(canonical["sources"][1]["heading"], "south");
    // The canonical form is the same scenario.
    let again = app.post_json("/v1/scenarios", canonical).await;
    assert_eq!(json_body(again, StatusCode::OK).await["id"], id.as_str());

    let stats = json_body(
        app.get(&format!("/v1/scenarios/{id}/stats")).await,
        StatusCode::OK,
    )
    .await;
    let lambda = stats["lambda_hat"].as_array().unwrap();
    let d_hat = stats["d_hat"].as_array().unwrap();
    // Row 9, column 0 (the north-west corner) is outside the first cone (the
    // second source emits nothing); row 2, column 5 is on the first cone's
    // axis (y = 20 + x·tan 10°).
    let at = |row: usize, col: usize| row * 20 + col;
    assert_eq!(lambda[at(9, 0)], 0.0);
    assert_eq!(d_hat[at(9, 0)], 0.0);
    assert!(lambda[at(2, 5)].as_f64().unwrap() > 0.1);
    assert!(d_hat[at(2, 5)].as_f64().unwrap() > 0.1);

    let body = json!({"sensors": [{"id": "a", "x": 55, "y": 25}, {"id": "b", "x": 150, "y": 80}],
                      "history": [[{"x": 45, "y": 25}, {"x": 150, "y": 70}]]});
    for estimator in ["exact", "paper"] {
        let mut body = body.clone();
        body["estimator"] = json!(estimator);
        let plan = json_body(
            app.post_json(&format!("/v1/scenarios/{id}/plan"), &body)
                .await,
            StatusCode::OK,
        )
        .await;
        assert_eq!(plan["plans"].as_array().unwrap().len(), 2);
        let total = plan["expected_detections"].as_f64().unwrap();
        assert!(total.is_finite() && total > 0.0, "{estimator}: {total}");
    }
}

/// `site-gates` is served with its cones and speed classes.
#[tokio::test]
async fn site_gates_is_built_in() {
    let app = spawn_app().await;
    let body = json_body(app.get("/v1/scenarios/site-gates").await, StatusCode::OK).await;
    assert_eq!(body["grid"], json!({"cols": 40, "rows": 30}));
    let sources = body["spec"]["sources"].as_array().unwrap();
    assert!(sources.iter().all(|s| s["speeds"].is_array()));
    assert!(sources.iter().any(|s| s["direction"].is_number()));
    let plan = json_body(
        app.post_json(
            "/v1/scenarios/site-gates/plan",
            &json!({"sensors": [{"id": 1, "x": 100, "y": 150}]}),
        )
        .await,
        StatusCode::OK,
    )
    .await;
    assert_eq!(plan["plans"][0]["path"].as_array().unwrap().len(), 3);
}

/// A spec may set its rays per π, within bounds: the value is kept in the
/// canonical spec, the scenario plans with it, and a coarser grid answers
/// close to the default one (within the errors of both against the model).
#[tokio::test]
async fn rays_per_pi_is_a_bounded_setting_of_the_spec() {
    let app = spawn_app().await;
    for bad in [json!(16), json!(4096), json!(64.5), json!("many")] {
        let mut spec = small_spec();
        spec["rays_per_pi"] = bad.clone();
        let res = app.post_json("/v1/scenarios", &spec).await;
        let status = res.status();
        assert!(
            status == StatusCode::UNPROCESSABLE_ENTITY || status == StatusCode::BAD_REQUEST,
            "{bad}: {status}"
        );
        let body = assert_problem(res, status, "rays_per_pi").await;
        assert!(body["detail"].as_str().unwrap().contains("rays_per_pi"));
    }
    let mut values = Vec::new();
    for rays in [None, Some(64)] {
        let mut spec = small_spec();
        if let Some(r) = rays {
            spec["rays_per_pi"] = json!(r);
        }
        let created = json_body(
            app.post_json("/v1/scenarios", &spec).await,
            StatusCode::CREATED,
        )
        .await;
        assert_eq!(
            created["spec"].get("rays_per_pi").cloned(),
            rays.map(|r| json!(r))
        );
        let id = created["id"].as_str().unwrap().to_owned();
        let body = json!({"sensors": [{"id": "a", "x": 35, "y": 45}, {"id": "b", "x": 65, "y": 55}],
                          "history": [[{"x": 45, "y": 45}, {"x": 65, "y": 45}]]});
        let plan = json_body(
            app.post_json(&format!("/v1/scenarios/{id}/plan"), &body)
                .await,
            StatusCode::OK,
        )
        .await;
        values.push(plan["expected_detections"].as_f64().unwrap());
    }
    assert!(close(values[0], values[1], 0.05), "{values:?}");
}
