//! `cargo xtask bench-elements [--quick]`: work against precision of the beam in 8 elements
//! (32 states), ours beside CVODE and diffsol, and `bench-elements-run`, its measuring part
//! (built with the feature `peers`).
//!
//! The scene: the paper's (scenes/paper.toml) with `n_elements = 8` and `damping_ratio =
//! 0.01`, reduced, on the benchmark's grid (0.01 s). Undamped, the jump of φ″ sets all 16
//! modes ringing for ever and every BDF must resolve the highest (10,800 rad/s; README,
//! *Limits*): a test of patience, not of solvers. Damped at 1 % in its first two modes, as a
//! real beam is, the high modes die out and the run is set by the modes that carry the motion.
//!
//! Ours runs as the CLI does (`Run`: the structured O(n) Newton, the stability guard). CVODE
//! (7.1.1 at -O3, its dense linear solver and dense difference-quotient Jacobian) and diffsol
//! (its BDF, nalgebra LU, the same difference-quotient Jacobian) get the same right-hand side
//! through `problem::FixedElements`. CVODE also runs with its band linear solver and band
//! difference-quotient Jacobian, the states node by node (`Order::ByNode`). The first-order
//! Jacobian holds M⁻¹ of the beam's band mass matrix, which is full, and the body couples
//! every node through u1 = −½qᵀGq: the exact Jacobian's band is the whole matrix (`cvode-band`,
//! half-bandwidths 31), and a narrower band is a truncated Jacobian that CVODE's modified
//! Newton may or may not converge with (`cvode-band15`, 3¾ nodes each side, and
//! `cvode-band23`; 3 to 15 were tried: every one up to 15 fails within the first 0.8 s at every
//! rtol from 1e-4 to 1e-8, its step driven down until 5,000 steps do not reach the next grid
//! time).
//!
//! The reference is ours at rtol 1e-12, checked against CVODE at 1e-12 (the disagreement is
//! in the report); the error is the benchmark's: the RMS over the grid and over v1, ϑ1, v̇1,
//! ϑ̇1 of (y − y_ref)/max|y_ref|. Timing: one untimed solve of each case, then R rounds (5;
//! 3 with `--quick`) of every case in a shuffled order; the median per case. The ratio at equal
//! error compares our time with CVODE's interpolated (log–log) at our error.

use std::fmt::Write as _;
use std::time::Instant;

use beam_body::model::Formulation;

use super::problem::{on_grid, read_scene, Outcome, Problem};
use super::{cvode, ours, shuffle};
use crate::{cargo, project_root, run_cmd, Mode, Result};

/// The solvers compared: ours as the CLI runs it, and without its stability guard (the dense
/// eigenvalues of the 32×32 Jacobian; on this damped scene its steps differ by a few per cent),
/// CVODE as it comes, CVODE with a Jacobian at the latest every 200 steps as ours takes them
/// with a Jacobian in parts (`CVodeSetJacEvalFrequency`; its Jacobians are 32 f-evaluations
/// each), CVODE with its band solver (the whole band, and two truncated bands; see the
/// module's documentation), and diffsol.
const SOLVERS: [&str; 8] = [
    "bdf",
    "bdf-noguard",
    "cvode",
    "cvode-msbj200",
    "cvode-band",
    "cvode-band15",
    "cvode-band23",
    "diffsol",
];
/// At most this many steps between two grid times for CVODE with a truncated band Jacobian
/// (CVODE's `mxstep` counts per output; see `solve`).
const TRUNCATED_MAX_STEPS: std::ffi::c_long = 5_000;
/// The CVODE runs the ratios are taken against.
const CVODES: [&str; 3] = ["cvode", "cvode-msbj200", "cvode-band"];

fn tolerances(mode: Mode) -> Vec<f64> {
    match mode {
        Mode::Full => (4..=10).map(|k| 10f64.powi(-k)).collect(),
        Mode::Quick => vec![1e-4, 1e-6, 1e-8],
    }
}

