//! Symmetric banded matrices of half-bandwidth 3, the shape of a beam of cubic Hermite
//! elements (two coordinates per node, each node coupled to its neighbours): the product, the
//! quadratic form and the Cholesky factorisation, each in O(n) for n rows.
//!
//! Storage: row i holds the entries A[i][i − k] for k = 0..=3 (k ≤ i), the lower band; the
//! upper half follows by symmetry. The Cholesky factor L (A = L Lᵀ) has the same shape
//! (Golub & Van Loan, *Matrix Computations*, 4th ed., alg. 4.3.5, band Cholesky).

/// The half-bandwidth: entries with |i − j| > BAND are zero.
pub const BAND: usize = 3;

/// A symmetric banded matrix by its lower band.
#[derive(Clone, Debug, PartialEq)]
pub struct Band {
    rows: Vec<[f64; BAND + 1]>,
}

#[allow(clippy::needless_range_loop)]
impl Band {
    /// The n×n zero matrix.
    pub fn zeros(n: usize) -> Self {
        Self { rows: vec![[0.0; BAND + 1]; n] }
    }

    pub fn n(&self) -> usize {
        self.rows.len()
    }

    /// A[i][j] for |i − j| ≤ BAND (0 outside the band).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (hi, lo) = if i >= j { (i, j) } else { (j, i) };
        if hi - lo > BAND {
            return 0.0;
        }
        self.rows[hi][hi - lo]
    }

    /// Adds `x` to A[i][j] and, by symmetry, to A[j][i] (once on the diagonal).
    pub fn add(&mut self, i: usize, j: usize, x: f64) {
        let (hi, lo) = if i >= j { (i, j) } else { (j, i) };
        assert!(hi - lo <= BAND, "({i}, {j}) is outside the band");
        self.rows[hi][hi - lo] += x;
    }

    /// `self + s·other`.
    pub fn plus_scaled(&self, s: f64, other: &Band) -> Band {
        let rows = self
            .rows
            .iter()
            .zip(&other.rows)
            .map(|(a, b)| std::array::from_fn(|k| a[k] + s * b[k]))
            .collect();
        Band { rows }
    }

    /// A·x into `y`.
    pub fn mul_into(&self, x: &[f64], y: &mut [f64]) {
        debug_assert!(x.len() == self.n() && y.len() == self.n());
        for (i, row) in self.rows.iter().enumerate() {
            y[i] = row[0] * x[i];
        }
        for (i, row) in self.rows.iter().enumerate() {
            for k in 1..=BAND.min(i) {
                let j = i - k;
                y[i] += row[k] * x[j];
                y[j] += row[k] * x[i];
            }
        }
    }

    /// A·x.
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n()];
        self.mul_into(x, &mut y);
        y
    }

    /// xᵀ A y.
    pub fn form(&self, x: &[f64], y: &[f64]) -> f64 {
        let mut s = 0.0;
        for (i, row) in self.rows.iter().enumerate() {
            s += row[0] * x[i] * y[i];
            for k in 1..=BAND.min(i) {
                let j = i - k;
                s += row[k] * (x[i] * y[j] + x[j] * y[i]);
            }
        }
        s
    }

    /// The Cholesky factor of a positive definite A; `None` if a pivot is not positive
    /// (A not positive definite) or not finite.
    pub fn cholesky(&self) -> Option<BandCholesky> {
        let mut f = BandCholesky { l: vec![[0.0; BAND + 1]; self.n()], inv: vec![0.0; self.n()] };
        self.factor_rows(&mut f, 0).then_some(f)
    }

    /// [`cholesky`](Self::cholesky) from `prefix`, the factor of a matrix whose rows before
    /// `first` are A's: row i of L depends on A's rows 0..=i only, so those rows are taken
    /// as they are and the rest computed, bit for bit as `cholesky` would. O(n − first) but
    /// for the copy. (For a beam whose tip block alone changes.)
    pub fn cholesky_after(&self, prefix: &BandCholesky, first: usize) -> Option<BandCholesky> {
        debug_assert!(prefix.l.len() == self.n() && first <= self.n());
        let mut f = prefix.clone();
        self.factor_rows(&mut f, first).then_some(f)
    }

    /// Rows `first`.. of the factor into `l`, whose earlier rows hold L's; false if a pivot
    /// is not positive or not finite.
    fn factor_rows(&self, f: &mut BandCholesky, first_row: usize) -> bool {
        let l = &mut f.l;
        for i in first_row..self.n() {
            let first = i.saturating_sub(BAND);
            for j in first..i {
                // L_ij = (A_ij − Σ_{p=first..j−1} L_ip L_jp) / L_jj
                let mut s = self.rows[i][i - j];
                for p in first..j {
                    s -= l[i][i - p] * l[j][j - p];
                }
                l[i][i - j] = s / l[j][0];
            }
            let mut d = self.rows[i][0];
            for p in first..i {
                d -= l[i][i - p] * l[i][i - p];
            }
            if !(d > 0.0 && d.is_finite()) {
                return false;
            }
            l[i][0] = d.sqrt();
            f.inv[i] = 1.0 / l[i][0];
        }
        true
    }
}

