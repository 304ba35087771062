"""Shared pieces of the work-precision benchmark's Python side (bench_scipy, bench_reference,
bench_report): paths, the scene table, the output grid, and the file formats of the benchmark
contract (target/bench/{cases,raw,costs}.csv, sol/ and ref/ files).

The equations come from the test oracle (tests/python/oracle.py: the sympy derivation from the
energies), imported through sys.path; nothing here is copied from the Rust sources.
"""

from __future__ import annotations

import csv
import math
import os
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
TESTS_PY = REPO / "tests" / "python"
if str(TESTS_PY) not in sys.path:
    sys.path.insert(0, str(TESTS_PY))

DEFAULT_DIR = REPO / "target" / "bench"

#: scene name -> (scene file relative to the repo, formulation)
SCENES = {
    "paper": ("scenes/paper.toml", "reduced"),
    "paper-dae": ("scenes/paper.toml", "dae"),
    "paper-dae-stabilized": ("scenes/paper.toml", "dae_stabilized"),
    "stiff": ("scenes/stiff.toml", "reduced"),
}

STATES_REDUCED = ("v1", "theta1", "dv1", "dtheta1")
STATES_DAE = ("v1", "theta1", "u2", "dv1", "dtheta1", "du2")

GRID_DT = 0.01  # s, the contract's output grid step

RAW_HEADER = (
    "round,solver,scene,rtol,h,time_s,steps,rejected,rhs_evals,jac_evals,lu_factorizations,"
    "newton_iters,status"
).split(",")
CASES_HEADER = ["solver", "scene", "rtol", "h"]
COSTS_HEADER = ["round", "scene", "rhs_ns", "lu_ns", "solve_ns", "rhs_throughput_ns", "solve_throughput_ns"]


def is_dae(formulation: str) -> bool:
    return formulation in ("dae", "dae_stabilized")


def state_names(scene: str):
    return STATES_DAE if is_dae(SCENES[scene][1]) else STATES_REDUCED


def scene_file(scene: str) -> Path:
    return REPO / SCENES[scene][0]


def scene_values(scene: str) -> dict:
    """The scene's values (oracle.PAPER_SCENE keys, defaults filled in) read with conftest.load_toml."""
    import oracle
    from conftest import load_toml

    raw = load_toml(scene_file(scene))
    unknown = set(raw) - set(oracle.PAPER_SCENE) - {"rtol", "atol", "max_order"}
    if unknown:
        raise KeyError(f"{scene_file(scene)}: keys the oracle does not know: {sorted(unknown)}")
    return oracle.scene_with_defaults({k: float(v) for k, v in raw.items() if k in oracle.PAPER_SCENE})


def scene_params(values: dict) -> dict:
    import oracle

    return {k: values[k] for k in oracle.PARAM_NAMES}


def grid(t_end: float):
    """t_k = k*0.01 s, k = 0 .. round(t_end/0.01); the last point is exactly t_end."""
    import numpy as np

    n = int(round(t_end / GRID_DT))
    t = np.arange(n + 1) * GRID_DT
    t[-1] = t_end
    return t


# --------------------------------------------------------------------------------------------------
# case keys and file names
# --------------------------------------------------------------------------------------------------


def parse_opt_float(text):
    """'' or '-' -> None, else float."""
    text = (text or "").strip()
    if text in ("", "-"):
        return None
    return float(text)


def case_key(solver, scene, rtol, h):
    """Key of a case independent of how rtol and h are spelled (1e-3 == 0.001)."""
    return (solver.strip(), scene.strip(), parse_opt_float(rtol), parse_opt_float(h))


def sol_name(solver, scene, rtol_text, h_text):
    r = rtol_text.strip() or "-"
    h = h_text.strip() or "-"
    return f"{solver}__{scene}__{r}__{h}.csv"


def parse_sol_name(name: str):
    """Inverse of sol_name (as a case_key), or None."""
    if not name.endswith(".csv"):
        return None
    parts = name[:-4].split("__")
    if len(parts) != 4:
        return None
    try:
        return case_key(*parts)
    except ValueError:
        return None


# --------------------------------------------------------------------------------------------------
# CSV files
# --------------------------------------------------------------------------------------------------


def read_table(path: Path, header=None):
    """A CSV file with a header as a list of dicts (values stripped strings); checks the header if given."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise ValueError(f"{path}: empty")
    head = [h.strip() for h in rows[0]]
    if header is not None and head[: len(header)] != list(header):
        raise ValueError(f"{path}: header {head} != {list(header)}")
    out = []
    for r in rows[1:]:
        if not r or all(not x.strip() for x in r):
            continue
        r = r + [""] * (len(head) - len(r))
        out.append({k: v.strip() for k, v in zip(head, r)})
    return out


def read_cases(path: Path):
    return read_table(path, CASES_HEADER)


def write_atomic(path: Path, text: str):
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix="." + path.name, suffix=".tmp")
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    os.chmod(tmp, 0o644)  # mkstemp makes 0600
    os.replace(tmp, path)


def fmt_float(x) -> str:
    """Full round-trip precision (Python repr)."""
    return repr(float(x))


def write_sol(path: Path, t, Y, names):
    import numpy as np

    Y = np.asarray(Y, dtype=float) + 0.0  # no -0.0
    lines = ["t," + ",".join(names)]
    for k in range(len(t)):
        lines.append(",".join([fmt_float(t[k])] + [fmt_float(v) for v in Y[k]]))
    write_atomic(path, "\n".join(lines) + "\n")


def read_sol(path: Path):
    """(names, t, Y) of a sol/ or ref/ file."""
    import numpy as np

    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    head = [h.strip() for h in rows[0]]
    if not head or head[0] != "t":
        raise ValueError(f"{path}: first column must be t, header {head}")
    data = np.array([[float(x) for x in r] for r in rows[1:] if r], dtype=float)
    if data.ndim != 2 or data.shape[1] != len(head):
        raise ValueError(f"{path}: ragged rows")
    return tuple(head[1:]), data[:, 0], data[:, 1:]


def append_raw(path: Path, rows):
    """Append rows (dicts with RAW_HEADER keys; None -> empty) to raw.csv, creating it with the header."""
    path.parent.mkdir(parents=True, exist_ok=True)
    new = not path.is_file() or path.stat().st_size == 0
    with open(path, "a", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        if new:
            w.writerow(RAW_HEADER)
        for r in rows:
            w.writerow(["" if r.get(k) is None else str(r[k]) for k in RAW_HEADER])
        fh.flush()


def clean_status(msg: str) -> str:
    """A short status without commas or newlines."""
    s = " ".join(str(msg).replace(",", ";").split())
    return s[:120] if s else "error"


def fmt_sig(x, digits=3) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    return f"{x:.{digits}g}"
