//! The registered scenarios and the jobs that precompute the large ones.
//!
//! A scenario whose precomputation is predicted ([`crate::cost`]) to take
//! longer than the synchronous budget is registered as a *job*: its spec is
//! stored durably at once, and the job waits in a queue (arrival order) for
//! one of `precompute_jobs` slots, then precomputes in blocks of cells that
//! report progress and check a cancellation token. When it ends the
//! scenario is ready. Deleting a pending scenario cancels its job; after a
//! restart, stored scenarios that were pending (or are large) start again.
//!
//! Lifecycle of a scenario: `queued` → `precomputing` → `ready`, or only
//! `ready` for a synchronous registration.
//!
//! Where the registered scenarios are kept ([`crate::store`]):
//! - With the file store (the default) the registry holds every one, loaded
//!   at start; the directory is this replica's own.
//! - With PostgreSQL the database is the catalogue and the registry a cache
//!   of it: a scenario is read from the database on this replica's first
//!   request for it and precomputed then (or started as a job if large),
//!   and its planner is kept in a cache bounded by memory, as inline
//!   scenarios are. Deletions reach every replica through LISTEN/NOTIFY
//!   ([`Registry::watch`]); after every (re)connection of the listener the
//!   held ids are checked against the table, so a notification missed
//!   during an outage never leaves a deleted scenario served. While the
//!   database is unreachable, what is held keeps serving, and what needs
//!   the database answers [`CatalogError::DatabaseUnavailable`].

use std::collections::btree_map::Entry as MapEntry;
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError, RwLock};
use std::time::{Duration, Instant};

use super::cache::PlannerCache;
use super::error::CatalogError;
use super::jobs::{Entry, Job, JobLimits, JobStatus, Pool, entry_id, precompute, precompute_on};
use super::shared;
use crate::metric_names;
use crate::planner::Planner;
use crate::scenario::{BUILTIN_IDS, Scenario, builtins};
use crate::store::{DbError, PgStore, Store};

#[derive(Debug, Default)]
struct State {
    scenarios: BTreeMap<String, Entry>,
    /// Jobs waiting for a slot, in arrival order.
    queue: VecDeque<Arc<Job>>,
    /// Jobs precomputing now.
    running: Vec<Arc<Job>>,
    limits: JobLimits,
}

#[derive(Debug, Default)]
struct Shared {
    state: RwLock<State>,
    /// The file store, if scenarios are kept in files.
    store: Option<Store>,
    /// The database, if scenarios are kept in PostgreSQL.
    db: Option<Database>,
}

/// The PostgreSQL catalogue and what this replica holds of it.
#[derive(Debug)]
struct Database {
    store: PgStore,
    /// Planners of ready registered scenarios used here, bounded by memory
    /// (pending ones are in the registry's map, with their jobs).
    cache: PlannerCache,
    /// Evictions so far: a load that saw this change while it read the
    /// row checks the row again before keeping the scenario.
    evictions: AtomicU64,
    /// One load per id at a time; the others wait and find it held.
    loading: Mutex<HashMap<String, Arc<tokio::sync::Mutex<()>>>>,
    /// The runtime its calls run on, for the precomputation jobs' threads
    /// ([`shared::obtain`]); `None` when made outside one.
    runtime: Option<tokio::runtime::Handle>,
}

/// One scenario of the catalogue, as [`Registry::catalogue`] lists it.
#[derive(Debug, Clone)]
pub enum Listed {
    /// Held by this replica, in whatever state.
    Held(Entry, Option<JobStatus>),
    /// In the database, not (yet) used on this replica.
    Stored(Box<Scenario>),
}

/// True for ids that can name a registered scenario (`s-` and 16 hex
/// digits, see [`crate::scenario`]): others need no database look-up.
fn derivable(id: &str) -> bool {
    id.len() == 18
        && id.starts_with("s-")
        && id[2..]
            .bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
}

/// The registered scenarios: built-in, registered and ready, or pending
/// (see the module docs). Cloning gives another handle to the same ones.
#[derive(Debug, Clone, Default)]
pub struct Registry {
    shared: Arc<Shared>,
}

