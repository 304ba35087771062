//! The equations of motion of the beam in n elements with the body at its tip: the paper's
//! model (`dynamics.rs`) with the beam of [`Elements`] in place of its one element, and
//! Rayleigh damping of the beam.
//!
//! Coordinates q (2n, [`Elements`]); the tip's deflection v1 = q_t and slope ϑ1 = q_{t+1}
//! (t = 2n − 2); its axial displacement u1 = −½qᵀGq. The body's centre of mass is
//! C = (l + u_h + r cos θ, v1 + r sin θ), θ = ϑ1 + φ. From T = ½q̇ᵀM_b q̇ + ½M2|Ċ|² + ½J_C θ̇²,
//! Π = ½qᵀKq − M2 g (u_h + r cos θ) and the dissipation ½q̇ᵀD q̇, D = αM_b + βK, Lagrange's
//! equations with u_h = u1(q) read (as in `dynamics.rs`, with A = ∂C/∂q)
//!
//!   M_b q̈ + K q + D q̇ + M2 Aᵀ(C̈ − g e_x) + J_C θ̈ e_ϑ = 0,
//!
//! A's rows: A_x = −(Gq + r sin θ e_ϑ), A_y = e_v + r cos θ e_ϑ (e_v, e_ϑ: the tip's unit
//! vectors), and C̈ = A q̈ + a with a = (−q̇ᵀGq̇ − r cos θ θ̇² − r sin θ φ″, −r sin θ θ̇² +
//! r cos θ φ″). The mass matrix M_b + M2 AᵀA + J_C e_ϑe_ϑᵀ is the banded B = M_b +
//! M2 A_yA_yᵀ + J_C e_ϑe_ϑᵀ (A_y lives on the tip's two coordinates) plus the rank-one
//! M2 a_x a_xᵀ, a_x = Gq + r sin θ e_ϑ: q̈ by a band Cholesky of B and the Sherman–Morrison
//! formula, O(n).
//!
//! The DAE formulations integrate u_h = u2 with the constraint u2 = u1(q) differentiated
//! twice; eliminating ü2 by the constraint's row leaves exactly the equations above (the
//! paper's §3 remark; `dynamics.rs` solves its 3×3 system by the same elimination), so their
//! q̈ is the reduced one and ü2 = −(Gq)ᵀq̈ − q̇ᵀGq̇. The linear formulation is the first-order
//! Taylor expansion about q = q̇ = q̈ = 0 with φ kept exact, as eq. (16).

use super::band::{Band, BandCholesky};
use super::differences::negative_jacobian;
use super::dynamics::BeamBody;
use super::elements::Elements;
use super::params::Params;
use super::phi::Phi;
use crate::math;
use nalgebra::{DMatrix, DVector};

/// The most elements (the range of `n_elements`).
pub use crate::settings::MAX_ELEMENTS;
/// The most coordinates, for the right-hand side's buffers on the stack.
const MAX_DOFS: usize = 2 * MAX_ELEMENTS;

/// M q̈ = F in parts: M = B + M2·a aᵀ.
struct Assembled {
    /// The body's entries (t, t), (t + 1, t), (t + 1, t + 1) of B beyond M_b's.
    tip: [f64; 3],
    a: Vec<f64>,
    f: Vec<f64>,
}

fn dot(u: &[f64], v: &[f64]) -> f64 {
    u.iter().zip(v).map(|(a, b)| a * b).sum()
}

/// The model with n elements.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamBodyN {
    pub params: Params,
    pub beam: Elements,
    /// D = αM_b + βK; `None` without damping.
    damping: Option<Band>,
    /// The paper's model with the same parameters, for what depends on the tip only (the
    /// hinge reactions).
    pub tip: BeamBody,
    /// (α, β) of D.
    rayleigh: (f64, f64),
    /// M_b's Cholesky factor: the mass matrix B of the equations differs from M_b in the
    /// tip's two rows only, so its factor is this one with those rows redone
    /// ([`BandCholesky::with_last_rows`]). `None` for a massless beam (one element, `m` =
    /// 0).
    mass_factor: Option<BandCholesky>,
}