fn rounds(mode: Mode) -> usize {
    match mode {
        Mode::Full => 5,
        Mode::Quick => 3,
    }
}

/// `bench-elements`: the optimised CVODE, then `bench-elements-run` with `peers`.
pub fn run(mode: Mode) -> Result {
    let mut cmd = cargo(["run", "--quiet", "--release", "-p", "beam-body-bench", "--features"]);
    cmd.args(["peers", "--", "bench-elements-run"]);
    if mode == Mode::Quick {
        cmd.arg("--quick");
    }
    if let Some(lib) = super::optimized_cvode() {
        cmd.env(super::CVODE_LIB_VARIABLE, lib);
    }
    run_cmd(&mut cmd)
}

/// The scene of the benchmark.
fn problem() -> Result<Problem> {
    let path = project_root().join("scenes").join("paper.toml");
    let mut scene = read_scene(&path)?;
    scene.params.n_elements = super::problem::ELEMENTS;
    scene.params.damping_ratio = 0.01;
    scene.formulation = Formulation::Reduced;
    Ok(on_grid("elements-8", scene, &path)?)
}

fn solve(solver: &str, problem: &Problem, rtol: f64) -> std::result::Result<Outcome, String> {
    match solver {
        "bdf" => ours::bdf(problem, rtol),
        "bdf-noguard" => {
            let mut scene = problem.scene.clone();
            scene.solver.stability_guard = false;
            let unguarded =
                Problem { name: problem.name.clone(), scene, grid: problem.grid.clone() };
            ours::bdf(&unguarded, rtol)
        }
        "cvode" => cvode::run(problem, rtol),
        "cvode-msbj200" => {
            let options = cvode::Options { msbj: Some(200), ..Default::default() };
            cvode::run_with(problem, rtol, options)
        }
        band if band.starts_with("cvode-band") => {
            let width = band["cvode-band".len()..].parse().unwrap_or(i64::MAX);
            // A truncated band's Newton may crawl at tiny steps before it fails: stop it at
            // 5,000 steps between grid times (the dense solver takes 32 on average at 1e-10).
            let options = cvode::Options {
                band: Some(width),
                max_steps: Some(TRUNCATED_MAX_STEPS),
                ..Default::default()
            };
            cvode::run_with(problem, rtol, options)
        }
        #[cfg(feature = "peers")]
        "diffsol" => super::diffsol::run(problem, rtol),
        other => Err(format!("solver `{other}` not built (feature `peers`)")),
    }
}

/// The rows of an outcome (v1, ϑ1, v̇1, ϑ̇1 per grid time).
fn rows(o: &Outcome) -> Vec<[f64; 4]> {
    o.states.rows().map(|r| [r[0], r[1], r[2], r[3]]).collect()
}

/// One case's result.
struct Point {
    solver: &'static str,
    rtol: f64,
    error: f64,
    seconds: f64,
    steps: Option<u64>,
    rhs_evals: Option<u64>,
    jac_evals: Option<u64>,
    /// Why the solve failed (a truncated band Jacobian), if it did.
    failure: Option<String>,
}

impl Point {
    fn failed(solver: &'static str, rtol: f64, why: String) -> Point {
        let (steps, rhs_evals, jac_evals) = (None, None, None);
        let (error, seconds, failure) = (f64::NAN, f64::NAN, Some(why));
        Point { solver, rtol, error, seconds, steps, rhs_evals, jac_evals, failure }
    }
}

