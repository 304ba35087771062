//! Eigenvalues of a real matrix, for the stability guard.
//!
//! The classical two-stage method: reduction to upper Hessenberg form by Gaussian
//! elimination with partial pivoting (a similarity transform), then the implicit Francis
//! double-shift QR iteration with deflation and the "exceptional" shifts after 10 and 20
//! stagnant iterations. Sources: J. H. Wilkinson and C. Reinsch, *Handbook for Automatic
//! Computation II: Linear Algebra* (1971), contributions II/13 (elmhes) and II/14 (hqr);
//! G. H. Golub and C. F. Van Loan, *Matrix Computations*, 4th ed., §7.4–7.5.
//!
//! nalgebra's Schur form does the same job generically; for the 4×4 and 6×6 Jacobians of the
//! model it costs about five times as much and allocates, and the guard runs at every
//! Jacobian evaluation. The unit tests check this routine against nalgebra.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OMatrix};

/// Iterations allowed in all before giving up: LAPACK dlahqr's ITMAX = 30·max(10, N). Some
/// matrices need more than EISPACK's 30 per eigenvalue (a random 4×4 in the tests needs 35).
const fn max_iterations(n: usize) -> usize {
    30 * if n > 10 { n } else { 10 }
}
/// An exceptional shift after every this many iterations without a deflation (dlahqr's
/// KEXSH; EISPACK hqr shifts at 10 and 20 only).
const EXCEPTIONAL_SHIFT_EVERY: usize = 10;

/// `|a|` with the sign of `b` (Fortran's SIGN).
fn with_sign(a: f64, b: f64) -> f64 {
    if b >= 0.0 {
        a.abs()
    } else {
        -a.abs()
    }
}

/// Reduces `a` (n×n, row-major) to upper Hessenberg form by stabilised elimination: a similarity
/// transform, so the eigenvalues are unchanged. Entries below the subdiagonal are zeroed.
fn hessenberg(a: &mut [f64], n: usize) {
    for m in 1..n.saturating_sub(1) {
        // Pivot: the largest entry of column m−1 on or below row m.
        let mut pivot = m;
        for i in m + 1..n {
            if a[i * n + m - 1].abs() > a[pivot * n + m - 1].abs() {
                pivot = i;
            }
        }
        let x = a[pivot * n + m - 1];
        if pivot != m {
            for j in 0..n {
                a.swap(pivot * n + j, m * n + j);
            }
            for row in 0..n {
                a.swap(row * n + pivot, row * n + m);
            }
        }
        if x == 0.0 {
            continue;
        }
        if n > BY_ROWS_FROM {
            eliminate_by_rows(a, n, m, x);
            continue;
        }
        for i in m + 1..n {
            let y = a[i * n + m - 1] / x;
            if y == 0.0 {
                continue;
            }
            // Row i −= y·row m, then column m += y·column i (the inverse transform).
            a[i * n + m - 1] = 0.0;
            for j in m..n {
                a[i * n + j] -= y * a[m * n + j];
            }
            for row in 0..n {
                a[row * n + m] += y * a[row * n + i];
            }
        }
    }
}

/// Above this size [`hessenberg`] applies a step's transform by rows ([`eliminate_by_rows`]):
/// the beam in 5 or more elements. Below, EISPACK's order, which the paper's model (4 and 6
/// states) has always used, bit for bit.
const BY_ROWS_FROM: usize = 16;

/// Step `m` of [`hessenberg`] (pivot `x` in place) as L⁻¹AL with L = I + Σ yᵢ eᵢ e_mᵀ, the
/// multipliers yᵢ = a[i][m−1]/x all known first: every row op (row i −= yᵢ·row m), then the
/// column op as one dot product a row (a[r][m] += Σ yᵢ a[r][i]). The same transform as
/// EISPACK's interleaved order, whose column ops stride through the matrix: at 128 states the
/// reduction took as long as the QR iteration (perf).
fn eliminate_by_rows(a: &mut [f64], n: usize, m: usize, x: f64) {
    let y: Vec<f64> = (m + 1..n).map(|i| a[i * n + m - 1] / x).collect();
    let (head, tail) = a.split_at_mut((m + 1) * n);
    let row_m = &head[m * n..(m + 1) * n];
    for (k, row) in tail.chunks_exact_mut(n).enumerate() {
        if y[k] == 0.0 {
            continue;
        }
        row[m - 1] = 0.0;
        for j in m..n {
            row[j] -= y[k] * row_m[j];
        }
    }
    for row in a.chunks_exact_mut(n) {
        let dot: f64 = row[m + 1..].iter().zip(&y).map(|(v, yk)| yk * v).sum();
        row[m] += dot;
    }
}

