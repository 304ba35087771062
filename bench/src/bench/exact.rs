//! `cargo xtask bench-exact [--quick]`: the exact beam at the paper's price (issue 46). The
//! undamped paper scene (scenes/paper.toml, reduced, 10.2 s) with the geometrically exact beam
//! in n elements, each integrator, against the paper's model (the quadratic beam in one
//! element, 2 coordinates, BDF) at the same rtol, all in one run.
//!
//! Two errors, never mixed (the developers' guide): the **integration error** of a case is
//! against the same n at a tight tolerance (one reference per n, shared by every integrator);
//! the **error against the beam** is against the largest n at its tight tolerance (the
//! converged exact beam: model and integration error together). Both are the largest
//! difference over the 0.01 s grid and the whole run, over the reference's largest |value|
//! (v1, ϑ1; M and M_root for the hinge's and the root's moments, which carry the element modes'
//! accelerations). The energy a case loses (a filtered integrator damps what it does not
//! resolve): its energy at t_end against its reference's; after the turn the undamped model
//! conserves it.
//!
//! CVODE (its BDF, dense, atol 1e-3·rtol) on the exact beam through the equations that Model
//! Exchange exports (`cvode::run_equations`): the peer the issue names, compared at equal
//! integration error against the same reference as Radau.
//!
//! Timing: one untimed run of each case (its outputs and counters), then R rounds (3; 2 with
//! `--quick`) of every case in a shuffled order, each recording the tip's states on the grid
//! (`ours`, as the benchmark's other solvers); the median per case.

use std::fmt::Write as _;
use std::time::Instant;

use beam_body::model::{BeamModel, Formulation, Outputs};
use beam_body::scene::IntegratorChoice;
use beam_body::solver::Method;

use super::problem::{on_grid, read_scene, Problem};
use super::{cvode, ours, shuffle};
use crate::{project_root, Mode, Result};

/// One case: the paper's model (`elements` 0) or the exact beam in `elements`, one integrator,
/// one rtol.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Case {
    elements: usize,
    solver: Solver,
    rtol: f64,
}

/// Who integrates: our BDF, our Radau IIA, or CVODE (its BDF, dense, through the equations
/// Model Exchange exports, atol 1e-3·rtol).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Solver {
    Bdf,
    Radau,
    Cvode,
}

impl Solver {
    fn name(self) -> &'static str {
        match self {
            Solver::Bdf => Method::Bdf.name(),
            Solver::Radau => Method::Radau.name(),
            Solver::Cvode => "CVODE",
        }
    }

    /// Ours as the `integrator` setting names it; `None` for CVODE.
    fn ours(self) -> Option<IntegratorChoice> {
        match self {
            Solver::Bdf => Some(IntegratorChoice::Bdf),
            Solver::Radau => Some(IntegratorChoice::Radau),
            Solver::Cvode => None,
        }
    }
}

impl Case {
    fn label(&self) -> String {
        match self.elements {
            0 => "the paper's model (bdf)".to_string(),
            n => format!("exact, {n} ({})", self.solver.name()),
        }
    }
}

/// What a mode measures.
struct Plan {
    /// The exact beam's element counts; the last is the beam's reference.
    elements: Vec<usize>,
    /// Every rtol of the paper's model and of Radau.
    rtols: Vec<f64>,
    /// The exact beam with the BDF: (n, rtol), where it is affordable (its steps follow the
    /// highest element mode: n = 8 takes 226,000 at any rtol).
    bdf: Vec<(usize, f64)>,
    /// CVODE on the exact beam: (n, rtol), n of 4, 8 or 16 among `elements`.
    cvode: Vec<(usize, f64)>,
    /// Radau beyond `rtols`: (n, rtol), where a CVODE run's error is below Radau's at 1e-8.
    radau: Vec<(usize, f64)>,
    /// The references' rtol for n and fewer elements, and for more.
    reference_rtol: (usize, f64, f64),
    rounds: usize,
}

