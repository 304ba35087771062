//! `cargo xtask bench [--quick]`: the work-precision benchmark (error against run time), and
//! `bench-run --round K`, one round of its Rust cases.
//!
//! Every solver runs the same scenes ([`problem::SCENES`]) on the same output grid
//! (t_k = k·0.01 s), with atol = 1e-3·rtol. Files, all under `target/bench/`:
//! - `cases.csv` (`solver,scene,rtol,h`): written here, read by both runners. The rtol and h
//!   texts are the cases' names: `raw.csv` and the `sol/` file names repeat them verbatim.
//! - `raw.csv` (`round,solver,scene,rtol,h,time_s,steps,rejected,rhs_evals,jac_evals,
//!   lu_factorizations,newton_iters,status`): one row per case and round, appended by
//!   `bench-run` (the Rust solvers) and `bench/python/bench_scipy.py` (SciPy).
//! - `sol/<solver>__<scene>__<rtol>__<h>.csv` (`-` for an empty field): the solution on the
//!   grid, written in round 0, the warm-up.
//! - `costs.csv` (`round,scene,rhs_ns,lu_ns,solve_ns,rhs_throughput_ns,solve_throughput_ns`):
//!   appended by `bench-run` after the cases of every round, so that the prices see the machine
//!   as the timed solves do (the report takes their medians over the timed rounds).
//! - `ref/` (the reference solutions, `bench/python/bench_reference.py`) and the outputs
//!   `work_precision.{csv,png,md}` (`bench/python/bench_report.py`).
//!
//! Timing: a warm-up round 0, then R timed rounds (10; 3 with `--quick`). In each round all
//! Rust cases run in one release process in an order shuffled with seed = round, each timed
//! solve right after an untimed one of the same case (so that it finds its code and data
//! warm, as the next of many solves would), then all SciPy cases in one Python process.
//! `time_s` is the wall time of one complete solve (`Instant` around the call): building the
//! solver, both segments of the law, and the grid values (into one buffer, [`problem::States`]); not
//! the file I/O. There is no per-case time limit (a solve runs in-process), so
//! the case list holds only cases that finish in seconds.

mod cvode;
#[cfg(feature = "peers")]
mod diffsol;
mod dostep;
pub mod elements;
pub mod exact;
pub mod fmu;
mod me;
mod ours;
pub mod problem;
mod sundials_build;

use std::collections::HashMap;
use std::fmt::Write as _;
use std::fs;
use std::hint::black_box;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use beam_body::model::{BeamBody, DaeSystem, Formulation, TwoDofSystem};
use beam_body::solver::{Lu, OdeSystem};
use nalgebra::{Const, SMatrix, SVector};

use crate::{cargo, project_root, python, relative, run_cmd, target_dir, write_text, Mode, Result};
use problem::{state_names, Counters, Outcome, Problem, SCENES};

/// The solvers that `bench-run` runs in-process.
const RUST_SOLVERS: [&str; 7] = ["bdf", "bdf-fixed", "fmu", "fmu3", "cvode", "cvode-me", "diffsol"];
/// The solvers of `bench/python/bench_scipy.py`.
const SCIPY_SOLVERS: [&str; 3] = ["scipy-bdf", "scipy-radau", "scipy-lsoda"];
/// FMPy's CVode on the FMU's Model Exchange, which `bench_scipy.py` runs too (paper only).
const FMPY_ME: &str = "fmpy-me";

const CASES_HEADER: &str = "solver,scene,rtol,h";
const RAW_HEADER: &str = "round,solver,scene,rtol,h,time_s,steps,rejected,rhs_evals,jac_evals,\
                          lu_factorizations,newton_iters,status";
const COSTS_HEADER: &str =
    "round,scene,rhs_ns,lu_ns,solve_ns,rhs_throughput_ns,solve_throughput_ns";

/// The time limit of one SciPy solve (`bench_scipy.py --max-seconds`).
fn scipy_max_seconds(mode: Mode) -> u32 {
    match mode {
        Mode::Full => 60,
        Mode::Quick => 20,
    }
}

/// Timed rounds after the warm-up.
fn rounds(mode: Mode) -> u64 {
    match mode {
        Mode::Full => 10,
        Mode::Quick => 3,
    }
}

/// `--round K` of `bench-run`.
pub fn parse_round(options: &[String]) -> Result<u64> {
    match options {
        [flag, k] if flag == "--round" => {
            k.parse().map_err(|_| format!("`--round {k}`: not a round number").into())
        }
        _ => Err("usage: bench-run --round K".into()),
    }
}

fn bench_dir() -> PathBuf {
    target_dir().join("bench")
}

fn create_dir(dir: &Path) -> Result {
    fs::create_dir_all(dir).map_err(|err| format!("cannot create {}: {err}", relative(dir)).into())
}

