//! `cargo xtask sweep [--quick]`: stiff and extreme cases, each run against a reference, and
//! `sweep-case ID`, one case in its own process.
//!
//! Every case runs in a child process (`xtask sweep-case ID`) under a wall-clock limit, so a
//! hang, a crash or a runaway case ends as a status of its row, never as a stuck sweep. The
//! child prints one tab-separated result line; the parent writes `target/sweep/sweep.csv`
//! and `target/sweep/sweep.md`.
//!
//! The reference of a case is the same formulation's equations integrated by an explicit
//! Dormand–Prince 5(4) pair ([`reference`]) at rtol 1e-12: it shares only the right-hand side
//! with the BDF. The error, as in the benchmark, is the RMS over the output grid and over
//! v1, ϑ1, v̇1, ϑ̇1 of (y − y_ref)/max|y_ref|, with the maximum alongside.

pub mod fmu;
pub mod reference;
mod report;

use std::fmt::Write as _;
use std::fs;
use std::io::Read as _;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use beam_body::model::{BeamBody, Formulation, PaperLaw, PhiPiece};
use beam_body::sim::SimError;
use beam_body::sim::{simulate, Scene};
use beam_body::solver::problems::SlowAndFast;
use beam_body::solver::{OdeSystem, SolverError};
use nalgebra::{Const, SVector};

use crate::bench::problem::{with_system, WithSystem};
use crate::{cargo, relative, run_cmd, target_dir, write_text, Mode, Result};
use reference::{Dopri5, RefError};

