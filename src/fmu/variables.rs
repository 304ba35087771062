//! The single source of truth for the beam–body FMU's interface: every variable with its
//! value reference, causality, variability, type, start value, unit and description; the
//! units; the default experiment; the capability flags. Parameters are rows of the settings
//! table ([`crate::settings`]), so their name, unit, range, start value and description come
//! from there.
//!
//! `cargo xtask gen` writes `modelDescription/modelDescription.xml` from these tables, the
//! binding dispatches on [`Var`], and the GUID is a hash of the tables ([`guid`]), so the
//! three cannot drift apart. No I/O, no `unsafe`.
#![forbid(unsafe_code)]

pub use crate::fmi::description::{
    BaseType, Capabilities, Causality, DefaultExperiment, Dim, ExchangeCapabilities,
    Fmi3Capabilities, Only, Type, Unit, VarInfo, Variability, LOG_CATEGORIES,
};
use crate::hash::fnv1a_128;
use std::fmt;
use std::sync::OnceLock;

/// `modelIdentifier`, the binary's name and the prefix of nothing (the binary exports the
/// standard names).
pub const MODEL_IDENTIFIER: &str = "BeamBody";
pub const MODEL_NAME: &str = "BeamBody";
pub const MODEL_DESCRIPTION: &str = "Inextensible elastic cantilever beam with a heavy rigid body \
hinged at its tip and turned through a large angle phi(t); Russkikh & Shklyarchuk (2020). The beam \
by Ritz in n_elements cubic Hermite elements (1, the default, is the paper's model: 2 coordinates), \
its geometric nonlinearity cut at second order as in the paper (beam = quadratic) or kept whole \
(beam = exact, the inextensible elastica). The quadratic beam in four formulations: the paper's \
three, constraints exact (eq. 15), DAE with the inextensibility constraint (eq. 20-21) and \
linearised (eq. 16), and the DAE projected onto the constraint.";
/// `version`: the crate's version (Cargo.toml). Not part of the GUID, which names the
/// interface: a release that changes no variable keeps it.
pub const MODEL_VERSION: &str = env!("CARGO_PKG_VERSION");
/// `generationTool`; like every attribute, the same on every build (no date, no path).
pub const GENERATION_TOOL: &str = concat!("beam-body ", env!("CARGO_PKG_VERSION"));

/// `<DefaultExperiment>`: the paper's scene (12 turn periods T = 0.85 s, its output step).
pub const DEFAULT_EXPERIMENT: DefaultExperiment =
    DefaultExperiment { start_time: 0.0, stop_time: 10.2, tolerance: 1e-6, step_size: 0.0085 };

/// The `<CoSimulation>` capability flags. Each one that is true is implemented and tested.
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

const fn unit(name: &'static str, kg: i32, m: i32, s: i32, rad: i32) -> Unit {
    Unit::new(name, kg, m, s, rad)
}

pub const UNITS: &[Unit] = &[
    unit("m", 0, 1, 0, 0),
    unit("rad", 0, 0, 0, 1),
    unit("s", 0, 0, 1, 0),
    unit("1/s", 0, 0, -1, 0),
    unit("Hz", 0, 0, -1, 0),
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

pub use crate::settings::{
    EnumType, ENUM_TYPES, FORMULATION_TYPE, PHI_INTERPOLATION_TYPE, PHI_SOURCE_TYPE,
    RANGE_CHECK_TYPE,
};
use crate::settings::{Key, Kind, Setting, Value};

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
    Phi0,
    V10,
    Theta10,
    Dv10,
    Dtheta10,
    NElements,
    DampingAlpha,
    DampingBeta,
    DampingRatio,
    MRoot,
    QRoot,
    VQuarter,
    VMid,
    VThreeQuarter,
    Beam,
    BeamGravity,
    Dphi,
    Ddphi,
    DerV1,
    DerTheta1,
    DerDv1,
    DerDtheta1,
    Time,
    RangeMarginV1,
    RangeMarginTheta1,
    IntermediateStep,
    NodalV,
    NodalTheta,
    Q,
    Dq,
    Ddq,
    EnergyCheck,
    PhiFilterFrequency,
    PhiFiltered,
    DphiFiltered,
    DdphiFiltered,
    Integrator,
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

/// One `<ScalarVariable>`: what the FMI core knows of it ([`VarInfo`], which it derefs to),
/// and what the binding needs: its [`Var`] and, for a parameter, its setting.
#[derive(Clone, Copy, PartialEq)]
pub struct Variable {
    pub var: Var,
    pub info: VarInfo,
    /// The setting of a parameter ([`crate::settings`]), whose row gives the rest.
    pub setting: Option<Key>,
}

impl Variable {
    pub fn vr(&self) -> u32 {
        self.var.vr()
    }
}

impl std::ops::Deref for Variable {
    type Target = VarInfo;
    fn deref(&self) -> &VarInfo {
        &self.info
    }
}

/// Field by field as the table's rows were before [`VarInfo`] was split out: the GUID hashes
/// this text, so it stays the same for the same interface.
impl fmt::Debug for Variable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let i = &self.info;
        f.debug_struct("Variable")
            .field("var", &self.var)
            .field("name", &i.name)
            .field("causality", &i.causality)
            .field("variability", &i.variability)
            .field("ty", &i.ty)
            .field("description", &i.description)
            .field("derivative_of", &i.derivative_of)
            .field("setting", &self.setting)
            .field("structural", &i.structural)
            .field("dims", &i.dims)
            .field("only", &i.only)
            .finish()
    }
}

