"""The FMU's shared library under a small C host (tests/c_host/host.c): dlopen/dlsym, a variadic logger,
the paper's scene, 1000 instantiate/free cycles with the life cycle and FMU states, and 8 instances
stepping in 8 pthreads; natively and under valgrind memcheck.

What is compared, and how closely:
- the host's trajectory of the paper's scene (v1, theta1, u2 at the 1021 communication points) against
  the same calls made through FMPy's FMU2Slave in this process: bit for bit. Same library, same
  arguments (tc = k*h, h = 0.01, tolerance undefined, stop time 10.2), same libm: any difference
  would be state that leaks between calls or instances, or a dependence on the host.
- the same trajectory against the CLI (`beam-body simulate scenes/paper.toml --set dt_out=0.01`):
  |host - CLI| <= SAME_STEPS * max|y_CLI| per state. With the law the FMU's integrator runs ahead of the
  communication points and takes the CLI's own steps (the same stop time, 10.2 s), so the two agree to
  the rounding of the output times (test_fmu_law.py).
- 8 threads against the same 8 configurations run one after another: bit for bit (checked in C).
- Model Exchange (check 4 of host.c): the host's own RK4 at 0.5 ms through the time event at t_rot,
  against the CLI at rtol 1e-11: within ME_TOL (measured 7.1e-9 m in v1, 1.3e-8 rad in theta1: RK4's
  error at that step); the FMU state restored at 5.1 s continues bit for bit (checked in C).

Valgrind: the main run keeps the library loaded at exit (--no-dlclose) and must show no error and no
definitely/indirectly/possibly lost block, without suppressions. A second run unloads and reloads the
library 5 times and must lose nothing either: the FMU's statics own no heap once no instance or FMU
state is alive (the pointer registry drops its tables when it empties; the GUID is a fixed-size array).
Before that fix this run lost 150-260 bytes per load, which a host that reloads the FMU for every run
(FMPy does) would pay each time.

FMI 3.0 (host.c --fmi3, on BeamBody-fmi3.fmu's x86_64-linux library, the same binary): checks 1-4, with the
full counts, run by the same C code through adapters, each an FMI 2.0 function the checks call made of
FMI 3.0 calls (the set-up with fmi3EnterInitializationMode, phi_source with fmi3SetInt64; fmi3DoStep's
out-arguments checked at every step: no event handling needed, no early return, lastSuccessfulTime =
tc + h exactly; fmi3UpdateDiscreteStates's six); then
- the scene's and Model Exchange's trajectories equal the FMI 2.0 run's bit for bit (one core);
- check 5, the intermediate-update callback (phi_source = input, requiredIntermediateVariables = {phi},
  intermediate_step = 1 ms, h = 8.5 ms over 1.7 s, phi = the law with the C library's sin): 1600
  callbacks, 8 a step, the FMU's rule's number (computed here independently, intermediate_callbacks) and
  times; v1 within 1e-5 m of the law's run at rtol 1e-8 (measured 2.2e-6 m; with phi at the communication
  points only 2.4e-4 m; at the default rtol 1e-6 the integrator's own error, 6.0e-5 m, would hide it);
- check 6, 12 calls refused with fmi3Error and no crash: NULL instance (4 functions), an FMI 2.0 instance
  to fmi3DoStep and an FMI 3.0 one to fmi2DoStep, fmi3InstantiateScheduledExecution (NULL), in
  configuration mode a parameter that is not structural and fmi3ExitConfigurationMode twice,
  fmi3UpdateDiscreteStates in co-simulation, a NULL out-argument of fmi3DoStep, fmi3DoStep on Model
  Exchange;
- check 7, arrays: n_elements = 4 set in configuration mode (fmi3SetUInt64), 100 co-simulation steps with
  nodal_v read with nValues = 4 (its last element v1, bit for bit; nothing written past it), nValues = 3
  refused; Model Exchange with n_elements = 2 has 8 continuous states.
Measured: 0.14 s natively (FMI 2.0's run: 0.05 s); under valgrind, one run of checks 1-6 with 100 cycles
and 2 threads, the library unloaded and reloaded once: 3.2 s, no error, nothing lost.

Windows (wine), Linux aarch64 (qemu) and the bit-identity across platforms are in
test_c_host_platforms.py; the helpers both use are in c_host_util.py, the compiled native host is the
session fixture `host_exe` (conftest.py).

Figures go to target/fmu-report.txt.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from c_host_util import (CYCLES, H, N_STEPS, THREADS, first_difference, fmi3_summary_problems,
                         host_failure, intermediate_callbacks, parse_summary, read_trajectory, run_host)
from fmu_util import PHI_SOURCE_LAW, T_END, Slave, cli, missing_tool

RTOL = 1e-6  # the FMU's default tolerance (DefaultExperiment) and the CLI's default rtol
ME_TOL = 1e-7  # |host's RK4 on the Model Exchange equations - CLI at rtol 1e-11| (see the docstring)
SAME_STEPS = 1e-12  # see the module docstring

# Under valgrind the full counts take about 5 s on this machine (one core: valgrind serialises
# threads), so the main valgrind run keeps them; the reload run only needs a few loads.
VALGRIND_CYCLES = CYCLES
VALGRIND_THREADS = THREADS
RELOADS = 4
# FMI 3.0 under valgrind: one run, shorter (every kind of cycle is still made; the cycles and threads
# are the same C code as FMI 2.0's), unloading and reloading the library once.
VALGRIND_FMI3_CYCLES = 100
VALGRIND_FMI3_THREADS = 2
VALGRIND_FMI3_RELOADS = 1

NATIVE_TIMEOUT = 60
VALGRIND_TIMEOUT = 300

VALGRIND_ARGS = [
    "--tool=memcheck",
    "--leak-check=full",
    "--show-leak-kinds=definite,indirect,possible",
    "--errors-for-leak-kinds=definite,indirect,possible",
    "--error-exitcode=99",
    "--num-callers=40",
]


# --------------------------------------------------------------------------------------------------
# fixtures
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def native(host_exe, fmu_unzipdir, tmp_path_factory):
    """One native run with the full counts; its trajectory file and stdout (the Model Exchange
    trajectory is beside it, `paper_me.csv`)."""
    traj = tmp_path_factory.mktemp("c_host_run") / "paper.csv"
    me = traj.with_name("paper_me.csv")
    proc, seconds = run_host(
        [host_exe, fmu_unzipdir, "--cycles", CYCLES, "--threads", THREADS, "-o", traj, "--me-out", me],
        NATIVE_TIMEOUT,
    )
    return proc, seconds, traj


@pytest.fixture(scope="module")
def native3(host_exe, fmu3_unzipdir, tmp_path_factory):
    """The same run through FMI 3.0 (--fmi3) on the FMI 3.0 archive: checks 1-4 with the full counts,
    then 5 (intermediate update), 6 (misuse) and 7 (arrays)."""
    traj = tmp_path_factory.mktemp("c_host_run_fmi3") / "paper.csv"
    me = traj.with_name("paper_me.csv")
    proc, seconds = run_host(
        [host_exe, fmu3_unzipdir, "--fmi3", "--cycles", CYCLES, "--threads", THREADS, "-o", traj,
         "--me-out", me],
        NATIVE_TIMEOUT,
    )
    return proc, seconds, traj


# --------------------------------------------------------------------------------------------------
# native
# --------------------------------------------------------------------------------------------------


def test_native_host_passes(native, fmu_report):
    proc, seconds, _ = native
    assert proc.returncode == 0, host_failure(proc, seconds)
    s = parse_summary(proc.stdout)
    assert s["host"]["result"] == "PASS", host_failure(proc, seconds)
    assert int(s["scene"]["points"]) == N_STEPS + 1
    assert int(s["cycles"]["n"]) == CYCLES
    assert (s["threads"]["n"], s["threads"]["identical"], s["threads"]["distinct"]) == (
        str(THREADS), "1", str(THREADS)
    ), proc.stdout
    assert (s["exchange"]["points"], s["exchange"]["events"], s["exchange"]["restored"]) == (
        str(N_STEPS + 1), "1", "identical"
    ), proc.stdout
    tag = "c_host native"
    fmu_report.figure(tag, "wall_seconds", seconds, f"{CYCLES} cycles, {THREADS} threads, compile excluded")
    fmu_report.figure(tag, "exchange_seconds", float(s["exchange"]["seconds"]),
                      f"{s['exchange']['steps']} RK4 steps of Model Exchange")
    fmu_report.figure(tag, "scene_seconds", float(s["scene"]["seconds"]))
    fmu_report.figure(tag, "cycles_seconds", float(s["cycles"]["seconds"]), f"{s['cycles']['messages']} log messages")
    fmu_report.figure(tag, "threads_sequential_seconds", float(s["threads"]["sequential_seconds"]))
    fmu_report.figure(tag, "threads_parallel_seconds", float(s["threads"]["parallel_seconds"]))
    fmu_report.note(tag, f"final v1 = {s['scene_final']['v1']}, max|v1| = {s['scene_max_abs']['v1']}")


def host_trajectory(native, me: bool = False) -> dict:
    """The scene's trajectory of a native run (fixture `native` or `native3`); with `me`, Model
    Exchange's."""
    proc, seconds, traj = native
    if me:
        traj = traj.with_name("paper_me.csv")
    if proc.returncode != 0 or not traj.is_file():
        pytest.fail("the native host run failed (see test_native_host_passes and test_fmi3_native_host_passes)\n"
                    + host_failure(proc, seconds), pytrace=False)
    data = read_trajectory(traj)  # %.17g, checked against the bits the host wrote beside it
    assert data["t"].shape == (N_STEPS + 1,), data["t"].shape
    return data


