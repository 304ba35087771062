//! The collocation system of a mechanical system y = (x, ẋ), M(x)ẍ = F(t, x, ẋ), solved for
//! the stages' velocities through its residual R = Mẍ − F ([`OdeSystem::residual`]) instead
//! of f = (ẋ, M⁻¹F): the exact beam's R costs O(n) where f needs its dense M and a
//! Cholesky.
//!
//! With V_i = ẋ_n + Zv_i the stage velocities, the positions and accelerations follow
//! linearly: X_i = x_n + c_i h ẋ_n + h Σ_j a_ij Zv_j and Ẍ_i = Σ_j (A⁻¹)_ij Zv_j / h, and the
//! stages solve R(X_i, V_i, Ẍ_i) = 0. Simplified Newton at the Jacobian's point, with
//! δX = hA δV and δẌ = A⁻¹δV/h, has the matrix A⁻¹/h ⊗ M + I ⊗ C + hA ⊗ S; in W = T⁻¹Zv it
//! splits like the first-order one, into (M + γC + γ²S) for γ = h/μ and for
//! γ = h/(α − iβ): the same m×m factorisations (linear.rs). The solution is the first-order
//! collocation's (the same equations, eliminated differently), so the error estimate and
//! the dense output are unchanged.

use super::linear::Jacobian;
use super::tableau::{butcher_and_inverse, C, T, TI};
use super::*;

type Stage = Vec<f64>;

impl<D: Dim> Radau<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// [`collocate`](Self::collocate) by the residual, where the system gives one and the
    /// Jacobian is structured; `None` otherwise.
    pub(super) fn collocate_mechanical<S: OdeSystem<D>>(
        &mut self,
        sys: &S,
        h: f64,
        z: &mut Stages<D>,
    ) -> Option<Result<(usize, f64), NewtonFail>> {
        if !self.residual_form || !matches!(self.jac, Some(Jacobian::Second(_))) {
            return None;
        }
        let factors = self.factors.as_ref()?;
        let m = self.y.len() / 2;
        let (x0, v0) = self.y.as_slice().split_at(m);
        let (a, ai) = butcher_and_inverse();
        let weights = self.scale(&self.y);
        let wv = &weights.as_slice()[m..];
        let r = self.internal_tolerance().0;
        // A tenth of the first-order form's (collocate): here Newton's contraction follows the
        // change of M since the Jacobian, not h·ΔJ, and stops further from the solution (the
        // exact beam in 8 elements at rtol 1e-3: v1 6.4e-4 of its peak off with the same
        // tolerance, 3.9e-4 with a tenth, at the same cost).
        let tol = 0.1 * (10.0 * f64::EPSILON / r).max(0.03f64.min(r.sqrt()));
        let mix = |c: &[[f64; 3]; 3], s: &[Stage; 3], out: &mut [Stage; 3]| {
            for (o, c) in out.iter_mut().zip(c) {
                for (k, o) in o.iter_mut().enumerate() {
                    *o = c[0] * s[0][k] + c[1] * s[1][k] + c[2] * s[2][k];
                }
            }
        };
        // The buffers of the last step, resized (an allocation each was 3 % of a run's time).
        let mut scratch = std::mem::take(&mut self.scratch);
        scratch.resize(m);
        let Scratch { zv, w, d, x, v, acc, res } = &mut scratch;
        for (zv, z) in zv.iter_mut().zip(z.iter()) {
            zv.copy_from_slice(&z.as_slice()[m..]);
        }
        mix(&TI, zv, w);
        let mut old_norm = 0.0;
        let mut rate;
        let mut result = Err(NewtonFail::Diverged);
        for k in 0..NEWTON_MAXITER {
            for i in 0..3 {
                for c in 0..m {
                    let s = a[i][0] * zv[0][c] + a[i][1] * zv[1][c] + a[i][2] * zv[2][c];
                    x[c] = x0[c] + C[i] * h * v0[c] + h * s;
                    v[c] = v0[c] + zv[i][c];
                    acc[c] = (ai[i][0] * zv[0][c] + ai[i][1] * zv[1][c] + ai[i][2] * zv[2][c]) / h;
                }
                if !sys.residual(self.t + C[i] * h, x, v, acc, &mut res[i]) {
                    self.residual_form = false;
                    self.scratch = scratch;
                    return None;
                }
                res[i].iter_mut().for_each(|r| *r = -*r);
            }
            self.stats.rhs_evals += 3;
            self.stats.newton_iters += 1;
            if !res.iter().all(|r| r.iter().all(|x| x.is_finite())) {
                result = Err(NewtonFail::NonFinite);
                break;
            }
            mix(&TI, res, d);
            let [d0, d1, d2] = d;
            factors.solve_reduced_real(d0)?;
            factors.solve_reduced_complex(d1, d2)?;
            let n = (d
                .iter()
                .flat_map(|d| d.iter().zip(wv).map(|(x, w)| (x / w) * (x / w)))
                .sum::<f64>()
                / (3 * m).max(1) as f64)
                .sqrt();
            let converged = match Newton::judge(k, n, old_norm, tol) {
                Newton::Fails(why) => {
                    result = Err(why);
                    break;
                }
                Newton::Converges(r, done) => {
                    rate = r;
                    done
                }
            };
            for (w, d) in w.iter_mut().zip(d.iter()) {
                w.iter_mut().zip(d).for_each(|(w, d)| *w += d);
            }
            mix(&T, w, zv);
            if converged {
                result = Ok((k + 1, rate));
                break;
            }
            old_norm = n;
        }
        if result.is_ok() {
            self.stage_acc = (0..m)
                .map(|c| (ai[2][0] * zv[0][c] + ai[2][1] * zv[1][c] + ai[2][2] * zv[2][c]) / h)
                .collect();
        }
        // The first-order stages: Zx_i = c_i h ẋ_n + h Σ_j a_ij Zv_j.
        for (i, zi) in z.iter_mut().enumerate() {
            let s = zi.as_mut_slice();
            for c in 0..m {
                s[c] = C[i] * h * v0[c]
                    + h * (a[i][0] * zv[0][c] + a[i][1] * zv[1][c] + a[i][2] * zv[2][c]);
                s[m + c] = zv[i][c];
            }
        }
        self.scratch = scratch;
        Some(result)
    }
}

/// The residual form's Newton buffers, m entries each: the stages' velocity increments Zv,
/// W = T⁻¹Zv, the increments, a stage's positions, velocities and accelerations, and the
/// three residuals. Not part of the solver's state.
#[derive(Clone, Debug, Default)]
pub(super) struct Scratch {
    zv: [Stage; 3],
    w: [Stage; 3],
    d: [Stage; 3],
    x: Stage,
    v: Stage,
    acc: Stage,
    res: [Stage; 3],
}

impl Scratch {
    fn resize(&mut self, m: usize) {
        let Scratch { zv, w, d, x, v, acc, res } = self;
        for b in zv.iter_mut().chain(w).chain(d).chain(res).chain([x, v, acc]) {
            b.resize(m, 0.0);
        }
    }
}
