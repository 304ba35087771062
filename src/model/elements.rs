//! The clamped beam as n uniform cubic Hermite elements: coordinates q = (v_1, ϑ_1, …, v_n,
//! ϑ_n), the deflection and the slope at the nodes x_i = i·l/n (node 0 is clamped), and
//! the assembled matrices of its energies:
//!
//! - mass M_b = m∫NᵀN dx (T1 = ½q̇ᵀM_b q̇),
//! - stiffness K = EI∫N″ᵀN″ dx (Π1 = ½qᵀKq),
//! - G = ∫N′ᵀN′ dx, the second-order axial shortening of the tip u1 = −½∫v′² dx = −½qᵀGq.
//!
//! The element matrices are the classical ones of the Hermite beam element (consistent mass
//! m h/420·[156, 22h, 54, −13h; …], stiffness EI/h³·[12, 6h, −12, 6h; …] and geometric
//! stiffness 1/(30h)·[36, 3h, −36, 3h; …]: J. S. Przemieniecki, *Theory of Matrix Structural
//! Analysis*, 1968, §5.6, §11.3). With n = 1 they are the paper's eq. (10)–(11) and (8).

use super::band::Band;

/// Shape functions of the element on ξ ∈ [0, 1] of length h, for (v_a, ϑ_a, v_b, ϑ_b):
/// values, first, second and third derivatives in x.
pub(super) fn shape(xi: f64, h: f64) -> [[f64; 4]; 4] {
    let (x2, x3) = (xi * xi, xi * xi * xi);
    [
        [1.0 - 3.0 * x2 + 2.0 * x3, h * (xi - 2.0 * x2 + x3), 3.0 * x2 - 2.0 * x3, h * (x3 - x2)],
        [
            (-6.0 * xi + 6.0 * x2) / h,
            1.0 - 4.0 * xi + 3.0 * x2,
            (6.0 * xi - 6.0 * x2) / h,
            3.0 * x2 - 2.0 * xi,
        ],
        [
            (-6.0 + 12.0 * xi) / (h * h),
            (-4.0 + 6.0 * xi) / h,
            (6.0 - 12.0 * xi) / (h * h),
            (6.0 * xi - 2.0) / h,
        ],
        [12.0 / (h * h * h), 6.0 / (h * h), -12.0 / (h * h * h), 6.0 / (h * h)],
    ]
}

/// The beam's assembled matrices for n elements.
#[derive(Clone, Debug, PartialEq)]
pub struct Elements {
    pub n: usize,
    /// Beam length [m] and element length l/n.
    pub l: f64,
    h: f64,
    pub mass: Band,
    pub stiffness: Band,
    /// G = ∫N′ᵀN′ dx, dimensionless per unit length of q's units.
    pub g: Band,
}

impl Elements {
    /// The matrices of a beam of length `l`, stiffness `ei` and mass per length `m` in `n`
    /// elements (n ≥ 1).
    pub fn new(n: usize, l: f64, ei: f64, m: f64) -> Self {
        assert!(n >= 1, "at least one element");
        let h = l / n as f64;
        let me = scaled(
            m * h / 420.0,
            [
                [156.0, 22.0 * h, 54.0, -13.0 * h],
                [22.0 * h, 4.0 * h * h, 13.0 * h, -3.0 * h * h],
                [54.0, 13.0 * h, 156.0, -22.0 * h],
                [-13.0 * h, -3.0 * h * h, -22.0 * h, 4.0 * h * h],
            ],
        );
        let ke = scaled(
            ei / (h * h * h),
            [
                [12.0, 6.0 * h, -12.0, 6.0 * h],
                [6.0 * h, 4.0 * h * h, -6.0 * h, 2.0 * h * h],
                [-12.0, -6.0 * h, 12.0, -6.0 * h],
                [6.0 * h, 2.0 * h * h, -6.0 * h, 4.0 * h * h],
            ],
        );
        let ge = scaled(
            1.0 / (30.0 * h),
            [
                [36.0, 3.0 * h, -36.0, 3.0 * h],
                [3.0 * h, 4.0 * h * h, -3.0 * h, -h * h],
                [-36.0, -3.0 * h, 36.0, -3.0 * h],
                [3.0 * h, -h * h, -3.0 * h, 4.0 * h * h],
            ],
        );
        let dofs = 2 * n;
        let (mut mass, mut stiffness, mut g) =
            (Band::zeros(dofs), Band::zeros(dofs), Band::zeros(dofs));
        for e in 0..n {
            // Global index of local dof a of element e: node e's (v, ϑ) are 2e − 2, 2e − 1;
            // node 0 is clamped and has none.
            let index = |a: usize| (2 * e + a).checked_sub(2);
            for a in 0..4 {
                for b in 0..=a {
                    if let (Some(i), Some(j)) = (index(a), index(b)) {
                        mass.add(i, j, me[a][b]);
                        stiffness.add(i, j, ke[a][b]);
                        g.add(i, j, ge[a][b]);
                    }
                }
            }
        }
        Self { n, l, h, mass, stiffness, g }
    }

