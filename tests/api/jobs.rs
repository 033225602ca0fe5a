//! Precomputation as a job: a scenario above the synchronous budget is
//! accepted at once (202) and precomputed in the background with progress;
//! plans wait with 503 and Retry-After; it ends `ready` with the statistics
//! a synchronous precompute gives; DELETE cancels it (the CPU stops); a
//! restart resumes it; the queue is bounded; an inline scenario above the
//! budget is refused; a synchronous registration nobody waits for stops and
//! is not stored.

use std::time::{Duration, Instant};

use reqwest::{StatusCode, header};
use serde_json::{Value, json};
use vigil::http::config::Settings;
use vigil::planner::Planner;
use vigil::scenario::{BUILTIN_IDS, Scenario, ScenarioSpec};

use crate::helpers::{
    Server, TestApp, assert_problem, cpu_seconds, json_body, metric, spawn_with, temp_dir,
};

/// A scenario with circular fields of view (the costly general path) on a
/// `side`×`side` lattice of a 300×300 zone: about 1 s of CPU for 300, 4 s
/// for 600. `rate` tells specs apart.
fn circles(side: u32, rate: f64) -> Value {
    let cell = 300.0 / side as f64;
    json!({
        "zone": {"width": 300, "height": 300}, "cell_size": cell,
        "fov": {"shape": "circle", "radius": 10}, "target_speed": 10,
        "sources": [{"x": -1, "y": 100, "rate": rate}, {"x": 301, "y": 200, "rate": 0.3},
                    {"x": 100, "y": -1, "rate": 0.3}, {"x": 200, "y": 301, "rate": 0.3}]
    })
}

/// Every registration is a job.
async fn jobs_app(jobs: usize, queue: usize) -> TestApp {
    spawn_with(Settings {
        sync_precompute_ms: 0.0,
        precompute_jobs: jobs,
        precompute_queue: queue,
        ..Settings::default()
    })
    .await
}

/// Registers `spec`, expecting 202 and a Location; returns the path and
/// the body.
async fn accepted(address: &str, spec: &Value) -> (String, Value) {
    let res = reqwest::Client::new()
        .post(format!("{address}/v1/scenarios"))
        .json(spec)
        .send()
        .await
        .unwrap();
    let location = res
        .headers()
        .get(header::LOCATION)
        .map(|v| v.to_str().unwrap().to_owned());
    let body = json_body(res, StatusCode::ACCEPTED).await;
    let location = location.expect("a Location header");
    assert_eq!(
        location,
        format!("/v1/scenarios/{}", body["id"].as_str().unwrap())
    );
    assert!(body.get("summary").is_none(), "{body}");
    (location, body)
}

async fn status(address: &str, path: &str) -> Value {
    let res = reqwest::get(format!("{address}{path}")).await.unwrap();
    json_body(res, StatusCode::OK).await
}