def test_host_matches_fmpy_bit_for_bit(native, fmu_unzipdir, fmu_model_description, fmu_report):
    """The same calls through FMPy's FMU2Slave, in this process: identical doubles."""
    h = host_trajectory(native)
    s = Slave(fmu_unzipdir, fmu_model_description, name="c_host_reference")
    try:
        s.start(tolerance=None, start_time=0.0, stop_time=T_END, integers={"phi_source": PHI_SOURCE_LAW})
        rows = [s.get(("v1", "theta1", "u2"))]
        for k in range(1, N_STEPS + 1):
            s.fmu.doStep((k - 1) * H, H)  # tc = (k-1)*h exactly as host.c computes it
            rows.append(s.get(("v1", "theta1", "u2")))
        s.fmu.terminate()
        errors = s.errors()
    finally:
        s.free()
    assert not errors, errors
    ref = np.array(rows)
    mismatches, n_diff = [], 0
    for j, q in enumerate(("v1", "theta1", "u2")):
        diff = np.flatnonzero(h[q].view(np.uint64) != np.ascontiguousarray(ref[:, j]).view(np.uint64))
        n_diff += diff.size
        if diff.size:
            k = int(diff[0])
            mismatches.append(f"{q}: {diff.size} points differ, first at t = {k * H:g}: "
                              f"host {h[q][k]!r} vs FMPy {ref[k, j]!r}")
    fmu_report.figure("c_host vs FMPy", "differing_values", n_diff,
                      f"bit-for-bit comparison of v1, theta1, u2 at {N_STEPS + 1} points")
    assert not mismatches, "\n".join(mismatches)


