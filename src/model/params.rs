use super::formulation::BeamModel;
use crate::range::Range;
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
    /// Cubic Hermite elements of the beam, 1..=32. Default 1 (the paper's model).
    pub n_elements: usize,
    /// Rayleigh damping of the beam, D = αM_b + βK: α [1/s] and β [s], each ≥ 0. Default 0.
    pub damping_alpha: f64,
    pub damping_beta: f64,
    /// Rayleigh damping given as the ratio ζ ≥ 0 of the first two modes at rest at φ = 0,
    /// instead of α and β. Default 0.
    pub damping_ratio: f64,
    /// The beam's theory: the paper's quadratic cut, or the geometrically exact elastica.
    /// Default quadratic.
    pub beam: BeamModel,
    /// Gravity on the beam itself, along +x (the paper leaves it out). Default false.
    pub beam_gravity: bool,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            l: 2.5,
            ei: 1000.0,
            m: 2.0,
            m2: 12.0,
            j_c: 1.0,
            r: 0.5,
            g: 10.0,
            n_elements: 1,
            damping_alpha: 0.0,
            damping_beta: 0.0,
            damping_ratio: 0.0,
            beam: BeamModel::Quadratic,
            beam_gravity: false,
        }
    }
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

pub(crate) fn check(name: &'static str, value: f64, allowed: Range) -> Result<(), ParamError> {
    if allowed.contains(value) {
        Ok(())
    } else {
        Err(ParamError { name, value, allowed })
    }
}

impl Params {
    /// Checks every range (the settings table checks them too, before; the model checks what
    /// it is given). The mass matrix, which depends on the state too, is checked by
    /// [`BeamBody::check_start`](super::BeamBody::check_start).
    pub fn validate(&self) -> Result<(), ParamError> {
        check("l", self.l, Range::Positive)?;
        check("EI", self.ei, Range::Positive)?;
        check("m", self.m, Range::NonNegative)?;
        check("M2", self.m2, Range::Positive)?;
        check("J_C", self.j_c, Range::NonNegative)?;
        check("r", self.r, Range::NonNegative)?;
        check("g", self.g, Range::Finite)?;
        let elements = Range::Integers(1, super::MAX_ELEMENTS as i64);
        check("n_elements", self.n_elements as f64, elements)?;
        check("damping_alpha", self.damping_alpha, Range::NonNegative)?;
        check("damping_beta", self.damping_beta, Range::NonNegative)?;
        check("damping_ratio", self.damping_ratio, Range::NonNegative)
    }

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
