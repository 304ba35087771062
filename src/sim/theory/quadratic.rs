//! The beam in n quadratic elements ([`BeamBodyN`]): the paper's second-order beam with more
//! coordinates, y = (q, q̇) of 4n states (reduced, linear) or (q, u2, q̇, u̇2) of 4n + 2 (dae,
//! dae_stabilized); its Jacobian banded plus rank one in minimal coordinates.
#![forbid(unsafe_code)]

use super::Theory;
use crate::model::{BeamBodyN, ElementsSystem, Formulation, Kinematics, PhiPiece};
use crate::scene::InitialState;
use crate::solver::{Layout, OdeSystem};
use nalgebra::{DVector, Dyn};

#[derive(Clone, Debug)]
pub struct Quadratic {
    model: BeamBodyN,
    formulation: Formulation,
}

impl Quadratic {
    pub fn new(model: BeamBodyN, formulation: Formulation) -> Self {
        Quadratic { model, formulation }
    }
}

impl Theory for Quadratic {
    type D = Dyn;
    type System<'a> = ElementsSystem<'a>;

    fn states(&self) -> usize {
        2 * (self.model.dofs() + usize::from(self.formulation.is_dae()))
    }

    fn system(&self, phi: PhiPiece, range_check: bool) -> ElementsSystem<'_> {
        ElementsSystem { model: &self.model, phi, formulation: self.formulation, range_check }
    }

    fn kinematics(sys: &ElementsSystem<'_>, t: f64, y: &DVector<f64>) -> Kinematics {
        sys.kinematics(t, y)
    }

    /// The one cubic of the tip's values ([`ElementsSystem::start`]).
    fn start(&self, phi: PhiPiece, i: &InitialState) -> Result<DVector<f64>, String> {
        Ok(self.system(phi, true).start(i.v1, i.theta1, i.dv1, i.dtheta1))
    }

    /// Banded in minimal coordinates; the DAE formulations give no parts (a dense Jacobian by
    /// differences).
    fn layout(&self) -> Option<Layout> {
        (!self.formulation.is_dae()).then_some(Layout::Banded)
    }

    /// Every coordinate, rate and acceleration: q, q̇ of the state, q̈ of f; without the DAE's
    /// u2, u̇2, ü2.
    fn motion(sys: &ElementsSystem<'_>, t: f64, y: &DVector<f64>, out: &mut Vec<f64>) {
        motion_of(sys, sys.model.dofs(), t, y, out);
    }

    fn nodal_shape(&self, y: &[f64]) -> Vec<f64> {
        y[..self.model.dofs()].to_vec()
    }

    fn tip(&self, y: &[f64]) -> (f64, f64) {
        self.model.tip_values(y)
    }
}

/// The motion of a beam's `nq` coordinates q at (t, y): q and q̇ from the state, y = (q, q̇) or,
/// with the DAE's u2, (q, u2, q̇, u̇2); q̈ from f, whose second half is the accelerations.
pub(super) fn motion_of<S: OdeSystem<Dyn>>(
    sys: &S,
    nq: usize,
    t: f64,
    y: &DVector<f64>,
    out: &mut Vec<f64>,
) {
    let dy = sys.rhs(t, y);
    let nc = y.len() / 2;
    out.extend_from_slice(&y.as_slice()[..nq]);
    out.extend_from_slice(&y.as_slice()[nc..nc + nq]);
    out.extend_from_slice(&dy.as_slice()[nc..nc + nq]);
}
