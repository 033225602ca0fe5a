//! The state every handler shares: the catalogue, the inline planners, the
//! sessions and the settings.

use std::sync::Arc;

use super::carries::Carries;
use super::config::{Config, Settings};
use super::session_store::SessionStore;
use crate::catalog::{PlannerCache, Registry};
use crate::store::{PgStore, Store};

/// State shared by every handler.
#[derive(Debug, Clone)]
pub struct AppState {
    /// The registered scenarios.
    pub registry: Arc<Registry>,
    /// Planners of scenarios planned inline (`POST /v1/plan`).
    pub cache: Arc<PlannerCache>,
    /// Step-by-step clients' sessions.
    pub sessions: Arc<SessionStore>,
    /// What the sessions' steps kept for their next steps, on this replica.
    pub carries: Arc<Carries>,
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
        let carries = Arc::new(Carries::new(
            settings.session_carry_bytes,
            settings.session_ttl,
        ));
        Self {
            registry: Arc::new(registry),
            cache: Arc::new(PlannerCache::new(settings.cache_bytes)),
            sessions: Arc::new(SessionStore::new(
                settings.session_ttl,
                settings.max_sessions,
                carries.clone(),
            )),
            carries,
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
    /// deletions on the current runtime ([`Registry::watch`]); sessions are
    /// kept in the database too.
    pub fn from_database(config: &Config, store: PgStore) -> Self {
        let settings = Settings::from(config);
        let registry =
            Registry::with_database(store.clone(), settings.job_limits(), settings.cache_bytes);
        registry.watch();
        let state = Self::with_settings(registry, settings);
        let s = &state.settings;
        let sessions = SessionStore::with_database(
            s.session_ttl,
            s.max_sessions,
            s.session_cache_bytes,
            store,
            state.carries.clone(),
        );
        Self {
            sessions: Arc::new(sessions),
            ..state
        }
    }
}

impl Default for AppState {
    fn default() -> Self {
        Self::new()
    }
}
