//! FMI 3.0's arrays: the structural parameter `n_elements`, set in configuration mode only,
//! sizes the nodal shape (`nodal_v`, `nodal_theta`) and Model Exchange's states (`q`, `dq`),
//! whose elements all count in `nValues`; Model Exchange then integrates the beam in n
//! elements, which FMI 2.0's fixed states cannot.

use super::{vr, Host, ERROR};
use beam_body::fmi3::exports::*;
use beam_body::fmi3::types::*;
use beam_body::fmu::variables::Var;
use std::ptr::null;

impl Host {
    fn set_elements(&self, n: u64) -> fmi3Status {
        unsafe { fmi3SetUInt64(self.c, &vr(Var::NElements), 1, &n, 1) }
    }

    /// Configuration mode, `n_elements` = `n`, back to `instantiated`.
    #[track_caller]
    fn configure(&self, n: u64) {
        self.ok(unsafe { fmi3EnterConfigurationMode(self.c) });
        self.ok(self.set_elements(n));
        self.ok(unsafe { fmi3ExitConfigurationMode(self.c) });
    }

    /// Every element of the array `var`, read with `nValues` = `n`.
    fn get_array(&self, var: Var, n: usize) -> (fmi3Status, Vec<f64>) {
        let mut out = vec![f64::NAN; n];
        let s = unsafe { fmi3GetFloat64(self.c, &vr(var), 1, out.as_mut_ptr(), n) };
        (s, out)
    }

    #[track_caller]
    fn array(&self, var: Var, n: usize) -> Vec<f64> {
        let (s, y) = self.get_array(var, n);
        self.ok(s);
        y
    }

    fn enter_tol(&self, tol: f64) -> fmi3Status {
        unsafe { fmi3EnterInitializationMode(self.c, fmi3True, tol, 0.0, fmi3False, 0.0) }
    }
}

