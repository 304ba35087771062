//! Runs a scene: the model, a formulation and the integrator, sampled on an output grid.
//!
//! The integrator takes its own steps and the outputs come from its dense output, so the
//! grid never shortens a step. At the law's breakpoint t_rot, where φ'' jumps, the
//! integrator stops exactly and restarts at order 1 with the next smooth piece of φ.
//! No I/O: rows go to a callback.
#![forbid(unsafe_code)]

use crate::model::{
    BeamBody, DaeSystem, Formulation, HostSignal, Interpolation, Kinematics, Outputs, PaperLaw,
    ParamError, Params, Phi, PhiPiece, Poly, RangeCheck, Sample, TwoDofSystem, HISTORY,
};
use crate::solver::{
    check_rtol, Bdf, BdfConfig, FixedStep, OdeSystem, SolverError, StateVisitor, Stats, StepOutcome,
};
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

/// How φ reaches the model in a standalone run. The sampled feeds do what an FMI host does
/// with the FMU at communication step `dt_comm`, so the FMU can be checked against them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhiFeed {
    /// The law itself; its breakpoint is hit exactly.
    Law,
    /// At each communication point, the law's φ, φ', φ'' as a Taylor polynomial over the
    /// step (a host that sends derivatives).
    Derivatives,
    /// The law's values at the communication points only (a host that sends values).
    Values,
}

/// A scene: what to simulate and how to sample it.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub params: Params,
    pub law: PaperLaw,
    pub initial: InitialState,
    pub formulation: Formulation,
    pub solver: BdfConfig,
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
    /// How the sampled feeds are interpolated between communication points. Default
    /// [`Interpolation::Smooth`].
    pub phi_interpolation: Interpolation,
    /// What the run does when the state leaves the range of validity. Default
    /// [`RangeCheck::Stop`].
    pub range_check: RangeCheck,
}

impl Default for Scene {
    fn default() -> Self {
        Self {
            params: Params::default(),
            law: PaperLaw::default(),
            initial: InitialState::default(),
            formulation: Formulation::Reduced,
            solver: BdfConfig::default(),
            t_end: 10.0,
            dt_out: 0.01,
            phi_feed: PhiFeed::Law,
            dt_comm: 0.01,
            phi_extrapolation: HISTORY - 1,
            phi_interpolation: Interpolation::Smooth,
            range_check: RangeCheck::Stop,
        }
    }
}

/// Names [`Scene::set`] accepts besides the model parameters.
pub const SCENE_KEYS: [&str; 21] = [
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
    "phi_interpolation",
    "range_check",
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
        if name == "range_check" {
            self.range_check = text.parse()?;
            return Ok(());
        }
        if name == "phi_interpolation" {
            self.phi_interpolation = text.parse()?;
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
        self.set_parsed(name, value, text)
    }

    /// Sets one named number: a model parameter or a numeric key of [`SCENE_KEYS`], with the
    /// checks and messages of [`set`](Self::set).
    pub fn set_number(&mut self, name: &str, value: f64) -> Result<(), String> {
        self.set_parsed(name, value, &value.to_string())
    }

    fn set_parsed(&mut self, name: &str, value: f64, text: &str) -> Result<(), String> {
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
            "rtol" => match check_rtol(value) {
                Ok(()) => {
                    let _: () = self.solver.rtol = value;
                    Ok(())
                }
                Err(allowed) => range(false, allowed),
            },
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

/// What a finished run reports besides its outputs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// The integrator's counters.
    pub stats: Stats,
    /// With `range_check = warn`: where the run left the range of validity.
    pub warning: Option<String>,
}

/// Runs the scene, calling `sink` with the outputs at every output time.
pub fn simulate(scene: &Scene, sink: impl FnMut(&Outputs)) -> Result<Report, SimError> {
    let (report, result) = simulate_partial(scene, sink);
    result.map(|()| report)
}

/// [`simulate`], which also reports a failed run: the counters up to the failure, and the
/// warning if one came first. A run that fails before its first step has zero counters.
pub fn simulate_partial(
    scene: &Scene,
    mut sink: impl FnMut(&Outputs),
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
        sink(&run.outputs_at(t)?);
        Ok(())
    };
    let result = drive(scene, &mut run, &mut emit);
    let warning = warning.or_else(|| run.take_warning());
    (Report { stats: run.stats(), warning }, result)
}

/// The law's φ, φ′, φ″ at t as a host sends them with `scene.phi_feed`.
fn host_sample(scene: &Scene, t: f64) -> Sample {
    match scene.phi_feed {
        PhiFeed::Derivatives => Sample::with_derivatives(t, scene.law.eval(t)),
        _ => Sample::value(t, scene.law.eval(t).phi),
    }
}

