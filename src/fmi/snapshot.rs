//! Everything an FMU state holds ([`Snapshot`]), and its byte format: a frame written here
//! around the core's fields and the model's, read back from untrusted bytes.
//!
//! Layout (all integers little-endian):
//!
//! | bytes | content |
//! |-------|---------|
//! | 8     | magic `FMUSTATE` |
//! | 4     | format version: the core's [`CORE_VERSION`] times 1000 plus the model's |
//! | 38    | the model's GUID (a state from another interface is refused) |
//! | 8     | payload length n |
//! | n     | payload: the core's fields ([`visit_core`]), then the model's ([`Model::visit_state`]); a real is its 8 IEEE-754 bytes, a count 8 bytes, a flag one byte 0 or 1 |
//! | 8     | FNV-1a 64 checksum of everything before it |
//!
//! One walk serves the writer and the reader, so they cannot disagree. The reader checks the
//! frame, then every field, with the same rules as the calls that set them. Malformed bytes
//! give an error, never a panic.
#![forbid(unsafe_code)]

use super::description::Version;
use super::machine::{Interface, State};
use super::model::{Model, Restore, Setup};
use crate::hash::fnv1a_64;
use crate::math::same_time;
use crate::visit::StateVisitor;

/// Everything an FMU state holds: the whole instance except its name and logger.
#[derive(Clone, Debug)]
pub struct Snapshot<M> {
    /// The interface of the instance that made it: a state restores only into its own.
    pub(crate) interface: Interface,
    /// The model description of the instance that made it: a state restores only into an
    /// instance of the same version (their variables and states differ).
    pub(crate) version: Version,
    pub(crate) state: State,
    pub(crate) setup: Setup,
    /// The communication time: the start time, then the end of the last step (co-simulation),
    /// or the time the host set last (Model Exchange).
    pub(crate) time: f64,
    pub(crate) last_successful_time: f64,
    /// fmi2Terminated: the FMU stopped the run.
    pub(crate) terminated: bool,
    pub(crate) model: M,
}

impl<M> Snapshot<M> {
    /// The interface of the instance that made it.
    pub fn interface(&self) -> Interface {
        self.interface
    }

    /// The state of the instance it holds.
    pub fn state(&self) -> State {
        self.state
    }

    /// The FMI version of the instance that made it: it restores only into that version's.
    pub fn version(&self) -> Version {
        self.version
    }
}

impl<M: Model> Snapshot<M> {
    pub(crate) fn new(interface: Interface, version: Version) -> Snapshot<M> {
        Snapshot {
            interface,
            version,
            state: State::Instantiated,
            setup: Setup::NONE,
            time: 0.0,
            last_successful_time: 0.0,
            terminated: false,
            model: M::new(version),
        }
    }
}

const MAGIC: &[u8; 8] = b"FMUSTATE";
/// Version of the core's part of the byte format; bump it when [`visit_core`] changes.
pub const CORE_VERSION: u32 = 7;
const GUID_LEN: usize = 38;
/// Bytes of the frame before the payload: magic, version, GUID, payload length.
pub const HEADER: usize = 8 + 4 + GUID_LEN + 8;

/// The format version of `M`'s states.
pub fn version<M: Model>() -> u32 {
    CORE_VERSION * 1000 + M::STATE_VERSION
}

/// Serializes a snapshot. The one walk that writes also checks what it writes with the
/// reader's rules, so a snapshot that no reader would accept is an error here, not bytes.
pub fn serialize<M: Model>(snapshot: &Snapshot<M>) -> Result<Vec<u8>, String> {
    let mut writer = Writer(Vec::with_capacity(1024));
    let mut copy = snapshot.clone();
    visit(&mut copy, &mut writer)?;
    let payload = writer.0;
    let mut out = Vec::with_capacity(HEADER + payload.len() + 8);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&version::<M>().to_le_bytes());
    out.extend_from_slice(M::guid().as_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&payload);
    let sum = fnv1a_64(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    Ok(out)
}

/// Makes the frame of `bytes` consistent again after an edit of the payload: its length and
/// the checksum. Tests and the fuzzer edit fields with it, so that their bytes reach the
/// field checks behind the frame's.
pub fn reseal(bytes: &mut [u8]) {
    if bytes.len() < HEADER + 8 {
        return;
    }
    let payload = (bytes.len() - HEADER - 8) as u64;
    bytes[HEADER - 8..HEADER].copy_from_slice(&payload.to_le_bytes());
    reseal_checksum(bytes);
}

/// Rewrites the checksum of `bytes` alone (a test of the frame's other checks).
pub fn reseal_checksum(bytes: &mut [u8]) {
    if let Some(n) = bytes.len().checked_sub(8) {
        let sum = fnv1a_64(&bytes[..n]);
        bytes[n..].copy_from_slice(&sum.to_le_bytes());
    }
}