/// What a case is expected to do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Expect {
    /// Succeed with an error at most this (relative RMS against the reference).
    Accurate(f64),
    /// Stop with a clear message containing this text.
    Fails(&'static str),
    /// Run to the end with finite outputs; no reference (a horizon too long for one).
    Completes,
    /// Either as `Accurate`, or stop with a clear message containing the text (a drive so
    /// violent that the beam may leave the model's range).
    AccurateOrStops(f64, &'static str),
    /// As `Completes`, or stop with a message containing the text ("" for any message).
    CompletesOrStops(&'static str),
}

/// What the integrator says when the beam leaves the model's range of validity.
const RANGE_MESSAGE: &str = "outside the model's range of validity";

/// One row of the sweep.
#[derive(Clone, Debug)]
pub struct Case {
    pub group: &'static str,
    pub name: String,
    pub scene: Scene,
    pub expect: Expect,
    /// In the quick subset that `cargo xtask test` runs.
    pub quick: bool,
    /// Through the packaged FMU instead of the standalone driver.
    pub fmu: Option<fmu::FmuRun>,
    /// The guard's test problem instead of the model (the scene gives rtol, the guard
    /// setting and t_end).
    pub test_problem: Option<SlowAndFast>,
    /// The reference's relative tolerance (absolute: 1e-3 of it).
    pub reference_rtol: f64,
}

/// The accuracy expected of a run: 5·rtol^(5/6) per period of the fastest mode over the
/// horizon (at least 50 periods), at most 0.5.
///
/// On an undamped oscillation the global error of a tolerance-controlled integrator is
/// mostly phase error, which grows linearly with the number of periods. Controlling the
/// error per step at order q gives h ∝ tol^(1/(q+1)) and a global error ∝ tol^(q/(q+1))
/// (Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.4), tol^(5/6) at order 5: measured
/// on the paper's scene, error ≈ 0.25·periods·rtol^(5/6) from rtol 1e-2 to 1e-14. A phase
/// error saturates at O(1), hence the cap.
fn accurate(scene: &Scene) -> Expect {
    let periods =
        fastest_omega(scene).map_or(0.0, |w| w * scene.t_end / (2.0 * std::f64::consts::PI));
    Expect::Accurate((5.0 * scene.solver.rtol.powf(5.0 / 6.0) * periods.max(50.0)).min(0.5))
}

/// The fastest angular frequency of small oscillations about the static equilibria at the
/// angles where the body rests, φ0 and φ0 + φ_end. (With J_C = 0 the faster mode is 2× as
/// fast at φ = π as at 0, and the scene spends most of its horizon at π.)
fn fastest_omega(scene: &Scene) -> Option<f64> {
    let model = BeamBody::new(scene.params).ok()?;
    let law = scene.law;
    let w2 = model.modes(law.phi0).omega2[1].max(model.modes(law.phi0 + law.phi_end).omega2[1]);
    (w2 > 0.0).then(|| w2.sqrt())
}

fn paper() -> Scene {
    Scene { t_end: 10.2, dt_out: 0.0085, ..Scene::default() }
}

fn case(group: &'static str, name: String, scene: Scene, quick: bool) -> Case {
    let expect = accurate(&scene);
    Case { group, name, scene, expect, quick, fmu: None, test_problem: None, reference_rtol: 1e-12 }
}

/// The case list, in a fixed order (a case's id is its index).
pub fn cases() -> Vec<Case> {
    let mut list = Vec::new();
    let formulations = [Formulation::Reduced, Formulation::DaeStabilized];
    // Stiffness: EI from 0.1 to 10⁷ times the paper's.
    for (k, factor) in [1e-1, 1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7].into_iter().enumerate() {
        for f in formulations {
            let mut s = paper();
            s.params.ei *= factor;
            s.formulation = f;
            let quick = f == Formulation::Reduced && matches!(k, 1 | 5 | 8);
            list.push(case("stiffness", format!("EI x {factor:e}"), s, quick));
        }
    }
    // The error of a stiff scene is the phase of its fast vibration, over up to 10⁵ periods:
    // it shrinks with the tolerance.
    for factor in [1e4, 1e7] {
        for k in [8, 10] {
            let mut s = paper();
            s.params.ei *= factor;
            s.solver.rtol = 10f64.powi(-k);
            list.push(case("stiffness", format!("EI x {factor:e}, rtol 1e-{k}"), s, false));
        }
    }
    // Mass and inertia.
    let mut masses: Vec<(String, Scene)> = Vec::new();
    let mut s = paper();
    s.params.m = 1e-6;
    masses.push(("m = 1e-6 (massless beam)".into(), s));
    let mut s = paper();
    s.params.j_c = 0.0;
    masses.push(("J_C = 0 (point mass at r)".into(), s));
    let mut s = paper();
    s.params.r = 0.0;
    masses.push(("r = 0".into(), s));
    for factor in [1e-3, 1e-2, 1e-1, 1e1, 1e2, 1e3] {
        let mut s = paper();
        s.params.m2 *= factor;
        masses.push((format!("M2 x {factor:e}"), s));
    }
    for (i, (name, s)) in masses.into_iter().enumerate() {
        for f in formulations {
            let scene = Scene { formulation: f, ..s.clone() };
            let mut c = case("mass", name.clone(), scene, i == 0 && f == Formulation::Reduced);
            // A body 100× heavier swings the beam past the range of validity.
            if let Expect::Accurate(bound) = c.expect {
                c.expect = Expect::AccurateOrStops(bound, RANGE_MESSAGE);
            }
            list.push(c);
        }
    }
    // Violent turns.
    for t_rot in [0.85, 0.2, 0.05] {
        for turns in [1.0, 4.0, 10.0] {
            let mut s = paper();
            s.law =
                PaperLaw { t_rot, phi_end: turns * std::f64::consts::PI, ..PaperLaw::default() };
            let quick = t_rot == 0.05 && turns == 10.0;
            let mut c = case("turn", format!("t_rot = {t_rot} s, phi_end = {turns} pi"), s, quick);
            if let Expect::Accurate(bound) = c.expect {
                c.expect = Expect::AccurateOrStops(bound, RANGE_MESSAGE);
            }
            list.push(c);
        }
    }
    // Gravity: none, and reversed below and above the buckling load.
    let mut s = paper();
    s.params.g = 0.0;
    list.push(case("gravity", "g = 0".into(), s, false));
    let g_cr = BeamBody::buckling_g(paper().params);
    for (ratio, quick) in [(0.9, false), (1.1, true)] {
        let mut s = paper();
        s.params.g = ratio * g_cr;
        s.law.phi_end = 0.0;
        s.initial.v1 = 1e-3;
        let name = format!("g = {ratio} g_cr = {:.4} m/s^2 (reversed)", ratio * g_cr);
        let mut c = case("gravity", name, s, quick);
        if ratio > 1.0 {
            c.expect = Expect::Fails(RANGE_MESSAGE);
        }
        list.push(c);
    }
    // Tolerances.
    for k in 2..=14 {
        let rtol = 10f64.powi(-k);
        let mut s = paper();
        s.solver.rtol = rtol;
        let quick = k == 2 || k == 13;
        let mut c = case("tolerance", format!("rtol = 1e-{k}"), s, quick);
        // Below 1e-10 the reference runs at 1e-14, about the limit of an explicit method in
        // double precision over 10⁵ steps.
        if k > 10 {
            c.reference_rtol = 1e-14;
        }
        list.push(c);
    }
    // Below the solver's lower limit: refused, with the allowed range.
    let mut s = paper();
    s.solver.rtol = 1e-15;
    let mut c = case("tolerance", "rtol = 1e-15".into(), s, true);
    c.expect = Expect::Fails("rtol");
    list.push(c);
    // The stability guard, on and off, over stiffness and tolerance: the paper's turn, and
    // the free vibration from a deflection near the first mode's shape (φ fixed).
    for free in [false, true] {
        for factor in [1e2, 1e3, 1e4, 1e5] {
            for k in 3..=6 {
                for guard in [true, false] {
                    let mut s = paper();
                    s.params.ei *= factor;
                    s.solver.rtol = 10f64.powi(-k);
                    s.solver.stability_guard = guard;
                    if free {
                        s.law.phi_end = 0.0;
                        s.initial.v1 = 0.01;
                        s.initial.theta1 = 0.006;
                    }
                    let on = if guard { "on" } else { "off" };
                    let what = if free { "free vibration" } else { "turn" };
                    let name = format!("{what}, EI x {factor:e}, rtol 1e-{k}, guard {on}");
                    let quick = !free && factor == 1e4 && k == 4;
                    list.push(case("guard", name, s, quick));
                }
            }
        }
    }
    // The guard's test problem: an unresolved undamped fast mode beside a slow driven lag,
    // where the unguarded BDF3–5 let the fast mode grow (solver::problems::SlowAndFast).
    for fast in [3.0, 10.0, 30.0, 100.0, 300.0] {
        for guard in [true, false] {
            let mut s = Scene { t_end: 200.0, ..paper() };
            s.solver.rtol = 1e-5;
            s.solver.stability_guard = guard;
            let on = if guard { "on" } else { "off" };
            list.push(Case {
                group: "guard, test problem",
                name: format!("driven lag + undamped mode, omega = {fast}, guard {on}"),
                scene: s,
                // The slow component's amplitude is 0.45: rtol 1e-5 of it, with margin.
                expect: Expect::Accurate(1e-4),
                quick: fast == 30.0,
                fmu: None,
                test_problem: Some(SlowAndFast { fast, slow_oscillates: false }),
                reference_rtol: f64::NAN,
            });
        }
    }
    // Beams of several elements: the highest mode grows like n² (1.8·10⁵ rad/s at n = 32
    // at φ = 0, `beam-body modes`, and 100× that at EI × 10⁴). With 1 % Rayleigh damping of the first two modes
    // (a real beam's), and undamped at rtol 1e-4 and with BDF2 only (README: the settings for
    // many undamped elements; undamped, the reference of 32 takes more than 10 minutes). The
    // reference is the BDF at rtol 1e-10 (`own_reference`).
    for (n, ei, zeta, rtol, max_order) in [
        (8, 1.0, 0.01, 1e-5, 5),
        (32, 1.0, 0.01, 1e-5, 5),
        (8, 1e4, 0.01, 1e-5, 5),
        (32, 1e4, 0.01, 1e-5, 5),
        (8, 1.0, 0.0, 1e-4, 5),
        (8, 1.0, 0.0, 1e-4, 2),
        (16, 1.0, 0.0, 1e-4, 2),
    ] {
        let mut s = paper();
        s.params.n_elements = n;
        s.params.ei *= ei;
        s.params.damping_ratio = zeta;
        s.solver.rtol = rtol;
        s.solver.max_order = max_order;
        // At EI × 10⁴ the modes are 100× as fast: 1 s holds 5 000 periods of the second.
        if ei > 1.0 {
            s.t_end = 1.0;
        }
        let mut name = format!("n = {n}, EI x {ei:e}, zeta = {zeta}, rtol {rtol:e}");
        if max_order < 5 {
            name += &format!(", max order {max_order}");
        }
        let quick = n == 8 && ei > 1.0;
        let mut c = case("elements", name, s, quick);
        c.reference_rtol = 1e-10;
        list.push(c);
    }
    // A long horizon: the paper's turn, then 10⁴ s at constant φ (energy is conserved). The
    // unprojected DAE's drift grows quadratically and stops it at l/10; 100 s show its size.
    let horizons = [
        (Formulation::Reduced, 1e4),
        (Formulation::Dae, 1e2),
        (Formulation::Dae, 1e4),
        (Formulation::DaeStabilized, 1e4),
        (Formulation::Linear, 1e4),
    ];
    for (f, t_end) in horizons {
        let s = Scene { t_end, dt_out: 1.0, formulation: f, ..paper() };
        let stops = f == Formulation::Dae && t_end > 1e3;
        list.push(Case {
            group: "horizon",
            name: format!("t_end = {t_end:e} s"),
            scene: s,
            expect: if stops { Expect::Fails("drift = ") } else { Expect::Completes },
            quick: stops,
            fmu: None,
            test_problem: None,
            reference_rtol: 1e-12,
        });
    }
    // Communication steps through the FMU, φ from the law: at most 2·10⁴ steps (a shorter
    // horizon for the smallest), about 10³ recorded points.
    for (k, h) in [1e-6f64, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0].into_iter().enumerate() {
        let wanted = ((10.2 / h).ceil() as usize).min(20_000);
        let stride = wanted.div_ceil(1000);
        let n = stride * wanted.div_ceil(stride);
        let s = Scene { t_end: n as f64 * h, dt_out: stride as f64 * h, ..paper() };
        let name = format!("FMU, H = {h:e} s, t_end = {:.4} s", s.t_end);
        let mut c = case("communication", name, s, k == 2);
        c.fmu = Some(fmu::FmuRun { h, stride, phi: fmu::FmuPhi::Law });
        list.push(c);
    }
    // A step in the φ input (values only): an infinite acceleration, which the FMU smooths
    // over one communication step (its Hermite reconstruction).
    for jump in [0.01, 0.1, 1.0, 10.0, 1e3] {
        let s = Scene { t_end: 3.0, dt_out: 0.01, ..paper() };
        let how = fmu::FmuRun { h: 0.01, stride: 1, phi: fmu::FmuPhi::Step { t_jump: 1.0, jump } };
        list.push(Case {
            group: "phi step",
            name: format!("FMU, phi jumps by {jump:e} rad at t = 1 s, H = 0.01 s"),
            scene: s,
            expect: Expect::CompletesOrStops(""),
            quick: jump == 1e3,
            fmu: Some(how),
            test_problem: None,
            reference_rtol: 1e-12,
        });
    }
    list
}

/// The measured outcome of a case. NaN (and 0 steps) where a quantity does not apply.
#[derive(Clone, Debug, Default)]
pub struct Row {
    pub status: String,
    pub error: f64,
    pub max_error: f64,
    /// The RMS error over v1 and ϑ1 only.
    pub position_error: f64,
    /// The largest |u2 − u1(v1, ϑ1)| reported [m].
    pub drift: f64,
    /// (E(t_end) − E)/|E| with E the energy at the first output after the turn.
    pub energy_drift: f64,
    pub steps: u64,
    pub rejected: u64,
    pub time_s: f64,
    pub stiffness: f64,
    /// Periods of the fastest mode over the horizon.
    pub periods: f64,
    /// Where a run stopped, and where the reference, with the same range check, left the
    /// range.
    pub t_stop: f64,
    pub t_ref_stop: f64,
    /// The guard's test problem: the largest amplitude of its fast oscillator (initially 1e-9).
    pub amplitude: f64,
    pub message: String,
}

impl Row {
    fn new() -> Self {
        let nan = f64::NAN;
        Row {
            error: nan,
            max_error: nan,
            position_error: nan,
            drift: nan,
            energy_drift: nan,
            stiffness: nan,
            periods: nan,
            t_stop: nan,
            t_ref_stop: nan,
            amplitude: nan,
            ..Row::default()
        }
    }
}

/// The stiffness ratio of a scene: the fastest frequency of small oscillations about the
/// equilibrium at φ = 0 against the rate of the turn, ω_max·t_rot (radians of the fastest
/// mode per turn time; the paper's scene: 29). Both beam modes scale alike with EI, so
/// their ratio stays near 10 and does not measure stiffness.
fn stiffness_ratio(scene: &Scene) -> f64 {
    fastest_omega(scene).map_or(f64::NAN, |w| w * scene.law.t_rot)
}

/// Runs the reference of `scene` on its output grid at relative tolerance `rtol`: the states
/// (v1, ϑ1, v̇1, ϑ̇1) per grid time, the law's two smooth pieces integrated separately.
fn reference_solution(
    scene: &Scene,
    model: &BeamBody,
    rtol: f64,
) -> std::result::Result<Vec<[f64; 4]>, RefError> {
    if scene.params.n_elements > 1 {
        return own_reference(scene, rtol);
    }
    with_system(scene, model, Reference { scene, rtol })
}

/// The reference of a beam of several elements: the BDF itself at `rtol` (its error is then
/// integration error against the same equations, not an independent integrator's). The
/// Dormand–Prince reference is of fixed size, and an explicit method would need about 10⁷
/// steps a second for 32 stiff elements (their highest mode reaches 1.8·10⁷ rad/s at EI × 10⁴); the
/// n-element equations and their integration are checked independently by the Python
/// oracle (tests/python/oracle/test_oracle_elements_rust.py).
fn own_reference(scene: &Scene, rtol: f64) -> std::result::Result<Vec<[f64; 4]>, RefError> {
    let mut tight = scene.clone();
    tight.solver.rtol = rtol;
    tight.solver.atol = 0.0;
    // The default method whatever the case's (a case of BDF2 alone is judged against BDF5).
    tight.solver.max_order = 5;
    tight.solver.stability_guard = true;
    let mut states = Vec::new();
    match simulate(&tight, |o| states.push([o.v1, o.theta1, o.dv1, o.dtheta1])) {
        Ok(_) => Ok(states),
        Err(SimError::Solver(SolverError::OutOfRange { t, name, value, .. })) => {
            Err(RefError::OutOfRange { t, name, value })
        }
        Err(e) => Err(RefError::Own(e.to_string())),
    }
}

/// [`reference_solution`]'s integration, for [`with_system`].
struct Reference<'a> {
    scene: &'a Scene,
    rtol: f64,
}

impl WithSystem for Reference<'_> {
    type Output = std::result::Result<Vec<[f64; 4]>, RefError>;
    fn apply<const N: usize, S, F>(self, system: F, y0: SVector<f64, N>) -> Self::Output
    where
        S: OdeSystem<Const<N>> + Copy,
        F: Fn(PhiPiece) -> S,
    {
        let mut r = Dopri5::new(0.0, y0, self.rtol, 1e-3 * self.rtol, 50_000_000);
        // Positions first, then their rates: (v1, ϑ1) at 0, 1 and (v̇1, ϑ̇1) at N/2, N/2 + 1.
        let rates = N / 2;
        self.scene
            .output_times()
            .map(|t| {
                advance_piecewise(&mut r, t, self.scene.law, &system)?;
                Ok([r.y[0], r.y[1], r.y[rates], r.y[rates + 1]])
            })
            .collect()
    }
}

