//! Runs a scene: the model, a formulation and the integrator, sampled on an output grid.
//!
//! The integrator takes its own steps and the outputs come from its dense output, so the
//! grid never shortens a step. At the law's breakpoint t_rot, where φ'' jumps, the
//! integrator stops exactly and restarts at order 1 with the next smooth piece of φ.
//! No I/O: rows go to a callback.

use crate::model::{
    pq, u1, BeamBody, DaeSystem, Formulation, Outputs, PaperLaw, ParamError, Params, PhiPiece,
    TwoDofSystem,
};
use crate::solver::{Bdf, BdfConfig, FixedStep, OdeSystem, SolverError, Stats};
use nalgebra::SVector;
use std::fmt;

/// Initial state of the beam [m, rad, m/s, rad/s]. The DAE's u2, u̇2 start consistent.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct InitialState {
    pub v1: f64,
    pub theta1: f64,
    pub dv1: f64,
    pub dtheta1: f64,
}

/// Integrator settings of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverOptions {
    /// Relative tolerance. Default 1e-6.
    pub rtol: f64,
    /// Absolute tolerance for every state. Default `None`: 1e-3·rtol.
    pub atol: Option<f64>,
    /// Highest BDF order, 1..=5. Default 5.
    pub max_order: usize,
    /// The paper's constant-step mode. Default `None`.
    pub fixed_step: Option<FixedStep>,
    /// The BDF3–5 stability guard. Default on.
    pub stability_guard: bool,
}

impl Default for SolverOptions {
    fn default() -> Self {
        Self { rtol: 1e-6, atol: None, max_order: 5, fixed_step: None, stability_guard: true }
    }
}

impl SolverOptions {
    pub fn config<const N: usize>(&self) -> BdfConfig<N> {
        let mut cfg = BdfConfig::new(self.rtol);
        if let Some(a) = self.atol {
            cfg.atol = SVector::from_element(a);
        }
        cfg.max_order = self.max_order;
        cfg.fixed_step = self.fixed_step;
        cfg.stability_guard = self.stability_guard;
        cfg
    }
}

/// A scene: what to simulate and how to sample it.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub params: Params,
    pub law: PaperLaw,
    pub initial: InitialState,
    pub formulation: Formulation,
    pub solver: SolverOptions,
    /// End time [s], > 0. Default 10.
    pub t_end: f64,
    /// Output step [s], > 0. Default 0.01.
    pub dt_out: f64,
}

impl Default for Scene {
    fn default() -> Self {
        Self {
            params: Params::default(),
            law: PaperLaw::default(),
            initial: InitialState::default(),
            formulation: Formulation::Reduced,
            solver: SolverOptions::default(),
            t_end: 10.0,
            dt_out: 0.01,
        }
    }
}

/// Names [`Scene::set`] accepts besides the model parameters.
pub const SCENE_KEYS: [&str; 16] = [
    "t_rot",
    "phi_end",
    "phi0",
    "t_end",
    "dt_out",
    "v1_0",
    "theta1_0",
    "dv1_0",
    "dtheta1_0",
    "formulation",
    "rtol",
    "atol",
    "max_order",
    "fixed_step",
    "fixed_order",
    "stability_guard",
];

