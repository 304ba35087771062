//! The stability guard: an order cap against the BDF3–5 instability near the imaginary axis.
//!
//! BDF3–5 are only A(α)-stable. For an undamped mode λ = ±iω the largest root of the
//! order-q formula at constant step exceeds 1 for h·ω in a band (numerics-notes.md; Hairer &
//! Wanner, *Solving ODEs II*, §V.2): the parasitic amplitude then grows by up to 4.6 %, 19 %
//! and 38 % per step for q = 3, 4, 5. The error controller cannot see a mode whose amplitude
//! is below the tolerance, so it may park h inside the band; the mode then grows until the
//! controller reacts by shrinking h, which for h·ω above the peak makes the growth worse.
//!
//! With N ≤ 8 states the eigenvalues of J are cheap. Each time J is evaluated we store its
//! weakly damped oscillatory modes; before each step the order is capped so that no such mode
//! has h·|λ| inside the unstable band of the order used. BDF1 and BDF2 are A-stable and are
//! never capped.

use super::eigen::eigenvalues;
use super::error::SolverError;
use super::snapshot::{require, visit_usize, StateVisitor};
use crate::math;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OMatrix};

/// The angle α (degrees) of A(α)-stability of BDF_q, index q (Hairer & Wanner II, table V.2.1).
/// Modes within α of the negative real axis are stable at any step.
pub const A_STABILITY_ANGLE_DEG: [f64; 6] = [90.0, 90.0, 90.0, 86.03, 73.35, 51.84];

/// The band of h·ω, for λ = iω, in which BDF_q is unstable: the upper end is where the largest
/// root falls back to 1, the lower end where it first exceeds 1 + 10⁻³ per step (below that
/// the growth is of the size of the truncation error, which the error test controls). The
/// ends are rounded outwards; `tests::bands_match_root_moduli` recomputes them.
pub fn unstable_band(q: usize) -> Option<(f64, f64)> {
    match q {
        3 => Some((0.25, 1.94)),
        4 => Some((0.38, 4.72)),
        5 => Some((0.72, 9.40)),
        _ => None,
    }
}

/// The amplitude change per period of an undamped mode resolved by BDF_q at h·ω = y, below
/// the order's unstable band: |ζ(iy)|^(2π/y) − 1 in magnitude, from the leading term of the
/// largest root's modulus, |ζ(iy)| = 1 + c_q·y^(p+1) + …, times 2π/y steps per period:
/// BDF1 −y²/2, BDF2 −y⁴/4, BDF3 +y⁴/4, BDF4 +y⁶/3, BDF5 −y⁶/6. BDF3 and BDF4 let the
/// amplitude grow, BDF1, 2 and 5 damp it; either way the error accumulates over the periods
/// a run lasts. (`tests::drift_matches_root_moduli` checks it against the roots: for
/// y ≤ 0.25 it is between 0.8 and 1.5 times the true drift, mostly above it.)
pub fn drift_per_period(q: usize, y: f64) -> f64 {
    use std::f64::consts::PI;
    match q {
        1 => PI * y,
        2 | 3 => 0.5 * PI * math::powi(y, 3),
        4 => 2.0 * PI / 3.0 * math::powi(y, 5),
        _ => PI / 3.0 * math::powi(y, 5),
    }
}

/// For BDF1 and BDF2: a mode with h·|λ| at or above this is not resolved (fewer than 2π
/// steps per period), and the guard may let those orders damp it.
const UNRESOLVED_FROM: f64 = 1.0;

/// Largest number of modes stored (one per complex-conjugate pair).
const MAX_MODES: usize = 8;
/// Modes whose eigenvalue lies more than this angle (degrees) from the negative real axis
/// into the right half-plane are growing physically (e.g. buckling); capping the order does
/// not help them and they are ignored.
const MAX_ANGLE_DEG: f64 = 95.0;

