//! The single source of truth for the FMU's interface: every variable with its value
//! reference, causality, variability, type, start value, unit and description; the unit and
//! enumeration types; the log categories; the default experiment; the capability flags.
//!
//! `cargo xtask gen` writes `modelDescription/modelDescription.xml` from these tables, the
//! instance code dispatches on [`Var`], and the GUID is a hash of the tables
//! ([`guid`]), so the three cannot drift apart. No I/O, no `unsafe`.
#![forbid(unsafe_code)]

use std::sync::OnceLock;

/// `modelIdentifier`, the binary's name and the prefix of nothing (the binary exports the
/// standard names).
pub const MODEL_IDENTIFIER: &str = "BeamBody";
pub const MODEL_NAME: &str = "BeamBody";
pub const MODEL_DESCRIPTION: &str = "Inextensible elastic cantilever beam (Ritz, 2 coordinates) \
with a heavy rigid body hinged at its tip and turned through a large angle phi(t); \
Russkikh & Shklyarchuk (2020). The paper's three formulations: constraints exact (eq. 15), DAE \
with the inextensibility constraint (eq. 20-21), linearised (eq. 16); and the DAE projected onto \
the constraint.";
/// `version`: the crate's version (Cargo.toml). Not part of the GUID, which names the
/// interface: a release that changes no variable keeps it.
pub const MODEL_VERSION: &str = env!("CARGO_PKG_VERSION");
/// `generationTool`; like every attribute, the same on every build (no date, no path).
pub const GENERATION_TOOL: &str = concat!("beam-body ", env!("CARGO_PKG_VERSION"));

/// `<DefaultExperiment>`: the paper's scene (12 turn periods T = 0.85 s, its output step).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DefaultExperiment {
    pub start_time: f64,
    pub stop_time: f64,
    pub tolerance: f64,
    pub step_size: f64,
}

pub const DEFAULT_EXPERIMENT: DefaultExperiment =
    DefaultExperiment { start_time: 0.0, stop_time: 10.2, tolerance: 1e-6, step_size: 0.0085 };

/// The `<CoSimulation>` capability flags. Each one that is true is implemented and tested.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capabilities {
    pub can_handle_variable_communication_step_size: bool,
    pub can_interpolate_inputs: bool,
    pub max_output_derivative_order: u32,
    pub can_run_asynchronuously: bool,
    pub can_be_instantiated_only_once_per_process: bool,
    pub can_not_use_memory_management_functions: bool,
    pub can_get_and_set_fmu_state: bool,
    pub can_serialize_fmu_state: bool,
    pub provides_directional_derivative: bool,
}

pub const CAPABILITIES: Capabilities = Capabilities {
    can_handle_variable_communication_step_size: true,
    can_interpolate_inputs: true,
    max_output_derivative_order: 2,
    can_run_asynchronuously: false,
    can_be_instantiated_only_once_per_process: false,
    can_not_use_memory_management_functions: true,
    can_get_and_set_fmu_state: true,
    can_serialize_fmu_state: true,
    provides_directional_derivative: false,
};

/// A `<Unit>`: name and SI base-unit exponents (kg, m, s, rad; the others are zero).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit {
    pub name: &'static str,
    pub kg: i32,
    pub m: i32,
    pub s: i32,
    pub rad: i32,
}

const fn unit(name: &'static str, kg: i32, m: i32, s: i32, rad: i32) -> Unit {
    Unit { name, kg, m, s, rad }
}

pub const UNITS: &[Unit] = &[
    unit("m", 0, 1, 0, 0),
    unit("rad", 0, 0, 0, 1),
    unit("s", 0, 0, 1, 0),
    unit("kg", 1, 0, 0, 0),
    unit("kg/m", 1, -1, 0, 0),
    unit("kg.m2", 1, 2, 0, 0),
    unit("N.m2", 1, 3, -2, 0),
    unit("m/s", 0, 1, -1, 0),
    unit("m/s2", 0, 1, -2, 0),
    unit("rad/s", 0, 0, -1, 1),
    unit("rad/s2", 0, 0, -2, 1),
    unit("N", 1, 1, -2, 0),
    unit("N.m", 1, 2, -2, 0),
    unit("J", 1, 2, -2, 0),
];

/// An `<EnumerationType>`; item `k` (0-based) has the value `k + 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnumType {
    pub name: &'static str,
    pub description: &'static str,
    /// (name, description), in order.
    pub items: &'static [(&'static str, &'static str)],
}

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
        ("law", "the paper's law phi_end*sin^2(pi*t/(2*t_rot)), then held"),
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
                  (|v1| <= l, |theta1| <= pi/2, the dae formulation's drift)",
    items: &[
        ("stop", "the step ends there with fmi2Discard and a message"),
        ("warn", "fmi2Warning with a message, once; the run goes on"),
        ("off", "the run goes on; a state that is not a number still ends the step"),
    ],
};

