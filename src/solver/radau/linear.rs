//! The two Newton matrices of a Radau IIA step of size h: (μ/h)·I − J, real, and
//! ((α − iβ)/h)·I − J, complex (Hairer & Wanner, IV.8: the stage system transformed by T
//! splits into these). Multiplied through by γ = h/μ they are I − γJ, the BDF's matrix, so
//! the real one is the BDF's factorisation ([`Lu`], [`SecondOrder::factor`]) and the complex
//! one the same reduction in complex arithmetic: for a mechanical system (x, ẋ) with
//! J = [[0, I], [−M⁻¹S, −M⁻¹C]], (M + γC + γ²S) dẋ = M r2 − γ S r1 and dx = r1 + γ dẋ, an
//! m×m solve in place of the 2m×2m one.

use super::super::lu::Lu;
use super::super::second_order::{SecondOrder, SecondOrderLu};
use nalgebra::allocator::Allocator;
use nalgebra::{Complex, DMatrix, DefaultAllocator, Dim, OMatrix, OVector};

type C64 = Complex<f64>;

/// The Jacobian a step uses: dense, or a mechanical system's parts.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub(super) enum Jacobian<D: Dim>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    Dense(OMatrix<f64, D, D>),
    Second(SecondOrder),
}

/// Both matrices factored for one h.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub(super) enum Factors<D: Dim>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    Dense {
        h: f64,
        real: Lu<D>,
        complex: ComplexLu,
    },
    /// `banded`: a banded Jacobian's M, C and S made dense, for the first-order solves.
    Second {
        h: f64,
        real: SecondOrderLu,
        complex: ComplexLu,
        banded: Option<Box<[DMatrix<f64>; 3]>>,
    },
}

/// γ = h/μ for the real eigenvalue and for α − iβ: with T⁻¹A⁻¹T's block [[α, β], [−β, α]],
/// the increments dW₁ + i·dW₂ solve ((α − iβ)/h − J)(dW₁ + i·dW₂) = r₁ + i·r₂.
fn gammas(h: f64) -> (f64, C64) {
    let mu = C64::new(super::tableau::MU_ALPHA, -super::tableau::MU_BETA);
    (h / super::tableau::MU_REAL, C64::new(h, 0.0) / mu)
}

/// The n×n matrix Σ_k c_k·A_k (complex c_k, real A_k given column by column, as nalgebra
/// stores them), row by row, real and imaginary parts.
fn combine(n: usize, terms: &[(C64, &[f64])]) -> (Vec<f64>, Vec<f64>) {
    let (mut re, mut im) = (vec![0.0; n * n], vec![0.0; n * n]);
    // One pass, each entry written once, in tiles of TILE columns by TILE rows: the transpose
    // then touches a few cache lines at a time (term by term over the whole matrix it was a
    // tenth of a 32-element run). Each entry's sum is taken in the terms' order.
    const TILE: usize = 8;
    for j0 in (0..n).step_by(TILE) {
        for i0 in (0..n).step_by(TILE) {
            for j in j0..(j0 + TILE).min(n) {
                for i in i0..(i0 + TILE).min(n) {
                    // Column j holds the j-th entry of every row.
                    let (mut r, mut m) = (0.0, 0.0);
                    for (c, a) in terms {
                        let x = a[j * n + i];
                        r += c.re * x;
                        m += c.im * x;
                    }
                    re[i * n + j] = r;
                    im[i * n + j] = m;
                }
            }
        }
    }
    (re, im)
}

/// M, C and S of a Jacobian's parts: borrowed where dense, else from `banded`.
fn parts<'a>(
    s: &'a SecondOrder,
    banded: &'a Option<Box<[DMatrix<f64>; 3]>>,
) -> [&'a DMatrix<f64>; 3] {
    match (s, banded) {
        (SecondOrder::Dense(p), _) => [&p.mass, &p.damping, &p.stiffness],
        (_, Some(b)) => [&b[0], &b[1], &b[2]],
        (SecondOrder::Banded(_), None) => unreachable!("banded parts are kept with their factors"),
    }
}

