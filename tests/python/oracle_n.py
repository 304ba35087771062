"""Independent n-element physics oracle for the beam-body model (numpy + scipy; no Rust, no sympy).

The "quadratic" model of shared/model-notes.md ("Beyond the paper: the model's own error") with an
arbitrary Ritz basis for the transverse deflection v(x, t) of the clamped, inextensible Euler-Bernoulli
beam, and the heavy rigid body hinged at its tip, turned by the prescribed relative angle phi(t):

* v(x, t) = N(x) . q(t), N(x) the row of shape functions of a basis that satisfies the clamp
  v(0) = v'(0) = 0. Two bases, one code path (a basis only provides N and its x-derivatives):
    - "hermite": n uniform cubic Hermite elements, q = (v_1, th_1, ..., v_n, th_n) at x_i = i l/n;
    - "poly": K global polynomials x^2 P_k(2x/l - 1), k = 0..K-1 (P_k Legendre); q = the coefficients.
* energies (the integrals are evaluated by composite Gauss-Legendre quadrature of the shape functions):
    T1 = 1/2 int m vdot^2 dx              -> 1/2 qd^T M_b qd,   M_b = m int N^T N dx
    Pi1 = 1/2 int EI v''^2 dx             -> 1/2 q^T K q,       K = EI int N''^T N'' dx
    u1 = -1/2 int (v')^2 dx (tip shortening, inextensibility to second order) = -1/2 q^T G q,
                                                                G = int N'^T N' dx
    tip rows b = N(l), c = N'(l): v1 = b.q, theta1 = c.q
    C = (l + u_h + r cos theta, v1 + r sin theta), theta = theta1 + phi
    T2 = 1/2 M2 |C'|^2 + 1/2 J_C theta'^2,  Pi2 = -M2 g (u_h + r cos theta)   (gravity along +x)
    Rayleigh dissipation F = 1/2 qd^T D qd, D = alpha M_b + beta K (generalized force -D qd).
    The beam's own weight (beam_gravity=True; the paper leaves it out): g per unit length m along +x,
    as the body's, Pi_w = -int m g x(s) ds with x(s) = s + u(s), u(s) = -1/2 int_0^s v'^2 the axial
    displacement of the inextensible beam to second order (u(l) = u1). Exchanging the order of the
    double integral (sigma < s < l has length l - sigma):
        Pi_w = -m g l^2/2 + 1/2 m g int (l - x) v'^2 dx = const + 1/2 q^T K_w q,
        K_w = m g G_w,  G_w = int (l - x) N'^T N' dx
    (a tension m g (l - x) from the weight beyond x: g > 0 stiffens the beam); lagrangian() computes
    Pi_w from the double integral itself, checked against K_w in the tests.
* formulations (residual rows are generalized forces, as in tests/python/oracle.py):
    reduced: u_h = u1(q); R = d/dt dL/dqd - dL/dq + D qd. With A = dC/dq (rows a_x = -G q - r sin(theta) c,
             a_y = b + r cos(theta) c) the body's part is M2 A^T C'' + J_C c theta'' + dPi2/dq (for
             T = 1/2 M |C'|^2 with C = C(q, t), d/dt dT/dqd - dT/dq = M (dC/dq)^T C'' ), so
             R = M(q) qdd + ...,  M(q) = M_b + M2 A^T A + J_C c c^T.
    linear:  the first-order Taylor expansion of the reduced R about q = qd = qdd = 0 with phi, phi',
             phi'' kept exact; the derivatives are taken by the complex step (Squire & Trapp, SIAM Rev.
             40 (1998) 110), exact to round-off because R is analytic in q, qd, qdd.
    dae:     u_h = u2 a free coordinate; E_x = d/dt dL/dxd - dL/dx (+ D qd) for x in (q, u2);
             lambda = E_u2; f = u2 - u1(q); R_q = E_q - lambda df/dq, R_u2 = u2'' - d^2/dt^2 u1(q)
             (the constraint differentiated twice, as the paper integrates it).
  Every residual is affine in the accelerations; the accelerations solve Mass a = -R(a = 0).
  The residuals are checked in test_oracle_elements.py against a finite-difference Euler-Lagrange
  operator applied to the energy integrals themselves (lagrangian(), no assembled matrices).

With n = 1 (Hermite), or K = 2 polynomials (the same space), the equations are those of
tests/python/oracle.py (checked in test_oracle_elements.py, to round-off).

Integration (trajectory): the highest element modes are stiff (omega_max = 317, 2.2e3, 1.1e4, 4.5e4,
1.8e5 rad/s for 2..32 Hermite elements; 820..1.2e4 for K = 6..14 polynomials) and the jumps of phi''
at 0 and t_rot excite them, so an explicit method must resolve them (DOP853 at rtol 1e-12: 2e5
evaluations for 4 elements over 2 s) and scipy's Radau is slower still. The default is an 8-stage
Gauss-Legendre method (order 16, A-stable) with fixed steps <= 2 ms (gauss_integrate). Measured on the
paper's scene: against DOP853, 1e-13 m for n <= 2 (n = 1: against oracle.py) and 4 elements over
[0, 2 s]; steps of 1.7 ms against 0.94 ms over 10.2 s: <= 3e-9 m in v1, 4e-9 rad in theta1 for up to 32
elements and 14 polynomials, but up to 0.04 N m (1e-4 of its peak) in the root moment EI v''(0): the
modes the step does not resolve (omega h >~ 5) carry little deflection but much curvature.

Loads (Model.hinge_loads, Model.root_loads, Trajectory.loads), from the oracle's own equations:
* the hinge's (N, P, M), the force and moment the body exerts on the beam tip (paper eq. 18-19; -M is
  the drive's torque on the body), by Newton-Euler for the body freed at the hinge: it carries
  (-N, -P) at the hinge H = C - r (cos theta, sin theta), the moment -M and its weight M2 g along +x:
      M2 C_x'' = M2 g - N,   M2 C_y'' = -P,   J_C theta'' = (H - C) x (-N, -P) - M
      => N = M2 (g - C_x''),  P = -M2 C_y'',  M = r (P cos theta - N sin theta) - J_C theta''.
* the root's shear force Q_root and bending moment M_root (EI v'''(0) and EI v''(0) of the exact
  beam), as the clamp's reactions by d'Alembert's principle (Lanczos, The Variational Principles of
  Mechanics, 1970, ch. IV) with the virtual rigid motions of beam and body: the rigid translation
  dv = 1 and rotation dv = x about the clamp span, with the clamped basis, the basis with the clamp
  freed (for the Hermite elements 1 = N_v0 + sum N_vi and x = N_th0 + sum (x_i N_vi + N_thi); for the
  polynomials, all of degree <= K + 1), so the clamp's reactions are the generalized forces along them
  (the clamped rows vanish on the motion),
  E(dv) = int m (v_tt + alpha v_t) dv dx + int EI v'' dv'' (+ beta ...) + the body's
  M2 C'' . dC + J_C theta'' dtheta + dPi2 + dPi_w. For a rigid motion dv'' = 0 (no elastic or
  stiffness-proportional damping part); the translation moves the body by dC = (0, 1); the rotation
  by dv1 = l, dtheta = 1 and du1 = -int v' dv' dx = -v1 (exact for any field), so
  dC = (-v1 - r sin theta, l + r cos theta) = (-C_y, l + r cos theta), dPi2 = -M2 g dC_x = M2 g C_y,
  dPi_w = m g int (l - x) v' dx = m g int v dx (by parts). The clamp's force on the beam is
  E(1) = Q_root, its moment E(x) = -M_root (for a static tip force P: Q_root = -P, M_root = P l):
      Q_root = int m (v_tt + alpha v_t) dx + M2 C_y''
      M_root = -[int m x (v_tt + alpha v_t) dx + M2 (C_y'' (l + r cos theta) - C_x'' C_y) + J_C theta''
                 + M2 g C_y + m g int v dx]
  (with the hinge loads, M_root = M + P l - N v1 - int m x (v_tt + alpha v_t) dx - m g int v dx: the
  moment of the tip's loads, the lever arm l rather than l + u1 as the quadratic model's
  kinematics). Model.clamp_reactions computes them a second way, as the residual rows of the clamped
  node of the model with the clamp's dofs freed (Hermite only). They are not the elements' own
  EI v''(0) (Trajectory.root_moment), which converges more slowly with n.

Small oscillations (natural_frequencies): Newton's method for the static equilibrium at a held phi, the
tangent stiffness by the complex step, and the generalized eigenproblem with M(q*). At phi = 0 both bases
converge from above to continuum_frequencies (the beam-column frequency equation).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.polynomial import Legendre, Polynomial

# --------------------------------------------------------------------------------------------------
# Parameters and the scene
# --------------------------------------------------------------------------------------------------

from paper_example import DEFAULT_PARAMS, PAPER_LAW, PARAM_NAMES  # noqa: E402

DAMPING_NAMES = ("damping_alpha", "damping_beta")

PAPER_SCENE = {**DEFAULT_PARAMS, **PAPER_LAW}

CACHE_DIR = Path(__file__).resolve().parents[2] / "target" / "oracle-cache"


def full_params(params=None):
    p = dict(DEFAULT_PARAMS)
    if params:
        unknown = set(params) - set(PARAM_NAMES) - set(DAMPING_NAMES)
        if unknown:
            raise KeyError(f"unknown parameter(s) {sorted(unknown)}")
        p.update({k: float(v) for k, v in params.items() if k in PARAM_NAMES})
    return p


def _damping(params, damping):
    """(alpha, beta): the damping argument, overridden by damping_alpha / damping_beta in params."""
    a, b = (float(x) for x in damping)
    if params:
        a = float(params.get("damping_alpha", a))
        b = float(params.get("damping_beta", b))
    return a, b


def scene_with_defaults(scene=None):
    s = dict(PAPER_SCENE)
    if scene:
        s.update({k: float(v) for k, v in scene.items()})
    return s


# --------------------------------------------------------------------------------------------------
# Shape-function providers
# --------------------------------------------------------------------------------------------------


class HermiteBasis:
    """n uniform cubic Hermite beam elements, node 0 clamped; dofs (v_i, th_i), i = 1..n.

    Local shape functions on an element of length h, xi = (x - x_a)/h in [0, 1] (the classical cubic
    Hermite interpolants of the Euler-Bernoulli beam element, e.g. Przemieniecki, Theory of Matrix
    Structural Analysis, 1968, §5.3; Zienkiewicz & Taylor, The Finite Element Method, vol. 2):
        H1 = 1 - 3 xi^2 + 2 xi^3,   H2 = h (xi - 2 xi^2 + xi^3),     (v, v' at the left node)
        H3 = 3 xi^2 - 2 xi^3,       H4 = h (-xi^2 + xi^3)            (v, v' at the right node)
    d/dx = (1/h) d/dxi. At an interior node the element to its right is used (v'' and v''' jump there);
    x = l belongs to the last element.

    free_root=True frees the clamp: the dofs are then (v_0, th_0, v_1, th_1, ..., v_n, th_n) (for the
    clamp's reactions, Model.clamp_reactions)."""

    name = "hermite"

    def __init__(self, n, l, free_root=False):
        if n < 1:
            raise ValueError("n >= 1 elements")
        self.n, self.l, self.h = int(n), float(l), float(l) / n
        self.free_root = bool(free_root)
        self._off = 2 if self.free_root else 0  # the column of node k's v is 2 (k - 1) + _off
        self.ndof = 2 * self.n + self._off
        self.breaks = np.linspace(0.0, self.l, self.n + 1)
        self.nodes = self.breaks[1:]
        h = self.h
        self._local = [
            Polynomial([1.0, 0.0, -3.0, 2.0]),
            Polynomial([0.0, h, -2.0 * h, h]),
            Polynomial([0.0, 0.0, 3.0, -2.0]),
            Polynomial([0.0, 0.0, -h, h]),
        ]
        self.quad_points = 6  # per element (4 are exact for N''N'', degree 6 -> 2*4-1 = 7)

    def eval(self, x, d=0):
        """(len(x), ndof): the d-th x-derivative of the shape functions at x."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        e = np.clip(np.floor(x / self.h).astype(int), 0, self.n - 1)
        xi = (x - e * self.h) / self.h
        out = np.zeros((len(x), self.ndof), dtype=float)
        scale = self.h ** (-d)
        vals = [p.deriv(d)(xi) * scale if d else p(xi) for p in self._local]
        rows = np.arange(len(x))
        # left node e (dofs 2(e-1), 2(e-1)+1; absent for e = 0, the clamp, unless freed), right node
        # e+1 (dofs 2e, 2e+1); all shifted by 2 with the clamp freed
        o = self._off
        left = (e >= 1) | self.free_root
        out[rows[left], 2 * (e[left] - 1) + o] = vals[0][left]
        out[rows[left], 2 * (e[left] - 1) + 1 + o] = vals[1][left]
        out[rows, 2 * e + o] = vals[2]
        out[rows, 2 * e + 1 + o] = vals[3]
        return out

    def tip_dofs(self):
        return self.ndof - 2, self.ndof - 1


class LegendreBasis:
    """K global polynomials f_k(x) = x^2 P_k(2x/l - 1), k = 0..K-1 (P_k the Legendre polynomials): they
    span x^2 * (polynomials of degree < K), i.e. exactly the polynomials of degree <= K+1 with
    v(0) = v'(0) = 0. Built as Legendre series in xi = 2x/l - 1 (x = l (1 + xi)/2):
    f_k = (l/2)^2 (1 + xi)^2 P_k(xi); d/dx = (2/l) d/dxi."""

    name = "poly"

    def __init__(self, K, l):
        if K < 1:
            raise ValueError("K >= 1 functions")
        self.n = self.K = int(K)
        self.l = float(l)
        self.ndof = self.K
        self.breaks = np.array([0.0, self.l])
        one_plus_xi_sq = Legendre([1.0, 1.0]) ** 2
        self._f = [(self.l / 2) ** 2 * one_plus_xi_sq * Legendre.basis(k) for k in range(self.K)]
        self.quad_points = self.K + 6  # N''N'' has degree 2K-2 in x, N N degree 2K+2

    def eval(self, x, d=0):
        x = np.atleast_1d(np.asarray(x, dtype=float))
        xi = 2.0 * x / self.l - 1.0
        s = (2.0 / self.l) ** d
        return np.stack([(f.deriv(d)(xi) * s if d else f(xi)) for f in self._f], axis=1)


def make_basis(basis, n, l):
    if basis == "hermite":
        return HermiteBasis(n, l)
    if basis in ("poly", "polynomial", "legendre"):
        return LegendreBasis(n, l)
    raise ValueError(f"unknown basis {basis!r}")


def quadrature(breaks, npts):
    """Composite Gauss-Legendre rule (npts nodes per interval between breaks; exact for polynomials of
    degree 2 npts - 1 on each interval; nodes/weights from numpy.polynomial.legendre.leggauss, the
    Golub-Welsch eigenvalue method, Math. Comp. 23 (1969) 221)."""
    xg, wg = np.polynomial.legendre.leggauss(npts)
    xs, ws = [], []
    for a, b in zip(breaks[:-1], breaks[1:]):
        xs.append(0.5 * (b - a) * xg + 0.5 * (a + b))
        ws.append(0.5 * (b - a) * wg)
    return np.concatenate(xs), np.concatenate(ws)


# --------------------------------------------------------------------------------------------------
# The model
# --------------------------------------------------------------------------------------------------


def _phis(phis):
    ph, dph, ddph = (np.asarray(v) for v in phis)
    return ph, dph, ddph


class Model:
    """Assembled matrices and the residuals / accelerations of the three formulations.

    Arrays of states broadcast: q, qd, qdd of shape (..., ndof), phi tuples of shape (...).
    beam_gravity: the beam's own weight (K_w of the module docstring)."""

    def __init__(self, basis, params=None, damping=(0.0, 0.0), beam_gravity=False):
        self.basis = basis
        self.p = full_params(params)
        self.alpha, self.beta = _damping(params, damping)
        self.beam_gravity = bool(beam_gravity)
        p = self.p
        xq, wq = quadrature(basis.breaks, basis.quad_points)
        N0, N1, N2 = (basis.eval(xq, d) for d in (0, 1, 2))
        self.Mb = p["m"] * N0.T @ (wq[:, None] * N0)
        self.K = p["EI"] * N2.T @ (wq[:, None] * N2)
        self.G = N1.T @ (wq[:, None] * N1)
        # G_w = int (l - x) N'^T N' dx (degree 2 deg N' + 1: exact with the rule's points)
        Gw = N1.T @ ((wq * (p["l"] - xq))[:, None] * N1)
        self.Kw = (p["m"] * p["g"] if self.beam_gravity else 0.0) * Gw
        for A in (self.Mb, self.K, self.G, self.Kw):
            A[:] = 0.5 * (A + A.T)
        self.b = basis.eval([p["l"]], 0)[0]
        self.c = basis.eval([p["l"]], 1)[0]
        self.D = self.alpha * self.Mb + self.beta * self.K
        self.ndof = basis.ndof
        self._Mb_inv = np.linalg.inv(self.Mb)

    # ---- fields ----------------------------------------------------------------------------------
    def field(self, q, x, d=0):
        """d-th x-derivative of v at the points x for coordinates q (..., ndof) -> (..., len(x))."""
        return np.asarray(q) @ self.basis.eval(x, d).T

    def tip(self, q):
        """(v1, theta1) = (b.q, c.q)."""
        q = np.asarray(q)
        return q @ self.b, q @ self.c

    def u1(self, q):
        q = np.asarray(q)
        return -0.5 * np.einsum("...i,ij,...j->...", q, self.G, q)

    def du1(self, q, qd):
        return -np.einsum("...i,ij,...j->...", np.asarray(q), self.G, np.asarray(qd))

    # ---- residuals ---------------------------------------------------------------------------------
    def _body(self, phis, q, qd, qdd):
        """The body's angle terms and its centre's lateral acceleration: (Gq, thd, thdd, sin th,
        cos th, Cydd), with th = theta1 + phi."""
        r, b, c = self.p["r"], self.b, self.c
        ph, dph, ddph = _phis(phis)
        th = q @ c + ph
        thd = qd @ c + dph
        thdd = qdd @ c + ddph
        s, co = np.sin(th), np.cos(th)
        Cydd = qdd @ b + r * co * thdd - r * s * thd**2
        return q @ self.G, thd, thdd, s, co, Cydd

    def residual_reduced(self, phis, q, qd, qdd):
        """R = M(q) qdd + (the rest); complex-safe (transposes never conjugate)."""
        p = self.p
        r, M2, J_C, g = p["r"], p["M2"], p["J_C"], p["g"]
        b, c, G = self.b, self.c, self.G
        Gq, thd, thdd, s, co, Cydd = self._body(phis, q, qd, qdd)
        a_x = -Gq - r * s[..., None] * c
        a_y = b + r * co[..., None] * c
        ddu1 = -np.sum((qd @ G) * qd, axis=-1) - np.sum(Gq * qdd, axis=-1)
        Cxdd = ddu1 - r * s * thdd - r * co * thd**2
        return (
            qdd @ self.Mb
            + q @ self.K
            + qd @ self.D
            + M2 * (a_x * Cxdd[..., None] + a_y * Cydd[..., None])
            + J_C * c * thdd[..., None]
            + M2 * g * (Gq + r * s[..., None] * c)
            + q @ self.Kw
        )

    def residual_linear(self, phis, q, qd, qdd):
        R0, Jq, Jqd, M0 = self.linear_parts(phis)
        return R0 + np.einsum("...ij,...j->...i", Jq, q) + np.einsum("...ij,...j->...i", Jqd, qd) + np.einsum(
            "...ij,...j->...i", M0, qdd
        )

    def linear_parts(self, phis, h=1e-30):
        """(R0, dR/dq, dR/dqd, dR/dqdd) of the reduced residual at q = qd = qdd = 0 (complex step)."""
        ph, dph, ddph = (np.asarray(v, dtype=float) for v in _phis(phis))
        n = self.ndof
        shp = ph.shape
        E = np.eye(n) * (1j * h)
        z = np.zeros(shp + (n, n), dtype=complex)
        zr = np.zeros(shp + (n,))
        pb = tuple(v[..., None] for v in (ph, dph, ddph))  # broadcast over the n directions
        R0 = self.residual_reduced((ph, dph, ddph), zr, zr, zr)
        Jq = np.imag(self.residual_reduced(pb, z + E, z, z)) / h
        Jqd = np.imag(self.residual_reduced(pb, z, z + E, z)) / h
        Jqdd = np.imag(self.residual_reduced(pb, z, z, z + E)) / h
        # row index = residual component; the batch axis -2 is the direction: transpose the last two
        return R0, np.swapaxes(Jq, -1, -2), np.swapaxes(Jqd, -1, -2), np.swapaxes(Jqdd, -1, -2)

    def residual_dae(self, phis, q, u2, qd, du2, qdd, ddu2):
        """(R_q (..., ndof), R_u2 (...)): the freed body with its own longitudinal coordinate u2."""
        p = self.p
        r, M2, J_C, g = p["r"], p["M2"], p["J_C"], p["g"]
        b, c, G = self.b, self.c, self.G
        Gq, thd, thdd, s, co, Cydd = self._body(phis, q, qd, qdd)
        Cxdd = ddu2 - r * s * thdd - r * co * thd**2
        E_q = (
            qdd @ self.Mb
            + q @ self.K
            + qd @ self.D
            + M2 * ((-r * s[..., None] * c) * Cxdd[..., None] + (b + r * co[..., None] * c) * Cydd[..., None])
            + J_C * c * thdd[..., None]
            + M2 * g * r * s[..., None] * c
            + q @ self.Kw
        )
        lam = M2 * Cxdd - M2 * g  # E_u2
        # f = u2 - u1(q) = u2 + 1/2 q^T G q: df/dq = G q
        R_q = E_q - lam[..., None] * Gq
        ddu1 = -np.sum((qd @ G) * qd, axis=-1) - np.sum(Gq * qdd, axis=-1)
        R_u2 = ddu2 - ddu1
        return R_q, R_u2

    def dae_multiplier(self, phis, q, u2, qd, du2, qdd, ddu2):
        """lambda = E_u2 = M2 (x_C'' - g): minus the hinge force N along x on the body side."""
        p = self.p
        ph, dph, ddph = _phis(phis)
        th = q @ self.c + ph
        thd = qd @ self.c + dph
        thdd = qdd @ self.c + ddph
        Cxdd = ddu2 - p["r"] * np.sin(th) * thdd - p["r"] * np.cos(th) * thd**2
        return p["M2"] * (Cxdd - p["g"])

    # ---- loads (module docstring, "Loads") -----------------------------------------------------------
    def _body_accel(self, phis, q, qd, qdd):
        """(C_x'' , C_y'', theta, theta'') of the body on the reduced model's motion (u_h = u1(q))."""
        r = self.p["r"]
        q, qd, qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
        Gq, thd, thdd, s, co, Cydd = self._body(phis, q, qd, qdd)
        ddu1 = -np.sum((qd @ self.G) * qd, axis=-1) - np.sum(Gq * qdd, axis=-1)
        Cxdd = ddu1 - r * s * thdd - r * co * thd**2
        return Cxdd, Cydd, np.arctan2(s, co), thdd

    def hinge_loads(self, phis, q, qd, qdd):
        """(N, P, M): the force and moment the body exerts on the beam tip, from the body's Newton-Euler
        equations (module docstring); q, qd, qdd on the reduced model's motion."""
        p = self.p
        Cxdd, Cydd, th, thdd = self._body_accel(phis, q, qd, qdd)
        N = p["M2"] * (p["g"] - Cxdd)
        P = -p["M2"] * Cydd
        M = p["r"] * (P * np.cos(th) - N * np.sin(th)) - p["J_C"] * thdd
        return N, P, M

    def root_loads(self, phis, q, qd, qdd):
        """(M_root, Q_root): the clamp's reactions by d'Alembert's principle with the virtual rigid
        translation and rotation of beam and body (module docstring)."""
        p = self.p
        m, l, r, M2, g = p["m"], p["l"], p["r"], p["M2"], p["g"]
        q, qd, qdd = (np.asarray(a, dtype=float) for a in (q, qd, qdd))
        xq, wq = quadrature(self.basis.breaks, self.basis.quad_points)
        B0 = self.basis.eval(xq, 0)
        # the beam's inertia and mass-proportional damping force density m (v_tt + alpha v_t)
        f = m * ((qdd + self.alpha * qd) @ B0.T)
        Cxdd, Cydd, th, thdd = self._body_accel(phis, q, qd, qdd)
        v1 = q @ self.b
        Cy = v1 + r * np.sin(th)
        Q_root = np.sum(wq * f, axis=-1) + M2 * Cydd
        E_rot = (
            np.sum(wq * xq * f, axis=-1)
            + M2 * (Cydd * (l + r * np.cos(th)) - Cxdd * Cy)
            + p["J_C"] * thdd
            + M2 * g * Cy
        )
        if self.beam_gravity:
            E_rot = E_rot + m * g * np.sum(wq * (q @ B0.T), axis=-1)
        return -E_rot, Q_root

    def clamp_reactions(self, phis, q, qd, qdd):
        """(M_root, Q_root) a second way: (-R_th0, R_v0), R the residual rows of the clamped node of the
        same model with the clamp's dofs freed (HermiteBasis(free_root=True)), at the clamped state
        (v_0 = th_0 = 0 and their rates); also returns the freed model's other rows, which the clamped
        model's accelerations make zero. Hermite elements only."""
        if not isinstance(self.basis, HermiteBasis) or self.basis.free_root:
            raise ValueError("clamp_reactions: a clamped Hermite model")
        free = Model(HermiteBasis(self.basis.n, self.p["l"], free_root=True), self.p,
                     (self.alpha, self.beta), self.beam_gravity)
        pad = lambda a: np.concatenate([np.zeros(np.shape(a)[:-1] + (2,)), a], axis=-1)  # noqa: E731
        R = free.residual_reduced(phis, pad(np.asarray(q, float)), pad(np.asarray(qd, float)),
                                  pad(np.asarray(qdd, float)))
        return -R[..., 1], R[..., 0], R[..., 2:]

    # ---- mass matrices and accelerations -----------------------------------------------------------
    def mass_matrix(self, q, phi):
        """M(q) = M_b + M2 A^T A + J_C c c^T (checked against dR/dqdd in the tests)."""
        p = self.p
        q = np.asarray(q, dtype=float)
        th = q @ self.c + np.asarray(phi)
        a_x = -(q @ self.G) - p["r"] * np.sin(th)[..., None] * self.c
        a_y = self.b + p["r"] * np.cos(th)[..., None] * self.c
        outer = lambda u, v: u[..., :, None] * v[..., None, :]  # noqa: E731
        return self.Mb + p["M2"] * (outer(a_x, a_x) + outer(a_y, a_y)) + p["J_C"] * np.outer(self.c, self.c)

    def accelerations(self, phis, q, qd, formulation="reduced"):
        """qdd solving R(q, qd, qdd) = 0 for the reduced or linear formulation."""
        q = np.asarray(q, dtype=float)
        qd = np.asarray(qd, dtype=float)
        if formulation == "reduced":
            ph = np.broadcast_to(np.asarray(phis[0], dtype=float), q.shape[:-1])
            Mq = self.mass_matrix(q, ph)
            rhs = -self.residual_reduced(phis, q, qd, np.zeros_like(q))
        elif formulation == "linear":
            R0, Jq, Jqd, M0 = self.linear_parts(phis)
            Mq = M0
            rhs = -(R0 + np.einsum("...ij,...j->...i", Jq, q) + np.einsum("...ij,...j->...i", Jqd, qd))
        elif formulation in ("dae", "dae_stabilized"):
            raise ValueError("use accelerations_dae for the dae formulation")
        else:
            raise ValueError(formulation)
        Mq, rhs = np.broadcast_arrays(Mq, rhs[..., None])
        return np.linalg.solve(Mq, rhs)[..., 0]

    def dae_mass_b(self, phis, q, u2, qd, du2):
        """(Mass (..., ndof+1, ndof+1), b (..., ndof+1)) of the dae residual, exact by affinity:
        column j = R(e_j) - R(0)."""
        q = np.asarray(q, dtype=float)
        n = self.ndof
        u2 = np.asarray(u2, dtype=float)
        du2 = np.asarray(du2, dtype=float)

        def Rfull(qdd, ddu2):
            Rq, Ru = self.residual_dae(phis, q, u2, qd, du2, qdd, ddu2)
            return np.concatenate([Rq, np.asarray(Ru)[..., None]], axis=-1)

        zq = np.zeros(q.shape)
        zu = np.zeros(q.shape[:-1])
        b = Rfull(zq, zu)
        cols = []
        for j in range(n + 1):
            e = np.zeros(n + 1)
            e[j] = 1.0
            cols.append(Rfull(zq + e[:n], zu + e[n]) - b)
        return np.stack(cols, axis=-1), b

    def accelerations_dae(self, phis, q, u2, qd, du2):
        """(qdd, ddu2) of the dae formulation."""
        Mm, b = self.dae_mass_b(phis, q, u2, qd, du2)
        a = np.linalg.solve(Mm, -b[..., None])[..., 0]
        return a[..., :-1], a[..., -1]

    # ---- energy-integral Lagrangian (no assembled matrices: for the finite-difference checks) --------
    def lagrangian(self, q, qd, phi, dphi, uh=None, duh=None, npts=None):
        """(L, F_Rayleigh) from the energy integrals evaluated on the field itself by quadrature (more
        points than the assembly uses); u_h = u1(q) (reduced) unless uh/duh are given (the DAE's
        free coordinate). Complex-safe. Returns L = T1 + T2 - Pi1 - Pi2 (- Pi_w with the beam's weight)
        and the Rayleigh dissipation F = 1/2 int (alpha m vdot^2 + beta EI vdot''^2) dx.

        The beam's weight, Pi_w = -int m g (s + u(s)) ds, is the double integral itself: u(s) at each
        outer point s by its own composite rule on [0, s] (not K_w, whose single integral comes from
        exchanging the order)."""
        p = self.p
        basis = self.basis
        xq, wq = quadrature(basis.breaks, (npts or basis.quad_points + 3))
        B0, B1, B2 = (basis.eval(xq, d) for d in (0, 1, 2))
        v1f, v2f = q @ B1.T, q @ B2.T
        vt0, vt1, vt2 = qd @ B0.T, qd @ B1.T, qd @ B2.T
        T1 = 0.5 * p["m"] * np.sum(wq * vt0**2, axis=-1)
        Pi1 = 0.5 * p["EI"] * np.sum(wq * v2f**2, axis=-1)
        if uh is None:
            uh = -0.5 * np.sum(wq * v1f**2, axis=-1)
            duh = -np.sum(wq * v1f * vt1, axis=-1)
        bl = basis.eval([p["l"]], 0)[0]
        cl = basis.eval([p["l"]], 1)[0]
        v1, th1, dv1, dth1 = q @ bl, q @ cl, qd @ bl, qd @ cl
        th = th1 + phi
        thd = dth1 + dphi
        r = p["r"]
        xCd = duh - r * np.sin(th) * thd
        yCd = dv1 + r * np.cos(th) * thd
        T2 = 0.5 * p["M2"] * (xCd**2 + yCd**2) + 0.5 * p["J_C"] * thd**2
        Pi2 = -p["M2"] * p["g"] * (uh + r * np.cos(th))
        F = 0.5 * np.sum(wq * (self.alpha * p["m"] * vt0**2 + self.beta * p["EI"] * vt2**2), axis=-1)
        L = T1 + T2 - Pi1 - Pi2
        if self.beam_gravity:
            S, B1in = self._inner_rule(xq, npts or basis.quad_points + 3)
            u = -0.5 * (q @ B1in.T) ** 2 @ S.T  # u(x_j) = -1/2 int_0^x_j v'^2
            L = L + p["m"] * p["g"] * np.sum(wq * (xq + u), axis=-1)  # - Pi_w
        return L, F

    def _inner_rule(self, xq, npts):
        """For the outer points xq: (S, B1) with S (len(xq), P) the weights of the composite rules on
        [0, x_j] (npts points between breaks) over their P inner points together, and B1 the shape
        functions' slopes at those points."""
        pts, rows = [], []
        for xj in xq:
            br = np.append(self.basis.breaks[self.basis.breaks < xj], xj)
            xi, wi = quadrature(br, npts)
            pts.append(xi)
            rows.append(wi)
        S = np.zeros((len(xq), sum(len(w) for w in rows)))
        k = 0
        for j, w in enumerate(rows):
            S[j, k : k + len(w)] = w
            k += len(w)
        return S, self.basis.eval(np.concatenate(pts), 1)

    def energy(self, phis, q, qd):
        """Total energy T1 + T2 + Pi1 + Pi2 (+ Pi_w) of the reduced model (from the assembled matrices;
        the potentials without their constants -M2 g l and -m g l^2 / 2)."""
        p = self.p
        ph, dph, _ = _phis(phis)
        q, qd = np.asarray(q), np.asarray(qd)
        uh, duh = self.u1(q), self.du1(q, qd)
        th = q @ self.c + ph
        thd = qd @ self.c + dph
        T1 = 0.5 * np.einsum("...i,ij,...j->...", qd, self.Mb, qd)
        Pi1 = 0.5 * np.einsum("...i,ij,...j->...", q, self.K, q)
        xCd = duh - p["r"] * np.sin(th) * thd
        yCd = qd @ self.b + p["r"] * np.cos(th) * thd
        T2 = 0.5 * p["M2"] * (xCd**2 + yCd**2) + 0.5 * p["J_C"] * thd**2
        Pi2 = -p["M2"] * p["g"] * (uh + p["r"] * np.cos(th))
        Piw = 0.5 * np.einsum("...i,ij,...j->...", q, self.Kw, q)
        return T1 + T2 + Pi1 + Pi2 + Piw

    # ---- fast scalar right-hand side (reduced) -----------------------------------------------------
    def _rhs_reduced(self):
        """f(phi, dphi, ddphi, q, qd) -> qdd for one state: M(q) = M_b + U U^T (rank 3) solved by the
        Sherman-Morrison-Woodbury identity with M_b^-1 precomputed (Golub & Van Loan, Matrix
        Computations, §2.1.4). Checked against accelerations() in the tests."""
        p = self.p
        r, M2, J_C, g = p["r"], p["M2"], p["J_C"], p["g"]
        b, c, G, D = self.b, self.c, self.G, self.D
        K = self.K + self.Kw  # the beam's weight: a stiffness
        Mbi = self._Mb_inv
        Mbi_c = Mbi @ c
        Mbi_b = Mbi @ b
        sM2, sJ = math.sqrt(M2), math.sqrt(J_C)
        damped = bool(np.any(D))

        def f(ph, dph, ddph, q, qd):
            Gq = G @ q
            th = c @ q + ph
            thd = c @ qd + dph
            s, co = math.sin(th), math.cos(th)
            a_x = -Gq - (r * s) * c
            a_y = b + (r * co) * c
            Cx0 = -(qd @ G @ qd) - r * s * ddph - r * co * thd * thd
            Cy0 = r * co * ddph - r * s * thd * thd
            rhs = -(K @ q + M2 * (a_x * Cx0 + a_y * Cy0) + (J_C * ddph) * c + (M2 * g) * (Gq + (r * s) * c))
            if damped:
                rhs -= D @ qd
            # Woodbury with U = [sqrt(M2) a_x, sqrt(M2) a_y, sqrt(J_C) c]
            Mbi_ax = -(Mbi @ Gq) - (r * s) * Mbi_c
            Mbi_ay = Mbi_b + (r * co) * Mbi_c
            Z = np.stack([sM2 * Mbi_ax, sM2 * Mbi_ay, sJ * Mbi_c], axis=1)  # M_b^-1 U
            U = np.stack([sM2 * a_x, sM2 * a_y, sJ * c], axis=1)
            y = Mbi @ rhs
            S = np.eye(3) + U.T @ Z
            return y - Z @ np.linalg.solve(S, U.T @ y)

        return f


def model(n, params=None, basis="hermite", damping=(0.0, 0.0), beam_gravity=False) -> Model:
    """The n-element (Hermite) or n-function (poly) model. params may also hold damping_alpha [1/s] and
    damping_beta [s] (they override damping = (alpha, beta)); beam_gravity: the beam's own weight."""
    p = full_params(params)
    return Model(make_basis(basis, n, p["l"]), params, damping, beam_gravity)


# --------------------------------------------------------------------------------------------------
# Trajectories
# --------------------------------------------------------------------------------------------------


@dataclass
class Trajectory:
    t: np.ndarray
    v1: np.ndarray
    theta1: np.ndarray
    u2: np.ndarray  # u1(q) for reduced/linear, the coordinate for dae
    q: np.ndarray  # (len(t), ndof)
    qd: np.ndarray
    du2: np.ndarray
    model: Model = field(repr=False, default=None)
    stats: dict = field(default_factory=dict)
    scene: dict = field(default=None)  # the scene with its defaults (for phi along t)

    def v(self, x, d=0):
        """(len(t), len(x)): d-th x-derivative of v at the points x along the trajectory."""
        return self.model.field(self.q, x, d)

    def root_moment(self):
        """EI v''(0, t): the elements' own curvature at the clamp (not the clamp's reaction M_root)."""
        return self.model.p["EI"] * self.v([0.0], 2)[:, 0]

    def phis(self):
        """(phi, phi', phi'') at t (right-continuous: at t_rot, the hold's)."""
        return phi_at(self.scene, self.t)

    def accelerations(self):
        """q'' along t from the model's own equations (reduced; the linear formulation's own for a
        linear trajectory is not offered)."""
        return self.model.accelerations(self.phis(), self.q, self.qd)

    def loads(self):
        """{N, P, M, M_root, Q_root} along t (module docstring, "Loads"), on the reduced model's
        motion."""
        phis, qdd = self.phis(), self.accelerations()
        N, P, M = self.model.hinge_loads(phis, self.q, self.qd, qdd)
        M_root, Q_root = self.model.root_loads(phis, self.q, self.qd, qdd)
        return {"N": N, "P": P, "M": M, "M_root": M_root, "Q_root": Q_root}


def output_grid(scene):
    s = scene_with_defaults(scene)
    n = int(math.floor(s["t_end"] / s["dt_out"] + 1e-9))
    grid = np.arange(n + 1) * s["dt_out"]
    if s["t_end"] - grid[-1] > 1e-9 * max(1.0, s["t_end"]):
        grid = np.append(grid, s["t_end"])
    return grid


def phi_at(scene, t):
    """(phi, phi', phi'') of the scene's law at the times t, right-continuous (at t_rot: the hold)."""
    s = scene_with_defaults(scene)
    t = np.asarray(t, dtype=float)
    law = _law_fn(s)
    turning = (s["t_rot"] > 0) and (s["phi_end"] != s["phi0"])
    inside = (t < s["t_rot"]) if turning else np.zeros(t.shape, dtype=bool)
    return tuple(np.where(inside, a, b) for a, b in zip(law(t, True), law(t, False)))


def _segments(s, t_end):
    """Integration segments: phi'' jumps at 0 and t_rot."""
    t_rot = s["t_rot"]
    if t_rot > 0 and s["phi_end"] != s["phi0"] and t_rot < t_end:
        return [(0.0, t_rot, True), (t_rot, t_end, False)]
    if t_rot > 0 and s["phi_end"] != s["phi0"]:
        return [(0.0, t_end, True)]
    return [(0.0, t_end, False)]


def _law_fn(s):
    """law(t, turning) -> (phi, dphi, ddphi) for the scene (arrays or floats)."""
    w = math.pi / (2.0 * s["t_rot"]) if s["t_rot"] > 0 else 0.0
    phi0, dphi_tot = s["phi0"], s["phi_end"] - s["phi0"]
    held = s["phi_end"] if s["t_rot"] > 0 else s["phi0"]

    def law(tt, turning):
        if turning:
            return (
                phi0 + dphi_tot * np.sin(w * tt) ** 2,
                dphi_tot * w * np.sin(2 * w * tt),
                2 * dphi_tot * w * w * np.cos(2 * w * tt),
            )
        z = np.zeros_like(np.asarray(tt, dtype=float))
        return z + held, z, z

    return law


def _residual_and_jac(mdl, formulation):
    """(resid(phis, x, x', x''), jac(phis, x, x', x'') -> (M, C, K)) of a formulation in the
    coordinates x = q (reduced, linear) or x = (q, u2) (dae)."""
    n = mdl.ndof
    if formulation == "reduced":
        resid = mdl.residual_reduced

        def jac(phis, x, v, a):
            return _jac_complex_step(resid, phis, x, v, a)

    elif formulation == "linear":
        resid = mdl.residual_linear

        def jac(phis, x, v, a):
            _, Jq, Jqd, M0 = mdl.linear_parts(phis)
            shape = np.shape(x)[:-1] + (n, n)
            return tuple(np.broadcast_to(J, shape) for J in (M0, Jqd, Jq))

    elif formulation in ("dae", "dae_stabilized"):

        def resid(phis, X, Xd, Xdd):
            Rq, Ru = mdl.residual_dae(
                phis, X[..., :n], X[..., n], Xd[..., :n], Xd[..., n], Xdd[..., :n], Xdd[..., n]
            )
            return np.concatenate([Rq, np.asarray(Ru)[..., None] + np.zeros(Rq.shape[:-1] + (1,))], axis=-1)

        def jac(phis, x, v, a):
            return _jac_complex_step(resid, phis, x, v, a)

    else:
        raise ValueError(formulation)
    return resid, jac


def _integrate(mdl, formulation, s, t_eval, x0, v0, method, rtol, atol, h, stages):
    """Y (len(t_eval), 2 nx) = (x, x'), stats."""
    segments = _segments(s, float(t_eval[-1]))
    law = _law_fn(s)
    resid, jac = _residual_and_jac(mdl, formulation)
    nx = len(x0)
    if method == "gauss":
        return gauss_integrate(resid, jac, law, segments, t_eval, x0, v0, h, stages)
    if method != "DOP853":
        raise ValueError(f"method {method!r}: 'gauss' or 'DOP853'")
    from scipy.integrate import solve_ivp

    if formulation == "reduced":
        f = mdl._rhs_reduced()

        def acc(ph, x, v):
            return f(*ph, x, v)

    else:

        def acc(ph, x, v):
            ph1 = tuple(np.array([p]) for p in ph)
            Mx = jac(ph1, x[None], v[None], np.zeros((1, nx)))[0][0]
            return np.linalg.solve(Mx, -resid(ph1, x[None], v[None], np.zeros((1, nx)))[0])

    Y = np.empty((len(t_eval), 2 * nx))
    y = np.concatenate([x0, v0]).astype(float)
    nfev = 0
    for a, bnd, turning in segments:

        def rhs(tt, yy, turning=turning):
            ph = tuple(float(p) for p in law(tt, turning))
            return np.concatenate([yy[nx:], acc(ph, yy[:nx], yy[nx:])])

        sol = solve_ivp(rhs, (a, bnd), y, method="DOP853", rtol=rtol, atol=atol, dense_output=True)
        assert sol.success, sol.message
        nfev += sol.nfev
        msk = (t_eval >= a) & (t_eval <= bnd)
        Y[msk] = sol.sol(t_eval[msk]).T
        y = sol.y[:, -1]
    return Y, {"nfev": nfev}


def gauss_coefficients(s):
    """Butcher tableau (c, A, b) of the s-stage Gauss-Legendre collocation method (order 2s, A-stable,
    symplectic; Butcher, Math. Comp. 18 (1964) 50; Hairer & Wanner, Solving ODEs II, §IV.5): c_i the
    Gauss nodes on [0, 1], a_ij = int_0^c_i l_j, b_j = int_0^1 l_j with l_j the Lagrange polynomials
    on c. The integrals are evaluated by s-point Gauss quadrature on [0, c_i] (exact: l_j has degree
    s - 1) of l_j in product form, which keeps them at round-off (~1e-16; power-series coefficients
    lost 4e-13 at s = 8)."""
    xg, wg = np.polynomial.legendre.leggauss(s)
    c = 0.5 * (xg + 1.0)

    def lag(j, tau):
        others = np.delete(c, j)
        return np.prod((tau[:, None] - others) / (c[j] - others), axis=1)

    A = np.zeros((s, s))
    b = np.zeros(s)
    for j in range(s):
        for i in range(s):
            tau = 0.5 * c[i] * (xg + 1.0)
            A[i, j] = 0.5 * c[i] * np.sum(wg * lag(j, tau))
        b[j] = 0.5 * np.sum(wg * lag(j, c))  # = w_j / 2
    return c, A, b


def _jac_complex_step(resid, phis, x, v, a, h=1e-30):
    """(dR/da, dR/dv, dR/dx), each (..., n, n) [row = residual component], of a complex-safe residual
    R(phis, x, v, a) at a batch of points x, v, a (..., n) with phis (...), by the complex step."""
    n = x.shape[-1]
    E = np.eye(n) * (1j * h)
    pb = tuple(np.asarray(p, dtype=float)[..., None] for p in phis)
    X, V, Aa = (np.asarray(u)[..., None, :] + np.zeros((n, n), dtype=complex) for u in (x, v, a))
    out = []
    for k in range(3):
        args = [X, V, Aa]
        args[2 - k] = args[2 - k] + E
        out.append(np.swapaxes(np.imag(resid(pb, *args)), -1, -2) / h)
    return tuple(out)


NEWTON_NOISE = 1e-7  # see gauss_integrate


def gauss_integrate(resid, jac, law, segments, t_eval, x0, v0, h, stages=8, maxit=25, tol=1e-15):
    """Integrate the second-order system R(phis, x, x', x'') = 0 (R affine in x'') by the s-stage
    Gauss-Legendre method in Nystrom form (Hairer, Norsett & Wanner, Solving ODEs I, §II.14): the
    unknowns are the stage accelerations A_i, with V_i = v0 + h sum_j a_ij A_j and
    X_i = x0 + c_i h v0 + h^2 sum_j (a^2)_ij A_j. The method is A-stable, so the step is not limited by
    the stiff high element modes. Fixed steps of at most h; every time in t_eval and every segment
    bound is a step end (no interpolation).

    The stage equations are solved by simplified Newton with the Jacobian I (x) M + h a (x) C +
    h^2 a^2 (x) K (M, C, K = dR/dx'', dR/dx', dR/dx from jac at the mean of the stage values; the stiff
    elastic part is linear, so it is exact there), decoupled by the eigendecomposition a = T L T^-1
    into s complex n x n systems M + h l_i C + h^2 l_i^2 K (the transformation Butcher (1976) and
    Hairer & Wanner, Solving ODEs II, §IV.8 use for Radau IIA); conjugate eigenvalues give conjugate
    solutions, so only one of each pair is factorized. The Jacobian is refreshed whenever an iteration
    contracts by less than 10x, and after the first iteration (the first is taken at the guess).

    jac(phis, x, v, a) -> (M, C, K) batched like _jac_complex_step; law(t_array, turning) ->
    (phi, dphi, ddphi) arrays. Returns Y (len(t_eval), 2 n) = (x, x') at t_eval, and stats."""
    from scipy.linalg import lu_factor, lu_solve

    c, A, bw = gauss_coefficients(stages)
    A2 = A @ A
    bA = bw @ A
    lam, T = np.linalg.eig(A)
    Tinv = np.linalg.inv(T)
    # one representative per conjugate pair: (index, index of its conjugate or None)
    reps, done = [], set()
    for i in range(stages):
        if i in done:
            continue
        j = None
        if abs(lam[i].imag) > 1e-14:
            cand = [k for k in range(stages) if k != i and k not in done and abs(lam[k] - np.conj(lam[i])) < 1e-10]
            j = cand[0]
            done.add(j)
        done.add(i)
        reps.append((i, j))
    n = len(x0)
    x = np.array(x0, dtype=float)
    v = np.array(v0, dtype=float)
    Y = np.full((len(t_eval), 2 * n), np.nan)
    t_eval = np.asarray(t_eval, dtype=float)
    stats = {"steps": 0, "newton": 0, "max_newton": 0, "jacobians": 0, "max_err": 0.0}
    eps_t = 1e-12
    xmax, vmax = np.max(np.abs(x)), np.max(np.abs(v))
    for a_seg, b_seg, turning in segments:
        inner = t_eval[(t_eval > a_seg + eps_t) & (t_eval < b_seg - eps_t)]
        pts = np.concatenate([[a_seg], inner, [b_seg]])
        at_start = np.abs(t_eval - a_seg) <= eps_t
        Y[at_start] = np.concatenate([x, v])
        Ast = None  # no guess across a jump of phi''
        for t0, t1 in zip(pts[:-1], pts[1:]):
            m = max(1, int(math.ceil((t1 - t0) / h - 1e-9)))
            hh = (t1 - t0) / m
            for k in range(m):
                ts = t0 + k * hh
                phs = law(ts + c * hh, turning)
                phm = tuple(np.atleast_1d(p) for p in law(np.array([ts + 0.5 * hh]), turning))
                if Ast is not None:
                    pass  # the previous step's stage accelerations (a polynomial extrapolation of
                    # them amplifies the stiff modes' components: measured worse)
                else:  # the acceleration at the step start
                    ph0 = tuple(np.atleast_1d(p) for p in law(np.array([ts]), turning))
                    M0 = jac(ph0, x[None], v[None], np.zeros((1, n)))[0][0]
                    R0 = resid(ph0, x[None], v[None], np.zeros((1, n)))[0]
                    Ast = np.tile(np.linalg.solve(M0, -R0), (stages, 1))
                prev, lus = np.inf, None
                for it in range(maxit):
                    Q = x + hh * c[:, None] * v + hh * hh * (A2 @ Ast)
                    V = v + hh * (A @ Ast)
                    R = resid(phs, Q, V, Ast)
                    if lus is None:
                        Mj, Cj, Kj = (J[0] for J in jac(phm, Q.mean(0)[None], V.mean(0)[None], Ast.mean(0)[None]))
                        lus = {i: lu_factor(Mj + hh * lam[i] * Cj + (hh * lam[i]) ** 2 * Kj, check_finite=False)
                               for i, _ in reps}
                        stats["jacobians"] += 1
                    Rt = Tinv @ R
                    dW = np.empty((stages, n), dtype=complex)
                    for i, j in reps:
                        dW[i] = lu_solve(lus[i], -Rt[i], check_finite=False)
                        if j is not None:
                            dW[j] = np.conj(dW[i])
                    dA = np.real(T @ dW)
                    Ast = Ast + dA
                    # the increment's effect on the stage values (X_i, V_i), relative to the largest
                    # state so far (a norm that contracts monotonically; projections such as b.dA need
                    # not; the running maximum keeps it meaningful where all velocities vanish)
                    xs = max(xmax, np.max(np.abs(x + hh * v + hh * hh * (bA @ Ast)))) + 1e-300
                    vs = max(vmax, np.max(np.abs(v + hh * (bw @ Ast)))) + 1e-300
                    err = max(hh * hh * np.max(np.abs(A2 @ dA)) / xs, hh * np.max(np.abs(A @ dA)) / vs)
                    # converged: below tol, or stagnating at the round-off level: round-off
                    # delta x ~ eps |x| becomes delta a ~ omega_max^2 eps |x| in the stiffest mode,
                    # h omega_max^2 eps ~ 1e-9 relative in v for 32 elements at h = 2 ms (a
                    # displacement h omega_max eps |x| ~ 1e-14 |x|: harmless)
                    if err <= tol or (it >= 2 and err >= 0.5 * prev and err <= NEWTON_NOISE):
                        break
                    if it == 0 or err > 0.1 * prev:
                        # refresh the Jacobian after the first iteration (it was taken at the guess,
                        # the previous step's accelerations) and whenever the contraction is slow
                        lus = None
                    prev = err
                else:
                    if err > NEWTON_NOISE:
                        raise RuntimeError(f"Gauss step at t={ts}: Newton did not converge ({err})")
                stats["max_err"] = max(stats["max_err"], float(err))
                stats["newton"] += it + 1
                stats["max_newton"] = max(stats["max_newton"], it + 1)
                stats["steps"] += 1
                x = x + hh * v + hh * hh * (bA @ Ast)
                v = v + hh * (bw @ Ast)
                xmax = max(xmax, np.max(np.abs(x)))
                vmax = max(vmax, np.max(np.abs(v)))
            hit = np.abs(t_eval - t1) <= eps_t
            Y[hit] = np.concatenate([x, v])
    return Y, stats


def _cache_key(obj):
    h = hashlib.sha256()
    h.update(json.dumps(obj, sort_keys=True).encode())
    h.update(Path(__file__).read_bytes())
    import scipy

    h.update(scipy.__version__.encode())
    h.update(np.__version__.encode())
    return h.hexdigest()[:20]


_MEMO: dict = {}

#: default step bound of the Gauss method [s] (with 8 stages: 1e-13 from DOP853 for n <= 4 over
#: [0, 2 s]; see the module docstring for the paper's scene over 10.2 s)
DEFAULT_H = 2e-3


def save_trajectory(path, Y, stats):
    """Writes a cached trajectory atomically (a temporary file in the cache, renamed)."""
    CACHE_DIR.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=CACHE_DIR, suffix=".npz")
    os.close(fd)
    np.savez(tmp, Y=Y, stats=json.dumps(stats))
    os.replace(tmp, path)


def trajectory(
    n,
    formulation="reduced",
    scene=None,
    basis="hermite",
    t_eval=None,
    rtol=1e-12,
    atol=1e-14,
    method="gauss",
    h=None,
    stages=8,
    damping=(0.0, 0.0),
    q0=None,
    qd0=None,
    cache=True,
    beam_gravity=False,
):
    """Integrate the n-element / n-function model on t_eval (default: the scene's output grid), per
    segment [0, t_rot], [t_rot, t_end] (phi'' jumps at both ends of the turn). Returns a Trajectory
    (t, v1, theta1, u2, q, qd, du2; u2 = u1(q) for reduced/linear, the coordinate for dae).

    method "gauss" (default): the implicit Gauss-Legendre method of gauss_integrate with `stages`
    stages (order 2 stages) and steps of at most h (default DEFAULT_H), unaffected by the stiffness of
    the high element modes (omega_max ~ 1.8e5 rad/s for 32 Hermite elements). method "DOP853":
    scipy's explicit Dormand-Prince 8(5,3) with rtol/atol (resolves the highest mode: slow for
    stiff cases; for cross-checks). scipy's Radau (with the exact Jacobian) was tried: 0.7e6 to 2e6
    evaluations for 4 elements over 2 s at rtol 1e-10..1e-12, slower than DOP853, so it is not offered.

    q0, qd0: initial coordinates (default zero; the dae starts consistent, u2 = u1(q0)).
    beam_gravity: the beam's own weight (module docstring).
    Cached in target/oracle-cache (npz, keyed by the arguments, this file's text and the scipy and
    numpy versions) and in memory."""
    s = scene_with_defaults(scene)
    params = {k: s[k] for k in PARAM_NAMES}
    for k in DAMPING_NAMES:
        if k in s:
            params[k] = s[k]
    mdl = model(n, params, basis, damping, beam_gravity)
    if t_eval is None:
        t_eval = output_grid(s)
    t_eval = np.asarray(t_eval, dtype=float)
    h = DEFAULT_H if h is None else float(h)
    nd = mdl.ndof
    q0 = np.zeros(nd) if q0 is None else np.asarray(q0, dtype=float)
    qd0 = np.zeros(nd) if qd0 is None else np.asarray(qd0, dtype=float)
    dae = formulation in ("dae", "dae_stabilized")
    key = _cache_key(
        [n, formulation, s, basis, list(map(float, t_eval)), rtol, atol, method, h, stages,
         [mdl.alpha, mdl.beta], list(map(float, q0)), list(map(float, qd0))]
        + (["beam_gravity"] if mdl.beam_gravity else [])
    )
    if key in _MEMO:
        Y, stats = _MEMO[key]
    else:
        path = CACHE_DIR / f"oracle_n-{key}.npz"
        Y = None
        if cache and path.is_file():
            try:
                with np.load(path) as z:
                    Y, stats = z["Y"], json.loads(str(z["stats"]))
                    stats["cached"] = True
            except Exception:  # corrupt cache: recompute
                Y = None
        if Y is None:
            if dae:
                x0 = np.concatenate([q0, [mdl.u1(q0)]])
                v0 = np.concatenate([qd0, [mdl.du1(q0, qd0)]])
            else:
                x0, v0 = q0, qd0
            Y, stats = _integrate(mdl, formulation, s, t_eval, x0, v0, method, rtol, atol, h, stages)
            assert np.all(np.isfinite(Y)), "trajectory: not every output time was reached"
            if cache:
                save_trajectory(path, Y, stats)
        _MEMO[key] = (Y, stats)
    if dae:
        q, u2, qd, du2 = Y[:, :nd], Y[:, nd], Y[:, nd + 1 : 2 * nd + 1], Y[:, 2 * nd + 1]
    else:
        q, qd = Y[:, :nd], Y[:, nd:]
        u2, du2 = mdl.u1(q), mdl.du1(q, qd)
    v1, th1 = mdl.tip(q)
    return Trajectory(t_eval, v1, th1, u2, q, qd, du2, mdl, dict(stats), s)


# --------------------------------------------------------------------------------------------------
# Small oscillations about the static equilibrium at a held phi
# --------------------------------------------------------------------------------------------------


def tangent_stiffness(mdl, q, phi, h=1e-30):
    """dR/dq of the reduced residual at rest (qd = qdd = 0, phi' = phi'' = 0), by the complex step."""
    n = mdl.ndof
    E = np.eye(n) * (1j * h)
    z = np.zeros((n, n))
    R = mdl.residual_reduced((np.full(n, phi), 0.0, 0.0), q + E, z, z)
    return np.imag(R).T / h


def static_equilibrium(mdl, phi, tol=1e-12, maxit=50):
    """Newton's method on R(q, 0, 0) = 0 at phi' = phi'' = 0 from q = 0, with the exact tangent
    stiffness (complex step) and step halving if the residual grows. Converged when the residual is
    below tol times its terms' size (|K| |q| + M2 g (|G| |q| + r |c|): the elastic forces' round-off
    grows with the stiffness of the finest elements), after at least one full Newton step."""
    n = mdl.ndof
    z = np.zeros(n)
    p = mdl.p

    def res(q):
        return mdl.residual_reduced((phi, 0.0, 0.0), q, z, z)

    def scale(q):
        aq = np.abs(q)
        gravity = abs(p["M2"] * p["g"]) * (np.abs(mdl.G) @ aq + abs(p["r"]) * np.abs(mdl.c))
        return np.abs(mdl.K) @ aq + np.abs(mdl.Kw) @ aq + gravity + 1e-300

    return damped_newton(res, lambda q: tangent_stiffness(mdl, q, phi), scale, np.zeros(n), tol, maxit,
                         f"static equilibrium at phi={phi}")


def damped_newton(res, jac, scale, q, tol, maxit, what):
    """Newton's method on res(q) = 0 from q, the step halved while the residual's norm grows; converged
    when |res| <= tol * scale(q) componentwise, after at least one full step unless res(q) vanishes at
    the start. Raises RuntimeError naming `what` otherwise."""
    Rq = res(q)
    for it in range(maxit):
        if np.all(np.abs(Rq) <= tol * scale(q)) and (it > 0 or not np.any(Rq)):
            return q
        dq = np.linalg.solve(jac(q), -Rq)
        lam = 1.0
        while True:
            qn = q + lam * dq
            Rn = res(qn)
            if np.linalg.norm(Rn) < np.linalg.norm(Rq) or lam < 1e-6:
                break
            lam *= 0.5
        q, Rq = qn, Rn
    raise RuntimeError(f"{what}: Newton did not converge, |R| / scale = {np.max(np.abs(Rq) / scale(q))}")


def small_oscillations(n, phi, params=None, basis="hermite", damping=(0.0, 0.0), beam_gravity=False):
    """(q*, omega^2 ascending, modes (columns, mass-normalized), M(q*), K_T(q*), model)."""
    from scipy.linalg import eigh

    mdl = model(n, params, basis, damping, beam_gravity)
    q = static_equilibrium(mdl, phi)
    KT = tangent_stiffness(mdl, q, phi)
    asym = np.max(np.abs(KT - KT.T)) / np.max(np.abs(KT))
    assert asym < 1e-10, asym  # a conservative system at rest: the tangent stiffness is symmetric
    KT = 0.5 * (KT + KT.T)
    Mq = mdl.mass_matrix(q, phi)
    w2, V = eigh(KT, Mq)
    return q, w2, V, Mq, KT, mdl


def natural_frequencies(n, phi, params=None, basis="hermite", k=None, beam_gravity=False):
    """Ascending angular frequencies omega [rad/s] of small oscillations about the static equilibrium at a
    held phi (phi' = phi'' = 0); the first k (all by default). An unstable mode (omega^2 <= 0) raises."""
    _, w2, _, _, _, _ = small_oscillations(n, phi, params, basis, beam_gravity=beam_gravity)
    if np.any(w2 <= 0):
        raise ValueError(f"unstable equilibrium at phi={phi}: omega^2 = {w2[w2 <= 0]}")
    w = np.sqrt(w2)
    return w if k is None else w[:k]


# --------------------------------------------------------------------------------------------------
# Continuum reference at phi = 0: the beam-column under the body's pull with the body rigidly fixed
# --------------------------------------------------------------------------------------------------


def continuum_frequencies(k, params=None, w_max=None, npts=4000):
    """The first k angular frequencies of the continuum linearization at phi = 0 (q = 0 is the static
    equilibrium there): the quadratic forms of the model at phi = 0,
        stiffness  EI int v''^2 + P int v'^2 + P r v'(l)^2,   P = M2 g   (from Pi1 and Pi2 = -M2 g (u1 + r cos))
        mass       m int v^2 + M2 (v(l) + r v'(l))^2 + J_C v'(l)^2,
    give by the calculus of variations EI v'''' - P v'' - m w^2 v = 0 on (0, l), v(0) = v'(0) = 0 and at l
        -EI v''' + P v' - w^2 M2 (v + r v') = 0,     EI v'' + P r v' - w^2 (M2 r (v + r v') + J_C v') = 0.
    With s^2 = (P +- sqrt(P^2 + 4 EI m w^2)) / (2 EI) = a^2, -b^2 the solution is
    v = A1 (cosh a x - cos b x) + A2 (sinh a x / a - sin b x / b) (clamp built in); the 2x2 determinant of
    the tip conditions vanishes at the frequencies (scanned for sign changes, refined by brentq)."""
    from scipy.optimize import brentq

    p = full_params(params)
    l, EI, m, M2, J_C, r, g = (p[k_] for k_ in PARAM_NAMES)
    P = M2 * g

    def det(w):
        disc = math.sqrt(P * P + 4 * EI * m * w * w)
        a = math.sqrt((P + disc) / (2 * EI))
        b = math.sqrt((-P + disc) / (2 * EI))
        ch, sh, cb, sb = math.cosh(a * l), math.sinh(a * l), math.cos(b * l), math.sin(b * l)
        # derivatives 0..3 at l of the two clamp-satisfying solutions
        y1 = (ch - cb, a * sh + b * sb, a * a * ch + b * b * cb, a**3 * sh - b**3 * sb)
        y2 = (sh / a - sb / b, ch - cb, a * sh + b * sb, a * a * ch + b * b * cb)

        def bc(y):
            v, v1, v2, v3 = y
            return (
                -EI * v3 + P * v1 - w * w * M2 * (v + r * v1),
                EI * v2 + P * r * v1 - w * w * (M2 * r * (v + r * v1) + J_C * v1),
            )

        c1, c2 = bc(y1), bc(y2)
        # scale out the exponential growth for a well-conditioned sign
        return (c1[0] * c2[1] - c1[1] * c2[0]) / (ch * ch)

    if w_max is None:
        w_max = 50.0 * (k + 2) ** 2 * math.sqrt(EI / (m * l**4))
    ws = np.linspace(1e-6, w_max, npts)
    ds = np.array([det(w) for w in ws])
    roots = []
    for i in range(len(ws) - 1):
        if ds[i] == 0.0:
            roots.append(ws[i])
        elif ds[i] * ds[i + 1] < 0:
            roots.append(brentq(det, ws[i], ws[i + 1], xtol=1e-14, rtol=1e-15, maxiter=200))
        if len(roots) >= k:
            break
    if len(roots) < k:
        raise RuntimeError(f"found {len(roots)} < {k} roots below {w_max}")
    return np.array(roots[:k])
