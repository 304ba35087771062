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
#![allow(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn)]

use super::core::Core;
use super::instance::{Instance, Logger, Status};
use std::cell::Cell;
use std::collections::{BTreeMap, BTreeSet};
use std::ffi::{c_char, c_int, c_uint, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

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
/// B-trees rather than hash tables: no `RandomState`, so the library asks the operating system
/// for no random numbers (Rust's std gets them from `ProcessPrng` on Windows, which wine 8 lacks).
struct Registry {
    instances: BTreeSet<usize>,
    /// Each live FMU state, with the instance that made it. fmi2FreeInstance frees the
    /// states its instance leaves behind: it "frees all the allocated memory" of the
    /// instance (FMI 2.0 §2.1.5).
    states: BTreeMap<usize, usize>,
}

static REGISTRY: Mutex<Option<Registry>> = Mutex::new(None);

/// Runs `f` on the registry under its lock. The tables are dropped whenever nothing is
/// registered: a host that unloads the library (`dlclose`) cannot free what a static still
/// owns, and valgrind counts it as lost once per load (tests/python/test_c_host.py). Empty
/// tables do not allocate, so re-creating them costs nothing.
fn with_registry<T>(f: impl FnOnce(&mut Registry) -> T) -> T {
    // No code panics while holding the lock, so poisoning can only come from outside; the
    // sets stay consistent either way.
    let mut guard = REGISTRY.lock().unwrap_or_else(|e| e.into_inner());
    let registry = guard
        .get_or_insert_with(|| Registry { instances: BTreeSet::new(), states: BTreeMap::new() });
    let out = f(registry);
    if registry.instances.is_empty() && registry.states.is_empty() {
        *guard = None;
    }
    out
}

/// How many instances have been freed: a pointer found live at one count is live while the
/// count stays the same.
static FREED: AtomicU64 = AtomicU64::new(0);

thread_local! {
    /// The last instance this thread found live, with the count of frees then. It spares the
    /// registry's lock on every call after the first (an uncontended lock and a B-tree lookup
    /// cost about as much as a third of a step at a 0.1 ms communication step). No destructor:
    /// the library registers none for its threads.
    static LAST_LIVE: Cell<(usize, u64)> = const { Cell::new((0, u64::MAX)) };
}

/// Whether `c` is a live instance: from this thread's last answer while no instance has been
/// freed since, else from the registry.
fn is_live(c: usize) -> bool {
    let freed = FREED.load(Ordering::Acquire);
    if LAST_LIVE.with(Cell::get) == (c, freed) {
        return true;
    }
    let live = with_registry(|r| r.instances.contains(&c));
    if live {
        LAST_LIVE.with(|last| last.set((c, freed)));
    }
    live
}

/// The instance behind `c`, if `c` is a live instance of this library.
///
/// # Safety
/// The host must not use the same instance from two threads at once (FMI 2.0 §2.1.1).
unsafe fn instance<'a>(c: fmi2Component) -> Option<&'a mut Instance> {
    if c.is_null() || !is_live(c as usize) {
        return None;
    }
    // SAFETY: registered pointers come from Box::into_raw in fmi2Instantiate and are removed
    // before fmi2FreeInstance drops them.
    Some(unsafe { &mut *(c as *mut Instance) })
}

/// The snapshot behind `s`, if `s` is a live FMU state of this library.
unsafe fn snapshot<'a>(s: fmi2FMUstate) -> Option<&'a mut Core> {
    if s.is_null() || !with_registry(|r| r.states.contains_key(&(s as usize))) {
        return None;
    }
    // SAFETY: registered pointers come from Box::into_raw in this module.
    Some(unsafe { &mut *(s as *mut Core) })
}

/// Registers a new FMU state made by `owner`.
fn register_state(owner: &Instance, core: Box<Core>) -> fmi2FMUstate {
    let p = Box::into_raw(core) as fmi2FMUstate;
    let owner = owner as *const Instance as usize;
    with_registry(|r| r.states.insert(p as usize, owner));
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
///
/// A fatal instance refuses every call here, before `body` looks at any argument, with
/// fmi2Error and an "illegal call sequence" message: FMI 2.0 (§2.1.3, fmi2Fatal) allows no
/// further call, and the host already got fmi2Fatal from the call that panicked.
fn guard(c: fmi2Component, func: &str, body: impl FnOnce(&mut Instance) -> Status) -> fmi2Status {
    // SAFETY: see `instance`.
    let Some(inst) = (unsafe { instance(c) }) else {
        return Status::Error as fmi2Status;
    };
    if !inst.check_not_fatal(func) {
        return Status::Error as fmi2Status;
    }
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
    // SAFETY: non-NULL, aligned, and the caller guarantees n valid elements.
    Some(unsafe { std::slice::from_raw_parts(p, n) })
}

/// Mutable counterpart of [`slice`].
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        return Some(&mut []);
    }
    if p.is_null() || !p.is_aligned() || n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return None;
    }
    // SAFETY: non-NULL, aligned, and the caller guarantees n valid elements.
    Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// A C string as UTF-8; `None` for NULL or invalid UTF-8.
