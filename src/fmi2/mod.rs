//! The FMI 2.0 interface, Model Exchange and Co-Simulation: a thin `extern "C"` layer over
//! the generic core ([`crate::fmi`]) with the beam–body model ([`crate::fmu`]). With
//! [`crate::fmi3`] and [`crate::capi`], it holds all the crate's `unsafe` code.
//!
//! - [`types`]: the C types.
//! - [`exports`]: the 44 exported `fmi2…` functions (common, Model Exchange, co-simulation),
//!   over the C edge both versions share ([`crate::capi`]: registry, guard, FMU states).

pub mod exports;
#[cfg(test)]
mod tests;
pub mod types;

pub use crate::capi::{Core, Instance};
use crate::fmi::{mask, Api, Interface, Logger, State, Status, Version};

/// FMI 2.0's interface as the core needs it: the core's names are FMI 2.0's.
pub static API: Api = Api {
    prefix: "fmi2",
    version: Version::Fmi2,
    rename: |name| name,
    token: "fmuGUID",
    state_name: State::name,
    count_name: |name| name,
    step_end: ("fmi2LastSuccessfulTime", "fmi2Terminated"),
    directional_flag: "providesDirectionalDerivative",
    // FMI 2.0 §3.2.3: the derivatives from event mode on, the nominals from instantiation.
    derivatives_mask: mask::DERIVATIVES,
    nominals_mask: mask::NOMINALS,
    configuration_mode: false,
};

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
    Instance::instantiate(&API, interface, name, guid, log, logging_on)
}
