//! The one table of settings: every number, choice and switch a run takes, with its name,
//! unit, kind, range, default and description, and where it appears (a scene key always; an
//! FMU parameter, a study parameter, a CLI flag where marked).
//!
//! Everything else is derived from [`SETTINGS`]: the FMU's parameters and so
//! `modelDescription.xml` (`fmu::variables`), [`Scene::default`](crate::scene::Scene) and
//! its `set`, the study's list of parameters, and the CLI's flags and help. A new setting is
//! a row here and its field in [`Scene`](crate::scene::Scene). No I/O, no `unsafe`.
#![forbid(unsafe_code)]

pub use crate::choice::EnumType;
use crate::range::Range;

pub const FORMULATION_TYPE: EnumType = EnumType {
    name: "Formulation",
    description: "Which equations of the paper are integrated",
    items: &[
        ("reduced", "eq. (15): hinge constraints exact, 2 DOF, u2 = u1(v1, theta1)"),
        ("dae", "eq. (20)+(21): u2 integrated with the constraint differentiated twice; drifts"),
        ("dae_stabilized", "eq. (20)+(21) projected onto u2 = u1, du2 = du1 after every step"),
        ("linear", "eq. (16): linearised in v1, theta1; phi exact"),
    ],
};

pub const PHI_SOURCE_TYPE: EnumType = EnumType {
    name: "PhiSource",
    description: "Where the hinge angle phi(t) comes from",
    items: &[
        ("input", "the input phi, with its derivatives if the host sends them"),
        ("law", "the paper's law phi0 + phi_end*sin^2(pi*t/(2*t_rot)), then held"),
    ],
};

pub const PHI_INTERPOLATION_TYPE: EnumType = EnumType {
    name: "PhiInterpolation",
    description: "How the input phi is interpolated between communication points",
    items: &[
        (
            "smooth",
            "pieces joined with continuous phi, phi' and phi'' to a target extrapolated from the \
             last values and sent derivatives; jumps of the signal restart the integrator",
        ),
        (
            "taylor",
            "FMI's polynomial phi + phi'*s + phi''*s^2/2 from the sent derivatives over each step \
             (with values only, a cubic to the extrapolated value and slope)",
        ),
    ],
};

pub const RANGE_CHECK_TYPE: EnumType = EnumType {
    name: "RangeCheck",
    description: "What a step does when the state leaves the range of validity of the equations \
                  (the quadratic beam: |v1| <= l, |theta1| <= pi/2, the dae formulation's drift; \
                  the exact beam: a centreline that crosses itself)",
    items: &[
        ("stop", "the run ends there with a message (the FMU: Discard)"),
        ("warn", "a warning, once (the FMU: Warning); the run goes on"),
        ("off", "the run goes on; a state that is not a number still ends it"),
    ],
};

pub const ENERGY_CHECK_TYPE: EnumType = EnumType {
    name: "EnergyCheck",
    description: "What a step does when the energy balance breaks: the energy's change no longer \
                  matches the work of the drive and of the damping within a bound scaled by the \
                  tolerance (numerical instability)",
    items: &[
        ("stop", "the run ends there with a message (the FMU: Discard)"),
        ("warn", "a warning, once (the FMU: Warning); the run goes on"),
        ("off", "no check"),
    ],
};

pub const COLUMNS_TYPE: EnumType = EnumType {
    name: "Columns",
    description: "The columns of a CLI run's CSV",
    items: &[
        ("paper", "time, the tip's motion, phi, the hinge reactions, energy and drift"),
        (
            "beam",
            "those, then the root's bending moment and shear force and the deflection at l/4, \
             l/2, 3l/4",
        ),
        (
            "shape",
            "those, then every node's deflection and slope, v_k and theta_k at x = k*l/n, k = \
             1..n (node n is the tip; the exact beam: at the arc length k*l/n)",
        ),
    ],
};

pub const BEAM_TYPE: EnumType = EnumType {
    name: "Beam",
    description: "The beam's theory",
    items: &[
        (
            "quadratic",
            "the paper's: deflection v(x), the geometric nonlinearity kept to second order (u = -1/2 int v'^2), no axial inertia; valid for |v1| <= l, |theta1| <= pi/2",
        ),
        (
            "exact",
            "the inextensible elastica in the section angle alpha(s), with the beam's axial inertia: valid at any rotation (formulation reduced)",
        ),
    ],
};

