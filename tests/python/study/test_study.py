"""Design studies (issue 15): the native runner `beam-body study`, and python/beam_body_study on
one machine and on Dask.

- the native runner, the chunked local engine and the Dask engine give the same table;
- a real deployment on loopback (a `dask scheduler` and two `dask worker` processes) loses no row
  and duplicates none when a worker is killed in the middle of the study;
- a re-run after an interrupted study computes only the missing chunks;
- bad study files are refused before anything runs, with the field named;
- the metrics are those of `beam-body simulate`'s outputs, with the static deflection of the
  independent oracle; the Latin hypercube samples fill every stratum of scipy's distributions.
"""

from __future__ import annotations

import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from conftest import PAPER_SCENE, REPO, TARGET, read_csv, run_cli, write_report

sys.path.insert(0, str(REPO / "python"))

import pyarrow as pa  # noqa: E402
import pyarrow.csv as pacsv  # noqa: E402
import pyarrow.parquet as pq  # noqa: E402

import oracle  # noqa: E402
from beam_body_study.columns import bare  # noqa: E402

REPORT = TARGET / "study-report.txt"

#: A small study with every kind of axis and a soft beam that leaves the range of validity.
MIXED = f"""
scene = "{PAPER_SCENE}"
metrics = ["residual_v1", "peak_M", "peak_N", "max_v1", "max_theta1", "energy_final"]
[set]
t_end = 3.0
dt_out = 0.01
[sampling]
samples = 40
seed = 11
[parameters.EI]
values = [1000, 20]
[parameters.t_rot]
start = 0.6
stop = 1.2
count = 3
[parameters.M2]
distribution = "uniform"
low = 6
high = 24
[parameters.J_C]
distribution = "normal"
mean = 1.0
sd = 0.15
min = 0.2
"""


def report(line: str) -> None:
    with open(REPORT, "a", encoding="utf-8") as f:
        f.write(line.rstrip() + "\n")


def front_env(beam_body) -> dict:
    return dict(os.environ, PYTHONPATH=str(REPO / "python"), BEAM_BODY_BIN=str(beam_body))


def front(beam_body, *args, timeout=300, check=True):
    """`python -m beam_body_study ARGS`; fails the test on a non-zero exit with check."""
    cmd = [sys.executable, "-m", "beam_body_study", *map(str, args)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                          env=front_env(beam_body), cwd=REPO)
    if check and proc.returncode != 0:
        pytest.fail(f"`{' '.join(cmd)}` exited with {proc.returncode}:\n{proc.stderr[-4000:]}",
                    pytrace=False)
    return proc


def plan(beam_body, study: Path) -> dict:
    return json.loads(run_cli(beam_body, ["study", study, "--plan"]))


def native_table(beam_body, study: Path, tmp: Path, threads=2) -> pa.Table:
    """The whole study from the native runner, read with the plan's column types."""
    out = tmp / f"native-{study.stem}.csv"
    run_cli(beam_body, ["study", study, "--threads", threads, "--quiet", "-o", out])
    types = {"int64": pa.int64(), "float64": pa.float64(), "string": pa.string()}
    schema = {c["name"]: types[c["type"]] for c in plan(beam_body, study)["columns"]}
    convert = pacsv.ConvertOptions(column_types=schema, strings_can_be_null=False)
    return pacsv.read_csv(out, convert_options=convert)


def bare_names(table: pa.Table) -> pa.Table:
    """The table with its columns named without their units (`peak_M [N.m]` -> `peak_M`)."""
    return table.rename_columns([bare(name) for name in table.column_names])


def same_rows(a: pa.Table, b: pa.Table) -> bool:
    return a.replace_schema_metadata(None).equals(b.replace_schema_metadata(None))


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def complete(table: pa.Table, cases: int) -> None:
    """Every case exactly once, in order."""
    case = table.column("case").to_numpy()
    assert len(case) == cases, f"{len(case)} rows for {cases} cases"
    assert len(np.unique(case)) == cases, "duplicated cases"
    assert np.array_equal(case, np.arange(cases)), "missing or misordered cases"