impl<D: Dim> Factors<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// Both matrices for step `h`; `None` if one is singular or not finite.
    pub fn new(jac: &Jacobian<D>, h: f64) -> Option<Self> {
        let (gr, gc) = gammas(h);
        let one = C64::new(1.0, 0.0);
        match jac {
            Jacobian::Dense(j) => {
                let d = j.shape_generic().0;
                let n = d.value();
                let eye = OMatrix::<f64, D, D>::identity_generic(d, d);
                let real = Lu::factor(&(&eye - j * gr))?;
                let (re, im) = combine(n, &[(one, eye.as_slice()), (-gc, j.as_slice())]);
                Some(Factors::Dense { h, real, complex: ComplexLu::factor(n, re, im)? })
            }
            Jacobian::Second(s) => {
                let real = s.factor(gr)?;
                let banded = match s {
                    SecondOrder::Banded(p) => {
                        Some(Box::new([p.mass.dense(), p.damping.dense(), p.stiffness.dense()]))
                    }
                    SecondOrder::Dense(_) => None,
                };
                let [mass, damping, stiffness] = parts(s, &banded);
                let m = mass.nrows();
                let terms = [(one, mass), (gc, damping), (gc * gc, stiffness)];
                let (re, im) = combine(m, &terms.map(|(c, a)| (c, a.as_slice())));
                Some(Factors::Second { h, real, complex: ComplexLu::factor(m, re, im)?, banded })
            }
        }
    }

    /// The step these were factored for.
    pub fn h(&self) -> f64 {
        match self {
            Factors::Dense { h, .. } | Factors::Second { h, .. } => *h,
        }
    }

    /// ((μ/h)·I − J)⁻¹ r, in place.
    pub fn solve_real(&self, jac: &Jacobian<D>, r: &mut OVector<f64, D>) {
        let (gr, _) = gammas(self.h());
        *r *= gr;
        match (self, jac) {
            (Factors::Dense { real, .. }, _) => *r = real.solve(r),
            (Factors::Second { real, .. }, Jacobian::Second(s)) => real.solve(s, r.as_mut_slice()),
            _ => r.fill(f64::NAN),
        }
    }

    /// (((α − iβ)/h)·I − J)⁻¹ (re + i·im), in place, with the Jacobian these were factored
    /// from.
    pub fn solve_complex(
        &self,
        jac: &Jacobian<D>,
        re: &mut OVector<f64, D>,
        im: &mut OVector<f64, D>,
    ) {
        let (_, gc) = gammas(self.h());
        for (r, i) in re.iter_mut().zip(im.iter_mut()) {
            let z = gc * C64::new(*r, *i);
            (*r, *i) = (z.re, z.im);
        }
        match (self, jac) {
            (Factors::Dense { complex, .. }, _) => {
                complex.solve(re.as_mut_slice(), im.as_mut_slice())
            }
            (Factors::Second { complex, banded, .. }, Jacobian::Second(s)) => {
                // dẋ = (M + γC + γ²S)⁻¹ (M r2 − γ S r1), dx = r1 + γ dẋ.
                let [mass, _, stiffness] = parts(s, banded);
                let m = mass.nrows();
                let (r1, r2) = re.as_mut_slice().split_at_mut(m);
                let (i1, i2) = im.as_mut_slice().split_at_mut(m);
                let g1: Vec<C64> =
                    r1.iter().zip(i1.iter()).map(|(r, i)| gc * C64::new(*r, *i)).collect();
                let (mut dr, mut di) = (vec![0.0; m], vec![0.0; m]);
                for i in 0..m {
                    for (j, g1) in g1.iter().enumerate() {
                        dr[i] += mass[(i, j)] * r2[j] - stiffness[(i, j)] * g1.re;
                        di[i] += mass[(i, j)] * i2[j] - stiffness[(i, j)] * g1.im;
                    }
                }
                complex.solve(&mut dr, &mut di);
                for k in 0..m {
                    let g = gc * C64::new(dr[k], di[k]);
                    r1[k] += g.re;
                    i1[k] += g.im;
                    (r2[k], i2[k]) = (dr[k], di[k]);
                }
            }
            _ => {
                re.fill(f64::NAN);
                im.fill(f64::NAN);
            }
        }
    }
}

