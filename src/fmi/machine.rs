//! The state machine of an FMU instance: its states, the sets of states in which each
//! function may be called, the statuses, and the error that carries a status to the edge.
#![forbid(unsafe_code)]

/// The states an instance can be in: co-simulation's (FMI 2.0, spec §4.2.4) and Model
/// Exchange's (§3.2.3), which share the first two and the last three. `stepInProgress` and
/// `stepCanceled` never occur: steps are synchronous. FMI 3.0 has the same states under other
/// names (Step Mode is `StepComplete`; a discarded step leaves it in `StepFailed`), and one
/// more: Intermediate Update Mode, inside fmi3DoStep while the host's callback runs. The
/// order is that of a serialized state's `state` field: new states go last.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    Instantiated,
    InitializationMode,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
    Fatal,
    EventMode,
    ContinuousTimeMode,
    IntermediateUpdate,
    /// FMI 3.0's Configuration Mode: after instantiation, where the structural parameters
    /// are set.
    ConfigurationMode,
}

impl State {
    const ALL: [State; 11] = [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::StepFailed,
        State::Terminated,
        State::Error,
        State::Fatal,
        State::EventMode,
        State::ContinuousTimeMode,
        State::IntermediateUpdate,
        State::ConfigurationMode,
    ];

    /// After initialization, before the end: stepping (co-simulation) or in event or
    /// continuous-time mode (Model Exchange).
    pub fn is_running(self) -> bool {
        matches!(self, State::StepComplete | State::EventMode | State::ContinuousTimeMode)
    }

    pub(crate) fn bit(self) -> u32 {
        1 << self as u32
    }

    pub fn name(self) -> &'static str {
        match self {
            State::Instantiated => "instantiated",
            State::InitializationMode => "initialization mode",
            State::StepComplete => "step complete",
            State::StepFailed => "step failed",
            State::Terminated => "terminated",
            State::Error => "error",
            State::Fatal => "fatal",
            State::EventMode => "event mode",
            State::ContinuousTimeMode => "continuous-time mode",
            State::IntermediateUpdate => "intermediate update mode",
            State::ConfigurationMode => "configuration mode",
        }
    }

    pub(crate) fn to_index(self) -> u64 {
        self as u64
    }

    pub(crate) fn from_index(k: u64) -> Option<State> {
        State::ALL.get(k as usize).copied()
    }
}

/// Sets of states in which a function may be called.
pub(crate) mod mask {
    use super::State::{self, *};
    pub(crate) const fn bits(states: &[State]) -> u32 {
        let mut m = 0;
        let mut k = 0;
        while k < states.len() {
            m |= 1 << states[k] as u32;
            k += 1;
        }
        m
    }
    pub const ANY_BUT_FATAL: u32 = bits(&[
        Instantiated,
        InitializationMode,
        StepComplete,
        StepFailed,
        Terminated,
        Error,
        EventMode,
        ContinuousTimeMode,
        IntermediateUpdate,
        ConfigurationMode,
    ]);
    pub const INSTANTIATED: u32 = bits(&[Instantiated]);
    /// FMI 3.0's Configuration Mode.
    pub const CONFIGURATION: u32 = bits(&[ConfigurationMode]);
    pub const INITIALIZATION: u32 = bits(&[InitializationMode]);
    // Co-simulation's own functions.
    pub const STEP_COMPLETE: u32 = bits(&[StepComplete]);
    /// Inside FMI 3.0's DoStep, while the host's callback runs.
    pub const INTERMEDIATE_UPDATE: u32 = bits(&[IntermediateUpdate]);
    pub const STATUS: u32 = bits(&[StepComplete, StepFailed, Terminated]);
    pub const OUTPUT_DERIVATIVES: u32 = bits(&[StepComplete, StepFailed, Terminated, Error]);
    /// No state: the function needs a step in progress, which never exists.
    pub const NONE: u32 = 0;
    // Model Exchange's own functions (FMI 2.0 §3.2.3; Reference-FMUs' masks).
    pub const EVENT: u32 = bits(&[EventMode]);
    pub const CONTINUOUS: u32 = bits(&[ContinuousTimeMode]);
    pub const EVENT_OR_CONTINUOUS: u32 = bits(&[EventMode, ContinuousTimeMode]);
    pub const STATES_AND_INDICATORS: u32 =
        bits(&[InitializationMode, EventMode, ContinuousTimeMode, Terminated, Error]);
    pub const DERIVATIVES: u32 = bits(&[EventMode, ContinuousTimeMode, Terminated, Error]);
    /// FMI 3.0's GetNumberOfContinuousStates and GetNumberOfEventIndicators (Reference-FMUs'
    /// masks).
    pub const COUNTS: u32 =
        bits(&[Instantiated, InitializationMode, EventMode, ContinuousTimeMode, Terminated, Error]);
    /// FMI 3.0's GetContinuousStateDerivatives and GetNominalsOfContinuousStates: like the
    /// states and indicators, from initialization mode on (FMI 3.0 §3.2's states;
    /// Reference-FMUs' masks). FMI 2.0 allows the derivatives from event mode on, and the
    /// nominals from instantiation.
    pub const EXCHANGE_ARRAYS3: u32 = STATES_AND_INDICATORS;
    pub const NOMINALS: u32 =
        bits(&[Instantiated, EventMode, ContinuousTimeMode, Terminated, Error]);
}

