//! The geometrically exact beam (issue 28): the inextensible elastica in n elements with the
//! body hinged at its tip, valid at any rotation.
//!
//! **Field.** Arc length s ∈ [0, l]; the section angle α(s) = w′(s), with w the n cubic
//! Hermite elements of [`Elements`](super::Elements) and the same coordinates q = (w_1, α_1,
//! …, w_n, α_n): α is continuous and piecewise quadratic, α(0) = 0, α_i = α(s_i) and
//! ϑ1 = α_n. Its linearisation about the straight beam is the quadratic model's at the same n
//! (α′ = w″: the same K; the same mass at q = 0), so the two differ only by the nonlinearity
//! (docs/decisions.md, "The exact beam's field").
//!
//! **Discrete kinematics.** In each element the Gauss–Legendre points s_i (6 a element,
//! weights w_i) carry the positions r_i = R_e + h Σ_j A_ij e(α_j), e = (cos α, sin α), with
//! A the Gauss collocation matrix (A_ij = ∫₀^{c_i} ℓ_j, the Butcher matrix of the Gauss
//! method) and R_{e+1} = R_e + h Σ_j b_j e(α_j); the tip is r(l) = R_n = (l + u1, v1). r is
//! a function of q alone, so inextensibility holds with no constraint. The body's centre is
//! C = r(l) + r_C (cos θ, sin θ), θ = ϑ1 + φ.
//!
//! **Energies.** T = ½m Σ_i w_i |ṙ_i|² + ½M2|Ċ|² + ½J_C θ̇² (the beam's axial inertia
//! included), Π = ½qᵀKq − M2 g C_x [− m g Σ_i w_i x_i with the beam's weight], dissipation
//! ½q̇ᵀDq̇ with the quadratic model's D. Since every r_i is a function of q, Lagrange's
//! equations of this discrete T are d'Alembert's exactly:
//!
//!   R_k = m Σ_i w_i J_ik·(r̈_i − g_b e_x) + M2 ∂C/∂q_k·(C̈ − g e_x) + J_C θ̈ δ_{k,ϑ1}
//!         + (Kq + Dq̇)_k = 0,
//!
//! J_ik = ∂r_i/∂q_k = run(p N_k′)_i with p = (−sin α, cos α), r̈_i = run(p α̈ − e α̇²)_i. The
//! sum over i is taken by the transpose of the running integral (an adjoint sweep from the
//! tip), so R costs O(n). The mass matrix M = ∂R/∂q̈ is dense; it is assembled from the
//! structure of J (constant beyond each coordinate's two elements) in O(n²) and solved by
//! Cholesky. The tests check R against the energies, and tests/python/oracle_exact.py derives
//! the same model independently.
//!
//! 6 Gauss points an element put the residual within 1e-11, 7e-11 and 2e-9 of its limit for a
//! beam of 4 elements bent by 0.5, 1.5 and 3 rad at the tip (measured against 24 points with
//! the oracle; one element bent by 3 rad is 7e-7 off); the points are part of the
//! discretisation, and the energy of the discrete model is conserved exactly.

use super::dense::{cholesky_in_place, cholesky_solve};
use super::differences::negative_jacobian;
use super::dynamics_n::{rest, small_oscillations, BeamBodyN, MAX_ELEMENTS};
use super::elements::shape;
use super::params::Params;
use super::phi::Phi;
use crate::math;
use nalgebra::{DMatrix, DVector};

/// Gauss–Legendre points per element along s.
pub const GAUSS_POINTS: usize = 6;
const P: usize = GAUSS_POINTS;
const MAX_DOFS: usize = 2 * MAX_ELEMENTS;

/// The 6-point Gauss–Legendre rule on [−1, 1], the positive nodes with their weights
/// (Abramowitz & Stegun, *Handbook of Mathematical Functions*, Table 25.4).
const GAUSS_LEGENDRE_6: [(f64, f64); 3] = [
    (0.238_619_186_083_196_9, 0.467_913_934_572_691_05),
    (0.661_209_386_466_264_5, 0.360_761_573_048_138_6),
    (0.932_469_514_203_152, 0.171_324_492_379_170_35),
];

/// The rule on [0, 1]: nodes c, weights b and the collocation matrix A (A_ij = ∫₀^{c_i} ℓ_j
/// for the Lagrange polynomials ℓ_j of the nodes: exact for polynomials of degree < 6).
#[derive(Clone, Debug, PartialEq)]
struct Rule {
    c: [f64; P],
    b: [f64; P],
    a: [[f64; P]; P],
    /// d_j = Σ_i b_i A_ij and G_jk = Σ_i b_i A_ij A_ik: the running integral's adjoint
    /// composed with it, so the residual's two sweeps need one P×P product an element.
    d: [f64; P],
    g: [[f64; P]; P],
}

