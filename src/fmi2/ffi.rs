//! The 34 functions of the FMI 2.0 common and co-simulation API, exported under their
//! standard names. This is the only `unsafe` code in the crate.
//!
//! Each function does three things: it checks the instance pointer against the registry of
//! live instances, turns C pointers into slices and strings (NULL only where the count is
//! 0), and calls the safe [`Instance`] method inside [`guard`], which catches any panic so
//! that nothing unwinds into the host. A caught panic makes the instance fatal.
//!
//! Types are written by hand from `fmi2TypesPlatform.h` and `fmi2FunctionTypes.h`
//! (FMI 2.0.4): a dozen type aliases and one struct do not justify bindgen and libclang
//! (ARCHITECTURE.md, "Dependencies").
#![allow(non_snake_case, non_camel_case_types, non_upper_case_globals)]

use super::instance::{Core, Instance, Logger, Status};
use std::collections::HashSet;
use std::ffi::{c_char, c_int, c_uint, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Mutex, MutexGuard};

pub type fmi2Component = *mut c_void;
pub type fmi2ComponentEnvironment = *mut c_void;
pub type fmi2FMUstate = *mut c_void;
pub type fmi2ValueReference = c_uint;
pub type fmi2Real = f64;
pub type fmi2Integer = c_int;
pub type fmi2Boolean = c_int;
pub type fmi2Char = c_char;
pub type fmi2String = *const fmi2Char;
pub type fmi2Byte = c_char;
pub type fmi2Status = c_int;
pub type fmi2Type = c_int;
pub type fmi2StatusKind = c_int;

pub const fmi2True: fmi2Boolean = 1;
pub const fmi2False: fmi2Boolean = 0;

/// fmi2CallbackLogger: printf-like; we always pass `"%s"` and the message.
pub type fmi2CallbackLogger = unsafe extern "C" fn(
    fmi2ComponentEnvironment,
    fmi2String,
    fmi2Status,
    fmi2String,
    fmi2String,
    ...
);

/// fmi2CallbackFunctions. The memory functions are never called
/// (canNotUseMemoryManagementFunctions = true).
#[repr(C)]
pub struct fmi2CallbackFunctions {
    pub logger: Option<fmi2CallbackLogger>,
    pub allocateMemory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    pub freeMemory: Option<unsafe extern "C" fn(*mut c_void)>,
    pub stepFinished: Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>,
    pub componentEnvironment: fmi2ComponentEnvironment,
}

// ----- registry of live instances and FMU states ---------------------------------------------

/// Addresses of the instances and FMU states this library handed out and has not freed.
/// A pointer not in it (freed twice, foreign, garbage) is refused instead of dereferenced.
struct Registry {
    instances: HashSet<usize>,
    states: HashSet<usize>,
}

static REGISTRY: Mutex<Option<Registry>> = Mutex::new(None);

fn registry() -> MutexGuard<'static, Option<Registry>> {
    // No code panics while holding the lock, so poisoning can only come from outside; the
    // sets stay consistent either way.
    let mut guard = REGISTRY.lock().unwrap_or_else(|e| e.into_inner());
    guard.get_or_insert_with(|| Registry { instances: HashSet::new(), states: HashSet::new() });
    guard
}

fn with_registry<T>(f: impl FnOnce(&mut Registry) -> T) -> T {
    f(registry().as_mut().expect("initialised by registry()"))
}

/// The instance behind `c`, if `c` is a live instance of this library.
///
/// # Safety
/// The host must not use the same instance from two threads at once (FMI 2.0 §2.1.1).
unsafe fn instance<'a>(c: fmi2Component) -> Option<&'a mut Instance> {
    if c.is_null() || !with_registry(|r| r.instances.contains(&(c as usize))) {
        return None;
    }
    // SAFETY: registered pointers come from Box::into_raw in fmi2Instantiate and are removed
    // before fmi2FreeInstance drops them.
    Some(&mut *(c as *mut Instance))
}

/// The snapshot behind `s`, if `s` is a live FMU state of this library.
unsafe fn snapshot<'a>(s: fmi2FMUstate) -> Option<&'a mut Core> {
    if s.is_null() || !with_registry(|r| r.states.contains(&(s as usize))) {
        return None;
    }
    // SAFETY: registered pointers come from Box::into_raw in this module.
    Some(&mut *(s as *mut Core))
}

fn register_state(core: Box<Core>) -> fmi2FMUstate {
    let p = Box::into_raw(core) as fmi2FMUstate;
    with_registry(|r| r.states.insert(p as usize));
    p
}

// ----- the panic guard and pointer helpers ----------------------------------------------------

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_string()
    }
}

