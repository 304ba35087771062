//! Solver `fmu`: the packaged FMU (`target/fmu/BeamBody.fmu`, extracted to
//! `target/bench/fmu/BeamBody/`) driven by the native host ([`crate::import`]) with φ from the
//! built-in law (phi_source = law), tolerance = the case's rtol (fmi2SetupExperiment), and
//! fmi2DoStep at a constant communication step H from 0 to t_end.
//!
//! The FMU integrates with the same BDF as `bdf` and, with the law, takes its steps: its
//! integrator runs ahead of the communication points and the outputs come from its dense
//! output. The difference to `bdf` is the cost of the FMI layer and of the outputs asked at
//! every communication point. FMI reports no work counters, so they stay empty.

use std::path::{Path, PathBuf};

use beam_body::fmu::variables::{Var, FORMULATION_TYPE, MODEL_IDENTIFIER, PHI_SOURCE_TYPE};
use beam_body::model::Formulation;
use beam_body::sim::Scene;

use super::problem::{Counters, Outcome, Problem, States};
use crate::import::{Call, CoSimulation, Common, Fmi2Error, Fmu2, InstanceCS};
use crate::{relative, target_dir, Result};

/// Where `cargo xtask bench` extracts the FMU and `bench-run` loads it from.
pub fn extracted_dir() -> PathBuf {
    target_dir().join("bench").join("fmu").join(MODEL_IDENTIFIER)
}

/// Builds and packages the FMU (as `cargo xtask fmu` does) and extracts it to a clean
/// [`extracted_dir`], so the benchmark runs exactly the packaged binary.
pub fn prepare() -> Result<PathBuf> {
    prepare_at(extracted_dir())
}

/// Builds and packages this machine's FMU next to `dir` (`dir`.fmu) and extracts it to a clean
/// `dir`.
pub fn prepare_at(dir: PathBuf) -> Result<PathBuf> {
    let out_dir = dir.parent().ok_or_else(|| format!("{} has no parent", relative(&dir)))?;
    let fmu = crate::fmu::build_package_in(out_dir, false)?.main;
    crate::fmu::extract(&fmu, &dir)?;
    Ok(dir)
}

/// Loads the extracted FMU (once per process: a tool loads an FMU once, then instantiates).
pub fn load(dir: &Path) -> std::result::Result<Fmu2, String> {
    if !dir.join("modelDescription.xml").is_file() {
        return Err(format!("no FMU in {} (`cargo xtask bench` extracts it)", relative(dir)));
    }
    Fmu2::load(dir).map_err(|err| err.to_string())
}

/// One run: instantiate, set the parameters, fmi2SetupExperiment(tolerance = `rtol`),
/// initialise, fmi2DoStep with communication step `h` to t_end, reading the states at the
/// grid times, terminate and free.
pub fn run(
    fmu: &Fmu2,
    problem: &Problem,
    rtol: f64,
    h: f64,
) -> std::result::Result<Outcome, String> {
    solve(fmu, problem, rtol, h).map_err(|err| err.to_string())
}

/// Sets the scene's formulation, φ source (`"law"` or `"input"`), model parameters and law.
pub fn set_scene(instance: &mut impl Common, scene: &Scene, phi_source: &str) -> Result {
    let source = item(PHI_SOURCE_TYPE.items, phi_source)?;
    let formulation = item(FORMULATION_TYPE.items, &scene.formulation.name().replace('-', "_"))?;
    let vrs = [Var::PhiSource.vr(), Var::Formulation.vr()];
    instance.set_integer(&vrs, &[source, formulation]).call("fmi2SetInteger")?;
    let p = &scene.params;
    let reals = [
        (Var::L, p.l),
        (Var::Ei, p.ei),
        (Var::M, p.m),
        (Var::M2, p.m2),
        (Var::JC, p.j_c),
        (Var::R, p.r),
        (Var::G, p.g),
        (Var::TRot, scene.law.t_rot),
        (Var::PhiEnd, scene.law.phi_end),
    ];
    let vrs: Vec<u32> = reals.iter().map(|(v, _)| v.vr()).collect();
    let values: Vec<f64> = reals.iter().map(|(_, x)| *x).collect();
    instance.set_real(&vrs, &values).call("fmi2SetReal")?;
    Ok(())
}

