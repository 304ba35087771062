"""Runs a study in chunks, on this machine or on a Dask cluster, and writes its table.

The study is cut into chunks of consecutive cases. Each chunk is one call of the native
runner, `beam-body study STUDY --cases A..B`, which writes CSV; its rows depend only on the
case numbers, so the chunks can run anywhere, in any order. Finished chunks are kept in a
work directory beside the output (`OUT.parts/`), each written atomically under its chunk
number: a re-run computes only the chunks that are missing, and a chunk computed twice (a
worker that died after finishing it) is still one file. The table is assembled from the
chunks, checked (every case once, in order), and written as Parquet or CSV.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from . import worker
from .errors import Interrupted, StudyError

#: The default number of cases per chunk, and the least number of chunks (for the balance
#: of the load between workers and for what an interruption loses).
CHUNK_CASES = 1000
MIN_CHUNKS = 16

#: The most cases a run accepts unless told otherwise (`--max-cases`; the CLI's default too):
#: a typo in a grid's count should be refused, not started as a month of work.
MAX_CASES = 1_000_000

#: The table's formats, by the output's extension.
FORMATS = {".parquet": "parquet", ".csv": "csv"}

__all__ = ["Interrupted", "StudyError", "plan", "run_study"]


def default_cli() -> str:
    """$BEAM_BODY_BIN, else target/release/beam-body of this checkout, else beam-body on PATH."""
    env = os.environ.get("BEAM_BODY_BIN")
    if env:
        return env
    local = Path(__file__).resolve().parents[2] / "target" / "release" / "beam-body"
    if local.is_file():
        return str(local)
    found = shutil.which("beam-body")
    if found:
        return found
    raise StudyError(
        "the beam-body CLI was not found: build it (cargo build --release), put it on PATH, "
        "or pass --cli PATH"
    )


@dataclass
class Plan:
    """A checked study: what `beam-body study --plan` says of it, and its texts."""

    path: Path
    cli: str
    cli_sha256: str
    #: The CLI's hash of the parsed study and of its fully resolved base scene: a comment,
    #: the layout or the order of keys does not change it, a value does.
    fingerprint: str
    cases: int
    columns: list
    parameters: list
    metrics: list
    study_text: str
    scene_text: str | None

    def spec(self) -> dict:
        """What a worker needs to run a chunk (see worker.run_chunk)."""
        return {
            "cli": self.cli,
            "cli_sha256": self.cli_sha256,
            "study_text": self.study_text,
            "scene_text": self.scene_text,
        }

    def identity(self, chunk_size: int) -> dict:
        """What makes finished chunks reusable: the study and its scene as parsed (not their
        texts: a comment must not throw away hours of chunks), the binary, the chunking (kept
        in a work directory's manifest)."""
        return {
            "fingerprint": self.fingerprint,
            "cli_sha256": self.cli_sha256,
            "chunk_size": chunk_size,
        }

    def key_tag(self, chunk_size: int) -> str:
        """One short hash of the identity (the tag of a study's Dask tasks)."""
        return sha256_text(json.dumps(self.identity(chunk_size), sort_keys=True))[:16]

    def header(self) -> str:
        """The CSV header line the CLI writes for this study (without its newline)."""
        return ",".join(c["name"] for c in self.columns)


def plan(study: str | Path, cli: str | None = None) -> Plan:
    """Checks the study with the CLI (nothing runs) and reads what a run needs."""
    cli = os.path.abspath(cli or default_cli())
    if not os.path.isfile(cli):
        raise StudyError(f"the beam-body CLI {cli} does not exist")
    path = Path(study)
    proc = subprocess.run([cli, "study", str(path), "--plan"], capture_output=True, text=True)
    if proc.returncode != 0:
        raise StudyError(proc.stderr.strip().removeprefix("error: "))
    info = json.loads(proc.stdout)
    if "fingerprint" not in info:
        # The work directory's identity rests on it; without it a re-run could not tell a
        # changed study from a reformatted one.
        raise StudyError(f"the beam-body CLI {cli} is too old for this tool: its `study --plan` "
                         "gives no fingerprint; build the current one (cargo build --release)")
    scene_text = Path(info["scene"]).read_text(encoding="utf-8") if info["scene"] else None
    return Plan(
        path=path,
        cli=cli,
        cli_sha256=worker.file_sha256(cli),
        fingerprint=info["fingerprint"],
        cases=info["cases"],
        columns=info["columns"],
        parameters=info["parameters"],
        metrics=info["metrics"],
        study_text=path.read_text(encoding="utf-8"),
        scene_text=scene_text,
    )


def default_chunk_size(cases: int) -> int:
    """About CHUNK_CASES cases per chunk, but at least MIN_CHUNKS chunks (and 1 case)."""
    return max(1, min(CHUNK_CASES, math.ceil(cases / MIN_CHUNKS)))


def output_format(out: Path, fmt: str | None) -> str:
    """The table's format: `fmt`, else the output's extension; an unknown extension is
    refused rather than guessed (`-o x.json` must not quietly hold Parquet)."""
    if fmt is not None:
        if fmt not in FORMATS.values():
            raise StudyError(f"--format {fmt}: must be parquet or csv")
        return fmt
    found = FORMATS.get(out.suffix.lower())
    if found is None:
        ext = f"not {out.suffix}" if out.suffix else "and the name has no extension"
        raise StudyError(f"-o {out}: the table is written as .parquet or .csv, {ext} (or name "
                         "the format with --format parquet|csv)")
    return found


def sha256_text(text: str | None) -> str:
    return hashlib.sha256((text or "").encode()).hexdigest()


#: The files a work directory holds, which --restart removes (nothing else is touched).
OWN_FILES = ("manifest.json", "lock", "chunk-*.csv", "chunk-*.json", "*.tmp-*")


class WorkDir:
    """The finished chunks of one study: `chunk-NNNNNN.csv` and its `.json` (who computed it),
    beside `manifest.json`. One run at a time holds it (`lock`, where the platform has flock)."""

    def __init__(self, path: Path, plan: Plan, chunk_size: int, restart: bool):
        self.path = path
        self.chunk_size = chunk_size
        self.cases = plan.cases
        self.chunks = math.ceil(plan.cases / chunk_size) if plan.cases else 0
        parts = plan.identity(chunk_size)
        manifest = path / "manifest.json"
        path.mkdir(parents=True, exist_ok=True)
        self._lock = self._take_lock()
        if manifest.exists() and not restart:
            try:
                old = json.loads(manifest.read_text())
            except ValueError:
                raise StudyError(f"{manifest} is not a manifest of this tool: pass --restart "
                                 "to discard the work directory's chunks, or another "
                                 "--work-dir") from None
            if "fingerprint" not in old:
                raise StudyError(f"{path} holds the chunks of an older version of this tool, "
                                 "which identified a study by its text: pass --restart to "
                                 "discard them, or another --work-dir")
            if any(old.get(k) != v for k, v in parts.items()):
                names = {"fingerprint": "the study or its base scene",
                         "cli_sha256": "the beam-body binary", "chunk_size": "the chunk size"}
                changed = [names[k] for k in names if old.get(k) != parts[k]]
                what = " and ".join([", ".join(changed[:-1]), changed[-1]] if len(changed) > 1
                                    else changed)
                raise StudyError(
                    f"{path} holds the chunks of an earlier run, and {what} changed since: "
                    f"pass --restart to discard them, or another --work-dir"
                )
        if restart:
            for pattern in OWN_FILES:
                for f in path.glob(pattern):
                    if f.name != "lock":
                        f.unlink()
        elif not manifest.exists() and any(path.glob("chunk-*.csv")):
            raise StudyError(f"{path} holds chunk files but no manifest.json: pass --restart to "
                             "discard them, or another --work-dir")
        for stale in path.glob("*.tmp-*"):  # left by an interrupted run (the lock is ours)
            stale.unlink()
        if not manifest.exists():
            atomic_write(
                manifest,
                json.dumps(
                    {
                        **parts,
                        "study": str(plan.path),
                        "cases": plan.cases,
                        "chunks": self.chunks,
                    },
                    indent=1,
                ).encode(),
            )

    def _take_lock(self):
        """An exclusive flock on `lock`, held while this object lives; None without fcntl."""
        try:
            import fcntl
        except ImportError:  # Windows: no lock
            return None
        f = open(self.path / "lock", "a+")
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.close()
            raise StudyError(f"another run is using {self.path}") from None
        return f

    def bounds(self, k: int) -> tuple:
        return k * self.chunk_size, min((k + 1) * self.chunk_size, self.cases)

    def csv(self, k: int) -> Path:
        return self.path / f"chunk-{k:06d}.csv"

    def done(self) -> set:
        return {k for k in range(self.chunks) if self.csv(k).exists()}

    def save(self, k: int, result: dict) -> None:
        """Stores a chunk's rows after checking that they are its cases; the same rows
        again (a chunk computed twice) replace the file with identical bytes."""
        data = result["csv"]
        start, stop = self.bounds(k)
        lines = data.decode().splitlines()
        cases = [int(line.split(",", 1)[0]) for line in lines[1:] if line]
        if cases != list(range(start, stop)):
            raise StudyError(f"chunk {k}: the rows are not cases {start}..{stop}")
        info = {key: result[key] for key in ("worker", "host", "seconds")}
        atomic_write(self.path / f"chunk-{k:06d}.json", json.dumps(info).encode(), durable=False)
        atomic_write(self.csv(k), data)


def atomic_write(path: Path, data: bytes, durable: bool = True) -> None:
    """Writes a file whole or not at all: a temporary file in the same directory, renamed.
    `durable` flushes it to the disk before the rename, so that a power cut cannot leave the
    new name on an empty file (2 ms here; the chunks' rows need it, their notes do not)."""
    tmp = path.with_name(f"{path.name}.tmp-{os.getpid()}")
    with open(tmp, "wb") as f:
        f.write(data)
        if durable:
            f.flush()
            os.fsync(f.fileno())
    os.replace(tmp, path)


class Progress:
    """Chunks and cases done, the rate and the time left, on stderr."""

    def __init__(self, total_cases: int, chunks: int, skipped: int, quiet: bool):
        self.total, self.chunks, self.quiet = total_cases, chunks, quiet
        self.skipped_chunks = skipped
        self.start = time.perf_counter()
        self.done_cases = 0
        self.done_chunks = 0
        self.terminal = sys.stderr.isatty()
        self.last = 0.0
        #: Seconds to start the cluster and connect to it (the Dask engine).
        self.startup = 0.0

    def add(self, cases: int, final: bool = False) -> None:
        self.done_cases += cases
        self.done_chunks += 1
        now = time.perf_counter()
        if self.quiet or (not final and now - self.last < (0.25 if self.terminal else 5.0)):
            return
        self.last = now
        secs = max(now - self.start, 1e-9)
        rate = self.done_cases / secs
        left = self.total - self.done_cases
        eta = f"{left / rate:.0f} s left" if rate > 0 else ""
        line = (
            f"study: {self.done_chunks + self.skipped_chunks}/{self.chunks} chunks, "
            f"{self.done_cases} of {self.total} cases to compute, {rate:.0f} cases/s, {eta}"
        )
        print(("\r" + line + "\x1b[K") if self.terminal else line, end="" if self.terminal else "\n",
              file=sys.stderr, flush=True)

    def finish(self) -> None:
        if self.terminal and not self.quiet and self.last:
            print(file=sys.stderr)


def run_local(plan: Plan, work: WorkDir, todo: list, threads: int | None, progress: Progress):
    """Each chunk as one call of the CLI on every core (or `threads`), one after another."""
    threads = threads if threads is not None else available_cores()
    spec = plan.spec()
    for k in todo:
        start, stop = work.bounds(k)
        try:
            result = worker.run_chunk(spec, k, start, stop, threads=threads)
        except RuntimeError as e:
            raise StudyError(f"{e} (the finished chunks are kept in {work.path})") from None
        if result.get("interrupted"):
            raise KeyboardInterrupt
        work.save(k, result)
        progress.add(stop - start)


def available_cores() -> int:
    """The cores this process may run on (its affinity), as the CLI counts them."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on every platform
        return os.cpu_count() or 1


class ByValue:
    """A function that the standard pickle sends by value: as a call of cloudpickle.loads on
    cloudpickle's bytes of it, which any process with distributed (and so cloudpickle) can
    load. Loading gives the function itself."""

    def __init__(self, fn):
        import cloudpickle

        self.fn = fn
        self.blob = cloudpickle.dumps(fn)

    def __reduce__(self):
        import cloudpickle

        return (cloudpickle.loads, (self.blob,))

    def __call__(self, *args, **kwargs):
        return self.fn(*args, **kwargs)


def run_dask(plan: Plan, work: WorkDir, todo: list, scheduler: str | None, workers: int | None,
             progress: Progress, local_processes: bool = False) -> list:
    """Each chunk as one task on a Dask cluster: a LocalCluster of `workers` single-threaded
    workers (default: one per core; threads of this process, or processes with
    `local_processes`), or the scheduler at `scheduler`. The client writes
    each chunk as its result arrives. Returns the errors of the chunks that failed."""
    import cloudpickle
    from distributed import Client, LocalCluster, as_completed

    # The task function travels by value: the scheduler and the workers need no copy of this
    # package. (distributed pickles a task graph with the standard pickle, which sends
    # functions by reference, whatever cloudpickle's by-value registry holds; see ByValue.)
    cloudpickle.register_pickle_by_value(worker)
    task = ByValue(worker.run_chunk)
    cluster = client = None
    errors = []
    began = time.perf_counter()
    try:
        if scheduler:
            client = Client(scheduler, timeout="30s")
        else:
            # Workers as threads of this process by default: a task spends its time waiting
            # for the CLI's process, so worker processes would only add interpreters competing
            # for the cores (docs/study.md measures both).
            n = workers if workers is not None else available_cores()
            cluster = LocalCluster(n_workers=n, threads_per_worker=1,
                                   processes=local_processes,
                                   dashboard_address=":0")  # a free port: 8787 may be taken
            client = Client(cluster)
        progress.startup = time.perf_counter() - began
        # The spec goes with every task (a few kB): a task moved to another worker after a
        # death needs nothing that died with the first.
        spec = plan.spec()
        tag = plan.key_tag(work.chunk_size)
        futures = {}
        for k in todo:
            start, stop = work.bounds(k)
            fut = client.submit(task, spec, k, start, stop,
                                key=f"beam-body-{tag}-chunk-{k}", pure=False)
            futures[fut] = k
        for fut in as_completed(futures):
            k = futures[fut]
            try:
                result = fut.result()
                if result.get("interrupted"):
                    # The same Ctrl-C as the tool's, which may not have reached it yet.
                    raise KeyboardInterrupt
                work.save(k, result)
            except Exception as e:  # noqa: BLE001: a chunk's failure is reported, not fatal
                errors.append(f"chunk {k}: {e}")
                continue
            finally:
                fut.release()
            start, stop = work.bounds(k)
            progress.add(stop - start)
    except KeyboardInterrupt:
        # Closing cancels the tasks in flight, and the same Ctrl-C killed their CLI processes:
        # Dask logs each as a warning or a failed task, news to nobody who pressed Ctrl-C.
        silence_dask()
        raise
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    return errors


def silence_dask() -> None:
    """Mutes the loggers of Dask and of its event loop for the rest of the process."""
    import logging

    names = [n for n in logging.root.manager.loggerDict
             if n.split(".")[0] in ("distributed", "dask", "tornado", "asyncio")]
    for name in names + ["distributed", "asyncio", "tornado"]:
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)


def schema(plan: Plan):
    import pyarrow as pa

    types = {"int64": pa.int64(), "float64": pa.float64(), "string": pa.string()}
    return pa.schema([(c["name"], types[c["type"]]) for c in plan.columns])


def assemble(plan: Plan, work: WorkDir, out: Path, fmt: str) -> dict:
    """Writes the table of every chunk, in case order, to `out` (whole or not at all), one
    chunk at a time: a study of 10⁷ rows never sits in memory. Checks that the chunks hold
    each case once, in order. Returns the count of each status.

    CSV is the chunks' own text, the header once: byte for byte what `beam-body study`
    writes for the whole study, numbers in the CLI's shortest round-trip form (a reader
    through pyarrow would write them again in its own)."""
    import numpy as np
    import pyarrow as pa
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    meta = {
        b"beam_body.study": plan.study_text.encode(),
        b"beam_body.scene": (plan.scene_text or "").encode(),
        b"beam_body.fingerprint": plan.fingerprint.encode(),
        b"beam_body.cli_sha256": plan.cli_sha256.encode(),
    }
    sch = schema(plan).with_metadata(meta)
    convert = pacsv.ConvertOptions(column_types=sch, strings_can_be_null=False,
                                   quoted_strings_can_be_null=False)
    header = (plan.header() + "\n").encode()
    tmp = out.with_name(f"{out.name}.tmp-{os.getpid()}")
    statuses: dict = {}
    if fmt == "parquet":
        writer = pq.ParquetWriter(tmp, sch)
        write, close = writer.write_table, writer.close
    else:
        raw = open(tmp, "wb")
        raw.write(header)
        write, close = None, raw.close
    try:
        for k in range(work.chunks):
            data = work.csv(k).read_bytes()
            first, _, rows = data.partition(b"\n")
            if first + b"\n" != header:
                raise StudyError(f"{work.csv(k)}: its header is not the study's "
                                 f"({plan.header()}): pass --restart to compute it again")
            try:
                part = pacsv.read_csv(pa.BufferReader(data), convert_options=convert)
            except pa.ArrowInvalid as e:
                raise StudyError(f"{work.csv(k)}: not a chunk of this study ({e}): pass "
                                 "--restart to compute it again") from None
            start, stop = work.bounds(k)
            if not np.array_equal(part.column("case").to_numpy(), np.arange(start, stop)):
                raise StudyError(f"{work.csv(k)} does not hold cases {start}..{stop}")
            for status in part.column("status").to_pylist():
                statuses[status] = statuses.get(status, 0) + 1
            if write is not None:
                write(part.replace_schema_metadata(meta))
            else:
                raw.write(rows)
        if work.chunks == 0 and write is not None:
            write(sch.empty_table())
        close()
    except BaseException:
        close()
        tmp.unlink(missing_ok=True)
        raise
    os.replace(tmp, out)
    return statuses


def run_study(study, out, *, engine="local", scheduler=None, workers=None, threads=None,
              chunk_size=None, work_dir=None, restart=False, cli=None, fmt=None, quiet=False,
              local_processes=False, max_cases=MAX_CASES):
    """Runs a study and writes its table to `out`. Returns a summary dict.

    Ctrl-C raises Interrupted, whose message says how many chunks are kept.

    With `engine="dask"` and no scheduler, a script that calls this must guard its top level
    with `if __name__ == "__main__":` when `local_processes` is set: the workers' processes are
    started by multiprocessing's spawn, which imports the script again."""
    out = Path(out)
    fmt = output_format(out, fmt)
    if engine not in ("local", "dask"):
        raise StudyError(f"--engine {engine}: must be local or dask")
    for name, value in (("--chunk-size", chunk_size), ("--workers", workers),
                        ("--threads", threads), ("--max-cases", max_cases)):
        if value is not None and value < 1:
            raise StudyError(f"{name} {value}: must be at least 1")
    p = plan(study, cli)
    if max_cases is not None and p.cases > max_cases:
        raise StudyError(f"{study}: the study has {p.cases:,} cases, more than the limit of "
                         f"{max_cases:,}: pass --max-cases {p.cases} to run them all")
    size = chunk_size if chunk_size is not None else default_chunk_size(p.cases)
    out.parent.mkdir(parents=True, exist_ok=True)
    work = WorkDir(Path(work_dir) if work_dir else out.with_name(out.name + ".parts"), p, size,
                   restart)
    done = work.done()
    todo = [k for k in range(work.chunks) if k not in done]
    if not quiet:
        print(f"study: {p.cases} cases in {work.chunks} chunks of {size}; {len(done)} done "
              f"already in {work.path}, {len(todo)} to compute ({engine})", file=sys.stderr)
    todo_cases = sum(work.bounds(k)[1] - work.bounds(k)[0] for k in todo)
    progress = Progress(todo_cases, work.chunks, len(done), quiet)
    began = time.perf_counter()
    errors = []
    try:
        if engine == "local":
            run_local(p, work, todo, threads, progress)
        else:
            errors = run_dask(p, work, todo, scheduler, workers, progress, local_processes)
    except KeyboardInterrupt:
        progress.finish()
        kept = len(work.done())
        raise Interrupted(f"{kept} of {work.chunks} chunks are finished and kept in {work.path}; "
                          "run the same command again to go on from there") from None
    progress.finish()
    seconds = time.perf_counter() - began
    if errors:
        raise StudyError(
            f"{len(errors)} of {len(todo)} chunks failed (the others are kept in {work.path}; "
            "run again to retry):\n  " + "\n  ".join(errors)
        )
    statuses = assemble(p, work, out, fmt)
    summary = {
        "cases": p.cases,
        "chunks": work.chunks,
        "computed_chunks": len(todo),
        "computed_cases": todo_cases,
        "seconds": seconds,
        "startup_seconds": progress.startup,
        "statuses": statuses,
        "output": str(out),
    }
    if not quiet:
        rate = f", {todo_cases / seconds:.0f} cases/s" if todo_cases and seconds > 0 else ""
        counts = ", ".join(f"{k} {v}" for k, v in sorted(statuses.items()))
        startup = f" (of which {progress.startup:.2f} s to start the cluster or connect)" \
            if engine == "dask" else ""
        print(f"study: computed {len(todo)} chunks ({todo_cases} cases) in {seconds:.2f} s"
              f"{startup}{rate}; {counts}; wrote {out}", file=sys.stderr)
    return summary
