//! HTTP layer: a thin JSON API over the [`planner`](crate::planner).
//!
//! [`router`] builds the whole application from an [`AppState`]; the binary
//! only binds and serves it. Every error is an [`ApiError`], rendered as
//! `application/problem+json`. CPU work runs off the async workers: plans on
//! rayon's global pool, at most one per worker at a time ([`on_rayon`]), and
//! scenario precomputation on a pool of its own ([`precompute`]).
//!
//! | Method | Path | Success |
//! |---|---|---|
//! | GET | `/healthz` | 200 `{"status":"ok"}` |
//! | GET | `/v1/scenarios` | 200 `{"scenarios":[…]}` |
//! | POST | `/v1/scenarios` | 201 (new) or 200 (existing) summary |
//! | GET | `/v1/scenarios/{id}` | 200 summary |
//! | DELETE | `/v1/scenarios/{id}` | 204 |
//! | GET | `/v1/scenarios/{id}/stats` | 200 per-cell statistics |
//! | POST | `/v1/scenarios/{id}/plan` | 200 [`PlanResponse`](crate::planner::PlanResponse) |
//! | POST | `/v1/plan` | 200 plan (scenario by id or inline) |
//! | POST | `/v1/scenarios/{id}/evaluate` | 200 [`EvaluateResponse`](crate::evaluate::EvaluateResponse) |
//! | POST | `/v1/evaluate` | 200 scores (scenario by id or inline) |
//! | POST | `/v1/sessions` | 201 session |
//! | GET | `/v1/sessions/{id}` | 200 session |
//! | DELETE | `/v1/sessions/{id}` | 204 |
//! | POST | `/v1/sessions/{id}/step` | 200 plan and step number |

/// The rules of a scenario spec that no JSON Schema can state, for the
/// operations' descriptions (the fuzzer's list is `.ci/schemathesis/hooks.py`).
macro_rules! spec_rules {
    () => {
        " Rules no schema can state (each a 422 whose `detail` names the field): the zone's \
        width and height are whole multiples of `cell_size`, and the lattice has at most \
        4,000,000 cells; every source lies strictly outside the zone; a source without \
        `direction` is beside exactly one edge of the zone or gives a `heading` whose \
        half-plane holds the zone; some direction of each source's cone enters the zone; \
        `target_speed` is required when some source gives no `speeds`; a source's weights sum \
        to a finite number; and Σ rate·diagonal/speed over the speed classes is at most 1e9 \
        (the statistics stay finite)."
    };
}

/// The rules of a plan request that no JSON Schema can state.
macro_rules! plan_rules {
    () => {
        " Rules no schema can state (each a 422 whose `detail` names the field): every sensor \
        and history position lies in the scenario's zone, and sensor ids are unique."
    };
}

/// The rules of an evaluate request's paths that no JSON Schema can state.
macro_rules! path_rules {
    () => {
        " The paths' rules (each a 422 whose `detail` names the field): one path per sensor, \
        each naming a sensor of `sensors` once, of exactly T cells (the horizon's steps 1..T), \
        every cell on the lattice and outside the no-go zones, each step a move of at most the \
        sensor type's speed (king moves) that free cells allow, from the sensor's own cell."
    };
}

pub mod config;
pub mod error;
pub mod evaluate;
pub mod extract;
pub mod health;
pub mod middleware;
pub mod openapi;
pub mod plan;
pub mod scenarios;
pub mod serve;
pub mod sessions;

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

use axum::Router;
use axum::error_handling::HandleErrorLayer;
use axum::extract::DefaultBodyLimit;
use axum::http::{HeaderValue, Method, Uri, header};
use axum::routing::{get, post};
use tower::ServiceBuilder;
use tower::limit::GlobalConcurrencyLimitLayer;
use tower_http::cors::{Any, CorsLayer};
use tower_http::request_id::{MakeRequestUuid, PropagateRequestIdLayer, SetRequestIdLayer};
use tower_http::trace::{DefaultOnFailure, TraceLayer};
use tracing::Level;

use self::config::{Config, Settings};
use crate::catalog::{PlannerCache, Registry};
use crate::limits::MAX_BODY_BYTES;
use crate::store::{PgStore, Store};

pub use error::{ApiError, Problem};

/// Pieces of work that may wait for a rayon worker, per worker; past that,
/// more are shed at once with 503. Eight plans of the reference workload
/// are ~5 ms of queue: a burst is absorbed, while under sustained overload
/// clients hear "retry" at once instead of timing out in a queue that only
/// grows (and the server would then be planning for clients already gone).
pub const QUEUE_PER_WORKER: usize = 8;

/// Work admitted to rayon at once: one piece per worker. With more, the
/// pieces would interleave on the workers (a worker waiting in a join runs
/// other jobs meanwhile), so all of them would finish late together, their
/// working sets evicting each other from cache. The rest wait here in
/// arrival order (the semaphore is fair), and a request whose client leaves
/// while waiting is never computed.
struct WorkQueue {
    slots: Arc<tokio::sync::Semaphore>,
    waiting: AtomicUsize,
    max_waiting: usize,
}

