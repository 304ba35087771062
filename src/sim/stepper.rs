//! A theory with our integrator ([`Stepper`]), behind the one interface [`Run`](super::Run)
//! steps ([`Integration`]): each operation written once, for every theory.
#![forbid(unsafe_code)]

use super::balance::{self, EnergyMonitor};
use super::theory::{Build, Theory};
use super::SimError;
use crate::model::{Energy, EnergyBalance, Kinematics, PhiPiece, Power};
use crate::scene::InitialState;
use crate::solver::{
    Bdf, BdfConfig, Integrator, Method, OdeSystem, Radau, RangeViolation, SolverError, Stats,
    StepOutcome,
};
use crate::visit::StateVisitor;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OVector};
use std::fmt::Debug;

/// What a run asks of its theory and integrator, whatever the theory. `piece` is the piece of
/// φ in use; times are the integrator's.
pub(super) trait Integration: Debug + Send + Sync {
    fn clone_box(&self) -> Box<dyn Integration>;
    /// The solver's time: that of its last step.
    fn t(&self) -> f64;
    /// The number of states.
    fn dimension(&self) -> usize;
    fn set_max_steps(&mut self, max_steps: u64);
    fn stats(&self) -> Stats;
    /// Drops the step history: the integrator goes on at order 1 from its state.
    fn restart(&mut self) -> Result<(), SolverError>;
    /// Whether `t` is not behind the last step ([`Bdf::reaches_back_to`]).
    fn reaches_back_to(&self, t: f64) -> bool;
    /// Steps on `piece` until t ≥ `times.0`, never past `times.1` ([`advance_probing`]).
    fn advance(
        &mut self,
        piece: PhiPiece,
        range_check: bool,
        times: (f64, f64),
        step: Stepping,
        monitor: &mut Option<EnergyMonitor>,
    ) -> Result<(), SimError>;
    /// The energy check's part of the last step ([`monitor_step`]).
    fn monitor_last_step(
        &self,
        piece: PhiPiece,
        monitor: &mut Option<EnergyMonitor>,
    ) -> Result<(), SimError>;
    /// The Jacobi integral at the last step.
    fn energy(&self, piece: PhiPiece) -> Energy;
    /// Whether the state at the last step is inside the range of validity.
    fn check_range(&self, piece: PhiPiece) -> Result<(), RangeViolation>;
    /// The motion at `t` inside the last step (dense output).
    fn kinematics_at(&self, piece: PhiPiece, t: f64) -> Result<Kinematics, SolverError>;
    /// The states a benchmark records at `t` ([`Theory::record`]).
    fn record_at(&self, piece: PhiPiece, t: f64, out: &mut [f64; 6]) -> Result<usize, SolverError>;
    /// q, q̇, q̈ at `t` ([`Theory::motion`]).
    fn motion_at(&self, piece: PhiPiece, t: f64, out: &mut Vec<f64>) -> Result<(), SolverError>;
    /// Every node's (v_k, ϑ_k) at `t` ([`Theory::nodal_shape`]).
    fn nodal_shape_at(&self, t: f64) -> Result<Vec<f64>, SolverError>;
    fn visit_state(&mut self, v: &mut dyn StateVisitor);
    fn check_state(&self) -> Result<(), SolverError>;
}

impl Clone for Box<dyn Integration> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// How [`Integration::advance`] steps: `probe`, its first step probes whether the history
/// survived a change of f ([`Bdf::probe_step`]); `single`, it takes one step.
#[derive(Clone, Copy, Debug)]
pub(super) struct Stepping {
    pub probe: bool,
    pub single: bool,
}

/// A theory and the integrator of its state.
#[derive(Clone, Debug)]
pub(super) struct Stepper<T: Theory, I>
where
    DefaultAllocator: Allocator<T::D> + Allocator<T::D, T::D>,
{
    theory: T,
    bdf: I,
}

/// Builds a [`Stepper`] from the start of the theory on `piece`.
pub(super) struct Start<'a> {
    pub piece: PhiPiece,
    pub init: InitialState,
    pub config: &'a BdfConfig,
    pub t0: f64,
}

impl Build for Start<'_> {
    type Out = Result<Box<dyn Integration>, SimError>;

    fn build<T: Theory>(self, theory: T) -> Self::Out
    where
        DefaultAllocator: Allocator<T::D> + Allocator<T::D, T::D>,
        Bdf<T::D>: Send + Sync,
        Radau<T::D>: Send + Sync,
    {
        let y0 = theory.start(self.piece, &self.init).map_err(SimError::Setting)?;
        // The layout the saved state has too: a run restored from it sets the same.
        let layout = theory.layout();
        Ok(match self.config.method {
            Method::Bdf => {
                let mut bdf = Bdf::new(*self.config, self.t0, y0)?;
                bdf.set_second_order(layout);
                Box::new(Stepper { theory, bdf })
            }
            Method::Radau => {
                let mut bdf = Radau::new(*self.config, self.t0, y0)?;
                bdf.set_second_order(layout);
                Box::new(Stepper { theory, bdf })
            }
        })
    }
}

