"""Design studies of the beam-body model: many runs of one scene, on every core or on Dask.

    python -m beam_body_study run STUDY.toml -o results.parquet [--engine dask [--scheduler ADDRESS]]
    python -m beam_body_study plot heatmap results.parquet --x t_rot --y M2 --z residual_v1 -o map.png
    python -m beam_body_study plot hist results.parquet --metric peak_M -o hist.png

The study file's format is in the README (Design studies). The runs are the native runner's,
`beam-body study`; this package cuts the study into chunks, runs them, keeps the finished ones
for a re-run, and writes the table with pyarrow.
"""

from .runner import StudyError, plan, run_study

__all__ = ["StudyError", "plan", "run_study"]
