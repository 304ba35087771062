"""FMI 3.0's arrays sized by the structural parameter n_elements, through FMPy's FMU3Slave and FMU3Model: the
beam in n elements by co-simulation and by Model Exchange, with the nodal shape read as arrays.

- n_elements is set in configuration mode (fmi3EnterConfigurationMode, fmi3SetUInt64,
  fmi3ExitConfigurationMode); elsewhere, and through FMPy's simulate_fmu (which sets start values in the
  instantiated state and sizes its states from the model description's start value), it is refused.
- Co-simulation with the law, N = 4 elements, the FMU's tolerance the CLI's rtol (1e-6), output every 8.5
  ms to 2 s: nodal_v and nodal_theta (4 values each, fmi3GetFloat64 with nValues = 4) equal the CLI's
  `--columns shape` columns v_k, theta_k to the rounding of the output times (bound 1e-12 of max|y|;
  measured 9.5e-16 m and 1.0e-15 rad: one core, one integrator, the same steps).
- Model Exchange, N = 3 elements, 12 states: q and dq as x, integrated by FMPy's CVode (its
  fmpy.sundials.CVodeSolver, as simulate_fmu builds it) at rtol 1e-10, the law's end t_rot a time event,
  against the CLI at rtol 1e-11, output every 50 ms to 2 s: measured 6.6e-10 m in nodal_v and 1.1e-8 rad in
  nodal_theta, asserted within 2x. q read as an array is the first half of x, bit for bit.
"""

from __future__ import annotations

import fmpy
import numpy as np
import pytest

from fmu_util import H0, PHI_SOURCE_LAW, Slave3, cli

N_CS = 4
N_ME = 3
T = 2.0
CS_SAME = 1e-12  # |FMI 3.0 CS - CLI| / max|y|: the same run
ME_RTOL = 1e-10
ME_REF = dict(rtol=1e-11, atol=1e-13)
ME_N_MEASURED = {"v": 6.6e-10, "theta": 1.1e-8}  # |FMPy CVode ME - CLI| in the nodal shape (m, rad)


def vrs(md):
    return {v.name: v.valueReference for v in md.modelVariables}


def configure(fmu, vr, n):
    fmu.enterConfigurationMode()
    fmu.setUInt64([vr["n_elements"]], [n])
    fmu.exitConfigurationMode()


def nodal(fmu, vr, n):
    """nodal_v and nodal_theta, n values each, in one fmi3GetFloat64."""
    y = fmu.getFloat64([vr["nodal_v"], vr["nodal_theta"]], nValues=2 * n)
    return np.array(y[:n]), np.array(y[n:])


def cli_shape(beam_body, n, **sets):
    c = cli(beam_body, n_elements=n, columns="shape", t_end=T, **sets)
    v = np.column_stack([c[f"v_{k}"] for k in range(1, n + 1)])
    theta = np.column_stack([c[f"theta_{k}"] for k in range(1, n + 1)])
    return c["t"], v, theta


def test_structural_parameter_only_in_configuration_mode(fmu3_unzipdir, md3):
    """fmi3SetUInt64 of n_elements outside configuration mode is refused naming it; inside, other variables
    are; FMPy's simulate_fmu, which sets start values in the instantiated state, cannot change it."""
    vr = vrs(md3)
    s = Slave3(fmu3_unzipdir, md3, name="structural")
    try:
        with pytest.raises(Exception):
            s.fmu.setUInt64([vr["n_elements"]], [4])
        assert any("structural parameter" in m and "configuration mode" in m for _, _, m in s.errors()), s.messages
        s.fmu.enterConfigurationMode()
        with pytest.raises(Exception):
            s.fmu.setFloat64([vr["l"]], [2.0])
        assert any("only the structural parameters" in m for _, _, m in s.errors()), s.messages
        s.fmu.setUInt64([vr["n_elements"]], [4])
        s.fmu.exitConfigurationMode()
    finally:
        s.free()
    messages = []
    with pytest.raises(Exception):
        fmpy.simulate_fmu(str(fmu3_unzipdir), start_values={"n_elements": 4}, stop_time=0.01,
                          logger=lambda *args: messages.append(args[-1]))
    assert any(b"structural parameter" in m and b"configuration mode" in m for m in messages), messages