impl BeamBodyN {
    /// The model of `params`: `params.n_elements` elements (1..=32) and Rayleigh damping
    /// α [1/s], β [s] (each ≥ 0). A massless beam (m = 0) has one element only: the nodes
    /// inside it would have no inertia.
    pub fn new(params: Params) -> Result<Self, String> {
        let tip = BeamBody::new(params).map_err(|e| e.to_string())?;
        let Params { n_elements: n, damping_alpha: alpha, damping_beta: beta, .. } = params;
        if n > 1 && params.m == 0.0 {
            return Err(format!(
                "`n_elements` = {n} needs a beam with mass (`m` > 0): the nodes inside a \
                 massless beam have no inertia; use n_elements = 1 for m = 0"
            ));
        }
        let beam = Elements::new(n, params.l, params.ei, params.m);
        let mass_factor = beam.mass.cholesky();
        let mut model =
            Self { params, beam, damping: None, tip, rayleigh: (alpha, beta), mass_factor };
        let zeta = params.damping_ratio;
        if zeta > 0.0 {
            if alpha != 0.0 || beta != 0.0 {
                return Err(format!(
                    "`damping_ratio` = {zeta:?} sets the damping, and so do `damping_alpha` = \
                     {alpha:?} and `damping_beta` = {beta:?}: give either the ratio or alpha and \
                     beta"
                ));
            }
            model.rayleigh = model.rayleigh_for(zeta)?;
        }
        let (alpha, beta) = model.rayleigh;
        model.damping = (alpha != 0.0 || beta != 0.0).then(|| {
            let b = &model.beam;
            Band::zeros(b.dofs()).plus_scaled(alpha, &b.mass).plus_scaled(beta, &b.stiffness)
        });
        Ok(model)
    }

    /// Rayleigh's α and β that give the beam's own first two modes (the cantilever alone,
    /// without the body: K φ = ω² M_b φ) the damping ratio ζ: ζ_k = ½(α/ω_k + βω_k) at
    /// k = 1, 2, so α = 2ζω1ω2/(ω1 + ω2) and β = 2ζ/(ω1 + ω2) (A. K. Chopra, *Dynamics of
    /// Structures*, 4th ed., §11.4.1). Damping is the beam's material's; the body adds none,
    /// so the modes of beam and body have ratios of their own ([`modal_damping`]).
    ///
    /// [`modal_damping`]: Self::modal_damping
    fn rayleigh_for(&self, zeta: f64) -> Result<(f64, f64), String> {
        let n = self.dofs();
        let dense = |b: &Band| DMatrix::from_fn(n, n, |i, j| b.get(i, j));
        let omega2 = dense(&self.beam.mass)
            .cholesky()
            .and_then(|ch| ch.l().try_inverse())
            .map(|linv| {
                let k = dense(&self.beam.stiffness);
                let mut w2: Vec<f64> = (&linv * k * linv.transpose())
                    .symmetric_eigenvalues()
                    .iter()
                    .copied()
                    .collect();
                w2.sort_by(f64::total_cmp);
                w2
            })
            .ok_or_else(|| {
                format!("`damping_ratio` = {zeta:?} needs a beam with mass (`m` > 0)")
            })?;
        let (w1, w2) = (omega2[0].sqrt(), omega2[1].sqrt());
        Ok((2.0 * zeta * w1 * w2 / (w1 + w2), 2.0 * zeta / (w1 + w2)))
    }

