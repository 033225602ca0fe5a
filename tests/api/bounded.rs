//! Work nobody waits for stops: a plan that would run for seconds, against
//! a real `vigil-server` process whose request time limit is short, answers
//! 504 within the limit plus 100 ms, and the process's CPU time (read from
//! /proc, not from the server's word) stops growing within 200 ms after;
//! the same when the client drops the connection instead.

use std::time::{Duration, Instant};

use reqwest::StatusCode;

use crate::helpers::{Server, cpu_after, cpu_seconds, heavy_plan, temp_dir, wait_busy};

async fn cancelled_count(address: &str, reason: &str) -> f64 {
    crate::helpers::metric(
        address,
        "vigil_cancelled_total",
        &["kind=\"plan\"", &format!("reason=\"{reason}\"")],
    )
    .await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plan_stops_when_its_time_is_up() {
    let dir = temp_dir("timeout-cpu");
    let server = Server::start_with(&dir, &["--request-timeout-ms", "400", "--max-plan-ms", "0"]);
    let pid = server.child.id();
    let body = heavy_plan();
    let client = reqwest::Client::new();
    let url = format!("{}/v1/scenarios/paper-v10/plan", server.address);
    let before = cpu_seconds(pid);
    let sent = Instant::now();
    let res = client.post(&url).json(&body).send().await.unwrap();
    let answered = sent.elapsed();
    assert_eq!(res.status(), StatusCode::GATEWAY_TIMEOUT);
    assert!(
        answered <= Duration::from_millis(500),
        "504 after {answered:?} for a 400 ms limit"
    );
    let at_504 = Instant::now();
    let used = cpu_seconds(pid) - before;
    assert!(
        used >= 0.2,
        "the plan used only {used} s of CPU: too light to test"
    );
    let after = cpu_after(pid, at_504);
    assert!(
        after <= 0.03,
        "{after} s of CPU in the 500 ms from 200 ms after the 504"
    );
    assert_eq!(cancelled_count(&server.address, "timeout").await, 1.0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plan_stops_when_its_client_leaves() {
    let dir = temp_dir("client-gone-cpu");
    let server = Server::start_with(
        &dir,
        &["--request-timeout-ms", "30000", "--max-plan-ms", "0"],
    );
    let pid = server.child.id();
    let body = heavy_plan();
    let url = format!("{}/v1/scenarios/paper-v10/plan", server.address);
    let before = cpu_seconds(pid);
    let request = tokio::spawn(async move {
        reqwest::Client::new()
            .post(&url)
            .json(&body)
            .send()
            .await
            .map(|r| r.status())
    });
    // Leave once the plan is well under way.
    let pid_copy = pid;
    tokio::task::spawn_blocking(move || wait_busy(pid_copy, before, 0.3))
        .await
        .unwrap();
    request.abort();
    let _ = request.await;
    // The server learns that the client left when it next polls the
    // connection, which on a loaded machine may be late: measure from the
    // moment it has counted the cancellation, not from the abort.
    let left = Instant::now();
    while cancelled_count(&server.address, "client_gone").await < 1.0 {
        assert!(
            left.elapsed() < Duration::from_secs(10),
            "the server never counted the client's departure"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let counted = Instant::now();
    let after = tokio::task::spawn_blocking(move || cpu_after(pid, counted))
        .await
        .unwrap();
    assert!(
        after <= 0.03,
        "{after} s of CPU in the 500 ms from 200 ms after the server counted the client's departure"
    );
    assert_eq!(cancelled_count(&server.address, "client_gone").await, 1.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Plans are admitted by their predicted cost: one predicted above
/// `--max-plan-ms` is refused with 422 before any work (the process's CPU
/// barely moves: reading and checking the body), one below it is served.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plan_predicted_above_the_limit_is_refused_before_any_work() {
    let dir = temp_dir("cost-limit");
    let server = Server::start_with(&dir, &["--max-plan-ms", "500"]);
    let pid = server.child.id();
    let body = heavy_plan();
    let client = reqwest::Client::new();
    let url = format!("{}/v1/scenarios/paper-v10/plan", server.address);
    let before = cpu_seconds(pid);
    let res = client.post(&url).json(&body).send().await.unwrap();
    let problem = crate::helpers::assert_problem(
        res,
        StatusCode::UNPROCESSABLE_ENTITY,
        "above this server's limit of 500 ms",
    )
    .await;
    assert!(
        problem["type"]
            .as_str()
            .unwrap()
            .ends_with("/plan-too-costly")
    );
    let used = cpu_seconds(pid) - before;
    assert!(used <= 0.1, "{used} s of CPU to refuse a plan");
    assert_eq!(
        crate::helpers::metric(
            &server.address,
            "vigil_plans_refused_total",
            &["reason=\"cost\""]
        )
        .await,
        1.0
    );
    let res = client
        .post(&url)
        .json(&crate::helpers::plan_request())
        .send()
        .await
        .unwrap();
    assert_eq!(res.status(), StatusCode::OK);
    let _ = std::fs::remove_dir_all(&dir);
}
