//! The run's energy check: after every accepted step, the energy's change against the work of
//! the drive and of the damping, so that a run that has gone numerically unstable stops saying
//! so instead of returning a trajectory with exit 0.
//!
//! The balance holds exactly for the equations integrated ([`crate::model::EnergyBalance`]);
//! what breaks it is the integration. An undamped beam's highest element modes, set ringing by
//! the jumps of φ″, sit where BDF3–5 amplify them at loose tolerances
//! (shared/numerics-notes.md): their energy grows without bound while every error test
//! passes. The residual r = E(t) − E(t0) − W + D, with W the drive's work and D the energy
//! damped, is checked against a bound scaled by the tolerance and by the energy the run has
//! handled (the largest sum of the energy's parts seen, plus ∫|P_drive| dt and D).
//!
//! The powers are integrated over each step by the two-point Gauss–Legendre rule (order 4) on
//! the integrator's dense output, whose derivative gives the accelerations there. A rule
//! through the steps' own end points does worse: the quadratic through three lost 5e-6 of the
//! drive's work on the paper's scene at rtol 1e-10, and the quartic through five, across a
//! step 150 times longer than the next, 0.6 J of 150.
#![forbid(unsafe_code)]

use crate::model::{Energy, Power, RangeCheck};
use crate::visit::StateVisitor;
use std::fmt;

/// The bound on |r| relative to the energy scale: rtol·(`RTOL_FACTOR` + the steps taken), at
/// most `MAX_RELATIVE` (and that with a fixed step, whose accuracy the user chose). Each step
/// may add an error of the order of rtol to the energy; they add up in a long run (a stable
/// integration's energy drifts linearly: 3e-6 rtol a step on the paper's scene at rtol 1e-6),
/// while an instability grows geometrically and crosses any such bound within tens of steps.
/// Measured over the scenes of docs/model_error.md, 1 to 8 elements, both beams, every
/// formulation and rtol from 1e-2 to 1e-10 (docs/stability.md, "The energy check").
pub const RTOL_FACTOR: f64 = 100.0;
pub const MAX_RELATIVE: f64 = 0.1;
/// The balance is checked every this many steps (and the energy computed): the powers are
/// integrated at every step, but the energy costs up to a right-hand side (the exact beam's
/// sweep along the centreline), and an instability grows over tens of steps.
pub const CHECK_EVERY: u64 = 8;
/// The two-point Gauss–Legendre rule on a step [t0, t0 + h]: the points at t0 + h(½ ∓ 1/(2√3)),
/// each of weight h/2 (Abramowitz & Stegun, Table 25.4).
pub const GAUSS_2: [f64; 2] = [0.211_324_865_405_187_1, 0.788_675_134_594_812_9];

/// The running energy balance of a run ([module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct EnergyMonitor {
    /// The setting `energy_check`: `Stop`, `Warn` or `Off`.
    set: RangeCheck,
    /// What it does now: `Warn` becomes `Off` once it has warned.
    check: RangeCheck,
    /// rtol, or `None` with a fixed step.
    rtol: Option<f64>,
    /// The steps integrated.
    steps: u64,
    /// The time of the last step's end.
    t: f64,
    /// The energy at the start, the drive's work since (with the jumps of E where φ or φ′
    /// jumped), and the energy damped.
    start: f64,
    work: f64,
    damped: f64,
    /// ∫|P_drive| dt, and the largest sum of the energy's parts seen.
    throughput: f64,
    largest: f64,
    /// The energy at the last check.
    energy: f64,
    /// The largest |r| relative to the energy scale seen, for the run's summary.
    worst: f64,
    /// A warning of `Warn`, until taken.
    warning: Option<String>,
}

/// A broken energy balance: the run can no longer vouch for its trajectory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unstable {
    pub t: f64,
    /// E(t) − E(t0), W − D, and the bound on their difference [J].
    pub change: f64,
    pub accounted: f64,
    pub bound: f64,
}

impl fmt::Display for Unstable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "numerical instability at t = {}: the energy balance is broken (the energy changed \
             by {:+.4e} J since the start, but the drive's work and the damping account for \
             {:+.4e} J; the difference may be at most {:.3e} J at this tolerance): the \
             integrator's error is not under control (an unstable integration, or a tolerance too \
             loose for this run), and the trajectory cannot be trusted. Ways out: a tighter rtol, \
             integrator = radau (L-stable: it damps the modes it does not resolve), max_order = \
             2 (BDF2 does too), or damping of the beam (damping_ratio = 0.01); energy_check = \
             warn keeps the run going",
            self.t, self.change, self.accounted, self.bound
        )
    }
}