    /// The damping ratio of each mode at rest at a held φ, ascending in frequency:
    /// ζ_k = φ_kᵀDφ_k/(2ω_k) for φ_k of unit modal mass, the body's inertia included (the
    /// ratio of the mode's own decay when the modes' coupling through D is small). Zero
    /// without damping; `None` where [`modes`](Self::modes) has none.
    pub fn modal_damping(&self, phi_fixed: f64) -> Option<Vec<f64>> {
        let (_, omega2, shapes) = self.mode_shapes(phi_fixed)?;
        Some(
            omega2
                .iter()
                .enumerate()
                .map(|(k, w2)| {
                    let shape: Vec<f64> = shapes.column(k).iter().copied().collect();
                    let d = self.damping.as_ref().map_or(0.0, |d| d.form(&shape, &shape));
                    d / (2.0 * w2.abs().sqrt())
                })
                .collect(),
        )
    }

    /// D = αM_b + βK, `None` without damping.
    pub(super) fn damping_band(&self) -> Option<&Band> {
        self.damping.as_ref()
    }

    /// Rayleigh's (α [1/s], β [s]) in use: as given, or from `damping_ratio`.
    pub fn rayleigh(&self) -> (f64, f64) {
        self.rayleigh
    }

    /// The tip's deflection and slope (v1, ϑ1) at q: its coordinates.
    pub fn tip_values(&self, q: &[f64]) -> (f64, f64) {
        let t = self.beam.tip();
        (q[t], q[t + 1])
    }

    /// The number of coordinates, 2n.
    pub fn dofs(&self) -> usize {
        self.beam.dofs()
    }

    /// The tip's axial displacement u1 = −½qᵀGq and its rate −(Gq)ᵀq̇.
    pub fn u1(&self, q: &[f64], qd: &[f64]) -> (f64, f64) {
        let gq = self.beam.g.mul(q);
        let dot: f64 = gq.iter().zip(qd).map(|(a, b)| a * b).sum();
        let u = gq.iter().zip(q).map(|(a, b)| a * b).sum::<f64>();
        (-0.5 * u, -dot)
    }

    /// −K q − D q̇ into `f`.
    pub(super) fn elastic_into(&self, q: &[f64], qd: &[f64], f: &mut [f64]) {
        self.restoring_into(q, qd, f);
        f.iter_mut().for_each(|f| *f = -*f);
    }

    /// Kq + Dq̇ into `f`: the negative of [`elastic_into`](Self::elastic_into)'s.
    pub(super) fn restoring_into(&self, q: &[f64], qd: &[f64], f: &mut [f64]) {
        self.beam.stiffness.mul_into(q, f);
        if let Some(d) = &self.damping {
            let mut dq = [0.0; MAX_DOFS];
            let dq = &mut dq[..qd.len()];
            d.mul_into(qd, dq);
            f.iter_mut().zip(dq.iter()).for_each(|(f, d)| *f += d);
        }
    }

    /// The reduced equations M q̈ = F at (q, q̇), into the caller's buffers: Gq into `gq`,
    /// a into `a` and F into `f`; returns the body's tip block of B ([`solve_b`]) and
    /// q̇ᵀGq̇. M is B plus the rank-one M2·a aᵀ (the module's notes).
    ///
    /// [`solve_b`]: Self::solve_b
    fn assemble_into(
        &self,
        phi: &Phi,
        q: &[f64],
        qd: &[f64],
        gq: &mut [f64],
        a: &mut [f64],
        f: &mut [f64],
    ) -> ([f64; 3], f64) {
        let Params { m2, j_c, r, g: grav, .. } = self.params;
        let t = self.beam.tip();
        let (s, c) = math::sin_cos(q[t + 1] + phi.phi);
        let dth = qd[t + 1] + phi.dphi;
        self.beam.g.mul_into(q, gq);
        let w = self.beam.g.form(qd, qd);
        let ax = -w - r * c * dth * dth - r * s * phi.ddphi - grav;
        let ay = -r * s * dth * dth + r * c * phi.ddphi;
        // B = M_b + M2 A_yA_yᵀ + J_C e_ϑe_ϑᵀ on the tip's block.
        let tip = [m2, m2 * r * c, m2 * r * r * c * c + j_c];
        // F = −Kq − Dq̇ − M2 (A_x a_x + A_y a_y) − J_C φ″ e_ϑ, with A_x = −a.
        a.copy_from_slice(gq);
        a[t + 1] += r * s;
        self.elastic_into(q, qd, f);
        for (f, a) in f.iter_mut().zip(a.iter()) {
            *f += m2 * a * ax;
        }
        f[t] -= m2 * ay;
        f[t + 1] -= m2 * r * c * ay + j_c * phi.ddphi;
        (tip, w)
    }

