//! The beam–body model under Model Exchange: the host's integrator steps the equations
//! ([`Equations`]) of the model's coordinates and rates, then the two states of the filter of
//! φ ([`PhiFilter`]): x = (q, q̇, φ_f, φ_f′). The model gives their derivatives, the range of
//! validity as event indicators, and the law's end as a time event. A host that sets `phi`
//! and never `dphi` or `ddphi` drives the model with the filter's φ, φ′, φ″; one that sets
//! them, with what it sends.
//!
//! The filter's input is the host's φ sampled at each completed integrator step or event, and
//! followed from one sample to the next by a ramp as long as the last interval between them
//! (a first-order hold, one interval behind): not the input at each evaluation of the
//! derivatives. FMPy sets a Model Exchange input inside its solver's root function, at times of
//! the step's own choosing, so that f was not a function of (t, x), and CVode, with a filter
//! that passes φ's changes to φ″ with a gain ω²/b, failed ("mxstep steps taken") at rtol 1e-6
//! on the paper's scene; holding each sample instead made f jump at every sample, and CVode
//! failed its error test at rtol 1e-8. The ramp keeps f continuous in t.
#![forbid(unsafe_code)]

use super::variables::{
    Causality, Var, DERIVATIVES, DERIVATIVES3, EVENT_INDICATORS, STATES, STATES3,
};
use super::BeamBodyFmu;
use crate::fmi::{self, EventInfo, Notes, Setup, StepEnd, Version};
use crate::model::{BeamModel, Kinematics, Phi, PhiFilter, PhiPiece, RangeCheck};
use crate::sim::Equations;
use crate::solver::RangeViolation;
use crate::visit::StateVisitor;

/// The equations and where the host has put them: time, states, and what the event
/// iteration has settled.
#[derive(Clone, Debug)]
pub struct Exchange {
    pub eq: Equations,
    pub filter: PhiFilter,
    pub t: f64,
    /// The model's states, then the filter's (φ_f, φ_f′).
    pub x: Vec<f64>,
    /// The filter's input: a ramp to the host's last sample of φ.
    pub ramp: Ramp,
    /// The law's end t_rot has been handled in event mode: φ holds from there on.
    pub turned: bool,
    /// `range_check` now: `warn` becomes `off` once it has warned.
    pub range: RangeCheck,
}

/// The filter's input between the host's samples of φ: from `from` at `t0` to `to` at
/// `t0 + len`, held after (`len` = 0: at `to` from `t0` on).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ramp {
    pub t0: f64,
    pub from: f64,
    pub to: f64,
    pub len: f64,
}

impl Ramp {
    /// At `phi` from `t0` on.
    pub fn at(t0: f64, phi: f64) -> Self {
        Self { t0, from: phi, to: phi, len: 0.0 }
    }

    pub fn eval(&self, t: f64) -> f64 {
        if self.len > 0.0 && t < self.t0 + self.len {
            let s = ((t - self.t0) / self.len).max(0.0);
            self.from + (self.to - self.from) * s
        } else {
            self.to
        }
    }

    /// The host's sample `phi` at `t`: a ramp from where this one is now to it, as long as
    /// the interval since the last sample (or as the last ramp, at the same time).
    pub fn sample(&mut self, t: f64, phi: f64) {
        let len = if t > self.t0 { t - self.t0 } else { self.len };
        *self = Ramp { t0: t, from: self.eval(t), to: phi, len };
    }
}

impl Exchange {
    /// The number of the model's states (without the filter's two).
    fn model_states(&self) -> usize {
        self.x.len() - PhiFilter::STATES
    }

    /// The model's states.
    pub fn model_x(&self) -> &[f64] {
        &self.x[..self.model_states()]
    }

    /// The filter's φ, φ′, φ″ at its states for its input now.
    pub fn filtered(&self) -> Phi {
        let m = self.model_states();
        let state = self.x[m..].try_into().expect("the filter's states end x");
        self.filter.phi(self.ramp.eval(self.t), state)
    }

