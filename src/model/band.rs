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
        let n = self.n();
        let (x, y) = (&x[..n], &mut y[..n]);
        for (i, row) in self.rows.iter().enumerate() {
            y[i] = row[0] * x[i];
        }
        // Rows below the band's corner in one loop of fixed length (the compiler unrolls it).
        for (i, row) in self.rows.iter().enumerate().take(BAND) {
            for k in 1..=i {
                y[i] += row[k] * x[i - k];
                y[i - k] += row[k] * x[i];
            }
        }
        for i in BAND..n {
            let row = &self.rows[i];
            let (lo, at) = (&x[i - BAND..i], x[i]);
            // In the order the products were added before (the same bits).
            let mut s = y[i];
            for k in 1..=BAND {
                s += row[k] * lo[BAND - k];
            }
            y[i] = s;
            let ylo = &mut y[i - BAND..i];
            for k in 1..=BAND {
                ylo[BAND - k] += row[k] * at;
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

    /// Row i of A's lower band.
    pub fn row(&self, i: usize) -> [f64; BAND + 1] {
        self.rows[i]
    }

    /// Rows `first`.. of the factor into `f`, whose earlier rows hold L's; false if a pivot
    /// is not positive or not finite.
    fn factor_rows(&self, f: &mut BandCholesky, first_row: usize) -> bool {
        for i in first_row..self.n() {
            let Some(row) = factor_row(&self.rows[i], i, |j| f.l[j]) else {
                return false;
            };
            f.l[i] = row;
            f.inv[i] = 1.0 / row[0];
        }
        true
    }
}

/// Row i of the Cholesky factor L of A from A's row i (`a`, its lower band) and L's rows
/// before it (`l(j)`, j < i): L_ij = (A_ij − Σ_p L_ip L_jp) / L_jj and L_ii = √(A_ii − Σ_p
/// L_ip²) (Golub & Van Loan, alg. 4.3.5). `None` if the pivot is not positive or not finite.
fn factor_row(
    a: &[f64; BAND + 1],
    i: usize,
    l: impl Fn(usize) -> [f64; BAND + 1],
) -> Option<[f64; BAND + 1]> {
    let first = i.saturating_sub(BAND);
    let mut row = [0.0; BAND + 1];
    for j in first..i {
        let lj = l(j);
        let mut s = a[i - j];
        for p in first..j {
            s -= row[i - p] * lj[j - p];
        }
        row[i - j] = s / lj[0];
    }
    let mut d = a[0];
    for p in first..i {
        d -= row[i - p] * row[i - p];
    }
    if !(d > 0.0 && d.is_finite()) {
        return None;
    }
    row[0] = d.sqrt();
    Some(row)
}

/// The factor L of A = L Lᵀ, banded as A.
#[derive(Clone, Debug, PartialEq)]
pub struct BandCholesky {
    l: Vec<[f64; BAND + 1]>,
    /// 1/L_ii: the substitutions multiply, as a division on their chain of dependent rows
    /// costs several times a multiplication's latency.
    inv: Vec<f64>,
}

impl BandCholesky {
    /// Solves A x = b in place (`b` becomes x).
    pub fn solve_in_place(&self, b: &mut [f64]) {
        substitute(self.l.len(), |i| (&self.l[i], self.inv[i]), [b]);
    }

    /// [`solve_in_place`](Self::solve_in_place) for two right-hand sides at once, each as
    /// that solves it: the two chains of dependent rows interleave.
    pub fn solve2_in_place(&self, b: &mut [f64], c: &mut [f64]) {
        substitute(self.l.len(), |i| (&self.l[i], self.inv[i]), [b, c]);
    }

    /// The factor of A + E from A's, `self`, where E lives in the last two rows and columns
    /// only: `last` are those two rows of A + E (lower band). Row i of L depends on A's rows
    /// 0..=i alone, so L's other rows are A's and only these two are computed, bit for bit as
    /// [`Band::cholesky`] of A + E would. No allocation. `None` if A + E is not positive
    /// definite there (or A has fewer than two rows).
    pub fn with_last_rows(&self, last: [[f64; BAND + 1]; 2]) -> Option<TailCholesky<'_>> {
        let n = self.l.len();
        if n < 2 {
            return None;
        }
        let second = factor_row(&last[0], n - 2, |j| self.l[j])?;
        let end = factor_row(&last[1], n - 1, |j| if j == n - 2 { second } else { self.l[j] })?;
        Some(TailCholesky { head: self, tail: [second, end], inv: [1.0 / second[0], 1.0 / end[0]] })
    }
}

