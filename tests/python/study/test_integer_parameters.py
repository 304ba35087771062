"""Issue 43, item 9: a study of an integer parameter (n_elements). A grid with points between integers,
or a distribution, passed `--plan`, ran, and wrote "invalid" rows with exit code 0; the column held
`1.0`. Now both are refused when the study is read, by `--plan` and so by the study tool before it
runs anything, naming the parameter and what it takes; a grid of whole steps runs each integer, and the
column is an integer column in the CLI's CSV, in `--plan`'s types, and in the tool's Parquet and CSV.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO

sys.path.insert(0, str(REPO / "python"))

import pyarrow as pa  # noqa: E402
import pyarrow.parquet as pq  # noqa: E402

#: A short run, so that the three cases take milliseconds.
HEAD = 'metrics = ["max_v1"]\n[set]\nt_end = 0.5\n'
GRID = HEAD + "[parameters.n_elements]\nstart = 1\nstop = 3\ncount = 3\n[parameters.M2]\nvalues = [12.0]\n"


def cli(beam_body, *args):
    return subprocess.run([str(beam_body), *map(str, args)], capture_output=True, text=True, timeout=120)


def tool(beam_body, *args):
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"), BEAM_BODY_BIN=str(beam_body))
    return subprocess.run([sys.executable, "-m", "beam_body_study", *map(str, args)], capture_output=True,
                          text=True, timeout=120, env=env, cwd=REPO)


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("axis, needle", [
    ("start = 1\nstop = 4\ncount = 3\n", "this grid (start = 1, stop = 4, count = 3) has the point 2.5"),
    ('distribution = "uniform"\nlow = 1\nhigh = 4\n', "a distribution gives real numbers"),
])
def test_a_non_integer_axis_is_refused_by_plan_and_by_the_tool(beam_body, tmp_path, axis, needle):
    sampling = "[sampling]\nsamples = 4\nseed = 1\n" if "distribution" in axis else ""
    study = write(tmp_path / "bad.toml", HEAD + sampling + "[parameters.n_elements]\n" + axis)
    proc = cli(beam_body, "study", study, "--plan")
    assert proc.returncode == 2 and proc.stdout == "", proc.stderr
    for n in ("`parameters.n_elements`", "`n_elements` must be an integer in 1..=32", needle,
              "`values = [1, 2, 4]`"):
        assert n in proc.stderr, (n, proc.stderr)
    out = tmp_path / "bad.parquet"
    proc = tool(beam_body, "run", study, "-o", out, "--quiet")
    assert proc.returncode == 2 and needle in proc.stderr, proc.stderr
    assert not out.exists()


def test_an_integer_grid_runs_each_integer_in_an_integer_column(beam_body, tmp_path):
    study = write(tmp_path / "grid.toml", GRID)
    plan = json.loads(cli(beam_body, "study", study, "--plan").stdout)
    types = {c["name"]: c["type"] for c in plan["columns"]}
    assert types["n_elements"] == "int64" and types["M2 [kg]"] == "float64", types

    proc = cli(beam_body, "study", study, "--quiet")
    assert proc.returncode == 0, proc.stderr
    rows = [line.split(",") for line in proc.stdout.splitlines()[1:]]
    assert [r[1] for r in rows] == ["1", "2", "3"] and [r[2] for r in rows] == ["12.0"] * 3
    assert [r[4] for r in rows] == ["ok"] * 3, proc.stdout

    parquet = tmp_path / "grid.parquet"
    proc = tool(beam_body, "run", study, "-o", parquet, "--quiet")
    assert proc.returncode == 0, proc.stderr
    table = pq.read_table(parquet)
    assert table.schema.field("n_elements").type == pa.int64()
    assert table.column("n_elements").to_pylist() == [1, 2, 3]
    csv = tmp_path / "grid.csv"
    proc = tool(beam_body, "run", study, "-o", csv, "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert csv.read_text() == cli(beam_body, "study", study, "--quiet").stdout
