//! `beam-body`: the standalone solver. Runs the model without FMI.
//!
//! ```text
//! beam-body simulate SCENE.toml [--formulation F] [--rtol X] [--atol X] [--set NAME=VALUE]...
//!                    [--fixed-step H --order K] [--max-order K] [--no-guard] [-o OUT.csv]
//! beam-body modes [SCENE.toml] [--set NAME=VALUE]...
//! beam-body residual --formulation F [--set NAME=VALUE]...   (stdin → stdout, for the oracle)
//! beam-body study STUDY.toml [--cases A..B] [--threads N] [--scene FILE] [--quiet] [-o OUT.csv]
//! beam-body study STUDY.toml --plan
//! ```

use beam_body::model::{BeamBody, Formulation, Outputs, Phi};
use beam_body::sim::{scene_entries, simulate, Scene};
use beam_body::study::{run_cases, Row, Status, Study};
use nalgebra::{Vector2, Vector3};
use std::f64::consts::PI;
use std::io::{self, BufRead, BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

const USAGE: &str = "\
usage:
  beam-body simulate SCENE.toml [options] [-o OUT.csv]
      Runs a scene and writes CSV (t,v1,theta1,u2,dv1,dtheta1,du2,phi,dphi,ddphi,N,P,M,energy,drift;
      SI units) at t = k*dt_out up to and including t_end; to stdout without -o.
      Run statistics go to stderr.
  beam-body modes [SCENE.toml] [--set NAME=VALUE]...
      Small-oscillation periods about the static equilibrium at phi = 0, pi/2, pi.
  beam-body residual --formulation F [--set NAME=VALUE]...
      Reads states from stdin, one per line:
        reduced, linear:     phi dphi ddphi v1 theta1 dv1 dtheta1 ddv1 ddtheta1
        dae, dae-stabilized: phi dphi ddphi v1 theta1 u2 dv1 dtheta1 du2 ddv1 ddtheta1 ddu2
      and writes the residuals of the equations of motion, then the accelerations of the
      model's right-hand side.
  beam-body study STUDY.toml [--cases A..B] [--threads N] [--scene FILE] [--quiet] [-o OUT.csv]
      Runs a design study (README: Design studies) on every core and writes one CSV row
      per case: case, the parameters, the metrics, status, message, steps. Cases A..B
      (half-open) only, with --cases; the base scene FILE instead of the study's `scene`,
      with --scene. Progress goes to stderr (not with --quiet). The file appears when the
      study is done.
  beam-body study STUDY.toml --plan
      Checks the study and prints, as JSON, its number of cases, its columns and the path
      of its base scene; runs nothing.

options:
  --formulation F     reduced | dae | dae-stabilized | linear   (default reduced)
  --rtol X            relative tolerance, in [1e-14, 1]          (default 1e-6)
  --atol X            absolute tolerance, > 0                    (default 1e-3*rtol)
  --set NAME=VALUE    any scene key: l EI m M2 J_C r g t_rot phi_end phi0 t_end dt_out
                      v1_0 theta1_0 dv1_0 dtheta1_0 rtol atol max_order
  --fixed-step H      the paper's constant-step BDF with step H [s]
  --order K           order of the constant-step BDF, 1..=5      (default 2)
  --max-order K       highest order of the adaptive BDF, 1..=5   (default 5)
  --no-guard          switch off the BDF3-5 stability guard
  -o FILE             write the CSV to FILE
";

/// A command-line or input error: printed as `error: …`, exit code 2.
struct Usage(String);

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("simulate") => cmd_simulate(&args[1..]),
        Some("modes") => cmd_modes(&args[1..]),
        Some("residual") => cmd_residual(&args[1..]),
        Some("study") => cmd_study(&args[1..]),
        Some("help" | "--help" | "-h") => {
            print!("{USAGE}");
            Ok(())
        }
        Some(other) => Err(Usage(format!("unknown command `{other}`\n\n{USAGE}"))),
        None => Err(Usage(USAGE.to_string())),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Usage(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(2)
        }
    }
}

/// Options shared by the commands.
struct Cli {
    scene: Scene,
    output: Option<String>,
    scene_file: Option<String>,
}

