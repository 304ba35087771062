"""Pictures of a study's table: a heatmap over a two-parameter grid, a histogram with quantiles.

The columns are named as the user likes (`peak_M` or `peak_M [N.m]`, see columns.find); the axis
labels take their units from the table's headers, so that they cannot disagree with the data.
"""

from __future__ import annotations

import warnings
from pathlib import Path

from .columns import bare, find, label, pretty_unit, unit
from .errors import StudyError


def read_table(path: str | Path):
    """A study's table (CSV if its name ends in .csv, else Parquet) as a pyarrow Table; a
    missing or unreadable file is a StudyError naming it."""
    import pyarrow as pa
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    path = Path(path)
    if not path.exists():
        raise StudyError(f"{path}: no such file (a table written by `run`: .parquet or .csv)")
    kind = "CSV" if path.suffix.lower() == ".csv" else "Parquet"
    try:
        return pacsv.read_csv(path) if kind == "CSV" else pq.read_table(path)
    except (pa.ArrowException, OSError, ValueError) as e:
        reason = (str(e).strip().splitlines() or [type(e).__name__])[0]
        raise StudyError(f"cannot read {path} as {kind}: {reason}") from None


def output_types() -> list:
    """The extensions matplotlib writes (without the dot)."""
    from matplotlib.backend_bases import FigureCanvasBase

    return sorted(FigureCanvasBase.get_supported_filetypes())


def check_output(out: str | Path) -> None:
    """Refuses, before any drawing, a picture's name whose extension matplotlib cannot write
    (it would fail after the work, or without an extension write the default format under a
    name that hides it)."""
    ext = Path(out).suffix.lower().removeprefix(".")
    types = output_types()
    if ext not in types:
        what = f"cannot write .{ext}" if ext else "needs an extension to choose a format"
        raise StudyError(f"-o {out}: matplotlib {what}; it writes "
                         + ", ".join(f".{t}" for t in types))


def save(fig, out: str | Path) -> None:
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    try:
        fig.savefig(out)
    except (OSError, RuntimeError) as e:  # a directory without write access; .pgf without LaTeX
        raise StudyError(f"cannot write {out}: {e}") from None


def numeric_column(table, header: str, option: str):
    """The column's values as a list (None where missing); refuses text columns."""
    import pyarrow as pa

    col = table.column(header)
    t = col.type
    if not (pa.types.is_integer(t) or pa.types.is_floating(t) or pa.types.is_null(t)):
        raise StudyError(f"{option} {bare(header)}: a column of {t}, not of numbers")
    return col.to_pylist()


def quantile(values, q: float) -> float:
    """The q-quantile by linear interpolation between order statistics (numpy's default,
    Hyndman & Fan's type 7)."""
    import numpy as np

    return float(np.quantile(values, q))


