//! A failing step, and the input's derivatives.

use super::*;

// ===== 9. a failing step =======================================================================

#[track_caller]
pub(crate) fn check_failed_state(h: &Host, tc: f64, dt: f64) {
    assert_eq!(h.boolean_status(TERMINATED), (OK, fmi2True));
    let (s, last) = h.real_status(LAST_SUCCESSFUL_TIME);
    assert_eq!(s, OK);
    assert!(
        last >= tc && last < tc + dt,
        "fmi2LastSuccessfulTime = {last}, step [{tc}, {})",
        tc + dt
    );
    let y = h.outputs();
    assert!(y.iter().all(|x| x.is_finite()), "outputs in stepFailed: {y:?}");
    // No further step; a rollback or fmi2Terminate is what a host can do.
    let s = h.step(last, dt);
    h.expect_error(s, &["fmi2DoStep", "illegal call sequence", "`step failed`"]);
    h.expect_ok(h.terminate());
    assert_eq!(h.boolean_status(TERMINATED), (OK, fmi2True));
    assert_eq!(h.outputs().len(), y.len());
}

#[test]
fn a_step_that_cannot_be_integrated_is_discarded() {
    let _g = shared();
    // (a) The paper's fixed-step BDF5, too large a step for a stiff beam: Newton fails.
    let f = Host::new("fixed");
    stiff_fixed_step(&f);
    assert_eq!(f.boolean_status(TERMINATED), (OK, fmi2False));
    let s = f.step(0.0, 0.5);
    let r = f.expect_status(s, DISCARD, &["fmi2DoStep: integration failed: ", "Newton"]);
    assert_eq!(r.category, "logStatusDiscard");
    assert!(r.message.contains("fmi2Terminated = true"), "{}", r.message);
    check_failed_state(&f, 0.0, 0.5);

    // (b) φ as an input jumps to 10¹⁵ rad between two communication points 1 ms apart.
    // (Jumps of 10⁶ to 10¹² rad do fail too, but only after the integrator's 10⁶ internal
    // steps: 15 to 80 s in a debug build.)
    let h = Host::new("jump");
    let st = h.real_status(LAST_SUCCESSFUL_TIME).0;
    h.expect_error(st, &["illegal call sequence", "`instantiated`"]);
    let dt = 1e-3;
    let tc = jump_to(&h, JUMP);
    let s = h.step(tc, dt);
    let r = h.expect_status(s, DISCARD, &["fmi2DoStep: integration failed: ", "fmi2Terminated"]);
    assert_eq!(r.category, "logStatusDiscard");
    assert!(
        ["Newton", "singular", "not finite", "step size"].iter().any(|w| r.message.contains(w)),
        "the message names the cause: {}",
        r.message
    );
    check_failed_state(&h, tc, dt);

    // A host may roll back a failed step to a state saved before it.
    let g = Host::new("rollback");
    g.initialize();
    g.expect_ok(g.set_real(Var::Phi, 0.0));
    g.expect_ok(g.step(0.0, dt));
    let y = bits(&g.outputs());
    let mut saved: fmi2FMUstate = null_mut();
    g.expect_ok(g.get_state(&mut saved));
    g.expect_ok(g.set_real(Var::Phi, JUMP));
    let s = g.step(dt, dt);
    g.expect_status(s, DISCARD, &["fmi2DoStep: ", "The FMU stopped at"]);
    g.expect_ok(g.set_state(saved));
    assert_eq!(g.boolean_status(TERMINATED), (OK, fmi2False));
    assert_eq!(bits(&g.outputs()), y);
    g.expect_ok(g.set_real(Var::Phi, 0.0));
    g.expect_ok(g.step(dt, dt));
    g.expect_ok(g.free_state(&mut saved));
}

/// The jump of the input φ that makes a step fail fast.
pub(crate) const JUMP: f64 = 1e15;

/// Input mode; steps [0, 1 ms] and [1, 2 ms] with φ = 0, then sets φ = `jump`. Returns
/// the next communication point, 2 ms.
pub(crate) fn jump_to(h: &Host, jump: f64) -> f64 {
    let dt = 1e-3;
    h.initialize();
    for k in 0..2 {
        h.expect_ok(h.set_real(Var::Phi, 0.0));
        h.expect_ok(h.step(k as f64 * dt, dt));
        assert_eq!(h.boolean_status(TERMINATED), (OK, fmi2False));
    }
    h.expect_ok(h.set_real(Var::Phi, jump));
    2.0 * dt
}