fn parse(args: &[String], allow_output: bool) -> Result<Cli, Usage> {
    let mut scene = Scene::default();
    let mut output = None;
    let mut scene_file = None;
    let mut sets: Vec<(String, String)> = Vec::new();
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let mut value =
            |flag: &str| it.next().cloned().ok_or_else(|| Usage(format!("{flag} needs a value")));
        match arg.as_str() {
            "--formulation" => sets.push(("formulation".into(), value(arg)?)),
            "--rtol" => sets.push(("rtol".into(), value(arg)?)),
            "--atol" => sets.push(("atol".into(), value(arg)?)),
            "--max-order" => sets.push(("max_order".into(), value(arg)?)),
            "--fixed-step" => sets.push(("fixed_step".into(), value(arg)?)),
            "--order" => sets.push(("fixed_order".into(), value(arg)?)),
            "--no-guard" => sets.push(("stability_guard".into(), "false".into())),
            "--set" => {
                let kv = value(arg)?;
                let (k, v) = kv
                    .split_once('=')
                    .ok_or_else(|| Usage(format!("--set expects NAME=VALUE, got `{kv}`")))?;
                sets.push((k.trim().to_string(), v.trim().to_string()));
            }
            "-o" | "--output" if allow_output => output = Some(value(arg)?),
            flag if flag.starts_with('-') => {
                return Err(Usage(format!("unknown option `{flag}`\n\n{USAGE}")))
            }
            file if scene_file.is_none() => scene_file = Some(file.to_string()),
            extra => return Err(Usage(format!("unexpected argument `{extra}`"))),
        }
    }
    // The scene file first, then the command line over it.
    if let Some(path) = &scene_file {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Usage(format!("cannot read scene file {path}: {e}")))?;
        for (line, key, val) in scene_entries(&text).map_err(|e| Usage(format!("{path}: {e}")))? {
            scene.set(&key, &val).map_err(|e| Usage(format!("{path}:{line}: {e}")))?;
        }
    }
    for (k, v) in &sets {
        scene.set(k, v).map_err(Usage)?;
    }
    Ok(Cli { scene, output, scene_file })
}

