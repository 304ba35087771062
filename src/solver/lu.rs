//! Dense LU with partial pivoting for the small Newton matrices (N ≤ 8), on the stack, and
//! the inverse it gives, through which the Newton iteration solves.
//!
//! nalgebra's `LU` needs typenum bounds (`Const<N>: DimMin`) that a generic `const N` cannot
//! name, and this is twenty lines (Golub & Van Loan, *Matrix Computations*, alg. 3.4.1).

use super::error::SolverError;
use super::snapshot::{require, require_finite, visit_usize, StateVisitor};
use nalgebra::{SMatrix, SVector};

#[derive(Clone, Debug, PartialEq)]
pub struct Lu<const N: usize> {
    /// The rows of L (unit lower, below the diagonal) and U (above it), row-permuted; the
    /// diagonal holds the reciprocals of U's pivots, so that a solve multiplies where it
    /// would divide (the back substitution's divisions are a chain, each waiting for the one
    /// before). Plain rows rather than a matrix: a row swap moves one array, and the loops
    /// index in bounds the compiler can see (nalgebra's indexing checks each access).
    rows: [[f64; N]; N],
    /// Row `i` of the factors is row `perm[i]` of the original matrix.
    perm: [usize; N],
    /// The inverse A⁻¹ by rows, from the factors: [`solve`](Self::solve) is one
    /// matrix-vector product, whose N² products are independent, where the substitutions
    /// are a chain of N steps of dependent products (the solve sits on the Newton
    /// iteration's chain: f, residual, solve, correction, f again). Derived from the
    /// factors and the permutation, not part of a saved state.
    inverse: [[f64; N]; N],
}

// Index loops with constant bounds throughout: they unroll, and the bounds checks go.
#[allow(clippy::needless_range_loop)]
impl<const N: usize> Lu<N> {
    /// Factors `a`; `None` if a pivot is zero, non-finite or below round-off of ‖a‖, or its
    /// reciprocal is not finite.
    pub fn factor(a: &SMatrix<f64, N, N>) -> Option<Self> {
        let mut f: [[f64; N]; N] = std::array::from_fn(|i| std::array::from_fn(|j| a[(i, j)]));
        let mut perm: [usize; N] = std::array::from_fn(|i| i);
        // max |a_ij|, NaN entries passed over (as f64::max does; the pivot test then refuses
        // them), on the rows: nalgebra's matrix iterator was several times slower here.
        let mut scale = 0.0f64;
        for x in f.iter().flatten() {
            if x.abs() > scale {
                scale = x.abs();
            }
        }
        let tiny = scale * f64::EPSILON * N as f64;
        for k in 0..N {
            let (mut piv, mut best) = (k, f[k][k].abs());
            for i in k + 1..N {
                if f[i][k].abs() > best {
                    piv = i;
                    best = f[i][k].abs();
                }
            }
            if !(best.is_finite() && best > tiny) {
                return None;
            }
            if piv != k {
                f.swap(k, piv);
                perm.swap(k, piv);
            }
            let inv = 1.0 / f[k][k];
            if !inv.is_finite() {
                return None;
            }
            f[k][k] = inv;
            let pivot_row = f[k];
            for i in k + 1..N {
                let m = f[i][k] * inv;
                f[i][k] = m;
                for j in k + 1..N {
                    f[i][j] -= m * pivot_row[j];
                }
            }
        }
        let mut lu = Self { rows: f, perm, inverse: [[0.0; N]; N] };
        lu.inverse = lu.invert();
        Some(lu)
    }

    /// A⁻¹ by rows: column k is the substitutions' solution of A x = e_k.
    fn invert(&self) -> [[f64; N]; N] {
        let mut inverse = [[0.0; N]; N];
        for k in 0..N {
            let mut e = [0.0; N];
            e[k] = 1.0;
            let x = self.substitute(&e);
            for i in 0..N {
                inverse[i][k] = x[i];
            }
        }
        inverse
    }

