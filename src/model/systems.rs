//! The formulations as first-order systems for the integrator, and the outputs they report.
//!
//! State layouts: `TwoDofSystem` (reduced, linear): y = (v1, ϑ1, v̇1, ϑ̇1);
//! `DaeSystem` (dae, dae_stabilized): y = (v1, ϑ1, u2, v̇1, ϑ̇1, u̇2).

use super::dynamics::{BeamBody, Reactions};
use super::kinematics::{pq, u1, u1_accel_bias};
use super::phi::{Phi, PhiPiece};
use crate::solver::{OdeSystem, RangeViolation};
use nalgebra::{SVector, Vector2, Vector3, Vector4, Vector6, U4, U6};

/// The range of validity the integration enforces: beyond it the Ritz model of moderately
/// large deflections (inextensible beam, axial shortening u1 quadratic in v1 and ϑ1) no
/// longer describes a beam, and a run that gets there (buckling under a reversed load, a
/// non-physical jump of φ) stops with [`SolverError::OutOfRange`](crate::solver::SolverError)
/// instead of reporting numbers. The limits are generous, far beyond "moderately large" (the
/// paper's scene reaches |v1| = 0.24·l and |ϑ1| = 0.41 rad): they catch divergence, not
/// loss of accuracy.
pub fn check_deflection(l: f64, v1: f64, theta1: f64) -> Result<(), RangeViolation> {
    if v1.is_nan() || v1.abs() > l {
        return Err(RangeViolation { name: "v1", value: v1, allowed: "|v1| <= l" });
    }
    if theta1.is_nan() || theta1.abs() > std::f64::consts::FRAC_PI_2 {
        return Err(RangeViolation { name: "theta1", value: theta1, allowed: "|theta1| <= pi/2" });
    }
    Ok(())
}