/// Solves L Lᵀ x = b in place for each of the K right-hand sides `bs`, L's row i and 1/L_ii
/// given by `row(i)`: forward, then back substitution. The K chains of dependent rows are
/// independent and interleave (a chain's row waits on the latency of the one before).
fn substitute<'r, const K: usize>(
    n: usize,
    row: impl Fn(usize) -> (&'r [f64; BAND + 1], f64),
    mut bs: [&mut [f64]; K],
) {
    debug_assert!(bs.iter().all(|b| b.len() == n));
    for i in 0..n {
        let (li, inv) = row(i);
        let mut s: [f64; K] = std::array::from_fn(|k| bs[k][i]);
        for p in i.saturating_sub(BAND)..i {
            for (s, b) in s.iter_mut().zip(bs.iter()) {
                *s -= li[i - p] * b[p];
            }
        }
        for (s, b) in s.iter().zip(bs.iter_mut()) {
            b[i] = s * inv;
        }
    }
    for i in (0..n).rev() {
        let mut s: [f64; K] = std::array::from_fn(|k| bs[k][i]);
        for p in i + 1..n.min(i + BAND + 1) {
            let lp = row(p).0;
            for (s, b) in s.iter_mut().zip(bs.iter()) {
                *s -= lp[p - i] * b[p];
            }
        }
        let inv = row(i).1;
        for (s, b) in s.iter().zip(bs.iter_mut()) {
            b[i] = s * inv;
        }
    }
}

/// A Cholesky factor whose last two rows replace those of another's
/// ([`BandCholesky::with_last_rows`]).
pub struct TailCholesky<'a> {
    head: &'a BandCholesky,
    tail: [[f64; BAND + 1]; 2],
    inv: [f64; 2],
}

impl TailCholesky<'_> {
    /// Row i of L and 1/L_ii.
    #[inline]
    fn row(&self, i: usize) -> (&[f64; BAND + 1], f64) {
        let n = self.head.l.len();
        if i + 2 >= n {
            let k = i + 2 - n;
            (&self.tail[k], self.inv[k])
        } else {
            (&self.head.l[i], self.head.inv[i])
        }
    }

    /// Solves (A + E) x = b in place, as [`BandCholesky::solve_in_place`] would with the
    /// full factor.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        substitute(self.head.l.len(), |i| self.row(i), [b]);
    }

    /// Solves (A + E) x = b and (A + E) y = c in place, the two chains interleaved.
    pub fn solve2_in_place(&self, b: &mut [f64], c: &mut [f64]) {
        substitute(self.head.l.len(), |i| self.row(i), [b, c]);
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
            let want = dense.clone().lu().solve(&yv).unwrap();
            let got = DVector::from_vec(b.clone());
            assert!((got - &want).norm() <= 1e-12 * want.norm(), "n = {n}");
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
                changed.add(n - 1, n - 1, 0.75);
                let full = changed.cholesky().unwrap();
                let base = a.cholesky().unwrap();
                let tail = base.with_last_rows([changed.row(n - 2), changed.row(n - 1)]).unwrap();
                let (mut u, mut v) = (y.clone(), x.clone());
                tail.solve2_in_place(&mut u, &mut v);
                let (mut u_full, mut v_full) = (y.clone(), x.clone());
                full.solve2_in_place(&mut u_full, &mut v_full);
                assert_eq!((u, v), (u_full, v_full), "n = {n}");
            }
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