    /// The host's φ, φ′, φ″ (phi_source = input): as it sent them, or, if it sends φ alone,
    /// the filter's.
    fn host(&self, values: &super::values::Values) -> Phi {
        if values.rates_set {
            Phi { phi: values.input.phi, dphi: values.rates[0], ddphi: values.rates[1] }
        } else {
            self.filtered()
        }
    }

    /// The piece of φ at the current time, the host's input being `host`.
    fn piece(&self, host: Phi) -> PhiPiece {
        self.eq.piece(self.t, self.turned, host)
    }

    /// The piece of φ at the current time for the host's values.
    fn piece_of(&self, values: &super::values::Values) -> PhiPiece {
        self.piece(self.host(values))
    }

    /// x′ at the current time into `out`: the model's equations, and the filter's.
    pub fn derivatives(&self, values: &super::values::Values, out: &mut [f64]) {
        let m = self.model_states();
        self.eq.derivatives(self.t, self.piece_of(values), self.model_x(), &mut out[..m]);
        let f = self.filtered();
        out[m] = f.dphi;
        out[m + 1] = f.ddphi;
    }

    /// FMI 3.0's state arrays: q (the first half of x), dq (the second), or ddq (the
    /// second half of x′).
    pub fn state_array(&self, var: Var, values: &super::values::Values) -> Vec<f64> {
        let (m, half) = (self.model_states(), self.model_states() / 2);
        match var {
            Var::Q => self.x[..half].to_vec(),
            Var::Dq => self.x[half..m].to_vec(),
            _ => {
                let mut dx = vec![0.0; self.x.len()];
                self.derivatives(values, &mut dx);
                dx[half..m].to_vec()
            }
        }
    }

    pub fn kinematics(&self, values: &super::values::Values) -> Kinematics {
        self.eq.kinematics(self.t, self.piece_of(values), self.model_x())
    }

    /// Checks the range at the current state: `None` inside it (or with the check off and
    /// the coordinates numbers), else why and whether the run must end. `warn` then turns
    /// the check off.
    ///
    /// At an event (`at_event`), a state on a limit to within the indicators' rounding counts
    /// as past it: that is where the host's root finding puts the event, on either side.
    fn range_violation(&mut self, host: Phi, at_event: bool) -> Option<(String, bool)> {
        let check = self.range != RangeCheck::Off;
        let v = match self.eq.check_range(self.t, self.piece(host), self.model_x(), check) {
            Err(v) => v,
            Ok(()) if at_event => self.on_a_limit(host)?,
            Ok(()) => return None,
        };
        let what = format!(
            "at t = {:?} the state left the range of validity: `{}` = {:?}, allowed {}",
            self.t, v.name, v.value, v.allowed
        );
        Some(match self.range {
            RangeCheck::Warn => {
                self.range = RangeCheck::Off;
                (
                    format!("{what}; the run goes on outside it (range_check = warn, said once)"),
                    false,
                )
            }
            RangeCheck::Stop => {
                (format!("{what}; terminateSimulation = true (range_check = stop)"), true)
            }
            RangeCheck::Off => (format!("{what}; terminateSimulation = true"), true),
        })
    }

    /// The event indicators: the margins of the quadratic model's range of validity, l − |v1|
    /// and π/2 − |ϑ1|; `None` with the check off, or for the exact beam, whose one limit (a
    /// centreline that crosses itself) is checked at each step's end.
    fn margins(&self) -> Option<[f64; 2]> {
        if self.range == RangeCheck::Off || !self.eq.tip_limits() {
            return None;
        }
        let (v1, theta1) = self.eq.tip(self.model_x());
        let l = self.eq.model().params.l;
        Some([l - v1.abs(), std::f64::consts::FRAC_PI_2 - theta1.abs()])
    }