def test_host_matches_cli(native, beam_body, fmu_report):
    """Against the standalone solver on the same grid, within K_TOL * rtol * max|y| (see the docstring)."""
    h = host_trajectory(native)
    c = cli(beam_body, dt_out=H)
    assert len(c["t"]) == N_STEPS + 1, f"{len(c['t'])} CLI rows, expected {N_STEPS + 1}"
    assert np.max(np.abs(h["t"] - c["t"])) <= 1e-12, "the host's and the CLI's grids differ"
    failures = []
    for q in ("v1", "theta1", "u2"):
        assert np.all(np.isfinite(h[q])), f"non-finite {q}"
        scale = float(np.max(np.abs(c[q])))
        d = float(np.max(np.abs(h[q] - c[q])))
        fmu_report.figure("c_host vs CLI", f"max|host-CLI|_{q}", d, f"{d / scale:.1e} of max|y| (bound {SAME_STEPS:g})")
        if d > SAME_STEPS * scale:
            failures.append(f"{q}: |host - CLI| = {d:.3e}: not the CLI's steps")
    assert not failures, "\n".join(failures)


def test_host_model_exchange_matches_cli(native, beam_body, fmu_report):
    """The host's RK4 (0.5 ms) on the Model Exchange equations, through the law's time event, against
    the CLI's co-simulation equations at rtol 1e-11 on the same grid: within ME_TOL."""
    proc, seconds, traj = native
    me = traj.with_name("paper_me.csv")
    if proc.returncode != 0 or not me.is_file():
        pytest.fail("the native host run failed (see test_native_host_passes)\n" + host_failure(proc, seconds),
                    pytrace=False)
    h = read_trajectory(me)
    c = cli(beam_body, dt_out=H, rtol=1e-11, atol=1e-13)
    assert np.max(np.abs(h["t"] - c["t"])) <= 1e-12, "the host's and the CLI's grids differ"
    failures = []
    for q in ("v1", "theta1", "u2"):
        d = float(np.max(np.abs(h[q] - c[q])))
        fmu_report.figure("c_host Model Exchange vs CLI", f"max|host-CLI|_{q}", d, "RK4 h = 0.5 ms, CLI rtol 1e-11")
        if not d <= ME_TOL:
            failures.append(f"{q}: |host - CLI| = {d:.3e} > {ME_TOL:g}")
    assert not failures, "\n".join(failures)


