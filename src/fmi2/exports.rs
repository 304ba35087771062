//! The 44 functions of the FMI 2.0 API, common, Model Exchange and co-simulation, exported
//! under their standard names.
//!
//! Each function checks the instance pointer against the registry of live instances, turns
//! C pointers into slices and strings, and calls the safe [`Instance`] method inside the
//! panic guard, which catches any panic so that nothing unwinds into the host. A caught
//! panic makes the instance fatal.
#![allow(non_snake_case)]
#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

use super::types::*;
use super::{Core, Instance};
use crate::capi::guard::{get_values, guard, null_arg, set_values, slice, slice_mut, text};
use crate::capi::registry::{unregister_instance, with_registry};
use crate::capi::states;
use crate::fmi::{Interface, Logger, Status};
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// # Safety
/// None: returns a static string.
#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// # Safety
/// None: returns a static string.
#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// # Safety
/// `c` is an instance from fmi2Instantiate; `categories` holds `n` C strings.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    guard(c, "fmi2SetDebugLogging", |inst| {
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(cats) = (unsafe { slice(categories, nCategories) }) else {
            return null_arg(inst, "fmi2SetDebugLogging", "categories", nCategories);
        };
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let names: Vec<Option<&str>> = cats.iter().map(|s| unsafe { text(*s) }).collect();
        inst.set_debug_logging(loggingOn != fmi2False, &names)
    })
}

// ----- creation and destruction ---------------------------------------------------------------

/// Wraps the host's logger: `logger(env, instanceName, status, category, "%s", message)`.
fn host_logger(functions: &fmi2CallbackFunctions, name: &str) -> Option<Logger> {
    let logger = functions.logger?;
    let env = functions.componentEnvironment as usize;
    let name = CString::new(name.replace('\0', " ")).ok()?;
    Some(Box::new(move |status: Status, category: &str, message: &str| {
        let category = CString::new(category.replace('\0', " ")).unwrap_or_default();
        let message = CString::new(message.replace('\0', " ")).unwrap_or_default();
        // SAFETY: the host promised a valid logger for the instance's lifetime; "%s" makes
        // the message a plain argument, never a format.
        unsafe {
            logger(
                env as fmi2ComponentEnvironment,
                name.as_ptr(),
                status as fmi2Status,
                category.as_ptr(),
                c"%s".as_ptr(),
                message.as_ptr(),
            )
        }
    }))
}

/// # Safety
/// Strings are NULL or NUL-terminated; `functions` is NULL or points to valid callbacks that
/// outlive the instance.
#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    _fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    let made = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let functions = unsafe { functions.as_ref() }?;
        let name = if instanceName.is_null() {
            None
        } else {
            // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
            Some(unsafe { CStr::from_ptr(instanceName) }.to_string_lossy().into_owned())
        };
        let mut log = host_logger(functions, name.as_deref().unwrap_or("(null)"))?;
        let Some(name) = name else {
            log(Status::Error, "logStatusError", "fmi2Instantiate: instanceName is NULL");
            return None;
        };
        let guid = if fmuGUID.is_null() {
            "(null)".into()
        } else {
            // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
            unsafe { CStr::from_ptr(fmuGUID) }.to_string_lossy()
        };
        let inst = super::instantiate(&name, fmuType, &guid, log, loggingOn != fmi2False)?;
        let p = Box::into_raw(Box::new(inst)) as fmi2Component;
        with_registry(|r| r.instances.insert(p as usize));
        Some(p)
    }));
    made.ok().flatten().unwrap_or(std::ptr::null_mut())
}

/// # Safety
/// `c` is NULL or an instance from fmi2Instantiate. NULL, unknown and already freed
/// pointers are ignored.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    let orphans = unregister_instance(c);
    let Some(orphans) = orphans else {
        return; // NULL, unknown or already freed
    };
    for s in orphans {
        // SAFETY: registered states come from Box::into_raw and were just unregistered.
        drop(unsafe { Box::from_raw(s as *mut Core) });
    }
    // SAFETY: it was registered, so it came from Box::into_raw and is freed only here.
    let mut boxed = unsafe { Box::from_raw(c as *mut Instance) };
    let _ = catch_unwind(AssertUnwindSafe(move || {
        boxed.trace_free();
        drop(boxed)
    }));
}

// ----- lifecycle ------------------------------------------------------------------------------