/// The run of `simulate` at t = 0, before its first step.
fn start(scene: &Scene) -> Result<Run, SimError> {
    let model = scene.validate()?;
    let (formulation, solver, init) = (scene.formulation, &scene.solver, scene.initial);
    let mut run = if scene.phi_feed == PhiFeed::Law {
        Run::with_law(model, formulation, solver, 0.0, init, scene.law)?
    } else {
        let signal = HostSignal::new(scene.phi_interpolation, scene.phi_extrapolation);
        Run::with_host(model, formulation, solver, 0.0, init, signal, host_sample(scene, 0.0))?
    };
    run.set_range_check(scene.range_check);
    Ok(run)
}

/// Steps `run` to t_end, calling `emit` at every output time.
fn drive(
    scene: &Scene,
    run: &mut Run,
    emit: &mut impl FnMut(&mut Run, f64) -> Result<(), SimError>,
) -> Result<(), SimError> {
    let outputs = scene.output_times();
    if scene.phi_feed == PhiFeed::Law {
        return run.step_to_sampling(scene.t_end, outputs, emit);
    }
    // As a host does: the law's value (and derivatives) at each communication point.
    let mut outputs = outputs.peekable();
    let comm: Vec<f64> = grid(scene.dt_comm, scene.t_end).collect();
    for w in comm.windows(2) {
        let (a, b) = (w[0], w[1]);
        run.set_sample(host_sample(scene, a));
        let mut times = Vec::new();
        while let Some(t) = outputs.next_if(|&t| t <= b) {
            times.push(t);
        }
        run.step_to_sampling(b, times, &mut *emit)?;
    }
    Ok(())
}

/// Where a run's φ comes from. The host's variant is the larger by 0.3 kB; a run holds
/// one, so boxing would only add an indirection to every piece.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhiInput {
    /// The paper's law; the integrator lands on its breakpoint t_rot and restarts there.
    Law(PaperLaw),
    /// A host's samples at the communication points ([`Run::set_sample`]).
    Host(HostSignal),
}

/// The integrator and the model for a formulation chosen at run time, with the φ input they
/// are driven by. The standalone driver ([`simulate`]) and the FMU both step through it
/// ([`step_to`](Self::step_to)), so they integrate the same way. `Clone` copies everything
/// (FMU state save and restore).
#[derive(Clone, Debug)]
pub struct Run {
    model: BeamBody,
    formulation: Formulation,
    input: PhiInput,
    /// The piece of φ in use: what the right-hand side evaluates.
    piece: PhiPiece,
    /// The host's sample at the current time, for the next step.
    sample: Option<Sample>,
    /// What to do when the state leaves the range of validity, as set, and now: `Warn`
    /// becomes `Off` once it has warned.
    range_set: RangeCheck,
    range: RangeCheck,
    /// The warning of `Warn`, until [`take_warning`](Self::take_warning).
    warning: Option<String>,
    /// Set by a new piece whose φ″ differs from the last one's at the join, until the next
    /// step: that step probes whether the history survives the change
    /// ([`Bdf::probe_step`]). Only within one [`step_to`](Self::step_to).
    untested_join: bool,
    bdf: Integrator,
}

/// Whether two times differ by no more than a few ulps: the round-off of a host's tc + h.
fn within_rounding(a: f64, b: f64) -> bool {
    (a - b).abs() <= 16.0 * f64::EPSILON * a.abs().max(b.abs())
}

/// [`Bdf::advance`], whose first step, with `probe`, is a [`Bdf::probe_step`]: the
/// integrator restarts at its time if the history did not survive a change of f there.
fn advance_probing<const N: usize, S: OdeSystem<N>>(
    bdf: &mut Bdf<N>,
    sys: &S,
    tout: f64,
    tstop: f64,
    probe: bool,
) -> Result<(), SolverError> {
    if probe && bdf.t() < tout && bdf.probe_step(sys, tstop)? == StepOutcome::Rejected {
        bdf.reinit(bdf.t(), *bdf.y())?;
    }
    bdf.advance(sys, tout, tstop)
}

fn two_dof(model: &BeamBody, phi: PhiPiece, formulation: Formulation) -> TwoDofSystem<'_> {
    TwoDofSystem { model, phi, linear: formulation == Formulation::Linear, range_check: true }
}