/// Advances the reference to `t`, stopping at the law's breakpoint t_rot on the way so that
/// each step sees one smooth piece of φ.
fn advance_piecewise<const N: usize, S: OdeSystem<Const<N>>>(
    r: &mut Dopri5<N>,
    t: f64,
    law: PaperLaw,
    system: impl Fn(PhiPiece) -> S,
) -> std::result::Result<(), RefError> {
    if r.t < law.t_rot && t > law.t_rot {
        r.advance(&system(law.piece_from(r.t)), law.t_rot)?;
    }
    r.advance(&system(law.piece_from(r.t)), t)
}

/// `sweep-case ID`: runs one case and prints its result line.
pub fn run_case(options: &[String]) -> Result {
    let id: usize = match options {
        [id] => id.parse().map_err(|_| format!("`sweep-case` takes a case number, not `{id}`"))?,
        _ => return Err("usage: sweep-case ID".into()),
    };
    let list = cases();
    let case = list.get(id).ok_or_else(|| format!("no case {id} (there are {})", list.len()))?;
    let row = measure(case);
    println!("{}", row_fields(&row).join("\t"));
    Ok(())
}

/// Runs the case in this process.
fn measure(case: &Case) -> Row {
    let scene = &case.scene;
    let mut row = Row::new();
    if let Some(problem) = case.test_problem {
        return measure_test_problem(case, problem, row);
    }
    row.stiffness = stiffness_ratio(scene);
    row.periods =
        fastest_omega(scene).map_or(f64::NAN, |w| w * scene.t_end / (2.0 * std::f64::consts::PI));
    let model = match scene.validate() {
        Ok(m) => m,
        Err(e) => return stopped(case, e.to_string(), row),
    };
    let start = Instant::now();
    if let Some(how) = &case.fmu {
        let result = fmu::run(scene, how);
        row.time_s = start.elapsed().as_secs_f64();
        return match result {
            Ok(states) => judge(case, &model, states, row),
            Err(message) => stopped(case, message, row),
        };
    }
    let mut states: Vec<[f64; 4]> = Vec::new();
    let mut drift: f64 = 0.0;
    // Energy at the first output after the turn and at the last: φ is constant in between.
    let (mut e_after_turn, mut e_end) = (None, f64::NAN);
    let result = simulate(scene, |o| {
        states.push([o.v1, o.theta1, o.dv1, o.dtheta1]);
        drift = drift.max(o.drift.abs());
        if o.t >= scene.law.t_rot && e_after_turn.is_none() {
            e_after_turn = Some(o.energy);
        }
        e_end = o.energy;
    });
    row.time_s = start.elapsed().as_secs_f64();
    row.drift = drift;
    row.energy_drift = match e_after_turn {
        Some(e0) if e0 != 0.0 => (e_end - e0) / e0.abs(),
        _ => f64::NAN,
    };
    match result {
        Ok(report) => {
            row.steps = report.stats.steps;
            row.rejected = report.stats.rejected();
        }
        Err(e) => {
            if let SimError::Solver(SolverError::OutOfRange { t, name, .. }) = e {
                row.t_stop = t;
                // A deflection out of range is physics if the reference, with the same check,
                // leaves the range too. (The dae's drift is the formulation's own error.)
                if name != "drift" {
                    match reference_solution(scene, &model, case.reference_rtol) {
                        Err(RefError::OutOfRange { t, .. }) => row.t_ref_stop = t,
                        Err(other) => row.message = format!("; reference: {other}"),
                        Ok(_) => row.t_ref_stop = f64::INFINITY,
                    }
                }
            }
            return stopped(case, e.to_string(), row);
        }
    }
    judge(case, &model, states, row)
}

