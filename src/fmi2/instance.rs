//! One FMU instance, in safe Rust: the state machine, argument checks, get and set by value
//! reference, `do_step` with the internal BDF, and FMU state snapshots.
//!
//! [`ffi`](super::ffi) turns C pointers into slices and strings and calls these methods;
//! everything else happens here. Each method logs its own errors through the instance's
//! [`Logger`] and returns the FMI status. No `unsafe`, no I/O.
#![forbid(unsafe_code)]

use super::state;
use super::variables::{
    BaseType, Causality, Type, Var, Variable, CAPABILITIES, LOG_CATEGORIES, VARIABLES,
};
use crate::model::{
    BeamBody, Formulation, HostSignal, Interpolation, Outputs, PaperLaw, Params, Sample,
};
use crate::sim::{InitialState, Run, SolverOptions};
use crate::solver::FixedStep;
use std::fmt;

/// fmi2Status.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[repr(i32)]
pub enum Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
}

/// The states of the FMI 2.0 co-simulation state machine (spec §4.2.4) that an instance can
/// be in. `stepInProgress` and `stepCanceled` never occur: steps are synchronous.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    Instantiated,
    InitializationMode,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
    Fatal,
}

impl State {
    const ALL: [State; 7] = [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::StepFailed,
        State::Terminated,
        State::Error,
        State::Fatal,
    ];

    fn bit(self) -> u32 {
        1 << self as u32
    }

    fn name(self) -> &'static str {
        match self {
            State::Instantiated => "instantiated",
            State::InitializationMode => "initialization mode",
            State::StepComplete => "step complete",
            State::StepFailed => "step failed",
            State::Terminated => "terminated",
            State::Error => "error",
            State::Fatal => "fatal",
        }
    }

    pub(super) fn to_index(self) -> u64 {
        self as u64
    }

    pub(super) fn from_index(k: u64) -> Option<State> {
        State::ALL.get(k as usize).copied()
    }
}

/// Sets of states in which a function may be called.
mod mask {
    use super::State::*;
    const fn bits(states: &[super::State]) -> u32 {
        let mut m = 0;
        let mut k = 0;
        while k < states.len() {
            m |= 1 << states[k] as u32;
            k += 1;
        }
        m
    }
    pub const ANY_BUT_FATAL: u32 =
        bits(&[Instantiated, InitializationMode, StepComplete, StepFailed, Terminated, Error]);
    pub const INSTANTIATED: u32 = bits(&[Instantiated]);
    pub const INITIALIZATION: u32 = bits(&[InitializationMode]);
    pub const STEP_COMPLETE: u32 = bits(&[StepComplete]);
    pub const TERMINATE: u32 = bits(&[StepComplete, StepFailed]);
    pub const GET: u32 = bits(&[InitializationMode, StepComplete, StepFailed, Terminated, Error]);
    pub const SET: u32 = bits(&[Instantiated, InitializationMode, StepComplete]);
    pub const STATUS: u32 = bits(&[StepComplete, StepFailed, Terminated]);
    pub const OUTPUT_DERIVATIVES: u32 = bits(&[StepComplete, StepFailed, Terminated, Error]);
    /// No state: the function needs a step in progress, which never exists.
    pub const NONE: u32 = 0;
}

/// fmi2Type: only co-simulation is provided.
pub const FMI2_COSIMULATION: i32 = 1;

/// fmi2StatusKind.
pub const STATUS_DO_STEP: i32 = 0;
pub const STATUS_PENDING: i32 = 1;
pub const STATUS_LAST_SUCCESSFUL_TIME: i32 = 2;
pub const STATUS_TERMINATED: i32 = 3;

/// Where log messages go: (status, category, message). The FFI layer forwards them to the
/// host's logger; tests collect them.
pub type Logger = Box<dyn FnMut(Status, &str, &str)>;

/// Where φ comes from (the `phi_source` enumeration).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhiSource {
    Input,
    Law,
}

/// The values of the parameters and the input.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Values {
    pub params: Params,
    pub law: PaperLaw,
    pub atol: f64,
    pub fixed_step: f64,
    pub formulation: Formulation,
    pub phi_source: PhiSource,
    pub max_order: i32,
    pub fixed_order: i32,
    pub phi_extrapolation: i32,
    pub phi_interpolation: Interpolation,
    pub stability_guard: bool,
    pub phi: f64,
}

/// A value of any FMI base type.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Value {
    Real(f64),
    Integer(i32),
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

impl Values {
    /// The start values of the variable table.
    pub(super) fn from_table() -> Values {
        let mut v = Values {
            params: Params::default(),
            law: PaperLaw::default(),
            atol: 0.0,
            fixed_step: 0.0,
            formulation: Formulation::Reduced,
            phi_source: PhiSource::Input,
            max_order: 5,
            fixed_order: 2,
            phi_extrapolation: 3,
            phi_interpolation: Interpolation::Smooth,
            stability_guard: true,
            phi: 0.0,
        };
        for var in VARIABLES {
            let start = match var.ty {
                Type::Real { start: Some(s), .. } => Value::Real(s),
                Type::Real { start: None, .. } => continue,
                Type::Integer { start, .. } | Type::Enumeration { start, .. } => {
                    Value::Integer(start)
                }
                Type::Boolean { start } => Value::Boolean(start),
            };
            v.set(var, start).expect("the table's start values are in range");
        }
        v
    }

