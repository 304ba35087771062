"""Continuum (Euler–Bernoulli) natural frequencies of the beam with the heavy body held at phi = 0 or pi.

An independent check of the project's Ritz models: nothing here uses the project's code or equations. The
linearised equations are derived below by Hamilton's principle with sympy (`derive_linearised_equations`);
the solver (`continuum_frequencies`) uses the same result written out by hand (`_tip_operator`), and the
tests check that the two agree coefficient by coefficient.

System (SI): beam clamped at x = 0, length l, bending stiffness EI, mass m per length, inextensible, no
axial or rotary inertia; deflection w(x, t). A rigid body (mass M2, inertia J_C about its centre of mass C,
C at distance r from the hinge) is fixed to the tip section at a held relative angle phi:
theta = w'(l) + phi, C = (l + u(l) + r cos theta, w(l) + r sin theta), u(l) = -1/2 int_0^l w'^2 dx
(inextensibility, second order). Gravity g along +x acts on the body only.

Energies: T = 1/2 int m w_t^2 dx + 1/2 M2 |C_t|^2 + 1/2 J_C theta_t^2,
          V = 1/2 int EI w''^2 dx - M2 g x_C.

Linearisation (w = O(eps), u = O(eps^2), phi held):
  first order:  L1 = -M2 g r sin(phi) w'(l): a tip moment M2 g r sin(phi). It vanishes for sin(phi) = 0,
                so at phi = 0 and phi = pi the straight beam is an equilibrium (at any other phi the
                equilibrium is bent and the formulas below do not apply);
  second order (c = cos(phi) = +-1, s = sin(phi) = 0):
    L2 = int [1/2 m w_t^2 - 1/2 EI w''^2 - 1/2 P w'^2] dx
         + 1/2 M2 (w_t(l) + r c w_t'(l))^2 + 1/2 J_C w_t'(l)^2 - 1/2 M2 g r c w'(l)^2,
    with P = dL2/du(l) = M2 g: the body's weight enters through M2 g u(l) = -1/2 M2 g int w'^2, i.e. an axial
    TENSION P = M2 g (for g > 0) at both phi = 0 and phi = pi (the hinge force is the weight, along +x, in
    both cases). The body's x-velocity is second order (u_t and r sin(theta) theta_t), so it drops out.

Result (Hamilton's principle, J_h = J_C + M2 r^2 the body's inertia about the hinge, c^2 = 1):
  field equation, 0 < x < l:      EI w'''' - P w'' + m w_tt = 0,           P = M2 g;
  clamp, x = 0:                   w = 0,  w' = 0;
  shear (delta w(l)), x = l:      EI w''' - P w' - M2 (w_tt + r c w_tt') = 0;
  moment (delta w'(l)), x = l:    EI w'' + M2 r c w_tt + J_h w_tt' + M2 g r c w' = 0.
The pendulum term M2 g r c w'(l) stiffens at phi = 0 (body hanging beyond the tip, c = +1) and softens at
phi = pi (body turned back over the beam, c = -1); the tension term -P w'' stiffens in both.

Frequencies: w = W(x) e^{i omega t}, W = sum A_j e^{s_j x} with EI s^4 - P s^2 - m omega^2 = 0, i.e.
s = +-lam1, +-i lam2, lam1^2 = (P + sqrt(P^2 + 4 EI m omega^2)) / (2 EI), lam2^2 = (-P + sqrt(...)) / (2 EI).
The basis {e^{lam1 (x-l)}, e^{-lam1 x}, cos lam2 x, sin lam2 x} is bounded on [0, l], so the 4x4 boundary
determinant (rows normalised to unit max-norm, which keeps its sign) is a continuous function of omega
without poles; its sign changes are bracketed on a fine grid and refined by brentq.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.linalg import eigh
from scipy.optimize import brentq

from paper_example import DEFAULT_PARAMS, PARAM_NAMES  # noqa: E402

_PHI_TOL = 1e-12


def full_params(params=None) -> dict:
    p = dict(DEFAULT_PARAMS)
    if params:
        unknown = set(params) - set(PARAM_NAMES)
        if unknown:
            raise ValueError(f"unknown parameter(s) {sorted(unknown)}; allowed: {PARAM_NAMES}")
        p.update({k: float(v) for k, v in params.items()})
    if p["l"] <= 0 or p["EI"] <= 0 or p["m"] <= 0:
        raise ValueError("l, EI and m must be positive")
    if p["M2"] < 0 or p["J_C"] < 0:
        raise ValueError("M2 and J_C must be non-negative")
    return p


def held_angle_sign(phi: float) -> int:
    """cos(phi) = +1 for phi = 0, -1 for phi = pi; anything else is refused."""
    if abs(phi) <= _PHI_TOL:
        return 1
    if abs(phi - math.pi) <= _PHI_TOL:
        return -1
    raise ValueError(
        f"phi = {phi!r}: the continuum solution is only valid for phi in {{0, pi}}. There sin(phi) = 0 and "
        "the beam is straight at equilibrium; at any other phi the body's weight bends the beam by the tip "
        "moment M2*g*r*sin(phi), and this closed form (linearised about the straight beam) does not hold."
    )


# --------------------------------------------------------------------------------------------------
# 1. Derivation (sympy, Hamilton's principle)
# --------------------------------------------------------------------------------------------------


@lru_cache(maxsize=1)
def derive_linearised_equations():
    """Derive the linearised field equation and tip boundary conditions from the energies.

    Returns a dict of sympy objects:
      'symbols': dict of the parameter symbols and c (= cos phi), s (= sin phi);
      'first_order': the O(eps) Lagrangian (a multiple of w'(l)), before setting s = 0;
      'P': the axial force dL2/du(l);
      'field': EI w'''' - P w'' + m w_tt (= 0), as the negative Euler–Lagrange expression;
      'bc_shear', 'bc_moment': the tip conditions (= 0) as linear forms in the symbols
        W0..W3 = w, w', w'', w''' at x = l and A0, A1 = w_tt, w_tt' at x = l (s = 0, c^2 = 1 applied).
    """
    import sympy as sp

    x, t, eps = sp.symbols("x t epsilon")
    l, EI, m, M2, J_C, r, g = sp.symbols("l EI m M2 J_C r g", positive=True)
    c, s = sp.symbols("c s")  # cos(phi), sin(phi) of the held angle
    phi = sp.Symbol("phi")

    # Tip quantities of the beam as functions of time: deflection W, slope A, axial displacement U.
    W, A, U = (sp.Function(n)(t) for n in ("W", "A", "U"))
    theta = phi + eps * A
    x_C = l + eps**2 * U + r * sp.cos(theta)
    y_C = eps * W + r * sp.sin(theta)
    T_body = M2 / 2 * (sp.diff(x_C, t) ** 2 + sp.diff(y_C, t) ** 2) + J_C / 2 * sp.diff(theta, t) ** 2
    V_body = -M2 * g * x_C
    L_body = T_body - V_body

    def order(expr, k):
        e = sp.diff(expr, eps, k).subs(eps, 0) / sp.factorial(k)
        e = sp.expand(sp.expand_trig(e))
        return e.subs({sp.cos(phi): c, sp.sin(phi): s})

    L1 = sp.simplify(order(L_body, 1))
    L2 = order(L_body, 2)
    # At the held angles s = 0 and c^2 = 1.
    L2 = sp.expand(L2.subs(s, 0)).subs(c**2, 1)

    # U enters L2 linearly with a constant coefficient: that coefficient is the axial force P.
    P = sp.simplify(sp.diff(L2, U))
    assert not P.has(U) and not P.has(sp.Derivative(U, t)), P
    assert sp.simplify(L2.diff(sp.Derivative(U, t))) == 0

    # Beam Lagrangian density; the u(l) = -1/2 int w'^2 dx term of L2 becomes -1/2 P w'^2 in the density.
    w = sp.Function("w")(x, t)
    wt, wx, wxx = sp.symbols("w_t w_x w_xx")
    dens = m / 2 * wt**2 - EI / 2 * wxx**2 + P * (-sp.Rational(1, 2) * wx**2)
    back = {wt: sp.diff(w, t), wx: sp.diff(w, x), wxx: sp.diff(w, x, 2)}
    d_wt = dens.diff(wt).subs(back)
    d_wx = dens.diff(wx).subs(back)
    d_wxx = dens.diff(wxx).subs(back)
    # Euler–Lagrange of int int dens dx dt:  - d/dt(d_wt) - d/dx(d_wx) + d2/dx2(d_wxx) = 0
    euler = -sp.diff(d_wt, t) - sp.diff(d_wx, x) + sp.diff(d_wxx, x, 2)
    field = sp.expand(-euler)
    # Boundary terms at x = l from integrating by parts in x:
    #   [(d_wx - d/dx d_wxx) delta w + d_wxx delta w_x]_{x=l}
    bnd_w = d_wx - sp.diff(d_wxx, x)
    bnd_wx = d_wxx
    # Body Euler–Lagrange expressions (from L2) in its coordinates W = w(l), A = w'(l).
    def el(q):
        return sp.diff(L2, q) - sp.diff(sp.diff(L2, sp.Derivative(q, t)), t)

    E_W, E_A = el(W), el(A)

    W0, W1, W2, W3, A0, A1 = sp.symbols("W0 W1 W2 W3 A0 A1")
    tip_beam = {
        sp.diff(w, x, 3): W3, sp.diff(w, x, 2): W2, sp.diff(w, x): W1, w: W0,
    }
    tip_body = {
        sp.Derivative(W, (t, 2)): A0, sp.Derivative(A, (t, 2)): A1,
    }

    def to_tip(expr_beam, expr_body):
        e = sp.expand(expr_beam).subs(tip_beam) + sp.expand(expr_body).subs(tip_body)
        e = e.subs({A: W1, W: W0})
        return sp.expand(e)

    bc_shear = to_tip(bnd_w, E_W)
    bc_moment = to_tip(bnd_wx, E_A)
    return {
        "symbols": dict(l=l, EI=EI, m=m, M2=M2, J_C=J_C, r=r, g=g, c=c, s=s, x=x, t=t, w=w),
        "tip_symbols": (W0, W1, W2, W3, A0, A1),
        "first_order": L1,
        "P": P,
        "field": field,
        "bc_shear": bc_shear,
        "bc_moment": bc_moment,
    }


# --------------------------------------------------------------------------------------------------
# 2. The boundary-value problem, written out by hand (checked against the derivation by the tests)
# --------------------------------------------------------------------------------------------------


def axial_force(p) -> float:
    """P = M2 g: tension for g > 0, the same at phi = 0 and phi = pi."""
    return p["M2"] * p["g"]


def _tip_operator(omega2, p, c):
    """Coefficients (2 x 4) of the tip conditions on (W, W', W'', W''') at x = l for w = W(x) e^{i omega t}
    (w_tt -> -omega^2 W), in the form of `derive_linearised_equations`:
      shear:  EI W''' - P W' + M2 omega^2 (W + r c W') = 0
      moment: EI W'' - omega^2 (M2 r c W + J_h W') + M2 g r c W' = 0.
    omega2 may be an array (leading axis); returns shape omega2.shape + (2, 4)."""
    EI, M2, J_C, r, g = p["EI"], p["M2"], p["J_C"], p["r"], p["g"]
    P = axial_force(p)
    Jh = J_C + M2 * r * r
    w2 = np.asarray(omega2, dtype=float)
    out = np.zeros(w2.shape + (2, 4))
    out[..., 0, 0] = M2 * w2
    out[..., 0, 1] = -P + M2 * r * c * w2
    out[..., 0, 3] = EI
    out[..., 1, 0] = -M2 * r * c * w2
    out[..., 1, 1] = -Jh * w2 + M2 * g * r * c
    out[..., 1, 2] = EI
    return out


def _wavenumbers(omega, p):
    """lam1, lam2 > 0 with EI s^4 - P s^2 - m omega^2 = 0 at s = +-lam1, +-i lam2."""
    EI, m = p["EI"], p["m"]
    P = axial_force(p)
    omega = np.asarray(omega, dtype=float)
    root = np.sqrt(P * P + 4.0 * EI * m * omega**2)
    lam1 = np.sqrt((P + root) / (2 * EI))
    # -P + root computed without cancellation for P > 0
    lam2_sq = np.where(P > 0, 4.0 * EI * m * omega**2 / (P + root), -P + root) / (2 * EI)
    return lam1, np.sqrt(lam2_sq)


def boundary_matrix(omega, p, c):
    """4x4 boundary matrix (rows: w(0), w'(0), shear, moment; columns: e^{lam1(x-l)}, e^{-lam1 x},
    cos lam2 x, sin lam2 x), each row scaled to unit max-norm. Vectorised over omega."""
    l = p["l"]
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    a, b = _wavenumbers(omega, p)
    ea = np.exp(-a * l)
    ca, sa = np.cos(b * l), np.sin(b * l)
    n = omega.size
    # derivative k = 0..3 of the 4 basis functions at x = 0 and x = l: shape (n, 4 derivs, 4 funcs)
    at0 = np.empty((n, 4, 4))
    atl = np.empty((n, 4, 4))
    for k in range(4):
        at0[:, k, 0] = a**k * ea
        at0[:, k, 1] = (-a) ** k
        atl[:, k, 0] = a**k
        atl[:, k, 1] = (-a) ** k * ea
    # cos(b x): cos, -b sin, -b^2 cos, b^3 sin ; sin(b x): sin, b cos, -b^2 sin, -b^3 cos
    at0[:, :, 2] = np.stack([np.ones(n), np.zeros(n), -(b**2), np.zeros(n)], axis=1)
    at0[:, :, 3] = np.stack([np.zeros(n), b, np.zeros(n), -(b**3)], axis=1)
    atl[:, :, 2] = np.stack([ca, -b * sa, -(b**2) * ca, b**3 * sa], axis=1)
    atl[:, :, 3] = np.stack([sa, b * ca, -(b**2) * sa, -(b**3) * ca], axis=1)
    B = np.empty((n, 4, 4))
    B[:, 0, :] = at0[:, 0, :]
    B[:, 1, :] = at0[:, 1, :]
    B[:, 2:, :] = _tip_operator(omega**2, p, c) @ atl
    B /= np.abs(B).max(axis=2, keepdims=True)
    return B


def frequency_determinant(omega, p, c):
    return np.linalg.det(boundary_matrix(omega, p, c))


def _omega_scale(p):
    """sqrt(EI / (m l^4)): omega = (beta l)^2 * scale for the bare cantilever."""
    return math.sqrt(p["EI"] / (p["m"] * p["l"] ** 4))


def continuum_frequencies(phi, k=5, params=None, step=0.005):
    """The first k natural frequencies omega [rad/s] of the linearised continuum at phi = 0 or pi.

    Raises ValueError for any other phi, and if the straight equilibrium is statically unstable (then the
    lowest omega^2 < 0 and the real roots below would not be the first k)."""
    c = held_angle_sign(phi)
    p = full_params(params)
    if min(static_stiffness_eigenvalues(phi, params)) <= 0:
        raise ValueError(f"straight equilibrium at phi = {phi} is statically unstable for {p}")
    scale = _omega_scale(p)
    roots = []
    # scan in beta*l (omega = (beta l)^2 * scale): the roots are spaced ~pi apart in beta*l
    bl_lo = 1e-3
    while len(roots) < k:
        bl = np.arange(bl_lo, bl_lo + 20.0 + step / 2, step)
        om = bl**2 * scale
        d = frequency_determinant(om, p, c)
        idx = np.nonzero(np.sign(d[:-1]) * np.sign(d[1:]) < 0)[0]
        for i in idx:
            f = lambda w: frequency_determinant(w, p, c)[0]
            w0 = brentq(f, om[i], om[i + 1], xtol=1e-14, rtol=4 * np.finfo(float).eps, maxiter=200)
            # a true root: the boundary matrix is singular there (not a sign change through infinity)
            sv = np.linalg.svd(boundary_matrix(w0, p, c)[0], compute_uv=False)
            if sv[-1] > 1e-8 * sv[0]:
                raise RuntimeError(f"sign change of the determinant at omega = {w0} is not a root: {sv}")
            roots.append(w0)
            if len(roots) == k:
                break
        bl_lo = bl[-1]
        if bl_lo > 400:
            raise RuntimeError("frequency scan did not find enough roots")
    return np.array(roots[:k])


# --------------------------------------------------------------------------------------------------
# Statics in the same framework: tip stiffness of the beam-column, straightness, stability
# --------------------------------------------------------------------------------------------------


def beam_column_tip_stiffness(params=None):
    """Exact 2x2 static stiffness of the clamped beam-column (axial force P = M2 g) for the tip deflection
    and slope (W, A): V_beam = 1/2 [W A] K [W A]^T when the interior satisfies EI w'''' - P w'' = 0.
    By parts, V_beam = 1/2 [EI w'' w' - (EI w''' - P w') w]_{x=l}, so the generalised tip forces are
    F = -(EI w''' - P w')(l) (conjugate to W) and M = EI w''(l) (conjugate to A).
    P = 0 gives the classic EI/l^3 [[12, -6 l], [-6 l, 4 l^2]]."""
    p = full_params(params)
    EI, l = p["EI"], p["l"]
    P = axial_force(p)
    if P > 0:
        k = math.sqrt(P / EI)
        fns = [
            lambda x, d: [1.0, 0.0, 0.0, 0.0][d],
            lambda x, d: [x, 1.0, 0.0, 0.0][d],
            lambda x, d: k**d * math.exp(k * (x - l)),
            lambda x, d: (-k) ** d * math.exp(-k * x),
        ]
    elif P < 0:
        k = math.sqrt(-P / EI)
        fns = [
            lambda x, d: [1.0, 0.0, 0.0, 0.0][d],
            lambda x, d: [x, 1.0, 0.0, 0.0][d],
            lambda x, d: [math.cos(k * x), -k * math.sin(k * x), -k * k * math.cos(k * x), k**3 * math.sin(k * x)][d],
            lambda x, d: [math.sin(k * x), k * math.cos(k * x), -k * k * math.sin(k * x), -(k**3) * math.cos(k * x)][d],
        ]
    else:
        fns = [lambda x, d, j=j: (math.prod(range(j - d + 1, j + 1)) * x ** (j - d) if d <= j else 0.0) for j in range(4)]
    S = np.array([[f(0.0, 0) for f in fns], [f(0.0, 1) for f in fns], [f(l, 0) for f in fns], [f(l, 1) for f in fns]])
    K = np.empty((2, 2))
    for j, rhs in enumerate(([0, 0, 1, 0], [0, 0, 0, 1])):
        a = np.linalg.solve(S, np.array(rhs, dtype=float))
        d = [sum(a[i] * fns[i](l, n) for i in range(4)) for n in range(4)]
        K[0, j] = -(EI * d[3] - P * d[1])
        K[1, j] = EI * d[2]
    return K


def static_stiffness_eigenvalues(phi, params=None):
    """Eigenvalues of the condensed static stiffness at the straight equilibrium (phi = 0 or pi): the
    beam-column tip stiffness plus the body's pendulum term M2 g r cos(phi) on the slope. For P >= 0 the
    interior of the beam (tip held) is stable, so the straight state is stable iff both are > 0."""
    c = held_angle_sign(phi)
    p = full_params(params)
    K = beam_column_tip_stiffness(params) + np.array([[0.0, 0.0], [0.0, p["M2"] * p["g"] * p["r"] * c]])
    return np.linalg.eigvalsh(0.5 * (K + K.T))


def static_tip_response(phi, params=None):
    """First-order static tip deflection and slope (W, A) of the beam about the straight state under the
    first-order tip moment M2 g r sin(phi) (the O(eps) Lagrangian): solves
    (K_tip + diag(0, M2 g r cos phi)) [W, A] = [0, -M2 g r sin phi]. Meaningful as an equilibrium only
    where it is zero (phi = 0, pi); elsewhere it is just the linear response (the bent state)."""
    p = full_params(params)
    K = beam_column_tip_stiffness(params) + np.array([[0.0, 0.0], [0.0, p["M2"] * p["g"] * p["r"] * math.cos(phi)]])
    return np.linalg.solve(K, np.array([0.0, -p["M2"] * p["g"] * p["r"] * math.sin(phi)]))


# --------------------------------------------------------------------------------------------------
# Independent discretisation: Rayleigh–Ritz with global polynomials x^2 P_j(2x/l - 1)
# --------------------------------------------------------------------------------------------------


def ritz_matrices(phi, n, params=None):
    """Mass and stiffness matrices of the Ritz model with n global polynomials xi^2 P_j(2 xi - 1)
    (xi = x/l, P_j Legendre), built from the NONLINEAR energies (not from the boundary conditions):
      u(l) = -1/2 q^T G q, theta = c_v^T q + phi, x_C = l + u + r cos theta, y_C = b^T q + r sin theta,
      M = m int N N^T + M2 (grad x_C grad x_C^T + grad y_C grad y_C^T) + J_C c_v c_v^T  at q = 0,
      K = Hessian of  1/2 q^T K_b q - M2 g x_C(q)  at q = 0.
    Any phi is accepted here (q = 0 is an equilibrium only for sin phi = 0)."""
    from numpy.polynomial import legendre as L

    p = full_params(params)
    l, EI, m, M2, J_C, r, g = (p[k] for k in PARAM_NAMES)
    xi, wq = L.leggauss(n + 4)
    xi = 0.5 * (xi + 1.0)
    wq = 0.5 * wq
    N = np.empty((n, xi.size))
    N1 = np.empty_like(N)
    N2 = np.empty_like(N)
    tip = np.empty(n)
    tip1 = np.empty(n)
    for j in range(n):
        Pj = L.Legendre.basis(j, domain=[0, 1])
        d1, d2 = Pj.deriv(1), Pj.deriv(2)
        N[j] = xi**2 * Pj(xi)
        N1[j] = (2 * xi * Pj(xi) + xi**2 * d1(xi)) / l
        N2[j] = (2 * Pj(xi) + 4 * xi * d1(xi) + xi**2 * d2(xi)) / l**2
        tip[j] = Pj(1.0)
        tip1[j] = (2 * Pj(1.0) + d1(1.0)) / l
    Mb = m * l * (N * wq) @ N.T
    Kb = EI * l * (N2 * wq) @ N2.T
    G = l * (N1 * wq) @ N1.T  # u(l) = -1/2 q^T G q
    s, c = math.sin(phi), math.cos(phi)
    grad_x = -r * s * tip1  # d x_C / dq at q = 0 (the -G q part vanishes)
    grad_y = tip + r * c * tip1
    M = Mb + M2 * (np.outer(grad_x, grad_x) + np.outer(grad_y, grad_y)) + J_C * np.outer(tip1, tip1)
    hess_xC = -G - r * c * np.outer(tip1, tip1)
    K = Kb - M2 * g * hess_xC
    return M, K


def ritz_frequencies(phi, n, k=5, params=None):
    """The k lowest Ritz omega [rad/s]; an unstable mode (omega^2 < 0) is returned as -sqrt(-omega^2)."""
    M, K = ritz_matrices(phi, n, params)
    w2 = eigh(K, M, eigvals_only=True)[:k]
    return np.sign(w2) * np.sqrt(np.abs(w2))


# --------------------------------------------------------------------------------------------------
# Classic reference: cantilever with a tip point mass (no offset, no rotary inertia, no gravity)
# --------------------------------------------------------------------------------------------------


def tip_mass_cantilever_frequencies(mass_ratio, k=3, EI=1000.0, m=2.0, l=2.5):
    """Roots of 1 + cos(bl) cosh(bl) + mu bl (cos(bl) sinh(bl) - sin(bl) cosh(bl)) = 0, mu = M/(m l),
    omega = (bl)^2 sqrt(EI/(m l^4)). The equation: Karnovsky & Lebed, "Formulas for Structural Dynamics",
    McGraw-Hill 2004, section 7.5.3 / Table 7.6 (cantilever with a lumped mass at the free end); also
    Laura, Pombo & Susemihl, J. Sound Vib. 37 (1974) 161-168. Divided by cosh(bl) to stay bounded."""

    def f(bl):
        return 1.0 / np.cosh(bl) + np.cos(bl) + mass_ratio * bl * (np.cos(bl) * np.tanh(bl) - np.sin(bl))

    grid = np.arange(1e-3, 4.0 * k + 6.0, 1e-3)
    vals = f(grid)
    roots = []
    for i in np.nonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)[0]:
        roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-15))
        if len(roots) == k:
            break
    bl = np.array(roots)
    return bl**2 * math.sqrt(EI / (m * l**4)), bl
