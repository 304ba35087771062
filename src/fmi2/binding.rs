//! The model binding: the variables of the table bound to the model's parameters, the φ
//! input and the outputs, with get and set by variable (Reference-FMUs' `model.c`). The
//! state machine ([`instance`](super::instance)) knows the model only through this file.
#![forbid(unsafe_code)]

use super::variables::{Var, Variable};
use crate::model::{Kinematics, Reactions};
use crate::scene::Scene;
use crate::settings::{self, Kind, Setting};
use std::fmt;

/// The values of the parameters (the settings of a run, as the CLI has them) and the input.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Values {
    pub settings: Scene,
    pub phi: f64,
}

/// A value of any FMI base type.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Value {
    Real(f64),
    Integer(i32),
    Boolean(bool),
}

/// The bare value, as the traces show it.
impl fmt::Debug for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Real(x) => write!(f, "{x:?}"),
            Value::Integer(k) => write!(f, "{k:?}"),
            Value::Boolean(b) => write!(f, "{b:?}"),
        }
    }
}

/// A setting's value as FMI has it: enumerations are 1-based.
fn to_fmi(value: settings::Value) -> Value {
    match value {
        settings::Value::Real(x) => Value::Real(x),
        settings::Value::Integer(k) => Value::Integer(k as i32),
        settings::Value::Choice(k) => Value::Integer(k as i32 + 1),
        settings::Value::Bool(b) => Value::Boolean(b),
    }
}

/// An FMI value as the setting's value; the base type is checked before.
fn from_fmi(setting: &Setting, value: Value) -> Result<settings::Value, String> {
    Ok(match (setting.kind, value) {
        (Kind::Choice(ty), Value::Integer(k)) => {
            let n = ty.items.len() as i32;
            if !(1..=n).contains(&k) {
                let items: Vec<String> = ty
                    .items
                    .iter()
                    .enumerate()
                    .map(|(j, i)| format!("{} ({})", j + 1, i.0))
                    .collect();
                return Err(format!(
                    "`{}` = {k} is out of range: must be one of {}",
                    setting.name,
                    items.join(", ")
                ));
            }
            settings::Value::Choice((k - 1) as usize)
        }
        (_, Value::Integer(k)) => settings::Value::Integer(k as i64),
        (_, Value::Real(x)) => settings::Value::Real(x),
        (_, Value::Boolean(b)) => settings::Value::Bool(b),
    })
}

impl Values {
    /// The start values: the settings table's (the FMU's where they differ), and φ = 0.
    pub(super) fn from_table() -> Values {
        let mut settings = Scene::default();
        for s in settings::SETTINGS.iter().filter(|s| s.fmu_start.is_some()) {
            settings.set(s.key, s.fmu_default()).expect("the table's start values are in range");
        }
        Values { settings, phi: 0.0 }
    }

    /// Sets the input `phi`, which must be finite.
    pub(super) fn set_phi(&mut self, x: f64) -> Result<(), String> {
        if !x.is_finite() {
            return Err(format!("`phi` = {x:?} is out of range: must be finite"));
        }
        self.phi = x;
        Ok(())
    }

    /// Sets `var` after checking the value's range; the error names the variable and the
    /// allowed range.
    pub(super) fn set(&mut self, var: &Variable, value: Value) -> Result<(), String> {
        match (var.setting, value) {
            (Some(key), _) => {
                let value = from_fmi(Setting::of(key), value)?;
                self.settings.set(key, value)
            }
            (None, Value::Real(x)) if var.var == Var::Phi => self.set_phi(x),
            _ => unreachable!("outputs are rejected before, other types by type"),
        }
    }

    /// The value of a parameter or the input.
    pub(super) fn get(&self, var: &Variable) -> Option<Value> {
        match var.setting {
            Some(key) => Some(to_fmi(self.settings.get(key))),
            None if var.var == Var::Phi => Some(Value::Real(self.phi)),
            None => None,
        }
    }
}

/// What an output is computed from: the motion (cheap, with every step's outputs), or the
/// reactions or the energy (computed only when one of them is read).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Group {
    Motion,
    Reactions,
    Energy,
}

/// The group of output `var`; `None` for a variable that is not an output.
pub(super) fn group(var: Var) -> Option<Group> {
    Some(match var {
        Var::N | Var::P | Var::Moment => Group::Reactions,
        Var::Energy => Group::Energy,
        Var::V1
        | Var::Theta1
        | Var::U2
        | Var::Dv1
        | Var::Dtheta1
        | Var::Du2
        | Var::Drift
        | Var::PhiApplied
        | Var::DphiApplied
        | Var::DdphiApplied => Group::Motion,
        _ => return None,
    })
}

/// The value of a motion output `var`; `None` for the other variables.
pub(super) fn motion(var: Var, k: &Kinematics) -> Option<f64> {
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
        _ => return None,
    })
}

/// The value of a reaction output `var`; `None` for the other variables.
pub(super) fn reaction(var: Var, r: &Reactions) -> Option<f64> {
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
/// exactly: the rates and accelerations of v1, theta1 and u2 (the accelerations from the
/// equations of motion at the current state), and φ′, φ″ of the piece in use. `None` for the
/// other outputs and orders.
pub(super) fn derivative(var: Var, order: i32, k: &Kinematics) -> Option<f64> {
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
pub(super) fn with_derivatives(order: i32) -> &'static str {
    match order {
        1 => "v1, theta1, u2, dv1, dtheta1, du2, phi_applied, dphi_applied",
        _ => "v1, theta1, u2, phi_applied",
    }
}

/// Most internal steps in one fmi2DoStep, so that a step always returns in bounded time
/// (about a second in a release build); beyond it the step is discarded with a message. The
/// stiffest scene of the sweep (EI × 10⁷) needs about 5·10⁴ steps per simulated second.
pub const MAX_STEPS_PER_DO_STEP: u64 = 1_000_000;
