//! The FMU under Model Exchange, through the core's API: a run by a host's integrator
//! against co-simulation, the time event at the law's end, the range of validity, what it
//! refuses, directional derivatives and FMU states.

use super::variables::{Var, DERIVATIVES, STATES};
use crate::fmi::{Logger, State, Status};
use crate::fmi2::Instance;
use std::cell::RefCell;
use std::rc::Rc;

type Messages = Rc<RefCell<Vec<(Status, String)>>>;

const ME: i32 = 0;
const CS: i32 = 1;
/// FMI 2.0 Model Exchange's states: (v1, ϑ1, v̇1, ϑ̇1) and the filter's (φ_f, φ_f′).
const NX: usize = STATES.len();

fn instance(kind: i32) -> (Instance, Messages) {
    let messages: Messages = Rc::default();
    let sink = messages.clone();
    let log: Logger = Box::new(move |s, _c, m| sink.borrow_mut().push((s, m.to_string())));
    let inst = crate::fmi2::instantiate("me", kind, super::variables::guid(), log, false);
    (inst.expect("instantiates"), messages)
}

fn last(m: &Messages) -> String {
    m.borrow().last().map(|(_, s)| s.clone()).unwrap_or_default()
}

/// An ME instance of the paper's scene with the law, in event mode at t = 0, after
/// `ints` = [(vr, value)] and `reals` were set.
fn exchange_with(ints: &[(Var, i32)], reals: &[(Var, f64)]) -> (Instance, Messages) {
    let (mut inst, msgs) = instance(ME);
    assert_eq!(inst.set_integer(&[Var::PhiSource.vr()], &[2]), Status::Ok);
    for (var, k) in ints {
        assert_eq!(inst.set_integer(&[var.vr()], &[*k]), Status::Ok, "{}", last(&msgs));
    }
    for (var, x) in reals {
        assert_eq!(inst.set_real(&[var.vr()], &[*x]), Status::Ok, "{}", last(&msgs));
    }
    assert_eq!(inst.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(inst.exit_initialization_mode(), Status::Ok, "{}", last(&msgs));
    assert_eq!(inst.state(), State::EventMode);
    (inst, msgs)
}

/// The classical Runge–Kutta step of the instance's equations from its time to `to`.
fn rk4(inst: &mut Instance, to: f64) {
    rk4_with(inst, to, &|_, _| {})
}

/// [`rk4`] of a host that sets φ, φ′, φ″ = `input(t)` at every evaluation.
fn rk4_driven(inst: &mut Instance, to: f64, input: &dyn Fn(f64) -> [f64; 3]) {
    let vrs = [Var::Phi.vr(), Var::Dphi.vr(), Var::Ddphi.vr()];
    rk4_with(inst, to, &|inst, t| assert_eq!(inst.set_real(&vrs, &input(t)), Status::Ok))
}

/// [`rk4`] of a host that calls `set(inst, t)` (its inputs) before every evaluation.
fn rk4_with(inst: &mut Instance, to: f64, set: &dyn Fn(&mut Instance, f64)) {
    let mut x = [0.0; NX];
    assert_eq!(inst.get_continuous_states(&mut x), Status::Ok);
    let t = inst.core.time;
    let h = to - t;
    let f = |inst: &mut Instance, t: f64, x: &[f64; NX]| {
        set(inst, t);
        assert_eq!(inst.set_time(t), Status::Ok);
        assert_eq!(inst.set_continuous_states(x), Status::Ok);
        let mut dx = [0.0; NX];
        assert_eq!(inst.get_derivatives(&mut dx), Status::Ok);
        dx
    };
    let add = |a: &[f64; NX], k: &[f64; NX], s: f64| std::array::from_fn(|i| a[i] + s * k[i]);
    let k1 = f(inst, t, &x);
    let k2 = f(inst, t + 0.5 * h, &add(&x, &k1, 0.5 * h));
    let k3 = f(inst, t + 0.5 * h, &add(&x, &k2, 0.5 * h));
    let k4 = f(inst, t + h, &add(&x, &k3, h));
    let next: [f64; NX] =
        std::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
    assert_eq!(inst.set_time(to), Status::Ok);
    assert_eq!(inst.set_continuous_states(&next), Status::Ok);
    let end = inst.completed_integrator_step().expect("completes");
    assert_eq!(end.0, crate::fmi::StepEnd::default());
}

/// The host's integrator (RK4, h = 0.25 ms) through the law's time event at t_rot = 0.85 s
/// to 1.2 s agrees with co-simulation at rtol 1e-10 to 1e-8 (measured: 2.6e-9 rad in ϑ1,
/// RK4's error at that step); after the event φ holds (φ″ = 0), before it the turn's φ″ < 0 at t_rot.
#[test]
fn a_host_integrator_runs_the_law_through_its_time_event() {
    let (mut me, msgs) = exchange_with(&[], &[]);
    let (info, _) = me.new_discrete_states().unwrap();
    assert_eq!(info.next_event_time, Some(0.85));
    assert!(!info.terminate_simulation && !info.new_discrete_states_needed);
    assert_eq!(me.enter_continuous_time_mode(), Status::Ok);
    let h = 0.85 / 3400.0;
    for k in 1..=3400 {
        rk4(&mut me, k as f64 * h);
    }
    let dd = [Var::DdphiApplied.vr()];
    let mut ddphi = [0.0];
    assert_eq!(me.get_real(&dd, &mut ddphi), Status::Ok);
    assert!(ddphi[0] < -1.0, "the turn's end before the event: {ddphi:?}");
    assert_eq!(me.enter_event_mode(), Status::Ok);
    let (info, status) = me.new_discrete_states().unwrap();
    assert_eq!((info.next_event_time, status), (None, Status::Ok));
    assert_eq!(me.get_real(&dd, &mut ddphi), Status::Ok);
    assert_eq!(ddphi[0], 0.0, "held after the event");
    assert_eq!(me.enter_continuous_time_mode(), Status::Ok);
    for k in 3401..=4800 {
        rk4(&mut me, k as f64 * h);
    }
    assert!((me.core.time - 1.2).abs() < 1e-12);

    let (mut cs, cs_msgs) = instance(CS);
    assert_eq!(cs.set_integer(&[Var::PhiSource.vr()], &[2]), Status::Ok);
    assert_eq!(cs.setup_experiment(Some(1e-10), 0.0, None), Status::Ok);
    assert_eq!(cs.enter_initialization_mode(), Status::Ok);
    assert_eq!(cs.exit_initialization_mode(), Status::Ok);
    assert_eq!(cs.do_step(0.0, 1.2), Status::Ok);
    let vrs = [Var::V1.vr(), Var::Theta1.vr(), Var::U2.vr(), Var::Moment.vr()];
    let (mut a, mut b) = ([0.0; 4], [0.0; 4]);
    assert_eq!(me.get_real(&vrs, &mut a), Status::Ok);
    assert_eq!(cs.get_real(&vrs, &mut b), Status::Ok, "{}", last(&cs_msgs));
    for k in 0..3 {
        assert!((a[k] - b[k]).abs() < 1e-8, "output {k}: ME {a:?} CS {b:?}");
    }
    assert!((a[3] - b[3]).abs() < 1e-5 * b[3].abs().max(1.0), "M: ME {a:?} CS {b:?}");
    // The derivatives are readable as variables, equal to GetDerivatives.
    let mut dx = [0.0; NX];
    assert_eq!(me.get_derivatives(&mut dx), Status::Ok);
    let mut der = [0.0; NX];
    assert_eq!(me.get_real(&DERIVATIVES.map(Var::vr), &mut der), Status::Ok);
    assert_eq!(der, dx);
    assert!(msgs.borrow().iter().all(|(s, _)| *s == Status::Ok), "{:?}", msgs.borrow());
}

/// A host that drives φ through the inputs `phi`, `dphi` and `ddphi` (the law's values at
/// every RK4 stage, the hold from t_rot on) integrates the same motion as the law inside the
/// FMU: to 1e-12 over [0, 1.2 s], the same arithmetic but for φ's polynomial form.
#[test]
fn a_host_drives_phi_through_the_three_inputs() {
    let law = crate::model::PaperLaw::default();
    let input = |t: f64| {
        let p = law.eval(t);
        [p.phi, p.dphi, p.ddphi]
    };
    let (mut driven, msgs) = exchange_with(&[(Var::PhiSource, 1)], &[(Var::Phi, 0.0)]);
    let (mut inside, _) = exchange_with(&[], &[]);
    for inst in [&mut driven, &mut inside] {
        inst.new_discrete_states().unwrap();
        assert_eq!(inst.enter_continuous_time_mode(), Status::Ok);
    }
    let h = 0.85 / 3400.0;
    for k in 1..=4800 {
        // Before the law's event, its turn piece even at t_rot: the input gives that side too.
        let before = |t: f64| if k <= 3400 { input(t.min(0.85 - 1e-15)) } else { input(t) };
        rk4_driven(&mut driven, k as f64 * h, &before);
        rk4(&mut inside, k as f64 * h);
        if k == 3400 {
            assert_eq!(inside.enter_event_mode(), Status::Ok);
            inside.new_discrete_states().unwrap();
            assert_eq!(inside.enter_continuous_time_mode(), Status::Ok);
        }
    }
    let (mut a, mut b) = ([0.0; NX], [0.0; NX]);
    assert_eq!(driven.get_continuous_states(&mut a), Status::Ok);
    assert_eq!(inside.get_continuous_states(&mut b), Status::Ok);
    // The model's states (the filters follow their own inputs: the law's φ and 0).
    for k in 0..4 {
        assert!((a[k] - b[k]).abs() < 1e-12 * b[k].abs().max(1.0), "{a:?} {b:?}");
    }
    assert!(msgs.borrow().is_empty(), "{:?}", msgs.borrow());
}

/// What Model Exchange refuses, each with a message that names why: a beam whose states
/// the model description does not declare, a DAE, co-simulation's functions, the wrong
/// number of states, non-finite states and times; and what co-simulation refuses of it.
#[test]
fn model_exchange_refuses_with_messages() {
    for (ints, words) in [
        (vec![(Var::NElements, 2)], "`n_elements` = 2"),
        (vec![(Var::Beam, 2)], "the exact beam's states are other coordinates"),
        (vec![(Var::Formulation, 2)], "is a DAE"),
    ] {
        let (mut inst, msgs) = instance(ME);
        for (var, k) in &ints {
            assert_eq!(inst.set_integer(&[var.vr()], &[*k]), Status::Ok);
        }
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        assert_eq!(inst.exit_initialization_mode(), Status::Error);
        assert!(last(&msgs).contains(words), "{words}: {}", last(&msgs));
        assert_eq!(inst.state(), State::Error);
    }

    let (mut inst, msgs) = exchange_with(&[], &[]);
    assert_eq!(inst.do_step(0.0, 0.1), Status::Error);
    assert!(last(&msgs).contains("a co-simulation function"), "{}", last(&msgs));
    assert_eq!(inst.set_real_input_derivatives(&[Var::Phi.vr()], &[1], &[1.0]), Status::Error);
    assert_eq!(inst.set_continuous_states(&[0.0; NX]), Status::Error, "event mode");
    assert!(last(&msgs).contains("not allowed in state `event mode`"), "{}", last(&msgs));
    assert_eq!(inst.enter_continuous_time_mode(), Status::Ok);
    assert_eq!(inst.set_continuous_states(&[0.0; 3]), Status::Error);
    assert!(last(&msgs).contains("nx = 3"), "{}", last(&msgs));
    assert_eq!(inst.set_continuous_states(&[0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0]), Status::Error);
    assert!(last(&msgs).contains("x[1] = NaN (`theta1`)"), "{}", last(&msgs));
    assert_eq!(inst.set_time(f64::INFINITY), Status::Error);
    assert_eq!(inst.set_time(-1.0), Status::Error, "before the start");
    assert!(last(&msgs).contains("startTime"), "{}", last(&msgs));
    assert_eq!(inst.get_event_indicators(&mut [0.0; 3]), Status::Error);
    assert!(last(&msgs).contains("ni = 3"), "{}", last(&msgs));
    assert_eq!(inst.set_integer(&[Var::NElements.vr()], &[2]), Status::Error);
    assert!(last(&msgs).contains("fixed parameter"), "{}", last(&msgs));
    assert_eq!(inst.set_real(&[Var::DerV1.vr()], &[1.0]), Status::Error);
    assert!(last(&msgs).contains("calculated local"), "{}", last(&msgs));
    assert_eq!(inst.terminate(), Status::Ok);
    assert_eq!(inst.get_derivatives(&mut [0.0; NX]), Status::Ok, "allowed when terminated");

    let (mut cs, msgs) = instance(CS);
    assert_eq!(cs.enter_event_mode(), Status::Error);
    assert!(last(&msgs).contains("a Model Exchange function"), "{}", last(&msgs));
    assert_eq!(cs.get_nominals(&mut [0.0; NX]), Status::Error);
}

/// The range of validity: the event indicators are its margins (l − |v1|, π/2 − |ϑ1|), and
/// a step that leaves it ends the run (`stop`) or warns once (`warn`).
#[test]
fn the_range_of_validity_is_located_and_enforced() {
    for (check, terminate) in [(1, true), (2, false)] {
        let (mut inst, msgs) = exchange_with(&[(Var::RangeCheck, check)], &[]);
        assert_eq!(inst.enter_continuous_time_mode(), Status::Ok);
        let mut z = [0.0; 2];
        assert_eq!(inst.get_event_indicators(&mut z), Status::Ok);
        assert_eq!(z, [2.5, std::f64::consts::FRAC_PI_2], "margins at rest");
        assert_eq!(inst.set_continuous_states(&[2.6, 0.2, 0.0, 0.0, 0.0, 0.0]), Status::Ok);
        assert_eq!(inst.get_event_indicators(&mut z), Status::Ok);
        assert!((z[0] + 0.1).abs() < 1e-12 && z[1] > 0.0, "{z:?}");
        let (end, status) = inst.completed_integrator_step().unwrap();
        assert_eq!((end.terminate_simulation, status), (terminate, Status::Warning));
        assert!(last(&msgs).contains("`v1` = 2.6"), "{}", last(&msgs));
        if !terminate {
            // Warned once; the check is off from here, its indicators constant.
            let (end, status) = inst.completed_integrator_step().unwrap();
            assert_eq!((end.terminate_simulation, status), (false, Status::Ok));
            assert_eq!(inst.get_event_indicators(&mut z), Status::Ok);
            assert_eq!(z, [1.0, 1.0]);
        }
    }
}

/// The directional derivative: the linear formulation's f is linear in x (at fixed inputs)
/// and in the host's φ″ (at fixed x), so along either it is f(x + v) − f(x) to round-off;
/// unknowns that are states give the seed back; a value reference that is neither is
/// refused with the allowed ones.
#[test]
fn directional_derivatives_of_the_linear_equations_are_exact() {
    let (mut inst, msgs) = exchange_with(&[(Var::Formulation, 4), (Var::PhiSource, 1)], &[]);
    assert_eq!(inst.enter_continuous_time_mode(), Status::Ok);
    let x = [0.05, -0.02, 0.3, 0.1, 0.35, 0.2];
    let inputs = [Var::Phi.vr(), Var::Dphi.vr(), Var::Ddphi.vr()];
    let u = [0.4, 1.0, -3.0];
    let f = |inst: &mut Instance, x: &[f64; NX], u: [f64; 3]| {
        assert_eq!(inst.set_real(&inputs, &u), Status::Ok);
        assert_eq!(inst.set_continuous_states(x), Status::Ok);
        let mut dx = [0.0; NX];
        assert_eq!(inst.get_derivatives(&mut dx), Status::Ok);
        dx
    };
    let base = f(&mut inst, &x, u);
    let along_x = f(&mut inst, &[x[0] + 0.01, x[1], x[2], x[3] - 0.5, x[4], x[5]], u);
    let along_u = f(&mut inst, &x, [u[0], u[1], u[2] + 7.0]);
    let mut unknowns: Vec<u32> = DERIVATIVES.iter().map(|v| v.vr()).collect();
    unknowns.push(STATES[3].vr());
    for (knowns, seed, moved) in [
        (vec![STATES[0].vr(), STATES[3].vr()], vec![0.01, -0.5], along_x),
        (vec![Var::Ddphi.vr()], vec![7.0], along_u),
    ] {
        let _ = f(&mut inst, &x, u);
        let mut out = [0.0; NX + 1];
        let status = inst.get_directional_derivative_exchange(&unknowns, &knowns, &seed, &mut out);
        assert_eq!(status, Status::Ok, "{}", last(&msgs));
        for k in 0..NX {
            let want = moved[k] - base[k];
            assert!((out[k] - want).abs() <= 1e-8 * want.abs().max(1.0), "{k}: {out:?} {want}");
        }
        let want = if knowns.len() == 2 { -0.5 } else { 0.0 };
        assert!((out[NX] - want).abs() <= 1e-12, "{out:?}");
    }
    let v1 = [Var::V1.vr()];
    // An output: the hinge moment, against differences of its values.
    let _ = f(&mut inst, &x, u);
    let m = |inst: &mut Instance, x0: f64| {
        let mut y = x;
        y[0] = x0;
        assert_eq!(inst.set_continuous_states(&y), Status::Ok);
        let mut out = [0.0];
        assert_eq!(inst.get_real(&[Var::Moment.vr()], &mut out), Status::Ok);
        out[0]
    };
    let fd = (m(&mut inst, x[0] + 1e-6) - m(&mut inst, x[0] - 1e-6)) / 2e-6;
    let _ = m(&mut inst, x[0]);
    let mut dm = [0.0];
    let moment = [Var::Moment.vr()];
    assert_eq!(inst.get_directional_derivative_exchange(&moment, &v1, &[1.0], &mut dm), Status::Ok);
    assert!((dm[0] - fd).abs() <= 1e-6 * fd.abs().max(1.0), "{dm:?} {fd}");
    let bad = inst.get_directional_derivative_exchange(&[Var::M.vr()], &v1, &[1.0], &mut [0.0]);
    assert_eq!(bad, Status::Error);
    assert!(
        last(&msgs).contains("not an output, a state or a state derivative"),
        "{}",
        last(&msgs)
    );
    assert!(last(&msgs).contains("`der(v1)`"), "{}", last(&msgs));
    // Seeds far from 1 neither overflow nor underflow.
    for scale in [1e-200, 1e200] {
        let mut d = [0.0];
        let st =
            inst.get_directional_derivative_exchange(&[DERIVATIVES[2].vr()], &v1, &[scale], &mut d);
        assert_eq!(st, Status::Ok, "{}", last(&msgs));
        let mut d1 = [0.0];
        let st =
            inst.get_directional_derivative_exchange(&[DERIVATIVES[2].vr()], &v1, &[1.0], &mut d1);
        assert_eq!(st, Status::Ok);
        assert!((d[0] / scale - d1[0]).abs() <= 1e-6 * d1[0].abs(), "{scale}: {d:?} {d1:?}");
    }
    let bad = inst.get_directional_derivative_exchange(&v1, &[Var::L.vr()], &[1.0], &mut [0.0]);
    assert_eq!(bad, Status::Error);
    assert!(last(&msgs).contains("`dphi` (50)"), "{}", last(&msgs));
}

/// An FMU state of Model Exchange restores the states, the event's flag and the time in
/// another ME instance, from its bytes too; a co-simulation instance refuses it.
#[test]
fn model_exchange_states_restore_and_stay_in_their_interface() {
    let (mut me, _) = exchange_with(&[], &[]);
    me.new_discrete_states().unwrap();
    assert_eq!(me.enter_continuous_time_mode(), Status::Ok);
    for k in 1..=40 {
        rk4(&mut me, k as f64 * 0.025);
    }
    assert_eq!(me.enter_event_mode(), Status::Ok);
    me.new_discrete_states().unwrap();
    let snap = me.get_state().unwrap();
    let bytes = me.serialize(&snap).unwrap();
    let restored = me.deserialize(&bytes).unwrap();

    let (mut other, _) = instance(ME);
    assert_eq!(other.set_state(&restored), Status::Ok);
    assert_eq!(other.state(), State::EventMode);
    let (mut a, mut b) = ([0.0; NX], [0.0; NX]);
    assert_eq!(me.get_continuous_states(&mut a), Status::Ok);
    assert_eq!(other.get_continuous_states(&mut b), Status::Ok);
    assert_eq!(a, b);
    let (info, _) = other.new_discrete_states().unwrap();
    assert_eq!(info.next_event_time, None, "the event at t_rot = 0.85 s was handled");
    assert_eq!(other.core.time, 1.0);
    assert_eq!(crate::fmi::serialize(&other.get_state().unwrap()).unwrap(), bytes);

    let (mut cs, msgs) = instance(CS);
    assert_eq!(cs.set_state(&restored), Status::Error);
    assert!(last(&msgs).contains("saved by a Model Exchange instance"), "{}", last(&msgs));
}

/// A host that lands on the law's event a rounding error early (t + (t_next − t) rounds
/// below t_next) has the event handled there, and the state serializes (the writer's check
/// of the event's flag allows the same rounding); a state at rest on a limit of the range, as
/// a start may be, is inside it, as co-simulation has it.
#[test]
fn events_at_rounding_distance_and_states_on_a_limit() {
    let (mut me, msgs) = exchange_with(&[], &[]);
    me.new_discrete_states().unwrap();
    assert_eq!(me.enter_continuous_time_mode(), Status::Ok);
    assert_eq!(me.set_time(0.85 - 2e-16), Status::Ok);
    assert_eq!(me.enter_event_mode(), Status::Ok);
    let (info, _) = me.new_discrete_states().unwrap();
    assert_eq!(info.next_event_time, None, "handled");
    let snap = me.get_state().unwrap();
    let bytes = me.serialize(&snap).expect("serializes");
    assert!(me.deserialize(&bytes).is_ok());

    let theta = std::f64::consts::FRAC_PI_2;
    let (mut rest, _) = exchange_with(&[], &[(Var::Theta10, theta)]);
    let (info, status) = rest.new_discrete_states().unwrap();
    assert_eq!((info.terminate_simulation, status), (false, Status::Ok));
    assert!(msgs.borrow().is_empty(), "{:?}", msgs.borrow());
}

/// A host that sets φ alone (the paper's law sampled every 8.5 ms, interpolated linearly as
/// fmuCheck does) drives the model through the filter of φ: RK4 at h = 0.2 ms gives the
/// paper's peak |v1| (the CLI's at rtol 1e-10) to 1 % at the default 10 Hz (measured: 0.15 %),
/// where φ′ = φ″ = 0 gave about half of it. The filter's variables are its states and φ″, and
/// the model's φ is theirs; a host that then sets `dphi` and `ddphi` gets them as sent.
#[test]
fn a_host_that_sets_phi_alone_drives_the_filter() {
    use crate::sim::{simulate, Scene};
    let scene = Scene { t_end: 3.0, dt_out: 0.001, ..Scene::default() };
    let mut scene_tight = scene.clone();
    scene_tight.solver.rtol = 1e-10;
    let mut want = 0.0f64;
    simulate(&scene_tight, |o| want = want.max(o.v1.abs())).unwrap();
    let law = crate::model::PaperLaw::default();
    let dt_in = 0.0085;
    let sampled = move |t: f64| {
        let k = (t / dt_in).floor();
        let (a, b) = (law.eval(k * dt_in).phi, law.eval((k + 1.0) * dt_in).phi);
        a + (b - a) * (t / dt_in - k)
    };
    let (mut me, msgs) = exchange_with(&[(Var::PhiSource, 1)], &[(Var::Phi, 0.0)]);
    me.new_discrete_states().unwrap();
    assert_eq!(me.enter_continuous_time_mode(), Status::Ok);
    let h = 2e-4;
    let mut peak = 0.0f64;
    let set_phi = |inst: &mut Instance, t: f64| {
        assert_eq!(inst.set_real(&[Var::Phi.vr()], &[sampled(t)]), Status::Ok);
    };
    for k in 1..=(3.0 / h) as usize {
        rk4_with(&mut me, k as f64 * h, &set_phi);
        let mut v = [0.0];
        assert_eq!(me.get_real(&[Var::V1.vr()], &mut v), Status::Ok);
        peak = peak.max(v[0].abs());
    }
    assert!((peak - want).abs() < 0.01 * want, "peak |v1| {peak} against {want}");
    let mut x = [0.0; NX];
    assert_eq!(me.get_continuous_states(&mut x), Status::Ok);
    let filter = [Var::PhiFiltered, Var::DphiFiltered, Var::DdphiFiltered].map(Var::vr);
    let applied = [Var::PhiApplied, Var::DphiApplied, Var::DdphiApplied].map(Var::vr);
    let (mut f, mut a) = ([0.0; 3], [0.0; 3]);
    assert_eq!(me.get_real(&filter, &mut f), Status::Ok);
    assert_eq!(me.get_real(&applied, &mut a), Status::Ok);
    assert_eq!(&f[..2], &x[4..], "the filter's states");
    assert_eq!(f, a, "the model's phi is the filter's");
    assert!((f[0] - std::f64::consts::PI).abs() < 1e-6 && f[1].abs() < 1e-4, "{f:?}");
    // dphi and ddphi set: the model takes them, whatever the filter holds.
    let vrs = [Var::Phi.vr(), Var::Dphi.vr(), Var::Ddphi.vr()];
    assert_eq!(me.set_real(&vrs, &[3.0, 0.5, -2.0]), Status::Ok);
    assert_eq!(me.get_real(&applied, &mut a), Status::Ok);
    assert_eq!(a, [3.0, 0.5, -2.0]);
    assert!(msgs.borrow().is_empty(), "{:?}", msgs.borrow());
}
