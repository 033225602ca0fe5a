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
//! The file store keeps only each spec (statistics are rebuilt from it at
//! start). With a database, the catalogue keeps each spec with its
//! creation time, what a replica precomputed for it ([`precomputed`]) so
//! that the others load it instead, and the sessions ([`sessions`]).

pub mod file;
pub mod postgres;
pub mod precomputed;
pub mod sessions;

pub use file::{FORMAT, Store};
pub use postgres::{DbError, PgStore};
