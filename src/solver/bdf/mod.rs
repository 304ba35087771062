//! The integrator: variable-order (1–5), variable-step BDF in Nordsieck form with modified
//! Newton iteration, in the manner of CVODE.
//!
//! Step and order selection, Newton convergence and Jacobian/LU reuse follow the CVODE
//! description (Hindmarsh et al., "SUNDIALS", ACM TOMS 31 (2005), §2.1, and the SUNDIALS
//! CVODE user guide, "Mathematical considerations"); every constant below names its source.
//! With a fixed dimension all data live on the stack and a step allocates nothing.

use super::coeffs::{lower_order, raise_order, StepCoeffs, NCOL, QMAX};
use super::config::BdfConfig;
use super::error::{Allowed, SolverError};
use super::guard::StabilityGuard;
use super::lu::Lu;
use super::second_order::{Layout, SecondOrder, SecondOrderLu};
use super::snapshot::{
    require, require_finite, require_non_negative, require_not_below_zero, visit_matrix,
    visit_usize, visit_vector, StateVisitor, MAX_COUNT,
};
use super::stats::Stats;
use super::system::{OdeSystem, RangeViolation};
use crate::math;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector, U1};

mod control;
mod newton;
mod nordsieck;
mod state;

// Step-size factors (CVODE, cvode.c): growth cap on the first step and later steps, cap after
// two error failures, floor after an error failure, factor after a Newton failure.
const ETA_MAX_FIRST: f64 = 1.0e4;
const ETA_MAX: f64 = 10.0;
const ETA_MAX_AFTER_FAILURES: f64 = 0.2;
const ETA_MIN: f64 = 0.1;
const ETA_NEWTON_FAIL: f64 = 0.25;
/// A new step size is adopted only if it is at least this factor larger (CVODE's THRESH).
const ETA_THRESHOLD: f64 = 1.5;
/// Safety biases on the error estimates at orders q−1, q, q+1, and the small addend in
/// η = 1/((bias·dsm)^(1/(q+1)) + ADDON) (CVODE's BIAS1, BIAS2, BIAS3, ADDON).
const BIAS_DOWN: f64 = 6.0;
const BIAS_SAME: f64 = 6.0;
const BIAS_UP: f64 = 10.0;
const ADDON: f64 = 1.0e-6;
/// Failure limits per step (CVODE's defaults maxnef = 7, maxncf = 10), and the error-failure
/// count after which the order drops (MXNEF1 = 3) and the growth cap applies (SMALL_NEF = 2).
const MAX_ERROR_FAILURES: u32 = 7;
const MAX_NEWTON_FAILURES: u32 = 10;
const ERROR_FAILURES_ORDER_DROP: u32 = 3;
const ERROR_FAILURES_GROWTH_CAP: u32 = 2;
/// Steps to wait at order 1 after the order was forced down to 1 (LONG_WAIT).
const LONG_WAIT: usize = 10;
/// Largest `qwait` the integrator sets: LONG_WAIT, q + 1 ≤ QMAX + 1 after an order change, or
/// 2; it only counts down from there. A restored state may not exceed it.
const MAX_QWAIT: usize = if LONG_WAIT > QMAX + 1 { LONG_WAIT } else { QMAX + 1 };
// Newton (CVODE cvNls): iterations per attempt, rate damping, divergence ratio, and the
// fraction of the error budget the iteration error may take (NLS_MAXCOR, CRDOWN, RDIV,
// nlscoef).
const NEWTON_MAX_ITERS: usize = 3;
const RATE_DAMPING: f64 = 0.3;
const DIVERGENCE_RATIO: f64 = 2.0;
const NEWTON_COEF: f64 = 0.1;
// Jacobian and LU reuse (CVODE cvLs): refactor after MSBP steps or when γ changed by more than
// DGMAX; re-evaluate J after MSBJ steps, or after a Newton failure when γ changed little.
const REFACTOR_STEPS: u64 = 20;
const REFACTOR_GAMMA_RATIO: f64 = 0.3;
const REJAC_STEPS: u64 = 51;
/// MSBJ for a Jacobian in parts (`OdeSystem::second_order`, n elements): with it the guard
/// takes the eigenvalues of the dense J, O(N³) against the O(N) of a step, and the Newton
/// iteration's own tests ask for a fresh J when the old one stops converging (CVODE lets a
/// user set MSBJ, `CVodeSetJacEvalFrequency`, for the same trade).
const REJAC_STEPS_STRUCTURED: u64 = 200;
const REJAC_GAMMA_RATIO: f64 = 0.2;
/// Floor of the finite-difference increment, in units of h·ε·N·‖f‖ (CVODE's MIN_INC_MULT).
const FD_MIN_INC_MULT: f64 = 1000.0;

/// A step that would end within this relative distance short of the stop time is stretched
/// to land on it, rather than leave a sliver of a step (round-off in a fixed-step run).
const LANDING_STRETCH: f64 = 1e-6;

