use std::fmt;
use std::str::FromStr;

/// The formulations the model offers (paper §2–3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Formulation {
    /// Eq. (15): all hinge constraints satisfied exactly, 2 DOF; u2 = u1(v1, ϑ1) (eq. 21).
    Reduced,
    /// Eq. (20)+(21), the paper's way: the body's axial coordinate u2 integrated with the
    /// constraint (21) differentiated twice. The constraint drifts.
    Dae,
    /// The same DAE with the drift removed by projecting onto the constraint manifold after
    /// every step and at every output.
    DaeStabilized,
    /// Eq. (16): linearised in v1, ϑ1 about the undeformed beam, φ exact.
    Linear,
}

impl Formulation {
    pub const ALL: [Formulation; 4] =
        [Formulation::Reduced, Formulation::Dae, Formulation::DaeStabilized, Formulation::Linear];

    /// The name used on the command line and in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Formulation::Reduced => "reduced",
            Formulation::Dae => "dae",
            Formulation::DaeStabilized => "dae_stabilized",
            Formulation::Linear => "linear",
        }
    }

    /// Whether the state carries u2 and u̇2 (6 states instead of 4).
    pub fn is_dae(self) -> bool {
        matches!(self, Formulation::Dae | Formulation::DaeStabilized)
    }
}

impl fmt::Display for Formulation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Formulation {
    type Err = String;
    /// The names of [`name`](Formulation::name).
    fn from_str(s: &str) -> Result<Self, String> {
        by_name(&Formulation::ALL, Formulation::name, "formulation", s)
    }
}

/// The beam's theory (the setting `beam`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BeamModel {
    /// The paper's: v a graph over x, the geometric nonlinearity cut at second order
    /// (u1 = −½∫v′²), no axial inertia of the beam.
    #[default]
    Quadratic,
    /// The inextensible elastica in the section angle, valid at any rotation, with the
    /// beam's axial inertia (`exact.rs`).
    Exact,
}

impl BeamModel {
    pub const ALL: [BeamModel; 2] = [BeamModel::Quadratic, BeamModel::Exact];

    pub fn name(self) -> &'static str {
        match self {
            BeamModel::Quadratic => "quadratic",
            BeamModel::Exact => "exact",
        }
    }
}

impl FromStr for BeamModel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        by_name(&BeamModel::ALL, BeamModel::name, "beam", s)
    }
}

/// What a run does when the state leaves the region where the equations hold (|v1| ≤ l,
/// |ϑ1| ≤ π/2, and the dae formulation's drift; [`check_deflection`](super::systems)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RangeCheck {
    /// Stop the run there with a message (the default).
    #[default]
    Stop,
    /// Say so once, then go on.
    Warn,
    /// Go on without a word. A state that is not a number still stops the run.
    Off,
}

impl RangeCheck {
    pub const ALL: [RangeCheck; 3] = [RangeCheck::Stop, RangeCheck::Warn, RangeCheck::Off];

    pub fn name(self) -> &'static str {
        match self {
            RangeCheck::Stop => "stop",
            RangeCheck::Warn => "warn",
            RangeCheck::Off => "off",
        }
    }
}

impl FromStr for RangeCheck {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        by_name(&RangeCheck::ALL, RangeCheck::name, "range_check", s)
    }
}

/// The item of `all` whose `name` is `text`; the error names the setting `key` and every item.
pub(crate) fn by_name<T: Copy>(
    all: &[T],
    name: fn(T) -> &'static str,
    key: &str,
    text: &str,
) -> Result<T, String> {
    all.iter().copied().find(|item| name(*item) == text).ok_or_else(|| {
        let names: Vec<&str> = all.iter().map(|item| name(*item)).collect();
        format!("`{key}` = {text}: must be one of {}", names.join(", "))
    })
}

crate::settings::choice_field!(Formulation, BeamModel, RangeCheck);
