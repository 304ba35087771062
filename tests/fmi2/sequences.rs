//! Illegal call sequences in every state, and calls on NULL, garbage and freed instances.

use super::*;

// ===== 3. illegal call sequences ================================================================

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum St {
    Instantiated,
    Init,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
}
pub(crate) use St::*;

pub(crate) const ALL_STATES: [St; 6] =
    [Instantiated, Init, StepComplete, StepFailed, Terminated, Error];

impl St {
    /// The name the FMU uses in its messages.
    fn fmu_name(self) -> &'static str {
        match self {
            Instantiated => "`instantiated`",
            Init => "`initialization mode`",
            StepComplete => "`step complete`",
            StepFailed => "`step failed`",
            Terminated => "`terminated`",
            Error => "`error`",
        }
    }
}

/// An instance in state `st`, and its communication time.
pub(crate) fn reach(st: St) -> (Host, f64) {
    let h = Host::new(&format!("in {st:?}"));
    let t = match st {
        Instantiated => 0.0,
        Init => {
            h.expect_ok(h.setup(Some(1e-6), 0.0, None));
            h.expect_ok(h.enter());
            0.0
        }
        StepComplete | Terminated => {
            h.initialize();
            h.expect_ok(h.step(0.0, 0.01));
            if st == Terminated {
                h.expect_ok(h.terminate());
            }
            0.01
        }
        StepFailed => {
            fail_a_step(&h);
            h.real_status(LAST_SUCCESSFUL_TIME).1
        }
        Error => {
            fail_initialization(&h);
            0.0
        }
    };
    (h, t)
}

/// Reaches the error state from `instantiated`: each value is in range, but together they
/// leave the mass matrix singular (a massless beam, J_C = 0 and φ(0) = 0).
pub(crate) fn fail_initialization(h: &Host) {
    h.expect_ok(h.set_real(Var::M, 0.0));
    h.expect_ok(h.set_real(Var::JC, 0.0));
    h.expect_ok(h.setup(None, 0.0, None));
    h.expect_ok(h.enter());
    let status = h.exit();
    h.expect_error(status, &["fmi2ExitInitializationMode", "singular at the start"]);
}

/// Checks that `h` is (still) in state `st` and usable there. Consumes the state.
#[track_caller]
pub(crate) fn probe(h: &Host, st: St, t: f64) {
    match st {
        Instantiated => h.expect_ok(h.enter()),
        Init => h.expect_ok(h.exit()),
        StepComplete => h.expect_ok(h.step(t, 0.01)),
        StepFailed => {
            assert_eq!(h.boolean_status(TERMINATED), (OK, fmi2True));
            h.expect_ok(h.terminate());
        }
        Terminated => {
            let (s, _) = h.real_status(LAST_SUCCESSFUL_TIME);
            h.expect_ok(s);
            let s = h.terminate();
            h.expect_error(s, &["fmi2Terminate", "illegal call sequence", "`terminated`"]);
        }
        Error => {
            let (s, _) = h.real_status(LAST_SUCCESSFUL_TIME);
            h.expect_error(s, &["fmi2GetRealStatus", "illegal call sequence", "`error`"]);
            assert_eq!(h.real(Var::M), 0.0);
            h.expect_ok(h.reset());
        }
    }
}

pub(crate) const GET: &[St] = &[Init, StepComplete, StepFailed, Terminated, Error];
pub(crate) const SET: &[St] = &[Instantiated, Init, StepComplete];
pub(crate) const STATUS: &[St] = &[StepComplete, StepFailed, Terminated];
pub(crate) const OUTPUT_DERIVATIVES: &[St] = &[StepComplete, StepFailed, Terminated, Error];

/// A call with arguments that are valid wherever the call is allowed.
pub(crate) type Call = (&'static str, &'static [St], fn(&Host, f64) -> fmi2Status);