impl EnergyMonitor {
    /// The monitor of a run at `t0` whose energy there is `e`. `rtol` of an adaptive run, or
    /// `None` with a fixed step.
    pub fn new(check: RangeCheck, rtol: Option<f64>, t0: f64, e: Energy) -> Self {
        Self {
            set: check,
            check,
            rtol,
            steps: 0,
            t: t0,
            start: e.energy,
            work: 0.0,
            damped: 0.0,
            throughput: 0.0,
            largest: e.scale,
            energy: e.energy,
            worst: 0.0,
            warning: None,
        }
    }

    /// The bound on |r| relative to the energy scale now.
    fn relative(&self) -> f64 {
        let r = self.rtol.map_or(MAX_RELATIVE, |r| r * (RTOL_FACTOR + self.steps as f64));
        r.min(MAX_RELATIVE)
    }

    /// The residual r and the energy scale now.
    fn residual(&self) -> (f64, f64) {
        let r = self.energy - self.start - self.work + self.damped;
        (r, self.largest + self.throughput + self.damped)
    }

    /// Whether the monitor checks anything (not `Off`, nor `Warn` after its warning).
    pub fn active(&self) -> bool {
        self.check != RangeCheck::Off
    }

    /// A step to `t` of length `h`, with the powers `p` at its two Gauss points ([`GAUSS_2`]).
    /// Returns whether the balance is due to be checked ([`check`](Self::check)).
    pub fn step(&mut self, t: f64, h: f64, p: [Power; 2]) -> bool {
        if !self.active() {
            return false;
        }
        self.steps += 1;
        self.t = t;
        let w = 0.5 * h;
        self.work += w * (p[0].drive + p[1].drive);
        self.throughput += w * (p[0].drive.abs() + p[1].drive.abs());
        self.damped += w * (p[0].dissipation + p[1].dissipation);
        self.steps % CHECK_EVERY == 0
    }

    /// The energy `e` at the last step's end: the check.
    pub fn check(&mut self, e: Energy) -> Result<(), Unstable> {
        if !self.active() {
            return Ok(());
        }
        self.largest = self.largest.max(e.scale);
        self.energy = e.energy;
        let (r, scale) = self.residual();
        let bound = self.relative() * scale;
        self.worst = self.worst.max(r.abs() / scale);
        // NaN fails too.
        if r.abs() <= bound {
            return Ok(());
        }
        let unstable = self.unstable(bound);
        if self.check == RangeCheck::Warn {
            self.warning = Some(format!("{unstable}; the run goes on (energy_check = warn)"));
            self.check = RangeCheck::Off;
            return Ok(());
        }
        Err(unstable)
    }

    fn unstable(&self, bound: f64) -> Unstable {
        let (change, accounted) = (self.energy - self.start, self.work - self.damped);
        Unstable { t: self.t, change, accounted, bound }
    }

    /// φ or φ′ jumped at the current time: the energy there under the old piece and the new,
    /// whose difference is the drive's impulsive work. The check follows.
    pub fn jump(&mut self, before: Energy, after: Energy) -> Result<(), Unstable> {
        if !self.active() {
            return Ok(());
        }
        self.check(before)?;
        self.work += after.energy - before.energy;
        self.check(after)
    }

    /// The error of the balance now, if it is broken (a restored state's, say).
    pub fn violation(&self) -> Option<Unstable> {
        let (r, scale) = self.residual();
        let bound = self.relative() * scale;
        let broken = r.abs() > bound || r.is_nan();
        (self.check == RangeCheck::Stop && broken).then(|| self.unstable(bound))
    }

    /// The largest |r| seen relative to the energy scale.
    pub fn worst(&self) -> f64 {
        self.worst
    }

    /// The warning of `Warn`, once.
    pub fn take_warning(&mut self) -> Option<String> {
        self.warning.take()
    }

    /// Visits the monitor's state; `check_state` judges what a reader wrote. The setting and
    /// the bound are the settings' (a reader builds the monitor from them first).
    pub fn visit_state(&mut self, v: &mut impl StateVisitor) {
        let mut warned = self.check != self.set;
        v.flag("energy_warned", &mut warned);
        // Off after a warning; a warning under another setting is refused by `check_state`.
        self.check = if warned { RangeCheck::Off } else { self.set };
        self.warning = None;
        v.count("energy_steps", &mut self.steps);
        for (name, x) in [
            ("energy_t", &mut self.t),
            ("energy_start", &mut self.start),
            ("energy_work", &mut self.work),
            ("energy_damped", &mut self.damped),
            ("energy_throughput", &mut self.throughput),
            ("energy_largest", &mut self.largest),
            ("energy", &mut self.energy),
            ("energy_worst", &mut self.worst),
        ] {
            v.real(name, x);
        }
    }

