//! Independent instances, and what a host sees first.

use super::*;

// ===== 16. independent instances ================================================================

pub(crate) fn configure_pair(h: &Host, stiff: bool) {
    h.expect_ok(h.set_integer(Var::PhiSource, 2));
    if stiff {
        h.expect_ok(h.set_real(Var::Ei, 2500.0));
        h.expect_ok(h.set_real(Var::M2, 6.0));
        h.expect_ok(h.set_integer(Var::Formulation, 4));
    }
    h.initialize();
}

#[test]
fn interleaved_instances_stay_independent() {
    let _g = shared();
    let n = 40;
    let (a, b) = (Host::new("A"), Host::new("B"));
    configure_pair(&a, false);
    configure_pair(&b, true);
    let (mut ra, mut rb) = (Vec::new(), Vec::new());
    for k in 0..n {
        let t = k as f64 * 0.01;
        a.expect_ok(a.step(t, 0.01));
        b.expect_ok(b.step(t, 0.01));
        ra.push(bits(&a.outputs()));
        rb.push(bits(&b.outputs()));
    }
    drop(a); // freeing one does not disturb the other
    b.expect_ok(b.step(n as f64 * 0.01, 0.01));
    drop(b);
    for (stiff, interleaved) in [(false, &ra), (true, &rb)] {
        let alone = Host::new("alone");
        configure_pair(&alone, stiff);
        assert_eq!(&run_rows(&alone, n), interleaved, "stiff = {stiff}");
    }
    assert_ne!(ra, rb);
}

/// Different instances may run on different threads at the same time (FMI 2.0 §2.1.1
/// forbids only concurrent calls on one instance).
#[test]
fn instances_run_concurrently_on_threads() {
    let _g = shared();
    let run = |stiff: bool| {
        let h = Host::new(if stiff { "thread stiff" } else { "thread soft" });
        configure_pair(&h, stiff);
        run_rows(&h, 40)
    };
    let alone = [run(false), run(true)];
    for _ in 0..3 {
        let threads: Vec<_> =
            (0..4).map(|k| std::thread::spawn(move || (k % 2 == 1, run(k % 2 == 1)))).collect();
        for t in threads {
            let (stiff, rows) = t.join().expect("no panic");
            assert_eq!(rows, alone[stiff as usize]);
        }
    }
}

/// A step so short that h² underflows (the Hermite piece of φ from the host's values would
/// be 0/0), or a jump of φ so large that its slopes overflow: the step is discarded with a
/// message, never a panic (fmi2Fatal). A step that does not even advance t is refused.
#[test]
fn steps_whose_input_cannot_be_extrapolated_are_discarded_not_fatal() {
    let _g = shared();
    // (first step, its h, φ for the second step, its h): the second is the one that fails.
    let cases =
        [(false, 0.0, 0.5, 1e-200), (true, 1e-3, 1e300, 1e-3), (true, 1e-3, -f64::MAX, 1e-3)];
    for (first, t, phi, h_step) in cases {
        let h = Host::new("extrapolation");
        h.initialize();
        h.expect_ok(h.set_real(Var::Phi, 0.0));
        if first {
            h.expect_ok(h.step(0.0, t));
        }
        h.expect_ok(h.set_real(Var::Phi, phi));
        let s = h.step(t, h_step);
        let r = h.expect_status(s, DISCARD, &["fmi2DoStep: ", "The FMU stopped at"]);
        assert!(r.message.contains("not finite"), "h = {h_step:e}, phi = {phi:e}: {r:?}");
        assert_eq!(h.real_status(LAST_SUCCESSFUL_TIME), (OK, t));
        assert_eq!(h.boolean_status(TERMINATED), (OK, fmi2True));
        h.expect_ok(h.terminate());
    }
    // h = 1e-197 at t = 1e-3: t + h = t. Refused, and the run goes on.
    let h = Host::new("no advance");
    h.initialize();
    h.expect_ok(h.step(0.0, 1e-3));
    let s = h.step(1e-3, 1e-197);
    h.expect_error(s, &["fmi2DoStep", "would not advance"]);
    h.expect_ok(h.step(1e-3, 1e-3));
}

// ===== 17. what a host sees first =================================================================

