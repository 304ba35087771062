//! The Newton matrix of a mechanical system, factored in O(n): a system y = (x, ẋ) of m
//! coordinates whose accelerations solve M(x) ẍ = F(t, x, ẋ), with M, ∂R/∂ẋ and ∂R/∂x
//! (R = M ẍ − F at the accelerations ẍ of the Jacobian's point) each a band matrix and a
//! rank-one term u·vᵀ. With J = [[0, I], [−M⁻¹S, −M⁻¹C]] (S = ∂R/∂x, C = ∂R/∂ẋ), the
//! Newton system (I − γJ)(dx, dẋ) = (r1, r2) reduces to
//!
//!   (M + γC + γ²S) dẋ = M r2 − γ S r1,   dx = r1 + γ dẋ,
//!
//! In the banded layout ([`BandedParts`]) its matrix is a band (LU with pivoting,
//! [`GenBand`]) and three rank-one terms (Sherman–Morrison–Woodbury with a 3×3 capacitance
//! matrix; Golub & Van Loan, *Matrix Computations*, 4th ed., §2.1.4), and everything costs
//! O(m): the dense LU of I − γJ costs O(m³) and its solve O(m²). In the dense layout
//! ([`DenseParts`], the exact beam's configuration-dependent mass matrix) it is an m×m LU,
//! an eighth of the 2m×2m one's cost.

use super::band::{BandLu, GenBand};
use super::snapshot::StateVisitor;
use nalgebra::{DMatrix, DVector, DVectorView, DVectorViewMut, Dyn, Matrix3, Vector3, LU};

/// A band matrix plus u·vᵀ.
#[derive(Clone, Debug, PartialEq)]
pub struct BandRankOne {
    pub band: GenBand,
    pub u: Vec<f64>,
    pub v: Vec<f64>,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl BandRankOne {
    /// The m×m zero matrix.
    pub fn zeros(m: usize) -> Self {
        Self { band: GenBand::zeros(m), u: vec![0.0; m], v: vec![0.0; m] }
    }

    /// A·x added, times `s`, to `y`.
    fn mul_add(&self, s: f64, x: &[f64], y: &mut [f64]) {
        self.band.mul_add(s, x, y);
        let svx = s * dot(&self.v, x);
        for (y, u) in y.iter_mut().zip(&self.u) {
            *y += u * svx;
        }
    }

    /// The dense matrix.
    pub fn dense(&self) -> DMatrix<f64> {
        let m = self.u.len();
        DMatrix::from_fn(m, m, |i, j| self.band.get(i, j) + self.u[i] * self.v[j])
    }
}

/// The parts of a second-order system's Jacobian at a point, in one of two layouts.
#[derive(Clone, Debug, PartialEq)]
pub enum SecondOrder {
    Banded(BandedParts),
    Dense(DenseParts),
}

/// The layout of [`SecondOrder`] a solver expects ([`Bdf::set_second_order`]).
///
/// [`Bdf::set_second_order`]: super::Bdf::set_second_order
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    Banded,
    Dense,
}

/// M, C and S as dense m×m matrices.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseParts {
    pub mass: DMatrix<f64>,
    pub damping: DMatrix<f64>,
    pub stiffness: DMatrix<f64>,
}

/// [`SecondOrder`]'s Newton matrix factored for one γ. A solver holds one.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum SecondOrderLu {
    Banded(BandedLu),
    Dense { gamma: f64, lu: LU<f64, Dyn, Dyn> },
}

impl SecondOrder {
    /// The m×m zero parts of a layout.
    pub fn zeros(layout: Layout, m: usize) -> Self {
        match layout {
            Layout::Banded => SecondOrder::Banded(BandedParts::zeros(m)),
            Layout::Dense => {
                let z = DMatrix::zeros(m, m);
                SecondOrder::Dense(DenseParts { mass: z.clone(), damping: z.clone(), stiffness: z })
            }
        }
    }

    /// Its layout.
    pub fn layout(&self) -> Layout {
        match self {
            SecondOrder::Banded(_) => Layout::Banded,
            SecondOrder::Dense(_) => Layout::Dense,
        }
    }

    /// The number of coordinates m (the system has 2m states).
    pub fn coordinates(&self) -> usize {
        match self {
            SecondOrder::Banded(p) => p.coordinates(),
            SecondOrder::Dense(p) => p.mass.nrows(),
        }
    }

