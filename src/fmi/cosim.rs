//! Co-simulation's calls on an instance whose model integrates itself ([`CoSimulation`]):
//! the step, the derivatives of inputs and outputs, and FMI 2.0's status queries.
#![forbid(unsafe_code)]

use super::description::{BaseType, Causality};
use super::instance::{trace, Func, Instance};
use super::machine::{mask, FmiError, FmiResult, Interface, State, Status};
use super::model::{CoSimulation, Notes};
use crate::math::same_time;

/// fmi2StatusKind.
pub const STATUS_DO_STEP: i32 = 0;
pub const STATUS_PENDING: i32 = 1;
pub const STATUS_LAST_SUCCESSFUL_TIME: i32 = 2;
pub const STATUS_TERMINATED: i32 = 3;

/// The most parts one step with intermediate update is cut into (FMI 3.0): the host's
/// callback runs at most this many times a step.
pub const MAX_PARTS: f64 = 100.0;

impl<M: CoSimulation> Instance<M> {
    /// Whether `f`, a co-simulation function, may be called in the current state (`mask`)
    /// on this instance.
    fn cs_allowed(&self, f: Func, mask: u32) -> FmiResult<()> {
        self.allowed_in(f, Interface::CoSimulation, mask)
    }

    /// SetRealInputDerivatives: derivatives of the inputs at the next communication point,
    /// for the next step only.
    pub fn set_real_input_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> Status {
        let r = self.try_set_real_input_derivatives(vrs, orders, values);
        self.status(r)
    }

    fn try_set_real_input_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> FmiResult {
        let f = self.func("SetRealInputDerivatives");
        self.cs_allowed(f, self.masks().set)?;
        if vrs.len() != orders.len() || vrs.len() != values.len() {
            return Err(FmiError::error(format!("{f}: arrays of different lengths")));
        }
        let max = M::MAX_INPUT_DERIVATIVE_ORDER;
        for ((vr, order), value) in vrs.iter().zip(orders).zip(values) {
            let info = Self::lookup(f, *vr, BaseType::Real)?;
            if info.causality != Causality::Input || !M::takes_derivatives(*vr) {
                let inputs: Vec<String> = (0..M::variable_count() as u32)
                    .filter(|k| M::takes_derivatives(*k))
                    .filter_map(|k| M::variable(k).map(|v| format!("`{}` ({k})", v.name)))
                    .collect();
                return Err(FmiError::error(format!(
                    "{f}: value reference {vr} (`{}`) is not an input that takes derivatives; \
                     only {} does",
                    info.name,
                    inputs.join(", ")
                )));
            }
            if !(1..=max).contains(order) {
                let orders: Vec<String> = (1..=max).map(|k| k.to_string()).collect();
                return Err(FmiError::error(format!(
                    "{f}: order {order} of `{}` is out of range: must be {}",
                    info.name,
                    orders.join(" or ")
                )));
            }
            if !value.is_finite() {
                return Err(FmiError::error(format!(
                    "{f}: derivative of order {order} of `{}` = {value} is out of range: \
                     must be finite",
                    info.name
                )));
            }
        }
        for ((vr, order), value) in vrs.iter().zip(orders).zip(values) {
            self.core.model.set_input_derivative(*vr, *order, *value);
        }
        trace!(self, "{f}: vr {vrs:?}, order {orders:?}, value {values:?}");
        Ok(Status::Ok)
    }

