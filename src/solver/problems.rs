//! A test problem for the stability guard, shared by the integrator's tests and by the
//! sweep (`cargo xtask sweep --group "guard, test problem"`): the trap of BDF3–5 near the
//! imaginary axis (numerics-notes.md), in its simplest form.

use super::{Bdf, BdfConfig, OdeSystem, SolverError, Stats};
use crate::math;
use nalgebra::{SMatrix, SVector, U4};

/// A slow motion and an undamped fast oscillator whose amplitude (1e-9) lies below the
/// absolute tolerance, so the error controller does not resolve it.
///
/// y = (y0, y1, y2, y3): the fast oscillator is y1'' = −ω²y1 (y3 = y1'). The slow motion is
/// either a first-order lag driven at unit frequency, y0' = −(y0 − sin t)/2, whose Jacobian
/// eigenvalue −1/2 is real (`slow_oscillates = false`), or a second undamped oscillator of
/// unit frequency (y0'' = −y0, y2 = y0').
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlowAndFast {
    /// The fast oscillator's angular frequency ω.
    pub fast: f64,
    pub slow_oscillates: bool,
}

impl OdeSystem<U4> for SlowAndFast {
    fn rhs(&self, t: f64, y: &SVector<f64, 4>) -> SVector<f64, 4> {
        let (slow0, slow2) =
            if self.slow_oscillates { (y[2], -y[0]) } else { (-0.5 * (y[0] - math::sin(t)), 0.0) };
        SVector::<f64, 4>::new(slow0, y[3], slow2, -self.fast * self.fast * y[1])
    }

    fn jacobian(&self, _t: f64, _y: &SVector<f64, 4>) -> Option<SMatrix<f64, 4, 4>> {
        let mut j = SMatrix::<f64, 4, 4>::zeros();
        if self.slow_oscillates {
            j[(0, 2)] = 1.0;
            j[(2, 0)] = -1.0;
        } else {
            j[(0, 0)] = -0.5;
        }
        j[(1, 3)] = 1.0;
        j[(3, 1)] = -self.fast * self.fast;
        Some(j)
    }
}

/// The outcome of [`SlowAndFast::run`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlowAndFastRun {
    /// The largest amplitude of the fast oscillator over all accepted steps (initially 1e-9).
    pub fast_amplitude: f64,
    /// |y0 − exact| at the end.
    pub slow_error: f64,
    pub stats: Stats,
}

impl SlowAndFast {
    /// The initial state: the slow motion at rest (the lag) or at y0 = 1 (the oscillator),
    /// the fast one displaced by 1e-9.
    pub fn initial(&self) -> SVector<f64, 4> {
        SVector::<f64, 4>::new(if self.slow_oscillates { 1.0 } else { 0.0 }, 1e-9, 0.0, 0.0)
    }

    /// The exact slow component: cos t, or the lag's solution from rest,
    /// (sin t − 2 cos t + 2 e^(−t/2))/5.
    pub fn slow_exact(&self, t: f64) -> f64 {
        if self.slow_oscillates {
            math::cos(t)
        } else {
            (math::sin(t) - 2.0 * math::cos(t) + 2.0 * math::exp(-0.5 * t)) / 5.0
        }
    }

    /// Runs from [`initial`](Self::initial) at t = 0 to `t_end` with rtol `rtol`, atol 1e-6
    /// on every component, and the guard on or off.
    pub fn run(&self, rtol: f64, guard: bool, t_end: f64) -> Result<SlowAndFastRun, SolverError> {
        let mut cfg = BdfConfig::new(rtol);
        cfg.atol = Some(1e-6);
        cfg.stability_guard = guard;
        let mut s = Bdf::new(cfg, 0.0, self.initial())?;
        let mut amp: f64 = 0.0;
        while s.t() < t_end {
            s.step(self, t_end)?;
            s.check_state()?;
            let y = s.y();
            amp = amp.max((y[1] * y[1] + math::powi(y[3] / self.fast, 2)).sqrt());
        }
        Ok(SlowAndFastRun {
            fast_amplitude: amp,
            slow_error: (s.y()[0] - self.slow_exact(t_end)).abs(),
            stats: *s.stats(),
        })
    }
}