/// The factor L of A = L Lᵀ, banded as A.
#[derive(Clone, Debug, PartialEq)]
pub struct BandCholesky {
    l: Vec<[f64; BAND + 1]>,
    /// 1/L_ii: the substitutions multiply, as a division on their chain of dependent rows
    /// costs several times a multiplication's latency.
    inv: Vec<f64>,
}

#[allow(clippy::needless_range_loop)]
impl BandCholesky {
    /// Solves A x = b in place (`b` becomes x).
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.l.len();
        for i in 0..n {
            let mut s = b[i];
            for p in i.saturating_sub(BAND)..i {
                s -= self.l[i][i - p] * b[p];
            }
            b[i] = s * self.inv[i];
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for p in i + 1..n.min(i + BAND + 1) {
                s -= self.l[p][p - i] * b[p];
            }
            b[i] = s * self.inv[i];
        }
    }

    /// [`solve_in_place`](Self::solve_in_place) for two right-hand sides at once, each as
    /// that solves it: the two chains of dependent rows interleave.
    pub fn solve2_in_place(&self, b: &mut [f64], c: &mut [f64]) {
        let n = self.l.len();
        debug_assert!(b.len() == n && c.len() == n);
        for i in 0..n {
            let (mut s, mut t) = (b[i], c[i]);
            for p in i.saturating_sub(BAND)..i {
                s -= self.l[i][i - p] * b[p];
                t -= self.l[i][i - p] * c[p];
            }
            b[i] = s * self.inv[i];
            c[i] = t * self.inv[i];
        }
        for i in (0..n).rev() {
            let (mut s, mut t) = (b[i], c[i]);
            for p in i + 1..n.min(i + BAND + 1) {
                s -= self.l[p][p - i] * b[p];
                t -= self.l[p][p - i] * c[p];
            }
            b[i] = s * self.inv[i];
            c[i] = t * self.inv[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// A random symmetric positive definite banded matrix and its dense copy.
    fn random(n: usize, seed: u64) -> (Band, DMatrix<f64>) {
        let mut uniform = crate::math::test_sequence(seed);
        let mut next = || uniform() - 0.5;
        let mut a = Band::zeros(n);
        for i in 0..n {
            a.add(i, i, 4.0 + next());
            for k in 1..=BAND.min(i) {
                a.add(i, i - k, 0.5 * next());
            }
        }
        let dense = DMatrix::from_fn(n, n, |i, j| a.get(i, j));
        (a, dense)
    }

    #[test]
    fn product_form_and_solve_match_dense_algebra() {
        for (n, seed) in [(1, 1), (2, 2), (4, 3), (7, 4), (64, 5)] {
            let (a, dense) = random(n, seed);
            let x: Vec<f64> = (0..n).map(|i| 0.3 + crate::math::sin(i as f64)).collect();
            let y: Vec<f64> = (0..n).map(|i| crate::math::cos(i as f64 * 0.7)).collect();
            let (xv, yv) = (DVector::from_vec(x.clone()), DVector::from_vec(y.clone()));
            let ax = &dense * &xv;
            let ours = a.mul(&x);
            assert!((DVector::from_vec(ours) - &ax).norm() <= 1e-13 * ax.norm());
            let form = xv.dot(&(&dense * &yv));
            assert!((a.form(&x, &y) - form).abs() <= 1e-13 * form.abs().max(1.0));
            let mut b = y.clone();
            a.cholesky().unwrap().solve_in_place(&mut b);
            let (mut b2, mut x2) = (y.clone(), x.clone());
            a.cholesky().unwrap().solve2_in_place(&mut b2, &mut x2);
            let mut x1 = x.clone();
            a.cholesky().unwrap().solve_in_place(&mut x1);
            assert_eq!((&b2, &x2), (&b, &x1));
            // The factor of a matrix that differs in its last two rows, from this one's.
            if n >= 2 {
                let mut changed = a.clone();
                changed.add(n - 2, n - 2, 1.5);
                changed.add(n - 1, n - 2, -0.25);
                let full = changed.cholesky().unwrap();
                assert_eq!(changed.cholesky_after(&a.cholesky().unwrap(), n - 2).unwrap(), full);
                assert_ne!(changed.cholesky_after(&a.cholesky().unwrap(), n - 1).unwrap(), full);
            }
            let want = dense.clone().lu().solve(&yv).unwrap();
            assert!((DVector::from_vec(b) - &want).norm() <= 1e-12 * want.norm(), "n = {n}");
        }
    }

    #[test]
    fn an_indefinite_matrix_has_no_cholesky_factor() {
        let mut a = Band::zeros(3);
        a.add(0, 0, 1.0);
        a.add(1, 1, 1.0);
        a.add(1, 0, 2.0);
        a.add(2, 2, 1.0);
        assert!(a.cholesky().is_none());
        assert!(Band::zeros(2).cholesky().is_none());
    }
}
