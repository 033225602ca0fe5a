//! Where sessions are kept, one of two ways chosen at start-up:
//! - **In this replica's memory** (no database): an LRU map bounded by an
//!   idle time to live and a count, the least recently used evicted first;
//!   expired sessions are dropped at the next session request.
//! - **In the database** (`--database-url`, [`crate::store::sessions`]):
//!   every replica serves every session. This replica's memory holds only
//!   a cache of sessions it served, bounded in bytes. A step is
//!   acknowledged only once stored over the version it was made from
//!   ([`SessionStore::save`]). It is made from the cached state, with no
//!   read, while no other replica moves the session on; once one did (the
//!   store failed), each step first checks the cached state against the
//!   row's version and reloads it if needed, until a check finds nobody
//!   moved it. A short step without an Idempotency-Key writes its new state
//!   while its plan is made and commits it once the plan is
//!   ([`SessionStore::save_early`]), so that only the commit waits for it.
//!
//! Either way a step answered for an `Idempotency-Key` is answered again,
//! unchanged, to a retry with that key and the same body
//! ([`Refreshed::Replay`]); with that key and another body it is refused
//! ([`ApiError::IdempotencyKeyReused`]).

use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use axum::body::Bytes;
use lru::LruCache;

use super::carries::Carries;
use super::error::ApiError;
use crate::metric_names;
use crate::planner::Planner;
use crate::session::{PreparedStep, Session, Snapshot};
use crate::store::sessions::{NewSession, StepWrite};
use crate::store::{DbError, PgStore};

/// What every session id starts with; 32 hexadecimal digits follow.
const SESSION_ID_PREFIX: &str = "ss-";

/// Whether `id` has the form of the ids [`SessionStore::create`] makes:
/// any other names no session, and is not looked up (nor cached, nor sent
/// to the database, which refuses some bytes).
fn is_session_id(id: &str) -> bool {
    id.strip_prefix(SESSION_ID_PREFIX)
        .is_some_and(|hex| hex.len() == 32 && hex.bytes().all(|b| b.is_ascii_hexdigit()))
}

/// A session shared by its requests on this replica; its steps here run
/// one at a time.
pub type Shared = Arc<tokio::sync::Mutex<Held>>;

/// A session as this replica holds it.
#[derive(Debug, Default)]
pub struct Held {
    /// The state, once loaded.
    session: Option<Session>,
    /// In the database: the row's version this state is.
    version: i64,
    /// The state may differ from the stored one (a step made here was not
    /// stored): reload it whatever the version.
    stale: bool,
    /// The last step this replica made: its Idempotency-Key, request
    /// digest and answer.
    last: Option<(String, [u8; 32], Bytes)>,
    /// In the database: a step of another replica was stored over one
    /// made here, so look at the row before making the next (a session
    /// served by one replica at a time makes its steps from the cache).
    shared: bool,
}

/// What a step or a read finds ([`SessionStore::refresh`]).
#[derive(Debug)]
pub enum Refreshed<'a> {
    /// The session, current, and the stored version it is at.
    Session(&'a mut Session, Base),
    /// The answer already given to this Idempotency-Key.
    Replay(Bytes),
}

/// The stored version of a refreshed session's state: what a step made
/// from it is stored over ([`SessionStore::save_early`]).
#[derive(Debug, Clone, Copy)]
pub struct Base(i64);

/// Plans predicted to take longer than this, ms, are stored once made
/// rather than while they are made ([`SessionStore::save_early`]): the
/// early write holds a pooled connection and its row's lock until its plan
/// ends.
const SAVE_EARLY_MAX_MS: f64 = 100.0;

/// A step's `Idempotency-Key` and its request's digest
/// ([`crate::session::StepRequest::digest`]): a retry has both of the step
/// it retries.
#[derive(Debug, Clone, Copy)]
pub struct StepKey<'a> {
    /// The header's value.
    pub key: &'a str,
    /// The request's digest.
    pub digest: [u8; 32],
}

