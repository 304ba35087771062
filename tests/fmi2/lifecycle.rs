//! The lifecycle, and fmi2Instantiate's arguments.

use super::*;

// ===== 1. lifecycle =============================================================================

#[test]
fn lifecycle_with_the_built_in_law() {
    let _g = shared();
    let h = Host::new("law");
    h.expect_ok(h.set_integer(Var::PhiSource, 2));
    h.expect_ok(h.setup(Some(1e-6), 0.0, Some(1.0)));
    h.expect_ok(h.enter());
    // Initialization mode: the outputs of the start state, at rest.
    let y0 = h.outputs();
    assert!(y0.iter().all(|x| x.is_finite()), "{y0:?}");
    assert_eq!(h.real(Var::V1), 0.0);
    assert_eq!(h.real(Var::Dv1), 0.0);
    assert_eq!(h.real(Var::Theta1), 0.0);
    assert_eq!(h.real(Var::PhiApplied), 0.0);
    let (s, src) = h.get_integers(&[vr(Var::PhiSource)]);
    assert_eq!((s, src[0]), (OK, 2));
    h.expect_ok(h.exit());
    assert_eq!(h.real(Var::V1), 0.0, "still at rest at t = 0");

    let dt = 0.01;
    for k in 0..100 {
        h.expect_ok(h.step(k as f64 * dt, dt));
    }
    let y = h.outputs();
    assert!(y.iter().all(|x| x.is_finite()), "{y:?}");
    let v1 = h.real(Var::V1);
    assert!(v1 != 0.0 && v1.abs() < 1.0, "v1 = {v1}");
    // t = 1 > t_rot: the turn is over and φ is held at π.
    assert!((h.real(Var::PhiApplied) - PI).abs() < 1e-12);
    assert_eq!(h.real(Var::DphiApplied), 0.0);
    assert_eq!(h.real_status(LAST_SUCCESSFUL_TIME), (OK, 100.0 * dt));
    assert_eq!(h.boolean_status(TERMINATED), (OK, fmi2False));
    h.expect_ok(h.terminate());
    assert_eq!(h.real(Var::V1), v1, "outputs stay readable after fmi2Terminate");
    assert!(h.take().is_empty(), "logging is off: nothing is logged");
}

/// φ from the host: the paper's law sampled at each communication point and held (no
/// derivatives), as FMPy's simulate_fmu sends it. The FMU reconstructs φ', φ'' from values.
#[test]
fn lifecycle_with_the_input() {
    let _g = shared();
    let dt = 0.01;
    let n = 100;
    let input = Host::new("input");
    input.initialize(); // phi_source defaults to input
    let law = Host::law("law");
    for k in 0..n {
        let tc = k as f64 * dt;
        input.expect_ok(input.set_real(Var::Phi, paper_phi(tc)));
        assert_eq!(input.real(Var::Phi), paper_phi(tc));
        input.expect_ok(input.step(tc, dt));
        law.expect_ok(law.step(tc, dt));
    }
    let y = input.outputs();
    assert!(y.iter().all(|x| x.is_finite()), "{y:?}");
    let (vi, vl) = (input.real(Var::V1), law.real(Var::V1));
    assert!(vi != 0.0);
    // φ reconstructed from the host's samples follows the law closely (6e-4 relative when
    // written; φ'' is only approximated from values).
    assert!((vi - vl).abs() < 5e-3 * vl.abs(), "input {vi} vs law {vl}");
    assert!((input.real(Var::PhiApplied) - PI).abs() < 1e-9);
    input.expect_ok(input.terminate());
}

// ===== 2. fmi2Instantiate ======================================================================

/// Calls fmi2Instantiate; a non-NULL result is freed and reported as a failure.
pub(crate) fn instantiate_expecting_null(
    name: fmi2String,
    fmu_type: fmi2Type,
    guid: fmi2String,
    functions: *const fmi2CallbackFunctions,
) {
    let c =
        unsafe { fmi2Instantiate(name, fmu_type, guid, null(), functions, fmi2False, fmi2False) };
    if !c.is_null() {
        unsafe { fmi2FreeInstance(c) };
        panic!("fmi2Instantiate should have returned NULL");
    }
}

/// The single error record of a failed instantiation.
#[track_caller]
pub(crate) fn single_error(log: &Collector, name: &str, needles: &[&str]) {
    let records = log.take();
    assert_declared_categories(&records);
    assert_eq!(records.len(), 1, "{records:#?}");
    let r = &records[0];
    assert_eq!((r.status, r.category.as_str(), r.name.as_str()), (ERROR, "logStatusError", name));
    for n in needles {
        assert!(r.message.contains(n), "{n:?} not in {:?}", r.message);
    }
}