impl Rule {
    fn new() -> Self {
        let mut c = [0.0; P];
        let mut b = [0.0; P];
        for (k, (x, w)) in GAUSS_LEGENDRE_6.iter().enumerate() {
            c[2 - k] = 0.5 * (1.0 - x);
            c[3 + k] = 0.5 * (1.0 + x);
            b[2 - k] = 0.5 * w;
            b[3 + k] = 0.5 * w;
        }
        // Σ_j A_ij c_j^k = c_i^(k+1)/(k+1), k = 0..5: one Vandermonde system for every row.
        let v = DMatrix::from_fn(P, P, |k, j| math::powi(c[j], k as i32));
        let lu = v.lu();
        let mut a = [[0.0; P]; P];
        for (i, row) in a.iter_mut().enumerate() {
            let rhs = nalgebra::DVector::from_fn(P, |k, _| {
                math::powi(c[i], k as i32 + 1) / (k as f64 + 1.0)
            });
            let x = lu.solve(&rhs).expect("the Gauss nodes are distinct");
            row.iter_mut().zip(x.iter()).for_each(|(r, x)| *r = *x);
        }
        let d = std::array::from_fn(|j| (0..P).map(|i| b[i] * a[i][j]).sum());
        let g = std::array::from_fn(|j| {
            std::array::from_fn(|k| (0..P).map(|i| b[i] * a[i][j] * a[i][k]).sum())
        });
        Self { c, b, a, d, g }
    }
}

/// α's sine and cosine and its rate at one Gauss point.
#[derive(Clone, Copy, Debug, Default)]
struct Section {
    sin: f64,
    cos: f64,
    rate: f64,
}

/// [`Section`] at every Gauss point, element by element: n·P of them, on the heap (arrays for
/// the largest n, zeroed at every residual, were 15 % of a run's instructions at 8 elements).
struct Angles {
    at: Vec<Section>,
}

/// One element in the residual's sweep: f = p α̈ − e α̇² at its points (x, then y), the sum
/// of its point forces and its base's increment.
type ElementSweep = ([[f64; P]; 2], [f64; 2], [f64; 2]);

/// The exact beam with n elements and the body.
#[derive(Clone, Debug, PartialEq)]
pub struct ExactBeam {
    /// The quadratic model of the same parameters: K, D, the elements and the body's
    /// reactions, which the two share.
    pub quadratic: BeamBodyN,
    rule: Rule,
    /// ∂α/∂(w_a, α_a, w_b, α_b) at each Gauss point of an element.
    slope: [[f64; 4]; P],
    /// Gravity on the beam (`beam_gravity`), along +x: g or 0.
    g_beam: f64,
}

fn dot(u: &[f64], v: &[f64]) -> f64 {
    u.iter().zip(v).map(|(a, b)| a * b).sum()
}

/// Element e's four coordinates (w_a, α_a, w_b, α_b) of `q`; node 0 is clamped.
fn local(q: &[f64], e: usize) -> [f64; 4] {
    if e == 0 {
        [0.0, 0.0, q[0], q[1]]
    } else {
        [q[2 * e - 2], q[2 * e - 1], q[2 * e], q[2 * e + 1]]
    }
}

/// A Gauss point of the centreline: its arc length, its weight and its motion.
pub type GaussPoint = (f64, f64, PointMotion);

/// The motion of one point of the centreline: position, velocity and acceleration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointMotion {
    pub r: [f64; 2],
    pub v: [f64; 2],
    pub a: [f64; 2],
}

impl ExactBeam {
    /// The model of `params` (as [`BeamBodyN::new`]), with the beam's own weight if
    /// `params.beam_gravity`.
    pub fn new(params: Params) -> Result<Self, String> {
        let quadratic = BeamBodyN::new(params)?;
        if params.m == 0.0 {
            return Err("`beam` = exact needs a beam with mass (`m` > 0): its mass matrix is \
                        the beam's own, and a massless beam has none"
                .to_string());
        }
        let rule = Rule::new();
        let h = quadratic.beam.l / quadratic.beam.n as f64;
        let slope = rule.c.map(|c| shape(c, h)[1]);
        let g_beam = if params.beam_gravity { params.g } else { 0.0 };
        Ok(Self { quadratic, rule, slope, g_beam })
    }

    pub fn params(&self) -> &Params {
        &self.quadratic.params
    }

    fn n(&self) -> usize {
        self.quadratic.beam.n
    }

    fn h(&self) -> f64 {
        self.quadratic.beam.l / self.n() as f64
    }

    /// The number of coordinates, 2n.
    pub fn dofs(&self) -> usize {
        self.quadratic.dofs()
    }

    /// α at each Gauss point of element e for coordinates `q`.
    fn alpha(&self, q: &[f64], e: usize) -> [f64; P] {
        let l = local(q, e);
        let mut a = [0.0; P];
        for (a, g) in a.iter_mut().zip(&self.slope) {
            *a = g[0] * l[0] + g[1] * l[1] + g[2] * l[2] + g[3] * l[3];
        }
        a
    }

