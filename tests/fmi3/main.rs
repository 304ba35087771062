//! The FMI 3.0 API through its 75 exported `fmi3…` functions, called as a C host calls them:
//! co-simulation against FMI 2.0's bit for bit (one core), Model Exchange, the host's φ
//! through the intermediate-update callback, enumerations as Int64, FMU states, the
//! functions the model does not provide, NULL pointers, and the state machine in every
//! state (`misuse.rs`).

mod arrays;
#[allow(unused_imports)]
#[path = "../common/mod.rs"]
mod common;
mod fuzz_regressions;
mod misuse;

use beam_body::fmi3::exports::*;
use beam_body::fmi3::types::*;
use beam_body::fmu::variables::{guid, Var};
use std::cell::{Cell, RefCell};
use std::f64::consts::PI;
use std::ffi::{c_void, CStr, CString};
use std::ptr::{null, null_mut};

pub const OK: fmi3Status = fmi3OK;
pub const ERROR: fmi3Status = fmi3Error;

/// The paper's law φ = π sin²(πt / (2·0.85)) for t < 0.85, then π.
pub fn paper_phi(t: f64) -> f64 {
    if t < 0.85 {
        PI * beam_body::math::powi(beam_body::math::sin(PI * t / (2.0 * 0.85)), 2)
    } else {
        PI
    }
}

pub fn vr(var: Var) -> fmi3ValueReference {
    var.vr()
}

/// A call on an instance, made from inside the host's callback.
pub type Probe = fn(fmi3Instance) -> fmi3Status;
/// φ(t), as the host's callback sets it.
pub type Signal = fn(f64) -> f64;

/// What the host's callbacks see: the log, and for the intermediate-update callback the
/// instance and what it does there.
#[derive(Default)]
pub struct Env {
    pub log: RefCell<Vec<(fmi3Status, String, String)>>,
    pub instance: Cell<usize>,
    /// φ(t) the callback sets; `None`: the callback sets nothing.
    pub phi: Cell<Option<Signal>>,
    pub times: RefCell<Vec<f64>>,
    /// intermediateVariableSetRequested of each callback.
    pub set_requested: RefCell<Vec<bool>>,
    /// v1 read in each callback (NaN where the read failed).
    pub v1: RefCell<Vec<f64>>,
    /// Statuses of the calls the callback made.
    pub statuses: RefCell<Vec<fmi3Status>>,
    /// A call to make from inside the callback, with its status kept in `statuses`.
    pub probe: Cell<Option<Probe>>,
}

unsafe extern "C" fn log_message(
    env: fmi3InstanceEnvironment,
    status: fmi3Status,
    category: fmi3String,
    message: fmi3String,
) {
    let env = unsafe { &*(env as *const Env) };
    let text = |s: fmi3String| unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned();
    env.log.borrow_mut().push((status, text(category), text(message)));
}

unsafe extern "C" fn intermediate_update(
    env: fmi3InstanceEnvironment,
    t: fmi3Float64,
    set_requested: fmi3Boolean,
    get_allowed: fmi3Boolean,
    _step_finished: fmi3Boolean,
    can_return_early: fmi3Boolean,
    _early: *mut fmi3Boolean,
    _early_time: *mut fmi3Float64,
) {
    let env = unsafe { &*(env as *const Env) };
    assert_eq!((get_allowed, can_return_early), (fmi3True, fmi3False));
    env.times.borrow_mut().push(t);
    env.set_requested.borrow_mut().push(set_requested == fmi3True);
    let c = env.instance.get() as fmi3Instance;
    let mut v1 = f64::NAN;
    // NaN stays when the read fails.
    unsafe { fmi3GetFloat64(c, &vr(Var::V1), 1, &mut v1, 1) };
    env.v1.borrow_mut().push(v1);
    if let Some(phi) = env.phi.get() {
        let s = unsafe { fmi3SetFloat64(c, &vr(Var::Phi), 1, &phi(t), 1) };
        env.statuses.borrow_mut().push(s);
    }
    if let Some(probe) = env.probe.get() {
        let s = probe(c);
        env.statuses.borrow_mut().push(s);
    }
}

/// One FMI 3.0 instance with its host environment.
pub struct Host {
    pub c: fmi3Instance,
    pub env: Box<Env>,
}

impl Drop for Host {
    fn drop(&mut self) {
        unsafe { fmi3FreeInstance(self.c) }
    }
}

pub fn token() -> CString {
    CString::new(guid()).unwrap()
}

impl Host {
    pub fn cs(name: &str) -> Host {
        Host::cs_with(name, &[], false)
    }

