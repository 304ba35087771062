//! Sources of the prescribed hinge angle φ(t) and its first two derivatives.

use super::params::{check, ParamError, FINITE, POSITIVE};
use crate::math;
use std::f64::consts::PI;

/// φ, φ', φ'' at one instant [rad, rad/s, rad/s²].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Phi {
    pub phi: f64,
    pub dphi: f64,
    pub ddphi: f64,
}

/// The paper's turn (§4): φ = φ0 + φ_end·sin²(πt/(2·t_rot)) for 0 ≤ t ≤ t_rot, then
/// φ0 + φ_end. φ'' jumps at t = 0 and at t = t_rot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaperLaw {
    /// Angle before the turn φ0 [rad]. Default 0 (not in the paper; 0 reproduces it).
    pub phi0: f64,
    /// Angle turned φ_end [rad]. Default π.
    pub phi_end: f64,
    /// Duration of the turn t_rot [s], > 0. Default 0.85 (the paper's T).
    pub t_rot: f64,
}

impl Default for PaperLaw {
    fn default() -> Self {
        Self { phi0: 0.0, phi_end: PI, t_rot: 0.85 }
    }
}

impl PaperLaw {
    pub fn validate(&self) -> Result<(), ParamError> {
        check("phi0", self.phi0, FINITE)?;
        check("phi_end", self.phi_end, FINITE)?;
        check("t_rot", self.t_rot, POSITIVE)
    }

    /// The law at t, taking the turn's formula up to and including t_rot.
    pub fn eval(&self, t: f64) -> Phi {
        self.piece_from(t).eval(t)
    }

    /// The smooth piece that holds on the interval starting at `t`: the turn for t < t_rot,
    /// the hold after. At a breakpoint the driver restarts the integrator with the piece that
    /// follows it, so f is never evaluated across the jump of φ''.
    pub fn piece_from(&self, t: f64) -> PhiPiece {
        if t < self.t_rot {
            PhiPiece::Turn(*self)
        } else {
            PhiPiece::Hold(self.phi0 + self.phi_end)
        }
    }

    /// Where φ'' jumps, after t = 0.
    pub fn breakpoint(&self) -> f64 {
        self.t_rot
    }
}

/// φ given from outside over one step: the Taylor polynomial
/// φ(t) = φ + φ'·(t − t0) + ½φ''·(t − t0)² + ⅙φ'''·(t − t0)³. A host's
/// SetRealInputDerivatives gives the first three terms (`jerk` = 0); [`ValueHistory`] gives
/// up to all four.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TaylorSignal {
    /// Expansion point t0 [s].
    pub t0: f64,
    /// φ(t0), φ'(t0), φ''(t0).
    pub at_t0: Phi,
    /// φ'''(t0) [rad/s³].
    pub jerk: f64,
}

/// The last few values of an input φ at the communication points, and the piece of φ that
/// a step uses when the host sends values only.
///
/// The scheme ([`piece`](Self::piece)): the polynomial of degree d through the last d + 1
/// samples (Newton's divided differences, any spacing) is extrapolated to the end of the
/// step, tc + H, for a target value and slope. The step then uses the cubic Hermite
/// polynomial from the current φ and φ' at tc to that target. So φ and φ' are continuous
/// from step to step, and the φ'' the beam feels always integrates to the change of φ': no
/// part of the drive's impulse is lost at a communication point, which a piece that jumped
/// in φ' would lose (the scheme without this converged at order 1 only).
/// For a smooth φ the target is off by O(H^(d+1)) in φ and O(H^d) in φ', so φ'' on the step
/// is off by O(H^(d−1)) for d ≤ 3; with d = 3 the solution converges at order 2.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ValueHistory {
    /// Newest first.
    t: [f64; HISTORY],
    u: [f64; HISTORY],
    len: usize,
}

const HISTORY: usize = 4;

impl ValueHistory {
    /// The highest degree of the extrapolation.
    pub const MAX_DEGREE: usize = HISTORY - 1;

    /// Records φ(t) = u. Samples at or after `t` are dropped first: a sample at the newest
    /// time replaces it, and a host that went back in time restored an older state.
    pub fn push(&mut self, t: f64, u: f64) {
        let keep = (0..self.len).find(|&k| self.t[k] < t).unwrap_or(self.len);
        let kept = (self.len - keep).min(HISTORY - 1);
        self.t.copy_within(keep..keep + kept, 1);
        self.u.copy_within(keep..keep + kept, 1);
        self.t[0] = t;
        self.u[0] = u;
        self.len = kept + 1;
        // Unused slots are zero, so equal histories compare equal.
        self.t[self.len..].fill(0.0);
        self.u[self.len..].fill(0.0);
    }

