//! What the catalogue can fail with. The HTTP layer maps each to a status
//! (`http::error`); nothing here knows about HTTP.

use super::jobs::JobStatus;
use crate::store::DbError;

/// A catalogue operation that did not succeed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CatalogError {
    /// No scenario has this id.
    #[error("no scenario with id `{0}`")]
    NotFound(String),
    /// The scenario is still being precomputed.
    #[error("scenario `{id}` is still being precomputed")]
    NotReady {
        /// The scenario's id.
        id: String,
        /// Its job's status.
        status: JobStatus,
    },
    /// A built-in scenario cannot be deleted.
    #[error("scenario `{0}` is built in and cannot be deleted")]
    Builtin(String),
    /// As many jobs wait as the queue holds, and none could start now.
    #[error("{limit} precomputation jobs are already waiting")]
    QueueFull {
        /// The queue's bound.
        limit: usize,
        /// Seconds until a slot is likely to free.
        retry_after_s: u64,
    },
    /// The file store failed to write or remove a scenario, or a
    /// background task failed: a broken disk or a bug, the message says
    /// which.
    #[error("{0}")]
    Internal(String),
    /// The PostgreSQL catalogue is unreachable or too slow.
    #[error("the scenario catalogue's database is unavailable")]
    DatabaseUnavailable,
}

impl From<DbError> for CatalogError {
    /// Logs the database's error here: the caller is only told to retry.
    fn from(e: DbError) -> Self {
        tracing::warn!(error = %e, "the scenario database is unavailable");
        CatalogError::DatabaseUnavailable
    }
}

impl From<tokio::task::JoinError> for CatalogError {
    fn from(e: tokio::task::JoinError) -> Self {
        CatalogError::Internal(format!("background task failed: {e}"))
    }
}
