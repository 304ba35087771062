//! One FMU instance, generic over its model: the state machine, logging, argument checks and
//! the lifecycle here; get and set by value reference in `values`, FMU state snapshots in
//! `states`. Co-simulation's calls are in [`cosim`](super::cosim), Model Exchange's in
//! [`exchange`](super::exchange).
//!
//! An interface layer (`fmi2`, `fmi3`) turns C pointers into slices and strings and calls these
//! methods; everything else happens here or in the model. Each method logs its own errors
//! through the instance's [`Logger`] and returns the status. No `unsafe`, no I/O.
#![forbid(unsafe_code)]

use super::api::Api;
use super::description::{BaseType, Causality, Dim, Only, VarInfo, Version, LOG_CATEGORIES};
use super::machine::{mask, FmiError, FmiResult, Interface, Masks, State, Status};
use super::model::{Model, Notes, Setup, Value};
use super::snapshot::{self, Snapshot};
use std::fmt;

mod states;
mod values;

/// Logs a call when `logCalls` is on: the message, and even its arguments, only then.
macro_rules! trace {
    ($inst:expr, $($arg:tt)*) => {
        if $inst.logging.0[$crate::fmi::instance::LOG_CALLS] {
            $inst.trace(format_args!($($arg)*))
        }
    };
}
pub(crate) use trace;

/// The index of `logCalls` in [`LOG_CATEGORIES`].
pub(crate) const LOG_CALLS: usize = 4;

/// Where log messages go: (status, category, message). The interface layer forwards them to
/// the host's logger; tests collect them.
pub type Logger = Box<dyn FnMut(Status, &str, &str)>;

/// The host's intermediate-update callback (FMI 3.0 co-simulation), called at a time inside
/// a step. Shared, so that the interface layer calls a clone of it with no borrow of the
/// instance alive: the host calls back into the instance from it.
pub type IntermediateUpdate = std::rc::Rc<dyn Fn(f64, bool)>;

/// Log switches, per category of [`LOG_CATEGORIES`].
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LogFlags(pub(crate) [bool; LOG_CATEGORIES.len()]);

/// A function's name in messages: the interface (its prefix, `fmi2`, and its names) and the
/// core's name of the function (FMI 2.0's, `DoStep`), joined only when a message is written.
#[derive(Clone, Copy)]
pub struct Func(pub &'static Api, pub &'static str);

impl Func {
    /// The model description its interface serves.
    pub fn version(&self) -> Version {
        self.0.version
    }
}

impl fmt::Display for Func {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}{}", self.0.prefix, (self.0.rename)(self.1))
    }
}

/// One FMU instance.
pub struct Instance<M> {
    name: String,
    /// The interface that made it: its function names and rules.
    api: &'static Api,
    log: Logger,
    pub(crate) logging: LogFlags,
    pub(crate) core: Snapshot<M>,
    /// The host's intermediate-update callback, when it asked for intermediate variables.
    intermediate_update: Option<IntermediateUpdate>,
    /// Whether the host reads outputs in intermediate update mode (it named one in
    /// `requiredIntermediateVariables`).
    pub(crate) intermediate_outputs: bool,
    /// In intermediate update mode: whether the host set an input there.
    pub(crate) intermediate_set: bool,
}

impl<M: fmt::Debug> fmt::Debug for Instance<M> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Instance").field("name", &self.name).field("core", &self.core).finish()
    }
}

/// "`name` (vr) = value, …" for the traces of get and set calls, an array's elements in
/// brackets (`sizes`: each reference's count of values, one each without it); formatted only
/// when a trace is written.
struct Listing<'a, M, T>(&'a [u32], &'a [T], Option<&'a [usize]>, std::marker::PhantomData<M>);

