//! Integration tests of the Radau IIA(5) integrator on problems with known solutions: a
//! stiff scalar problem, Robertson's kinetics, an undamped fast mode it must damp rather than
//! resolve, its dense output, landing on a stop time, and its saved state.

mod bytes;
use beam_body::math::{cos, powi, sin};
use beam_body::solver::problems::SlowAndFast;
use beam_body::solver::{Bdf, BdfConfig, Integrator, Method, OdeSystem, Radau, StepOutcome};
use bytes::{read_into, to_bytes};
use nalgebra::{SMatrix, SVector, Vector1, Vector3, U1, U3};

/// The tolerance Radau's error test applies for a relative tolerance `rtol`, RADAU5's
/// 0.1·rtol^(2/3): what the error is held to below.
fn internal(rtol: f64) -> f64 {
    0.1 * beam_body::math::pow(rtol, 2.0 / 3.0)
}

fn config(rtol: f64, atol: f64) -> BdfConfig {
    BdfConfig { method: Method::Radau, atol: Some(atol), ..BdfConfig::new(rtol) }
}

/// Prothero–Robinson: y' = λ(y − sin t) + cos t, y = sin t; λ = −10⁶ makes it stiff.
struct ProtheroRobinson(f64);

impl OdeSystem<U1> for ProtheroRobinson {
    fn rhs(&self, t: f64, y: &Vector1<f64>) -> Vector1<f64> {
        Vector1::new(self.0 * (y[0] - sin(t)) + cos(t))
    }
}

/// On a stiff problem the steps follow the solution (sin t), not λ = −10⁶, and the error at
/// the steps is within the tolerance. (Between the steps the dense output, the collocation
/// polynomial, is of order 3, the stage order: where the step grows past the solution's scale
/// it is less accurate than the steps; docs/decisions.md.)
#[test]
fn the_steps_on_a_stiff_problem_follow_the_solution() {
    for rtol in [1e-3, 1e-6, 1e-9] {
        let mut s = Radau::new(config(rtol, rtol), 0.0, Vector1::new(0.0)).unwrap();
        let mut worst = 0.0f64;
        s.advance_with(&ProtheroRobinson(-1e6), 10.0, 10.0, |s: &Radau<U1>| {
            worst = worst.max((s.y()[0] - sin(s.t())).abs());
            Ok::<_, beam_body::solver::SolverError>(())
        })
        .unwrap();
        let st = *s.stats();
        eprintln!("rtol {rtol:e}: error {worst:.2e}, {st:?}");
        assert!(worst < 10.0 * internal(rtol), "rtol {rtol}: error {worst}");
        assert!(st.steps < 300, "rtol {rtol}: {} steps", st.steps);
    }
}

/// An oscillator, y'' = −y: the global error and the dense output's follow the tolerance
/// down, about as the method's order says.
struct Oscillator;

impl OdeSystem<nalgebra::U2> for Oscillator {
    fn rhs(&self, _: f64, y: &SVector<f64, 2>) -> SVector<f64, 2> {
        SVector::<f64, 2>::new(y[1], -y[0])
    }
}

#[test]
fn the_error_and_the_dense_output_follow_the_tolerance() {
    let mut last = (f64::INFINITY, 0u64);
    for rtol in [1e-4, 1e-6, 1e-8, 1e-10] {
        let y0 = SVector::<f64, 2>::new(0.0, 1.0);
        let mut s = Radau::new(config(rtol, rtol), 0.0, y0).unwrap();
        let (mut worst, mut dense) = (0.0f64, 0.0f64);
        s.advance_with(&Oscillator, 20.0, 20.0, |s: &Radau<nalgebra::U2>| {
            worst = worst.max((s.y()[0] - sin(s.t())).abs());
            for k in 1..4 {
                let t = s.t() - s.last_h() * k as f64 / 4.0;
                dense = dense.max((s.interpolate(t).unwrap()[0] - sin(t)).abs());
            }
            Ok::<_, beam_body::solver::SolverError>(())
        })
        .unwrap();
        let st = *s.stats();
        eprintln!("rtol {rtol:e}: error {worst:.2e}, dense {dense:.2e}, {st:?}");
        // Over about three periods the global error is a few local ones.
        assert!(worst < 30.0 * internal(rtol), "rtol {rtol}: error {worst}");
        assert!(dense < 30.0 * internal(rtol), "rtol {rtol}: dense output error {dense}");
        assert!(worst < last.0 && st.steps > last.1, "the error falls, the steps grow");
        last = (worst, st.steps);
    }
}

/// Robertson's chemical kinetics (Hairer & Wanner II, §IV.1), the classic stiff problem.
struct Robertson;

