"""Figures the docs quote from the CLI, kept in step with it (issue 43: docs/model.md's step counts had
gone stale). The runs are deterministic (the same binary gives the same bits), so a count is quoted
exactly and the positions to the digits written.
"""

from __future__ import annotations

import re
import subprocess

import pytest

from conftest import REPO, read_csv

PAPER = REPO / "scenes" / "paper.toml"


def model_md_rows():
    """docs/model.md's table "Measured (...)": (n, damping_ratio, v1, theta1 or None, steps)."""
    text = (REPO / "docs" / "model.md").read_text(encoding="utf-8")
    section = text.split("| n | v1(10.2 s) [m] | ϑ1(10.2 s) [rad] | steps |", 1)[1].split("\n\n", 1)[0]
    rows = []
    for line in section.strip().splitlines()[1:]:
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        m = re.fullmatch(r"(\d+)(?:, `damping_ratio` = ([0-9.]+))?", cells[0])
        assert m, line
        theta = cells[2] or None
        rows.append((int(m.group(1)), m.group(2), cells[1], theta, int(cells[3].replace(",", ""))))
    assert len(rows) >= 4, rows
    return rows


@pytest.mark.parametrize("row", model_md_rows(), ids=lambda r: f"n={r[0]}" + (f",zeta={r[1]}" if r[1] else ""))
def test_model_md_step_counts_and_positions_are_the_cli_s(beam_body, row):
    n, zeta, v1, theta1, steps = row
    args = [str(beam_body), "simulate", str(PAPER), "--elements", str(n)]
    if zeta:
        args += ["--set", f"damping_ratio={zeta}"]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=300, cwd=REPO)
    assert proc.returncode == 0, proc.stderr
    got = int(re.search(r"steps (\d+)", proc.stderr).group(1))
    assert got == steps, f"docs/model.md quotes {steps:,} steps for this row; the CLI takes {got:,}"
    rows = read_csv(proc.stdout)
    assert f"{rows['v1'][-1]:.{len(v1.split('.')[1])}f}" == v1, (rows["v1"][-1], v1)
    if theta1:
        assert f"{rows['theta1'][-1]:.{len(theta1.split('.')[1])}f}" == theta1, (rows["theta1"][-1], theta1)