impl Scene {
    /// Sets one named value from its text: a model parameter ([`Params::NAMES`]) or one of
    /// [`SCENE_KEYS`]. The error names the key and its allowed values.
    pub fn set(&mut self, name: &str, text: &str) -> Result<(), String> {
        if name == "formulation" {
            self.formulation = text.parse()?;
            return Ok(());
        }
        if name == "stability_guard" {
            self.solver.stability_guard = match text {
                "true" | "1" => true,
                "false" | "0" => false,
                _ => return Err(format!("`stability_guard` = {text}: must be true or false")),
            };
            return Ok(());
        }
        let value: f64 = text.parse().map_err(|_| format!("`{name}` = {text}: not a number"))?;
        if self.params.set(name, value).map_err(|e| e.to_string())? {
            return Ok(());
        }
        let range = |ok: bool, allowed: &str| {
            if ok {
                Ok(())
            } else {
                Err(format!("`{name}` = {text} is out of range: must be {allowed}"))
            }
        };
        let positive = value.is_finite() && value > 0.0;
        let finite = value.is_finite();
        let order = value.fract() == 0.0 && (1.0..=5.0).contains(&value);
        match name {
            "t_rot" => range(positive, "positive and finite").map(|_| self.law.t_rot = value),
            "phi_end" => range(finite, "finite").map(|_| self.law.phi_end = value),
            "phi0" => range(finite, "finite").map(|_| self.law.phi0 = value),
            "t_end" => range(positive, "positive and finite").map(|_| self.t_end = value),
            "dt_out" => range(positive, "positive and finite").map(|_| self.dt_out = value),
            "v1_0" => range(finite, "finite").map(|_| self.initial.v1 = value),
            "theta1_0" => range(finite, "finite").map(|_| self.initial.theta1 = value),
            "dv1_0" => range(finite, "finite").map(|_| self.initial.dv1 = value),
            "dtheta1_0" => range(finite, "finite").map(|_| self.initial.dtheta1 = value),
            "rtol" => range((1e-14..=1.0).contains(&value), "in [1e-14, 1]")
                .map(|_| self.solver.rtol = value),
            "atol" => {
                range(positive, "positive and finite").map(|_| self.solver.atol = Some(value))
            }
            "max_order" => {
                range(order, "an integer in 1..=5").map(|_| self.solver.max_order = value as usize)
            }
            "fixed_step" => range(positive, "positive and finite").map(|_| {
                let order = self.solver.fixed_step.map_or(2, |f| f.order);
                self.solver.fixed_step = Some(FixedStep { h: value, order });
            }),
            "fixed_order" => range(order, "an integer in 1..=5").map(|_| {
                let h = self.solver.fixed_step.map_or(f64::NAN, |f| f.h);
                self.solver.fixed_step = Some(FixedStep { h, order: value as usize });
            }),
            _ => Err(format!(
                "unknown name `{name}`: must be one of {}, {}",
                Params::NAMES.join(", "),
                SCENE_KEYS.join(", ")
            )),
        }
    }

    /// The output times k·dt_out, k = 0, 1, …, ending exactly at t_end (a last, shorter
    /// interval if t_end is not a multiple of dt_out).
    pub fn output_times(&self) -> impl Iterator<Item = f64> + '_ {
        let ratio = self.t_end / self.dt_out;
        let n = (ratio + 1e-9).floor() as u64;
        let exact = (ratio - n as f64).abs() <= 1e-9 * ratio.max(1.0);
        let last = if exact { n } else { n + 1 };
        (0..=last).map(move |k| if k == last { self.t_end } else { k as f64 * self.dt_out })
    }

    /// Checks everything that does not need the integrator.
    pub fn validate(&self) -> Result<BeamBody, SimError> {
        let model = BeamBody::new(self.params).map_err(SimError::Param)?;
        self.law.validate().map_err(SimError::Param)?;
        model
            .check_start(self.law.eval(0.0).phi, self.initial.v1, self.initial.theta1)
            .map_err(SimError::Param)?;
        if let Some(f) = self.solver.fixed_step {
            if !(f.h.is_finite() && f.h > 0.0) {
                return Err(SimError::Setting(
                    "`fixed_order` needs `fixed_step` (the constant step size) as well".into(),
                ));
            }
        }
        Ok(model)
    }
}

/// Why a run failed.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    Param(ParamError),
    Setting(String),
    Solver(SolverError),
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::Param(e) => e.fmt(f),
            SimError::Setting(s) => f.write_str(s),
            SimError::Solver(e) => write!(f, "integration failed: {e}"),
        }
    }
}

impl std::error::Error for SimError {}

impl From<SolverError> for SimError {
    fn from(e: SolverError) -> Self {
        SimError::Solver(e)
    }
}

