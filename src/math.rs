//! The elementary functions of the model and the solver, one implementation on every platform.
//!
//! `f64::sin`, `exp`, `powf` and the rest call the C library of the platform the binary runs
//! on: glibc on Linux, msvcrt on Windows, Apple's libm on macOS. Their results differ in the
//! last bits (msvcrt's, under wine, by up to 134 ulp near zero), and a stiff integration
//! amplifies such a difference: the same FMU gave v1 3.4e-6 apart on linux64 and win64 after
//! the paper's 10.2 s. These wrappers call the `libm` crate instead, a Rust port of musl's
//! libm (itself from FreeBSD's msun), compiled into the binary, so every platform computes the
//! same bits from the same inputs.
//!
//! Square roots, `abs`, `floor` and the arithmetic operators are exactly rounded by IEEE 754
//! and need no wrapper. Integer powers do: `f64::powi` with an exponent known only at run time
//! becomes a call to `__powidf2` on Linux and macOS but to the C library's `pow` on Windows
//! (LLVM lowers it so for the Windows targets), so [`powi`] multiplies out itself. `clippy.toml`
//! refuses the `f64` methods that would bypass this module.
#![forbid(unsafe_code)]

/// sin x.
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

/// cos x.
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// (sin x, cos x), with one argument reduction.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

/// eˣ.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// The complementary error function erfc x = 1 − erf x.
#[inline]
pub fn erfc(x: f64) -> f64 {
    libm::erfc(x)
}

/// The natural logarithm of x.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// log₂ x.
#[inline]
pub fn log2(x: f64) -> f64 {
    libm::log2(x)
}

/// xʸ.
#[inline]
pub fn pow(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// xⁿ by binary powering: the multiplications, in the order, of compiler-rt's `__powidf2`
/// (and of LLVM's expansion of a constant exponent), so the bits are those `f64::powi` gives
/// on Linux, on every target.
#[inline]
pub fn powi(x: f64, n: i32) -> f64 {
    let product = powi_const(x, n.unsigned_abs());
    if n < 0 {
        1.0 / product
    } else {
        product
    }
}

/// xⁿ for n ≥ 0, the multiplications of [`powi`]; usable in constants.
#[inline]
pub const fn powi_const(x: f64, n: u32) -> f64 {
    let mut base = x;
    let mut bits = n;
    let mut product = 1.0;
    loop {
        if bits & 1 == 1 {
            product *= base;
        }
        bits >>= 1;
        if bits == 0 {
            break;
        }
        base *= base;
    }
    product
}

/// The angle of the point (x, y) from the positive x axis, in (−π, π].
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// √(x² + y²) without undue overflow or underflow.
#[inline]
pub fn hypot(x: f64, y: f64) -> f64 {
    libm::hypot(x, y)
}

/// Whether two times are the same up to the rounding of a sum such as a host's tc + h or
/// start + n·h: 64 ulps of the largest of |a|, |b| and `scale` (a step size, or 0). The one
/// meaning of "the same time" for the FMI core and the driver.
///
/// An infinite time (a stop that is none, `f64::INFINITY`) is the same as itself only.
pub fn same_time(a: f64, b: f64, scale: f64) -> bool {
    let d = (a - b).abs();
    a == b || d.is_finite() && d <= 64.0 * f64::EPSILON * a.abs().max(b.abs()).max(scale)
}

/// A fixed pseudo-random sequence for tests, uniform in [0, 1): a 64-bit linear congruential
/// generator (Knuth's MMIX constants), the top 53 bits of its state.
#[cfg(test)]
pub(crate) fn test_sequence(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{E, FRAC_PI_2, FRAC_PI_4, LN_2, PI};

    /// Values that every correct implementation returns exactly (or to the correctly rounded
    /// constant), so that a wrong wrapper (arguments swapped, the wrong function) fails.
    #[test]
    fn wrappers_compute_the_functions_they_name() {
        assert_eq!(sin(0.0), 0.0);
        assert_eq!(cos(0.0), 1.0);
        assert!((sin(FRAC_PI_2) - 1.0).abs() <= f64::EPSILON);
        assert!((cos(PI) + 1.0).abs() <= f64::EPSILON);
        let (s, c) = sin_cos(0.3);
        assert_eq!((s, c), (sin(0.3), cos(0.3)));
        assert_eq!(exp(0.0), 1.0);
        assert!((exp(1.0) - E).abs() <= f64::EPSILON * E);
        assert_eq!(ln(1.0), 0.0);
        assert!((ln(2.0) - LN_2).abs() <= f64::EPSILON);
        assert_eq!(log2(1024.0), 10.0);
        assert_eq!(pow(2.0, 10.0), 1024.0);
        assert_eq!(pow(9.0, 0.5), 3.0);
        assert!((atan2(1.0, 1.0) - FRAC_PI_4).abs() <= f64::EPSILON);
        assert!((atan2(1.0, -1.0) - 3.0 * FRAC_PI_4).abs() <= 2.0 * f64::EPSILON);
        assert_eq!(powi(3.0, 0), 1.0);
        assert_eq!(powi(3.0, 5), 243.0);
        assert_eq!(powi(2.0, -3), 0.125);
        assert_eq!(powi(-1.5, 3), -3.375);
        assert_eq!(hypot(3.0, 4.0), 5.0);
        assert_eq!(hypot(3e300, 4e300), 5e300);
    }

    /// The same bits as `f64::powi` where that is compiler-rt's `__powidf2` (a run-time
    /// exponent) or LLVM's expansion (a constant one), on awkward bases.
    #[test]
    #[cfg(not(windows))]
    #[allow(clippy::disallowed_methods)]
    fn powi_has_the_bits_of_std_powi_off_windows() {
        let exponents: Vec<i32> = (-9..=9).chain([17, 31, 64, -40]).collect();
        for k in 1..500 {
            let x = 1.0 + k as f64 * 0.0123456789;
            for &n in &exponents {
                let n = std::hint::black_box(n);
                assert_eq!(powi(x, n).to_bits(), x.powi(n).to_bits(), "{x}^{n}");
            }
            assert_eq!(powi(x, 2).to_bits(), x.powi(2).to_bits());
            assert_eq!(powi(x, 3).to_bits(), x.powi(3).to_bits());
            assert_eq!(powi(x, 5).to_bits(), x.powi(5).to_bits());
        }
    }

    /// libm agrees with glibc, which is correctly rounded in practice, to within two ulps:
    /// the wrappers change bits, not values.
    #[test]
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[allow(clippy::disallowed_methods)]
    fn close_to_the_platform_library() {
        let ulps = |a: f64, b: f64| (a - b).abs() / (f64::EPSILON * a.abs().max(f64::MIN_POSITIVE));
        for k in 1..2000 {
            let x = k as f64 * 0.00731 - 7.0;
            assert!(ulps(sin(x), x.sin()) <= 2.0, "sin {x}");
            assert!(ulps(cos(x), x.cos()) <= 2.0, "cos {x}");
            assert!(ulps(exp(x), x.exp()) <= 2.0, "exp {x}");
            let y = x.abs() + 1e-3;
            assert!(ulps(ln(y), y.ln()) <= 2.0, "ln {y}");
            assert!(ulps(pow(y, 1.0 / 3.0), y.powf(1.0 / 3.0)) <= 2.0, "pow {y}");
            assert!(ulps(atan2(x, 0.7), x.atan2(0.7)) <= 2.0, "atan2 {x}");
        }
    }
}