/// The FMU parameter of a setting: its name, unit, range, start value and description are
/// the table's. Enumerations are 1-based.
const fn param(var: Var, key: Key) -> Variable {
    let s = Setting::of(key);
    let ty = match (s.kind, s.fmu_default()) {
        (Kind::Real { unit }, Value::Real(start)) => {
            Type::Real { unit, start: Some(start), min: s.range.min(), max: s.range.max() }
        }
        (Kind::Integer, Value::Integer(start)) => {
            let (min, max) = match s.range {
                crate::range::Range::Integers(lo, hi) => (lo as i32, hi as i32),
                _ => (i32::MIN, i32::MAX),
            };
            Type::Integer { start: start as i32, min, max }
        }
        (Kind::Choice(ty), Value::Choice(k)) => Type::Enumeration { ty, start: k as i32 + 1 },
        (Kind::Bool, Value::Bool(start)) => Type::Boolean { start },
        _ => panic!("a setting's default has its kind"),
    };
    Variable {
        var,
        info: VarInfo {
            name: s.name,
            causality: Causality::Parameter,
            variability: Variability::Fixed,
            ty,
            description: s.description,
            derivative_of: None,
            // n_elements sizes FMI 3.0's arrays.
            structural: matches!(key, Key::NElements),
            dims: &[],
            only: Only::Both,
        },
        setting: Some(key),
    }
}

/// A continuous real that is not a parameter: an output or a derivative (no start value),
/// or an input (start value 0).
const fn continuous(
    var: Var,
    causality: Causality,
    name: &'static str,
    unit: &'static str,
    description: &'static str,
    derivative_of: Option<u32>,
) -> Variable {
    let start = if matches!(causality, Causality::Input) { Some(0.0) } else { None };
    Variable {
        var,
        info: VarInfo {
            name,
            causality,
            variability: Variability::Continuous,
            ty: Type::Real { unit: Some(unit), start, min: None, max: None },
            description,
            derivative_of,
            structural: false,
            dims: &[],
            only: Only::Both,
        },
        setting: None,
    }
}

const fn output(
    var: Var,
    name: &'static str,
    unit: &'static str,
    description: &'static str,
) -> Variable {
    continuous(var, Causality::Output, name, unit, description, None)
}

/// A real input with start value 0.
const fn input(
    var: Var,
    name: &'static str,
    unit: &'static str,
    description: &'static str,
) -> Variable {
    continuous(var, Causality::Input, name, unit, description, None)
}

/// The derivative of the continuous state `of` (Model Exchange): a local variable.
const fn derivative(
    var: Var,
    of: Var,
    name: &'static str,
    unit: &'static str,
    description: &'static str,
) -> Variable {
    let v = continuous(var, Causality::Local, name, unit, description, Some(of as u32));
    Variable { info: VarInfo { only: Only::Fmi2, ..v.info }, ..v }
}

/// A variable of Model Exchange's filter of φ ([`crate::model::PhiFilter`]): a calculated
/// local of both versions, the derivative of `of`.
const fn filtered(
    var: Var,
    of: Option<Var>,
    name: &'static str,
    unit: &'static str,
    description: &'static str,
) -> Variable {
    let of = match of {
        Some(v) => Some(v as u32),
        None => None,
    };
    continuous(var, Causality::Local, name, unit, description, of)
}

