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

use std::collections::btree_map::Entry as MapEntry;
use std::collections::{BTreeMap, VecDeque};
use std::sync::{Arc, OnceLock, PoisonError, RwLock};
use std::time::{Duration, Instant};

use super::error::ApiError;
use crate::cancel::{CancelToken, Cancelled, Progress};
use crate::cost;
use crate::planner::Planner;
use crate::scenario::{BUILTIN_IDS, Scenario, builtins};
use crate::store::Store;

/// The bounds on precomputation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JobLimits {
    /// A registration predicted to take longer than this (milliseconds,
    /// wall time on the precompute pool) runs as a job.
    pub sync_precompute_ms: f64,
    /// Jobs running at once.
    pub jobs: usize,
    /// Jobs waiting at most; past it a registration is refused with 503.
    pub queue: usize,
}

impl Default for JobLimits {
    fn default() -> Self {
        Self {
            sync_precompute_ms: 1000.0,
            jobs: 1,
            queue: 16,
        }
    }
}

/// Which pool a precomputation runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pool {
    /// Registrations answered when done (and inline scenarios).
    Sync,
    /// Background jobs.
    Jobs,
}

/// The precompute pools: threads of their own, so a large scenario's many
/// tasks do not sit ahead of every plan's on rayon's global pool; they
/// share the cores through the OS scheduler instead. Jobs have a pool
/// apart from synchronous registrations: in one pool, a small
/// registration's work would queue behind every block of a running job.
fn pool(which: Pool) -> Option<&'static rayon::ThreadPool> {
    static SYNC: OnceLock<Option<rayon::ThreadPool>> = OnceLock::new();
    static JOBS: OnceLock<Option<rayon::ThreadPool>> = OnceLock::new();
    let (cell, name) = match which {
        Pool::Sync => (&SYNC, "vigil-precompute"),
        Pool::Jobs => (&JOBS, "vigil-job"),
    };
    cell.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .thread_name(move |i| format!("{name}-{i}"))
            .build()
            .map_err(|e| tracing::warn!(error = %e, "no precompute pool; using the global one"))
            .ok()
    })
    .as_ref()
}

/// Predicted wall time of precomputing `s` on the precompute pool,
/// milliseconds: the model's CPU time ([`cost::precompute_ms`]) shared by
/// the pool's threads (the work splits evenly over blocks of cells).
pub fn predicted_precompute_ms(s: &Scenario) -> f64 {
    let threads =
        pool(Pool::Sync).map_or_else(rayon::current_num_threads, |p| p.current_num_threads());
    cost::precompute_ms(s) / threads.max(1) as f64
}

/// Precomputes a scenario's statistics on the precompute pool.
pub fn precompute(scenario: Scenario) -> Planner {
    match precompute_cancellable(scenario, &CancelToken::never(), &Progress::default()) {
        Ok(planner) => planner,
        Err(Cancelled) => unreachable!("work that is never cancelled finishes"),
    }
}

/// [`precompute`], stopping within one block of cells once `cancel` is
/// cancelled, and advancing `progress` (see [`Planner::precompute`]).
///
/// # Errors
/// [`Cancelled`] once `cancel` is cancelled.
pub fn precompute_cancellable(
    scenario: Scenario,
    cancel: &CancelToken,
    progress: &Progress,
) -> Result<Planner, Cancelled> {
    precompute_on(Pool::Sync, scenario, cancel, progress)
}

fn precompute_on(
    which: Pool,
    scenario: Scenario,
    cancel: &CancelToken,
    progress: &Progress,
) -> Result<Planner, Cancelled> {
    let planner = match pool(which) {
        Some(pool) => pool.install(|| Planner::precompute(scenario, cancel, progress)),
        None => Planner::precompute(scenario, cancel, progress),
    }?;
    metrics::histogram!("vigil_precompute_seconds").record(planner.precompute_ms / 1e3);
    Ok(planner)
}

/// A scenario being precomputed in the background, or waiting to be.
#[derive(Debug)]
pub struct Job {
    /// The scenario.
    pub scenario: Scenario,
    /// Predicted wall time of its precomputation, milliseconds.
    pub predicted_ms: f64,
    cancel: CancelToken,
    progress: Progress,
    started: OnceLock<Instant>,
}

