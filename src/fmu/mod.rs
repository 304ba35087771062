//! The beam–body model as an FMU: its variables ([`variables`]), their values
//! ([`values`]) and outputs ([`outputs`]), bound to the FMI core through [`fmi::Model`] and
//! [`fmi::CoSimulation`]. The only place that knows both the FMI core and the model; the
//! core knows the model only through these traits.
//!
//! A run is started the one way the CLI starts one ([`Run::start`]) on the same settings
//! ([`Scene`](crate::scene::Scene)), with the experiment's tolerance.
#![forbid(unsafe_code)]

pub mod exchange;
pub mod outputs;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_exchange;
pub mod values;
pub mod variables;

use crate::fmi::{self, Interface, Notes, Restore, Setup, State, StepFailure, Value, Version};
use crate::model::{BeamBody, Kinematics, Reactions};
use crate::scene::PhiSource;
use crate::sim::{Run, SimError};
use crate::solver::check_rtol;
use crate::solver::SolverError;
use crate::visit::StateVisitor;
use outputs::{Cache, Group};
use values::Values;
use variables::{
    Var, Variable, DEFAULT_EXPERIMENT, EVENT_INDICATORS, INDICATOR_VARIABLES, INTERMEDIATE_INPUTS,
    VARIABLES,
};

/// Most internal steps in one DoStep, so that a step always returns in bounded time (about
/// a second in a release build); beyond it the step is discarded with a message. The
/// stiffest scene of the sweep (EI × 10⁷) needs about 5·10⁴ steps per simulated second.
pub const MAX_STEPS_PER_DO_STEP: u64 = 1_000_000;

/// The variables of Model Exchange's filter of φ: its states and φ″.
const FILTERED: [Var; 3] = [Var::PhiFiltered, Var::DphiFiltered, Var::DdphiFiltered];

/// Version of the model's part of a serialized state; bump it when `visit_state` changes.
const STATE_VERSION: u32 = 7;

/// The beam–body FMU's model: the values, the run from ExitInitializationMode on, the
/// outputs computed at the current time, and what the host has been told about φ.
#[derive(Clone, Debug)]
pub struct BeamBodyFmu {
    /// The model description the instance serves: FMI 3.0's has arrays sized by
    /// `n_elements`, and Model Exchange states of any beam.
    pub version: Version,
    pub values: Values,
    /// The integrator, from ExitInitializationMode on (co-simulation).
    pub run: Option<Run>,
    /// The communication time (co-simulation): where the outputs are. With the law, the
    /// integrator runs ahead of it ([`Run::step_past`]).
    at: f64,
    /// Where the integrator must stop: the experiment's stop time, or none (∞).
    stop: f64,
    /// Running ahead, the integrator's last step, which ends after the communication time,
    /// left the range of validity (`range_check = stop`) or broke the energy balance
    /// (`energy_check = stop`): the next DoStep that reaches its end fails there
    /// ([`Run::exit_reason`] says why).
    exit_ahead: bool,
    /// The host's intermediate-update callback set no φ: the next step extends the samples
    /// held. Set and used within one fmi3DoStep, so not part of the FMU state.
    hold: bool,
    /// What is left of the current communication step's budget of integrator steps
    /// ([`MAX_STEPS_PER_DO_STEP`]), shared by the parts of an FMI 3.0 step with intermediate
    /// update. Reset at each step's start, so not part of the FMU state.
    budget: u64,
    /// The budget of a communication step: [`MAX_STEPS_PER_DO_STEP`] (tests lower it).
    pub(crate) step_budget: u64,
    /// The equations a host integrates (Model Exchange), from ExitInitializationMode on, or
    /// built in initialization mode for the start state.
    pub exchange: Option<Box<exchange::Exchange>>,
    cache: Cache,
    phi: PhiNotes,
}

/// The host's use of the input φ, for the warnings that say what a run really does. Not
/// part of a serialized state.
#[derive(Clone, Copy, Debug, Default)]
struct PhiNotes {
    /// The host has set φ since instantiation or reset.
    set: bool,
    /// Told that φ is ignored (`phi_source` = law).
    told_ignored: bool,
    /// Told that φ was never set (`phi_source` = input).
    told_unset: bool,
    /// Told that co-simulation does not use `dphi` and `ddphi`.
    told_rates: bool,
}

fn row(vr: u32) -> &'static Variable {
    &VARIABLES[vr as usize]
}

