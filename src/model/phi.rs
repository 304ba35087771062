//! Sources of the prescribed hinge angle φ(t) and its first two derivatives.

use super::params::{check, ParamError, FINITE, POSITIVE};
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
/// φ(t) = φ + φ'·(t − t0) + ½φ''·(t − t0)² (FMI's SetRealInputDerivatives), or a constant
/// when the derivatives are zero.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TaylorSignal {
    /// Expansion point t0 [s].
    pub t0: f64,
    /// φ(t0), φ'(t0), φ''(t0).
    pub at_t0: Phi,
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
                let (s, c) = (w * t).sin_cos();
                Phi {
                    phi: law.phi0 + 0.5 * law.phi_end * (1.0 - c),
                    dphi: 0.5 * law.phi_end * w * s,
                    ddphi: 0.5 * law.phi_end * w * w * c,
                }
            }
            PhiPiece::Hold(phi) => Phi { phi, dphi: 0.0, ddphi: 0.0 },
            PhiPiece::Taylor(sig) => {
                let d = t - sig.t0;
                let a = sig.at_t0;
                Phi {
                    phi: a.phi + d * (a.dphi + 0.5 * d * a.ddphi),
                    dphi: a.dphi + d * a.ddphi,
                    ddphi: a.ddphi,
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
        let want = PI * (PI * t / (2.0 * 0.85)).sin().powi(2);
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
        });
        let p = s.eval(1.5);
        assert!((p.phi - (0.5 + 1.0 - 0.5)).abs() < 1e-15);
        assert!((p.dphi - 0.0).abs() < 1e-15);
        assert_eq!(p.ddphi, -4.0);
    }
}
