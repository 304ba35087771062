"""The FMU with the built-in law (phi_source = law) under fmpy.simulate_fmu, against the CLI.

Both integrate the same equations with the same BDF at the same tolerance, and with the law the FMU
takes the CLI's own steps: its integrator runs ahead of the communication points (the law is known
ahead) and the outputs at tc + h come from its dense output, as the CLI's at its grid times. With the
same stop time (FMPy's 10.2 s, the CLI's t_end) the two step sequences are the same, so they agree to
the rounding of the output times: FMPy's communication points and the CLI's k*dt differ by ulps
(measured 2e-15 m in v1). SAME_STEPS bounds that, relative to max|y|. K_TOL, the bound of two different
step sequences (a few hundred rtol*max|y| on this 12-period scene, before the FMU ran ahead: K = 35 ...
361 measured), is the other tests' for what lands on every communication point (a host's input).

Figures go to target/fmu-report.txt.
"""

from __future__ import annotations

import fmpy
import numpy as np
import pytest

from fmu_util import FORMULATION_ENUM, H0, OUTPUTS, PHI_SOURCE_LAW, STATES, T_END, T_ROT, cli

# The FMU's own global error (against the CLI at rtol 1e-12) may not exceed ERR_RATIO x the CLI's:
# measured 0.56 ... 1.09 for the reduced formulation; 3 is a ~3x margin.
ERR_RATIO = 3.0
# dae: the FMU's max |drift| may not exceed DRIFT_RATIO x the CLI's at the same rtol. Measured 0.54 (rtol
# 1e-6) and 3.8 (rtol 1e-9: the FMU restarts nothing, but it ends a step on each of the 1200 communication
# points, and the drift is a sum of local errors). 10 is a ~2.6x margin.
DRIFT_RATIO = 10.0
REF_RTOL = 1e-12  # the CLI at rtol 1e-12 agrees with rtol 1e-10 to 5.5e-8: reference for "exact"
SAME_STEPS = 1e-12  # |FMU - CLI| / max|y| with the law: the same steps, outputs at times ulps apart


def simulate_law(fmu_dir, rtol, formulation=1, output=OUTPUTS):
    return fmpy.simulate_fmu(
        str(fmu_dir),
        start_values={"phi_source": PHI_SOURCE_LAW, "formulation": formulation},
        relative_tolerance=rtol,
        output_interval=H0,
        stop_time=T_END,
        output=list(output),
    )


def check_grid(r, c):
    assert len(r) == len(c["t"]) == 1201, f"{len(r)} FMU rows, {len(c['t'])} CLI rows, expected 1201"
    assert np.max(np.abs(r["time"] - c["t"])) <= 1e-12, "the FMU's and the CLI's grids differ"
    for name in r.dtype.names:
        assert np.all(np.isfinite(r[name])), f"non-finite values in {name}"


@pytest.mark.parametrize("rtol", [1e-6, 1e-9])
def test_law_mode_matches_cli(fmu_unzipdir, beam_body, fmu_report, rtol):
    r = simulate_law(fmu_unzipdir, rtol)
    c = cli(beam_body, rtol=rtol)
    ref = cli(beam_body, rtol=REF_RTOL)
    check_grid(r, c)
    # phi comes from the law in both
    assert np.max(np.abs(r["phi_applied"] - c["phi_applied"])) <= 1e-14 * np.pi
    tag = f"law rtol={rtol:g}"
    failures = []
    for q in STATES:
        d = float(np.max(np.abs(r[q] - c[q])))
        e_fmu = float(np.max(np.abs(r[q] - ref[q])))
        e_cli = float(np.max(np.abs(c[q] - ref[q])))
        fmu_report.figure(tag, f"max|FMU-CLI|_{q}", d, f"{d / np.max(np.abs(c[q])):.1e} of max|y| (bound {SAME_STEPS:g})")
        fmu_report.figure(tag, f"err_vs_ref_{q}", e_fmu, f"CLI's own: {e_cli:.3e}, ratio {e_fmu / e_cli:.2f} (bound {ERR_RATIO:g})")
        if d > SAME_STEPS * np.max(np.abs(c[q])):
            failures.append(f"{q}: |FMU - CLI| = {d:.3e}: not the same steps as the CLI's")
        if e_fmu > ERR_RATIO * e_cli:
            failures.append(f"{q}: the FMU's error {e_fmu:.3e} > {ERR_RATIO:g} x the CLI's {e_cli:.3e}")
    assert not failures, "\n".join(failures)


