//! The byte format of a serialized FMU state, and its reader for untrusted bytes.
//!
//! Layout (all integers little-endian):
//!
//! | bytes | content |
//! |-------|---------|
//! | 8     | magic `BBFMUST\0` |
//! | 4     | format version, [`VERSION`] |
//! | 38    | the model's GUID (a state from another interface is refused) |
//! | 8     | payload length n |
//! | n     | payload: the fields of [`Core`] in the order of [`visit_core`]; a real is its 8 IEEE-754 bytes, a count 8 bytes, a flag one byte 0 or 1 |
//! | 8     | FNV-1a 64 checksum of everything before it |
//!
//! The field list is written once, in [`visit_core`], which both the writer and the reader
//! run: they cannot disagree. The reader checks the frame, then every field: finite reals,
//! parameters in their ranges (the same checks as fmi2SetReal), integrator order, steps and
//! history (`Bdf::check_state`). Malformed bytes give an error, never a panic.
#![forbid(unsafe_code)]

use super::binding::Values;
use super::core::{Core, State};
use super::variables::guid;
use crate::settings::{Value, SETTINGS};
use crate::solver::{check_rtol, StateVisitor};

const MAGIC: &[u8; 8] = b"BBFMUST\0";
/// Version of the byte format; bump it when [`visit_core`] changes.
pub const VERSION: u32 = 4;
const GUID_LEN: usize = 38;
const HEADER: usize = 8 + 4 + GUID_LEN + 8;

use crate::hash::fnv1a_64;

