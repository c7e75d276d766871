//! An explicit little-endian byte format for saved states: no raw memory,
//! no pointers; every field written and read in a fixed order.

/// Appends fields to a byte buffer.
#[derive(Default)]
pub struct ByteWriter {
    /// The bytes written so far.
    pub buf: Vec<u8>,
}

impl ByteWriter {
    /// One byte.
    pub fn u8(&mut self, x: u8) {
        self.buf.push(x);
    }
    /// A little-endian u32.
    pub fn u32(&mut self, x: u32) {
        self.buf.extend_from_slice(&x.to_le_bytes());
    }
    /// A little-endian u64.
    pub fn u64(&mut self, x: u64) {
        self.buf.extend_from_slice(&x.to_le_bytes());
    }
    /// A little-endian f64 (bit exact).
    pub fn f64(&mut self, x: f64) {
        self.buf.extend_from_slice(&x.to_le_bytes());
    }
    /// Several f64 in order.
    pub fn f64s(&mut self, xs: &[f64]) {
        xs.iter().for_each(|&x| self.f64(x));
    }
    /// A length-prefixed UTF-8 string.
    pub fn str(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.buf.extend_from_slice(s.as_bytes());
    }
}

/// Reads fields back; every read fails cleanly past the end.
pub struct ByteReader<'a> {
    bytes: &'a [u8],
}

/// A saved state that cannot be read.
pub type SnapshotError = String;

/// Refuses a saved state with a negative peak (a largest |value|): those of
/// the structure's `|u0|` and `|a0|`, and of the slips (every simulator's).
pub(crate) fn check_peaks(structure: [f64; 2], slips: &[f64]) -> Result<(), SnapshotError> {
    if structure.iter().chain(slips).any(|&p| p < 0.0) {
        return Err("a peak of the saved state is negative".into());
    }
    Ok(())
}

impl<'a> ByteReader<'a> {
    /// Reads from `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        ByteReader { bytes }
    }
    fn take<const N: usize>(&mut self) -> Result<[u8; N], SnapshotError> {
        if self.bytes.len() < N {
            return Err("the saved state is truncated".into());
        }
        let (head, rest) = self.bytes.split_at(N);
        self.bytes = rest;
        Ok(head.try_into().expect("length checked"))
    }
    /// One byte.
    pub fn u8(&mut self) -> Result<u8, SnapshotError> {
        Ok(self.take::<1>()?[0])
    }
    /// A little-endian u32.
    pub fn u32(&mut self) -> Result<u32, SnapshotError> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    /// A little-endian u64.
    pub fn u64(&mut self) -> Result<u64, SnapshotError> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    /// A little-endian f64.
    pub fn f64(&mut self) -> Result<f64, SnapshotError> {
        Ok(f64::from_le_bytes(self.take()?))
    }
    /// Fills `out` in order.
    pub fn f64s(&mut self, out: &mut [f64]) -> Result<(), SnapshotError> {
        for x in out.iter_mut() {
            *x = self.f64()?;
        }
        Ok(())
    }
    /// A length-prefixed UTF-8 string.
    pub fn str(&mut self) -> Result<String, SnapshotError> {
        let n = self.u32()? as usize;
        if self.bytes.len() < n {
            return Err("the saved state is truncated".into());
        }
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        String::from_utf8(head.to_vec()).map_err(|_| "a saved string is not UTF-8".into())
    }
    /// Whether every byte has been read.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
}

use crate::physics::params::{Params, Support};

impl Params {
    /// Writes every field in a fixed order (part of saved states).
    pub fn write(&self, w: &mut ByteWriter) {
        w.u32(self.n_blocks as u32);
        w.f64s(&[self.mp, self.tp, self.zeta, self.g]);
        w.f64s(&self.alpha);
        w.f64s(&self.mus);
        w.f64s(&self.muk);
        w.u8(match self.support {
            Support::Structure => 0,
            Support::Prescribed => 1,
        });
    }

    /// Reads what [`Params::write`] wrote (not validated here).
    pub fn read(r: &mut ByteReader) -> Result<Params, SnapshotError> {
        let mut p = Params {
            n_blocks: r.u32()? as usize,
            ..Params::default()
        };
        let mut head = [0.0; 4];
        r.f64s(&mut head)?;
        [p.mp, p.tp, p.zeta, p.g] = head;
        r.f64s(&mut p.alpha)?;
        r.f64s(&mut p.mus)?;
        r.f64s(&mut p.muk)?;
        p.support = match r.u8()? {
            0 => Support::Structure,
            1 => Support::Prescribed,
            x => return Err(format!("unknown support {x} in the saved state")),
        };
        Ok(p)
    }
}
