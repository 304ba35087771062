"""The exact-beam oracle (tests/python/oracle_exact.py, issue 28) checked against itself and the
quadratic oracle (tests/python/oracle_n.py); no Rust involved yet.

* Its residual (d'Alembert, through the chain rule along alpha) is the Euler-Lagrange operator of
  T - V computed from positions alone (finite differences of Elastica.lagrangian), at rotations of
  up to 3 rad, with and without the beam's weight.
* Its linearisation about the straight beam is the quadratic model's at the same n: the same mass
  matrix at q = 0, and residuals that differ by O(q^3) with phi held at 0 (O(q^2) while it turns:
  the paper's model keeps the tip's transverse Jacobian (b + r cos(theta) c) to first order).
* The integrals along s converge spectrally in the Gauss points per element.
* After the turn the total energy is constant (no damping), and a tiny turn agrees with the
  quadratic model to within the square of its amplitude.

Measured figures are printed (`pytest -s`) and written to target/oracle-report.txt ("# exact ...").
"""

from __future__ import annotations

import numpy as np
import pytest

import oracle_exact as ox
import oracle_n as on
from conftest import write_report


def _report(key, text):
    print(text)
    write_report(f"exact-{key}", "# exact " + text)


def _euler_lagrange(model, qf, qdf, phf, t, dt=1e-4, d=1e-5):
    """d/dt dL/dqd - dL/dq at t along q(t), phi(t), by central differences of the Lagrangian."""
    n = model.ndof

    def partial(q, qd, ph, wrt_rate):
        out = np.zeros(n)
        for k in range(n):
            e = np.zeros(n)
            e[k] = d
            if wrt_rate:
                hi, lo = model.lagrangian(q, qd + e, *ph), model.lagrangian(q, qd - e, *ph)
            else:
                hi, lo = model.lagrangian(q + e, qd, *ph), model.lagrangian(q - e, qd, *ph)
            out[k] = (hi - lo) / (2 * d)
        return out

    def p_rate(tt):
        return partial(qf(tt), qdf(tt), phf(tt)[:2], True)

    return (p_rate(t + dt) - p_rate(t - dt)) / (2 * dt) - partial(qf(t), qdf(t), phf(t)[:2], False)


@pytest.mark.parametrize("beam_gravity", [False, True])
def test_residual_is_the_euler_lagrange_operator_of_the_energies(beam_gravity):
    model = ox.Elastica(3, beam_gravity=beam_gravity)
    rng = np.random.default_rng(2)
    c = rng.standard_normal((4, model.ndof)) * np.array([0.6, 0.8, 0.5, 0.4])[:, None]

    def qf(t):
        return c[0] + c[1] * t + c[2] * t**2 + c[3] * t**3

    def qdf(t):
        return c[1] + 2 * c[2] * t + 3 * c[3] * t**2

    def phf(t):
        return (0.4 + 1.3 * t - 0.8 * t**2, 1.3 - 1.6 * t, -1.6)

    t = 0.3
    q = qf(t)
    alpha = np.max(np.abs(q @ model.N1.T))
    assert alpha > 2.0  # well beyond any quadratic cut
    residual = model.residual(phf(t), q, qdf(t), 2 * c[2] + 6 * c[3] * t)
    el = _euler_lagrange(model, qf, qdf, phf, t)
    error = np.max(np.abs(el - residual)) / np.max(np.abs(residual))
    _report(f"lagrange-{beam_gravity}",
            f"residual against d/dt dL/dqd - dL/dq (3 elements, |alpha| up to {alpha:.2f} rad, "
            f"beam gravity {beam_gravity}): {error:.1e} of its largest entry")
    assert error < 1e-6


