//! Sessions kept in the database: any replica serves any session, a
//! `kill -9` loses no acknowledged step, concurrent steps are serialised,
//! a retried step is not made twice, and the idle time and count hold
//! across replicas.

use std::sync::Arc;
use std::time::{Duration, Instant};

use reqwest::StatusCode;
use serde_json::{Value, json};
use sqlx::Connection;

use crate::cluster::Cluster;
use crate::server::{Server, body, spec};

/// Step `k` of a deterministic run: two sensors moving, and a target
/// detected every third step.
fn step_body(k: u32) -> Value {
    let x = 15.0 + f64::from(k % 7) * 10.0;
    let detections = if k.is_multiple_of(3) {
        json!([{"id": k, "x": 5.0 + f64::from(k), "y": 50.0, "vx": 6.0, "vy": 0.0}])
    } else {
        json!([])
    };
    json!({
        "sensors": [{"id": "a", "x": x, "y": 25.0}, {"id": "b", "x": 85.0, "y": x}],
        "detections": detections,
    })
}

/// A step's answer without its timing.
fn answer(mut v: Value) -> Value {
    if let Some(o) = v.as_object_mut() {
        o.remove("compute_micros");
    }
    v
}

/// Two answers alike but for rounding: every number to 1e-9 (relative
/// past 1), everything else equal. A replica that carried the session's
/// derived state from its last step (its carry) plans the stateless plan to
/// that precision, not to the bit.
fn same_answer(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => match (x.as_f64(), y.as_f64()) {
            (Some(x), Some(y)) => (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0),
            _ => x == y,
        },
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same_answer(x, y))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .all(|(k, v)| y.get(k).is_some_and(|w| same_answer(v, w)))
        }
        _ => a == b,
    }
}

async fn open(server: &Server, body_json: &Value) -> String {
    let (status, info) = body(server.post("/v1/sessions", body_json).await).await;
    assert_eq!(status, StatusCode::CREATED, "{info}");
    info["id"].as_str().unwrap().to_owned()
}

async fn step(server: &Server, id: &str, k: u32) -> Value {
    let (status, v) = body(
        server
            .post(&format!("/v1/sessions/{id}/step"), &step_body(k))
            .await,
    )
    .await;
    assert_eq!(status, StatusCode::OK, "step {k}: {v}");
    answer(v)
}

/// A session on an inline scenario, stepped alternately through two
/// replicas, one of which is killed with SIGKILL mid-run and restarted:
/// every step answers as the same session on a single replica does, and
/// both replicas read the same session.
pub async fn sessions_across_replicas(cluster: Arc<Cluster>) {
    let url = cluster.database("sessions_across").await;
    let one = Server::start("one", &url, &[]);
    let mut a = Server::start("a", &url, &[]);
    let b = Server::start("b", &url, &[]);
    let create = json!({"scenario": spec(7), "history_steps": 4});
    let reference = open(&one, &create).await;
    let shared = open(&a, &create).await;
    for k in 0..14 {
        let expected = step(&one, &reference, k).await;
        if k == 6 {
            // Killed after acknowledging steps 0..=5: the next steps go
            // to B, then to A restarted.
            a.kill();
        }
        if k == 9 {
            a = Server::start("a2", &url, &[]);
        }
        let server = if (6..9).contains(&k) || k % 2 == 1 {
            &b
        } else {
            &a
        };
        let got = step(server, &shared, k).await;
        assert!(
            same_answer(&got, &expected),
            "step {k}: {got} against {expected}"
        );
    }
    for server in [&a, &b] {
        let (status, info) = body(server.get(&format!("/v1/sessions/{shared}")).await).await;
        assert_eq!(status, StatusCode::OK);
        assert_eq!(info["step"], 14);
        let (_, reference_info) = body(one.get(&format!("/v1/sessions/{reference}")).await).await;
        assert_eq!(info["tracks"], reference_info["tracks"]);
    }
}

/// Step `k` of a learning run: every detection in a look, with an id.
fn learning_step(k: u32) -> Value {
    let detections = if k.is_multiple_of(2) {
        json!([{"id": format!("t{k}"), "x": 40.0 + f64::from(k % 5), "y": 50.0, "vx": 6.0, "vy": 0.0}])
    } else {
        json!([])
    };
    json!({
        "sensors": [{"id": "a", "x": 50.0, "y": 50.0}, {"id": "b", "x": 20.0 + f64::from(k % 4) * 10.0, "y": 80.0}],
        "detections": detections,
    })
}