/// Runs the guard's test problem: the error is that of its slow component at the end.
fn measure_test_problem(case: &Case, problem: SlowAndFast, mut row: Row) -> Row {
    let solver = &case.scene.solver;
    let start = Instant::now();
    let result = problem.run(solver.rtol, solver.stability_guard, case.scene.t_end);
    row.time_s = start.elapsed().as_secs_f64();
    match result {
        Ok(run) => {
            row.error = run.slow_error;
            row.amplitude = run.fast_amplitude;
            row.steps = run.stats.steps;
            row.rejected = run.stats.rejected();
            row.status = match case.expect {
                Expect::Accurate(bound) if run.slow_error > bound => {
                    row.message = format!("error {:.2e} above the expected {bound:.1e}", row.error);
                    "inaccurate".into()
                }
                _ => "ok".into(),
            };
            row
        }
        Err(e) => stopped(case, e.to_string(), row),
    }
}

/// How far a run's stop may be from the reference's, relative to the reference's time. Near
/// the edge of the range the beam moves fast, so the two cross it almost together; a stop
/// that the reference does not share is a numerical failure, not physics.
const STOP_AGREEMENT: f64 = 0.05;

/// The row of a run that stopped with `message`. A stop at the range of validity counts as
/// expected only if the reference leaves the range at nearly the same time (FMU runs, whose
/// input reconstruction the reference does not replicate, excepted).
fn stopped(case: &Case, message: String, mut row: Row) -> Row {
    let expected = match case.expect {
        Expect::Fails(text) | Expect::AccurateOrStops(_, text) | Expect::CompletesOrStops(text) => {
            message.contains(text)
        }
        _ => false,
    };
    let confirmed = case.fmu.is_some()
        || row.t_stop.is_nan()
        || row.t_ref_stop.is_nan()
        || (row.t_stop - row.t_ref_stop).abs() <= STOP_AGREEMENT * row.t_ref_stop;
    row.status = if expected && confirmed { "stopped (expected)" } else { "failed" }.into();
    if expected && !confirmed {
        let reference = if row.t_ref_stop.is_finite() {
            format!("the reference leaves the range at t = {:.4} s", row.t_ref_stop)
        } else {
            "the reference stays in range".to_string()
        };
        row.message = format!("{message}; {reference}{}", row.message);
    } else {
        row.message = format!("{message}{}", row.message);
    }
    row
}