# --- the same table from every runner ---------------------------------------------------------


def test_native_local_and_dask_runners_give_identical_tables(beam_body, tmp_path):
    study = write(tmp_path / "mixed.toml", MIXED)
    info = plan(beam_body, study)
    assert info["cases"] == 2 * 3 * 40
    native = native_table(beam_body, study, tmp_path)
    complete(native, info["cases"])
    statuses = set(native.column("status").to_pylist())
    assert statuses == {"ok", "stopped"}, statuses  # EI = 20 leaves the range of validity
    stopped = [r for r in bare_names(native).to_pylist() if r["status"] == "stopped"]
    assert all(r["EI"] == 20 and r["peak_M"] is None and r["steps"] > 0 for r in stopped)
    assert all("range of validity" in r["message"] for r in stopped)

    local = tmp_path / "local.parquet"
    front(beam_body, "run", study, "-o", local, "--chunk-size", 37, "--threads", 2)
    dask = tmp_path / "dask.parquet"
    front(beam_body, "run", study, "-o", dask, "--engine", "dask", "--workers", 2,
          "--chunk-size", 50)
    t_local, t_dask = pq.read_table(local), pq.read_table(dask)
    assert same_rows(native, t_local), "the chunked local engine differs from the native runner"
    assert same_rows(native, t_dask), "the Dask engine differs from the native runner"
    meta = t_dask.schema.metadata
    assert meta[b"beam_body.study"].decode() == MIXED
    assert meta[b"beam_body.scene"].decode() == PAPER_SCENE.read_text()
    # CSV on request, the same rows again.
    csv_out = tmp_path / "local.csv"
    front(beam_body, "run", study, "-o", csv_out, "--chunk-size", 37)
    types = {f.name: f.type for f in native.schema}
    back = pacsv.read_csv(csv_out, convert_options=pacsv.ConvertOptions(
        column_types=types, strings_can_be_null=False))
    assert same_rows(native, back)


# --- a real deployment on loopback, and a worker that dies -------------------------------------


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


#: The longest a scheduler or a worker of the test may live [s].
LIFETIME = 300


def start(cmd, log: Path) -> subprocess.Popen:
    """A process in its own session, so that it and its children can be killed together, and
    killed by `timeout` after LIFETIME seconds whatever happens to the test."""
    out = open(log, "wb")
    return subprocess.Popen(["timeout", "-s", "KILL", str(LIFETIME), *map(str, cmd)], stdout=out,
                            stderr=subprocess.STDOUT, start_new_session=True,
                            env=dict(os.environ, PYTHONPATH=""))


