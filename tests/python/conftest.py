"""Fixtures for the physics-oracle tests.

The Rust CLI comes from $BEAM_BODY_BIN, else <repo>/target/release/beam-body. A missing binary is a test
FAILURE (not a skip): build it with `cargo xtask test`.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
TARGET = REPO / "target"
CACHE_DIR = TARGET / "oracle-cache"
REPORT_FILE = TARGET / "oracle-report.txt"
PAPER_SCENE = REPO / "scenes" / "paper.toml"
FORMULATIONS = ("reduced", "dae", "dae-stabilized", "linear")


def binary_path() -> Path:
    env = os.environ.get("BEAM_BODY_BIN")
    return Path(env) if env else TARGET / "release" / "beam-body"


@pytest.fixture(scope="session")
def beam_body() -> Path:
    path = binary_path()
    if not path.is_file() or not os.access(path, os.X_OK):
        pytest.fail(
            f"beam-body CLI binary not found or not executable at {path} "
            "(set BEAM_BODY_BIN or build it): run `cargo xtask test`",
            pytrace=False,
        )
    return path


def run_cli(binary: Path, args, stdin_text: str | None = None, timeout: float = 600.0) -> str:
    """Run the CLI; fail the test with its stderr on a non-zero exit. Returns stdout."""
    cmd = [str(binary), *[str(a) for a in args]]
    proc = subprocess.run(
        cmd, input=stdin_text, capture_output=True, text=True, timeout=timeout, cwd=REPO
    )
    if proc.returncode != 0:
        pytest.fail(
            f"`{' '.join(cmd)}` exited with {proc.returncode}\nstderr:\n{proc.stderr[-4000:]}",
            pytrace=False,
        )
    return proc.stdout


def set_args(params: dict) -> list[str]:
    out = []
    for k, v in params.items():
        out += ["--set", f"{k}={float(v)!r}"]
    return out


def load_toml(path: Path) -> dict:
    """Flattened scene: leaf keys of all tables (the contract's keys are unique names)."""
    try:
        import tomllib  # Python >= 3.11
    except ModuleNotFoundError:  # pragma: no cover
        import tomli as tomllib  # type: ignore
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    flat: dict = {}

    def walk(d):
        for k, v in d.items():
            if isinstance(v, dict):
                walk(v)
            else:
                flat[k] = v

    walk(data)
    return flat


@pytest.fixture(scope="session")
def paper_scene_file() -> Path:
    if not PAPER_SCENE.is_file():
        pytest.fail(f"scene file {PAPER_SCENE} is missing", pytrace=False)
    return PAPER_SCENE


_REPORT: dict[str, str] = {}


def write_report(key: str, line: str):
    """target/oracle-report.txt: one line per formulation, first word the formulation; other facts on
    lines starting with '# ' (the file is rewritten after every test)."""
    _REPORT[key] = line
    REPORT_FILE.parent.mkdir(parents=True, exist_ok=True)
    order = [f for f in FORMULATIONS if f in _REPORT] + [k for k in _REPORT if k not in FORMULATIONS]
    REPORT_FILE.write_text("".join(_REPORT[k] + "\n" for k in order))
