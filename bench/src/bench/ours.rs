//! Our integrator: `bdf` (adaptive, the scene's solver options with the case's rtol) and
//! `bdf-fixed` (the paper's constant-step mode), both through [`beam_body::sim::simulate`],
//! the driver of the CLI: it lands on the law's breakpoint t_rot and restarts there.

use beam_body::model::Sample;
use beam_body::scene::IntegratorChoice;
use beam_body::sim::{Run, Scene, SimError};
use beam_body::solver::{BdfConfig, Stats};

use super::problem::{Counters, Outcome, Problem, States};

/// The order of `bdf-fixed`. The paper (Russkikh & Shklyarchuk 2020, §4) says only "BDF in
/// PTC MathCad 15.0 with a constant step Δτ = 1e-5"; it names no order. We use BDF2, the
/// highest A-stable BDF and the default of the scene key `fixed_order`, as the project's
/// fixed-step test does (tests/model.rs).
pub const FIXED_ORDER: usize = 2;

/// The tolerance of the Newton corrector in `bdf-fixed` (the only use of rtol in that
/// mode): tight, so that the error is the method's truncation error, not the corrector's.
/// With steps of 1e-3 s and less the predictor is already close, so it costs few extra
/// iterations.
pub const FIXED_NEWTON_RTOL: f64 = 1e-10;

/// Our adaptive BDF at `rtol`, atol = 1e-3·rtol (the default rule).
pub fn bdf(problem: &Problem, rtol: f64) -> Result<Outcome, String> {
    with_integrator(problem, IntegratorChoice::Bdf, rtol)
}

/// Our adaptive `integrator` at `rtol` with its default atol (`BdfConfig::atol`).
pub fn with_integrator(
    problem: &Problem,
    integrator: IntegratorChoice,
    rtol: f64,
) -> Result<Outcome, String> {
    solve(problem, &adaptive(problem, integrator, rtol))
}

/// The problem's scene for our adaptive `integrator` at `rtol` with its default atol.
pub fn adaptive(problem: &Problem, integrator: IntegratorChoice, rtol: f64) -> Scene {
    let mut scene = problem.scene.clone();
    scene.solver.rtol = rtol;
    scene.solver.atol = 0.0;
    scene.solver.fixed_step = 0.0;
    scene.solver.integrator = integrator;
    scene
}

/// Our BDF of order [`FIXED_ORDER`] with the constant step `h` [s].
pub fn bdf_fixed(problem: &Problem, h: f64) -> Result<Outcome, String> {
    let mut scene = problem.scene.clone();
    scene.solver.rtol = FIXED_NEWTON_RTOL;
    scene.solver.atol = 0.0;
    scene.solver.fixed_step = h;
    scene.solver.fixed_order = FIXED_ORDER;
    solve(problem, &scene)
}

/// The run on the problem's grid: our driver (`Run`, as the CLI and the FMU use it), states
/// from its dense output. Like the other solvers, it records the states only; the CLI's
/// `simulate` would also compute accelerations, reactions and energy at every grid point.
fn solve(problem: &Problem, scene: &Scene) -> Result<Outcome, String> {
    let mut states = States::with_capacity(problem.grid.len());
    let mut y = [0.0; 6];
    let stats = drive(problem, scene, |run, t| {
        let n = run.state_at(t, &mut y)?;
        states.push(&y[..n]);
        Ok(())
    })?;
    Ok(Outcome { states, counters: counters(&stats) })
}

/// The CLI's driver ([`Run`]) through `scene` to its t_end, calling `sink` at each time of the
/// problem's grid; the run's counters.
pub fn drive(
    problem: &Problem,
    scene: &Scene,
    sink: impl FnMut(&mut Run, f64) -> Result<(), SimError>,
) -> Result<Stats, String> {
    scene.validate()?;
    let max_steps = BdfConfig::default().max_steps;
    let mut run = Run::start(scene, 0.0, Sample::value(0.0, 0.0), max_steps)
        .map_err(|err| err.to_string())?;
    run.step_to_sampling(scene.t_end, problem.grid.iter().copied(), sink)
        .map_err(|err| err.to_string())?;
    Ok(run.stats())
}

fn counters(stats: &Stats) -> Counters {
    Counters {
        steps: Some(stats.steps),
        rejected: Some(stats.rejected()),
        rhs_evals: Some(stats.total_rhs_evals()),
        jac_evals: Some(stats.jac_evals),
        lu_factorizations: Some(stats.lu_factorizations),
        newton_iters: Some(stats.newton_iters),
    }
}