// ---------------------------------------------------------------------------------------
// The cases.

/// One case: a solver on a scene at a tolerance or a step. The texts are as in `cases.csv`.
#[derive(Clone, Debug, PartialEq)]
struct Case {
    solver: String,
    scene: String,
    /// Empty for `bdf-fixed`.
    rtol: String,
    /// The fixed step (`bdf-fixed`) or the communication step (`fmu`); empty otherwise.
    h: String,
}

impl Case {
    fn new(solver: &str, scene: &str, rtol: &str, h: &str) -> Case {
        Case { solver: solver.into(), scene: scene.into(), rtol: rtol.into(), h: h.into() }
    }

    fn is_rust(&self) -> bool {
        RUST_SOLVERS.contains(&self.solver.as_str())
    }

    /// A case of `bench_scipy.py`: SciPy's solvers and FMPy's.
    fn is_scipy(&self) -> bool {
        SCIPY_SOLVERS.contains(&self.solver.as_str()) || self.solver == FMPY_ME
    }

    /// `sol/<solver>__<scene>__<rtol>__<h>.csv`, `-` for an empty field.
    fn solution_file(&self) -> PathBuf {
        let dash = |s: &str| if s.is_empty() { "-".to_string() } else { s.to_string() };
        bench_dir().join("sol").join(format!(
            "{}__{}__{}__{}.csv",
            self.solver,
            self.scene,
            dash(&self.rtol),
            dash(&self.h)
        ))
    }

    fn label(&self) -> String {
        let mut label = format!("{} {}", self.solver, self.scene);
        if !self.rtol.is_empty() {
            label.push_str(&format!(" rtol={}", self.rtol));
        }
        if !self.h.is_empty() {
            label.push_str(&format!(" h={}", self.h));
        }
        label
    }
}

/// 10^(−top − k/2): exact decades as literals ("1e-4"), half decades as the shortest text
/// that reads back to the same double ("3.1622776601683795e-4").
pub(super) fn half_decade(top: u32, k: u32) -> String {
    // Not `is_multiple_of`: the workspace's rust-version is 1.80.
    if k % 2 == 1 {
        format!("{:e}", 10f64.powf(-f64::from(top) - f64::from(k) / 2.0))
    } else {
        format!("1e-{}", top + k / 2)
    }
}

/// The case list of a mode.
///
/// - `bdf`, `cvode`, `diffsol`: every scene, rtol 1e-3 … 1e-14 in half decades (quick: 1e-4,
///   1e-6, 1e-8). Down to 1e-14, our rtol's floor, so that the errors reach 1e-8 on every
///   scene: the stiff scene's error is still 2e-5 at 1e-10 and about 1e-8 at 1e-14, where a
///   solve takes 0.6 s (ours) to 2 s (CVODE).
/// - `bdf-fixed`: paper and stiff, the paper's Δτ = 1e-3, 1e-4, 1e-5 in τ = t/T with
///   T = t_rot = 0.85 s, i.e. h = 8.5e-4, 8.5e-5, 8.5e-6 s (quick: the first two).
/// - `fmu`: paper, communication step H = 1e-2, 1e-3, 1e-4 s × rtol 1e-4, 1e-6, 1e-8 (quick:
///   H = 1e-2, 1e-3 at rtol 1e-6).
/// - `scipy-*`: a Python right-hand side costs tens of µs per call (a solve of the paper's
///   scene takes 0.3–2 s at rtol 1e-6, against 1 ms for `bdf`), so SciPy gets fewer cases:
///   the paper's scenes at rtol 1e-3 … 1e-8 (quick: 1e-4, 1e-6); the stiff scene, where every
///   solver needs ~10⁵ steps (8 s for LSODA at rtol 1e-4, minutes for BDF and Radau), at
///   1e-3, 3.2e-4, 1e-4 only, and not at all in the quick run. A SciPy case that takes more
///   than [`Mode::scipy_max_seconds`] is aborted and not run again (bench_scipy.py).
fn cases(mode: Mode) -> Vec<Case> {
    let texts = |list: &[&str]| list.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let (tight, scipy, scipy_stiff, fixed, fmu) = match mode {
        Mode::Full => (
            (0..23).map(|k| half_decade(3, k)).collect(),
            (0..11).map(|k| half_decade(3, k)).collect(),
            (0..3).map(|k| half_decade(3, k)).collect(),
            texts(&["8.5e-4", "8.5e-5", "8.5e-6"]),
            ["1e-4", "1e-6", "1e-8"]
                .iter()
                .flat_map(|r| ["1e-2", "1e-3", "1e-4"].map(|h| (*r, h)))
                .collect(),
        ),
        Mode::Quick => (
            texts(&["1e-4", "1e-6", "1e-8"]),
            texts(&["1e-4", "1e-6"]),
            vec![],
            texts(&["8.5e-4", "8.5e-5"]),
            vec![("1e-6", "1e-2"), ("1e-6", "1e-3")],
        ),
    };
    let mut list = Vec::new();
    for (scene, _, _) in SCENES {
        for solver in ["bdf", "cvode", "diffsol"] {
            list.extend(tight.iter().map(|rtol| Case::new(solver, scene, rtol, "")));
        }
        if scene == "paper" || scene == "stiff" {
            list.extend(fixed.iter().map(|h| Case::new("bdf-fixed", scene, "", h)));
        }
        if scene == "paper" {
            list.extend(fmu.iter().map(|(rtol, h)| Case::new("fmu", scene, rtol, h)));
            list.extend(fmu.iter().map(|(rtol, h)| Case::new("fmu3", scene, rtol, h)));
            list.extend(tight.iter().map(|rtol| Case::new("cvode-me", scene, rtol, "")));
            list.extend(scipy.iter().map(|rtol| Case::new(FMPY_ME, scene, rtol, "")));
        }
        let scipy = if scene == "stiff" { &scipy_stiff } else { &scipy };
        for solver in SCIPY_SOLVERS {
            list.extend(scipy.iter().map(|rtol| Case::new(solver, scene, rtol, "")));
        }
    }
    list
}

