//! Following the PostgreSQL catalogue from a replica: deletions made
//! through any replica reach this one by LISTEN/NOTIFY, and the database's
//! health is checked every second.
//!
//! A notification can be missed while the listener is disconnected, so
//! after every (re)connection the held ids are checked against the table
//! ([`Registry::recheck`]) before notifications are followed again.

use std::time::Duration;

use super::registry::Registry;
use crate::store::postgres::Deletions;
use crate::store::{DbError, PgStore};

/// How often the database is pinged (`/healthz`, `vigil_database_up`).
const PING_EVERY: Duration = Duration::from_secs(1);
/// How long to wait before listening again after the listener failed.
const RELISTEN_AFTER: Duration = Duration::from_millis(250);
/// How often [`down`] looks at the ping's result.
const DOWN_POLL: Duration = Duration::from_millis(200);

impl Registry {
    /// With a database, starts the background tasks on the current tokio
    /// runtime: one follows deletions (evicting each deleted id at once,
    /// and after every (re)connection checking what is held against the
    /// table, see [`Registry::recheck`]); one checks every second that the
    /// database answers. Without one, does nothing.
    pub fn watch(&self) {
        let Some(store) = self.database().cloned() else {
            return;
        };
        let pinged = store.clone();
        tokio::spawn(async move {
            loop {
                pinged.ping().await;
                tokio::time::sleep(PING_EVERY).await;
            }
        });
        let registry = self.clone();
        tokio::spawn(async move {
            loop {
                match store.listen().await {
                    Ok(deletions) => follow(&registry, &store, deletions).await,
                    Err(e) => tracing::debug!(error = %e, "cannot follow deletions yet"),
                }
                tokio::time::sleep(RELISTEN_AFTER).await;
            }
        });
    }
}

/// After a (re)connection: drops what was deleted while nobody listened,
/// then evicts each deleted id as its notification comes, until the
/// connection is lost.
async fn follow(registry: &Registry, store: &PgStore, mut deletions: Deletions) {
    match registry.recheck().await {
        Ok(dropped) => tracing::info!(dropped, "following deletions in the database"),
        Err(e) => {
            tracing::warn!(error = %e, "cannot check the held scenarios");
            return;
        }
    }
    loop {
        let next = tokio::select! {
            next = deletions.next() => next,
            // A connection cut without a reset never ends `next`: the
            // check every second notices it instead.
            () = down(store) => Err(DbError::Down),
        };
        match next {
            Ok(id) => {
                if registry.evict(&id) {
                    tracing::info!(%id, "dropped a scenario deleted through another replica");
                }
            }
            Err(e) => {
                tracing::warn!(error = %e, "lost the database's deletion notifications; reconnecting");
                return;
            }
        }
    }
}

/// Resolves once the database's check every second has failed.
async fn down(store: &PgStore) {
    while store.is_up() {
        tokio::time::sleep(DOWN_POLL).await;
    }
}