/// The dimensions of a nodal array: one value per node, n_elements of them.
const NODES: &[Dim] = &[Dim::Param(Var::NElements as u32)];
/// The dimensions of the coordinates q and their rates: (n_elements, 2), a node's two
/// coordinates in a row.
const NODES_BY_TWO: &[Dim] = &[Dim::Param(Var::NElements as u32), Dim::Fixed(2)];

/// An FMI 3.0 array of reals sized by `dims`: an output, or a local (the Model Exchange
/// states and their derivatives); `unit` "" for none.
const fn array(
    var: Var,
    causality: Causality,
    dims: &'static [Dim],
    name: &'static str,
    unit: &'static str,
    description: &'static str,
    derivative_of: Option<Var>,
) -> Variable {
    let of = match derivative_of {
        Some(v) => Some(v as u32),
        None => None,
    };
    let v = continuous(var, causality, name, unit, description, of);
    // No unit for "": q mixes metres and radians.
    let ty = if unit.is_empty() {
        Type::Real { unit: None, start: None, min: None, max: None }
    } else {
        v.info.ty
    };
    Variable { info: VarInfo { dims, only: Only::Fmi3, ty, ..v.info }, ..v }
}

/// Every variable, in value-reference order (`VARIABLES[k].vr() == k`, checked by a test).
/// Defaults are the paper's example (§4), as in [`crate::model::Params`].
pub const VARIABLES: &[Variable] = &[
    param(Var::L, Key::L),
    param(Var::Ei, Key::Ei),
    param(Var::M, Key::M),
    param(Var::M2, Key::M2),
    param(Var::JC, Key::JC),
    param(Var::R, Key::R),
    param(Var::G, Key::G),
    param(Var::TRot, Key::TRot),
    param(Var::PhiEnd, Key::PhiEnd),
    param(Var::Atol, Key::Atol),
    param(Var::FixedStep, Key::FixedStep),
    param(Var::Formulation, Key::Formulation),
    param(Var::PhiSource, Key::PhiSource),
    param(Var::MaxOrder, Key::MaxOrder),
    param(Var::FixedOrder, Key::FixedOrder),
    param(Var::PhiExtrapolation, Key::PhiExtrapolation),
    param(Var::PhiInterpolation, Key::PhiInterpolation),
    param(Var::RangeCheck, Key::RangeCheck),
    param(Var::StabilityGuard, Key::StabilityGuard),
    input(Var::Phi, "phi", "rad", "Hinge angle of the body (used with phi_source = input)"),
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
    // Added after the outputs, so that the value references of FMUs before them still hold.
    param(Var::Phi0, Key::Phi0),
    param(Var::V10, Key::V10),
    param(Var::Theta10, Key::Theta10),
    param(Var::Dv10, Key::Dv10),
    param(Var::Dtheta10, Key::Dtheta10),
    param(Var::NElements, Key::NElements),
    param(Var::DampingAlpha, Key::DampingAlpha),
    param(Var::DampingBeta, Key::DampingBeta),
    param(Var::DampingRatio, Key::DampingRatio),
    output(
        Var::MRoot,
        "M_root",
        "N.m",
        "Bending moment of the beam at the clamp, EI*v''(0) (the clamp's consistent reaction; the \
         exact beam: from the balance of angular momentum)",
    ),
    output(
        Var::QRoot,
        "Q_root",
        "N",
        "Shear force of the beam at the clamp, EI*v'''(0) (the clamp's consistent reaction; the \
         exact beam: from the balance of momentum)",
    ),
    output(
        Var::VQuarter,
        "v_quarter",
        "m",
        "Deflection of the beam at x = l/4 (the exact beam: at arc length l/4)",
    ),
    output(
        Var::VMid,
        "v_mid",
        "m",
        "Deflection of the beam at x = l/2 (the exact beam: at arc length l/2)",
    ),
    output(
        Var::VThreeQuarter,
        "v_three_quarter",
        "m",
        "Deflection of the beam at x = 3l/4 (the exact beam: at arc length 3l/4)",
    ),
    param(Var::Beam, Key::Beam),
    param(Var::BeamGravity, Key::BeamGravity),
    input(
        Var::Dphi,
        "dphi",
        "rad/s",
        "Rate of the hinge angle, with phi_source = input, for Model Exchange, which uses it \
         with phi at every evaluation; co-simulation ignores it (there phi's derivatives come by \
         fmi2SetRealInputDerivatives in FMI 2.0, and phi inside a step by intermediate update \
         in FMI 3.0)",
    ),
    input(
        Var::Ddphi,
        "ddphi",
        "rad/s2",
        "Angular acceleration of the hinge, with phi_source = input, for Model Exchange: as \
         dphi",
    ),
    derivative(Var::DerV1, Var::V1, "der(v1)", "m/s", "Time derivative of v1 (Model Exchange)"),
    derivative(
        Var::DerTheta1,
        Var::Theta1,
        "der(theta1)",
        "rad/s",
        "Time derivative of theta1 (Model Exchange)",
    ),
    derivative(
        Var::DerDv1,
        Var::Dv1,
        "der(dv1)",
        "m/s2",
        "Time derivative of dv1: the tip's acceleration (Model Exchange)",
    ),
    derivative(
        Var::DerDtheta1,
        Var::Dtheta1,
        "der(dtheta1)",
        "rad/s2",
        "Time derivative of dtheta1: the tip section's angular acceleration (Model Exchange)",
    ),
    Variable {
        var: Var::Time,
        info: VarInfo {
            name: "time",
            causality: Causality::Independent,
            variability: Variability::Continuous,
            ty: Type::Real { unit: Some("s"), start: None, min: None, max: None },
            description: "Simulation time",
            derivative_of: None,
            structural: false,
            dims: &[],
            only: Only::Both,
        },
        setting: None,
    },
    continuous(
        Var::RangeMarginV1,
        Causality::Local,
        "range_margin_v1",
        "m",
        "l - |v1|: the margin of the quadratic model's range of validity in v1, an event \
         indicator of Model Exchange (1 with range_check = off or the exact beam)",
        None,
    ),
    continuous(
        Var::RangeMarginTheta1,
        Causality::Local,
        "range_margin_theta1",
        "rad",
        "pi/2 - |theta1|: the margin of the range of validity in theta1, an event indicator of \
         Model Exchange (1 with range_check = off or the exact beam)",
        None,
    ),
    param(Var::IntermediateStep, Key::IntermediateStep),
    array(
        Var::NodalV,
        Causality::Output,
        NODES,
        "nodal_v",
        "m",
        "Deflection v_k of every node k = 1..n_elements at x = k*l/n_elements, the tip last \
         (the exact beam: the centreline's y at arc length k*l/n_elements)",
        None,
    ),
    array(
        Var::NodalTheta,
        Causality::Output,
        NODES,
        "nodal_theta",
        "rad",
        "Slope theta_k of every node k = 1..n_elements, the tip last (the exact beam: the \
         section's angle)",
        None,
    ),
    array(
        Var::Q,
        Causality::Local,
        NODES_BY_TWO,
        "q",
        "",
        "Generalized coordinates, a row per node (Model Exchange's states): (v_k, theta_k) of \
         the quadratic beam in m and rad; the exact beam's own coordinates",
        None,
    ),
    array(
        Var::Dq,
        Causality::Local,
        NODES_BY_TWO,
        "dq",
        "",
        "Rates of the generalized coordinates q (Model Exchange's states)",
        Some(Var::Q),
    ),
    array(
        Var::Ddq,
        Causality::Local,
        NODES_BY_TWO,
        "ddq",
        "",
        "Accelerations of the generalized coordinates: the time derivative of dq (Model \
         Exchange)",
        Some(Var::Dq),
    ),
    param(Var::EnergyCheck, Key::EnergyCheck),
    param(Var::PhiFilterFrequency, Key::PhiFilterFrequency),
    filtered(
        Var::PhiFiltered,
        None,
        "phi_filtered",
        "rad",
        "Model Exchange: the hinge angle from the filter of the input phi (a continuous state; \
         the model's phi when the host sets phi alone, with phi_source = input); \
         co-simulation: phi_applied",
    ),
    filtered(
        Var::DphiFiltered,
        Some(Var::PhiFiltered),
        "dphi_filtered",
        "rad/s",
        "The rate of phi_filtered (a continuous state of Model Exchange; co-simulation: \
         dphi_applied)",
    ),
    filtered(
        Var::DdphiFiltered,
        Some(Var::DphiFiltered),
        "ddphi_filtered",
        "rad/s2",
        "The angular acceleration from the filter: the derivative of dphi_filtered \
         (co-simulation: ddphi_applied)",
    ),
    param(Var::Integrator, Key::Integrator),
];

