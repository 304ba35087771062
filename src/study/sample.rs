//! The numbers behind a study's cases: grid points, and Latin hypercube samples of the random
//! parameters, each a pure function of (seed, parameter name, sample index). Any chunk of a
//! study computes its cases alone, and gets the same values as a run of the whole study.

use crate::math;
use std::f64::consts::{PI, SQRT_2};

/// SplitMix64's output function: a bijective mixer of 64-bit words (Steele, Lea & Flood,
/// "Fast splittable pseudorandom number generators", OOPSLA 2014; the constants are those of
/// Vigna's public-domain `splitmix64.c`).
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// SplitMix64's increment, the golden ratio in 64 bits.
const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// A hash of three words.
fn hash3(a: u64, b: u64, c: u64) -> u64 {
    mix(mix(mix(a.wrapping_add(GOLDEN)) ^ b.wrapping_add(GOLDEN.wrapping_mul(2))) ^ c)
}

/// 64-bit FNV-1a of a name: the key of a parameter's samples, so that adding or removing
/// another parameter leaves its column unchanged.
pub(crate) fn name_key(name: &str) -> u64 {
    crate::hash::fnv1a_64(name.as_bytes())
}

/// A pseudo-random permutation of 0..n, evaluated one element at a time: a balanced Feistel
/// network on the smallest domain of 4^k ≥ n elements, with cycle walking back into 0..n
/// (Black & Rogaway, "Ciphers with arbitrary finite domains", CT-RSA 2002). A Feistel
/// network is a bijection whatever its round function, and cycle walking keeps that on
/// 0..n; the domain is below 4n, so a walk takes fewer than four rounds on average.
#[derive(Clone, Copy, Debug)]
pub struct Permutation {
    n: u64,
    half_bits: u32,
    key: u64,
}

impl Permutation {
    const ROUNDS: u64 = 6;

    /// The permutation of 0..n keyed by `key`; `n` ≥ 1.
    pub fn new(n: u64, key: u64) -> Self {
        assert!(n >= 1, "a permutation of no elements");
        let bits = 64 - (n - 1).leading_zeros();
        Self { n, half_bits: bits.div_ceil(2).max(1), key }
    }

    /// The image of `x` < n.
    pub fn apply(&self, x: u64) -> u64 {
        debug_assert!(x < self.n);
        let mut y = x;
        loop {
            y = self.feistel(y);
            if y < self.n {
                return y;
            }
        }
    }

    fn feistel(&self, x: u64) -> u64 {
        let mask = (1u64 << self.half_bits) - 1;
        let (mut left, mut right) = (x >> self.half_bits, x & mask);
        for round in 0..Self::ROUNDS {
            let f = hash3(self.key, round, right) & mask;
            (left, right) = (right, left ^ f);
        }
        (left << self.half_bits) | right
    }
}

/// The Latin hypercube coordinate of sample `s` of `n` for the parameter keyed `key`, in
/// (0, 1): the stratum `perm(s)` of n equal strata, and a uniform point inside it. Each
/// stratum holds exactly one of the n samples (McKay, Beckman & Conover, Technometrics 21,
/// 1979).
pub fn latin_hypercube(seed: u64, key: u64, s: u64, n: u64) -> f64 {
    let perm = Permutation::new(n, hash3(seed, key, 0x5354_5241_5441)); // "STRATA"
    let stratum = perm.apply(s);
    // 52 random bits, centred: the jitter is in [2⁻⁵³, 1 − 2⁻⁵³], exactly. The sum can still
    // round to n in the last stratum of a large n, so the result is kept inside (0, 1).
    let bits = hash3(seed, key, s.wrapping_add(1).wrapping_mul(GOLDEN)) >> 12;
    let jitter = (bits as f64 + 0.5) / (1u64 << 52) as f64;
    open_unit((stratum as f64 + jitter) / n as f64)
}

/// `u` moved into the open interval (0, 1): [f64::MIN_POSITIVE, 1 − 2⁻⁵³].
pub fn open_unit(u: f64) -> f64 {
    u.clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON / 2.0)
}

/// The standard normal distribution function Φ(x) = erfc(−x/√2)/2.
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * math::erfc(-x / SQRT_2)
}

/// The standard normal quantile Φ⁻¹(p), p in (0, 1): Acklam's rational approximation
/// (relative error below 1.15e-9; P. J. Acklam, "An algorithm for computing the inverse
/// normal cumulative distribution function", 2003, whose coefficients these are), then one
/// step of Halley's method on Φ(x) − p, which brings it to a few ulps.
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    const P_LOW: f64 = 0.02425;
    debug_assert!(p > 0.0 && p < 1.0);
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    let x = if p < P_LOW {
        tail((-2.0 * math::ln(p)).sqrt())
    } else if p > 1.0 - P_LOW {
        -tail((-2.0 * math::ln(1.0 - p)).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    };
    // Halley: u = (Φ(x) − p)/φ(x), x ← x − u/(1 + x·u/2).
    let e = normal_cdf(x) - p;
    let u = e * (2.0 * PI).sqrt() * math::exp(0.5 * x * x);
    x - u / (1.0 + 0.5 * x * u)
}

