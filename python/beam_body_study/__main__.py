"""The command line: `beam-body-study run|plot|animate ...` or `python -m beam_body_study
run|plot|animate ...` (see the package's docstring).

Every error a user can make ends as one line, `error: ...`, with exit status 2; Ctrl-C as one
line saying what was kept, with exit status 130. A traceback means a bug of this tool.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

from . import __doc__ as PACKAGE_DOC
from . import __version__
from .errors import Interrupted, StudyError
from .runner import MAX_CASES, default_cli, run_study


def version_lines() -> list:
    """This tool's version, and that of the `beam-body` CLI it would run, where there is one."""
    lines = [f"beam-body-study {__version__}"]
    try:
        cli = default_cli()
    except StudyError:
        return lines + ["beam-body: not found ($BEAM_BODY_BIN, target/release/beam-body of "
                        "this checkout, or beam-body on PATH)"]
    try:
        proc = subprocess.run([cli, "--version"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as e:
        return lines + [f"beam-body: {cli} does not run: {e}"]
    out = proc.stdout.strip()
    if proc.returncode == 0 and out.startswith("beam-body "):
        return lines + [f"{out} ({cli})"]
    return lines + [f"beam-body: {cli} tells no version: too old for this tool, build the "
                    "current one (cargo build --release)"]


class VersionAction(argparse.Action):
    """`--version`: like argparse's own, but the CLI's version is looked up only when asked."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
                 help=None):
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print("\n".join(version_lines()))
        parser.exit()


def prog_name() -> str:
    """The name the user typed: the console script's, or `python -m beam_body_study`."""
    argv0 = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else ""
    return "python -m beam_body_study" if argv0 in ("", "-m", "__main__.py") else argv0


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog=prog_name(), description=PACKAGE_DOC,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action=VersionAction,
                    help="print this tool's version and that of the beam-body CLI, and exit")
    sub = ap.add_subparsers(dest="command", required=True)

    run = sub.add_parser("run", help="run a study and write its table")
    run.add_argument("study", help="the study file (TOML)")
    run.add_argument("-o", "--output", required=True,
                     help="OUT.parquet or OUT.csv (another name needs --format)")
    run.add_argument("--format", choices=("parquet", "csv"),
                     help="the table's format (default: from the extension, .parquet or .csv)")
    run.add_argument("--engine", choices=("local", "dask"), default="local",
                     help="local: the native runner on every core (default); dask: a Dask "
                          "cluster (a LocalCluster unless --scheduler)")
    run.add_argument("--scheduler", help="address of a Dask scheduler (implies --engine dask)")
    run.add_argument("--workers", type=int,
                     help="LocalCluster: the number of single-threaded workers, threads of this "
                          "process that each wait for one CLI process (default: one per core)")
    run.add_argument("--threads", type=int, help="local: threads of the native runner "
                                                 "(default: every core)")
    run.add_argument("--chunk-size", type=int, help="cases per chunk (default: 1000, or fewer "
                                                    "so that there are at least 16 chunks)")
    run.add_argument("--max-cases", type=int, default=MAX_CASES,
                     help=f"refuse a study of more cases than this (default: {MAX_CASES:,})")
    run.add_argument("--work-dir", help="where finished chunks are kept (default: OUT.parts)")
    run.add_argument("--restart", action="store_true",
                     help="discard the finished chunks of an earlier run")
    run.add_argument("--cli", help="the beam-body binary (default: $BEAM_BODY_BIN, "
                                   "target/release/beam-body, or beam-body on PATH)")
    run.add_argument("--quiet", action="store_true", help="no progress on stderr")

    plot = sub.add_parser("plot", help="draw a study's table")
    kinds = plot.add_subparsers(dest="kind", required=True)
    column = " (a column's name; its unit in brackets may be left out)"
    hm = kinds.add_parser("heatmap", help="a metric over a two-parameter grid")
    hm.add_argument("table", help="a table written by `run` (.parquet or .csv)")
    hm.add_argument("--x", required=True, help="the parameter across" + column)
    hm.add_argument("--y", required=True, help="the parameter up" + column)
    hm.add_argument("--z", required=True, help="the metric" + column)
    hm.add_argument("--contour", type=float, action="append",
                    help="draw the level line of z at this value (repeatable)")
    hm.add_argument("--log", action="store_true", help="logarithmic colour scale")
    hm.add_argument("--title")
    hm.add_argument("-o", "--output", required=True, help="the picture (.png, .pdf, .svg, ...)")
    hist = kinds.add_parser("hist", help="the distribution of a metric, with quantiles")
    hist.add_argument("table", help="a table written by `run` (.parquet or .csv)")
    hist.add_argument("--metric", required=True, help="the metric" + column)
    hist.add_argument("--quantile", type=float, action="append",
                      help="mark this quantile (repeatable; default 0.5 and 0.99)")
    hist.add_argument("--bins", type=int, default=60)
    hist.add_argument("--title")
    hist.add_argument("-o", "--output", required=True, help="the picture (.png, .pdf, .svg, ...)")
    anim = sub.add_parser("animate", help="the beam and the body through a run, as a GIF")
    anim.add_argument("scene", help="the scene file (TOML), as `beam-body simulate` reads it")
    anim.add_argument("-o", "--output", required=True, help="the animation (.gif)")
    anim.add_argument("--elements", type=int, help="n_elements (default: the scene's)")
    anim.add_argument("--beam", choices=("quadratic", "exact"),
                      help="the beam's theory (default: the scene's)")
    anim.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                      help="a setting on top of the scene (repeatable), as the CLI's --set")
    anim.add_argument("--fps", type=float, default=20.0,
                      help="frames per second of simulated time, and of the GIF (default 20)")
    anim.add_argument("--dpi", type=int, default=72, help="resolution (default 72)")
    anim.add_argument("--cli", help="the beam-body binary (default: $BEAM_BODY_BIN, "
                                    "target/release/beam-body, or beam-body on PATH)")
    shown = anim.add_mutually_exclusive_group()
    shown.add_argument("--progress", action="store_true",
                       help="frames drawn on stderr even when it is not a terminal (by default "
                            "only on a terminal)")
    shown.add_argument("--quiet", action="store_true", help="nothing on stderr but errors")
    return ap