/// Get, set, serialize, deserialize and free an FMU state: allowed everywhere but `fatal`.
pub(crate) fn fmu_state_round_trip(h: &Host, _t: f64) -> fmi2Status {
    let mut s: fmi2FMUstate = null_mut();
    let mut status = h.get_state(&mut s);
    if status == OK {
        status = h.set_state(s);
    }
    let mut size = 0;
    if status == OK {
        status = unsafe { fmi2SerializedFMUstateSize(h.c, s, &mut size) };
    }
    let mut bytes = vec![0u8; size];
    if status == OK {
        status =
            unsafe { fmi2SerializeFMUstate(h.c, s, bytes.as_mut_ptr() as *mut fmi2Byte, size) };
    }
    let mut d: fmi2FMUstate = null_mut();
    if status == OK {
        status = h.deserialize(&bytes, &mut d);
    }
    if status == OK {
        status = h.set_state(d);
    }
    for p in [&mut s, &mut d] {
        if !p.is_null() {
            let free = h.free_state(p);
            if status == OK {
                status = free;
            }
        }
    }
    status
}

pub(crate) fn calls() -> Vec<Call> {
    vec![
        ("fmi2SetupExperiment", &[Instantiated], |h, _| h.setup(Some(1e-6), 0.0, None)),
        ("fmi2EnterInitializationMode", &[Instantiated], |h, _| h.enter()),
        ("fmi2ExitInitializationMode", &[Init], |h, _| h.exit()),
        ("fmi2Terminate", &[StepComplete, StepFailed], |h, _| h.terminate()),
        ("fmi2DoStep", &[StepComplete], |h, t| h.step(t, 0.01)),
        ("fmi2Reset", &ALL_STATES, |h, _| h.reset()),
        ("fmi2SetDebugLogging", &ALL_STATES, |h, _| h.debug_logging(true, &[c"logCalls"])),
        ("fmi2GetReal", GET, |h, _| h.get_reals(&[vr(Var::L)]).0),
        ("fmi2GetInteger", GET, |h, _| h.get_integers(&[vr(Var::Formulation)]).0),
        ("fmi2GetBoolean", GET, |h, _| h.get_booleans(&[vr(Var::StabilityGuard)]).0),
        ("fmi2GetString", GET, |h, _| unsafe { fmi2GetString(h.c, null(), 0, null_mut()) }),
        ("fmi2SetReal", SET, |h, _| h.set_real(Var::Phi, 0.0)),
        ("fmi2SetInteger", SET, |h, _| h.set_integer(Var::Formulation, 1)),
        ("fmi2SetBoolean", SET, |h, _| h.set_boolean(Var::StabilityGuard, true)),
        ("fmi2SetString", SET, |h, _| unsafe { fmi2SetString(h.c, null(), 0, null()) }),
        ("fmi2SetRealInputDerivatives", SET, |h, _| h.set_derivative(Var::Phi, 1, 0.0)),
        ("fmi2GetRealOutputDerivatives", OUTPUT_DERIVATIVES, |h, _| {
            let (vrs, order, mut out) = ([vr(Var::V1)], [1], [0.0]);
            unsafe {
                fmi2GetRealOutputDerivatives(h.c, vrs.as_ptr(), 1, order.as_ptr(), out.as_mut_ptr())
            }
        }),
        ("fmi2GetDirectionalDerivative", GET, |h, _| {
            let (unknown, known, dv, mut out) = ([vr(Var::V1)], [vr(Var::Phi)], [1.0], [0.0]);
            unsafe {
                fmi2GetDirectionalDerivative(
                    h.c,
                    unknown.as_ptr(),
                    1,
                    known.as_ptr(),
                    1,
                    dv.as_ptr(),
                    out.as_mut_ptr(),
                )
            }
        }),
        ("fmi2CancelStep", &[], |h, _| unsafe { fmi2CancelStep(h.c) }),
        ("fmi2GetStatus", STATUS, |h, _| {
            let mut s = -1;
            unsafe { fmi2GetStatus(h.c, DO_STEP_STATUS, &mut s) }
        }),
        ("fmi2GetRealStatus", STATUS, |h, _| h.real_status(LAST_SUCCESSFUL_TIME).0),
        ("fmi2GetIntegerStatus", STATUS, |h, _| {
            let mut k = -1;
            unsafe { fmi2GetIntegerStatus(h.c, DO_STEP_STATUS, &mut k) }
        }),
        ("fmi2GetBooleanStatus", STATUS, |h, _| h.boolean_status(TERMINATED).0),
        ("fmi2GetStringStatus", STATUS, |h, _| {
            let mut s: fmi2String = null();
            unsafe { fmi2GetStringStatus(h.c, PENDING_STATUS, &mut s) }
        }),
        ("fmi2GetFMUstate", &ALL_STATES, fmu_state_round_trip),
        // The other FMU-state functions one by one, each with a state from another instance.
        ("fmi2SetFMUstate", &ALL_STATES, |h, _| {
            let (d, mut s) = donor_state();
            let status = h.set_state(s);
            d.expect_ok(d.free_state(&mut s));
            status
        }),
        ("fmi2FreeFMUstate", &ALL_STATES, |h, _| {
            let (d, mut s) = donor_state();
            let status = h.free_state(&mut s);
            if !s.is_null() {
                d.expect_ok(d.free_state(&mut s));
            }
            status
        }),
        ("fmi2SerializedFMUstateSize", &ALL_STATES, |h, _| {
            let (d, mut s) = donor_state();
            let mut size = 0;
            let status = unsafe { fmi2SerializedFMUstateSize(h.c, s, &mut size) };
            assert_eq!(size != 0, status == OK, "size {size}");
            d.expect_ok(d.free_state(&mut s));
            status
        }),
        ("fmi2SerializeFMUstate", &ALL_STATES, |h, _| {
            let (d, mut s) = donor_state();
            let want = d.serialize(s);
            let mut bytes = vec![0u8; want.len()];
            let p = bytes.as_mut_ptr() as *mut fmi2Byte;
            let status = unsafe { fmi2SerializeFMUstate(h.c, s, p, bytes.len()) };
            assert_eq!(bytes == want, status == OK, "bytes written iff fmi2OK");
            d.expect_ok(d.free_state(&mut s));
            status
        }),
        ("fmi2DeSerializeFMUstate", &ALL_STATES, |h, _| {
            let (d, mut s) = donor_state();
            let bytes = d.serialize(s);
            d.expect_ok(d.free_state(&mut s));
            let mut p: fmi2FMUstate = null_mut();
            let status = h.deserialize(&bytes, &mut p);
            assert_eq!(!p.is_null(), status == OK, "a state iff fmi2OK");
            if !p.is_null() {
                d.expect_ok(d.free_state(&mut p));
            }
            status
        }),
    ]
}