/// With the range check off: only that the coordinates are numbers.
pub(super) fn check_numbers(values: &[(&'static str, f64)]) -> Result<(), RangeViolation> {
    match values.iter().find(|(_, x)| x.is_nan()) {
        Some(&(name, value)) => Err(RangeViolation { name, value, allowed: "a number" }),
        None => Ok(()),
    }
}

/// The unprojected DAE (eq. (20)+(21) with the constraint differentiated twice) satisfies
/// u2 = u1(v1, ϑ1) only up to a drift that grows with time, quadratically once the drive
/// has stopped: 3e-4 m at 10 s, 0.63 m at 500 s and 199 m at 10⁴ s on the paper's scene at
/// rtol 1e-6 (`cargo xtask sweep --group horizon`). Beyond a tenth of the beam's length the
/// state no longer describes a configuration of the beam, and the run stops.
pub fn check_drift(l: f64, drift: f64) -> Result<(), RangeViolation> {
    if drift.is_nan() || drift.abs() > 0.1 * l {
        return Err(RangeViolation {
            name: "drift",
            value: drift,
            allowed: "|u2 - u1(v1, theta1)| <= l/10 (the dae formulation drifts from its \
                      constraint; dae_stabilized does not)",
        });
    }
    Ok(())
}

/// The motion at one instant (SI units): coordinates, rates and accelerations, and φ. The
/// cheap part of the outputs: the reactions and the energy follow from it
/// ([`reactions`](Self::reactions), [`energy`](Self::energy)) when asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    pub t: f64,
    /// Tip deflection [m], tip section rotation [rad], body's axial hinge displacement [m].
    pub v1: f64,
    pub theta1: f64,
    pub u2: f64,
    /// Their rates [m/s, rad/s, m/s].
    pub dv1: f64,
    pub dtheta1: f64,
    pub du2: f64,
    /// Their accelerations [m/s², rad/s², m/s²].
    pub ddv1: f64,
    pub ddtheta1: f64,
    pub ddu2: f64,
    pub phi: Phi,
    /// Constraint residual u2 − u1(v1, ϑ1) [m]: identically 0 where u2 is computed from (21).
    pub drift: f64,
    /// The beam's kinetic and strain energy [J] of a beam in n elements; `None` for the
    /// paper's, whose energy follows from (v1, ϑ1) and their rates.
    pub beam_energy: Option<f64>,
    /// The first node's (x = l/n) deflection and slope, their rates and accelerations (the
    /// tip's with one element), for the loads at the root.
    pub node1: [f64; 6],
    /// The deflection at x = l/4, l/2 and 3l/4 [m], then its rate [m/s] and acceleration
    /// [m/s²] there: `quarter[order][point]`.
    pub quarter: [[f64; 3]; 3],
    /// Rayleigh's (α, β) of the beam in use.
    pub rayleigh: (f64, f64),
    /// The root's shear force and bending moment [N, N·m] where the system computes them
    /// itself (the exact beam); `None`: from `node1` and the reactions.
    pub root: Option<(f64, f64)>,
}

/// The deflection of the paper's single element at l/4, l/2 and 3l/4 for tip values
/// (v1, ϑ1): v = v1(3ξ² − 2ξ³) + lϑ1(ξ³ − ξ²).
fn quarter_points(l: f64, v1: f64, theta1: f64) -> [f64; 3] {
    [0.25, 0.5, 0.75].map(|xi: f64| {
        v1 * (3.0 * xi * xi - 2.0 * xi * xi * xi) + l * theta1 * (xi * xi * xi - xi * xi)
    })
}

impl Kinematics {
    /// The hinge reactions (eq. 19).
    pub fn reactions(&self, model: &BeamBody) -> Reactions {
        model.reactions(&self.phi, self.theta1, self.dtheta1, self.ddtheta1, self.ddv1, self.ddu2)
    }

    /// The total mechanical energy [J].
    pub fn energy(&self, model: &BeamBody) -> f64 {
        let (q, qd) = (Vector2::new(self.v1, self.theta1), Vector2::new(self.dv1, self.dtheta1));
        match self.beam_energy {
            Some(beam) => {
                let (t2, p2) = model.body_energies(&self.phi, q, qd, self.u2, self.du2);
                beam + (t2 + p2)
            }
            None => model.energy(&self.phi, q, qd, self.u2, self.du2),
        }
    }

    /// The shear force and bending moment at the clamp [N, N·m] (`elements::root_loads`),
    /// given the hinge reactions.
    pub fn root_loads(&self, model: &BeamBody, reactions: &Reactions) -> (f64, f64) {
        if let Some(root) = self.root {
            return root;
        }
        let p = &model.params;
        super::elements::root_loads(
            p.n_elements,
            (p.l, p.ei, p.m),
            self.rayleigh,
            self.node1,
            reactions.n,
        )
    }

    /// Everything, the reactions and the energy included.
    pub fn outputs(&self, model: &BeamBody) -> Outputs {
        let reactions = self.reactions(model);
        Outputs {
            t: self.t,
            v1: self.v1,
            theta1: self.theta1,
            u2: self.u2,
            dv1: self.dv1,
            dtheta1: self.dtheta1,
            du2: self.du2,
            phi: self.phi,
            reactions,
            energy: self.energy(model),
            drift: self.drift,
            root: self.root_loads(model, &reactions),
            quarter: self.quarter[0],
        }
    }
}

/// Everything reported at one instant (SI units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outputs {
    pub t: f64,
    /// Tip deflection [m], tip section rotation [rad], body's axial hinge displacement [m].
    pub v1: f64,
    pub theta1: f64,
    pub u2: f64,
    /// Their rates [m/s, rad/s, m/s].
    pub dv1: f64,
    pub dtheta1: f64,
    pub du2: f64,
    pub phi: Phi,
    pub reactions: Reactions,
    /// Total mechanical energy [J].
    pub energy: f64,
    /// Constraint residual u2 − u1(v1, ϑ1) [m]: identically 0 where u2 is computed from (21).
    pub drift: f64,
    /// The shear force [N] and bending moment [N·m] at the clamp.
    pub root: (f64, f64),
    /// The deflection at x = l/4, l/2 and 3l/4 [m].
    pub quarter: [f64; 3],
}

