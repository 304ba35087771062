//! The exact beam ([`ExactBeam`]): valid at any rotation, y = (q, q̇) of 4n states, its Jacobian
//! dense; its one limit, a centreline that crosses itself, is checked at each step's end.
#![forbid(unsafe_code)]

use super::quadratic::motion_of;
use super::Theory;
use crate::model::{ExactBeam, ExactSystem, Kinematics, PhiPiece};
use crate::scene::InitialState;
use crate::solver::Layout;
use nalgebra::{DVector, Dyn};

#[derive(Clone, Debug)]
pub struct Exact {
    model: ExactBeam,
}

impl Exact {
    pub fn new(model: ExactBeam) -> Self {
        Exact { model }
    }
}

impl Theory for Exact {
    type D = Dyn;
    type System<'a> = ExactSystem<'a>;

    fn states(&self) -> usize {
        2 * self.model.dofs()
    }

    fn system(&self, phi: PhiPiece, range_check: bool) -> ExactSystem<'_> {
        ExactSystem { model: &self.model, phi, range_check }
    }

    fn kinematics(sys: &ExactSystem<'_>, t: f64, y: &DVector<f64>) -> Kinematics {
        sys.kinematics(t, y)
    }

    /// The cubic whose centreline's tip has the tip's values ([`ExactSystem::start`]).
    fn start(&self, phi: PhiPiece, i: &InitialState) -> Result<DVector<f64>, String> {
        self.system(phi, true).start(i.v1, i.theta1, i.dv1, i.dtheta1)
    }

    fn layout(&self) -> Option<Layout> {
        Some(Layout::Dense)
    }

    fn motion(sys: &ExactSystem<'_>, t: f64, y: &DVector<f64>, out: &mut Vec<f64>) {
        motion_of(sys, sys.model.dofs(), t, y, out);
    }

    /// The centreline's y = r_y(s_k) and the section angle α(s_k) at the arc length s_k = k·l/n.
    fn nodal_shape(&self, y: &[f64]) -> Vec<f64> {
        let q = &y[..self.model.dofs()];
        let zero = vec![0.0; q.len()];
        let (n, l) = (q.len() / 2, self.model.params().l);
        (1..=n)
            .flat_map(|k| {
                let s = l * k as f64 / n as f64;
                [self.model.point(q, &zero, &zero, s).r[1], q[2 * k - 1]]
            })
            .collect()
    }

    /// r_y(l) and α(l).
    fn tip(&self, y: &[f64]) -> (f64, f64) {
        self.model.tip_values(&y[..self.model.dofs()])
    }

    fn tip_limits(&self) -> bool {
        false
    }
}
