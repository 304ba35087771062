//! FMI 2.0 Model Exchange through the C API: its state machine in every state for all 40
//! functions that take an instance, the two interfaces refusing each other's functions, and
//! the arrays' pointers and counts.

use super::sequences::{calls as cs_calls, Call};
use super::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Me {
    Instantiated,
    Init,
    Event,
    Continuous,
    Terminated,
    Error,
}
use Me::{Continuous, Error, Event, Init, Instantiated, Terminated};

const ALL: [Me; 6] = [Instantiated, Init, Event, Continuous, Terminated, Error];
/// The model description's continuous states: v1, theta1, dv1, dtheta1 and the two of the
/// filter of phi.
const NX: usize = 6;

impl Me {
    fn fmu_name(self) -> &'static str {
        match self {
            Instantiated => "`instantiated`",
            Init => "`initialization mode`",
            Event => "`event mode`",
            Continuous => "`continuous-time mode`",
            Terminated => "`terminated`",
            Error => "`error`",
        }
    }
}

fn event_info() -> fmi2EventInfo {
    fmi2EventInfo {
        newDiscreteStatesNeeded: 0,
        terminateSimulation: 0,
        nominalsOfContinuousStatesChanged: 0,
        valuesOfContinuousStatesChanged: 0,
        nextEventTimeDefined: 0,
        nextEventTime: 0.0,
    }
}

impl Host {
    fn new_discrete_states(&self) -> (fmi2Status, fmi2EventInfo) {
        let mut info = event_info();
        let status = unsafe { fmi2NewDiscreteStates(self.c, &mut info) };
        (status, info)
    }

    fn continuous_time_mode(&self) -> fmi2Status {
        unsafe { fmi2EnterContinuousTimeMode(self.c) }
    }

    fn completed_step(&self) -> (fmi2Status, fmi2Boolean, fmi2Boolean) {
        let (mut enter, mut stop) = (-1, -1);
        let status =
            unsafe { fmi2CompletedIntegratorStep(self.c, fmi2True, &mut enter, &mut stop) };
        (status, enter, stop)
    }

    fn derivatives(&self) -> (fmi2Status, [f64; NX]) {
        let mut dx = [f64::NAN; NX];
        let status = unsafe { fmi2GetDerivatives(self.c, dx.as_mut_ptr(), NX) };
        (status, dx)
    }
}

/// A Model Exchange instance in state `st`.
fn reach(st: Me) -> Host {
    let h = Host::exchange(&format!("ME in {st:?}"));
    match st {
        Instantiated => {}
        Init => {
            h.expect_ok(h.setup(None, 0.0, None));
            h.expect_ok(h.enter());
        }
        Event | Continuous | Terminated => {
            h.initialize();
            if st != Event {
                h.expect_ok(h.new_discrete_states().0);
                h.expect_ok(h.continuous_time_mode());
            }
            if st == Terminated {
                h.expect_ok(h.terminate());
            }
        }
        Error => super::sequences::fail_initialization(&h),
    }
    h
}

/// Checks that `h` is still in `st` and usable there.
#[track_caller]
fn probe(h: &Host, st: Me) {
    match st {
        Instantiated => h.expect_ok(h.enter()),
        Init => h.expect_ok(h.exit()),
        Event => h.expect_ok(h.continuous_time_mode()),
        Continuous => h.expect_ok(h.completed_step().0),
        Terminated => {
            h.expect_ok(h.derivatives().0);
            let s = h.terminate();
            h.expect_error(s, &["fmi2Terminate", "illegal call sequence", "`terminated`"]);
        }
        Error => h.expect_ok(h.reset()),
    }
}

/// A Model Exchange call: its name, the states that allow it, and the call with arguments
/// valid there.
type MeCall = (&'static str, &'static [Me], fn(&Host) -> fmi2Status);

/// A call of the matrix: co-simulation's table's (`None`: its own functions) or Model
/// Exchange's.
type AnyCall = (&'static str, Option<&'static [Me]>, Box<dyn Fn(&Host) -> fmi2Status>);