    fn angles(&self, q: &[f64], qd: &[f64]) -> Angles {
        let mut at = vec![Section::default(); self.n() * P];
        for (e, points) in at.chunks_exact_mut(P).enumerate() {
            self.element_angles(q, qd, e, points);
        }
        Angles { at }
    }

    /// Element e's [`Section`]s into `out` (P of them).
    fn element_angles(&self, q: &[f64], qd: &[f64], e: usize, out: &mut [Section]) {
        let (a, ad) = (self.alpha(q, e), self.alpha(qd, e));
        for (i, point) in out.iter_mut().enumerate() {
            let (sin, cos) = math::sin_cos(a[i]);
            *point = Section { sin, cos, rate: ad[i] };
        }
    }

    /// The generalised forces R(q, q̇, q̈) into `out` (the module's equations), zero on a
    /// motion; returns the tip's acceleration r̈(l). O(n).
    ///
    /// With f_j = p_j α̈_j − e_j α̇_j² at an element's points, r̈_i = R̈_e + h Σ_k A_ik f_k and
    /// the point forces F_i = m h b_i (r̈_i − g_b e_x), the adjoint sweep's
    /// B_j = h b_j L_e + h Σ_i A_ij F_i (L_e: the force of everything beyond the element) is
    /// h b_j L_e + m h² d_j (R̈_e − g_b e_x) + m h³ Σ_k G_jk f_k, and Σ_i F_i is
    /// m h (R̈_e − g_b e_x) + m h² Σ_k d_k f_k ([`Rule`]'s d and G).
    fn residual_with(
        &self,
        ang: &Angles,
        phi: &Phi,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        out: &mut [f64],
    ) -> [f64; 2] {
        let Params { m, m2, j_c, r, g, .. } = *self.params();
        let (n, h) = (self.n(), self.h());
        let Rule { b, d, g: gm, .. } = &self.rule;
        let (mh, mh2, mh3) = (m * h, m * h * h, m * h * h * h);
        // Root to tip: each element's f, the sum of its point forces and its base's increment
        // h Σ b_j f_j, pushed (a zeroed buffer for the largest n costs more than the
        // allocation); their totals.
        let mut elements: Vec<ElementSweep> = Vec::with_capacity(n);
        let mut base = [0.0; 2];
        let mut total = [0.0; 2];
        for e in 0..n {
            let [fx, fy] = self.point_accelerations(ang, qdd, e);
            let sum = [
                mh * (base[0] - self.g_beam) + mh2 * dot(d, &fx),
                mh * base[1] + mh2 * dot(d, &fy),
            ];
            let step = [h * dot(b, &fx), h * dot(b, &fy)];
            elements.push(([fx, fy], sum, step));
            total[0] += sum[0];
            total[1] += sum[1];
            base[0] += step[0];
            base[1] += step[1];
        }
        let t = 2 * n - 2;
        let (st, ct) = math::sin_cos(q[t + 1] + phi.phi);
        let (dth, ddth) = (qd[t + 1] + phi.dphi, qdd[t + 1] + phi.ddphi);
        // C̈ − g e_x, times M2: the force the tip carries to the body.
        let tip = [
            m2 * (base[0] - r * st * ddth - r * ct * dth * dth - g),
            m2 * (base[1] + r * ct * ddth - r * st * dth * dth),
        ];
        self.quadratic.restoring_into(q, qd, out);
        // Root to tip again, L_e = tip + Σ F − (the forces up to e's end), and
        // R_k = Σ_j ∂α_j/∂q_k (p_j · B_j).
        let mut later = [tip[0] + total[0], tip[1] + total[1]];
        let mut base = [-self.g_beam, 0.0];
        for (e, ([fx, fy], sum, step)) in elements.iter().enumerate() {
            later[0] -= sum[0];
            later[1] -= sum[1];
            let mut beta = [0.0; P];
            for (j, point) in ang.at[e * P..(e + 1) * P].iter().enumerate() {
                let bx = h * b[j] * later[0] + mh2 * d[j] * base[0] + mh3 * dot(&gm[j], fx);
                let by = h * b[j] * later[1] + mh2 * d[j] * base[1] + mh3 * dot(&gm[j], fy);
                beta[j] = -point.sin * bx + point.cos * by;
            }
            let mut to = [0.0; 4];
            for (g, beta) in self.slope.iter().zip(beta) {
                for (to, g) in to.iter_mut().zip(g) {
                    *to += g * beta;
                }
            }
            // Element e's coordinates are (w, α) of nodes e and e + 1; node 0 is clamped.
            let (from, to) = if e == 0 { (0, &to[2..]) } else { (2 * e - 2, &to[..]) };
            out[from..from + to.len()].iter_mut().zip(to).for_each(|(o, x)| *o += x);
            base[0] += step[0];
            base[1] += step[1];
        }
        out[t + 1] += r * (-st * tip[0] + ct * tip[1]) + j_c * ddth;
        [base[0] + self.g_beam, base[1]]
    }

