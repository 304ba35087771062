//! The exact beam ([`ExactBeam`]) as a first-order system y = (q, q̇) of 4n states, its
//! outputs, and the one limit it still has: its centreline must not cross itself.

use super::exact::ExactBeam;
use super::phi::PhiPiece;
use super::systems::Kinematics;
use crate::solver::{DenseParts, OdeSystem, RangeViolation, SecondOrder};
use nalgebra::{DMatrix, DVector, Dyn};

/// The exact beam on a piece of φ.
#[derive(Clone, Copy, Debug)]
pub struct ExactSystem<'a> {
    pub model: &'a ExactBeam,
    pub phi: PhiPiece,
    /// Whether [`check_range`](OdeSystem::check_range) stops a centreline that crosses
    /// itself; without it only a state that is not a number stops.
    pub range_check: bool,
}

/// Where two segments p0–p1 and q0–q1 cross, as the fraction along the first; `None` if
/// they do not (touching ends count as no crossing).
fn crossing(p0: [f64; 2], p1: [f64; 2], q0: [f64; 2], q1: [f64; 2]) -> Option<f64> {
    let d = [p1[0] - p0[0], p1[1] - p0[1]];
    let e = [q1[0] - q0[0], q1[1] - q0[1]];
    let den = d[0] * e[1] - d[1] * e[0];
    if den == 0.0 {
        return None;
    }
    let w = [q0[0] - p0[0], q0[1] - p0[1]];
    let s = (w[0] * e[1] - w[1] * e[0]) / den;
    let t = (w[0] * d[1] - w[1] * d[0]) / den;
    (s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0).then_some(s)
}

impl ExactSystem<'_> {
    pub fn states(&self) -> usize {
        2 * self.model.dofs()
    }

    /// The state of the tip's values: the nodal (w, α) of one cubic w, as
    /// [`ElementsSystem::start`](super::ElementsSystem::start) takes, with its end slope ϑ1
    /// and its end value chosen so that the centreline's tip is at v1 = r_y(l) (by secant
    /// iterations); the rates alike, v̇1 = ṙ_y(l) being linear in them. An error names v1_0
    /// when no such cubic is found (a deflection the beam cannot reach).
    pub fn start(
        &self,
        v1: f64,
        theta1: f64,
        dv1: f64,
        dtheta1: f64,
    ) -> Result<DVector<f64>, String> {
        let beam = &self.model.quadratic.beam;
        let model = self.model;
        let tip_y = |a: f64| model.tip_values(&beam.tip_cubic(a, theta1)).0 - v1;
        let (mut a, mut b) = (v1, v1 + 1e-3 * (v1.abs() + 1e-3));
        let (mut fa, mut fb) = (tip_y(a), tip_y(b));
        for _ in 0..60 {
            if fb.abs() <= 1e-14 * (1.0 + v1.abs()) || fb == fa {
                break;
            }
            let c = b - fb * (b - a) / (fb - fa);
            (a, fa) = (b, fb);
            b = c;
            fb = tip_y(b);
        }
        if fb.is_nan() || fb.abs() > 1e-12 * (1.0 + v1.abs()) {
            return Err(format!(
                "the initial state `v1_0` = {v1:?} with `theta1_0` = {theta1:?}: no cubic shape of \
                 the exact beam ends at that deflection (it must be well inside |v1_0| < l = {:?})",
                beam.l
            ));
        }
        let q = beam.tip_cubic(b, theta1);
        let zero = vec![0.0; q.len()];
        let rate = |a: f64| model.tip(&q, &beam.tip_cubic(a, dtheta1), &zero).v[1];
        let (r0, r1) = (rate(0.0), rate(1.0));
        // At the fold of the reachable deflections the tip's rate no longer follows the shape's.
        if (r1 - r0).abs() < 1e-6 || !(r1 - r0).is_finite() {
            return Err(format!(
                "the initial state `v1_0` = {v1:?}: at the furthest deflection the exact beam \
                 reaches, `dv1_0` = {dv1:?} has no shape rate; start nearer the straight beam"
            ));
        }
        let qd = beam.tip_cubic((dv1 - r0) / (r1 - r0), dtheta1);
        Ok(DVector::from_iterator(self.states(), q.into_iter().chain(qd)))
    }

    /// The motion at (t, y): the tip's, the quarter points', the beam's energy and the loads
    /// at the root by the balance of momentum and of angular momentum of beam and body.
    pub fn kinematics(&self, t: f64, y: &DVector<f64>) -> Kinematics {
        let model = self.model;
        let nq = model.dofs();
        let (q, qd) = y.as_slice().split_at(nq);
        let phi = self.phi.eval(t);
        let mut acc = vec![0.0; nq];
        model.accelerations(&phi, q, qd, &mut acc);
        // One sweep of the Gauss points for the tip, the beam's energy and the root's loads,
        // and the quarter points that are nodes (n a multiple of 4).
        let (points, nodes) = model.gauss_points(q, qd, &acc);
        let tip = nodes[nodes.len() - 1];
        let l = model.params().l;
        let n = nodes.len();
        let at = [1, 2, 3].map(|k| match k * n % 4 {
            0 => nodes[k * n / 4 - 1],
            _ => model.point(q, qd, &acc, k as f64 / 4.0 * l),
        });
        let (t1, p1) = model.beam_energy_at(q, &points);
        let tp = nq - 2;
        Kinematics {
            t,
            v1: tip.r[1],
            theta1: q[tp + 1],
            u2: tip.r[0] - l,
            dv1: tip.v[1],
            dtheta1: qd[tp + 1],
            du2: tip.v[0],
            ddv1: tip.a[1],
            ddtheta1: acc[tp + 1],
            ddu2: tip.a[0],
            phi,
            drift: 0.0,
            beam_energy: Some(t1 + p1),
            node1: [q[0], q[1], qd[0], qd[1], acc[0], acc[1]],
            quarter: [at.map(|p| p.r[1]), at.map(|p| p.v[1]), at.map(|p| p.a[1])],
            rayleigh: model.quadratic.rayleigh(),
            root: Some(model.root_loads_at(&phi, q, qd, &acc, &points, &nodes)),
        }
    }
}

