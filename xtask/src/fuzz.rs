//! `cargo xtask fuzz`: the libFuzzer targets of `fuzz/` (cargo-fuzz's layout), built and run
//! without cargo-fuzz, on stable Rust.
//!
//! The build passes the instrumentation that cargo-fuzz passes (SanitizerCoverage through
//! LLVM's `sancov-module` pass, `--cfg fuzzing`, debug assertions and overflow checks) for the
//! host triple only, so build scripts stay uninstrumented; `libfuzzer-sys` compiles libFuzzer
//! itself with the system's C++ compiler. No AddressSanitizer: it needs a nightly compiler,
//! and the code under test (`Instance`, `fmi2::state`) is safe Rust, where a memory error
//! cannot happen without a panic first; the `unsafe` C layer is checked under valgrind by the
//! C host test instead.
//!
//! Corpora: `target/fuzz/corpus/TARGET/` grows across runs. It starts from seeds written
//! here (serialized FMU states of the current format, for `deserialize`) and from the
//! committed inputs in `fuzz/regressions/TARGET/` (inputs that once failed, replayed by
//! every run).

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use beam_body::fmi::{Logger, Status};
use beam_body::fmi2::types::{FMI2_COSIMULATION, FMI2_MODEL_EXCHANGE};
use beam_body::fmi2::{instantiate, Instance};
use beam_body::fmu::variables::{guid, Var};

use crate::{cargo, project_root, relative, target_dir, Result};

/// The fuzz targets (`fuzz/fuzz_targets/*.rs`).
pub const TARGETS: [&str; 3] = ["deserialize", "api_sequence", "api_sequence3"];

/// Seconds per target of `cargo xtask test`'s smoke run.
pub const SMOKE_SECONDS: u64 = 15;

const HELP: &str = "usage: cargo xtask fuzz [--time SECONDS] [TARGET...]   (targets: deserialize, \
                    api_sequence, api_sequence3; default: all, 600 s each)";

/// What one fuzzing run did.
pub struct Outcome {
    pub target: &'static str,
    pub executions: u64,
    pub seconds: f64,
    pub corpus: usize,
}

/// `cargo xtask fuzz [--time SECONDS] [TARGET...]`.
pub fn run(options: &[String]) -> Result {
    let mut seconds = 600;
    let mut targets = Vec::new();
    let mut it = options.iter();
    while let Some(option) = it.next() {
        match option.as_str() {
            "--time" => {
                let value = it.next().ok_or(HELP)?;
                seconds = value
                    .parse()
                    .map_err(|_| format!("--time takes whole seconds, not `{value}`\n{HELP}"))?;
            }
            name => match TARGETS.iter().find(|t| **t == name) {
                Some(t) => targets.push(*t),
                None => return Err(format!("unknown fuzz target `{name}`\n{HELP}").into()),
            },
        }
    }
    if targets.is_empty() {
        targets = TARGETS.to_vec();
    }
    let outcomes = fuzz(&targets, seconds)?;
    for o in &outcomes {
        println!("{}", o.line());
    }
    Ok(())
}

/// The smoke run of `cargo xtask test`: every target for [`SMOKE_SECONDS`].
pub fn smoke() -> Result {
    for o in fuzz(&TARGETS, SMOKE_SECONDS)? {
        eprintln!("{}", o.line());
    }
    Ok(())
}

impl Outcome {
    fn line(&self) -> String {
        format!(
            "fuzz {}: {} executions in {:.0} s ({:.0}/s), corpus {} inputs, no failure",
            self.target,
            self.executions,
            self.seconds,
            self.executions as f64 / self.seconds.max(1e-9),
            self.corpus
        )
    }
}

/// Builds the targets, then runs each for `seconds`; an error names the failing input.
fn fuzz(targets: &[&'static str], seconds: u64) -> Result<Vec<Outcome>> {
    let bin = build()?;
    targets.iter().map(|t| run_target(&bin, t, seconds)).collect()
}

/// The host's target triple, from `rustc -vV`.
fn host_triple() -> Result<String> {
    let out = Command::new("rustc")
        .arg("-vV")
        .output()
        .map_err(|e| format!("could not run `rustc -vV`: {e}"))?;
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_string))
        .ok_or_else(|| "`rustc -vV` printed no host triple".into())
}

