//! Typed ranges of numbers: which values a setting or a model parameter allows, and how to say
//! it. One type for the model's checks, the settings table, the FMU's `min`/`max` and the
//! messages, so that the words and the test cannot disagree.
#![forbid(unsafe_code)]

use std::fmt;

/// The allowed values of a number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// Greater than zero and finite.
    Positive,
    /// Zero or more, and finite.
    NonNegative,
    /// Any finite value.
    Finite,
    /// The finite values in [lo, hi].
    Closed(f64, f64),
    /// The integers lo..=hi.
    Integers(i64, i64),
}

impl Range {
    /// Whether `x` lies in the range. NaN and the infinities never do.
    pub fn contains(self, x: f64) -> bool {
        x.is_finite()
            && match self {
                Range::Positive => x > 0.0,
                Range::NonNegative => x >= 0.0,
                Range::Finite => true,
                Range::Closed(lo, hi) => (lo..=hi).contains(&x),
                Range::Integers(lo, hi) => x.fract() == 0.0 && (lo as f64..=hi as f64).contains(&x),
            }
    }

    /// The smallest allowed value, as an FMI `min` attribute: a positive range starts at the
    /// smallest positive normal double, so that a host's own range check refuses 0.
    pub const fn min(self) -> Option<f64> {
        match self {
            Range::Positive => Some(f64::MIN_POSITIVE),
            Range::NonNegative => Some(0.0),
            Range::Finite => None,
            Range::Closed(lo, _) => Some(lo),
            Range::Integers(lo, _) => Some(lo as f64),
        }
    }

    /// The largest allowed value, as an FMI `max` attribute.
    pub const fn max(self) -> Option<f64> {
        match self {
            Range::Closed(_, hi) => Some(hi),
            Range::Integers(_, hi) => Some(hi as f64),
            _ => None,
        }
    }
}

/// The range in words, for "… must be {range}".
impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Range::Positive => f.write_str("positive and finite"),
            Range::NonNegative => f.write_str("non-negative and finite"),
            Range::Finite => f.write_str("finite"),
            Range::Closed(lo, hi) => write!(f, "in [{lo:?}, {hi:?}]"),
            Range::Integers(lo, hi) => write!(f, "an integer in {lo}..={hi}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_hold_what_their_words_say() {
        assert!(Range::Positive.contains(1e-300) && !Range::Positive.contains(0.0));
        assert!(Range::NonNegative.contains(0.0) && !Range::NonNegative.contains(-1e-300));
        assert!(!Range::Finite.contains(f64::NAN) && !Range::Finite.contains(f64::INFINITY));
        assert!(
            Range::Closed(1e-14, 1.0).contains(1.0) && !Range::Closed(1e-14, 1.0).contains(2.0)
        );
        assert!(Range::Integers(1, 5).contains(3.0) && !Range::Integers(1, 5).contains(3.5));
        assert_eq!(Range::Positive.min(), Some(f64::MIN_POSITIVE));
        assert!(Range::Positive.contains(Range::Positive.min().unwrap()));
        assert_eq!(Range::Closed(1e-14, 1.0).to_string(), "in [1e-14, 1.0]");
        assert_eq!(Range::Integers(0, 3).to_string(), "an integer in 0..=3");
    }
}