    /// Sets `var` after checking the value's range; the error names the variable and the
    /// allowed range.
    pub(super) fn set(&mut self, var: &Variable, value: Value) -> Result<(), String> {
        let bad = |allowed: &str, shown: String| {
            Err(format!("`{}` = {shown} is out of range: must be {allowed}", var.name))
        };
        match value {
            Value::Real(x) => {
                // Non-finite values are refused with the variable's whole range, not just
                // "finite": `EI` = NaN says "positive and finite".
                let finite = x.is_finite();
                match var.var {
                    Var::L | Var::Ei | Var::M | Var::M2 | Var::JC | Var::R | Var::G => {
                        self.params.set(var.name, x).map_err(|e| e.to_string())?;
                    }
                    Var::TRot if finite && x > 0.0 => self.law.t_rot = x,
                    Var::TRot => return bad("positive and finite", format!("{x:?}")),
                    Var::Atol if finite && x >= 0.0 => self.atol = x,
                    Var::FixedStep if finite && x >= 0.0 => self.fixed_step = x,
                    Var::Atol | Var::FixedStep => {
                        return bad("non-negative and finite", format!("{x:?}"))
                    }
                    Var::PhiEnd | Var::Phi if !finite => return bad("finite", format!("{x:?}")),
                    Var::PhiEnd => self.law.phi_end = x,
                    Var::Phi => self.phi = x,
                    _ => unreachable!("outputs are rejected before, other types by type"),
                }
            }
            Value::Integer(k) => {
                let (lo, hi) = match var.ty {
                    Type::Integer { min, max, .. } => (min, max),
                    Type::Enumeration { ty, .. } => (1, ty.items.len() as i32),
                    _ => unreachable!("checked by type"),
                };
                if !(lo..=hi).contains(&k) {
                    let allowed = match var.ty {
                        Type::Enumeration { ty, .. } => {
                            let items: Vec<String> = (lo..=hi)
                                .map(|j| format!("{j} ({})", ty.items[(j - 1) as usize].0))
                                .collect();
                            format!("one of {}", items.join(", "))
                        }
                        _ => format!("an integer in {lo}..={hi}"),
                    };
                    return bad(&allowed, k.to_string());
                }
                match var.var {
                    Var::Formulation => self.formulation = Formulation::ALL[(k - 1) as usize],
                    Var::PhiSource => {
                        self.phi_source = if k == 1 { PhiSource::Input } else { PhiSource::Law }
                    }
                    Var::MaxOrder => self.max_order = k,
                    Var::FixedOrder => self.fixed_order = k,
                    Var::PhiExtrapolation => self.phi_extrapolation = k,
                    Var::PhiInterpolation => {
                        self.phi_interpolation = Interpolation::ALL[(k - 1) as usize]
                    }
                    _ => unreachable!("checked by type"),
                }
            }
            Value::Boolean(b) => match var.var {
                Var::StabilityGuard => self.stability_guard = b,
                _ => unreachable!("checked by type"),
            },
        }
        Ok(())
    }

    /// The value of a parameter or the input.
    pub(super) fn get(&self, var: Var) -> Option<Value> {
        let p = &self.params;
        Some(match var {
            Var::L => Value::Real(p.l),
            Var::Ei => Value::Real(p.ei),
            Var::M => Value::Real(p.m),
            Var::M2 => Value::Real(p.m2),
            Var::JC => Value::Real(p.j_c),
            Var::R => Value::Real(p.r),
            Var::G => Value::Real(p.g),
            Var::TRot => Value::Real(self.law.t_rot),
            Var::PhiEnd => Value::Real(self.law.phi_end),
            Var::Atol => Value::Real(self.atol),
            Var::FixedStep => Value::Real(self.fixed_step),
            Var::Phi => Value::Real(self.phi),
            Var::Formulation => {
                let k = Formulation::ALL.iter().position(|f| *f == self.formulation);
                Value::Integer(k.expect("every formulation is listed") as i32 + 1)
            }
            Var::PhiSource => Value::Integer(match self.phi_source {
                PhiSource::Input => 1,
                PhiSource::Law => 2,
            }),
            Var::MaxOrder => Value::Integer(self.max_order),
            Var::FixedOrder => Value::Integer(self.fixed_order),
            Var::PhiExtrapolation => Value::Integer(self.phi_extrapolation),
            Var::PhiInterpolation => {
                let k = Interpolation::ALL.iter().position(|i| *i == self.phi_interpolation);
                Value::Integer(k.expect("every interpolation is listed") as i32 + 1)
            }
            Var::StabilityGuard => Value::Boolean(self.stability_guard),
            _ => return None,
        })
    }

    /// The integrator settings, with the experiment's relative tolerance.
    fn solver_options(&self, rtol: f64) -> SolverOptions {
        SolverOptions {
            rtol,
            atol: (self.atol > 0.0).then_some(self.atol),
            max_order: self.max_order as usize,
            fixed_step: (self.fixed_step > 0.0)
                .then_some(FixedStep { h: self.fixed_step, order: self.fixed_order as usize }),
            stability_guard: self.stability_guard,
            max_steps: MAX_STEPS_PER_DO_STEP,
        }
    }
}

/// Most internal steps in one fmi2DoStep, so that a step always returns in bounded time
/// (about a second in a release build); beyond it the step is discarded with a message. The
/// stiffest scene of the sweep (EI × 10⁷) needs about 5·10⁴ steps per simulated second.
pub const MAX_STEPS_PER_DO_STEP: u64 = 1_000_000;

/// What fmi2SetupExperiment defined.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Setup {
    pub tolerance: Option<f64>,
    pub start_time: f64,
    pub stop_time: Option<f64>,
}

/// Relative tolerance when the host defines none: the DefaultExperiment's.
const DEFAULT_TOLERANCE: f64 = super::variables::DEFAULT_EXPERIMENT.tolerance;

