//! Equations of motion, derived from the energies (paper eq. 10–13).
//!
//! Generalised coordinates q = (v1, ϑ1). The body's centre of mass is
//! C = (l + u_h + r cos θ, v1 + r sin θ), θ = ϑ1 + φ, where u_h is the hinge's axial
//! displacement: u_h = u1(q) when the constraint (21) is eliminated, u_h = u2 in the DAE.
//! With T2 = ½M2|Ċ|² + ½J_C θ̇² and Π2 = −M2 g (u_h + r cos θ), Lagrange's equations read
//!
//!   M_b q̈ + K q + M2 J_Cᵀ (C̈ − g e_x) + J_C θ̈ e_ϑ = 0,
//!
//! with J_C = ∂C/∂q (the identity d/dt ∂T/∂q̇ − ∂T/∂q = M2 J_Cᵀ C̈ for T = ½M2|Ċ|²) and
//! C̈ = J_C q̈ + b, b the velocity and φ'' terms. The Python oracle re-derives all of this
//! symbolically from the energies and checks the residuals below at random states.

use super::differences::negative_jacobian;
use super::kinematics::{pq, u1_accel_bias};
use super::params::{ParamError, Params};
use super::phi::Phi;
use crate::math;
use nalgebra::{DVector, Matrix2, Matrix3, Vector2, Vector3};
use std::f64::consts::PI;

/// The model with its Ritz coefficients (paper eq. 10–11) computed once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BeamBody {
    pub params: Params,
    /// Beam mass matrix M_b = [[m_vv, m_vϑ], [m_vϑ, m_ϑϑ]].
    mb: Matrix2<f64>,
    /// Beam stiffness K = [[k_vv, k_vϑ], [k_vϑ, k_ϑϑ]].
    k: Matrix2<f64>,
    /// Body inertia about the hinge, J2 = J_C + M2 r².
    j2: f64,
}

/// Hinge reactions in the paper's sign convention (eq. 18–19): the body exerts the force
/// (N, P) [N] on the beam tip, along x and y, and the moment M [N·m] on the tip section. The
/// beam exerts −N, −P, −M on the body; −M is the torque the drive applies to the body in the
/// sense of increasing φ.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reactions {
    pub n: f64,
    pub p: f64,
    pub m: f64,
}

/// Small oscillations about the static equilibrium at a fixed φ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Modes {
    /// The fixed body angle φ [rad].
    pub phi: f64,
    /// Static equilibrium (v1, ϑ1) [m, rad].
    pub equilibrium: (f64, f64),
    /// Squared angular frequencies ω², ascending [rad²/s²]; negative means unstable.
    pub omega2: [f64; 2],
}

impl Modes {
    /// Periods 2π/ω [s]; `None` for a non-oscillatory (unstable) mode.
    pub fn periods(&self) -> [Option<f64>; 2] {
        self.omega2.map(|w2| (w2 > 0.0).then(|| 2.0 * PI / w2.sqrt()))
    }
}

/// sin θ, cos θ and θ̇ of the body, θ = ϑ1 + φ.
fn body_angle(phi: &Phi, theta1: f64, dtheta1: f64) -> (f64, f64, f64) {
    let (s, c) = math::sin_cos(theta1 + phi.phi);
    (s, c, dtheta1 + phi.dphi)
}

impl BeamBody {
    /// The model, after checking the parameter ranges.
    pub fn new(params: Params) -> Result<Self, ParamError> {
        params.validate()?;
        let Params { l, ei, m, m2, j_c, r, .. } = params;
        let mb = Matrix2::new(
            13.0 * m * l / 35.0,
            -11.0 * m * l * l / 210.0,
            -11.0 * m * l * l / 210.0,
            m * math::powi(l, 3) / 105.0,
        );
        let k = Matrix2::new(
            12.0 * ei / math::powi(l, 3),
            -6.0 * ei / (l * l),
            -6.0 * ei / (l * l),
            4.0 * ei / l,
        );
        Ok(Self { params, mb, k, j2: j_c + m2 * r * r })
    }

