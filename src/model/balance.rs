//! The energy balance of every formulation: the terms a run checks after each step to tell
//! an integration it can vouch for from one that has gone numerically unstable.
//!
//! Each formulation is Lagrange's equations of a Lagrangian L(q, q̇, t), whose time dependence
//! is the prescribed φ(t). Its Jacobi integral h = q̇·∂L/∂q̇ − L then obeys
//! dh/dt = −∂L/∂t − q̇ᵀD q̇ (E. T. Whittaker, *A Treatise on the Analytical Dynamics of
//! Particles and Rigid Bodies*, §38), D Rayleigh's damping αM_b + βK. With T = T₂ + T₁ + T₀,
//! its parts of degree 2, 1 and 0 in q̇, h = T₂ − T₀ + Π = E − T₁ − 2T₀, E = T + Π the
//! mechanical energy. Only the body depends on φ: with θ = ϑ1 + φ, its centre moves at
//! Ċ = V + r θ̇ (−sin θ, cos θ), V the hinge's velocity, and
//!
//!   ∂L/∂φ′ = M2 r (−sin θ, cos θ)·Ċ + J_C θ̇,
//!   ∂L/∂φ = −M2 r θ̇ (cos θ, sin θ)·Ċ − M2 g r sin θ,
//!   −∂L/∂t = −(∂L/∂φ φ′ + ∂L/∂φ′ φ″),
//!   T₁ = M2 r φ′ (−sin θ, cos θ)·(V + r ϑ̇1 (−sin θ, cos θ)) + J_C ϑ̇1 φ′,
//!   T₀ = ½ (M2 r² + J_C) φ′².
//!
//! None of it needs the accelerations, which the integrator's dense output gives less
//! accurately than the state (the drive's power −M φ′ through the hinge moment M, from the
//! accelerations, left 5 % of the work of a turn of 1000 rad unaccounted at rtol 1e-6). Where:
//! - the reduced formulation (15) and n elements: V = (u̇1, v̇1), u1 = −½qᵀGq; the exact beam:
//!   V = ṙ(l), the tip's velocity;
//! - the DAE formulations: V = (u̇2, v̇1), and the power −N (u̇2 − u̇1) of the hinge force on the
//!   constraint's drift (zero when stabilised), which does need the accelerations;
//! - the linear formulation (16), Lagrange's equations of L₂, the second-order Taylor
//!   expansion of L in (q, q̇) about the straight beam at rest with φ exact: its own h₂ and
//!   −∂L₂/∂t ([`linear`]). The full energy is not its invariant: the linear model's own
//!   equations move it by 2 % of the paper's scene.
//!
//! The tests below check each system's terms against the time derivative of its h along the
//! flow, to 1e-8.

use super::dynamics::BeamBody;
use super::dynamics_n::BeamBodyN;
use super::formulation::Formulation;
use super::kinematics::{pq, u1};
use super::params::Params;
use super::phi::Phi;
use super::systems::{DaeSystem, TwoDofSystem};
use super::systems_exact::ExactSystem;
use super::systems_n::ElementsSystem;
use crate::math;
use nalgebra::allocator::Allocator;
use nalgebra::{DVector, DefaultAllocator, Dim, Dyn, OVector, Vector2, U4, U6};

/// The powers of a formulation's energy balance at one instant [W].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Power {
    /// The power the drive puts in: −∂L/∂t.
    pub drive: f64,
    /// The power the damping takes out, ≥ 0.
    pub dissipation: f64,
}

/// A formulation's Jacobi integral at one instant [J].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// The Jacobi integral h, which changes only by the drive's and the damping's powers.
    pub energy: f64,
    /// The sum of the magnitudes of its parts (kinetic, elastic, the weights'): a scale for
    /// the balance's error.
    pub scale: f64,
}

