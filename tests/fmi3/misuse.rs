//! The FMI 3.0 state machine in every state: each function that takes an instance, called in
//! each state of each interface with arguments valid where it is allowed. Allowed: it is not
//! refused for its state. Not allowed: fmi3Error, with a message naming the function and the
//! state (or, for a function of the other interface, both interfaces), and the instance is
//! still usable in its state afterwards. The table of allowed states is written here from the
//! FMI 3.0 standard's state machines (§3.2 Model Exchange, §4.2 co-simulation; the masks of
//! Reference-FMUs' fmi3Functions.c), not from the core's masks.

use super::*;

/// The continuous states of one element: v1, theta1 (q), their rates (dq), the filter's two.
const NX: usize = 6;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum St {
    // co-simulation
    CsInstantiated,
    CsInit,
    StepMode,
    StepDiscarded,
    CsTerminated,
    CsError,
    // Model Exchange
    MeInstantiated,
    MeInit,
    Event,
    Continuous,
    MeTerminated,
    MeError,
}
use St::*;

const CS: [St; 6] = [CsInstantiated, CsInit, StepMode, StepDiscarded, CsTerminated, CsError];
const ME: [St; 6] = [MeInstantiated, MeInit, Event, Continuous, MeTerminated, MeError];

impl St {
    fn is_cs(self) -> bool {
        CS.contains(&self)
    }

    /// The state's name in the FMU's messages.
    fn name(self) -> &'static str {
        match self {
            CsInstantiated | MeInstantiated => "`instantiated`",
            CsInit | MeInit => "`initialization mode`",
            StepMode => "`step mode`",
            StepDiscarded => "`step discarded`",
            CsTerminated | MeTerminated => "`terminated`",
            CsError | MeError => "`error`",
            Event => "`event mode`",
            Continuous => "`continuous-time mode`",
        }
    }
}

/// Reaches the error state: each value in range, together a singular mass matrix.
fn fail_initialization(h: &Host) {
    h.ok(h.set_real(Var::M, 0.0));
    h.ok(h.set_real(Var::JC, 0.0));
    h.ok(h.enter(None));
    h.expect_error(h.exit(), &["fmi3ExitInitializationMode", "singular at the start"]);
}

/// A new instance in state `st`, and its time.
fn reach(st: St) -> Host {
    let h = if st.is_cs() { Host::cs(&format!("{st:?}")) } else { Host::me(&format!("{st:?}")) };
    h.ok(h.set_enum(Var::PhiSource, 2));
    match st {
        CsInstantiated | MeInstantiated => {}
        CsInit | MeInit => h.ok(h.enter(None)),
        StepMode | CsTerminated => {
            h.initialize();
            h.steps(0.0, 0.01, 1);
            if st == CsTerminated {
                h.ok(unsafe { fmi3Terminate(h.c) });
            }
        }
        StepDiscarded => {
            // A stiff beam at the paper's fixed step of 0.5 s at order 5: Newton fails.
            h.ok(h.set_real(Var::FixedStep, 0.5));
            h.ok(unsafe { fmi3SetInt32(h.c, &vr(Var::FixedOrder), 1, &5, 1) });
            h.ok(h.set_real(Var::Ei, 1e7));
            h.initialize();
            let (s, terminated, last) = h.step(0.0, 0.5);
            assert_eq!((s, terminated), (fmi3Discard, true), "{:#?}", h.take());
            assert!(last < 0.5);
            h.take();
        }
        Event | Continuous | MeTerminated => {
            h.initialize();
            if st != Event {
                update_discrete_states(&h);
                h.ok(unsafe { fmi3EnterContinuousTimeMode(h.c) });
            }
            if st == MeTerminated {
                h.ok(unsafe { fmi3Terminate(h.c) });
            }
        }
        CsError | MeError => fail_initialization(&h),
    }
    h
}

fn update_discrete_states(h: &Host) -> fmi3Status {
    let (mut a, mut b, mut c, mut d, mut e, mut t) = (0, 0, 0, 0, 0, 0.0);
    unsafe { fmi3UpdateDiscreteStates(h.c, &mut a, &mut b, &mut c, &mut d, &mut e, &mut t) }
}

