//! The FMI 2.0 interface, Model Exchange and Co-Simulation: a thin `extern "C"` layer over
//! the generic core ([`crate::fmi`]) with the beam–body model ([`crate::fmu`]). All the
//! crate's `unsafe` code is here.
//!
//! - [`types`]: the C types.
//! - `registry`: the live instances and FMU states; a pointer not in it is refused.
//! - `guard`: the panic guard and the pointer checks, and the one shape of the get and set
//!   functions.
//! - [`exports`]: the 44 exported `fmi2…` functions (common, Model Exchange, co-simulation).

pub mod exports;
mod guard;
mod registry;
#[cfg(test)]
mod tests;
pub mod types;

use crate::fmi::{self, Interface, Logger, Status};
use crate::fmu::BeamBodyFmu;

/// An FMI 2.0 instance of the beam–body model.
pub type Instance = fmi::Instance<BeamBodyFmu>;
/// An FMU state of it.
pub type Core = fmi::Snapshot<BeamBodyFmu>;

/// The prefix of FMI 2.0's function names, for messages.
pub const API: &str = "fmi2";

/// fmi2Instantiate in safe Rust: `None`, after logging why, for an empty name, a type that is
/// neither Model Exchange nor co-simulation, or a GUID that is not this model's.
pub fn instantiate(
    name: &str,
    fmu_type: i32,
    guid: &str,
    mut log: Logger,
    logging_on: bool,
) -> Option<Instance> {
    let interface = match fmu_type {
        types::FMI2_MODEL_EXCHANGE => Interface::ModelExchange,
        types::FMI2_COSIMULATION => Interface::CoSimulation,
        _ => {
            let msg = format!(
                "fmi2Instantiate: fmuType = {fmu_type} is out of range: must be \
                 fmi2ModelExchange ({}) or fmi2CoSimulation ({})",
                types::FMI2_MODEL_EXCHANGE,
                types::FMI2_COSIMULATION
            );
            log(Status::Error, "logStatusError", &msg);
            return None;
        }
    };
    Instance::instantiate(API, interface, name, guid, log, logging_on)
}
