//! `Run`: the driver the CLI and the FMU both step. It holds the model, the formulation, the
//! integrator and the φ input, chooses the piece of φ for each step, lands exactly on the
//! times asked, and restarts the integrator where φ'' jumps.
#![forbid(unsafe_code)]

use super::balance::EnergyMonitor;
use super::stepper::{Integration, Start, Stepping};
use super::{theory, SimError};
use crate::math;
use crate::model::{
    BeamBody, Energy, Formulation, HostSignal, Kinematics, Outputs, PaperLaw, Phi, PhiPiece, Poly,
    RangeCheck, Sample,
};
use crate::scene::{PhiSource, Scene};
#[cfg(doc)]
use crate::solver::{Bdf, BdfConfig};
use crate::solver::{RangeViolation, SolverError, Stats};
use crate::visit::StateVisitor;

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

/// The integrator and the theory a scene chose at run time, with the φ input they are driven
/// by. The standalone driver ([`simulate`](super::simulate)) and the FMU both step through it
/// ([`step_to`](Self::step_to)), so they integrate the same way. `Clone` copies everything
/// (FMU state save and restore).
#[derive(Clone, Debug)]
pub struct Run {
    /// The paper's model of the same parameters: the body, which the outputs' reactions
    /// follow from, whatever the theory.
    model: BeamBody,
    formulation: Formulation,
    input: PhiInput,
    /// The piece of φ in use: what the right-hand side evaluates.
    piece: PhiPiece,
    /// The host's sample at the current time, for the next step.
    sample: Option<Sample>,
    /// The next interval goes on from the samples held, with no new one
    /// ([`hold_sample`](Self::hold_sample)). Not part of the run's state: it is set and used
    /// within one call of the host.
    extend: bool,
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
    /// Within [`step_each`](Self::step_each): each advance takes one integrator step.
    single_step: bool,
    /// The integrator's step limit per call ([`BdfConfig::max_steps`]), which
    /// [`step_each`](Self::step_each) applies to its own calls.
    max_steps: u64,
    /// The energy check after every step (`energy_check`); `None` when it is off.
    energy: Option<EnergyMonitor>,
    /// The scene's beam theory and its integrator.
    bdf: Box<dyn Integration>,
}

impl Run {
    /// The run of `scene` from `t0`, before its first step: the one way the CLI and the FMU
    /// start one. With `phi_source = input`, `first` is the host's sample at t0 (the law
    /// ignores it). At most `max_steps` steps per call of [`step_to`](Self::step_to).
    pub fn start(scene: &Scene, t0: f64, first: Sample, max_steps: u64) -> Result<Run, SimError> {
        let (input, law) = (scene.phi_source == PhiSource::Input, scene.law);
        let phi0 = if input { first.phi } else { law.eval(t0).phi };
        let model = scene.check_model(phi0).map_err(SimError::Setting)?;
        let (input, piece) = if input {
            let mut signal = HostSignal::new(scene.phi_interpolation, scene.phi_extrapolation);
            let piece = PhiPiece::Poly(signal.start(Sample { t: t0, ..first }));
            (PhiInput::Host(signal), piece)
        } else {
            (PhiInput::Law(law), law.piece_from(t0))
        };
        let config = scene.solver_config(max_steps);
        let start = Start { piece, init: scene.initial, config: &config, t0 };
        let bdf = theory::build(scene, model, start)??;
        let mut run = Run {
            model,
            formulation: scene.formulation,
            input,
            piece,
            sample: None,
            extend: false,
            range_set: scene.range_check,
            range: scene.range_check,
            warning: None,
            untested_join: false,
            single_step: false,
            max_steps: config.max_steps,
            energy: None,
            bdf,
        };
        if scene.energy_check != RangeCheck::Off {
            let rtol = (config.fixed_step.is_none()).then_some(config.rtol);
            let e = run.energy_now();
            run.energy = Some(EnergyMonitor::new(scene.energy_check, rtol, t0, e));
        }
        Ok(run)
    }

