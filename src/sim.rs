//! Runs a scene: the model, a formulation and the integrator, sampled on an output grid.
//!
//! The integrator takes its own steps and the outputs come from its dense output, so the
//! grid never shortens a step. At the law's breakpoint t_rot, where φ'' jumps, the
//! integrator stops exactly and restarts at order 1 with the next smooth piece of φ.
//! No I/O: rows go to a callback.
#![forbid(unsafe_code)]

use crate::model::{
    BeamBody, DaeSystem, Formulation, Outputs, PaperLaw, ParamError, Params, Phi, PhiPiece,
    TaylorSignal, TwoDofSystem, ValueHistory,
};
use crate::solver::{Bdf, BdfConfig, FixedStep, SolverError, StateVisitor, Stats};
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
    /// Most internal steps in one call of the integrator (one output interval, one FMI
    /// communication step), ≥ 1. Default 10⁷.
    pub max_steps: u64,
}

impl Default for SolverOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-6,
            atol: None,
            max_order: 5,
            fixed_step: None,
            stability_guard: true,
            max_steps: 10_000_000,
        }
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
        cfg.max_steps = self.max_steps;
        cfg
    }
}

/// How φ reaches the model in a standalone run. The sampled feeds do what an FMI host does
/// with the FMU at communication step `dt_comm`, so the FMU can be checked against them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhiFeed {
    /// The law itself; its breakpoint is hit exactly.
    Law,
    /// At each communication point, the law's φ, φ', φ'' as a Taylor polynomial over the
    /// step (a host that sends derivatives).
    Derivatives,
    /// The law's values at the communication points only, extrapolated by
    /// [`ValueHistory`] (a host that sends values).
    Values,
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
    /// How φ reaches the model. Default [`PhiFeed::Law`].
    pub phi_feed: PhiFeed,
    /// Communication step of the sampled feeds [s], > 0. Default 0.01.
    pub dt_comm: f64,
    /// Degree of the extrapolation of [`PhiFeed::Values`], 0..=3. Default 3.
    pub phi_extrapolation: usize,
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
            phi_feed: PhiFeed::Law,
            dt_comm: 0.01,
            phi_extrapolation: ValueHistory::MAX_DEGREE,
        }
    }
}

