"""range_check = stop | warn | off, in the CLI and the FMU, against the independent oracle.

The turn at t_rot = 0.2 s takes theta1 beyond pi/2, out of the range where the model's equations are
valid: with the default (stop) the run ends there with a message; with warn it says so once and goes on;
with off it goes on silently. The equations themselves go on: the oracle's independent solution of the
sympy-derived reduced equations (scipy DOP853 at rtol 1e-13, oracle.reference_solution) reaches the same
max |theta1| (1.71 rad) and the same trajectory.
"""

from __future__ import annotations

import subprocess

import numpy as np
from fmpy.fmi1 import FMICallException

import oracle
from conftest import read_csv, run_cli
from fmu_util import PAPER_SCENE, Slave

T_ROT = 0.2
# The CLI at rtol 1e-10 against the oracle at 1e-13, over the whole run (10.2 s), in theta1: measured
# 1.7e-6 rad.
ORACLE_TOL = 1e-5


def cli_args(check: str) -> list[str]:
    return ["simulate", str(PAPER_SCENE), "--set", f"t_rot={T_ROT}", "--set", f"range_check={check}"]


def test_stop_ends_the_run_with_a_message(beam_body):
    proc = subprocess.run([str(beam_body), *cli_args("stop")], capture_output=True, text=True, timeout=60)
    assert proc.returncode != 0
    assert "theta1" in proc.stderr and "pi/2" in proc.stderr, proc.stderr


def test_warn_and_off_go_on_and_follow_the_oracle(beam_body, fmu_report):
    proc = subprocess.run([str(beam_body), *cli_args("warn")], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.count("warning") == 1 and "range_check = warn" in proc.stderr, proc.stderr
    warn = read_csv(proc.stdout)
    assert np.array_equal(warn["theta1"], read_csv(run_cli(beam_body, cli_args("off")))["theta1"]), (
        "warn and off integrate the same way"
    )
    off = read_csv(run_cli(beam_body, cli_args("off") + ["--rtol", "1e-10"]))
    t = off["t"]
    assert t[-1] == 10.2
    _, y = oracle.reference_solution("reduced", {"t_rot": T_ROT, "t_end": 10.2, "dt_out": 0.0085}, t_eval=t)
    peak, peak_oracle = float(np.max(np.abs(off["theta1"]))), float(np.max(np.abs(y[:, 1])))
    diff = float(np.max(np.abs(off["theta1"] - y[:, 1])))
    fmu_report.figure("range_check", "max|theta1| CLI, oracle", f"{peak:.4f}, {peak_oracle:.4f}", f"max diff {diff:.2e}")
    assert abs(peak - 1.71) < 0.01 and abs(peak - peak_oracle) < 1e-3
    assert diff < ORACLE_TOL


def test_fmu_warns_once_then_goes_on(fmu_unzipdir, fmu_model_description):
    items = {name: k + 1 for k, name in enumerate(("stop", "warn", "off"))}
    for check, want in (("stop", "discard"), ("warn", "warning"), ("off", "ok")):
        s = Slave(fmu_unzipdir, fmu_model_description, name=f"range-{check}", logging_on=True)
        try:
            s.start(tolerance=1e-6, stop_time=1.0, integers={"phi_source": 2, "range_check": items[check]},
                    reals={"t_rot": T_ROT})
            statuses = []
            for k in range(100):
                try:
                    s.fmu.doStep(k * 0.01, 0.01)
                    statuses.append(0)
                except FMICallException as e:
                    statuses.append(int(e.status))
                    break
            warnings = [m for m in s.messages if m[1] == 1]
            if want == "discard":
                assert statuses[-1] == 2 and len(statuses) < 100, statuses
            elif want == "warning":
                # FMPy raises only above fmi2Warning: every step goes through, one is logged.
                assert statuses == [0] * 100 and len(warnings) == 1, (statuses, warnings)
                assert "range_check = warn" in warnings[0][3], warnings
            else:
                assert statuses == [0] * 100 and not warnings
        finally:
            s.free()