/// Serializes a snapshot.
pub(super) fn serialize(core: &Core) -> Vec<u8> {
    let mut writer = Writer(Vec::with_capacity(1024));
    let mut copy = core.clone();
    visit_core(&mut copy, &mut writer).expect("a valid snapshot writes without error");
    let payload = writer.0;
    let mut out = Vec::with_capacity(HEADER + payload.len() + 8);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(guid().as_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&payload);
    let sum = fnv1a_64(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    out
}

/// Reads a snapshot from untrusted bytes.
pub(super) fn deserialize(bytes: &[u8]) -> Result<Core, String> {
    if bytes.len() < HEADER + 8 {
        return Err(format!(
            "{} bytes is too short for an FMU state (at least {})",
            bytes.len(),
            HEADER + 8
        ));
    }
    if &bytes[..8] != MAGIC {
        return Err("not a BeamBody FMU state (bad magic bytes)".into());
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != VERSION {
        return Err(format!("state format version {version} is not supported: must be {VERSION}"));
    }
    if &bytes[12..12 + GUID_LEN] != guid().as_bytes() {
        return Err("the state was saved by a different model interface (GUID differs)".into());
    }
    let n = u64::from_le_bytes(bytes[12 + GUID_LEN..HEADER].try_into().expect("8 bytes"));
    let expected = (bytes.len() - HEADER - 8) as u64;
    if n != expected {
        return Err(format!("payload length {n} does not match the {expected} bytes present"));
    }
    let (body, sum) = bytes.split_at(bytes.len() - 8);
    if fnv1a_64(body) != u64::from_le_bytes(sum.try_into().expect("8 bytes")) {
        return Err("checksum mismatch: the state bytes are corrupt".into());
    }
    let mut reader = Reader { bytes: &body[HEADER..], pos: 0, error: None };
    let mut core = Core::new();
    let visited = visit_core(&mut core, &mut reader);
    if let Some(e) = reader.error {
        return Err(e);
    }
    visited?;
    if reader.pos != reader.bytes.len() {
        return Err(format!(
            "{} unread bytes after the last field",
            reader.bytes.len() - reader.pos
        ));
    }
    Ok(core)
}

/// An optional real as a flag and a value, the value 0 when the flag is clear. A reader
/// refuses a clear flag with any other value: every snapshot then has exactly one byte form,
/// and accepted bytes serialize back unchanged (found by fuzzing: a `tolerance` left in
/// beside `tolerance_defined` = 0 was dropped on the way).
fn visit_optional(
    v: &mut impl StateVisitor,
    flag: &'static str,
    name: &'static str,
    slot: &mut Option<f64>,
) -> Result<(), String> {
    let mut set = slot.is_some();
    let mut x = slot.unwrap_or(0.0);
    v.flag(flag, &mut set);
    v.real(name, &mut x);
    if !set && x.to_bits() != 0 {
        return Err(format!("field `{name}` = {x:?} although `{flag}` is 0: must be 0"));
    }
    *slot = set.then_some(x);
    Ok(())
}

/// Visits every field of a snapshot; the writer reads them, the reader overwrites and
/// checks them. Fields that index something are converted, and checked, on the way.
pub(super) fn visit_core(core: &mut Core, v: &mut impl StateVisitor) -> Result<(), String> {
    let mut state = core.state.to_index();
    v.count("state", &mut state);
    core.state = State::from_index(state)
        .filter(|s| *s != State::Fatal)
        .ok_or_else(|| format!("field `state` = {state} is not a state an FMU state can hold"))?;
    visit_values(&mut core.values, v)?;

    let s = &mut core.setup;
    visit_optional(v, "tolerance_defined", "tolerance", &mut s.tolerance)?;
    v.real("start_time", &mut s.start_time);
    visit_optional(v, "stop_time_defined", "stop_time", &mut s.stop_time)?;
    v.real("time", &mut core.time);
    v.real("last_successful_time", &mut core.last_successful_time);
    v.flag("terminated", &mut core.terminated);
    for (k, slot) in core.pending.iter_mut().enumerate() {
        let names = [("pending_dphi_set", "pending_dphi"), ("pending_ddphi_set", "pending_ddphi")];
        visit_optional(v, names[k].0, names[k].1, slot)?;
    }
    check_head(core)?;

    let mut has_run = core.run.is_some();
    v.flag("run", &mut has_run);
    let needs_run =
        matches!(core.state, State::StepComplete | State::StepFailed | State::Terminated);
    let may_run = needs_run || core.state == State::Error;
    if has_run != needs_run && !(has_run && may_run) {
        return Err(format!("field `run` = {has_run} contradicts the state `{:?}`", core.state));
    }
    if !has_run {
        core.run = None;
        return Ok(());
    }
    if core.run.is_none() {
        core.run = Some(core.build_run().map_err(|e| format!("the saved parameters: {e}"))?);
    }
    let run = core.run.as_mut().expect("built above");
    run.visit_state(v);
    run.check_state()?;
    // After every step, successful or not, the communication time, the last successful
    // time and the integrator's time agree (up to the rounding of tc + h).
    let fuzz = 64.0 * f64::EPSILON * core.time.abs().max(1.0);
    for (name, t) in
        [("integrator time", run.t()), ("last_successful_time", core.last_successful_time)]
    {
        if (t - core.time).abs() > fuzz {
            return Err(format!("field `{name}` = {t} does not match `time` = {}", core.time));
        }
    }
    Ok(())
}

/// The FMU's parameters, in the order of the settings table, and the input; checked with the
/// same rules as fmi2Set*.
fn visit_values(values: &mut Values, v: &mut impl StateVisitor) -> Result<(), String> {
    for setting in SETTINGS.iter().filter(|s| s.appears.fmu) {
        let mut value = values.settings.get(setting.key);
        match &mut value {
            Value::Real(x) => v.real(setting.name, x),
            Value::Integer(k) => {
                let mut c = *k as u64;
                v.count(setting.name, &mut c);
                *k = i64::try_from(c).unwrap_or(-1);
            }
            Value::Choice(k) => {
                let mut c = *k as u64;
                v.count(setting.name, &mut c);
                *k = usize::try_from(c).unwrap_or(usize::MAX);
            }
            Value::Bool(b) => v.flag(setting.name, b),
        }
        values.settings.set(setting.key, value).map_err(|e| format!("field {e}"))?;
    }
    v.real("phi", &mut values.phi);
    values.set_phi(values.phi).map_err(|e| format!("field {e}"))
}

fn check_head(core: &Core) -> Result<(), String> {
    let s = &core.setup;
    if let Some(tol) = s.tolerance {
        if let Err(allowed) = check_rtol(tol) {
            return Err(format!("field `tolerance` = {tol:?} is out of range: must be {allowed}"));
        }
    }
    if !s.start_time.is_finite() {
        return Err(format!("field `start_time` = {} is not finite", s.start_time));
    }
    if let Some(stop) = s.stop_time {
        if !(stop.is_finite() && stop >= s.start_time) {
            return Err(format!(
                "field `stop_time` = {stop} is out of range: must be >= start_time"
            ));
        }
    }
    for (name, t) in [("time", core.time), ("last_successful_time", core.last_successful_time)] {
        if !(t.is_finite() && t >= s.start_time) {
            return Err(format!(
                "field `{name}` = {t} is out of range: must be finite and >= start_time"
            ));
        }
    }
    if core.pending.iter().flatten().any(|x| !x.is_finite()) {
        return Err("field `pending` holds a non-finite derivative".into());
    }
    Ok(())
}

struct Writer(Vec<u8>);

impl StateVisitor for Writer {
    fn real(&mut self, _: &'static str, x: &mut f64) {
        self.0.extend_from_slice(&x.to_bits().to_le_bytes());
    }
    fn count(&mut self, _: &'static str, x: &mut u64) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn flag(&mut self, _: &'static str, x: &mut bool) {
        self.0.push(*x as u8);
    }
}

/// Where each field of `core`'s serialized bytes starts, in the order written: (name, offset
/// from the first byte of the state). The writer's own encoding gives the offsets.
#[cfg(test)]
pub(super) fn field_offsets(core: &Core) -> Vec<(&'static str, usize)> {
    struct Offsets(Writer, Vec<(&'static str, usize)>);
    impl StateVisitor for Offsets {
        fn real(&mut self, name: &'static str, x: &mut f64) {
            self.1.push((name, HEADER + self.0 .0.len()));
            self.0.real(name, x);
        }
        fn count(&mut self, name: &'static str, x: &mut u64) {
            self.1.push((name, HEADER + self.0 .0.len()));
            self.0.count(name, x);
        }
        fn flag(&mut self, name: &'static str, x: &mut bool) {
            self.1.push((name, HEADER + self.0 .0.len()));
            self.0.flag(name, x);
        }
    }
    let mut offsets = Offsets(Writer(Vec::new()), Vec::new());
    visit_core(&mut core.clone(), &mut offsets).expect("a valid snapshot writes without error");
    offsets.1
}

/// Reads fields in order; the first short read or bad flag is kept in `error`, and every
/// later read yields zero, so the visit completes and the caller reports the error.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    error: Option<String>,
}

impl Reader<'_> {
    fn take<const K: usize>(&mut self, name: &str) -> [u8; K] {
        if self.error.is_none() {
            if let Some(chunk) = self.bytes.get(self.pos..self.pos + K) {
                self.pos += K;
                return chunk.try_into().expect("K bytes");
            }
            self.error = Some(format!("the state ends before field `{name}`"));
        }
        [0; K]
    }
}

impl StateVisitor for Reader<'_> {
    fn real(&mut self, name: &'static str, x: &mut f64) {
        *x = f64::from_bits(u64::from_le_bytes(self.take(name)));
    }
    fn count(&mut self, name: &'static str, x: &mut u64) {
        *x = u64::from_le_bytes(self.take(name));
    }
    fn flag(&mut self, name: &'static str, x: &mut bool) {
        let [b] = self.take::<1>(name);
        if b > 1 && self.error.is_none() {
            self.error = Some(format!("field `{name}` = {b} is not a flag (0 or 1)"));
        }
        *x = b == 1;
    }
    fn discarded(&mut self, name: &'static str, as_written: bool) {
        if !as_written && self.error.is_none() {
            self.error =
                Some(format!("the fields of an absent `{name}` must be as written (zeros)"));
        }
    }
}
