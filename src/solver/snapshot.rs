//! The integrator state field by field, for FMI's `fmi2SerializeFMUstate` and
//! `fmi2DeSerializeFMUstate`.
//!
//! [`Bdf::visit_state`](super::Bdf::visit_state) walks every field that changes during
//! integration in one fixed order. A writer visitor reads each field; a reader overwrites
//! it. The same walk serves both directions, so the two cannot disagree on the order or the
//! set of fields. The byte format (endianness, header, version) is the caller's.
//!
//! Data that are read back may be corrupt. A reader may store any value, so the walk never
//! panics. [`Bdf::check_state`](super::Bdf::check_state) then rejects every value the
//! integrator could not have produced, before the state is used.

use super::error::SolverError;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector};

pub use crate::visit::{visit_usize, StateVisitor};

/// Largest counter a restored state may hold: 2⁵³. Every integer up to it is exact as an
/// `f64`, which is how an FMU reports counters. It is also far above any real run: one
/// `advance` takes at most 10⁷ steps by default. Sums of two counters
/// ([`Stats::rejected`](super::Stats::rejected)) and the `+ 1` of a step cannot overflow
/// from there.
pub(crate) const MAX_COUNT: u64 = 1 << 53;

/// Visits the components of a vector in index order.
pub(crate) fn visit_vector<V: StateVisitor + ?Sized, D: Dim>(
    v: &mut V,
    name: &'static str,
    x: &mut OVector<f64, D>,
) where
    DefaultAllocator: Allocator<D>,
{
    for e in x.iter_mut() {
        v.real(name, e);
    }
}

/// Visits the entries of a matrix in column-major order.
pub(crate) fn visit_matrix<V: StateVisitor + ?Sized, D: Dim>(
    v: &mut V,
    name: &'static str,
    x: &mut OMatrix<f64, D, D>,
) where
    DefaultAllocator: Allocator<D, D>,
{
    for e in x.iter_mut() {
        v.real(name, e);
    }
}

/// `Ok` if `ok`, else [`SolverError::InvalidState`] naming `field`.
pub(crate) fn require(ok: bool, field: &'static str) -> Result<(), SolverError> {
    if ok {
        Ok(())
    } else {
        Err(SolverError::InvalidState { field })
    }
}

/// Requires every value to be finite.
pub(crate) fn require_finite<'a>(
    values: impl IntoIterator<Item = &'a f64>,
    field: &'static str,
) -> Result<(), SolverError> {
    require(values.into_iter().all(|x| x.is_finite()), field)
}

/// Requires no value to be below 0: each is ≥ 0, +∞ or NaN.
pub(crate) fn require_not_below_zero<'a>(
    values: impl IntoIterator<Item = &'a f64>,
    field: &'static str,
) -> Result<(), SolverError> {
    require(values.into_iter().all(|x| x.is_nan() || *x >= 0.0), field)
}

