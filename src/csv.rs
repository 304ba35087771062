//! The CSV the CLI and the study tool write: headers that name their units, `name [unit]`,
//! and numbers in the shortest form that reads back exactly (Rust's `{:?}` of a double:
//! `0.0085`, `-0.591`, `12.0`, `1e-7`), which spreadsheets and pandas read as written.
#![forbid(unsafe_code)]

use std::fmt::Write;

/// A column's header: `name [unit]`, or `name` without a unit.
pub fn header(name: &str, unit: Option<&str>) -> String {
    match unit {
        Some(u) => format!("{name} [{u}]"),
        None => name.to_string(),
    }
}

/// Appends `x` to `line` in the CSV's number form: std's `{:?}`, written by the `zmij` crate
/// where the two agree. Both give the shortest digits that read back exactly, but
/// - std switches to an exponent below 1e-4 where zmij's layout waits until 1e-5 (`1e-5`
///   against `0.00001`), and zmij writes `1e+16` from 1e16 on;
/// - where a double lies exactly halfway between two shortest forms, std rounds the tie up and
///   zmij to even (`2.9802322387695313e-8`, 2⁻²⁵, against `…312e-8`). A tie needs an exact
///   decimal expansion of 18 digits, so few significant bits: below 1e9, a significand with
///   at least 14 trailing zero bits (m·2⁻ᵖ < 1e9 with m·5ᵖ < 1e18 needs m < 2³⁹).
///
/// Those ranges, the significands with 12 or more trailing zero bits, and NaN and ±∞ go to
/// std, so that a CSV's bytes do not depend on which path wrote them
/// (`tests::fast_path_writes_what_std_writes`). zmij (D. Tolnay's port of V. Zverovich's Żmij,
/// after Schubfach) replaced the `ryu` crate, with the same layout and ties: it formats the
/// paper's 18,015 numbers in 0.70× Ryū's time (632 against 902 µs, best of 30).
pub fn push_number(line: &mut String, x: f64) {
    let a = x.abs();
    let significand = (x.to_bits() & ((1 << 52) - 1)) | (1 << 52);
    let few_bits = significand.trailing_zeros() >= 12;
    if !few_bits && (a < 1e-5 || (1e-4..1e9).contains(&a)) {
        line.push_str(zmij::Buffer::new().format_finite(x));
    } else {
        let _ = write!(line, "{x:?}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_back_exactly_and_headers_name_units() {
        for x in [0.0085, -0.591, 12.0, 1e-7, 0.0, -0.0, 1e300, 5e-324, std::f64::consts::PI] {
            let mut s = String::new();
            push_number(&mut s, x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        let mut s = String::new();
        push_number(&mut s, 0.0085);
        assert_eq!(s, "0.0085");
        assert_eq!(header("v1", Some("m")), "v1 [m]");
        assert_eq!(header("case", None), "case");
    }

    /// The fast path against std's `{:?}` on 4 million doubles: random bit patterns (every
    /// exponent) and numbers of 1 to 17 digits with exponents from 1e-30 to 1e30.
    #[test]
    fn fast_path_writes_what_std_writes() {
        let mut uniform = crate::math::test_sequence(0x5eed);
        let mut word = || (uniform() * (1u64 << 53) as f64) as u64;
        let (mut line, mut checked) = (String::new(), 0);
        for i in 0..4_000_000u64 {
            let bits = (word() << 11) ^ word();
            let x = if i % 2 == 0 {
                f64::from_bits(bits)
            } else {
                let digits = 1 + (bits >> 8) % 17;
                let mantissa = (bits >> 20) % 10u64.pow(digits as u32);
                let exponent = ((bits >> 4) % 61) as i32 - 30 - digits as i32;
                let sign = if bits & 1 == 1 { -1.0 } else { 1.0 };
                sign * mantissa as f64 * crate::math::powi(10.0, exponent)
            };
            line.clear();
            push_number(&mut line, x);
            assert_eq!(line, format!("{x:?}"), "bits {:#x}", x.to_bits());
            checked += 1;
        }
        assert_eq!(checked, 4_000_000);
        // Grids of k·2⁻ᵐ (times of a dyadic step, and the ties: 0.5 + 2⁻¹⁷, 2⁻²⁵), and every
        // power of two.
        for m in 0..=60 {
            let step = crate::math::powi(2.0, -m);
            for k in (1..200_000u64).step_by(7).chain([(1 << 16) + 1, 3 << 20]) {
                for x in [k as f64 * step, -(k as f64) * step, 0.5 + k as f64 * step] {
                    line.clear();
                    push_number(&mut line, x);
                    assert_eq!(line, format!("{x:?}"), "bits {:#x}", x.to_bits());
                }
            }
        }
        // Odd significands of 30 to 40 bits (14 to 24 trailing zeros in the double), scaled
        // into the fast range: where ties first appear (629306376.8476563, 38 bits).
        for bits in 30..=40u32 {
            for _ in 0..2_000 {
                let m = (word() >> (53 - bits)) | (1 << (bits - 1)) | 1;
                for p in bits.saturating_sub(31)..bits + 12 {
                    let x = m as f64 * crate::math::powi(2.0, -(p as i32));
                    line.clear();
                    push_number(&mut line, x);
                    assert_eq!(line, format!("{x:?}"), "bits {:#x}", x.to_bits());
                }
            }
        }
        for e in -1074..=1023 {
            let x = crate::math::powi(2.0, e);
            line.clear();
            push_number(&mut line, x);
            assert_eq!(line, format!("{x:?}"));
        }
        for x in [1e-5, 9.99e-5, 1e-4, 1e9, 1e-6, 0.0, -0.0, f64::NAN, f64::INFINITY, 5e-324] {
            line.clear();
            push_number(&mut line, x);
            assert_eq!(line, format!("{x:?}"));
        }
    }
}