/// # Safety
/// `c` is an instance from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    toleranceDefined: fmi2Boolean,
    tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2SetupExperiment", |inst| {
        inst.setup_experiment(
            (toleranceDefined != fmi2False).then_some(tolerance),
            startTime,
            (stopTimeDefined != fmi2False).then_some(stopTime),
        )
    })
}

/// # Safety
/// `c` is an instance from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2EnterInitializationMode", Instance::enter_initialization_mode)
}

/// # Safety
/// `c` is an instance from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2ExitInitializationMode", Instance::exit_initialization_mode)
}

/// # Safety
/// `c` is an instance from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2Terminate", Instance::terminate)
}

/// # Safety
/// `c` is an instance from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2Reset", Instance::reset)
}

// ----- get and set ----------------------------------------------------------------------------

/// The eight get and set functions, which share one shape: `$helper` ([`get_values`] or
/// [`set_values`]) checks the pointers and calls `$body` on the instance and the slices.
macro_rules! values_function {
    ($name:ident, $helper:ident, $ptr:ty, |$inst:ident, $vr:ident, $value:pat_param| $body:expr) => {
        /// # Safety
        /// `c` is an instance; `vr` and `value` hold `nvr` elements.
        #[no_mangle]
        pub unsafe extern "C" fn $name(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: $ptr,
        ) -> fmi2Status {
            // SAFETY: the function's contract is the helper's.
            unsafe {
                $helper(c, stringify!($name), vr, nvr, value, nvr, |$inst, $vr, $value| $body)
            }
        }
    };
}

values_function!(fmi2GetReal, get_values, *mut fmi2Real, |inst, vr, value| inst
    .get_real(vr, value));
values_function!(fmi2GetInteger, get_values, *mut fmi2Integer, |inst, vr, value| inst
    .get_integer(vr, value));
values_function!(fmi2GetBoolean, get_values, *mut fmi2Boolean, |inst, vr, value| {
    let mut flags = vec![false; vr.len()];
    let status = inst.get_boolean(vr, &mut flags);
    if status == Status::Ok {
        for (out, f) in value.iter_mut().zip(flags) {
            *out = if f { fmi2True } else { fmi2False };
        }
    }
    status
});
values_function!(fmi2GetString, get_values, *mut fmi2String, |inst, vr, _| inst.get_string(vr));
values_function!(fmi2SetReal, set_values, *const fmi2Real, |inst, vr, value| inst
    .set_real(vr, value));
values_function!(fmi2SetInteger, set_values, *const fmi2Integer, |inst, vr, value| inst
    .set_integer(vr, value));
values_function!(fmi2SetBoolean, set_values, *const fmi2Boolean, |inst, vr, value| {
    let flags: Vec<bool> = value.iter().map(|b| *b != fmi2False).collect();
    inst.set_boolean(vr, &flags)
});
values_function!(fmi2SetString, set_values, *const fmi2String, |inst, vr, _| inst.set_string(vr));

// ----- FMU state ------------------------------------------------------------------------------

/// # Safety
/// `c` is an instance; `state` points to NULL or to a state from this library.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    // SAFETY: the function's contract is the helper's.
    unsafe { states::get(c, "fmi2GetFMUstate", state) }
}

/// # Safety
/// `c` is an instance; `state` is a state from fmi2GetFMUstate or fmi2DeSerializeFMUstate.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    // SAFETY: the function's contract is the helper's.
    unsafe { states::set(c, "fmi2SetFMUstate", state) }
}

/// # Safety
/// `c` is an instance; `state` points to NULL or to a state from this library, which is
/// freed and set to NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    // SAFETY: the function's contract is the helper's.
    unsafe { states::free(c, "fmi2FreeFMUstate", state) }
}

/// # Safety
/// `c` is an instance; `state` a state from this library; `size` points to a usize.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    // SAFETY: the function's contract is the helper's.
    unsafe { states::serialized_size(c, "fmi2SerializedFMUstateSize", state, size) }
}

/// # Safety
/// `c` is an instance; `state` a state from this library; `serializedState` holds `size`
/// bytes.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    state: fmi2FMUstate,
    serializedState: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        states::serialize(c, "fmi2SerializeFMUstate", state, serializedState as *mut u8, size)
    }
}

/// # Safety
/// `c` is an instance; `serializedState` holds `size` bytes; `state` points to NULL or to a
/// state from this library.
#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    serializedState: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        states::deserialize(c, "fmi2DeSerializeFMUstate", serializedState as *const u8, size, state)
    }
}