fn cmd_simulate(args: &[String]) -> Result<(), Usage> {
    let cli = parse(args, true)?;
    if cli.scene_file.is_none() {
        return Err(Usage(format!("simulate needs a scene file\n\n{USAGE}")));
    }
    let scene = cli.scene;
    let sink: Box<dyn Write> = match &cli.output {
        Some(path) => Box::new(
            std::fs::File::create(path).map_err(|e| Usage(format!("cannot create {path}: {e}")))?,
        ),
        None => Box::new(io::stdout().lock()),
    };
    let mut out = BufWriter::new(sink);
    let mut io_error = None;
    let write_row = |out: &mut BufWriter<Box<dyn Write>>, o: &Outputs| {
        let fields: Vec<String> = o.values().iter().map(|v| format!("{v:e}")).collect();
        writeln!(out, "{}", fields.join(","))
    };
    writeln!(out, "{}", Outputs::COLUMNS.join(",")).map_err(|e| Usage(e.to_string()))?;
    let mut rows = 0usize;
    let mut max_drift: f64 = 0.0;
    let (mut e_min, mut e_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let start = Instant::now();
    let result = simulate(&scene, |o| {
        rows += 1;
        max_drift = max_drift.max(o.drift.abs());
        e_min = e_min.min(o.energy);
        e_max = e_max.max(o.energy);
        if io_error.is_none() {
            if let Err(e) = write_row(&mut out, o) {
                io_error = Some(e);
            }
        }
    });
    let elapsed = start.elapsed();
    if let Some(e) = io_error.or_else(|| out.flush().err()) {
        return Err(Usage(format!("writing the CSV failed: {e}")));
    }
    let report = result.map_err(|e| Usage(e.to_string()))?;
    if let Some(w) = &report.warning {
        eprintln!("beam-body: warning: {w}");
    }
    let stats = report.stats;
    let s = scene.solver;
    let mode = match s.fixed_step {
        Some(f) => format!("fixed step h = {:e} s, order {}", f.h, f.order),
        None => format!(
            "rtol {:e}, atol {:e}, max order {}, guard {}",
            s.rtol,
            s.atol(),
            s.max_order,
            if s.stability_guard { "on" } else { "off" }
        ),
    };
    eprintln!("beam-body: {} formulation, {mode}", scene.formulation);
    eprintln!(
        "  steps {}  rejected {} (error test {}, Newton {})  f-evals {} (+{} for Jacobians)",
        stats.steps,
        stats.rejected(),
        stats.error_test_failures,
        stats.newton_failures,
        stats.rhs_evals,
        stats.rhs_evals_jac
    );
    eprintln!(
        "  Jacobians {}  LU factorizations {}  Newton iterations {}  order caps {}  restarts {}",
        stats.jac_evals,
        stats.lu_factorizations,
        stats.newton_iters,
        stats.order_caps,
        stats.restarts
    );
    eprintln!(
        "  rows {rows}  max |drift| {max_drift:.3e} m  energy range {:.6e} J  wall {:.3} ms",
        e_max - e_min,
        elapsed.as_secs_f64() * 1e3
    );
    Ok(())
}

fn cmd_modes(args: &[String]) -> Result<(), Usage> {
    let cli = parse(args, false)?;
    let model = BeamBody::new(cli.scene.params).map_err(|e| Usage(e.to_string()))?;
    println!(
        "{:<6}  {:>19}  {:>19}  {:>17}  {:>17}",
        "phi", "v1_eq [m]", "theta1_eq [rad]", "T1 [s]", "T2 [s]"
    );
    for (label, phi) in [("0", 0.0), ("pi/2", PI / 2.0), ("pi", PI)] {
        let m = model.modes(phi);
        let fmt = |p: Option<f64>| p.map_or("unstable".to_string(), |t| format!("{t:.15}"));
        let [t1, t2] = m.periods();
        let (v, th) = m.equilibrium;
        println!("{label:<6}  {v:>+19.12e}  {th:>+19.12e}  {:>17}  {:>17}", fmt(t1), fmt(t2));
    }
    Ok(())
}

fn cmd_residual(args: &[String]) -> Result<(), Usage> {
    let cli = parse(args, false)?;
    let model = BeamBody::new(cli.scene.params).map_err(|e| Usage(e.to_string()))?;
    let form = cli.scene.formulation;
    let width = if form.is_dae() { 12 } else { 9 };
    let stdout = io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    for (i, line) in io::stdin().lock().lines().enumerate() {
        let line = line.map_err(|e| Usage(e.to_string()))?;
        if line.trim().is_empty() {
            continue;
        }
        let v: Vec<f64> = line
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|e| Usage(format!("stdin line {}: {e}", i + 1)))?;
        if v.len() != width {
            return Err(Usage(format!(
                "stdin line {}: {} numbers, the {form} formulation needs {width}",
                i + 1,
                v.len()
            )));
        }
        let phi = Phi { phi: v[0], dphi: v[1], ddphi: v[2] };
        let row: Vec<f64> = if form.is_dae() {
            let (x, xd, xdd) = (
                Vector3::new(v[3], v[4], v[5]),
                Vector3::new(v[6], v[7], v[8]),
                Vector3::new(v[9], v[10], v[11]),
            );
            let (a, b) = model.dae(&phi, x, xd);
            let acc = model.dae_accel(&phi, x, xd);
            (a * xdd - b).iter().chain(acc.iter()).copied().collect()
        } else {
            let linear = form == Formulation::Linear;
            let (q, qd, qdd) =
                (Vector2::new(v[3], v[4]), Vector2::new(v[5], v[6]), Vector2::new(v[7], v[8]));
            let (m, f) =
                if linear { model.linear(&phi, q, qd) } else { model.reduced(&phi, q, qd) };
            let acc = model.two_dof_accel(linear, &phi, q, qd);
            (m * qdd - f).iter().chain(acc.iter()).copied().collect()
        };
        let text: Vec<String> = row.iter().map(|x| format!("{x:e}")).collect();
        writeln!(out, "{}", text.join(" ")).map_err(|e| Usage(e.to_string()))?;
    }
    out.flush().map_err(|e| Usage(e.to_string()))
}

/// The most threads `study --threads` takes.
const MAX_THREADS: usize = 1024;

/// The options of `study`.
struct StudyArgs {
    file: String,
    output: Option<String>,
    cases: Option<(u64, u64)>,
    threads: Option<usize>,
    scene: Option<String>,
    quiet: bool,
    plan: bool,
}

