//! The beam in n elements of either theory (`beam = quadratic | exact`) and its system: the
//! one place a run chooses between [`BeamBodyN`] and [`ExactBeam`].

use super::dynamics_n::BeamBodyN;
use super::exact::ExactBeam;
use super::formulation::{BeamModel, Formulation};
use super::params::Params;
use super::phi::PhiPiece;
use super::systems::Kinematics;
use super::systems_exact::ExactSystem;
use super::systems_n::ElementsSystem;
use crate::solver::{Layout, OdeSystem, RangeViolation, SecondOrder};
use nalgebra::{DMatrix, DVector, Dyn};

/// The beam in n elements (or damped, or exact), with the body. A run holds one, boxed.
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
            BeamN::Quadratic(m) => {
                let t = m.beam.tip();
                (q[t], q[t + 1])
            }
            BeamN::Exact(m) => m.tip_values(q),
        }
    }

    /// Every node's deflection and slope (v_k, ϑ_k), k = 1..n, the tip last: the
    /// coordinates of the quadratic beam; the centreline's y = r_y(s_k) and the section angle
    /// α(s_k) of the exact one, at the arc length s_k = k·l/n.
    pub fn nodal_shape(&self, q: &[f64]) -> Vec<f64> {
        match self {
            BeamN::Quadratic(_) => q.to_vec(),
            BeamN::Exact(m) => {
                let zero = vec![0.0; q.len()];
                let (n, l) = (q.len() / 2, m.params().l);
                (1..=n)
                    .flat_map(|k| {
                        let s = l * k as f64 / n as f64;
                        [m.point(q, &zero, &zero, s).r[1], q[2 * k - 1]]
                    })
                    .collect()
            }
        }
    }

    /// The system on piece `phi`.
    pub fn system(
        &self,
        phi: PhiPiece,
        formulation: Formulation,
        range_check: bool,
    ) -> SystemN<'_> {
        match self {
            BeamN::Quadratic(model) => {
                SystemN::Quadratic(ElementsSystem { model, phi, formulation, range_check })
            }
            BeamN::Exact(model) => SystemN::Exact(ExactSystem { model, phi, range_check }),
        }
    }
}

/// The system of a [`BeamN`].
#[derive(Clone, Copy, Debug)]
pub enum SystemN<'a> {
    Quadratic(ElementsSystem<'a>),
    Exact(ExactSystem<'a>),
}

impl SystemN<'_> {
    /// The state with the tip's values ([`ElementsSystem::start`], [`ExactSystem::start`]).
    pub fn start(
        &self,
        v1: f64,
        theta1: f64,
        dv1: f64,
        dtheta1: f64,
    ) -> Result<DVector<f64>, String> {
        match self {
            SystemN::Quadratic(s) => Ok(s.start(v1, theta1, dv1, dtheta1)),
            SystemN::Exact(s) => s.start(v1, theta1, dv1, dtheta1),
        }
    }

    /// The layout of the parts [`second_order`](OdeSystem::second_order) gives, `None` if it
    /// gives none (the quadratic beam's DAE formulations: a dense Jacobian by differences).
    pub fn layout(&self) -> Option<Layout> {
        match self {
            SystemN::Quadratic(s) => (!s.formulation.is_dae()).then_some(Layout::Banded),
            SystemN::Exact(_) => Some(Layout::Dense),
        }
    }

    /// The outputs' motion at (t, y).
    pub fn kinematics(&self, t: f64, y: &DVector<f64>) -> Kinematics {
        match self {
            SystemN::Quadratic(s) => s.kinematics(t, y),
            SystemN::Exact(s) => s.kinematics(t, y),
        }
    }
}

impl OdeSystem<Dyn> for SystemN<'_> {
    fn rhs(&self, t: f64, y: &DVector<f64>) -> DVector<f64> {
        match self {
            SystemN::Quadratic(s) => s.rhs(t, y),
            SystemN::Exact(s) => s.rhs(t, y),
        }
    }

    fn jacobian(&self, t: f64, y: &DVector<f64>) -> Option<DMatrix<f64>> {
        match self {
            SystemN::Quadratic(s) => s.jacobian(t, y),
            SystemN::Exact(s) => s.jacobian(t, y),
        }
    }

    fn second_order(&self, t: f64, y: &DVector<f64>) -> Option<SecondOrder> {
        match self {
            SystemN::Quadratic(s) => s.second_order(t, y),
            SystemN::Exact(s) => s.second_order(t, y),
        }
    }

    fn project(&self, t: f64, y: &DVector<f64>) -> Option<DVector<f64>> {
        match self {
            SystemN::Quadratic(s) => s.project(t, y),
            SystemN::Exact(s) => s.project(t, y),
        }
    }

    fn check_range(&self, t: f64, y: &DVector<f64>) -> Result<(), RangeViolation> {
        match self {
            SystemN::Quadratic(s) => s.check_range(t, y),
            SystemN::Exact(s) => s.check_range(t, y),
        }
    }
}