/// # Safety
/// `c` is an instance; `vUnknown_ref` and `dvUnknown` hold `nUnknown` elements,
/// `vKnown_ref` and `dvKnown` `nKnown`. Model Exchange provides it; co-simulation logs that
/// it does not and returns fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    vUnknown_ref: *const fmi2ValueReference,
    nUnknown: usize,
    vKnown_ref: *const fmi2ValueReference,
    nKnown: usize,
    dvKnown: *const fmi2Real,
    dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetDirectionalDerivative";
    guard(c, F, |inst| {
        if inst.interface() == Interface::CoSimulation {
            return inst.get_directional_derivative();
        }
        // SAFETY: each pointer holds its count of elements (the function's contract).
        let args = unsafe {
            (
                slice(vUnknown_ref, nUnknown),
                slice(vKnown_ref, nKnown),
                slice(dvKnown, nKnown),
                slice_mut(dvUnknown, nUnknown),
            )
        };
        match args {
            (Some(u), Some(k), Some(dv), Some(out)) => {
                inst.get_directional_derivative_exchange(u, k, dv, out)
            }
            (None, ..) => null_arg(inst, F, "vUnknown_ref", nUnknown),
            (_, None, ..) => null_arg(inst, F, "vKnown_ref", nKnown),
            (_, _, None, _) => null_arg(inst, F, "dvKnown", nKnown),
            (.., None) => null_arg(inst, F, "dvUnknown", nUnknown),
        }
    })
}

// ----- Model Exchange -------------------------------------------------------------------------

/// # Safety
/// `c` is an instance from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2EnterEventMode", Instance::enter_event_mode)
}

/// # Safety
/// `c` is an instance; `eventInfo` points to an fmi2EventInfo.
#[no_mangle]
pub unsafe extern "C" fn fmi2NewDiscreteStates(
    c: fmi2Component,
    eventInfo: *mut fmi2EventInfo,
) -> fmi2Status {
    const F: &str = "fmi2NewDiscreteStates";
    guard(c, F, |inst| {
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(out) = (unsafe { eventInfo.as_mut() }) else {
            return null_arg(inst, F, "eventInfo", 1);
        };
        match inst.new_discrete_states() {
            Ok((info, status)) => {
                let flag = |b: bool| if b { fmi2True } else { fmi2False };
                *out = fmi2EventInfo {
                    newDiscreteStatesNeeded: flag(info.new_discrete_states_needed),
                    terminateSimulation: flag(info.terminate_simulation),
                    nominalsOfContinuousStatesChanged: flag(
                        info.nominals_of_continuous_states_changed,
                    ),
                    valuesOfContinuousStatesChanged: flag(info.values_of_continuous_states_changed),
                    nextEventTimeDefined: flag(info.next_event_time.is_some()),
                    nextEventTime: info.next_event_time.unwrap_or(0.0),
                };
                status
            }
            Err(status) => status,
        }
    })
}

/// # Safety
/// `c` is an instance from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2EnterContinuousTimeMode", Instance::enter_continuous_time_mode)
}

/// # Safety
/// `c` is an instance; the two flags point to fmi2Booleans.
#[no_mangle]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: fmi2Component,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
    enterEventMode: *mut fmi2Boolean,
    terminateSimulation: *mut fmi2Boolean,
) -> fmi2Status {
    const F: &str = "fmi2CompletedIntegratorStep";
    guard(c, F, |inst| {
        // SAFETY: the pointers are the host's, valid as the FMI function's contract says.
        let (Some(enter), Some(terminate)) =
            (unsafe { enterEventMode.as_mut() }, unsafe { terminateSimulation.as_mut() })
        else {
            let arg =
                if enterEventMode.is_null() { "enterEventMode" } else { "terminateSimulation" };
            return null_arg(inst, F, arg, 1);
        };
        match inst.completed_integrator_step() {
            Ok((end, status)) => {
                *enter = if end.enter_event_mode { fmi2True } else { fmi2False };
                *terminate = if end.terminate_simulation { fmi2True } else { fmi2False };
                status
            }
            Err(status) => status,
        }
    })
}

/// # Safety
/// `c` is an instance from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    guard(c, "fmi2SetTime", |inst| inst.set_time(time))
}

/// # Safety
/// `c` is an instance; `x` holds `nx` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetContinuousStates(
    c: fmi2Component,
    x: *const fmi2Real,
    nx: usize,
) -> fmi2Status {
    const F: &str = "fmi2SetContinuousStates";
    // SAFETY: `x` holds `nx` elements (the function's contract).
    guard(c, F, |inst| match unsafe { slice(x, nx) } {
        Some(x) => inst.set_continuous_states(x),
        None => null_arg(inst, F, "x", nx),
    })
}

