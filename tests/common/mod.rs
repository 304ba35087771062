//! A minimal FMI 2.0 host for the integration tests: it calls the exported `fmi2…`
//! functions exactly as a C host would, with a logger that records every message into a
//! collector reached through `componentEnvironment`.
#![allow(dead_code)] // not every test binary uses every helper

use beam_body::fmi2::exports::*;
use beam_body::fmi2::types::*;
use beam_body::fmu::variables::{guid, Var, LOG_CATEGORIES};
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::ptr::{null, null_mut};
use std::sync::{Mutex, RwLock, RwLockReadGuard, RwLockWriteGuard};

// The C constants under short names (the library's, src/fmi2/types.rs).
pub use beam_body::fmi2::types::{
    fmi2CoSimulation as CO_SIMULATION, fmi2Discard as DISCARD, fmi2DoStepStatus as DO_STEP_STATUS,
    fmi2Error as ERROR, fmi2Fatal as FATAL, fmi2LastSuccessfulTime as LAST_SUCCESSFUL_TIME,
    fmi2ModelExchange as MODEL_EXCHANGE, fmi2OK as OK, fmi2PendingStatus as PENDING_STATUS,
    fmi2Terminated as TERMINATED, fmi2Warning as WARNING,
};

/// The value reference of `var`.
pub fn vr(var: Var) -> fmi2ValueReference {
    var.vr()
}

// ----- isolation of tests that use freed pointers ----------------------------------------------

/// `cargo test` runs the tests of a binary on threads of one process. A test that calls a
/// function on a *freed* instance or FMU state relies on the address not having been handed
/// out again meanwhile; another test's fmi2Instantiate could reuse it. Such tests take the
/// write lock, every other test the read lock. (nextest runs each test in its own process.)
static ADDRESSES: RwLock<()> = RwLock::new(());

pub fn shared() -> RwLockReadGuard<'static, ()> {
    ADDRESSES.read().unwrap_or_else(|e| e.into_inner())
}

pub fn exclusive() -> RwLockWriteGuard<'static, ()> {
    ADDRESSES.write().unwrap_or_else(|e| e.into_inner())
}

// ----- the logger --------------------------------------------------------------------------------

/// One call of the logger.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// The `componentEnvironment` the FMU passed back.
    pub env: usize,
    pub name: String,
    pub status: fmi2Status,
    pub category: String,
    /// The format string: must be exactly "%s".
    pub fmt: String,
    pub message: String,
}

/// Where the logger puts the records of one instance; `componentEnvironment` points to it.
#[derive(Debug, Default)]
pub struct Collector {
    records: Mutex<Vec<Record>>,
}

impl Collector {
    pub fn env(&self) -> fmi2ComponentEnvironment {
        self as *const Collector as fmi2ComponentEnvironment
    }

    /// Every record so far, after checking that each used the format "%s" and came with
    /// this collector's environment pointer.
    pub fn records(&self) -> Vec<Record> {
        let records = self.records.lock().unwrap_or_else(|e| e.into_inner()).clone();
        for r in &records {
            assert_eq!(
                r.fmt, "%s",
                "the FMU must pass its message as the argument of \"%s\": {r:?}"
            );
            assert_eq!(r.env, self.env() as usize, "wrong componentEnvironment: {r:?}");
        }
        records
    }

    /// The records so far, which are then forgotten.
    pub fn take(&self) -> Vec<Record> {
        let records = self.records();
        self.records.lock().unwrap_or_else(|e| e.into_inner()).clear();
        records
    }
}

fn lossy(p: *const c_char) -> String {
    if p.is_null() {
        "<NULL>".to_string()
    } else {
        // SAFETY: the FMU passes NUL-terminated strings that live for the call.
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }
}

