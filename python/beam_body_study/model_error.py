"""The model's error against run time: `cargo xtask model-error` (python -m beam_body_study.model_error).

The paper's model is one cubic element of a beam whose geometric nonlinearity is cut at second
order. This report measures how far the n-element model of the same equations is from the
converged beam (the same quadratic equations in many elements), and what each run costs, so
that a user can choose n and rtol together.

Two errors, kept apart:
- model error: a run of n elements at the tightest rtol against the reference (n_ref
  elements, tightest rtol): what the n elements leave out of the converged quadratic beam;
- integration error: a run of n elements at rtol against the same n at the tightest rtol.
The total error of a run is against the reference; the figure plots it against run time.

The reference is itself n_ref elements: its own distance from the limit is estimated from the
last halving (n_ref/2 against n_ref) and reported beside it.

The beam itself is the geometrically exact beam (`beam = exact`: the inextensible elastica, valid
at any rotation, with the beam's axial inertia) converged in elements. Every (model, n) pair is
measured against it too: the paper's model, the quadratic model in n elements (whose limit is
the quadratic cut's error) and the exact beam in n elements. The fast turn, whose solution no
discretisation converges for after the turn, is measured by the growth of a small perturbation.

Runs go through the CLI (`beam-body simulate`): trajectories on a 1 ms grid (errors and peaks;
a grid peak is a lower bound, within the motion's change over 1 ms), then each run once more
without output rows for its run time, one at a time, best of three below 2 s (a trajectory of
more than 10 s gives its own time). Runs are cached
in the output directory under their settings, so a second call only writes the report.
"""

from __future__ import annotations

import argparse
import csv
import math
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from .runner import default_cli

ROOT = Path(__file__).resolve().parents[2]
SCENE_FILE = ROOT / "scenes" / "paper.toml"


@dataclass(frozen=True)
class Scene:
    name: str
    title: str
    settings: tuple  # (key, value) pairs on top of scenes/paper.toml
    t_rot: float = 0.85


SCENES = (
    Scene("paper", "the paper's scene (phi_end = pi, t_rot = 0.85 s, M2 = 12 kg)", ()),
    Scene("small", "a small turn (phi_end = 0.3)", (("phi_end", 0.3),)),
    Scene("light", "a light body (M2 = 1 kg, J_C = 0.05 kg.m2)", (("M2", 1.0), ("J_C", 0.05))),
    Scene("slow", "a slow turn (t_rot = 3 s)", (("t_rot", 3.0),), t_rot=3.0),
)


@dataclass(frozen=True)
class Plan:
    scenes: tuple
    elements: tuple
    rtols: tuple
    n_ref: int
    t_end: float
    dt_out: float = 1e-3
    #: The exact beam's elements, and its reference's (at the tightest rtol): "the beam".
    exact_elements: tuple = ()
    n_ref_exact: int = 0

    @property
    def rtol_ref(self) -> float:
        return min(self.rtols)


FULL = Plan(SCENES, (1, 2, 4, 8, 16), (1e-4, 1e-6, 1e-8), 32, 10.2,
            exact_elements=(1, 2, 4, 8), n_ref_exact=16)
#: A smoke test of the whole path in seconds (the test suite's): 2 s of two scenes.
QUICK = Plan(SCENES[:2], (1, 2), (1e-4, 1e-6), 4, 2.0, exact_elements=(1, 2), n_ref_exact=4)

EXACT = "exact"
QUADRATIC = "quadratic"


@dataclass
class Run:
    """One CLI run's trajectory (columns by bare name) and its statistics."""
    scene: Scene
    n: int
    rtol: float
    columns: dict = field(default_factory=dict)
    steps: int = 0
    seconds: float = math.nan
    beam: str = QUADRATIC


def rtol_text(rtol: float) -> str:
    """1e-08 as 1e-8."""
    mantissa, exponent = f"{rtol:e}".split("e")
    return f"{float(mantissa):g}e{int(exponent)}"


def run_name(scene: Scene, n: int, rtol: float, beam: str = QUADRATIC) -> str:
    """The cache's name of a run (the quadratic beam's without a suffix, as before the exact)."""
    suffix = "" if beam == QUADRATIC else f"__{beam}"
    return f"{scene.name}__n{n}__rtol{rtol_text(rtol)}{suffix}"


def cli_args(plan: Plan, scene: Scene, n: int, rtol: float, rows: bool,
             beam: str = QUADRATIC) -> list:
    sets = list(scene.settings) + [("t_end", plan.t_end),
                                   ("dt_out", plan.dt_out if rows else plan.t_end)]
    args = ["simulate", str(SCENE_FILE), "--elements", str(n), "--rtol", repr(rtol),
            "--beam", beam]
    for key, value in sets:
        args += ["--set", f"{key}={value if isinstance(value, str) else repr(value)}"]
    if rows:
        args += ["--columns", "beam"]
    return args