#[test]
fn instantiate_returns_null_for_bad_arguments() {
    let _g = shared();
    let log = Box::<Collector>::default();
    let cb = callbacks(log.env());
    let g = guid_c();
    let name = c"inst";

    // NULL functions: no logger to tell.
    instantiate_expecting_null(name.as_ptr(), CO_SIMULATION, g.as_ptr(), null());

    // NULL logger: nobody to tell either, and the other callbacks are not used.
    let no_logger = fmi2CallbackFunctions {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: log.env(),
    };
    instantiate_expecting_null(name.as_ptr(), CO_SIMULATION, g.as_ptr(), &no_logger);
    assert!(log.take().is_empty());

    instantiate_expecting_null(null(), CO_SIMULATION, g.as_ptr(), &*cb);
    single_error(&log, "(null)", &["fmi2Instantiate", "instanceName is NULL"]);

    instantiate_expecting_null(c"".as_ptr(), CO_SIMULATION, g.as_ptr(), &*cb);
    single_error(&log, "", &["fmi2Instantiate", "instanceName is empty"]);

    let wrong = c"{00000000-0000-0000-0000-000000000000}";
    instantiate_expecting_null(name.as_ptr(), CO_SIMULATION, wrong.as_ptr(), &*cb);
    single_error(&log, "inst", &["GUID", wrong.to_str().unwrap(), guid()]);

    instantiate_expecting_null(name.as_ptr(), CO_SIMULATION, null(), &*cb);
    single_error(&log, "inst", &["GUID", "(null)"]);

    // A GUID that differs only by case, or by missing braces, is still wrong.
    let upper = CString::new(guid().to_uppercase()).unwrap();
    if upper.as_bytes() != guid().as_bytes() {
        instantiate_expecting_null(name.as_ptr(), CO_SIMULATION, upper.as_ptr(), &*cb);
        single_error(&log, "inst", &["GUID"]);
    }
    let bare = CString::new(guid().trim_matches(|c| c == '{' || c == '}')).unwrap();
    instantiate_expecting_null(name.as_ptr(), CO_SIMULATION, bare.as_ptr(), &*cb);
    single_error(&log, "inst", &["GUID"]);

    instantiate_expecting_null(name.as_ptr(), 7, g.as_ptr(), &*cb);
    single_error(&log, "inst", &["fmuType = 7", "fmi2ModelExchange (0) or fmi2CoSimulation (1)"]);
}

#[test]
fn instantiate_keeps_its_own_copy_of_the_name() {
    let _g = shared();
    let log = Box::<Collector>::default();
    let callbacks = callbacks(log.env());
    let g = guid_c();
    let raw: *mut c_char = CString::new("original").unwrap().into_raw();
    let c = unsafe {
        fmi2Instantiate(raw, CO_SIMULATION, g.as_ptr(), null(), &*callbacks, fmi2False, fmi2False)
    };
    assert!(!c.is_null());
    // The host overwrites and frees its buffer.
    unsafe {
        for k in 0..8 {
            *raw.add(k) = b'Z' as c_char;
        }
        drop(CString::from_raw(raw));
    }
    let _junk: Vec<CString> = (0..64).map(|_| CString::new("garbage!").unwrap()).collect();
    let h = Host { c, name: "original".into(), log, callbacks };
    let status = h.step(0.0, 0.01); // illegal in `instantiated`
    let r = h.expect_error(status, &["fmi2DoStep", "illegal call sequence"]);
    assert_eq!(r.name, "original");
}

#[test]
fn instantiate_with_logging_on_traces_calls() {
    let _g = shared();
    let h = Host::with_logging("traced", true);
    let records = h.take();
    assert_declared_categories(&records);
    assert!(
        records.iter().any(|r| r.status == OK
            && r.category == "logCalls"
            && r.message.contains("fmi2Instantiate")
            && r.message.contains("traced")),
        "{records:#?}"
    );
}

/// visible and loggingOn take any fmi2Boolean (non-zero is true; visible is ignored), with
/// or without a resource location. loggingOn decides whether calls are traced from the
/// start: not at all when false, fmi2Instantiate itself and the calls after when true.
#[test]
fn instantiate_accepts_every_visible_and_logging_on_value() {
    let _g = shared();
    let g = guid_c();
    let resources = c"file:///tmp/beam_body/resources";
    for visible in [fmi2False, fmi2True, 2] {
        for logging_on in [fmi2False, fmi2True, -1] {
            for location in [null(), resources.as_ptr()] {
                let what = format!("visible {visible}, loggingOn {logging_on}, {location:?}");
                let log = Box::<Collector>::default();
                let callbacks = callbacks(log.env());
                let c = unsafe {
                    fmi2Instantiate(
                        c"variant".as_ptr(),
                        CO_SIMULATION,
                        g.as_ptr(),
                        location,
                        &*callbacks,
                        visible,
                        logging_on,
                    )
                };
                assert!(!c.is_null(), "{what}: {:#?}", log.records());
                let h = Host { c, name: "variant".into(), log, callbacks };
                let traced = logging_on != fmi2False;
                let records = h.take();
                if traced {
                    assert_eq!(records.len(), 1, "{what}: {records:#?}");
                    let r = &records[0];
                    assert_eq!((r.status, r.category.as_str()), (OK, "logCalls"), "{what}");
                    assert_eq!(r.message, "fmi2Instantiate: instance `variant`", "{what}");
                } else {
                    assert!(records.is_empty(), "{what}: {records:#?}");
                }
                let st = h.setup(Some(1e-6), 0.0, None);
                let records = h.take();
                assert_eq!(st, OK, "{what}: {records:#?}");
                let setup_traced =
                    records.iter().any(|r| r.message.starts_with("fmi2SetupExperiment: "));
                assert_eq!(setup_traced, traced, "{what}: {records:#?}");
                h.expect_ok(h.enter());
                h.expect_ok(h.exit());
                let st = h.set_real(Var::Phi, 0.0);
                h.take();
                assert_eq!(st, OK, "{what}");
                h.expect_ok(h.step(0.0, 0.01));
            }
        }
    }
}
