//! Random sequences of fmi2 calls, with random arguments, through the safe `Instance` API
//! that the C functions forward to, on a co-simulation or a Model Exchange instance (the
//! first byte). Checks the properties of `beam_body_fuzz` after every call, that a successful
//! fmi2DoStep lands exactly on tc + h in stepComplete, and that Model Exchange's derivatives
//! and event indicators are finite when they are given.
#![no_main]

use beam_body::fmi::{
    Interface, State, Status, STATUS_DO_STEP, STATUS_LAST_SUCCESSFUL_TIME, STATUS_TERMINATED,
};
use beam_body::fmi2::{Core, Instance};
use beam_body::fmu::variables::LOG_CATEGORIES;
use beam_body_fuzz::{check_outputs, check_status, instance_of, Num, Records};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
enum Op {
    Setup {
        tolerance: Option<Num>,
        start: Num,
        stop: Option<Num>,
    },
    Enter,
    Exit,
    Terminate,
    Reset,
    SetReal(Vec<(u8, Num)>),
    SetInteger(Vec<(u8, i32)>),
    SetBoolean(Vec<(u8, bool)>),
    GetInteger(Vec<u8>),
    GetBoolean(Vec<u8>),
    GetString(Vec<u8>),
    SetString(Vec<u8>),
    SetInputDerivatives(Vec<(u8, i8, Num)>),
    /// tc: `None` is the current time; h from `Num`.
    DoStep {
        tc: Option<Num>,
        h: Num,
    },
    GetState(u8),
    SetState(u8),
    FreeState(u8),
    /// Serialize the snapshot in a slot, deserialize it into another.
    RoundTrip(u8, u8),
    DebugLogging {
        on: bool,
        categories: Vec<u8>,
    },
    CancelStep,
    Status(i8),
    RealStatus(i8),
    BooleanStatus(i8),
    OutputDerivatives(Vec<(u8, i8)>),
    DirectionalDerivative,
    // Model Exchange.
    EnterEventMode,
    NewDiscreteStates,
    EnterContinuousTimeMode,
    CompletedIntegratorStep,
    SetTime(Num),
    /// The length is the host's nx (the model's is 4).
    SetContinuousStates(Vec<Num>),
    GetContinuousStates(u8),
    GetDerivatives(u8),
    GetEventIndicators(u8),
    GetNominals(u8),
    /// Unknowns, knowns with their seeds.
    DirectionalDerivativeMe(Vec<u8>, Vec<(u8, Num)>),
}

const SLOTS: usize = 4;

struct Harness {
    inst: Instance,
    records: Records,
    slots: [Option<Box<Core>>; SLOTS],
    /// The communication time as the host tracks it.
    time: f64,
}

fn vrs(list: &[u8]) -> Vec<u32> {
    list.iter().map(|v| u32::from(*v) % 60).collect()
}

impl Harness {
    fn call(&mut self, op: &Op) {
        let before = self.records.borrow().len();
        let (name, status) = self.apply(op);
        check_status(name, status, &self.records, before);
        check_outputs(&mut self.inst, &self.records);
    }

