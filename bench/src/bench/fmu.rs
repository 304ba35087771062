//! Solvers `fmu` and `fmu3`: the packaged FMU (`target/fmu/BeamBody.fmu`, extracted to
//! `target/bench/fmu/BeamBody/`; `BeamBody-fmi3.fmu` to `target/bench/fmu/BeamBody-fmi3/`)
//! driven by the native host ([`crate::import`], FMI 2.0 or 3.0) with φ from the built-in law
//! (phi_source = law), tolerance = the case's rtol (fmi2SetupExperiment,
//! fmi3EnterInitializationMode), and DoStep at a constant communication step H from 0 to t_end.
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
use crate::import::{
    Call, CoSimulation, CoSimulation3, Common, Common3, Fmi2Error, Fmu2, Fmu3, GetSet3, InstanceCS,
    InstanceCS3,
};
use crate::{relative, target_dir, Result};

/// Where `cargo xtask bench` extracts the FMU and `bench-run` loads it from.
pub fn extracted_dir() -> PathBuf {
    target_dir().join("bench").join("fmu").join(MODEL_IDENTIFIER)
}

/// Where `cargo xtask bench` extracts the FMI 3.0 archive.
pub fn extracted_dir3() -> PathBuf {
    target_dir().join("bench").join("fmu").join(format!("{MODEL_IDENTIFIER}-fmi3"))
}

/// Builds and packages the FMU (as `cargo xtask fmu` does) and extracts it to a clean
/// [`extracted_dir`] (and the FMI 3.0 archive to [`extracted_dir3`]), so the benchmark runs
/// exactly the packaged binary.
pub fn prepare() -> Result<PathBuf> {
    let dir = extracted_dir();
    let packages = package_next_to(&dir)?;
    crate::fmu::extract(&packages.main, &dir)?;
    crate::fmu::extract(&packages.fmi3, &extracted_dir3())?;
    Ok(dir)
}

/// Builds and packages this machine's FMU next to `dir` (`dir`.fmu) and extracts it to a clean
/// `dir`.
pub fn prepare_at(dir: PathBuf) -> Result<PathBuf> {
    let fmu = package_next_to(&dir)?.main;
    crate::fmu::extract(&fmu, &dir)?;
    Ok(dir)
}

fn package_next_to(dir: &Path) -> Result<crate::fmu::Packages> {
    let out_dir = dir.parent().ok_or_else(|| format!("{} has no parent", relative(dir)))?;
    crate::fmu::build_package_in(out_dir, false)
}

/// Loads the extracted FMU (once per process: a tool loads an FMU once, then instantiates).
pub fn load(dir: &Path) -> std::result::Result<Fmu2, String> {
    if !dir.join("modelDescription.xml").is_file() {
        return Err(format!("no FMU in {} (`cargo xtask bench` extracts it)", relative(dir)));
    }
    Fmu2::load(dir).map_err(|err| err.to_string())
}

/// Loads the extracted FMI 3.0 FMU.
pub fn load3(dir: &Path) -> std::result::Result<Fmu3, String> {
    if !dir.join("modelDescription.xml").is_file() {
        return Err(format!("no FMU in {} (`cargo xtask bench` extracts it)", relative(dir)));
    }
    Fmu3::load(dir).map_err(|err| err.to_string())
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
    let solve = || solve(&mut fmu.instantiate(MODEL_IDENTIFIER, false)?, problem, rtol, h);
    solve().map_err(|err| err.to_string())
}

/// [`run`] through FMI 3.0.
pub fn run3(
    fmu: &Fmu3,
    problem: &Problem,
    rtol: f64,
    h: f64,
) -> std::result::Result<Outcome, String> {
    let solve = || solve(&mut fmu.instantiate(MODEL_IDENTIFIER)?, problem, rtol, h);
    solve().map_err(|err| err.to_string())
}

/// What a run asks of a co-simulation instance, of either FMI version.
trait Slave {
    fn set_enums(&mut self, vrs: &[u32], values: &[i32]) -> Result;
    fn set_reals(&mut self, vrs: &[u32], values: &[f64]) -> Result;
    fn initialize(&mut self, rtol: f64, start: f64, stop: f64) -> Result;
    fn get_reals(&mut self, vrs: &[u32], out: &mut [f64]) -> Result;
    /// DoStep; a discarded step is an error that says where it stopped.
    fn step(&mut self, tc: f64, h: f64) -> Result;
    fn terminate(&mut self) -> Result;
}

