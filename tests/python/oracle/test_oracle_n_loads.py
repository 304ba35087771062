"""Loads of the quadratic beam in n elements, and the beam's own weight, against the n-element oracle
(tests/python/oracle_n.py: energies by quadrature, its own equations and integrator; no code of src/).

* The Rust CLI's hinge reactions N, P, M and root loads M_root, Q_root (`--columns beam`) for n = 1, 2
  and 4 elements on the paper's scene over [0, 3 s] (the turn and 2.15 s of vibration) and on the same
  scene with Rayleigh damping, against the oracle's loads on its own trajectory: N, P, M by Newton-Euler
  for the freed body, M_root and Q_root as the clamp's reactions by d'Alembert's principle with the
  virtual rigid motions of beam and body (oracle_n's docstring, "Loads"). The oracle's loads are first
  checked against two other derivations: the clamp's reactions as the residual rows of the model with
  the clamp freed, and (n = 1) the sympy oracle's hinge reactions (Lagrange's equations of the freed
  body, tests/python/oracle.py); and the hinge loads must close the beam's own equations.
* The beam's weight (`beam_gravity`): oracle_n's potential -int m g x ds of the inextensible beam, g
  along +x (> 0 stretches the beam, as the body's weight), is checked against the Euler-Lagrange
  operator of the potential computed as the double integral it is, and against the frequencies of the
  hanging chain (EI and the body -> 0). The Rust's quadratic beam refuses `beam_gravity` ("needs
  `beam` = exact": the paper's beam has no weight), so the Rust side is its exact beam at a small turn
  (phi_end = 0.003), where the exact and the quadratic beam in the same n elements differ only by terms
  cubic in the motion (docs/model.md: 1.25e-7 of the peak in v1 without the weight); the same oracle
  without the weight misses it by 7e-2.

The Rust runs at rtol 1e-12: at 1e-10 its loads carry its own integration error, 2.9e-6 of the peak in
N with 4 elements (measured against rtol 1e-12 and against the oracle at a 4x finer step, which moves
its loads by 1e-9). Measured figures go to target/oracle-report.txt ("# n-loads ...").
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import jn_zeros

import oracle
import oracle_n as on
from conftest import PAPER_SCENE, read_csv, run_cli, set_args, write_report
from test_oracle_elements import _check_lagrange

RNG_SEED = 20200139
T_END = 3.0  # s: the turn (0.85 s) and 2.15 s of the vibration after it
LOADS = ("N", "P", "M", "M_root", "Q_root")
DAMPED = {"damping_alpha": 0.5, "damping_beta": 1e-3}  # 1/s, s: zeta = 0.07 in the first mode, the
# highest ones (2.2e3 rad/s with 4 elements) overdamped
SCENES = {"paper": {"t_end": T_END}, "damped": {"t_end": T_END, **DAMPED}}
T_JUMP_EXCLUSION = 1e-9  # s: the row at t_rot is skipped (phi'' jumps there; the loads are two-valued)


def _report(key, text):
    print("\n" + text)
    write_report(f"n-loads-{key}", "# n-loads " + text)


def _simulate(beam_body, n, scene, extra=()):
    # atol 1e-15, the BDF's default at this rtol, for either integrator (Radau's default is atol = rtol).
    out = run_cli(beam_body, ["simulate", str(PAPER_SCENE), "--elements", str(n), "--rtol", "1e-12",
                              "--set", "atol=1e-15", "--columns", "beam", *extra, *set_args(scene)])
    return read_csv(out)


# --------------------------------------------------------------------------------------------------
# The oracle's loads, three ways
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [1, 2, 4])
@pytest.mark.parametrize("beam_gravity", [False, True], ids=["no-weight", "weight"])
def test_oracle_loads_agree_with_the_clamp_s_residual_rows_and_the_beam_s_balance(n, beam_gravity):
    """At random states (moderately large deflections, any phi, Rayleigh damping), with the oracle's own
    accelerations:
    * root_loads (virtual rigid motions) = clamp_reactions (the rows of v_0, th_0 of the model with the
      clamp freed), whose other rows vanish;
    * the hinge loads close the beam's equations: the beam alone, loaded at its tip by (N, P, M) through
      the virtual work N du1 + P dv1 + M dtheta1 (du1 = -G q . dq), obeys
      M_b q'' + D q' + K q + K_w q = -N G q + P b + M c;
    * n = 1: (N, P, M) are the sympy oracle's hinge reactions (no damping or weight there).
    Measured: root loads two ways (relative to each one's peak) 1.7e-15, 6.2e-15, 4.6e-14 at n = 1, 2, 4
    (the round-off of the clamp's stiff rows, K ~ 1e5 N/m at n = 4, against loads of 1e2); the freed
    rows and the beam's balance (relative to the largest term) <= 1.9e-15; sympy 4.5e-16. Asserted
    2e-13."""
    rng = np.random.default_rng(RNG_SEED + n)
    mdl = on.model(n, DAMPED, beam_gravity=beam_gravity)
    count = 30
    phis = (rng.uniform(-np.pi, np.pi, count), rng.normal(0, 3, count), rng.normal(0, 20, count))
    q = rng.normal(0, 0.15, (count, mdl.ndof))
    qd = rng.normal(0, 1.0, (count, mdl.ndof))
    qdd = mdl.accelerations(phis, q, qd)
    M_root, Q_root = mdl.root_loads(phis, q, qd, qdd)
    M_c, Q_c, rest = mdl.clamp_reactions(phis, q, qd, qdd)
    N, P, M = mdl.hinge_loads(phis, q, qd, qdd)
    # the size of the beam's rows: its inertia, elastic and damping forces
    terms = [qdd @ mdl.Mb, q @ mdl.K, qd @ mdl.D, q @ mdl.Kw, N[:, None] * (q @ mdl.G),
             P[:, None] * mdl.b, M[:, None] * mdl.c]
    size = max(float(np.max(np.abs(t))) for t in terms)
    balance = terms[0] + terms[1] + terms[2] + terms[3] + terms[4] - terms[5] - terms[6]
    err = {
        "M_root": float(np.max(np.abs(M_root - M_c)) / np.max(np.abs(M_c))),
        "Q_root": float(np.max(np.abs(Q_root - Q_c)) / np.max(np.abs(Q_c))),
        "freed rows": float(np.max(np.abs(rest)) / size),
        "beam balance": float(np.max(np.abs(balance)) / size),
    }
    if n == 1 and not beam_gravity:
        plain = on.model(1)
        qdd1 = plain.accelerations(phis, q, qd)
        X = np.column_stack([*phis, q, qd, qdd1])
        ref = oracle.hinge_reactions_reduced(X)
        mine = np.column_stack(plain.hinge_loads(phis, q, qd, qdd1))
        err["sympy"] = float(np.max(np.abs(mine - ref) / np.max(np.abs(ref), axis=0)))
    _report(f"oracle-{n}-{int(beam_gravity)}",
            f"oracle loads three ways, n={n}{' with the weight' if beam_gravity else ''}: " +
            ", ".join(f"{k} {v:.1e}" for k, v in err.items()))
    for k, v in err.items():
        assert v <= 2e-13, (k, err)


# --------------------------------------------------------------------------------------------------
# The Rust CLI's loads against the oracle's
# --------------------------------------------------------------------------------------------------

#: (scene, n) -> (tolerance of the loads relative to each one's peak, of v1 and theta1 in m or rad).
#: Measured, max over N, P, M, M_root, Q_root; max over v1, theta1:
#:   paper  n=1: 1.4e-9 (M), 2.3e-10   n=2: 2.3e-8 (N), 8.5e-12   n=4: 6.7e-8 (N), 2.9e-12
#:   damped n=1: 6.1e-10 (M), 8.9e-11  n=2: 5.8e-10 (Q_root), 4.5e-11  n=4: 4.0e-10 (Q_root), 3.9e-11
#: The undamped elements' figures are the Rust's integration error in its fastest modes (rtol 1e-13
#: and the oracle at a 4x finer step leave them; the damping's beta takes those modes away).
TOL = {
    ("paper", 1): (5e-9, 1e-9),
    ("paper", 2): (7e-8, 3e-11),
    ("paper", 4): (2e-7, 1e-11),
    ("damped", 1): (2e-9, 3e-10),
    ("damped", 2): (2e-9, 1.5e-10),
    ("damped", 4): (1.5e-9, 1.5e-10),
}


@pytest.mark.parametrize("scene,n", list(TOL), ids=[f"{s}-n{n}" for s, n in TOL])
def test_rust_loads_match_the_oracle(beam_body, scene, n):
    sc = SCENES[scene]
    rust = _simulate(beam_body, n, sc)
    traj = on.trajectory(n, scene=sc, t_eval=rust["t"])
    ref = traj.loads()
    keep = np.abs(rust["t"] - on.scene_with_defaults(sc)["t_rot"]) > T_JUMP_EXCLUSION
    assert keep.sum() == len(keep) - 1, "expected exactly one output row at t_rot"
    rel = {k: float(np.max(np.abs(rust[k] - ref[k])[keep]) / np.max(np.abs(ref[k]))) for k in LOADS}
    motion = {k: float(np.max(np.abs(rust[k] - getattr(traj, k)))) for k in ("v1", "theta1")}
    # information: the elements' own EI v''(0) is not the clamp's reaction (it converges more slowly)
    curvature = float(np.max(np.abs(traj.root_moment() - ref["M_root"])) / np.max(np.abs(ref["M_root"])))
    tol_loads, tol_motion = TOL[(scene, n)]
    _report(f"rust-{scene}-{n}",
            f"rust {scene} n={n}: max |CLI - oracle| / peak: " +
            ", ".join(f"{k} {v:.1e}" for k, v in rel.items()) + "; " +
            ", ".join(f"{k} {v:.1e}" for k, v in motion.items()) +
            f" (abs); the oracle's EI v''(0) vs its M_root: {curvature:.1e}")
    for k in LOADS:
        assert np.all(np.isfinite(rust[k])), k
        assert rel[k] <= tol_loads, (k, rel)
    for k in motion:
        assert motion[k] <= tol_motion, (k, motion)


# --------------------------------------------------------------------------------------------------
# The beam's weight
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("basis,n,tol", [("hermite", 3, 3e-14), ("poly", 5, 5e-12)])
def test_oracle_beam_weight_is_the_euler_lagrange_operator_of_its_potential(basis, n, tol):
    """The residuals with the weight (reduced and dae, damping on) against the finite-difference
    Euler-Lagrange operator of the energies (test_oracle_elements._check_lagrange), whose potential
    Pi_w = -int m g (s + u(s)) ds is the double integral (u(s) by its own rule on [0, s]), not K_w.
    Measured 7.6e-15 (hermite 3), 1.4e-12 (poly 5) of a row's size (the stencil's round-off); asserted
    3e-14 and 5e-12. The check can fail: with K_w's sign flipped it misses by 4e-3 and 3e-4."""
    rng = np.random.default_rng(RNG_SEED + 10 * n)
    params = {"l": 2.1, "M2": 7.0, "J_C": 0.6, "r": 0.35}
    mdl = on.model(n, params, basis, damping=(0.3, 2e-3), beam_gravity=True)
    worst = _check_lagrange(mdl, rng, count=4, tol=tol)
    _report(f"weight-lagrange-{basis}{n}",
            f"beam weight: Euler-Lagrange of the energies vs residual ({basis} {n}): {worst:.1e}")
    mdl.Kw *= -1.0
    with pytest.raises(AssertionError):
        _check_lagrange(mdl, np.random.default_rng(RNG_SEED + 10 * n), count=1, tol=1e-6)


def test_oracle_beam_weight_gives_the_hanging_chain():
    """With EI and the body -> 0 the beam under its weight is the hanging chain, whose angular
    frequencies are omega_k = (j_0,k / 2) sqrt(g / l), j_0,k the zeros of the Bessel function J_0
    (D. Bernoulli 1733; Rayleigh, The Theory of Sound, vol. 1, 1894, the vertical chain): the tension
    m g (l - x) of the weight beyond x, g > 0 along +x. The elements' clamp v'(0) = 0, which the chain
    has not, costs a frequency error of 0.058/n, so two meshes are extrapolated (Richardson, first order).
    Measured, modes 1-3, 16 and 32 elements: 1.8e-5, 2.0e-5, 2.4e-5; asserted 1e-4. A weight of the
    wrong sign compresses the chain: no real frequencies."""
    p = {"EI": 1e-6, "M2": 1e-6, "J_C": 0.0, "r": 0.0, "m": 2.0, "l": 2.5, "g": 10.0}
    chain = jn_zeros(0, 3) / 2.0 * math.sqrt(p["g"] / p["l"])
    w16, w32 = (on.natural_frequencies(n, 0.0, p, k=3, beam_gravity=True) for n in (16, 32))
    assert np.all(w32 < w16) and np.all(w32 > chain), (w16, w32, chain)  # Ritz: from above
    err = np.abs(2.0 * w32 - w16 - chain) / chain
    _report("weight-chain", "beam weight: hanging chain, modes 1-3, 16/32 elements extrapolated: " +
            ", ".join(f"{e:.1e}" for e in err))
    assert np.all(err <= 1e-4), err


#: Rust's exact beam with its weight, n = 2, phi_end = 0.003, against oracle_n's quadratic beam with the
#: weight; max |diff| / peak (N: of N - M2 g, second order in the motion). Measured: v1 1.2e-7, theta1
#: 1.1e-7, N 4.7e-7, P 2.7e-7, M 5.9e-8, M_root 1.5e-7, Q_root 2.8e-7. v1, theta1, M, M_root are the
#: cubic terms of the exact beam (halving the turn divides them by 4); P, Q_root, N add the Rust's
#: integration error (rtol 1e-13 halves them). Without the weight the oracle misses by 2.9e-2 (M) to
#: 1.3e-1 (Q_root).
TOL_WEIGHT = {"v1": 4e-7, "theta1": 4e-7, "N": 1.5e-6, "P": 1e-6, "M": 2e-7, "M_root": 5e-7,
              "Q_root": 1e-6}
SMALL_TURN = {"t_end": T_END, "phi_end": 0.003}


def test_rust_exact_beam_weight_at_a_small_turn_matches_the_oracle(beam_body):
    n = 2
    rust = _simulate(beam_body, n, SMALL_TURN, ["--beam", "exact", "--set", "beam_gravity=true"])
    keep = np.abs(rust["t"] - on.scene_with_defaults(SMALL_TURN)["t_rot"]) > T_JUMP_EXCLUSION
    M2g = on.full_params()["M2"] * on.full_params()["g"]

    def misses(beam_gravity):
        traj = on.trajectory(n, scene=SMALL_TURN, t_eval=rust["t"], beam_gravity=beam_gravity)
        ref = {**traj.loads(), "v1": traj.v1, "theta1": traj.theta1}
        ref["N"] = ref["N"] - M2g
        got = {k: rust[k] for k in ref}
        got["N"] = got["N"] - M2g
        return {k: float(np.max(np.abs(got[k] - ref[k])[keep]) / np.max(np.abs(ref[k]))) for k in TOL_WEIGHT}

    rel = misses(True)
    without = misses(False)
    _report("weight-rust-exact",
            f"beam weight: rust exact n={n} phi_end=0.003 vs oracle_n quadratic, max |diff| / peak: " +
            ", ".join(f"{k} {v:.1e}" for k, v in rel.items()) + "; the oracle without the weight: " +
            ", ".join(f"{k} {v:.1e}" for k, v in without.items()))
    for k, tol in TOL_WEIGHT.items():
        assert rel[k] <= tol, (k, rel)
        assert without[k] >= 1e4 * tol, (k, without)  # the weight is seen
