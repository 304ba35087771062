//! Coefficients of the fixed-leading-coefficient BDF in Nordsieck form, and the changes of
//! the Nordsieck array when the order changes.
//!
//! Sources: K. R. Jackson and R. Sacks-Davis, "An alternative implementation of variable
//! step-size multistep formulas for stiff ODEs", ACM TOMS 6 (1980) 295–318 (the
//! fixed-leading-coefficient form); P. N. Brown, G. D. Byrne and A. C. Hindmarsh, "VODE",
//! SIAM J. Sci. Stat. Comput. 10 (1989) 1038–1051; and the CVODE description in
//! A. C. Hindmarsh et al., "SUNDIALS", ACM TOMS 31 (2005) 363–396, §2.1, whose error
//! constants (tq) and order-change formulas these are.
//!
//! Notation. The new step goes from t_{n−1} to t_n = t_{n−1} + h. `tau[k]` (k ≥ 1) is the
//! size of the k-th most recent accepted step. ξ_j = (t_n − t_{n−j}) / h, so ξ_1 = 1 and
//! ξ_j = (h + τ_1 + … + τ_{j−1}) / h.

use super::error::SolverError;
use super::snapshot::{require_finite, require_not_below_zero, StateVisitor};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OVector};

/// Highest BDF order.
pub(crate) const QMAX: usize = 5;
/// Columns of the Nordsieck array, z_j = h^j y^(j) / j!, j = 0..=QMAX.
pub(crate) const NCOL: usize = QMAX + 1;

/// Coefficients for one step of order q.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct StepCoeffs {
    /// The corrector vector: after the step z_j ← z_j + l_j·Δ, with Δ the correction.
    pub l: [f64; NCOL],
    /// Error-estimate constants: tq[2] turns ‖Δ‖ into the local error at order q, tq[1] at
    /// order q−1 (from z_q), tq[3] at order q+1 (from the difference of two corrections),
    /// tq[5] rescales a saved correction to the current step. tq[1] and tq[3] are computed
    /// only when an order change is being considered. Index 0 and 4 are unused.
    pub tq: [f64; NCOL],
    /// What they were computed from: the order (0: nothing yet), whether tq[1] and tq[3]
    /// were computed, the step h and the past steps τ_1..=τ_q (0 beyond q).
    /// [`StepCoeffs::update`] reuses them for the same order, step and past steps, as over
    /// a run of equal steps. (The coefficients depend only on the ratios ξ; the key is the
    /// steps themselves, which cost no division to compare, and equal steps give equal
    /// ratios.)
    pub key_q: usize,
    pub key_order_change: bool,
    pub key_h: f64,
    pub key_tau: [f64; QMAX],
}

impl StepCoeffs {
    /// Visits l, then tq, then the key (see [`Bdf::visit_state`](super::Bdf::visit_state)).
    pub(crate) fn visit<V: StateVisitor + ?Sized>(&mut self, v: &mut V) {
        for x in &mut self.l {
            v.real("coeffs.l", x);
        }
        for x in &mut self.tq {
            v.real("coeffs.tq", x);
        }
        let mut q = self.key_q as u64;
        v.count("coeffs.key_q", &mut q);
        self.key_q = usize::try_from(q).unwrap_or(usize::MAX);
        v.flag("coeffs.key_order_change", &mut self.key_order_change);
        v.real("coeffs.key_h", &mut self.key_h);
        for x in &mut self.key_tau {
            v.real("coeffs.key_tau", x);
        }
    }

    /// l is finite. tq is not negative: its entries are absolute values or 0. They may be
    /// +∞ or NaN, which [`coeffs_for`] produces at isolated step ratios: a zero of
    /// a2 = 1 + q·a1 makes tq[2] and tq[3] infinite, and a zero of 1/ξ* makes l_q = 0 and
    /// tq[1], tq[5] = 0/0. The integrator recomputes the coefficients before it uses them,
    /// so the stored ones never influence a later step.
    pub(crate) fn check(&self) -> Result<(), SolverError> {
        require_finite(&self.l, "coeffs.l")?;
        require_not_below_zero(&self.tq, "coeffs.tq")?;
        if self.key_q > QMAX {
            return Err(SolverError::InvalidState { field: "coeffs.key_q" });
        }
        require_finite(&[self.key_h], "coeffs.key_h")?;
        require_finite(&self.key_tau, "coeffs.key_tau")?;
        // Coefficients that would be reused must be the ones their key gives.
        if self.key_q > 0 {
            let q = self.key_q;
            let mut tau = [0.0; NCOL + 1];
            tau[1..=QMAX].copy_from_slice(&self.key_tau);
            if self.key_h <= 0.0
                || self.key_tau[..q].iter().any(|t| *t < 0.0)
                || self.key_tau[q..].iter().any(|t| *t != 0.0)
                || !same(self, &coeffs_for(q, self.key_h, &tau, self.key_order_change))
            {
                return Err(SolverError::InvalidState { field: "coeffs" });
            }
        } else if self.key_h != 0.0 || self.key_tau.iter().any(|t| *t != 0.0) {
            return Err(SolverError::InvalidState { field: "coeffs" });
        }
        Ok(())
    }
}

