//! General (not necessarily symmetric) band matrices of half-bandwidth [`P`] and their LU with
//! partial pivoting, in O(n) for n rows: the Newton matrix of a mechanical system whose
//! coordinates couple only to their neighbours ([`super::SecondOrder`]).
//!
//! Storage: row i holds A[i][j] for j = i − P ..= i + 2P at index j − i + P; the P extra
//! superdiagonals take the fill-in of the row interchanges (LAPACK's dgbtrf keeps the same
//! room; Golub & Van Loan, *Matrix Computations*, 4th ed., §4.3.5, band LU with pivoting).

/// The half-bandwidth of the matrix before factorisation: A[i][j] = 0 for |i − j| > P.
pub const P: usize = 3;
const WIDTH: usize = 3 * P + 1;

/// A band matrix, or its LU factors in place.
#[derive(Clone, Debug, PartialEq)]
pub struct GenBand {
    rows: Vec<[f64; WIDTH]>,
}

/// The LU factors of a [`GenBand`] with its row interchanges.
#[derive(Clone, Debug, PartialEq)]
pub struct BandLu {
    lu: GenBand,
    perm: Vec<usize>,
    /// 1/U_kk.
    inv_pivot: Vec<f64>,
}

#[allow(clippy::needless_range_loop)]
impl GenBand {
    /// The n×n zero matrix.
    pub fn zeros(n: usize) -> Self {
        Self { rows: vec![[0.0; WIDTH]; n] }
    }

    pub fn n(&self) -> usize {
        self.rows.len()
    }

    /// Every stored entry, row by row (the fill-in room included): for a saved state.
    pub(crate) fn entries_mut(&mut self) -> impl Iterator<Item = &mut f64> {
        self.rows.iter_mut().flatten()
    }

    /// Whether every stored entry is finite.
    pub(crate) fn is_finite(&self) -> bool {
        self.rows.iter().flatten().all(|x| x.is_finite())
    }

    /// A[i][j]; 0 outside the band.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        if j + P < i || j > i + 2 * P {
            return 0.0;
        }
        self.rows[i][j + P - i]
    }

    /// Adds `x` to A[i][j], |i − j| ≤ P.
    pub fn add(&mut self, i: usize, j: usize, x: f64) {
        debug_assert!(i.abs_diff(j) <= P, "({i}, {j}) is outside the band");
        self.rows[i][j + P - i] += x;
    }

    /// `self += s·other`.
    pub fn add_scaled(&mut self, s: f64, other: &GenBand) {
        for (a, b) in self.rows.iter_mut().zip(&other.rows) {
            for (x, y) in a.iter_mut().zip(b) {
                *x += s * y;
            }
        }
    }

    /// s·A·x added to `y`.
    pub fn mul_add(&self, s: f64, x: &[f64], y: &mut [f64]) {
        let n = self.n();
        for (i, (row, yi)) in self.rows.iter().zip(y.iter_mut()).enumerate() {
            let mut sum = 0.0;
            if let Some(window) = x.get(i.wrapping_sub(P)..i + P + 1) {
                // An inner row: the whole band, a fixed-length loop (the same sums in the same
                // order as the clipped loop below).
                for (a, b) in row.iter().zip(window) {
                    sum += a * b;
                }
            } else {
                let lo = i.saturating_sub(P);
                let hi = (i + P).min(n - 1);
                for j in lo..=hi {
                    sum += row[j + P - i] * x[j];
                }
            }
            *yi += s * sum;
        }
    }

    /// The LU factors with partial pivoting; `None` if a pivot is zero or a factor is not
    /// finite (the matrix is singular, or not finite).
    pub fn lu(&self) -> Option<BandLu> {
        let n = self.n();
        let mut a = self.clone();
        let mut perm = vec![0; n];
        for k in 0..n {
            // The pivot: the largest |A[i][k]| for i = k ..= k + P.
            let last = (k + P).min(n - 1);
            let mut p = k;
            for i in k + 1..=last {
                if a.get(i, k).abs() > a.get(p, k).abs() {
                    p = i;
                }
            }
            perm[k] = p;
            let pivot = a.get(p, k);
            if pivot == 0.0 || !pivot.is_finite() {
                return None;
            }
            let right = (k + 2 * P).min(n - 1);
            if p != k {
                for j in k..=right {
                    let (x, y) = (a.get(k, j), a.get(p, j));
                    a.rows[k][j + P - k] = y;
                    if j <= p + 2 * P {
                        a.rows[p][j + P - p] = x;
                    }
                }
            }
            for i in k + 1..=last {
                let m = a.get(i, k) / pivot;
                a.rows[i][k + P - i] = m;
                if m != 0.0 {
                    for j in k + 1..=right {
                        let akj = a.rows[k][j + P - k];
                        a.rows[i][j + P - i] -= m * akj;
                    }
                }
            }
        }
        // The pivots' reciprocals: the back substitution multiplies (a division on its
        // chain of dependent rows costs several times a multiplication's latency).
        let inv_pivot = (0..n).map(|k| 1.0 / a.rows[k][P]).collect();
        a.is_finite().then_some(BandLu { lu: a, perm, inv_pivot })
    }
}

