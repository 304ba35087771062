"""FMU state and instance life cycle through fmpy.fmi2.FMU2Slave: getFMUstate/setFMUstate rollback,
serializeFMUstate/deSerializeFMUstate into another instance, fmi2Reset, and two instances side by side.
Every comparison is exact (==): a restored or repeated run must do the same arithmetic.

The three ways phi reaches the model are covered: the law (phi_source = law), values only (the FMU
extrapolates from its history of samples, which must be part of the state) and values with derivatives.
The input modes use a sine wave, not the paper's law: the law is constant after t = 0.85, where any
history of samples extrapolates to the same value and a state that lost its history would go unnoticed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from fmu_util import OUTPUTS, PHI_SOURCE_LAW, T_END, Slave

H = 0.01  # communication step: t = 3 and t = 5 are communication points
K3, K5 = 300, 500
MODES = ("law", "values", "derivatives")
# The integrators (integrator: 1 = bdf, 2 = radau), each on the beam it is for: the paper's model
# with the BDF; Radau on the exact beam in 2 elements (beam: 2 = exact), whose state holds the
# structured Jacobian.
INTEGRATORS = {"bdf": {}, "radau": {"integrator": 2, "beam": 2, "n_elements": 2}}


def make(fmu_unzipdir, md, mode, name="a", reals=None, tolerance=1e-6, integrator="bdf"):
    s = Slave(fmu_unzipdir, md, name=name)
    integers = {"phi_source": PHI_SOURCE_LAW} if mode == "law" else {}
    integers.update(INTEGRATORS[integrator])
    return s.start(tolerance=tolerance, start_time=0.0, stop_time=T_END, integers=integers, reals=reals, phi0=0.0)


def wave(t, a=0.5, w=3.0):
    """The input of the input modes: phi = a (1 - cos(w t)), with phi' and phi'' (at rest at t = 0)."""
    return a * (1.0 - math.cos(w * t)), a * w * math.sin(w * t), a * w * w * math.cos(w * t)


def phi_shifted(t):
    """Another input from t = 3 on (to dirty the instance between restores): the wave plus
    0.05 sin(2 (t - 3)), so it leaves the wave smoothly. (A jump at t = 3, as a different wave
    would make, is non-physical: the beam it drives leaves the model's range and the FMU
    discards the step.)"""
    phi, dphi, ddphi = wave(t)
    x = 2.0 * (t - 3.0)
    return phi + 0.05 * math.sin(x), dphi + 0.1 * math.cos(x), ddphi - 0.2 * math.sin(x)


def step(s, mode, k, phi_fn=wave):
    tc = k * H
    if mode == "law":
        s.fmu.doStep(tc, H)
    elif mode == "values":
        s.step_input(tc, H, phi_fn(tc)[0])
    else:
        s.step_input(tc, H, *phi_fn(tc))
    return s.get(OUTPUTS)


def run(s, mode, k0, k1, phi_fn=wave):
    return np.array([step(s, mode, k, phi_fn) for k in range(k0, k1)])


