//! φ sent by a host: what it gave at each communication point, and the piece of φ that the
//! next step integrates with.
//!
//! FMI 2.0 (§4.2.1) leaves the interpolation of inputs between communication points to the
//! slave, which may use the history of what it received. [`Interpolation::Smooth`] does:
//! - **Extrapolation.** The polynomial through the newest samples' values and sent
//!   derivatives (Hermite interpolation: Newton's divided differences on repeated nodes) is
//!   evaluated at the end of the step, tc + h, for a target φ, φ′ and φ″. With values only,
//!   the newest `degree + 1` values; with φ′ and φ″, the newest two samples (a quintic).
//! - **A C² join.** The step's piece is the quintic from φ, φ′ and φ″ of the piece in use at
//!   tc to the target at tc + h. So f is continuous at a communication point and the BDF keeps
//!   its history there; the target is recomputed from the host's samples at every point, so
//!   the error of one step's guess does not carry over to the next.
//! - **Jumps.** The host's data at tc are compared with what the piece in use predicted. A
//!   mismatch far beyond the error estimate of that prediction (the change when the oldest
//!   condition is dropped, or the previous step's if larger: one alone vanishes where a
//!   derivative of the signal does) is a jump of the signal itself, in φ″ or lower: the history
//!   before tc is dropped and the integrator restarts there (the paper's law, sent through
//!   the FMU, jumps in φ″ at t_rot).
//! - **The start, values only.** A value says nothing of the slope, so the first step holds
//!   φ. Until the history is full, each new sample improves the estimate σ of φ′ at the
//!   start, and the piece's φ′ moves by the change of σ, and φ by its integral since the
//!   start, as jumps. The beam's coordinates are relative to the rotating body, so these jumps
//!   give it no impulse, whereas a continuous catch-up would (a ramp sent as values got a
//!   kick of its whole slope). The part of the lag that is real φ″ the hold missed is
//!   delivered by the following pieces.
//!
//! [`Interpolation::Taylor`] is FMI's literal polynomial φ + φ′s + ½φ″s² over each step when
//! the host sends derivatives (and, with values only, a C¹ cubic to the extrapolated value and
//! slope); φ′ jumps at every communication point, and the integrator restarts where φ″ does.

use super::phi::{Phi, Poly};
use crate::visit::{visit_usize, StateVisitor};

/// How the pieces of a host's φ are built (the `phi_interpolation` setting).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Interpolation {
    /// C² pieces to an extrapolated target, with jump detection (the default).
    #[default]
    Smooth,
    /// FMI's literal Taylor polynomial over each step.
    Taylor,
}

impl Interpolation {
    pub const ALL: [Interpolation; 2] = [Interpolation::Smooth, Interpolation::Taylor];

    pub fn name(self) -> &'static str {
        match self {
            Interpolation::Smooth => "smooth",
            Interpolation::Taylor => "taylor",
        }
    }
}

impl std::str::FromStr for Interpolation {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        super::formulation::by_name(
            &Interpolation::ALL,
            Interpolation::name,
            "phi_interpolation",
            s,
        )
    }
}

/// What the host gave for φ at one communication point: the value, and the derivatives it
/// sent with fmi2SetRealInputDerivatives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sample {
    pub t: f64,
    pub phi: f64,
    pub dphi: Option<f64>,
    pub ddphi: Option<f64>,
}

impl Sample {
    pub fn value(t: f64, phi: f64) -> Sample {
        Sample { t, phi, dphi: None, ddphi: None }
    }

    pub fn with_derivatives(t: f64, at: Phi) -> Sample {
        Sample { t, phi: at.phi, dphi: Some(at.dphi), ddphi: Some(at.ddphi) }
    }

    /// The sample as φ, φ′, φ″, missing derivatives taken as 0.
    pub fn taylor(&self) -> Phi {
        Phi { phi: self.phi, dphi: self.dphi.unwrap_or(0.0), ddphi: self.ddphi.unwrap_or(0.0) }
    }

    fn sent_derivatives(&self) -> bool {
        self.dphi.is_some() || self.ddphi.is_some()
    }

    /// The conditions this sample puts on an interpolating polynomial: its value, then φ′,
    /// then φ″ (φ″ only with φ′: divided differences need consecutive derivatives).
    fn orders(&self) -> usize {
        match (self.dphi, self.ddphi) {
            (None, _) => 1,
            (Some(_), None) => 2,
            (Some(_), Some(_)) => 3,
        }
    }

    fn derivative(&self, order: usize) -> f64 {
        match order {
            0 => self.phi,
            1 => self.dphi.unwrap_or(0.0),
            _ => self.ddphi.unwrap_or(0.0),
        }
    }
}

