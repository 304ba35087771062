//! The types that describe an FMU's interface: variables with their causality, variability,
//! type, start value and range; units; the default experiment; the co-simulation capability
//! flags. A model fills them in ([`crate::fmu::variables`] for the beam–body model); the
//! core reads them to check calls, and `cargo xtask gen` writes `modelDescription.xml` from
//! them. No I/O, no `unsafe`.
#![forbid(unsafe_code)]

pub use crate::settings::EnumType;

/// `<DefaultExperiment>`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DefaultExperiment {
    pub start_time: f64,
    pub stop_time: f64,
    pub tolerance: f64,
    pub step_size: f64,
}

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

/// The `<ModelExchange>` capability flags (the memory and instantiation flags are the
/// co-simulation's). Each one that is true is implemented and tested.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExchangeCapabilities {
    /// Whether the host may skip fmi2CompletedIntegratorStep: false, since the step's end
    /// is where the range of validity is checked.
    pub completed_integrator_step_not_needed: bool,
    pub provides_directional_derivative: bool,
}

/// A `<Unit>`: name and SI base-unit exponents (kg, m, s, rad; the others are zero).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit {
    pub name: &'static str,
    pub kg: i32,
    pub m: i32,
    pub s: i32,
    pub rad: i32,
}

impl Unit {
    pub const fn new(name: &'static str, kg: i32, m: i32, s: i32, rad: i32) -> Unit {
        Unit { name, kg, m, s, rad }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    Parameter,
    Input,
    Output,
    /// Computed and readable, never set: the derivatives of the continuous states.
    Local,
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

/// What the core knows of one variable (a `<ScalarVariable>`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VarInfo {
    pub name: &'static str,
    pub causality: Causality,
    pub variability: Variability,
    pub ty: Type,
    pub description: &'static str,
    /// For the derivative of a continuous state (Model Exchange): the state's value
    /// reference.
    pub derivative_of: Option<u32>,
}

/// `<LogCategories>`: (name, description). Warnings and errors are always logged; the
/// others only when debug logging is on for them.
pub const LOG_CATEGORIES: &[(&str, &str)] = &[
    ("logStatusWarning", "Warnings"),
    ("logStatusDiscard", "Steps that ended early (fmi2Discard)"),
    ("logStatusError", "Errors: illegal calls, bad arguments, failed steps"),
    ("logStatusFatal", "Fatal errors: a caught panic"),
    ("logCalls", "Every call of the FMI API, with its arguments"),
    ("logAll", "All of the above"),
];
