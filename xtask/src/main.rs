//! Project tasks: `cargo xtask <command>`. See `cargo xtask help`.
//!
//! The alias runs the launcher (`xtask/launch`) first, which makes sure libclang is there for
//! fmi-sys's bindgen, then this crate. Its dependencies: the library (its interface tables,
//! `beam_body::fmu::variables`, and its scenes), quick-xml, zip, and fmi (the native FMI host,
//! with log and tempfile); xtask/Cargo.toml says why each. The benchmarks are a crate of
//! their own (bench/).

use std::env;
use std::process::ExitCode;
use xtask::{descriptions, fmu, study, test, Result};

const HELP: &str = "\
Usage: cargo xtask <command> [options]

Commands:
  test [--rust-only | --python-only]
          Run the whole test suite: set up the Python venv (target/venv),
          build the release binary, run the Rust tests and the Python tests.
  gen     Write modelDescription/modelDescription.xml (FMI 2.0) and
          modelDescription/fmi3/modelDescription.xml (FMI 3.0) from the interface
          tables (src/fmu/variables.rs). Commit the result; a test fails when either
          is stale.
  fmu [--all-platforms]
          Build and check the FMUs, target/fmu/BeamBody.fmu (FMI 2.0) and
          target/fmu/BeamBody-fmi3.fmu (FMI 3.0):
          - refuse a stale modelDescription.xml (either version);
          - run the paper's scene (scenes/paper.toml) through the standalone solver,
            the reference (target/fmu/paper.csv);
          - build the library (cargo rustc --release --lib --no-default-features
            --crate-type cdylib) and zip
            modelDescription.xml, binaries/linux64/BeamBody.so and
            documentation/index.html into BeamBody.fmu, and the FMI 3.0
            modelDescription.xml, binaries/x86_64-linux/BeamBody.so (the same
            library) and documentation/index.html into BeamBody-fmi3.fmu;
          - --all-platforms: also cross-build win64, macOS (x86_64 and arm64) and Linux
            aarch64 with Debian's Rust (installing the toolchains with apt-get as root),
            into BeamBody.fmu (binaries/win64, darwin64 universal, aarch64-darwin,
            aarch64-linux), BeamBody-fmi3.fmu (binaries/x86_64-windows, x86_64-darwin,
            aarch64-darwin, aarch64-linux) and target/fmu/BeamBody-aarch64-linux.fmu
            (the aarch64 library in binaries/linux64, where FMPy looks on Linux
            aarch64);
          - validate each archive with FMPy when target/venv exists;
          - extract BeamBody.fmu to target/fmu/BeamBody/, load the .so there with a
            native FMI 2.0 host, run the same scene through it
            (target/fmu/paper_fmu.csv) and compare.
  bench [--quick]
          The work-precision benchmark (error against run time, target/bench/):
          - set up target/venv with bench/python/requirements-bench.txt, package the
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
  bench-elements [--quick]
          Work against precision of the beam in 8 elements (32 states, 1 % damping): ours
          beside CVODE (dense; band, whole and truncated) and diffsol on the same right-hand
          side, the error against ours at rtol 1e-12; rtol 1e-4..1e-10 (3 tolerances with
          --quick), 5 rounds (3), medians; target/bench/elements.md, and
          docs/work_precision_elements.md in the full run.
  bench-exact [--quick]
          The exact beam at the paper's price: the undamped paper scene, the exact beam in
          n = 2, 8, 32 elements (2, 8 with --quick) with Radau IIA at rtol 1e-2..1e-8 (3
          tolerances), and with the BDF where it is affordable, beside the paper's model
          at the same rtol; integration error against the same n at a tight rtol, error
          against the largest n (the beam), the energy the integrator takes out, the
          issue-46 goals with their verdicts; 3 rounds (2), medians;
          target/bench/exact.md, and docs/work_precision_exact.md in the full run.
  bench-run --round K
          One round of the benchmark's Rust cases (used by `bench`, in a release build
          with --features bench): run the cases of target/bench/cases.csv in an order
          shuffled with seed K and append to target/bench/raw.csv; round 0 (the warm-up)
          also writes the solutions (target/bench/sol/) and target/bench/costs.csv.
  bench-ab [REV] [--rounds R] [--sample SCENE FORMULATION RTOL]
          The time per step of the library at git revision REV (default HEAD) against
          the working tree's: a small runner (bench/ab/runner.rs) built against each
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
          - draw docs/figure3.png and docs/model.png (bench/python/figures.py).
          The claims are tested by `cargo test -p beam-body-bench figures` (run by `test`).
  study ARGS...
          The study tool (python/beam_body_study, README: Design studies) with the
          release CLI, in target/venv: `study run STUDY.toml -o OUT.parquet [--engine
          dask [--scheduler ADDRESS]]`, `study plot heatmap|hist ...`, `study --help`.
  model-error [--quick]
          The model's error against run time (python/beam_body_study/model_error.py):
          the quadratic model in n = 1, 2, 4, 8, 16 elements at rtol 1e-4, 1e-6, 1e-8
          against n = 32 at 1e-8 on four scenes (the paper's, phi_end = 0.3, M2 = 1 kg,
          t_rot = 3 s), and both it and the exact beam in n = 1, 2, 4, 8 against the
          beam itself (the exact beam, n = 16 at 1e-8); model, integration and total
          errors of v1, theta1 and the metrics; run times; the fast turn's perturbation
          growth. Writes docs/model_error.{md,png} (runs cached in
          target/model_error/runs/; about 25 minutes on 2 cores from scratch). --quick:
          2 s of two scenes, n = 1, 2 against n = 4, into target/model_error/ (the test
          suite's smoke test).
  bench-study [--quick]
          Throughput of the study runners side by side (bench/python/bench_study.py):
          a 10^4-case study through the native runner on 1 and 2 threads, the chunked
          local engine, a LocalCluster of 1 and 2 workers and a loopback scheduler with
          2 worker processes; the overhead of a chunk's CLI call; 5 shuffled rounds
          (2 with --quick); target/bench/study.{csv,md}, and docs/study.md in the full run.
  profile Where the integrator's instructions go, per accepted step: callgrind on
          one run of each benchmark scene at rtol 1e-6 (a release build with symbols in
          target/prof), by the source line of each instruction: the integrator, the
          coefficients, the model, sin and cos, log/exp/pow, LU, the guard
          (bench/python/profile_step.py); target/prof/profile.md.
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
            descriptions::run()
        }
        "fmu" => match options {
            [] => fmu::run(false),
            [option] if option == "--all-platforms" => fmu::run(true),
            [option, ..] => Err(format!(
                "`fmu` has no option `{option}` (only --all-platforms); run `cargo xtask help`"
            )
            .into()),
        },
        "fuzz" => xtask::fuzz::run(options),
        "study" => study::run(options),
        "model-error" => study::model_error(options),
        // The benchmarks and experiments live in their own crate (bench/); these run it.
        "bench" | "bench-run" | "bench-ab" | "bench-dostep" | "bench-elements" | "bench-exact"
        | "bench-elements-run" | "bench-study" | "sweep" | "sweep-case" | "figures" | "profile" => {
            xtask::bench(command, options)
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