/// A live FMU state of a separate instance in `instantiated`, and that instance.
pub(crate) fn donor_state() -> (Host, fmi2FMUstate) {
    let d = Host::new("donor");
    let mut s: fmi2FMUstate = null_mut();
    d.expect_ok(d.get_state(&mut s));
    (d, s)
}

/// The documented outcome of a call in a state that allows it, with the arguments of
/// [`calls`]: `Ok` for fmi2OK, `Err(reason)` for fmi2Error with a message naming the call
/// and `reason`.
pub(crate) fn allowed_outcome(name: &str, st: St) -> Result<(), &'static str> {
    match name {
        // Declared unsupported in modelDescription.xml: they log why and return fmi2Error.
        "fmi2GetDirectionalDerivative"
        | "fmi2GetStatus"
        | "fmi2GetIntegerStatus"
        | "fmi2GetStringStatus" => Err("not provided"),
        // The error state is reached here with parameters that make no model: no outputs.
        "fmi2GetRealOutputDerivatives" if st == Error => Err("the outputs cannot be computed"),
        // The only integer and boolean variables are fixed parameters.
        "fmi2SetInteger" | "fmi2SetBoolean" if st == StepComplete => Err("fixed parameter"),
        _ => Ok(()),
    }
}

/// For every reachable state and every function that takes an instance (30, the FMU-state
/// functions one by one; fmi2FreeInstance has its own test), with debug logging off and
/// with logCalls on:
/// - a call that the state machine forbids returns fmi2Error, logs "illegal call sequence"
///   with the function and state, and leaves the instance usable in its state;
/// - a call that it allows returns its documented status ([`allowed_outcome`]): fmi2OK
///   with nothing logged when logging is off and a logCalls trace naming the call when it
///   is on, or fmi2Error with a message naming the call and the reason.
#[test]
fn illegal_call_sequences_are_refused_in_every_state() {
    let _g = shared();
    let (mut illegal, mut pairs) = (0, 0);
    for logging in [false, true] {
        for st in ALL_STATES {
            for (name, allowed, call) in calls() {
                let (h, t) = reach(st);
                if logging {
                    h.expect_ok(h.debug_logging(true, &[c"logCalls"]));
                }
                let status = call(&h, t);
                if !allowed.contains(&st) {
                    let r = h.expect_error(status, &[name, "illegal call sequence", st.fmu_name()]);
                    assert_eq!(r.name, h.name);
                    probe(&h, st, t);
                    illegal += 1;
                } else if let Err(reason) = allowed_outcome(name, st) {
                    let r = h.expect_error(status, &[&format!("{name}: "), reason]);
                    assert!(!r.message.contains("illegal call sequence"), "{r:?}");
                } else {
                    let records = h.take();
                    assert_eq!(status, OK, "{name} in {st:?}: {records:#?}");
                    // The call of fmi2SetDebugLogging switches logCalls on itself.
                    if logging || name == "fmi2SetDebugLogging" {
                        assert!(!records.is_empty(), "{name} in {st:?} is not traced");
                        assert!(
                            records.iter().all(|r| r.status == OK && r.category == "logCalls"),
                            "{name} in {st:?}: {records:#?}"
                        );
                        let head = format!("{name}: ");
                        assert!(
                            records.iter().any(|r| r.message.starts_with(&head)),
                            "no trace of {name} in {st:?}: {records:#?}"
                        );
                    } else {
                        assert!(records.is_empty(), "{name} in {st:?}, logging off: {records:#?}");
                    }
                }
                pairs += 1;
            }
        }
    }
    // 6 states × 30 functions, twice; the state machine forbids 67 of the 180 pairs.
    assert_eq!((pairs, illegal), (2 * 6 * 30, 2 * 67));
}

