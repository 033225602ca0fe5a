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

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

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
