//! Session mode over HTTP: the per-session ordering of the steps against a
//! fake server that detects overlaps, the waits counted in the latency,
//! and a short end-to-end run of the binary against the app in process.

use std::collections::{BTreeSet, HashMap};
use std::process::Output;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::Router;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, StatusCode};
use axum::routing::{delete, post};
use bytes::Bytes;
use tokio::net::TcpListener;
use vigil::catalog::Registry;
use vigil::http::config::Settings;
use vigil::http::{AppState, router};
use vigil_loadtest::generator::{RunConfig, SessionTarget, Summary, Target, run};
use vigil_loadtest::schedule::Arrivals;

/// What the fake session server saw.
#[derive(Default)]
struct Seen {
    next_id: AtomicU64,
    /// Per session: the bodies of its steps in arrival order, and whether
    /// a step is in flight.
    sessions: Mutex<HashMap<String, (Vec<String>, bool)>>,
    overlaps: AtomicU64,
    deleted: AtomicU64,
    /// Per session: which listener served each step.
    served_by: Mutex<HashMap<String, Vec<usize>>>,
    /// Per session: the `Idempotency-Key` of each step, if it had one.
    keys: Mutex<HashMap<String, Vec<Option<String>>>>,
}

/// A server with the session routes: each step takes `service` plus a few
/// ms that vary with the session and the step, and counts the steps that
/// arrive while their session is busy.
async fn fake_sessions(service: Duration) -> (String, Arc<Seen>) {
    let seen = Arc::new(Seen::default());
    let base = listen(fake_app(&seen, service, 0)).await;
    (base, seen)
}

/// `replicas` fake servers sharing their sessions, as replicas on one
/// database do.
async fn fake_replicas(service: Duration, replicas: usize) -> (Vec<String>, Arc<Seen>) {
    let seen = Arc::new(Seen::default());
    let mut bases = Vec::new();
    for i in 0..replicas {
        bases.push(listen(fake_app(&seen, service, i)).await);
    }
    (bases, seen)
}

async fn listen(app: Router) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").await.expect("bind");
    let addr = listener.local_addr().expect("addr");
    tokio::spawn(async move {
        axum::serve(listener, app).await.expect("serve");
    });
    format!("http://{addr}")
}

/// The fake server's routes, as listener `index` serves them.
fn fake_app(seen: &Arc<Seen>, service: Duration, index: usize) -> Router {
    Router::new()
        .route(
            "/v1/sessions",
            post(|State(seen): State<Arc<Seen>>| async move {
                let id = format!("f{}", seen.next_id.fetch_add(1, Ordering::SeqCst));
                seen.sessions
                    .lock()
                    .expect("lock")
                    .insert(id.clone(), (Vec::new(), false));
                (StatusCode::CREATED, format!("{{\"id\":\"{id}\"}}"))
            }),
        )
        .route(
            "/v1/sessions/{id}/step",
            post(
                move |State(seen): State<Arc<Seen>>,
                      Path(id): Path<String>,
                      headers: HeaderMap,
                      body: String| async move {
                    let key = headers
                        .get("idempotency-key")
                        .map(|v| v.to_str().expect("a text key").to_owned());
                    seen.keys
                        .lock()
                        .expect("lock")
                        .entry(id.clone())
                        .or_default()
                        .push(key);
                    let n = {
                        let mut map = seen.sessions.lock().expect("lock");
                        let Some((bodies, busy)) = map.get_mut(&id) else {
                            return StatusCode::NOT_FOUND;
                        };
                        if *busy {
                            seen.overlaps.fetch_add(1, Ordering::SeqCst);
                        }
                        *busy = true;
                        bodies.push(body);
                        let n = bodies.len() as u64;
                        seen.served_by
                            .lock()
                            .expect("lock")
                            .entry(id.clone())
                            .or_default()
                            .push(index);
                        n
                    };
                    let jitter = Duration::from_millis((n * 7 + id.len() as u64) % 13);
                    tokio::time::sleep(service + jitter).await;
                    if let Some((_, busy)) = seen.sessions.lock().expect("lock").get_mut(&id) {
                        *busy = false;
                    }
                    StatusCode::OK
                },
            ),
        )
        .route(
            "/v1/sessions/{id}",
            delete(
                |State(seen): State<Arc<Seen>>, Path(id): Path<String>| async move {
                    let gone = seen.sessions.lock().expect("lock").remove(&id).is_some();
                    seen.deleted.fetch_add(1, Ordering::SeqCst);
                    if gone {
                        StatusCode::NO_CONTENT
                    } else {
                        StatusCode::NOT_FOUND
                    }
                },
            ),
        )
        .with_state(Arc::clone(seen))
}

fn target(base: &str, warmup: usize, steps: usize, sessions: usize) -> Target {
    replicated(&[base.to_owned()], warmup, steps, sessions)
}