    /// The energy check's part of the last step, which ended in an error that did not stop the
    /// run (the range left with `range_check = warn`).
    fn monitor_last_step(&mut self) -> Result<(), SimError> {
        self.bdf.monitor_last_step(self.piece, &mut self.energy)
    }

    /// The energy at the solver's last step, with the piece in use.
    fn energy_now(&self) -> Energy {
        self.bdf.energy(self.piece)
    }

    /// Switches to `piece` at the current time, for the energy check too: where φ or φ′
    /// `jumped`, the energy there under the old piece and the new ([`EnergyMonitor::jump`]).
    fn set_piece(&mut self, piece: PhiPiece, jumped: bool) -> Result<(), SimError> {
        let active = self.energy.as_ref().is_some_and(EnergyMonitor::active);
        let before = (active && jumped).then(|| self.energy_now());
        self.piece = piece;
        if let Some(before) = before {
            let after = self.energy_now();
            let m = self.energy.as_mut().expect("active");
            m.jump(before, after).map_err(SimError::Unstable)?;
        }
        Ok(())
    }

    /// The largest error of the energy balance so far relative to the energy the run has
    /// handled; `None` when the check is off.
    pub fn energy_worst(&self) -> Option<f64> {
        self.energy.as_ref().map(EnergyMonitor::worst)
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
        self.bdf.t()
    }

    /// The number of the integrator's states: 4 or 6 for the paper's model, 4n or 4n + 2
    /// for n elements.
    pub fn dimension(&self) -> usize {
        self.bdf.dimension()
    }

    /// The piece of φ in use.
    pub fn piece(&self) -> PhiPiece {
        self.piece
    }

    /// The most steps one call of [`step_to`](Self::step_to) (or its like) takes from now on:
    /// what is left of a budget shared by several calls (at least 1).
    pub fn set_max_steps(&mut self, max_steps: u64) {
        self.max_steps = max_steps.max(1);
        self.bdf.set_max_steps(max_steps);
    }

