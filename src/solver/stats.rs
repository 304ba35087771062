use super::error::SolverError;
use super::snapshot::{require, StateVisitor, MAX_COUNT};

/// Work counters, cumulative since the solver was created.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted internal steps.
    pub steps: u64,
    /// Steps rejected by the local error test.
    pub error_test_failures: u64,
    /// Steps rejected because Newton's iteration failed to converge.
    pub newton_failures: u64,
    /// Evaluations of f by the integrator, excluding those spent on Jacobians.
    pub rhs_evals: u64,
    /// Evaluations of f spent on finite-difference Jacobians.
    pub rhs_evals_jac: u64,
    /// Jacobian evaluations (analytic or finite-difference).
    pub jac_evals: u64,
    /// LU factorisations of the Newton matrix `I − γJ`.
    pub lu_factorizations: u64,
    /// Newton iterations.
    pub newton_iters: u64,
    /// Steps after which the stability guard lowered the order the controller had chosen.
    pub order_caps: u64,
    /// Restarts at order 1 (initial start and [`Bdf::reinit`](super::Bdf::reinit)).
    pub restarts: u64,
}

impl Stats {
    /// Rejected steps of either kind.
    pub fn rejected(&self) -> u64 {
        self.error_test_failures + self.newton_failures
    }

    /// All evaluations of f, Jacobian ones included.
    pub fn total_rhs_evals(&self) -> u64 {
        self.rhs_evals + self.rhs_evals_jac
    }

    /// The counters as (name, field), in declaration order.
    fn fields(&mut self) -> [(&'static str, &mut u64); 10] {
        [
            ("stats.steps", &mut self.steps),
            ("stats.error_test_failures", &mut self.error_test_failures),
            ("stats.newton_failures", &mut self.newton_failures),
            ("stats.rhs_evals", &mut self.rhs_evals),
            ("stats.rhs_evals_jac", &mut self.rhs_evals_jac),
            ("stats.jac_evals", &mut self.jac_evals),
            ("stats.lu_factorizations", &mut self.lu_factorizations),
            ("stats.newton_iters", &mut self.newton_iters),
            ("stats.order_caps", &mut self.order_caps),
            ("stats.restarts", &mut self.restarts),
        ]
    }

    /// Visits every counter in declaration order.
    pub(crate) fn visit<V: StateVisitor + ?Sized>(&mut self, v: &mut V) {
        for (name, x) in self.fields() {
            v.count(name, x);
        }
    }

    /// Every counter is at most [`MAX_COUNT`].
    pub(crate) fn check(&self) -> Result<(), SolverError> {
        let mut copy = *self;
        for (name, x) in copy.fields() {
            require(*x <= MAX_COUNT, name)?;
        }
        Ok(())
    }
}