def parse_stats(stderr: str) -> tuple:
    """(steps, wall seconds) from the CLI's statistics on stderr."""
    steps = re.search(r"steps (\d+)", stderr)
    wall = re.search(r"wall ([0-9.]+) ms", stderr)
    if not (steps and wall):
        raise RuntimeError(f"no statistics in the CLI's output:\n{stderr}")
    return int(steps.group(1)), float(wall.group(1)) / 1e3


def simulate(cli: str, plan: Plan, run: Run, out_dir: Path) -> Run:
    """The trajectory of `run`, from the cache when its CSV is there."""
    name = run_name(run.scene, run.n, run.rtol, run.beam)
    csv_path, log_path = out_dir / f"{name}.csv", out_dir / f"{name}.log"
    if not csv_path.exists():
        part = csv_path.with_suffix(".csv.part")
        args = cli_args(plan, run.scene, run.n, run.rtol, True, run.beam) + ["-o", str(part)]
        done = subprocess.run([cli, *args], capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"{cli} {' '.join(args)} failed:\n{done.stderr}")
        log_path.write_text(done.stderr)
        part.rename(csv_path)
    run.steps, _ = parse_stats(log_path.read_text())
    with open(csv_path, newline="") as f:
        reader = csv.reader(f)
        header = [h.split(" [")[0] for h in next(reader)]
        values = [[float(x) for x in row] for row in reader]
    run.columns = {h: [row[k] for row in values] for k, h in enumerate(header)}
    return run


def time_run(cli: str, plan: Plan, run: Run, out_dir: Path) -> None:
    """The run time of the integration alone (no output rows): best of three below 2 s. A
    trajectory that took longer than 10 s gives its own wall time: its rows (about 2 µs each,
    20 ms for 10,201) are under 0.2 % of it."""
    name = run_name(run.scene, run.n, run.rtol, run.beam)
    path = out_dir / f"{name}.time"
    if path.exists():
        run.seconds = float(path.read_text())
        return
    _, wall = parse_stats((out_dir / f"{name}.log").read_text())
    if wall > 10.0:
        path.write_text(repr(wall))
        run.seconds = wall
        return
    args = cli_args(plan, run.scene, run.n, run.rtol, False, run.beam) + ["-o", "/dev/null"]
    best = math.inf
    for attempt in range(3):
        done = subprocess.run([cli, *args], capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"{cli} {' '.join(args)} failed:\n{done.stderr}")
        best = min(best, parse_stats(done.stderr)[1])
        if best > 2.0:
            break
    path.write_text(repr(best))
    run.seconds = best


# ----- what is compared -------------------------------------------------------------------

def window(run: Run, t_hi: float) -> range:
    t = run.columns["t"]
    return range(0, sum(1 for x in t if x <= t_hi + 1e-9))


def rel_max_diff(a: Run, b: Run, column: str, t_hi: float) -> float:
    """max |a − b| over [0, t_hi], over max |b| on the whole run (the peak of the reference)."""
    xa, xb = a.columns[column], b.columns[column]
    if len(xa) != len(xb):
        raise RuntimeError(f"{run_name(a.scene, a.n, a.rtol, a.beam)}: grid differs from the "
                           "reference's")
    peak = max(abs(x) for x in xb)
    return max(abs(xa[k] - xb[k]) for k in window(b, t_hi)) / peak


def metrics(run: Run) -> dict:
    """The figures users decide by, on the 1 ms grid: residual vibration (half the range of v1
    after the turn), peak hinge moment |M|, peak root moment |M_root|, max |v1|."""
    t, v1 = run.columns["t"], run.columns["v1"]
    after = [v for s, v in zip(t, v1) if s >= run.scene.t_rot]
    return {
        "residual vibration": 0.5 * (max(after) - min(after)),
        "peak M": max(abs(x) for x in run.columns["M"]),
        "peak M_root": max(abs(x) for x in run.columns["M_root"]),
        "max v1": max(abs(x) for x in v1),
    }


WINDOWS = (("[0, T]", 1.0), ("[0, 2T]", 2.0), ("whole run", math.inf))


def errors(run: Run, ref: Run) -> dict:
    """Relative errors of `run` against `ref`: v1 and theta1 over the windows, the metrics."""
    out = {}
    for label, k in WINDOWS:
        t_hi = min(k * run.scene.t_rot, ref.columns["t"][-1])
        out[f"v1 {label}"] = rel_max_diff(run, ref, "v1", t_hi)
        out[f"theta1 {label}"] = rel_max_diff(run, ref, "theta1", t_hi)
    mine, theirs = metrics(run), metrics(ref)
    for key, value in theirs.items():
        out[key] = abs(mine[key] - value) / abs(value)
    return out