pub const ENUM_TYPES: &[EnumType] =
    &[FORMULATION_TYPE, PHI_SOURCE_TYPE, PHI_INTERPOLATION_TYPE, RANGE_CHECK_TYPE];

/// `<LogCategories>`: (name, description). Errors are always logged; the others only when
/// debug logging is on for them.
pub const LOG_CATEGORIES: &[(&str, &str)] = &[
    ("logStatusWarning", "Warnings"),
    ("logStatusDiscard", "Steps that ended early (fmi2Discard)"),
    ("logStatusError", "Errors: illegal calls, bad arguments, failed steps"),
    ("logStatusFatal", "Fatal errors: a caught panic"),
    ("logCalls", "Every call of the FMI API, with its arguments"),
    ("logAll", "All of the above"),
];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    Parameter,
    Input,
    Output,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    Fixed,
    Continuous,
}

/// A variable's type, start value and range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Type {
    /// `start` is `None` for outputs (initial = "calculated").
    Real {
        unit: Option<&'static str>,
        start: Option<f64>,
        min: Option<f64>,
        max: Option<f64>,
    },
    Integer {
        start: i32,
        min: i32,
        max: i32,
    },
    Enumeration {
        ty: &'static EnumType,
        start: i32,
    },
    Boolean {
        start: bool,
    },
}

impl Type {
    /// The FMI base type whose functions (fmi2GetReal, …) access the variable.
    pub fn base(&self) -> BaseType {
        match self {
            Type::Real { .. } => BaseType::Real,
            Type::Integer { .. } | Type::Enumeration { .. } => BaseType::Integer,
            Type::Boolean { .. } => BaseType::Boolean,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BaseType {
    Real,
    Integer,
    Boolean,
    String,
}

/// The variables, by value reference. Value references are unique across all types.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Var {
    L = 0,
    Ei,
    M,
    M2,
    JC,
    R,
    G,
    TRot,
    PhiEnd,
    Atol,
    FixedStep,
    Formulation,
    PhiSource,
    MaxOrder,
    FixedOrder,
    PhiExtrapolation,
    PhiInterpolation,
    RangeCheck,
    StabilityGuard,
    Phi,
    V1,
    Theta1,
    U2,
    Dv1,
    Dtheta1,
    Du2,
    N,
    P,
    Moment,
    Drift,
    Energy,
    PhiApplied,
    DphiApplied,
    DdphiApplied,
}

impl Var {
    /// The variable with value reference `vr`.
    pub fn from_vr(vr: u32) -> Option<Var> {
        VARIABLES.get(vr as usize).map(|v| v.var)
    }

    pub fn vr(self) -> u32 {
        self as u32
    }

    /// Its row in [`VARIABLES`].
    pub fn info(self) -> &'static Variable {
        &VARIABLES[self as usize]
    }
}

/// One `<ScalarVariable>`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variable {
    pub var: Var,
    pub name: &'static str,
    pub causality: Causality,
    pub variability: Variability,
    pub ty: Type,
    pub description: &'static str,
}

impl Variable {
    pub fn vr(&self) -> u32 {
        self.var.vr()
    }
}

const fn real_param(
    var: Var,
    name: &'static str,
    unit: &'static str,
    start: f64,
    min: Option<f64>,
    description: &'static str,
) -> Variable {
    Variable {
        var,
        name,
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        ty: Type::Real { unit: Some(unit), start: Some(start), min, max: None },
        description,
    }
}

const fn int_param(
    var: Var,
    name: &'static str,
    start: i32,
    min: i32,
    max: i32,
    description: &'static str,
) -> Variable {
    Variable {
        var,
        name,
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        ty: Type::Integer { start, min, max },
        description,
    }
}

const fn output(
    var: Var,
    name: &'static str,
    unit: &'static str,
    description: &'static str,
) -> Variable {
    Variable {
        var,
        name,
        causality: Causality::Output,
        variability: Variability::Continuous,
        ty: Type::Real { unit: Some(unit), start: None, min: None, max: None },
        description,
    }
}

