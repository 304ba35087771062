//! NULL arrays, bad value references, bad parameter values, fmi2DoStep's arguments.

use super::*;

// ===== 5. NULL arrays ==========================================================================

#[test]
fn null_arrays_with_elements_are_errors_and_without_are_fine() {
    let _g = shared();
    let h = Host::law("arrays");
    let rv = [vr(Var::Phi)];
    let iv = [vr(Var::Formulation)];
    let bv = [vr(Var::StabilityGuard)];
    let (mut r, mut i, mut b) = ([0.0], [0], [0]);
    let mut s: [fmi2String; 1] = [null()];
    let strings = [c"text".as_ptr()];
    let order = [1];
    // One by one, so each message is matched to its call.
    macro_rules! null_case {
        ($func:literal, $arg:literal, $call:expr) => {{
            let status = unsafe { $call };
            h.expect_error(status, &[concat!($func, ": argument `", $arg, "` is NULL")]);
        }};
    }
    null_case!("fmi2GetReal", "vr", fmi2GetReal(h.c, null(), 1, r.as_mut_ptr()));
    null_case!("fmi2GetReal", "value", fmi2GetReal(h.c, rv.as_ptr(), 1, null_mut()));
    null_case!("fmi2SetReal", "vr", fmi2SetReal(h.c, null(), 1, r.as_ptr()));
    null_case!("fmi2SetReal", "value", fmi2SetReal(h.c, rv.as_ptr(), 1, null()));
    null_case!("fmi2GetInteger", "vr", fmi2GetInteger(h.c, null(), 1, i.as_mut_ptr()));
    null_case!("fmi2GetInteger", "value", fmi2GetInteger(h.c, iv.as_ptr(), 1, null_mut()));
    null_case!("fmi2SetInteger", "vr", fmi2SetInteger(h.c, null(), 1, i.as_ptr()));
    null_case!("fmi2SetInteger", "value", fmi2SetInteger(h.c, iv.as_ptr(), 1, null()));
    null_case!("fmi2GetBoolean", "vr", fmi2GetBoolean(h.c, null(), 1, b.as_mut_ptr()));
    null_case!("fmi2GetBoolean", "value", fmi2GetBoolean(h.c, bv.as_ptr(), 1, null_mut()));
    null_case!("fmi2SetBoolean", "vr", fmi2SetBoolean(h.c, null(), 1, b.as_ptr()));
    null_case!("fmi2SetBoolean", "value", fmi2SetBoolean(h.c, bv.as_ptr(), 1, null()));
    null_case!("fmi2GetString", "vr", fmi2GetString(h.c, null(), 1, s.as_mut_ptr()));
    null_case!("fmi2GetString", "value", fmi2GetString(h.c, rv.as_ptr(), 1, null_mut()));
    null_case!("fmi2SetString", "vr", fmi2SetString(h.c, null(), 1, strings.as_ptr()));
    null_case!("fmi2SetString", "value", fmi2SetString(h.c, rv.as_ptr(), 1, null()));
    null_case!(
        "fmi2SetRealInputDerivatives",
        "vr",
        fmi2SetRealInputDerivatives(h.c, null(), 1, order.as_ptr(), r.as_ptr())
    );
    null_case!(
        "fmi2SetRealInputDerivatives",
        "order",
        fmi2SetRealInputDerivatives(h.c, rv.as_ptr(), 1, null(), r.as_ptr())
    );
    null_case!(
        "fmi2SetRealInputDerivatives",
        "value",
        fmi2SetRealInputDerivatives(h.c, rv.as_ptr(), 1, order.as_ptr(), null())
    );
    // A misaligned array is refused like NULL, never read or written.
    null_case!(
        "fmi2GetReal",
        "value",
        fmi2GetReal(h.c, rv.as_ptr(), 1, (r.as_mut_ptr() as *mut u8).add(1) as *mut f64)
    );
    null_case!(
        "fmi2SetReal",
        "vr",
        fmi2SetReal(h.c, (rv.as_ptr() as *const u8).add(1) as *const u32, 1, r.as_ptr())
    );
    null_case!(
        "fmi2GetRealStatus",
        "value",
        fmi2GetRealStatus(h.c, LAST_SUCCESSFUL_TIME, null_mut())
    );
    null_case!("fmi2GetBooleanStatus", "value", fmi2GetBooleanStatus(h.c, TERMINATED, null_mut()));
    null_case!("fmi2SetDebugLogging", "categories", fmi2SetDebugLogging(h.c, fmi2True, 2, null()));
    null_case!("fmi2GetFMUstate", "FMUstate", fmi2GetFMUstate(h.c, null_mut()));
    null_case!("fmi2FreeFMUstate", "FMUstate", fmi2FreeFMUstate(h.c, null_mut()));
    null_case!(
        "fmi2DeSerializeFMUstate",
        "serializedState",
        fmi2DeSerializeFMUstate(h.c, null(), 100, &mut null_mut())
    );
    let mut st: fmi2FMUstate = null_mut();
    h.expect_ok(h.get_state(&mut st));
    null_case!(
        "fmi2SerializedFMUstateSize",
        "size",
        fmi2SerializedFMUstateSize(h.c, st, null_mut())
    );
    null_case!(
        "fmi2SerializeFMUstate",
        "serializedState",
        fmi2SerializeFMUstate(h.c, st, null_mut(), 10_000)
    );
    h.expect_ok(h.free_state(&mut st));

    // nvr = 0: NULL arrays are fine and nothing is touched.
    unsafe {
        h.expect_ok(fmi2GetReal(h.c, null(), 0, null_mut()));
        h.expect_ok(fmi2SetReal(h.c, null(), 0, null()));
        h.expect_ok(fmi2GetInteger(h.c, null(), 0, null_mut()));
        h.expect_ok(fmi2SetInteger(h.c, null(), 0, null()));
        h.expect_ok(fmi2GetBoolean(h.c, null(), 0, null_mut()));
        h.expect_ok(fmi2SetBoolean(h.c, null(), 0, null()));
        h.expect_ok(fmi2GetString(h.c, null(), 0, null_mut()));
        h.expect_ok(fmi2SetString(h.c, null(), 0, null()));
        h.expect_ok(fmi2SetRealInputDerivatives(h.c, null(), 0, null(), null()));
        h.expect_ok(fmi2SetDebugLogging(h.c, fmi2False, 0, null()));
    }
    // The functions that are not provided refuse NULL arrays and pointers the same way as
    // valid ones, without reading or writing them.
    unsafe {
        let st = fmi2GetDirectionalDerivative(h.c, null(), 1, null(), 1, null(), null_mut());
        h.expect_error(st, &["fmi2GetDirectionalDerivative", "not provided"]);
        let st = fmi2GetRealOutputDerivatives(h.c, null(), 1, null(), null_mut());
        h.expect_error(st, &["fmi2GetRealOutputDerivatives", "`vr` is NULL"]);
        let st = fmi2GetStatus(h.c, DO_STEP_STATUS, null_mut());
        h.expect_error(st, &["fmi2GetStatus", "not provided"]);
        let st = fmi2GetIntegerStatus(h.c, DO_STEP_STATUS, null_mut());
        h.expect_error(st, &["fmi2GetIntegerStatus", "not provided"]);
        let st = fmi2GetStringStatus(h.c, PENDING_STATUS, null_mut());
        h.expect_error(st, &["fmi2GetStringStatus", "not provided"]);
    }
    // A state serialized into no buffer at all (size 0, NULL): too small, nothing written.
    let mut st: fmi2FMUstate = null_mut();
    h.expect_ok(h.get_state(&mut st));
    let s = unsafe { fmi2SerializeFMUstate(h.c, st, null_mut(), 0) };
    h.expect_error(s, &["fmi2SerializeFMUstate", "too small"]);
    h.expect_ok(h.free_state(&mut st));
    // The instance is still fine.
    h.steps(0.0, 0.01, 2);
}

