//! What the core knows of a model: the traits a model implements to sit behind every FMI
//! interface. [`Model`] is what every interface needs (variables, values, start, state);
//! [`CoSimulation`] adds the model's own integration between communication points. FMI 2.0
//! Model Exchange and FMI 3.0 add their traits beside it (continuous states, derivatives and
//! event indicators; arrays sized by a structural parameter), over the same `Model`.
#![forbid(unsafe_code)]

use super::description::{VarInfo, Version};
use super::machine::{Interface, State};
use crate::visit::StateVisitor;
use std::fmt;

/// A value of any FMI base type.
#[derive(Clone, Copy, PartialEq)]
pub enum Value {
    Real(f64),
    /// An integer of any of the FMI types (Int32; FMI 3.0's Int64 and UInt64): each fits, so
    /// the model sees, and names in a refusal, the value the host sent.
    Integer(i128),
    Boolean(bool),
}

/// The bare value, as the traces show it.
impl fmt::Debug for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Real(x) => write!(f, "{x:?}"),
            Value::Integer(k) => write!(f, "{k:?}"),
            Value::Boolean(b) => write!(f, "{b:?}"),
        }
    }
}

impl Value {
    /// The real; the core has checked the base type.
    pub fn real(self) -> f64 {
        match self {
            Value::Real(x) => x,
            _ => unreachable!("checked by type"),
        }
    }

    /// The integer; the core has checked the base type.
    pub fn integer(self) -> i128 {
        match self {
            Value::Integer(k) => k,
            _ => unreachable!("checked by type"),
        }
    }

    /// The boolean; the core has checked the base type.
    pub fn boolean(self) -> bool {
        match self {
            Value::Boolean(b) => b,
            _ => unreachable!("checked by type"),
        }
    }
}

/// What the host set up for the experiment (fmi2SetupExperiment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setup {
    pub tolerance: Option<f64>,
    pub start_time: f64,
    pub stop_time: Option<f64>,
}

impl Setup {
    pub(crate) const NONE: Setup = Setup { tolerance: None, start_time: 0.0, stop_time: None };
}

/// A step that failed: the time the model reached, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct StepFailure {
    pub t: f64,
    pub message: String,
}

/// What a model's part of a restored state must agree with: the core's part, read before it.
#[derive(Clone, Copy, Debug)]
pub struct Restore {
    /// The interface of the instance that saved it.
    pub interface: Interface,
    /// The model description it served.
    pub version: Version,
    pub setup: Setup,
    /// The instance's state.
    pub state: State,
    /// The communication time (co-simulation), or the time the host set (Model Exchange).
    pub time: f64,
}

/// Messages a call leaves for the host, logged as warnings after the call's trace.
pub type Notes = Vec<String>;

/// A model behind the FMI core. The core checks every call (state, value reference, base
/// type, causality, array lengths, finiteness of the host's numbers) before it calls these
/// methods, and turns their errors into the interface's statuses and log messages.
pub trait Model: Clone + fmt::Debug + Sized {
    /// Version of the model's part of a serialized state; bump it when
    /// [`visit_state`](Self::visit_state) changes.
    const STATE_VERSION: u32;

    /// The variable with value reference `vr`; `None` past the last.
    fn variable(vr: u32) -> Option<&'static VarInfo>;
    /// The number of variables: value references are `0..variable_count()`.
    fn variable_count() -> usize;
    /// The interface's GUID: instantiation and restored states must match it.
    fn guid() -> &'static str;

    /// The model at its start values (instantiation and reset), serving the model
    /// description of `version` (FMI 3.0's has arrays sized by structural parameters).
    fn new(version: Version) -> Self;
    /// `Err(allowed)` when the model cannot integrate at relative tolerance `tol`.
    fn check_tolerance(tol: f64) -> Result<(), String>;

    /// The value of `vr` (a parameter, an input, or an output at the current time, computed
    /// now if need be). In initialization mode outputs are those of the start state.
    fn get(&mut self, vr: u32, setup: &Setup) -> Result<Value, String>;
    /// The values of array variable `vr` (FMI 3.0), row-major, into `out`, which the core
    /// has sized from the variable's dimensions.
    fn get_array(&mut self, vr: u32, setup: &Setup, out: &mut [f64]) -> Result<(), String>;
    /// Whether `vr` takes `value` (its range), without setting it.
    fn check(&self, vr: u32, value: Value) -> Result<(), String>;
    /// Sets `vr` to `value` after the same check. The core has checked that the variable may
    /// be set in `state`. Warnings go to `notes`.
    fn set(&mut self, vr: u32, value: Value, state: State, notes: &mut Notes)
        -> Result<(), String>;
    /// Whether input `vr` may be set in intermediate update mode (FMI 3.0
    /// `intermediateUpdate = "true"` on an input).
    fn intermediate_input(vr: u32) -> bool;
    /// Whether `vr` is marked `intermediateUpdate = "true"` (FMI 3.0), so that a host may
    /// name it in `requiredIntermediateVariables`: an intermediate input, or an output the
    /// model gives at any time inside a step.
    fn intermediate_variable(vr: u32) -> bool;
    /// Leaves initialization: checks every value together and starts at `setup.start_time`,
    /// for `interface` (its own integrator for co-simulation, the equations alone for Model
    /// Exchange).
    fn start(&mut self, setup: &Setup, interface: Interface) -> Result<(), String>;

