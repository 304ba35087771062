//! The FMU's model behind the core, in Rust: the law against the standalone driver, FMU
//! states that continue bit for bit, output derivatives, lazy outputs.

use super::variables::Var;
use crate::fmi::{Logger, Status};
use crate::fmi2::{Core, Instance};
use crate::sim::{simulate, Scene};
use std::cell::RefCell;
use std::rc::Rc;

type Messages = Rc<RefCell<Vec<(Status, String)>>>;

fn new_instance() -> (Instance, Messages) {
    let messages: Messages = Rc::default();
    let sink = messages.clone();
    let log: Logger = Box::new(move |s, _c, m| sink.borrow_mut().push((s, m.to_string())));
    let inst = crate::fmi2::instantiate("test", 1, super::variables::guid(), log, false);
    (inst.expect("instantiates"), messages)
}

fn law_instance(rtol: f64) -> (Instance, Messages) {
    let (mut inst, msgs) = new_instance();
    assert_eq!(inst.set_integer(&[Var::PhiSource.vr()], &[2]), Status::Ok);
    assert_eq!(inst.setup_experiment(Some(rtol), 0.0, Some(10.2)), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(inst.exit_initialization_mode(), Status::Ok);
    (inst, msgs)
}

#[test]
fn law_mode_matches_the_standalone_driver() {
    let (mut inst, msgs) = law_instance(1e-8);
    let scene = Scene { t_end: 1.7, dt_out: 0.0085, ..Scene::default() };
    let mut rows = Vec::new();
    let mut scene_tight = scene.clone();
    scene_tight.solver.rtol = 1e-8;
    simulate(&scene_tight, |o| rows.push(*o)).unwrap();
    let vrs = [Var::V1.vr(), Var::Theta1.vr(), Var::U2.vr()];
    let mut worst = 0.0f64;
    for (k, row) in rows.iter().enumerate().skip(1) {
        let tc = (k - 1) as f64 * 0.0085;
        let status = inst.do_step(tc, row.t - tc);
        assert_eq!(status, Status::Ok, "at {tc}: {:?}", msgs.borrow().last());
        let mut out = [0.0; 3];
        assert_eq!(inst.get_real(&vrs, &mut out), Status::Ok);
        worst = worst.max((out[0] - row.v1).abs()).max((out[1] - row.theta1).abs());
    }
    assert!(worst < 1e-6, "worst difference {worst}");
}

/// The paper's scene at rtol 1e-6 after 60 steps of 8.5 ms (t = 0.51 s): the instance, its
/// FMU state and the state's bytes.
fn state_at_0_51() -> (Instance, Box<Core>, Vec<u8>) {
    let (mut inst, _) = law_instance(1e-6);
    let h = 0.0085;
    for k in 0..60 {
        assert_eq!(inst.do_step(k as f64 * h, h), Status::Ok);
    }
    let snap = inst.get_state().unwrap();
    let bytes = inst.serialize(&snap).unwrap();
    (inst, snap, bytes)
}

/// Writes `fuzz/regressions/deserialize/*` again in the current state format, each the
/// state of the paper's scene at t = 0.51 s with one defect the fuzzer once found
/// accepted: after a change of the format (`fmi::CORE_VERSION`, the model's `STATE_VERSION`), run
/// `cargo test --lib write_fuzz_regressions -- --ignored`. Each file is a mode byte 1
/// (the reader of the regressions and the fuzz target reseal the rest) and the bytes.
#[test]
#[ignore = "regenerates files: cargo test --lib write_fuzz_regressions -- --ignored"]
fn write_fuzz_regressions() {
    let (_, snap, bytes) = state_at_0_51();
    let offsets = crate::fmi::field_offsets(&snap);
    let at = |name: &str, k: usize| offsets.iter().filter(|f| f.0 == name).nth(k).unwrap().1;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions/deserialize");
    let write = |file: &str, edit: &dyn Fn(&mut Vec<u8>)| {
        let mut b = bytes.clone();
        edit(&mut b);
        let mut out = vec![1u8];
        out.extend_from_slice(&b);
        std::fs::write(dir.join(file), out).unwrap();
    };
    // The flag of the LU cleared, its factors left in.
    write("lu-factors-without-an-lu", &|b| b[at("lu", 0)] = 0);
    // tolerance_defined cleared, the tolerance left in.
    write("tolerance-value-without-its-flag", &|b| b[at("tolerance_defined", 0)] = 0);
    // The law's piece (the turn, kind 0) with a real it does not use.
    write("unused-reals-of-the-law-piece", &|b| {
        let i = at("piece", 1);
        b[i..i + 8].copy_from_slice(&0.5f64.to_le_bytes());
    });
    // FMI 3.0 states, which an FMI 2.0 instance refuses at fmi2SetFMUstate: the same scene's,
    // which restores into an FMI 3.0 instance; and that state with 100 J of the drive's work
    // that never happened, which the reader accepts (a finite number) and whose next step
    // discards, the energy balance broken (the fuzz target once checked such a discard by
    // FMI 2.0's name).
    let (mut inst3, _) = law_instance3(1e-6);
    for k in 0..60 {
        assert_eq!(inst3.do_step(k as f64 * 0.0085, 0.0085), Status::Ok);
    }
    let snap3 = inst3.get_state().unwrap();
    let bytes3 = inst3.serialize(&snap3).unwrap();
    let offsets3 = crate::fmi::field_offsets(&snap3);
    let work = offsets3.iter().find(|f| f.0 == "energy_work").unwrap().1;
    let write3 = |file: &str, edit: &dyn Fn(&mut Vec<u8>)| {
        let mut b = bytes3.clone();
        edit(&mut b);
        std::fs::write(dir.join(file), [&[1u8][..], &b].concat()).unwrap();
    };
    write3("fmi3-state-restores-into-an-fmi3-instance", &|_| {});
    write3("fmi3-state-whose-step-discards", &|b| {
        let w = f64::from_le_bytes(b[work..work + 8].try_into().unwrap()) + 100.0;
        b[work..work + 8].copy_from_slice(&w.to_le_bytes());
    });
}

/// An FMI 3.0 co-simulation of the paper's scene, its law, initialized at rtol `rtol`.
fn law_instance3(rtol: f64) -> (Instance, Messages) {
    let messages: Messages = Rc::default();
    let sink = messages.clone();
    let log: Logger = Box::new(move |s, _c, m| sink.borrow_mut().push((s, m.to_string())));
    let cs = crate::fmi3::CoSimulationArgs {
        event_mode_used: false,
        required: &[],
        intermediate_update: None,
    };
    let interface = crate::fmi::Interface::CoSimulation;
    let guid = super::variables::guid();
    let mut inst = crate::fmi3::instantiate("test", interface, guid, log, false, Some(cs))
        .expect("instantiates");
    let law = |v: i64| crate::fmi::Value::Integer(v.into());
    let base = crate::fmi::BaseType::Int64;
    assert_eq!(inst.set("SetInt64", base, &[Var::PhiSource.vr()], &[2i64], law), Status::Ok);
    assert_eq!(inst.enter_initialization_mode_with(Some(rtol), 0.0, Some(10.2)), Status::Ok);
    assert_eq!(inst.exit_initialization_mode(), Status::Ok);
    (inst, messages)
}

/// A new instance restores `bytes`, a state of `a`; both take the steps `steps` of 8.5 ms and
/// report the same bits after each. Returns the new instance.
fn continues_alike(a: &mut Instance, bytes: &[u8], steps: std::ops::Range<usize>) -> Instance {
    let h = 0.0085;
    let (mut b, _) = new_instance();
    let restored = b.deserialize(bytes).unwrap();
    assert_eq!(b.set_state(&restored), Status::Ok);
    let vrs: Vec<u32> = (Var::V1.vr()..=Var::DdphiApplied.vr()).collect();
    for k in steps {
        assert_eq!(a.do_step(k as f64 * h, h), Status::Ok);
        assert_eq!(b.do_step(k as f64 * h, h), Status::Ok);
        let (mut ya, mut yb) = (vec![0.0; vrs.len()], vec![0.0; vrs.len()]);
        a.get_real(&vrs, &mut ya);
        b.get_real(&vrs, &mut yb);
        assert_eq!(ya, yb, "step {k}");
    }
    b
}

/// The states of the beam in elements continue bit for bit in a new instance, as the paper's
/// model's do, whatever their integrator keeps: the exact beam's dense second-order parts,
/// the quadratic beam's banded ones, and the dense LU of its DAE formulation (whose Jacobian
/// comes by differences).
#[test]
fn states_of_the_beam_in_elements_continue_bit_for_bit() {
    // (beam, formulation) as the enumerations' values.
    for (beam, formulation) in [(2, 1), (1, 1), (1, 2)] {
        let (mut a, _) = new_instance();
        assert_eq!(a.set_integer(&[Var::PhiSource.vr()], &[2]), Status::Ok);
        assert_eq!(a.set_integer(&[Var::NElements.vr()], &[4]), Status::Ok);
        assert_eq!(a.set_integer(&[Var::Beam.vr()], &[beam]), Status::Ok);
        assert_eq!(a.set_integer(&[Var::Formulation.vr()], &[formulation]), Status::Ok);
        assert_eq!(a.setup_experiment(Some(1e-6), 0.0, Some(10.2)), Status::Ok);
        assert_eq!(a.enter_initialization_mode(), Status::Ok);
        assert_eq!(a.exit_initialization_mode(), Status::Ok);
        let h = 0.0085;
        for k in 0..60 {
            assert_eq!(a.do_step(k as f64 * h, h), Status::Ok);
        }
        let state = a.get_state().unwrap();
        let bytes = a.serialize(&state).unwrap();
        continues_alike(&mut a, &bytes, 60..160);
    }
}

#[test]
fn serialized_state_continues_bit_for_bit() {
    let (mut a, _, bytes) = state_at_0_51();
    let mut b = continues_alike(&mut a, &bytes, 60..200);
    // Any flipped byte is refused.
    for i in (0..bytes.len()).step_by(7) {
        let mut bad = bytes.clone();
        bad[i] ^= 0x40;
        assert!(b.deserialize(&bad).is_err(), "byte {i}");
    }
}

/// The largest differences of the output derivatives of v1, theta1, u2 and the quarter
/// points' deflections from central differences of the outputs over steps h, relative to the
/// largest derivative, for orders 1 and 2, over 0.4 s of the paper's scene in `elements`
/// elements.
fn finite_difference_errors(h: f64, elements: i32, beam: i32) -> [f64; 2] {
    let (mut inst, msgs) = new_instance();
    assert_eq!(inst.set_integer(&[Var::PhiSource.vr()], &[2]), Status::Ok);
    assert_eq!(inst.set_integer(&[Var::NElements.vr()], &[elements]), Status::Ok);
    assert_eq!(inst.set_integer(&[Var::Beam.vr()], &[beam]), Status::Ok);
    assert_eq!(inst.setup_experiment(Some(1e-12), 0.0, Some(10.2)), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(inst.exit_initialization_mode(), Status::Ok);
    const K: usize = 6;
    let vars = [Var::V1, Var::Theta1, Var::U2, Var::VQuarter, Var::VMid, Var::VThreeQuarter]
        .map(|v| v.vr());
    let (mut values, mut d1, mut d2) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..(0.4 / h).round() as usize {
        assert_eq!(inst.do_step(k as f64 * h, h), Status::Ok, "{:?}", msgs.borrow().last());
        let mut y = [0.0; K];
        assert_eq!(inst.get_real(&vars, &mut y), Status::Ok);
        let (mut a, mut b) = ([0.0; K], [0.0; K]);
        assert_eq!(inst.get_real_output_derivatives(&vars, &[1; K], &mut a), Status::Ok);
        assert_eq!(inst.get_real_output_derivatives(&vars, &[2; K], &mut b), Status::Ok);
        values.push(y);
        d1.push(a);
        d2.push(b);
    }
    let mut worst = [0.0f64; 2];
    for j in 0..K {
        let scale1 = d1.iter().map(|d| d[j].abs()).fold(0.0, f64::max);
        let scale2 = d2.iter().map(|d| d[j].abs()).fold(0.0, f64::max);
        for k in 1..values.len() - 1 {
            let fd1 = (values[k + 1][j] - values[k - 1][j]) / (2.0 * h);
            let fd2 = (values[k + 1][j] - 2.0 * values[k][j] + values[k - 1][j]) / (h * h);
            worst[0] = worst[0].max((fd1 - d1[k][j]).abs() / scale1);
            worst[1] = worst[1].max((fd2 - d2[k][j]).abs() / scale2);
        }
    }
    worst
}

#[test]
fn output_derivatives_match_finite_differences_of_the_outputs() {
    // Central differences are off by O(h²): the differences shrink 4-fold per halving.
    // Four elements vibrate up to 460 rad/s (ω·h = 0.23 at h = 5e-4): shorter steps. The
    // exact beam (beam = 2) computes its tip's and quarter points' motion its own way.
    for (elements, h, beam) in [(1, 2e-3, 1), (4, 5e-4, 1), (4, 5e-4, 2)] {
        let (coarse, fine) = (
            finite_difference_errors(h, elements, beam),
            finite_difference_errors(h / 2.0, elements, beam),
        );
        for order in 0..2 {
            let ratio = coarse[order] / fine[order];
            assert!(
                fine[order] < 1e-2 && (3.0..5.0).contains(&ratio),
                "{elements} elements, beam {beam}, order {}: {coarse:?} {fine:?}",
                order + 1
            );
        }
    }
    // Outside what the motion gives: refused, with the allowed ones named.
    let (mut inst, msgs) = law_instance(1e-6);
    assert_eq!(inst.do_step(0.0, 0.01), Status::Ok);
    let mut x = [0.0];
    assert_eq!(inst.get_real_output_derivatives(&[Var::N.vr()], &[1], &mut x), Status::Error);
    assert!(msgs.borrow().last().unwrap().1.contains("only v1, theta1"));
    assert_eq!(inst.get_real_output_derivatives(&[Var::V1.vr()], &[3], &mut x), Status::Error);
    assert_eq!(inst.get_real_output_derivatives(&[Var::Ei.vr()], &[1], &mut x), Status::Error);
}

#[test]
fn reactions_and_energy_are_computed_only_when_read() {
    let (mut inst, _) = law_instance(1e-6);
    assert_eq!(inst.do_step(0.0, 0.01), Status::Ok);
    let mut x = [0.0];
    assert_eq!(inst.get_real(&[Var::V1.vr()], &mut x), Status::Ok);
    let c = inst.core.model.cache;
    assert!(c.kinematics.is_some() && c.reactions.is_none() && c.energy.is_none());
    assert_eq!(inst.get_real(&[Var::Moment.vr()], &mut x), Status::Ok);
    assert!(inst.core.model.cache.reactions.is_some() && inst.core.model.cache.energy.is_none());
    // The same values as the standalone outputs at the communication time.
    let run = inst.core.model.run.as_ref().unwrap();
    let o = run.outputs_at(inst.core.time).unwrap();
    assert_eq!(x[0], o.reactions.m);
    assert_eq!(inst.get_real(&[Var::Energy.vr()], &mut x), Status::Ok);
    assert_eq!(x[0], o.energy);
}

/// Running ahead with the law, the fast turn (t_rot = 0.2 s) leaves the range of validity in
/// an integrator step that ends between two communication points: the DoSteps before that
/// end succeed, the one that reaches it is discarded there, at the time and with the
/// message of the exit; an FMU state taken in between restores the same ending; and the
/// outputs stop at the exit, as the standalone run's do.
#[test]
fn running_ahead_the_range_exit_ends_the_step_that_reaches_it() {
    let start = |inst: &mut Instance| {
        assert_eq!(inst.set_integer(&[Var::PhiSource.vr()], &[2]), Status::Ok);
        assert_eq!(inst.set_real(&[Var::TRot.vr()], &[0.2]), Status::Ok);
        assert_eq!(inst.setup_experiment(Some(1e-6), 0.0, None), Status::Ok);
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        assert_eq!(inst.exit_initialization_mode(), Status::Ok);
    };
    let (mut inst, msgs) = new_instance();
    start(&mut inst);
    let h = 0.001;
    let mut k = 0;
    let mut snapshots = Vec::new();
    let discard = loop {
        snapshots.push(inst.get_state().unwrap());
        let status = inst.do_step(k as f64 * h, h);
        if status != Status::Ok {
            break status;
        }
        k += 1;
        assert!(k < 1000, "the fast turn must leave the range");
    };
    assert_eq!(discard, Status::Discard);
    let exit = inst.get_real_status(crate::fmi::STATUS_LAST_SUCCESSFUL_TIME).unwrap();
    let message = msgs.borrow().last().unwrap().1.clone();
    assert!(message.contains("theta1") && message.contains("range of validity"), "{message}");
    assert!(exit > k as f64 * h && exit <= (k + 1) as f64 * h, "{exit} in step {k}");
    assert!(message.contains(&format!("at t = {exit}")), "the exit's time: {message}");
    // The state before the failing step, restored elsewhere, ends the same way.
    let (mut other, _) = new_instance();
    let before = snapshots.pop().unwrap();
    let bytes = inst.serialize(&before).unwrap();
    let restored = other.deserialize(&bytes).unwrap();
    assert_eq!(other.set_state(&restored), Status::Ok);
    assert_eq!(other.do_step(k as f64 * h, h), Status::Discard);
    let again = other.get_real_status(crate::fmi::STATUS_LAST_SUCCESSFUL_TIME).unwrap();
    assert_eq!(again, exit);
}

/// Co-simulation ignores the inputs `dphi` and `ddphi` (Model Exchange's): a host that sets
/// them at every communication point (zeros, as a master that pushes every input does) gets
/// the same numbers as one that does not, and is told once.
#[test]
fn co_simulation_ignores_dphi_and_ddphi() {
    let run = |set_rates: bool| {
        let (mut inst, msgs) = new_instance();
        assert_eq!(inst.setup_experiment(Some(1e-6), 0.0, None), Status::Ok);
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        assert_eq!(inst.exit_initialization_mode(), Status::Ok);
        let mut v1 = Vec::new();
        for k in 0..50 {
            let t = k as f64 * 0.01;
            let phi = crate::model::PaperLaw::default().eval(t).phi;
            assert_eq!(inst.set_real(&[Var::Phi.vr()], &[phi]), Status::Ok);
            if set_rates {
                let status = inst.set_real(&[Var::Dphi.vr(), Var::Ddphi.vr()], &[0.0, 0.0]);
                assert_eq!(status, if k == 0 { Status::Warning } else { Status::Ok }, "{k}");
            }
            assert_eq!(inst.do_step(t, 0.01), Status::Ok);
            let mut x = [0.0];
            assert_eq!(inst.get_real(&[Var::V1.vr()], &mut x), Status::Ok);
            v1.push(x[0]);
        }
        let warnings: Vec<String> = msgs
            .borrow()
            .iter()
            .filter(|(s, _)| *s == Status::Warning)
            .map(|(_, m)| m.clone())
            .collect();
        (v1, warnings)
    };
    let (plain, none) = run(false);
    let (with_rates, told) = run(true);
    assert_eq!(plain, with_rates);
    assert!(none.is_empty(), "{none:?}");
    assert_eq!(told.len(), 1, "{told:?}");
    assert!(told[0].contains("co-simulation ignores"), "{told:?}");
}

/// fmi2SetRealInputDerivatives takes φ's derivatives only: `dphi` and `ddphi` are inputs too
/// (Model Exchange's), and are refused naming the one that takes them (found by fuzzing: the
/// derivative of `ddphi` was taken as φ's).
#[test]
fn input_derivatives_are_phi_s_only() {
    let (mut inst, msgs) = law_instance(1e-6);
    for var in [Var::Dphi, Var::Ddphi, Var::V1] {
        let status = inst.set_real_input_derivatives(&[var.vr()], &[1], &[1.0]);
        assert_eq!(status, Status::Error, "{var:?}");
        let last = msgs.borrow().last().unwrap().1.clone();
        assert!(last.contains("only `phi` (19) does"), "{last}");
    }
    assert_eq!(inst.set_real_input_derivatives(&[Var::Phi.vr()], &[1], &[1.0]), Status::Ok);
}

/// The parts of one communication step (FMI 3.0's intermediate update) share one budget of
/// integrator steps: parts that each fit in it fail once their sum passes it, and the next
/// step has the whole budget again.
#[test]
fn the_parts_of_a_step_share_its_budget_of_integrator_steps() {
    use crate::fmi::{CoSimulation, Interface, Model, Setup, State, Value, Version};
    let started = || {
        let mut fmu = super::BeamBodyFmu::new(Version::Fmi3);
        let setup = Setup { tolerance: Some(1e-8), start_time: 0.0, stop_time: None };
        let law = Value::Integer(2);
        Model::set(&mut fmu, Var::PhiSource.vr(), law, State::Instantiated, &mut Vec::new())
            .unwrap();
        fmu.start(&setup, Interface::CoSimulation).unwrap();
        fmu
    };
    let (part, parts) = (0.01, 30);
    let mut notes = Vec::new();
    // One step of 30 parts with the whole budget: the steps of each part.
    let mut a = started();
    a.begin_step();
    let mut per_part = Vec::new();
    for k in 0..parts {
        let before = a.budget;
        a.do_step(k as f64 * part, (k + 1) as f64 * part, &mut notes).unwrap();
        per_part.push(before - a.budget);
    }
    let total: u64 = per_part.iter().sum();
    let largest = *per_part.iter().max().unwrap();
    assert!(4 * largest < total, "{per_part:?}");
    // Half that budget: the same parts fail part way, each well within it.
    let mut b = started();
    b.step_budget = total / 2;
    b.begin_step();
    let mut t = 0.0;
    let failed = loop {
        match b.do_step(t, t + part, &mut notes) {
            Ok(()) => t += part,
            Err(e) => break e,
        }
        assert!(t < parts as f64 * part, "the budget of {} steps was never spent", total / 2);
    };
    assert!(failed.message.contains("integrator steps in its parts"), "{}", failed.message);
    assert!(t > 2.0 * part, "spent after {t} s: {per_part:?}");
    // A new step has the whole budget again.
    b.begin_step();
    b.do_step(failed.t, failed.t + part, &mut notes).unwrap();
}

/// A run the integrator cannot vouch for (the exact beam in 4 undamped elements at rtol 1e-3
/// with `integrator = bdf`, whose highest modes BDF3–5 amplify): DoStep discards, saying why
/// and what to do, in FMI 2.0 and 3.0; with `energy_check = warn` the run goes on after one
/// warning. The default integrator (Radau IIA on the exact beam) runs it to the end.
#[test]
fn a_broken_energy_balance_discards_the_step() {
    let setup = |inst: &mut Instance, set_int: &dyn Fn(&mut Instance, Var, i64) -> Status| {
        assert_eq!(set_int(inst, Var::NElements, 4), Status::Ok);
        assert_eq!(set_int(inst, Var::Beam, 2), Status::Ok);
        // The enumeration's values count from 1: auto, bdf, radau.
        assert_eq!(set_int(inst, Var::Integrator, 2), Status::Ok);
    };
    let run = |inst: &mut Instance, msgs: &Messages| {
        let h = 0.0085;
        for k in 0..1200 {
            let status = inst.do_step(k as f64 * h, h);
            if status != Status::Ok {
                return (status, k as f64 * h, msgs.borrow().last().cloned());
            }
        }
        (Status::Ok, 10.2, None)
    };
    // An FMI 2.0 instance with the law, ready to step; `more`: (variable, integer value).
    let start = |more: &[(Var, i32)]| {
        let (mut inst, msgs) = new_instance();
        assert_eq!(inst.set_integer(&[Var::PhiSource.vr()], &[2]), Status::Ok);
        setup(&mut inst, &|i, v, k| i.set_integer(&[v.vr()], &[k as i32]));
        for &(var, value) in more {
            assert_eq!(inst.set_integer(&[var.vr()], &[value]), Status::Ok);
        }
        assert_eq!(inst.setup_experiment(Some(1e-3), 0.0, Some(10.2)), Status::Ok);
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        assert_eq!(inst.exit_initialization_mode(), Status::Ok);
        (inst, msgs)
    };
    // FMI 2.0.
    let (mut inst, msgs) = start(&[]);
    let (status, t, msg) = run(&mut inst, &msgs);
    assert_eq!(status, Status::Discard, "{msg:?}");
    let (_, msg) = msg.unwrap();
    assert!(msg.contains("numerical instability") && msg.contains("tighter rtol"), "{msg}");
    assert!(t > 0.5 && t < 10.0, "{t}");
    // The same, going on after a warning.
    let (mut inst, msgs) = start(&[(Var::EnergyCheck, 2)]);
    let h = 0.0085;
    let mut warnings = 0;
    for k in 0..1200 {
        match inst.do_step(k as f64 * h, h) {
            Status::Ok => {}
            Status::Warning => warnings += 1,
            other => panic!("{other:?} at step {k}: {:?}", msgs.borrow().last()),
        }
    }
    assert_eq!(warnings, 1);
    assert!(msgs.borrow().iter().any(|(_, m)| m.contains("energy_check = warn")));
    // The default integrator.
    let (mut inst, msgs) = start(&[(Var::Integrator, 1)]);
    let (status, t, msg) = run(&mut inst, &msgs);
    assert_eq!((status, t), (Status::Ok, 10.2), "{msg:?}");
}

/// A restored FMI 3.0 state whose balance has 100 J too much of the drive's work (the fuzz
/// regression `fmi3-state-whose-step-discards`): the next fmi3DoStep discards, naming the
/// broken balance.
#[test]
fn a_state_with_a_broken_balance_discards_its_next_step() {
    let (mut inst, msgs) = law_instance3(1e-6);
    for k in 0..60 {
        assert_eq!(inst.do_step(k as f64 * 0.0085, 0.0085), Status::Ok);
    }
    let snap = inst.get_state().unwrap();
    let mut bytes = inst.serialize(&snap).unwrap();
    let offsets = crate::fmi::field_offsets(&snap);
    let work = offsets.iter().find(|f| f.0 == "energy_work").unwrap().1;
    let w = f64::from_le_bytes(bytes[work..work + 8].try_into().unwrap()) + 100.0;
    bytes[work..work + 8].copy_from_slice(&w.to_le_bytes());
    crate::fmi::reseal(&mut bytes);
    let restored = inst.deserialize(&bytes).unwrap();
    assert_eq!(inst.set_state(&restored), Status::Ok);
    // Running ahead, the integrator may hold the next communication point already: the
    // check comes with its next step.
    let discarded = (60..63).find(|&k| inst.do_step(k as f64 * 0.0085, 0.0085) != Status::Ok);
    assert!(discarded.is_some());
    let last = msgs.borrow().last().cloned().unwrap().1;
    assert!(last.contains("fmi3DoStep") && last.contains("energy balance is broken"), "{last}");
}
