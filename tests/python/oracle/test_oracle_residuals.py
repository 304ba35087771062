"""Residuals and accelerations of the Rust CLI (`beam-body residual`) against the sympy oracle.

For every formulation and several parameter sets, ~200 random evaluation points are batched through the
CLI's stdin. The oracle's rows come from Lagrange's equations of the model's energies (oracle.py).

Tolerances:
* residual row i: |R_rust - R_sym| <= 1e-10 * (1 + max |additive term of the expanded row|);
* accelerations: |A_rust - A_sym| <= 1e-10 * (1 + max_j |A_sym_j|) per point (the mass matrices have a
  condition number below ~40 over the sampled box, so double precision gives ~1e-14 here), and the
  Rust accelerations must also zero the oracle's residual to the residual tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import oracle
from conftest import run_cli, set_args

N_POINTS = 200
RTOL = 1e-10

PARAM_SETS = {
    "paper": {},
    "set1": {"l": 1.7, "EI": 350.0, "m": 0.8, "M2": 25.0, "J_C": 2.3, "r": 0.9, "g": 9.81},
    "set2": {"l": 3.3, "EI": 4200.0, "m": 3.5, "M2": 4.0, "J_C": 0.2, "r": 0.15, "g": 1.6},
    "set3": {"l": 0.9, "EI": 75.0, "m": 1.3, "M2": 0.7, "J_C": 0.05, "r": 1.4, "g": 20.0},
}


def random_points(formulation: str, seed: int, params: dict) -> np.ndarray:
    """Rows in the CLI's input layout for the formulation."""
    rng = np.random.default_rng(seed)
    n = N_POINTS
    phi = rng.uniform(-2 * np.pi, 2 * np.pi, n)
    dphi = rng.uniform(-10, 10, n)
    ddphi = rng.uniform(-50, 50, n)
    v1 = rng.uniform(-0.5, 0.5, n)
    th1 = rng.uniform(-0.5, 0.5, n)
    dv1, dth1 = rng.uniform(-3, 3, (2, n))
    ddv1, ddth1 = rng.uniform(-30, 30, (2, n))
    # a few special points: the undeformed state and phi on multiples of pi/2
    v1[:3] = th1[:3] = dv1[:3] = dth1[:3] = 0.0
    phi[:8] = np.arange(8) * np.pi / 2 - 2 * np.pi
    if oracle.n_dof(formulation) == 2:
        return np.column_stack([phi, dphi, ddphi, v1, th1, dv1, dth1, ddv1, ddth1])
    u2 = oracle.u1(v1, th1, params) + rng.uniform(-1e-2, 1e-2, n)
    u2[:5] = oracle.u1(v1[:5], th1[:5], params)
    du2 = rng.uniform(-3, 3, n)
    ddu2 = rng.uniform(-30, 30, n)
    return np.column_stack([phi, dphi, ddphi, v1, th1, u2, dv1, dth1, du2, ddv1, ddth1, ddu2])


def format_lines(X: np.ndarray) -> str:
    return "".join(" ".join(repr(float(x)) for x in row) + "\n" for row in X)


def parse_output(text: str, n_lines: int, n_cols: int) -> np.ndarray:
    lines = [ln for ln in text.splitlines() if ln.strip()]
    assert len(lines) == n_lines, f"expected {n_lines} output lines, got {len(lines)}"
    rows = []
    for i, ln in enumerate(lines):
        fields = ln.split()
        assert len(fields) == n_cols, f"line {i}: expected {n_cols} numbers, got {len(fields)}: {ln!r}"
        rows.append([float(f) for f in fields])
    return np.array(rows)


def describe(X, i, formulation):
    names = [str(s) for s in oracle.formulation(formulation).args]
    return ", ".join(f"{n}={float(x)!r}" for n, x in zip(names, X[i]))