    /// Checks a state written by a visitor: a warning only under `warn`, finite fields, sums of
    /// magnitudes not negative.
    pub fn check_state(&self) -> Result<(), String> {
        if self.check != self.set && self.set != RangeCheck::Warn {
            return Err("field `energy_warned`: set, but energy_check is not warn".into());
        }
        let fields = [
            self.t,
            self.start,
            self.work,
            self.damped,
            self.throughput,
            self.largest,
            self.energy,
            self.worst,
        ];
        if !fields.iter().all(|x| x.is_finite()) {
            return Err("field `energy…`: not a finite number".into());
        }
        if self.damped < 0.0 || self.throughput < 0.0 || self.largest < 0.0 || self.worst < 0.0 {
            return Err("field `energy…`: a sum of magnitudes is negative".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two-point rule integrates cubics exactly.
    #[test]
    fn the_gauss_rule_is_exact_for_cubics() {
        let f = |t: f64| 3.0 - 2.0 * t + 5.0 * t * t - 4.0 * t * t * t;
        let prim = |t: f64| 3.0 * t - t * t + 5.0 * t * t * t / 3.0 - t * t * t * t;
        let (t0, h) = (0.3, 0.7);
        let q = 0.5 * h * GAUSS_2.iter().map(|c| f(t0 + c * h)).sum::<f64>();
        assert!((q - (prim(t0 + h) - prim(t0))).abs() < 1e-14);
    }

    fn power(drive: f64) -> [Power; 2] {
        [Power { drive, dissipation: 0.0 }; 2]
    }

    fn energy(energy: f64) -> Energy {
        Energy { energy, scale: 100.0 }
    }

    /// A constant power's work balances a linear rise of the energy; a jump of the energy
    /// where φ jumps counts as work; a rise that nothing accounts for fails, naming the time, or
    /// warns once with `Warn`.
    #[test]
    fn work_balances_energy_and_a_gain_from_nowhere_fails() {
        let mut m = EnergyMonitor::new(RangeCheck::Stop, Some(1e-6), 0.0, energy(10.0));
        for k in 1..=10 {
            let t = 0.1 * k as f64;
            m.step(t, 0.1, power(2.0));
            m.check(energy(10.0 + 2.0 * t)).unwrap();
        }
        m.jump(energy(12.0), energy(20.0)).unwrap();
        m.step(1.1, 0.1, power(2.0));
        m.check(energy(20.2)).unwrap();
        assert!(m.worst() < 1e-12);
        m.step(1.2, 0.1, power(2.0));
        let err = m.check(energy(20.5)).unwrap_err();
        assert_eq!(err.t, 1.2);
        assert!(err.to_string().contains("numerical instability at t = 1.2"), "{err}");
        assert!(m.violation().is_some());

        let mut w = EnergyMonitor::new(RangeCheck::Warn, Some(1e-6), 0.0, energy(10.0));
        w.step(0.1, 0.1, power(0.0));
        w.check(energy(11.0)).unwrap();
        assert!(w.take_warning().unwrap().contains("energy_check = warn"));
        assert!(!w.active());
        w.step(0.2, 0.1, power(0.0));
        w.check(energy(50.0)).unwrap();
        assert!(w.take_warning().is_none());
    }

    /// The balance is due every CHECK_EVERY steps.
    #[test]
    fn a_check_is_due_every_few_steps() {
        let mut m = EnergyMonitor::new(RangeCheck::Stop, Some(1e-6), 0.0, energy(1.0));
        let due: Vec<u64> = (1..=20).filter(|&k| m.step(k as f64, 1.0, power(0.0))).collect();
        assert_eq!(due, [CHECK_EVERY, 2 * CHECK_EVERY]);
    }

    /// The bound: rtol (100 + the steps) of the scale, at most a tenth of it, and that with a
    /// fixed step.
    #[test]
    fn the_bound_scales_with_the_tolerance() {
        let m = |rtol| EnergyMonitor::new(RangeCheck::Stop, rtol, 0.0, energy(1.0));
        assert!((m(Some(1e-6)).relative() - 1e-4).abs() < 1e-18);
        let mut after = m(Some(1e-6));
        for k in 1..=900 {
            after.step(k as f64, 1.0, power(0.0));
        }
        assert!((after.relative() - 1e-3).abs() < 1e-15);
        assert_eq!(m(Some(1e-2)).relative(), 0.1);
        assert_eq!(m(None).relative(), 0.1);
    }
}
