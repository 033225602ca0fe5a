//! Where registered scenarios are kept, so that an acknowledged
//! registration survives a restart.
//!
//! Two backends, one chosen at start-up:
//! - [`file`](mod@file) (the default): one JSON file per scenario in this replica's
//!   own directory (`--data-dir`). Nothing else to run, but each replica
//!   has a catalogue of its own.
//! - [`postgres`] (`--database-url`): one row per scenario in a PostgreSQL
//!   database, so every replica pointed at it serves the same catalogue.
//!   The schema comes from the migrations under `migrations/`, applied at
//!   start; deletions are pushed to every replica with LISTEN/NOTIFY.
//!
//! With a database, sessions are kept there too ([`sessions`]).
//!
//! Either way only the spec is kept (with its id, and in PostgreSQL its
//! creation time): statistics are rebuilt by each replica from the spec.

pub mod file;
pub mod postgres;
pub mod sessions;

pub use file::{FORMAT, Store};
pub use postgres::{DbError, PgStore};