    /// Checks that the mass matrix of (15) is positive definite at the given start; the
    /// error says why not in the parameters' words.
    pub fn check_start(&self, phi: f64, v1: f64, theta1: f64) -> Result<(), String> {
        let at = Phi { phi, ..Phi::default() };
        let (m, _) = self.reduced(&at, Vector2::new(v1, theta1), Vector2::zeros());
        let scale = m[(0, 0)] * m[(1, 1)];
        if m[(0, 0)] > 0.0 && m.determinant() > 1e-12 * scale {
            return Ok(());
        }
        let Params { m: mass, j_c, r, .. } = self.params;
        Err(format!(
            "the equations of motion are singular at the start (their mass matrix is not \
             positive definite): the rotation theta1 of a massless beam (m = {mass:?}) has no \
             inertia unless the body has some about the hinge (J_C = {j_c:?} > 0, or its \
             centre of mass off the beam's axis: r*sin(phi) != 0 with r = {r:?}, phi = {phi:?} \
             at the start)"
        ))
    }

    /// ∂C/∂q: rows x, y; columns v1, ϑ1.
    fn jc(&self, q: Vector2<f64>, s: f64, c: f64) -> Matrix2<f64> {
        let Params { l, r, .. } = self.params;
        let (p, qq) = pq(l, q[0], q[1]);
        Matrix2::new(-p, -l * qq - r * s, 1.0, r * c)
    }

    /// The mass matrix M_b + M2·J_Cᵀ·J_C + J_C·e_ϑ·e_ϑᵀ for the Jacobian `jc` = ∂C/∂q.
    fn mass(&self, jc: &Matrix2<f64>) -> Matrix2<f64> {
        let mut mass = self.mb + jc.transpose() * jc * self.params.m2;
        mass[(1, 1)] += self.params.j_c;
        mass
    }

    /// Eq. (15), dimensional: mass matrix M(q) and right-hand side F(q, q̇, t) such that
    /// M q̈ = F.
    pub fn reduced(
        &self,
        phi: &Phi,
        q: Vector2<f64>,
        qd: Vector2<f64>,
    ) -> (Matrix2<f64>, Vector2<f64>) {
        let Params { l, m2, j_c, r, g, .. } = self.params;
        let (s, c, dth) = body_angle(phi, q[1], qd[1]);
        let jc = self.jc(q, s, c);
        let w = u1_accel_bias(l, qd[0], qd[1]);
        // C̈ − g e_x = J_C q̈ + a, with a:
        let a = Vector2::new(
            -w - r * c * dth * dth - r * s * phi.ddphi - g,
            -r * s * dth * dth + r * c * phi.ddphi,
        );
        let mass = self.mass(&jc);
        let mut rhs = -(self.k * q) - jc.transpose() * a * m2;
        rhs[1] -= j_c * phi.ddphi;
        (mass, rhs)
    }

    /// Eq. (16): the first-order Taylor expansion of eq. (15) in (q, q̇, q̈) about the
    /// undeformed beam at rest, with φ, φ', φ'' kept exact. Returns (M0, F) with M0 q̈ = F.
    pub fn linear(
        &self,
        phi: &Phi,
        q: Vector2<f64>,
        qd: Vector2<f64>,
    ) -> (Matrix2<f64>, Vector2<f64>) {
        let Params { l, m2, j_c, r, g, .. } = self.params;
        let (s0, c0) = math::sin_cos(phi.phi);
        let (w, ddphi) = (phi.dphi, phi.ddphi);
        let (v1, th, dth) = (q[0], q[1], qd[1]);
        let jc0 = Matrix2::new(0.0, -r * s0, 1.0, r * c0);
        // (C̈ − g e_x) at q = q̇ = q̈ = 0 …
        let a0 =
            Vector2::new(-r * c0 * w * w - r * s0 * ddphi - g, -r * s0 * w * w + r * c0 * ddphi);
        // … its first-order change through θ = ϑ1 + φ and θ̇ = ϑ̇1 + φ' (w = O(q̇²) drops) …
        let da = Vector2::new(
            r * s0 * w * w * th - 2.0 * r * c0 * w * dth - r * c0 * ddphi * th,
            -r * c0 * w * w * th - 2.0 * r * s0 * w * dth - r * s0 * ddphi * th,
        );
        // … and the first-order change of J_C.
        let djc = Matrix2::new(
            -(1.2 * v1 / l - 0.1 * th),
            0.1 * v1 - (2.0 * l / 15.0) * th - r * c0 * th,
            0.0,
            -r * s0 * th,
        );
        let mass = self.mass(&jc0);
        let mut rhs = -(self.k * q) - (jc0.transpose() * (a0 + da) + djc.transpose() * a0) * m2;
        rhs[1] -= j_c * ddphi;
        (mass, rhs)
    }

