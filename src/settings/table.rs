//! The declaration of every setting ([`for_each_setting!`]), the enumerations they choose from,
//! and the constants their entries name.
#![forbid(unsafe_code)]

use super::{Appears, EnumType, Group, Kind, Setting, Value};
use crate::range::Range;
pub const FORMULATION_TYPE: EnumType = EnumType {
    name: "Formulation",
    description: "Which equations of the paper are integrated",
    items: &[
        ("reduced", "eq. (15): hinge constraints exact, 2 DOF, u2 = u1(v1, theta1)"),
        ("dae", "eq. (20)+(21): u2 integrated with the constraint differentiated twice; drifts"),
        ("dae_stabilized", "eq. (20)+(21) projected onto u2 = u1, du2 = du1 after every step"),
        ("linear", "eq. (16): linearised in v1, theta1; phi exact"),
    ],
};

pub const PHI_SOURCE_TYPE: EnumType = EnumType {
    name: "PhiSource",
    description: "Where the hinge angle phi(t) comes from",
    items: &[
        ("input", "the input phi, with its derivatives if the host sends them"),
        ("law", "the paper's law phi0 + phi_end*sin^2(pi*t/(2*t_rot)), then held"),
    ],
};

pub const PHI_INTERPOLATION_TYPE: EnumType = EnumType {
    name: "PhiInterpolation",
    description: "How the input phi is interpolated between communication points",
    items: &[
        (
            "smooth",
            "pieces joined with continuous phi, phi' and phi'' to a target extrapolated from the \
             last values and sent derivatives; jumps of the signal restart the integrator",
        ),
        (
            "taylor",
            "FMI's polynomial phi + phi'*s + phi''*s^2/2 from the sent derivatives over each step \
             (with values only, a cubic to the extrapolated value and slope)",
        ),
    ],
};

pub const RANGE_CHECK_TYPE: EnumType = EnumType {
    name: "RangeCheck",
    description: "What a step does when the state leaves the range of validity of the equations \
                  (the quadratic beam: |v1| <= l, |theta1| <= pi/2, the dae formulation's drift; \
                  the exact beam: a centreline that crosses itself)",
    items: &[
        ("stop", "the run ends there with a message (the FMU: Discard)"),
        ("warn", "a warning, once (the FMU: Warning); the run goes on"),
        ("off", "the run goes on; a state that is not a number still ends it"),
    ],
};

pub const INTEGRATOR_TYPE: EnumType = EnumType {
    name: "Integrator",
    description: "The integrator inside the model",
    items: &[
        (
            "auto",
            "radau for the exact beam, bdf for the paper's theories and the constant-step mode",
        ),
        ("bdf", "variable-order BDF (CVODE's method), orders 1 to max_order, with the stability guard"),
        (
            "radau",
            "Radau IIA of order 5 (RADAU5's method): L-stable, its error estimate blind to the \
             stiff modes it damps; the step follows the motion, not the beam's highest element mode",
        ),
    ],
};

pub const ENERGY_CHECK_TYPE: EnumType = EnumType {
    name: "EnergyCheck",
    description: "What a step does when the energy balance breaks: the energy's change no longer \
                  matches the work of the drive and of the damping within a bound scaled by the \
                  tolerance (numerical instability)",
    items: &[
        ("stop", "the run ends there with a message (the FMU: Discard)"),
        ("warn", "a warning, once (the FMU: Warning); the run goes on"),
        ("off", "no check"),
    ],
};

pub const COLUMNS_TYPE: EnumType = EnumType {
    name: "Columns",
    description: "The columns of a CLI run's CSV",
    items: &[
        ("paper", "time, the tip's motion, phi, the hinge reactions, energy and drift"),
        (
            "beam",
            "those, then the root's bending moment and shear force and the deflection at l/4, \
             l/2, 3l/4",
        ),
        (
            "shape",
            "those, then every node's deflection and slope, v_k and theta_k at x = k*l/n, k = \
             1..n (node n is the tip; the exact beam: at the arc length k*l/n)",
        ),
    ],
};

