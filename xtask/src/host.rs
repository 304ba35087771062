//! A native FMI 2.0 Co-Simulation host: loads an extracted FMU's shared library with
//! libloading and calls it through the standard C ABI, as a simulation tool would.
//!
//! - [`Fmu2::load`] reads `modelDescription.xml` (GUID, modelIdentifier), dlopens
//!   `binaries/linux64/<modelIdentifier>.so` and resolves all 34 functions that a CS FMU must
//!   export (like FMPy, it refuses a binary that lacks one).
//! - [`Fmu2::instantiate`] returns an [`Instance`], a safe handle whose methods return
//!   `Result` and whose `Drop` calls `fmi2FreeInstance`.
//!
//! The C declarations follow fmi2FunctionTypes.h and fmi2TypesPlatform.h of FMI 2.0.x.
//! `cargo xtask fmu` uses this module to run the packaged FMU; the benchmark reuses it.

use std::ffi::{c_char, c_int, c_uint, c_void, CStr, CString};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use libloading::Library;

use crate::xml::Element;
use crate::{relative, Result};

// ---------------------------------------------------------------------------------------
// The C types.

pub type Component = *mut c_void;
pub type ComponentEnvironment = *mut c_void;
pub type FmuStatePtr = *mut c_void;
pub type ValueReference = c_uint;
pub type Fmi2Boolean = c_int;
pub type Fmi2String = *const c_char;

const FMI2_TRUE: Fmi2Boolean = 1;
const FMI2_FALSE: Fmi2Boolean = 0;
/// `fmi2Type`: fmi2ModelExchange = 0, fmi2CoSimulation = 1.
const FMI2_CO_SIMULATION: c_int = 1;

fn fmi2_bool(b: bool) -> Fmi2Boolean {
    if b {
        FMI2_TRUE
    } else {
        FMI2_FALSE
    }
}

/// `fmi2CallbackLogger`: `void (*)(fmi2ComponentEnvironment, fmi2String instanceName,
/// fmi2Status, fmi2String category, fmi2String message, ...)`; printf-like.
pub type Logger =
    unsafe extern "C" fn(ComponentEnvironment, Fmi2String, c_int, Fmi2String, Fmi2String, ...);
pub type AllocateMemory = unsafe extern "C" fn(usize, usize) -> *mut c_void;
pub type FreeMemory = unsafe extern "C" fn(*mut c_void);
pub type StepFinished = unsafe extern "C" fn(ComponentEnvironment, c_int);

/// `fmi2CallbackFunctions`. The FMU may keep a pointer to it, so an [`Instance`] keeps it
/// boxed until `fmi2FreeInstance`.
#[repr(C)]
pub struct CallbackFunctions {
    pub logger: Option<Logger>,
    pub allocate_memory: Option<AllocateMemory>,
    pub free_memory: Option<FreeMemory>,
    pub step_finished: Option<StepFinished>,
    pub component_environment: ComponentEnvironment,
}

/// `fmi2Status`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Ok,
    Warning,
    Discard,
    Error,
    Fatal,
    Pending,
}

impl Status {
    fn from_raw(raw: c_int) -> Option<Status> {
        Some(match raw {
            0 => Status::Ok,
            1 => Status::Warning,
            2 => Status::Discard,
            3 => Status::Error,
            4 => Status::Fatal,
            5 => Status::Pending,
            _ => return None,
        })
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "fmi2{self:?}")
    }
}

/// `fmi2StatusKind`, for the Get…Status functions.
#[allow(dead_code)] // the whole C enum; the wrappers ask for two kinds
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub enum StatusKind {
    DoStepStatus = 0,
    PendingStatus = 1,
    LastSuccessfulTime = 2,
    Terminated = 3,
}

/// A call that returned a status outside {OK, Warning} (or Discard, where a method accepts
/// it). `messages` are what the FMU logged during the call.
#[derive(Debug)]
pub struct CallError {
    pub function: &'static str,
    pub status: Option<Status>,
    pub raw: c_int,
    pub messages: Vec<String>,
}

impl fmt::Display for CallError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self.status {
            Some(status) => write!(f, "{} returned {status}", self.function)?,
            None => write!(f, "{} returned the unknown status {}", self.function, self.raw)?,
        }
        for message in &self.messages {
            write!(f, "\n  logged: {message}")?;
        }
        Ok(())
    }
}

impl std::error::Error for CallError {}

// ---------------------------------------------------------------------------------------
// The functions.

type GetTypesPlatform = unsafe extern "C" fn() -> *const c_char;
type GetVersion = unsafe extern "C" fn() -> *const c_char;
type SetDebugLogging =
    unsafe extern "C" fn(Component, Fmi2Boolean, usize, *const Fmi2String) -> c_int;
