"""The FMU in Ecos (PyPI `ecospy`, which loads its libecosc.so; that needs Debian's libtbb12), a host
nobody on this team wrote, with phi as an input.

The scene: the paper's, with phi_source at its default (input). An Ecos simulation of one model
instance `beam` with a fixed step of 0.0085 s; before every step the test sets `beam::phi` to
fmu_util.law(t)[0] at the simulation's time t, and after it reads beam::v1, beam::theta1, beam::u2:
1200 steps, t = 0 .. 10.2 s.

What is compared, and how closely:
- the calls Ecos makes, read from the FMU's own `logCalls` trace through a traced copy of the FMU
  (fmu_util.traced_fmu, tests/python/trace_shim.c; Ecos instantiates with loggingOn = false and has no
  switch for it): fmi2SetupExperiment(tolerance undefined, so the FMU's 1e-6; startTime 0; stopTime
  undefined), then per step fmi2SetReal(phi) (Ecos buffers the set and sends it before the step) and
  fmi2DoStep(tc_k, 0.0085) with tc_(k+1) = tc_k + 0.0085, a running sum (it ends at
  10.199999999999836, and drifts from k*0.0085 by up to 107 ulps), and phi the law at tc_k.
  test_ecos_calls asserts exactly that sequence, so that an Ecos that changed it fails there, with the
  difference named, before the comparison below.
- Ecos's trajectory against FMPy's FMU2Slave making the same calls (setupExperiment without tolerance
  or stop time; setReal(phi), doStep(tc_k, 0.0085) with Ecos's tc_k and phi): bit for bit, v1, theta1
  and u2 at all 1200 communication points. The FMU is deterministic and Ecos's extra calls (a getReal
  per variable read) change nothing, so any difference would be a call we did not see or state that
  leaks from the host.
- for scale, not for the match: FMPy on the grid simulate_fmu uses (tc = k*0.0085). The drift of Ecos's
  running sum is enough to change the adaptive BDF's step sequence (it ends every step on tc + h), and
  the two runs carry different global errors: measured v1 4.9e-5 m, theta1 4.4e-5 rad, u2 9.6e-6 m, i.e.
  84, 108 and 109 rtol*max|y|, within the tolerance's global error on this 12-period scene (a few hundred
  rtol*max|y|, see test_c_host.py). Bounded by K_GRID * rtol * max|y| per state, K_GRID = 1000 as there.

Enumerations: Ecos 0.7.2 registers no property for FMI 2.0 Enumeration variables: `beam::formulation`
and `beam::phi_source` exist as no type ("No int property beam::phi_source found!"), and a parameter
set that names one is logged ("No variable named 'phi_source' of type int registered ...") and ignored.
So in Ecos both keep their defaults (reduced, input). Integer and Boolean parameters work, in a
parameter set or with set_integer/set_bool before init (a trace shows Ecos sending them in
initialization mode): max_order, fixed_order and stability_guard here.
test_ecos_enumerations_cannot_be_set shows all of it.

A failed step: Ecos checks none of the FMU's statuses, and with loggingOn = false and (in its source)
a logger that discards every message, it reports nothing. A step the FMU cannot complete (fmi2Discard,
then fmi2Error for every later call) does not stop it: its time runs on to the end while the outputs
keep the values of the last successful step (test_ecos_ignores_a_failed_step). An fmi2Instantiate that
returns NULL is ignored too (seen with a broken tracing shim: Ecos ran on and read 0.0 everywhere).

Also seen: Ecos passes the FMU's path, not the instance name `beam`, as fmi2Instantiate's
instanceName (recorded in target/fmu-report.txt; the FMU does not depend on it).

FMI 3.0 (BeamBody-fmi3.fmu; Ecos loads it through its fmi4c): the same scene, the same calls from the
Python side. Ecos runs it, and its trajectory is its FMI 2.0 run's bit for bit (v1, theta1, u2 and the
times, all 1200 steps), and FMPy's FMU3Slave making the same calls (fmu_util.replay3:
enterInitializationMode without tolerance or stop time, setFloat64(phi), doStep(tc_k, 0.0085)) bit for
bit. The law cannot be selected here either: Ecos skips FMI 3.0's Enumeration variables at load
("[ecos] [warning] Variable named 'phi_source' is of unsupported type, skipping.", one line for each of
the 5), so phi is the input, set before every step as above; against the law itself (the CLI at rtol
1e-12) that is the values-only reconstruction at 8.5 ms: measured 2.5e-4 m in v1, 1.3e-3 rad in theta1,
1.4e-4 m in u2 (test_fmu3.py's ladder), asserted within 2x. Ecos also prints 'Function "fmi3GetVersion"
is not provided by this FMU.' before "Loading FMI version 3...": its fmi4c calls its own placeholder
before it has loaded the library (LD_DEBUG=bindings shows it then binding fmi3GetVersion and 73 other
fmi3 functions from BeamBody.so, which exports all 75); the message is Ecos's, not the FMU's, and
nothing fails.

Figures go to target/fmu-report.txt.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from fmu_util import (H0, STATES, T_END, assert_host_matches_fmpy, cli, law, missing_tool, read_trace, replay3,
                      setup_of, steps_of, traced_fmu)

N_COMM = round(T_END / H0)  # 1200 steps
RTOL = 1e-6  # the FMU's tolerance when setupExperiment defines none (Ecos defines none)
# FMPy on the plain grid k*0.0085 vs Ecos's running sum, for scale (module docstring): at most
# K_GRID * RTOL * max|y| per state. Measured K = 84 (v1), 108 (theta1), 109 (u2).
K_GRID = 1000.0
JUMP = 1e12  # rad: the input jump at t = 1 that no step can follow (test_fmu_failure.py)
# rad/s: phi before the jump, a slow ramp, so that v1 moves until the failed step and its freeze shows
# (at phi = 0 the beam rests at v1 = 0 exactly, which the FMU also reports when the first attempt after
# the jump fails)
RAMP = 0.1
# FMI 3.0: Ecos's run against the law (the CLI at rtol 1e-12), max over the steps, measured (v1 m, theta1
# rad, u2 m); asserted within 2x.
ECOS3_VS_LAW = {"v1": 2.5e-4, "theta1": 1.3e-3, "u2": 1.4e-4}


@pytest.fixture(scope="module")
def ecos():
    """ecospy's classes; a missing package or libtbb12 fails on CI and skips elsewhere."""
    try:
        from ecospy import EcosSimulation, EcosSimulationStructure
    except (ImportError, OSError) as e:
        missing_tool(
            f"ecospy is not importable ({e}): pip install -r tests/requirements.txt; "
            "its libecosc.so needs libtbb.so.12 (apt-get install libtbb12)"
        )
    return EcosSimulation, EcosSimulationStructure


