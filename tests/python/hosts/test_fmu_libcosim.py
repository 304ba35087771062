"""The FMU in libcosim (PyPI `libcosimpy`, the Open Simulation Platform's co-simulation library), a host
nobody on this team wrote, with phi as an input.

The scene: the paper's, with phi_source at its default (input). A fixed-step libcosim execution with a
step of 8,500,000 ns (libcosim's time is integer nanoseconds, so 8.5 ms is exact), an override
manipulator that sets phi = fmu_util.law(t)[0] at every communication point t before the step, and a
last-value observer that reads v1, theta1, u2 after it: 1200 steps, t = 0 .. 10.2 s.

What is compared, and how closely:
- the calls libcosim makes, read from the FMU's own `logCalls` trace through a traced copy of the FMU
  (fmu_util.traced_fmu, tests/python/trace_shim.c): fmi2SetupExperiment(tolerance undefined, so the
  FMU's 1e-6; startTime 0; stopTime undefined), then per step fmi2SetReal(phi) and fmi2DoStep(tc_k, h_k)
  with tc_k = k*8500000/1e9 (the nanosecond count converted to seconds), h_k = tc_(k+1) - tc_k and phi
  the law at tc_k. So tc_k is within an ulp of k*0.0085 (it differs at 555 of the 1200 steps), but h_k,
  a difference of two numbers up to 10.2, equals 0.0085 at only 4 steps and is off by up to 868 ulps of
  0.0085 (0.008499999999999997 at k = 2). test_libcosim_calls asserts exactly that sequence, so that a
  libcosim that changed it fails there, with the difference named, before the comparison below.
- libcosim's trajectory against FMPy's FMU2Slave making the same calls (setupExperiment without
  tolerance or stop time; setReal(phi), doStep(tc_k, h_k) with libcosim's tc_k, h_k and phi): bit for
  bit, v1, theta1 and u2 at all 1200 communication points. The FMU is deterministic and libcosim's extra
  calls (it reads every variable after each step, and sets parameters it is given both before
  setupExperiment and in initialization mode) change nothing, so any difference would be a call we did
  not see or state that leaks from the host.
- for scale, not for the match: FMPy on the grid simulate_fmu uses (tc = k*0.0085, h = 0.0085). Its
  tc and h differ from libcosim's as said above, and that is enough: the adaptive BDF
  ends every step on tc + h, its step-size control takes other decisions, and the two runs carry
  different global errors. Measured: v1 4.3e-5 m, theta1 3.5e-5 rad, u2 7.7e-6 m, i.e. 73, 85 and 88
  rtol*max|y|, within the tolerance's global error on this 12-period scene (a few hundred rtol*max|y|,
  see test_c_host.py). Bounded by K_GRID * rtol * max|y| per state, K_GRID = 1000 as there.

Enumerations: libcosim 0.0.6 does not support FMI 2.0 Enumeration variables. It logs "Enumeration
variable type not supported ... will be ignored" for `formulation` and `phi_source`, leaves them out of
its variable list and refuses to set them, so in libcosim both keep their defaults (reduced, input).
Integer parameters can be set (max_order, checked here) and the Boolean stability_guard is listed.
test_libcosim_enumerations_cannot_be_set shows all of it.

A failed step: libcosim checks the FMU's statuses. A step the FMU cannot complete (fmi2Discard) makes
step() return False and leaves the execution in its error state (test_libcosim_stops_at_a_failed_step).
libcosim instantiates with loggingOn = true and logs the FMU's messages at its own log level.

Figures go to target/fmu-report.txt.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from fmu_util import (H0, STATES, T_END, assert_host_matches_fmpy, law, missing_tool, read_trace, setup_of,
                      steps_of, traced_fmu)

H_NS = 8_500_000  # the communication step in libcosim's unit, ns
N_COMM = round(T_END / H0)  # 1200 steps
RTOL = 1e-6  # the FMU's tolerance when setupExperiment defines none (libcosim defines none)
# FMPy on the plain grid k*0.0085 vs libcosim's tc and h, for scale (module docstring): at most
# K_GRID * RTOL * max|y| per state. Measured K = 73 (v1), 85 (theta1), 88 (u2).
K_GRID = 1000.0
JUMP = 1e12  # rad: the input jump at t = 1 that no step can follow (test_fmu_failure.py)


@pytest.fixture(scope="module")
def cosim():
    """libcosimpy's modules; a missing package fails on CI and skips elsewhere."""
    try:
        from libcosimpy import CosimEnums, CosimExecution, CosimLogging, CosimManipulator, CosimObserver, CosimSlave
    except (ImportError, OSError) as e:
        missing_tool(f"libcosimpy is not importable ({e}): pip install -r tests/requirements.txt")
    # libcosim logs at trace level by default, every FMU message included: warnings and errors only.
    CosimLogging.log_output_level(CosimLogging.CosimLogLevel.WARNING)
    return CosimEnums, CosimExecution, CosimManipulator, CosimObserver, CosimSlave