/// Samples kept: the extrapolation of values uses up to four.
pub const HISTORY: usize = 4;
/// Most conditions of one extrapolation: two samples with φ, φ′ and φ″.
const MAX_CONDITIONS: usize = 6;
/// A mismatch this many times the prediction's error estimate is a jump.
const JUMP_FACTOR: f64 = 10.0;

/// The host's φ: the newest samples and what the piece in use predicted for the next one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HostSignal {
    pub interpolation: Interpolation,
    /// Degree of the extrapolation of values, 0..=3.
    pub degree: usize,
    /// Newest first; `len` are in use, the rest zero.
    history: [Sample; HISTORY],
    len: usize,
    /// Error estimate of the piece in use at its end, for φ, φ′ and φ″; infinite when there
    /// is none (no jump can be told from an error then).
    predicted_error: [f64; 3],
    /// The estimate of the step before, which `predicted_error` includes.
    last_error: [f64; 3],
    /// Values only, from the start until the history is full: the φ′ at the start that the
    /// pieces include (0 until it is known)…
    start_slope: Option<f64>,
    /// … and the last estimate of it.
    start_estimate: Option<f64>,
}

/// Why no piece could be built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SignalError {
    /// No sample at the step's start.
    NoSample,
    /// The coefficients are not finite: a step so short that 1/h² overflows, or values so
    /// far apart that the slopes do.
    NotFinite,
}

impl std::fmt::Display for SignalError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SignalError::NoSample => "no value of `phi` at the start of the step",
            SignalError::NotFinite => {
                "the input `phi` over the step is not finite when extrapolated from its samples"
            }
        })
    }
}

impl HostSignal {
    pub fn new(interpolation: Interpolation, degree: usize) -> HostSignal {
        HostSignal {
            interpolation,
            degree: degree.min(HISTORY - 1),
            history: [Sample::default(); HISTORY],
            len: 0,
            predicted_error: [f64::INFINITY; 3],
            last_error: [f64::INFINITY; 3],
            start_slope: None,
            start_estimate: None,
        }
    }

    /// The samples, newest first.
    pub fn samples(&self) -> &[Sample] {
        &self.history[..self.len]
    }

    /// The piece of φ before the first step, from the first sample: its Taylor polynomial
    /// (a hold with values only).
    pub fn start(&mut self, first: Sample) -> Poly {
        self.history = [Sample::default(); HISTORY];
        self.history[0] = first;
        self.len = 1;
        self.predicted_error = [f64::INFINITY; 3];
        self.last_error = [f64::INFINITY; 3];
        let open = self.interpolation == Interpolation::Smooth
            && !first.sent_derivatives()
            && self.degree > 0;
        self.start_slope = open.then_some(0.0);
        self.start_estimate = None;
        Poly::taylor(first.t, first.taylor())
    }

    /// Records the host's sample at the start of a step. Samples at or after its time are
    /// dropped first: a host that went back in time restored an older state.
    fn push(&mut self, s: Sample) {
        if self.len == 0 || self.history[0].t < s.t {
            // The common case, a newer sample: all move one down, the oldest of a full
            // history drops out (the unused ones are zeros, and stay so).
            // (element by element: copy_within calls memmove for these 144 bytes)
            for k in (1..HISTORY).rev() {
                self.history[k] = self.history[k - 1];
            }
            self.history[0] = s;
            self.len = (self.len + 1).min(HISTORY);
            return;
        }
        let keep = (0..self.len).find(|&k| self.history[k].t < s.t).unwrap_or(self.len);
        let kept = (self.len - keep).min(HISTORY - 1);
        self.history.copy_within(keep..keep + kept, 1);
        self.history[0] = s;
        self.len = kept + 1;
        self.history[self.len..].fill(Sample::default());
    }

    /// The piece for the step [s.t, s.t + h], given the host's sample `s` at its start and
    /// φ, φ′, φ″ there of the piece in use (`current`).
    /// On failure the signal may have recorded the sample.
    pub fn plan(&mut self, s: Sample, current: Phi, h: f64) -> Result<Poly, SignalError> {
        if !(h.is_finite() && h > 0.0) {
            return Err(SignalError::NotFinite);
        }
        match self.interpolation {
            Interpolation::Smooth => self.plan_smooth(s, current, h),
            Interpolation::Taylor => self.plan_taylor(s, current, h),
        }
    }

    /// The piece for the step [now, now + h] without a new sample (a host that was asked for
    /// its input inside a step and set none, FMI 3.0's intermediate update): from φ, φ′ of the
    /// piece in use (`current`) to the extrapolation of the samples held to now + h, a C¹
    /// join. Holding the last value as a sample at `now` instead would make a staircase of the
    /// signal, whose slopes the next samples would then see.
    pub fn extend(&self, current: Phi, now: f64, h: f64) -> Result<Poly, SignalError> {
        if self.len == 0 {
            return Err(SignalError::NoSample);
        }
        let ahead = now + h - self.history[0].t;
        if !(h.is_finite() && h > 0.0 && ahead > 0.0) {
            return Err(SignalError::NotFinite);
        }
        let derivatives = self.history[0].sent_derivatives();
        let target = self.extrapolate(ahead, derivatives).ok_or(SignalError::NotFinite)?.0;
        finite(Poly::hermite_c1(now, h, current, target))
    }

