//! The PostgreSQL catalogue (`--database-url`): one row per registered
//! scenario (id, spec, creation time), shared by every replica pointed at
//! the same database.
//!
//! - **Schema.** The migrations under `migrations/` are compiled into the
//!   binary and applied at start on a connection of their own, under
//!   sqlx's migration lock (an advisory lock), so replicas starting at once
//!   do not race. A database migrated by a newer binary (a migration this
//!   one does not know) or whose applied migration differs from ours is a
//!   start-up error, never overwritten.
//! - **Writes.** A registration is one `INSERT … ON CONFLICT (id) DO
//!   NOTHING`: atomic (a `kill -9` leaves the row absent or whole), and the
//!   same spec registered through two replicas at once gives one row, the
//!   first insert creating it and the other finding it.
//! - **Deletions** fire a trigger that notifies channel [`CHANNEL`] with
//!   the id; [`PgStore::listen`] follows it.
//! - **Faults.** Every call is bounded by the configured timeout (the
//!   pool's acquire timeout, the server-side `statement_timeout`, and a
//!   timer around the whole call), so an unreachable database gives a
//!   [`DbError`] quickly rather than a hang. The pool tests a connection
//!   idle for a second or more before handing it out and opens new ones as
//!   needed, so it recovers by itself when the database returns. [`PgStore::is_up`] (and the gauge
//!   `vigil_database_up`) says whether the last contact succeeded.
//!
//! Queries are checked at run time: building needs no database.

use std::collections::HashSet;
use std::str::FromStr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use sqlx::migrate::{MigrateError, Migrator};
use sqlx::postgres::{PgConnectOptions, PgListener, PgPool, PgPoolOptions};
use sqlx::{Connection, PgConnection};

use super::FORMAT;
use crate::metric_names;
use crate::scenario::{Scenario, ScenarioSpec};

/// The schema's migrations, from `migrations/`.
pub static MIGRATOR: Migrator = sqlx::migrate!("./migrations");

/// The channel on which deletions are notified (payload: the id).
pub const CHANNEL: &str = "vigil_scenarios";

/// Time limit of a call while the database is known to be down (its last
/// contact failed): the background check, every second, uses the full one.
const WHILE_DOWN: Duration = Duration::from_millis(300);

/// Connections in a replica's pool (the deletion listener holds one more).
const POOL_SIZE: u32 = 8;

/// A pooled connection idle this long is checked (a ping) before use.
const CHECK_IDLE_AFTER: Duration = Duration::from_secs(1);

/// Why a call to the database failed: it is unreachable, too slow, or
/// refused the query. Every one is answered 503 with `Retry-After`.
#[derive(Debug, thiserror::Error)]
pub enum DbError {
    /// No answer within the timeout.
    #[error("the database did not answer within {0} ms")]
    Timeout(u64),
    /// The check every second failed ([`PgStore::is_up`] is false).
    #[error("the database does not answer its checks")]
    Down,
    /// The driver's error (connection refused or lost, pool timed out, …).
    #[error("database error: {0}")]
    Sqlx(#[from] sqlx::Error),
}

/// A handle on the catalogue: a connection pool and the database's state.
/// Cloning gives another handle to the same pool.
#[derive(Debug, Clone)]
pub struct PgStore {
    pub(super) pool: PgPool,
    timeout: Duration,
    up: Arc<AtomicBool>,
}

/// A registered scenario as a row holds it.
#[derive(Debug, Clone)]
pub struct Row {
    /// The scenario.
    pub scenario: Scenario,
    /// When it was first registered (RFC 3339, UTC).
    pub created_at: String,
}

impl PgStore {
    /// Connects to `url`, applies the migrations, and returns a store whose
    /// calls each take at most `timeout`. While the database cannot be
    /// reached, tries again for up to `wait`.
    ///
    /// # Errors
    /// A message for the log: a bad URL, a database still unreachable after
    /// `wait`, or a schema this binary must not touch (see the module docs).
    pub async fn connect(url: &str, timeout: Duration, wait: Duration) -> Result<Self, String> {
        let ms = timeout.as_millis().max(1).to_string();
        let options = PgConnectOptions::from_str(url)
            .map_err(|e| format!("invalid --database-url: {e}"))?
            .application_name("vigil-server")
            .options([("statement_timeout", ms.as_str())]);
        let until = Instant::now() + wait;
        loop {
            match migrate(&options, timeout).await {
                Ok(()) => break,
                Err(Fatal::Schema(e)) => return Err(e),
                Err(Fatal::Unreachable(e)) if Instant::now() >= until => {
                    return Err(format!(
                        "the database is unreachable (tried for {} s): {e}",
                        wait.as_secs()
                    ));
                }
                Err(Fatal::Unreachable(e)) => {
                    tracing::warn!(error = %e, "the database is unreachable; retrying");
                    tokio::time::sleep(Duration::from_millis(500)).await;
                }
            }
        }
        let pool = PgPoolOptions::new()
            .max_connections(POOL_SIZE)
            .min_connections(0)
            .acquire_timeout(timeout)
            // A connection idle for a while is checked before use, so the
            // pool recovers by itself from a database restart; one in
            // steady use is not, which saves a round trip per call.
            .test_before_acquire(false)
            .before_acquire(|conn, meta| {
                Box::pin(async move {
                    if meta.idle_for < CHECK_IDLE_AFTER {
                        return Ok(true);
                    }
                    Ok(conn.ping().await.is_ok())
                })
            })
            .connect_lazy_with(options);
        let store = Self {
            pool,
            timeout,
            up: Arc::new(AtomicBool::new(true)),
        };
        metrics::gauge!(metric_names::DATABASE_UP).set(1.0);
        Ok(store)
    }

