//! FMI 3.0's co-simulation functions: step mode, output derivatives and DoStep, whose
//! intermediate-update loop is the core's (`Instance::do_step_in_parts`).
#![allow(non_snake_case)]
#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

use super::exchange::flag;
use super::types::*;
use super::Instance;
use crate::capi::guard::{guard, null_arg, slice, slice_mut, status_of};
use crate::fmi::{Interface, Status};

/// # Safety
/// `instance` is an instance from fmi3Instantiate…. Without event mode there is nothing to
/// leave: refused.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status {
    guard(instance, "fmi3EnterStepMode", |inst| {
        let why = match inst.interface() {
            Interface::CoSimulation => {
                "this FMU's co-simulation has no event mode (hasEventMode = false): \
                 fmi3ExitInitializationMode leads to step mode"
            }
            Interface::ModelExchange => "a co-simulation function, on a Model Exchange instance",
        };
        inst.unsupported("EnterStepMode", why)
    })
}

/// # Safety
/// `instance` is an instance; `valueReferences` and `orders` hold `nValueReferences`
/// elements, `values` `nValues`.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetOutputDerivatives(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    orders: *const fmi3Int32,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetOutputDerivatives";
    let n = nValueReferences;
    guard(instance, F, |inst| {
        if n != nValues {
            let msg = format!(
                "{F}: nValues = {nValues} with {n} value references: only scalar outputs have \
                 derivatives here, so they must be equal"
            );
            inst.log(Status::Error, &msg);
            return Status::Error;
        }
        // SAFETY: each pointer holds `n` elements (the function's contract).
        match unsafe { (slice(valueReferences, n), slice(orders, n), slice_mut(values, n)) } {
            (Some(vr), Some(order), Some(value)) => {
                inst.get_real_output_derivatives(vr, order, value)
            }
            (None, _, _) => null_arg(inst, F, "valueReferences", n),
            (_, None, _) => null_arg(inst, F, "orders", n),
            (_, _, None) => null_arg(inst, F, "values", n),
        }
    })
}

/// fmi3DoStep's out-arguments.
/// Raw pointers, checked non-NULL, never references: a host may pass one address for the
/// flags it ignores, and may read them in its intermediate-update callback while a step runs.
struct StepOuts {
    event_handling_needed: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    early_return: *mut fmi3Boolean,
    last_successful_time: *mut fmi3Float64,
}

impl StepOuts {
    fn write(&self, inst: &Instance) {
        let (terminated, last) = inst.step_end();
        // SAFETY: non-NULL (checked when made), the host's, valid for writes for the call.
        unsafe {
            self.event_handling_needed.write(fmi3False);
            self.terminate_simulation.write(flag(terminated));
            self.early_return.write(fmi3False);
            self.last_successful_time.write(last);
        }
    }
}

/// # Safety
/// `instance` is an instance; the four out-arguments point to their types.
///
/// With the host's intermediate-update callback (given at instantiation, with `phi` among
/// the required intermediate variables) and φ from the host, the step is cut into parts of
/// `intermediate_step`: between the parts the instance is in intermediate update mode and
/// the host's callback may set φ at that time (if it sets nothing, the FMU extends the
/// samples it holds). The callback runs with no borrow of the
/// instance alive, since the host calls back into it.
#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    currentCommunicationPoint: fmi3Float64,
    communicationStepSize: fmi3Float64,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    eventHandlingNeeded: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    earlyReturn: *mut fmi3Boolean,
    lastSuccessfulTime: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3DoStep";
    let (tc, h) = (currentCommunicationPoint, communicationStepSize);
    let outs = StepOuts {
        event_handling_needed: eventHandlingNeeded,
        terminate_simulation: terminateSimulation,
        early_return: earlyReturn,
        last_successful_time: lastSuccessfulTime,
    };
    let flags = [outs.event_handling_needed, outs.terminate_simulation, outs.early_return];
    if flags.iter().any(|p| p.is_null()) || outs.last_successful_time.is_null() {
        return guard(instance, F, |inst| {
            let names = [
                ("eventHandlingNeeded", eventHandlingNeeded.is_null()),
                ("terminateSimulation", terminateSimulation.is_null()),
                ("earlyReturn", earlyReturn.is_null()),
                ("lastSuccessfulTime", lastSuccessfulTime.is_null()),
            ];
            let arg = names.iter().find(|(_, null)| *null).map_or("?", |(n, _)| n);
            null_arg(inst, F, arg, 1)
        });
    }
    // Each phase of the step on the instance, its out-arguments written after it; the host's
    // callback runs between phases, with no borrow of the instance alive.
    Instance::do_step_in_parts(tc, h, |phase| {
        let status = guard(instance, F, |inst| {
            let status = phase(inst);
            outs.write(inst);
            status
        });
        status_of(status)
    }) as fmi3Status
}