/// A step with h·ρ_last at or above this many times its order's lower band edge, ρ_last the
/// largest |λ| of the last Jacobian's stored modes, takes the modes without trying the bounds
/// first: every bound is ≥ ρ ≥ ρ_last had J not changed, and the modes move little from one
/// Jacobian to the next, so the bounds would not keep the step out of the band. Only the work
/// depends on it, not the order chosen.
const SKIP_BOUNDS_FROM: f64 = 1.5;

/// Squarings of J² in the refined bound ([`refined_radius_bound`]): ‖J^16‖∞^(1/16).
const SQUARINGS: usize = 3;

/// The ∞-norm (largest row sum of moduli) of a square matrix.
fn norm_inf<D: Dim>(m: &OMatrix<f64, D, D>) -> f64
where
    DefaultAllocator: Allocator<D, D>,
{
    m.row_iter().map(|row| row.iter().map(|x| x.abs()).sum::<f64>()).fold(0.0, f64::max)
}

/// The first bound on the spectral radius, ρ(J) ≤ ‖J²‖∞^½ (ρ(J)² = ρ(J²), which no
/// induced norm is below); for a mechanical system the square matters: ‖J‖ grows with ω²,
/// ‖J²‖^½ with ω. A J that is not finite may give any bound (a NaN row sum drops out of the
/// maximum); its modes, when a step asks for them, are none: [`eigenvalues`] refuses it.
fn radius_bound<D: Dim>(jac: &OMatrix<f64, D, D>) -> f64
where
    DefaultAllocator: Allocator<D, D>,
{
    norm_inf(&(jac * jac)).sqrt()
}

/// A tighter upper bound ρ̄ ≥ ρ(J) = max |λ|, from `squarings` more products after J²:
/// ρ(J) = ρ(J^m)^(1/m) ≤ ‖J^m‖^(1/m) for any induced norm, m = 2^(squarings+1), and the
/// bound falls towards ρ(J) as m grows (Gelfand's formula). For a mechanical system
/// J ≈ [[0, I], [A, B]], so J² ≈ diag(A, A) with ρ(A) = ω_max²: ‖J²‖∞^½
/// ([`radius_bound`]) over-estimates ω_max by the row sums of A, whose entries mix the
/// scales of the coordinates: by 1.14–3.0×, 1.5× on average, over the Jacobians of the
/// paper's scene at rtol 1e-6. With m = 16 ([`SQUARINGS`]) the bound is 1.02–1.27× ρ (1.11×
/// on average; the DAE's alike). It exceeds ρ by about κ^(1/m), κ the condition of the
/// eigenvectors, so the squarings matter where the modes' shapes are far from orthogonal.
/// Each power is scaled to norm 1 before it is squared, so nothing overflows: with
/// s_1 = ‖J²‖ and s_k = ‖(M_(k−1)/s_(k−1))²‖ ≤ 1, ρ(J)² ≤ s_1·(s_2·(…·s_k^½)…)^½; with
/// no squaring it is [`radius_bound`]. Infinite if J is not finite.
// Out of line: it runs only when a step reaches the first bound's band.
#[inline(never)]
fn refined_radius_bound<D: Dim>(jac: &OMatrix<f64, D, D>, squarings: usize) -> f64
where
    DefaultAllocator: Allocator<D, D>,
{
    if !jac.iter().all(|x| x.is_finite()) {
        return f64::INFINITY;
    }
    let mut m = jac * jac;
    let mut scales = [1.0; SQUARINGS + 1];
    let mut used = 0;
    for scale in scales.iter_mut() {
        *scale = norm_inf(&m);
        used += 1;
        if used > squarings || *scale == 0.0 || !scale.is_finite() {
            break;
        }
        m /= *scale;
        m = &m * &m;
    }
    // ρ(J)² ≤ s_1·(s_2·(…·s_k^½)…)^½, folded from the innermost (the loop sets s_1 at least).
    let mut square = scales[used - 1];
    for s in scales[..used - 1].iter().rev() {
        square = s * square.sqrt();
    }
    square.sqrt()
}

