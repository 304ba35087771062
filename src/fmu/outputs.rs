//! The outputs by variable: which are computed from the motion, which from the reactions
//! or the energy, and which have time derivatives.
#![forbid(unsafe_code)]

use super::variables::Var;
use crate::model::{Kinematics, Reactions};

/// What an output is computed from: the motion (cheap, with every step's outputs), or the
/// reactions or the energy (computed only when one of them is read).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    Motion,
    Reactions,
    Energy,
    /// The loads at the root, from the motion and the hinge's axial force.
    Root,
}

/// The outputs at the communication time, by group, each computed at its first request
/// after a change. Not part of a serialized state.
#[derive(Clone, Copy, Debug, Default)]
pub struct Cache {
    pub kinematics: Option<Kinematics>,
    pub reactions: Option<Reactions>,
    pub energy: Option<f64>,
}

/// The group of output `var`; `None` for a variable that is not an output.
pub fn group(var: Var) -> Option<Group> {
    Some(match var {
        Var::N | Var::P | Var::Moment => Group::Reactions,
        Var::Energy => Group::Energy,
        Var::MRoot | Var::QRoot => Group::Root,
        Var::VQuarter | Var::VMid | Var::VThreeQuarter => Group::Motion,
        Var::V1
        | Var::Theta1
        | Var::U2
        | Var::Dv1
        | Var::Dtheta1
        | Var::Du2
        | Var::Drift
        | Var::PhiApplied
        | Var::DphiApplied
        | Var::DdphiApplied
        | Var::DerV1
        | Var::DerTheta1
        | Var::DerDv1
        | Var::DerDtheta1 => Group::Motion,
        _ => return None,
    })
}

/// The value of a motion output `var`; `None` for the other variables.
pub fn motion(var: Var, k: &Kinematics) -> Option<f64> {
    Some(match var {
        Var::V1 => k.v1,
        Var::Theta1 => k.theta1,
        Var::U2 => k.u2,
        Var::Dv1 => k.dv1,
        Var::Dtheta1 => k.dtheta1,
        Var::Du2 => k.du2,
        Var::Drift => k.drift,
        Var::PhiApplied => k.phi.phi,
        Var::DphiApplied => k.phi.dphi,
        Var::DdphiApplied => k.phi.ddphi,
        Var::VQuarter => k.quarter[0][0],
        Var::VMid => k.quarter[0][1],
        Var::VThreeQuarter => k.quarter[0][2],
        // The states' derivatives (Model Exchange's x = (v1, ϑ1, v̇1, ϑ̇1)).
        Var::DerV1 => k.dv1,
        Var::DerTheta1 => k.dtheta1,
        Var::DerDv1 => k.ddv1,
        Var::DerDtheta1 => k.ddtheta1,
        _ => return None,
    })
}

/// The value of a reaction output `var`; `None` for the other variables.
pub fn reaction(var: Var, r: &Reactions) -> Option<f64> {
    Some(match var {
        Var::N => r.n,
        Var::P => r.p,
        Var::Moment => r.m,
        _ => return None,
    })
}

/// Highest order of the output derivatives (fmi2GetRealOutputDerivatives), the
/// `maxOutputDerivativeOrder` of the model description.
pub const MAX_OUTPUT_DERIVATIVE_ORDER: i32 = 2;

/// The time derivative of order `order` (1 or 2) of output `var`, where the motion gives it
/// exactly: the rates and accelerations of v1, theta1, u2 and of the deflections at the
/// quarter points (the accelerations from the equations of motion at the current state), and
/// φ′, φ″ of the piece in use. `None` for the other outputs and orders (the reactions' and the
/// root loads' would need the jerk).
pub fn derivative(var: Var, order: i32, k: &Kinematics) -> Option<f64> {
    let point = match var {
        Var::VQuarter => Some(0),
        Var::VMid => Some(1),
        Var::VThreeQuarter => Some(2),
        _ => None,
    };
    if let (Some(point), 1 | 2) = (point, order) {
        return Some(k.quarter[order as usize][point]);
    }
    Some(match (var, order) {
        (Var::V1, 1) => k.dv1,
        (Var::V1, 2) | (Var::Dv1, 1) => k.ddv1,
        (Var::Theta1, 1) => k.dtheta1,
        (Var::Theta1, 2) | (Var::Dtheta1, 1) => k.ddtheta1,
        (Var::U2, 1) => k.du2,
        (Var::U2, 2) | (Var::Du2, 1) => k.ddu2,
        (Var::PhiApplied, 1) => k.phi.dphi,
        (Var::PhiApplied, 2) | (Var::DphiApplied, 1) => k.phi.ddphi,
        _ => return None,
    })
}

/// The outputs that have derivatives of order `order` ([`derivative`]), for error messages.
pub fn with_derivatives(order: i32) -> &'static str {
    match order {
        1 => {
            "v1, theta1, u2, dv1, dtheta1, du2, phi_applied, dphi_applied, v_quarter, v_mid, \
             v_three_quarter"
        }
        _ => "v1, theta1, u2, phi_applied, v_quarter, v_mid, v_three_quarter",
    }
}
