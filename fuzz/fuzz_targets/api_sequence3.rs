//! Random sequences of fmi3 calls, with random arguments, through the safe `Instance` API
//! that the C functions forward to, on an FMI 3.0 co-simulation or Model Exchange instance
//! (the first byte). The harness plays the host of fmi3DoStep's intermediate update itself
//! (the interface layer's loop: plan, parts, the callback's mode between them, where it sets
//! `phi` and may call anything). Checks the properties of `beam_body_fuzz` after every call,
//! that a completed step lands exactly on tc + h in step mode, and that Model Exchange's
//! counts are the model's.
#![no_main]

use beam_body::fmi::description::BaseType;
use beam_body::fmi::{Interface, State, Status, Value};
use beam_body::fmi3::{Core, Instance};
use beam_body::fmu::variables::{Var, LOG_CATEGORIES};
use beam_body_fuzz::{check_outputs, check_status, instance3, Num, Records};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
enum Op {
    EnterInitializationMode { tolerance: Option<Num>, start: Num, stop: Option<Num> },
    Exit,
    Terminate,
    Reset,
    SetFloat64(Vec<(u8, Num)>),
    SetInt32(Vec<(u8, i32)>),
    SetInt64(Vec<(u8, i64)>),
    GetInt64(Vec<u8>),
    SetBoolean(Vec<(u8, bool)>),
    /// A type without variables (Float32 … Clock): get or set.
    NoVariables { ty: u8, set: bool, vrs: Vec<u8> },
    /// tc: `None` is the current time. With `phi`, through intermediate update: the host
    /// sets these values of φ in the callback's mode, one per part, and makes `inside` there.
    DoStep { tc: Option<Num>, h: Num, phi: Option<Vec<Num>>, inside: Option<Box<Op>> },
    EnterIntermediateUpdate,
    LeaveIntermediateUpdate,
    GetState(u8),
    SetState(u8),
    RoundTrip(u8, u8),
    DebugLogging { on: bool, categories: Vec<u8> },
    OutputDerivatives(Vec<(u8, i8)>),
    Unsupported(u8),
    // Model Exchange.
    EnterEventMode,
    UpdateDiscreteStates,
    EnterContinuousTimeMode,
    CompletedIntegratorStep,
    SetTime(Num),
    SetContinuousStates(Vec<Num>),
    GetDerivatives(u8),
    Counts,
}

const SLOTS: usize = 4;
const NO_VARIABLES: [(BaseType, &str, &str); 9] = [
    (BaseType::Float32, "GetFloat32", "SetFloat32"),
    (BaseType::Int8, "GetInt8", "SetInt8"),
    (BaseType::UInt8, "GetUInt8", "SetUInt8"),
    (BaseType::Int16, "GetInt16", "SetInt16"),
    (BaseType::UInt16, "GetUInt16", "SetUInt16"),
    (BaseType::UInt32, "GetUInt32", "SetUInt32"),
    (BaseType::String, "GetString", "SetString"),
    (BaseType::Binary, "GetBinary", "SetBinary"),
    (BaseType::Clock, "GetClock", "SetClock"),
];
/// The first is no longer unsupported: `Unsupported(k)` with k % 4 = 0 toggles configuration
/// mode, setting `n_elements` = 1 + (k / 4) % 4 on the way in (the variant keeps its place,
/// so that the committed regressions keep their meaning).
const UNSUPPORTED: [&str; 4] =
    ["EnterConfigurationMode", "EvaluateDiscreteStates", "GetAdjointDerivative", "EnterStepMode"];

struct Harness {
    inst: Instance,
    records: Records,
    slots: [Option<Box<Core>>; SLOTS],
    time: f64,
    /// Nesting of `inside` calls (an op inside a step inside an op …).
    depth: usize,
}

fn pairs<T: Copy>(list: &[(u8, T)]) -> (Vec<u32>, Vec<T>) {
    (list.iter().map(|(v, _)| u32::from(*v) % 64).collect(), list.iter().map(|(_, x)| *x).collect())
}

impl Harness {
    fn call(&mut self, op: &Op) {
        let before = self.records.borrow().len();
        let (name, status) = self.apply(op);
        check_status(name, status, &self.records, before);
        check_outputs(&mut self.inst, &self.records);
    }

    /// fmi3DoStep as `Instance::do_step_in_parts` runs it with the host's callback, whose part
    /// this plays: an op inside the callback needs the harness, which the instance's stored
    /// callback cannot reach.
    fn step(&mut self, tc: f64, h: f64, phi: &[Num], inside: Option<&Op>) -> Status {
        let target = match self.inst.plan_step(tc, h) {
            Ok(t) => t,
            Err(s) => return s,
        };
        let mut worst = Status::Ok;
        let mut k = 0;
        loop {
            let (s, reached) = self.inst.step_part(target, h);
            worst = worst.max(s);
            if s > Status::Warning || reached {
                break;
            }
            k += 1;
            assert!(k as f64 <= beam_body::fmi::MAX_PARTS + 1.0, "step {h}: {k} parts");
            assert_eq!(self.inst.enter_intermediate_update(), Status::Ok);
            assert_eq!(self.inst.state(), State::IntermediateUpdate);
            if let Some(x) = phi.get(k % phi.len().max(1)) {
                let s = self.inst.set_real(&[Var::Phi.vr()], &[x.value()]);
                assert!(s != Status::Fatal);
            }
            if let (Some(op), true) = (inside, self.depth < 2) {
                self.depth += 1;
                self.call(op);
                self.depth -= 1;
            }
            let left = self.inst.leave_intermediate_update();
            if left != Status::Ok {
                // The op inside changed the state (a reset, a restored FMU state): the step
                // is over for the host.
                return left;
            }
        }
        worst
    }

