//! The FMI 2.0 Co-Simulation layer.
//!
//! - [`variables`]: the table of variables, units, types and flags: the single source of
//!   truth for `modelDescription.xml` and the value references.
//! - [`instance`]: one FMU instance in safe Rust: the state machine, argument checks, get and
//!   set by value reference, `do_step` with the internal BDF, FMU state and its byte format.
//! - [`ffi`]: the 34 exported `fmi2…` functions: the only `unsafe` code in the crate. Pointer
//!   checks, the panic guard, and the host's logger.

pub mod ffi;
pub mod instance;
mod state;
pub mod variables;