def vrs(md, names):
    by_name = {v.name: v.valueReference for v in md.modelVariables}
    return [by_name[n] for n in names]


def new_execution(cosim, fmu):
    """An execution with one instance `beam` of the FMU, an override manipulator and a last-value
    observer: (execution, slave index, manipulator, observer, slave). Deleting them all (the test's
    references and the returned tuple) terminates and frees the instance."""
    _, CosimExecution, CosimManipulator, CosimObserver, CosimSlave = cosim
    ex = CosimExecution.CosimExecution.from_step_size(H_NS)
    slave = CosimSlave.CosimLocalSlave(fmu_path=str(fmu), instance_name="beam")
    index = ex.add_local_slave(slave)
    assert index >= 0, "libcosim could not add the FMU"
    manipulator = CosimManipulator.CosimManipulator.create_override()
    observer = CosimObserver.CosimObserver.create_last_value()
    assert ex.add_manipulator(manipulator) and ex.add_observer(observer)
    return ex, index, manipulator, observer, slave


def run_libcosim(cosim, fmu, md, n_steps=N_COMM):
    """The scene in libcosim: phi = law(t) set before every step. {'t': the time after each step, 'y':
    v1, theta1, u2 after each step (one row per step), 'wall': seconds}."""
    ex, i, manipulator, observer, slave = new_execution(cosim, fmu)
    [vr_phi], out = vrs(md, ["phi"]), vrs(md, STATES)
    t, y = [], []
    start = time.perf_counter()
    for _ in range(n_steps):
        tc = ex.status().current_time / 1e9
        assert manipulator.slave_real_values(i, [vr_phi], [law(tc)[0]])
        assert ex.step(), f"libcosim's step from t = {tc} failed"
        t.append(ex.status().current_time / 1e9)
        y.append(observer.last_real_values(i, out))
    wall = time.perf_counter() - start
    del ex, manipulator, observer, slave
    return {"t": np.array(t), "y": np.array(y), "wall": wall}


def libcosim_steps(n_steps=N_COMM):
    """(tc, h, phi) of libcosim's steps, as its time arithmetic gives them (module docstring)."""
    tc = [k * H_NS / 1e9 for k in range(n_steps + 1)]
    return [(a, b - a, law(a)[0]) for a, b in zip(tc[:-1], tc[1:])]


@pytest.fixture(scope="module")
def libcosim_run(cosim, fmu_file, fmu_model_description):
    return run_libcosim(cosim, fmu_file, fmu_model_description)


