//! The beam in n elements of either theory (`beam = quadratic | exact`): the one place the
//! parameters choose between [`BeamBodyN`] and [`ExactBeam`], with what both give (the
//! equilibrium and the modes at a held φ). A run steps either through its theory
//! (`sim::theory`).

use super::dynamics_n::BeamBodyN;
use super::exact::ExactBeam;
use super::formulation::{BeamModel, Formulation};
use super::params::Params;
use nalgebra::DVector;

/// The beam in n elements (or damped, or exact), with the body.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum BeamN {
    Quadratic(BeamBodyN),
    Exact(ExactBeam),
}

impl BeamN {
    /// The model `params.beam` names. The exact beam takes the reduced formulation only: it
    /// has no inextensibility constraint to relax (it holds by construction), and its
    /// linearisation is the quadratic model's. The beam's weight is the exact beam's only.
    pub fn new(params: Params, formulation: Formulation) -> Result<Self, String> {
        match params.beam {
            BeamModel::Quadratic if params.beam_gravity => Err(
                "`beam_gravity` = true needs `beam` = exact: the quadratic model is the paper's \
                 beam, which has no weight of its own"
                    .to_string(),
            ),
            BeamModel::Quadratic => BeamBodyN::new(params).map(BeamN::Quadratic),
            BeamModel::Exact if formulation != Formulation::Reduced => Err(format!(
                "`formulation` = {formulation} needs `beam` = quadratic: the exact beam is \
                 inextensible by construction, with no constraint to relax, and its \
                 linearisation is the quadratic model's; use formulation = reduced"
            )),
            BeamModel::Exact => ExactBeam::new(params).map(BeamN::Exact),
        }
    }

    /// The quadratic model of the same parameters (the exact beam's K, D and elements).
    pub fn quadratic(&self) -> &BeamBodyN {
        match self {
            BeamN::Quadratic(m) => m,
            BeamN::Exact(m) => &m.quadratic,
        }
    }

    /// The number of coordinates, 2n.
    pub fn dofs(&self) -> usize {
        self.quadratic().dofs()
    }

    /// The static equilibrium q at a held φ (of the linear equations with `linear`, which the
    /// exact beam shares with the quadratic one).
    pub fn equilibrium(&self, phi_fixed: f64, linear: bool) -> Option<DVector<f64>> {
        match self {
            BeamN::Exact(m) if !linear => m.equilibrium(phi_fixed),
            _ => self.quadratic().equilibrium(phi_fixed, linear),
        }
    }

    /// The small oscillations' ω², ascending, about the equilibrium at a held φ, with it.
    pub fn modes(&self, phi_fixed: f64) -> Option<(DVector<f64>, Vec<f64>)> {
        match self {
            BeamN::Quadratic(m) => m.modes(phi_fixed),
            BeamN::Exact(m) => m.modes(phi_fixed),
        }
    }

    /// The tip's deflection and slope (v1, ϑ1) at q: the tip's coordinates of the quadratic
    /// beam, r_y(l) and α(l) of the exact one.
    pub fn tip_values(&self, q: &[f64]) -> (f64, f64) {
        match self {
            BeamN::Quadratic(m) => m.tip_values(q),
            BeamN::Exact(m) => m.tip_values(q),
        }
    }
}