impl Outputs {
    /// Column names and units, in the order of [`values`](Self::values): the FMU's names of
    /// the same outputs.
    pub const COLUMNS: [(&'static str, &'static str); 15] = [
        ("t", "s"),
        ("v1", "m"),
        ("theta1", "rad"),
        ("u2", "m"),
        ("dv1", "m/s"),
        ("dtheta1", "rad/s"),
        ("du2", "m/s"),
        ("phi_applied", "rad"),
        ("dphi_applied", "rad/s"),
        ("ddphi_applied", "rad/s2"),
        ("N", "N"),
        ("P", "N"),
        ("M", "N.m"),
        ("energy", "J"),
        ("drift", "m"),
    ];

    /// The beam's columns, after [`COLUMNS`](Self::COLUMNS) when asked for (`columns =
    /// beam`), in the order of [`beam_values`](Self::beam_values).
    pub const BEAM_COLUMNS: [(&'static str, &'static str); 5] = [
        ("M_root", "N.m"),
        ("Q_root", "N"),
        ("v_quarter", "m"),
        ("v_mid", "m"),
        ("v_three_quarter", "m"),
    ];

    pub fn beam_values(&self) -> [f64; 5] {
        [self.root.1, self.root.0, self.quarter[0], self.quarter[1], self.quarter[2]]
    }

    pub fn values(&self) -> [f64; 15] {
        [
            self.t,
            self.v1,
            self.theta1,
            self.u2,
            self.dv1,
            self.dtheta1,
            self.du2,
            self.phi.phi,
            self.phi.dphi,
            self.phi.ddphi,
            self.reactions.n,
            self.reactions.p,
            self.reactions.m,
            self.energy,
            self.drift,
        ]
    }
}

/// Eq. (15) (`linear = false`) or eq. (16) (`linear = true`).
#[derive(Clone, Copy, Debug)]
pub struct TwoDofSystem<'a> {
    pub model: &'a BeamBody,
    pub phi: PhiPiece,
    pub linear: bool,
    /// Whether [`check_range`](OdeSystem::check_range) checks the range of validity; a
    /// state that is not a number is refused either way.
    pub range_check: bool,
}

impl TwoDofSystem<'_> {
    fn split(y: &Vector4<f64>) -> (Vector2<f64>, Vector2<f64>) {
        (Vector2::new(y[0], y[1]), Vector2::new(y[2], y[3]))
    }

    /// The outputs at (t, y): u2 from (21), reactions from (19) with the hinge's axial
    /// acceleration ü1 = −p v̈1 − l q ϑ̈1 − w.
    pub fn kinematics(&self, t: f64, y: &Vector4<f64>) -> Kinematics {
        let phi = self.phi.eval(t);
        let (q, qd) = Self::split(y);
        let acc = self.model.two_dof_accel(self.linear, &phi, q, qd);
        let l = self.model.params.l;
        let (p, qq) = pq(l, q[0], q[1]);
        Kinematics {
            t,
            v1: q[0],
            theta1: q[1],
            u2: u1(l, q[0], q[1]),
            dv1: qd[0],
            dtheta1: qd[1],
            du2: -p * qd[0] - l * qq * qd[1],
            ddv1: acc[0],
            ddtheta1: acc[1],
            ddu2: -p * acc[0] - l * qq * acc[1] - u1_accel_bias(l, qd[0], qd[1]),
            phi,
            drift: 0.0,
            beam_energy: None,
            node1: [q[0], q[1], qd[0], qd[1], acc[0], acc[1]],
            quarter: [
                quarter_points(l, q[0], q[1]),
                quarter_points(l, qd[0], qd[1]),
                quarter_points(l, acc[0], acc[1]),
            ],
            rayleigh: (0.0, 0.0),
            root: None,
        }
    }

    pub fn outputs(&self, t: f64, y: &Vector4<f64>) -> Outputs {
        self.kinematics(t, y).outputs(self.model)
    }
}