    /// f_j = p_j α̈_j − e_j α̇_j² at element e's points, x and y.
    fn point_accelerations(&self, ang: &Angles, qdd: &[f64], e: usize) -> [[f64; P]; 2] {
        let add = self.alpha(qdd, e);
        let (mut fx, mut fy) = ([0.0; P], [0.0; P]);
        for (j, &Section { sin: s, cos: c, rate: w }) in
            ang.at[e * P..(e + 1) * P].iter().enumerate()
        {
            fx[j] = -s * add[j] - c * w * w;
            fy[j] = c * add[j] - s * w * w;
        }
        [fx, fy]
    }

    /// R(q, q̇, q̈) into `out`, zero on a motion ([`residual_with`](Self::residual_with)).
    pub fn residual(&self, phi: &Phi, q: &[f64], qd: &[f64], qdd: &[f64], out: &mut [f64]) {
        let ang = self.angles(q, qd);
        self.residual_with(&ang, phi, q, qd, qdd, out);
    }

    /// S = ∂R/∂q and C = ∂R/∂q̇ at (q, q̇, q̈) by forward differences of R (steps 1e-7·(1 +
    /// |x|)) into `parts` (2n × 4n: S, then C). A column moves one coordinate, which enters the
    /// angles of at most two elements: only theirs are computed again, and a column costs one
    /// sweep, O(n).
    pub fn residual_differences(
        &self,
        phi: &Phi,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        parts: &mut DMatrix<f64>,
    ) {
        let nq = q.len();
        let mut ang = self.angles(q, qd);
        let (mut r0, mut r) = (vec![0.0; nq], vec![0.0; nq]);
        self.residual_with(&ang, phi, q, qd, qdd, &mut r0);
        let mut x = [q, qd].concat();
        let mut saved = [Section::default(); 2 * P];
        for c in 0..2 * nq {
            // Coordinate k is in elements k/2 (its right node) and k/2 + 1 (its left node).
            let first = (c % nq) / 2;
            let points = first * P..((first + 2).min(self.n())) * P;
            let kept = &mut saved[..points.len()];
            kept.copy_from_slice(&ang.at[points.clone()]);
            let value = x[c];
            let step = 1e-7 * (1.0 + value.abs());
            x[c] += step;
            let (qp, qdp) = x.split_at(nq);
            for (e, out) in ang.at[points.clone()].chunks_exact_mut(P).enumerate() {
                self.element_angles(qp, qdp, first + e, out);
            }
            self.residual_with(&ang, phi, qp, qdp, qdd, &mut r);
            x[c] = value;
            ang.at[points].copy_from_slice(kept);
            for k in 0..nq {
                parts[(k, c)] = (r[k] - r0[k]) / step;
            }
        }
    }

    /// The mass matrix M = ∂R/∂q̈ into `mass` (row-major, 2n × 2n) at q with the body at θ.
    /// The beam's part m Σ_i w_i J_ik·J_il from J's structure: J_k varies on its coordinate's
    /// (at most two) elements, is zero before them and u_k = ∂r(l)/∂q_k after.
    fn mass_with(&self, ang: &Angles, theta: f64, mass: &mut [f64]) {
        let Params { m, m2, j_c, r, .. } = *self.params();
        let (n, h) = (self.n(), self.h());
        let nq = 2 * n;
        let Rule { a, b, .. } = &self.rule;
        mass[..nq * nq].fill(0.0);
        let mut u = [[0.0; 2]; MAX_DOFS];
        // ∂r/∂q of the left node's coordinates at the element's start.
        let mut carry = [[0.0; 2]; 2];
        for e in 0..n {
            let first = if e == 0 { 2 } else { 0 };
            // p_j ∂α_j/∂q_a at the points, then J at the points and its weighted sum W.
            let mut jac = [[[0.0; 2]; P]; 4];
            let mut total = [[0.0; 2]; 4];
            for loc in first..4 {
                let (mut px, mut py) = ([0.0; P], [0.0; P]);
                for j in 0..P {
                    let point = ang.at[e * P + j];
                    px[j] = -point.sin * self.slope[j][loc];
                    py[j] = point.cos * self.slope[j][loc];
                }
                let pre = if loc < 2 { carry[loc] } else { [0.0; 2] };
                for i in 0..P {
                    jac[loc][i] = [pre[0] + h * dot(&a[i], &px), pre[1] + h * dot(&a[i], &py)];
                }
                total[loc] = [pre[0] + h * dot(b, &px), pre[1] + h * dot(b, &py)];
            }
            let weighted = |x: usize, y: usize| -> f64 {
                (0..P)
                    .map(|i| b[i] * (jac[x][i][0] * jac[y][i][0] + jac[x][i][1] * jac[y][i][1]))
                    .sum::<f64>()
                    * m
                    * h
            };
            for (x, jx) in jac.iter().enumerate().skip(first) {
                let gx = 2 * e + x - 2;
                for y in first..=x {
                    let gy = 2 * e + y - 2;
                    let v = weighted(x, y);
                    mass[gx * nq + gy] += v;
                    if gx != gy {
                        mass[gy * nq + gx] += v;
                    }
                }
                // Against the coordinates done before this element: J_d = u_d here.
                let wsum: [f64; 2] =
                    std::array::from_fn(|c| m * h * (0..P).map(|i| b[i] * jx[i][c]).sum::<f64>());
                for d in 0..(2 * e).saturating_sub(2) {
                    let v = wsum[0] * u[d][0] + wsum[1] * u[d][1];
                    mass[gx * nq + d] += v;
                    mass[d * nq + gx] += v;
                }
            }
            if e >= 1 {
                u[2 * e - 2] = total[0];
                u[2 * e - 1] = total[1];
            }
            carry = [total[2], total[3]];
        }
        u[nq - 2] = carry[0];
        u[nq - 1] = carry[1];
        // Coordinates both done: node i is done on the n − 1 − i elements after its own two.
        for d1 in 0..nq.saturating_sub(2) {
            for d2 in 0..=d1 {
                let after = (n - 1 - (d1 / 2 + 1)) as f64;
                let v = m * h * after * (u[d1][0] * u[d2][0] + u[d1][1] * u[d2][1]);
                mass[d1 * nq + d2] += v;
                if d1 != d2 {
                    mass[d2 * nq + d1] += v;
                }
            }
        }
        // The body: M2 ∂C/∂q_k·∂C/∂q_l + J_C on ϑ1, ∂C/∂q_k = u_k + r (−sin θ, cos θ) δ_{k,ϑ1}.
        let (st, ct) = math::sin_cos(theta);
        u[nq - 1][0] -= r * st;
        u[nq - 1][1] += r * ct;
        for k in 0..nq {
            for l in 0..nq {
                mass[k * nq + l] += m2 * (u[k][0] * u[l][0] + u[k][1] * u[l][1]);
            }
        }
        mass[nq * nq - 1] += j_c;
    }