    /// GetRealOutputDerivatives: time derivatives of the outputs at the communication time,
    /// where the model gives them: masters that extrapolate their inputs use these.
    pub fn get_real_output_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        out: &mut [f64],
    ) -> Status {
        let f = self.func("GetRealOutputDerivatives");
        let r = (|| {
            self.cs_allowed(f, mask::OUTPUT_DERIVATIVES)?;
            let max = M::MAX_OUTPUT_DERIVATIVE_ORDER;
            for ((vr, order), slot) in vrs.iter().zip(orders).zip(out.iter_mut()) {
                let info = Self::lookup(f, *vr, BaseType::Real)?;
                if info.causality != Causality::Output {
                    return Err(FmiError::error(format!(
                        "{f}: `{}` ({vr}) is not an output",
                        info.name
                    )));
                }
                if !(1..=max).contains(order) {
                    return Err(FmiError::error(format!(
                        "{f}: order {order} of `{}` is out of range: must be 1..={max} \
                         (maxOutputDerivativeOrder)",
                        info.name
                    )));
                }
                let setup = self.core.setup;
                let x = self
                    .core
                    .model
                    .output_derivative(*vr, *order, &setup)
                    .map_err(|msg| {
                        FmiError::error(format!("{f}: the outputs cannot be computed: {msg}"))
                    })?
                    .ok_or_else(|| {
                        FmiError::error(format!(
                            "{f}: `{}` has no derivative of order {order}: only {} have",
                            info.name,
                            M::outputs_with_derivatives(*order)
                        ))
                    })?;
                if !x.is_finite() {
                    return Err(FmiError::error(format!(
                        "{f}: the derivative of order {order} of `{}` is not finite at t = {}",
                        info.name, self.core.time
                    )));
                }
                *slot = x;
            }
            trace!(self, "{f}: vr {vrs:?}, order {orders:?}, value {out:?}");
            Ok(Status::Ok)
        })();
        self.status(r)
    }

    /// DoStep: integrates from `tc` to exactly `tc + h`.
    pub fn do_step(&mut self, tc: f64, h: f64) -> Status {
        let f = self.func("DoStep");
        let r = self.check_step(f, tc, h).and_then(|target| {
            trace!(self, "{f}: tc = {tc}, h = {h}");
            self.core.model.begin_step();
            self.advance(f, tc, target)
        });
        self.status(r)
    }

    /// DoStep of an interface whose host may ask for intermediate updates (FMI 3.0): with no
    /// callback, [`do_step`](Self::do_step); with one, the step planned, then part by part
    /// ([`step_part`](Self::step_part)) with the host's callback between them in intermediate
    /// update mode, and the worst status of the parts. The host's callback calls back into the
    /// instance, so no borrow of it may be alive then: the interface layer lends the instance
    /// to each phase through `access`, which runs the phase on it and returns its status (the
    /// layer's guard: finding the instance, catching a panic, writing the out-arguments).
    pub fn do_step_in_parts(
        tc: f64,
        h: f64,
        mut access: impl FnMut(&mut dyn FnMut(&mut Self) -> Status) -> Status,
    ) -> Status {
        let mut callback = None;
        let status = access(&mut |inst| match inst.intermediate_update() {
            None => inst.do_step(tc, h),
            Some(cb) => {
                callback = Some(cb);
                Status::Ok
            }
        });
        let Some(callback) = callback else {
            return status;
        };
        let mut target = f64::NAN;
        let planned = access(&mut |inst| match inst.plan_step(tc, h) {
            Ok(t) => {
                target = t;
                Status::Ok
            }
            Err(status) => status,
        });
        if planned > Status::Warning {
            return planned;
        }
        let mut worst = planned;
        loop {
            let (mut reached, mut t) = (true, f64::NAN);
            let part = access(&mut |inst| {
                let (status, end) = inst.step_part(target, h);
                (reached, t) = (end, inst.time());
                status
            });
            worst = worst.max(part);
            if part > Status::Warning || reached {
                return worst;
            }
            let mut set_requested = false;
            let entered = access(&mut |inst| {
                set_requested = inst.intermediate_set_requested();
                inst.enter_intermediate_update()
            });
            if entered > Status::Warning {
                return entered;
            }
            callback(t, set_requested);
            let left = access(&mut |inst| inst.leave_intermediate_update());
            if left > Status::Warning {
                return left;
            }
        }
    }

    /// The first phase of [`do_step_in_parts`](Self::do_step_in_parts): checks the step as
    /// [`do_step`](Self::do_step) does and gives its end `tc + h`. Public, with the phases
    /// below, for the fuzz harness, which plays the host's part between them.
    pub fn plan_step(&mut self, tc: f64, h: f64) -> Result<f64, Status> {
        let f = self.func("DoStep");
        let r = self.check_step(f, tc, h).inspect(|_| {
            trace!(self, "{f}: tc = {tc}, h = {h}, with intermediate update");
            self.core.model.begin_step();
        });
        self.edge(r)
    }

    /// One part of a planned step of size `h` towards `target`: the model's
    /// [`intermediate_spacing`](CoSimulation::intermediate_spacing) (at least `h` /
    /// [`MAX_PARTS`], so that a step returns in bounded time), or the rest of the step when
    /// that is at most a quarter more. The status, and whether `target` is reached.
    pub fn step_part(&mut self, target: f64, h: f64) -> (Status, bool) {
        let f = self.func("DoStep");
        let from = self.core.time;
        let to = match self.core.model.intermediate_spacing(self.intermediate_outputs) {
            Some(dt) if dt > 0.0 => {
                let dt = dt.max(h / MAX_PARTS);
                if from + 1.25 * dt < target && from + dt > from {
                    from + dt
                } else {
                    target
                }
            }
            _ => target,
        };
        let r = self.cs_allowed(f, mask::STEP_COMPLETE).and_then(|()| {
            trace!(self, "{f}: from t = {from:?} to {to:?}");
            self.advance(f, from, to)
        });
        (self.status(r), to == target)
    }

    /// The FMU's time.
    pub fn time(&self) -> f64 {
        self.core.time
    }

    /// Enters intermediate update mode at the FMU's time, between two parts of a step: the
    /// host may set the intermediate inputs and get values.
    pub fn enter_intermediate_update(&mut self) -> Status {
        let f = self.func("DoStep");
        let r = self.cs_allowed(f, mask::STEP_COMPLETE).map(|()| {
            self.core.state = State::IntermediateUpdate;
            self.intermediate_set = false;
            let t = self.core.time;
            trace!(self, "{f}: intermediate update at t = {t:?}");
            Status::Ok
        });
        self.status(r)
    }

    /// Whether the model asks the host for its inputs at the intermediate points (FMI 3.0's
    /// `intermediateVariableSetRequested`): it takes inputs between communication points.
    pub fn intermediate_set_requested(&self) -> bool {
        self.core.model.intermediate_spacing(false).is_some()
    }

    /// Back to step mode after the host's intermediate-update callback; without an input set
    /// there, the model goes on from the samples it holds.
    pub fn leave_intermediate_update(&mut self) -> Status {
        let f = self.func("DoStep");
        let r = self.cs_allowed(f, mask::INTERMEDIATE_UPDATE).map(|()| {
            self.core.state = State::StepComplete;
            if !self.intermediate_set {
                self.core.model.hold_input();
            }
            Status::Ok
        });
        self.status(r)
    }

    /// The checks of a step from `tc` by `h`: the state, `h`, `tc` against the FMU's time,
    /// the stop time. The step's end `tc + h`.
    fn check_step(&self, f: Func, tc: f64, h: f64) -> FmiResult<f64> {
        self.cs_allowed(f, mask::STEP_COMPLETE)?;
        let time = self.core.time;
        if !(h.is_finite() && h > 0.0) {
            return Err(FmiError::error(format!(
                "{f}: communicationStepSize = {h} is out of range: must be positive and finite"
            )));
        }
        // "Up to rounding": hosts compute tc as start + n·h or by sums; allow a few ulps.
        if !(tc.is_finite() && same_time(tc, time, h)) {
            return Err(FmiError::error(format!(
                "{f}: currentCommunicationPoint = {tc} does not match the FMU's time {time}"
            )));
        }
        if tc + h == tc {
            return Err(FmiError::error(format!(
                "{f}: communicationStepSize = {h:?} is below the resolution of the time \
                 tc = {tc:?} (tc + h = tc): the step would not advance"
            )));
        }
        let target = tc + h;
        if let Some(stop) = self.core.setup.stop_time {
            if target > stop && !same_time(target, stop, h) {
                return Err(FmiError::error(format!(
                    "{f}: the step to t = {target} passes stopTime = {stop}"
                )));
            }
        }
        Ok(target)
    }

    /// The model's step from `from` to `to`, checked; the FMU's time becomes `to`, or where
    /// the model stopped.
    fn advance(&mut self, f: Func, from: f64, to: f64) -> FmiResult {
        let mut notes = Notes::new();
        let result = self.core.model.do_step(from, to, &mut notes);
        let told = self.notes(f, notes);
        if let Err(e) = result {
            let t = e.t;
            self.core.time = t;
            self.core.last_successful_time = t;
            self.core.terminated = true;
            self.core.state = State::StepFailed;
            let (last, terminated) = f.0.step_end;
            return Err(FmiError::discard(format!(
                "{f}: {}. The FMU stopped at t = {t} ({last}), with {terminated} = true",
                e.message
            )));
        }
        self.core.time = to;
        self.core.last_successful_time = to;
        Ok(told)
    }

    /// After a step: whether the model ended the run (a discarded step), and the time of the
    /// last successful one (FMI 3.0's DoStep returns both; FMI 2.0 asks by GetStatus).
    pub fn step_end(&self) -> (bool, f64) {
        (self.core.terminated, self.core.last_successful_time)
    }

    /// CancelStep: steps are synchronous, so there is never one to cancel.
    pub fn cancel_step(&mut self) -> Status {
        let f = self.func("CancelStep");
        let r = self.cs_allowed(f, mask::NONE).map(|()| Status::Error);
        self.status(r)
    }

    /// GetStatus, GetIntegerStatus, GetStringStatus (FMI 2.0): none of their kinds is
    /// provided (they concern asynchronous steps).
    pub fn get_unprovided_status(&mut self, name: &'static str, kind: i32) -> Status {
        let f = self.func(name);
        let r = self.cs_allowed(f, mask::STATUS).and_then(|()| {
            Err(FmiError::error(format!(
                "{f}: status kind {kind} is not provided: fmi2DoStep never returns fmi2Pending"
            )))
        });
        self.status(r)
    }

    /// GetRealStatus (FMI 2.0): fmi2LastSuccessfulTime.
    pub fn get_real_status(&mut self, kind: i32) -> Result<f64, Status> {
        let f = self.func("GetRealStatus");
        let r = self.cs_allowed(f, mask::STATUS).and_then(|()| {
            if kind != STATUS_LAST_SUCCESSFUL_TIME {
                return Err(FmiError::error(format!(
                    "{f}: status kind {kind} is not provided: only fmi2LastSuccessfulTime \
                     ({STATUS_LAST_SUCCESSFUL_TIME})"
                )));
            }
            let t = self.core.last_successful_time;
            trace!(self, "{f}: fmi2LastSuccessfulTime = {t:?}");
            Ok(t)
        });
        self.edge(r)
    }

    /// GetBooleanStatus (FMI 2.0): fmi2Terminated.
    pub fn get_boolean_status(&mut self, kind: i32) -> Result<bool, Status> {
        let f = self.func("GetBooleanStatus");
        let r = self.cs_allowed(f, mask::STATUS).and_then(|()| {
            if kind != STATUS_TERMINATED {
                return Err(FmiError::error(format!(
                    "{f}: status kind {kind} is not provided: only fmi2Terminated \
                     ({STATUS_TERMINATED})"
                )));
            }
            let terminated = self.core.terminated;
            trace!(self, "{f}: fmi2Terminated = {terminated}");
            Ok(terminated)
        });
        self.edge(r)
    }

    /// GetDirectionalDerivative of a co-simulation instance: not provided (its
    /// providesDirectionalDerivative = false; Model Exchange's is true).
    pub fn get_directional_derivative(&mut self) -> Status {
        let f = self.func("GetDirectionalDerivative");
        let r = self.cs_allowed(f, self.masks().get).and_then(|()| {
            Err(FmiError::error(format!(
                "{f}: not provided in co-simulation ({} = false); Model Exchange provides it",
                f.0.directional_flag
            )))
        });
        self.status(r)
    }
}