# ----- sensitivity of the fast turn -------------------------------------------------------

def fast_turn(cli: str, elements: tuple, t_rot: float, out_dir: Path, t_end: float = 1.0,
              beam: str = QUADRATIC) -> list:
    """The fast turn in n elements (rtol 1e-10, unperturbed): per n, (n, max |theta1| over the
    turn, max |v1 − v1 of the most elements| over the turn and over [0, t_end] in m)."""
    runs = {}
    for n in elements:
        sets = (("t_rot", t_rot), ("v1_0", 0.0), ("range_check", "off"))
        scene = Scene(f"fast{t_rot:g}-v0{0.0:g}", "", sets, t_rot)
        plan = Plan((scene,), (n,), (1e-10,), n, t_end)
        runs[n] = simulate(cli, plan, Run(scene, n, 1e-10, beam=beam), out_dir)
    top = runs[max(elements)]
    t = top.columns["t"]
    rows = []
    for n, run in runs.items():
        d = [abs(a - b) for a, b in zip(run.columns["v1"], top.columns["v1"])]
        turn = [k for k, x in enumerate(t) if x <= t_rot + 1e-9]
        rows.append((n, max(abs(run.columns["theta1"][k]) for k in turn),
                     max(d[k] for k in turn), max(d)))
    return rows


def perturbation_growth(cli: str, n: int, t_rot: float, out_dir: Path, t_end: float = 1.0,
                        dv: float = 1e-9, beam: str = QUADRATIC) -> tuple:
    """Growth of a perturbation of the tip's start deflection by `dv` [m] in the turn of
    duration `t_rot`, n elements, rtol 1e-10: (rate [1/s] fitted to log|Δv1| on
    [t_rot, t_hi], t_hi, |Δv1| at t_hi), t_hi where |Δv1| first reaches 1 mm (or t_end)."""
    runs = []
    for v0 in (0.0, dv):
        # The buckled beam leaves the range |theta1| <= pi/2 within the second: the run goes
        # on (range_check = off) to show the growth, which is the point.
        sets = (("t_rot", t_rot), ("v1_0", v0), ("range_check", "off"))
        scene = Scene(f"fast{t_rot:g}-v0{v0:g}", "", sets, t_rot)
        plan = Plan((scene,), (n,), (1e-10,), n, t_end)
        runs.append(simulate(cli, plan, Run(scene, n, 1e-10, beam=beam), out_dir))
    t = runs[0].columns["t"]
    diff = [abs(a - b) for a, b in zip(runs[0].columns["v1"], runs[1].columns["v1"])]
    hi = next((k for k, d in enumerate(diff) if d >= 1e-3), len(diff) - 1)
    pts = [(t[k], math.log(diff[k])) for k in range(hi + 1) if t[k] >= t_rot and diff[k] > 0]
    if len(pts) < 2:
        return math.nan, t[hi], diff[hi]
    mt = sum(p[0] for p in pts) / len(pts)
    ml = sum(p[1] for p in pts) / len(pts)
    slope = sum((p[0] - mt) * (p[1] - ml) for p in pts) / sum((p[0] - mt) ** 2 for p in pts)
    return slope, t[hi], diff[hi]


# ----- against the beam itself -------------------------------------------------------------

@dataclass
class BeamRuns:
    """The exact beam's runs by (scene, n, rtol), and its references by scene: the beam."""
    runs: dict
    refs: dict

    def ladder(self, plan: Plan, scene: Scene, runs: dict, refs: dict) -> list:
        """Every (model, n) of a scene at the tightest rtol, from the paper's model to the
        beam: (label, model, n, its runs by rtol)."""
        tight = plan.rtol_ref
        out = []
        for n in plan.elements:
            label = "the paper's model" if n == 1 else "quadratic"
            out.append((label, QUADRATIC, n, {r: runs[scene.name, n, r] for r in plan.rtols}))
        out.append(("quadratic (its reference)", QUADRATIC, plan.n_ref,
                    {tight: refs[scene.name]}))
        for n in plan.exact_elements:
            out.append(("exact", EXACT, n, {r: self.runs[scene.name, n, r] for r in plan.rtols}))
        out.append(("exact (the beam)", EXACT, plan.n_ref_exact, {tight: self.refs[scene.name]}))
        return out


def cheapest_keeping(by_rtol: dict, beam: Run, tight: float, slack: float = 1.1) -> Run:
    """The loosest-tolerance run whose total error against the beam is within `slack` of the
    tightest one's: what its accuracy costs when the integration error does not show."""
    best = errors(by_rtol[tight], beam)["v1 whole run"]
    ok = [r for r in by_rtol if errors(by_rtol[r], beam)["v1 whole run"] <= slack * best]
    return by_rtol[max(ok)]