impl Setup {
    fn rtol(&self) -> f64 {
        self.tolerance.unwrap_or(DEFAULT_TOLERANCE)
    }
}

/// Everything an FMU state holds: the whole instance except its name and logger.
#[derive(Clone, Debug)]
pub struct Core {
    pub(super) state: State,
    pub(super) values: Values,
    pub(super) setup: Setup,
    /// The integrator, from fmi2ExitInitializationMode on.
    pub(super) run: Option<Run>,
    /// φ' and φ'' sent for the next step only.
    pub(super) pending: [Option<f64>; 2],
    /// The communication time: the start time, then the end of the last step.
    pub(super) time: f64,
    pub(super) last_successful_time: f64,
    /// fmi2Terminated: the FMU stopped the run.
    pub(super) terminated: bool,
    /// Outputs at `time`, computed at the first request after a change.
    pub(super) cache: Option<Outputs>,
}

impl Core {
    pub(super) fn new() -> Core {
        Core {
            state: State::Instantiated,
            values: Values::from_table(),
            setup: Setup { tolerance: None, start_time: 0.0, stop_time: None },
            run: None,
            pending: [None, None],
            time: 0.0,
            last_successful_time: 0.0,
            terminated: false,
            cache: None,
        }
    }

    /// The host's sample of φ at `t`: the input's value and the derivatives sent for the
    /// next step.
    pub(super) fn sample(&self, t: f64) -> Sample {
        Sample { t, phi: self.values.phi, dphi: self.pending[0], ddphi: self.pending[1] }
    }

    /// A fresh integrator at the start time, after checking every parameter together.
    pub(super) fn build_run(&self) -> Result<Run, String> {
        let v = &self.values;
        let model = BeamBody::new(v.params).map_err(|e| e.to_string())?;
        let t0 = self.setup.start_time;
        let options = v.solver_options(self.setup.rtol());
        let init = InitialState::default();
        let run = match v.phi_source {
            PhiSource::Law => Run::with_law(model, v.formulation, &options, t0, init, v.law),
            PhiSource::Input => {
                let signal = HostSignal::new(v.phi_interpolation, v.phi_extrapolation as usize);
                Run::with_host(model, v.formulation, &options, t0, init, signal, self.sample(t0))
            }
        }
        .map_err(|e| e.to_string())?;
        let phi0 = run.piece().eval(t0).phi;
        run.model().check_start(phi0, 0.0, 0.0).map_err(|e| e.to_string())?;
        Ok(run)
    }
}

/// Log switches, per category of [`LOG_CATEGORIES`].
#[derive(Clone, Copy, Debug, Default)]
struct LogFlags([bool; LOG_CATEGORIES.len()]);

/// One FMU instance.
pub struct Instance {
    name: String,
    log: Logger,
    logging: LogFlags,
    core: Core,
}

impl fmt::Debug for Instance {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Instance").field("name", &self.name).field("core", &self.core).finish()
    }
}

fn category_of(status: Status) -> &'static str {
    match status {
        Status::Ok => "logCalls",
        Status::Warning => "logStatusWarning",
        Status::Discard => "logStatusDiscard",
        Status::Error => "logStatusError",
        Status::Fatal => "logStatusFatal",
    }
}

/// "`name` (vr) = value, …" for the traces of get and set calls; formatted only when a
/// trace is written.
struct Listing<'a, T>(&'a [u32], &'a [T]);

impl<T: fmt::Debug> fmt::Display for Listing<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, (vr, value)) in self.0.iter().zip(self.1).enumerate() {
            let name = Var::from_vr(*vr).map_or("?", |v| v.info().name);
            let sep = if k == 0 { "" } else { ", " };
            write!(f, "{sep}`{name}` ({vr}) = {value:?}")?;
        }
        if self.0.is_empty() {
            write!(f, "no variables")?;
        }
        Ok(())
    }
}

