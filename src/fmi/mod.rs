//! The generic FMI core: what every FMI interface of a model shares, knowing the model only
//! through the traits of [`model`].
//!
//! - [`description`]: the types that describe an interface (variables, units, flags).
//! - [`Api`]: what one FMI version changes in the names and rules, as data its interface
//!   layer hands to the instance; the core never asks which version it serves.
//! - [`model`]: the traits a model implements ([`Model`], [`CoSimulation`],
//!   [`ModelExchange`]), and the values
//!   that cross them.
//! - `machine`: the states, the masks of allowed calls, the statuses and the error that
//!   carries a status to the edge.
//! - `instance`: one instance: logging, the lifecycle, get and set by value reference, FMU
//!   state snapshots. `cosim`: the co-simulation calls; `exchange`: Model Exchange's.
//! - `snapshot`: what an FMU state holds, and its byte format.
//!
//! No `unsafe` and no I/O: the interface layers (`crate::fmi2`, `crate::fmi3`) turn the C
//! calls into calls of [`Instance`], and the errors into C statuses once, at their edge.
#![forbid(unsafe_code)]

mod api;
mod cosim;
pub mod description;
mod exchange;
mod instance;
mod machine;
pub mod model;
mod snapshot;

pub use api::Api;
pub use cosim::{
    MAX_PARTS, STATUS_DO_STEP, STATUS_LAST_SUCCESSFUL_TIME, STATUS_PENDING, STATUS_TERMINATED,
};
pub use description::{BaseType, Dim, Only, VarInfo, Version, LOG_CATEGORIES};
pub use exchange::{EventInfo, StepEnd};
pub use instance::{Func, Instance, IntermediateUpdate, Logger};
pub(crate) use machine::mask;
pub use machine::{FmiError, FmiResult, Interface, State, Status};
pub use model::{CoSimulation, Model, ModelExchange, Notes, Restore, Setup, StepFailure, Value};
pub use snapshot::{
    deserialize, field_offsets, reseal, reseal_checksum, serialize, version, visit_optional,
    Snapshot, CORE_VERSION, HEADER,
};