/// A system whose energy balance a run can check: its powers after every step, its Jacobi
/// integral now and then.
pub trait EnergyBalance<D: Dim>
where
    DefaultAllocator: Allocator<D>,
{
    /// φ at `t` (the piece the system is on).
    fn phi(&self, t: f64) -> Phi;
    /// The powers at a state y with ẏ = `dy` (the integrator's dense output) where φ is `phi`;
    /// only the unprojected DAE's drift term uses `dy`.
    fn power(&self, phi: &Phi, y: &OVector<f64, D>, dy: &OVector<f64, D>) -> Power;
    /// The Jacobi integral at (t, y).
    fn energy(&self, t: f64, y: &OVector<f64, D>) -> Energy;
    /// Whether the powers vanish where φ is `phi`, whatever the state: φ held (φ′ = φ″ = 0),
    /// no damping, no constraint to drift from. Then nothing needs the state there.
    fn passive(&self, phi: &Phi) -> bool;
}

/// φ held: the drive does no work. A host's held φ keeps the round-off of the pieces that
/// joined it (φ′ ≈ 1e-13 rad/s and φ″ ≈ 5e-11 rad/s² after the paper's turn sampled every
/// 10 ms): below 1e-12 rad/s and 1e-9 rad/s² φ counts as held, and a drive's power of at most
/// 1e-12 of the body's angular momentum, and 1e-9 of its inertia, [W] is left out.
fn held(phi: &Phi) -> bool {
    phi.dphi.abs() <= 1e-12 && phi.ddphi.abs() <= 1e-9
}

/// The body's terms of the balance (module docs): T₁, T₀ and −∂L/∂t, for the hinge's velocity
/// `v` and the tip section's angle and rate.
struct Body {
    t1: f64,
    t0: f64,
    drive: f64,
}

fn body(params: &Params, phi: &Phi, theta1: f64, dtheta1: f64, v: [f64; 2]) -> Body {
    let Params { m2, j_c, r, g, .. } = *params;
    let (s, c) = math::sin_cos(theta1 + phi.phi);
    let (w, ddphi) = (phi.dphi, phi.ddphi);
    let dth = dtheta1 + w;
    let cd = [v[0] - r * s * dth, v[1] + r * c * dth];
    let dl_dw = m2 * r * (-s * cd[0] + c * cd[1]) + j_c * dth;
    let dl_dphi = -m2 * r * dth * (c * cd[0] + s * cd[1]) - m2 * g * r * s;
    let cq = [v[0] - r * s * dtheta1, v[1] + r * c * dtheta1];
    Body {
        t1: w * (m2 * r * (-s * cq[0] + c * cq[1]) + j_c * dtheta1),
        t0: 0.5 * (m2 * r * r + j_c) * w * w,
        drive: -(dl_dphi * w + dl_dw * ddphi),
    }
}

/// h = E − T₁ − 2T₀ of the reduced, DAE, n-element and exact formulations, with the beam's
/// energies `beam` (kinetic, potential) and the body's at the tip `q` = (v1, ϑ1), rates `qd`,
/// the hinge at `u` (axial displacement, rate).
fn mechanical_energy(
    model: &BeamBody,
    phi: &Phi,
    q: Vector2<f64>,
    qd: Vector2<f64>,
    u: [f64; 2],
    beam: (f64, f64),
) -> Energy {
    let (t2, p2) = model.body_energies(phi, q, qd, u[0], u[1]);
    let b = body(&model.params, phi, q[1], qd[1], [u[1], qd[0]]);
    Energy {
        energy: beam.0 + beam.1 + t2 + p2 - b.t1 - 2.0 * b.t0,
        scale: beam.0.abs() + beam.1.abs() + t2 + p2.abs(),
    }
}

/// The quantities of the linear model's Lagrangian L₂ that involve the beam: the tip's
/// (v1, ϑ1) and rates, ½q̇ᵀM_b q̇, ½qᵀKq, qᵀGq and qᵀGq̇ (u1 = −½qᵀGq).
struct Forms {
    q: Vector2<f64>,
    qd: Vector2<f64>,
    kinetic: f64,
    elastic: f64,
    gq: f64,
    gqd: f64,
}