    /// The number of coordinates, 2n.
    pub fn dofs(&self) -> usize {
        2 * self.n
    }

    /// The index of the tip's deflection v1 in q; the tip's slope ϑ1 follows it.
    pub fn tip(&self) -> usize {
        2 * self.n - 2
    }

    /// The nodal values (v_k, ϑ_k), k = 1..n, of the one cubic of a cantilever with tip
    /// deflection `v1` and slope `theta1` (the paper's single element): the start of every n
    /// is the same shape.
    pub fn tip_cubic(&self, v1: f64, theta1: f64) -> Vec<f64> {
        let one = Elements::new(1, self.l, 1.0, 1.0);
        (1..=self.n)
            .flat_map(|k| {
                let [v, dv, ..] = one.field(&[v1, theta1], self.l * k as f64 / self.n as f64);
                [v, dv]
            })
            .collect()
    }

    /// v and its first three derivatives in x at `x` ∈ [0, l] for coordinates `q`. At a node
    /// the element to its right is used (the left one at x = l); v‴ jumps there.
    pub fn field(&self, q: &[f64], x: f64) -> [f64; 4] {
        let e = ((x / self.h).floor().max(0.0) as usize).min(self.n - 1);
        let xi = x / self.h - e as f64;
        let node = |k: usize, a: usize| if k == 0 { 0.0 } else { q[2 * k - 2 + a] };
        let dofs = [node(e, 0), node(e, 1), node(e + 1, 0), node(e + 1, 1)];
        shape(xi, self.h).map(|n| n.iter().zip(&dofs).map(|(n, d)| n * d).sum())
    }
}

/// The shear force and bending moment at the clamp [N, N·m], EI·v‴(0) and EI·v″(0), as the
/// clamp's consistent reactions: the rows of the clamped node (v_0, ϑ_0) of the first
/// element's equations, M_e q̈ + D_e q̇ + K_e q + N G_e q with the tip's axial force N (the
/// hinge force along x, which the beam carries as its tension), over the first node's
/// (v, ϑ) and their rates and accelerations, `node1`. The clamp exerts (R_v, R_ϑ) on the
/// beam; the beam's shear force there is R_v and its bending moment −R_ϑ. A consistent
/// reaction converges faster with the elements than the elements' own v″(0) and v‴(0) (for
/// a static tip load it is exact with any number of them).
pub fn root_loads(
    n: usize,
    (l, ei, m): (f64, f64, f64),
    (alpha, beta): (f64, f64),
    node1: [f64; 6],
    axial: f64,
) -> (f64, f64) {
    let h = l / n as f64;
    // Rows v_a, ϑ_a of the element matrices, columns v_b, ϑ_b (Przemieniecki, as above).
    let me = [[54.0, -13.0 * h], [13.0 * h, -3.0 * h * h]].map(|r| r.map(|x| x * m * h / 420.0));
    let ke = [[-12.0, 6.0 * h], [-6.0 * h, 2.0 * h * h]].map(|r| r.map(|x| x * ei / (h * h * h)));
    let ge = [[-36.0, 3.0 * h], [-3.0 * h, -h * h]].map(|r| r.map(|x| x / (30.0 * h)));
    let [v, th, dv, dth, ddv, ddth] = node1;
    let row = |i: usize| {
        let mass = me[i][0] * ddv + me[i][1] * ddth;
        let stiff = ke[i][0] * v + ke[i][1] * th;
        let damp =
            alpha * (me[i][0] * dv + me[i][1] * dth) + beta * (ke[i][0] * dv + ke[i][1] * dth);
        mass + damp + stiff + axial * (ge[i][0] * v + ge[i][1] * th)
    };
    (row(0), -row(1))
}