impl<M: Model, T: fmt::Debug> fmt::Display for Listing<'_, M, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut at = 0;
        for (k, vr) in self.0.iter().enumerate() {
            let info = M::variable(*vr);
            let name = info.map_or("?", |v| v.name);
            let sep = if k == 0 { "" } else { ", " };
            let n = self.2.map_or(1, |sizes| sizes[k]);
            let values = &self.1[at.min(self.1.len())..(at + n).min(self.1.len())];
            at += n;
            match values {
                [one] if info.is_none_or(|v| v.dims.is_empty()) => {
                    write!(f, "{sep}`{name}` ({vr}) = {one:?}")?
                }
                _ => write!(f, "{sep}`{name}` ({vr}) = {values:?}")?,
            }
        }
        if self.0.is_empty() {
            write!(f, "no variables")?;
        }
        Ok(())
    }
}

fn listing<'a, M, T>(vrs: &'a [u32], values: &'a [T]) -> Listing<'a, M, T> {
    Listing(vrs, values, None, std::marker::PhantomData)
}

impl<M: Model> Instance<M> {
    /// A new instance called `name` of `interface`, made through `api`, after checking the
    /// name and the GUID. `None`, after logging why, otherwise.
    pub fn instantiate(
        api: &'static Api,
        interface: Interface,
        name: &str,
        guid: &str,
        mut log: Logger,
        logging_on: bool,
    ) -> Option<Instance<M>> {
        let func = Func(api, "Instantiate");
        let checked = if name.is_empty() {
            Err("instanceName is empty".to_string())
        } else if guid != M::guid() {
            Err(format!(
                "{} {guid} does not match this binary's {}: wrong or stale FMU",
                api.token,
                M::guid()
            ))
        } else {
            Ok(())
        };
        if let Err(msg) = checked {
            log(Status::Error, "logStatusError", &format!("{func}: {msg}"));
            return None;
        }
        let mut inst = Instance {
            name: name.to_string(),
            api,
            log,
            logging: LogFlags([logging_on; LOG_CATEGORIES.len()]),
            core: Snapshot::new(interface, api.version),
            intermediate_update: None,
            intermediate_outputs: false,
            intermediate_set: false,
        };
        inst.trace(format_args!("{func}: instance `{name}`"));
        Some(inst)
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// Keeps the host's intermediate-update callback (FMI 3.0 co-simulation), through which
    /// the host reads `outputs` or not.
    pub fn set_intermediate_update(&mut self, callback: IntermediateUpdate, outputs: bool) {
        self.intermediate_update = Some(callback);
        self.intermediate_outputs = outputs;
    }

    /// The host's intermediate-update callback, if it gave one.
    pub fn intermediate_update(&self) -> Option<IntermediateUpdate> {
        self.intermediate_update.clone()
    }

    /// The interface that made it.
    pub fn api(&self) -> &'static Api {
        self.api
    }

