//! The C API's edge: panics caught, freed and foreign pointers refused, the fatal state.
#![allow(unsafe_code)]

use super::exports::*;
use super::types::*;
use crate::capi::guard::guard;
use crate::capi::registry::{instance, snapshot, with_registry};

use crate::fmi::{Logger, State, Status};
use crate::fmu::variables::Var;
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::ptr::{null, null_mut};
use std::sync::{Arc, Mutex as StdMutex};

/// The tests of this module register instances and call functions on freed pointers;
/// they take this lock so that no other test of the module registers an instance at a
/// freed address meanwhile. (No other unit test registers instances.)
static REGISTERING: StdMutex<()> = StdMutex::new(());

fn registering() -> std::sync::MutexGuard<'static, ()> {
    REGISTERING.lock().unwrap_or_else(|e| e.into_inner())
}

/// A panic inside an exported body is caught: the call returns fmi2Fatal, the panic is
/// logged, the instance refuses everything after, and it can still be freed.
#[test]
fn a_panic_is_caught_logged_and_makes_the_instance_fatal() {
    let _g = registering();
    let log = Arc::new(StdMutex::new(Vec::<(Status, String)>::new()));
    let sink = log.clone();
    let logger: Logger = Box::new(move |s, _, m| sink.lock().unwrap().push((s, m.to_string())));
    let guid = crate::fmu::variables::guid();
    let inst = super::instantiate("panicky", 1, guid, logger, false).unwrap();
    let c = Box::into_raw(Box::new(inst)) as fmi2Component;
    with_registry(|r| r.instances.insert(c as usize));

    let status = guard(c, "fmi2Test", |_| panic!("boom"));
    assert_eq!(status, Status::Fatal as fmi2Status);
    // SAFETY: `c` is registered and not in use elsewhere.
    assert_eq!(unsafe { instance(c) }.unwrap().state(), State::Fatal);
    let last = log.lock().unwrap().last().cloned().unwrap();
    assert_eq!(last.0, Status::Fatal);
    assert!(last.1.contains("fmi2Test") && last.1.contains("boom"), "{}", last.1);

    // SAFETY: valid instance; the calls check their state first.
    unsafe {
        assert_eq!(fmi2Reset(c), Status::Error as fmi2Status);
        assert_eq!(fmi2DoStep(c, 0.0, 0.1, 0), Status::Error as fmi2Status);
        fmi2FreeInstance(c);
        assert_eq!(fmi2Reset(c), Status::Error as fmi2Status, "freed: refused");
    }
}

// ----- the fatal state, through the C API ----------------------------------------------

/// One call of the host's logger: (status, category, format, message).
type Record = (fmi2Status, String, String, String);
type Records = StdMutex<Vec<Record>>;

fn lossy(p: *const c_char) -> String {
    if p.is_null() {
        return "<NULL>".into();
    }
    // SAFETY: the FMU passes NUL-terminated strings that live for the call.
    unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
}

/// The host's logger with the variadic `...` written as one fixed pointer parameter, as
/// in tests/common/mod.rs: sound on x86_64 System V (and Windows x64, AArch64 Linux),
/// where the first variadic pointer travels like a sixth fixed one. `env` is a `Records`.
unsafe extern "C" fn record(
    env: *mut c_void,
    _name: *const c_char,
    status: c_int,
    category: *const c_char,
    fmt: *const c_char,
    arg: *const c_char,
) {
    // SAFETY: every environment of these tests is a live `Records`.
    let records = unsafe { &*(env as *const Records) };
    let fmt = lossy(fmt);
    let message = if fmt == "%s" { lossy(arg) } else { String::new() };
    records.lock().unwrap().push((status, lossy(category), fmt, message));
}

#[cfg(all(target_arch = "aarch64", target_vendor = "apple"))]
compile_error!("`record` relies on variadic arguments travelling like fixed ones");

