//! Solver `diffsol`: the BDF of the diffsol crate (a variable-order NDF/BDF after SciPy's
//! and ode15s' design), with nalgebra's dense matrices and LU (`NalgebraMat`, `NalgebraLU`),
//! on the same compiled right-hand sides as ours (`TwoDofSystem`, `DaeSystem`), through
//! `OdeBuilder::rhs_implicit` closures.
//!
//! Jacobian: diffsol asks for the action of the Jacobian on a vector, J(x)·v, and builds the
//! dense J column by column from J·e_j. Our systems have no analytic Jacobian and diffsol
//! has no finite differences of its own, so the closure returns the forward difference
//! (f(x + σv) − f(x))/σ of the same right-hand side, with σ = √ε·max(1, max |x_i| over the
//! support of v)/‖v‖∞, and f(x) cached across the N columns of one Jacobian: N + 1
//! f-evaluations per Jacobian, as CVODE's and ours take. (CVODE's increment also has a floor
//! that needs the step size and ‖f‖, which the closure does not see.) All f-evaluations,
//! those of the Jacobians included, are counted in `rhs_evals`.
//!
//! As our driver does (`Run::step_to`), a solve stops on the law's breakpoint t_rot
//! (`set_stop_time`) and restarts there with the next piece of φ: a new problem and solver
//! from the state reached (order 1, diffsol's own initial step). The grid values come from
//! diffsol's interpolation inside the last step (`interpolate_inplace`).
//!
//! dae_stabilized: diffsol has no hook to project after each step (changing its state
//! restarts it at order 1), so it integrates the DAE unprojected and only the grid values are
//! projected (`DaeSystem::project`, as our driver's outputs are). Ours also projects after
//! every step. So diffsol's dae_stabilized is its dae plus projected outputs.
#![cfg(feature = "peers")]

use std::cell::{Cell, RefCell};

use beam_body::model::PhiPiece;
use beam_body::solver::OdeSystem;
use diffsol::{
    NalgebraLU, NalgebraMat, NalgebraVec, OdeBuilder, OdeEquations, OdeSolverMethod,
    OdeSolverStopReason, Op, Vector,
};
use nalgebra::{Const, SVector};

use super::problem::{state_names, with_system, Counters, Outcome, Problem, States, WithSystem};

/// Solves `problem` with diffsol's BDF at `rtol`, atol = 1e-3·rtol for every state.
pub fn run(problem: &Problem, rtol: f64) -> Result<Outcome, String> {
    let model = problem.scene.validate().map_err(|err| err.to_string())?;
    with_system(&problem.scene, &model, Diffsol { problem, rtol })
}

/// [`solve`] with its arguments, for [`with_system`].
struct Diffsol<'a> {
    problem: &'a Problem,
    rtol: f64,
}

impl WithSystem for Diffsol<'_> {
    type Output = Result<Outcome, String>;
    fn apply<const N: usize, S, F>(self, system: F, y0: SVector<f64, N>) -> Self::Output
    where
        S: OdeSystem<Const<N>> + Copy,
        F: Fn(PhiPiece) -> S,
    {
        solve(self.problem, self.rtol, system, y0)
    }
}

/// diffsol's counters, summed over the segments, and our count of f-evaluations.
#[derive(Default)]
struct Work {
    steps: u64,
    rejected: u64,
    rhs_evals: u64,
    jac_evals: u64,
    lu_factorizations: u64,
    newton_iters: u64,
}

impl Work {
    fn counters(&self) -> Counters {
        Counters {
            steps: Some(self.steps),
            rejected: Some(self.rejected),
            rhs_evals: Some(self.rhs_evals),
            jac_evals: Some(self.jac_evals),
            lu_factorizations: Some(self.lu_factorizations),
            newton_iters: Some(self.newton_iters),
        }
    }
}

fn solve<S, const N: usize>(
    problem: &Problem,
    rtol: f64,
    system: impl Fn(PhiPiece) -> S,
    y0: SVector<f64, N>,
) -> Result<Outcome, String>
where
    S: OdeSystem<Const<N>> + Copy,
{
    let law = problem.scene.law;
    let grid = &problem.grid;
    let (t0, t_end) = match (grid.first(), grid.last()) {
        (Some(&a), Some(&b)) if b > a => (a, b),
        _ => return Err("the grid needs two increasing times".into()),
    };
    let bp = law.breakpoint();
    let mut bounds = vec![t0];
    if bp > t0 && bp < t_end {
        bounds.push(bp);
    }
    bounds.push(t_end);

    let mut states =
        States::with_capacity(grid.len()).leading(state_names(problem.scene.formulation).len());
    let first = system(law.piece_from(t0));
    states.push(row(&first, t0, y0).as_slice());
    let mut work = Work::default();
    let mut y = y0;
    for w in bounds.windows(2) {
        let (a, b) = (w[0], w[1]);
        let times: Vec<f64> = grid.iter().copied().filter(|&t| t > a && t <= b).collect();
        y = segment(system(law.piece_from(a)), a, y, b, rtol, &times, &mut states, &mut work)?;
    }
    Ok(Outcome { states, counters: work.counters() })
}

/// A grid row: the state, projected where the system projects (`DaeSystem::outputs`).
fn row<S: OdeSystem<Const<N>>, const N: usize>(
    system: &S,
    t: f64,
    y: SVector<f64, N>,
) -> SVector<f64, N> {
    system.project(t, &y).unwrap_or(y)
}

/// The point of a finite-difference Jacobian and f there: (t, x, f(t, x)).
type Base<const N: usize> = (f64, SVector<f64, N>, SVector<f64, N>);