def hierarchy(plan: Plan, runs: dict, refs: dict, beam: BeamRuns) -> list:
    """The report's first table: the model hierarchy against the beam, with run times."""
    tight = plan.rtol_ref
    first = plan.scenes[0]
    lines = [
        "## The model hierarchy against the beam",
        "",
        f"The beam: the exact beam in {plan.n_ref_exact} elements at rtol {rtol_text(tight)}. "
        "Each model's error (its tightest run, over the beam's peak) and what it costs: the "
        "run time of its loosest tolerance that keeps that error (within 10 %). "
        f"{first.title[0].upper()}{first.title[1:]}:",
        "",
        "| model | n | v1 over [0, 2T] | theta1 over [0, 2T] | v1 whole run | theta1 whole run | "
        "max v1 | run time | rtol |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    the_beam = beam.refs[first.name]
    for label, _, n, by_rtol in beam.ladder(plan, first, runs, refs):
        e = errors(by_rtol[tight], the_beam)
        run = cheapest_keeping(by_rtol, the_beam, tight)
        lines.append(
            f"| {label} | {n} | {fmt(e['v1 [0, 2T]'])} | {fmt(e['theta1 [0, 2T]'])} | "
            f"{fmt(e['v1 whole run'])} | {fmt(e['theta1 whole run'])} | {fmt(e['max v1'])} | "
            f"{fmt_time(run.seconds)} | {rtol_text(run.rtol)} |")
    lines += [
        "",
        "Every scene, v1 over the whole run against the beam (theta1 alike), with the run time "
        "as above:",
        "",
        "| scene | the paper's model | quadratic, n = "
        f"{plan.n_ref} (the quadratic cut) | " + " | ".join(
            f"exact, n = {n}" for n in plan.exact_elements) + " |",
        "|---" * (2 + len(plan.exact_elements)) + "|---|",
    ]
    for scene in plan.scenes:
        the_beam = beam.refs[scene.name]
        cells = []
        for label, model, n, by_rtol in beam.ladder(plan, scene, runs, refs):
            keep = (model == QUADRATIC and n in (1, plan.n_ref)) or (
                model == EXACT and n in plan.exact_elements)
            if keep:
                e = errors(by_rtol[tight], the_beam)["v1 whole run"]
                run = cheapest_keeping(by_rtol, the_beam, tight)
                cells.append(f"{fmt(e)} in {fmt_time(run.seconds)}")
        lines.append(f"| {scene.name} | " + " | ".join(cells) + " |")
    lines.append("")
    return lines


def beam_section(plan: Plan, scene: Scene, runs: dict, refs: dict, beam: BeamRuns) -> list:
    """A scene's models against the beam, and the exact beam's own convergence."""
    tight = plan.rtol_ref
    the_beam = beam.refs[scene.name]
    lines = [f"Against the beam (the exact beam, n = {plan.n_ref_exact}, rtol {rtol_text(tight)}, "
             f"{the_beam.steps:,} steps, {fmt_time(the_beam.seconds)}).", ""]
    half = beam.runs.get((scene.name, plan.n_ref_exact // 2, tight))
    if half is not None:
        e = errors(half, the_beam)["v1 whole run"]
        lines[0] += (f" Its last halving (n = {plan.n_ref_exact // 2} against "
                     f"{plan.n_ref_exact}) moves v1 by {fmt(e)} of its peak over the whole run.")
    keys = list(errors(the_beam, the_beam).keys())
    lines += ["Each model at rtol " + rtol_text(tight) + " against the beam:", "",
              "| model | n | " + " | ".join(keys) + " |", "|---" * (len(keys) + 2) + "|"]
    for label, _, n, by_rtol in beam.ladder(plan, scene, runs, refs)[:-1]:
        e = errors(by_rtol[tight], the_beam)
        lines.append(f"| {label} | {n} | " + " | ".join(fmt(e[k]) for k in keys) + " |")
    lines += ["", "The exact beam's integration error and total error of v1 over the whole run, "
              "and run time:", "",
              "| n | rtol | steps | run time | integration error | total error |",
              "|---|---|---|---|---|---|"]
    for n in plan.exact_elements:
        own = beam.runs[scene.name, n, tight]
        for r in plan.rtols:
            run = beam.runs[scene.name, n, r]
            integ = fmt(rel_max_diff(run, own, "v1", math.inf)) if r != tight else "(itself)"
            lines.append(f"| {n} | {rtol_text(r)} | {run.steps:,} | {fmt_time(run.seconds)} | "
                         f"{integ} | {fmt(errors(run, the_beam)['v1 whole run'])} |")
    return lines + [""]


# ----- the report --------------------------------------------------------------------------

def fmt(x: float) -> str:
    if not math.isfinite(x):
        return "—"
    if x == 0:
        return "0"
    return f"{100 * x:.2g} %" if x >= 1e-3 else f"{x:.1e}"


def fmt_time(s: float) -> str:
    if s >= 1:
        return f"{s:.3g} s"
    return f"{1e3 * s:.3g} ms"


def figure(plan: Plan, runs: dict, refs: dict, out: Path, beam: BeamRuns) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = (("v1 whole run", "whole run"), ("v1 [0, 2T]", "[0, 2T]"))
    fig, axes = plt.subplots(len(rows) + 1, len(plan.scenes), figsize=(4 * len(plan.scenes), 10),
                             sharex="col", squeeze=False)
    markers = {r: m for r, m in zip(sorted(plan.rtols, reverse=True), "o^sD")}
    colors = plt.get_cmap("viridis")
    for j, scene in enumerate(plan.scenes):
        ref = refs[scene.name]
        for i, (key, label) in enumerate(rows):
            ax = axes[i][j]
            for k, n in enumerate(plan.elements):
                color = colors(k / max(1, len(plan.elements) - 1))
                pts = sorted((runs[scene.name, n, r].seconds,
                              errors(runs[scene.name, n, r], ref)[key], r) for r in plan.rtols)
                ax.plot([p[0] for p in pts], [p[1] for p in pts], "-", color=color,
                        label=f"n = {n}")
                for x, y, r in pts:
                    ax.plot(x, y, markers[r], color=color, ms=5)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.grid(True, which="both", alpha=0.3)
            if i == 0:
                ax.set_title(scene.title.split(" (")[0] + f"\n({scene.title.split(' (')[1]}",
                             fontsize=9)
            if j == 0:
                ax.set_ylabel(f"max |v1 − v1_ref| / max |v1_ref|\nover the {label}")
        # Both models against the beam itself: the quadratic dashed, the exact solid.
        ax = axes[len(rows)][j]
        the_beam = beam.refs[scene.name]
        for model, dash, elements, table in ((QUADRATIC, "--", plan.elements, runs),
                                              (EXACT, "-", plan.exact_elements, beam.runs)):
            for k, n in enumerate(elements):
                color = colors(plan.elements.index(n) / max(1, len(plan.elements) - 1))
                pts = sorted((table[scene.name, n, r].seconds,
                              errors(table[scene.name, n, r], the_beam)["v1 whole run"], r)
                             for r in plan.rtols)
                ax.plot([p[0] for p in pts], [p[1] for p in pts], dash, color=color)
                for x, y, r in pts:
                    ax.plot(x, y, markers[r], color=color, ms=5,
                            mfc="white" if model == QUADRATIC else color)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.set_xlabel("run time [s]")
        if j == 0:
            ax.set_ylabel(f"against the beam (exact, n = {plan.n_ref_exact}):\n"
                          "quadratic dashed, exact solid")
    handles, labels = axes[0][0].get_legend_handles_labels()
    for r, m in markers.items():
        handles.append(plt.Line2D([], [], marker=m, color="gray", ls=""))
        labels.append(f"rtol {rtol_text(r)}")
    fig.legend(handles, labels, loc="lower center", ncol=len(handles), fontsize=8)
    fig.suptitle(f"Total error against run time: the quadratic model in n elements against its own "
                 f"{plan.n_ref} (rtol {rtol_text(plan.rtol_ref)}; top rows), both models against the "
                 "exact beam (bottom row)", fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.95))
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)


def report(plan: Plan, runs: dict, refs: dict, growth: list, figure_name: str,
           command: str, beam: BeamRuns) -> str:
    rtol_ref = plan.rtol_ref
    lines = [
        "# The model's error against run time",
        "",
        f"Written by `{command}` (python/beam_body_study/model_error.py; a run's cache in "
        "target/model_error/). Machine: 2 shared cores; a run time is one run of the CLI "
        "without output rows (best of three below 2 s; above 10 s the trajectory's own run, "
        "beside another), so ratios under 1.5× are noise.",
        "",
        "The model: the paper's quadratic equations (the constraint eliminated, `reduced`), "
        "the beam in n cubic Hermite elements; n = 1 is the paper's model. No damping. "
        f"The reference: n = {plan.n_ref} at rtol {rtol_text(rtol_ref)}. **Model error**: n elements "
        f"at rtol {rtol_text(rtol_ref)} against the reference. **Integration error**: n elements at "
        f"rtol against the same n at rtol {rtol_text(rtol_ref)}. **Total error**: against the "
        "reference. All are relative: the largest difference in the window over the "
        "reference's largest |value| on the whole run (v1, theta1), or the relative difference "
        "of a metric. T = t_rot is the end of the turn. The metrics are on a 1 ms grid: "
        "residual vibration = half the range of v1 after the turn (t ≥ T), peak M = max |M| "
        "(the hinge moment), peak M_root = max |M_root| (the root bending moment EI v''(0)), "
        "max v1 = max |v1|.",
        "",
        "The beam itself: the geometrically exact beam (`beam = exact`, the inextensible "
        "elastica in the section angle, with the beam's axial inertia, valid at any rotation), "
        f"converged in {plan.n_ref_exact} elements. Against it, the quadratic model's limit is "
        "the error of the quadratic cut. What this does not measure: damping (none here, as in "
        "the paper).",
        "",
        f"![total error against run time]({figure_name})",
        "",
    ]
    lines += hierarchy(plan, runs, refs, beam)
    lines += summary(plan, runs, refs)
    for scene in plan.scenes:
        ref = refs[scene.name]
        half = runs.get((scene.name, plan.n_ref // 2, rtol_ref))
        lines += [f"## {scene.title[0].upper()}{scene.title[1:]}", ""]
        ref_line = (f"Reference: n = {plan.n_ref}, rtol {rtol_text(rtol_ref)}, {ref.steps:,} steps, "
                    f"{fmt_time(ref.seconds)}.")
        quarter = runs.get((scene.name, plan.n_ref // 4, rtol_ref))
        if half is not None:
            e = errors(half, ref)["v1 whole run"]
            ref_line += (f" Its last halving (n = {plan.n_ref // 2} against {plan.n_ref}) "
                         f"moves v1 by {fmt(e)} of its peak over the whole run.")
            if quarter is not None and e > 0:
                # Errors falling by a factor c a halving: the reference's own error is about
                # the last halving's change over (c − 1).
                c = errors(quarter, ref)["v1 whole run"] / e - 1.0
                ref_line += (f" The halving before moves it {c + 1:.3g} times as much, so the "
                             f"reference is about {fmt(e / c)} from the limit of n → ∞"
                             if c > 1 else " The halving before moves it no more: the "
                             "elements have not settled into their rate of convergence")
                ref_line += "."
        lines += [ref_line, ""]
        keys = list(errors(runs[scene.name, plan.elements[0], rtol_ref], ref).keys())
        lines += [f"Model error (each n at rtol {rtol_text(rtol_ref)} against the reference):", ""]
        lines += ["| n | " + " | ".join(keys) + " |", "|---" * (len(keys) + 1) + "|"]
        for n in plan.elements:
            e = errors(runs[scene.name, n, rtol_ref], ref)
            lines.append(f"| {n} | " + " | ".join(fmt(e[k]) for k in keys) + " |")
        m = metrics(ref)
        lines += ["", "The reference's metrics: " + ", ".join(
            f"{k} {v:.4g}" for k, v in m.items()) + " (m, N.m).", ""]
        lines += ["Integration error and total error of v1 over the whole run, and run time:",
                  "", "| n | rtol | steps | run time | integration error | total error |",
                  "|---|---|---|---|---|---|"]
        for n in plan.elements:
            tight = runs[scene.name, n, rtol_ref]
            for r in plan.rtols:
                run = runs[scene.name, n, r]
                integ = rel_max_diff(run, tight, "v1", math.inf) if r != rtol_ref else 0.0
                total = errors(run, ref)["v1 whole run"]
                lines.append(f"| {n} | {rtol_text(r)} | {run.steps:,} | {fmt_time(run.seconds)} | "
                             f"{fmt(integ) if r != rtol_ref else '(itself)'} | {fmt(total)} |")
        lines.append("")
        lines += beam_section(plan, scene, runs, refs, beam)
    if growth:
        growth, fast, exact_growth, exact_fast = growth
        most = max(r[0] for r in fast)
        lines += [
            "## Where no figure converges: the fast turn",
            "",
            "With t_rot = 0.2 s the body pushes the tip far past the cantilever's Euler load, "
            "and the beam buckles (the run goes on past |theta1| = pi/2 here, range_check = "
            "off, to show it). The motion in n elements, rtol 1e-10, against n = "
            f"{most}:",
            "",
            f"| n | max abs theta1 over the turn [rad] | max abs (v1 − v1 of n = {most}) over "
            "the turn [m] | the same over [0, 1 s] [m] |",
            "|---|---|---|---|",
        ]
        for n, th, d_turn, d_all in fast:
            lines.append(f"| {n} | {th:.3g} | {d_turn:.2g} | {d_all:.2g} |")
        lines += [
            "",
            "A perturbation of the tip's start deflection by 1e-9 m grows after the turn at the "
            "rate below (a least-squares fit of log |Δv1| from t_rot to where it reaches 1 mm, "
            "or to 1 s): a figure of this scene after the turn is sensitive to everything, "
            "elements and tolerance included, and none is reported as converged.",
            "",
            "| n | t_rot | growth rate [1/s] | growth per second | Δv1 reached | at t |",
            "|---|---|---|---|---|---|",
        ]
        for n, t_rot, (rate, t_hi, d) in growth:
            lines.append(f"| {n} | {t_rot:g} s | {rate:.3g} | {math.exp(rate):.3g}× | {d:.2g} m | "
                         f"{t_hi:.3g} s |")
        most = max(r[0] for r in exact_fast)
        lines += [
            "",
            "The exact beam runs through the fast turn (its range check would stop it only if "
            "the centreline crossed itself). The same measures over [0, 3 s], against n = "
            f"{most} of the exact beam:",
            "",
            f"| n | max abs theta1 over the turn [rad] | max abs (v1 − v1 of n = {most}) over "
            "the turn [m] | the same over [0, 3 s] [m] |",
            "|---|---|---|---|",
        ]
        for n, th, d_turn, d_all in exact_fast:
            lines.append(f"| {n} | {th:.3g} | {d_turn:.2g} | {d_all:.2g} |")
        lines += ["", "A perturbation of the tip's start deflection by 1e-8 m, as above:", "",
                  "| n | t_rot | growth rate [1/s] | growth per second | Δv1 reached | at t |",
                  "|---|---|---|---|---|---|"]
        for n, t_rot, (rate, t_hi, d) in exact_growth:
            lines.append(f"| {n} | {t_rot:g} s | {rate:.3g} | {math.exp(rate):.3g}× | {d:.2g} m | "
                         f"{t_hi:.3g} s |")
        lines.append("")
    return "\n".join(lines)


def summary(plan: Plan, runs: dict, refs: dict) -> list:
    """The report's first table and what to read from it, from the measured runs."""
    tight = plan.rtol_ref
    mid = sorted(plan.rtols)[len(plan.rtols) // 2]
    lines = [
        "## Summary",
        "",
        "The model error of v1 and theta1 (each n at rtol "
        f"{rtol_text(tight)}, over the reference's peak), the fewest elements that bring v1 "
        "over the whole run within 1 % and 0.1 %, and the run time of those at rtol "
        f"{rtol_text(mid)}:",
        "",
        "| scene | n = 1 over [0, 2T] (v1, theta1) | n = 1 over the whole run | n for 1 % | "
        "n for 0.1 % | their run times |",
        "|---|---|---|---|---|---|",
    ]
    for scene in plan.scenes:
        ref = refs[scene.name]
        one = errors(runs[scene.name, plan.elements[0], tight], ref)
        need = []
        for level in (1e-2, 1e-3):
            n = next((n for n in plan.elements
                      if errors(runs[scene.name, n, tight], ref)["v1 whole run"] < level), None)
            need.append(n)
        times = " / ".join(fmt_time(runs[scene.name, n, mid].seconds) if n else "—"
                           for n in need)
        lines.append(
            f"| {scene.name} | {fmt(one['v1 [0, 2T]'])}, {fmt(one['theta1 [0, 2T]'])} | "
            f"{fmt(one['v1 whole run'])}, {fmt(one['theta1 whole run'])} | "
            f"{need[0] or '> %d' % plan.elements[-1]} | {need[1] or '> %d' % plan.elements[-1]} | "
            f"{times} |")
    big = [n for n in plan.elements if n >= 4]
    if big:
        n = big[-1]
        steps = {r: runs[plan.scenes[0].name, n, r].steps for r in plan.rtols}
        lo, hi = min(plan.rtols), max(plan.rtols)
        lines += [
            "",
            "What to read from it:",
            integration_line(plan, runs, refs),
            f"- For n ≥ 4 the steps hardly depend on rtol ({n} elements, {scene_title(plan)}: "
            f"{steps[hi]:,} steps at rtol {rtol_text(hi)}, {steps[lo]:,} at {rtol_text(lo)}). "
            "The paper's law has a jump of phi'' at t = 0 and at T, which sets every mode of "
            "the beam vibrating; the undamped model keeps them, and the integrator resolves "
            "the highest, whose period falls as 1/n². Damping "
            "(`damping_ratio`, `damping_alpha`, `damping_beta`) takes them out.",
            "- The peak hinge moment converges slowly and not monotonically: the same jump "
            "puts every mode's acceleration into the hinge moment, and the 1 ms grid samples "
            "modes of shorter period than that.",
        ]
    return lines + [""]


def integration_line(plan: Plan, runs: dict, refs: dict) -> str:
    """The largest ratio of integration error to model error (v1, whole run) over the scenes,
    n ≥ 2 and the looser tolerances."""
    worst = (0.0, None)
    for scene in plan.scenes:
        for n in plan.elements[1:]:
            tight = runs[scene.name, n, plan.rtol_ref]
            model = errors(tight, refs[scene.name])["v1 whole run"]
            for r in plan.rtols:
                if r != plan.rtol_ref and model > 0:
                    ratio = rel_max_diff(runs[scene.name, n, r], tight, "v1", math.inf) / model
                    worst = max(worst, (ratio, (scene.name, n, r)), key=lambda w: w[0])
    if worst[1] is None:
        return "- (no integration error to compare)"
    name, n, r = worst[1]
    return (f"- For n ≥ 2 the integration error of v1 is at most {worst[0]:.2g} times the model "
            f"error at rtol {rtol_text(max(plan.rtols))} and tighter (the most: {name}, n = "
            f"{n}, rtol {rtol_text(r)}): choose n first; a loose rtol costs little accuracy.")


def scene_title(plan: Plan) -> str:
    return plan.scenes[0].title.split(" (")[0]


def compute(plan: Plan, out_dir: Path, cli: str, jobs: int, log) -> tuple:
    """Every run of the plan: (the quadratic beam's runs by (scene, n, rtol), its references by
    scene, the exact beam's runs likewise, and its references: the beam)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    todo = [Run(s, n, r) for s in plan.scenes for n in plan.elements for r in plan.rtols]
    todo += [Run(s, plan.n_ref, plan.rtol_ref) for s in plan.scenes]
    todo += [Run(s, n, r, beam=EXACT) for s in plan.scenes for n in plan.exact_elements
             for r in plan.rtols]
    todo += [Run(s, plan.n_ref_exact, plan.rtol_ref, beam=EXACT) for s in plan.scenes
             if plan.n_ref_exact]
    unique = {run_name(r.scene, r.n, r.rtol, r.beam): r for r in todo}
    started = time.monotonic()
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        # The slowest first, so that the pool ends together (the exact beam's step costs about
        # three of the quadratic's).
        order = sorted(unique.values(), key=lambda r: (-r.n * (3 if r.beam == EXACT else 1), r.rtol))
        done = list(pool.map(lambda r: simulate(cli, plan, r, out_dir), order))
    log(f"trajectories: {len(done)} runs in {time.monotonic() - started:.0f} s")
    for r in done:
        time_run(cli, plan, r, out_dir)
    log(f"run times measured, {time.monotonic() - started:.0f} s in all")
    runs = {(r.scene.name, r.n, r.rtol): r for r in done if r.beam == QUADRATIC}
    exact = {(r.scene.name, r.n, r.rtol): r for r in done if r.beam == EXACT}
    refs = {s.name: runs[s.name, plan.n_ref, plan.rtol_ref] for s in plan.scenes}
    beams = {s.name: exact[s.name, plan.n_ref_exact, plan.rtol_ref] for s in plan.scenes
             if plan.n_ref_exact}
    return runs, refs, exact, beams


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="model-error", description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true",
                   help="2 s of two scenes, n = 1, 2 against n = 4 (a smoke test)")
    p.add_argument("--out-dir", type=Path, default=ROOT / "target" / "model_error")
    p.add_argument("--docs", type=Path, default=None,
                   help="write model_error.md and model_error.png here (default: --out-dir)")
    p.add_argument("--cli", default=None, help="the beam-body CLI (default: the release build)")
    p.add_argument("--jobs", type=int, default=2, help="trajectory runs at once (default 2)")
    args = p.parse_args(argv)
    plan = QUICK if args.quick else FULL
    cli = args.cli or default_cli()
    runs_dir = args.out_dir / ("runs-quick" if args.quick else "runs")
    log = lambda text: print(f"model-error: {text}", file=sys.stderr, flush=True)
    runs, refs, exact, beams = compute(plan, runs_dir, cli, args.jobs, log)
    growth = []
    if not args.quick:
        rates = [(n, 0.2, perturbation_growth(cli, n, 0.2, runs_dir)) for n in (4, 8, 16)]
        growth = (rates, fast_turn(cli, (1, 2, 4, 8, 16), 0.2, runs_dir))
        exact_rates = [(n, 0.2, perturbation_growth(cli, n, 0.2, runs_dir, t_end=3.0, dv=1e-8,
                                                    beam=EXACT)) for n in (4, 8)]
        growth += (exact_rates, fast_turn(cli, (2, 4, 8, 16), 0.2, runs_dir, t_end=3.0,
                                          beam=EXACT))
    docs = args.docs or args.out_dir
    docs.mkdir(parents=True, exist_ok=True)
    beam = BeamRuns(exact, beams)
    figure(plan, runs, refs, docs / "model_error.png", beam)
    command = "cargo xtask model-error" + (" --quick" if args.quick else "")
    text = report(plan, runs, refs, growth, "model_error.png", command, beam)
    (docs / "model_error.md").write_text(text + "\n")
    log(f"wrote {docs / 'model_error.md'} and {docs / 'model_error.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
