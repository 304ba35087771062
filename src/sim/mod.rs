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

mod balance;
mod equations;
mod run;
mod stepper;
mod systems;
pub mod theory;

pub use balance::{Unstable, MAX_RELATIVE, RTOL_FACTOR};
pub use equations::Equations;
pub use run::{PhiInput, Run};
pub use systems::{dae, dae_start, elements_system, two_dof, two_dof_start};

/// Why a run failed.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    /// The settings do not make a run: the message names the setting.
    Setting(String),
    Solver(SolverError),
    /// The energy balance broke: the integration went numerically unstable.
    Unstable(Unstable),
    /// The consumer of the outputs ended the run ([`simulate_partial`]).
    Stopped,
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::Setting(s) => f.write_str(s),
            SimError::Solver(e @ SolverError::OutOfRange { name: "v1" | "theta1", .. }) => write!(
                f,
                "integration failed: {e}. The quadratic beam holds only there: a turn this fast \
                 or a load this heavy needs beam = exact, valid at any rotation; a run that went \
                 numerically unstable gets there too (energy_check says so first, unless it is \
                 off): then a tighter rtol, max_order = 2 or damping"
            ),
            SimError::Solver(e) => write!(f, "integration failed: {e}"),
            SimError::Unstable(e) => write!(f, "integration failed: {e}"),
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
    /// The largest error of the energy balance relative to the energy the run handled
    /// (`None`: `energy_check = off`).
    pub energy_error: Option<f64>,
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
    with_run(scene, |run, warning| {
        let mut emit = |run: &mut Run, t: f64| {
            note_warning(run, warning);
            match sink(&run.outputs_at(t)?, run) {
                ControlFlow::Continue(()) => Ok(()),
                ControlFlow::Break(()) => Err(SimError::Stopped),
            }
        };
        drive(scene, run, |run, t, times| run.step_to_sampling(t, times, &mut emit))
    })
}

/// Runs the scene, calling `sink` after every integrator step with the run and the time the
/// step started from: the run's dense output covers the step, and the steps tile [0, t_end].
/// For what lies between the points of a grid (a study's peaks, [`crate::study`]); the
/// output grid is not used. Reports as [`simulate_partial`].
pub fn simulate_steps(
    scene: &Scene,
    mut sink: impl FnMut(&Run, f64),
) -> (Report, Result<(), SimError>) {
    with_run(scene, |run, warning| {
        let mut each = |run: &mut Run, from: f64| {
            note_warning(run, warning);
            sink(run, from);
            Ok(())
        };
        drive(scene, run, |run, t, _| run.step_each(t, &mut each))
    })
}

/// Starts the scene's run, lets `body` step it, and reports its counters and the first
/// warning (`body` notes those of the steps it sees, [`note_warning`]).
fn with_run(
    scene: &Scene,
    body: impl FnOnce(&mut Run, &mut Option<String>) -> Result<(), SimError>,
) -> (Report, Result<(), SimError>) {
    let mut run = match start(scene) {
        Ok(run) => run,
        Err(e) => return (Report::default(), Err(e)),
    };
    let mut warning = None;
    let result = body(&mut run, &mut warning);
    let warning = warning.or_else(|| run.take_warning());
    (Report { stats: run.stats(), warning, energy_error: run.energy_worst() }, result)
}

