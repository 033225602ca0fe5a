//! A plain binary encoding of precomputed statistics and indexes, for a
//! replica to store what it precomputed and another to load it
//! ([`crate::planner::Planner::encode_precomputed`]): numbers little-endian
//! and arrays prefixed by their length, so that every `f64` comes back to
//! the bit and a large array is read at memory speed.
//!
//! A [`Reader`] checks every length against what is left before it
//! allocates: a truncated or garbled input is an error, never a panic or a
//! huge allocation.

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

/// Reads values in the order a [`Writer`] wrote them.
#[derive(Debug)]
pub struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    /// A reader of `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Reader { bytes }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], CodecError> {
        if n > self.bytes.len() {
            return Err(CodecError(format!(
                "truncated: {n} bytes wanted, {} left",
                self.bytes.len()
            )));
        }
        let (head, tail) = self.bytes.split_at(n);
        self.bytes = tail;
        Ok(head)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], CodecError> {
        let mut out = [0; N];
        out.copy_from_slice(self.take(N)?);
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
        if n.checked_mul(width).is_none_or(|b| b > self.bytes.len()) {
            return Err(CodecError(format!(
                "truncated: an array of {n} items of {width} bytes, {} bytes left",
                self.bytes.len()
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
        match self.take(1)?[0] {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(CodecError(format!("a flag of {b}"))),
        }
    }

    /// Raw bytes.
    pub fn bytes(&mut self) -> Result<&'a [u8], CodecError> {
        let n = self.count(1)?;
        self.take(n)
    }

    /// An array of `N`-byte words, each made a value by `from`.
    fn words<const N: usize, T>(&mut self, from: fn([u8; N]) -> T) -> Result<Vec<T>, CodecError> {
        let n = self.count(N)?;
        Ok(self
            .take(N * n)?
            .chunks_exact(N)
            .map(|c| from(c.try_into().unwrap_or([0; N])))
            .collect())
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
        if self.bytes.is_empty() {
            Ok(())
        } else {
            Err(CodecError(format!("{} bytes left over", self.bytes.len())))
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
        // A length far past the input allocates nothing and fails.
        let mut huge = Writer::new();
        huge.u64(u64::MAX / 2);
        assert!(Reader::new(&huge.finish()).f64s().is_err());
    }
}
