//! The FMI 3.0 interface, Model Exchange and Co-Simulation: a thin `extern "C"` layer over
//! the generic core ([`crate::fmi`]) with the beam–body model ([`crate::fmu`]), in the same
//! binary as FMI 2.0 (`BeamBody-fmi3.fmu` ships it in FMI 3.0's platform folders).
//!
//! - [`types`]: the C types.
//! - [`exports`]: the 75 exported `fmi3…` functions (the common ones; `values`, `exchange`
//!   and `cosim` hold the rest, which it re-exports), over the C edge both versions share
//!   ([`crate::capi`]: registry, guard, FMU states). Those the model does not provide
//!   (scheduled execution, clocks, reconfiguration mode, adjoint derivatives, variable
//!   dependencies, types it has no variables of) return fmi3Error with a message that says
//!   why (FMI 3.0 §2.5).
//!
//! What FMI 3.0 changes for this model (docs/interfaces.md, "FMI 3.0"): the setup comes with
//! EnterInitializationMode; enumerations are Int64; there are no input derivatives, and the
//! host may hand over φ inside a step through its intermediate-update callback instead;
//! co-simulation has no event mode (`hasEventMode = false`).

mod cosim;
mod exchange;
pub mod exports;
pub mod types;
mod values;

pub use crate::capi::{Core, Instance};
use crate::fmi::Model as _;
use crate::fmi::{mask, Api, Interface, IntermediateUpdate, Logger, State, Status, Version};
use crate::fmu::variables::{Var, VARIABLES};
use crate::fmu::BeamBodyFmu;

/// FMI 3.0's interface as the core needs it: its names of the calls, states and counts the
/// core names as FMI 2.0 does, and its rules.
pub static API: Api = Api {
    prefix: "fmi3",
    version: Version::Fmi3,
    rename,
    token: "instantiationToken",
    state_name,
    count_name: |name| match name {
        "nx" => "nContinuousStates",
        "ni" => "nEventIndicators",
        other => other,
    },
    step_end: ("lastSuccessfulTime", "terminateSimulation"),
    directional_flag: "providesDirectionalDerivatives",
    // FMI 3.0 §3.2: the derivatives and nominals from initialization mode on, like the
    // states and indicators (Reference-FMUs' masks).
    derivatives_mask: mask::EXCHANGE_ARRAYS3,
    nominals_mask: mask::EXCHANGE_ARRAYS3,
    configuration_mode: true,
};

/// FMI 3.0's name of a function the core names as FMI 2.0 does: the same call, renamed.
fn rename(name: &'static str) -> &'static str {
    match name {
        "GetFMUstate" => "GetFMUState",
        "SetFMUstate" => "SetFMUState",
        "FreeFMUstate" => "FreeFMUState",
        "SerializedFMUstateSize" => "SerializedFMUStateSize",
        "SerializeFMUstate" => "SerializeFMUState",
        "DeSerializeFMUstate" => "DeserializeFMUState",
        "GetReal" => "GetFloat64",
        "SetReal" => "SetFloat64",
        "GetInteger" => "GetInt32",
        "SetInteger" => "SetInt32",
        "GetDerivatives" => "GetContinuousStateDerivatives",
        "GetRealOutputDerivatives" => "GetOutputDerivatives",
        "NewDiscreteStates" => "UpdateDiscreteStates",
        other => other,
    }
}

/// FMI 3.0's name of a state: its Step Mode, and a step discarded there; the others are
/// FMI 2.0's names.
fn state_name(state: State) -> &'static str {
    match state {
        State::StepComplete => "step mode",
        State::StepFailed => "step discarded",
        other => other.name(),
    }
}

/// Co-simulation has no event mode (hasEventMode = false): its event calls are refused.
pub(crate) const NO_EVENT_MODE: &str =
    "this FMU's co-simulation has no event mode (hasEventMode = \
    false); it is a Model Exchange function here";

/// What fmi3InstantiateCoSimulation takes beyond the common arguments.
pub struct CoSimulationArgs<'a> {
    pub event_mode_used: bool,
    /// `requiredIntermediateVariables`.
    pub required: &'a [u32],
    /// The host's callback, wrapped: `None` when it passed NULL.
    pub intermediate_update: Option<IntermediateUpdate>,
}

/// fmi3Instantiate… in safe Rust: `None`, after logging why, for an empty name, a wrong
/// token, event mode asked of co-simulation, or a required intermediate variable that is
/// not one.
pub fn instantiate(
    name: &str,
    interface: Interface,
    token: &str,
    mut log: Logger,
    logging_on: bool,
    cs: Option<CoSimulationArgs>,
) -> Option<Instance> {
    let mut callback = None;
    if let Some(cs) = cs {
        if cs.event_mode_used {
            let msg = "fmi3InstantiateCoSimulation: eventModeUsed = true, but this FMU's \
                       co-simulation has no event mode (hasEventMode = false): its integrator \
                       handles the law's end and the range check inside fmi3DoStep";
            log(Status::Error, "logStatusError", msg);
            return None;
        }
        if let Err(msg) = check_required(cs.required) {
            log(Status::Error, "logStatusError", &format!("fmi3InstantiateCoSimulation: {msg}"));
            return None;
        }
        // The callback serves a host that will set φ or read outputs in it.
        let outputs = cs.required.iter().any(|vr| !BeamBodyFmu::intermediate_input(*vr));
        if !cs.required.is_empty() {
            callback = cs.intermediate_update.map(|cb| (cb, outputs));
        }
    }
    let mut inst = Instance::instantiate(&API, interface, name, token, log, logging_on)?;
    if let Some((cb, outputs)) = callback {
        inst.set_intermediate_update(cb, outputs);
    }
    Some(inst)
}

/// The variables a host may name in `requiredIntermediateVariables`: those marked
/// `intermediateUpdate = "true"` (FMI 3.0 requires it), the intermediate input `phi` and the
/// outputs. Values of any variable can be read in intermediate update mode anyway.
fn check_required(required: &[u32]) -> Result<(), String> {
    for vr in required {
        let Some(v) = VARIABLES.get(*vr as usize) else {
            return Err(format!(
                "requiredIntermediateVariables holds unknown value reference {vr}: must be \
                 below {}",
                VARIABLES.len()
            ));
        };
        if !BeamBodyFmu::intermediate_variable(*vr) {
            let phi = Var::Phi.info().name;
            return Err(format!(
                "requiredIntermediateVariables holds `{}` ({vr}), which is not marked \
                 intermediateUpdate = true: only the input `{phi}` and the outputs are",
                v.name
            ));
        }
    }
    Ok(())
}
