//! Dense symmetric positive definite systems in a caller's buffer, without allocation: the
//! exact beam's configuration-dependent mass matrix (`exact.rs`).

/// Factors the n×n symmetric matrix `a` (row-major, its lower triangle read) in place as
/// L·Lᵀ, L in the lower triangle (Golub & Van Loan, *Matrix Computations*, 4th ed.,
/// Alg. 4.2.1). False if it is not positive definite (or not finite).
pub fn cholesky_in_place(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    true
}

/// Solves L·Lᵀ x = b in place with the factor of [`cholesky_in_place`].
pub fn cholesky_solve(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[k * n + i] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn solves_as_nalgebra_does_and_refuses_an_indefinite_matrix() {
        let n = 7;
        let b = DMatrix::from_fn(n, n, |i, j| ((3 * i + 5 * j) % 11) as f64 / 7.0 - 0.6);
        let a = &b * b.transpose() + DMatrix::identity(n, n);
        let rhs = DVector::from_fn(n, |i, _| i as f64 - 2.5);
        let want = a.clone().cholesky().unwrap().solve(&rhs);
        let mut buf: Vec<f64> = a.transpose().iter().copied().collect();
        assert!(cholesky_in_place(&mut buf, n));
        let mut x: Vec<f64> = rhs.iter().copied().collect();
        cholesky_solve(&buf, n, &mut x);
        for (x, w) in x.iter().zip(want.iter()) {
            assert!((x - w).abs() < 1e-12 * want.amax(), "{x} {w}");
        }
        let mut bad: Vec<f64> = (&a - DMatrix::identity(n, n) * 100.0).iter().copied().collect();
        assert!(!cholesky_in_place(&mut bad, n));
        let mut nan = vec![f64::NAN; n * n];
        assert!(!cholesky_in_place(&mut nan, n));
    }
}
