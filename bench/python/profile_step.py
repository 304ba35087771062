"""Where the integrator's instructions go, per accepted step (`cargo xtask profile`).

Runs callgrind on `beam-body study` of one case of a scene (the study's runner needs no CSV
formatting, and with dt_out beyond t_end the outputs are taken only at 0 and t_end, so what is
counted is the integration),
with a binary built with symbols and line tables, and splits the instructions by where their
source lines are. Fat LTO inlines most functions into `Bdf::attempt_step`, so a function's
inclusive count says little; the source line of each instruction says where it came from:
- an instruction from one of our files belongs to that file's part (bdf.rs, coeffs.rs, lu.rs,
  guard.rs and eigen.rs, the model's files, sim.rs and signal.rs);
- one from the standard library (an inlined `+`, a slice index) belongs to the function it was
  inlined into, and so to that function's part;
- libm's instructions are the elementary functions' part (sin and cos, log, exp, pow).

callgrind counts instructions, not time: the counts repeat exactly for the same binary and input,
whatever else the machine does. Usage: profile_step.py BINARY SCENE.toml [--formulation F]
[--rtol X] [--label NAME] (several scenes: run it once per scene).
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

#: Our source files, by part.
PARTS = {
    "right-hand side (model)": ("model/dynamics.rs", "model/kinematics.rs", "model/systems.rs",
                                "model/phi.rs", "model/params.rs"),
    "coefficients": ("solver/coeffs.rs",),
    "LU factorisation and solves": ("solver/lu.rs",),
    "stability guard": ("solver/guard.rs", "solver/eigen.rs"),
    "integrator (bdf/)": ("solver/bdf/", "solver/config.rs", "solver/stats.rs",
                            "solver/system.rs"),
    "driver and output sampling": ("sim.rs", "model/signal.rs", "study/"),
    "sin and cos (libm)": ("sincos.rs", "k_sin.rs", "k_cos.rs", "rem_pio2", "/sin.rs",
                           "/cos.rs"),
    "log, exp, pow (libm, math.rs)": ("src/math.rs", "libm-"),
}

#: A function (its symbol) → the part of the code it belongs to, for inlined std code.
OWNERS = [
    ("model::", "right-hand side (model)"),
    ("solver::coeffs", "coefficients"),
    ("solver::lu", "LU factorisation and solves"),
    ("solver::guard", "stability guard"),
    ("solver::eigen", "stability guard"),
    ("solver::bdf", "integrator (bdf.rs)"),
    ("sim::", "driver and output sampling"),
    ("study::", "driver and output sampling"),
]

LINE = re.compile(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(\S.*?):(.*?)(?:\s+\[.*\])?$")


def part_of(file: str, function: str) -> str:
    for part, needles in PARTS.items():
        if any(n in file for n in needles):
            return part
    if "/rustc/" in file or "/library/" in file:
        for needle, part in OWNERS:
            if needle in function:
                return part
        return "std (formatting, threads, allocation)"
    return "process start and the rest"


def run_callgrind(binary: Path, scene: Path, formulation: str, rtol: str, tmp: Path,
                  options: list[str]) -> tuple[Path, int]:
    """callgrind (with `options`) on `beam-body study` of one case of the scene, outputs only
    at 0 and t_end; the callgrind file and the accepted steps."""
    # A study without parameters is one case: the scene itself.
    study = tmp / "one.toml"
    # Outputs only at 0 and t_end: the output sampling is not the integrator's cost.
    study.write_text(f'scene = "{scene}"\nformulation = "{formulation}"\n'
                     f'rtol = {rtol}\nmetrics = ["max_v1"]\n[set]\ndt_out = 1e6\n')
    out = tmp / "cg.out"
    run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                          *options, str(binary), "study", str(study), "--threads", "1", "-o",
                          str(tmp / "row.csv")], capture_output=True, text=True)
    if run.returncode != 0:
        print(run.stderr, file=sys.stderr)
        raise SystemExit(1)
    row = (tmp / "row.csv").read_text().splitlines()[1].split(",")
    return out, int(row[-1])


def arguments() -> argparse.ArgumentParser:
    """The arguments both profile scripts take: BINARY SCENE [--formulation F] [--rtol X]."""
    ap = argparse.ArgumentParser()
    ap.add_argument("binary")
    ap.add_argument("scene")
    ap.add_argument("--formulation", default="reduced")
    ap.add_argument("--rtol", default="1e-6")
    return ap


def main() -> int:
    ap = arguments()
    ap.add_argument("--label")
    args = ap.parse_args()
    scene = Path(args.scene).resolve()
    with tempfile.TemporaryDirectory() as tmp:
        out, steps = run_callgrind(Path(args.binary), scene, args.formulation, args.rtol,
                                   Path(tmp), [])
        ann = subprocess.run(["callgrind_annotate", "--auto=no", "--threshold=100", str(out)],
                             capture_output=True, text=True, check=True).stdout
    total, parts = 0, defaultdict(int)
    for line in ann.splitlines():
        m = LINE.match(line)
        if not m or "PROGRAM TOTALS" in line:
            continue
        count = int(m.group(1).replace(",", ""))
        parts[part_of(m.group(2), m.group(3))] += count
        total += count
    run_total = sum(v for k, v in parts.items() if k != "process start and the rest"
                    and not k.startswith("std"))
    label = args.label or f"{scene.stem} ({args.formulation}, rtol {args.rtol})"
    print(f"## {label}: {steps} accepted steps, {total:,} instructions in all\n")
    print("| part | instructions per step | share of the run |")
    print("|---|---|---|")
    for k, v in sorted(parts.items(), key=lambda kv: -kv[1]):
        share = f"{100 * v / run_total:.1f} %" if k in PARTS or k.startswith("integ") else "–"
        print(f"| {k} | {v / steps:,.0f} | {share} |")
    print(f"| **the run (the parts above with a share)** | **{run_total / steps:,.0f}** | 100 % |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