/// A session that learns rates, alternated between two replicas: every
/// step's plan and learnt rates are those of the same session on one
/// replica.
pub async fn learning_sessions_across_replicas(cluster: Arc<Cluster>) {
    let url = cluster.database("sessions_learning").await;
    let one = Server::start("one", &url, &[]);
    let a = Server::start("a", &url, &[]);
    let b = Server::start("b", &url, &[]);
    let create = json!({"scenario": spec(8), "learn_rates": true});
    let reference = open(&one, &create).await;
    let shared = open(&a, &create).await;
    let mut scenarios = std::collections::HashSet::new();
    for k in 0..12 {
        let send = async |server: &Server, id: &str| {
            let res = server
                .post(&format!("/v1/sessions/{id}/step"), &learning_step(k))
                .await;
            let (status, v) = body(res).await;
            assert_eq!(status, StatusCode::OK, "step {k}: {v}");
            answer(v)
        };
        let expected = send(&one, &reference).await;
        let server = if k % 2 == 0 { &b } else { &a };
        let got = send(server, &shared).await;
        assert_eq!(got, expected, "step {k}");
        scenarios.insert(expected["scenario"].as_str().unwrap().to_owned());
    }
    // The rates drifted enough to plan on scenarios at learnt rates: the
    // replicas rebuilt or kept those planners as the one replica did.
    assert!(scenarios.len() >= 3, "{scenarios:?}");
}

