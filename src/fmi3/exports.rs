//! The 75 functions of the FMI 3.0 API (`fmi3Functions.h`), exported under their standard
//! names: common, Model Exchange, co-simulation, scheduled execution.
//!
//! As in FMI 2.0 (`fmi2/exports.rs`), each function finds the instance in the registry of
//! live ones, turns C pointers into slices, and calls the safe [`Instance`] method inside
//! the panic guard, which also refuses an instance made by fmi2Instantiate. The functions the
//! model does not provide return fmi3Error with a message that says why.
#![allow(non_snake_case)]
#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

use super::types::*;
use super::{CoSimulationArgs, Instance, NO_EVENT_MODE};
use crate::capi::guard::{guard, null_arg, slice, slice_mut, text};
use crate::capi::registry::{unregister_instance, with_registry};
use crate::capi::{states, Core};
use crate::fmi::{Interface, IntermediateUpdate, Logger, Status};
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::rc::Rc;

pub use super::cosim::*;
pub use super::exchange::*;
pub use super::values::*;

/// # Safety
/// None: returns a static string.
#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// # Safety
/// `instance` is an instance from fmi3Instantiate…; `categories` holds `nCategories` C
/// strings.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    loggingOn: fmi3Boolean,
    nCategories: usize,
    categories: *const fmi3String,
) -> fmi3Status {
    const F: &str = "fmi3SetDebugLogging";
    guard(instance, F, |inst| {
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(cats) = (unsafe { slice(categories, nCategories) }) else {
            return null_arg(inst, F, "categories", nCategories);
        };
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let names: Vec<Option<&str>> = cats.iter().map(|s| unsafe { text(*s) }).collect();
        inst.set_debug_logging(loggingOn != fmi3False, &names)
    })
}

// ----- creation and destruction ---------------------------------------------------------------

/// Wraps the host's logger: `logMessage(env, status, category, message)`. FMI 3.0 allows
/// NULL, which drops the messages.
fn host_logger(log: Option<fmi3LogMessageCallback>, env: fmi3InstanceEnvironment) -> Logger {
    let Some(log) = log else {
        return Box::new(|_, _, _| {});
    };
    let env = env as usize;
    Box::new(move |status: Status, category: &str, message: &str| {
        let category = CString::new(category.replace('\0', " ")).unwrap_or_default();
        let message = CString::new(message.replace('\0', " ")).unwrap_or_default();
        // SAFETY: the host promised a valid callback for the instance's lifetime.
        unsafe {
            log(
                env as fmi3InstanceEnvironment,
                status as fmi3Status,
                category.as_ptr(),
                message.as_ptr(),
            )
        }
    })
}

/// The host's intermediate-update callback, called with the FMU's time and whether the
/// model asks for its inputs there: the host may set the intermediate inputs and get
/// values; the FMU never returns early.
fn host_intermediate_update(
    callback: Option<fmi3IntermediateUpdateCallback>,
    env: fmi3InstanceEnvironment,
) -> Option<IntermediateUpdate> {
    let callback = callback?;
    let env = env as usize;
    Some(Rc::new(move |t: f64, set_requested: bool| {
        let mut early: fmi3Boolean = fmi3False;
        let mut early_time: fmi3Float64 = t;
        // SAFETY: the host promised a valid callback for the instance's lifetime; the two
        // out-arguments are ours.
        unsafe {
            callback(
                env as fmi3InstanceEnvironment,
                t,
                fmi3Boolean::from(set_requested),
                fmi3True,  // intermediateVariableGetAllowed
                fmi3True,  // intermediateStepFinished
                fmi3False, // canReturnEarly
                &mut early,
                &mut early_time,
            )
        }
    }))
}

/// The common part of the instantiate functions: the strings, the instance, its
/// registration. NULL, after logging why, on any failure.
///
/// # Safety
/// Strings are NULL or NUL-terminated.
unsafe fn instantiate(
    interface: Interface,
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    loggingOn: fmi3Boolean,
    mut log: Logger,
    cs: Option<CoSimulationArgs>,
) -> fmi3Instance {
    let made = catch_unwind(AssertUnwindSafe(|| {
        let func = match interface {
            Interface::CoSimulation => "fmi3InstantiateCoSimulation",
            Interface::ModelExchange => "fmi3InstantiateModelExchange",
        };
        if instanceName.is_null() {
            log(Status::Error, "logStatusError", &format!("{func}: instanceName is NULL"));
            return None;
        }
        // SAFETY: non-NULL, and the host's NUL-terminated string.
        let name = unsafe { CStr::from_ptr(instanceName) }.to_string_lossy().into_owned();
        let token = if instantiationToken.is_null() {
            "(null)".into()
        } else {
            // SAFETY: non-NULL, and the host's NUL-terminated string.
            unsafe { CStr::from_ptr(instantiationToken) }.to_string_lossy()
        };
        let inst = super::instantiate(&name, interface, &token, log, loggingOn != fmi3False, cs)?;
        let p = Box::into_raw(Box::new(inst)) as fmi3Instance;
        with_registry(|r| r.instances.insert(p as usize));
        Some(p)
    }));
    made.ok().flatten().unwrap_or(std::ptr::null_mut())
}