/// `n_elements` is set in configuration mode only, as a UInt64, within its range; it sizes
/// the nodal shape, whose tip is v1 and whose middle node is v_mid; `nValues` counts every
/// element, and a wrong count names the array's size.
#[test]
fn n_elements_is_structural_and_sizes_the_nodal_shape() {
    let h = Host::cs("arrays");
    h.ok(h.set_enum(Var::PhiSource, 2));
    let s = h.set_elements(4);
    h.expect_error(s, &["fmi3SetUInt64", "`n_elements`", "structural parameter", "configuration"]);
    let s = unsafe { fmi3SetInt32(h.c, &vr(Var::NElements), 1, &4, 1) };
    h.expect_error(s, &["fmi3SetInt32", "`n_elements`", "UInt64"]);
    h.ok(unsafe { fmi3EnterConfigurationMode(h.c) });
    let s = h.set_real(Var::L, 2.0);
    h.expect_error(s, &["fmi3SetFloat64", "`l`", "only the structural parameters"]);
    let s = h.set_elements(33);
    h.expect_error(s, &["fmi3SetUInt64", "n_elements", "1..=32"]);
    // Values beyond Int32 and Int64 are named as sent (they once saturated to 2147483647).
    for n in [(1u64 << 32) + 4, 1 << 31, u64::MAX] {
        let s = h.set_elements(n);
        h.expect_error(
            s,
            &["fmi3SetUInt64", &format!("`n_elements` = {n} is out of range"), "1..=32"],
        );
    }
    let s = h.enter(None);
    h.expect_error(s, &["fmi3EnterInitializationMode", "configuration mode"]);
    h.ok(h.set_elements(4));
    h.ok(unsafe { fmi3ExitConfigurationMode(h.c) });
    let s = unsafe { fmi3ExitConfigurationMode(h.c) };
    h.expect_error(s, &["fmi3ExitConfigurationMode", "instantiated"]);
    h.ok(h.enter_tol(1e-8));
    let mut n = 0u64;
    h.ok(unsafe { fmi3GetUInt64(h.c, &vr(Var::NElements), 1, &mut n, 1) });
    assert_eq!(n, 4);
    // The start state's shape, before the run: the beam at rest.
    assert_eq!(h.array(Var::NodalV, 4), [0.0; 4]);
    h.ok(h.exit());
    let t = h.steps(0.0, 0.01, 50);
    let v = h.array(Var::NodalV, 4);
    let theta = h.array(Var::NodalTheta, 4);
    assert_eq!(v[3].to_bits(), h.real(Var::V1).to_bits(), "the tip last: {v:?}");
    assert_eq!(theta[3].to_bits(), h.real(Var::Theta1).to_bits());
    // Node 2 of 4 is at l/2, where a cubic Hermite element takes its nodal value.
    assert!((v[1] - h.real(Var::VMid)).abs() < 1e-12 * v[3].abs(), "{v:?}");
    assert!(v[3].abs() > 1e-3, "the beam bends: {v:?}");
    // Both arrays and a scalar in one call: 4 + 4 + 1 values.
    let vrs = [vr(Var::NodalV), vr(Var::NodalTheta), vr(Var::V1)];
    let mut all = [f64::NAN; 9];
    h.ok(unsafe { fmi3GetFloat64(h.c, vrs.as_ptr(), 3, all.as_mut_ptr(), 9) });
    assert_eq!(all[..4], v[..]);
    assert_eq!(all[4..8], theta[..]);
    assert_eq!(all[8], v[3]);
    // The call's trace names each array with its elements.
    h.take();
    h.ok(unsafe { fmi3SetDebugLogging(h.c, fmi3True, 0, null()) });
    h.ok(unsafe { fmi3GetFloat64(h.c, vrs.as_ptr(), 3, all.as_mut_ptr(), 9) });
    h.ok(unsafe { fmi3SetDebugLogging(h.c, fmi3False, 0, null()) });
    let traced = format!("`nodal_v` (60) = [{:?}, {:?}, {:?}, {:?}]", v[0], v[1], v[2], v[3]);
    let log = h.take();
    assert!(
        log.iter()
            .any(|(_, _, m)| m.contains(&traced) && m.contains(&format!("`v1` (20) = {:?}", v[3]))),
        "{log:#?}"
    );
    let s = unsafe { fmi3GetFloat64(h.c, vrs.as_ptr(), 3, all.as_mut_ptr(), 8) };
    h.expect_error(s, &["nValues = 8", "name 9 values", "`nodal_v` has 4"]);
    // Co-simulation gives Model Exchange's states too: q is the nodal shape (the quadratic
    // beam's coordinates), a node's (v_k, θ_k) a row, and dq's last row the tip's rates.
    let q = h.array(Var::Q, 8);
    let interleaved: Vec<f64> = v.iter().zip(&theta).flat_map(|(a, b)| [*a, *b]).collect();
    assert_eq!(q, interleaved);
    let dq = h.array(Var::Dq, 8);
    assert_eq!([dq[6], dq[7]], [h.real(Var::Dv1), h.real(Var::Dtheta1)]);
    assert!(h.array(Var::Ddq, 8).iter().all(|x| x.is_finite() && *x != 0.0));
    // No reconfiguration: the structural parameter is fixed.
    let s = unsafe { fmi3EnterConfigurationMode(h.c) };
    h.expect_error(s, &["fmi3EnterConfigurationMode", "step mode", "no reconfiguration mode"]);
    // An FMI 2.0 instance knows no arrays.
    use beam_body::fmi2::exports as f2;
    let functions = super::common::callbacks(std::ptr::null_mut());
    let name = std::ffi::CString::new("fmi2").unwrap();
    let b = unsafe {
        f2::fmi2Instantiate(name.as_ptr(), 1, super::token().as_ptr(), null(), &*functions, 0, 0)
    };
    let mut y = 0.0;
    assert_eq!(unsafe { f2::fmi2GetReal(b, &vr(Var::NodalV), 1, &mut y) }, ERROR);
    unsafe { f2::fmi2FreeInstance(b) };
    h.steps(t, 0.01, 1);
}

/// A DAE formulation has more states than q and dq (u2), yet gives them in co-simulation, from
/// the start state on: (v1, ϑ1), their rates and accelerations.
#[test]
fn a_dae_gives_q_and_dq() {
    let h = Host::cs("dae arrays");
    h.ok(h.set_enum(Var::PhiSource, 2));
    h.ok(h.set_enum(Var::Formulation, 2));
    h.ok(h.set_real(Var::V10, 0.01));
    h.ok(h.enter(None));
    assert_eq!(h.array(Var::Q, 2), [0.01, 0.0]);
    h.ok(h.exit());
    h.steps(0.0, 0.01, 20);
    let (q, dq, ddq) = (h.array(Var::Q, 2), h.array(Var::Dq, 2), h.array(Var::Ddq, 2));
    assert_eq!(q, [h.real(Var::V1), h.real(Var::Theta1)]);
    assert_eq!(dq, [h.real(Var::Dv1), h.real(Var::Dtheta1)]);
    assert!(ddq.iter().all(|x| x.is_finite() && *x != 0.0), "{ddq:?}");
}