fn dae(model: &BeamBody, phi: PhiPiece, formulation: Formulation) -> DaeSystem<'_> {
    let stabilized = formulation == Formulation::DaeStabilized;
    DaeSystem { model, phi, stabilized, range_check: true }
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
    /// A run from `init` at `t0` driven by the law. The DAE's u2 and u̇2 start consistent.
    pub fn with_law(
        model: BeamBody,
        formulation: Formulation,
        options: &BdfConfig,
        t0: f64,
        init: InitialState,
        law: PaperLaw,
    ) -> Result<Self, SolverError> {
        Self::new(model, formulation, options, t0, init, PhiInput::Law(law), law.piece_from(t0))
    }

    /// A run from `init` at `t0` driven by a host, whose sample at t0 is `first`.
    pub fn with_host(
        model: BeamBody,
        formulation: Formulation,
        options: &BdfConfig,
        t0: f64,
        init: InitialState,
        mut signal: HostSignal,
        first: Sample,
    ) -> Result<Self, SolverError> {
        let piece = PhiPiece::Poly(signal.start(Sample { t: t0, ..first }));
        Self::new(model, formulation, options, t0, init, PhiInput::Host(signal), piece)
    }

    fn new(
        model: BeamBody,
        formulation: Formulation,
        options: &BdfConfig,
        t0: f64,
        init: InitialState,
        input: PhiInput,
        piece: PhiPiece,
    ) -> Result<Self, SolverError> {
        let bdf = if formulation.is_dae() {
            let free =
                SVector::<f64, 6>::new(init.v1, init.theta1, 0.0, init.dv1, init.dtheta1, 0.0);
            let y0 = dae(&model, piece, formulation).consistent(&free);
            Integrator::Dae(Bdf::new(*options, t0, y0)?)
        } else {
            let y0 = SVector::<f64, 4>::new(init.v1, init.theta1, init.dv1, init.dtheta1);
            Integrator::Two(Bdf::new(*options, t0, y0)?)
        };
        Ok(Self {
            model,
            formulation,
            input,
            piece,
            sample: None,
            range_set: RangeCheck::Stop,
            range: RangeCheck::Stop,
            warning: None,
            untested_join: false,
            bdf,
        })
    }

    pub fn model(&self) -> &BeamBody {
        &self.model
    }

    pub fn formulation(&self) -> Formulation {
        self.formulation
    }

    pub fn input(&self) -> &PhiInput {
        &self.input
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

    /// The host's φ (and the derivatives it sent) at the current time, for the next
    /// [`step_to`](Self::step_to); its time is taken as the run's. The law ignores it.
    pub fn set_sample(&mut self, sample: Sample) {
        self.sample = Some(Sample { t: self.t(), ..sample });
    }

    /// Steps to exactly `t`. See [`step_to_sampling`](Self::step_to_sampling).
    pub fn step_to(&mut self, t: f64) -> Result<(), SimError> {
        self.step_to_sampling(t, [], |_, _| Ok(()))
    }

    /// Steps to exactly `t`, calling `sink` at each of `times` (increasing, up to t) on the
    /// way, with the run stepped past it. With a host's input, a sample set since the last
    /// call gives the piece of φ for the whole interval to t; without one, the piece in use
    /// goes on. With the law, the integrator lands on its breakpoint and restarts there with
    /// the next piece, so f is never evaluated across the jump of φ''.
    ///
    /// On failure the run is at its last accepted step, with the piece it got there with,
    /// so its outputs there are valid (a host's signal keeps the sample it was given).
    pub fn step_to_sampling(
        &mut self,
        t: f64,
        times: impl IntoIterator<Item = f64>,
        mut sink: impl FnMut(&mut Run, f64) -> Result<(), SimError>,
    ) -> Result<(), SimError> {
        let (t0, piece) = (self.t(), self.piece);
        let result = self.begin(t).and_then(|()| {
            for tout in times {
                self.advance_to(tout.min(t), t)?;
                sink(self, tout)?;
            }
            Ok(self.advance_to(t, t)?)
        });
        if result.is_err() && self.t() <= t0 {
            self.piece = piece;
        }
        self.untested_join = false;
        result
    }

    /// Chooses the piece for the interval to `t` from a pending sample.
    fn begin(&mut self, t: f64) -> Result<(), SimError> {
        let now = self.t();
        let (PhiInput::Host(signal), Some(sample)) = (&mut self.input, self.sample.take()) else {
            return Ok(());
        };
        let current = self.piece.eval(now);
        let poly = signal.plan(sample, current, t - now).map_err(|e| {
            SimError::Setting(format!(
                "{e} (phi = {:?} at t = {now}, h = {:?})",
                sample.phi,
                t - now
            ))
        })?;
        self.switch_piece(PhiPiece::Poly(poly), current)?;
        Ok(())
    }

    /// Switches to `piece`. The integrator restarts where φ or φ′ jump at the current time
    /// (by more than round-off). Where only φ″ does, as at a C¹ join of a smooth input, it
    /// keeps its history, and the next step's first attempt tells whether the history
    /// survived the jump of f: if it fails its error test, the integrator restarts there
    /// ([`Bdf::probe_step`]). Kept across a large jump of f, the history made the error test
    /// fail repeatedly at tight tolerances (values every 8.5 ms failed at rtol 1e-10); a
    /// restart at every jump of φ″ cost 8,505 restarts at a 0.1 ms communication step.
    /// `old` is φ of the piece in use at the current time.
    fn switch_piece(&mut self, piece: PhiPiece, old: Phi) -> Result<(), SolverError> {
        let new = match piece {
            PhiPiece::Poly(p) if p.t0 == self.t() => p.at_start(),
            _ => piece.eval(self.t()),
        };
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0);
        self.piece = piece;
        if !(same(old.phi, new.phi) && same(old.dphi, new.dphi)) {
            self.restart()?;
        } else if !same(old.ddphi, new.ddphi) {
            self.untested_join = true;
        }
        Ok(())
    }

    /// Drops the integrator's step history: it goes on at order 1 from its state.
    fn restart(&mut self) -> Result<(), SolverError> {
        match &mut self.bdf {
            Integrator::Two(b) => b.reinit(b.t(), *b.y()),
            Integrator::Dae(b) => b.reinit(b.t(), *b.y()),
        }
    }

    fn two_dof(&self) -> TwoDofSystem<'_> {
        two_dof(&self.model, self.piece, self.formulation)
    }

    fn dae(&self) -> DaeSystem<'_> {
        dae(&self.model, self.piece, self.formulation)
    }

    /// Steps until t ≥ `tout`, never past `tstop`, through the law's breakpoint.
    fn advance_to(&mut self, tout: f64, tstop: f64) -> Result<(), SolverError> {
        // An output inside the last step takes no step: return before the breakpoint logic
        // and the solver's own checks, which would decide the same (at loose tolerances
        // there are more outputs than steps). Not while a join waits for its probing step.
        if tout <= self.t() && !self.untested_join && self.reaches_back_to(tout) {
            return Ok(());
        }
        let PhiInput::Law(law) = self.input else {
            return self.advance(tout, tstop);
        };
        let bp = law.breakpoint();
        // A stop within rounding of the breakpoint is the breakpoint (a host's tc + h), so the
        // integrator never takes a step of a few ulps after landing on it.
        let tstop = if within_rounding(tstop, bp) { bp } else { tstop };
        let tout = tout.min(tstop);
        loop {
            let turning = matches!(self.piece, PhiPiece::Turn(_));
            if turning && self.t() >= bp && tout > self.t() {
                self.piece = law.piece_from(bp);
                self.restart()?;
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

    /// Steps with the current piece until t ≥ `tout`, never past `tstop`
    /// ([`Bdf::advance`]). A `tout` within rounding of the solver's time takes no step. With
    /// `range_check = warn`, the first step out of the range of validity records a warning
    /// and the run goes on without the check.
    fn advance(&mut self, tout: f64, tstop: f64) -> Result<(), SolverError> {
        loop {
            if tout > self.t() && within_rounding(tout, self.t()) {
                return Ok(());
            }
            let (model, piece, formulation) = (&self.model, self.piece, self.formulation);
            let range_check = self.range != RangeCheck::Off;
            let probe = std::mem::take(&mut self.untested_join);
            let result = match &mut self.bdf {
                Integrator::Two(b) => {
                    let sys = TwoDofSystem { range_check, ..two_dof(model, piece, formulation) };
                    advance_probing(b, &sys, tout, tstop, probe)
                }
                Integrator::Dae(b) => {
                    let sys = DaeSystem { range_check, ..dae(model, piece, formulation) };
                    advance_probing(b, &sys, tout, tstop, probe)
                }
            };
            match result {
                Err(e @ SolverError::OutOfRange { .. }) if self.range == RangeCheck::Warn => {
                    self.warning = Some(format!(
                        "{e}; the run goes on outside the range of validity (range_check = warn)"
                    ));
                    self.range = RangeCheck::Off;
                }
                other => return other,
            }
        }
    }

    /// What to do when the state leaves the range of validity (default `Stop`).
    pub fn set_range_check(&mut self, range: RangeCheck) {
        self.range_set = range;
        self.range = range;
    }

    /// The warning of `range_check = warn`, once: `Some` after the step that left the range.
    pub fn take_warning(&mut self) -> Option<String> {
        self.warning.take()
    }

    /// Whether `t` is not behind the integrator's last step ([`Bdf::reaches_back_to`]).
    fn reaches_back_to(&self, t: f64) -> bool {
        match &self.bdf {
            Integrator::Two(b) => b.reaches_back_to(t),
            Integrator::Dae(b) => b.reaches_back_to(t),
        }
    }

    /// The outputs at `t` inside the last step (dense output), with the current piece.
    pub fn outputs_at(&self, t: f64) -> Result<Outputs, SolverError> {
        Ok(self.kinematics_at(t)?.outputs(&self.model))
    }

    /// The motion at `t` inside the last step (dense output): the outputs without the
    /// reactions and the energy, which follow from it.
    pub fn kinematics_at(&self, t: f64) -> Result<Kinematics, SolverError> {
        Ok(match &self.bdf {
            Integrator::Two(b) => self.two_dof().kinematics(t, &b.interpolate(t)?),
            Integrator::Dae(b) => self.dae().kinematics(t, &b.interpolate(t)?),
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

    /// Visits the run's state: the piece of φ in use, the host's signal and the integrator
    /// ([`Bdf::visit_state`]). The model, formulation, settings and law are the caller's to
    /// restore (by building the run from them first); [`check_state`](Self::check_state)
    /// then validates what a reader wrote.
    pub fn visit_state(&mut self, v: &mut impl StateVisitor) {
        let (mut kind, mut r) = match self.piece {
            PhiPiece::Turn(_) => (0u64, [0.0; 8]),
            PhiPiece::Hold(x) => (1, [x, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
            PhiPiece::Poly(p) => {
                let c = p.c;
                (2, [p.t0, p.h, c[0], c[1], c[2], c[3], c[4], c[5]])
            }
        };
        v.count("piece_kind", &mut kind);
        for x in r.iter_mut() {
            v.real("piece", x);
        }
        // The law's piece uses none of the reals, a held angle only the first: the others
        // are written as zeros and must read as zeros (one byte form per state).
        let used = [0, 1, 8].get(kind as usize).copied().unwrap_or(8);
        v.discarded("piece", r[used..].iter().all(|x| x.to_bits() == 0));
        self.piece = match (kind, self.input) {
            (0, PhiInput::Law(law)) => PhiPiece::Turn(law),
            (1, _) => PhiPiece::Hold(r[0]),
            (2, _) => {
                PhiPiece::Poly(Poly { t0: r[0], h: r[1], c: [r[2], r[3], r[4], r[5], r[6], r[7]] })
            }
            // Refused by `check_state`: a law's turn in a host-driven run, or a bad kind.
            _ => PhiPiece::Hold(f64::NAN),
        };
        if let PhiInput::Host(signal) = &mut self.input {
            signal.visit(v);
        }
        let mut warned = self.range != self.range_set;
        v.flag("range_warned", &mut warned);
        self.range = if warned { RangeCheck::Off } else { self.range_set };
        if warned && self.range_set != RangeCheck::Warn {
            // Refused by `check_state`.
            self.range_set = RangeCheck::Stop;
            self.range = RangeCheck::Warn;
        }
        match &mut self.bdf {
            Integrator::Two(b) => b.visit_state(v),
            Integrator::Dae(b) => b.visit_state(v),
        }
    }

    /// Checks a state written by a visitor: the piece (finite, and of a kind the input
    /// makes), the signal ([`HostSignal::check`]) and the integrator ([`Bdf::check_state`]).
    pub fn check_state(&self) -> Result<(), String> {
        let ok = match (self.piece, self.input) {
            (PhiPiece::Turn(_), PhiInput::Law(_)) => true,
            (PhiPiece::Hold(x), PhiInput::Law(_)) => x.is_finite(),
            (PhiPiece::Poly(p), PhiInput::Host(_)) => p.is_finite() && p.h > 0.0,
            _ => false,
        };
        if !ok {
            return Err("field `piece`: not a finite piece of φ that this input makes".into());
        }
        if let PhiInput::Host(signal) = &self.input {
            signal.check()?;
        }
        let range_ok = self.range == self.range_set
            || (self.range_set == RangeCheck::Warn && self.range == RangeCheck::Off);
        if !range_ok {
            return Err("field `range_warned`: set, but range_check is not warn".into());
        }
        match &self.bdf {
            Integrator::Two(b) => b.check_state(),
            Integrator::Dae(b) => b.check_state(),
        }
        .map_err(|e| e.to_string())
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
            let mut run =
                Run::with_law(model, formulation, &scene.solver, 0.0, scene.initial, law).unwrap();
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
