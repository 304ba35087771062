//! Logging, the version, reset, and the functions that are not provided.

use super::*;

// ===== 12. logging ==============================================================================

#[test]
fn logging_is_silent_when_off_and_errors_always_go_out() {
    let _g = shared();
    let h = Host::law("quiet");
    h.steps(0.0, 0.01, 5);
    let mut s: fmi2FMUstate = null_mut();
    h.expect_ok(h.get_state(&mut s));
    h.expect_ok(h.set_state(s));
    h.serialize(s);
    h.expect_ok(h.free_state(&mut s));
    let _ = h.outputs();
    h.expect_ok(h.terminate());
    h.expect_ok(h.reset());
    assert!(h.take().is_empty(), "a successful run with logging off logs nothing");

    // Errors are logged whatever the settings.
    h.expect_ok(h.debug_logging(false, &[c"logAll"]));
    let st = h.step(0.0, 0.01);
    h.expect_error(st, &["illegal call sequence"]);
    h.expect_ok(h.debug_logging(false, &[c"logStatusError"]));
    let st = h.set_real(Var::L, -1.0);
    h.expect_error(st, &["`l`"]);

    // Unknown categories are refused, with the list of known ones.
    let st = h.debug_logging(true, &[c"logNonsense"]);
    let r = h.expect_error(st, &["fmi2SetDebugLogging", "logNonsense", "logCalls", "logAll"]);
    assert_eq!(r.category, "logStatusError");
    let st = h.debug_logging(true, &[c"logCalls", c"LOGCALLS"]);
    h.expect_error(st, &["LOGCALLS"]);
    let cats = [c"logCalls".as_ptr(), null()];
    let st = unsafe { fmi2SetDebugLogging(h.c, fmi2True, 2, cats.as_ptr()) };
    h.expect_error(st, &["fmi2SetDebugLogging", "unknown log category"]);
    // ... and a refused call changed nothing: still silent.
    h.initialize();
    h.expect_ok(h.set_real(Var::Phi, 0.0));
    h.expect_ok(h.step(0.0, 0.01));
    assert!(h.take().is_empty());

    // logCalls on: fmi2DoStep says what it does, in category logCalls.
    h.expect_ok(h.debug_logging(true, &[c"logCalls"]));
    h.take();
    assert_eq!(h.step(0.01, 0.01), OK);
    let records = h.take();
    assert_declared_categories(&records);
    let r = records
        .iter()
        .find(|r| r.message.contains("fmi2DoStep"))
        .unwrap_or_else(|| panic!("no trace of fmi2DoStep: {records:#?}"));
    assert_eq!((r.status, r.category.as_str(), r.name.as_str()), (OK, "logCalls", "quiet"));
    assert_eq!(r.env, h.log.env() as usize);

    // nCategories = 0 and loggingOn = false: every category off, silent again.
    assert_eq!(unsafe { fmi2SetDebugLogging(h.c, fmi2False, 0, null()) }, OK);
    h.take();
    h.expect_ok(h.step(0.02, 0.01));
    assert!(h.take().is_empty());
    // nCategories = 0 and loggingOn = true: every category on.
    assert_eq!(unsafe { fmi2SetDebugLogging(h.c, fmi2True, 0, null()) }, OK);
    h.take();
    assert_eq!(h.step(0.03, 0.01), OK);
    assert!(h.take().iter().any(|r| r.category == "logCalls"));
    // logAll off switches logCalls off too.
    h.expect_ok(h.debug_logging(false, &[c"logAll"]));
    h.expect_ok(h.step(0.04, 0.01));
    assert!(h.take().is_empty());
}

