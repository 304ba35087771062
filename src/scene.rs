//! A scene: every setting of one run, as the table [`SETTINGS`] lists them, and the checks
//! that need several of them at once. The CLI reads it from a scene file and `--set`, a study
//! from its files, the FMU from its parameters: one value, one set of rules.
//!
//! No I/O: text comes in, a scene or an error that names the setting (and, from a file, the
//! line) goes out.
#![forbid(unsafe_code)]

use crate::model::{BeamBody, BeamModel, Formulation, Interpolation, PaperLaw, Params, RangeCheck};
use crate::settings::{Field, Key, Kind, Setting, Value, SETTINGS};
use crate::solver::{BdfConfig, FixedStep, Method};

/// Initial state of the beam [m, rad, m/s, rad/s]. The DAE's u2, u̇2 start consistent.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct InitialState {
    pub v1: f64,
    pub theta1: f64,
    pub dv1: f64,
    pub dtheta1: f64,
}

/// Where φ comes from (`phi_source`). In the CLI, `Input` feeds the law's samples at every
/// `dt_comm` exactly as an FMI host feeds the FMU, so that the two can be compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhiSource {
    Input,
    Law,
}

impl PhiSource {
    /// In the order of the enumeration's items.
    pub const ALL: [PhiSource; 2] = [PhiSource::Input, PhiSource::Law];
}

/// The integrator's settings as the table has them: plain numbers, 0 for "the default".
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolverSettings {
    pub rtol: f64,
    /// 0: the integrator's default (`BdfConfig::atol`).
    pub atol: f64,
    pub max_order: usize,
    /// 0: the adaptive BDF.
    pub fixed_step: f64,
    /// 0: order 2 (with `fixed_step`).
    pub fixed_order: usize,
    pub stability_guard: bool,
    pub integrator: IntegratorChoice,
}

/// The `integrator` setting: a method, or `auto`, the one that wins on the scene's beam
/// (docs/decisions.md, "Radau IIA"): Radau IIA for the exact beam, whose element modes set
/// the BDF's step; the BDF for the paper's theories, where it takes fewer, cheaper steps, and
/// for the paper's constant-step mode, which is the BDF's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IntegratorChoice {
    #[default]
    Auto,
    Bdf,
    Radau,
}

impl IntegratorChoice {
    /// In the order of the enumeration's items.
    pub const ALL: [IntegratorChoice; 3] =
        [IntegratorChoice::Auto, IntegratorChoice::Bdf, IntegratorChoice::Radau];

    /// The method a run of `beam` uses; `fixed`: the constant-step mode.
    pub fn method(self, beam: BeamModel, fixed: bool) -> Method {
        match self {
            IntegratorChoice::Bdf => Method::Bdf,
            IntegratorChoice::Radau => Method::Radau,
            IntegratorChoice::Auto if fixed || beam == BeamModel::Quadratic => Method::Bdf,
            IntegratorChoice::Auto => Method::Radau,
        }
    }
}

impl SolverSettings {
    /// The integrator's configuration for a run of `beam`, with at most `max_steps` steps per
    /// call.
    pub fn config(&self, beam: BeamModel, max_steps: u64) -> BdfConfig {
        let order = if self.fixed_order == 0 { 2 } else { self.fixed_order };
        BdfConfig {
            rtol: self.rtol,
            atol: (self.atol > 0.0).then_some(self.atol),
            max_order: self.max_order,
            fixed_step: (self.fixed_step > 0.0).then_some(FixedStep { h: self.fixed_step, order }),
            stability_guard: self.stability_guard,
            method: self.integrator.method(beam, self.fixed_step > 0.0),
            max_steps,
            ..BdfConfig::default()
        }
    }

    /// The absolute tolerance in use for a run of `beam`.
    pub fn atol(&self, beam: BeamModel) -> f64 {
        self.config(beam, 1).atol()
    }
}

