//! The Nordsieck history: prediction by the Pascal triangle and its undoing, rescaling for
//! a new step size, the method's coefficients, and the history's update after a step.

use super::*;

/// The prediction z ← P·z by the Pascal triangle (CVODE cvPredict), or with `UNDO` its
/// inverse (cvRestore), for order q. This runs at every step attempt. The additions are
/// written out for each order, each on two columns split apart (`split_at_mut`), so that
/// the compiler sees them disjoint and, for a fixed dimension, keeps the columns in
/// registers (loops over j kept them in memory; docs/decisions.md, "The prediction written
/// out"). They are those of the triangle, in its order.
pub(super) fn pascal<D: Dim, const UNDO: bool>(zn: &mut [OVector<f64, D>; NCOL], q: usize)
where
    DefaultAllocator: Allocator<D>,
{
    /// z_{j−1} ± z_j for each j listed, in the order listed.
    macro_rules! triangle {
        ($q:literal: $($j:literal)*) => {{
            $(
                let (lo, hi) = zn.split_at_mut($j);
                if UNDO {
                    lo[$j - 1] -= &hi[0];
                } else {
                    lo[$j - 1] += &hi[0];
                }
            )*
        }};
    }
    // The sweeps k = 1..=q, each j = q down to k.
    match q {
        1 => triangle!(1: 1),
        2 => triangle!(2: 2 1 2),
        3 => triangle!(3: 3 2 1 3 2 3),
        4 => triangle!(4: 4 3 2 1 4 3 2 4 3 4),
        _ => triangle!(5: 5 4 3 2 1 5 4 3 2 5 4 3 5 4 5),
    }
}

impl<D: Dim> Bdf<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// Advances t and predicts the Nordsieck array by the Pascal triangle.
    pub(super) fn predict(&mut self) {
        self.t = match self.landing {
            Some(tstop) => tstop,
            None => self.t + self.h,
        };
        pascal::<D, false>(&mut self.zn, self.q);
    }

    /// Undoes [`predict`](Self::predict) after a rejected step.
    pub(super) fn restore(&mut self, t_prior: f64) {
        self.t = t_prior;
        pascal::<D, true>(&mut self.zn, self.q);
    }

    /// Multiplies the step by `eta`: z_j ← η^j z_j.
    pub(super) fn rescale(&mut self, eta: f64) {
        let mut factor = 1.0;
        for j in 1..=self.q {
            factor *= eta;
            self.zn[j] *= factor;
        }
        self.h = self.hscale * eta;
        self.hscale = self.h;
        if let Some(tstop) = self.landing {
            // A rescale after a failure abandons the landing.
            if (self.t + self.h - tstop).abs() > 1e-12 * self.h.abs().max(tstop.abs()) {
                self.landing = None;
            }
        }
    }

    /// The coefficients of the attempt, and γ = h/l_1 with what the Newton iteration derives
    /// from it, when the step, the order or the past steps changed.
    pub(super) fn set_coeffs(&mut self) {
        if self.coeffs.update(self.q, self.h, &self.tau, self.qwait == 1) {
            self.gamma = self.h / self.coeffs.l[1];
            self.derive_from_coeffs();
        }
    }

    /// [`NewtonScalars`] from γ, γ of the LU and the coefficients.
    pub(super) fn derive_from_coeffs(&mut self) {
        self.derived.inv_l1 = 1.0 / self.coeffs.l[1];
        self.derived.tol = NEWTON_COEF / self.coeffs.tq[2];
        self.derive_gamma_ratio();
    }

    /// The γ ratio and the update's scale of [`NewtonScalars`].
    pub(super) fn derive_gamma_ratio(&mut self) {
        let ratio = if self.has_factor() { self.gamma / self.gamma_lu } else { 1.0 };
        self.derived.gamma_ratio = ratio;
        self.derived.scale = if ratio != 1.0 { 2.0 / (1.0 + ratio) } else { 1.0 };
    }

    // ----- Newton -------------------------------------------------------------------------

    pub(super) fn complete_step(&mut self) {
        self.stats.steps += 1;
        self.hu = self.h;
        self.qu = self.q;
        // Both loops with the order as a constant (`by_order!`), so that they unroll.
        fn shift_history<const Q: usize>(tau: &mut [f64; NCOL + 1]) {
            for i in (2..=Q).rev() {
                tau[i] = tau[i - 1];
            }
        }
        fn correct<D: Dim, const Q: usize>(
            zn: &mut [OVector<f64, D>; NCOL],
            acor: &OVector<f64, D>,
            l: &[f64; NCOL],
        ) where
            DefaultAllocator: Allocator<D>,
        {
            for j in 0..=Q {
                zn[j] += acor * l[j];
            }
        }
        by_order!(self.q, Q => shift_history::<Q>(&mut self.tau));
        if self.q == 1 && self.stats.steps > 1 {
            self.tau[2] = self.tau[1];
        }
        self.tau[1] = self.h;
        by_order!(self.q, Q => correct::<D, Q>(&mut self.zn, &self.acor, &self.coeffs.l));
        self.qwait = self.qwait.saturating_sub(1);
        let qmax = self.max_order();
        let fixed_raising = self.cfg.fixed_step.is_some() && self.q < qmax;
        if (self.qwait == 1 || fixed_raising) && self.q != qmax {
            // Keep this correction: the error estimate at order q+1 and the raise need it.
            self.zn[qmax].copy_from(&self.acor);
            self.saved_tq5 = self.coeffs.tq[5];
        }
        self.update_weights();
    }
}