/// # Safety
/// Strings are NULL or NUL-terminated; `logMessage` is NULL or valid for the instance's
/// lifetime.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: Option<fmi3LogMessageCallback>,
) -> fmi3Instance {
    let log = host_logger(logMessage, instanceEnvironment);
    // SAFETY: the strings are the host's, as the function's contract says.
    unsafe {
        instantiate(
            Interface::ModelExchange,
            instanceName,
            instantiationToken,
            loggingOn,
            log,
            None,
        )
    }
}

/// # Safety
/// Strings are NULL or NUL-terminated; `requiredIntermediateVariables` holds
/// `nRequiredIntermediateVariables` value references; the callbacks are NULL or valid for
/// the instance's lifetime.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    eventModeUsed: fmi3Boolean,
    _earlyReturnAllowed: fmi3Boolean,
    requiredIntermediateVariables: *const fmi3ValueReference,
    nRequiredIntermediateVariables: usize,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: Option<fmi3LogMessageCallback>,
    intermediateUpdate: Option<fmi3IntermediateUpdateCallback>,
) -> fmi3Instance {
    let mut log = host_logger(logMessage, instanceEnvironment);
    // SAFETY: the array is the host's, valid as the function's contract says.
    let Some(required) =
        (unsafe { slice(requiredIntermediateVariables, nRequiredIntermediateVariables) })
    else {
        let msg = format!(
            "fmi3InstantiateCoSimulation: argument `requiredIntermediateVariables` is NULL \
             (or misaligned) with {nRequiredIntermediateVariables} elements"
        );
        log(Status::Error, "logStatusError", &msg);
        return std::ptr::null_mut();
    };
    let cs = CoSimulationArgs {
        event_mode_used: eventModeUsed != fmi3False,
        required,
        intermediate_update: host_intermediate_update(intermediateUpdate, instanceEnvironment),
    };
    // SAFETY: the strings are the host's, as the function's contract says.
    unsafe {
        instantiate(
            Interface::CoSimulation,
            instanceName,
            instantiationToken,
            loggingOn,
            log,
            Some(cs),
        )
    }
}

/// # Safety
/// `logMessage` is NULL or a valid callback. Scheduled execution is not provided: NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _instanceName: fmi3String,
    _instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    _loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: Option<fmi3LogMessageCallback>,
    _clockUpdate: Option<fmi3ClockUpdateCallback>,
    _lockPreemption: Option<fmi3PreemptionCallback>,
    _unlockPreemption: Option<fmi3PreemptionCallback>,
) -> fmi3Instance {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        let mut log = host_logger(logMessage, instanceEnvironment);
        log(
            Status::Error,
            "logStatusError",
            "fmi3InstantiateScheduledExecution: not provided: the model description declares \
             Model Exchange and co-simulation only",
        );
    }));
    std::ptr::null_mut()
}

/// # Safety
/// `instance` is NULL or an instance from fmi3Instantiate…. NULL, unknown and already freed
/// pointers are ignored.
#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    let Some(orphans) = unregister_instance(instance) else {
        return; // NULL, unknown or already freed
    };
    for s in orphans {
        // SAFETY: registered states come from Box::into_raw and were just unregistered.
        drop(unsafe { Box::from_raw(s as *mut Core) });
    }
    // SAFETY: it was registered, so it came from Box::into_raw and is freed only here.
    let mut boxed = unsafe { Box::from_raw(instance as *mut Instance) };
    let _ = catch_unwind(AssertUnwindSafe(move || {
        boxed.trace_free();
        drop(boxed)
    }));
}

// ----- lifecycle ------------------------------------------------------------------------------