# --------------------------------------------------------------------------------------------------
# FMI 3.0, native
# --------------------------------------------------------------------------------------------------


def test_fmi3_native_host_passes(native3, fmu_report):
    """host --fmi3: the 75 exports, checks 1-4 through FMI 3.0 with the full counts, the
    intermediate-update callback (as many calls as the FMU's rule gives, computed here on its own: 8
    a step, 1600), the misuse refused."""
    proc, seconds, _ = native3
    assert proc.returncode == 0, host_failure(proc, seconds)
    s = parse_summary(proc.stdout)
    assert s["host"]["result"] == "PASS", host_failure(proc, seconds)
    problems = fmi3_summary_problems(s, CYCLES, THREADS)
    tag = "c_host fmi3 native"
    iu = s["intermediate"]
    fmu_report.figure(tag, "wall_seconds", seconds, f"checks 1-6, {CYCLES} cycles, {THREADS} threads, compile excluded")
    fmu_report.figure(tag, "intermediate_callbacks", int(iu["callbacks"]),
                      f"the rule: {intermediate_callbacks()}, {iu['per_step_min']} a step")
    fmu_report.figure(tag, "intermediate_max_dv1", float(iu["max_dv1"]),
                      f"vs the law's run at rtol {iu['rtol']}; phi at the communication points only: "
                      f"{iu['max_dv1_values_only']}")
    fmu_report.figure(tag, "intermediate_seconds", float(iu["seconds"]), "three runs of 200 steps")
    fmu_report.figure(tag, "misuse_refused", int(s["misuse"]["refused"]))
    assert not problems, "\n".join(problems) + "\n" + proc.stdout[-3000:]


@pytest.mark.parametrize("me", [False, True], ids=["co-simulation", "model-exchange"])
def test_fmi3_is_fmi2s_bit_for_bit(native, native3, me, fmu_report):
    """The paper's scene (check 1) and the host's RK4 on Model Exchange (check 4) through FMI 3.0 give
    the FMI 2.0 run's doubles at every communication point: one core under both APIs, the same calls
    (the set-up's tolerance and times with fmi3EnterInitializationMode, phi_source with fmi3SetInt64)."""
    where = first_difference(host_trajectory(native3, me), host_trajectory(native, me))
    what = "model_exchange" if me else "scene"
    fmu_report.figure("c_host fmi3 vs fmi2", f"{what}_identical", int(where is None),
                      f"v1, theta1, u2 at {N_STEPS + 1} points, bit for bit" + (f": {where}" if where else ""))
    assert where is None, f"FMI 3.0 vs FMI 2.0 ({what}): {where}"