@pytest.mark.parametrize("rtol", [1e-6, 1e-9])
@pytest.mark.parametrize("formulation", list(FORMULATION_ENUM))
def test_each_formulation_matches_cli(fmu_unzipdir, beam_body, fmu_report, formulation, rtol):
    r = simulate_law(fmu_unzipdir, rtol, formulation=FORMULATION_ENUM[formulation])
    c = cli(beam_body, rtol=rtol, formulation=formulation)
    check_grid(r, c)
    tag = f"formulation={formulation} rtol={rtol:g}"
    failures = []
    for q in STATES:
        a, b = r[q], c[q]
        what = q
        if formulation == "dae" and q == "u2":
            # the dae's u2 = u1(v1, theta1) + drift: compare u1; the drift is checked below
            a, b, what = r["u2"] - r["drift"], c["u2"] - c["drift"], "u1=u2-drift"
        d = float(np.max(np.abs(a - b)))
        fmu_report.figure(tag, f"max|FMU-CLI|_{what}", d, f"{d / np.max(np.abs(b)):.1e} of max|y| (bound {SAME_STEPS:g})")
        if d > SAME_STEPS * np.max(np.abs(b)):
            failures.append(f"{what}: |FMU - CLI| = {d:.3e}: not the same steps as the CLI's")
    drift_fmu, drift_cli = float(np.max(np.abs(r["drift"]))), float(np.max(np.abs(c["drift"])))
    fmu_report.figure(tag, "max|drift|", drift_fmu, f"CLI: {drift_cli:.3e}")
    if formulation == "dae":
        assert drift_fmu > 0.0, "dae: drift is identically 0: is the dae formulation really integrated?"
        if drift_fmu > DRIFT_RATIO * drift_cli:
            failures.append(f"dae: max|drift| {drift_fmu:.3e} > {DRIFT_RATIO:g} x the CLI's {drift_cli:.3e}")
    else:
        # dae_stabilized projects after every step and at every output; reduced and linear have u2 = u1
        n_bad = int(np.count_nonzero(r["drift"] != 0.0))
        if n_bad:
            failures.append(f"{formulation}: drift != 0 at {n_bad} rows (max {drift_fmu:.3e}); must be exactly 0")
    assert not failures, "\n".join(failures)


BEAM_ENUM = {"quadratic": 1, "exact": 2}  # the enumeration Beam: item k has the value k + 1


@pytest.mark.parametrize("beam", list(BEAM_ENUM))
def test_the_beam_in_elements_matches_cli(fmu_unzipdir, beam_body, fmu_report, beam):
    """The beam in 4 elements, quadratic or geometrically exact, chosen by one parameter of the same
    interface, against the CLI with the same settings, at rtol 1e-9 (as above). The root's loads and the
    quarter point, which the exact beam computes its own way, and the energy (constant after the turn)
    come along. The root's loads follow from accelerations, which jump with phi'' at t_rot (the FMU reports
    the limit after it there, the CLI the one before) and carry the high modes' integration error: they
    are compared away from t_rot, relative to their peak (measured 6e-7 in M_root, 7e-6 in Q_root)."""
    rtol = 1e-9
    extra = ("v_mid", "energy")
    loads = ("M_root", "Q_root")
    r = fmpy.simulate_fmu(
        str(fmu_unzipdir),
        start_values={"phi_source": PHI_SOURCE_LAW, "beam": BEAM_ENUM[beam], "n_elements": 4},
        relative_tolerance=rtol,
        output_interval=H0,
        stop_time=T_END,
        output=list(STATES) + list(extra) + list(loads),
    )
    c = cli(beam_body, rtol=rtol, beam=beam, n_elements=4, columns="beam")
    check_grid(r, c)
    tag = f"beam={beam} n=4 rtol={rtol:g}"
    failures = []
    for q in STATES + extra:
        d = float(np.max(np.abs(r[q] - c[q])))
        fmu_report.figure(tag, f"max|FMU-CLI|_{q}", d, f"{d / np.max(np.abs(c[q])):.1e} of max|y| (bound {SAME_STEPS:g})")
        if d > SAME_STEPS * np.max(np.abs(c[q])):
            failures.append(f"{q}: |FMU - CLI| = {d:.3e}: not the same steps as the CLI's")
    away = np.abs(c["t"] - T_ROT) > 1e-9
    for q in loads:
        d = float(np.max(np.abs(r[q] - c[q])[away]) / np.max(np.abs(c[q])))
        fmu_report.figure(tag, f"max|FMU-CLI|/peak_{q}", d, "bound 1e-4, away from t_rot")
        if d > 1e-4:
            failures.append(f"{q}: |FMU - CLI| = {d:.3e} of its peak > 1e-4")
    assert not failures, "\n".join(failures)
    other = cli(beam_body, rtol=rtol, beam=[b for b in BEAM_ENUM if b != beam][0], n_elements=4)
    # the two beams differ by the quadratic cut: far more than the FMU and the CLI do (0.2 m in v1 at 10.2 s)
    assert np.max(np.abs(other["v1"] - c["v1"])) > 1e-2
