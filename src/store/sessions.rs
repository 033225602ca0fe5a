//! Sessions in the PostgreSQL database (`--database-url`): one row per
//! session (see `migrations/` for the columns), so that any replica serves
//! any session.
//!
//! - **Steps** are stored by compare-and-set on the row's `version`
//!   ([`PgStore::save_session`]): a step made from version `v` is stored
//!   only if the row is still at `v`, so two replicas stepping one session
//!   at once never both succeed, and the loser makes its step again from
//!   the winner's state. A single `UPDATE` in autocommit: once it returns,
//!   the step is durable. Or the same `UPDATE` in a transaction begun
//!   while the step's plan is made ([`PgStore::begin_step`]), committed
//!   once it is: the row's lock makes a step of another replica wait for
//!   the commit, then find the row moved on.
//! - **Idle time and count.** A row not used for the time to live is
//!   expired: every query treats it as absent, and creations delete the
//!   expired rows. A creation past the count deletes the least recently
//!   used. Creations take a transaction-scoped advisory lock
//!   ([`CREATE_LOCK`]) so that replicas creating at once keep the count.

use std::time::Duration;

use super::{DbError, PgStore};

/// The advisory lock creations hold (`vigil_ss` in ASCII).
pub const CREATE_LOCK: i64 = 0x7669_6769_6c5f_7373;

/// A session's row as a step or a read needs it.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionRow {
    /// Steps stored.
    pub version: i64,
    /// The encoding of `state`.
    pub format: i32,
    /// The snapshot, unless the caller holds this version already.
    pub state: Option<Vec<u8>>,
    /// The scenario's id.
    pub scenario_id: String,
    /// The scenario's spec, when asked for.
    pub spec: Option<Vec<u8>>,
    /// The answer to the last step, when its Idempotency-Key is the one
    /// asked about.
    pub replay: Option<Vec<u8>>,
    /// The digest of that step's request, when it was stored with it.
    pub replay_digest: Option<Vec<u8>>,
}

/// What [`PgStore::create_session`] dropped to make room.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Made {
    /// Rows expired.
    pub idle: u64,
    /// Least recently used rows dropped past the count.
    pub capacity: u64,
    /// Rows after the creation.
    pub live: u64,
}

/// A new session's row.
#[derive(Debug, Clone, Copy)]
pub struct NewSession<'a> {
    /// Its id.
    pub id: &'a str,
    /// Its scenario's id.
    pub scenario_id: &'a str,
    /// Its scenario's spec (CBOR).
    pub spec: &'a [u8],
    /// The encoding of `state`.
    pub format: i32,
    /// Its snapshot.
    pub state: &'a [u8],
}

/// The expiry condition on a row, its time to live in seconds being `$2`
/// (a macro, so that constant statements can include it).
macro_rules! live {
    () => {
        "last_used > now() - make_interval(secs => $2)"
    };
}

/// [`live!`] for the statements built at run time.
const LIVE: &str = live!();

/// The compare-and-set that stores a step of session `id` made from
/// version `base` ([`PgStore::save_session`], [`PgStore::begin_step`]).
struct StepUpdate<'a> {
    id: &'a str,
    ttl: Duration,
    base: i64,
    format: i32,
    state: &'a [u8],
    /// The step's Idempotency-Key and request digest, if it had a key.
    key: Option<(&'a str, &'a [u8])>,
    /// Its answer, stored if it had a key.
    response: &'a [u8],
}

/// [`StepUpdate`]'s statement.
const STEP_UPDATE: &str = concat!(
    "UPDATE sessions SET version = version + 1, format = $4, state = $5, ",
    "last_key = $6, last_response = CASE WHEN $6 IS NULL THEN NULL ELSE $7 END, ",
    "digest_key = $6, last_digest = $8, last_used = now() ",
    "WHERE id = $1 AND ",
    live!(),
    " AND version = $3"
);

impl<'a> StepUpdate<'a> {
    /// The update of a step without an Idempotency-Key.
    fn unkeyed(id: &'a str, ttl: Duration, base: i64, format: i32, state: &'a [u8]) -> Self {
        StepUpdate {
            id,
            ttl,
            base,
            format,
            state,
            key: None,
            response: &[],
        }
    }