    /// True if the last contact with the database succeeded.
    pub fn is_up(&self) -> bool {
        self.up.load(Ordering::Relaxed)
    }

    fn set_up(&self, up: bool) {
        if self.up.swap(up, Ordering::Relaxed) != up {
            if up {
                tracing::info!("the database is reachable again");
            } else {
                tracing::warn!("the database is unreachable");
            }
        }
        metrics::gauge!(metric_names::DATABASE_UP).set(if up { 1.0 } else { 0.0 });
    }

    /// Whether the pool has two connections free (idle, or room to open
    /// them): one for a call that holds its connection for a while (a
    /// step's write during its plan), one left for the calls that do not.
    pub fn has_spare_connection(&self) -> bool {
        let room = POOL_SIZE.saturating_sub(self.pool.size()) as usize;
        self.pool.num_idle() + room >= 2
    }

    /// Runs `call` within the timeout (a short one while the database is
    /// known to be down, so requests that need it fail fast) and records
    /// whether the database answered.
    pub(super) async fn bounded<T>(
        &self,
        call: impl Future<Output = Result<T, sqlx::Error>>,
    ) -> Result<T, DbError> {
        let limit = if self.is_up() {
            self.timeout
        } else {
            self.timeout.min(WHILE_DOWN)
        };
        self.within(limit, call).await
    }

    pub(super) async fn within<T>(
        &self,
        limit: Duration,
        call: impl Future<Output = Result<T, sqlx::Error>>,
    ) -> Result<T, DbError> {
        let result = match tokio::time::timeout(limit, call).await {
            Ok(Ok(value)) => Ok(value),
            Ok(Err(e)) => Err(DbError::Sqlx(e)),
            Err(_) => Err(DbError::Timeout(limit.as_millis() as u64)),
        };
        // A query the server refused (`Database`) means it answered.
        let answered = matches!(
            &result,
            Ok(_) | Err(DbError::Sqlx(sqlx::Error::Database(_)))
        );
        self.set_up(answered);
        result
    }

    /// Checks that the database answers within the full timeout, updating
    /// [`PgStore::is_up`].
    pub async fn ping(&self) -> bool {
        self.within(self.timeout, sqlx::query("SELECT 1").execute(&self.pool))
            .await
            .is_ok()
    }

    /// Stores a scenario unless its id is there already; true if this call
    /// created the row.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn insert(&self, scenario: &Scenario) -> Result<bool, DbError> {
        let spec = serde_json::to_string(&scenario.spec)
            .map_err(|e| DbError::Sqlx(sqlx::Error::Encode(Box::new(e))))?;
        let done = self
            .bounded(
                sqlx::query(
                    "INSERT INTO scenarios (id, format, spec) VALUES ($1, $2, $3::jsonb) \
                     ON CONFLICT (id) DO NOTHING",
                )
                .bind(&scenario.id)
                .bind(FORMAT as i32)
                .bind(spec)
                .execute(&self.pool),
            )
            .await?;
        Ok(done.rows_affected() == 1)
    }

    /// The scenario stored under `id`, if any (a row that does not make a
    /// valid scenario of that id is logged and taken as absent).
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn get(&self, id: &str) -> Result<Option<Row>, DbError> {
        let row: Option<(String, i32, String, String)> = self
            .bounded(
                sqlx::query_as(
                    "SELECT id, format, spec::text, \
                     to_char(created_at AT TIME ZONE 'UTC', 'YYYY-MM-DD\"T\"HH24:MI:SS.US\"Z\"') \
                     FROM scenarios WHERE id = $1",
                )
                .bind(id)
                .fetch_optional(&self.pool),
            )
            .await?;
        Ok(row.and_then(parse))
    }

    /// Every stored scenario, sorted by id (invalid rows logged and left
    /// out).
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn list(&self) -> Result<Vec<Row>, DbError> {
        let rows: Vec<(String, i32, String, String)> = self
            .bounded(
                sqlx::query_as(
                    "SELECT id, format, spec::text, \
                     to_char(created_at AT TIME ZONE 'UTC', 'YYYY-MM-DD\"T\"HH24:MI:SS.US\"Z\"') \
                     FROM scenarios ORDER BY id",
                )
                .fetch_all(&self.pool),
            )
            .await?;
        Ok(rows.into_iter().filter_map(parse).collect())
    }

