"""Hinge reactions N, P, M of the paper scene and the natural periods of `beam-body modes`, against the
oracle.

Reactions (paper eq. 18-19): the body is freed with its own coordinates (u2, v2, Theta); with
L_body = T2 - Pi2 and E_x = d/dt dL_body/dx' - dL_body/dx, N = -E_u2, P = -E_v2, M = -E_Theta, derived
symbolically in oracle._derive_reactions and evaluated on the motion (v2 = v1, Theta = theta1 + phi,
u2 = u1(v1, theta1)). The reference motion is the cached scipy DOP853 solution of the oracle's reduced
ODE (test_oracle_paper.reference); its accelerations come from the oracle's right-hand side and u2'' is
the exact second time derivative of u1(v1(t), theta1(t)).

Periods: oracle.small_oscillations / natural_periods (static equilibrium of the reduced model at a locked
turn angle, exact symbolic stiffness) against the `modes` table.

Measured numbers are printed (`pytest -s`) and written to target/oracle-report.txt.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import oracle
from conftest import run_cli, set_args, write_report
from test_oracle_paper import METHODS, reference, scene_values, simulate

TOL_REACTIONS = 1e-5  # relative to max |reference| of each of N, P, M
TOL_BALANCE = 1e-8  # beam generalized-force balance on the reference, relative
TOL_LINEAR_START = 0.10  # linear vs reduced reactions during the first LINEAR_WINDOW seconds
LINEAR_WINDOW = 0.1  # s
T_JUMP_EXCLUSION = 1e-9  # s: rows this close to t_rot are skipped (phi'' jumps, reactions two-valued)
TOL_PERIOD = 1e-6  # relative
TOL_EQUILIBRIUM = 1e-8  # m, rad (absolute)


# --------------------------------------------------------------------------------------------------
# reference reactions (memoized per scene)
# --------------------------------------------------------------------------------------------------

_REF: dict = {}


def reference_reactions(scene):
    """(t, X_reduced, NPM): the oracle's reduced reference on the scene's output grid, in the ARGS_REDUCED
    layout with accelerations from the oracle's right-hand side, and its N, P, M."""
    key = tuple(sorted(scene.items()))
    if key in _REF:
        return _REF[key]
    t, Ys = reference("reduced", scene)
    Y = Ys[METHODS[0][0]]
    p = {k: scene[k] for k in oracle.PARAM_NAMES}
    phi, dphi, ddphi = oracle.phi_law(t, scene["phi0"], scene["phi_end"], scene["t_rot"])
    X = np.stack([phi, dphi, ddphi, Y[:, 0], Y[:, 1], Y[:, 2], Y[:, 3], 0 * t, 0 * t], axis=1)
    X[:, 7:9] = oracle.accelerations("reduced", X, p)
    NPM = oracle.hinge_reactions_reduced(X, p)
    _REF[key] = (t, X, NPM)
    return _REF[key]


def _params(scene):
    return {k: scene[k] for k in oracle.PARAM_NAMES}


# --------------------------------------------------------------------------------------------------
# reactions
# --------------------------------------------------------------------------------------------------