/// The answer to replay to `key` when the session's last step had its key,
/// that step's request digest being `digest` (`None` for a step stored
/// without one, by a replica older than digests, which is trusted).
///
/// # Errors
/// [`ApiError::IdempotencyKeyReused`] when the digests differ.
fn replay<'a>(
    key: StepKey<'_>,
    digest: Option<&[u8]>,
    answer: Bytes,
) -> Result<Refreshed<'a>, ApiError> {
    match digest {
        Some(digest) if digest != key.digest => {
            Err(ApiError::IdempotencyKeyReused(key.key.to_owned()))
        }
        _ => Ok(Refreshed::Replay(answer)),
    }
}

/// A cached session and what it costs.
#[derive(Debug)]
struct Entry {
    held: Shared,
    used: Instant,
    bytes: usize,
}

#[derive(Debug)]
struct Map {
    lru: LruCache<String, Entry>,
    bytes: usize,
}

/// The sessions (see the module docs).
#[derive(Debug)]
pub struct SessionStore {
    map: Mutex<Map>,
    ttl: Duration,
    capacity: usize,
    /// With a database: the cache's bound, bytes.
    cache_bytes: usize,
    db: Option<PgStore>,
    /// The sessions' carries: a session's goes when it ends here.
    carries: Arc<Carries>,
}

impl SessionStore {
    /// Sessions in memory: at most `capacity`, each dropped after `ttl`
    /// without a request, with their steps' `carries`.
    pub fn new(ttl: Duration, capacity: usize, carries: Arc<Carries>) -> Self {
        Self {
            map: Mutex::new(Map {
                lru: LruCache::unbounded(),
                bytes: 0,
            }),
            ttl,
            capacity: capacity.max(1),
            cache_bytes: usize::MAX,
            db: None,
            carries,
        }
    }

    /// Sessions in database `db` (at most `capacity`, each dropped after
    /// `ttl` without a request), with a cache here of at most
    /// `cache_bytes`, and their steps' `carries`.
    pub fn with_database(
        ttl: Duration,
        capacity: usize,
        cache_bytes: usize,
        db: PgStore,
        carries: Arc<Carries>,
    ) -> Self {
        Self {
            cache_bytes,
            db: Some(db),
            ..Self::new(ttl, capacity, carries)
        }
    }