impl BeamBodyFmu {
    /// A fresh run at the start time, after checking every parameter together: the CLI's
    /// [`Run::start`] on the FMU's settings, with the experiment's tolerance.
    fn build_run(&self, setup: &Setup) -> Result<Run, String> {
        let mut scene = self.values.settings.clone();
        scene.solver.rtol = setup.tolerance.unwrap_or(DEFAULT_EXPERIMENT.tolerance);
        let t0 = setup.start_time;
        let first = crate::model::Sample { t: t0, ..self.values.input };
        Run::start(&scene, t0, first, MAX_STEPS_PER_DO_STEP).map_err(|e| e.to_string())
    }

    /// Whether the integrator runs ahead of the communication points: with the law, whose φ
    /// is known ahead, at an adaptive step ([`Run::step_past`]).
    fn runs_ahead(&self) -> bool {
        let s = &self.values.settings;
        s.phi_source == PhiSource::Law && s.solver.fixed_step == 0.0
    }

    /// The motion at the current time, computed now if it is not cached.
    fn kinematics(&mut self, setup: &Setup) -> Result<Kinematics, String> {
        if let Some(k) = self.cache.kinematics {
            return Ok(k);
        }
        let k = match (&self.run, &self.exchange) {
            (Some(run), _) => run.kinematics_at(self.at).map_err(|e| e.to_string())?,
            (None, Some(ex)) => ex.kinematics(&self.values),
            // Initialization mode: the outputs of the start state.
            (None, None) => {
                let run = self.build_run(setup)?;
                run.kinematics_at(setup.start_time).map_err(|e| e.to_string())?
            }
        };
        self.cache.kinematics = Some(k);
        Ok(k)
    }

    /// Event indicator `k` as a variable: Model Exchange's, or in co-simulation the same
    /// margins of the range of validity at the current time.
    fn range_margin(&mut self, k: usize, setup: &Setup) -> Result<f64, String> {
        let mut m = [0.0; EVENT_INDICATORS];
        if self.exchange.is_some() {
            fmi::ModelExchange::event_indicators(self, &mut m);
            return Ok(m[k]);
        }
        let kin = self.kinematics(setup)?;
        let exact = self.values.settings.params.beam == crate::model::BeamModel::Exact;
        if self.values.settings.range_check == crate::model::RangeCheck::Off || exact {
            return Ok(1.0);
        }
        let l = self.values.settings.params.l;
        m = [l - kin.v1.abs(), std::f64::consts::FRAC_PI_2 - kin.theta1.abs()];
        Ok(m[k])
    }

    /// Every node's (v_k, ϑ_k) at the current time, the tip last
    /// ([`Run::coordinates_at`]); in initialization mode, of the start state.
    fn nodal(&mut self, setup: &Setup) -> Result<Vec<f64>, String> {
        let mut out = Vec::new();
        match (&self.run, &self.exchange) {
            (Some(run), _) => run.coordinates_at(self.at, &mut out).map_err(|e| e.to_string())?,
            (None, Some(ex)) => out = ex.eq.nodal_shape(&ex.x),
            (None, None) => {
                let run = self.build_run(setup)?;
                run.coordinates_at(setup.start_time, &mut out).map_err(|e| e.to_string())?
            }
        }
        Ok(out)
    }

    /// Model Exchange's states q or dq, or ddq, the derivative of dq: the host's states
    /// (Model Exchange), the run's (co-simulation), or the start state's (before either).
    fn state_array(&mut self, var: &Variable, setup: &Setup) -> Result<Vec<f64>, String> {
        if let Some(ex) = &self.exchange {
            return Ok(ex.state_array(var.var, &self.values));
        }
        let mut motion = Vec::new();
        match &self.run {
            Some(run) => run.motion_at(self.at, &mut motion),
            None => self.build_run(setup)?.motion_at(setup.start_time, &mut motion),
        }
        .map_err(|e| e.to_string())?;
        // (q, q̇, q̈), a third each.
        let n = motion.len() / 3;
        let k = match var.var {
            Var::Q => 0,
            Var::Dq => 1,
            _ => 2,
        };
        Ok(motion[k * n..(k + 1) * n].to_vec())
    }

    /// φ, φ′ or φ″ (`k`) of Model Exchange's filter; co-simulation's applied ones.
    fn filtered(&mut self, k: usize, setup: &Setup) -> Result<f64, String> {
        let phi = match &self.exchange {
            Some(ex) => ex.filtered(),
            None => self.kinematics(setup)?.phi,
        };
        Ok([phi.phi, phi.dphi, phi.ddphi][k])
    }