    /// The limit the state is on, to within 1e-12 of it (relative), moving out, as a
    /// violation. A state at rest on a limit (a start there) is inside, as co-simulation has it.
    fn on_a_limit(&self, host: Phi) -> Option<RangeViolation> {
        let m = self.margins()?;
        let on = [m[0] <= 1e-12 * self.eq.model().params.l, m[1] <= 1e-12];
        if on == [false, false] {
            return None;
        }
        let k = self.eq.kinematics(self.t, self.piece(host), self.model_x());
        if on[0] && k.v1 * k.dv1 > 0.0 {
            Some(RangeViolation { name: "v1", value: k.v1, allowed: "|v1| <= l" })
        } else if on[1] && k.theta1 * k.dtheta1 > 0.0 {
            Some(RangeViolation { name: "theta1", value: k.theta1, allowed: "|theta1| <= pi/2" })
        } else {
            None
        }
    }
}

/// FMI 2.0 Model Exchange fixes its states in the model description: the paper's two
/// coordinates of the quadratic beam in one element (damping allowed), and the filter's two.
fn check_fmi2(values: &super::values::Values) -> Result<(), String> {
    let p = &values.settings.params;
    if p.n_elements != 1 || p.beam != BeamModel::Quadratic {
        let other = if p.beam == BeamModel::Exact {
            format!(
                "the exact beam's states are other coordinates (the section angles of its {} \
                 element(s), 4·n of them)",
                p.n_elements
            )
        } else {
            format!("`n_elements` = {} would need {} of them", p.n_elements, 4 * p.n_elements)
        };
        return Err(format!(
            "FMI 2.0 Model Exchange runs the quadratic beam in one element: its model \
             description declares 6 continuous states, v1, theta1, dv1, dtheta1 and the two of \
             the filter of phi, and {other}; use FMI 3.0's Model Exchange (BeamBody-fmi3.fmu, \
             whose states are arrays sized by n_elements) or co-simulation for this beam"
        ));
    }
    Ok(())
}

impl BeamBodyFmu {
    /// The Model Exchange equations at the start time from the current values.
    pub(super) fn build_exchange(&self, setup: &Setup) -> Result<Exchange, String> {
        if self.version == Version::Fmi2 {
            check_fmi2(&self.values)?;
        }
        let t = setup.start_time;
        let eq = Equations::new(&self.values.settings, t, self.values.input.phi)
            .map_err(|e| e.to_string())?;
        let turned = eq.law().is_some_and(|law| t >= law.breakpoint());
        let range = eq.range_check();
        let filter = PhiFilter::new(self.values.settings.phi_filter_frequency);
        // The filter starts at the host's φ, at rest; x holds only its states until the
        // model's start, which reads them (φ alone from the host).
        let phi0 = self.values.input.phi;
        let rest = PhiFilter::at_rest(phi0);
        let ramp = Ramp::at(t, phi0);
        let mut ex = Exchange { eq, filter, t, x: rest.to_vec(), ramp, turned, range };
        let mut x = ex.eq.start(ex.piece_of(&self.values)).map_err(|e| e.to_string())?;
        x.extend(rest);
        ex.x = x;
        Ok(ex)
    }

    fn exchange(&self) -> &Exchange {
        self.exchange.as_deref().expect("the core calls this after the equations exist")
    }

    fn exchange_mut(&mut self) -> &mut Exchange {
        self.cache = Default::default();
        self.exchange.as_deref_mut().expect("the core calls this after the equations exist")
    }

