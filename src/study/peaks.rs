//! A study's metrics from the integrator's dense output: the largest magnitude of each output
//! over every step, found on the step's interpolant, not sampled on a grid (a grid's peak is
//! only a lower bound, and the study needs no `dt_out`).
//!
//! Each step is sampled at its start (the last step's end), middle and end.
//! Where the parabola through the three samples has its vertex inside the step and that
//! vertex could beat the peak so far, the extremum is found on the interpolant by Brent's
//! method; otherwise the samples are the step's extrema. A step of a resolved motion is far
//! shorter than a period, so an extremum inside it is a single hump the parabola sees.

use super::Metric;
use crate::model::{Phi, Reactions};
use crate::sim::Run;

/// What the metrics take from one instant: the tip's motion always, the hinge reactions and
/// the root's moment only if a metric needs them (the energy only at the end).
#[derive(Clone, Copy)]
struct Instant {
    /// φ there: where it jumps (φ″ at the law's t_rot or at a host's sample), a step's end
    /// is not the next one's start.
    phi: Phi,
    v1: f64,
    theta1: f64,
    reactions: Reactions,
    root_moment: f64,
}

/// Which of the costlier outputs the metrics need.
#[derive(Clone, Copy)]
struct Needs {
    reactions: bool,
    root: bool,
}

/// The outputs at `t` inside the run's last step, as far as `needs` asks (the others 0).
fn instant(run: &Run, t: f64, needs: Needs) -> Option<Instant> {
    let k = run.kinematics_at(t).ok()?;
    let model = run.model();
    let reactions = if needs.reactions { k.reactions(model) } else { Reactions::default() };
    let root_moment = if needs.root { k.root_loads(model, &reactions).1 } else { 0.0 };
    Some(Instant { phi: k.phi, v1: k.v1, theta1: k.theta1, reactions, root_moment })
}

/// The signed output whose largest magnitude metric `m` is (`None`: the final energy).
fn signal(m: Metric, o: &Instant, v1_eq: f64) -> Option<f64> {
    Some(match m {
        Metric::ResidualV1 => o.v1 - v1_eq,
        Metric::PeakM => o.reactions.m,
        Metric::PeakMRoot => o.root_moment,
        Metric::PeakN => o.reactions.n,
        Metric::PeakP => o.reactions.p,
        Metric::MaxV1 => o.v1,
        Metric::MaxTheta1 => o.theta1,
        Metric::EnergyFinal => return None,
    })
}

/// Relative tolerance in time of the refined extrema, of the step's length: the value is
/// then exact to about its square (a hump is flat at its top).
const TIME_TOL: f64 = 1e-7;

/// The metrics of one run so far.
pub(super) struct Peaks {
    metrics: Vec<Metric>,
    /// The static deflection residual_v1 is measured from, and the time it starts at.
    v1_eq: f64,
    t_rot: f64,
    /// The run's end, where the final energy is taken.
    t_end: f64,
    /// Per metric: the largest magnitude so far (NaN once an output was NaN; `None` before
    /// the metric's window starts).
    peak: Vec<Option<f64>>,
    energy: f64,
    needs: Needs,
    /// The end of the last step: its time and the outputs there.
    last: Option<(f64, Instant)>,
}

impl Peaks {
    pub(super) fn new(metrics: &[Metric], v1_eq: f64, t_rot: f64, t_end: f64) -> Self {
        let any = |list: &[Metric]| metrics.iter().any(|m| list.contains(m));
        let root = any(&[Metric::PeakMRoot]);
        let reactions = root || any(&[Metric::PeakM, Metric::PeakN, Metric::PeakP]);
        Self {
            needs: Needs { reactions, root },
            metrics: metrics.to_vec(),
            v1_eq,
            t_rot,
            t_end,
            peak: vec![None; metrics.len()],
            energy: f64::NAN,
            last: None,
        }
    }

    /// Takes the step from `from` to `run.t()`.
    pub(super) fn step(&mut self, run: &Run, from: f64) {
        let to = run.t();
        let needs = self.needs;
        let at = |t: f64| instant(run, t, needs);
        // The start is the last step's end, unless φ jumped there (φ″ at the law's t_rot or at
        // a host's sample): the reactions jump with it, and the last end is their left limit,
        // which the last step took.
        let start = match self.last.take() {
            Some((t, o)) if t == from && o.phi == run.piece().eval(from) => Some(o),
            _ => at(from),
        };
        let (mid, end) = (at(0.5 * (from + to)), at(to));
        let (Some(start), Some(mid), Some(end)) = (start, mid, end) else {
            self.peak.iter_mut().for_each(|p| *p = Some(f64::NAN));
            return;
        };
        for k in 0..self.metrics.len() {
            let m = self.metrics[k];
            // residual_v1 counts from t_rot on; the law's steps end there, a host's may not.
            let a = if m == Metric::ResidualV1 { from.max(self.t_rot) } else { from };
            // The final energy is taken below.
            if to < a || m == Metric::EnergyFinal {
                continue;
            }
            let v1_eq = self.v1_eq;
            let g = move |o: &Instant| signal(m, o, v1_eq).unwrap_or(f64::NAN);
            let eval = |t: f64| at(t).map_or(f64::NAN, |o| g(&o));
            let samples = if a == from {
                [(from, g(&start)), (0.5 * (from + to), g(&mid)), (to, g(&end))]
            } else if a == to {
                // The window starts at this step's end (t_rot = t_end): one point.
                [(to, g(&end)); 3]
            } else {
                let c = 0.5 * (a + to);
                [(a, eval(a)), (c, eval(c)), (to, g(&end))]
            };
            self.take(k, samples, eval);
        }
        if self.metrics.contains(&Metric::EnergyFinal)
            && crate::math::same_time(to, self.t_end, 0.0)
        {
            self.energy = run.outputs_at(to).map_or(f64::NAN, |o| o.energy);
        }
        self.last = Some((to, end));
    }