fn write_cases(path: &Path, cases: &[Case]) -> Result {
    let mut text = format!("{CASES_HEADER}\n");
    for c in cases {
        writeln!(text, "{},{},{},{}", c.solver, c.scene, c.rtol, c.h).expect("String");
    }
    write_text(path, &text)
}

fn read_cases(path: &Path) -> Result<Vec<Case>> {
    let text = fs::read_to_string(path).map_err(|err| {
        format!("cannot read {}: {err} (`cargo xtask bench` writes it)", relative(path))
    })?;
    let mut lines = text.lines();
    if lines.next().map(str::trim) != Some(CASES_HEADER) {
        return Err(format!("{}: the header is not `{CASES_HEADER}`", relative(path)).into());
    }
    let mut cases = Vec::new();
    for (i, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let [solver, scene, rtol, h] = fields[..] else {
            return Err(format!("{}:{}: expected 4 fields: {line}", relative(path), i + 2).into());
        };
        cases.push(Case::new(solver, scene, rtol, h));
    }
    Ok(cases)
}

// ---------------------------------------------------------------------------------------
// `cargo xtask bench`.

/// `cargo xtask bench-dostep`: the cost of one fmi2DoStep alone ([`dostep`]).
pub fn run_dostep(mode: Mode) -> Result {
    let dir = bench_dir();
    create_dir(&dir)?;
    let fmu_dir = fmu::prepare()?;
    dostep_report(mode, &fmu_dir, &dir)
}

/// Runs the DoStep benchmark, prints its table and, in the full run, copies it to docs/.
fn dostep_report(mode: Mode, fmu_dir: &Path, dir: &Path) -> Result {
    let table = dostep::run(mode, fmu_dir, dir)?;
    println!("\n{table}");
    if mode == Mode::Full {
        write_text(&project_root().join("docs").join("dostep.md"), &table)?;
    }
    Ok(())
}