impl Job {
    fn new(scenario: Scenario) -> Self {
        Self {
            predicted_ms: predicted_precompute_ms(&scenario),
            scenario,
            cancel: CancelToken::new(),
            progress: Progress::default(),
            started: OnceLock::new(),
        }
    }

    /// Seconds until this running job ends: from its measured rate once a
    /// few blocks are done, from the prediction before.
    fn remaining_s(&self) -> f64 {
        let Some(started) = self.started.get() else {
            return self.predicted_ms / 1e3;
        };
        let elapsed = started.elapsed().as_secs_f64();
        let done = self.progress.fraction();
        if done >= 0.02 {
            elapsed * (1.0 - done) / done
        } else {
            (self.predicted_ms / 1e3 - elapsed).max(0.0)
        }
    }
}

/// Where a registered scenario is in its lifecycle.
#[derive(Debug, Clone)]
pub enum Entry {
    /// Precomputed: plans are served.
    Ready(Arc<Planner>),
    /// Queued or precomputing.
    Pending(Arc<Job>),
}

/// What a pending scenario's status says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JobStatus {
    /// Its place in the queue (1 = next), or `None` while it runs.
    pub queue_position: Option<usize>,
    /// Share of its blocks of cells done, 0..1.
    pub progress: f64,
    /// Seconds until it is ready, estimated.
    pub eta_s: f64,
}