fn parse_study_args(args: &[String]) -> Result<StudyArgs, Usage> {
    let mut out = StudyArgs {
        file: String::new(),
        output: None,
        cases: None,
        threads: None,
        scene: None,
        quiet: false,
        plan: false,
    };
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let mut value =
            |flag: &str| it.next().cloned().ok_or_else(|| Usage(format!("{flag} needs a value")));
        match arg.as_str() {
            "-o" | "--output" => out.output = Some(value(arg)?),
            "--cases" => {
                let text = value(arg)?;
                let range = text.split_once("..").and_then(|(a, b)| {
                    Some((a.trim().parse::<u64>().ok()?, b.trim().parse::<u64>().ok()?))
                });
                match range {
                    Some((a, b)) if a <= b => out.cases = Some((a, b)),
                    _ => {
                        return Err(Usage(format!(
                            "--cases {text}: expected A..B with integers 0 <= A <= B"
                        )))
                    }
                }
            }
            "--threads" => {
                let text = value(arg)?;
                match text.parse::<usize>() {
                    Ok(n) if (1..=MAX_THREADS).contains(&n) => out.threads = Some(n),
                    _ => {
                        return Err(Usage(format!(
                            "--threads {text}: must be an integer in 1..={MAX_THREADS}"
                        )))
                    }
                }
            }
            "--scene" => out.scene = Some(value(arg)?),
            "--quiet" | "-q" => out.quiet = true,
            "--plan" => out.plan = true,
            flag if flag.starts_with('-') => {
                return Err(Usage(format!("unknown option `{flag}`\n\n{USAGE}")))
            }
            file if out.file.is_empty() => out.file = file.to_string(),
            extra => return Err(Usage(format!("unexpected argument `{extra}`"))),
        }
    }
    if out.file.is_empty() {
        return Err(Usage(format!("study needs a study file\n\n{USAGE}")));
    }
    if let Some(o) = out.output.as_ref().filter(|o| o.to_ascii_lowercase().ends_with(".parquet")) {
        return Err(Usage(format!(
            "-o {o}: beam-body study writes CSV; the study tool writes Parquet: \
             python -m beam_body_study run {} -o {o} (or cargo xtask study run ...)",
            out.file
        )));
    }
    Ok(out)
}

fn cmd_study(args: &[String]) -> Result<(), Usage> {
    let a = parse_study_args(args)?;
    let text = std::fs::read_to_string(&a.file)
        .map_err(|e| Usage(format!("cannot read study file {}: {e}", a.file)))?;
    // The base scene: --scene, or the study's `scene` relative to the study file.
    let dir = Path::new(&a.file).parent().unwrap_or(Path::new("")).to_path_buf();
    let mut scene_file: Option<PathBuf> = None;
    let study = Study::parse(&text, |path| {
        let file = a.scene.as_ref().map_or_else(|| dir.join(path), PathBuf::from);
        let text = std::fs::read_to_string(&file)
            .map_err(|e| format!("cannot read the scene file {}: {e}", file.display()));
        scene_file = Some(file);
        text
    })
    .map_err(|e| Usage(format!("{}: {e}", a.file)))?;
    if let (Some(scene), None) = (&a.scene, study.scene_path()) {
        return Err(Usage(format!(
            "--scene {scene}: the study {} names no base scene (`scene = \"...\"`) to replace",
            a.file
        )));
    }
    let total = study.cases();
    let (first, end) = a.cases.unwrap_or((0, total));
    if end > total {
        return Err(Usage(format!(
            "--cases {first}..{end}: the study has {total} cases (0..{total})"
        )));
    }
    if a.plan {
        println!("{}", plan_json(&study, scene_file.as_deref()));
        return Ok(());
    }
    let threads =
        a.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));

    // The rows go to a temporary file beside OUT, renamed to OUT once all are written; into
    // OUT directly where it exists and is not a regular file (a device, a pipe).
    let special = |out: &String| std::fs::metadata(out).is_ok_and(|m| !m.is_file());
    let partial = a
        .output
        .as_ref()
        .filter(|out| !special(out))
        .map(|out| format!("{out}.partial-{}", std::process::id()));
    let sink: Box<dyn Write> = match (&partial, &a.output) {
        (Some(path), _) | (None, Some(path)) => Box::new(
            std::fs::File::create(path).map_err(|e| Usage(format!("cannot create {path}: {e}")))?,
        ),
        (None, None) => Box::new(io::stdout().lock()),
    };
    let mut out = BufWriter::new(sink);
    let header: Vec<String> = study.columns().into_iter().map(|(name, _)| name).collect();
    let mut progress = Progress::new(end - first, threads, a.quiet);
    let mut counts = [0u64; 5];
    let start = Instant::now();
    let result = writeln!(out, "{}", header.join(",")).and_then(|()| {
        run_cases(
            &study,
            first..end,
            threads,
            |done| progress.update(done),
            |row| {
                counts[row.status as usize] += 1;
                write_study_row(&mut out, &row)
            },
        )
    });
    let result = result.and_then(|()| out.flush());
    drop(out);
    let elapsed = start.elapsed();
    progress.finish();
    if let Err(e) = result {
        if let Some(p) = &partial {
            let _ = std::fs::remove_file(p);
        }
        return Err(Usage(format!("writing the rows failed: {e}")));
    }
    if let (Some(p), Some(out)) = (&partial, &a.output) {
        std::fs::rename(p, out).map_err(|e| Usage(format!("cannot rename {p} to {out}: {e}")))?;
    }
    if !a.quiet {
        let n = end - first;
        let secs = elapsed.as_secs_f64();
        let statuses: Vec<String> = [Status::Ok, Status::Warning, Status::Stopped]
            .into_iter()
            .chain([Status::Failed, Status::Invalid])
            .filter(|&s| counts[s as usize] > 0)
            .map(|s| format!("{} {}", s.name(), counts[s as usize]))
            .collect();
        eprintln!(
            "study: {n} cases in {secs:.2} s, {:.0} cases/s on {threads} threads; {}",
            n as f64 / secs.max(1e-9),
            if statuses.is_empty() { "no cases".to_string() } else { statuses.join(", ") }
        );
    }
    Ok(())
}