def new_simulation(ecos, fmu, parameters=None):
    """An Ecos simulation of one instance `beam` of the FMU, step H0, with an optional parameter set
    `ps`; (simulation, structure). Not initialised."""
    EcosSimulation, EcosSimulationStructure = ecos
    structure = EcosSimulationStructure()
    structure.add_model("beam", str(fmu))
    if parameters is not None:
        structure.add_parameter_set("ps", parameters)
    return EcosSimulation(structure=structure, step_size=H0), structure


def close(sim, structure):
    sim.terminate()
    sim.free()
    structure.free()


def run_ecos(ecos, fmu, n_steps=N_COMM):
    """The scene in Ecos: phi = law(t) set before every step. {'t': the times after each step, 'y': v1,
    theta1, u2 after each step (one row per step), 'wall': seconds}."""
    sim, structure = new_simulation(ecos, fmu)
    assert sim.init(), "Ecos could not initialise the simulation"
    t, y = [], []
    start = time.perf_counter()
    for _ in range(n_steps):
        tc = sim.get_time()
        sim.set_real("beam::phi", law(tc)[0])
        t.append(sim.step())
        y.append([sim.get_real(f"beam::{q}") for q in STATES])
    wall = time.perf_counter() - start
    close(sim, structure)
    return {"t": np.array(t), "y": np.array(y), "wall": wall}


def ecos_steps(n_steps=N_COMM):
    """(tc, h, phi) of Ecos's steps, as its time arithmetic gives them (module docstring)."""
    steps, tc = [], 0.0
    for _ in range(n_steps):
        steps.append((tc, H0, law(tc)[0]))
        tc += H0
    return steps


@pytest.fixture(scope="module")
def ecos_run(ecos, fmu_file):
    return run_ecos(ecos, fmu_file)


