//! `beam-body study`: a design study on every core, one CSV row per case.

use crate::location::at_file;
use crate::output::Output;
use crate::progress::Progress;
use crate::{interrupt, note, print, CmdResult, Failure};
use beam_body::csv;
use beam_body::study::{run_cases, Row, Status, Study};
use lexopt::prelude::*;
use std::ffi::OsString;
use std::io::Write;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

pub const HELP: &str = "\
usage: beam-body study STUDY.toml [OPTIONS] [-o OUT.csv]
       beam-body study STUDY.toml --plan

Runs a design study (README: Design studies) on every core and writes one CSV row per
case: case, the parameters, the metrics, status, message, steps (headers name their
units, as simulate's do). The rows go to stdout, or to OUT.csv, which appears when the
study is done. The number of cases is stated first, on stderr. Ctrl-C starts no case
more, lets the cases running finish, keeps the rows (OUT.csv.partial) and names the
--cases that go on from there.

options:
  --cases A..B        run cases A..B (half-open) only
  --threads N         threads, 1..=1024 (default: one per core)
  --scene FILE        the base scene FILE instead of the study's `scene`
  --max-cases N       refuse to run more than N cases (default 1000000)
  --quiet, -q         no progress or summary on stderr
  --plan              check the study and print, as JSON, its number of cases, its
                      columns, its base scene and its fingerprint; run nothing
  -o, --output FILE   write the CSV to FILE (-: stdout)
  -h, --help          this text
";

/// The most threads `--threads` takes.
const MAX_THREADS: usize = 1024;
/// The default of `--max-cases`.
const MAX_CASES_DEFAULT: u64 = 1_000_000;

struct StudyArgs {
    file: String,
    output: Option<String>,
    cases: Option<(u64, u64)>,
    threads: Option<usize>,
    scene: Option<String>,
    max_cases: u64,
    quiet: bool,
    plan: bool,
}

fn parse(args: Vec<OsString>) -> Result<Option<StudyArgs>, Failure> {
    let mut parser = lexopt::Parser::from_args(args);
    let mut a = StudyArgs {
        file: String::new(),
        output: None,
        cases: None,
        threads: None,
        scene: None,
        max_cases: MAX_CASES_DEFAULT,
        quiet: false,
        plan: false,
    };
    let mut file = None;
    while let Some(arg) = parser.next().map_err(bad)? {
        match arg {
            Long("help") | Short('h') => {
                print(HELP)?;
                return Ok(None);
            }
            Short('o') | Long("output") => {
                a.output = Some(parser.value().map_err(bad)?.string().map_err(bad)?)
            }
            Long("cases") => {
                let text = parser.value().map_err(bad)?.string().map_err(bad)?;
                let range = text.split_once("..").and_then(|(x, y)| {
                    Some((x.trim().parse::<u64>().ok()?, y.trim().parse::<u64>().ok()?))
                });
                a.cases = match range {
                    Some((x, y)) if x <= y => Some((x, y)),
                    _ => {
                        return Err(Failure::Usage(format!(
                            "--cases {text}: expected A..B with integers 0 <= A <= B"
                        )))
                    }
                };
            }
            Long("threads") => {
                let within = |n: &usize| (1..=MAX_THREADS).contains(n);
                let wanted = format!("an integer in 1..={MAX_THREADS}");
                a.threads = Some(integer(&mut parser, "--threads", within, &wanted)?);
            }
            Long("max-cases") => {
                a.max_cases =
                    integer(&mut parser, "--max-cases", |n| *n >= 1, "a positive integer")?;
            }
            Long("scene") => a.scene = Some(parser.value().map_err(bad)?.string().map_err(bad)?),
            Long("quiet") | Short('q') => a.quiet = true,
            Long("plan") => a.plan = true,
            Value(v) if file.is_none() => file = Some(v.string().map_err(bad)?),
            other => return Err(bad(other.unexpected())),
        }
    }
    a.file = file.ok_or_else(|| {
        Failure::Usage("study needs a study file (beam-body study --help)".into())
    })?;
    if let Some(o) = a.output.as_ref().filter(|o| o.to_ascii_lowercase().ends_with(".parquet")) {
        return Err(Failure::Usage(format!(
            "-o {o}: beam-body study writes CSV; the study tool writes Parquet: \
             beam-body-study run {} -o {o} (or cargo xtask study run ...)",
            a.file
        )));
    }
    Ok(Some(a))
}

/// A parser's error as the study's usage error.
fn bad(e: lexopt::Error) -> Failure {
    Failure::Usage(format!("study: {e} (beam-body study --help)"))
}

/// The integer value of `flag`, refused, with the flag and the text, unless `ok`.
fn integer<T: std::str::FromStr>(
    parser: &mut lexopt::Parser,
    flag: &str,
    ok: impl Fn(&T) -> bool,
    wanted: &str,
) -> Result<T, Failure> {
    let text = parser.value().map_err(bad)?.string().map_err(bad)?;
    match text.parse::<T>() {
        Ok(n) if ok(&n) => Ok(n),
        _ => Err(Failure::Usage(format!("{flag} {text}: must be {wanted}"))),
    }
}

pub fn run(args: Vec<OsString>) -> CmdResult {
    let Some(a) = parse(args)? else {
        return Ok(());
    };
    let text = std::fs::read_to_string(&a.file)
        .map_err(|e| Failure::Usage(format!("cannot read the study file {}: {e}", a.file)))?;
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
    .map_err(|e| Failure::Usage(at_file(&a.file, &e)))?;
    if let (Some(scene), None) = (&a.scene, study.scene_path()) {
        return Err(Failure::Usage(format!(
            "--scene {scene}: the study {} names no base scene (`scene = \"...\"`) to replace",
            a.file
        )));
    }
    let total = study.cases();
    let (first, end) = a.cases.unwrap_or((0, total));
    if end > total {
        return Err(Failure::Usage(format!(
            "--cases {first}..{end}: the study has {total} cases (0..{total})"
        )));
    }
    if a.plan {
        return print(&format!("{}\n", plan_json(&study, scene_file.as_deref())));
    }
    let n = end - first;
    if n > a.max_cases {
        return Err(Failure::Usage(format!(
            "{}: {n} cases to run, more than --max-cases {}: check the study's counts and \
             samples, or pass --max-cases {n} to run them all",
            a.file, a.max_cases
        )));
    }
    let threads =
        a.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if !a.quiet {
        note(format_args!("study: {n} cases of {total} on {threads} threads"));
    }

    // Everything is checked: the rows go to OUT through a temporary file (`output.rs`).
    interrupt::install();
    let mut out = Output::open(a.output.as_deref())?;
    let header: Vec<String> = study.columns().into_iter().map(|(name, _)| name).collect();
    let integer: Vec<bool> = study.parameters().iter().map(|p| p.is_integer()).collect();
    let mut progress =
        Progress::new(n as f64, Duration::from_secs(1), true, a.quiet, move |done, rate| {
            format!("study: {done:.0}/{n} cases, {rate:.0} cases/s on {threads} threads")
        });
    let mut counts = [0u64; 5];
    let mut written = 0u64;
    let mut line = String::new();
    let start = Instant::now();
    let result = writeln!(out.writer(), "{}", header.join(",")).and_then(|()| {
        run_cases(
            &study,
            first..end,
            threads,
            |done| {
                progress.update(done as f64);
                if interrupt::interrupted() {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            },
            |row| {
                counts[row.status as usize] += 1;
                line.clear();
                study_row(&mut line, &row, &integer);
                written += 1;
                // A row a case, as it comes: a case takes far longer than a write, and
                // the file shows the study's progress.
                let w = out.writer();
                w.write_all(line.as_bytes()).and_then(|()| w.flush())
            },
        )
    });
    let elapsed = start.elapsed();
    progress.finish();
    if let Err(e) = result {
        let failure = out.failed(e);
        out.abandon();
        return Err(failure);
    }
    if interrupt::interrupted() && first + written < end {
        let wrote = out.abandon();
        let done = first + written;
        let rest = match &a.output {
            Some(_) => "-o REST.csv",
            None => "> REST.csv",
        };
        return Err(Failure::Interrupted(format!(
            "interrupted: the rows of cases {first}..{done} of {first}..{end} are in {wrote}; \
             the rest: beam-body study {} --cases {done}..{end} {rest}",
            a.file
        )));
    }
    out.finish()?;
    if !a.quiet {
        let secs = elapsed.as_secs_f64();
        let statuses: Vec<String> = [Status::Ok, Status::Warning, Status::Stopped]
            .into_iter()
            .chain([Status::Failed, Status::Invalid])
            .filter(|&s| counts[s as usize] > 0)
            .map(|s| format!("{} {}", s.name(), counts[s as usize]))
            .collect();
        note(format_args!(
            "study: {n} cases in {secs:.2} s, {:.0} cases/s on {threads} threads; {}",
            n as f64 / secs.max(1e-9),
            if statuses.is_empty() { "no cases".to_string() } else { statuses.join(", ") }
        ));
    }
    Ok(())
}

/// One CSV row into `line`: numbers as `simulate` writes them, an integer parameter's value
/// (where `integer[i]`) as an integer, an empty field for a metric the run did not reach, the
/// message quoted as RFC 4180 has it.
fn study_row(line: &mut String, row: &Row, integer: &[bool]) {
    line.push_str(&row.case.to_string());
    for (v, &int) in row.values.iter().zip(integer) {
        line.push(',');
        if int {
            line.push_str(&(*v as i64).to_string());
        } else {
            csv::push_number(line, *v);
        }
    }
    for m in &row.metrics {
        line.push(',');
        if let Some(v) = m {
            csv::push_number(line, *v);
        }
    }
    // One line per row, whatever a message holds.
    let msg = row.message.replace(['\n', '\r'], " ");
    line.push(',');
    line.push_str(row.status.name());
    line.push(',');
    if msg.contains([',', '"']) {
        line.push('"');
        line.push_str(&msg.replace('"', "\"\""));
        line.push('"');
    } else {
        line.push_str(&msg);
    }
    line.push(',');
    line.push_str(&row.steps.to_string());
    line.push('\n');
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
        "{{\"cases\": {}, \"samples\": {}, \"scene\": {scene}, \"fingerprint\": \"{}\", \
         \"parameters\": {}, \"metrics\": {}, \"columns\": {}}}",
        study.cases(),
        study.samples(),
        study.fingerprint(),
        list(study.parameters().iter().map(|p| quote(&p.name)).collect()),
        list(study.metrics().iter().map(|m| quote(m.name())).collect()),
        list(columns)
    )
}