/// Point `k` of `count` from `start` to `stop`, evenly spaced or (with `log`) in geometric
/// progression; the last point is `stop` exactly.
pub fn grid_point(start: f64, stop: f64, count: u64, k: u64, log: bool) -> f64 {
    if count == 1 || k == 0 {
        return start;
    }
    if k == count - 1 {
        return stop;
    }
    let frac = k as f64 / (count - 1) as f64;
    if log {
        start * math::pow(stop / start, frac)
    } else {
        start + (stop - start) * frac
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutations_are_bijections_for_every_size() {
        for n in [1u64, 2, 3, 4, 5, 7, 16, 17, 100, 255, 256, 257, 1000, 4097] {
            for key in [0u64, 1, 0xdead_beef] {
                let p = Permutation::new(n, key);
                let mut seen = vec![false; n as usize];
                for x in 0..n {
                    let y = p.apply(x);
                    assert!(y < n, "n = {n}: {x} -> {y}");
                    assert!(!seen[y as usize], "n = {n}: {y} hit twice");
                    seen[y as usize] = true;
                }
            }
        }
    }

    #[test]
    fn permutations_differ_by_key_and_are_not_the_identity() {
        let (a, b) = (Permutation::new(1000, 1), Permutation::new(1000, 2));
        let fixed_a = (0..1000).filter(|&x| a.apply(x) == x).count();
        let same = (0..1000).filter(|&x| a.apply(x) == b.apply(x)).count();
        // A random permutation has one fixed point on average, and two independent ones
        // agree at one place on average.
        assert!(fixed_a < 10, "{fixed_a} fixed points");
        assert!(same < 10, "{same} common images");
    }

    #[test]
    fn latin_hypercube_coordinates_stay_inside_the_open_unit_interval() {
        // The last stratum of a large n, where (n − 1 + jitter)/n can round to 1.
        let n = 1u64 << 40;
        for s in 0..2000 {
            let u = latin_hypercube(9, 1, s, n);
            assert!(u > 0.0 && u < 1.0, "{u}");
        }
        assert_eq!(open_unit(1.0), 1.0 - f64::EPSILON / 2.0);
        assert!(normal_quantile(open_unit(1.0)).is_finite());
        assert!(normal_quantile(open_unit(0.0)).is_finite());
    }

    #[test]
    fn latin_hypercube_puts_one_sample_in_each_stratum() {
        let n = 997;
        let mut hit = vec![0; n as usize];
        for s in 0..n {
            let u = latin_hypercube(42, name_key("EI"), s, n);
            assert!(u > 0.0 && u < 1.0);
            hit[(u * n as f64) as usize] += 1;
        }
        assert!(hit.iter().all(|&c| c == 1));
        // Another parameter's column is another permutation.
        let same = (0..n)
            .filter(|&s| {
                let a = latin_hypercube(42, name_key("EI"), s, n);
                let b = latin_hypercube(42, name_key("M2"), s, n);
                (a * n as f64) as u64 == (b * n as f64) as u64
            })
            .count();
        assert!(same < 10, "{same}");
    }

    #[test]
    fn normal_quantile_inverts_the_distribution_function() {
        // Φ⁻¹ at reference points (Abramowitz & Stegun, table 26.5; 1.959963984540054 etc.).
        let cases = [
            (0.5, 0.0),
            (0.975, 1.959_963_984_540_054),
            (0.99, 2.326_347_874_040_841),
            (0.999, 3.090_232_306_167_813),
            (0.025, -1.959_963_984_540_054),
            (0.841_344_746_068_542_9, 1.0),
        ];
        for (p, x) in cases {
            let got = normal_quantile(p);
            assert!((got - x).abs() <= 1e-14 * x.abs().max(1.0), "Φ⁻¹({p}) = {got}, not {x}");
        }
        for k in 1..2000 {
            let p = k as f64 / 2000.0;
            let x = normal_quantile(p);
            // The rounding of x alone moves Φ(x) by φ(x)·|x|·ε ≤ (1 + x²)·min(p, 1 − p)·ε.
            let tol = 8.0 * f64::EPSILON * (1.0 + x * x) * p.min(1.0 - p) + 2.0 * f64::EPSILON;
            assert!((normal_cdf(x) - p).abs() <= tol, "p = {p}: {}", normal_cdf(x) - p);
        }
        for p in [1e-300, 1e-100, 1e-12, 1e-6] {
            let x = normal_quantile(p);
            assert!(((normal_cdf(x) - p) / p).abs() < 1e-12, "p = {p}: x = {x}");
        }
    }

    #[test]
    fn grids_end_exactly_at_their_bounds() {
        assert_eq!(grid_point(0.4, 2.0, 5, 0, false), 0.4);
        assert_eq!(grid_point(0.4, 2.0, 5, 4, false), 2.0);
        assert!((grid_point(0.4, 2.0, 5, 2, false) - 1.2).abs() < 1e-15);
        assert!((grid_point(1.0, 1000.0, 4, 1, true) - 10.0).abs() < 1e-14);
        assert_eq!(grid_point(1.0, 1000.0, 4, 3, true), 1000.0);
        assert_eq!(grid_point(3.0, 9.0, 1, 0, false), 3.0);
    }
}