    /// The accelerations q̈ into `out`, and the tip's acceleration r̈(l). NaN if the mass
    /// matrix is not positive definite. No allocation.
    pub fn accelerations(&self, phi: &Phi, q: &[f64], qd: &[f64], out: &mut [f64]) -> [f64; 2] {
        let nq = q.len();
        let ang = self.angles(q, qd);
        let zero = [0.0; MAX_DOFS];
        self.residual_with(&ang, phi, q, qd, &zero[..nq], out);
        out.iter_mut().for_each(|f| *f = -*f);
        // On the heap: zeroing a stack buffer for the largest n costs more than the allocation.
        let mut mass = vec![0.0; nq * nq];
        self.mass_with(&ang, q[nq - 1] + phi.phi, &mut mass);
        if !cholesky_in_place(&mut mass[..nq * nq], nq) {
            out.fill(f64::NAN);
            return [f64::NAN; 2];
        }
        cholesky_solve(&mass[..nq * nq], nq, out);
        self.tip_acceleration(&ang, out)
    }

    /// r̈(l) = Σ_e h Σ_j b_j (p_j α̈_j − e_j α̇_j²).
    fn tip_acceleration(&self, ang: &Angles, qdd: &[f64]) -> [f64; 2] {
        let h = self.h();
        let mut acc = [0.0; 2];
        for e in 0..self.n() {
            let [fx, fy] = self.point_accelerations(ang, qdd, e);
            for (j, b) in self.rule.b.iter().enumerate() {
                acc[0] += h * b * fx[j];
                acc[1] += h * b * fy[j];
            }
        }
        acc
    }

    /// The mass matrix at q with the body at φ (dense, for tests and modes).
    pub fn mass_matrix(&self, q: &[f64], phi: f64) -> DMatrix<f64> {
        let nq = q.len();
        let ang = self.angles(q, &vec![0.0; nq]);
        let mut mass = vec![0.0; nq * nq];
        self.mass_with(&ang, q[nq - 1] + phi, &mut mass);
        DMatrix::from_row_slice(nq, nq, &mass)
    }

    /// The motion of the centreline's point at arc length `s` ∈ [0, l]: Gauss's rule over the
    /// whole elements before it and over the part of its own.
    pub fn point(&self, q: &[f64], qd: &[f64], qdd: &[f64], s: f64) -> PointMotion {
        let (n, h) = (self.n(), self.h());
        let e_end = ((s / h).floor().max(0.0) as usize).min(n);
        let mut out = PointMotion::default();
        let mut add = |e: usize, from: f64, to: f64| {
            let (ql, vl, al) = (local(q, e), local(qd, e), local(qdd, e));
            for j in 0..P {
                let xi = from + (to - from) * self.rule.c[j];
                let d = shape(xi, h)[1];
                let (a, w, dd) = (dot(&d, &ql), dot(&d, &vl), dot(&d, &al));
                let (sa, ca) = math::sin_cos(a);
                let wt = h * (to - from) * self.rule.b[j];
                out.r[0] += wt * ca;
                out.r[1] += wt * sa;
                out.v[0] -= wt * sa * w;
                out.v[1] += wt * ca * w;
                out.a[0] += wt * (-sa * dd - ca * w * w);
                out.a[1] += wt * (ca * dd - sa * w * w);
            }
        };
        for e in 0..e_end.min(n) {
            add(e, 0.0, 1.0);
        }
        if e_end < n {
            let xi = s / h - e_end as f64;
            if xi > 0.0 {
                add(e_end, 0.0, xi);
            }
        }
        out
    }