/// Value references of the recorded states, in the contract's order.
fn state_vrs(f: Formulation) -> Vec<u32> {
    let vars: &[Var] = if f.is_dae() {
        &[Var::V1, Var::Theta1, Var::U2, Var::Dv1, Var::Dtheta1, Var::Du2]
    } else {
        &[Var::V1, Var::Theta1, Var::Dv1, Var::Dtheta1]
    };
    vars.iter().map(|v| v.vr()).collect()
}

/// The value of an enumeration item: its 1-based position.
fn item(items: &[(&str, &str)], name: &str) -> Result<i32> {
    let position = items.iter().position(|(item, _)| *item == name);
    Ok(position.ok_or_else(|| format!("the FMU has no enumeration item `{name}`"))? as i32 + 1)
}

/// The communication points: every grid time, and between two grid times t_k + i·h for
/// the whole steps in between, so the grid times are hit exactly.
fn communication_points(grid: &[f64], h: f64) -> Result<(Vec<f64>, Vec<usize>)> {
    let mut points = vec![grid[0]];
    let mut at_grid = vec![0];
    for pair in grid.windows(2) {
        let ratio = (pair[1] - pair[0]) / h;
        let m = ratio.round().max(1.0) as usize;
        if (ratio - m as f64).abs() > 1e-6 * ratio {
            return Err(format!(
                "the communication step {h} does not divide {}",
                pair[1] - pair[0]
            )
            .into());
        }
        points.extend((1..m).map(|i| pair[0] + i as f64 * h));
        points.push(pair[1]);
        at_grid.push(points.len() - 1);
    }
    Ok((points, at_grid))
}

fn solve(fmu: &Fmu2, problem: &Problem, rtol: f64, h: f64) -> Result<Outcome> {
    let scene = &problem.scene;
    let (points, at_grid) = communication_points(&problem.grid, h)?;
    let vrs = state_vrs(scene.formulation);
    let mut instance = fmu.instantiate(MODEL_IDENTIFIER, false)?;
    set_scene(&mut instance, scene, "law")?;
    let stop = Some(*points.last().unwrap_or(&0.0));
    instance.setup_experiment(Some(rtol), points[0], stop).call("fmi2SetupExperiment")?;
    instance.enter_initialization_mode().call("fmi2EnterInitializationMode")?;
    instance.exit_initialization_mode().call("fmi2ExitInitializationMode")?;

    let mut states = States::with_capacity(problem.grid.len());
    let mut row = vec![0.0; vrs.len()];
    let mut read = |instance: &mut InstanceCS| -> Result {
        instance.get_real(&vrs, &mut row).call("fmi2GetReal")?;
        states.push(&row);
        Ok(())
    };
    read(&mut instance)?;
    let mut next_grid = at_grid.iter().skip(1).peekable();
    for (k, pair) in points.windows(2).enumerate() {
        let (tc, step) = (pair[0], pair[1] - pair[0]);
        match instance.do_step(tc, step, true) {
            Err(Fmi2Error::Discard) => {
                let reached = instance.last_successful_time().call("fmi2GetRealStatus")?;
                return Err(format!("fmi2DoStep({tc}; {step}) discarded at t = {reached}").into());
            }
            result => result.call("fmi2DoStep")?,
        };
        if next_grid.peek() == Some(&&(k + 1)) {
            read(&mut instance)?;
            next_grid.next();
        }
    }
    instance.terminate().call("fmi2Terminate")?;
    drop(instance);
    Ok(Outcome { states, counters: Counters::default() })
}