impl Registry {
    /// A registry with no scenarios.
    pub fn empty() -> Self {
        Self::default()
    }

    /// A registry holding the built-in scenarios ([`BUILTIN_IDS`]),
    /// precomputed now.
    pub fn with_builtins() -> Self {
        let scenarios = builtins()
            .into_iter()
            .map(|s| (s.id.clone(), Entry::Ready(Arc::new(Planner::new(s)))))
            .collect();
        Self::from_parts(scenarios, None, None, JobLimits::default())
    }

    /// The built-ins, with registered scenarios in PostgreSQL: read on
    /// first use, their planners kept in a cache of at most `cache_bytes`.
    /// Call [`Registry::watch`] from the async runtime to follow deletions.
    pub fn with_database(store: PgStore, limits: JobLimits, cache_bytes: usize) -> Self {
        let scenarios = builtins()
            .into_iter()
            .map(|s| (s.id.clone(), Entry::Ready(Arc::new(Planner::new(s)))))
            .collect();
        let db = Database {
            store,
            cache: PlannerCache::new(cache_bytes),
            evictions: AtomicU64::new(0),
            loading: Mutex::new(HashMap::new()),
            runtime: tokio::runtime::Handle::try_current().ok(),
        };
        Self::from_parts(scenarios, None, Some(db), limits)
    }

    /// The database, when scenarios are kept in PostgreSQL.
    pub fn database(&self) -> Option<&PgStore> {
        self.shared.db.as_ref().map(|db| &db.store)
    }

    /// The built-ins plus the scenarios kept in `store`: those predicted
    /// within the synchronous budget are precomputed now (in parallel), the
    /// others start again as jobs, in id order, whatever the queue's bound
    /// (they were accepted before). New registrations are written there.
    pub fn with_store(store: Store, stored: Vec<Scenario>, limits: JobLimits) -> Self {
        use rayon::prelude::*;
        let (now, later): (Vec<Scenario>, Vec<Scenario>) = stored
            .into_iter()
            .partition(|s| limits.too_long_inline(s).is_none());
        let mut scenarios: BTreeMap<String, Entry> = builtins()
            .into_iter()
            .map(|s| (s.id.clone(), Entry::Ready(Arc::new(Planner::new(s)))))
            .collect();
        let planners: Vec<Planner> = now.into_par_iter().map(precompute).collect();
        for p in planners {
            tracing::info!(id = %p.scenario.id, precompute_ms = p.precompute_ms, "loaded a stored scenario");
            scenarios
                .entry(p.scenario.id.clone())
                .or_insert_with(|| Entry::Ready(Arc::new(p)));
        }
        let registry = Self::from_parts(scenarios, Some(store), None, limits);
        {
            let mut state = registry.write();
            for s in later {
                if state.scenarios.contains_key(&s.id) {
                    continue;
                }
                let job = Arc::new(Job::new(s));
                tracing::info!(id = %job.scenario.id, predicted_ms = job.predicted_ms, "resuming the precomputation of a stored scenario");
                state
                    .scenarios
                    .insert(job.scenario.id.clone(), Entry::Pending(job.clone()));
                state.queue.push_back(job);
            }
        }
        registry.pump();
        registry
    }

    fn from_parts(
        scenarios: BTreeMap<String, Entry>,
        store: Option<Store>,
        db: Option<Database>,
        limits: JobLimits,
    ) -> Self {
        let registry = Self {
            shared: Arc::new(Shared {
                state: RwLock::new(State {
                    scenarios,
                    limits,
                    ..State::default()
                }),
                store,
                db,
            }),
        };
        registry.update_gauges(&registry.read());
        registry
    }

    /// Sets the bounds on precomputation (for jobs submitted from now on).
    pub fn set_limits(&self, limits: JobLimits) {
        self.write().limits = limits;
        self.pump();
    }

    /// The bounds on precomputation.
    pub fn limits(&self) -> JobLimits {
        self.read().limits
    }

