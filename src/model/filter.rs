//! φ, φ′ and φ″ from φ alone, for a host that sends only the angle (Model Exchange): the
//! filter of Modelica's `Rotational.Sources.Position` with `exact = false`.
//!
//! The input φ_in passes the second-order Bessel low-pass filter 1/(1 + (a/ω)s + (b/ω²)s²),
//! ω = 2π f_crit, a = 1.3617, b = 0.6180 (Modelica Standard Library,
//! `Modelica.Mechanics.Rotational.Sources.Position`): its states are the angle and the rate
//! the body is driven with, and φ″ = ((φ_in − φ)ω − a φ′)·ω/b. Its step response overshoots by
//! 0.4 %, and it delays a slow input by a/ω (43 ms at 5 Hz) with little distortion (a Bessel
//! filter's delay is nearly the same at every frequency it passes).
#![forbid(unsafe_code)]

use super::phi::Phi;

/// The coefficients of s and s² of Modelica's Bessel filter.
const A: f64 = 1.3617;
const B: f64 = 0.6180;

/// The filter at a cut-off frequency.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhiFilter {
    /// ω = 2π f_crit [rad/s].
    w: f64,
}

impl PhiFilter {
    /// Its states: the filtered φ and φ′.
    pub const STATES: usize = 2;

    /// The filter of cut-off frequency `f_crit` [Hz] (positive and finite).
    pub fn new(f_crit: f64) -> Self {
        Self { w: 2.0 * std::f64::consts::PI * f_crit }
    }

    /// The filtered φ, φ′, φ″ at the filter's state (φ, φ′) for the input `input`: the
    /// state's derivative is (φ′, φ″).
    pub fn phi(&self, input: f64, state: [f64; Self::STATES]) -> Phi {
        let ddphi = ((input - state[0]) * self.w - A * state[1]) * (self.w / B);
        Phi { phi: state[0], dphi: state[1], ddphi }
    }

    /// Its state at rest at `phi` (Modelica's initial equation).
    pub fn at_rest(phi: f64) -> [f64; Self::STATES] {
        [phi, 0.0]
    }

    /// The delay of a slow input, a/ω [s].
    pub fn delay(&self) -> f64 {
        A / self.w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ramp at rate c comes out as the ramp delayed by a/ω, at rate c, once the start has
    /// died away; a step settles at the input with an overshoot of 0.4 %.
    #[test]
    fn a_ramp_is_delayed_and_a_step_settles() {
        let f = PhiFilter::new(5.0);
        let (h, c) = (1e-5, 2.0);
        let (mut x, mut t, mut peak) = ([0.0, 0.0], 0.0, 0.0f64);
        // Classical Runge–Kutta on the filter's two states.
        let rk4 = |x: [f64; 2], t: f64, input: &dyn Fn(f64) -> f64| {
            let d = |x: [f64; 2], t: f64| {
                let p = f.phi(input(t), x);
                [p.dphi, p.ddphi]
            };
            let k1 = d(x, t);
            let k2 = d([x[0] + 0.5 * h * k1[0], x[1] + 0.5 * h * k1[1]], t + 0.5 * h);
            let k3 = d([x[0] + 0.5 * h * k2[0], x[1] + 0.5 * h * k2[1]], t + 0.5 * h);
            let k4 = d([x[0] + h * k3[0], x[1] + h * k3[1]], t + h);
            [0, 1].map(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
        };
        let ramp = |t: f64| c * t;
        for _ in 0..100_000 {
            x = rk4(x, t, &ramp);
            t += h;
        }
        assert!((x[1] - c).abs() < 1e-9, "rate {}", x[1]);
        assert!(
            (x[0] - c * (t - f.delay())).abs() < 1e-9,
            "{} against {}",
            x[0],
            c * (t - f.delay())
        );
        let step = |_: f64| 1.0;
        let (mut x, mut t) = ([0.0, 0.0], 0.0);
        for _ in 0..100_000 {
            x = rk4(x, t, &step);
            t += h;
            peak = peak.max(x[0]);
        }
        assert!((x[0] - 1.0).abs() < 1e-9 && peak > 1.003 && peak < 1.005, "{} {peak}", x[0]);
    }
}