    /// Co-simulation with the given required intermediate variables; `callback`: whether to
    /// pass the intermediate-update callback.
    pub fn cs_with(name: &str, required: &[u32], callback: bool) -> Host {
        let env = Box::<Env>::default();
        let name = CString::new(name).unwrap();
        let cb: Option<fmi3IntermediateUpdateCallback> =
            if callback { Some(intermediate_update) } else { None };
        let c = unsafe {
            fmi3InstantiateCoSimulation(
                name.as_ptr(),
                token().as_ptr(),
                null(),
                fmi3False,
                fmi3False,
                fmi3False,
                fmi3False,
                required.as_ptr(),
                required.len(),
                &*env as *const Env as *mut c_void,
                Some(log_message),
                cb,
            )
        };
        assert!(!c.is_null(), "{:?}", env.log.borrow());
        env.instance.set(c as usize);
        Host { c, env }
    }

    pub fn me(name: &str) -> Host {
        let env = Box::<Env>::default();
        let name = CString::new(name).unwrap();
        let c = unsafe {
            fmi3InstantiateModelExchange(
                name.as_ptr(),
                token().as_ptr(),
                null(),
                fmi3False,
                fmi3False,
                &*env as *const Env as *mut c_void,
                Some(log_message),
            )
        };
        assert!(!c.is_null(), "{:?}", env.log.borrow());
        env.instance.set(c as usize);
        Host { c, env }
    }

    /// The log so far, emptied.
    pub fn take(&self) -> Vec<(fmi3Status, String, String)> {
        std::mem::take(&mut *self.env.log.borrow_mut())
    }

    /// Asserts `status` is Error and that an error message holding every needle was logged.
    #[track_caller]
    pub fn expect_error(&self, status: fmi3Status, needles: &[&str]) {
        let log = self.take();
        assert_eq!(status, ERROR, "{log:#?}");
        assert!(
            log.iter().any(|(s, cat, m)| *s == ERROR
                && cat == "logStatusError"
                && needles.iter().all(|n| m.contains(n))),
            "no error message with {needles:?}: {log:#?}"
        );
    }

    #[track_caller]
    pub fn ok(&self, status: fmi3Status) {
        assert_eq!(status, OK, "{:#?}", self.take());
    }

    pub fn enter(&self, stop: Option<f64>) -> fmi3Status {
        let (defined, stop) = (stop.is_some() as fmi3Boolean, stop.unwrap_or(0.0));
        unsafe { fmi3EnterInitializationMode(self.c, fmi3True, 1e-6, 0.0, defined, stop) }
    }

    pub fn exit(&self) -> fmi3Status {
        unsafe { fmi3ExitInitializationMode(self.c) }
    }

    #[track_caller]
    pub fn initialize(&self) {
        self.ok(self.enter(None));
        self.ok(self.exit());
    }

    pub fn set_real(&self, var: Var, x: f64) -> fmi3Status {
        unsafe { fmi3SetFloat64(self.c, &vr(var), 1, &x, 1) }
    }

    pub fn get_reals(&self, vars: &[Var]) -> (fmi3Status, Vec<f64>) {
        let vrs: Vec<u32> = vars.iter().map(|v| vr(*v)).collect();
        let mut out = vec![f64::NAN; vrs.len()];
        let s =
            unsafe { fmi3GetFloat64(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr(), out.len()) };
        (s, out)
    }

    #[track_caller]
    pub fn real(&self, var: Var) -> f64 {
        let (s, y) = self.get_reals(&[var]);
        self.ok(s);
        y[0]
    }

    /// fmi3GetDirectionalDerivative of `unknowns` along `seed` in `knowns`, into `n` values
    /// (each array counts all its elements).
    pub fn directional(
        &self,
        unknowns: &[Var],
        knowns: &[Var],
        seed: &[f64],
        n: usize,
    ) -> (fmi3Status, Vec<f64>) {
        let (u, k): (Vec<u32>, Vec<u32>) =
            (unknowns.iter().map(|v| vr(*v)).collect(), knowns.iter().map(|v| vr(*v)).collect());
        let mut out = vec![f64::NAN; n];
        let s = unsafe {
            fmi3GetDirectionalDerivative(
                self.c,
                u.as_ptr(),
                u.len(),
                k.as_ptr(),
                k.len(),
                seed.as_ptr(),
                seed.len(),
                out.as_mut_ptr(),
                n,
            )
        };
        (s, out)
    }

    pub fn set_enum(&self, var: Var, k: i64) -> fmi3Status {
        unsafe { fmi3SetInt64(self.c, &vr(var), 1, &k, 1) }
    }

