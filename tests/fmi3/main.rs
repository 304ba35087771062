//! The FMI 3.0 API through its 75 exported `fmi3…` functions, called as a C host calls them:
//! co-simulation against FMI 2.0's bit for bit (one core), Model Exchange, the host's φ
//! through the intermediate-update callback, enumerations as Int64, FMU states, the
//! functions the model does not provide, NULL pointers, and the state machine in every
//! state (`misuse.rs`).

#[allow(dead_code, unused_imports)]
#[path = "../common/mod.rs"]
mod common;
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

/// What the host's callbacks see: the log, and for the intermediate-update callback the
/// instance and what it does there.
#[derive(Default)]
pub struct Env {
    pub log: RefCell<Vec<(fmi3Status, String, String)>>,
    pub instance: Cell<usize>,
    /// φ(t) the callback sets; `None`: the callback sets nothing.
    pub phi: Cell<Option<fn(f64) -> f64>>,
    pub times: RefCell<Vec<f64>>,
    /// Statuses of the calls the callback made.
    pub statuses: RefCell<Vec<fmi3Status>>,
    /// A call to make from inside the callback, with its status kept in `statuses`.
    pub probe: Cell<Option<fn(fmi3Instance) -> fmi3Status>>,
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
    assert_eq!((set_requested, get_allowed, can_return_early), (fmi3True, fmi3True, fmi3False));
    env.times.borrow_mut().push(t);
    let c = env.instance.get() as fmi3Instance;
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