// ===== 6. bad value references =================================================================

#[test]
fn bad_value_references_are_errors_naming_the_variable() {
    let _g = shared();
    let h = Host::new("vrs");
    h.expect_ok(h.setup(None, 0.0, None));
    h.expect_ok(h.enter());

    let n = VARIABLES.len() as u32;
    for bad in [9999, n, u32::MAX] {
        let msg = format!("unknown value reference {bad}");
        let s = h.get_reals(&[bad]).0;
        h.expect_error(s, &["fmi2GetReal", &msg]);
        let s = h.set_reals(&[bad], &[1.0]);
        h.expect_error(s, &["fmi2SetReal", &msg]);
        let s = h.get_integers(&[bad]).0;
        h.expect_error(s, &["fmi2GetInteger", &msg]);
        let s = h.get_booleans(&[bad]).0;
        h.expect_error(s, &["fmi2GetBoolean", &msg]);
        let s = unsafe { fmi2SetInteger(h.c, [bad].as_ptr(), 1, [1].as_ptr()) };
        h.expect_error(s, &["fmi2SetInteger", &msg]);
        let s = unsafe { fmi2SetBoolean(h.c, [bad].as_ptr(), 1, [1].as_ptr()) };
        h.expect_error(s, &["fmi2SetBoolean", &msg]);
    }
    // A bad reference after good ones fails the whole call.
    let s = h.get_reals(&[vr(Var::L), vr(Var::V1), 9999]).0;
    h.expect_error(s, &["9999"]);

    // Wrong type.
    let s = h.get_integers(&[vr(Var::L)]).0;
    h.expect_error(s, &["fmi2GetInteger", "`l`", "Real"]);
    let s = h.get_reals(&[vr(Var::Formulation)]).0;
    h.expect_error(s, &["fmi2GetReal", "`formulation`", "Integer"]);
    let s = h.get_reals(&[vr(Var::MaxOrder)]).0;
    h.expect_error(s, &["fmi2GetReal", "`max_order`"]);
    let s = h.get_booleans(&[vr(Var::V1)]).0;
    h.expect_error(s, &["fmi2GetBoolean", "`v1`", "Real"]);
    let s = h.get_reals(&[vr(Var::StabilityGuard)]).0;
    h.expect_error(s, &["fmi2GetReal", "`stability_guard`", "Boolean"]);
    let s = unsafe { fmi2SetInteger(h.c, [vr(Var::Ei)].as_ptr(), 1, [5].as_ptr()) };
    h.expect_error(s, &["fmi2SetInteger", "`EI`"]);
    let s = h.set_boolean(Var::Phi, true);
    h.expect_error(s, &["fmi2SetBoolean", "`phi`"]);
    let mut out: [fmi2String; 1] = [null()];
    let s = unsafe { fmi2GetString(h.c, [vr(Var::V1)].as_ptr(), 1, out.as_mut_ptr()) };
    h.expect_error(s, &["fmi2GetString", "`v1`"]);
    let s = unsafe { fmi2SetString(h.c, [vr(Var::L)].as_ptr(), 1, [c"2".as_ptr()].as_ptr()) };
    h.expect_error(s, &["fmi2SetString", "`l`"]);

    // Outputs cannot be set, in any state.
    for var in [Var::V1, Var::Energy, Var::DdphiApplied] {
        let s = h.set_real(var, 0.0);
        h.expect_error(s, &["fmi2SetReal", &format!("`{}`", var.info().name), "output"]);
    }
    // Parameters can be set in initialization mode.
    h.expect_ok(h.set_real(Var::Ei, 1200.0));
    h.expect_ok(h.exit());
    let s = h.set_real(Var::V1, 0.0);
    h.expect_error(s, &["cannot set `v1`", "output"]);

    // stepComplete: fixed parameters are refused, the input is accepted.
    let s = h.set_real(Var::Ei, 2000.0);
    h.expect_error(s, &["fmi2SetReal", "`EI`", "fixed parameter"]);
    assert_eq!(h.real(Var::Ei), 1200.0);
    let s = h.set_integer(Var::Formulation, 2);
    h.expect_error(s, &["fmi2SetInteger", "`formulation`", "fixed parameter"]);
    let s = h.set_boolean(Var::StabilityGuard, false);
    h.expect_error(s, &["fmi2SetBoolean", "`stability_guard`", "fixed parameter"]);
    h.expect_ok(h.set_real(Var::Phi, 0.25));
    assert_eq!(h.real(Var::Phi), 0.25);
    // All or nothing: phi is not set when EI in the same call is refused.
    let s = h.set_reals(&[vr(Var::Phi), vr(Var::Ei)], &[0.5, 2000.0]);
    h.expect_error(s, &["`EI`"]);
    assert_eq!(h.real(Var::Phi), 0.25);
    h.steps(0.0, 0.01, 2);
}