    /// DoStep; the status and (terminateSimulation, lastSuccessfulTime).
    pub fn step(&self, tc: f64, h: f64) -> (fmi3Status, bool, f64) {
        let (mut event, mut terminate, mut early, mut last) = (9u8, 9u8, 9u8, f64::NAN);
        let s = unsafe {
            fmi3DoStep(self.c, tc, h, fmi3True, &mut event, &mut terminate, &mut early, &mut last)
        };
        if s <= fmi3Warning {
            assert_eq!((event, early), (fmi3False, fmi3False));
        }
        (s, terminate == fmi3True, last)
    }

    /// Steps `n` times by `h` from `t`, asserting OK; the new time.
    #[track_caller]
    pub fn steps(&self, t: f64, h: f64, n: usize) -> f64 {
        let mut t = t;
        for _ in 0..n {
            let (s, terminated, last) = self.step(t, h);
            assert_eq!(s, OK, "DoStep({t}, {h}): {:#?}", self.take());
            t += h;
            assert!(!terminated && last == t);
        }
        t
    }
}

/// The tip's motion.
pub const MOTION: [Var; 3] = [Var::V1, Var::Theta1, Var::U2];

/// Co-simulation with the law through FMI 3.0 gives FMI 2.0's numbers bit for bit (one core,
/// one model), and `time` is the communication time.
#[test]
fn co_simulation_is_fmi2_s_bit_for_bit() {
    use beam_body::fmi2::exports as f2;
    let a = Host::cs("fmi3");
    a.ok(a.set_enum(Var::PhiSource, 2));
    a.initialize();
    // FMI 2.0 through its own exports.
    let b = {
        let name = CString::new("fmi2").unwrap();
        let functions = common::callbacks(null_mut());
        let c = unsafe {
            f2::fmi2Instantiate(name.as_ptr(), 1, token().as_ptr(), null(), &*functions, 0, 0)
        };
        assert!(!c.is_null());
        c
    };
    unsafe {
        assert_eq!(f2::fmi2SetInteger(b, &vr(Var::PhiSource), 1, &2), OK);
        assert_eq!(f2::fmi2SetupExperiment(b, 1, 1e-6, 0.0, 0, 0.0), OK);
        assert_eq!(f2::fmi2EnterInitializationMode(b), OK);
        assert_eq!(f2::fmi2ExitInitializationMode(b), OK);
    }
    let mut t = 0.0;
    for _ in 0..120 {
        a.steps(t, 0.01, 1);
        assert_eq!(unsafe { f2::fmi2DoStep(b, t, 0.01, 1) }, OK);
        t += 0.01;
        let (s, y3) = a.get_reals(&MOTION);
        a.ok(s);
        let mut y2 = [0.0; 3];
        let vrs = MOTION.map(vr);
        assert_eq!(unsafe { f2::fmi2GetReal(b, vrs.as_ptr(), 3, y2.as_mut_ptr()) }, OK);
        assert_eq!(y3.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), y2.map(f64::to_bits));
        assert_eq!(a.real(Var::Time), t);
    }
    assert!(a.real(Var::V1).abs() > 0.1, "the beam moved");
    unsafe { f2::fmi2FreeInstance(b) };
}

/// A host's φ, values only at the communication points, with phi_source = input.
fn input_host(name: &str, required: &[u32], callback: bool) -> Host {
    let h = Host::cs_with(name, required, callback);
    h.ok(h.set_enum(Var::PhiSource, 1));
    h.ok(h.set_real(Var::Phi, paper_phi(0.0)));
    h.initialize();
    h
}

/// Runs `h` to t = 1.02 by steps of `dt`, setting φ at each communication point; the tip's
/// motion at the end.
fn run_input(h: &Host, dt: f64) -> Vec<f64> {
    let n = (1.02 / dt).round() as usize;
    let mut t = 0.0;
    for k in 0..n {
        h.ok(h.set_real(Var::Phi, paper_phi(t)));
        let (s, _, _) = h.step(t, dt);
        assert_eq!(s, OK, "{:#?}", h.take());
        t = (k + 1) as f64 * dt;
    }
    let (s, y) = h.get_reals(&MOTION);
    h.ok(s);
    y
}

