//! The C edge that FMI 2.0 (`fmi2`) and FMI 3.0 (`fmi3`) share: the registry of live
//! instances and FMU states, the panic guard and pointer checks, and the functions whose C
//! shape is the same in both versions (the FMU state's six). Each version's exports are a thin
//! layer over these and the generic core ([`crate::fmi`]).
//!
//! - `registry`: the live instances and FMU states; a pointer not in it is refused.
//! - `guard`: the panic guard, the version check, the pointer checks, and the one shape of
//!   the get and set functions.
//! - `states`: GetFMUState … DeserializeFMUState, for both versions.
#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

pub(crate) mod guard;
pub(crate) mod registry;
pub(crate) mod states;

use crate::fmi;
use crate::fmu::BeamBodyFmu;
use std::ffi::{c_int, c_void};

/// An instance of the beam–body model, whichever version made it.
pub type Instance = fmi::Instance<BeamBodyFmu>;
/// An FMU state of it.
pub type Core = fmi::Snapshot<BeamBodyFmu>;
/// fmi2Component, fmi3Instance, fmi2FMUstate, fmi3FMUState: opaque pointers.
pub type Handle = *mut c_void;
/// fmi2Status and fmi3Status: an `int` (fmi3Status is a C enum, an `int` on every platform
/// we build for).
pub type CStatus = c_int;
