//! The formulations of the beam in n elements ([`BeamBodyN`]) as first-order systems of a
//! run-time dimension, and the outputs they report.
//!
//! State layouts, with q the 2n coordinates ([`Elements`](super::Elements)): reduced and
//! linear y = (q, q̇), 4n states; dae and dae_stabilized y = (q, u2, q̇, u̇2), 4n + 2.

use super::dynamics_n::BeamBodyN;
use super::formulation::Formulation;
use super::phi::PhiPiece;
use super::systems::{check_deflection, check_drift, check_numbers, Kinematics};
use crate::solver::{OdeSystem, RangeViolation, SecondOrder};
use nalgebra::{DVector, Dyn};

/// One of the four formulations of the model in n elements.
#[derive(Clone, Copy, Debug)]
pub struct ElementsSystem<'a> {
    pub model: &'a BeamBodyN,
    pub phi: PhiPiece,
    pub formulation: Formulation,
    /// As [`TwoDofSystem::range_check`](super::TwoDofSystem::range_check).
    pub range_check: bool,
}

impl ElementsSystem<'_> {
    /// The number of states.
    pub fn states(&self) -> usize {
        2 * self.coordinates()
    }

    /// The coordinates: q, and u2 in the DAE formulations.
    fn coordinates(&self) -> usize {
        self.model.dofs() + usize::from(self.formulation.is_dae())
    }

    /// The state with q and q̇ interpolated from the tip's values by the one cubic of a
    /// cantilever with that deflection and slope (the paper's single element; the start of
    /// every n is the same shape), u2 and u̇2 consistent.
    pub fn start(&self, v1: f64, theta1: f64, dv1: f64, dtheta1: f64) -> DVector<f64> {
        let beam = &self.model.beam;
        let (nq, nc) = (beam.dofs(), self.coordinates());
        let mut y = DVector::zeros(self.states());
        y.as_mut_slice()[..nq].copy_from_slice(&beam.tip_cubic(v1, theta1));
        y.as_mut_slice()[nc..nc + nq].copy_from_slice(&beam.tip_cubic(dv1, dtheta1));
        if self.formulation.is_dae() {
            let (u, du) = self.model.u1(&y.as_slice()[..nq], &y.as_slice()[nc..nc + nq]);
            y[nq] = u;
            y[nc + nq] = du;
        }
        y
    }

    /// The state projected onto the constraint: u2 = u1(q), u̇2 = −(Gq)ᵀq̇.
    pub fn consistent(&self, y: &DVector<f64>) -> DVector<f64> {
        let (nq, nc) = (self.model.dofs(), self.coordinates());
        let mut out = y.clone();
        let (u, du) = self.model.u1(&y.as_slice()[..nq], &y.as_slice()[nc..nc + nq]);
        out[nq] = u;
        out[nc + nq] = du;
        out
    }

    /// q̈ into `acc[..2n]` (and ü2 into `acc[2n]` in the DAE formulations); returns the
    /// hinge's axial acceleration.
    fn accelerations(&self, t: f64, y: &[f64], acc: &mut [f64]) -> f64 {
        let (nq, nc) = (self.model.dofs(), self.coordinates());
        let (q, qd) = (&y[..nq], &y[nc..nc + nq]);
        let phi = self.phi.eval(t);
        match self.formulation {
            Formulation::Linear => {
                self.model.linear(&phi, q, qd, &mut acc[..nq]);
                // u2 of the linear model is the quadratic u1 of its q (eq. 21), as for n = 1.
                let gq = self.model.beam.g.mul(q);
                let w = self.model.beam.g.form(qd, qd);
                -gq.iter().zip(&acc[..nq]).map(|(a, b)| a * b).sum::<f64>() - w
            }
            Formulation::Reduced => self.model.reduced(&phi, q, qd, &mut acc[..nq]),
            Formulation::Dae | Formulation::DaeStabilized => {
                let ddu = self.model.reduced(&phi, q, qd, &mut acc[..nq]);
                acc[nq] = ddu;
                ddu
            }
        }
    }

    /// The outputs' motion at (t, y): the tip's, projected first when stabilised.
    pub fn kinematics(&self, t: f64, y: &DVector<f64>) -> Kinematics {
        let y = if self.formulation == Formulation::DaeStabilized {
            self.consistent(y)
        } else {
            y.clone()
        };
        let (nq, nc) = (self.model.dofs(), self.coordinates());
        let s = y.as_slice();
        let (q, qd) = (&s[..nq], &s[nc..nc + nq]);
        let mut acc = vec![0.0; nc];
        let ddu = self.accelerations(t, s, &mut acc);
        let (u1, du1) = self.model.u1(q, qd);
        let (u2, du2, drift) = if self.formulation.is_dae() {
            (s[nq], s[nc + nq], s[nq] - u1)
        } else {
            (u1, du1, 0.0)
        };
        let tip = self.model.beam.tip();
        let (t1, p1) = self.model.beam_energy(q, qd);
        Kinematics {
            t,
            v1: q[tip],
            theta1: q[tip + 1],
            u2,
            dv1: qd[tip],
            dtheta1: qd[tip + 1],
            du2,
            ddv1: acc[tip],
            ddtheta1: acc[tip + 1],
            ddu2: ddu,
            phi: self.phi.eval(t),
            drift,
            beam_energy: Some(t1 + p1),
            node1: [q[0], q[1], qd[0], qd[1], acc[0], acc[1]],
            quarter: [q, qd, &acc[..nq]].map(|c| {
                [0.25, 0.5, 0.75].map(|f| self.model.beam.field(c, f * self.model.beam.l)[0])
            }),
            rayleigh: self.model.rayleigh(),
            root: None,
        }
    }
}