fn callbacks(records: &Records) -> Box<fmi2CallbackFunctions> {
    type Fixed = unsafe extern "C" fn(
        *mut c_void,
        *const c_char,
        c_int,
        *const c_char,
        *const c_char,
        *const c_char,
    );
    // SAFETY: function pointers of the same size; ABI-compatible, see `record`.
    let logger = unsafe { std::mem::transmute::<Fixed, fmi2CallbackLogger>(record as Fixed) };
    Box::new(fmi2CallbackFunctions {
        logger: Some(logger),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: records as *const Records as fmi2ComponentEnvironment,
    })
}

fn instantiate(name: &CStr, functions: &fmi2CallbackFunctions) -> fmi2Component {
    let guid = CString::new(crate::fmu::variables::guid()).unwrap();
    // SAFETY: valid strings; `functions` outlives the instance in every test.
    let c = unsafe {
        fmi2Instantiate(name.as_ptr(), 1, guid.as_ptr(), null(), functions, fmi2False, fmi2True)
    };
    assert!(!c.is_null());
    c
}

const OK: fmi2Status = fmi2OK;
const ERROR: fmi2Status = fmi2Error;
const FATAL: fmi2Status = fmi2Fatal;

/// An instance in stepComplete at t = 0.01, with the built-in law.
///
/// # Safety
/// `c` is a live instance.
unsafe fn to_step_complete(c: fmi2Component) {
    // SAFETY: as this function's contract says.
    unsafe {
        let source = [Var::PhiSource.vr()];
        assert_eq!(fmi2SetInteger(c, source.as_ptr(), 1, [2].as_ptr()), OK);
        assert_eq!(fmi2SetupExperiment(c, fmi2True, 1e-6, 0.0, fmi2False, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2ExitInitializationMode(c), OK);
        assert_eq!(fmi2DoStep(c, 0.0, 0.01, fmi2False), OK);
    }
}

/// Each of the 40 functions that take an instance, called on `c` with arguments that are
/// valid in stepComplete or, for Model Exchange's, in its modes (so that only the state can
/// be the reason for a refusal), some in several variants. `snap` is a live FMU state and `bytes` its serialized form.
///
/// # Safety
/// `c` and `snap` are live.
unsafe fn instance_calls(
    c: fmi2Component,
    snap: fmi2FMUstate,
    bytes: &[u8],
) -> Vec<(&'static str, fmi2Status)> {
    // SAFETY: as this function's contract says.
    unsafe {
        let (rv, iv, bv) = ([Var::Phi.vr()], [Var::MaxOrder.vr()], [Var::StabilityGuard.vr()]);
        let (mut r, mut i, mut b) = ([0.5], [3], [fmi2True]);
        let mut string: [fmi2String; 1] = [null()];
        let cats = [c"logAll".as_ptr()];
        let mut fresh: fmi2FMUstate = null_mut();
        let mut existing = snap;
        let mut none: fmi2FMUstate = null_mut();
        let mut size = 0usize;
        let mut out = vec![0u8; bytes.len()];
        let (mut k, mut flag) = (-1, -1);
        let bp = bytes.as_ptr() as *const fmi2Byte;
        let op = out.as_mut_ptr() as *mut fmi2Byte;
        let outputs = [Var::V1.vr()];
        let mut info = fmi2EventInfo {
            newDiscreteStatesNeeded: -1,
            terminateSimulation: -1,
            nominalsOfContinuousStatesChanged: -1,
            valuesOfContinuousStatesChanged: -1,
            nextEventTimeDefined: -1,
            nextEventTime: -1.0,
        };
        let mut x = [0.5; 4];
        let calls = vec![
            ("fmi2SetDebugLogging", fmi2SetDebugLogging(c, fmi2True, 1, cats.as_ptr())),
            ("fmi2SetDebugLogging", fmi2SetDebugLogging(c, fmi2False, 0, null())),
            ("fmi2SetupExperiment", fmi2SetupExperiment(c, fmi2True, 1e-6, 0.0, fmi2False, 0.0)),
            ("fmi2EnterInitializationMode", fmi2EnterInitializationMode(c)),
            ("fmi2ExitInitializationMode", fmi2ExitInitializationMode(c)),
            ("fmi2Terminate", fmi2Terminate(c)),
            ("fmi2Reset", fmi2Reset(c)),
            ("fmi2GetReal", fmi2GetReal(c, rv.as_ptr(), 1, r.as_mut_ptr())),
            ("fmi2GetReal", fmi2GetReal(c, null(), 0, null_mut())),
            ("fmi2GetReal", fmi2GetReal(c, null(), 1, null_mut())),
            ("fmi2GetInteger", fmi2GetInteger(c, iv.as_ptr(), 1, i.as_mut_ptr())),
            ("fmi2GetBoolean", fmi2GetBoolean(c, bv.as_ptr(), 1, b.as_mut_ptr())),
            ("fmi2GetString", fmi2GetString(c, null(), 0, string.as_mut_ptr())),
            ("fmi2SetReal", fmi2SetReal(c, rv.as_ptr(), 1, [0.25].as_ptr())),
            ("fmi2SetReal", fmi2SetReal(c, rv.as_ptr(), 1, [f64::NAN].as_ptr())),
            ("fmi2SetInteger", fmi2SetInteger(c, iv.as_ptr(), 1, [3].as_ptr())),
            ("fmi2SetBoolean", fmi2SetBoolean(c, bv.as_ptr(), 1, [fmi2False].as_ptr())),
            ("fmi2SetString", fmi2SetString(c, null(), 0, null())),
            ("fmi2GetFMUstate", fmi2GetFMUstate(c, &mut fresh)),
            ("fmi2GetFMUstate", fmi2GetFMUstate(c, &mut existing)),
            ("fmi2SetFMUstate", fmi2SetFMUstate(c, snap)),
            ("fmi2FreeFMUstate", fmi2FreeFMUstate(c, &mut existing)),
            ("fmi2FreeFMUstate", fmi2FreeFMUstate(c, &mut none)),
            ("fmi2SerializedFMUstateSize", fmi2SerializedFMUstateSize(c, snap, &mut size)),
            ("fmi2SerializeFMUstate", fmi2SerializeFMUstate(c, snap, op, out.len())),
            ("fmi2DeSerializeFMUstate", fmi2DeSerializeFMUstate(c, bp, bytes.len(), &mut fresh)),
            ("fmi2DeSerializeFMUstate", fmi2DeSerializeFMUstate(c, bp, bytes.len(), &mut existing)),
            (
                "fmi2GetDirectionalDerivative",
                fmi2GetDirectionalDerivative(
                    c,
                    outputs.as_ptr(),
                    1,
                    rv.as_ptr(),
                    1,
                    [1.0].as_ptr(),
                    r.as_mut_ptr(),
                ),
            ),
            (
                "fmi2SetRealInputDerivatives",
                fmi2SetRealInputDerivatives(c, rv.as_ptr(), 1, [1].as_ptr(), [0.5].as_ptr()),
            ),
            (
                "fmi2GetRealOutputDerivatives",
                fmi2GetRealOutputDerivatives(c, outputs.as_ptr(), 1, [1].as_ptr(), r.as_mut_ptr()),
            ),
            ("fmi2DoStep", fmi2DoStep(c, 0.01, 0.01, fmi2False)),
            ("fmi2CancelStep", fmi2CancelStep(c)),
            ("fmi2GetStatus", fmi2GetStatus(c, 0, &mut k)),
            ("fmi2GetRealStatus", fmi2GetRealStatus(c, 2, r.as_mut_ptr())),
            ("fmi2GetIntegerStatus", fmi2GetIntegerStatus(c, 0, &mut k)),
            ("fmi2GetBooleanStatus", fmi2GetBooleanStatus(c, 3, &mut flag)),
            ("fmi2GetStringStatus", fmi2GetStringStatus(c, 1, string.as_mut_ptr())),
            ("fmi2EnterEventMode", fmi2EnterEventMode(c)),
            ("fmi2NewDiscreteStates", fmi2NewDiscreteStates(c, &mut info)),
            ("fmi2EnterContinuousTimeMode", fmi2EnterContinuousTimeMode(c)),
            ("fmi2CompletedIntegratorStep", fmi2CompletedIntegratorStep(c, 0, &mut k, &mut flag)),
            ("fmi2SetTime", fmi2SetTime(c, 0.5)),
            ("fmi2SetContinuousStates", fmi2SetContinuousStates(c, x.as_ptr(), 4)),
            ("fmi2GetDerivatives", fmi2GetDerivatives(c, x.as_mut_ptr(), 4)),
            ("fmi2GetEventIndicators", fmi2GetEventIndicators(c, x.as_mut_ptr(), 2)),
            ("fmi2GetContinuousStates", fmi2GetContinuousStates(c, x.as_mut_ptr(), 4)),
            (
                "fmi2GetNominalsOfContinuousStates",
                fmi2GetNominalsOfContinuousStates(c, x.as_mut_ptr(), 4),
            ),
        ];
        // Nothing was written through an output argument.
        assert!(fresh.is_null() && existing == snap && none.is_null());
        assert!(out.iter().all(|x| *x == 0) && size == 0);
        assert_eq!((r, i, b, k, flag), ([0.5], [3], [fmi2True], -1, -1));
        assert!(string[0].is_null());
        assert_eq!(x, [0.5; 4]);
        assert_eq!((info.terminateSimulation, info.nextEventTime), (-1, -1.0));
        calls
    }
}

/// The fatal state, which only a panic reaches, for all 44 functions (FMI 2.0 §2.1.3:
/// after fmi2Fatal no function may be called). Chosen and checked here:
/// - each of the 40 functions with a status returns fmi2Error, the status of every
///   illegal call, and logs "`<function>`: illegal call sequence: not allowed in state
///   `fatal`", whatever its arguments (valid ones, NULL arrays, nvr = 0, NULL states);
/// - none of them touches the instance, its FMU states or the output arguments, and none
///   is traced although logCalls is on;
/// - fmi2FreeInstance still frees the instance (a host that does so should not leak it;
///   nothing of the model is read);
/// - fmi2GetTypesPlatform, fmi2GetVersion and fmi2Instantiate take no instance: they
///   work as always. The panic was caught inside one instance, so other instances, old
///   and new, are intact: fatal is per instance.
#[test]
fn a_fatal_instance_refuses_all_44_functions_and_stays_untouched() {
    let _g = registering();
    let records: Box<Records> = Box::default();
    let functions = callbacks(&records);
    let c = instantiate(c"doomed", &functions);
    let other_records: Box<Records> = Box::default();
    let other_functions = callbacks(&other_records);
    let other = instantiate(c"bystander", &other_functions);
    let take = |r: &Records| std::mem::take(&mut *r.lock().unwrap());

    // SAFETY: `c` and `other` are live instances of this test; the FMU states are ours.
    unsafe {
        to_step_complete(c);
        to_step_complete(other);
        let mut snap: fmi2FMUstate = null_mut();
        assert_eq!(fmi2GetFMUstate(c, &mut snap), OK);
        let mut size = 0;
        assert_eq!(fmi2SerializedFMUstateSize(c, snap, &mut size), OK);
        let mut bytes = vec![0u8; size];
        let p = bytes.as_mut_ptr() as *mut fmi2Byte;
        assert_eq!(fmi2SerializeFMUstate(c, snap, p, size), OK);
        // logCalls is on (loggingOn at instantiation): the calls so far were traced.
        assert!(take(&records).iter().any(|r| r.3.starts_with("fmi2DoStep: tc = 0")));

        assert_eq!(guard(c, "fmi2DoStep", |_| panic!("boom")), FATAL);
        let panic = take(&records);
        assert_eq!(panic.len(), 1, "{panic:#?}");
        assert_eq!(
            (panic[0].0, panic[0].1.as_str(), panic[0].2.as_str()),
            (FATAL, "logStatusFatal", "%s")
        );
        assert!(panic[0].3.contains("fmi2DoStep: internal error (panic): boom"), "{panic:?}");

        let debug = |c: fmi2Component| format!("{:?}", instance(c).unwrap());
        let before = debug(c);
        assert!(before.contains("Fatal"), "{before}");
        let snap_before = crate::fmi::serialize(snapshot(snap).unwrap()).unwrap();

        let calls = instance_calls(c, snap, &bytes);
        let mut names: Vec<&str> = calls.iter().map(|(n, _)| *n).collect();
        names.dedup();
        assert_eq!(names.len(), 40, "{names:?}");
        let log = take(&records);
        assert_eq!(log.len(), calls.len(), "one record per call: {log:#?}");
        for ((name, status), (s, category, fmt, message)) in calls.iter().zip(&log) {
            assert_eq!(*status, ERROR, "{name} in fatal");
            assert_eq!((*s, category.as_str(), fmt.as_str()), (ERROR, "logStatusError", "%s"));
            let want = format!("{name}: illegal call sequence: not allowed in state `fatal`");
            assert_eq!(message, &want);
        }
        assert_eq!(debug(c), before, "a fatal instance is not touched");
        let snap_after = crate::fmi::serialize(snapshot(snap).unwrap()).unwrap();
        assert_eq!(snap_after, snap_before, "nor are the FMU states passed to it");
        assert!(with_registry(|r| r.states.contains_key(&(snap as usize))), "nor freed");

        // The three functions without an instance.
        assert_eq!(CStr::from_ptr(fmi2GetTypesPlatform()), c"default");
        assert_eq!(CStr::from_ptr(fmi2GetVersion()), c"2.0");
        let new = instantiate(c"newcomer", &other_functions);
        assert_eq!(fmi2SetupExperiment(new, fmi2False, 0.0, 0.0, fmi2False, 0.0), OK);
        fmi2FreeInstance(new);
        assert!(take(&records).is_empty(), "nothing reaches the fatal instance's logger");
        // The bystander, made before the panic, continues.
        assert_eq!(fmi2DoStep(other, 0.01, 0.01, fmi2False), OK);
        let mut x = [0.0];
        assert_eq!(fmi2GetReal(other, [Var::V1.vr()].as_ptr(), 1, x.as_mut_ptr()), OK);
        assert!(x[0].is_finite() && x[0] != 0.0, "{x:?}");
        assert!(take(&other_records).iter().all(|r| r.0 == OK), "only traces");

        // fmi2FreeInstance frees it (traced: logCalls is on), and then it is unknown.
        fmi2FreeInstance(c);
        let freed = take(&records);
        assert_eq!(freed.len(), 1, "{freed:#?}");
        assert_eq!((freed[0].0, freed[0].1.as_str()), (OK, "logCalls"));
        assert_eq!(freed[0].3, "fmi2FreeInstance: instance `doomed`");
        assert!(!with_registry(|r| r.instances.contains(&(c as usize))));
        assert_eq!(fmi2Reset(c), ERROR);
        fmi2FreeInstance(c); // a no-op
        assert!(take(&records).is_empty(), "a freed instance has no logger");

        // fmi2FreeInstance freed the FMU state its instance left behind: the pointer is
        // unknown now, and refused.
        assert!(!with_registry(|r| r.states.contains_key(&(snap as usize))));
        assert_eq!(fmi2FreeFMUstate(other, &mut snap), ERROR);
        let refused = take(&other_records);
        assert!(refused.iter().any(|r| r.3.contains("fmi2FreeFMUstate")), "{refused:#?}");
        fmi2FreeInstance(other);
    }
}