    /// The tip's motion r(l), ṙ(l), r̈(l) for the accelerations `qdd`.
    pub fn tip(&self, q: &[f64], qd: &[f64], qdd: &[f64]) -> PointMotion {
        self.point(q, qd, qdd, self.quadratic.beam.l)
    }

    /// The generalised force −R(q, 0, 0) at rest with the body held at `phi_fixed`.
    fn force_at_rest(&self, phi_fixed: f64, q: &DVector<f64>) -> DVector<f64> {
        let held = Phi { phi: phi_fixed, ..Phi::default() };
        let zero = vec![0.0; q.len()];
        let mut r = vec![0.0; q.len()];
        self.residual(&held, q.as_slice(), &zero, &zero, &mut r);
        -DVector::from_vec(r)
    }

    /// The static equilibrium q with the body held at `phi_fixed`, by Newton's method from the
    /// straight beam; `None` if it does not converge.
    pub fn equilibrium(&self, phi_fixed: f64) -> Option<DVector<f64>> {
        rest(self.dofs(), |q| self.force_at_rest(phi_fixed, q))
    }

    /// Squared angular frequencies ω² [rad²/s²], ascending, of the small oscillations about
    /// the static equilibrium at a held φ, with that equilibrium (as
    /// [`BeamBodyN::modes`]).
    pub fn modes(&self, phi_fixed: f64) -> Option<(DVector<f64>, Vec<f64>)> {
        let q = self.equilibrium(phi_fixed)?;
        let kt = negative_jacobian(|q| self.force_at_rest(phi_fixed, q), &q);
        let (omega2, _) = small_oscillations(self.mass_matrix(q.as_slice(), phi_fixed), &kt)?;
        Some((q, omega2))
    }

    /// The tip's deflection v1 = r_y(l) and slope ϑ1 = α_n at q.
    pub fn tip_values(&self, q: &[f64]) -> (f64, f64) {
        let zero = vec![0.0; q.len()];
        (self.tip(q, &zero, &zero).r[1], q[q.len() - 1])
    }

    /// Every Gauss point's arc length, weight and motion, element by element, and every
    /// node's motion (node k at s = k·l/n, k = 1..n, the tip last): the running sums of the
    /// module's notes (off the integrator's path).
    pub fn gauss_points(
        &self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
    ) -> (Vec<GaussPoint>, Vec<PointMotion>) {
        let (n, h) = (self.n(), self.h());
        let Rule { a, b, c, .. } = &self.rule;
        let mut out = Vec::with_capacity(n * P);
        let mut nodes = Vec::with_capacity(n);
        let mut base = PointMotion::default();
        for e in 0..n {
            let (al, w, dd) = (self.alpha(q, e), self.alpha(qd, e), self.alpha(qdd, e));
            let mut f = [[[0.0; P]; 2]; 3];
            for j in 0..P {
                let (sa, ca) = math::sin_cos(al[j]);
                f[0][0][j] = ca;
                f[0][1][j] = sa;
                f[1][0][j] = -sa * w[j];
                f[1][1][j] = ca * w[j];
                f[2][0][j] = -sa * dd[j] - ca * w[j] * w[j];
                f[2][1][j] = ca * dd[j] - sa * w[j] * w[j];
            }
            let run = |row: &[f64; P], start: &[f64; 2], f: &[[f64; P]; 2]| -> [f64; 2] {
                [start[0] + h * dot(row, &f[0]), start[1] + h * dot(row, &f[1])]
            };
            for i in 0..P {
                let point = PointMotion {
                    r: run(&a[i], &base.r, &f[0]),
                    v: run(&a[i], &base.v, &f[1]),
                    a: run(&a[i], &base.a, &f[2]),
                };
                out.push(((e as f64 + c[i]) * h, h * b[i], point));
            }
            base = PointMotion {
                r: run(b, &base.r, &f[0]),
                v: run(b, &base.v, &f[1]),
                a: run(b, &base.a, &f[2]),
            };
            nodes.push(base);
        }
        (out, nodes)
    }

    /// The beam's kinetic and potential energies [J]: ½m Σ w_i|ṙ_i|², and ½qᵀKq with the
    /// weight's −m g_b Σ w_i (x_i − s_i) (zero for the straight beam).
    pub fn beam_energy(&self, q: &[f64], qd: &[f64]) -> (f64, f64) {
        let (points, _) = self.gauss_points(q, qd, &vec![0.0; q.len()]);
        self.beam_energy_at(q, &points)
    }