type Instantiate = unsafe extern "C" fn(
    Fmi2String,
    c_int,
    Fmi2String,
    Fmi2String,
    *const CallbackFunctions,
    Fmi2Boolean,
    Fmi2Boolean,
) -> Component;
type FreeInstance = unsafe extern "C" fn(Component);
type SetupExperiment =
    unsafe extern "C" fn(Component, Fmi2Boolean, f64, f64, Fmi2Boolean, f64) -> c_int;
type ComponentOnly = unsafe extern "C" fn(Component) -> c_int;
type GetReal = unsafe extern "C" fn(Component, *const ValueReference, usize, *mut f64) -> c_int;
type GetInteger =
    unsafe extern "C" fn(Component, *const ValueReference, usize, *mut c_int) -> c_int;
type GetBoolean =
    unsafe extern "C" fn(Component, *const ValueReference, usize, *mut Fmi2Boolean) -> c_int;
type GetString =
    unsafe extern "C" fn(Component, *const ValueReference, usize, *mut Fmi2String) -> c_int;
type SetReal = unsafe extern "C" fn(Component, *const ValueReference, usize, *const f64) -> c_int;
type SetInteger =
    unsafe extern "C" fn(Component, *const ValueReference, usize, *const c_int) -> c_int;
type SetBoolean =
    unsafe extern "C" fn(Component, *const ValueReference, usize, *const Fmi2Boolean) -> c_int;
type SetString =
    unsafe extern "C" fn(Component, *const ValueReference, usize, *const Fmi2String) -> c_int;
type GetFmuState = unsafe extern "C" fn(Component, *mut FmuStatePtr) -> c_int;
type SetFmuState = unsafe extern "C" fn(Component, FmuStatePtr) -> c_int;
type FreeFmuState = unsafe extern "C" fn(Component, *mut FmuStatePtr) -> c_int;
type SerializedFmuStateSize = unsafe extern "C" fn(Component, FmuStatePtr, *mut usize) -> c_int;
type SerializeFmuState = unsafe extern "C" fn(Component, FmuStatePtr, *mut c_char, usize) -> c_int;
type DeSerializeFmuState =
    unsafe extern "C" fn(Component, *const c_char, usize, *mut FmuStatePtr) -> c_int;
type GetDirectionalDerivative = unsafe extern "C" fn(
    Component,
    *const ValueReference,
    usize,
    *const ValueReference,
    usize,
    *const f64,
    *mut f64,
) -> c_int;
type SetRealInputDerivatives = unsafe extern "C" fn(
    Component,
    *const ValueReference,
    usize,
    *const c_int,
    *const f64,
) -> c_int;
type GetRealOutputDerivatives =
    unsafe extern "C" fn(Component, *const ValueReference, usize, *const c_int, *mut f64) -> c_int;
type DoStep = unsafe extern "C" fn(Component, f64, f64, Fmi2Boolean) -> c_int;
type GetStatus = unsafe extern "C" fn(Component, c_int, *mut c_int) -> c_int;
type GetRealStatus = unsafe extern "C" fn(Component, c_int, *mut f64) -> c_int;
type GetIntegerStatus = unsafe extern "C" fn(Component, c_int, *mut c_int) -> c_int;
type GetBooleanStatus = unsafe extern "C" fn(Component, c_int, *mut Fmi2Boolean) -> c_int;
type GetStringStatus = unsafe extern "C" fn(Component, c_int, *mut Fmi2String) -> c_int;

/// All 34 functions of an FMI 2.0 CS FMU (25 common, 9 co-simulation). Plain function
/// pointers copied out of the library, valid while [`Fmu2`] holds it.
#[allow(dead_code)] // resolved to check that the binary is complete; not all are wrapped
struct Api {
    get_types_platform: GetTypesPlatform,
    get_version: GetVersion,
    set_debug_logging: SetDebugLogging,
    instantiate: Instantiate,
    free_instance: FreeInstance,
    setup_experiment: SetupExperiment,
    enter_initialization_mode: ComponentOnly,
    exit_initialization_mode: ComponentOnly,
    terminate: ComponentOnly,
    reset: ComponentOnly,
    get_real: GetReal,
    get_integer: GetInteger,
    get_boolean: GetBoolean,
    get_string: GetString,
    set_real: SetReal,
    set_integer: SetInteger,
    set_boolean: SetBoolean,
    set_string: SetString,
    get_fmu_state: GetFmuState,
    set_fmu_state: SetFmuState,
    free_fmu_state: FreeFmuState,
    serialized_fmu_state_size: SerializedFmuStateSize,
    serialize_fmu_state: SerializeFmuState,
    de_serialize_fmu_state: DeSerializeFmuState,
    get_directional_derivative: GetDirectionalDerivative,
    set_real_input_derivatives: SetRealInputDerivatives,
    get_real_output_derivatives: GetRealOutputDerivatives,
    do_step: DoStep,
    cancel_step: ComponentOnly,
    get_status: GetStatus,
    get_real_status: GetRealStatus,
    get_integer_status: GetIntegerStatus,
    get_boolean_status: GetBooleanStatus,
    get_string_status: GetStringStatus,
}