/// Every enumeration of the FMU's table, in the order of the model description.
pub const ENUM_TYPES: &[EnumType] = &[
    FORMULATION_TYPE,
    PHI_SOURCE_TYPE,
    PHI_INTERPOLATION_TYPE,
    RANGE_CHECK_TYPE,
    BEAM_TYPE,
    ENERGY_CHECK_TYPE,
];

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

/// A field that holds a setting: its value as the table has it, and back.
pub trait Field: Sized {
    fn value(&self, kind: Kind) -> Value;
    /// The field's value from one the table has checked.
    fn from_value(value: Value) -> Self;
}

impl Field for f64 {
    fn value(&self, _: Kind) -> Value {
        Value::Real(*self)
    }
    fn from_value(value: Value) -> Self {
        if let Value::Real(x) = value {
            x
        } else {
            f64::NAN
        }
    }
}

impl Field for bool {
    fn value(&self, _: Kind) -> Value {
        Value::Bool(*self)
    }
    fn from_value(value: Value) -> Self {
        matches!(value, Value::Bool(true))
    }
}

/// A count, or the index of an item where the setting is a choice (`columns`).
impl Field for usize {
    fn value(&self, kind: Kind) -> Value {
        match kind {
            Kind::Choice(_) => Value::Choice(*self),
            _ => Value::Integer(*self as i64),
        }
    }
    fn from_value(value: Value) -> Self {
        match value {
            Value::Integer(k) => k.max(0) as usize,
            Value::Choice(k) => k,
            _ => 0,
        }
    }
}

impl Field for u64 {
    fn value(&self, _: Kind) -> Value {
        Value::Integer(*self as i64)
    }
    fn from_value(value: Value) -> Self {
        if let Value::Integer(k) = value {
            k.max(0) as u64
        } else {
            0
        }
    }
}

/// [`Field`] for enumerations, each with `ALL`, its items in the order of its [`EnumType`]: the
/// value is the item's index.
macro_rules! choice_field {
    ($($t:ty),*) => {$(
        impl $crate::settings::Field for $t {
            fn value(&self, _: $crate::settings::Kind) -> $crate::settings::Value {
                let k = <$t>::ALL.iter().position(|a| a == self).expect("every item is listed");
                $crate::settings::Value::Choice(k)
            }
            fn from_value(value: $crate::settings::Value) -> Self {
                let k = if let $crate::settings::Value::Choice(k) = value { k } else { 0 };
                <$t>::ALL[k.min(<$t>::ALL.len() - 1)]
            }
        }
    )*};
}
pub(crate) use choice_field;

/// The settings held in one of the scene's parts (`params`, `law`), as `Key field` pairs, for
/// the part's `Default` (the table's defaults) and `validate` (the table's ranges), which
/// `with_settings!` writes: `for_each_setting!(fields_of, params Params)`.
macro_rules! fields_of {
    (@go $part:ident $ty:ident [$($key:ident $f:ident)*]) => {
        $crate::settings::with_settings!($ty $($key $f)*);
    };
    (@go params $ty:ident [$($acc:tt)*]
        $key:ident { field: params.$f:ident, $($rest:tt)* } $($tail:tt)*) => {
        $crate::settings::fields_of!(@go params $ty [$($acc)* $key $f] $($tail)*);
    };
    (@go law $ty:ident [$($acc:tt)*]
        $key:ident { field: law.$f:ident, $($rest:tt)* } $($tail:tt)*) => {
        $crate::settings::fields_of!(@go law $ty [$($acc)* $key $f] $($tail)*);
    };
    (@go $part:ident $ty:ident [$($acc:tt)*] $key:ident { $($rest:tt)* } $($tail:tt)*) => {
        $crate::settings::fields_of!(@go $part $ty [$($acc)*] $($tail)*);
    };
    ($part:ident $ty:ident $($entries:tt)*) => {
        $crate::settings::fields_of!(@go $part $ty [] $($entries)*);
    };
}
pub(crate) use fields_of;

