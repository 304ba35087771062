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

mod runner;
mod sample;

pub use runner::run_cases;
pub use sample::{normal_cdf, normal_quantile};

use crate::model::{BeamBody, Formulation, Outputs};
use crate::scene::locate;
use crate::settings::{Setting, SETTINGS};
use crate::sim::{simulate_partial, Scene, SimError};
use crate::solver::SolverError;
use sample::{grid_point, latin_hypercube, name_key, open_unit};
use std::fmt;
use toml::{Table, Value};

/// The settings a study can vary (`appears.study` in the table): the model's parameters, the
/// law and the initial state.
pub fn variables() -> impl Iterator<Item = &'static Setting> {
    SETTINGS.iter().filter(|s| s.appears.study)
}

/// What a study computes per run, over the output times k·dt_out of the run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// max |v1 − v1_eq| [m] over t ≥ t_rot, with v1_eq the static deflection at φ_end (of the
    /// formulation's own equations: (15), or (16) for the linear one).
    ResidualV1,
    /// max |M| [N·m], the hinge moment.
    PeakM,
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
    pub const ALL: [Metric; 7] = [
        Metric::ResidualV1,
        Metric::PeakM,
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
            Metric::PeakM => "N.m",
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

/// How a random parameter is distributed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Distribution {
    Uniform {
        low: f64,
        high: f64,
    },
    /// Normal with mean and standard deviation, truncated to [min, max] where given.
    Normal {
        mean: f64,
        sd: f64,
        min: f64,
        max: f64,
    },
    /// Log-normal with the mean and standard deviation of the value itself.
    LogNormal {
        mean: f64,
        sd: f64,
    },
}

impl Distribution {
    /// The value at probability `u` in (0, 1).
    fn quantile(&self, u: f64) -> f64 {
        match *self {
            Distribution::Uniform { low, high } => low + (high - low) * u,
            Distribution::Normal { mean, sd, min, max } => {
                let (lo, hi) = (normal_cdf((min - mean) / sd), normal_cdf((max - mean) / sd));
                // p can round to 0 or 1 where [min, max] lies far in a tail.
                let p = open_unit(lo + (hi - lo) * u);
                (mean + sd * normal_quantile(p)).clamp(min, max)
            }
            Distribution::LogNormal { mean, sd } => {
                let (mu, sigma) = lognormal_mu_sigma(mean, sd);
                crate::math::exp(mu + sigma * normal_quantile(u))
            }
        }
    }

    /// The smallest and largest values it can take.
    fn support(&self) -> (f64, f64) {
        match *self {
            Distribution::Uniform { low, high } => (low, high),
            Distribution::Normal { min, max, .. } => (min, max),
            Distribution::LogNormal { .. } => (f64::MIN_POSITIVE, f64::INFINITY),
        }
    }
}

/// μ and σ of ln X for a log-normal X with the given mean and standard deviation:
/// σ² = ln(1 + sd²/mean²), μ = ln(mean) − σ²/2.
fn lognormal_mu_sigma(mean: f64, sd: f64) -> (f64, f64) {
    let s2 = crate::math::ln(1.0 + (sd / mean) * (sd / mean));
    (crate::math::ln(mean) - 0.5 * s2, s2.sqrt())
}

/// Where a parameter's values come from.
#[derive(Clone, Debug, PartialEq)]
pub enum Axis {
    /// `count` points from `start` to `stop`, evenly or (log) geometrically spaced.
    Grid { start: f64, stop: f64, count: u64, log: bool },
    /// The values listed.
    Values(Vec<f64>),
    /// A Latin hypercube sample of `[sampling] samples` values.
    Random(Distribution),
}

impl Axis {
    fn grid_len(&self) -> Option<u64> {
        match self {
            Axis::Grid { count, .. } => Some(*count),
            Axis::Values(v) => Some(v.len() as u64),
            Axis::Random(_) => None,
        }
    }

    fn grid_value(&self, k: u64) -> f64 {
        match self {
            Axis::Grid { start, stop, count, log } => grid_point(*start, *stop, *count, k, *log),
            Axis::Values(v) => v[k as usize],
            Axis::Random(_) => unreachable!("not a grid"),
        }
    }