impl OdeSystem<Dyn> for ExactSystem<'_> {
    fn rhs(&self, t: f64, y: &DVector<f64>) -> DVector<f64> {
        let nq = self.model.dofs();
        let mut f = DVector::zeros(y.len());
        let (rates, acc) = f.as_mut_slice().split_at_mut(nq);
        rates.copy_from_slice(&y.as_slice()[nq..]);
        let (q, qd) = y.as_slice().split_at(nq);
        self.model.accelerations(&self.phi.eval(t), q, qd, acc);
        f
    }

    fn residual(&self, t: f64, x: &[f64], v: &[f64], a: &[f64], out: &mut [f64]) -> bool {
        self.model.residual(&self.phi.eval(t), x, v, a, out);
        true
    }

    /// The parts M, C = ∂R/∂q̇ and S = ∂R/∂q at the accelerations of y, dense: S and C by
    /// forward differences of the residual (O(n) a column, so O(n²) in all).
    fn second_order(&self, t: f64, y: &DVector<f64>) -> Option<SecondOrder> {
        let model = self.model;
        let nq = model.dofs();
        let phi = self.phi.eval(t);
        let (q, qd) = y.as_slice().split_at(nq);
        let mut acc = vec![0.0; nq];
        model.accelerations(&phi, q, qd, &mut acc);
        if !acc.iter().all(|x| x.is_finite()) {
            return None;
        }
        let mut parts = DMatrix::zeros(nq, 2 * nq);
        model.residual_differences(&phi, q, qd, &acc, &mut parts);
        Some(SecondOrder::Dense(DenseParts {
            mass: model.mass_matrix(q, phi.phi),
            damping: parts.columns(nq, nq).into_owned(),
            stiffness: parts.columns(0, nq).into_owned(),
        }))
    }

    fn check_range(&self, _t: f64, y: &DVector<f64>) -> Result<(), RangeViolation> {
        let nq = self.model.dofs();
        if let Some(k) = (0..2 * nq).find(|&k| !y[k].is_finite()) {
            return Err(RangeViolation { name: "q", value: y[k], allowed: "a number" });
        }
        if !self.range_check {
            return Ok(());
        }
        let q = &y.as_slice()[..nq];
        // A curve whose tangent turns by less than π cannot cross itself (the loop between
        // two crossing points turns by more than π): only then is the polyline searched.
        let (lo, hi) = self.model.angle_range(q);
        if hi - lo <= std::f64::consts::PI {
            return Ok(());
        }
        let line = self.model.centreline(q);
        for i in 0..line.len() - 1 {
            for j in i + 2..line.len() - 1 {
                let (p0, p1) = (line[i], line[i + 1]);
                if let Some(f) = crossing(p0.1, p1.1, line[j].1, line[j + 1].1) {
                    return Err(RangeViolation {
                        name: "beam",
                        value: p0.0 + f * (p1.0 - p0.0),
                        allowed: "a centreline that does not cross itself (the model has no \
                                  contact; the value is the arc length where it crosses)",
                    });
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Params;

    /// A beam bent into a circular arc (α = c s/l, which the elements hold exactly) crosses
    /// itself once the arc exceeds a full turn, and not before.
    #[test]
    fn an_arc_beyond_a_full_turn_is_out_of_range() {
        let params =
            Params { n_elements: 4, beam: crate::model::BeamModel::Exact, ..Params::default() };
        let model = ExactBeam::new(params).unwrap();
        let l = params.l;
        let state = |c: f64| {
            let mut y = DVector::zeros(16);
            for k in 1..=4 {
                let s = l * k as f64 / 4.0;
                y[2 * k - 2] = c * s * s / (2.0 * l);
                y[2 * k - 1] = c * s / l;
            }
            y
        };
        let phi = PhiPiece::Hold(0.0);
        let sys = ExactSystem { model: &model, phi, range_check: true };
        let pi = std::f64::consts::PI;
        assert!(sys.check_range(0.0, &state(0.9 * pi)).is_ok());
        assert!(sys.check_range(0.0, &state(1.8 * pi)).is_ok());
        let e = sys.check_range(0.0, &state(2.4 * pi)).unwrap_err();
        assert_eq!(e.name, "beam");
        // The tip of a 432° arc comes back over the part 72° behind the start of the circle.
        assert!(e.value > 0.0 && e.value < l / 2.0, "{}", e.value);
        let off = ExactSystem { range_check: false, ..sys };
        assert!(off.check_range(0.0, &state(2.4 * pi)).is_ok());
        let mut nan = state(0.5);
        nan[3] = f64::NAN;
        assert_eq!(off.check_range(0.0, &nan).unwrap_err().name, "q");
    }

    #[test]
    fn segments_cross_only_inside() {
        let c = crossing([0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0]);
        assert_eq!(c, Some(0.5));
        assert_eq!(crossing([0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [2.0, 1.0]), None);
        assert_eq!(crossing([0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]), None);
    }
}
