//! The database tests (see the harness in `main.rs`).

use std::collections::HashSet;
use std::sync::Arc;
use std::time::{Duration, Instant};

use reqwest::StatusCode;
use serde_json::json;
use sqlx::Connection;

use crate::Test;
use crate::cluster::Cluster;
use crate::precomputed;
use crate::server::{Server, assert_unavailable, body, spec};
use crate::sessions;

/// Every test, in the order run (the one that stops the server last).
pub const ALL: &[(&str, Test)] = &[
    ("replicas_start_at_once", |c| {
        Box::pin(replicas_start_at_once(c))
    }),
    ("shared_catalogue", |c| Box::pin(shared_catalogue(c))),
    ("same_spec_through_two_replicas", |c| {
        Box::pin(same_spec_through_two_replicas(c))
    }),
    ("jobs_across_replicas", |c| {
        Box::pin(jobs_across_replicas(c))
    }),
    ("restart_keeps_scenarios", |c| {
        Box::pin(restart_keeps_scenarios(c))
    }),
    ("kill_9_during_registrations", |c| {
        Box::pin(kill_9_during_registrations(c))
    }),
    ("import_dir", |c| Box::pin(import_dir(c))),
    ("newer_schema_refused", |c| {
        Box::pin(newer_schema_refused(c))
    }),
    ("sessions_across_replicas", |c| {
        Box::pin(sessions::sessions_across_replicas(c))
    }),
    ("learning_sessions_across_replicas", |c| {
        Box::pin(sessions::learning_sessions_across_replicas(c))
    }),
    ("a_dropped_step_is_not_stored", |c| {
        Box::pin(sessions::a_dropped_step_is_not_stored(c))
    }),
    ("concurrent_steps_are_serialised", |c| {
        Box::pin(sessions::concurrent_steps_are_serialised(c))
    }),
    ("retried_steps_are_made_once", |c| {
        Box::pin(sessions::retried_steps_are_made_once(c))
    }),
    ("retries_follow_the_database", |c| {
        Box::pin(sessions::retries_follow_the_database(c))
    }),
    ("session_bounds_across_replicas", |c| {
        Box::pin(sessions::session_bounds_across_replicas(c))
    }),
    ("precomputed_once_across_replicas", |c| {
        Box::pin(precomputed::precomputed_once_across_replicas(c))
    }),
    ("precomputed_rows_are_whole_and_checked", |c| {
        Box::pin(precomputed::precomputed_rows_are_whole_and_checked(c))
    }),
    ("database_outage", |c| Box::pin(database_outage(c))),
];

async fn connect(url: &str) -> sqlx::PgConnection {
    sqlx::PgConnection::connect(url).await.expect("connect")
}

async fn count_rows(url: &str) -> i64 {
    let mut conn = connect(url).await;
    let (n,): (i64,) = sqlx::query_as("SELECT count(*) FROM scenarios")
        .fetch_one(&mut conn)
        .await
        .expect("count");
    n
}

/// Three replicas starting at once on an empty database: the migration
/// lock serializes them, all come up, and the schema is applied once.
async fn replicas_start_at_once(cluster: Arc<Cluster>) {
    let url = cluster.database("start_at_once").await;
    let handles: Vec<_> = (0..3)
        .map(|i| {
            let url = url.clone();
            std::thread::spawn(move || Server::start(&format!("r{i}"), &url, &[]))
        })
        .collect();
    let servers: Vec<Server> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    for s in &servers {
        let (status, health) = body(s.get("/healthz").await).await;
        assert_eq!(status, StatusCode::OK);
        assert_eq!(health["database"], "up", "{health}");
    }
    let mut conn = connect(&url).await;
    let (n,): (i64,) = sqlx::query_as("SELECT count(*) FROM _sqlx_migrations")
        .fetch_one(&mut conn)
        .await
        .unwrap();
    assert_eq!(n as usize, vigil::store::postgres::MIGRATOR.iter().count());
}