/// # Safety
/// `instance` is an instance from fmi3Instantiate….
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    toleranceDefined: fmi3Boolean,
    tolerance: fmi3Float64,
    startTime: fmi3Float64,
    stopTimeDefined: fmi3Boolean,
    stopTime: fmi3Float64,
) -> fmi3Status {
    guard(instance, "fmi3EnterInitializationMode", |inst| {
        inst.enter_initialization_mode_with(
            (toleranceDefined != fmi3False).then_some(tolerance),
            startTime,
            (stopTimeDefined != fmi3False).then_some(stopTime),
        )
    })
}

/// # Safety
/// `instance` is an instance from fmi3Instantiate….
#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    guard(instance, "fmi3ExitInitializationMode", Instance::exit_initialization_mode)
}

/// # Safety
/// `instance` is an instance from fmi3Instantiate….
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterEventMode(instance: fmi3Instance) -> fmi3Status {
    guard(instance, "fmi3EnterEventMode", |inst| match inst.interface() {
        Interface::ModelExchange => inst.enter_event_mode(),
        Interface::CoSimulation => inst.unsupported("EnterEventMode", NO_EVENT_MODE),
    })
}

/// # Safety
/// `instance` is an instance from fmi3Instantiate….
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    guard(instance, "fmi3EnterConfigurationMode", Instance::enter_configuration_mode)
}

/// # Safety
/// `instance` is an instance from fmi3Instantiate….
#[no_mangle]
pub unsafe extern "C" fn fmi3ExitConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    guard(instance, "fmi3ExitConfigurationMode", Instance::exit_configuration_mode)
}

/// # Safety
/// `instance` is an instance from fmi3Instantiate….
#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    guard(instance, "fmi3Terminate", Instance::terminate)
}

/// # Safety
/// `instance` is an instance from fmi3Instantiate….
#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    guard(instance, "fmi3Reset", Instance::reset)
}

// ----- what the model does not provide --------------------------------------------------------

/// Functions the model does not provide, with why: each returns fmi3Error and logs that.
macro_rules! unsupported {
    ($($name:ident($($arg:ident: $ty:ty),*) => $why:expr;)*) => {$(
        /// # Safety
        /// `instance` is an instance from fmi3Instantiate…; the other arguments are not read.
        #[no_mangle]
        pub unsafe extern "C" fn $name(instance: fmi3Instance, $($arg: $ty),*) -> fmi3Status {
            $(let _ = $arg;)*
            guard(instance, stringify!($name), |inst| {
                inst.unsupported(&stringify!($name)[4..], $why)
            })
        }
    )*};
}

const NO_CLOCKS: &str = "the model has no clocks";

unsupported! {
    fmi3GetNumberOfVariableDependencies(_vr: fmi3ValueReference, _n: *mut usize) =>
        "variable dependencies are not provided; <ModelStructure> lists no dependencies, so \
         every unknown may depend on every known";
    fmi3GetVariableDependencies(
        _dependent: fmi3ValueReference,
        _element_indices_of_dependent: *mut usize,
        _independents: *mut fmi3ValueReference,
        _element_indices_of_independents: *mut usize,
        _kinds: *mut fmi3DependencyKind,
        _n: usize
    ) => "variable dependencies are not provided; <ModelStructure> lists no dependencies, so \
          every unknown may depend on every known";
    fmi3GetAdjointDerivative(
        _unknowns: *const fmi3ValueReference,
        _n_unknowns: usize,
        _knowns: *const fmi3ValueReference,
        _n_knowns: usize,
        _seed: *const fmi3Float64,
        _n_seed: usize,
        _sensitivity: *mut fmi3Float64,
        _n_sensitivity: usize
    ) => "providesAdjointDerivatives = false";
    fmi3GetIntervalDecimal(
        _vr: *const fmi3ValueReference, _n: usize, _intervals: *mut fmi3Float64,
        _qualifiers: *mut fmi3IntervalQualifier
    ) => NO_CLOCKS;
    fmi3GetIntervalFraction(
        _vr: *const fmi3ValueReference, _n: usize, _counters: *mut fmi3UInt64,
        _resolutions: *mut fmi3UInt64, _qualifiers: *mut fmi3IntervalQualifier
    ) => NO_CLOCKS;
    fmi3GetShiftDecimal(_vr: *const fmi3ValueReference, _n: usize, _shifts: *mut fmi3Float64)
        => NO_CLOCKS;
    fmi3GetShiftFraction(
        _vr: *const fmi3ValueReference, _n: usize, _counters: *mut fmi3UInt64,
        _resolutions: *mut fmi3UInt64
    ) => NO_CLOCKS;
    fmi3SetIntervalDecimal(
        _vr: *const fmi3ValueReference, _n: usize, _intervals: *const fmi3Float64
    ) => NO_CLOCKS;
    fmi3SetIntervalFraction(
        _vr: *const fmi3ValueReference, _n: usize, _counters: *const fmi3UInt64,
        _resolutions: *const fmi3UInt64
    ) => NO_CLOCKS;
    fmi3SetShiftDecimal(_vr: *const fmi3ValueReference, _n: usize, _shifts: *const fmi3Float64)
        => NO_CLOCKS;
    fmi3SetShiftFraction(
        _vr: *const fmi3ValueReference, _n: usize, _counters: *const fmi3UInt64,
        _resolutions: *const fmi3UInt64
    ) => NO_CLOCKS;
    fmi3EvaluateDiscreteStates() => "providesEvaluateDiscreteStates = false: the model has no \
        discrete states";
    fmi3ActivateModelPartition(_clock: fmi3ValueReference, _t: fmi3Float64) =>
        "scheduled execution is not provided";
}