/// The harmonic numbers H_q = Σ_{j=1}^{q} 1/j, q = 0..=QMAX (−α0 of BDF_q).
const HARMONIC: [f64; NCOL] =
    [0.0, 1.0, 1.5, 1.5 + 1.0 / 3.0, 1.5 + 1.0 / 3.0 + 0.25, 1.5 + 1.0 / 3.0 + 0.25 + 0.2];

/// Bitwise equality of the coefficients (NaN entries included), keys aside.
fn same(a: &StepCoeffs, b: &StepCoeffs) -> bool {
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    bits(&a.l) == bits(&b.l) && bits(&a.tq) == bits(&b.tq)
}

/// Coefficients of the order-q step of size h after the steps `tau`: those of `prev` when
/// they were computed for the same order, steps and `order_change`, else new ones.
///
/// `order_change` asks for tq[1] and tq[3], which need one more past step.
#[cfg(test)]
pub(crate) fn bdf_coeffs(
    prev: &StepCoeffs,
    q: usize,
    h: f64,
    tau: &[f64; NCOL + 1],
    order_change: bool,
) -> StepCoeffs {
    let mut c = *prev;
    c.update(q, h, tau, order_change);
    c
}

impl StepCoeffs {
    /// Makes these the coefficients of the order-q step of size h after the steps `tau`,
    /// keeping them when they were computed for the same order, steps and `order_change`
    /// (in place: this runs at every step attempt).
    ///
    /// `order_change` asks for tq[1] and tq[3], which need one more past step. Returns
    /// whether the coefficients were computed anew (else they are the ones of the same
    /// order, step and past steps).
    pub(crate) fn update(
        &mut self,
        q: usize,
        h: f64,
        tau: &[f64; NCOL + 1],
        order_change: bool,
    ) -> bool {
        debug_assert!((1..=QMAX).contains(&q));
        by_order!(q, Q => self.update_q::<Q>(h, tau, order_change))
    }

    fn update_q<const Q: usize>(
        &mut self,
        h: f64,
        tau: &[f64; NCOL + 1],
        order_change: bool,
    ) -> bool {
        // Coefficients computed with tq[1] and tq[3] serve a step that does not need them:
        // the order change is considered every other step, so this keeps the cache warm.
        // The key holds τ_1..=τ_q, the steps that ξ_2..=ξ_{q+1} are made of.
        if self.key_q == Q
            && self.key_h == h
            && self.key_tau[..Q] == tau[1..=Q]
            && (self.key_order_change || !order_change)
        {
            return false;
        }
        *self = coeffs_q::<Q>(h, tau, order_change);
        true
    }
}

/// The coefficients for order q, step h and past steps `tau` (see [`StepCoeffs::update`]).
fn coeffs_for(q: usize, h: f64, tau: &[f64; NCOL + 1], order_change: bool) -> StepCoeffs {
    by_order!(q, Q => coeffs_q::<Q>(h, tau, order_change))
}

