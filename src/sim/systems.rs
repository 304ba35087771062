//! The systems a scene makes, for our integrator (`Run`) and for a host's (`Equations`): the
//! model a scene's parameters build, and each formulation's system on a piece of φ with its
//! initial state.
#![forbid(unsafe_code)]

use super::SimError;
use crate::model::{
    BeamBody, BeamBodyN, BeamN, DaeSystem, ElementsSystem, Formulation, PhiPiece, TwoDofSystem,
};
use crate::scene::{InitialState, Scene};
use nalgebra::SVector;

/// The model a scene describes: the paper's two coordinates on the stack, or the beam in n
/// elements (damped, exact) on the heap. The one construction [`Run::start`](super::Run) and
/// [`Equations::new`] share.
pub(super) fn build_model(
    scene: &Scene,
    phi0: f64,
) -> Result<(BeamBody, Option<Box<BeamN>>), SimError> {
    let model = scene.check_model(phi0).map_err(SimError::Setting)?;
    let elements = (!scene.params.is_paper_model())
        .then(|| BeamN::new(scene.params, scene.formulation).map(Box::new))
        .transpose()
        .map_err(SimError::Setting)?;
    Ok((model, elements))
}

/// The system of the four-state formulations (reduced, linear) on piece `phi`: the one step
/// from a formulation to its equations, for the driver and the benchmark's peers.
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
