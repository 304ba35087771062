//! The sweep's reference integrator: the explicit Runge–Kutta pair of Dormand and Prince,
//! order 5(4), with local extrapolation and the standard step-size controller.
//!
//! Source of the method and its coefficients: J. R. Dormand and P. J. Prince, "A family of
//! embedded Runge–Kutta formulae", J. Comput. Appl. Math. 6 (1980) 19–26; the controller as
//! in E. Hairer, S. P. Nørsett and G. Wanner, *Solving ODEs I*, 2nd ed., §II.4.
//!
//! It shares nothing with the BDF but the right-hand side, so a BDF error that the two would
//! make alike (step-size or order policy, Newton, the stability guard) cannot hide in the
//! reference. Being explicit, its step is bounded by stability, |h·λ| ≲ 3.3 on the
//! imaginary axis: a stiff scene costs about t_end·|λ|max/3 steps, which the sweep bounds
//! with `max_steps`.

use beam_body::solver::OdeSystem;
use nalgebra::{Const, SVector};

// Butcher tableau (Dormand & Prince 1980, table 2): nodes c, stages a, 5th-order weights b
// (equal to the last stage row: the method is FSAL) and the error weights e = b − b̂.
const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// Why the reference gave up.
#[derive(Debug, Clone, PartialEq)]
pub enum RefError {
    TooManySteps {
        t: f64,
    },
    StepTooSmall {
        t: f64,
    },
    NonFinite {
        t: f64,
    },
    /// The state left the system's range of validity ([`OdeSystem::check_range`]) after the
    /// step that ended at `t`: the same check as the BDF's.
    OutOfRange {
        t: f64,
        name: &'static str,
        value: f64,
    },
    /// The reference of a beam of several elements, the BDF itself at a tight tolerance
    /// (`super::own_reference`), failed with this message.
    Own(String),
}

impl std::fmt::Display for RefError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RefError::TooManySteps { t } => write!(f, "step limit reached at t = {t}"),
            RefError::StepTooSmall { t } => write!(f, "step size underflow at t = {t}"),
            RefError::NonFinite { t } => write!(f, "non-finite state at t = {t}"),
            RefError::OutOfRange { t, name, value } => {
                write!(f, "{name} = {value:e} at t = {t} is out of range")
            }
            RefError::Own(message) => write!(f, "the BDF reference: {message}"),
        }
    }
}

/// An adaptive Dormand–Prince 5(4) run.
pub struct Dopri5<const N: usize> {
    pub t: f64,
    pub y: SVector<f64, N>,
    rtol: f64,
    atol: f64,
    h: f64,
    pub steps: u64,
    pub max_steps: u64,
}

impl<const N: usize> Dopri5<N> {
    pub fn new(t: f64, y: SVector<f64, N>, rtol: f64, atol: f64, max_steps: u64) -> Self {
        Self { t, y, rtol, atol, h: 0.0, steps: 0, max_steps }
    }

    /// Integrates to exactly `t_out` (the last step is shortened to land on it). Within the
    /// call the last stage serves as the next first stage (FSAL); each call starts afresh,
    /// so `sys` may differ between calls (a new piece of φ).
    pub fn advance<S: OdeSystem<Const<N>>>(&mut self, sys: &S, t_out: f64) -> Result<(), RefError> {
        let mut f0 = sys.rhs(self.t, &self.y);
        if self.h == 0.0 {
            // A first step from the size of y and f (Hairer, Nørsett & Wanner I, §II.4).
            let d0 = self.norm(&self.y, &self.y);
            let d1 = self.norm(&f0, &self.y);
            self.h = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
        }
        while self.t < t_out {
            if self.steps >= self.max_steps {
                return Err(RefError::TooManySteps { t: self.t });
            }
            let remaining = t_out - self.t;
            if remaining <= 4.0 * f64::EPSILON * t_out.abs() {
                // t_out within rounding of t (a grid time computed differently from a
                // breakpoint): the state does not change at this resolution.
                self.t = t_out;
                break;
            }
            let landing = self.h >= remaining;
            let h = if landing { remaining } else { self.h };
            if h <= 1e-15 * self.t.abs().max(1.0) {
                return Err(RefError::StepTooSmall { t: self.t });
            }
            let mut k = [SVector::<f64, N>::zeros(); 7];
            k[0] = f0;
            for i in 1..7 {
                let mut yi = self.y;
                for (j, kj) in k.iter().enumerate().take(i) {
                    yi += kj * (h * A[i][j]);
                }
                k[i] = sys.rhs(self.t + C[i] * h, &yi);
            }
            // The 5th-order solution is the last stage's argument (FSAL): y + h·Σ a_7j k_j.
            let mut y_new = self.y;
            for (j, kj) in k.iter().enumerate().take(6) {
                y_new += kj * (h * A[6][j]);
            }
            let mut err = SVector::<f64, N>::zeros();
            for (j, kj) in k.iter().enumerate() {
                err += kj * (h * E[j]);
            }
            if !y_new.iter().chain(k[6].iter()).all(|v| v.is_finite()) {
                // Overflow from a step far too large: shrink hard and retry.
                self.h = h * 0.1;
                if !self.y.iter().all(|v| v.is_finite()) {
                    return Err(RefError::NonFinite { t: self.t });
                }
                continue;
            }
            let e = self.norm_max(&err, &self.y, &y_new);
            if e <= 1.0 {
                self.t = if landing { t_out } else { self.t + h };
                self.y = y_new;
                f0 = k[6];
                self.steps += 1;
                if let Err(v) = sys.check_range(self.t, &self.y) {
                    return Err(RefError::OutOfRange { t: self.t, name: v.name, value: v.value });
                }
            }
            // h_new = h·min(5, max(0.2, 0.9·e^(−1/5))) (Hairer, Nørsett & Wanner I, II.4).
            let factor = if e == 0.0 { 5.0 } else { (0.9 * e.powf(-0.2)).clamp(0.2, 5.0) };
            let proposed = h * if e <= 1.0 { factor } else { factor.min(1.0) };
            // A step shortened to land keeps the size it had before.
            self.h = if landing && e <= 1.0 { self.h.max(proposed) } else { proposed };
        }
        Ok(())
    }