impl<T: Theory, I: Integrator<T::D> + Send + Sync + 'static> Integration for Stepper<T, I>
where
    DefaultAllocator: Allocator<T::D> + Allocator<T::D, T::D>,
{
    fn clone_box(&self) -> Box<dyn Integration> {
        Box::new(self.clone())
    }

    fn t(&self) -> f64 {
        self.bdf.t()
    }

    fn dimension(&self) -> usize {
        self.bdf.dimension()
    }

    fn set_max_steps(&mut self, max_steps: u64) {
        self.bdf.set_max_steps(max_steps);
    }

    fn stats(&self) -> Stats {
        *self.bdf.stats()
    }

    fn restart(&mut self) -> Result<(), SolverError> {
        let (t, y) = (self.bdf.t(), self.bdf.y().clone());
        self.bdf.reinit(t, y)
    }

    fn reaches_back_to(&self, t: f64) -> bool {
        self.bdf.reaches_back_to(t)
    }

    fn advance(
        &mut self,
        piece: PhiPiece,
        range_check: bool,
        times: (f64, f64),
        step: Stepping,
        monitor: &mut Option<EnergyMonitor>,
    ) -> Result<(), SimError> {
        let sys = self.theory.system(piece, range_check);
        advance_probing(&mut self.bdf, &sys, times, step, monitor)
    }

    fn monitor_last_step(
        &self,
        piece: PhiPiece,
        monitor: &mut Option<EnergyMonitor>,
    ) -> Result<(), SimError> {
        let sys = self.theory.system(piece, true);
        let y = self.bdf.y();
        monitor_step(monitor, &sys, &self.bdf, &mut (y.clone(), y.clone()))
    }

    fn energy(&self, piece: PhiPiece) -> Energy {
        self.theory.system(piece, true).energy(self.bdf.t(), self.bdf.y())
    }

    fn check_range(&self, piece: PhiPiece) -> Result<(), RangeViolation> {
        self.theory.system(piece, true).check_range(self.bdf.t(), self.bdf.y())
    }

    fn kinematics_at(&self, piece: PhiPiece, t: f64) -> Result<Kinematics, SolverError> {
        Ok(T::kinematics(&self.theory.system(piece, true), t, &self.bdf.interpolate(t)?))
    }

    fn record_at(&self, piece: PhiPiece, t: f64, out: &mut [f64; 6]) -> Result<usize, SolverError> {
        Ok(T::record(&self.theory.system(piece, true), t, &self.bdf.interpolate(t)?, out))
    }

    fn motion_at(&self, piece: PhiPiece, t: f64, out: &mut Vec<f64>) -> Result<(), SolverError> {
        out.clear();
        T::motion(&self.theory.system(piece, true), t, &self.bdf.interpolate(t)?, out);
        Ok(())
    }

    fn nodal_shape_at(&self, t: f64) -> Result<Vec<f64>, SolverError> {
        Ok(self.theory.nodal_shape(self.bdf.interpolate(t)?.as_slice()))
    }

    fn visit_state(&mut self, v: &mut dyn StateVisitor) {
        self.bdf.visit_state(v);
    }

    fn check_state(&self) -> Result<(), SolverError> {
        self.bdf.check_state()
    }
}

/// After an accepted step of `bdf`: the powers at the step's Gauss points, from the dense
/// output and its derivative ([`balance::GAUSS_2`]) in the buffers `buf`, and the energy
/// `monitor`'s check when due.
fn monitor_step<D: Dim, S: OdeSystem<D> + EnergyBalance<D>, I: Integrator<D>>(
    monitor: &mut Option<EnergyMonitor>,
    sys: &S,
    bdf: &I,
    buf: &mut (OVector<f64, D>, OVector<f64, D>),
) -> Result<(), SimError>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    let Some(m) = monitor.as_mut().filter(|m| m.active()) else {
        return Ok(());
    };
    let (t, h) = (bdf.t(), bdf.last_h());
    let mut p = [Power::default(); 2];
    for (p, c) in p.iter_mut().zip(balance::GAUSS_2) {
        let ti = t - h + c * h;
        let phi = sys.phi(ti);
        if !sys.passive(&phi) {
            bdf.interpolate_into(ti, &mut buf.0, &mut buf.1)?;
            *p = sys.power(&phi, &buf.0, &buf.1);
        }
    }
    if m.step(t, h, p) {
        m.check(sys.energy(t, bdf.y())).map_err(SimError::Unstable)?;
    }
    Ok(())
}

/// [`Bdf::advance`], whose first step, with `step.probe`, is a [`Bdf::probe_step`]: the
/// integrator restarts at its time if the history did not survive a change of f there. After
/// every accepted step the energy `monitor` checks the balance.
fn advance_probing<D: Dim, S: OdeSystem<D> + EnergyBalance<D>, I: Integrator<D>>(
    bdf: &mut I,
    sys: &S,
    (tout, tstop): (f64, f64),
    step: Stepping,
    monitor: &mut Option<EnergyMonitor>,
) -> Result<(), SimError>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    let mut buf = (bdf.y().clone(), bdf.y().clone());
    let mut after = |bdf: &I| monitor_step(monitor, sys, bdf, &mut buf);
    if step.probe && bdf.t() < tout {
        if bdf.probe_step(sys, tstop)? == StepOutcome::Rejected {
            let (t, y) = (bdf.t(), bdf.y().clone());
            bdf.reinit(t, y)?;
        } else {
            after(bdf)?;
            if step.single {
                return Ok(());
            }
        }
    }
    if step.single {
        if bdf.t() < tout {
            bdf.step(sys, tstop)?;
            after(bdf)?;
        }
        return Ok(());
    }
    bdf.advance_with(sys, tout, tstop, after)
}