    /// Metric `k` over a step sampled at its ends and middle: its samples, then each sign's
    /// interior hump if the parabola says it may beat the peak.
    fn take(&mut self, k: usize, samples: [(f64, f64); 3], eval: impl Fn(f64) -> f64) {
        let mut best = samples.iter().fold(0.0f64, |b, &(_, v)| nan_max(b, v.abs()));
        let so_far = self.peak[k].unwrap_or(0.0);
        for sign in [1.0, -1.0] {
            let [(a, fa), (m, fm), (b, fb)] = samples.map(|(t, v)| (t, sign * v));
            let curvature = fa - 2.0 * fm + fb;
            if curvature.is_nan() || curvature >= 0.0 {
                continue; // convex (or NaN): the maximum is at an end
            }
            // The vertex of the parabola through the three equally spaced samples.
            let offset = 0.25 * (fa - fb) / curvature * (b - a);
            let vertex = m + offset;
            let predicted = fm - (fb - fa) * (fb - fa) / (8.0 * curvature);
            if vertex <= a || vertex >= b || predicted <= best.max(so_far) {
                continue;
            }
            let top = maximize(|t| sign * eval(t), a, b, vertex, TIME_TOL * (b - a));
            best = nan_max(best, top);
        }
        self.peak[k] = Some(self.peak[k].map_or(best, |p| nan_max(p, best)));
    }

    /// The value of metric `m` (NaN if a run never reached its window).
    pub(super) fn get(&self, m: Metric) -> f64 {
        if m == Metric::EnergyFinal {
            return self.energy;
        }
        self.metrics.iter().position(|&x| x == m).and_then(|k| self.peak[k]).unwrap_or(f64::NAN)
    }
}

/// max that keeps a NaN (`f64::max` drops it): a NaN output must reach the metric and fail
/// the row.
fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// The largest value of `f` on [a, b] near `x`, by Brent's method: parabolic steps through
/// the three best points, safeguarded by golden sections (R. P. Brent, *Algorithms for
/// Minimization without Derivatives*, 1973, ch. 5), until the bracket is `tol` wide. Returns
/// the largest value evaluated (never below f(x)).
fn maximize(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64, x0: f64, tol: f64) -> f64 {
    const GOLDEN: f64 = 0.381_966_011_250_105_1; // (3 − √5)/2
    let (mut x, mut w, mut v) = (x0, x0, x0);
    let fx0 = f(x0);
    if fx0.is_nan() {
        return f64::NAN;
    }
    let (mut fx, mut fw, mut fv) = (fx0, fx0, fx0);
    let (mut d, mut e) = (0.0f64, 0.0f64);
    for _ in 0..60 {
        let mid = 0.5 * (a + b);
        if (x - mid).abs() <= 2.0 * tol - 0.5 * (b - a) {
            break;
        }
        let mut golden = true;
        if e.abs() > tol {
            // A parabola through x, w, v (maximizing: the signs of a minimizer on −f).
            let r = (x - w) * (fv - fx);
            let q0 = (x - v) * (fw - fx);
            let mut p = (x - v) * q0 - (x - w) * r;
            let mut q = 2.0 * (q0 - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            if p.abs() < (0.5 * q * e).abs() && p > q * (a - x) && p < q * (b - x) {
                e = d;
                d = p / q;
                let u = x + d;
                if u - a < 2.0 * tol || b - u < 2.0 * tol {
                    d = if x < mid { tol } else { -tol };
                }
                golden = false;
            }
        }
        if golden {
            e = if x < mid { b - x } else { a - x };
            d = GOLDEN * e;
        }
        let u = if d.abs() >= tol { x + d } else { x + tol.copysign(d) };
        let fu = f(u);
        if fu.is_nan() {
            return f64::NAN;
        }
        if fu >= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu >= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu >= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    fx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brent_finds_the_top_of_a_hump() {
        // sin on [1, 2]: the top at π/2, from a start off it.
        let top = maximize(crate::math::sin, 1.0, 2.0, 1.3, 1e-7);
        assert!((top - 1.0).abs() < 1e-13, "{top}");
        // A hump near the end of the interval, started from the parabola's guess.
        let f = |t: f64| -(t - 0.97) * (t - 0.97) + 0.1 * crate::math::powi(t - 0.97, 3);
        let top = maximize(f, 0.0, 1.0, 0.9, 1e-7);
        assert!(top.abs() < 1e-13, "{top}");
    }
}
