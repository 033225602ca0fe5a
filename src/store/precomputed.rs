//! What a replica precomputed for a registered scenario, stored once for
//! every replica on the database (`--database-url`): see the table
//! `precomputed` in `migrations/`.
//!
//! - **Bytes.** [`Planner::encode_precomputed`](crate::planner::Planner::encode_precomputed)'s
//!   bytes, cut in chunks of [`RAW_CHUNK_BYTES`], each byte-shuffled and
//!   compressed with zstd on its own (with its checksum, so a corrupt
//!   chunk is found on reading), so that they are compressed in parallel,
//!   and a chunk read is decompressed and decoded while the next are read
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
    /// The stored row.
    Head(Head),
    /// The next chunk, compressed.
    Chunk(Vec<u8>),
}

/// The head of a stored precomputation: its row, which tells how many
/// chunks follow.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Head {
    /// Its encoding's version.
    pub format: i32,
    /// Its size uncompressed.
    pub raw_bytes: usize,
    /// Its chunks.
    pub chunks: usize,
}

/// Chunks decompressed ahead of the reader at most: enough to keep both
/// busy, few enough that their buffers are reused rather than fresh.
const AHEAD: usize = 2;

/// Reads the precomputation whose [`Part`]s arrive on `parts`: `read` gets
/// its head and, through `next`, its raw bytes chunk by chunk, in order,
/// each given back once read so that its buffer holds a later one. The
/// chunks are decompressed on a thread of their own while `read` reads the
/// one before and the next ones arrive. Returns what `read` returned and
/// the size compressed.
///
/// # Errors
/// A message when the parts do not start with a head, or the head's
/// chunks do not fit its size. `next` fails when the parts stop early or
/// a chunk is not whole zstd data of its size (corrupt, truncated, or of
/// another size).
pub fn unpack<T>(
    parts: Receiver<Part>,
    read: impl FnOnce(Head, &mut dyn FnMut(Vec<u8>) -> Result<Vec<u8>, String>) -> T,
) -> Result<(T, usize), String> {
    let Ok(Part::Head(head)) = parts.recv() else {
        return Err("no stored precomputation came".into());
    };
    let Head {
        raw_bytes, chunks, ..
    } = head;
    if chunks != raw_bytes.div_ceil(RAW_CHUNK_BYTES) {
        return Err(format!("{chunks} chunks for {raw_bytes} bytes"));
    }
    let (ready, from_unpacker) = std::sync::mpsc::sync_channel(AHEAD);
    let (to_unpacker, spent) = std::sync::mpsc::channel::<Vec<u8>>();
    std::thread::scope(|scope| {
        let unpacker = scope.spawn(move || {
            let mut compressed = 0;
            let mut shuffled = Vec::new();
            for k in 0..chunks {
                let size = RAW_CHUNK_BYTES.min(raw_bytes - k * RAW_CHUNK_BYTES);
                let piece = match parts.recv() {
                    Ok(Part::Chunk(packed)) => {
                        compressed += packed.len();
                        let buffer = spent.try_recv().unwrap_or_default();
                        unpack_chunk(&packed, size, &mut shuffled, buffer)
                    }
                    _ => Err(format!("{k} chunks of {chunks} came")),
                };
                let failed = piece.is_err();
                // A reader gone (it failed, or read all) ends the work.
                if ready.send(piece).is_err() || failed {
                    break;
                }
            }
            compressed
        });
        let mut next = move |read: Vec<u8>| {
            if read.capacity() > 0 {
                let _ = to_unpacker.send(read);
            }
            from_unpacker
                .recv()
                .unwrap_or_else(|_| Err("the chunks stopped".into()))
        };
        let out = read(head, &mut next);
        // Dropping the receiver lets an unpacker that is ahead finish.
        drop(next);
        let compressed = unpacker
            .join()
            .map_err(|_| "the unpacker failed".to_string())?;
        Ok((out, compressed))
    })
}

/// Chunk `packed`, of `size` bytes raw, decompressed through `shuffled`
/// into `piece` (a buffer of an earlier chunk, or empty).
fn unpack_chunk(
    packed: &[u8],
    size: usize,
    shuffled: &mut Vec<u8>,
    mut piece: Vec<u8>,
) -> Result<Vec<u8>, String> {
    shuffled.resize(RAW_CHUNK_BYTES, 0);
    let n = zstd::bulk::Decompressor::new()
        .and_then(|mut zstd| zstd.decompress_to_buffer(packed, shuffled.as_mut_slice()))
        .map_err(|e| e.to_string())?;
    if n != size {
        return Err(format!("a chunk of {n} bytes, {size} expected"));
    }
    // A buffer of a whole chunk already has the length: not written twice.
    piece.resize(size, 0);
    unshuffle(&shuffled[..n], &mut piece);
    Ok(piece)
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
            let head = Part::Head(Head {
                format,
                raw_bytes: usize::try_from(raw_bytes).unwrap_or(usize::MAX),
                chunks: usize::try_from(chunks).unwrap_or(0),
            });
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
            let head = Part::Head(Head {
                format: self.format,
                raw_bytes: self.raw_bytes,
                chunks: self.chunks.len(),
            });
            std::iter::once(head).chain(self.chunks.iter().cloned().map(Part::Chunk))
        }
    }

    fn stored_parts(raw: &[u8]) -> Vec<Part> {
        Stored::compress(1, raw).unwrap().parts().collect()
    }

    #[test]
    fn compressed_bytes_come_back_and_corruption_is_found() {
        let raw: Vec<u8> = (0..3 * RAW_CHUNK_BYTES + 5)
            .map(|i| (i * 7 % 251) as u8)
            .collect();
        // The head, the raw bytes read chunk by chunk (each buffer given
        // back), and the size compressed.
        let unpack_of = |parts: Vec<Part>| -> Result<(Head, Vec<u8>, usize), String> {
            let (to, from) = std::sync::mpsc::channel();
            parts.into_iter().for_each(|part| to.send(part).unwrap());
            drop(to);
            let (read, compressed) = unpack(from, |head, next| {
                let mut raw = Vec::new();
                let mut piece = Vec::new();
                while raw.len() < head.raw_bytes {
                    piece = next(piece)?;
                    raw.extend_from_slice(&piece);
                }
                Ok::<_, String>((head, raw))
            })?;
            let (head, raw) = read?;
            Ok((head, raw, compressed))
        };
        let stored = Stored::compress(1, &raw).unwrap();
        assert_eq!(stored.chunks.len(), 4);
        let (head, back, compressed) = unpack_of(stored.parts().collect()).unwrap();
        assert_eq!(
            (head.format, head.raw_bytes, compressed),
            (1, raw.len(), stored.compressed_bytes())
        );
        assert!(back == raw);
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
        swapped.swap(1, 4);
        assert!(unpack_of(swapped).is_err());
        // A head whose chunks do not fit its size.
        let mut parts = stored_parts(&raw);
        parts[0] = Part::Head(Head {
            format: 1,
            raw_bytes: raw.len(),
            chunks: 5,
        });
        assert!(unpack_of(parts).is_err());
        // Parts that stop early, or never start with a head.
        let mut parts = stored_parts(&raw);
        parts.pop();
        assert!(unpack_of(parts).is_err());
        assert!(unpack_of(stored_parts(&raw).split_off(1)).is_err());
        assert!(unpack_of(Vec::new()).is_err());
    }
}
