"""The command line: `python -m beam_body_study run|plot ...` (see the package's docstring)."""

from __future__ import annotations

import argparse
import sys

from .runner import StudyError, run_study


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m beam_body_study", description=__doc__)
    sub = ap.add_subparsers(dest="command", required=True)

    run = sub.add_parser("run", help="run a study and write its table")
    run.add_argument("study", help="the study file (TOML)")
    run.add_argument("-o", "--output", required=True, help="OUT.parquet, or OUT.csv")
    run.add_argument("--format", choices=("parquet", "csv"),
                     help="the table's format (default: from the extension; parquet)")
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
    run.add_argument("--work-dir", help="where finished chunks are kept (default: OUT.parts)")
    run.add_argument("--restart", action="store_true",
                     help="discard the finished chunks of an earlier run")
    run.add_argument("--cli", help="the beam-body binary (default: $BEAM_BODY_BIN, "
                                   "target/release/beam-body, or beam-body on PATH)")
    run.add_argument("--quiet", action="store_true", help="no progress on stderr")

    plot = sub.add_parser("plot", help="draw a study's table")
    kinds = plot.add_subparsers(dest="kind", required=True)
    hm = kinds.add_parser("heatmap", help="a metric over a two-parameter grid")
    hm.add_argument("table")
    hm.add_argument("--x", required=True)
    hm.add_argument("--y", required=True)
    hm.add_argument("--z", required=True, help="the metric")
    hm.add_argument("--contour", type=float, action="append",
                    help="draw the level line of z at this value (repeatable)")
    hm.add_argument("--log", action="store_true", help="logarithmic colour scale")
    hm.add_argument("--title")
    hm.add_argument("-o", "--output", required=True)
    hist = kinds.add_parser("hist", help="the distribution of a metric, with quantiles")
    hist.add_argument("table")
    hist.add_argument("--metric", required=True)
    hist.add_argument("--quantile", type=float, action="append",
                      help="mark this quantile (repeatable; default 0.5 and 0.99)")
    hist.add_argument("--bins", type=int, default=60)
    hist.add_argument("--title")
    hist.add_argument("-o", "--output", required=True)

    args = ap.parse_args(argv)
    try:
        if args.command == "run":
            engine = "dask" if args.scheduler else args.engine
            run_study(args.study, args.output, engine=engine, scheduler=args.scheduler,
                      workers=args.workers, threads=args.threads, chunk_size=args.chunk_size,
                      work_dir=args.work_dir, restart=args.restart, cli=args.cli,
                      fmt=args.format, quiet=args.quiet)
        else:
            from . import plots

            table = plots.read_table(args.table)
            if args.kind == "heatmap":
                info = plots.heatmap(table, args.x, args.y, args.z, args.output,
                                     contour=args.contour, log_z=args.log, title=args.title)
                print(f"plot: {info['nx']} × {info['ny']} grid, {info['failed']} cells without "
                      f"a value; wrote {args.output}", file=sys.stderr)
            else:
                info = plots.histogram(table, args.metric, args.output,
                                       quantiles=tuple(args.quantile or (0.5, 0.99)),
                                       bins=args.bins, title=args.title)
                qs = ", ".join(f"q{100 * q:g} = {v:.6g}" for q, v in info["quantiles"].items())
                print(f"plot: {info['n']} runs, {info['missing']} without a value; {qs}; "
                      f"wrote {args.output}", file=sys.stderr)
    except StudyError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\ninterrupted: the finished chunks are kept; run the same command again to go "
              "on", file=sys.stderr)
        return 130
    except (ValueError, KeyError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
