//! Registered scenarios precomputed once for every replica: a replica
//! loads what another stored (and plans the same, to the bit), two that
//! start at once compute once, a replica killed mid-precompute leaves no
//! half row, and a corrupt row is computed again, never used.

use std::sync::Arc;
use std::time::{Duration, Instant};

use reqwest::StatusCode;
use serde_json::{Value, json};
use sqlx::Connection;

use crate::cluster::Cluster;
use crate::server::{Server, body};

/// Every registration a job, so that precomputations go through claims.
const JOBS: [&str; 2] = ["--sync-precompute-ms", "0"];

/// A scenario of `side`² cells, distinct for each `n`.
fn lattice(side: u32, n: u32) -> Value {
    json!({
        "name": format!("stored-{side}-{n}"),
        "zone": {"width": side, "height": side}, "cell_size": 1,
        "fov": {"shape": "square", "half_width": 2.5}, "target_speed": 2,
        "sources": [{"x": -1, "y": side / 2, "rate": 0.1 + 0.01 * f64::from(n)},
                    {"x": side / 2, "y": side + 1, "rate": 0.2}]
    })
}

/// A plan on `id` through `server`, once it is ready, without its timing.
async fn plan_when_ready(server: &Server, id: &str, within: Duration) -> Value {
    let started = Instant::now();
    let req = json!({"sensors": [{"id": "a", "x": 10.5, "y": 10.5}, {"id": "b", "x": 20.5, "y": 12.5}],
        "targets": [{"x": 15.0, "y": 15.0, "vx": 1.0, "vy": 0.5}], "horizon": 3});
    loop {
        let (status, mut v) =
            body(server.post(&format!("/v1/scenarios/{id}/plan"), &req).await).await;
        match status {
            StatusCode::OK => {
                v.as_object_mut().unwrap().remove("compute_micros");
                return v;
            }
            StatusCode::SERVICE_UNAVAILABLE => {}
            other => panic!("{other}: {v}"),
        }
        assert!(
            started.elapsed() < within,
            "{id} not ready: {}",
            server.log_text()
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

async fn register(server: &Server, spec: &Value) -> String {
    let (status, v) = body(server.post("/v1/scenarios", spec).await).await;
    assert!(status.is_success(), "{status}: {v}");
    v["id"].as_str().unwrap().to_owned()
}

async fn stored_rows(url: &str) -> (i64, i64) {
    let mut conn = sqlx::PgConnection::connect(url).await.unwrap();
    let (heads,): (i64,) = sqlx::query_as("SELECT count(*) FROM precomputed")
        .fetch_one(&mut conn)
        .await
        .unwrap();
    let (chunks,): (i64,) = sqlx::query_as("SELECT count(*) FROM precomputed_chunks")
        .fetch_one(&mut conn)
        .await
        .unwrap();
    (heads, chunks)
}

async fn outcome(server: &Server, outcome: &str) -> f64 {
    server
        .metric_with("vigil_precomputed_total", &format!("outcome=\"{outcome}\""))
        .await
        .unwrap_or(0.0)
}

/// Precomputed through A (a job), stored; B loads it instead of computing
/// and plans the same, to the bit; a scenario registered at once through
/// both, and asked of both, is computed once.
pub async fn precomputed_once_across_replicas(cluster: Arc<Cluster>) {
    let url = cluster.database("precomputed_once").await;
    let a = Arc::new(Server::start("a", &url, &JOBS));
    let b = Arc::new(Server::start("b", &url, &JOBS));
    let id = register(&a, &lattice(120, 0)).await;
    let on_a = plan_when_ready(&a, &id, Duration::from_secs(60)).await;
    // Stored in the background once ready.
    let started = Instant::now();
    while stored_rows(&url).await.0 < 1 {
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "{}",
            a.log_text()
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let on_b = plan_when_ready(&b, &id, Duration::from_secs(60)).await;
    assert_eq!(on_b, on_a);
    assert_eq!(outcome(&b, "loaded").await, 1.0);
    assert_eq!(outcome(&b, "computed").await, 0.0);

    // Both at once: one computes, the other waits for its row.
    let spec = lattice(300, 1);
    let (ia, ib) = tokio::join!(register(&a, &spec), register(&b, &spec));
    assert_eq!(ia, ib);
    let (pa, pb) = tokio::join!(
        plan_when_ready(&a, &ia, Duration::from_secs(120)),
        plan_when_ready(&b, &ib, Duration::from_secs(120))
    );
    assert_eq!(pa, pb);
    let computed = outcome(&a, "computed").await + outcome(&b, "computed").await;
    assert_eq!(computed, 2.0, "the first scenario on A, the second once");
    assert_eq!(stored_rows(&url).await.0, 2);
}

/// A replica killed with SIGKILL while it precomputes leaves no row (nor
/// chunk); another then computes and stores it. A stored row that does
/// not decode is computed again (and replaced), never used.
pub async fn precomputed_rows_are_whole_and_checked(cluster: Arc<Cluster>) {
    let url = cluster.database("precomputed_whole").await;
    let mut a = Server::start("a", &url, &JOBS);
    let id = register(&a, &lattice(1500, 2)).await;
    let started = Instant::now();
    loop {
        let (_, v) = body(a.get(&format!("/v1/scenarios/{id}")).await).await;
        if v["status"] == "precomputing" {
            break;
        }
        assert!(started.elapsed() < Duration::from_secs(20), "{v}");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    a.kill();
    assert_eq!(stored_rows(&url).await, (0, 0));
    let b = Server::start("b", &url, &JOBS);
    let on_b = plan_when_ready(&b, &id, Duration::from_secs(120)).await;
    let started = Instant::now();
    while stored_rows(&url).await.0 < 1 {
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "{}",
            b.log_text()
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert_eq!(outcome(&b, "computed").await, 1.0);

    // Garble a chunk: the next replica refuses it, computes, stores anew.
    let mut conn = sqlx::PgConnection::connect(&url).await.unwrap();
    sqlx::query(
        "UPDATE precomputed_chunks SET data = overlay(data placing '\\xdeadbeef'::bytea from 100) \
         WHERE n = 0",
    )
    .execute(&mut conn)
    .await
    .unwrap();
    let c = Server::start("c", &url, &JOBS);
    let on_c = plan_when_ready(&c, &id, Duration::from_secs(120)).await;
    assert_eq!(on_c, on_b);
    assert_eq!(outcome(&c, "rejected").await, 1.0);
    assert_eq!(outcome(&c, "computed").await, 1.0);
    assert!(c.log_text().contains("cannot be used"), "{}", c.log_text());
}