    /// The Model Exchange part of a state: the states, the event flags, the range's.
    pub(super) fn visit_exchange<V: StateVisitor>(
        &mut self,
        v: &mut V,
        at: &fmi::Restore,
    ) -> Result<(), String> {
        let mut has = self.exchange.is_some();
        v.flag("exchange", &mut has);
        use fmi::State::*;
        let needs = matches!(at.state, EventMode | ContinuousTimeMode | Terminated);
        let may = needs || matches!(at.state, InitializationMode | Error);
        if (needs && !has) || (has && !may) {
            return Err(format!("field `exchange` = {has} contradicts the state `{:?}`", at.state));
        }
        if !has {
            self.exchange = None;
            return Ok(());
        }
        if self.exchange.is_none() {
            let built = self.build_exchange(&at.setup);
            self.exchange =
                Some(Box::new(built.map_err(|e| format!("the saved parameters: {e}"))?));
        }
        let ex = self.exchange.as_deref_mut().expect("built above");
        let mut n = ex.x.len() as u64;
        v.count("exchange.states", &mut n);
        if n != ex.x.len() as u64 {
            return Err(format!(
                "field `exchange.states` = {n}: the saved parameters make {} states",
                ex.x.len()
            ));
        }
        for x in ex.x.iter_mut() {
            v.real("exchange.x", x);
        }
        let r = &mut ex.ramp;
        v.real("exchange.ramp.t0", &mut r.t0);
        v.real("exchange.ramp.from", &mut r.from);
        v.real("exchange.ramp.to", &mut r.to);
        v.real("exchange.ramp.len", &mut r.len);
        if ex.x.iter().any(|x| !x.is_finite()) {
            return Err("field `exchange.x` holds a non-finite state".into());
        }
        let r = ex.ramp;
        if ![r.t0, r.from, r.to, r.len].iter().all(|x| x.is_finite()) || r.len < 0.0 {
            return Err("field `exchange.ramp`: not finite, or a negative length".into());
        }
        v.flag("exchange.turned", &mut ex.turned);
        let mut warned = ex.range != ex.eq.range_check();
        v.flag("exchange.range_warned", &mut warned);
        if warned && ex.eq.range_check() != RangeCheck::Warn {
            return Err("field `exchange.range_warned`: set, but range_check is not warn".into());
        }
        ex.range = if warned { RangeCheck::Off } else { ex.eq.range_check() };
        ex.t = at.time;
        if let Some(law) = ex.eq.law() {
            let bp = law.breakpoint();
            if ex.turned && ex.t < bp && !crate::math::same_time(ex.t, bp, 0.0) {
                return Err(format!(
                    "field `exchange.turned` = true before the law's end t_rot = {bp:?} (time = \
                     {:?})",
                    ex.t
                ));
            }
        } else if ex.turned {
            return Err(
                "field `exchange.turned` = true without the law (phi_source = input)".into()
            );
        }
        Ok(())
    }
}

impl fmi::ModelExchange for BeamBodyFmu {
    const INDICATORS: usize = EVENT_INDICATORS;

    fn prepare_exchange(&mut self, setup: &Setup) -> Result<(), String> {
        if self.exchange.is_none() {
            self.exchange = Some(Box::new(self.build_exchange(setup)?));
        }
        Ok(())
    }

    fn state_count(&self) -> usize {
        match (&self.exchange, self.version) {
            (Some(ex), _) => ex.x.len(),
            // FMI 2.0's model description: the six of `STATES` (other beams are refused at
            // ExitInitializationMode, naming them).
            (None, Version::Fmi2) => STATES.len(),
            // FMI 3.0's: q and dq, 2·n_elements each, and the filter's two.
            (None, Version::Fmi3) => 4 * self.values.settings.params.n_elements + PhiFilter::STATES,
        }
    }

    fn state_name(&self, k: usize) -> String {
        match self.version {
            Version::Fmi2 => {
                STATES.get(k).map_or_else(|| format!("x[{k}]"), |v| format!("`{}`", v.info().name))
            }
            Version::Fmi3 => {
                let m = fmi::ModelExchange::state_count(self) - PhiFilter::STATES;
                let half = m / 2;
                match k {
                    k if k < half => format!("x[{k}] (`q` element {k})"),
                    k if k < m => format!("x[{k}] (`dq` element {})", k - half),
                    k => {
                        let first = STATES3.len() - PhiFilter::STATES;
                        let var = STATES3.get(first + k - m).map_or("?", |v| v.info().name);
                        format!("x[{k}] (`{var}`)")
                    }
                }
            }
        }
    }