/// The row of a run that reached its end with `states` on the scene's output grid.
fn judge(case: &Case, model: &BeamBody, states: Vec<[f64; 4]>, mut row: Row) -> Row {
    let scene = &case.scene;
    if !states.iter().flatten().all(|v| v.is_finite()) {
        row.status = "NaN".into();
        row.message = "a reported output is not finite".into();
        return row;
    }
    let bound = match case.expect {
        Expect::Accurate(bound) | Expect::AccurateOrStops(bound, _) => bound,
        Expect::Completes | Expect::CompletesOrStops(_) => {
            row.status = "ok".into();
            return row;
        }
        Expect::Fails(_) => {
            row.status = "unexpected".into();
            row.message = "ran to the end although a failure was expected".into();
            return row;
        }
    };
    match reference_solution(scene, model, case.reference_rtol) {
        Ok(reference) => {
            let (rms, max) = relative_error(&states, &reference, &[0, 1, 2, 3]);
            row.position_error = relative_error(&states, &reference, &[0, 1]).0;
            row.error = rms;
            row.max_error = max;
            row.status = if rms <= bound {
                "ok".into()
            } else {
                row.message = format!("error {rms:.2e} above the expected {bound:.1e}");
                "inaccurate".into()
            };
        }
        Err(e) => {
            row.status = "no reference".into();
            row.message = format!("reference: {e}");
        }
    }
    row
}