/// So in n elements: the state is (q, u2, q̇, u̇2), and `q`, `dq`, `ddq` are 2n values each, the
/// tip's last (they were 2n + 1, and reading them was refused).
#[test]
fn a_dae_in_elements_gives_q_and_dq() {
    let h = Host::cs("dae arrays in elements");
    h.ok(h.set_enum(Var::PhiSource, 2));
    h.ok(h.set_enum(Var::Formulation, 2));
    h.ok(unsafe { fmi3EnterConfigurationMode(h.c) });
    h.ok(h.set_elements(2));
    h.ok(unsafe { fmi3ExitConfigurationMode(h.c) });
    h.ok(h.enter(None));
    h.ok(h.exit());
    h.steps(0.0, 0.01, 20);
    let (q, dq, ddq) = (h.array(Var::Q, 4), h.array(Var::Dq, 4), h.array(Var::Ddq, 4));
    assert_eq!(q[2..], [h.real(Var::V1), h.real(Var::Theta1)]);
    assert_eq!(dq[2..], [h.real(Var::Dv1), h.real(Var::Dtheta1)]);
    assert!(ddq.iter().all(|x| x.is_finite() && *x != 0.0), "{ddq:?}");
}

/// Model Exchange of the beam in 3 elements: 14 states, q and dq as arrays in the order of
/// x, then the two of the filter of φ; integrated by RK4 through the FMI 3.0 calls, it meets FMI 3.0 co-simulation of the same
/// beam (BDF at rtol 1e-10) to the accuracy of both. The directional derivative takes and
/// gives arrays.
#[test]
fn model_exchange_runs_the_beam_in_elements() {
    const N: usize = 3;
    const NX: usize = 4 * N + 2;
    let a = Host::me("me in elements");
    a.ok(a.set_enum(Var::PhiSource, 2));
    let mut n = 0usize;
    a.ok(unsafe { fmi3GetNumberOfContinuousStates(a.c, &mut n) });
    assert_eq!(n, 6, "one element at the start value");
    a.configure(N as u64);
    a.ok(unsafe { fmi3GetNumberOfContinuousStates(a.c, &mut n) });
    assert_eq!(n, NX);
    a.initialize();
    let (mut need, mut term, mut nom, mut val, mut def, mut next) = (9, 9, 9, 9, 9, f64::NAN);
    a.ok(unsafe {
        fmi3UpdateDiscreteStates(a.c, &mut need, &mut term, &mut nom, &mut val, &mut def, &mut next)
    });
    a.ok(unsafe { fmi3EnterContinuousTimeMode(a.c) });
    let mut x = [0.0; NX];
    let s = unsafe { fmi3GetContinuousStates(a.c, x.as_mut_ptr(), 4) };
    a.expect_error(s, &["nContinuousStates = 4", "14"]);
    a.ok(unsafe { fmi3GetContinuousStates(a.c, x.as_mut_ptr(), NX) });
    let f = |t: f64, x: &[f64; NX]| -> [f64; NX] {
        let mut d = [0.0; NX];
        a.ok(unsafe { fmi3SetTime(a.c, t) });
        a.ok(unsafe { fmi3SetContinuousStates(a.c, x.as_ptr(), NX) });
        a.ok(unsafe { fmi3GetContinuousStateDerivatives(a.c, d.as_mut_ptr(), NX) });
        d
    };
    let axpy = |x: &[f64; NX], h: f64, d: &[f64; NX]| -> [f64; NX] {
        std::array::from_fn(|i| x[i] + h * d[i])
    };
    let (dt, steps) = (2e-5, 10_000);
    let mut t = 0.0;
    for _ in 0..steps {
        let k1 = f(t, &x);
        let k2 = f(t + dt / 2.0, &axpy(&x, dt / 2.0, &k1));
        let k3 = f(t + dt / 2.0, &axpy(&x, dt / 2.0, &k2));
        let k4 = f(t + dt, &axpy(&x, dt, &k3));
        x = std::array::from_fn(|i| x[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        t += dt;
        let (mut enter, mut stop) = (9, 9);
        a.ok(unsafe { fmi3SetTime(a.c, t) });
        a.ok(unsafe { fmi3SetContinuousStates(a.c, x.as_ptr(), NX) });
        a.ok(unsafe { fmi3CompletedIntegratorStep(a.c, fmi3True, &mut enter, &mut stop) });
        assert_eq!((enter, stop), (fmi3False, fmi3False));
    }
    // q and dq are the halves of x's model part, bit for bit; the nodal shape of the
    // quadratic beam is q.
    let q = a.array(Var::Q, 2 * N);
    let dq = a.array(Var::Dq, 2 * N);
    assert_eq!([q, dq].concat(), x[..4 * N]);
    let v = a.array(Var::NodalV, N);
    assert_eq!(v, [x[0], x[2], x[4]]);

    let b = Host::cs("cs in elements");
    b.ok(b.set_enum(Var::PhiSource, 2));
    b.configure(N as u64);
    b.ok(b.enter_tol(1e-10));
    b.ok(b.exit());
    b.steps(0.0, 0.02, 10);
    let v_cs = b.array(Var::NodalV, N);
    let theta_cs = b.array(Var::NodalTheta, N);
    let theta = a.array(Var::NodalTheta, N);
    for k in 0..N {
        assert!((v[k] - v_cs[k]).abs() < 1e-6, "node {k}: ME {v:?}, CS {v_cs:?}");
        assert!((theta[k] - theta_cs[k]).abs() < 1e-6, "node {k}: {theta:?}, {theta_cs:?}");
    }
    assert!(v[N - 1].abs() > 1e-3, "the beam bends: {v:?}");

    // d ddq / d q along a seed, against a central difference of the derivatives.
    let seed: [f64; 2 * N] = std::array::from_fn(|i| 0.1 * (i as f64 + 1.0));
    let (status, out) = a.directional(&[Var::Ddq], &[Var::Q], &seed, 2 * N);
    a.ok(status);
    let e = 1e-6;
    let mut xp = x;
    let mut xm = x;
    for i in 0..2 * N {
        xp[i] += e * seed[i];
        xm[i] -= e * seed[i];
    }
    let (dp, dm) = (f(t, &xp), f(t, &xm));
    let scale = out.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for i in 0..2 * N {
        let fd = (dp[2 * N + i] - dm[2 * N + i]) / (2.0 * e);
        assert!((out[i] - fd).abs() < 1e-5 * scale, "{i}: {out:?} against {fd}");
    }
    let s = a.directional(&[Var::Ddq], &[Var::Q], &seed[..1], 2 * N).0;
    a.expect_error(s, &["fmi3GetDirectionalDerivative", "1 seeds", "an array state counts 6"]);
}

/// FMU states in configuration mode (FMI 3.0's super state "FMU State Setable" holds every
/// state): one saved there restores the structural parameter and the mode. A state saved by
/// an FMI 2.0 instance of the same library is refused by an FMI 3.0 one, naming the versions.
#[test]
fn fmu_states_hold_configuration_mode_and_their_version() {
    use std::ptr::null_mut;
    let h = Host::cs("configured state");
    h.ok(unsafe { fmi3EnterConfigurationMode(h.c) });
    h.ok(h.set_elements(4));
    let mut s = null_mut();
    h.ok(unsafe { fmi3GetFMUState(h.c, &mut s) });
    h.ok(unsafe { fmi3Reset(h.c) });
    h.ok(unsafe { fmi3SetFMUState(h.c, s) });
    h.ok(h.set_elements(3)); // still in configuration mode
    h.ok(unsafe { fmi3SetFMUState(h.c, s) });
    h.ok(unsafe { fmi3ExitConfigurationMode(h.c) });
    h.ok(h.enter(None));
    let mut n = 0u64;
    h.ok(unsafe { fmi3GetUInt64(h.c, &vr(Var::NElements), 1, &mut n, 1) });
    assert_eq!(n, 4);
    h.ok(unsafe { fmi3FreeFMUState(h.c, &mut s) });

    use beam_body::fmi2::exports as f2;
    let functions = super::common::callbacks(null_mut());
    let name = std::ffi::CString::new("fmi2").unwrap();
    let b = unsafe {
        f2::fmi2Instantiate(name.as_ptr(), 1, super::token().as_ptr(), null(), &*functions, 0, 0)
    };
    let (mut s2, mut size) = (null_mut(), 0usize);
    assert_eq!(unsafe { f2::fmi2GetFMUstate(b, &mut s2) }, 0);
    assert_eq!(unsafe { f2::fmi2SerializedFMUstateSize(b, s2, &mut size) }, 0);
    let mut bytes = vec![0u8; size];
    assert_eq!(unsafe { f2::fmi2SerializeFMUstate(b, s2, bytes.as_mut_ptr().cast(), size) }, 0);
    unsafe { f2::fmi2FreeFMUstate(b, &mut s2) };
    unsafe { f2::fmi2FreeInstance(b) };
    let c = Host::cs("fmi3 instance");
    let mut r = null_mut();
    c.ok(unsafe { fmi3DeserializeFMUState(c.c, bytes.as_ptr(), size, &mut r) });
    let st = unsafe { fmi3SetFMUState(c.c, r) };
    c.expect_error(st, &["fmi3SetFMUState", "other FMI version", "Fmi2"]);
    c.ok(unsafe { fmi3FreeFMUState(c.c, &mut r) });
}
