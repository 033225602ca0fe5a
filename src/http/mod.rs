//! HTTP layer: a thin JSON API over the [`planner`](crate::planner).
//!
//! [`router`] builds the whole application from an [`AppState`]; the binary
//! only binds and serves it. Every error is an [`ApiError`], rendered as
//! `application/problem+json`. CPU work (precomputing a scenario, planning)
//! runs on tokio's blocking pool.
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

pub mod error;
pub mod extract;
pub mod health;
pub mod plan;
pub mod scenarios;

use std::collections::BTreeMap;
use std::collections::btree_map::Entry;
use std::sync::{Arc, PoisonError, RwLock};

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::{Method, Uri};
use axum::routing::{get, post};
use tower_http::trace::TraceLayer;

use crate::planner::Planner;
use crate::scenario::{BUILTIN_IDS, builtins};

pub use error::{ApiError, Problem};

/// Largest request body accepted, bytes. Large enough for a plan request
/// with the most targets allowed ([`MAX_TARGETS`](crate::planner::MAX_TARGETS))
/// written at full precision.
pub const MAX_BODY_BYTES: usize = 8 * 1024 * 1024;

/// The registered scenarios, each with its precomputed [`Planner`].
#[derive(Debug, Default)]
pub struct Registry {
    planners: RwLock<BTreeMap<String, Arc<Planner>>>,
}

impl Registry {
    /// A registry with no scenarios.
    pub fn empty() -> Self {
        Self::default()
    }

    /// A registry holding the built-in scenarios ([`BUILTIN_IDS`]),
    /// precomputed now.
    pub fn with_builtins() -> Self {
        let planners = builtins()
            .into_iter()
            .map(|s| (s.id.clone(), Arc::new(Planner::new(s))))
            .collect();
        Self {
            planners: RwLock::new(planners),
        }
    }

    /// True for the ids of built-in scenarios, which cannot be deleted.
    pub fn is_builtin(id: &str) -> bool {
        BUILTIN_IDS.contains(&id)
    }

    // A panic while holding the lock cannot leave the map half-updated (every
    // critical section is a single map operation), so poisoning is ignored.
    fn read(&self) -> std::sync::RwLockReadGuard<'_, BTreeMap<String, Arc<Planner>>> {
        self.planners.read().unwrap_or_else(PoisonError::into_inner)
    }

    fn write(&self) -> std::sync::RwLockWriteGuard<'_, BTreeMap<String, Arc<Planner>>> {
        self.planners
            .write()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// The planner of a scenario.
    pub fn get(&self, id: &str) -> Option<Arc<Planner>> {
        self.read().get(id).cloned()
    }

    /// Every planner, sorted by scenario id.
    pub fn list(&self) -> Vec<Arc<Planner>> {
        self.read().values().cloned().collect()
    }

    /// Registers a planner under its scenario's id unless one is already
    /// there. Returns the planner now registered under that id and whether
    /// it is the one passed in (an existing entry is never replaced).
    pub fn insert(&self, planner: Arc<Planner>) -> (Arc<Planner>, bool) {
        match self.write().entry(planner.scenario.id.clone()) {
            Entry::Occupied(e) => (Arc::clone(e.get()), false),
            Entry::Vacant(e) => (Arc::clone(e.insert(planner)), true),
        }
    }

    /// Removes a scenario. Fails with [`ApiError::BuiltinScenario`] for a
    /// built-in and [`ApiError::ScenarioNotFound`] for an unknown id.
    pub fn remove(&self, id: &str) -> Result<Arc<Planner>, ApiError> {
        if Self::is_builtin(id) {
            return Err(ApiError::BuiltinScenario(id.to_owned()));
        }
        self.write()
            .remove(id)
            .ok_or_else(|| ApiError::ScenarioNotFound(id.to_owned()))
    }
}

/// State shared by every handler.
#[derive(Debug, Clone)]
pub struct AppState {
    /// The registered scenarios.
    pub registry: Arc<Registry>,
}

impl AppState {
    /// State with the built-in scenarios registered (precomputes them, which
    /// is CPU work: call it at startup).
    pub fn new() -> Self {
        Self::with_registry(Registry::with_builtins())
    }

    /// State over a given registry.
    pub fn with_registry(registry: Registry) -> Self {
        Self {
            registry: Arc::new(registry),
        }
    }
}

impl Default for AppState {
    fn default() -> Self {
        Self::new()
    }
}

/// The application: every route, problem+json fallbacks for unknown routes
/// (404) and methods (405), a body limit of [`MAX_BODY_BYTES`] and request
/// tracing.
pub fn router(state: AppState) -> Router {
    Router::new()
        .route("/healthz", get(health::healthz))
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
        // Must follow the routes: it applies to those already added.
        .method_not_allowed_fallback(method_not_allowed)
        .fallback(not_found)
        .layer(DefaultBodyLimit::max(MAX_BODY_BYTES))
        .layer(TraceLayer::new_for_http())
        .with_state(state)
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
