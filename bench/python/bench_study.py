"""Throughput of the study runners, side by side in one run (`cargo xtask bench-study`).

The study: examples/hinge_moment_mc.toml (10,000 Latin hypercube samples of EI, M2, J_C on the
paper's scene, 10.2 s each) with the paper's output grid, dt_out = 8.5 ms. Each round runs,
in a shuffled order:

- native-1, native-2: `beam-body study` on 1 and 2 threads (no chunks; the reference);
- local-2: `python -m beam_body_study run` with the local engine (chunks of 625 cases, each
  one call of the CLI on 2 threads);
- localcluster-1, localcluster-2: the Dask engine on a LocalCluster of 1 and 2 single-threaded
  workers, threads of the client's process (the default; its start-up is timed apart);
- localcluster-2-processes: the same with 2 worker processes (each with its nanny);
- loopback-2: the Dask engine on a `dask scheduler` with two `dask worker` processes on
  127.0.0.1, started before the timed run.

Reported: the median over the rounds of the wall time of the computing part and its runs per
second, and the median over the rounds of its ratio to the native runner on as many cores in the
same round. On this machine the rounds differ by more than the runners do, so the overhead of a
path is measured apart, in each round: a study of 400 cases that cost almost nothing (t_end =
8.5 ms), in chunks of one case, through each path on 2 cores. Its time per chunk, times the 2
cores, is what a chunk costs a path beside its cases; divided by a default chunk's cases, the
overhead per case. Also the cost of one chunk's CLI call alone (an empty chunk: process start,
parsing the study, the temporary files), the basis of the choice of the CLI over Python bindings
(docs/decisions.md, *Design studies*).

Writes target/bench/study.csv (every run) and target/bench/study.md; with the full run also
docs/study.md.
"""

from __future__ import annotations

import argparse
import csv
import os
import random
import re
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python"))

from beam_body_study import runner, worker  # noqa: E402

OUT = REPO / "target" / "bench"
CHUNK = 625  # 16 chunks of the 10,000 cases


def study_file(tmp: Path) -> Path:
    text = (REPO / "examples" / "hinge_moment_mc.toml").read_text()
    text = re.sub(r"dt_out = 0\.001 .*", "dt_out = 0.0085", text)
    text = text.replace('scene = "../scenes/paper.toml"',
                        f'scene = "{REPO / "scenes" / "paper.toml"}"')
    path = tmp / "mc.toml"
    path.write_text(text)
    return path


