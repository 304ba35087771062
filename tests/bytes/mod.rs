//! An FMU state's bytes, as a host keeps them: the integrators' tests write a state and read it
//! back through these.

#![allow(dead_code)] // each test binary uses some of these

use beam_body::solver::Integrator;
use beam_body::visit::StateVisitor;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim};

/// Writes a state as little-endian bytes, as an FMU's `fmi2SerializeFMUstate` would: reals by
/// their bits, counts as u64, flags as one byte.
pub struct ByteWriter(pub Vec<u8>);

impl StateVisitor for ByteWriter {
    fn real(&mut self, _: &'static str, x: &mut f64) {
        self.0.extend(x.to_bits().to_le_bytes());
    }
    fn count(&mut self, _: &'static str, x: &mut u64) {
        self.0.extend(x.to_le_bytes());
    }
    fn flag(&mut self, _: &'static str, x: &mut bool) {
        self.0.push(u8::from(*x));
    }
}

/// Reads what [`ByteWriter`] wrote from untrusted bytes. The visitor cannot fail, so the
/// first problem (too few bytes, a flag byte other than 0 or 1) is recorded and the rest of
/// the fields are left alone.
pub struct ByteReader<'a> {
    pub bytes: &'a [u8],
    pub error: Option<&'static str>,
}

impl ByteReader<'_> {
    fn take<const K: usize>(&mut self, name: &'static str) -> Option<[u8; K]> {
        if self.error.is_some() {
            return None;
        }
        match self.bytes.split_first_chunk::<K>() {
            Some((head, rest)) => {
                self.bytes = rest;
                Some(*head)
            }
            None => {
                self.error = Some(name);
                None
            }
        }
    }
}

impl StateVisitor for ByteReader<'_> {
    fn real(&mut self, name: &'static str, x: &mut f64) {
        if let Some(b) = self.take::<8>(name) {
            *x = f64::from_bits(u64::from_le_bytes(b));
        }
    }
    fn count(&mut self, name: &'static str, x: &mut u64) {
        if let Some(b) = self.take::<8>(name) {
            *x = u64::from_le_bytes(b);
        }
    }
    fn flag(&mut self, name: &'static str, x: &mut bool) {
        match self.take::<1>(name) {
            Some([0]) => *x = false,
            Some([1]) => *x = true,
            Some(_) => self.error = Some(name),
            None => {}
        }
    }
}

/// The state of an integrator as bytes.
pub fn to_bytes<D: Dim, I: Integrator<D>>(s: &I) -> Vec<u8>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    let mut w = ByteWriter(Vec::new());
    Integrator::visit_state(&mut s.clone(), &mut w);
    w.0
}

/// Reads a state from untrusted bytes into `s` (a fresh solver of the same configuration),
/// checked as a host's would be.
pub fn read_into<D: Dim, I: Integrator<D>>(mut s: I, bytes: &[u8]) -> Result<I, String>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    let mut r = ByteReader { bytes, error: None };
    Integrator::visit_state(&mut s, &mut r);
    if let Some(field) = r.error {
        return Err(format!("truncated or malformed at `{field}`"));
    }
    if !r.bytes.is_empty() {
        return Err(format!("{} bytes left over", r.bytes.len()));
    }
    s.check_state().map_err(|e| e.to_string())?;
    Ok(s)
}