fn plan(mode: Mode) -> Plan {
    match mode {
        Mode::Full => Plan {
            elements: vec![2, 8, 16, 32],
            // Half decades (the work-precision protocol, numerics notes): an equal-error
            // comparison then picks a run within √10 of the error asked, not within 10.
            rtols: (0..=12).map(|k| rtol(2, k)).collect(),
            bdf: vec![(2, 1e-2), (2, 1e-3), (2, 1e-4), (2, 1e-6), (2, 1e-8), (8, 1e-6)],
            cvode: vec![(8, 1e-4), (8, 1e-6), (16, 1e-4), (16, 1e-6)],
            // CVODE in 16 elements at rtol 1e-6 reaches 8e-10 of the peak: Radau's runs to
            // 1e-9, against a reference at 1e-10, measure that comparison.
            radau: vec![(16, rtol(8, 1)), (16, 1e-9)],
            reference_rtol: (16, 1e-10, 1e-9),
            rounds: 3,
        },
        Mode::Quick => Plan {
            elements: vec![2, 8],
            rtols: vec![1e-3, 1e-4, 1e-6],
            bdf: vec![(2, 1e-3), (2, 1e-6)],
            cvode: vec![(8, 1e-4)],
            radau: vec![],
            reference_rtol: (8, 1e-9, 1e-9),
            rounds: 2,
        },
    }
}

/// The k-th half decade below 10^(−top) ([`super::half_decade`]) as a number.
fn rtol(top: u32, k: u32) -> f64 {
    super::half_decade(top, k).parse().expect("the text of a number")
}

/// An rtol as the tables print it: a decade as its literal, a half decade to three digits.
fn rtol_text(rtol: f64) -> String {
    let text = format!("{rtol:e}");
    if text.len() <= 6 {
        text
    } else {
        format!("{rtol:.2e}")
    }
}

/// The scene: the paper's, undamped, reduced; `elements` 0 is the paper's model.
fn problem(elements: usize) -> Result<Problem> {
    let path = project_root().join("scenes").join("paper.toml");
    let mut scene = read_scene(&path)?;
    scene.formulation = Formulation::Reduced;
    if elements > 0 {
        scene.params.beam = BeamModel::Exact;
        scene.params.n_elements = elements;
    }
    Ok(on_grid(&format!("exact-{elements}"), scene, &path)?)
}

/// What an untimed run gives: the outputs on the grid and the counters.
struct Trajectory {
    rows: Vec<Outputs>,
    steps: u64,
}

/// A run of `case` recording every output on the grid (the CLI's driver, `Run`).
fn trajectory(problem: &Problem, solver: Solver, rtol: f64) -> Result<Trajectory> {
    let Some(integrator) = solver.ours() else {
        let o = cvode::run_equations(problem, rtol)?;
        let rows = cvode::outputs_of(problem, &o)?;
        return Ok(Trajectory { rows, steps: o.counters.steps.unwrap_or(0) });
    };
    // The scene the timed runs take (`ours::with_integrator`).
    let scene = ours::adaptive(problem, integrator, rtol);
    let mut rows = Vec::with_capacity(problem.grid.len());
    let stats = ours::drive(problem, &scene, |run, t| {
        rows.push(run.outputs_at(t)?);
        Ok(())
    })?;
    Ok(Trajectory { rows, steps: stats.steps })
}