/// A step whose client goes away while its plan is made, its new state
/// being written meanwhile (`vigil_session_writes_total{when="during_plan"}`),
/// is not stored: both replicas read the session at the step before, and
/// the next step follows that one.
pub async fn a_dropped_step_is_not_stored(cluster: Arc<Cluster>) {
    let url = cluster.database("sessions_dropped").await;
    let a = Server::start("a", &url, &[]);
    let b = Server::start("b", &url, &[]);
    let id = open(
        &a,
        &json!({"scenario_id": "paper-v10", "horizon": 12, "coordination": "iterated"}),
    )
    .await;
    let first = json!({"sensors": [{"id": "s0", "x": 20.0, "y": 20.0}], "horizon": 2});
    let (status, v) = body(a.post(&format!("/v1/sessions/{id}/step"), &first).await).await;
    assert_eq!((status, &v["step"]), (StatusCode::OK, &json!(0)), "{v}");
    // Tens of milliseconds of plan (80 sensors, T = 12): the client waits
    // 10 of them.
    let sensors: Vec<Value> = (0..80)
        .map(|i| json!({"id": format!("s{i}"), "x": 10 + (i * 37) % 280, "y": 10 + (i * 53) % 280}))
        .collect();
    let impatient = reqwest::Client::builder()
        .timeout(Duration::from_millis(10))
        .build()
        .unwrap();
    let sent = impatient
        .post(format!("{}/v1/sessions/{id}/step", a.address))
        .json(&json!({"sensors": sensors}))
        .send()
        .await;
    assert!(sent.is_err(), "answered within 10 ms: {sent:?}");
    let until = Instant::now() + Duration::from_secs(10);
    while a
        .metric_with("vigil_cancelled_total", "client_gone")
        .await
        .unwrap_or(0.0)
        < 1.0
    {
        assert!(Instant::now() < until, "the plan was not cancelled");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let early = a
        .metric_with("vigil_session_writes_total", "during_plan")
        .await;
    assert_eq!(early, Some(2.0), "both steps wrote during their plans");
    for server in [&a, &b] {
        let (status, info) = body(server.get(&format!("/v1/sessions/{id}")).await).await;
        assert_eq!(
            (status, &info["step"]),
            (StatusCode::OK, &json!(1)),
            "{info}"
        );
    }
    let (status, v) = body(b.post(&format!("/v1/sessions/{id}/step"), &first).await).await;
    assert_eq!((status, &v["step"]), (StatusCode::OK, &json!(1)), "{v}");
    let (status, v) = body(a.post(&format!("/v1/sessions/{id}/step"), &first).await).await;
    assert_eq!((status, &v["step"]), (StatusCode::OK, &json!(2)), "{v}");
}

/// Steps sent at once through two replicas: each answered one is made
/// from the one before (distinct, consecutive step numbers), the others
/// are refused with 409, and the session counts exactly the answered.
pub async fn concurrent_steps_are_serialised(cluster: Arc<Cluster>) {
    let url = cluster.database("sessions_concurrent").await;
    let a = Arc::new(Server::start("a", &url, &[]));
    let b = Arc::new(Server::start("b", &url, &[]));
    let id = open(&a, &json!({"scenario_id": "paper-v10"})).await;
    let tasks: Vec<_> = (0..12u32)
        .map(|k| {
            let server = if k % 2 == 0 { a.clone() } else { b.clone() };
            let id = id.clone();
            tokio::spawn(async move {
                let res = server
                    .post(&format!("/v1/sessions/{id}/step"), &step_body(k))
                    .await;
                body(res).await
            })
        })
        .collect();
    let mut steps = Vec::new();
    for task in tasks {
        let (status, v) = task.await.unwrap();
        match status {
            StatusCode::OK => steps.push(v["step"].as_u64().unwrap()),
            StatusCode::CONFLICT => assert_eq!(
                v["type"], "https://vigil.dev/problems/session-step-conflict",
                "{v}"
            ),
            other => panic!("{other}: {v}"),
        }
    }
    steps.sort_unstable();
    let n = steps.len() as u64;
    assert!(n >= 2, "{steps:?}");
    assert_eq!(steps, (0..n).collect::<Vec<_>>());
    for server in [&a, &b] {
        let (_, info) = body(server.get(&format!("/v1/sessions/{id}")).await).await;
        assert_eq!(info["step"], n);
    }
}

/// A step retried with its Idempotency-Key, on the other replica and at
/// once on both, is answered with the first answer and made once; its key
/// with another body is refused on both.
pub async fn retried_steps_are_made_once(cluster: Arc<Cluster>) {
    let url = cluster.database("sessions_retry").await;
    let a = Arc::new(Server::start("a", &url, &[]));
    let b = Arc::new(Server::start("b", &url, &[]));
    let id = open(&a, &json!({"scenario_id": "paper-v10"})).await;
    let send = |server: Arc<Server>, key: &'static str, k: u32| {
        let id = id.clone();
        async move {
            let res = server
                .post_with_key(&format!("/v1/sessions/{id}/step"), &step_body(k), key)
                .await;
            assert_eq!(res.status(), StatusCode::OK);
            res.bytes().await.unwrap()
        }
    };
    let first = send(a.clone(), "step-0", 0).await;
    assert_eq!(send(b.clone(), "step-0", 0).await, first);
    assert_eq!(send(a.clone(), "step-0", 0).await, first);
    // Its key with another body, on either replica: refused, not replayed.
    for server in [&a, &b] {
        let res = server
            .post_with_key(&format!("/v1/sessions/{id}/step"), &step_body(1), "step-0")
            .await;
        let (status, problem) = body(res).await;
        assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{problem}");
        assert!(
            problem["type"]
                .as_str()
                .unwrap()
                .ends_with("idempotency-key-reused")
        );
    }
    // The same new step through both at once: made once.
    let (x, y) = tokio::join!(
        tokio::spawn(send(a.clone(), "step-1", 1)),
        tokio::spawn(send(b.clone(), "step-1", 1))
    );
    let (x, y) = (x.unwrap(), y.unwrap());
    assert_eq!(x, y);
    let x: Value = serde_json::from_slice(&x).unwrap();
    assert_eq!(x["step"], 1);
    let (_, info) = body(b.get(&format!("/v1/sessions/{id}")).await).await;
    assert_eq!(info["step"], 2);
    // A replica older than request digests stores a step with its key and
    // answer only, leaving the digest of an earlier key: that key is then
    // answered whatever the body, as before digests, not refused.
    let mut conn = sqlx::PgConnection::connect(&url).await.unwrap();
    sqlx::query(
        "UPDATE sessions SET version = version + 1, last_key = 'old-2', \
         last_response = convert_to('{\"step\":2}', 'UTF8') WHERE id = $1",
    )
    .bind(&id)
    .execute(&mut conn)
    .await
    .unwrap();
    for server in [&a, &b] {
        let res = server
            .post_with_key(&format!("/v1/sessions/{id}/step"), &step_body(5), "old-2")
            .await;
        assert_eq!(res.status(), StatusCode::OK);
        assert_eq!(&res.bytes().await.unwrap()[..], br#"{"step":2}"#);
    }
}

/// The idle time to live and the count hold across replicas: a session
/// created through one replica is evicted by a creation through the
/// other, and one idle past the time to live is gone from both.
pub async fn session_bounds_across_replicas(cluster: Arc<Cluster>) {
    let url = cluster.database("sessions_bounds").await;
    let args = ["--session-ttl-s", "2", "--max-sessions", "2"];
    let a = Server::start("a", &url, &args);
    let b = Server::start("b", &url, &args);
    let create = json!({"scenario_id": "paper-v10"});
    let first = open(&a, &create).await;
    let second = open(&b, &create).await;
    // Using the first makes the second the least recently used.
    assert_eq!(
        b.get(&format!("/v1/sessions/{first}")).await.status(),
        StatusCode::OK
    );
    let third = open(&a, &create).await;
    for server in [&a, &b] {
        let path = format!("/v1/sessions/{second}");
        assert_eq!(server.get(&path).await.status(), StatusCode::NOT_FOUND);
        let path = format!("/v1/sessions/{first}");
        assert_eq!(server.get(&path).await.status(), StatusCode::OK);
    }
    assert_eq!(
        a.metric_with("vigil_sessions_evicted_total", "reason=\"capacity\"")
            .await,
        Some(1.0)
    );
    // Both idle past the time to live: gone everywhere.
    let idle = Instant::now();
    tokio::time::sleep(Duration::from_millis(2500)).await;
    for id in [&first, &third] {
        for server in [&a, &b] {
            let (status, problem) = body(server.get(&format!("/v1/sessions/{id}")).await).await;
            assert_eq!(status, StatusCode::NOT_FOUND, "{problem}");
        }
    }
    assert!(idle.elapsed() >= Duration::from_secs(2));
    let idle_a = a
        .metric_with("vigil_sessions_evicted_total", "reason=\"idle\"")
        .await
        .unwrap_or(0.0);
    let idle_b = b
        .metric_with("vigil_sessions_evicted_total", "reason=\"idle\"")
        .await
        .unwrap_or(0.0);
    assert_eq!(idle_a + idle_b, 2.0);
}

/// The database, not a replica's memory of its last answer, decides a
/// retry: once another replica stepped or deleted the session, a key this
/// replica answered is a new step (with any body) or a 404, as it is in
/// memory. A step to an unknown id is a 404 whatever its body, a refused
/// step of a live session does not leave it idle, and an id of another
/// form is not found (never sent to the database).
pub async fn retries_follow_the_database(cluster: Arc<Cluster>) {
    let url = cluster.database("sessions_replays").await;
    let args = ["--session-ttl-s", "3"];
    let a = Server::start("a", &url, &args);
    let b = Server::start("b", &url, &args);
    let id = open(&a, &json!({"scenario_id": "paper-v10"})).await;
    let path = format!("/v1/sessions/{id}/step");
    let keyed = async |server: &Server, k: u32, key: &str| {
        let (status, v) = body(server.post_with_key(&path, &step_body(k), key).await).await;
        assert_eq!(status, StatusCode::OK, "step {k} with {key}: {v}");
        v["step"].as_u64().unwrap()
    };
    assert_eq!(keyed(&a, 0, "k0").await, 0);
    assert_eq!(step(&b, &id, 1).await["step"], 1);
    // The last step had no key: k0 again is a new step, not a replay.
    assert_eq!(keyed(&a, 0, "k0").await, 2);
    assert_eq!(keyed(&b, 3, "k1").await, 3);
    // k0 is no longer the last step's key: another body is a new step.
    assert_eq!(keyed(&a, 4, "k0").await, 4);
    // Refused steps through A keep the session used, as requests.
    for _ in 0..3 {
        tokio::time::sleep(Duration::from_millis(1200)).await;
        let (status, problem) = body(a.post(&path, &json!({"sensors": 3})).await).await;
        assert_eq!(status, StatusCode::BAD_REQUEST, "{problem}");
    }
    assert_eq!(
        b.get(&format!("/v1/sessions/{id}")).await.status(),
        StatusCode::OK
    );
    assert_eq!(
        b.delete(&format!("/v1/sessions/{id}")).await.status(),
        StatusCode::NO_CONTENT
    );
    let (status, problem) = body(a.post_with_key(&path, &step_body(4), "k0").await).await;
    assert_eq!(status, StatusCode::NOT_FOUND, "{problem}");
    // Unknown ids: 404 before the body is looked at; other forms too.
    let unknown = format!("/v1/sessions/ss-{}/step", "0".repeat(32));
    for server in [&a, &b] {
        let (status, problem) = body(server.post(&unknown, &json!({"sensors": 3})).await).await;
        assert_eq!(status, StatusCode::NOT_FOUND, "{problem}");
        for odd in ["ss-%00", "ss-xyz", "x"] {
            let (status, problem) = body(server.get(&format!("/v1/sessions/{odd}")).await).await;
            assert_eq!(status, StatusCode::NOT_FOUND, "{odd}: {problem}");
        }
    }
}