/// Checks that `h` is still in `st` and usable there.
#[track_caller]
fn probe(h: &Host, st: St) {
    match st {
        CsInstantiated | MeInstantiated => h.ok(h.enter(None)),
        CsInit | MeInit => h.ok(h.exit()),
        StepMode => h.ok(h.step(0.01, 0.01).0),
        StepDiscarded | CsTerminated | Event | Continuous | MeTerminated => {
            let s = h.get_reals(&[Var::V1]).0;
            assert!(s <= fmi3Warning, "{st:?}: {:#?}", h.take());
            if st == Event {
                h.ok(unsafe { fmi3EnterContinuousTimeMode(h.c) });
            }
        }
        CsError | MeError => {
            assert_eq!(h.real(Var::M), 0.0);
            h.ok(unsafe { fmi3Reset(h.c) });
        }
    }
}

/// A call of the matrix: its name, the states that allow it, and the call.
type Call = (&'static str, &'static [St], fn(&Host) -> fmi3Status);

const GET: &[St] = &[
    CsInit,
    StepMode,
    StepDiscarded,
    CsTerminated,
    CsError,
    MeInit,
    Event,
    Continuous,
    MeTerminated,
    MeError,
];
const FMU_STATE: &[St] = &[
    CsInstantiated,
    CsInit,
    StepMode,
    StepDiscarded,
    CsTerminated,
    CsError,
    MeInstantiated,
    MeInit,
    Event,
    Continuous,
    MeTerminated,
    MeError,
];

fn calls() -> Vec<Call> {
    vec![
        ("fmi3EnterInitializationMode", &[CsInstantiated, MeInstantiated], |h| h.enter(None)),
        ("fmi3ExitInitializationMode", &[CsInit, MeInit], |h| h.exit()),
        // Configuration mode, from `instantiated` only (no tunable structural parameter, so
        // no reconfiguration mode); left at once, so that the state is `instantiated` again.
        ("fmi3EnterConfigurationMode", &[CsInstantiated, MeInstantiated], |h| {
            let s = unsafe { fmi3EnterConfigurationMode(h.c) };
            if s == OK {
                h.ok(unsafe { fmi3ExitConfigurationMode(h.c) });
            }
            s
        }),
        ("fmi3ExitConfigurationMode", &[], |h| unsafe { fmi3ExitConfigurationMode(h.c) }),
        // The structural parameter: in configuration mode only (tested there in arrays.rs).
        ("fmi3SetUInt64", &[], |h| unsafe { fmi3SetUInt64(h.c, &vr(Var::NElements), 1, &2, 1) }),
        ("fmi3Terminate", &[StepMode, StepDiscarded, Event, Continuous], |h| unsafe {
            fmi3Terminate(h.c)
        }),
        ("fmi3GetFloat64", GET, |h| h.get_reals(&[Var::V1, Var::L, Var::Time]).0),
        // An input: before initialization, and while running.
        (
            "fmi3SetFloat64",
            &[CsInstantiated, CsInit, StepMode, MeInstantiated, MeInit, Event, Continuous],
            |h| h.set_real(Var::Phi, 0.1),
        ),
        // A fixed parameter: before initialization ends only.
        ("fmi3SetFloat64", &[CsInstantiated, CsInit, MeInstantiated, MeInit], |h| {
            h.set_real(Var::L, 2.5)
        }),
        ("fmi3GetInt64", GET, |h| {
            let mut k = 0i64;
            unsafe { fmi3GetInt64(h.c, &vr(Var::Formulation), 1, &mut k, 1) }
        }),
        ("fmi3GetFMUState", FMU_STATE, |h| {
            let mut s = null_mut();
            let status = unsafe { fmi3GetFMUState(h.c, &mut s) };
            if !s.is_null() {
                h.ok(unsafe { fmi3FreeFMUState(h.c, &mut s) });
            }
            status
        }),
        ("fmi3DoStep", &[StepMode], |h| h.step(0.01, 0.01).0),
        ("fmi3GetOutputDerivatives", &[StepMode, StepDiscarded, CsTerminated, CsError], |h| {
            let mut d = 0.0;
            unsafe { fmi3GetOutputDerivatives(h.c, &vr(Var::V1), 1, &1, &mut d, 1) }
        }),
        ("fmi3EnterEventMode", &[Event, Continuous], |h| unsafe { fmi3EnterEventMode(h.c) }),
        ("fmi3UpdateDiscreteStates", &[Event], update_discrete_states),
        ("fmi3EnterContinuousTimeMode", &[Event], |h| unsafe { fmi3EnterContinuousTimeMode(h.c) }),
        ("fmi3SetTime", &[Event, Continuous], |h| unsafe { fmi3SetTime(h.c, 0.0) }),
        ("fmi3SetContinuousStates", &[Continuous], |h| {
            let x = [0.0; NX];
            unsafe { fmi3SetContinuousStates(h.c, x.as_ptr(), NX) }
        }),
        (
            "fmi3GetContinuousStateDerivatives",
            &[MeInit, Event, Continuous, MeTerminated, MeError],
            |h| {
                let mut x = [0.0; NX];
                unsafe { fmi3GetContinuousStateDerivatives(h.c, x.as_mut_ptr(), NX) }
            },
        ),
        ("fmi3GetEventIndicators", &[MeInit, Event, Continuous, MeTerminated, MeError], |h| {
            let mut z = [0.0; 2];
            unsafe { fmi3GetEventIndicators(h.c, z.as_mut_ptr(), 2) }
        }),
        ("fmi3GetContinuousStates", &[MeInit, Event, Continuous, MeTerminated, MeError], |h| {
            let mut x = [0.0; NX];
            unsafe { fmi3GetContinuousStates(h.c, x.as_mut_ptr(), NX) }
        }),
        (
            "fmi3GetNominalsOfContinuousStates",
            &[MeInit, Event, Continuous, MeTerminated, MeError],
            |h| {
                let mut x = [0.0; NX];
                unsafe { fmi3GetNominalsOfContinuousStates(h.c, x.as_mut_ptr(), NX) }
            },
        ),
        (
            "fmi3GetNumberOfContinuousStates",
            &[MeInstantiated, MeInit, Event, Continuous, MeTerminated, MeError],
            |h| {
                let mut n = 0;
                unsafe { fmi3GetNumberOfContinuousStates(h.c, &mut n) }
            },
        ),
        ("fmi3CompletedIntegratorStep", &[Continuous], |h| {
            let (mut a, mut b) = (0, 0);
            unsafe { fmi3CompletedIntegratorStep(h.c, fmi3True, &mut a, &mut b) }
        }),
        (
            "fmi3GetDirectionalDerivative",
            &[MeInit, Event, Continuous, MeTerminated, MeError],
            |h| h.directional(&[Var::Ddq], &[Var::Dq], &[1.0, 0.0], 2).0,
        ),
    ]
}