def heatmap(table, x: str, y: str, z: str, out: str | Path, contour: list | None = None,
            log_z: bool = False, title: str | None = None) -> dict:
    """`z` over the grid of `x` and `y` (one row per grid point); cells whose run did not reach
    the end are marked. With `contour`, the level lines of z at those values. Returns what
    the picture shows: the grid's size, the failed cells, and notes (a level outside the
    data's range, which draws no line)."""
    names = table.column_names
    x, y, z = find(names, x, "--x"), find(names, y, "--y"), find(names, z, "--z")
    check_output(out)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.colors import LogNorm

    xcol, ycol = numeric_column(table, x, "--x"), numeric_column(table, y, "--y")
    zcol = numeric_column(table, z, "--z")
    for header, col, option in ((x, xcol, "--x"), (y, ycol, "--y")):
        if None in col:
            raise StudyError(f"{option} {bare(header)}: some rows have no value; a heatmap's "
                             "axes are parameters")
    xs, ys = sorted(set(xcol)), sorted(set(ycol))
    if len(xs) * len(ys) != table.num_rows:
        raise StudyError(
            f"{bare(x)} × {bare(y)} is not the table's grid: {len(xs)} × {len(ys)} values for "
            f"{table.num_rows} rows (a heatmap needs one row per grid point)"
        )
    ix = {v: i for i, v in enumerate(xs)}
    iy = {v: i for i, v in enumerate(ys)}
    grid = np.full((len(ys), len(xs)), np.nan)
    for xv, yv, zv in zip(xcol, ycol, zcol):
        grid[iy[yv], ix[xv]] = np.nan if zv is None else zv
    values = grid[np.isfinite(grid)]
    if values.size == 0:
        raise StudyError(f"--z {bare(z)}: no run has a value to draw")
    if log_z and not (values > 0).any():
        raise StudyError(f"--log: {bare(z)} has no positive value for a logarithmic scale")
    lo, hi = float(values.min()), float(values.max())
    u = f" {pretty_unit(unit(z))}" if unit(z) else ""
    levels = sorted(contour or [])
    notes = [f"--contour {v:g}: outside the range of {bare(z)} in the data, {lo:.6g} to "
             f"{hi:.6g}{u}: no line drawn" for v in levels if not lo <= v <= hi]
    inside = [v for v in levels if lo <= v <= hi]

    fig, ax = plt.subplots(figsize=(7.5, 5.2), dpi=110)
    norm = LogNorm(vmin=values[values > 0].min(), vmax=hi) if log_z else None
    mesh = ax.pcolormesh(xs, ys, grid, shading="nearest", cmap="viridis", norm=norm)
    fig.colorbar(mesh, ax=ax, label=label(z))
    failed = np.isnan(grid)
    if failed.any():
        fy, fx = np.nonzero(failed)
        ax.scatter(np.asarray(xs)[fx], np.asarray(ys)[fy], marker="x", color="red", s=12,
                   label="run did not reach t_end")
        ax.legend(loc="upper right", fontsize=8)
    if inside:
        with warnings.catch_warnings():
            # A level at the very edge of the data may have no line; the notes say what was
            # asked outside the range, matplotlib's own warning would only repeat it vaguely.
            warnings.simplefilter("ignore", UserWarning)
            cs = ax.contour(xs, ys, grid, levels=inside, colors="white", linewidths=1.4)
        ax.clabel(cs, fmt=lambda v: f"{v:g}{u}", fontsize=8)
    ax.set_xlabel(label(x))
    ax.set_ylabel(label(y))
    ax.set_title(title or f"{bare(z)} over {bare(x)} × {bare(y)} ({table.num_rows} runs)")
    fig.tight_layout()
    try:
        save(fig, out)
    finally:
        plt.close(fig)
    return {"nx": len(xs), "ny": len(ys), "failed": int(failed.sum()), "notes": notes,
            "range": (lo, hi)}


def histogram(table, metric: str, out: str | Path, quantiles=(0.5, 0.99), bins: int = 60,
              title: str | None = None) -> dict:
    """The distribution of `metric` over the runs that reached the end, with its quantiles
    marked. Returns the quantiles and the number of runs that did not reach the end."""
    metric = find(table.column_names, metric, "--metric")
    for q in quantiles:
        if not 0 <= q <= 1:
            raise StudyError(f"--quantile {q:g}: must be in [0, 1] (0.99 is the 99th "
                             "percentile)")
    if bins < 1:
        raise StudyError(f"--bins {bins}: must be at least 1")
    check_output(out)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    column = numeric_column(table, metric, "--metric")
    values = np.array([v for v in column if v is not None], dtype=float)
    missing = table.num_rows - len(values)
    if len(values) == 0:
        raise StudyError(f"--metric {bare(metric)}: no run has a value")
    qs = {q: quantile(values, q) for q in quantiles}
    fig, ax = plt.subplots(figsize=(7.5, 4.6), dpi=110)
    ax.hist(values, bins=bins, color="#4c72b0", alpha=0.85)
    for i, (q, v) in enumerate(sorted(qs.items())):
        ax.axvline(v, color=["#dd8452", "#c44e52", "#8172b3", "#55a868"][i % 4], lw=1.6,
                   label=f"{100 * q:g}th percentile: {v:.4g}")
    ax.set_xlabel(label(metric))
    ax.set_ylabel("runs")
    note = f", {missing} did not reach t_end" if missing else ""
    ax.set_title(title or f"{bare(metric)}: {len(values)} runs{note}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    try:
        save(fig, out)
    finally:
        plt.close(fig)
    return {"quantiles": qs, "missing": missing, "n": len(values)}
