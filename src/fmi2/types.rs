//! The C types of FMI 2.0, written by hand from `fmi2TypesPlatform.h` and
//! `fmi2FunctionTypes.h` (FMI 2.0.4): a dozen type aliases and two structs do not justify
//! bindgen and libclang (docs/decisions.md, "Dependencies").
#![allow(non_snake_case, non_camel_case_types, non_upper_case_globals)]
#![allow(unsafe_code)]

use std::ffi::{c_char, c_int, c_uint, c_void};

pub type fmi2Component = *mut c_void;
pub type fmi2ComponentEnvironment = *mut c_void;
pub type fmi2FMUstate = *mut c_void;
pub type fmi2ValueReference = c_uint;
pub type fmi2Real = f64;
pub type fmi2Integer = c_int;
pub type fmi2Boolean = c_int;
pub type fmi2Char = c_char;
pub type fmi2String = *const fmi2Char;
pub type fmi2Byte = c_char;
pub type fmi2Status = c_int;
pub type fmi2Type = c_int;
pub type fmi2StatusKind = c_int;

pub const fmi2True: fmi2Boolean = 1;
pub const fmi2False: fmi2Boolean = 0;

/// fmi2CallbackLogger: printf-like; we always pass `"%s"` and the message.
pub type fmi2CallbackLogger = unsafe extern "C" fn(
    fmi2ComponentEnvironment,
    fmi2String,
    fmi2Status,
    fmi2String,
    fmi2String,
    ...
);

/// fmi2CallbackFunctions. The memory functions are never called
/// (canNotUseMemoryManagementFunctions = true).
#[repr(C)]
pub struct fmi2CallbackFunctions {
    pub logger: Option<fmi2CallbackLogger>,
    pub allocateMemory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    pub freeMemory: Option<unsafe extern "C" fn(*mut c_void)>,
    pub stepFinished: Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>,
    pub componentEnvironment: fmi2ComponentEnvironment,
}

/// fmi2Status, the core's [`Status`](crate::fmi::Status) as C has it.
pub const fmi2OK: fmi2Status = crate::fmi::Status::Ok as fmi2Status;
pub const fmi2Warning: fmi2Status = crate::fmi::Status::Warning as fmi2Status;
pub const fmi2Discard: fmi2Status = crate::fmi::Status::Discard as fmi2Status;
pub const fmi2Error: fmi2Status = crate::fmi::Status::Error as fmi2Status;
pub const fmi2Fatal: fmi2Status = crate::fmi::Status::Fatal as fmi2Status;

/// fmi2Type.
pub const fmi2ModelExchange: fmi2Type = 0;
pub const fmi2CoSimulation: fmi2Type = 1;
pub const FMI2_MODEL_EXCHANGE: fmi2Type = fmi2ModelExchange;
pub const FMI2_COSIMULATION: fmi2Type = fmi2CoSimulation;

/// fmi2EventInfo (Model Exchange's fmi2NewDiscreteStates).
#[repr(C)]
pub struct fmi2EventInfo {
    pub newDiscreteStatesNeeded: fmi2Boolean,
    pub terminateSimulation: fmi2Boolean,
    pub nominalsOfContinuousStatesChanged: fmi2Boolean,
    pub valuesOfContinuousStatesChanged: fmi2Boolean,
    pub nextEventTimeDefined: fmi2Boolean,
    pub nextEventTime: fmi2Real,
}

/// fmi2StatusKind.
pub const fmi2DoStepStatus: fmi2StatusKind = crate::fmi::STATUS_DO_STEP;
pub const fmi2PendingStatus: fmi2StatusKind = crate::fmi::STATUS_PENDING;
pub const fmi2LastSuccessfulTime: fmi2StatusKind = crate::fmi::STATUS_LAST_SUCCESSFUL_TIME;
pub const fmi2Terminated: fmi2StatusKind = crate::fmi::STATUS_TERMINATED;