/// The host's logger, written with a sixth *fixed* pointer parameter `arg` instead of the
/// C variadic `...`: stable Rust cannot define a variadic function.
///
/// This is sound on the x86_64 System V ABI (this machine, linux64): variadic arguments are
/// passed exactly like fixed ones, so the first variadic pointer argument travels in the
/// sixth integer-argument register (%r9), which is where a sixth fixed pointer parameter is
/// read from. (The caller also sets %al to the number of vector registers used; a
/// non-variadic callee ignores it.) The same holds for Windows x64 and for AArch64 Linux,
/// but not for AArch64 Apple, where variadic arguments go on the stack. The FMU always
/// calls `logger(env, name, status, category, "%s", message)`, so there is exactly one
/// variadic argument, a `const char*`; `fmt` is recorded and checked to be "%s".
unsafe extern "C" fn test_logger(
    env: *mut c_void,
    name: *const c_char,
    status: c_int,
    category: *const c_char,
    fmt: *const c_char,
    arg: *const c_char,
) {
    if env.is_null() {
        return; // a test passed no collector; nothing to record into
    }
    // SAFETY: every environment our tests pass is a live `Collector`.
    let collector = unsafe { &*(env as *const Collector) };
    let record = Record {
        env: env as usize,
        name: lossy(name),
        status,
        category: lossy(category),
        fmt: lossy(fmt),
        // Only read the argument as a string when the format says it is one.
        message: if lossy(fmt) == "%s" { lossy(arg) } else { String::new() },
    };
    collector.records.lock().unwrap_or_else(|e| e.into_inner()).push(record);
}

#[cfg(all(target_arch = "aarch64", target_vendor = "apple"))]
compile_error!("test_logger relies on variadic arguments travelling like fixed ones");

/// [`test_logger`] as the variadic `fmi2CallbackLogger`.
pub fn logger() -> fmi2CallbackLogger {
    type Fixed = unsafe extern "C" fn(
        *mut c_void,
        *const c_char,
        c_int,
        *const c_char,
        *const c_char,
        *const c_char,
    );
    // SAFETY: same size (function pointers); the call is ABI-compatible, see test_logger.
    unsafe { std::mem::transmute::<Fixed, fmi2CallbackLogger>(test_logger as Fixed) }
}

/// The callbacks, with the given environment.
pub fn callbacks(env: fmi2ComponentEnvironment) -> Box<fmi2CallbackFunctions> {
    Box::new(fmi2CallbackFunctions {
        logger: Some(logger()),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: env,
    })
}

// ----- one instance ------------------------------------------------------------------------------

/// One instance with its collector and callbacks, freed on drop.
pub struct Host {
    pub c: fmi2Component,
    pub name: String,
    // Dropped after the instance (Drop::drop runs before the fields are dropped).
    pub log: Box<Collector>,
    pub callbacks: Box<fmi2CallbackFunctions>,
}

impl Drop for Host {
    fn drop(&mut self) {
        // SAFETY: `c` is NULL or an instance of this host (FreeInstance ignores NULL).
        unsafe { fmi2FreeInstance(self.c) };
        self.c = null_mut();
        if !std::thread::panicking() {
            self.log.records();
        }
    }
}

pub fn guid_c() -> CString {
    CString::new(guid()).unwrap()
}

impl Host {
    /// An instance that takes phi from the host (`phi_source` = input, the start value), with
    /// phi set to 0 before the run, as most tests drive it.
    pub fn new(name: &str) -> Host {
        let h = Host::with_logging(name, false);
        assert_eq!(h.set_real(Var::Phi, 0.0), OK);
        h.log.take();
        h
    }

    pub fn with_logging(name: &str, logging_on: bool) -> Host {
        Host::of_type(name, logging_on, CO_SIMULATION)
    }

    /// A Model Exchange instance, as [`Host::new`] makes a co-simulation one.
    pub fn exchange(name: &str) -> Host {
        let h = Host::of_type(name, false, MODEL_EXCHANGE);
        assert_eq!(h.set_real(Var::Phi, 0.0), OK);
        h.log.take();
        h
    }

    /// An instance of `fmu_type` (fmi2CoSimulation or fmi2ModelExchange).
    pub fn of_type(name: &str, logging_on: bool, fmu_type: fmi2Type) -> Host {
        let log = Box::<Collector>::default();
        let callbacks = callbacks(log.env());
        let cname = CString::new(name).unwrap();
        let g = guid_c();
        // SAFETY: valid strings; `callbacks` and `log` live as long as the instance.
        let c = unsafe {
            fmi2Instantiate(
                cname.as_ptr(),
                fmu_type,
                g.as_ptr(),
                null(),
                &*callbacks,
                fmi2False,
                logging_on as fmi2Boolean,
            )
        };
        assert!(!c.is_null(), "fmi2Instantiate failed: {:?}", log.records());
        Host { c, name: name.to_string(), log, callbacks }
    }

    /// An instance as instantiated, with the table's start values and nothing set.
    pub fn plain(name: &str) -> Host {
        Host::with_logging(name, false)
    }

    /// The records since the last call, each checked for format, environment and name.
    pub fn take(&self) -> Vec<Record> {
        let records = self.log.take();
        for r in &records {
            assert_eq!(r.name, self.name, "logged with the wrong instance name: {r:?}");
            assert!(
                LOG_CATEGORIES.iter().any(|(c, _)| *c == r.category),
                "undeclared log category: {r:?}"
            );
        }
        records
    }

