//! `cargo xtask test`: the whole test suite, from a fresh clone.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::fmu::Packages;
use crate::{build_release_binary, cargo, project_root, python, run_cmd, status_of, Result};

/// Which half of the suite to run.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    All,
    RustOnly,
    PythonOnly,
}

impl Scope {
    pub fn parse(options: &[String]) -> Result<Scope> {
        match options {
            [] => Ok(Scope::All),
            [option] if option == "--rust-only" => Ok(Scope::RustOnly),
            [option] if option == "--python-only" => Ok(Scope::PythonOnly),
            [option] => Err(format!(
                "`test` has no option `{option}` (expected --rust-only or --python-only)"
            )
            .into()),
            _ => Err("`test` takes at most one option: --rust-only or --python-only".into()),
        }
    }
}

pub fn run(scope: Scope) -> Result {
    let mut report = Report::default();
    if scope == Scope::RustOnly {
        report.step("rust tests", rust_tests);
        return report.finish();
    }
    report.step("system packages", system_packages);
    let python = report.step("python venv", python::ensure_venv);
    let binary = report.step("build beam-body (release)", build_release_binary);
    let fmu = report.step("package the FMUs (all platforms)", || crate::fmu::build_package(true));
    let fmi_sim = report.step("fmi-sim (rust-fmi's host)", crate::tools::ensure_fmi_sim);
    if scope == Scope::All {
        report.step("rust tests", rust_tests);
        report.step("rust tests against CVODE", cvode_tests);
        report.step("rust tests (aarch64, qemu)", crate::platforms::test_linux_aarch64);
        // The sweep's representative subset: every row must end as expected (ok within its
        // error bound, or stopped with the expected message).
        report.step("sweep --quick", || crate::bench("sweep", &["--quick".to_string()]));
        // Each fuzz target for a few seconds, replaying fuzz/regressions/ first.
        report.step("fuzz smoke", crate::fuzz::smoke);
    }
    match (python, binary, fmu) {
        (Some(python), Some(binary), Some(fmu)) => {
            report.step("python tests", || pytest(&python, &binary, &fmu, fmi_sim.as_deref()));
        }
        _ => report.skip("python tests", "needs the venv, the release binary and the FMU"),
    }
    report.finish()
}

/// Installs the system packages the suite needs (apt-get as root on Debian), or names them.
pub fn system_packages() -> Result {
    use crate::system::{ensure, CROSS_TOOLCHAINS, FOREIGN_RUNNERS, TEST_TOOLS};
    ensure("cargo xtask test", &[TEST_TOOLS, CROSS_TOOLCHAINS, FOREIGN_RUNNERS])
}

fn rust_tests() -> Result {
    if nextest_available() {
        run_cmd(&mut cargo(["nextest", "run", "--workspace", "--release"]))?;
        // nextest does not run doctests.
        run_cmd(&mut cargo(["test", "--workspace", "--release", "--doc"]))
    } else {
        eprintln!("cargo-nextest is not installed; using cargo test");
        run_cmd(&mut cargo(["test", "--workspace", "--release"]))
    }
}

/// The benchmark crate's tests that compare with CVODE (ignored by a plain `cargo test`,
/// which reports them so): CVODE built from source as the benchmark builds it, then every
/// ignored test of the crate run with `BEAM_BODY_CVODE_LIB` naming it. A library that cannot
/// be built fails the step.
fn cvode_tests() -> Result {
    let mut build =
        cargo(["run", "--quiet", "--release", "-p", "beam-body-bench", "--", "cvode-lib"]);
    eprintln!("$ {}", crate::display(&build));
    let out = build.stderr(Stdio::inherit()).output()?;
    if !out.status.success() {
        return Err(format!("building CVODE failed ({})", out.status).into());
    }
    let lib = String::from_utf8(out.stdout)?.trim().to_string();
    let mut tests = if nextest_available() {
        cargo(["nextest", "run", "-p", "beam-body-bench", "--release", "--run-ignored", "only"])
    } else {
        cargo(["test", "-p", "beam-body-bench", "--release", "--", "--ignored"])
    };
    run_cmd(tests.env("BEAM_BODY_CVODE_LIB", lib))
}

fn nextest_available() -> bool {
    cargo(["nextest", "--version"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|status| status.success())
}

fn pytest(python: &Path, binary: &Path, fmu: &Packages, fmi_sim: Option<&Path>) -> Result {
    let root = project_root();
    let mut cmd = Command::new(python);
    cmd.args(["-m", "pytest", "tests/python", "-q", "-ra"])
        .env("BEAM_BODY_BIN", binary)
        .env("BEAM_BODY_FMU", &fmu.main)
        .env("BEAM_BODY_FMU_FMI3", &fmu.fmi3)
        .env("BEAM_BODY_ROOT", &root)
        .envs(fmu.aarch64_linux.iter().map(|p| ("BEAM_BODY_FMU_AARCH64_LINUX", p)))
        .envs(fmi_sim.map(|p| ("BEAM_BODY_FMI_SIM", p)))
        .current_dir(&root);
    let status = status_of(&mut cmd)?;
    match status.code() {
        Some(0) => Ok(()),
        Some(5) => Err("pytest collected no tests in tests/python (exit status: 5)".into()),
        _ => Err(format!("pytest failed ({status})").into()),
    }
}

/// The outcome of each step, printed one line per step at the end.
#[derive(Default)]
struct Report {
    steps: Vec<(&'static str, Outcome)>,
}

enum Outcome {
    Passed(Duration),
    Failed(Duration, String),
    Skipped(&'static str),
}

impl Report {
    /// Runs one step; its failure is reported but does not stop the others.
    fn step<T>(&mut self, name: &'static str, f: impl FnOnce() -> Result<T>) -> Option<T> {
        eprintln!("\n==> {name}");
        let start = Instant::now();
        let result = f();
        let elapsed = start.elapsed();
        match result {
            Ok(value) => {
                self.steps.push((name, Outcome::Passed(elapsed)));
                Some(value)
            }
            Err(err) => {
                eprintln!("error: {err}");
                self.steps.push((name, Outcome::Failed(elapsed, err.to_string())));
                None
            }
        }
    }

    fn skip(&mut self, name: &'static str, reason: &'static str) {
        self.steps.push((name, Outcome::Skipped(reason)));
    }

    fn finish(self) -> Result {
        eprintln!("\n==> summary");
        let mut bad = 0;
        for (name, outcome) in &self.steps {
            let line = match outcome {
                Outcome::Passed(time) => {
                    format!("ok       {name:<26} {:>7.1} s", time.as_secs_f64())
                }
                Outcome::Failed(time, err) => {
                    let first_line = err.lines().next().unwrap_or_default();
                    format!("FAILED   {name:<26} {:>7.1} s  {first_line}", time.as_secs_f64())
                }
                Outcome::Skipped(reason) => format!("skipped  {name:<26} {:>9}  {reason}", ""),
            };
            if !matches!(outcome, Outcome::Passed(_)) {
                bad += 1;
            }
            eprintln!("  {line}");
        }
        match bad {
            0 => Ok(()),
            n => Err(format!("{n} of {} test steps did not pass", self.steps.len()).into()),
        }
    }
}
