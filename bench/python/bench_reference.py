"""Reference solutions of the work-precision benchmark on the contract's output grid.

    python bench/python/bench_reference.py [--dir target/bench] [--scenes paper,stiff,...] [--force]
                                           [--budget-seconds 600] [--jobs N]

For each scene it writes <dir>/ref/<scene>.csv (same format as the sol/ files: t and the states on the
grid t_k = k·0.01 s) and <dir>/ref/<scene>.txt (the methods, their run times and their
disagreement), from two different methods that must agree far below the smallest error plotted.

Methods (the reduced equations of the test oracle, tests/python/oracle.py, integrated by
oracle.reference_solution: scipy.integrate.solve_ivp on [0, t_rot] and [t_rot, t_end] separately,
grid values from the methods' dense output):
* A, the values written: DOP853 (explicit Runge-Kutta 8(5,3)) at rtol 1e-13, atol 1e-15;
* B, the check: Radau IIA (implicit, order 5) at rtol 1e-12, atol 1e-14.
For the scene files in CLI_SECOND (scenes/stiff.toml, EI = 1e7: bending periods of 21 ms and 1.9 ms
over 10.2 s, about 5500 periods of the fast mode), Radau at rtol 1e-12 did not finish in 600 s
(measured), so B is the project's Rust CLI instead: `target/release/beam-body simulate <scene>
--set rtol=1e-14 --set dt_out=0.01`, its adaptive variable-order BDF at its tightest rtol (a different
method and a different implementation of the equations). Its own error dominates the disagreement
(measured on stiff against DOP853: 2.1e-6, 3.1e-7, 4.7e-8 at rtol 1e-12, 1e-13, 1e-14). The same
fallback to the CLI happens for any scene whose Radau run exceeds --budget-seconds.
Every scene also gets C, DOP853 at rtol 3e-14 (scipy's floor is 100·eps): the difference of A and C
bounds the error of the values written, A, where the A-B disagreement is dominated by B.

The DAE scenes (paper-dae, paper-dae-stabilized) have the SAME exact solution as the reduced model:
u2 = u1(v1, theta1) and du2 = d/dt u1 = -p·dv1 - l·q·dtheta1 (oracle.u1_and_rate). Their reference is
therefore the reduced reference of scenes/paper.toml with those two columns added; the drift of the
index-1 DAE away from the constraint is part of a DAE solver's error.

The disagreement is measured like the benchmark's error: per component, |y_A - y_B| divided by
max_k |y_A(t_k)|; the .txt gives its maximum and its RMS over the grid and the components.

The scipy runs are child processes, --jobs at a time (default: the number of cores), longest first.

Cache: a scene is skipped when its ref/<scene>.csv and .txt exist and ref/<scene>.stamp matches the
hash of its inputs (the scene file, this script, bench_common.py, oracle.py, the scipy and numpy
versions). The Rust binary is NOT part of the stamp (it changes with every build and is never the
values written, only a check); use --force to recompute.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import multiprocessing as mp
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_common as bc  # noqa: E402

METHOD_A = ("DOP853", 1e-13, 1e-15)
METHOD_B = ("Radau", 1e-12, 1e-14)
METHOD_C = ("DOP853", 3e-14, 3e-16)  # self-convergence check of A
CLI_RTOL = "1e-14"
#: scene files where B is the Rust CLI without trying Radau (measured: > 600 s at rtol 1e-12)
CLI_SECOND = {"scenes/stiff.toml"}
#: rough run times in s (measured on a 2-core Xeon) to start the longest jobs first
EXPECTED_S = {("scenes/stiff.toml", "A"): 135, ("scenes/stiff.toml", "C"): 115,
              ("scenes/paper.toml", "B"): 40, ("scenes/paper.toml", "C"): 3}

DESC = {
    "DOP853": "scipy DOP853 (explicit Runge-Kutta 8(5,3))",
    "Radau": "scipy Radau (Radau IIA, implicit, order 5)",
}


def scene_groups(scenes):
    """{scene file: [scenes]}: the DAE scenes share the reduced reference of their scene file."""
    groups: dict = {}
    for s in scenes:
        groups.setdefault(bc.SCENES[s][0], []).append(s)
    return groups


def stamp_of(scene: str) -> str:
    import scipy

    h = hashlib.sha256()
    for p in (bc.scene_file(scene), Path(__file__), Path(bc.__file__), bc.TESTS_PY / "oracle.py"):
        h.update(p.name.encode())
        h.update(Path(p).read_bytes())
    h.update(json.dumps([scene, bc.SCENES[scene], METHOD_A, METHOD_B, METHOD_C, CLI_RTOL,
                         scipy.__version__, np.__version__]).encode())
    return h.hexdigest()


def up_to_date(ref_dir: Path, scene: str) -> bool:
    st = ref_dir / f"{scene}.stamp"
    return (
        (ref_dir / f"{scene}.csv").is_file()
        and (ref_dir / f"{scene}.txt").is_file()
        and st.is_file()
        and st.read_text().strip() == stamp_of(scene)
    )


# --------------------------------------------------------------------------------------------------
# scipy runs in child processes
# --------------------------------------------------------------------------------------------------


def _scipy_child(values, method, rtol, atol, out_path):
    import oracle

    t0 = time.perf_counter()
    tg = bc.grid(values["t_end"])
    _, Y = oracle.reference_solution("reduced", values, method=method, rtol=rtol, atol=atol, t_eval=tg)
    np.save(out_path, Y)
    with open(out_path + ".time", "w") as fh:
        fh.write(repr(time.perf_counter() - t0))


class Job:
    def __init__(self, group, tag, values, method):
        self.group, self.tag, self.values, self.method = group, tag, values, method
        self.proc = self.path = self.t0 = None
        self.result = None  # (Y, seconds) or (None, reason)

    def start(self):
        fd, self.path = tempfile.mkstemp(suffix=".npy")
        os.close(fd)
        self.proc = mp.get_context("fork").Process(target=_scipy_child,
                                                   args=(self.values, *self.method, self.path))
        self.t0 = time.perf_counter()
        self.proc.start()

    def poll(self, budget):
        """True when finished (self.result set)."""
        if self.proc.is_alive():
            if time.perf_counter() - self.t0 <= budget:
                return False
            self.proc.terminate()
            self.proc.join()
            self.result = (None, f"not finished within the budget of {budget:.0f} s")
        else:
            self.proc.join()
            if self.proc.exitcode != 0:
                self.result = (None, f"failed (exit code {self.proc.exitcode})")
            else:
                self.result = (np.load(self.path), float(Path(self.path + ".time").read_text()))
        for f in (self.path, self.path + ".time"):
            if os.path.exists(f):
                os.remove(f)
        return True


def run_jobs(jobs, n_parallel, budget):
    pending = sorted(jobs, key=lambda j: -EXPECTED_S.get((j.group, j.tag), 5))
    running = []
    while pending or running:
        while pending and len(running) < n_parallel:
            j = pending.pop(0)
            j.start()
            running.append(j)
        time.sleep(0.1)
        for j in list(running):
            if j.poll(budget):
                running.remove(j)
                m = j.method
                msg = f"{j.result[1]:.1f} s" if j.result[0] is not None else j.result[1]
                print(f"  {j.group} {j.tag}: {m[0]} rtol {m[1]:g}: {msg}", file=sys.stderr)


def run_cli(scene: str, tg):
    """The Rust CLI's adaptive BDF at rtol CLI_RTOL on the grid: (Y reduced states, seconds, command)."""
    from conftest import binary_path, read_csv

    binary = binary_path()
    if not binary.is_file():
        raise FileNotFoundError(f"{binary} missing (cargo build --release)")
    args = ["simulate", bc.SCENES[scene][0], "--formulation", "reduced",
            "--set", f"rtol={CLI_RTOL}", "--set", "dt_out=0.01"]
    t0 = time.perf_counter()
    proc = subprocess.run([str(binary), *args], capture_output=True, text=True, cwd=bc.REPO)
    secs = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{binary} {' '.join(args)}: exit {proc.returncode}: {proc.stderr[-2000:]}")
    d = read_csv(proc.stdout)
    if len(d["t"]) != len(tg) or np.max(np.abs(d["t"] - tg)) > 1e-9:
        raise RuntimeError(f"CLI grid ({len(d['t'])} rows, last {d['t'][-1]}) != bench grid ({len(tg)} rows)")
    Y = np.stack([d[c] for c in bc.STATES_REDUCED], axis=1)
    return Y, secs, "target/release/beam-body " + " ".join(args)