impl OdeSystem<U3> for Robertson {
    fn rhs(&self, _t: f64, y: &Vector3<f64>) -> Vector3<f64> {
        let a = -0.04 * y[0] + 1e4 * y[1] * y[2];
        let c = 3e7 * y[1] * y[1];
        Vector3::new(a, -a - c, c)
    }
}

fn robertson(cfg: &BdfConfig) -> Radau<U3> {
    let mut s = Radau::new(*cfg, 0.0, Vector3::new(1.0, 0.0, 0.0)).unwrap();
    s.set_atol(Vector3::new(1e-8, 1e-14, 1e-6)).unwrap();
    s
}

/// Robertson at t = 40 against the published solution (SUNDIALS' cvRoberts_dns, Hairer &
/// Wanner), with forward-difference Jacobians, and on to t = 4·10⁶.
#[test]
fn robertson_against_the_published_solution() {
    let mut s = robertson(&config(1e-6, 1e-8));
    s.advance_with(&Robertson, 40.0, 40.0, |_: &Radau<U3>| {
        Ok::<_, beam_body::solver::SolverError>(())
    })
    .unwrap();
    let want = Vector3::new(7.158271e-1, 9.185535e-6, 2.841637e-1);
    for i in 0..3 {
        let rel = (s.y()[i] - want[i]).abs() / want[i];
        assert!(rel < 1e-5, "component {i}: {} vs {} (rel {rel:.1e})", s.y()[i], want[i]);
    }
    let st = *s.stats();
    eprintln!("Robertson to 40: {st:?}");
    assert!(st.steps < 200 && st.rhs_evals_jac > 0 && st.rhs_evals_jac % 3 == 0);
    s.advance_with(&Robertson, 4e6, 4e6, |_: &Radau<U3>| {
        Ok::<_, beam_body::solver::SolverError>(())
    })
    .unwrap();
    assert_eq!(s.t(), 4e6);
    assert!((s.y().sum() - 1.0).abs() < 1e-6, "mass is conserved: {}", s.y().sum());
}

/// An undamped fast mode (ω = 10⁴) beside a slow oscillation (ω = 1), its velocity above the
/// absolute tolerance: the BDF's estimate sees it and the BDF resolves it, with hundreds of
/// thousands of steps (and lets it grow); Radau damps it (L-stable) and its filtered estimate
/// does not count it, so its steps follow the slow motion, which it gets right.
#[test]
fn an_undamped_fast_mode_is_damped_not_resolved() {
    let sys = SlowAndFast { fast: 1e4, slow_oscillates: true };
    let t_end = 20.0;
    let run = |method: Method, a: f64| {
        let cfg = BdfConfig { method, atol: Some(1e-6), ..BdfConfig::new(1e-6) };
        let mut y0 = sys.initial();
        y0[1] = a;
        let (mut amp, mut slow): (f64, f64) = (0.0, 0.0);
        let mut watch = |t: f64, y: &SVector<f64, 4>| {
            if t > 1.0 {
                amp = amp.max((y[1] * y[1] + powi(y[3] / sys.fast, 2)).sqrt());
            }
            slow = slow.max((y[0] - sys.slow_exact(t)).abs());
        };
        let stats = match method {
            Method::Radau => {
                let mut s = Radau::new(cfg, 0.0, y0).unwrap();
                while s.t() < t_end {
                    s.step(&sys, t_end).unwrap();
                    watch(s.t(), s.y());
                }
                *s.stats()
            }
            Method::Bdf => {
                let mut s = Bdf::new(cfg, 0.0, y0).unwrap();
                while s.t() < t_end {
                    s.step(&sys, t_end).unwrap();
                    watch(s.t(), s.y());
                }
                *s.stats()
            }
        };
        eprintln!("{method:?} {a:e}: fast amplitude after t = 1 {amp:.1e}, slow error {slow:.1e}, {stats:?}");
        (amp, slow, stats.steps)
    };
    // 1e-9 in y1 is 1e-5 in y1' = y3: above atol, which the BDF's estimate sees.
    let (amp, slow, steps) = run(Method::Radau, 1e-9);
    let (bdf_amp, _, bdf_steps) = run(Method::Bdf, 1e-9);
    assert!(amp < 1e-15, "Radau damps the fast mode: {amp}");
    assert!(bdf_amp > 1e-9, "the BDF keeps it (and lets it grow): {bdf_amp}");
    assert!(slow < 10.0 * internal(1e-6), "the slow motion is right: {slow}");
    assert!(steps < 1000 && 100 * steps < bdf_steps, "Radau {steps} steps, BDF {bdf_steps}");
}