/// An output compared: its name and value.
type Quantity = (&'static str, fn(&Outputs) -> f64);

/// The outputs compared.
const QUANTITIES: [Quantity; 4] = [
    ("v1", |o| o.v1),
    ("theta1", |o| o.theta1),
    ("M", |o| o.reactions.m),
    ("M_root", |o| o.root.1),
];

/// Per quantity, the largest |difference| over the grid over the reference's largest |value|.
fn errors(rows: &[Outputs], reference: &[Outputs]) -> [f64; 4] {
    QUANTITIES.map(|(_, f)| {
        let scale = reference.iter().map(|o| f(o).abs()).fold(0.0, f64::max).max(1e-300);
        rows.iter().zip(reference).map(|(a, b)| (f(a) - f(b)).abs()).fold(0.0, f64::max) / scale
    })
}

/// The relative difference of the peaks |max| of a quantity (index into [`QUANTITIES`]).
fn peak_change(rows: &[Outputs], reference: &[Outputs], k: usize) -> f64 {
    let f = QUANTITIES[k].1;
    let peak = |r: &[Outputs]| r.iter().map(|o| f(o).abs()).fold(0.0, f64::max);
    peak(rows) / peak(reference) - 1.0
}

/// One case's result.
struct Point {
    case: Case,
    /// Integration error (against the same n), per quantity.
    integration: [f64; 4],
    /// Against the beam (the largest n), per quantity; the paper's model too.
    beam: [f64; 4],
    /// Relative change of the peaks of M and M_root against the same n's reference.
    peaks: [f64; 2],
    /// Energy at t_end minus the reference's [J].
    energy_lost: f64,
    steps: u64,
    seconds: f64,
    failure: Option<String>,
}

/// `bench-exact [--quick]`: measures and writes target/bench/exact.md (copied to
/// docs/work_precision_exact.md by a full run).
pub fn run(mode: Mode) -> Result {
    let plan = plan(mode);
    let started = Instant::now();
    if !plan.cvode.is_empty() && std::env::var_os(super::CVODE_LIB_VARIABLE).is_none() {
        if let Some(lib) = super::optimized_cvode() {
            // Before the first CVODE call loads it; nothing else runs yet.
            std::env::set_var(super::CVODE_LIB_VARIABLE, lib);
        }
    }
    let beam_n = *plan.elements.last().expect("at least one element count");
    // The references, one per n, shared by every integrator.
    let mut references = Vec::new();
    for &n in &plan.elements {
        let rtol =
            if n <= plan.reference_rtol.0 { plan.reference_rtol.1 } else { plan.reference_rtol.2 };
        let t = Instant::now();
        let reference = trajectory(&problem(n)?, Solver::Radau, rtol)?;
        eprintln!(
            "bench-exact: reference n = {n}, radau at rtol {rtol:e}: {} steps, {:.1} s",
            reference.steps,
            t.elapsed().as_secs_f64()
        );
        references.push((n, rtol, reference));
    }
    // The BDF's reference for the smallest n: how far the two integrators' references agree.
    let (n0, rtol0, ref0) = &references[0];
    let check = trajectory(&problem(*n0)?, Solver::Bdf, *rtol0)?;
    let agreement = errors(&check.rows, &ref0.rows)[0];
    let beam = &references.last().expect("a reference").2.rows;

    let mut cases = Vec::new();
    for &rtol in &plan.rtols {
        cases.push(Case { elements: 0, solver: Solver::Bdf, rtol });
        for &n in &plan.elements {
            cases.push(Case { elements: n, solver: Solver::Radau, rtol });
        }
    }
    for &(elements, rtol) in &plan.bdf {
        cases.push(Case { elements, solver: Solver::Bdf, rtol });
    }
    for &(elements, rtol) in &plan.radau {
        cases.push(Case { elements, solver: Solver::Radau, rtol });
    }
    for &(elements, rtol) in &plan.cvode {
        cases.push(Case { elements, solver: Solver::Cvode, rtol });
    }
    let problems: Vec<(usize, Problem)> = std::iter::once(0)
        .chain(plan.elements.iter().copied())
        .map(|n| problem(n).map(|p| (n, p)))
        .collect::<Result<_>>()?;
    let problem_of = |n: usize| &problems.iter().find(|(m, _)| *m == n).expect("built").1;

    let mut points = Vec::new();
    for &case in &cases {
        let own = references.iter().find(|(n, _, _)| *n == case.elements);
        let point = match trajectory(problem_of(case.elements), case.solver, case.rtol) {
            Ok(tr) => {
                let own = own.map_or(&tr.rows, |(_, _, r)| &r.rows);
                let energy_end = |r: &[Outputs]| r.last().map_or(f64::NAN, |o| o.energy);
                Point {
                    case,
                    integration: errors(&tr.rows, own),
                    beam: errors(&tr.rows, beam),
                    peaks: [peak_change(&tr.rows, own, 2), peak_change(&tr.rows, own, 3)],
                    energy_lost: energy_end(own) - energy_end(&tr.rows),
                    steps: tr.steps,
                    seconds: f64::NAN,
                    failure: None,
                }
            }
            Err(e) => Point {
                case,
                integration: [f64::NAN; 4],
                beam: [f64::NAN; 4],
                peaks: [f64::NAN; 2],
                energy_lost: f64::NAN,
                steps: 0,
                seconds: f64::NAN,
                failure: Some(e.to_string()),
            },
        };
        eprintln!(
            "bench-exact: {} at rtol {}: {} steps, v1 {:.2e} against the beam{}",
            case.label(),
            rtol_text(case.rtol),
            point.steps,
            point.beam[0],
            point.failure.as_deref().map_or(String::new(), |f| format!(" (failed: {f})"))
        );
        points.push(point);
    }

    let mut times: Vec<Vec<f64>> = vec![Vec::new(); cases.len()];
    for round in 0..plan.rounds {
        let mut order: Vec<usize> =
            (0..cases.len()).filter(|&k| points[k].failure.is_none()).collect();
        shuffle(&mut order, round as u64 + 1);
        for k in order {
            let case = cases[k];
            let t = Instant::now();
            let problem = problem_of(case.elements);
            let o = match case.solver.ours() {
                Some(integrator) => ours::with_integrator(problem, integrator, case.rtol),
                None => cvode::run_equations(problem, case.rtol),
            }?;
            times[k].push(t.elapsed().as_secs_f64());
            std::hint::black_box(o);
        }
        eprintln!("bench-exact: round {} of {} done", round + 1, plan.rounds);
    }
    for (p, t) in points.iter_mut().zip(&mut times) {
        t.sort_by(f64::total_cmp);
        if !t.is_empty() {
            p.seconds = t[t.len() / 2];
        }
    }
    let header = Header {
        mode,
        rounds: plan.rounds,
        seconds: started.elapsed().as_secs_f64(),
        references: references.iter().map(|(n, r, t)| (*n, *r, t.steps)).collect(),
        agreement,
        beam_n,
    };
    let md = report(&points, &header);
    super::write_report(&md, "exact.md", "work_precision_exact.md", mode)?;
    Ok(())
}

/// What the report says of the run as a whole.
struct Header {
    mode: Mode,
    rounds: usize,
    seconds: f64,
    /// (n, rtol, steps) of each reference.
    references: Vec<(usize, f64, u64)>,
    /// The smallest n's reference by the BDF against Radau's, v1.
    agreement: f64,
    beam_n: usize,
}

fn report(points: &[Point], h: &Header) -> String {
    let mut md = String::from("# Work against precision: the exact beam, undamped\n\n");
    let refs: Vec<String> =
        h.references.iter().map(|(n, r, s)| format!("n = {n} at rtol {r:e} ({s} steps)")).collect();
    let (n0, r0, _) = h.references[0];
    let _ = writeln!(
        md,
        "Written by `cargo xtask bench-exact` ({}; {} rounds, medians; {:.0} s in all) on this \
         machine's 2 cores. The scene: scenes/paper.toml, undamped, reduced, 10.2 s on the \
         0.01 s grid; the geometrically exact beam in n elements against the paper's model (the \
         quadratic beam in one element, its BDF) at the same rtol, each integrator with its \
         default atol (the BDF 1e-3·rtol, Radau rtol). See bench/src/bench/exact.rs.\n\n\
         - **Integration error**: against the same n at a tight rtol (Radau): {}. The BDF's \
         run of n = {n0} at rtol {r0:e} is {:.1e} of the peak of v1 from Radau's.\n\
         - **Against the beam**: against n = {} (the converged exact beam: the model's error \
         and the integration's together); the paper's model too.\n\
         - Each is the largest |difference| over the grid and the whole run over the \
         reference's largest |value|. ΔE: the energy at 10.2 s minus the reference's (after the \
         turn the model conserves it; what an integrator's damping takes out). M, M_root peak: \
         the relative change of max |M| and max |M_root| (the element modes' accelerations).\n",
        if h.mode == Mode::Quick { "--quick" } else { "full" },
        h.rounds,
        h.seconds,
        refs.join(", "),
        h.agreement,
        h.beam_n,
    );
    md.push_str(
        "| beam (integrator) | rtol | steps | time [ms] | × the paper's model | v1 | ϑ1 | M | \
         M_root | v1 against the beam | ϑ1 against the beam | M peak | M_root peak | ΔE [J] |\n",
    );
    md.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    let paper_time = |rtol: f64| {
        points
            .iter()
            .find(|p| p.case.elements == 0 && p.case.rtol == rtol)
            .map(|p| p.seconds)
            .unwrap_or(f64::NAN)
    };
    for p in points {
        let c = &p.case;
        if let Some(why) = &p.failure {
            let why = why.split(": the energy").next().unwrap_or(why);
            let _ = writeln!(
                md,
                "| {} | {} | failed: {why} | | | | | | | | | | | |",
                c.label(),
                rtol_text(c.rtol)
            );
            continue;
        }
        let ratio = match p.seconds / paper_time(c.rtol) {
            _ if c.elements == 0 => "1".to_string(),
            r if r.is_finite() => format!("{r:.0}"),
            _ => "—".to_string(),
        };
        let own = |x: f64| if c.elements == 0 { "—".to_string() } else { format!("{x:.1e}") };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.2} | {ratio} | {} | {} | {} | {} | {:.1e} | {:.1e} | {} | {} | \
             {} |",
            c.label(),
            rtol_text(c.rtol),
            p.steps,
            1e3 * p.seconds,
            own(p.integration[0]),
            own(p.integration[1]),
            own(p.integration[2]),
            own(p.integration[3]),
            p.beam[0],
            p.beam[1],
            own(p.peaks[0]),
            own(p.peaks[1]),
            if c.elements == 0 { "—".to_string() } else { format!("{:+.1e}", -p.energy_lost) },
        );
    }
    md.push_str("\n## The goals of issue 46, as measured here\n\n");
    for line in goals(points) {
        let _ = writeln!(md, "- {line}");
    }
    md
}

