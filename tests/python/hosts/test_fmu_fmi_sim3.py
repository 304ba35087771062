"""The FMI 3.0 archive in rust-fmi's `fmi-sim` 0.7.0 ($BEAM_BODY_FMI_SIM, as test_fmu_fmi_sim.py; it reads
the FMI version from the archive): Model Exchange and co-simulation against the CLI, and what it cannot do.

What does not work (fmi-sim's limit, not the FMU's): its model-description reader, fmi-schema 0.8.0, has
no <Enumeration> child in ModelVariables (src/fmi3/variable/model_variables.rs), so the 5 enumerations
(formulation, phi_source, phi_interpolation, range_check, beam) are dropped without a word:
`--init-values phi_source=2` is `Error: Invalid variable name: phi_source. Valid variables are: [...]`.
The law cannot be selected, and phi is an input, read from a CSV file (`-i`), as the CLI and FMPy feed it.
(fmi-schema 0.8.0 also reads a <Float64> strictly, `strict(unknown_attribute, ...)` without `unit`,
`quantity`, `displayUnit`, `relativeQuantity`, `unbounded` or `nominal`, all allowed by FMI 3.0: a
`unit` on a variable made fmi-sim refuse the archive, `Error: unknown field "unit" in element
"FmiFloat64"`; the description gives units through declared types since, test_fmu3_description.py.)

What works:
- co-simulation on the paper's grid (8.5 ms, rtol 1e-6; fmi-sim sets phi from the table at each
  communication point, the law's samples there, fmu_util.cli_law): the CLI fed the same samples
  (`phi_source = input, dt_comm = 0.0085`) to rounding, measured 0 at every row but the last (2.1e-15 m:
  fmi-sim's last point is 1200 * 0.0085 = 10.200000000000001, the CLI's 10.2), and FMPy's simulate_fmu on
  the FMI 3.0 archive with the same table bit for bit. Against the law itself 2.6e-4 m in v1: the
  values-only reconstruction at 8.5 ms (test_fmu3.py).
- Model Exchange: forward Euler at 2e-5 s over [0, 1.2 s], phi, dphi, ddphi from a table every 1 ms
  (linear interpolation; the law's end t_rot as two rows at 0.85, an input event): 3.8e-4 m off the CLI
  at rtol 1e-11 in v1, FMI 2.0's figure at the same step with the law (test_fmu_fmi_sim.py): Euler's
  error. Asserted within 0.5x .. 2x of it.

Figures go to target/fmu-report.txt.
"""

from __future__ import annotations

import math
import os
import re
import subprocess
from pathlib import Path

import fmpy
import numpy as np
import pytest

from fmu_util import H0, STATES, T_END, T_ROT, cli, cli_law, comm_grid, law, law_table, missing_tool

ENUMERATIONS = ("formulation", "phi_source", "phi_interpolation", "range_check", "beam")
RTOL = 1e-6  # the FMU's default tolerance, which fmi-sim passes (the DefaultExperiment's)
SAME_FEED_TOL = 1e-12
T_ME, H_ME = 1.2, 2e-5
ME_ERROR = 3.8e-4  # test_fmu_fmi_sim.py: FMI 2.0, the law, Euler at 2e-5, m in v1; FMI 3.0 measured 3.81e-4


@pytest.fixture(scope="module")
def fmi_sim() -> Path:
    path = os.environ.get("BEAM_BODY_FMI_SIM")
    if not path or not Path(path).is_file():
        missing_tool("fmi-sim is not installed: $BEAM_BODY_FMI_SIM is not set (`cargo xtask test` sets it)")
    return Path(path)


def run(fmi_sim, fmu, out: Path, interface: str, stop: float, interval: float, inputs: Path | None = None,
        extra=(), check=True):
    cmd = [str(fmi_sim), "--model", str(fmu), "-o", str(out)]
    if inputs is not None:
        cmd += ["-i", str(inputs)]
    cmd += [interface, "-f", repr(stop), "--output-interval", repr(interval), *extra]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if not check:
        return proc
    assert proc.returncode == 0, f"{' '.join(cmd)} exited with {proc.returncode}:\n{proc.stderr[-3000:]}"
    lines = out.read_text().splitlines()
    header = lines[0].split(",")
    data = np.array([[float(x) for x in line.split(",")] for line in lines[1:] if line], dtype=float)
    return {name: data[:, k] for k, name in enumerate(header)}


def write_table(path: Path, names, rows):
    with open(path, "w") as fh:
        fh.write(",".join(("time", *names)) + "\n")
        for row in rows:
            fh.write(",".join(repr(float(v)) for v in row) + "\n")
    return path