    /// True for the ids of built-in scenarios, which cannot be deleted.
    pub fn is_builtin(id: &str) -> bool {
        BUILTIN_IDS.contains(&id)
    }

    // A panic while holding the lock cannot leave the state half-updated
    // (no critical section panics between its updates), so poisoning is
    // ignored.
    fn read(&self) -> std::sync::RwLockReadGuard<'_, State> {
        self.shared
            .state
            .read()
            .unwrap_or_else(PoisonError::into_inner)
    }

    fn write(&self) -> std::sync::RwLockWriteGuard<'_, State> {
        self.shared
            .state
            .write()
            .unwrap_or_else(PoisonError::into_inner)
    }

    fn update_gauges(&self, state: &State) {
        let cached = self.shared.db.as_ref().map_or(0, |db| db.cache.usage().0);
        metrics::gauge!(metric_names::SCENARIOS_LOADED)
            .set((state.scenarios.len() + cached) as f64);
        metrics::gauge!(metric_names::PRECOMPUTE_JOBS, "state" => "queued")
            .set(state.queue.len() as f64);
        metrics::gauge!(metric_names::PRECOMPUTE_JOBS, "state" => "running")
            .set(state.running.len() as f64);
    }

    /// The planner of a ready scenario held here.
    pub fn get(&self, id: &str) -> Option<Arc<Planner>> {
        match self.entry(id)? {
            (Entry::Ready(p), _) => Some(p),
            (Entry::Pending(_), _) => None,
        }
    }

    /// The planner of a scenario held here, to plan with.
    ///
    /// # Errors
    /// [`CatalogError::NotFound`] for an id not held here,
    /// [`CatalogError::NotReady`] while it is pending.
    pub fn ready(&self, id: &str) -> Result<Arc<Planner>, CatalogError> {
        match self.entry(id) {
            Some(found) => Self::planner_of(id, found),
            None => Err(CatalogError::NotFound(id.to_owned())),
        }
    }

    fn planner_of(
        id: &str,
        found: (Entry, Option<JobStatus>),
    ) -> Result<Arc<Planner>, CatalogError> {
        match found {
            (Entry::Ready(p), _) => Ok(p),
            (Entry::Pending(job), status) => Err(CatalogError::NotReady {
                id: id.to_owned(),
                status: status.unwrap_or(JobStatus {
                    queue_position: None,
                    progress: job.progress.fraction(),
                    eta_s: job.remaining_s(),
                }),
            }),
        }
    }

    /// A scenario held here in whatever state, with its job's status when
    /// pending.
    pub fn entry(&self, id: &str) -> Option<(Entry, Option<JobStatus>)> {
        {
            let state = self.read();
            if let Some(entry) = state.scenarios.get(id) {
                let status = Self::status_of(&state, entry);
                return Some((entry.clone(), status));
            }
        }
        let planner = self.shared.db.as_ref()?.cache.get(id)?;
        Some((Entry::Ready(planner), None))
    }

    /// A scenario in whatever state: held here, or (with a database) read
    /// from it and made ready here, or started as a job if large.
    ///
    /// # Errors
    /// [`CatalogError::NotFound`] for an unknown id,
    /// [`CatalogError::DatabaseUnavailable`] if it must be read and cannot be.
    pub async fn lookup(&self, id: &str) -> Result<(Entry, Option<JobStatus>), CatalogError> {
        if let Some(found) = self.entry(id) {
            return Ok(found);
        }
        match &self.shared.db {
            Some(db) if derivable(id) => self.load(db, id).await,
            _ => Err(CatalogError::NotFound(id.to_owned())),
        }
    }

    /// The planner of a scenario to plan with, read from the database on a
    /// miss ([`Registry::lookup`]).
    ///
    /// # Errors
    /// Those of [`Registry::lookup`], and [`CatalogError::NotReady`]
    /// while it is pending.
    pub async fn resolve(&self, id: &str) -> Result<Arc<Planner>, CatalogError> {
        let found = self.lookup(id).await?;
        Self::planner_of(id, found)
    }

    /// Reads `id` from the database and makes it ready here (a large one is
    /// started as a job), one load per id at a time.
    async fn load(
        &self,
        db: &Database,
        id: &str,
    ) -> Result<(Entry, Option<JobStatus>), CatalogError> {
        let lock = db
            .loading
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .entry(id.to_owned())
            .or_default()
            .clone();
        let result = {
            let _one = lock.lock().await;
            match self.entry(id) {
                Some(found) => Ok(found),
                None => self.load_now(db, id).await,
            }
        };
        let mut loading = db.loading.lock().unwrap_or_else(PoisonError::into_inner);
        // Ours and the map's: nobody else waits on this id.
        if Arc::strong_count(&lock) <= 2 {
            loading.remove(id);
        }
        result
    }

    async fn load_now(
        &self,
        db: &Database,
        id: &str,
    ) -> Result<(Entry, Option<JobStatus>), CatalogError> {
        let seen = db.evictions.load(Ordering::SeqCst);
        let row = db
            .store
            .get(id)
            .await
            .map_err(CatalogError::from)?
            .ok_or_else(|| CatalogError::NotFound(id.to_owned()))?;
        let scenario = row.scenario;
        if self.limits().too_long_inline(&scenario).is_some() {
            tracing::info!(%id, "a stored scenario is precomputed here as a job");
            let (entry, _) = self.enqueue(scenario);
            let status = self.entry(id).and_then(|(_, status)| status);
            return Ok((entry, status));
        }
        let planner = match shared::load(&db.store, &scenario).await {
            Some(planner) => Arc::new(planner),
            None => {
                let planner =
                    Arc::new(tokio::task::spawn_blocking(move || precompute(scenario)).await?);
                shared::save_later(&db.store, planner.clone());
                planner
            }
        };
        tracing::info!(%id, precompute_ms = planner.precompute_ms, "loaded a stored scenario");
        // Deleted while it was read or precomputed: its notification may
        // have come before it was held, so ask the table again.
        if db.evictions.load(Ordering::SeqCst) != seen {
            let present = db
                .store
                .existing(&[id.to_owned()])
                .await
                .map_err(CatalogError::from)?;
            if !present.contains(id) {
                return Err(CatalogError::NotFound(id.to_owned()));
            }
        }
        Ok((Entry::Ready(self.hold(db, planner)), None))
    }

    /// Keeps a ready planner of a registered scenario in the database's
    /// cache; returns the one now held under its id.
    fn hold(&self, db: &Database, planner: Arc<Planner>) -> Arc<Planner> {
        let state = self.write();
        let held = match state.scenarios.get(&planner.scenario.id) {
            Some(Entry::Ready(p)) => p.clone(),
            _ => db.cache.insert(planner),
        };
        self.update_gauges(&state);
        held
    }

    /// Every scenario held here, sorted by id, with its job's status when
    /// pending.
    pub fn list(&self) -> Vec<(Entry, Option<JobStatus>)> {
        let mut held: Vec<(Entry, Option<JobStatus>)> = {
            let state = self.read();
            state
                .scenarios
                .values()
                .map(|e| (e.clone(), Self::status_of(&state, e)))
                .collect()
        };
        if let Some(db) = &self.shared.db {
            for id in db.cache.ids() {
                if let Some(p) = db.cache.get(&id) {
                    held.push((Entry::Ready(p), None));
                }
            }
            held.sort_by(|a, b| entry_id(&a.0).cmp(entry_id(&b.0)));
        }
        held
    }

    /// The catalogue, sorted by id: every scenario held here with the file
    /// store; with a database, the built-ins and every stored scenario,
    /// as held here or only stored.
    ///
    /// # Errors
    /// [`CatalogError::DatabaseUnavailable`] if the database cannot be read.
    pub async fn catalogue(&self) -> Result<Vec<Listed>, CatalogError> {
        let Some(db) = &self.shared.db else {
            return Ok(self
                .list()
                .into_iter()
                .map(|(e, s)| Listed::Held(e, s))
                .collect());
        };
        let rows = db.store.list().await.map_err(CatalogError::from)?;
        let mut listed: Vec<(String, Listed)> = BUILTIN_IDS
            .iter()
            .filter_map(|id| self.entry(id))
            .map(|(e, s)| (entry_id(&e).to_owned(), Listed::Held(e, s)))
            .collect();
        for row in rows {
            let id = row.scenario.id.clone();
            let item = match self.entry(&id) {
                Some((e, s)) => Listed::Held(e, s),
                None => Listed::Stored(Box::new(row.scenario)),
            };
            listed.push((id, item));
        }
        listed.sort_by(|a, b| a.0.cmp(&b.0));
        Ok(listed.into_iter().map(|(_, l)| l).collect())
    }

    fn status_of(state: &State, entry: &Entry) -> Option<JobStatus> {
        match entry {
            Entry::Ready(_) => None,
            Entry::Pending(job) => Some(Self::job_status(state, job)),
        }
    }

    /// A pending job's status. A queued job waits for the running ones and
    /// those ahead of it, spread over the slots, then for its own run.
    fn job_status(state: &State, job: &Arc<Job>) -> JobStatus {
        let progress = job.progress.fraction();
        match state.queue.iter().position(|j| Arc::ptr_eq(j, job)) {
            None => JobStatus {
                queue_position: None,
                progress,
                eta_s: job.remaining_s(),
            },
            Some(place) => {
                let ahead: f64 = state.running.iter().map(|j| j.remaining_s()).sum::<f64>()
                    + state
                        .queue
                        .iter()
                        .take(place)
                        .map(|j| j.remaining_s())
                        .sum::<f64>();
                JobStatus {
                    queue_position: Some(place + 1),
                    progress,
                    eta_s: ahead / state.limits.jobs.max(1) as f64 + job.remaining_s(),
                }
            }
        }
    }

    /// Registers a planner under its scenario's id unless one is already
    /// there, storing it first (so an acknowledged scenario is durable).
    /// Returns the entry now registered under that id and whether this call
    /// created it (with a database: whether it created the row, so the same
    /// spec registered through two replicas at once is created once).
    ///
    /// # Errors
    /// [`CatalogError::Internal`] if the file store fails,
    /// [`CatalogError::DatabaseUnavailable`] if the database does.
    pub async fn insert(&self, planner: Arc<Planner>) -> Result<(Entry, bool), CatalogError> {
        if let Some((existing, _)) = self.entry(&planner.scenario.id) {
            return Ok((existing, false));
        }
        if let Some(db) = &self.shared.db {
            let created = db
                .store
                .insert(&planner.scenario)
                .await
                .map_err(CatalogError::from)?;
            if created {
                shared::save_later(&db.store, planner.clone());
            }
            return Ok((Entry::Ready(self.hold(db, planner)), created));
        }
        let registry = self.clone();
        tokio::task::spawn_blocking(move || {
            registry.save(&planner.scenario)?;
            let mut state = registry.write();
            let out = match state.scenarios.entry(planner.scenario.id.clone()) {
                MapEntry::Occupied(e) => (e.get().clone(), false),
                MapEntry::Vacant(e) => (e.insert(Entry::Ready(planner)).clone(), true),
            };
            registry.update_gauges(&state);
            Ok(out)
        })
        .await?
    }

    /// Accepts a scenario as a precomputation job: stores its spec durably,
    /// queues the job and starts it when a slot is free. Returns the entry
    /// now registered under its id (an existing one wins) and whether it is
    /// a new job.
    ///
    /// # Errors
    /// [`CatalogError::QueueFull`] when as many jobs wait as the queue holds
    /// and none could start now; [`CatalogError::Internal`] if the file store
    /// fails, [`CatalogError::DatabaseUnavailable`] if the database does.
    pub async fn submit(&self, scenario: Scenario) -> Result<(Entry, bool), CatalogError> {
        if let Some((existing, _)) = self.entry(&scenario.id) {
            return Ok((existing, false));
        }
        self.check_room()?;
        match &self.shared.db {
            Some(db) => {
                db.store
                    .insert(&scenario)
                    .await
                    .map_err(CatalogError::from)?;
            }
            None => {
                let registry = self.clone();
                let copy = scenario.clone();
                tokio::task::spawn_blocking(move || registry.save(&copy)).await??;
            }
        }
        Ok(self.enqueue(scenario))
    }

    /// Queues a job for a stored scenario unless its id is held already.
    fn enqueue(&self, scenario: Scenario) -> (Entry, bool) {
        let job = Arc::new(Job::new(scenario));
        let out = {
            let mut state = self.write();
            match state.scenarios.get(&job.scenario.id) {
                Some(existing) => (existing.clone(), false),
                None => {
                    state
                        .scenarios
                        .insert(job.scenario.id.clone(), Entry::Pending(job.clone()));
                    state.queue.push_back(job.clone());
                    (Entry::Pending(job), true)
                }
            }
        };
        self.pump();
        out
    }

    fn check_room(&self) -> Result<(), CatalogError> {
        let state = self.read();
        let free_slot = state.running.len() < state.limits.jobs.max(1) && state.queue.is_empty();
        if !free_slot && state.queue.len() >= state.limits.queue {
            let wait: f64 = state.running.iter().map(|j| j.remaining_s()).sum::<f64>()
                / state.limits.jobs.max(1) as f64;
            return Err(CatalogError::QueueFull {
                limit: state.limits.queue,
                retry_after_s: wait.ceil().clamp(1.0, 3600.0) as u64,
            });
        }
        Ok(())
    }

    /// Writes a scenario to the file store, if there is one. Blocking I/O.
    fn save(&self, scenario: &Scenario) -> Result<(), CatalogError> {
        match &self.shared.store {
            Some(store) => store.save(scenario).map_err(|e| {
                CatalogError::Internal(format!("storing scenario {}: {e}", scenario.id))
            }),
            None => Ok(()),
        }
    }

    /// Starts queued jobs while slots are free, each on a thread of its own
    /// that drives the precompute pool.
    fn pump(&self) {
        let mut state = self.write();
        while state.running.len() < state.limits.jobs.max(1) {
            let Some(job) = state.queue.pop_front() else {
                break;
            };
            state.running.push(job.clone());
            let _ = job.started.set(Instant::now());
            let registry = self.clone();
            let spawned = std::thread::Builder::new()
                .name("vigil-job".into())
                .spawn(move || registry.run(job));
            if let Err(e) = spawned {
                tracing::error!(error = %e, "cannot start a precompute job");
            }
        }
        self.update_gauges(&state);
    }

    /// Runs a job to its end, then makes its scenario ready (unless it was
    /// deleted meanwhile) and starts the next.
    fn run(&self, job: Arc<Job>) {
        let id = job.scenario.id.clone();
        tracing::info!(%id, predicted_ms = job.predicted_ms, "precompute job started");
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let scenario = job.scenario.clone();
            match &self.shared.db {
                Some(Database {
                    store,
                    runtime: Some(runtime),
                    ..
                }) => shared::obtain(runtime, store, scenario, &job.cancel, &job.progress),
                _ => precompute_on(Pool::Jobs, scenario, &job.cancel, &job.progress),
            }
        }));
        {
            let mut state = self.write();
            state.running.retain(|j| !Arc::ptr_eq(j, &job));
            let current =
                matches!(state.scenarios.get(&id), Some(Entry::Pending(j)) if Arc::ptr_eq(j, &job));
            match result {
                Ok(Ok(planner)) if current => {
                    tracing::info!(%id, precompute_ms = planner.precompute_ms, predicted_ms = job.predicted_ms, "precompute job done");
                    match &self.shared.db {
                        // Held in the bounded cache, like every registered
                        // scenario read from the database.
                        Some(db) => {
                            db.cache.insert(Arc::new(planner));
                            state.scenarios.remove(&id);
                        }
                        None => {
                            state.scenarios.insert(id, Entry::Ready(Arc::new(planner)));
                        }
                    }
                }
                Ok(_) => tracing::info!(%id, "precompute job cancelled"),
                Err(_) => {
                    // A bug; the spec stays stored, so a restart tries again.
                    tracing::error!(%id, "precompute job panicked");
                    if current {
                        state.scenarios.remove(&id);
                    }
                }
            }
            self.update_gauges(&state);
        }
        self.pump();
    }

    /// Removes a scenario from the store (file or database) and from this
    /// replica; a pending one's job is cancelled at once.
    ///
    /// # Errors
    /// [`CatalogError::Builtin`] for a built-in,
    /// [`CatalogError::NotFound`] for an unknown id,
    /// [`CatalogError::Internal`] if the file store fails and
    /// [`CatalogError::DatabaseUnavailable`] if the database does.
    pub async fn remove(&self, id: &str) -> Result<(), CatalogError> {
        if Self::is_builtin(id) {
            return Err(CatalogError::Builtin(id.to_owned()));
        }
        if let Some(db) = &self.shared.db {
            let existed = derivable(id) && db.store.delete(id).await.map_err(CatalogError::from)?;
            // Every replica evicts it on the notification; this one at once.
            self.evict(id);
            return if existed {
                Ok(())
            } else {
                Err(CatalogError::NotFound(id.to_owned()))
            };
        }
        if self.entry(id).is_none() {
            return Err(CatalogError::NotFound(id.to_owned()));
        }
        let registry = self.clone();
        let owned = id.to_owned();
        tokio::task::spawn_blocking(move || {
            if let Some(store) = &registry.shared.store {
                store.remove(&owned).map_err(|e| {
                    CatalogError::Internal(format!("removing scenario {owned}: {e}"))
                })?;
            }
            if registry.evict(&owned) {
                Ok(())
            } else {
                Err(CatalogError::NotFound(owned))
            }
        })
        .await?
    }

    /// Drops a registered scenario from this replica (not from the store),
    /// cancelling its job if pending; true if it was held.
    pub fn evict(&self, id: &str) -> bool {
        if Self::is_builtin(id) {
            return false;
        }
        let mut state = self.write();
        let mut held = false;
        if let Some(removed) = state.scenarios.remove(id) {
            held = true;
            if let Entry::Pending(job) = &removed {
                job.cancel.cancel();
                state.queue.retain(|j| !Arc::ptr_eq(j, job));
                metrics::counter!(metric_names::CANCELLED_TOTAL, "kind" => "precompute", "reason" => "deleted")
                    .increment(1);
            }
        }
        if let Some(db) = &self.shared.db {
            db.evictions.fetch_add(1, Ordering::SeqCst);
            held |= db.cache.get(id).is_some();
            db.cache.remove(id);
        }
        self.update_gauges(&state);
        held
    }

    /// Checks the registered scenarios held here against the database's
    /// table and drops those no longer in it; returns how many.
    ///
    /// # Errors
    /// [`DbError`] if the database cannot be read.
    pub async fn recheck(&self) -> Result<usize, DbError> {
        let Some(db) = &self.shared.db else {
            return Ok(0);
        };
        let mut held: Vec<String> = self
            .read()
            .scenarios
            .keys()
            .filter(|id| !Self::is_builtin(id))
            .cloned()
            .collect();
        held.extend(db.cache.ids());
        if held.is_empty() {
            return Ok(0);
        }
        let present = db.store.existing(&held).await?;
        let mut dropped = 0;
        for id in held.iter().filter(|id| !present.contains(*id)) {
            tracing::info!(%id, "dropping a scenario deleted from the database");
            self.evict(id);
            dropped += 1;
        }
        Ok(dropped)
    }

    /// Waits until no job runs or waits, up to `timeout` (for tests and
    /// tools); true if they all ended.
    pub fn wait_idle(&self, timeout: Duration) -> bool {
        let until = Instant::now() + timeout;
        loop {
            {
                let state = self.read();
                if state.running.is_empty() && state.queue.is_empty() {
                    return true;
                }
            }
            if Instant::now() >= until {
                return false;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}
