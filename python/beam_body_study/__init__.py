"""Design studies of the beam-body model: many runs of one scene, on every core or on Dask.

    beam-body-study run STUDY.toml -o results.parquet [--engine dask [--scheduler ADDRESS]]
    beam-body-study plot heatmap results.parquet --x t_rot --y M2 --z residual_v1 -o map.png
    beam-body-study plot hist results.parquet --metric peak_M -o hist.png
    beam-body-study animate SCENE.toml -o turn.gif [--elements N] [--beam exact] [--set NAME=VALUE]

(`python -m beam_body_study` is the same command.) The study file's format is in the README
(Design studies). The runs are the native runner's, `beam-body study`; this package cuts the
study into chunks, runs them, keeps the finished ones for a re-run, and writes the table with
pyarrow. `animate` draws one run of a scene, the beam and the body, as a GIF.
"""

# The one place of the version: python/pyproject.toml reads it from here.
__version__ = "0.1.0"

from .errors import Interrupted, StudyError  # noqa: E402
from .runner import plan, run_study  # noqa: E402

__all__ = ["Interrupted", "StudyError", "__version__", "plan", "run_study"]