/// A scene: what to simulate and how to sample it. Its fields are the table's settings;
/// [`Scene::default`] holds the table's defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub params: Params,
    pub law: PaperLaw,
    pub initial: InitialState,
    pub formulation: Formulation,
    pub phi_source: PhiSource,
    pub phi_interpolation: Interpolation,
    pub phi_extrapolation: usize,
    /// FMI 3.0's intermediate update: the spacing of the host's φ inside a step.
    pub intermediate_step: f64,
    /// The CLI's emulated host also sends φ′, φ″ (`phi_source = input`).
    pub input_derivatives: bool,
    /// The CLI's emulated host's communication step [s].
    pub dt_comm: f64,
    pub solver: SolverSettings,
    pub range_check: RangeCheck,
    /// What a broken energy balance does (`energy_check`: stop, warn, off).
    pub energy_check: RangeCheck,
    /// Model Exchange's filter of a host's φ sent alone: its cut-off frequency [Hz].
    pub phi_filter_frequency: f64,
    /// End time [s].
    pub t_end: f64,
    /// Output step [s].
    pub dt_out: f64,
    /// Most output rows (and communication steps of an emulated host) a run may have.
    pub max_rows: u64,
    /// The CLI's CSV columns, the item of `columns`: 0 paper, 1 beam (the beam's columns
    /// too), 2 shape (and the nodes' coordinates).
    pub columns: usize,
}

impl Default for Scene {
    /// The defaults of [`SETTINGS`]: every field is a setting's, so the blank values below are
    /// all overwritten.
    fn default() -> Self {
        let mut scene = Scene {
            params: Params::default(),
            law: PaperLaw::default(),
            initial: InitialState::default(),
            formulation: Formulation::Reduced,
            phi_source: PhiSource::Law,
            phi_interpolation: Interpolation::default(),
            phi_extrapolation: 0,
            intermediate_step: 0.0,
            input_derivatives: false,
            dt_comm: 0.0,
            solver: SolverSettings::default(),
            range_check: RangeCheck::default(),
            energy_check: RangeCheck::default(),
            phi_filter_frequency: 0.0,
            t_end: 0.0,
            dt_out: 0.0,
            max_rows: 0,
            columns: 0,
        };
        for s in SETTINGS {
            scene.put(s.key, s.default);
        }
        scene
    }
}

crate::settings::choice_field!(PhiSource, IntegratorChoice);

/// The scene's `get` and `put` from the declaration of the settings: each key reads and writes
/// its field.
macro_rules! accessors {
    ($($key:ident { field: $($field:ident).+, $($rest:tt)* })*) => {
        impl Scene {
            /// The value of a setting.
            pub fn get(&self, key: Key) -> Value {
                let kind = Setting::of(key).kind;
                match key {
                    $(Key::$key => self.$($field).+.value(kind),)*
                }
            }

            /// Stores a checked value.
            fn put(&mut self, key: Key, value: Value) {
                match key {
                    $(Key::$key => self.$($field).+ = Field::from_value(value),)*
                }
            }
        }
    };
}

crate::settings::for_each_setting!(accessors);

impl Scene {
    /// Sets a setting after checking its value against the table; the error names the
    /// setting and what it allows, and leaves the scene unchanged.
    pub fn set(&mut self, key: Key, value: Value) -> Result<(), String> {
        let value = Setting::of(key).check(value)?;
        self.put(key, value);
        Ok(())
    }

    /// Sets the setting called `name` from the text a user typed (`--set NAME=VALUE`).
    pub fn set_text(&mut self, name: &str, text: &str) -> Result<(), String> {
        let setting = Setting::by_name(name)?;
        let value = setting.parse(text)?;
        self.set(setting.key, value)
    }

    /// Sets the setting called `name` to the number `value` (a study's parameter): a real,
    /// or an integer given as a whole number.
    pub fn set_number(&mut self, name: &str, value: f64) -> Result<(), String> {
        let setting = Setting::by_name(name)?;
        let value = match setting.kind {
            Kind::Integer if value.fract() == 0.0 && value.abs() <= (1u64 << 53) as f64 => {
                Value::Integer(value as i64)
            }
            Kind::Integer => {
                return Err(format!("`{}` = {value:?}: must be {}", name, setting.expects()))
            }
            _ => Value::Real(value),
        };
        self.set(setting.key, value)
    }