impl OdeSystem<U4> for TwoDofSystem<'_> {
    fn rhs(&self, t: f64, y: &Vector4<f64>) -> Vector4<f64> {
        let (q, qd) = Self::split(y);
        let acc = self.model.two_dof_accel(self.linear, &self.phi.eval(t), q, qd);
        Vector4::new(qd[0], qd[1], acc[0], acc[1])
    }

    fn check_range(&self, _t: f64, y: &Vector4<f64>) -> Result<(), RangeViolation> {
        if !self.range_check {
            return check_numbers(&[("v1", y[0]), ("theta1", y[1])]);
        }
        check_deflection(self.model.params.l, y[0], y[1])
    }
}

/// Eq. (20)+(21), constraint differentiated twice; `stabilized` projects onto the
/// constraint manifold u2 = u1(v1, ϑ1), u̇2 = −p v̇1 − l q ϑ̇1.
#[derive(Clone, Copy, Debug)]
pub struct DaeSystem<'a> {
    pub model: &'a BeamBody,
    pub phi: PhiPiece,
    pub stabilized: bool,
    /// As [`TwoDofSystem::range_check`].
    pub range_check: bool,
}

impl DaeSystem<'_> {
    fn split(y: &Vector6<f64>) -> (Vector3<f64>, Vector3<f64>) {
        (Vector3::new(y[0], y[1], y[2]), Vector3::new(y[3], y[4], y[5]))
    }

    /// The consistent state with the same v1, ϑ1, v̇1, ϑ̇1.
    pub fn consistent(&self, y: &Vector6<f64>) -> Vector6<f64> {
        let l = self.model.params.l;
        let (p, qq) = pq(l, y[0], y[1]);
        let mut out = *y;
        out[2] = u1(l, y[0], y[1]);
        out[5] = -p * y[3] - l * qq * y[4];
        out
    }

    /// The outputs at (t, y), reactions from (19) with ẍ_h = ü2; projected first when
    /// stabilised, so the dense output is consistent too.
    pub fn kinematics(&self, t: f64, y: &Vector6<f64>) -> Kinematics {
        let y = if self.stabilized { self.consistent(y) } else { *y };
        let phi = self.phi.eval(t);
        let (x, xd) = Self::split(&y);
        let acc = self.model.dae_accel(&phi, x, xd);
        Kinematics {
            t,
            v1: x[0],
            theta1: x[1],
            u2: x[2],
            dv1: xd[0],
            dtheta1: xd[1],
            du2: xd[2],
            ddv1: acc[0],
            ddtheta1: acc[1],
            ddu2: acc[2],
            phi,
            drift: x[2] - u1(self.model.params.l, x[0], x[1]),
            beam_energy: None,
            node1: [x[0], x[1], xd[0], xd[1], acc[0], acc[1]],
            quarter: {
                let l = self.model.params.l;
                [
                    quarter_points(l, x[0], x[1]),
                    quarter_points(l, xd[0], xd[1]),
                    quarter_points(l, acc[0], acc[1]),
                ]
            },
            rayleigh: (0.0, 0.0),
            root: None,
        }
    }

    pub fn outputs(&self, t: f64, y: &Vector6<f64>) -> Outputs {
        self.kinematics(t, y).outputs(self.model)
    }
}

impl OdeSystem<U6> for DaeSystem<'_> {
    fn rhs(&self, t: f64, y: &Vector6<f64>) -> Vector6<f64> {
        let (x, xd) = Self::split(y);
        let acc = self.model.dae_accel(&self.phi.eval(t), x, xd);
        Vector6::new(xd[0], xd[1], xd[2], acc[0], acc[1], acc[2])
    }

    fn project(&self, _t: f64, y: &SVector<f64, 6>) -> Option<SVector<f64, 6>> {
        self.stabilized.then(|| self.consistent(y))
    }

    fn check_range(&self, _t: f64, y: &Vector6<f64>) -> Result<(), RangeViolation> {
        if !self.range_check {
            return check_numbers(&[("v1", y[0]), ("theta1", y[1]), ("u2", y[2])]);
        }
        let l = self.model.params.l;
        check_deflection(l, y[0], y[1])?;
        if !self.stabilized {
            check_drift(l, y[2] - u1(l, y[0], y[1]))?;
        }
        Ok(())
    }
}
