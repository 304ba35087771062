"""Independent oracle for the geometrically exact beam of issue 28 (numpy; no Rust, no sympy).

The inextensible elastica: arc length s in [0, l], the section angle alpha(s, t) as the Ritz field,
the clamp at s = 0 (alpha(0) = 0, r(0) = 0), and the heavy rigid body hinged at the tip and turned by
the prescribed relative angle phi(t), as in the paper.

* The field. alpha = w'(s) with w(s) = N(s) . q and N the n uniform cubic Hermite elements of
  oracle_n.HermiteBasis (w(0) = w'(0) = 0), q = (w_1, a_1, ..., w_n, a_n): alpha is continuous and
  piecewise quadratic, a_i = alpha(s_i) and theta1 = alpha(l) = a_n. Why this space: for small
  rotations x = s, v = w, and it is exactly the space of the quadratic model's v' at the same n, so
  the two models share their linearisation about the straight beam (the same K, the same M_b): at
  the same n they differ only by the nonlinearity, which the small-turn check needs.
* Position r(s) = int_0^s (cos alpha, sin alpha) ds': inextensible by construction. Tip r(l) =
  (l + u1, v1). Body: theta = theta1 + phi, centre C = r(l) + r_off (cos theta, sin theta).
* Energies: T = 1/2 int m |r_t|^2 ds + 1/2 M2 |C_t|^2 + 1/2 J_C theta_t^2 (the beam's axial inertia
  included); V = 1/2 int EI alpha'^2 ds - M2 g C_x [- int m g x ds with beam gravity]; Rayleigh
  dissipation 1/2 qd^T D qd, D = alpha_R M_b + beta_R K with M_b = m int N^T N ds the beam's mass
  matrix at q = 0 (the quadratic model's).
* Equations (residual(), d'Alembert): R_k = int m J_k . r_tt ds + M2 (dC/dq_k) . C_tt
  + J_C (dtheta/dq_k) theta_tt + dV/dq_k + (D qd)_k = 0, J_k = dr/dq_k. The chain rule through alpha
  (r depends on q only through alpha, linearly in q) gives J_k(s) = int_0^s (-sin a, cos a) N_k' and
  r_tt = int_0^s [(-sin a, cos a) a_tt - (cos a, sin a) a_t^2]. These are checked in
  test_oracle_exact.py against a finite-difference Euler-Lagrange operator applied to T - V
  computed from positions alone (lagrangian(): r_t by the complex step of r(s; q)).
* Integrals along s: n elements with `npts` Gauss-Legendre points each. The running integrals
  int_0^s f at the Gauss points come from the Gauss collocation integration matrix (a_ij =
  int_0^{c_i} l_j, the Butcher matrix of the Gauss method; oracle_n.gauss_coefficients), exact for a
  polynomial of degree < npts in an element; the totals from the Gauss weights. cos(alpha) of a
  quadratic alpha is not a polynomial: the error falls spectrally in npts (test: 8, 10 and 12 points
  against 24; 12 gives about 1e-10 of the residual at rotations of several radians an element).

Everything is complex-safe (no abs, no conjugate), so oracle_n.gauss_integrate can take the
Jacobians by the complex step, and the trajectories are integrated by its implicit Gauss method.
"""

from __future__ import annotations

import numpy as np

from oracle_n import (
    DEFAULT_H,
    HermiteBasis,
    Model,
    _jac_complex_step,
    _law_fn,
    _segments,
    full_params,
    gauss_coefficients,
    gauss_integrate,
    output_grid,
    scene_with_defaults,
)
from paper_example import PARAM_NAMES

#: Gauss points per element for the integrals along s (see the module's docstring).
DEFAULT_NPTS = 12


