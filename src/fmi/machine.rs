//! The state machine of an FMU instance: its states, the sets of states in which each
//! function may be called, the statuses, and the error that carries a status to the edge.
#![forbid(unsafe_code)]

/// The states an instance can be in (FMI 2.0 co-simulation, spec §4.2.4). `stepInProgress`
/// and `stepCanceled` never occur: steps are synchronous.
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
    const fn bits(states: &[State]) -> u32 {
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