    /// [`assemble_into`](Self::assemble_into) into new vectors (off the integrator's path).
    fn assemble(&self, phi: &Phi, q: &[f64], qd: &[f64]) -> Assembled {
        let n = q.len();
        let (mut gq, mut a, mut f) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let (tip, _) = self.assemble_into(phi, q, qd, &mut gq, &mut a, &mut f);
        Assembled { tip, a, f }
    }

    /// B = M_b with the body's `tip` entries added at (t, t), (t + 1, t), (t + 1, t + 1).
    fn tip_band(&self, tip: [f64; 3]) -> Band {
        let t = self.beam.tip();
        let mut b = self.beam.mass.clone();
        b.add(t, t, tip[0]);
        b.add(t + 1, t, tip[1]);
        b.add(t + 1, t + 1, tip[2]);
        b
    }

    /// Solves B x = f in place, and B z = a too if `a` is given, B = [`tip_band`](Self::tip_band)
    /// (`tip`). The tip's rows are the last two, so B's factor is M_b's with those two redone
    /// ([`BandCholesky::with_last_rows`], no allocation), bit for bit B's own. False if B is
    /// not positive definite.
    fn solve_b(&self, tip: [f64; 3], f: &mut [f64], a: Option<&mut [f64]>) -> bool {
        let t = self.beam.tip();
        debug_assert_eq!(t + 2, f.len());
        let (mut last, mut end) = (self.beam.mass.row(t), self.beam.mass.row(t + 1));
        last[0] += tip[0];
        end[1] += tip[1];
        end[0] += tip[2];
        // A massless beam has no M_b to factor: B's own factor then, its tip rows redone alike.
        let own;
        let head = match &self.mass_factor {
            Some(mass) => mass,
            None => match self.tip_band(tip).cholesky() {
                Some(factor) => {
                    own = factor;
                    &own
                }
                None => return false,
            },
        };
        let Some(chol) = head.with_last_rows([last, end]) else {
            return false;
        };
        match a {
            Some(a) => chol.solve2_in_place(f, a),
            None => chol.solve_in_place(f),
        }
        true
    }

    /// The reduced equations' accelerations q̈ into `out`, and the tip's axial acceleration
    /// ü1. NaN if the mass matrix is not positive definite. No allocation.
    pub fn reduced(&self, phi: &Phi, q: &[f64], qd: &[f64], out: &mut [f64]) -> f64 {
        let n = q.len();
        let (mut gq, mut a, mut z) = ([0.0; MAX_DOFS], [0.0; MAX_DOFS], [0.0; MAX_DOFS]);
        let (gq, a, z) = (&mut gq[..n], &mut a[..n], &mut z[..n]);
        let (tip, w) = self.assemble_into(phi, q, qd, gq, a, out);
        z.copy_from_slice(a);
        if !self.solve_b(tip, out, Some(z)) {
            out.fill(f64::NAN);
            return f64::NAN;
        }
        // (B + M2 a aᵀ)⁻¹F = x − z (M2 aᵀx) / (1 + M2 aᵀz)
        let m2 = self.params.m2;
        let k = m2 * dot(a, out) / (1.0 + m2 * dot(a, z));
        for (o, z) in out.iter_mut().zip(z.iter()) {
            *o -= z * k;
        }
        -dot(gq, out) - w
    }

