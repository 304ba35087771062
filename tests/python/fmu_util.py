"""Helpers for the FMU tests (tests/python/fmu/test_fmu_*.py).

- the FMU's path ($BEAM_BODY_FMU, else target/fmu/BeamBody.fmu), and the FMI 3.0 FMU's
  ($BEAM_BODY_FMU_FMI3, else target/fmu/BeamBody-fmi3.fmu);
- the paper's law phi(t), evaluated with the same formula and operation order as the Rust model
  (src/model/phi.rs, PhiPiece::Turn / Hold), so that samples are bit-identical to the CLI's;
- CLI runs (`beam-body simulate scenes/paper.toml --set ...`), cached per session;
- `Slave`: a thin wrapper of fmpy.fmi2.FMU2Slave with a logger that collects the FMU's messages;
- `Slave3`: the same over fmpy.fmi3.FMU3Slave for the FMI 3.0 archive (and `replay3`);
- for hosts written by others (test_fmu_libcosim.py, test_fmu_ecos.py): a copy of the FMU that traces
  every FMI call the host makes (`traced_fmu`, tests/python/trace_shim.c), a reader of that trace, and
  `replay`, FMPy making the calls a host made;
- the measured-figure report, target/fmu-report.txt (appended, one block per session).
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import time
import zipfile
from ctypes import byref
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
TARGET = REPO / "target"
FMU_REPORT_FILE = TARGET / "fmu-report.txt"
MODEL_DESCRIPTION_XML = REPO / "modelDescription" / "modelDescription.xml"
MODEL_DESCRIPTION3_XML = REPO / "modelDescription" / "fmi3" / "modelDescription.xml"
PAPER_SCENE = REPO / "scenes" / "paper.toml"

STATES = ("v1", "theta1", "u2")
OUTPUTS = ("v1", "theta1", "u2", "dv1", "dtheta1", "du2", "N", "P", "M", "drift", "energy",
           "phi_applied", "dphi_applied", "ddphi_applied")

# The paper's scene (scenes/paper.toml and the FMU's DefaultExperiment).
T_ROT = 0.85
PHI_END = math.pi
T_END = 10.2
H0 = 0.0085

# Enumerations of the modelDescription (src/fmu/variables.rs).
FORMULATION_ENUM = {"reduced": 1, "dae": 2, "dae_stabilized": 3, "linear": 4}
PHI_SOURCE_LAW = 2  # phi_source: 1 = input (the default), 2 = law

# fmi2StatusKind
FMI2_LAST_SUCCESSFUL_TIME = 2
FMI2_TERMINATED = 3


def fmu_path() -> Path:
    env = os.environ.get("BEAM_BODY_FMU")
    return Path(env) if env else TARGET / "fmu" / "BeamBody.fmu"


def fmu3_path() -> Path:
    env = os.environ.get("BEAM_BODY_FMU_FMI3")
    return Path(env) if env else TARGET / "fmu" / "BeamBody-fmi3.fmu"


# --------------------------------------------------------------------------------------------------
# the law
# --------------------------------------------------------------------------------------------------


def law(t: float, t_rot: float = T_ROT, phi_end: float = PHI_END, phi0: float = 0.0):
    """(phi, dphi, ddphi) of the paper's law at t: phi0 + phi_end*sin^2(pi t/(2 t_rot)) for t < t_rot,
    phi0 + phi_end after (the piece that starts at t, as PaperLaw::piece_from). Same expression as the
    Rust code (0.5*phi_end*(1 - cos(w t)), w = pi/t_rot), but with this platform's sin/cos (Python's
    math: glibc here), while the model uses its own (src/math.rs, the libm crate): the two agree to an
    ulp or two, not always bit for bit. Where a test needs the model's own bits, use cli_law."""
    t = float(t)
    if t < t_rot:
        w = math.pi / t_rot
        s, c = math.sin(w * t), math.cos(w * t)
        return (phi0 + 0.5 * phi_end * (1.0 - c), 0.5 * phi_end * w * s, 0.5 * phi_end * w * w * c)
    return (phi0 + phi_end, 0.0, 0.0)


