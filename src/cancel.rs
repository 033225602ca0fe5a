//! Cancellation of a request's work: the HTTP layer cancels a plan's token
//! when nobody waits for the answer any more (its deadline passed, or its
//! client went away), and the planner checks the token at coarse points
//! (per sensor and step of the search, per coordination round), so the
//! work stops soon after instead of running to the end for nobody.
//!
//! ```
//! use vigil::cancel::{CancelToken, Cancelled};
//! let token = CancelToken::new();
//! let worker = token.clone();
//! assert_eq!(worker.check(), Ok(()));
//! token.cancel();
//! assert_eq!(worker.check(), Err(Cancelled));
//! assert!(CancelToken::never().check().is_ok());
//! ```
//!
//! Long work (a scenario's precomputation) also reports its [`Progress`]:
//! the share of its blocks done, for the client watching the job.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// A shared flag: once cancelled, every clone reads cancelled.
#[derive(Debug, Clone, Default)]
pub struct CancelToken(Option<Arc<AtomicBool>>);

/// The work was cancelled before it finished.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the work was cancelled")]
pub struct Cancelled;

impl CancelToken {
    /// A token not yet cancelled.
    pub fn new() -> Self {
        Self(Some(Arc::new(AtomicBool::new(false))))
    }

    /// A token that is never cancelled (in-process callers, tests); its
    /// checks cost one branch.
    pub fn never() -> Self {
        Self(None)
    }

    /// Cancels the work of every clone of this token.
    pub fn cancel(&self) {
        if let Some(flag) = &self.0 {
            flag.store(true, Ordering::Relaxed);
        }
    }

    /// True once [`CancelToken::cancel`] was called on some clone.
    #[inline]
    pub fn is_cancelled(&self) -> bool {
        self.0.as_ref().is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// `Err(Cancelled)` once cancelled.
    #[inline]
    pub fn check(&self) -> Result<(), Cancelled> {
        if self.is_cancelled() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }
}

/// Progress of long work, counted in blocks: the worker sets the total
/// once and advances as blocks finish; any thread reads the fraction done.
///
/// ```
/// use vigil::cancel::Progress;
/// let p = Progress::default();
/// assert_eq!(p.fraction(), 0.0);
/// p.add_total(4);
/// p.advance(1);
/// assert_eq!(p.fraction(), 0.25);
/// ```
#[derive(Debug, Default)]
pub struct Progress {
    done: AtomicUsize,
    total: AtomicUsize,
}

impl Progress {
    /// Adds `blocks` to the work to do.
    pub fn add_total(&self, blocks: usize) {
        self.total.fetch_add(blocks, Ordering::Relaxed);
    }

    /// Records `blocks` more as done.
    pub fn advance(&self, blocks: usize) {
        self.done.fetch_add(blocks, Ordering::Relaxed);
    }

    /// The share of the blocks done, in `[0, 1]` (0 before any total).
    pub fn fraction(&self) -> f64 {
        let total = self.total.load(Ordering::Relaxed);
        if total == 0 {
            return 0.0;
        }
        (self.done.load(Ordering::Relaxed) as f64 / total as f64).min(1.0)
    }
}