/// The host's φ through the intermediate-update callback: called inside each step every
/// `intermediate_step` (1 ms), it sets φ there, and the run is then far closer to the law's
/// than with φ at the communication points only (values reconstructed from samples 42.5 ms
/// apart; measured 1.3e-5 m against 6.5e-3 m).
#[test]
fn intermediate_update_hands_phi_inside_the_step() {
    let reference = {
        let h = Host::cs("law");
        h.ok(h.set_enum(Var::PhiSource, 2));
        h.initialize();
        h.steps(0.0, 0.0425, 24);
        h.get_reals(&MOTION).1
    };
    let values_only = run_input(&input_host("values", &[], false), 0.0425);
    let host = input_host("intermediate", &[vr(Var::Phi)], true);
    host.env.phi.set(Some(paper_phi));
    let intermediate = run_input(&host, 0.0425);
    let times = host.env.times.borrow().clone();
    // 42 parts of 1 ms and one of 1.5 ms in each step (the last part up to 1.25 ms).
    assert_eq!(times.len(), 24 * 42, "the callback ran inside the steps");
    assert!(times.windows(2).all(|w| w[1] - w[0] > 0.99e-3 && w[1] - w[0] < 1.51e-3));
    assert!(host.env.statuses.borrow().iter().all(|s| *s == OK), "{:#?}", host.take());
    let err = |y: &[f64]| (y[0] - reference[0]).abs();
    let (e_values, e_intermediate) = (err(&values_only), err(&intermediate));
    assert!(
        e_intermediate < 0.01 * e_values && e_intermediate < 1e-4,
        "v1 error with intermediate update {e_intermediate:e}, values only {e_values:e}"
    );
    // Without `phi` among the required variables the callback is never called.
    let quiet = input_host("not required", &[], true);
    quiet.env.phi.set(Some(paper_phi));
    run_input(&quiet, 0.0425);
    assert!(quiet.env.times.borrow().is_empty());
    // With the law, the callback is given but there is nothing to hand over: one part.
    let law = Host::cs_with("law with callback", &[vr(Var::Phi)], true);
    law.ok(law.set_enum(Var::PhiSource, 2));
    law.initialize();
    law.steps(0.0, 0.0425, 4);
    assert!(law.env.times.borrow().is_empty());
}

/// A host that reads the outputs inside the step (fmusim's `--intermediate-update` lists
/// every output it records in requiredIntermediateVariables): with the law, the callback
/// comes every `intermediate_step` without asking for inputs, v1 read there is the one a run
/// with a communication step of 0.5 ms gives at the same time (the integrator's own steps and
/// its dense output, in both), and the communication points are those of the run without the
/// callback, bit for bit.
#[test]
fn intermediate_update_serves_the_outputs() {
    let run = |host: &Host, dt: f64, n: usize| {
        host.ok(host.set_enum(Var::PhiSource, 2));
        host.ok(unsafe { fmi3EnterInitializationMode(host.c, fmi3True, 1e-10, 0.0, 0, 0.0) });
        host.ok(host.exit());
        let mut at_points = Vec::new();
        for k in 0..n {
            let (s, _, _) = host.step(k as f64 * dt, dt);
            assert_eq!(s, OK, "{:#?}", host.take());
            at_points.push(host.real(Var::V1));
        }
        at_points
    };
    let outputs = [vr(Var::V1), vr(Var::Theta1), vr(Var::Moment), vr(Var::Energy)];
    let reader = Host::cs_with("reader", &outputs, true);
    let coarse = run(&reader, 0.0085, 40);
    let fine = run(&Host::cs("fine"), 0.0005, 680);
    let plain = run(&Host::cs("plain"), 0.0085, 40);
    let times = reader.env.times.borrow().clone();
    assert_eq!(times.len(), 40 * 8, "8 callbacks in each step of 8.5 ms");
    assert!(reader.env.set_requested.borrow().iter().all(|r| !r), "no input asked for");
    assert!(reader.env.statuses.borrow().iter().all(|s| *s == OK), "{:#?}", reader.take());
    let v1 = reader.env.v1.borrow().clone();
    let worst = times
        .iter()
        .zip(&v1)
        .map(|(t, v)| (v - fine[(t / 0.0005).round() as usize - 1]).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-12, "v1 in the callbacks against the 0.5 ms run: {worst:e}");
    assert!(v1.iter().any(|v| v.abs() > 1e-3), "the beam moved");
    assert_eq!(coarse, plain, "the callbacks moved the communication points");
}

