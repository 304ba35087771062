"""Independent physics oracle for the beam-body model (sympy + scipy).

Everything here is derived from the ENERGIES of the model (shared/model-notes.md), never from the
equations in the paper text or from the Rust sources:

* beam (one cubic Hermite element, inextensible), coordinates q = (v1, theta1):
    T1  = 1/2 (m_vv v1'^2 + 2 m_vt v1' th1' + m_tt th1'^2),  m_vv = 13 m l/35, m_vt = -11 m l^2/210,
                                                            m_tt = m l^3/105
    Pi1 = 1/2 (k_vv v1^2 + 2 k_vt v1 th1 + k_tt th1^2),       k_vv = 12 EI/l^3, k_vt = -6 EI/l^2,
                                                            k_tt = 4 EI/l
    u1  = -l (3/5 vb^2 - 1/10 vb th1 + 1/15 th1^2),  vb = v1/l   (tip shortening, inextensibility)
* rigid body hinged at the tip, absolute angle theta = theta1 + phi(t) (phi prescribed):
    C   = (l + u_h + r cos theta, v1 + r sin theta)
    T2  = 1/2 M2 |C'|^2 + 1/2 J_C theta'^2,   Pi2 = -M2 g (u_h + r cos theta)   (gravity along +x)
  with u_h = u1(v1, theta1) (reduced model) or u_h = u2, a free coordinate (DAE model).

Formulations (residual conventions of the CLI contract, rows are generalized forces):
* reduced:   R_i = d/dt dL/dq'_i - dL/dq_i,  L = T1 + T2 - Pi1 - Pi2,  u_h = u1(q).
* linear:    first-order Taylor expansion of the reduced R about q = q' = q'' = 0 (phi, phi', phi''
             kept exact).
* dae / dae_stabilized: E_x = d/dt dL_tot/dx' - dL_tot/dx for x in (v1, theta1, u2), u_h = u2,
             lambda = E_u2, f = u2 - u1(v1, theta1);
             R_1 = E_v1 - lambda df/dv1, R_2 = E_th1 - lambda df/dth1, R_3 = u2'' - d^2/dt^2 u1.

Every residual is linear in the accelerations, R = Mass(x) a + b(x); the oracle's accelerations are
the solution of Mass a = -b.

The module derives everything once at import and caches lambdified (numpy, cse) functions.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass

import numpy as np
import sympy as sp

# --------------------------------------------------------------------------------------------------
# Parameters
# --------------------------------------------------------------------------------------------------

from paper_example import DEFAULT_PARAMS, PAPER_LAW, PARAM_NAMES  # noqa: E402

# The paper's example (§4): default parameters and law, zero initial state, tau = t/T up to 12.
# Every scene key of the CLI contract appears, so this also lists the names a scene may set.
PAPER_SCENE = {
    **DEFAULT_PARAMS,
    **PAPER_LAW,
    "v1_0": 0.0,
    "theta1_0": 0.0,
    "dv1_0": 0.0,
    "dtheta1_0": 0.0,
}

FORMULATIONS = ("reduced", "dae", "dae_stabilized", "linear")


def full_params(params=None):
    p = dict(DEFAULT_PARAMS)
    if params:
        unknown = set(params) - set(PARAM_NAMES)
        if unknown:
            raise KeyError(f"unknown parameter(s) {sorted(unknown)}")
        p.update({k: float(v) for k, v in params.items()})
    return p


def _pvec(params):
    p = full_params(params)
    return [p[k] for k in PARAM_NAMES]


# --------------------------------------------------------------------------------------------------
# Symbolic derivation
# --------------------------------------------------------------------------------------------------

t = sp.Symbol("t", real=True)
l, EI, m, M2, J_C, r, g = sp.symbols("l EI m M2 J_C r g", positive=True)
PSYMS = (l, EI, m, M2, J_C, r, g)

# plain symbols for the evaluation point
ph, dph, ddph = sp.symbols("phi dphi ddphi", real=True)
v1s, th1s, u2s = sp.symbols("v1 theta1 u2", real=True)
dv1s, dth1s, du2s = sp.symbols("dv1 dtheta1 du2", real=True)
ddv1s, ddth1s, ddu2s = sp.symbols("ddv1 ddtheta1 ddu2", real=True)


def u1_expr(v1, th1):
    vb = v1 / l
    return -l * (sp.Rational(3, 5) * vb**2 - sp.Rational(1, 10) * vb * th1 + sp.Rational(1, 15) * th1**2)


def _energies(v1, th1, uh, phi):
    """T1, Pi1, T2, Pi2 as functions of time-dependent expressions (v1, th1, uh, phi are of t)."""
    m_vv = 13 * m * l / 35
    m_vt = -11 * m * l**2 / 210
    m_tt = m * l**3 / 105
    k_vv = 12 * EI / l**3
    k_vt = -6 * EI / l**2
    k_tt = 4 * EI / l
    v1d, th1d = v1.diff(t), th1.diff(t)
    T1 = sp.Rational(1, 2) * (m_vv * v1d**2 + 2 * m_vt * v1d * th1d + m_tt * th1d**2)
    Pi1 = sp.Rational(1, 2) * (k_vv * v1**2 + 2 * k_vt * v1 * th1 + k_tt * th1**2)
    theta = th1 + phi
    xC = l + uh + r * sp.cos(theta)
    yC = v1 + r * sp.sin(theta)
    T2 = sp.Rational(1, 2) * M2 * (xC.diff(t) ** 2 + yC.diff(t) ** 2) + sp.Rational(1, 2) * J_C * theta.diff(t) ** 2
    Pi2 = -M2 * g * (uh + r * sp.cos(theta))
    return T1, Pi1, T2, Pi2


_v1f = sp.Function("v1")(t)
_th1f = sp.Function("theta1")(t)
_u2f = sp.Function("u2")(t)
_phif = sp.Function("phi")(t)


def _to_symbols(expr):
    """Replace functions of time and their derivatives by plain symbols (highest order first)."""
    reps2 = {
        _v1f.diff(t, 2): ddv1s,
        _th1f.diff(t, 2): ddth1s,
        _u2f.diff(t, 2): ddu2s,
        _phif.diff(t, 2): ddph,
    }
    reps1 = {_v1f.diff(t): dv1s, _th1f.diff(t): dth1s, _u2f.diff(t): du2s, _phif.diff(t): dph}
    reps0 = {_v1f: v1s, _th1f: th1s, _u2f: u2s, _phif: ph}
    expr = expr.subs(reps2)
    expr = expr.subs(reps1)
    expr = expr.subs(reps0)
    return expr


def _euler_lagrange(L, coords):
    return [sp.diff(sp.diff(L, c.diff(t)), t) - sp.diff(L, c) for c in coords]


def _derive():
    out = {}
    # ---------------- reduced ----------------
    u1f = u1_expr(_v1f, _th1f)
    T1, Pi1, T2, Pi2 = _energies(_v1f, _th1f, u1f, _phif)
    L = T1 + T2 - Pi1 - Pi2
    R_red = [sp.expand(_to_symbols(e)) for e in _euler_lagrange(L, [_v1f, _th1f])]
    out["R_reduced"] = R_red

    # ---------------- linear: first-order Taylor expansion about q = q' = q'' = 0 -------------------
    xs = (v1s, th1s, dv1s, dth1s, ddv1s, ddth1s)
    zero = {x: 0 for x in xs}
    R_lin = []
    for e in R_red:
        e0 = e.subs(zero)
        e1 = sum(sp.diff(e, x).subs(zero) * x for x in xs)
        R_lin.append(sp.expand(e0 + e1))
    out["R_linear"] = R_lin

    # ---------------- DAE: free body with its own longitudinal coordinate u2 -------------------------
    T1d, Pi1d, T2d, Pi2d = _energies(_v1f, _th1f, _u2f, _phif)
    Ltot = T1d - Pi1d + T2d - Pi2d
    E_v1, E_th1, E_u2 = _euler_lagrange(Ltot, [_v1f, _th1f, _u2f])
    f = _u2f - u1f
    lam = E_u2
    R1 = E_v1 - lam * sp.diff(f, _v1f)
    R2 = E_th1 - lam * sp.diff(f, _th1f)
    R3 = _u2f.diff(t, 2) - sp.diff(u1f, t, 2)
    out["R_dae"] = [sp.expand(_to_symbols(e)) for e in (R1, R2, R3)]
    out["lambda_dae"] = sp.expand(_to_symbols(lam))

    # ---------------- energy and u1 (for the CSV checks) --------------------------------------------
    # energy with a free hinge coordinate u_h = u2 and its rate du2 (the reduced case substitutes
    # u2 = u1(q), du2 = d/dt u1(q) numerically)
    E_tot = T1d + T2d + Pi1d + Pi2d
    out["energy"] = sp.expand(_to_symbols(E_tot))
    out["kinetic"] = sp.expand(_to_symbols(T1d + T2d))
    out["u1"] = u1_expr(v1s, th1s)
    out["du1"] = sp.expand(_to_symbols(sp.diff(u1f, t)))
    out["ddu1"] = sp.expand(_to_symbols(sp.diff(u1f, t, 2)))
    return out


SYM = _derive()

# argument orders (the CLI's line layouts)
ARGS_REDUCED = (ph, dph, ddph, v1s, th1s, dv1s, dth1s, ddv1s, ddth1s)
ARGS_DAE = (ph, dph, ddph, v1s, th1s, u2s, dv1s, dth1s, du2s, ddv1s, ddth1s, ddu2s)
ACC_REDUCED = (ddv1s, ddth1s)
ACC_DAE = (ddv1s, ddth1s, ddu2s)


def _lambdify_list(args, exprs):
    """Vectorized numpy function returning an array of shape (len(exprs), *broadcast shape)."""
    f = sp.lambdify(list(args) + list(PSYMS), list(exprs), modules="numpy", cse=True)

    def call(*vals):
        res = f(*vals)
        return np.array(np.broadcast_arrays(*[np.asarray(x, dtype=float) for x in res]))

    return call


@dataclass
class _Formulation:
    name: str
    args: tuple
    acc: tuple
    R: list
    f_R: object = None
    f_terms: object = None
    f_mass: object = None
    f_b: object = None

    def __post_init__(self):
        self.f_R = _lambdify_list(self.args, self.R)
        # row scale: max |additive term| of the expanded row (for relative tolerances)
        terms = [sp.Add.make_args(e) for e in self.R]
        self._term_slices = []
        k = 0
        for ts in terms:
            self._term_slices.append(slice(k, k + len(ts)))
            k += len(ts)
        self.f_terms = _lambdify_list(self.args, [a for ts in terms for a in ts])
        mass = sp.Matrix(self.R).jacobian(sp.Matrix(self.acc))
        b = [e.subs({a: 0 for a in self.acc}) for e in self.R]
        # the residual must be affine in the accelerations
        for i, e in enumerate(self.R):
            for a in self.acc:
                assert sp.diff(e, a, 2) == 0, (self.name, i, a)
        self.f_mass = _lambdify_list(self.args, list(mass))
        self.f_b = _lambdify_list(self.args, b)
        self.n = len(self.acc)

    def _split(self, X, params):
        X = np.atleast_2d(np.asarray(X, dtype=float))
        assert X.shape[1] == len(self.args), (self.name, X.shape)
        return [X[:, i] for i in range(X.shape[1])] + _pvec(params)

    def residual(self, X, params=None):
        """X: (N, nargs) rows in the CLI line layout. Returns (N, n) residuals."""
        return self.f_R(*self._split(X, params)).T

    def row_scale(self, X, params=None):
        """(N, n): the largest |additive term| of each expanded residual row at each point."""
        T = np.abs(self.f_terms(*self._split(X, params)))
        return np.stack([T[s].max(axis=0) for s in self._term_slices], axis=1)

    def mass_b(self, X, params=None):
        cols = self._split(X, params)
        N = len(cols[0])
        Mm = self.f_mass(*cols).T.reshape(N, self.n, self.n)
        b = self.f_b(*cols).T
        return Mm, b

    def accelerations(self, X, params=None):
        """Solve R = 0 for the accelerations (the acceleration columns of X are ignored)."""
        Mm, b = self.mass_b(X, params)
        return np.linalg.solve(Mm, -b[..., None])[..., 0]


_FORMS = {
    "reduced": _Formulation("reduced", ARGS_REDUCED, ACC_REDUCED, SYM["R_reduced"]),
    "linear": _Formulation("linear", ARGS_REDUCED, ACC_REDUCED, SYM["R_linear"]),
    "dae": _Formulation("dae", ARGS_DAE, ACC_DAE, SYM["R_dae"]),
}
_FORMS["dae_stabilized"] = _FORMS["dae"]


def formulation(name) -> _Formulation:
    return _FORMS[name]


def n_inputs(name):
    return len(_FORMS[name].args)


def n_dof(name):
    return _FORMS[name].n


def residual(name, X, params=None):
    return _FORMS[name].residual(X, params)


def row_scale(name, X, params=None):
    return _FORMS[name].row_scale(X, params)


def accelerations(name, X, params=None):
    return _FORMS[name].accelerations(X, params)


# energy(phi, dphi, v1, theta1, u2, dv1, dtheta1, du2, params)
_E_ARGS = (ph, dph, v1s, th1s, u2s, dv1s, dth1s, du2s)
_f_energy = _lambdify_list(_E_ARGS, [SYM["energy"], SYM["kinetic"]])
_f_u1 = _lambdify_list((v1s, th1s, dv1s, dth1s), [SYM["u1"], SYM["du1"]])


def u1_and_rate(v1, th1, dv1, dth1, params=None):
    u, du = _f_u1(v1, th1, dv1, dth1, *_pvec(params))
    return u, du


def u1(v1, th1, params=None):
    return u1_and_rate(v1, th1, 0.0 * np.asarray(v1), 0.0 * np.asarray(th1), params)[0]


def energy(phi, dphi, v1, th1, u2, dv1, dth1, du2, params=None):
    """Total energy T1 + T2 + Pi1 + Pi2 with hinge coordinate u_h = u2 and rate du2."""
    return _f_energy(phi, dphi, v1, th1, u2, dv1, dth1, du2, *_pvec(params))[0]


def kinetic_energy(phi, dphi, v1, th1, u2, dv1, dth1, du2, params=None):
    return _f_energy(phi, dphi, v1, th1, u2, dv1, dth1, du2, *_pvec(params))[1]


def energy_reduced(phi, dphi, v1, th1, dv1, dth1, params=None):
    """Energy of the reduced model (u_h = u1(q), du_h = d/dt u1(q))."""
    u, du = u1_and_rate(v1, th1, dv1, dth1, params)
    return energy(phi, dphi, v1, th1, u, dv1, dth1, du, params)


# --------------------------------------------------------------------------------------------------
# Symbolic self-checks (used by the tests; no Rust involved)
# --------------------------------------------------------------------------------------------------


def check_dae_reduces_to_reduced():
    """Substitute u2 = u1(q), u2' = d/dt u1, u2'' = d^2/dt^2 u1 into the DAE rows 1-2; the result must be
    the reduced residual exactly. Returns the two simplified differences (both must be 0)."""
    reps = {u2s: SYM["u1"], du2s: SYM["du1"], ddu2s: SYM["ddu1"]}
    R = SYM["R_dae"]
    # row 3 is u2'' - d^2 u1/dt^2, which vanishes under the substitution
    diffs = [sp.simplify(sp.expand(R[i].subs(reps) - SYM["R_reduced"][i])) for i in range(2)]
    diffs.append(sp.simplify(sp.expand(R[2].subs(reps))))
    return diffs


def check_linear_is_series():
    """R_linear must equal the eps-series of R_reduced(eps*x) to first order. Returns differences."""
    eps = sp.Symbol("eps")
    xs = (v1s, th1s, dv1s, dth1s, ddv1s, ddth1s)
    diffs = []
    for e, el in zip(SYM["R_reduced"], SYM["R_linear"]):
        se = e.subs({x: eps * x for x in xs}, simultaneous=True)
        ser = sp.series(se, eps, 0, 2).removeO().subs(eps, 1)
        diffs.append(sp.simplify(sp.expand(ser - el)))
    return diffs


# --------------------------------------------------------------------------------------------------
# Rotation law
# --------------------------------------------------------------------------------------------------


def phi_law(tt, phi0=0.0, phi_end=math.pi, t_rot=0.85):
    """phi = phi0 + phi_end sin^2(pi t / (2 t_rot)) for t <= t_rot, then phi0 + phi_end.
    Returns (phi, dphi, ddphi) arrays."""
    tt = np.asarray(tt, dtype=float)
    w = math.pi / (2.0 * t_rot)
    inside = tt <= t_rot
    # sin^2(w t) = (1 - cos(2 w t))/2
    phi = np.where(inside, phi0 + phi_end * np.sin(w * tt) ** 2, phi0 + phi_end)
    dphi = np.where(inside, phi_end * w * np.sin(2 * w * tt), 0.0)
    ddphi = np.where(inside, 2 * phi_end * w * w * np.cos(2 * w * tt), 0.0)
    return phi, dphi, ddphi


# --------------------------------------------------------------------------------------------------
# Reference simulation (scipy) of the reduced / linear 2-DOF ODEs
# --------------------------------------------------------------------------------------------------

# scalar (math-module) right-hand sides for speed inside solve_ivp: accelerations solved
# symbolically (2x2, Cramer) so that no numpy call is needed per evaluation.


def _scalar_rhs(R):
    mass = sp.Matrix(R).jacobian(sp.Matrix(ACC_REDUCED))
    b = sp.Matrix([e.subs({a: 0 for a in ACC_REDUCED}) for e in R])
    det = mass[0, 0] * mass[1, 1] - mass[0, 1] * mass[1, 0]
    a1 = (-b[0] * mass[1, 1] + b[1] * mass[0, 1]) / det
    a2 = (-b[1] * mass[0, 0] + b[0] * mass[1, 0]) / det
    args = [ph, dph, ddph, v1s, th1s, dv1s, dth1s] + list(PSYMS)
    return sp.lambdify(args, [a1, a2], modules="math", cse=True)


_RHS = {"reduced": None, "linear": None}


def _rhs_fun(name):
    if _RHS[name] is None:
        _RHS[name] = _scalar_rhs(SYM["R_" + name])
    return _RHS[name]


def scene_with_defaults(scene=None):
    s = dict(PAPER_SCENE)
    if scene:
        s.update({k: float(v) for k, v in scene.items()})
    return s


def output_grid(scene):
    """t = k*dt_out up to and including t_end: when t_end is not on the grid (within 1e-9 relative),
    a last row at t_end itself is added."""
    s = scene_with_defaults(scene)
    n = int(math.floor(s["t_end"] / s["dt_out"] + 1e-9))
    grid = np.arange(n + 1) * s["dt_out"]
    if s["t_end"] - grid[-1] > 1e-9 * max(1.0, s["t_end"]):
        grid = np.append(grid, s["t_end"])
    return grid


def reference_solution(name, scene=None, method="DOP853", rtol=1e-13, atol=1e-15, t_eval=None):
    """Integrate the reduced or linear ODE of this oracle with scipy on [0, t_end], in the segments
    [0, t_rot] and [t_rot, t_end] (phi'' jumps at both ends of the turn). Returns (t, Y) with
    Y columns (v1, theta1, dv1, dtheta1)."""
    from scipy.integrate import solve_ivp

    s = scene_with_defaults(scene)
    p = _pvec({k: s[k] for k in PARAM_NAMES})
    f = _rhs_fun(name)
    law = (s["phi0"], s["phi_end"], s["t_rot"])
    w = math.pi / (2.0 * s["t_rot"])

    def rhs_turn(tt, y):
        phi = law[0] + law[1] * math.sin(w * tt) ** 2
        dphi = law[1] * w * math.sin(2 * w * tt)
        ddphi = 2 * law[1] * w * w * math.cos(2 * w * tt)
        a1, a2 = f(phi, dphi, ddphi, y[0], y[1], y[2], y[3], *p)
        return [y[2], y[3], a1, a2]

    phi_c = law[0] + law[1]

    def rhs_hold(tt, y):
        a1, a2 = f(phi_c, 0.0, 0.0, y[0], y[1], y[2], y[3], *p)
        return [y[2], y[3], a1, a2]

    if t_eval is None:
        t_eval = output_grid(s)
    t_eval = np.asarray(t_eval, dtype=float)
    y0 = np.array([s["v1_0"], s["theta1_0"], s["dv1_0"], s["dtheta1_0"]])
    t_rot, t_end = s["t_rot"], max(s["t_end"], float(t_eval[-1]))
    Y = np.empty((len(t_eval), 4))
    kw = dict(method=method, rtol=rtol, atol=atol, dense_output=True)
    if t_rot > 0 and s["phi_end"] != 0.0:
        t1 = min(t_rot, t_end)
        sol1 = solve_ivp(rhs_turn, (0.0, t1), y0, **kw)
        assert sol1.success, sol1.message
        m1 = t_eval <= t1
        Y[m1] = sol1.sol(t_eval[m1]).T
        y1 = sol1.y[:, -1]
        if t_end > t1:
            sol2 = solve_ivp(rhs_hold, (t1, t_end), y1, **kw)
            assert sol2.success, sol2.message
            Y[~m1] = sol2.sol(t_eval[~m1]).T
    else:
        sol = solve_ivp(rhs_hold, (0.0, t_end), y0, **kw)
        assert sol.success, sol.message
        Y[:] = sol.sol(t_eval).T
    return t_eval, Y


def reference_key(name, scene, method, rtol, atol):
    """Hash of everything a cached reference depends on (including this file's derivation)."""
    h = hashlib.sha256()
    h.update(json.dumps([name, scene_with_defaults(scene), method, rtol, atol], sort_keys=True).encode())
    h.update(sp.srepr(SYM["R_" + name]).encode())
    import scipy

    h.update(scipy.__version__.encode())
    return h.hexdigest()[:20]


# --------------------------------------------------------------------------------------------------
# Small oscillations about the static equilibrium at a fixed turn angle phi
# --------------------------------------------------------------------------------------------------


def _stiffness_fun():
    """Lambdified exact Jacobian dR_reduced/d(v1, theta1) (2x2, row-major) in the ARGS_REDUCED layout."""
    global _F_STIFF
    if _F_STIFF is None:
        _F_STIFF = _lambdify_list(ARGS_REDUCED, [sp.diff(e, x) for e in SYM["R_reduced"] for x in (v1s, th1s)])
    return _F_STIFF


_F_STIFF = None


def _static_point(phi, q):
    return np.array([phi, 0.0, 0.0, q[0], q[1], 0.0, 0.0, 0.0, 0.0])


def static_equilibrium(phi, params=None):
    """Static equilibrium (v1, theta1) of the reduced model at fixed phi (phi' = phi'' = 0): fsolve from
    q = 0, then Newton steps with the exact Jacobian (fsolve may stop with "not making good progress"
    once it is at rounding level for large static deflections); the residual must vanish relative to
    the size of its terms."""
    from scipy.optimize import fsolve

    F = _FORMS["reduced"]
    fK = _stiffness_fun()

    def res(q):
        return F.residual([_static_point(phi, q)], params)[0]

    q, info, ier, msg = fsolve(res, [0.0, 0.0], full_output=True, xtol=1e-14)
    for _ in range(3):
        X = _static_point(phi, q)
        K = np.asarray(fK(*X, *_pvec(params))).reshape(2, 2)
        q = q - np.linalg.solve(K, res(q))
    scale = F.row_scale([_static_point(phi, q)], params)[0]
    assert np.all(np.abs(res(q)) <= 1e-12 * (1.0 + scale)), (phi, q, res(q), msg)
    return q


def small_oscillations(phi, params=None):
    """(q*, omega^2 ascending) of the reduced model linearized about its static equilibrium q* at a
    fixed turn angle phi (drive locked: phi' = phi'' = 0): Mass(q*) dq'' + K dq = 0 with K = dR/dq at
    q*, q' = q'' = 0 (velocity-dependent terms vanish at rest). No stability assumption: an
    omega^2 <= 0 is a non-oscillatory (unstable) mode."""
    from scipy.linalg import eig

    F = _FORMS["reduced"]
    q = static_equilibrium(phi, params)
    X0 = _static_point(phi, q)
    Mm = F.mass_b([X0], params)[0][0]
    # stiffness by exact symbolic differentiation
    K = np.asarray(_stiffness_fun()(*X0, *_pvec(params))).reshape(2, 2)
    w2 = eig(K, Mm, right=False)
    assert np.max(np.abs(np.imag(w2))) <= 1e-12 * np.max(np.abs(w2)), w2
    return q, np.sort(np.real(w2))


def natural_periods(phi, params=None):
    """Periods (s, longest first) of small oscillations of the reduced model about its static equilibrium
    at a fixed turn angle phi (drive locked: phi' = phi'' = 0); see small_oscillations. Both modes must
    be oscillatory."""
    _, w2 = small_oscillations(phi, params)
    assert np.all(w2 > 0), f"static equilibrium at phi={phi} is not stable: omega^2 = {w2}"
    return 2 * math.pi / np.sqrt(w2)


# --------------------------------------------------------------------------------------------------
# Hinge reactions N, P, M (paper eq. 18-19)
# --------------------------------------------------------------------------------------------------
# The body is freed: its own coordinates are the hinge displacement (u2 along x, v2 along y) and its
# absolute angle Theta, with L_body = T2 - Pi2, C = (l + u2 + r cos Theta, v2 + r sin Theta),
# T2 = 1/2 M2 |C'|^2 + 1/2 J_C Theta'^2, Pi2 = -M2 g (u2 + r cos Theta). With
# E_x = d/dt dL_body/dx' - dL_body/dx the reactions are N = -E_u2, P = -E_v2, M = -E_Theta (the force
# and moment the body applies to the beam tip), evaluated on the motion v2 = v1, Theta = theta1 + phi,
# u2 = the hinge coordinate (u1(v1, theta1) in the reduced model).


def _derive_reactions():
    u2b = sp.Function("u2_body")(t)
    v2b = sp.Function("v2_body")(t)
    thb = sp.Function("Theta_body")(t)
    xC = l + u2b + r * sp.cos(thb)
    yC = v2b + r * sp.sin(thb)
    T2 = sp.Rational(1, 2) * M2 * (xC.diff(t) ** 2 + yC.diff(t) ** 2) + sp.Rational(1, 2) * J_C * thb.diff(t) ** 2
    Pi2 = -M2 * g * (u2b + r * sp.cos(thb))
    E = _euler_lagrange(T2 - Pi2, [u2b, v2b, thb])
    NPM = [-e for e in E]
    # on the motion (derivatives replaced highest order first, then the functions themselves)
    on = {u2b: _u2f, v2b: _v1f, thb: _th1f + _phif}
    out = []
    for e in NPM:
        for k in (2, 1):
            e = e.subs({f.diff(t, k): target.diff(t, k) for f, target in on.items()})
        e = e.subs(on)
        out.append(sp.expand(_to_symbols(e)))
    return out


SYM["reactions"] = _derive_reactions()
_f_reactions = _lambdify_list(ARGS_DAE, SYM["reactions"])
_f_u1_derivs = _lambdify_list(
    (v1s, th1s, dv1s, dth1s, ddv1s, ddth1s), [SYM["u1"], SYM["du1"], SYM["ddu1"]]
)


def hinge_reactions_dae(X, params=None):
    """X: (n, 12) rows in the ARGS_DAE layout (phi dphi ddphi v1 theta1 u2 dv1 dtheta1 du2 ddv1 ddtheta1
    ddu2). Returns (n, 3): N, P, M."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    return _f_reactions(*[X[:, i] for i in range(X.shape[1])], *_pvec(params)).T


def hinge_reactions_reduced(X, params=None):
    """X: (n, 9) rows in the ARGS_REDUCED layout (phi dphi ddphi v1 theta1 dv1 dtheta1 ddv1 ddtheta1);
    the hinge coordinate is u2 = u1(v1, theta1) with u2' and u2'' its exact time derivatives along the
    motion. Returns (n, 3): N, P, M."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    ph_, dph_, ddph_, v1_, th1_, dv1_, dth1_, ddv1_, ddth1_ = (X[:, i] for i in range(9))
    u, du, ddu = _f_u1_derivs(v1_, th1_, dv1_, dth1_, ddv1_, ddth1_, *_pvec(params))
    Xd = np.stack([ph_, dph_, ddph_, v1_, th1_, u, dv1_, dth1_, du, ddv1_, ddth1_, ddu], axis=1)
    return hinge_reactions_dae(Xd, params)