    /// The model the outputs are computed with.
    fn model(&self) -> Result<BeamBody, String> {
        match (&self.run, &self.exchange) {
            (Some(run), _) => Ok(*run.model()),
            (None, Some(ex)) => Ok(*ex.eq.model()),
            (None, None) => BeamBody::new(self.values.settings.params).map_err(|e| e.to_string()),
        }
    }

    /// The hinge reactions at the current time, computed at the first request.
    fn reactions(&mut self, k: &Kinematics) -> Result<Reactions, String> {
        let r = match self.cache.reactions {
            Some(r) => r,
            None => k.reactions(&self.model()?),
        };
        self.cache.reactions = Some(r);
        Ok(r)
    }

    /// The value of output `var` at the current time, its group computed if needed.
    fn output(&mut self, var: Var, setup: &Setup) -> Result<f64, String> {
        let k = self.kinematics(setup)?;
        Ok(match outputs::group(var).expect("only outputs come here") {
            Group::Motion => outputs::motion(var, &k).expect("a motion output"),
            Group::Reactions => {
                let r = self.reactions(&k)?;
                outputs::reaction(var, &r).expect("a reaction output")
            }
            Group::Root => {
                let r = self.reactions(&k)?;
                let (shear, moment) = k.root_loads(&self.model()?, &r);
                if var == Var::MRoot {
                    moment
                } else {
                    shear
                }
            }
            Group::Energy => {
                let e = match self.cache.energy {
                    Some(e) => e,
                    None => k.energy(&self.model()?),
                };
                self.cache.energy = Some(e);
                e
            }
        })
    }

    /// After the host set φ: with `phi_source = law` the law drives the body and φ is not
    /// used. A host that sends φ between steps is driving it, and is told so once (a host
    /// that sets every input's start value before the run is not).
    fn phi_used(&mut self, state: State, notes: &mut Notes) {
        self.phi.set = true;
        let law = self.values.settings.phi_source == PhiSource::Law;
        if !law || !state.is_running() || self.phi.told_ignored {
            return;
        }
        self.phi.told_ignored = true;
        notes.push(format!(
            "the input `phi` is ignored: `phi_source` = law ({}), so the built-in law turns \
             the body; set `phi_source` = input ({}) before initialization to drive phi \
             (said once)",
            PhiSource::Law as i32 + 1,
            PhiSource::Input as i32 + 1
        ));
    }

    /// After the host set `dphi` or `ddphi` between steps: co-simulation does not use them
    /// (they are Model Exchange's φ′ and φ″: a master that sets every input would otherwise
    /// send zeros as φ's derivatives), and with the law nobody does. Told once.
    fn rates_used(&mut self, state: State, notes: &mut Notes) {
        let law = self.values.settings.phi_source == PhiSource::Law;
        if self.phi.told_rates || !(state == State::StepComplete || law && state.is_running()) {
            return;
        }
        self.phi.told_rates = true;
        notes.push(if law {
            "the inputs `dphi` and `ddphi` are ignored: `phi_source` = law (said once)".to_string()
        } else {
            "the inputs `dphi` and `ddphi` are Model Exchange's φ′ and φ″; co-simulation ignores \
             them and takes φ's derivatives through fmi2SetRealInputDerivatives (said once)"
                .to_string()
        });
    }

    /// Before a step (co-simulation) or at the first event (Model Exchange) with
    /// `phi_source` = input: a host that has never set φ runs the model
    /// at φ's start value, the body never turning, which is rarely what it means (FMPy's
    /// `simulate_fmu` without an input does so). It is told once.
    fn check_phi_sent(&mut self, notes: &mut Notes) {
        let input = self.values.settings.phi_source == PhiSource::Input;
        if !input || self.phi.set || self.phi.told_unset {
            return;
        }
        self.phi.told_unset = true;
        notes.push(format!(
            "the input `phi` has not been set, so it stays at {:?} rad and the body does not \
             turn; set `phi` at every communication point (Model Exchange: with `dphi` and \
             `ddphi`, as the host's time goes), or set `phi_source` = law ({}) for the \
             paper's turn (said once)",
            self.values.input.phi,
            PhiSource::Law as i32 + 1
        ));
    }