/// With no start values, phi is the input at its start value 0: a host that steps without
/// ever setting it (FMPy's simulate_fmu without an input) is told so at the first step, once,
/// with fmi2Warning and logging off; the run goes on, the body at rest.
#[test]
fn an_input_never_set_is_a_warning_at_the_first_step() {
    let _g = shared();
    let h = Host::plain("never set");
    h.initialize();
    let s = h.step(0.0, 0.01);
    let r =
        h.expect_status(s, WARNING, &["input `phi` has not been set", "`phi_source` = law (2)"]);
    assert_eq!(r.category, "logStatusWarning");
    h.steps(0.01, 0.01, 3);
    assert_eq!(h.real(Var::V1), 0.0);
    // A host that sets phi, even to its start value, is not warned.
    let g = Host::plain("set");
    g.initialize();
    g.expect_ok(g.set_real(Var::Phi, 0.0));
    g.expect_ok(g.step(0.0, 0.01));
}

/// A host that sends phi between steps while the law drives the body is told, once, with
/// fmi2Warning, even with logging off; setting phi before the run (a host applying start
/// values) is not a warning.
#[test]
fn phi_sent_to_the_law_is_a_warning_once() {
    let _g = shared();
    let h = Host::plain("ignored phi");
    h.expect_ok(h.set_integer(Var::PhiSource, 2));
    h.expect_ok(h.set_real(Var::Phi, 0.0));
    h.initialize();
    let s = h.set_real(Var::Phi, 0.5);
    let r = h.expect_status(s, WARNING, &["`phi` is ignored", "`phi_source` = input (1)"]);
    assert_eq!(r.category, "logStatusWarning");
    h.expect_ok(h.step(0.0, 0.01));
    // Said once; the law, not the host's phi, turned the body.
    h.expect_ok(h.set_real(Var::Phi, 0.6));
    assert!((h.real(Var::PhiApplied) - paper_phi(0.01)).abs() < 1e-15);
}

/// Warnings reach a host that has not switched debug logging on (FMI 2.0.4 §2.1.3: a
/// function that returns fmi2Warning has called the logger).
#[test]
fn warnings_reach_a_host_with_logging_off() {
    let _g = shared();
    let h = Host::plain("warn");
    h.expect_ok(h.set_integer(Var::PhiSource, 2));
    h.expect_ok(h.set_integer(Var::RangeCheck, 2));
    h.expect_ok(h.set_real(Var::PhiEnd, 1000.0));
    h.initialize();
    let mut t = 0.0;
    let mut warned = None;
    for _ in 0..200 {
        let s = h.step(t, 0.01);
        t += 0.01;
        if s == WARNING {
            warned = Some(h.take());
            break;
        }
        assert_eq!(s, OK, "{:#?}", h.take());
    }
    let records = warned.expect("the run leaves the range of validity and says so");
    assert!(
        records.iter().any(|r| r.status == WARNING
            && r.category == "logStatusWarning"
            && r.message.contains("range_check = warn")),
        "{records:#?}"
    );
}

/// One rule for fixed_order, as in the CLI: it needs fixed_step.
#[test]
fn fixed_order_without_fixed_step_is_refused_naming_both() {
    let _g = shared();
    let h = Host::plain("fixed order");
    h.expect_ok(h.set_integer(Var::FixedOrder, 3));
    h.expect_ok(h.setup(None, 0.0, None));
    h.expect_ok(h.enter());
    let s = h.exit();
    h.expect_error(s, &["fmi2ExitInitializationMode", "`fixed_order` = 3", "`fixed_step` > 0"]);
}

/// The start angle and the initial state are parameters, as in the CLI and the studies.
#[test]
fn the_initial_state_and_phi0_are_parameters() {
    let _g = shared();
    let h = Host::plain("initial");
    h.expect_ok(h.set_integer(Var::PhiSource, 2));
    h.expect_ok(h.set_real(Var::V10, 0.1));
    h.expect_ok(h.set_real(Var::Dtheta10, -0.2));
    h.expect_ok(h.set_real(Var::Phi0, 0.3));
    h.expect_ok(h.setup(None, 0.0, None));
    h.expect_ok(h.enter());
    assert_eq!((h.real(Var::V1), h.real(Var::Dtheta1)), (0.1, -0.2));
    assert_eq!(h.real(Var::PhiApplied), 0.3);
    h.expect_ok(h.exit());
    // Outside the range of validity at the start: refused at once, in the user's words.
    let g = Host::plain("initial out of range");
    g.expect_ok(g.set_real(Var::V10, 3.0));
    g.expect_ok(g.setup(None, 0.0, None));
    g.expect_ok(g.enter());
    let s = g.exit();
    g.expect_error(s, &["initial state `v1_0` = 3.0", "|v1| <= l"]);
}
