use super::SecondOrder;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector};

/// A state outside the region where a system's equations hold (see
/// [`OdeSystem::check_range`]): the component, its value and the allowed range in words.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RangeViolation {
    pub name: &'static str,
    pub value: f64,
    pub allowed: &'static str,
}

/// A first-order system `y' = f(t, y)` in dimension `D`: a number fixed at compile time
/// (`Const<N>`, the state on the stack) or at run time (`Dyn`, on the heap).
pub trait OdeSystem<D: Dim>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// The right-hand side `f(t, y)`.
    fn rhs(&self, t: f64, y: &OVector<f64, D>) -> OVector<f64, D>;

    /// The Jacobian `∂f/∂y`, when the system has an analytic one. `None` (the default) makes
    /// the solver use forward differences.
    fn jacobian(&self, _t: f64, _y: &OVector<f64, D>) -> Option<OMatrix<f64, D, D>> {
        None
    }

    /// The Jacobian in the structured form of a mechanical system ([`SecondOrder`]: the
    /// states are (x, ẋ) with x′ = ẋ exactly, and M, ∂R/∂ẋ, ∂R/∂x are bands plus rank one),
    /// for a solver set up with [`Bdf::set_second_order`](super::Bdf::set_second_order):
    /// Newton then costs O(n) a step. `None` (the default) falls back to
    /// [`jacobian`](Self::jacobian) and a dense LU.
    fn second_order(&self, _t: f64, _y: &OVector<f64, D>) -> Option<SecondOrder> {
        None
    }

    /// For a mechanical system y = (x, ẋ) of m coordinates (see
    /// [`second_order`](Self::second_order)): the residual R(t, x, ẋ, ẍ) = M(x)ẍ − F(t, x, ẋ)
    /// into `out`, for an integrator that solves its stages for the accelerations instead of
    /// calling [`rhs`](Self::rhs) (Radau IIA): worth it where R costs less than ẍ = M⁻¹F (the
    /// exact beam: O(n), where f needs the dense M and its Cholesky). Returns `false` (the
    /// default) where the system does not give it.
    fn residual(&self, _t: f64, _x: &[f64], _v: &[f64], _a: &[f64], _out: &mut [f64]) -> bool {
        false
    }

    /// Projection onto an invariant manifold (constraint stabilisation after each accepted
    /// step, the pattern of CVODE's `CVodeSetProjFn`). `None` (the default) means no
    /// projection. The projected point must be close to `y`: the difference is added to the
    /// step's correction. The error test uses the error estimate e projected as
    /// P(P(y) + e) − P(y), so it should be smooth near the manifold.
    fn project(&self, _t: f64, _y: &OVector<f64, D>) -> Option<OVector<f64, D>> {
        None
    }

    /// Whether `y` is still inside the region where the equations are valid, checked after
    /// every accepted step: a violation stops the integration with
    /// [`SolverError::OutOfRange`](super::SolverError::OutOfRange) at that step. The
    /// default accepts every state.
    fn check_range(&self, _t: f64, _y: &OVector<f64, D>) -> Result<(), RangeViolation> {
        Ok(())
    }
}