/// Builds the fuzz targets with coverage instrumentation; returns their directory.
fn build() -> Result<PathBuf> {
    let triple = host_triple()?;
    let dir = target_dir().join("fuzz");
    // As cargo-fuzz 0.12 (src/project.rs) instruments a build without a sanitizer.
    let flags = [
        "-Cpasses=sancov-module",
        "-Cllvm-args=-sanitizer-coverage-level=4",
        "-Cllvm-args=-sanitizer-coverage-inline-8bit-counters",
        "-Cllvm-args=-sanitizer-coverage-pc-table",
        "-Cllvm-args=-sanitizer-coverage-trace-compares",
        "--cfg",
        "fuzzing",
        "-Cdebug-assertions",
        "-Coverflow-checks",
    ];
    let manifest = project_root().join("fuzz").join("Cargo.toml");
    let mut cmd = cargo(["build", "--release", "--bins", "--target", &triple, "--manifest-path"]);
    cmd.arg(&manifest)
        .env("CARGO_TARGET_DIR", &dir)
        .env_remove("RUSTFLAGS")
        .env("CARGO_ENCODED_RUSTFLAGS", flags.join("\u{1f}"));
    crate::run_cmd(&mut cmd)?;
    Ok(dir.join(triple).join("release"))
}

/// Runs one target for `seconds` on its corpus; fails with the reproducer's path if
/// libFuzzer finds a failing input.
fn run_target(bin: &Path, target: &'static str, seconds: u64) -> Result<Outcome> {
    let root = target_dir().join("fuzz");
    let corpus = root.join("corpus").join(target);
    let artifacts = root.join("artifacts").join(target);
    for dir in [&corpus, &artifacts] {
        fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", relative(dir)))?;
    }
    if target == "deserialize" {
        write_state_seeds(&corpus)?;
    }
    let log_path = root.join(format!("{target}.log"));
    let log = fs::File::create(&log_path)
        .map_err(|e| format!("cannot write {}: {e}", relative(&log_path)))?;
    let mut cmd = Command::new(bin.join(target));
    cmd.arg(&corpus);
    let regressions = project_root().join("fuzz").join("regressions").join(target);
    if regressions.is_dir() {
        cmd.arg(&regressions);
    }
    cmd.arg(format!("-max_total_time={seconds}"))
        // A DoStep may take MAX_STEPS_PER_DO_STEP (10⁶) integrator steps before it gives up:
        // about a second in a release build, 14 s in this instrumented one (an api_sequence
        // input found on 2026-12-05). Such an input is a bounded step, not a hang.
        .arg("-timeout=30")
        .arg("-rss_limit_mb=2048")
        .arg("-max_len=8192")
        .arg("-print_final_stats=1")
        .arg(format!("-artifact_prefix={}/", artifacts.display()))
        .stdout(Stdio::null())
        .stderr(log);
    eprintln!("$ {} (log: {})", crate::display(&cmd), relative(&log_path));
    let start = Instant::now();
    let tick = crate::progress::ticker(format!("fuzz {target}"), move || format!("of {seconds} s"));
    let status = cmd.status().map_err(|e| format!("could not run the fuzz target `{target}`: {e}"));
    drop(tick);
    let status = status?;
    let text = fs::read_to_string(&log_path).unwrap_or_default();
    if !status.success() {
        let tail: Vec<&str> = text.lines().rev().take(40).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        return Err(format!(
            "fuzz target `{target}` failed ({status}); reproduce with `{} ARTIFACT` (artifacts \
             in {}), log {}:\n{}",
            relative(&bin.join(target)),
            relative(&artifacts),
            relative(&log_path),
            tail.join("\n")
        )
        .into());
    }
    let stat = |name: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(name).map(|v| v.trim().parse::<u64>().unwrap_or(0)))
            .unwrap_or(0)
    };
    let executions = stat("stat::number_of_executed_units:");
    if executions == 0 {
        return Err(
            format!("fuzz target `{target}` ran no input; see {}", relative(&log_path)).into()
        );
    }
    let corpus_size = fs::read_dir(&corpus).map(|d| d.count()).unwrap_or(0);
    Ok(Outcome { target, executions, seconds: start.elapsed().as_secs_f64(), corpus: corpus_size })
}

