"""SciPy solvers of the work-precision benchmark: `scipy-bdf`, `scipy-radau`, `scipy-lsoda`
(scipy.integrate.solve_ivp methods 'BDF', 'Radau', 'LSODA') on a NumPy right-hand side; and
`fmpy-me`, FMPy's CVode on the FMU's Model Exchange (`solve_fmpy`), the other Python solver.

    python bench/python/bench_scipy.py --round K [--cases target/bench/cases.csv] [--dir target/bench]
                                       [--max-seconds 120]

Runs the cases of cases.csv whose solver is one of the three, in an order shuffled with seed K, and
appends one row per case to <dir>/raw.csv (the contract's columns). In round 0 (the warm-up) it also
writes <dir>/sol/<solver>__<scene>__<rtol>__<h>.csv.

The right-hand side is what a reasonable Python user would write: the equations of the test oracle
(tests/python/oracle.py, derived with sympy from the energies) are split into R = Mass(x)·a + b(x);
ONE lambdified function (sympy.lambdify, cse, math module for scalar arguments) returns Mass and b,
and numpy.linalg.solve gives the accelerations. No Jacobian is given: BDF and Radau build theirs by
forward differences (scipy.integrate._ivp.common.num_jac), LSODA by its own internal differences.

Scenes (bench contract): paper and stiff in the reduced formulation (4 states v1, theta1, dv1,
dtheta1); paper-dae and paper-dae-stabilized as the index-1 DAE (the constraint u2 = u1(v1, theta1)
differentiated twice), an ODE in 6 states (v1, theta1, u2, dv1, dtheta1, du2). For
paper-dae-stabilized, a projection after each accepted step is not possible inside solve_ivp: scipy
gets the UNSTABILISED index-1 integration, and only the reported grid values are projected onto the
constraint (u2 = u1(v1, theta1), du2 = d/dt u1 = -p·dv1 - l·q·dtheta1).

Two segments [0, t_rot] and [t_rot, t_end] (phi'' jumps at t_rot), each a separate solve_ivp call
restarted from the end of the first. rtol from the case, atol = 1e-3·rtol for every component.
Integration runs with dense_output=True and WITHOUT t_eval, so that sol.t holds exactly the accepted
steps; the grid values come from sol.sol (the methods' own dense output).

Counters written to raw.csv:
* steps: accepted steps, len(sol.t) - 1 summed over the two segments;
* rejected: empty (solve_ivp does not report them);
* rhs_evals: every call of the right-hand side, counted in the function itself. This is NOT scipy's
  nfev for BDF and Radau: there, the finite-difference Jacobian evaluates through fun_single /
  fun_vectorized, which do not increment nfev (scipy/integrate/_ivp/base.py, bdf.py `jac_wrapped`,
  radau.py `jac_wrapped`); for LSODA the Fortran code calls the counted wrapper for everything, so
  its nfev equals our count;
* jac_evals: njev (for LSODA scipy sets njev = nlu = iwork[12], the Fortran NJE);
* lu_factorizations: nlu;
* newton_iters: empty (not reported).
time_s is time.perf_counter around one complete solve: building the closures, both segments, and
the grid values (projection included), not file I/O.

--max-seconds N: a case is aborted when its right-hand side sees more than N s since the start of
the solve (status `timeout`); a case that timed out in an earlier round of the same raw.csv is not run
again (status `skipped-after-timeout`).
"""

from __future__ import annotations

import argparse
import math
import random
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_common as bc  # noqa: E402

METHODS = {"scipy-bdf": "BDF", "scipy-radau": "Radau", "scipy-lsoda": "LSODA"}
#: A host's integrator on the FMU's Model Exchange: FMPy's simulate_fmu with its CVode (BDF, the
#: default), on the packaged FMU that `cargo xtask bench` extracts to <dir>/fmu/BeamBody.
HOSTS = {"fmpy-me": "CVode"}


class Timeout(Exception):
    pass


# --------------------------------------------------------------------------------------------------
# right-hand sides
# --------------------------------------------------------------------------------------------------

