//! The one table of settings: every number, choice and switch a run takes, with its name,
//! unit, kind, range, default and description, and where it appears (a scene key always; an
//! FMU parameter, a study parameter, a CLI flag where marked).
//!
//! Every setting is declared once, in `table.rs` (`for_each_setting!`), and everything else
//! is derived from that: [`Key`] and [`SETTINGS`], the scene's fields by key and
//! [`Scene::default`](crate::scene::Scene), the model's defaults and ranges (`field.rs`), the
//! FMU's parameters and so `modelDescription.xml` (`fmu::variables`), the study's parameters,
//! and the CLI's flags and help. A new setting is an entry there and its field in
//! [`Scene`](crate::scene::Scene). No I/O, no `unsafe`.
#![forbid(unsafe_code)]

mod field;
mod table;

pub use crate::choice::EnumType;
use crate::range::Range;
pub use field::Field;
pub(crate) use field::{choice_field, fields_of, with_settings};
pub(crate) use table::for_each_setting;
pub use table::*;

/// What kind of value a setting holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// A real number in a unit (`None`: dimensionless, or a value in each state's unit).
    Real {
        unit: Option<&'static str>,
    },
    Integer,
    /// One item of an enumeration.
    Choice(&'static EnumType),
    Bool,
}

/// A setting's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Real(f64),
    Integer(i64),
    /// The index of an item (0-based).
    Choice(usize),
    Bool(bool),
}

/// The groups of settings, for the lists of the docs (`cargo xtask gen`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    Model,
    Law,
    Initial,
    Input,
    Solver,
    Checks,
    Run,
}

impl Group {
    /// Every group, in the order the docs list them.
    pub const ALL: [Group; 7] = [
        Group::Model,
        Group::Law,
        Group::Initial,
        Group::Solver,
        Group::Checks,
        Group::Input,
        Group::Run,
    ];

    /// The group's title in the docs.
    pub const fn title(self) -> &'static str {
        match self {
            Group::Model => "the model",
            Group::Law => "the law of φ (`phi_source = law`)",
            Group::Initial => "the initial state",
            Group::Input => "φ from a host (`phi_source = input`)",
            Group::Solver => "the equations and the solver",
            Group::Checks => "the checks",
            Group::Run => "the run and its output",
        }
    }
}

/// Where a setting appears besides the scene (every setting is a scene key).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Appears {
    /// A parameter of the FMU (fixed, set before initialization).
    pub fmu: bool,
    /// A parameter a design study can vary.
    pub study: bool,
    /// A flag of the CLI's `simulate`, `--flag VALUE`, besides `--set NAME=VALUE`.
    pub flag: Option<&'static str>,
    /// A key of a study file's top level (`rtol = 1e-8`), besides `[set]`.
    pub study_key: bool,
}

/// One row of the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setting {
    pub key: Key,
    pub name: &'static str,
    pub kind: Kind,
    /// The allowed values of a real or an integer (unused for choices and switches).
    pub range: Range,
    pub default: Value,
    pub description: &'static str,
    pub appears: Appears,
    /// The FMU's start value where it differs from `default` (only `phi_source`).
    pub fmu_start: Option<Value>,
}