/// One weakly damped mode: |λ| and its angle from the negative real axis in degrees.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Mode {
    modulus: f64,
    angle_deg: f64,
}

/// The oscillatory modes of the last Jacobian.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct StabilityGuard {
    /// The slots: [`MAX_MODES`], or for a system of more equations one per complex pair it
    /// can have ([`for_dimension`](Self::for_dimension)), so that no mode goes unwatched.
    modes: Vec<Mode>,
    count: usize,
    /// Derived from the modes, not state: index q holds the smallest |h| at which some mode
    /// enters the unstable band of BDF_q (∞ if none can). Below it order q needs no check,
    /// which is every step of a run whose modes are resolved.
    unsafe_from: [f64; 6],
    /// The modes of the last Jacobian are not computed yet: `unsafe_from` then holds the
    /// bounds from its spectral radius bound, and [`max_safe_order`](Self::max_safe_order)
    /// computes them when a step reaches one.
    pending: bool,
    /// Whether `unsafe_from`, while the modes are pending, holds the refined bound (false
    /// when they are not: derived, not state).
    refined: bool,
    /// Whether `unsafe_from`, while the modes are pending, holds a bound at all (before the
    /// first step that asks, it holds 0 for BDF3–5: derived, not state).
    bounded: bool,
    /// The largest |λ| of the stored modes, 0 if none: a prediction of where the next
    /// Jacobian's lie, which only decides whether to try the bounds first (derived from the
    /// modes, not state).
    last_radius: f64,
}

impl Default for StabilityGuard {
    fn default() -> Self {
        Self::for_dimension(0)
    }
}

impl StabilityGuard {
    /// A guard for a system of `n` equations: [`MAX_MODES`] slots, or n/2 if more.
    pub(crate) fn for_dimension(n: usize) -> Self {
        Self {
            modes: vec![Mode::default(); MAX_MODES.max(n / 2)],
            count: 0,
            unsafe_from: [f64::INFINITY; 6],
            pending: false,
            refined: false,
            bounded: false,
            last_radius: 0.0,
        }
    }

    /// Takes a new Jacobian `jac` (at Jacobian evaluations only, not every step). Its modes
    /// are computed only when a step could reach the unstable band of one of them: every
    /// eigenvalue has |λ| ≤ ρ̄, so a step of order q with h·ρ̄ below BDF_q's lower band edge
    /// needs none. Nothing is computed here: the first step of order 3–5 computes ρ̄ =
    /// ‖J²‖∞^½ ([`radius_bound`]); a step that reaches its band refines it to ‖J^16‖∞^(1/16)
    /// ([`refined_radius_bound`]), and only a step that reaches that one's computes the modes
    /// (at once, without the bounds, where the last modes show that they could not spare
    /// them: [`SKIP_BOUNDS_FROM`]). On the paper's scene at rtol 1e-5 the first bound sent 27
    /// of 34 Jacobians to the eigenvalues, though no step reached BDF3's band; the refined one
    /// sends 3. The decisions are those of the modes computed at once.
    pub(crate) fn update<D: Dim>(&mut self, jac: &OMatrix<f64, D, D>)
    where
        DefaultAllocator: Allocator<D, D>,
    {
        self.count = 0;
        self.pending = true;
        self.refined = false;
        self.bounded = false;
        // No bound yet: a step of order 3–5 asks (`max_safe_order`); so does a state written.
        self.bound_by(f64::INFINITY);
        // A Jacobian that is not finite has no modes to find: the guard allows any order.
        if !jac.iter().all(|x| x.is_finite()) {
            self.resolve(jac);
        }
    }

    /// `unsafe_from` from a bound on the eigenvalues' moduli, while the modes are pending.
    fn bound_by(&mut self, bound: f64) {
        for (q, from) in self.unsafe_from.iter_mut().enumerate() {
            *from = unstable_band(q).map_or(f64::INFINITY, |(lo, _)| lo / bound);
        }
    }