/// RMS and maximum over the grid and the components `components` of (y − y_ref)/max|y_ref|.
pub(crate) fn relative_error(
    ours: &[[f64; 4]],
    reference: &[[f64; 4]],
    components: &[usize],
) -> (f64, f64) {
    let n = ours.len().min(reference.len());
    let mut sum = 0.0;
    let mut max: f64 = 0.0;
    for &c in components {
        let scale = reference.iter().map(|r| r[c].abs()).fold(0.0, f64::max).max(1e-300);
        for k in 0..n {
            let d = (ours[k][c] - reference[k][c]).abs() / scale;
            sum += d * d;
            max = max.max(d);
        }
    }
    ((sum / (components.len() * n.max(1)) as f64).sqrt(), max)
}

const CSV_HEADER: &str = "id,group,case,formulation,status,error,max_error,position_error,\
    drift,energy_drift,steps,rejected,time_s,stiffness_ratio,periods,t_stop,t_ref_stop,\
    amplitude,message";

fn row_fields(row: &Row) -> Vec<String> {
    let mut f: Vec<String> = vec![row.status.clone()];
    f.extend(
        [row.error, row.max_error, row.position_error, row.drift, row.energy_drift]
            .map(|x| format!("{x:e}")),
    );
    f.push(row.steps.to_string());
    f.push(row.rejected.to_string());
    f.extend(
        [row.time_s, row.stiffness, row.periods, row.t_stop, row.t_ref_stop, row.amplitude]
            .map(|x| format!("{x:e}")),
    );
    f.push(row.message.replace(['\t', '\n'], " "));
    f
}