/// Every variable, in value-reference order (`VARIABLES[k].vr() == k`, checked by a test).
/// Defaults are the paper's example (§4), as in [`crate::model::Params`].
pub const VARIABLES: &[Variable] = &[
    real_param(Var::L, "l", "m", 2.5, Some(0.0), "Beam length, > 0"),
    real_param(Var::Ei, "EI", "N.m2", 1000.0, Some(0.0), "Bending stiffness, > 0"),
    real_param(Var::M, "m", "kg/m", 2.0, Some(0.0), "Beam mass per unit length, >= 0"),
    real_param(Var::M2, "M2", "kg", 12.0, Some(0.0), "Mass of the rigid body, > 0"),
    real_param(
        Var::JC,
        "J_C",
        "kg.m2",
        1.0,
        Some(0.0),
        "Moment of inertia of the body about its centre of mass, >= 0",
    ),
    real_param(Var::R, "r", "m", 0.5, Some(0.0), "Hinge-to-centre-of-mass distance, >= 0"),
    real_param(
        Var::G,
        "g",
        "m/s2",
        10.0,
        None,
        "Gravity along the undeformed beam axis (> 0 stretches the beam)",
    ),
    real_param(
        Var::TRot,
        "t_rot",
        "s",
        0.85,
        Some(0.0),
        "Duration of the turn of the built-in law (phi_source = law), > 0",
    ),
    real_param(
        Var::PhiEnd,
        "phi_end",
        "rad",
        std::f64::consts::PI,
        None,
        "Angle turned by the built-in law (phi_source = law)",
    ),
    Variable {
        var: Var::Atol,
        name: "atol",
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        ty: Type::Real { unit: None, start: Some(0.0), min: Some(0.0), max: None },
        description: "Absolute tolerance of the integrator for every state (in its SI unit); \
                      0 selects 1e-3 * tolerance",
    },
    real_param(
        Var::FixedStep,
        "fixed_step",
        "s",
        0.0,
        Some(0.0),
        "Constant internal step of the paper's fixed-step BDF; 0 selects the adaptive BDF",
    ),
    Variable {
        var: Var::Formulation,
        name: "formulation",
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        ty: Type::Enumeration { ty: &FORMULATION_TYPE, start: 1 },
        description: "Equations integrated: reduced (15), dae (20-21), dae_stabilized, linear (16)",
    },
    Variable {
        var: Var::PhiSource,
        name: "phi_source",
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        ty: Type::Enumeration { ty: &PHI_SOURCE_TYPE, start: 1 },
        description: "Source of the hinge angle: the input phi, or the paper's law",
    },
    int_param(Var::MaxOrder, "max_order", 5, 1, 5, "Highest order of the adaptive BDF, 1..5"),
    int_param(
        Var::FixedOrder,
        "fixed_order",
        2,
        1,
        5,
        "Order of the fixed-step BDF (used when fixed_step > 0), 1..5",
    ),
    int_param(
        Var::PhiExtrapolation,
        "phi_extrapolation",
        3,
        0,
        3,
        "Degree of the polynomial through the last input values that gives phi over a step \
         when the host sends no derivatives, 0..3",
    ),
    Variable {
        var: Var::PhiInterpolation,
        name: "phi_interpolation",
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        ty: Type::Enumeration { ty: &PHI_INTERPOLATION_TYPE, start: 1 },
        description: "Interpolation of the input phi between communication points: smooth or \
                      taylor",
    },
    Variable {
        var: Var::RangeCheck,
        name: "range_check",
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        ty: Type::Enumeration { ty: &RANGE_CHECK_TYPE, start: 1 },
        description: "Outside the range of validity (|theta1| <= pi/2, ...): stop, warn or off",
    },
    Variable {
        var: Var::StabilityGuard,
        name: "stability_guard",
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        ty: Type::Boolean { start: true },
        description: "Cap the BDF order where an undamped mode would be amplified by BDF3-5",
    },
    Variable {
        var: Var::Phi,
        name: "phi",
        causality: Causality::Input,
        variability: Variability::Continuous,
        ty: Type::Real { unit: Some("rad"), start: Some(0.0), min: None, max: None },
        description: "Hinge angle of the body (phi_source = input)",
    },
    output(Var::V1, "v1", "m", "Tip deflection"),
    output(Var::Theta1, "theta1", "rad", "Rotation of the beam's tip section"),
    output(Var::U2, "u2", "m", "Axial displacement of the hinge (body side)"),
    output(Var::Dv1, "dv1", "m/s", "Rate of the tip deflection"),
    output(Var::Dtheta1, "dtheta1", "rad/s", "Rate of the tip section rotation"),
    output(Var::Du2, "du2", "m/s", "Rate of the hinge's axial displacement"),
    output(Var::N, "N", "N", "Hinge force of the body on the beam tip, along x (paper eq. 18-19)"),
    output(Var::P, "P", "N", "Hinge force of the body on the beam tip, along y (paper eq. 18-19)"),
    output(
        Var::Moment,
        "M",
        "N.m",
        "Hinge moment of the body on the beam's tip section; -M is the torque the drive applies \
         to the body (paper eq. 18-19)",
    ),
    output(
        Var::Drift,
        "drift",
        "m",
        "Constraint residual u2 - u1(v1, theta1); 0 except in the dae formulation",
    ),
    output(Var::Energy, "energy", "J", "Total mechanical energy of beam and body"),
    output(Var::PhiApplied, "phi_applied", "rad", "Hinge angle the model used"),
    output(Var::DphiApplied, "dphi_applied", "rad/s", "Rate of the hinge angle the model used"),
    output(
        Var::DdphiApplied,
        "ddphi_applied",
        "rad/s2",
        "Angular acceleration of the hinge the model used",
    ),
];