    /// Solves `a x = b` by forward and back substitution on the factors.
    fn substitute(&self, b: &[f64; N]) -> [f64; N] {
        let f = &self.rows;
        let mut x: [f64; N] = std::array::from_fn(|i| b[self.perm[i]]);
        for i in 0..N {
            for j in 0..i {
                x[i] -= f[i][j] * x[j];
            }
        }
        for i in (0..N).rev() {
            for j in i + 1..N {
                x[i] -= f[i][j] * x[j];
            }
            x[i] *= f[i][i];
        }
        x
    }

    /// A stand-in for the fields of an absent LU when a state is visited: zero factors and
    /// the identity permutation.
    pub(crate) fn placeholder() -> Self {
        Self { rows: [[0.0; N]; N], perm: std::array::from_fn(|i| i), inverse: [[0.0; N]; N] }
    }

    /// Whether this is bit for bit the [`placeholder`](Self::placeholder).
    pub(crate) fn is_placeholder(&self) -> bool {
        self.rows.iter().flatten().all(|x| x.to_bits() == 0)
            && self.perm.iter().enumerate().all(|(i, p)| *p == i)
    }

    /// Visits the factors (column-major), then the permutation; the inverse follows from
    /// them (zeros while the permutation is not one, which [`check`](Self::check) refuses).
    pub(crate) fn visit<V: StateVisitor + ?Sized>(&mut self, v: &mut V) {
        for j in 0..N {
            for i in 0..N {
                v.real("lu.factors", &mut self.rows[i][j]);
            }
        }
        for p in &mut self.perm {
            visit_usize(v, "lu.perm", p);
        }
        self.inverse = if self.check_perm().is_ok() { self.invert() } else { [[0.0; N]; N] };
    }

    /// What [`factor`](Self::factor) guarantees: finite factors, non-zero (reciprocal)
    /// pivots, and a permutation of 0..N (so [`solve`](Self::solve) indexes in range).
    pub(crate) fn check(&self) -> Result<(), SolverError> {
        require_finite(self.rows.iter().flatten(), "lu.factors")?;
        require((0..N).all(|i| self.rows[i][i] != 0.0), "lu.factors")?;
        self.check_perm()
    }

    fn check_perm(&self) -> Result<(), SolverError> {
        let mut seen = [false; N];
        for &p in &self.perm {
            require(p < N && !seen[p], "lu.perm")?;
            seen[p] = true;
        }
        Ok(())
    }

    /// Solves `a x = b`: x = A⁻¹ b.
    pub fn solve(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        SVector::from(std::array::from_fn(|i| {
            let row = &self.inverse[i];
            let mut x = 0.0;
            for j in 0..N {
                x += row[j] * b[j];
            }
            x
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    #[test]
    fn solves_with_pivoting() {
        let a = Matrix3::new(0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0);
        let x = Vector3::new(1.0, -2.0, 0.5);
        let lu = Lu::factor(&a).unwrap();
        assert!((lu.solve(&(a * x)) - x).norm() < 1e-14);
    }

    /// The inverse is that of the matrix, and the solve through it agrees with the
    /// substitutions on the factors to round-off.
    #[test]
    fn inverse_is_the_matrix_inverse() {
        let a = Matrix3::new(0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0);
        let lu = Lu::factor(&a).unwrap();
        let inv = SMatrix::<f64, 3, 3>::from_fn(|i, j| lu.inverse[i][j]);
        assert!((inv * a - SMatrix::<f64, 3, 3>::identity()).norm() < 1e-14);
        let b = Vector3::new(0.3, -1.0, 2.5);
        let by_substitution = Vector3::from(lu.substitute(&[b[0], b[1], b[2]]));
        assert!((lu.solve(&b) - by_substitution).norm() < 1e-14);
    }

    #[test]
    fn rejects_singular_and_nan() {
        let a = Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 1.0, 1.0);
        assert!(Lu::factor(&a).is_none());
        let b = Matrix3::new(f64::NAN, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(Lu::factor(&b).is_none());
    }
}