    /// [`beam_energy`](Self::beam_energy) from the Gauss points' motion at (q, q̇)
    /// ([`gauss_points`](Self::gauss_points), any q̈).
    pub fn beam_energy_at(&self, q: &[f64], points: &[GaussPoint]) -> (f64, f64) {
        let m = self.params().m;
        let (mut kinetic, mut weight) = (0.0, 0.0);
        for &(s, w, p) in points {
            kinetic += 0.5 * m * w * (p.v[0] * p.v[0] + p.v[1] * p.v[1]);
            weight -= m * self.g_beam * w * (p.r[0] - s);
        }
        (kinetic, 0.5 * self.quadratic.beam.stiffness.form(q, q) + weight)
    }

    /// The shear force and bending moment at the clamp [N, N·m] with the convention of
    /// [`root_loads`](super::elements::root_loads) (the clamp exerts (R_v, R_ϑ) on the beam;
    /// shear R_v, moment −R_ϑ), from the balance of momentum and angular momentum about the
    /// clamp of beam and body together (the drive's torque is internal): the clamp's
    /// reactions for a rigid translation and rotation of the whole, exact for the discrete
    /// model. Of the damping, βK is internal and adds nothing; αM_b adds its resultant.
    pub fn root_loads(&self, phi: &Phi, q: &[f64], qd: &[f64], qdd: &[f64]) -> (f64, f64) {
        let (points, nodes) = self.gauss_points(q, qd, qdd);
        self.root_loads_at(phi, q, qd, qdd, &points, &nodes)
    }

    /// [`root_loads`](Self::root_loads) from [`gauss_points`](Self::gauss_points) at the same
    /// (q, q̇, q̈).
    pub fn root_loads_at(
        &self,
        phi: &Phi,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        points: &[GaussPoint],
        nodes: &[PointMotion],
    ) -> (f64, f64) {
        let Params { m, m2, j_c, r, g, .. } = *self.params();
        let tip = nodes[nodes.len() - 1];
        let nq = q.len();
        let (st, ct) = math::sin_cos(q[nq - 1] + phi.phi);
        let (dth, ddth) = (qd[nq - 1] + phi.dphi, qdd[nq - 1] + phi.ddphi);
        let c = [tip.r[0] + r * ct, tip.r[1] + r * st];
        let cdd = [
            tip.a[0] - r * st * ddth - r * ct * dth * dth,
            tip.a[1] + r * ct * ddth - r * st * dth * dth,
        ];
        let cross = |x: [f64; 2], y: [f64; 2]| x[0] * y[1] - x[1] * y[0];
        let mut force_y = m2 * cdd[1];
        let mut moment = m2 * cross(c, cdd) + j_c * ddth + m2 * g * c[1];
        for &(_, w, p) in points {
            force_y += m * w * p.a[1];
            moment += m * w * (cross(p.r, p.a) + self.g_beam * p.r[1]);
        }
        // Rayleigh's αM_b term is a force −α m ẇ(s) along y on the beam (M_b is the mass at
        // rest), which a rigid motion of the whole does work against: its resultant and moment
        // go through the clamp, as the quadratic model's consistent reactions take them.
        let alpha = self.quadratic.rayleigh().0;
        if alpha != 0.0 {
            let h = self.h();
            for e in 0..self.n() {
                let vl = local(qd, e);
                for j in 0..P {
                    let wdot = dot(&shape(self.rule.c[j], h)[0], &vl);
                    let (s, wt) = ((e as f64 + self.rule.c[j]) * h, h * self.rule.b[j]);
                    force_y += alpha * m * wt * wdot;
                    moment += alpha * m * wt * s * wdot;
                }
            }
        }
        (force_y, -moment)
    }

    /// The centreline at the clamp, the Gauss points and the nodes: (s, r), from the clamp.
    pub fn centreline(&self, q: &[f64]) -> Vec<(f64, [f64; 2])> {
        let zero = vec![0.0; q.len()];
        let (points, nodes) = self.gauss_points(q, &zero, &zero);
        let h = self.h();
        let mut line = vec![(0.0, [0.0; 2])];
        for (e, (element, node)) in points.chunks(P).zip(&nodes).enumerate() {
            line.extend(element.iter().map(|(s, _, p)| (*s, p.r)));
            line.push(((e + 1) as f64 * h, node.r));
        }
        line
    }