/// Every variable through each of the 8 get and set functions of another base type (and
/// both string functions: the model has no strings): fmi2Error naming the function, the
/// variable and its type; no value changes. Unknown references for the string functions too.
#[test]
fn every_get_and_set_of_the_wrong_type_is_refused_naming_the_variable() {
    let _g = shared();
    let h = Host::new("types");
    h.expect_ok(h.setup(None, 0.0, None));
    h.expect_ok(h.enter()); // initialization mode: every get and set is allowed
    let all = |h: &Host| {
        let of = |base: BaseType| -> Vec<fmi2ValueReference> {
            fmi2_variables().filter(|v| v.ty.base() == base).map(|v| v.vr()).collect()
        };
        let (s1, reals) = h.get_reals(&of(BaseType::Real));
        let (s2, ints) = h.get_integers(&of(BaseType::Integer));
        let (s3, bools) = h.get_booleans(&of(BaseType::Boolean));
        assert_eq!((s1, s2, s3), (OK, OK, OK), "{:#?}", h.take());
        (bits(&reals), ints, bools)
    };
    let before = all(&h);
    let mut refused = 0;
    for var in fmi2_variables() {
        let base = var.ty.base();
        let vrs = [var.vr()];
        let needles = |func: &'static str| {
            let a = if base == BaseType::Integer { "an" } else { "a" };
            [func, &format!("`{}`", var.name), &format!("{a} {base:?} variable")].map(String::from)
        };
        let mut check = |func: &'static str, status: fmi2Status| {
            let n = needles(func);
            h.expect_error(status, &[n[0].as_str(), n[1].as_str(), n[2].as_str()]);
            refused += 1;
        };
        unsafe {
            if base != BaseType::Real {
                check("fmi2GetReal", h.get_reals(&vrs).0);
                check("fmi2SetReal", h.set_reals(&vrs, &[1.0]));
            }
            if base != BaseType::Integer {
                check("fmi2GetInteger", h.get_integers(&vrs).0);
                check("fmi2SetInteger", fmi2SetInteger(h.c, vrs.as_ptr(), 1, [1].as_ptr()));
            }
            if base != BaseType::Boolean {
                check("fmi2GetBoolean", h.get_booleans(&vrs).0);
                check("fmi2SetBoolean", fmi2SetBoolean(h.c, vrs.as_ptr(), 1, [1].as_ptr()));
            }
            let mut out: [fmi2String; 1] = [null()];
            check("fmi2GetString", fmi2GetString(h.c, vrs.as_ptr(), 1, out.as_mut_ptr()));
            assert!(out[0].is_null());
            let text = [c"1".as_ptr()];
            check("fmi2SetString", fmi2SetString(h.c, vrs.as_ptr(), 1, text.as_ptr()));
        }
    }
    // Each variable: 2 functions of each of the 2 other numeric types, and 2 string ones.
    assert_eq!(refused, fmi2_variables().count() * 6);
    for bad in [VARIABLES.len() as u32, 9999, u32::MAX] {
        let msg = format!("unknown value reference {bad}");
        let mut out: [fmi2String; 1] = [null()];
        let s = unsafe { fmi2GetString(h.c, [bad].as_ptr(), 1, out.as_mut_ptr()) };
        h.expect_error(s, &["fmi2GetString", &msg]);
        let s = unsafe { fmi2SetString(h.c, [bad].as_ptr(), 1, [c"1".as_ptr()].as_ptr()) };
        h.expect_error(s, &["fmi2SetString", &msg]);
    }
    assert_eq!(all(&h), before, "no value changed");
    h.expect_ok(h.exit());
}