/// FMI 2.0 Model Exchange's continuous states, in the order of x: the paper's coordinates
/// (v1, ϑ1) and their rates. Its model description fixes them, so it runs one element of
/// the quadratic beam (docs/interfaces.md, "Model Exchange").
/// Then the two states of the filter of φ, for a host that sends φ alone.
pub const STATES: [Var; 6] =
    [Var::V1, Var::Theta1, Var::Dv1, Var::Dtheta1, Var::PhiFiltered, Var::DphiFiltered];
/// Their derivatives, in the same order.
pub const DERIVATIVES: [Var; 6] = [
    Var::DerV1,
    Var::DerTheta1,
    Var::DerDv1,
    Var::DerDtheta1,
    Var::DphiFiltered,
    Var::DdphiFiltered,
];
/// FMI 3.0 Model Exchange's continuous states: the arrays q and dq, sized by n_elements,
/// so that it runs any beam (docs/interfaces.md, "FMI 3.0").
/// Then the filter's two, as in FMI 2.0.
pub const STATES3: [Var; 4] = [Var::Q, Var::Dq, Var::PhiFiltered, Var::DphiFiltered];
/// Their derivatives, in the same order.
pub const DERIVATIVES3: [Var; 4] = [Var::Dq, Var::Ddq, Var::DphiFiltered, Var::DdphiFiltered];
/// The number of event indicators: the margins of the range of validity, l − |v1| and
/// π/2 − |ϑ1|.
pub const EVENT_INDICATORS: usize = 2;
/// The event indicators as variables (FMI 3.0 lists them by value reference).
pub const INDICATOR_VARIABLES: [Var; EVENT_INDICATORS] =
    [Var::RangeMarginV1, Var::RangeMarginTheta1];