fn parse_row(line: &str) -> Option<Row> {
    let f: Vec<&str> = line.trim_end_matches(['\n', '\r']).split('\t').collect();
    if f.len() != 15 {
        return None;
    }
    let x = |i: usize| f[i].parse::<f64>().ok();
    Some(Row {
        status: f[0].to_string(),
        error: x(1)?,
        max_error: x(2)?,
        position_error: x(3)?,
        drift: x(4)?,
        energy_drift: x(5)?,
        steps: f[6].parse().ok()?,
        rejected: f[7].parse().ok()?,
        time_s: x(8)?,
        stiffness: x(9)?,
        periods: x(10)?,
        t_stop: x(11)?,
        t_ref_stop: x(12)?,
        amplitude: x(13)?,
        message: f[14].to_string(),
    })
}

/// Runs `xtask sweep-case ID` under a wall-clock limit.
fn run_child(exe: &std::path::Path, id: usize, limit: Duration) -> Row {
    let mut child = match Command::new(exe)
        .args(["sweep-case", &id.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
    {
        Ok(c) => c,
        Err(e) => return Row { status: "crashed".into(), message: e.to_string(), ..Row::new() },
    };
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) => {
                let mut out = String::new();
                let mut err = String::new();
                if let Some(mut s) = child.stdout.take() {
                    let _ = s.read_to_string(&mut out);
                }
                if let Some(mut s) = child.stderr.take() {
                    let _ = s.read_to_string(&mut err);
                }
                return match (status.success(), parse_row(&out)) {
                    (true, Some(row)) => row,
                    _ => Row {
                        status: "crashed".into(),
                        message: format!("exit {status}: {}", err.trim().replace('\n', " ")),
                        ..Row::new()
                    },
                };
            }
            Ok(None) if start.elapsed() > limit => {
                let _ = child.kill();
                let _ = child.wait();
                return Row {
                    status: "timeout".into(),
                    message: format!("killed after {} s", limit.as_secs()),
                    time_s: start.elapsed().as_secs_f64(),
                    ..Row::new()
                };
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(5)),
            Err(e) => {
                return Row { status: "crashed".into(), message: e.to_string(), ..Row::new() }
            }
        }
    }
}