    /// Eq. (20)+(21) with (21) differentiated twice, unknowns x = (v1, ϑ1, u2): rows 1–2 are
    /// the beam equations (18) with the reactions N, P, M of the body equations (19)
    /// substituted; row 3 is ü2 − d²u1/dt² = 0. Returns (A, b) with A ẍ = b.
    pub fn dae(
        &self,
        phi: &Phi,
        x: Vector3<f64>,
        xd: Vector3<f64>,
    ) -> (Matrix3<f64>, Vector3<f64>) {
        let Params { l, m2, r, g, .. } = self.params;
        let (s, c, dth) = body_angle(phi, x[1], xd[1]);
        let (p, qq) = pq(l, x[0], x[1]);
        let w = u1_accel_bias(l, xd[0], xd[1]);
        let kq = self.k * Vector2::new(x[0], x[1]);
        let (mb, j2) = (&self.mb, self.j2);
        // N = −M2 ü2 + M2 r s ϑ̈1 + n0 from (19), with the acceleration-free part n0.
        let n0 = m2 * (r * s * phi.ddphi + r * c * dth * dth + g);
        let a = Matrix3::new(
            mb[(0, 0)] + m2,
            mb[(0, 1)] + m2 * r * c + p * m2 * r * s,
            -p * m2,
            mb[(1, 0)] + m2 * r * c,
            mb[(1, 1)] + j2 + l * qq * m2 * r * s,
            -m2 * r * s - l * qq * m2,
            p,
            l * qq,
            1.0,
        );
        let b = Vector3::new(
            -kq[0] - m2 * r * c * phi.ddphi + m2 * r * s * dth * dth - p * n0,
            -kq[1] - j2 * phi.ddphi - m2 * g * r * s - l * qq * n0,
            -w,
        );
        (a, b)
    }

    /// Accelerations of (15) or (16): q̈ = M⁻¹F. NaN if M is singular.
    pub fn two_dof_accel(
        &self,
        linear: bool,
        phi: &Phi,
        q: Vector2<f64>,
        qd: Vector2<f64>,
    ) -> Vector2<f64> {
        let (m, f) = if linear { self.linear(phi, q, qd) } else { self.reduced(phi, q, qd) };
        // Cramer's rule with one division (an inverse would take four).
        let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
        if det == 0.0 {
            return Vector2::repeat(f64::NAN);
        }
        let inv_det = 1.0 / det;
        Vector2::new(
            (m[(1, 1)] * f[0] - m[(0, 1)] * f[1]) * inv_det,
            (m[(0, 0)] * f[1] - m[(1, 0)] * f[0]) * inv_det,
        )
    }

    /// Accelerations (v̈1, ϑ̈1, ü2) of the DAE. NaN if A is singular.
    pub fn dae_accel(&self, phi: &Phi, x: Vector3<f64>, xd: Vector3<f64>) -> Vector3<f64> {
        let (a, b) = self.dae(phi, x, xd);
        solve_constrained(a, b).unwrap_or(Vector3::repeat(f64::NAN))
    }

    /// The hinge reactions from the body equations (19), given the body's motion: the
    /// beam-tip state (ϑ1, ϑ̇1, ϑ̈1, v̈1) and the hinge's axial acceleration ẍ_h (ü1 or ü2).
    pub fn reactions(
        &self,
        phi: &Phi,
        theta1: f64,
        dtheta1: f64,
        ddtheta1: f64,
        ddv1: f64,
        ddx_h: f64,
    ) -> Reactions {
        let Params { m2, r, g, .. } = self.params;
        let (s, c, dth) = body_angle(phi, theta1, dtheta1);
        let ddth = ddtheta1 + phi.ddphi;
        Reactions {
            n: -m2 * (ddx_h - r * s * ddth - r * c * dth * dth - g),
            p: -m2 * (ddv1 + r * c * ddth - r * s * dth * dth),
            m: -(self.j2 * ddth + m2 * r * (-s * ddx_h + c * ddv1) + m2 * g * r * s),
        }
    }

