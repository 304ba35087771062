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

/// Appends `x` to `line` in the CSV's number form: std's `{:?}`, written by the `ryu` crate
/// where the two agree. Both give the shortest digits that read back exactly; std switches to
/// an exponent below 1e-4 where Ryū's layout waits until 1e-5 (`1e-5` against `0.00001`), and
/// above about 1e13 a double can lie exactly halfway between two shortest forms, which the
/// two round apart (`…268.063` against `…268.062`). Those ranges, and NaN and ±∞, go to std,
/// so that a CSV's bytes do not depend on which path wrote them
/// (`tests::ryu_path_writes_what_std_writes`).
pub fn push_number(line: &mut String, x: f64) {
    let a = x.abs();
    if a < 1e-5 || (1e-4..1e9).contains(&a) {
        line.push_str(ryu::Buffer::new().format_finite(x));
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
    fn ryu_path_writes_what_std_writes() {
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
        for x in [1e-5, 9.99e-5, 1e-4, 1e9, 1e-6, 0.0, -0.0, f64::NAN, f64::INFINITY, 5e-324] {
            line.clear();
            push_number(&mut line, x);
            assert_eq!(line, format!("{x:?}"));
        }
    }
}
