"""The FMU's Windows and Linux-aarch64 libraries under the C host (tests/c_host/host.c), cross-compiled
on this x86-64 Linux machine and run under emulation, and bit-identity across the three platforms.

- win64: host.c compiled with mingw-w64 (x86_64-w64-mingw32-gcc: Windows threads, no mingw runtime
  DLL), run under wine64 in a fresh private WINEPREFIX on binaries/win64/BeamBody.dll;
- aarch64-linux: host.c compiled with aarch64-linux-gnu-gcc, run under qemu-aarch64 (user mode,
  -L /usr/aarch64-linux-gnu) on binaries/aarch64-linux/BeamBody.so;
- linux64: the native host (conftest's `host_exe`) on binaries/linux64/BeamBody.so, the reference.

On win64 and aarch64-linux the host runs its four checks with the full counts (the paper's scene,
1000 instantiate/free cycles, 8 threads bit-identical to a serial run, Model Exchange under its own
RK4; test_c_host.py runs them natively), and saves the FMU state after communication step K_SAVE of
the scene. Then, bit for bit:
- the Model Exchange trajectory on each emulated platform equals the native one;
- the scene's trajectory (v1, theta1, u2 at the 1021 communication points) on each platform equals
  the native one (a native run without --save-state: saving a state must not disturb the run);
- the serialized FMU state at step K_SAVE is the same bytes on all three platforms;
- a state saved on any platform, restored on any platform (all 9 pairs, --resume), continues the
  scene exactly as the uninterrupted native run does, from step K_SAVE to the end.
The library computes sin, cos, exp, pow, ... with its own libm (src/math.rs): nothing of the
platform's C library enters the numbers, so nothing is compared with a tolerance. A difference is
reported with the first point (and quantity) where it appears.

FMI 3.0: the same host with --fmi3 on the FMI 3.0 archive ($BEAM_BODY_FMU_FMI3) loads
binaries/x86_64-windows/BeamBody.dll under wine and binaries/aarch64-linux/BeamBody.so under qemu, and
runs checks 1-4 through FMI 3.0 (FMI3_CYCLES cycles and FMI3_THREADS threads: fewer than FMI 2.0's, the
same C code), the intermediate-update callback (check 5: the count of the FMU's rule, 1600, and v1 within
1e-5 m of the law's run), the misuse refusals (check 6) and the arrays (check 7). Then, bit for bit, its scene and its Model
Exchange trajectory on each emulated platform equal the native FMI 2.0 runs' (test_c_host.py compares
the native FMI 3.0 run with them). Check 5 sets phi with the platform's own sin, so its v1 is only
reported against the native --fmi3 run's (measured: identical on both). Times: 2.7 s under wine (its
start-up), 1.0 s under qemu.

The libraries come from the FMUs ($BEAM_BODY_FMU, $BEAM_BODY_FMU_FMI3); all of them must be built
from the same source. A missing cross compiler, emulator, or binary in the FMU fails the test when
$CI is set and skips it otherwise. Times (wine prefix creation, each run) go to target/fmu-report.txt.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

from c_host_util import (CYCLES, N_STEPS, THREADS, compile_host, first_difference, fmi3_summary_problems,
                         host_failure, parse_summary, read_trajectory, run_host)
from fmu_util import missing_tool

K_SAVE = 50  # t = 0.5 s: mid-turn, the integrator's history full, the law still varying
# host --fmi3 on the emulated platforms: fewer cycles and threads than FMI 2.0's runs (the same C code
# runs them; every kind of cycle is still made) to keep the added time small.
FMI3_CYCLES = 100
FMI3_THREADS = 4

# Measured on this machine (2 shared cores, other jobs running): native scene 0.02 s (process
# included); wine prefix creation 19-28 s; full checks 3 s under wine (mostly wine's start-up) and
# 4 s under qemu (the scene 0.3 s, 40x native); a resumed scene 3.5 s (wine) and 0.5 s (qemu).
# The limits leave a margin of 100x and more for a loaded machine.
NATIVE_TIMEOUT = 120
WINE_PREFIX_TIMEOUT = 300
WINE_TIMEOUT = 600
QEMU_TIMEOUT = 900

QEMU_LD_PREFIX = Path("/usr/aarch64-linux-gnu")

# What host.exe may import: Windows' own DLLs, nothing of the mingw runtime (libwinpthread-1.dll,
# libgcc_s_seh-1.dll), which a Windows machine does not have.
HOST_EXE_IMPORTS = {"kernel32.dll", "msvcrt.dll"}
MINGW_RUNTIME_DLLS = {"libwinpthread-1.dll", "libgcc_s_seh-1.dll", "libstdc++-6.dll"}


@dataclass
class Platform:
    """A compiled host and how to run it on this machine."""

    name: str  # the FMI platform tuple of binaries/<name>/
    exe: Path
    timeout: float
    prefix: list = field(default_factory=list)  # the emulator's command line, [] natively
    env: dict | None = None
    windows: bool = False

    def path(self, p: Path) -> str:
        """A path of this machine as the host sees it: wine maps Z: to /."""
        p = Path(p).resolve()
        return "Z:" + str(p).replace("/", "\\") if self.windows else str(p)

    def run(self, unzipdir: Path, *args):
        """Runs the host; Path arguments are translated. Returns (process, seconds)."""
        cmd = [*self.prefix, self.exe, self.path(unzipdir),
               *(self.path(a) if isinstance(a, Path) else str(a) for a in args)]
        return run_host(cmd, self.timeout, env=self.env)


def library(fmu_unzipdir: Path, platform: str) -> Path:
    ext = {"win64": "dll", "darwin64": "dylib"}.get(platform, "so")
    lib = fmu_unzipdir / "binaries" / platform / f"BeamBody.{ext}"
    if not lib.is_file():
        missing_tool(f"the FMU has no {lib.relative_to(fmu_unzipdir)} (build it with the cross binaries)")
    return lib


#: The FMI 3.0 archive's folder (platform tuple) of each platform here.
FMI3_TUPLES = {"linux64": "x86_64-linux", "win64": "x86_64-windows", "aarch64-linux": "aarch64-linux"}


def library3(fmu3_unzipdir: Path, platform: str) -> Path:
    """The FMI 3.0 archive's library for `platform` (FMI 2.0's name): missing fails on CI, else skips."""
    ext = {"win64": "dll"}.get(platform, "so")
    lib = fmu3_unzipdir / "binaries" / FMI3_TUPLES[platform] / f"BeamBody.{ext}"
    if not lib.is_file():
        missing_tool(f"the FMI 3.0 FMU has no {lib.relative_to(fmu3_unzipdir)} "
                     "(build it with `cargo xtask fmu --all-platforms`)")
    return lib


def tool(name: str, hint: str, fallbacks=()) -> str:
    for candidate in (name, *fallbacks):
        path = shutil.which(candidate) or (candidate if os.access(candidate, os.X_OK) else None)
        if path:
            return path
    missing_tool(f"`{name}` is not installed ({hint})")


# --------------------------------------------------------------------------------------------------
# the three platforms
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def linux64(host_exe, fmu_unzipdir) -> Platform:
    library(fmu_unzipdir, "linux64")
    return Platform("linux64", host_exe, NATIVE_TIMEOUT)


@pytest.fixture(scope="module")
def wine_env(tmp_path_factory, fmu_report):
    """A fresh private WINEPREFIX (64-bit), created once with wineboot and timed; its wineserver is
    stopped at the end."""
    wine = tool("wine64", "apt-get install wine64", fallbacks=("/usr/lib/wine/wine64", "wine"))
    wineserver = tool("wineserver", "apt-get install wine64")
    prefix = tmp_path_factory.mktemp("wineprefix") / "pfx"
    env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}  # no window, no dialog
    env.update(WINEPREFIX=str(prefix), WINEARCH="win64", WINEDEBUG="-all",
               # no prompt to install wine-mono (.NET) or wine-gecko (HTML) into the prefix
               WINEDLLOVERRIDES="mscoree,mshtml=")
    try:
        t0 = time.perf_counter()
        proc = subprocess.run([wine, "wineboot", "--init"], env=env, capture_output=True, text=True,
                              timeout=WINE_PREFIX_TIMEOUT)
        # wineboot returns before the prefix is written out: wait for the wineserver to finish
        subprocess.run([wineserver, "--wait"], env=env, capture_output=True, timeout=WINE_PREFIX_TIMEOUT)
        seconds = time.perf_counter() - t0
        assert proc.returncode == 0 and (prefix / "drive_c" / "windows" / "system32").is_dir(), (
            f"wineboot --init exited with {proc.returncode}:\n{proc.stderr[-3000:]}"
        )
        assert (prefix / "dosdevices" / "z:").is_symlink(), "the prefix has no Z: drive for /"
        fmu_report.figure("c_host win64", "wine_prefix_seconds", seconds, f"wineboot --init, {wine}")
        yield wine, env, prefix
    finally:
        # this prefix's wineserver only (it would otherwise linger a few seconds after the tests)
        subprocess.run([wineserver, "--kill"], env=env, capture_output=True, timeout=60)


@pytest.fixture(scope="module")
def win64(request, fmu_unzipdir, tmp_path_factory) -> Platform:
    library(fmu_unzipdir, "win64")
    cc = tool("x86_64-w64-mingw32-gcc", "apt-get install gcc-mingw-w64-x86-64")
    exe = compile_host(cc, tmp_path_factory.mktemp("c_host_win64") / "host.exe", libs=["-lm"])
    wine, env, _ = request.getfixturevalue("wine_env")  # only once there is something to run
    return Platform("win64", exe, WINE_TIMEOUT, prefix=[wine], env=env, windows=True)


@pytest.fixture(scope="module")
def aarch64_linux(fmu_unzipdir, tmp_path_factory) -> Platform:
    library(fmu_unzipdir, "aarch64-linux")
    cc = tool("aarch64-linux-gnu-gcc", "apt-get install gcc-aarch64-linux-gnu")
    qemu = tool("qemu-aarch64", "apt-get install qemu-user")
    if not (QEMU_LD_PREFIX / "lib" / "ld-linux-aarch64.so.1").exists():
        missing_tool(f"no aarch64 C library under {QEMU_LD_PREFIX} (apt-get install libc6-arm64-cross)")
    exe = compile_host(cc, tmp_path_factory.mktemp("c_host_aarch64") / "host", flags=["-pthread"],
                       libs=["-ldl", "-lm"])
    env = dict(os.environ, QEMU_LD_PREFIX=str(QEMU_LD_PREFIX))
    return Platform("aarch64-linux", exe, QEMU_TIMEOUT, prefix=[qemu, "-L", str(QEMU_LD_PREFIX)], env=env)


PLATFORMS = ("linux64", "win64", "aarch64-linux")
EMULATED = ("win64", "aarch64-linux")


def get_platform(request, name: str) -> Platform:
    return request.getfixturevalue(name.replace("-", "_"))


# --------------------------------------------------------------------------------------------------
# the runs, each made once per module
# --------------------------------------------------------------------------------------------------


@dataclass
class Run:
    proc: subprocess.CompletedProcess
    seconds: float
    traj: Path
    state: Path | None = None

    def passed(self) -> bool:
        return self.proc.returncode == 0 and "host result=PASS" in self.proc.stdout

    def require(self, what: str):
        if not self.passed():
            pytest.fail(f"{what} failed\n{host_failure(self.proc, self.seconds)}", pytrace=False)
        return self


class Runs:
    """Memoized host runs; the FMU state files and trajectories go to one tmp directory."""

    def __init__(self, tmp: Path, fmu_unzipdir: Path):
        self.tmp, self.unzipdir, self.memo = tmp, fmu_unzipdir, {}

    def _once(self, key, make):
        if key not in self.memo:
            self.memo[key] = make()
        return self.memo[key]

    def reference(self, request) -> Run:
        """Native, the scene only, no FMU state saved: the uninterrupted run."""
        def make():
            p, traj = get_platform(request, "linux64"), self.tmp / "linux64-reference.csv"
            return Run(*p.run(self.unzipdir, "--cycles", 0, "--threads", 0, "-o", traj), traj)
        return self._once("reference", make)

    def main(self, request, name: str) -> Run:
        """The scene saving the state after step K_SAVE; on the emulated platforms with the full
        cycles and threads checks (natively test_c_host.py runs those)."""
        def make():
            p = get_platform(request, name)
            traj, state = self.tmp / f"{name}.csv", self.tmp / f"{name}-state-{K_SAVE}.bin"
            counts = [0, 0] if name == "linux64" else [CYCLES, THREADS]
            proc, seconds = p.run(self.unzipdir, "--cycles", counts[0], "--threads", counts[1],
                                  "--save-state", K_SAVE, state, "-o", traj, "--me-out", me_trajectory(traj))
            return Run(proc, seconds, traj, state)
        return self._once(("main", name), make)

    def fmi3(self, request, name: str, fmu3_unzipdir: Path) -> Run:
        """host --fmi3 on the FMI 3.0 archive's library for `name`: checks 1-6 (FMI3_CYCLES cycles and
        FMI3_THREADS threads), the scene's and Model Exchange's trajectories written."""
        def make():
            library3(fmu3_unzipdir, name)
            p, traj = get_platform(request, name), self.tmp / f"{name}-fmi3.csv"
            proc, seconds = p.run(fmu3_unzipdir, "--fmi3", "--cycles", FMI3_CYCLES, "--threads", FMI3_THREADS,
                                  "-o", traj, "--me-out", me_trajectory(traj))
            return Run(proc, seconds, traj)
        return self._once(("fmi3", name), make)

    def resume(self, request, src: str, dst: str) -> Run:
        """The state saved on `src`, restored on `dst`, the scene continued to its end."""
        def make():
            state = self.main(request, src).require(f"the {src} run that saves the state").state
            p, traj = get_platform(request, dst), self.tmp / f"resume-{src}-on-{dst}.csv"
            return Run(*p.run(self.unzipdir, "--cycles", 0, "--threads", 0, "--resume", state, "-o", traj),
                       traj)
        return self._once(("resume", src, dst), make)


@pytest.fixture(scope="module")
def runs(tmp_path_factory, fmu_unzipdir) -> Runs:
    return Runs(tmp_path_factory.mktemp("c_host_platforms"), fmu_unzipdir)


def me_trajectory(traj: Path) -> Path:
    """Where a main run writes its Model Exchange trajectory (host.c's check 4, --me-out)."""
    return traj.with_name(traj.stem + "-me.csv")


# --------------------------------------------------------------------------------------------------
# the emulated platforms pass the host's checks
# --------------------------------------------------------------------------------------------------


def test_host_exe_needs_no_mingw_runtime(win64, fmu_unzipdir, wine_env, fmu_report):
    """host.exe imports only Windows' own DLLs; the FMU's DLL imports nothing that is not in a
    plain Windows (here: the fresh wine prefix's system32), in particular no mingw runtime DLL."""
    objdump = tool("x86_64-w64-mingw32-objdump", "apt-get install binutils-mingw-w64-x86-64")

    def imports(path: Path) -> set[str]:
        out = subprocess.run([objdump, "-p", str(path)], capture_output=True, text=True, check=True).stdout
        return {l.split(":", 1)[1].strip().lower() for l in out.splitlines() if "DLL Name:" in l}

    exe_imports = imports(win64.exe)
    assert exe_imports <= HOST_EXE_IMPORTS, f"host.exe imports {sorted(exe_imports - HOST_EXE_IMPORTS)}"
    dll = library(fmu_unzipdir, "win64")
    dll_imports = imports(dll)
    fmu_report.note("c_host win64", f"BeamBody.dll imports {', '.join(sorted(dll_imports))}")
    system32 = {p.name.lower() for p in (wine_env[2] / "drive_c" / "windows" / "system32").iterdir()}
    assert not dll_imports & MINGW_RUNTIME_DLLS, f"BeamBody.dll needs {sorted(dll_imports & MINGW_RUNTIME_DLLS)}"
    # api-ms-win-*: API sets, which the loader maps to system DLLs (no file of that name needed)
    unknown = {d for d in dll_imports - system32 if not d.startswith(("api-ms-win-", "ext-ms-win-"))}
    assert not unknown, f"BeamBody.dll imports DLLs wine does not have: {sorted(unknown)}"


@pytest.mark.parametrize("name", EMULATED)
def test_host_passes_emulated(request, runs, name, fmu_report):
    """The paper's scene, 1000 instantiate/free cycles and 8 threads bit-identical to the serial runs,
    under wine (win64) or qemu (aarch64-linux)."""
    run = runs.main(request, name).require(f"the host on {name}")
    s = parse_summary(run.proc.stdout)
    assert int(s["scene"]["points"]) == N_STEPS + 1
    assert int(s["cycles"]["n"]) == CYCLES
    assert (s["threads"]["n"], s["threads"]["identical"], s["threads"]["distinct"]) == (
        str(THREADS), "1", str(THREADS)
    ), run.proc.stdout
    assert int(s["save_state"]["step"]) == K_SAVE and run.state.stat().st_size == int(s["save_state"]["bytes"])
    assert (s["exchange"]["points"], s["exchange"]["events"], s["exchange"]["restored"]) == (
        str(N_STEPS + 1), "1", "identical"
    ), run.proc.stdout
    tag = f"c_host {name}"
    how = "wine64" if name == "win64" else "qemu-aarch64"
    fmu_report.figure(tag, "wall_seconds", run.seconds,
                      f"under {how}: scene + {CYCLES} cycles + {THREADS} threads, compile excluded")
    fmu_report.figure(tag, "scene_seconds", float(s["scene"]["seconds"]))
    fmu_report.figure(tag, "cycles_seconds", float(s["cycles"]["seconds"]), f"{s['cycles']['messages']} log messages")
    fmu_report.figure(tag, "threads_sequential_seconds", float(s["threads"]["sequential_seconds"]))
    fmu_report.figure(tag, "threads_parallel_seconds", float(s["threads"]["parallel_seconds"]))
    fmu_report.note(tag, f"final v1 = {s['scene_final']['v1']}, fingerprint {s['scene']['fingerprint']}")


# --------------------------------------------------------------------------------------------------
# bit-identity
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", PLATFORMS)
def test_trajectory_bit_identical(request, runs, name, fmu_report):
    """The scene on `name` (saving a state at K_SAVE on the way) against the native uninterrupted run."""
    ref_run = runs.reference(request).require("the native reference run")
    run = runs.main(request, name).require(f"the host on {name}")
    ref, traj = read_trajectory(ref_run.traj), read_trajectory(run.traj)
    assert len(traj["t"]) == N_STEPS + 1
    where = first_difference(traj, ref)
    fmu_report.figure(f"c_host {name} vs linux64", "trajectory_identical", int(where is None),
                      f"v1, theta1, u2 at {N_STEPS + 1} points, bit for bit" + (f": {where}" if where else ""))
    if name == "linux64":
        fmu_report.figure("c_host linux64", "scene_save_state_seconds", run.seconds,
                          f"scene only, state saved at step {K_SAVE}")
        fmu_report.figure("c_host linux64", "scene_seconds", ref_run.seconds, "scene only")
    assert where is None, f"{name} vs linux64: {where}"


@pytest.mark.parametrize("name", EMULATED)
def test_model_exchange_bit_identical(request, runs, name, fmu_report):
    """The host's RK4 on the Model Exchange equations (check 4) on `name` against linux64: the same
    bits at every communication point, through the law's event."""
    ref = read_trajectory(me_trajectory(runs.main(request, "linux64").require("the native run").traj))
    mine = read_trajectory(me_trajectory(runs.main(request, name).require(f"the host on {name}").traj))
    where = first_difference(mine, ref)
    fmu_report.figure(f"c_host {name} vs linux64", "model_exchange_identical", int(where is None),
                      f"RK4 on Model Exchange, {N_STEPS + 1} points" + (f": {where}" if where else ""))
    assert where is None, f"Model Exchange on {name} vs linux64: {where}"


@pytest.mark.parametrize("name", EMULATED)
def test_state_bytes_identical(request, runs, name, fmu_report):
    """The serialized FMU state after step K_SAVE: the same bytes on `name` as natively."""
    ref = runs.main(request, "linux64").require("the native run").state.read_bytes()
    mine = runs.main(request, name).require(f"the host on {name}").state.read_bytes()
    same = mine == ref
    detail = f"{len(ref)} bytes at step {K_SAVE}"
    if not same:
        k = next((i for i, (a, b) in enumerate(zip(mine, ref)) if a != b), min(len(mine), len(ref)))
        detail += f"; {name} has {len(mine)} bytes, the first difference at offset {k}"
    fmu_report.figure(f"c_host {name} vs linux64", "state_bytes_identical", int(same), detail)
    assert same, f"the serialized state differs: {detail}"


@pytest.mark.parametrize("src", PLATFORMS)
@pytest.mark.parametrize("dst", PLATFORMS)
def test_cross_restore(request, runs, src, dst, fmu_report):
    """The state saved on `src` after step K_SAVE, restored on `dst`: the continuation equals the
    uninterrupted native run from step K_SAVE on, bit for bit."""
    ref = read_trajectory(runs.reference(request).require("the native reference run").traj)
    run = runs.resume(request, src, dst).require(f"resuming the {src} state on {dst}")
    s = parse_summary(run.proc.stdout)
    assert int(s["resume"]["step"]) == K_SAVE, run.proc.stdout
    cont = read_trajectory(run.traj)
    assert len(cont["t"]) == N_STEPS + 1 - K_SAVE
    assert np.array_equal(cont["t"], ref["t"][K_SAVE:])
    where = first_difference(cont, {k: v[K_SAVE:] for k, v in ref.items()}, offset=K_SAVE)
    fmu_report.figure(f"c_host resume {src} -> {dst}", "continuation_identical", int(where is None),
                      f"{run.seconds:.1f} s, steps {K_SAVE}..{N_STEPS}" + (f": {where}" if where else ""))
    assert where is None, f"{src} state resumed on {dst}: {where}"


# --------------------------------------------------------------------------------------------------
# FMI 3.0: the FMI 3.0 archive's libraries under the same host (--fmi3)
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", EMULATED)
def test_fmi3_host_passes_emulated(request, runs, fmu3_unzipdir, name, fmu_report):
    """host --fmi3 under wine (binaries/x86_64-windows/BeamBody.dll) or qemu
    (binaries/aarch64-linux/BeamBody.so): checks 1-4 through FMI 3.0, the intermediate-update callback
    (the rule's count, v1 near the law's with this platform's sin) and the refusals of misuse."""
    run = runs.fmi3(request, name, fmu3_unzipdir).require(f"the FMI 3.0 host on {name}")
    s = parse_summary(run.proc.stdout)
    problems = fmi3_summary_problems(s, FMI3_CYCLES, FMI3_THREADS)
    tag = f"c_host fmi3 {name}"
    how = "wine64" if name == "win64" else "qemu-aarch64"
    fmu_report.figure(tag, "wall_seconds", run.seconds,
                      f"under {how}: checks 1-6, {FMI3_CYCLES} cycles, {FMI3_THREADS} threads")
    fmu_report.figure(tag, "intermediate_max_dv1", float(s["intermediate"]["max_dv1"]),
                      f"{s['intermediate']['callbacks']} callbacks, the host's sin")
    assert not problems, "\n".join(problems) + "\n" + run.proc.stdout[-3000:]


@pytest.mark.parametrize("name", EMULATED)
def test_fmi3_trajectories_bit_identical(request, runs, fmu3_unzipdir, name, fmu_report):
    """The FMI 3.0 scene and Model Exchange on `name` against the native FMI 2.0 runs, bit for bit: one
    core under both APIs, the same numbers on every platform. Check 5's final v1 against the native
    --fmi3 run's is reported (phi comes from each platform's sin there)."""
    ref = read_trajectory(runs.reference(request).require("the native reference run").traj)
    ref_me = read_trajectory(me_trajectory(runs.main(request, "linux64").require("the native run").traj))
    run = runs.fmi3(request, name, fmu3_unzipdir).require(f"the FMI 3.0 host on {name}")
    where = first_difference(read_trajectory(run.traj), ref)
    where_me = first_difference(read_trajectory(me_trajectory(run.traj)), ref_me)
    tag = f"c_host fmi3 {name} vs fmi2 linux64"
    fmu_report.figure(tag, "trajectory_identical", int(where is None),
                      f"v1, theta1, u2 at {N_STEPS + 1} points, bit for bit" + (f": {where}" if where else ""))
    fmu_report.figure(tag, "model_exchange_identical", int(where_me is None),
                      f"RK4 on Model Exchange, {N_STEPS + 1} points" + (f": {where_me}" if where_me else ""))
    native = runs.fmi3(request, "linux64", fmu3_unzipdir).require("the native FMI 3.0 host")
    v1 = {r: float(parse_summary(x.proc.stdout)["intermediate_final"]["v1"]) for r, x in (("native", native), (name, run))}
    fmu_report.figure(f"c_host fmi3 {name} vs linux64", "intermediate_final_dv1", abs(v1[name] - v1["native"]),
                      "check 5's v1 at 1.7 s: phi from each platform's sin")
    assert where is None, f"FMI 3.0 scene on {name} vs FMI 2.0 on linux64: {where}"
    assert where_me is None, f"FMI 3.0 Model Exchange on {name} vs FMI 2.0 on linux64: {where_me}"
