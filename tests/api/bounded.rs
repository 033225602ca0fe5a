//! Work nobody waits for stops: a plan that would run for seconds, against
//! a real `vigil-server` process whose request time limit is short, answers
//! 504 within the limit plus 100 ms, and the process's CPU time (read from
//! /proc, not from the server's word) stops growing within 200 ms after;
//! the same when the client drops the connection instead.

use std::time::{Duration, Instant};

use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::helpers::{Server, temp_dir};

/// Clock ticks per second of /proc's CPU times (`getconf CLK_TCK`; 100 on
/// Linux).
const TICKS_PER_S: f64 = 100.0;

/// The process's CPU time (user + system), seconds, from /proc/PID/stat.
fn cpu_seconds(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("/proc/PID/stat");
    // The command name (field 2) may hold spaces: count from after it.
    let rest = &stat[stat.rfind(')').expect("a command name") + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the whole line.
    let ticks: u64 = fields[11].parse::<u64>().unwrap() + fields[12].parse::<u64>().unwrap();
    ticks as f64 / TICKS_PER_S
}

/// A plan on `paper-v10` that runs for seconds: 256 sensors, horizon 12,
/// iterated coordination, 4 000 targets and 8 steps of history.
fn heavy_plan() -> Value {
    let sensors: Vec<Value> = (0..256)
        .map(|i| json!({"id": i, "x": 5.0 + (i % 16) as f64 * 18.0, "y": 5.0 + (i / 16) as f64 * 18.0}))
        .collect();
    let targets: Vec<Value> = (0..4000)
        .map(|i| {
            let f = i as f64;
            json!({"x": (f * 7.3) % 300.0, "y": (f * 13.7) % 300.0, "vx": (f % 7.0) - 3.0, "vy": (f % 5.0) - 2.0})
        })
        .collect();
    let history: Vec<Value> = (1..=8)
        .map(|s| {
            let step: Vec<Value> = (0..256)
                .map(|i| {
                    json!({"x": (5.0 + (i % 16) as f64 * 18.0 + s as f64) % 300.0,
                           "y": 5.0 + (i / 16) as f64 * 18.0})
                })
                .collect();
            json!(step)
        })
        .collect();
    json!({"sensors": sensors, "targets": targets, "history": history, "horizon": 12,
           "coordination": "iterated"})
}

/// Waits until the server has used `busy` seconds of CPU over what it had
/// at `before` (so the plan is running), or panics after 10 s.
fn wait_busy(pid: u32, before: f64, busy: f64) {
    let started = Instant::now();
    while cpu_seconds(pid) < before + busy {
        assert!(
            started.elapsed() < Duration::from_secs(10),
            "the plan never ran"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// CPU used between 200 ms and 700 ms after `since`: the work must have
/// stopped by the first reading.
fn cpu_after(pid: u32, since: Instant) -> f64 {
    std::thread::sleep(Duration::from_millis(200).saturating_sub(since.elapsed()));
    let a = cpu_seconds(pid);
    std::thread::sleep(Duration::from_millis(500));
    cpu_seconds(pid) - a
}

async fn cancelled_count(address: &str, reason: &str) -> f64 {
    let text = reqwest::get(format!("{address}/metrics"))
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    text.lines()
        .find(|l| {
            l.starts_with("vigil_cancelled_total")
                && l.contains("kind=\"plan\"")
                && l.contains(&format!("reason=\"{reason}\""))
        })
        .and_then(|l| l.rsplit(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.0)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plan_stops_when_its_time_is_up() {
    let dir = temp_dir("timeout-cpu");
    let server = Server::start_with(&dir, &["--request-timeout-ms", "400"]);
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
    let server = Server::start_with(&dir, &["--request-timeout-ms", "30000"]);
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
    let left = Instant::now();
    let _ = request.await;
    let after = cpu_after(pid, left);
    assert!(
        after <= 0.03,
        "{after} s of CPU in the 500 ms from 200 ms after the client left"
    );
    assert_eq!(cancelled_count(&server.address, "client_gone").await, 1.0);
    let _ = std::fs::remove_dir_all(&dir);
}