    pub fn stats(&self) -> Stats {
        self.bdf.stats()
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

    /// Steps until the run reaches `t`, never past `tstop` (`f64::INFINITY`: no stop): the
    /// integrator takes its own steps, as the CLI's run does, and its dense output
    /// ([`kinematics_at`](Self::kinematics_at)) gives the values at `t`. A `t` inside the
    /// last step takes no step. Only for an input known ahead: the law (with a host's input,
    /// the piece beyond `t` is not known yet, and [`step_to`](Self::step_to) lands on `t`).
    pub fn step_past(&mut self, t: f64, tstop: f64) -> Result<(), SimError> {
        debug_assert!(matches!(self.input, PhiInput::Law(_)), "the law's input is known ahead");
        self.interval(t, |run| run.advance_to(t, tstop))
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
        self.interval(t, |run| {
            for tout in times {
                run.advance_to(tout.min(t), t)?;
                sink(run, tout)?;
            }
            run.advance_to(t, t)
        })
    }

    /// An interval to `t` of [`step_to_sampling`](Self::step_to_sampling) or
    /// [`step_each`](Self::step_each): the piece from a pending sample, `body`'s steps, and on
    /// a failure before the first step, the piece the run had.
    fn interval(
        &mut self,
        t: f64,
        body: impl FnOnce(&mut Run) -> Result<(), SimError>,
    ) -> Result<(), SimError> {
        let (t0, piece) = (self.t(), self.piece);
        let result = self.begin(t).and_then(|()| body(self));
        if result.is_err() && self.t() <= t0 {
            self.piece = piece;
        }
        self.untested_join = false;
        result
    }

    /// Steps to `t` as [`step_to_sampling`](Self::step_to_sampling) does, calling `sink`
    /// after every integrator step with the time the step started from: the step's dense
    /// output ([`outputs_at`](Self::outputs_at)) then covers [that time, [`t`](Self::t)], and
    /// the steps tile the interval without a gap. For what a grid would miss: the extrema of
    /// an output between the grid's points (a study's peaks).
    pub fn step_each(
        &mut self,
        t: f64,
        mut sink: impl FnMut(&mut Run, f64) -> Result<(), SimError>,
    ) -> Result<(), SimError> {
        self.interval(t, |run| {
            // As `Bdf::advance` does, at most max_steps steps a call; a call that takes no
            // step (a restart at the law's breakpoint) counts too, so the loop always ends.
            let mut calls = 0u64;
            while run.t() < t && !math::same_time(run.t(), t, 0.0) {
                if calls == run.max_steps {
                    let max_steps = run.max_steps;
                    return Err(SolverError::TooManySteps { t: run.t(), max_steps }.into());
                }
                calls += 1;
                let before = run.t();
                run.single_step = true;
                let stepped = run.advance_to(t, t);
                run.single_step = false;
                stepped?;
                if run.t() > before {
                    sink(run, before)?;
                }
            }
            Ok(())
        })
    }

    /// The host gave no sample at the current time though asked for one (FMI 3.0's
    /// intermediate update): the next interval's piece of φ extends the samples held
    /// ([`HostSignal::extend`]).
    pub fn hold_sample(&mut self) {
        self.sample = None;
        self.extend = true;
    }

    /// Chooses the piece for the interval to `t` from a pending sample.
    fn begin(&mut self, t: f64) -> Result<(), SimError> {
        let now = self.t();
        if std::mem::take(&mut self.extend) {
            if let PhiInput::Host(signal) = &self.input {
                let current = self.piece.eval(now);
                let poly = signal.extend(current, now, t - now).map_err(|e| {
                    SimError::Setting(format!("{e} (extended from t = {now} to {t})"))
                })?;
                self.switch_piece(PhiPiece::Poly(poly), current)?;
            }
            return Ok(());
        }
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
    fn switch_piece(&mut self, piece: PhiPiece, old: Phi) -> Result<(), SimError> {
        let new = match piece {
            PhiPiece::Poly(p) if p.t0 == self.t() => p.at_start(),
            _ => piece.eval(self.t()),
        };
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0);
        let jumped = !(same(old.phi, new.phi) && same(old.dphi, new.dphi));
        self.set_piece(piece, jumped)?;
        if jumped {
            self.restart()?;
        } else if !same(old.ddphi, new.ddphi) {
            self.untested_join = true;
        }
        Ok(())
    }

    /// Drops the integrator's step history: it goes on at order 1 from its state.
    fn restart(&mut self) -> Result<(), SolverError> {
        self.bdf.restart()
    }

    /// Steps until t ≥ `tout`, never past `tstop`, through the law's breakpoint.
    fn advance_to(&mut self, tout: f64, tstop: f64) -> Result<(), SimError> {
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
        let tstop = if math::same_time(tstop, bp, 0.0) { bp } else { tstop };
        let tout = tout.min(tstop);
        loop {
            let turning = matches!(self.piece, PhiPiece::Turn(_));
            if turning && self.t() >= bp && tout > self.t() {
                // The law is C¹ at its end: φ and φ′ go on, φ″ jumps.
                self.set_piece(law.piece_from(bp), false)?;
                self.restart()?;
                continue;
            }
            if turning && tout > bp && tstop > bp {
                self.advance(bp, bp)?;
                if self.single_step {
                    return Ok(());
                }
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
    fn advance(&mut self, tout: f64, tstop: f64) -> Result<(), SimError> {
        loop {
            if tout > self.t() && math::same_time(tout, self.t(), 0.0) {
                return Ok(());
            }
            let range_check = self.range != RangeCheck::Off;
            let probe = std::mem::take(&mut self.untested_join);
            let (single, before) = (self.single_step, self.t());
            let step = Stepping { probe, single };
            let times = (tout, tstop);
            let result = self.bdf.advance(self.piece, range_check, times, step, &mut self.energy);
            match result {
                Err(SimError::Solver(e @ SolverError::OutOfRange { .. }))
                    if self.range == RangeCheck::Warn =>
                {
                    self.warning = Some(format!(
                        "{e}; the run goes on outside the range of validity (range_check = warn)"
                    ));
                    self.range = RangeCheck::Off;
                    // The step that left the range stands, and its work counts.
                    self.monitor_last_step()?;
                    // In single steps, it is the one.
                    if single && self.t() > before {
                        return Ok(());
                    }
                }
                other => return other,
            }
        }
    }

    /// Whether the state at the end of the last accepted step is outside the range of
    /// validity: the error the integrator gave when that step left it, made again from the
    /// same step (after an FMU state was restored, say).
    pub fn range_violation(&self) -> Option<SolverError> {
        let t = self.t();
        let checked = self.bdf.check_range(self.piece);
        checked.err().map(|RangeViolation { name, value, allowed }| SolverError::OutOfRange {
            t,
            name,
            value,
            allowed,
        })
    }

    /// What to do when the state leaves the range of validity (default `Stop`).
    pub fn set_range_check(&mut self, range: RangeCheck) {
        self.range_set = range;
        self.range = range;
    }

    /// The warning of `range_check = warn` or `energy_check = warn`, once: `Some` after the
    /// step that left the range or broke the balance.
    pub fn take_warning(&mut self) -> Option<String> {
        let energy = self.energy.as_mut().and_then(EnergyMonitor::take_warning);
        self.warning.take().or(energy)
    }

    /// Why the run stopped at its last accepted step, made again from that step (after an FMU
    /// state was restored, say): the state outside the range of validity, or the energy
    /// balance broken.
    pub fn exit_reason(&self) -> Option<String> {
        let range = self.range_violation().map(|e| SimError::Solver(e).to_string());
        range.or_else(|| Some(SimError::Unstable(self.energy.as_ref()?.violation()?).to_string()))
    }

    /// Whether `t` is not behind the integrator's last step ([`Bdf::reaches_back_to`]).
    pub fn reaches_back_to(&self, t: f64) -> bool {
        self.bdf.reaches_back_to(t)
    }

    /// The outputs at `t` inside the last step (dense output), with the current piece.
    pub fn outputs_at(&self, t: f64) -> Result<Outputs, SolverError> {
        Ok(self.kinematics_at(t)?.outputs(&self.model))
    }

    /// The motion at `t` inside the last step (dense output): the outputs without the
    /// reactions and the energy, which follow from it.
    pub fn kinematics_at(&self, t: f64) -> Result<Kinematics, SolverError> {
        self.bdf.kinematics_at(self.piece, t)
    }

    /// The state at `t` inside the last step (dense output) into `out`: (v1, ϑ1, v̇1, ϑ̇1),
    /// or (v1, ϑ1, u2, v̇1, ϑ̇1, u̇2) for the DAE formulations (projected when stabilised, as
    /// the outputs are); for n elements, the tip's four in any formulation. Returns the number
    /// of states written. Cheaper than
    /// [`outputs_at`](Self::outputs_at), which also computes accelerations, reactions and
    /// energy; the benchmark records this, as the other solvers record their states.
    pub fn state_at(&self, t: f64, out: &mut [f64; 6]) -> Result<usize, SolverError> {
        self.bdf.record_at(self.piece, t, out)
    }

    /// The beam's generalized coordinates q, their rates q̇ and accelerations q̈ at `t` inside
    /// the last step (dense output), each in `out` in turn: Model Exchange's states and their
    /// derivatives. The paper's two coordinates (v1, ϑ1) in every formulation (a DAE's own
    /// state has u2 besides); every node's for n elements.
    pub fn motion_at(&self, t: f64, out: &mut Vec<f64>) -> Result<(), SolverError> {
        self.bdf.motion_at(self.piece, t, out)
    }

    /// The coordinates q at `t` inside the last step (dense output) into `out`: every node's
    /// (v_k, ϑ_k), k = 1..n, the tip last
    /// ([`Theory::nodal_shape`](super::theory::Theory::nodal_shape)); (v1, ϑ1) for the
    /// paper's model.
    pub fn coordinates_at(&self, t: f64, out: &mut Vec<f64>) -> Result<(), SolverError> {
        out.clear();
        out.extend(self.bdf.nodal_shape_at(t)?);
        Ok(())
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
        if let Some(m) = &mut self.energy {
            m.visit_state(v);
        }
        self.bdf.visit_state(v);
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
        if let Some(m) = &self.energy {
            m.check_state()?;
        }
        self.bdf.check_state().map_err(|e| e.to_string())
    }
}