/// The linear formulation's balance: L₂'s Jacobi integral and −∂L₂/∂t. With θ ≈ φ + ϑ1
/// expanded to second order and u̇1 = −qᵀGq̇, L₂ = T₂ − Π₂ reads
///
///   T₂ = ½q̇ᵀM_b q̇ + ½J₂(ϑ̇1 + φ′)² + ½M2[v̇1² + 2r c(ϑ̇1 + φ′)v̇1 − 2r s φ′ϑ1 v̇1
///        + 2r s φ′ qᵀGq̇],
///   Π₂ = ½qᵀKq − M2 g(−½qᵀGq + r(c − s ϑ1 − ½c ϑ1²)),
///
/// s, c = sin φ, cos φ, J₂ = J_C + M2 r². T₂'s parts of degree 2, 1 and 0 in q̇ give
/// h₂ = T₂⁽²⁾ − T₂⁽⁰⁾ + Π₂.
fn linear(params: &Params, phi: &Phi, f: &Forms) -> (Energy, f64) {
    let Params { m2, j_c, r, g, .. } = *params;
    let j2 = j_c + m2 * r * r;
    let (s, c) = math::sin_cos(phi.phi);
    let (w, ddphi) = (phi.dphi, phi.ddphi);
    let th = f.q[1];
    let (dv, dth) = (f.qd[0], f.qd[1]);
    let t2 = f.kinetic + 0.5 * j2 * dth * dth + 0.5 * m2 * (dv * dv + 2.0 * r * c * dth * dv);
    let t0 = 0.5 * j2 * w * w;
    let gravity = -m2 * g * (-0.5 * f.gq + r * (c - s * th - 0.5 * c * th * th));
    // ∂L₂/∂φ′ and ∂L₂/∂φ.
    let dl_dw = j2 * (dth + w) + m2 * r * (c * dv - s * th * dv + s * f.gqd);
    let dt_dphi = m2 * r * (-s * dth * dv - s * w * dv - c * w * th * dv + c * w * f.gqd);
    let dpi_dphi = -m2 * g * r * (-s - c * th + 0.5 * s * th * th);
    let energy = Energy {
        energy: t2 - t0 + f.elastic + gravity,
        scale: t2 + t0 + f.elastic + gravity.abs(),
    };
    (energy, -((dt_dphi - dpi_dphi) * w + dl_dw * ddphi))
}

impl TwoDofSystem<'_> {
    fn forms(&self, y: &OVector<f64, U4>) -> Forms {
        let l = self.model.params.l;
        let (q, qd) = (Vector2::new(y[0], y[1]), Vector2::new(y[2], y[3]));
        let (p, qq) = pq(l, q[0], q[1]);
        let gq = Vector2::new(p, l * qq);
        let (kinetic, elastic) = self.model.beam_energies(q, qd);
        Forms { q, qd, kinetic, elastic, gq: gq.dot(&q), gqd: gq.dot(&qd) }
    }
}

impl EnergyBalance<U4> for TwoDofSystem<'_> {
    fn phi(&self, t: f64) -> Phi {
        self.phi.eval(t)
    }

    fn passive(&self, phi: &Phi) -> bool {
        held(phi)
    }

    fn power(&self, phi: &Phi, y: &OVector<f64, U4>, _dy: &OVector<f64, U4>) -> Power {
        let f = self.forms(y);
        let drive = if self.linear {
            linear(&self.model.params, phi, &f).1
        } else {
            // u̇1 = −qᵀGq̇.
            body(&self.model.params, phi, f.q[1], f.qd[1], [-f.gqd, f.qd[0]]).drive
        };
        Power { drive, dissipation: 0.0 }
    }

    fn energy(&self, t: f64, y: &OVector<f64, U4>) -> Energy {
        let phi = self.phi.eval(t);
        let f = self.forms(y);
        if self.linear {
            return linear(&self.model.params, &phi, &f).0;
        }
        let u = [u1(self.model.params.l, f.q[0], f.q[1]), -f.gqd];
        mechanical_energy(self.model, &phi, f.q, f.qd, u, (f.kinetic, f.elastic))
    }
}