/// Inside the callback: the intermediate input may be set, values read; other inputs,
/// parameters, a nested step and FMU states are refused.
#[test]
fn intermediate_update_mode_allows_only_its_calls() {
    fn probes() -> [(Probe, fmi3Status); 6] {
        [
            (|c| unsafe { fmi3Reset(c) }, ERROR),
            (|c| unsafe { fmi3SetFloat64(c, &vr(Var::Dphi), 1, &0.0, 1) }, ERROR),
            (|c| unsafe { fmi3SetFloat64(c, &vr(Var::L), 1, &2.0, 1) }, ERROR),
            (
                |c| {
                    let (mut a, mut b, mut d, mut t) = (0, 0, 0, 0.0);
                    unsafe { fmi3DoStep(c, 0.0, 0.01, 1, &mut a, &mut b, &mut d, &mut t) }
                },
                ERROR,
            ),
            (
                |c| {
                    let mut s = null_mut();
                    unsafe { fmi3GetFMUState(c, &mut s) }
                },
                ERROR,
            ),
            (
                |c| {
                    let mut y = [0.0; 2];
                    let vrs = [vr(Var::V1), vr(Var::Time)];
                    unsafe { fmi3GetFloat64(c, vrs.as_ptr(), 2, y.as_mut_ptr(), 2) }
                },
                OK,
            ),
        ]
    }
    for (k, (probe, want)) in probes().into_iter().enumerate() {
        let host = input_host(&format!("probe {k}"), &[vr(Var::Phi)], true);
        host.env.probe.set(Some(probe));
        host.env.phi.set(Some(paper_phi));
        host.ok(host.set_real(Var::Phi, 0.0));
        let (s, _, _) = host.step(0.0, 0.0425);
        assert_eq!(s, OK, "{:#?}", host.take());
        let got = host.env.statuses.borrow().clone();
        assert!(!got.is_empty());
        assert!(got.chunks(2).all(|pair| pair == [OK, want]), "probe {k}: {got:?}");
        let log = host.take();
        if want == ERROR {
            let needle = [
                "fmi3Reset: illegal call sequence",
                "intermediate update mode",
                "intermediate update mode",
                "illegal call sequence",
                "illegal call sequence",
                "",
            ][k];
            assert!(log.iter().any(|(_, _, m)| m.contains(needle)), "probe {k}: {log:#?}");
        }
        // After the step, the instance is back in step mode.
        host.steps(0.0425, 0.0425, 1);
    }
}

/// Model Exchange: 6 states (the paper's four, the filter's two), 2 event indicators equal to
/// the `range_margin_*` variables,
/// derivatives those of FMI 2.0's Model Exchange at the same state.
#[test]
fn model_exchange_gives_fmi2_s_derivatives() {
    use beam_body::fmi2::exports as f2;
    let a = Host::me("me3");
    a.ok(a.set_enum(Var::PhiSource, 2));
    let mut n = 0usize;
    a.ok(unsafe { fmi3GetNumberOfContinuousStates(a.c, &mut n) });
    assert_eq!(n, 6);
    a.ok(unsafe { fmi3GetNumberOfEventIndicators(a.c, &mut n) });
    assert_eq!(n, 2);
    a.initialize();
    let (mut need, mut term, mut nom, mut val, mut def, mut next) = (9, 9, 9, 9, 9, f64::NAN);
    a.ok(unsafe {
        fmi3UpdateDiscreteStates(a.c, &mut need, &mut term, &mut nom, &mut val, &mut def, &mut next)
    });
    assert_eq!((need, term, def), (fmi3False, fmi3False, fmi3True));
    assert_eq!(next, 0.85, "the law's end is a time event");
    a.ok(unsafe { fmi3EnterContinuousTimeMode(a.c) });
    let functions = common::callbacks(null_mut());
    let name = CString::new("me2").unwrap();
    let b = unsafe {
        f2::fmi2Instantiate(name.as_ptr(), 0, token().as_ptr(), null(), &*functions, 0, 0)
    };
    assert!(!b.is_null());
    unsafe {
        assert_eq!(f2::fmi2SetInteger(b, &vr(Var::PhiSource), 1, &2), OK);
        assert_eq!(f2::fmi2SetupExperiment(b, 1, 1e-6, 0.0, 0, 0.0), OK);
        assert_eq!(f2::fmi2EnterInitializationMode(b), OK);
        assert_eq!(f2::fmi2ExitInitializationMode(b), OK);
        let mut info = std::mem::zeroed();
        assert_eq!(f2::fmi2NewDiscreteStates(b, &mut info), OK);
        assert_eq!(f2::fmi2EnterContinuousTimeMode(b), OK);
    }
    for (t, x) in
        [(0.3, [0.01, -0.02, 0.3, -0.1, 0.2, 1.0]), (0.6, [0.2, 0.1, -0.5, 0.4, 0.0, 0.0])]
    {
        a.ok(unsafe { fmi3SetTime(a.c, t) });
        a.ok(unsafe { fmi3SetContinuousStates(a.c, x.as_ptr(), 6) });
        let mut d3 = [0.0; 6];
        a.ok(unsafe { fmi3GetContinuousStateDerivatives(a.c, d3.as_mut_ptr(), 6) });
        let mut d2 = [0.0; 6];
        unsafe {
            assert_eq!(f2::fmi2SetTime(b, t), OK);
            assert_eq!(f2::fmi2SetContinuousStates(b, x.as_ptr(), 6), OK);
            assert_eq!(f2::fmi2GetDerivatives(b, d2.as_mut_ptr(), 6), OK);
        }
        assert_eq!(d3.map(f64::to_bits), d2.map(f64::to_bits));
        assert_eq!(d3[0], x[2]);
        let mut z = [0.0; 2];
        a.ok(unsafe { fmi3GetEventIndicators(a.c, z.as_mut_ptr(), 2) });
        let (s, margins) = a.get_reals(&[Var::RangeMarginV1, Var::RangeMarginTheta1]);
        a.ok(s);
        assert_eq!(z.to_vec(), margins);
        assert_eq!(z[1], PI / 2.0 - x[1].abs());
        assert_eq!(a.real(Var::Time), t);
        let (mut enter, mut stop) = (9, 9);
        a.ok(unsafe { fmi3CompletedIntegratorStep(a.c, fmi3True, &mut enter, &mut stop) });
        assert_eq!((enter, stop), (fmi3False, fmi3False));
    }
    // A directional derivative: d q′ / d dq = 1 along dq's first element (q′ = dq).
    let (status, out) = a.directional(&[Var::Dq], &[Var::Dq], &[1.0, 0.0], 2);
    a.ok(status);
    assert!((out[0] - 1.0).abs() < 1e-8 && out[1].abs() < 1e-8, "{out:?}");
    unsafe { f2::fmi2FreeInstance(b) };
}

