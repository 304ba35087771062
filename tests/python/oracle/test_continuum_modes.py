"""Continuum (Euler–Bernoulli beam-column + rigid tip body) natural frequencies at phi = 0 and pi:
the sympy derivation against the hand-written boundary conditions, analytic limits (bare cantilever,
tip point mass), an independent Rayleigh–Ritz discretisation built from the energies, and the sign of the
tension term. No Rust and no project code involved (see tests/python/continuum.py).

Run with `-s` to see the frequencies and convergence tables.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import continuum as C

PI = math.pi
OTHER = {"l": 1.7, "EI": 350.0, "m": 1.3, "M2": 25.0, "J_C": 2.0, "r": 0.9, "g": 9.81}


# ---------------------------------------------------------------------------------------------- derivation


def test_derivation_structure():
    d = C.derive_linearised_equations()
    S = d["symbols"]
    w, x, t = S["w"], S["x"], S["t"]
    assert sp.simplify(d["P"] - S["M2"] * S["g"]) == 0  # tension P = M2 g
    expected = S["EI"] * w.diff(x, 4) - S["M2"] * S["g"] * w.diff(x, 2) + S["m"] * w.diff(t, 2)
    assert sp.simplify(d["field"] - expected) == 0
    # the first-order (static) term is proportional to sin(phi): zero at phi = 0, pi
    assert d["first_order"].has(S["s"]) and sp.simplify(d["first_order"].subs(S["s"], 0)) == 0


@pytest.mark.parametrize("c", [1, -1])
@pytest.mark.parametrize("params", [C.DEFAULT_PARAMS, OTHER])
def test_hand_boundary_conditions_match_derivation(c, params):
    """The solver's tip operator (harmonic: w_tt -> -omega^2 w) equals the derived conditions up to a
    row factor (+-1)."""
    d = C.derive_linearised_equations()
    S = d["symbols"]
    W0, W1, W2, W3, A0, A1 = d["tip_symbols"]
    subs = {S[k]: params[k] for k in C.PARAM_NAMES}
    subs[S["c"]] = c
    p = C.full_params(params)
    for omega2 in (0.0, 3.7, 1234.5):
        hand = C._tip_operator(omega2, p, c)
        for row, name in ((0, "bc_shear"), (1, "bc_moment")):
            e = d[name].subs(subs).subs({A0: -omega2 * W0, A1: -omega2 * W1})
            derived = np.array([float(sp.expand(e).coeff(v)) for v in (W0, W1, W2, W3)])
            sign = np.sign(derived[2 + (1 - row)])  # EI W''' (shear) or EI W'' (moment)
            assert np.allclose(sign * derived, hand[row], rtol=1e-13, atol=1e-12), (name, derived, hand[row])


# ---------------------------------------------------------------------------------------------- limits


def test_bare_cantilever():
    """M2 = J_C = r = g = 0: beta_k l = 1.87510, 4.69409, 7.85476, omega = (beta l)^2 sqrt(EI/(m l^4))."""
    p = {"M2": 0.0, "J_C": 0.0, "r": 0.0, "g": 0.0}
    for phi in (0.0, PI):
        om = C.continuum_frequencies(phi, k=3, params=p)
        bl = np.sqrt(om / C._omega_scale(C.full_params(p)))
        assert np.allclose(bl, [1.87510, 4.69409, 7.85476], atol=6e-6), bl
        # and to full precision against 1 + cos cosh = 0 solved separately
        ref, _ = C.tip_mass_cantilever_frequencies(0.0, k=3)
        assert np.allclose(om, ref, rtol=1e-10)


@pytest.mark.parametrize("mass", [0.5, 5.0, 12.0, 100.0])
def test_tip_point_mass(mass):
    """r = J_C = g = 0: the classic tip-mass equation (Karnovsky & Lebed 2004, sec. 7.5.3)."""
    p = {"M2": mass, "J_C": 0.0, "r": 0.0, "g": 0.0}
    pp = C.full_params(p)
    om = C.continuum_frequencies(0.0, k=3, params=p)
    ref, _ = C.tip_mass_cantilever_frequencies(mass / (pp["m"] * pp["l"]), k=3, EI=pp["EI"], m=pp["m"], l=pp["l"])
    assert np.allclose(om, ref, rtol=1e-10), (om, ref)


def test_offset_only_enters_with_cos_phi():
    """r = 0: phi = 0 and phi = pi are the same system (c multiplies r only)."""
    p = {"r": 0.0}
    assert np.allclose(C.continuum_frequencies(0.0, params=p), C.continuum_frequencies(PI, params=p), rtol=1e-12)


# ---------------------------------------------------------------------------------------------- Ritz


@pytest.mark.parametrize("phi", [0.0, PI])
@pytest.mark.parametrize("params", [None, OTHER], ids=["paper", "other"])
def test_ritz_converges_to_continuum(phi, params):
    """Global polynomials x^2 P_j(2x/l - 1), matrices from the nonlinear energies (not from the boundary
    conditions): Ritz values are upper bounds, decrease with n, and converge (spectrally) to the roots."""
    cont = C.continuum_frequencies(phi, k=5, params=params)
    rows = []
    prev = None
    for n in (3, 4, 6, 8, 10, 12):
        rz = C.ritz_frequencies(phi, n, k=3, params=params)
        err = (rz - cont[:3]) / cont[:3]
        rows.append((n, err))
        assert np.all(err > -1e-10), (n, err)  # Rayleigh–Ritz upper bound (to the rounding floor)
        if prev is not None:
            assert np.all(err <= prev + 1e-10), (n, err, prev)  # down to the rounding floor
        prev = err
    assert np.all(np.abs(rows[-1][1]) < 1e-9), rows[-1]
    # no root missed or spurious among the first five
    # (measured 2.3e-10 at 16 elements, the paper's parameters)
    assert np.allclose(C.ritz_frequencies(phi, 16, k=5, params=params), cont, rtol=1e-9, atol=0)
    print(f"\nphi={phi:.4f} params={params or 'paper'} continuum: {np.array2string(cont, precision=6)}")
    for n, err in rows:
        print(f"  Ritz n={n:2d}: rel. errors of omega_1..3 = {np.array2string(err, precision=2)}")


def test_one_element_vs_continuum():
    """n = 2 spans {x^2, x^3}, the project's single Hermite element: omega_2(phi=0) = 34.6 rad/s there,
    against 33.42 rad/s for the continuum."""
    one = C.ritz_frequencies(0.0, 2, k=2)
    cont = C.continuum_frequencies(0.0, k=2)
    assert abs(one[1] - 34.6) < 0.05 and abs(cont[1] - 33.42) < 0.01, (one, cont)
    print(f"\n1 element: {one}, continuum: {cont}")


# ---------------------------------------------------------------------------------------------- tension


@pytest.mark.parametrize("r", [0.5, 0.0])
def test_tension_raises_frequencies_at_phi0(r):
    """Gravity along +x pulls the beam (P = M2 g > 0): raising g raises every frequency at phi = 0, also
    with r = 0, where only the tension term -P w'' (and -P w' in the shear condition) depends on g."""
    prev = None
    for g in (0.0, 5.0, 10.0, 20.0):
        om = C.continuum_frequencies(0.0, params={"g": g, "r": r})
        if prev is not None:
            assert np.all(om > prev * (1 + 1e-6)), (g, om, prev)
        prev = om


# ---------------------------------------------------------------------------------------------- statics


def test_static_equilibrium_straight_and_stable():
    # classic clamped-beam tip stiffness without axial force; symmetric with it
    K0 = C.beam_column_tip_stiffness({"g": 0.0})
    EI, l = 1000.0, 2.5
    assert np.allclose(K0, EI / l**3 * np.array([[12, -6 * l], [-6 * l, 4 * l * l]]), rtol=1e-12)
    K = C.beam_column_tip_stiffness()
    assert abs(K[0, 1] - K[1, 0]) < 1e-9 * abs(K).max() and K[0, 0] > K0[0, 0]  # tension stiffens
    for phi in (0.0, PI):
        assert np.all(np.abs(C.static_tip_response(phi)) < 1e-15)  # straight
        assert min(C.static_stiffness_eigenvalues(phi)) > 0  # and stable
    # at phi = pi/2 the first-order tip response is far from zero: the equilibrium is bent
    assert abs(C.static_tip_response(PI / 2)[0]) > 0.05


def test_static_instability_matches_vanishing_frequency():
    """At phi = pi the inverted body destabilises as g grows; where the static stiffness loses
    definiteness, omega_1 -> 0 in the continuum and in the Ritz model alike."""
    from scipy.optimize import brentq

    g_crit = brentq(lambda g: min(C.static_stiffness_eigenvalues(PI, {"g": g})), 300.0, 1000.0, xtol=1e-10)
    om = C.continuum_frequencies(PI, k=1, params={"g": g_crit * (1 - 1e-4)})[0]
    om_closer = C.continuum_frequencies(PI, k=1, params={"g": g_crit * (1 - 1e-6)})[0]
    assert abs((om / om_closer) ** 2 / 100.0 - 1.0) < 0.01, (om, om_closer)  # omega^2 ~ (g_crit - g)
    assert C.ritz_frequencies(PI, 14, k=1, params={"g": g_crit * (1 + 1e-4)})[0] < 0
    with pytest.raises(ValueError, match="unstable"):
        C.continuum_frequencies(PI, params={"g": g_crit * 1.01})
    print(f"\nphi = pi: straight state unstable for g > {g_crit:.4f} m/s^2 (omega_1 just below: {om:.4g})")


def test_phi_outside_0_pi_rejected():
    for bad in (PI / 2, 0.1, -PI, 2 * PI):
        with pytest.raises(ValueError, match=r"phi in \{0, pi\}.*sin\(phi\)"):
            C.continuum_frequencies(bad)