/// The function `name` (NUL-terminated) of `lib`, copied out of its `Symbol`; `None` after
/// recording the name (without the NUL) in `missing`. Shared by this host and the
/// benchmark's CVODE loader.
///
/// # Safety
/// `T` must be the function's true C signature, and `lib` must stay loaded while the pointer
/// is used.
pub(crate) unsafe fn symbol<T: Copy>(
    lib: &Library,
    name: &'static str,
    missing: &mut Vec<&'static str>,
) -> Option<T> {
    match lib.get::<T>(name.as_bytes()) {
        Ok(symbol) => Some(*symbol),
        Err(_) => {
            missing.push(name.trim_end_matches('\0'));
            None
        }
    }
}

impl Api {
    /// Resolves every function; the error names all that are missing.
    fn resolve(lib: &Library, path: &Path) -> Result<Api> {
        let mut missing = Vec::new();
        // SAFETY (for every `sym` below): each name is resolved with the signature that the
        // FMI 2.0 standard gives it (fmi2FunctionTypes.h). The pointer is copied out of the
        // `Symbol`, and `Fmu2` keeps `lib` loaded for as long as it holds the pointers.
        macro_rules! sym {
            ($name:literal) => {
                unsafe { symbol(lib, concat!($name, "\0"), &mut missing) }
            };
        }
        let api = (|| {
            Some(Api {
                get_types_platform: sym!("fmi2GetTypesPlatform")?,
                get_version: sym!("fmi2GetVersion")?,
                set_debug_logging: sym!("fmi2SetDebugLogging")?,
                instantiate: sym!("fmi2Instantiate")?,
                free_instance: sym!("fmi2FreeInstance")?,
                setup_experiment: sym!("fmi2SetupExperiment")?,
                enter_initialization_mode: sym!("fmi2EnterInitializationMode")?,
                exit_initialization_mode: sym!("fmi2ExitInitializationMode")?,
                terminate: sym!("fmi2Terminate")?,
                reset: sym!("fmi2Reset")?,
                get_real: sym!("fmi2GetReal")?,
                get_integer: sym!("fmi2GetInteger")?,
                get_boolean: sym!("fmi2GetBoolean")?,
                get_string: sym!("fmi2GetString")?,
                set_real: sym!("fmi2SetReal")?,
                set_integer: sym!("fmi2SetInteger")?,
                set_boolean: sym!("fmi2SetBoolean")?,
                set_string: sym!("fmi2SetString")?,
                get_fmu_state: sym!("fmi2GetFMUstate")?,
                set_fmu_state: sym!("fmi2SetFMUstate")?,
                free_fmu_state: sym!("fmi2FreeFMUstate")?,
                serialized_fmu_state_size: sym!("fmi2SerializedFMUstateSize")?,
                serialize_fmu_state: sym!("fmi2SerializeFMUstate")?,
                de_serialize_fmu_state: sym!("fmi2DeSerializeFMUstate")?,
                get_directional_derivative: sym!("fmi2GetDirectionalDerivative")?,
                set_real_input_derivatives: sym!("fmi2SetRealInputDerivatives")?,
                get_real_output_derivatives: sym!("fmi2GetRealOutputDerivatives")?,
                do_step: sym!("fmi2DoStep")?,
                cancel_step: sym!("fmi2CancelStep")?,
                get_status: sym!("fmi2GetStatus")?,
                get_real_status: sym!("fmi2GetRealStatus")?,
                get_integer_status: sym!("fmi2GetIntegerStatus")?,
                get_boolean_status: sym!("fmi2GetBooleanStatus")?,
                get_string_status: sym!("fmi2GetStringStatus")?,
            })
        })();
        api.ok_or_else(|| {
            format!(
                "{} does not export {} (an FMI 2.0 CS FMU exports all 34 fmi2 functions)",
                relative(path),
                missing.join(", ")
            )
            .into()
        })
    }
}

// ---------------------------------------------------------------------------------------
// The host's callbacks.

/// What the logger of one instance received.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogMessage {
    pub status: Option<Status>,
    pub category: String,
    pub message: String,
}

impl fmt::Display for LogMessage {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self.status {
            Some(status) => write!(f, "[{status}] [{}] {}", self.category, self.message),
            None => write!(f, "[unknown status] [{}] {}", self.category, self.message),
        }
    }
}

/// The `componentEnvironment` of an instance: where its logger writes.
struct Environment {
    /// Echo every message to stderr as it arrives.
    echo: bool,
    messages: Mutex<Vec<LogMessage>>,
}

/// # Safety
/// `ptr` is NULL or a NUL-terminated string valid for the duration of the call.
unsafe fn string_of(ptr: *const c_char) -> String {
    if ptr.is_null() {
        "(null)".to_owned()
    } else {
        CStr::from_ptr(ptr).to_string_lossy().into_owned()
    }
}

