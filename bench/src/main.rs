//! Benchmarks and verification experiments of beam-body, apart from the tasks that build,
//! package and test it (xtask). `cargo xtask bench`, `bench-ab`, `bench-dostep`, `bench-study`,
//! `sweep`, `figures` and `profile` run this binary; `cargo xtask help` describes each.
//!
//! It reads the model and the scenes as the CLI does (`beam_body`, feature `cli`), and the
//! packaged FMU through xtask's native FMI host.

// The platform's sin, exp, powf, ... are fine here: the experiments compute references, bounds
// and reports on this machine, while the library uses `beam_body::math` (clippy.toml).
#![allow(clippy::disallowed_methods)]

mod ab;
mod bench;
mod figures;
mod profile;
mod sweep;

// xtask's helpers, under the names the experiments have always used.
pub use xtask::{
    build_release_binary, cargo, fmu, import, progress, project_root, python, relative, run_cmd,
    system, target_dir, write_text, Mode, Result,
};

use std::env;
use std::process::{Command, ExitCode};

fn main() -> ExitCode {
    let args: Vec<String> = env::args().skip(1).collect();
    let (command, options) = match args.split_first() {
        Some((command, options)) => (command.as_str(), options),
        None => ("", &[][..]),
    };
    let result = match command {
        "bench" => Mode::parse(command, options).and_then(bench::run),
        "bench-elements" => Mode::parse(command, options).and_then(bench::elements::run),
        "bench-exact" => Mode::parse(command, options).and_then(bench::exact::run),
        "bench-elements-run" => {
            Mode::parse(command, options).and_then(bench::elements::run_measure)
        }
        "bench-run" => bench::parse_round(options).and_then(bench::run_round),
        "bench-ab" => ab::run(options),
        "bench-dostep" => Mode::parse(command, options).and_then(bench::run_dostep),
        "bench-study" => Mode::parse(command, options).and_then(|m| bench_study(m == Mode::Quick)),
        "sweep" => sweep::run(options),
        "sweep-case" => sweep::run_case(options),
        "figures" => no_options(command, options).and_then(|()| figures::run()),
        "profile" => no_options(command, options).and_then(|()| profile::run()),
        "cvode-lib" => no_options(command, options).and_then(|()| bench::print_cvode_lib()),
        other => Err(format!("unknown command `{other}`; run `cargo xtask help`").into()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err}");
            ExitCode::FAILURE
        }
    }
}

fn no_options(command: &str, options: &[String]) -> Result {
    match options.first() {
        None => Ok(()),
        Some(option) => {
            Err(format!("`{command}` takes no option `{option}`; run `cargo xtask help`").into())
        }
    }
}

/// `cargo xtask bench-study [--quick]`: bench/python/bench_study.py (the runners side by side).
fn bench_study(quick: bool) -> Result {
    let python = python::ensure_venv()?;
    let binary = build_release_binary()?;
    let root = project_root();
    let mut cmd = Command::new(python);
    cmd.arg(root.join("bench").join("python").join("bench_study.py"))
        .args(quick.then_some("--quick"))
        .env("BEAM_BODY_BIN", binary)
        .env("PYTHONPATH", xtask::study::python_path())
        .current_dir(&root);
    run_cmd(&mut cmd)
}