/// Model Exchange's own ten functions, with arguments valid where each is allowed.
fn exchange_calls() -> Vec<MeCall> {
    vec![
        ("fmi2EnterEventMode", &[Event, Continuous], |h| unsafe { fmi2EnterEventMode(h.c) }),
        ("fmi2NewDiscreteStates", &[Event], |h| h.new_discrete_states().0),
        ("fmi2EnterContinuousTimeMode", &[Event], |h| h.continuous_time_mode()),
        ("fmi2CompletedIntegratorStep", &[Continuous], |h| h.completed_step().0),
        ("fmi2SetTime", &[Event, Continuous], |h| unsafe { fmi2SetTime(h.c, 0.25) }),
        ("fmi2SetContinuousStates", &[Continuous], |h| unsafe {
            fmi2SetContinuousStates(h.c, [0.01, 0.0, 0.0, 0.0, 0.0, 0.0].as_ptr(), NX)
        }),
        ("fmi2GetDerivatives", &[Event, Continuous, Terminated, Error], |h| h.derivatives().0),
        ("fmi2GetEventIndicators", &[Init, Event, Continuous, Terminated, Error], |h| {
            let mut z = [0.0; 2];
            unsafe { fmi2GetEventIndicators(h.c, z.as_mut_ptr(), 2) }
        }),
        ("fmi2GetContinuousStates", &[Init, Event, Continuous, Terminated, Error], |h| {
            let mut x = [0.0; NX];
            unsafe { fmi2GetContinuousStates(h.c, x.as_mut_ptr(), NX) }
        }),
        (
            "fmi2GetNominalsOfContinuousStates",
            &[Instantiated, Event, Continuous, Terminated, Error],
            |h| {
                let mut x = [0.0; NX];
                unsafe { fmi2GetNominalsOfContinuousStates(h.c, x.as_mut_ptr(), NX) }
            },
        ),
    ]
}

const GET: &[Me] = &[Init, Event, Continuous, Terminated, Error];
const SET: &[Me] = &[Instantiated, Init, Event, Continuous];

/// Where co-simulation's table of common functions allows a call, Model Exchange's states
/// that allow it (FMI 2.0 §3.2.3); `None` for co-simulation's own functions.
fn common_allowed(name: &str) -> Option<&'static [Me]> {
    Some(match name {
        "fmi2SetupExperiment" | "fmi2EnterInitializationMode" => &[Instantiated],
        "fmi2ExitInitializationMode" => &[Init],
        "fmi2Terminate" => &[Event, Continuous],
        "fmi2Reset" | "fmi2SetDebugLogging" => &ALL,
        "fmi2GetReal" | "fmi2GetInteger" | "fmi2GetBoolean" | "fmi2GetString" => GET,
        "fmi2GetDirectionalDerivative" => GET,
        "fmi2SetReal" | "fmi2SetInteger" | "fmi2SetBoolean" | "fmi2SetString" => SET,
        "fmi2GetFMUstate"
        | "fmi2SetFMUstate"
        | "fmi2FreeFMUstate"
        | "fmi2SerializedFMUstateSize"
        | "fmi2SerializeFMUstate"
        | "fmi2DeSerializeFMUstate" => &ALL,
        _ => return None,
    })
}

/// The documented outcome of an allowed call in `st`: `Err(reason)` for fmi2Error with a
/// message naming the call and the reason.
fn outcome(name: &str, st: Me) -> Result<(), &'static str> {
    match (name, st) {
        // The only integer and boolean variables are fixed parameters.
        ("fmi2SetInteger" | "fmi2SetBoolean", Event | Continuous) => Err("fixed parameter"),
        // The donor of co-simulation's table is a co-simulation instance.
        ("fmi2SetFMUstate", _) => Err("saved by a co-simulation instance"),
        // The error state is reached with values that make no model.
        (
            "fmi2GetDerivatives"
            | "fmi2GetEventIndicators"
            | "fmi2GetContinuousStates"
            | "fmi2GetDirectionalDerivative",
            Error,
        ) => Err("the model cannot start"),
        ("fmi2GetReal", Error) => Ok(()), // a parameter
        _ => Ok(()),
    }
}

/// Every state of Model Exchange × every function that takes an instance (co-simulation's
/// table of 30 and Model Exchange's 10), with logCalls off and on:
/// - co-simulation's own functions are refused in every state, naming the interface;
/// - a call the state machine forbids returns fmi2Error, logs "illegal call sequence" with
///   the function and the state, and leaves the instance usable in its state;
/// - an allowed call returns fmi2OK (traced when logCalls is on) or its documented error.
#[test]
fn model_exchange_call_sequences_in_every_state() {
    let _g = shared();
    let cs: Vec<Call> = cs_calls();
    let (mut illegal, mut foreign, mut pairs) = (0, 0, 0);
    for logging in [false, true] {
        for st in ALL {
            let mut all: Vec<AnyCall> = Vec::new();
            for (name, _, call) in cs.iter().copied() {
                all.push((name, common_allowed(name), Box::new(move |h| call(h, 0.0))));
            }
            for (name, allowed, call) in exchange_calls() {
                all.push((name, Some(allowed), Box::new(call)));
            }
            assert_eq!(all.len(), 40);
            for (name, allowed, call) in all {
                let h = reach(st);
                if logging {
                    h.expect_ok(h.debug_logging(true, &[c"logCalls"]));
                }
                let status = call(&h);
                match allowed {
                    None => {
                        h.expect_error(
                            status,
                            &[name, "a co-simulation function", "Model Exchange"],
                        );
                        probe(&h, st);
                        foreign += 1;
                    }
                    Some(states) if !states.contains(&st) => {
                        h.expect_error(status, &[name, "illegal call sequence", st.fmu_name()]);
                        probe(&h, st);
                        illegal += 1;
                    }
                    Some(_) => match outcome(name, st) {
                        Err(reason) => {
                            let r = h.expect_error(status, &[&format!("{name}: "), reason]);
                            assert!(!r.message.contains("illegal call sequence"), "{r:?}");
                        }
                        Ok(()) => {
                            let records = h.take();
                            assert_eq!(status, OK, "{name} in {st:?}: {records:#?}");
                            let traced = records.iter().any(|r| r.message.starts_with(name));
                            assert_eq!(
                                traced,
                                logging || name == "fmi2SetDebugLogging",
                                "{name} in {st:?}: {records:#?}"
                            );
                        }
                    },
                }
                pairs += 1;
            }
        }
    }
    // 6 states × 40 functions, twice: co-simulation's 9 own functions are refused in each
    // state, and the state machine forbids 65 of the other 186 pairs (32 of the 21 common
    // functions', 33 of Model Exchange's 10).
    assert_eq!((pairs, foreign, illegal), (2 * 6 * 40, 2 * 6 * 9, 2 * 65));
}