/// The logger, implemented without C variadics, which stable Rust cannot define.
///
/// The FMU calls `logger(env, name, status, category, "%s", message)` (fmi-notes: the
/// message always travels as the argument of a literal "%s"). On x86_64 System V and on
/// AArch64 Linux (AAPCS64), the variadic arguments of a call are passed exactly like named
/// ones: the first variadic pointer goes in the next integer register (r9, x5), where a
/// sixth fixed parameter is read. So this six-parameter function, cast to the variadic
/// [`Logger`] type, receives the message as `arg0`. It reads `arg0` only when the format is
/// exactly "%s"; any other format is printed verbatim, unformatted, and `arg0` is ignored.
/// Other ABIs (Apple AArch64 passes variadics on the stack, Windows x64 differs too) get a
/// logger that prints the format only.
#[cfg(all(target_os = "linux", any(target_arch = "x86_64", target_arch = "aarch64")))]
unsafe extern "C" fn host_logger(
    env: ComponentEnvironment,
    _instance_name: Fmi2String,
    status: c_int,
    category: Fmi2String,
    format: Fmi2String,
    arg0: Fmi2String,
) {
    let message = if !format.is_null() && CStr::from_ptr(format).to_bytes() == b"%s" {
        string_of(arg0)
    } else {
        string_of(format)
    };
    record(env, status, string_of(category), message);
}

#[cfg(all(target_os = "linux", any(target_arch = "x86_64", target_arch = "aarch64")))]
fn logger() -> Logger {
    type Fixed = unsafe extern "C" fn(
        ComponentEnvironment,
        Fmi2String,
        c_int,
        Fmi2String,
        Fmi2String,
        Fmi2String,
    );
    // SAFETY: see `host_logger`: on these ABIs a variadic call with one pointer after the
    // format reaches a six-parameter function with that pointer as its sixth argument.
    unsafe { std::mem::transmute::<Fixed, Logger>(host_logger) }
}

/// The portable fallback: the format string only (see the Linux variant).
#[cfg(not(all(target_os = "linux", any(target_arch = "x86_64", target_arch = "aarch64"))))]
unsafe extern "C" fn host_logger(
    env: ComponentEnvironment,
    _instance_name: Fmi2String,
    status: c_int,
    category: Fmi2String,
    format: Fmi2String,
) {
    record(env, status, string_of(category), string_of(format));
}

#[cfg(not(all(target_os = "linux", any(target_arch = "x86_64", target_arch = "aarch64"))))]
fn logger() -> Logger {
    type Fixed =
        unsafe extern "C" fn(ComponentEnvironment, Fmi2String, c_int, Fmi2String, Fmi2String);
    // SAFETY: the named parameters of a variadic call are passed as for a fixed one.
    unsafe { std::mem::transmute::<Fixed, Logger>(host_logger) }
}

/// # Safety
/// `env` is NULL or the `Environment` of a live [`Instance`].
unsafe fn record(env: ComponentEnvironment, status: c_int, category: String, message: String) {
    let message = LogMessage { status: Status::from_raw(status), category, message };
    let Some(env) = (env as *const Environment).as_ref() else {
        eprintln!("FMU (no environment): {message}");
        return;
    };
    if env.echo {
        eprintln!("FMU: {message}");
    }
    if let Ok(mut messages) = env.messages.lock() {
        messages.push(message);
    }
}

extern "C" {
    // From the C library that std links anyway; FMI 2.0 hosts pass calloc and free.
    fn calloc(nobj: usize, size: usize) -> *mut c_void;
    fn free(ptr: *mut c_void);
}

unsafe extern "C" fn allocate_memory(nobj: usize, size: usize) -> *mut c_void {
    calloc(nobj, size)
}

unsafe extern "C" fn free_memory(ptr: *mut c_void) {
    free(ptr)
}

// ---------------------------------------------------------------------------------------
// The safe wrapper.

/// A loaded FMU: its modelDescription's identity and the resolved functions.
pub struct Fmu2 {
    pub dir: PathBuf,
    pub model_identifier: String,
    pub guid: String,
    api: Api,
    // Last: the function pointers in `api` point into it.
    _lib: Library,
}

impl Fmu2 {
    /// The platform directory that FMI 2.0 names for this host.
    pub const PLATFORM: &'static str = "linux64";