/// `bench-elements-run [--quick]`: measures and writes target/bench/elements.md (copied to
/// docs/work_precision_elements.md by a full run).
pub fn run_measure(mode: Mode) -> Result {
    let problem = problem()?;
    let started = Instant::now();
    let reference = rows(&ours::bdf(&problem, 1e-12)?);
    let check = rows(&cvode::run(&problem, 1e-12)?);
    let (disagreement, _) = crate::sweep::relative_error(&check, &reference, &[0, 1, 2, 3]);
    eprintln!(
        "bench-elements: reference (ours at 1e-12) against CVODE at 1e-12: {disagreement:.2e}"
    );

    let mut cases: Vec<(&'static str, f64)> = Vec::new();
    for rtol in tolerances(mode) {
        cases.extend(SOLVERS.iter().map(|&s| (s, rtol)));
    }
    // Untimed: the error and the counters, and every code path warm.
    // A CVODE with a truncated band Jacobian may fail; its failure is reported, not timed.
    let mut points: Vec<Point> = Vec::new();
    for &(solver, rtol) in &cases {
        let o = match solve(solver, &problem, rtol) {
            Ok(o) => o,
            Err(e) if solver.starts_with("cvode-band") => {
                eprintln!("bench-elements: {solver} at {rtol:e} failed: {e}");
                points.push(Point::failed(solver, rtol, e));
                continue;
            }
            Err(e) => return Err(format!("{solver} at {rtol:e}: {e}").into()),
        };
        let (error, _) = crate::sweep::relative_error(&rows(&o), &reference, &[0, 1, 2, 3]);
        let c = o.counters;
        eprintln!("bench-elements: {solver} at {rtol:e}: error {error:.2e}, {:?} steps", c.steps);
        points.push(Point {
            solver,
            rtol,
            error,
            seconds: f64::NAN,
            steps: c.steps,
            rhs_evals: c.rhs_evals,
            jac_evals: c.jac_evals,
            failure: None,
        });
    }
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); cases.len()];
    for round in 0..rounds(mode) {
        let mut order: Vec<usize> =
            (0..cases.len()).filter(|&k| points[k].failure.is_none()).collect();
        shuffle(&mut order, round as u64 + 1);
        for k in order {
            let (solver, rtol) = cases[k];
            let t = Instant::now();
            let o = solve(solver, &problem, rtol)?;
            times[k].push(t.elapsed().as_secs_f64());
            std::hint::black_box(o);
        }
        eprintln!("bench-elements: round {} of {} done", round + 1, rounds(mode));
    }
    for (p, t) in points.iter_mut().zip(&mut times) {
        t.sort_by(f64::total_cmp);
        if !t.is_empty() {
            p.seconds = t[t.len() / 2];
        }
    }
    let md = report(&points, disagreement, mode, started.elapsed().as_secs_f64());
    super::write_report(&md, "elements.md", "work_precision_elements.md", mode)?;
    Ok(())
}

/// Our time over CVODE's at our error, CVODE's time interpolated in log–log between its two
/// points that bracket the error (`None` outside CVODE's range).
fn ratio_at_equal_error(ours: &Point, cvode: &[&Point]) -> Option<f64> {
    let mut sorted: Vec<&&Point> = cvode.iter().filter(|p| p.error > 0.0).collect();
    sorted.sort_by(|a, b| a.error.total_cmp(&b.error));
    let (e, ln) = (ours.error, f64::ln);
    sorted.windows(2).find(|w| w[0].error <= e && e <= w[1].error).map(|w| {
        let s = (ln(e) - ln(w[0].error)) / (ln(w[1].error) - ln(w[0].error));
        let t = (ln(w[0].seconds) + s * (ln(w[1].seconds) - ln(w[0].seconds))).exp();
        ours.seconds / t
    })
}