    fn plan_taylor(&mut self, s: Sample, current: Phi, h: f64) -> Result<Poly, SignalError> {
        self.push(s);
        if s.sent_derivatives() {
            return finite(Poly::taylor(s.t, s.taylor()));
        }
        let target = self.extrapolate(h, false).ok_or(SignalError::NotFinite)?.0;
        finite(Poly::hermite_c1(s.t, h, current, target))
    }

    fn plan_smooth(&mut self, s: Sample, current: Phi, h: f64) -> Result<Poly, SignalError> {
        if s.sent_derivatives() {
            self.plan_derivatives(s, current, h)
        } else {
            self.plan_values(s, current, h)
        }
    }

    /// With derivatives: the quintic through the newest two samples gives the target, and
    /// the piece joins C² (f stays continuous, and the BDF keeps its history).
    fn plan_derivatives(&mut self, s: Sample, current: Phi, h: f64) -> Result<Poly, SignalError> {
        self.start_slope = None;
        self.start_estimate = None;
        let mut start = current;
        // A sample at the time of the newest one replaces it (the first step after the start
        // sample, a host that went back): the host's data there describe the signal better
        // than the piece in use, which was built without them.
        let again = self.len > 0 && self.history[0].t == s.t;
        if again || self.is_jump(&s, &current, h) {
            // The signal itself jumped: only what the host gives from tc on describes it.
            self.len = if again { self.len } else { 0 };
            self.last_error = [f64::INFINITY; 3];
            start = s.taylor();
        }
        self.push(s);
        let (target, error) = self.extrapolate(h, true).ok_or(SignalError::NotFinite)?;
        for ((p, e), last) in self.predicted_error.iter_mut().zip(error).zip(self.last_error) {
            *p = e.max(last);
        }
        self.last_error = error;
        finite(Poly::hermite_c2(s.t, h, start, target))
    }

    /// With values only: the cubic from φ and φ′ of the piece in use to the extrapolated
    /// value and slope (a C¹ join: φ″ then changes at tc by the extrapolation's error in it,
    /// which the driver weighs against the tolerance).
    fn plan_values(&mut self, s: Sample, current: Phi, h: f64) -> Result<Poly, SignalError> {
        self.predicted_error = [f64::INFINITY; 3];
        self.last_error = [f64::INFINITY; 3];
        self.push(s);
        let mut start = current;
        if let Some(applied) = self.start_slope {
            if self.len > self.degree + 1 {
                self.start_slope = None;
                self.start_estimate = None;
            } else if let Some(slope) = self.slope_at_oldest() {
                // φ′ at the start as the samples so far tell it, if the change from the
                // last estimate shows it to be known (a signal from rest gives estimates that
                // fall towards 0 with each sample; a ramp, the same slope twice). The pieces
                // so far lag by the change, in φ′ and by its integral since the start in φ:
                // both are added as jumps.
                let known =
                    self.start_estimate.is_some_and(|e| slope.abs() > 2.0 * (slope - e).abs());
                let sigma = if known { slope } else { 0.0 };
                let since = s.t - self.history[self.len - 1].t;
                start.dphi += sigma - applied;
                start.phi += (sigma - applied) * since;
                let open = self.len < self.degree + 1;
                self.start_slope = open.then_some(sigma);
                self.start_estimate = open.then_some(slope);
            }
        }
        let target = self.extrapolate(h, false).ok_or(SignalError::NotFinite)?.0;
        finite(Poly::hermite_c1(s.t, h, start, target))
    }

    /// Whether the host's data at tc differ from the prediction by more than the
    /// prediction's error could explain.
    fn is_jump(&self, s: &Sample, current: &Phi, h: f64) -> bool {
        if self.len == 0 {
            return false;
        }
        // Round-off of a derivative of order r computed from values of size u over spacing
        // h is about eps·u/h^r.
        let u = s.phi.abs().max(current.phi.abs());
        let du = s.dphi.unwrap_or(0.0).abs().max(current.dphi.abs());
        let ddu = s.ddphi.unwrap_or(0.0).abs().max(current.ddphi.abs());
        let (size, inv) = (u + du * h + ddu * h * h, 1.0 / h);
        let scale = [size, size * inv, size * (inv * inv)];
        let predicted = [current.phi, current.dphi, current.ddphi];
        (0..s.orders()).any(|r| {
            let mismatch = (s.derivative(r) - predicted[r]).abs();
            let floor = 1e3 * f64::EPSILON * scale[r];
            mismatch > JUMP_FACTOR * self.predicted_error[r] + floor
        })
    }