#[allow(clippy::needless_range_loop)]
impl BandLu {
    /// Solves A x = b in place.
    pub fn solve(&self, b: &mut [f64]) {
        let n = self.lu.n();
        let a = &self.lu;
        // L y = P b: the interchanges in the order they were made.
        for k in 0..n {
            let p = self.perm[k];
            if p != k {
                b.swap(k, p);
            }
            let last = (k + P).min(n - 1);
            let bk = b[k];
            for i in k + 1..=last {
                b[i] -= a.rows[i][k + P - i] * bk;
            }
        }
        // U x = y.
        for k in (0..n).rev() {
            let right = (k + 2 * P).min(n - 1);
            let mut s = b[k];
            for j in k + 1..=right {
                s -= a.rows[k][j + P - k] * b[j];
            }
            b[k] = s * self.inv_pivot[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// A pseudo-random band matrix (a small LCG) and its dense copy; `weak` makes the diagonal
    /// small, so that the factorisation has to interchange rows.
    fn random(n: usize, seed: u64, weak: bool) -> (GenBand, DMatrix<f64>) {
        let mut uniform = crate::math::test_sequence(seed);
        let mut next = || uniform() - 0.5;
        let mut band = GenBand::zeros(n);
        for i in 0..n {
            for j in i.saturating_sub(P)..=(i + P).min(n - 1) {
                let x = if i == j && !weak { 4.0 + next() } else { next() };
                band.add(i, j, x);
            }
        }
        let dense = DMatrix::from_fn(n, n, |i, j| band.get(i, j));
        (band, dense)
    }

    #[test]
    fn lu_solves_like_a_dense_lu_with_and_without_interchanges() {
        for (n, seed, weak) in [(1, 1, false), (5, 2, true), (16, 3, false), (40, 4, true)] {
            let (band, dense) = random(n, seed, weak);
            let b = DVector::from_fn(n, |i, _| crate::math::sin(i as f64 * 0.7) + 0.3);
            let want = dense.clone().lu().solve(&b).unwrap();
            let mut x: Vec<f64> = b.iter().copied().collect();
            band.lu().unwrap().solve(&mut x);
            let err = (DVector::from_vec(x) - &want).amax();
            assert!(err <= 1e-11 * want.amax(), "n {n}: {err}");
            let mut y = vec![0.0; n];
            band.mul_add(1.0, want.as_slice(), &mut y);
            assert!((DVector::from_vec(y) - &b).amax() < 1e-12);
        }
    }

    #[test]
    fn a_singular_matrix_has_no_lu() {
        let mut band = GenBand::zeros(4);
        for i in 0..3 {
            band.add(i, i, 1.0);
        }
        assert!(band.lu().is_none());
        band.add(3, 3, f64::NAN);
        assert!(band.lu().is_none());
    }
}