    /// The parameters in the order of the settings table, the input and its pending
    /// derivatives; checked with the same rules as the setters.
    fn visit_values(&mut self, v: &mut impl StateVisitor) -> Result<(), String> {
        use crate::settings::{Value as S, SETTINGS};
        let values = &mut self.values;
        for setting in SETTINGS.iter().filter(|s| s.appears.fmu) {
            let mut value = values.settings.get(setting.key);
            match &mut value {
                S::Real(x) => v.real(setting.name, x),
                S::Integer(k) => {
                    let mut c = *k as u64;
                    v.count(setting.name, &mut c);
                    *k = i64::try_from(c).unwrap_or(-1);
                }
                S::Choice(k) => {
                    let mut c = *k as u64;
                    v.count(setting.name, &mut c);
                    *k = usize::try_from(c).unwrap_or(usize::MAX);
                }
                S::Bool(b) => v.flag(setting.name, b),
            }
            values.settings.set(setting.key, value).map_err(|e| format!("field {e}"))?;
        }
        let input = &mut values.input;
        v.real("phi", &mut input.phi);
        let [phi, dphi, ddphi] = [Var::Phi, Var::Dphi, Var::Ddphi].map(Var::info);
        values::check_input(phi, input.phi).map_err(|e| format!("field {e}"))?;
        for (k, var) in [dphi, ddphi].into_iter().enumerate() {
            v.real(var.name, &mut values.rates[k]);
            values::check_input(var, values.rates[k]).map_err(|e| format!("field {e}"))?;
        }
        v.flag("rates_set", &mut values.rates_set);
        let input = &mut values.input;
        fmi::visit_optional(v, "pending_dphi_set", "pending_dphi", &mut input.dphi)?;
        fmi::visit_optional(v, "pending_ddphi_set", "pending_ddphi", &mut input.ddphi)?;
        if [input.dphi, input.ddphi].iter().flatten().any(|x| !x.is_finite()) {
            return Err("field `pending` holds a non-finite derivative".into());
        }
        Ok(())
    }
}

impl fmi::Model for BeamBodyFmu {
    const STATE_VERSION: u32 = STATE_VERSION;