pub const BEAM_TYPE: EnumType = EnumType {
    name: "Beam",
    description: "The beam's theory",
    items: &[
        (
            "quadratic",
            "the paper's: deflection v(x), the geometric nonlinearity kept to second order (u = -1/2 int v'^2), no axial inertia; valid for |v1| <= l, |theta1| <= pi/2",
        ),
        (
            "exact",
            "the inextensible elastica in the section angle alpha(s), with the beam's axial inertia: valid at any rotation (formulation reduced)",
        ),
    ],
};

/// Every enumeration of the FMU's table, in the order of the model description.
pub const ENUM_TYPES: &[EnumType] = &[
    FORMULATION_TYPE,
    PHI_SOURCE_TYPE,
    PHI_INTERPOLATION_TYPE,
    RANGE_CHECK_TYPE,
    BEAM_TYPE,
    ENERGY_CHECK_TYPE,
    INTEGRATOR_TYPE,
];

const fn real(unit: &'static str) -> Kind {
    Kind::Real { unit: Some(unit) }
}

const NOWHERE: Appears = Appears { fmu: false, study: false, flag: None, study_key: false };
const FMU: Appears = Appears { fmu: true, ..NOWHERE };
/// A number of the model, the law or the initial state: an FMU parameter a study can vary.
const PHYSICAL: Appears = Appears { fmu: true, study: true, ..NOWHERE };

const fn flag(fmu: bool, flag: &'static str) -> Appears {
    Appears { fmu, flag: Some(flag), ..NOWHERE }
}

/// A flag of the CLI and a key of a study file's top level.
const fn study_key(fmu: bool, flag: &'static str) -> Appears {
    Appears { study_key: true, ..self::flag(fmu, flag) }
}

use crate::solver::{ORDER_RANGE, RTOL_RANGE};
use Range::{Finite, Integers, NonNegative, Positive};
use Value::{Bool, Choice, Integer, Real};