    /// Asserts `status` is fmi2Error and that an error was logged whose message contains
    /// every needle; forgets the records.
    #[track_caller]
    pub fn expect_error(&self, status: fmi2Status, needles: &[&str]) -> Record {
        self.expect_status(status, ERROR, needles)
    }

    #[track_caller]
    pub fn expect_status(&self, status: fmi2Status, want: fmi2Status, needles: &[&str]) -> Record {
        let records = self.take();
        assert_eq!(status, want, "status; log: {records:#?}");
        let category = match want {
            WARNING => "logStatusWarning",
            DISCARD => "logStatusDiscard",
            ERROR => "logStatusError",
            FATAL => "logStatusFatal",
            _ => "logCalls",
        };
        let found = records.iter().find(|r| {
            r.status == want
                && r.category == category
                && needles.iter().all(|n| r.message.contains(n))
        });
        match found {
            Some(r) => r.clone(),
            None => panic!("no {category} message containing {needles:?}; log: {records:#?}"),
        }
    }

    /// Asserts `status` is fmi2OK and nothing but trace messages were logged.
    #[track_caller]
    pub fn expect_ok(&self, status: fmi2Status) {
        let records = self.take();
        assert_eq!(status, OK, "status; log: {records:#?}");
        assert!(records.iter().all(|r| r.status == OK), "unexpected messages: {records:#?}");
    }

    // ----- thin wrappers: each returns the status ------------------------------------------

    pub fn setup(&self, tol: Option<f64>, start: f64, stop: Option<f64>) -> fmi2Status {
        unsafe {
            fmi2SetupExperiment(
                self.c,
                tol.is_some() as fmi2Boolean,
                tol.unwrap_or(0.0),
                start,
                stop.is_some() as fmi2Boolean,
                stop.unwrap_or(0.0),
            )
        }
    }

    pub fn enter(&self) -> fmi2Status {
        unsafe { fmi2EnterInitializationMode(self.c) }
    }

    pub fn exit(&self) -> fmi2Status {
        unsafe { fmi2ExitInitializationMode(self.c) }
    }

    pub fn terminate(&self) -> fmi2Status {
        unsafe { fmi2Terminate(self.c) }
    }

    pub fn reset(&self) -> fmi2Status {
        unsafe { fmi2Reset(self.c) }
    }

    pub fn step(&self, tc: f64, h: f64) -> fmi2Status {
        unsafe { fmi2DoStep(self.c, tc, h, fmi2False) }
    }