pub fn run(mode: Mode) -> Result {
    let started = Instant::now();
    let dir = bench_dir();
    create_dir(&dir)?;
    let root = project_root();

    // Setup: the venv, the FMU, SUNDIALS, the release build. Not part of the timed phases.
    let python = python::ensure_venv()?;
    let requirements = root.join("bench").join("python").join("requirements-bench.txt");
    if requirements.is_file() {
        let mut pip = Command::new(&python);
        pip.args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "-r"])
            .arg(relative(&requirements))
            .current_dir(&root);
        run_cmd(&mut pip)?;
    } else {
        eprintln!("warning: no {}: not installing the report's packages", relative(&requirements));
    }
    let fmu_dir = fmu::prepare()?;
    eprintln!("FMU extracted to {}", relative(&fmu_dir));
    let cvode_lib = optimized_cvode();
    let cvode = cvode_lib.is_some();
    // The CLI (the reference script's second method) and the release runner of the rounds:
    // the binary that `cargo run --release -p beam-body-bench --features peers -- bench-run` runs, built
    // once so that cargo's checks stay out of the rounds.
    crate::build_release_binary()?;
    run_cmd(&mut cargo(["build", "--release", "-p", "beam-body-bench", "--features", "peers"]))?;
    let runner = target_dir().join("release").join("beam-body-bench");

    let cases = cases(mode);
    let cases_csv = dir.join("cases.csv");
    write_cases(&cases_csv, &cases)?;
    let n_rust = cases.iter().filter(|c| c.is_rust()).count();
    let n_scipy = cases.iter().filter(|c| c.is_scipy()).count();
    println!(
        "{}: {} cases ({n_rust} Rust, {n_scipy} SciPy); cvode {}",
        relative(&cases_csv),
        cases.len(),
        if cvode { "available" } else { "UNAVAILABLE (its cases will fail)" }
    );
    // A fresh run: the raw timings and the solutions of the previous one go.
    for stale in [dir.join("raw.csv"), dir.join("costs.csv")] {
        if stale.exists() {
            fs::remove_file(&stale)
                .map_err(|err| format!("cannot remove {}: {err}", relative(&stale)))?;
        }
    }
    let sol = dir.join("sol");
    if sol.exists() {
        fs::remove_dir_all(&sol)
            .map_err(|err| format!("cannot remove {}: {err}", relative(&sol)))?;
    }
    let setup = started.elapsed();

    // The reference solutions (cached by the script).
    let phase = Instant::now();
    let scripts = root.join("bench").join("python");
    let script = |name: &str| -> Option<PathBuf> {
        let path = scripts.join(name);
        if path.is_file() {
            Some(path)
        } else {
            eprintln!("warning: no {}: skipped", relative(&path));
            None
        }
    };
    if let Some(reference) = script("bench_reference.py") {
        let _tick = crate::progress::ticker("bench: reference solutions", String::new);
        run_cmd(Command::new(&python).arg(relative(&reference)).current_dir(&root))?;
    }
    let reference_time = phase.elapsed();

    // Round 0 (warm-up, solutions, costs), then the timed rounds.
    let scipy_script = script("bench_scipy.py");
    let rounds = rounds(mode);
    let max_seconds = scipy_max_seconds(mode).to_string();
    let phase = Instant::now();
    for round in 0..=rounds {
        let _tick = crate::progress::ticker(format!("bench: round {round}/{rounds}"), String::new);
        let round_text = round.to_string();
        let t = Instant::now();
        let mut rust_round = Command::new(&runner);
        rust_round.args(["bench-run", "--round", &round_text]).current_dir(&root);
        if let Some(lib) = &cvode_lib {
            rust_round.env(CVODE_LIB_VARIABLE, lib);
        }
        run_cmd(&mut rust_round)?;
        let rust = t.elapsed();
        let t = Instant::now();
        if let Some(scipy) = &scipy_script {
            run_cmd(
                Command::new(&python)
                    .arg(relative(scipy))
                    .args(["--round", &round_text, "--max-seconds", &max_seconds])
                    .current_dir(&root),
            )?;
        }
        let scipy = t.elapsed();
        let name = if round == 0 {
            "round 0 (warm-up)".to_string()
        } else {
            format!("round {round}/{rounds}")
        };
        println!(
            "{name}: {n_rust} Rust cases {:.1} s, {n_scipy} scipy cases {:.1} s",
            rust.as_secs_f64(),
            scipy.as_secs_f64()
        );
    }
    let rounds_time = phase.elapsed();

    let phase = Instant::now();
    if let Some(report) = script("bench_report.py") {
        let _tick = crate::progress::ticker("bench: report", String::new);
        let mut cmd = Command::new(&python);
        cmd.arg(relative(&report)).current_dir(&root);
        // Only the full run replaces the snapshot in docs/; --quick reports in target/bench.
        if mode == Mode::Quick {
            cmd.args(["--no-docs", "--command", "cargo xtask bench --quick"]);
        }
        run_cmd(&mut cmd)?;
    }
    let report_time = phase.elapsed();

    // The cost of one fmi2DoStep, from a bare C host (after the rounds: nothing else runs).
    let phase = Instant::now();
    dostep_report(mode, &fmu_dir, &dir)?;
    let dostep_time = phase.elapsed();

    println!("\nOutputs:");
    for name in ["work_precision.csv", "work_precision.png", "work_precision.md"] {
        let path = dir.join(name);
        let mark = if path.exists() { "" } else { "  (missing)" };
        println!("  {}{mark}", relative(&path));
    }
    if mode == Mode::Full {
        for name in ["work_precision.png", "work_precision.md"] {
            let path = root.join("docs").join(name);
            let mark = if path.exists() { "" } else { "  (missing)" };
            println!("  {}{mark}", relative(&path));
        }
    } else {
        println!("  (docs/ keeps the snapshot of the last full run)");
    }
    println!(
        "  raw data: {}, {}, sol/, ref/",
        relative(&dir.join("raw.csv")),
        relative(&dir.join("costs.csv"))
    );
    let secs = Duration::as_secs_f64;
    println!(
        "\nTime: setup {:.1} s, reference {:.1} s, rounds {:.1} s ({} + warm-up), report {:.1} s, \
         DoStep costs {:.1} s; benchmark (reference excluded) {:.1} s, total {:.1} s",
        secs(&setup),
        secs(&reference_time),
        secs(&rounds_time),
        rounds,
        secs(&report_time),
        secs(&dostep_time),
        secs(&(rounds_time + report_time + dostep_time)),
        secs(&started.elapsed()),
    );
    Ok(())
}