/// Requires every value to be finite and ≥ 0.
pub(crate) fn require_non_negative<'a>(
    values: impl IntoIterator<Item = &'a f64>,
    field: &'static str,
) -> Result<(), SolverError> {
    require(values.into_iter().all(|x| x.is_finite() && *x >= 0.0), field)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;
    use crate::solver::{Bdf, BdfConfig, FixedStep, OdeSystem, StepOutcome};
    use nalgebra::{SVector, U4};

    /// What a slot of a written state holds.
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Kind {
        Real,
        Count,
        Flag,
    }

    /// Writes every field as a `u64`: reals by their bits, flags as 0 or 1.
    #[derive(Default)]
    struct Writer {
        data: Vec<u64>,
        layout: Vec<(Kind, &'static str)>,
    }

    impl StateVisitor for Writer {
        fn real(&mut self, name: &'static str, x: &mut f64) {
            self.data.push(x.to_bits());
            self.layout.push((Kind::Real, name));
        }
        fn count(&mut self, name: &'static str, x: &mut u64) {
            self.data.push(*x);
            self.layout.push((Kind::Count, name));
        }
        fn flag(&mut self, name: &'static str, x: &mut bool) {
            self.data.push(u64::from(*x));
            self.layout.push((Kind::Flag, name));
        }
    }

    /// Reads what [`Writer`] wrote; a flag is true for any non-zero word.
    struct Reader<'a> {
        data: &'a [u64],
        pos: usize,
    }

    impl Reader<'_> {
        fn next(&mut self) -> u64 {
            let x = self.data[self.pos];
            self.pos += 1;
            x
        }
    }

    impl StateVisitor for Reader<'_> {
        fn real(&mut self, _: &'static str, x: &mut f64) {
            *x = f64::from_bits(self.next());
        }
        fn count(&mut self, _: &'static str, x: &mut u64) {
            *x = self.next();
        }
        fn flag(&mut self, _: &'static str, x: &mut bool) {
            *x = self.next() != 0;
        }
    }

    fn write<D: Dim>(s: &Bdf<D>) -> Writer
    where
        DefaultAllocator: Allocator<D> + Allocator<D, D>,
    {
        // Visit a clone: writing must not need (or make) changes to the original.
        let mut copy = s.clone();
        let mut w = Writer::default();
        copy.visit_state(&mut w);
        assert_eq!(format!("{copy:?}"), format!("{s:?}"), "writing changed the state");
        w
    }

    /// Reads `data` into a fresh solver built with `cfg`, then checks it.
    fn read(cfg: &BdfConfig, data: &[u64]) -> Result<Bdf<U4>, SolverError> {
        let mut s = Bdf::new(*cfg, 0.0, SVector::zeros()).unwrap();
        let mut r = Reader { data, pos: 0 };
        s.visit_state(&mut r);
        assert_eq!(r.pos, data.len(), "the reader saw a different number of fields");
        s.check_state()?;
        Ok(s)
    }

    /// Two driven first-order lags coupled weakly to a fast, lightly damped oscillator
    /// (ω = 60, ζ = 0.01, a mode for the stability guard) whose amplitude is below the
    /// tolerance. The run has rejected steps, order caps and fresh Jacobians. No analytic
    /// Jacobian: J is by differences.
    struct LagsAndFast;

    impl OdeSystem<U4> for LagsAndFast {
        fn rhs(&self, t: f64, y: &SVector<f64, 4>) -> SVector<f64, 4> {
            let (w, zeta) = (60.0, 0.01);
            SVector::<f64, 4>::new(
                -0.5 * (y[0] - math::sin(t)) + 1e-3 * y[1],
                y[3],
                -0.2 * (y[2] - math::cos(0.5 * t)),
                -w * w * y[1] - 2.0 * zeta * w * y[3] + 1e-6 * y[0],
            )
        }
    }

    fn cfg() -> BdfConfig {
        let mut cfg = BdfConfig::new(1e-6);
        cfg.atol = Some(1e-7);
        cfg
    }

    fn y0() -> SVector<f64, 4> {
        SVector::<f64, 4>::new(0.0, 1e-9, 1.0, 0.0)
    }

    /// One step of `s`, and its dense output at a few points of the step, as comparable text
    /// (errors included).
    fn step_and_sample<D: Dim, S: OdeSystem<D>>(s: &mut Bdf<D>, sys: &S, tstop: f64) -> String
    where
        DefaultAllocator: Allocator<D> + Allocator<D, D>,
    {
        let outcome = s.step(sys, tstop);
        let (_, hu) = s.last_step();
        let samples: Vec<_> =
            [0.0, 0.25, 0.5, 0.9, 1.0].iter().map(|f| s.interpolate(s.t() - f * hu)).collect();
        format!("{outcome:?} {samples:?}")
    }

    /// Restores `original`'s state into a fresh solver, then steps both `steps` times and
    /// requires every state, outcome, dense output and counter to agree bit for bit.
    fn assert_restored_continues<S: OdeSystem<U4>>(
        original: &Bdf<U4>,
        sys: &S,
        tstop: f64,
        steps: usize,
    ) {
        let written = write(original);
        let mut restored = read(original.config(), &written.data).unwrap();
        // Debug prints every field (shortest round-trip form of each f64), the unvisited
        // configuration included: equal text means nothing was left out.
        assert_eq!(format!("{restored:?}"), format!("{:?}", original.settled()));
        let mut original = original.clone();
        for k in 0..steps {
            let a = step_and_sample(&mut original, sys, tstop);
            let b = step_and_sample(&mut restored, sys, tstop);
            assert_eq!(a, b, "step {k} after restoring");
            assert_eq!(write(&original).data, write(&restored).data, "state after step {k}");
            assert_eq!(original.stats(), restored.stats());
            if a.starts_with("Err") || original.t() >= tstop {
                break;
            }
        }
        assert_eq!(format!("{restored:?}"), format!("{:?}", original.settled()));
    }

    #[test]
    fn layout_is_the_documented_order() {
        let s = Bdf::new(cfg(), 0.0, y0()).unwrap();
        let w = write(&s);
        let n = 4;
        let mut want: Vec<(Kind, &str)> = vec![(Kind::Real, "t")];
        want.extend(std::iter::repeat_n((Kind::Real, "zn"), 6 * n));
        want.extend([(Kind::Real, "hscale"), (Kind::Real, "h")]);
        want.extend([(Kind::Count, "q"), (Kind::Count, "q_next")]);
        want.extend([(Kind::Real, "h_next"), (Kind::Count, "qwait")]);
        want.extend(std::iter::repeat_n((Kind::Real, "tau"), 7));
        want.extend(std::iter::repeat_n((Kind::Real, "coeffs.l"), 6));
        want.extend(std::iter::repeat_n((Kind::Real, "coeffs.tq"), 6));
        want.extend([(Kind::Count, "coeffs.key_q"), (Kind::Flag, "coeffs.key_order_change")]);
        want.push((Kind::Real, "coeffs.key_h"));
        want.extend(std::iter::repeat_n((Kind::Real, "coeffs.key_tau"), 5));
        want.extend([(Kind::Real, "saved_tq5"), (Kind::Real, "hu"), (Kind::Count, "qu")]);
        want.extend(std::iter::repeat_n((Kind::Real, "acor"), n));
        want.extend(std::iter::repeat_n((Kind::Real, "ewt"), n));
        want.push((Kind::Real, "eta_max"));
        want.extend(std::iter::repeat_n((Kind::Real, "jac"), n * n));
        want.extend([(Kind::Flag, "jac_valid"), (Kind::Flag, "lu")]);
        want.extend(std::iter::repeat_n((Kind::Real, "lu.factors"), n * n));
        want.extend(std::iter::repeat_n((Kind::Count, "lu.perm"), n));
        want.extend([(Kind::Real, "gamma"), (Kind::Real, "gamma_lu"), (Kind::Real, "rate")]);
        want.extend([(Kind::Count, "steps_at_lu"), (Kind::Count, "steps_at_jac")]);
        for _ in 0..8 {
            want.extend([(Kind::Real, "guard.modulus"), (Kind::Real, "guard.angle")]);
        }
        want.push((Kind::Count, "guard.count"));
        want.extend([(Kind::Flag, "started"), (Kind::Flag, "landing"), (Kind::Real, "landing")]);
        for name in [
            "stats.steps",
            "stats.error_test_failures",
            "stats.newton_failures",
            "stats.rhs_evals",
            "stats.rhs_evals_jac",
            "stats.jac_evals",
            "stats.lu_factorizations",
            "stats.newton_iters",
            "stats.order_caps",
            "stats.restarts",
        ] {
            want.push((Kind::Count, name));
        }
        assert_eq!(w.layout, want);
    }

    #[test]
    fn restored_state_continues_bit_for_bit() {
        let sys = LagsAndFast;
        let t_end = 30.0;
        let mut s = Bdf::new(cfg(), 0.0, y0()).unwrap();
        // Fresh from new(), before any step.
        assert_restored_continues(&s, &sys, t_end, 300);
        s.step(&sys, t_end).unwrap();
        // After the first step.
        assert_restored_continues(&s, &sys, t_end, 300);
        // Mid-run, right after steps that followed a rejected attempt, an order cap, a fresh
        // Jacobian, and at regular intervals.
        let (mut after_rejection, mut after_cap, mut after_jac) = (0, 0, 0);
        let mut k = 0;
        while s.t() < t_end {
            let before = *s.stats();
            s.step(&sys, t_end).unwrap();
            // Every state of the run passes the check.
            s.check_state().unwrap();
            let now = *s.stats();
            k += 1;
            let rejected = now.rejected() > before.rejected();
            let capped = now.order_caps > before.order_caps;
            let fresh_jac = now.jac_evals > before.jac_evals;
            if (rejected && after_rejection < 3)
                || (capped && after_cap < 3)
                || (fresh_jac && after_jac < 3)
                || k % 250 == 0
            {
                after_rejection += usize::from(rejected);
                after_cap += usize::from(capped);
                after_jac += usize::from(fresh_jac);
                assert_restored_continues(&s, &sys, t_end, 300);
            }
        }
        let st = *s.stats();
        assert!(after_rejection > 0 && st.error_test_failures > 0, "{st:?}");
        assert!(after_cap > 0, "no order cap: {st:?}");
        assert!(st.rhs_evals_jac > 0);
        // After reinit (not started, old step sizes kept) and its first step.
        s.reinit(s.t(), y0()).unwrap();
        assert_restored_continues(&s, &sys, t_end + 5.0, 300);
        s.step(&sys, t_end + 5.0).unwrap();
        assert_restored_continues(&s, &sys, t_end + 5.0, 300);
    }

    #[test]
    fn restored_state_lands_on_the_stop_time() {
        let sys = LagsAndFast;
        let mut s = Bdf::new(cfg(), 0.0, y0()).unwrap();
        s.advance(&sys, 0.9, f64::INFINITY).unwrap();
        // The next steps end exactly on tstop = 1.
        assert_restored_continues(&s, &sys, 1.0, 300);
        while s.step(&sys, 1.0).unwrap() != StepOutcome::ReachedStop {}
        assert_eq!(s.t(), 1.0);
        assert_restored_continues(&s, &sys, 2.0, 300);
    }

    #[test]
    fn restored_fixed_step_state_continues_bit_for_bit() {
        let sys = LagsAndFast;
        let cfg = BdfConfig { fixed_step: Some(FixedStep { h: 1e-3, order: 4 }), ..cfg() };
        let mut s = Bdf::new(cfg, 0.0, y0()).unwrap();
        for _ in 0..3 {
            s.step(&sys, 1.0).unwrap();
            assert_restored_continues(&s, &sys, 1.0, 100);
        }
        assert_eq!(s.next_step().0, 4);
    }

    /// A state left by a failed step (f turns NaN for t > 0.5) can be saved and restored too.
    #[test]
    fn restored_state_after_a_failure_continues_bit_for_bit() {
        struct Blowup;
        impl OdeSystem<U4> for Blowup {
            fn rhs(&self, t: f64, y: &SVector<f64, 4>) -> SVector<f64, 4> {
                let f = LagsAndFast.rhs(t, y);
                if t > 0.5 {
                    f * f64::NAN
                } else {
                    f
                }
            }
        }
        let mut s = Bdf::new(cfg(), 0.0, y0()).unwrap();
        s.advance(&Blowup, 1.0, 1.0).unwrap_err();
        assert_restored_continues(&s, &LagsAndFast, 1.0, 300);
    }

    /// A mid-run state with an LU, guard modes and every counter non-zero.
    fn mid_run_state() -> Bdf<U4> {
        let mut s = Bdf::new(cfg(), 0.0, y0()).unwrap();
        s.advance(&LagsAndFast, 12.0, f64::INFINITY).unwrap();
        s
    }

    /// Every real slot set to NaN or ±∞, and every count to a huge value, is rejected and
    /// named, unless the field allows it or the slot is unused (the payload of an absent
    /// LU or landing); a state that passes the check is stepped, which must not panic.
    #[test]
    fn corrupt_fields_are_rejected_and_named() {
        let s = mid_run_state();
        let cfg = *s.config();
        let w = write(&s);
        assert!(w.data[w.layout.iter().position(|l| l.1 == "lu").unwrap()] == 1);
        assert!(w.data[w.layout.iter().position(|l| l.1 == "guard.count").unwrap()] > 0);
        let mut checked = 0;
        for (i, &(kind, name)) in w.layout.iter().enumerate() {
            let bad: &[u64] = match kind {
                Kind::Real => &[
                    f64::NAN.to_bits(),
                    (-f64::NAN).to_bits(),
                    f64::INFINITY.to_bits(),
                    f64::NEG_INFINITY.to_bits(),
                ],
                Kind::Count => &[u64::MAX, MAX_COUNT + 1, u64::from(u32::MAX) + 1],
                Kind::Flag => &[],
            };
            for &value in bad {
                let mut data = w.data.clone();
                data[i] = value;
                let x = f64::from_bits(value);
                let allowed = match (kind, name) {
                    (Kind::Real, "saved_tq5") => x.is_nan() || x == f64::INFINITY,
                    (Kind::Real, "rate") => x == f64::INFINITY,
                    // 2³² is a valid counter, and no valid step count for steps_at_*.
                    (Kind::Count, name) => value <= MAX_COUNT && name.starts_with("stats."),
                    _ => false,
                };
                match read(&cfg, &data) {
                    Err(e) => {
                        // Cached coefficients that disagree with their key are caught as a
                        // whole.
                        let field = match (name, e) {
                            ("coeffs.tq", SolverError::InvalidState { field: "coeffs" }) => name,
                            _ => match e {
                                SolverError::InvalidState { field } => field,
                                _ => "",
                            },
                        };
                        assert_eq!(field, name, "slot {i}: {e:?}");
                        assert!(!allowed, "slot {i} `{name}` = {x} was rejected");
                        checked += 1;
                    }
                    Ok(mut r) => {
                        let unused = write(&r).data == w.data;
                        assert!(allowed || unused, "slot {i} `{name}` = {value:#x} passed");
                        for _ in 0..50 {
                            let _ = r.step(&LagsAndFast, 20.0);
                        }
                    }
                }
            }
        }
        assert!(checked > 300, "{checked} rejections");
    }

    /// Consistency rules between fields.
    #[test]
    fn inconsistent_states_are_rejected() {
        let s = mid_run_state();
        let cfg = *s.config();
        let w = write(&s);
        let slot = |name: &str, k: usize| {
            w.layout.iter().enumerate().filter(|l| l.1 .1 == name).nth(k).unwrap().0
        };
        let with = |changes: &[(usize, u64)]| {
            let mut data = w.data.clone();
            for &(i, v) in changes {
                data[i] = v;
            }
            read(&cfg, &data).map(|_| ()).map_err(|e| match e {
                SolverError::InvalidState { field } => field,
                e => panic!("{e}"),
            })
        };
        assert_eq!(with(&[]), Ok(()));
        // Orders outside this configuration's range; lowering max_order rejects the state.
        assert_eq!(with(&[(slot("q", 0), 0)]), Err("q"));
        assert_eq!(with(&[(slot("q", 0), 6)]), Err("q"));
        assert_eq!(with(&[(slot("q_next", 0), 0)]), Err("q_next"));
        assert_eq!(with(&[(slot("qu", 0), 6)]), Err("qu"));
        assert_eq!(with(&[(slot("qwait", 0), 11)]), Err("qwait"));
        let q = s.last_step().0;
        assert!(q >= 2, "order {q}");
        let lower = BdfConfig { max_order: q - 1, ..cfg };
        assert_eq!(read(&lower, &w.data).unwrap_err(), SolverError::InvalidState { field: "q" });
        // Negative values.
        assert_eq!(with(&[(slot("hscale", 0), (-1e-3f64).to_bits())]), Err("hscale"));
        assert_eq!(with(&[(slot("h_next", 0), (-1e-3f64).to_bits())]), Err("h_next"));
        assert_eq!(with(&[(slot("tau", 2), (-1e-3f64).to_bits())]), Err("tau"));
        assert_eq!(with(&[(slot("coeffs.tq", 2), (-0.5f64).to_bits())]), Err("coeffs.tq"));
        assert_eq!(with(&[(slot("eta_max", 0), 0.5f64.to_bits())]), Err("eta_max"));
        assert_eq!(with(&[(slot("rate", 0), (-1.0f64).to_bits())]), Err("rate"));
        assert_eq!(with(&[(slot("guard.angle", 0), 120f64.to_bits())]), Err("guard.angle"));
        assert_eq!(with(&[(slot("guard.count", 0), 9)]), Err("guard.count"));
        // The LU: a repeated index, and a zero pivot.
        let p0 = w.data[slot("lu.perm", 0)];
        assert_eq!(with(&[(slot("lu.perm", 1), p0)]), Err("lu.perm"));
        assert_eq!(with(&[(slot("lu.factors", 5), 0)]), Err("lu.factors"));
        // ... which do not matter when there is no LU.
        assert_eq!(with(&[(slot("lu", 0), 0), (slot("lu.perm", 1), p0)]), Ok(()));
        // Counters: the last LU and J cannot lie after the last step.
        let steps = w.data[slot("stats.steps", 0)];
        assert_eq!(with(&[(slot("steps_at_lu", 0), steps + 1)]), Err("steps_at_lu"));
        assert_eq!(with(&[(slot("steps_at_jac", 0), steps + 1)]), Err("steps_at_jac"));
        assert_eq!(with(&[(slot("stats.restarts", 0), MAX_COUNT + 1)]), Err("stats.restarts"));
    }

    /// xorshift64*, for reproducible garbage.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }
        fn below(&mut self, n: u64) -> u64 {
            self.next() % n
        }
        fn uniform(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Random finite values of every size put into a valid state: those that pass the check
    /// are stepped and sampled, which must not panic (debug builds also trap integer
    /// overflow).
    #[test]
    fn garbage_that_passes_the_check_does_not_panic() {
        let states = [mid_run_state(), Bdf::new(cfg(), 0.0, y0()).unwrap()];
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut passed = 0;
        for trial in 0..3000 {
            let s = &states[trial % 2];
            // Garbage may leave a tiny step far from tstop: bound the work of `advance`.
            let cfg = BdfConfig { max_steps: 200, ..*s.config() };
            let w = write(s);
            let mut data = w.data.clone();
            for _ in 0..1 + rng.below(4) {
                let i = rng.below(data.len() as u64) as usize;
                let old = f64::from_bits(data[i]);
                data[i] = match w.layout[i].0 {
                    Kind::Real => {
                        let x = match rng.below(10) {
                            0 => 0.0,
                            1 => -old,
                            2 => old * (1.0 + 1e-3 * rng.uniform()),
                            3 => old * math::pow(10.0, 40.0 * rng.uniform() - 20.0),
                            4 => f64::MAX * rng.uniform(),
                            5 => f64::MIN_POSITIVE * rng.uniform(),
                            6 => 1e-300,
                            7 => -1e3 * rng.uniform(),
                            _ => math::pow(10.0, 600.0 * rng.uniform() - 300.0),
                        };
                        x.to_bits()
                    }
                    Kind::Count => match rng.below(4) {
                        0 => rng.below(12),
                        1 => data[i].wrapping_add(1),
                        2 => data[i].saturating_sub(1),
                        _ => MAX_COUNT - rng.below(3),
                    },
                    Kind::Flag => rng.below(2),
                };
            }
            let Ok(mut r) = read(&cfg, &data) else { continue };
            passed += 1;
            let tstop = r.t() + math::pow(10.0, 4.0 * rng.uniform() - 2.0);
            for _ in 0..30 {
                let (_, hu) = r.last_step();
                let _ = r.interpolate(r.t() - 0.5 * hu);
                if r.step(&LagsAndFast, tstop).is_err() && rng.below(2) == 0 {
                    break;
                }
            }
            let _ = r.advance(&LagsAndFast, tstop, tstop);
            r.check_state().ok();
        }
        assert!(passed > 1000, "{passed} of 3000 garbage states passed the check");
    }

    #[test]
    fn placeholder_lu_is_valid_and_writes_zeros() {
        let s = Bdf::new(cfg(), 0.0, y0()).unwrap();
        let w = write(&s);
        for (i, l) in w.layout.iter().enumerate() {
            if l.1 == "lu.factors" {
                assert_eq!(w.data[i], 0);
            }
        }
        let perm: Vec<u64> =
            (0..w.data.len()).filter(|&i| w.layout[i].1 == "lu.perm").map(|i| w.data[i]).collect();
        assert_eq!(perm, [0, 1, 2, 3]);
    }
}