    /// Number of samples held, ≤ 4.
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The samples (t, φ), newest first.
    pub fn samples(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        (0..self.len).map(|k| (self.t[k], self.u[k]))
    }

    /// Rebuilds a history from samples given newest first (FMU state restore). `None`
    /// unless there are at most 4, times are finite and strictly decreasing, values finite.
    pub fn from_samples(samples: &[(f64, f64)]) -> Option<Self> {
        let ok = samples.len() <= HISTORY
            && samples.iter().all(|(t, u)| t.is_finite() && u.is_finite())
            && samples.windows(2).all(|w| w[0].0 > w[1].0);
        ok.then(|| {
            let mut h = Self::default();
            for &(t, u) in samples.iter().rev() {
                h.push(t, u);
            }
            h
        })
    }

    /// The Taylor expansion at the newest sample of the polynomial of degree
    /// min(`degree`, len − 1) through the newest samples. `None` without samples.
    pub fn extrapolation(&self, degree: usize) -> Option<TaylorSignal> {
        if self.len == 0 {
            return None;
        }
        let n = degree.min(self.len - 1).min(Self::MAX_DEGREE) + 1;
        // Divided differences in place: c[k] = u[x0, …, xk], nodes newest first.
        let (x, mut c) = (self.t, self.u);
        for order in 1..n {
            for k in (order..n).rev() {
                c[k] = (c[k] - c[k - 1]) / (x[k] - x[k - order]);
            }
        }
        let coef = |k: usize| if k < n { c[k] } else { 0.0 };
        // p(x0 + s) = c0 + c1 s + c2 s (s + d1) + c3 s (s + d1)(s + d2), with dk = x0 − xk.
        let d1 = if n > 1 { x[0] - x[1] } else { 0.0 };
        let d2 = if n > 2 { x[0] - x[2] } else { 0.0 };
        let (c1, c2, c3) = (coef(1), coef(2), coef(3));
        Some(TaylorSignal {
            t0: x[0],
            at_t0: Phi {
                phi: c[0],
                dphi: c1 + c2 * d1 + c3 * d1 * d2,
                ddphi: 2.0 * (c2 + c3 * (d1 + d2)),
            },
            jerk: 6.0 * c3,
        })
    }

    /// The piece of φ for the step [t0, t0 + h] that starts at the newest sample's time t0:
    /// the cubic Hermite polynomial from `start` (φ and φ' at t0 of the piece in use; its φ''
    /// is not used) to the value and slope at t0 + h of [`extrapolation`](Self::extrapolation).
    /// `None` without samples, for h ≤ 0, or when a coefficient is not finite: a step so
    /// short that h² or h³ underflows (h = 1e-200 gives 0/0), or values so far apart that the
    /// slopes overflow.
    pub fn piece(&self, degree: usize, start: Phi, h: f64) -> Option<TaylorSignal> {
        let ext = self.extrapolation(degree)?;
        if h.is_nan() || h <= 0.0 {
            return None;
        }
        let target = PhiPiece::Taylor(ext).eval(ext.t0 + h);
        let (a, b) = (start.phi, start.dphi);
        let rise = target.phi - a;
        // φ(t0 + s) = a + b s + c2 s² + c3 s³ with φ(t0 + h) = target.phi, φ'(t0 + h) = target.dphi.
        let c2 = (3.0 * rise - (2.0 * b + target.dphi) * h) / (h * h);
        let c3 = ((b + target.dphi) * h - 2.0 * rise) / (h * h * h);
        let piece = TaylorSignal {
            t0: ext.t0,
            at_t0: Phi { phi: a, dphi: b, ddphi: 2.0 * c2 },
            jerk: 6.0 * c3,
        };
        let finite = [piece.t0, a, b, piece.at_t0.ddphi, piece.jerk].iter().all(|x| x.is_finite());
        finite.then_some(piece)
    }
}

/// One smooth piece of φ(t), as the right-hand side evaluates it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhiPiece {
    /// The sin² turn of [`PaperLaw`], on 0 ≤ t ≤ t_rot.
    Turn(PaperLaw),
    /// A constant angle [rad].
    Hold(f64),
    /// A quadratic Taylor polynomial.
    Taylor(TaylorSignal),
}