    /// The beam's kinetic and strain energies T1 = ½q̇ᵀM_b q̇ and Π1 = ½qᵀKq [J].
    pub fn beam_energies(&self, q: Vector2<f64>, qd: Vector2<f64>) -> (f64, f64) {
        (0.5 * qd.dot(&(self.mb * qd)), 0.5 * q.dot(&(self.k * q)))
    }

    /// Total mechanical energy T1 + T2 + Π1 + Π2 [J], Π2 = −M2 g (u_h + r cos θ).
    pub fn energy(&self, phi: &Phi, q: Vector2<f64>, qd: Vector2<f64>, u_h: f64, du_h: f64) -> f64 {
        let (t1, p1) = self.beam_energies(q, qd);
        let (t2, p2) = self.body_energies(phi, q, qd, u_h, du_h);
        t1 + t2 + p1 + p2
    }

    /// The body's kinetic and potential energies T2 and Π2 [J] for the tip's (v1, ϑ1) = `q`,
    /// their rates `qd`, and the hinge's axial displacement and rate.
    pub fn body_energies(
        &self,
        phi: &Phi,
        q: Vector2<f64>,
        qd: Vector2<f64>,
        u_h: f64,
        du_h: f64,
    ) -> (f64, f64) {
        let Params { m2, j_c, r, g, .. } = self.params;
        let (s, c, dth) = body_angle(phi, q[1], qd[1]);
        let vc = Vector2::new(du_h - r * s * dth, qd[0] + r * c * dth);
        let t2 = 0.5 * m2 * vc.norm_squared() + 0.5 * j_c * dth * dth;
        let p2 = -m2 * g * (u_h + r * c);
        (t2, p2)
    }

