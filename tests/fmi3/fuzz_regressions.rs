//! The FMI 3.0 states in `fuzz/regressions/deserialize/`, replayed on the FMI 3.0 path they
//! were found on (fmi3DeserializeFMUState, fmi3SetFMUState into an FMI 3.0 co-simulation,
//! fmi3DoStep), as `tests/fmi2/fmu_state.rs` replays the FMI 2.0 ones; there, an FMI 2.0
//! instance only refuses them. Each file is the fuzz target's input: a mode byte (odd: reseal
//! the rest, as the target does), then a serialized state.

use super::{vr, Host, MOTION, OK};
use beam_body::fmi3::exports::*;
use beam_body::fmi3::types::*;
use beam_body::fmu::variables::Var;
use std::ptr::null_mut;

/// The regression's state, deserialized and set into a fresh FMI 3.0 co-simulation.
fn restored(file: &str) -> (Host, f64) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/regressions/deserialize")
        .join(file);
    let input = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (mode, rest) = input.split_first().expect("a mode byte");
    let mut bytes = rest.to_vec();
    if mode % 2 == 1 {
        beam_body::fmi::reseal(&mut bytes);
    }
    let h = Host::cs(file);
    let mut s = null_mut();
    h.ok(unsafe { fmi3DeserializeFMUState(h.c, bytes.as_ptr(), bytes.len(), &mut s) });
    h.ok(unsafe { fmi3SetFMUState(h.c, s) });
    h.ok(unsafe { fmi3FreeFMUState(h.c, &mut s) });
    let t = h.real(Var::Time);
    (h, t)
}

/// The paper's scene at t = 0.51 s restores into an FMI 3.0 instance and steps on to the
/// end of the turn with finite outputs and the body turned to π.
#[test]
fn an_fmi3_state_restores_into_an_fmi3_instance_and_steps_on() {
    let (h, t) = restored("fmi3-state-restores-into-an-fmi3-instance");
    assert!((t - 0.51).abs() < 1e-9, "restored at t = {t}");
    let end = h.steps(t, 0.0085, 50);
    let (s, y) = h.get_reals(&MOTION);
    h.ok(s);
    assert!(y.iter().all(|x| x.is_finite()) && y[0].abs() > 0.05, "{y:?} at {end}");
    assert!((h.real(Var::PhiApplied) - std::f64::consts::PI).abs() < 1e-12);
}

/// The same state with 100 J of the drive's work that never happened: the reader takes it
/// (a finite number), and fmi3DoStep discards at the energy check's next look (every 8
/// integrator steps), naming the broken energy balance and fmi3DoStep, not FMI 2.0's
/// function (the fuzz target once expected FMI 2.0's name).
#[test]
fn an_fmi3_state_with_a_broken_balance_discards_by_fmi3_s_name() {
    let (h, mut t) = restored("fmi3-state-whose-step-discards");
    let mut s = OK;
    for _ in 0..10 {
        s = h.step(t, 0.0085).0;
        if s != OK {
            break;
        }
        t += 0.0085;
    }
    let log = h.take();
    assert_eq!(s, fmi3Discard, "{log:#?}");
    assert!(
        log.iter().any(|(st, _, m)| *st == fmi3Discard
            && m.contains("fmi3DoStep")
            && m.contains("energy balance is broken")),
        "{log:#?}"
    );
    let mut v1 = f64::NAN;
    let st = unsafe { fmi3GetFloat64(h.c, &vr(Var::V1), 1, &mut v1, 1) };
    assert!(st == OK && v1.is_finite(), "the outputs of the last good point stay: {v1}");
}