    /// The smallest and largest values.
    fn bounds(&self) -> (f64, f64) {
        match self {
            Axis::Grid { start, stop, .. } => (start.min(*stop), start.max(*stop)),
            Axis::Values(v) => {
                v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)))
            }
            Axis::Random(d) => d.support(),
        }
    }
}

/// A varied parameter: one of [`VARIABLES`] and its axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    pub name: String,
    pub axis: Axis,
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
    /// Parses and checks a study file. `load_scene` gets the value of its `scene` key (a
    /// path, relative to the study file) and returns the scene file's text. Errors name the
    /// field (`parameters.M2.count`) and what it allows.
    pub fn parse(
        text: &str,
        load_scene: impl FnOnce(&str) -> Result<String, String>,
    ) -> Result<Study, String> {
        Self::parse_table(text, load_scene).map_err(|e| locate_field(text, e))
    }

    fn parse_table(
        text: &str,
        load_scene: impl FnOnce(&str) -> Result<String, String>,
    ) -> Result<Study, String> {
        let table: Table = text.parse().map_err(|e| crate::scene::syntax_error(text, &e))?;
        const TOP: [&str; 8] =
            ["scene", "formulation", "rtol", "atol", "metrics", "sampling", "set", "parameters"];
        check_keys(&table, "", &TOP)?;

        let mut base = Scene::default();
        let scene = match table.get("scene") {
            Some(v) => Some(string(v, "scene")?.to_string()),
            None => None,
        };
        if let Some(path) = &scene {
            let text = load_scene(path).map_err(|e| format!("`scene`: {e}"))?;
            base.apply_toml(&text).map_err(|e| format!("scene {path}: {e}"))?;
        }
        for key in ["formulation", "rtol", "atol"] {
            if let Some(v) = table.get(key) {
                base.set_toml(key, v).map_err(|e| format!("`{key}`: {e}"))?;
            }
        }
        let set = match table.get("set") {
            Some(v) => Some(sub_table(v, "set")?),
            None => None,
        };
        for (key, v) in set.into_iter().flatten() {
            base.set_toml(key, v).map_err(|e| format!("`set.{key}`: {e}"))?;
        }
        base.validate().map_err(|e| format!("the base scene: {e}"))?;

        let mut parameters = Vec::new();
        if let Some(v) = table.get("parameters") {
            for (name, spec) in sub_table(v, "parameters")? {
                let field = format!("parameters.{name}");
                if !variables().any(|s| s.name == name) {
                    let names: Vec<&str> = variables().map(|s| s.name).collect();
                    return Err(format!(
                        "`{field}`: unknown parameter `{name}`; a study can vary {}",
                        names.join(", ")
                    ));
                }
                if set.is_some_and(|s| s.contains_key(name)) {
                    return Err(format!("`{field}`: `{name}` is also fixed in [set]"));
                }
                let axis = parse_axis(sub_table(spec, &field)?, &field)?;
                check_axis_range(&base, name, &axis, &field)?;
                parameters.push(Parameter { name: name.clone(), axis });
            }
        }

        let random = parameters.iter().any(|p| matches!(p.axis, Axis::Random(_)));
        let (mut samples, mut seed) = (1, 0);
        match table.get("sampling") {
            Some(v) => {
                let s = sub_table(v, "sampling")?;
                check_keys(s, "sampling", &["samples", "seed"])?;
                if !random {
                    return Err("`sampling`: no parameter has a distribution".into());
                }
                samples = count(s.get("samples"), "sampling.samples")?;
                if samples > MAX_CASES {
                    return Err(format!(
                        "`sampling.samples` = {samples}: must be at most {MAX_CASES} (2^53)"
                    ));
                }
                seed = match s.get("seed") {
                    Some(Value::Integer(i)) if *i >= 0 => *i as u64,
                    Some(_) => return Err("`sampling.seed`: must be a non-negative integer".into()),
                    None => return Err("`sampling.seed` is missing: give a seed".into()),
                };
            }
            None if random => {
                return Err(
                    "`sampling` is missing: random parameters need `[sampling] samples = N` \
                     and `seed = S`"
                        .into(),
                )
            }
            None => {}
        }

        let metrics = match table.get("metrics") {
            None => Metric::ALL.to_vec(),
            Some(Value::Array(items)) => {
                let mut out = Vec::new();
                for (i, item) in items.iter().enumerate() {
                    let field = format!("metrics[{i}]");
                    let name = string(item, &field)?;
                    let m = Metric::by_name(name).ok_or_else(|| {
                        let all: Vec<_> = Metric::ALL.iter().map(|m| m.name()).collect();
                        format!("`{field}`: unknown metric `{name}`; one of {}", all.join(", "))
                    })?;
                    if out.contains(&m) {
                        return Err(format!("`{field}`: `{name}` is listed twice"));
                    }
                    out.push(m);
                }
                if out.is_empty() {
                    return Err("`metrics`: the list is empty".into());
                }
                out
            }
            Some(_) => {
                let all: Vec<_> = Metric::ALL.iter().map(|m| m.name()).collect();
                return Err(format!(
                    "`metrics`: must be a list of metric names: {}",
                    all.join(", ")
                ));
            }
        };
        if metrics.contains(&Metric::ResidualV1) {
            check_residual_window(&base, &parameters)?;
        }

        let mut cases: u64 = samples;
        for p in &parameters {
            if let Some(n) = p.axis.grid_len() {
                cases = cases
                    .checked_mul(n)
                    .filter(|&c| c <= MAX_CASES)
                    .ok_or_else(|| format!("`parameters`: more than {MAX_CASES} cases"))?;
            }
        }
        Ok(Study { base, scene, parameters, metrics, samples, seed, cases })
    }

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
            (crate::csv::header(&p.name, unit), ColumnType::Float)
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

    /// The parameters' values of case `case` (< [`cases`](Self::cases)). The grids vary in
    /// the order written, the first slowest; the random samples vary fastest, the same n
    /// samples at every grid point.
    pub fn values(&self, case: u64) -> Vec<f64> {
        assert!(case < self.cases, "case {case} of {}", self.cases);
        let (mut grid_index, sample) = (case / self.samples, case % self.samples);
        let mut values = vec![0.0; self.parameters.len()];
        for (i, p) in self.parameters.iter().enumerate().rev() {
            if let Some(n) = p.axis.grid_len() {
                values[i] = p.axis.grid_value(grid_index % n);
                grid_index /= n;
            }
        }
        for (i, p) in self.parameters.iter().enumerate() {
            if let Axis::Random(d) = &p.axis {
                let u = latin_hypercube(self.seed, name_key(&p.name), sample, self.samples);
                values[i] = d.quantile(u);
            }
        }
        values
    }

    /// Runs case `case` and computes its metrics. Never fails: see [`Row`].
    pub fn run_case(&self, case: u64) -> Row {
        let values = self.values(case);
        let mut row = Row {
            case,
            values: values.clone(),
            metrics: vec![None; self.metrics.len()],
            status: Status::Invalid,
            message: String::new(),
            steps: 0,
        };
        let mut scene = self.base.clone();
        for (p, &v) in self.parameters.iter().zip(&values) {
            if let Err(e) = scene.set_number(&p.name, v) {
                row.message = e;
                return row;
            }
        }
        // The static deflection residual_v1 is measured from; only that metric needs it.
        let v1_eq = if self.metrics.contains(&Metric::ResidualV1) {
            if scene.law.t_rot >= scene.t_end {
                row.message = format!(
                    "residual_v1 needs t_end > t_rot, but t_rot = {} and t_end = {}",
                    scene.law.t_rot, scene.t_end
                );
                return row;
            }
            let linear = scene.formulation == Formulation::Linear;
            match BeamBody::new(scene.params).map(|m| m.equilibrium(scene.law.phi_end, linear)) {
                Ok(Some((v1, _))) => v1,
                Ok(None) => {
                    row.status = Status::Failed;
                    row.message = format!(
                        "the static equilibrium at phi_end = {} did not converge (residual_v1 \
                         is measured from it)",
                        scene.law.phi_end
                    );
                    return row;
                }
                Err(e) => {
                    row.message = e.to_string();
                    return row;
                }
            }
        } else {
            0.0 // unused; an invalid model is reported by the run
        };
        let mut acc = Accumulator::new(v1_eq, scene.law.t_rot);
        let (report, result) = simulate_partial(&scene, |o| {
            acc.add(o);
            std::ops::ControlFlow::Continue(())
        });
        row.steps = report.stats.steps;
        match result {
            Ok(()) => {
                (row.status, row.message) = match report.warning {
                    Some(w) => (Status::Warning, w),
                    None => (Status::Ok, String::new()),
                };
                for (slot, &m) in row.metrics.iter_mut().zip(&self.metrics) {
                    let value = acc.get(m);
                    if !value.is_finite() {
                        row.status = Status::Failed;
                        row.message = format!("metric `{}` is not finite ({value})", m.name());
                        row.metrics.fill(None);
                        return row;
                    }
                    *slot = Some(value);
                }
            }
            Err(e) => {
                row.status = match &e {
                    SimError::Setting(_) => Status::Invalid,
                    SimError::Solver(SolverError::OutOfRange { .. }) => Status::Stopped,
                    SimError::Solver(_) | SimError::Stopped => Status::Failed,
                };
                row.message = e.to_string();
            }
        }
        row
    }
}