# --------------------------------------------------------------------------------------------------
# valgrind
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def valgrind() -> str:
    path = shutil.which("valgrind")
    if path is None:
        missing_tool("valgrind is not installed (apt-get install valgrind)")
    return path


def memcheck(valgrind, host_exe, fmu_unzipdir, log: Path, host_args, extra=()):
    cmd = [valgrind, *VALGRIND_ARGS, *extra, f"--log-file={log}", host_exe, fmu_unzipdir, *host_args]
    proc, seconds = run_host(cmd, VALGRIND_TIMEOUT)
    text = log.read_text(errors="replace") if log.is_file() else ""
    return proc, seconds, text


SUMMARY_LINE = re.compile(
    r"(ERROR SUMMARY:.*|definitely lost:.*|indirectly lost:.*|possibly lost:.*|still reachable:.*|"
    r"suppressed:.*bytes.*|All heap blocks were freed.*|used_suppression:.*|in use at exit:.*|total heap usage:.*)"
)


def summary(text: str) -> str:
    """valgrind's summary lines, each once (with -s the ERROR SUMMARY is printed twice)."""
    return "\n".join(dict.fromkeys(m.group(1).strip() for m in SUMMARY_LINE.finditer(text)))


def lost_bytes(text: str, kind: str) -> int | None:
    m = re.search(rf"{kind} lost: ([\d,]+) bytes", text)
    return int(m.group(1).replace(",", "")) if m else None


def first_error(text: str, n_lines: int = 40) -> str:
    """The first error or loss record of the log, for the assertion message."""
    lines = [re.sub(r"^==\d+== ?", "", l) for l in text.splitlines()]
    for i, l in enumerate(lines):
        if re.search(r"(Invalid|uninitialised|Mismatched|are (definitely|indirectly|possibly) lost)", l):
            return "\n".join(lines[i:i + n_lines])
    return ""


def check_clean(text: str, proc, seconds) -> list[str]:
    problems = []
    if proc.returncode != 0:
        problems.append(f"valgrind/host exit status {proc.returncode} (99: valgrind found errors)")
    m = re.search(r"ERROR SUMMARY: (\d+) errors", text)
    if m is None:
        problems.append("no ERROR SUMMARY line in valgrind's log")
    elif int(m.group(1)) != 0:
        problems.append(f"ERROR SUMMARY: {m.group(1)} errors")
    if "All heap blocks were freed" not in text:
        for kind in ("definitely", "indirectly", "possibly"):
            b = lost_bytes(text, kind)
            if b is None:
                problems.append(f"no '{kind} lost' line in valgrind's log")
            elif b:
                problems.append(f"{kind} lost: {b} bytes")
    return problems


def test_valgrind_memcheck_clean(valgrind, host_exe, fmu_unzipdir, tmp_path, fmu_report):
    """Scene, cycles and threads under memcheck: no invalid access, no uninitialised value, no leak
    (still reachable is allowed: the loader's and std's own blocks of a library that stays loaded)."""
    log = tmp_path / "memcheck.log"
    proc, seconds, text = memcheck(
        valgrind, host_exe, fmu_unzipdir, log,
        ["--cycles", VALGRIND_CYCLES, "--threads", VALGRIND_THREADS, "--no-dlclose"],
        extra=["-s"],
    )
    problems = check_clean(text, proc, seconds)
    if "host result=PASS" not in proc.stdout:
        problems.append("the host itself failed:\n" + host_failure(proc, seconds))
    tag = "c_host valgrind"
    fmu_report.figure(tag, "wall_seconds", seconds, f"{VALGRIND_CYCLES} cycles, {VALGRIND_THREADS} threads")
    for line in summary(text).splitlines():
        fmu_report.note(tag, line)
    assert not problems, "\n".join(problems) + f"\n--- valgrind summary ---\n{summary(text)}\n" \
        f"--- first report ---\n{first_error(text)}"


