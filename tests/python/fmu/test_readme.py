"""README.md's FMPy blocks run as they are written, from the repository root: the six lines of the
paper's scene, the exact beam in FMPy (`"beam": 2`) and FMI 3.0 Model Exchange in n elements. A new
user's first lines must work."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys

import pytest

from conftest import REPO
from fmu_util import fmu3_path, fmu_path


def readme_python_blocks() -> list[str]:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    section = text.split("## The FMU in FMPy", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, re.S)


def run_block(tmp_path, code: str, check: str) -> str:
    """Runs `code` and then `check` from a copy of the repository's layout holding the FMUs under test
    (target/fmu/BeamBody.fmu, BeamBody-fmi3.fmu), so the blocks' paths name them whatever their path.
    Returns stdout."""
    fmu, fmu3 = fmu_path(), fmu3_path()
    assert fmu.exists() and fmu3.exists(), f"{fmu} or {fmu3} is missing: run `cargo xtask fmu`"
    (tmp_path / "target" / "fmu").mkdir(parents=True, exist_ok=True)
    shutil.copy(fmu, tmp_path / "target" / "fmu" / "BeamBody.fmu")
    shutil.copy(fmu3, tmp_path / "target" / "fmu" / "BeamBody-fmi3.fmu")
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run(
        [sys.executable, "-c", code + check], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600
    )
    assert proc.returncode == 0, f"the README's block failed:\n{proc.stdout}\n{proc.stderr[-3000:]}"
    return proc.stdout


def test_the_readme_has_its_three_blocks():
    blocks = readme_python_blocks()
    assert len(blocks) == 3, f"README.md's FMPy section has {len(blocks)} python blocks, expected 3"
    assert '"beam": 2' in blocks[1] and "FMU3Model" in blocks[2]


def test_readme_fmpy_block_runs(tmp_path):
    """The six lines run, and their v1 is the paper's: its peak on the block's own output grid (the
    DefaultExperiment's) within 2e-6 m of the sympy oracle's on the same grid (scipy DOP853 at rtol
    1e-13; the FMU at its default rtol 1e-6 measured 5e-7 m off)."""
    import json

    import numpy as np

    import oracle

    code = readme_python_blocks()[0]
    lines = [l for l in code.splitlines() if l.strip() and not l.lstrip().startswith("#")]
    assert len(lines) <= 6, f"the README promises six lines; the block has {len(lines)}"
    check = (
        "\nimport math\n"
        "assert abs(result['time'][-1] - 10.2) < 1e-9, result['time'][-1]\n"
        "assert all(math.isfinite(v) for name in ('v1', 'theta1', 'u2', 'M') for v in result[name])\n"
    ) + CHECK
    out = run_block(tmp_path, code, check)
    result = json.loads(out.split("RESULT ", 1)[1])
    t, v1 = np.array(result["t"]), np.array(result["v1"])
    _, Y = oracle.reference_solution("reduced", oracle.PAPER_SCENE, t_eval=t)
    peak, want = float(np.max(np.abs(v1))), float(np.max(np.abs(Y[:, 0])))
    assert abs(peak - want) < 2e-6, (peak, want)


def cli_v1(beam_body, t_end, **settings):
    """The CLI's (t, v1) on the paper's scene with `settings`, at rtol 1e-10."""
    import numpy as np

    args = [str(beam_body), "simulate", str(REPO / "scenes" / "paper.toml"), "--rtol", "1e-10",
            "--set", f"t_end={t_end}", "--set", "dt_out=0.001"]
    for k, v in settings.items():
        args += ["--set", f"{k}={v}"]
    out = subprocess.run(args, capture_output=True, text=True, timeout=600, check=True).stdout
    rows = np.array([[float(x) for x in line.split(",")[:2]] for line in out.splitlines()[1:]])
    return rows[:, 0], rows[:, 1]


# Each block's result against the CLI on the same beam: max |v1 - the CLI's| over the run, at the
# block's output points, within the block's tolerance (co-simulation at the default rtol 1e-6, Model
# Exchange through FMPy's CVode at rtol 1e-8).
CHECK = (
    "\nimport json\n"
    "print('RESULT', json.dumps({'t': [float(x) for x in result['time']], 'v1': [float(x) for x in result['v1']]}))\n"
)


@pytest.mark.parametrize("k, t_end, tol", [(1, 10.2, 2e-3), (2, 2.0, 1e-4)], ids=["exact beam", "fmi3 me n elements"])
def test_readme_exact_beam_blocks_give_the_cli_s_beam(tmp_path, beam_body, fmu_report, k, t_end, tol):
    """The exact beam in 4 elements, through FMI 2.0 co-simulation and FMI 3.0 Model Exchange, against
    the CLI's exact beam in 4 elements at rtol 1e-10."""
    import json

    import numpy as np

    out = run_block(tmp_path, readme_python_blocks()[k], CHECK)
    result = json.loads(out.split("RESULT ", 1)[1])
    t, v1 = np.array(result["t"]), np.array(result["v1"])
    assert abs(t[-1] - t_end) < 1e-9, t[-1]
    t_ref, v_ref = cli_v1(beam_body, t_end, beam="exact", n_elements=4)
    d = float(np.max(np.abs(np.interp(t, t_ref, v_ref) - v1)))
    fmu_report.figure("README", f"block {k + 1}: max|v1 - CLI exact n=4|", d, f"over {t_end} s")
    assert d <= tol, f"README block {k + 1}: |v1 - the CLI's| = {d:.3e} > {tol:g}"
    assert np.max(np.abs(v1)) > 0.3, "the body turned and the beam bent"


def test_the_readme_is_a_front_page():
    """A newcomer's front page (issue 43: the opening was dense and cited issue numbers): at most 250
    lines, no issue numbers (the history is in docs/), and in its first screen a one-line CLI run of the
    exact beam in n elements and the FMPy value that selects it."""
    text = (REPO / "README.md").read_text(encoding="utf-8")
    lines = text.splitlines()
    assert len(lines) <= 250, f"README.md has {len(lines)} lines"
    cited = re.findall(r"(?i)\bissues?\s+#?\d+", text)
    assert not cited, cited
    first_screen = "\n".join(lines[:40])
    assert re.search(r"beam-body simulate \S+ .*--beam exact --elements \d", first_screen), first_screen
    assert '"beam": 2' in text