    /// The buckling value of g < 0 (gravity reversed, compressing the beam along its axis)
    /// for the other parameters of `params`: where the lowest squared frequency about the
    /// equilibrium at φ = 0 ([`modes`](Self::modes)) crosses zero, by bisection to the
    /// resolution of f64. Below it in magnitude the straight beam is stable.
    pub fn buckling_g(params: Params) -> f64 {
        let omega2 = |g: f64| {
            let p = Params { g, ..params };
            BeamBody::new(p).map_or(f64::NAN, |m| m.modes(0.0).omega2[0])
        };
        let (mut lo, mut hi) = (0.0, -1.0);
        while omega2(hi) > 0.0 && hi > -1e12 {
            lo = hi;
            hi *= 2.0;
        }
        loop {
            let mid = 0.5 * (lo + hi);
            if mid == lo || mid == hi {
                return mid;
            }
            if omega2(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }

    /// The static equilibrium (v1, ϑ1) [m, rad] at a fixed φ: of (15) (which the DAE
    /// formulations share), or of (16) with `linear`. `None` if Newton's method did not
    /// converge.
    pub fn equilibrium(&self, phi_fixed: f64, linear: bool) -> Option<(f64, f64)> {
        let phi = Phi { phi: phi_fixed, ..Phi::default() };
        let (q, converged) = if linear {
            static_equilibrium(|q| self.linear(&phi, q, Vector2::zeros()).1)
        } else {
            static_equilibrium(|q| self.reduced(&phi, q, Vector2::zeros()).1)
        };
        converged.then_some((q[0], q[1]))
    }

    /// Natural frequencies of (15) linearised about its static equilibrium at a fixed φ.
    /// The equilibrium solves K q = M2 g J_C(q)ᵀ e_x by Newton's method.
    pub fn modes(&self, phi_fixed: f64) -> Modes {
        let phi = Phi { phi: phi_fixed, ..Phi::default() };
        let force = |q: Vector2<f64>| self.reduced(&phi, q, Vector2::zeros()).1;
        let (q, _) = static_equilibrium(force);
        let (mass, _) = self.reduced(&phi, q, Vector2::zeros());
        let kt = tangent_stiffness(force, q);
        // Symmetrise: M⁻¹K_t is similar to L⁻¹K_t L⁻ᵀ with M = LLᵀ.
        let omega2 = match mass.cholesky() {
            Some(ch) => {
                let linv = ch.l().try_inverse().unwrap_or_else(Matrix2::zeros);
                let sym = linv * (kt + kt.transpose()) * 0.5 * linv.transpose();
                let mut ev = sym.symmetric_eigenvalues();
                if ev[0] > ev[1] {
                    ev.swap_rows(0, 1);
                }
                [ev[0], ev[1]]
            }
            None => [f64::NAN; 2],
        };
        Modes { phi: phi_fixed, equilibrium: (q[0], q[1]), omega2 }
    }
}

/// The tangent stiffness −∂F/∂q at q ([`negative_jacobian`]'s differences).
fn tangent_stiffness(
    force: impl Fn(Vector2<f64>) -> Vector2<f64>,
    q: Vector2<f64>,
) -> Matrix2<f64> {
    let f =
        |x: &DVector<f64>| DVector::from_column_slice(force(Vector2::new(x[0], x[1])).as_slice());
    let k = negative_jacobian(f, &DVector::from_column_slice(q.as_slice()));
    Matrix2::from_column_slice(k.as_slice())
}

/// The q at rest where the generalised force vanishes, F(q, 0) = 0, by Newton's method from
/// q = 0 (the equilibria of this beam are near the undeformed state), and whether the
/// iteration converged (else the last iterate).
fn static_equilibrium(force: impl Fn(Vector2<f64>) -> Vector2<f64>) -> (Vector2<f64>, bool) {
    let mut q = Vector2::zeros();
    for _ in 0..50 {
        let Some(inv) = tangent_stiffness(&force, q).try_inverse() else {
            return (q, false);
        };
        let dq = inv * force(q);
        q += dq;
        if !q.iter().all(|x| x.is_finite()) {
            return (q, false);
        }
        if dq.norm() < 1e-14 * (1.0 + q.norm()) {
            return (q, true);
        }
    }
    (q, false)
}

/// x with A x = b for the DAE's A, whose last row is the constraint's, (c0, c1, 1): the
/// unit coefficient of ü2 is the pivot that eliminates ü2 from the first two rows, which
/// leaves the 2×2 Schur complement, the mass matrix of the reduced equations (15), symmetric
/// and positive definite for the physical parameters; it is solved by Cramer's rule with one
/// division, and ü2 follows from the last row. A 3×3 elimination with partial pivoting
/// (three pivots, three reciprocals on the chain) cost twice the instructions. `None` if
/// the complement is singular or not finite.
fn solve_constrained(a: Matrix3<f64>, b: Vector3<f64>) -> Option<Vector3<f64>> {
    debug_assert_eq!(a[(2, 2)], 1.0);
    let (c0, c1) = (a[(2, 0)], a[(2, 1)]);
    let (e0, e1) = (a[(0, 2)], a[(1, 2)]);
    let (m00, m01) = (a[(0, 0)] - e0 * c0, a[(0, 1)] - e0 * c1);
    let (m10, m11) = (a[(1, 0)] - e1 * c0, a[(1, 1)] - e1 * c1);
    let (f0, f1) = (b[0] - e0 * b[2], b[1] - e1 * b[2]);
    let det = m00 * m11 - m01 * m10;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let x0 = (m11 * f0 - m01 * f1) * inv_det;
    let x1 = (m00 * f1 - m10 * f0) * inv_det;
    Some(Vector3::new(x0, x1, b[2] - c0 * x0 - c1 * x1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::kinematics::u1;

    #[test]
    fn constrained_solve_matches_nalgebra_lu() {
        // The DAE's shape (last row (c0, c1, 1)): a saddle-like one, one with a tiny
        // constraint row, the model's own, and a singular one.
        let saddle = Matrix3::new(2.0, 0.3, 0.7, 0.3, 1.5, -2.5, 0.7, -2.5, 1.0);
        let tiny = Matrix3::new(30.0, 4.0, -1e-3, 4.0, 2.0, -5.0, 1e-4, 0.2, 1.0);
        let x = Vector3::new(-0.1, 0.05, 0.001);
        let xd = Vector3::new(0.3, -0.2, 0.01);
        let (own, _) = model().dae(&phi(), x, xd);
        let b = Vector3::new(1.0, -2.0, 0.5);
        for a in [saddle, tiny, own] {
            let (ours, lu) = (solve_constrained(a, b).unwrap(), a.lu().solve(&b).unwrap());
            assert!((ours - lu).norm() <= 1e-13 * lu.norm(), "{ours} vs {lu}");
            assert!((a * ours - b).norm() <= 1e-12 * b.norm());
        }
        // Rows 1 and 2 dependent once ü2 is eliminated.
        let singular = Matrix3::new(1.0, 2.0, 1.0, 2.0, 4.0, 2.0, 0.0, 0.0, 1.0);
        assert!(solve_constrained(singular, b).is_none());
        let mut nan = Matrix3::repeat(f64::NAN);
        nan[(2, 2)] = 1.0;
        assert!(solve_constrained(nan, b).is_none());
    }

    fn model() -> BeamBody {
        BeamBody::new(Params::default()).unwrap()
    }

    fn phi() -> Phi {
        Phi { phi: 1.1, dphi: -2.3, ddphi: 7.0 }
    }

    /// Substituting ü2 from the twice-differentiated constraint into the DAE's beam rows
    /// gives back eq. (15) (the paper's §3 remark).
    #[test]
    fn dae_reduces_to_eq15() {
        let bb = model();
        let (q, qd) = (Vector2::new(0.21, -0.13), Vector2::new(0.7, 1.9));
        let l = bb.params.l;
        let x = Vector3::new(q[0], q[1], u1(l, q[0], q[1]));
        let (p, qq) = pq(l, q[0], q[1]);
        let xd = Vector3::new(qd[0], qd[1], -p * qd[0] - l * qq * qd[1]);
        let acc = bb.dae_accel(&phi(), x, xd);
        let red = bb.two_dof_accel(false, &phi(), q, qd);
        assert!((acc.fixed_rows::<2>(0) - red).norm() < 1e-12 * red.norm());
    }

    /// The DAE rows equal (18) with N, P, M from (19), at arbitrary accelerations.
    #[test]
    fn dae_rows_are_beam_equations_with_body_reactions() {
        let bb = model();
        let (x, xd) = (Vector3::new(0.1, 0.2, -0.03), Vector3::new(-0.4, 0.9, 0.2));
        let xdd = Vector3::new(3.0, -5.0, 1.5);
        let (a, b) = bb.dae(&phi(), x, xd);
        let rows = a * xdd - b;
        let re = bb.reactions(&phi(), x[1], xd[1], xdd[1], xdd[0], xdd[2]);
        let (p, qq) = pq(bb.params.l, x[0], x[1]);
        let beam = bb.mb * Vector2::new(xdd[0], xdd[1]) + bb.k * Vector2::new(x[0], x[1]);
        assert!((rows[0] - (beam[0] + p * re.n - re.p)).abs() < 1e-10);
        assert!((rows[1] - (beam[1] + bb.params.l * qq * re.n - re.m)).abs() < 1e-10);
    }

    /// The linear model is the first-order part of the reduced one: their difference at
    /// amplitude ε is O(ε²).
    #[test]
    fn linear_is_first_order_part() {
        let bb = model();
        let residual = |lin: bool, e: f64| {
            let (q, qd, qdd) = (
                Vector2::new(0.3, -0.5) * e,
                Vector2::new(1.0, 2.0) * e,
                Vector2::new(-4.0, 3.0) * e,
            );
            let (m, f) = if lin { bb.linear(&phi(), q, qd) } else { bb.reduced(&phi(), q, qd) };
            m * qdd - f
        };
        let d1 = (residual(true, 1e-2) - residual(false, 1e-2)).norm();
        let d2 = (residual(true, 1e-3) - residual(false, 1e-3)).norm();
        let ratio = d1 / d2;
        assert!((ratio - 100.0).abs() < 5.0, "difference should scale as ε²: ratio {ratio}");
        assert!((residual(true, 0.0) - residual(false, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn periods_near_the_papers_estimate() {
        let bb = model();
        let modes = bb.modes(PI / 2.0);
        let t = modes.periods()[0].unwrap();
        assert!((1.0..2.5).contains(&t), "fundamental period {t}");
        assert!(modes.omega2[1] > modes.omega2[0]);
    }

    #[test]
    fn massless_point_body_is_rejected_at_phi_zero() {
        let p = Params { m: 0.0, j_c: 0.0, ..Params::default() };
        let bb = BeamBody::new(p).unwrap();
        let e = bb.check_start(0.0, 0.0, 0.0).unwrap_err();
        assert!(e.to_string().contains("positive definite"), "{e}");
        assert!(model().check_start(0.0, 0.0, 0.0).is_ok());
    }
}