    /// A copy with the modes of `jac` computed if they are pending.
    pub(crate) fn resolved<D: Dim>(&self, jac: &OMatrix<f64, D, D>) -> StabilityGuard
    where
        DefaultAllocator: Allocator<D, D>,
    {
        let mut g = self.clone();
        g.resolve(jac);
        g
    }

    /// Stores the oscillatory modes of `jac` if they are pending. If the eigenvalue
    /// iteration fails, no mode is stored and the guard allows any order, as it does without
    /// a Jacobian.
    pub(crate) fn resolve<D: Dim>(&mut self, jac: &OMatrix<f64, D, D>)
    where
        DefaultAllocator: Allocator<D, D>,
    {
        if !self.pending {
            return;
        }
        self.pending = false;
        self.refined = false;
        self.bounded = false;
        self.count = 0;
        let Some(eigenvalues) = eigenvalues(jac) else {
            self.derive_bounds();
            return;
        };
        for &(re, im) in eigenvalues.iter() {
            if im <= 0.0 || self.count == self.modes.len() {
                continue;
            }
            let angle_deg = math::atan2(im, -re).to_degrees();
            if angle_deg <= MAX_ANGLE_DEG {
                self.modes[self.count] = Mode { modulus: math::hypot(re, im), angle_deg };
                self.count += 1;
            }
        }
        self.derive_bounds();
    }

    fn derive_bounds(&mut self) {
        let modes = &self.modes[..self.count.min(self.modes.len())];
        self.last_radius = modes.iter().map(|m| m.modulus).fold(0.0, f64::max);
        for (q, bound) in self.unsafe_from.iter_mut().enumerate() {
            *bound = match unstable_band(q) {
                Some((lo, _)) => modes
                    .iter()
                    .filter(|m| m.angle_deg > A_STABILITY_ANGLE_DEG[q])
                    .map(|m| lo / m.modulus)
                    .fold(f64::INFINITY, f64::min),
                None => f64::INFINITY,
            };
        }
    }

    /// Visits every stored slot (modulus, angle), in use or not, then the count, of a guard
    /// whose modes are not pending ([`resolved`](Self::resolved)).
    pub(crate) fn visit<V: StateVisitor + ?Sized>(&mut self, v: &mut V) {
        debug_assert!(!self.pending);
        for m in &mut self.modes {
            v.real("guard.modulus", &mut m.modulus);
            v.real("guard.angle", &mut m.angle_deg);
        }
        visit_usize(v, "guard.count", &mut self.count);
        self.derive_bounds();
    }

    /// What [`update`](Self::update) stores: finite moduli ≥ 0, angles in
    /// [0, `MAX_ANGLE_DEG`], at most one per slot. Unused slots hold zeros or earlier
    /// modes, which satisfy the same bounds.
    pub(crate) fn check(&self) -> Result<(), SolverError> {
        for m in &self.modes {
            require(m.modulus.is_finite() && m.modulus >= 0.0, "guard.modulus")?;
            require((0.0..=MAX_ANGLE_DEG).contains(&m.angle_deg), "guard.angle")?;
        }
        require(self.count <= self.modes.len(), "guard.count")
    }

    /// Forgets the stored modes (the guard then allows any order).
    pub(crate) fn clear(&mut self) {
        self.count = 0;
        self.pending = false;
        self.refined = false;
        self.bounded = false;
        self.derive_bounds();
    }

