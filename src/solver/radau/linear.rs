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
use nalgebra::{Complex, DMatrix, DefaultAllocator, Dim, Dyn, OMatrix, OVector, U1};

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
    Dense { h: f64, real: Lu<D>, complex: ComplexLu<D> },
    Second { h: f64, real: SecondOrderLu, complex: ComplexLu<Dyn>, parts: Box<[DMatrix<f64>; 3]> },
}

/// γ = h/μ for the real eigenvalue and for α − iβ: with T⁻¹A⁻¹T's block [[α, β], [−β, α]],
/// the increments dW₁ + i·dW₂ solve ((α − iβ)/h − J)(dW₁ + i·dW₂) = r₁ + i·r₂.
fn gammas(h: f64) -> (f64, C64) {
    let mu = C64::new(super::tableau::MU_ALPHA, -super::tableau::MU_BETA);
    (h / super::tableau::MU_REAL, C64::new(h, 0.0) / mu)
}

impl<D: Dim> Factors<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// Both matrices for step `h`; `None` if one is singular or not finite.
    pub fn new(jac: &Jacobian<D>, h: f64) -> Option<Self> {
        let (gr, gc) = gammas(h);
        match jac {
            Jacobian::Dense(j) => {
                let d = j.shape_generic().0;
                let eye = OMatrix::<f64, D, D>::identity_generic(d, d);
                let real = Lu::factor(&(&eye - j * gr))?;
                let a = OMatrix::<C64, D, D>::from_fn_generic(d, d, |r, c| {
                    C64::new(eye[(r, c)], 0.0) - gc * j[(r, c)]
                });
                Some(Factors::Dense { h, real, complex: ComplexLu::factor(a)? })
            }
            Jacobian::Second(s) => {
                let real = s.factor(gr)?;
                let parts = Box::new(dense_parts(s));
                let [mass, damping, stiffness] = &*parts;
                let m = mass.nrows();
                let a = OMatrix::<C64, Dyn, Dyn>::from_fn_generic(Dyn(m), Dyn(m), |r, c| {
                    C64::new(mass[(r, c)], 0.0) + gc * damping[(r, c)] + gc * gc * stiffness[(r, c)]
                });
                Some(Factors::Second { h, real, complex: ComplexLu::<Dyn>::factor(a)?, parts })
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

    /// (((α − iβ)/h)·I − J)⁻¹ (re + i·im), in place.
    pub fn solve_complex(&self, re: &mut OVector<f64, D>, im: &mut OVector<f64, D>) {
        let (_, gc) = gammas(self.h());
        let d = re.shape_generic().0;
        let mut b = OVector::<C64, D>::from_fn_generic(d, U1, |i, _| gc * C64::new(re[i], im[i]));
        match self {
            Factors::Dense { complex, .. } => complex.solve(b.as_mut_slice()),
            Factors::Second { complex, parts, .. } => {
                let [mass, _, stiffness] = &**parts;
                let m = mass.nrows();
                let (r1, r2) = b.as_mut_slice().split_at_mut(m);
                let mut dv: Vec<C64> = (0..m)
                    .map(|i| {
                        (0..m).map(|j| r2[j] * mass[(i, j)] - gc * r1[j] * stiffness[(i, j)]).sum()
                    })
                    .collect();
                complex.solve(&mut dv);
                for ((x, v), d) in r1.iter_mut().zip(r2.iter_mut()).zip(dv) {
                    *x += gc * d;
                    *v = d;
                }
            }
        }
        for (i, z) in b.iter().enumerate() {
            re[i] = z.re;
            im[i] = z.im;
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

    /// The same with γ = h/(α − iβ) for re + i·im, in place; `b` is room for the complex
    /// right-hand side.
    pub fn solve_reduced_complex(
        &self,
        re: &mut [f64],
        im: &mut [f64],
        b: &mut Vec<C64>,
    ) -> Option<()> {
        let Factors::Second { h, complex, .. } = self else { return None };
        let (_, gc) = gammas(*h);
        b.clear();
        b.extend(re.iter().zip(im.iter()).map(|(r, i)| gc * C64::new(*r, *i)));
        complex.solve(b);
        for ((r, i), z) in re.iter_mut().zip(im.iter_mut()).zip(b.iter()) {
            *r = z.re;
            *i = z.im;
        }
        Some(())
    }
}

/// M, C and S dense, whatever the layout.
fn dense_parts(s: &SecondOrder) -> [DMatrix<f64>; 3] {
    match s {
        SecondOrder::Dense(p) => [p.mass.clone(), p.damping.clone(), p.stiffness.clone()],
        SecondOrder::Banded(p) => [p.mass.dense(), p.damping.dense(), p.stiffness.dense()],
    }
}

/// LU with partial pivoting of a complex matrix (Golub & Van Loan, *Matrix Computations*,
/// alg. 3.4.1), kept row-major as [`Lu`] keeps its real factors.
#[derive(Clone, Debug)]
pub(super) struct ComplexLu<D: Dim>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    rows: OMatrix<C64, D, D>,
    /// Row k was swapped with row `swaps[k]` at step k (LAPACK's ipiv).
    swaps: Vec<usize>,
}

#[allow(clippy::needless_range_loop)]
impl<D: Dim> ComplexLu<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// Factors `a`; `None` if a pivot is zero or not finite.
    pub fn factor(a: OMatrix<C64, D, D>) -> Option<Self> {
        let d = a.shape_generic().0;
        let n = d.value();
        let mut rows = a.transpose();
        let f = rows.as_mut_slice();
        let mut swaps = Vec::with_capacity(n);
        let scale = f.iter().map(|z| z.norm_sqr()).fold(0.0, f64::max).sqrt();
        for k in 0..n {
            let (mut p, mut best) = (k, -1.0);
            for i in k..n {
                let v = f[i * n + k].norm_sqr();
                if v > best {
                    (p, best) = (i, v);
                }
            }
            if !(best.is_finite() && best.sqrt() > 1e3 * f64::EPSILON * scale) {
                return None;
            }
            if p != k {
                for j in 0..n {
                    f.swap(k * n + j, p * n + j);
                }
            }
            swaps.push(p);
            let inv = C64::new(1.0, 0.0) / f[k * n + k];
            f[k * n + k] = inv;
            // Rows below k minus multiples of row k, as slices (no index checks in the loop).
            let (upper, lower) = f.split_at_mut((k + 1) * n);
            let pivot_row = &upper[k * n + k + 1..(k + 1) * n];
            for row in lower.chunks_exact_mut(n) {
                let l = row[k] * inv;
                row[k] = l;
                if l != C64::new(0.0, 0.0) {
                    for (x, u) in row[k + 1..].iter_mut().zip(pivot_row) {
                        *x -= l * u;
                    }
                }
            }
        }
        Some(Self { rows, swaps })
    }

    /// A⁻¹ b, in place.
    pub fn solve(&self, b: &mut [C64]) {
        let n = b.len();
        let f = self.rows.as_slice();
        for (k, &p) in self.swaps.iter().enumerate() {
            b.swap(k, p);
        }
        let x = b;
        for (i, row) in f.chunks_exact(n).enumerate() {
            let s: C64 = row[..i].iter().zip(&x[..i]).map(|(l, x)| l * x).sum();
            x[i] -= s;
        }
        for (i, row) in f.chunks_exact(n).enumerate().rev() {
            let s: C64 = row[i + 1..].iter().zip(&x[i + 1..]).map(|(u, x)| u * x).sum();
            x[i] = (x[i] - s) * row[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::DenseParts;
    use nalgebra::{DVector, Matrix4, Vector4};

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
        f.solve_complex(&mut re, &mut im);
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
        dense.solve_complex(&mut r1, &mut i1);
        second.solve_complex(&mut r2, &mut i2);
        assert!((&r1 - &r2).abs().max() < 1e-12 && (&i1 - &i2).abs().max() < 1e-12);
        let (mut x1, mut x2) = (re0.clone(), re0.clone());
        dense.solve_real(&Jacobian::Dense(jd), &mut x1);
        second.solve_real(&Jacobian::Second(s), &mut x2);
        assert!((&x1 - &x2).abs().max() < 1e-12);
    }
}