/// `cargo xtask sweep [--quick]`.
pub fn run(options: &[String]) -> Result {
    let (mode, group) = match options {
        [g, name] if g == "--group" => (Mode::Full, Some(name.as_str())),
        _ => (Mode::parse("sweep", options)?, None),
    };
    crate::bench::fmu::prepare_at(fmu::extracted_dir())?;
    run_cmd(&mut cargo(["build", "--release", "-p", "beam-body-bench"]))?;
    let exe = target_dir().join("release").join("beam-body-bench");
    let list = cases();
    let selected: Vec<usize> = (0..list.len())
        .filter(|&i| match group {
            Some(g) => list[i].group == g,
            None => mode == Mode::Full || list[i].quick,
        })
        .collect();
    if selected.is_empty() {
        return Err(format!("no sweep case in group `{}`", group.unwrap_or("")).into());
    }
    let limit = Duration::from_secs(if mode == Mode::Full { 600 } else { 60 });
    let out_dir = target_dir().join("sweep");
    fs::create_dir_all(&out_dir)
        .map_err(|e| format!("cannot create {}: {e}", relative(&out_dir)))?;
    let mut csv = format!("{CSV_HEADER}\n");
    let start = Instant::now();
    // Children run two (or as many as there are cores) at a time; rows keep the case order.
    let jobs = std::thread::available_parallelism().map_or(1, |n| n.get()).min(4);
    let next = std::sync::atomic::AtomicUsize::new(0);
    let done = std::sync::Mutex::new(Vec::<(usize, Row)>::new());
    // A case may take minutes (its limit is 600 s): a progress line between case lines.
    let finished = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let total = selected.len();
    let counter = finished.clone();
    let _tick = crate::progress::ticker("sweep", move || {
        format!("{}/{total} cases done", counter.load(std::sync::atomic::Ordering::SeqCst))
    });
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| loop {
                let n = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                let Some(&id) = selected.get(n) else { break };
                let row = run_child(&exe, id, limit);
                finished.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                let c = &list[id];
                let mut done = done.lock().unwrap_or_else(|e| e.into_inner());
                done.push((id, row.clone()));
                eprintln!(
                    "[{}/{}] {:<9} {:<42} {:<14} {:<18} error {:.2e}  {}",
                    done.len(),
                    selected.len(),
                    c.group,
                    c.name,
                    c.scene.formulation.name(),
                    row.status,
                    row.error,
                    report::duration(row.time_s)
                );
            });
        }
    });
    let mut rows = done.into_inner().unwrap_or_else(|e| e.into_inner());
    rows.sort_by_key(|(id, _)| *id);
    for (id, row) in &rows {
        let c = &list[*id];
        let fields: Vec<String> =
            row_fields(row)
                .iter()
                .map(|f| {
                    if f.contains(',') {
                        format!("\"{}\"", f.replace('"', "'"))
                    } else {
                        f.clone()
                    }
                })
                .collect();
        let _ = writeln!(
            csv,
            "{id},{},\"{}\",{},{}",
            c.group,
            c.name,
            c.scene.formulation.name(),
            fields.join(",")
        );
    }
    let csv_path = out_dir.join("sweep.csv");
    write_text(&csv_path, &csv)?;
    let md_path = out_dir.join("sweep.md");
    let report = report::markdown(&list, &rows, &preamble());
    write_text(&md_path, &report)?;
    if mode == Mode::Full && group.is_none() {
        let docs = crate::project_root().join("docs").join("sweep.md");
        write_text(&docs, &report)?;
        eprintln!("sweep: copied the report to {}", relative(&docs));
    }
    eprintln!(
        "sweep: {} cases in {:.1} s; wrote {} and {}",
        rows.len(),
        start.elapsed().as_secs_f64(),
        relative(&csv_path),
        relative(&md_path)
    );
    let bad: Vec<String> = rows
        .iter()
        .filter(|(_, r)| !matches!(r.status.as_str(), "ok" | "stopped (expected)"))
        .map(|(id, r)| format!("case {id} ({}): {} {}", list[*id].name, r.status, r.message))
        .collect();
    if mode == Mode::Quick && !bad.is_empty() {
        return Err(format!("sweep cases not as expected:\n  {}", bad.join("\n  ")).into());
    }
    Ok(())
}

/// The report's head: when and where it ran, how to rerun it, and how to read it.
fn preamble() -> String {
    let date = Command::new("date")
        .args(["-u", "+%Y-%m-%d"])
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map_or_else(|| "an unknown date".to_string(), |d| d.trim().to_string());
    let cpu = fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!(
        "# Stiff and extreme cases\n\n\
         Snapshot of {date} on {cores} cores ({cpu}); regenerate with `cargo xtask sweep` \
         (writes target/sweep/sweep.csv and sweep.md, and copies this file to docs/), or one \
         group with `cargo xtask sweep --group NAME`. `cargo xtask test` runs a quick subset \
         and fails unless each of its cases ends as expected.\n\n\
         Each case runs in its own process under a wall-clock limit (600 s), so a hang or a \
         crash would show as a status. The reference is the same formulation integrated by an \
         explicit Dormand–Prince 5(4) pair at rtol 1e-12 (`bench/src/sweep/reference.rs`), \
         which shares only the right-hand side and the range check with the BDF. The error \
         is the RMS over the output grid and over v1, ϑ1, v̇1, ϑ̇1 of (y − y_ref)/max|y_ref|; \
         the position error takes v1 and ϑ1 only. A case is *ok* if its error is within \
         5·rtol^(5/6) per period of the fastest mode (at least 50 periods, at most 0.5 in \
         all): on an undamped oscillation a tolerance-controlled integrator's global error \
         is mostly phase error, which grows with the number of periods, and with error \
         control per step at order 5 it scales as rtol^(5/6). *stopped (expected)* means the run ended \
         with the message the case expects and, for a beam leaving the model's range of \
         validity (|v1| ≤ l, |ϑ1| ≤ π/2), that the reference leaves it too, within 5 % of the \
         same time: the stop is physics, not a numerical failure. Time is the wall time of \
         the run alone (reference excluded).\n\n"
    )
}