/// The GUID: a 128-bit FNV-1a hash of every table in this file, so any change to the
/// interface changes it. Formatted like a UUID, in braces.
///
/// Kept in a fixed-size static, not a `String`: a host that unloads the library
/// (`dlclose`) cannot free what a static points to, and the C host test under valgrind
/// counts every such block as lost, once per load.
pub fn guid() -> &'static str {
    static GUID: OnceLock<[u8; 38]> = OnceLock::new();
    let bytes = GUID.get_or_init(|| {
        let text = format!(
            "{MODEL_IDENTIFIER}|{MODEL_NAME}|{MODEL_DESCRIPTION}|{DEFAULT_EXPERIMENT:?}|\
             {CAPABILITIES:?}|{UNITS:?}|{ENUM_TYPES:?}|{LOG_CATEGORIES:?}|{VARIABLES:?}"
        );
        let h = fnv1a_128(text.as_bytes());
        let formatted = format!(
            "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
            (h >> 96) as u32,
            (h >> 80) as u16,
            (h >> 64) as u16,
            (h >> 48) as u16,
            h & 0xffff_ffff_ffff
        );
        formatted.as_bytes().try_into().expect("a braced UUID has 38 characters")
    });
    std::str::from_utf8(bytes).expect("hex digits, dashes and braces")
}

/// FNV-1a, 128-bit variant (Fowler, Noll, Vo; offset basis and prime from the FNV
/// reference, draft-eastlake-fnv).
fn fnv1a_128(bytes: &[u8]) -> u128 {
    const OFFSET: u128 = 0x6c62272e07bb014262b821756295c58d;
    const PRIME: u128 = 0x0000000001000000000000000000013B;
    bytes.iter().fold(OFFSET, |h, &b| (h ^ b as u128).wrapping_mul(PRIME))
}

/// The variable called `name`.
pub fn by_name(name: &str) -> Option<&'static Variable> {
    VARIABLES.iter().find(|v| v.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Params;

    #[test]
    fn value_references_are_the_row_index_and_names_unique() {
        for (k, v) in VARIABLES.iter().enumerate() {
            assert_eq!(v.vr() as usize, k, "{}", v.name);
            assert_eq!(Var::from_vr(k as u32), Some(v.var));
            assert_eq!(VARIABLES.iter().filter(|w| w.name == v.name).count(), 1, "{}", v.name);
            assert!(!v.description.is_empty());
        }
        assert_eq!(Var::from_vr(VARIABLES.len() as u32), None);
    }

    #[test]
    fn parameter_defaults_are_the_models() {
        let p = Params::default();
        let start = |var: Var| match var.info().ty {
            Type::Real { start: Some(s), .. } => s,
            _ => panic!("{var:?} has no real start"),
        };
        for (name, value) in Params::NAMES.iter().zip([p.l, p.ei, p.m, p.m2, p.j_c, p.r, p.g]) {
            let v = by_name(name).unwrap();
            assert_eq!(start(v.var), value, "{name}");
        }
        let law = crate::model::PaperLaw::default();
        assert_eq!(start(Var::TRot), law.t_rot);
        assert_eq!(start(Var::PhiEnd), law.phi_end);
    }

    #[test]
    fn every_unit_is_declared() {
        for v in VARIABLES {
            if let Type::Real { unit: Some(u), .. } = v.ty {
                assert!(UNITS.iter().any(|d| d.name == u), "{}: unit {u}", v.name);
            }
        }
    }

    #[test]
    fn guid_is_stable_and_uuid_shaped() {
        let g = guid();
        assert_eq!(g.len(), 38);
        assert!(g.starts_with('{') && g.ends_with('}'));
        assert_eq!(g, guid());
    }
}
