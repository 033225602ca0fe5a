//! The sessions of this replica, in memory: bounded by an idle time to live
//! and a count, the least recently used evicted first; expired sessions are
//! dropped at the next session request.

use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use lru::LruCache;

use super::error::ApiError;
use crate::metric_names;
use crate::session::Session;

/// A session shared by its requests; its steps run one at a time.
pub type Shared = Arc<tokio::sync::Mutex<Session>>;

/// The sessions of this replica: an LRU map bounded by count and idle time.
#[derive(Debug)]
pub struct SessionStore {
    inner: Mutex<LruCache<String, (Shared, Instant)>>,
    ttl: Duration,
    capacity: usize,
}

impl SessionStore {
    /// A store of at most `capacity` sessions, each dropped after `ttl`
    /// without a request.
    pub fn new(ttl: Duration, capacity: usize) -> Self {
        Self {
            inner: Mutex::new(LruCache::unbounded()),
            ttl,
            capacity: capacity.max(1),
        }
    }

    /// The idle time to live.
    pub fn ttl(&self) -> Duration {
        self.ttl
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, LruCache<String, (Shared, Instant)>> {
        // Every critical section is a single map operation: poisoning
        // cannot leave it half-updated.
        self.inner.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Drops the sessions idle longer than the time to live: the least
    /// recently used come first, so only the expired are visited.
    fn sweep(&self, map: &mut LruCache<String, (Shared, Instant)>, now: Instant) {
        while let Some((_, (_, used))) = map.peek_lru() {
            if now.duration_since(*used) <= self.ttl {
                break;
            }
            map.pop_lru();
            metrics::counter!(metric_names::SESSIONS_EVICTED_TOTAL, "reason" => "idle")
                .increment(1);
        }
        metrics::gauge!(metric_names::SESSIONS_LIVE).set(map.len() as f64);
    }

    /// Keeps a new session under a fresh id, evicting the least recently
    /// used past the capacity.
    pub fn insert(&self, session: Session) -> (String, Shared) {
        let id = format!("ss-{}", uuid::Uuid::new_v4().simple());
        let shared = Arc::new(tokio::sync::Mutex::new(session));
        let now = Instant::now();
        let mut map = self.lock();
        self.sweep(&mut map, now);
        while map.len() >= self.capacity {
            map.pop_lru();
            metrics::counter!(metric_names::SESSIONS_EVICTED_TOTAL, "reason" => "capacity")
                .increment(1);
        }
        map.put(id.clone(), (shared.clone(), now));
        metrics::gauge!(metric_names::SESSIONS_LIVE).set(map.len() as f64);
        (id, shared)
    }

    /// A live session, marked as used now.
    ///
    /// # Errors
    /// [`ApiError::SessionNotFound`] for an unknown, expired or evicted id.
    pub fn get(&self, id: &str) -> Result<Shared, ApiError> {
        let now = Instant::now();
        let mut map = self.lock();
        self.sweep(&mut map, now);
        match map.get_mut(id) {
            Some((session, used)) => {
                *used = now;
                Ok(session.clone())
            }
            None => Err(self.not_found(id)),
        }
    }

    /// Removes a session.
    ///
    /// # Errors
    /// [`ApiError::SessionNotFound`] for an unknown, expired or evicted id.
    pub fn remove(&self, id: &str) -> Result<(), ApiError> {
        let mut map = self.lock();
        self.sweep(&mut map, Instant::now());
        let removed = map.pop(id).map(|_| ()).ok_or_else(|| self.not_found(id));
        metrics::gauge!(metric_names::SESSIONS_LIVE).set(map.len() as f64);
        removed
    }

    fn not_found(&self, id: &str) -> ApiError {
        ApiError::SessionNotFound {
            id: id.to_owned(),
            ttl_s: self.ttl.as_secs(),
        }
    }
}