// ----- FMU state ------------------------------------------------------------------------------

/// # Safety
/// `instance` is an instance; `state` points to NULL or to a state from this library.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFMUState(
    instance: fmi3Instance,
    state: *mut fmi3FMUState,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe { states::get(instance, "fmi3GetFMUState", state) }
}

/// # Safety
/// `instance` is an instance; `state` is a state from this library.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFMUState(
    instance: fmi3Instance,
    state: fmi3FMUState,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe { states::set(instance, "fmi3SetFMUState", state) }
}

/// # Safety
/// `instance` is an instance; `state` points to NULL or to a state from this library, which
/// is freed and set to NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi3FreeFMUState(
    instance: fmi3Instance,
    state: *mut fmi3FMUState,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe { states::free(instance, "fmi3FreeFMUState", state) }
}

/// # Safety
/// `instance` is an instance; `state` a state from this library; `size` points to a usize.
#[no_mangle]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: fmi3Instance,
    state: fmi3FMUState,
    size: *mut usize,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe { states::serialized_size(instance, "fmi3SerializedFMUStateSize", state, size) }
}

/// # Safety
/// `instance` is an instance; `state` a state from this library; `serializedState` holds
/// `size` bytes.
#[no_mangle]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: fmi3Instance,
    state: fmi3FMUState,
    serializedState: *mut fmi3Byte,
    size: usize,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe { states::serialize(instance, "fmi3SerializeFMUState", state, serializedState, size) }
}

/// # Safety
/// `instance` is an instance; `serializedState` holds `size` bytes; `state` points to NULL
/// or to a state from this library.
#[no_mangle]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: fmi3Instance,
    serializedState: *const fmi3Byte,
    size: usize,
    state: *mut fmi3FMUState,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        states::deserialize(instance, "fmi3DeserializeFMUState", serializedState, size, state)
    }
}

/// # Safety
/// `instance` is an instance; `unknowns` and `sensitivity` hold `nUnknowns` elements,
/// `knowns` and `seed` `nKnowns` (every variable is a scalar: nSeed = nKnowns,
/// nSensitivity = nUnknowns). Model Exchange provides it; co-simulation logs that it does
/// not and returns fmi3Error.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    nUnknowns: usize,
    knowns: *const fmi3ValueReference,
    nKnowns: usize,
    seed: *const fmi3Float64,
    nSeed: usize,
    sensitivity: *mut fmi3Float64,
    nSensitivity: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetDirectionalDerivative";
    guard(instance, F, |inst| {
        if inst.interface() == Interface::CoSimulation {
            return inst.get_directional_derivative();
        }
        // SAFETY: each pointer holds its count of elements (the function's contract); an
        // array's elements all count in nSeed and nSensitivity, which the model checks.
        let args = unsafe {
            (
                slice(unknowns, nUnknowns),
                slice(knowns, nKnowns),
                slice(seed, nSeed),
                slice_mut(sensitivity, nSensitivity),
            )
        };
        match args {
            (Some(u), Some(k), Some(dv), Some(out)) => {
                inst.get_directional_derivative_exchange(u, k, dv, out)
            }
            (None, ..) => null_arg(inst, F, "unknowns", nUnknowns),
            (_, None, ..) => null_arg(inst, F, "knowns", nKnowns),
            (_, _, None, _) => null_arg(inst, F, "seed", nSeed),
            (.., None) => null_arg(inst, F, "sensitivity", nSensitivity),
        }
    })
}
