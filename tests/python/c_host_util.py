"""Helpers shared by the C-host tests (test_c_host.py: native and valgrind; test_c_host_platforms.py:
Windows under wine, Linux aarch64 under qemu, and bit-identity across platforms).

- the host's source, its constants (host.c: H, N_STEPS) and the default check counts;
- compiling it with a given C compiler, warnings as errors;
- running it with a time limit, and its `<what> key=value ...` summary lines;
- reading its trajectory CSV (-o), with the exact bits of every value, and where two differ;
- FMI 3.0 (--fmi3): the constants of checks 5 and 6, the callbacks check 5 must count (the FMU's rule,
  computed here on its own), and the assertions on an --fmi3 run's summary that every platform shares.
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

# host.c's check 5 (--fmi3): IU_STEPS communication steps of IU_H, the FMU's intermediate_step IU_DT,
# |v1 - the law's run| below IU_TOL; check 6 refuses MISUSE_REFUSED calls; check 7 runs co-simulation in
# ARRAYS_N elements (nodal_v read as an array) and Model Exchange in ARRAYS_N_ME (4 states each).
IU_H = 0.0085
IU_DT = 1e-3
IU_STEPS = 200
IU_TOL = 1e-5
MAX_PARTS = 1e2  # the FMU's bound on the parts of one step (src/fmi/cosim.rs, MAX_PARTS)
MISUSE_REFUSED = 12
ARRAYS_N = 4
ARRAYS_N_ME = 2
FMI3_EXPORTS = 75


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


def intermediate_callbacks(h: float = IU_H, dt: float = IU_DT, steps: int = IU_STEPS) -> int:
    """How many times the FMU calls host.c's intermediate-update callback in check 5, by the FMU's rule
    (src/fmi/cosim.rs, step_part) with the same floating-point operations: from the FMU's time, parts
    of dt (at least h/MAX_PARTS) while more than 1.25 dt remains of the step to tc + h, then the rest;
    the callback between two parts. With h = 8.5 ms and dt = 1 ms: 8 parts of 1 ms and one of 0.5 ms,
    8 callbacks a step."""
    n, t = 0, 0.0
    for k in range(steps):
        target, part = k * h + h, max(dt, h / MAX_PARTS)
        while t + 1.25 * part < target and t + part > t:
            t += part
            n += 1
        t = target
    return n


def fmi3_summary_problems(s: dict[str, dict[str, str]], cycles: int, threads: int) -> list[str]:
    """What is wrong in the summary of a passed `host --fmi3` run (parse_summary): checks 1-4 with their
    counts, check 5's callbacks (the rule's number, the same in every step) and its v1 bound, check 6's
    refusals."""
    problems = []

    def expect(what, got, want):
        if got != want:
            problems.append(f"{what}: {got!r}, expected {want!r}")

    expect("host fmi", s["host"].get("fmi"), "3.0")
    expect("host exports", s["host"].get("exports"), str(FMI3_EXPORTS))
    expect("scene points", s["scene"].get("points"), str(N_STEPS + 1))
    expect("cycles n", s["cycles"].get("n"), str(cycles))
    if threads:
        expect("threads (n, identical, distinct)",
               (s["threads"].get("n"), s["threads"].get("identical"), s["threads"].get("distinct")),
               (str(threads), "1", str(threads)))
    expect("exchange (points, events, restored)",
           (s["exchange"].get("points"), s["exchange"].get("events"), s["exchange"].get("restored")),
           (str(N_STEPS + 1), "1", "identical"))
    iu = s.get("intermediate", {})
    want = intermediate_callbacks()
    expect("intermediate callbacks", iu.get("callbacks"), str(want))
    expect("intermediate callbacks a step (min, max)", (iu.get("per_step_min"), iu.get("per_step_max")),
           (str(want // IU_STEPS),) * 2)
    if not float(iu.get("max_dv1", "nan")) < IU_TOL:
        problems.append(f"intermediate max_dv1 = {iu.get('max_dv1')} m, not below {IU_TOL:g}")
    expect("misuse refused", s.get("misuse", {}).get("refused"), str(MISUSE_REFUSED))
    arrays = s.get("arrays", {})
    expect("arrays (n_elements, Model Exchange's n_elements and states)",
           (arrays.get("n_elements"), arrays.get("me_n_elements"), arrays.get("me_states")),
           (str(ARRAYS_N), str(ARRAYS_N_ME), str(4 * ARRAYS_N_ME + 2)))
    return problems


def first_difference(a: dict, b: dict, offset: int = 0) -> str | None:
    """Where two trajectories (read_trajectory) first differ bitwise: the point, each quantity's
    values there, and how many points differ in all; None if identical."""
    n = len(a["t"])
    assert len(b["t"]) == n, (len(a["t"]), len(b["t"]))
    diff = np.zeros(n, dtype=bool)
    for q in STATES:
        diff |= a[f"{q}_bits"] != b[f"{q}_bits"]
    if not diff.any():
        return None
    k = int(np.flatnonzero(diff)[0])
    parts = []
    for q in STATES:
        x, y = float(a[q][k]), float(b[q][k])
        ulps = abs(int(a[f"{q}_bits"][k].astype(np.int64)) - int(b[f"{q}_bits"][k].astype(np.int64)))
        parts.append(f"{q} {x!r} vs {y!r} ({ulps} ulp, {abs(x - y):.3e})")
    return (f"{int(diff.sum())} of {n} points differ, the first at step {k + offset} "
            f"(t = {(k + offset) * H:g}): " + "; ".join(parts))


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