impl Slave for InstanceCS {
    fn set_enums(&mut self, vrs: &[u32], values: &[i32]) -> Result {
        self.set_integer(vrs, values).call("fmi2SetInteger").map(drop)
    }
    fn set_reals(&mut self, vrs: &[u32], values: &[f64]) -> Result {
        self.set_real(vrs, values).call("fmi2SetReal").map(drop)
    }
    fn initialize(&mut self, rtol: f64, start: f64, stop: f64) -> Result {
        self.setup_experiment(Some(rtol), start, Some(stop)).call("fmi2SetupExperiment")?;
        self.enter_initialization_mode().call("fmi2EnterInitializationMode")?;
        self.exit_initialization_mode().call("fmi2ExitInitializationMode").map(drop)
    }
    fn get_reals(&mut self, vrs: &[u32], out: &mut [f64]) -> Result {
        self.get_real(vrs, out).call("fmi2GetReal").map(drop)
    }
    fn step(&mut self, tc: f64, h: f64) -> Result {
        match self.do_step(tc, h, true) {
            Err(Fmi2Error::Discard) => {
                let reached = self.last_successful_time().call("fmi2GetRealStatus")?;
                Err(format!("fmi2DoStep({tc}; {h}) discarded at t = {reached}").into())
            }
            result => result.call("fmi2DoStep").map(drop),
        }
    }
    fn terminate(&mut self) -> Result {
        Common::terminate(self).call("fmi2Terminate").map(drop)
    }
}

impl Slave for InstanceCS3 {
    fn set_enums(&mut self, vrs: &[u32], values: &[i32]) -> Result {
        let values: Vec<i64> = values.iter().map(|k| i64::from(*k)).collect();
        self.set_int64(vrs, &values).call("fmi3SetInt64").map(drop)
    }
    fn set_reals(&mut self, vrs: &[u32], values: &[f64]) -> Result {
        self.set_float64(vrs, values).call("fmi3SetFloat64").map(drop)
    }
    fn initialize(&mut self, rtol: f64, start: f64, stop: f64) -> Result {
        self.enter_initialization_mode(Some(rtol), start, Some(stop))
            .call("fmi3EnterInitializationMode")?;
        self.exit_initialization_mode().call("fmi3ExitInitializationMode").map(drop)
    }
    fn get_reals(&mut self, vrs: &[u32], out: &mut [f64]) -> Result {
        self.get_float64(vrs, out).call("fmi3GetFloat64").map(drop)
    }
    fn step(&mut self, tc: f64, h: f64) -> Result {
        let (mut event, mut terminate, mut early, mut last) = (false, false, false, f64::NAN);
        let status = self.do_step(tc, h, true, &mut event, &mut terminate, &mut early, &mut last);
        match status {
            Err(crate::import::Fmi3Error::Discard) => {
                Err(format!("fmi3DoStep({tc}; {h}) discarded at t = {last}").into())
            }
            result => result.call("fmi3DoStep").map(drop),
        }
    }
    fn terminate(&mut self) -> Result {
        Common3::terminate(self).call("fmi3Terminate").map(drop)
    }
}

/// Sets the scene's formulation, φ source (`"law"` or `"input"`), model parameters and law.
pub fn set_scene(instance: &mut impl Common, scene: &Scene, phi_source: &str) -> Result {
    let (enums, reals) = scene_values(scene, phi_source)?;
    let (vrs, values): (Vec<u32>, Vec<i32>) = enums.into_iter().unzip();
    instance.set_integer(&vrs, &values).call("fmi2SetInteger")?;
    let (vrs, values): (Vec<u32>, Vec<f64>) = reals.into_iter().unzip();
    instance.set_real(&vrs, &values).call("fmi2SetReal")?;
    Ok(())
}

/// The enumerations (φ source, formulation) and reals (model parameters and law) of a scene,
/// as (value reference, value).
#[allow(clippy::type_complexity)]
fn scene_values(scene: &Scene, phi_source: &str) -> Result<(Vec<(u32, i32)>, Vec<(u32, f64)>)> {
    let source = item(PHI_SOURCE_TYPE.items, phi_source)?;
    let formulation = item(FORMULATION_TYPE.items, &scene.formulation.name().replace('-', "_"))?;
    let enums = vec![(Var::PhiSource.vr(), source), (Var::Formulation.vr(), formulation)];
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
    Ok((enums, reals.iter().map(|(v, x)| (v.vr(), *x)).collect()))
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

fn solve(instance: &mut impl Slave, problem: &Problem, rtol: f64, h: f64) -> Result<Outcome> {
    let scene = &problem.scene;
    let (points, at_grid) = communication_points(&problem.grid, h)?;
    let vrs = state_vrs(scene.formulation);
    let (enums, reals) = scene_values(scene, "law")?;
    let (evrs, evalues): (Vec<u32>, Vec<i32>) = enums.into_iter().unzip();
    instance.set_enums(&evrs, &evalues)?;
    let (rvrs, rvalues): (Vec<u32>, Vec<f64>) = reals.into_iter().unzip();
    instance.set_reals(&rvrs, &rvalues)?;
    instance.initialize(rtol, points[0], *points.last().unwrap_or(&0.0))?;

    let mut states = States::with_capacity(problem.grid.len());
    let mut row = vec![0.0; vrs.len()];
    instance.get_reals(&vrs, &mut row)?;
    states.push(&row);
    let mut next_grid = at_grid.iter().skip(1).peekable();
    for (k, pair) in points.windows(2).enumerate() {
        instance.step(pair[0], pair[1] - pair[0])?;
        if next_grid.peek() == Some(&&(k + 1)) {
            instance.get_reals(&vrs, &mut row)?;
            states.push(&row);
            next_grid.next();
        }
    }
    instance.terminate()?;
    Ok(Outcome { states, counters: Counters::default() })
}