def test_reference_reactions_balance_the_beam(paper_scene_file):
    """On the reference motion, the beam's own equations with the hinge loads (N, P, M) applied to the tip
    must balance: M_b q'' + K q = (P - p N, M - l q N), p = 6/5 v1/l - theta1/10,
    q = -v1/(10 l) + 2/15 theta1 (the virtual work N du1 + P dv1 + M dtheta1 with
    du1 = -p dv1 - l q dtheta1). This fixes the sign convention: N, P, M act on the beam (eq. 18)."""
    scene = scene_values(paper_scene_file)
    p = _params(scene)
    l, EI, m = p["l"], p["EI"], p["m"]
    t, X, NPM = reference_reactions(scene)
    Mb = np.array([[13 * m * l / 35, -11 * m * l**2 / 210], [-11 * m * l**2 / 210, m * l**3 / 105]])
    Kb = np.array([[12 * EI / l**3, -6 * EI / l**2], [-6 * EI / l**2, 4 * EI / l]])
    v1, th1, ddq = X[:, 3], X[:, 4], X[:, 7:9]
    q = np.stack([v1, th1], axis=1)
    pp = 6 / 5 * v1 / l - th1 / 10
    qq = -v1 / (10 * l) + 2 / 15 * th1
    N, P, M = NPM.T
    lhs = ddq @ Mb.T + q @ Kb.T
    rhs = np.stack([P - pp * N, M - l * qq * N], axis=1)
    scale = np.maximum(np.abs(lhs).max(axis=0), np.abs(rhs).max(axis=0))
    err = np.abs(lhs - rhs).max(axis=0) / scale
    msg = (
        f"reactions: beam balance M_b q'' + K q = (P - p N, M - l q N) on the reference: rel. residual "
        f"v1-row {err[0]:.3e}, theta1-row {err[1]:.3e} (scales {scale[0]:.4g} N, {scale[1]:.4g} N m)"
    )
    print("\n" + msg)
    write_report("reactions-balance", "# " + msg)
    assert np.all(np.isfinite(NPM))
    assert np.all(err <= TOL_BALANCE), msg


@pytest.mark.parametrize("formulation", ["reduced", "dae", "dae_stabilized"])
def test_hinge_reactions_against_reference(beam_body, paper_scene_file, formulation):
    scene = scene_values(paper_scene_file)
    t, X, NPM = reference_reactions(scene)
    c = simulate(beam_body, paper_scene_file, formulation)
    assert len(c["t"]) == len(t) and np.max(np.abs(c["t"] - t)) <= 1e-9, f"{formulation}: t column"
    keep = np.abs(t - scene["t_rot"]) > T_JUMP_EXCLUSION
    assert keep.sum() == len(t) - 1, "expected exactly one output row at t_rot"
    errs, parts = {}, []
    for j, name in enumerate("NPM"):
        col = c[name][keep]
        ref = NPM[keep, j]
        assert np.all(np.isfinite(c[name])), f"{formulation}: non-finite {name}"
        scale = np.abs(ref).max()
        d = np.abs(col - ref)
        k = int(np.argmax(d))
        errs[name] = d.max() / scale
        parts.append(
            f"{name}: rel {errs[name]:.3e} (max|diff| {d.max():.3e} at t={t[keep][k]:.4f} s, max|ref| {scale:.4g})"
        )
    line = f"reactions-{formulation} (N, P, M vs oracle on the scipy reference, t_rot row skipped): " + "; ".join(parts)
    print("\n" + line)
    write_report(f"reactions-{formulation}", "# " + line)
    for name in "NPM":
        assert errs[name] <= TOL_REACTIONS, line


def test_linear_reactions_near_reduced_at_start(beam_body, paper_scene_file):
    """The linearized model's reactions are only comparable while the motion is small: during the first
    0.1 s they must be within 10 % (of max |reduced| over that window) of the oracle's reduced ones."""
    scene = scene_values(paper_scene_file)
    t, X, NPM = reference_reactions(scene)
    c = simulate(beam_body, paper_scene_file, "linear")
    assert len(c["t"]) == len(t) and np.max(np.abs(c["t"] - t)) <= 1e-9, "linear: t column"
    for name in "NPM":
        assert np.all(np.isfinite(c[name])), f"linear: non-finite {name}"
    win = t <= LINEAR_WINDOW + 1e-12
    parts, errs = [], {}
    for j, name in enumerate("NPM"):
        ref = NPM[win, j]
        scale = np.abs(ref).max()
        errs[name] = np.abs(c[name][win] - ref).max() / scale
        parts.append(f"{name}: {errs[name]:.3e} (max|reduced| {scale:.4g})")
    line = f"reactions-linear vs oracle reduced, t <= {LINEAR_WINDOW} s ({win.sum()} rows), max|diff| / max|reduced|: " + "; ".join(parts)
    print("\n" + line)
    write_report("reactions-linear", "# " + line)
    for name in "NPM":
        assert errs[name] <= TOL_LINEAR_START, line


