//! A plain binary encoding of precomputed statistics and indexes, for a
//! replica to store what it precomputed and another to load it
//! ([`crate::planner::Planner::encode_precomputed`]): numbers little-endian
//! and arrays prefixed by their length, so that every `f64` comes back to
//! the bit and a large array is read at memory speed.
//!
//! A [`Reader`] checks every length against what is left before it
//! allocates: a truncated or garbled input is an error, never a panic or a
//! huge allocation.

use std::borrow::Cow;

/// Why bytes could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct CodecError(pub String);

/// Appends values to a byte buffer.
#[derive(Debug, Default)]
pub struct Writer {
    buf: Vec<u8>,
}

impl Writer {
    /// An empty buffer.
    pub fn new() -> Self {
        Self::default()
    }

    /// The bytes written.
    pub fn finish(self) -> Vec<u8> {
        self.buf
    }

    /// A `u64`.
    pub fn u64(&mut self, v: u64) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A length or index.
    pub fn len(&mut self, n: usize) {
        self.u64(n as u64);
    }

    /// An `f64`, to the bit.
    pub fn f64(&mut self, v: f64) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A flag.
    pub fn bool(&mut self, v: bool) {
        self.buf.push(u8::from(v));
    }

    /// Raw bytes, length first.
    pub fn bytes(&mut self, v: &[u8]) {
        self.len(v.len());
        self.buf.extend_from_slice(v);
    }

    /// An array of `f64`, length first.
    pub fn f64s(&mut self, v: &[f64]) {
        self.len(v.len());
        self.buf.reserve(8 * v.len());
        for x in v {
            self.buf.extend_from_slice(&x.to_le_bytes());
        }
    }

    /// An array of `u32`, length first.
    pub fn u32s(&mut self, v: &[u32]) {
        self.len(v.len());
        self.buf.reserve(4 * v.len());
        for x in v {
            self.buf.extend_from_slice(&x.to_le_bytes());
        }
    }

    /// An array of `usize` (as `u64`), length first.
    pub fn usizes(&mut self, v: &[usize]) {
        self.len(v.len());
        for &x in v {
            self.len(x);
        }
    }
}

/// Hands a [`Reader`] the next piece of its bytes, given back the one it
/// read (so that its buffer can hold a later piece).
pub type NextPiece<'a> = dyn FnMut(Vec<u8>) -> Result<Vec<u8>, CodecError> + 'a;

/// Reads values in the order a [`Writer`] wrote them, from one slice or
/// from pieces handed over one after the other ([`Reader::pieces`]): a
/// value may lie across two pieces.
pub struct Reader<'a> {
    /// The current piece, read up to `at`.
    piece: Cow<'a, [u8]>,
    at: usize,
    /// Bytes not read yet, this piece's and the later ones'.
    left: usize,
    /// Where the later pieces come from.
    next: Option<&'a mut NextPiece<'a>>,
}

impl std::fmt::Debug for Reader<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Reader")
            .field("left", &self.left)
            .finish_non_exhaustive()
    }
}

impl<'a> Reader<'a> {
    /// A reader of `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Reader {
            piece: Cow::Borrowed(bytes),
            at: 0,
            left: bytes.len(),
            next: None,
        }
    }

    /// A reader of `total` bytes that `next` hands over piece by piece,
    /// each given back once read. Pieces that end before `total` bytes, or
    /// run past it, are an error.
    pub fn pieces(total: usize, next: &'a mut NextPiece<'a>) -> Self {
        Reader {
            piece: Cow::Owned(Vec::new()),
            at: 0,
            left: total,
            next: Some(next),
        }
    }

    /// The unread bytes of the current piece, the next one's once it is
    /// read whole; empty only at the end.
    fn current(&mut self) -> Result<&[u8], CodecError> {
        while self.at == self.piece.len() && self.left > 0 {
            let Some(next) = self.next.as_mut() else {
                return Err(CodecError(format!("{} bytes missing", self.left)));
            };
            let spent = std::mem::take(&mut self.piece).into_owned();
            let piece = next(spent)?;
            if piece.is_empty() || piece.len() > self.left {
                return Err(CodecError(format!(
                    "a piece of {} bytes with {} left",
                    piece.len(),
                    self.left
                )));
            }
            self.piece = Cow::Owned(piece);
            self.at = 0;
        }
        Ok(&self.piece[self.at..])
    }

    fn advance(&mut self, n: usize) {
        self.at += n;
        self.left -= n;
    }

    fn truncated(&self, n: usize) -> CodecError {
        CodecError(format!("truncated: {n} bytes wanted, {} left", self.left))
    }

    /// Fills `out` with the next bytes.
    fn take_into(&mut self, out: &mut [u8]) -> Result<(), CodecError> {
        if out.len() > self.left {
            return Err(self.truncated(out.len()));
        }
        let mut done = 0;
        while done < out.len() {
            let cur = self.current()?;
            let k = cur.len().min(out.len() - done);
            out[done..done + k].copy_from_slice(&cur[..k]);
            self.advance(k);
            done += k;
        }
        Ok(())
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], CodecError> {
        let mut out = [0; N];
        self.take_into(&mut out)?;
        Ok(out)
    }

    /// A `u64`.
    pub fn u64(&mut self) -> Result<u64, CodecError> {
        Ok(u64::from_le_bytes(self.array()?))
    }

    /// A length or index.
    #[allow(clippy::len_without_is_empty)]
    pub fn len(&mut self) -> Result<usize, CodecError> {
        usize::try_from(self.u64()?).map_err(|_| CodecError("a length past usize".into()))
    }

    /// A length of an array of `width`-byte items, checked against what is
    /// left.
    fn count(&mut self, width: usize) -> Result<usize, CodecError> {
        let n = self.len()?;
        if n.checked_mul(width).is_none_or(|b| b > self.left) {
            return Err(CodecError(format!(
                "truncated: an array of {n} items of {width} bytes, {} bytes left",
                self.left
            )));
        }
        Ok(n)
    }

    /// An `f64`.
    pub fn f64(&mut self) -> Result<f64, CodecError> {
        Ok(f64::from_le_bytes(self.array()?))
    }

    /// A flag.
    pub fn bool(&mut self) -> Result<bool, CodecError> {
        match self.array::<1>()?[0] {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(CodecError(format!("a flag of {b}"))),
        }
    }

    /// Raw bytes.
    pub fn bytes(&mut self) -> Result<Vec<u8>, CodecError> {
        let n = self.count(1)?;
        let mut out = vec![0; n];
        self.take_into(&mut out)?;
        Ok(out)
    }

    /// An array of `N`-byte words, each made a value by `from`: the whole
    /// words of each piece at once, a word across two pieces on its own.
    fn words<const N: usize, T>(&mut self, from: fn([u8; N]) -> T) -> Result<Vec<T>, CodecError> {
        let n = self.count(N)?;
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let want = n - out.len();
            let cur = self.current()?;
            let whole = (cur.len() / N).min(want);
            if whole == 0 {
                out.push(from(self.array()?));
                continue;
            }
            out.extend(
                cur[..whole * N]
                    .chunks_exact(N)
                    .map(|c| from(c.try_into().unwrap_or([0; N]))),
            );
            self.advance(whole * N);
        }
        Ok(out)
    }

    /// An array of `f64`.
    pub fn f64s(&mut self) -> Result<Vec<f64>, CodecError> {
        self.words(f64::from_le_bytes)
    }

    /// An array of `u32`.
    pub fn u32s(&mut self) -> Result<Vec<u32>, CodecError> {
        self.words(u32::from_le_bytes)
    }

    /// An array of `usize`.
    pub fn usizes(&mut self) -> Result<Vec<usize>, CodecError> {
        let n = self.count(8)?;
        (0..n).map(|_| self.len()).collect()
    }

    /// Checks that everything was read.
    pub fn end(&self) -> Result<(), CodecError> {
        if self.left == 0 {
            Ok(())
        } else {
            Err(CodecError(format!("{} bytes left over", self.left)))
        }
    }
}