fn work_queue() -> &'static WorkQueue {
    static QUEUE: OnceLock<WorkQueue> = OnceLock::new();
    QUEUE.get_or_init(|| {
        let workers = rayon::current_num_threads();
        WorkQueue {
            slots: Arc::new(tokio::sync::Semaphore::new(workers)),
            waiting: AtomicUsize::new(0),
            max_waiting: QUEUE_PER_WORKER * workers,
        }
    })
}

/// Counts a request as waiting while it exists (a cancelled wait included).
struct Waiting<'a>(&'a AtomicUsize);

impl Drop for Waiting<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::Relaxed);
    }
}

/// Runs CPU work (a plan) on rayon's global pool and awaits its result:
/// one hop from the async worker straight to the thread that plans, whose
/// parallel parts then split without further hand-offs (see
/// [`Planner::plan`](crate::planner::Planner::plan)). At most one piece runs per worker; up to
/// [`QUEUE_PER_WORKER`] per worker wait, in arrival order.
///
/// # Errors
/// [`ApiError::Overloaded`] when the queue is full, and
/// [`ApiError::Internal`] if the work panicked.
pub async fn on_rayon<T: Send + 'static>(
    work: impl FnOnce() -> T + Send + 'static,
) -> Result<T, ApiError> {
    let permit = admit().await?;
    let (tx, rx) = tokio::sync::oneshot::channel();
    rayon::spawn(move || {
        // Held until the work ends, even when the client has left.
        let _permit = permit;
        // A request dropped while queued (client gone, timed out) is not
        // planned: under overload, dead work would otherwise fill the queue
        // and starve the live requests.
        if tx.is_closed() {
            return;
        }
        // A panic becomes a 500 (rayon would abort the process).
        let _ = tx.send(std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)));
    });
    match rx.await {
        Ok(Ok(value)) => Ok(value),
        Ok(Err(_)) => Err(ApiError::Internal("the planning task panicked".into())),
        Err(_) => Err(ApiError::Internal("the planning task was lost".into())),
    }
}

/// A place among the workers for one piece of work: at once when one is
/// free, else after those queued before it, or [`ApiError::Overloaded`]
/// at once when the queue is full.
async fn admit() -> Result<tokio::sync::OwnedSemaphorePermit, ApiError> {
    let queue = work_queue();
    match queue.slots.clone().try_acquire_owned() {
        Ok(permit) => Ok(permit),
        Err(_) => {
            if queue.waiting.fetch_add(1, Ordering::Relaxed) >= queue.max_waiting {
                queue.waiting.fetch_sub(1, Ordering::Relaxed);
                count_shed();
                return Err(ApiError::Overloaded);
            }
            let _waiting = Waiting(&queue.waiting);
            queue
                .slots
                .clone()
                .acquire_owned()
                .await
                .map_err(|_| ApiError::Internal("the work queue is closed".into()))
        }
    }
}

/// Runs short CPU work on this async worker, admitted like [`on_rayon`]'s
/// (one piece per rayon worker, the same queue and shedding): for a pool of
/// one thread, the hop to it and back costs two thread switches a request
/// on a core that does both. Only for work of a few milliseconds: this
/// worker serves no other request meanwhile, and a deadline cannot stop it
/// before it ends.
///
/// # Errors
/// As [`on_rayon`].
pub async fn on_this_worker<T>(work: impl FnOnce() -> T) -> Result<T, ApiError> {
    let _permit = admit().await?;
    // The requests that arrived meanwhile queue (or are shed) first.
    tokio::task::yield_now().await;
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(work))
        .map_err(|_| ApiError::Internal("the planning task panicked".into()))
}

/// True when work sent to [`on_rayon`] now would be shed: every worker
/// busy and the queue full. A hint for shedding a request before its body
/// is parsed ([`extract::QueuedJson`]); `on_rayon` decides for itself.
pub(crate) fn queue_full() -> bool {
    let queue = work_queue();
    queue.slots.available_permits() == 0
        && queue.waiting.load(Ordering::Relaxed) >= queue.max_waiting
}

/// Counts a request shed for load.
pub(crate) fn count_shed() {
    metrics::counter!("vigil_http_shed_total").increment(1);
}

/// State shared by every handler.
#[derive(Debug, Clone)]
pub struct AppState {
    /// The registered scenarios.
    pub registry: Arc<Registry>,
    /// Planners of scenarios planned inline (`POST /v1/plan`).
    pub cache: Arc<PlannerCache>,
    /// Step-by-step clients' sessions.
    pub sessions: Arc<sessions::SessionStore>,
    /// Limits, keys and CORS.
    pub settings: Arc<Settings>,
}

impl AppState {
    /// State with the built-in scenarios registered, nothing stored and
    /// default settings (precomputes the built-ins, which is CPU work: call
    /// it at startup).
    pub fn new() -> Self {
        Self::with_registry(Registry::with_builtins())
    }

    /// State over a given registry, with default settings.
    pub fn with_registry(registry: Registry) -> Self {
        Self::with_settings(registry, Settings::default())
    }