/// Names [`Scene::set`] accepts besides the model parameters.
pub const SCENE_KEYS: [&str; 19] = [
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
    "phi_feed",
    "dt_comm",
    "phi_extrapolation",
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
        if name == "phi_feed" {
            self.phi_feed = match text {
                "law" => PhiFeed::Law,
                "derivatives" => PhiFeed::Derivatives,
                "values" => PhiFeed::Values,
                _ => {
                    return Err(format!(
                        "`phi_feed` = {text}: must be one of law, derivatives, values"
                    ))
                }
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
            "dt_comm" => range(positive, "positive and finite").map(|_| self.dt_comm = value),
            "phi_extrapolation" => {
                let ok = value.fract() == 0.0 && (0.0..=3.0).contains(&value);
                range(ok, "an integer in 0..=3").map(|_| self.phi_extrapolation = value as usize)
            }
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
    pub fn output_times(&self) -> impl Iterator<Item = f64> {
        grid(self.dt_out, self.t_end)
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

/// The `key = value` lines of a flat TOML scene file: numbers, booleans and "strings",
/// `#` comments, as (line number, key, value). Tables and arrays are not part of the scene
/// format. Parsing only: the caller reads the file and applies the entries ([`Scene::set`]).
pub fn scene_entries(text: &str) -> Result<Vec<(usize, String, String)>, String> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let n = i + 1;
        let line = match raw.find('#') {
            Some(pos) if !raw[..pos].contains('"') => &raw[..pos],
            _ => raw,
        }
        .trim();
        if line.is_empty() {
            continue;
        }
        if line.starts_with('[') {
            return Err(format!(
                "line {n}: tables are not used: a scene is flat `key = value` lines"
            ));
        }
        let (key, val) = line
            .split_once('=')
            .ok_or_else(|| format!("line {n}: expected `key = value`, got `{line}`"))?;
        let val = val.trim();
        let val = match val.strip_prefix('"') {
            Some(rest) => {
                rest.strip_suffix('"').ok_or_else(|| format!("line {n}: unterminated string"))?
            }
            None => val,
        };
        out.push((n, key.trim().to_string(), val.to_string()));
    }
    Ok(out)
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

/// The times k·`step`, k = 0, 1, …, ending exactly at `t_end` (a last, shorter interval if
/// `t_end` is not a multiple of `step`).
fn grid(step: f64, t_end: f64) -> impl Iterator<Item = f64> {
    let ratio = t_end / step;
    let n = (ratio + 1e-9).floor() as u64;
    let exact = (ratio - n as f64).abs() <= 1e-9 * ratio.max(1.0);
    let last = if exact { n } else { n + 1 };
    (0..=last).map(move |k| if k == last { t_end } else { k as f64 * step })
}

/// Runs the scene, calling `sink` with the outputs at every output time. Returns the
/// integrator's counters.
pub fn simulate(scene: &Scene, mut sink: impl FnMut(&Outputs)) -> Result<Stats, SimError> {
    let model = scene.validate()?;
    let law = scene.law;
    // As the FMU starts: the law, the host's derivatives, or the value at rest.
    let start = match scene.phi_feed {
        PhiFeed::Law => law.piece_from(0.0),
        PhiFeed::Derivatives => {
            PhiPiece::Taylor(TaylorSignal { t0: 0.0, at_t0: law.eval(0.0), jerk: 0.0 })
        }
        PhiFeed::Values => PhiPiece::Taylor(TaylorSignal {
            t0: 0.0,
            at_t0: Phi { phi: law.eval(0.0).phi, dphi: 0.0, ddphi: 0.0 },
            jerk: 0.0,
        }),
    };
    let mut run = Run::new(model, scene.formulation, &scene.solver, 0.0, scene.initial, start)?;
    let mut outputs = scene.output_times().peekable();
    if scene.phi_feed == PhiFeed::Law {
        for t in outputs {
            run.advance_law(&law, t, scene.t_end)?;
            sink(&run.outputs_at(t)?);
        }
        return Ok(run.stats());
    }
    let comm: Vec<f64> = grid(scene.dt_comm, scene.t_end).collect();
    let mut history = ValueHistory::default();
    for w in comm.windows(2) {
        let (a, b) = (w[0], w[1]);
        let signal = match scene.phi_feed {
            PhiFeed::Derivatives => TaylorSignal { t0: a, at_t0: law.eval(a), jerk: 0.0 },
            _ => {
                history.push(a, law.eval(a).phi);
                let start = run.piece().eval(a);
                history.piece(scene.phi_extrapolation, start, b - a).expect("a sample, h > 0")
            }
        };
        run.switch_piece(PhiPiece::Taylor(signal))?;
        while let Some(&t) = outputs.peek() {
            if t > b {
                break;
            }
            run.advance(t, b)?;
            sink(&run.outputs_at(t)?);
            outputs.next();
        }
        run.advance(b, b)?;
    }
    Ok(run.stats())
}

/// The integrator and the model for a formulation chosen at run time, advanced piece by
/// piece of φ. The standalone driver ([`simulate`]) and the FMU both step through it, so they
/// integrate the same way. `Clone` copies everything (FMU state save and restore).
#[derive(Clone, Debug)]
pub struct Run {
    model: BeamBody,
    formulation: Formulation,
    piece: PhiPiece,
    bdf: Integrator,
}

/// Whether two times differ by no more than a few ulps: the round-off of a host's tc + h.
fn within_rounding(a: f64, b: f64) -> bool {
    (a - b).abs() <= 16.0 * f64::EPSILON * a.abs().max(b.abs())
}

fn two_dof(model: &BeamBody, phi: PhiPiece, formulation: Formulation) -> TwoDofSystem<'_> {
    TwoDofSystem { model, phi, linear: formulation == Formulation::Linear }
}

fn dae(model: &BeamBody, phi: PhiPiece, formulation: Formulation) -> DaeSystem<'_> {
    DaeSystem { model, phi, stabilized: formulation == Formulation::DaeStabilized }
}

/// Four states (reduced, linear) or six (dae, dae-stabilized). The variants differ by
/// 0.5 kB; a run holds one, so boxing would only add an indirection to every step.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
enum Integrator {
    Two(Bdf<4>),
    Dae(Bdf<6>),
}

impl Run {
    /// A run from `init` at `t0`, with φ from `piece` until [`set_piece`](Self::set_piece).
    /// The DAE's u2 and u̇2 start consistent.
    pub fn new(
        model: BeamBody,
        formulation: Formulation,
        options: &SolverOptions,
        t0: f64,
        init: InitialState,
        piece: PhiPiece,
    ) -> Result<Self, SolverError> {
        let bdf = if formulation.is_dae() {
            let free =
                SVector::<f64, 6>::new(init.v1, init.theta1, 0.0, init.dv1, init.dtheta1, 0.0);
            let y0 = dae(&model, piece, formulation).consistent(&free);
            Integrator::Dae(Bdf::new(options.config(), t0, y0)?)
        } else {
            let y0 = SVector::<f64, 4>::new(init.v1, init.theta1, init.dv1, init.dtheta1);
            Integrator::Two(Bdf::new(options.config(), t0, y0)?)
        };
        Ok(Self { model, formulation, piece, bdf })
    }

    pub fn model(&self) -> &BeamBody {
        &self.model
    }

    pub fn formulation(&self) -> Formulation {
        self.formulation
    }

    /// The solver's time: that of its last step.
    pub fn t(&self) -> f64 {
        match &self.bdf {
            Integrator::Two(b) => b.t(),
            Integrator::Dae(b) => b.t(),
        }
    }

    /// The piece of φ in use.
    pub fn piece(&self) -> PhiPiece {
        self.piece
    }

    pub fn stats(&self) -> Stats {
        match &self.bdf {
            Integrator::Two(b) => *b.stats(),
            Integrator::Dae(b) => *b.stats(),
        }
    }

    /// Uses `piece` for φ from now on. With `restart`, the integrator drops its step history
    /// and restarts at order 1 (for a jump of φ''); without, the error test sees the change.
    pub fn set_piece(&mut self, piece: PhiPiece, restart: bool) -> Result<(), SolverError> {
        self.piece = piece;
        if restart {
            match &mut self.bdf {
                Integrator::Two(b) => b.reinit(b.t(), *b.y()),
                Integrator::Dae(b) => b.reinit(b.t(), *b.y()),
            }?;
        }
        Ok(())
    }

    /// Switches to `piece`, restarting the integrator if φ, φ' or φ'' jump at the current
    /// time (by more than round-off). A jump of φ'' is a jump of f: kept across it, the step
    /// history makes the error test fail repeatedly at tight tolerances (the paper's scene
    /// with derivatives sent every 8.5 ms failed at rtol 1e-10 without this restart).
    pub fn switch_piece(&mut self, piece: PhiPiece) -> Result<(), SolverError> {
        let t = self.t();
        let (old, new) = (self.piece.eval(t), piece.eval(t));
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0);
        let jump =
            !(same(old.phi, new.phi) && same(old.dphi, new.dphi) && same(old.ddphi, new.ddphi));
        self.set_piece(piece, jump)
    }

    fn two_dof(&self) -> TwoDofSystem<'_> {
        two_dof(&self.model, self.piece, self.formulation)
    }

    fn dae(&self) -> DaeSystem<'_> {
        dae(&self.model, self.piece, self.formulation)
    }

    /// Steps with the current piece until t ≥ `tout`, never past `tstop`
    /// ([`Bdf::advance`]).
    /// A `tout` within rounding of the solver's time takes no step.
    pub fn advance(&mut self, tout: f64, tstop: f64) -> Result<(), SolverError> {
        if tout > self.t() && within_rounding(tout, self.t()) {
            return Ok(());
        }
        let (model, piece, formulation) = (&self.model, self.piece, self.formulation);
        match &mut self.bdf {
            Integrator::Two(b) => b.advance(&two_dof(model, piece, formulation), tout, tstop),
            Integrator::Dae(b) => b.advance(&dae(model, piece, formulation), tout, tstop),
        }
    }

    /// [`advance`](Self::advance) with φ from `law`: lands exactly on the law's breakpoint
    /// and restarts there with the next piece, so f is never evaluated across the jump of
    /// φ''. The current piece must be `law.piece_from(self.t())`.
    pub fn advance_law(
        &mut self,
        law: &PaperLaw,
        tout: f64,
        tstop: f64,
    ) -> Result<(), SolverError> {
        let bp = law.breakpoint();
        // A stop within rounding of the breakpoint is the breakpoint (a host's tc + h), so the
        // integrator never takes a step of a few ulps after landing on it.
        let tstop = if within_rounding(tstop, bp) { bp } else { tstop };
        let tout = tout.min(tstop);
        loop {
            let turning = matches!(self.piece, PhiPiece::Turn(_));
            if turning && self.t() >= bp && tout > self.t() {
                self.set_piece(law.piece_from(bp), true)?;
                continue;
            }
            if turning && tout > bp && tstop > bp {
                self.advance(bp, bp)?;
                continue;
            }
            let stop = if turning { tstop.min(bp) } else { tstop };
            return self.advance(tout, stop);
        }
    }

    /// The outputs at `t` inside the last step (dense output), with the current piece.
    pub fn outputs_at(&self, t: f64) -> Result<Outputs, SolverError> {
        Ok(match &self.bdf {
            Integrator::Two(b) => self.two_dof().outputs(t, &b.interpolate(t)?),
            Integrator::Dae(b) => self.dae().outputs(t, &b.interpolate(t)?),
        })
    }

    /// The state at `t` inside the last step (dense output) into `out`: (v1, ϑ1, v̇1, ϑ̇1),
    /// or (v1, ϑ1, u2, v̇1, ϑ̇1, u̇2) for the DAE formulations (projected when stabilised, as
    /// the outputs are). Returns the number of states written. Cheaper than
    /// [`outputs_at`](Self::outputs_at), which also computes accelerations, reactions and
    /// energy; the benchmark records this, as the other solvers record their states.
    pub fn state_at(&self, t: f64, out: &mut [f64; 6]) -> Result<usize, SolverError> {
        match &self.bdf {
            Integrator::Two(b) => {
                out[..4].copy_from_slice(b.interpolate(t)?.as_slice());
                Ok(4)
            }
            Integrator::Dae(b) => {
                let mut y = b.interpolate(t)?;
                if self.formulation == Formulation::DaeStabilized {
                    y = self.dae().consistent(&y);
                }
                out.copy_from_slice(y.as_slice());
                Ok(6)
            }
        }
    }

    /// Visits the integrator's state ([`Bdf::visit_state`]); the model, formulation and
    /// settings are the caller's to restore.
    pub fn visit_state(&mut self, v: &mut impl StateVisitor) {
        match &mut self.bdf {
            Integrator::Two(b) => b.visit_state(v),
            Integrator::Dae(b) => b.visit_state(v),
        }
    }

    /// Checks a state written by a visitor ([`Bdf::check_state`]).
    pub fn check_state(&self) -> Result<(), SolverError> {
        match &self.bdf {
            Integrator::Two(b) => b.check_state(),
            Integrator::Dae(b) => b.check_state(),
        }
    }
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

    #[test]
    fn state_at_matches_the_outputs() {
        for formulation in Formulation::ALL {
            let scene = Scene { formulation, ..Scene::default() };
            let model = scene.validate().unwrap();
            let law = scene.law;
            let mut run = Run::new(
                model,
                formulation,
                &scene.solver,
                0.0,
                scene.initial,
                law.piece_from(0.0),
            )
            .unwrap();
            run.advance_law(&law, 0.5, 1.0).unwrap();
            let o = run.outputs_at(0.5).unwrap();
            let mut y = [0.0; 6];
            let n = run.state_at(0.5, &mut y).unwrap();
            let want: Vec<f64> = if formulation.is_dae() {
                vec![o.v1, o.theta1, o.u2, o.dv1, o.dtheta1, o.du2]
            } else {
                vec![o.v1, o.theta1, o.dv1, o.dtheta1]
            };
            assert_eq!(&y[..n], &want[..], "{formulation}");
        }
    }
}