impl Setting {
    /// The unit, for the FMU, the CSV headers and the help (`None`: none).
    pub const fn unit(&self) -> Option<&'static str> {
        match self.kind {
            Kind::Real { unit } => unit,
            _ => None,
        }
    }

    /// The allowed values in words, for messages and the help.
    pub fn allowed(&self) -> String {
        match self.kind {
            Kind::Real { .. } | Kind::Integer => self.range.to_string(),
            Kind::Choice(ty) => format!("one of {}", ty.names()),
            Kind::Bool => "true or false".to_string(),
        }
    }

    /// A value as the user writes it: a number, an item's name, true or false.
    pub fn show(&self, value: Value) -> String {
        match (value, self.kind) {
            (Value::Real(x), _) => format!("{x:?}"),
            (Value::Integer(k), _) => k.to_string(),
            (Value::Choice(k), Kind::Choice(ty)) => {
                ty.items.get(k).map_or_else(|| format!("item {k}"), |i| i.0.to_string())
            }
            (Value::Choice(k), _) => format!("item {k}"),
            (Value::Bool(b), _) => b.to_string(),
        }
    }

    /// Checks `value` against the kind and the range; the error names the setting and what it
    /// allows.
    pub fn check(&self, value: Value) -> Result<Value, String> {
        let ok = match (self.kind, value) {
            (Kind::Real { .. }, Value::Real(x)) => self.range.contains(x),
            (Kind::Integer, Value::Integer(k)) => self.range.contains(k as f64),
            (Kind::Choice(ty), Value::Choice(k)) => k < ty.items.len(),
            (Kind::Bool, Value::Bool(_)) => true,
            _ => return Err(format!("`{}`: must be {}", self.name, self.expects())),
        };
        if ok {
            Ok(value)
        } else {
            Err(format!(
                "`{}` = {} is out of range: must be {}",
                self.name,
                self.show(value),
                self.allowed()
            ))
        }
    }

    /// What the setting takes, for a value of the wrong type: "a number (positive and
    /// finite) [m]", "one of reduced, dae, ...".
    pub fn expects(&self) -> String {
        match self.kind {
            Kind::Real { unit } => {
                let unit = unit.map_or(String::new(), |u| format!(" [{u}]"));
                format!("a number, {}{unit}", self.range)
            }
            Kind::Integer => self.range.to_string(),
            Kind::Choice(ty) => format!("one of {}", ty.names()),
            Kind::Bool => "true or false".to_string(),
        }
    }

    /// Parses a value from the command line's text: a number, an item's name, true or false.
    pub fn parse(&self, text: &str) -> Result<Value, String> {
        let text = text.trim();
        let value = match self.kind {
            Kind::Real { .. } => parse_number(text).map(Value::Real),
            Kind::Integer => text.replace('_', "").parse::<i64>().ok().map(Value::Integer),
            Kind::Choice(ty) => {
                let name = text.trim_matches(|c| c == '"' || c == '\'');
                ty.index(name).map(Value::Choice)
            }
            Kind::Bool => match text {
                "true" => Some(Value::Bool(true)),
                "false" => Some(Value::Bool(false)),
                _ => None,
            },
        };
        let value =
            value.ok_or_else(|| format!("`{}` = {text}: must be {}", self.name, self.expects()))?;
        self.check(value)
    }

    /// The FMU's start value.
    pub const fn fmu_default(&self) -> Value {
        match self.fmu_start {
            Some(v) => v,
            None => self.default,
        }
    }

    /// The row of `key`.
    pub const fn of(key: Key) -> &'static Setting {
        &SETTINGS[key as usize]
    }

    /// The row called `name`; the error lists every name.
    pub fn by_name(name: &str) -> Result<&'static Setting, String> {
        SETTINGS.iter().find(|s| s.name == name).ok_or_else(|| {
            let names: Vec<&str> = SETTINGS.iter().map(|s| s.name).collect();
            format!("unknown setting `{name}`: must be one of {}", names.join(", "))
        })
    }
}

/// A number as TOML or Rust writes it: `1e-6`, `1_000`, `0.5`, `-3`. Underscores only between
/// digits, as in TOML.
fn parse_number(text: &str) -> Option<f64> {
    let bytes = text.as_bytes();
    let digit = |i: usize| bytes.get(i).is_some_and(u8::is_ascii_digit);
    let ok = (0..bytes.len()).all(|i| bytes[i] != b'_' || (i > 0 && digit(i - 1) && digit(i + 1)));
    if !ok {
        return None;
    }
    text.replace('_', "").parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_in_key_order_with_unique_names_and_valid_defaults() {
        for (k, s) in SETTINGS.iter().enumerate() {
            assert_eq!(s.key as usize, k, "{}", s.name);
            assert_eq!(SETTINGS.iter().filter(|t| t.name == s.name).count(), 1, "{}", s.name);
            assert_eq!(s.check(s.default), Ok(s.default), "{}", s.name);
            assert_eq!(s.check(s.fmu_default()), Ok(s.fmu_default()), "{}", s.name);
            assert!(!s.description.is_empty(), "{}", s.name);
        }
    }

    #[test]
    fn parse_takes_what_a_user_types_and_names_the_setting() {
        let ei = Setting::of(Key::Ei);
        assert_eq!(ei.parse("1_000"), Ok(Value::Real(1000.0)));
        assert_eq!(ei.parse(" 2e3 "), Ok(Value::Real(2000.0)));
        let e = ei.parse("0").unwrap_err();
        assert_eq!(e, "`EI` = 0.0 is out of range: must be positive and finite");
        let e = ei.parse("exact").unwrap_err();
        assert!(e.contains("`EI` = exact: must be a number, positive and finite [N.m2]"), "{e}");
        assert!(ei.parse("1__0").is_err() && ei.parse("_1").is_err());
        let f = Setting::of(Key::Formulation);
        assert_eq!(f.parse("dae_stabilized"), Ok(Value::Choice(2)));
        let e = f.parse("dae-stabilized").unwrap_err();
        assert!(e.contains("one of reduced, dae, dae_stabilized, linear"), "{e}");
        assert_eq!(
            Setting::of(Key::MaxOrder).parse("6").unwrap_err(),
            "`max_order` = 6 is out of range: must be an integer in 1..=5"
        );
        assert!(Setting::by_name("beam_theory")
            .unwrap_err()
            .starts_with("unknown setting `beam_theory`"));
    }
}