    /// The run's model in words, for a run's summary: the beam's theory and elements, the
    /// formulation, the damping and the beam's weight.
    pub fn describe(&self) -> String {
        let p = &self.params;
        let elements = match p.n_elements {
            1 => "1 element".to_string(),
            n => format!("{n} elements"),
        };
        let paper = if p.is_paper_model() { " (the paper's model)" } else { "" };
        let damping = if p.damping_ratio > 0.0 {
            format!("damping_ratio {:?}", p.damping_ratio)
        } else if p.damping_alpha > 0.0 || p.damping_beta > 0.0 {
            format!("damping_alpha {:?} 1/s, damping_beta {:?} s", p.damping_alpha, p.damping_beta)
        } else {
            "undamped".to_string()
        };
        let weight = if p.beam_gravity { ", the beam's weight" } else { "" };
        format!(
            "{} beam in {elements}{paper}, {} formulation, {damping}{weight}",
            p.beam.name(),
            self.formulation
        )
    }

    /// The integrator's configuration for a run of this scene.
    pub fn solver_config(&self, max_steps: u64) -> BdfConfig {
        self.solver.config(self.params.beam, max_steps)
    }

    /// φ at t = 0 under the settings (the law's φ0 + its value there, or the host's start).
    fn start_phi(&self) -> f64 {
        self.law.eval(0.0).phi
    }

    /// The checks that need several settings at once, and the model: everything a run needs
    /// before its first step, except the output grid ([`rows`](Self::rows)). The errors say
    /// what is wrong in the settings' names.
    pub fn check_model(&self, phi_at_start: f64) -> Result<BeamBody, String> {
        let model = BeamBody::new(self.params).map_err(|e| e.to_string())?;
        self.law.validate().map_err(|e| e.to_string())?;
        let s = &self.solver;
        if s.fixed_order != 0 && s.fixed_step == 0.0 {
            return Err(format!(
                "`fixed_order` = {} needs a constant step, `fixed_step` > 0; without one the \
                 integrator is the adaptive BDF, whose highest order is `max_order`",
                s.fixed_order
            ));
        }
        let i = self.initial;
        // The exact beam holds at any rotation: its one limit (a centreline that crosses
        // itself) is checked along the run.
        if self.range_check == RangeCheck::Stop && self.params.beam == BeamModel::Quadratic {
            let l = self.params.l;
            if i.v1.abs() > l {
                return Err(format!(
                    "the initial state `v1_0` = {:?} is outside the range of validity |v1| <= l \
                     = {l:?} (range_check = stop)",
                    i.v1
                ));
            }
            if i.theta1.abs() > std::f64::consts::FRAC_PI_2 {
                return Err(format!(
                    "the initial state `theta1_0` = {:?} is outside the range of validity \
                     |theta1| <= pi/2 (range_check = stop)",
                    i.theta1
                ));
            }
        }
        model.check_start(phi_at_start, i.v1, i.theta1)?;
        Ok(model)
    }

    /// Checks everything a standalone run needs before its first step: the model, the
    /// settings together and the number of rows.
    pub fn validate(&self) -> Result<BeamBody, String> {
        let model = self.check_model(self.start_phi())?;
        self.check_grid()?;
        Ok(model)
    }

    /// The output rows, and an emulated host's communication steps, against `max_rows`.
    pub fn check_grid(&self) -> Result<(), String> {
        self.rows()?;
        if self.phi_source == PhiSource::Input {
            count(self.dt_comm, self.t_end, self.max_rows, "dt_comm", "communication steps")?;
        }
        Ok(())
    }

    /// The number of output rows, t = k·dt_out up to and including t_end; an error when it
    /// exceeds `max_rows`, computed without overflow whatever the numbers.
    pub fn rows(&self) -> Result<u64, String> {
        count(self.dt_out, self.t_end, self.max_rows, "dt_out", "output rows")
    }