/// The `start` state: no instance. Each of the 30 calls of [`calls`] with a NULL instance
/// returns fmi2Error and logs nothing (there is no logger to call: the callbacks come with
/// fmi2Instantiate), not even to another live instance's logger. fmi2FreeInstance(NULL) is
/// a no-op; the three functions without an instance work.
#[test]
fn every_call_without_an_instance_is_refused_silently() {
    let _g = shared();
    let bystander = Host::law("bystander");
    let log = Box::<Collector>::default();
    let callbacks = callbacks(log.env());
    let nobody = Host { c: null_mut(), name: "nobody".into(), log, callbacks };
    let calls = calls();
    assert_eq!(calls.len(), 30);
    for (name, _, call) in calls {
        let status = call(&nobody, 0.0);
        assert_eq!(status, ERROR, "{name}(NULL)");
        assert!(nobody.take().is_empty(), "{name}(NULL) has no logger");
        assert!(bystander.take().is_empty(), "{name}(NULL) logged to another instance");
    }
    unsafe { fmi2FreeInstance(null_mut()) };
    let platform = unsafe { CStr::from_ptr(fmi2GetTypesPlatform()) };
    assert_eq!(platform, c"default");
    let version = unsafe { CStr::from_ptr(fmi2GetVersion()) };
    assert_eq!(version, c"2.0");
    // fmi2Instantiate is the one function for `start`.
    let h = Host::new("first");
    h.expect_ok(h.setup(None, 0.0, None));
    assert!(bystander.take().is_empty());
    bystander.steps(0.0, 0.01, 2);
}