/// Polls until `status` is `want`, or panics after `within`.
async fn wait_status(address: &str, path: &str, want: &str, within: Duration) -> Value {
    let started = Instant::now();
    loop {
        let body = status(address, path).await;
        if body["status"] == want {
            return body;
        }
        assert!(started.elapsed() < within, "still {body} after {within:?}");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

fn retry_after(res: &reqwest::Response) -> u64 {
    res.headers()
        .get(header::RETRY_AFTER)
        .expect("Retry-After")
        .to_str()
        .unwrap()
        .parse()
        .expect("Retry-After in whole seconds")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_reports_progress_and_ends_with_the_synchronous_statistics() {
    let app = jobs_app(1, 16).await;
    let spec = circles(300, 0.3);
    let sent = Instant::now();
    let (path, body) = accepted(&app.address, &spec).await;
    assert!(
        sent.elapsed() < Duration::from_millis(500),
        "202 after {:?}",
        sent.elapsed()
    );
    assert!(["queued", "precomputing"].contains(&body["status"].as_str().unwrap()));
    assert!(body["predicted_precompute_ms"].as_f64().unwrap() > 0.0);
    // Posting it again while pending: the same job, 202 again.
    let again = app.post_json("/v1/scenarios", &spec).await;
    assert_eq!(again.status(), StatusCode::ACCEPTED);

    let mut progress = Vec::new();
    let mut refused_plan = false;
    loop {
        let body = status(&app.address, &path).await;
        match body["status"].as_str().unwrap() {
            "ready" => break,
            "precomputing" => {
                let p = body["progress"].as_f64().unwrap();
                assert!((0.0..=1.0).contains(&p), "{body}");
                assert!(body["eta_s"].as_f64().unwrap() >= 0.0, "{body}");
                progress.push(p);
                if !refused_plan {
                    let plan = app
                        .post_json(
                            &format!("{path}/plan"),
                            &json!({"sensors": [{"id": 1, "x": 150, "y": 150}]}),
                        )
                        .await;
                    assert!(retry_after(&plan) >= 1);
                    let problem =
                        assert_problem(plan, StatusCode::SERVICE_UNAVAILABLE, "precomputing").await;
                    assert!(
                        problem["type"]
                            .as_str()
                            .unwrap()
                            .ends_with("/scenario-not-ready")
                    );
                    let stats = app.get(&format!("{path}/stats")).await;
                    assert_eq!(stats.status(), StatusCode::SERVICE_UNAVAILABLE);
                    assert!(retry_after(&stats) >= 1);
                    refused_plan = true;
                }
            }
            "queued" => {}
            other => panic!("status {other}"),
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    assert!(refused_plan, "never saw it precomputing");
    assert!(
        progress.windows(2).all(|w| w[0] <= w[1]),
        "progress went back: {progress:?}"
    );
    let inside = progress.iter().filter(|&&p| p > 0.0 && p < 1.0).count();
    assert!(
        progress.first() < progress.last() && inside >= 2,
        "progress did not rise: {progress:?}"
    );

    let ready = status(&app.address, &path).await;
    assert_eq!(ready["progress"], 1.0);
    assert!(ready.get("eta_s").is_none());
    assert!(ready["summary"]["precompute_ms"].as_f64().unwrap() > 0.0);
    let plan = app
        .post_json(
            &format!("{path}/plan"),
            &json!({"sensors": [{"id": 1, "x": 150, "y": 150}]}),
        )
        .await;
    assert_eq!(plan.status(), StatusCode::OK);

    // The statistics equal a synchronous precompute's, bit for bit: the
    // same shortest round-trip text of every number.
    let served = app.get(&format!("{path}/stats")).await;
    assert_eq!(served.status(), StatusCode::OK);
    let served = served.text().await.unwrap();
    let spec: ScenarioSpec = serde_json::from_value(spec).unwrap();
    let planner = tokio::task::spawn_blocking(move || Planner::new(Scenario::new(spec).unwrap()))
        .await
        .unwrap();
    let stats = &planner.stats[0];
    for (name, values) in [
        ("lambda_hat", &stats.lambda_hat),
        ("escape_time", &stats.escape_time),
        ("d_hat", &stats.d_hat),
    ] {
        let expected = format!("\"{name}\":{}", serde_json::to_string(values).unwrap());
        assert!(
            served.contains(&expected),
            "{name} differs from a synchronous precompute"
        );
    }
    assert_eq!(
        ready["summary"]["expected_targets_in_zone"],
        json!(stats.expected_targets_in_zone)
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_queue_is_bounded_and_delete_cancels_a_job() {
    let app = jobs_app(1, 1).await;
    let (first, body) = accepted(&app.address, &circles(600, 0.31)).await;
    assert_eq!(body["status"], "precomputing");
    let (second, body) = accepted(&app.address, &circles(600, 0.32)).await;
    assert_eq!(body["status"], "queued", "{body}");
    assert_eq!(body["queue_position"], 1, "{body}");
    assert!(
        body["eta_s"].as_f64().unwrap() >= body["predicted_precompute_ms"].as_f64().unwrap() / 1e3,
        "{body}"
    );
    // Past the queue's bound: 503 with Retry-After, and nothing stored.
    let third = app.post_json("/v1/scenarios", &circles(600, 0.33)).await;
    assert!(retry_after(&third) >= 1);
    let problem = assert_problem(third, StatusCode::SERVICE_UNAVAILABLE, "waiting").await;
    assert!(
        problem["type"]
            .as_str()
            .unwrap()
            .ends_with("/precompute-queue-full")
    );
    let list = json_body(app.get("/v1/scenarios").await, StatusCode::OK).await;
    let statuses: Vec<&str> = list["scenarios"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["status"] != "ready")
        .map(|s| s["status"].as_str().unwrap())
        .collect();
    assert_eq!(statuses.len(), 2, "{list}");

    // Deleting the running job frees its slot: the queued one starts.
    assert_eq!(app.delete(&first).await.status(), StatusCode::NO_CONTENT);
    assert_eq!(app.get(&first).await.status(), StatusCode::NOT_FOUND);
    wait_status(
        &app.address,
        &second,
        "precomputing",
        Duration::from_secs(10),
    )
    .await;
    assert_eq!(app.delete(&second).await.status(), StatusCode::NO_CONTENT);
    assert_eq!(app.get(&second).await.status(), StatusCode::NOT_FOUND);
    assert!(
        metric(
            &app.address,
            "vigil_cancelled_total",
            &["kind=\"precompute\"", "reason=\"deleted\""]
        )
        .await
            >= 2.0
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_inline_scenario_above_the_budget_is_refused() {
    let app = jobs_app(1, 16).await;
    let res = app
        .post_json(
            "/v1/plan",
            &json!({"scenario": crate::helpers::small_spec(),
                    "sensors": [{"id": 1, "x": 50, "y": 50}]}),
        )
        .await;
    let problem = assert_problem(res, StatusCode::UNPROCESSABLE_ENTITY, "POST /v1/scenarios").await;
    let detail = problem["detail"].as_str().unwrap();
    assert!(detail.contains("predicted to take"), "{detail}");
    assert!(
        problem["type"]
            .as_str()
            .unwrap()
            .ends_with("/precompute-too-costly"),
        "{problem}"
    );
    // Named by id, a ready scenario is served as before.
    let res = app
        .post_json(
            "/v1/plan",
            &json!({"scenario_id": "paper-v10", "sensors": [{"id": 1, "x": 50, "y": 50}]}),
        )
        .await;
    assert_eq!(res.status(), StatusCode::OK);
}

/// Waits until the job at `path` has done `at_least` of its blocks.
async fn wait_progress(address: &str, path: &str, at_least: f64) -> Value {
    let started = Instant::now();
    loop {
        let body = status(address, path).await;
        if body["status"] == "precomputing" && body["progress"].as_f64().unwrap() >= at_least {
            return body;
        }
        assert!(
            body["status"] != "ready",
            "finished before {at_least}: {body}"
        );
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "no progress: {body}"
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn deleting_a_job_stops_its_cpu_within_a_second() {
    let dir = temp_dir("job-delete");
    let server = Server::start_with(&dir, &["--sync-precompute-ms", "0"]);
    let pid = server.child.id();
    let (path, _) = accepted(&server.address, &circles(600, 0.3)).await;
    wait_progress(&server.address, &path, 0.1).await;
    let res = reqwest::Client::new()
        .delete(format!("{}{path}", server.address))
        .send()
        .await
        .unwrap();
    assert_eq!(res.status(), StatusCode::NO_CONTENT);
    let deleted = Instant::now();
    // Busy up to now; idle in the half second after the first second.
    let a = tokio::task::spawn_blocking(move || {
        std::thread::sleep(Duration::from_secs(1).saturating_sub(deleted.elapsed()));
        let a = cpu_seconds(pid);
        std::thread::sleep(Duration::from_millis(500));
        cpu_seconds(pid) - a
    })
    .await
    .unwrap();
    assert!(
        a <= 0.03,
        "{a} s of CPU in the 500 ms from 1 s after the DELETE"
    );
    let res = reqwest::get(format!("{}{path}", server.address))
        .await
        .unwrap();
    assert_eq!(res.status(), StatusCode::NOT_FOUND);
    // Not stored either: nothing in the data directory.
    let files = std::fs::read_dir(&dir).unwrap().count();
    assert_eq!(files, 0, "the data directory still holds the scenario");
    drop(server);
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_restart_resumes_an_unfinished_job() {
    let dir = temp_dir("job-restart");
    let args = ["--sync-precompute-ms", "0"];
    let server = Server::start_with(&dir, &args);
    let spec = circles(600, 0.3);
    let (path, _) = accepted(&server.address, &spec).await;
    wait_progress(&server.address, &path, 0.2).await;
    // kill -9: no chance to finish or to write anything more.
    drop(server);

    let server = Server::start_with(&dir, &args);
    let body = status(&server.address, &path).await;
    assert!(
        ["queued", "precomputing"].contains(&body["status"].as_str().unwrap()),
        "{body}"
    );
    let ready = wait_status(&server.address, &path, "ready", Duration::from_secs(60)).await;
    assert_eq!(ready["spec"], status(&server.address, &path).await["spec"]);
    let plan = reqwest::Client::new()
        .post(format!("{}{path}/plan", server.address))
        .json(&json!({"sensors": [{"id": 1, "x": 150, "y": 150}]}))
        .send()
        .await
        .unwrap();
    assert_eq!(plan.status(), StatusCode::OK);
    drop(server);
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_synchronous_registration_nobody_waits_for_stops_and_is_not_stored() {
    let dir = temp_dir("sync-timeout");
    let server = Server::start_with(
        &dir,
        &[
            "--sync-precompute-ms",
            "1000000000",
            "--request-timeout-ms",
            "500",
        ],
    );
    let pid = server.child.id();
    let before = cpu_seconds(pid);
    let sent = Instant::now();
    let res = reqwest::Client::new()
        .post(format!("{}/v1/scenarios", server.address))
        .json(&circles(600, 0.3))
        .send()
        .await
        .unwrap();
    assert_eq!(res.status(), StatusCode::GATEWAY_TIMEOUT);
    assert!(
        sent.elapsed() <= Duration::from_millis(600),
        "{:?}",
        sent.elapsed()
    );
    let at_504 = Instant::now();
    assert!(cpu_seconds(pid) - before >= 0.1, "too light to test");
    let after = tokio::task::spawn_blocking(move || crate::helpers::cpu_after(pid, at_504))
        .await
        .unwrap();
    assert!(after <= 0.03, "{after} s of CPU from 200 ms after the 504");
    let list = status(&server.address, "/v1/scenarios").await;
    assert!(
        list["scenarios"]
            .as_array()
            .unwrap()
            .iter()
            .all(|s| BUILTIN_IDS.contains(&s["id"].as_str().unwrap())),
        "{list}"
    );
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    assert_eq!(
        metric(
            &server.address,
            "vigil_cancelled_total",
            &["kind=\"precompute\"", "reason=\"timeout\""]
        )
        .await,
        1.0
    );
    drop(server);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A running job does not hold up a small registration: jobs have a pool
/// of their own, and the small one is answered while the job goes on.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_small_registration_is_not_queued_behind_a_job() {
    let app = spawn_with(Settings {
        sync_precompute_ms: 50.0,
        ..Settings::default()
    })
    .await;
    let (path, _) = accepted(&app.address, &circles(600, 0.34)).await;
    wait_progress(&app.address, &path, 0.05).await;
    let sent = Instant::now();
    let res = app
        .post_json("/v1/scenarios", &crate::helpers::small_spec())
        .await;
    let took = sent.elapsed();
    let body = json_body(res, StatusCode::CREATED).await;
    assert_eq!(body["status"], "ready");
    let job = status(&app.address, &path).await;
    assert_eq!(job["status"], "precomputing", "the job ended first: {job}");
    assert!(took < Duration::from_secs(1), "201 after {took:?}");
    assert_eq!(app.delete(&path).await.status(), StatusCode::NO_CONTENT);
}

/// A learning session precomputes its scenario again as its rates move,
/// inline: past the synchronous budget it is refused (422 naming
/// `learn_rates`), while a plain session of the same scenario is opened.
#[tokio::test]
async fn a_learning_session_over_the_inline_budget_is_refused() {
    let app = jobs_app(1, 4).await;
    let res = app
        .post_json(
            "/v1/sessions",
            &json!({"scenario_id": "paper-v10", "learn_rates": true}),
        )
        .await;
    let body = assert_problem(res, StatusCode::UNPROCESSABLE_ENTITY, "learn_rates").await;
    assert!(
        body["detail"]
            .as_str()
            .is_some_and(|d| d.contains("--sync-precompute-ms")),
        "{body}"
    );
    let res = app
        .post_json("/v1/sessions", &json!({"scenario_id": "paper-v10"}))
        .await;
    assert_eq!(res.status(), StatusCode::CREATED);
}
