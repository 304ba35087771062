//! Model-level tests through the driver: conservation, agreement between formulations,
//! linearisation order, constraint drift, the paper's fixed-step mode.

use beam_body::model::{BeamBody, BeamBodyN, Outputs};
use beam_body::sim::{simulate, Scene};
use beam_body::solver::Stats;
use std::f64::consts::PI;

fn paper() -> Scene {
    let mut s = Scene::default();
    s.set_text("t_end", "10.2").unwrap();
    s.set_text("dt_out", "0.0085").unwrap();
    s
}

fn run(scene: &Scene) -> (Vec<Outputs>, Stats) {
    let mut rows = Vec::new();
    let stats = simulate(scene, |o| rows.push(*o)).unwrap_or_else(|e| panic!("{e}")).stats;
    (rows, stats)
}

fn with(mut scene: Scene, sets: &[(&str, &str)]) -> Scene {
    for (k, v) in sets {
        scene.set_text(k, v).unwrap();
    }
    scene
}

fn max_diff(a: &[Outputs], b: &[Outputs], f: impl Fn(&Outputs) -> f64) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| (f(x) - f(y)).abs()).fold(0.0, f64::max)
}

/// With φ locked and gravity conservative the total energy is constant; its drift shrinks
/// with the tolerance.
#[test]
fn energy_is_conserved_with_phi_locked() {
    let base = with(
        Scene::default(),
        &[
            ("phi_end", "0"),
            ("v1_0", "0.2"),
            ("dtheta1_0", "0.5"),
            ("t_end", "30"),
            ("dt_out", "0.01"),
        ],
    );
    // Scale: the energy of the oscillation, above the undeformed state at rest.
    let (rest, _) =
        run(&with(base.clone(), &[("v1_0", "0"), ("dtheta1_0", "0"), ("t_end", "0.01")]));
    for form in ["reduced", "dae_stabilized", "linear"] {
        let mut drifts = Vec::new();
        for rtol in ["1e-6", "1e-9"] {
            let scene = with(base.clone(), &[("formulation", form), ("rtol", rtol)]);
            let (rows, _) = run(&scene);
            let e0 = rows[0].energy;
            let drift = rows.iter().map(|o| (o.energy - e0).abs()).fold(0.0, f64::max);
            drifts.push(drift / (e0 - rest[0].energy));
        }
        eprintln!("{form}: relative energy drift at rtol 1e-6, 1e-9: {drifts:?}");
        // The linear model is not conservative in the nonlinear energy: check it loosely.
        let limit = if form == "linear" { 1.0 } else { 1e-3 };
        assert!(drifts[0] < limit, "{form}: energy drift {} at rtol 1e-6", drifts[0]);
        if form != "linear" {
            assert!(drifts[1] < 1e-5, "{form}: energy drift {} at rtol 1e-9", drifts[1]);
            assert!(drifts[1] < drifts[0] / 30.0, "{form}: drift must shrink with rtol");
        }
    }
}

/// `reduced`, `dae` and `dae_stabilized` solve the same motion (paper §3: differentiating
/// the constraint twice and substituting ü2 gives back eq. 15).
#[test]
fn reduced_and_dae_agree_on_the_paper_scene() {
    let scene = |form| with(paper(), &[("formulation", form), ("rtol", "1e-10")]);
    let (red, _) = run(&scene("reduced"));
    for form in ["dae", "dae_stabilized"] {
        let (dae, _) = run(&scene(form));
        let dv = max_diff(&red, &dae, |o| o.v1);
        let dth = max_diff(&red, &dae, |o| o.theta1);
        let du = max_diff(&red, &dae, |o| o.u2);
        let dm = max_diff(&red, &dae, |o| o.reactions.m);
        eprintln!(
            "{form} vs reduced: v1 {dv:.2e} m, theta1 {dth:.2e} rad, u2 {du:.2e} m, M {dm:.2e} N m"
        );
        assert!(dv < 1e-6 && dth < 1e-6 && du < 1e-6, "{form}: {dv} {dth} {du}");
        assert!(dm < 1e-3, "{form}: hinge moment differs by {dm}");
    }
}