    /// The idle time to live.
    pub fn ttl(&self) -> Duration {
        self.ttl
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Map> {
        // Every critical section is a few map operations that cannot fail
        // half-way: poisoning cannot leave it inconsistent.
        self.map.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// In memory: drops the sessions idle longer than the time to live
    /// (the least recently used come first, so only the expired are
    /// visited).
    fn sweep(&self, map: &mut Map, now: Instant) {
        if self.db.is_some() {
            return;
        }
        while let Some((_, entry)) = map.lru.peek_lru() {
            if now.duration_since(entry.used) <= self.ttl {
                break;
            }
            if let Some((id, gone)) = map.lru.pop_lru() {
                map.bytes -= gone.bytes;
                self.carries.forget(&id);
            }
            metrics::counter!(metric_names::SESSIONS_EVICTED_TOTAL, "reason" => "idle")
                .increment(1);
        }
        metrics::gauge!(metric_names::SESSIONS_LIVE).set(map.lru.len() as f64);
    }

    /// Puts `held` in the map, evicting past the count (in memory) or past
    /// the byte budget (a cache).
    fn put(&self, id: &str, held: Shared, bytes: usize) {
        let now = Instant::now();
        let mut map = self.lock();
        self.sweep(&mut map, now);
        if let Some(old) = map.lru.put(
            id.to_owned(),
            Entry {
                held,
                used: now,
                bytes,
            },
        ) {
            map.bytes -= old.bytes;
        }
        map.bytes += bytes;
        while map.lru.len() > 1
            && (if self.db.is_some() {
                map.bytes > self.cache_bytes
            } else {
                map.lru.len() > self.capacity
            })
        {
            let Some((id, gone)) = map.lru.pop_lru() else {
                break;
            };
            map.bytes -= gone.bytes;
            if self.db.is_none() {
                // The session is gone (in the database, only its cache).
                self.carries.forget(&id);
                metrics::counter!(metric_names::SESSIONS_EVICTED_TOTAL, "reason" => "capacity")
                    .increment(1);
            }
        }
        if self.db.is_none() {
            metrics::gauge!(metric_names::SESSIONS_LIVE).set(map.lru.len() as f64);
        }
    }

    /// Updates what the cached session `id` costs, if it is cached.
    fn resize(&self, id: &str, bytes: usize) {
        let mut map = self.lock();
        let Some(entry) = map.lru.peek_mut(id) else {
            return;
        };
        let old = std::mem::replace(&mut entry.bytes, bytes);
        map.bytes = map.bytes - old + bytes;
    }

    /// Drops session `id` (and its carry): it ended.
    fn forget(&self, id: &str) {
        self.carries.forget(id);
        let mut map = self.lock();
        if let Some(gone) = map.lru.pop(id) {
            map.bytes -= gone.bytes;
        }
        if self.db.is_none() {
            metrics::gauge!(metric_names::SESSIONS_LIVE).set(map.lru.len() as f64);
        }
    }

    /// Keeps a new session under a fresh id (in the database, stored
    /// first), evicting the least recently used past the count.
    ///
    /// # Errors
    /// [`ApiError::DatabaseUnavailable`] if the database cannot store it.
    pub async fn create(&self, session: Session) -> Result<(String, Shared), ApiError> {
        let id = format!("{SESSION_ID_PREFIX}{}", uuid::Uuid::new_v4().simple());
        if let Some(db) = &self.db {
            let snapshot = session.snapshot();
            let spec = encode_spec(session.planner())?;
            let made = db
                .create_session(
                    NewSession {
                        id: &id,
                        scenario_id: &session.planner().scenario.id,
                        spec: &spec,
                        format: Snapshot::FORMAT,
                        state: &snapshot.encode(),
                    },
                    self.ttl,
                    self.capacity,
                )
                .await?;
            for (reason, n) in [("idle", made.idle), ("capacity", made.capacity)] {
                metrics::counter!(metric_names::SESSIONS_EVICTED_TOTAL, "reason" => reason)
                    .increment(n);
            }
            metrics::gauge!(metric_names::SESSIONS_LIVE).set(made.live as f64);
        }
        let bytes = session.memory_bytes();
        let held = Arc::new(tokio::sync::Mutex::new(Held {
            session: Some(session),
            ..Held::default()
        }));
        self.put(&id, held.clone(), bytes);
        Ok((id, held))
    }

    /// Session `id` as this replica holds it, marked as used now: in
    /// memory, the session itself; in the database, its cached state, or
    /// a place to load it into ([`SessionStore::refresh`] makes it
    /// current).
    ///
    /// # Errors
    /// [`ApiError::SessionNotFound`] in memory for an unknown, expired or
    /// evicted id.
    pub fn checkout(&self, id: &str) -> Result<Shared, ApiError> {
        if !is_session_id(id) {
            return Err(self.not_found(id));
        }
        let now = Instant::now();
        let mut map = self.lock();
        self.sweep(&mut map, now);
        if let Some(entry) = map.lru.get_mut(id) {
            entry.used = now;
            return Ok(entry.held.clone());
        }
        if self.db.is_none() {
            return Err(self.not_found(id));
        }
        drop(map);
        let held = Shared::default();
        self.put(id, held.clone(), 0);
        Ok(held)
    }

    /// Makes `held` (session `id`'s, from [`SessionStore::checkout`])
    /// current: in the database, reloads its state if the row moved on
    /// (building its planner with `resolve`, of the scenario's id and its
    /// spec, if nothing is loaded yet). With `key`, the answer to the last
    /// step if it was made for that Idempotency-Key and request. With
    /// `touch`, marks the session used now in the database.
    ///
    /// # Errors
    /// [`ApiError::SessionNotFound`] if the session is not live;
    /// [`ApiError::IdempotencyKeyReused`] if the last step had `key` and
    /// another request;
    /// [`ApiError::DatabaseUnavailable`]; `resolve`'s errors; an internal
    /// error for a stored session this server cannot read.
    pub async fn refresh<'a>(
        &self,
        id: &str,
        held: &'a mut Held,
        key: Option<StepKey<'_>>,
        touch: bool,
        resolve: impl AsyncFnOnce(String, Vec<u8>) -> Result<Arc<Planner>, ApiError>,
    ) -> Result<Refreshed<'a>, ApiError> {
        let cached = held.session.is_some() && !held.stale;
        // A retry of the last step made here: in the database, another
        // replica may have stepped, deleted or expired the session since,
        // so the row decides whether to replay (and a replay is a use).
        let retry = key.is_some_and(|k| held.last.as_ref().is_some_and(|(last, ..)| last == k.key));
        let touch = touch || retry;
        let Some(db) = self.db.as_ref().filter(|_| touch || !cached || held.shared) else {
            // In memory, or a cached state that no other replica moved on
            // lately: the step is made from it, and its compare-and-set
            // finds out if another replica moved it after all.
            if let (Some(key), Some((last, digest, answer))) = (key, &held.last)
                && key.key == last
            {
                return replay(key, Some(digest), answer.clone());
            }
            return match &mut held.session {
                Some(session) => Ok(Refreshed::Session(session, Base(held.version))),
                None => Err(self.not_found(id)),
            };
        };
        let have = cached.then_some(held.version);
        let row = db
            .load_session(
                id,
                self.ttl,
                have,
                held.session.is_none(),
                key.map(|k| k.key),
                touch,
            )
            .await?;
        let Some(row) = row else {
            return Err(self.gone(db, id).await);
        };
        if let (Some(key), Some(answer)) = (key, row.replay) {
            return replay(key, row.replay_digest.as_deref(), Bytes::from(answer));
        }
        if let Some(state) = row.state {
            let planner = match (&held.session, row.spec) {
                (Some(session), _) => session.planner().clone(),
                (None, Some(spec)) => resolve(row.scenario_id, spec).await?,
                (None, None) => {
                    return Err(ApiError::Internal(format!(
                        "session {id}: its spec was not loaded"
                    )));
                }
            };
            let reuse = held
                .session
                .as_ref()
                .and_then(|s| s.learner())
                .map(|l| l.planner().clone());
            let format = row.format;
            // Decoding, and for a learning session maybe a precomputation:
            // off the async workers.
            let session = tokio::task::spawn_blocking(move || {
                if format != Snapshot::FORMAT {
                    return Err(format!(
                        "format {format} (this server reads {})",
                        Snapshot::FORMAT
                    ));
                }
                Session::restore(planner, Snapshot::decode(&state)?, reuse)
            })
            .await?
            .map_err(|reason| {
                tracing::error!(%id, %reason, "a stored session cannot be read");
                ApiError::Internal(format!("stored session {id} cannot be read: {reason}"))
            })?;
            self.resize(id, session.memory_bytes());
            held.session = Some(session);
            held.last = None;
        } else {
            // Nobody moved it since: make the next steps from the cache.
            held.shared = false;
        }
        held.version = row.version;
        held.stale = false;
        match &mut held.session {
            Some(session) => Ok(Refreshed::Session(session, Base(held.version))),
            None => Err(ApiError::Internal(format!("session {id} was not loaded"))),
        }
    }