_LAMBDIFIED: dict = {}


def mass_and_b(formulation: str):
    """f(phi, dphi, ddphi, <positions>, <velocities>, *params) -> (Mass rows, b) of the oracle's
    residual R = Mass·a + b of the formulation (reduced: 2 accelerations; dae: 3)."""
    key = "dae" if bc.is_dae(formulation) else formulation
    if key not in _LAMBDIFIED:
        import oracle
        import sympy as sp

        if key == "dae":
            R, acc, args = oracle.SYM["R_dae"], oracle.ACC_DAE, oracle.ARGS_DAE
        else:
            R, acc, args = oracle.SYM["R_" + key], oracle.ACC_REDUCED, oracle.ARGS_REDUCED
        R = sp.Matrix(R)
        mass = R.jacobian(sp.Matrix(acc))
        b = R.subs({a: 0 for a in acc})
        for e in R:  # affine in the accelerations
            assert all(sp.diff(e, a, 2) == 0 for a in acc)
        state_args = [a for a in args if a not in acc]  # phi dphi ddphi, positions, velocities
        _LAMBDIFIED[key] = sp.lambdify(
            state_args + list(oracle.PSYMS), [mass.tolist(), list(b)], modules="math", cse=True
        )
    return _LAMBDIFIED[key]


def make_rhs(f, params, n_dof, piece, law, counter, deadline):
    """solve_ivp right-hand side on one piece of the law ('turn': t in [0, t_rot], 'hold': after)."""
    phi0, phi_end, t_rot = law
    w = math.pi / (2.0 * t_rot)
    solve = np.linalg.solve
    concat = np.concatenate
    clock = time.perf_counter

    if piece == "turn":

        def rhs(t, y):
            counter[0] += 1
            if clock() > deadline:
                raise Timeout()
            s = math.sin(w * t)
            phi = phi0 + phi_end * s * s
            dphi = phi_end * w * math.sin(2.0 * w * t)
            ddphi = 2.0 * phi_end * w * w * math.cos(2.0 * w * t)
            mass, b = f(phi, dphi, ddphi, *y.tolist(), *params)
            return concat((y[n_dof:], -solve(mass, b)))

    else:
        phi_c = phi0 + phi_end

        def rhs(t, y):
            counter[0] += 1
            if clock() > deadline:
                raise Timeout()
            mass, b = f(phi_c, 0.0, 0.0, *y.tolist(), *params)
            return concat((y[n_dof:], -solve(mass, b)))

    return rhs


class Problem:
    """Everything of a scene that does not depend on the case (built before any timing)."""

    def __init__(self, scene: str):
        import oracle

        self.scene = scene
        self.formulation = bc.SCENES[scene][1]
        self.values = bc.scene_values(scene)
        s = self.values
        self.pdict = bc.scene_params(s)
        self.params = [self.pdict[k] for k in oracle.PARAM_NAMES]
        self.law = (s["phi0"], s["phi_end"], s["t_rot"])
        self.t_rot, self.t_end = s["t_rot"], s["t_end"]
        if not 0.0 < self.t_rot < self.t_end:
            raise ValueError(f"{scene}: expected 0 < t_rot < t_end")
        self.grid = bc.grid(self.t_end)
        self.names = bc.state_names(scene)
        self.f = mass_and_b(self.formulation)
        y0 = [s["v1_0"], s["theta1_0"], s["dv1_0"], s["dtheta1_0"]]
        if bc.is_dae(self.formulation):
            u, du = oracle.u1_and_rate(y0[0], y0[1], y0[2], y0[3], self.pdict)
            y0 = [y0[0], y0[1], float(u), y0[2], y0[3], float(du)]
        self.y0 = np.array(y0, dtype=float)
        self.n_dof = len(self.y0) // 2
        self.project = self.formulation == "dae_stabilized"


