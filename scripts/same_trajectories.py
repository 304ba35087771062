"""Compares two builds of the FMU (or of the CLI) bit for bit on a set of runs: the check that a
refactoring changed no result.

    python scripts/same_trajectories.py fmu OLD.fmu NEW.fmu
    python scripts/same_trajectories.py cli OLD/beam-body NEW/beam-body [--simulate-only]

FMU: FMPy runs of every formulation with the law, and with the input fed from the law's values
and derivatives (phi_source = input), at two tolerances; 3 elements, quadratic and exact; Model
Exchange (FMI 2.0, and FMI 3.0 from the FMU beside it named -fmi3); every output at every
communication point must be equal as doubles. CLI: `simulate` on the regression scenes and the first 200 cases
of each example study, stdout byte for byte; `--simulate-only` leaves out the studies (against a
build before 2026-12-04, whose study metrics came from the output grid, not the dense output).
Exit code 0 when all agree, 1 with the first difference otherwise.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FORMULATIONS = {"reduced": 1, "dae": 2, "dae_stabilized": 3, "linear": 4}
OUTPUTS = ["v1", "theta1", "u2", "dv1", "dtheta1", "du2", "N", "P", "M", "drift", "energy",
           "phi_applied", "dphi_applied", "ddphi_applied"]


def fmu_runs(path: str):
    import fmpy
    import numpy as np

    for name, f in FORMULATIONS.items():
        for tol in (1e-6, 1e-9):
            yield (name, tol, "law"), fmpy.simulate_fmu(
                path, start_values={"formulation": f, "phi_source": 2}, stop_time=3.0,
                output_interval=0.0085, relative_tolerance=tol, output=OUTPUTS)
        t = np.arange(0.0, 3.0 + 1e-9, 0.0085)
        phi = np.where(t < 0.85, np.pi * np.sin(np.pi * t / 1.7) ** 2, np.pi)
        signal = np.array(list(zip(t, phi)), dtype=[("time", float), ("phi", float)])
        yield (name, 1e-6, "input"), fmpy.simulate_fmu(
            path, start_values={"formulation": f, "phi_source": 1}, stop_time=3.0,
            output_interval=0.0085, input=signal, output=OUTPUTS)
    # The beam in 3 elements, quadratic and exact, in co-simulation.
    for beam in (1, 2):
        yield ("elements", beam), fmpy.simulate_fmu(
            path, start_values={"phi_source": 2, "n_elements": 3, "beam": beam}, stop_time=1.0,
            output_interval=0.0085, output=OUTPUTS)
    # Model Exchange with the host's integrator (FMPy's CVODE), FMI 2.0 and, if the FMU of the
    # same name with -fmi3 is there, 3.0: the paper's model (simulate_fmu cannot set FMI 3.0's
    # structural n_elements; tests/python/fmu/test_fmu3_arrays.py runs elements).
    fmi3 = Path(path).with_name(Path(path).stem + "-fmi3.fmu")
    for fmu in [path] + ([str(fmi3)] if fmi3.exists() else []):
        yield ("model exchange", Path(fmu).name), fmpy.simulate_fmu(
            fmu, fmi_type="ModelExchange", start_values={"phi_source": 2}, stop_time=2.0,
            output_interval=0.0085, output=OUTPUTS)


def compare_fmus(old: str, new: str) -> int:
    runs = 0
    for (key, a), (_, b) in zip(fmu_runs(old), fmu_runs(new), strict=True):
        for column in OUTPUTS:
            if not (a[column].tobytes() == b[column].tobytes()):
                print(f"differ: {key} {column}")
                return 1
        runs += 1
    print(f"{runs} FMU runs, {len(OUTPUTS)} outputs each: identical bit for bit")
    return 0


#: (scene file, extra arguments) of the `simulate` runs.
SCENES = [
    ("paper.toml", []),
    ("stiff.toml", []),
    ("paper.toml", ["--formulation", "dae"]),
    ("paper.toml", ["--formulation", "dae_stabilized"]),
    ("paper.toml", ["--formulation", "linear"]),
    ("paper.toml", ["--set", "phi_end=6.283185307179586", "--set", "M2=24"]),
    ("paper.toml", ["--set", "EI=1e7", "--set", "t_end=2"]),
    ("paper.toml", ["--fixed-step", "1e-3", "--fixed-order", "3", "--set", "t_end=3"]),
    ("paper.toml", ["--rtol", "1e-9", "--set", "t_end=3"]),
    ("paper.toml", ["--elements", "4", "--set", "t_end=2", "--columns", "shape"]),
    ("paper.toml", ["--elements", "3", "--formulation", "dae", "--set", "t_end=2"]),
    ("paper.toml", ["--elements", "3", "--formulation", "dae_stabilized", "--set", "t_end=2"]),
    ("paper.toml", ["--elements", "3", "--formulation", "linear", "--set", "t_end=2"]),
    ("paper.toml", ["--elements", "3", "--beam", "exact", "--set", "t_end=1", "--columns", "shape"]),
    ("paper.toml", ["--elements", "2", "--set", "damping_ratio=0.02", "--set", "t_end=2"]),
    ("paper.toml", ["--set", "phi_source=input", "--set", "t_end=2"]),
    ("paper.toml", ["--set", "phi_source=input", "--elements", "3", "--set", "t_end=1"]),
]


def compare_clis(old: str, new: str, studies: bool) -> int:
    runs = [["simulate", str(REPO / "scenes" / scene), *extra] for scene, extra in SCENES]
    for study in sorted((REPO / "examples").glob("*.toml")) if studies else []:
        runs.append(["study", str(study), "--cases", "0..200", "--quiet"])
    for args in runs:
        a = subprocess.run([old, *args], capture_output=True, check=True).stdout
        b = subprocess.run([new, *args], capture_output=True, check=True).stdout
        if a != b:
            print(f"differ: {' '.join(args)}")
            return 1
    print(f"{len(runs)} CLI runs ({'scenes and study chunks' if studies else 'scenes'}): CSV "
          "identical byte for byte")
    return 0


if __name__ == "__main__":
    kind, old, new = sys.argv[1:4]
    studies = "--simulate-only" not in sys.argv[4:]
    sys.exit(compare_fmus(old, new) if kind == "fmu" else compare_clis(old, new, studies))