    /// The linear equations' accelerations (eq. 16 generalised) into `out`. NaN if the mass
    /// matrix is not positive definite.
    pub fn linear(&self, phi: &Phi, q: &[f64], qd: &[f64], out: &mut [f64]) {
        let Params { m2, j_c, r, g: grav, .. } = self.params;
        let t = self.beam.tip();
        let (s0, c0) = math::sin_cos(phi.phi);
        let (w, ddphi) = (phi.dphi, phi.ddphi);
        let (th, dth) = (q[t + 1], qd[t + 1]);
        // (C̈ − g e_x) at rest and its first-order change through θ and θ̇.
        let (a0x, a0y) =
            (-r * c0 * w * w - r * s0 * ddphi - grav, -r * s0 * w * w + r * c0 * ddphi);
        let dax = r * s0 * w * w * th - 2.0 * r * c0 * w * dth - r * c0 * ddphi * th;
        let day = -r * c0 * w * w * th - 2.0 * r * s0 * w * dth - r * s0 * ddphi * th;
        let tip = [m2, m2 * r * c0, m2 * r * r + j_c];
        // −M2 [A0ᵀ(a0 + da) + dAᵀ a0], A0_x = −r s0 e_ϑ, A0_y = e_v + r c0 e_ϑ,
        // dA_x = −Gq − r c0 ϑ e_ϑ, dA_y = −r s0 ϑ e_ϑ.
        let mut gq = [0.0; MAX_DOFS];
        let gq = &mut gq[..q.len()];
        self.beam.g.mul_into(q, gq);
        let f = out;
        self.elastic_into(q, qd, f);
        for (f, g) in f.iter_mut().zip(gq.iter()) {
            *f += m2 * g * a0x;
        }
        f[t] -= m2 * (a0y + day);
        f[t + 1] -= m2
            * (-r * s0 * (a0x + dax) + r * c0 * (a0y + day)
                - r * c0 * th * a0x
                - r * s0 * th * a0y)
            + j_c * ddphi;
        if !self.solve_b(tip, f, None) {
            f.fill(f64::NAN);
        }
    }

    /// The generalised force F(q) at rest (q̇ = 0) with the body held at `phi_fixed`.
    fn force_at_rest(&self, phi_fixed: f64, q: &DVector<f64>) -> DVector<f64> {
        let held = Phi { phi: phi_fixed, ..Phi::default() };
        let zero = vec![0.0; q.len()];
        DVector::from_vec(self.assemble(&held, q.as_slice(), &zero).f)
    }

    /// The linear equations' accelerations at rest at a held φ: zero where their force is.
    fn linear_at_rest(&self, phi_fixed: f64, q: &DVector<f64>) -> DVector<f64> {
        let held = Phi { phi: phi_fixed, ..Phi::default() };
        let zero = vec![0.0; q.len()];
        let mut acc = vec![0.0; q.len()];
        self.linear(&held, q.as_slice(), &zero, &mut acc);
        DVector::from_vec(acc)
    }

    /// The tangent stiffness −∂F/∂q at rest.
    fn tangent_stiffness(&self, phi_fixed: f64, q: &DVector<f64>) -> DMatrix<f64> {
        negative_jacobian(|q| self.force_at_rest(phi_fixed, q), q)
    }

    /// The static equilibrium q at a held φ, F(q, 0) = 0 (of the linear equations with
    /// `linear`).
    pub fn equilibrium(&self, phi_fixed: f64, linear: bool) -> Option<DVector<f64>> {
        if linear {
            rest(self.dofs(), |q| self.linear_at_rest(phi_fixed, q))
        } else {
            rest(self.dofs(), |q| self.force_at_rest(phi_fixed, q))
        }
    }

    /// Squared angular frequencies ω² [rad²/s²], ascending, of the small oscillations about
    /// the static equilibrium at a held φ, with that equilibrium; negative means unstable.
    /// `None` if there is no equilibrium or the mass matrix is not positive definite.
    pub fn modes(&self, phi_fixed: f64) -> Option<(DVector<f64>, Vec<f64>)> {
        let (q, omega2, _) = self.mode_shapes(phi_fixed)?;
        Some((q, omega2))
    }