/// `Default` and `validate` of a part whose every field is a setting: the defaults and the
/// ranges of the table, written once there. `validate` returns the first setting out of its
/// range, in the table's order, through `check_setting` (in scope where it is used).
macro_rules! with_settings {
    ($ty:ident $($key:ident $f:ident)*) => {
        impl Default for $ty {
            /// The settings' defaults: the paper's example (§4).
            fn default() -> Self {
                use $crate::settings::{Field, Key, Setting};
                $ty { $($f: Field::from_value(Setting::of(Key::$key).default),)* }
            }
        }

        impl $ty {
            /// Checks every range, the settings table's (which checks them too, before; the
            /// model checks what it is given).
            pub fn validate(&self) -> Result<(), ParamError> {
                use $crate::settings::Key;
                $(check_setting(Key::$key, &self.$f)?;)*
                Ok(())
            }
        }
    };
}
pub(crate) use with_settings;

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

const fn real(unit: &'static str) -> Kind {
    Kind::Real { unit: Some(unit) }
}

const NOWHERE: Appears = Appears { fmu: false, study: false, flag: None, study_key: false };
const FMU: Appears = Appears { fmu: true, ..NOWHERE };
/// A number of the model, the law or the initial state: an FMU parameter a study can vary.
const PHYSICAL: Appears = Appears { fmu: true, study: true, ..NOWHERE };

const fn flag(fmu: bool, flag: &'static str) -> Appears {
    Appears { fmu, flag: Some(flag), ..NOWHERE }
}

/// A flag of the CLI and a key of a study file's top level.
const fn study_key(fmu: bool, flag: &'static str) -> Appears {
    Appears { study_key: true, ..self::flag(fmu, flag) }
}

use crate::solver::{ORDER_RANGE, RTOL_RANGE};
use Range::{Finite, Integers, NonNegative, Positive};
use Value::{Bool, Choice, Integer, Real};