    /// Visits every number, named `structure`: the banded parts' ([`BandedParts::visit`]),
    /// or each dense part's m² entries, column by column.
    pub(crate) fn visit<V: StateVisitor + ?Sized>(&mut self, v: &mut V) {
        match self {
            SecondOrder::Banded(p) => p.visit(v),
            SecondOrder::Dense(p) => {
                for part in [&mut p.mass, &mut p.damping, &mut p.stiffness] {
                    part.iter_mut().for_each(|x| v.real("structure", x));
                }
            }
        }
    }

    /// Whether every number is finite.
    pub(crate) fn is_finite(&self) -> bool {
        match self {
            SecondOrder::Banded(p) => p.is_finite(),
            SecondOrder::Dense(p) => {
                [&p.mass, &p.damping, &p.stiffness].iter().all(|m| m.iter().all(|x| x.is_finite()))
            }
        }
    }

    /// The Newton matrix for `gamma` factored; `None` if it is singular.
    pub fn factor(&self, gamma: f64) -> Option<SecondOrderLu> {
        match self {
            SecondOrder::Banded(p) => p.factor(gamma).map(SecondOrderLu::Banded),
            SecondOrder::Dense(p) => {
                // One pass, each entry rounded as (M + C·γ) + S·γ² (as the sum of the scaled
                // matrices was).
                let g2 = gamma * gamma;
                let mut t = p.mass.clone();
                let (c, s) = (p.damping.as_slice(), p.stiffness.as_slice());
                for ((t, c), s) in t.as_mut_slice().iter_mut().zip(c).zip(s) {
                    *t = (*t + c * gamma) + s * g2;
                }
                if !t.iter().all(|x| x.is_finite()) {
                    return None;
                }
                let lu = t.lu();
                lu.is_invertible().then_some(SecondOrderLu::Dense { gamma, lu })
            }
        }
    }

    /// The dense Jacobian J of the first-order system, 2m×2m: [[0, I], [−M⁻¹S, −M⁻¹C]].
    /// `None` if M is singular.
    pub fn dense_jacobian(&self) -> Option<DMatrix<f64>> {
        match self {
            SecondOrder::Banded(p) => p.dense_jacobian(),
            SecondOrder::Dense(p) => {
                let m = p.mass.nrows();
                let lu = p.mass.clone().lu();
                let mut j = DMatrix::zeros(2 * m, 2 * m);
                for k in 0..m {
                    j[(k, m + k)] = 1.0;
                }
                for (offset, part) in [(0, &p.stiffness), (m, &p.damping)] {
                    let x = lu.solve(&(-part))?;
                    j.view_mut((m, offset), (m, m)).copy_from(&x);
                }
                Some(j)
            }
        }
    }
}

impl SecondOrderLu {
    /// Solves (M + γC + γ²S) x = b in place (m entries): the reduced matrix itself.
    pub fn solve_reduced(&self, b: &mut [f64]) {
        match self {
            SecondOrderLu::Banded(lu) => lu.solve_reduced(b),
            SecondOrderLu::Dense { lu, .. } => {
                let m = b.len();
                if !lu.solve_mut(&mut DVectorViewMut::from_slice(b, m)) {
                    b.fill(f64::NAN);
                }
            }
        }
    }

    /// Solves (I − γJ)(dx, dẋ) = (r1, r2) in place, `r` = (r1, r2) of 2m entries, with the
    /// parts this was factored from.
    pub fn solve(&self, parts: &SecondOrder, r: &mut [f64]) {
        match (self, parts) {
            (SecondOrderLu::Banded(lu), SecondOrder::Banded(p)) => lu.solve(p, r),
            (SecondOrderLu::Dense { gamma, lu }, SecondOrder::Dense(p)) => {
                let m = p.mass.nrows();
                let (r1, r2) = r.split_at_mut(m);
                // M r2 − (S r1)·γ, by the products `*` takes, into two buffers (the Newton
                // iteration's solve: no other allocation).
                let (mut dv, mut sr1) = (DVector::zeros(m), DVector::zeros(m));
                dv.gemv(1.0, &p.mass, &DVectorView::from_slice(r2, m), 0.0);
                sr1.gemv(1.0, &p.stiffness, &DVectorView::from_slice(r1, m), 0.0);
                dv.iter_mut().zip(sr1.iter()).for_each(|(b, s)| *b -= s * *gamma);
                if !lu.solve_mut(&mut dv) {
                    dv.fill(f64::NAN);
                }
                for ((x, v), d) in r1.iter_mut().zip(r2.iter_mut()).zip(dv.iter()) {
                    *x += gamma * d;
                    *v = *d;
                }
            }
            _ => r.fill(f64::NAN),
        }
    }
}

