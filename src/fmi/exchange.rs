//! Model Exchange's calls on an instance whose host integrates the model's equations
//! ([`ModelExchange`]): time, continuous states, derivatives, event indicators, the event
//! iteration and the integrator's completed steps. The state machine is the core's
//! ([`Instance`]); this file adds Model Exchange's own functions to it.
#![forbid(unsafe_code)]

use super::instance::{trace, Instance};
use super::machine::{mask, FmiError, FmiResult, Interface, State, Status};
use super::model::{ModelExchange, Notes};

/// What fmi2NewDiscreteStates tells the host (fmi2EventInfo).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EventInfo {
    pub new_discrete_states_needed: bool,
    pub terminate_simulation: bool,
    pub nominals_of_continuous_states_changed: bool,
    pub values_of_continuous_states_changed: bool,
    /// The next time event, if there is one.
    pub next_event_time: Option<f64>,
}

/// What fmi2CompletedIntegratorStep tells the host.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepEnd {
    pub enter_event_mode: bool,
    pub terminate_simulation: bool,
}

impl<M: ModelExchange> Instance<M> {
    /// Checks that `func`, a Model Exchange function, may be called in the current state
    /// (`allowed`) on this instance.
    fn exchange(&self, func: &'static str, allowed: u32) -> FmiResult<super::instance::Func> {
        let f = self.func(func);
        self.allowed_in(f, Interface::ModelExchange, allowed)?;
        Ok(f)
    }

    /// Checks that the host's array of `n` elements has the model's size `size`.
    fn check_count(
        f: super::instance::Func,
        what: &'static str,
        n: usize,
        size: usize,
    ) -> FmiResult<()> {
        if n == size {
            return Ok(());
        }
        let what = (f.0.count_name)(what);
        Err(FmiError::error(format!(
            "{f}: {what} = {n} is out of range: the model has {size} (the model description's \
             count)"
        )))
    }

    /// A call that only changes the mode: `func`, allowed in `allowed`, leads to `to`.
    fn enter_mode(&mut self, func: &'static str, allowed: u32, to: State) -> Status {
        let r = self.exchange(func, allowed).map(|f| {
            self.core.state = to;
            let t = self.core.time;
            trace!(self, "{f}: at t = {t:?}");
            Status::Ok
        });
        self.status(r)
    }

    /// EnterEventMode.
    pub fn enter_event_mode(&mut self) -> Status {
        self.enter_mode("EnterEventMode", mask::EVENT_OR_CONTINUOUS, State::EventMode)
    }

    /// NewDiscreteStates: one pass of the event iteration, and the call's status (a warning
    /// when the model told the host something).
    pub fn new_discrete_states(&mut self) -> Result<(EventInfo, Status), Status> {
        let r = self.exchange("NewDiscreteStates", mask::EVENT).map(|f| {
            let mut notes = Notes::new();
            let info = self.core.model.update_discrete_states(&mut notes);
            if info.terminate_simulation {
                self.core.terminated = true;
            }
            trace!(self, "{f}: {info:?}");
            (info, self.notes(f, notes))
        });
        self.edge(r)
    }

    /// GetNumberOfContinuousStates (FMI 3.0): the model's count, which before
    /// initialization is the model description's.
    pub fn number_of_continuous_states(&mut self) -> Result<usize, Status> {
        let r = self.exchange("GetNumberOfContinuousStates", mask::COUNTS).map(|f| {
            let n = self.core.model.state_count();
            trace!(self, "{f}: {n}");
            n
        });
        self.edge(r)
    }

    /// GetNumberOfEventIndicators (FMI 3.0).
    pub fn number_of_event_indicators(&mut self) -> Result<usize, Status> {
        let r = self.exchange("GetNumberOfEventIndicators", mask::COUNTS).map(|f| {
            let n = M::INDICATORS;
            trace!(self, "{f}: {n}");
            n
        });
        self.edge(r)
    }

    /// EnterContinuousTimeMode.
    pub fn enter_continuous_time_mode(&mut self) -> Status {
        self.enter_mode("EnterContinuousTimeMode", mask::EVENT, State::ContinuousTimeMode)
    }

    /// CompletedIntegratorStep: the host accepted a step; the model checks its range.
    pub fn completed_integrator_step(&mut self) -> Result<(StepEnd, Status), Status> {
        let r = self.exchange("CompletedIntegratorStep", mask::CONTINUOUS).and_then(|f| {
            let mut notes = Notes::new();
            let result = self.core.model.completed_integrator_step(&mut notes);
            let told = self.notes(f, notes);
            let end = result.map_err(|msg| FmiError::error(format!("{f}: {msg}")))?;
            if end.terminate_simulation {
                self.core.terminated = true;
            }
            let t = self.core.time;
            trace!(self, "{f}: at t = {t:?}: {end:?}");
            Ok((end, told))
        });
        self.edge(r)
    }

    /// SetTime.
    pub fn set_time(&mut self, t: f64) -> Status {
        let r = self.exchange("SetTime", mask::EVENT_OR_CONTINUOUS).and_then(|f| {
            // Any finite time from the start on: an integrator evaluates the equations past
            // its output times and past stopTime (CVODE without a stop time does).
            let start = self.core.setup.start_time;
            if !(t.is_finite() && t >= start) {
                return Err(FmiError::error(format!(
                    "{f}: time = {t:?} is out of range: must be finite and >= startTime = \
                     {start:?}"
                )));
            }
            self.core.time = t;
            self.core.last_successful_time = t;
            self.core.model.set_time(t);
            trace!(self, "{f}: t = {t:?}");
            Ok(Status::Ok)
        });
        self.status(r)
    }