    fn set_time(&mut self, t: f64) {
        self.exchange_mut().t = t;
    }

    fn set_states(&mut self, x: &[f64]) {
        self.exchange_mut().x.copy_from_slice(x);
    }

    fn states(&self, out: &mut [f64]) {
        out.copy_from_slice(&self.exchange().x);
    }

    fn derivatives(&mut self, out: &mut [f64]) -> Result<(), String> {
        self.exchange().derivatives(&self.values, out);
        Ok(())
    }

    fn event_indicators(&mut self, out: &mut [f64]) {
        match self.exchange().margins() {
            Some(m) => out.copy_from_slice(&m),
            // Nothing to locate: constant indicators.
            None => out.fill(1.0),
        }
    }

    fn nominals(&self, out: &mut [f64]) {
        // SI units: the paper's scene has |v1| ≤ 0.59 m, |ϑ1| ≤ 0.41 rad and rates of a few
        // per second, so 1 is their scale.
        out.fill(1.0);
    }

    fn update_discrete_states(&mut self, notes: &mut Notes) -> EventInfo {
        self.check_phi_sent(notes);
        let phi = self.values.input.phi;
        let ex = self.exchange_mut();
        ex.ramp.sample(ex.t, phi);
        let host = self.exchange().host(&self.values);
        let ex = self.exchange_mut();
        let mut info = EventInfo::default();
        if let Some(law) = ex.eq.law().copied() {
            let bp = law.breakpoint();
            if !ex.turned && (ex.t >= bp || crate::math::same_time(ex.t, bp, 0.0)) {
                ex.turned = true;
            }
            if !ex.turned {
                info.next_event_time = Some(bp);
            }
        }
        if let Some((msg, stop)) = ex.range_violation(host, true) {
            info.terminate_simulation = stop;
            notes.push(msg);
        }
        info
    }

    fn completed_integrator_step(&mut self, notes: &mut Notes) -> Result<StepEnd, String> {
        let host = self.exchange().host(&self.values);
        let phi = self.values.input.phi;
        let ex = self.exchange_mut();
        ex.ramp.sample(ex.t, phi);
        let mut end = StepEnd::default();
        if let Some((msg, stop)) = ex.range_violation(host, false) {
            end.terminate_simulation = stop;
            notes.push(msg);
        }
        Ok(end)
    }