def test_co_simulation_in_elements_gives_the_clis_nodal_shape(fmu3_unzipdir, md3, beam_body, fmu_report):
    vr = vrs(md3)
    t_ref, v_ref, theta_ref = cli_shape(beam_body, N_CS)
    s = Slave3(fmu3_unzipdir, md3, name="cs in elements")
    try:
        configure(s.fmu, vr, N_CS)
        s.start(tolerance=1e-6, int64={"phi_source": PHI_SOURCE_LAW})
        rows_v, rows_theta = [], []
        v, theta = nodal(s.fmu, vr, N_CS)
        rows_v.append(v)
        rows_theta.append(theta)
        steps = int(round(T / H0))
        for k in range(steps):
            s.fmu.doStep(k * H0, H0)
            v, theta = nodal(s.fmu, vr, N_CS)
            assert v[-1] == s.get(["v1"])[0], "the tip last"
            rows_v.append(v)
            rows_theta.append(theta)
        assert not s.errors(), s.errors()
        # nValues counts every element: 3 for an array of 4 is refused, naming the size.
        with pytest.raises(Exception):
            s.fmu.getFloat64([vr["nodal_v"]], nValues=3)
        assert any("`nodal_v` has 4" in m for _, _, m in s.errors()), s.messages
    finally:
        s.free()
    # The CLI's grid k*8.5 ms, and its last row at t_end = 2 s.
    assert np.allclose(t_ref[:steps + 1], np.arange(steps + 1) * H0, rtol=0, atol=1e-12)
    for name, got, ref in (("v", np.array(rows_v), v_ref), ("theta", np.array(rows_theta), theta_ref)):
        ref = ref[:steps + 1]
        d = float(np.max(np.abs(got - ref)))
        fmu_report.figure("fmi3 arrays", f"max|CS nodal_{name} - CLI|, {N_CS} elements", d,
                          "rtol 1e-6, h = 8.5 ms, 2 s")
        assert d <= CS_SAME * np.max(np.abs(ref)), f"nodal_{name}: {d:.3e}"
        assert np.max(np.abs(ref[:, -1])) > 1e-2, "the beam bends"


class _NoInput:
    """simulate_fmu's input object, for a run with the law (phi is not an input)."""

    def apply(self, _t):
        pass


def test_model_exchange_in_elements_with_fmpy_cvode(fmu3_unzipdir, md3, beam_body, fmu_report):
    """FMU3Model configured for N_ME elements, integrated by FMPy's CVode as simulate_fmu builds it, with the
    time event at t_rot: the nodal shape against the CLI in as many elements."""
    from fmpy.fmi3 import FMU3Model
    from fmpy.sundials import CVodeSolver

    vr = vrs(md3)
    fmu = FMU3Model(guid=md3.guid, unzipDirectory=str(fmu3_unzipdir),
                    modelIdentifier=md3.modelExchange.modelIdentifier, instanceName="me in elements")
    fmu.instantiate()
    try:
        # q and dq, 2 n_elements each, and the filter of phi's 2.
        assert fmu.getNumberOfContinuousStates() == 6
        configure(fmu, vr, N_ME)
        nx = fmu.getNumberOfContinuousStates()
        assert nx == 4 * N_ME + 2
        fmu.setInt64([vr["phi_source"]], [PHI_SOURCE_LAW])
        fmu.enterInitializationMode(tolerance=ME_RTOL, startTime=0.0, stopTime=T)
        fmu.exitInitializationMode()
        _, terminate, _, _, defined, next_event = fmu.updateDiscreteStates()
        assert not terminate and defined and next_event == pytest.approx(0.85)
        fmu.enterContinuousTimeMode()
        solver = CVodeSolver(nx=nx, nz=fmu.getNumberOfEventIndicators(), get_x=fmu.getContinuousStates,
                             set_x=fmu.setContinuousStates, get_dx=fmu.getContinuousStateDerivatives,
                             get_z=fmu.getEventIndicators, get_nominals=fmu.getNominalsOfContinuousStates,
                             set_time=fmu.setTime, input=_NoInput(), startTime=0.0, maxStep=T / 50,
                             relativeTolerance=ME_RTOL, maxNumSteps=100_000)
        # Rounded, so that 17 x 0.05 is t_rot = 0.85, the time event, itself.
        grid = np.round(np.arange(int(round(T / 0.05)) + 1) * 0.05, 12)
        time, rows_v, rows_theta = 0.0, [], []
        for t_out in grid:
            while time < t_out:
                target = min(t_out, next_event) if defined else t_out
                _, _, time = solver.step(time, target)
                fmu.setTime(time)
                enter, terminate = fmu.completedIntegratorStep()
                assert not enter and not terminate
                if defined and time >= next_event:
                    fmu.enterEventMode()
                    _, terminate, _, _, defined, next_event = fmu.updateDiscreteStates()
                    fmu.enterContinuousTimeMode()
                    solver.reset(time)
            x = np.zeros(nx)
            fmu.getContinuousStates(np.ctypeslib.as_ctypes(x), nx)
            q = np.array(fmu.getFloat64([vr["q"]], nValues=2 * N_ME))
            assert np.array_equal(q, x[:2 * N_ME]), "q is the first half of the model's part of x"
            v, theta = nodal(fmu, vr, N_ME)
            rows_v.append(v)
            rows_theta.append(theta)
        fmu.terminate()
    finally:
        fmu.freeInstance()
    t_ref, v_ref, theta_ref = cli_shape(beam_body, N_ME, dt_out=0.05, **ME_REF)
    assert np.allclose(t_ref, grid, rtol=0, atol=1e-12)
    for name, got, ref in (("v", np.array(rows_v), v_ref), ("theta", np.array(rows_theta), theta_ref)):
        d = float(np.max(np.abs(got - ref)))
        fmu_report.figure("fmi3 arrays", f"max|ME nodal_{name} - CLI|, {N_ME} elements", d,
                          f"FMPy CVode rtol {ME_RTOL:g} against the CLI at rtol 1e-11")
        assert d <= 2 * ME_N_MEASURED[name], f"nodal_{name}: |ME - CLI| = {d:.3e} > 2 x {ME_N_MEASURED[name]}"
        assert np.max(np.abs(ref[:, -1])) > 1e-2, "the beam bends"
