"""The integrator's cost per step against the number of elements: `python bench/python/cost_per_step.py`.

`--variant beam=exact` adds the exact beam beside the quadratic one, each run interleaved with the
other's, and the ratio of their costs per step ("× first").

The paper's scene (reduced, rtol 1e-6, no output rows), n = 1, 2, 4, ..., 32, over a span that
takes the run about half a second; each run 5 times, interleaved across n, and the median of
wall time / accepted steps (the CLI's own figures). What a step costs grows with the size of
the Newton matrix: the table says by how much per doubling of n.
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


#: `--set KEY=VALUE` settings for every run (main's --set).
SETTINGS: list = []


def run(variant: tuple, n: int, t_end: float) -> tuple:
    cli, extra = variant
    args = [cli, "simulate", str(ROOT / "scenes" / "paper.toml"), "--elements", str(n),
            "--set", f"t_end={t_end!r}", "--set", f"dt_out={t_end!r}", "-o", "/dev/null"]
    for setting in SETTINGS + list(extra):
        args += ["--set", setting]
    err = subprocess.run(args, capture_output=True, text=True, check=True).stderr
    steps = int(re.search(r"steps (\d+)", err).group(1))
    jacs = int(re.search(r"Jacobians (\d+)", err).group(1))
    lus = int(re.search(r"LU factorizations (\d+)", err).group(1))
    wall = float(re.search(r"wall ([0-9.]+) ms", err).group(1)) / 1e3
    return steps, jacs, lus, wall


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cli", action="append",
                   help="a beam-body binary (repeat to compare builds side by side, each run "
                        "interleaved with the others'; default target/release/beam-body)")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--max-elements", type=int, default=32)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="a setting for every run (repeatable), e.g. stability_guard=false")
    p.add_argument("--variant", action="append", default=[], metavar="KEY=VALUE[,KEY=VALUE]",
                   help="besides each build as it is, the first build with these settings too "
                        "(repeatable), interleaved with the rest, e.g. beam=exact")
    args = p.parse_args(argv)
    SETTINGS[:] = args.set
    builds = args.cli or [str(ROOT / "target" / "release" / "beam-body")]
    clis = [(b, ()) for b in builds] + [(builds[0], tuple(v.split(","))) for v in args.variant]
    ns = [n for n in (1, 2, 4, 8, 16, 32) if n <= args.max_elements]
    # A span per n that costs the first build about 0.5 s, from a short probe.
    spans = {}
    for n in ns:
        _, _, _, wall = run(clis[0], n, 0.05)
        spans[n] = min(10.2, max(0.05, 0.05 * 0.5 / max(wall, 1e-4)))
    samples = {(c, n): [] for c in clis for n in ns}
    for _ in range(args.rounds):
        for n in ns:
            for c in clis:
                samples[c, n].append(run(c, n, spans[n]))
    for c in clis:
        print(f"\n{c[0]}" + (f" with {', '.join(c[1])}" if c[1] else "") + ":\n")
        print("| n | states | span [s] | steps | Jacobians | LU | µs per step (median) | "
              "× previous n |" + (" × first |" if c != clis[0] else ""))
        print("|---|---|---|---|---|---|---|---|" + ("---|" if c != clis[0] else ""))
        prev = None
        for n in ns:
            per_step = statistics.median(w / s for s, _, _, w in samples[c, n])
            steps, jacs, lus, _ = samples[c, n][0]
            ratio = f"{per_step / prev:.2f}" if prev else "–"
            line = (f"| {n} | {4 * n} | {spans[n]:.3g} | {steps:,} | {jacs:,} | {lus:,} | "
                    f"{1e6 * per_step:.3g} | {ratio} |")
            if c != clis[0]:
                first = statistics.median(w / s for s, _, _, w in samples[clis[0], n])
                line += f" {per_step / first:.2f} |"
            print(line)
            prev = per_step
    return 0


if __name__ == "__main__":
    sys.exit(main())
