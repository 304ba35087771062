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
FORMULATIONS = ("reduced", "dae", "dae_stabilized", "linear")


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


#: The CLI's CSV columns, and their headers as the CSV writes them (`name [unit]`, the FMU's
#: names and units of the same outputs).
COLUMNS = "t,v1,theta1,u2,dv1,dtheta1,du2,phi_applied,dphi_applied,ddphi_applied,N,P,M,energy,drift".split(",")
UNITS = "s,m,rad,m,m/s,rad/s,m/s,rad,rad/s,rad/s2,N,N,N.m,J,m".split(",")
HEADER = [f"{c} [{u}]" for c, u in zip(COLUMNS, UNITS)]


BEAM_COLUMNS = "M_root,Q_root,v_quarter,v_mid,v_three_quarter".split(",")
BEAM_UNITS = "N.m,N,m,m,m".split(",")


def read_csv(text: str) -> dict:
    """The CLI's CSV output as {column name without its unit: numpy array}; checks the header: the
    paper's columns, and the beam's after them (`--columns beam`) if present, then the nodes'
    (`--columns shape`: v_k, theta_k)."""
    import csv
    import io

    import numpy as np

    rows = list(csv.reader(io.StringIO(text)))
    assert rows, "empty CSV"
    header = [h.strip() for h in rows[0]]
    columns = COLUMNS
    if len(header) > len(HEADER):
        columns = COLUMNS + BEAM_COLUMNS
        beam = HEADER + [f"{c} [{u}]" for c, u in zip(BEAM_COLUMNS, BEAM_UNITS)]
        assert header[:len(beam)] == beam, header
        nodes = header[len(beam):]
        assert len(nodes) % 2 == 0, header
        for k in range(len(nodes) // 2):
            assert nodes[2 * k:2 * k + 2] == [f"v_{k + 1} [m]", f"theta_{k + 1} [rad]"], header
            columns = columns + [f"v_{k + 1}", f"theta_{k + 1}"]
    else:
        assert header == HEADER, f"CSV header {header} != {HEADER}"
    data = np.array([[float(x) for x in r] for r in rows[1:] if r], dtype=float)
    assert data.ndim == 2 and data.shape[1] == len(columns)
    return {c: data[:, i] for i, c in enumerate(columns)}


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


# --------------------------------------------------------------------------------------------------
# FMU fixtures (tests/python/fmu/test_fmu_*.py; helpers in fmu_util.py)
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="session")
def fmu_file() -> Path:
    """The FMU: $BEAM_BODY_FMU, else target/fmu/BeamBody.fmu. Missing is a FAILURE, not a skip."""
    import fmu_util

    path = fmu_util.fmu_path()
    if not path.is_file():
        pytest.fail(
            f"FMU not found at {path} (set BEAM_BODY_FMU or build it): run `cargo xtask fmu` "
            "(it writes target/fmu/BeamBody.fmu), then `cargo xtask test`",
            pytrace=False,
        )
    return path


@pytest.fixture(scope="session")
def fmu3_file() -> Path:
    """The FMI 3.0 FMU: $BEAM_BODY_FMU_FMI3, else target/fmu/BeamBody-fmi3.fmu. Missing is a FAILURE,
    not a skip."""
    import fmu_util

    path = fmu_util.fmu3_path()
    if not path.is_file():
        pytest.fail(
            f"FMI 3.0 FMU not found at {path} (set BEAM_BODY_FMU_FMI3 or build it): run `cargo xtask fmu` "
            "(it writes target/fmu/BeamBody-fmi3.fmu), then `cargo xtask test`",
            pytrace=False,
        )
    return path


@pytest.fixture(scope="session")
def fmu_model_description(fmu_file):
    from fmpy import read_model_description

    return read_model_description(str(fmu_file), validate=False)


@pytest.fixture(scope="session")
def fmu_unzipdir(fmu_file, tmp_path_factory) -> Path:
    """The FMU extracted once per session (for fmpy.fmi2.FMU2Slave and simulate_fmu)."""
    import fmpy

    return Path(fmpy.extract(str(fmu_file), unzipdir=str(tmp_path_factory.mktemp("BeamBody_fmu"))))


@pytest.fixture(scope="session")
def fmu3_unzipdir(fmu3_file, tmp_path_factory) -> Path:
    """The FMI 3.0 FMU extracted once per session (for FMPy's FMU3Slave, FMU3Model and simulate_fmu, and the C
    host's --fmi3 checks)."""
    import fmpy

    return Path(fmpy.extract(str(fmu3_file), unzipdir=str(tmp_path_factory.mktemp("BeamBody_fmi3_fmu"))))


@pytest.fixture(scope="session")
def md3(fmu3_file):
    """The FMI 3.0 FMU's model description as FMPy reads it (not validated: its own tests validate)."""
    from fmpy import read_model_description

    return read_model_description(str(fmu3_file), validate=False)


@pytest.fixture(scope="session")
def fmu_report():
    """target/fmu-report.txt: measured figures, one per line, appended per session."""
    import fmu_util

    return fmu_util.Report()


# --------------------------------------------------------------------------------------------------
# the C host (tests/python/hosts/test_c_host*.py; helpers in c_host_util.py)
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="session")
def host_exe(tmp_path_factory) -> Path:
    """tests/c_host/host.c compiled with the system's cc; any warning fails the build (-Werror)."""
    import shutil

    from c_host_util import compile_host
    from fmu_util import missing_tool

    cc = shutil.which("cc")
    if cc is None:
        missing_tool("no C compiler: `cc` is not on PATH")
    exe = tmp_path_factory.mktemp("c_host") / "host"
    return compile_host(cc, exe, flags=["-pthread"], libs=["-ldl", "-lm"])