def law_sin2(t: np.ndarray) -> np.ndarray:
    """The law as the paper writes it, pi*sin^2(pi t/(2*0.85)) for t <= 0.85, then pi (a check of law())."""
    t = np.asarray(t, dtype=float)
    return np.where(t <= T_ROT, math.pi * np.sin(math.pi * t / (2 * T_ROT)) ** 2, math.pi)


def comm_grid(h: float, t_end: float = T_END) -> np.ndarray:
    """The communication points k*h, k = 0..n, exactly as FMPy's simulate_fmu computes them
    (start + k*h) and as the CLI's grid does (k*step), with n = round(t_end/h)."""
    n = int(round(t_end / h))
    assert abs(n * h - t_end) <= 1e-9 * t_end, f"{t_end} is not a multiple of {h}"
    return np.arange(n + 1, dtype=float) * h


def law_table(h: float, t_end: float = T_END, phi_fn=law) -> np.ndarray:
    """The input table for simulate_fmu: ('time', 'phi') exactly on the communication grid, so FMPy's
    linear interpolation returns the sample itself at every communication point."""
    t = comm_grid(h, t_end)
    phi = np.array([phi_fn(x)[0] for x in t])
    return np.array(list(zip(t, phi)), dtype=[("time", np.float64), ("phi", np.float64)])


# --------------------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------------------


_CLI_CACHE: dict = {}


def cli(binary: Path, **sets) -> dict:
    """`beam-body simulate scenes/paper.toml --set k=v ...` as columns; memoised per session."""
    from conftest import read_csv, run_cli  # the CLI runner: a non-zero exit fails the test

    key = tuple(sorted((k, str(v)) for k, v in sets.items()))
    if key not in _CLI_CACHE:
        args = ["simulate", str(PAPER_SCENE)]
        for k, v in sets.items():
            args += ["--set", f"{k}={v!r}" if isinstance(v, float) else f"{k}={v}"]
        _CLI_CACHE[key] = read_csv(run_cli(binary, args))
    return _CLI_CACHE[key]


def cli_law(binary: Path, h: float):
    """The law exactly as the model evaluates it (its own sin and cos), sampled by the CLI on the grid
    k*h: a function of those times only, (phi, dphi, ddphi) at t = k*h. The CLI's CSV round-trips every
    value, and its host feed (phi_source = input, with or without input_derivatives) sample the same law at the same points. From
    t_rot on, the law is the hold piece (phi_end, 0, 0) (the piece that starts at t, as law()), with no
    sine to evaluate; an output row at exactly t_rot shows the turn's one-sided values instead."""
    c = cli(binary, dt_out=h)
    rows = np.c_[c["phi_applied"], c["dphi_applied"], c["ddphi_applied"]]

    def at(t: float):
        k = int(round(t / h))
        assert abs(k * h - t) <= 1e-12 * max(1.0, t), f"t = {t} is not on the grid k*{h}"
        if t >= T_ROT:
            return (PHI_END, 0.0, 0.0)
        return tuple(float(x) for x in rows[k])

    return at


# --------------------------------------------------------------------------------------------------
# FMU2Slave
# --------------------------------------------------------------------------------------------------

# FMPy's logger proxy (fmpy/logging, native/src/logging/logging.c in FMPy's sources) formats the FMU's
# printf-style message in C and forwards it to ONE process-global Python logger, `static s_logger`, which
# every addLoggerProxy() call replaces, for every callbacks struct (FMPy's defaultCallbacks included).
# If that Python callback is garbage-collected (simulate_fmu(logger=...) drops its own when it returns),
# the next message any FMU logs jumps to freed memory: a segfault. So the tests point s_logger at one
# permanent dispatcher, which routes messages by instance name, and re-install it after every
# simulate_fmu(logger=...) (install_logger_proxy).
_ROUTES: dict[str, list] = {}
UNROUTED: list = []


def _dispatch(env, instance_name, status, category, message):
    name = (instance_name or b"").decode("utf-8", "replace")
    record = (
        name,
        int(status),
        (category or b"").decode("utf-8", "replace"),
        (message or b"").decode("utf-8", "replace"),
    )
    sink = _ROUTES.get(name)
    if sink is not None:
        sink.append(record)
    else:
        UNROUTED.append(record)
        print(f"[status {record[1]}] {name}: {record[3]}")