def test_valgrind_unload_leaves_nothing(valgrind, host_exe, fmu_unzipdir, tmp_path, fmu_report):
    """A host that loads, uses and unloads the library RELOADS + 1 times (as FMPy does for every
    simulate_fmu) must not lose memory: after dlclose nothing can free what the library kept."""
    log = tmp_path / "memcheck_reload.log"
    # Leaks are not counted as errors here, so that ERROR SUMMARY and the exit status tell the
    # memory errors (a hard failure) apart from the leak (the expected failure).
    proc, seconds, text = memcheck(
        valgrind, host_exe, fmu_unzipdir, log, ["--cycles", 16, "--threads", 2, "--reloads", RELOADS],
        extra=["--errors-for-leak-kinds=none"],
    )
    assert "host result=PASS" in proc.stdout, host_failure(proc, seconds)
    assert proc.returncode == 0 and re.search(r"ERROR SUMMARY: 0 errors", text), (
        f"memory errors (not leaks) after reloading, exit status {proc.returncode}\n{summary(text)}\n"
        f"--- first report ---\n{first_error(text)}"
    )
    assert proc.stdout.count("dlclose unloaded=1") == RELOADS + 1, (
        "the library stayed mapped after dlclose: this test measures nothing\n" + proc.stdout[-2000:]
    )
    fmu_report.figure("c_host valgrind reload", "definitely_lost_bytes", lost_bytes(text, "definitely") or 0,
                      f"{RELOADS + 1} loads")
    leaks = {kind: lost_bytes(text, kind) for kind in ("definitely", "indirectly", "possibly")}
    assert "All heap blocks were freed" in text or all(b == 0 for b in leaks.values()), (
        f"memory lost after {RELOADS + 1} loads: "
        + ", ".join(f"{k} lost {b} bytes" for k, b in leaks.items())
        + f"\n--- valgrind summary ---\n{summary(text)}\n--- first report ---\n{first_error(text)}"
    )


def test_valgrind_fmi3_clean(valgrind, host_exe, fmu3_unzipdir, tmp_path, fmu_report):
    """host --fmi3 (checks 1-6, shorter: VALGRIND_FMI3_CYCLES cycles, VALGRIND_FMI3_THREADS threads) under
    memcheck, the library unloaded at the end, then loaded, used and unloaded once more: no error, and no
    block lost, definitely, indirectly or possibly (after the unload nothing could free it)."""
    log = tmp_path / "memcheck_fmi3.log"
    proc, seconds, text = memcheck(
        valgrind, host_exe, fmu3_unzipdir, log,
        ["--fmi3", "--cycles", VALGRIND_FMI3_CYCLES, "--threads", VALGRIND_FMI3_THREADS,
         "--reloads", VALGRIND_FMI3_RELOADS],
        extra=["-s"],
    )
    problems = check_clean(text, proc, seconds)
    if "host result=PASS" not in proc.stdout:
        problems.append("the host itself failed:\n" + host_failure(proc, seconds))
    elif proc.stdout.count("dlclose unloaded=1") != VALGRIND_FMI3_RELOADS + 1:
        problems.append("the library stayed mapped after dlclose: the leak check measures less\n" + proc.stdout[-2000:])
    tag = "c_host fmi3 valgrind"
    fmu_report.figure(tag, "wall_seconds", seconds,
                      f"checks 1-6, {VALGRIND_FMI3_CYCLES} cycles, {VALGRIND_FMI3_THREADS} threads, "
                      f"{VALGRIND_FMI3_RELOADS + 1} loads")
    for line in summary(text).splitlines():
        fmu_report.note(tag, line)
    assert not problems, "\n".join(problems) + f"\n--- valgrind summary ---\n{summary(text)}\n" \
        f"--- first report ---\n{first_error(text)}"