/// Sessions opened through `bases[0]`, their steps spread over `bases`.
fn replicated(bases: &[String], warmup: usize, steps: usize, sessions: usize) -> Target {
    keyed(bases, warmup, steps, sessions, false)
}

/// [`replicated`], its timed steps with an `Idempotency-Key` if `keys`.
fn keyed(bases: &[String], warmup: usize, steps: usize, sessions: usize, keys: bool) -> Target {
    let body = |s: String| Bytes::from(s);
    let base = &bases[0];
    Target::Session(Arc::new(SessionTarget {
        sessions_url: format!("{base}/v1/sessions"),
        step_url: format!("{base}/v1/sessions/{{id}}/step"),
        bases: bases.to_vec(),
        create: Bytes::from_static(b"{}"),
        warmup: (0..warmup).map(|i| body(format!("w{i}"))).collect(),
        steps: (0..steps).map(|i| body(format!("s{i}"))).collect(),
        sessions,
        idempotency_keys: keys,
    }))
}

fn config(target: Target, rate: f64, duration_ms: u64, connections: usize) -> RunConfig {
    RunConfig {
        target,
        rate,
        arrivals: Arrivals::Constant,
        duration: Duration::from_millis(duration_ms),
        warmup: Duration::ZERO,
        connections,
        seed: 3,
        timeout: Duration::from_secs(10),
        api_key: None,
    }
}

/// 3 sessions at 150/s: a session's steps come every 20 ms, and take 5 to
/// 17 ms, so over 8 connections they would overlap if not held back. Every
/// session sees its warm-up, then its own steps in order, cycled, never
/// two at once; the sessions are closed at the end.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_sessions_steps_never_overlap_and_come_in_order() {
    let (base, seen) = fake_sessions(Duration::from_millis(5)).await;
    let cfg = config(target(&base, 2, 4, 3), 150.0, 1000, 8);
    let r = run(&cfg).await.expect("run");
    let s = r.summary;
    assert_eq!((s.errors, s.shed), (0, 0), "{}", r.describe());
    assert_eq!(s.requests, 150, "{}", r.describe());
    assert_eq!(seen.overlaps.load(Ordering::SeqCst), 0);
    assert_eq!(seen.next_id.load(Ordering::SeqCst), 3);
    assert_eq!(seen.deleted.load(Ordering::SeqCst), 3);
    // All closed.
    assert!(seen.sessions.lock().expect("lock").is_empty());
    assert!(!r.session_wait.is_empty(), "{}", r.describe());
}

/// With `idempotency_keys`, every timed step of a session names itself by
/// a key of its own (a retry would reuse it), and the warm-up none;
/// without, no step has one.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn timed_steps_carry_keys_of_their_own_when_asked() {
    for keys in [true, false] {
        let (base, seen) = fake_sessions(Duration::from_millis(1)).await;
        let cfg = config(keyed(&[base], 2, 3, 2, keys), 100.0, 300, 4);
        let r = run(&cfg).await.expect("run");
        assert_eq!(r.summary.errors, 0, "{}", r.describe());
        let sent = seen.keys.lock().expect("lock").clone();
        assert_eq!(sent.len(), 2, "{sent:?}");
        for steps in sent.values() {
            let (warmup, timed) = steps.split_at(2);
            assert!(warmup.iter().all(Option::is_none), "{steps:?}");
            assert!(timed.len() >= 10, "{steps:?}");
            let named: BTreeSet<&String> = timed.iter().flatten().collect();
            let want = if keys { timed.len() } else { 0 };
            assert_eq!(named.len(), want, "{steps:?}");
        }
    }
}

/// The order of the bodies each session received, read while the run is
/// in flight (the sessions are closed at its end).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn each_session_walks_its_warm_up_then_its_steps_cycled() {
    let (base, seen) = fake_sessions(Duration::from_millis(2)).await;
    let cfg = config(target(&base, 2, 3, 2), 100.0, 600, 4);
    let seen2 = Arc::clone(&seen);
    // Snapshot the bodies just before the run ends (its last request is
    // intended at 590 ms and takes at most ~20 ms).
    let snap = tokio::spawn(async move {
        tokio::time::sleep(Duration::from_millis(400)).await;
        seen2
            .sessions
            .lock()
            .expect("lock")
            .values()
            .map(|(b, _)| b.clone())
            .collect::<Vec<_>>()
    });
    let r = run(&cfg).await.expect("run");
    assert_eq!(r.summary.errors, 0, "{}", r.describe());
    let bodies = snap.await.expect("snapshot");
    assert_eq!(bodies.len(), 2);
    for b in bodies {
        assert!(b.len() >= 2 + 4, "{b:?}");
        for (i, body) in b.iter().enumerate() {
            let want = if i < 2 {
                format!("w{i}")
            } else {
                format!("s{}", (i - 2) % 3)
            };
            assert_eq!(body, &want, "{b:?}");
        }
    }
    assert_eq!(seen.overlaps.load(Ordering::SeqCst), 0);
}

