//! Raw little-endian values in a byte buffer, for states saved to disk and read back exactly
//! (film states, checkpoints): integers and the bit patterns of floats, so every value comes
//! back bit for bit. Reading is bounded by the buffer: a length read from the data is checked
//! against the bytes that are left before anything is allocated, so a damaged or hostile file
//! is an error, never a huge allocation.

use crate::error::Reason;

/// Appends values to a buffer.
#[derive(Default)]
pub struct ByteWriter {
    pub bytes: Vec<u8>,
}

impl ByteWriter {
    pub fn u64(&mut self, v: u64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    pub fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }

    /// A length-prefixed byte string.
    pub fn bytes(&mut self, b: &[u8]) {
        self.u64(b.len() as u64);
        self.bytes.extend_from_slice(b);
    }

    /// A length-prefixed sequence of f64 triples.
    pub fn triples(&mut self, v: &[[f64; 3]]) {
        self.u64(v.len() as u64);
        for t in v {
            t.iter().for_each(|&c| self.f64(c));
        }
    }

    /// A length-prefixed sequence of i128 triples (each as low then high u64).
    pub fn fixed_triples(&mut self, v: &[[i128; 3]]) {
        self.u64(v.len() as u64);
        for t in v {
            for &c in t {
                self.u64(c as u64);
                self.u64((c >> 64) as u64);
            }
        }
    }

    /// A length-prefixed sequence of f64.
    pub fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        v.iter().for_each(|&c| self.f64(c));
    }

    /// A length-prefixed sequence of u64.
    pub fn u64s(&mut self, v: &[u64]) {
        self.u64(v.len() as u64);
        v.iter().for_each(|&c| self.u64(c));
    }
}

/// Reads values back in the order they were written.
pub struct ByteReader<'a> {
    bytes: &'a [u8],
}

impl<'a> ByteReader<'a> {
    pub fn new(bytes: &'a [u8]) -> ByteReader<'a> {
        ByteReader { bytes }
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.bytes.len()
    }

    fn take(&mut self, n: usize) -> Reason<&'a [u8]> {
        if n > self.bytes.len() {
            return Err("the data ends early (truncated or damaged)".into());
        }
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        Ok(head)
    }

    pub fn u64(&mut self) -> Reason<u64> {
        let b = self.take(8)?;
        Ok(u64::from_le_bytes(b.try_into().map_err(|_| "short read")?))
    }

    pub fn f64(&mut self) -> Reason<f64> {
        self.u64().map(f64::from_bits)
    }

    /// A length prefix for items of `item` bytes each, checked against what is left.
    fn len(&mut self, item: usize) -> Reason<usize> {
        let n = self.u64()?;
        match usize::try_from(n) {
            Ok(n) if n.checked_mul(item).is_some_and(|b| b <= self.bytes.len()) => Ok(n),
            _ => Err(format!(
                "a count of {n} exceeds the data ({} bytes left)",
                self.bytes.len()
            )),
        }
    }

    pub fn bytes(&mut self) -> Reason<&'a [u8]> {
        let n = self.len(1)?;
        self.take(n)
    }

    pub fn triples(&mut self) -> Reason<Vec<[f64; 3]>> {
        let n = self.len(24)?;
        (0..n)
            .map(|_| Ok([self.f64()?, self.f64()?, self.f64()?]))
            .collect()
    }

    pub fn fixed_triples(&mut self) -> Reason<Vec<[i128; 3]>> {
        let n = self.len(48)?;
        let mut one = || -> Reason<i128> {
            let lo = self.u64()?;
            let hi = self.u64()?;
            Ok((i128::from(hi as i64) << 64) | i128::from(lo))
        };
        (0..n).map(|_| Ok([one()?, one()?, one()?])).collect()
    }

    pub fn f64s(&mut self) -> Reason<Vec<f64>> {
        let n = self.len(8)?;
        (0..n).map(|_| self.f64()).collect()
    }

    pub fn u64s(&mut self) -> Reason<Vec<u64>> {
        let n = self.len(8)?;
        (0..n).map(|_| self.u64()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_come_back_bit_for_bit() {
        let mut w = ByteWriter::default();
        w.u64(u64::MAX);
        w.f64(-0.0);
        w.triples(&[[f64::MIN_POSITIVE, 1.0 / 3.0, f64::MAX]]);
        w.f64s(&[5e-324]);
        w.u64s(&[7, 8]);
        w.bytes(b"stage");
        w.fixed_triples(&[[i128::MIN, -1, i128::MAX]]);
        let mut r = ByteReader::new(&w.bytes);
        assert_eq!(r.u64(), Ok(u64::MAX));
        assert_eq!(r.f64().unwrap().to_bits(), (-0.0f64).to_bits());
        assert_eq!(
            r.triples(),
            Ok(vec![[f64::MIN_POSITIVE, 1.0 / 3.0, f64::MAX]])
        );
        assert_eq!(r.f64s().unwrap()[0].to_bits(), 1);
        assert_eq!(r.u64s(), Ok(vec![7, 8]));
        assert_eq!(r.bytes(), Ok(&b"stage"[..]));
        assert_eq!(r.fixed_triples(), Ok(vec![[i128::MIN, -1, i128::MAX]]));
        assert_eq!(r.remaining(), 0);
        assert!(r.u64().is_err());
    }

    #[test]
    fn a_count_beyond_the_data_is_an_error_not_an_allocation() {
        let mut w = ByteWriter::default();
        w.u64(1 << 60);
        assert!(ByteReader::new(&w.bytes)
            .triples()
            .unwrap_err()
            .contains("exceeds"));
        assert!(ByteReader::new(&w.bytes).bytes().is_err());
    }
}
