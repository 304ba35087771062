//! Dense LU with partial pivoting for the Newton matrices, and the inverse it gives,
//! through which the Newton iteration solves.
//!
//! nalgebra's `LU` needs typenum bounds (`Const<N>: DimMin`) that a generic `const N` cannot
//! name, and this is twenty lines (Golub & Van Loan, *Matrix Computations*, alg. 3.4.1).

use super::error::SolverError;
use super::snapshot::{require, require_finite, visit_usize, StateVisitor};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector, U1};

/// The factors of a square matrix of dimension `D`, fixed (`Const<N>`, on the stack) or
/// dynamic (`Dyn`). The factors and the inverse are kept row by row in the flat, row-major
/// buffer of a `D×D` matrix (the matrix holds their transposes, nalgebra being
/// column-major): the loops index `i·n + j`, and for a fixed `D` the compiler sees `n` and
/// the buffer's length as constants, unrolls them and drops the bounds checks.
#[derive(Clone, Debug, PartialEq)]
pub struct Lu<D: Dim>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// The rows of L (unit lower, below the diagonal) and U (above it), row-permuted; the
    /// diagonal holds the reciprocals of U's pivots, so that a solve multiplies where it
    /// would divide (the back substitution's divisions are a chain, each waiting for the one
    /// before). Row-major rather than a matrix: a row swap moves one row, and the loops
    /// index in bounds the compiler can see (nalgebra's indexing checks each access).
    rows: OMatrix<f64, D, D>,
    /// Row `i` of the factors is row `perm[i]` of the original matrix.
    perm: OVector<usize, D>,
    /// The inverse A⁻¹ by rows, from the factors, for a fixed dimension: [`solve`](Self::solve)
    /// is then one matrix-vector product, whose N² products are independent, where the
    /// substitutions are a chain of N steps of dependent products (the solve sits on the
    /// Newton iteration's chain: f, residual, solve, correction, f again). A run-time
    /// dimension (many states) solves by substitution, also N² products, and spares the N³
    /// of the inverse at every factorisation. Derived from the factors and the permutation,
    /// not part of a saved state; empty without it.
    inverse: OMatrix<f64, D, D>,
}