    /// SetContinuousStates: all of them, each finite.
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Status {
        let r = self.exchange("SetContinuousStates", mask::CONTINUOUS).and_then(|f| {
            Self::check_count(f, "nx", x.len(), self.core.model.state_count())?;
            if let Some(k) = x.iter().position(|v| !v.is_finite()) {
                return Err(FmiError::error(format!(
                    "{f}: x[{k}] = {} ({}) is out of range: must be finite",
                    x[k],
                    self.core.model.state_name(k)
                )));
            }
            self.core.model.set_states(x);
            trace!(self, "{f}: x = {x:?}");
            Ok(Status::Ok)
        });
        self.status(r)
    }

    /// GetContinuousStates.
    pub fn get_continuous_states(&mut self, out: &mut [f64]) -> Status {
        let r = self.exchange("GetContinuousStates", mask::STATES_AND_INDICATORS).and_then(|f| {
            self.started(f)?;
            Self::check_count(f, "nx", out.len(), self.core.model.state_count())?;
            self.core.model.states(out);
            trace!(self, "{f}: x = {out:?}");
            Ok(Status::Ok)
        });
        self.status(r)
    }

    /// The equations exist from ExitInitializationMode on; in initialization mode (and in
    /// the error state a failed initialization leaves) the model builds them from its values
    /// on the first request, as it computes outputs there, or says why it cannot.
    fn started(&mut self, f: super::instance::Func) -> FmiResult<()> {
        let setup = self.core.setup;
        self.core
            .model
            .prepare_exchange(&setup)
            .map_err(|msg| FmiError::error(format!("{f}: the model cannot start: {msg}")))
    }

    /// GetDerivatives. Non-finite derivatives (a state far outside the model's range, which
    /// an integrator's trial may reach) are refused with fmi2Discard, so that the host
    /// retries with a smaller step (FMI 2.0 §2.1.3).
    pub fn get_derivatives(&mut self, out: &mut [f64]) -> Status {
        let allowed = self.api().derivatives_mask;
        let r = self.exchange("GetDerivatives", allowed).and_then(|f| {
            self.started(f)?;
            Self::check_count(f, "nx", out.len(), self.core.model.state_count())?;
            let t = self.core.time;
            self.core
                .model
                .derivatives(out)
                .map_err(|msg| FmiError::discard(format!("{f}: {msg}")))?;
            if let Some(k) = out.iter().position(|v| !v.is_finite()) {
                return Err(FmiError::discard(format!(
                    "{f}: the derivative of x[{k}] ({}) is not finite at t = {t:?}",
                    self.core.model.state_name(k)
                )));
            }
            trace!(self, "{f}: dx = {out:?}");
            Ok(Status::Ok)
        });
        self.status(r)
    }

    /// GetEventIndicators.
    pub fn get_event_indicators(&mut self, out: &mut [f64]) -> Status {
        let r = self.exchange("GetEventIndicators", mask::STATES_AND_INDICATORS).and_then(|f| {
            self.started(f)?;
            Self::check_count(f, "ni", out.len(), M::INDICATORS)?;
            self.core.model.event_indicators(out);
            trace!(self, "{f}: z = {out:?}");
            Ok(Status::Ok)
        });
        self.status(r)
    }

    /// GetNominalsOfContinuousStates.
    pub fn get_nominals(&mut self, out: &mut [f64]) -> Status {
        let allowed = self.api().nominals_mask;
        let r = self.exchange("GetNominalsOfContinuousStates", allowed).and_then(|f| {
            Self::check_count(f, "nx", out.len(), self.core.model.state_count())?;
            self.core.model.nominals(out);
            trace!(self, "{f}: {out:?}");
            Ok(Status::Ok)
        });
        self.status(r)
    }

    /// GetDirectionalDerivative of a Model Exchange instance: the derivative of outputs,
    /// states or state derivatives along a seed of states or inputs; a non-finite result is
    /// an error.
    pub fn get_directional_derivative_exchange(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        out: &mut [f64],
    ) -> Status {
        let f = self.func("GetDirectionalDerivative");
        let r = self.allowed(f, self.masks().get).and_then(|()| {
            if let Some(k) = seed.iter().position(|v| !v.is_finite()) {
                return Err(FmiError::error(format!(
                    "{f}: dvKnown[{k}] = {} is out of range: must be finite",
                    seed[k]
                )));
            }
            self.started(f)?;
            self.core
                .model
                .directional_derivative(unknowns, knowns, seed, out)
                .map_err(|msg| FmiError::error(format!("{f}: {msg}")))?;
            if let Some(k) = out.iter().position(|v| !v.is_finite()) {
                return Err(FmiError::error(format!(
                    "{f}: dvUnknown[{k}] = {} is not finite at this state and seed",
                    out[k]
                )));
            }
            trace!(self, "{f}: unknowns {unknowns:?}, knowns {knowns:?}, seed {seed:?}: {out:?}");
            Ok(Status::Ok)
        });
        self.status(r)
    }
}
