//! Precomputation: the bounds on it, the thread pools it runs on, and the
//! jobs that run it in the background for large scenarios.

use std::sync::{Arc, OnceLock};
use std::time::Instant;

use crate::cancel::{CancelToken, Cancelled, Progress};
use crate::cost;
use crate::metric_names;
use crate::planner::Planner;
use crate::scenario::Scenario;

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

impl JobLimits {
    /// The defaults, which `vigil-server`'s flags also start from.
    pub const DEFAULT: JobLimits = JobLimits {
        sync_precompute_ms: 1000.0,
        jobs: 1,
        queue: 16,
    };

    /// The predicted wall time of precomputing `s`
    /// ([`predicted_precompute_ms`]) when it is above
    /// `sync_precompute_ms`: such a precompute runs as a job, never
    /// inline in a request.
    pub fn too_long_inline(&self, s: &Scenario) -> Option<f64> {
        let predicted = predicted_precompute_ms(s);
        (predicted > self.sync_precompute_ms).then_some(predicted)
    }
}

impl Default for JobLimits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Which pool a precomputation runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Pool {
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

pub(super) fn precompute_on(
    which: Pool,
    scenario: Scenario,
    cancel: &CancelToken,
    progress: &Progress,
) -> Result<Planner, Cancelled> {
    let planner = match pool(which) {
        Some(pool) => pool.install(|| Planner::precompute(scenario, cancel, progress)),
        None => Planner::precompute(scenario, cancel, progress),
    }?;
    metrics::histogram!(metric_names::PRECOMPUTE_SECONDS).record(planner.precompute_ms / 1e3);
    Ok(planner)
}

/// A scenario being precomputed in the background, or waiting to be.
#[derive(Debug)]
pub struct Job {
    /// The scenario.
    pub scenario: Scenario,
    /// Predicted wall time of its precomputation, milliseconds.
    pub predicted_ms: f64,
    pub(super) cancel: CancelToken,
    pub(super) progress: Progress,
    pub(super) started: OnceLock<Instant>,
}

impl Job {
    pub(super) fn new(scenario: Scenario) -> Self {
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
    pub(super) fn remaining_s(&self) -> f64 {
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

/// The id of an entry's scenario.
pub fn entry_id(entry: &Entry) -> &str {
    match entry {
        Entry::Ready(p) => &p.scenario.id,
        Entry::Pending(j) => &j.scenario.id,
    }
}