/// The metrics of one run so far.
struct Accumulator {
    v1_eq: f64,
    t_rot: f64,
    /// `None` until the first output time at or after t_rot.
    residual: Option<f64>,
    peak_m: f64,
    peak_n: f64,
    peak_p: f64,
    max_v1: f64,
    max_theta1: f64,
    energy: f64,
}

impl Accumulator {
    fn new(v1_eq: f64, t_rot: f64) -> Self {
        Self {
            v1_eq,
            t_rot,
            residual: None,
            peak_m: 0.0,
            peak_n: 0.0,
            peak_p: 0.0,
            max_v1: 0.0,
            max_theta1: 0.0,
            energy: f64::NAN,
        }
    }

    /// `f64::max` ignores a NaN operand; a NaN output must reach the metric and fail the row.
    fn add(&mut self, o: &Outputs) {
        let max = |acc: f64, x: f64| if x.is_nan() || acc.is_nan() { f64::NAN } else { acc.max(x) };
        let r = &o.reactions;
        self.peak_m = max(self.peak_m, r.m.abs());
        self.peak_n = max(self.peak_n, r.n.abs());
        self.peak_p = max(self.peak_p, r.p.abs());
        self.max_v1 = max(self.max_v1, o.v1.abs());
        self.max_theta1 = max(self.max_theta1, o.theta1.abs());
        if o.t >= self.t_rot {
            let d = (o.v1 - self.v1_eq).abs();
            self.residual = Some(self.residual.map_or(d, |r| max(r, d)));
        }
        self.energy = o.energy;
    }

