//! The Jacobian of the n-element equations in the integrator's structured form
//! ([`SecondOrder`]): with R(q, q̇) = M(q)·ā − F(q, q̇) at the accelerations ā of the point,
//! the mass M, C = ∂R/∂q̇ and S = ∂R/∂q, each the beam's band (with the body's terms on the
//! tip's block) and a rank-one term a·cᵀ, a = Gq + r sin θ e_ϑ. Derived by hand from
//! `dynamics_n.rs`'s M and F (the notation there); `tests` check every part against
//! central differences of the accelerations.
//!
//! Reduced (θ = ϑ_tip + φ, s, c = sin θ, cos θ, θ̇ = ϑ̇_tip + φ′; e = e_ϑ, e_t = e_v):
//! - M = B + M2 a aᵀ.
//! - C = D + M2 a (2Gq̇ + 2rcθ̇ e)ᵀ − 2M2 r s θ̇ (e_t + rc e) eᵀ.
//! - S = K + M2 (aᵀā − a_x) G + M2 a (Gā + rc ā_ϑ e − ∂a_x/∂θ e)ᵀ + (∂B/∂θ ā) eᵀ +
//!   M2 (e_t + rc e)(∂a_y/∂θ) eᵀ + M2 r c (aᵀā − a_x) e eᵀ − M2 r s a_y e eᵀ, with
//!   ∂a_x/∂θ = r s θ̇² − r c φ″ and ∂a_y/∂θ = −r c θ̇² − r s φ″.
//!
//! Linear (eq. 16 generalised; B0 and the a0 of `linear`): M = B0, C = D + M2 ∂day/∂ϑ̇ e_t eᵀ,
//! S = K − M2 a0_x G + (the tip block of ∂/∂ϑ of the tip's rows).

use super::dynamics_n::BeamBodyN;
use super::params::Params;
use super::phi::Phi;
use crate::math;
use crate::solver::{BandedParts, GenBand, SecondOrder};

/// `band` of the model's symmetric [`Band`](super::band::Band) into `out`, times `s`.
fn add_symmetric(out: &mut GenBand, s: f64, band: &super::band::Band) {
    let n = band.n();
    for i in 0..n {
        for j in i.saturating_sub(3)..=(i + 3).min(n - 1) {
            out.add(i, j, s * band.get(i, j));
        }
    }
}