    pub fn set_reals(&self, vrs: &[fmi2ValueReference], values: &[f64]) -> fmi2Status {
        assert_eq!(vrs.len(), values.len());
        unsafe { fmi2SetReal(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }

    pub fn set_real(&self, var: Var, x: f64) -> fmi2Status {
        self.set_reals(&[vr(var)], &[x])
    }

    pub fn get_reals(&self, vrs: &[fmi2ValueReference]) -> (fmi2Status, Vec<f64>) {
        let mut out = vec![f64::NAN; vrs.len()];
        let s = unsafe { fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
        (s, out)
    }

    /// The value of a real variable; asserts fmi2OK.
    #[track_caller]
    pub fn real(&self, var: Var) -> f64 {
        let (s, out) = self.get_reals(&[vr(var)]);
        assert_eq!(s, OK, "fmi2GetReal({var:?}): {:#?}", self.take());
        out[0]
    }

    pub fn set_integer(&self, var: Var, k: i32) -> fmi2Status {
        let vrs = [vr(var)];
        unsafe { fmi2SetInteger(self.c, vrs.as_ptr(), 1, [k].as_ptr()) }
    }

    pub fn get_integers(&self, vrs: &[fmi2ValueReference]) -> (fmi2Status, Vec<i32>) {
        let mut out = vec![i32::MIN; vrs.len()];
        let s = unsafe { fmi2GetInteger(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
        (s, out)
    }

    pub fn set_boolean(&self, var: Var, b: bool) -> fmi2Status {
        let vrs = [vr(var)];
        unsafe { fmi2SetBoolean(self.c, vrs.as_ptr(), 1, [b as fmi2Boolean].as_ptr()) }
    }

    pub fn get_booleans(&self, vrs: &[fmi2ValueReference]) -> (fmi2Status, Vec<fmi2Boolean>) {
        let mut out = vec![-1; vrs.len()];
        let s = unsafe { fmi2GetBoolean(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
        (s, out)
    }

    pub fn set_derivative(&self, var: Var, order: i32, x: f64) -> fmi2Status {
        let vrs = [vr(var)];
        unsafe {
            fmi2SetRealInputDerivatives(self.c, vrs.as_ptr(), 1, [order].as_ptr(), [x].as_ptr())
        }
    }

    pub fn real_status(&self, kind: fmi2StatusKind) -> (fmi2Status, f64) {
        let mut x = f64::NAN;
        let s = unsafe { fmi2GetRealStatus(self.c, kind, &mut x) };
        (s, x)
    }

    pub fn boolean_status(&self, kind: fmi2StatusKind) -> (fmi2Status, fmi2Boolean) {
        let mut b = -1;
        let s = unsafe { fmi2GetBooleanStatus(self.c, kind, &mut b) };
        (s, b)
    }

    pub fn debug_logging(&self, on: bool, categories: &[&CStr]) -> fmi2Status {
        let ptrs: Vec<fmi2String> = categories.iter().map(|c| c.as_ptr()).collect();
        unsafe {
            fmi2SetDebugLogging(
                self.c,
                on as fmi2Boolean,
                ptrs.len(),
                if ptrs.is_empty() { null() } else { ptrs.as_ptr() },
            )
        }
    }

    pub fn get_state(&self, state: &mut fmi2FMUstate) -> fmi2Status {
        unsafe { fmi2GetFMUstate(self.c, state) }
    }

    pub fn set_state(&self, state: fmi2FMUstate) -> fmi2Status {
        unsafe { fmi2SetFMUstate(self.c, state) }
    }

    pub fn free_state(&self, state: &mut fmi2FMUstate) -> fmi2Status {
        unsafe { fmi2FreeFMUstate(self.c, state) }
    }

    /// Serializes `state`; asserts fmi2OK.
    #[track_caller]
    pub fn serialize(&self, state: fmi2FMUstate) -> Vec<u8> {
        let mut size = 0usize;
        assert_eq!(unsafe { fmi2SerializedFMUstateSize(self.c, state, &mut size) }, OK);
        let mut bytes = vec![0u8; size];
        let s = unsafe {
            fmi2SerializeFMUstate(self.c, state, bytes.as_mut_ptr() as *mut fmi2Byte, size)
        };
        assert_eq!(s, OK, "{:#?}", self.take());
        bytes
    }

    pub fn deserialize(&self, bytes: &[u8], state: &mut fmi2FMUstate) -> fmi2Status {
        unsafe {
            fmi2DeSerializeFMUstate(self.c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), state)
        }
    }

    // ----- composite steps ---------------------------------------------------------------

    /// Setup (tolerance 1e-6, start 0, no stop time), enter and exit initialization mode;
    /// asserts fmi2OK throughout.
    #[track_caller]
    pub fn initialize(&self) {
        self.expect_ok(self.setup(Some(1e-6), 0.0, None));
        self.expect_ok(self.enter());
        self.expect_ok(self.exit());
    }

    /// A law-driven instance in stepComplete at t = 0.
    #[track_caller]
    pub fn law(name: &str) -> Host {
        let h = Host::new(name);
        h.expect_ok(h.set_integer(Var::PhiSource, 2));
        h.initialize();
        h
    }

    /// Steps `n` times by `h` from `t`; asserts fmi2OK; returns the new time.
    #[track_caller]
    pub fn steps(&self, t: f64, h: f64, n: usize) -> f64 {
        let mut t = t;
        for _ in 0..n {
            let s = self.step(t, h);
            assert_eq!(s, OK, "DoStep({t}, {h}): {:#?}", self.take());
            t += h;
        }
        t
    }

    /// Every output, in value-reference order.
    #[track_caller]
    pub fn outputs(&self) -> Vec<f64> {
        let (s, y) = self.get_reals(&OUTPUTS.map(vr));
        assert_eq!(s, OK, "{:#?}", self.take());
        y
    }
}

pub const OUTPUTS: [Var; 14] = [
    Var::V1,
    Var::Theta1,
    Var::U2,
    Var::Dv1,
    Var::Dtheta1,
    Var::Du2,
    Var::N,
    Var::P,
    Var::Moment,
    Var::Drift,
    Var::Energy,
    Var::PhiApplied,
    Var::DphiApplied,
    Var::DdphiApplied,
];

/// Bit patterns, for bit-for-bit comparison (NaN-safe, distinguishes ±0).
pub fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}
