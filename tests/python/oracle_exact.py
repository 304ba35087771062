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
  matrix at q = 0 (the quadratic model's). K = EI int N2^T N2 ds and M_b are assembled here by this
  module's own Gauss points (checked against oracle_n's and the cantilever's deflection
  P l^3 / (3 EI) in test_oracle_exact_loads.py).
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

* Loads (Elastica.loads, loads_along; issue 44): the hinge's N, P, M from the body's Newton-Euler
  equations, the clamp's Q_root, M_root from the balance of momentum and angular momentum of beam
  and body about the clamp, with the accelerations from the residual.
* Small oscillations (static_equilibrium, small_oscillations): Newton's method on R(q, 0, 0) at a
  held phi, the tangent stiffness by the complex step, the generalized eigenproblem with M(q*).

Everything is complex-safe (no abs, no conjugate), so oracle_n.gauss_integrate can take the
Jacobians by the complex step, and the trajectories are integrated by its implicit Gauss method.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

from oracle_n import (
    CACHE_DIR,
    DAMPING_NAMES,
    DEFAULT_H,
    HermiteBasis,
    _jac_complex_step,
    _law_fn,
    _segments,
    damped_newton,
    full_params,
    gauss_coefficients,
    gauss_integrate,
    output_grid,
    save_trajectory,
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
        self.N0 = self.basis.eval(self.s, 0)  # w = N0 q (the deflection of the linearisation)
        # The strain energy 1/2 int EI alpha'^2 ds = 1/2 q^T K q and the beam's mass matrix at
        # q = 0, M_b = m int N^T N ds, assembled here by this class's own Gauss points (exact:
        # alpha' = N2 q is linear and w = N0 q cubic in an element, so the integrands have degree
        # 2 and 6 < 2 npts). Rayleigh's dissipation 1/2 qd^T D qd, D = alpha_R M_b + beta_R K.
        # K and M_b are the quadratic model's by definition of the field (alpha' = w''), checked
        # against oracle_n's assembly and against the cantilever's static deflection in
        # test_oracle_exact_loads.py (issue 44).
        self.K = p["EI"] * (self.N2.T * self.w) @ self.N2
        self.Mb = p["m"] * (self.N0.T * self.w) @ self.N0
        self.K, self.Mb = 0.5 * (self.K + self.K.T), 0.5 * (self.Mb + self.Mb.T)
        a_R, b_R = (float(x) for x in damping)
        if params:  # as oracle_n.Model: damping_alpha / damping_beta in params override `damping`
            a_R, b_R = float(params.get("damping_alpha", a_R)), float(params.get("damping_beta", b_R))
        self.rayleigh = (a_R, b_R)
        self.D = a_R * self.Mb + b_R * self.K

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

    def accelerations(self, phis, q, qd):
        """qdd (..., ndof) solving R(q, qd, qdd) = 0. R is affine in qdd with real coefficients, so
        R(q, qd, i e_k) = R(q, qd, 0) + i M e_k exactly: one complex evaluation gives the mass matrix
        (imaginary part) and the rest (real part), batched over leading axes."""
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        E = 1j * np.eye(self.ndof)
        pb = tuple(np.asarray(v, dtype=float)[..., None] for v in phis)
        R = self.residual(pb, q[..., None, :], qd[..., None, :], E + np.zeros(q.shape[:-1] + E.shape))
        Mx = np.swapaxes(np.imag(R), -1, -2)
        return np.linalg.solve(Mx, -np.real(R[..., 0, :])[..., None])[..., 0]

    def loads(self, phis, q, qd, qdd):
        """The hinge's and the clamp's loads on a motion (q, qd, qdd), as a dict of arrays (...):

        * N, P: the force of the body on the beam's tip, along x and y; M: the moment of the body on
          the tip section (-M is the drive's torque on the body). From the body's own equations of
          motion, Newton-Euler about its centre C, with the body's loads on the beam the reverse of
          the beam's on the body (Newton's third law): M2 C'' = -(N, P) + M2 g e_x and
          J_C theta'' = -M + (r_tip - C) x (-(N, P)), r_tip - C = -r (cos theta, sin theta).
        * Q_root, M_root: the shear and the bending moment at the clamp, Q_root = F_y and
          M_root = -tau with (F, tau) the force and torque of the clamp on the beam: the signs of
          EI v'''(0) and EI v''(0) of the linear cantilever (a static tip load P along y gives
          Q_root = -P, M_root = P l). From the balance of momentum and of angular momentum about
          the clamp O of beam and body together, the hinge's loads and the drive's torque being
          internal (Goldstein, Classical Mechanics, 3rd ed., §1.2):
              F + (external forces) = d/dt (m int r_t ds + M2 C_t),
              tau + (their moments about O) = d/dt (m int r x r_t ds + M2 C x C_t + J_C theta_t).
          The external forces: the weights (M2 g e_x at C; m g e_x per unit length with the beam's
          weight) and the mass-proportional damping. D = alpha_R M_b + beta_R K is a generalized
          force, not a force field, so its share of the clamp's load needs the dissipation extended
          to a rigid motion (y0, b0) of the clamp: beta_R K dissipates by curvature rates, which a
          rigid motion leaves alone (no share); alpha_R M_b is the linearised drag against the
          absolute lateral velocity, 1/2 alpha_R m int (y0_t + b0_t s + w_t)^2 ds (w = N0 q), whose
          derivatives at y0_t = b0_t = 0, alpha_R m int w_t ds and alpha_R m int s w_t ds, the
          clamp supplies.
        """
        p = self.p
        m, M2, J_C, g, r = p["m"], p["M2"], p["J_C"], p["g"], p["r"]
        ph, dph, ddph = (np.asarray(v, dtype=float) for v in phis)
        q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
        rp, rtip = self.positions(q)
        _, _, rtt, rtt_t = self._kinematics(q, qd, qdd)
        c = self.c_tip
        th, thd, thdd = q @ c + ph, qd @ c + dph, qdd @ c + ddph
        e = np.stack([np.cos(th), np.sin(th)], axis=-1)
        e_perp = np.stack([-np.sin(th), np.cos(th)], axis=-1)
        C = rtip + r * e
        Ctt = rtt_t + r * (e_perp * thdd[..., None] - e * (thd**2)[..., None])
        # the body: M2 C'' = -(N, P) + M2 g e_x
        N = M2 * (g - Ctt[..., 0])
        P = -M2 * Ctt[..., 1]
        # about C: J_C theta'' = -M + (-r e) x (-(N, P)) = -M + r (e_x P - e_y N)
        M = r * (e[..., 0] * P - e[..., 1] * N) - J_C * thdd

        def cross(a, b):
            return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]

        g_b = g if self.beam_gravity else 0.0
        a_R = self.rayleigh[0]
        wt = qd @ self.N0.T  # w_t at the Gauss points
        Fy = (M2 * Ctt[..., 1] + m * np.sum(self.w * rtt[..., 1], axis=-1)
              + a_R * m * np.sum(self.w * wt, axis=-1))
        # the weights' moments about O: C x (M2 g e_x) = -M2 g C_y, r x (m g e_x) = -m g r_y
        tau = (M2 * cross(C, Ctt) + J_C * thdd + m * np.sum(self.w * cross(rp, rtt), axis=-1)
               + M2 * g * C[..., 1] + m * g_b * np.sum(self.w * rp[..., 1], axis=-1)
               + a_R * m * np.sum(self.w * self.s * wt, axis=-1))
        return {"N": N, "P": P, "M": M, "Q_root": Fy, "M_root": -tau}

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
               damping=(0.0, 0.0), cache=True):
    """(t, q, qd, model, stats) of the exact beam on t_eval (default: the scene's output grid), by the
    implicit Gauss method of oracle_n with steps of at most h, per segment of phi''. The scene may hold
    damping_alpha / damping_beta (they override `damping`). Cached in memory and in
    target/oracle-cache (npz, keyed by the arguments, the text of this file and of oracle_n.py and the
    numpy and scipy versions)."""
    s = scene_with_defaults(scene)
    params = {k: s[k] for k in PARAM_NAMES}
    params.update({k: s[k] for k in DAMPING_NAMES if k in s})
    mdl = Elastica(n, params, damping, beam_gravity, npts)
    t_eval = output_grid(s) if t_eval is None else np.asarray(t_eval, dtype=float)
    h = DEFAULT_H if h is None else float(h)
    key = _cache_key([n, s, list(map(float, t_eval)), h, stages, npts, bool(beam_gravity), list(mdl.rayleigh)])
    path = CACHE_DIR / f"oracle_exact-{key}.npz"
    if key in _MEMO:
        Y, stats = _MEMO[key]
    elif cache and path.is_file():
        with np.load(path) as z:
            Y, stats = z["Y"], {**json.loads(str(z["stats"])), "cached": True}
    else:
        segments = _segments(s, float(t_eval[-1]))

        def jac(phis, x, v, a):
            return _jac_complex_step(mdl.residual, phis, x, v, a)

        z = np.zeros(mdl.ndof)
        Y, stats = gauss_integrate(mdl.residual, jac, _law_fn(s), segments, t_eval, z, z, h, stages)
        assert np.all(np.isfinite(Y)), "not every output time was reached"
        if cache:
            save_trajectory(path, Y, stats)
    _MEMO[key] = (Y, stats)
    return t_eval, Y[:, : mdl.ndof], Y[:, mdl.ndof :], mdl, dict(stats)


