"""Small oscillations of the oracle's reduced model about the static equilibrium at a fixed turn angle
(no Rust involved): `oracle.natural_periods` against a hand-written linearization, and the periods at
phi = 0, pi/2, pi printed for the report (the paper quotes "about 1.6 s" with the body turned by pi/2).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import eigh

import oracle
from conftest import write_report


def hand_periods(phi, p):
    """phi in {0, pi}: equilibrium q = 0. Linearized by hand from the energies:
    mass: beam Hermite matrix + body  M2 [[1, r c], [r c, r^2]] + J_C [[0, 0], [0, 1]], c = cos(phi)
    (at q = 0 the tip x-motion is second order); phi = pi/2 also works with c = 0 when g = 0;
    stiffness: beam matrix + M2 g * Hessian(-u1) + M2 g r c [[0, 0], [0, 1]] (from Pi2 = -M2 g (u1 + r cos theta))."""
    l, EI, m, M2, J_C, r, g = (p[k] for k in oracle.PARAM_NAMES)
    c = round(math.cos(phi))
    Mb = np.array([[13 * m * l / 35, -11 * m * l**2 / 210], [-11 * m * l**2 / 210, m * l**3 / 105]])
    Kb = np.array([[12 * EI / l**3, -6 * EI / l**2], [-6 * EI / l**2, 4 * EI / l]])
    Mbody = M2 * np.array([[1.0, r * c], [r * c, r * r]]) + J_C * np.array([[0, 0], [0, 1.0]])
    Kg = M2 * g * np.array([[6 / (5 * l), -1 / 10], [-1 / 10, 2 * l / 15]])
    Kr = M2 * g * r * c * np.array([[0, 0], [0, 1.0]])
    w2 = eigh(Kb + Kg + Kr, Mb + Mbody, eigvals_only=True)
    return np.sort(2 * math.pi / np.sqrt(w2))[::-1]


@pytest.mark.parametrize("phi", [0.0, math.pi])
@pytest.mark.parametrize("params", [{}, {"g": 0.0}, {"l": 1.7, "EI": 350.0, "M2": 25.0, "r": 0.9, "g": 9.81}])
def test_natural_periods_match_hand_linearization(phi, params):
    p = oracle.full_params(params)
    T = oracle.natural_periods(phi, params)
    assert np.allclose(T, hand_periods(phi, p), rtol=1e-10), (T, hand_periods(phi, p))


def test_natural_periods_quarter_turn_without_gravity():
    p = oracle.full_params({"g": 0.0})
    l, EI, m, M2, J_C, r = (p[k] for k in ("l", "EI", "m", "M2", "J_C", "r"))
    Mb = np.array([[13 * m * l / 35, -11 * m * l**2 / 210], [-11 * m * l**2 / 210, m * l**3 / 105]])
    Kb = np.array([[12 * EI / l**3, -6 * EI / l**2], [-6 * EI / l**2, 4 * EI / l]])
    Mm = Mb + np.diag([M2, M2 * r * r + J_C])
    w2 = eigh(Kb, Mm, eigvals_only=True)
    T_hand = np.sort(2 * math.pi / np.sqrt(w2))[::-1]
    assert np.allclose(oracle.natural_periods(math.pi / 2, {"g": 0.0}), T_hand, rtol=1e-10)


def test_natural_periods_report():
    rows = []
    for name, phi in (("0", 0.0), ("pi/2", math.pi / 2), ("pi", math.pi)):
        T = oracle.natural_periods(phi)
        q = oracle.static_equilibrium(phi)
        rows.append(
            f"phi={name}: periods {T[0]:.4f} s, {T[1]:.4f} s (static v1={q[0]:.5f} m, theta1={q[1]:.5f} rad)"
        )
    msg = "natural periods (paper parameters): " + "; ".join(rows)
    print("\n" + msg)
    write_report("periods", "# " + msg)
    T_quarter = oracle.natural_periods(math.pi / 2)[0]
    # The paper: "a period of about 1.6 s with the body turned by pi/2", two figures: the oracle's
    # 1.5348 s is 4.1 % below it. The period itself is checked tightly (1e-10) against the mass and
    # stiffness matrices assembled by hand, without gravity, above.
    assert abs(T_quarter - 1.6) < 0.05 * 1.6, msg