/// fmi2GetTypesPlatform, fmi2GetVersion, fmi2Instantiate (with fmi2FreeInstance of the new
/// instance) and fmi2FreeInstance(NULL) take no instance: whatever the state of a live one,
/// they work and leave it alone, in its state and silent.
#[test]
fn functions_without_an_instance_work_whatever_the_state_of_others() {
    let _g = shared();
    for st in ALL_STATES {
        let (h, t) = reach(st);
        let platform = unsafe { CStr::from_ptr(fmi2GetTypesPlatform()) };
        assert_eq!(platform, c"default", "{st:?}");
        let version = unsafe { CStr::from_ptr(fmi2GetVersion()) };
        assert_eq!(version, c"2.0", "{st:?}");
        let other = Host::new("other");
        other.expect_ok(other.setup(None, 0.0, None));
        drop(other);
        unsafe { fmi2FreeInstance(null_mut()) };
        assert!(h.take().is_empty(), "{st:?}");
        probe(&h, st, t);
    }
}

/// fmi2FreeInstance in each of the six reachable states (the fatal state: ffi.rs's unit
/// tests): traced when logCalls is on, silent otherwise; afterwards every call on the freed
/// pointer returns fmi2Error without calling its logger, and a second free is a no-op.
#[test]
fn free_instance_works_in_every_state() {
    // Calls on freed pointers: no other test may get their addresses meanwhile.
    let _g = exclusive();
    for logging in [false, true] {
        for st in ALL_STATES {
            let (mut h, _) = reach(st);
            if logging {
                h.expect_ok(h.debug_logging(true, &[c"logCalls"]));
            }
            let c = h.c;
            unsafe { fmi2FreeInstance(c) };
            h.c = null_mut();
            let records = h.take();
            if logging {
                assert_eq!(records.len(), 1, "{st:?}: {records:#?}");
                let r = &records[0];
                assert_eq!((r.status, r.category.as_str()), (OK, "logCalls"));
                assert_eq!(r.message, format!("fmi2FreeInstance: instance `{}`", h.name));
            } else {
                assert!(records.is_empty(), "{st:?}: {records:#?}");
            }
            for (name, status) in call_everything(c) {
                assert_eq!(status, ERROR, "{name} after fmi2FreeInstance in {st:?}");
            }
            unsafe { fmi2FreeInstance(c) };
            assert!(h.take().is_empty(), "a freed instance calls no logger");
        }
    }
}

/// Two live instances; A is freed twice (and NULL once): the second free is refused by the
/// registry, so B is neither freed nor disturbed: it continues bit for bit like an
/// instance that never saw the frees, and still logs under its own name.
#[test]
fn freeing_one_instance_twice_leaves_another_alive() {
    let _g = exclusive();
    let mut a = Host::law("A");
    let b = Host::law("B");
    let reference = Host::law("reference");
    for h in [&a, &b, &reference] {
        h.steps(0.0, 0.01, 3);
    }
    let c = a.c;
    unsafe {
        fmi2FreeInstance(c);
        fmi2FreeInstance(c);
        fmi2FreeInstance(null_mut());
    }
    a.c = null_mut();
    assert!(a.log.records().is_empty());
    assert_eq!(unsafe { fmi2DoStep(c, 0.03, 0.01, fmi2False) }, ERROR, "A is gone");
    for k in 3..30 {
        let t = k as f64 * 0.01;
        b.expect_ok(b.step(t, 0.01));
        reference.expect_ok(reference.step(t, 0.01));
        assert_eq!(bits(&b.outputs()), bits(&reference.outputs()), "step {k}");
    }
    let st = b.setup(None, 0.0, None);
    let r = b.expect_error(st, &["fmi2SetupExperiment", "illegal call sequence"]);
    assert_eq!((r.name.as_str(), r.env), ("B", b.log.env() as usize));
    b.expect_ok(b.terminate());
    assert!(a.log.records().is_empty());
}