/// When a step fails without progress (fmi2LastSuccessfulTime = tc), the outputs at that
/// time are those the host read before the step: the rejected step's φ must not leak into
/// them, and they must stay readable.
#[test]
fn outputs_in_step_failed_are_those_at_the_last_successful_time() {
    let _g = shared();
    for jump in [JUMP, 1e300] {
        let h = Host::new("leak");
        let tc = jump_to(&h, jump);
        let before = bits(&h.outputs());
        let s = h.step(tc, 1e-3);
        h.expect_status(s, DISCARD, &["fmi2DoStep: ", "The FMU stopped at"]);
        assert_eq!(h.real_status(LAST_SUCCESSFUL_TIME), (OK, tc));
        let (s, after) = h.get_reals(&OUTPUTS.map(vr));
        assert_eq!(s, OK, "jump {jump:e}: {:#?}", h.take());
        assert_eq!(bits(&after), before, "jump {jump:e}: {after:?}");
    }
}

// ===== 10. fmi2SetRealInputDerivatives ==========================================================

#[test]
fn input_derivatives_are_checked_and_used_for_one_step() {
    let _g = shared();
    let h = Host::new("derivatives");
    // FMI's literal polynomial over each step (phi_interpolation = taylor); the default,
    // smooth, is tested in tests/python/fmu/test_fmu_input.py.
    h.expect_ok(h.set_integer(Var::PhiInterpolation, 2));
    // Allowed before initialization too.
    h.expect_ok(h.set_derivative(Var::Phi, 1, 0.0));
    h.initialize();
    for (order, needle) in [(3, "order 3"), (0, "order 0"), (-1, "order -1")] {
        let s = h.set_derivative(Var::Phi, order, 1.0);
        h.expect_error(s, &["fmi2SetRealInputDerivatives", needle, "`phi`", "1 or 2"]);
    }
    let s = h.set_derivative(Var::V1, 1, 1.0);
    h.expect_error(s, &["fmi2SetRealInputDerivatives", "not an input", "`phi`"]);
    let s = h.set_derivative(Var::L, 1, 1.0);
    h.expect_error(s, &["fmi2SetRealInputDerivatives", "not an input"]);
    let s = unsafe {
        fmi2SetRealInputDerivatives(h.c, [9999].as_ptr(), 1, [1].as_ptr(), [1.0].as_ptr())
    };
    h.expect_error(s, &["fmi2SetRealInputDerivatives", "unknown value reference 9999"]);
    let s = unsafe {
        fmi2SetRealInputDerivatives(
            h.c,
            [vr(Var::Formulation)].as_ptr(),
            1,
            [1].as_ptr(),
            [1.0].as_ptr(),
        )
    };
    h.expect_error(s, &["`formulation`"]);
    for x in [f64::NAN, f64::INFINITY] {
        let s = h.set_derivative(Var::Phi, 2, x);
        h.expect_error(s, &["fmi2SetRealInputDerivatives", "finite"]);
    }
    // All or nothing: a valid φ' is not kept when φ'' in the same call is refused (the
    // step below would end with φ' = 3.1 instead of 0.1).
    let vrs = [vr(Var::Phi), vr(Var::Phi)];
    let s = unsafe {
        fmi2SetRealInputDerivatives(h.c, vrs.as_ptr(), 2, [1, 2].as_ptr(), [3.0, f64::NAN].as_ptr())
    };
    h.expect_error(s, &["finite"]);

    // φ = 0 and φ'' = 1 for the step [0, 0.1]: φ(t) = t²/2 over it.
    h.expect_ok(h.set_real(Var::Phi, 0.0));
    h.expect_ok(h.set_derivative(Var::Phi, 2, 1.0));
    h.expect_ok(h.step(0.0, 0.1));
    assert_eq!(h.real(Var::DdphiApplied), 1.0);
    assert!((h.real(Var::DphiApplied) - 0.1).abs() < 1e-15);
    assert!((h.real(Var::PhiApplied) - 0.005).abs() < 1e-15);
    // The next step gets no derivatives: they do not persist. φ is reconstructed from the
    // values 0 at t = 0 and 0.1: the step ends at φ = 0, φ' = 0 (a cubic from the state at
    // 0.1, so φ'' is not 1 but whatever brings φ back).
    h.expect_ok(h.set_real(Var::Phi, 0.0));
    h.expect_ok(h.step(0.1, 0.1));
    assert_ne!(h.real(Var::DdphiApplied), 1.0);
    assert!(h.real(Var::PhiApplied).abs() < 1e-15, "{}", h.real(Var::PhiApplied));
    assert!(h.real(Var::DphiApplied).abs() < 1e-14, "{}", h.real(Var::DphiApplied));
    // φ' alone.
    h.expect_ok(h.set_derivative(Var::Phi, 1, 2.0));
    h.expect_ok(h.step(0.2, 0.1));
    assert_eq!(h.real(Var::DphiApplied), 2.0);
    assert_eq!(h.real(Var::DdphiApplied), 0.0);
    assert!((h.real(Var::PhiApplied) - 0.2).abs() < 1e-15);
}
