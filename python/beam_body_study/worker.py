"""The task a Dask worker runs: one chunk of a study through the `beam-body` CLI.

This module is sent to the workers by value (cloudpickle), so a worker needs only Python with
`distributed` and the `beam-body` binary; not this package. It imports nothing of the package.
"""

from __future__ import annotations

import hashlib
import os
import signal
import socket
import subprocess
import tempfile
import time

#: The CLI's exit statuses when a SIGINT or SIGTERM stopped it: 130 (the shell's code for SIGINT)
#: once its handler is installed; killed by the signal itself (subprocess's -2 or -15) when the
#: signal came before the handler, in the first milliseconds of the process (seen in CI).
INTERRUPTED_EXITS = (130, -signal.SIGINT, -signal.SIGTERM)

#: sha256 of the binaries this process has run, by (path, size, mtime).
_HASHES: dict = {}


def file_sha256(path: str) -> str:
    """The sha256 of a file, cached per process while its size and mtime do not change."""
    st = os.stat(path)
    key = (os.path.abspath(path), st.st_size, st.st_mtime_ns)
    if key not in _HASHES:
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
        _HASHES[key] = h.hexdigest()
    return _HASHES[key]


def worker_name() -> str:
    """The Dask worker's name, or the host and process where no worker runs this."""
    try:
        from distributed import get_worker

        return str(get_worker().name)
    except (ImportError, ValueError):
        return f"{socket.gethostname()}:{os.getpid()}"


def run_chunk(spec: dict, chunk: int, start: int, stop: int, threads: int = 1) -> dict:
    """Runs cases start..stop of the study in `spec` and returns the CSV text with its origin, or
    `interrupted` set when a SIGINT or SIGTERM stopped the CLI.

    `spec` holds the CLI's path and sha256 (a worker whose binary differs refuses: its rows
    could differ), the study file's text and its base scene's text. Both are written to a
    temporary directory, so the worker needs no shared file system.
    """
    cli = spec["cli"]
    if not os.path.isfile(cli):
        raise RuntimeError(f"beam-body CLI not found on worker {worker_name()}: {cli}")
    sha = file_sha256(cli)
    if sha != spec["cli_sha256"]:
        raise RuntimeError(
            f"the beam-body CLI on worker {worker_name()} ({cli}, sha256 {sha[:12]}) is not "
            f"the client's (sha256 {spec['cli_sha256'][:12]}): install the same build"
        )
    began = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="beam-body-chunk-") as tmp:
        study = os.path.join(tmp, "study.toml")
        with open(study, "w", encoding="utf-8") as f:
            f.write(spec["study_text"])
        # The limit on cases is the client's (run --max-cases); a chunk larger than the CLI's
        # default limit, with a larger --chunk-size, must not be refused here.
        cmd = [cli, "study", study, "--cases", f"{start}..{stop}", "--threads", str(threads),
               "--max-cases", str(max(1, stop - start))]
        if spec.get("scene_text") is not None:
            scene = os.path.join(tmp, "scene.toml")
            with open(scene, "w", encoding="utf-8") as f:
                f.write(spec["scene_text"])
            cmd += ["--scene", scene]
        out = os.path.join(tmp, "rows.csv")
        cmd += ["--quiet", "-o", out]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode in INTERRUPTED_EXITS:
            # Ctrl-C reached the CLI (the terminal signals the whole process group): the run
            # is being interrupted, which the client reports as such, whichever sees it first.
            # A result, not an exception, which Dask's workers would log as a failed task.
            return {"chunk": chunk, "interrupted": True, "worker": worker_name()}
        if proc.returncode != 0:
            raise RuntimeError(
                f"chunk {chunk} (cases {start}..{stop}) failed on {worker_name()}: "
                f"`beam-body study` exited with {proc.returncode}: {proc.stderr.strip()}"
            )
        with open(out, "rb") as f:
            data = f.read()
    return {
        "chunk": chunk,
        "csv": data,
        "worker": worker_name(),
        "host": socket.gethostname(),
        "seconds": time.perf_counter() - began,
    }
