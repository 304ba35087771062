"""`cargo xtask model-error` (python/beam_body_study/model_error.py): its quick run end to end
through the CLI, and the README's quotation of the full report (docs/model_error.md).

Change detectors: the report's figures are the code's own. A model error is the difference of two
trajectories, and each is checked against a reference that shares no code with the Rust: the quadratic
model against the sympy oracle (tests/python/oracle/test_oracle_paper.py, test_oracle_elements_rust.py)
and the exact beam against tests/python/oracle_exact.py (test_oracle_exact_rust.py)."""

from __future__ import annotations

import re
import sys

from conftest import REPO

sys.path.insert(0, str(REPO / "python"))

from beam_body_study import model_error as me  # noqa: E402


def table_rows(text: str, heading: str, first: str) -> dict:
    """{first cell: cells} of the first table after `first` in the section `heading`."""
    section = text.split(f"## {heading}", 1)[1].split("\n## ", 1)[0]
    table = section.split(first, 1)[1]
    rows = {}
    for line in table.splitlines()[1:]:
        if not line.startswith("|"):
            if rows:
                break
            continue
        cells = [c.strip() for c in line.strip("|").split("|")]
        if not cells[0].startswith("---"):
            rows.setdefault(cells[0], []).append(cells[1:])
    return rows


def percent(cell: str) -> float:
    """'0.85 %' or '7.7e-04' as a fraction."""
    return float(cell.rstrip(" %")) / 100 if cell.endswith("%") else float(cell)


def test_quick_report_measures_what_it_says(beam_body, tmp_path):
    assert me.main(["--quick", "--out-dir", str(tmp_path), "--cli", str(beam_body)]) == 0
    text = (tmp_path / "model_error.md").read_text()
    assert (tmp_path / "model_error.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for scene in me.QUICK.scenes:
        title = scene.title[0].upper() + scene.title[1:]
        model = table_rows(text, title, "Model error")
        one, two = (percent(model[str(n)][0][4]) for n in (1, 2))  # v1 over the whole run
        # One element is off the 4-element reference by about a percent of the peak; two
        # elements by ten times less (the elements converge about 16-fold a halving).
        assert 1e-3 < one < 5e-2 and two < one / 5, (scene.name, one, two)
        runs = table_rows(text, title, "Integration error")
        for n in ("1", "2"):
            loose, tight = runs[n]
            assert tight[3] == "(itself)"
            integration = percent(loose[3])
            # rtol 1e-4 against 1e-6 of the same n: small, but not nothing.
            assert 0 < integration < 1e-2, (scene.name, n, integration)
            # The total error of the tight run is the model error.
            assert tight[4] == model[n][0][4]
    # The model hierarchy against the beam (the exact beam in 4 elements): the paper's model is
    # off it by the quadratic cut, several percent of the peak over 2 s of the paper's scene, and
    # the quadratic model in more elements no closer; the exact beam in 2 elements is within 0.2 %.
    ladder = table_rows(text, "The model hierarchy against the beam", "| model")
    paper, quadratic = ladder["the paper's model"][0], ladder["quadratic"][0]
    exact_one, exact_two = ladder["exact"]
    v1 = 3  # v1 over the whole run
    assert percent(paper[v1]) > 3e-2 and percent(quadratic[v1]) > 3e-2, (paper, quadratic)
    assert percent(exact_one[v1]) < percent(paper[v1]) / 3, (exact_one, paper)
    assert percent(exact_two[v1]) < 2e-3, exact_two
    assert ladder["exact (the beam)"][0][v1] == "0"


def test_errors_of_a_run_against_itself_vanish():
    scene = me.SCENES[0]
    t = [0.01 * k for k in range(200)]
    cols = {"t": t, "v1": [0.1 * x for x in t], "theta1": [-x for x in t],
            "M": [5.0 - x for x in t], "M_root": [x * x for x in t]}
    run = me.Run(scene, 1, 1e-6, cols)
    assert all(v == 0 for v in me.errors(run, run).values())
    other = me.Run(scene, 1, 1e-6, dict(cols, v1=[0.1 * x + (0.01 if x > 1.0 else 0) for x in t]))
    e = me.errors(other, run)
    assert e["v1 [0, T]"] == 0 and abs(e["v1 whole run"] - 0.01 / max(cols["v1"])) < 1e-12


def test_readme_quotes_the_report_change_detector():
    """The README's figures of the paper's model against the converged beam are those of
    docs/model_error.md (the quotation, not the figures, is what this checks)."""
    report = (REPO / "docs" / "model_error.md").read_text()
    readme = (REPO / "README.md").read_text()
    quoted = re.search(r"docs/model_error\.md", readme)
    assert quoted, "README.md does not point to docs/model_error.md"
    model = table_rows(report, "The paper's scene", "Model error")
    for cell in model["1"][0][4:6]:  # v1 and theta1 over the whole run
        assert cell in readme, f"README.md does not quote {cell!r} from docs/model_error.md"