/// Keeps the warning of the step just taken, if any.
fn note_warning(run: &mut Run, warning: &mut Option<String>) {
    if let Some(w) = run.take_warning() {
        *warning = Some(w);
    }
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

/// Checks that the scene makes a run, as [`simulate`] starts it, without stepping it: the
/// settings, the model and the start.
pub fn check(scene: &Scene) -> Result<(), SimError> {
    start(scene).map(drop)
}

/// The run of `simulate` at t = 0, before its first step.
fn start(scene: &Scene) -> Result<Run, SimError> {
    // Run::start checks the model and the settings together; the grid is the driver's.
    scene.check_grid().map_err(SimError::Setting)?;
    Run::start(scene, 0.0, host_sample(scene, 0.0), BdfConfig::default().max_steps)
}

/// Steps `run` to t_end through `segment(run, t, times)`, which steps to t with the output
/// times up to t: once with the law, or once per communication interval with the host's
/// sample at its start.
fn drive(
    scene: &Scene,
    run: &mut Run,
    mut segment: impl FnMut(&mut Run, f64, &mut dyn Iterator<Item = f64>) -> Result<(), SimError>,
) -> Result<(), SimError> {
    let mut outputs = scene.output_times().peekable();
    if scene.phi_source == PhiSource::Law {
        return segment(run, scene.t_end, &mut outputs);
    }
    // As a host does: the law's value (and derivatives) at each communication point.
    let mut comm = grid(scene.dt_comm, scene.t_end).peekable();
    while let (Some(a), Some(&b)) = (comm.next(), comm.peek()) {
        run.set_sample(host_sample(scene, a));
        let mut times = std::iter::from_fn(|| outputs.next_if(|&t| t <= b));
        segment(run, b, &mut times)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Formulation;

    /// The steps `simulate_steps` reports tile [0, t_end], across the law's breakpoint and a
    /// host's samples, and are the steps of the run `simulate` takes; so with
    /// `range_check = warn` past the step that leaves the range (a body 100 times heavier
    /// swings the beam past |ϑ1| = π/2 at 0.87 s), which the warning names.
    #[test]
    fn simulate_steps_sees_every_step_of_the_run() {
        use crate::model::RangeCheck;
        let heavy = |mut s: Scene| {
            s.params.m2 *= 100.0;
            s.range_check = RangeCheck::Warn;
            s
        };
        for (phi_source, warn) in
            [(PhiSource::Law, false), (PhiSource::Input, false), (PhiSource::Law, true)]
        {
            let scene = Scene { t_end: 2.0, phi_source, dt_comm: 0.1, ..Scene::default() };
            let scene = if warn { heavy(scene) } else { scene };
            let mut ends = vec![0.0];
            let (report, result) = simulate_steps(&scene, |run, from| {
                assert_eq!(from, *ends.last().unwrap(), "{phi_source:?}");
                assert!(run.t() > from);
                ends.push(run.t());
            });
            result.unwrap();
            assert_eq!(*ends.last().unwrap(), scene.t_end);
            assert!(ends.contains(&scene.law.t_rot) || phi_source == PhiSource::Input);
            let grid = simulate(&scene, |_| {}).unwrap();
            assert_eq!(report.stats, grid.stats, "{phi_source:?}");
            assert_eq!(ends.len() as u64 - 1, report.stats.steps, "{phi_source:?}");
            assert_eq!(report.warning.is_some(), warn, "{:?}", report.warning);
        }
    }

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

    /// `motion_at` gives q, q̇ and q̈, a third each, for every theory and formulation: the tip's
    /// two coordinates for the paper's model, every node's for n elements, without the DAE's u2
    /// (whose state is (q, u2, q̇, u̇2)); for the quadratic beam q is `coordinates_at`'s and the
    /// tip's rates and accelerations are the outputs'. Before, the DAE in n elements gave
    /// (q, u2, ...) and FMI 3.0's `q`, `dq`, `ddq` refused to be read.
    #[test]
    fn motion_at_is_q_dq_ddq_in_every_formulation() {
        use crate::model::BeamModel;
        for (n, beam) in
            [(1, BeamModel::Quadratic), (2, BeamModel::Quadratic), (2, BeamModel::Exact)]
        {
            for formulation in Formulation::ALL {
                if beam == BeamModel::Exact && formulation != Formulation::Reduced {
                    continue;
                }
                let mut scene = Scene { formulation, ..Scene::default() };
                (scene.params.n_elements, scene.params.beam) = (n, beam);
                let mut run = Run::start(&scene, 0.0, host_sample(&scene, 0.0), 1_000_000).unwrap();
                let (mut motion, mut q) = (Vec::new(), Vec::new());
                run.step_to(0.5).unwrap();
                run.motion_at(0.5, &mut motion).unwrap();
                run.coordinates_at(0.5, &mut q).unwrap();
                let what = format!("{n} {beam:?} {formulation}");
                assert_eq!(motion.len(), 3 * 2 * n, "{what}");
                let k = run.kinematics_at(0.5).unwrap();
                let tip = 2 * n - 2;
                let rates = &motion[2 * n..4 * n];
                // The exact beam's coordinates are (w_k, α_k): its tip's α is ϑ1.
                assert_eq!(rates[tip + 1], k.dtheta1, "{what}");
                if beam == BeamModel::Quadratic {
                    assert_eq!(rates[tip], k.dv1, "{what}");
                    assert_eq!(&motion[..2 * n], &q[..], "{what}");
                    let acc = &motion[4 * n..];
                    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1.0);
                    assert!(close(acc[tip], k.ddv1) && close(acc[tip + 1], k.ddtheta1), "{what}");
                }
            }
        }
    }
}