/// One CSV row: numbers in Rust's shortest round-trip form (read back exactly), an empty
/// field for a metric the run did not reach, the message quoted as RFC 4180 has it.
fn write_study_row(out: &mut impl Write, row: &Row) -> io::Result<()> {
    write!(out, "{}", row.case)?;
    for v in &row.values {
        write!(out, ",{v:e}")?;
    }
    for m in &row.metrics {
        match m {
            Some(v) => write!(out, ",{v:e}")?,
            None => write!(out, ",")?,
        }
    }
    // One line per row, whatever a message holds.
    let msg = row.message.replace(['\n', '\r'], " ");
    if msg.contains([',', '"']) {
        write!(out, ",{},\"{}\",{}", row.status.name(), msg.replace('"', "\"\""), row.steps)?;
    } else {
        write!(out, ",{},{msg},{}", row.status.name(), row.steps)?;
    }
    writeln!(out)
}

/// `study --plan`: what the study is, as JSON.
fn plan_json(study: &Study, scene_file: Option<&Path>) -> String {
    let quote = |s: &str| {
        let mut q = String::from('"');
        for c in s.chars() {
            match c {
                '"' => q.push_str("\\\""),
                '\\' => q.push_str("\\\\"),
                c if (c as u32) < 0x20 => q.push_str(&format!("\\u{:04x}", c as u32)),
                c => q.push(c),
            }
        }
        q.push('"');
        q
    };
    let list = |items: Vec<String>| format!("[{}]", items.join(", "));
    let scene = scene_file
        .map(|p| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf()))
        .map_or("null".to_string(), |p| quote(&p.to_string_lossy()));
    let columns = study
        .columns()
        .into_iter()
        .map(|(name, ty)| format!("{{\"name\": {}, \"type\": \"{ty}\"}}", quote(&name)))
        .collect();
    format!(
        "{{\"cases\": {}, \"samples\": {}, \"scene\": {scene}, \"parameters\": {}, \"metrics\": {}, \"columns\": {}}}",
        study.cases(),
        study.samples(),
        list(study.parameters().iter().map(|p| quote(&p.name)).collect()),
        list(study.metrics().iter().map(|m| quote(m.name())).collect()),
        list(columns)
    )
}

/// The progress line of `study` on stderr: redrawn in place on a terminal, a line every 10 s
/// otherwise.
struct Progress {
    total: u64,
    threads: usize,
    start: Instant,
    last: Option<Instant>,
    every: Duration,
    terminal: bool,
    quiet: bool,
    done: u64,
}

impl Progress {
    fn new(total: u64, threads: usize, quiet: bool) -> Self {
        let terminal = io::stderr().is_terminal();
        let every = Duration::from_millis(if terminal { 250 } else { 10_000 });
        Self { total, threads, start: Instant::now(), last: None, every, terminal, quiet, done: 0 }
    }

    fn update(&mut self, done: u64) {
        self.done = done;
        let now = Instant::now();
        if self.quiet || now.duration_since(self.last.unwrap_or(self.start)) < self.every {
            return;
        }
        self.last = Some(now);
        let secs = now.duration_since(self.start).as_secs_f64();
        let rate = done as f64 / secs.max(1e-9);
        let left = if done > 0 {
            format!("{:.0} s left", (self.total - done) as f64 / rate)
        } else {
            "time left unknown".to_string()
        };
        let line = format!(
            "study: {done}/{} cases  {:.0} %  {rate:.0} cases/s on {} threads  {left}",
            self.total,
            100.0 * done as f64 / self.total.max(1) as f64,
            self.threads
        );
        if self.terminal {
            eprint!("\r{line}\x1b[K");
        } else {
            eprintln!("{line}");
        }
    }

    fn finish(&self) {
        if self.terminal && !self.quiet && self.last.is_some() {
            eprintln!();
        }
    }
}