    /// The output times k·dt_out, k = 0, 1, …, ending exactly at t_end (a last, shorter
    /// interval if t_end is not a multiple of dt_out). Check [`rows`](Self::rows) first.
    pub fn output_times(&self) -> impl Iterator<Item = f64> {
        grid(self.dt_out, self.t_end)
    }
}

/// The number of points of [`grid`] (step, t_end), refused above `limit` with a message that
/// names the step's setting. Counted exactly where the count fits a double's integers, and
/// compared as a double where it does not: no conversion saturates or wraps.
fn count(step: f64, t_end: f64, limit: u64, name: &str, what: &str) -> Result<u64, String> {
    let ratio = t_end / step;
    let n = (ratio < 9.0e15).then(|| grid_len(step, t_end));
    match n {
        Some(n) if n <= limit => Ok(n),
        _ => {
            let shown = n.map_or_else(|| format!("{ratio:.3e}"), |n| n.to_string());
            Err(format!(
                "t_end = {t_end:?} with `{name}` = {step:?} makes {shown} {what}, more than \
                 `max_rows` = {limit}: raise `{name}`, shorten t_end, or raise `max_rows` \
                 (--max-rows) if you mean it"
            ))
        }
    }
}

/// The index of the last point of [`grid`], and whether t_end is one of the k·step.
fn grid_last(step: f64, t_end: f64) -> u64 {
    let ratio = t_end / step;
    let n = (ratio + 1e-9).floor() as u64;
    let exact = (ratio - n as f64).abs() <= 1e-9 * ratio.max(1.0);
    if exact {
        n
    } else {
        n + 1
    }
}

/// The number of points of [`grid`].
fn grid_len(step: f64, t_end: f64) -> u64 {
    grid_last(step, t_end) + 1
}

/// The times k·`step`, k = 0, 1, …, ending exactly at `t_end` (a last, shorter interval if
/// `t_end` is not a multiple of `step`). For ratios t_end/step that [`count`] accepts.
pub(crate) fn grid(step: f64, t_end: f64) -> impl Iterator<Item = f64> {
    let last = grid_last(step, t_end);
    (0..=last).map(move |k| if k == last { t_end } else { k as f64 * step })
}

#[cfg(feature = "cli")]
mod file;
#[cfg(feature = "cli")]
pub use file::{locate, syntax_error, toml_value};

#[cfg(test)]
mod tests {
    use super::*;

    /// `Scene::set` and `get` take every setting of the table, by key and by the name and
    /// text a user types, and give back what was set.
    #[test]
    fn every_setting_of_the_table_is_set_and_read_back() {
        for s in crate::settings::SETTINGS.iter() {
            let mut scene = Scene::default();
            assert_eq!(scene.get(s.key), s.default, "{}", s.name);
            scene.set(s.key, s.default).unwrap();
            assert_eq!(scene.get(s.key), s.default, "{}", s.name);
            scene.set_text(s.name, &s.show(s.fmu_default())).unwrap();
            assert_eq!(scene.get(s.key), s.fmu_default(), "{}", s.name);
        }
    }

    #[test]
    fn defaults_are_the_tables_and_the_models() {
        let s = Scene::default();
        for setting in SETTINGS {
            assert_eq!(s.get(setting.key), setting.default, "{}", setting.name);
        }
        assert_eq!(s.params, Params::default());
        assert_eq!(s.law, PaperLaw::default());
        assert_eq!(s.solver.config(s.params.beam, 10_000_000), BdfConfig::default());
    }

    #[test]
    fn every_setting_round_trips_and_a_refused_value_changes_nothing() {
        for setting in SETTINGS {
            let mut s = Scene::default();
            s.set(setting.key, setting.default).unwrap();
            assert_eq!(s, Scene::default(), "{}", setting.name);
            if let Value::Real(_) = setting.default {
                assert!(s.set(setting.key, Value::Real(f64::NAN)).is_err(), "{}", setting.name);
                assert_eq!(s, Scene::default(), "{}", setting.name);
            }
        }
    }