/// The three parts of a second-order system's Jacobian at a point, each a band and a rank-one
/// term.
#[derive(Clone, Debug, PartialEq)]
pub struct BandedParts {
    /// M, the mass matrix.
    pub mass: BandRankOne,
    /// C = ∂R/∂ẋ.
    pub damping: BandRankOne,
    /// S = ∂R/∂x.
    pub stiffness: BandRankOne,
}

/// [`BandedParts`]' Newton matrix factored for one γ.
#[derive(Clone, Debug)]
pub struct BandedLu {
    gamma: f64,
    lu: BandLu,
    /// Z = T_band⁻¹ U, the three columns of U = (u_M, u_C, u_S).
    z: [Vec<f64>; 3],
    /// V = (v_M, γ v_C, γ² v_S), and the LU of the capacitance matrix I + Vᵀ Z.
    v: [Vec<f64>; 3],
    capacitance: nalgebra::LU<f64, nalgebra::U3, nalgebra::U3>,
}

impl BandedParts {
    /// The m×m zero parts.
    pub fn zeros(m: usize) -> Self {
        let z = BandRankOne::zeros(m);
        Self { mass: z.clone(), damping: z.clone(), stiffness: z }
    }

    /// The number of coordinates m (the system has 2m states).
    pub fn coordinates(&self) -> usize {
        self.mass.u.len()
    }

    /// Visits every number: each part's band entries (10 a row), u, v; named `structure`.
    pub(crate) fn visit<V: StateVisitor + ?Sized>(&mut self, v: &mut V) {
        for part in [&mut self.mass, &mut self.damping, &mut self.stiffness] {
            for x in part.band.entries_mut().chain(part.u.iter_mut()).chain(part.v.iter_mut()) {
                v.real("structure", x);
            }
        }
    }

    /// Whether every number is finite.
    pub(crate) fn is_finite(&self) -> bool {
        self.parts()
            .iter()
            .all(|p| p.band.is_finite() && p.u.iter().chain(&p.v).all(|x| x.is_finite()))
    }

    fn parts(&self) -> [&BandRankOne; 3] {
        [&self.mass, &self.damping, &self.stiffness]
    }

    /// The Newton matrix for `gamma` factored; `None` if it is singular.
    pub fn factor(&self, gamma: f64) -> Option<BandedLu> {
        let scale = [1.0, gamma, gamma * gamma];
        let mut t = self.mass.band.clone();
        t.add_scaled(gamma, &self.damping.band);
        t.add_scaled(gamma * gamma, &self.stiffness.band);
        let lu = t.lu()?;
        let parts = self.parts();
        let z = parts.map(|p| {
            let mut z = p.u.clone();
            lu.solve(&mut z);
            z
        });
        let v: [Vec<f64>; 3] =
            std::array::from_fn(|i| parts[i].v.iter().map(|x| scale[i] * x).collect());
        let cap = Matrix3::from_fn(|i, j| f64::from(u8::from(i == j)) + dot(&v[i], &z[j]));
        let capacitance = cap.lu();
        if !capacitance.is_invertible() || !cap.iter().all(|x| x.is_finite()) {
            return None;
        }
        Some(BandedLu { gamma, lu, z, v, capacitance })
    }

    /// The dense Jacobian J of the first-order system, 2m×2m: [[0, I], [−M⁻¹S, −M⁻¹C]].
    /// `None` if M is singular. O(m²) with the band solves: for the stability guard's modes
    /// and the state, at each Jacobian, not each step.
    pub fn dense_jacobian(&self) -> Option<DMatrix<f64>> {
        let m = self.coordinates();
        let mass = BandedParts { mass: self.mass.clone(), ..BandedParts::zeros(m) }.factor(0.0)?;
        let mut j = DMatrix::zeros(2 * m, 2 * m);
        for k in 0..m {
            j[(k, m + k)] = 1.0;
        }
        let mut col = vec![0.0; m];
        for (offset, part) in [(0, &self.stiffness), (m, &self.damping)] {
            let dense = part.dense();
            for c in 0..m {
                col.iter_mut().zip(dense.column(c).iter()).for_each(|(x, d)| *x = -d);
                mass.solve_reduced(&mut col);
                for (r, x) in col.iter().enumerate() {
                    j[(m + r, offset + c)] = *x;
                }
            }
        }
        Some(j)
    }
}