def assert_same(a, b, what):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape, f"{what}: shapes {a.shape} != {b.shape}"
    if not np.array_equal(a, b):
        i, j = np.argwhere(a != b)[0]
        pytest.fail(
            f"{what}: not bit-identical; first difference at step {i}, {OUTPUTS[j]}: {a[i, j]!r} != {b[i, j]!r} "
            f"(max |diff| {np.max(np.abs(a - b)):.3e})",
            pytrace=False,
        )


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("mode", MODES)
def test_get_set_state_rollback(fmu_unzipdir, fmu_model_description, fmu_report, mode, integrator):
    """Run to t = 3, getFMUstate, run to 5 (recording), setFMUstate, run to 5 again: identical. Then
    restore, run 3 -> 5 with another input, restore again and rerun the original: identical again.
    An uninterrupted run 0 -> 5 gives the same outputs too (getFMUstate has no side effect)."""
    md = fmu_model_description
    straight = make(fmu_unzipdir, md, mode, name="straight", integrator=integrator)
    s = make(fmu_unzipdir, md, mode, name="rollback", integrator=integrator)
    try:
        y_straight = run(straight, mode, 0, K5)
        run(s, mode, 0, K3)
        state = s.fmu.getFMUstate()
        y1 = run(s, mode, K3, K5)
        s.fmu.setFMUstate(state)
        assert s.get(OUTPUTS) == list(y_straight[K3 - 1]), f"{mode}: outputs at t = 3 after setFMUstate"
        y2 = run(s, mode, K3, K5)
        s.fmu.setFMUstate(state)
        y_other = run(s, mode, K3, K5, phi_fn=phi_shifted)
        s.fmu.setFMUstate(state)
        y3 = run(s, mode, K3, K5)
        s.fmu.freeFMUstate(state)
        assert_same(y1, y2, f"{mode}: run 3 -> 5 after setFMUstate")
        assert_same(y1, y3, f"{mode}: run 3 -> 5 after a second setFMUstate")
        assert_same(y_straight[K3:K5], y1, f"{mode}: rollback run vs uninterrupted run")
        if mode != "law":
            assert not np.array_equal(y_other, y1), f"{mode}: the shifted input changed nothing"
        assert not s.errors() and not straight.errors(), s.errors() + straight.errors()
        fmu_report.figure(f"state {mode} {integrator}", "rollback_max|diff|", float(np.max(np.abs(y1 - y3))))
    finally:
        s.free()
        straight.free()


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("mode", MODES)
def test_serialized_state_continues_in_a_new_instance(fmu_unzipdir, fmu_model_description, fmu_report, mode, integrator):
    """serializeFMUstate at t = 3, deSerializeFMUstate + setFMUstate in a NEW instance (another
    instanceName, only instantiated), then both step 200 times: identical at every step."""
    md = fmu_model_description
    a = make(fmu_unzipdir, md, mode, name="original", integrator=integrator)
    b = Slave(fmu_unzipdir, md, name="restored")  # instantiated only
    try:
        run(a, mode, 0, K3)
        state = a.fmu.getFMUstate()
        data = a.fmu.serializeFMUstate(state)
        a.fmu.freeFMUstate(state)
        fmu_report.figure(f"state {mode} {integrator}", "serialized_bytes", len(data))
        assert isinstance(data, bytes) and len(data) > 0
        state_b = b.fmu.deSerializeFMUstate(data)
        b.fmu.setFMUstate(state_b)
        b.fmu.freeFMUstate(state_b)
        assert b.get(OUTPUTS) == a.get(OUTPUTS), f"{mode}: outputs right after the restore"
        ya = run(a, mode, K3, K3 + 200)
        yb = run(b, mode, K3, K3 + 200)
        assert_same(ya, yb, f"{mode}: original vs restored instance")
        assert not a.errors() and not b.errors(), a.errors() + b.errors()
        # the restored instance keeps its own name: an illegal doStep (wrong time) is logged as "restored"
        with pytest.raises(FMICallException):
            b.fmu.doStep(0.0, H)
        assert b.errors() and all(m[0] == "restored" for m in b.errors()), b.errors()
        assert not a.errors(), f"the restored instance's error was logged under the original's name: {a.errors()}"
    finally:
        a.free()
        b.free()


@pytest.mark.parametrize("mode", ("law", "values"))
def test_reset_then_rerun_is_identical(fmu_unzipdir, fmu_model_description, mode):
    """A fresh instance's run equals the run of an instance that first ran with EI = 2000, was reset
    (back to the start values) and set up again; and again after a second reset."""
    md = fmu_model_description
    fresh = make(fmu_unzipdir, md, mode, name="fresh")
    s = make(fmu_unzipdir, md, mode, name="reset", reals={"EI": 2000.0})
    try:
        y0 = run(fresh, mode, 0, K3)
        y_ei = run(s, mode, 0, K3 // 2)
        assert not np.array_equal(y_ei, y0[: K3 // 2]), "EI = 2000 changed nothing"
        integers = {"phi_source": PHI_SOURCE_LAW} if mode == "law" else {}
        for attempt in (1, 2):
            s.fmu.reset()
            s.start(tolerance=1e-6, start_time=0.0, stop_time=T_END, integers=integers, phi0=0.0)
            assert s.fmu.getReal([s.vr["EI"]]) == [1000.0], "fmi2Reset did not restore the start value of EI"
            y = run(s, mode, 0, K3)
            assert_same(y0, y, f"{mode}: rerun after reset #{attempt}")
        assert not s.errors(), s.errors()
    finally:
        s.free()
        fresh.free()


@pytest.mark.parametrize("mode", ("law", "values"))
def test_two_instances_side_by_side(fmu_unzipdir, fmu_model_description, mode):
    """Two instances in one process (EI = 1000 and 2000), stepped alternately over the whole scene,
    equal the same two runs done one after the other."""
    md = fmu_model_description
    n = int(round(T_END / H))
    sep = {}
    for ei in (1000.0, 2000.0):
        s = make(fmu_unzipdir, md, mode, name=f"alone-{ei:g}", reals={"EI": ei})
        try:
            sep[ei] = run(s, mode, 0, n)
        finally:
            s.free()
    a = make(fmu_unzipdir, md, mode, name="a", reals={"EI": 1000.0})
    b = make(fmu_unzipdir, md, mode, name="b", reals={"EI": 2000.0})
    try:
        ya, yb = [], []
        for k in range(n):
            ya.append(step(a, mode, k))
            yb.append(step(b, mode, k))
        assert_same(sep[1000.0], ya, f"{mode}: EI = 1000 interleaved vs alone")
        assert_same(sep[2000.0], yb, f"{mode}: EI = 2000 interleaved vs alone")
        assert not np.array_equal(sep[1000.0], sep[2000.0])
    finally:
        a.free()
        b.free()