/// The variable that names the CVODE library `cvode.rs` loads.
pub(crate) const CVODE_LIB_VARIABLE: &str = "BEAM_BODY_CVODE_LIB";

/// The CVODE library of the `cvode` cases: the one named by `BEAM_BODY_CVODE_LIB` if set,
/// else an optimised build from source ([`sundials_build`]); `None` when that build fails,
/// and the cvode cases then fail, each with its reason. (Debian's `libsundials-cvode6` is
/// compiled at -O0, about 3x slower than the same source at -O2: a flattering peer, so it is
/// no fallback.)
pub(crate) fn optimized_cvode() -> Option<PathBuf> {
    if let Some(lib) = std::env::var_os(CVODE_LIB_VARIABLE) {
        eprintln!("cvode: {CVODE_LIB_VARIABLE} = {}", PathBuf::from(&lib).display());
        return Some(lib.into());
    }
    match sundials_build::ensure_optimized_cvode(&target_dir()) {
        Ok(lib) => {
            eprintln!("cvode: {}", relative(&lib));
            Some(lib)
        }
        Err(err) => {
            eprintln!("warning: no optimised CVODE ({err}); the cvode cases will fail");
            None
        }
    }
}

/// `cvode-lib`: builds the optimised CVODE (or finds it built) and prints its path, for
/// `cargo xtask test`, which runs the tests that need it with `BEAM_BODY_CVODE_LIB` set.
pub fn print_cvode_lib() -> Result {
    let lib = sundials_build::ensure_optimized_cvode(&target_dir())?;
    println!("{}", lib.display());
    Ok(())
}

// ---------------------------------------------------------------------------------------
// `bench-run --round K`.

pub fn run_round(round: u64) -> Result {
    let dir = bench_dir();
    let all = read_cases(&dir.join("cases.csv"))?;
    let mut cases: Vec<Case> = all.into_iter().filter(Case::is_rust).collect();
    shuffle(&mut cases, round);

    let mut problems: HashMap<String, std::result::Result<Problem, String>> = HashMap::new();
    for case in &cases {
        problems.entry(case.scene.clone()).or_insert_with(|| problem::problem(&case.scene));
    }
    let fmu = if cases.iter().any(|c| c.solver == "fmu" || c.solver == "cvode-me") {
        Some(fmu::load(&fmu::extracted_dir()))
    } else {
        None
    };
    let fmu3 = cases.iter().any(|c| c.solver == "fmu3").then(|| fmu::load3(&fmu::extracted_dir3()));

    let warm_up = round == 0;
    // CVODE's library is loaded at its first use: here, before the timed solves.
    if cases.iter().any(|c| c.solver == "cvode") {
        match cvode::describe() {
            Ok(text) if warm_up => eprintln!("cvode: {text}"),
            Ok(_) => {}
            Err(err) => eprintln!("cvode unavailable: {err}"),
        }
    }
    if warm_up {
        create_dir(&dir.join("sol"))?;
    }
    let raw_path = dir.join("raw.csv");
    let new_file = !raw_path.exists();
    let mut raw = fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&raw_path)
        .map_err(|err| format!("cannot open {}: {err}", relative(&raw_path)))?;
    if new_file {
        writeln!(raw, "{RAW_HEADER}").map_err(|err| format!("{}: {err}", relative(&raw_path)))?;
    }

    let (mut failed, mut total) = (0, Duration::ZERO);
    for case in &cases {
        let problem = problems.get(&case.scene).expect("every scene was loaded");
        let (time, result) = match problem {
            Ok(problem) => {
                if !warm_up {
                    // The same solve once untimed first, in this process: the timed one finds
                    // its code, data and allocator warm, as the next of many solves would.
                    drop(timed_solve(case, problem, (fmu.as_ref(), fmu3.as_ref())));
                }
                timed_solve(case, problem, (fmu.as_ref(), fmu3.as_ref()))
            }
            Err(err) => (Duration::ZERO, Err(err.clone())),
        };
        total += time;
        let status = match &result {
            Ok(_) => "ok".to_string(),
            Err(err) => {
                failed += 1;
                err.replace([',', '\n', '\r'], ";")
            }
        };
        let counters = result.as_ref().map(|o| o.counters).unwrap_or_default();
        writeln!(raw, "{}", raw_row(round, case, time, &counters, &status))
            .map_err(|err| format!("{}: {err}", relative(&raw_path)))?;
        if warm_up {
            match (&result, problem) {
                (Ok(outcome), Ok(problem)) => {
                    write_solution(&case.solution_file(), problem, outcome)?;
                    eprintln!("  {:<50} {:>9.4} s", case.label(), time.as_secs_f64());
                }
                _ => eprintln!("  {:<50} FAILED: {status}", case.label()),
            }
        } else if result.is_err() {
            eprintln!("  {}: FAILED: {status}", case.label());
        }
    }
    eprintln!(
        "bench-run round {round}: {} Rust cases ({failed} failed), {:.2} s of solves",
        cases.len(),
        total.as_secs_f64()
    );

    let mut scenes: Vec<&str> = cases.iter().map(|c| c.scene.as_str()).collect();
    scenes.sort_unstable();
    scenes.dedup();
    append_costs(&dir.join("costs.csv"), round, &scenes)?;
    Ok(())
}

