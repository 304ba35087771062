"""Report of the work-precision benchmark: errors, medians, CSV, figure and markdown summary.

    python bench/python/bench_report.py [--dir target/bench] [--docs-dir docs | --no-docs]
                                        [--command "cargo xtask bench"]

Reads <dir>/cases.csv, raw.csv (rounds >= 1 for timing; round 0, the warm-up, only for counters
and the sol/ files), sol/, ref/ and costs.csv, and writes
* <dir>/work_precision.csv, header
  solver,scene,rtol,error,max_error,time_s,time_min_s,steps,rejected,rhs_evals,jac_evals,lu_factorizations
  (one row per case with a solution or a timing; bdf-fixed and fmu carry their step in the solver
  label, e.g. bdf-fixed(h=1e-4), fmu(H=1e-3));
* <dir>/work_precision.png: error against median time, log-log, one panel per scene;
* <dir>/work_precision.md: the summary;
then copies the PNG and the MD into docs/.

Error of a case (bench contract): e_i(t_k) = (y_i - y_ref,i)/max_k |y_ref,i| per state component i
(positions and velocities), error = RMS over the grid and the components, max_error = max |e|.

Comparisons at an error level E (markdown): each solver's points (median time, error) are reduced to
their Pareto front (a point counts only if it is more accurate than every cheaper point of the same
solver); the time at E is interpolated log-log between the two front points around E. Above the
front's largest error, the solver's cheapest run already reaches E, so only an upper bound "≤" on its
time is known; below the smallest error, E is out of its reach ("—"). Steps at E are interpolated
the same way on the (steps, error) front.

Lower bound at E: the fewest steps any solver needed for E, times (rhs_ns + solve_ns), the cost of
one right-hand side and one LU solve from costs.csv (the least work per step of any implicit method
with a factorisation reused across steps), each priced as a call that waits for the one before, as in
the Newton iteration (costs.csv also has the cost of independent calls). Overhead per step of our bdf: (time - rhs_evals·rhs_ns -
lu_factorizations·lu_ns - newton_iters·solve_ns) / steps, from our cases' own counters, interpolated
at E in log E between the two cases around it.
"""

from __future__ import annotations

import argparse
import datetime as dt
import math
import os
import platform
import shutil
import statistics
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_common as bc  # noqa: E402

OURS = "bdf"
FIXED = "bdf-fixed"
#: Every decade from 1e-3 to 1e-8 (issue 16: ours ≤ 0.5× CVODE's time at each of them).
LEVELS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
#: The targets of the Targets table.
TARGET_CVODE_RATIO = 2.0
TARGET_OVERHEAD_NS = 120.0
#: The co-simulation FMU at H = 10 ms against the host's CVODE on its Model Exchange (issue 29).
TARGET_CS_OVER_ME = 2.0
KNOWN_SOLVERS = ("bdf", "bdf-fixed", "cvode", "ida", "diffsol", "scipy-bdf", "scipy-radau",
                 "scipy-lsoda", "fmu", "fmu3", "cvode-me", "fmpy-me")
WP_HEADER = ("solver,scene,rtol,error,max_error,time_s,time_min_s,steps,rejected,rhs_evals,"
             "jac_evals,lu_factorizations").split(",")
COUNTERS = ("steps", "rejected", "rhs_evals", "jac_evals", "lu_factorizations", "newton_iters")


# --------------------------------------------------------------------------------------------------
# formatting
# --------------------------------------------------------------------------------------------------


def fmt_step(h: float) -> str:
    """1e-4 rather than 0.0001 or 1e-04."""
    e = math.floor(math.log10(h) + 1e-12)
    mant = h / 10.0**e
    if abs(mant - round(mant)) < 1e-9:
        m = int(round(mant))
        return f"{m}e{e}" if m != 1 else f"1e{e}"
    return f"{h:g}"


def fmt_time(s) -> str:
    if s is None or not math.isfinite(s):
        return "—"
    if s >= 1:
        return f"{s:.3g} s"
    if s >= 1e-3:
        return f"{s * 1e3:.3g} ms"
    return f"{s * 1e6:.3g} µs"