unsafe fn text<'a>(s: fmi2String) -> Option<&'a str> {
    if s.is_null() {
        return None;
    }
    // SAFETY: non-NULL, and the caller guarantees a NUL-terminated string.
    unsafe { CStr::from_ptr(s) }.to_str().ok()
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
    let owner = c as usize;
    let orphans = with_registry(|r| {
        if !r.instances.remove(&owner) {
            return None;
        }
        // Every thread's cached answer for a live instance is now stale.
        FREED.fetch_add(1, Ordering::Release);
        let mine: Vec<usize> =
            r.states.iter().filter(|(_, o)| **o == owner).map(|(s, _)| *s).collect();
        for s in &mine {
            r.states.remove(s);
        }
        Some(mine)
    });
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

/// # Safety
/// `c` is an instance; `vr` and `value` hold `nvr` elements.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    // SAFETY: each pointer holds `nvr` elements (the function's contract).
    guard(c, "fmi2GetReal", |inst| match unsafe { (slice(vr, nvr), slice_mut(value, nvr)) } {
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
    // SAFETY: each pointer holds `nvr` elements (the function's contract).
    guard(c, "fmi2GetInteger", |inst| match unsafe { (slice(vr, nvr), slice_mut(value, nvr)) } {
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
    // SAFETY: each pointer holds `nvr` elements (the function's contract).
    guard(c, "fmi2GetBoolean", |inst| match unsafe { (slice(vr, nvr), slice_mut(value, nvr)) } {
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
    // SAFETY: each pointer holds `nvr` elements (the function's contract).
    guard(c, "fmi2GetString", |inst| match unsafe { (slice(vr, nvr), slice_mut(value, nvr)) } {
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
    // SAFETY: each pointer holds `nvr` elements (the function's contract).
    guard(c, "fmi2SetReal", |inst| match unsafe { (slice(vr, nvr), slice(value, nvr)) } {
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
    // SAFETY: each pointer holds `nvr` elements (the function's contract).
    guard(c, "fmi2SetInteger", |inst| match unsafe { (slice(vr, nvr), slice(value, nvr)) } {
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
    // SAFETY: each pointer holds `nvr` elements (the function's contract).
    guard(c, "fmi2SetBoolean", |inst| match unsafe { (slice(vr, nvr), slice(value, nvr)) } {
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
    // SAFETY: each pointer holds `nvr` elements (the function's contract).
    guard(c, "fmi2SetString", |inst| match unsafe { (slice(vr, nvr), slice(value, nvr)) } {
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
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(slot) = (unsafe { state.as_mut() }) else {
            return null_arg(inst, "fmi2GetFMUstate", "FMUstate", 1);
        };
        if slot.is_null() {
            return match inst.get_state() {
                Ok(core) => {
                    *slot = register_state(inst, core);
                    Status::Ok
                }
                Err(status) => status,
            };
        }
        // SAFETY: `snapshot` finds only live states of this library; FMI forbids using one from two threads at once.
        match unsafe { snapshot(*slot) } {
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
    // SAFETY: `snapshot` finds only live states of this library; FMI forbids using one from two threads at once.
    guard(c, "fmi2SetFMUstate", |inst| match unsafe { snapshot(state) } {
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
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(slot) = (unsafe { state.as_mut() }) else {
            return null_arg(inst, "fmi2FreeFMUstate", "FMUstate", 1);
        };
        let status = inst.check_free_state(slot.is_null());
        if status != Status::Ok || slot.is_null() {
            return status; // refused, or nothing to free
        }
        if with_registry(|r| r.states.remove(&(*slot as usize))).is_none() {
            return unknown_state(inst, "fmi2FreeFMUstate");
        }
        // SAFETY: it was registered, so it came from Box::into_raw and is freed only here.
        drop(unsafe { Box::from_raw(*slot as *mut Core) });
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
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(size) = (unsafe { size.as_mut() }) else {
            return null_arg(inst, "fmi2SerializedFMUstateSize", "size", 1);
        };
        // SAFETY: `snapshot` finds only live states of this library; FMI forbids using one from two threads at once.
        let Some(core) = (unsafe { snapshot(state) }) else {
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
        // SAFETY: `snapshot` finds only live states of this library; FMI forbids using one from two threads at once.
        let Some(core) = (unsafe { snapshot(state) }) else {
            return unknown_state(inst, F);
        };
        let bytes = match inst.serialize(core) {
            Ok(b) => b,
            Err(status) => return status,
        };
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(out) = (unsafe { slice_mut(serializedState as *mut u8, size) }) else {
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
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(bytes) = (unsafe { slice(serializedState as *const u8, size) }) else {
            return null_arg(inst, F, "serializedState", size);
        };
        // SAFETY: the pointer is the host's, valid as the FMI function's contract says.
        let Some(slot) = (unsafe { state.as_mut() }) else {
            return null_arg(inst, F, "FMUstate", 1);
        };
        let core = match inst.deserialize(bytes) {
            Ok(core) => core,
            Err(status) => return status,
        };
        if slot.is_null() {
            *slot = register_state(inst, core);
            return Status::Ok;
        }
        // SAFETY: `snapshot` finds only live states of this library; FMI forbids using one from two threads at once.
        match unsafe { snapshot(*slot) } {
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
    guard(c, "fmi2GetStringStatus", |inst| inst.get_unprovided_status("fmi2GetStringStatus", s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmi2::instance::State;
    use crate::fmi2::variables::Var;
    use std::ptr::{null, null_mut};
    use std::sync::{Arc, Mutex as StdMutex};

    /// The tests of this module register instances and call functions on freed pointers;
    /// they take this lock so that no other test of the module registers an instance at a
    /// freed address meanwhile. (No other unit test registers instances.)
    static REGISTERING: StdMutex<()> = StdMutex::new(());

    fn registering() -> std::sync::MutexGuard<'static, ()> {
        REGISTERING.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A panic inside an exported body is caught: the call returns fmi2Fatal, the panic is
    /// logged, the instance refuses everything after, and it can still be freed.
    #[test]
    fn a_panic_is_caught_logged_and_makes_the_instance_fatal() {
        let _g = registering();
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

    // ----- the fatal state, through the C API ----------------------------------------------

    /// One call of the host's logger: (status, category, format, message).
    type Record = (fmi2Status, String, String, String);
    type Records = StdMutex<Vec<Record>>;

    fn lossy(p: *const c_char) -> String {
        if p.is_null() {
            return "<NULL>".into();
        }
        // SAFETY: the FMU passes NUL-terminated strings that live for the call.
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }

    /// The host's logger with the variadic `...` written as one fixed pointer parameter, as
    /// in tests/common/mod.rs: sound on x86_64 System V (and Windows x64, AArch64 Linux),
    /// where the first variadic pointer travels like a sixth fixed one. `env` is a `Records`.
    unsafe extern "C" fn record(
        env: *mut c_void,
        _name: *const c_char,
        status: c_int,
        category: *const c_char,
        fmt: *const c_char,
        arg: *const c_char,
    ) {
        // SAFETY: every environment of these tests is a live `Records`.
        let records = unsafe { &*(env as *const Records) };
        let fmt = lossy(fmt);
        let message = if fmt == "%s" { lossy(arg) } else { String::new() };
        records.lock().unwrap().push((status, lossy(category), fmt, message));
    }

    #[cfg(all(target_arch = "aarch64", target_vendor = "apple"))]
    compile_error!("`record` relies on variadic arguments travelling like fixed ones");

    fn callbacks(records: &Records) -> Box<fmi2CallbackFunctions> {
        type Fixed = unsafe extern "C" fn(
            *mut c_void,
            *const c_char,
            c_int,
            *const c_char,
            *const c_char,
            *const c_char,
        );
        // SAFETY: function pointers of the same size; ABI-compatible, see `record`.
        let logger = unsafe { std::mem::transmute::<Fixed, fmi2CallbackLogger>(record as Fixed) };
        Box::new(fmi2CallbackFunctions {
            logger: Some(logger),
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: records as *const Records as fmi2ComponentEnvironment,
        })
    }

    fn instantiate(name: &CStr, functions: &fmi2CallbackFunctions) -> fmi2Component {
        let guid = CString::new(crate::fmi2::variables::guid()).unwrap();
        // SAFETY: valid strings; `functions` outlives the instance in every test.
        let c = unsafe {
            fmi2Instantiate(name.as_ptr(), 1, guid.as_ptr(), null(), functions, fmi2False, fmi2True)
        };
        assert!(!c.is_null());
        c
    }

    const OK: fmi2Status = Status::Ok as fmi2Status;
    const ERROR: fmi2Status = Status::Error as fmi2Status;
    const FATAL: fmi2Status = Status::Fatal as fmi2Status;

    /// An instance in stepComplete at t = 0.01, with the built-in law.
    ///
    /// # Safety
    /// `c` is a live instance.
    unsafe fn to_step_complete(c: fmi2Component) {
        // SAFETY: as this function's contract says.
        unsafe {
            let source = [Var::PhiSource.vr()];
            assert_eq!(fmi2SetInteger(c, source.as_ptr(), 1, [2].as_ptr()), OK);
            assert_eq!(fmi2SetupExperiment(c, fmi2True, 1e-6, 0.0, fmi2False, 0.0), OK);
            assert_eq!(fmi2EnterInitializationMode(c), OK);
            assert_eq!(fmi2ExitInitializationMode(c), OK);
            assert_eq!(fmi2DoStep(c, 0.0, 0.01, fmi2False), OK);
        }
    }

    /// Each of the 30 functions that take an instance, called on `c` with arguments that are
    /// valid in stepComplete (so that only the state can be the reason for a refusal), some
    /// in several variants. `snap` is a live FMU state and `bytes` its serialized form.
    ///
    /// # Safety
    /// `c` and `snap` are live.
    unsafe fn instance_calls(
        c: fmi2Component,
        snap: fmi2FMUstate,
        bytes: &[u8],
    ) -> Vec<(&'static str, fmi2Status)> {
        // SAFETY: as this function's contract says.
        unsafe {
            let (rv, iv, bv) = ([Var::Phi.vr()], [Var::MaxOrder.vr()], [Var::StabilityGuard.vr()]);
            let (mut r, mut i, mut b) = ([0.5], [3], [fmi2True]);
            let mut string: [fmi2String; 1] = [null()];
            let cats = [c"logAll".as_ptr()];
            let mut fresh: fmi2FMUstate = null_mut();
            let mut existing = snap;
            let mut none: fmi2FMUstate = null_mut();
            let mut size = 0usize;
            let mut out = vec![0u8; bytes.len()];
            let (mut k, mut flag) = (-1, -1);
            let bp = bytes.as_ptr() as *const fmi2Byte;
            let op = out.as_mut_ptr() as *mut fmi2Byte;
            let outputs = [Var::V1.vr()];
            let calls = vec![
                ("fmi2SetDebugLogging", fmi2SetDebugLogging(c, fmi2True, 1, cats.as_ptr())),
                ("fmi2SetDebugLogging", fmi2SetDebugLogging(c, fmi2False, 0, null())),
                (
                    "fmi2SetupExperiment",
                    fmi2SetupExperiment(c, fmi2True, 1e-6, 0.0, fmi2False, 0.0),
                ),
                ("fmi2EnterInitializationMode", fmi2EnterInitializationMode(c)),
                ("fmi2ExitInitializationMode", fmi2ExitInitializationMode(c)),
                ("fmi2Terminate", fmi2Terminate(c)),
                ("fmi2Reset", fmi2Reset(c)),
                ("fmi2GetReal", fmi2GetReal(c, rv.as_ptr(), 1, r.as_mut_ptr())),
                ("fmi2GetReal", fmi2GetReal(c, null(), 0, null_mut())),
                ("fmi2GetReal", fmi2GetReal(c, null(), 1, null_mut())),
                ("fmi2GetInteger", fmi2GetInteger(c, iv.as_ptr(), 1, i.as_mut_ptr())),
                ("fmi2GetBoolean", fmi2GetBoolean(c, bv.as_ptr(), 1, b.as_mut_ptr())),
                ("fmi2GetString", fmi2GetString(c, null(), 0, string.as_mut_ptr())),
                ("fmi2SetReal", fmi2SetReal(c, rv.as_ptr(), 1, [0.25].as_ptr())),
                ("fmi2SetReal", fmi2SetReal(c, rv.as_ptr(), 1, [f64::NAN].as_ptr())),
                ("fmi2SetInteger", fmi2SetInteger(c, iv.as_ptr(), 1, [3].as_ptr())),
                ("fmi2SetBoolean", fmi2SetBoolean(c, bv.as_ptr(), 1, [fmi2False].as_ptr())),
                ("fmi2SetString", fmi2SetString(c, null(), 0, null())),
                ("fmi2GetFMUstate", fmi2GetFMUstate(c, &mut fresh)),
                ("fmi2GetFMUstate", fmi2GetFMUstate(c, &mut existing)),
                ("fmi2SetFMUstate", fmi2SetFMUstate(c, snap)),
                ("fmi2FreeFMUstate", fmi2FreeFMUstate(c, &mut existing)),
                ("fmi2FreeFMUstate", fmi2FreeFMUstate(c, &mut none)),
                ("fmi2SerializedFMUstateSize", fmi2SerializedFMUstateSize(c, snap, &mut size)),
                ("fmi2SerializeFMUstate", fmi2SerializeFMUstate(c, snap, op, out.len())),
                (
                    "fmi2DeSerializeFMUstate",
                    fmi2DeSerializeFMUstate(c, bp, bytes.len(), &mut fresh),
                ),
                (
                    "fmi2DeSerializeFMUstate",
                    fmi2DeSerializeFMUstate(c, bp, bytes.len(), &mut existing),
                ),
                (
                    "fmi2GetDirectionalDerivative",
                    fmi2GetDirectionalDerivative(
                        c,
                        outputs.as_ptr(),
                        1,
                        rv.as_ptr(),
                        1,
                        [1.0].as_ptr(),
                        r.as_mut_ptr(),
                    ),
                ),
                (
                    "fmi2SetRealInputDerivatives",
                    fmi2SetRealInputDerivatives(c, rv.as_ptr(), 1, [1].as_ptr(), [0.5].as_ptr()),
                ),
                (
                    "fmi2GetRealOutputDerivatives",
                    fmi2GetRealOutputDerivatives(
                        c,
                        outputs.as_ptr(),
                        1,
                        [1].as_ptr(),
                        r.as_mut_ptr(),
                    ),
                ),
                ("fmi2DoStep", fmi2DoStep(c, 0.01, 0.01, fmi2False)),
                ("fmi2CancelStep", fmi2CancelStep(c)),
                ("fmi2GetStatus", fmi2GetStatus(c, 0, &mut k)),
                ("fmi2GetRealStatus", fmi2GetRealStatus(c, 2, r.as_mut_ptr())),
                ("fmi2GetIntegerStatus", fmi2GetIntegerStatus(c, 0, &mut k)),
                ("fmi2GetBooleanStatus", fmi2GetBooleanStatus(c, 3, &mut flag)),
                ("fmi2GetStringStatus", fmi2GetStringStatus(c, 1, string.as_mut_ptr())),
            ];
            // Nothing was written through an output argument.
            assert!(fresh.is_null() && existing == snap && none.is_null());
            assert!(out.iter().all(|x| *x == 0) && size == 0);
            assert_eq!((r, i, b, k, flag), ([0.5], [3], [fmi2True], -1, -1));
            assert!(string[0].is_null());
            calls
        }
    }

    /// The fatal state, which only a panic reaches, for all 34 functions (FMI 2.0 §2.1.3:
    /// after fmi2Fatal no function may be called). Chosen and checked here:
    /// - each of the 30 functions with a status returns fmi2Error, the status of every
    ///   illegal call, and logs "`<function>`: illegal call sequence: not allowed in state
    ///   `fatal`", whatever its arguments (valid ones, NULL arrays, nvr = 0, NULL states);
    /// - none of them touches the instance, its FMU states or the output arguments, and none
    ///   is traced although logCalls is on;
    /// - fmi2FreeInstance still frees the instance (a host that does so should not leak it;
    ///   nothing of the model is read);
    /// - fmi2GetTypesPlatform, fmi2GetVersion and fmi2Instantiate take no instance: they
    ///   work as always. The panic was caught inside one instance, so other instances, old
    ///   and new, are intact: fatal is per instance.
    #[test]
    fn a_fatal_instance_refuses_all_34_functions_and_stays_untouched() {
        let _g = registering();
        let records: Box<Records> = Box::default();
        let functions = callbacks(&records);
        let c = instantiate(c"doomed", &functions);
        let other_records: Box<Records> = Box::default();
        let other_functions = callbacks(&other_records);
        let other = instantiate(c"bystander", &other_functions);
        let take = |r: &Records| std::mem::take(&mut *r.lock().unwrap());

        // SAFETY: `c` and `other` are live instances of this test; the FMU states are ours.
        unsafe {
            to_step_complete(c);
            to_step_complete(other);
            let mut snap: fmi2FMUstate = null_mut();
            assert_eq!(fmi2GetFMUstate(c, &mut snap), OK);
            let mut size = 0;
            assert_eq!(fmi2SerializedFMUstateSize(c, snap, &mut size), OK);
            let mut bytes = vec![0u8; size];
            let p = bytes.as_mut_ptr() as *mut fmi2Byte;
            assert_eq!(fmi2SerializeFMUstate(c, snap, p, size), OK);
            // logCalls is on (loggingOn at instantiation): the calls so far were traced.
            assert!(take(&records).iter().any(|r| r.3.starts_with("fmi2DoStep: tc = 0")));

            assert_eq!(guard(c, "fmi2DoStep", |_| panic!("boom")), FATAL);
            let panic = take(&records);
            assert_eq!(panic.len(), 1, "{panic:#?}");
            assert_eq!(
                (panic[0].0, panic[0].1.as_str(), panic[0].2.as_str()),
                (FATAL, "logStatusFatal", "%s")
            );
            assert!(panic[0].3.contains("fmi2DoStep: internal error (panic): boom"), "{panic:?}");

            let debug = |c: fmi2Component| format!("{:?}", instance(c).unwrap());
            let before = debug(c);
            assert!(before.contains("Fatal"), "{before}");
            let snap_before = crate::fmi2::state::serialize(snapshot(snap).unwrap());

            let calls = instance_calls(c, snap, &bytes);
            let mut names: Vec<&str> = calls.iter().map(|(n, _)| *n).collect();
            names.dedup();
            assert_eq!(names.len(), 30, "{names:?}");
            let log = take(&records);
            assert_eq!(log.len(), calls.len(), "one record per call: {log:#?}");
            for ((name, status), (s, category, fmt, message)) in calls.iter().zip(&log) {
                assert_eq!(*status, ERROR, "{name} in fatal");
                assert_eq!((*s, category.as_str(), fmt.as_str()), (ERROR, "logStatusError", "%s"));
                let want = format!("{name}: illegal call sequence: not allowed in state `fatal`");
                assert_eq!(message, &want);
            }
            assert_eq!(debug(c), before, "a fatal instance is not touched");
            let snap_after = crate::fmi2::state::serialize(snapshot(snap).unwrap());
            assert_eq!(snap_after, snap_before, "nor are the FMU states passed to it");
            assert!(with_registry(|r| r.states.contains_key(&(snap as usize))), "nor freed");

            // The three functions without an instance.
            assert_eq!(CStr::from_ptr(fmi2GetTypesPlatform()), c"default");
            assert_eq!(CStr::from_ptr(fmi2GetVersion()), c"2.0");
            let new = instantiate(c"newcomer", &other_functions);
            assert_eq!(fmi2SetupExperiment(new, fmi2False, 0.0, 0.0, fmi2False, 0.0), OK);
            fmi2FreeInstance(new);
            assert!(take(&records).is_empty(), "nothing reaches the fatal instance's logger");
            // The bystander, made before the panic, continues.
            assert_eq!(fmi2DoStep(other, 0.01, 0.01, fmi2False), OK);
            let mut x = [0.0];
            assert_eq!(fmi2GetReal(other, [Var::V1.vr()].as_ptr(), 1, x.as_mut_ptr()), OK);
            assert!(x[0].is_finite() && x[0] != 0.0, "{x:?}");
            assert!(take(&other_records).iter().all(|r| r.0 == OK), "only traces");

            // fmi2FreeInstance frees it (traced: logCalls is on), and then it is unknown.
            fmi2FreeInstance(c);
            let freed = take(&records);
            assert_eq!(freed.len(), 1, "{freed:#?}");
            assert_eq!((freed[0].0, freed[0].1.as_str()), (OK, "logCalls"));
            assert_eq!(freed[0].3, "fmi2FreeInstance: instance `doomed`");
            assert!(!with_registry(|r| r.instances.contains(&(c as usize))));
            assert_eq!(fmi2Reset(c), ERROR);
            fmi2FreeInstance(c); // a no-op
            assert!(take(&records).is_empty(), "a freed instance has no logger");

            // fmi2FreeInstance freed the FMU state its instance left behind: the pointer is
            // unknown now, and refused.
            assert!(!with_registry(|r| r.states.contains_key(&(snap as usize))));
            assert_eq!(fmi2FreeFMUstate(other, &mut snap), ERROR);
            let refused = take(&other_records);
            assert!(refused.iter().any(|r| r.3.contains("fmi2FreeFMUstate")), "{refused:#?}");
            fmi2FreeInstance(other);
        }
    }
}