    /// Loads an extracted FMU from `dir`: `modelDescription.xml` and
    /// `binaries/linux64/<modelIdentifier>.so`.
    pub fn load(dir: &Path) -> Result<Fmu2> {
        let md_path = dir.join("modelDescription.xml");
        let text = std::fs::read_to_string(&md_path)
            .map_err(|err| format!("cannot read {}: {err}", relative(&md_path)))?;
        let root = Element::parse(&text).map_err(|err| format!("{}: {err}", relative(&md_path)))?;
        if root.attr("fmiVersion") != Some("2.0") {
            return Err(format!("{} is not an FMI 2.0 modelDescription", relative(&md_path)).into());
        }
        let guid = root.required("guid")?.to_owned();
        let model_identifier = root
            .child("CoSimulation")
            .and_then(|cs| Ok(cs.required("modelIdentifier")?.to_owned()))
            .map_err(|err| format!("{}: not a co-simulation FMU: {err}", relative(&md_path)))?;

        let so = dir.join("binaries").join(Self::PLATFORM).join(format!("{model_identifier}.so"));
        // SAFETY: loading runs the library's initialisers; the FMU is our own Rust cdylib,
        // whose initialisers are those of std.
        let lib = unsafe { Library::new(&so) }
            .map_err(|err| format!("cannot load {}: {err}", relative(&so)))?;
        let api = Api::resolve(&lib, &so)?;
        Ok(Fmu2 { dir: dir.to_path_buf(), model_identifier, guid, api, _lib: lib })
    }

    /// `fmi2GetVersion` ("2.0").
    pub fn version(&self) -> String {
        // SAFETY: the function takes nothing and returns a static string.
        unsafe { string_of((self.api.get_version)()) }
    }

    /// `fmi2GetTypesPlatform` ("default").
    pub fn types_platform(&self) -> String {
        // SAFETY: as for `version`.
        unsafe { string_of((self.api.get_types_platform)()) }
    }

    /// `fmi2Instantiate` as co-simulation, with the modelDescription's GUID, the host's
    /// logger, calloc/free and `fmuResourceLocation` = the FMU's `resources` URI.
    /// `echo`: print the FMU's log messages to stderr as they arrive (they are kept either
    /// way, see [`Instance::messages`]).
    pub fn instantiate(&self, name: &str, logging_on: bool, echo: bool) -> Result<Instance<'_>> {
        let env = Box::new(Environment { echo, messages: Mutex::new(Vec::new()) });
        let callbacks = Box::new(CallbackFunctions {
            logger: Some(logger()),
            allocate_memory: Some(allocate_memory),
            free_memory: Some(free_memory),
            step_finished: None,
            component_environment: &*env as *const Environment as *mut c_void,
        });
        let name_c = CString::new(name).map_err(|_| "the instance name contains NUL")?;
        let guid = CString::new(self.guid.as_str()).map_err(|_| "the GUID contains NUL")?;
        let resources = CString::new(file_uri(&self.dir.join("resources")))
            .map_err(|_| "the FMU's path contains NUL")?;
        // SAFETY: every pointer is valid for the call; `callbacks` and `env` are boxed and
        // owned by the returned Instance, so they outlive the component, which is freed in
        // its Drop.
        let component = unsafe {
            (self.api.instantiate)(
                name_c.as_ptr(),
                FMI2_CO_SIMULATION,
                guid.as_ptr(),
                resources.as_ptr(),
                &*callbacks,
                FMI2_FALSE,
                fmi2_bool(logging_on),
            )
        };
        let messages = env.messages.lock().map(|m| m.clone()).unwrap_or_default();
        if component.is_null() {
            let mut err = format!("fmi2Instantiate returned NULL for {}", self.model_identifier);
            for message in messages {
                err.push_str(&format!("\n  logged: {message}"));
            }
            return Err(err.into());
        }
        Ok(Instance { fmu: self, component, _callbacks: callbacks, env })
    }
}

/// `file://` URI of an absolute path (percent-encoding what RFC 3986 does not allow).
fn file_uri(path: &Path) -> String {
    let mut uri = String::from("file://");
    for byte in path.to_string_lossy().bytes() {
        match byte {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'/' | b'-' | b'_' | b'.' | b'~' => {
                uri.push(byte as char)
            }
            _ => uri.push_str(&format!("%{byte:02X}")),
        }
    }
    uri
}

/// An FMU state handle from [`Instance::get_fmu_state`]; give it back to
/// [`Instance::free_fmu_state`] (the FMU frees what is left at `fmi2FreeInstance`).
pub struct FmuState(FmuStatePtr);

/// One instance of an FMU. Not `Send`: FMI 2.0 allows calls from one thread at a time only,
/// and the raw component pointer keeps it so.
pub struct Instance<'a> {
    fmu: &'a Fmu2,
    component: Component,
    // The FMU may hold pointers to these until fmi2FreeInstance (see Drop).
    _callbacks: Box<CallbackFunctions>,
    env: Box<Environment>,
}