def fmt_num(x, digits=3) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    return f"{x:.{digits}g}"


def fmt_int(x) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    return f"{int(round(x)):,}".replace(",", " ")


def csv_float(x) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return ""
    return f"{x:.6e}"


def csv_int(x) -> str:
    return "" if x is None else str(int(round(x)))


# --------------------------------------------------------------------------------------------------
# inputs
# --------------------------------------------------------------------------------------------------


class Case:
    def __init__(self, solver, scene, rtol_text, h_text):
        self.solver, self.scene = solver, scene
        self.rtol_text, self.h_text = rtol_text, h_text
        self.rtol = bc.parse_opt_float(rtol_text)
        self.h = bc.parse_opt_float(h_text)
        self.key = (solver, scene, self.rtol, self.h)
        self.rows = []
        self.error = self.max_error = None
        self.time = self.time_min = None
        self.n_timed = 0
        self.counters = {k: None for k in COUNTERS}
        self.failures = []  # (round, status)
        self.residual = None  # (max |u2 - u1|, max |du2 - du1|) for dae scenes
        self.problem = None  # why there is no error

    @property
    def label(self):
        if self.h is None:
            return self.solver
        sym = "H" if self.solver in ("fmu", "fmu3") else "h"
        return f"{self.solver}({sym}={fmt_step(self.h)})"

    @property
    def usable(self):
        return self.error is not None and self.time is not None


def load_cases(d: Path, notes):
    cases: dict = {}
    order = []
    if (d / "cases.csv").is_file():
        for r in bc.read_cases(d / "cases.csv"):
            c = Case(r["solver"], r["scene"], r["rtol"], r["h"])
            if c.key not in cases:
                cases[c.key] = c
                order.append(c.key)
    else:
        notes.append("cases.csv missing: the cases are taken from raw.csv")
    raw_rows = []
    if (d / "raw.csv").is_file():
        raw_rows = bc.read_table(d / "raw.csv", bc.RAW_HEADER)
    else:
        notes.append("raw.csv missing: no timings")
    for r in raw_rows:
        c = Case(r["solver"], r["scene"], r["rtol"], r["h"])
        if c.key not in cases:
            cases[c.key] = c
            order.append(c.key)
        cases[c.key].rows.append(r)
    return [cases[k] for k in order]


def _float(text):
    try:
        x = float(text)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def summarize_rows(c: Case):
    times = []
    ok_rows = []
    for r in c.rows:
        try:
            rk = int(r["round"])
        except ValueError:
            rk = -1
        if r["status"] != "ok":
            c.failures.append((rk, r["status"]))
            continue
        ok_rows.append(r)
        t = _float(r["time_s"])
        if rk >= 1 and t is not None:
            times.append(t)
    if times:
        c.time = statistics.median(times)
        c.time_min = min(times)
        c.n_timed = len(times)
    for k in COUNTERS:
        vals = [_float(r[k]) for r in ok_rows]
        vals = [v for v in vals if v is not None]
        if vals:
            c.counters[k] = statistics.median(vals)


def load_refs(d: Path, scenes, notes):
    refs, texts = {}, {}
    for s in scenes:
        p = d / "ref" / f"{s}.csv"
        if not p.is_file():
            notes.append(f"reference ref/{s}.csv missing: no errors for scene {s}")
            continue
        refs[s] = bc.read_sol(p)
        tp = d / "ref" / f"{s}.txt"
        texts[s] = tp.read_text() if tp.is_file() else ""
    return refs, texts


def sol_index(d: Path):
    idx = {}
    sd = d / "sol"
    if sd.is_dir():
        for p in sd.iterdir():
            k = bc.parse_sol_name(p.name)
            if k is not None:
                idx[k] = p
    return idx


