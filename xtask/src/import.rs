//! The native FMI 2.0 and 3.0 host: the importers of the `fmi` crate (rust-fmi), which dlopen
//! the FMU's binary and call it through the C ABI as a simulation tool does, and what xtask
//! adds:
//!
//! - [`Fmu2::load`] opens an *extracted* FMU. The importer opens only a .fmu, which it
//!   extracts into a temporary directory of its own ([`fmi::import::from_path`]); here that
//!   directory holds symbolic links to the extracted `binaries/` (and `resources/`), so the
//!   importer loads the packaged .so where it was extracted.
//! - [`Fmu2`] keeps one binding of the library open, so that it stays loaded between instances
//!   (each instance opens the library again; dlopen counts references).
//! - The FMU's log messages: fmi-sys formats them (its `logger.c`) and hands them to the `log`
//!   crate, the instance name as the target, the status as the level (the category is
//!   dropped). The logger here prints warnings and errors to stderr and keeps the last
//!   messages, which [`Call::call`] appends to the error of a failed call.
//! - [`Call::call`]: rust-fmi's `Fmi2Error` reads "Error" or "Discard" only; the error of a
//!   call names the function and what the FMU logged.

use std::collections::VecDeque;
use std::fmt;
use std::path::Path;
use std::sync::{Mutex, Once};

use fmi::fmi2::binding::Fmi2Binding;
use fmi::fmi2::import::Fmi2Import;
pub use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS, InstanceME, ModelExchange};
pub use fmi::fmi2::Fmi2Error;
use fmi::fmi2::{Fmi2Res, Fmi2Status};
use fmi::fmi3::binding::Fmi3Binding;
use fmi::fmi3::import::Fmi3Import;
pub use fmi::fmi3::instance::InstanceCS as InstanceCS3;
pub use fmi::fmi3::{
    CoSimulation as CoSimulation3, Common as Common3, Fmi3Error, Fmi3Model, GetSet as GetSet3,
};
use fmi::traits::{FmiImport, FmiStatus};
pub use fmi::EventFlags;
use tempfile::TempDir;

use crate::{relative, Result};

/// A loaded FMU: the importer, and the library it loaded.
pub struct Fmu2 {
    import: Fmi2Import,
    /// Keeps the .so loaded while the FMU is (see the module's documentation).
    _library: Fmi2Binding,
}

impl Fmu2 {
    /// Loads the FMU extracted in `dir`: `modelDescription.xml` and this machine's library,
    /// `binaries/linux64/<modelIdentifier>.so` on Linux x86-64 (rust-fmi picks the folder).
    pub fn load(dir: &Path) -> Result<Fmu2> {
        let (import, library) = load::<Fmi2Import>(dir, |import| {
            import.model_description().co_simulation.as_ref().map(|cs| cs.model_identifier.clone())
        })?;
        Ok(Fmu2 { import, _library: library })
    }

    /// `fmi2Instantiate` as co-simulation, with the modelDescription's GUID, rust-fmi's logger,
    /// calloc/free and the `resources` URI; not visible.
    pub fn instantiate(&self, name: &str, logging_on: bool) -> Result<InstanceCS> {
        take_messages();
        self.import.instantiate_cs(name, false, logging_on).map_err(instantiation_error)
    }

    /// [`instantiate`](Self::instantiate) as Model Exchange.
    pub fn instantiate_me(&self, name: &str, logging_on: bool) -> Result<InstanceME> {
        take_messages();
        self.import.instantiate_me(name, false, logging_on).map_err(instantiation_error)
    }
}

/// The importer of the FMU extracted in `dir` (either version) and its library, loaded from
/// the folder of this machine; `cs_id` gives the co-simulation's modelIdentifier.
fn load<I: FmiImport>(dir: &Path, cs_id: impl Fn(&I) -> Option<String>) -> Result<(I, I::Binding)> {
    let (md, xml, dir, links) = linked(dir)?;
    let import = I::new(links, &xml).map_err(|err| format!("{}: {err}", relative(&md)))?;
    let id = cs_id(&import).ok_or_else(|| format!("{} has no CoSimulation", relative(&md)))?;
    let so = dir.join(import.shared_lib_path(&id)?);
    let library =
        import.binding(&id).map_err(|err| format!("cannot load {}: {err}", relative(&so)))?;
    Ok((import, library))
}

/// The logger, set once; the extracted FMU in `dir`: its modelDescription's path and text, the
/// directory, and a temporary directory that links to its `binaries/` and `resources/`.
fn linked(dir: &Path) -> Result<(std::path::PathBuf, String, std::path::PathBuf, TempDir)> {
    static LOGGER: Once = Once::new();
    LOGGER.call_once(|| {
        if log::set_logger(&MESSAGES).is_ok() {
            log::set_max_level(log::LevelFilter::Warn);
        }
    });
    let md = dir.join("modelDescription.xml");
    let xml = std::fs::read_to_string(&md)
        .map_err(|err| format!("cannot read {}: {err}", relative(&md)))?;
    let dir = std::path::absolute(dir)?;
    let links = tempfile::Builder::new().prefix("xtask-fmu-").tempdir()?;
    for name in ["binaries", "resources"] {
        let (target, link) = (dir.join(name), links.path().join(name));
        if target.exists() {
            #[cfg(unix)]
            std::os::unix::fs::symlink(&target, &link)?;
            #[cfg(windows)]
            std::os::windows::fs::symlink_dir(&target, &link)?;
        }
    }
    Ok((md, xml, dir, links))
}