    /// State over a given registry and settings (which set the registry's
    /// bounds on precomputation).
    pub fn with_settings(registry: Registry, settings: Settings) -> Self {
        registry.set_limits(settings.job_limits());
        Self {
            registry: Arc::new(registry),
            cache: Arc::new(PlannerCache::new(settings.cache_bytes)),
            sessions: Arc::new(sessions::SessionStore::new(
                settings.session_ttl,
                settings.max_sessions,
            )),
            settings: Arc::new(settings),
        }
    }

    /// State from the server's configuration: opens the store under
    /// `data_dir` and rebuilds the statistics of what it holds.
    pub fn from_config(config: &Config) -> std::io::Result<Self> {
        let (store, stored) = Store::open(&config.data_dir)?;
        let settings = Settings::from(config);
        Ok(Self::with_settings(
            Registry::with_store(store, stored, settings.job_limits()),
            settings,
        ))
    }
}

impl AppState {
    /// State from the server's configuration with scenarios in the
    /// database `store` (connected and migrated): starts following its
    /// deletions on the current runtime ([`Registry::watch`]).
    pub fn from_database(config: &Config, store: PgStore) -> Self {
        let settings = Settings::from(config);
        let registry = Registry::with_database(store, settings.job_limits(), settings.cache_bytes);
        registry.watch();
        Self::with_settings(registry, settings)
    }
}

impl Default for AppState {
    fn default() -> Self {
        Self::new()
    }
}

/// The application: every route; on /v1, the API key check (when set), then
/// load shedding past a global concurrency limit (503) and a time limit
/// (504); problem+json fallbacks for unknown routes (404) and methods (405);
/// a body limit of [`MAX_BODY_BYTES`] (413); request metrics, request ids,
/// tracing and CORS (when configured).
pub fn router(state: AppState) -> Router {
    let settings = state.settings.clone();
    let v1 = Router::new()
        .route(
            "/v1/scenarios",
            get(scenarios::list).post(scenarios::create),
        )
        .route(
            "/v1/scenarios/{id}",
            get(scenarios::get).delete(scenarios::delete),
        )
        .route("/v1/scenarios/{id}/stats", get(scenarios::stats))
        .route("/v1/scenarios/{id}/plan", post(plan::plan))
        .route("/v1/plan", post(plan::plan_inline))
        .route("/v1/scenarios/{id}/evaluate", post(evaluate::evaluate))
        .route("/v1/evaluate", post(evaluate::evaluate_inline))
        .route("/v1/sessions", post(sessions::create))
        .route(
            "/v1/sessions/{id}",
            get(sessions::get).delete(sessions::delete),
        )
        .route("/v1/sessions/{id}/step", post(sessions::step))
        .layer(
            ServiceBuilder::new()
                .layer(HandleErrorLayer::new(middleware::overload_error))
                .load_shed()
                .layer(GlobalConcurrencyLimitLayer::new(settings.max_in_flight))
                .timeout(settings.request_timeout),
        )
        .layer(axum::middleware::from_fn_with_state(
            state.clone(),
            middleware::require_key,
        ));
    let app = Router::new()
        .route("/healthz", get(health::healthz))
        .route("/openapi.json", get(openapi::serve))
        .route("/metrics", get(middleware::render))
        .merge(v1)
        // Must follow the routes: it applies to those already added.
        .method_not_allowed_fallback(method_not_allowed)
        .fallback(not_found)
        .layer(DefaultBodyLimit::max(MAX_BODY_BYTES))
        .layer(axum::middleware::from_fn(middleware::track))
        // Failures are logged where they are made (`ApiError`), once and
        // at their level; shed requests (503) not at all above debug.
        .layer(TraceLayer::new_for_http().on_failure(DefaultOnFailure::new().level(Level::DEBUG)))
        .layer(PropagateRequestIdLayer::x_request_id())
        .layer(SetRequestIdLayer::x_request_id(MakeRequestUuid));
    let app = match cors(&settings.cors_origins) {
        Some(layer) => app.layer(layer),
        None => app,
    };
    // Install the metrics recorder before the first request records.
    middleware::prometheus();
    app.with_state(state)
}

/// The CORS layer for the configured origins, if any.
fn cors(origins: &[String]) -> Option<CorsLayer> {
    if origins.is_empty() {
        return None;
    }
    let layer = CorsLayer::new()
        .allow_methods([Method::GET, Method::POST, Method::DELETE])
        .allow_headers([header::CONTENT_TYPE, header::AUTHORIZATION]);
    Some(if origins.iter().any(|o| o == "*") {
        layer.allow_origin(Any)
    } else {
        let list: Vec<HeaderValue> = origins
            .iter()
            .filter_map(|o| HeaderValue::from_str(o).ok())
            .collect();
        layer.allow_origin(list)
    })
}

async fn not_found(uri: Uri) -> ApiError {
    ApiError::RouteNotFound(uri.path().to_owned())
}

async fn method_not_allowed(method: Method, uri: Uri) -> ApiError {
    ApiError::MethodNotAllowed {
        method: method.to_string(),
        path: uri.path().to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::time::Duration;

    use axum::extract::FromRequest;

    use super::{ApiError, QUEUE_PER_WORKER, extract, on_rayon, queue_full, work_queue};

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
}
