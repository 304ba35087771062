"""fmi2GetRealOutputDerivatives (maxOutputDerivativeOrder = 2) against the independent oracle.

The FMU (phi from the law, tolerance 1e-10, communication step 8.5 ms) reports d/dt and d^2/dt^2 of v1
and theta1 and d/dt of u2 at every communication point. The oracle's reference solution of its own
sympy-derived equations (scipy DOP853 at rtol 1e-13) gives the rates, its accelerations follow from
solving its residuals for them (oracle.accelerations), and u1_and_rate gives du2 = du1/dt. Against
central differences of the outputs, see the Rust test
`output_derivatives_match_finite_differences_of_the_outputs`.
"""

from __future__ import annotations

import numpy as np

import oracle
from fmu_util import H0, PHI_SOURCE_LAW, T_END, Slave

# Measured, relative to each derivative's largest value: d/dt 1.5e-7 (v1), 2.9e-7 (theta1), 2.7e-7
# (u2); d2/dt2 3.1e-7 (v1), 3.8e-7 (theta1): the states' own error at this tolerance, carried
# through the equations of motion.
REL_TOL = 1e-6


def test_output_derivatives_match_the_oracle(fmu_unzipdir, fmu_model_description, fmu_report):
    s = Slave(fmu_unzipdir, fmu_model_description, name="output-derivatives")
    names = ["v1", "theta1", "u2"]
    vr = [s.vr[n] for n in names]
    n = int(round(T_END / H0))
    rows, d1, d2 = [], [], []
    try:
        s.start(tolerance=1e-10, stop_time=T_END, integers={"phi_source": PHI_SOURCE_LAW})
        for k in range(n):
            s.fmu.doStep(k * H0, H0)
            rows.append(s.get(["v1", "theta1", "dv1", "dtheta1"]))
            d1.append(s.fmu.getRealOutputDerivatives(vr, [1, 1, 1]))
            d2.append(s.fmu.getRealOutputDerivatives(vr[:2], [2, 2]))
        assert not s.errors(), s.errors()
    finally:
        s.free()
    t = (np.arange(n) + 1) * H0
    t[-1] = T_END
    _, y = oracle.reference_solution("reduced", t_eval=t)
    phi, dphi, ddphi = oracle.phi_law(t)
    # phi'' of the law jumps at t_rot; the FMU's own side is the hold from t_rot on, the oracle's the
    # turn up to it: leave that point out.
    keep = np.abs(t - 0.85) > 1e-9
    X = np.stack([phi, dphi, ddphi, y[:, 0], y[:, 1], y[:, 2], y[:, 3], 0 * t, 0 * t], axis=1)
    acc = oracle.accelerations("reduced", X)
    du2 = oracle.u1_and_rate(y[:, 0], y[:, 1], y[:, 2], y[:, 3])[1]
    d1, d2 = np.array(d1), np.array(d2)
    want1 = np.stack([y[:, 2], y[:, 3], du2], axis=1)
    for j, name in enumerate(names):
        e = float(np.max(np.abs(d1[keep, j] - want1[keep, j]))) / float(np.max(np.abs(want1[:, j])))
        fmu_report.figure("output derivatives", f"d/dt {name} vs oracle (relative)", e)
        assert e <= REL_TOL, f"d/dt {name}: {e:.2e}"
    for j, name in enumerate(names[:2]):
        e = float(np.max(np.abs(d2[keep, j] - acc[keep, j]))) / float(np.max(np.abs(acc[:, j])))
        fmu_report.figure("output derivatives", f"d2/dt2 {name} vs oracle (relative)", e)
        assert e <= REL_TOL, f"d2/dt2 {name}: {e:.2e}"
    # The rates reported as outputs and as first derivatives are the same numbers.
    assert np.array_equal(d1[:, 0], np.array(rows)[:, 2]) and np.array_equal(d1[:, 1], np.array(rows)[:, 3])