_PERMANENT_LOGGER = None


def _permanent_logger():
    global _PERMANENT_LOGGER
    if _PERMANENT_LOGGER is None:
        from fmpy.fmi2 import fmi2CallbackLoggerTYPE

        _PERMANENT_LOGGER = fmi2CallbackLoggerTYPE(_dispatch)  # module global: never freed
    return _PERMANENT_LOGGER


def install_logger_proxy():
    """Points FMPy's global logger proxy at the permanent dispatcher (see above)."""
    from fmpy.fmi2 import fmi2CallbackFunctions
    from fmpy.logging import addLoggerProxy

    cb = fmi2CallbackFunctions()
    cb.logger = _permanent_logger()
    addLoggerProxy(byref(cb))


class Slave:
    """An instance of the FMU through fmpy.fmi2.FMU2Slave. Its log messages
    (instanceName, status, category, message) are collected in `messages` (routed by instance name,
    which must be unique among live instances)."""

    def __init__(self, unzipdir, model_description, name="instance", logging_on=False):
        from fmpy import calloc, free
        from fmpy.fmi2 import (
            FMU2Slave,
            fmi2CallbackAllocateMemoryTYPE,
            fmi2CallbackFreeMemoryTYPE,
            fmi2CallbackFunctions,
        )
        from fmpy.logging import addLoggerProxy

        assert name not in _ROUTES, f"instance name {name!r} is in use"
        self.name = name
        self.md = model_description
        self.vr = {v.name: v.valueReference for v in model_description.modelVariables}
        self.messages: list[tuple[str, int, str, str]] = []
        _ROUTES[name] = self.messages

        cb = fmi2CallbackFunctions()
        cb.logger = _permanent_logger()
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(cb))  # s_logger = the dispatcher; cb.logger = the C proxy
        self._callbacks = cb  # the FMU keeps a pointer to it: keep it alive
        self.freed = False
        self.fmu = FMU2Slave(
            guid=model_description.guid,
            unzipDirectory=str(unzipdir),
            modelIdentifier=model_description.coSimulation.modelIdentifier,
            instanceName=name,
        )
        try:
            self.fmu.instantiate(callbacks=cb, loggingOn=logging_on)
        except Exception:
            del _ROUTES[name]
            raise

    # -- set-up ------------------------------------------------------------------------------------

    def start(self, tolerance=None, start_time=0.0, stop_time=None, integers=None, reals=None, phi0=None):
        """setupExperiment, parameters, enterInitializationMode, (phi), exitInitializationMode."""
        f = self.fmu
        f.setupExperiment(tolerance=tolerance, startTime=start_time, stopTime=stop_time)
        for name, value in (integers or {}).items():
            f.setInteger([self.vr[name]], [int(value)])
        for name, value in (reals or {}).items():
            f.setReal([self.vr[name]], [float(value)])
        f.enterInitializationMode()
        if phi0 is not None:
            f.setReal([self.vr["phi"]], [float(phi0)])
        f.exitInitializationMode()
        return self

    # -- stepping ----------------------------------------------------------------------------------

    def get(self, names=OUTPUTS) -> list[float]:
        return self.fmu.getReal([self.vr[n] for n in names])

    def step_input(self, tc, h, phi, dphi=None, ddphi=None):
        """setReal(phi) [+ setRealInputDerivatives orders 1 and 2], doStep(tc, h)."""
        f, vr = self.fmu, self.vr["phi"]
        f.setReal([vr], [phi])
        if dphi is not None:
            f.setRealInputDerivatives([vr], [1], [dphi])
        if ddphi is not None:
            f.setRealInputDerivatives([vr], [2], [ddphi])
        f.doStep(tc, h)

    def free(self):
        if not self.freed:
            self.freed = True
            try:
                self.fmu.freeInstance()
            finally:
                if _ROUTES.get(self.name) is self.messages:
                    del _ROUTES[self.name]

    def errors(self, min_status=2):
        return [m for m in self.messages if m[1] >= min_status]


def run_derivatives(slave: Slave, times, names=OUTPUTS, phi_fn=law) -> np.ndarray:
    """Steps an input-mode instance sending phi, phi', phi'' of phi_fn at each tc."""
    out = []
    for a, b in zip(times[:-1], times[1:]):
        p, dp, ddp = phi_fn(a)
        slave.step_input(a, b - a, p, dp, ddp)
        out.append(slave.get(names))
    return np.array(out)