/// Runs the scene, calling `sink` with the outputs at every output time. Returns the
/// integrator's counters.
pub fn simulate(scene: &Scene, mut sink: impl FnMut(&Outputs)) -> Result<Stats, SimError> {
    let model = scene.validate()?;
    let init = scene.initial;
    match scene.formulation {
        Formulation::Reduced | Formulation::Linear => {
            let linear = scene.formulation == Formulation::Linear;
            let y0 = SVector::<f64, 4>::new(init.v1, init.theta1, init.dv1, init.dtheta1);
            let make = |phi| TwoDofSystem { model: &model, phi, linear };
            run(scene, y0, make, |s, t, y| s.outputs(t, y), &mut sink)
        }
        Formulation::Dae | Formulation::DaeStabilized => {
            let stabilized = scene.formulation == Formulation::DaeStabilized;
            let l = model.params.l;
            let (p, q) = pq(l, init.v1, init.theta1);
            let y0 = SVector::<f64, 6>::from([
                init.v1,
                init.theta1,
                u1(l, init.v1, init.theta1),
                init.dv1,
                init.dtheta1,
                -p * init.dv1 - l * q * init.dtheta1,
            ]);
            let make = |phi| DaeSystem { model: &model, phi, stabilized };
            run(scene, y0, make, |s, t, y| s.outputs(t, y), &mut sink)
        }
    }
}

fn run<const N: usize, S: OdeSystem<N>>(
    scene: &Scene,
    y0: SVector<f64, N>,
    make: impl Fn(PhiPiece) -> S,
    outputs: impl Fn(&S, f64, &SVector<f64, N>) -> Outputs,
    sink: &mut impl FnMut(&Outputs),
) -> Result<Stats, SimError> {
    let law = scene.law;
    let mut segment_ends = Vec::with_capacity(2);
    if law.breakpoint() < scene.t_end {
        segment_ends.push(law.breakpoint());
    }
    segment_ends.push(scene.t_end);
    let mut segment = 0;
    let mut sys = make(law.piece_from(0.0));
    let mut solver = Bdf::new(scene.solver.config(), 0.0, y0)?;
    for t in scene.output_times() {
        if t == 0.0 {
            sink(&outputs(&sys, 0.0, &y0));
            continue;
        }
        loop {
            let end = segment_ends[segment];
            if t <= end {
                solver.advance(&sys, t, end)?;
                sink(&outputs(&sys, t, &solver.interpolate(t)?));
                break;
            }
            // Cross the breakpoint: land on it, then restart with the next piece of φ.
            solver.advance(&sys, end, end)?;
            let y = *solver.y();
            segment += 1;
            sys = make(law.piece_from(end));
            solver.reinit(end, y)?;
        }
    }
    Ok(*solver.stats())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_grid_is_exact_and_ends_at_t_end() {
        let scene = Scene { t_end: 10.2, dt_out: 0.0085, ..Scene::default() };
        let times: Vec<f64> = scene.output_times().collect();
        assert_eq!(times.len(), 1201);
        assert_eq!(times[0], 0.0);
        assert_eq!(times[7], 7.0 * 0.0085);
        assert_eq!(*times.last().unwrap(), 10.2);
        let uneven = Scene { t_end: 1.05, dt_out: 0.1, ..Scene::default() };
        let times: Vec<f64> = uneven.output_times().collect();
        assert_eq!(times.len(), 12);
        assert_eq!(times[10], 1.0);
        assert_eq!(times[11], 1.05);
    }

    #[test]
    fn set_rejects_unknown_names_and_bad_values() {
        let mut s = Scene::default();
        assert!(s.set("EI", "2000").is_ok());
        assert!(s.set("t_rot", "0.5").is_ok());
        assert_eq!(s.law.t_rot, 0.5);
        let e = s.set("EI", "-1").unwrap_err();
        assert!(e.contains("EI") && e.contains("positive"), "{e}");
        let e = s.set("bogus", "1").unwrap_err();
        assert!(e.contains("unknown name `bogus`"), "{e}");
        assert!(s.set("dt_out", "0").is_err());
        assert!(s.set("formulation", "dae-stabilized").is_ok());
        assert!(s.set("formulation", "quantum").is_err());
        assert!(s.set("max_order", "6").is_err());
    }
}
