//! The C types of FMI 3.0, written by hand from `fmi3PlatformTypes.h` and
//! `fmi3FunctionTypes.h` (FMI 3.0): as for FMI 2.0, a few aliases and no structs do not
//! justify bindgen.
#![allow(non_snake_case, non_camel_case_types, non_upper_case_globals)]
#![allow(unsafe_code)]

use std::ffi::{c_char, c_int, c_void};

pub type fmi3Instance = *mut c_void;
pub type fmi3InstanceEnvironment = *mut c_void;
pub type fmi3FMUState = *mut c_void;
pub type fmi3ValueReference = u32;
pub type fmi3Float32 = f32;
pub type fmi3Float64 = f64;
pub type fmi3Int8 = i8;
pub type fmi3UInt8 = u8;
pub type fmi3Int16 = i16;
pub type fmi3UInt16 = u16;
pub type fmi3Int32 = i32;
pub type fmi3UInt32 = u32;
pub type fmi3Int64 = i64;
pub type fmi3UInt64 = u64;
/// C's `bool`, taken as its byte: a byte other than 0 or 1 from a host is true rather than
/// undefined behaviour (a Rust `bool` must be 0 or 1).
pub type fmi3Boolean = u8;
pub type fmi3Char = c_char;
pub type fmi3String = *const fmi3Char;
pub type fmi3Byte = u8;
pub type fmi3Binary = *const fmi3Byte;
pub type fmi3Clock = fmi3Boolean;
/// fmi3Status, fmi3DependencyKind, fmi3IntervalQualifier: C enums, an `int`.
pub type fmi3Status = c_int;
pub type fmi3DependencyKind = c_int;
pub type fmi3IntervalQualifier = c_int;

pub const fmi3True: fmi3Boolean = 1;
pub const fmi3False: fmi3Boolean = 0;

/// fmi3Status, the core's [`Status`](crate::fmi::Status) as C has it.
pub const fmi3OK: fmi3Status = crate::fmi::Status::Ok as fmi3Status;
pub const fmi3Warning: fmi3Status = crate::fmi::Status::Warning as fmi3Status;
pub const fmi3Discard: fmi3Status = crate::fmi::Status::Discard as fmi3Status;
pub const fmi3Error: fmi3Status = crate::fmi::Status::Error as fmi3Status;
pub const fmi3Fatal: fmi3Status = crate::fmi::Status::Fatal as fmi3Status;

/// fmi3LogMessageCallback: the message as it is, not a format.
pub type fmi3LogMessageCallback =
    unsafe extern "C" fn(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String);

/// fmi3IntermediateUpdateCallback.
pub type fmi3IntermediateUpdateCallback = unsafe extern "C" fn(
    fmi3InstanceEnvironment,
    fmi3Float64,      // intermediateUpdateTime
    fmi3Boolean,      // intermediateVariableSetRequested
    fmi3Boolean,      // intermediateVariableGetAllowed
    fmi3Boolean,      // intermediateStepFinished
    fmi3Boolean,      // canReturnEarly
    *mut fmi3Boolean, // earlyReturnRequested
    *mut fmi3Float64, // earlyReturnTime
);

/// fmi3ClockUpdateCallback (scheduled execution, which this FMU does not provide).
pub type fmi3ClockUpdateCallback = unsafe extern "C" fn(fmi3InstanceEnvironment);
/// fmi3LockPreemptionCallback and fmi3UnlockPreemptionCallback (the same).
pub type fmi3PreemptionCallback = unsafe extern "C" fn();