    fn variable(vr: u32) -> Option<&'static fmi::VarInfo> {
        VARIABLES.get(vr as usize).map(|v| &v.info)
    }

    fn variable_count() -> usize {
        VARIABLES.len()
    }

    fn guid() -> &'static str {
        variables::guid()
    }

    fn new(version: Version) -> Self {
        BeamBodyFmu {
            version,
            values: Values::from_table(),
            run: None,
            at: 0.0,
            stop: f64::INFINITY,
            exit_ahead: false,
            hold: false,
            budget: MAX_STEPS_PER_DO_STEP,
            step_budget: MAX_STEPS_PER_DO_STEP,
            exchange: None,
            cache: Cache::default(),
            phi: PhiNotes::default(),
        }
    }

    fn check_tolerance(tol: f64) -> Result<(), String> {
        check_rtol(tol).map_err(|range| range.to_string())
    }

    fn get(&mut self, vr: u32, setup: &Setup) -> Result<Value, String> {
        let var = row(vr);
        if !var.dims.is_empty() {
            return Err(format!("`{}` is an array: it has no scalar value", var.name));
        }
        if let Some(k) = INDICATOR_VARIABLES.iter().position(|v| *v == var.var) {
            return self.range_margin(k, setup).map(Value::Real);
        }
        if let Some(k) = FILTERED.iter().position(|v| *v == var.var) {
            return self.filtered(k, setup).map(Value::Real);
        }
        match self.values.get(var) {
            Some(v) => Ok(v),
            None => self.output(var.var, setup).map(Value::Real),
        }
    }

    fn get_array(&mut self, vr: u32, setup: &Setup, out: &mut [f64]) -> Result<(), String> {
        let var = row(vr);
        let values = match var.var {
            Var::NodalV | Var::NodalTheta => {
                let odd = usize::from(var.var == Var::NodalTheta);
                let nodal = self.nodal(setup)?;
                nodal.iter().skip(odd).step_by(2).copied().collect()
            }
            Var::Q | Var::Dq | Var::Ddq => self.state_array(var, setup)?,
            _ => return Err(format!("`{}` is not an array", var.name)),
        };
        if values.len() != out.len() {
            return Err(format!(
                "`{}` has {} values at the current parameters, not {}",
                var.name,
                values.len(),
                out.len()
            ));
        }
        out.copy_from_slice(&values);
        Ok(())
    }

    fn check(&self, vr: u32, value: Value) -> Result<(), String> {
        self.values.check(row(vr), value)
    }

    fn set(
        &mut self,
        vr: u32,
        value: Value,
        state: State,
        notes: &mut Notes,
    ) -> Result<(), String> {
        let var = row(vr);
        self.values.set(var, value)?;
        self.cache = Cache::default();
        if matches!(state, State::Instantiated | State::InitializationMode) {
            // The start state follows from the values: built again when next needed.
            self.exchange = None;
        }
        match var.var {
            Var::Phi => self.phi_used(state, notes),
            Var::Dphi | Var::Ddphi => self.rates_used(state, notes),
            _ => {}
        }
        Ok(())
    }

    fn intermediate_input(vr: u32) -> bool {
        INTERMEDIATE_INPUTS.iter().any(|v| v.vr() == vr)
    }

    fn intermediate_variable(vr: u32) -> bool {
        VARIABLES.get(vr as usize).is_some_and(variables::intermediate_update)
    }

    fn start(&mut self, setup: &Setup, interface: Interface) -> Result<(), String> {
        match interface {
            Interface::CoSimulation => {
                let run = self.build_run(setup)?;
                self.values.input.dphi = None;
                self.values.input.ddphi = None;
                self.run = Some(run);
                self.at = setup.start_time;
                self.stop = setup.stop_time.unwrap_or(f64::INFINITY);
                self.exit_ahead = false;
            }
            Interface::ModelExchange => {
                self.exchange = Some(Box::new(self.build_exchange(setup)?));
            }
        }
        self.cache = Cache::default();
        Ok(())
    }

    fn visit_state<V: StateVisitor>(&mut self, v: &mut V, at: &Restore) -> Result<(), String> {
        self.version = at.version;
        self.visit_values(v)?;
        if at.interface == Interface::ModelExchange {
            return self.visit_exchange(v, at);
        }
        let mut has_run = self.run.is_some();
        v.flag("run", &mut has_run);
        let needs_run =
            matches!(at.state, State::StepComplete | State::StepFailed | State::Terminated);
        let may_run = needs_run || at.state == State::Error;
        if has_run != needs_run && !(has_run && may_run) {
            return Err(format!("field `run` = {has_run} contradicts the state `{:?}`", at.state));
        }
        if !has_run {
            self.run = None;
            return Ok(());
        }
        if self.run.is_none() {
            self.run =
                Some(self.build_run(&at.setup).map_err(|e| format!("the saved parameters: {e}"))?);
        }
        let ahead = self.runs_ahead();
        let run = self.run.as_mut().expect("built above");
        // The integrator's size, which the saved parameters fix (n_elements, formulation): a
        // state whose parameters were changed after it was written is refused here, before
        // its integrator's fields are read out of place.
        let states = run.dimension() as u64;
        let mut saved = states;
        v.count("run.states", &mut saved);
        if saved != states {
            let p = &self.values.settings;
            return Err(format!(
                "field `run.states` = {saved}: the saved parameters (n_elements = {}, \
                 formulation = {}) make an integrator of {states} states",
                p.params.n_elements, p.formulation
            ));
        }
        run.visit_state(v);
        run.check_state()?;
        // After every step, successful or not, the integrator is at the communication time
        // (up to the rounding of tc + h), or, running ahead with the law, within one of its
        // steps after it.
        let t = run.t();
        let at_time = crate::math::same_time(t, at.time, 1.0);
        if !(at_time || ahead && t > at.time && run.reaches_back_to(at.time)) {
            let what = if ahead { "is not within one step after" } else { "does not match" };
            return Err(format!("field `integrator time` = {t} {what} `time` = {}", at.time));
        }
        v.flag("exit_ahead", &mut self.exit_ahead);
        if self.exit_ahead && !(ahead && t > at.time && run.exit_reason().is_some()) {
            return Err("field `exit_ahead` = true, but the integrator's last step is not \
                        ahead and out of the range of validity"
                .into());
        }
        self.at = at.time;
        self.stop = at.setup.stop_time.unwrap_or(f64::INFINITY);
        Ok(())
    }
}

impl fmi::CoSimulation for BeamBodyFmu {
    const MAX_OUTPUT_DERIVATIVE_ORDER: i32 = outputs::MAX_OUTPUT_DERIVATIVE_ORDER;
    const MAX_INPUT_DERIVATIVE_ORDER: i32 = 2;