// ===== 7. bad parameter values ==================================================================

#[test]
fn out_of_range_parameters_are_refused_and_leave_values_unchanged() {
    let _g = shared();
    let h = Host::plain("ranges");
    let name = |var: Var| format!("`{}`", var.info().name);

    // Non-finite values, for every real parameter and the input.
    for var in REAL_PARAMS.into_iter().chain([Var::Phi]) {
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let s = h.set_real(var, x);
            h.expect_error(s, &["fmi2SetReal", &name(var), "finite"]);
        }
    }
    // Range limits: (variable, refused value, words of the allowed range).
    let refused: &[(Var, f64, &str)] = &[
        (Var::L, 0.0, "positive"),
        (Var::L, -1.0, "positive"),
        (Var::Ei, 0.0, "positive"),
        (Var::Ei, -1e3, "positive"),
        (Var::M2, 0.0, "positive"),
        (Var::M, -1.0, "non-negative"),
        (Var::JC, -1e-9, "non-negative"),
        (Var::R, -0.5, "non-negative"),
        (Var::TRot, 0.0, "positive"),
        (Var::TRot, -1.0, "positive"),
        (Var::Atol, -1e-6, "non-negative"),
        (Var::FixedStep, -0.01, "non-negative"),
        (Var::DampingAlpha, -0.1, "non-negative"),
        (Var::DampingBeta, -1e-4, "non-negative"),
        (Var::DampingRatio, -0.02, "non-negative"),
    ];
    for &(var, x, allowed) in refused {
        let s = h.set_real(var, x);
        h.expect_error(s, &["fmi2SetReal", &name(var), "out of range", allowed]);
    }
    let int_refused: &[(Var, i32, &str)] = &[
        (Var::Formulation, 0, "one of 1 (reduced), 2 (dae), 3 (dae_stabilized), 4 (linear)"),
        (Var::Formulation, 5, "one of 1 (reduced)"),
        (Var::PhiSource, 0, "one of 1 (input), 2 (law)"),
        (Var::PhiSource, 3, "one of 1 (input), 2 (law)"),
        (Var::MaxOrder, 0, "1..=5"),
        (Var::MaxOrder, 6, "1..=5"),
        (Var::FixedOrder, -1, "0..=5"),
        (Var::FixedOrder, 6, "0..=5"),
        (Var::PhiExtrapolation, -1, "0..=3"),
        (Var::PhiExtrapolation, 4, "0..=3"),
        (Var::NElements, 0, "1..=32"),
        (Var::NElements, 33, "1..=32"),
    ];
    for &(var, k, allowed) in int_refused {
        let s = h.set_integer(var, k);
        h.expect_error(s, &["fmi2SetInteger", &name(var), "out of range", allowed]);
    }
    // All or nothing: l = 3 is not kept when EI = NaN in the same call is refused.
    let s = h.set_reals(&[vr(Var::L), vr(Var::Ei)], &[3.0, f64::NAN]);
    h.expect_error(s, &["`EI`", "finite"]);
    let s = h.set_reals(&[vr(Var::Ei), vr(Var::L)], &[2000.0, 0.0]);
    h.expect_error(s, &["`l`", "positive"]);
    let s = unsafe {
        fmi2SetInteger(h.c, [vr(Var::MaxOrder), vr(Var::Formulation)].as_ptr(), 2, [3, 9].as_ptr())
    };
    h.expect_error(s, &["`formulation`"]);

    // The boundaries that are allowed.
    for (var, x) in [(Var::M, 0.0), (Var::JC, 0.0), (Var::R, 0.0), (Var::G, -10.0)] {
        h.expect_ok(h.set_real(var, x));
        h.expect_ok(h.set_real(var, table_real(var)));
    }

    // Nothing changed: every parameter reads back as its start value.
    h.expect_ok(h.enter());
    // Initialization mode refuses the same values.
    let s = h.set_real(Var::L, -1.0);
    h.expect_error(s, &["`l`"]);
    let s = h.set_integer(Var::MaxOrder, 6);
    h.expect_error(s, &["`max_order`"]);
    let vrs: Vec<u32> = REAL_PARAMS.into_iter().chain([Var::Phi]).map(vr).collect();
    let (s, got) = h.get_reals(&vrs);
    assert_eq!(s, OK);
    for (var, x) in REAL_PARAMS.into_iter().chain([Var::Phi]).zip(got) {
        assert_eq!(x.to_bits(), table_real(var).to_bits(), "{var:?}");
    }
    assert_eq!(h.real(Var::L), 2.5);
    let (s, ints) = h.get_integers(&INT_PARAMS.map(vr));
    assert_eq!(s, OK);
    for (var, k) in INT_PARAMS.into_iter().zip(ints) {
        let start = match var.info().ty {
            Type::Integer { start, .. } | Type::Enumeration { start, .. } => start,
            _ => unreachable!(),
        };
        assert_eq!(k, start, "{var:?}");
    }
    h.expect_ok(h.exit());
}