    fn get(&self, m: Metric) -> f64 {
        match m {
            Metric::ResidualV1 => self.residual.unwrap_or(f64::NAN),
            Metric::PeakM => self.peak_m,
            Metric::PeakN => self.peak_n,
            Metric::PeakP => self.peak_p,
            Metric::MaxV1 => self.max_v1,
            Metric::MaxTheta1 => self.max_theta1,
            Metric::EnergyFinal => self.energy,
        }
    }
}

/// residual_v1 needs output times after the turn: t_end > t_rot for every case.
fn check_residual_window(base: &Scene, parameters: &[Parameter]) -> Result<(), String> {
    let t_end = base.t_end;
    match parameters.iter().find(|p| p.name == "t_rot") {
        Some(p) => {
            let hi = p.axis.bounds().1;
            if hi >= t_end {
                let bound = match &p.axis {
                    Axis::Random(Distribution::Normal { .. }) => " (set `max` below it)",
                    Axis::Random(Distribution::LogNormal { .. }) => {
                        " (a log-normal is unbounded above: use a truncated normal)"
                    }
                    _ => "",
                };
                return Err(format!(
                    "`parameters.t_rot` reaches {hi}, but the metric residual_v1 needs \
                     t_rot < t_end = {t_end}{bound}"
                ));
            }
        }
        None if base.law.t_rot >= t_end => {
            return Err(format!(
                "`metrics`: residual_v1 needs t_rot < t_end, but t_rot = {} and t_end = {t_end}",
                base.law.t_rot
            ))
        }
        None => {}
    }
    Ok(())
}

