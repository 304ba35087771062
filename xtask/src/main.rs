//! Project tasks: `cargo xtask <command>`. See `cargo xtask help`.
//!
//! The alias runs the launcher (`xtask/launch`) first, which makes sure libclang is there for
//! fmi-sys's bindgen, then this crate. Its dependencies: the interface tables of the library
//! (`beam_body::fmu::variables`), quick-xml, zip, fmi (the native FMI host, with log and
//! tempfile), libloading and nalgebra, and diffsol with the feature `bench` only (see
//! Cargo.toml for why each).

// The platform's sin, exp, powf, ... are fine here: xtask computes references, bounds and
// reports on this machine, while the library uses `beam_body::math` (clippy.toml).
#![allow(clippy::disallowed_methods)]

mod ab;
mod bench;
mod docs;
mod figures;
mod fmu;
mod fuzz;
mod import;
mod model_description;
mod platforms;
mod profile;
mod progress;
mod python;
mod study;
mod summary;
mod sweep;
mod system;
mod test;
mod xml;

use std::env;
use std::error::Error;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, ExitStatus};

type Result<T = (), E = Box<dyn Error>> = std::result::Result<T, E>;

const HELP: &str = "\
Usage: cargo xtask <command> [options]

Commands:
  test [--rust-only | --python-only]
          Run the whole test suite: set up the Python venv (target/venv),
          build the release binary, run the Rust tests and the Python tests.
  gen     Write modelDescription/modelDescription.xml from the interface tables
          (src/fmi2/variables.rs). Commit the result; a test fails when it is stale.
  fmu [--all-platforms]
          Build and check the FMU, target/fmu/BeamBody.fmu:
          - refuse a stale modelDescription.xml;
          - run the paper's scene (scenes/paper.toml) through the standalone solver,
            the reference (target/fmu/paper.csv);
          - build the library (cargo rustc --release --lib --no-default-features
            --crate-type cdylib) and zip
            modelDescription.xml, binaries/linux64/BeamBody.so and
            documentation/index.html;
          - --all-platforms: also cross-build win64, macOS (x86_64 and arm64) and Linux
            aarch64 with Debian's Rust (installing the toolchains with apt-get as root),
            into BeamBody.fmu (binaries/win64, darwin64 universal, aarch64-darwin,
            aarch64-linux) and target/fmu/BeamBody-aarch64-linux.fmu (the aarch64
            library in binaries/linux64, where FMPy looks on Linux aarch64);
          - validate it with FMPy when target/venv exists;
          - extract it to target/fmu/BeamBody/, load the .so there with a native FMI 2.0
            host, run the same scene through it (target/fmu/paper_fmu.csv) and compare.
  bench [--quick]
          The work-precision benchmark (error against run time, target/bench/):
          - set up target/venv with xtask/python/requirements-bench.txt, package the
            FMU, build CVODE 7.1.1 at -O3 from the sundials-sys crate's C sources
            (once; Debian's -O0 libsundials through apt-get only if that fails);
          - write the cases (target/bench/cases.csv): solvers bdf, bdf-fixed, cvode,
            diffsol, fmu, scipy-bdf, scipy-radau, scipy-lsoda on the scenes paper,
            paper-dae, paper-dae-stabilized and stiff;
          - compute the reference solutions once (cached in target/bench/ref/);
          - a warm-up round, then 10 timed rounds (3 with --quick), each running every
            Rust case in one release process and every SciPy case in one Python process,
            in a shuffled order;
          - write work_precision.csv, .png and .md, and copy the figure and the table
            to docs/;
          - then the cost of one fmi2DoStep (bench-dostep, below).
          --quick: fewer tolerances and steps and 3 rounds (a few minutes).
  bench-dostep [--quick]
          The cost of one fmi2DoStep alone, the last part of `bench`: a bare C host
          (tests/c_host/host.c) on the packaged FMU, the paper's scene at tolerance 1e-6,
          communication steps 1e-2, 1e-3, 1e-4 s, for each way phi arrives (law, values,
          values with derivatives, taylor) against the fixed-step BDF2 floor; 10 rounds
          (3 with --quick); target/bench/dostep.{csv,md}, and docs/dostep.md in the full run.
  bench-run --round K
          One round of the benchmark's Rust cases (used by `bench`, in a release build
          with --features bench): run the cases of target/bench/cases.csv in an order
          shuffled with seed K and append to target/bench/raw.csv; round 0 (the warm-up)
          also writes the solutions (target/bench/sol/) and target/bench/costs.csv.
  bench-ab [REV] [--rounds R] [--sample SCENE FORMULATION RTOL]
          The time per step of the library at git revision REV (default HEAD) against
          the working tree's: a small runner (xtask/ab/runner.rs) built against each
          (target/ab/), both run at the same time, one per core, swapping cores and
          start order every round; ten cases (paper, paper-dae, paper-dae-stabilized at
          rtol 1e-4, 1e-6, 1e-8; stiff at 1e-4); the median per case over R rounds
          (default 8) and the ratio REV / tree. --sample: the working tree's runner
          alone on one case (e.g. paper reduced 1e-6) for 40 s under SIGPROF, the
          time by line of src/.
  sweep [--quick | --group NAME]
          Stiff and extreme cases (first cut; target/sweep/sweep.{csv,md}): stiffness,
          mass, turn, gravity, tolerance, guard, horizon, communication and phi step
          groups, each case in a child process under a time limit, against an explicit
          Dormand-Prince 5(4) reference. --quick: a subset that fails on an unexpected
          status; --group: one group.
  sweep-case ID
          Run one sweep case and print its result line (used by `sweep`).
  fuzz [--time SECONDS] [TARGET...]
          Build the libFuzzer targets of fuzz/ (deserialize: fmi2DeSerializeFMUstate on
          arbitrary bytes; api_sequence: random sequences of fmi2 calls) with coverage
          instrumentation on stable Rust, and run each for SECONDS (default 600) on its
          corpus in target/fuzz/corpus/, replaying fuzz/regressions/. A failing input
          is written to target/fuzz/artifacts/ and fails the command. `cargo xtask test`
          runs each target for 15 s.
  figures The paper's Fig. 3 and a drawing of the model:
          - run scenes/paper.toml at rtol 1e-8 in the formulations reduced (eq. 15),
            dae (eq. 20+21) and linear (eq. 16), output every Δτ = 0.005 up to τ = 12;
          - write target/figures/figure3.csv and the measured numbers (extremes,
            (15) against (20)+(21) and (16), integration error, small-oscillation
            periods) to target/figures/figure3.txt; fail if (15) and (20)+(21) differ
            by 1e-3 of the scale or more, or (16) from (15) by 0.5 of it or less;
          - draw docs/figure3.png and docs/model.png (xtask/python/figures.py).
          The claims are tested by `cargo test -p xtask figures` (run by `test`).
  study ARGS...
          The study tool (python/beam_body_study, README: Design studies) with the
          release CLI, in target/venv: `study run STUDY.toml -o OUT.parquet [--engine
          dask [--scheduler ADDRESS]]`, `study plot heatmap|hist ...`, `study --help`.
  bench-study [--quick]
          Throughput of the study runners side by side (xtask/python/bench_study.py):
          a 10^4-case study through the native runner on 1 and 2 threads, the chunked
          local engine, a LocalCluster of 1 and 2 workers and a loopback scheduler with
          2 worker processes; the overhead of a chunk's CLI call; 5 shuffled rounds
          (2 with --quick); target/bench/study.{csv,md}, and docs/study.md in the full run.
  profile Where the integrator's instructions go, per accepted step: callgrind on
          one run of each benchmark scene at rtol 1e-6 (a release build with symbols in
          target/prof), by the source line of each instruction: the integrator, the
          coefficients, the model, sin and cos, log/exp/pow, LU, the guard
          (xtask/python/profile_step.py); target/prof/profile.md.
  setup   Install what the build and the whole suite need beyond Rust and Python:
          the launcher that `cargo xtask` runs first (xtask/launch) installs
          libclang-dev (bindgen in fmi-sys) when libclang is missing; then the Debian
          packages of `test` (cc, g++, valgrind; the cross toolchains of
          `fmu --all-platforms`; wine, qemu-user, libtbb12), with apt-get when running
          as root (otherwise it names them). .ci/run runs it before clippy.
  help    Print this message.