    /// Weighted RMS of `v` with weights atol + rtol·|y|.
    fn norm(&self, v: &SVector<f64, N>, y: &SVector<f64, N>) -> f64 {
        let s: f64 = v
            .iter()
            .zip(y.iter())
            .map(|(a, b)| (a / (self.atol + self.rtol * b.abs())).powi(2))
            .sum();
        (s / N as f64).sqrt()
    }

    /// Weighted RMS with weights atol + rtol·max(|y0|, |y1|).
    fn norm_max(&self, v: &SVector<f64, N>, y0: &SVector<f64, N>, y1: &SVector<f64, N>) -> f64 {
        let s: f64 = (0..N)
            .map(|i| (v[i] / (self.atol + self.rtol * y0[i].abs().max(y1[i].abs()))).powi(2))
            .sum();
        (s / N as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    struct Oscillator;
    impl OdeSystem<Const<2>> for Oscillator {
        fn rhs(&self, _t: f64, y: &Vector2<f64>) -> Vector2<f64> {
            Vector2::new(y[1], -y[0])
        }
    }

    #[test]
    fn tableau_is_consistent() {
        for i in 0..7 {
            let row: f64 = A[i].iter().sum();
            assert!((row - C[i]).abs() < 1e-15, "row {i}");
        }
        assert!(E.iter().sum::<f64>().abs() < 1e-16);
        // Order 5 conditions on b = A[6] (a sample): Σb = 1, Σb·c = 1/2, Σb·c⁴ = 1/5.
        let b = |p: i32| (0..6).map(|j| A[6][j] * C[j].powi(p)).sum::<f64>();
        for p in 0..5 {
            assert!((b(p) - 1.0 / (p + 1) as f64).abs() < 1e-14, "Σ b c^{p}");
        }
    }

    /// y' = 1 with the range y ≤ 1: the run stops after the step that crosses it, with the
    /// check's variable and value, as the BDF does.
    #[test]
    fn stops_where_the_system_leaves_its_range() {
        struct Ramp;
        impl OdeSystem<Const<1>> for Ramp {
            fn rhs(&self, _t: f64, _y: &SVector<f64, 1>) -> SVector<f64, 1> {
                SVector::<f64, 1>::new(1.0)
            }
            fn check_range(
                &self,
                _t: f64,
                y: &SVector<f64, 1>,
            ) -> Result<(), beam_body::solver::RangeViolation> {
                if y[0] > 1.0 {
                    return Err(beam_body::solver::RangeViolation {
                        name: "y",
                        value: y[0],
                        allowed: "y <= 1",
                    });
                }
                Ok(())
            }
        }
        let mut r = Dopri5::new(0.0, SVector::<f64, 1>::new(0.0), 1e-8, 1e-8, 1000);
        match r.advance(&Ramp, 5.0) {
            Err(RefError::OutOfRange { t, name: "y", value }) => {
                assert!(t > 1.0 && t < 5.0 && (value - t).abs() < 1e-12, "t {t}, y {value}");
            }
            other => panic!("expected a range stop, got {other:?}"),
        }
    }

    #[test]
    fn converges_at_fifth_order_and_meets_tight_tolerances() {
        let mut errors = Vec::new();
        for rtol in [1e-6, 1e-9, 1e-12] {
            let mut r = Dopri5::new(0.0, Vector2::new(1.0, 0.0), rtol, rtol, 10_000_000);
            r.advance(&Oscillator, 20.0).unwrap();
            let err = ((r.y[0] - 20f64.cos()).powi(2) + (r.y[1] + 20f64.sin()).powi(2)).sqrt();
            assert!(err < 100.0 * rtol, "rtol {rtol}: error {err}");
            errors.push((err, r.steps));
        }
        // Steps grow like tol^(−1/5): 10³ tighter costs about 10^(3/5) ≈ 4× the steps.
        let growth = errors[2].1 as f64 / errors[1].1 as f64;
        assert!((3.0..6.0).contains(&growth), "step growth {growth}");
    }
}