impl EnergyBalance<U6> for DaeSystem<'_> {
    fn phi(&self, t: f64) -> Phi {
        self.phi.eval(t)
    }

    fn passive(&self, phi: &Phi) -> bool {
        self.stabilized && held(phi)
    }

    fn power(&self, phi: &Phi, y: &OVector<f64, U6>, dy: &OVector<f64, U6>) -> Power {
        let y = if self.stabilized { self.consistent(y) } else { *y };
        let l = self.model.params.l;
        let (q, qd) = (Vector2::new(y[0], y[1]), Vector2::new(y[3], y[4]));
        let mut drive = body(&self.model.params, phi, q[1], qd[1], [y[5], qd[0]]).drive;
        let (p, qq) = pq(l, q[0], q[1]);
        let drift_rate = y[5] + p * qd[0] + l * qq * qd[1];
        if drift_rate != 0.0 {
            let r = self.model.reactions(phi, q[1], qd[1], dy[4], dy[3], dy[5]);
            drive -= r.n * drift_rate;
        }
        Power { drive, dissipation: 0.0 }
    }

    fn energy(&self, t: f64, y: &OVector<f64, U6>) -> Energy {
        let y = if self.stabilized { self.consistent(y) } else { *y };
        let phi = self.phi.eval(t);
        let (q, qd) = (Vector2::new(y[0], y[1]), Vector2::new(y[3], y[4]));
        let beam = self.model.beam_energies(q, qd);
        mechanical_energy(self.model, &phi, q, qd, [y[2], y[5]], beam)
    }
}

/// The dissipation q̇ᵀDq̇ of the beam in n elements.
fn dissipation(model: &BeamBodyN, qd: &[f64]) -> f64 {
    model.damping_band().map_or(0.0, |d| d.form(qd, qd))
}

impl ElementsSystem<'_> {
    fn forms(&self, q: &[f64], qd: &[f64]) -> Forms {
        let model = self.model;
        let t = model.beam.tip();
        let (kinetic, elastic) = model.beam_energy(q, qd);
        Forms {
            q: Vector2::new(q[t], q[t + 1]),
            qd: Vector2::new(qd[t], qd[t + 1]),
            kinetic,
            elastic,
            gq: model.beam.g.form(q, q),
            gqd: model.beam.g.form(q, qd),
        }
    }

    /// The state, projected onto the constraint when stabilised (into `buf`), as a slice,
    /// with q and q̇ within it.
    fn parts<'a>(
        &self,
        y: &'a DVector<f64>,
        buf: &'a mut Option<DVector<f64>>,
    ) -> (&'a [f64], &'a [f64], &'a [f64]) {
        let y = if self.formulation == Formulation::DaeStabilized {
            buf.insert(self.consistent(y))
        } else {
            y
        };
        let (nq, nc, s) = (self.model.dofs(), self.states() / 2, y.as_slice());
        (s, &s[..nq], &s[nc..nc + nq])
    }
}