/// Debug logging off (loggingOn = false and no fmi2SetDebugLogging): a whole run with 100
/// communication steps, each with SetReal, DoStep, GetReal and the status queries, FMU
/// states, Terminate and Reset, calls the logger not once. Then an error and a discarded
/// step give exactly one record each.
#[test]
fn a_run_with_logging_off_logs_nothing_at_all() {
    let _g = shared();
    let h = Host::new("silent");
    let mut statuses = vec![
        h.setup(Some(1e-6), 0.0, Some(2.0)),
        h.set_real(Var::Ei, 1200.0),
        h.set_integer(Var::MaxOrder, 4),
        h.set_boolean(Var::StabilityGuard, true),
        h.enter(),
        h.get_reals(&OUTPUTS.map(vr)).0,
        h.exit(),
    ];
    let dt = 0.01;
    for k in 0..100 {
        let tc = k as f64 * dt;
        statuses.push(h.set_real(Var::Phi, paper_phi(tc)));
        statuses.push(h.step(tc, dt));
        statuses.push(h.get_reals(&OUTPUTS.map(vr)).0);
        statuses.push(h.get_integers(&[vr(Var::Formulation)]).0);
        statuses.push(h.real_status(LAST_SUCCESSFUL_TIME).0);
        statuses.push(h.boolean_status(TERMINATED).0);
        if k % 25 == 0 {
            let mut s: fmi2FMUstate = null_mut();
            statuses.push(h.get_state(&mut s));
            statuses.push(h.set_state(s));
            let bytes = h.serialize(s);
            let mut d: fmi2FMUstate = null_mut();
            statuses.push(h.deserialize(&bytes, &mut d));
            statuses.push(h.free_state(&mut s));
            statuses.push(h.free_state(&mut d));
        }
    }
    statuses.push(h.set_derivative(Var::Phi, 1, 0.0));
    statuses.push(h.terminate());
    statuses.push(h.reset());
    assert_eq!(statuses.len(), 7 + 100 * 6 + 4 * 5 + 3);
    let records = h.log.records();
    assert!(statuses.iter().all(|s| *s == OK), "{statuses:?}: {records:#?}");
    assert!(records.is_empty(), "logging is off: {records:#?}");

    let s = h.step(0.0, dt);
    let records = h.take();
    assert_eq!(s, ERROR);
    assert_eq!(records.len(), 1, "{records:#?}");
    assert_eq!((records[0].status, records[0].category.as_str()), (ERROR, "logStatusError"));
    assert!(records[0].message.starts_with("fmi2DoStep: illegal call sequence"));
    stiff_fixed_step(&h);
    let s = h.step(0.0, 0.5);
    let records = h.take();
    assert_eq!(s, DISCARD);
    assert_eq!(records.len(), 1, "{records:#?}");
    assert_eq!((records[0].status, records[0].category.as_str()), (DISCARD, "logStatusDiscard"));
}