    /// φ′ at the oldest sample of the polynomial through all the values held.
    fn slope_at_oldest(&self) -> Option<f64> {
        let oldest = self.history[self.len - 1].t;
        let newest = self.history[0].t;
        let span = newest - oldest;
        if span.is_nan() || span <= 0.0 {
            return None;
        }
        let (z, c, n) = self.divided_differences(span, false, self.len);
        let x = (oldest - newest) / span;
        let slope = newton(&z[..n], &c[..n], x).1 / span;
        slope.is_finite().then_some(slope)
    }

    /// φ, φ′, φ″ at tc + h of the polynomial through the newest samples, and an estimate of
    /// their errors: the change of each when the oldest condition is dropped.
    fn extrapolate(&self, h: f64, derivatives: bool) -> Option<(Phi, [f64; 3])> {
        let (p, q) = match self.quintic(h, derivatives).or_else(|| self.even(h, derivatives)) {
            Some(pq) => pq,
            None => {
                let most = if derivatives { MAX_CONDITIONS } else { self.degree + 1 };
                let (z, c, n) = self.divided_differences(h, derivatives, most);
                let eval = |m: usize| {
                    let (p, dp, ddp) = newton(&z[..m], &c[..m], 1.0);
                    [p, dp, ddp]
                };
                // The last term; infinite with a single condition. Values only need none:
                // their joins are C¹, and no jump is looked for.
                let q = if n > 1 && derivatives { eval(n - 1) } else { [f64::INFINITY; 3] };
                (eval(n), q)
            }
        };
        let inv = 1.0 / h;
        let scale = [1.0, inv, inv * inv];
        let target = Phi { phi: p[0] * scale[0], dphi: p[1] * scale[1], ddphi: p[2] * scale[2] };
        let error = [0, 1, 2].map(|k| {
            let e = (p[k] - q[k]).abs() * scale[k];
            if e.is_nan() {
                f64::INFINITY
            } else {
                e
            }
        });
        let finite = [target.phi, target.dphi, target.ddphi].iter().all(|x| x.is_finite());
        finite.then_some((target, error))
    }

    /// Values only, at a constant communication step (the samples at tc − kh to within
    /// round-off): the extrapolation to tc + h as fixed weights of the values (the Lagrange
    /// polynomials of the nodes 0, −1, …, −d at 1 and their derivatives; sympy). No error
    /// estimate: values need none.
    fn even(&self, h: f64, derivatives: bool) -> Option<([f64; 3], [f64; 3])> {
        const W: [[[f64; 4]; 3]; 4] = [
            [[1.0, 0.0, 0.0, 0.0], [0.0; 4], [0.0; 4]],
            [[2.0, -1.0, 0.0, 0.0], [1.0, -1.0, 0.0, 0.0], [0.0; 4]],
            [[3.0, -3.0, 1.0, 0.0], [2.5, -4.0, 1.5, 0.0], [1.0, -2.0, 1.0, 0.0]],
            [[4.0, -6.0, 4.0, -1.0], [13.0 / 3.0, -9.5, 7.0, -11.0 / 6.0], [3.0, -8.0, 7.0, -2.0]],
        ];
        if derivatives {
            return None;
        }
        let n = (self.degree + 1).min(self.len);
        let tc = self.history[0].t;
        let tolerance = 16.0 * f64::EPSILON * (1.0 + tc.abs() / h);
        let even = (1..n).all(|k| ((self.history[k].t - tc) / h + k as f64).abs() <= tolerance);
        if !even {
            return None;
        }
        let w = &W[n - 1];
        let at = |k: usize| (0..n).map(|i| w[k][i] * self.history[i].phi).sum::<f64>();
        Some(([at(0), at(1), at(2)], [f64::INFINITY; 3]))
    }