/// Every call of the table in every state of both interfaces: 25 calls × 12 states.
#[test]
fn every_call_in_every_state() {
    let mut counts = (0, 0);
    for (name, allowed, call) in calls() {
        for st in CS.into_iter().chain(ME) {
            let h = reach(st);
            let status = call(&h);
            let log = h.take();
            let refusal = |m: &str| {
                ["illegal call sequence", "this instance was instantiated for", "not provided"]
                    .iter()
                    .any(|r| m.contains(r))
            };
            if allowed.contains(&st) {
                // Allowed: not refused for the state (an error state's outputs may still fail
                // to compute, saying why).
                let refused = log.iter().any(|(_, _, m)| refusal(m));
                assert!(
                    status <= fmi3Warning || status == ERROR && !refused && st.name() == "`error`",
                    "{name} in {st:?}: {status}, {log:#?}"
                );
                counts.0 += 1;
                continue;
            }
            counts.1 += 1;
            assert_eq!(status, ERROR, "{name} in {st:?} must be refused: {log:#?}");
            let other_interface =
                log.iter().any(|(_, _, m)| m.contains("this instance was instantiated for"));
            let refused_here =
                log.iter().any(|(_, _, m)| m.starts_with(name) && m.contains(st.name()));
            let unprovided = log.iter().any(|(_, _, m)| m.contains("not provided"));
            assert!(
                refused_here || other_interface || unprovided,
                "{name} in {st:?}: no message naming the state or interface: {log:#?}"
            );
            probe(&h, st);
        }
    }
    // The table's own count, so that a shrunk table fails.
    assert_eq!(counts.0 + counts.1, 25 * 12);
    assert!(counts.1 > counts.0, "{counts:?}");
}
