//! The modified Newton iteration of a step: the iteration, the Jacobian (analytic or by finite
//! differences, CVODE cvLsSetup/cvDlsDQJac) and the LU of I − γJ, with their reuse.

use super::*;

impl<D: Dim> Bdf<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// Solves the corrector equation γ·f(t_n, y_n) = z_1/l_1 + Δ for the correction
    /// Δ = y_n − y_n(predicted) by modified Newton on I − γJ, reusing J and the LU.
    pub(super) fn newton<S: OdeSystem<D>>(
        &mut self,
        sys: &S,
        mut conv_fail: ConvFail,
    ) -> Result<(), NewtonFail> {
        loop {
            let gamma_ratio = self.derived.gamma_ratio;
            let needs_setup = !self.has_factor()
                || conv_fail != ConvFail::None
                || self.stats.steps >= self.steps_at_lu + REFACTOR_STEPS
                || (gamma_ratio - 1.0).abs() > REFACTOR_GAMMA_RATIO;
            let mut fresh_jac = false;
            if needs_setup {
                fresh_jac = !self.jac_valid
                    || self.stats.steps >= self.steps_at_jac + self.rejac_steps()
                    || conv_fail == ConvFail::Other
                    || (conv_fail == ConvFail::BadJacobian
                        && (gamma_ratio - 1.0).abs() < REJAC_GAMMA_RATIO);
                if fresh_jac {
                    self.evaluate_jacobian(sys)?;
                }
                self.factor()?;
            }
            match self.newton_iterate(sys) {
                Ok(()) => return Ok(()),
                Err(NewtonFail::Diverged) if !fresh_jac => conv_fail = ConvFail::BadJacobian,
                Err(NewtonFail::NonFinite) if !fresh_jac => conv_fail = ConvFail::Other,
                Err(e) => return Err(e),
            }
        }
    }

    /// Steps after which J is evaluated again, at the latest.
    fn rejac_steps(&self) -> u64 {
        if self.structure.is_some() {
            REJAC_STEPS_STRUCTURED
        } else {
            REJAC_STEPS
        }
    }

    pub(super) fn newton_iterate<S: OdeSystem<D>>(&mut self, sys: &S) -> Result<(), NewtonFail> {
        if !self.has_factor() {
            return Err(NewtonFail::Singular);
        }
        // A stale γ in the LU is corrected by scaling the update (CVODE cvLsSolve for BDF).
        let NewtonScalars { scale, inv_l1, tol, .. } = self.derived;
        let mut acor = OVector::<f64, D>::zeros_generic(self.zn[0].shape_generic().0, U1);
        let mut y = self.zn[0].clone();
        let mut del2_prev = 0.0;
        for m in 0..NEWTON_MAX_ITERS {
            let f = sys.rhs(self.t, &y);
            self.stats.rhs_evals += 1;
            self.stats.newton_iters += 1;
            // A non-finite f needs no test of its own: ±∞ or NaN in f gives ±∞ or NaN in the
            // residual, the solve carries it into Δ (no product or sum makes it finite again),
            // and the test of ‖Δ‖ below fails in this same iteration.
            let residual = f * self.gamma - (&self.zn[1] * inv_l1 + &acor);
            let delta = match (&self.structure, &self.structured, &self.lu) {
                (Some(parts), Some(f), _) => {
                    let mut r = residual;
                    f.solve(parts, r.as_mut_slice());
                    r * scale
                }
                (_, _, Some(lu)) => lu.solve(&residual) * scale,
                _ => return Err(NewtonFail::Singular),
            };
            acor += &delta;
            y = &self.zn[0] + &acor;
            // The tests on squares: no square root on the iteration's chain (the one root
            // left, of the ratio, is taken from the second iteration on).
            let del2 = self.wrms_squared(&delta);
            if !del2.is_finite() {
                return Err(NewtonFail::NonFinite);
            }
            if m > 0 {
                self.rate = (RATE_DAMPING * self.rate).max((del2 / del2_prev).sqrt());
            }
            let damped = self.rate.min(1.0);
            if del2 * (damped * damped) <= tol * tol {
                self.acor = acor;
                return Ok(());
            }
            if m > 0 && del2 > DIVERGENCE_RATIO * DIVERGENCE_RATIO * del2_prev {
                break;
            }
            del2_prev = del2;
        }
        Err(NewtonFail::Diverged)
    }

    /// J at the predicted state: analytic if the system has one, else forward differences
    /// with CVODE's increment rule (cvLsDenseDQJac): σ_j = max(√ε·|y_j|, m_inc/w_j) with
    /// m_inc = 1000·|h|·ε·N·‖f‖_wrms.
    pub(super) fn evaluate_jacobian<S: OdeSystem<D>>(&mut self, sys: &S) -> Result<(), NewtonFail> {
        let y = self.zn[0].clone();
        let n = y.len();
        self.stats.jac_evals += 1;
        self.steps_at_jac = self.stats.steps;
        let structure = self
            .second_order
            .and_then(|layout| sys.second_order(self.t, &y).filter(|s| s.layout() == layout));
        let dense = structure.as_ref().map(|s| {
            let d = y.shape_generic().0;
            s.dense_jacobian()
                .map(|j| OMatrix::<f64, D, D>::from_iterator_generic(d, d, j.iter().copied()))
        });
        self.structure = structure;
        let jac = match dense {
            Some(Some(j)) => j,
            Some(None) => {
                self.jac_valid = false;
                return Err(NewtonFail::NonFinite);
            }
            None => match sys.jacobian(self.t, &y) {
                Some(j) => j,
                None => {
                    let f0 = sys.rhs(self.t, &y);
                    self.stats.rhs_evals_jac += 1;
                    if !f0.iter().all(|v| v.is_finite()) {
                        return Err(NewtonFail::NonFinite);
                    }
                    let fnorm = self.wrms(&f0);
                    let min_inc = if fnorm > 0.0 {
                        FD_MIN_INC_MULT * self.h.abs() * f64::EPSILON * n as f64 * fnorm
                    } else {
                        1.0
                    };
                    let sqrt_eps = f64::EPSILON.sqrt();
                    let d = y.shape_generic().0;
                    let mut jac = OMatrix::<f64, D, D>::zeros_generic(d, d);
                    let mut yj = y.clone();
                    for j in 0..n {
                        let inc = (sqrt_eps * y[j].abs()).max(min_inc / self.ewt[j]);
                        yj[j] = y[j] + inc;
                        let fj = sys.rhs(self.t, &yj);
                        yj[j] = y[j];
                        self.stats.rhs_evals_jac += 1;
                        jac.set_column(j, &((fj - &f0) / inc));
                    }
                    jac
                }
            },
        };
        if !all_finite(jac.as_slice()) {
            self.jac_valid = false;
            return Err(NewtonFail::NonFinite);
        }
        self.jac = jac;
        self.jac_valid = true;
        if self.cfg.stability_guard && self.cfg.fixed_step.is_none() {
            self.guard.update(&self.jac);
        } else {
            self.guard.clear();
        }
        Ok(())
    }

    /// LU of I − γJ with the current γ (structured, if the Jacobian is).
    pub(super) fn factor(&mut self) -> Result<(), NewtonFail> {
        if let Some(parts) = &self.structure {
            self.structured = parts.factor(self.gamma);
            self.lu = None;
        } else {
            let d = self.jac.shape_generic().0;
            let m = OMatrix::<f64, D, D>::identity_generic(d, d) - &self.jac * self.gamma;
            self.lu = Lu::factor(&m);
            self.structured = None;
        }
        self.stats.lu_factorizations += 1;
        self.steps_at_lu = self.stats.steps;
        self.gamma_lu = self.gamma;
        self.derive_gamma_ratio();
        self.rate = 1.0;
        if self.has_factor() {
            Ok(())
        } else {
            Err(NewtonFail::Singular)
        }
    }

    // ----- after an accepted step ---------------------------------------------------------
}