#[allow(dead_code)] // the full wrapper is for every host in xtask; `fmu` uses a part of it
impl Instance<'_> {
    fn message_count(&self) -> usize {
        self.env.messages.lock().map(|m| m.len()).unwrap_or(0)
    }

    /// Every message the FMU has logged so far.
    pub fn messages(&self) -> Vec<LogMessage> {
        self.env.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }

    /// The result of a call: `Ok(status)` for OK and Warning (and Discard when
    /// `discard_ok`), else a [`CallError`] with what was logged since message `since`.
    fn check(
        &self,
        function: &'static str,
        raw: c_int,
        since: usize,
        discard_ok: bool,
    ) -> Result<Status> {
        match Status::from_raw(raw) {
            Some(status @ (Status::Ok | Status::Warning)) => Ok(status),
            Some(Status::Discard) if discard_ok => Ok(Status::Discard),
            status => {
                let messages = self
                    .env
                    .messages
                    .lock()
                    .map(|m| m.iter().skip(since).map(|m| m.to_string()).collect())
                    .unwrap_or_default();
                Err(Box::new(CallError { function, status, raw, messages }))
            }
        }
    }

    /// Calls `f` with the component and checks its status.
    fn call(
        &mut self,
        function: &'static str,
        discard_ok: bool,
        f: impl FnOnce(Component) -> c_int,
    ) -> Result<Status> {
        let since = self.message_count();
        let raw = f(self.component);
        self.check(function, raw, since, discard_ok)
    }

    /// `fmi2SetDebugLogging`; no categories means all of them.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<Status> {
        let owned: Vec<CString> = categories
            .iter()
            .map(|c| CString::new(*c))
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| "a category contains NUL")?;
        let pointers: Vec<Fmi2String> = owned.iter().map(|c| c.as_ptr()).collect();
        let f = self.fmu.api.set_debug_logging;
        // SAFETY: `pointers` holds `len` valid strings for the duration of the call.
        self.call("fmi2SetDebugLogging", false, |c| unsafe {
            f(c, fmi2_bool(on), pointers.len(), pointers.as_ptr())
        })
    }

    /// `fmi2SetupExperiment`; `None` leaves the tolerance or the stop time undefined.
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start: f64,
        stop: Option<f64>,
    ) -> Result<Status> {
        let f = self.fmu.api.setup_experiment;
        // SAFETY: plain values.
        self.call("fmi2SetupExperiment", false, |c| unsafe {
            f(
                c,
                fmi2_bool(tolerance.is_some()),
                tolerance.unwrap_or(0.0),
                start,
                fmi2_bool(stop.is_some()),
                stop.unwrap_or(0.0),
            )
        })
    }

    pub fn enter_initialization_mode(&mut self) -> Result<Status> {
        let f = self.fmu.api.enter_initialization_mode;
        // SAFETY: the component is live.
        self.call("fmi2EnterInitializationMode", false, |c| unsafe { f(c) })
    }

    pub fn exit_initialization_mode(&mut self) -> Result<Status> {
        let f = self.fmu.api.exit_initialization_mode;
        // SAFETY: the component is live.
        self.call("fmi2ExitInitializationMode", false, |c| unsafe { f(c) })
    }

    pub fn terminate(&mut self) -> Result<Status> {
        let f = self.fmu.api.terminate;
        // SAFETY: the component is live.
        self.call("fmi2Terminate", false, |c| unsafe { f(c) })
    }

    pub fn reset(&mut self) -> Result<Status> {
        let f = self.fmu.api.reset;
        // SAFETY: the component is live.
        self.call("fmi2Reset", false, |c| unsafe { f(c) })
    }

    pub fn get_real(&mut self, vrs: &[ValueReference], values: &mut [f64]) -> Result<Status> {
        lengths_match("fmi2GetReal", vrs.len(), values.len())?;
        let f = self.fmu.api.get_real;
        // SAFETY: both slices have `vrs.len()` elements.
        self.call("fmi2GetReal", false, |c| unsafe {
            f(c, vrs.as_ptr(), vrs.len(), values.as_mut_ptr())
        })
    }

    pub fn set_real(&mut self, vrs: &[ValueReference], values: &[f64]) -> Result<Status> {
        lengths_match("fmi2SetReal", vrs.len(), values.len())?;
        let f = self.fmu.api.set_real;
        // SAFETY: both slices have `vrs.len()` elements.
        self.call("fmi2SetReal", false, |c| unsafe {
            f(c, vrs.as_ptr(), vrs.len(), values.as_ptr())
        })
    }

    pub fn get_integer(&mut self, vrs: &[ValueReference], values: &mut [i32]) -> Result<Status> {
        lengths_match("fmi2GetInteger", vrs.len(), values.len())?;
        let f = self.fmu.api.get_integer;
        // SAFETY: both slices have `vrs.len()` elements.
        self.call("fmi2GetInteger", false, |c| unsafe {
            f(c, vrs.as_ptr(), vrs.len(), values.as_mut_ptr())
        })
    }

    pub fn set_integer(&mut self, vrs: &[ValueReference], values: &[i32]) -> Result<Status> {
        lengths_match("fmi2SetInteger", vrs.len(), values.len())?;
        let f = self.fmu.api.set_integer;
        // SAFETY: both slices have `vrs.len()` elements.
        self.call("fmi2SetInteger", false, |c| unsafe {
            f(c, vrs.as_ptr(), vrs.len(), values.as_ptr())
        })
    }

    pub fn get_boolean(&mut self, vrs: &[ValueReference], values: &mut [bool]) -> Result<Status> {
        lengths_match("fmi2GetBoolean", vrs.len(), values.len())?;
        let mut raw = vec![FMI2_FALSE; vrs.len()];
        let f = self.fmu.api.get_boolean;
        // SAFETY: both buffers have `vrs.len()` elements.
        let status = self.call("fmi2GetBoolean", false, |c| unsafe {
            f(c, vrs.as_ptr(), vrs.len(), raw.as_mut_ptr())
        })?;
        for (value, raw) in values.iter_mut().zip(raw) {
            *value = raw != FMI2_FALSE;
        }
        Ok(status)
    }

    pub fn set_boolean(&mut self, vrs: &[ValueReference], values: &[bool]) -> Result<Status> {
        lengths_match("fmi2SetBoolean", vrs.len(), values.len())?;
        let raw: Vec<Fmi2Boolean> = values.iter().map(|&b| fmi2_bool(b)).collect();
        let f = self.fmu.api.set_boolean;
        // SAFETY: both buffers have `vrs.len()` elements.
        self.call("fmi2SetBoolean", false, |c| unsafe {
            f(c, vrs.as_ptr(), vrs.len(), raw.as_ptr())
        })
    }

    /// `fmi2SetRealInputDerivatives`: `orders[k]`-th derivative of input `vrs[k]`.
    pub fn set_real_input_derivatives(
        &mut self,
        vrs: &[ValueReference],
        orders: &[i32],
        values: &[f64],
    ) -> Result<Status> {
        lengths_match("fmi2SetRealInputDerivatives", vrs.len(), values.len())?;
        lengths_match("fmi2SetRealInputDerivatives", vrs.len(), orders.len())?;
        let f = self.fmu.api.set_real_input_derivatives;
        // SAFETY: the three slices have `vrs.len()` elements.
        self.call("fmi2SetRealInputDerivatives", false, |c| unsafe {
            f(c, vrs.as_ptr(), vrs.len(), orders.as_ptr(), values.as_ptr())
        })
    }

    pub fn get_real_output_derivatives(
        &mut self,
        vrs: &[ValueReference],
        orders: &[i32],
        values: &mut [f64],
    ) -> Result<Status> {
        lengths_match("fmi2GetRealOutputDerivatives", vrs.len(), values.len())?;
        lengths_match("fmi2GetRealOutputDerivatives", vrs.len(), orders.len())?;
        let f = self.fmu.api.get_real_output_derivatives;
        // SAFETY: the three slices have `vrs.len()` elements.
        self.call("fmi2GetRealOutputDerivatives", false, |c| unsafe {
            f(c, vrs.as_ptr(), vrs.len(), orders.as_ptr(), values.as_mut_ptr())
        })
    }

    /// `fmi2DoStep`. `Ok(Status::Discard)` means only part of the step was done; ask
    /// [`Self::last_successful_time`] and [`Self::terminated`].
    pub fn do_step(&mut self, current: f64, step: f64, no_set_prior: bool) -> Result<Status> {
        let f = self.fmu.api.do_step;
        // SAFETY: plain values.
        self.call("fmi2DoStep", true, |c| unsafe { f(c, current, step, fmi2_bool(no_set_prior)) })
    }

    pub fn cancel_step(&mut self) -> Result<Status> {
        let f = self.fmu.api.cancel_step;
        // SAFETY: the component is live.
        self.call("fmi2CancelStep", false, |c| unsafe { f(c) })
    }

    /// `fmi2GetRealStatus(fmi2LastSuccessfulTime)`.
    pub fn last_successful_time(&mut self) -> Result<f64> {
        let mut value = f64::NAN;
        let f = self.fmu.api.get_real_status;
        // SAFETY: `value` is a valid out-pointer.
        self.call("fmi2GetRealStatus", false, |c| unsafe {
            f(c, StatusKind::LastSuccessfulTime as c_int, &mut value)
        })?;
        Ok(value)
    }

    /// `fmi2GetBooleanStatus(fmi2Terminated)`.
    pub fn terminated(&mut self) -> Result<bool> {
        let mut value = FMI2_FALSE;
        let f = self.fmu.api.get_boolean_status;
        // SAFETY: `value` is a valid out-pointer.
        self.call("fmi2GetBooleanStatus", false, |c| unsafe {
            f(c, StatusKind::Terminated as c_int, &mut value)
        })?;
        Ok(value != FMI2_FALSE)
    }

    /// `fmi2GetFMUstate` into a new state.
    pub fn get_fmu_state(&mut self) -> Result<FmuState> {
        let mut state: FmuStatePtr = std::ptr::null_mut();
        let f = self.fmu.api.get_fmu_state;
        // SAFETY: a NULL *state asks the FMU for a new one.
        self.call("fmi2GetFMUstate", false, |c| unsafe { f(c, &mut state) })?;
        if state.is_null() {
            return Err("fmi2GetFMUstate returned OK but no state".into());
        }
        Ok(FmuState(state))
    }

    /// `fmi2SetFMUstate`.
    pub fn set_fmu_state(&mut self, state: &FmuState) -> Result<Status> {
        let f = self.fmu.api.set_fmu_state;
        // SAFETY: `state` came from this instance (get or deserialize) and is not freed.
        self.call("fmi2SetFMUstate", false, |c| unsafe { f(c, state.0) })
    }

    /// `fmi2FreeFMUstate`.
    pub fn free_fmu_state(&mut self, state: FmuState) -> Result<Status> {
        let mut ptr = state.0;
        let f = self.fmu.api.free_fmu_state;
        // SAFETY: `state` came from this instance and is consumed here.
        self.call("fmi2FreeFMUstate", false, |c| unsafe { f(c, &mut ptr) })
    }

    /// `fmi2SerializedFMUstateSize` and `fmi2SerializeFMUstate`.
    pub fn serialize_fmu_state(&mut self, state: &FmuState) -> Result<Vec<u8>> {
        let mut size = 0usize;
        let f = self.fmu.api.serialized_fmu_state_size;
        // SAFETY: `state` is live; `size` is a valid out-pointer.
        self.call("fmi2SerializedFMUstateSize", false, |c| unsafe { f(c, state.0, &mut size) })?;
        let mut bytes = vec![0u8; size];
        let f = self.fmu.api.serialize_fmu_state;
        // SAFETY: `bytes` has `size` bytes.
        self.call("fmi2SerializeFMUstate", false, |c| unsafe {
            f(c, state.0, bytes.as_mut_ptr().cast(), size)
        })?;
        Ok(bytes)
    }

    /// `fmi2DeSerializeFMUstate` into a new state.
    pub fn deserialize_fmu_state(&mut self, bytes: &[u8]) -> Result<FmuState> {
        let mut state: FmuStatePtr = std::ptr::null_mut();
        let f = self.fmu.api.de_serialize_fmu_state;
        // SAFETY: `bytes` is valid for its length; a NULL *state asks for a new state.
        self.call("fmi2DeSerializeFMUstate", false, |c| unsafe {
            f(c, bytes.as_ptr().cast(), bytes.len(), &mut state)
        })?;
        if state.is_null() {
            return Err("fmi2DeSerializeFMUstate returned OK but no state".into());
        }
        Ok(FmuState(state))
    }
}

