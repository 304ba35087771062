//! A parameter's axis: a grid of values, or samples of a distribution.

use super::*;

/// How a random parameter is distributed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Distribution {
    Uniform {
        low: f64,
        high: f64,
    },
    /// Normal with mean and standard deviation, truncated to [min, max] where given.
    Normal {
        mean: f64,
        sd: f64,
        min: f64,
        max: f64,
    },
    /// Log-normal with the mean and standard deviation of the value itself.
    LogNormal {
        mean: f64,
        sd: f64,
    },
}

impl Distribution {
    /// The value at probability `u` in (0, 1).
    pub(super) fn quantile(&self, u: f64) -> f64 {
        match *self {
            Distribution::Uniform { low, high } => low + (high - low) * u,
            Distribution::Normal { mean, sd, min, max } => {
                let (lo, hi) = (normal_cdf((min - mean) / sd), normal_cdf((max - mean) / sd));
                // p can round to 0 or 1 where [min, max] lies far in a tail.
                let p = open_unit(lo + (hi - lo) * u);
                (mean + sd * normal_quantile(p)).clamp(min, max)
            }
            Distribution::LogNormal { mean, sd } => {
                let (mu, sigma) = lognormal_mu_sigma(mean, sd);
                crate::math::exp(mu + sigma * normal_quantile(u))
            }
        }
    }

    /// The smallest and largest values it can take.
    fn support(&self) -> (f64, f64) {
        match *self {
            Distribution::Uniform { low, high } => (low, high),
            Distribution::Normal { min, max, .. } => (min, max),
            Distribution::LogNormal { .. } => (f64::MIN_POSITIVE, f64::INFINITY),
        }
    }
}

/// μ and σ of ln X for a log-normal X with the given mean and standard deviation:
/// σ² = ln(1 + sd²/mean²), μ = ln(mean) − σ²/2.
pub(super) fn lognormal_mu_sigma(mean: f64, sd: f64) -> (f64, f64) {
    let s2 = crate::math::ln(1.0 + (sd / mean) * (sd / mean));
    (crate::math::ln(mean) - 0.5 * s2, s2.sqrt())
}

/// Where a parameter's values come from.
#[derive(Clone, Debug, PartialEq)]
pub enum Axis {
    /// `count` points from `start` to `stop`, evenly or (log) geometrically spaced.
    Grid { start: f64, stop: f64, count: u64, log: bool },
    /// The values listed.
    Values(Vec<f64>),
    /// A Latin hypercube sample of `[sampling] samples` values.
    Random(Distribution),
}

impl Axis {
    pub(super) fn grid_len(&self) -> Option<u64> {
        match self {
            Axis::Grid { count, .. } => Some(*count),
            Axis::Values(v) => Some(v.len() as u64),
            Axis::Random(_) => None,
        }
    }

    pub(super) fn grid_value(&self, k: u64) -> f64 {
        match self {
            Axis::Grid { start, stop, count, log } => grid_point(*start, *stop, *count, k, *log),
            Axis::Values(v) => v[k as usize],
            Axis::Random(_) => unreachable!("not a grid"),
        }
    }

    /// The smallest and largest values.
    pub(super) fn bounds(&self) -> (f64, f64) {
        match self {
            Axis::Grid { start, stop, .. } => (start.min(*stop), start.max(*stop)),
            Axis::Values(v) => {
                v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)))
            }
            Axis::Random(d) => d.support(),
        }
    }
}
