//! Sources of the prescribed hinge angle φ(t) and its first two derivatives.

use super::params::{check_setting, ParamError};
use crate::math;
use crate::settings::fields_of;
use std::f64::consts::PI;

/// φ, φ', φ'' at one instant [rad, rad/s, rad/s²].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Phi {
    pub phi: f64,
    pub dphi: f64,
    pub ddphi: f64,
}

/// The paper's turn (§4): φ = φ0 + φ_end·sin²(πt/(2·t_rot)) for 0 ≤ t ≤ t_rot, then
/// φ0 + φ_end. φ'' jumps at t = 0 and at t = t_rot. Its defaults and ranges are the settings
/// table's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaperLaw {
    /// Angle before the turn φ0 [rad] (not in the paper; 0 reproduces it).
    pub phi0: f64,
    /// Angle turned φ_end [rad].
    pub phi_end: f64,
    /// Duration of the turn t_rot [s] (the paper's T).
    pub t_rot: f64,
}

crate::settings::for_each_setting!(fields_of, law PaperLaw);

impl PaperLaw {
    /// The law at t: the turn's formula before t_rot, the hold from t_rot on.
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

/// A polynomial piece of φ of degree ≤ 5 in the scaled time s = (t − t0)/h:
/// φ = Σ c_k s^k. The scale h (the step it was built for, or 1) keeps the coefficients of the
/// order of φ's changes over the step, whatever h is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Poly {
    pub t0: f64,
    pub h: f64,
    pub c: [f64; 6],
}

impl Poly {
    /// φ + φ′(t − t0) + ½φ″(t − t0)², the Taylor polynomial at t0.
    pub fn taylor(t0: f64, at: Phi) -> Poly {
        Poly { t0, h: 1.0, c: [at.phi, at.dphi, 0.5 * at.ddphi, 0.0, 0.0, 0.0] }
    }

    /// The cubic on [t0, t0 + h] from φ and φ′ of `start` (its φ″ is not used) to φ and φ′
    /// of `end`.
    pub fn hermite_c1(t0: f64, h: f64, start: Phi, end: Phi) -> Poly {
        let (a0, a1) = (start.phi, start.dphi * h);
        let r0 = end.phi - a0 - a1;
        let r1 = end.dphi * h - a1;
        // c2 + c3 = r0, 2c2 + 3c3 = r1.
        Poly { t0, h, c: [a0, a1, 3.0 * r0 - r1, r1 - 2.0 * r0, 0.0, 0.0] }
    }

    /// The quintic on [t0, t0 + h] from φ, φ′, φ″ of `start` to those of `end`.
    pub fn hermite_c2(t0: f64, h: f64, start: Phi, end: Phi) -> Poly {
        let (a0, a1, a2) = (start.phi, start.dphi * h, 0.5 * start.ddphi * h * h);
        let r0 = end.phi - a0 - a1 - a2;
        let r1 = end.dphi * h - a1 - 2.0 * a2;
        let r2 = end.ddphi * h * h - 2.0 * a2;
        // c3 + c4 + c5 = r0, 3c3 + 4c4 + 5c5 = r1, 6c3 + 12c4 + 20c5 = r2.
        let c3 = 10.0 * r0 - 4.0 * r1 + 0.5 * r2;
        let c4 = -15.0 * r0 + 7.0 * r1 - r2;
        let c5 = 6.0 * r0 - 3.0 * r1 + 0.5 * r2;
        Poly { t0, h, c: [a0, a1, a2, c3, c4, c5] }
    }

    pub fn eval(&self, t: f64) -> Phi {
        // One division: the right-hand side evaluates this at every Newton iteration.
        let inv = 1.0 / self.h;
        let s = (t - self.t0) * inv;
        let c = &self.c;
        let (mut p, mut dp, mut ddp) = (c[5], 0.0, 0.0);
        for k in (0..5).rev() {
            ddp = ddp * s + 2.0 * dp;
            dp = dp * s + p;
            p = p * s + c[k];
        }
        Phi { phi: p, dphi: dp * inv, ddphi: ddp * (inv * inv) }
    }

    /// φ, φ′, φ″ at t0 (what [`eval`](Self::eval) gives there, without the Horner steps).
    pub fn at_start(&self) -> Phi {
        let inv = 1.0 / self.h;
        let c = &self.c;
        Phi { phi: c[0], dphi: c[1] * inv, ddphi: 2.0 * c[2] * (inv * inv) }
    }

    /// Whether φ, φ′ and φ″ are finite over the piece's step: finite coefficients, and
    /// 1/h² finite (a step so short that it overflows gives no finite φ″).
    pub fn is_finite(&self) -> bool {
        let inv = 1.0 / self.h;
        let sum: f64 = self.c.iter().map(|c| c.abs()).sum();
        self.t0.is_finite() && (sum * inv * inv * 20.0).is_finite() && self.h > 0.0
    }
}

/// One smooth piece of φ(t), as the right-hand side evaluates it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhiPiece {
    /// The sin² turn of [`PaperLaw`], on 0 ≤ t ≤ t_rot.
    Turn(PaperLaw),
    /// A constant angle [rad].
    Hold(f64),
    /// A polynomial of a host's signal.
    Poly(Poly),
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
            PhiPiece::Poly(p) => p.eval(t),
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
    fn polynomial_pieces_meet_their_end_conditions() {
        let start = Phi { phi: 0.5, dphi: 2.0, ddphi: -4.0 };
        let end = Phi { phi: 0.9, dphi: -1.0, ddphi: 3.0 };
        let (t0, h) = (1.0, 0.25);
        let q = Poly::hermite_c2(t0, h, start, end);
        let c = Poly::hermite_c1(t0, h, start, end);
        let close = |a: Phi, b: Phi, orders: usize| {
            let (a, b) = ([a.phi, a.dphi, a.ddphi], [b.phi, b.dphi, b.ddphi]);
            (0..orders).all(|k| (a[k] - b[k]).abs() < 1e-12)
        };
        assert!(close(q.eval(t0), start, 3) && close(q.eval(t0 + h), end, 3));
        assert!(close(c.eval(t0), start, 2) && close(c.eval(t0 + h), end, 2));
        // The Taylor piece is the quadratic.
        let p = Poly::taylor(t0, start).eval(1.5);
        assert!((p.phi - (0.5 + 1.0 - 0.5)).abs() < 1e-15);
        assert!(p.dphi.abs() < 1e-15);
        assert_eq!(p.ddphi, -4.0);
    }

    /// Found by fuzzing (`api_sequence`): a step of h = 1e-197 made the old form's h²
    /// underflow to 0, and its coefficients 0/0. In the scaled form the coefficients stay
    /// finite and φ″ overflows: not a finite piece.
    #[test]
    fn pieces_over_steps_whose_powers_underflow_are_not_finite() {
        let (start, end) = (Phi::default(), Phi { phi: 1.0, ..Phi::default() });
        assert!(!Poly::hermite_c2(0.0, 1e-197, start, end).is_finite());
        assert!(Poly::hermite_c2(0.0, 1e-100, start, end).is_finite());
        let far = Phi { phi: 1e300, ..Phi::default() };
        assert!(!Poly::hermite_c2(0.0, 1e-100, start, far).is_finite(), "slopes overflow");
    }
}