/// The eigenvalues of `mat` as (re, im) pairs, complex ones in conjugate pairs with the
/// positive imaginary part second; `None` if the QR iteration does not converge or `mat`
/// has non-finite entries.
// The reflections update three rows at once, indexed together.
#[allow(clippy::needless_range_loop)]
pub(crate) fn eigenvalues<D: Dim>(mat: &OMatrix<f64, D, D>) -> Option<Vec<(f64, f64)>>
where
    DefaultAllocator: Allocator<D, D>,
{
    if !mat.iter().all(|x| x.is_finite()) {
        return None;
    }
    let n = mat.nrows();
    // Mᵀ in column-major order is M row by row.
    let mut t = mat.transpose();
    let a = t.as_mut_slice();
    hessenberg(a, n);
    let mut out = vec![(0.0, 0.0); n];
    if n == 0 {
        return Some(out);
    }
    // Scale for the negligibility tests of zero diagonal blocks.
    let mut norm = 0.0;
    for i in 0..n {
        for v in &a[i * n + i.saturating_sub(1)..(i + 1) * n] {
            norm += v.abs();
        }
    }
    // `nn`: the last row of the active (undeflated) block; `shift`: the exceptional shifts
    // accumulated so far, subtracted from the diagonal.
    let mut nn = n - 1;
    let mut shift = 0.0;
    let mut iters = 0;
    let mut total = 0;
    loop {
        // The lowest l ≤ nn such that a[l * n + l−1] is negligible: rows l..=nn form the block.
        let mut l = nn;
        while l > 0 {
            let mut s = a[(l - 1) * n + l - 1].abs() + a[l * n + l].abs();
            if s == 0.0 {
                s = norm;
            }
            if a[l * n + l - 1].abs() + s == s {
                a[l * n + l - 1] = 0.0;
                break;
            }
            l -= 1;
        }
        let mut x = a[nn * n + nn];
        if l == nn {
            // A 1×1 block has split off: one real eigenvalue.
            out[nn] = (x + shift, 0.0);
            iters = 0;
            match nn.checked_sub(1) {
                Some(next) => nn = next,
                None => return Some(out),
            }
            continue;
        }
        let mut y = a[(nn - 1) * n + nn - 1];
        let mut w = a[nn * n + nn - 1] * a[(nn - 1) * n + nn];
        if l + 1 == nn {
            // A 2×2 block: its two eigenvalues in closed form.
            let p = 0.5 * (y - x);
            let q = p * p + w;
            let z = q.abs().sqrt();
            x += shift;
            if q >= 0.0 {
                let z = p + with_sign(z, p);
                let second = if z != 0.0 { x - w / z } else { x + z };
                out[nn - 1] = (x + z, 0.0);
                out[nn] = (second, 0.0);
            } else {
                out[nn - 1] = (x + p, -z);
                out[nn] = (x + p, z);
            }
            iters = 0;
            match nn.checked_sub(2) {
                Some(next) => nn = next,
                None => return Some(out),
            }
            continue;
        }
        if total == max_iterations(n) {
            return None;
        }
        if iters > 0 && iters % EXCEPTIONAL_SHIFT_EVERY == 0 {
            // Exceptional shift, to break a cycle (Wilkinson & Reinsch II/14).
            shift += x;
            for i in 0..=nn {
                a[i * n + i] -= x;
            }
            let s = a[nn * n + nn - 1].abs() + a[(nn - 1) * n + nn - 2].abs();
            x = 0.75 * s;
            y = x;
            w = -0.4375 * s * s;
        }
        iters += 1;
        total += 1;
        // The double shift is by the eigenvalues of the trailing 2×2 block (x, y, w). Start
        // the bulge at the lowest m ≥ l where two consecutive small subdiagonals allow it.
        let mut m = nn - 2;
        let (mut p, mut q, mut r);
        loop {
            let z = a[m * n + m];
            let (rr, ss) = (x - z, y - z);
            p = (rr * ss - w) / a[(m + 1) * n + m] + a[m * n + m + 1];
            q = a[(m + 1) * n + m + 1] - z - rr - ss;
            r = a[(m + 2) * n + m + 1];
            let s = p.abs() + q.abs() + r.abs();
            p /= s;
            q /= s;
            r /= s;
            if m == l {
                break;
            }
            let u = a[m * n + m - 1].abs() * (q.abs() + r.abs());
            let v =
                p.abs() * (a[(m - 1) * n + m - 1].abs() + z.abs() + a[(m + 1) * n + m + 1].abs());
            if u + v == v {
                break;
            }
            m -= 1;
        }
        for i in m + 2..=nn {
            a[i * n + i - 2] = 0.0;
            if i != m + 2 {
                a[i * n + i - 3] = 0.0;
            }
        }
        // Chase the bulge down with 3×3 Householder reflections (rows k..k+2).
        for k in m..nn {
            let last = k + 1 == nn;
            let mut scale = 1.0;
            if k != m {
                p = a[k * n + k - 1];
                q = a[(k + 1) * n + k - 1];
                r = if last { 0.0 } else { a[(k + 2) * n + k - 1] };
                scale = p.abs() + q.abs() + r.abs();
                if scale == 0.0 {
                    continue;
                }
                p /= scale;
                q /= scale;
                r /= scale;
            }
            let s = with_sign((p * p + q * q + r * r).sqrt(), p);
            if s == 0.0 {
                continue;
            }
            if k == m {
                if l != m {
                    a[k * n + k - 1] = -a[k * n + k - 1];
                }
            } else {
                a[k * n + k - 1] = -s * scale;
            }
            p += s;
            let (vx, vy, vz) = (p / s, q / s, r / s);
            q /= p;
            r /= p;
            for j in k..=nn {
                let mut t = a[k * n + j] + q * a[(k + 1) * n + j];
                if !last {
                    t += r * a[(k + 2) * n + j];
                    a[(k + 2) * n + j] -= t * vz;
                }
                a[(k + 1) * n + j] -= t * vy;
                a[k * n + j] -= t * vx;
            }
            for i in l..=nn.min(k + 3) {
                let row = &mut a[i * n..(i + 1) * n];
                let mut t = vx * row[k] + vy * row[k + 1];
                if !last {
                    t += vz * row[k + 2];
                    row[k + 2] -= t * r;
                }
                row[k + 1] -= t * q;
                row[k] -= t;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;
    use nalgebra::{DMatrix, SMatrix};

    /// Sorted (re, im) of nalgebra's Schur form, the reference.
    fn reference(m: &[f64], n: usize) -> Vec<(f64, f64)> {
        let d = DMatrix::from_row_slice(n, n, m);
        let s = nalgebra::Schur::try_new(d, 1e-15, 10_000).expect("nalgebra Schur");
        let mut v: Vec<_> = s.complex_eigenvalues().iter().map(|c| (c.re, c.im)).collect();
        v.sort_by(|a, b| a.partial_cmp(b).unwrap());
        v
    }

    fn ours<const N: usize>(m: &[f64]) -> Vec<(f64, f64)> {
        let mut v = eigenvalues(&SMatrix::<f64, N, N>::from_row_slice(m)).expect("converges");
        v.sort_by(|a, b| a.partial_cmp(b).unwrap());
        v
    }

    fn assert_close(a: &[(f64, f64)], b: &[(f64, f64)], scale: f64) {
        for (x, y) in a.iter().zip(b) {
            let d = (math::powi(x.0 - y.0, 2) + math::powi(x.1 - y.1, 2)).sqrt();
            assert!(d <= 1e-9 * scale, "{a:?} vs {b:?}");
        }
    }

    /// A deterministic pseudo-random sequence in [−1, 1) (xorshift64).
    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
    }

    fn check_random<const N: usize>(seed: u64, cases: usize) {
        let mut r = rng(seed);
        for _ in 0..cases {
            let m: Vec<f64> = (0..N * N).map(|_| r()).collect();
            let norm = m.iter().map(|x| x.abs()).sum::<f64>();
            assert_close(&ours::<N>(&m), &reference(&m, N), norm);
        }
    }

    #[test]
    fn random_matrices_match_nalgebra() {
        check_random::<2>(1, 200);
        check_random::<3>(2, 200);
        check_random::<4>(3, 500);
        check_random::<6>(4, 500);
        check_random::<8>(5, 200);
        // Above BY_ROWS_FROM: the reduction by rows.
        check_random::<24>(6, 50);
        check_random::<40>(7, 20);
    }

    #[test]
    fn second_order_systems_match_nalgebra() {
        // J = [[0, I], [A, B]] as the model's Jacobians are, over stiffness scales up to 1e7.
        let mut r = rng(9);
        for k in 0..300 {
            let stiff = math::powi(10f64, k % 8);
            let (a, b): (Vec<f64>, Vec<f64>) = (
                (0..4).map(|_| -stiff * (1.5 + r())).collect(),
                (0..4).map(|_| 0.01 * r()).collect(),
            );
            #[rustfmt::skip]
            let m = [
                0.0, 0.0, 1.0, 0.0,
                0.0, 0.0, 0.0, 1.0,
                a[0], a[1], b[0], b[1],
                a[2], a[3], b[2], b[3],
            ];
            let norm = m.iter().map(|x| x.abs()).sum::<f64>();
            assert_close(&ours::<4>(&m), &reference(&m, 4), norm);
        }
    }

    #[test]
    fn known_spectra() {
        // Undamped oscillator ±100i.
        let v = ours::<2>(&[0.0, 1.0, -1e4, 0.0]);
        assert_close(&v, &[(0.0, -100.0), (0.0, 100.0)], 100.0);
        // Companion matrix of (x−1)(x−2)(x−3)(x−4) = x⁴ − 10x³ + 35x² − 50x + 24.
        let v = ours::<4>(&[
            10.0, -35.0, 50.0, -24.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,
        ]);
        assert_close(&v, &[(1.0, 0.0), (2.0, 0.0), (3.0, 0.0), (4.0, 0.0)], 100.0);
        // Already triangular, a zero matrix, and a Jordan block.
        assert_close(
            &ours::<3>(&[1.0, 5.0, 6.0, 0.0, 2.0, 7.0, 0.0, 0.0, 3.0]),
            &[(1.0, 0.0), (2.0, 0.0), (3.0, 0.0)],
            10.0,
        );
        assert_eq!(ours::<3>(&[0.0; 9]), vec![(0.0, 0.0); 3]);
        let v = ours::<2>(&[2.0, 1.0, 0.0, 2.0]);
        assert_close(&v, &[(2.0, 0.0), (2.0, 0.0)], 1.0);
        // A random matrix on which the Francis iteration stalls for 35 iterations (EISPACK's
        // limit of 30 per eigenvalue gives up on it); eigenvalues from numpy.linalg.eigvals.
        #[rustfmt::skip]
        let slow = [
            -0.3472179152609305, 0.4060868811928595, 0.6744504603845838, -0.4795570691253572,
            -0.7794115788887219, -0.7039808924769908, -0.7083991964128897, -0.22302706341327783,
            0.5578719922685123, -0.7470191870405893, -0.2425324175610739, 0.5349031200497381,
            -0.6699284862292323, -0.2025277827154357, -0.950359236531745, 0.9914366099017295,
        ];
        let (a, b) = ((0.76744289, 0.29096407), (-0.91859019, 0.26857679));
        let expected = [(b.0, -b.1), (b.0, b.1), (a.0, -a.1), (a.0, a.1)];
        for (x, y) in ours::<4>(&slow).iter().zip(&expected) {
            assert!((x.0 - y.0).abs() < 1e-8 && (x.1 - y.1).abs() < 1e-8, "{x:?} vs {y:?}");
        }
        // Non-finite entries are refused.
        assert!(eigenvalues(&SMatrix::<f64, 2, 2>::new(f64::NAN, 0.0, 0.0, 1.0)).is_none());
    }
}