    fn query(&self) -> sqlx::query::Query<'a, sqlx::Postgres, sqlx::postgres::PgArguments> {
        sqlx::query(STEP_UPDATE)
            .bind(self.id)
            .bind(self.ttl.as_secs_f64())
            .bind(self.base)
            .bind(self.format)
            .bind(self.state)
            .bind(self.key.map(|(key, _)| key))
            .bind(self.response)
            .bind(self.key.map(|(_, digest)| digest))
    }
}

/// A step written by [`PgStore::begin_step`], not yet committed.
#[derive(Debug)]
pub struct StepWrite {
    tx: sqlx::Transaction<'static, sqlx::Postgres>,
}

impl StepWrite {
    /// Stores the step for good: once this returns, it is durable.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow (the step
    /// may then have been stored or not).
    pub async fn commit(self, store: &PgStore) -> Result<(), DbError> {
        store.bounded(self.tx.commit()).await
    }
}

impl PgStore {
    /// Stores a new session, first deleting the expired rows and, past
    /// `capacity` rows, the least recently used.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn create_session(
        &self,
        new: NewSession<'_>,
        ttl: Duration,
        capacity: usize,
    ) -> Result<Made, DbError> {
        let ttl_s = ttl.as_secs_f64();
        let capacity = i64::try_from(capacity.max(1)).unwrap_or(i64::MAX);
        self.bounded(async {
            let mut tx = self.pool.begin().await?;
            sqlx::query("SELECT pg_advisory_xact_lock($1)")
                .bind(CREATE_LOCK)
                .execute(&mut *tx)
                .await?;
            let idle = sqlx::query(&format!(
                "DELETE FROM sessions WHERE id <> $1 AND NOT ({LIVE})"
            ))
            .bind(new.id)
            .bind(ttl_s)
            .execute(&mut *tx)
            .await?
            .rows_affected();
            let (count,): (i64,) = sqlx::query_as("SELECT count(*) FROM sessions")
                .fetch_one(&mut *tx)
                .await?;
            let over = (count - capacity + 1).max(0);
            let evicted = if over > 0 {
                sqlx::query(
                    "DELETE FROM sessions WHERE id IN \
                     (SELECT id FROM sessions ORDER BY last_used LIMIT $1)",
                )
                .bind(over)
                .execute(&mut *tx)
                .await?
                .rows_affected()
            } else {
                0
            };
            sqlx::query(
                "INSERT INTO sessions (id, scenario_id, spec, format, state) \
                 VALUES ($1, $2, $3, $4, $5)",
            )
            .bind(new.id)
            .bind(new.scenario_id)
            .bind(new.spec)
            .bind(new.format)
            .bind(new.state)
            .execute(&mut *tx)
            .await?;
            tx.commit().await?;
            Ok(Made {
                idle,
                capacity: evicted,
                live: u64::try_from(count - evicted as i64 + 1).unwrap_or(0),
            })
        })
        .await
    }

    /// The live row of session `id`, if any. `have`: the version the
    /// caller holds (its state is then left out if unchanged); `spec`:
    /// whether to include the spec; `key`: an Idempotency-Key whose stored
    /// answer (and request digest) to return; `touch`: mark the session
    /// used now.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn load_session(
        &self,
        id: &str,
        ttl: Duration,
        have: Option<i64>,
        spec: bool,
        key: Option<&str>,
        touch: bool,
    ) -> Result<Option<SessionRow>, DbError> {
        let columns = "version, format, \
             CASE WHEN version IS NOT DISTINCT FROM $3 THEN NULL ELSE state END, \
             scenario_id, CASE WHEN $4 THEN spec END, \
             CASE WHEN last_key = $5 THEN last_response END, \
             CASE WHEN last_key = $5 AND digest_key = $5 THEN last_digest END";
        let sql = if touch {
            format!(
                "UPDATE sessions SET last_used = now() WHERE id = $1 AND {LIVE} RETURNING {columns}"
            )
        } else {
            format!("SELECT {columns} FROM sessions WHERE id = $1 AND {LIVE}")
        };
        type Columns = (
            i64,
            i32,
            Option<Vec<u8>>,
            String,
            Option<Vec<u8>>,
            Option<Vec<u8>>,
            Option<Vec<u8>>,
        );
        let row: Option<Columns> = self
            .bounded(
                sqlx::query_as(&sql)
                    .bind(id)
                    .bind(ttl.as_secs_f64())
                    .bind(have)
                    .bind(spec)
                    .bind(key)
                    .fetch_optional(&self.pool),
            )
            .await?;
        Ok(row.map(
            |(version, format, state, scenario_id, spec, replay, replay_digest)| SessionRow {
                version,
                format,
                state,
                scenario_id,
                spec,
                replay,
                replay_digest,
            },
        ))
    }

    /// Stores a step of session `id` made from version `base`, with its
    /// Idempotency-Key and request digest if it had a key: true if stored
    /// (the row is then at `base + 1`), false if the row moved on from
    /// `base`, expired or is gone.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow (the step
    /// may then have been stored or not).
    #[allow(clippy::too_many_arguments)]
    pub async fn save_session(
        &self,
        id: &str,
        ttl: Duration,
        base: i64,
        format: i32,
        state: &[u8],
        key: Option<(&str, &[u8])>,
        response: &[u8],
    ) -> Result<bool, DbError> {
        let step = StepUpdate {
            key,
            response,
            ..StepUpdate::unkeyed(id, ttl, base, format, state)
        };
        let done = self.bounded(step.query().execute(&self.pool)).await?;
        Ok(done.rows_affected() == 1)
    }

    /// Begins storing a step of session `id` made from version `base`, one
    /// without an Idempotency-Key, as [`PgStore::save_session`] does but in
    /// a transaction left open, so that the write runs while the step's
    /// plan is made: the row is then locked at `base + 1`, and nobody sees
    /// the step until [`StepWrite::commit`] (dropping the [`StepWrite`]
    /// rolls it back). `None` if the row moved on from `base`, expired or
    /// is gone.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn begin_step(
        &self,
        id: &str,
        ttl: Duration,
        base: i64,
        format: i32,
        state: &[u8],
    ) -> Result<Option<StepWrite>, DbError> {
        let step = StepUpdate::unkeyed(id, ttl, base, format, state);
        self.bounded(async {
            let mut tx = self.pool.begin().await?;
            let done = step.query().execute(&mut *tx).await?;
            Ok((done.rows_affected() == 1).then_some(StepWrite { tx }))
        })
        .await
    }

    /// Marks session `id` used now; false if it is not live.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn touch_session(&self, id: &str, ttl: Duration) -> Result<bool, DbError> {
        let done = self
            .bounded(
                sqlx::query(&format!(
                    "UPDATE sessions SET last_used = now() WHERE id = $1 AND {LIVE}"
                ))
                .bind(id)
                .bind(ttl.as_secs_f64())
                .execute(&self.pool),
            )
            .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Deletes session `id`: `Some(true)` if it was live, `Some(false)` if
    /// it had expired (now deleted), `None` if there was no row.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn delete_session(&self, id: &str, ttl: Duration) -> Result<Option<bool>, DbError> {
        let row: Option<(bool,)> = self
            .bounded(
                sqlx::query_as(&format!(
                    "DELETE FROM sessions WHERE id = $1 RETURNING {LIVE}"
                ))
                .bind(id)
                .bind(ttl.as_secs_f64())
                .fetch_optional(&self.pool),
            )
            .await?;
        Ok(row.map(|(live,)| live))
    }

    /// Deletes session `id` if it has expired; true if it did.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn drop_expired_session(&self, id: &str, ttl: Duration) -> Result<bool, DbError> {
        let done = self
            .bounded(
                sqlx::query(&format!(
                    "DELETE FROM sessions WHERE id = $1 AND NOT ({LIVE})"
                ))
                .bind(id)
                .bind(ttl.as_secs_f64())
                .execute(&self.pool),
            )
            .await?;
        Ok(done.rows_affected() == 1)
    }
}
