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

/// Appends `x` to `line` in the CSV's number form.
pub fn push_number(line: &mut String, x: f64) {
    let _ = write!(line, "{x:?}");
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
}