    /// Records a step made on `held` (session `id`'s, made current by
    /// [`SessionStore::refresh`]) and answered `answer`: in the database,
    /// stores it over the version it was made from. False if another step
    /// was stored first (or the session expired): `held` is then reloaded
    /// at the next [`SessionStore::refresh`] and the step must be made
    /// again.
    ///
    /// # Errors
    /// [`ApiError::DatabaseUnavailable`] (the step may have been stored or
    /// not; `held` is reloaded at the next refresh).
    pub async fn save(
        &self,
        id: &str,
        held: &mut Held,
        key: Option<StepKey<'_>>,
        answer: &Bytes,
    ) -> Result<bool, ApiError> {
        let Some(session) = &held.session else {
            return Err(ApiError::Internal(format!("session {id} was not loaded")));
        };
        let Some(db) = &self.db else {
            return Ok(self.record(id, held, true, key, answer));
        };
        // Until it is known to be stored, this state is not the stored one.
        held.stale = true;
        let state = session.snapshot().encode();
        metrics::counter!(metric_names::SESSION_WRITES_TOTAL, "when" => "after_plan").increment(1);
        let stored = db
            .save_session(
                id,
                self.ttl,
                held.version,
                Snapshot::FORMAT,
                &state,
                key.as_ref().map(|k| (k.key, &k.digest[..])),
                answer,
            )
            .await?;
        Ok(self.record(id, held, stored, key, answer))
    }

