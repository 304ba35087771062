//! The values of the FMU's parameters and its input: the settings of a run (a [`Scene`],
//! as the CLI has them) and the host's sample of φ, with the derivatives it sent for the next
//! step. Get, check and set by variable, with FMI's conventions (enumerations 1-based).
#![forbid(unsafe_code)]

use super::variables::{Causality, Var, Variable};
use crate::fmi::Value;
use crate::model::Sample;
use crate::scene::Scene;
use crate::settings::{self, Kind, Setting};

/// The values of the parameters and the input.
#[derive(Clone, Debug, PartialEq)]
pub struct Values {
    pub settings: Scene,
    /// The input φ and the derivatives sent for the next step only; its time is the step's.
    pub input: Sample,
    /// The inputs `dphi` and `ddphi` as the host set them last (Model Exchange's φ′, φ″;
    /// co-simulation does not use them).
    pub rates: [f64; 2],
    /// Whether the host has set `dphi` or `ddphi`: Model Exchange then takes φ′ and φ″ from
    /// them, else from its filter of φ.
    pub rates_set: bool,
}

/// A setting's value as FMI has it: enumerations are 1-based.
fn to_fmi(value: settings::Value) -> Value {
    match value {
        settings::Value::Real(x) => Value::Real(x),
        settings::Value::Integer(k) => Value::Integer(k.into()),
        settings::Value::Choice(k) => Value::Integer(k as i128 + 1),
        settings::Value::Bool(b) => Value::Boolean(b),
    }
}

/// An FMI value as the setting's value; the base type is checked before.
fn from_fmi(setting: &Setting, value: Value) -> Result<settings::Value, String> {
    Ok(match (setting.kind, value) {
        (Kind::Choice(ty), Value::Integer(k)) => {
            let n = ty.items.len() as i128;
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
        // Beyond i64, beyond every setting's range.
        (_, Value::Integer(k)) => match i64::try_from(k) {
            Ok(k) => settings::Value::Integer(k),
            Err(_) => {
                return Err(format!(
                    "`{}` = {k} is out of range: must be {}",
                    setting.name,
                    setting.allowed()
                ))
            }
        },
        (_, Value::Real(x)) => settings::Value::Real(x),
        (_, Value::Boolean(b)) => settings::Value::Bool(b),
    })
}

/// An input (`phi`, `dphi`, `ddphi`) must be finite.
pub(super) fn check_input(var: &Variable, x: f64) -> Result<(), String> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(format!("`{}` = {x:?} is out of range: must be finite", var.name))
    }
}

/// The index in [`Values::rates`] of the inputs `dphi` and `ddphi`.
fn rate(var: Var) -> Option<usize> {
    match var {
        Var::Dphi => Some(0),
        Var::Ddphi => Some(1),
        _ => None,
    }
}

impl Values {
    /// The start values: the settings table's (the FMU's where they differ), and φ = 0.
    pub fn from_table() -> Values {
        let mut settings = Scene::default();
        for s in settings::SETTINGS.iter().filter(|s| s.fmu_start.is_some()) {
            settings.set(s.key, s.fmu_default()).expect("the table's start values are in range");
        }
        Values { settings, input: Sample::value(0.0, 0.0), rates: [0.0; 2], rates_set: false }
    }

    /// Checks that `var` takes `value`; the error names the variable and the allowed range.
    pub fn check(&self, var: &Variable, value: Value) -> Result<(), String> {
        match (var.setting, value) {
            (Some(key), _) => Setting::of(key).check(from_fmi(Setting::of(key), value)?).map(drop),
            (None, Value::Real(x)) if var.causality == Causality::Input => check_input(var, x),
            _ => unreachable!("outputs are rejected before, other types by type"),
        }
    }

    /// Sets `var` after checking the value's range.
    pub fn set(&mut self, var: &Variable, value: Value) -> Result<(), String> {
        match (var.setting, value) {
            (Some(key), _) => {
                let value = from_fmi(Setting::of(key), value)?;
                self.settings.set(key, value)
            }
            (None, Value::Real(x)) if var.causality == Causality::Input => {
                check_input(var, x)?;
                // `dphi` and `ddphi` are Model Exchange's; co-simulation takes derivatives
                // through fmi2SetRealInputDerivatives only (docs/decisions.md).
                match rate(var.var) {
                    Some(k) => {
                        self.rates[k] = x;
                        self.rates_set = true;
                    }
                    None => self.input.phi = x,
                }
                Ok(())
            }
            _ => unreachable!("outputs are rejected before, other types by type"),
        }
    }

    /// The value of a parameter or the input; `None` for an output.
    pub fn get(&self, var: &Variable) -> Option<Value> {
        match var.setting {
            Some(key) => Some(to_fmi(self.settings.get(key))),
            None if var.var == Var::Phi => Some(Value::Real(self.input.phi)),
            None => rate(var.var).map(|k| Value::Real(self.rates[k])),
        }
    }
}
