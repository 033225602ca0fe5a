//! Operating the service: body limit, API key, load shedding, time limit,
//! durability across kill -9, a corrupt store, graceful shutdown, the
//! stateless /v1/plan, request ids and metrics.

use std::process::Command;
use std::time::Duration;

use reqwest::{StatusCode, header};
use serde_json::{Value, json};
use vigil::http::config::Settings;

use crate::helpers::{
    Server, assert_problem, cpu_seconds, heavy_plan, spawn_with, temp_dir, wait_busy,
};

/// A plan request that keeps a core busy for a while: many sensors, a long
/// horizon, iterated coordination.
fn slow_plan() -> Value {
    let sensors: Vec<Value> = (0..120)
        .map(|i| json!({"id": i, "x": 5 + (i % 12) * 25, "y": 5 + (i / 12) * 29}))
        .collect();
    json!({"sensors": sensors, "horizon": 12, "coordination": "iterated"})
}

#[tokio::test]
async fn api_key_guards_v1_only() {
    let app = spawn_with(Settings {
        api_key: Some("s3cret".into()),
        ..Settings::default()
    })
    .await;
    let url = app.url("/v1/scenarios");
    let none = app.client.get(&url).send().await.unwrap();
    assert_eq!(none.headers()[header::WWW_AUTHENTICATE], "Bearer");
    assert_problem(none, StatusCode::UNAUTHORIZED, "Authorization").await;
    let wrong = app
        .client
        .get(&url)
        .bearer_auth("s3creT")
        .send()
        .await
        .unwrap();
    assert_problem(wrong, StatusCode::UNAUTHORIZED, "Authorization").await;
    let plan = app
        .client
        .post(app.url("/v1/scenarios/paper-v10/plan"))
        .json(&json!({"sensors": [{"id": 1, "x": 5, "y": 5}]}))
        .send()
        .await
        .unwrap();
    assert_eq!(plan.status(), StatusCode::UNAUTHORIZED);
    let right = app
        .client
        .get(&url)
        .bearer_auth("s3cret")
        .send()
        .await
        .unwrap();
    assert_eq!(right.status(), StatusCode::OK);
    for open in ["/healthz", "/metrics"] {
        assert_eq!(app.get(open).await.status(), StatusCode::OK, "{open}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_flood_is_shed_with_503_while_healthz_answers() {
    let app = spawn_with(Settings {
        max_in_flight: 1,
        ..Settings::default()
    })
    .await;
    let body = slow_plan();
    let mut flood = Vec::new();
    for _ in 0..12 {
        let (client, url, body) = (
            app.client.clone(),
            app.url("/v1/scenarios/paper-v10/plan"),
            body.clone(),
        );
        flood.push(tokio::spawn(async move {
            client.post(url).json(&body).send().await.unwrap()
        }));
    }
    tokio::time::sleep(Duration::from_millis(30)).await;
    let health = tokio::time::timeout(Duration::from_secs(2), app.get("/healthz"))
        .await
        .expect("healthz answers during the flood");
    assert_eq!(health.status(), StatusCode::OK);
    let mut statuses = Vec::new();
    for task in flood {
        let res = task.await.unwrap();
        let status = res.status();
        if status == StatusCode::SERVICE_UNAVAILABLE {
            assert_eq!(res.headers()[header::RETRY_AFTER], "1");
            assert_problem(res, StatusCode::SERVICE_UNAVAILABLE, "capacity").await;
        }
        statuses.push(status);
    }
    assert!(statuses.contains(&StatusCode::OK), "{statuses:?}");
    assert!(
        statuses.contains(&StatusCode::SERVICE_UNAVAILABLE),
        "{statuses:?}"
    );
    let metrics = app.get("/metrics").await.text().await.unwrap();
    assert!(metrics.contains("vigil_http_shed_total"), "{metrics}");
}

#[tokio::test]
async fn slow_requests_time_out_with_504() {
    let app = spawn_with(Settings {
        request_timeout: Duration::from_millis(20),
        ..Settings::default()
    })
    .await;
    let res = app
        .post_json("/v1/scenarios/paper-v10/plan", &slow_plan())
        .await;
    assert_problem(res, StatusCode::GATEWAY_TIMEOUT, "time limit").await;
    // The server carries on.
    assert_eq!(app.get("/healthz").await.status(), StatusCode::OK);
}

#[tokio::test]
async fn v1_plan_takes_an_inline_scenario_or_an_id() {
    let app = crate::helpers::spawn_app().await;
    let spec = json!({
        "zone": {"width": 120, "height": 80}, "cell_size": 10,
        "fov": {"shape": "square", "half_width": 15}, "target_speed": 6,
        "sources": [{"x": -2, "y": 40, "rate": 0.5}]
    });
    let sensors = json!([{"id": "a", "x": 15, "y": 15}, {"id": "b", "x": 95, "y": 55}]);
    let res = app
        .post_json("/v1/plan", &json!({"scenario": spec, "sensors": sensors}))
        .await;
    assert_eq!(res.status(), StatusCode::OK);
    let plan: Value = res.json().await.unwrap();
    let id = plan["scenario"].as_str().unwrap().to_owned();
    assert_eq!(plan["plans"].as_array().unwrap().len(), 2);
    // Inline scenarios are cached, not registered.
    assert_eq!(
        app.get(&format!("/v1/scenarios/{id}")).await.status(),
        StatusCode::NOT_FOUND
    );
    let again = app
        .post_json("/v1/plan", &json!({"scenario_id": id, "sensors": sensors}))
        .await;
    assert_eq!(again.status(), StatusCode::OK);
    let builtin = app
        .post_json(
            "/v1/plan",
            &json!({"scenario_id": "paper-v15", "sensors": sensors, "horizon": 2}),
        )
        .await;
    assert_eq!(builtin.status(), StatusCode::OK);
    let neither = app
        .post_json("/v1/plan", &json!({"sensors": sensors}))
        .await;
    assert_problem(neither, StatusCode::UNPROCESSABLE_ENTITY, "scenario_id").await;
    let both = app
        .post_json(
            "/v1/plan",
            &json!({"scenario_id": id, "scenario": spec, "sensors": sensors}),
        )
        .await;
    assert_problem(both, StatusCode::UNPROCESSABLE_ENTITY, "scenario_id").await;
    let unknown = app
        .post_json(
            "/v1/plan",
            &json!({"scenario_id": "s-nope", "sensors": sensors}),
        )
        .await;
    assert_problem(unknown, StatusCode::NOT_FOUND, "s-nope").await;
    let mut bad = spec.clone();
    bad["cell_size"] = json!(7);
    let invalid = app
        .post_json("/v1/plan", &json!({"scenario": bad, "sensors": sensors}))
        .await;
    assert_problem(
        invalid,
        StatusCode::UNPROCESSABLE_ENTITY,
        "scenario.zone.width",
    )
    .await;
}

#[tokio::test]
async fn responses_carry_request_ids_and_metrics_are_exposed() {
    let app = crate::helpers::spawn_app().await;
    let res = app.get("/v1/scenarios").await;
    assert!(res.headers().contains_key("x-request-id"));
    let given = app
        .client
        .get(app.url("/healthz"))
        .header("x-request-id", "abc-123")
        .send()
        .await
        .unwrap();
    assert_eq!(given.headers()["x-request-id"], "abc-123");
    app.post_json(
        "/v1/scenarios/paper-v10/plan",
        &json!({"sensors": [{"id": 1, "x": 5, "y": 5}]}),
    )
    .await;
    let metrics = app.get("/metrics").await.text().await.unwrap();
    for name in [
        "vigil_http_requests_total",
        "vigil_plan_duration_seconds",
        "vigil_http_requests_in_flight",
        "vigil_scenarios_loaded",
    ] {
        assert!(metrics.contains(name), "{name} missing from\n{metrics}");
    }
}

fn small_spec(speed: f64) -> Value {
    json!({
        "name": "durable", "zone": {"width": 100, "height": 100}, "cell_size": 10,
        "fov": {"shape": "circle", "radius": 20}, "target_speed": speed,
        "sources": [{"x": 50, "y": -3, "rate": 0.4}]
    })
}

#[tokio::test]
async fn scenarios_survive_kill_9_and_corrupt_files_are_skipped() {
    let dir = temp_dir("durable");
    let client = reqwest::Client::new();
    let id = {
        let server = Server::start(&dir);
        let res = client
            .post(format!("{}/v1/scenarios", server.address))
            .json(&small_spec(7.0))
            .send()
            .await
            .unwrap();
        assert_eq!(res.status(), StatusCode::CREATED);
        let id = res.json::<Value>().await.unwrap()["id"]
            .as_str()
            .unwrap()
            .to_owned();
        // A second one, deleted before the kill: it must stay deleted.
        let gone = client
            .post(format!("{}/v1/scenarios", server.address))
            .json(&small_spec(9.0))
            .send()
            .await
            .unwrap()
            .json::<Value>()
            .await
            .unwrap()["id"]
            .as_str()
            .unwrap()
            .to_owned();
        let del = client
            .delete(format!("{}/v1/scenarios/{gone}", server.address))
            .send()
            .await
            .unwrap();
        assert_eq!(del.status(), StatusCode::NO_CONTENT);
        id
        // Dropping the server sends SIGKILL: no chance to flush anything.
    };
    std::fs::write(
        dir.join("s-0123456789abcdef.json"),
        b"{\"format\":1,\"id\":\"s-01",
    )
    .unwrap();
    std::fs::write(dir.join("notes.json"), b"[\"not a scenario\"]").unwrap();
    let server = Server::start(&dir);
    let res = client
        .get(format!("{}/v1/scenarios/{id}", server.address))
        .send()
        .await
        .unwrap();
    assert_eq!(res.status(), StatusCode::OK);
    let list: Value = client
        .get(format!("{}/v1/scenarios", server.address))
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    // The built-ins and the surviving scenario; the corrupt files are
    // skipped but left in place.
    assert_eq!(
        list["scenarios"].as_array().unwrap().len(),
        vigil::scenario::BUILTIN_IDS.len() + 1,
        "{list}"
    );
    assert!(dir.join("notes.json").exists());
    drop(server);
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigterm_finishes_the_plan_in_flight_then_exits_0() {
    // Found (or installed) first: the signal must come while the plan runs.
    let kill = vigil_testenv::kill();
    let dir = temp_dir("shutdown");
    let mut server = Server::start_with(&dir, &["--max-plan-ms", "0"]);
    let url = format!("{}/v1/scenarios/paper-v10/plan", server.address);
    // A plan of seconds, well over the delay below.
    let body = heavy_plan();
    let idle = cpu_seconds(server.child.id());
    let started = std::time::Instant::now();
    let in_flight = tokio::spawn(async move {
        let res = reqwest::Client::new().post(url).json(&body).send().await;
        (res, started.elapsed())
    });
    // Signalled once the plan runs (its request read whole).
    let child = server.child.id();
    tokio::task::spawn_blocking(move || wait_busy(child, idle, 0.2))
        .await
        .unwrap();
    let pid = server.child.id().to_string();
    let signalled = started.elapsed();
    let killed = Command::new(kill).args(["-TERM", &pid]).status().unwrap();
    assert!(killed.success());
    let (res, answered) = in_flight.await.unwrap();
    let res = res.expect("the in-flight plan completes");
    assert_eq!(res.status(), StatusCode::OK);
    assert!(
        answered > signalled,
        "the plan ended before the signal ({answered:?} ≤ {signalled:?})"
    );
    assert!(res.json::<Value>().await.unwrap()["plans"].is_array());
    let status = tokio::task::spawn_blocking(move || {
        let status = server.child.wait();
        (status, server)
    })
    .await
    .unwrap()
    .0
    .unwrap();
    assert!(status.success(), "exit status {status:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Precomputation runs on a pool of its own: five plans sent while a large
/// scenario (2.25 million cells) is being registered finish first. (With no
/// synchronous budget, so the registration itself waits for it.)
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn registering_a_large_scenario_does_not_stall_plans() {
    let app = spawn_with(Settings {
        sync_precompute_ms: f64::INFINITY,
        ..Settings::default()
    })
    .await;
    let spec = json!({
        "zone": {"width": 300, "height": 300}, "cell_size": 0.2,
        "fov": {"shape": "square", "half_width": 30}, "target_speed": 10,
        "sources": [{"x": -1, "y": 100, "rate": 0.3}, {"x": 301, "y": 200, "rate": 0.3},
                    {"x": 100, "y": -1, "rate": 0.3}, {"x": 200, "y": 301, "rate": 0.3}]
    });
    let (client, url) = (app.client.clone(), app.url("/v1/scenarios"));
    let register = tokio::spawn(async move {
        let res = client.post(url).json(&spec).send().await.unwrap();
        (res.status(), std::time::Instant::now())
    });
    let mut planned = std::time::Instant::now();
    for _ in 0..5 {
        tokio::time::sleep(Duration::from_millis(100)).await;
        let plan = app
            .post_json(
                "/v1/scenarios/paper-v10/plan",
                &json!({"sensors": [{"id": 1, "x": 155, "y": 155}, {"id": 2, "x": 35, "y": 35}]}),
            )
            .await;
        planned = std::time::Instant::now();
        assert_eq!(plan.status(), StatusCode::OK);
    }
    let (status, registered) = register.await.unwrap();
    assert_eq!(status, StatusCode::CREATED);
    assert!(
        planned < registered,
        "the plan waited for the registration to finish"
    );
}

/// `THP_enabled` of process `pid` (`/proc/PID/status`): 0 once the process
/// turned transparent huge pages off for itself.
fn thp_enabled(pid: &str) -> String {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).expect("/proc/PID/status");
    let line = status.lines().find_map(|l| l.strip_prefix("THP_enabled:"));
    line.expect("a THP_enabled line").trim().to_owned()
}

#[test]
fn the_server_turns_huge_pages_off_unless_asked() {
    let dir = temp_dir("huge-pages");
    let server = Server::start(&dir);
    assert_eq!(thp_enabled(&server.child.id().to_string()), "0");
    drop(server);
    // With the flag it keeps what it inherited, as this process has it.
    let server = Server::start_with(&dir, &["--huge-pages"]);
    let inherited = thp_enabled("self");
    assert_eq!(thp_enabled(&server.child.id().to_string()), inherited);
}
