//! What the fuzz targets share: an instance whose log is recorded, and the checks that hold
//! after any call, whatever the bytes were.
//!
//! The properties (each a panic, which libFuzzer reports as a crash):
//! - no call panics, and none returns fmi2Fatal (only a caught panic may);
//! - every fmi2Error or fmi2Discard is logged, with a message that names the function;
//! - every Real variable that can be read is finite (no NaN is reported as a valid output);
//! - an accepted serialized state serializes back to the same bytes, and restores an
//!   instance that then behaves like any other.

use std::cell::RefCell;
use std::rc::Rc;

use beam_body::fmi::{Interface, State, Status};
use beam_body::fmi2::types::{FMI2_COSIMULATION, FMI2_MODEL_EXCHANGE};
use beam_body::fmi2::{instantiate, Instance};
use beam_body::fmi3;
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use beam_body::fmu::variables::{guid, BaseType, VARIABLES};

/// The log records of one instance: (status, category, message).
pub type Records = Rc<RefCell<Vec<(Status, String, String)>>>;

/// A co-simulation instance with a recording logger.
pub fn instance(logging_on: bool) -> (Instance, Records) {
    instance_of(Interface::CoSimulation, logging_on)
}

/// An instance of `interface` with a recording logger.
pub fn instance_of(interface: Interface, logging_on: bool) -> (Instance, Records) {
    let fmu_type = match interface {
        Interface::CoSimulation => FMI2_COSIMULATION,
        Interface::ModelExchange => FMI2_MODEL_EXCHANGE,
    };
    let records: Records = Rc::default();
    let sink = records.clone();
    let logger = Box::new(move |status: Status, category: &str, message: &str| {
        sink.borrow_mut().push((status, category.to_string(), message.to_string()));
    });
    let inst =
        instantiate("fuzz", fmu_type, guid(), logger, logging_on).expect("a valid instantiation");
    (inst, records)
}

/// An FMI 3.0 instance of `interface` with a recording logger; co-simulation's asks for
/// intermediate update of `phi` (the harness plays the host's callback itself).
pub fn instance3(interface: Interface) -> (Instance, Records) {
    let records: Records = Rc::default();
    let sink = records.clone();
    let logger = Box::new(move |status: Status, category: &str, message: &str| {
        sink.borrow_mut().push((status, category.to_string(), message.to_string()));
    });
    let phi = beam_body::fmu::variables::Var::Phi.vr();
    let cs = (interface == Interface::CoSimulation).then(|| fmi3::CoSimulationArgs {
        event_mode_used: false,
        required: std::slice::from_ref(&phi),
        intermediate_update: Some(Rc::new(|_, _| {})),
    });
    let inst = fmi3::instantiate("fuzz", interface, guid(), logger, false, cs)
        .expect("a valid instantiation");
    (inst, records)
}

/// A number, biased towards the values that matter at boundaries.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum Num {
    Zero,
    One,
    MinusOne,
    Nan,
    Inf,
    NegInf,
    Tiny,
    Huge,
    /// k/100: the ordinary range of the parameters and of communication steps.
    Hundredths(i16),
    Raw(f64),
}

impl Num {
    pub fn value(self) -> f64 {
        match self {
            Num::Zero => 0.0,
            Num::One => 1.0,
            Num::MinusOne => -1.0,
            Num::Nan => f64::NAN,
            Num::Inf => f64::INFINITY,
            Num::NegInf => f64::NEG_INFINITY,
            Num::Tiny => 1e-300,
            Num::Huge => 1e300,
            Num::Hundredths(k) => f64::from(k) / 100.0,
            Num::Raw(x) => x,
        }
    }
}

/// Checks the status of the call `function` made, against the records it logged (those
/// after `before`).
pub fn check_status(function: &str, status: Status, records: &Records, before: usize) {
    assert_ne!(status, Status::Fatal, "{function} returned fmi2Fatal");
    if matches!(status, Status::Warning | Status::Error | Status::Discard) {
        let log = records.borrow();
        let logged = log[before..].iter().any(|(s, _, m)| *s == status && m.contains(function));
        assert!(logged, "{function} returned {status:?} without logging why: {:?}", &log[before..]);
    }
}

/// Whether fmi2GetReal is allowed in `state`.
fn readable(state: State) -> bool {
    matches!(
        state,
        State::InitializationMode
            | State::StepComplete
            | State::StepFailed
            | State::Terminated
            | State::Error
            | State::EventMode
            | State::ContinuousTimeMode
            | State::IntermediateUpdate
    )
}

/// Reads every Real variable where the state allows it, and checks that each is finite.
pub fn check_outputs(inst: &mut Instance, records: &Records) {
    if !readable(inst.state()) {
        return;
    }
    // The scalars of the instance's model description (FMI 3.0's arrays are read by count).
    let version = inst.api().version;
    let vrs: Vec<u32> = VARIABLES
        .iter()
        .filter(|v| v.ty.base() == BaseType::Real && v.dims.is_empty() && v.in_version(version))
        .map(|v| v.vr())
        .collect();
    let mut out = vec![0.0; vrs.len()];
    let before = records.borrow().len();
    let status = inst.get_real(&vrs, &mut out);
    let name = if inst.api().prefix == "fmi3" { "fmi3GetFloat64" } else { "fmi2GetReal" };
    check_status(name, status, records, before);
    if status == Status::Ok {
        for (vr, x) in vrs.iter().zip(&out) {
            assert!(x.is_finite(), "{name} gave {x} for {}", VARIABLES[*vr as usize].name);
        }
    }
}

pub use beam_body::fmi::{reseal, HEADER};