def test_libcosim_calls(cosim, fmu_file, fmu_model_description, libcosim_run, tmp_path, monkeypatch, fmu_report):
    """The calls libcosim makes, from the traced FMU: set-up, then one setReal(phi) and doStep per step
    with the tc, h and phi of libcosim_steps(); and the traced run's trajectory is the plain run's."""
    trace = tmp_path / "libcosim.trace"
    monkeypatch.setenv("BEAM_BODY_TRACE", str(trace))
    traced = run_libcosim(cosim, traced_fmu(fmu_file, tmp_path), fmu_model_description)
    calls = read_trace(trace)
    functions = [c.function for c in calls]
    fmu_report.note("libcosim", f"host's fmi2Instantiate: {calls[0].text}")

    setups = [setup_of(c) for c in calls if c.function == "fmi2SetupExperiment"]
    assert setups == [(None, 0.0, None)], f"libcosim's fmi2SetupExperiment(tolerance, start, stop): {setups}"
    order = ["fmi2SetupExperiment", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2DoStep"]
    assert [functions.index(f) for f in order] == sorted(functions.index(f) for f in order), functions[:12]
    assert functions[-2:] == ["fmi2Terminate", "fmi2FreeInstance"]
    errors = [c for c in calls if c.status != 0]
    assert not errors, f"the FMU answered libcosim with non-OK statuses: {errors[:5]}"

    steps, expected = steps_of(calls), libcosim_steps()
    assert len(steps) == N_COMM, f"{len(steps)} fmi2DoStep calls, expected {N_COMM}"
    wrong = [(k, got, want) for k, (got, want) in enumerate(zip(steps, expected)) if got != want]
    assert not wrong, f"{len(wrong)} steps differ from libcosim_steps(), first (k, traced, expected): {wrong[:3]}"
    off_grid = sum(1 for _tc, h, _phi in steps if h != H0)
    fmu_report.figure("libcosim", "steps_with_h_not_0.0085", off_grid, f"of {N_COMM}: h_k = tc_(k+1) - tc_k")
    assert np.array_equal(traced["y"], libcosim_run["y"]), "the traced FMU changed libcosim's trajectory"


def test_libcosim_matches_fmpy(fmu_unzipdir, fmu_model_description, libcosim_run, fmu_report):
    """libcosim vs FMPy making the same calls: bit for bit. FMPy on the plain grid: within K_GRID
    rtol*max|y|."""
    assert_host_matches_fmpy("libcosim", libcosim_run, libcosim_steps(), fmu_unzipdir, fmu_model_description, fmu_report, RTOL, K_GRID)


def test_libcosim_enumerations_cannot_be_set(cosim, fmu_file, fmu_model_description, capfd, fmu_report):
    """libcosim ignores the Enumeration parameters formulation and phi_source (logged, not listed, not
    settable), so phi comes from the input; the Integer parameter max_order can be set."""
    names = ["formulation", "phi_source", "max_order", "phi_applied"]
    vr = dict(zip(names, vrs(fmu_model_description, names)))
    ex, i, manipulator, observer, slave = new_execution(cosim, fmu_file)
    captured = capfd.readouterr()
    log = captured.out + captured.err
    for name in ("formulation", "phi_source"):
        message = f"Enumeration variable type not supported, variable with name {name} will be ignored"
        assert message in log, log[-2000:]
    listed = {v.name.decode() for v in ex.slave_variables(i)}
    assert {"max_order", "stability_guard", "phi"} <= listed
    assert not listed & {"formulation", "phi_source"}, f"libcosim lists {listed & {'formulation', 'phi_source'}}"

    assert not ex.integer_initial_value(i, vr["phi_source"], 2), "libcosim accepted an initial value of phi_source"
    assert not manipulator.slave_integer_values(i, [vr["formulation"]], [2]), "libcosim set formulation"
    assert ex.integer_initial_value(i, vr["max_order"], 2), "libcosim refused max_order"
    for _ in range(2):  # phi = 0 (the input's start value) while the law would have turned the body
        assert ex.step()
    max_order = observer.last_integer_values(i, [vr["max_order"]])
    phi_applied = observer.last_real_values(i, [vr["phi_applied"]])[0]
    del ex, manipulator, observer, slave
    fmu_report.note("libcosim", f"Enumerations ignored (logged, unlisted, refused); max_order set to {max_order}")
    assert max_order == [2]
    assert phi_applied == 0.0 and law(2 * H0)[0] > 1e-3, f"phi_applied = {phi_applied}: not the input"


def test_libcosim_stops_at_a_failed_step(cosim, fmu_file, fmu_model_description, fmu_report):
    """A step the FMU cannot complete (phi jumps by JUMP at t = 1, as in test_fmu_failure.py: the FMU
    returns fmi2Discard) ends libcosim's run: step() returns False, the execution is in its error state
    and its time stays at the failed step's start."""
    CosimEnums = cosim[0]
    ex, i, manipulator, observer, slave = new_execution(cosim, fmu_file)
    [vr_phi] = vrs(fmu_model_description, ["phi"])
    for _ in range(N_COMM):
        tc = ex.status().current_time / 1e9
        assert manipulator.slave_real_values(i, [vr_phi], [JUMP if tc >= 1.0 else 0.0])
        if not ex.step():
            break
    status = ex.status()
    del ex, manipulator, observer, slave
    state = CosimEnums.CosimExecutionState(status.state)
    fmu_report.note("libcosim", f"failed step: step() returned False at t = {tc}, execution state {state.name}")
    assert 1.0 <= tc < 1.0 + H0, f"libcosim stepped on to t = {tc} after the failed step"
    assert status.current_time / 1e9 == tc
    assert state == CosimEnums.CosimExecutionState.ERROR