    /// The highest order ≤ `q` at which step `h` keeps every mode of `jac`, the Jacobian of
    /// the last [`update`](Self::update), outside the unstable band. The modes are computed
    /// here if the step may need them.
    pub(crate) fn max_safe_order<D: Dim>(
        &mut self,
        q: usize,
        h: f64,
        jac: &OMatrix<f64, D, D>,
    ) -> usize
    where
        DefaultAllocator: Allocator<D, D>,
    {
        // Only order q's own band can need the modes: the loop below stops at the first order
        // whose band `h` is below, and the bounds' `unsafe_from` is below the modes'.
        if self.pending && q >= 3 && h.abs() >= self.unsafe_from[q] {
            // Where the last modes put this step well inside the band's reach, the bounds
            // would not spare the modes (each costs O(N³), as they do): straight to them.
            let lo = unstable_band(q).map_or(f64::INFINITY, |(lo, _)| lo);
            if h.abs() * self.last_radius < SKIP_BOUNDS_FROM * lo {
                if !self.bounded {
                    self.bounded = true;
                    self.bound_by(radius_bound(jac));
                }
                if h.abs() >= self.unsafe_from[q] && !self.refined {
                    self.refined = true;
                    self.bound_by(refined_radius_bound(jac, SQUARINGS));
                }
            }
            if h.abs() >= self.unsafe_from[q] {
                self.resolve(jac);
            }
        }
        let mut k = q;
        while k >= 3 && h.abs() >= self.unsafe_from[k] && !self.safe(k, h) {
            k -= 1;
        }
        k
    }

    /// Whether the guard may move the step to order `q` and size `h`: no stored mode in the
    /// unstable band, and every resolved stored mode (below the band) drifts by at most
    /// `max_drift` per period. A lower order that damps a resolved mode by more than the
    /// tolerance, or lets it grow, over hundreds of periods is no cure for an unstable one:
    /// then the guard leaves the choice to the error test (see `Bdf::choose_next`).
    pub(crate) fn acceptable(&self, q: usize, h: f64, max_drift: f64) -> bool {
        if !self.safe(q, h) {
            return false;
        }
        // Below `lo` a mode counts as resolved: BDF3–5's lower band edge, or for BDF1 and
        // BDF2, which have no band, fewer than 2π steps per period (h·|λ| = 1); damping a
        // mode that is not resolved is what a stiff integrator should do with it.
        let lo = unstable_band(q).map_or(UNRESOLVED_FROM, |(lo, _)| lo);
        self.modes[..self.count].iter().all(|m| {
            let y = h.abs() * m.modulus;
            m.angle_deg <= A_STABILITY_ANGLE_DEG[3]
                || y >= lo
                || drift_per_period(q, y) <= max_drift
        })
    }