    /// [`modes`](Self::modes) with the shapes: column k is mode k, normalised to unit modal
    /// mass (φ_kᵀMφ_k = 1).
    fn mode_shapes(&self, phi_fixed: f64) -> Option<(DVector<f64>, Vec<f64>, DMatrix<f64>)> {
        let q = self.equilibrium(phi_fixed, false)?;
        let held = Phi { phi: phi_fixed, ..Phi::default() };
        let zero = vec![0.0; q.len()];
        let Assembled { tip, a, .. } = self.assemble(&held, q.as_slice(), &zero);
        let b = self.tip_band(tip);
        let n = q.len();
        let m2 = self.params.m2;
        let mass = DMatrix::from_fn(n, n, |i, j| b.get(i, j) + m2 * a[i] * a[j]);
        let kt = self.tangent_stiffness(phi_fixed, &q);
        let (omega2, shapes) = small_oscillations(mass, &kt)?;
        Some((q, omega2, shapes))
    }

    /// The beam's kinetic and strain energies, ½q̇ᵀM_b q̇ and ½qᵀKq [J].
    pub fn beam_energy(&self, q: &[f64], qd: &[f64]) -> (f64, f64) {
        (0.5 * self.beam.mass.form(qd, qd), 0.5 * self.beam.stiffness.form(q, q))
    }
}

/// The q of `n` coordinates where `r` vanishes, by Newton's method from the straight beam, to a
/// step of 1e-11 of the coordinates (the Jacobian by differences of a beam of many elements
/// limits it); `None` if it does not converge.
pub(super) fn rest(n: usize, r: impl Fn(&DVector<f64>) -> DVector<f64>) -> Option<DVector<f64>> {
    let mut q = DVector::zeros(n);
    for _ in 0..50 {
        let dq = negative_jacobian(&r, &q).lu().solve(&r(&q))?;
        q += &dq;
        if !q.iter().all(|x| x.is_finite()) {
            return None;
        }
        if dq.norm() < 1e-11 * (1.0 + q.norm()) {
            return Some(q);
        }
    }
    None
}