/// A stop time is landed on exactly, and the step after it is not the cut one.
#[test]
fn a_stop_time_is_landed_on_exactly() {
    let mut s = Radau::new(config(1e-8, 1e-10), 0.0, Vector1::new(0.0)).unwrap();
    let sys = ProtheroRobinson(-1.0);
    let tstop = 0.1 + 1e-13;
    let mut outcome = StepOutcome::Stepped;
    while outcome != StepOutcome::ReachedStop {
        outcome = s.step(&sys, tstop).unwrap();
    }
    assert_eq!(s.t(), tstop);
    let before = s.last_h();
    s.step(&sys, 10.0).unwrap();
    assert!(s.last_h() >= 0.5 * before, "{} after {before}", s.last_h());
    assert!(s.step(&sys, s.t()).is_err(), "a stop time not ahead is refused");
}

fn from_bytes(cfg: &BdfConfig, bytes: &[u8]) -> Result<Radau<U3>, String> {
    read_into(robertson(cfg), bytes)
}

/// A state saved mid-run and read into a fresh solver continues bit for bit; damaged bytes
/// give an error or a state that steps without a panic.
#[test]
fn a_saved_state_continues_bit_for_bit_and_damage_never_panics() {
    let cfg = BdfConfig { max_steps: 200, ..config(1e-6, 1e-8) };
    let mut s = robertson(&cfg);
    let done = |_: &Radau<U3>| Ok::<_, beam_body::solver::SolverError>(());
    s.advance_with(&Robertson, 1.0, f64::INFINITY, done).unwrap();
    let bytes = to_bytes(&s);
    let mut restored = from_bytes(&cfg, &bytes).unwrap();
    s.advance_with(&Robertson, 40.0, 40.0, done).unwrap();
    restored.advance_with(&Robertson, 40.0, 40.0, done).unwrap();
    assert_eq!(restored.y(), s.y());
    assert_eq!(restored.t(), s.t());
    assert_eq!(restored.stats().steps, s.stats().steps);
    for len in 0..bytes.len() {
        assert!(from_bytes(&cfg, &bytes[..len]).is_err(), "truncated to {len} bytes");
    }
    for value in [0xff, 0x7f] {
        for i in 0..bytes.len() {
            let mut damaged = bytes.clone();
            damaged[i] = value;
            if let Ok(mut r) = from_bytes(&cfg, &damaged) {
                let _ = r.advance_with(&Robertson, 2.0, f64::INFINITY, done);
            }
        }
    }
}

/// The Jacobian a system gives is the one used: a linear system with an analytic Jacobian
/// takes no forward differences, and a fixed-step setting is refused naming it.
#[test]
fn an_analytic_jacobian_is_used_and_a_fixed_step_refused() {
    struct Linear;
    impl OdeSystem<nalgebra::U2> for Linear {
        fn rhs(&self, _: f64, y: &SVector<f64, 2>) -> SVector<f64, 2> {
            SVector::<f64, 2>::new(y[1], -100.0 * y[0] - 0.1 * y[1])
        }
        fn jacobian(&self, _: f64, _: &SVector<f64, 2>) -> Option<SMatrix<f64, 2, 2>> {
            Some(SMatrix::<f64, 2, 2>::new(0.0, 1.0, -100.0, -0.1))
        }
    }
    let mut s = Radau::new(config(1e-8, 1e-10), 0.0, SVector::<f64, 2>::new(1.0, 0.0)).unwrap();
    s.advance_with(&Linear, 1.0, 1.0, |_: &Radau<nalgebra::U2>| {
        Ok::<_, beam_body::solver::SolverError>(())
    })
    .unwrap();
    assert_eq!(s.stats().rhs_evals_jac, 0);
    assert!(s.stats().jac_evals >= 1);
    let cfg = BdfConfig {
        fixed_step: Some(beam_body::solver::FixedStep { h: 0.01, order: 2 }),
        ..config(1e-6, 1e-8)
    };
    let e = Radau::new(cfg, 0.0, SVector::<f64, 2>::new(1.0, 0.0)).unwrap_err().to_string();
    assert!(e.contains("fixed_step"), "{e}");
}

/// A double pendulum of point masses in its two angles: M(x)ẍ = F(x, ẋ), a mechanical system
/// with a configuration-dependent mass matrix, given three ways: f alone, f and the
/// structured Jacobian, and those with the residual R = Mẍ − F.
#[derive(Clone, Copy)]
struct Pendulum {
    structured: bool,
    residual: bool,
}

impl Pendulum {
    fn mass(x: &[f64]) -> [[f64; 2]; 2] {
        let c = cos(x[0] - x[1]);
        [[2.0, c], [c, 1.0]]
    }

