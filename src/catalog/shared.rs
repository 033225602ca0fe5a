//! Precomputing a registered scenario once for every replica on the
//! database ([`crate::store::precomputed`]): a replica loads what another
//! stored, or claims the work, precomputes, and stores it; a replica that
//! finds the work claimed waits for the stored row instead of computing
//! too, and computes after all if the claim's holder dies without storing
//! (its lock goes with it).
//!
//! A stored precomputation of another format, of another scenario, or that
//! does not decode is never used: it is logged, deleted, and computed
//! again.

use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::runtime::Handle;

use super::jobs::{Pool, precompute_on};
use crate::cancel::{CancelToken, Cancelled, Progress};
use crate::codec::CodecError;
use crate::metric_names;
use crate::planner::{PRECOMPUTED_FORMAT, Planner};
use crate::scenario::Scenario;
use crate::store::PgStore;
use crate::store::precomputed::{Stored, unpack};

/// How often a replica waiting for another's precomputation looks for it.
const WAIT_POLL: Duration = Duration::from_millis(250);

/// Counts a precomputation by how this replica got it (`loaded`,
/// `computed`), or what became of a stored one (`stored`, `rejected`).
fn count(outcome: &'static str) {
    metrics::counter!(metric_names::PRECOMPUTED_TOTAL, "outcome" => outcome).increment(1);
}

/// The stored precomputation of `scenario`, if there is one that this
/// build reads (one that it does not is deleted, so it is stored again).
/// Its chunks are decompressed and decoded as they are read ([`unpack`]).
pub(super) async fn load(store: &PgStore, scenario: &Scenario) -> Option<Planner> {
    let id = scenario.id.clone();
    let started = Instant::now();
    let (to, parts) = std::sync::mpsc::channel();
    let wanted = scenario.clone();
    let decoding = tokio::task::spawn_blocking(move || {
        let decoded = unpack(parts, |head, next| {
            if head.format != PRECOMPUTED_FORMAT as i32 {
                return Err(format!(
                    "format {}, this server reads {PRECOMPUTED_FORMAT}",
                    head.format
                ));
            }
            let mut next = |read| next(read).map_err(CodecError);
            Planner::from_precomputed_pieces(wanted, head.raw_bytes, &mut next)
                .map_err(|e| e.to_string())
        });
        let (planner, compressed) = decoded?;
        Ok((planner?, compressed))
    });
    let sent = store.send_precomputed(&id, &to).await;
    drop(to);
    let decoded = decoding
        .await
        .unwrap_or_else(|e| Err(format!("decoding failed: {e}")));
    match sent {
        Ok(true) => {}
        Ok(false) => return None,
        Err(e) => {
            tracing::warn!(%id, error = %e, "cannot read a stored precomputation");
            return None;
        }
    }
    match decoded {
        Ok((planner, compressed)) => {
            tracing::info!(%id, compressed, load_ms = started.elapsed().as_secs_f64() * 1e3, "loaded a stored precomputation");
            count("loaded");
            Some(planner)
        }
        Err(reason) => {
            tracing::warn!(%id, %reason, "a stored precomputation cannot be used; computing it again");
            count("rejected");
            let _ = store.drop_precomputed(&id).await;
            None
        }
    }
}

/// `planner`'s precomputation, compressed to be stored (CPU work).
pub(super) fn pack(planner: &Planner) -> Option<Stored> {
    Stored::compress(PRECOMPUTED_FORMAT as i32, &planner.encode_precomputed())
        .map_err(|e| {
            tracing::error!(id = %planner.scenario.id, error = %e, "cannot compress a precomputation");
        })
        .ok()
}

/// Stores scenario `id`'s packed precomputation unless one is stored
/// already.
pub(super) async fn put(store: &PgStore, id: &str, stored: Stored) {
    let started = Instant::now();
    match store.store_precomputed(id, &stored).await {
        Ok(true) => {
            tracing::info!(%id, raw = stored.raw_bytes, compressed = stored.compressed_bytes(),
                store_ms = started.elapsed().as_secs_f64() * 1e3, "stored a precomputation");
            count("stored");
        }
        Ok(false) => {}
        Err(e) => tracing::warn!(%id, error = %e, "cannot store a precomputation"),
    }
}

/// Stores `planner`'s precomputation in the background, unless one is
/// stored already.
pub(super) fn save_later(store: &PgStore, planner: Arc<Planner>) {
    let store = store.clone();
    tokio::spawn(async move {
        let id = planner.scenario.id.clone();
        let packed = tokio::task::spawn_blocking(move || pack(&planner)).await;
        if let Ok(Some(stored)) = packed {
            put(&store, &id, stored).await;
        }
    });
}

/// A registered scenario's planner for a precomputation job, on its own
/// thread (not the runtime's): loaded if stored, else precomputed here
/// under a claim and stored, else (claimed by another replica) waited for.
/// Without the database it is precomputed here.
///
/// # Errors
/// [`Cancelled`] once `cancel` is cancelled (the scenario was deleted).
pub(super) fn obtain(
    runtime: &Handle,
    store: &PgStore,
    scenario: Scenario,
    cancel: &CancelToken,
    progress: &Progress,
) -> Result<Planner, Cancelled> {
    let id = scenario.id.clone();
    let mut waiting = false;
    loop {
        cancel.check()?;
        if let Some(planner) = runtime.block_on(load(store, &scenario)) {
            return Ok(planner);
        }
        let claim = match runtime.block_on(store.claim_precompute(&id)) {
            Ok(Some(claim)) => claim,
            Ok(None) => {
                if !waiting {
                    tracing::info!(%id, "another replica is precomputing this scenario; waiting for it");
                    waiting = true;
                }
                let deadline = Instant::now() + WAIT_POLL;
                while Instant::now() < deadline {
                    cancel.check()?;
                    std::thread::sleep(Duration::from_millis(25));
                }
                continue;
            }
            Err(e) => {
                tracing::warn!(%id, error = %e, "cannot claim a precomputation; computing it here");
                let planner = precompute_on(Pool::Jobs, scenario, cancel, progress)?;
                count("computed");
                return Ok(planner);
            }
        };
        // Stored by another between the look and the claim?
        if let Some(planner) = runtime.block_on(load(store, &scenario)) {
            runtime.block_on(claim.release());
            return Ok(planner);
        }
        let planner = precompute_on(Pool::Jobs, scenario, cancel, progress);
        if let Ok(planner) = &planner {
            count("computed");
            if let Some(stored) = pack(planner) {
                runtime.block_on(put(store, &id, stored));
            }
        }
        runtime.block_on(claim.release());
        return planner;
    }
}