def solve_case(prob: Problem, method: str, rtol: float, max_seconds: float):
    """One complete solve. Returns (time_s, grid values Y, counters dict)."""
    from scipy.integrate import solve_ivp

    import oracle

    start = time.perf_counter()
    deadline = start + max_seconds
    counter = [0]
    rhs1 = make_rhs(prob.f, prob.params, prob.n_dof, "turn", prob.law, counter, deadline)
    rhs2 = make_rhs(prob.f, prob.params, prob.n_dof, "hold", prob.law, counter, deadline)
    kw = dict(method=method, rtol=rtol, atol=1e-3 * rtol, dense_output=True)
    sol1 = solve_ivp(rhs1, (0.0, prob.t_rot), prob.y0, **kw)
    if sol1.status != 0:
        raise RuntimeError(f"segment 1: {sol1.message}")
    sol2 = solve_ivp(rhs2, (prob.t_rot, prob.t_end), sol1.y[:, -1], **kw)
    if sol2.status != 0:
        raise RuntimeError(f"segment 2: {sol2.message}")
    tg = prob.grid
    first = tg <= prob.t_rot
    Y = np.empty((len(tg), len(prob.y0)))
    Y[first] = sol1.sol(tg[first]).T
    Y[~first] = sol2.sol(tg[~first]).T
    if prob.project:
        # output projection only (see the module docstring): u2 = u1(v1, theta1), du2 = d/dt u1
        u, du = oracle.u1_and_rate(Y[:, 0], Y[:, 1], Y[:, 3], Y[:, 4], prob.pdict)
        Y[:, 2], Y[:, 5] = u, du
    elapsed = time.perf_counter() - start
    counters = {
        "steps": (len(sol1.t) - 1) + (len(sol2.t) - 1),
        "rhs_evals": counter[0],
        "jac_evals": sol1.njev + sol2.njev,
        "lu_factorizations": sol1.nlu + sol2.nlu,
        "scipy_nfev": sol1.nfev + sol2.nfev,
    }
    return elapsed, Y, counters


def solve_fmpy(prob: Problem, rtol: float, fmu_dir: Path, model_description):
    """FMPy's CVode on the FMU's Model Exchange (the paper's scene: its defaults, phi from the law),
    output every grid step. FMPy sets atol = rtol * nominal (1 for every state), handles the law's
    time event at t_rot, and records two rows there (before and after the event): the second is kept.
    FMPy reports no counters. time_s is the whole simulate_fmu call, as a user pays it (instantiation,
    initialisation and the Python callbacks of its CVode included; the library was loaded once
    before the timing)."""
    import fmpy

    if prob.scene != "paper":
        raise ValueError(f"fmpy-me runs the paper's scene (the FMU's defaults), not {prob.scene}")
    start = time.perf_counter()
    r = fmpy.simulate_fmu(str(fmu_dir), model_description=model_description, fmi_type="ModelExchange",
                          start_values={"phi_source": 2}, relative_tolerance=rtol,
                          output_interval=bc.GRID_DT, stop_time=prob.t_end, output=list(prob.names),
                          validate=False)
    t = r["time"]
    keep = np.r_[t[1:] != t[:-1], True]
    Y = np.column_stack([np.interp(prob.grid, t[keep], r[n][keep]) for n in prob.names])
    elapsed = time.perf_counter() - start
    if not np.isclose(t[-1], prob.t_end) or not np.all(np.isfinite(Y)):
        raise RuntimeError(f"FMPy's run ended at t = {t[-1]}")
    return elapsed, Y, {}


# --------------------------------------------------------------------------------------------------
# driver
# --------------------------------------------------------------------------------------------------