/// The one declaration of every setting, in the order of [`Key`]: its key, then the
/// [`Scene`](crate::scene::Scene) field that holds it, its name, kind, range (of a number),
/// default, group, where it appears, its FMU start value where that differs from the default,
/// and its description. Each use passes a macro that takes the list (the X-macro pattern): [`Key`],
/// [`SETTINGS`] and [`Key::group`] here, the scene's `get` and `put` in `scene.rs`. Defaults
/// are the paper's example (§4).
macro_rules! for_each_setting {
    ($use:ident $(, $($arg:tt)*)?) => {
        $use! {
        $($($arg)*)?
        L {
            field: params.l,
            name: "l", kind: real("m"), range: Positive, default: Real(2.5), group: Model,
            appears: PHYSICAL,
            description: "Beam length",
        }
        Ei {
            field: params.ei,
            name: "EI", kind: real("N.m2"), range: Positive, default: Real(1000.0), group: Model,
            appears: PHYSICAL,
            description: "Bending stiffness",
        }
        M {
            field: params.m,
            name: "m", kind: real("kg/m"), range: NonNegative, default: Real(2.0), group: Model,
            appears: PHYSICAL,
            description: "Beam mass per unit length",
        }
        M2 {
            field: params.m2,
            name: "M2", kind: real("kg"), range: Positive, default: Real(12.0), group: Model,
            appears: PHYSICAL,
            description: "Mass of the rigid body",
        }
        JC {
            field: params.j_c,
            name: "J_C", kind: real("kg.m2"), range: NonNegative, default: Real(1.0), group: Model,
            appears: PHYSICAL,
            description: "Moment of inertia of the body about its centre of mass",
        }
        R {
            field: params.r,
            name: "r", kind: real("m"), range: NonNegative, default: Real(0.5), group: Model,
            appears: PHYSICAL,
            description: "Hinge-to-centre-of-mass distance",
        }
        G {
            field: params.g,
            name: "g", kind: real("m/s2"), range: Finite, default: Real(10.0), group: Model,
            appears: PHYSICAL,
            description: "Gravity along the undeformed beam axis (> 0 stretches the beam)",
        }
        NElements {
            field: params.n_elements,
            name: "n_elements", kind: Kind::Integer, range: Integers(1, MAX_ELEMENTS as i64),
            default: Integer(1), group: Model,
            appears: Appears { flag: Some("--elements"), ..PHYSICAL },
            description: "Cubic Hermite elements of the beam: 1 is the paper's model (2 \
coordinates), n has 2n",
        }
        DampingAlpha {
            field: params.damping_alpha,
            name: "damping_alpha", kind: real("1/s"), range: NonNegative, default: Real(0.0),
            group: Model, appears: PHYSICAL,
            description: "Rayleigh damping of the beam: alpha times its mass matrix (0: none, as \
in the paper)",
        }
        DampingBeta {
            field: params.damping_beta,
            name: "damping_beta", kind: real("s"), range: NonNegative, default: Real(0.0),
            group: Model, appears: PHYSICAL,
            description: "Rayleigh damping of the beam: beta times its stiffness matrix (0: none, \
as in the paper)",
        }
        DampingRatio {
            field: params.damping_ratio,
            name: "damping_ratio", kind: Kind::Real { unit: None }, range: NonNegative,
            default: Real(0.0), group: Model, appears: PHYSICAL,
            description: "Rayleigh damping of the beam set by the damping ratio zeta of its own \
first two modes (the cantilever without the body); alpha and beta follow: give \
either this or them",
        }
        Beam {
            field: params.beam,
            name: "beam", kind: Kind::Choice(&BEAM_TYPE), range: Finite, default: Choice(0),
            group: Model, appears: flag(true, "--beam"),
            description: "The beam's theory: quadratic (the paper's cut at second order) or exact \
(the inextensible elastica, valid at any rotation)",
        }
        BeamGravity {
            field: params.beam_gravity,
            name: "beam_gravity", kind: Kind::Bool, range: Finite, default: Bool(false),
            group: Model, appears: FMU,
            description: "Gravity on the beam itself, g per unit length m along +x (the paper \
leaves it out)",
        }
        TRot {
            field: law.t_rot,
            name: "t_rot", kind: real("s"), range: Positive, default: Real(0.85), group: Law,
            appears: PHYSICAL,
            description: "Duration of the turn of the built-in law (phi_source = law)",
        }
        PhiEnd {
            field: law.phi_end,
            name: "phi_end", kind: real("rad"), range: Finite, default: Real(std::f64::consts::PI),
            group: Law, appears: PHYSICAL,
            description: "Angle turned by the built-in law (phi_source = law)",
        }
        Phi0 {
            field: law.phi0,
            name: "phi0", kind: real("rad"), range: Finite, default: Real(0.0), group: Law,
            appears: PHYSICAL,
            description: "Angle of the body at t = 0 under the built-in law, from which it turns \
by phi_end",
        }
        V10 {
            field: initial.v1,
            name: "v1_0", kind: real("m"), range: Finite, default: Real(0.0), group: Initial,
            appears: PHYSICAL,
            description: "Tip deflection at the start",
        }
        Theta10 {
            field: initial.theta1,
            name: "theta1_0", kind: real("rad"), range: Finite, default: Real(0.0), group: Initial,
            appears: PHYSICAL,
            description: "Rotation of the tip section at the start",
        }
        Dv10 {
            field: initial.dv1,
            name: "dv1_0", kind: real("m/s"), range: Finite, default: Real(0.0), group: Initial,
            appears: PHYSICAL,
            description: "Rate of v1 at the start",
        }
        Dtheta10 {
            field: initial.dtheta1,
            name: "dtheta1_0", kind: real("rad/s"), range: Finite, default: Real(0.0),
            group: Initial, appears: PHYSICAL,
            description: "Rate of theta1 at the start",
        }
        Formulation {
            field: formulation,
            name: "formulation", kind: Kind::Choice(&FORMULATION_TYPE), range: Finite,
            default: Choice(0), group: Solver, appears: study_key(true, "--formulation"),
            description: "Equations integrated: reduced (15), dae (20-21), dae_stabilized, linear \
(16)",
        }
        PhiSource {
            field: phi_source,
            name: "phi_source", kind: Kind::Choice(&PHI_SOURCE_TYPE), range: Finite,
            default: Choice(1), group: Input, appears: FMU, fmu_start: Choice(0),
            description: "Source of the hinge angle: the input phi (the FMU's default), or the \
paper's law (the CLI's default; the CLI's input is the law sampled as a host \
would, every dt_comm)",
        }
        PhiInterpolation {
            field: phi_interpolation,
            name: "phi_interpolation", kind: Kind::Choice(&PHI_INTERPOLATION_TYPE), range: Finite,
            default: Choice(0), group: Input, appears: FMU,
            description: "Interpolation of the input phi between communication points: smooth or \
taylor",
        }
        PhiExtrapolation {
            field: phi_extrapolation,
            name: "phi_extrapolation", kind: Kind::Integer, range: Integers(0, 3),
            default: Integer(3), group: Input, appears: FMU,
            description: "Degree of the polynomial through the last input values that gives phi \
over a step when the host sends no derivatives",
        }
        IntermediateStep {
            field: intermediate_step,
            name: "intermediate_step", kind: real("s"), range: NonNegative, default: Real(1e-3),
            group: Input, appears: FMU,
            description: "FMI 3.0 co-simulation, phi_source = input, with the host's \
intermediate-update callback: fmi3DoStep asks the host for phi every \
intermediate_step inside a communication step (the last part up to 1.25 times as \
long); 0 asks only at the communication points",
        }
        InputDerivatives {
            field: input_derivatives,
            name: "input_derivatives", kind: Kind::Bool, range: Finite, default: Bool(false),
            group: Input, appears: NOWHERE,
            description: "CLI, phi_source = input: the emulated host also sends phi' and phi'' at \
every communication point (fmi2SetRealInputDerivatives)",
        }
        DtComm {
            field: dt_comm,
            name: "dt_comm", kind: real("s"), range: Positive, default: Real(0.01), group: Input,
            appears: NOWHERE,
            description: "CLI, phi_source = input: the emulated host's communication step",
        }
        Rtol {
            field: solver.rtol,
            name: "rtol", kind: Kind::Real { unit: None }, range: RTOL_RANGE, default: Real(1e-6),
            group: Solver, appears: study_key(false, "--rtol"),
            description: "Relative tolerance of the integrator (the FMU takes \
fmi2SetupExperiment's)",
        }
        Atol {
            field: solver.atol,
            name: "atol", kind: Kind::Real { unit: None }, range: NonNegative, default: Real(0.0),
            group: Solver, appears: study_key(true, "--atol"),
            description: "Absolute tolerance of the integrator for every state, in its SI unit; 0 \
selects 1e-3 times the relative tolerance",
        }
        MaxOrder {
            field: solver.max_order,
            name: "max_order", kind: Kind::Integer, range: ORDER_RANGE, default: Integer(5),
            group: Solver, appears: flag(true, "--max-order"),
            description: "Highest order of the adaptive BDF",
        }
        FixedStep {
            field: solver.fixed_step,
            name: "fixed_step", kind: real("s"), range: NonNegative, default: Real(0.0),
            group: Solver, appears: flag(true, "--fixed-step"),
            description: "Constant internal step of the paper's fixed-step BDF; 0 selects the \
adaptive BDF",
        }
        FixedOrder {
            field: solver.fixed_order,
            name: "fixed_order", kind: Kind::Integer, range: Integers(0, 5), default: Integer(0),
            group: Solver, appears: flag(true, "--fixed-order"),
            description: "Order of the fixed-step BDF, needs fixed_step > 0; 0 selects order 2",
        }
        StabilityGuard {
            field: solver.stability_guard,
            name: "stability_guard", kind: Kind::Bool, range: Finite, default: Bool(true),
            group: Solver, appears: flag(true, "--stability-guard"),
            description: "Cap the BDF order where an undamped mode would be amplified by BDF3-5",
        }
        RangeCheck {
            field: range_check,
            name: "range_check", kind: Kind::Choice(&RANGE_CHECK_TYPE), range: Finite,
            default: Choice(0), group: Checks, appears: FMU,
            description: "Outside the range of validity (|v1| <= l, |theta1| <= pi/2, ...; the \
exact beam: a centreline that crosses itself): stop, warn or off",
        }
        EnergyCheck {
            field: energy_check,
            name: "energy_check", kind: Kind::Choice(&ENERGY_CHECK_TYPE), range: Finite,
            default: Choice(0), group: Checks, appears: FMU,
            description: "When the energy balance breaks (the energy's change against the work of \
the drive and the damping, after every step, within 100 rtol of the energy \
handled, at most 10 %): the run is numerically unstable; stop, warn or off",
        }
        PhiFilterFrequency {
            field: phi_filter_frequency,
            name: "phi_filter_frequency", kind: real("Hz"), range: Positive,
            default: Real(PHI_FILTER_FREQUENCY), group: Input, appears: FMU,
            description: "Model Exchange with phi_source = input, when the host sets phi but not \
dphi and ddphi: the cut-off frequency of the second-order filter whose states \
give phi, phi' and phi'' from phi (Modelica's Rotational.Sources.Position with \
exact = false); a host that sets dphi and ddphi gets them as it sends them",
        }
        TEnd {
            field: t_end,
            name: "t_end", kind: real("s"), range: Positive, default: Real(10.0), group: Run,
            appears: NOWHERE,
            description: "End time of a CLI run",
        }
        DtOut {
            field: dt_out,
            name: "dt_out", kind: real("s"), range: Positive, default: Real(0.01), group: Run,
            appears: NOWHERE,
            description: "Output step of a CLI run: rows at t = k*dt_out and at t_end",
        }
        MaxRows {
            field: max_rows,
            name: "max_rows", kind: Kind::Integer, range: Integers(1, 1 << 53),
            default: Integer(MAX_ROWS_DEFAULT), group: Run, appears: flag(false, "--max-rows"),
            description: "Most output rows a CLI run or a study case may have (t_end/dt_out + 1); \
a run that would have more is refused before it starts",
        }
        Columns {
            field: columns,
            name: "columns", kind: Kind::Choice(&COLUMNS_TYPE), range: Finite, default: Choice(0),
            group: Run, appears: flag(false, "--columns"),
            description: "Columns of a CLI run's CSV: paper (the default), beam (and the loads at \
the root and the deflection at the quarter points; the FMU has them as outputs), \
or shape (and the nodes' deflections and slopes, for pictures)",
        }
        }
    };
}
pub(crate) use for_each_setting;