    fn safe(&self, q: usize, h: f64) -> bool {
        let Some((lo, hi)) = unstable_band(q) else {
            return true;
        };
        self.modes[..self.count].iter().all(|m| {
            let x = h.abs() * m.modulus;
            m.angle_deg <= A_STABILITY_ANGLE_DEG[q] || x < lo || x > hi
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix2;

    type C = (f64, f64);
    fn mul(a: C, b: C) -> C {
        (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
    }
    fn div(a: C, b: C) -> C {
        let d = b.0 * b.0 + b.1 * b.1;
        ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
    }
    fn sub(a: C, b: C) -> C {
        (a.0 - b.0, a.1 - b.1)
    }

    /// Largest |ζ| of BDF_q applied to y' = λy with hλ = z: the roots of
    /// Σ_{j=1}^{q} (1/j)(1 − w)^j = z in w = 1/ζ, by Durand–Kerner iteration.
    fn max_root_modulus(q: usize, z: C) -> f64 {
        // Coefficients of the polynomial in w, ascending.
        let mut c = vec![(0.0, 0.0); q + 1];
        for j in 1..=q {
            // (1 − w)^j by the binomial theorem.
            let mut binom = 1.0;
            for (k, ck) in c.iter_mut().enumerate().take(j + 1) {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                ck.0 += sign * binom / j as f64;
                binom = binom * (j - k) as f64 / (k + 1) as f64;
            }
        }
        c[0] = sub(c[0], z);
        let lead = c[q];
        let monic: Vec<C> = c.iter().map(|&a| div(a, lead)).collect();
        let eval = |w: C| {
            let mut acc = monic[q];
            for k in (0..q).rev() {
                acc = mul(acc, w);
                acc = (acc.0 + monic[k].0, acc.1 + monic[k].1);
            }
            acc
        };
        let mut roots: Vec<C> = (0..q)
            .map(|k| {
                let a = 0.4 + 0.9 * k as f64;
                (
                    math::powi(0.9_f64, k as i32) * math::cos(a),
                    math::powi(0.9_f64, k as i32) * math::sin(a),
                )
            })
            .collect();
        for _ in 0..500 {
            for i in 0..q {
                let mut den = (1.0, 0.0);
                for j in 0..q {
                    if i != j {
                        den = mul(den, sub(roots[i], roots[j]));
                    }
                }
                roots[i] = sub(roots[i], div(eval(roots[i]), den));
            }
        }
        roots.iter().map(|w| 1.0 / (w.0 * w.0 + w.1 * w.1).sqrt()).fold(0.0, f64::max)
    }

    #[test]
    fn root_finder_reproduces_known_peaks() {
        // numerics-notes.md: worst growth per step 1.046, 1.19, 1.38 for BDF3, 4, 5.
        let peak =
            |q| (1..2000).map(|i| max_root_modulus(q, (0.0, i as f64 * 0.005))).fold(0.0, f64::max);
        assert!((peak(3) - 1.0456).abs() < 1e-3);
        assert!((peak(4) - 1.1910).abs() < 1e-3);
        assert!((peak(5) - 1.3791).abs() < 1e-3);
        // BDF2 is A-stable: no growth anywhere on the imaginary axis.
        assert!((1..400).all(|i| max_root_modulus(2, (0.0, i as f64 * 0.05)) <= 1.0 + 1e-12));
    }

    #[test]
    fn bands_match_root_moduli() {
        for q in 3..=5 {
            let (lo, hi) = unstable_band(q).unwrap();
            // Just inside the band the growth exceeds 1 + 1e-3 (lower end) or 1 (upper end).
            assert!(max_root_modulus(q, (0.0, lo + 0.01)) > 1.0 + 1e-3, "q={q} lo");
            assert!(max_root_modulus(q, (0.0, hi - 0.01)) > 1.0, "q={q} hi");
            // The edges are tight to within 0.02 and rounded outwards.
            assert!(max_root_modulus(q, (0.0, lo - 0.02)) < 1.0 + 1e-3, "q={q} below");
            assert!(max_root_modulus(q, (0.0, hi)) <= 1.0 + 1e-9, "q={q} above");
            assert!(max_root_modulus(q, (0.0, hi - 0.02)) > 1.0, "q={q} tight");
        }
    }

    #[test]
    fn drift_matches_root_moduli() {
        for q in 1..=5 {
            for y in [0.01, 0.03, 0.1, 0.25] {
                let modulus = max_root_modulus(q, (0.0, y));
                let truth = (math::pow(modulus, 2.0 * std::f64::consts::PI / y) - 1.0).abs();
                let ratio = drift_per_period(q, y) / truth;
                assert!((0.8..=1.5).contains(&ratio), "q={q} y={y}: {ratio}");
            }
        }
    }

    #[test]
    fn radius_bound_is_above_every_eigenvalue_and_tight_for_two_modes() {
        use nalgebra::Matrix4;
        let radius = |m: &Matrix4<f64>| {
            let ev = eigenvalues(m).unwrap();
            ev.iter().map(|&(re, im)| math::hypot(re, im)).fold(0.0, f64::max)
        };
        // Random matrices (a fixed linear congruential sequence), of scales 1e-3 to 1e3.
        let mut uniform = math::test_sequence(12345);
        let mut next = || uniform() * 2.0 - 1.0;
        for case in 0..300 {
            let scale = math::powi(10.0, case % 7 - 3);
            let m = Matrix4::from_fn(|_, _| next() * scale);
            let rho = radius(&m);
            let mut last = f64::INFINITY;
            for k in 0..=SQUARINGS {
                let bound = refined_radius_bound(&m, k);
                assert!(bound >= rho * (1.0 - 1e-12), "case {case}, {k}: {bound} < {rho}");
                assert!(bound <= last * (1.0 + 1e-12), "case {case}, {k}: {bound} > {last}");
                last = bound;
            }
        }
        // Two undamped modes of 5 and 30 rad/s coupled through a stiffness matrix of mixed
        // scales (coordinates in m and rad), as the paper's beam: J = [[0, I], [−M⁻¹K, 0]].
        let (w1, w2) = (5.0f64, 30.0f64);
        let t = nalgebra::Matrix2::new(1.0, 8.0, -0.3, 1.0);
        let a =
            -(t * nalgebra::Matrix2::new(w1 * w1, 0.0, 0.0, w2 * w2) * t.try_inverse().unwrap());
        let mut jac = Matrix4::zeros();
        jac.fixed_view_mut::<2, 2>(0, 2).fill_with_identity();
        jac.fixed_view_mut::<2, 2>(2, 0).copy_from(&a);
        let (rho, bound) = (radius(&jac), refined_radius_bound(&jac, SQUARINGS));
        assert!((rho - w2).abs() < 1e-9 * w2);
        let first = radius_bound(&jac);
        assert_eq!(first, refined_radius_bound(&jac, 0));
        assert!(first > 1.4 * rho, "‖J²‖^½ = {first} is not loose here");
        assert!(bound >= rho && bound < 1.1 * rho, "{bound} against {rho} ({first} unsquared)");
        // The zero matrix has no modes; a non-finite one gives a non-finite bound.
        assert_eq!(refined_radius_bound(&Matrix4::<f64>::zeros(), SQUARINGS), 0.0);
        assert!(!refined_radius_bound(&Matrix4::from_element(f64::NAN), 0).is_finite());

        // The guard refines the bound before it computes the modes: a step with h·ρ = 0.2,
        // below BDF3's band, but h·‖J²‖^½ above it, computes none.
        // Only the order's own band calls for them: BDF5's starts at 0.72/‖J²‖^½, above h.
        let mut g = StabilityGuard::default();
        g.update(&jac);
        let h = 0.2 / rho;
        assert!(h * first > 0.25 && h * first < 0.72);
        assert_eq!(g.max_safe_order(5, h, &jac), 5);
        assert!(g.pending && !g.refined);
        assert_eq!(g.max_safe_order(3, h, &jac), 3);
        assert!(g.pending && g.refined);
        // h·ρ = 1: inside BDF4's and BDF5's bands, above BDF3's lower edge: the modes.
        assert_eq!(g.max_safe_order(5, 1.0 / rho, &jac), 2);
        assert!(!g.pending && g.count == 2);
    }

    #[test]
    fn caps_order_for_undamped_mode_in_band() {
        let omega = 100.0;
        let jac = Matrix2::new(0.0, 1.0, -omega * omega, 0.0);
        let mut g = StabilityGuard::default();
        g.update(&jac);
        // h·ω = 0.1: below every band, and below BDF3's for the bound ρ̄ = ω too: the modes
        // are not computed.
        assert_eq!(g.max_safe_order(5, 0.001, &jac), 5);
        assert!(g.pending && g.count == 0);
        // BDF2 has no band: no step of order 2 needs them either.
        assert_eq!(g.max_safe_order(2, 1.0, &jac), 2);
        assert!(g.pending);
        // h·ω = 2: inside the bands of BDF4 and BDF5 and above BDF3's.
        assert_eq!(g.max_safe_order(5, 0.02, &jac), 3);
        assert!(!g.pending && g.count == 1);
        assert!((g.modes[0].modulus - omega).abs() < 1e-9);
        assert_eq!(g.max_safe_order(5, 0.001, &jac), 5);
        // h·ω = 1: BDF5 and BDF4 unsafe, and BDF3 too: cap at 2.
        assert_eq!(g.max_safe_order(5, 0.01, &jac), 2);
        // A strongly damped mode (angle within α_5) never caps.
        let damped = Matrix2::new(0.0, 1.0, -omega * omega, -1.9 * omega);
        g.update(&damped);
        assert_eq!(g.max_safe_order(5, 0.02, &damped), 5);
        assert!(!g.pending);
    }
}
