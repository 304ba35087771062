//! Visiting a state field by field: the one walk that both writes a state and reads it back
//! ([`StateVisitor`]). The integrator, the φ input and the FMU core each walk their fields
//! with it; the byte format (endianness, header, version) belongs to whoever frames the bytes.
#![forbid(unsafe_code)]

/// Visits every field of a state in a fixed order: a writer reads each field, a reader
/// overwrites it. The names are for error messages.
pub trait StateVisitor {
    /// A real field. A reader may store any value, NaN included; the owner's check judges it.
    fn real(&mut self, name: &'static str, x: &mut f64);
    /// A counter, order or index. A reader may store any value.
    fn count(&mut self, name: &'static str, x: &mut u64);
    /// A boolean field.
    fn flag(&mut self, name: &'static str, x: &mut bool);
    /// Called after visiting fields whose values are discarded (those of an absent LU, an
    /// unset landing time), with whether they held what a writer gives (zeros, the identity
    /// permutation). A reader may refuse anything else, so that every state has a single
    /// byte form. By default nothing happens.
    fn discarded(&mut self, _name: &'static str, _as_written: bool) {}
}

/// Visits a `usize` as a `u64`. A value that does not fit the platform's `usize` becomes
/// `usize::MAX`, which every range check rejects.
pub fn visit_usize<V: StateVisitor + ?Sized>(v: &mut V, name: &'static str, x: &mut usize) {
    let mut c = u64::try_from(*x).unwrap_or(u64::MAX);
    v.count(name, &mut c);
    *x = usize::try_from(c).unwrap_or(usize::MAX);
}