def animate_command(args) -> None:
    from .animate import Progress, animate

    shown = not args.quiet and (args.progress or sys.stderr.isatty())
    info = animate(args.cli or default_cli(), args.scene, args.output, args.set,
                   elements=args.elements, beam=args.beam, fps=args.fps, dpi=args.dpi,
                   progress=Progress() if shown else None)
    if not args.quiet:
        print(f"animate: {info['frames']} frames of {info['elements']} element(s); "
              f"wrote {args.output}", file=sys.stderr)


def run_command(args) -> None:
    engine = "dask" if args.scheduler else args.engine
    run_study(args.study, args.output, engine=engine, scheduler=args.scheduler,
              workers=args.workers, threads=args.threads, chunk_size=args.chunk_size,
              work_dir=args.work_dir, restart=args.restart, cli=args.cli, fmt=args.format,
              quiet=args.quiet, max_cases=args.max_cases)


def plot_command(args) -> None:
    from . import plots

    table = plots.read_table(args.table)
    if args.kind == "heatmap":
        info = plots.heatmap(table, args.x, args.y, args.z, args.output,
                             contour=args.contour, log_z=args.log, title=args.title)
        for note in info["notes"]:
            print(f"warning: {note}", file=sys.stderr)
        print(f"plot: {info['nx']} × {info['ny']} grid, {info['failed']} cells without "
              f"a value; wrote {args.output}", file=sys.stderr)
    else:
        info = plots.histogram(table, args.metric, args.output,
                               quantiles=tuple(args.quantile or (0.5, 0.99)),
                               bins=args.bins, title=args.title)
        qs = ", ".join(f"q{100 * q:g} = {v:.6g}" for q, v in info["quantiles"].items())
        print(f"plot: {info['n']} runs, {info['missing']} without a value; {qs}; "
              f"wrote {args.output}", file=sys.stderr)


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    try:
        if args.command == "run":
            run_command(args)
        elif args.command == "animate":
            animate_command(args)
        else:
            plot_command(args)
    except Interrupted as e:
        print(f"interrupted: {e}", file=sys.stderr)
        return 130
    except StudyError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except OSError as e:  # a file the user named that cannot be read or written
        where = f"{e.filename}: " if e.filename else ""
        print(f"error: {where}{e.strerror or e}", file=sys.stderr)
        return 2
    return 0


def entry() -> None:
    """The command's entry (console script and `python -m`): main, then an exit that skips the
    interpreter's teardown. pyarrow's native thread pools, used from Dask's worker threads,
    can abort the process at teardown ("terminate called without an active exception", exit
    -6) after the work is done and written (apache/arrow#34314): seen once in CI on the Dask
    engine. Everything the tool writes is closed before main returns."""
    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":
    entry()
