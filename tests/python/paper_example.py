"""The paper's example (Russkikh & Shklyarchuk 2020, section 4; /work/shared/model-notes.md): its
parameters under the CLI's setting names, and its turn and output grid. Facts the oracles and the
peers share; each derives its equations on its own."""

import math

PARAM_NAMES = ("l", "EI", "m", "M2", "J_C", "r", "g")
DEFAULT_PARAMS = {"l": 2.5, "EI": 1000.0, "m": 2.0, "M2": 12.0, "J_C": 1.0, "r": 0.5, "g": 10.0}

#: The turn phi = phi_end sin^2(pi t / (2 t_rot)) and the grid tau = t/T up to 12 by 0.01.
PAPER_LAW = {"t_rot": 0.85, "phi_end": math.pi, "phi0": 0.0, "t_end": 10.2, "dt_out": 0.0085}