impl BandedLu {
    /// Solves (I − γJ)(dx, dẋ) = (r1, r2) in place, `r` = (r1, r2) of 2m entries, with the
    /// parts this was factored from.
    pub fn solve(&self, parts: &BandedParts, r: &mut [f64]) {
        let m = parts.coordinates();
        let (r1, r2) = r.split_at_mut(m);
        // b = M r2 − γ S r1, then dẋ = (M + γC + γ²S)⁻¹ b, dx = r1 + γ dẋ.
        let mut b = vec![0.0; m];
        parts.mass.mul_add(1.0, r2, &mut b);
        parts.stiffness.mul_add(-self.gamma, r1, &mut b);
        self.solve_reduced(&mut b);
        for ((x, v), dv) in r1.iter_mut().zip(r2.iter_mut()).zip(&b) {
            *x += self.gamma * dv;
            *v = *dv;
        }
    }

    /// Solves (M + γC + γ²S) x = b in place.
    fn solve_reduced(&self, b: &mut [f64]) {
        // Woodbury: x = y − Z (I + VᵀZ)⁻¹ Vᵀ y, y = T_band⁻¹ b.
        self.lu.solve(b);
        let w = Vector3::from_fn(|i, _| dot(&self.v[i], b));
        let k = self.capacitance.solve(&w).unwrap_or_else(Vector3::zeros);
        for (i, x) in b.iter_mut().enumerate() {
            *x -= self.z[0][i] * k[0] + self.z[1][i] * k[1] + self.z[2][i] * k[2];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;

    /// Parts of a small system with every entry of its band and vectors set.
    fn parts(m: usize) -> BandedParts {
        let mut s = BandedParts::zeros(m);
        let mut k = 0.0_f64;
        for (p, (diag, spread)) in [
            (&mut s.mass, (5.0, 0.3)),
            (&mut s.damping, (0.7, 0.2)),
            (&mut s.stiffness, (40.0, 9.0)),
        ] {
            for i in 0..m {
                for j in i.saturating_sub(3)..=(i + 3).min(m - 1) {
                    k += 1.0;
                    let x = if i == j { diag } else { spread * math::sin(0.37 * k) };
                    p.band.add(i, j, x);
                }
                p.u[i] = math::cos(0.3 * i as f64 + diag);
                p.v[i] = spread * math::sin(0.5 * i as f64);
            }
        }
        s
    }

    #[test]
    fn the_reduced_solve_is_the_dense_newton_solve() {
        for m in [1, 2, 7, 20] {
            let s = parts(m);
            let j = s.dense_jacobian().unwrap();
            let mass = s.mass.dense();
            // J's lower rows times M are −(S, C).
            let lower = &mass * j.view((m, 0), (m, 2 * m));
            let want = -DMatrix::from_fn(m, 2 * m, |r, c| {
                if c < m {
                    s.stiffness.dense()[(r, c)]
                } else {
                    s.damping.dense()[(r, c - m)]
                }
            });
            assert!((lower - &want).amax() < 1e-11 * want.amax(), "m {m}");
            for gamma in [1e-4, 0.01, 0.3] {
                let newton = DMatrix::identity(2 * m, 2 * m) - &j * gamma;
                let r = DVector::from_fn(2 * m, |i, _| math::sin(1.3 * i as f64) + 0.2);
                let want = newton.lu().solve(&r).unwrap();
                let banded = SecondOrder::Banded(s.clone());
                let dense = SecondOrder::Dense(DenseParts {
                    mass: s.mass.dense(),
                    damping: s.damping.dense(),
                    stiffness: s.stiffness.dense(),
                });
                for parts in [&banded, &dense] {
                    let mut x: Vec<f64> = r.iter().copied().collect();
                    parts.factor(gamma).unwrap().solve(parts, &mut x);
                    let err = (DVector::from_vec(x) - &want).amax();
                    assert!(err <= 1e-10 * want.amax(), "m {m}, gamma {gamma}: {err}");
                }
                let jd = dense.dense_jacobian().unwrap();
                assert!((&jd - &j).amax() < 1e-10 * j.amax(), "m {m}");
            }
        }
    }
}
