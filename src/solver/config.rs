use super::error::{Allowed, SolverError};
use crate::range::Range;

/// The paper's mode: constant step `h` and a fixed order (reached by raising the order one
/// step at a time from 1, at the same step size).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedStep {
    /// Step size [time unit of the system], > 0.
    pub h: f64,
    /// BDF order, 1..=5.
    pub order: usize,
}

/// The integrator: the adaptive (or fixed-step) BDF, or Radau IIA of order 5.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    #[default]
    Bdf,
    Radau,
}

impl Method {
    /// Its name, as the `integrator` setting spells it.
    pub fn name(self) -> &'static str {
        match self {
            Method::Bdf => "bdf",
            Method::Radau => "radau",
        }
    }
}

/// Integrator settings: the one settings type of a run, with every default (the CLI's scene,
/// the FMU's parameters and the benchmark fill it in).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BdfConfig {
    /// The integrator. Default the BDF.
    pub method: Method,
    /// Relative tolerance, in [`RTOL_RANGE`] ([`check_rtol`]). Default 1e-6.
    pub rtol: f64,
    /// Absolute tolerance for every state, > 0 (a zero would divide by |y| = 0). Default
    /// `None`: [`atol`](Self::atol).
    pub atol: Option<f64>,
    /// Highest order used, 1..=5. Default 5.
    pub max_order: usize,
    /// First step size; `None` estimates it from f and an f-difference. Default `None`.
    pub h_init: Option<f64>,
    /// Smallest step size allowed, ≥ 0. Default 0 (only round-off limits the step).
    pub h_min: f64,
    /// Largest step size allowed, > 0. Default +∞.
    pub h_max: f64,
    /// Most internal steps in one call of [`Bdf::advance`](super::Bdf::advance) (one output
    /// interval, one FMI communication step), ≥ 1. Default 10⁷.
    pub max_steps: u64,
    /// Cap the order so that no weakly damped mode of the Jacobian sits in the unstable band
    /// of BDF3–5 (see `guard.rs`). Default `true`.
    pub stability_guard: bool,
    /// Constant step and order instead of error control (the paper's mode). Default `None`.
    pub fixed_step: Option<FixedStep>,
}

impl Default for BdfConfig {
    fn default() -> Self {
        Self {
            method: Method::Bdf,
            rtol: 1e-6,
            atol: None,
            max_order: 5,
            h_init: None,
            h_min: 0.0,
            h_max: f64::INFINITY,
            max_steps: 10_000_000,
            stability_guard: true,
            fixed_step: None,
        }
    }
}

/// The allowed relative tolerances: written once, here; the settings table's `rtol` takes it.
pub const RTOL_RANGE: Range = Range::Closed(1e-14, 1.0);

/// The allowed orders of the BDF, adaptive (`max_order`) or fixed (`fixed_order`).
pub const ORDER_RANGE: Range = Range::Integers(1, 5);

/// The one check of the relative tolerance, for the solver, the CLI and the FMU. The error is
/// the allowed range, for "… must be {error}".
pub fn check_rtol(rtol: f64) -> Result<(), Range> {
    if RTOL_RANGE.contains(rtol) {
        Ok(())
    } else {
        Err(RTOL_RANGE)
    }
}

impl BdfConfig {
    /// The defaults with relative tolerance `rtol`.
    pub fn new(rtol: f64) -> Self {
        Self { rtol, ..Self::default() }
    }

    /// The absolute tolerance in use: `atol`, or by default 1e-3·rtol for the BDF and rtol
    /// for Radau (docs/decisions.md, "Radau IIA"): Radau's error test damps what it does not
    /// resolve, and a floor far below the motion's scale (the states are O(1) in SI units)
    /// would make it resolve every element mode of amplitude above it.
    pub fn atol(&self) -> f64 {
        let factor = match self.method {
            Method::Bdf => 1e-3,
            Method::Radau => 1.0,
        };
        self.atol.unwrap_or(factor * self.rtol)
    }

    /// Checks every field against its allowed range.
    pub fn validate(&self) -> Result<(), SolverError> {
        let bad = |field: &'static str, value: f64, allowed: &'static str| {
            Err(SolverError::InvalidConfig { field, value, allowed: Allowed::Words(allowed) })
        };
        let outside = |field: &'static str, value: f64, range: Range| {
            Err(SolverError::InvalidConfig { field, value, allowed: Allowed::Range(range) })
        };
        if let Err(range) = check_rtol(self.rtol) {
            return outside("rtol", self.rtol, range);
        }
        let atol = self.atol();
        if !(atol.is_finite() && atol > 0.0) {
            return bad("atol", atol, "positive and finite");
        }
        if !ORDER_RANGE.contains(self.max_order as f64) {
            return outside("max_order", self.max_order as f64, ORDER_RANGE);
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
            if !ORDER_RANGE.contains(f.order as f64) {
                return outside("fixed_step.order", f.order as f64, ORDER_RANGE);
            }
        }
        Ok(())
    }
}
