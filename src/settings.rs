//! The one table of settings: every number, choice and switch a run takes, with its name,
//! unit, kind, range, default and description, and where it appears (a scene key always; an
//! FMU parameter, a study parameter, a CLI flag where marked).
//!
//! Everything else is derived from [`SETTINGS`]: the FMU's parameters and so
//! `modelDescription.xml` (`fmu::variables`), [`Scene::default`](crate::scene::Scene) and
//! its `set`, the study's list of parameters, and the CLI's flags and help. A new setting is
//! a row here and its field in [`Scene`](crate::scene::Scene). No I/O, no `unsafe`.
#![forbid(unsafe_code)]

pub use crate::fmi::description::EnumType;
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

/// The settings, by row of [`SETTINGS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Key {
    L,
    Ei,
    M,
    M2,
    JC,
    R,
    G,
    NElements,
    DampingAlpha,
    DampingBeta,
    DampingRatio,
    Beam,
    BeamGravity,
    TRot,
    PhiEnd,
    Phi0,
    V10,
    Theta10,
    Dv10,
    Dtheta10,
    Formulation,
    PhiSource,
    PhiInterpolation,
    PhiExtrapolation,
    IntermediateStep,
    InputDerivatives,
    DtComm,
    Rtol,
    Atol,
    MaxOrder,
    FixedStep,
    FixedOrder,
    StabilityGuard,
    RangeCheck,
    EnergyCheck,
    PhiFilterFrequency,
    TEnd,
    DtOut,
    MaxRows,
    Columns,
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

