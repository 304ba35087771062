//! The model binding: the variables of the table bound to the model's parameters, the φ
//! input and the outputs, with get and set by variable (Reference-FMUs' `model.c`). The
//! state machine ([`instance`](super::instance)) knows the model only through this file.
#![forbid(unsafe_code)]

use super::variables::{Type, Var, Variable, VARIABLES};
use crate::model::{
    Formulation, Interpolation, Kinematics, PaperLaw, Params, RangeCheck, Reactions,
};
use crate::solver::{BdfConfig, FixedStep};
use std::fmt;

/// Where φ comes from (the `phi_source` enumeration).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhiSource {
    Input,
    Law,
}

/// The values of the parameters and the input.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Values {
    pub params: Params,
    pub law: PaperLaw,
    pub atol: f64,
    pub fixed_step: f64,
    pub formulation: Formulation,
    pub phi_source: PhiSource,
    pub max_order: i32,
    pub fixed_order: i32,
    pub phi_extrapolation: i32,
    pub phi_interpolation: Interpolation,
    pub range_check: RangeCheck,
    pub stability_guard: bool,
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

impl Values {
    /// The start values of the variable table.
    pub(super) fn from_table() -> Values {
        let mut v = Values {
            params: Params::default(),
            law: PaperLaw::default(),
            atol: 0.0,
            fixed_step: 0.0,
            formulation: Formulation::Reduced,
            phi_source: PhiSource::Input,
            max_order: 5,
            fixed_order: 2,
            phi_extrapolation: 3,
            phi_interpolation: Interpolation::Smooth,
            range_check: RangeCheck::Stop,
            stability_guard: true,
            phi: 0.0,
        };
        for var in VARIABLES {
            let start = match var.ty {
                Type::Real { start: Some(s), .. } => Value::Real(s),
                Type::Real { start: None, .. } => continue,
                Type::Integer { start, .. } | Type::Enumeration { start, .. } => {
                    Value::Integer(start)
                }
                Type::Boolean { start } => Value::Boolean(start),
            };
            v.set(var, start).expect("the table's start values are in range");
        }
        v
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
        let bad = |allowed: &str, shown: String| {
            Err(format!("`{}` = {shown} is out of range: must be {allowed}", var.name))
        };
        match value {
            Value::Real(x) => {
                // Non-finite values are refused with the variable's whole range, not just
                // "finite": `EI` = NaN says "positive and finite".
                let finite = x.is_finite();
                match var.var {
                    Var::L | Var::Ei | Var::M | Var::M2 | Var::JC | Var::R | Var::G => {
                        self.params.set(var.name, x).map_err(|e| e.to_string())?;
                    }
                    Var::TRot if finite && x > 0.0 => self.law.t_rot = x,
                    Var::TRot => return bad("positive and finite", format!("{x:?}")),
                    Var::Atol if finite && x >= 0.0 => self.atol = x,
                    Var::FixedStep if finite && x >= 0.0 => self.fixed_step = x,
                    Var::Atol | Var::FixedStep => {
                        return bad("non-negative and finite", format!("{x:?}"))
                    }
                    Var::PhiEnd if !finite => return bad("finite", format!("{x:?}")),
                    Var::PhiEnd => self.law.phi_end = x,
                    Var::Phi => self.set_phi(x)?,
                    _ => unreachable!("outputs are rejected before, other types by type"),
                }
            }
            Value::Integer(k) => {
                let (lo, hi) = match var.ty {
                    Type::Integer { min, max, .. } => (min, max),
                    Type::Enumeration { ty, .. } => (1, ty.items.len() as i32),
                    _ => unreachable!("checked by type"),
                };
                if !(lo..=hi).contains(&k) {
                    let allowed = match var.ty {
                        Type::Enumeration { ty, .. } => {
                            let items: Vec<String> = (lo..=hi)
                                .map(|j| format!("{j} ({})", ty.items[(j - 1) as usize].0))
                                .collect();
                            format!("one of {}", items.join(", "))
                        }
                        _ => format!("an integer in {lo}..={hi}"),
                    };
                    return bad(&allowed, k.to_string());
                }
                match var.var {
                    Var::Formulation => self.formulation = Formulation::ALL[(k - 1) as usize],
                    Var::PhiSource => {
                        self.phi_source = if k == 1 { PhiSource::Input } else { PhiSource::Law }
                    }
                    Var::MaxOrder => self.max_order = k,
                    Var::FixedOrder => self.fixed_order = k,
                    Var::PhiExtrapolation => self.phi_extrapolation = k,
                    Var::PhiInterpolation => {
                        self.phi_interpolation = Interpolation::ALL[(k - 1) as usize]
                    }
                    Var::RangeCheck => self.range_check = RangeCheck::ALL[(k - 1) as usize],
                    _ => unreachable!("checked by type"),
                }
            }
            Value::Boolean(b) => match var.var {
                Var::StabilityGuard => self.stability_guard = b,
                _ => unreachable!("checked by type"),
            },
        }
        Ok(())
    }

    /// The value of a parameter or the input.
    pub(super) fn get(&self, var: Var) -> Option<Value> {
        let p = &self.params;
        Some(match var {
            Var::L => Value::Real(p.l),
            Var::Ei => Value::Real(p.ei),
            Var::M => Value::Real(p.m),
            Var::M2 => Value::Real(p.m2),
            Var::JC => Value::Real(p.j_c),
            Var::R => Value::Real(p.r),
            Var::G => Value::Real(p.g),
            Var::TRot => Value::Real(self.law.t_rot),
            Var::PhiEnd => Value::Real(self.law.phi_end),
            Var::Atol => Value::Real(self.atol),
            Var::FixedStep => Value::Real(self.fixed_step),
            Var::Phi => Value::Real(self.phi),
            Var::Formulation => {
                let k = Formulation::ALL.iter().position(|f| *f == self.formulation);
                Value::Integer(k.expect("every formulation is listed") as i32 + 1)
            }
            Var::PhiSource => Value::Integer(match self.phi_source {
                PhiSource::Input => 1,
                PhiSource::Law => 2,
            }),
            Var::MaxOrder => Value::Integer(self.max_order),
            Var::FixedOrder => Value::Integer(self.fixed_order),
            Var::PhiExtrapolation => Value::Integer(self.phi_extrapolation),
            Var::PhiInterpolation => {
                let k = Interpolation::ALL.iter().position(|i| *i == self.phi_interpolation);
                Value::Integer(k.expect("every interpolation is listed") as i32 + 1)
            }
            Var::RangeCheck => {
                let k = RangeCheck::ALL.iter().position(|r| *r == self.range_check);
                Value::Integer(k.expect("every range check is listed") as i32 + 1)
            }
            Var::StabilityGuard => Value::Boolean(self.stability_guard),
            _ => return None,
        })
    }

    /// The integrator settings, with the experiment's relative tolerance.
    pub(super) fn solver_settings(&self, rtol: f64) -> BdfConfig {
        BdfConfig {
            rtol,
            atol: (self.atol > 0.0).then_some(self.atol),
            max_order: self.max_order as usize,
            fixed_step: (self.fixed_step > 0.0)
                .then_some(FixedStep { h: self.fixed_step, order: self.fixed_order as usize }),
            stability_guard: self.stability_guard,
            max_steps: MAX_STEPS_PER_DO_STEP,
            ..BdfConfig::default()
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