/// Debug logging on: each call gives exactly one record (none per internal step), in
/// category logCalls, naming the call and showing its arguments and outcome; errors come
/// in logStatusError instead. Switching categories one by one selects what comes out.
#[test]
fn with_logging_on_every_call_is_traced_once_with_its_arguments() {
    let _g = shared();
    let mut h = Host::new("traced");
    let one = |h: &Host, func: &str, status: fmi2Status, needles: &[&str]| {
        let records = h.take();
        assert_declared_categories(&records);
        assert_eq!(status, OK, "{func}: {records:#?}");
        assert_eq!(records.len(), 1, "{func}: one record per call: {records:#?}");
        let r = &records[0];
        assert_eq!((r.status, r.category.as_str()), (OK, "logCalls"), "{r:?}");
        assert!(r.message.starts_with(&format!("{func}: ")), "{func}: {r:?}");
        for n in needles {
            assert!(r.message.contains(n), "{func}: {n:?} not in {:?}", r.message);
        }
    };
    // nCategories = 0: all categories.
    let st = h.debug_logging(true, &[]);
    one(&h, "fmi2SetDebugLogging", st, &["loggingOn = true"]);
    let st = h.set_real(Var::Ei, 1200.0);
    one(&h, "fmi2SetReal", st, &[&format!("`EI` ({}) = 1200.0", vr(Var::Ei))]);
    let st = unsafe {
        fmi2SetInteger(h.c, [vr(Var::MaxOrder), vr(Var::PhiSource)].as_ptr(), 2, [4, 1].as_ptr())
    };
    one(&h, "fmi2SetInteger", st, &["`max_order`", "= 4", "`phi_source`", "= 1"]);
    let st = h.set_boolean(Var::StabilityGuard, true);
    one(&h, "fmi2SetBoolean", st, &["`stability_guard`", "= true"]);
    let st = h.setup(Some(1e-6), 0.0, Some(2.0));
    one(&h, "fmi2SetupExperiment", st, &["1e-6", "2.0"]);
    let st = h.enter();
    one(&h, "fmi2EnterInitializationMode", st, &["initialization mode"]);
    let (st, y) = h.get_reals(&[vr(Var::L), vr(Var::V1)]);
    one(&h, "fmi2GetReal", st, &["`l`", "= 2.5", "`v1`", &format!("= {:?}", y[1])]);
    let st = h.exit();
    one(&h, "fmi2ExitInitializationMode", st, &["t = 0.0"]);
    let dt = 0.01;
    let mut tc = 0.0;
    for _ in 0..100 {
        let st = h.set_real(Var::Phi, paper_phi(tc));
        one(&h, "fmi2SetReal", st, &["`phi`"]);
        let st = h.step(tc, dt);
        one(&h, "fmi2DoStep", st, &[&format!("tc = {tc}, h = {dt}")]);
        tc += dt;
    }
    let (st, ints) = h.get_integers(&[vr(Var::Formulation)]);
    let listed = format!("`formulation` ({}) = {}", vr(Var::Formulation), ints[0]);
    one(&h, "fmi2GetInteger", st, &[&listed]);
    let (st, _) = h.get_booleans(&[vr(Var::StabilityGuard)]);
    one(&h, "fmi2GetBoolean", st, &["`stability_guard`", "= true"]);
    let st = h.set_derivative(Var::Phi, 1, 0.5);
    one(&h, "fmi2SetRealInputDerivatives", st, &["order [1]", "value [0.5]"]);
    let (st, t) = h.real_status(LAST_SUCCESSFUL_TIME);
    one(&h, "fmi2GetRealStatus", st, &[&format!("fmi2LastSuccessfulTime = {t:?}")]);
    let st = h.boolean_status(TERMINATED).0;
    one(&h, "fmi2GetBooleanStatus", st, &["fmi2Terminated = false"]);
    let mut s: fmi2FMUstate = null_mut();
    let st = h.get_state(&mut s);
    one(&h, "fmi2GetFMUstate", st, &["state `step complete`", &format!("t = {t:?}")]);
    let mut size = 0;
    let st = unsafe { fmi2SerializedFMUstateSize(h.c, s, &mut size) };
    one(&h, "fmi2SerializedFMUstateSize", st, &[&format!("{size} bytes")]);
    let mut bytes = vec![0u8; size];
    let p = bytes.as_mut_ptr() as *mut fmi2Byte;
    let st = unsafe { fmi2SerializeFMUstate(h.c, s, p, size) };
    one(&h, "fmi2SerializeFMUstate", st, &[&format!("{size} bytes")]);
    let st = h.deserialize(&bytes, &mut s);
    one(&h, "fmi2DeSerializeFMUstate", st, &[&format!("{size} bytes"), "`step complete`"]);
    let st = h.set_state(s);
    one(&h, "fmi2SetFMUstate", st, &["restored"]);
    let st = h.free_state(&mut s);
    one(&h, "fmi2FreeFMUstate", st, &["a snapshot"]);
    let st = h.free_state(&mut s);
    one(&h, "fmi2FreeFMUstate", st, &["NULL"]);
    let st = h.terminate();
    one(&h, "fmi2Terminate", st, &[&format!("t = {t:?}")]);
    let st = h.reset();
    one(&h, "fmi2Reset", st, &["instantiated"]);

    // An error: one record, in logStatusError, not traced as well.
    let st = h.step(0.0, dt);
    let records = h.take();
    assert_eq!(st, ERROR);
    assert_eq!(records.len(), 1, "{records:#?}");
    assert_eq!(records[0].category, "logStatusError");

    // Only logStatusError: calls are no longer traced (switching logCalls off is silent),
    // errors still come out.
    assert_eq!(h.debug_logging(false, &[c"logAll"]), OK);
    assert_eq!(h.debug_logging(true, &[c"logStatusError"]), OK);
    assert!(h.take().is_empty());
    assert_eq!(h.setup(None, 0.0, None), OK);
    assert!(h.take().is_empty());
    let st = h.exit();
    h.expect_error(st, &["fmi2ExitInitializationMode", "illegal call sequence"]);
    // logCalls alone again.
    let st = h.debug_logging(true, &[c"logCalls"]);
    one(&h, "fmi2SetDebugLogging", st, &["logCalls"]);
    let st = h.enter();
    one(&h, "fmi2EnterInitializationMode", st, &[]);
    // fmi2FreeInstance is traced too.
    unsafe { fmi2FreeInstance(h.c) };
    h.c = null_mut();
    one(&h, "fmi2FreeInstance", OK, &["instance `traced`"]);
}

// ===== 13. version =============================================================================

#[test]
fn types_platform_and_version() {
    let platform = unsafe { CStr::from_ptr(fmi2GetTypesPlatform()) };
    assert_eq!(platform.to_str().unwrap(), "default");
    let version = unsafe { CStr::from_ptr(fmi2GetVersion()) };
    assert_eq!(version.to_str().unwrap(), "2.0");
}

// ===== 14. reset ===============================================================================

