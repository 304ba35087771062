//! The project's tasks as a library: the helpers every task shares (paths, cargo, commands),
//! and the tasks of `cargo xtask` (build, package, generate, test). The benchmarks and the
//! verification experiments (`bench/`, crate `beam-body-bench`) use it too.

// The platform's sin, exp, powf, ... are fine here: xtask computes bounds and reports on this
// machine, while the library uses `beam_body::math` (clippy.toml).
#![allow(clippy::disallowed_methods)]

pub mod descriptions;
pub mod docs;
pub mod fmu;
pub mod fuzz;
pub mod generated;
pub mod import;
pub mod model_description;
pub mod model_description3;
pub mod platforms;
pub mod progress;
pub mod python;
pub mod study;
pub mod summary;
pub mod system;
pub mod test;
pub mod tools;
pub mod xml;

use std::env;
use std::error::Error;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus};

pub type Result<T = (), E = Box<dyn Error>> = std::result::Result<T, E>;

/// The full run of a long command or its `--quick` subset (`bench`, `sweep`).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Mode {
    Full,
    Quick,
}

impl Mode {
    /// No option: full; `--quick`: quick; anything else names `command` in its error.
    pub fn parse(command: &str, options: &[String]) -> Result<Mode> {
        match options {
            [] => Ok(Mode::Full),
            [option] if option == "--quick" => Ok(Mode::Quick),
            [option, ..] => {
                Err(format!("`{command}` has no option `{option}` (only --quick)").into())
            }
        }
    }
}

/// Writes `text` to `path`, naming the file in the error.
pub fn write_text(path: &Path, text: &str) -> Result {
    std::fs::write(path, text)
        .map_err(|err| format!("cannot write {}: {err}", relative(path)).into())
}

/// The workspace root: the parent of this crate's directory.
pub fn project_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in a subdirectory of the workspace")
        .to_path_buf()
}

/// Cargo's target directory (honours `CARGO_TARGET_DIR`).
pub fn target_dir() -> PathBuf {
    let root = project_root();
    match env::var_os("CARGO_TARGET_DIR") {
        Some(dir) => root.join(dir),
        None => root.join("target"),
    }
}

/// A `cargo` command: the cargo that invoked us (`CARGO`), run in the project root.
pub fn cargo<I, S>(args: I) -> Command
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    let mut cmd = Command::new(env::var_os("CARGO").unwrap_or_else(|| "cargo".into()));
    cmd.args(args).current_dir(project_root());
    cmd
}

/// `cargo run --release -p beam-body-bench -- COMMAND OPTIONS`: a benchmark or an experiment,
/// which live in their own crate (bench/).
pub fn bench(command: &str, options: &[String]) -> Result {
    let mut cmd = cargo(["run", "--quiet", "--release", "-p", "beam-body-bench", "--"]);
    cmd.arg(command).args(options);
    run_cmd(&mut cmd)
}

/// Builds `target/release/beam-body` and returns its absolute path.
pub fn build_release_binary() -> Result<PathBuf> {
    run_cmd(&mut cargo(["build", "--release", "--bin", "beam-body"]))?;
    Ok(target_dir().join("release").join("beam-body"))
}

/// Runs `cmd` with inherited stdio, echoing it first; a non-zero exit is an error.
pub fn run_cmd(cmd: &mut Command) -> Result {
    let status = status_of(cmd)?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{}` failed ({status})", display(cmd)).into())
    }
}

/// Runs `cmd` with inherited stdio, echoing it first, and returns how it ended.
pub fn status_of(cmd: &mut Command) -> Result<ExitStatus> {
    eprintln!("$ {}", display(cmd));
    let status = cmd
        .status()
        .map_err(|err| format!("could not run `{}`: {err}", cmd.get_program().to_string_lossy()))?;
    Ok(status)
}

/// `program arg1 arg2 ...`, for messages, with the program's path shortened.
pub fn display(cmd: &Command) -> String {
    let program = cmd.get_program();
    let program = if env::var_os("CARGO").is_some_and(|cargo| cargo == program) {
        "cargo".to_owned()
    } else {
        relative(Path::new(program))
    };
    let args = cmd.get_args().map(OsStr::to_string_lossy);
    std::iter::once(program.into()).chain(args).collect::<Vec<_>>().join(" ")
}

/// `path` relative to the project root when it is inside it, for messages.
pub fn relative(path: &Path) -> String {
    let root = project_root();
    path.strip_prefix(&root).unwrap_or(path).display().to_string()
}
