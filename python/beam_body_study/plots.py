"""Pictures of a study's table: a heatmap over a two-parameter grid, a histogram with quantiles."""

from __future__ import annotations

from pathlib import Path

#: Units of the columns, for the axis labels.
UNITS = {
    "l": "m", "EI": "N·m²", "m": "kg/m", "M2": "kg", "J_C": "kg·m²", "r": "m", "g": "m/s²",
    "t_rot": "s", "phi_end": "rad", "phi0": "rad", "v1_0": "m", "theta1_0": "rad",
    "dv1_0": "m/s", "dtheta1_0": "rad/s", "residual_v1": "m", "peak_M": "N·m", "peak_N": "N",
    "peak_P": "N", "max_v1": "m", "max_theta1": "rad", "energy_final": "J",
}


def label(name: str) -> str:
    unit = UNITS.get(name)
    return f"{name} [{unit}]" if unit else name


def read_table(path: str | Path):
    """A study's table (Parquet, or CSV as written by `run`) as a pyarrow Table."""
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    path = Path(path)
    if path.suffix.lower() == ".csv":
        return pacsv.read_csv(path)
    return pq.read_table(path)


def quantile(values, q: float) -> float:
    """The q-quantile by linear interpolation between order statistics (numpy's default,
    Hyndman & Fan's type 7)."""
    import numpy as np

    return float(np.quantile(values, q))


def heatmap(table, x: str, y: str, z: str, out: str | Path, contour: list | None = None,
            log_z: bool = False, title: str | None = None) -> dict:
    """`z` over the grid of `x` and `y` (one row per grid point); cells whose run did not reach
    the end are hatched. With `contour`, the level lines of z at those values. Returns what
    the picture shows: the grid's size and the failed cells."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.colors import LogNorm

    cols = table.to_pydict()
    xs, ys = sorted(set(cols[x])), sorted(set(cols[y]))
    if len(xs) * len(ys) != table.num_rows:
        raise ValueError(
            f"{x} × {y} is not the table's grid: {len(xs)} × {len(ys)} values for "
            f"{table.num_rows} rows (a heatmap needs one row per grid point)"
        )
    ix = {v: i for i, v in enumerate(xs)}
    iy = {v: i for i, v in enumerate(ys)}
    grid = np.full((len(ys), len(xs)), np.nan)
    for xv, yv, zv in zip(cols[x], cols[y], cols[z]):
        grid[iy[yv], ix[xv]] = np.nan if zv is None else zv
    fig, ax = plt.subplots(figsize=(7.5, 5.2), dpi=110)
    norm = LogNorm(vmin=np.nanmin(grid[grid > 0]), vmax=np.nanmax(grid)) if log_z else None
    mesh = ax.pcolormesh(xs, ys, grid, shading="nearest", cmap="viridis", norm=norm)
    fig.colorbar(mesh, ax=ax, label=label(z))
    failed = np.isnan(grid)
    if failed.any():
        fy, fx = np.nonzero(failed)
        ax.scatter(np.asarray(xs)[fx], np.asarray(ys)[fy], marker="x", color="red", s=12,
                   label="run did not reach t_end")
        ax.legend(loc="upper right", fontsize=8)
    if contour:
        cs = ax.contour(xs, ys, grid, levels=sorted(contour), colors="white", linewidths=1.4)
        unit = UNITS.get(z, "")
        ax.clabel(cs, fmt=lambda v: f"{v:g} {unit}".strip(), fontsize=8)
    ax.set_xlabel(label(x))
    ax.set_ylabel(label(y))
    ax.set_title(title or f"{z} over {x} × {y} ({table.num_rows} runs)")
    fig.tight_layout()
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    plt.close(fig)
    return {"nx": len(xs), "ny": len(ys), "failed": int(failed.sum())}


def histogram(table, metric: str, out: str | Path, quantiles=(0.5, 0.99), bins: int = 60,
              title: str | None = None) -> dict:
    """The distribution of `metric` over the runs that reached the end, with its quantiles
    marked. Returns the quantiles and the number of runs that did not reach the end."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    values = np.array([v for v in table.column(metric).to_pylist() if v is not None])
    missing = table.num_rows - len(values)
    if len(values) == 0:
        raise ValueError(f"no run has a value of {metric}")
    qs = {q: quantile(values, q) for q in quantiles}
    fig, ax = plt.subplots(figsize=(7.5, 4.6), dpi=110)
    ax.hist(values, bins=bins, color="#4c72b0", alpha=0.85)
    for i, (q, v) in enumerate(sorted(qs.items())):
        ax.axvline(v, color=["#dd8452", "#c44e52", "#8172b3", "#55a868"][i % 4], lw=1.6,
                   label=f"{100 * q:g}th percentile: {v:.4g}")
    ax.set_xlabel(label(metric))
    ax.set_ylabel("runs")
    note = f", {missing} did not reach t_end" if missing else ""
    ax.set_title(title or f"{metric}: {len(values)} runs{note}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    plt.close(fig)
    return {"quantiles": qs, "missing": missing, "n": len(values)}