/// Integrates `system` from (`t0`, `y0`) to exactly `t1`, pushing the rows at `times` (in
/// (t0, t1]) onto `states`; returns the state at `t1`.
#[allow(clippy::too_many_arguments)]
fn segment<S: OdeSystem<Const<N>> + Copy, const N: usize>(
    system: S,
    t0: f64,
    y0: SVector<f64, N>,
    t1: f64,
    rtol: f64,
    times: &[f64],
    states: &mut States,
    work: &mut Work,
) -> Result<SVector<f64, N>, String> {
    let err = |e: diffsol::error::DiffsolError| format!("diffsol: {e}");
    let rhs_evals = Cell::new(0u64);
    // (t, x, f(x)) of the Jacobian being built: its N columns share f(x).
    let base: RefCell<Option<Base<N>>> = RefCell::new(None);
    let f = |x: &SVector<f64, N>, t: f64| {
        rhs_evals.set(rhs_evals.get() + 1);
        system.rhs(t, x)
    };
    let rhs = |x: &[f64], _p: &[f64], t: f64, y: &mut [f64]| {
        y.copy_from_slice(f(&SVector::from_column_slice(x), t).as_slice());
    };
    let jac_mul = |x: &[f64], _p: &[f64], t: f64, v: &[f64], y: &mut [f64]| {
        let x = SVector::<f64, N>::from_column_slice(x);
        let v = SVector::<f64, N>::from_column_slice(v);
        let v_max = v.amax();
        if v_max == 0.0 {
            y.fill(0.0);
            return;
        }
        let mut cache = base.borrow_mut();
        let fx = match *cache {
            Some((tc, xc, fc)) if tc == t && xc == x => fc,
            _ => {
                let fx = f(&x, t);
                *cache = Some((t, x, fx));
                fx
            }
        };
        let scale = x.iter().zip(v.iter()).filter(|(_, vi)| **vi != 0.0).map(|(xi, _)| xi.abs());
        let sigma = f64::EPSILON.sqrt() * scale.fold(1.0, f64::max) / v_max;
        let jv = (f(&(x + v * sigma), t) - fx) / sigma;
        y.copy_from_slice(jv.as_slice());
    };
    let mut problem = OdeBuilder::<NalgebraMat<f64>>::new()
        .t0(t0)
        .rtol(rtol)
        .atol([1e-3 * rtol])
        .rhs_implicit(rhs, jac_mul)
        .init(move |_p, _t, y| y.copy_from_slice(y0.as_slice()), N)
        .build()
        .map_err(err)?;
    // diffsol caps the Newton failures of the whole solve (50 by default), where CVODE and
    // ours cap those of one step (10): lifted, so a long run is not aborted for failures
    // that each step recovered from (the stiff scene exceeds 50 at every rtol tried).
    problem.ode_options.max_nonlinear_solver_failures = usize::MAX;
    let mut solver = problem.bdf::<NalgebraLU<f64>>().map_err(err)?;
    solver.set_stop_time(t1).map_err(err)?;
    let mut reached = false;
    let mut buffer = solver.state().y.clone();
    let read = |v: &NalgebraVec<f64>| SVector::<f64, N>::from_fn(|i, _| v.get_index(i));
    for &t in times {
        while !reached && solver.state().t < t {
            reached = matches!(solver.step().map_err(err)?, OdeSolverStopReason::TstopReached);
        }
        let y = if t >= solver.state().t {
            // On the stop time (diffsol lands within round-off of it).
            read(solver.state().y)
        } else {
            solver.interpolate_inplace(t, &mut buffer).map_err(err)?;
            read(&buffer)
        };
        states.push(row(&system, t, y).as_slice());
    }
    while !reached {
        reached = matches!(solver.step().map_err(err)?, OdeSolverStopReason::TstopReached);
    }
    let y1 = read(solver.state().y);
    let stats = solver.get_statistics();
    work.steps += stats.number_of_steps as u64;
    work.rejected +=
        (stats.number_of_error_test_failures + stats.number_of_nonlinear_solver_fails) as u64;
    work.lu_factorizations += stats.number_of_linear_solver_setups as u64;
    work.newton_iters += stats.number_of_nonlinear_solver_iterations as u64;
    work.jac_evals += problem.eqn.rhs().statistics().number_of_matrix_evals as u64;
    drop(solver);
    work.rhs_evals += rhs_evals.get();
    Ok(y1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::problem::problem;
    use beam_body::sim::simulate;

    #[test]
    fn diffsol_agrees_with_our_driver_on_the_paper_scene() {
        for scene in ["paper", "paper-dae", "paper-dae-stabilized"] {
            let p = problem(scene).unwrap();
            let out = run(&p, 1e-8).unwrap();
            assert_eq!(out.states.len(), p.grid.len());
            let mut ours = p.scene.clone();
            ours.solver.rtol = 1e-8;
            let mut v1 = Vec::new();
            simulate(&ours, |o| v1.push(o.v1)).unwrap();
            assert_eq!(v1.len(), p.grid.len());
            let dv = out.states.rows().zip(&v1).map(|(y, v)| (y[0] - v).abs()).fold(0.0, f64::max);
            eprintln!("{scene}: max |Δv1| = {dv:.3e}, {:?} steps", out.counters.steps);
            assert!(dv < 1e-5, "{scene}: max |Δv1| = {dv:e}");
            let c = out.counters;
            assert!(c.steps.unwrap() > 100 && c.lu_factorizations.unwrap() > 0);
            assert!(c.rhs_evals.unwrap() > c.steps.unwrap() && c.jac_evals.unwrap() > 0);
        }
    }
}