/// Writes serialized FMU states of this build's format into `dir`: the deserializer's
/// seeds, one per state of the state machine that has a distinct shape (no integrator yet,
/// the law, the input with derivatives, the DAE, a failed step, terminated; Model Exchange in
/// event mode, in continuous-time mode after the law's event, terminated).
fn write_state_seeds(dir: &Path) -> Result {
    let mut seeds: Vec<Vec<u8>> = Vec::new();
    let quiet = || -> Logger { Box::new(|_, _, _| {}) };
    let new_of = |fmu_type| {
        instantiate("seed", fmu_type, guid(), quiet(), false)
            .ok_or("cannot instantiate the FMU in-process")
    };
    let new = || new_of(FMI2_COSIMULATION);
    let snapshot = |inst: &mut Instance| -> Result<Vec<u8>> {
        let core = inst.get_state().map_err(|s| format!("fmi2GetFMUstate: {s:?}"))?;
        inst.serialize(&core).map_err(|s| format!("fmi2SerializeFMUstate: {s:?}").into())
    };
    let ok = |what: &str, s: Status| -> Result {
        if s == Status::Ok {
            Ok(())
        } else {
            Err(format!("seed: {what} returned {s:?}").into())
        }
    };
    // Enumerations count from 1: phi_source input = 1, law = 2; formulation reduced = 1,
    // dae = 2, dae_stabilized = 3, linear = 4 (fmu::variables).
    let mut inst = new()?;
    seeds.push(snapshot(&mut inst)?);
    ok("phi_source", inst.set_integer(&[Var::PhiSource.vr()], &[2]))?;
    ok("enter", inst.enter_initialization_mode())?;
    seeds.push(snapshot(&mut inst)?);
    ok("exit", inst.exit_initialization_mode())?;
    for k in 0..20 {
        ok("step", inst.do_step(f64::from(k) * 0.05, 0.05))?;
    }
    seeds.push(snapshot(&mut inst)?);
    ok("terminate", inst.terminate())?;
    seeds.push(snapshot(&mut inst)?);
    // The input with derivatives, in the stabilized DAE; then a jump that stops the run.
    let mut inst = new()?;
    ok("formulation", inst.set_integer(&[Var::Formulation.vr()], &[3]))?;
    ok("phi_source", inst.set_integer(&[Var::PhiSource.vr()], &[1]))?;
    ok("enter", inst.enter_initialization_mode())?;
    ok("exit", inst.exit_initialization_mode())?;
    for k in 0..10 {
        let t = f64::from(k) * 0.01;
        ok("phi", inst.set_real(&[Var::Phi.vr()], &[0.5 * t * t]))?;
        ok("dphi", inst.set_real_input_derivatives(&[Var::Phi.vr()], &[1], &[t]))?;
        ok("step", inst.do_step(t, 0.01))?;
    }
    seeds.push(snapshot(&mut inst)?);
    ok("phi", inst.set_real(&[Var::Phi.vr()], &[1e3]))?;
    if inst.do_step(0.1, 0.01) != Status::Discard {
        return Err("seed: a jump of φ by 1e3 rad was not discarded".into());
    }
    seeds.push(snapshot(&mut inst)?);
    // Model Exchange with the law: event mode at the start, continuous-time mode after the
    // law's event at t_rot = 0.85 s, terminated.
    let mut inst = new_of(FMI2_MODEL_EXCHANGE)?;
    ok("phi_source", inst.set_integer(&[Var::PhiSource.vr()], &[2]))?;
    ok("enter", inst.enter_initialization_mode())?;
    ok("exit", inst.exit_initialization_mode())?;
    seeds.push(snapshot(&mut inst)?);
    inst.new_discrete_states().map_err(|s| format!("seed: fmi2NewDiscreteStates: {s:?}"))?;
    ok("time", inst.set_time(0.85))?;
    inst.new_discrete_states().map_err(|s| format!("seed: fmi2NewDiscreteStates: {s:?}"))?;
    ok("continuous", inst.enter_continuous_time_mode())?;
    // The beam's four states, then the filter of φ's two.
    ok("states", inst.set_continuous_states(&[0.3, 0.2, -1.0, 0.5, 3.1, 0.2]))?;
    seeds.push(snapshot(&mut inst)?);
    ok("terminate", inst.terminate())?;
    seeds.push(snapshot(&mut inst)?);
    // The target's first byte is its mode (odd: reseal the frame after mutation).
    for (k, bytes) in seeds.iter().enumerate() {
        for mode in [0u8, 1] {
            let path = dir.join(format!("seed-{k}-{mode}"));
            let framed: Vec<u8> = std::iter::once(mode).chain(bytes.iter().copied()).collect();
            fs::write(&path, framed)
                .map_err(|e| format!("cannot write {}: {e}", relative(&path)))?;
        }
    }
    Ok(())
}