    /// With the law, the integrator takes its own steps, as the CLI's run does, and the
    /// outputs at `to` come from its dense output; else it lands on `to` (a host's input is
    /// known up to `to` only; the fixed step is the paper's one step per communication
    /// step). A step that fails past `to` (the range left just after it) fails this
    /// DoStep at `to`, where the outputs are complete.
    fn begin_step(&mut self) {
        self.budget = self.step_budget;
    }

    fn do_step(&mut self, from: f64, to: f64, notes: &mut Notes) -> Result<(), StepFailure> {
        self.check_phi_sent(notes);
        let spent = |budget: u64, t: f64| StepFailure {
            t,
            message: format!(
                "the communication step has taken its {budget} integrator steps in its parts \
                 before t = {t:?}: use shorter communication steps"
            ),
        };
        if self.budget == 0 {
            return Err(spent(self.step_budget, from));
        }
        // An earlier part of this step spent some of the budget.
        let shared = self.budget < self.step_budget;
        let sample = crate::model::Sample { t: from, ..self.values.input };
        self.values.input.dphi = None;
        self.values.input.ddphi = None;
        self.cache = Cache::default();
        // `to` may pass the stop time by the core's rounding allowance: never stop before it.
        let (ahead, stop) = (self.runs_ahead(), self.stop.max(to));
        let run = self.run.as_mut().expect("a started model has a run");
        run.set_max_steps(self.budget);
        let steps_before = run.stats().steps;
        if self.exit_ahead {
            // The last step, past the last communication time, left the range at its end.
            if to < run.t() {
                self.at = to;
                return Ok(());
            }
            let (t, why) = (run.t(), run.exit_reason());
            self.at = t;
            let message = why.unwrap_or_else(|| "the state left the range of validity".into());
            return Err(StepFailure { t, message });
        }
        let stepped = if ahead {
            run.step_past(to, stop)
        } else {
            if std::mem::take(&mut self.hold) {
                run.hold_sample();
            } else {
                run.set_sample(sample);
            }
            run.step_to(to)
        };
        self.budget = self.budget.saturating_sub(run.stats().steps - steps_before);
        match stepped {
            // Running ahead, the step that crossed `to` left the range after it: this step is
            // complete; the one that reaches the exit fails there.
            Err(SimError::Solver(SolverError::OutOfRange { .. }) | SimError::Unstable(_))
                if ahead && run.t() > to =>
            {
                self.exit_ahead = true;
            }
            Err(SimError::Solver(SolverError::TooManySteps { .. })) if shared => {
                let t = run.t().min(to);
                self.at = t;
                return Err(spent(self.step_budget, t));
            }
            Err(e) => {
                let t = run.t().min(to);
                self.at = t;
                return Err(StepFailure { t, message: e.to_string() });
            }
            Ok(()) => {}
        }
        self.at = to;
        notes.extend(run.take_warning());
        Ok(())
    }

    /// φ only: `dphi` and `ddphi` are Model Exchange's inputs.
    fn takes_derivatives(vr: u32) -> bool {
        vr == Var::Phi.vr()
    }

    fn set_input_derivative(&mut self, vr: u32, order: i32, value: f64) {
        debug_assert_eq!(vr, Var::Phi.vr(), "the one input");
        let slot =
            if order == 1 { &mut self.values.input.dphi } else { &mut self.values.input.ddphi };
        *slot = Some(value);
        self.cache = Cache::default();
    }

    fn output_derivative(
        &mut self,
        vr: u32,
        order: i32,
        setup: &Setup,
    ) -> Result<Option<f64>, String> {
        let k = self.kinematics(setup)?;
        Ok(outputs::derivative(row(vr).var, order, &k))
    }

    fn outputs_with_derivatives(order: i32) -> &'static str {
        outputs::with_derivatives(order)
    }

    /// With the host's φ, or for a host that reads the outputs inside a step:
    /// `intermediate_step`. Not the integrator's own step: each sample
    /// of values only joins the pieces of φ with a jump of φ″ that may restart the
    /// integrator, whose next step is then small, so that the samples would crowd and their
    /// divided differences lose φ″ to round-off (measured: the error of v1 grew 200-fold).
    fn hold_input(&mut self) {
        self.hold = true;
    }

    fn intermediate_spacing(&self, outputs: bool) -> Option<f64> {
        let s = &self.values.settings;
        let dt = s.intermediate_step;
        ((outputs || s.phi_source == PhiSource::Input) && dt > 0.0).then_some(dt)
    }
}