    /// Its interface's name of `state`.
    pub(crate) fn state_name(&self, state: State) -> &'static str {
        (self.api.state_name)(state)
    }

    pub fn state(&self) -> State {
        self.core.state
    }

    pub fn interface(&self) -> Interface {
        self.core.interface
    }

    /// The sets of states of this instance's interface.
    #[inline]
    pub(crate) fn masks(&self) -> &'static Masks {
        self.core.interface.masks()
    }

    /// Whether `func`, a function of `interface` only, may be called on this instance in the
    /// current state (`mask`): a function of the other interface is refused naming both.
    pub(crate) fn allowed_in(&self, func: Func, interface: Interface, mask: u32) -> FmiResult<()> {
        let mine = self.core.interface;
        if mine != interface {
            return Err(FmiError::error(format!(
                "{func}: a {} function, but this instance was instantiated for {}",
                interface.name(),
                mine.name()
            )));
        }
        self.allowed(func, mask)
    }

    /// The name of function `name` of this instance's interface, for messages.
    pub(crate) fn func(&self, name: &'static str) -> Func {
        Func(self.api, name)
    }

    // ----- logging and the edge -----------------------------------------------------------

    /// Logs `msg`. Warnings, discards, errors and fatal errors always go out: a function that
    /// returns one of them has called the logger (FMI 2.0.4, §2.1.3, the meaning of
    /// fmi2Warning and of the statuses above it), and debug logging (`loggingOn`) concerns
    /// the other messages, which go out only when their category is on.
    pub fn log(&mut self, status: Status, msg: &str) {
        let category = status.category();
        let always = status >= Status::Warning;
        let k = LOG_CATEGORIES.iter().position(|(c, _)| *c == category).unwrap_or(0);
        if always || self.logging.0[k] {
            (self.log)(status, category, msg);
        }
    }

    /// Logs each note as a warning from `func`; the status: Warning if there was one. No
    /// note, the common case on every call, costs a test.
    #[inline]
    pub(crate) fn notes(&mut self, func: Func, notes: Notes) -> Status {
        if notes.is_empty() {
            return Status::Ok;
        }
        self.log_notes(func, notes)
    }

    #[cold]
    #[inline(never)]
    fn log_notes(&mut self, func: Func, notes: Notes) -> Status {
        for note in notes {
            self.log(Status::Warning, &format!("{func}: {note}"));
        }
        Status::Warning
    }

    /// The one place where a result becomes an FMI status: a failure is logged with its
    /// message and returns its status.
    #[inline]
    pub fn edge<T>(&mut self, result: FmiResult<T>) -> Result<T, Status> {
        result.map_err(|e| self.failed(e))
    }

    /// The failure of [`edge`](Self::edge), out of the calls' fast path.
    #[cold]
    #[inline(never)]
    fn failed(&mut self, e: FmiError) -> Status {
        self.log(e.status, &e.message);
        e.status
    }

    /// [`edge`](Self::edge) for calls that return a status only.
    #[inline]
    pub(crate) fn status(&mut self, result: FmiResult) -> Status {
        self.edge(result).unwrap_or_else(|status| status)
    }

    /// Logs a call (see [`trace!`]).
    pub(crate) fn trace(&mut self, msg: fmt::Arguments<'_>) {
        if self.logging.0[LOG_CALLS] {
            (self.log)(Status::Ok, "logCalls", &msg.to_string());
        }
    }

    /// Traces an FMU-state call with the instance's state and time afterwards.
    fn trace_state(&mut self, what: fmt::Arguments<'_>) {
        let (state, t) = (self.core.state, self.core.time);
        trace!(self, "{what}: state `{}`, t = {t:?}", self.state_name(state));
    }

    /// FreeInstance: traces the call; the caller then drops the instance. Allowed in every
    /// state, fatal included: freeing touches no model data, and a host that frees a fatal
    /// instance (which FMI 2.0 does not ask of it) should not leak it.
    pub fn trace_free(&mut self) {
        if self.logging.0[LOG_CALLS] {
            let msg = format!("{}: instance `{}`", self.func("FreeInstance"), self.name);
            (self.log)(Status::Ok, "logCalls", &msg);
        }
    }

    /// Refuses every call on a fatal instance before the call touches anything (its
    /// arguments included): logs the illegal call and returns false.
    #[inline]
    pub fn check_not_fatal(&mut self, func: &str) -> bool {
        let allowed = self.allowed(func, mask::ANY_BUT_FATAL);
        self.edge(allowed).is_ok()
    }

    /// Whether `func` may be called in the current state.
    #[inline]
    pub(crate) fn allowed(&self, func: impl fmt::Display, mask: u32) -> FmiResult<()> {
        let state = self.core.state;
        if mask & state.bit() != 0 {
            return Ok(());
        }
        Err(illegal(func, self.state_name(state)))
    }

    /// SetDebugLogging. `categories`: `None` where the host passed NULL or invalid UTF-8.
    /// An empty list switches every category.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[Option<&str>]) -> Status {
        let r = self.try_set_debug_logging(on, categories);
        self.status(r)
    }

    fn try_set_debug_logging(&mut self, on: bool, categories: &[Option<&str>]) -> FmiResult {
        let f = self.func("SetDebugLogging");
        self.allowed(f, mask::ANY_BUT_FATAL)?;
        let mut flags = self.logging;
        if categories.is_empty() {
            flags.0 = [on; LOG_CATEGORIES.len()];
        }
        for c in categories {
            let Some(k) = c.and_then(|c| LOG_CATEGORIES.iter().position(|(n, _)| *n == c)) else {
                let names: Vec<&str> = LOG_CATEGORIES.iter().map(|(n, _)| *n).collect();
                return Err(FmiError::error(format!(
                    "{f}: unknown log category {c:?}: must be one of {}",
                    names.join(", ")
                )));
            };
            if LOG_CATEGORIES[k].0 == "logAll" {
                flags.0 = [on; LOG_CATEGORIES.len()];
            } else {
                flags.0[k] = on;
            }
        }
        self.logging = flags;
        trace!(self, "{f}: loggingOn = {on}, categories {categories:?}");
        Ok(Status::Ok)
    }

    // ----- lifecycle ----------------------------------------------------------------------

    /// SetupExperiment.
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Status {
        let r = self.try_setup_experiment(tolerance, start_time, stop_time);
        self.status(r)
    }

    fn try_setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> FmiResult {
        let f = self.func("SetupExperiment");
        self.allowed(f, mask::INSTANTIATED)?;
        self.setup(f, tolerance, start_time, stop_time)
    }

    /// The experiment's setup, checked: FMI 2.0's SetupExperiment, FMI 3.0's
    /// EnterInitializationMode.
    fn setup(
        &mut self,
        f: Func,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> FmiResult {
        if let Some(tol) = tolerance {
            M::check_tolerance(tol).map_err(|allowed| {
                FmiError::error(format!(
                    "{f}: tolerance = {tol:?} is out of range: must be {allowed}"
                ))
            })?;
        }
        if !start_time.is_finite() {
            return Err(FmiError::error(format!(
                "{f}: startTime = {start_time} is out of range: must be finite"
            )));
        }
        if let Some(stop) = stop_time {
            if !(stop.is_finite() && stop >= start_time) {
                return Err(FmiError::error(format!(
                    "{f}: stopTime = {stop} is out of range: must be finite and \
                     >= startTime = {start_time}"
                )));
            }
        }
        let setup = Setup { tolerance, start_time, stop_time };
        self.core.setup = setup;
        self.core.time = start_time;
        self.core.last_successful_time = start_time;
        trace!(self, "{f}: {setup:?}");
        Ok(Status::Ok)
    }

    /// EnterInitializationMode.
    pub fn enter_initialization_mode(&mut self) -> Status {
        let f = self.func("EnterInitializationMode");
        let r = self.allowed(f, mask::INSTANTIATED).map(|()| {
            self.core.state = State::InitializationMode;
            trace!(self, "{f}: state `initialization mode`");
            Status::Ok
        });
        self.status(r)
    }

    /// FMI 3.0's EnterConfigurationMode: from `instantiated`, to set the structural
    /// parameters. The model has no tunable structural parameter, so there is no
    /// reconfiguration mode (from step or event mode).
    pub fn enter_configuration_mode(&mut self) -> Status {
        self.configuration(
            "EnterConfigurationMode",
            mask::INSTANTIATED,
            State::ConfigurationMode,
            "the structural parameters are fixed: there is no reconfiguration mode, and \
             configuration mode comes right after instantiation",
        )
    }

    /// FMI 3.0's ExitConfigurationMode: back to `instantiated`, where the arrays have the
    /// sizes just set.
    pub fn exit_configuration_mode(&mut self) -> Status {
        self.configuration(
            "ExitConfigurationMode",
            mask::CONFIGURATION,
            State::Instantiated,
            "it leaves configuration mode",
        )
    }

    fn configuration(&mut self, name: &'static str, allowed: u32, to: State, why: &str) -> Status {
        let f = self.func(name);
        let r = match self.allowed(f, allowed) {
            Ok(()) => {
                self.core.state = to;
                trace!(self, "{f}: state `{}`", self.state_name(to));
                Ok(Status::Ok)
            }
            Err(e) => Err(FmiError::error(format!("{} ({why})", e.message))),
        };
        self.status(r)
    }

    /// EnterInitializationMode of FMI 3.0, which takes the experiment's setup (FMI 2.0's
    /// SetupExperiment).
    pub fn enter_initialization_mode_with(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Status {
        let f = self.func("EnterInitializationMode");
        let r = self.allowed(f, mask::INSTANTIATED).and_then(|()| {
            self.setup(f, tolerance, start_time, stop_time)?;
            self.core.state = State::InitializationMode;
            trace!(self, "{f}: state `initialization mode`");
            Ok(Status::Ok)
        });
        self.status(r)
    }

    /// ExitInitializationMode: the model checks all its values together and starts. A
    /// failure puts the instance in the error state.
    pub fn exit_initialization_mode(&mut self) -> Status {
        let r = self.try_exit_initialization_mode();
        self.status(r)
    }

    fn try_exit_initialization_mode(&mut self) -> FmiResult {
        let f = self.func("ExitInitializationMode");
        self.allowed(f, mask::INITIALIZATION)?;
        let setup = self.core.setup;
        if let Err(msg) = self.core.model.start(&setup, self.core.interface) {
            self.core.state = State::Error;
            return Err(FmiError::error(format!("{f}: {msg}")));
        }
        let t0 = setup.start_time;
        self.core.time = t0;
        self.core.last_successful_time = t0;
        self.core.terminated = false;
        let state = self.masks().initialized;
        self.core.state = state;
        trace!(self, "{f}: started at t = {t0:?}, state `{}`", (f.0.state_name)(state));
        Ok(Status::Ok)
    }

    /// Terminate.
    pub fn terminate(&mut self) -> Status {
        let f = self.func("Terminate");
        let r = self.allowed(f, self.masks().terminate).map(|()| {
            self.core.state = State::Terminated;
            let t = self.core.time;
            trace!(self, "{f}: at t = {t:?}");
            Status::Ok
        });
        self.status(r)
    }

    /// Reset: back to `instantiated` with the start values. Debug-logging settings stay.
    pub fn reset(&mut self) -> Status {
        let f = self.func("Reset");
        // Not inside fmi3DoStep's callback, whose step is half done (FMI 3.0 allows only get
        // and set there).
        let r = self.allowed(f, mask::ANY_BUT_FATAL & !mask::INTERMEDIATE_UPDATE).map(|()| {
            self.core = Snapshot::new(self.core.interface, self.core.version);
            trace!(self, "{f}: back to `instantiated` with the start values");
            Status::Ok
        });
        self.status(r)
    }

    /// A function the model does not provide (FMI 3.0 §2.5: it returns Error and says so):
    /// Error, with `why`.
    pub fn unsupported(&mut self, name: &'static str, why: &str) -> Status {
        let f = self.func(name);
        self.status(Err(FmiError::error(format!("{f}: not provided: {why}"))))
    }

    /// Marks the instance fatal after a caught panic: nothing but FreeInstance works
    /// afterwards.
    pub fn set_fatal(&mut self, msg: &str) {
        self.core.state = State::Fatal;
        self.log(Status::Fatal, msg);
    }
}

/// A snapshot the writer refuses: one that its reader would refuse too.
#[cold]
#[inline(never)]
fn unwritable(func: Func, e: String) -> FmiError {
    FmiError::error(format!("{func}: the FMU state cannot be serialized: {e}"))
}

#[cold]
#[inline(never)]
fn illegal(func: impl fmt::Display, state: &str) -> FmiError {
    FmiError::error(format!("{func}: illegal call sequence: not allowed in state `{state}`"))
}

#[cold]
#[inline(never)]
fn bad_reference(
    func: Func,
    vr: u32,
    base: BaseType,
    found: Option<&VarInfo>,
    count: usize,
) -> FmiError {
    FmiError::error(match found {
        None => format!("{func}: unknown value reference {vr}: must be below {count}"),
        Some(info) => {
            let version = func.version();
            let ty = info.base_in(version);
            let a = |name: &str| if name.starts_with('I') { "an" } else { "a" };
            let (is, asked) = (ty.name(version), base.name(version));
            format!(
                "{func}: value reference {vr} is `{}`, {} {is} variable, not {} {asked}",
                info.name,
                a(is),
                a(asked)
            )
        }
    })
}
