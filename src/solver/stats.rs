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
}