    /// R(x, ẋ, ẍ) = M ẍ − F with F of gravity (g = 9.81, unit lengths and masses).
    fn res(x: &[f64], v: &[f64], a: &[f64], out: &mut [f64]) {
        let m = Self::mass(x);
        let s = sin(x[0] - x[1]);
        let g = 9.81;
        out[0] = m[0][0] * a[0] + m[0][1] * a[1] + s * v[1] * v[1] + 2.0 * g * sin(x[0]);
        out[1] = m[1][0] * a[0] + m[1][1] * a[1] - s * v[0] * v[0] + g * sin(x[1]);
    }
}

impl OdeSystem<nalgebra::Dyn> for Pendulum {
    fn rhs(&self, _: f64, y: &nalgebra::DVector<f64>) -> nalgebra::DVector<f64> {
        let (x, v) = y.as_slice().split_at(2);
        let mut r = [0.0; 2];
        Self::res(x, v, &[0.0; 2], &mut r);
        let m = Self::mass(x);
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        let a0 = (-r[0] * m[1][1] + r[1] * m[0][1]) / det;
        let a1 = (-r[1] * m[0][0] + r[0] * m[1][0]) / det;
        nalgebra::DVector::from_vec(vec![v[0], v[1], a0, a1])
    }

    fn second_order(
        &self,
        t: f64,
        y: &nalgebra::DVector<f64>,
    ) -> Option<beam_body::solver::SecondOrder> {
        if !self.structured {
            return None;
        }
        let f = self.rhs(t, y);
        let acc = [f[2], f[3]];
        let part = |offset: usize| {
            nalgebra::DMatrix::from_fn(2, 2, |k, c| {
                let mut yp = y.clone();
                let step = 1e-7 * (1.0 + y[offset + c].abs());
                yp[offset + c] += step;
                let (mut r0, mut r1) = ([0.0; 2], [0.0; 2]);
                Self::res(&y.as_slice()[..2], &y.as_slice()[2..], &acc, &mut r0);
                Self::res(&yp.as_slice()[..2], &yp.as_slice()[2..], &acc, &mut r1);
                (r1[k] - r0[k]) / step
            })
        };
        let m = Self::mass(&y.as_slice()[..2]);
        Some(beam_body::solver::SecondOrder::Dense(beam_body::solver::DenseParts {
            mass: nalgebra::DMatrix::from_fn(2, 2, |i, j| m[i][j]),
            damping: part(2),
            stiffness: part(0),
        }))
    }

    fn residual(&self, _: f64, x: &[f64], v: &[f64], a: &[f64], out: &mut [f64]) -> bool {
        if self.residual {
            Self::res(x, v, a, out);
        }
        self.residual
    }
}

/// The stages solved through the residual give the collocation solution the first-order
/// Newton gives, on a system whose mass matrix changes with the configuration: each way's
/// error against a tight reference follows the tolerance, and the residual form calls f
/// only once a step.
#[test]
fn the_residual_form_solves_the_same_collocation_system() {
    let y0 = nalgebra::DVector::from_vec(vec![0.6, -0.2, 0.0, 0.0]);
    let run = |sys: Pendulum, rtol: f64| {
        let mut s = Radau::new(config(rtol, rtol), 0.0, y0.clone()).unwrap();
        s.set_second_order(Some(beam_body::solver::Layout::Dense));
        let done = |_: &Radau<nalgebra::Dyn>| Ok::<_, beam_body::solver::SolverError>(());
        s.advance_with(&sys, 3.0, 3.0, done).unwrap();
        (s.y().clone(), *s.stats())
    };
    let all = Pendulum { structured: true, residual: true };
    let (reference, _) = run(Pendulum { structured: true, residual: false }, 1e-12);
    for rtol in [1e-4, 1e-7] {
        let mut errors = vec![];
        for sys in [
            Pendulum { structured: false, residual: false },
            Pendulum { residual: false, ..all },
            all,
        ] {
            let (y, st) = run(sys, rtol);
            let e = (&y - &reference).amax();
            eprintln!(
                "rtol {rtol:e} structured {} residual {}: error {e:.1e}, {st:?}",
                sys.structured, sys.residual
            );
            assert!(e < 30.0 * internal(rtol), "rtol {rtol}: error {e}");
            errors.push((e, st));
        }
        // With the residual, Newton's iterations call R, and f once a step (its end).
        let st = errors[2].1;
        assert!(st.rhs_evals >= 3 * st.newton_iters && st.jac_evals > 0);
        assert!(
            errors.iter().all(|(e, _)| *e < 10.0 * errors[0].0.max(internal(rtol))),
            "{errors:?}"
        );
    }
}