_MEMO: dict = {}


def _cache_key(obj):
    digest = hashlib.sha256(json.dumps(obj, sort_keys=True).encode())
    for module in ("oracle_exact.py", "oracle_n.py"):
        digest.update((Path(__file__).resolve().parent / module).read_bytes())
    import scipy

    digest.update(f"{np.__version__} {scipy.__version__}".encode())
    return digest.hexdigest()[:20]


def loads_along(t, q, qd, model, scene=None):
    """The loads of Elastica.loads along a trajectory (t, q, qd) of trajectory(): phi from the scene's
    law (the turn's piece for t < t_rot, the hold's from t_rot on: phi'' jumps at t_rot, where the
    loads have two values), the accelerations from the oracle's own residual."""
    s = scene_with_defaults(scene)
    law, t = _law_fn(s), np.asarray(t, dtype=float)
    turning = t < s["t_rot"]
    phis = tuple(np.where(turning, a, b) for a, b in zip(law(t, True), law(t, False)))
    qdd = model.accelerations(phis, q, qd)
    return model.loads(phis, q, qd, qdd)


# --------------------------------------------------------------------------------------------------
# Small oscillations about the static equilibrium at a held phi
# --------------------------------------------------------------------------------------------------


def tangent_stiffness(mdl, q, phi):
    """dR/dq at rest (qd = qdd = 0, phi' = phi'' = 0), by the complex step of the residual."""
    z = np.zeros((1, mdl.ndof))
    held = (np.array([phi]), np.zeros(1), np.zeros(1))
    return _jac_complex_step(mdl.residual, held, np.asarray(q, dtype=float)[None], z, z)[2][0]