/// The loaded FMUs, FMI 2.0 and 3.0, each if a case needs it.
type Loaded<'a> = (
    Option<&'a std::result::Result<crate::import::Fmu2, String>>,
    Option<&'a std::result::Result<crate::import::Fmu3, String>>,
);

/// Runs one case, timing the solve alone (the case's numbers are parsed before).
fn timed_solve(
    case: &Case,
    problem: &Problem,
    (fmu, fmu3): Loaded,
) -> (Duration, std::result::Result<Outcome, String>) {
    let number = |name: &str, text: &str| -> std::result::Result<f64, String> {
        text.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite() && *x > 0.0)
            .ok_or_else(|| format!("{name} `{text}` is not a positive number"))
    };
    let rtol = || number("rtol", &case.rtol);
    let h = || number("h", &case.h);
    let start = Instant::now();
    let result = match case.solver.as_str() {
        "bdf" => rtol().and_then(|rtol| ours::bdf(problem, rtol)),
        "bdf-fixed" => h().and_then(|h| ours::bdf_fixed(problem, h)),
        "fmu" => match fmu {
            Some(Ok(fmu)) => {
                rtol().and_then(|rtol| h().and_then(|h| fmu::run(fmu, problem, rtol, h)))
            }
            Some(Err(err)) => Err(err.clone()),
            None => Err("the FMU was not loaded".into()),
        },
        "fmu3" => match fmu3 {
            Some(Ok(fmu)) => {
                rtol().and_then(|rtol| h().and_then(|h| fmu::run3(fmu, problem, rtol, h)))
            }
            Some(Err(err)) => Err(err.clone()),
            None => Err("the FMI 3.0 FMU was not loaded".into()),
        },
        "cvode" => rtol().and_then(|rtol| cvode::run(problem, rtol)),
        "cvode-me" => match fmu {
            Some(Ok(fmu)) => rtol().and_then(|rtol| me::run(fmu, problem, rtol)),
            Some(Err(err)) => Err(err.clone()),
            None => Err("the FMU was not loaded".into()),
        },
        "diffsol" => rtol().and_then(|rtol| diffsol::run(problem, rtol)),
        other => Err(format!("unknown solver `{other}`")),
    };
    let time = start.elapsed();
    let result = result.and_then(|outcome| check_outcome(problem, outcome));
    (time, result)
}

/// `diffsol` is compiled only with the feature `peers` (its crate is an optional dependency).
#[cfg(not(feature = "peers"))]
mod diffsol {
    use super::problem::{Outcome, Problem};

    pub fn run(_problem: &Problem, _rtol: f64) -> Result<Outcome, String> {
        Err("diffsol is built only with --features peers".into())
    }
}

/// A solution must have one finite row of the right width per grid time.
fn check_outcome(problem: &Problem, outcome: Outcome) -> std::result::Result<Outcome, String> {
    let width = state_names(problem.scene.formulation).len();
    if outcome.states.len() != problem.grid.len() {
        return Err(format!("{} rows for {} grid times", outcome.states.len(), problem.grid.len()));
    }
    for (row, t) in outcome.states.rows().zip(&problem.grid) {
        if row.len() != width {
            return Err(format!("{} states at t = {t} instead of {width}", row.len()));
        }
        if !row.iter().all(|x| x.is_finite()) {
            return Err(format!("a non-finite state at t = {t}"));
        }
    }
    Ok(outcome)
}

fn raw_row(round: u64, case: &Case, time: Duration, c: &Counters, status: &str) -> String {
    let count = |x: Option<u64>| x.map(|n| n.to_string()).unwrap_or_default();
    format!(
        "{round},{},{},{},{},{:e},{},{},{},{},{},{},{status}",
        case.solver,
        case.scene,
        case.rtol,
        case.h,
        time.as_secs_f64(),
        count(c.steps),
        count(c.rejected),
        count(c.rhs_evals),
        count(c.jac_evals),
        count(c.lu_factorizations),
        count(c.newton_iters),
    )
}