/// One session, a 50 ms step, 100 steps/s offered over 4 connections: the
/// steps run one at a time (20/s), and each one's wait for the previous
/// counts in its latency, as queueing does: median ~1 s, not 50 ms.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn steps_spread_over_replicas_as_a_load_balancer_does() {
    let (bases, seen) = fake_replicas(Duration::from_millis(1), 2).await;
    let r = run(&config(replicated(&bases, 2, 5, 3), 200.0, 300, 8))
        .await
        .expect("a run");
    assert_eq!(r.summary.errors, 0, "{}", r.describe());
    assert_eq!(seen.overlaps.load(Ordering::SeqCst), 0);
    let served = seen.served_by.lock().expect("lock").clone();
    assert_eq!(served.len(), 3);
    for (id, replicas) in &served {
        // Warm-up through the first; then each step on the replica the
        // step before was not.
        assert_eq!(replicas[..2], [0, 0], "{id}");
        let run = &replicas[2..];
        assert!(run.len() >= 4, "{id}: {replicas:?}");
        assert!(run.windows(2).all(|w| w[0] != w[1]), "{id}: {replicas:?}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_wait_for_the_sessions_previous_step_counts_in_the_latency() {
    let (base, seen) = fake_sessions(Duration::from_millis(50)).await;
    // 50 ms + up to 12 ms of jitter per step.
    let cfg = config(target(&base, 0, 5, 1), 100.0, 500, 4);
    let r = run(&cfg).await.expect("run");
    let s = r.summary;
    assert_eq!(s.requests, 50, "{}", r.describe());
    assert_eq!(s.errors, 0, "{}", r.describe());
    assert_eq!(seen.overlaps.load(Ordering::SeqCst), 0);
    assert!(s.p50_ms > 800.0, "{}", r.describe());
    assert!(s.p99_ms > 1700.0, "{}", r.describe());
    assert!(s.achieved_rate < 22.0, "{s:?}");
    // The 4 connections hold steps of the one session, each waiting for
    // the one before it: ~3 steps of ~56 ms (the rest waits for a
    // connection, in the send wait).
    assert!(
        r.session_wait.value_at_quantile(0.5) > 100_000,
        "{}",
        r.describe()
    );
}

async fn spawn_vigil() -> String {
    let listener = TcpListener::bind("127.0.0.1:0").await.expect("bind");
    let addr = listener.local_addr().expect("addr");
    let state = tokio::task::spawn_blocking(|| {
        AppState::with_settings(Registry::with_builtins(), Settings::default())
    })
    .await
    .expect("state");
    tokio::spawn(async move {
        axum::serve(listener, router(state)).await.expect("serve");
    });
    format!("http://{addr}")
}

async fn bin(args: Vec<String>) -> Output {
    tokio::task::spawn_blocking(move || {
        std::process::Command::new(env!("CARGO_BIN_EXE_vigil-loadtest"))
            .args(&args)
            .output()
            .expect("runs")
    })
    .await
    .expect("joined")
}

/// The binary against the app: 3 sessions of a small run, warmed, stepped
/// at 50/s, closed; `--out` has a run's fields; no session is left open.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_session_run_through_the_binary_against_the_app() {
    let url = spawn_vigil().await;
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("session.json");
    let o = bin([
        "--url",
        &url,
        "--endpoint",
        "session",
        "--sessions",
        "3",
        "--rate",
        "50",
        "--arrivals",
        "constant",
        "--duration",
        "1s",
        "--warmup",
        "200ms",
        "--connections",
        "4",
        "--sensors",
        "4",
        "--history",
        "4",
        "--count",
        "6",
        "--out",
        out.to_str().expect("utf-8"),
    ]
    .map(str::to_owned)
    .to_vec())
    .await;
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "stdout: {stdout}\nstderr: {stderr}");
    assert!(stdout.contains("session wait"), "{stdout}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("written")).expect("JSON");
    let keys: BTreeSet<&str> = v
        .as_object()
        .expect("object")
        .keys()
        .map(String::as_str)
        .collect();
    assert_eq!(keys.len(), 11, "{keys:?}");
    let s: Summary = serde_json::from_value(v).expect("a run's fields");
    assert_eq!((s.errors, s.shed), (0, 0), "{stdout}");
    assert_eq!(s.requests, 50, "{stdout}");
    let metrics = reqwest::get(format!("{url}/metrics"))
        .await
        .expect("metrics")
        .text()
        .await
        .expect("text");
    assert!(metrics.contains("vigil_sessions_live 0"), "{metrics}");

    // A wrong scenario fails at once, in the preflight.
    let o = bin(
        ["--url", &url, "--endpoint", "session", "--scenario", "nope"]
            .map(str::to_owned)
            .to_vec(),
    )
    .await;
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("unknown scenario"), "{stderr}");
}