/// At small amplitude the linear model agrees with the nonlinear one through second order.
/// The system is symmetric under the mirror (v1, ϑ1, φ) → (−v1, −ϑ1, −φ), so the response
/// is odd in φ_end and the first difference is cubic: it shrinks eight times when the turn
/// angle halves (a generic linearisation would give four).
#[test]
fn linear_agrees_with_reduced_to_second_order() {
    let diff = |phi_end: f64| {
        let base = with(Scene::default(), &[("t_end", "5"), ("rtol", "1e-11")]);
        let mut red = base.clone();
        red.set_text("phi_end", &phi_end.to_string()).unwrap();
        let mut lin = red.clone();
        lin.set_text("formulation", "linear").unwrap();
        let (a, _) = run(&red);
        let (b, _) = run(&lin);
        let amp = a.iter().map(|o| o.v1.abs()).fold(0.0, f64::max);
        (max_diff(&a, &b, |o| o.v1), amp)
    };
    let (d1, a1) = diff(0.01);
    let (d2, a2) = diff(0.005);
    let ratio = d1 / d2;
    eprintln!("linear - reduced: {d1:.3e} m at phi_end 0.01 (amplitude {a1:.3e}), {d2:.3e} at 0.005; ratio {ratio:.3}");
    assert!((ratio - 8.0).abs() < 0.4, "difference ratio {ratio}, want 8 (cubic difference)");
    assert!(d1 < 1e-2 * a1, "relative difference {}", d1 / a1);
    assert!((a1 / a2 - 2.0).abs() < 0.05, "amplitude is linear in phi_end");
}

/// The paper's DAE drifts; the drift is reported, bounded and shrinks with the tolerance.
/// The stabilised variant keeps u2 = u1(v1, ϑ1) to round-off.
#[test]
fn dae_drift_is_reported_and_bounded() {
    let drift = |form: &str, rtol: &str| {
        let (rows, _) = run(&with(paper(), &[("formulation", form), ("rtol", rtol)]));
        rows.iter().map(|o| o.drift.abs()).fold(0.0, f64::max)
    };
    let (d6, d10) = (drift("dae", "1e-6"), drift("dae", "1e-10"));
    let s6 = drift("dae_stabilized", "1e-6");
    eprintln!("dae drift: {d6:.2e} m at rtol 1e-6, {d10:.2e} m at 1e-10; stabilized {s6:.2e} m");
    assert!(d6 > 0.0 && d6 < 2e-3, "drift {d6}");
    assert!(d10 < 5e-7, "drift {d10}");
    assert!(d10 < d6 / 100.0);
    // Round-off: u2 ~ 0.09 m, so a few ulps of it.
    assert!(s6 <= 1e-16, "stabilized drift {s6}");
}

/// Where the drift grows past l/10 (rtol 2e-2 on the paper's scene: 1.48 m by t = 10.2 s
/// unchecked), the unprojected DAE stops with a message naming the drift and its bound; the
/// stabilised variant runs the same scene to the end. (The drift at so loose a tolerance is a
/// sum of local errors of either sign: at rtol 1e-2 it was 0.71 m until the step choice of
/// issue 16 moved the last bits of some decisions, and is 0.09 m since; at 2e-2 it was 1.53 m
/// and is 1.48 m.)
#[test]
fn dae_drift_beyond_a_tenth_of_the_length_stops_the_run() {
    let scene = |form: &str| with(paper(), &[("formulation", form), ("rtol", "2e-2")]);
    let mut last = None;
    let err = simulate(&scene("dae"), |o| last = Some(*o)).unwrap_err().to_string();
    assert!(err.contains("drift = ") && err.contains("<= l/10"), "{err}");
    assert!(err.contains("outside the model's range of validity"), "{err}");
    let last = last.expect("some outputs before the stop");
    assert!(last.drift.abs() <= 0.25 && last.t < 10.2, "t = {}, drift {}", last.t, last.drift);
    let (rows, _) = run(&scene("dae_stabilized"));
    assert_eq!(rows.len(), 1201);
}