/// [`coeffs_for`] with the order a constant, so that its loops unroll. In terms of the
/// ratios ξ_j = (h + τ_1 + … + τ_{j−1})/h, j = 1..=q+1.
fn coeffs_q<const Q: usize>(h: f64, tau: &[f64; NCOL + 1], order_change: bool) -> StepCoeffs {
    let qf = Q as f64;

    // 1/ξ_j, j = 1..=q+1 (index 0 unused).
    let mut inv_xi = [0.0; NCOL + 1];
    inv_xi[1] = 1.0;
    let mut span = h;
    for j in 2..=(Q + 1).min(NCOL) {
        span += tau[j - 1];
        inv_xi[j] = 1.0 / (span / h);
    }
    // Λ(x) = Π_{j=1}^{q−1} (1 + x/ξ_j) · (1 + x/ξ*): the l_j are its coefficients. After
    // the k-th factor only l_0..=l_k are non-zero, so the update stops there.
    let mut l = [0.0; NCOL];
    l[0] = 1.0;
    #[allow(clippy::needless_range_loop)] // index loops with constant bounds: they unroll
    for k in 1..Q {
        for i in (1..=k).rev() {
            l[i] += l[i - 1] * inv_xi[k];
        }
    }
    // α0 = −Σ 1/j is the leading coefficient of the fixed-leading-coefficient formula;
    // α̂0 = −Σ 1/ξ_j that of the variable-coefficient formula on the same points.
    let alpha0 = -HARMONIC[Q];
    let sum_inv_xi_head: f64 = inv_xi[1..Q].iter().sum();
    let alpha0_hat = -sum_inv_xi_head - inv_xi[Q];
    // 1/ξ* is chosen so that l_1 = −α0.
    let inv_xi_star = if Q == 1 { 1.0 } else { -sum_inv_xi_head - alpha0 };
    for i in (1..=Q).rev() {
        l[i] += l[i - 1] * inv_xi_star;
    }

    let mut tq = [0.0; NCOL];
    let a1 = 1.0 - alpha0_hat + alpha0;
    let a2 = 1.0 + qf * a1;
    tq[2] = (a1 / (alpha0 * a2)).abs();
    tq[5] = (a2 * inv_xi_star / (l[Q] * inv_xi[Q])).abs();
    if order_change {
        tq[1] = if Q > 1 {
            let c = inv_xi_star / l[Q];
            let a3 = alpha0 + 1.0 / qf;
            let a4 = alpha0_hat + inv_xi[Q];
            (c * (1.0 - a4 + a3) / a3).abs()
        } else {
            1.0
        };
        let inv_xi_next = inv_xi[(Q + 1).min(NCOL)];
        let a5 = alpha0 - 1.0 / (qf + 1.0);
        let a6 = alpha0_hat - inv_xi_next;
        let c_next = (1.0 - a6 + a5) / a2;
        tq[3] = (c_next / (inv_xi_next * (qf + 2.0) * a5)).abs();
    }
    let mut key_tau = [0.0; QMAX];
    key_tau[..Q].copy_from_slice(&tau[1..=Q]);
    StepCoeffs { l, tq, key_q: Q, key_order_change: order_change, key_h: h, key_tau }
}

/// Raises the order from q to q+1 after an accepted step of order q: fills z_{q+1} from the
/// saved correction `delta` of that step and adjusts z_2..z_q so the array stays the
/// Nordsieck array of a polynomial through the same history.
///
/// `hscale` is the step the array is scaled with (the last step), `tau` the step history.
pub(crate) fn raise_order<D: Dim>(
    zn: &mut [OVector<f64, D>; NCOL],
    q: usize,
    hscale: f64,
    tau: &[f64; NCOL + 1],
    delta: &OVector<f64, D>,
) where
    DefaultAllocator: Allocator<D>,
{
    debug_assert!(q < QMAX);
    // Distances back from t_n in units of hscale: (τ_1 + … + τ_{j+1}) / hscale.
    let mut c = [0.0; NCOL + 1];
    c[2] = 1.0;
    let mut alpha0 = -1.0;
    let mut alpha1 = 1.0;
    let mut prod = 1.0;
    let mut prev = 1.0;
    let mut span = hscale;
    for j in 1..q {
        span += tau[j + 1];
        let x = span / hscale;
        prod *= x;
        alpha0 -= 1.0 / (j + 1) as f64;
        alpha1 += 1.0 / x;
        for i in (2..=j + 2).rev() {
            c[i] = c[i] * prev + c[i - 1];
        }
        prev = x;
    }
    let a1 = (-alpha0 - alpha1) / prod;
    zn[q + 1] = delta * a1;
    for j in 2..=q {
        let add = &zn[q + 1] * c[j];
        zn[j] += add;
    }
}

