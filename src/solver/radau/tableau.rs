//! The Radau IIA method of three stages (order 5, stage order 3, L-stable) as RADAU5 uses
//! it (Hairer & Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., §IV.8): the
//! nodes, the eigenvalues of A⁻¹ and the basis T that block-diagonalises it, the
//! error-estimate weights and the collocation polynomial's coefficients. The numbers are
//! Hairer and Wanner's (also those of SciPy's `radau.py`); the tests below derive each from
//! the Butcher tableau.

/// The nodes c = ((4 − √6)/10, (4 + √6)/10, 1).
pub(super) const C: [f64; 3] = [0.15505102572168222, 0.6449489742783178, 1.0];

/// The real eigenvalue of A⁻¹, 3 + 3^(2/3) − 3^(1/3).
pub(super) const MU_REAL: f64 = 3.637834252744496;

/// The complex pair of A⁻¹, α ± iβ: 3 + (3^(1/3) − 3^(2/3))/2 and (3^(5/6) + 3^(7/6))/2.
pub(super) const MU_ALPHA: f64 = 2.6810828736277523;
pub(super) const MU_BETA: f64 = 3.050430199247411;

/// T⁻¹A⁻¹T = [[μ, 0, 0], [0, α, β], [0, −β, α]] (rows of T).
pub(super) const T: [[f64; 3]; 3] = [
    [0.09443876248897524, -0.1412552950209542, 0.03002919410514742],
    [0.2502131229653333, 0.20412935229379994, -0.3829421127572619],
    [1.0, 1.0, 0.0],
];

/// T⁻¹ (rows).
pub(super) const TI: [[f64; 3]; 3] = [
    [4.178718591551904, 0.32768282076106237, 0.5233764454994495],
    [-4.178718591551904, -0.32768282076106237, 0.47662355450055044],
    [0.5028726349457868, -2.571926949855605, 0.5960392048282249],
];

/// The embedded error estimate: err = (μ/h·I − J)⁻¹ (f(y_n) + Σ_i E_i Z_i / h), the
/// difference of the solution and a lower-order one filtered by the Newton matrix, so that
/// stiff components it damps do not count (Hairer & Wanner, IV.8, (8.19)–(8.20)):
/// E = (−13 − 7√6, −13 + 7√6, −1)/3.
pub(super) const E: [f64; 3] = [-10.048809399827414, 1.382142733160748, -0.3333333333333333];

/// The collocation polynomial u(x) = Σ_k Q_k x^(k+1) through u(c_i) = Z_i, with
/// Q_k = Σ_i P[i][k] Z_i: P = (Vᵀ)⁻¹, V_ik = c_i^(k+1).
pub(super) const P: [[f64; 3]; 3] = [
    [10.048809399827414, -25.62959144707664, 15.580782047249224],
    [-1.382142733160748, 10.296258113743303, -8.914115380582556],
    [0.3333333333333333, -2.6666666666666665, 3.3333333333333335],
];

/// The Butcher matrix A and its inverse, as T Λ⁻¹ T⁻¹ and T Λ T⁻¹ from the constants above
/// (so that they agree with the transformation to round-off).
pub(super) fn butcher_and_inverse() -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
    let d = MU_ALPHA * MU_ALPHA + MU_BETA * MU_BETA;
    let lam = [[MU_REAL, 0.0, 0.0], [0.0, MU_ALPHA, MU_BETA], [0.0, -MU_BETA, MU_ALPHA]];
    let inv = [
        [1.0 / MU_REAL, 0.0, 0.0],
        [0.0, MU_ALPHA / d, -MU_BETA / d],
        [0.0, MU_BETA / d, MU_ALPHA / d],
    ];
    let similar = |l: &[[f64; 3]; 3]| {
        std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                (0..3).map(|k| (0..3).map(|m| T[i][k] * l[k][m] * TI[m][j]).sum::<f64>()).sum()
            })
        })
    };
    (similar(&inv), similar(&lam))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::powi;
    use nalgebra::Matrix3;

    fn m(rows: [[f64; 3]; 3]) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| rows[i][j])
    }

    /// The Butcher matrix of Radau IIA(5) in closed form (Hairer & Wanner, Table IV.5.6).
    fn butcher() -> Matrix3<f64> {
        let s = 6f64.sqrt();
        m([
            [(88.0 - 7.0 * s) / 360.0, (296.0 - 169.0 * s) / 1800.0, (-2.0 + 3.0 * s) / 225.0],
            [(296.0 + 169.0 * s) / 1800.0, (88.0 + 7.0 * s) / 360.0, (-2.0 - 3.0 * s) / 225.0],
            [(16.0 - s) / 36.0, (16.0 + s) / 36.0, 1.0 / 9.0],
        ])
    }

    #[test]
    fn the_nodes_are_the_row_sums_and_t_block_diagonalises_the_inverse() {
        let a = butcher();
        for (i, c) in C.iter().enumerate() {
            assert!((a.row(i).sum() - c).abs() < 1e-15);
        }
        let (a2, ai) = butcher_and_inverse();
        assert!(
            (m(a2) - a).abs().max() < 1e-14
                && (m(ai) * a - Matrix3::identity()).abs().max() < 1e-13
        );
        let d = m(TI) * a.try_inverse().unwrap() * m(T);
        let want = m([[MU_REAL, 0.0, 0.0], [0.0, MU_ALPHA, MU_BETA], [0.0, -MU_BETA, MU_ALPHA]]);
        assert!((d - want).abs().max() < 1e-12, "{d}");
        assert!((m(T) * m(TI) - Matrix3::identity()).abs().max() < 1e-14);
        // The real eigenvalue and the pair from their closed forms (cube roots of 3).
        let (r3, r9) = (1.4422495703074083, 2.080083823051904);
        assert!((MU_REAL - (3.0 + r9 - r3)).abs() < 1e-14);
        assert!((MU_ALPHA - (3.0 + 0.5 * (r3 - r9))).abs() < 1e-14);
        assert!((MU_BETA - 0.5 * 3f64.sqrt() * (r3 + r9)).abs() < 1e-14);
    }

    #[test]
    fn the_polynomial_interpolates_the_stages_and_the_estimate_is_of_order_three() {
        // u(c_j) = Σ_i Z_i Σ_k P[i][k] c_j^(k+1) = Z_j.
        for (i, p) in P.iter().enumerate() {
            for (j, c) in C.iter().enumerate() {
                let v: f64 = (0..3).map(|k| p[k] * powi(*c, k as i32 + 1)).sum();
                assert!((v - if i == j { 1.0 } else { 0.0 }).abs() < 1e-13);
            }
        }
        // Σ E_i Z_i / h + f(y0) vanishes on y = t^k for k ≤ 2 (Z_i = (c_i h)^k, f = k t^(k−1)
        // at t = 0): the estimate is the gap to a method of order 3.
        let e0: f64 = E.iter().zip(C).map(|(e, c)| e * c).sum();
        assert!((e0 + 1.0).abs() < 1e-13, "k = 1");
        for k in 2..=3 {
            let ek: f64 = E.iter().zip(C).map(|(e, c)| e * powi(c, k)).sum();
            assert!(ek.abs() < 1e-13, "k = {k}: {ek}");
        }
    }
}