def run_values(slave: Slave, steps, names=STATES) -> np.ndarray:
    """Steps an input-mode instance through `steps`, (tc, h, phi) each: setReal(phi), doStep(tc, h),
    getReal(names) after the step. One row per step."""
    out = []
    for tc, h, phi in steps:
        slave.step_input(tc, h, phi)
        out.append(slave.get(names))
    return np.array(out)


def replay(unzipdir, model_description, steps, name, names=STATES):
    """A fresh FMU2Slave (Slave) through `steps` as run_values does, after setupExperiment with neither
    tolerance nor stop time (what libcosim and Ecos send) and no parameter set: (rows, wall seconds of
    the steps)."""
    s = Slave(unzipdir, model_description, name=name)
    try:
        s.start(tolerance=None, stop_time=None)
        start = time.perf_counter()
        rows = run_values(s, steps, names)
        return rows, time.perf_counter() - start
    finally:
        s.free()


def assert_host_matches_fmpy(host: str, run: dict, steps, unzipdir, model_description, report,
                             rtol: float, k_grid: float):
    """A host's run of the paper's scene with phi as an input ({'t', 'y', 'wall'}, y: STATES after
    each step) against FMPy's FMU2Slave replaying the host's own `steps` (tc, h, phi): bit for bit;
    and against FMPy on the plain grid (tc = k*H0, h = H0), for scale: within k_grid*rtol*max|y| per
    state (the global error of the tolerance; a different tc changes the step sequence)."""
    n = len(steps)
    assert np.allclose(run["t"], H0 * np.arange(1, n + 1), rtol=0, atol=1e-12), f"{host}'s time"
    assert np.all(np.isfinite(run["y"])) and np.max(np.abs(run["y"][:, 0])) > 0.1, f"{host}'s run did not move"
    y, wall_fmpy = replay(unzipdir, model_description, steps, f"{host}-fmpy")
    grid = [(k * H0, H0, law(k * H0)[0]) for k in range(n)]
    y_grid, _ = replay(unzipdir, model_description, grid, f"{host}-fmpy-grid")

    report.figure(host, "wall_s", run["wall"], f"{n} steps; FMPy's FMU2Slave: {wall_fmpy:.3f} s")
    for j, q in enumerate(STATES):
        d = float(np.max(np.abs(run["y"][:, j] - y[:, j])))
        scale = rtol * float(np.max(np.abs(y[:, j])))
        k = float(np.max(np.abs(run["y"][:, j] - y_grid[:, j]))) / scale
        comment = f"same calls; FMPy on tc = k*{H0}: {k * scale:.3e} = {k:.0f} rtol*max|y|"
        report.figure(host, f"max|{host}-FMPy| {q}", d, comment)
        assert d == 0.0, f"{q}: {host} and FMPy making the same calls differ by {d}"
        assert k <= k_grid, f"{q}: {host} vs FMPy on the plain grid differ by {k:.0f} rtol*max|y|"


# --------------------------------------------------------------------------------------------------
# FMU3Slave (the FMI 3.0 archive)
# --------------------------------------------------------------------------------------------------

# FMI 3.0's logger has no global proxy in FMPy (fmi3InstantiateCoSimulation takes the callback itself,
# and FMU3Slave keeps it alive), so each Slave3 collects its own messages.


