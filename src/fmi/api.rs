//! What one FMI version's interface changes in the core's names and rules, as data: each
//! interface layer (`crate::fmi2`, `crate::fmi3`) defines one [`Api`] and hands it to
//! [`Instance::instantiate`](super::Instance::instantiate). The core asks the instance's
//! `Api`, never which version made it.

use super::description::Version;
use super::machine::State;

/// One FMI version's interface, as the core needs to know it.
#[derive(Debug)]
pub struct Api {
    /// The prefix of its function names (`fmi2`).
    pub prefix: &'static str,
    /// The model description it serves.
    pub version: Version,
    /// Its name of a function the core names as FMI 2.0 does (`GetReal` → `GetFloat64`).
    pub rename: fn(&'static str) -> &'static str,
    /// The instantiate argument that names the model description (`fmuGUID`).
    pub token: &'static str,
    /// Its name of a state (FMI 3.0's "step mode" is FMI 2.0's "step complete").
    pub state_name: fn(State) -> &'static str,
    /// Its name of a count argument the core names as FMI 2.0 does (`nx`).
    pub count_name: fn(&'static str) -> &'static str,
    /// In a discarded step's message, its names of the time the FMU stopped at and of the flag
    /// that says the FMU cannot go on (`fmi2LastSuccessfulTime`, `fmi2Terminated`).
    pub step_end: (&'static str, &'static str),
    /// The capability flag of directional derivatives (`providesDirectionalDerivative`).
    pub directional_flag: &'static str,
    /// The states GetDerivatives and GetNominalsOfContinuousStates are allowed in.
    pub derivatives_mask: u32,
    pub nominals_mask: u32,
    /// Whether a structural parameter is set in configuration mode only (FMI 3.0); otherwise it
    /// is a parameter like the others (FMI 2.0).
    pub configuration_mode: bool,
}

impl Api {
    /// Whether a call named `func` (`fmi2DoStep`) is one of this interface's.
    pub fn owns(&self, func: &str) -> bool {
        func.starts_with(self.prefix)
    }
}