impl<D: Dim> Factors<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// For a mechanical system's stages solved for the velocities (Radau's residual form):
    /// (M + γC + γ²S) x = γ b with γ = h/μ, in place; `None` without the structured factors.
    pub fn solve_reduced_real(&self, b: &mut [f64]) -> Option<()> {
        let Factors::Second { h, real, .. } = self else { return None };
        let (gr, _) = gammas(*h);
        b.iter_mut().for_each(|x| *x *= gr);
        real.solve_reduced(b);
        Some(())
    }

    /// The same with γ = h/(α − iβ) for re + i·im, in place.
    pub fn solve_reduced_complex(&self, re: &mut [f64], im: &mut [f64]) -> Option<()> {
        let Factors::Second { h, complex, .. } = self else { return None };
        let (_, gc) = gammas(*h);
        for (r, i) in re.iter_mut().zip(im.iter_mut()) {
            let z = gc * C64::new(*r, *i);
            (*r, *i) = (z.re, z.im);
        }
        complex.solve(re, im);
        Some(())
    }
}

/// LU with partial pivoting of a complex matrix (Golub & Van Loan, *Matrix Computations*,
/// alg. 3.4.1), row-major, its real and imaginary parts in separate arrays: the elimination's
/// inner loop is then four real products a pair of entries on contiguous slices, which the
/// compiler vectorises (complex numbers stored in pairs were 19 instructions an entry; the
/// exact beam in 32 elements spent 30 % of a run in this factorisation).
#[derive(Clone, Debug)]
pub(super) struct ComplexLu {
    n: usize,
    /// The rows of L (unit lower, below the diagonal) and U (above it), row-permuted; the
    /// diagonal holds the reciprocals of U's pivots.
    re: Vec<f64>,
    im: Vec<f64>,
    /// Row k was swapped with row `swaps[k]` at step k (LAPACK's ipiv).
    swaps: Vec<usize>,
}

impl ComplexLu {
    /// Factors the n×n matrix `re + i·im`, each given row by row; `None` if a pivot is zero
    /// or not finite.
    pub fn factor(n: usize, mut re: Vec<f64>, mut im: Vec<f64>) -> Option<Self> {
        debug_assert!(re.len() == n * n && im.len() == n * n);
        let mut swaps = Vec::with_capacity(n);
        let scale = re.iter().zip(&im).map(|(a, b)| a * a + b * b).fold(0.0, f64::max).sqrt();
        for k in 0..n {
            let (mut p, mut best) = (k, -1.0);
            for i in k..n {
                let v = re[i * n + k] * re[i * n + k] + im[i * n + k] * im[i * n + k];
                if v > best {
                    (p, best) = (i, v);
                }
            }
            if !(best.is_finite() && best.sqrt() > 1e3 * f64::EPSILON * scale) {
                return None;
            }
            if p != k {
                for j in 0..n {
                    re.swap(k * n + j, p * n + j);
                    im.swap(k * n + j, p * n + j);
                }
            }
            swaps.push(p);
            let (pr, pi) = (re[k * n + k], im[k * n + k]);
            let (ir, ii) = (pr / best, -pi / best);
            re[k * n + k] = ir;
            im[k * n + k] = ii;
            // Rows below k minus multiples of row k, as slices (no index checks in the loop).
            let (re_up, re_low) = re.split_at_mut((k + 1) * n);
            let (im_up, im_low) = im.split_at_mut((k + 1) * n);
            let (ur, ui) = (&re_up[k * n + k + 1..], &im_up[k * n + k + 1..]);
            for (xr, xi) in re_low.chunks_exact_mut(n).zip(im_low.chunks_exact_mut(n)) {
                let (a, b) = (xr[k], xi[k]);
                let (lr, li) = (a * ir - b * ii, a * ii + b * ir);
                xr[k] = lr;
                xi[k] = li;
                if lr != 0.0 || li != 0.0 {
                    // Equal lengths, visible to the compiler: no checks, and it vectorises.
                    let len = ur.len();
                    let (xr, xi, ui) =
                        (&mut xr[k + 1..k + 1 + len], &mut xi[k + 1..k + 1 + len], &ui[..len]);
                    for j in 0..len {
                        let (a, b) = (ur[j], ui[j]);
                        xr[j] -= lr * a - li * b;
                        xi[j] -= lr * b + li * a;
                    }
                }
            }
        }
        Some(Self { n, re, im, swaps })
    }

