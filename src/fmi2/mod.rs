//! The FMI 2.0 Co-Simulation layer.
//!
//! - [`variables`]: the table of variables, units, types and flags: the single source of
//!   truth for `modelDescription.xml` and the value references.
//! - `binding`: the variables bound to the model (parameters, the input, the outputs), with
//!   get and set by variable: the only place that knows both the table and the model.
//! - `core`: what an FMU state holds.
//! - [`instance`]: one FMU instance in safe Rust: the generic state machine, argument checks,
//!   get and set by value reference, `do_step`, FMU state snapshots.
//! - `state`: the byte format of a serialized FMU state.
//! - [`ffi`]: the 34 exported `fmi2…` functions: the only `unsafe` code in the crate. Pointer
//!   checks, the panic guard, and the host's logger.

mod binding;
mod core;
pub mod ffi;
pub mod instance;
mod state;
pub mod variables;
