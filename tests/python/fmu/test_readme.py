"""README.md's FMPy block runs as it is written, from the repository root, and gives the paper's
scene: a new user's first six lines must work."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys

from conftest import REPO


def readme_python_block() -> str:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    section = text.split("## The FMU in FMPy", 1)[1]
    match = re.search(r"```python\n(.*?)```", section, re.S)
    assert match, "README.md has no ```python block under '## The FMU in FMPy'"
    return match.group(1)


def test_readme_fmpy_block_runs(tmp_path):
    code = readme_python_block()
    lines = [l for l in code.splitlines() if l.strip() and not l.lstrip().startswith("#")]
    assert len(lines) <= 6, f"the README promises six lines; the block has {len(lines)}"
    fmu = os.environ.get("BEAM_BODY_FMU")
    assert fmu, "BEAM_BODY_FMU is not set: run `cargo xtask test`"
    # The block names target/fmu/BeamBody.fmu relative to the repository root: run it from a copy of
    # that layout, so the test uses the FMU under test whatever its path.
    (tmp_path / "target" / "fmu").mkdir(parents=True)
    shutil.copy(fmu, tmp_path / "target" / "fmu" / "BeamBody.fmu")
    check = (
        "\nimport math\n"
        "assert abs(result['time'][-1] - 10.2) < 1e-9, result['time'][-1]\n"
        "peak = max(abs(v) for v in result['v1'])\n"
        "assert 0.55 < peak < 0.62, peak\n"  # the paper's scene: max |v1| = 0.591 m (Fig. 3a)
        "assert all(math.isfinite(v) for name in ('v1', 'theta1', 'u2', 'M') for v in result[name])\n"
        "print('peak |v1|', peak)\n"
    )
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run(
        [sys.executable, "-c", code + check], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, f"the README's block failed:\n{proc.stdout}\n{proc.stderr[-3000:]}"
    assert "peak |v1|" in proc.stdout