/// The one declaration of every setting, in the order of [`Key`]: its key, then the
/// [`Scene`](crate::scene::Scene) field that holds it, its name, kind, range (of a number),
/// default, group, where it appears, its FMU start value where that differs from the default,
/// and its description. Each use passes a macro that takes the list (the X-macro pattern): [`Key`],
/// [`SETTINGS`] and [`Key::group`] here, the scene's `get` and `put` in `scene.rs`. Defaults
/// are the paper's example (§4).
macro_rules! for_each_setting {
    ($use:ident $(, $($arg:tt)*)?) => {
        $use! {
        $($($arg)*)?
        L {
            field: params.l,
            name: "l", kind: real("m"), range: Positive, default: Real(2.5), group: Model,
            appears: PHYSICAL,
            description: "Beam length",
        }
        Ei {
            field: params.ei,
            name: "EI", kind: real("N.m2"), range: Positive, default: Real(1000.0), group: Model,
            appears: PHYSICAL,
            description: "Bending stiffness",
        }
        M {
            field: params.m,
            name: "m", kind: real("kg/m"), range: NonNegative, default: Real(2.0), group: Model,
            appears: PHYSICAL,
            description: "Beam mass per unit length",
        }
        M2 {
            field: params.m2,
            name: "M2", kind: real("kg"), range: Positive, default: Real(12.0), group: Model,
            appears: PHYSICAL,
            description: "Mass of the rigid body",
        }
        JC {
            field: params.j_c,
            name: "J_C", kind: real("kg.m2"), range: NonNegative, default: Real(1.0), group: Model,
            appears: PHYSICAL,
            description: "Moment of inertia of the body about its centre of mass",
        }
        R {
            field: params.r,
            name: "r", kind: real("m"), range: NonNegative, default: Real(0.5), group: Model,
            appears: PHYSICAL,
            description: "Hinge-to-centre-of-mass distance",
        }
        G {
            field: params.g,
            name: "g", kind: real("m/s2"), range: Finite, default: Real(10.0), group: Model,
            appears: PHYSICAL,
            description: "Gravity along the undeformed beam axis (> 0 stretches the beam)",
        }
        NElements {
            field: params.n_elements,
            name: "n_elements", kind: Kind::Integer, range: Integers(1, MAX_ELEMENTS as i64),
            default: Integer(1), group: Model,
            appears: Appears { flag: Some("--elements"), ..PHYSICAL },
            description: "Cubic Hermite elements of the beam: 1 is the paper's model (2 \
coordinates), n has 2n",
        }
        DampingAlpha {
            field: params.damping_alpha,
            name: "damping_alpha", kind: real("1/s"), range: NonNegative, default: Real(0.0),
            group: Model, appears: PHYSICAL,
            description: "Rayleigh damping of the beam: alpha times its mass matrix (0: none, as \
in the paper)",
        }
        DampingBeta {
            field: params.damping_beta,
            name: "damping_beta", kind: real("s"), range: NonNegative, default: Real(0.0),
            group: Model, appears: PHYSICAL,
            description: "Rayleigh damping of the beam: beta times its stiffness matrix (0: none, \
as in the paper)",
        }
        DampingRatio {
            field: params.damping_ratio,
            name: "damping_ratio", kind: Kind::Real { unit: None }, range: NonNegative,
            default: Real(0.0), group: Model, appears: PHYSICAL,
            description: "Rayleigh damping of the beam set by the damping ratio zeta of its own \
first two modes (the cantilever without the body); alpha and beta follow: give \
either this or them",
        }
        Beam {
            field: params.beam,
            name: "beam", kind: Kind::Choice(&BEAM_TYPE), range: Finite, default: Choice(0),
            group: Model, appears: flag(true, "--beam"),
            description: "The beam's theory: quadratic (the paper's cut at second order) or exact \
(the inextensible elastica, valid at any rotation)",
        }
        BeamGravity {
            field: params.beam_gravity,
            name: "beam_gravity", kind: Kind::Bool, range: Finite, default: Bool(false),
            group: Model, appears: FMU,
            description: "Gravity on the beam itself, g per unit length m along +x (the paper \
leaves it out)",
        }
        TRot {
            field: law.t_rot,
            name: "t_rot", kind: real("s"), range: Positive, default: Real(0.85), group: Law,
            appears: PHYSICAL,
            description: "Duration of the turn of the built-in law (phi_source = law)",
        }
        PhiEnd {
            field: law.phi_end,
            name: "phi_end", kind: real("rad"), range: Finite, default: Real(std::f64::consts::PI),
            group: Law, appears: PHYSICAL,
            description: "Angle turned by the built-in law (phi_source = law)",
        }
        Phi0 {
            field: law.phi0,
            name: "phi0", kind: real("rad"), range: Finite, default: Real(0.0), group: Law,
            appears: PHYSICAL,
            description: "Angle of the body at t = 0 under the built-in law, from which it turns \
by phi_end",
        }
        V10 {
            field: initial.v1,
            name: "v1_0", kind: real("m"), range: Finite, default: Real(0.0), group: Initial,
            appears: PHYSICAL,
            description: "Tip deflection at the start",
        }
        Theta10 {
            field: initial.theta1,
            name: "theta1_0", kind: real("rad"), range: Finite, default: Real(0.0), group: Initial,
            appears: PHYSICAL,
            description: "Rotation of the tip section at the start",
        }
        Dv10 {
            field: initial.dv1,
            name: "dv1_0", kind: real("m/s"), range: Finite, default: Real(0.0), group: Initial,
            appears: PHYSICAL,
            description: "Rate of v1 at the start",
        }
        Dtheta10 {
            field: initial.dtheta1,
            name: "dtheta1_0", kind: real("rad/s"), range: Finite, default: Real(0.0),
            group: Initial, appears: PHYSICAL,
            description: "Rate of theta1 at the start",
        }
        Formulation {
            field: formulation,
            name: "formulation", kind: Kind::Choice(&FORMULATION_TYPE), range: Finite,
            default: Choice(0), group: Solver, appears: study_key(true, "--formulation"),
            description: "Equations integrated: reduced (15), dae (20-21), dae_stabilized, linear \
(16)",
        }
        PhiSource {
            field: phi_source,
            name: "phi_source", kind: Kind::Choice(&PHI_SOURCE_TYPE), range: Finite,
            default: Choice(1), group: Input, appears: FMU, fmu_start: Choice(0),
            description: "Source of the hinge angle: the input phi (the FMU's default), or the \
paper's law (the CLI's default; the CLI's input is the law sampled as a host \
would, every dt_comm)",
        }
        PhiInterpolation {
            field: phi_interpolation,
            name: "phi_interpolation", kind: Kind::Choice(&PHI_INTERPOLATION_TYPE), range: Finite,
            default: Choice(0), group: Input, appears: FMU,
            description: "Interpolation of the input phi between communication points: smooth or \
taylor",
        }
        PhiExtrapolation {
            field: phi_extrapolation,
            name: "phi_extrapolation", kind: Kind::Integer, range: Integers(0, 3),
            default: Integer(3), group: Input, appears: FMU,
            description: "Degree of the polynomial through the last input values that gives phi \
over a step when the host sends no derivatives",
        }
        IntermediateStep {
            field: intermediate_step,
            name: "intermediate_step", kind: real("s"), range: NonNegative, default: Real(1e-3),
            group: Input, appears: FMU,
            description: "FMI 3.0 co-simulation, phi_source = input, with the host's \
intermediate-update callback: fmi3DoStep asks the host for phi every \
intermediate_step inside a communication step (the last part up to 1.25 times as \
long); 0 asks only at the communication points",
        }
        InputDerivatives {
            field: input_derivatives,
            name: "input_derivatives", kind: Kind::Bool, range: Finite, default: Bool(false),
            group: Input, appears: NOWHERE,
            description: "CLI, phi_source = input: the emulated host also sends phi' and phi'' at \
every communication point (fmi2SetRealInputDerivatives)",
        }
        DtComm {
            field: dt_comm,
            name: "dt_comm", kind: real("s"), range: Positive, default: Real(0.01), group: Input,
            appears: NOWHERE,
            description: "CLI, phi_source = input: the emulated host's communication step",
        }
        Rtol {
            field: solver.rtol,
            name: "rtol", kind: Kind::Real { unit: None }, range: RTOL_RANGE, default: Real(1e-6),
            group: Solver, appears: study_key(false, "--rtol"),
            description: "Relative tolerance of the integrator (the FMU takes \
fmi2SetupExperiment's)",
        }
        Atol {
            field: solver.atol,
            name: "atol", kind: Kind::Real { unit: None }, range: NonNegative, default: Real(0.0),
            group: Solver, appears: study_key(true, "--atol"),
            description: "Absolute tolerance of the integrator for every state, in its SI unit; 0 \
selects 1e-3 times the relative tolerance (integrator = bdf) or the relative tolerance (radau)",
        }
        MaxOrder {
            field: solver.max_order,
            name: "max_order", kind: Kind::Integer, range: ORDER_RANGE, default: Integer(5),
            group: Solver, appears: flag(true, "--max-order"),
            description: "Highest order of the adaptive BDF",
        }
        FixedStep {
            field: solver.fixed_step,
            name: "fixed_step", kind: real("s"), range: NonNegative, default: Real(0.0),
            group: Solver, appears: flag(true, "--fixed-step"),
            description: "Constant internal step of the paper's fixed-step BDF; 0 selects the \
adaptive BDF",
        }
        FixedOrder {
            field: solver.fixed_order,
            name: "fixed_order", kind: Kind::Integer, range: Integers(0, 5), default: Integer(0),
            group: Solver, appears: flag(true, "--fixed-order"),
            description: "Order of the fixed-step BDF, needs fixed_step > 0; 0 selects order 2",
        }
        StabilityGuard {
            field: solver.stability_guard,
            name: "stability_guard", kind: Kind::Bool, range: Finite, default: Bool(true),
            group: Solver, appears: flag(true, "--stability-guard"),
            description: "Cap the BDF order where an undamped mode would be amplified by BDF3-5",
        }
        Integrator {
            field: solver.integrator,
            name: "integrator", kind: Kind::Choice(&INTEGRATOR_TYPE), range: Finite,
            default: Choice(0), group: Solver, appears: flag(true, "--integrator"),
            description: "The integrator: auto (radau for the exact beam, bdf otherwise), bdf \
(variable order, the stability guard) or radau (Radau IIA of order 5, L-stable: the step \
follows the motion, not the beam's highest mode)",
        }
        RangeCheck {
            field: range_check,
            name: "range_check", kind: Kind::Choice(&RANGE_CHECK_TYPE), range: Finite,
            default: Choice(0), group: Checks, appears: FMU,
            description: "Outside the range of validity (|v1| <= l, |theta1| <= pi/2, ...; the \
exact beam: a centreline that crosses itself): stop, warn or off",
        }
        EnergyCheck {
            field: energy_check,
            name: "energy_check", kind: Kind::Choice(&ENERGY_CHECK_TYPE), range: Finite,
            default: Choice(0), group: Checks, appears: FMU,
            description: "When the energy balance breaks (the energy's change against the work of \
the drive and the damping, after every step, within 100 rtol of the energy \
handled, at most 10 %): the run is numerically unstable; stop, warn or off",
        }
        PhiFilterFrequency {
            field: phi_filter_frequency,
            name: "phi_filter_frequency", kind: real("Hz"), range: Positive,
            default: Real(PHI_FILTER_FREQUENCY), group: Input, appears: FMU,
            description: "Model Exchange with phi_source = input, when the host sets phi but not \
dphi and ddphi: the cut-off frequency of the second-order filter whose states \
give phi, phi' and phi'' from phi (Modelica's Rotational.Sources.Position with \
exact = false); a host that sets dphi and ddphi gets them as it sends them",
        }
        TEnd {
            field: t_end,
            name: "t_end", kind: real("s"), range: Positive, default: Real(10.0), group: Run,
            appears: NOWHERE,
            description: "End time of a CLI run",
        }
        DtOut {
            field: dt_out,
            name: "dt_out", kind: real("s"), range: Positive, default: Real(0.01), group: Run,
            appears: NOWHERE,
            description: "Output step of a CLI run: rows at t = k*dt_out and at t_end",
        }
        MaxRows {
            field: max_rows,
            name: "max_rows", kind: Kind::Integer, range: Integers(1, 1 << 53),
            default: Integer(MAX_ROWS_DEFAULT), group: Run, appears: flag(false, "--max-rows"),
            description: "Most output rows a CLI run or a study case may have (t_end/dt_out + 1); \
a run that would have more is refused before it starts",
        }
        Columns {
            field: columns,
            name: "columns", kind: Kind::Choice(&COLUMNS_TYPE), range: Finite, default: Choice(0),
            group: Run, appears: flag(false, "--columns"),
            description: "Columns of a CLI run's CSV: paper (the default), beam (and the loads at \
the root and the deflection at the quarter points; the FMU has them as outputs), \
or shape (and the nodes' deflections and slopes, for pictures)",
        }
        }
    };
}
pub(crate) use for_each_setting;

