//! The types that describe an FMU's interface: variables with their causality, variability,
//! type, start value and range; units; the default experiment; the co-simulation capability
//! flags. A model fills them in ([`crate::fmu::variables`] for the beam–body model); the
//! core reads them to check calls, and `cargo xtask gen` writes `modelDescription.xml` from
//! them. No I/O, no `unsafe`.
#![forbid(unsafe_code)]

/// The enumeration of a setting, which a description lists as an `<EnumerationType>`.
pub use crate::choice::EnumType;

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

/// FMI 3.0's co-simulation flags beyond FMI 2.0's. Each one that is true is implemented and
/// tested.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fmi3Capabilities {
    /// fmi3DoStep calls the host's intermediate-update callback inside the step (every
    /// `intermediate_step`), and the host may set the inputs listed as intermediate then.
    pub provides_intermediate_update: bool,
    pub has_event_mode: bool,
    pub can_return_early_after_intermediate_update: bool,
    /// The derivatives of the inputs the FMU's reconstruction expects to be continuous.
    pub recommended_intermediate_input_smoothness: u32,
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
    /// The one independent variable, time: the host's (FMI 3.0 requires it).
    Independent,
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
    /// The FMI 2.0 base type whose functions (fmi2GetReal, …) access the variable.
    pub fn base(&self) -> BaseType {
        match self {
            Type::Real { .. } => BaseType::Real,
            Type::Integer { .. } | Type::Enumeration { .. } => BaseType::Integer,
            Type::Boolean { .. } => BaseType::Boolean,
        }
    }

    /// The FMI 3.0 type whose functions access it: Float64 (`Real`), Int32 (`Integer`),
    /// Int64 for enumerations (FMI 3.0 §2.4.7.5), Boolean.
    pub fn base3(&self) -> BaseType {
        match self {
            Type::Enumeration { .. } => BaseType::Int64,
            _ => self.base(),
        }
    }
}

/// The types of the get and set functions. FMI 2.0 has the first four; FMI 3.0 calls `Real`
/// Float64 and `Integer` Int32, and has the rest, of which this model has variables of Int64
/// only (its enumerations).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BaseType {
    Real,
    Integer,
    Boolean,
    String,
    Float32,
    Int8,
    UInt8,
    Int16,
    UInt16,
    UInt32,
    Int64,
    UInt64,
    Binary,
    Clock,
}

impl BaseType {
    /// Its name in the model description of `version`.
    pub fn name(self, version: Version) -> &'static str {
        match (self, version == Version::Fmi3) {
            (BaseType::Real, true) => "Float64",
            (BaseType::Integer, true) => "Int32",
            (BaseType::Real, false) => "Real",
            (BaseType::Integer, false) => "Integer",
            (BaseType::Boolean, _) => "Boolean",
            (BaseType::String, _) => "String",
            (BaseType::Float32, _) => "Float32",
            (BaseType::Int8, _) => "Int8",
            (BaseType::UInt8, _) => "UInt8",
            (BaseType::Int16, _) => "Int16",
            (BaseType::UInt16, _) => "UInt16",
            (BaseType::UInt32, _) => "UInt32",
            (BaseType::Int64, _) => "Int64",
            (BaseType::UInt64, _) => "UInt64",
            (BaseType::Binary, _) => "Binary",
            (BaseType::Clock, _) => "Clock",
        }
    }
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
    /// FMI 3.0: a structural parameter (`causality = "structuralParameter"`, UInt64), which
    /// sizes arrays and is set in configuration mode only. FMI 2.0 has it as a parameter.
    pub structural: bool,
    /// FMI 3.0: the array's dimensions, outermost first (row-major); empty for a scalar.
    pub dims: &'static [Dim],
    /// The model descriptions that hold the variable.
    pub only: Only,
}

impl VarInfo {
    /// The type of the get and set functions that access it in `version`: in FMI 3.0
    /// [`Type::base3`], and UInt64 for a structural parameter (FMI 3.0 §2.4.7.4: a
    /// `<Dimension>` refers to a UInt64).
    pub fn base_in(&self, version: Version) -> BaseType {
        match (version == Version::Fmi3, self.structural) {
            (true, true) => BaseType::UInt64,
            (true, false) => self.ty.base3(),
            (false, _) => self.ty.base(),
        }
    }

    /// Whether the model description of `version` holds it.
    pub fn in_version(&self, version: Version) -> bool {
        match self.only {
            Only::Both => true,
            Only::Fmi2 => version == Version::Fmi2,
            Only::Fmi3 => version == Version::Fmi3,
        }
    }
}

/// One dimension of an FMI 3.0 array variable (`<Dimension>`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dim {
    /// Sized by the structural parameter with this value reference.
    Param(u32),
    /// A fixed size.
    Fixed(u64),
}

/// Which model descriptions hold a variable: FMI 3.0's arrays are not in FMI 2.0's, and the
/// scalar state derivatives FMI 2.0 Model Exchange declares are not in FMI 3.0's, whose
/// states are arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Only {
    Both,
    Fmi2,
    Fmi3,
}

/// The model description a model instance serves, which fixes its variables and states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Version {
    Fmi2,
    Fmi3,
}

/// `<LogCategories>`: (name, description). Warnings and errors are always logged; the
/// others only when debug logging is on for them.
pub const LOG_CATEGORIES: &[(&str, &str)] = &[
    ("logStatusWarning", "Warnings"),
    ("logStatusDiscard", "Steps that ended early (Discard)"),
    ("logStatusError", "Errors: illegal calls, bad arguments, failed steps"),
    ("logStatusFatal", "Fatal errors: a caught panic"),
    ("logCalls", "Every call of the FMI API, with its arguments"),
    ("logAll", "All of the above"),
];