def test_ecos_calls(ecos, fmu_file, ecos_run, tmp_path, monkeypatch, fmu_report):
    """The calls Ecos makes, from the traced FMU: set-up, one setReal(phi) and doStep per step with the
    tc, h and phi of ecos_steps(); and the traced run's trajectory is the plain run's."""
    trace = tmp_path / "ecos.trace"
    monkeypatch.setenv("BEAM_BODY_TRACE", str(trace))
    traced_file = traced_fmu(fmu_file, tmp_path)
    traced = run_ecos(ecos, traced_file)
    calls = read_trace(trace)
    functions = [c.function for c in calls]
    fmu_report.note("ecos", f"host's fmi2Instantiate: {calls[0].text}; instanceName {calls[0].instance!r}")
    assert calls[0].text.startswith("loggingOn = 0"), calls[0].text

    setups = [setup_of(c) for c in calls if c.function == "fmi2SetupExperiment"]
    assert setups == [(None, 0.0, None)], f"Ecos's fmi2SetupExperiment(tolerance, start, stop): {setups}"
    order = ["fmi2SetupExperiment", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2DoStep"]
    assert [functions.index(f) for f in order] == sorted(functions.index(f) for f in order), functions[:12]
    assert functions[-2:] == ["fmi2Terminate", "fmi2FreeInstance"]
    errors = [c for c in calls if c.status != 0]
    assert not errors, f"the FMU answered Ecos with non-OK statuses: {errors[:5]}"

    steps, expected = steps_of(calls), ecos_steps()
    assert len(steps) == N_COMM, f"{len(steps)} fmi2DoStep calls, expected {N_COMM}"
    wrong = [(k, got, want) for k, (got, want) in enumerate(zip(steps, expected)) if got != want]
    assert not wrong, f"{len(wrong)} steps differ from ecos_steps(), first (k, traced, expected): {wrong[:3]}"
    drift = max(abs(tc - k * H0) for k, (tc, _h, _phi) in enumerate(steps))
    fmu_report.figure("ecos", "max|tc_k - k*0.0085|", drift, "Ecos sums the steps")
    assert np.array_equal(traced["y"], ecos_run["y"]), "the traced FMU changed Ecos's trajectory"


def test_ecos_matches_fmpy(fmu_unzipdir, fmu_model_description, ecos_run, fmu_report):
    """Ecos vs FMPy making the same calls: bit for bit. FMPy on the plain grid: within K_GRID rtol*max|y|."""
    assert_host_matches_fmpy("ecos", ecos_run, ecos_steps(), fmu_unzipdir, fmu_model_description, fmu_report, RTOL, K_GRID)


def test_ecos_enumerations_cannot_be_set(ecos, fmu_file, capfd, fmu_report):
    """Ecos has no property for the Enumerations formulation and phi_source (of any type) and ignores
    them in a parameter set, so phi comes from the input; Integer and Boolean parameters can be set."""
    sim, structure = new_simulation(ecos, fmu_file, {"beam::phi_source": 2, "beam::max_order": 2})
    for name in ("beam::formulation", "beam::phi_source"):
        with pytest.raises(Exception, match=f"No int property {name} found"):
            sim.set_integer(name, 2)
        for get in (sim.get_integer, sim.get_real, sim.get_bool, sim.get_string):
            with pytest.raises(Exception):
                get(name)
    sim.set_integer("beam::fixed_order", 3)
    sim.set_bool("beam::stability_guard", False)
    capfd.readouterr()
    assert sim.init(parameter_set="ps")
    log = capfd.readouterr()
    log = log.out + log.err
    assert "No variable named 'phi_source' of type int registered for instance 'beam'" in log, log[-2000:]
    for _ in range(2):  # phi = 0 (the input's start value): the law would have turned the body
        sim.step()
    ints = [sim.get_integer(f"beam::{n}") for n in ("max_order", "fixed_order")]
    guard = sim.get_bool("beam::stability_guard")
    phi_applied = sim.get_real("beam::phi_applied")
    close(sim, structure)
    fmu_report.note("ecos", f"Enumerations have no property; max_order, fixed_order = {ints}, guard = {guard}")
    assert ints == [2, 3] and guard is False
    assert phi_applied == 0.0 and law(2 * H0)[0] > 1e-3, f"phi_applied = {phi_applied}: not the input"


def test_ecos_ignores_a_failed_step(ecos, fmu_file, capfd, fmu_report):
    """Ecos checks no status: a step the FMU cannot complete (phi ramps at RAMP, then jumps by JUMP at
    t = 1, as in test_fmu_failure.py: the FMU returns fmi2Discard, then refuses every further step with
    fmi2Error)
    does not stop it. Its time runs on to 10.2 s while the outputs stay at the last successful step, and
    with loggingOn = false and a logger that discards everything, nothing about it reaches the output."""
    sim, structure = new_simulation(ecos, fmu_file)
    assert sim.init()
    t, v1 = [], []
    for _ in range(N_COMM):
        tc = sim.get_time()
        sim.set_real("beam::phi", JUMP if tc >= 1.0 else RAMP * tc)
        t.append(sim.step())
        v1.append(sim.get_real("beam::v1"))
    close(sim, structure)
    captured = capfd.readouterr()
    t, v1 = np.array(t), np.array(v1)
    frozen = t[np.argmax(v1 == v1[-1])]  # the first time v1 had its final value
    fmu_report.note("ecos", f"failed step: Ecos ran on to t = {t[-1]:.4f}; v1 = {v1[-1]:.6g} from t = {frozen:.4f} on")
    assert abs(t[-1] - T_END) < 1e-9, "Ecos stopped"
    assert 1.0 <= frozen < 1.0 + 2 * H0, f"v1 froze at t = {frozen}, not at the failed step"
    assert np.count_nonzero(np.diff(v1[t >= 1.0 + 2 * H0])) == 0
    log = captured.out + captured.err
    assert "integration failed" not in log and "fmi2DoStep" not in log, f"Ecos reported the failure: {log[-1000:]}"


# --------------------------------------------------------------------------------------------------
# FMI 3.0
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def ecos3_run(ecos, fmu3_file):
    return run_ecos(ecos, fmu3_file)


def test_ecos_fmi3_is_its_fmi2_run_and_fmpys(ecos_run, ecos3_run, fmu3_file, beam_body, tmp_path, fmu_report):
    """Ecos on the FMI 3.0 archive: its FMI 2.0 run bit for bit, FMPy's FMU3Slave making the same calls bit
    for bit, and the law within 2x of the measured values-only error."""
    import fmpy
    from fmpy import read_model_description

    r3, r2 = ecos3_run, ecos_run
    fmu_report.figure("ecos fmi3", "wall_s", r3["wall"], f"{N_COMM} steps; FMI 2.0: {r2['wall']:.3f} s")
    assert np.array_equal(r3["t"], r2["t"]), "Ecos's times differ between the two archives"
    assert np.all(np.isfinite(r3["y"])) and np.max(np.abs(r3["y"][:, 0])) > 0.1, "Ecos's FMI 3.0 run did not move"
    d = float(np.max(np.abs(r3["y"] - r2["y"])))
    fmu_report.figure("ecos fmi3", "max|FMI 3.0 - FMI 2.0|", d, "v1, theta1, u2, all steps")
    assert d == 0.0, f"Ecos: FMI 3.0 and FMI 2.0 differ by {d}"
    md3 = read_model_description(str(fmu3_file), validate=False)
    unzipdir = fmpy.extract(str(fmu3_file), unzipdir=str(tmp_path / "fmu3"))
    y = replay3(unzipdir, md3, ecos_steps(), "ecos-fmpy3")
    assert np.array_equal(r3["y"], y), f"Ecos and FMPy (FMI 3.0, the same calls) differ by {np.max(np.abs(r3['y'] - y))}"
    ref = cli(beam_body, rtol=1e-12)
    for j, q in enumerate(STATES):
        e = float(np.max(np.abs(r3["y"][:, j] - ref[q][1:])))
        fmu_report.figure("ecos fmi3", f"max|Ecos - law|_{q}", e, f"values only, 8.5 ms, rtol 1e-6 (bound 2 x {ECOS3_VS_LAW[q]:g})")
        assert e <= 2 * ECOS3_VS_LAW[q], f"{q}: Ecos (FMI 3.0) vs the law: {e:.3e}"


def test_ecos_fmi3_skips_the_enumerations(ecos, fmu3_file, capfd, fmu_report):
    """Ecos skips FMI 3.0's Enumeration variables at load, with a warning each: phi_source has no
    property of any type, so phi is the input; the placeholder message of its fmi4c is recorded."""
    capfd.readouterr()
    sim, structure = new_simulation(ecos, fmu3_file)
    log = capfd.readouterr()
    log = log.out + log.err
    for name in ("formulation", "phi_source", "phi_interpolation", "range_check", "beam"):
        assert f"Variable named '{name}' is of unsupported type, skipping." in log, log[-2000:]
    placeholder = [line for line in log.splitlines() if "is not provided by this FMU" in line]
    fmu_report.note("ecos fmi3", f"Ecos's output at load: {placeholder}")
    with pytest.raises(Exception, match="No int property beam::phi_source found"):
        sim.set_integer("beam::phi_source", 2)
    assert sim.init()
    for _ in range(2):
        sim.step()
    phi_applied = sim.get_real("beam::phi_applied")
    close(sim, structure)
    assert phi_applied == 0.0 and law(2 * H0)[0] > 1e-3, f"phi_applied = {phi_applied}: not the input"
