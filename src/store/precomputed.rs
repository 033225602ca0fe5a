//! What a replica precomputed for a registered scenario, stored once for
//! every replica on the database (`--database-url`): see the table
//! `precomputed` in `migrations/`.
//!
//! - **Bytes.** [`Planner::encode_precomputed`](crate::planner::Planner::encode_precomputed)'s
//!   bytes, compressed with zstd (with its checksum, so a corrupt chunk is
//!   found on reading) and cut in chunks of [`CHUNK_BYTES`].
//! - **Once.** A replica about to precompute takes a claim
//!   ([`PgStore::claim_precompute`]), a session-level advisory lock on a
//!   connection of its own: another replica that finds it taken waits for
//!   the row instead of computing too, and the lock goes with the
//!   connection if its holder dies.
//! - **Whole or absent.** A row and its chunks are written in one
//!   transaction.
//!
//! Reads and writes move up to hundreds of megabytes, so they get
//! [`TRANSFER_TIMEOUT`] instead of the database's usual time limit.

use std::time::Duration;

use sqlx::{Connection, PgConnection};

use super::{DbError, PgStore};

/// The size of a stored chunk, compressed.
pub const CHUNK_BYTES: usize = 8 << 20;

/// Time limit of reading or writing a stored precomputation.
pub const TRANSFER_TIMEOUT: Duration = Duration::from_secs(600);

/// The first key of the claims' advisory locks (`vigl` in ASCII); the
/// second is the scenario id's hash.
const CLAIM_CLASS: i32 = 0x7669_676c;

/// The zstd level: fast to write, and reading is as fast at any level.
const LEVEL: i32 = 1;

/// A stored precomputation, compressed.
#[derive(Debug)]
pub struct Stored {
    /// Its encoding's version.
    pub format: i32,
    /// Its size uncompressed.
    pub raw_bytes: usize,
    /// Its chunks, in order.
    pub chunks: Vec<Vec<u8>>,
}

impl Stored {
    /// `raw` compressed and cut in chunks.
    ///
    /// # Errors
    /// A message if zstd fails.
    pub fn compress(format: i32, raw: &[u8]) -> Result<Self, String> {
        let mut encoder = zstd::Encoder::new(Vec::new(), LEVEL).map_err(|e| e.to_string())?;
        encoder.include_checksum(true).map_err(|e| e.to_string())?;
        std::io::Write::write_all(&mut encoder, raw).map_err(|e| e.to_string())?;
        let packed = encoder.finish().map_err(|e| e.to_string())?;
        Ok(Stored {
            format,
            raw_bytes: raw.len(),
            chunks: packed.chunks(CHUNK_BYTES).map(<[u8]>::to_vec).collect(),
        })
    }

    /// The bytes [`Stored::compress`] was given.
    ///
    /// # Errors
    /// A message for chunks that are not whole zstd data of `raw_bytes`
    /// (corrupt, truncated, or of another size).
    pub fn decompress(&self) -> Result<Vec<u8>, String> {
        let packed = self.chunks.concat();
        let raw = zstd::stream::decode_all(packed.as_slice()).map_err(|e| e.to_string())?;
        if raw.len() != self.raw_bytes {
            return Err(format!(
                "{} bytes uncompressed, {} recorded",
                raw.len(),
                self.raw_bytes
            ));
        }
        Ok(raw)
    }

    /// Its size compressed.
    pub fn compressed_bytes(&self) -> usize {
        self.chunks.iter().map(Vec::len).sum()
    }
}

/// A claim on precomputing one scenario, held until released or dropped
/// (its connection closed).
#[derive(Debug)]
pub struct Claim {
    conn: PgConnection,
}

impl Claim {
    /// Releases the claim.
    pub async fn release(self) {
        // Closing the connection ends its session, and the lock with it.
        let _ = self.conn.close().await;
    }
}