/// The paper's constant-step BDF reproduces the adaptive solution.
#[test]
fn fixed_step_mode_matches_adaptive() {
    let (reference, _) = run(&with(paper(), &[("rtol", "1e-10")]));
    // Δτ = 1e-4, i.e. h = 8.5e-5 s, BDF2 (the paper used Δτ = 1e-5: see the CLI).
    let fixed = with(paper(), &[("fixed_step", "8.5e-5"), ("fixed_order", "2")]);
    let (rows, stats) = run(&fixed);
    let err = max_diff(&reference, &rows, |o| o.v1);
    eprintln!("fixed-step BDF2, h = 8.5e-5 s: max v1 error {err:.2e} m, {} steps", stats.steps);
    assert_eq!(stats.rejected(), 0);
    assert!((119_999..=120_002).contains(&stats.steps), "steps {}", stats.steps);
    assert!(err < 1e-4, "error {err}");
}

/// The φ columns follow the law, and the phase after the turn holds φ_end.
#[test]
fn phi_columns_follow_the_law() {
    let (rows, _) = run(&paper());
    let law = paper().law;
    for o in &rows {
        let want = law.eval(o.t);
        assert!((o.phi.phi - want.phi).abs() < 1e-15);
        assert!((o.phi.ddphi - want.ddphi).abs() < 1e-12);
    }
    assert_eq!(rows.last().unwrap().phi.phi, PI);
}

/// Reversed gravity above the buckling load: the straight beam is unstable and the
/// deflection grows without bound in the model. The run must stop at a finite time with a
/// message naming the variable and its allowed range, not run on to garbage or NaN; below
/// the load the same start oscillates and stays small.
#[test]
fn divergence_above_buckling_stops_with_a_clear_message() {
    let g_cr = BeamBody::buckling_g(paper().params);
    assert!(g_cr < 0.0, "{g_cr}");
    for formulation in ["reduced", "dae", "dae_stabilized"] {
        let scene = |ratio: f64| {
            with(
                paper(),
                &[
                    ("g", &(ratio * g_cr).to_string()),
                    ("phi_end", "0"),
                    ("v1_0", "1e-3"),
                    ("formulation", formulation),
                ],
            )
        };
        let (rows, _) = run(&scene(0.9));
        assert!(rows.iter().all(|o| o.v1.abs() < 0.05), "{formulation}: below buckling");
        let mut last_t = 0.0;
        let err = simulate(&scene(1.1), |o| last_t = o.t).unwrap_err().to_string();
        assert!(err.contains("outside the model's range of validity"), "{formulation}: {err}");
        assert!(err.contains("v1") || err.contains("theta1"), "{err}");
        assert!(last_t > 0.1 && last_t < 10.2, "{formulation}: stopped after t = {last_t}");
    }
}