    /// The common case of [`extrapolate`](Self::extrapolate) in closed form: φ, φ′ and φ″ at
    /// both newest samples. The quintic p(x) = A0 + A1x + A2x² + c3x³ + c4x⁴ + c5x⁵ in the
    /// scaled time x = (t − tc)/h, from p, p′ and p″/2 at x = 0 (A0, A1, A2) and at x = −d
    /// (B0, B1, B2), has, with the residuals r0 = B0 − (A0 − A1d + A2d²),
    /// r1 = B1 − (A1 − 2A2d) and r2 = B2 − A2 (solved with sympy):
    /// c3 = −(d²r2 + 4dr1 + 10r0)/d³, c4 = −(2d²r2 + 7dr1 + 15r0)/d⁴,
    /// c5 = −(d²r2 + 3dr1 + 6r0)/d⁵; without the last condition (B2) the quartic has
    /// c3 = −(dr1 + 4r0)/d³, c4 = −(dr1 + 3r0)/d⁴. Returns p, p′, p″ at x = 1 of both.
    fn quintic(&self, h: f64, derivatives: bool) -> Option<([f64; 3], [f64; 3])> {
        let [a, b] = self.history[..2] else { return None };
        if !derivatives || self.len < 2 || a.orders() < 3 || b.orders() < 3 {
            return None;
        }
        let d = (a.t - b.t) / h;
        let (a0, a1, a2) = (a.phi, a.derivative(1) * h, 0.5 * a.derivative(2) * h * h);
        let (b0, b1, b2) = (b.phi, b.derivative(1) * h, 0.5 * b.derivative(2) * h * h);
        let r0 = b0 - (a0 - a1 * d + a2 * d * d);
        let r1 = b1 - (a1 - 2.0 * a2 * d);
        let r2 = b2 - a2;
        // One division: the powers of 1/d by products.
        let d2 = d * d;
        let i1 = 1.0 / d;
        let (i3, i4) = (i1 * i1 * i1, i1 * i1 * i1 * i1);
        let i5 = i4 * i1;
        let c3 = -(d2 * r2 + 4.0 * d * r1 + 10.0 * r0) * i3;
        let c4 = -(2.0 * d2 * r2 + 7.0 * d * r1 + 15.0 * r0) * i4;
        let c5 = -(d2 * r2 + 3.0 * d * r1 + 6.0 * r0) * i5;
        let at_one = |c3: f64, c4: f64, c5: f64| {
            [
                a0 + a1 + a2 + c3 + c4 + c5,
                a1 + 2.0 * a2 + 3.0 * c3 + 4.0 * c4 + 5.0 * c5,
                2.0 * a2 + 6.0 * c3 + 12.0 * c4 + 20.0 * c5,
            ]
        };
        let q3 = -(d * r1 + 4.0 * r0) * i3;
        let q4 = -(d * r1 + 3.0 * r0) * i4;
        Some((at_one(c3, c4, c5), at_one(q3, q4, 0.0)))
    }

    /// Newton's divided differences of the newest conditions, at most `most`, in the scaled
    /// time x = (t − tc)/scale: the nodes, the coefficients and their number. With
    /// `derivatives`, each sample gives its value and sent derivatives (repeated nodes); else
    /// its value only.
    fn divided_differences(
        &self,
        scale: f64,
        derivatives: bool,
        most: usize,
    ) -> ([f64; MAX_CONDITIONS], [f64; MAX_CONDITIONS], usize) {
        let tc = self.history[0].t;
        let mut z = [0.0; MAX_CONDITIONS];
        // The data of each condition's node, value first: f⁽ʲ⁾·scale^j/j!, the j-th
        // divided difference on a node repeated j + 1 times (in the scaled time).
        let mut data = [[0.0; 3]; MAX_CONDITIONS];
        let (most, mut n) = (most.min(MAX_CONDITIONS), 0);
        let powers = [1.0, scale, 0.5 * scale * scale];
        'fill: for s in self.samples() {
            let orders = if derivatives { s.orders() } else { 1 };
            let node = (s.t - tc) / scale;
            let d = [s.phi, s.derivative(1) * powers[1], s.derivative(2) * powers[2]];
            for _ in 0..orders {
                if n == most {
                    break 'fill;
                }
                z[n] = node;
                data[n] = d;
                n += 1;
            }
        }
        let mut q = [0.0; MAX_CONDITIONS];
        for i in 0..n {
            q[i] = data[i][0];
        }
        let mut c = [0.0; MAX_CONDITIONS];
        c[0] = q[0];
        for j in 1..n {
            for i in (j..n).rev() {
                q[i] = if z[i] == z[i - j] {
                    data[i][j]
                } else {
                    (q[i] - q[i - 1]) / (z[i] - z[i - j])
                };
            }
            c[j] = q[j];
        }
        (z, c, n)
    }

    /// Visits every field in a fixed order, for FMU state save and restore; then
    /// [`check`](Self::check) validates what a reader wrote. The settings (interpolation,
    /// degree) are the caller's to restore.
    pub fn visit(&mut self, v: &mut impl StateVisitor) {
        visit_usize(v, "signal_len", &mut self.len);
        for s in self.history.iter_mut() {
            v.real("signal_t", &mut s.t);
            v.real("signal_phi", &mut s.phi);
            visit_optional(v, "signal_dphi", &mut s.dphi);
            visit_optional(v, "signal_ddphi", &mut s.ddphi);
        }
        for e in self.predicted_error.iter_mut().chain(self.last_error.iter_mut()) {
            v.real("signal_error", e);
        }
        visit_optional(v, "signal_start_slope", &mut self.start_slope);
        visit_optional(v, "signal_start_estimate", &mut self.start_estimate);
    }

    /// Checks a signal a state reader wrote: at most four samples, newest first with
    /// strictly decreasing finite times, finite values, unused slots zero, error estimates
    /// not negative or NaN.
    pub fn check(&self) -> Result<(), String> {
        if self.len > HISTORY {
            return Err(format!("field `signal_len` = {} is out of range: at most 4", self.len));
        }
        let used = self.samples();
        let finite = |x: Option<f64>| x.is_none_or(f64::is_finite);
        if !used.iter().all(|s| s.t.is_finite() && s.phi.is_finite())
            || !used.iter().all(|s| finite(s.dphi) && finite(s.ddphi))
        {
            return Err("field `signal`: sample times and values must be finite".into());
        }
        if !used.windows(2).all(|w| w[0].t > w[1].t) {
            return Err("field `signal`: sample times must decrease, newest first".into());
        }
        if self.history[self.len..].iter().any(|s| *s != Sample::default()) {
            return Err("field `signal`: unused samples must be zero".into());
        }
        if self.predicted_error.iter().chain(&self.last_error).any(|e| e.is_nan() || *e < 0.0) {
            return Err("field `signal_error` must be non-negative".into());
        }
        if !finite(self.start_slope) || !finite(self.start_estimate) {
            return Err(
                "fields `signal_start_slope` and `signal_start_estimate` must be finite".into()
            );
        }
        Ok(())
    }
}

