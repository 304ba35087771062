use std::fmt;

/// Physical parameters (SI units). Defaults are the paper's example (§4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Beam length l [m]. Positive. Default 2.5.
    pub l: f64,
    /// Bending stiffness EI [N·m²]. Positive. Default 1000.
    pub ei: f64,
    /// Beam mass per unit length m [kg/m]. Non-negative. Default 2.
    pub m: f64,
    /// Body mass M2 [kg]. Positive. Default 12.
    pub m2: f64,
    /// Body moment of inertia about its centre of mass J_C [kg·m²]. Non-negative. Default 1.
    pub j_c: f64,
    /// Distance from the hinge to the body's centre of mass r [m]. Non-negative. Default 0.5.
    pub r: f64,
    /// Gravity along +x, the undeformed beam axis, g [m/s²]. Any finite value. Default 10.
    pub g: f64,
}

impl Default for Params {
    fn default() -> Self {
        Self { l: 2.5, ei: 1000.0, m: 2.0, m2: 12.0, j_c: 1.0, r: 0.5, g: 10.0 }
    }
}

/// A parameter outside its allowed range.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamError {
    /// The parameter's name as the user writes it (`EI`, `t_rot`, …).
    pub name: String,
    pub value: f64,
    /// The allowed range, in words.
    pub allowed: &'static str,
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "parameter `{}` = {:?} is out of range: must be {}",
            self.name, self.value, self.allowed
        )
    }
}

impl std::error::Error for ParamError {}

pub(crate) const POSITIVE: &str = "positive and finite";
pub(crate) const NON_NEGATIVE: &str = "non-negative and finite";
pub(crate) const FINITE: &str = "finite";

pub(crate) fn check(name: &str, value: f64, allowed: &'static str) -> Result<(), ParamError> {
    let ok = match allowed {
        POSITIVE => value.is_finite() && value > 0.0,
        NON_NEGATIVE => value.is_finite() && value >= 0.0,
        _ => value.is_finite(),
    };
    if ok {
        Ok(())
    } else {
        Err(ParamError { name: name.to_string(), value, allowed })
    }
}

impl Params {
    /// The names accepted by [`set`](Self::set), in the paper's notation.
    pub const NAMES: [&'static str; 7] = ["l", "EI", "m", "M2", "J_C", "r", "g"];

    /// Sets the parameter called `name` (one of [`NAMES`](Self::NAMES)) after checking its
    /// range. Returns `Ok(false)` for a name that is not a parameter.
    pub fn set(&mut self, name: &str, value: f64) -> Result<bool, ParamError> {
        let (slot, allowed) = match name {
            "l" => (&mut self.l, POSITIVE),
            "EI" => (&mut self.ei, POSITIVE),
            "m" => (&mut self.m, NON_NEGATIVE),
            "M2" => (&mut self.m2, POSITIVE),
            "J_C" => (&mut self.j_c, NON_NEGATIVE),
            "r" => (&mut self.r, NON_NEGATIVE),
            "g" => (&mut self.g, FINITE),
            _ => return Ok(false),
        };
        check(name, value, allowed)?;
        *slot = value;
        Ok(true)
    }

    /// Checks every range. The mass matrix, which depends on the state too, is checked by
    /// [`BeamBody::new`](super::BeamBody::new).
    pub fn validate(&self) -> Result<(), ParamError> {
        check("l", self.l, POSITIVE)?;
        check("EI", self.ei, POSITIVE)?;
        check("m", self.m, NON_NEGATIVE)?;
        check("M2", self.m2, POSITIVE)?;
        check("J_C", self.j_c, NON_NEGATIVE)?;
        check("r", self.r, NON_NEGATIVE)?;
        check("g", self.g, FINITE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_checks_range_and_names_the_parameter() {
        let mut p = Params::default();
        assert_eq!(p.set("EI", 2000.0), Ok(true));
        assert_eq!(p.ei, 2000.0);
        let e = p.set("EI", 0.0).unwrap_err();
        assert_eq!(e.name, "EI");
        assert!(e.to_string().contains("positive"), "{e}");
        assert!(p.set("m", -1.0).is_err());
        assert!(p.set("J_C", 0.0).is_ok());
        assert!(p.set("l", f64::NAN).is_err());
        assert!(p.set("g", -10.0).is_ok());
        assert_eq!(p.set("nope", 1.0), Ok(false));
        assert_eq!(p.ei, 2000.0, "a rejected value leaves the parameter unchanged");
    }
}