// Index loops throughout: with a fixed dimension their bounds are constants; they unroll,
// and the bounds checks go.
#[allow(clippy::needless_range_loop)]
impl<D: Dim> Lu<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// Factors `a`; `None` if a pivot is zero, non-finite or below round-off of ‖a‖, or its
    /// reciprocal is not finite.
    pub fn factor(a: &OMatrix<f64, D, D>) -> Option<Self> {
        let (d, _) = a.shape_generic();
        let n = d.value();
        // Aᵀ in column-major order is A row by row.
        let mut rows = a.transpose();
        let f = rows.as_mut_slice();
        let mut perm = OVector::<usize, D>::from_fn_generic(d, U1, |i, _| i);
        // max |a_ij|, NaN entries passed over (as f64::max does; the pivot test then refuses
        // them), on the rows: nalgebra's matrix iterator was several times slower here.
        let mut scale = 0.0f64;
        for x in f.iter() {
            if x.abs() > scale {
                scale = x.abs();
            }
        }
        let tiny = scale * f64::EPSILON * n as f64;
        for k in 0..n {
            let (mut piv, mut best) = (k, f[k * n + k].abs());
            for i in k + 1..n {
                if f[i * n + k].abs() > best {
                    piv = i;
                    best = f[i * n + k].abs();
                }
            }
            if !(best.is_finite() && best > tiny) {
                return None;
            }
            if piv != k {
                for j in 0..n {
                    f.swap(k * n + j, piv * n + j);
                }
                perm.swap_rows(k, piv);
            }
            let inv = 1.0 / f[k * n + k];
            if !inv.is_finite() {
                return None;
            }
            f[k * n + k] = inv;
            // Rows below k minus multiples of row k, as slices: no index checks in the inner
            // loop for a run-time dimension either.
            let (upper, lower) = f.split_at_mut((k + 1) * n);
            let pivot_row = &upper[k * n + k + 1..];
            for row in lower.chunks_exact_mut(n) {
                let m = row[k] * inv;
                row[k] = m;
                for (x, u) in row[k + 1..].iter_mut().zip(pivot_row) {
                    *x -= m * u;
                }
            }
        }
        let inverse = OMatrix::<f64, D, D>::zeros_generic(d, d);
        let mut lu = Self { rows, perm, inverse };
        lu.inverse = lu.invert();
        Some(lu)
    }

    fn n(&self) -> usize {
        self.rows.nrows()
    }

    /// Whether the solves go through the inverse: with a dimension fixed at compile time.
    fn keeps_inverse() -> bool {
        D::try_to_usize().is_some()
    }

    /// A⁻¹ by rows: column k is the substitutions' solution of A x = e_k; an empty matrix
    /// where the solves do without it ([`keeps_inverse`](Self::keeps_inverse)).
    fn invert(&self) -> OMatrix<f64, D, D> {
        let (d, _) = self.rows.shape_generic();
        if !Self::keeps_inverse() {
            let empty = D::from_usize(0);
            return OMatrix::<f64, D, D>::zeros_generic(empty, empty);
        }
        let n = self.n();
        let mut inverse = OMatrix::<f64, D, D>::zeros_generic(d, d);
        let inv = inverse.as_mut_slice();
        let mut e = OVector::<f64, D>::zeros_generic(d, U1);
        for k in 0..n {
            e.fill(0.0);
            e[k] = 1.0;
            let x = self.substitute(&e);
            for i in 0..n {
                inv[i * n + k] = x[i];
            }
        }
        inverse
    }

    /// Solves `a x = b` by forward and back substitution on the factors.
    fn substitute(&self, b: &OVector<f64, D>) -> OVector<f64, D> {
        let mut x = b.clone();
        self.substitute_in_place(x.as_mut_slice());
        x
    }

    /// Solves `a x = b` in place (`b` of the matrix's dimension) by forward and back
    /// substitution on the factors.
    fn substitute_in_place(&self, b: &mut [f64]) {
        let n = self.n();
        let f = self.rows.as_slice();
        // The permuted right-hand side: on the stack up to 128 entries, else on the heap.
        let (mut stack, mut heap) = ([0.0; 128], Vec::new());
        let x = if n <= stack.len() {
            &mut stack[..n]
        } else {
            heap.resize(n, 0.0);
            &mut heap[..]
        };
        for (x, &p) in x.iter_mut().zip(self.perm.iter()) {
            *x = b[p];
        }
        // Entry by entry in order, as the index loops did (the same bits).
        for (i, row) in f.chunks_exact(n).enumerate() {
            let (done, rest) = x.split_at_mut(i);
            for (l, x) in row[..i].iter().zip(done.iter()) {
                rest[0] -= l * x;
            }
        }
        for (i, row) in f.chunks_exact(n).enumerate().rev() {
            let (head, done) = x.split_at_mut(i + 1);
            for (u, x) in row[i + 1..].iter().zip(done.iter()) {
                head[i] -= u * x;
            }
            head[i] *= row[i];
        }
        b.copy_from_slice(x);
    }

    /// A stand-in for the fields of an absent LU of dimension `d` when a state is visited:
    /// zero factors and the identity permutation.
    pub(crate) fn placeholder(d: D) -> Self {
        Self {
            rows: OMatrix::<f64, D, D>::zeros_generic(d, d),
            perm: OVector::<usize, D>::from_fn_generic(d, U1, |i, _| i),
            inverse: OMatrix::<f64, D, D>::zeros_generic(d, d),
        }
    }

    /// Whether this is bit for bit the [`placeholder`](Self::placeholder).
    pub(crate) fn is_placeholder(&self) -> bool {
        self.rows.iter().all(|x| x.to_bits() == 0)
            && self.perm.iter().enumerate().all(|(i, p)| *p == i)
    }

    /// Visits the factors (column-major), then the permutation; the inverse follows from
    /// them (zeros while the permutation is not one, which [`check`](Self::check) refuses).
    pub(crate) fn visit<V: StateVisitor + ?Sized>(&mut self, v: &mut V) {
        let n = self.n();
        let f = self.rows.as_mut_slice();
        for j in 0..n {
            for i in 0..n {
                v.real("lu.factors", &mut f[i * n + j]);
            }
        }
        for p in self.perm.iter_mut() {
            visit_usize(v, "lu.perm", p);
        }
        self.inverse = if self.check_perm().is_ok() {
            self.invert()
        } else {
            let (d, _) = self.rows.shape_generic();
            let d = if Self::keeps_inverse() { d } else { D::from_usize(0) };
            OMatrix::<f64, D, D>::zeros_generic(d, d)
        };
    }

    /// What [`factor`](Self::factor) guarantees: finite factors, non-zero (reciprocal)
    /// pivots, and a permutation of 0..N (so [`solve`](Self::solve) indexes in range).
    pub(crate) fn check(&self) -> Result<(), SolverError> {
        let n = self.n();
        let f = self.rows.as_slice();
        require_finite(f.iter(), "lu.factors")?;
        require((0..n).all(|i| f[i * n + i] != 0.0), "lu.factors")?;
        self.check_perm()
    }

    fn check_perm(&self) -> Result<(), SolverError> {
        let n = self.n();
        let mut seen = vec![false; n];
        for &p in self.perm.iter() {
            require(p < n && !seen[p], "lu.perm")?;
            seen[p] = true;
        }
        Ok(())
    }

    /// Solves `a x = b`: x = A⁻¹ b.
    pub fn solve(&self, b: &OVector<f64, D>) -> OVector<f64, D> {
        if !Self::keeps_inverse() {
            return self.substitute(b);
        }
        let n = self.n();
        let inv = self.inverse.as_slice();
        OVector::<f64, D>::from_fn_generic(b.shape_generic().0, U1, |i, _| {
            let row = &inv[i * n..(i + 1) * n];
            let mut x = 0.0;
            for j in 0..n {
                x += row[j] * b[j];
            }
            x
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, SMatrix, Vector3};

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
        let inv = lu.inverse.transpose();
        assert!((inv * a - SMatrix::<f64, 3, 3>::identity()).norm() < 1e-14);
        let b = Vector3::new(0.3, -1.0, 2.5);
        let by_substitution = lu.substitute(&b);
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