impl OdeSystem<Dyn> for ElementsSystem<'_> {
    fn rhs(&self, t: f64, y: &DVector<f64>) -> DVector<f64> {
        let nc = self.coordinates();
        let mut f = DVector::zeros(y.len());
        let (rates, acc) = f.as_mut_slice().split_at_mut(nc);
        rates.copy_from_slice(&y.as_slice()[nc..]);
        self.accelerations(t, y.as_slice(), acc);
        f
    }

    /// The reduced and linear formulations' Jacobian as bands and rank-one terms
    /// (`jacobian_n.rs`); the DAE formulations' (with u2) by differences.
    fn second_order(&self, t: f64, y: &DVector<f64>) -> Option<SecondOrder> {
        let linear = match self.formulation {
            Formulation::Reduced => false,
            Formulation::Linear => true,
            Formulation::Dae | Formulation::DaeStabilized => return None,
        };
        let nq = self.model.dofs();
        let (q, qd) = y.as_slice().split_at(nq);
        self.model.second_order(&self.phi.eval(t), q, qd, linear)
    }

    fn project(&self, _t: f64, y: &DVector<f64>) -> Option<DVector<f64>> {
        (self.formulation == Formulation::DaeStabilized).then(|| self.consistent(y))
    }

    fn check_range(&self, _t: f64, y: &DVector<f64>) -> Result<(), RangeViolation> {
        let tip = self.model.beam.tip();
        let (v1, theta1) = (y[tip], y[tip + 1]);
        let nq = self.model.dofs();
        if !self.range_check {
            if let Some(k) = (0..self.coordinates()).find(|&k| y[k].is_nan()) {
                return Err(RangeViolation { name: "q", value: y[k], allowed: "a number" });
            }
            return check_numbers(&[("v1", v1), ("theta1", theta1)]);
        }
        let l = self.model.params.l;
        check_deflection(l, v1, theta1)?;
        if self.formulation == Formulation::Dae {
            let q = &y.as_slice()[..nq];
            check_drift(l, y[nq] + 0.5 * self.model.beam.g.form(q, q))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{BeamBody, DaeSystem, Params, TwoDofSystem};
    use nalgebra::{Vector4, Vector6};

    /// With one element each formulation's right-hand side is the paper's model's, to
    /// round-off, and so are the outputs.
    #[test]
    fn one_element_has_the_paper_s_right_hand_sides() {
        let params = Params::default();
        let n1 = BeamBodyN::new(params).unwrap();
        let paper = BeamBody::new(params).unwrap();
        let phi = PhiPiece::Hold(0.7);
        let t = 0.3;
        for formulation in Formulation::ALL {
            let sys = ElementsSystem { model: &n1, phi, formulation, range_check: true };
            let y = sys.start(0.1, -0.05, 0.3, 0.2);
            let f = sys.rhs(t, &y);
            let (want, k_want) = if formulation.is_dae() {
                let stabilized = formulation == Formulation::DaeStabilized;
                let dae = DaeSystem { model: &paper, phi, stabilized, range_check: true };
                let y6 = Vector6::from_column_slice(y.as_slice());
                (dae.rhs(t, &y6).as_slice().to_vec(), dae.kinematics(t, &y6))
            } else {
                let linear = formulation == Formulation::Linear;
                let two = TwoDofSystem { model: &paper, phi, linear, range_check: true };
                let y4 = Vector4::from_column_slice(y.as_slice());
                (two.rhs(t, &y4).as_slice().to_vec(), two.kinematics(t, &y4))
            };
            for (a, b) in f.iter().zip(&want) {
                assert!(
                    (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                    "{formulation:?}: {f} vs {want:?}"
                );
            }
            let k = sys.kinematics(t, &y);
            let (e, e_want) = (k.energy(&paper), k_want.energy(&paper));
            assert!((e - e_want).abs() <= 1e-12 * e_want.abs(), "{formulation:?}: {e} vs {e_want}");
            let (r, r_want) = (k.reactions(&paper), k_want.reactions(&paper));
            assert!((r.m - r_want.m).abs() <= 1e-10 * r_want.m.abs().max(1.0), "{formulation:?}");
        }
    }
}