/// Checks that every value the axis can give is one the scene accepts for `name`, by
/// setting its bounds on a scratch scene: the scene's own checks are the one definition of
/// the ranges.
fn check_axis_range(base: &Scene, name: &str, axis: &Axis, field: &str) -> Result<(), String> {
    let (lo_key, hi_key) = match axis {
        // A list: every value, so that the error names the one that is out of range.
        Axis::Values(values) => {
            for (i, &v) in values.iter().enumerate() {
                if let Err(e) = base.clone().set_number(name, v) {
                    return Err(format!("`{field}.values[{i}]`: {e}"));
                }
            }
            return Ok(());
        }
        Axis::Grid { start, stop, .. } if start <= stop => ("start", "stop"),
        Axis::Grid { .. } => ("stop", "start"),
        Axis::Random(Distribution::Uniform { .. }) => ("low", "high"),
        Axis::Random(Distribution::Normal { .. }) => ("min", "max"),
        Axis::Random(Distribution::LogNormal { .. }) => ("mean", "mean"),
    };
    let (lo, hi) = axis.bounds();
    for (value, key) in [(lo, lo_key), (hi, hi_key)] {
        // An unbounded side is checked at the largest finite value.
        let probe = value.clamp(-f64::MAX, f64::MAX);
        if let Err(e) = base.clone().set_number(name, probe) {
            if value.is_infinite() {
                let side = if value < 0.0 { "below" } else { "above" };
                let allowed = e.rsplit_once("must be ").map_or(e.as_str(), |(_, a)| a);
                return Err(format!(
                    "`{field}`: the distribution is unbounded {side}, and `{name}` must be \
                     {allowed}: set `{field}.{key}` to truncate it"
                ));
            }
            return Err(format!("`{field}.{key}`: {e}"));
        }
    }
    Ok(())
}

fn parse_axis(spec: &Table, field: &str) -> Result<Axis, String> {
    let num = |key: &str| number(spec.get(key), &format!("{field}.{key}"));
    if let Some(kind) = spec.get("distribution") {
        let kind = string(kind, &format!("{field}.distribution"))?;
        let d = match kind {
            "uniform" => {
                check_keys(spec, field, &["distribution", "low", "high"])?;
                let (low, high) = (num("low")?, num("high")?);
                if low >= high {
                    return Err(format!("`{field}.high` = {high}: must exceed low = {low}"));
                }
                Distribution::Uniform { low, high }
            }
            "normal" => {
                check_keys(spec, field, &["distribution", "mean", "sd", "min", "max"])?;
                let (mean, sd) = (num("mean")?, num("sd")?);
                positive(sd, &format!("{field}.sd"))?;
                let bound = |key: &str, default: f64| match spec.get(key) {
                    Some(_) => num(key),
                    None => Ok(default),
                };
                let (min, max) = (bound("min", f64::NEG_INFINITY)?, bound("max", f64::INFINITY)?);
                if min >= max {
                    return Err(format!("`{field}.max` = {max}: must exceed min = {min}"));
                }
                // Enough probability inside [min, max] to sample it by the quantile.
                if normal_cdf((max - mean) / sd) - normal_cdf((min - mean) / sd) < 1e-6 {
                    return Err(format!(
                        "`{field}`: [min, max] = [{min}, {max}] holds less than 1e-6 of the \
                         distribution's probability"
                    ));
                }
                Distribution::Normal { mean, sd, min, max }
            }
            "lognormal" | "log-normal" => {
                check_keys(spec, field, &["distribution", "mean", "sd"])?;
                let (mean, sd) = (num("mean")?, num("sd")?);
                positive(mean, &format!("{field}.mean"))?;
                positive(sd, &format!("{field}.sd"))?;
                Distribution::LogNormal { mean, sd }
            }
            other => {
                return Err(format!(
                    "`{field}.distribution` = \"{other}\": must be uniform, normal or lognormal"
                ))
            }
        };
        return Ok(Axis::Random(d));
    }
    if let Some(v) = spec.get("values") {
        check_keys(spec, field, &["values"])?;
        let Value::Array(items) = v else {
            return Err(format!("`{field}.values`: must be a list of numbers"));
        };
        if items.is_empty() {
            return Err(format!("`{field}.values`: the list is empty"));
        }
        let values = items
            .iter()
            .enumerate()
            .map(|(i, x)| number(Some(x), &format!("{field}.values[{i}]")))
            .collect::<Result<Vec<_>, _>>()?;
        return Ok(Axis::Values(values));
    }
    if spec.contains_key("start") || spec.contains_key("stop") || spec.contains_key("count") {
        check_keys(spec, field, &["start", "stop", "count", "spacing"])?;
        let (start, stop) = (num("start")?, num("stop")?);
        let count = count(spec.get("count"), &format!("{field}.count"))?;
        let log = match spec.get("spacing") {
            None => false,
            Some(v) => match string(v, &format!("{field}.spacing"))? {
                "linear" => false,
                "log" => true,
                other => {
                    return Err(format!(
                        "`{field}.spacing` = \"{other}\": must be \"linear\" or \"log\""
                    ))
                }
            },
        };
        if log && !(start > 0.0 && stop > 0.0) {
            return Err(format!(
                "`{field}`: a log grid needs start and stop > 0, got {start} and {stop}"
            ));
        }
        if count > 1 && start == stop {
            return Err(format!(
                "`{field}.stop` = {stop}: must differ from start when count = {count} > 1"
            ));
        }
        if count == 1 && start != stop {
            return Err(format!(
                "`{field}.stop` = {stop}: a grid of count = 1 is its start alone, so stop must \
                 equal start = {start} (or use values = [...])"
            ));
        }
        return Ok(Axis::Grid { start, stop, count, log });
    }
    Err(format!(
        "`{field}`: give a grid (start, stop, count[, spacing]), a list (values = [...]) or a \
         distribution (distribution = \"uniform\" | \"normal\" | \"lognormal\")"
    ))
}