/// What the model does not provide returns fmi3Error with why; types without variables
/// answer an empty request with OK and refuse any value reference naming its type.
#[test]
fn unprovided_functions_say_why() {
    let h = Host::cs("unprovided");
    h.ok(h.enter(None));
    let calls: [(Probe, &str); 8] = [
        (|c| unsafe { fmi3EvaluateDiscreteStates(c) }, "providesEvaluateDiscreteStates"),
        (|c| unsafe { fmi3ActivateModelPartition(c, 0, 0.0) }, "scheduled execution"),
        (|c| unsafe { fmi3GetShiftDecimal(c, null(), 0, null_mut()) }, "no clocks"),
        (|c| unsafe { fmi3SetIntervalFraction(c, null(), 0, null(), null()) }, "no clocks"),
        (
            |c| unsafe {
                fmi3GetAdjointDerivative(c, null(), 0, null(), 0, null(), 0, null_mut(), 0)
            },
            "providesAdjointDerivatives",
        ),
        (|c| unsafe { fmi3GetNumberOfVariableDependencies(c, 0, null_mut()) }, "dependencies"),
        (|c| unsafe { fmi3EnterStepMode(c) }, "hasEventMode = false"),
        (|c| unsafe { fmi3EnterEventMode(c) }, "hasEventMode = false"),
    ];
    for (call, why) in calls {
        h.expect_error(call(h.c), &["not provided", why]);
    }
    let mut f = [0f32; 1];
    h.ok(unsafe { fmi3GetFloat32(h.c, null(), 0, f.as_mut_ptr(), 0) });
    let s = unsafe { fmi3GetFloat32(h.c, &vr(Var::L), 1, f.as_mut_ptr(), 1) };
    h.expect_error(s, &["fmi3GetFloat32", "`l`", "a Float64 variable, not a Float32"]);
    let s = unsafe { fmi3SetUInt8(h.c, &vr(Var::Formulation), 1, &1u8, 1) };
    h.expect_error(s, &["fmi3SetUInt8", "an Int64 variable, not a UInt8"]);
    let s = unsafe {
        fmi3InstantiateScheduledExecution(
            null(),
            null(),
            null(),
            0,
            0,
            null_mut(),
            None,
            None,
            None,
            None,
        )
    };
    assert!(s.is_null());
}