impl Instance {
    /// fmi2Instantiate. `None`, after logging why, for an empty name, a GUID that is not
    /// this model's, or a type other than co-simulation.
    pub fn instantiate(
        name: &str,
        fmu_type: i32,
        guid: &str,
        mut log: Logger,
        logging_on: bool,
    ) -> Option<Instance> {
        let fail = |log: &mut Logger, msg: String| {
            log(Status::Error, "logStatusError", &format!("fmi2Instantiate: {msg}"));
            None
        };
        if name.is_empty() {
            return fail(&mut log, "instanceName is empty".into());
        }
        if fmu_type != FMI2_COSIMULATION {
            return fail(
                &mut log,
                format!(
                    "fmuType = {fmu_type}: this FMU provides co-simulation only \
                     (fmi2CoSimulation = {FMI2_COSIMULATION})"
                ),
            );
        }
        let ours = super::variables::guid();
        if guid != ours {
            return fail(
                &mut log,
                format!("fmuGUID {guid} does not match this binary's {ours}: wrong or stale FMU"),
            );
        }
        let mut inst = Instance {
            name: name.to_string(),
            log,
            logging: LogFlags([logging_on; LOG_CATEGORIES.len()]),
            core: Core::new(),
        };
        inst.trace(format_args!("fmi2Instantiate: instance `{name}`"));
        Some(inst)
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn state(&self) -> State {
        self.core.state
    }

    // ----- logging ------------------------------------------------------------------------

    /// Logs `msg`. Errors, discards and fatal errors always go out; other messages only
    /// when their category is on.
    pub fn log(&mut self, status: Status, msg: &str) {
        let category = category_of(status);
        let always = status >= Status::Discard;
        let k = LOG_CATEGORIES.iter().position(|(c, _)| *c == category).unwrap_or(0);
        if always || self.logging.0[k] {
            (self.log)(status, category, msg);
        }
    }

    /// Logs `msg` at `status` and returns it.
    fn fail(&mut self, status: Status, msg: impl fmt::Display) -> Status {
        self.log(status, &msg.to_string());
        status
    }

    /// Logs a call when `logCalls` is on; the message is built only then.
    fn trace(&mut self, msg: fmt::Arguments<'_>) {
        if self.logging.0[4] {
            (self.log)(Status::Ok, "logCalls", &msg.to_string());
        }
    }

    /// Traces an FMU-state call with the instance's state and time afterwards.
    fn trace_state(&mut self, what: &str) {
        let (state, t) = (self.core.state, self.core.time);
        self.trace(format_args!("{what}: state `{}`, t = {t:?}", state.name()));
    }

    /// fmi2FreeInstance: traces the call; the caller then drops the instance. Allowed in
    /// every state, fatal included: freeing touches no model data, and a host that frees a
    /// fatal instance (which FMI 2.0 does not ask of it) should not leak it.
    pub fn trace_free(&mut self) {
        if self.logging.0[4] {
            let msg = format!("fmi2FreeInstance: instance `{}`", self.name);
            (self.log)(Status::Ok, "logCalls", &msg);
        }
    }

    /// Refuses every call on a fatal instance before the call touches anything (its
    /// arguments included): logs the illegal call and returns false.
    pub fn check_not_fatal(&mut self, func: &str) -> bool {
        self.allowed(func, mask::ANY_BUT_FATAL)
    }

    /// Checks that `func` may be called in the current state; logs and returns false if not.
    fn allowed(&mut self, func: &str, mask: u32) -> bool {
        let state = self.core.state;
        if mask & state.bit() != 0 {
            return true;
        }
        self.log(
            Status::Error,
            &format!("{func}: illegal call sequence: not allowed in state `{}`", state.name()),
        );
        false
    }

    /// fmi2SetDebugLogging. `categories`: `None` where the host passed NULL or invalid
    /// UTF-8. An empty list switches every category.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[Option<&str>]) -> Status {
        const F: &str = "fmi2SetDebugLogging";
        if !self.allowed(F, mask::ANY_BUT_FATAL) {
            return Status::Error;
        }
        let mut flags = self.logging;
        if categories.is_empty() {
            flags.0 = [on; LOG_CATEGORIES.len()];
        }
        for c in categories {
            let Some(k) = c.and_then(|c| LOG_CATEGORIES.iter().position(|(n, _)| *n == c)) else {
                let names: Vec<&str> = LOG_CATEGORIES.iter().map(|(n, _)| *n).collect();
                return self.fail(
                    Status::Error,
                    format!("{F}: unknown log category {c:?}: must be one of {}", names.join(", ")),
                );
            };
            if LOG_CATEGORIES[k].0 == "logAll" {
                flags.0 = [on; LOG_CATEGORIES.len()];
            } else {
                flags.0[k] = on;
            }
        }
        self.logging = flags;
        self.trace(format_args!("{F}: loggingOn = {on}, categories {categories:?}"));
        Status::Ok
    }

    // ----- lifecycle ----------------------------------------------------------------------

    /// fmi2SetupExperiment.
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Status {
        const F: &str = "fmi2SetupExperiment";
        if !self.allowed(F, mask::INSTANTIATED) {
            return Status::Error;
        }
        if let Some(tol) = tolerance {
            if !(tol.is_finite() && (1e-14..=1.0).contains(&tol)) {
                return self.fail(
                    Status::Error,
                    format!("{F}: tolerance = {tol:?} is out of range: must be in [1e-14, 1]"),
                );
            }
        }
        if !start_time.is_finite() {
            return self.fail(
                Status::Error,
                format!("{F}: startTime = {start_time} is out of range: must be finite"),
            );
        }
        if let Some(stop) = stop_time {
            if !(stop.is_finite() && stop >= start_time) {
                return self.fail(
                    Status::Error,
                    format!(
                        "{F}: stopTime = {stop} is out of range: must be finite and \
                         >= startTime = {start_time}"
                    ),
                );
            }
        }
        let setup = Setup { tolerance, start_time, stop_time };
        self.core.setup = setup;
        self.core.time = start_time;
        self.core.last_successful_time = start_time;
        self.core.cache = None;
        self.trace(format_args!("{F}: {setup:?}"));
        Status::Ok
    }

    /// fmi2EnterInitializationMode.
    pub fn enter_initialization_mode(&mut self) -> Status {
        if !self.allowed("fmi2EnterInitializationMode", mask::INSTANTIATED) {
            return Status::Error;
        }
        self.core.state = State::InitializationMode;
        self.core.cache = None;
        self.trace(format_args!("fmi2EnterInitializationMode: state `initialization mode`"));
        Status::Ok
    }

    /// fmi2ExitInitializationMode: checks all parameters together and starts the
    /// integrator. A failure puts the instance in the error state.
    pub fn exit_initialization_mode(&mut self) -> Status {
        const F: &str = "fmi2ExitInitializationMode";
        if !self.allowed(F, mask::INITIALIZATION) {
            return Status::Error;
        }
        match self.core.build_run() {
            Ok(run) => {
                let t0 = self.core.setup.start_time;
                self.core.pending = [None, None];
                self.core.run = Some(run);
                self.core.time = t0;
                self.core.last_successful_time = t0;
                self.core.terminated = false;
                self.core.cache = None;
                self.core.state = State::StepComplete;
                self.trace(format_args!("{F}: integrator started at t = {t0:?}"));
                Status::Ok
            }
            Err(msg) => {
                self.core.state = State::Error;
                self.fail(Status::Error, format!("{F}: {msg}"))
            }
        }
    }

