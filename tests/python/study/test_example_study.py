"""The study commands of docs/design-studies.md run as written, from the repository root, and give
the figures that page quotes. The outputs go to a temporary directory instead of target/study/,
so that the test does not meet the finished chunks of an earlier run."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys

import numpy as np
import pyarrow.parquet as pq

from conftest import REPO

sys.path.insert(0, str(REPO / "python"))

from beam_body_study.columns import bare  # noqa: E402


def read_bare(path):
    """A table as {column name without its unit: values}."""
    return {bare(k): v for k, v in pq.read_table(path).to_pydict().items()}


def readme_study_commands() -> list:
    section = (REPO / "docs" / "design-studies.md").read_text(encoding="utf-8")
    match = re.search(r"```sh\n(.*?)```", section, re.S)
    assert match, "docs/design-studies.md has no ```sh block"
    return [line for line in match.group(1).splitlines() if line.strip()]


def test_design_studies_commands_and_figures_change_detector(tmp_path):
    """A change detector: the commands run as written, and the figures the page quotes are those this
    code computes (it wrote them). The same metrics are checked against the oracle, which shares no code
    with this, in test_study.py (test_turn_map_and_hinge_moment_metrics_against_the_oracle)."""
    commands = readme_study_commands()
    assert len(commands) == 4 and all(c.startswith("cargo xtask study ") for c in commands)
    for command in commands:
        args = [a.replace("target/study/", f"{tmp_path}/") for a in shlex.split(command)]
        proc = subprocess.run(args, cwd=REPO, capture_output=True, text=True, timeout=900)
        assert proc.returncode == 0, f"`{command}` failed:\n{proc.stderr[-4000:]}"

    readme = (REPO / "docs" / "design-studies.md").read_text(encoding="utf-8")
    turn = read_bare(tmp_path / "turn_map.parquet")
    assert len(turn["case"]) == 2812 and set(turn["status"]) == {"ok"}
    t_rot, residual = np.array(turn["t_rot"]), np.array(turn["residual_v1"])
    below = residual < 0.01
    # The page's figures of the map.
    assert f"{below.sum()} of the 2,812 cases are below 1 cm" in readme, below.sum()
    assert f"none with a turn shorter than {t_rot[below].min():g} s" in readme
    short = residual[t_rot <= 2.0]
    assert 0.2 < short.min() and short.max() < 0.65, (short.min(), short.max())
    last = residual[np.isclose(t_rot, 8.0)]
    assert f"{100 * np.mean(last < 0.01):.0f} % of the masses" in readme
    assert f"the worst leaves {100 * last.max():.1f} cm" in readme

    mc = read_bare(tmp_path / "hinge_moment_mc.parquet")
    assert len(mc["case"]) == 10_000 and set(mc["status"]) == {"ok"}
    peak = np.array(mc["peak_M"])
    q50, q99 = np.quantile(peak, 0.5), np.quantile(peak, 0.99)
    assert f"the median is {q50:.1f} N·m" in readme, q50
    assert f"the 99th percentile is {q99:.1f} N·m" in readme, q99
    for png in ("turn_map.png", "hinge_moment_mc.png"):
        assert (tmp_path / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