/// Whether every element is finite, as `iter().all(is_finite)` decides, without its early
/// exit: branch-free, so that it vectorizes.
fn all_finite(xs: &[f64]) -> bool {
    xs.iter().fold(true, |ok, x| ok & x.is_finite())
}

/// What one call of [`Bdf::step`] achieved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepOutcome {
    /// One step was accepted; the stop time is still ahead.
    Stepped,
    /// The step landed exactly on the stop time.
    ReachedStop,
    /// Only from [`Bdf::probe_step`]: the first attempt failed its error test, and the
    /// solver is back at t_n.
    Rejected,
}

/// Why the last Newton attempt failed, which decides what the next setup refreshes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ConvFail {
    None,
    /// The iteration failed with a stale Jacobian.
    BadJacobian,
    /// The last attempt failed the error test: refactor with the new γ, keep J.
    ErrorTest,
    /// The last attempt failed Newton for another reason: fresh J.
    Other,
}

/// Why a Newton attempt gave up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum NewtonFail {
    Diverged,
    NonFinite,
    Singular,
}

/// See [`Bdf::derived`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct NewtonScalars {
    /// γ / γ of the LU (1 without an LU).
    gamma_ratio: f64,
    /// The update's scale for a stale γ in the LU: 2/(1 + γ ratio) (CVODE cvLsSolve).
    scale: f64,
    /// 1 / l_1.
    inv_l1: f64,
    /// The bound on the iteration's weighted correction, NEWTON_COEF / tq[2].
    tol: f64,
}

/// Failed attempts of the current step, by kind.
#[derive(Default)]
struct Failures {
    newton: u32,
    error_test: u32,
}

/// The integrator state: history, order, step, Newton matrix, counters. `Clone` copies all of
/// it, so a clone continues exactly as the original would (FMU state save and restore).
#[derive(Clone, Debug)]
pub struct Bdf<D: Dim>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    cfg: BdfConfig,
    /// Absolute tolerance per state: `cfg.atol()` for each, unless [`set_atol`](Self::set_atol).
    atol: OVector<f64, D>,
    /// t_n, the time of the last accepted step.
    t: f64,
    /// Nordsieck array z_j = hscale^j y^(j)(t_n)/j!.
    zn: [OVector<f64, D>; NCOL],
    /// The step the columns of `zn` are scaled with.
    hscale: f64,
    /// Size of the step being attempted (after the pending change is applied).
    h: f64,
    /// Order of the step being attempted.
    q: usize,
    /// Order and step chosen for the next step, applied when it starts.
    q_next: usize,
    h_next: f64,
    /// Steps to wait before an order change is considered.
    qwait: usize,
    /// Recent accepted step sizes, tau[1] the most recent.
    tau: [f64; NCOL + 1],
    coeffs: StepCoeffs,
    /// tq[5] of the step whose correction was saved in zn[qmax].
    saved_tq5: f64,
    /// Size and order of the last accepted step.
    hu: f64,
    qu: usize,
    /// The last accepted correction and its norm.
    acor: OVector<f64, D>,
    /// Error weights 1/(rtol|y| + atol).
    ewt: OVector<f64, D>,
    /// Cap on the next step-size ratio.
    eta_max: f64,
    /// Newton: Jacobian, LU of I − γ_p·J, γ = h/l_1, the γ_p of the LU, convergence rate.
    jac: OMatrix<f64, D, D>,
    jac_valid: bool,
    lu: Option<Lu<D>>,
    /// With [`set_second_order`](Self::set_second_order): the system's structured Jacobian
    /// at the point of `jac` (`jac` is then its dense copy, for the guard), and the O(n)
    /// factorisation of the Newton matrix in place of `lu`.
    second_order: Option<Layout>,
    structure: Option<SecondOrder>,
    structured: Option<SecondOrderLu>,
    /// A restored state flagged a factorisation its parts do not give (not visited: set on
    /// reading, refused by the check).
    lu_unrestorable: bool,
    gamma: f64,
    gamma_lu: f64,
    /// What the Newton iteration derives from γ, γ of the LU and the coefficients, which
    /// change only with the step or the order or at a factorisation: kept, so that an
    /// attempt does not divide to get them again. Not part of a saved state (reading one
    /// derives them).
    derived: NewtonScalars,
    rate: f64,
    steps_at_lu: u64,
    steps_at_jac: u64,
    guard: StabilityGuard,
    /// Whether the first step has been taken since the last (re)initialisation.
    started: bool,
    /// Set when the attempted step was clipped to end exactly on the stop time.
    landing: Option<f64>,
    stats: Stats,
}