    /// fmi2Terminate.
    pub fn terminate(&mut self) -> Status {
        if !self.allowed("fmi2Terminate", mask::TERMINATE) {
            return Status::Error;
        }
        self.core.state = State::Terminated;
        let t = self.core.time;
        self.trace(format_args!("fmi2Terminate: at t = {t:?}"));
        Status::Ok
    }

    /// fmi2Reset: back to `instantiated` with the start values. Debug-logging settings stay.
    pub fn reset(&mut self) -> Status {
        if !self.allowed("fmi2Reset", mask::ANY_BUT_FATAL) {
            return Status::Error;
        }
        self.core = Core::new();
        self.trace(format_args!("fmi2Reset: back to `instantiated` with the start values"));
        Status::Ok
    }

    /// Marks the instance fatal after a caught panic: nothing but fmi2FreeInstance works
    /// afterwards.
    pub fn set_fatal(&mut self, msg: &str) {
        self.core.state = State::Fatal;
        self.log(Status::Fatal, msg);
    }

    // ----- get and set --------------------------------------------------------------------

    /// Finds `vr` and checks it has base type `base`.
    fn lookup(&mut self, func: &str, vr: u32, base: BaseType) -> Result<&'static Variable, Status> {
        let Some(var) = Var::from_vr(vr) else {
            return Err(self.fail(
                Status::Error,
                format!("{func}: unknown value reference {vr}: must be below {}", VARIABLES.len()),
            ));
        };
        let info = var.info();
        if info.ty.base() != base {
            return Err(self.fail(
                Status::Error,
                format!(
                    "{func}: value reference {vr} is `{}`, a {:?} variable, not a {base:?}",
                    info.name,
                    info.ty.base()
                ),
            ));
        }
        Ok(info)
    }

    /// The outputs at the communication time, computed now if they are not cached.
    fn outputs(&mut self, func: &str) -> Result<Outputs, Status> {
        if let Some(o) = self.core.cache {
            return Ok(o);
        }
        let computed = match &self.core.run {
            Some(run) => run.outputs_at(run.t()).map_err(|e| e.to_string()),
            // Initialization mode: the outputs of the start state.
            None => self.core.build_run().and_then(|run| {
                run.outputs_at(self.core.setup.start_time).map_err(|e| e.to_string())
            }),
        };
        match computed {
            Ok(o) => {
                self.core.cache = Some(o);
                Ok(o)
            }
            Err(msg) => {
                Err(self
                    .fail(Status::Error, format!("{func}: the outputs cannot be computed: {msg}")))
            }
        }
    }

    /// The value of any variable of base type `base`.
    fn get_value(&mut self, func: &str, vr: u32, base: BaseType) -> Result<Value, Status> {
        let info = self.lookup(func, vr, base)?;
        if let Some(v) = self.core.values.get(info.var) {
            return Ok(v);
        }
        let o = self.outputs(func)?;
        let x = match info.var {
            Var::V1 => o.v1,
            Var::Theta1 => o.theta1,
            Var::U2 => o.u2,
            Var::Dv1 => o.dv1,
            Var::Dtheta1 => o.dtheta1,
            Var::Du2 => o.du2,
            Var::N => o.reactions.n,
            Var::P => o.reactions.p,
            Var::Moment => o.reactions.m,
            Var::Drift => o.drift,
            Var::Energy => o.energy,
            Var::PhiApplied => o.phi.phi,
            Var::DphiApplied => o.phi.dphi,
            Var::DdphiApplied => o.phi.ddphi,
            _ => unreachable!("parameters and the input are served above"),
        };
        if !x.is_finite() {
            return Err(self.fail(
                Status::Error,
                format!("{func}: output `{}` is not finite at t = {}", info.name, o.t),
            ));
        }
        Ok(Value::Real(x))
    }

    fn get_all<T: fmt::Debug>(
        &mut self,
        func: &str,
        base: BaseType,
        vrs: &[u32],
        out: &mut [T],
        convert: impl Fn(Value) -> T,
    ) -> Status {
        if !self.allowed(func, mask::GET) {
            return Status::Error;
        }
        if vrs.len() != out.len() {
            return self.fail(
                Status::Error,
                format!("{func}: {} value references but {} values", vrs.len(), out.len()),
            );
        }
        for (vr, slot) in vrs.iter().zip(out.iter_mut()) {
            match self.get_value(func, *vr, base) {
                Ok(v) => *slot = convert(v),
                Err(status) => return status,
            }
        }
        self.trace(format_args!("{func}: {}", Listing(vrs, &*out)));
        Status::Ok
    }

    /// fmi2GetReal.
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Status {
        self.get_all("fmi2GetReal", BaseType::Real, vrs, out, |v| match v {
            Value::Real(x) => x,
            _ => unreachable!("checked by type"),
        })
    }

    /// fmi2GetInteger (integers and enumerations).
    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Status {
        self.get_all("fmi2GetInteger", BaseType::Integer, vrs, out, |v| match v {
            Value::Integer(k) => k,
            _ => unreachable!("checked by type"),
        })
    }

    /// fmi2GetBoolean.
    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [bool]) -> Status {
        self.get_all("fmi2GetBoolean", BaseType::Boolean, vrs, out, |v| match v {
            Value::Boolean(b) => b,
            _ => unreachable!("checked by type"),
        })
    }

    /// fmi2GetString: this model has no string variables.
    pub fn get_string(&mut self, vrs: &[u32]) -> Status {
        if !self.allowed("fmi2GetString", mask::GET) {
            return Status::Error;
        }
        match vrs.first() {
            None => {
                self.trace(format_args!("fmi2GetString: no variables"));
                Status::Ok
            }
            Some(vr) => {
                self.lookup("fmi2GetString", *vr, BaseType::String).err().unwrap_or(Status::Error)
            }
        }
    }

    /// Sets all values or none: each is checked first, against its variable's causality,
    /// the current state and its range.
    fn set_all(&mut self, func: &str, base: BaseType, vrs: &[u32], values: &[Value]) -> Status {
        if !self.allowed(func, mask::SET) {
            return Status::Error;
        }
        if vrs.len() != values.len() {
            return self.fail(
                Status::Error,
                format!("{func}: {} value references but {} values", vrs.len(), values.len()),
            );
        }
        let mut next = self.core.values;
        for (vr, value) in vrs.iter().zip(values) {
            let info = match self.lookup(func, *vr, base) {
                Ok(info) => info,
                Err(status) => return status,
            };
            let state = self.core.state;
            let refusal = match info.causality {
                Causality::Output => Some("it is an output".to_string()),
                Causality::Parameter if state == State::StepComplete => Some(format!(
                    "it is a fixed parameter, settable only before fmi2ExitInitializationMode \
                     (state is `{}`)",
                    state.name()
                )),
                _ => None,
            };
            if let Some(why) = refusal {
                return self
                    .fail(Status::Error, format!("{func}: cannot set `{}`: {why}", info.name));
            }
            if let Err(msg) = next.set(info, *value) {
                return self.fail(Status::Error, format!("{func}: {msg}"));
            }
        }
        self.core.values = next;
        self.core.cache = None;
        self.trace(format_args!("{func}: {}", Listing(vrs, values)));
        Status::Ok
    }

    /// fmi2SetReal.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        let values: Vec<Value> = values.iter().map(|x| Value::Real(*x)).collect();
        self.set_all("fmi2SetReal", BaseType::Real, vrs, &values)
    }

    /// fmi2SetInteger (integers and enumerations).
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        let values: Vec<Value> = values.iter().map(|k| Value::Integer(*k)).collect();
        self.set_all("fmi2SetInteger", BaseType::Integer, vrs, &values)
    }

    /// fmi2SetBoolean.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Status {
        let values: Vec<Value> = values.iter().map(|b| Value::Boolean(*b)).collect();
        self.set_all("fmi2SetBoolean", BaseType::Boolean, vrs, &values)
    }

    /// fmi2SetString: this model has no string variables.
    pub fn set_string(&mut self, vrs: &[u32]) -> Status {
        if !self.allowed("fmi2SetString", mask::SET) {
            return Status::Error;
        }
        match vrs.first() {
            None => {
                self.trace(format_args!("fmi2SetString: no variables"));
                Status::Ok
            }
            Some(vr) => {
                self.lookup("fmi2SetString", *vr, BaseType::String).err().unwrap_or(Status::Error)
            }
        }
    }

    // ----- co-simulation ------------------------------------------------------------------

    /// fmi2SetRealInputDerivatives: φ' (order 1) and φ'' (order 2) at the next
    /// communication point, for the next step only.
    pub fn set_real_input_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> Status {
        const F: &str = "fmi2SetRealInputDerivatives";
        if !self.allowed(F, mask::SET) {
            return Status::Error;
        }
        if vrs.len() != orders.len() || vrs.len() != values.len() {
            return self.fail(Status::Error, format!("{F}: arrays of different lengths"));
        }
        let mut pending = self.core.pending;
        for ((vr, order), value) in vrs.iter().zip(orders).zip(values) {
            if let Err(status) = self.lookup(F, *vr, BaseType::Real) {
                return status;
            }
            if *vr != Var::Phi.vr() {
                return self.fail(
                    Status::Error,
                    format!(
                        "{F}: value reference {vr} is not an input; only `phi` ({}) is",
                        Var::Phi.vr()
                    ),
                );
            }
            if !(1..=2).contains(order) {
                return self.fail(
                    Status::Error,
                    format!("{F}: order {order} of `phi` is out of range: must be 1 or 2"),
                );
            }
            if !value.is_finite() {
                return self.fail(Status::Error, format!("{F}: derivative of order {order} of `phi` = {value} is out of range: must be finite"));
            }
            pending[(*order - 1) as usize] = Some(*value);
        }
        self.core.pending = pending;
        self.core.cache = None;
        self.trace(format_args!("{F}: vr {vrs:?}, order {orders:?}, value {values:?}"));
        Status::Ok
    }

    /// fmi2GetRealOutputDerivatives: not provided (maxOutputDerivativeOrder = 0).
    pub fn get_real_output_derivatives(&mut self) -> Status {
        const F: &str = "fmi2GetRealOutputDerivatives";
        if !self.allowed(F, mask::OUTPUT_DERIVATIVES) {
            return Status::Error;
        }
        debug_assert_eq!(CAPABILITIES.max_output_derivative_order, 0);
        self.fail(Status::Error, format!("{F}: not provided (maxOutputDerivativeOrder = 0)"))
    }

    /// fmi2DoStep: integrates from `tc` to exactly `tc + h`.
    pub fn do_step(&mut self, tc: f64, h: f64) -> Status {
        const F: &str = "fmi2DoStep";
        if !self.allowed(F, mask::STEP_COMPLETE) {
            return Status::Error;
        }
        let time = self.core.time;
        if !(h.is_finite() && h > 0.0) {
            return self.fail(
                Status::Error,
                format!(
                    "{F}: communicationStepSize = {h} is out of range: must be positive and finite"
                ),
            );
        }
        // "Up to rounding": hosts compute tc as start + n·h or by sums; allow a few ulps.
        let fuzz = 64.0 * f64::EPSILON * time.abs().max(tc.abs()).max(h);
        if !(tc.is_finite() && (tc - time).abs() <= fuzz) {
            return self.fail(
                Status::Error,
                format!(
                    "{F}: currentCommunicationPoint = {tc} does not match the FMU's time {time}"
                ),
            );
        }
        if tc + h == tc {
            return self.fail(
                Status::Error,
                format!(
                    "{F}: communicationStepSize = {h:?} is below the resolution of the time \
                     tc = {tc:?} (tc + h = tc): the step would not advance"
                ),
            );
        }
        let target = tc + h;
        if let Some(stop) = self.core.setup.stop_time {
            if target > stop + 64.0 * f64::EPSILON * stop.abs().max(h) {
                return self.fail(
                    Status::Error,
                    format!("{F}: the step to t = {target} passes stopTime = {stop}"),
                );
            }
        }
        self.trace(format_args!("{F}: tc = {tc}, h = {h}"));
        let sample = self.core.sample(tc);
        self.core.pending = [None, None];
        let run = self.core.run.as_mut().expect("stepComplete has an integrator");
        run.set_sample(sample);
        let result = run.step_to(target).map_err(|e| (e.to_string(), run.t()));
        self.core.cache = None;
        match result {
            Ok(()) => {
                self.core.time = target;
                self.core.last_successful_time = target;
                Status::Ok
            }
            Err((e, t)) => {
                self.core.time = t;
                self.core.last_successful_time = t;
                self.core.terminated = true;
                self.core.state = State::StepFailed;
                self.fail(
                    Status::Discard,
                    format!(
                        "{F}: integration failed: {e}. The FMU stopped at t = {t} (fmi2LastSuccessfulTime), \
                         with fmi2Terminated = true"
                    ),
                )
            }
        }
    }

    /// fmi2CancelStep: steps are synchronous, so there is never one to cancel.
    pub fn cancel_step(&mut self) -> Status {
        self.allowed("fmi2CancelStep", mask::NONE);
        Status::Error
    }

    /// fmi2GetStatus, fmi2GetIntegerStatus, fmi2GetStringStatus: none of their kinds is
    /// provided (they concern asynchronous steps).
    pub fn get_unprovided_status(&mut self, func: &str, kind: i32) -> Status {
        if !self.allowed(func, mask::STATUS) {
            return Status::Error;
        }
        self.fail(
            Status::Error,
            format!(
                "{func}: status kind {kind} is not provided: fmi2DoStep never returns fmi2Pending"
            ),
        )
    }

    /// fmi2GetRealStatus: fmi2LastSuccessfulTime.
    pub fn get_real_status(&mut self, kind: i32) -> Result<f64, Status> {
        const F: &str = "fmi2GetRealStatus";
        if !self.allowed(F, mask::STATUS) {
            return Err(Status::Error);
        }
        if kind != STATUS_LAST_SUCCESSFUL_TIME {
            return Err(self.fail(Status::Error, format!("{F}: status kind {kind} is not provided: only fmi2LastSuccessfulTime ({STATUS_LAST_SUCCESSFUL_TIME})")));
        }
        let t = self.core.last_successful_time;
        self.trace(format_args!("{F}: fmi2LastSuccessfulTime = {t:?}"));
        Ok(t)
    }

    /// fmi2GetBooleanStatus: fmi2Terminated.
    pub fn get_boolean_status(&mut self, kind: i32) -> Result<bool, Status> {
        const F: &str = "fmi2GetBooleanStatus";
        if !self.allowed(F, mask::STATUS) {
            return Err(Status::Error);
        }
        if kind != STATUS_TERMINATED {
            return Err(self.fail(Status::Error, format!("{F}: status kind {kind} is not provided: only fmi2Terminated ({STATUS_TERMINATED})")));
        }
        let terminated = self.core.terminated;
        self.trace(format_args!("{F}: fmi2Terminated = {terminated}"));
        Ok(terminated)
    }

    /// fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative = false).
    pub fn get_directional_derivative(&mut self) -> Status {
        const F: &str = "fmi2GetDirectionalDerivative";
        if !self.allowed(F, mask::GET) {
            return Status::Error;
        }
        self.fail(
            Status::Error,
            format!("{F}: not provided (providesDirectionalDerivative = false)"),
        )
    }

    // ----- FMU state ----------------------------------------------------------------------

    /// fmi2GetFMUstate: a copy of everything but the name and logger.
    pub fn get_state(&mut self) -> Result<Box<Core>, Status> {
        if !self.allowed("fmi2GetFMUstate", mask::GET | mask::INSTANTIATED) {
            return Err(Status::Error);
        }
        self.trace_state("fmi2GetFMUstate: new snapshot");
        Ok(Box::new(self.core.clone()))
    }

    /// fmi2GetFMUstate into an existing snapshot, reusing its memory.
    pub fn get_state_into(&mut self, snapshot: &mut Core) -> Status {
        if !self.allowed("fmi2GetFMUstate", mask::GET | mask::INSTANTIATED) {
            return Status::Error;
        }
        snapshot.clone_from(&self.core);
        self.trace_state("fmi2GetFMUstate: into the existing snapshot");
        Status::Ok
    }

    /// fmi2SetFMUstate.
    pub fn set_state(&mut self, snapshot: &Core) -> Status {
        if !self.allowed("fmi2SetFMUstate", mask::GET | mask::INSTANTIATED) {
            return Status::Error;
        }
        self.core.clone_from(snapshot);
        self.trace_state("fmi2SetFMUstate: restored");
        Status::Ok
    }

    /// Checks that fmi2FreeFMUstate may be called (it may, in every state but fatal).
    /// `is_null`: the host passed a pointer to NULL, so there is nothing to free.
    pub fn check_free_state(&mut self, is_null: bool) -> Status {
        if !self.allowed("fmi2FreeFMUstate", mask::ANY_BUT_FATAL) {
            return Status::Error;
        }
        let what = if is_null { "NULL, nothing to free" } else { "a snapshot" };
        self.trace(format_args!("fmi2FreeFMUstate: {what}"));
        Status::Ok
    }

    /// fmi2SerializeFMUstate: the byte form of a snapshot ([`state`] documents the format).
    pub fn serialize(&mut self, snapshot: &Core) -> Result<Vec<u8>, Status> {
        if !self.allowed("fmi2SerializeFMUstate", mask::GET | mask::INSTANTIATED) {
            return Err(Status::Error);
        }
        let bytes = state::serialize(snapshot);
        self.trace(format_args!("fmi2SerializeFMUstate: {} bytes", bytes.len()));
        Ok(bytes)
    }

    /// fmi2SerializedFMUstateSize.
    pub fn serialized_size(&mut self, snapshot: &Core) -> Result<usize, Status> {
        if !self.allowed("fmi2SerializedFMUstateSize", mask::GET | mask::INSTANTIATED) {
            return Err(Status::Error);
        }
        let n = state::serialize(snapshot).len();
        self.trace(format_args!("fmi2SerializedFMUstateSize: {n} bytes"));
        Ok(n)
    }

    /// fmi2DeSerializeFMUstate: a snapshot from untrusted bytes. Every field is checked;
    /// malformed bytes give an error that says what is wrong.
    pub fn deserialize(&mut self, bytes: &[u8]) -> Result<Box<Core>, Status> {
        const F: &str = "fmi2DeSerializeFMUstate";
        if !self.allowed(F, mask::GET | mask::INSTANTIATED) {
            return Err(Status::Error);
        }
        let n = bytes.len();
        let core = state::deserialize(bytes)
            .map(Box::new)
            .map_err(|e| self.fail(Status::Error, format!("{F}: {e}")))?;
        self.trace(format_args!("{F}: {n} bytes, a snapshot in state `{}`", core.state.name()));
        Ok(core)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{simulate, Scene};
    use std::cell::RefCell;
    use std::rc::Rc;

    type Messages = Rc<RefCell<Vec<(Status, String)>>>;

    fn new_instance() -> (Instance, Messages) {
        let messages: Messages = Rc::default();
        let sink = messages.clone();
        let log: Logger = Box::new(move |s, _c, m| sink.borrow_mut().push((s, m.to_string())));
        let inst = Instance::instantiate("test", 1, super::super::variables::guid(), log, false);
        (inst.expect("instantiates"), messages)
    }

    fn law_instance(rtol: f64) -> (Instance, Messages) {
        let (mut inst, msgs) = new_instance();
        assert_eq!(inst.set_integer(&[Var::PhiSource.vr()], &[2]), Status::Ok);
        assert_eq!(inst.setup_experiment(Some(rtol), 0.0, Some(10.2)), Status::Ok);
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        assert_eq!(inst.exit_initialization_mode(), Status::Ok);
        (inst, msgs)
    }

    #[test]
    fn law_mode_matches_the_standalone_driver() {
        let (mut inst, msgs) = law_instance(1e-8);
        let scene = Scene { t_end: 1.7, dt_out: 0.0085, ..Scene::default() };
        let mut rows = Vec::new();
        let mut scene_tight = scene.clone();
        scene_tight.solver.rtol = 1e-8;
        simulate(&scene_tight, |o| rows.push(*o)).unwrap();
        let vrs = [Var::V1.vr(), Var::Theta1.vr(), Var::U2.vr()];
        let mut worst = 0.0f64;
        for (k, row) in rows.iter().enumerate().skip(1) {
            let tc = (k - 1) as f64 * 0.0085;
            let status = inst.do_step(tc, row.t - tc);
            assert_eq!(status, Status::Ok, "at {tc}: {:?}", msgs.borrow().last());
            let mut out = [0.0; 3];
            assert_eq!(inst.get_real(&vrs, &mut out), Status::Ok);
            worst = worst.max((out[0] - row.v1).abs()).max((out[1] - row.theta1).abs());
        }
        assert!(worst < 1e-6, "worst difference {worst}");
    }

    #[test]
    fn serialized_state_continues_bit_for_bit() {
        let (mut a, _) = law_instance(1e-6);
        let h = 0.0085;
        for k in 0..60 {
            assert_eq!(a.do_step(k as f64 * h, h), Status::Ok);
        }
        let snap = a.get_state().unwrap();
        let bytes = a.serialize(&snap).unwrap();
        let (mut b, _) = new_instance();
        let restored = b.deserialize(&bytes).unwrap();
        assert_eq!(b.set_state(&restored), Status::Ok);
        let vrs: Vec<u32> = (Var::V1.vr()..=Var::DdphiApplied.vr()).collect();
        for k in 60..200 {
            assert_eq!(a.do_step(k as f64 * h, h), Status::Ok);
            assert_eq!(b.do_step(k as f64 * h, h), Status::Ok);
            let (mut ya, mut yb) = (vec![0.0; vrs.len()], vec![0.0; vrs.len()]);
            a.get_real(&vrs, &mut ya);
            b.get_real(&vrs, &mut yb);
            assert_eq!(ya, yb, "step {k}");
        }
        // Any flipped byte is refused.
        for i in (0..bytes.len()).step_by(7) {
            let mut bad = bytes.clone();
            bad[i] ^= 0x40;
            assert!(b.deserialize(&bad).is_err(), "byte {i}");
        }
    }
}
