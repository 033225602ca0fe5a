//! Where a plan's parallel loops run.
//!
//! On a worker of a rayon pool they split among the pool's workers. On any
//! other thread (a server with one core plans on its async worker) they run
//! on that thread, one item after the other: a parallel loop entered from
//! outside the pool would hand its work to the pool and wait for it, two
//! thread switches per loop. Each loop of a plan computes its items
//! independently and combines them in a fixed order, so the answer is the
//! same to the last bit either way.

/// The least items per piece of a plan's parallel loops (their
/// `with_min_len`): 1 on a worker of a rayon pool, every item elsewhere.
pub(crate) fn min_len() -> usize {
    if rayon::current_thread_index().is_some() {
        1
    } else {
        usize::MAX
    }
}

/// How many items a plan's parallel loop runs at once: the pool's workers
/// on a worker of a rayon pool, one elsewhere. A loop that may stop early
/// takes its items in batches of this many.
pub(crate) fn width() -> usize {
    if rayon::current_thread_index().is_some() {
        rayon::current_num_threads()
    } else {
        1
    }
}