fn scaled(s: f64, m: [[f64; 4]; 4]) -> [[f64; 4]; 4] {
    m.map(|row| row.map(|x| s * x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The element matrices are the energies' integrals: Gauss–Legendre quadrature (5 points,
    /// exact for these polynomials) of NᵀN, N″ᵀN″ and N′ᵀN′ over each element, from the shape
    /// functions.
    #[test]
    fn assembled_matrices_are_the_integrals_of_the_shape_functions() {
        let (n, l, ei, m) = (3, 2.5, 1000.0, 2.0);
        let beam = Elements::new(n, l, ei, m);
        let gauss = [
            (0.0, 128.0 / 225.0),
            (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
            (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
            (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
            (0.906_179_845_938_664, 0.236_926_885_056_189_1),
        ];
        let dofs = 2 * n;
        for i in 0..dofs {
            for j in 0..dofs {
                let mut e_i = vec![0.0; dofs];
                let mut e_j = vec![0.0; dofs];
                e_i[i] = 1.0;
                e_j[j] = 1.0;
                let (mut mm, mut kk, mut gg) = (0.0, 0.0, 0.0);
                let h = l / n as f64;
                for e in 0..n {
                    for (x, w) in gauss {
                        let at = (e as f64 + 0.5 + 0.5 * x) * h;
                        let (fi, fj) = (beam.field(&e_i, at), beam.field(&e_j, at));
                        mm += 0.5 * h * w * m * fi[0] * fj[0];
                        gg += 0.5 * h * w * fi[1] * fj[1];
                        kk += 0.5 * h * w * ei * fi[2] * fj[2];
                    }
                }
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-11 * (1.0 + b.abs());
                assert!(close(beam.mass.get(i, j), mm), "M[{i}][{j}]");
                assert!(close(beam.stiffness.get(i, j), kk), "K[{i}][{j}]");
                assert!(close(beam.g.get(i, j), gg), "G[{i}][{j}]");
            }
        }
    }

    /// One element is the paper's eq. (10)–(11) and u1 of eq. (8).
    #[test]
    fn one_element_is_the_paper_s_matrices() {
        let (l, ei, m) = (2.5, 1000.0, 2.0);
        let b = Elements::new(1, l, ei, m);
        let close = |a: f64, want: f64| (a - want).abs() <= 1e-12 * want.abs();
        assert!(close(b.mass.get(0, 0), 13.0 * m * l / 35.0));
        assert!(close(b.mass.get(0, 1), -11.0 * m * l * l / 210.0));
        assert!(close(b.mass.get(1, 1), m * l * l * l / 105.0));
        assert!(close(b.stiffness.get(0, 0), 12.0 * ei / (l * l * l)));
        assert!(close(b.stiffness.get(0, 1), -6.0 * ei / (l * l)));
        assert!(close(b.stiffness.get(1, 1), 4.0 * ei / l));
        let q = [0.3, -0.2];
        let u1 = -0.5 * b.g.form(&q, &q);
        assert!((u1 - super::super::kinematics::u1(l, q[0], q[1])).abs() < 1e-15);
    }

    /// For a static tip load P the root's shear and moment are −P and P·l (the clamp pushes
    /// down and turns back), exactly, with any number of elements: the cubic deflection is
    /// then the exact one.
    #[test]
    fn root_loads_of_a_static_tip_load_are_exact() {
        let (l, ei, p) = (2.5, 1000.0, 40.0);
        for n in [1, 3, 8] {
            let x1 = l / n as f64;
            // v = P x²(3l − x)/(6EI), v' = P x(2l − x)/(2EI)
            let v = p * x1 * x1 * (3.0 * l - x1) / (6.0 * ei);
            let th = p * x1 * (2.0 * l - x1) / (2.0 * ei);
            let (q, m) = root_loads(n, (l, ei, 2.0), (0.0, 0.0), [v, th, 0.0, 0.0, 0.0, 0.0], 0.0);
            assert!((q + p).abs() < 1e-9 * p && (m - p * l).abs() < 1e-9 * p * l, "{n}: {q} {m}");
        }
    }

    /// The field interpolates the nodes, is C¹ across them, and is zero with zero slope at
    /// the clamp.
    #[test]
    fn the_field_passes_through_the_nodes() {
        let beam = Elements::new(4, 2.0, 1.0, 1.0);
        let q: Vec<f64> = (0..8).map(|k| 0.1 * k as f64 - 0.3).collect();
        for k in 1..=4 {
            let x = 0.5 * k as f64;
            let [v, dv, ..] = beam.field(&q, x);
            assert!((v - q[2 * k - 2]).abs() < 1e-14 && (dv - q[2 * k - 1]).abs() < 1e-14);
            if k < 4 {
                let left = beam.field(&q, x - 1e-9);
                assert!((left[0] - v).abs() < 1e-8 && (left[1] - dv).abs() < 1e-7);
            }
        }
        let [v0, dv0, ..] = beam.field(&q, 0.0);
        assert_eq!((v0, dv0), (0.0, 0.0));
    }
}
