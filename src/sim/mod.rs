//! Runs a scene: the model, a formulation and the integrator, sampled on an output grid.
//!
//! The integrator takes its own steps and the outputs come from its dense output, so the
//! grid never shortens a step. At the law's breakpoint t_rot, where φ'' jumps, the
//! integrator stops exactly and restarts at order 1 with the next smooth piece of φ.
//! No I/O: rows go to a callback.
#![forbid(unsafe_code)]

use crate::model::{Outputs, Sample};
use crate::scene::grid;
use crate::solver::{BdfConfig, SolverError, Stats};
use std::fmt;
use std::ops::ControlFlow;

pub use crate::scene::{InitialState, PhiSource, Scene};

mod run;

pub use run::{dae, dae_start, two_dof, two_dof_start, PhiInput, Run};

/// Why a run failed.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    /// The settings do not make a run: the message names the setting.
    Setting(String),
    Solver(SolverError),
    /// The consumer of the outputs ended the run ([`simulate_partial`]).
    Stopped,
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::Setting(s) => f.write_str(s),
            SimError::Solver(e) => write!(f, "integration failed: {e}"),
            SimError::Stopped => f.write_str("the run was stopped by the consumer of its outputs"),
        }
    }
}

impl std::error::Error for SimError {}

impl From<SolverError> for SimError {
    fn from(e: SolverError) -> Self {
        SimError::Solver(e)
    }
}

/// What a finished run reports besides its outputs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// The integrator's counters.
    pub stats: Stats,
    /// With `range_check = warn`: where the run left the range of validity.
    pub warning: Option<String>,
}

/// Runs the scene, calling `sink` with the outputs at every output time.
pub fn simulate(scene: &Scene, mut sink: impl FnMut(&Outputs)) -> Result<Report, SimError> {
    let (report, result) = simulate_partial(scene, |o, _| {
        sink(o);
        ControlFlow::Continue(())
    });
    result.map(|()| report)
}

/// [`simulate`], which also reports a failed run: the counters up to the failure, and the
/// warning if one came first. A run that fails before its first step has zero counters.
/// `sink` may end the run at once with [`ControlFlow::Break`] (a closed output), which
/// fails it with [`SimError::Stopped`]; it gets the run too, for what the outputs do not hold
/// (the nodes' coordinates: [`Run::coordinates_at`]).
pub fn simulate_partial(
    scene: &Scene,
    mut sink: impl FnMut(&Outputs, &Run) -> ControlFlow<()>,
) -> (Report, Result<(), SimError>) {
    let mut run = match start(scene) {
        Ok(run) => run,
        Err(e) => return (Report::default(), Err(e)),
    };
    let mut warning = None;
    let mut emit = |run: &mut Run, t: f64| {
        if let Some(w) = run.take_warning() {
            warning = Some(w);
        }
        match sink(&run.outputs_at(t)?, run) {
            ControlFlow::Continue(()) => Ok(()),
            ControlFlow::Break(()) => Err(SimError::Stopped),
        }
    };
    let result = drive(scene, &mut run, &mut emit);
    let warning = warning.or_else(|| run.take_warning());
    (Report { stats: run.stats(), warning }, result)
}

/// The law's φ, φ′, φ″ at t as a host sends them (with `input_derivatives`, the
/// derivatives too).
fn host_sample(scene: &Scene, t: f64) -> Sample {
    if scene.input_derivatives {
        Sample::with_derivatives(t, scene.law.eval(t))
    } else {
        Sample::value(t, scene.law.eval(t).phi)
    }
}

/// The run of `simulate` at t = 0, before its first step.
fn start(scene: &Scene) -> Result<Run, SimError> {
    // Run::start checks the model and the settings together; the grid is the driver's.
    scene.check_grid().map_err(SimError::Setting)?;
    Run::start(scene, 0.0, host_sample(scene, 0.0), BdfConfig::default().max_steps)
}

/// Steps `run` to t_end, calling `emit` at every output time.
fn drive(
    scene: &Scene,
    run: &mut Run,
    emit: &mut impl FnMut(&mut Run, f64) -> Result<(), SimError>,
) -> Result<(), SimError> {
    let outputs = scene.output_times();
    if scene.phi_source == PhiSource::Law {
        return run.step_to_sampling(scene.t_end, outputs, emit);
    }
    // As a host does: the law's value (and derivatives) at each communication point.
    let mut outputs = outputs.peekable();
    let mut comm = grid(scene.dt_comm, scene.t_end).peekable();
    while let (Some(a), Some(&b)) = (comm.next(), comm.peek()) {
        run.set_sample(host_sample(scene, a));
        let mut times = Vec::new();
        while let Some(t) = outputs.next_if(|&t| t <= b) {
            times.push(t);
        }
        run.step_to_sampling(b, times, &mut *emit)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Formulation;

    #[test]
    fn state_at_matches_the_outputs() {
        for formulation in Formulation::ALL {
            let scene = Scene { formulation, ..Scene::default() };
            let mut run = Run::start(&scene, 0.0, host_sample(&scene, 0.0), 1_000_000).unwrap();
            let (mut o, mut y, mut n) = (None, [0.0; 6], 0);
            run.step_to_sampling(1.0, [0.5], |run, t| {
                o = Some(run.outputs_at(t)?);
                n = run.state_at(t, &mut y)?;
                Ok(())
            })
            .unwrap();
            let o = o.unwrap();
            let want: Vec<f64> = if formulation.is_dae() {
                vec![o.v1, o.theta1, o.u2, o.dv1, o.dtheta1, o.du2]
            } else {
                vec![o.v1, o.theta1, o.dv1, o.dtheta1]
            };
            assert_eq!(&y[..n], &want[..], "{formulation}");
        }
    }
}