def compute_error(c: Case, path: Path, ref):
    names, t, Y = bc.read_sol(path)
    rnames, rt, R = ref
    if len(t) != len(rt) or np.max(np.abs(t - rt)) > 1e-9 * max(1.0, float(np.max(np.abs(rt)))):
        c.problem = f"grid of {path.name} ({len(t)} points) differs from the reference ({len(rt)})"
        return None
    missing = [n for n in rnames if n not in names]
    if missing:
        c.problem = f"{path.name} lacks {', '.join(missing)}"
        return None
    Y = np.stack([Y[:, names.index(n)] for n in rnames], axis=1)
    scale = np.max(np.abs(R), axis=0)
    scale = np.where(scale > 0, scale, 1.0)
    e = (Y - R) / scale
    if not np.all(np.isfinite(e)):
        c.problem = "non-finite values in the solution"
        return None
    c.error = float(np.sqrt(np.mean(e * e)))
    c.max_error = float(np.max(np.abs(e)))
    return names, t, Y


def constraint_residual(scene, names, Y):
    import oracle

    vals = bc.scene_values(scene)
    col = {n: Y[:, names.index(n)] for n in names}
    u, du = oracle.u1_and_rate(col["v1"], col["theta1"], col["dv1"], col["dtheta1"], bc.scene_params(vals))
    return float(np.max(np.abs(col["u2"] - u))), float(np.max(np.abs(col["du2"] - du)))


def load_costs(d: Path, notes):
    out = {}
    p = d / "costs.csv"
    if not p.is_file():
        notes.append("costs.csv missing: no lower bound and no overhead per step")
        return out
    # One row per scene and round: the median over the timed rounds (round 0, the warm-up, only
    # when there is nothing else), each price on its own.
    keys = ("rhs_ns", "lu_ns", "solve_ns", "rhs_throughput_ns", "solve_throughput_ns")
    rows = {}
    for r in bc.read_table(p, bc.COSTS_HEADER):
        v = [_float(r[k]) for k in keys]
        if all(x is not None for x in v):
            rows.setdefault(r["scene"], []).append((r["round"] != "0", v))
    for scene, measured in rows.items():
        timed = [v for is_timed, v in measured if is_timed] or [v for _, v in measured]
        out[scene] = {k: statistics.median(v[i] for v in timed) for i, k in enumerate(keys)}
        out[scene]["rounds"] = len(timed)
    return out


# --------------------------------------------------------------------------------------------------
# curves and interpolation
# --------------------------------------------------------------------------------------------------


class Curve:
    """The usable cases of one solver (or solver + step) on one scene."""

    def __init__(self, label, solver, cases):
        self.label, self.solver = label, solver
        self.cases = sorted(cases, key=lambda c: c.time)

    def front(self, cost):
        """Pareto front [(cost, error, case)] with cost increasing and error strictly decreasing."""
        pts = sorted(((cost(c), c.error, c) for c in self.cases if cost(c) is not None and c.error > 0),
                     key=lambda p: (p[0], p[1]))
        out = []
        for p in pts:
            if not out or p[1] < out[-1][1]:
                out.append(p)
        return out

    def at(self, E, cost=lambda c: c.time):
        """(kind, value, (i, j, w)) with kind '=' or '<=', or None when E is out of reach.
        (i, j, w): the two front cases around E and the weight of j in log E."""
        fr = self.front(cost)
        if not fr:
            return None
        if E >= fr[0][1]:
            return ("=" if E == fr[0][1] else "<=", fr[0][0], (fr[0][2], fr[0][2], 0.0))
        for (c0, e0, k0), (c1, e1, k1) in zip(fr, fr[1:]):
            if e0 >= E >= e1:
                w = (math.log(E) - math.log(e0)) / (math.log(e1) - math.log(e0))
                val = math.exp(math.log(c0) + w * (math.log(c1) - math.log(c0)))
                return ("=", val, (k0, k1, w))
        return None


def build_curves(cases):
    """{scene: {label: Curve}}; a solver is split by its step only if it also varies rtol."""
    by = {}
    for c in cases:
        if c.usable:
            by.setdefault(c.scene, {}).setdefault(c.solver, []).append(c)
    out = {}
    for scene, solvers in by.items():
        out[scene] = {}
        for solver, cs in solvers.items():
            hs = {c.h for c in cs}
            rts = {c.rtol for c in cs}
            if len(hs) > 1 and len(rts) > 1:
                for h in sorted(hs, key=lambda x: (x is None, x)):
                    sub = [c for c in cs if c.h == h]
                    out[scene][sub[0].label] = Curve(sub[0].label, solver, sub)
            else:
                out[scene][solver] = Curve(solver, solver, cs)
    return out