/// An error unless `got` is `want`, naming `what`.
pub fn expect_len(what: &str, got: usize, want: usize) -> Result<(), CodecError> {
    if got == want {
        Ok(())
    } else {
        Err(CodecError(format!("{what}: {got} items, {want} expected")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_come_back_to_the_bit_and_truncation_is_an_error() {
        let mut w = Writer::new();
        let xs = [0.1, -0.0, f64::INFINITY, f64::MIN_POSITIVE, 1.0 / 3.0];
        w.f64s(&xs);
        w.u32s(&[7, u32::MAX]);
        w.bool(true);
        w.usizes(&[3, 5]);
        w.bytes(b"id");
        let bytes = w.finish();
        let read = |bytes: &[u8]| -> Result<_, CodecError> {
            let mut r = Reader::new(bytes);
            let out = (
                r.f64s()?,
                r.u32s()?,
                r.bool()?,
                r.usizes()?,
                r.bytes()?.to_vec(),
            );
            r.end()?;
            Ok(out)
        };
        let (back, ints, flag, lens, id) = read(&bytes).unwrap();
        assert!(
            back.iter()
                .zip(&xs)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
        assert_eq!(
            (ints, flag, lens, id),
            (vec![7, u32::MAX], true, vec![3, 5], b"id".to_vec())
        );
        for cut in 0..bytes.len() {
            assert!(read(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(read(&longer).is_err());
        // The same bytes in pieces of many sizes read the same (buffers
        // given back and reused); pieces that end before the total, or a
        // total that is not the bytes', fail.
        let in_pieces = |bytes: &[u8], size: usize, total: usize| -> Result<_, CodecError> {
            let mut chunks = bytes.chunks(size);
            let mut next = |mut spent: Vec<u8>| -> Result<Vec<u8>, CodecError> {
                let chunk = chunks.next().ok_or(CodecError("no more".into()))?;
                spent.clear();
                spent.extend_from_slice(chunk);
                Ok(spent)
            };
            let mut r = Reader::pieces(total, &mut next);
            let out = (r.f64s()?, r.u32s()?, r.bool()?, r.usizes()?, r.bytes()?);
            r.end()?;
            Ok(out)
        };
        let whole = read(&bytes).unwrap();
        for size in [1, 2, 3, 5, 7, 8, 9, 13, bytes.len()] {
            let got = in_pieces(&bytes, size, bytes.len()).unwrap();
            assert!(
                got.0
                    .iter()
                    .zip(&whole.0)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "pieces of {size}"
            );
            assert_eq!(
                (&got.1, got.2, &got.3, &got.4),
                (&whole.1, whole.2, &whole.3, &whole.4)
            );
            assert!(in_pieces(&bytes[..bytes.len() - 1], size, bytes.len()).is_err());
            assert!(in_pieces(&bytes, size, bytes.len() + 1).is_err());
            assert!(in_pieces(&bytes, size, bytes.len() - 1).is_err());
        }
        // A length far past the input allocates nothing and fails.
        let mut huge = Writer::new();
        huge.u64(u64::MAX / 2);
        assert!(Reader::new(&huge.finish()).f64s().is_err());
    }
}