/// The range of a real parameter or the input, as the refusals state it.
pub(crate) fn real_range(var: Var) -> &'static str {
    match var {
        Var::L | Var::Ei | Var::M2 | Var::TRot => "positive and finite",
        Var::M | Var::JC | Var::R | Var::Atol | Var::FixedStep => "non-negative and finite",
        Var::G | Var::PhiEnd | Var::Phi => "finite",
        Var::Phi0 | Var::V10 | Var::Theta10 | Var::Dv10 | Var::Dtheta10 => "finite",
        other => panic!("{other:?} is not a real parameter or input"),
    }
}

/// NaN and ±Inf for every real parameter and the input, in every state where they may be
/// set: refused with a message naming the variable, the value and its whole allowed range
/// (`EI` = NaN: "must be positive and finite", not just "finite"); the value is unchanged.
#[test]
fn non_finite_values_are_refused_with_the_whole_range_and_change_nothing() {
    let _g = shared();
    let non_finite = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
    let h = Host::new("non-finite");
    for mode in ["instantiated", "initialization mode"] {
        if mode == "initialization mode" {
            h.expect_ok(h.setup(None, 0.0, None));
            h.expect_ok(h.enter());
        }
        for var in REAL_PARAMS.into_iter().chain([Var::Phi]) {
            for x in non_finite {
                let s = h.set_real(var, x);
                let value = format!("`{}` = {x:?}", var.info().name);
                let range = format!("out of range: must be {}", real_range(var));
                let r = h.expect_error(s, &["fmi2SetReal: ", &value, &range]);
                assert!(r.message.ends_with(real_range(var)), "{mode}: {}", r.message);
            }
        }
    }
    for var in REAL_PARAMS.into_iter().chain([Var::Phi]) {
        assert_eq!(h.real(var).to_bits(), table_real(var).to_bits(), "{var:?}");
    }
    // stepComplete: the input is refused the same way and keeps its value; a fixed
    // parameter is refused as such whatever its value.
    h.expect_ok(h.exit());
    h.expect_ok(h.set_real(Var::Phi, 0.125));
    for x in non_finite {
        let s = h.set_real(Var::Phi, x);
        h.expect_error(s, &["fmi2SetReal: ", &format!("`phi` = {x:?}"), "must be finite"]);
        assert_eq!(h.real(Var::Phi), 0.125);
        let s = h.set_real(Var::Ei, x);
        h.expect_error(s, &["fmi2SetReal", "`EI`", "fixed parameter"]);
        for order in [1, 2] {
            let s = h.set_derivative(Var::Phi, order, x);
            let needle = format!("order {order} of `phi` = {x}");
            h.expect_error(s, &["fmi2SetRealInputDerivatives", &needle, "must be finite"]);
        }
    }
    assert_eq!(h.real(Var::Ei), 1000.0);
    h.expect_ok(h.step(0.0, 0.01));
    assert_eq!(h.real(Var::Phi), 0.125);
}