impl PhiPiece {
    pub fn eval(&self, t: f64) -> Phi {
        match *self {
            PhiPiece::Turn(law) => {
                let w = PI / law.t_rot;
                let (s, c) = math::sin_cos(w * t);
                Phi {
                    phi: law.phi0 + 0.5 * law.phi_end * (1.0 - c),
                    dphi: 0.5 * law.phi_end * w * s,
                    ddphi: 0.5 * law.phi_end * w * w * c,
                }
            }
            PhiPiece::Hold(phi) => Phi { phi, dphi: 0.0, ddphi: 0.0 },
            PhiPiece::Taylor(sig) => {
                let d = t - sig.t0;
                let (a, j) = (sig.at_t0, sig.jerk);
                Phi {
                    phi: a.phi + d * (a.dphi + d * (0.5 * a.ddphi + d * j / 6.0)),
                    dphi: a.dphi + d * (a.ddphi + 0.5 * d * j),
                    ddphi: a.ddphi + d * j,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn law_matches_its_derivatives_and_ends() {
        let law = PaperLaw::default();
        assert_eq!(law.eval(0.0).phi, 0.0);
        assert!((law.eval(law.t_rot).phi - PI).abs() < 1e-15);
        assert!(law.eval(law.t_rot).dphi.abs() < 1e-14);
        assert_eq!(law.eval(5.0), Phi { phi: PI, dphi: 0.0, ddphi: 0.0 });
        // Central differences of φ and φ' agree with the analytic φ' and φ''.
        let h = 1e-5;
        for &t in &[0.1, 0.3, 0.6, 0.8] {
            let (a, b, m) = (law.eval(t - h), law.eval(t + h), law.eval(t));
            assert!(((b.phi - a.phi) / (2.0 * h) - m.dphi).abs() < 1e-8);
            assert!(((b.dphi - a.dphi) / (2.0 * h) - m.ddphi).abs() < 1e-6);
        }
        // φ = φ_end·sin²(πt/(2 t_rot)) exactly.
        let t = 0.37;
        let want = PI * math::powi(math::sin(PI * t / (2.0 * 0.85)), 2);
        assert!((law.eval(t).phi - want).abs() < 1e-14);
    }

    #[test]
    fn pieces_switch_at_the_breakpoint() {
        let law = PaperLaw::default();
        assert!(matches!(law.piece_from(0.0), PhiPiece::Turn(_)));
        assert_eq!(law.piece_from(law.t_rot), PhiPiece::Hold(PI));
        // The turn's own formula, evaluated at t_rot, keeps the left-hand φ''.
        assert!(law.piece_from(0.0).eval(law.t_rot).ddphi < 0.0);
    }

    #[test]
    fn taylor_signal_is_quadratic() {
        let s = PhiPiece::Taylor(TaylorSignal {
            t0: 1.0,
            at_t0: Phi { phi: 0.5, dphi: 2.0, ddphi: -4.0 },
            jerk: 0.0,
        });
        let p = s.eval(1.5);
        assert!((p.phi - (0.5 + 1.0 - 0.5)).abs() < 1e-15);
        assert!((p.dphi - 0.0).abs() < 1e-15);
        assert_eq!(p.ddphi, -4.0);
    }

    #[test]
    fn history_reproduces_polynomials_of_its_degree() {
        // A cubic through uneven samples is reproduced exactly by degree 3, with its
        // derivatives at the newest sample.
        let p = |t: f64| 0.3 - 1.2 * t + 0.7 * t * t + 0.25 * t * t * t;
        let dp = |t: f64| -1.2 + 1.4 * t + 0.75 * t * t;
        let ddp = |t: f64| 1.4 + 1.5 * t;
        let mut h = ValueHistory::default();
        assert!(h.extrapolation(3).is_none());
        for &t in &[0.0, 0.1, 0.25, 0.3, 0.42] {
            h.push(t, p(t));
        }
        assert_eq!(h.len(), 4);
        let s = h.extrapolation(3).unwrap();
        assert_eq!(s.t0, 0.42);
        assert!((s.at_t0.phi - p(0.42)).abs() < 1e-14);
        assert!((s.at_t0.dphi - dp(0.42)).abs() < 1e-12);
        assert!((s.at_t0.ddphi - ddp(0.42)).abs() < 1e-10);
        assert!((s.jerk - 1.5).abs() < 1e-9);
        let ahead = PhiPiece::Taylor(s).eval(0.5);
        assert!((ahead.phi - p(0.5)).abs() < 1e-13);
        // Degree 0 holds the newest value; degree 1 is the secant.
        let s0 = h.extrapolation(0).unwrap();
        assert_eq!(
            (s0.at_t0.phi, s0.at_t0.dphi, s0.at_t0.ddphi, s0.jerk),
            (p(0.42), 0.0, 0.0, 0.0)
        );
        let s1 = h.extrapolation(1).unwrap();
        assert!((s1.at_t0.dphi - (p(0.42) - p(0.3)) / 0.12).abs() < 1e-12);
    }

    #[test]
    fn history_converges_at_its_order_on_a_smooth_signal() {
        // Error of the extrapolated φ'' one step ahead of the newest sample, for sin t:
        // O(H^(d−1)) for degree d.
        let err = |d: usize, h: f64| {
            let mut hist = ValueHistory::default();
            for k in 0..4 {
                let t = 1.0 + k as f64 * h;
                hist.push(t, math::sin(t));
            }
            let t = 1.0 + 4.0 * h;
            (PhiPiece::Taylor(hist.extrapolation(d).unwrap()).eval(t).ddphi + math::sin(t)).abs()
        };
        for d in [2, 3] {
            let order = math::log2(err(d, 1e-2) / err(d, 5e-3));
            assert!((order - (d as f64 - 1.0)).abs() < 0.15, "degree {d}: order {order}");
        }
    }

    #[test]
    fn history_drops_samples_from_the_future_and_validates_restores() {
        let mut h = ValueHistory::default();
        for k in 0..6 {
            h.push(k as f64, k as f64 * 10.0);
        }
        let all: Vec<_> = h.samples().collect();
        assert_eq!(all, [(5.0, 50.0), (4.0, 40.0), (3.0, 30.0), (2.0, 20.0)]);
        h.push(3.5, -1.0);
        let all: Vec<_> = h.samples().collect();
        assert_eq!(all, [(3.5, -1.0), (3.0, 30.0), (2.0, 20.0)]);
        h.push(3.5, -2.0);
        assert_eq!(h.samples().next(), Some((3.5, -2.0)));
        assert_eq!(h.len(), 3);
        let copy = ValueHistory::from_samples(&h.samples().collect::<Vec<_>>()).unwrap();
        assert_eq!(copy, h);
        assert!(ValueHistory::from_samples(&[(1.0, 0.0), (2.0, 0.0)]).is_none());
        assert!(ValueHistory::from_samples(&[(1.0, f64::NAN)]).is_none());
    }

    #[test]
    fn hermite_piece_is_c1_and_hits_the_extrapolated_target() {
        let p = |t: f64| math::sin(2.0 * t);
        let mut hist = ValueHistory::default();
        for t in [0.0, 0.1, 0.2, 0.3] {
            hist.push(t, p(t));
        }
        let start = Phi { phi: 0.55, dphi: 1.7, ddphi: 99.0 };
        let s = hist.piece(3, start, 0.1).unwrap();
        assert_eq!((s.t0, s.at_t0.phi, s.at_t0.dphi), (0.3, 0.55, 1.7));
        let end = PhiPiece::Taylor(s).eval(0.4);
        let target = PhiPiece::Taylor(hist.extrapolation(3).unwrap()).eval(0.4);
        assert!((end.phi - target.phi).abs() < 1e-13);
        assert!((end.dphi - target.dphi).abs() < 1e-12);
        assert!(hist.piece(3, start, 0.0).is_none());
        assert!(ValueHistory::default().piece(3, start, 0.1).is_none());
    }

    /// Found by fuzzing (`api_sequence`): a step of h = 1e-197 makes h² underflow to 0, and
    /// the Hermite coefficients 0/0. No piece, rather than a NaN one.
    #[test]
    fn hermite_piece_refuses_steps_whose_powers_underflow() {
        let mut hist = ValueHistory::default();
        hist.push(0.0, 0.0);
        hist.push(1.0, 0.0);
        let start = Phi::default();
        assert!(hist.piece(3, start, 1e-197).is_none());
        assert!(hist.piece(3, start, 1e-100).is_some());
        hist.push(2.0, 1e300);
        assert!(hist.piece(3, start, 1e-100).is_none(), "slopes overflow");
    }
}