    /// Begins storing step `prepared` of `session` (refreshed at `base`)
    /// while its plan is made, when that saves time: in the database, for a
    /// step without an Idempotency-Key (whose answer would be one more
    /// write after the plan), of a session that does not learn, its plan
    /// predicted to take at most [`SAVE_EARLY_MAX_MS`], with a connection
    /// to spare ([`PgStore::has_spare_connection`]). Else `None`: store it
    /// with [`SessionStore::save`] once made. The write is seen by nobody
    /// until [`SessionStore::finish_early`] commits it; dropped, it is
    /// rolled back.
    pub fn save_early<'s>(
        &'s self,
        id: &'s str,
        base: Base,
        session: &Session,
        prepared: &PreparedStep,
        predicted_ms: f64,
        key: Option<StepKey<'_>>,
    ) -> Option<impl Future<Output = Result<Option<StepWrite>, DbError>> + 's> {
        let db = self.db.as_ref().filter(|db| {
            key.is_none() && predicted_ms <= SAVE_EARLY_MAX_MS && db.has_spare_connection()
        })?;
        let state = session.snapshot_after(prepared)?.encode();
        let ttl = self.ttl;
        metrics::counter!(metric_names::SESSION_WRITES_TOTAL, "when" => "during_plan").increment(1);
        Some(async move {
            db.begin_step(id, ttl, base.0, Snapshot::FORMAT, &state)
                .await
        })
    }

    /// [`SessionStore::save`] for a step whose write `written` began with
    /// [`SessionStore::save_early`]: commits it.
    ///
    /// # Errors
    /// As [`SessionStore::save`].
    pub async fn finish_early(
        &self,
        id: &str,
        held: &mut Held,
        written: Result<Option<StepWrite>, DbError>,
        answer: &Bytes,
    ) -> Result<bool, ApiError> {
        let Some(db) = &self.db else {
            return Err(ApiError::Internal(format!("session {id}: no database")));
        };
        held.stale = true;
        let stored = match written? {
            Some(write) => {
                write.commit(db).await?;
                true
            }
            None => false,
        };
        Ok(self.record(id, held, stored, None, answer))
    }

    /// Notes in `held` whether its step, answered `answer`, was `stored`.
    fn record(
        &self,
        id: &str,
        held: &mut Held,
        stored: bool,
        key: Option<StepKey<'_>>,
        answer: &Bytes,
    ) -> bool {
        if !stored {
            held.shared = true;
            return false;
        }
        if self.db.is_some() {
            held.version += 1;
            held.stale = false;
        }
        held.last = key.map(|k| (k.key.to_owned(), k.digest, answer.clone()));
        let bytes = held.session.as_ref().map_or(0, Session::memory_bytes);
        self.resize(id, bytes + answer.len());
        true
    }

    /// Marks session `id` (from [`SessionStore::checkout`]) used now, as
    /// any request to it does, for a request refused before its session
    /// was read: in the database, a session that is not live is then
    /// not found (and not kept in the cache), as in memory, where
    /// `checkout` found that out.
    ///
    /// # Errors
    /// [`ApiError::SessionNotFound`] if the session is not live;
    /// [`ApiError::DatabaseUnavailable`].
    pub async fn confirm(&self, id: &str) -> Result<(), ApiError> {
        let Some(db) = &self.db else {
            return Ok(());
        };
        if db.touch_session(id, self.ttl).await? {
            return Ok(());
        }
        Err(self.gone(db, id).await)
    }

    /// Session `id`, found not live in the database: drops it here (and
    /// its row, if it expired, counted as idle) and returns its 404.
    async fn gone(&self, db: &PgStore, id: &str) -> ApiError {
        self.forget(id);
        if db.drop_expired_session(id, self.ttl).await.unwrap_or(false) {
            metrics::counter!(metric_names::SESSIONS_EVICTED_TOTAL, "reason" => "idle")
                .increment(1);
        }
        self.not_found(id)
    }

    /// Marks session `id` used now (after a step that failed, which
    /// stored nothing), in the background; nothing to do in memory.
    pub fn touch(&self, id: &str) {
        if let Some(db) = self.db.clone() {
            let (id, ttl) = (id.to_owned(), self.ttl);
            tokio::spawn(async move {
                let _ = db.touch_session(&id, ttl).await;
            });
        }
    }

    /// Removes a session.
    ///
    /// # Errors
    /// [`ApiError::SessionNotFound`] for an unknown, expired or evicted id;
    /// [`ApiError::DatabaseUnavailable`].
    pub async fn remove(&self, id: &str) -> Result<(), ApiError> {
        if !is_session_id(id) {
            return Err(self.not_found(id));
        }
        let Some(db) = &self.db else {
            let mut map = self.lock();
            self.sweep(&mut map, Instant::now());
            let removed = map.lru.pop(id);
            if let Some(gone) = &removed {
                map.bytes -= gone.bytes;
                self.carries.forget(id);
            }
            metrics::gauge!(metric_names::SESSIONS_LIVE).set(map.lru.len() as f64);
            return removed.map(|_| ()).ok_or_else(|| self.not_found(id));
        };
        let deleted = db.delete_session(id, self.ttl).await?;
        self.forget(id);
        match deleted {
            Some(true) => Ok(()),
            Some(false) => {
                metrics::counter!(metric_names::SESSIONS_EVICTED_TOTAL, "reason" => "idle")
                    .increment(1);
                Err(self.not_found(id))
            }
            None => Err(self.not_found(id)),
        }
    }

    fn not_found(&self, id: &str) -> ApiError {
        ApiError::SessionNotFound {
            id: id.to_owned(),
            ttl_s: self.ttl.as_secs(),
        }
    }
}