/// Runs `body` on the instance behind `c`. NULL or unknown `c` gives fmi2Error (there is no
/// logger to tell). A panic is caught, logged, and makes the instance fatal.
fn guard(c: fmi2Component, func: &str, body: impl FnOnce(&mut Instance) -> Status) -> fmi2Status {
    // SAFETY: see `instance`.
    let Some(inst) = (unsafe { instance(c) }) else {
        return Status::Error as fmi2Status;
    };
    match catch_unwind(AssertUnwindSafe(|| body(inst))) {
        Ok(status) => status as fmi2Status,
        Err(payload) => {
            let msg = format!("{func}: internal error (panic): {}", panic_text(&*payload));
            let _ = catch_unwind(AssertUnwindSafe(|| {
                // SAFETY: the borrow inside `body` ended with the unwind.
                if let Some(inst) = unsafe { instance(c) } {
                    inst.set_fatal(&msg);
                }
            }));
            Status::Fatal as fmi2Status
        }
    }
}

/// `n` elements at `p`: an empty slice when `n` is 0 (whatever `p`), `None` for NULL or a
/// misaligned pointer.
///
/// # Safety
/// A non-NULL `p` must point to `n` valid elements, as the FMI caller guarantees.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        return Some(&[]);
    }
    if p.is_null() || !p.is_aligned() || n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return None;
    }
    Some(std::slice::from_raw_parts(p, n))
}

/// Mutable counterpart of [`slice`].
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        return Some(&mut []);
    }
    if p.is_null() || !p.is_aligned() || n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return None;
    }
    Some(std::slice::from_raw_parts_mut(p, n))
}

/// A C string as UTF-8; `None` for NULL or invalid UTF-8.
unsafe fn text<'a>(s: fmi2String) -> Option<&'a str> {
    if s.is_null() {
        return None;
    }
    CStr::from_ptr(s).to_str().ok()
}

fn null_arg(inst: &mut Instance, func: &str, arg: &str, n: usize) -> Status {
    inst.log(
        Status::Error,
        &format!("{func}: argument `{arg}` is NULL (or misaligned) with {n} elements"),
    );
    Status::Error
}

// ----- version and logging --------------------------------------------------------------------

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
        let Some(cats) = slice(categories, nCategories) else {
            return null_arg(inst, "fmi2SetDebugLogging", "categories", nCategories);
        };
        let names: Vec<Option<&str>> = cats.iter().map(|s| text(*s)).collect();
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
        let functions = functions.as_ref()?;
        let name = if instanceName.is_null() {
            None
        } else {
            Some(CStr::from_ptr(instanceName).to_string_lossy().into_owned())
        };
        let mut log = host_logger(functions, name.as_deref().unwrap_or("(null)"))?;
        let Some(name) = name else {
            log(Status::Error, "logStatusError", "fmi2Instantiate: instanceName is NULL");
            return None;
        };
        let guid = if fmuGUID.is_null() {
            "(null)".into()
        } else {
            CStr::from_ptr(fmuGUID).to_string_lossy()
        };
        let inst = Instance::instantiate(&name, fmuType, &guid, log, loggingOn != fmi2False)?;
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
    if c.is_null() || !with_registry(|r| r.instances.remove(&(c as usize))) {
        return;
    }
    // SAFETY: it was registered, so it came from Box::into_raw and is freed only here.
    let boxed = Box::from_raw(c as *mut Instance);
    let _ = catch_unwind(AssertUnwindSafe(move || drop(boxed)));
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

/// # Safety
/// `c` is an instance; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2GetReal", |inst| match (slice(vr, nvr), slice_mut(value, nvr)) {
        (Some(vr), Some(value)) => inst.get_real(vr, value),
        (None, _) => null_arg(inst, "fmi2GetReal", "vr", nvr),
        (_, None) => null_arg(inst, "fmi2GetReal", "value", nvr),
    })
}

/// # Safety
/// `c` is an instance; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    guard(c, "fmi2GetInteger", |inst| match (slice(vr, nvr), slice_mut(value, nvr)) {
        (Some(vr), Some(value)) => inst.get_integer(vr, value),
        (None, _) => null_arg(inst, "fmi2GetInteger", "vr", nvr),
        (_, None) => null_arg(inst, "fmi2GetInteger", "value", nvr),
    })
}

/// # Safety
/// `c` is an instance; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    guard(c, "fmi2GetBoolean", |inst| match (slice(vr, nvr), slice_mut(value, nvr)) {
        (Some(vr), Some(value)) => {
            let mut flags = vec![false; vr.len()];
            let status = inst.get_boolean(vr, &mut flags);
            if status == Status::Ok {
                for (out, f) in value.iter_mut().zip(flags) {
                    *out = if f { fmi2True } else { fmi2False };
                }
            }
            status
        }
        (None, _) => null_arg(inst, "fmi2GetBoolean", "vr", nvr),
        (_, None) => null_arg(inst, "fmi2GetBoolean", "value", nvr),
    })
}