/// An optional real as a flag and a value, 0 when the flag is clear (a reader refuses any
/// other value there: one byte form per state).
fn visit_optional(v: &mut impl StateVisitor, name: &'static str, x: &mut Option<f64>) {
    let mut set = x.is_some();
    v.flag(name, &mut set);
    let mut value = x.unwrap_or(0.0);
    v.real(name, &mut value);
    v.discarded(name, set || value.to_bits() == 0);
    *x = set.then_some(value);
}

fn finite(p: Poly) -> Result<Poly, SignalError> {
    if p.is_finite() {
        Ok(p)
    } else {
        Err(SignalError::NotFinite)
    }
}

/// The Newton form c0 + (x − z0)(c1 + (x − z1)(c2 + …)) and its first two derivatives at x.
fn newton(z: &[f64], c: &[f64], x: f64) -> (f64, f64, f64) {
    let n = c.len();
    let (mut p, mut dp, mut ddp) = (c[n - 1], 0.0, 0.0);
    for k in (0..n - 1).rev() {
        let d = x - z[k];
        ddp = ddp * d + 2.0 * dp;
        dp = dp * d + p;
        p = p * d + c[k];
    }
    (p, dp, ddp)
}

crate::settings::choice_field!(Interpolation);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;

    fn smooth(degree: usize) -> HostSignal {
        HostSignal::new(Interpolation::Smooth, degree)
    }

    /// Feeds `f` at t = 0, h, 2h, … as values or with derivatives, stepping the pieces, and
    /// returns them.
    fn feed(
        sig: &mut HostSignal,
        f: impl Fn(f64) -> Phi,
        h: f64,
        steps: usize,
        derivatives: bool,
    ) -> Vec<Poly> {
        let sample = |t: f64| {
            if derivatives {
                Sample::with_derivatives(t, f(t))
            } else {
                Sample::value(t, f(t).phi)
            }
        };
        let mut piece = sig.start(sample(0.0));
        let mut out = Vec::new();
        for k in 0..steps {
            let t = k as f64 * h;
            piece = sig.plan(sample(t), piece.eval(t), h).unwrap();
            out.push(piece);
        }
        out
    }

    fn sine(t: f64) -> Phi {
        let (s, c) = math::sin_cos(3.0 * t);
        Phi { phi: s, dphi: 3.0 * c, ddphi: -9.0 * s }
    }

    #[test]
    fn newton_form_reproduces_hermite_data() {
        // Nodes 0, 0, 0, −1, −1, −1 with the data of a quintic reproduce it exactly.
        let p = |t: f64| 1.0 + t - 0.5 * t * t + 0.3 * math::powi(t, 3) - 0.2 * math::powi(t, 5);
        let dp = |t: f64| 1.0 - t + 0.9 * t * t - math::powi(t, 4);
        let ddp = |t: f64| -1.0 + 1.8 * t - 4.0 * math::powi(t, 3);
        let mut sig = smooth(3);
        sig.push(Sample { t: -0.1, phi: p(-0.1), dphi: Some(dp(-0.1)), ddphi: Some(ddp(-0.1)) });
        sig.push(Sample { t: 0.0, phi: p(0.0), dphi: Some(dp(0.0)), ddphi: Some(ddp(0.0)) });
        let (target, error) = sig.extrapolate(0.1, true).unwrap();
        assert!((target.phi - p(0.1)).abs() < 1e-14, "{target:?}");
        assert!((target.dphi - dp(0.1)).abs() < 1e-12);
        assert!((target.ddphi - ddp(0.1)).abs() < 1e-10);
        assert!(error[2] > 0.0);
    }

    #[test]
    fn closed_form_quintic_agrees_with_divided_differences() {
        let mut sig = smooth(3);
        sig.push(Sample::with_derivatives(0.3, sine(0.3)));
        sig.push(Sample::with_derivatives(0.37, sine(0.37)));
        let h = 0.05;
        let (p, q) = sig.quintic(h, true).unwrap();
        let (z, c, n) = sig.divided_differences(h, true, MAX_CONDITIONS);
        assert_eq!(n, 6);
        let (p2, q2) = (newton(&z, &c, 1.0), newton(&z[..5], &c[..5], 1.0));
        for (x, y) in
            [(p[0], p2.0), (p[1], p2.1), (p[2], p2.2), (q[0], q2.0), (q[1], q2.1), (q[2], q2.2)]
        {
            assert!((x - y).abs() < 1e-12 * (1.0 + y.abs()), "{x} vs {y}");
        }
    }

    #[test]
    fn even_weights_agree_with_divided_differences() {
        for degree in 0..=3 {
            let mut sig = smooth(degree);
            for k in 0..4 {
                let t = 0.3 + k as f64 * 0.05;
                sig.push(Sample::value(t, sine(t).phi));
            }
            let (p, _) = sig.even(0.05, false).unwrap();
            let n = degree + 1;
            let (z, c, m) = sig.divided_differences(0.05, false, n);
            assert_eq!(m, n);
            let q = newton(&z[..n], &c[..n], 1.0);
            for (a, b) in [(p[0], q.0), (p[1], q.1), (p[2], q.2)] {
                assert!((a - b).abs() < 1e-12, "degree {degree}: {a} vs {b}");
            }
        }
        let mut uneven = smooth(3);
        for t in [0.0, 0.1, 0.25] {
            uneven.push(Sample::value(t, 1.0));
        }
        assert!(uneven.even(0.1, false).is_none());
    }

    #[test]
    fn smooth_pieces_join_in_phi_and_dphi_and_with_derivatives_in_ddphi() {
        // The largest jump of φ″ at a join after the start (the values' slope at t = 0 is
        // added in the first four steps).
        let ddphi_jump = |derivatives: bool, h: f64| {
            let pieces = feed(&mut smooth(3), sine, h, (0.4 / h) as usize, derivatives);
            let mut worst = 0.0f64;
            for (k, w) in pieces.windows(2).enumerate().skip(8) {
                let t = (k + 1) as f64 * h;
                let (a, b) = (w[0].eval(t), w[1].eval(t));
                assert!((a.phi - b.phi).abs() < 1e-14, "{derivatives} φ at {t}");
                assert!((a.dphi - b.dphi).abs() < 1e-12, "{derivatives} φ′ at {t}");
                worst = worst.max((a.ddphi - b.ddphi).abs());
            }
            worst
        };
        assert!(ddphi_jump(true, 0.01) < 1e-9, "with derivatives the joins are C²");
        // With values a C¹ join: φ″ changes by the extrapolation's error in it, O(h²).
        let order = math::log2(ddphi_jump(false, 0.01) / ddphi_jump(false, 0.005));
        assert!((order - 2.0).abs() < 0.3, "order {order}");
    }

    /// The pieces' φ″ against the signal's over a run: its order in h.
    fn ddphi_error(derivatives: bool, h: f64) -> f64 {
        let steps = (1.0 / h).round() as usize;
        let pieces = feed(&mut smooth(3), sine, h, steps, derivatives);
        let mut worst = 0.0f64;
        for (k, p) in pieces.iter().enumerate().skip(8) {
            for j in 1..=4 {
                let t = (k as f64 + j as f64 / 4.0) * h;
                worst = worst.max((p.eval(t).ddphi - sine(t).ddphi).abs());
            }
        }
        worst
    }

    #[test]
    fn smooth_pieces_converge_in_ddphi() {
        // Values: the cubic's target φ″ is O(h²); derivatives: the quintic's, O(h⁴).
        for (derivatives, want) in [(false, 2.0), (true, 4.0)] {
            let order = math::log2(ddphi_error(derivatives, 0.02) / ddphi_error(derivatives, 0.01));
            assert!(order > want - 0.3, "derivatives {derivatives}: order {order}");
        }
        assert!(ddphi_error(true, 0.01) < 1e-3 * ddphi_error(false, 0.01));
    }

    #[test]
    fn a_jump_in_ddphi_is_found_and_restarts_from_the_host() {
        // φ″ = 2 until t = 0.5, then 0: φ and φ′ continuous.
        let f = |t: f64| {
            if t < 0.5 {
                Phi { phi: t * t, dphi: 2.0 * t, ddphi: 2.0 }
            } else {
                Phi { phi: 0.25 + (t - 0.5), dphi: 1.0, ddphi: 0.0 }
            }
        };
        let h = 0.01;
        let pieces = feed(&mut smooth(3), f, h, 80, true);
        // Before the jump the pieces are the parabola, after it the line.
        let at = |k: usize| pieces[k].eval(k as f64 * h);
        assert!((at(30).ddphi - 2.0).abs() < 1e-9);
        assert_eq!(at(50).ddphi, 0.0, "restarted from the host's φ″ at t = 0.5");
        assert!((pieces[60].eval(0.605).ddphi).abs() < 1e-9);
        // Through values the history spans the kink for three steps; then the pieces are
        // the line again.
        let pieces = feed(&mut smooth(3), f, h, 80, false);
        assert!((pieces[56].eval(0.565).ddphi).abs() < 1e-9, "{:?}", pieces[56].eval(0.565));
    }

    #[test]
    fn a_smooth_signal_is_never_taken_for_a_jump() {
        for h in [0.1, 0.01, 1e-3, 1e-4] {
            let mut sig = smooth(3);
            let sample = |t: f64| Sample::with_derivatives(t, sine(t));
            let mut piece = sig.start(sample(0.0));
            for k in 0..200 {
                let t = k as f64 * h;
                let current = piece.eval(t);
                if k > 2 {
                    assert!(!sig.is_jump(&sample(t), &current, h), "h {h} k {k}");
                }
                piece = sig.plan(sample(t), current, h).unwrap();
            }
        }
    }

    #[test]
    fn a_ramp_sent_as_values_gets_its_slope_without_a_kick() {
        // φ = 0.3 + 2t. The first step holds φ; the second catches up towards the slope; at
        // the third sample the slope at the start is known and added as a jump, and the
        // pieces take the catch-up back. The impulse the pieces deliver (φ″ integrated, the
        // jumps left out) is zero in the end: no kick. From the fourth step on the pieces are
        // the ramp.
        let impulse = |f: &dyn Fn(f64) -> Phi, steps: usize| {
            let h = 0.01;
            let pieces = feed(&mut smooth(3), f, h, steps, false);
            let sum: f64 = pieces
                .iter()
                .enumerate()
                .map(|(k, p)| p.eval((k + 1) as f64 * h).dphi - p.eval(k as f64 * h).dphi)
                .sum();
            (sum, pieces)
        };
        let ramp = |t: f64| Phi { phi: 0.3 + 2.0 * t, dphi: 2.0, ddphi: 0.0 };
        let (sum, pieces) = impulse(&ramp, 20);
        assert_eq!(pieces[0].eval(0.005).dphi, 0.0);
        assert!(sum.abs() < 1e-9, "impulse {sum}");
        for (k, p) in pieces.iter().enumerate().skip(4) {
            let t = (k as f64 + 0.5) * h_of(&pieces);
            assert!((p.eval(t).dphi - 2.0).abs() < 1e-9, "step {k}: {:?}", p.eval(t));
            assert!((p.eval(t).phi - ramp(t).phi).abs() < 1e-9, "step {k}: {:?}", p.eval(t));
        }
        // A signal from rest (φ′(0) = 0) gets no jump: the pieces deliver all of its φ′.
        let rest = |t: f64| Phi {
            phi: 1.0 - math::cos(3.0 * t),
            dphi: 3.0 * math::sin(3.0 * t),
            ddphi: 9.0 * math::cos(3.0 * t),
        };
        let (sum, pieces) = impulse(&rest, 20);
        assert!((sum - pieces[19].eval(0.2).dphi).abs() < 1e-12, "no jump for a start at rest");
    }

    fn h_of(pieces: &[Poly]) -> f64 {
        pieces[1].h
    }

    #[test]
    fn taylor_mode_is_the_literal_polynomial() {
        let mut sig = HostSignal::new(Interpolation::Taylor, 3);
        let at = sine(0.2);
        sig.start(Sample::with_derivatives(0.0, sine(0.0)));
        let p = sig.plan(Sample::with_derivatives(0.2, at), Phi::default(), 0.1).unwrap();
        let s = 0.05;
        let want = at.phi + at.dphi * s + 0.5 * at.ddphi * s * s;
        assert!((p.eval(0.25).phi - want).abs() < 1e-15);
    }

    #[test]
    fn plans_that_cannot_be_finite_fail() {
        let mut sig = smooth(3);
        sig.start(Sample::value(0.0, 0.0));
        sig.plan(Sample::value(0.0, 0.0), Phi::default(), 1.0).unwrap();
        assert!(sig.clone().plan(Sample::value(1.0, 1e300), Phi::default(), 1e-200).is_err());
        assert!(sig.plan(Sample::value(1.0, 0.0), Phi::default(), 0.0).is_err());
        assert!(sig.plan(Sample::value(1.0, 0.0), Phi::default(), f64::NAN).is_err());
    }
}
