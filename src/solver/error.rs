use crate::range::Range;
use std::fmt;

/// What a configuration field allows: a range, or words for what a range cannot say.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Allowed {
    Range(Range),
    Words(&'static str),
}

impl fmt::Display for Allowed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Allowed::Range(r) => r.fmt(f),
            Allowed::Words(w) => f.write_str(w),
        }
    }
}

/// Why the integrator stopped or refused its input. Every failure of a step names the time at
/// which it happened.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SolverError {
    /// A configuration field is outside its allowed range.
    InvalidConfig { field: &'static str, value: f64, allowed: Allowed },
    /// The initial state or a reinitialisation state has a NaN or infinite component.
    NonFiniteState { t: f64 },
    /// f returned NaN or ±∞ and no smaller step helped.
    NonFiniteRhs { t: f64 },
    /// The step size fell below `h_min` or below the resolution of t.
    StepSizeTooSmall { t: f64, h: f64 },
    /// The local error test failed too often in one step.
    ErrorTestFailures { t: f64, h: f64, failures: u32 },
    /// Newton's iteration failed too often in one step.
    NewtonFailures { t: f64, h: f64, failures: u32 },
    /// The Newton matrix `I − γJ` is singular.
    SingularMatrix { t: f64, h: f64 },
    /// More than `max_steps` internal steps in one call.
    TooManySteps { t: f64, max_steps: u64 },
    /// Dense output asked outside the last step `[lo, hi]`.
    OutsideLastStep { t: f64, lo: f64, hi: f64 },
    /// The target time lies behind the solver's time.
    TimeBehind { t: f64, target: f64 },
    /// The state left the region where the system's equations hold
    /// ([`OdeSystem::check_range`](super::OdeSystem::check_range)), after the step that
    /// ended at `t`.
    OutOfRange { t: f64, name: &'static str, value: f64, allowed: &'static str },
    /// A restored integrator state (see [`Bdf::visit_state`](super::Bdf::visit_state)) has a
    /// field outside the values the integrator can produce: corrupt or foreign data.
    InvalidState { field: &'static str },
}

impl fmt::Display for SolverError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use SolverError::*;
        match *self {
            InvalidConfig { field, value, allowed } => {
                write!(f, "solver setting `{field}` = {value:?} is out of range: must be {allowed}")
            }
            NonFiniteState { t } => write!(f, "non-finite state (NaN or ±inf) at t = {t}"),
            NonFiniteRhs { t } => write!(
                f,
                "the right-hand side is not finite (NaN or ±inf) near t = {t}, even at the smallest step"
            ),
            StepSizeTooSmall { t, h } => {
                write!(f, "step size underflow at t = {t}: h = {h:e} is below the resolution of t or h_min")
            }
            ErrorTestFailures { t, h, failures } => write!(
                f,
                "the local error test failed {failures} times in one step at t = {t} (h = {h:e})"
            ),
            NewtonFailures { t, h, failures } => write!(
                f,
                "Newton's iteration failed to converge {failures} times in one step at t = {t} (h = {h:e})"
            ),
            SingularMatrix { t, h } => {
                write!(f, "singular Newton matrix I - gamma*J at t = {t} (h = {h:e})")
            }
            TooManySteps { t, max_steps } => {
                write!(f, "more than {max_steps} steps in one call, stopped at t = {t}")
            }
            OutsideLastStep { t, lo, hi } => {
                write!(f, "dense output asked at t = {t}, outside the last step [{lo}, {hi}]")
            }
            TimeBehind { t, target } => {
                write!(f, "target time {target} lies behind the solver time {t}")
            }
            OutOfRange { t, name, value, allowed } => write!(
                f,
                "{name} = {value:.6e} at t = {t} is outside the model's range of validity: \
                 must be {allowed}"
            ),
            InvalidState { field } => {
                write!(f, "invalid integrator state: field `{field}` is out of range")
            }
        }
    }
}

impl std::error::Error for SolverError {}