/// The sequences named in the FMI notes, one by one.
#[test]
fn illegal_call_sequences_named_in_the_notes() {
    let _g = shared();
    let h = Host::new("seq");
    let s = h.step(0.0, 0.01);
    h.expect_error(s, &["fmi2DoStep: illegal call sequence", "`instantiated`"]);
    let s = h.exit();
    h.expect_error(s, &["fmi2ExitInitializationMode: illegal call sequence"]);
    let s = h.get_reals(&[vr(Var::L)]).0;
    h.expect_error(s, &["fmi2GetReal: illegal call sequence", "`instantiated`"]);
    h.expect_ok(h.enter());
    let s = h.enter();
    h.expect_error(s, &["fmi2EnterInitializationMode: illegal call sequence"]);
    let s = h.terminate();
    h.expect_error(s, &["fmi2Terminate: illegal call sequence", "`initialization mode`"]);
    let s = h.setup(None, 0.0, None);
    h.expect_error(s, &["fmi2SetupExperiment: illegal call sequence"]);
    h.expect_ok(h.exit());
    let s = h.setup(None, 0.0, None);
    h.expect_error(s, &["fmi2SetupExperiment: illegal call sequence", "`step complete`"]);
    let s = h.exit();
    h.expect_error(s, &["fmi2ExitInitializationMode: illegal call sequence"]);
    // Still usable in stepComplete.
    h.expect_ok(h.set_real(Var::Phi, 0.1));
    h.expect_ok(h.step(0.0, 0.01));
    h.expect_ok(h.terminate());
    let s = h.step(0.01, 0.01);
    h.expect_error(s, &["fmi2DoStep: illegal call sequence", "`terminated`"]);
    let s = h.set_real(Var::Phi, 0.2);
    h.expect_error(s, &["fmi2SetReal: illegal call sequence", "`terminated`"]);
    assert_eq!(h.real(Var::Phi), 0.1);
}

// ===== 4. NULL, garbage and freed instances ====================================================