def overhead_ns(c: Case, cost):
    """ns of integrator overhead per step of one case, or None."""
    k = c.counters
    if cost is None or c.time is None or not k["steps"]:
        return None
    if k["rhs_evals"] is None or k["lu_factorizations"] is None:
        return None
    newton = k["newton_iters"] or 0.0
    t_ns = c.time * 1e9 - k["rhs_evals"] * cost["rhs_ns"] - k["lu_factorizations"] * cost["lu_ns"] \
        - newton * cost["solve_ns"]
    return t_ns / k["steps"]


def ratio_text(peer, ours):
    """peer/ours with the bound kinds."""
    if peer is None or ours is None:
        return "—"
    r = peer[1] / ours[1]
    kp, ko = peer[0], ours[0]
    if kp == "=" and ko == "=":
        return f"{r:.3g}×"
    if kp == "<=" and ko == "=":
        return f"≤ {r:.3g}×"
    if kp == "=" and ko == "<=":
        return f"≥ {r:.3g}×"
    return "n/a"


def est_text(est, fmt=fmt_time):
    if est is None:
        return "—"
    return ("≤ " if est[0] == "<=" else "") + fmt(est[1])


# --------------------------------------------------------------------------------------------------
# outputs
# --------------------------------------------------------------------------------------------------


def write_csv(path: Path, cases):
    lines = [",".join(WP_HEADER)]
    for c in cases:
        if c.error is None and c.time is None:
            continue
        k = c.counters
        lines.append(",".join([
            c.label, c.scene, c.rtol_text if c.rtol is not None else "",
            csv_float(c.error), csv_float(c.max_error), csv_float(c.time), csv_float(c.time_min),
            csv_int(k["steps"]), csv_int(k["rejected"]), csv_int(k["rhs_evals"]),
            csv_int(k["jac_evals"]), csv_int(k["lu_factorizations"]),
        ]))
    bc.write_atomic(path, "\n".join(lines) + "\n")


def scene_order(names):
    known = [s for s in bc.SCENES if s in names]
    return known + sorted(s for s in names if s not in bc.SCENES)