// ===== 8. fmi2DoStep arguments ==================================================================

#[test]
fn do_step_checks_its_arguments() {
    let _g = shared();
    let h = Host::law("dostep");
    let t = h.steps(0.0, 0.01, 1);
    assert_eq!(t, 0.01);
    for dt in [0.0, -0.0, -0.01, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let s = h.step(t, dt);
        h.expect_error(s, &["fmi2DoStep", "communicationStepSize", "positive"]);
    }
    for tc in [t + 1e-3, t - 1e-3, 0.0, f64::NAN, f64::INFINITY] {
        let s = h.step(tc, 0.01);
        h.expect_error(s, &["fmi2DoStep", "currentCommunicationPoint", "does not match"]);
    }
    // A step below the resolution of t would not advance: refused, not taken as a no-op.
    let s = h.step(t, 1e-30);
    h.expect_error(s, &["fmi2DoStep", "communicationStepSize = 1e-30", "would not advance"]);
    // The failed calls left the instance in stepComplete at t.
    assert_eq!(h.real_status(LAST_SUCCESSFUL_TIME), (OK, t));
    // Rounding of the host's tc is tolerated: one ulp either way.
    let up = f64::from_bits(t.to_bits() + 1);
    h.expect_ok(h.step(up, 0.01));
    let t = up + 0.01;
    let down = f64::from_bits(t.to_bits() - 1);
    h.expect_ok(h.step(down, 0.01));
    let t = down + 0.01;
    // A variable step size (canHandleVariableCommunicationStepSize).
    h.expect_ok(h.step(t, 0.0037));
    let (s, last) = h.real_status(LAST_SUCCESSFUL_TIME);
    assert_eq!(s, OK);
    assert!((last - (t + 0.0037)).abs() < 1e-15);
}