    /// The directional derivative of any output, state or state derivative (`unknowns`)
    /// along `seed` in the states and the inputs φ, φ′, φ″ (`knowns`): the central difference
    /// of the values [`get`](fmi::Model::get) reads, at the step ε = ε_mach^(1/3)·max(1,
    /// max|(x, u)|)/max|seed| (relative accuracy about 1e-10: truncation O(ε²) against
    /// round-off O(ε_mach/ε); max norms, which neither overflow nor underflow). With the law,
    /// the inputs move nothing.
    fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        out: &mut [f64],
    ) -> Result<(), String> {
        let fmi3 = self.version == Version::Fmi3;
        let (states, derivatives): (&[Var], &[Var]) =
            if fmi3 { (&STATES3, &DERIVATIVES3) } else { (&STATES, &DERIVATIVES) };
        let names = |vars: &[Var]| -> String {
            let names: Vec<String> =
                vars.iter().map(|v| format!("`{}` ({})", v.info().name, v.vr())).collect();
            names.join(", ")
        };
        let inputs = [Var::Phi, Var::Dphi, Var::Ddphi];
        let nx = self.exchange().x.len();
        // Where each state variable's elements lie in x: the arrays q and dq hold a half each
        // of the model's states, the scalars one each.
        let n_array = (nx - PhiFilter::STATES) / 2;
        let mut spans = Vec::with_capacity(states.len());
        let mut at = 0;
        for v in states {
            let len = if v.info().dims.is_empty() { 1 } else { n_array };
            spans.push(at..at + len);
            at += len;
        }
        let mut vx = vec![0.0; nx];
        let mut vu = [0.0; 3];
        let mut seeds = seed.iter();
        let mut too_few = false;
        for vr in knowns {
            if let Some(k) = states.iter().position(|v| v.vr() == *vr) {
                for slot in &mut vx[spans[k].clone()] {
                    match seeds.next() {
                        Some(s) => *slot += s,
                        None => too_few = true,
                    }
                }
            } else if let Some(k) = inputs.iter().position(|v| v.vr() == *vr) {
                match seeds.next() {
                    Some(s) => vu[k] += s,
                    None => too_few = true,
                }
            } else {
                return Err(format!(
                    "known value reference {vr} is not a continuous state or an input: must \
                     be one of {}, {}",
                    names(states),
                    names(&inputs)
                ));
            }
        }
        if too_few || seeds.next().is_some() {
            return Err(format!(
                "{} seeds for the known value references {knowns:?}, whose elements number \
                 otherwise (an array state counts {n_array})",
                seed.len()
            ));
        }
        let n_elements = self.values.settings.params.n_elements;
        let mut sizes = Vec::with_capacity(unknowns.len());
        for vr in unknowns {
            let var = Var::from_vr(*vr).filter(|v| {
                let info = v.info();
                matches!(info.causality, Causality::Output | Causality::Local)
                    && info.in_version(self.version)
            });
            let Some(var) = var else {
                return Err(format!(
                    "unknown value reference {vr} is not an output, a state or a state \
                     derivative: must be one of those of <ModelStructure> (the outputs, {})",
                    names(derivatives)
                ));
            };
            sizes.push(match var.info().dims.len() {
                0 => 1,
                1 => n_elements,
                _ => 2 * n_elements,
            });
        }
        if sizes.iter().sum::<usize>() != out.len() {
            return Err(format!(
                "{} sensitivities for the unknown value references {unknowns:?}, which have {} \
                 elements",
                out.len(),
                sizes.iter().sum::<usize>()
            ));
        }
        let x0: Vec<f64> = self.exchange().x.clone();
        let u0 = [self.values.input.phi, self.values.rates[0], self.values.rates[1]];
        let amax = |a: &[f64]| a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let nv = amax(&vx).max(amax(&vu));
        if nv == 0.0 {
            out.fill(0.0);
            return Ok(());
        }
        // ε_mach^(1/3) = 2^(-52/3).
        const CBRT_EPS: f64 = 6.055454452393344e-6;
        let eps = CBRT_EPS * amax(&x0).max(amax(&u0)).max(1.0) / nv;
        let values = |fmu: &mut Self, s: f64| -> Result<Vec<f64>, String> {
            let x: Vec<f64> = x0.iter().zip(&vx).map(|(a, b)| a + s * b).collect();
            fmu.exchange_mut().x.copy_from_slice(&x);
            fmu.values.input.phi = u0[0] + s * vu[0];
            fmu.values.rates = [u0[1] + s * vu[1], u0[2] + s * vu[2]];
            let setup = Setup { tolerance: None, start_time: 0.0, stop_time: None };
            let mut got = vec![0.0; sizes.iter().sum()];
            let mut k = 0;
            for (vr, n) in unknowns.iter().zip(&sizes) {
                if Var::from_vr(*vr).is_some_and(|v| v.info().dims.is_empty()) {
                    got[k] = fmi::Model::get(fmu, *vr, &setup)?.real();
                } else {
                    fmi::Model::get_array(fmu, *vr, &setup, &mut got[k..k + n])?;
                }
                k += n;
            }
            Ok(got)
        };
        let plus = values(self, eps);
        let minus = values(self, -eps);
        // Back to the host's state and inputs, whatever happened.
        self.exchange_mut().x.copy_from_slice(&x0);
        self.values.input.phi = u0[0];
        self.values.rates = [u0[1], u0[2]];
        let (plus, minus) = (plus?, minus?);
        for ((slot, p), m) in out.iter_mut().zip(&plus).zip(&minus) {
            *slot = (p - m) / (2.0 * eps);
        }
        Ok(())
    }
}