/// `Some` of an optional macro argument.
macro_rules! optional {
    () => {
        None
    };
    ($e:expr) => {
        Some($e)
    };
}

/// [`Key`], [`Key::group`] and [`SETTINGS`] from the declaration.
macro_rules! declare {
    ($($key:ident {
        field: $($field:ident).+,
        name: $name:literal, kind: $kind:expr, range: $range:expr, default: $default:expr,
        group: $group:ident, appears: $appears:expr,
        $(fmu_start: $fmu_start:expr,)?
        description: $description:literal $(,)?
    })*) => {
        /// The settings, by row of [`SETTINGS`].
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Key {
            $($key,)*
        }

        impl Key {
            /// The setting's group.
            pub const fn group(self) -> Group {
                match self {
                    $(Key::$key => Group::$group,)*
                }
            }
        }

        /// Every setting, in the order of [`Key`] (`SETTINGS[k].key == k`).
        pub const SETTINGS: &[Setting] = &[$(Setting {
            key: Key::$key,
            name: $name,
            kind: $kind,
            range: $range,
            default: $default,
            description: $description,
            appears: $appears,
            fmu_start: optional!($($fmu_start)?),
        },)*];
    };
}

for_each_setting!(declare);

/// The most elements of the beam (`n_elements`), which sizes the model's arrays on the stack: the
/// beam's highest frequency grows as n², and 32 elements resolve the first modes far beyond the
/// model's other approximations.
pub const MAX_ELEMENTS: usize = 32;

/// The default of `phi_filter_frequency` [Hz] (docs/fmu.md, "Model Exchange with φ alone").
pub const PHI_FILTER_FREQUENCY: f64 = 10.0;

/// The default of `max_rows`: a million rows, about 0.2 GB of CSV.
pub const MAX_ROWS_DEFAULT: i64 = 1_000_000;

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