/// Calls each of the 30 functions that take an instance with `c`, and valid other
/// arguments; returns (name, status).
pub(crate) fn call_everything(c: fmi2Component) -> Vec<(&'static str, fmi2Status)> {
    let vrs = [vr(Var::L)];
    let ivrs = [vr(Var::Formulation)];
    let mut real = [0.0];
    let mut int = [0];
    let mut boolean = [0];
    let mut string: [fmi2String; 1] = [null()];
    let mut state: fmi2FMUstate = null_mut();
    let mut size = 0usize;
    let mut bytes = [0u8; 16];
    let order = [1];
    let mut status = 0;
    let cats = [c"logAll".as_ptr()];
    unsafe {
        vec![
            ("fmi2SetDebugLogging", fmi2SetDebugLogging(c, fmi2True, 1, cats.as_ptr())),
            ("fmi2SetupExperiment", fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0)),
            ("fmi2EnterInitializationMode", fmi2EnterInitializationMode(c)),
            ("fmi2ExitInitializationMode", fmi2ExitInitializationMode(c)),
            ("fmi2Terminate", fmi2Terminate(c)),
            ("fmi2Reset", fmi2Reset(c)),
            ("fmi2GetReal", fmi2GetReal(c, vrs.as_ptr(), 1, real.as_mut_ptr())),
            ("fmi2GetInteger", fmi2GetInteger(c, ivrs.as_ptr(), 1, int.as_mut_ptr())),
            ("fmi2GetBoolean", fmi2GetBoolean(c, vrs.as_ptr(), 1, boolean.as_mut_ptr())),
            ("fmi2GetString", fmi2GetString(c, vrs.as_ptr(), 1, string.as_mut_ptr())),
            ("fmi2SetReal", fmi2SetReal(c, vrs.as_ptr(), 1, [1.0].as_ptr())),
            ("fmi2SetInteger", fmi2SetInteger(c, ivrs.as_ptr(), 1, [1].as_ptr())),
            ("fmi2SetBoolean", fmi2SetBoolean(c, vrs.as_ptr(), 1, [1].as_ptr())),
            ("fmi2SetString", fmi2SetString(c, vrs.as_ptr(), 1, [c"x".as_ptr()].as_ptr())),
            ("fmi2GetFMUstate", fmi2GetFMUstate(c, &mut state)),
            ("fmi2SetFMUstate", fmi2SetFMUstate(c, state)),
            ("fmi2FreeFMUstate", fmi2FreeFMUstate(c, &mut state)),
            ("fmi2SerializedFMUstateSize", fmi2SerializedFMUstateSize(c, state, &mut size)),
            (
                "fmi2SerializeFMUstate",
                fmi2SerializeFMUstate(c, state, bytes.as_mut_ptr() as *mut fmi2Byte, 16),
            ),
            (
                "fmi2DeSerializeFMUstate",
                fmi2DeSerializeFMUstate(c, bytes.as_ptr() as *const fmi2Byte, 16, &mut state),
            ),
            (
                "fmi2GetDirectionalDerivative",
                fmi2GetDirectionalDerivative(
                    c,
                    vrs.as_ptr(),
                    1,
                    vrs.as_ptr(),
                    1,
                    [1.0].as_ptr(),
                    real.as_mut_ptr(),
                ),
            ),
            (
                "fmi2SetRealInputDerivatives",
                fmi2SetRealInputDerivatives(c, vrs.as_ptr(), 1, order.as_ptr(), [0.0].as_ptr()),
            ),
            (
                "fmi2GetRealOutputDerivatives",
                fmi2GetRealOutputDerivatives(c, vrs.as_ptr(), 1, order.as_ptr(), real.as_mut_ptr()),
            ),
            ("fmi2DoStep", fmi2DoStep(c, 0.0, 0.01, fmi2False)),
            ("fmi2CancelStep", fmi2CancelStep(c)),
            ("fmi2GetStatus", fmi2GetStatus(c, DO_STEP_STATUS, &mut status)),
            ("fmi2GetRealStatus", fmi2GetRealStatus(c, LAST_SUCCESSFUL_TIME, real.as_mut_ptr())),
            ("fmi2GetIntegerStatus", fmi2GetIntegerStatus(c, DO_STEP_STATUS, int.as_mut_ptr())),
            ("fmi2GetBooleanStatus", fmi2GetBooleanStatus(c, TERMINATED, boolean.as_mut_ptr())),
            ("fmi2GetStringStatus", fmi2GetStringStatus(c, PENDING_STATUS, string.as_mut_ptr())),
        ]
    }
}

#[test]
fn null_and_garbage_instances_give_error() {
    let _g = shared();
    let mut on_stack = [0u64; 64];
    for c in [null_mut(), 0x1234 as fmi2Component, on_stack.as_mut_ptr() as fmi2Component] {
        let results = call_everything(c);
        assert_eq!(results.len(), 30);
        for (name, status) in results {
            assert_eq!(status, ERROR, "{name}({c:?})");
        }
        unsafe { fmi2FreeInstance(c) }; // a no-op
    }
    assert!(on_stack.iter().all(|x| *x == 0), "nothing was written through a foreign pointer");
}

#[test]
fn freed_instances_are_refused() {
    // Freed addresses must not be handed out to another test meanwhile.
    let _g = exclusive();
    let mut h = Host::law("freed");
    h.steps(0.0, 0.01, 3);
    let c = h.c;
    unsafe { fmi2FreeInstance(c) };
    unsafe { fmi2FreeInstance(c) }; // the registry refuses the second free: a no-op
    h.c = null_mut();
    for (name, status) in call_everything(c) {
        assert_eq!(status, ERROR, "{name} on a freed instance");
    }
    assert!(h.log.records().is_empty(), "a freed instance has no logger to call");
    unsafe { fmi2FreeInstance(c) };
    // Other instances are not affected.
    let other = Host::law("other");
    other.steps(0.0, 0.01, 2);
}