/// `Some` of an optional macro argument.
macro_rules! optional {
    () => {
        None
    };
    ($e:expr) => {
        Some($e)
    };
}

/// [`Key`], [`Key::group`] and [`SETTINGS`] from the declaration.
macro_rules! declare {
    ($($key:ident {
        field: $($field:ident).+,
        name: $name:literal, kind: $kind:expr, range: $range:expr, default: $default:expr,
        group: $group:ident, appears: $appears:expr,
        $(fmu_start: $fmu_start:expr,)?
        description: $description:literal $(,)?
    })*) => {
        /// The settings, by row of [`SETTINGS`].
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Key {
            $($key,)*
        }

        impl Key {
            /// The setting's group.
            pub const fn group(self) -> Group {
                match self {
                    $(Key::$key => Group::$group,)*
                }
            }
        }

        /// Every setting, in the order of [`Key`] (`SETTINGS[k].key == k`).
        pub const SETTINGS: &[Setting] = &[$(Setting {
            key: Key::$key,
            name: $name,
            kind: $kind,
            range: $range,
            default: $default,
            description: $description,
            appears: $appears,
            fmu_start: optional!($($fmu_start)?),
        },)*];
    };
}

for_each_setting!(declare);

/// The most elements of the beam (`n_elements`), which sizes the model's arrays on the stack: the
/// beam's highest frequency grows as n², and 32 elements resolve the first modes far beyond the
/// model's other approximations.
pub const MAX_ELEMENTS: usize = 32;

/// The default of `phi_filter_frequency` \[Hz\] (docs/fmu.md, "Model Exchange with φ alone").
pub const PHI_FILTER_FREQUENCY: f64 = 10.0;

/// The default of `max_rows`: a million rows, about 0.2 GB of CSV.
pub const MAX_ROWS_DEFAULT: i64 = 1_000_000;