impl Key {
    /// The setting's group.
    pub const fn group(self) -> Group {
        use Key as K;
        match self {
            K::L | K::Ei | K::M | K::M2 | K::JC | K::R | K::G => Group::Model,
            K::NElements | K::DampingAlpha | K::DampingBeta | K::DampingRatio => Group::Model,
            K::Beam | K::BeamGravity => Group::Model,
            K::TRot | K::PhiEnd | K::Phi0 => Group::Law,
            K::V10 | K::Theta10 | K::Dv10 | K::Dtheta10 => Group::Initial,
            K::PhiSource | K::PhiInterpolation | K::PhiExtrapolation => Group::Input,
            K::IntermediateStep | K::InputDerivatives | K::DtComm => Group::Input,
            K::PhiFilterFrequency => Group::Input,
            K::Formulation | K::Rtol | K::Atol | K::MaxOrder | K::FixedStep => Group::Solver,
            K::FixedOrder | K::StabilityGuard => Group::Solver,
            K::RangeCheck | K::EnergyCheck => Group::Checks,
            K::TEnd | K::DtOut | K::MaxRows | K::Columns => Group::Run,
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

const fn real(unit: &'static str) -> Kind {
    Kind::Real { unit: Some(unit) }
}

const NOWHERE: Appears = Appears { fmu: false, study: false, flag: None };
const FMU: Appears = Appears { fmu: true, study: false, flag: None };
/// A number of the model, the law or the initial state: an FMU parameter a study can vary.
const PHYSICAL: Appears = Appears { fmu: true, study: true, flag: None };

const fn flag(fmu: bool, flag: &'static str) -> Appears {
    Appears { fmu, study: false, flag: Some(flag) }
}

const fn row(
    key: Key,
    name: &'static str,
    kind: Kind,
    range: Range,
    default: Value,
    description: &'static str,
    appears: Appears,
) -> Setting {
    Setting { key, name, kind, range, default, description, appears, fmu_start: None }
}

use Key as K;
use Range::{Finite, Integers, NonNegative, Positive};
use Value::{Bool, Choice, Integer, Real};

/// Every setting, in the order of [`Key`] (`SETTINGS[k].key == k`, checked by a test).
/// Defaults are the paper's example (§4).
pub const SETTINGS: [Setting; 40] = [
    row(K::L, "l", real("m"), Positive, Real(2.5), "Beam length", PHYSICAL),
    row(K::Ei, "EI", real("N.m2"), Positive, Real(1000.0), "Bending stiffness", PHYSICAL),
    row(K::M, "m", real("kg/m"), NonNegative, Real(2.0), "Beam mass per unit length", PHYSICAL),
    row(K::M2, "M2", real("kg"), Positive, Real(12.0), "Mass of the rigid body", PHYSICAL),
    row(
        K::JC,
        "J_C",
        real("kg.m2"),
        NonNegative,
        Real(1.0),
        "Moment of inertia of the body about its centre of mass",
        PHYSICAL,
    ),
    row(K::R, "r", real("m"), NonNegative, Real(0.5), "Hinge-to-centre-of-mass distance", PHYSICAL),
    row(
        K::G,
        "g",
        real("m/s2"),
        Finite,
        Real(10.0),
        "Gravity along the undeformed beam axis (> 0 stretches the beam)",
        PHYSICAL,
    ),
    row(
        K::NElements,
        "n_elements",
        Kind::Integer,
        Integers(1, crate::model::MAX_ELEMENTS as i64),
        Integer(1),
        "Cubic Hermite elements of the beam: 1 is the paper's model (2 coordinates), n has 2n",
        Appears { fmu: true, study: true, flag: Some("--elements") },
    ),
    row(
        K::DampingAlpha,
        "damping_alpha",
        real("1/s"),
        NonNegative,
        Real(0.0),
        "Rayleigh damping of the beam: alpha times its mass matrix (0: none, as in the paper)",
        PHYSICAL,
    ),
    row(
        K::DampingBeta,
        "damping_beta",
        real("s"),
        NonNegative,
        Real(0.0),
        "Rayleigh damping of the beam: beta times its stiffness matrix (0: none, as in the \
         paper)",
        PHYSICAL,
    ),
    row(
        K::DampingRatio,
        "damping_ratio",
        Kind::Real { unit: None },
        NonNegative,
        Real(0.0),
        "Rayleigh damping of the beam set by the damping ratio zeta of its own first two modes \
         (the cantilever without the body); alpha and beta follow: give either this or them",
        PHYSICAL,
    ),
    row(
        K::Beam,
        "beam",
        Kind::Choice(&BEAM_TYPE),
        Finite,
        Choice(0),
        "The beam's theory: quadratic (the paper's cut at second order) or exact (the \
         inextensible elastica, valid at any rotation)",
        flag(true, "--beam"),
    ),
    row(
        K::BeamGravity,
        "beam_gravity",
        Kind::Bool,
        Finite,
        Bool(false),
        "Gravity on the beam itself, g per unit length m along +x (the paper leaves it out)",
        FMU,
    ),
    row(
        K::TRot,
        "t_rot",
        real("s"),
        Positive,
        Real(0.85),
        "Duration of the turn of the built-in law (phi_source = law)",
        PHYSICAL,
    ),
    row(
        K::PhiEnd,
        "phi_end",
        real("rad"),
        Finite,
        Real(std::f64::consts::PI),
        "Angle turned by the built-in law (phi_source = law)",
        PHYSICAL,
    ),
    row(
        K::Phi0,
        "phi0",
        real("rad"),
        Finite,
        Real(0.0),
        "Angle of the body at t = 0 under the built-in law, from which it turns by phi_end",
        PHYSICAL,
    ),
    row(K::V10, "v1_0", real("m"), Finite, Real(0.0), "Tip deflection at the start", PHYSICAL),
    row(
        K::Theta10,
        "theta1_0",
        real("rad"),
        Finite,
        Real(0.0),
        "Rotation of the tip section at the start",
        PHYSICAL,
    ),
    row(K::Dv10, "dv1_0", real("m/s"), Finite, Real(0.0), "Rate of v1 at the start", PHYSICAL),
    row(
        K::Dtheta10,
        "dtheta1_0",
        real("rad/s"),
        Finite,
        Real(0.0),
        "Rate of theta1 at the start",
        PHYSICAL,
    ),
    row(
        K::Formulation,
        "formulation",
        Kind::Choice(&FORMULATION_TYPE),
        Finite,
        Choice(0),
        "Equations integrated: reduced (15), dae (20-21), dae_stabilized, linear (16)",
        flag(true, "--formulation"),
    ),
    // The CLI runs the paper's law unless told otherwise; the FMU takes phi from its input,
    // because some hosts (libcosim, Ecos) cannot set an enumeration, and every host must be
    // able to drive phi. An FMU whose input is never set says so at its first step.
    Setting {
        fmu_start: Some(Choice(0)),
        ..row(
            K::PhiSource,
            "phi_source",
            Kind::Choice(&PHI_SOURCE_TYPE),
            Finite,
            Choice(1),
            "Source of the hinge angle: the input phi (the FMU's default), or the paper's law \
             (the CLI's default; the CLI's input is the law sampled as a host would, every \
             dt_comm)",
            FMU,
        )
    },
    row(
        K::PhiInterpolation,
        "phi_interpolation",
        Kind::Choice(&PHI_INTERPOLATION_TYPE),
        Finite,
        Choice(0),
        "Interpolation of the input phi between communication points: smooth or taylor",
        FMU,
    ),
    row(
        K::PhiExtrapolation,
        "phi_extrapolation",
        Kind::Integer,
        Integers(0, 3),
        Integer(3),
        "Degree of the polynomial through the last input values that gives phi over a step \
         when the host sends no derivatives",
        FMU,
    ),
    row(
        K::IntermediateStep,
        "intermediate_step",
        real("s"),
        NonNegative,
        Real(1e-3),
        "FMI 3.0 co-simulation, phi_source = input, with the host's intermediate-update \
         callback: fmi3DoStep asks the host for phi every intermediate_step inside a \
         communication step (the last part up to 1.25 times as long); 0 asks only at the \
         communication points",
        FMU,
    ),
    row(
        K::InputDerivatives,
        "input_derivatives",
        Kind::Bool,
        Finite,
        Bool(false),
        "CLI, phi_source = input: the emulated host also sends phi' and phi'' at every \
         communication point (fmi2SetRealInputDerivatives)",
        NOWHERE,
    ),
    row(
        K::DtComm,
        "dt_comm",
        real("s"),
        Positive,
        Real(0.01),
        "CLI, phi_source = input: the emulated host's communication step",
        NOWHERE,
    ),
    row(
        K::Rtol,
        "rtol",
        Kind::Real { unit: None },
        Range::Closed(1e-14, 1.0),
        Real(1e-6),
        "Relative tolerance of the integrator (the FMU takes fmi2SetupExperiment's)",
        flag(false, "--rtol"),
    ),
    row(
        K::Atol,
        "atol",
        Kind::Real { unit: None },
        NonNegative,
        Real(0.0),
        "Absolute tolerance of the integrator for every state, in its SI unit; 0 selects \
         1e-3 times the relative tolerance",
        flag(true, "--atol"),
    ),
    row(
        K::MaxOrder,
        "max_order",
        Kind::Integer,
        Integers(1, 5),
        Integer(5),
        "Highest order of the adaptive BDF",
        flag(true, "--max-order"),
    ),
    row(
        K::FixedStep,
        "fixed_step",
        real("s"),
        NonNegative,
        Real(0.0),
        "Constant internal step of the paper's fixed-step BDF; 0 selects the adaptive BDF",
        flag(true, "--fixed-step"),
    ),
    row(
        K::FixedOrder,
        "fixed_order",
        Kind::Integer,
        Integers(0, 5),
        Integer(0),
        "Order of the fixed-step BDF, needs fixed_step > 0; 0 selects order 2",
        flag(true, "--fixed-order"),
    ),
    row(
        K::StabilityGuard,
        "stability_guard",
        Kind::Bool,
        Finite,
        Bool(true),
        "Cap the BDF order where an undamped mode would be amplified by BDF3-5",
        flag(true, "--stability-guard"),
    ),
    row(
        K::RangeCheck,
        "range_check",
        Kind::Choice(&RANGE_CHECK_TYPE),
        Finite,
        Choice(0),
        "Outside the range of validity (|v1| <= l, |theta1| <= pi/2, ...; the exact beam: a \
         centreline that crosses itself): stop, warn or off",
        FMU,
    ),
    row(
        K::EnergyCheck,
        "energy_check",
        Kind::Choice(&ENERGY_CHECK_TYPE),
        Finite,
        Choice(0),
        "When the energy balance breaks (the energy's change against the work of the drive \
         and the damping, after every step, within 100 rtol of the energy handled, at most \
         10 %): the run is numerically unstable; stop, warn or off",
        FMU,
    ),
    row(
        K::PhiFilterFrequency,
        "phi_filter_frequency",
        real("Hz"),
        Positive,
        Real(PHI_FILTER_FREQUENCY),
        "Model Exchange with phi_source = input, when the host sets phi but not dphi and \
         ddphi: the cut-off frequency of the second-order filter whose states give phi, phi' \
         and phi'' from phi (Modelica's Rotational.Sources.Position with exact = false); a \
         host that sets dphi and ddphi gets them as it sends them",
        FMU,
    ),
    row(K::TEnd, "t_end", real("s"), Positive, Real(10.0), "End time of a CLI run", NOWHERE),
    row(
        K::DtOut,
        "dt_out",
        real("s"),
        Positive,
        Real(0.01),
        "Output step of a CLI run: rows at t = k*dt_out and at t_end",
        NOWHERE,
    ),
    row(
        K::MaxRows,
        "max_rows",
        Kind::Integer,
        Integers(1, 1 << 53),
        Integer(MAX_ROWS_DEFAULT),
        "Most output rows a CLI run or a study case may have (t_end/dt_out + 1); a run that \
         would have more is refused before it starts",
        flag(false, "--max-rows"),
    ),
    row(
        K::Columns,
        "columns",
        Kind::Choice(&COLUMNS_TYPE),
        Finite,
        Choice(0),
        "Columns of a CLI run's CSV: paper (the default), beam (and the loads at the root and \
         the deflection at the quarter points; the FMU has them as outputs), or shape (and \
         the nodes' deflections and slopes, for pictures)",
        flag(false, "--columns"),
    ),
];

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
