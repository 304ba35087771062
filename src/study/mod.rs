//! Design studies: one scene run over a grid of parameters, a Latin hypercube sample of
//! random ones, or both, with metrics per run.
//!
//! A study file (TOML) names the base scene, the parameters, the metrics and the solver's
//! settings ([`Study::parse`]). Its cases are numbered 0..[`Study::cases`]; a case's values
//! depend only on its number, so any range of cases can run alone (a chunk) and give the rows
//! a run of the whole study gives. [`Study::run_case`] runs one case and never fails: a case
//! that cannot run, or stops, is a [`Row`] with its status and message. [`run_cases`] runs a
//! range on several threads. Parsing takes text and a loader for the scene file: no I/O here.
#![forbid(unsafe_code)]

mod axis;
mod case;
mod file;
mod peaks;
mod runner;
mod sample;

pub use axis::{Axis, Distribution};
pub use runner::run_cases;
pub use sample::{normal_cdf, normal_quantile};

use crate::model::{BeamBody, BeamN, Formulation};
use crate::scene::locate;
use crate::settings::{Kind, Setting, SETTINGS};
use crate::sim::{simulate_steps, Scene, SimError};
use crate::solver::SolverError;
use sample::{grid_point, latin_hypercube, name_key, open_unit};
use std::fmt;
use toml::{Table, Value};

/// The settings a study can vary (`appears.study` in the table): the model's parameters, the
/// law and the initial state.
pub fn variables() -> impl Iterator<Item = &'static Setting> {
    SETTINGS.iter().filter(|s| s.appears.study)
}

/// What a study computes per run, from the integrator's dense output over every step
/// ([`peaks`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// max |v1 − v1_eq| [m] over t ≥ t_rot, with v1_eq the static deflection at φ_end (of the
    /// formulation's own equations: (15), or (16) for the linear one).
    ResidualV1,
    /// max |M| [N·m], the hinge moment.
    PeakM,
    /// max |M_root| [N·m], the bending moment at the clamp.
    PeakMRoot,
    /// max |N| [N], the hinge force along x.
    PeakN,
    /// max |P| [N], the hinge force along y.
    PeakP,
    /// max |v1| [m].
    MaxV1,
    /// max |ϑ1| [rad].
    MaxTheta1,
    /// The total mechanical energy at t_end [J].
    EnergyFinal,
}

impl Metric {
    pub const ALL: [Metric; 8] = [
        Metric::ResidualV1,
        Metric::PeakM,
        Metric::PeakMRoot,
        Metric::PeakN,
        Metric::PeakP,
        Metric::MaxV1,
        Metric::MaxTheta1,
        Metric::EnergyFinal,
    ];

    /// The column name.
    pub fn name(self) -> &'static str {
        match self {
            Metric::ResidualV1 => "residual_v1",
            Metric::PeakM => "peak_M",
            Metric::PeakMRoot => "peak_M_root",
            Metric::PeakN => "peak_N",
            Metric::PeakP => "peak_P",
            Metric::MaxV1 => "max_v1",
            Metric::MaxTheta1 => "max_theta1",
            Metric::EnergyFinal => "energy_final",
        }
    }

    /// The unit of the column.
    pub fn unit(self) -> &'static str {
        match self {
            Metric::ResidualV1 | Metric::MaxV1 => "m",
            Metric::PeakM | Metric::PeakMRoot => "N.m",
            Metric::PeakN | Metric::PeakP => "N",
            Metric::MaxTheta1 => "rad",
            Metric::EnergyFinal => "J",
        }
    }

    fn by_name(name: &str) -> Option<Metric> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Ran to t_end.
    Ok,
    /// Ran to t_end, and left the range of validity on the way (`range_check = warn`).
    Warning,
    /// Stopped where the state left the range of validity (`range_check = stop`).
    Stopped,
    /// The integration failed, or a metric is not finite.
    Failed,
    /// The case's values do not make a valid scene.
    Invalid,
}

impl Status {
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Warning => "warning",
            Status::Stopped => "stopped",
            Status::Failed => "failed",
            Status::Invalid => "invalid",
        }
    }
}

/// One case's row: its number, the values of the parameters (in the study's order), the
/// metrics (`None` unless the run reached t_end), the status, its message, and the
/// integrator's accepted steps.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub case: u64,
    pub values: Vec<f64>,
    pub metrics: Vec<Option<f64>>,
    pub status: Status,
    pub message: String,
    pub steps: u64,
}

/// The type of a column of the results table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColumnType {
    Int,
    Float,
    Text,
}

/// A varied parameter: one of [`VARIABLES`] and its axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    pub name: String,
    pub axis: Axis,
}

impl Parameter {
    /// Whether the setting takes integers (`n_elements`): its values are whole numbers, and
    /// its column is an integer column.
    pub fn is_integer(&self) -> bool {
        is_integer(&self.name)
    }
}

/// Whether the setting called `name` takes integers.
fn is_integer(name: &str) -> bool {
    Setting::by_name(name).is_ok_and(|s| matches!(s.kind, Kind::Integer))
}

/// A study, checked: every case it names is a scene that can be set up (a case can still be
/// invalid for reasons that depend on several values at once, such as a singular mass
/// matrix at the start; its row says so).
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    base: Scene,
    scene: Option<String>,
    parameters: Vec<Parameter>,
    metrics: Vec<Metric>,
    samples: u64,
    seed: u64,
    cases: u64,
}

/// The most cases a study may have (the case number is exact in a double).
pub const MAX_CASES: u64 = 1 << 53;

impl Study {
    /// A hash of the parsed study and its resolved base scene (16 hex digits): the same for
    /// files that differ only in comments, layout, key order or the spelling of a number, and
    /// different for any change to what the study runs.
    pub fn fingerprint(&self) -> String {
        format!("{:016x}", crate::hash::fnv1a_64(format!("{self:?}").as_bytes()))
    }

    /// The number of cases: the product of the grids' counts, times the samples.
    pub fn cases(&self) -> u64 {
        self.cases
    }

    /// The base scene's path as the study file gives it.
    pub fn scene_path(&self) -> Option<&str> {
        self.scene.as_deref()
    }

    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    pub fn metrics(&self) -> &[Metric] {
        &self.metrics
    }

    /// The random samples per grid point (1 without random parameters).
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// The columns of the results table, in order: a column with a unit is headed
    /// `name [unit]`, as the CLI's CSV is.
    pub fn columns(&self) -> Vec<(String, ColumnType)> {
        let mut cols = vec![("case".to_string(), ColumnType::Int)];
        cols.extend(self.parameters.iter().map(|p| {
            let unit = Setting::by_name(&p.name).ok().and_then(|s| s.unit());
            let ty = if p.is_integer() { ColumnType::Int } else { ColumnType::Float };
            (crate::csv::header(&p.name, unit), ty)
        }));
        cols.extend(
            self.metrics
                .iter()
                .map(|m| (crate::csv::header(m.name(), Some(m.unit())), ColumnType::Float)),
        );
        cols.push(("status".into(), ColumnType::Text));
        cols.push(("message".into(), ColumnType::Text));
        cols.push(("steps".into(), ColumnType::Int));
        cols
    }
}

impl fmt::Display for ColumnType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ColumnType::Int => "int64",
            ColumnType::Float => "float64",
            ColumnType::Text => "string",
        })
    }
}

#[cfg(test)]
mod tests;
