"""A failing step must end the run, not hang it.

FMPy 0.3.32's simulate_fmu retries a step that returned fmi2Discard for ever unless the FMU reports
fmi2Terminated = true; then it records the outputs at fmi2LastSuccessfulTime and stops. The failing
input: phi jumps by 1e12 rad at t = 1 (non-physical: the hinge would have to turn 1e12 rad in one
communication step), which the integrator cannot follow: the first step after t = 1 fails.

Guards against a hang: simulate_fmu(timeout=...) and SIGALRM, which fails the test instead.
"""

from __future__ import annotations

import re
import signal
import time
from contextlib import contextmanager

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from fmu_util import FMI2_LAST_SUCCESSFUL_TIME, FMI2_TERMINATED, H0, T_END, Slave, install_logger_proxy

JUMP = 1e12  # rad
T_JUMP = 1.0
SIM_TIMEOUT = 30.0  # s, simulate_fmu's own guard (checked between steps)
ALARM = 60  # s, SIGALRM: fails the test if the run hangs anyway
FMI2_DISCARD, FMI2_ERROR = 2, 3


@contextmanager
def alarm(seconds):
    def on_alarm(signum, frame):
        raise TimeoutError(f"the run did not return within {seconds} s: a discarded step is retried for ever?")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def jump_table():
    t = np.array([0.0, T_JUMP, T_JUMP, T_END])
    phi = np.array([0.0, 0.0, JUMP, JUMP])
    return np.array(list(zip(t, phi)), dtype=[("time", np.float64), ("phi", np.float64)])


def test_failed_step_ends_simulate_fmu(fmu_unzipdir, fmu_report):
    messages = []

    def logger(env, instance_name, status, category, message):
        messages.append((int(status), category.decode(), message.decode()))

    t0 = time.monotonic()  # for the report only
    try:
        with alarm(ALARM):
            r = fmpy.simulate_fmu(
                str(fmu_unzipdir),
                input=jump_table(),
                output_interval=H0,
                stop_time=T_END,
                output=["v1", "theta1", "phi_applied"],
                logger=logger,
                timeout=SIM_TIMEOUT,
            )
    finally:
        # FMPy's logger proxy is process-global and still points at simulate_fmu's (now dropped)
        # ctypes wrapper of `logger`: re-point it before any FMU logs again (fmu_util, _dispatch).
        install_logger_proxy()
    elapsed = time.monotonic() - t0
    t_last = float(r["time"][-1])
    fmu_report.figure("failure", "simulate_fmu_last_time", repr(t_last), f"stop {T_END}; wall {elapsed:.2f} s")
    discards = [m for m in messages if m[0] == FMI2_DISCARD]
    for m in discards:
        fmu_report.note("failure", f"logged [{m[1]}] {m[2]}")
    # The FMU ended the run (fmi2Discard, then fmi2Terminated), not simulate_fmu's timeout, which
    # would stop at whatever time the clock ran out: the last time is the step of the jump's
    # (measured 1.0, the last good communication point).
    assert T_JUMP <= t_last <= T_JUMP + H0, f"last time {t_last}: expected the step of the jump at {T_JUMP}"
    assert discards, f"no fmi2Discard message was logged; messages: {messages}"
    status, category, text = discards[-1]
    assert category == "logStatusDiscard"
    assert "fmi2LastSuccessfulTime" in text and "fmi2Terminated = true" in text, text
    # the recorded last row is the FMU's last successful time, which the message states
    m = re.search(r"stopped at t = ([0-9.eE+-]+)", text)
    assert m and float(m.group(1)) == t_last, f"last row at {t_last!r}, message: {text}"
    # before the jump phi = 0: the beam stays at rest, exactly
    before = r["time"] < T_JUMP
    assert np.count_nonzero(before) > 100 and np.all(r["v1"][before] == 0.0)


def test_failed_step_status_protocol(fmu_unzipdir, fmu_model_description):
    """The same failure through FMU2Slave: doStep returns fmi2Discard; fmi2Terminated is true;
    fmi2LastSuccessfulTime lies in the step; outputs can still be read; another doStep is an error
    (state stepFailed); terminate works. The message carries the instance name."""
    h = 0.01
    s = Slave(fmu_unzipdir, fmu_model_description, name="failing")
    try:
        s.start(tolerance=1e-6, start_time=0.0, stop_time=T_END, phi0=0.0)
        k_jump = int(round(T_JUMP / h))
        with alarm(ALARM):
            for k in range(k_jump):
                s.step_input(k * h, h, 0.0)
            tc = k_jump * h
            with pytest.raises(FMICallException) as exc:
                s.step_input(tc, h, JUMP)
        assert exc.value.status == FMI2_DISCARD, f"doStep returned {exc.value.status}, expected fmi2Discard"
        assert s.fmu.getBooleanStatus(FMI2_TERMINATED) is True
        t_ok = s.fmu.getRealStatus(FMI2_LAST_SUCCESSFUL_TIME)
        assert tc <= t_ok < tc + h, f"fmi2LastSuccessfulTime {t_ok} not in [{tc}, {tc + h})"
        y = s.get(("v1", "theta1"))
        assert all(np.isfinite(y)), y
        discards = [m for m in s.messages if m[1] == FMI2_DISCARD]
        assert discards and discards[-1][0] == "failing" and discards[-1][2] == "logStatusDiscard", s.messages
        with pytest.raises(FMICallException) as exc2:
            s.fmu.doStep(t_ok, h)
        assert exc2.value.status == FMI2_ERROR
        assert any("illegal call sequence" in m[3] for m in s.messages if m[1] == FMI2_ERROR), s.messages
        s.fmu.terminate()
    finally:
        s.free()