class Elastica:
    """The exact beam in n elements with the body; arrays of states broadcast over leading axes."""

    def __init__(self, n, params=None, damping=(0.0, 0.0), beam_gravity=False, npts=DEFAULT_NPTS):
        self.p = p = full_params(params)
        self.basis = HermiteBasis(n, p["l"])
        self.n, self.ndof, self.h = n, self.basis.ndof, self.basis.h
        self.beam_gravity = bool(beam_gravity)
        c, A, b = gauss_coefficients(npts)
        self._A, self._b, self.npts = A, b, npts
        # Gauss points of every element, element by element (the same nodes as quadrature()).
        self.s = (self.basis.breaks[:-1, None] + self.h * c[None, :]).ravel()
        self.w = np.tile(self.h * b, n)
        self.N1 = self.basis.eval(self.s, 1)  # (P, ndof): alpha = N1 q
        self.N2 = self.basis.eval(self.s, 2)  # alpha' = N2 q
        self.c_tip = self.basis.eval([p["l"]], 1)[0]  # theta1 = c_tip . q
        # The strain energy and the Rayleigh damping are the quadratic model's, by definition of
        # the field (alpha' = w''; D from the beam's mass matrix at q = 0): taken from it.
        quadratic = Model(self.basis, params, damping)
        self.K, self.D = quadratic.K, quadratic.D

    # ---- integrals along s -------------------------------------------------------------------------
    def running(self, f, axis=-1):
        """(int_0^{s_P} f, int_0^l f) for f sampled at the Gauss points along `axis`."""
        f = np.moveaxis(np.asarray(f), axis, -1)
        fe = f.reshape(f.shape[:-1] + (self.n, self.npts))
        inside = self.h * fe @ self._A.T  # from each element's left end
        totals = self.h * fe @ self._b
        before = np.cumsum(totals, axis=-1) - totals  # the elements to the left
        run = (inside + before[..., None]).reshape(f.shape)
        return np.moveaxis(run, -1, axis), np.sum(totals, axis=-1)

    def positions(self, q):
        """r at the Gauss points (..., P, 2) and at the tip (..., 2)."""
        a = np.asarray(q) @ self.N1.T
        f = np.stack([np.cos(a), np.sin(a)], axis=-1)
        return self.running(f, axis=-2)

    def tip(self, q):
        """(u1, v1, theta1)."""
        _, rt = self.positions(q)
        return rt[..., 0] - self.p["l"], rt[..., 1], np.asarray(q) @ self.c_tip

    # ---- the equations -----------------------------------------------------------------------------
    def _kinematics(self, q, qd, qdd):
        """J (..., P, ndof, 2), J at the tip (..., ndof, 2), r_tt (..., P, 2) and at the tip."""
        a, ad, add = (np.asarray(x) @ self.N1.T for x in (q, qd, qdd))
        sa, ca = np.sin(a), np.cos(a)
        e_perp = np.stack([-sa, ca], axis=-1)  # d(cos a, sin a)/da
        J, Jt = self.running(e_perp[..., None, :] * self.N1[..., None], axis=-3)
        acc = e_perp * add[..., None] - np.stack([ca, sa], axis=-1) * (ad**2)[..., None]
        rtt, rtt_t = self.running(acc, axis=-2)
        return J, Jt, rtt, rtt_t

    def residual(self, phis, q, qd, qdd):
        """R(q, qd, qdd) (..., ndof): generalized forces, zero on a motion; affine in qdd."""
        p = self.p
        ph, dph, ddph = (np.asarray(v) for v in phis)
        q, qd, qdd = (np.asarray(x) for x in (q, qd, qdd))
        J, Jt, rtt, rtt_t = self._kinematics(q, qd, qdd)
        m, M2, J_C, g, r = p["m"], p["M2"], p["J_C"], p["g"], p["r"]
        beam = m * np.einsum("p,...pkd,...pd->...k", self.w, J, rtt)
        c = self.c_tip
        th, thd, thdd = q @ c + ph, qd @ c + dph, qdd @ c + ddph
        st, ct = np.sin(th), np.cos(th)
        # C = r(l) + r (cos th, sin th): dC/dq_k = Jt_k + r (-sin th, cos th) c_k.
        dCdq = Jt + r * np.stack([-st, ct], axis=-1)[..., None, :] * c[:, None]
        Ctt = rtt_t + r * (
            np.stack([-st, ct], axis=-1) * thdd[..., None] - np.stack([ct, st], axis=-1) * (thd**2)[..., None]
        )
        body = M2 * np.einsum("...kd,...d->...k", dCdq, Ctt) + J_C * c * thdd[..., None]
        gravity = -M2 * g * dCdq[..., 0]
        if self.beam_gravity:
            gravity = gravity - m * g * np.einsum("p,...pk->...k", self.w, J[..., 0])
        return beam + body + gravity + q @ self.K + qd @ self.D

    def mass_matrix(self, q, phi=0.0):
        """dR/dqdd at q (ndof, ndof)."""
        z = np.zeros(self.ndof)
        Mx, _, _ = _jac_complex_step(self.residual, (np.array([phi]), np.zeros(1), np.zeros(1)),
                                     np.asarray(q, dtype=float)[None], z[None], z[None])
        return Mx[0]

    # ---- energies from positions alone (for the checks) ----------------------------------------------
    def energies(self, q, qd, phi, dphi, eps=1e-30):
        """(T, V) at one state, r_t and C_t by the complex step of the positions r(s; q) along qd."""
        p = self.p
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)

        def points(qq, ph):
            r, rt = self.positions(qq)
            th = qq @ self.c_tip + ph
            return r, rt + p["r"] * np.stack([np.cos(th), np.sin(th)], axis=-1), th

        r, C, _ = points(q, phi)
        moving = points(q + 1j * eps * qd, phi + 1j * eps * dphi)
        r_t, C_t, th_t = (np.imag(z) / eps for z in moving)
        T = 0.5 * p["m"] * np.sum(self.w * np.sum(r_t**2, axis=-1))
        T += 0.5 * p["M2"] * np.sum(C_t**2) + 0.5 * p["J_C"] * th_t**2
        curvature = q @ self.N2.T
        V = 0.5 * p["EI"] * np.sum(self.w * curvature**2) - p["M2"] * p["g"] * C[0]
        if self.beam_gravity:
            V -= p["m"] * p["g"] * np.sum(self.w * r[:, 0])
        return T, V

    def lagrangian(self, q, qd, phi, dphi):
        T, V = self.energies(q, qd, phi, dphi)
        return T - V


def trajectory(n, scene=None, t_eval=None, h=None, stages=8, npts=DEFAULT_NPTS, beam_gravity=False,
               damping=(0.0, 0.0)):
    """(t, q, qd, model, stats) of the exact beam on t_eval (default: the scene's output grid), by the
    implicit Gauss method of oracle_n with steps of at most h, per segment of phi''."""
    s = scene_with_defaults(scene)
    params = {k: s[k] for k in PARAM_NAMES}
    mdl = Elastica(n, params, damping, beam_gravity, npts)
    t_eval = output_grid(s) if t_eval is None else np.asarray(t_eval, dtype=float)
    segments = _segments(s, float(t_eval[-1]))

    def jac(phis, x, v, a):
        return _jac_complex_step(mdl.residual, phis, x, v, a)

    z = np.zeros(mdl.ndof)
    Y, stats = gauss_integrate(mdl.residual, jac, _law_fn(s), segments, t_eval, z, z,
                               DEFAULT_H if h is None else h, stages)
    assert np.all(np.isfinite(Y)), "not every output time was reached"
    return t_eval, Y[:, : mdl.ndof], Y[:, mdl.ndof :], mdl, stats