    /// Visits the model's part of a state, after the core's: a writer reads each field, a
    /// reader overwrites and checks them against `at`.
    fn visit_state<V: StateVisitor>(&mut self, v: &mut V, at: &Restore) -> Result<(), String>;
}

/// A model that integrates itself between communication points (FMI co-simulation).
pub trait CoSimulation: Model {
    /// The highest order of output derivatives (`maxOutputDerivativeOrder`).
    const MAX_OUTPUT_DERIVATIVE_ORDER: i32;
    /// The highest order of input derivatives a host may send.
    const MAX_INPUT_DERIVATIVE_ORDER: i32;

    /// A communication step begins: the calls of [`do_step`](Self::do_step) up to its end
    /// (one, or the parts of an FMI 3.0 step with intermediate update) share one budget of
    /// work, so that a step returns in bounded time however it is cut.
    fn begin_step(&mut self);
    /// Integrates from the communication time `from` to exactly `to`. Warnings (also those
    /// of a step that then fails) go to `notes`.
    fn do_step(&mut self, from: f64, to: f64, notes: &mut Notes) -> Result<(), StepFailure>;
    /// Whether input `vr` takes derivatives (fmi2SetRealInputDerivatives).
    fn takes_derivatives(vr: u32) -> bool;
    /// Keeps the derivative of order `order` of input `vr` for the next step only. The core
    /// has checked that `vr` is an input that takes derivatives, the order and that the value
    /// is finite.
    fn set_input_derivative(&mut self, vr: u32, order: i32, value: f64);
    /// The derivative of order `order` of output `vr` at the current time; `Ok(None)` for an
    /// output that has none of that order.
    fn output_derivative(
        &mut self,
        vr: u32,
        order: i32,
        setup: &Setup,
    ) -> Result<Option<f64>, String>;
    /// The outputs that have derivatives of order `order`, for messages.
    fn outputs_with_derivatives(order: i32) -> &'static str;
    /// The host's intermediate-update callback set no intermediate input: the next step goes
    /// on from the inputs' samples held (the held value is not a new sample).
    fn hold_input(&mut self);
    /// The spacing of the intermediate points inside a communication step (FMI 3.0's
    /// intermediate update), where the host sets the model's inputs and, when it asked for
    /// `outputs`, reads them: `None` when there are none (the model takes no input between
    /// communication points, and the host wants no outputs there).
    fn intermediate_spacing(&self, outputs: bool) -> Option<f64>;
}

/// A model whose equations a host integrates (FMI Model Exchange): continuous states x, their
/// derivatives, event indicators, and the event iteration. The core checks the state, the
/// counts and the finiteness of the host's numbers before it calls these.
pub trait ModelExchange: Model {
    /// The number of event indicators, fixed by the model description.
    const INDICATORS: usize;

    /// Builds the equations from the current values if they are not built (initialization
    /// mode: the start state, as the outputs are there).
    fn prepare_exchange(&mut self, setup: &Setup) -> Result<(), String>;
    /// The number of continuous states the current values make.
    fn state_count(&self) -> usize;
    /// The name of continuous state `k`, for messages.
    fn state_name(&self, k: usize) -> String;
    fn set_time(&mut self, t: f64);
    /// Sets every state; the core has checked the count and that they are finite.
    fn set_states(&mut self, x: &[f64]);
    fn states(&self, out: &mut [f64]);
    /// The derivatives at the current time, states and inputs; an error where the equations
    /// cannot be evaluated there.
    fn derivatives(&mut self, out: &mut [f64]) -> Result<(), String>;
    fn event_indicators(&mut self, out: &mut [f64]);
    fn nominals(&self, out: &mut [f64]);
    /// One pass of the event iteration at the current time. Messages go to `notes`.
    fn update_discrete_states(&mut self, notes: &mut Notes) -> super::EventInfo;
    /// After an integrator step the host accepted: the model's checks at the step's end.
    fn completed_integrator_step(&mut self, notes: &mut Notes) -> Result<super::StepEnd, String>;
    /// The directional derivative of `unknowns` with respect to `knowns` along `seed` into
    /// `out` (the core has checked that `seed` is finite; the model checks the rest).
    fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        out: &mut [f64],
    ) -> Result<(), String>;
}
