//! Tangent stiffnesses by differences of a residual, for the modes and the rest states of
//! every beam.
#![forbid(unsafe_code)]

use nalgebra::{DMatrix, DVector};

/// −∂r/∂q of a residual r at q (for r = F(q) at rest: the tangent stiffness), by the
/// fourth-order central difference [8(r(q+h) − r(q−h)) − (r(q+2h) − r(q−2h))] / 12h
/// (Abramowitz & Stegun 25.3.6) with h = 7e-4·(1 + |q_j|), about the fifth root of the machine
/// epsilon, which balances the truncation error (∝ h⁴) against the round-off (∝ ε/h) (Press
/// et al., Numerical Recipes, 3rd ed., §5.7). The second-order difference at 1e-7 lost digits
/// to round-off: the periods of the exact beam in 8 elements about φ = π/2 were 4.4e-8 off
/// the oracle's complex-step linearisation (tests/python/oracle/test_oracle_exact_loads.py).
pub(super) fn negative_jacobian(
    r: impl Fn(&DVector<f64>) -> DVector<f64>,
    q: &DVector<f64>,
) -> DMatrix<f64> {
    let n = q.len();
    let mut kt = DMatrix::zeros(n, n);
    let at = |j: usize, step: f64| {
        let mut x = q.clone();
        x[j] += step;
        r(&x)
    };
    for j in 0..n {
        let h = 7e-4 * (1.0 + q[j].abs());
        let near = at(j, h) - at(j, -h);
        let far = at(j, 2.0 * h) - at(j, -2.0 * h);
        kt.set_column(j, &(-(near * 8.0 - far) / (12.0 * h)));
    }
    kt
}