/// The inputs a host may set in intermediate update mode (FMI 3.0 co-simulation).
pub const INTERMEDIATE_INPUTS: [Var; 1] = [Var::Phi];

/// Whether FMI 3.0 marks `v` `intermediateUpdate = "true"`: the intermediate inputs, which a
/// host may set in intermediate update mode, and every output, which it may read there (the
/// model gives them at any time inside a step from its state).
pub fn intermediate_update(v: &Variable) -> bool {
    INTERMEDIATE_INPUTS.contains(&v.var) || v.causality == Causality::Output
}

/// FMI 3.0's own capability flags (the others are FMI 2.0's).
pub const FMI3_CAPABILITIES: Fmi3Capabilities = Fmi3Capabilities {
    provides_intermediate_update: true,
    has_event_mode: false,
    can_return_early_after_intermediate_update: false,
    recommended_intermediate_input_smoothness: 2,
};

/// The `<ModelExchange>` capability flags.
pub const EXCHANGE_CAPABILITIES: ExchangeCapabilities = ExchangeCapabilities {
    completed_integrator_step_not_needed: false,
    provides_directional_derivative: true,
};

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
             {CAPABILITIES:?}|{EXCHANGE_CAPABILITIES:?}|{FMI3_CAPABILITIES:?}|{STATES:?}|{STATES3:?}|{EVENT_INDICATORS}|{UNITS:?}|{ENUM_TYPES:?}|{LOG_CATEGORIES:?}|{VARIABLES:?}"
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

/// The variable called `name`.
pub fn by_name(name: &str) -> Option<&'static Variable> {
    VARIABLES.iter().find(|v| v.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn the_parameters_are_the_settings_table_s() {
        let fmu: Vec<Key> = VARIABLES.iter().filter_map(|v| v.setting).collect();
        let table: Vec<Key> =
            crate::settings::SETTINGS.iter().filter(|s| s.appears.fmu).map(|s| s.key).collect();
        for key in &table {
            assert_eq!(fmu.iter().filter(|k| *k == key).count(), 1, "{key:?}");
        }
        assert_eq!(fmu.len(), table.len());
        for v in VARIABLES.iter().filter(|v| v.causality == Causality::Parameter) {
            let s = Setting::of(v.setting.expect("a parameter has its setting"));
            assert_eq!((v.name, v.description), (s.name, s.description));
        }
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
