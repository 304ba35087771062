use super::error::SolverError;
use nalgebra::SVector;

/// The paper's mode: constant step `h` and a fixed order (reached by raising the order one
/// step at a time from 1, at the same step size).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedStep {
    /// Step size [time unit of the system], > 0.
    pub h: f64,
    /// BDF order, 1..=5.
    pub order: usize,
}

/// Solver settings. Every field has a documented default (see [`BdfConfig::new`]).
#[derive(Clone, Debug, PartialEq)]
pub struct BdfConfig<const N: usize> {
    /// Relative tolerance, in [1e-14, 1]. Default 1e-6.
    pub rtol: f64,
    /// Absolute tolerance per component, each > 0 (a zero would divide by |y| = 0).
    /// Default `1e-3 · rtol` for every component.
    pub atol: SVector<f64, N>,
    /// Highest order used, 1..=5. Default 5.
    pub max_order: usize,
    /// First step size; `None` estimates it from f and an f-difference. Default `None`.
    pub h_init: Option<f64>,
    /// Smallest step size allowed, ≥ 0. Default 0 (only round-off limits the step).
    pub h_min: f64,
    /// Largest step size allowed, > 0. Default +∞.
    pub h_max: f64,
    /// Most internal steps in one call of [`Bdf::advance`](super::Bdf::advance). Default 10⁷.
    pub max_steps: u64,
    /// Cap the order so that no weakly damped mode of the Jacobian sits in the unstable band
    /// of BDF3–5 (see `guard.rs`). Default `true`.
    pub stability_guard: bool,
    /// Constant step and order instead of error control. Default `None`.
    pub fixed_step: Option<FixedStep>,
}

impl<const N: usize> BdfConfig<N> {
    /// Defaults with the given relative tolerance and `atol = 1e-3·rtol`.
    pub fn new(rtol: f64) -> Self {
        Self {
            rtol,
            atol: SVector::from_element(1e-3 * rtol),
            max_order: 5,
            h_init: None,
            h_min: 0.0,
            h_max: f64::INFINITY,
            max_steps: 10_000_000,
            stability_guard: true,
            fixed_step: None,
        }
    }

    /// Checks every field against its allowed range.
    pub fn validate(&self) -> Result<(), SolverError> {
        let bad = |field: &'static str, value: f64, allowed: &'static str| {
            Err(SolverError::InvalidConfig { field, value, allowed })
        };
        if !(self.rtol.is_finite() && (1e-14..=1.0).contains(&self.rtol)) {
            return bad("rtol", self.rtol, "a number in [1e-14, 1]");
        }
        if let Some(a) = self.atol.iter().find(|a| !(a.is_finite() && **a > 0.0)) {
            return bad("atol", *a, "positive and finite");
        }
        if !(1..=5).contains(&self.max_order) {
            return bad("max_order", self.max_order as f64, "an integer in 1..=5");
        }
        if let Some(h) = self.h_init {
            if !(h.is_finite() && h > 0.0) {
                return bad("h_init", h, "positive and finite");
            }
        }
        if !(self.h_min.is_finite() && self.h_min >= 0.0) {
            return bad("h_min", self.h_min, "non-negative and finite");
        }
        if !(self.h_max > 0.0 && self.h_max >= self.h_min) {
            return bad("h_max", self.h_max, "positive and ≥ h_min");
        }
        if self.max_steps == 0 {
            return bad("max_steps", 0.0, "at least 1");
        }
        if let Some(f) = self.fixed_step {
            if !(f.h.is_finite() && f.h > 0.0) {
                return bad("fixed_step.h", f.h, "positive and finite");
            }
            if !(1..=5).contains(&f.order) {
                return bad("fixed_step.order", f.order as f64, "an integer in 1..=5");
            }
        }
        Ok(())
    }
}
