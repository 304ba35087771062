//! The paper's model: one element, two coordinates (v1, ϑ1). In minimal coordinates
//! ([`Paper`]: eq. 15, or eq. 16 linearised), four states on the stack; with the hinge's axial
//! displacement u2 and the reaction of the inextensibility constraint ([`PaperDae`]: eq. 20–21),
//! six.
#![forbid(unsafe_code)]

use super::Theory;
use crate::model::{BeamBody, DaeSystem, Formulation, Kinematics, PhiPiece, TwoDofSystem};
use crate::scene::InitialState;
use crate::sim::systems::{dae, dae_start, two_dof, two_dof_start};
use nalgebra::{Vector4, Vector6, U4, U6};

/// The paper's model in minimal coordinates: y = (v1, ϑ1, v̇1, ϑ̇1).
#[derive(Clone, Debug)]
pub struct Paper {
    model: BeamBody,
    /// Reduced (eq. 15) or linear (eq. 16).
    formulation: Formulation,
}

impl Paper {
    /// `formulation` reduced or linear.
    pub fn new(model: BeamBody, formulation: Formulation) -> Self {
        Paper { model, formulation }
    }
}

impl Theory for Paper {
    type D = U4;
    type System<'a> = TwoDofSystem<'a>;

    fn states(&self) -> usize {
        4
    }

    fn system(&self, phi: PhiPiece, range_check: bool) -> TwoDofSystem<'_> {
        TwoDofSystem { range_check, ..two_dof(&self.model, phi, self.formulation) }
    }

    fn kinematics(sys: &TwoDofSystem<'_>, t: f64, y: &Vector4<f64>) -> Kinematics {
        sys.kinematics(t, y)
    }

    fn start(&self, _phi: PhiPiece, init: &InitialState) -> Result<Vector4<f64>, String> {
        Ok(two_dof_start(init))
    }

    fn record(_sys: &TwoDofSystem<'_>, _t: f64, y: &Vector4<f64>, out: &mut [f64; 6]) -> usize {
        out[..4].copy_from_slice(y.as_slice());
        4
    }

    fn nodal_shape(&self, y: &[f64]) -> Vec<f64> {
        y[..2].to_vec()
    }

    fn tip(&self, y: &[f64]) -> (f64, f64) {
        (y[0], y[1])
    }
}

/// The paper's DAE: y = (v1, ϑ1, u2, v̇1, ϑ̇1, u̇2), the constraint differentiated twice,
/// projected onto it after each step when stabilised.
#[derive(Clone, Debug)]
pub struct PaperDae {
    model: BeamBody,
    /// Dae or dae_stabilized.
    formulation: Formulation,
}

impl PaperDae {
    /// `formulation` dae or dae_stabilized.
    pub fn new(model: BeamBody, formulation: Formulation) -> Self {
        PaperDae { model, formulation }
    }
}

impl Theory for PaperDae {
    type D = U6;
    type System<'a> = DaeSystem<'a>;

    fn states(&self) -> usize {
        6
    }

    fn system(&self, phi: PhiPiece, range_check: bool) -> DaeSystem<'_> {
        DaeSystem { range_check, ..dae(&self.model, phi, self.formulation) }
    }

    fn kinematics(sys: &DaeSystem<'_>, t: f64, y: &Vector6<f64>) -> Kinematics {
        sys.kinematics(t, y)
    }

    /// u2 and u̇2 consistent with the constraint.
    fn start(&self, phi: PhiPiece, init: &InitialState) -> Result<Vector6<f64>, String> {
        Ok(dae_start(&self.system(phi, true), init))
    }

    /// The whole state, projected when stabilised (as the outputs are).
    fn record(sys: &DaeSystem<'_>, _t: f64, y: &Vector6<f64>, out: &mut [f64; 6]) -> usize {
        let y = if sys.stabilized { sys.consistent(y) } else { *y };
        out.copy_from_slice(y.as_slice());
        6
    }

    fn nodal_shape(&self, y: &[f64]) -> Vec<f64> {
        y[..2].to_vec()
    }

    fn tip(&self, y: &[f64]) -> (f64, f64) {
        (y[0], y[1])
    }
}