    #[test]
    fn output_grid_is_exact_and_ends_at_t_end() {
        let scene = Scene { t_end: 10.2, dt_out: 0.0085, ..Scene::default() };
        let times: Vec<f64> = scene.output_times().collect();
        assert_eq!((times.len() as u64, scene.rows()), (1201, Ok(1201)));
        assert_eq!(times[0], 0.0);
        assert_eq!(times[7], 7.0 * 0.0085);
        assert_eq!(*times.last().unwrap(), 10.2);
        let uneven = Scene { t_end: 1.05, dt_out: 0.1, ..Scene::default() };
        let times: Vec<f64> = uneven.output_times().collect();
        assert_eq!((times.len() as u64, uneven.rows()), (12, Ok(12)));
        assert_eq!(times[10], 1.0);
        assert_eq!(times[11], 1.05);
    }

    #[test]
    fn absurd_row_counts_are_refused_not_wrapped() {
        for dt_out in [1e-300, 1e-20, 1e-19, 1e-17, 1e-6] {
            let s = Scene { t_end: 10.2, dt_out, ..Scene::default() };
            let e = s.rows().unwrap_err();
            assert!(e.contains("`dt_out`") && e.contains("max_rows"), "{e}");
            assert!(s.validate().is_err());
        }
        let s = Scene { t_end: 1e9, ..Scene::default() };
        assert!(s.rows().unwrap_err().contains("100000000001 output rows"));
        let s = Scene { t_end: 1e300, ..Scene::default() };
        assert!(s.rows().unwrap_err().contains("1.000e302 output rows"));
        // At the limit exactly: a million rows pass, one more does not.
        let s = Scene { t_end: 999_999.0, dt_out: 1.0, ..Scene::default() };
        assert_eq!(s.rows(), Ok(1_000_000));
        let s = Scene { t_end: 1_000_000.0, dt_out: 1.0, ..Scene::default() };
        assert!(s.rows().is_err());
        let s = Scene {
            t_end: 10.2,
            dt_comm: 1e-300,
            phi_source: PhiSource::Input,
            ..Scene::default()
        };
        assert!(s.validate().unwrap_err().contains("communication steps"));
    }

    #[test]
    fn settings_checked_together_say_what_is_wrong() {
        let mut s = Scene::default();
        s.set_text("fixed_order", "3").unwrap();
        let e = s.validate().unwrap_err();
        assert!(e.starts_with("`fixed_order` = 3 needs a constant step, `fixed_step` > 0"), "{e}");
        s.set_text("fixed_step", "1e-3").unwrap();
        assert!(s.validate().is_ok());
        let mut s = Scene::default();
        s.set_text("v1_0", "3").unwrap();
        let e = s.validate().unwrap_err();
        assert!(e.contains("`v1_0` = 3.0 is outside the range of validity |v1| <= l"), "{e}");
        s.set_text("range_check", "off").unwrap();
        assert!(s.validate().is_ok());
        let mut s = Scene::default();
        for (k, v) in [("m", "0"), ("J_C", "0"), ("r", "0")] {
            s.set_text(k, v).unwrap();
        }
        let e = s.validate().unwrap_err();
        assert!(e.contains("singular at the start") && e.contains("J_C = 0.0"), "{e}");
    }

    #[test]
    fn set_text_names_unknown_settings_and_bad_values() {
        let mut s = Scene::default();
        s.set_text("EI", "2000").unwrap();
        assert_eq!(s.params.ei, 2000.0);
        let e = s.set_text("beam_theory", "exact").unwrap_err();
        assert!(e.starts_with("unknown setting `beam_theory`: must be one of l, EI,"), "{e}");
        let e = s.set_text("EI", "-1").unwrap_err();
        assert!(e.contains("`EI` = -1.0 is out of range: must be positive"), "{e}");
        assert!(s.set_text("dt_out", "0").is_err());
        assert!(s.set_text("formulation", "dae_stabilized").is_ok());
        assert_eq!(s.formulation, Formulation::DaeStabilized);
        assert!(s.set_text("formulation", "quantum").is_err());
        assert!(s.set_text("max_order", "6").is_err());
        assert!(s.set_text("stability_guard", "no").is_err());
    }
}
