//! What a driver asks of an integrator ([`Integrator`]), for the BDF and Radau IIA alike.

use super::{Bdf, OdeSystem, SolverError, Stats, StepOutcome};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OVector};

/// What [`Radau`](super::Radau) and [`Bdf`] give a driver: a step, a stop time it lands on, the
/// dense output of the last step, restarts, counters and the saved state.
pub trait Integrator<D: Dim>: Clone + std::fmt::Debug
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    fn t(&self) -> f64;
    fn y(&self) -> &OVector<f64, D>;
    fn dimension(&self) -> usize;
    fn stats(&self) -> &Stats;
    fn set_max_steps(&mut self, max_steps: u64);
    /// The most steps one call of [`advance_with`](Self::advance_with) takes.
    fn max_steps(&self) -> u64;
    /// The size of the last accepted step (0 before the first).
    fn last_h(&self) -> f64;
    fn reinit(&mut self, t: f64, y: OVector<f64, D>) -> Result<(), SolverError>;
    fn reaches_back_to(&self, t: f64) -> bool;
    fn interpolate(&self, t: f64) -> Result<OVector<f64, D>, SolverError>;
    fn interpolate_into(
        &self,
        t: f64,
        y: &mut OVector<f64, D>,
        dy: &mut OVector<f64, D>,
    ) -> Result<(), SolverError>;
    fn step<S: OdeSystem<D>>(&mut self, sys: &S, tstop: f64) -> Result<StepOutcome, SolverError>;
    fn probe_step<S: OdeSystem<D>>(
        &mut self,
        sys: &S,
        tstop: f64,
    ) -> Result<StepOutcome, SolverError>;
    /// Steps until `t ≥ tout`, never past `tstop` (use `tstop = tout` to end exactly there;
    /// `f64::INFINITY` for no stop), at most [`max_steps`](Self::max_steps) steps, calling
    /// `after` with the solver after every accepted step; an error of `after` ends the call,
    /// with the solver at that step. A `tout` already inside the last step takes no step
    /// (the dense output serves it).
    fn advance_with<S: OdeSystem<D>, E: From<SolverError>>(
        &mut self,
        sys: &S,
        tout: f64,
        tstop: f64,
        mut after: impl FnMut(&Self) -> Result<(), E>,
    ) -> Result<(), E> {
        if !self.reaches_back_to(tout) {
            return Err(SolverError::TimeBehind { t: self.t(), target: tout }.into());
        }
        let mut taken = 0u64;
        while self.t() < tout {
            if taken == self.max_steps() {
                return Err(SolverError::TooManySteps { t: self.t(), max_steps: taken }.into());
            }
            let outcome = self.step(sys, tstop)?;
            after(self)?;
            if outcome == StepOutcome::ReachedStop && self.t() < tout {
                return Err(SolverError::TimeBehind { t: tstop, target: tout }.into());
            }
            taken += 1;
        }
        Ok(())
    }
    fn visit_state(&mut self, v: &mut dyn crate::visit::StateVisitor);
    fn check_state(&self) -> Result<(), SolverError>;
}

impl<D: Dim> Integrator<D> for Bdf<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    fn t(&self) -> f64 {
        Bdf::t(self)
    }
    fn y(&self) -> &OVector<f64, D> {
        Bdf::y(self)
    }
    fn dimension(&self) -> usize {
        Bdf::dimension(self)
    }
    fn stats(&self) -> &Stats {
        Bdf::stats(self)
    }
    fn set_max_steps(&mut self, max_steps: u64) {
        Bdf::set_max_steps(self, max_steps)
    }
    fn max_steps(&self) -> u64 {
        self.config().max_steps
    }
    fn last_h(&self) -> f64 {
        self.last_step().1
    }
    fn reinit(&mut self, t: f64, y: OVector<f64, D>) -> Result<(), SolverError> {
        Bdf::reinit(self, t, y)
    }
    fn reaches_back_to(&self, t: f64) -> bool {
        Bdf::reaches_back_to(self, t)
    }
    fn interpolate(&self, t: f64) -> Result<OVector<f64, D>, SolverError> {
        Bdf::interpolate(self, t)
    }
    fn interpolate_into(
        &self,
        t: f64,
        y: &mut OVector<f64, D>,
        dy: &mut OVector<f64, D>,
    ) -> Result<(), SolverError> {
        Bdf::interpolate_into(self, t, y, dy)
    }
    fn step<S: OdeSystem<D>>(&mut self, sys: &S, tstop: f64) -> Result<StepOutcome, SolverError> {
        Bdf::step(self, sys, tstop)
    }
    fn probe_step<S: OdeSystem<D>>(
        &mut self,
        sys: &S,
        tstop: f64,
    ) -> Result<StepOutcome, SolverError> {
        Bdf::probe_step(self, sys, tstop)
    }
    fn visit_state(&mut self, v: &mut dyn crate::visit::StateVisitor) {
        Bdf::visit_state(self, v)
    }
    fn check_state(&self) -> Result<(), SolverError> {
        Bdf::check_state(self)
    }
}
