//! The integrator: variable-order (1–5), variable-step BDF in Nordsieck form with modified
//! Newton iteration, in the manner of CVODE.
//!
//! Step and order selection, Newton convergence and Jacobian/LU reuse follow the CVODE
//! description (Hindmarsh et al., "SUNDIALS", ACM TOMS 31 (2005), §2.1, and the SUNDIALS
//! CVODE user guide, "Mathematical considerations"); every constant below names its source.
//! All data live on the stack: a step allocates nothing.

use super::coeffs::{lower_order, raise_order, StepCoeffs, NCOL, QMAX};
use super::config::BdfConfig;
use super::error::SolverError;
use super::guard::StabilityGuard;
use super::lu::Lu;
use super::snapshot::{
    require, require_finite, require_non_negative, require_not_below_zero, visit_matrix,
    visit_usize, visit_vector, StateVisitor, MAX_COUNT,
};
use super::stats::Stats;
use super::system::{OdeSystem, RangeViolation};
use crate::math;
use nalgebra::{SMatrix, SVector};

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
const REJAC_GAMMA_RATIO: f64 = 0.2;
/// Floor of the finite-difference increment, in units of h·ε·N·‖f‖ (CVODE's MIN_INC_MULT).
const FD_MIN_INC_MULT: f64 = 1000.0;

/// A step that would end within this relative distance short of the stop time is stretched
/// to land on it, rather than leave a sliver of a step (round-off in a fixed-step run).
const LANDING_STRETCH: f64 = 1e-6;

/// The step-size ratio that brings an error estimate `err` (in units of the tolerance, for
/// a method whose error scales as h^`exponent`) to 1/`bias` of the tolerance:
/// η = 1/((bias·err)^(1/exponent) + ADDON) (CVODE cvChooseEta and cvHandleNFlag).
fn step_ratio(bias: f64, err: f64, exponent: usize) -> f64 {
    1.0 / (root(bias * err, exponent) + ADDON)
}

/// Whether the step ratio of [`step_ratio`] for `bias_err` = bias·err and `exponent` is at
/// least `eta` (> 1), without the root: bias·err ≤ (1/eta − ADDON)^exponent.
fn ratio_at_least(bias_err: f64, exponent: usize, eta: f64) -> bool {
    bias_err <= math::powi(1.0 / eta - ADDON, exponent as i32)
}

