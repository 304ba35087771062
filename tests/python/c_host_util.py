"""Helpers shared by the C-host tests (test_c_host.py: native and valgrind; test_c_host_platforms.py:
Windows under wine, Linux aarch64 under qemu, and bit-identity across platforms).

- the host's source, its constants (host.c: H, N_STEPS) and the default check counts;
- compiling it with a given C compiler, warnings as errors;
- running it with a time limit, and its `<what> key=value ...` summary lines;
- reading its trajectory CSV (-o), with the exact bits of every value.
"""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

import numpy as np

from fmu_util import REPO, STATES

HOST_DIR = REPO / "tests" / "c_host"
HOST_C = HOST_DIR / "host.c"

H = 0.01  # the host's communication step (host.c: H, N_STEPS)
N_STEPS = 1020

CYCLES = 1000
THREADS = 8

WARNINGS = ["-Wall", "-Wextra", "-Werror"]


def compile_host(cc: str, exe: Path, flags=(), libs=()) -> Path:
    """host.c compiled with `cc`; any warning fails the build (-Werror, and nothing on stderr)."""
    cmd = [cc, "-O1", "-g", *flags, *WARNINGS, "-o", str(exe), str(HOST_C), *libs]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and not proc.stderr.strip(), (
        f"`{' '.join(cmd)}` exited with {proc.returncode}:\n{proc.stderr[-4000:]}"
    )
    return exe


def run_host(cmd, timeout, env=None) -> tuple[subprocess.CompletedProcess, float]:
    t0 = time.perf_counter()
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=timeout, env=env)
    return proc, time.perf_counter() - t0


def host_failure(proc, seconds) -> str:
    return (f"host exited with {proc.returncode} after {seconds:.1f} s\n"
            f"--- stdout (tail) ---\n{proc.stdout[-3000:]}\n--- stderr (tail) ---\n{proc.stderr[-3000:]}")


def parse_summary(stdout: str) -> dict[str, dict[str, str]]:
    """The host's `<what> key=value ...` lines as {what: {key: value}} (later lines of the same kind
    override earlier ones, except `thread <i>` lines, which are keyed by index)."""
    out: dict[str, dict[str, str]] = {}
    for line in stdout.splitlines():
        words = line.split()
        if not words:
            continue
        what = words[0] if words[0] != "thread" else f"thread {words[1]}"
        out.setdefault(what, {}).update(w.split("=", 1) for w in words[1:] if "=" in w)
    return out


def read_trajectory(path: Path) -> dict[str, np.ndarray]:
    """The host's -o CSV: t, v1, theta1, u2 (%.17g) as float arrays and, under `<q>_bits`, the
    IEEE-754 bits the host wrote in hex, as uint64 arrays. Fails if a decimal value does not parse
    back to its bits (the platform's printf would then not round-trip)."""
    lines = path.read_bytes().decode("ascii").splitlines()
    header = lines[0].split(",")
    assert header == ["t", *STATES, *(f"{q}_bits" for q in STATES)], header
    rows = [l.split(",") for l in lines[1:] if l]
    out: dict[str, np.ndarray] = {"t": np.array([float(r[0]) for r in rows])}
    for j, q in enumerate(STATES):
        out[q] = np.array([float(r[1 + j]) for r in rows])
        out[f"{q}_bits"] = np.array([int(r[4 + j], 16) for r in rows], dtype=np.uint64)
        bad = np.flatnonzero(out[q].view(np.uint64) != out[f"{q}_bits"])
        assert bad.size == 0, (
            f"{path}: {q} at row {int(bad[0])}: the decimal {rows[bad[0]][1 + j]} does not give the bits "
            f"{rows[bad[0]][4 + j]}: %.17g does not round-trip in this host's C library"
        )
    return out