fn instantiation_error(err: fmi::Error) -> Box<dyn std::error::Error> {
    let text = match err {
        fmi::Error::Instantiation => "fmi2Instantiate returned NULL".to_string(),
        err => format!("fmi2Instantiate: {err}"),
    };
    with_messages(text).into()
}

/// A loaded FMI 3.0 FMU (`BeamBody-fmi3.fmu` extracted): the importer, and its library.
pub struct Fmu3 {
    import: Fmi3Import,
    _library: Fmi3Binding,
}

impl Fmu3 {
    /// Loads the FMU extracted in `dir`, this machine's library from its platform-tuple
    /// folder (`binaries/x86_64-linux/` on Linux x86-64).
    pub fn load(dir: &Path) -> Result<Fmu3> {
        let (import, library) = load::<Fmi3Import>(dir, |import| {
            import.model_description().co_simulation.as_ref().map(|cs| cs.model_identifier.clone())
        })?;
        Ok(Fmu3 { import, _library: library })
    }

    /// `fmi3InstantiateCoSimulation` with the instantiationToken, without event mode, early
    /// return or intermediate variables.
    pub fn instantiate(&self, name: &str) -> Result<InstanceCS3> {
        take_messages();
        self.import.instantiate_cs(name, false, false, false, false, &[]).map_err(|err| {
            let text = match err {
                fmi::Error::Instantiation => "fmi3InstantiateCoSimulation returned NULL".into(),
                err => format!("fmi3InstantiateCoSimulation: {err}"),
            };
            with_messages(text).into()
        })
    }
}

impl<T> Call<T> for std::result::Result<T, Fmi3Error> {
    fn call(self, function: &str) -> Result<T> {
        self.map_err(|err| with_messages(format!("{function} returned fmi3{err}")).into())
    }
}

/// What a call returned, as xtask's `Result`.
pub trait Call<T> {
    /// OK and Warning are `Ok`; else an error that names `function` and lists what the FMU
    /// logged since the last error (or `fmi2Instantiate`).
    fn call(self, function: &str) -> Result<T>;
}

impl<T> Call<T> for std::result::Result<T, Fmi2Error> {
    fn call(self, function: &str) -> Result<T> {
        self.map_err(|err| {
            let text = match err {
                Fmi2Error::Discard | Fmi2Error::Error | Fmi2Error::Fatal => {
                    format!("{function} returned fmi2{err}")
                }
                err => format!("{function}: {err}"),
            };
            with_messages(text).into()
        })
    }
}

impl Call<Fmi2Res> for Fmi2Status {
    fn call(self, function: &str) -> Result<Fmi2Res> {
        self.ok().call(function)
    }
}

fn with_messages(mut text: String) -> String {
    for message in take_messages() {
        text.push_str(&format!("\n  logged: {message}"));
    }
    text
}

/// One message of the FMU, as fmi-sys passes it on.
#[derive(Clone, Debug)]
pub struct LogMessage {
    pub instance: String,
    pub level: log::Level,
    pub message: String,
}

impl fmt::Display for LogMessage {
    /// `[status] message`, the status as fmi-sys's level tells it.
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let status = match self.level {
            log::Level::Info => "fmi2OK",
            log::Level::Warn => "fmi2Warning",
            log::Level::Trace => "fmi2Discard",
            log::Level::Error => "fmi2Error or fmi2Fatal",
            log::Level::Debug => "unknown status",
        };
        write!(f, "[{status}] {}", self.message)
    }
}

/// The messages logged since the last error (or `fmi2Instantiate`), oldest first.
pub fn take_messages() -> Vec<LogMessage> {
    MESSAGES.0.lock().map(|mut m| m.drain(..).collect()).unwrap_or_default()
}

/// At most this many messages are kept.
const KEPT: usize = 100;

struct Messages(Mutex<VecDeque<LogMessage>>);

static MESSAGES: Messages = Messages(Mutex::new(VecDeque::new()));

impl log::Log for Messages {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }

    /// fmi-sys passes the FMU's messages with the module path "logger", straight to the
    /// logger (no level filter); anything else comes from rust-fmi itself (warnings and
    /// errors, by the max level set in [`Fmu2::load`]).
    fn log(&self, record: &log::Record) {
        if record.module_path() != Some("logger") {
            eprintln!("{}: {}", record.target(), record.args());
            return;
        }
        let message = LogMessage {
            instance: record.target().to_owned(),
            level: record.level(),
            message: record.args().to_string(),
        };
        if message.level <= log::Level::Warn {
            eprintln!("FMU {}: {message}", message.instance);
        }
        if let Ok(mut messages) = self.0.lock() {
            if messages.len() == KEPT {
                messages.pop_front();
            }
            messages.push_back(message);
        }
    }

    fn flush(&self) {}
}

#[cfg(test)]
mod tests {
    use super::{take_messages, Call, Fmi2Error, MESSAGES};

    /// A message as fmi-sys's `callback_log` sends it, then the error of a failed call.
    #[test]
    fn failed_call_lists_the_logged_messages() {
        let _ = log::set_logger(&MESSAGES);
        take_messages();
        log::logger().log(
            &log::Record::builder()
                .args(format_args!("fmi2DoStep: 100% out of range"))
                .level(log::Level::Trace)
                .module_path(Some("logger"))
                .target("inst")
                .build(),
        );
        let err = Err::<(), _>(Fmi2Error::Discard).call("fmi2DoStep").unwrap_err();
        assert_eq!(
            err.to_string(),
            "fmi2DoStep returned fmi2Discard\n  logged: [fmi2Discard] fmi2DoStep: 100% out of range"
        );
        assert!(take_messages().is_empty());
    }
}