impl PgStore {
    /// The stored precomputation of scenario `id`, if any (a row whose
    /// chunks are missing is taken as absent).
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn load_precomputed(&self, id: &str) -> Result<Option<Stored>, DbError> {
        self.within(TRANSFER_TIMEOUT, async {
            let mut tx = self.pool.begin().await?;
            sqlx::query("SET LOCAL statement_timeout = 0")
                .execute(&mut *tx)
                .await?;
            let head: Option<(i32, i64, i32)> = sqlx::query_as(
                "SELECT format, raw_bytes, chunks FROM precomputed WHERE scenario_id = $1",
            )
            .bind(id)
            .fetch_optional(&mut *tx)
            .await?;
            let Some((format, raw_bytes, count)) = head else {
                return Ok(None);
            };
            let chunks: Vec<(Vec<u8>,)> = sqlx::query_as(
                "SELECT data FROM precomputed_chunks WHERE scenario_id = $1 ORDER BY n",
            )
            .bind(id)
            .fetch_all(&mut *tx)
            .await?;
            tx.commit().await?;
            if chunks.len() != usize::try_from(count).unwrap_or(0) {
                return Ok(None);
            }
            Ok(Some(Stored {
                format,
                raw_bytes: usize::try_from(raw_bytes).unwrap_or(usize::MAX),
                chunks: chunks.into_iter().map(|(c,)| c).collect(),
            }))
        })
        .await
    }

    /// Stores the precomputation of scenario `id`, unless one is stored
    /// already (or the scenario was deleted); true if this call stored it.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn store_precomputed(&self, id: &str, stored: &Stored) -> Result<bool, DbError> {
        self.within(TRANSFER_TIMEOUT, async {
            let mut tx = self.pool.begin().await?;
            sqlx::query("SET LOCAL statement_timeout = 0")
                .execute(&mut *tx)
                .await?;
            let head = sqlx::query(
                "INSERT INTO precomputed (scenario_id, format, raw_bytes, chunks) \
                 SELECT $1, $2, $3, $4 WHERE EXISTS (SELECT 1 FROM scenarios WHERE id = $1) \
                 ON CONFLICT (scenario_id) DO NOTHING",
            )
            .bind(id)
            .bind(stored.format)
            .bind(i64::try_from(stored.raw_bytes).unwrap_or(i64::MAX))
            .bind(i32::try_from(stored.chunks.len()).unwrap_or(i32::MAX))
            .execute(&mut *tx)
            .await?;
            if head.rows_affected() == 0 {
                return Ok(false);
            }
            for (n, chunk) in stored.chunks.iter().enumerate() {
                sqlx::query(
                    "INSERT INTO precomputed_chunks (scenario_id, n, data) VALUES ($1, $2, $3)",
                )
                .bind(id)
                .bind(i32::try_from(n).unwrap_or(i32::MAX))
                .bind(chunk)
                .execute(&mut *tx)
                .await?;
            }
            tx.commit().await?;
            Ok(true)
        })
        .await
    }

    /// Deletes the stored precomputation of scenario `id` (one that could
    /// not be read), so that the next replica stores a good one.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn drop_precomputed(&self, id: &str) -> Result<(), DbError> {
        self.bounded(
            sqlx::query("DELETE FROM precomputed WHERE scenario_id = $1")
                .bind(id)
                .execute(&self.pool),
        )
        .await?;
        Ok(())
    }

    /// Claims the precomputation of scenario `id` for this replica: `None`
    /// if another replica holds the claim.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn claim_precompute(&self, id: &str) -> Result<Option<Claim>, DbError> {
        self.bounded(async {
            // A connection of its own, never back to the pool: the lock
            // lives as long as it.
            let mut conn = self.pool.acquire().await?.detach();
            let (got,): (bool,) = sqlx::query_as("SELECT pg_try_advisory_lock($1, hashtext($2))")
                .bind(CLAIM_CLASS)
                .bind(id)
                .fetch_one(&mut conn)
                .await?;
            if got {
                Ok(Some(Claim { conn }))
            } else {
                let _ = conn.close().await;
                Ok(None)
            }
        })
        .await
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compressed_bytes_come_back_and_corruption_is_found() {
        let raw: Vec<u8> = (0..3 * CHUNK_BYTES / 2)
            .map(|i| (i * 7 % 251) as u8)
            .collect();
        let stored = Stored::compress(1, &raw).unwrap();
        assert_eq!(stored.decompress().unwrap(), raw);
        let mut bad = Stored {
            chunks: stored.chunks.clone(),
            ..stored
        };
        let last = bad.chunks.len() - 1;
        let mid = bad.chunks[last].len() / 2;
        bad.chunks[last][mid] ^= 0x40;
        assert!(bad.decompress().is_err());
        bad.chunks.pop();
        assert!(bad.decompress().is_err());
    }
}