/// # Safety
/// `c` is an instance; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    guard(c, "fmi2GetString", |inst| match (slice(vr, nvr), slice_mut(value, nvr)) {
        (Some(vr), Some(_)) => inst.get_string(vr),
        (None, _) => null_arg(inst, "fmi2GetString", "vr", nvr),
        (_, None) => null_arg(inst, "fmi2GetString", "value", nvr),
    })
}

/// # Safety
/// `c` is an instance; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2SetReal", |inst| match (slice(vr, nvr), slice(value, nvr)) {
        (Some(vr), Some(value)) => inst.set_real(vr, value),
        (None, _) => null_arg(inst, "fmi2SetReal", "vr", nvr),
        (_, None) => null_arg(inst, "fmi2SetReal", "value", nvr),
    })
}

/// # Safety
/// `c` is an instance; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    guard(c, "fmi2SetInteger", |inst| match (slice(vr, nvr), slice(value, nvr)) {
        (Some(vr), Some(value)) => inst.set_integer(vr, value),
        (None, _) => null_arg(inst, "fmi2SetInteger", "vr", nvr),
        (_, None) => null_arg(inst, "fmi2SetInteger", "value", nvr),
    })
}

/// # Safety
/// `c` is an instance; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    guard(c, "fmi2SetBoolean", |inst| match (slice(vr, nvr), slice(value, nvr)) {
        (Some(vr), Some(value)) => {
            let flags: Vec<bool> = value.iter().map(|b| *b != fmi2False).collect();
            inst.set_boolean(vr, &flags)
        }
        (None, _) => null_arg(inst, "fmi2SetBoolean", "vr", nvr),
        (_, None) => null_arg(inst, "fmi2SetBoolean", "value", nvr),
    })
}

/// # Safety
/// `c` is an instance; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    guard(c, "fmi2SetString", |inst| match (slice(vr, nvr), slice(value, nvr)) {
        (Some(vr), Some(_)) => inst.set_string(vr),
        (None, _) => null_arg(inst, "fmi2SetString", "vr", nvr),
        (_, None) => null_arg(inst, "fmi2SetString", "value", nvr),
    })
}

// ----- FMU state ------------------------------------------------------------------------------

/// # Safety
/// `c` is an instance; `state` points to NULL or to a state from this library.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    guard(c, "fmi2GetFMUstate", |inst| {
        let Some(slot) = state.as_mut() else {
            return null_arg(inst, "fmi2GetFMUstate", "FMUstate", 1);
        };
        if slot.is_null() {
            return match inst.get_state() {
                Ok(core) => {
                    *slot = register_state(core);
                    Status::Ok
                }
                Err(status) => status,
            };
        }
        match snapshot(*slot) {
            Some(existing) => inst.get_state_into(existing),
            None => unknown_state(inst, "fmi2GetFMUstate"),
        }
    })
}

fn unknown_state(inst: &mut Instance, func: &str) -> Status {
    inst.log(Status::Error, &format!("{func}: the FMU state is NULL, freed, or not from this FMU"));
    Status::Error
}

/// # Safety
/// `c` is an instance; `state` is a state from fmi2GetFMUstate or fmi2DeSerializeFMUstate.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    guard(c, "fmi2SetFMUstate", |inst| match snapshot(state) {
        Some(core) => inst.set_state(core),
        None => unknown_state(inst, "fmi2SetFMUstate"),
    })
}

/// # Safety
/// `c` is an instance; `state` points to NULL or to a state from this library, which is
/// freed and set to NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    guard(c, "fmi2FreeFMUstate", |inst| {
        let Some(slot) = state.as_mut() else {
            return null_arg(inst, "fmi2FreeFMUstate", "FMUstate", 1);
        };
        if slot.is_null() {
            return Status::Ok; // nothing to free
        }
        let status = inst.check_free_state();
        if status != Status::Ok {
            return status;
        }
        if !with_registry(|r| r.states.remove(&(*slot as usize))) {
            return unknown_state(inst, "fmi2FreeFMUstate");
        }
        // SAFETY: it was registered, so it came from Box::into_raw and is freed only here.
        drop(Box::from_raw(*slot as *mut Core));
        *slot = std::ptr::null_mut();
        Status::Ok
    })
}