impl EnergyBalance<Dyn> for ElementsSystem<'_> {
    fn phi(&self, t: f64) -> Phi {
        self.phi.eval(t)
    }

    fn passive(&self, phi: &Phi) -> bool {
        let drifts = self.formulation == Formulation::Dae;
        !drifts && self.model.damping_band().is_none() && held(phi)
    }

    fn power(&self, phi: &Phi, y: &DVector<f64>, dy: &DVector<f64>) -> Power {
        let model = self.model;
        let mut buf = None;
        let (s, q, qd) = self.parts(y, &mut buf);
        let (nq, nc) = (model.dofs(), self.states() / 2);
        let dissipation = dissipation(model, qd);
        let t = model.beam.tip();
        let g = &model.beam.g;
        if self.formulation == Formulation::Linear {
            let drive = linear(&model.params, phi, &self.forms(q, qd)).1;
            return Power { drive, dissipation };
        }
        // u̇1 = −qᵀGq̇ (G symmetric); the DAE's hinge moves at u̇2.
        let du1 = -g.form(q, qd);
        let du = if self.formulation.is_dae() { s[nc + nq] } else { du1 };
        let mut drive = body(&model.params, phi, q[t + 1], qd[t + 1], [du, qd[t]]).drive;
        let drift_rate = du - du1;
        if drift_rate != 0.0 {
            let d = dy.as_slice();
            let r =
                model.tip.reactions(phi, q[t + 1], qd[t + 1], d[nc + t + 1], d[nc + t], d[nc + nq]);
            drive -= r.n * drift_rate;
        }
        Power { drive, dissipation }
    }

    fn energy(&self, t: f64, y: &DVector<f64>) -> Energy {
        let model = self.model;
        let mut buf = None;
        let (s, q, qd) = self.parts(y, &mut buf);
        let (nq, nc) = (model.dofs(), self.states() / 2);
        let phi = self.phi.eval(t);
        let f = self.forms(q, qd);
        if self.formulation == Formulation::Linear {
            return linear(&model.params, &phi, &f).0;
        }
        let u = if self.formulation.is_dae() { [s[nq], s[nc + nq]] } else { [-0.5 * f.gq, -f.gqd] };
        mechanical_energy(&model.tip, &phi, f.q, f.qd, u, (f.kinetic, f.elastic))
    }
}

impl ExactSystem<'_> {
    /// The tip's position and velocity (no accelerations).
    fn tip_motion(&self, q: &[f64], qd: &[f64]) -> super::exact::PointMotion {
        let zero = [0.0; 2 * super::MAX_ELEMENTS];
        self.model.tip(q, qd, &zero[..q.len()])
    }
}