class Slave3:
    """An instance of the FMI 3.0 FMU through fmpy.fmi3.FMU3Slave. Its log messages (status, category,
    message) are collected in `messages`. `intermediate_update`, a Python function with the signature of
    fmi3IntermediateUpdateCallback (instanceEnvironment, intermediateUpdateTime,
    intermediateVariableSetRequested, intermediateVariableGetAllowed, intermediateStepFinished,
    canReturnEarly, earlyReturnRequested*, earlyReturnTime*), and `required`, the names listed in
    requiredIntermediateVariables, go to fmi3InstantiateCoSimulation."""

    def __init__(self, unzipdir, model_description, name="instance", logging_on=False,
                 intermediate_update=None, required=(), event_mode_used=False):
        from fmpy.fmi3 import FMU3Slave

        self.name = name
        self.md = model_description
        self.vr = {v.name: v.valueReference for v in model_description.modelVariables}
        self.messages: list[tuple[int, str, str]] = []

        def log(_env, status, category, message):
            self.messages.append((int(status), (category or b"").decode("utf-8", "replace"),
                                  (message or b"").decode("utf-8", "replace")))

        self.freed = False
        self.fmu = FMU3Slave(
            guid=model_description.guid,
            unzipDirectory=str(unzipdir),
            modelIdentifier=model_description.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate(loggingOn=logging_on, eventModeUsed=event_mode_used, logMessage=log,
                             intermediateUpdate=intermediate_update,
                             requiredIntermediateVariables=[self.vr[n] for n in required] or None)

    def start(self, tolerance=None, start_time=0.0, stop_time=None, int64=None, reals=None, phi0=None):
        """Parameters (Int64 for the enumerations, Float64), enterInitializationMode (with the
        experiment's tolerance and times), (phi), exitInitializationMode."""
        f = self.fmu
        for name, value in (int64 or {}).items():
            f.setInt64([self.vr[name]], [int(value)])
        for name, value in (reals or {}).items():
            f.setFloat64([self.vr[name]], [float(value)])
        f.enterInitializationMode(tolerance=tolerance, startTime=start_time, stopTime=stop_time)
        if phi0 is not None:
            f.setFloat64([self.vr["phi"]], [float(phi0)])
        f.exitInitializationMode()
        return self

    def get(self, names=OUTPUTS) -> list[float]:
        return self.fmu.getFloat64([self.vr[n] for n in names])

    def step_input(self, tc, h, phi=None):
        """setFloat64(phi) (when given), doStep(tc, h): (eventHandlingNeeded, terminateSimulation,
        earlyReturn, lastSuccessfulTime)."""
        if phi is not None:
            self.fmu.setFloat64([self.vr["phi"]], [float(phi)])
        return self.fmu.doStep(tc, h)

    def free(self):
        if not self.freed:
            self.freed = True
            self.fmu.freeInstance()

    def errors(self, min_status=2):
        return [m for m in self.messages if m[0] >= min_status]


def replay3(unzipdir, model_description, steps, name, names=STATES):
    """replay() on the FMI 3.0 FMU: a fresh Slave3 through `steps` (tc, h, phi) after
    enterInitializationMode with neither tolerance nor stop time and no parameter set; the rows of
    `names` after each step."""
    s = Slave3(unzipdir, model_description, name=name)
    try:
        s.start(tolerance=None, stop_time=None)
        rows = []
        for tc, h, phi in steps:
            s.step_input(tc, h, phi)
            rows.append(s.get(names))
        assert not s.errors(), s.errors()
        return np.array(rows)
    finally:
        s.free()


# --------------------------------------------------------------------------------------------------
# hosts written by others: the calls they make
# --------------------------------------------------------------------------------------------------

TRACE_SHIM_C = REPO / "tests" / "python" / "trace_shim.c"
_TRACED = 0  # traced copies made in this process


def missing_tool(what: str):
    """A missing compiler, emulator, valgrind or host package fails the test on CI ($CI set) and
    skips it elsewhere."""
    import pytest

    if os.environ.get("CI"):
        pytest.fail(f"{what} (CI is set: this test must run there)", pytrace=False)
    pytest.skip(what)


def traced_fmu(fmu_file: Path, workdir: Path) -> Path:
    """A copy of the FMU, workdir/BeamBody.fmu, in which binaries/linux64/BeamBody.so is
    tests/python/trace_shim.c (compiled here with cc) in front of the real library, renamed
    BeamBody_real_<pid>_<n>.so. Any host that runs it writes the FMU's `logCalls` trace of every call
    to the file named by $BEAM_BODY_TRACE (read it with read_trace). Everything else is the real FMU."""
    import pytest

    if shutil.which("cc") is None:
        missing_tool("no C compiler: `cc` is not on PATH (needed for the call-tracing shim)")
    global _TRACED
    _TRACED += 1
    real = f"BeamBody_real_{os.getpid()}_{_TRACED}.so"  # unique: see trace_shim.c, REAL_LIBRARY
    unzipped = workdir / "traced"
    with zipfile.ZipFile(fmu_file) as z:
        z.extractall(unzipped)
    bindir = unzipped / "binaries" / "linux64"
    (bindir / "BeamBody.so").rename(bindir / real)
    cmd = ["cc", "-std=c11", "-O1", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC",
           f'-DREAL_LIBRARY="{real}"', "-o", str(bindir / "BeamBody.so"), str(TRACE_SHIM_C),
           f"-L{bindir}", "-Wl,--no-as-needed", f"-l:{real}", "-Wl,-rpath,$ORIGIN", "-ldl"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.fail(f"compiling the tracing shim failed:\n{' '.join(cmd)}\n{proc.stderr}", pytrace=False)
    out = workdir / "BeamBody.fmu"
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        for f in sorted(unzipped.rglob("*")):
            if f.is_file():
                z.write(f, f.relative_to(unzipped).as_posix())
    return out


@dataclass
class Call:
    """One line of a trace: the FMU's message about one call, `<function>: <text>`."""

    instance: str
    status: int
    category: str
    function: str
    text: str


def read_trace(path: Path) -> list[Call]:
    """The lines a traced FMU wrote (see trace_shim.c), as Calls."""
    calls = []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        instance, status, category, message = line.split("\t", 3)
        function, _, text = message.partition(": ")
        calls.append(Call(instance, int(status), category, function, text))
    return calls


_LISTED = re.compile(r"`(\w+)` \((\d+)\) = ([^,]+)")
_SETUP = re.compile(
    r"Setup \{ tolerance: (None|Some\((.+?)\)), start_time: (.+?), stop_time: (None|Some\((.+?)\)) \}"
)


def listed(call: Call) -> dict[str, str]:
    """The variables of a traced set or get call: {name: value as the FMU printed it}."""
    return {name: value for name, _vr, value in _LISTED.findall(call.text)}


def setup_of(call: Call):
    """(tolerance, startTime, stopTime) of a traced fmi2SetupExperiment; None where undefined."""
    m = _SETUP.fullmatch(call.text)
    assert m, f"unexpected fmi2SetupExperiment trace: {call.text!r}"
    tol, start, stop = m.group(2), m.group(3), m.group(5)
    return (None if tol is None else float(tol), float(start), None if stop is None else float(stop))


def steps_of(calls: list[Call]):
    """The traced steps, (tc, h, phi) each: fmi2DoStep's arguments and the value of the last
    fmi2SetReal of `phi` since the previous step (None if phi was not set). Rust prints each f64 as
    the shortest decimal that reads back to it, so these are the host's values bit for bit."""
    steps, phi = [], None
    for c in calls:
        if c.function == "fmi2SetReal" and "phi" in listed(c):
            phi = float(listed(c)["phi"])
        elif c.function == "fmi2DoStep":
            m = re.fullmatch(r"tc = (\S+), h = (\S+)", c.text)
            assert m, f"unexpected fmi2DoStep trace: {c.text!r}"
            steps.append((float(m.group(1)), float(m.group(2)), phi))
            phi = None
    return steps


# --------------------------------------------------------------------------------------------------
# report
# --------------------------------------------------------------------------------------------------


class Report:
    """target/fmu-report.txt: a '# session <time>' line, then one line per measured figure,
    `<test> <name> = <value> [<comment>]`, appended as soon as it is measured."""

    def __init__(self, path: Path = FMU_REPORT_FILE):
        self.path = path
        self.started = False

    def _write(self, line: str):
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with open(self.path, "a", encoding="utf-8") as fh:
            if not self.started:
                self.started = True
                fh.write(f"# session {time.strftime('%Y-%m-%d %H:%M:%S')} fmu={fmu_path()}\n")
            fh.write(line.rstrip("\n") + "\n")

    def figure(self, test: str, name: str, value, comment: str = ""):
        v = f"{value:.3e}" if isinstance(value, float) else str(value)
        line = f"{test} {name} = {v}" + (f"  # {comment}" if comment else "")
        print(line)
        self._write(line)

    def note(self, test: str, text: str):
        line = f"{test} # {text}"
        print(line)
        self._write(line)
