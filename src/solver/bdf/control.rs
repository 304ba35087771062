//! Step-size and order selection after a step, and after a failed attempt (CVODE cvCompleteStep, cvPrepareNextStep,
//! cvChooseEta, cvAdjustOrder) and the step ratios they compute.

use super::*;

/// The step-size ratio that brings an error estimate `err` (in units of the tolerance, for
/// a method whose error scales as h^`exponent`) to 1/`bias` of the tolerance:
/// η = 1/((bias·err)^(1/exponent) + ADDON) (CVODE cvChooseEta and cvHandleNFlag).
pub(super) fn step_ratio(bias: f64, err: f64, exponent: usize) -> f64 {
    1.0 / (root(bias * err, exponent) + ADDON)
}

/// Whether the step ratio of [`step_ratio`] for `bias_err` = bias·err and `exponent` is at
/// least `eta` (> 1), without the root: bias·err ≤ (1/eta − ADDON)^exponent.
pub(super) fn ratio_at_least(bias_err: f64, exponent: usize, eta: f64) -> bool {
    bias_err <= math::powi(1.0 / eta - ADDON, exponent as i32)
}

/// (1/ETA_THRESHOLD − ADDON)^k for k = 0..=QMAX + 2, by the multiplications of
/// [`math::powi`], so that [`grows_sq`] decides as `ratio_at_least(.., ETA_THRESHOLD)` does.
pub(super) const GROWTH_BOUNDS: [f64; QMAX + 3] = {
    let base = 1.0 / ETA_THRESHOLD - ADDON;
    let mut table = [0.0; QMAX + 3];
    let mut k = 0;
    while k < table.len() {
        table[k] = math::powi_const(base, k as u32);
        k += 1;
    }
    table
};

/// Whether the step ratio for `bias_err_sq` = (bias·err)² and `exponent` reaches
/// ETA_THRESHOLD, the least growth that changes the step: (bias·err)² ≤
/// ((1/ETA_THRESHOLD − ADDON)^exponent)², the power from a table, on squares so that the
/// weighted norm needs no square root. It decides as `ratio_at_least(.., ETA_THRESHOLD)`
/// does, but at ties within round-off.
pub(super) fn grows_sq((bias_err_sq, exponent): (f64, usize)) -> bool {
    let bound = GROWTH_BOUNDS[exponent.min(QMAX + 2)];
    bias_err_sq <= bound * bound
}

/// Whether a^(1/k) < b^(1/l) for (a, k) and (b, l), a and b ≥ 0 or infinite: as
/// a^l < b^k, two integer powers, where these cannot overflow or underflow (a and b 0,
/// infinite or within 1e±40, and k, l ≤ 7), else as log(a)/k < log(b)/l. The two agree but
/// at ties within round-off.
pub(super) fn root_less((a, k): (f64, usize), (b, l): (f64, usize)) -> bool {
    let tame = |x: f64| x == 0.0 || x.is_infinite() || (1e-40..=1e40).contains(&x);
    if tame(a) && tame(b) && k <= 7 && l <= 7 {
        math::powi(a, l as i32) < math::powi(b, k as i32)
    } else {
        math::ln(a) / (k as f64) < math::ln(b) / (l as f64)
    }
}

/// x^(1/k), by square roots where they serve (k = 1, 2, 4): a fraction of the cost of
/// `powf`, which the order selection calls two or three times every other step. (Rust's
/// `cbrt` is correctly rounded and no cheaper than `powf`.)
pub(super) fn root(x: f64, k: usize) -> f64 {
    match k {
        1 => x,
        2 => x.sqrt(),
        4 => x.sqrt().sqrt(),
        _ => math::pow(x, 1.0 / k as f64),
    }
}