    /// A⁻¹ (re + i·im), in place.
    pub fn solve(&self, re: &mut [f64], im: &mut [f64]) {
        let n = self.n;
        for (k, &p) in self.swaps.iter().enumerate() {
            re.swap(k, p);
            im.swap(k, p);
        }
        let rows = self.re.chunks_exact(n).zip(self.im.chunks_exact(n));
        for (i, (lr, li)) in rows.clone().enumerate() {
            let (mut sr, mut si) = (0.0, 0.0);
            for j in 0..i {
                sr += lr[j] * re[j] - li[j] * im[j];
                si += lr[j] * im[j] + li[j] * re[j];
            }
            re[i] -= sr;
            im[i] -= si;
        }
        for (i, (ur, ui)) in rows.enumerate().rev() {
            let (mut xr, mut xi) = (re[i], im[i]);
            for j in i + 1..n {
                xr -= ur[j] * re[j] - ui[j] * im[j];
                xi -= ur[j] * im[j] + ui[j] * re[j];
            }
            re[i] = xr * ur[i] - xi * ui[i];
            im[i] = xr * ui[i] + xi * ur[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::DenseParts;
    use nalgebra::{DVector, Dyn, Matrix4, Vector4};

    fn jac4() -> Matrix4<f64> {
        Matrix4::new(
            0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, -40.0, 3.0, -0.2, 0.1, 5.0, -900.0, 0.3, -0.5,
        )
    }

    #[test]
    fn the_complex_solve_inverts_the_shifted_matrix() {
        let j = jac4();
        let h = 0.01;
        let f = Factors::new(&Jacobian::Dense(j), h).unwrap();
        let (mut re, mut im) =
            (Vector4::new(1.0, -2.0, 0.5, 3.0), Vector4::new(0.0, 1.0, -1.0, 2.0));
        let (re0, im0) = (re, im);
        f.solve_complex(&Jacobian::Dense(j), &mut re, &mut im);
        // ((α − iβ)/h − J)(re + i im) = re0 + i im0.
        let (a, b) = (super::super::tableau::MU_ALPHA / h, super::super::tableau::MU_BETA / h);
        let r = re * a + im * b - j * re;
        let i = im * a - re * b - j * im;
        assert!((r - re0).abs().max() < 1e-10 && (i - im0).abs().max() < 1e-10);
        let mut x = re0;
        f.solve_real(&Jacobian::Dense(j), &mut x);
        let back = x * (super::super::tableau::MU_REAL / h) - j * x;
        assert!((back - re0).abs().max() < 1e-10);
    }

    #[test]
    fn the_mechanical_reduction_gives_the_dense_solves() {
        let mass = DMatrix::from_row_slice(2, 2, &[2.0, 0.3, 0.3, 1.0]);
        let damping = DMatrix::from_row_slice(2, 2, &[0.2, -0.1, 0.05, 0.5]);
        let stiffness = DMatrix::from_row_slice(2, 2, &[80.0, -3.0, -5.0, 900.0]);
        let s = SecondOrder::Dense(DenseParts { mass, damping, stiffness });
        let jd = s.dense_jacobian().unwrap();
        let h = 0.02;
        let dense = Factors::new(&Jacobian::<Dyn>::Dense(jd.clone()), h).unwrap();
        let second = Factors::new(&Jacobian::<Dyn>::Second(s.clone()), h).unwrap();
        let re0 = DVector::from_vec(vec![1.0, -2.0, 0.5, 3.0]);
        let im0 = DVector::from_vec(vec![0.0, 1.0, -1.0, 2.0]);
        let (mut r1, mut i1, mut r2, mut i2) = (re0.clone(), im0.clone(), re0.clone(), im0.clone());
        dense.solve_complex(&Jacobian::Dense(jd.clone()), &mut r1, &mut i1);
        second.solve_complex(&Jacobian::Second(s.clone()), &mut r2, &mut i2);
        assert!((&r1 - &r2).abs().max() < 1e-12 && (&i1 - &i2).abs().max() < 1e-12);
        let (mut x1, mut x2) = (re0.clone(), re0.clone());
        dense.solve_real(&Jacobian::Dense(jd), &mut x1);
        second.solve_real(&Jacobian::Second(s), &mut x2);
        assert!((&x1 - &x2).abs().max() < 1e-12);
    }
}