def static_equilibrium(mdl, phi, tol=1e-12, maxit=50):
    """Newton's method on R(q, 0, 0) = 0 with the body held at phi, from the straight beam, with the
    exact tangent stiffness (complex step) and step halving while the residual grows. Converged when
    the residual is below tol times its terms' size (|K| |q| + M2 |g| (l + r), the elastic forces and
    the weight's moment about the clamp), after at least one full step if it did not vanish at q = 0."""
    p = mdl.p
    z = np.zeros(mdl.ndof)

    def res(q):
        return mdl.residual((phi, 0.0, 0.0), q, z, z)

    def scale(q):
        weight = abs(p["M2"] * p["g"]) * (p["l"] + p["r"])
        if mdl.beam_gravity:
            weight += abs(p["m"] * p["g"]) * p["l"] ** 2
        return np.abs(mdl.K) @ np.abs(q) + weight

    return damped_newton(res, lambda q: tangent_stiffness(mdl, q, phi), scale, np.zeros(mdl.ndof), tol, maxit,
                         f"static equilibrium at phi={phi}")


def small_oscillations(n, phi, params=None, beam_gravity=False, npts=DEFAULT_NPTS):
    """(q*, omega^2 ascending, modes (columns, mass-normalized), M(q*), K_T(q*), model) of the small
    oscillations about the static equilibrium q* with the body held at phi: the linearisation
    M(q*) dq'' + K_T(q*) dq = 0 of the oracle's own residual (at rest, R's derivative in qd vanishes
    without damping, and the one in q is K_T), solved as the generalized symmetric eigenproblem."""
    from scipy.linalg import eigh

    mdl = Elastica(n, params, beam_gravity=beam_gravity, npts=npts)
    q = static_equilibrium(mdl, phi)
    KT = tangent_stiffness(mdl, q, phi)
    asym = np.max(np.abs(KT - KT.T)) / np.max(np.abs(KT))
    assert asym < 1e-10, asym  # a conservative system at rest: K_T is the Hessian of V
    Mq = mdl.mass_matrix(q, phi)
    w2, V = eigh(0.5 * (KT + KT.T), 0.5 * (Mq + Mq.T))
    return q, w2, V, Mq, KT, mdl