impl BeamBodyN {
    /// The reduced (or, with `linear`, the linear) equations' Jacobian at (q, q̇) as
    /// [`SecondOrder`] parts; `None` where the mass matrix is not positive definite.
    pub fn second_order(
        &self,
        phi: &Phi,
        q: &[f64],
        qd: &[f64],
        linear: bool,
    ) -> Option<SecondOrder> {
        let n = self.dofs();
        let mut acc = vec![0.0; n];
        if linear {
            self.linear(phi, q, qd, &mut acc);
        } else {
            self.reduced(phi, q, qd, &mut acc);
        }
        if !acc.iter().all(|x| x.is_finite()) {
            return None;
        }
        let Params { m2, j_c, r, g: grav, .. } = self.params;
        let t = self.beam.tip();
        let e = t + 1;
        let beam = &self.beam;
        let mut parts = BandedParts::zeros(n);
        add_symmetric(&mut parts.mass.band, 1.0, &beam.mass);
        add_symmetric(&mut parts.stiffness.band, 1.0, &beam.stiffness);
        if let Some(d) = self.damping_band() {
            add_symmetric(&mut parts.damping.band, 1.0, d);
        }
        let (w, ddphi) = (phi.dphi, phi.ddphi);
        if linear {
            let (s0, c0) = math::sin_cos(phi.phi);
            let a0x = -r * c0 * w * w - r * s0 * ddphi - grav;
            let a0y = -r * s0 * w * w + r * c0 * ddphi;
            let mass = &mut parts.mass.band;
            mass.add(t, t, m2);
            mass.add(t, e, m2 * r * c0);
            mass.add(e, t, m2 * r * c0);
            mass.add(e, e, m2 * r * r + j_c);
            add_symmetric(&mut parts.stiffness.band, -m2 * a0x, &beam.g);
            // ∂(da)/∂ϑ and ∂(da)/∂ϑ̇ of `linear`'s first-order terms.
            let (dax_th, day_th) =
                (r * s0 * w * w - r * c0 * ddphi, -r * c0 * w * w - r * s0 * ddphi);
            let (dax_dth, day_dth) = (-2.0 * r * c0 * w, -2.0 * r * s0 * w);
            let st = &mut parts.stiffness.band;
            st.add(t, e, m2 * day_th);
            st.add(e, e, m2 * (-r * s0 * dax_th + r * c0 * day_th - r * c0 * a0x - r * s0 * a0y));
            let dp = &mut parts.damping.band;
            dp.add(t, e, m2 * day_dth);
            dp.add(e, e, m2 * (-r * s0 * dax_dth + r * c0 * day_dth));
            return Some(SecondOrder::Banded(parts));
        }
        let (s, c) = math::sin_cos(q[e] + phi.phi);
        let dth = qd[e] + w;
        let gq = beam.g.mul(q);
        let gv = beam.g.mul(qd);
        let ga = beam.g.mul(&acc);
        let ax = -beam.g.form(qd, qd) - r * c * dth * dth - r * s * ddphi - grav;
        let ay = -r * s * dth * dth + r * c * ddphi;
        let dax = r * s * dth * dth - r * c * ddphi;
        let day = -r * c * dth * dth - r * s * ddphi;
        let mut a = gq;
        a[e] += r * s;
        let a_acc: f64 = a.iter().zip(&acc).map(|(x, y)| x * y).sum();
        // M = B + M2 a aᵀ.
        let mass = &mut parts.mass.band;
        mass.add(t, t, m2);
        mass.add(t, e, m2 * r * c);
        mass.add(e, t, m2 * r * c);
        mass.add(e, e, m2 * r * r * c * c + j_c);
        parts.mass.u.clone_from(&a);
        parts.mass.v = a.iter().map(|x| m2 * x).collect();
        // C.
        let dp = &mut parts.damping.band;
        dp.add(t, e, -2.0 * m2 * r * s * dth);
        dp.add(e, e, -2.0 * m2 * r * s * dth * r * c);
        parts.damping.u.clone_from(&a);
        parts.damping.v = gv.iter().map(|x| 2.0 * m2 * x).collect();
        parts.damping.v[e] += 2.0 * m2 * r * c * dth;
        // S.
        add_symmetric(&mut parts.stiffness.band, m2 * (a_acc - ax), &beam.g);
        let st = &mut parts.stiffness.band;
        // (∂B/∂θ ā) eᵀ.
        st.add(t, e, -m2 * r * s * acc[e]);
        st.add(e, e, -m2 * r * s * acc[t] - 2.0 * m2 * r * r * c * s * acc[e]);
        // M2 (e_t + rc e) ∂a_y/∂θ eᵀ, and the θ-derivatives of a's and the tip row's r c.
        st.add(t, e, m2 * day);
        st.add(e, e, m2 * r * c * day + m2 * r * c * (a_acc - ax) - m2 * r * s * ay);
        parts.stiffness.u = a;
        parts.stiffness.v = ga.iter().map(|x| m2 * x).collect();
        parts.stiffness.v[e] += m2 * (r * c * acc[e] - dax);
        Some(SecondOrder::Banded(parts))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    fn model(n: usize, damping: bool) -> BeamBodyN {
        let mut p = Params { n_elements: n, ..Params::default() };
        if damping {
            p.damping_alpha = 0.3;
            p.damping_beta = 2e-3;
        }
        BeamBodyN::new(p).unwrap()
    }

    /// The accelerations' Jacobian A = ∂q̈/∂(q, q̇) by central differences.
    fn fd_jacobian(m: &BeamBodyN, phi: &Phi, q: &[f64], qd: &[f64], linear: bool) -> DMatrix<f64> {
        let n = q.len();
        let acc = |q: &[f64], qd: &[f64]| {
            let mut out = vec![0.0; n];
            if linear {
                m.linear(phi, q, qd, &mut out);
            } else {
                m.reduced(phi, q, qd, &mut out);
            }
            DVector::from_vec(out)
        };
        let mut a = DMatrix::zeros(n, 2 * n);
        for j in 0..2 * n {
            // q̈ is quadratic in q̇: central differences are exact there for any step, and a
            // large one keeps round-off (of accelerations up to 1e3 m/s²) out.
            let h = if j < n { 1e-6 } else { 1e-3 };
            let (mut qp, mut qm, mut vp, mut vm) =
                (q.to_vec(), q.to_vec(), qd.to_vec(), qd.to_vec());
            if j < n {
                qp[j] += h;
                qm[j] -= h;
            } else {
                vp[j - n] += h;
                vm[j - n] -= h;
            }
            a.set_column(j, &((acc(&qp, &vp) - acc(&qm, &vm)) / (2.0 * h)));
        }
        a
    }

    #[test]
    fn every_part_matches_central_differences() {
        let phi = Phi { phi: 1.1, dphi: -2.3, ddphi: 7.0 };
        for (n, damping) in [(1, false), (2, true), (4, false), (5, true)] {
            let m = model(n, damping);
            let dofs = m.dofs();
            let q: Vec<f64> = (0..dofs).map(|i| 0.08 * math::sin((i as f64) * 0.9 + 0.4)).collect();
            let qd: Vec<f64> = (0..dofs).map(|i| 0.5 * math::cos((i as f64) * 1.7 + 0.1)).collect();
            for linear in [false, true] {
                let parts = m.second_order(&phi, &q, &qd, linear).unwrap();
                let j = parts.dense_jacobian().unwrap();
                let lower = j.view((dofs, 0), (dofs, 2 * dofs)).clone_owned();
                let fd = fd_jacobian(&m, &phi, &q, &qd, linear);
                // Column by column: the body's terms sit in the tip's columns, far smaller
                // than the stiffness of the inner nodes.
                for c in 0..2 * dofs {
                    let (col, want) = (lower.column(c), fd.column(c));
                    let err = (col - want).amax();
                    assert!(
                        err <= 1e-6 * want.amax() + 1e-9,
                        "n {n} linear {linear} col {c}: {err}"
                    );
                }
            }
        }
    }
}