def earlier_timeouts(raw_path: Path, round_k: int):
    out = set()
    if not raw_path.is_file():
        return out
    try:
        rows = bc.read_table(raw_path, bc.RAW_HEADER)
    except ValueError:
        return out
    for r in rows:
        try:
            rk = int(r["round"])
        except ValueError:
            continue
        if rk < round_k and r["status"] == "timeout":
            out.add(bc.case_key(r["solver"], r["scene"], r["rtol"], r["h"]))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--round", type=int, required=True, help="round number (0 = warm-up, writes sol/)")
    ap.add_argument("--dir", type=Path, default=bc.DEFAULT_DIR, help="benchmark directory")
    ap.add_argument("--cases", type=Path, default=None, help="cases.csv (default <dir>/cases.csv)")
    ap.add_argument("--max-seconds", type=float, default=120.0, help="abort a case after this many s")
    args = ap.parse_args(argv)

    out_dir = args.dir
    cases_path = args.cases or out_dir / "cases.csv"
    raw_path = out_dir / "raw.csv"
    cases = [c for c in bc.read_cases(cases_path) if c["solver"] in METHODS or c["solver"] in HOSTS]
    random.Random(args.round).shuffle(cases)
    skip = earlier_timeouts(raw_path, args.round)

    t_setup = time.perf_counter()
    problems = {}
    for c in cases:
        if c["scene"] in bc.SCENES and c["scene"] not in problems:
            problems[c["scene"]] = Problem(c["scene"])
    import scipy.integrate  # noqa: F401  (imported before any timing)

    fmu_dir, model_description = out_dir / "fmu" / "BeamBody", None
    if any(c["solver"] in HOSTS for c in cases):
        import fmpy  # noqa: F401  (imported, the FMU read and its library loaded before any timing)
        from fmpy.fmi2 import FMU2Model

        model_description = fmpy.read_model_description(str(fmu_dir), validate=False)
        FMU2Model(guid=model_description.guid, unzipDirectory=str(fmu_dir), modelIdentifier="BeamBody",
                  instanceName="warm-up")

    print(
        f"bench_scipy: round {args.round}: {len(cases)} cases, setup {time.perf_counter() - t_setup:.1f} s",
        file=sys.stderr,
    )

    t_round = time.perf_counter()
    for c in cases:
        solver, scene = c["solver"], c["scene"]
        row = {"round": args.round, "solver": solver, "scene": scene, "rtol": c["rtol"], "h": c["h"]}
        key = bc.case_key(solver, scene, c["rtol"], c["h"])
        rtol = bc.parse_opt_float(c["rtol"])
        if scene not in problems:
            row["status"] = f"unknown scene {scene}"
        elif rtol is None:
            row["status"] = "no rtol"
        elif key in skip:
            row["status"] = "skipped-after-timeout"
        else:
            try:
                if solver in HOSTS:
                    elapsed, Y, cnt = solve_fmpy(problems[scene], rtol, fmu_dir, model_description)
                else:
                    elapsed, Y, cnt = solve_case(problems[scene], METHODS[solver], rtol, args.max_seconds)
            except Timeout:
                row["status"] = "timeout"
            except Exception as exc:  # a failed case is a row, not a crash
                row["status"] = bc.clean_status(f"{type(exc).__name__}: {exc}")
            else:
                row.update(
                    time_s=repr(elapsed),
                    steps=cnt.get("steps", ""),
                    rhs_evals=cnt.get("rhs_evals", ""),
                    jac_evals=cnt.get("jac_evals", ""),
                    lu_factorizations=cnt.get("lu_factorizations", ""),
                    status="ok",
                )
                if args.round == 0:
                    prob = problems[scene]
                    bc.write_sol(
                        out_dir / "sol" / bc.sol_name(solver, scene, c["rtol"], c["h"]),
                        prob.grid,
                        Y,
                        prob.names,
                    )
                print(
                    f"  {solver:12s} {scene:21s} rtol={c['rtol']:8s} {elapsed:8.3f} s "
                    f"steps={cnt.get('steps')} rhs={cnt.get('rhs_evals')} (scipy nfev {cnt.get('scipy_nfev')}) "
                    f"jac={cnt.get('jac_evals')} lu={cnt.get('lu_factorizations')}",
                    file=sys.stderr,
                )
        if row.get("status") != "ok":
            print(f"  {solver:12s} {scene:21s} rtol={c['rtol']:8s} {row['status']}", file=sys.stderr)
        bc.append_raw(raw_path, [row])
    print(f"bench_scipy: round {args.round} done in {time.perf_counter() - t_round:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