    /// The least and greatest section angle along the beam: α is quadratic in each element,
    /// so its extremes are at the nodes or at a vertex inside.
    pub fn angle_range(&self, q: &[f64]) -> (f64, f64) {
        let h = self.h();
        let (mut lo, mut hi) = (0.0_f64, 0.0_f64);
        for e in 0..self.n() {
            let ql = local(q, e);
            let at = |xi: f64| dot(&shape(xi, h)[1], &ql);
            let (a0, am, a1) = (at(0.0), at(0.5), at(1.0));
            let c2 = 2.0 * (a0 + a1 - 2.0 * am);
            let c1 = a1 - a0 - c2;
            let mut take = |x: f64| {
                lo = lo.min(x);
                hi = hi.max(x);
            };
            take(a0);
            take(a1);
            if c2 != 0.0 {
                let v = -c1 / (2.0 * c2);
                if v > 0.0 && v < 1.0 {
                    take(at(v));
                }
            }
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bent(model: &ExactBeam, amp: f64) -> Vec<f64> {
        // α(s) = amp (2s/l − s²/l²), w = amp (s²/l − s³/(3l²)), at the nodes.
        let (n, l) = (model.n(), model.params().l);
        (1..=n)
            .flat_map(|k| {
                let s = l * k as f64 / n as f64;
                [
                    amp * (s * s / l - s * s * s / (3.0 * l * l)),
                    amp * (2.0 * s / l - s * s / (l * l)),
                ]
            })
            .collect()
    }

    #[test]
    fn the_rule_integrates_polynomials_and_its_running_integrals() {
        let rule = Rule::new();
        for k in 0..12 {
            let sum: f64 = (0..P).map(|j| rule.b[j] * math::powi(rule.c[j], k)).sum();
            assert!((sum - 1.0 / (k as f64 + 1.0)).abs() < 1e-15, "degree {k}");
        }
        for i in 0..P {
            for k in 0..6 {
                let run: f64 = (0..P).map(|j| rule.a[i][j] * math::powi(rule.c[j], k)).sum();
                let want = math::powi(rule.c[i], k + 1) / (k as f64 + 1.0);
                assert!((run - want).abs() < 1e-14, "row {i}, degree {k}");
            }
        }
    }

    /// R is affine in q̈ with slope M, and M is symmetric and equals M_b (the quadratic
    /// model's) plus the body's terms for the straight beam.
    #[test]
    fn the_mass_matrix_is_the_residual_s_slope() {
        let p = Params { n_elements: 3, beam_gravity: true, ..Params::default() };
        let model = ExactBeam::new(p).unwrap();
        let nq = model.dofs();
        let q = bent(&model, 2.0);
        let qd: Vec<f64> = (0..nq).map(|k| 0.3 * math::sin(k as f64)).collect();
        let phi = Phi { phi: 0.8, dphi: 1.2, ddphi: -3.0 };
        let mass = model.mass_matrix(&q, phi.phi);
        let mut r0 = vec![0.0; nq];
        model.residual(&phi, &q, &qd, &vec![0.0; nq], &mut r0);
        for l in 0..nq {
            let mut e = vec![0.0; nq];
            e[l] = 1.0;
            let mut r = vec![0.0; nq];
            model.residual(&phi, &q, &qd, &e, &mut r);
            for k in 0..nq {
                let slope = r[k] - r0[k];
                assert!((slope - mass[(k, l)]).abs() < 1e-12 * mass.amax(), "({k}, {l})");
            }
        }
        assert!((&mass - mass.transpose()).amax() < 1e-13 * mass.amax());
        let straight = model.mass_matrix(&vec![0.0; nq], 0.0);
        let mb = &model.quadratic.beam.mass;
        let t = nq - 2;
        let Params { m2, r, j_c, .. } = p;
        for k in 0..nq {
            for l in 0..nq {
                let body = match (k, l) {
                    (a, b) if a == t && b == t => m2,
                    (a, b) if (a, b) == (t, t + 1) || (a, b) == (t + 1, t) => m2 * r,
                    (a, b) if a == t + 1 && b == t + 1 => m2 * r * r + j_c,
                    _ => 0.0,
                };
                let want = mb.get(k, l) + body;
                assert!((straight[(k, l)] - want).abs() < 1e-12, "({k}, {l})");
            }
        }
    }

    /// The accelerations solve M q̈ = −R(q, q̇, 0): R vanishes on them.
    #[test]
    fn accelerations_make_the_residual_vanish() {
        for n in [1, 2, 5] {
            let model = ExactBeam::new(Params { n_elements: n, ..Params::default() }).unwrap();
            let nq = model.dofs();
            let q = bent(&model, 1.4);
            let qd: Vec<f64> = (0..nq).map(|k| math::cos(k as f64)).collect();
            let phi = Phi { phi: 2.0, dphi: -1.0, ddphi: 5.0 };
            let mut qdd = vec![0.0; nq];
            let tip = model.accelerations(&phi, &q, &qd, &mut qdd);
            let mut res = vec![0.0; nq];
            model.residual(&phi, &q, &qd, &qdd, &mut res);
            let scale =
                model.quadratic.beam.stiffness.mul(&q).iter().fold(0.0_f64, |a, x| a.max(x.abs()));
            assert!(res.iter().all(|x| x.abs() < 1e-10 * scale), "{n}: {res:?}");
            let want = model.tip(&q, &qd, &qdd).a;
            assert!((tip[0] - want[0]).abs() < 1e-12 && (tip[1] - want[1]).abs() < 1e-12);
        }
    }
}
