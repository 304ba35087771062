//! The cost of one fmi2DoStep for each way φ arrives, against the communication step, from a
//! bare C host (`tests/c_host/host.c --bench-dostep`): the packaged FMU's library loaded with
//! dlopen, the paper's scene at tolerance 1e-6, communication steps 1e-2, 1e-3 and 1e-4 s; and
//! the exact beam in 8 elements at 1e-3 s, with the BDF and with Radau IIA.
//!
//! The floor is one internal step per communication step: the fixed-step BDF2 with h = the
//! communication step and φ from the built-in law, through the same FMI calls. Each other way
//! is timed with what it needs per step: fmi2SetReal of φ, and fmi2SetRealInputDerivatives of
//! φ′ and φ″ for the derivatives; the host's signal is computed before the clock starts. The
//! host runs every case once per round, in an order shuffled with the round as seed, a warm-up
//! round 0 first; the figure per case is the median over the timed rounds of (loop time /
//! communication steps), and its ratio to the floor's median at the same step. The real-time factor is the simulated 10.2 s over the loop time.
//!
//! Files: `target/bench/dostep.csv` (the host's rows) and `target/bench/dostep.md`, copied to
//! `docs/dostep.md` by the full run.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

use crate::{project_root, relative, write_text, Mode, Result};

/// The feeds in the order of the report, as the host names them.
const FEEDS: [&str; 8] = [
    "floor",
    "law",
    "values",
    "derivatives",
    "taylor",
    "exact-bdf",
    "exact-radau",
    "exact-radau-1e-4",
];

/// Compiles the host, runs it on the extracted FMU in `fmu_dir`, and writes the report.
pub fn run(mode: Mode, fmu_dir: &Path, out_dir: &Path) -> Result<String> {
    let exe = out_dir.join("dostep-host");
    let host_c = project_root().join("tests").join("c_host").join("host.c");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let mut compile = Command::new(&cc);
    compile
        .args(["-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-o"])
        .arg(&exe)
        .arg(&host_c)
        .args(["-ldl", "-lpthread", "-lm"]);
    crate::run_cmd(&mut compile)?;
    let rounds = match mode {
        Mode::Full => 10,
        Mode::Quick => 3,
    };
    eprintln!("$ {} {} --bench-dostep {rounds}", relative(&exe), relative(fmu_dir));
    let output = Command::new(&exe)
        .arg(fmu_dir)
        .args(["--bench-dostep", &rounds.to_string()])
        .output()
        .map_err(|err| format!("could not run {}: {err}", relative(&exe)))?;
    if !output.status.success() {
        return Err(format!(
            "{} --bench-dostep failed: {}",
            relative(&exe),
            String::from_utf8_lossy(&output.stderr)
        )
        .into());
    }
    let csv = String::from_utf8_lossy(&output.stdout).into_owned();
    write_text(&out_dir.join("dostep.csv"), &csv)?;
    let report = report(&csv, rounds)?;
    write_text(&out_dir.join("dostep.md"), &report)?;
    Ok(report)
}

/// The median of `values` (not empty).
fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// The Markdown table from the host's CSV: per communication step and feed, the median ns per
/// DoStep over the timed rounds, its ratio to the floor and the real-time factor.
fn report(csv: &str, rounds: u32) -> Result<String> {
    // (h text, feed) -> ns per DoStep, one per timed round
    let mut cost: BTreeMap<(String, String), Vec<f64>> = BTreeMap::new();
    let mut loop_s: BTreeMap<(String, String), Vec<f64>> = BTreeMap::new();
    for line in csv.lines().skip(1).filter(|l| !l.is_empty()) {
        let f: Vec<&str> = line.split(',').collect();
        let [round, feed, h, steps, seconds] = f[..] else {
            return Err(format!("dostep.csv: bad row `{line}`").into());
        };
        if round == "0" {
            continue;
        }
        let (steps, seconds): (f64, f64) = (
            steps.parse().map_err(|_| format!("dostep.csv: steps in `{line}`"))?,
            seconds.parse().map_err(|_| format!("dostep.csv: seconds in `{line}`"))?,
        );
        let key = (h.to_string(), feed.to_string());
        cost.entry(key.clone()).or_default().push(seconds / steps * 1e9);
        loop_s.entry(key).or_default().push(seconds);
    }
    let mut hs: Vec<String> = cost.keys().map(|(h, _)| h.clone()).collect();
    hs.sort_by(|a, b| b.parse::<f64>().unwrap_or(0.0).total_cmp(&a.parse().unwrap_or(0.0)));
    hs.dedup();
    let mut md = String::new();
    writeln!(
        md,
        "# The cost of one fmi2DoStep\n\n`cargo xtask bench`: the paper's scene (10.2 s) at \
         tolerance 1e-6 through a bare C host (`tests/c_host/host.c --bench-dostep`), medians of \
         {rounds} shuffled rounds after a warm-up. *floor*: the fixed-step BDF2 with h = the \
         communication step and φ from the law, one internal step per communication step; \
         *law*: the adaptive BDF with φ from the law; *values*, *derivatives*: φ sent as an \
         input (fmi2SetReal; with fmi2SetRealInputDerivatives of φ′ and φ″), smooth \
         interpolation; *taylor*: derivatives with `phi_interpolation = taylor`. At H = 1e-3 \
         only, the exact beam in 8 elements (`beam = exact`, `n_elements = 8`) with the law: \
         *exact-bdf* and *exact-radau*, `integrator = bdf` and `radau` at tolerance 1e-6; \
         *exact-radau-1e-4*: Radau at 1e-4, where 8 elements are within 1e-4 of the converged \
         beam (docs/work_precision_exact.md). × floor is against the paper's model's floor.\n"
    )
    .expect("String");
    writeln!(md, "| H [s] | way φ arrives | ns per DoStep | × floor | real-time factor |")
        .expect("String");
    writeln!(md, "| --- | --- | --- | --- | --- |").expect("String");
    for h in &hs {
        let floor = cost.get(&(h.clone(), "floor".into())).cloned().map(median);
        for feed in FEEDS {
            let key = (h.clone(), feed.to_string());
            let (Some(c), Some(s)) = (cost.get(&key), loop_s.get(&key)) else { continue };
            let ns = median(c.clone());
            let ratio = floor.map_or(f64::NAN, |f| ns / f);
            let rtf = 10.2 / median(s.clone());
            writeln!(md, "| {h} | {feed} | {ns:.0} | {ratio:.2} | {rtf:.0} |").expect("String");
        }
    }
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_takes_medians_of_the_timed_rounds_and_ratios_to_the_floor() {
        let csv = "round,feed,h,steps,seconds\n\
                   0,floor,0.01,1020,9\n\
                   1,floor,0.01,1020,0.000102\n2,floor,0.01,1020,0.000204\n3,floor,0.01,1020,0.000306\n\
                   1,law,0.01,1020,0.000204\n2,law,0.01,1020,0.000408\n3,law,0.01,1020,0.000306\n";
        let md = report(csv, 3).unwrap();
        assert!(md.contains("| 0.01 | floor | 200 | 1.00 |"), "{md}");
        assert!(md.contains("| 0.01 | law | 300 | 1.50 |"), "{md}");
    }
}