impl JobStatus {
    /// Seconds a client should wait before asking again (`Retry-After`).
    pub fn retry_after_s(&self) -> u64 {
        self.eta_s.ceil().clamp(1.0, 3600.0) as u64
    }
}

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
    store: Option<Store>,
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
        Self::from_parts(scenarios, None, JobLimits::default())
    }

    /// The built-ins plus the scenarios kept in `store`: those predicted
    /// within the synchronous budget are precomputed now (in parallel), the
    /// others start again as jobs, in id order, whatever the queue's bound
    /// (they were accepted before). New registrations are written there.
    pub fn with_store(store: Store, stored: Vec<Scenario>, limits: JobLimits) -> Self {
        use rayon::prelude::*;
        let (now, later): (Vec<Scenario>, Vec<Scenario>) = stored
            .into_iter()
            .partition(|s| predicted_precompute_ms(s) <= limits.sync_precompute_ms);
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
        let registry = Self::from_parts(scenarios, Some(store), limits);
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
        metrics::gauge!("vigil_scenarios_loaded").set(state.scenarios.len() as f64);
        metrics::gauge!("vigil_precompute_jobs", "state" => "queued").set(state.queue.len() as f64);
        metrics::gauge!("vigil_precompute_jobs", "state" => "running")
            .set(state.running.len() as f64);
    }

    /// The planner of a ready scenario.
    pub fn get(&self, id: &str) -> Option<Arc<Planner>> {
        match self.read().scenarios.get(id)? {
            Entry::Ready(p) => Some(p.clone()),
            Entry::Pending(_) => None,
        }
    }

    /// The planner of a scenario to plan with.
    ///
    /// # Errors
    /// [`ApiError::ScenarioNotFound`] for an unknown id,
    /// [`ApiError::ScenarioNotReady`] while it is pending.
    pub fn ready(&self, id: &str) -> Result<Arc<Planner>, ApiError> {
        let state = self.read();
        match state.scenarios.get(id) {
            Some(Entry::Ready(p)) => Ok(p.clone()),
            Some(Entry::Pending(job)) => Err(ApiError::ScenarioNotReady {
                id: id.to_owned(),
                status: Self::job_status(&state, job),
            }),
            None => Err(ApiError::ScenarioNotFound(id.to_owned())),
        }
    }

    /// A scenario in whatever state, with its job's status when pending.
    pub fn entry(&self, id: &str) -> Option<(Entry, Option<JobStatus>)> {
        let state = self.read();
        let entry = state.scenarios.get(id)?.clone();
        let status = Self::status_of(&state, &entry);
        Some((entry, status))
    }

    /// Every scenario, sorted by id, with its job's status when pending.
    pub fn list(&self) -> Vec<(Entry, Option<JobStatus>)> {
        let state = self.read();
        state
            .scenarios
            .values()
            .map(|e| (e.clone(), Self::status_of(&state, e)))
            .collect()
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
    /// there, writing it to the store first (so an acknowledged scenario is
    /// on disk). Returns the entry now registered under that id and whether
    /// it is the one passed in. Blocking I/O: call it off the async workers.
    pub fn insert(&self, planner: Arc<Planner>) -> Result<(Entry, bool), ApiError> {
        if let Some((existing, _)) = self.entry(&planner.scenario.id) {
            return Ok((existing, false));
        }
        self.save(&planner.scenario)?;
        let mut state = self.write();
        let out = match state.scenarios.entry(planner.scenario.id.clone()) {
            MapEntry::Occupied(e) => (e.get().clone(), false),
            MapEntry::Vacant(e) => (e.insert(Entry::Ready(planner)).clone(), true),
        };
        self.update_gauges(&state);
        Ok(out)
    }

    /// Accepts a scenario as a precomputation job: stores its spec durably,
    /// queues the job and starts it when a slot is free. Returns the entry
    /// now registered under its id (an existing one wins) and whether it is
    /// the new job. Blocking I/O: call it off the async workers.
    ///
    /// # Errors
    /// [`ApiError::QueueFull`] when as many jobs wait as the queue holds
    /// and none could start now; [`ApiError::Internal`] if the store fails.
    pub fn submit(&self, scenario: Scenario) -> Result<(Entry, bool), ApiError> {
        if let Some((existing, _)) = self.entry(&scenario.id) {
            return Ok((existing, false));
        }
        self.check_room()?;
        self.save(&scenario)?;
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
        Ok(out)
    }

    fn check_room(&self) -> Result<(), ApiError> {
        let state = self.read();
        let free_slot = state.running.len() < state.limits.jobs.max(1) && state.queue.is_empty();
        if !free_slot && state.queue.len() >= state.limits.queue {
            let wait: f64 = state.running.iter().map(|j| j.remaining_s()).sum::<f64>()
                / state.limits.jobs.max(1) as f64;
            return Err(ApiError::QueueFull {
                limit: state.limits.queue,
                retry_after_s: wait.ceil().clamp(1.0, 3600.0) as u64,
            });
        }
        Ok(())
    }

    fn save(&self, scenario: &Scenario) -> Result<(), ApiError> {
        match &self.shared.store {
            Some(store) => store
                .save(scenario)
                .map_err(|e| ApiError::Internal(format!("storing scenario {}: {e}", scenario.id))),
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
            precompute_on(Pool::Jobs, job.scenario.clone(), &job.cancel, &job.progress)
        }));
        {
            let mut state = self.write();
            state.running.retain(|j| !Arc::ptr_eq(j, &job));
            let current =
                matches!(state.scenarios.get(&id), Some(Entry::Pending(j)) if Arc::ptr_eq(j, &job));
            match result {
                Ok(Ok(planner)) if current => {
                    tracing::info!(%id, precompute_ms = planner.precompute_ms, predicted_ms = job.predicted_ms, "precompute job done");
                    state.scenarios.insert(id, Entry::Ready(Arc::new(planner)));
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

    /// Removes a scenario, from the store too; a pending one's job is
    /// cancelled at once. Fails with [`ApiError::BuiltinScenario`] for a
    /// built-in and [`ApiError::ScenarioNotFound`] for an unknown id.
    /// Blocking I/O.
    pub fn remove(&self, id: &str) -> Result<Entry, ApiError> {
        if Self::is_builtin(id) {
            return Err(ApiError::BuiltinScenario(id.to_owned()));
        }
        if self.entry(id).is_none() {
            return Err(ApiError::ScenarioNotFound(id.to_owned()));
        }
        if let Some(store) = &self.shared.store {
            store
                .remove(id)
                .map_err(|e| ApiError::Internal(format!("removing scenario {id}: {e}")))?;
        }
        let mut state = self.write();
        let removed = state
            .scenarios
            .remove(id)
            .ok_or_else(|| ApiError::ScenarioNotFound(id.to_owned()))?;
        if let Entry::Pending(job) = &removed {
            job.cancel.cancel();
            state.queue.retain(|j| !Arc::ptr_eq(j, job));
            metrics::counter!("vigil_cancelled_total", "kind" => "precompute", "reason" => "deleted")
                .increment(1);
        }
        self.update_gauges(&state);
        Ok(removed)
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