@pytest.mark.parametrize("pset", list(PARAM_SETS))
@pytest.mark.parametrize("formulation", oracle.FORMULATIONS)
def test_residuals_and_accelerations_match_oracle(beam_body, formulation, pset):
    params = PARAM_SETS[pset]
    seed = 1000 * oracle.FORMULATIONS.index(formulation) + list(PARAM_SETS).index(pset)
    X = random_points(formulation, seed, params)
    k = oracle.n_dof(formulation)

    out = run_cli(
        beam_body, ["residual", "--formulation", formulation, *set_args(params)], format_lines(X)
    )
    Y = parse_output(out, len(X), 2 * k)
    R_rust, A_rust = Y[:, :k], Y[:, k:]
    assert np.all(np.isfinite(Y)), "non-finite numbers in the CLI output"

    # residual rows
    R_sym = oracle.residual(formulation, X, params)
    scale = 1.0 + oracle.row_scale(formulation, X, params)
    err = np.abs(R_rust - R_sym) / scale
    i, j = np.unravel_index(np.argmax(err), err.shape)
    print(f"\n[{formulation}/{pset}] max relative residual error {err.max():.3e} (row {j + 1})")
    assert err.max() <= RTOL, (
        f"{formulation}/{pset}: residual row {j + 1} differs: rust={float(R_rust[i, j])!r} "
        f"oracle={float(R_sym[i, j])!r} |diff|={abs(R_rust[i, j] - R_sym[i, j]):.3e} "
        f"row scale={scale[i, j]:.3e}; at {describe(X, i, formulation)}"
    )

    # accelerations: forward error against the oracle's solution of R = 0
    A_sym = oracle.accelerations(formulation, X, params)
    a_scale = 1.0 + np.max(np.abs(A_sym), axis=1, keepdims=True)
    a_err = np.abs(A_rust - A_sym) / a_scale
    i, j = np.unravel_index(np.argmax(a_err), a_err.shape)
    print(f"[{formulation}/{pset}] max relative acceleration error {a_err.max():.3e}")
    assert a_err.max() <= RTOL, (
        f"{formulation}/{pset}: acceleration {j + 1} differs: rust={float(A_rust[i, j])!r} "
        f"oracle={float(A_sym[i, j])!r} |diff|={abs(A_rust[i, j] - A_sym[i, j]):.3e}; "
        f"at {describe(X, i, formulation)}"
    )

    # backward error: the Rust accelerations zero the oracle's residual
    XA = X.copy()
    XA[:, -k:] = A_rust
    back = np.abs(oracle.residual(formulation, XA, params)) / (
        1.0 + oracle.row_scale(formulation, XA, params)
    )
    assert back.max() <= RTOL, f"{formulation}/{pset}: oracle residual at the Rust accelerations {back.max():.3e}"


# --------------------------------------------------------------------------------------------------
# Symbolic self-checks of the oracle (no Rust involved)
# --------------------------------------------------------------------------------------------------


def test_dae_with_constraint_substituted_is_reduced_model():
    """u2 = u1(q), u2' = d/dt u1, u2'' = d^2/dt^2 u1 in the DAE rows 1-2 gives exactly the reduced
    residual (the paper's claim that differentiating the constraint twice returns eq. 15)."""
    diffs = oracle.check_dae_reduces_to_reduced()
    assert diffs == [0, 0, 0], diffs


def test_linear_residual_is_first_order_series_of_reduced():
    diffs = oracle.check_linear_is_series()
    assert diffs == [0, 0], diffs


def test_linear_residual_has_exact_large_rotation_terms():
    """At the undeformed state the linear and reduced residuals coincide for any phi, phi', phi''
    (the zeroth-order terms, e.g. the body's inertia and gravity, are kept exactly)."""
    zero = {s: 0 for s in (oracle.v1s, oracle.th1s, oracle.dv1s, oracle.dth1s, oracle.ddv1s, oracle.ddth1s)}
    for e_red, e_lin in zip(oracle.SYM["R_reduced"], oracle.SYM["R_linear"]):
        assert sp.simplify(e_red.subs(zero) - e_lin.subs(zero)) == 0
        assert e_lin.subs(zero) != 0


def test_residuals_are_lagrange_equations_of_a_conservative_system():
    """Power balance at fixed phi: with phi' = phi'' = 0, q' . R(q, q', q'') = dE/dt for the reduced
    model (E = T + Pi), checked numerically at random states."""
    rng = np.random.default_rng(7)
    n = 50
    phi = rng.uniform(-np.pi, np.pi, n)
    q = rng.uniform(-0.5, 0.5, (n, 2))
    qd = rng.uniform(-3, 3, (n, 2))
    qdd = rng.uniform(-30, 30, (n, 2))
    X = np.column_stack([phi, 0 * phi, 0 * phi, q, qd, qdd])
    R = oracle.residual("reduced", X)
    power = np.sum(qd * R, axis=1)
    # dE/dt by central differences along the path q(t) = q + qd t + qdd t^2/2
    h = 1e-5

    def E_at(s):
        qs = q + qd * s + 0.5 * qdd * s * s
        qds = qd + qdd * s
        return oracle.energy_reduced(phi, 0 * phi, qs[:, 0], qs[:, 1], qds[:, 0], qds[:, 1])

    dEdt = (E_at(h) - E_at(-h)) / (2 * h)
    assert np.allclose(power, dEdt, rtol=1e-6, atol=1e-6 * np.abs(power).max())