fn write_solution(path: &Path, problem: &Problem, outcome: &Outcome) -> Result {
    let mut text = String::from("t");
    for name in state_names(problem.scene.formulation) {
        text.push(',');
        text.push_str(name);
    }
    text.push('\n');
    for (t, row) in problem.grid.iter().zip(outcome.states.rows()) {
        write!(text, "{t:e}").expect("String");
        for x in row {
            write!(text, ",{x:e}").expect("String");
        }
        text.push('\n');
    }
    write_text(path, &text)
}

/// Writes a benchmark's report `md` to target/bench/`name` and prints it; a full run (`mode`)
/// copies it to docs/`docs_name`.
fn write_report(md: &str, name: &str, docs_name: &str, mode: Mode) -> Result {
    let dir = target_dir().join("bench");
    fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", relative(&dir)))?;
    let out = dir.join(name);
    write_text(&out, md)?;
    println!("{md}");
    eprintln!("wrote {}", relative(&out));
    if mode == Mode::Full {
        let docs = project_root().join("docs").join(docs_name);
        fs::copy(&out, &docs).map_err(|e| format!("cannot copy to {}: {e}", relative(&docs)))?;
        eprintln!("copied to {}", relative(&docs));
    }
    Ok(())
}

/// Fisher–Yates with SplitMix64 seeded by the round: a different, reproducible order in every
/// round.
fn shuffle<T>(items: &mut [T], seed: u64) {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    for i in (1..items.len()).rev() {
        let j = (next() % (i as u64 + 1)) as usize;
        items.swap(i, j);
    }
}

// ---------------------------------------------------------------------------------------
// costs.csv: the price of one right-hand side, one LU factorisation and one LU solve.

/// Repetitions per timed batch, and batches: 2·10⁵ repetitions per quantity; the cost is the
/// median over the batches of the time per repetition (one `Instant` pair per batch, so
/// its ~25 ns do not count).
const BATCH: u32 = 1000;
const BATCHES: usize = 200;

fn median_ns(mut f: impl FnMut()) -> f64 {
    for _ in 0..BATCH {
        f();
    }
    let mut per_call: Vec<f64> = (0..BATCHES)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..BATCH {
                f();
            }
            start.elapsed().as_secs_f64() * 1e9 / f64::from(BATCH)
        })
        .collect();
    per_call.sort_by(f64::total_cmp);
    per_call[BATCHES / 2]
}

/// For each scene: f at a state mid-run (t = 5 s, after the turn, with the law's piece
/// there) and, on the Newton matrix I − γJ of that state (J by forward differences, γ = 1e-3),
/// the integrator's own LU with partial pivoting and its solve (`beam_body::solver::Lu`).
///
/// `rhs_ns` and `solve_ns` are the costs of calls that each wait for the one before: the
/// argument of a call is made from the result of the last (y + 10⁻³⁰⁰·f, which leaves y as
/// it is, and which the compiler cannot drop), as in the Newton iteration, where f waits for
/// the solve and the solve for f. That is the price the integrator pays for them; calls with
/// nothing to wait for overlap (the `*_throughput_ns` columns, measured too: at N = 4 the
/// solve is 2-3 times cheaper that way). Until 2026-12-03 the costs were those of
/// independent calls, and nalgebra's LU stood in for ours (its solve cost 3-7 times ours).
fn append_costs(path: &Path, round: u64, scenes: &[&str]) -> Result {
    let mut text = if path.exists() { String::new() } else { format!("{COSTS_HEADER}\n") };
    for scene in scenes {
        let problem = problem::problem(scene)?;
        let s = &problem.scene;
        let model = BeamBody::new(s.params).map_err(|err| err.to_string())?;
        let t = 5.0;
        let piece = s.law.piece_from(t);
        let c = match s.formulation {
            Formulation::Reduced | Formulation::Linear => {
                let sys = TwoDofSystem {
                    model: &model,
                    phi: piece,
                    linear: s.formulation == Formulation::Linear,
                    range_check: true,
                };
                costs(&sys, t, SVector::<f64, 4>::new(0.01, 0.004, 0.05, 0.02))
            }
            Formulation::Dae | Formulation::DaeStabilized => {
                let sys = DaeSystem {
                    model: &model,
                    phi: piece,
                    stabilized: s.formulation == Formulation::DaeStabilized,
                    range_check: true,
                };
                let y = SVector::<f64, 6>::from([0.01, 0.004, 0.0, 0.05, 0.02, 0.0]);
                costs(&sys, t, sys.consistent(&y))
            }
        };
        writeln!(
            text,
            "{round},{scene},{:.2},{:.2},{:.2},{:.2},{:.2}",
            c.rhs, c.lu, c.solve, c.rhs_throughput, c.solve_throughput
        )
        .expect("String");
        if round == 0 {
            eprintln!(
                "  costs {}: rhs {:.1} ns (independent calls {:.1}), LU {:.1} ns, solve {:.1} ns \
                 (independent calls {:.1})",
                problem.name, c.rhs, c.rhs_throughput, c.lu, c.solve, c.solve_throughput
            );
        }
    }
    let mut file = fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map_err(|err| format!("cannot open {}: {err}", relative(path)))?;
    file.write_all(text.as_bytes()).map_err(|err| format!("{}: {err}", relative(path)).into())
}