def kill(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait(timeout=30)


def test_loopback_cluster_loses_no_row_when_a_worker_dies(beam_body, tmp_path):
    from distributed import Client

    study = write(tmp_path / "turns.toml", f"""
scene = "{PAPER_SCENE}"
metrics = ["residual_v1", "peak_M"]
[parameters.t_rot]
start = 0.5
stop = 3.0
count = 60
[parameters.M2]
start = 6
stop = 24
count = 50
""")
    cases = plan(beam_body, study)["cases"]
    native = native_table(beam_body, study, tmp_path)
    dask_bin = Path(sys.executable).parent / "dask"
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs, watcher = [], None
    try:
        procs.append(start([dask_bin, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                            "--no-dashboard"], tmp_path / "scheduler.log"))
        workers = {}
        for name in ("w1", "w2"):
            # No nanny: a killed worker stays dead, as a machine that goes away.
            workers[name] = start([dask_bin, "worker", address, "--name", name, "--nthreads",
                                   "1", "--no-nanny", "--no-dashboard"],
                                  tmp_path / f"{name}.log")
            procs.append(workers[name])
        watcher = Client(address, timeout="60s")
        watcher.wait_for_workers(2, timeout=60)

        out = tmp_path / "cluster.parquet"
        parts = tmp_path / "cluster.parquet.parts"
        began = time.perf_counter()
        run = subprocess.Popen(
            [sys.executable, "-m", "beam_body_study", "run", study, "-o", out, "--scheduler",
             address, "--chunk-size", "100", "--quiet"],
            env=front_env(beam_body), cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True)
        procs.append(run)

        def chunks_by(name):
            return [p for p in parts.glob("chunk-*.json")
                    if json.loads(p.read_text())["worker"] == name]

        # Kill w1 while it has chunks in hand, once it has finished some. It is stopped
        # (SIGSTOP) first, so that it can finish nothing between the look and the kill; the
        # pause lets what it sent before arrive and be saved.
        in_flight, deadline = [], time.monotonic() + 120
        w1_pid = workers["w1"].pid
        while not in_flight:
            assert time.monotonic() < deadline, "w1 never had a chunk in hand"
            assert run.poll() is None, f"the study ended before the kill: {run.stderr.read()}"
            if parts.exists() and len(chunks_by("w1")) >= 3:
                os.killpg(w1_pid, signal.SIGSTOP)
                time.sleep(0.5)
                info = watcher.scheduler_info()["workers"]
                for addr, keys in watcher.processing().items():
                    if info.get(addr, {}).get("name") == "w1" and keys:
                        in_flight = [int(str(k).rsplit("-", 1)[1]) for k in keys]
                if not in_flight:
                    os.killpg(w1_pid, signal.SIGCONT)
            if not in_flight:
                time.sleep(0.01)
        done_before = len(list(parts.glob("chunk-*.csv")))
        by_w1 = len(chunks_by("w1"))
        kill(workers["w1"])
        killed_at = time.perf_counter() - began

        _, err = run.communicate(timeout=300)
        assert run.returncode == 0, err
        seconds = time.perf_counter() - began
        table = pq.read_table(out)
        complete(table, cases)
        assert same_rows(native, table), "the table after the death differs from the native one"
        # The chunks w1 had in hand were computed by w2; those it finished are kept as they were.
        for k in in_flight:
            origin = json.loads((parts / f"chunk-{k:06d}.json").read_text())["worker"]
            assert origin == "w2", f"chunk {k}, in flight on w1 when it died, came from {origin}"
        assert len(chunks_by("w1")) == by_w1, "w1 delivered chunks after its death"
        assert len(chunks_by("w1")) + len(chunks_by("w2")) == math.ceil(cases / 100)
        report(f"worker death: {cases} cases in {math.ceil(cases / 100)} chunks of 100 on a "
               f"loopback scheduler with 2 workers; w1 killed (SIGKILL) at {killed_at:.2f} s "
               f"after {by_w1} chunks of its own ({done_before} in all), with chunks {in_flight} "
               f"in hand; w2 computed those, {len(chunks_by('w2'))} chunks in "
               f"all; study done at {seconds:.2f} s, {table.num_rows} rows, no duplicate, "
               f"identical to the native runner's table")
    finally:
        if watcher is not None:
            watcher.close()
        for p in reversed(procs):
            kill(p)


# --- re-running after an interruption ----------------------------------------------------------


def test_a_rerun_computes_only_the_missing_chunks(beam_body, tmp_path):
    study = write(tmp_path / "rerun.toml", f"""
scene = "{PAPER_SCENE}"
metrics = ["peak_M", "max_v1"]
[parameters.M2]
start = 6
stop = 24
count = 3000
""")
    native = native_table(beam_body, study, tmp_path)
    out = tmp_path / "rerun.parquet"
    parts = tmp_path / "rerun.parquet.parts"
    cmd = [sys.executable, "-m", "beam_body_study", "run", str(study), "-o", str(out),
           "--chunk-size", "100", "--threads", "1", "--quiet"]
    first = subprocess.Popen(cmd, env=front_env(beam_body), cwd=REPO,
                             stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 120
    while len(list(parts.glob("chunk-*.csv"))) < 4:
        assert time.monotonic() < deadline and first.poll() is None, "no chunks appeared"
        time.sleep(0.005)
    os.killpg(first.pid, signal.SIGKILL)  # as a crash: no clean-up
    first.wait(timeout=30)
    kept = {p.name: p.stat().st_mtime_ns for p in parts.glob("chunk-*.csv")}
    assert 4 <= len(kept) < 30 and not out.exists()
    # What a write cut short leaves: a temporary file, which the re-run removes.
    (parts / "chunk-000029.csv.tmp-999999").write_text("case,M2\n2900,")

    second = front(beam_body, *cmd[3:-1])
    assert f"30 chunks of 100; {len(kept)} done already" in second.stderr, second.stderr
    assert f"computed {30 - len(kept)} chunks ({(30 - len(kept)) * 100} cases)" in second.stderr
    for name, mtime in kept.items():
        assert (parts / name).stat().st_mtime_ns == mtime, f"{name} was computed again"
    assert not list(parts.glob("*.tmp-*")), "a partial file was left behind"
    assert same_rows(native, pq.read_table(out))

    # Once more: nothing to compute. A changed study is not mixed with the old chunks.
    third = front(beam_body, *cmd[3:-1])
    assert "computed 0 chunks" in third.stderr, third.stderr
    write(study, study.read_text().replace("count = 3000", "count = 3001"))
    fourth = front(beam_body, *cmd[3:-1], check=False)
    assert fourth.returncode == 2 and "--restart" in fourth.stderr, fourth.stderr
    report(f"re-run: killed after {len(kept)} of 30 chunks; the re-run computed "
           f"{30 - len(kept)}, left the {len(kept)} finished files untouched, and the table "
           f"equals the native runner's")


# --- bad study files ---------------------------------------------------------------------------

BAD = [
    ("[parameters.stiffness]\nvalues = [1]\n", "parameters.stiffness", "unknown parameter"),
    ("[parameters.M2]\nstart = -6\nstop = 24\ncount = 4\n", "parameters.M2.start",
     "positive"),
    ("[parameters.M2]\nstart = 6\nstop = 24\ncount = 0\n", "parameters.M2.count",
     "at least 1"),
    ("[sampling]\nsamples = 0\nseed = 1\n[parameters.EI]\ndistribution = \"uniform\"\n"
     "low = 900\nhigh = 1100\n", "sampling.samples", "at least 1"),
    ("[sampling]\nsamples = 10\nseed = 1\n[parameters.EI]\ndistribution = \"normal\"\n"
     "mean = 1000\nsd = 100\n", "parameters.EI", "unbounded below"),
]


@pytest.mark.parametrize("text,field,allowed", BAD, ids=[b[1] for b in BAD])
def test_a_bad_study_file_is_refused_before_anything_runs(beam_body, tmp_path, text, field,
                                                          allowed):
    study = write(tmp_path / "bad.toml", text)
    out = tmp_path / "out.parquet"
    for proc in (
        subprocess.run([str(beam_body), "study", str(study), "-o", str(tmp_path / "o.csv")],
                       capture_output=True, text=True, timeout=60),
        front(beam_body, "run", study, "-o", out, check=False),
    ):
        assert proc.returncode == 2, proc.stderr
        assert f"`{field}`" in proc.stderr and allowed in proc.stderr, proc.stderr
    assert not list(tmp_path.glob("o.csv*")), "the native runner wrote something"
    assert not out.exists() and not (tmp_path / "out.parquet.parts").exists()


# --- the metrics and the samples, checked independently ---------------------------------------


def test_metrics_are_those_of_the_simulated_outputs(beam_body, tmp_path):
    """residual_v1 about the bent state of a turn to pi/2, with the oracle's static deflection,
    and the peaks, against `beam-body simulate`'s CSV of the same case. The study takes its
    peaks from the integrator's dense output, so they lie above the CSV's on the study's own
    0.005 s grid, and within a fine grid's error of the peaks on a 0.1 ms grid: the grid misses
    about (omega*dt)^2/8 of a peak, 1.5e-6 at the second mode's 35 rad/s."""
    study = write(tmp_path / "half.toml", f"""
scene = "{PAPER_SCENE}"
[set]
t_end = 4.0
phi_end = 1.5707963267948966
dt_out = 0.005
[parameters.t_rot]
values = [0.7, 1.3]
[parameters.M2]
values = [8, 16]
""")
    table = bare_names(native_table(beam_body, study, tmp_path)).to_pylist()
    assert [r["status"] for r in table] == ["ok"] * 4
    for row in table:
        csv = run_cli(beam_body, ["simulate", PAPER_SCENE, "--set", "t_end=4.0", "--set",
                                  "phi_end=1.5707963267948966", "--set", "dt_out=0.0001",
                                  "--set", f"t_rot={row['t_rot']}", "--set", f"M2={row['M2']}"])
        fine = read_csv(csv)
        coarse = {k: v[::50] for k, v in fine.items()}
        assert np.allclose(coarse["t"][1:], np.arange(1, 801) * 0.005, rtol=0, atol=1e-12)
        params = {"M2": row["M2"]}
        v1_eq, _ = oracle.static_equilibrium(math.pi / 2, params)

        def peaks(data):
            after = data["t"] >= row["t_rot"]
            out = {"residual_v1": np.max(np.abs(data["v1"][after] - v1_eq))}
            for metric, column in (("peak_M", "M"), ("peak_N", "N"), ("peak_P", "P"),
                                   ("max_v1", "v1"), ("max_theta1", "theta1")):
                out[metric] = np.max(np.abs(data[column]))
            return out

        on_fine, on_coarse = peaks(fine), peaks(coarse)
        for metric, value in on_fine.items():
            # The oracle's v1_eq against the Rust one's: 1e-9 of the deflection.
            slack = 1e-9 * abs(v1_eq) if metric == "residual_v1" else 1e-12 * value
            assert row[metric] >= on_coarse[metric] - slack, (metric, row, on_coarse)
            assert row[metric] >= value - slack, (metric, row[metric], value)
            assert row[metric] - value <= 2e-6 * row[metric] + slack, (metric, row[metric], value)
        assert row["residual_v1"] < np.max(np.abs(fine["v1"]))
        assert row["energy_final"] == fine["energy"][-1]


def test_latin_hypercube_samples_fill_the_strata_of_scipys_distributions(beam_body, tmp_path):
    from scipy import stats

    n = 500
    study = write(tmp_path / "mc.toml", f"""
metrics = ["peak_M"]
[set]
t_end = 0.01
[sampling]
samples = {n}
seed = 2026
[parameters.EI]
distribution = "normal"
mean = 1000
sd = 150
min = 600
max = 1500
[parameters.M2]
distribution = "lognormal"
mean = 12
sd = 2.4
[parameters.r]
distribution = "uniform"
low = 0.4
high = 0.6
""")
    rows = bare_names(native_table(beam_body, study, tmp_path)).to_pydict()
    sigma = math.sqrt(math.log(1 + 0.2**2))
    lognormal = stats.lognorm(s=sigma, scale=12 * math.exp(-sigma**2 / 2))
    assert abs(lognormal.mean() - 12) < 1e-12 and abs(lognormal.std() - 2.4) < 1e-12
    dists = {
        "EI": stats.truncnorm((600 - 1000) / 150, (1500 - 1000) / 150, loc=1000, scale=150),
        "M2": lognormal,
        "r": stats.uniform(0.4, 0.2),
    }
    for name, dist in dists.items():
        u = dist.cdf(np.array(rows[name]))
        strata = np.floor(u * n + 1e-9).astype(int)
        assert sorted(strata) == list(range(n)), f"{name}: not one sample per stratum"
    # The columns are not aligned with one another (independent permutations).
    assert abs(np.corrcoef(rows["EI"], rows["M2"])[0, 1]) < 0.15


# --- the plots ---------------------------------------------------------------------------------


def test_plots_of_a_grid_and_of_a_sample(beam_body, tmp_path):
    study = write(tmp_path / "mixed.toml", MIXED)
    out = tmp_path / "mixed.parquet"
    front(beam_body, "run", study, "-o", out)
    table = pq.read_table(out)
    grid = tmp_path / "grid.parquet"
    g = write(tmp_path / "grid.toml", MIXED.split("[sampling]")[0] + """
[parameters.EI]
values = [1000, 20]
[parameters.t_rot]
start = 0.6
stop = 1.2
count = 4
""")
    front(beam_body, "run", g, "-o", grid)
    proc = front(beam_body, "plot", "heatmap", grid, "--x", "t_rot", "--y", "EI", "--z",
                 "residual_v1", "--contour", "0.3", "-o", tmp_path / "map.png")
    assert "4 × 2 grid, 4 cells without a value" in proc.stderr, proc.stderr
    proc = front(beam_body, "plot", "hist", out, "--metric", "peak_M", "--quantile", "0.99",
                 "-o", tmp_path / "hist.png")
    values = [v for v in bare_names(table).column("peak_M").to_pylist() if v is not None]
    q99 = np.quantile(values, 0.99)
    assert f"q99 = {q99:.6g}" in proc.stderr and f"{len(values)} runs" in proc.stderr
    for png in ("map.png", "hist.png"):
        assert (tmp_path / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # A heatmap of columns that are not a grid is refused with a reason.
    proc = front(beam_body, "plot", "heatmap", out, "--x", "M2", "--y", "EI", "--z", "peak_M",
                 "-o", tmp_path / "no.png", check=False)
    assert proc.returncode == 2 and "not the table's grid" in proc.stderr, proc.stderr


def test_turn_map_and_hinge_moment_metrics_against_the_oracle(beam_body, tmp_path):
    """The quantities of docs/design-studies.md's examples (residual_v1 of the turn map, peak_M of the
    hinge-moment study) for four cases of the reduced model, against the sympy oracle's own equations
    integrated by scipy (DOP853, rtol 1e-13; no Rust): residual_v1 the largest |v1| from the end of the
    turn (v1_eq = 0 at phi = pi), peak_M the largest |M| of its d'Alembert reactions, both on a 0.2 ms
    grid (the oracle's; the study takes its peaks from the dense output). The independent check beside
    test_example_study.py's change detector, whose figures this code wrote."""
    study = write(tmp_path / "map.toml", f"""
scene = "{PAPER_SCENE}"
metrics = ["residual_v1", "peak_M"]
rtol = 1e-10
[set]
t_end = 6.0
[parameters.t_rot]
values = [1.0, 3.0]
[parameters.M2]
values = [8, 16]
""")
    rows = bare_names(native_table(beam_body, study, tmp_path)).to_pylist()
    assert [r["status"] for r in rows] == ["ok"] * 4
    worst = {"residual_v1": 0.0, "peak_M": 0.0}
    for row in rows:
        scene = oracle.scene_with_defaults({"t_rot": row["t_rot"], "M2": row["M2"], "t_end": 6.0})
        t = np.arange(0, 30001) * 2e-4
        _, Y = oracle.reference_solution("reduced", scene, t_eval=t)
        p = {k: scene[k] for k in oracle.PARAM_NAMES}
        phi, dphi, ddphi = oracle.phi_law(t, scene["phi0"], scene["phi_end"], scene["t_rot"])
        X = np.stack([phi, dphi, ddphi, Y[:, 0], Y[:, 1], Y[:, 2], Y[:, 3], 0 * t, 0 * t], axis=1)
        X[:, 7:9] = oracle.accelerations("reduced", X, p)
        M = oracle.hinge_reactions_reduced(X, p)[:, 2]
        want = {"residual_v1": np.max(np.abs(Y[t >= row["t_rot"], 0])), "peak_M": np.max(np.abs(M))}
        for metric, value in want.items():
            worst[metric] = max(worst[metric], abs(row[metric] - value) / value)
    write_report("study-metrics-oracle", f"# study metrics against the oracle: {worst}")
    assert worst["residual_v1"] < 1e-6 and worst["peak_M"] < 1e-6, worst  # measured 2.3e-7, 1.1e-7