impl<D: Dim> Bdf<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// A solver at `(t0, y0)`. Nothing is evaluated until the first step.
    pub fn new(cfg: BdfConfig, t0: f64, y0: OVector<f64, D>) -> Result<Self, SolverError> {
        cfg.validate()?;
        if !t0.is_finite() || !y0.iter().all(|v| v.is_finite()) {
            return Err(SolverError::NonFiniteState { t: t0 });
        }
        let d = y0.shape_generic().0;
        let mut zn = std::array::from_fn(|_| OVector::zeros_generic(d, U1));
        zn[0] = y0;
        let mut bdf = Self {
            atol: OVector::from_element_generic(d, U1, cfg.atol()),
            cfg,
            t: t0,
            zn,
            hscale: 0.0,
            h: 0.0,
            q: 1,
            q_next: 1,
            h_next: 0.0,
            qwait: 2,
            tau: [0.0; NCOL + 1],
            coeffs: StepCoeffs::default(),
            saved_tq5: 0.0,
            hu: 0.0,
            qu: 0,
            acor: OVector::zeros_generic(d, U1),
            ewt: OVector::zeros_generic(d, U1),
            eta_max: ETA_MAX_FIRST,
            jac: OMatrix::zeros_generic(d, d),
            jac_valid: false,
            lu: None,
            second_order: None,
            structure: None,
            structured: None,
            lu_unrestorable: false,
            gamma: 0.0,
            gamma_lu: 0.0,
            derived: NewtonScalars::default(),
            rate: 1.0,
            steps_at_lu: 0,
            steps_at_jac: 0,
            guard: StabilityGuard::for_dimension(d.value()),
            started: false,
            landing: None,
            stats: Stats::default(),
        };
        // What the (empty) coefficients and γ give, as a state read back would have.
        bdf.derive_from_coeffs();
        Ok(bdf)
    }

    /// Newton by the system's structured Jacobian ([`OdeSystem::second_order`]) where it gives
    /// one, before the first step: O(n) a step for a mechanical system of banded coordinates.
    /// `layout` is the one the system's parts come in. It changes the saved state's layout
    /// ([`visit_state`](Self::visit_state)), so a reader sets it as the writer did.
    pub fn set_second_order(&mut self, layout: Option<Layout>) {
        self.second_order = layout;
    }

    /// Whether the Newton matrix is factored (densely or structured).
    fn has_factor(&self) -> bool {
        self.lu.is_some() || self.structured.is_some()
    }

    /// A different absolute tolerance for each state, each positive and finite (the uniform
    /// `cfg.atol()` otherwise), before the first step.
    pub fn set_atol(&mut self, atol: OVector<f64, D>) -> Result<(), SolverError> {
        self.check_dimension("atol", atol.len())?;
        if let Some(a) = atol.iter().find(|a| !(a.is_finite() && **a > 0.0)) {
            let allowed = Allowed::Words("positive and finite");
            return Err(SolverError::InvalidConfig { field: "atol", value: *a, allowed });
        }
        self.atol = atol;
        Ok(())
    }

    /// Restarts at `(t, y)` with order 1, for a discontinuity of f or of the state. Settings,
    /// counters and the Jacobian are kept; the step history is dropped.
    pub fn reinit(&mut self, t: f64, y: OVector<f64, D>) -> Result<(), SolverError> {
        self.check_dimension("y", y.len())?;
        if !t.is_finite() || !y.iter().all(|v| v.is_finite()) {
            return Err(SolverError::NonFiniteState { t });
        }
        self.t = t;
        for z in self.zn.iter_mut().skip(1) {
            z.fill(0.0);
        }
        self.zn[0] = y;
        self.q = 1;
        self.q_next = 1;
        self.qwait = 2;
        self.tau = [0.0; NCOL + 1];
        self.saved_tq5 = 0.0;
        self.hu = 0.0;
        self.qu = 0;
        self.eta_max = ETA_MAX_FIRST;
        self.lu = None;
        self.structured = None;
        self.derive_gamma_ratio();
        self.started = false;
        self.landing = None;
        Ok(())
    }

    /// Starts from known derivatives `derivatives[j] = y^(j)(t)`, j = 0..=q, at order
    /// q = `derivatives.len() − 1` and step `h`, as if constant steps `h` had been taken.
    /// Without it a run starts at order 1, whose first steps limit a fixed-step run of order
    /// q ≥ 3 to second-order accuracy; the convergence-order tests need it.
    pub fn set_history(
        &mut self,
        h: f64,
        derivatives: &[OVector<f64, D>],
    ) -> Result<(), SolverError> {
        let q = derivatives.len().saturating_sub(1);
        if !(1..=self.max_order()).contains(&q) {
            let allowed = Allowed::Words("y, y' and up to max_order higher derivatives");
            return Err(SolverError::InvalidConfig { field: "history", value: q as f64, allowed });
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(SolverError::InvalidConfig {
                field: "h",
                value: h,
                allowed: Allowed::Words("positive and finite"),
            });
        }
        for d in derivatives {
            self.check_dimension("history", d.len())?;
        }
        if !derivatives.iter().all(|d| d.iter().all(|v| v.is_finite())) {
            return Err(SolverError::NonFiniteState { t: self.t });
        }
        let mut factor = 1.0;
        for (j, d) in derivatives.iter().enumerate() {
            if j > 0 {
                factor *= h / j as f64;
            }
            self.zn[j] = d * factor;
        }
        self.q = q;
        self.q_next = q;
        self.qwait = q + 1;
        self.tau = [h; NCOL + 1];
        self.h = h;
        self.hscale = h;
        self.h_next = h;
        self.hu = 0.0;
        self.lu = None;
        self.structured = None;
        self.derive_gamma_ratio();
        self.started = true;
        self.update_weights();
        Ok(())
    }

    /// The number of equations.
    pub fn dimension(&self) -> usize {
        self.zn[0].len()
    }

    /// A vector given for `field` must have the solver's dimension (a run-time dimension
    /// may differ; a fixed one cannot).
    fn check_dimension(&self, field: &'static str, len: usize) -> Result<(), SolverError> {
        if len == self.dimension() {
            return Ok(());
        }
        let allowed = Allowed::Words("a vector of the solver's dimension");
        Err(SolverError::InvalidConfig { field, value: len as f64, allowed })
    }

    /// Time of the last accepted step.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// State at [`t`](Self::t).
    pub fn y(&self) -> &OVector<f64, D> {
        &self.zn[0]
    }

    /// Work counters.
    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    /// Settings.
    pub fn config(&self) -> &BdfConfig {
        &self.cfg
    }

    /// The most steps one call of [`advance`](Self::advance) takes (at least 1).
    pub fn set_max_steps(&mut self, max_steps: u64) {
        self.cfg.max_steps = max_steps.max(1);
    }

    /// The solver as a state read from this one's: the stability guard's modes computed if
    /// they are pending.
    #[cfg(test)]
    pub(crate) fn settled(&self) -> Self {
        let mut s = self.clone();
        s.guard = s.guard.resolved(&s.jac);
        s
    }

    /// Order and size of the last accepted step (0 and 0.0 before the first).
    pub fn last_step(&self) -> (usize, f64) {
        (self.qu, self.hu)
    }

    /// Order and size planned for the next step.
    pub fn next_step(&self) -> (usize, f64) {
        (self.q_next, self.h_next)
    }

    /// The state at `t` inside the last step `[t_n − h_u, t_n]`, from the Nordsieck
    /// polynomial (dense output, CVODE's CVodeGetDky with k = 0).
    pub fn interpolate(&self, t: f64) -> Result<OVector<f64, D>, SolverError> {
        let lo = self.t - self.hu;
        let fuzz = 100.0 * f64::EPSILON * (self.t.abs() + self.hu.abs());
        if !(t >= lo - fuzz && t <= self.t + fuzz) {
            return Err(SolverError::OutsideLastStep { t, lo, hi: self.t });
        }
        if !self.started || t == self.t {
            return Ok(self.zn[0].clone());
        }
        let s = (t - self.t) / self.hscale;
        // Estrin's scheme: pairs z_j + s·z_{j+1} combined with powers of s², a chain of
        // ⌈log2(q+1)⌉ levels instead of Horner's q.
        let z = &self.zn;
        let s2 = s * s;
        Ok(match self.q {
            1 => &z[0] + &z[1] * s,
            2 => (&z[0] + &z[1] * s) + &z[2] * s2,
            3 => (&z[0] + &z[1] * s) + (&z[2] + &z[3] * s) * s2,
            4 => (&z[0] + &z[1] * s) + ((&z[2] + &z[3] * s) + &z[4] * s2) * s2,
            _ => (&z[0] + &z[1] * s) + ((&z[2] + &z[3] * s) + (&z[4] + &z[5] * s) * s2) * s2,
        })
    }

    /// The state and its derivative at `t` inside the last step, from the Nordsieck
    /// polynomial, into `y` and `dy` (CVODE's CVodeGetDky with k = 0 and 1: Σ_j z_j s^j and
    /// Σ_j j z_j s^(j−1) / h), component by component with no temporary vector.
    pub fn interpolate_into(
        &self,
        t: f64,
        y: &mut OVector<f64, D>,
        dy: &mut OVector<f64, D>,
    ) -> Result<(), SolverError> {
        let lo = self.t - self.hu;
        let fuzz = 100.0 * f64::EPSILON * (self.t.abs() + self.hu.abs());
        if !(self.started && t >= lo - fuzz && t <= self.t + fuzz) {
            return Err(SolverError::OutsideLastStep { t, lo, hi: self.t });
        }
        let (s, q) = ((t - self.t) / self.hscale, self.q);
        let z: [&[f64]; NCOL] = std::array::from_fn(|j| self.zn[j].as_slice());
        let (y, dy) = (y.as_mut_slice(), dy.as_mut_slice());
        let inv_h = 1.0 / self.hscale;
        for i in 0..y.len() {
            let (mut v, mut d) = (z[q][i], q as f64 * z[q][i]);
            for j in (1..q).rev() {
                v = v * s + z[j][i];
                d = d * s + j as f64 * z[j][i];
            }
            y[i] = v * s + z[0][i];
            dy[i] = d * inv_h;
        }
        Ok(())
    }

    /// Whether `t` is not behind the last step `[t_n − h_u, t_n]` (to within round-off):
    /// what [`advance`](Self::advance) accepts as a target without an error. A `t` in
    /// `[t_n − h_u, t_n]` then needs no step, only [`interpolate`](Self::interpolate).
    pub fn reaches_back_to(&self, t: f64) -> bool {
        let lo = self.t - self.hu;
        t >= lo - 100.0 * f64::EPSILON * (lo.abs() + self.hu)
    }

    /// Steps until `t ≥ tout`, never past `tstop` (use `tstop = tout` to end exactly there;
    /// `f64::INFINITY` for no stop). Then [`interpolate`](Self::interpolate) gives y(tout).
    /// A `tout` already inside the last step takes no step.
    pub fn advance<S: OdeSystem<D>>(
        &mut self,
        sys: &S,
        tout: f64,
        tstop: f64,
    ) -> Result<(), SolverError> {
        self.advance_with(sys, tout, tstop, |_| Ok(()))
    }

    /// [`advance`](Self::advance), calling `after` with the solver after every accepted
    /// step; an error of `after` ends the call, with the solver at that step.
    pub fn advance_with<S: OdeSystem<D>, E: From<SolverError>>(
        &mut self,
        sys: &S,
        tout: f64,
        tstop: f64,
        after: impl FnMut(&Self) -> Result<(), E>,
    ) -> Result<(), E> {
        <Self as super::Integrator<D>>::advance_with(self, sys, tout, tstop, after)
    }

    /// Takes one step, never past `tstop`. A step whose end falls within round-off of `tstop`
    /// ends exactly on it. As CVODE's cvStep: attempts until one converges and passes the
    /// error test, each failure handled by its own function (cvHandleNFlag,
    /// cvHandleErrorTestFailure), then the completion and the choice of the next step.
    pub fn step<S: OdeSystem<D>>(
        &mut self,
        sys: &S,
        tstop: f64,
    ) -> Result<StepOutcome, SolverError> {
        self.attempt_step(sys, tstop, false)
    }

    /// One step after the right-hand side changed at t_n by an amount nobody weighed (a
    /// jump of an input's second derivative, say): the history is kept, and the step's first
    /// attempt tells whether it survived the change. If that attempt fails its error test,
    /// the change did not fit in the history: the solver is left at t_n (y_n unchanged, the
    /// failure counted) and returns [`StepOutcome::Rejected`], for the caller to
    /// [`reinit`](Self::reinit) it there. Otherwise as [`step`](Self::step).
    pub fn probe_step<S: OdeSystem<D>>(
        &mut self,
        sys: &S,
        tstop: f64,
    ) -> Result<StepOutcome, SolverError> {
        self.attempt_step(sys, tstop, true)
    }

    fn attempt_step<S: OdeSystem<D>>(
        &mut self,
        sys: &S,
        tstop: f64,
        probe: bool,
    ) -> Result<StepOutcome, SolverError> {
        if tstop <= self.t {
            return Err(SolverError::TimeBehind { t: self.t, target: tstop });
        }
        if !self.started {
            self.start(sys, tstop)?;
        } else {
            self.apply_pending(tstop);
        }
        let mut failures = Failures::default();
        let mut conv_fail = ConvFail::None;
        let dsm_sq = loop {
            self.check_step_size()?;
            let t_prior = self.t;
            self.predict();
            self.set_coeffs();
            if let Err(why) = self.newton(sys, conv_fail) {
                self.restore(t_prior);
                self.handle_newton_failure(why, &mut failures)?;
                conv_fail = ConvFail::Other;
                continue;
            }
            let dsm_sq = self.local_error(sys);
            if dsm_sq <= 1.0 || self.cfg.fixed_step.is_some() {
                break dsm_sq;
            }
            self.restore(t_prior);
            if probe && failures.error_test == 0 {
                self.stats.error_test_failures += 1;
                self.landing = None;
                return Ok(StepOutcome::Rejected);
            }
            self.handle_error_test_failure(sys, dsm_sq.sqrt(), &mut failures)?;
            conv_fail = ConvFail::ErrorTest;
        };
        self.complete_step();
        self.choose_next(dsm_sq);
        self.eta_max = ETA_MAX;
        let outcome = if self.landing.take().is_some() {
            StepOutcome::ReachedStop
        } else {
            StepOutcome::Stepped
        };
        // The step stands (t and y are its end); the caller learns that the state has left
        // the system's range and stops.
        if let Err(RangeViolation { name, value, allowed }) = sys.check_range(self.t, &self.zn[0]) {
            return Err(SolverError::OutOfRange { t: self.t, name, value, allowed });
        }
        Ok(outcome)
    }

    /// The square of the weighted norm of the step's local error estimate, in units of the
    /// tolerance (squared: the error test and the common case of the step choice need no
    /// square root).
    ///
    /// Projection (CVODE's cvDoProjection): the Nordsieck array takes the projected solution,
    /// and the error test measures the local error estimate projected onto the manifold
    /// (CVODE's default, CVodeSetProjErrEst), here as P(y + e) − P(y): the normal part of the
    /// correction is not an error of the step.
    fn local_error<S: OdeSystem<D>>(&mut self, sys: &S) -> f64 {
        let mut projected_error = None;
        if let Some(yp) = sys.project(self.t, &(&self.zn[0] + &self.acor)) {
            projected_error = sys.project(self.t, &(&yp + &self.acor)).map(|y| y - &yp);
            self.acor = yp - &self.zn[0];
        }
        let tq2 = self.coeffs.tq[2];
        self.wrms_squared(projected_error.as_ref().unwrap_or(&self.acor)) * (tq2 * tq2)
    }

    // ----- state save and restore (FMI) --------------------------------------------------

    /// First step after `new` or `reinit`: f(t0, y0), the initial step size, order 1.
    fn start<S: OdeSystem<D>>(&mut self, sys: &S, tstop: f64) -> Result<(), SolverError> {
        self.stats.restarts += 1;
        self.update_weights();
        let (t0, y0) = (self.t, self.zn[0].clone());
        let f0 = self.eval_rhs(sys, t0, &y0);
        if !f0.iter().all(|v| v.is_finite()) {
            return Err(SolverError::NonFiniteRhs { t: self.t });
        }
        let span = tstop - self.t;
        let mut h = match (self.cfg.fixed_step, self.cfg.h_init) {
            (Some(fixed), _) => fixed.h,
            (None, Some(h)) => h,
            (None, None) => self.initial_step(sys, &f0, span),
        };
        h = h.min(self.cfg.h_max).max(self.cfg.h_min);
        self.landing = None;
        if span <= h * (1.0 + LANDING_STRETCH) {
            h = span;
            self.landing = Some(tstop);
        }
        self.h = h;
        self.hscale = h;
        self.h_next = h;
        self.zn[1] = f0 * h;
        self.q = 1;
        self.q_next = 1;
        self.qwait = 2;
        self.started = true;
        Ok(())
    }

    /// Initial step: the BDF1 local error h²/2·‖y''‖ set to half the tolerance, with y''
    /// estimated by a difference of f along an explicit Euler probe (in the spirit of Hairer,
    /// Nørsett & Wanner I, §II.4, and CVODE's cvHin).
    fn initial_step<S: OdeSystem<D>>(&mut self, sys: &S, f0: &OVector<f64, D>, span: f64) -> f64 {
        let span = if span.is_finite() { span } else { 1.0e3 };
        let d1 = self.wrms(f0);
        let mut probe = if d1 > 1e-5 { 0.01 / d1 } else { 1e-6 };
        probe = probe.min(0.01 * span).max(1e-12 * (1.0 + self.t.abs()));
        let y1 = &self.zn[0] + f0 * probe;
        let f1 = self.eval_rhs(sys, self.t + probe, &y1);
        let d2 = if f1.iter().all(|v| v.is_finite()) { self.wrms(&(f1 - f0)) / probe } else { 0.0 };
        let h = if d2 > 1e-300 { (0.5 / d2).sqrt() } else { 100.0 * probe };
        h.min(100.0 * probe.max(1e-6)).min(0.1 * span)
    }

    /// Applies the order and step chosen after the last step, clipped to `tstop`.
    fn apply_pending(&mut self, tstop: f64) {
        if self.q_next > self.q {
            let delta = self.zn[self.max_order()].clone();
            raise_order(&mut self.zn, self.q, self.hscale, &self.tau, &delta);
            self.q += 1;
            self.qwait = self.q + 1;
        }
        while self.q_next < self.q {
            lower_order(&mut self.zn, self.q, self.hscale, &self.tau);
            self.q -= 1;
            self.qwait = self.q + 1;
        }
        let mut h = self.h_next;
        self.landing = None;
        let remaining = tstop - self.t;
        if remaining <= h * (1.0 + LANDING_STRETCH) {
            // A landing step within round-off of the last one keeps its size, so that a run
            // of equal communication steps keeps equal steps: the coefficients, the
            // Nordsieck scaling and the Jacobian's γ stay as they are (tc + h computed by a
            // host differs from step to step in its last bits).
            let resolution = 4.0 * f64::EPSILON * self.t.abs().max(tstop.abs());
            h = if (remaining - self.hscale).abs() <= resolution { self.hscale } else { remaining };
            self.landing = Some(tstop);
        }
        if h != self.hscale {
            self.rescale(h / self.hscale);
        } else {
            self.h = h;
        }
    }

    fn max_order(&self) -> usize {
        match self.cfg.fixed_step {
            Some(f) => f.order,
            None => self.cfg.max_order,
        }
    }

    fn check_step_size(&self) -> Result<(), SolverError> {
        let resolution = 4.0 * f64::EPSILON * self.t.abs().max(self.h.abs());
        if self.h.abs() <= resolution || self.h.abs() < self.cfg.h_min * (1.0 - 1e-12) {
            return Err(SolverError::StepSizeTooSmall { t: self.t, h: self.h });
        }
        Ok(())
    }

    fn eval_rhs<S: OdeSystem<D>>(
        &mut self,
        sys: &S,
        t: f64,
        y: &OVector<f64, D>,
    ) -> OVector<f64, D> {
        self.stats.rhs_evals += 1;
        sys.rhs(t, y)
    }

    fn update_weights(&mut self) {
        let rtol = self.cfg.rtol;
        self.ewt = self.zn[0].zip_map(&self.atol, |y, a| 1.0 / (rtol * y.abs() + a));
    }

    /// Weighted root-mean-square norm with the current error weights.
    fn wrms(&self, v: &OVector<f64, D>) -> f64 {
        self.wrms_squared(v).sqrt()
    }

    /// The square of [`wrms`](Self::wrms).
    fn wrms_squared(&self, v: &OVector<f64, D>) -> f64 {
        let s: f64 = v.iter().zip(self.ewt.iter()).map(|(a, w)| (a * w) * (a * w)).sum();
        s / v.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::control::{grows_sq, ratio_at_least, root, GROWTH_BOUNDS};
    use super::nordsieck::pascal;
    use super::*;
    use crate::solver::FixedStep;
    use nalgebra::{Matrix2, Vector1, Vector2, U1, U2};

    /// y' = −y, y(0) = 1.
    struct Decay;
    impl OdeSystem<U1> for Decay {
        fn rhs(&self, _t: f64, y: &Vector1<f64>) -> Vector1<f64> {
            -y
        }
    }

    /// Harmonic oscillator x'' = −ω²x as a first-order system, with its analytic Jacobian.
    struct Oscillator(f64);
    impl OdeSystem<U2> for Oscillator {
        fn rhs(&self, _t: f64, y: &Vector2<f64>) -> Vector2<f64> {
            Vector2::new(y[1], -self.0 * self.0 * y[0])
        }
        fn jacobian(&self, _t: f64, _y: &Vector2<f64>) -> Option<Matrix2<f64>> {
            Some(Matrix2::new(0.0, 1.0, -self.0 * self.0, 0.0))
        }
    }

    #[test]
    fn root_agrees_with_powf() {
        for k in 1..=7 {
            for x in [1e-300, 1e-12, 0.3, 1.0, 2.5, 7e5, 1e300] {
                let (a, b) = (root(x, k), math::pow(x, 1.0 / k as f64));
                assert!((a - b).abs() <= 4.0 * f64::EPSILON * b, "k={k} x={x}: {a} vs {b}");
            }
        }
        assert_eq!(root(0.0, 3), 0.0);
    }

    #[test]
    fn pascal_written_out_is_the_triangle_and_undoes_itself() {
        for q in 1..=QMAX {
            let mut zn = [Vector2::zeros(); NCOL];
            for (j, z) in zn.iter_mut().enumerate() {
                *z = Vector2::new(1.0 / (j as f64 + 1.7), -0.3 * j as f64 + 0.1);
            }
            let mut naive = zn;
            for k in 1..=q {
                for j in (k..=q).rev() {
                    let z = naive[j];
                    naive[j - 1] += z;
                }
            }
            let mut fast = zn;
            pascal::<U2, false>(&mut fast, q);
            assert_eq!(fast, naive, "q = {q}");
            pascal::<U2, true>(&mut fast, q);
            for (a, b) in fast.iter().zip(&zn) {
                assert!((a - b).norm() <= 1e-14, "q = {q}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn all_finite_is_every_element_finite() {
        let cases: [&[f64]; 7] = [
            &[],
            &[1.0, -2.0, 0.0, -0.0],
            &[f64::MAX, -f64::MAX, f64::MIN_POSITIVE, 5e-324],
            &[1.0, f64::INFINITY],
            &[f64::NEG_INFINITY, 1.0],
            &[0.0, f64::NAN, 3.0],
            &[f64::INFINITY, f64::NEG_INFINITY],
        ];
        for xs in cases {
            assert_eq!(all_finite(xs), xs.iter().all(|x| x.is_finite()), "{xs:?}");
        }
    }

    #[test]
    fn growth_table_decides_as_the_power() {
        for (k, bound) in GROWTH_BOUNDS.iter().enumerate().skip(1) {
            assert_eq!(*bound, math::powi(1.0 / ETA_THRESHOLD - ADDON, k as i32));
            for x in [0.0, 1e-9, 0.01, 0.1, 0.2, 0.3, 0.5, 0.6666, 0.7, 1.0, 10.0, f64::INFINITY] {
                let want = ratio_at_least(x, k, ETA_THRESHOLD);
                assert_eq!(grows_sq((x * x, k)), want, "x={x} k={k}");
            }
            // Just either side of the bound, beyond round-off: the squares decide alike.
            for (x, want) in [(bound * (1.0 - 1e-12), true), (bound * (1.0 + 1e-12), false)] {
                assert_eq!(grows_sq((x * x, k)), want, "k={k}");
                assert_eq!(ratio_at_least(x, k, ETA_THRESHOLD), want, "k={k}");
            }
        }
    }

    #[test]
    fn decay_to_tolerance_and_lands_on_stop() {
        let mut s = Bdf::new(BdfConfig::new(1e-8), 0.0, Vector1::new(1.0)).unwrap();
        s.advance(&Decay, 5.0, 5.0).unwrap();
        assert_eq!(s.t(), 5.0);
        let err = (s.y()[0] - math::exp(-5.0)).abs();
        assert!(err < 1e-8, "error {err}");
        assert!(s.last_step().0 >= 3, "order rose to {}", s.last_step().0);
    }

    #[test]
    fn dense_output_between_steps() {
        let mut s = Bdf::new(BdfConfig::new(1e-9), 0.0, Vector1::new(1.0)).unwrap();
        let mut worst: f64 = 0.0;
        let mut k = 1;
        while k <= 100 {
            let tk = k as f64 * 0.05;
            s.advance(&Decay, tk, f64::INFINITY).unwrap();
            worst = worst.max((s.interpolate(tk).unwrap()[0] - math::exp(-tk)).abs());
            k += 1;
        }
        assert!(worst < 1e-8, "dense output error {worst}");
        assert!(s.stats().steps < 200, "steps {}", s.stats().steps);
        assert!(s.interpolate(s.t() + 1.0).is_err());
    }

    /// y' = −y + c: a forcing that the caller changes between steps.
    struct Forced(f64);
    impl OdeSystem<U1> for Forced {
        fn rhs(&self, _t: f64, y: &Vector1<f64>) -> Vector1<f64> {
            Vector1::new(self.0 - y[0])
        }
    }

    #[test]
    fn probe_step_keeps_a_history_that_survives_a_change_and_rejects_one_that_does_not() {
        let mut s = Bdf::new(BdfConfig::new(1e-8), 0.0, Vector1::new(1.0)).unwrap();
        s.advance(&Forced(0.0), 1.0, 1.0).unwrap();
        assert!(s.last_step().0 >= 2, "order {}", s.last_step().0);
        // A change of f far below the tolerance: the history survives it.
        let mut small = s.clone();
        let outcome = small.probe_step(&Forced(1e-12), 2.0).unwrap();
        assert!(matches!(outcome, StepOutcome::Stepped | StepOutcome::ReachedStop));
        assert!(small.t() > 1.0);
        // A jump of f of the size of the solution: the first attempt fails its error test and
        // the solver is left where it was, for the caller to restart.
        let (y, failures) = (*s.y(), s.stats().error_test_failures);
        assert_eq!(s.probe_step(&Forced(1.0), 2.0).unwrap(), StepOutcome::Rejected);
        assert_eq!((s.t(), *s.y()), (1.0, y));
        assert_eq!(s.stats().error_test_failures, failures + 1);
        s.reinit(s.t(), y).unwrap();
        s.advance(&Forced(1.0), 2.0, 2.0).unwrap();
        // y(t) = 1 − (1 − y(1))·e^{−(t−1)} after the jump
        let exact = 1.0 - (1.0 - y[0]) * math::exp(-1.0);
        assert!((s.y()[0] - exact).abs() < 1e-7, "{} vs {exact}", s.y()[0]);
    }

    #[test]
    fn clone_continues_identically() {
        let mut a = Bdf::new(BdfConfig::new(1e-7), 0.0, Vector2::new(1.0, 0.0)).unwrap();
        let osc = Oscillator(3.0);
        a.advance(&osc, 1.0, f64::INFINITY).unwrap();
        let mut b = a.clone();
        a.advance(&osc, 4.0, 4.0).unwrap();
        b.advance(&osc, 4.0, 4.0).unwrap();
        assert_eq!(a.y(), b.y());
        assert_eq!(a.stats(), b.stats());
    }

    #[test]
    fn fixed_step_mode_keeps_the_step() {
        let cfg =
            BdfConfig { fixed_step: Some(FixedStep { h: 0.01, order: 3 }), ..BdfConfig::new(1e-6) };
        let mut s = Bdf::new(cfg, 0.0, Vector1::new(1.0)).unwrap();
        s.advance(&Decay, 1.0, 1.0).unwrap();
        assert_eq!(s.stats().steps, 100);
        assert_eq!(s.last_step().0, 3);
        assert!((s.last_step().1 - 0.01).abs() < 1e-12);
        assert_eq!(s.stats().rejected(), 0);
    }

    #[test]
    fn bad_settings_name_the_field() {
        let cfg = BdfConfig { rtol: 0.0, ..BdfConfig::new(1e-6) };
        let e = Bdf::new(cfg, 0.0, Vector1::new(1.0)).unwrap_err();
        assert!(e.to_string().contains("rtol"), "{e}");
        let e = Bdf::new(BdfConfig::new(1e-6), 0.0, Vector1::new(f64::NAN)).unwrap_err();
        assert!(matches!(e, SolverError::NonFiniteState { .. }));
    }
}
