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
use super::{CoSimulationArgs, Instance};
use crate::capi::guard::{
    get_values, guard, null_arg, set_values, slice, slice_mut, status_of, text,
};
use crate::capi::registry::{unregister_instance, with_registry};
use crate::capi::{states, Core};
use crate::fmi::description::BaseType;
use crate::fmi::{Interface, IntermediateUpdate, Logger, Status};
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::rc::Rc;

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

/// Co-simulation has no event mode (hasEventMode = false): its event calls are refused.
const NO_EVENT_MODE: &str = "this FMU's co-simulation has no event mode (hasEventMode = \
    false); it is a Model Exchange function here";

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

// ----- get and set ----------------------------------------------------------------------------

/// The get and set functions: `$helper` ([`get_values`] or [`set_values`]) checks the
/// pointers and calls `$body` on the instance, the value references and the `nValues`
/// values (an array's elements all count; the core checks that they add up).
macro_rules! values_function {
    ($name:ident, $helper:ident, $ptr:ty, |$inst:ident, $vr:ident, $value:pat_param| $body:expr) => {
        /// # Safety
        /// `instance` is an instance; `valueReferences` holds `nValueReferences` elements and
        /// `values` `nValues`.
        #[no_mangle]
        pub unsafe extern "C" fn $name(
            instance: fmi3Instance,
            valueReferences: *const fmi3ValueReference,
            nValueReferences: usize,
            values: $ptr,
            nValues: usize,
        ) -> fmi3Status {
            // SAFETY: each pointer holds its count of elements (the function's contract).
            unsafe {
                $helper(
                    instance,
                    stringify!($name),
                    valueReferences,
                    nValueReferences,
                    values,
                    nValues,
                    |$inst, $vr, $value| $body,
                )
            }
        }
    };
}

values_function!(fmi3GetFloat64, get_values, *mut fmi3Float64, |inst, vr, value| inst
    .get_real(vr, value));
values_function!(fmi3SetFloat64, set_values, *const fmi3Float64, |inst, vr, value| inst
    .set_real(vr, value));
values_function!(fmi3GetInt32, get_values, *mut fmi3Int32, |inst, vr, value| inst
    .get_integer(vr, value));
values_function!(fmi3SetInt32, set_values, *const fmi3Int32, |inst, vr, value| inst
    .set_integer(vr, value));
// The enumerations: Int64 in FMI 3.0 (their items are 1..=k; the model's range check refuses
// any other value, naming the variable and the value).
values_function!(fmi3GetInt64, get_values, *mut fmi3Int64, |inst, vr, value| inst.get(
    "GetInt64",
    BaseType::Int64,
    vr,
    value,
    |v| v.integer() as i64
));
values_function!(fmi3SetInt64, set_values, *const fmi3Int64, |inst, vr, value| inst.set(
    "SetInt64",
    BaseType::Int64,
    vr,
    value,
    |v: i64| crate::fmi::Value::Integer(v.into())
));
// The structural parameter n_elements: UInt64 in FMI 3.0 (a <Dimension> refers to one); the
// model's range check refuses a value beyond its range, naming it.
values_function!(fmi3GetUInt64, get_values, *mut fmi3UInt64, |inst, vr, value| inst.get(
    "GetUInt64",
    BaseType::UInt64,
    vr,
    value,
    |v| v.integer().max(0) as u64
));
values_function!(fmi3SetUInt64, set_values, *const fmi3UInt64, |inst, vr, value| inst.set(
    "SetUInt64",
    BaseType::UInt64,
    vr,
    value,
    |v: u64| crate::fmi::Value::Integer(v.into())
));
values_function!(fmi3GetBoolean, get_values, *mut fmi3Boolean, |inst, vr, value| {
    // As many as nValues: the core checks that they are the value references' count.
    let mut flags = vec![false; value.len()];
    let status = inst.get_boolean(vr, &mut flags);
    if status == Status::Ok {
        for (out, f) in value.iter_mut().zip(flags) {
            *out = if f { fmi3True } else { fmi3False };
        }
    }
    status
});
values_function!(fmi3SetBoolean, set_values, *const fmi3Boolean, |inst, vr, value| {
    let flags: Vec<bool> = value.iter().map(|b| *b != fmi3False).collect();
    inst.set_boolean(vr, &flags)
});

/// The get and set functions of the types the model has no variables of: any value
/// reference is refused, naming its variable's type.
macro_rules! no_variables {
    ($($get:ident, $set:ident, $ty:ty, $base:ident;)*) => {$(
        values_function!($get, get_values, *mut $ty, |inst, vr, _| inst.no_variables(
            &stringify!($get)[4..],
            BaseType::$base,
            false,
            vr
        ));
        values_function!($set, set_values, *const $ty, |inst, vr, _| inst.no_variables(
            &stringify!($set)[4..],
            BaseType::$base,
            true,
            vr
        ));
    )*};
}

no_variables! {
    fmi3GetFloat32, fmi3SetFloat32, fmi3Float32, Float32;
    fmi3GetInt8, fmi3SetInt8, fmi3Int8, Int8;
    fmi3GetUInt8, fmi3SetUInt8, fmi3UInt8, UInt8;
    fmi3GetInt16, fmi3SetInt16, fmi3Int16, Int16;
    fmi3GetUInt16, fmi3SetUInt16, fmi3UInt16, UInt16;
    fmi3GetUInt32, fmi3SetUInt32, fmi3UInt32, UInt32;
    fmi3GetString, fmi3SetString, fmi3String, String;
}

/// # Safety
/// `instance` is an instance; `valueReferences` holds `nValueReferences` elements, and
/// `valueSizes` and `values` `nValues`.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    _valueSizes: *mut usize,
    values: *mut fmi3Binary,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        get_values(
            instance,
            "fmi3GetBinary",
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |i, vr, _| i.no_variables("GetBinary", BaseType::Binary, false, vr),
        )
    }
}

/// # Safety
/// `instance` is an instance; `valueReferences` holds `nValueReferences` elements, and
/// `valueSizes` and `values` `nValues`.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    _valueSizes: *const usize,
    values: *const fmi3Binary,
    nValues: usize,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        set_values(
            instance,
            "fmi3SetBinary",
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |i, vr, _| i.no_variables("SetBinary", BaseType::Binary, true, vr),
        )
    }
}

/// # Safety
/// `instance` is an instance; `valueReferences` and `values` hold `nValueReferences`
/// elements.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetClock(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Clock,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        get_values(
            instance,
            "fmi3GetClock",
            valueReferences,
            nValueReferences,
            values,
            nValueReferences,
            |i, vr, _| i.no_variables("GetClock", BaseType::Clock, false, vr),
        )
    }
}

/// # Safety
/// `instance` is an instance; `valueReferences` and `values` hold `nValueReferences`
/// elements.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetClock(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Clock,
) -> fmi3Status {
    // SAFETY: the function's contract is the helper's.
    unsafe {
        set_values(
            instance,
            "fmi3SetClock",
            valueReferences,
            nValueReferences,
            values,
            nValueReferences,
            |i, vr, _| i.no_variables("SetClock", BaseType::Clock, true, vr),
        )
    }
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

// ----- Model Exchange -------------------------------------------------------------------------

/// Writes a flag through a host's pointer.
fn flag(b: bool) -> fmi3Boolean {
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

// ----- co-simulation --------------------------------------------------------------------------

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