/// Enumerations are Int64; Int32 is the integers'; `nValues` must match.
#[test]
fn enumerations_are_int64_and_values_are_counted() {
    let h = Host::cs("enums");
    h.ok(h.enter(None));
    let mut k = 0i64;
    h.ok(unsafe { fmi3GetInt64(h.c, &vr(Var::Formulation), 1, &mut k, 1) });
    assert!(k >= 1);
    h.ok(h.set_enum(Var::Formulation, 2));
    h.ok(unsafe { fmi3GetInt64(h.c, &vr(Var::Formulation), 1, &mut k, 1) });
    assert_eq!(k, 2);
    let s = unsafe { fmi3SetInt32(h.c, &vr(Var::Formulation), 1, &2, 1) };
    h.expect_error(s, &["fmi3SetInt32", "`formulation`", "an Int64 variable, not an Int32"]);
    for k in [1 << 40, i64::MIN, i64::MAX] {
        let s = h.set_enum(Var::Formulation, k);
        h.expect_error(s, &["fmi3SetInt64", &format!("`formulation` = {k} is out of range")]);
    }
    let mut n = 0i32;
    h.ok(unsafe { fmi3GetInt32(h.c, &vr(Var::MaxOrder), 1, &mut n, 1) });
    assert!((1..=5).contains(&n));
    let mut y = [0.0; 2];
    let s = unsafe { fmi3GetFloat64(h.c, &vr(Var::L), 1, y.as_mut_ptr(), 2) };
    h.expect_error(s, &["fmi3GetFloat64", "1 value references but 2 values"]);
    // Every type counts nValues: Boolean's too, also with NULL values and nValues = 0.
    let vrs = [vr(Var::StabilityGuard); 2];
    let mut flags = [fmi3False; 2];
    let s = unsafe { fmi3GetBoolean(h.c, vrs.as_ptr(), 2, flags.as_mut_ptr(), 1) };
    h.expect_error(s, &["fmi3GetBoolean", "2 value references but 1 values"]);
    let s = unsafe { fmi3GetBoolean(h.c, vrs.as_ptr(), 2, std::ptr::null_mut(), 0) };
    h.expect_error(s, &["fmi3GetBoolean", "2 value references but 0 values"]);
    let s = unsafe { fmi3SetBoolean(h.c, vrs.as_ptr(), 2, flags.as_ptr(), 1) };
    h.expect_error(s, &["fmi3SetBoolean", "2 value references but 1 values"]);
    h.ok(unsafe { fmi3GetBoolean(h.c, vrs.as_ptr(), 2, flags.as_mut_ptr(), 2) });
    // More value references than values: each slice has its own count, and the types
    // without variables refuse the first value reference.
    let (vrs, mut sizes, mut bins) = ([vr(Var::L); 3], [0usize; 1], [null(); 1]);
    let s =
        unsafe { fmi3GetBinary(h.c, vrs.as_ptr(), 3, sizes.as_mut_ptr(), bins.as_mut_ptr(), 1) };
    h.expect_error(s, &["fmi3GetBinary", "`l`", "not a Binary"]);
    let s = h.set_real(Var::Time, 1.0);
    h.expect_error(s, &["fmi3SetFloat64", "`time`", "independent variable"]);
    let s = h.set_real(Var::L, -1.0);
    h.expect_error(s, &["fmi3SetFloat64", "`l`"]);
}

/// An FMI 2.0 instance takes no FMI 3.0 call, nor the reverse.
#[test]
fn versions_do_not_mix() {
    use beam_body::fmi2::exports as f2;
    let h = Host::cs("fmi3 instance");
    h.ok(h.set_enum(Var::PhiSource, 2));
    h.initialize();
    let s = unsafe { f2::fmi2DoStep(h.c, 0.0, 0.01, 1) };
    h.expect_error(s, &["fmi2DoStep", "made by fmi3Instantiate"]);
    let functions = common::callbacks(null_mut());
    let name = CString::new("fmi2 instance").unwrap();
    let b = unsafe {
        f2::fmi2Instantiate(name.as_ptr(), 1, token().as_ptr(), null(), &*functions, 0, 0)
    };
    assert_eq!(unsafe { fmi3Terminate(b) }, ERROR);
    unsafe { f2::fmi2FreeInstance(b) };
    h.steps(0.0, 0.01, 2);
}

/// The instantiate functions refuse a wrong token, event mode in co-simulation and required
/// intermediate variables that cannot be, saying so; NULL names and callbacks do not crash.
#[test]
fn instantiation_refusals() {
    let env = Box::<Env>::default();
    let envp = &*env as *const Env as *mut c_void;
    let name = CString::new("x").unwrap();
    let bad = CString::new("{not-the-token}").unwrap();
    let cs = |token: &CString, event: fmi3Boolean, required: &[u32]| unsafe {
        fmi3InstantiateCoSimulation(
            name.as_ptr(),
            token.as_ptr(),
            null(),
            0,
            0,
            event,
            0,
            required.as_ptr(),
            required.len(),
            envp,
            Some(log_message),
            Some(intermediate_update),
        )
    };
    let expect = |c: fmi3Instance, needle: &str| {
        assert!(c.is_null());
        let log = std::mem::take(&mut *env.log.borrow_mut());
        assert!(
            log.iter().any(|(s, _, m)| *s == ERROR && m.contains(needle)),
            "{needle}: {log:#?}"
        );
    };
    expect(cs(&bad, 0, &[]), "instantiationToken {not-the-token} does not match");
    expect(cs(&token(), 1, &[]), "eventModeUsed = true");
    expect(cs(&token(), 0, &[vr(Var::Dphi)]), "`dphi`");
    expect(cs(&token(), 0, &[9999]), "unknown value reference 9999");
    expect(cs(&token(), 0, &[vr(Var::L)]), "`l`");
    let me = unsafe {
        fmi3InstantiateModelExchange(
            null(),
            token().as_ptr(),
            null(),
            0,
            0,
            envp,
            Some(log_message),
        )
    };
    expect(me, "instanceName is NULL");
    let quiet = unsafe {
        fmi3InstantiateModelExchange(name.as_ptr(), bad.as_ptr(), null(), 0, 0, null_mut(), None)
    };
    assert!(quiet.is_null());
}