# --------------------------------------------------------------------------------------------------


def with_hinge(values, Y4):
    """Reduced (v1, theta1, dv1, dtheta1) -> DAE (v1, theta1, u2, dv1, dtheta1, du2) on the exact
    constraint manifold."""
    import oracle

    u, du = oracle.u1_and_rate(Y4[:, 0], Y4[:, 1], Y4[:, 2], Y4[:, 3], bc.scene_params(values))
    return np.stack([Y4[:, 0], Y4[:, 1], u, Y4[:, 2], Y4[:, 3], du], axis=1)


def disagreement(A, B):
    """(max, rms, per-component max) of |A - B| / max_k |A| per component."""
    scale = np.max(np.abs(A), axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    e = (B - A) / scale
    return float(np.max(np.abs(e))), float(np.sqrt(np.mean(e * e))), np.max(np.abs(e), axis=0)


def method_text(m):
    return f"{DESC[m[0]]}, rtol {m[1]:g}, atol {m[2]:g}"


def write_group(path, scenes, values, jobs, ref_dir):
    tg = bc.grid(values["t_end"])
    YA, ta = jobs["A"].result
    if YA is None:
        raise RuntimeError(f"{path}: {METHOD_A[0]} {ta}")
    notes = []
    if "B" in jobs and jobs["B"].result[0] is not None:
        YB, tb = jobs["B"].result
        desc_b = method_text(METHOD_B)
    else:
        if "B" in jobs:
            notes.append(f"scipy {METHOD_B[0]} at rtol {METHOD_B[1]:g}: {jobs['B'].result[1]}; "
                         "the Rust CLI is the second method.")
        else:
            notes.append(f"scipy {METHOD_B[0]} at rtol {METHOD_B[1]:g} is too slow on this scene "
                         "(measured: not finished in 600 s); the Rust CLI is the second method.")
        YB, tb, cmd = run_cli(scenes[0], tg)
        desc_b = f"the Rust CLI's adaptive BDF at rtol {CLI_RTOL} (atol 1e-3·rtol): `{cmd}`"
        print(f"  {path} B: CLI rtol {CLI_RTOL}: {tb:.1f} s", file=sys.stderr)
    YC = tc = None
    if "C" in jobs:
        YC, tc = jobs["C"].result
        if YC is None:
            notes.append(f"self-convergence check {METHOD_C[0]} at rtol {METHOD_C[1]:g}: {tc}")

    for scene in scenes:
        form = bc.SCENES[scene][1]
        names = bc.state_names(scene)
        conv = (lambda Y: with_hinge(values, Y)) if bc.is_dae(form) else (lambda Y: Y)
        A, B = conv(YA), conv(YB)
        dmax, drms, per = disagreement(A, B)
        bc.write_sol(ref_dir / f"{scene}.csv", tg, A, names)
        lines = [
            f"reference for scene `{scene}` ({path}, formulation {form}) on t = k*0.01 s, "
            f"k = 0..{len(tg) - 1}",
            f"written: method A = {method_text(METHOD_A)} ({ta:.1f} s)",
            f"check:   method B = {desc_b} ({tb:.1f} s)",
            "the scipy methods integrate the oracle's reduced equations (tests/python/oracle.py) on "
            "[0, t_rot] and [t_rot, t_end] separately",
            f"max relative disagreement |A - B|/max|A| over the grid and components: {dmax:.3e}",
            f"RMS relative disagreement: {drms:.3e}",
            "per component (" + ", ".join(names) + "): " + ", ".join(f"{x:.2e}" for x in per),
        ]
        if YC is not None:
            cmax, crms, cper = disagreement(A, conv(YC))
            lines += [
                f"self-convergence: method C = {method_text(METHOD_C)} ({tc:.1f} s); "
                f"max |A - C|/max|A| {cmax:.3e}, RMS {crms:.3e} (same method, tighter: bounds the "
                "error of A)",
                "per component (" + ", ".join(names) + "): " + ", ".join(f"{x:.2e}" for x in cper),
            ]
        if bc.is_dae(form):
            lines.append(
                "DAE scene: the exact solution is the reduced one on the constraint manifold, "
                "u2 = u1(v1, theta1), du2 = -p·dv1 - l·q·dtheta1 (oracle.u1_and_rate); the DAE's own "
                "drift is part of a solver's error."
            )
        lines += [f"note: {n}" for n in notes]
        bc.write_atomic(ref_dir / f"{scene}.txt", "\n".join(lines) + "\n")
        bc.write_atomic(ref_dir / f"{scene}.stamp", stamp_of(scene) + "\n")
        extra = "" if YC is None else f", A vs C {disagreement(A, conv(YC))[0]:.2e}"
        print(f"  {scene}: max disagreement {dmax:.2e}, RMS {drms:.2e}{extra}", file=sys.stderr)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dir", type=Path, default=bc.DEFAULT_DIR)
    ap.add_argument("--scenes", default=",".join(bc.SCENES), help="comma-separated scene names")
    ap.add_argument("--force", action="store_true", help="recompute even when the stamp matches")
    ap.add_argument("--budget-seconds", type=float, default=600.0,
                    help="per scipy run; past it Radau is replaced by the Rust CLI")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="scipy runs at a time")
    args = ap.parse_args(argv)

    import oracle  # noqa: F401  (derived once, before the children fork)

    ref_dir = args.dir / "ref"
    scenes = [s.strip() for s in args.scenes.split(",") if s.strip()]
    for s in scenes:
        if s not in bc.SCENES:
            ap.error(f"unknown scene {s}; known: {', '.join(bc.SCENES)}")
    t0 = time.perf_counter()
    todo = {}
    for path, group in scene_groups(scenes).items():
        if not args.force and all(up_to_date(ref_dir, s) for s in group):
            print(f"bench_reference: {', '.join(group)} up to date", file=sys.stderr)
            continue
        values = bc.scene_values(group[0])
        jobs = {"A": Job(path, "A", values, METHOD_A), "C": Job(path, "C", values, METHOD_C)}
        if path not in CLI_SECOND:
            jobs["B"] = Job(path, "B", values, METHOD_B)
        todo[path] = (group, values, jobs)
    if not todo:
        return 0
    print(f"bench_reference: computing {', '.join(todo)} ({args.jobs} at a time)", file=sys.stderr)
    run_jobs([j for _, _, js in todo.values() for j in js.values()], max(1, args.jobs), args.budget_seconds)
    for path, (group, values, jobs) in todo.items():
        write_group(path, group, values, jobs, ref_dir)
    print(f"bench_reference: done in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