/// A scenario's spec as a session row keeps it (CBOR: every number to the
/// bit, so the spec rebuilds the same scenario and id).
fn encode_spec(planner: &Planner) -> Result<Vec<u8>, ApiError> {
    let mut bytes = Vec::new();
    ciborium::into_writer(&planner.scenario.spec, &mut bytes)
        .map_err(|e| ApiError::Internal(format!("encoding a scenario's spec: {e}")))?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::super::carries::tests::carry;
    use super::*;
    use crate::scenario::builtins;
    use crate::session::SessionSettings;

    /// A session dropped for the count, for idle time or by a delete
    /// takes its carry with it.
    #[tokio::test]
    async fn a_session_that_ends_drops_its_carry() {
        let planner = Arc::new(Planner::new(builtins().remove(0)));
        let carries = Arc::new(Carries::new(usize::MAX, Duration::from_secs(3600)));
        let store = SessionStore::new(Duration::from_millis(300), 1, carries.clone());
        let open = async || {
            let session = Session::new(planner.clone(), SessionSettings::default());
            let (id, _) = store.create(session).await.expect("in memory");
            carries.keep(&id, carry(&planner, 150.0));
            id
        };
        let first = open().await;
        assert!(carries.bytes() > 0);
        // The second takes the first's place (a count of 1).
        let second = open().await;
        assert!(carries.take(&first).is_empty());
        let kept = carries.bytes();
        assert!(kept > 0);
        // Idle past the time to live: gone at the next request.
        tokio::time::sleep(Duration::from_millis(400)).await;
        assert!(store.checkout(&second).is_err());
        assert_eq!(carries.bytes(), 0);
        let third = open().await;
        store.remove(&third).await.expect("live");
        assert_eq!(carries.bytes(), 0);
    }
}