def test_the_linearisation_is_the_quadratic_models():
    n = 2
    exact, quadratic = ox.Elastica(n), on.model(n)
    zero = np.zeros(2 * n)
    assert np.max(np.abs(exact.mass_matrix(zero, 0.3) - quadratic.mass_matrix(zero, 0.3))) < 1e-12
    rng = np.random.default_rng(5)
    q = rng.standard_normal(2 * n)
    for phis, order in [((0.0, 0.0, 0.0), 3), ((0.3, 0.5, -0.7), 2)]:
        gaps = [np.max(np.abs(exact.residual(phis, s * q, zero, zero)
                              - quadratic.residual_reduced(phis, s * q, zero, zero)))
                for s in (1e-2, 1e-3)]
        rate = np.log10(gaps[0] / gaps[1])
        _report(f"linear-{order}", f"exact - quadratic residual at q ~ 1e-2, 1e-3, phis {phis}: "
                f"{gaps[0]:.1e}, {gaps[1]:.1e} (order {rate:.2f})")
        assert abs(rate - order) < 0.05
    # With q held at 0 the rates and accelerations enter linearly in both.
    qd, qdd = 1e-3 * rng.standard_normal(2 * n), 1e-3 * rng.standard_normal(2 * n)
    phis = (0.3, 0.5, -0.7)
    gap = np.max(np.abs(exact.residual(phis, zero, qd, qdd) - quadratic.residual_reduced(phis, zero, qd, qdd)))
    assert gap < 1e-12


def test_integrals_along_the_beam_converge_in_the_gauss_points():
    rng = np.random.default_rng(3)
    for n in (1, 4):
        fine = ox.Elastica(n, npts=24)
        q, qd, qdd = (rng.standard_normal(2 * n) for _ in range(3))
        phis = (0.3, 0.5, -0.7)
        ref = fine.residual(phis, q, qd, qdd)
        errors = {k: np.max(np.abs(ox.Elastica(n, npts=k).residual(phis, q, qd, qdd) - ref))
                  / np.max(np.abs(ref)) for k in (8, 10, ox.DEFAULT_NPTS)}
        _report(f"npts-{n}", f"{n} elements, |alpha| up to {np.max(np.abs(q @ fine.N1.T)):.2f} rad: "
                "residual's error against 24 points a element: "
                + ", ".join(f"{k} points {e:.1e}" for k, e in errors.items()))
        assert errors[8] > errors[10] > errors[ox.DEFAULT_NPTS]
        assert errors[ox.DEFAULT_NPTS] < 1e-9


def test_energy_is_constant_after_the_turn():
    scene = {"t_end": 1.6, "dt_out": 0.05}
    t, q, qd, model, _ = ox.trajectory(2, scene)
    held = np.array([model.energies(q[k], qd[k], np.pi, 0.0) for k in np.flatnonzero(t >= 0.85)])
    energy, kinetic = held.sum(axis=1), held[:, 0].max()
    drift = np.max(np.abs(energy - energy[0])) / kinetic
    _report("energy", f"2 elements, paper's turn: energy over [T, 1.6 s] constant to {drift:.1e} of the "
            f"largest kinetic energy ({kinetic:.1f} J)")
    assert drift < 1e-9


def test_a_tiny_turn_agrees_with_the_quadratic_model():
    scene = {"phi_end": 0.003, "t_end": 1.7, "dt_out": 0.01}
    t, q, _, model, _ = ox.trajectory(2, scene)
    _, v1, th1 = model.tip(q)
    quad = on.trajectory(2, "reduced", scene)
    amplitude = np.max(np.abs(v1)) / model.p["l"]
    gaps = (np.max(np.abs(v1 - quad.v1)) / np.max(np.abs(v1)),
            np.max(np.abs(th1 - quad.theta1)) / np.max(np.abs(th1)))
    _report("tiny-turn", f"phi_end = 0.003, 2 elements, [0, 2T]: exact - quadratic {gaps[0]:.1e} (v1), "
            f"{gaps[1]:.1e} (theta1) of the peak; amplitude max|v1|/l = {amplitude:.1e}")
    assert max(gaps) < amplitude**2 * 10
