//! What a replica precomputed for a registered scenario, stored once for
//! every replica on the database (`--database-url`): see the table
//! `precomputed` in `migrations/`.
//!
//! - **Bytes.** [`Planner::encode_precomputed`](crate::planner::Planner::encode_precomputed)'s
//!   bytes, cut in chunks of [`RAW_CHUNK_BYTES`], each byte-shuffled and
//!   compressed with zstd on its own (with its checksum, so a corrupt
//!   chunk is found on reading), so that they are (de)compressed in
//!   parallel, and a chunk read is decompressed while the next are read
//!   ([`PgStore::send_precomputed`], [`unpack`]).
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

use std::sync::mpsc::{Receiver, Sender};
use std::sync::{Mutex, PoisonError};
use std::time::Duration;

use rayon::prelude::*;
use sqlx::{Connection, PgConnection};

use super::{DbError, PgStore};

/// Raw bytes per stored chunk (a multiple of 8, see [`shuffle`]); each is
/// compressed on its own.
pub const RAW_CHUNK_BYTES: usize = 8 << 20;

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
    /// Its chunks, in order: chunk `k` holds raw bytes from
    /// `k·RAW_CHUNK_BYTES` on.
    pub chunks: Vec<Vec<u8>>,
}

impl Stored {
    /// `raw` cut in chunks of [`RAW_CHUNK_BYTES`], each byte-shuffled and
    /// compressed on its own (in parallel).
    ///
    /// # Errors
    /// A message if zstd fails.
    pub fn compress(format: i32, raw: &[u8]) -> Result<Self, String> {
        let chunks = raw
            .par_chunks(RAW_CHUNK_BYTES)
            .map(|piece| {
                let mut shuffled = vec![0; piece.len()];
                shuffle(piece, &mut shuffled);
                let mut zstd = zstd::bulk::Compressor::new(LEVEL).map_err(|e| e.to_string())?;
                zstd.set_parameter(zstd::stream::raw::CParameter::ChecksumFlag(true))
                    .map_err(|e| e.to_string())?;
                zstd.compress(&shuffled).map_err(|e| e.to_string())
            })
            .collect::<Result<Vec<_>, String>>()?;
        Ok(Stored {
            format,
            raw_bytes: raw.len(),
            chunks,
        })
    }

    /// Its size compressed.
    pub fn compressed_bytes(&self) -> usize {
        self.chunks.iter().map(Vec::len).sum()
    }
}

/// What [`PgStore::send_precomputed`] sends, in order: the head, then
/// every chunk.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Part {
    /// The stored row: its encoding's version, its size uncompressed, and
    /// how many chunks follow.
    Head {
        /// Its encoding's version.
        format: i32,
        /// Its size uncompressed.
        raw_bytes: usize,
        /// Its chunks.
        chunks: usize,
    },
    /// The next chunk, compressed.
    Chunk(Vec<u8>),
}

/// A stored precomputation, decompressed ([`unpack`]).
#[derive(Debug)]
pub struct Unpacked {
    /// Its encoding's version.
    pub format: i32,
    /// The bytes [`Stored::compress`] was given.
    pub raw: Vec<u8>,
    /// Its size compressed.
    pub compressed_bytes: usize,
}

/// The precomputation whose [`Part`]s arrive on `parts`, each chunk
/// decompressed on the rayon pool as soon as it arrives, in parallel with
/// the next ones' arrival. Blocks until `parts` has sent every chunk the
/// head announced.
///
/// # Errors
/// A message when the parts stop early or do not start with a head, or
/// for chunks that are not whole zstd data of the head's size (corrupt,
/// truncated, or of another size).
pub fn unpack(parts: &Receiver<Part>) -> Result<Unpacked, String> {
    let Ok(Part::Head {
        format,
        raw_bytes,
        chunks,
    }) = parts.recv()
    else {
        return Err("no stored precomputation came".into());
    };
    if chunks != raw_bytes.div_ceil(RAW_CHUNK_BYTES) {
        return Err(format!("{chunks} chunks for {raw_bytes} bytes"));
    }
    let mut raw = vec![0; raw_bytes];
    let failed = Mutex::new(None);
    // Buffers of unpacked chunks, kept from chunk to chunk: fresh memory
    // costs page faults.
    let buffers = Mutex::new(Vec::new());
    let mut received = 0;
    let mut compressed_bytes = 0;
    rayon::in_place_scope(|scope| {
        for piece in raw.chunks_mut(RAW_CHUNK_BYTES) {
            let Ok(Part::Chunk(packed)) = parts.recv() else {
                break;
            };
            received += 1;
            compressed_bytes += packed.len();
            let (failed, buffers) = (&failed, &buffers);
            scope.spawn(move |_| {
                if let Err(e) = unpack_chunk(&packed, piece, buffers) {
                    failed
                        .lock()
                        .unwrap_or_else(PoisonError::into_inner)
                        .get_or_insert(e);
                }
            });
        }
    });
    if let Some(e) = failed.into_inner().unwrap_or_else(PoisonError::into_inner) {
        return Err(e);
    }
    if received != chunks {
        return Err(format!("{received} chunks of {chunks} came"));
    }
    Ok(Unpacked {
        format,
        raw,
        compressed_bytes,
    })
}

/// Decompresses chunk `packed` into `piece`, the part of the raw bytes it
/// holds, through a buffer of `buffers`.
fn unpack_chunk(
    packed: &[u8],
    piece: &mut [u8],
    buffers: &Mutex<Vec<Vec<u8>>>,
) -> Result<(), String> {
    let taken = buffers.lock().unwrap_or_else(PoisonError::into_inner).pop();
    let mut shuffled = taken.unwrap_or_else(|| vec![0; RAW_CHUNK_BYTES]);
    let n = zstd::bulk::Decompressor::new()
        .and_then(|mut zstd| zstd.decompress_to_buffer(packed, shuffled.as_mut_slice()))
        .map_err(|e| e.to_string())?;
    if n != piece.len() {
        return Err(format!("a chunk of {n} bytes, {} expected", piece.len()));
    }
    unshuffle(&shuffled[..n], piece);
    buffers
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .push(shuffled);
    Ok(())
}