    fn apply(&mut self, op: &Op) -> (&'static str, Status) {
        let inst = &mut self.inst;
        match op {
            Op::EnterInitializationMode { tolerance, start, stop } => {
                let (start, stop) = (start.value(), stop.map(Num::value));
                let s = inst.enter_initialization_mode_with(tolerance.map(Num::value), start, stop);
                if s == Status::Ok {
                    self.time = start;
                }
                ("fmi3EnterInitializationMode", s)
            }
            Op::Exit => ("fmi3ExitInitializationMode", inst.exit_initialization_mode()),
            Op::Terminate => ("fmi3Terminate", inst.terminate()),
            Op::Reset => {
                let s = inst.reset();
                if s == Status::Ok {
                    self.time = 0.0;
                }
                ("fmi3Reset", s)
            }
            Op::SetFloat64(list) => {
                let (vr, x) = pairs(list);
                let x: Vec<f64> = x.iter().map(|n| n.value()).collect();
                ("fmi3SetFloat64", inst.set_real(&vr, &x))
            }
            Op::SetInt32(list) => {
                let (vr, x) = pairs(list);
                ("fmi3SetInt32", inst.set_integer(&vr, &x))
            }
            Op::SetInt64(list) => {
                let (vr, x) = pairs(list);
                let s = inst.set("SetInt64", BaseType::Int64, &vr, &x, |v: i64| {
                    Value::Integer(v.into())
                });
                ("fmi3SetInt64", s)
            }
            Op::GetInt64(list) => {
                let vr: Vec<u32> = list.iter().map(|v| u32::from(*v) % 64).collect();
                let mut out = vec![0i64; vr.len()];
                let s = inst.get("GetInt64", BaseType::Int64, &vr, &mut out, |v| {
                    v.integer() as i64
                });
                ("fmi3GetInt64", s)
            }
            Op::SetBoolean(list) => {
                let (vr, x) = pairs(list);
                ("fmi3SetBoolean", inst.set_boolean(&vr, &x))
            }
            Op::NoVariables { ty, set, vrs } => {
                let (base, get_name, set_name) = NO_VARIABLES[usize::from(*ty) % NO_VARIABLES.len()];
                let vr: Vec<u32> = vrs.iter().map(|v| u32::from(*v) % 64).collect();
                let name = if *set { set_name } else { get_name };
                let s = inst.no_variables(name, base, *set, &vr);
                if !vr.is_empty() {
                    assert_ne!(s, Status::Ok, "{name} of {vr:?}: no variable has that type");
                }
                (name, s)
            }
            Op::DoStep { tc, h, phi, inside } => {
                let tc = tc.map_or(self.time, Num::value);
                let h = h.value();
                let s = match phi {
                    None => inst.do_step(tc, h),
                    Some(phi) => self.step(tc, h, phi, inside.as_deref()),
                };
                let inst = &mut self.inst;
                if matches!(s, Status::Ok | Status::Warning) && inst.state() == State::StepComplete {
                    let (terminated, t) = inst.step_end();
                    assert!(!terminated);
                    assert_eq!(t, tc + h, "fmi3DoStep({tc}, {h}) ended at {t}");
                    assert_eq!(inst.time(), t);
                    self.time = t;
                }
                if s == Status::Discard {
                    assert_eq!(inst.state(), State::StepFailed);
                    assert!(inst.step_end().0, "a discarded step sets terminateSimulation");
                }
                ("fmi3DoStep", s)
            }
            Op::EnterIntermediateUpdate => ("fmi3DoStep", inst.enter_intermediate_update()),
            Op::LeaveIntermediateUpdate => ("fmi3DoStep", inst.leave_intermediate_update()),
            Op::GetState(k) => {
                let r = inst.get_state();
                let s = r.as_ref().err().copied().unwrap_or(Status::Ok);
                if let Ok(core) = r {
                    self.slots[usize::from(*k) % SLOTS] = Some(core);
                }
                ("fmi3GetFMUState", s)
            }
            Op::SetState(k) => match &self.slots[usize::from(*k) % SLOTS] {
                Some(core) => {
                    let s = inst.set_state(core);
                    if s == Status::Ok {
                        self.time = inst.time();
                    }
                    ("fmi3SetFMUState", s)
                }
                None => ("fmi3SetFMUState", Status::Ok),
            },
            Op::RoundTrip(from, to) => {
                let Some(core) = &self.slots[usize::from(*from) % SLOTS] else {
                    return ("fmi3SerializeFMUState", Status::Ok);
                };
                let bytes = match inst.serialize(core) {
                    Ok(b) => b,
                    Err(s) => return ("fmi3SerializeFMUState", s),
                };
                match inst.deserialize(&bytes) {
                    Ok(back) => {
                        assert_eq!(inst.serialize(&back).expect("allowed"), bytes);
                        self.slots[usize::from(*to) % SLOTS] = Some(back);
                        ("fmi3DeserializeFMUState", Status::Ok)
                    }
                    Err(s) => panic!("a state this instance wrote was refused: {s:?}"),
                }
            }
            Op::DebugLogging { on, categories } => {
                let names: Vec<Option<&str>> = categories
                    .iter()
                    .map(|k| LOG_CATEGORIES.get(usize::from(*k)).map(|(n, _)| *n))
                    .collect();
                ("fmi3SetDebugLogging", inst.set_debug_logging(*on, &names))
            }
            Op::OutputDerivatives(list) => {
                let (vr, order) = pairs(list);
                let order: Vec<i32> = order.iter().map(|o| i32::from(*o)).collect();
                let mut out = vec![0.0; vr.len()];
                let s = inst.get_real_output_derivatives(&vr, &order, &mut out);
                if s == Status::Ok {
                    assert!(out.iter().all(|x| x.is_finite()), "non-finite derivative {out:?}");
                }
                ("fmi3GetOutputDerivatives", s)
            }
            Op::Unsupported(k) if *k % 4 == 0 => {
                if inst.state() == State::ConfigurationMode {
                    return ("fmi3ExitConfigurationMode", inst.exit_configuration_mode());
                }
                let s = inst.enter_configuration_mode();
                if s == Status::Ok {
                    let n = [1 + u64::from(*k / 4) % 4];
                    let set = inst.set("SetUInt64", BaseType::UInt64, &[Var::NElements.vr()], &n, |v| {
                        Value::Integer(v.into())
                    });
                    assert_eq!(set, Status::Ok, "n_elements = {n:?} in configuration mode");
                }
                ("fmi3EnterConfigurationMode", s)
            }
            Op::Unsupported(k) => {
                let name = UNSUPPORTED[usize::from(*k) % UNSUPPORTED.len()];
                let s = inst.unsupported(name, "fuzz");
                assert_eq!(s, Status::Error);
                (name, s)
            }
            Op::EnterEventMode => ("fmi3EnterEventMode", inst.enter_event_mode()),
            Op::UpdateDiscreteStates => match inst.new_discrete_states() {
                Ok((info, s)) => {
                    if let Some(t) = info.next_event_time {
                        assert!(t.is_finite(), "nextEventTime {t}");
                    }
                    ("fmi3UpdateDiscreteStates", s)
                }
                Err(s) => ("fmi3UpdateDiscreteStates", s),
            },
            Op::EnterContinuousTimeMode => {
                ("fmi3EnterContinuousTimeMode", inst.enter_continuous_time_mode())
            }
            Op::CompletedIntegratorStep => (
                "fmi3CompletedIntegratorStep",
                inst.completed_integrator_step().map_or_else(|s| s, |(_, s)| s),
            ),
            Op::SetTime(t) => ("fmi3SetTime", inst.set_time(t.value())),
            Op::SetContinuousStates(x) => {
                let x: Vec<f64> = x.iter().map(|n| n.value()).collect();
                ("fmi3SetContinuousStates", inst.set_continuous_states(&x))
            }
            Op::GetDerivatives(n) => {
                // Up to 19: the states of 1 to 4 elements (6 to 18), and counts around them.
                let mut dx = vec![0.0; usize::from(*n % 20)];
                let s = inst.get_derivatives(&mut dx);
                if s == Status::Ok {
                    assert!(dx.iter().all(|v| v.is_finite()), "non-finite derivatives {dx:?}");
                }
                ("fmi3GetContinuousStateDerivatives", s)
            }
            Op::Counts => {
                let n = inst.number_of_continuous_states();
                let z = inst.number_of_event_indicators();
                if let (Ok(n), Ok(z)) = (n, z) {
                    // 4 states a element (q and dq) and the filter's 2, 1 to 4 elements here.
                    assert!(n % 4 == 2 && (6..=18).contains(&n) && z == 2, "{n} states, {z}");
                }
                let s = n.err().or(z.err()).unwrap_or(Status::Ok);
                ("fmi3GetNumberOf", s)
            }
        }
    }
}

fuzz_target!(|input: (bool, Vec<Op>)| {
    let (exchange, ops) = input;
    if std::env::var_os("FUZZ_DEBUG").is_some() {
        eprintln!("Model Exchange: {exchange}\n{ops:#?}");
    }
    let interface = if exchange { Interface::ModelExchange } else { Interface::CoSimulation };
    let (inst, records) = instance3(interface);
    let mut h = Harness { inst, records, slots: Default::default(), time: 0.0, depth: 0 };
    for op in ops.iter().take(64) {
        h.call(op);
    }
});