/// The logarithmic decrement of the first mode at rest is its damping ratio: free vibration
/// in a mode of ratio ζ decays as x_{k+1}/x_k = exp(−2πζ/√(1 − ζ²)) per period (Chopra,
/// *Dynamics of Structures*, §2.2.4), with ζ_1 = φ_1ᵀDφ_1/(2ω_1) of the mode of beam and body
/// (`modal_damping`). `damping_ratio` = ζ gives the beam's own first two modes (without the
/// body) ζ; the first mode of beam and body, whose kinetic energy is mostly the body's, gets
/// less. The start is the cubic of a tip load (θ1 = 1.5·v1/l), close to the first mode; the
/// higher modes it also excites decay faster in time, and the peaks are taken after them.
#[test]
fn the_logarithmic_decrement_of_the_first_mode_is_the_damping_ratio() {
    for (n, zeta) in [(1, 0.02), (4, 0.02), (4, 0.05)] {
        let l = 2.5;
        let v0 = 0.01;
        let scene = with(
            Scene::default(),
            &[
                ("phi_end", "0"),
                ("n_elements", &n.to_string()),
                ("damping_ratio", &zeta.to_string()),
                ("v1_0", &v0.to_string()),
                ("theta1_0", &(1.5 * v0 / l).to_string()),
                ("t_end", "20"),
                ("dt_out", "0.0005"),
                ("rtol", "1e-9"),
            ],
        );
        let (rows, _) = run(&scene);
        // The largest v1 of each period, between upward zero crossings, after 4 s (the
        // second mode, at ten times the frequency, rides on the first; it decays as fast per
        // period of its own, ten times faster in time).
        let mut peaks = Vec::new();
        let mut current: Option<f64> = None;
        for w in rows.windows(2).filter(|w| w[0].t > 4.0) {
            if w[0].v1 < 0.0 && w[1].v1 >= 0.0 {
                if let Some(p) = current {
                    peaks.push(p);
                }
                current = Some(w[1].v1);
            } else if let Some(p) = current.as_mut() {
                *p = p.max(w[1].v1);
            }
        }
        assert!(peaks.len() >= 4, "n = {n}: {} peaks", peaks.len());
        let periods = (peaks.len() - 1) as f64;
        let delta = beam_body::math::ln(peaks[0] / peaks[peaks.len() - 1]) / periods;
        let measured = delta / (4.0 * PI * PI + delta * delta).sqrt();
        let params = beam_body::model::Params {
            n_elements: n,
            damping_ratio: zeta,
            ..beam_body::model::Params::default()
        };
        let want = BeamBodyN::new(params).unwrap().modal_damping(0.0).unwrap()[0];
        let rel = (measured - want).abs() / want;
        assert!(
            rel < 0.03 && want > 0.1 * zeta && want < zeta,
            "n = {n}, ζ = {zeta}: decrement gives ζ_1 = {measured}, the mode's ratio is {want} \
             ({rel:.2e} off)"
        );
    }
}

/// At rest the bending moment at the clamp balances the moment of the loads about it: the
/// body's weight M2·g along x at its centre y_C = v1 + r·sin θ gives M_root = −M2·g·y_C, and
/// no transverse load, Q_root = 0; with the body held at π/2 the beam is bent
/// (v1 ≈ −0.14 m). Damping brings the turn to rest; the root's loads are the clamp's
/// consistent reactions of the first element, with any number of elements.
#[test]
fn at_rest_the_root_moment_balances_the_body_s_weight() {
    // The exact beam's root loads come from the balance of (angular) momentum instead.
    for (n, beam) in [(1, "quadratic"), (4, "quadratic"), (4, "exact")] {
        let scene = with(
            Scene::default(),
            &[
                ("phi_end", &(PI / 2.0).to_string()),
                ("n_elements", &n.to_string()),
                ("beam", beam),
                ("damping_ratio", "0.3"),
                ("t_end", "60"),
                ("dt_out", "60"),
            ],
        );
        let (rows, _) = run(&scene);
        let o = rows.last().unwrap();
        let (m2, g, r) = (12.0, 10.0, 0.5);
        let y_c = o.v1 + r * beam_body::math::sin(o.theta1 + PI / 2.0);
        let (shear, moment) = o.root;
        let want = -m2 * g * y_c;
        assert!(o.v1 < -0.1, "bent: v1 = {}", o.v1);
        assert!((moment - want).abs() < 1e-4 * want.abs(), "{beam} n = {n}: {moment} vs {want}");
        assert!(shear.abs() < 1e-4, "{beam} n = {n}: Q_root = {shear}");
    }
}