/// Groups the bytes of `src`'s 8-byte words by position (every word's
/// first byte, then every second, …; a tail of fewer than 8 bytes kept as
/// is): the sign and exponent bytes of nearby `f64` repeat, and zstd finds
/// them together.
fn shuffle(src: &[u8], dst: &mut [u8]) {
    let n = src.len() / 8;
    for (i, word) in src.chunks_exact(8).enumerate() {
        for (b, &byte) in word.iter().enumerate() {
            dst[b * n + i] = byte;
        }
    }
    dst[8 * n..].copy_from_slice(&src[8 * n..]);
}

/// The inverse of [`shuffle`].
fn unshuffle(src: &[u8], dst: &mut [u8]) {
    let n = src.len() / 8;
    for (i, word) in dst.chunks_exact_mut(8).enumerate() {
        for (b, byte) in word.iter_mut().enumerate() {
            *byte = src[b * n + i];
        }
    }
    dst[8 * n..].copy_from_slice(&src[8 * n..]);
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
    /// Sends the stored precomputation of scenario `id` to `to` as it is
    /// read, its head then its chunks one by one, so that [`unpack`] works
    /// on the chunks read while the next are: false if there is none (a
    /// row whose chunks are missing is taken as absent). Reading stops
    /// early, still true, if `to`'s receiver is gone.
    ///
    /// # Errors
    /// [`DbError`] if the database is unreachable or too slow.
    pub async fn send_precomputed(&self, id: &str, to: &Sender<Part>) -> Result<bool, DbError> {
        self.within(TRANSFER_TIMEOUT, async {
            let mut tx = self.pool.begin().await?;
            // One snapshot for the row and all its chunks.
            sqlx::query("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ, READ ONLY")
                .execute(&mut *tx)
                .await?;
            sqlx::query("SET LOCAL statement_timeout = 0")
                .execute(&mut *tx)
                .await?;
            let head: Option<(i32, i64, i32)> = sqlx::query_as(
                "SELECT p.format, p.raw_bytes, p.chunks FROM precomputed p \
                 WHERE p.scenario_id = $1 AND p.chunks = \
                 (SELECT count(*) FROM precomputed_chunks c WHERE c.scenario_id = $1)",
            )
            .bind(id)
            .fetch_optional(&mut *tx)
            .await?;
            let Some((format, raw_bytes, chunks)) = head else {
                return Ok(false);
            };
            let head = Part::Head {
                format,
                raw_bytes: usize::try_from(raw_bytes).unwrap_or(usize::MAX),
                chunks: usize::try_from(chunks).unwrap_or(0),
            };
            if to.send(head).is_err() {
                return Ok(true);
            }
            for n in 0..chunks {
                let (data,): (Vec<u8>,) = sqlx::query_as(
                    "SELECT data FROM precomputed_chunks WHERE scenario_id = $1 AND n = $2",
                )
                .bind(id)
                .bind(n)
                .fetch_one(&mut *tx)
                .await?;
                if to.send(Part::Chunk(data)).is_err() {
                    break;
                }
            }
            tx.commit().await?;
            Ok(true)
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

    impl Stored {
        /// Its parts as [`PgStore::send_precomputed`] sends them: the
        /// head, then every chunk.
        fn parts(&self) -> impl Iterator<Item = Part> + '_ {
            let head = Part::Head {
                format: self.format,
                raw_bytes: self.raw_bytes,
                chunks: self.chunks.len(),
            };
            std::iter::once(head).chain(self.chunks.iter().cloned().map(Part::Chunk))
        }
    }

    fn stored_parts(raw: &[u8]) -> Vec<Part> {
        Stored::compress(1, raw).unwrap().parts().collect()
    }

    #[test]
    fn compressed_bytes_come_back_and_corruption_is_found() {
        let raw: Vec<u8> = (0..3 * RAW_CHUNK_BYTES / 2 + 5)
            .map(|i| (i * 7 % 251) as u8)
            .collect();
        let unpack_of = |parts: Vec<Part>| {
            let (to, from) = std::sync::mpsc::channel();
            parts.into_iter().for_each(|part| to.send(part).unwrap());
            drop(to);
            unpack(&from)
        };
        let stored = Stored::compress(1, &raw).unwrap();
        assert_eq!(stored.chunks.len(), 2);
        let back = unpack_of(stored.parts().collect()).unwrap();
        assert_eq!(
            (back.format, back.compressed_bytes),
            (1, stored.compressed_bytes())
        );
        assert_eq!(back.raw, raw);
        let mut bad = Stored {
            chunks: stored.chunks.clone(),
            ..stored
        };
        let last = bad.chunks.len() - 1;
        let mid = bad.chunks[last].len() / 2;
        bad.chunks[last][mid] ^= 0x40;
        assert!(unpack_of(bad.parts().collect()).is_err());
        // Chunks in the wrong order are whole zstd data of the wrong size.
        let mut swapped: Vec<Part> = stored_parts(&raw);
        swapped.swap(1, 2);
        assert!(unpack_of(swapped).is_err());
        // Parts that stop early, or never start with a head.
        let mut parts = stored_parts(&raw);
        parts.pop();
        assert!(unpack_of(parts).is_err());
        assert!(unpack_of(stored_parts(&raw).split_off(1)).is_err());
        assert!(unpack_of(Vec::new()).is_err());
    }
}