/// The goals this benchmark measures, each with its figure and verdict.
fn goals(points: &[Point]) -> Vec<String> {
    let find = |n: usize, i: Solver, rtol: f64| {
        points.iter().find(|p| {
            p.case.elements == n && p.case.solver == i && p.case.rtol == rtol && p.failure.is_none()
        })
    };
    let verdict = |ok: bool| if ok { "**holds**" } else { "**does not hold**" };
    let radau = Solver::Radau;
    let mut out = Vec::new();
    // Steps within 1.5× across n at rtol 1e-6.
    let steps: Vec<(usize, u64)> = points
        .iter()
        .filter(|p| p.case.elements > 0 && p.case.solver == radau && p.case.rtol == 1e-6)
        .filter(|p| p.failure.is_none())
        .map(|p| (p.case.elements, p.steps))
        .collect();
    if steps.len() > 1 {
        let max = steps.iter().map(|s| s.1).max().unwrap_or(0) as f64;
        let min = steps.iter().map(|s| s.1).min().unwrap_or(1) as f64;
        let list: Vec<String> = steps.iter().map(|(n, s)| format!("{s} at n = {n}")).collect();
        out.push(format!(
            "Steps at rtol 1e-6 within 1.5× of each other across n: {} (ratio {:.2}): {}.",
            list.join(", "),
            max / min,
            verdict(max / min <= 1.5)
        ));
    }
    // The exact beam in 8 elements within 1e-4 of the beam, at most 100× the paper's model.
    let cheapest = points
        .iter()
        .filter(|p| p.case.elements == 8 && p.case.solver == radau && p.failure.is_none())
        .filter(|p| p.beam[0] <= 1e-4)
        .max_by(|a, b| a.case.rtol.total_cmp(&b.case.rtol));
    if let Some(p) = cheapest {
        let paper = find(0, Solver::Bdf, p.case.rtol);
        if let Some(paper) = paper {
            let ratio = p.seconds / paper.seconds;
            out.push(format!(
                "8 elements within 1e-4 of the beam's peak of v1 ({:.1e} at rtol {}) in {:.0}× \
                 the paper's model's time at the same rtol ({:.2} ms against {:.3} ms), at most \
                 100×: {}.",
                p.beam[0],
                rtol_text(p.case.rtol),
                ratio,
                1e3 * p.seconds,
                1e3 * paper.seconds,
                verdict(ratio <= 100.0)
            ));
        }
    }
    // 32 elements at rtol 1e-6 in under 5 s.
    if let Some(p) = find(32, radau, 1e-6) {
        out.push(format!(
            "32 elements at rtol 1e-6 in {:.2} s, under 5 s: {}.",
            p.seconds,
            verdict(p.seconds < 5.0)
        ));
    }
    // At most half CVODE's time at CVODE's error, against the same reference.
    let mut cvode_ns: Vec<usize> =
        points.iter().filter(|p| p.case.solver == Solver::Cvode).map(|p| p.case.elements).collect();
    cvode_ns.sort_unstable();
    cvode_ns.dedup();
    for n in cvode_ns {
        let (mut list, mut worst, mut measured, mut failed) = (Vec::new(), 0.0f64, 0, 0);
        for c in points.iter().filter(|p| p.case.elements == n && p.case.solver == Solver::Cvode) {
            if c.failure.is_some() {
                failed += 1;
                list.push(format!("rtol {}: CVODE failed", rtol_text(c.case.rtol)));
                continue;
            }
            let best = points
                .iter()
                .filter(|p| p.case.elements == n && p.case.solver == radau && p.failure.is_none())
                .filter(|p| p.integration[0] <= c.integration[0])
                .min_by(|a, b| a.seconds.total_cmp(&b.seconds));
            let Some(r) = best else {
                list.push(format!(
                    "CVODE at rtol {} ({:.1e}): not measured, below Radau's tightest run \
                     here",
                    rtol_text(c.case.rtol),
                    c.integration[0]
                ));
                continue;
            };
            let ratio = r.seconds / c.seconds;
            worst = worst.max(ratio);
            measured += 1;
            list.push(format!(
                "CVODE at rtol {} ({:.1e}, {:.0} ms): Radau at rtol {} ({:.1e}, \
                 {:.1} ms), {:.3}×",
                rtol_text(c.case.rtol),
                c.integration[0],
                1e3 * c.seconds,
                rtol_text(r.case.rtol),
                r.integration[0],
                1e3 * r.seconds,
                ratio
            ));
        }
        out.push(format!(
            "n = {n}: Radau's time at CVODE's integration error of v1 (the same reference), at \
             most 0.5× CVODE's, in every comparison measured: {}: {}.",
            list.join("; "),
            verdict(measured > 0 && failed == 0 && worst <= 0.5)
        ));
    }
    // Error falls with rtol, at every n.
    let ns: Vec<usize> = {
        let mut ns: Vec<usize> =
            points.iter().map(|p| p.case.elements).filter(|&n| n > 0).collect();
        ns.sort_unstable();
        ns.dedup();
        ns
    };
    for n in ns {
        let all: Vec<&Point> =
            points.iter().filter(|p| p.case.elements == n && p.case.solver == radau).collect();
        let failed = all.iter().filter(|p| p.failure.is_some()).count();
        let mut series: Vec<&Point> = all.into_iter().filter(|p| p.failure.is_none()).collect();
        series.sort_by(|a, b| b.case.rtol.total_cmp(&a.case.rtol));
        let falls = series.windows(2).all(|w| w[1].integration[0] < w[0].integration[0]);
        let list: Vec<String> = series
            .iter()
            .map(|p| format!("{}: {:.1e}", rtol_text(p.case.rtol), p.integration[0]))
            .collect();
        out.push(format!(
            "n = {n}, Radau: every rtol runs to the end and the integration error of v1 falls \
             with rtol ({}): {}.",
            list.join(", "),
            verdict(falls && failed == 0 && !series.is_empty())
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(elements: usize, rtol: f64, steps: u64, error: f64, seconds: f64) -> Point {
        let solver = if elements == 0 { Solver::Bdf } else { Solver::Radau };
        Point {
            case: Case { elements, solver, rtol },
            integration: [error; 4],
            beam: [error; 4],
            peaks: [0.0; 2],
            energy_lost: 0.0,
            steps,
            seconds,
            failure: None,
        }
    }

    #[test]
    fn rtols_run_in_half_decades_and_print_short() {
        let rtols: Vec<f64> = (0..=3).map(|k| rtol(2, k)).collect();
        assert_eq!(rtols[0], 1e-2);
        assert_eq!(rtols[2], 1e-3);
        assert!((rtols[1] / 10f64.powf(-2.5) - 1.0).abs() < 1e-15);
        let texts: Vec<String> = rtols.iter().map(|&r| rtol_text(r)).collect();
        assert_eq!(texts, ["1e-2", "3.16e-3", "1e-3", "3.16e-4"]);
    }

    /// The verdicts follow the figures: steps within 1.5×, the price against the paper's
    /// model at the loosest rtol within 1e-4, an error that must fall with rtol.
    #[test]
    fn the_goals_say_what_the_figures_say() {
        let mut points = vec![
            point(0, 1e-4, 1000, 0.8, 0.001),
            point(0, 1e-6, 3000, 0.8, 0.002),
            point(2, 1e-4, 1500, 2e-4, 0.01),
            point(8, 1e-4, 1800, 5e-5, 0.05),
            point(2, 1e-6, 6000, 2e-6, 0.05),
            point(8, 1e-6, 8000, 4e-7, 0.3),
        ];
        let mut cvode = point(8, 1e-4, 200_000, 5e-7, 2.0);
        cvode.case.solver = Solver::Cvode;
        points.push(cvode);
        let text = goals(&points).join("\n");
        assert!(text.contains("(ratio 1.33): **holds**"), "{text}");
        assert!(
            text.contains("Radau at rtol 1e-6 (4.0e-7, 300.0 ms), 0.150×: **holds**"),
            "{text}"
        );
        assert!(
            text.contains("in 50× the paper's model's time") && text.contains("100×: **holds**")
        );
        assert!(!text.contains("does not hold"), "{text}");
        points[5].steps = 9001;
        points[3].seconds = 0.2;
        points[4].integration[0] = 3e-4;
        points[6].seconds = 0.5;
        let text = goals(&points).join("\n");
        assert!(text.contains("0.600×: **does not hold**"), "{text}");
        points[6].failure = Some("CVODE not available".into());
        let text = goals(&points).join("\n");
        assert!(text.contains("rtol 1e-4: CVODE failed: **does not hold**"), "{text}");
        assert!(text.contains("(ratio 1.50): **does not hold**"), "{text}");
        assert!(text.contains("in 200× the paper's model's time"), "{text}");
        assert!(
            text.contains("n = 2, Radau")
                && text.contains("rtol (1e-4: 2.0e-4, 1e-6: 3.0e-4): **does not hold**"),
            "{text}"
        );
    }
}