/// The shape of the four Model Exchange functions that fill an array of `n` reals.
macro_rules! array_function {
    ($name:ident, $arg:literal, $method:ident) => {
        /// # Safety
        /// `c` is an instance; the array holds `n` elements.
        #[no_mangle]
        pub unsafe extern "C" fn $name(
            c: fmi2Component,
            values: *mut fmi2Real,
            n: usize,
        ) -> fmi2Status {
            // SAFETY: `values` holds `n` elements (the function's contract).
            guard(c, stringify!($name), |inst| match unsafe { slice_mut(values, n) } {
                Some(out) => inst.$method(out),
                None => null_arg(inst, stringify!($name), $arg, n),
            })
        }
    };
}

array_function!(fmi2GetDerivatives, "derivatives", get_derivatives);
array_function!(fmi2GetEventIndicators, "eventIndicators", get_event_indicators);
array_function!(fmi2GetContinuousStates, "x", get_continuous_states);
array_function!(fmi2GetNominalsOfContinuousStates, "x_nominal", get_nominals);

// ----- co-simulation --------------------------------------------------------------------------

/// # Safety
/// `c` is an instance; `vr`, `order` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2SetRealInputDerivatives";
    // SAFETY: each pointer holds `nvr` elements (the function's contract).
    guard(c, F, |inst| match unsafe { (slice(vr, nvr), slice(order, nvr), slice(value, nvr)) } {
        (Some(vr), Some(order), Some(value)) => inst.set_real_input_derivatives(vr, order, value),
        (None, _, _) => null_arg(inst, F, "vr", nvr),
        (_, None, _) => null_arg(inst, F, "order", nvr),
        (_, _, None) => null_arg(inst, F, "value", nvr),
    })
}

/// # Safety
/// `c` is an instance. Not provided (maxOutputDerivativeOrder = 0).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetRealOutputDerivatives";
    // SAFETY: each pointer holds `nvr` elements (the function's contract).
    guard(c, F, |inst| {
        match unsafe { (slice(vr, nvr), slice(order, nvr), slice_mut(value, nvr)) } {
            (Some(vr), Some(order), Some(value)) => {
                inst.get_real_output_derivatives(vr, order, value)
            }
            (None, _, _) => null_arg(inst, F, "vr", nvr),
            (_, None, _) => null_arg(inst, F, "order", nvr),
            (_, _, None) => null_arg(inst, F, "value", nvr),
        }
    })
}

/// # Safety
/// `c` is an instance from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    guard(c, "fmi2DoStep", |inst| inst.do_step(currentCommunicationPoint, communicationStepSize))
}

/// # Safety
/// `c` is an instance from fmi2Instantiate.
#[no_mangle]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2CancelStep", Instance::cancel_step)
}

/// # Safety
/// `c` is an instance; `value` points to an fmi2Status.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    _value: *mut fmi2Status,
) -> fmi2Status {
    guard(c, "fmi2GetStatus", |inst| inst.get_unprovided_status("GetStatus", s))
}

/// # Safety
/// `c` is an instance; `value` points to an fmi2Real.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2GetRealStatus", |inst| {
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(value) = (unsafe { value.as_mut() }) else {
            return null_arg(inst, "fmi2GetRealStatus", "value", 1);
        };
        match inst.get_real_status(s) {
            Ok(t) => {
                *value = t;
                Status::Ok
            }
            Err(status) => status,
        }
    })
}

/// # Safety
/// `c` is an instance; `value` points to an fmi2Integer.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    _value: *mut fmi2Integer,
) -> fmi2Status {
    guard(c, "fmi2GetIntegerStatus", |inst| inst.get_unprovided_status("GetIntegerStatus", s))
}

/// # Safety
/// `c` is an instance; `value` points to an fmi2Boolean.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    guard(c, "fmi2GetBooleanStatus", |inst| {
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(value) = (unsafe { value.as_mut() }) else {
            return null_arg(inst, "fmi2GetBooleanStatus", "value", 1);
        };
        match inst.get_boolean_status(s) {
            Ok(b) => {
                *value = if b { fmi2True } else { fmi2False };
                Status::Ok
            }
            Err(status) => status,
        }
    })
}

/// # Safety
/// `c` is an instance; `value` points to an fmi2String.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    _value: *mut fmi2String,
) -> fmi2Status {
    guard(c, "fmi2GetStringStatus", |inst| inst.get_unprovided_status("GetStringStatus", s))
}
