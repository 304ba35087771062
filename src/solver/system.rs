use nalgebra::{SMatrix, SVector};

/// A state outside the region where a system's equations hold (see
/// [`OdeSystem::check_range`]): the component, its value and the allowed range in words.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RangeViolation {
    pub name: &'static str,
    pub value: f64,
    pub allowed: &'static str,
}

/// A first-order system `y' = f(t, y)` of `N` equations.
pub trait OdeSystem<const N: usize> {
    /// The right-hand side `f(t, y)`.
    fn rhs(&self, t: f64, y: &SVector<f64, N>) -> SVector<f64, N>;

    /// The Jacobian `∂f/∂y`, when the system has an analytic one. `None` (the default) makes
    /// the solver use forward differences.
    fn jacobian(&self, _t: f64, _y: &SVector<f64, N>) -> Option<SMatrix<f64, N, N>> {
        None
    }

    /// Projection onto an invariant manifold (constraint stabilisation after each accepted
    /// step, the pattern of CVODE's `CVodeSetProjFn`). `None` (the default) means no
    /// projection. The projected point must be close to `y`: the difference is added to the
    /// step's correction. The error test uses the error estimate e projected as
    /// P(P(y) + e) − P(y), so it should be smooth near the manifold.
    fn project(&self, _t: f64, _y: &SVector<f64, N>) -> Option<SVector<f64, N>> {
        None
    }

    /// Whether `y` is still inside the region where the equations are valid, checked after
    /// every accepted step: a violation stops the integration with
    /// [`SolverError::OutOfRange`](super::SolverError::OutOfRange) at that step. The
    /// default accepts every state.
    fn check_range(&self, _t: f64, _y: &SVector<f64, N>) -> Result<(), RangeViolation> {
        Ok(())
    }
}