/// Squared angular frequencies, ascending, and the mass-normalised shapes (columns) of the
/// small oscillations M ẍ + K_t x = 0. M⁻¹K_t is similar to L⁻¹K_t L⁻ᵀ with M = LLᵀ: a
/// symmetric eigenproblem (K_t symmetrised), whose unit eigenvectors y give the shapes L⁻ᵀy.
/// `None` if M is not positive definite.
pub(super) fn small_oscillations(
    mass: DMatrix<f64>,
    kt: &DMatrix<f64>,
) -> Option<(Vec<f64>, DMatrix<f64>)> {
    let n = mass.nrows();
    let linv = mass.cholesky()?.l().try_inverse()?;
    let sym = &linv * (kt + kt.transpose()) * 0.5 * linv.transpose();
    let eigen = sym.symmetric_eigen();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
    let omega2 = order.iter().map(|&k| eigen.eigenvalues[k]).collect();
    let shapes =
        DMatrix::from_fn(n, n, |i, k| (linv.transpose() * eigen.eigenvectors.column(order[k]))[i]);
    Some((omega2, shapes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    fn phi() -> Phi {
        Phi { phi: 1.1, dphi: -2.3, ddphi: 7.0 }
    }

    /// With one element the equations are the paper's (`dynamics.rs`), to round-off.
    #[test]
    fn one_element_is_the_paper_s_model() {
        let params = Params::default();
        let n1 = BeamBodyN::new(params).unwrap();
        let paper = BeamBody::new(params).unwrap();
        let (q, qd) = ([0.21, -0.13], [0.7, 1.9]);
        for linear in [false, true] {
            let mut acc = [0.0; 2];
            if linear {
                n1.linear(&phi(), &q, &qd, &mut acc);
            } else {
                n1.reduced(&phi(), &q, &qd, &mut acc);
            }
            let want = paper.two_dof_accel(linear, &phi(), Vector2::from(q), Vector2::from(qd));
            for k in 0..2 {
                assert!((acc[k] - want[k]).abs() <= 1e-12 * want.norm(), "{linear} {acc:?} {want}");
            }
        }
    }

    /// The accelerations satisfy Lagrange's equations of the energies: the residual
    /// d/dt ∂L/∂q̇ − ∂L/∂q + Dq̇, with the derivatives of L = T − Π taken by central
    /// differences of the energy functions along the motion, vanishes.
    #[test]
    fn accelerations_satisfy_lagrange_s_equations_of_the_energies() {
        let params =
            Params { n_elements: 4, damping_alpha: 0.3, damping_beta: 2e-3, ..Params::default() };
        let model = BeamBodyN::new(params).unwrap();
        let n = model.dofs();
        // A smooth deflection and rate (cubics in x, which the elements represent exactly):
        // the accelerations stay of the order of the slow modes', whose third time
        // derivatives the differences in time below can take.
        let nodal = |a: f64, b: f64| -> Vec<f64> {
            let l = params.l;
            (1..=n / 2)
                .flat_map(|k| {
                    let x = model.beam.l * k as f64 / (n / 2) as f64 / l;
                    [a * x * x + b * x * x * x, (2.0 * a * x + 3.0 * b * x * x) / l]
                })
                .collect()
        };
        let (q, qd) = (nodal(0.05, 0.02), nodal(0.4, -0.1));
        let ph = phi();
        let mut qdd = vec![0.0; n];
        model.reduced(&ph, &q, &qd, &mut qdd);
        let Params { m2, j_c, r, g, .. } = params;
        let lagrangian = |q: &[f64], qd: &[f64], phi: &Phi| {
            let (t1, p1) = model.beam_energy(q, qd);
            let (u, du) = model.u1(q, qd);
            let t = model.beam.tip();
            let th = q[t + 1] + phi.phi;
            let dth = qd[t + 1] + phi.dphi;
            let (s, c) = math::sin_cos(th);
            let vc = (du - r * s * dth, qd[t] + r * c * dth);
            let t2 = 0.5 * m2 * (vc.0 * vc.0 + vc.1 * vc.1) + 0.5 * j_c * dth * dth;
            let p2 = -m2 * g * (u + r * c);
            t1 + t2 - p1 - p2
        };
        // The state along the motion at time τ (second order in τ).
        let at = |tau: f64| {
            let qs: Vec<f64> =
                (0..n).map(|k| q[k] + qd[k] * tau + 0.5 * qdd[k] * tau * tau).collect();
            let qds: Vec<f64> = (0..n).map(|k| qd[k] + qdd[k] * tau).collect();
            let ps = Phi {
                phi: ph.phi + ph.dphi * tau + 0.5 * ph.ddphi * tau * tau,
                dphi: ph.dphi + ph.ddphi * tau,
                ddphi: ph.ddphi,
            };
            (qs, qds, ps)
        };
        let d = model.damping.as_ref().map_or(vec![0.0; n], |d| d.mul(&qd));
        let (eps, tau) = (1e-6, 1e-4);
        for i in 0..n {
            let dl_dqd = |tau: f64| {
                let (qs, mut qds, ps) = at(tau);
                qds[i] += eps;
                let plus = lagrangian(&qs, &qds, &ps);
                qds[i] -= 2.0 * eps;
                (plus - lagrangian(&qs, &qds, &ps)) / (2.0 * eps)
            };
            let ddt = (dl_dqd(tau) - dl_dqd(-tau)) / (2.0 * tau);
            let (mut qs, qds, ps) = at(0.0);
            qs[i] += eps;
            let plus = lagrangian(&qs, &qds, &ps);
            qs[i] -= 2.0 * eps;
            let dl_dq = (plus - lagrangian(&qs, &qds, &ps)) / (2.0 * eps);
            let residual = ddt - dl_dq + d[i];
            let scale = model.beam.stiffness.mul(&q)[i].abs() + m2 * g;
            assert!(residual.abs() < 1e-6 * scale, "row {i}: residual {residual}");
        }
    }

    /// With one element the modes are the paper's model's; with more, the frequencies fall
    /// towards the continuum's from above (Rayleigh-Ritz), and the first two at φ = 0 are
    /// within 0.1 % of the continuum's 3.514470 and 33.424625 rad/s with 8 elements
    /// (tests/python/continuum.py, an independent derivation).
    #[test]
    fn modes_are_the_paper_s_for_one_element_and_fall_towards_the_continuum() {
        let p = Params::default();
        for phi in [0.0, 1.2, std::f64::consts::PI] {
            let (_, w2) = BeamBodyN::new(p).unwrap().modes(phi).unwrap();
            let want = BeamBody::new(p).unwrap().modes(phi).omega2;
            for k in 0..2 {
                assert!((w2[k] - want[k]).abs() <= 1e-7 * want[k].abs(), "{phi}: {w2:?} {want:?}");
            }
        }
        let mut last = [f64::INFINITY; 2];
        for n in [1, 2, 4, 8] {
            let (_, w2) =
                BeamBodyN::new(Params { n_elements: n, ..p }).unwrap().modes(0.0).unwrap();
            let w = [w2[0].sqrt(), w2[1].sqrt()];
            assert!(w[0] < last[0] * (1.0 + 1e-9) && w[1] < last[1] * (1.0 + 1e-9), "{n}: {w:?}");
            last = w;
        }
        let continuum = [3.514470, 33.424625];
        for k in 0..2 {
            assert!(last[k] >= continuum[k] && last[k] < continuum[k] * 1.001, "{last:?}");
        }
        // The most elements, with the beam bent by the body at π/2: the equilibrium is found.
        let many = BeamBodyN::new(Params { n_elements: 32, ..p }).unwrap();
        let (q, w2) = many.modes(std::f64::consts::FRAC_PI_2).expect("an equilibrium at pi/2");
        assert!(q[62] < -0.14 && w2[0] > 0.0, "{} {w2:?}", q[62]);
    }

    /// The static equilibria of one element are the paper's model's, of the reduced and of the
    /// linear equations (residual_v1 of a study is measured from them); with more elements
    /// they move by the elements' error.
    #[test]
    fn equilibria_of_one_element_are_the_paper_s() {
        let p = Params::default();
        let paper = BeamBody::new(p).unwrap();
        for linear in [false, true] {
            for phi in [0.4, std::f64::consts::FRAC_PI_2, 2.5] {
                let q = BeamBodyN::new(p).unwrap().equilibrium(phi, linear).unwrap();
                let (v, th) = paper.equilibrium(phi, linear).unwrap();
                assert!((q[0] - v).abs() < 1e-10 && (q[1] - th).abs() < 1e-10, "{linear} {phi}");
                let four = BeamBodyN::new(Params { n_elements: 4, ..p }).unwrap();
                let q4 = four.equilibrium(phi, linear).unwrap();
                assert!((q4[6] - v).abs() < 1e-3 * v.abs() && q4[6] != v, "{linear} {phi}");
            }
        }
    }

    #[test]
    fn out_of_range_counts_and_damping_are_refused_naming_the_setting() {
        let p = Params::default();
        for n in [0, 33] {
            let e = BeamBodyN::new(Params { n_elements: n, ..p }).unwrap_err();
            assert!(e.contains("n_elements") && e.contains("32"), "{e}");
        }
        let e = BeamBodyN::new(Params { damping_alpha: -1.0, ..p }).unwrap_err();
        assert!(e.contains("damping_alpha"), "{e}");
        let e = BeamBodyN::new(Params { damping_beta: -1e-3, ..p }).unwrap_err();
        assert!(e.contains("damping_beta"), "{e}");
        let e = BeamBodyN::new(Params { n_elements: 2, m: 0.0, ..p }).unwrap_err();
        assert!(e.contains("n_elements") && e.contains("`m`"), "{e}");
    }
}