fn check_keys(table: &Table, field: &str, allowed: &[&str]) -> Result<(), String> {
    for key in table.keys() {
        if !allowed.contains(&key.as_str()) {
            let path = if field.is_empty() { key.clone() } else { format!("{field}.{key}") };
            return Err(format!("`{path}`: unknown key; expected one of {}", allowed.join(", ")));
        }
    }
    Ok(())
}

fn sub_table<'a>(v: &'a Value, field: &str) -> Result<&'a Table, String> {
    v.as_table().ok_or_else(|| format!("`{field}`: must be a table"))
}

fn string<'a>(v: &'a Value, field: &str) -> Result<&'a str, String> {
    v.as_str().ok_or_else(|| format!("`{field}`: must be a string"))
}

fn number(v: Option<&Value>, field: &str) -> Result<f64, String> {
    let x = match v {
        Some(Value::Float(x)) => *x,
        Some(Value::Integer(i)) => *i as f64,
        Some(_) => return Err(format!("`{field}`: must be a number")),
        None => return Err(format!("`{field}` is missing")),
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(format!("`{field}` = {x}: must be finite"))
    }
}

fn positive(x: f64, field: &str) -> Result<(), String> {
    if x > 0.0 {
        Ok(())
    } else {
        Err(format!("`{field}` = {x}: must be positive"))
    }
}

fn count(v: Option<&Value>, field: &str) -> Result<u64, String> {
    match v {
        Some(Value::Integer(i)) if *i >= 1 => Ok(*i as u64),
        Some(Value::Integer(i)) => Err(format!("`{field}` = {i}: must be at least 1")),
        Some(_) => Err(format!("`{field}`: must be an integer, at least 1")),
        None => Err(format!("`{field}` is missing")),
    }
}

/// `message`, prefixed with the line of the field it names first (`` `parameters.EI.count`:
/// … ``), when the study's text has it.
fn locate_field(text: &str, message: String) -> String {
    let field = message
        .strip_prefix('`')
        .and_then(|rest| rest.split_once('`'))
        .map(|(field, _)| field.to_string());
    match field {
        Some(field) => {
            // `metrics[2]` and `values[0]` are on the line of their list.
            let path: Vec<&str> =
                field.split('.').map(|k| k.split_once('[').map_or(k, |(k, _)| k)).collect();
            locate(text, &path, message)
        }
        None => message,
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