/// Lowers the order from q to q−1: drops z_q and adjusts z_2..z_{q−1}.
pub(crate) fn lower_order<D: Dim>(
    zn: &mut [OVector<f64, D>; NCOL],
    q: usize,
    hscale: f64,
    tau: &[f64; NCOL + 1],
) where
    DefaultAllocator: Allocator<D>,
{
    debug_assert!(q >= 2);
    let mut c = [0.0; NCOL + 1];
    c[2] = 1.0;
    let mut span = 0.0;
    for (j, step) in tau.iter().enumerate().take(q.saturating_sub(1)).skip(1) {
        span += step;
        let x = span / hscale;
        for i in (2..=j + 2).rev() {
            c[i] = c[i] * x + c[i - 1];
        }
    }
    for j in 2..q {
        let sub = &zn[q] * c[j];
        zn[j] -= sub;
    }
    zn[q].fill(0.0);
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SVector;

    /// At constant step the formula is the classical BDF; its Nordsieck vectors for BDF1–3
    /// are those of Byrne & Hindmarsh (1975), table I.
    #[test]
    fn constant_step_l_vectors() {
        let tau = [0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let c1 = bdf_coeffs(&StepCoeffs::default(), 1, 1.0, &tau, false);
        assert_eq!(&c1.l[..2], &[1.0, 1.0]);
        let c2 = bdf_coeffs(&StepCoeffs::default(), 2, 1.0, &tau, false);
        // Normalised so that l_0 = 1: BDF2 gives (1, 3/2, 1/2), BDF3 (1, 11/6, 1, 1/6).
        assert!((c2.l[1] - 1.5).abs() < 1e-15 && (c2.l[2] - 0.5).abs() < 1e-15);
        let c3 = bdf_coeffs(&StepCoeffs::default(), 3, 1.0, &tau, false);
        assert!((c3.l[1] - 11.0 / 6.0).abs() < 1e-15);
        assert!((c3.l[2] - 1.0).abs() < 1e-15);
        assert!((c3.l[3] - 1.0 / 6.0).abs() < 1e-15);
    }

    /// l_1 = Σ_{j≤q} 1/j for every order and any step history (fixed leading coefficient).
    #[test]
    fn leading_coefficient_is_fixed() {
        let tau = [0.0, 0.7, 1.3, 0.4, 2.0, 0.9, 1.1];
        for q in 1..=QMAX {
            let c = bdf_coeffs(&StepCoeffs::default(), q, 0.5, &tau, true);
            let want: f64 = (1..=q).map(|j| 1.0 / j as f64).sum();
            assert!((c.l[1] - want).abs() < 1e-14, "q = {q}");
            assert_eq!(c.l[0], 1.0);
            assert!(c.tq[1..=5].iter().enumerate().all(|(i, t)| i == 3 || t.is_finite()));
        }
    }

    /// The cache is keyed by the order, the step, the past steps the order uses and the
    /// flag: a computation with any of them changed gives the coefficients a fresh one
    /// gives, and a key that only differs in past steps beyond q is a hit.
    #[test]
    fn cached_coefficients_are_those_of_a_fresh_computation() {
        let tau = [0.0, 0.7, 1.3, 0.4, 2.0, 0.9, 1.1];
        for q in 1..=QMAX {
            for order_change in [false, true] {
                let first = bdf_coeffs(&StepCoeffs::default(), q, 0.5, &tau, order_change);
                assert_eq!(first, coeffs_for(q, 0.5, &tau, order_change));
                first.check().unwrap();
                // Changed step, a changed past step within q, the other order.
                let mut changed = tau;
                changed[q] *= 1.5;
                let other_q = if q == 1 { 2 } else { q - 1 };
                for (qq, h, t) in [(q, 0.6, tau), (q, 0.5, changed), (other_q, 0.5, tau)] {
                    let got = bdf_coeffs(&first, qq, h, &t, order_change);
                    assert!(same(&got, &coeffs_for(qq, h, &t, order_change)), "q = {q}");
                    assert_eq!((got.key_q, got.key_h), (qq, h));
                }
                // A step beyond q changed: not part of the key, a hit.
                let mut beyond = tau;
                beyond[(q + 1).min(NCOL)] += 1.0;
                assert_eq!(bdf_coeffs(&first, q, 0.5, &beyond, order_change), first);
                // Coefficients with tq[1] and tq[3] serve a step without the order change,
                // not the other way round.
                let plain = bdf_coeffs(&first, q, 0.5, &tau, false);
                assert_eq!(plain, first);
                if !order_change {
                    let full = bdf_coeffs(&first, q, 0.5, &tau, true);
                    assert!(full.key_order_change && full.tq[3] != 0.0, "q = {q}");
                }
            }
        }
    }

    /// Raising then lowering the order at constant step returns the original array.
    #[test]
    fn raise_then_lower_is_identity_on_old_columns() {
        let tau = [0.0, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1];
        let mut zn = [SVector::<f64, 1>::zeros(); NCOL];
        for (j, z) in zn.iter_mut().enumerate().take(4) {
            z[0] = 1.0 / (j as f64 + 1.0);
        }
        let before = zn;
        let delta = SVector::<f64, 1>::new(0.3);
        raise_order(&mut zn, 3, 0.1, &tau, &delta);
        lower_order(&mut zn, 4, 0.1, &tau);
        for j in 0..=3 {
            assert!((zn[j][0] - before[j][0]).abs() < 1e-14, "column {j}");
        }
    }
}