/// # Safety
/// `c` is an instance; `state` a state from this library; `size` points to a usize.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    guard(c, "fmi2SerializedFMUstateSize", |inst| {
        let Some(size) = size.as_mut() else {
            return null_arg(inst, "fmi2SerializedFMUstateSize", "size", 1);
        };
        let Some(core) = snapshot(state) else {
            return unknown_state(inst, "fmi2SerializedFMUstateSize");
        };
        match inst.serialized_size(core) {
            Ok(n) => {
                *size = n;
                Status::Ok
            }
            Err(status) => status,
        }
    })
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
    const F: &str = "fmi2SerializeFMUstate";
    guard(c, F, |inst| {
        let Some(core) = snapshot(state) else {
            return unknown_state(inst, F);
        };
        let bytes = match inst.serialize(core) {
            Ok(b) => b,
            Err(status) => return status,
        };
        let Some(out) = slice_mut(serializedState as *mut u8, size) else {
            return null_arg(inst, F, "serializedState", size);
        };
        if out.len() < bytes.len() {
            inst.log(
                Status::Error,
                &format!("{F}: size = {size} is too small: the state needs {} bytes (fmi2SerializedFMUstateSize)", bytes.len()),
            );
            return Status::Error;
        }
        out[..bytes.len()].copy_from_slice(&bytes);
        Status::Ok
    })
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
    const F: &str = "fmi2DeSerializeFMUstate";
    guard(c, F, |inst| {
        let Some(bytes) = slice(serializedState as *const u8, size) else {
            return null_arg(inst, F, "serializedState", size);
        };
        let Some(slot) = state.as_mut() else {
            return null_arg(inst, F, "FMUstate", 1);
        };
        let core = match inst.deserialize(bytes) {
            Ok(core) => core,
            Err(status) => return status,
        };
        if slot.is_null() {
            *slot = register_state(core);
            return Status::Ok;
        }
        match snapshot(*slot) {
            Some(existing) => {
                *existing = *core;
                Status::Ok
            }
            None => unknown_state(inst, F),
        }
    })
}

/// # Safety
/// `c` is an instance. Not provided: logs and returns fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _vUnknown_ref: *const fmi2ValueReference,
    _nUnknown: usize,
    _vKnown_ref: *const fmi2ValueReference,
    _nKnown: usize,
    _dvKnown: *const fmi2Real,
    _dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2GetDirectionalDerivative", Instance::get_directional_derivative)
}

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
    guard(c, F, |inst| match (slice(vr, nvr), slice(order, nvr), slice(value, nvr)) {
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
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2GetRealOutputDerivatives", Instance::get_real_output_derivatives)
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
    guard(c, "fmi2GetStatus", |inst| inst.get_unprovided_status("fmi2GetStatus", s))
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
        let Some(value) = value.as_mut() else {
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
    guard(c, "fmi2GetIntegerStatus", |inst| inst.get_unprovided_status("fmi2GetIntegerStatus", s))
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
        let Some(value) = value.as_mut() else {
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
    guard(c, "fmi2GetStringStatus", |inst| inst.get_unprovided_status("fmi2GetStringStatus", s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmi2::instance::State;
    use std::sync::{Arc, Mutex as StdMutex};

    /// A panic inside an exported body is caught: the call returns fmi2Fatal, the panic is
    /// logged, the instance refuses everything after, and it can still be freed.
    #[test]
    fn a_panic_is_caught_logged_and_makes_the_instance_fatal() {
        let log = Arc::new(StdMutex::new(Vec::<(Status, String)>::new()));
        let sink = log.clone();
        let logger: Logger = Box::new(move |s, _, m| sink.lock().unwrap().push((s, m.to_string())));
        let guid = crate::fmi2::variables::guid();
        let inst = Instance::instantiate("panicky", 1, guid, logger, false).unwrap();
        let c = Box::into_raw(Box::new(inst)) as fmi2Component;
        with_registry(|r| r.instances.insert(c as usize));

        let status = guard(c, "fmi2Test", |_| panic!("boom"));
        assert_eq!(status, Status::Fatal as fmi2Status);
        // SAFETY: `c` is registered and not in use elsewhere.
        assert_eq!(unsafe { instance(c) }.unwrap().state(), State::Fatal);
        let last = log.lock().unwrap().last().cloned().unwrap();
        assert_eq!(last.0, Status::Fatal);
        assert!(last.1.contains("fmi2Test") && last.1.contains("boom"), "{}", last.1);

        // SAFETY: valid instance; the calls check their state first.
        unsafe {
            assert_eq!(fmi2Reset(c), Status::Error as fmi2Status);
            assert_eq!(fmi2DoStep(c, 0.0, 0.1, 0), Status::Error as fmi2Status);
            fmi2FreeInstance(c);
            assert_eq!(fmi2Reset(c), Status::Error as fmi2Status, "freed: refused");
        }
    }
}