/// Sets the modified parameters of the reset test.
pub(crate) fn customize(h: &Host) {
    h.expect_ok(h.set_integer(Var::PhiSource, 2));
    h.expect_ok(h.set_real(Var::Ei, 1500.0));
    h.expect_ok(h.set_real(Var::G, 5.0));
    h.expect_ok(h.set_integer(Var::MaxOrder, 3));
    h.expect_ok(h.set_boolean(Var::StabilityGuard, false));
}

pub(crate) fn run_rows(h: &Host, n: usize) -> Vec<Vec<u64>> {
    (0..n)
        .map(|k| {
            h.expect_ok(h.step(k as f64 * 0.01, 0.01));
            bits(&h.outputs())
        })
        .collect()
}

#[test]
fn reset_returns_to_the_start_values() {
    let _g = shared();
    let h = Host::new("reset");
    customize(&h);
    h.expect_ok(h.setup(Some(1e-6), 0.0, Some(1.0)));
    h.expect_ok(h.enter());
    let rest = bits(&h.outputs());
    h.expect_ok(h.exit());
    let first = run_rows(&h, 30);

    h.expect_ok(h.reset());
    let st = h.get_reals(&[vr(Var::L)]).0;
    h.expect_error(st, &["fmi2GetReal", "illegal call sequence", "`instantiated`"]);
    h.expect_ok(h.setup(Some(1e-6), 0.0, Some(1.0)));
    h.expect_ok(h.enter());
    // Every parameter is back at its start value.
    for var in REAL_PARAMS.into_iter().chain([Var::Phi]) {
        assert_eq!(h.real(var).to_bits(), table_real(var).to_bits(), "{var:?}");
    }
    let (st, ints) = h.get_integers(&INT_PARAMS.map(vr));
    assert_eq!((st, ints), (OK, vec![1, 1, 5, 0, 3]));
    assert_eq!(h.get_booleans(&[vr(Var::StabilityGuard)]), (OK, vec![fmi2True]));
    // At rest.
    assert_eq!(h.real(Var::V1), 0.0);
    assert_eq!(h.real(Var::Dtheta1), 0.0);
    // The same parameters again, now in initialization mode: the same run, bit for bit.
    customize(&h);
    assert_eq!(bits(&h.outputs()), rest);
    h.expect_ok(h.exit());
    assert_eq!(run_rows(&h, 30), first);

    // Reset from stepFailed and from error works too.
    h.expect_ok(h.reset());
    fail_a_step(&h);
    h.expect_ok(h.reset());
    h.expect_ok(h.enter());
    assert_eq!(h.real(Var::V1), 0.0);
}

// ===== 15. functions that are not provided ======================================================

#[test]
fn unprovided_functions_log_and_return_error() {
    let _g = shared();
    let h = Host::law("unprovided");
    h.steps(0.0, 0.01, 1);
    let (u, k, dv, mut out) = ([vr(Var::V1)], [vr(Var::Phi)], [1.0], [7.0]);
    let st = unsafe {
        fmi2GetDirectionalDerivative(
            h.c,
            u.as_ptr(),
            1,
            k.as_ptr(),
            1,
            dv.as_ptr(),
            out.as_mut_ptr(),
        )
    };
    h.expect_error(st, &["fmi2GetDirectionalDerivative", "not provided"]);
    assert_eq!(out, [7.0], "nothing written");
    let st = unsafe { fmi2CancelStep(h.c) };
    h.expect_error(st, &["fmi2CancelStep"]);
    let mut status = -1;
    let st = unsafe { fmi2GetStatus(h.c, DO_STEP_STATUS, &mut status) };
    h.expect_error(st, &["fmi2GetStatus", "not provided"]);
    let mut int = -1;
    let st = unsafe { fmi2GetIntegerStatus(h.c, DO_STEP_STATUS, &mut int) };
    h.expect_error(st, &["fmi2GetIntegerStatus", "not provided"]);
    let mut string: fmi2String = null();
    let st = unsafe { fmi2GetStringStatus(h.c, PENDING_STATUS, &mut string) };
    h.expect_error(st, &["fmi2GetStringStatus", "not provided"]);
    // The provided status functions, with kinds they do not provide.
    let st = h.real_status(DO_STEP_STATUS).0;
    h.expect_error(st, &["fmi2GetRealStatus", "fmi2LastSuccessfulTime"]);
    let st = h.boolean_status(DO_STEP_STATUS).0;
    h.expect_error(st, &["fmi2GetBooleanStatus", "fmi2Terminated"]);
    // Still usable.
    h.steps(0.01, 0.01, 1);
}
