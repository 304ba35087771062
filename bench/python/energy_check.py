"""The energy check's calibration (docs/stability.md, "The energy check"): every scene of
docs/model_error.md and a few more, 1 to 8 elements of both beams, every formulation, rtol 1e-2 to
1e-10, each run with energy_check = warn. For each: whether the check warned, the largest error of
the balance relative to the energy handled (the CLI's summary), and the error of v1 against the
same run at rtol 1e-10 (relative to its peak). Prints one table row per rtol.

    python bench/python/energy_check.py [path/to/beam-body] [--jobs N]

About 20 minutes on one core.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import csv
import io
import subprocess
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "scenes" / "paper.toml"
SCENES = {
    "paper": [], "small": ["phi_end=0.3"], "light": ["M2=1", "J_C=0.05"], "slow": ["t_rot=3"],
    "stiff": ["EI=1e7"], "input": ["phi_source=input"], "damped": ["damping_ratio=0.01"],
    "gravity": ["beam_gravity=true"],
}
RTOLS = [1e-2, 1e-3, 1e-4, 1e-6, 1e-8]
REFERENCE = 1e-10


def run(cli, scene, beam, n, rtol, formulation):
    args = [cli, "simulate", str(PAPER), "--elements", str(n), "--beam", beam, "--rtol", repr(rtol),
            "--formulation", formulation, "--set", "energy_check=warn"]
    for s in SCENES[scene]:
        args += ["--set", s]
    p = subprocess.run(args, capture_output=True, text=True)
    worst = None
    for line in p.stderr.splitlines():
        if "energy balance error" in line:
            worst = float(line.split("energy balance error")[1].split()[0])
    rows = list(csv.reader(io.StringIO(p.stdout)))
    v1 = np.array([float(r[1]) for r in rows[1:]]) if len(rows) > 1 else None
    return {"code": p.returncode, "worst": worst, "warned": "warning" in p.stderr, "v1": v1}


def jobs():
    for scene in SCENES:
        for beam, n in [("quadratic", 1), ("quadratic", 2), ("quadratic", 4), ("quadratic", 8),
                        ("exact", 2), ("exact", 4), ("exact", 8)]:
            if (n == 8 and scene not in ("paper", "damped", "input")) or (scene == "stiff" and n > 2):
                continue
            if scene == "gravity" and beam != "exact":
                continue
            for rtol in RTOLS + [REFERENCE]:
                yield scene, beam, n, rtol, "reduced"
    for formulation in ["linear", "dae", "dae_stabilized"]:
        for n in [1, 4]:
            for rtol in RTOLS + [REFERENCE]:
                yield "paper", "quadratic", n, rtol, formulation


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cli", nargs="?", default=str(ROOT / "target" / "release" / "beam-body"))
    ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args()
    todo = list(jobs())
    with cf.ThreadPoolExecutor(a.jobs) as ex:
        results = dict(zip(todo, ex.map(lambda j: run(a.cli, *j), todo)))
    print("| rtol | runs | to the end, silent | warned | stopped otherwise | largest balance error of the silent ones | largest v1 error of the silent ones |")
    print("|---|---|---|---|---|---|---|")
    for rtol in RTOLS + [REFERENCE]:
        mine = [(j, r) for j, r in results.items() if j[3] == rtol]
        silent = [(j, r) for j, r in mine if r["code"] == 0 and not r["warned"]]
        warned = sum(1 for _, r in mine if r["code"] == 0 and r["warned"])
        other = sum(1 for _, r in mine if r["code"] != 0)
        errors = []
        for j, r in silent:
            ref = results[(j[0], j[1], j[2], REFERENCE, j[4])]["v1"]
            if rtol != REFERENCE and ref is not None and r["v1"] is not None and len(ref) == len(r["v1"]):
                errors.append(float(np.max(np.abs(r["v1"] - ref)) / np.max(np.abs(ref))))
        worst = max((r["worst"] for _, r in silent if r["worst"] is not None), default=float("nan"))
        err = f"{max(errors):.1e}" if errors else "(reference)"
        print(f"| {rtol:.0e} | {len(mine)} | {len(silent)} | {warned} | {other} | {worst:.1e} | {err} |")


if __name__ == "__main__":
    main()