fn report(points: &[Point], disagreement: f64, mode: Mode, seconds: f64) -> String {
    let mut md = String::from("# Work against precision: the beam in 8 elements\n\n");
    let _ = writeln!(
        md,
        "Written by `cargo xtask bench-elements` ({}; {} rounds, medians; {:.0} s in all) on \
         this machine's 2 cores. The scene: scenes/paper.toml with `n_elements = 8` and \
         `damping_ratio = 0.01` (32 states), reduced, on the 0.01 s grid to 10.2 s. The error \
         is the RMS over the grid and over v1, ϑ1, v̇1, ϑ̇1 of (y − y_ref)/max|y_ref|, against \
         ours at rtol 1e-12, which CVODE at 1e-12 matches to {disagreement:.1e}: integration \
         error, not the model's (docs/model_error.md). See bench/src/bench/elements.rs for \
         what each solver gets.\n",
        if mode == Mode::Quick { "--quick" } else { "full" },
        rounds(mode),
        seconds
    );
    md.push_str(
        "| solver | rtol | error | time [ms] | steps | f-evaluations | Jacobians | µs a step |\n",
    );
    md.push_str("|---|---|---|---|---|---|---|---|\n");
    let opt = |x: Option<u64>| x.map_or("—".to_string(), |v| v.to_string());
    for p in points {
        if let Some(why) = &p.failure {
            let why = why.split(": ").last().unwrap_or(why).trim_end_matches('.');
            let _ = writeln!(md, "| {} | {:e} | failed: {why} | | | | | |", p.solver, p.rtol);
            continue;
        }
        let per_step =
            p.steps.map_or("—".to_string(), |s| format!("{:.2}", 1e6 * p.seconds / s as f64));
        let _ = writeln!(
            md,
            "| {} | {:e} | {:.2e} | {:.2} | {} | {} | {} | {per_step} |",
            p.solver,
            p.rtol,
            p.error,
            1e3 * p.seconds,
            opt(p.steps),
            opt(p.rhs_evals),
            opt(p.jac_evals)
        );
    }
    let of = |name: &str| -> Vec<&Point> { points.iter().filter(|p| p.solver == name).collect() };
    for peer in CVODES {
        let _ = writeln!(
            md,
            "\nOur time over `{peer}`'s at the same error (its time interpolated log–log):\n"
        );
        let cvode = of(peer);
        for ours in ["bdf", "bdf-noguard"] {
            let _ = writeln!(md, "- `{ours}`:");
            let mut ratios = Vec::new();
            for p in of(ours) {
                let _ = match ratio_at_equal_error(p, &cvode) {
                    Some(r) => {
                        ratios.push(r);
                        writeln!(md, "  - rtol {:e} (error {:.2e}): {r:.2}", p.rtol, p.error)
                    }
                    None => writeln!(
                        md,
                        "  - rtol {:e} (error {:.2e}): outside its range",
                        p.rtol, p.error
                    ),
                };
            }
            if !ratios.is_empty() {
                ratios.sort_by(f64::total_cmp);
                let _ = writeln!(md, "  - median: **{:.2}**", ratios[ratios.len() / 2]);
            }
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    /// CVODE's band solver on the whole band solves the 8-element scene as the dense one does,
    /// and a band cut to 7 fails. Needs CVODE: ignored by a plain `cargo test`; `cargo xtask
    /// test` builds CVODE and runs it with `BEAM_BODY_CVODE_LIB` set.
    #[test]
    #[ignore = "needs CVODE (BEAM_BODY_CVODE_LIB): cargo xtask test builds it and runs this"]
    fn cvode_band_solver_needs_the_whole_band() {
        cvode::describe().expect("the CVODE library loads");
        let problem = problem().unwrap();
        let dense = rows(&solve("cvode", &problem, 1e-6).unwrap());
        let band = rows(&solve("cvode-band", &problem, 1e-6).unwrap());
        let (difference, _) = crate::sweep::relative_error(&band, &dense, &[0, 1, 2, 3]);
        eprintln!("band against dense at rtol 1e-6: {difference:.2e}");
        assert!(difference < 1e-4, "{difference:e}");
        let cut = solve("cvode-band7", &problem, 1e-6);
        assert!(cut.as_ref().is_err_and(|e| e.contains("mxstep")), "{:?}", cut.err());
    }
}