/// The prices of [`write_costs`], in ns.
struct Costs {
    rhs: f64,
    lu: f64,
    solve: f64,
    rhs_throughput: f64,
    solve_throughput: f64,
}

fn costs<const N: usize>(sys: &impl OdeSystem<Const<N>>, t: f64, y: SVector<f64, N>) -> Costs {
    // 10⁻³⁰⁰·x is far below an ulp of y: the chained arguments stay y.
    const TINY: f64 = 1e-300;
    let rhs_throughput = median_ns(|| {
        black_box(sys.rhs(black_box(t), black_box(&y)));
    });
    let mut chained = y;
    let rhs = median_ns(|| {
        chained = y + sys.rhs(t, &chained) * TINY;
    });
    black_box(chained);
    let f0 = sys.rhs(t, &y);
    let mut jac = SMatrix::<f64, N, N>::zeros();
    for j in 0..N {
        let mut yj = y;
        let inc = 1e-8 * y[j].abs().max(1e-3);
        yj[j] += inc;
        jac.set_column(j, &((sys.rhs(t, &yj) - f0) / inc));
    }
    let newton = SMatrix::<f64, N, N>::identity() - jac * 1e-3;
    let lu = median_ns(|| {
        black_box(Lu::factor(&black_box(newton)));
    });
    let factors = Lu::factor(&newton).expect("the Newton matrix at γ = 1e-3 is regular");
    let solve_throughput = median_ns(|| {
        black_box(factors.solve(black_box(&f0)));
    });
    let mut b = f0;
    let solve = median_ns(|| {
        b = f0 + factors.solve(&b) * TINY;
    });
    black_box(b);
    Costs { rhs, lu, solve, rhs_throughput, solve_throughput }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_decades_read_back_exactly() {
        let texts: Vec<String> = (0..23).map(|k| half_decade(3, k)).collect();
        assert_eq!(texts[0], "1e-3");
        assert_eq!(texts[2], "1e-4");
        assert_eq!(texts[14], "1e-10");
        assert_eq!(texts[22], "1e-14");
        for (k, text) in texts.iter().enumerate() {
            let x: f64 = text.parse().unwrap();
            let want = 10f64.powf(-3.0 - k as f64 / 2.0);
            assert!((x / want - 1.0).abs() < 1e-15, "{text}");
        }
    }

    #[test]
    fn case_lists_round_trip_through_the_csv() {
        let dir = std::env::temp_dir().join(format!("bench-cases-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        for mode in [Mode::Full, Mode::Quick] {
            let list = cases(mode);
            let path = dir.join("cases.csv");
            write_cases(&path, &list).unwrap();
            assert_eq!(read_cases(&path).unwrap(), list);
        }
        fs::remove_dir_all(&dir).unwrap();
        let quick = cases(Mode::Quick);
        assert_eq!(quick.iter().filter(|c| c.solver == "bdf").count(), 12);
        assert_eq!(quick.iter().filter(|c| c.solver == "fmu").count(), 2);
        assert_eq!(quick.iter().filter(|c| c.solver == "fmu3").count(), 2);
        assert_eq!(quick.iter().filter(|c| c.solver == "cvode-me").count(), 3);
        assert_eq!(quick.iter().filter(|c| c.solver == FMPY_ME).count(), 2);
        assert!(quick.iter().filter(|c| c.solver.ends_with("-me")).all(|c| c.scene == "paper"));
        let full = cases(Mode::Full);
        assert_eq!(full.iter().filter(|c| c.solver == "bdf").count(), 92);
        assert_eq!(full.iter().filter(|c| c.solver == "scipy-radau").count(), 36);
        assert!(!quick.iter().any(|c| c.is_scipy() && c.scene == "stiff"));
    }

    #[test]
    fn shuffle_is_a_permutation_that_depends_on_the_seed() {
        let mut a: Vec<u32> = (0..50).collect();
        let mut b = a.clone();
        shuffle(&mut a, 1);
        shuffle(&mut b, 2);
        assert_ne!(a, b);
        a.sort_unstable();
        assert_eq!(a, (0..50).collect::<Vec<_>>());
    }
}