/// A co-simulation instance refuses Model Exchange's ten functions in every state, naming
/// the interface, and stays usable.
#[test]
fn co_simulation_refuses_model_exchange_functions() {
    let _g = shared();
    for st in super::sequences::ALL_STATES {
        for (name, _, call) in exchange_calls() {
            let (h, t) = super::sequences::reach(st);
            let status = call(&h);
            h.expect_error(status, &[name, "a Model Exchange function", "co-simulation"]);
            super::sequences::probe(&h, st, t);
        }
    }
}

/// The arrays of Model Exchange: NULL with elements is an error naming the argument, a
/// count other than the model description's is an error naming it, and nothing is written.
#[test]
fn model_exchange_arrays_are_checked() {
    let _g = shared();
    let h = reach(Continuous);
    let s = unsafe { fmi2GetDerivatives(h.c, null_mut(), NX) };
    h.expect_error(s, &["fmi2GetDerivatives", "`derivatives` is NULL"]);
    let s = unsafe { fmi2SetContinuousStates(h.c, null(), NX) };
    h.expect_error(s, &["fmi2SetContinuousStates", "`x` is NULL"]);
    let mut x = [7.0; 5];
    let s = unsafe { fmi2GetContinuousStates(h.c, x.as_mut_ptr(), 5) };
    h.expect_error(s, &["fmi2GetContinuousStates", "nx = 5", "6"]);
    assert_eq!(x, [7.0; 5]);
    let s = unsafe { fmi2GetEventIndicators(h.c, x.as_mut_ptr(), 1) };
    h.expect_error(s, &["fmi2GetEventIndicators", "ni = 1"]);
    let s = unsafe { fmi2NewDiscreteStates(h.c, null_mut()) };
    h.expect_error(s, &["fmi2NewDiscreteStates", "`eventInfo` is NULL"]);
    let (mut enter, mut stop) = (0, 0);
    let s = unsafe { fmi2CompletedIntegratorStep(h.c, 0, null_mut(), &mut stop) };
    h.expect_error(s, &["fmi2CompletedIntegratorStep", "`enterEventMode` is NULL"]);
    let s = unsafe { fmi2CompletedIntegratorStep(h.c, 0, &mut enter, null_mut()) };
    h.expect_error(s, &["fmi2CompletedIntegratorStep", "`terminateSimulation` is NULL"]);
    let x = [0.0, f64::INFINITY, 0.0, 0.0, 0.0, 0.0];
    let s = unsafe { fmi2SetContinuousStates(h.c, x.as_ptr(), NX) };
    h.expect_error(s, &["fmi2SetContinuousStates", "x[1] = inf (`theta1`)", "finite"]);
    // Zero-length arrays with NULL are fine where the count is right, and here it is not.
    let s = unsafe { fmi2GetDerivatives(h.c, null_mut(), 0) };
    h.expect_error(s, &["fmi2GetDerivatives", "nx = 0"]);
    h.expect_ok(h.completed_step().0);
}

/// The event iteration of the law: at the start the next time event is t_rot; after it, none.
#[test]
fn the_law_s_end_is_a_time_event() {
    let _g = shared();
    let h = Host::exchange("law");
    h.expect_ok(h.set_integer(Var::PhiSource, 2));
    h.initialize();
    let (s, info) = h.new_discrete_states();
    h.expect_ok(s);
    assert_eq!((info.nextEventTimeDefined, info.nextEventTime), (fmi2True, 0.85));
    assert_eq!((info.terminateSimulation, info.newDiscreteStatesNeeded), (fmi2False, fmi2False));
    h.expect_ok(h.continuous_time_mode());
    h.expect_ok(unsafe { fmi2SetTime(h.c, 0.85) });
    h.expect_ok(unsafe { fmi2EnterEventMode(h.c) });
    let (s, info) = h.new_discrete_states();
    h.expect_ok(s);
    assert_eq!(info.nextEventTimeDefined, fmi2False);
}
