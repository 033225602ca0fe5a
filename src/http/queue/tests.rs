//! The queue admits one piece per worker and sheds past its bound.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use axum::extract::FromRequest;

use super::{QUEUE_PER_WORKER, on_rayon, queue_full, work_queue};
use crate::http::error::ApiError;
use crate::http::extract;

/// The tests here share rayon's pool and the work queue: one at a time.
static SERIAL: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn work_past_the_queue_is_shed_at_once() {
    let _serial = SERIAL.lock().await;
    let workers = rayon::current_num_threads();
    let release = Arc::new(AtomicUsize::new(0));
    let running = Arc::new(AtomicUsize::new(0));
    let hold = |release: Arc<AtomicUsize>, running: Arc<AtomicUsize>| {
        move || {
            running.fetch_add(1, Ordering::SeqCst);
            while release.load(Ordering::SeqCst) == 0 {
                std::thread::sleep(Duration::from_millis(1));
            }
        }
    };
    let mut tasks = Vec::new();
    for _ in 0..workers {
        tasks.push(tokio::spawn(on_rayon(hold(
            release.clone(),
            running.clone(),
        ))));
    }
    while running.load(Ordering::SeqCst) < workers {
        tokio::time::sleep(Duration::from_millis(1)).await;
    }
    for _ in 0..QUEUE_PER_WORKER * workers {
        tasks.push(tokio::spawn(on_rayon(hold(
            release.clone(),
            running.clone(),
        ))));
    }
    while work_queue().waiting.load(Ordering::SeqCst) < QUEUE_PER_WORKER * workers {
        tokio::time::sleep(Duration::from_millis(1)).await;
    }
    // The queue is full: the next is shed without waiting, and a body
    // for the queue is not even parsed (this one would be a 400).
    let shed = on_rayon(|| ()).await;
    assert!(matches!(shed, Err(ApiError::Overloaded)), "{shed:?}");
    assert!(queue_full());
    let body = |text: &'static str| {
        axum::http::Request::builder()
            .method("POST")
            .header("content-type", "application/json")
            .body(axum::body::Body::from(text))
            .expect("a request")
    };
    type Queued = extract::QueuedJson<serde_json::Value>;
    let shed = Queued::from_request(body("{not json"), &()).await;
    assert!(matches!(shed, Err(ApiError::Overloaded)), "{shed:?}");
    release.store(1, Ordering::SeqCst);
    for task in tasks {
        task.await.expect("joined").expect("queued work runs");
    }
    assert!(!queue_full());
    let parsed = Queued::from_request(body("{not json"), &()).await;
    assert!(
        matches!(parsed, Err(ApiError::MalformedBody(_))),
        "{parsed:?}"
    );
    let parsed = Queued::from_request(body(r#"{"a": 1}"#), &()).await;
    assert!(matches!(parsed, Ok(extract::QueuedJson(v)) if v["a"] == 1));
    assert_eq!(
        running.load(Ordering::SeqCst),
        (QUEUE_PER_WORKER + 1) * workers
    );
    assert_eq!(work_queue().waiting.load(Ordering::SeqCst), 0);
}

/// Work that splits (as a plan does) must not interleave with other
/// work on rayon's workers: at most one piece per worker is running.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn work_pieces_run_at_most_one_per_worker() {
    let _serial = SERIAL.lock().await;
    let running = Arc::new(AtomicUsize::new(0));
    let most = Arc::new(AtomicUsize::new(0));
    let tasks: Vec<_> = (0..12)
        .map(|_| {
            let (running, most) = (running.clone(), most.clone());
            tokio::spawn(on_rayon(move || {
                let now = running.fetch_add(1, Ordering::SeqCst) + 1;
                most.fetch_max(now, Ordering::SeqCst);
                // A worker waiting here for the stolen half would run
                // other queued jobs meanwhile, were any admitted.
                rayon::join(
                    || std::thread::sleep(Duration::from_millis(5)),
                    || std::thread::sleep(Duration::from_millis(30)),
                );
                running.fetch_sub(1, Ordering::SeqCst);
            }))
        })
        .collect();
    for task in tasks {
        task.await.expect("joined").expect("ran");
    }
    let most = most.load(Ordering::SeqCst);
    assert!(
        most <= rayon::current_num_threads(),
        "{most} pieces ran at once on {} workers",
        rayon::current_num_threads()
    );
}