# --------------------------------------------------------------------------------------------------
# natural periods
# --------------------------------------------------------------------------------------------------

MODE_ANGLES = (("0", 0.0), ("pi/2", math.pi / 2), ("pi", math.pi))
MODE_SETS = {
    "paper": {},
    "other": {"l": 1.7, "EI": 350.0, "M2": 25.0, "r": 0.9, "g": 9.81},
    # the body turned back over the tip (phi = pi) is an inverted pendulum: one mode is unstable
    "unstable-at-pi": {"r": 2.0, "EI": 200.0},
}


def parse_modes(text: str) -> dict:
    lines = [ln for ln in text.splitlines() if ln.strip()]
    assert len(lines) == 1 + len(MODE_ANGLES), f"modes: expected a header and 3 rows:\n{text}"
    rows = {}
    for ln in lines[1:]:
        f = ln.split()
        assert len(f) == 5, f"modes: row {ln!r} does not have 5 fields"
        rows[f[0]] = f[1:]
    assert list(rows) == [a for a, _ in MODE_ANGLES], f"modes: row labels {list(rows)}"
    return rows


def _digits_note(s: str, ref: float) -> str:
    """Whether the printed string s is exactly the reference rounded to the digits s shows."""
    mant = s.lower().split("e")[0]
    dec = len(mant.split(".")[1]) if "." in mant else 0
    if "e" in s.lower():
        rounded = f"{ref:+.{dec}e}"
        same = float(rounded) == float(s)
    else:
        rounded = f"{ref:.{dec}f}"
        same = float(rounded) == float(s)
    return f"printed {s!r} ({'=' if same else '!='} oracle rounded to the printed digits: {rounded})"


@pytest.mark.parametrize("set_name", list(MODE_SETS))
def test_modes_against_oracle(beam_body, set_name):
    params = MODE_SETS[set_name]
    rows = parse_modes(run_cli(beam_body, ["modes", *set_args(params)]))
    failures, parts = [], []
    worst_T, worst_q = 0.0, 0.0
    for label, phi in MODE_ANGLES:
        q, w2 = oracle.small_oscillations(phi, params)
        v1_s, th1_s, T1_s, T2_s = rows[label]
        for s, ref, what in ((v1_s, q[0], "v1_eq"), (th1_s, q[1], "theta1_eq")):
            d = abs(float(s) - ref)
            worst_q = max(worst_q, d)
            if not d <= TOL_EQUILIBRIUM:
                failures.append(f"phi={label} {what}: |diff| {d:.3e} > {TOL_EQUILIBRIUM:g}; oracle {ref!r}, {_digits_note(s, ref)}")
        for s, w, what in ((T1_s, w2[0], "T1"), (T2_s, w2[1], "T2")):
            if w <= 0:
                if s != "unstable":
                    failures.append(f"phi={label} {what}: oracle omega^2 = {w:.6g} <= 0 (unstable), CLI prints {s!r}")
                continue
            T = 2 * math.pi / math.sqrt(w)
            if s == "unstable":
                failures.append(f"phi={label} {what}: CLI 'unstable', oracle period {T!r} s")
                continue
            d = abs(float(s) - T) / T
            worst_T = max(worst_T, d)
            if not d <= TOL_PERIOD:
                failures.append(f"phi={label} {what}: rel diff {d:.3e} > {TOL_PERIOD:g}; oracle {T!r} s, {_digits_note(s, T)}")
        Ts = ", ".join("unstable" if w <= 0 else f"{2 * math.pi / math.sqrt(w):.7f}" for w in w2)
        parts.append(f"phi={label}: T = {Ts} s, eq = ({q[0]:.9f}, {q[1]:.9f})")
    line = (
        f"modes [{set_name} {params}]: max rel period diff {worst_T:.3e}, max |equilibrium diff| {worst_q:.3e}; "
        + "; ".join(parts)
    )
    print("\n" + line + ("\n  " + "\n  ".join(failures) if failures else ""))
    write_report(f"modes-{set_name}", "# " + line + (" FAILURES: " + " | ".join(failures) if failures else ""))
    assert not failures, "\n".join([line, *failures])
