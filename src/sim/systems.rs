//! Each of the paper's formulations as a system on a piece of φ, with its initial state: for
//! the paper's theory ([`theory::Paper`](super::theory::Paper)) and the benchmark's peers.
#![forbid(unsafe_code)]

use crate::model::{
    BeamBody, BeamBodyN, DaeSystem, ElementsSystem, Formulation, PhiPiece, TwoDofSystem,
};
use crate::scene::InitialState;
use nalgebra::SVector;

/// The system of the four-state formulations (reduced, linear) on piece `phi`: the one step
/// from a formulation to its equations, for the paper's theories and the benchmark's peers.
pub fn two_dof(model: &BeamBody, phi: PhiPiece, formulation: Formulation) -> TwoDofSystem<'_> {
    TwoDofSystem { model, phi, linear: formulation == Formulation::Linear, range_check: true }
}

/// The system of the beam in n elements on piece `phi`.
pub fn elements_system(
    model: &BeamBodyN,
    phi: PhiPiece,
    formulation: Formulation,
) -> ElementsSystem<'_> {
    ElementsSystem { model, phi, formulation, range_check: true }
}

/// The system of the six-state formulations (dae, dae_stabilized) on piece `phi`.
pub fn dae(model: &BeamBody, phi: PhiPiece, formulation: Formulation) -> DaeSystem<'_> {
    let stabilized = formulation == Formulation::DaeStabilized;
    DaeSystem { model, phi, stabilized, range_check: true }
}

/// The four-state formulations' initial state (v1, ϑ1, v̇1, ϑ̇1).
pub fn two_dof_start(init: &InitialState) -> SVector<f64, 4> {
    SVector::<f64, 4>::new(init.v1, init.theta1, init.dv1, init.dtheta1)
}

/// The DAE's initial state: u2 and u̇2 made consistent with the constraint of `system`.
pub fn dae_start(system: &DaeSystem<'_>, init: &InitialState) -> SVector<f64, 6> {
    let free = SVector::<f64, 6>::new(init.v1, init.theta1, 0.0, init.dv1, init.dtheta1, 0.0);
    system.consistent(&free)
}