/// (1/ETA_THRESHOLD − ADDON)^k for k = 0..=QMAX + 2, by the multiplications of
/// [`math::powi`], so that [`grows_sq`] decides as `ratio_at_least(.., ETA_THRESHOLD)` does.
const GROWTH_BOUNDS: [f64; QMAX + 3] = {
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
fn grows_sq((bias_err_sq, exponent): (f64, usize)) -> bool {
    let bound = GROWTH_BOUNDS[exponent.min(QMAX + 2)];
    bias_err_sq <= bound * bound
}

/// Whether a^(1/k) < b^(1/l) for (a, k) and (b, l), a and b ≥ 0 or infinite: as
/// a^l < b^k, two integer powers, where these cannot overflow or underflow (a and b 0,
/// infinite or within 1e±40, and k, l ≤ 7), else as log(a)/k < log(b)/l. The two agree but
/// at ties within round-off.
fn root_less((a, k): (f64, usize), (b, l): (f64, usize)) -> bool {
    let tame = |x: f64| x == 0.0 || x.is_infinite() || (1e-40..=1e40).contains(&x);
    if tame(a) && tame(b) && k <= 7 && l <= 7 {
        math::powi(a, l as i32) < math::powi(b, k as i32)
    } else {
        math::ln(a) / (k as f64) < math::ln(b) / (l as f64)
    }
}

/// Whether every element is finite, as `iter().all(is_finite)` decides, without its early
/// exit: branch-free, so that it vectorizes.
fn all_finite(xs: &[f64]) -> bool {
    xs.iter().fold(true, |ok, x| ok & x.is_finite())
}

/// x^(1/k), by square roots where they serve (k = 1, 2, 4): a fraction of the cost of
/// `powf`, which the order selection calls two or three times every other step. (Rust's
/// `cbrt` is correctly rounded and no cheaper than `powf`.)
fn root(x: f64, k: usize) -> f64 {
    match k {
        1 => x,
        2 => x.sqrt(),
        4 => x.sqrt().sqrt(),
        _ => math::pow(x, 1.0 / k as f64),
    }
}

/// The prediction z ← P·z by the Pascal triangle (CVODE cvPredict), or with `UNDO` its
/// inverse (cvRestore), for order q. This runs at every step attempt. The additions are
/// written out for each order, on a local copy of the columns, so that the columns stay in
/// registers: a load and a store per element instead of two loads and a store per addition
/// (loops over j kept them in memory: 15 % of the run's instructions on the paper's scene
/// before, issue 16). They are those of the triangle, in its order.
fn pascal<const N: usize, const UNDO: bool>(zn: &mut [SVector<f64, N>; NCOL], q: usize) {
    /// z_{j−1} ± z_j for each j listed, in the order listed, on a local copy of the columns.
    macro_rules! triangle {
        ($q:literal: $($j:literal)*) => {{
            let mut z = *zn;
            $(
                let zj = z[$j];
                if UNDO {
                    z[$j - 1] -= zj;
                } else {
                    z[$j - 1] += zj;
                }
            )*
            zn[..$q].copy_from_slice(&z[..$q]);
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
pub struct Bdf<const N: usize> {
    cfg: BdfConfig,
    /// Absolute tolerance per state: `cfg.atol()` for each, unless [`set_atol`](Self::set_atol).
    atol: SVector<f64, N>,
    /// t_n, the time of the last accepted step.
    t: f64,
    /// Nordsieck array z_j = hscale^j y^(j)(t_n)/j!.
    zn: [SVector<f64, N>; NCOL],
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
    acor: SVector<f64, N>,
    /// Error weights 1/(rtol|y| + atol).
    ewt: SVector<f64, N>,
    /// Cap on the next step-size ratio.
    eta_max: f64,
    /// Newton: Jacobian, LU of I − γ_p·J, γ = h/l_1, the γ_p of the LU, convergence rate.
    jac: SMatrix<f64, N, N>,
    jac_valid: bool,
    lu: Option<Lu<N>>,
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

impl<const N: usize> Bdf<N> {
    /// A solver at `(t0, y0)`. Nothing is evaluated until the first step.
    pub fn new(cfg: BdfConfig, t0: f64, y0: SVector<f64, N>) -> Result<Self, SolverError> {
        cfg.validate()?;
        if !t0.is_finite() || !y0.iter().all(|v| v.is_finite()) {
            return Err(SolverError::NonFiniteState { t: t0 });
        }
        let mut zn = [SVector::zeros(); NCOL];
        zn[0] = y0;
        let mut bdf = Self {
            atol: SVector::from_element(cfg.atol()),
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
            acor: SVector::zeros(),
            ewt: SVector::zeros(),
            eta_max: ETA_MAX_FIRST,
            jac: SMatrix::zeros(),
            jac_valid: false,
            lu: None,
            gamma: 0.0,
            gamma_lu: 0.0,
            derived: NewtonScalars::default(),
            rate: 1.0,
            steps_at_lu: 0,
            steps_at_jac: 0,
            guard: StabilityGuard::default(),
            started: false,
            landing: None,
            stats: Stats::default(),
        };
        // What the (empty) coefficients and γ give, as a state read back would have.
        bdf.derive_from_coeffs();
        Ok(bdf)
    }

    /// A different absolute tolerance for each state, each positive and finite (the uniform
    /// `cfg.atol()` otherwise), before the first step.
    pub fn set_atol(&mut self, atol: SVector<f64, N>) -> Result<(), SolverError> {
        if let Some(a) = atol.iter().find(|a| !(a.is_finite() && **a > 0.0)) {
            let allowed = "positive and finite";
            return Err(SolverError::InvalidConfig { field: "atol", value: *a, allowed });
        }
        self.atol = atol;
        Ok(())
    }

    /// Restarts at `(t, y)` with order 1, for a discontinuity of f or of the state. Settings,
    /// counters and the Jacobian are kept; the step history is dropped.
    pub fn reinit(&mut self, t: f64, y: SVector<f64, N>) -> Result<(), SolverError> {
        if !t.is_finite() || !y.iter().all(|v| v.is_finite()) {
            return Err(SolverError::NonFiniteState { t });
        }
        self.t = t;
        self.zn = [SVector::zeros(); NCOL];
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
        derivatives: &[SVector<f64, N>],
    ) -> Result<(), SolverError> {
        let q = derivatives.len().saturating_sub(1);
        if !(1..=self.max_order()).contains(&q) {
            let allowed = "y, y' and up to max_order higher derivatives";
            return Err(SolverError::InvalidConfig { field: "history", value: q as f64, allowed });
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(SolverError::InvalidConfig {
                field: "h",
                value: h,
                allowed: "positive and finite",
            });
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
        self.derive_gamma_ratio();
        self.started = true;
        self.update_weights();
        Ok(())
    }

    /// Time of the last accepted step.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// State at [`t`](Self::t).
    pub fn y(&self) -> &SVector<f64, N> {
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
    pub fn interpolate(&self, t: f64) -> Result<SVector<f64, N>, SolverError> {
        let lo = self.t - self.hu;
        let fuzz = 100.0 * f64::EPSILON * (self.t.abs() + self.hu.abs());
        if !(t >= lo - fuzz && t <= self.t + fuzz) {
            return Err(SolverError::OutsideLastStep { t, lo, hi: self.t });
        }
        if !self.started || t == self.t {
            return Ok(self.zn[0]);
        }
        let s = (t - self.t) / self.hscale;
        // Estrin's scheme: pairs z_j + s·z_{j+1} combined with powers of s², a chain of
        // ⌈log2(q+1)⌉ levels instead of Horner's q.
        let z = &self.zn;
        let s2 = s * s;
        Ok(match self.q {
            1 => z[0] + z[1] * s,
            2 => (z[0] + z[1] * s) + z[2] * s2,
            3 => (z[0] + z[1] * s) + (z[2] + z[3] * s) * s2,
            4 => (z[0] + z[1] * s) + ((z[2] + z[3] * s) + z[4] * s2) * s2,
            _ => (z[0] + z[1] * s) + ((z[2] + z[3] * s) + (z[4] + z[5] * s) * s2) * s2,
        })
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
    pub fn advance<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        tout: f64,
        tstop: f64,
    ) -> Result<(), SolverError> {
        // A target behind t is fine while it lies in the last step (dense output serves it).
        if !self.reaches_back_to(tout) {
            return Err(SolverError::TimeBehind { t: self.t, target: tout });
        }
        let mut taken = 0u64;
        while self.t < tout {
            if taken == self.cfg.max_steps {
                return Err(SolverError::TooManySteps { t: self.t, max_steps: taken });
            }
            if self.step(sys, tstop)? == StepOutcome::ReachedStop && self.t < tout {
                return Err(SolverError::TimeBehind { t: tstop, target: tout });
            }
            taken += 1;
        }
        Ok(())
    }

    /// Takes one step, never past `tstop`. A step whose end falls within round-off of `tstop`
    /// ends exactly on it. As CVODE's cvStep: attempts until one converges and passes the
    /// error test, each failure handled by its own function (cvHandleNFlag,
    /// cvHandleErrorTestFailure), then the completion and the choice of the next step.
    pub fn step<S: OdeSystem<N>>(
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
    pub fn probe_step<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        tstop: f64,
    ) -> Result<StepOutcome, SolverError> {
        self.attempt_step(sys, tstop, true)
    }

    fn attempt_step<S: OdeSystem<N>>(
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

    /// After a failed Newton iteration (CVODE cvHandleNFlag): gives up after
    /// MAX_NEWTON_FAILURES, at the smallest step or in fixed-step mode; else shrinks the step.
    fn handle_newton_failure(
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

    /// The square of the weighted norm of the step's local error estimate, in units of the
    /// tolerance (squared: the error test and the common case of the step choice need no
    /// square root).
    ///
    /// Projection (CVODE's cvDoProjection): the Nordsieck array takes the projected solution,
    /// and the error test measures the local error estimate projected onto the manifold
    /// (CVODE's default, CVodeSetProjErrEst), here as P(y + e) − P(y): the normal part of the
    /// correction is not an error of the step.
    fn local_error<S: OdeSystem<N>>(&mut self, sys: &S) -> f64 {
        let mut projected_error = None;
        if let Some(yp) = sys.project(self.t, &(self.zn[0] + self.acor)) {
            projected_error = sys.project(self.t, &(yp + self.acor)).map(|y| y - yp);
            self.acor = yp - self.zn[0];
        }
        let tq2 = self.coeffs.tq[2];
        self.wrms_squared(projected_error.as_ref().unwrap_or(&self.acor)) * (tq2 * tq2)
    }

    /// After a failed error test (CVODE cvDoErrorTest's failure branch): gives up after
    /// MAX_ERROR_FAILURES; else shrinks the step by the error's ratio, then, after repeated
    /// failures, drops the order, and at order 1 restarts from a fresh derivative.
    fn handle_error_test_failure<S: OdeSystem<N>>(
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
            let (t, y) = (self.t, self.zn[0]);
            let f = self.eval_rhs(sys, t, &y);
            if !f.iter().all(|v| v.is_finite()) {
                return Err(SolverError::NonFiniteRhs { t: self.t });
            }
            self.zn[1] = f * self.h;
        }
        Ok(())
    }

    // ----- state save and restore (FMI) --------------------------------------------------

    /// Visits every field that changes during integration, in one fixed order: a writer
    /// reads them, a reader overwrites them (FMI's `fmi2SerializeFMUstate` and
    /// `fmi2DeSerializeFMUstate`). Writing a state and reading it into any `Bdf<N>` built
    /// with the same configuration gives a solver that continues bit for bit like this one.
    ///
    /// The configuration is not visited: the caller rebuilds it from its own parameters.
    /// After reading, call [`check_state`](Self::check_state) before anything else; until it
    /// passes, the solver may hold any value the reader stored.
    ///
    /// The order, with the visitor call per item (`×k` for k calls with the same name):
    /// 1. `t`; `zn` ×N for each of the 6 Nordsieck columns z_0..z_5; `hscale`; `h`;
    ///    `q` (count); `q_next` (count); `h_next`; `qwait` (count); `tau` ×7.
    /// 2. `coeffs.l` ×6, `coeffs.tq` ×6, `coeffs.key_q` (count), `coeffs.key_order_change`
    ///    (flag), `coeffs.key_h`, `coeffs.key_tau` ×5; `saved_tq5`; `hu`; `qu` (count);
    ///    `acor` ×N; `ewt` ×N; `eta_max`.
    /// 3. `jac` ×N² (column-major); `jac_valid` (flag); `lu` (flag: an LU is present);
    ///    `lu.factors` ×N² (column-major); `lu.perm` ×N (counts). Without an LU the factors
    ///    and the permutation are still visited: a writer gives zeros and the identity, and
    ///    a reader's values are discarded (reported through [`StateVisitor::discarded`]).
    /// 4. `gamma`; `gamma_lu`; `rate`; `steps_at_lu` (count); `steps_at_jac` (count);
    ///    `guard.modulus`, `guard.angle` for each of 8 slots; `guard.count` (count).
    /// 5. `started` (flag); `landing` (flag), `landing` (real, 0 when the flag is false,
    ///    and then discarded on reading, through [`StateVisitor::discarded`]).
    /// 6. The [`Stats`] counters in declaration order, named `stats.steps` … `stats.restarts`.
    pub fn visit_state<V: StateVisitor + ?Sized>(&mut self, v: &mut V) {
        v.real("t", &mut self.t);
        for z in &mut self.zn {
            visit_vector(v, "zn", z);
        }
        v.real("hscale", &mut self.hscale);
        v.real("h", &mut self.h);
        visit_usize(v, "q", &mut self.q);
        visit_usize(v, "q_next", &mut self.q_next);
        v.real("h_next", &mut self.h_next);
        visit_usize(v, "qwait", &mut self.qwait);
        for x in &mut self.tau {
            v.real("tau", x);
        }
        self.coeffs.visit(v);
        v.real("saved_tq5", &mut self.saved_tq5);
        v.real("hu", &mut self.hu);
        visit_usize(v, "qu", &mut self.qu);
        visit_vector(v, "acor", &mut self.acor);
        visit_vector(v, "ewt", &mut self.ewt);
        v.real("eta_max", &mut self.eta_max);
        visit_matrix(v, "jac", &mut self.jac);
        v.flag("jac_valid", &mut self.jac_valid);
        let mut has_lu = self.lu.is_some();
        v.flag("lu", &mut has_lu);
        let mut lu = self.lu.clone().unwrap_or_else(Lu::placeholder);
        lu.visit(v);
        if !has_lu {
            v.discarded("lu", lu.is_placeholder());
        }
        self.lu = has_lu.then_some(lu);
        v.real("gamma", &mut self.gamma);
        v.real("gamma_lu", &mut self.gamma_lu);
        // Derived, not visited: what a reader stored gives them.
        self.derive_from_coeffs();
        v.real("rate", &mut self.rate);
        v.count("steps_at_lu", &mut self.steps_at_lu);
        v.count("steps_at_jac", &mut self.steps_at_jac);
        // The state holds the guard's modes, computed for it if they are pending (from the
        // Jacobian they would be computed from later, so a restored run continues alike).
        // Writing leaves this solver as it was; reading other modes takes them.
        let resolved = self.guard.resolved(&self.jac);
        let mut visited = resolved.clone();
        visited.visit(v);
        if visited != resolved {
            self.guard = visited;
        }
        v.flag("started", &mut self.started);
        let mut landing = self.landing.is_some();
        let mut tstop = self.landing.unwrap_or(0.0);
        v.flag("landing", &mut landing);
        v.real("landing", &mut tstop);
        if !landing {
            v.discarded("landing", tstop.to_bits() == 0);
        }
        self.landing = landing.then_some(tstop);
        self.stats.visit(v);
    }

    /// Checks a state a reader of [`visit_state`](Self::visit_state) just stored: every field
    /// must hold a value the integrator can produce under this solver's configuration.
    /// Returns [`SolverError::InvalidState`] naming the first bad field in visiting order.
    /// A state that passes can be stepped without panics.
    ///
    /// - Reals are finite, with three exceptions. `coeffs.tq` and `saved_tq5` are ≥ 0, +∞
    ///   or NaN: the coefficient formulas give +∞ and 0/0 at isolated step ratios (see
    ///   `StepCoeffs::check`), and the integrator copes with both. `rate` is ≥ 0 or +∞: it is
    ///   a ratio of two Newton increments that can overflow, and is reset at the next
    ///   factorisation.
    /// - `hscale`, `h`, `h_next`, `tau`, `hu`, `ewt`, `gamma`, `gamma_lu` and `saved_tq5`
    ///   are ≥ 0. The step sizes are 0 after [`new`](Self::new), and also once started when
    ///   the initial step size came out as 0 (the step then failed with
    ///   [`SolverError::StepSizeTooSmall`], as will every later one). `eta_max` lies in
    ///   [1, 10⁴], the caps the code sets.
    /// - `q` and `q_next` lie in 1..=max order and `qu` in 0..=max order. The max order is the
    ///   fixed step's order in fixed-step mode, else `max_order`, of this solver's
    ///   configuration: a state of a higher order is rejected. `qwait` ≤ 10 (LONG_WAIT).
    /// - A present LU has finite factors, non-zero pivots and a permutation of 0..N.
    /// - `steps_at_lu` and `steps_at_jac` are ≤ `stats.steps`. Every counter is ≤ 2⁵³.
    /// - The stability guard holds at most 8 modes, with finite moduli ≥ 0 and angles in
    ///   [0°, 95°].
    ///
    /// Values that could only arise from an overflow beyond 10³⁰⁸, or from a step that
    /// already failed on a non-finite value, are rejected too.
    pub fn check_state(&self) -> Result<(), SolverError> {
        let qmax = self.max_order();
        require_finite(&[self.t], "t")?;
        require_finite(self.zn.iter().flat_map(|z| z.iter()), "zn")?;
        require_non_negative(&[self.hscale], "hscale")?;
        require_non_negative(&[self.h], "h")?;
        require((1..=qmax).contains(&self.q), "q")?;
        require((1..=qmax).contains(&self.q_next), "q_next")?;
        require_non_negative(&[self.h_next], "h_next")?;
        require(self.qwait <= MAX_QWAIT, "qwait")?;
        require_non_negative(&self.tau, "tau")?;
        self.coeffs.check()?;
        require_not_below_zero(&[self.saved_tq5], "saved_tq5")?;
        require_non_negative(&[self.hu], "hu")?;
        require(self.qu <= qmax, "qu")?;
        require_finite(self.acor.iter(), "acor")?;
        require_non_negative(self.ewt.iter(), "ewt")?;
        require((1.0..=ETA_MAX_FIRST).contains(&self.eta_max), "eta_max")?;
        require_finite(self.jac.iter(), "jac")?;
        if let Some(lu) = &self.lu {
            lu.check()?;
        }
        require_non_negative(&[self.gamma], "gamma")?;
        require_non_negative(&[self.gamma_lu], "gamma_lu")?;
        require(self.rate >= 0.0, "rate")?;
        let steps = self.stats.steps.min(MAX_COUNT);
        require(self.steps_at_lu <= steps, "steps_at_lu")?;
        require(self.steps_at_jac <= steps, "steps_at_jac")?;
        self.guard.check()?;
        require_finite(&[self.landing.unwrap_or(0.0)], "landing")?;
        self.stats.check()
    }

    // ----- start, prediction, coefficients ------------------------------------------------

    /// First step after `new` or `reinit`: f(t0, y0), the initial step size, order 1.
    fn start<S: OdeSystem<N>>(&mut self, sys: &S, tstop: f64) -> Result<(), SolverError> {
        self.stats.restarts += 1;
        self.update_weights();
        let (t0, y0) = (self.t, self.zn[0]);
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
    fn initial_step<S: OdeSystem<N>>(&mut self, sys: &S, f0: &SVector<f64, N>, span: f64) -> f64 {
        let span = if span.is_finite() { span } else { 1.0e3 };
        let d1 = self.wrms(f0);
        let mut probe = if d1 > 1e-5 { 0.01 / d1 } else { 1e-6 };
        probe = probe.min(0.01 * span).max(1e-12 * (1.0 + self.t.abs()));
        let y1 = self.zn[0] + f0 * probe;
        let f1 = self.eval_rhs(sys, self.t + probe, &y1);
        let d2 = if f1.iter().all(|v| v.is_finite()) { self.wrms(&(f1 - f0)) / probe } else { 0.0 };
        let h = if d2 > 1e-300 { (0.5 / d2).sqrt() } else { 100.0 * probe };
        h.min(100.0 * probe.max(1e-6)).min(0.1 * span)
    }

    /// Applies the order and step chosen after the last step, clipped to `tstop`.
    fn apply_pending(&mut self, tstop: f64) {
        if self.q_next > self.q {
            let delta = self.zn[self.max_order()];
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

    /// Advances t and predicts the Nordsieck array by the Pascal triangle.
    fn predict(&mut self) {
        self.t = match self.landing {
            Some(tstop) => tstop,
            None => self.t + self.h,
        };
        pascal::<N, false>(&mut self.zn, self.q);
    }

    /// Undoes [`predict`](Self::predict) after a rejected step.
    fn restore(&mut self, t_prior: f64) {
        self.t = t_prior;
        pascal::<N, true>(&mut self.zn, self.q);
    }

    /// Multiplies the step by `eta`: z_j ← η^j z_j.
    fn rescale(&mut self, eta: f64) {
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
    fn set_coeffs(&mut self) {
        if self.coeffs.update(self.q, self.h, &self.tau, self.qwait == 1) {
            self.gamma = self.h / self.coeffs.l[1];
            self.derive_from_coeffs();
        }
    }

    /// [`NewtonScalars`] from γ, γ of the LU and the coefficients.
    fn derive_from_coeffs(&mut self) {
        self.derived.inv_l1 = 1.0 / self.coeffs.l[1];
        self.derived.tol = NEWTON_COEF / self.coeffs.tq[2];
        self.derive_gamma_ratio();
    }

    /// The γ ratio and the update's scale of [`NewtonScalars`].
    fn derive_gamma_ratio(&mut self) {
        let ratio = if self.lu.is_some() { self.gamma / self.gamma_lu } else { 1.0 };
        self.derived.gamma_ratio = ratio;
        self.derived.scale = if ratio != 1.0 { 2.0 / (1.0 + ratio) } else { 1.0 };
    }

    // ----- Newton -------------------------------------------------------------------------

    /// Solves the corrector equation γ·f(t_n, y_n) = z_1/l_1 + Δ for the correction
    /// Δ = y_n − y_n(predicted) by modified Newton on I − γJ, reusing J and the LU.
    fn newton<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        mut conv_fail: ConvFail,
    ) -> Result<(), NewtonFail> {
        loop {
            let gamma_ratio = self.derived.gamma_ratio;
            let needs_setup = self.lu.is_none()
                || conv_fail != ConvFail::None
                || self.stats.steps >= self.steps_at_lu + REFACTOR_STEPS
                || (gamma_ratio - 1.0).abs() > REFACTOR_GAMMA_RATIO;
            let mut fresh_jac = false;
            if needs_setup {
                fresh_jac = !self.jac_valid
                    || self.stats.steps >= self.steps_at_jac + REJAC_STEPS
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

    fn newton_iterate<S: OdeSystem<N>>(&mut self, sys: &S) -> Result<(), NewtonFail> {
        let lu = self.lu.as_ref().ok_or(NewtonFail::Singular)?;
        // A stale γ in the LU is corrected by scaling the update (CVODE cvLsSolve for BDF).
        let NewtonScalars { scale, inv_l1, tol, .. } = self.derived;
        let mut acor = SVector::<f64, N>::zeros();
        let mut y = self.zn[0];
        let mut del2_prev = 0.0;
        for m in 0..NEWTON_MAX_ITERS {
            let f = sys.rhs(self.t, &y);
            self.stats.rhs_evals += 1;
            self.stats.newton_iters += 1;
            // A non-finite f needs no test of its own: ±∞ or NaN in f gives ±∞ or NaN in the
            // residual, the solve carries it into Δ (no product or sum makes it finite again),
            // and the test of ‖Δ‖ below fails in this same iteration.
            let residual = f * self.gamma - (self.zn[1] * inv_l1 + acor);
            let delta = lu.solve(&residual) * scale;
            acor += delta;
            y = self.zn[0] + acor;
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
    fn evaluate_jacobian<S: OdeSystem<N>>(&mut self, sys: &S) -> Result<(), NewtonFail> {
        let y = self.zn[0];
        self.stats.jac_evals += 1;
        self.steps_at_jac = self.stats.steps;
        let jac = match sys.jacobian(self.t, &y) {
            Some(j) => j,
            None => {
                let f0 = sys.rhs(self.t, &y);
                self.stats.rhs_evals_jac += 1;
                if !f0.iter().all(|v| v.is_finite()) {
                    return Err(NewtonFail::NonFinite);
                }
                let fnorm = self.wrms(&f0);
                let min_inc = if fnorm > 0.0 {
                    FD_MIN_INC_MULT * self.h.abs() * f64::EPSILON * N as f64 * fnorm
                } else {
                    1.0
                };
                let sqrt_eps = f64::EPSILON.sqrt();
                let mut jac = SMatrix::<f64, N, N>::zeros();
                for j in 0..N {
                    let inc = (sqrt_eps * y[j].abs()).max(min_inc / self.ewt[j]);
                    let mut yj = y;
                    yj[j] += inc;
                    let fj = sys.rhs(self.t, &yj);
                    self.stats.rhs_evals_jac += 1;
                    jac.set_column(j, &((fj - f0) / inc));
                }
                jac
            }
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

    /// LU of I − γJ with the current γ.
    fn factor(&mut self) -> Result<(), NewtonFail> {
        let m = SMatrix::<f64, N, N>::identity() - self.jac * self.gamma;
        self.lu = Lu::factor(&m);
        self.stats.lu_factorizations += 1;
        self.steps_at_lu = self.stats.steps;
        self.gamma_lu = self.gamma;
        self.derive_gamma_ratio();
        self.rate = 1.0;
        self.lu.as_ref().map(|_| ()).ok_or(NewtonFail::Singular)
    }

    // ----- after an accepted step ---------------------------------------------------------

    fn complete_step(&mut self) {
        self.stats.steps += 1;
        self.hu = self.h;
        self.qu = self.q;
        // Both loops with the order as a constant (`by_order!`), so that they unroll.
        fn shift_history<const Q: usize>(tau: &mut [f64; NCOL + 1]) {
            for i in (2..=Q).rev() {
                tau[i] = tau[i - 1];
            }
        }
        fn correct<const N: usize, const Q: usize>(
            zn: &mut [SVector<f64, N>; NCOL],
            acor: &SVector<f64, N>,
            l: &[f64; NCOL],
        ) {
            for j in 0..=Q {
                zn[j] += acor * l[j];
            }
        }
        by_order!(self.q, Q => shift_history::<Q>(&mut self.tau));
        if self.q == 1 && self.stats.steps > 1 {
            self.tau[2] = self.tau[1];
        }
        self.tau[1] = self.h;
        by_order!(self.q, Q => correct::<N, Q>(&mut self.zn, &self.acor, &self.coeffs.l));
        self.qwait = self.qwait.saturating_sub(1);
        let qmax = self.max_order();
        let fixed_raising = self.cfg.fixed_step.is_some() && self.q < qmax;
        if (self.qwait == 1 || fixed_raising) && self.q != qmax {
            // Keep this correction: the error estimate at order q+1 and the raise need it.
            self.zn[qmax] = self.acor;
            self.saved_tq5 = self.coeffs.tq[5];
        }
        self.update_weights();
    }

    /// Chooses the order and step of the next step from the error estimates at orders q−1,
    /// q and q+1 (CVODE cvPrepareNextStep / cvChooseEta / cvSetEta), then applies the
    /// stability guard.
    fn choose_next(&mut self, dsm_sq: f64) {
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
    fn eta_same_order(&self, dsm_sq: f64) -> f64 {
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
    fn capped(&self, bias_err: f64, k: usize) -> bool {
        self.eta_max >= ETA_THRESHOLD && ratio_at_least(2.0 * bias_err, k, self.eta_max)
    }

    /// The order among q − 1, q, q + 1 that allows the largest step, and that step's ratio
    /// (CVODE cvChooseEta, from the error estimates of cvComputeEtaqm1 and cvComputeEtaqp1).
    /// The candidates (bias·err)^(1/k) are compared by integer powers ([`root_less`]), the
    /// smallest giving the largest η; the chosen one's ratio is exp(log(bias·err)/k), one
    /// logarithm and one exp, unless eta_max caps it anyway.
    fn eta_and_order(&mut self, dsm_sq: f64) -> (usize, f64) {
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
            let diff = self.acor - self.zn[qmax] * ratio;
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
            self.zn[qmax] = self.acor;
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
    fn best_stable_order(&self, limit: usize, dsm: f64) -> Option<(usize, f64)> {
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
    fn limit_growth(&self, eta: f64) -> f64 {
        let eta = eta.min(self.eta_max);
        eta / (self.h.abs() * eta / self.cfg.h_max).max(1.0)
    }

    fn eval_rhs<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t: f64,
        y: &SVector<f64, N>,
    ) -> SVector<f64, N> {
        self.stats.rhs_evals += 1;
        sys.rhs(t, y)
    }

    fn update_weights(&mut self) {
        let rtol = self.cfg.rtol;
        self.ewt = self.zn[0].zip_map(&self.atol, |y, a| 1.0 / (rtol * y.abs() + a));
    }

    /// Weighted root-mean-square norm with the current error weights.
    fn wrms(&self, v: &SVector<f64, N>) -> f64 {
        self.wrms_squared(v).sqrt()
    }

    /// The square of [`wrms`](Self::wrms).
    fn wrms_squared(&self, v: &SVector<f64, N>) -> f64 {
        let s: f64 = v.iter().zip(self.ewt.iter()).map(|(a, w)| (a * w) * (a * w)).sum();
        s / N as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::FixedStep;
    use nalgebra::{Matrix2, Vector1, Vector2};

    /// y' = −y, y(0) = 1.
    struct Decay;
    impl OdeSystem<1> for Decay {
        fn rhs(&self, _t: f64, y: &Vector1<f64>) -> Vector1<f64> {
            -y
        }
    }

    /// Harmonic oscillator x'' = −ω²x as a first-order system, with its analytic Jacobian.
    struct Oscillator(f64);
    impl OdeSystem<2> for Oscillator {
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
            pascal::<2, false>(&mut fast, q);
            assert_eq!(fast, naive, "q = {q}");
            pascal::<2, true>(&mut fast, q);
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
    impl OdeSystem<1> for Forced {
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