/// An FMI interface's kind: its states, and the sets of states of the calls that every
/// interface has but each allows in its own states. Data, not code: the state machine is
/// written once ([`Instance`](super::Instance)) and reads these.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interface {
    CoSimulation,
    ModelExchange,
}

/// The sets of states of one interface (see [`Interface::masks`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Masks {
    /// The state ExitInitializationMode leads to.
    pub initialized: State,
    /// The get functions (and GetDirectionalDerivative).
    pub get: u32,
    /// The set functions (in intermediate update mode, of the intermediate inputs only).
    pub set: u32,
    /// After initialization: fixed parameters can no longer be set, and the model runs.
    pub running: u32,
    pub terminate: u32,
    /// Get, set and serialize FMU states; the states an FMU state can hold.
    pub fmu_state: u32,
}

impl Interface {
    const fn make(
        running: &[State],
        initialized: State,
        get: &[State],
        set: &[State],
        terminate: &[State],
    ) -> Masks {
        use State::*;
        let get = mask::bits(get);
        let running = mask::bits(running);
        Masks {
            initialized,
            get,
            set: mask::bits(set),
            running,
            terminate: mask::bits(terminate),
            // Not inside fmi3DoStep's callback: the step is half done. FMI 3.0's configuration
            // mode, in the super state "FMU State Setable" as every state is, may hold one.
            fmu_state: (get | mask::INSTANTIATED | mask::CONFIGURATION)
                & !mask::bits(&[IntermediateUpdate]),
        }
    }

    /// FMI 2.0 §4.2.4 (co-simulation) and §3.2.3 (Model Exchange); FMI 3.0 §4.2 adds
    /// Intermediate Update Mode to co-simulation (an FMI 2.0 instance never enters it).
    pub(crate) fn masks(self) -> &'static Masks {
        use State::*;
        const CS: Masks = Interface::make(
            &[StepComplete, StepFailed, Terminated, IntermediateUpdate],
            StepComplete,
            &[InitializationMode, StepComplete, StepFailed, Terminated, Error, IntermediateUpdate],
            &[
                Instantiated,
                InitializationMode,
                StepComplete,
                IntermediateUpdate,
                ConfigurationMode,
            ],
            &[StepComplete, StepFailed],
        );
        const ME: Masks = Interface::make(
            &[EventMode, ContinuousTimeMode, Terminated],
            EventMode,
            &[InitializationMode, EventMode, ContinuousTimeMode, Terminated, Error],
            &[Instantiated, InitializationMode, EventMode, ContinuousTimeMode, ConfigurationMode],
            &[EventMode, ContinuousTimeMode],
        );
        match self {
            Interface::CoSimulation => &CS,
            Interface::ModelExchange => &ME,
        }
    }

    /// The interface's name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Interface::CoSimulation => "co-simulation",
            Interface::ModelExchange => "Model Exchange",
        }
    }

    pub(crate) fn to_index(self) -> u64 {
        self as u64
    }

    pub(crate) fn from_index(k: u64) -> Option<Interface> {
        [Interface::CoSimulation, Interface::ModelExchange].get(k as usize).copied()
    }
}

/// The status of a call: fmi2Status and fmi3Status have these values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[repr(i32)]
pub enum Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
}

impl Status {
    /// The log category of a message with this status.
    pub(crate) fn category(self) -> &'static str {
        match self {
            Status::Ok => "logCalls",
            Status::Warning => "logStatusWarning",
            Status::Discard => "logStatusDiscard",
            Status::Error => "logStatusError",
            Status::Fatal => "logStatusFatal",
        }
    }
}

/// Why a call failed: the status it returns and the message logged. Methods pass it on with
/// `?`; [`Instance::edge`](super::Instance::edge) logs it and turns it into the status, once,
/// for every function.
#[derive(Clone, Debug, PartialEq)]
pub struct FmiError {
    pub status: Status,
    pub message: String,
}

impl FmiError {
    pub(crate) fn error(message: impl Into<String>) -> FmiError {
        FmiError { status: Status::Error, message: message.into() }
    }

    pub(crate) fn discard(message: impl Into<String>) -> FmiError {
        FmiError { status: Status::Discard, message: message.into() }
    }
}

/// The result of a call: a value (the status for calls that return nothing else) or why not.
pub type FmiResult<T = Status> = Result<T, FmiError>;