def plot(path: Path, curves, scenes, title):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = sorted({lab for s in curves.values() for lab in s},
                    key=lambda x: (KNOWN_SOLVERS.index(x.split("(")[0]) if x.split("(")[0] in KNOWN_SOLVERS
                                   else 99, x))
    cmap = plt.get_cmap("tab10")
    colors = {lab: cmap(i % 10) for i, lab in enumerate(labels)}
    markers = "os^vD<>ph*"
    n = max(1, len(scenes))
    ncols = 2 if n > 1 else 1
    nrows = math.ceil(n / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(6.5 * ncols, 5.0 * nrows), squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    for ax, scene in zip(axes.flat, scenes):
        sc = curves.get(scene, {})
        for lab in labels:
            if lab not in sc:
                continue
            # along the tolerance (or the step), loosest first, as work-precision diagrams do
            cs = sorted(sc[lab].cases, key=lambda c: (-(c.rtol or 0.0), -(c.h or 0.0)))
            ours = lab == OURS
            ax.plot([c.time for c in cs], [c.error for c in cs], marker=markers[labels.index(lab) % 10],
                    color=colors[lab], label=lab, lw=2.4 if ours else 1.2, ms=6 if ours else 4.5,
                    zorder=3 if ours else 2)
            if len({c.h for c in cs}) > 1:  # points that differ in their step: name it
                for c in cs:
                    if c.h is not None:
                        ax.annotate(c.label[len(c.solver) + 1:-1], (c.time, c.error), fontsize=7,
                                    color=colors[lab], xytext=(4, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"{scene} ({bc.SCENES[scene][1] if scene in bc.SCENES else '?'})")
        ax.set_xlabel("median wall time of one solve [s]")
        ax.set_ylabel("RMS error, relative to max|y_ref| per state [-]")
        ax.grid(True, which="major", alpha=0.4)
        ax.grid(True, which="minor", alpha=0.12)
        if sc:
            ax.legend(fontsize=8, loc="best")
        else:
            ax.text(0.5, 0.5, "no data", transform=ax.transAxes, ha="center")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def cpu_model():
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def ref_disagreement(text):
    """The reference's method disagreement (and self-convergence, if any) from ref/<scene>.txt."""
    out, conv = "n/a", None
    for line in text.splitlines():
        if line.startswith("max relative disagreement"):
            out = line.split(":")[-1].strip()
        if line.startswith("self-convergence") and "max |A - C|/max|A|" in line:
            conv = line.split("max |A - C|/max|A|")[1].split(",")[0].strip()
    return out if conv is None else f"{out} (self-convergence of the written method: {conv})"


def ref_rms_floor(text):
    """The larger of the reference's RMS disagreements (A-B, A-C) from ref/<scene>.txt, or None."""
    vals = []
    for line in text.splitlines():
        if line.startswith("RMS relative disagreement:"):
            vals.append(_float(line.split(":")[-1].strip()))
        if line.startswith("self-convergence") and ", RMS " in line:
            vals.append(_float(line.split(", RMS ")[1].split()[0]))
    vals = [v for v in vals if v is not None]
    return max(vals) if vals else None


def markdown(cases, curves, scenes, costs, ref_texts, notes, args, date, cores):
    L = []
    L.append("# Work-precision benchmark")
    L.append("")
    L.append(f"Snapshot of {date} on {cores} cores ({cpu_model()}, {platform.system()} "
             f"{platform.machine()}); regenerate with `{args.command}` (writes target/bench/ and copies "
             "this file and the figure to docs/).")
    L.append("")
    n_rounds = max((c.n_timed for c in cases), default=0)
    L.append(f"Timed rounds: {n_rounds} (median and minimum per case; round 0 is the warm-up). "
             f"Solvers run interleaved in shuffled order within each round.")
    L.append("")
    L.append("![error against run time](work_precision.png)")
    L.append("")
    L.append("Error: RMS over the grid t = k·0.01 s and over positions and velocities of "
             "(y − y_ref)/max|y_ref| per state. Time: median wall time of one complete solve "
             "(timed rounds only, warm-up excluded), minimum alongside in work_precision.csv. "
             "Times at an error level are interpolated log-log along each solver's Pareto front; "
             "“≤” means the solver's cheapest run is already more accurate, “—” that the level is "
             "out of its reach. Ratios are peer time / our time (the target is ≥ 2× against cvode).")
    L.append("")
    targets = []
    for scene in scenes:
        sc = curves.get(scene, {})
        cost = costs.get(scene)
        L.append(f"## {scene}")
        L.append("")
        form = bc.SCENES[scene][1] if scene in bc.SCENES else "?"
        file_ = bc.SCENES[scene][0] if scene in bc.SCENES else "?"
        L.append(f"{file_}, formulation {form}. Reference: max disagreement of its two methods "
                 f"{ref_disagreement(ref_texts.get(scene, ''))} (ref/{scene}.txt).")
        if cost:
            L.append(f"Costs (Rust, costs.csv, medians of {cost['rounds']} rounds; each call waiting for the last, as in the Newton "
                     f"iteration): right-hand side {cost['rhs_ns']:.4g} ns, LU factorisation "
                     f"{cost['lu_ns']:.4g} ns, LU solve {cost['solve_ns']:.4g} ns (independent calls: "
                     f"right-hand side {cost['rhs_throughput_ns']:.4g} ns, solve "
                     f"{cost['solve_throughput_ns']:.4g} ns).")
        L.append("")
        ours = sc.get(OURS)
        if ours is None:
            L.append(f"No usable `{OURS}` cases on this scene.")
            L.append("")
        peers = [lab for lab in sc if lab not in (OURS, FIXED) and not lab.startswith(FIXED + "(")]
        peers.sort(key=lambda x: (KNOWN_SOLVERS.index(x.split("(")[0]) if x.split("(")[0] in KNOWN_SOLVERS
                                  else 99, x))
        worst = {"cvode": None, "overhead": None, "steps": None, "compared": [], "missing": []}
        if ours is not None:
            # (b1) time at equal error
            L.append("Time at equal error (ratio = peer / ours):")
            L.append("")
            L.append("| error | bdf (ours) | " + " | ".join(peers) + " |")
            L.append("|---|---|" + "---|" * len(peers))
            for E in LEVELS:
                o = ours.at(E)
                if o is None:
                    worst["missing"].append(E)
                    continue
                cells = []
                for p in peers:
                    pe = sc[p].at(E)
                    cells.append("—" if pe is None else f"{est_text(pe)} ({ratio_text(pe, o)})")
                    if p == "cvode" and pe is not None and pe[0] == "=" and o[0] == "=":
                        r = pe[1] / o[1]
                        worst["cvode"] = r if worst["cvode"] is None else min(worst["cvode"], r)
                        worst["compared"].append(E)
                L.append(f"| {fmt_step(E)} | {est_text(o)} | " + " | ".join(cells) + " |")
            L.append("")
            # (b2) steps, lower bound, overhead
            L.append("Steps and the performance limit (lower bound = fewest steps any solver needed × "
                     "(rhs_ns + solve_ns); overhead = (time − rhs_evals·rhs_ns − lu·lu_ns − "
                     "newton_iters·solve_ns)/steps of our cases, interpolated):")
            L.append("")
            L.append("| error | our steps | fewest steps (solver) | ours / fewest | lower bound | "
                     "our time / bound | overhead ns/step |")
            L.append("|---|---|---|---|---|---|---|")
            step_cost = lambda c: c.counters["steps"]  # noqa: E731
            for E in LEVELS:
                o = ours.at(E)
                if o is None:
                    continue
                os_ = ours.at(E, step_cost)
                best = None
                for lab, cv in sc.items():
                    st = cv.at(E, step_cost)
                    if st is not None and st[0] == "=" and (best is None or st[1] < best[1][1]):
                        best = (lab, st)
                lb = None
                if best is not None and cost is not None:
                    lb = best[1][1] * (cost["rhs_ns"] + cost["solve_ns"]) * 1e-9
                ov = None
                if cost is not None:
                    ca, cb, w = o[2]
                    oa, ob = overhead_ns(ca, cost), overhead_ns(cb, cost)
                    if oa is not None and ob is not None:
                        ov = (1 - w) * oa + w * ob
                sr = None
                if os_ is not None and best is not None and os_[0] == "=":
                    sr = os_[1] / best[1][1]
                    worst["steps"] = sr if worst["steps"] is None else max(worst["steps"], sr)
                if ov is not None and o[0] == "=":
                    worst["overhead"] = ov if worst["overhead"] is None else max(worst["overhead"], ov)
                L.append(
                    f"| {fmt_step(E)} | {est_text(os_, fmt_int)} | "
                    f"{'—' if best is None else fmt_int(best[1][1]) + ' (' + best[0] + ')'} | "
                    f"{fmt_num(sr)}{'' if sr is None else '×'} | {fmt_time(lb)} | "
                    f"{'—' if lb is None or o[0] != '=' else fmt_num(o[1] / lb) + '×'} | {fmt_num(ov)} |"
                )
            L.append("")
        # (b3) the paper's fixed-step method at its own accuracy
        fixed = [c for lab, cv in sc.items() if cv.solver == FIXED for c in cv.cases]
        best_fixed = None
        if fixed:
            L.append("The paper's fixed-step BDF at its own accuracy against ours at the same error:")
            L.append("")
            L.append("| case | error | its time | our time at that error | ratio |")
            L.append("|---|---|---|---|---|")
            for c in sorted(fixed, key=lambda c: -(c.h or 0)):
                o = ours.at(c.error) if ours is not None else None
                pe = ("=", c.time, None)
                rt = ratio_text(pe, o)
                if o is not None:
                    r = c.time / o[1]
                    best_fixed = r if best_fixed is None else min(best_fixed, r)
                L.append(f"| {c.label} | {c.error:.2e} | {fmt_time(c.time)} | {est_text(o)} | {rt} |")
            L.append("")
        # (b3b) co-simulation against a host's integrator on the Model Exchange of the same FMU
        cs = [c for cv in sc.values() if cv.solver in ("fmu", "fmu3") for c in cv.cases if c.h == 1e-2]
        hosts = [(lab, sc[lab]) for lab in ("cvode-me", "fmpy-me") if lab in sc]
        if cs and hosts:
            L.append(f"Co-simulation at H = 10 ms against a host's integrator on the FMU's Model Exchange, "
                     f"at the co-simulation's error (target ≥ {TARGET_CS_OVER_ME:g}×):")
            L.append("")
            L.append("| co-simulation case | error | its time | host | host's time at that error | ratio |")
            L.append("|---|---|---|---|---|---|")
            for c in sorted(cs, key=lambda c: c.error):
                for lab, cv in hosts:
                    L.append(f"| {c.label} rtol={c.rtol_text} | {c.error:.2e} | {fmt_time(c.time)} | {lab} | "
                             f"{est_text(cv.at(c.error))} | {ratio_text(cv.at(c.error), ('=', c.time, None))} |")
            L.append("")
        # (b4) our cases
        mine = sorted((c for c in cases if c.scene == scene and c.solver == OURS and c.error is not None),
                      key=lambda c: -(c.rtol or 0))
        if mine:
            L.append("Our cases:")
            L.append("")
            L.append("| rtol | error | max error | median time | min time | steps | rejected | rhs | jac | "
                     "LU | Newton | overhead ns/step |")
            L.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
            for c in mine:
                k = c.counters
                L.append(
                    f"| {c.rtol_text} | {c.error:.2e} | {c.max_error:.2e} | {fmt_time(c.time)} | "
                    f"{fmt_time(c.time_min)} | {fmt_int(k['steps'])} | {fmt_int(k['rejected'])} | "
                    f"{fmt_int(k['rhs_evals'])} | {fmt_int(k['jac_evals'])} | "
                    f"{fmt_int(k['lu_factorizations'])} | {fmt_int(k['newton_iters'])} | "
                    f"{fmt_num(overhead_ns(c, cost))} |"
                )
            L.append("")
        targets.append((scene, worst, best_fixed))

    # targets
    L.append("## Targets")
    L.append("")
    L.append(f"Levels: every decade from {fmt_step(LEVELS[0])} to {fmt_step(LEVELS[-1])}. The cvode "
             "ratio is over the levels where both curves reach the level (listed); a level that our "
             "curve does not reach, or where cvode's cheapest run is already more accurate (≤) or "
             "it does not get there (—), is not compared.")
    L.append("")
    L.append(f"| scene | cvode / ours, worst level (≥ {TARGET_CVODE_RATIO:g}) | levels compared | "
             "fixed-step / ours, worst case (≥ 1000) | "
             f"overhead ns/step, worst level (≤ {TARGET_OVERHEAD_NS:g}) | "
             "our steps / fewest, worst level (≤ 1.3) |")
    L.append("|---|---|---|---|---|---|")
    for scene, w, bf in targets:
        compared = ", ".join(fmt_step(E) for E in w["compared"]) or "none"
        if w["missing"]:
            compared += f" (ours does not reach {', '.join(fmt_step(E) for E in w['missing'])})"
        L.append(f"| {scene} | {fmt_num(w['cvode'])} | {compared} | {fmt_num(bf)} | "
                 f"{fmt_num(w['overhead'])} | {fmt_num(w['steps'])} |")
    L.append("")

    # (c) DAE constraint residuals
    daes = [c for c in cases if c.residual is not None]
    if daes:
        L.append("## Constraint residuals of the DAE formulations")
        L.append("")
        L.append("Max over the grid of |u2 − u1(v1, θ1)| and |du2 − d/dt u1| (the index-1 formulation "
                 "drifts; dae_stabilized projects; scipy's dae_stabilized projects only its output).")
        L.append("")
        L.append("| scene | solver | rtol | max \\|u2 − u1\\| [m] | max \\|du2 − du1\\| [m/s] |")
        L.append("|---|---|---|---|---|")
        for c in sorted(daes, key=lambda c: (c.scene, c.label, -(c.rtol or 0), -(c.h or 0))):
            L.append(f"| {c.scene} | {c.label} | {c.rtol_text or '—'} | {c.residual[0]:.2e} | "
                     f"{c.residual[1]:.2e} |")
        L.append("")

    # (d) notes
    L.append("## Notes")
    L.append("")
    for scene in scenes:
        floor = ref_rms_floor(ref_texts.get(scene, ""))
        if floor is None:
            continue
        low = [c for c in cases if c.scene == scene and c.error is not None and c.error < 10 * floor]
        if low:
            notes.append(
                f"{scene}: {len(low)} case(s) have an error below 10× the reference's RMS disagreement "
                f"({floor:.1e}); there the error measures the reference as much as the solver: "
                + ", ".join(f"{c.label} rtol {c.rtol_text or '—'} ({c.error:.1e})" for c in low[:8])
                + (" …" if len(low) > 8 else ""))
    present = {c.solver for c in cases}
    for s in KNOWN_SOLVERS:
        if s not in present:
            notes.append(f"solver `{s}`: not in this run (unavailable or not configured)")
    for s in sorted(present):
        cs = [c for c in cases if c.solver == s]
        if cs and not any(c.usable for c in cs):
            notes.append(f"solver `{s}`: no usable case (all failed or missing)")
    for c in cases:
        if c.failures:
            sts = sorted({st for _, st in c.failures})
            rounds = sorted({rk for rk, _ in c.failures})
            notes.append(f"{c.label} on {c.scene} rtol {c.rtol_text or '—'}: status "
                         f"{'; '.join(sts)} (rounds {', '.join(map(str, rounds))})")
        if c.problem:
            notes.append(f"{c.label} on {c.scene} rtol {c.rtol_text or '—'}: {c.problem}")
    L.extend(f"- {n}" for n in notes) if notes else L.append("- all cases ran")
    L.append("")
    return "\n".join(L)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dir", type=Path, default=bc.DEFAULT_DIR)
    ap.add_argument("--docs-dir", type=Path, default=bc.REPO / "docs")
    ap.add_argument("--no-docs", action="store_true", help="do not copy the PNG and MD into docs/")
    ap.add_argument("--command", default="cargo xtask bench", help="the command named in the summary")
    args = ap.parse_args(argv)

    d = args.dir
    notes: list = []
    cases = load_cases(d, notes)
    for c in cases:
        summarize_rows(c)
    scenes = scene_order({c.scene for c in cases})
    refs, ref_texts = load_refs(d, [s for s in scenes if s in bc.SCENES], notes)
    sols = sol_index(d)
    for c in cases:
        if c.scene not in bc.SCENES:
            c.problem = "unknown scene"
            continue
        p = sols.get(c.key)
        if p is None:
            if not c.failures:
                c.problem = "no sol/ file"
            continue
        if c.scene not in refs:
            continue
        res = compute_error(c, p, refs[c.scene])
        if res is not None and bc.is_dae(bc.SCENES[c.scene][1]):
            c.residual = constraint_residual(c.scene, res[0], res[2])
    costs = load_costs(d, notes)
    curves = build_curves(cases)

    now = dt.datetime.now().astimezone()
    date = now.strftime("%Y-%m-%d")
    cores = os.cpu_count()
    d.mkdir(parents=True, exist_ok=True)
    write_csv(d / "work_precision.csv", cases)
    plot(d / "work_precision.png", curves, scenes,
         f"Work-precision: error against median run time — {date}, {cores} cores")
    md = markdown(cases, curves, scenes, costs, ref_texts, notes, args, date, cores)
    bc.write_atomic(d / "work_precision.md", md)
    if not args.no_docs:
        args.docs_dir.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(d / "work_precision.png", args.docs_dir / "work_precision.png")
        shutil.copyfile(d / "work_precision.md", args.docs_dir / "work_precision.md")
    n_ok = sum(c.usable for c in cases)
    print(f"bench_report: {len(cases)} cases, {n_ok} with error and time -> {d / 'work_precision.csv'}, "
          f".png, .md" + ("" if args.no_docs else f"; copied to {args.docs_dir}"), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