def tiny_study_file(tmp: Path) -> Path:
    """400 cases of almost no work: what a chunk costs beside its cases."""
    text = study_file(tmp).read_text()
    text = text.replace("samples = 10000", "samples = 400")
    text = re.sub(r"^metrics = .*$", 'metrics = ["peak_M"]', text, flags=re.M)
    text = text.replace("dt_out = 0.0085", "dt_out = 0.0085\nt_end = 0.0085")
    path = tmp / "tiny.toml"
    path.write_text(text)
    return path


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Loopback:
    """A `dask scheduler` and two `dask worker` processes on 127.0.0.1."""

    def __init__(self, tmp: Path):
        from distributed import Client

        dask = Path(sys.executable).parent / "dask"
        port = free_port()
        self.address = f"tcp://127.0.0.1:{port}"
        began = time.perf_counter()
        self.procs = [self._start([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                                   "--no-dashboard"], tmp / "scheduler.log")]
        for name in ("w1", "w2"):
            self.procs.append(self._start([dask, "worker", self.address, "--name", name,
                                           "--nthreads", "1", "--no-dashboard"],
                                          tmp / f"{name}.log"))
        with Client(self.address, timeout="60s") as c:
            c.wait_for_workers(2, timeout=60)
        self.startup = time.perf_counter() - began

    @staticmethod
    def _start(cmd, log):
        return subprocess.Popen(cmd, stdout=open(log, "wb"), stderr=subprocess.STDOUT,
                                start_new_session=True, env=dict(os.environ, PYTHONPATH=""))

    def close(self):
        for p in reversed(self.procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
                try:
                    p.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    os.killpg(p.pid, signal.SIGKILL)
                    p.wait()


def run_native(cli: str, study: Path, threads: int, tmp: Path) -> dict:
    out = tmp / f"native-{threads}.csv"
    began = time.perf_counter()
    subprocess.run([cli, "study", str(study), "--threads", str(threads), "--quiet", "-o",
                    str(out)], check=True)
    return {"seconds": time.perf_counter() - began, "startup": 0.0}


def run_front(study: Path, tmp: Path, name: str, chunk_size=CHUNK, **kw) -> dict:
    out = tmp / f"{name}.parquet"
    began = time.perf_counter()
    summary = runner.run_study(study, out, restart=True, chunk_size=chunk_size, quiet=True, **kw)
    total = time.perf_counter() - began
    # The computing part: without the start of a LocalCluster (timed apart).
    return {"seconds": summary["seconds"] - summary["startup_seconds"],
            "startup": summary["startup_seconds"], "total": total}


def chunk_call_cost(cli: str, study: Path, calls: int) -> float:
    """The median seconds of one empty chunk through worker.run_chunk."""
    plan = runner.plan(study, cli)
    spec = plan.spec()
    times = []
    for _ in range(calls):
        began = time.perf_counter()
        worker.run_chunk(spec, 0, 0, 0)
        times.append(time.perf_counter() - began)
    return statistics.median(times)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="2 rounds instead of 5")
    args = ap.parse_args()
    rounds = 2 if args.quick else 5
    cli = runner.default_cli()
    OUT.mkdir(parents=True, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-study-") as t:
        tmp = Path(t)
        study = study_file(tmp)
        tiny = tiny_study_file(tmp)
        cases = runner.plan(study, cli).cases
        tiny_cases = runner.plan(tiny, cli).cases
        loop = Loopback(tmp)
        try:
            configs = {
                "native-1": lambda: run_native(cli, study, 1, tmp),
                "native-2": lambda: run_native(cli, study, 2, tmp),
                "local-2": lambda: run_front(study, tmp, "local", threads=2, cli=cli),
                "localcluster-1": lambda: run_front(study, tmp, "lc1", engine="dask", workers=1,
                                                    cli=cli),
                "localcluster-2": lambda: run_front(study, tmp, "lc2", engine="dask", workers=2,
                                                    cli=cli),
                "localcluster-2-processes": lambda: run_front(study, tmp, "lc2p", engine="dask",
                                                              workers=2, cli=cli,
                                                              local_processes=True),
                "loopback-2": lambda: run_front(study, tmp, "loop", engine="dask",
                                                scheduler=loop.address, cli=cli),
            }
            # The same paths on the tiny study, chunks of one case.
            per_chunk = {
                "local-2": lambda: run_front(tiny, tmp, "t-local", 1, threads=2, cli=cli),
                "localcluster-2": lambda: run_front(tiny, tmp, "t-lc2", 1, engine="dask",
                                                    workers=2, cli=cli),
                "localcluster-2-processes": lambda: run_front(tiny, tmp, "t-lc2p", 1,
                                                              engine="dask", workers=2, cli=cli,
                                                              local_processes=True),
                "loopback-2": lambda: run_front(tiny, tmp, "t-loop", 1, engine="dask",
                                                scheduler=loop.address, cli=cli),
            }
            chunk_rows = []
            rng = random.Random(15)
            configs["native-2"]()  # warm-up: the binary and the scene in the page cache
            for r in range(1, rounds + 1):
                order = list(configs)
                rng.shuffle(order)
                for name in order:
                    res = configs[name]()
                    rows.append({"round": r, "config": name, **res})
                    print(f"round {r}: {name:<15} {res['seconds']:7.3f} s "
                          f"({cases / res['seconds']:6.0f} runs/s)", file=sys.stderr)
                for name in rng.sample(list(per_chunk), len(per_chunk)):
                    res = per_chunk[name]()
                    chunk_rows.append({"round": r, "config": name, **res})
                    print(f"round {r}: {name:<15} chunks of 1 case: "
                          f"{2e3 * res['seconds'] / tiny_cases:6.2f} ms per chunk",
                          file=sys.stderr)
            chunk_cost_cli = chunk_call_cost(cli, study, 40)
        finally:
            loop.close()
        loop_startup = loop.startup

    with open(OUT / "study.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["round", "study", "config", "seconds", "startup",
                                          "total"])
        w.writeheader()
        for study_name, rs in (("mc-10000", rows), ("tiny-400-chunks-of-1", chunk_rows)):
            for row in rs:
                w.writerow({"study": study_name, **{k: row.get(k, "") for k in w.fieldnames
                                                    if k != "study"}})

    configs = list(dict.fromkeys(r["config"] for r in rows))
    med = {c: statistics.median(r["seconds"] for r in rows if r["config"] == c) for c in configs}
    startup = {c: statistics.median(r["startup"] for r in rows if r["config"] == c)
               for c in configs}
    cores = {"native-1": 1, "native-2": 2, "local-2": 2, "localcluster-1": 1,
             "localcluster-2": 2, "localcluster-2-processes": 2, "loopback-2": 2}
    by_round = {}
    for r in rows:
        by_round.setdefault(r["round"], {})[r["config"]] = r["seconds"]

    def ratio(c):
        ref = "native-1" if cores[c] == 1 else "native-2"
        return statistics.median(rr[c] / rr[ref] for rr in by_round.values())

    per_case = med["native-1"] / cases
    chunk_cost = {c: statistics.median(2 * r["seconds"] / tiny_cases for r in chunk_rows
                                       if r["config"] == c)
                  for c in dict.fromkeys(r["config"] for r in chunk_rows)}
    spread = {c: (min(r["seconds"] for r in rows if r["config"] == c),
                  max(r["seconds"] for r in rows if r["config"] == c)) for c in configs}
    lines = [
        "# Study throughput",
        "",
        f"`cargo xtask bench-study`: {cases:,} cases (examples/hinge_moment_mc.toml at "
        f"dt_out = 8.5 ms), {rounds} rounds in a shuffled order, medians; this machine has "
        f"{os.cpu_count()} cores. The time is that of the computing part: a LocalCluster's "
        "start is in its own column, and the loopback scheduler and workers (a `dask scheduler` "
        "and two `dask worker` processes with their nannies) were started before the rounds "
        f"({loop_startup:.2f} s). The ratio is the median over the rounds of the time over the "
        "native runner's on as many cores in the same round.",
        "",
        "| runner | cores | time [s] (min–max) | runs/s | time / native | cluster start [s] |",
        "|---|---|---|---|---|---|",
    ]
    for c in sorted(configs, key=list(cores).index):
        s = med[c]
        start = f"{startup[c]:.2f}" if startup[c] else "–"
        lo, hi = spread[c]
        lines.append(f"| {c} | {cores[c]} | {s:.2f} ({lo:.2f}–{hi:.2f}) | {cases / s:,.0f} | "
                     f"{ratio(c):.3f} | {start} |")
    lines += [
        "",
        "The rounds differ by more than the runners do. What each path costs beside its cases, "
        f"measured apart: {tiny_cases} cases of almost no work (t_end = 8.5 ms) in chunks of one "
        "case, on 2 cores; the time per chunk times 2 is a chunk's cost in core time, and over "
        f"a default chunk of {CHUNK} cases it is the overhead per case (one case costs "
        f"{per_case * 1e3:.3f} ms on one core):",
        "",
        "| path | per chunk [ms of core time] | per case, chunks of "
        f"{CHUNK} [µs] | share of a case |",
        "|---|---|---|---|",
    ]
    for c, o in sorted(chunk_cost.items(), key=lambda kv: list(cores).index(kv[0])):
        lines.append(f"| {c} | {o * 1e3:.2f} | {o / CHUNK * 1e6:.2f} | "
                     f"{o / CHUNK / per_case * 100:.2f} % |")
    lines += [
        "",
        f"Of that, one chunk's call of the CLI alone (an empty chunk: the process, the study's "
        f"parsing, the temporary files) costs {chunk_cost_cli * 1e3:.2f} ms, "
        f"{chunk_cost_cli / (CHUNK * per_case) * 100:.2f} % of a chunk of {CHUNK} cases: what "
        "Python bindings could save at most.",
    ]
    text = "\n".join(lines) + "\n"
    (OUT / "study.md").write_text(text)
    if not args.quick:
        (REPO / "docs" / "study.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