    fn apply(&mut self, op: &Op) -> (&'static str, Status) {
        let inst = &mut self.inst;
        match op {
            Op::Setup { tolerance, start, stop } => {
                let (start, stop) = (start.value(), stop.map(Num::value));
                let s = inst.setup_experiment(tolerance.map(Num::value), start, stop);
                if s == Status::Ok {
                    self.time = start;
                }
                ("fmi2SetupExperiment", s)
            }
            Op::Enter => ("fmi2EnterInitializationMode", inst.enter_initialization_mode()),
            Op::Exit => ("fmi2ExitInitializationMode", inst.exit_initialization_mode()),
            Op::Terminate => ("fmi2Terminate", inst.terminate()),
            Op::Reset => {
                let s = inst.reset();
                if s == Status::Ok {
                    self.time = 0.0;
                }
                ("fmi2Reset", s)
            }
            Op::SetReal(pairs) => {
                let vr: Vec<u32> = pairs.iter().map(|(v, _)| u32::from(*v) % 60).collect();
                let x: Vec<f64> = pairs.iter().map(|(_, n)| n.value()).collect();
                ("fmi2SetReal", inst.set_real(&vr, &x))
            }
            Op::SetInteger(pairs) => {
                let vr: Vec<u32> = pairs.iter().map(|(v, _)| u32::from(*v) % 60).collect();
                let x: Vec<i32> = pairs.iter().map(|(_, n)| *n).collect();
                ("fmi2SetInteger", inst.set_integer(&vr, &x))
            }
            Op::SetBoolean(pairs) => {
                let vr: Vec<u32> = pairs.iter().map(|(v, _)| u32::from(*v) % 60).collect();
                let x: Vec<bool> = pairs.iter().map(|(_, b)| *b).collect();
                ("fmi2SetBoolean", inst.set_boolean(&vr, &x))
            }
            Op::GetInteger(list) => {
                let vr = vrs(list);
                let mut out = vec![0; vr.len()];
                ("fmi2GetInteger", inst.get_integer(&vr, &mut out))
            }
            Op::GetBoolean(list) => {
                let vr = vrs(list);
                let mut out = vec![false; vr.len()];
                ("fmi2GetBoolean", inst.get_boolean(&vr, &mut out))
            }
            Op::GetString(list) => ("fmi2GetString", inst.get_string(&vrs(list))),
            Op::SetString(list) => ("fmi2SetString", inst.set_string(&vrs(list))),
            Op::SetInputDerivatives(list) => {
                let vr: Vec<u32> = list.iter().map(|(v, _, _)| u32::from(*v) % 60).collect();
                let order: Vec<i32> = list.iter().map(|(_, o, _)| i32::from(*o)).collect();
                let x: Vec<f64> = list.iter().map(|(_, _, n)| n.value()).collect();
                ("fmi2SetRealInputDerivatives", inst.set_real_input_derivatives(&vr, &order, &x))
            }
            Op::DoStep { tc, h } => {
                let tc = tc.map_or(self.time, Num::value);
                let h = h.value();
                let s = inst.do_step(tc, h);
                // fmi2Warning is a step done too (a warning of the range check, or of an input
                // never set).
                if matches!(s, Status::Ok | Status::Warning) {
                    assert_eq!(inst.state(), State::StepComplete);
                    let t = inst.get_real_status(STATUS_LAST_SUCCESSFUL_TIME).expect("allowed");
                    assert_eq!(t, tc + h, "fmi2DoStep({tc}, {h}) ended at {t}");
                    self.time = t;
                }
                if s == Status::Discard {
                    assert_eq!(inst.state(), State::StepFailed);
                }
                ("fmi2DoStep", s)
            }
            Op::GetState(k) => {
                let r = inst.get_state();
                let s = r.as_ref().err().copied().unwrap_or(Status::Ok);
                if let Ok(core) = r {
                    self.slots[usize::from(*k) % SLOTS] = Some(core);
                }
                ("fmi2GetFMUstate", s)
            }
            Op::SetState(k) => match &self.slots[usize::from(*k) % SLOTS] {
                Some(core) => {
                    let s = inst.set_state(core);
                    if s == Status::Ok {
                        if let Ok(t) = inst.get_real_status(STATUS_LAST_SUCCESSFUL_TIME) {
                            self.time = t;
                        }
                    }
                    ("fmi2SetFMUstate", s)
                }
                None => ("fmi2SetFMUstate", Status::Ok),
            },
            Op::FreeState(k) => {
                let slot = &self.slots[usize::from(*k) % SLOTS];
                let s = inst.check_free_state(slot.is_none());
                if s == Status::Ok {
                    self.slots[usize::from(*k) % SLOTS] = None;
                }
                ("fmi2FreeFMUstate", s)
            }
            Op::RoundTrip(from, to) => {
                let Some(core) = &self.slots[usize::from(*from) % SLOTS] else {
                    return ("fmi2SerializeFMUstate", Status::Ok);
                };
                let bytes = match inst.serialize(core) {
                    Ok(b) => b,
                    Err(s) => return ("fmi2SerializeFMUstate", s),
                };
                let size = inst.serialized_size(core).expect("allowed where serialize is");
                assert_eq!(size, bytes.len());
                match inst.deserialize(&bytes) {
                    Ok(back) => {
                        // What was written reads back as the same snapshot.
                        assert_eq!(inst.serialize(&back).expect("allowed"), bytes);
                        self.slots[usize::from(*to) % SLOTS] = Some(back);
                        ("fmi2DeSerializeFMUstate", Status::Ok)
                    }
                    Err(s) => panic!("a state this instance wrote was refused: {s:?}"),
                }
            }
            Op::DebugLogging { on, categories } => {
                let names: Vec<Option<&str>> = categories
                    .iter()
                    .map(|k| LOG_CATEGORIES.get(usize::from(*k)).map(|(n, _)| *n))
                    .collect();
                ("fmi2SetDebugLogging", inst.set_debug_logging(*on, &names))
            }
            Op::CancelStep => ("fmi2CancelStep", inst.cancel_step()),
            Op::Status(kind) => {
                let kind = STATUS_DO_STEP + i32::from(*kind);
                ("fmi2GetStatus", inst.get_unprovided_status("fmi2GetStatus", kind))
            }
            Op::RealStatus(kind) => (
                "fmi2GetRealStatus",
                inst.get_real_status(i32::from(*kind)).err().unwrap_or(Status::Ok),
            ),
            Op::BooleanStatus(kind) => {
                let kind = if *kind >= 0 { STATUS_TERMINATED } else { i32::from(*kind) };
                ("fmi2GetBooleanStatus", inst.get_boolean_status(kind).err().unwrap_or(Status::Ok))
            }
            Op::OutputDerivatives(list) => {
                let vr: Vec<u32> = list.iter().map(|(v, _)| u32::from(*v) % 60).collect();
                let order: Vec<i32> = list.iter().map(|(_, o)| i32::from(*o)).collect();
                let mut out = vec![0.0; vr.len()];
                let status = inst.get_real_output_derivatives(&vr, &order, &mut out);
                if status == Status::Ok {
                    assert!(out.iter().all(|x| x.is_finite()), "non-finite derivative {out:?}");
                }
                ("fmi2GetRealOutputDerivatives", status)
            }
            Op::DirectionalDerivative => match inst.interface() {
                Interface::CoSimulation => {
                    ("fmi2GetDirectionalDerivative", inst.get_directional_derivative())
                }
                Interface::ModelExchange => {
                    let vr = [20, 21];
                    let mut out = [0.0; 2];
                    let s = inst.get_directional_derivative_exchange(&vr, &[19], &[1.0], &mut out);
                    ("fmi2GetDirectionalDerivative", s)
                }
            },
            Op::EnterEventMode => ("fmi2EnterEventMode", inst.enter_event_mode()),
            Op::NewDiscreteStates => match inst.new_discrete_states() {
                Ok((info, s)) => {
                    if let Some(t) = info.next_event_time {
                        assert!(t.is_finite(), "nextEventTime {t}");
                    }
                    ("fmi2NewDiscreteStates", s)
                }
                Err(s) => ("fmi2NewDiscreteStates", s),
            },
            Op::EnterContinuousTimeMode => {
                ("fmi2EnterContinuousTimeMode", inst.enter_continuous_time_mode())
            }
            Op::CompletedIntegratorStep => (
                "fmi2CompletedIntegratorStep",
                inst.completed_integrator_step().map_or_else(|s| s, |(_, s)| s),
            ),
            Op::SetTime(t) => ("fmi2SetTime", inst.set_time(t.value())),
            Op::SetContinuousStates(x) => {
                let x: Vec<f64> = x.iter().map(|n| n.value()).collect();
                ("fmi2SetContinuousStates", inst.set_continuous_states(&x))
            }
            Op::GetContinuousStates(n) => {
                let mut x = vec![0.0; usize::from(*n % 8)];
                let s = inst.get_continuous_states(&mut x);
                if s == Status::Ok {
                    assert!(x.iter().all(|v| v.is_finite()), "non-finite states {x:?}");
                }
                ("fmi2GetContinuousStates", s)
            }
            Op::GetDerivatives(n) => {
                let mut dx = vec![0.0; usize::from(*n % 8)];
                let s = inst.get_derivatives(&mut dx);
                if s == Status::Ok {
                    assert!(dx.iter().all(|v| v.is_finite()), "non-finite derivatives {dx:?}");
                }
                ("fmi2GetDerivatives", s)
            }
            Op::GetEventIndicators(n) => {
                let mut z = vec![0.0; usize::from(*n % 8)];
                let s = inst.get_event_indicators(&mut z);
                if s == Status::Ok {
                    assert!(z.iter().all(|v| !v.is_nan()), "NaN event indicators {z:?}");
                }
                ("fmi2GetEventIndicators", s)
            }
            Op::GetNominals(n) => {
                let mut x = vec![0.0; usize::from(*n % 8)];
                ("fmi2GetNominalsOfContinuousStates", inst.get_nominals(&mut x))
            }
            Op::DirectionalDerivativeMe(unknowns, knowns) => {
                let u = vrs(unknowns);
                let k: Vec<u32> = knowns.iter().map(|(v, _)| u32::from(*v) % 60).collect();
                let seed: Vec<f64> = knowns.iter().map(|(_, n)| n.value()).collect();
                let mut out = vec![0.0; u.len()];
                let s = inst.get_directional_derivative_exchange(&u, &k, &seed, &mut out);
                ("fmi2GetDirectionalDerivative", s)
            }
        }
    }
}

fuzz_target!(|input: (bool, Vec<Op>)| {
    let (exchange, ops) = input;
    // FUZZ_DEBUG=1 prints the calls (to read a failing input: run the target on it).
    if std::env::var_os("FUZZ_DEBUG").is_some() {
        eprintln!("Model Exchange: {exchange}\n{ops:#?}");
    }
    let interface = if exchange { Interface::ModelExchange } else { Interface::CoSimulation };
    let (inst, records) = instance_of(interface, false);
    let mut h = Harness { inst, records, slots: Default::default(), time: 0.0 };
    for op in ops.iter().take(64) {
        h.call(op);
    }
});