    /// Deletes the row of `id`; true if there was one. Every replica's
    /// listener hears of it.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn delete(&self, id: &str) -> Result<bool, DbError> {
        let done = self
            .bounded(
                sqlx::query("DELETE FROM scenarios WHERE id = $1")
                    .bind(id)
                    .execute(&self.pool),
            )
            .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Which of `ids` are stored.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn existing(&self, ids: &[String]) -> Result<HashSet<String>, DbError> {
        let rows: Vec<(String,)> = self
            .bounded(
                sqlx::query_as("SELECT id FROM scenarios WHERE id = ANY($1)")
                    .bind(ids)
                    .fetch_all(&self.pool),
            )
            .await?;
        Ok(rows.into_iter().map(|(id,)| id).collect())
    }

    /// Stores every scenario of `scenarios` that is not stored yet; returns
    /// how many were added (the others were there already).
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn import(&self, scenarios: &[Scenario]) -> Result<usize, DbError> {
        let mut added = 0;
        for scenario in scenarios {
            if self.insert(scenario).await? {
                tracing::info!(id = %scenario.id, "imported");
                added += 1;
            }
        }
        Ok(added)
    }

    /// Starts following deletions on a connection of its own.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn listen(&self) -> Result<Deletions, DbError> {
        let listener = self
            .bounded(async {
                let mut listener = PgListener::connect_with(&self.pool).await?;
                listener.listen(CHANNEL).await?;
                Ok(listener)
            })
            .await?;
        Ok(Deletions { listener })
    }
}

/// The ids of deleted scenarios, as the database notifies them.
#[derive(Debug)]
pub struct Deletions {
    listener: PgListener,
}

impl Deletions {
    /// The next deleted id.
    ///
    /// # Errors
    /// [`DbError`] once the connection is lost: notifications sent until a
    /// new listener is up are missed, so its owner must then check what it
    /// holds against the table.
    pub async fn next(&mut self) -> Result<String, DbError> {
        match self.listener.try_recv().await? {
            Some(notification) => Ok(notification.payload().to_owned()),
            None => Err(DbError::Sqlx(sqlx::Error::Io(std::io::Error::new(
                std::io::ErrorKind::ConnectionAborted,
                "the listener's connection was lost",
            )))),
        }
    }
}

/// A row made into a scenario, or `None` (logged) if it is not one.
fn parse((id, format, spec, created_at): (String, i32, String, String)) -> Option<Row> {
    let scenario = (|| {
        if format != FORMAT as i32 {
            return Err(format!("format {format} (this server reads {FORMAT})"));
        }
        let spec: ScenarioSpec =
            serde_json::from_str(&spec).map_err(|e| format!("not a scenario spec: {e}"))?;
        let scenario = Scenario::new(spec).map_err(|e| format!("invalid spec: {e}"))?;
        if scenario.id != id {
            return Err(format!("its spec's id is {}", scenario.id));
        }
        Ok(scenario)
    })();
    match scenario {
        Ok(scenario) => Some(Row {
            scenario,
            created_at,
        }),
        Err(reason) => {
            tracing::warn!(%id, %reason, "skipping a stored scenario that cannot be loaded");
            None
        }
    }
}

/// Why the migrations could not be applied.
enum Fatal {
    /// The database cannot be reached (yet): worth trying again.
    Unreachable(String),
    /// The schema is not one this binary may touch: never retried.
    Schema(String),
}

/// Applies the migrations on a connection of its own (the migration lock
/// is a session lock: it must not go back to a pool if anything fails).
async fn migrate(options: &PgConnectOptions, timeout: Duration) -> Result<(), Fatal> {
    let connect = tokio::time::timeout(timeout, PgConnection::connect_with(options));
    let mut conn = match connect.await {
        Ok(Ok(conn)) => conn,
        Ok(Err(e)) => return Err(Fatal::Unreachable(e.to_string())),
        Err(_) => {
            return Err(Fatal::Unreachable(format!(
                "no connection within {} ms",
                timeout.as_millis()
            )));
        }
    };
    let known = MIGRATOR.iter().map(|m| m.version).max().unwrap_or(0);
    let result = MIGRATOR.run(&mut conn).await;
    let _ = conn.close().await;
    match result {
        Ok(()) => {
            tracing::info!(schema_version = known, "the database's schema is current");
            Ok(())
        }
        Err(MigrateError::VersionMissing(v)) => Err(Fatal::Schema(format!(
            "the database's schema has migration {v}, which this vigil-server does not know \
             (it knows up to {known}): a newer vigil-server migrated it; run that version or a \
             newer one against this database"
        ))),
        Err(MigrateError::VersionMismatch(v)) => Err(Fatal::Schema(format!(
            "migration {v} applied to the database differs from this vigil-server's: \
             the database was migrated by another build; refusing to touch it"
        ))),
        Err(MigrateError::Dirty(v)) => Err(Fatal::Schema(format!(
            "migration {v} was left half-applied in the database; repair it by hand"
        ))),
        Err(MigrateError::Execute(e)) if matches!(e, sqlx::Error::Database(_)) => Err(
            Fatal::Schema(format!("applying the migrations failed: {e}")),
        ),
        Err(e) => Err(Fatal::Unreachable(e.to_string())),
    }
}