#[test]
fn do_step_respects_a_defined_stop_time_only() {
    let _g = shared();
    let h = Host::new("stop");
    h.expect_ok(h.set_integer(Var::PhiSource, 2));
    h.expect_ok(h.setup(Some(1e-6), 0.0, Some(0.05)));
    h.expect_ok(h.enter());
    h.expect_ok(h.exit());
    let mut t = 0.0;
    for _ in 0..5 {
        h.expect_ok(h.step(t, 0.01)); // sums: 0.05000000000000001 is "at" stopTime
        t += 0.01;
    }
    let s = h.step(t, 0.01);
    h.expect_error(s, &["fmi2DoStep", "stopTime = 0.05"]);
    let s = h.step(t, 1e-6);
    h.expect_error(s, &["stopTime"]);
    h.expect_ok(h.terminate());

    // No stopTime: no limit, not even the DefaultExperiment's.
    let free = Host::new("no stop");
    free.expect_ok(free.set_integer(Var::PhiSource, 2));
    let start = DEFAULT_EXPERIMENT.stop_time - 0.1;
    free.expect_ok(free.setup(None, start, None));
    free.expect_ok(free.enter());
    free.expect_ok(free.exit());
    free.expect_ok(free.step(start, 0.5));
    assert!(free.real_status(LAST_SUCCESSFUL_TIME).1 > DEFAULT_EXPERIMENT.stop_time);

    // fmi2SetupExperiment's own checks.
    let bad = Host::new("setup");
    for (tol, start, stop, needle) in [
        (Some(0.0), 0.0, None, "tolerance"),
        (Some(f64::NAN), 0.0, None, "tolerance"),
        (Some(2.0), 0.0, None, "tolerance"),
        (None, f64::NAN, None, "startTime"),
        (None, f64::INFINITY, None, "startTime"),
        (None, 1.0, Some(0.5), "stopTime"),
        (None, 0.0, Some(f64::INFINITY), "stopTime"),
    ] {
        let s = bad.setup(tol, start, stop);
        bad.expect_error(s, &["fmi2SetupExperiment", needle, "out of range"]);
    }
    bad.expect_ok(bad.setup(None, 0.0, Some(0.0)));
}

/// The variables of FMI 2.0's model description (FMI 3.0's arrays are not among them).
fn fmi2_variables() -> impl Iterator<Item = &'static beam_body::fmu::variables::Variable> {
    VARIABLES.iter().filter(|v| v.in_version(beam_body::fmi::Version::Fmi2))
}

/// FMI 3.0's arrays are refused by an FMI 2.0 instance, naming the version.
#[test]
fn fmi3_s_arrays_are_not_fmi2_s() {
    let _g = shared();
    let h = Host::new("arrays");
    h.expect_ok(h.setup(None, 0.0, None));
    h.expect_ok(h.enter());
    for var in VARIABLES.iter().filter(|v| !v.in_version(beam_body::fmi::Version::Fmi2)) {
        let s = h.get_reals(&[var.vr()]).0;
        h.expect_error(s, &["fmi2GetReal", &format!("`{}`", var.name), "FMI 3.0's only"]);
    }
}