";

fn main() -> ExitCode {
    match run(&env::args().skip(1).collect::<Vec<_>>()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: &[String]) -> Result {
    let (command, options) = match args.split_first() {
        Some((command, options)) => (command.as_str(), options),
        None => ("help", &[][..]),
    };
    match command {
        "help" | "-h" | "--help" => {
            no_options(command, options)?;
            print!("{HELP}");
            Ok(())
        }
        // Everything it does today, the launcher did before this process started.
        "setup" => {
            no_options(command, options)?;
            test::system_packages()
        }
        "test" => test::run(test::Scope::parse(options)?),
        "gen" => {
            no_options(command, options)?;
            model_description::run()
        }
        "fmu" => match options {
            [] => fmu::run(false),
            [option] if option == "--all-platforms" => fmu::run(true),
            [option, ..] => Err(format!(
                "`fmu` has no option `{option}` (only --all-platforms); run `cargo xtask help`"
            )
            .into()),
        },
        "bench" => bench::run(Mode::parse(command, options)?),
        "bench-run" => bench::run_round(bench::parse_round(options)?),
        "bench-ab" => ab::run(options),
        "bench-dostep" => bench::run_dostep(Mode::parse(command, options)?),
        "sweep" => sweep::run(options),
        "sweep-case" => sweep::run_case(options),
        "fuzz" => fuzz::run(options),
        "figures" => {
            no_options(command, options)?;
            figures::run()
        }
        "study" => study::run(options),
        "bench-study" => study::bench(Mode::parse(command, options)? == Mode::Quick),
        "profile" => {
            no_options(command, options)?;
            profile::run()
        }
        other => Err(format!("unknown command `{other}`; run `cargo xtask help`").into()),
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
fn write_text(path: &Path, text: &str) -> Result {
    std::fs::write(path, text)
        .map_err(|err| format!("cannot write {}: {err}", relative(path)).into())
}

/// The workspace root: the parent of this crate's directory.
fn project_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in a subdirectory of the workspace")
        .to_path_buf()
}

/// Cargo's target directory (honours `CARGO_TARGET_DIR`).
fn target_dir() -> PathBuf {
    let root = project_root();
    match env::var_os("CARGO_TARGET_DIR") {
        Some(dir) => root.join(dir),
        None => root.join("target"),
    }
}

/// A `cargo` command: the cargo that invoked us (`CARGO`), run in the project root.
fn cargo<I, S>(args: I) -> Command
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    let mut cmd = Command::new(env::var_os("CARGO").unwrap_or_else(|| "cargo".into()));
    cmd.args(args).current_dir(project_root());
    cmd
}

/// Builds `target/release/beam-body` and returns its absolute path.
fn build_release_binary() -> Result<PathBuf> {
    run_cmd(&mut cargo(["build", "--release", "--bin", "beam-body"]))?;
    Ok(target_dir().join("release").join("beam-body"))
}

/// Runs `cmd` with inherited stdio, echoing it first; a non-zero exit is an error.
fn run_cmd(cmd: &mut Command) -> Result {
    let status = status_of(cmd)?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{}` failed ({status})", display(cmd)).into())
    }
}

/// Runs `cmd` with inherited stdio, echoing it first, and returns how it ended.
fn status_of(cmd: &mut Command) -> Result<ExitStatus> {
    eprintln!("$ {}", display(cmd));
    let status = cmd
        .status()
        .map_err(|err| format!("could not run `{}`: {err}", cmd.get_program().to_string_lossy()))?;
    Ok(status)
}

/// `program arg1 arg2 ...`, for messages, with the program's path shortened.
fn display(cmd: &Command) -> String {
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
fn relative(path: &Path) -> String {
    let root = project_root();
    path.strip_prefix(&root).unwrap_or(path).display().to_string()
}