/// Reads a snapshot from untrusted bytes.
pub fn deserialize<M: Model>(bytes: &[u8]) -> Result<Snapshot<M>, String> {
    if bytes.len() < HEADER + 8 {
        return Err(format!(
            "{} bytes is too short for an FMU state (at least {})",
            bytes.len(),
            HEADER + 8
        ));
    }
    if &bytes[..8] != MAGIC {
        return Err("not an FMU state of this library (bad magic bytes)".into());
    }
    let found = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    let ours = version::<M>();
    if found != ours {
        return Err(format!("state format version {found} is not supported: must be {ours}"));
    }
    if &bytes[12..12 + GUID_LEN] != M::guid().as_bytes() {
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
    let mut snapshot = Snapshot::new(Interface::CoSimulation, Version::Fmi2);
    let visited = visit(&mut snapshot, &mut reader);
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
    Ok(snapshot)
}

/// Visits the core's fields, then the model's.
fn visit<M: Model>(s: &mut Snapshot<M>, v: &mut impl StateVisitor) -> Result<(), String> {
    visit_core(s, v)?;
    // The experiment's tolerance, by the rule of SetupExperiment.
    if let Some(tol) = s.setup.tolerance {
        M::check_tolerance(tol).map_err(|allowed| {
            format!("field `tolerance` = {tol:?} is out of range: must be {allowed}")
        })?;
    }
    let at = Restore {
        interface: s.interface,
        version: s.version,
        setup: s.setup,
        state: s.state,
        time: s.time,
    };
    s.model.visit_state(v, &at)
}

/// An optional real as a flag and a value, the value 0 when the flag is clear. A reader
/// refuses a clear flag with any other value: every snapshot then has exactly one byte form,
/// and accepted bytes serialize back unchanged (found by fuzzing: a `tolerance` left in
/// beside `tolerance_defined` = 0 was dropped on the way).
pub fn visit_optional(
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

/// Visits the core's fields; the writer reads them, the reader overwrites and checks them.
fn visit_core<M>(s: &mut Snapshot<M>, v: &mut impl StateVisitor) -> Result<(), String> {
    let mut interface = s.interface.to_index();
    v.count("interface", &mut interface);
    s.interface = Interface::from_index(interface).ok_or_else(|| {
        format!("field `interface` = {interface} is not an interface: must be 0 or 1")
    })?;
    let mut version = s.version as u64;
    v.count("version", &mut version);
    s.version = match version {
        0 => Version::Fmi2,
        1 => Version::Fmi3,
        _ => {
            return Err(format!(
            "field `version` = {version} is not an FMI version: must be 0 (FMI 2.0) or 1 (FMI 3.0)"
        ))
        }
    };
    let mut state = s.state.to_index();
    v.count("state", &mut state);
    let mut all = s.interface.masks().fmu_state;
    if s.version == Version::Fmi2 {
        // FMI 2.0 has no configuration mode.
        all &= !super::machine::mask::CONFIGURATION;
    }
    s.state = State::from_index(state).filter(|st| st.bit() & all != 0).ok_or_else(|| {
        format!(
            "field `state` = {state} is not a state a {} FMU state can hold",
            s.interface.name()
        )
    })?;
    let setup = &mut s.setup;
    visit_optional(v, "tolerance_defined", "tolerance", &mut setup.tolerance)?;
    v.real("start_time", &mut setup.start_time);
    visit_optional(v, "stop_time_defined", "stop_time", &mut setup.stop_time)?;
    v.real("time", &mut s.time);
    v.real("last_successful_time", &mut s.last_successful_time);
    v.flag("terminated", &mut s.terminated);
    check_times(s)
}

/// The core's checks of the times, once read.
fn check_times<M>(s: &Snapshot<M>) -> Result<(), String> {
    let setup = &s.setup;
    if !setup.start_time.is_finite() {
        return Err(format!("field `start_time` = {} is not finite", setup.start_time));
    }
    if let Some(stop) = setup.stop_time {
        if !(stop.is_finite() && stop >= setup.start_time) {
            return Err(format!(
                "field `stop_time` = {stop} is out of range: must be >= start_time"
            ));
        }
    }
    for (name, t) in [("time", s.time), ("last_successful_time", s.last_successful_time)] {
        if !(t.is_finite() && t >= setup.start_time) {
            return Err(format!(
                "field `{name}` = {t} is out of range: must be finite and >= start_time"
            ));
        }
    }
    // After every step, successful or not, the communication time and the last successful
    // time agree (up to the rounding of tc + h).
    if !same_time(s.last_successful_time, s.time, 1.0) {
        return Err(format!(
            "field `last_successful_time` = {} does not match `time` = {}",
            s.last_successful_time, s.time
        ));
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

/// Where each field of a snapshot's serialized bytes starts, in the order written: (name,
/// offset from the first byte of the state). The writer's own encoding gives the offsets.
pub fn field_offsets<M: Model>(snapshot: &Snapshot<M>) -> Vec<(&'static str, usize)> {
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
    visit(&mut snapshot.clone(), &mut offsets).expect("a valid snapshot writes without error");
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
