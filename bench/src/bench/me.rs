//! Solver `cvode-me`: the host's CVODE on our FMI 2.0 Model Exchange. The packaged FMU (the
//! `fmu` solver's, extracted) is instantiated as Model Exchange through the native importer
//! ([`crate::import`]), with φ from the built-in law and the case's parameters, and CVODE
//! (the `cvode` solver's, at the same settings: dense, rtol, atol = 1e-3·rtol) integrates
//! x′ = f(t, x) with f = fmi2SetTime, fmi2SetContinuousStates, fmi2GetDerivatives: what a
//! simulation tool such as fmusim does with CVODE. The law's end t_rot is the FMU's time
//! event: CVODE stops there, the host runs the event iteration (fmi2EnterEventMode,
//! fmi2NewDiscreteStates, fmi2EnterContinuousTimeMode) and CVODE restarts.
//!
//! The grid values are CVODE's (its interpolation), the states x = (v1, ϑ1, v̇1, ϑ̇1) that the
//! FMU's first four continuous states are; its last two, the filter of an input φ that the law
//! does not use, stay at rest and the host holds them there. fmi2CompletedIntegratorStep is not
//! called (CVODE's normal
//! mode has no hook after a step); it only checks the range of validity, which the paper's
//! scene never leaves.

use std::cell::RefCell;

use beam_body::fmu::variables::MODEL_IDENTIFIER;
use beam_body::model::PhiPiece;
use beam_body::solver::OdeSystem;
use nalgebra::{Vector4, U4};

use super::problem::{Outcome, Problem};
use crate::import::{Call, Common, EventFlags, Fmu2, InstanceME, ModelExchange};
use crate::Result;

/// The FMU's continuous states: the model's four and the filter's two.
const FMU_STATES: usize = 6;

/// The FMU's equations as CVODE sees them: one instance in continuous-time mode, shared by
/// every copy (CVODE's user data holds one).
#[derive(Clone, Copy)]
struct MeSystem<'a> {
    instance: &'a RefCell<InstanceME>,
}

impl OdeSystem<U4> for MeSystem<'_> {
    /// f(t, x) through the FMU; a call that fails gives NaN, which CVODE takes as a
    /// recoverable failure (a smaller step).
    fn rhs(&self, t: f64, y: &Vector4<f64>) -> Vector4<f64> {
        let mut inst = self.instance.borrow_mut();
        let (mut x, mut dx) = ([0.0; FMU_STATES], [f64::NAN; FMU_STATES]);
        x[..4].copy_from_slice(y.as_slice());
        let ok = inst.set_time(t).is_ok()
            && inst.set_continuous_states(&x).is_ok()
            && inst.get_derivatives(&mut dx).is_ok();
        if !ok {
            dx.fill(f64::NAN);
        }
        Vector4::from_column_slice(&dx[..4])
    }
}

/// The event iteration at the current time, then continuous-time mode.
fn event_iteration(inst: &mut InstanceME) -> Result {
    let mut flags = EventFlags { discrete_states_need_update: true, ..Default::default() };
    let mut passes = 0;
    while flags.discrete_states_need_update {
        passes += 1;
        if passes > 10 {
            return Err("the event iteration does not end".into());
        }
        inst.new_discrete_states(&mut flags).call("fmi2NewDiscreteStates")?;
        if flags.terminate_simulation {
            return Err("the FMU asked to terminate at an event".into());
        }
    }
    inst.enter_continuous_time_mode().call("fmi2EnterContinuousTimeMode")?;
    Ok(())
}

/// One run at `rtol` from instantiation to the last grid time.
pub fn run(fmu: &Fmu2, problem: &Problem, rtol: f64) -> std::result::Result<Outcome, String> {
    solve(fmu, problem, rtol).map_err(|err| err.to_string())
}

fn solve(fmu: &Fmu2, problem: &Problem, rtol: f64) -> Result<Outcome> {
    let scene = &problem.scene;
    let mut inst = fmu.instantiate_me(MODEL_IDENTIFIER, false)?;
    super::fmu::set_scene(&mut inst, scene, "law")?;
    let t0 = problem.grid.first().copied().unwrap_or(0.0);
    inst.setup_experiment(Some(rtol), t0, None).call("fmi2SetupExperiment")?;
    inst.enter_initialization_mode().call("fmi2EnterInitializationMode")?;
    inst.exit_initialization_mode().call("fmi2ExitInitializationMode")?;
    event_iteration(&mut inst)?;
    let mut states = [0.0; FMU_STATES];
    inst.get_continuous_states(&mut states).call("fmi2GetContinuousStates")?;
    let x = Vector4::from_column_slice(&states[..4]);
    let instance = RefCell::new(inst);
    let events = RefCell::new(Vec::new());
    let t_rot = scene.law.breakpoint();
    // Called at the start with the turn and at t_rot with the hold: there, the FMU's event.
    let system = |piece: PhiPiece| {
        if matches!(piece, PhiPiece::Hold(_)) {
            let mut inst = instance.borrow_mut();
            let handled = inst
                .enter_event_mode()
                .call("fmi2EnterEventMode")
                .and_then(|_| inst.set_time(t_rot).call("fmi2SetTime"))
                .and_then(|_| event_iteration(&mut inst));
            events.borrow_mut().push(handled.map_err(|e| e.to_string()));
        }
        MeSystem { instance: &instance }
    };
    let outcome = super::cvode::run_system(problem, rtol, system, x)?;
    for handled in events.into_inner() {
        handled?;
    }
    instance.into_inner().terminate().call("fmi2Terminate")?;
    Ok(outcome)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::problem::problem;

    /// The host's CVODE on the Model Exchange equations against CVODE on the same equations
    /// compiled in (the `cvode` solver) at rtol 1e-8: the same integrator on the same f, so
    /// the same steps to round-off (and the FMI calls change no bit of f).
    /// Needs CVODE and the FMU: ignored by a plain `cargo test`; `cargo xtask test` builds
    /// both and runs it with `BEAM_BODY_CVODE_LIB` set (the FMU extracted here).
    #[test]
    #[ignore = "needs CVODE (BEAM_BODY_CVODE_LIB) and the FMU: cargo xtask test runs this"]
    fn cvode_on_model_exchange_is_cvode_on_the_compiled_equations() {
        super::super::cvode::describe().expect("the CVODE library loads");
        let dir = super::super::fmu::prepare().expect("the FMU builds and extracts");
        let fmu = super::super::fmu::load(&dir).expect("the extracted FMU loads");
        let p = problem("paper").unwrap();
        let me = run(&fmu, &p, 1e-8).unwrap();
        let compiled = super::super::cvode::run(&p, 1e-8).unwrap();
        assert_eq!(me.states.len(), compiled.states.len());
        let worst = me
            .states
            .rows()
            .zip(compiled.states.rows())
            .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
            .fold(0.0, f64::max);
        eprintln!("max |cvode-me - cvode| = {worst:.3e}, steps {:?}", me.counters.steps);
        assert!(worst < 1e-12, "{worst:e}");
        assert_eq!(me.counters.steps, compiled.counters.steps);
    }
}