def test_fmi_sim_sees_no_enumeration(fmi_sim, fmu3_file, tmp_path, fmu_report):
    """fmi-sim 0.7.0 reads the archive but drops its enumerations: phi_source cannot be set (module
    docstring). When a later fmi-sim reads them, this test fails: run the law through it then."""
    proc = run(fmi_sim, fmu3_file, tmp_path / "enum.csv", "co-simulation", 0.1, H0,
               extra=("--init-values", "phi_source=2"), check=False)
    first = proc.stderr.strip().splitlines()[0] if proc.stderr.strip() else ""
    fmu_report.note("fmi-sim fmi3", f"--init-values phi_source=2: exit {proc.returncode}, {first[:80]!r}")
    assert proc.returncode != 0 and "Invalid variable name: phi_source" in proc.stderr, proc.stderr[-2000:]
    listed = re.search(r"Valid variables are: \[(.*?)\]", proc.stderr)
    assert listed, proc.stderr[-2000:]
    names = set(re.findall(r'"([^"]+)"', listed.group(1)))
    assert {"phi", "v1", "intermediate_step", "time"} <= names and not names & set(ENUMERATIONS), names


def test_fmi_sim_co_simulation_fmi3_is_the_clis_same_feed(fmi_sim, fmu3_file, beam_body, tmp_path, fmu_report):
    phi = cli_law(beam_body, H0)
    table = write_table(tmp_path / "phi.csv", ("phi",), [(t, phi(t)[0]) for t in comm_grid(H0)])
    r = run(fmi_sim, fmu3_file, tmp_path / "cs3.csv", "co-simulation", T_END, H0, table)
    c = cli(beam_body, rtol=RTOL, phi_source="input", dt_comm=H0)
    assert len(r["time"]) == len(c["t"]) == 1201 and np.max(np.abs(r["time"] - c["t"])) <= 1e-12
    fmpy_run = fmpy.simulate_fmu(str(fmu3_file), input=law_table(H0, phi_fn=phi), relative_tolerance=RTOL,
                                 output_interval=H0, stop_time=T_END, output=list(STATES))
    ref = cli(beam_body, rtol=1e-12)
    for q in STATES:
        d = float(np.max(np.abs(r[q] - c[q])))
        d_inner = float(np.max(np.abs(r[q][:-1] - c[q][:-1])))
        e = float(np.max(np.abs(r[q] - ref[q])))
        fmu_report.figure("fmi-sim fmi3 co-simulation", f"max|fmi-sim - CLI(values)|_{q}", d,
                          f"all but the last row: {d_inner:.1e}; vs the law: {e:.2e}")
        assert d <= SAME_FEED_TOL, f"{q}: fmi-sim (FMI 3.0) vs the CLI with the same feed: {d:.3e}"
        assert np.array_equal(r[q], fmpy_run[q]), f"{q}: fmi-sim and FMPy (FMI 3.0, the same table) differ"


def test_fmi_sim_model_exchange_fmi3_is_eulers(fmi_sim, fmu3_file, beam_body, tmp_path, fmu_report):
    rows = []
    for k in range(int(round(T_ME * 1000)) + 1):
        t = k / 1000
        if t == T_ROT:  # the turn's end, then the hold: an input event
            w = math.pi / T_ROT
            rows.append((t, math.pi, 0.5 * math.pi * w * math.sin(math.pi), 0.5 * math.pi * w * w * math.cos(math.pi)))
        rows.append((t, *law(t)))
    assert sum(1 for row in rows if row[0] == T_ROT) == 2
    table = write_table(tmp_path / "phi_me.csv", ("phi", "dphi", "ddphi"), rows)
    r = run(fmi_sim, fmu3_file, tmp_path / "me3.csv", "model-exchange", T_ME, H_ME, table)
    assert abs(r["time"][-1] - T_ME) < 1e-9, f"fmi-sim's run ended at {r['time'][-1]}"
    ref = cli(beam_body, rtol=1e-11, atol=1e-13, dt_out=0.01)
    m = ref["t"] <= T_ME + 1e-12
    d = {q: float(np.max(np.abs(np.interp(ref["t"][m], r["time"], r[q]) - ref[q][m]))) for q in STATES}
    fmu_report.figure("fmi-sim fmi3 model exchange", f"max|Euler h={H_ME:g} - CLI|_v1", d["v1"],
                      f"FMI 2.0 with the law: {ME_ERROR:g}; theta1 {d['theta1']:.2e}, u2 {d['u2']:.2e}")
    assert 0.5 * ME_ERROR <= d["v1"] <= 2 * ME_ERROR, d
