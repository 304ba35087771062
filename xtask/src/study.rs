//! `cargo xtask study ARGS...`: the study tool (python/beam_body_study) from a fresh clone.

use std::env;
use std::ffi::OsString;
use std::process::Command;

use crate::{build_release_binary, project_root, python, status_of, Result};

/// `python -m beam_body_study ARGS` in target/venv, with the release CLI, in the caller's
/// directory (so that relative paths are the caller's).
pub fn run(args: &[String]) -> Result {
    if args.is_empty() {
        return Err("`study` needs a command of the study tool: run, plot, or --help \
                    (cargo xtask study run examples/turn_map.toml -o target/study/turn_map.parquet)"
            .into());
    }
    module("beam_body_study", args, "the study tool")
}

/// `cargo xtask model-error [--quick]`: the model's error against run time
/// (python/beam_body_study/model_error.py); the full run writes docs/model_error.{md,png}.
pub fn model_error(args: &[String]) -> Result {
    let mut args = args.to_vec();
    if !args.iter().any(|a| a == "--quick" || a == "--docs" || a == "-h" || a == "--help") {
        args.extend(["--docs".into(), project_root().join("docs").display().to_string()]);
    }
    module("beam_body_study.model_error", &args, "model-error")
}

/// `python -m MODULE ARGS` in target/venv with the release CLI.
fn module(module: &str, args: &[String], what: &str) -> Result {
    let python = python::ensure_venv()?;
    let binary = build_release_binary()?;
    let mut cmd = Command::new(python);
    cmd.args(["-m", module])
        .args(args)
        .env("BEAM_BODY_BIN", binary)
        .env("PYTHONPATH", python_path());
    let status = status_of(&mut cmd)?;
    match status.code() {
        Some(0) => Ok(()),
        _ => Err(format!("{what} failed ({status})").into()),
    }
}

/// python/ first, then what PYTHONPATH held.
pub fn python_path() -> OsString {
    let mut paths = vec![project_root().join("python")];
    if let Some(old) = env::var_os("PYTHONPATH") {
        paths.extend(env::split_paths(&old));
    }
    env::join_paths(paths).unwrap_or_else(|_| project_root().join("python").into_os_string())
}
