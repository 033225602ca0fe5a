//! The planning queue: CPU work (plans, evaluations) admitted to rayon's
//! pool one piece per worker, a bounded number waiting in arrival order,
//! the rest shed at once with 503.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

use super::error::ApiError;
use crate::metric_names;

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
/// is parsed ([`super::extract::QueuedJson`]); `on_rayon` decides for itself.
pub(crate) fn queue_full() -> bool {
    let queue = work_queue();
    queue.slots.available_permits() == 0
        && queue.waiting.load(Ordering::Relaxed) >= queue.max_waiting
}

/// Counts a request shed for load.
pub(crate) fn count_shed() {
    metrics::counter!(metric_names::HTTP_SHED_TOTAL).increment(1);
}

#[cfg(test)]
mod tests;