/// NULL out-arguments and arrays are errors, not crashes.
#[test]
fn null_pointers_are_refused() {
    let h = Host::cs("nulls");
    h.ok(h.set_enum(Var::PhiSource, 2));
    h.initialize();
    let (mut a, mut b, mut t) = (0, 0, 0.0);
    let s = unsafe { fmi3DoStep(h.c, 0.0, 0.01, 1, &mut a, &mut b, null_mut(), &mut t) };
    h.expect_error(s, &["fmi3DoStep", "`earlyReturn` is NULL"]);
    let s = unsafe { fmi3GetFloat64(h.c, &vr(Var::V1), 1, null_mut(), 1) };
    h.expect_error(s, &["fmi3GetFloat64", "`value` is NULL"]);
    let s = unsafe { fmi3GetOutputDerivatives(h.c, &vr(Var::V1), 1, null(), null_mut(), 1) };
    h.expect_error(s, &["fmi3GetOutputDerivatives", "`orders` is NULL"]);
    assert_eq!(
        unsafe { fmi3DoStep(null_mut(), 0.0, 0.01, 1, &mut a, &mut b, &mut a, &mut t) },
        ERROR
    );
    unsafe { fmi3FreeInstance(null_mut()) };
    h.steps(0.0, 0.01, 1);
}

/// FMU states: serialized in the middle of a run, restored into another instance, the run
/// continues bit for bit; output derivatives come with fmi3GetOutputDerivatives.
#[test]
fn fmu_states_continue_bit_for_bit() {
    let a = Host::cs("a");
    a.ok(a.set_enum(Var::PhiSource, 2));
    a.initialize();
    let t = a.steps(0.0, 0.02, 20);
    let mut s = null_mut();
    a.ok(unsafe { fmi3GetFMUState(a.c, &mut s) });
    let mut size = 0;
    a.ok(unsafe { fmi3SerializedFMUStateSize(a.c, s, &mut size) });
    let mut bytes = vec![0u8; size];
    a.ok(unsafe { fmi3SerializeFMUState(a.c, s, bytes.as_mut_ptr(), size) });
    a.ok(unsafe { fmi3FreeFMUState(a.c, &mut s) });
    assert!(s.is_null());
    a.steps(t, 0.02, 10);
    let end = a.get_reals(&MOTION).1;
    let b = Host::cs("b");
    let mut r = null_mut();
    b.ok(unsafe { fmi3DeserializeFMUState(b.c, bytes.as_ptr(), size, &mut r) });
    b.ok(unsafe { fmi3SetFMUState(b.c, r) });
    b.steps(t, 0.02, 10);
    assert_eq!(
        b.get_reals(&MOTION).1.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
        end.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
    );
    let (vrs, orders) = ([vr(Var::V1), vr(Var::V1)], [1, 2]);
    let mut d = [0.0; 2];
    b.ok(unsafe {
        fmi3GetOutputDerivatives(b.c, vrs.as_ptr(), 2, orders.as_ptr(), d.as_mut_ptr(), 2)
    });
    assert_eq!(d[0], b.real(Var::Dv1));
    // A Model Exchange instance refuses a co-simulation state.
    let me = Host::me("me");
    let st = unsafe { fmi3SetFMUState(me.c, r) };
    me.expect_error(st, &["fmi3SetFMUState", "co-simulation"]);
}

/// A host that lists `phi` but sets nothing in its callback (FMI 3.0: it *may* set): the
/// FMU goes on from the samples it holds, extrapolated, so the run is what values at the
/// communication points give (a held value taken as a sample would make a staircase of φ,
/// and at 8.5 ms the run left the range of validity at t = 0.30 s).
#[test]
fn a_callback_that_sets_nothing_extends_the_samples_held() {
    let h = 0.0085;
    let n = 120; // to 1.02 s
    let law = Host::cs("law");
    law.ok(law.set_enum(Var::PhiSource, 2));
    law.initialize();
    law.steps(0.0, h, n);
    let reference = law.get_reals(&MOTION).1;
    let values = run_input(&input_host("values", &[], false), h);
    let silent = input_host("silent", &[vr(Var::Phi)], true);
    let y = run_input(&silent, h);
    assert_eq!(silent.env.times.borrow().len(), n * 8, "8 parts of 1 ms and one of 0.5 ms");
    let (e_values, e_silent) = ((values[0] - reference[0]).abs(), (y[0] - reference[0]).abs());
    eprintln!("v1 error: values only {e_values:e}, callback setting nothing {e_silent:e}");
    assert!(e_silent < 2.0 * e_values + 1e-6, "{e_silent:e} against {e_values:e}");
}