impl EnergyBalance<Dyn> for ExactSystem<'_> {
    fn phi(&self, t: f64) -> Phi {
        self.phi.eval(t)
    }

    fn passive(&self, phi: &Phi) -> bool {
        self.model.quadratic.damping_band().is_none() && held(phi)
    }

    fn power(&self, phi: &Phi, y: &DVector<f64>, _dy: &DVector<f64>) -> Power {
        let model = self.model;
        let nq = model.dofs();
        let (q, qd) = y.as_slice().split_at(nq);
        let dissipation = dissipation(&model.quadratic, qd);
        let v = self.tip_motion(q, qd).v;
        let drive = body(model.params(), phi, q[nq - 1], qd[nq - 1], v).drive;
        Power { drive, dissipation }
    }

    fn energy(&self, t: f64, y: &DVector<f64>) -> Energy {
        let model = self.model;
        let nq = model.dofs();
        let (q, qd) = y.as_slice().split_at(nq);
        let phi = self.phi.eval(t);
        let motion = self.tip_motion(q, qd);
        let l = model.params().l;
        let (tq, tqd) =
            (Vector2::new(motion.r[1], q[nq - 1]), Vector2::new(motion.v[1], qd[nq - 1]));
        let u = [motion.r[0] - l, motion.v[0]];
        mechanical_energy(&model.quadratic.tip, &phi, tq, tqd, u, model.beam_energy(q, qd))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{BeamModel, ExactBeam, PaperLaw, PhiPiece};
    use crate::solver::OdeSystem;

    /// dE/dt along the flow at (t, y), by central differences of the energy at (t ± ε,
    /// y ± ε f), against the balance's drive − dissipation there: the terms are those of the
    /// equations the system integrates.
    fn check<D: Dim, S: OdeSystem<D> + EnergyBalance<D>>(sys: &S, t: f64, y: &OVector<f64, D>)
    where
        DefaultAllocator: Allocator<D> + Allocator<D, D>,
    {
        check_with(sys, t, y, 1e-4)
    }

    /// [`check`] with the differences' step `eps`.
    fn check_with<D: Dim, S: OdeSystem<D> + EnergyBalance<D>>(
        sys: &S,
        t: f64,
        y: &OVector<f64, D>,
        eps: f64,
    ) where
        DefaultAllocator: Allocator<D> + Allocator<D, D>,
    {
        let f = sys.rhs(t, y);
        let p = sys.power(&sys.phi(t), y, &f);
        let e = sys.energy(t, y);
        let at = |s: f64| sys.energy(t + s, &(y + &f * s)).energy;
        // Fourth order: its error and round-off both below 1e-9 of the scale here.
        let de = (-at(2.0 * eps) + 8.0 * at(eps) - 8.0 * at(-eps) + at(-2.0 * eps)) / (12.0 * eps);
        let want = p.drive - p.dissipation;
        assert!(
            (de - want).abs() <= 1e-8 * e.scale.max(1.0),
            "dE/dt = {de}, drive - dissipation = {want} ({} - {}), scale {}",
            p.drive,
            p.dissipation,
            e.scale
        );
        assert!(e.scale > 0.0 && p.dissipation >= 0.0);
    }

    /// Inside the turn, where φ′ and φ″ are both far from zero.
    const T: f64 = 0.3;

    fn turn() -> PhiPiece {
        PaperLaw::default().piece_from(T)
    }

    /// A turn of 1000 rad in 0.85 s, the body spinning at up to 3700 rad/s.
    #[test]
    fn the_balance_holds_in_a_violent_turn() {
        let model = BeamBody::new(Params::default()).unwrap();
        let law = PaperLaw { phi_end: 1000.0, ..PaperLaw::default() };
        let y = nalgebra::Vector4::new(0.2, 1.9, 0.7, 40.0);
        let sys = TwoDofSystem {
            model: &model,
            phi: law.piece_from(T),
            linear: false,
            range_check: false,
        };
        // The body turns by 0.2 mrad in 1e-7 s: differences of that step.
        check_with(&sys, T, &y, 1e-7);
    }

    #[test]
    fn the_paper_model_s_formulations_balance() {
        let model = BeamBody::new(Params::default()).unwrap();
        let y = nalgebra::Vector4::new(0.2, -0.15, 0.7, 0.4);
        for linear in [false, true] {
            let sys = TwoDofSystem { model: &model, phi: turn(), linear, range_check: true };
            check(&sys, T, &y);
        }
        // Off the constraint, so that the hinge force's power on the drift counts.
        let y = nalgebra::Vector6::new(0.2, -0.15, -0.011, 0.7, 0.4, 0.05);
        let sys = DaeSystem { model: &model, phi: turn(), stabilized: false, range_check: true };
        check(&sys, T, &y);
    }

    /// A state of n elements: a smooth shape with rates, far from the straight beam.
    fn state(n: usize, extra: usize) -> DVector<f64> {
        let nc = 2 * n + extra;
        DVector::from_fn(2 * nc, |k, _| {
            let x = (k % nc + 1) as f64 / nc as f64;
            if k < nc {
                0.2 * x * x
            } else {
                0.5 * x - 0.3 * x * x
            }
        })
    }

    #[test]
    fn the_elements_formulations_balance_with_damping() {
        let params =
            Params { n_elements: 3, damping_alpha: 0.3, damping_beta: 2e-3, ..Params::default() };
        let model = BeamBodyN::new(params).unwrap();
        for formulation in [Formulation::Reduced, Formulation::Linear, Formulation::Dae] {
            let extra = usize::from(formulation.is_dae());
            let sys = ElementsSystem { model: &model, phi: turn(), formulation, range_check: true };
            check(&sys, T, &state(3, extra));
        }
    }

    #[test]
    fn the_exact_beam_balances_with_weight_and_damping() {
        let params = Params {
            n_elements: 3,
            beam: BeamModel::Exact,
            beam_gravity: true,
            damping_ratio: 0.02,
            ..Params::default()
        };
        let model = ExactBeam::new(params).unwrap();
        let sys = ExactSystem { model: &model, phi: turn(), range_check: true };
        check(&sys, T, &state(3, 0));
    }
}
