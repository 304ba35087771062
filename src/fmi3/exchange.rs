//! FMI 3.0's Model Exchange functions.
#![allow(non_snake_case)]
#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

use super::types::*;
use super::{Instance, NO_EVENT_MODE};
use crate::capi::guard::{guard, null_arg, slice, slice_mut};
use crate::fmi::{Interface, Status};

/// Writes a flag through a host's pointer.
pub(super) fn flag(b: bool) -> fmi3Boolean {
    if b {
        fmi3True
    } else {
        fmi3False
    }
}

/// # Safety
/// `instance` is an instance; each pointer points to its type.
#[no_mangle]
pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
    instance: fmi3Instance,
    discreteStatesNeedUpdate: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    nominalsOfContinuousStatesChanged: *mut fmi3Boolean,
    valuesOfContinuousStatesChanged: *mut fmi3Boolean,
    nextEventTimeDefined: *mut fmi3Boolean,
    nextEventTime: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3UpdateDiscreteStates";
    guard(instance, F, |inst| {
        if inst.interface() == Interface::CoSimulation {
            return inst.unsupported("UpdateDiscreteStates", NO_EVENT_MODE);
        }
        let flags = [
            discreteStatesNeedUpdate,
            terminateSimulation,
            nominalsOfContinuousStatesChanged,
            valuesOfContinuousStatesChanged,
            nextEventTimeDefined,
        ];
        if flags.iter().any(|p| p.is_null()) || nextEventTime.is_null() {
            let names = [
                ("discreteStatesNeedUpdate", discreteStatesNeedUpdate.is_null()),
                ("terminateSimulation", terminateSimulation.is_null()),
                ("nominalsOfContinuousStatesChanged", nominalsOfContinuousStatesChanged.is_null()),
                ("valuesOfContinuousStatesChanged", valuesOfContinuousStatesChanged.is_null()),
                ("nextEventTimeDefined", nextEventTimeDefined.is_null()),
                ("nextEventTime", nextEventTime.is_null()),
            ];
            let arg = names.iter().find(|(_, null)| *null).map_or("?", |(n, _)| n);
            return null_arg(inst, F, arg, 1);
        }
        match inst.new_discrete_states() {
            Ok((info, status)) => {
                let values = [
                    info.new_discrete_states_needed,
                    info.terminate_simulation,
                    info.nominals_of_continuous_states_changed,
                    info.values_of_continuous_states_changed,
                    info.next_event_time.is_some(),
                ];
                // SAFETY: non-NULL, and the host's, valid for writes as the function's contract
                // says. Written through the raw pointers, one at a time: a host may pass one
                // address for several flags it ignores.
                unsafe {
                    for (p, b) in flags.iter().zip(values) {
                        p.write(flag(b));
                    }
                    nextEventTime.write(info.next_event_time.unwrap_or(0.0));
                }
                status
            }
            Err(status) => status,
        }
    })
}

/// # Safety
/// `instance` is an instance from fmi3Instantiate….
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status {
    guard(instance, "fmi3EnterContinuousTimeMode", Instance::enter_continuous_time_mode)
}

/// # Safety
/// `instance` is an instance; the two flags point to fmi3Booleans.
#[no_mangle]
pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
    instance: fmi3Instance,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    enterEventMode: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
) -> fmi3Status {
    const F: &str = "fmi3CompletedIntegratorStep";
    guard(instance, F, |inst| {
        if enterEventMode.is_null() || terminateSimulation.is_null() {
            let arg =
                if enterEventMode.is_null() { "enterEventMode" } else { "terminateSimulation" };
            return null_arg(inst, F, arg, 1);
        }
        match inst.completed_integrator_step() {
            Ok((end, status)) => {
                // SAFETY: non-NULL, the host's, valid for writes; written through the raw
                // pointers, which may be one address.
                unsafe {
                    enterEventMode.write(flag(end.enter_event_mode));
                    terminateSimulation.write(flag(end.terminate_simulation));
                }
                status
            }
            Err(status) => status,
        }
    })
}

/// # Safety
/// `instance` is an instance from fmi3Instantiate….
#[no_mangle]
pub unsafe extern "C" fn fmi3SetTime(instance: fmi3Instance, time: fmi3Float64) -> fmi3Status {
    guard(instance, "fmi3SetTime", |inst| inst.set_time(time))
}

/// # Safety
/// `instance` is an instance; `continuousStates` holds `nContinuousStates` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetContinuousStates(
    instance: fmi3Instance,
    continuousStates: *const fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetContinuousStates";
    // SAFETY: the array holds `nContinuousStates` elements (the function's contract).
    guard(instance, F, |inst| match unsafe { slice(continuousStates, nContinuousStates) } {
        Some(x) => inst.set_continuous_states(x),
        None => null_arg(inst, F, "continuousStates", nContinuousStates),
    })
}

/// The shape of the four Model Exchange functions that fill an array of `n` reals.
macro_rules! array_function {
    ($name:ident, $arg:literal, $method:ident) => {
        /// # Safety
        /// `instance` is an instance; the array holds `n` elements.
        #[no_mangle]
        pub unsafe extern "C" fn $name(
            instance: fmi3Instance,
            values: *mut fmi3Float64,
            n: usize,
        ) -> fmi3Status {
            // SAFETY: `values` holds `n` elements (the function's contract).
            guard(instance, stringify!($name), |inst| match unsafe { slice_mut(values, n) } {
                Some(out) => inst.$method(out),
                None => null_arg(inst, stringify!($name), $arg, n),
            })
        }
    };
}

array_function!(fmi3GetContinuousStateDerivatives, "derivatives", get_derivatives);
array_function!(fmi3GetEventIndicators, "eventIndicators", get_event_indicators);
array_function!(fmi3GetContinuousStates, "continuousStates", get_continuous_states);
array_function!(fmi3GetNominalsOfContinuousStates, "nominals", get_nominals);

/// The shape of the two counts.
macro_rules! count_function {
    ($name:ident, $arg:literal, $method:ident) => {
        /// # Safety
        /// `instance` is an instance; the pointer points to a `size_t`.
        #[no_mangle]
        pub unsafe extern "C" fn $name(instance: fmi3Instance, n: *mut usize) -> fmi3Status {
            guard(instance, stringify!($name), |inst| {
                // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
                let Some(n) = (unsafe { n.as_mut() }) else {
                    return null_arg(inst, stringify!($name), $arg, 1);
                };
                match inst.$method() {
                    Ok(count) => {
                        *n = count;
                        Status::Ok
                    }
                    Err(status) => status,
                }
            })
        }
    };
}

count_function!(fmi3GetNumberOfContinuousStates, "nContinuousStates", number_of_continuous_states);
count_function!(fmi3GetNumberOfEventIndicators, "nEventIndicators", number_of_event_indicators);
