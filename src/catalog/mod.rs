//! The scenario catalogue: which scenarios this replica serves, where they
//! are kept, and the jobs that precompute the large ones.
//!
//! - [`registry`]: the catalogue itself ([`Registry`]): built-ins, the
//!   registered scenarios and their lifecycle (`queued` → `precomputing` →
//!   `ready`), kept in the file store or cached from PostgreSQL with one
//!   load per id at a time;
//! - [`jobs`]: the bounds on precomputation ([`JobLimits`]), its thread
//!   pools and the background jobs;
//! - [`cache`]: planners bounded by memory (inline scenarios, and the
//!   PostgreSQL catalogue's scenarios used here);
//! - `shared`: with a database, each registered scenario precomputed once
//!   for every replica, and loaded by the others;
//! - `watch`: following deletions made through other replicas;
//! - [`error`]: what it fails with ([`CatalogError`]).
//!
//! It is plain domain code: the HTTP layer maps [`CatalogError`] to its
//! responses.

pub mod cache;
pub mod error;
pub mod jobs;
pub mod registry;
mod shared;
mod watch;

pub use cache::PlannerCache;
pub use error::CatalogError;
pub use jobs::{
    Entry, Job, JobLimits, JobStatus, entry_id, precompute, precompute_cancellable,
    predicted_precompute_ms,
};
pub use registry::{Listed, Registry};
