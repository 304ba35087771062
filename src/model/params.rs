use super::formulation::BeamModel;
use crate::range::Range;
use crate::settings::{fields_of, Field, Key, Setting, Value};
use std::fmt;

/// Physical parameters (SI units). Their defaults (the paper's example, §4) and ranges are the
/// settings table's (`settings::for_each_setting!`), which `Default` and `validate` take.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Beam length l [m].
    pub l: f64,
    /// Bending stiffness EI [N·m²].
    pub ei: f64,
    /// Beam mass per unit length m [kg/m].
    pub m: f64,
    /// Body mass M2 [kg].
    pub m2: f64,
    /// Body moment of inertia about its centre of mass J_C [kg·m²].
    pub j_c: f64,
    /// Distance from the hinge to the body's centre of mass r [m].
    pub r: f64,
    /// Gravity along +x, the undeformed beam axis, g [m/s²].
    pub g: f64,
    /// Cubic Hermite elements of the beam.
    pub n_elements: usize,
    /// Rayleigh damping of the beam, D = αM_b + βK: α [1/s] and β [s].
    pub damping_alpha: f64,
    pub damping_beta: f64,
    /// Rayleigh damping given as the ratio ζ ≥ 0 of the first two modes at rest at φ = 0,
    /// instead of α and β.
    pub damping_ratio: f64,
    /// The beam's theory: the paper's quadratic cut, or the geometrically exact elastica.
    pub beam: BeamModel,
    /// Gravity on the beam itself, along +x (the paper leaves it out).
    pub beam_gravity: bool,
}

/// A parameter outside its allowed range.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamError {
    /// The parameter's name as the user writes it (`EI`, `t_rot`, …).
    pub name: &'static str,
    pub value: f64,
    pub allowed: Range,
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

/// The value of a part's field against its setting's range: a number outside it is an error
/// naming the setting (choices and switches hold only valid values).
pub(crate) fn check_setting(key: Key, field: &impl Field) -> Result<(), ParamError> {
    let s = Setting::of(key);
    let value = match field.value(s.kind) {
        Value::Real(x) => x,
        Value::Integer(k) => k as f64,
        Value::Choice(_) | Value::Bool(_) => return Ok(()),
    };
    if s.range.contains(value) {
        Ok(())
    } else {
        Err(ParamError { name: s.name, value, allowed: s.range })
    }
}

crate::settings::for_each_setting!(fields_of, params Params);

impl Params {
    /// Whether these are the paper's model: one element of the quadratic beam without damping
    /// or the beam's weight, which the two-coordinate equations of `dynamics.rs` integrate on
    /// the stack.
    pub fn is_paper_model(&self) -> bool {
        self.n_elements == 1
            && self.beam == BeamModel::Quadratic
            && !self.beam_gravity
            && self.damping_alpha == 0.0
            && self.damping_beta == 0.0
            && self.damping_ratio == 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validate_names_the_parameter_and_its_range() {
        assert!(Params::default().validate().is_ok());
        let e = Params { ei: 0.0, ..Params::default() }.validate().unwrap_err();
        assert_eq!((e.name, e.allowed), ("EI", Range::Positive));
        assert!(e.to_string().contains("positive"), "{e}");
        assert!(Params { m: -1.0, ..Params::default() }.validate().is_err());
        assert!(Params { j_c: 0.0, ..Params::default() }.validate().is_ok());
        assert!(Params { l: f64::NAN, ..Params::default() }.validate().is_err());
        assert!(Params { g: -10.0, ..Params::default() }.validate().is_ok());
    }
}