impl<D: Dim> Bdf<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// Chooses the order and step of the next step from the error estimates at orders q−1,
    /// q and q+1 (CVODE cvPrepareNextStep / cvChooseEta / cvSetEta), then applies the
    /// stability guard.
    pub(super) fn choose_next(&mut self, dsm_sq: f64) {
        if let Some(fixed) = self.cfg.fixed_step {
            self.h_next = fixed.h;
            self.q_next = (self.q + 1).min(fixed.order);
            return;
        }
        let (mut q_next, mut eta) = (self.q, 1.0);
        if self.eta_max > 1.0 {
            (q_next, eta) = if self.qwait != 0 {
                (self.q, self.eta_same_order(dsm_sq))
            } else {
                self.qwait = 2;
                self.eta_and_order(dsm_sq)
            };
            if eta < ETA_THRESHOLD {
                eta = 1.0;
                q_next = self.q;
            } else {
                eta = self.limit_growth(eta);
            }
        } else {
            self.qwait = self.qwait.max(2);
        }
        if self.cfg.stability_guard
            && self.guard.max_safe_order(q_next, self.h * eta, &self.jac) < q_next
        {
            // A weakly damped mode of J would sit in the unstable band of that order: take
            // instead the stable order whose own error estimate allows the largest step, if
            // one keeps the resolved modes accurate. If none does, the mode is left to the
            // error test, which sees its growth and shortens the step.
            if let Some(choice) = self.best_stable_order(q_next, dsm_sq.sqrt()) {
                self.stats.order_caps += 1;
                (q_next, eta) = choice;
            }
        }
        self.q_next = q_next;
        self.h_next = self.h * eta;
    }

    /// The step ratio at the same order (CVODE cvSetEta's case without an order change).
    /// Only a growth by ETA_THRESHOLD or more changes the step. Below
    /// (BIAS_SAME·dsm > (1/ETA_THRESHOLD − ADDON)^(q+1)) the ratio need not be computed:
    /// this saves a powf in most steps.
    pub(super) fn eta_same_order(&self, dsm_sq: f64) -> f64 {
        let q = self.q;
        if !grows_sq((BIAS_SAME * BIAS_SAME * dsm_sq, q + 1)) {
            return 1.0;
        }
        let dsm = dsm_sq.sqrt();
        if self.capped(BIAS_SAME * dsm, q + 1) {
            self.eta_max
        } else {
            step_ratio(BIAS_SAME, dsm, q + 1)
        }
    }

    /// Whether the step ratio 1/((bias·err)^(1/k) + ADDON) of `bias_err` = bias·err is surely
    /// above `eta_max`, which then caps it ([`limit_growth`](Self::limit_growth)), when
    /// eta_max is itself a growth (≥ ETA_THRESHOLD): the ratio need not be computed. A
    /// comparison with an integer power, with a margin of a factor 2 in bias·err (2^(1/k) in
    /// the ratio) that no rounding of the root bridges, so the step is what the root gives.
    /// This is the common case of a step held short by the landing on a communication point,
    /// where the estimate would allow far more.
    pub(super) fn capped(&self, bias_err: f64, k: usize) -> bool {
        self.eta_max >= ETA_THRESHOLD && ratio_at_least(2.0 * bias_err, k, self.eta_max)
    }

    /// The order among q − 1, q, q + 1 that allows the largest step, and that step's ratio
    /// (CVODE cvChooseEta, from the error estimates of cvComputeEtaqm1 and cvComputeEtaqp1).
    /// The candidates (bias·err)^(1/k) are compared by integer powers ([`root_less`]), the
    /// smallest giving the largest η; the chosen one's ratio is exp(log(bias·err)/k), one
    /// logarithm and one exp, unless eta_max caps it anyway.
    pub(super) fn eta_and_order(&mut self, dsm_sq: f64) -> (usize, f64) {
        let q = self.q;
        // The candidates first as squares, (bias·err)²: no square root in the common case.
        let same_sq = (BIAS_SAME * BIAS_SAME * dsm_sq, q + 1);
        let mut down_sq = (f64::INFINITY, q);
        if q > 1 {
            let tq1 = self.coeffs.tq[1];
            down_sq.0 = BIAS_DOWN * BIAS_DOWN * (self.wrms_squared(&self.zn[q]) * (tq1 * tq1));
        }
        let qmax = self.cfg.max_order;
        let mut up_sq = (f64::INFINITY, q + 2);
        if q != qmax && self.saved_tq5 != 0.0 {
            let ratio = (self.coeffs.tq[5] / self.saved_tq5)
                * math::powi(self.h / self.tau[2], q as i32 + 1);
            let diff = &self.acor - &self.zn[qmax] * ratio;
            let tq3 = self.coeffs.tq[3];
            up_sq.0 = BIAS_UP * BIAS_UP * (self.wrms_squared(&diff) * (tq3 * tq3));
        }
        // An order whose step ratio stays below the threshold is no candidate: if none
        // reaches it, the step and the order stay (choose_next), and the comparisons and the
        // root are not needed. This is the common case.
        if !(grows_sq(same_sq) || grows_sq(down_sq) || grows_sq(up_sq)) {
            return (q, 1.0);
        }
        let unsquare = |(x, k): (f64, usize)| (x.sqrt(), k);
        let (same, down, up) = (unsquare(same_sq), unsquare(down_sq), unsquare(up_sq));
        let (mut best, mut q_next) = (same, q);
        if root_less(down, best) && !root_less(up, down) {
            best = down;
            q_next = q - 1;
        } else if root_less(up, best) {
            best = up;
            q_next = q + 1;
            self.zn[qmax].copy_from(&self.acor);
        }
        let (bias_err, k) = best;
        if self.capped(bias_err, k) {
            return (q_next, self.eta_max);
        }
        (q_next, 1.0 / (math::exp(math::ln(bias_err) / k as f64) + ADDON))
    }

    /// The order k ≤ `limit` (and ≤ q) and step ratio η with the largest step among those the
    /// stability guard accepts ([`StabilityGuard::acceptable`] with a drift of at most rtol per
    /// period). Order q uses its error estimate `dsm`; a lower order k uses the local error of
    /// BDF_k at constant step, k!·z_{k+1} (error constant 1/(k+1) times h^{k+1}y^{(k+1)}).
    /// `None` if no order is acceptable.
    pub(super) fn best_stable_order(&self, limit: usize, dsm: f64) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        let mut factorial = 1.0;
        for k in 1..=limit.min(self.q) {
            factorial *= k as f64;
            let err = if k == self.q { dsm } else { factorial * self.wrms(&self.zn[k + 1]) };
            let raw = step_ratio(BIAS_SAME, err, k + 1);
            // Grow only past the usual threshold; shrink at once if the estimate asks for it.
            let eta = if raw < ETA_THRESHOLD { raw.min(1.0) } else { self.limit_growth(raw) };
            let larger = best.is_none_or(|(_, b)| eta > b);
            if larger && self.guard.acceptable(k, self.h * eta, self.cfg.rtol) {
                best = Some((k, eta));
            }
        }
        best
    }

    // ----- helpers ------------------------------------------------------------------------

    /// Caps a step-size ratio at `eta_max` and so that the step stays ≤ `h_max` (CVODE
    /// cvSetEta).
    pub(super) fn limit_growth(&self, eta: f64) -> f64 {
        let eta = eta.min(self.eta_max);
        eta / (self.h.abs() * eta / self.cfg.h_max).max(1.0)
    }

    /// After a failed Newton iteration (CVODE cvHandleNFlag): gives up after
    /// MAX_NEWTON_FAILURES, at the smallest step or in fixed-step mode; else shrinks the step.
    pub(super) fn handle_newton_failure(
        &mut self,
        why: NewtonFail,
        failures: &mut Failures,
    ) -> Result<(), SolverError> {
        failures.newton += 1;
        self.stats.newton_failures += 1;
        self.eta_max = 1.0;
        let at_floor = self.h.abs() <= self.cfg.h_min * (1.0 + 1e-12);
        if failures.newton >= MAX_NEWTON_FAILURES || at_floor || self.cfg.fixed_step.is_some() {
            return Err(match why {
                NewtonFail::NonFinite => SolverError::NonFiniteRhs { t: self.t },
                NewtonFail::Singular => SolverError::SingularMatrix { t: self.t, h: self.h },
                NewtonFail::Diverged => {
                    SolverError::NewtonFailures { t: self.t, h: self.h, failures: failures.newton }
                }
            });
        }
        let eta = ETA_NEWTON_FAIL.max(self.cfg.h_min / self.h.abs());
        self.rescale(eta);
        Ok(())
    }

    /// After a failed error test (CVODE cvDoErrorTest's failure branch): gives up after
    /// MAX_ERROR_FAILURES; else shrinks the step by the error's ratio, then, after repeated
    /// failures, drops the order, and at order 1 restarts from a fresh derivative.
    pub(super) fn handle_error_test_failure<S: OdeSystem<D>>(
        &mut self,
        sys: &S,
        dsm: f64,
        failures: &mut Failures,
    ) -> Result<(), SolverError> {
        failures.error_test += 1;
        self.stats.error_test_failures += 1;
        self.eta_max = 1.0;
        if failures.error_test >= MAX_ERROR_FAILURES {
            return Err(SolverError::ErrorTestFailures {
                t: self.t,
                h: self.h,
                failures: failures.error_test,
            });
        }
        let floor = self.cfg.h_min / self.h.abs();
        if failures.error_test < ERROR_FAILURES_ORDER_DROP {
            let mut eta = step_ratio(BIAS_SAME, dsm, self.q + 1);
            eta = eta.max(ETA_MIN).max(floor);
            if failures.error_test >= ERROR_FAILURES_GROWTH_CAP {
                eta = eta.min(ETA_MAX_AFTER_FAILURES);
            }
            self.rescale(eta);
        } else if self.q > 1 {
            // Repeated failures: the history is suspect; drop the order.
            lower_order(&mut self.zn, self.q, self.hscale, &self.tau);
            self.q -= 1;
            self.qwait = self.q + 1;
            self.rescale(ETA_MIN.max(floor));
        } else {
            // Order 1 already: restart from a fresh derivative.
            self.h *= ETA_MIN.max(floor);
            self.hscale = self.h;
            self.landing = None;
            self.qwait = LONG_WAIT;
            let (t, y) = (self.t, self.zn[0].clone());
            let f = self.eval_rhs(sys, t, &y);
            if !f.iter().all(|v| v.is_finite()) {
                return Err(SolverError::NonFiniteRhs { t: self.t });
            }
            self.zn[1] = f * self.h;
        }
        Ok(())
    }
}