fn lengths_match(function: &str, vrs: usize, values: usize) -> Result {
    if vrs == values {
        Ok(())
    } else {
        Err(format!("{function}: {vrs} value references but {values} values").into())
    }
}

impl Drop for Instance<'_> {
    fn drop(&mut self) {
        // SAFETY: the component came from fmi2Instantiate and is freed exactly once; the
        // callbacks and the environment are dropped only after this call.
        unsafe { (self.fmu.api.free_instance)(self.component) }
    }
}

#[cfg(test)]
mod tests {
    use std::ffi::{c_void, CString};
    use std::path::Path;
    use std::sync::Mutex;

    use super::{file_uri, logger, Environment, Status};

    #[test]
    fn resource_uri_is_percent_encoded() {
        assert_eq!(file_uri(Path::new("/a b/c%d/é")), "file:///a%20b/c%25d/%C3%A9");
        assert_eq!(file_uri(Path::new("/work/x-1_y.z")), "file:///work/x-1_y.z");
    }

    /// The logger, called through its variadic type as C code calls it.
    #[test]
    fn logger_reads_the_message_of_a_percent_s_call() {
        let env = Environment { echo: false, messages: Mutex::new(Vec::new()) };
        let env_ptr = &env as *const Environment as *mut c_void;
        let name = CString::new("inst").unwrap();
        let category = CString::new("logStatusError").unwrap();
        let percent_s = CString::new("%s").unwrap();
        let message = CString::new("100% sure: a message").unwrap();
        let plain = CString::new("no format").unwrap();
        let log = logger();
        // SAFETY: the arguments are valid C strings, as the FMI logger expects.
        unsafe {
            log(env_ptr, name.as_ptr(), 3, category.as_ptr(), percent_s.as_ptr(), message.as_ptr());
            log(env_ptr, name.as_ptr(), 0, category.as_ptr(), plain.as_ptr());
        }
        let messages = env.messages.into_inner().unwrap();
        assert_eq!(messages.len(), 2);
        assert_eq!(messages[0].status, Some(Status::Error));
        assert_eq!(messages[0].category, "logStatusError");
        #[cfg(all(target_os = "linux", any(target_arch = "x86_64", target_arch = "aarch64")))]
        assert_eq!(messages[0].message, "100% sure: a message");
        assert_eq!(messages[1].status, Some(Status::Ok));
        assert_eq!(messages[1].message, "no format");
    }
}