/// Registered through A: read, planned and listed through B; deleted
/// through A: gone from B within 1 s.
async fn shared_catalogue(cluster: Arc<Cluster>) {
    let url = cluster.database("shared").await;
    let a = Server::start("a", &url, &[]);
    let b = Server::start("b", &url, &[]);

    let res = a.post("/v1/scenarios", &spec(1)).await;
    let location = res
        .headers()
        .get("location")
        .map(|v| v.to_str().unwrap().to_owned());
    let (status, created) = body(res).await;
    assert_eq!(status, StatusCode::CREATED, "{created}");
    let id = created["id"].as_str().unwrap().to_owned();
    assert_eq!(
        location.as_deref(),
        Some(format!("/v1/scenarios/{id}").as_str())
    );

    // B lists it before it has used it: from the database.
    let (status, list) = body(b.get("/v1/scenarios").await).await;
    assert_eq!(status, StatusCode::OK);
    let listed = list["scenarios"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["id"] == id.as_str())
        .unwrap_or_else(|| panic!("{id} not listed by B: {list}"));
    assert_eq!(listed["status"], "stored", "{listed}");
    assert_eq!(
        list["scenarios"].as_array().unwrap().len(),
        vigil::scenario::BUILTIN_IDS.len() + 1,
        "{list}"
    );

    // B serves it on its first request.
    let (status, got) = body(b.get(&format!("/v1/scenarios/{id}")).await).await;
    assert_eq!(status, StatusCode::OK, "{got}");
    assert_eq!(got["id"], id.as_str());
    assert_eq!(got["status"], "ready");
    assert_eq!(got["spec"], created["spec"]);
    assert_eq!(
        got["summary"]["expected_targets_in_zone"],
        created["summary"]["expected_targets_in_zone"]
    );
    let (status, plan_b) = body(b.plan(&id).await).await;
    assert_eq!(status, StatusCode::OK, "{plan_b}");
    let (status, plan_a) = body(a.plan(&id).await).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(plan_a["plans"], plan_b["plans"]);
    let (status, _) = body(b.get(&format!("/v1/scenarios/{id}/stats")).await).await;
    assert_eq!(status, StatusCode::OK);
    // By id through /v1/plan, on a third scenario B has never seen.
    let (_, other) = body(a.post("/v1/scenarios", &spec(2)).await).await;
    let other = other["id"].as_str().unwrap().to_owned();
    let (status, by_id) = body(
        b.post(
            "/v1/plan",
            &json!({"scenario_id": other, "sensors": [{"id": "a", "x": 15, "y": 15}]}),
        )
        .await,
    )
    .await;
    assert_eq!(status, StatusCode::OK, "{by_id}");

    // Deleted through A: B answers 404 within 1 s.
    let res = a.delete(&format!("/v1/scenarios/{id}")).await;
    assert_eq!(res.status(), StatusCode::NO_CONTENT);
    let deleted = Instant::now();
    loop {
        let status = b.plan(&id).await.status();
        if status == StatusCode::NOT_FOUND {
            break;
        }
        assert_eq!(status, StatusCode::OK);
        assert!(
            deleted.elapsed() < Duration::from_secs(1),
            "B still serves a scenario deleted through A 1 s ago:\n{}",
            b.log_text()
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    println!(
        "  B saw the deletion after {} ms",
        deleted.elapsed().as_millis()
    );
    assert_eq!(
        b.get(&format!("/v1/scenarios/{id}")).await.status(),
        StatusCode::NOT_FOUND
    );
    assert_eq!(
        b.delete(&format!("/v1/scenarios/{id}")).await.status(),
        StatusCode::NOT_FOUND
    );
    // Unknown and built-in ids as before.
    assert_eq!(
        b.get("/v1/scenarios/s-0000000000000000").await.status(),
        StatusCode::NOT_FOUND
    );
    assert_eq!(
        b.get("/v1/scenarios/nope").await.status(),
        StatusCode::NOT_FOUND
    );
    assert_eq!(
        b.delete("/v1/scenarios/paper-v10").await.status(),
        StatusCode::CONFLICT
    );
    assert_eq!(count_rows(&url).await, 1);
}

/// The same specs registered through A and B at the same moment: one row
/// and one id each, 201 on one replica and 200 on the other, no error.
async fn same_spec_through_two_replicas(cluster: Arc<Cluster>) {
    let url = cluster.database("same_spec").await;
    let a = Arc::new(Server::start("a", &url, &[]));
    let b = Arc::new(Server::start("b", &url, &[]));
    let n = 12;
    for k in 0..n {
        let s = spec(100 + k);
        let (ra, rb) = tokio::join!(a.post("/v1/scenarios", &s), b.post("/v1/scenarios", &s));
        let ((sa, ba), (sb, bb)) = (body(ra).await, body(rb).await);
        assert_eq!(ba["id"], bb["id"], "{ba} {bb}");
        let mut statuses = [sa.as_u16(), sb.as_u16()];
        statuses.sort_unstable();
        assert_eq!(statuses, [200, 201], "spec {k}: {ba} {bb}");
    }
    assert_eq!(count_rows(&url).await, i64::from(n));
}

/// A large scenario (a job) registered through A is a job on B too: B's
/// first request starts it there, and B serves plans once it is ready.
async fn jobs_across_replicas(cluster: Arc<Cluster>) {
    let url = cluster.database("jobs").await;
    // Every registration is a job.
    let args = ["--sync-precompute-ms", "0"];
    let a = Server::start("a", &url, &args);
    let b = Server::start("b", &url, &args);
    let (status, accepted) = body(a.post("/v1/scenarios", &spec(7)).await).await;
    assert_eq!(status, StatusCode::ACCEPTED, "{accepted}");
    let id = accepted["id"].as_str().unwrap().to_owned();
    let (status, first) = body(b.get(&format!("/v1/scenarios/{id}")).await).await;
    assert_eq!(status, StatusCode::OK, "{first}");
    assert!(
        ["queued", "precomputing", "ready"].contains(&first["status"].as_str().unwrap()),
        "{first}"
    );
    let started = Instant::now();
    loop {
        let res = b.plan(&id).await;
        match res.status() {
            StatusCode::OK => break,
            StatusCode::SERVICE_UNAVAILABLE => {
                assert!(res.headers().contains_key("retry-after"));
            }
            other => panic!("{other}: {}", res.text().await.unwrap()),
        }
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "never ready on B"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    // Posting it again through B: it is ready there now, 200.
    let (status, again) = body(b.post("/v1/scenarios", &spec(7)).await).await;
    assert_eq!(status, StatusCode::OK, "{again}");
    assert_eq!(count_rows(&url).await, 1);
}

/// A restarted replica still has what was registered through it.
async fn restart_keeps_scenarios(cluster: Arc<Cluster>) {
    let url = cluster.database("restart").await;
    let mut a = Server::start("a", &url, &[]);
    let (status, created) = body(a.post("/v1/scenarios", &spec(3)).await).await;
    assert_eq!(status, StatusCode::CREATED);
    let id = created["id"].as_str().unwrap().to_owned();
    a.kill();
    let a = Server::start("a2", &url, &[]);
    let (status, got) = body(a.get(&format!("/v1/scenarios/{id}")).await).await;
    assert_eq!(status, StatusCode::OK, "{got}");
    assert_eq!(got["spec"], created["spec"]);
    assert_eq!(a.plan(&id).await.status(), StatusCode::OK);
    // The same spec again: 200, still one row.
    assert_eq!(
        a.post("/v1/scenarios", &spec(3)).await.status(),
        StatusCode::OK
    );
    assert_eq!(count_rows(&url).await, 1);
}

/// `kill -9` in the middle of a burst of registrations: every
/// acknowledged one is stored, and every row is a whole scenario.
async fn kill_9_during_registrations(cluster: Arc<Cluster>) {
    let url = cluster.database("kill9").await;
    let mut a = Server::start("a", &url, &[]);
    let a_addr = a.address.clone();
    let client = reqwest::Client::new();
    let acked = Arc::new(std::sync::Mutex::new(Vec::<String>::new()));
    let mut tasks = Vec::new();
    for w in 0..8u32 {
        let (client, addr, acked) = (client.clone(), a_addr.clone(), acked.clone());
        tasks.push(tokio::spawn(async move {
            for k in 0..200u32 {
                let res = client
                    .post(format!("{addr}/v1/scenarios"))
                    .json(&spec(1000 + w * 1000 + k))
                    .send()
                    .await;
                let Ok(res) = res else { return };
                if res.status() == StatusCode::CREATED {
                    let v: serde_json::Value = match res.json().await {
                        Ok(v) => v,
                        Err(_) => return,
                    };
                    acked
                        .lock()
                        .unwrap()
                        .push(v["id"].as_str().unwrap().to_owned());
                }
            }
        }));
    }
    // Kill it once a good number are acknowledged.
    let started = Instant::now();
    while acked.lock().unwrap().len() < 40 {
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "registrations too slow"
        );
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    a.kill();
    for t in tasks {
        let _ = t.await;
    }
    let acked: Vec<String> = acked.lock().unwrap().clone();
    let mut conn = connect(&url).await;
    let rows: Vec<(String, i32, String)> =
        sqlx::query_as("SELECT id, format, spec::text FROM scenarios")
            .fetch_all(&mut conn)
            .await
            .unwrap();
    let stored: HashSet<&str> = rows.iter().map(|(id, _, _)| id.as_str()).collect();
    for id in &acked {
        assert!(
            stored.contains(id.as_str()),
            "acknowledged {id} is not stored"
        );
    }
    for (id, format, spec) in &rows {
        assert_eq!(*format, 1);
        let spec: vigil::scenario::ScenarioSpec = serde_json::from_str(spec).unwrap();
        let scenario = vigil::scenario::Scenario::new(spec).unwrap();
        assert_eq!(&scenario.id, id, "a row whose spec is not its id's");
    }
    println!(
        "  {} acknowledged, {} rows, all whole",
        acked.len(),
        rows.len()
    );
    // A new replica serves every one.
    let b = Server::start("b", &url, &[]);
    for id in acked.iter().take(10) {
        assert_eq!(b.plan(id).await.status(), StatusCode::OK);
    }
}

/// `--import-dir` loads a file store's scenarios; twice changes nothing.
async fn import_dir(cluster: Arc<Cluster>) {
    let url = cluster.database("import").await;
    let dir = std::env::temp_dir().join(format!("vigil-pg-import-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (store, _) = vigil::store::Store::open(&dir).unwrap();
    let mut ids = Vec::new();
    for k in 0..3 {
        let s: vigil::scenario::ScenarioSpec = serde_json::from_value(spec(500 + k)).unwrap();
        let s = vigil::scenario::Scenario::new(s).unwrap();
        store.save(&s).unwrap();
        ids.push(s.id);
    }
    std::fs::write(dir.join("s-0000000000000000.json"), b"{\"format\":1").unwrap();
    let import = || {
        std::process::Command::new(env!("CARGO_BIN_EXE_vigil-server"))
            .args(["--database-url", &url, "--import-dir"])
            .arg(&dir)
            .env("RUST_LOG", "info,sqlx=warn")
            .output()
            .unwrap()
    };
    let first = import();
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    assert!(String::from_utf8_lossy(&first.stderr).contains("added=3"));
    let mut conn = connect(&url).await;
    let created: Vec<(String, String)> =
        sqlx::query_as("SELECT id, created_at::text FROM scenarios ORDER BY id")
            .fetch_all(&mut conn)
            .await
            .unwrap();
    let second = import();
    assert!(
        second.status.success(),
        "{}",
        String::from_utf8_lossy(&second.stderr)
    );
    assert!(String::from_utf8_lossy(&second.stderr).contains("added=0"));
    let again: Vec<(String, String)> =
        sqlx::query_as("SELECT id, created_at::text FROM scenarios ORDER BY id")
            .fetch_all(&mut conn)
            .await
            .unwrap();
    assert_eq!(created, again);
    let mut sorted = ids.clone();
    sorted.sort();
    assert_eq!(
        created.iter().map(|(id, _)| id.clone()).collect::<Vec<_>>(),
        sorted
    );
    let a = Server::start("a", &url, &[]);
    assert_eq!(a.plan(&ids[0]).await.status(), StatusCode::OK);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A database migrated by a newer binary is a start-up error.
async fn newer_schema_refused(cluster: Arc<Cluster>) {
    let url = cluster.database("newer").await;
    drop(Server::start("a", &url, &[]));
    let mut conn = connect(&url).await;
    sqlx::query(
        "INSERT INTO _sqlx_migrations (version, description, success, checksum, execution_time) \
         VALUES (99991231000000, 'from the future', true, '\\x00', 0)",
    )
    .execute(&mut conn)
    .await
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_vigil-server"))
        .args(["--bind", "127.0.0.1:0", "--database-url", &url])
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{log}");
    assert!(log.contains("does not know"), "{log}");
}

/// The database stops in the middle of a run and comes back on the same
/// port: meanwhile, plans on cached, built-in and inline scenarios answer
/// 200; catalogue writes, uncached reads and sessions answer 503
/// problem+json with Retry-After, fast; no other 5xx; `/healthz` and the gauge say so. After,
/// everything works again without restarting either server.
async fn database_outage(cluster: Arc<Cluster>) {
    assert!(
        cluster.owned(),
        "this test stops and starts the database: it needs a server of its own (unset \
         VIGIL_TEST_DATABASE_URL: the tests then start one, and install PostgreSQL's programs \
         if they are missing)"
    );
    let url = cluster.database("outage").await;
    let timeout_ms = 3000;
    let args = [
        "--request-timeout-ms",
        "3000",
        "--database-timeout-ms",
        "1000",
    ];
    let a = Server::start("a", &url, &args);
    let b = Server::start("b", &url, &args);
    let (_, cached) = body(a.post("/v1/scenarios", &spec(1)).await).await;
    let cached = cached["id"].as_str().unwrap().to_owned();
    // Each registered through the other replica: not held by the one
    // that reads it.
    let (_, uncached_b) = body(a.post("/v1/scenarios", &spec(2)).await).await;
    let uncached_b = uncached_b["id"].as_str().unwrap().to_owned();
    let (_, uncached_a) = body(b.post("/v1/scenarios", &spec(4)).await).await;
    let uncached_a = uncached_a["id"].as_str().unwrap().to_owned();
    let (_, doomed) = body(a.post("/v1/scenarios", &spec(3)).await).await;
    let doomed = doomed["id"].as_str().unwrap().to_owned();
    for s in [&a, &b] {
        assert_eq!(s.plan(&cached).await.status(), StatusCode::OK);
        assert_eq!(s.plan(&doomed).await.status(), StatusCode::OK);
    }
    let (_, session) = body(
        a.post("/v1/sessions", &json!({"scenario_id": "paper-v10"}))
            .await,
    )
    .await;
    let session = format!("/v1/sessions/{}", session["id"].as_str().unwrap());
    let step = json!({"sensors": [{"id": "a", "x": 15, "y": 15}], "detections": []});
    let (status, first) = body(a.post(&format!("{session}/step"), &step).await).await;
    assert_eq!((status, &first["step"]), (StatusCode::OK, &json!(0)));

    cluster.stop();
    let stopped = Instant::now();
    for s in [&a, &b] {
        loop {
            let (status, health) = body(s.get("/healthz").await).await;
            assert_eq!(status, StatusCode::OK);
            if health["database"] == "down" {
                break;
            }
            assert!(stopped.elapsed() < Duration::from_secs(5), "{health}");
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
        assert_eq!(s.metric("vigil_database_up").await, Some(0.0));
    }
    let inline = json!({"scenario": spec(9), "sensors": [{"id": "a", "x": 15, "y": 15}]});
    for round in 0..3 {
        for (s, uncached) in [(&a, &uncached_a), (&b, &uncached_b)] {
            let t = Instant::now();
            assert_eq!(
                s.plan(&cached).await.status(),
                StatusCode::OK,
                "round {round}"
            );
            assert_eq!(s.plan("paper-v10").await.status(), StatusCode::OK);
            assert_eq!(s.post("/v1/plan", &inline).await.status(), StatusCode::OK);
            assert_eq!(
                s.get(&format!("/v1/scenarios/{cached}")).await.status(),
                StatusCode::OK
            );
            assert_eq!(s.get("/healthz").await.status(), StatusCode::OK);
            assert_unavailable(s.post("/v1/scenarios", &spec(50 + round)).await, "write").await;
            assert_unavailable(s.delete(&format!("/v1/scenarios/{cached}")).await, "delete").await;
            assert_unavailable(s.get("/v1/scenarios").await, "list").await;
            assert_unavailable(s.get(&format!("/v1/scenarios/{uncached}")).await, "read").await;
            assert_unavailable(s.plan(uncached).await, "plan uncached").await;
            assert_unavailable(s.post(&format!("{session}/step"), &step).await, "step").await;
            assert_unavailable(s.get(&session).await, "session").await;
            let took = t.elapsed();
            // Twelve requests, none near the request timeout.
            assert!(
                took < Duration::from_millis(timeout_ms),
                "round {round} took {took:?}"
            );
        }
    }

    cluster.restart();
    // A deletion made while the replicas may not yet listen again: the
    // re-check after reconnecting (or the notification) drops it.
    let mut conn = connect(&url).await;
    sqlx::query("DELETE FROM scenarios WHERE id = $1")
        .bind(&doomed)
        .execute(&mut conn)
        .await
        .unwrap();
    let back = Instant::now();
    for s in [&a, &b] {
        loop {
            let status = s.plan(&doomed).await.status();
            if status == StatusCode::NOT_FOUND {
                break;
            }
            assert_eq!(status, StatusCode::OK);
            assert!(
                back.elapsed() < Duration::from_secs(5),
                "a scenario deleted during the reconnection is still served:\n{}",
                s.log_text()
            );
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }
    // Everything works again, without a restart: the session goes on
    // from its last stored step.
    let (status, second) = body(b.post(&format!("{session}/step"), &step).await).await;
    assert_eq!(
        (status, &second["step"]),
        (StatusCode::OK, &json!(1)),
        "{second}"
    );
    let (status, created) = body(a.post("/v1/scenarios", &spec(60)).await).await;
    assert_eq!(status, StatusCode::CREATED, "{created}");
    assert_eq!(b.plan(&uncached_b).await.status(), StatusCode::OK);
    assert_eq!(
        a.get(&format!("/v1/scenarios/{uncached_a}")).await.status(),
        StatusCode::OK
    );
    assert_eq!(
        b.plan(created["id"].as_str().unwrap()).await.status(),
        StatusCode::OK
    );
    assert_eq!(b.get("/v1/scenarios").await.status(), StatusCode::OK);
    for s in [&a, &b] {
        let (_, health) = body(s.get("/healthz").await).await;
        assert_eq!(health["database"], "up", "{health}");
        assert_eq!(s.metric("vigil_database_up").await, Some(1.0));
    }
    // Deletions reach the other replica again.
    assert_eq!(
        a.delete(&format!("/v1/scenarios/{cached}")).await.status(),
        StatusCode::NO_CONTENT
    );
    let deleted = Instant::now();
    while b.plan(&cached).await.status() != StatusCode::NOT_FOUND {
        assert!(
            deleted.elapsed() < Duration::from_secs(1),
            "{}",
            b.log_text()
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    for s in [&a, &b] {
        let log = s.log_text();
        assert!(!log.contains("panicked"), "{log}");
        assert!(!log.contains("Status code: 500"), "{log}");
    }
}
