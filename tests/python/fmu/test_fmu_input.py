"""phi as an input (phi_source = input, the default): values only through fmpy.simulate_fmu(input=...),
and values with derivatives through fmpy.fmi2.FMU2Slave (FMPy 0.3.32's set_input_derivatives is broken).

Two kinds of check:
- against the CLI fed the same way (`--set phi_source=input [--set input_derivatives=true] --set dt_comm=H`): the FMU and the
  standalone solver reconstruct phi over a step with the same code, so they must agree to rounding;
- against the exact law (the CLI with the law itself at rtol 1e-12): the error of the reconstruction, its
  convergence in the communication step H and its observed order log2(e(H)/e(H/2)).

The input samples are the law exactly as the Rust model evaluates it (fmu_util.cli_law: the CLI's own
samples on the grid), and the table is exactly on the communication grid, so FMPy's linear interpolation
hands the FMU the sample itself. test_law_samples_are_the_clis checks that these are the paper's law, and
that Python's own evaluation (fmu_util.law, with the platform's sin and cos) agrees to an ulp or two.

The FMU interpolates phi between communication points by `phi_interpolation`: `smooth` (the default:
a C2 quintic to a target extrapolated from the last two samples' values and derivatives, or a C1 cubic
to the target extrapolated from the last values; src/model/signal.rs) or `taylor` (FMI's literal
polynomial phi + phi' s + phi'' s^2/2 per step). The convergence tests measure both.

Figures go to target/fmu-report.txt.
"""

from __future__ import annotations

import math

import fmpy
import numpy as np
import pytest

from fmu_util import (
    H0,
    STATES,
    T_END,
    T_ROT,
    Slave,
    cli,
    cli_law,
    comm_grid,
    law,
    law_sin2,
    law_table,
    run_derivatives,
)

RTOL = 1e-10  # tolerance of the input-mode runs: far below the reconstruction errors measured here
REF_RTOL = 1e-12  # the "exact" law: the CLI at rtol 1e-12 (it differs from rtol 1e-10 by 5.5e-8 m)
HALVINGS = 4  # H = H0 * {1, 1/2, 1/4, 1/8}
HS = [H0 / 2**k for k in range(HALVINGS)]
ERR_STATES = ("v1", "theta1")

# FMU vs CLI with the same feed: the same arithmetic on the same samples. Measured: values 4.6e-15, only at
# the last row, where FMPy's last communication point is 1200 * 0.0085 = 10.200000000000001 and the CLI's
# is 10.2 (every other row is identical); derivatives 0 (the FMU2Slave loop ends exactly at 10.2).
SAME_FEED_TOL = 1e-12
# derivatives feed: the brief's bound (the measured difference is 0, see above).
DERIVATIVES_TOL = 1e-6
# Observed orders: assert at least these on the last halving. Measured at rtol 1e-10, H0/4 -> H0/8:
# values, degree 3: 2.95, degree 2: 2.99, degree 1: 1.99 (the scheme's documented order is 2, for d = 3).
MIN_ORDER_VALUES = 1.5
# (phi'' jumps at t = 0 and t = t_rot; a reconstruction whose phi' jumped at communication points would
# lose part of the drive's impulse there and converge at order 1 only, as FMI's Taylor polynomial does.
# The values feed avoids that with a C1 Hermite piece per step, src/model/signal.rs.)
# degree 0 is not expected to converge (the Hermite step's target slope is 0: O(1) error in phi'), but it
# must stay bounded: measured max error 4.3e-2 m at H0; bound 0.1 m (max |v1| is 0.59 m). Measured with
# the CLI (phi_source=input, phi_extrapolation=0) at smaller H: 7.2e-3 (H0/8), 4.9e-3, 4.1e-3, 3.7e-3
# (H0/64): an error floor, not convergence.
DEGREE0_MAX_ERR = 0.1
# After the turn phi is constant and every reconstruction is exact, so the error on [2, 10.2] is the error
# made during the turn, carried along: measured ratio err[2,10.2]/err[0,2) = 0.35 ... 1.17; bound 3.
SMOOTH_PART_RATIO = 3.0

_SIM: dict = {}


def simulate_values(fmu_dir, beam_body, h, degree=3):
    """simulate_fmu with the law's values on the grid k*h as the input table (memoised)."""
    key = (h, degree)
    if key not in _SIM:
        _SIM[key] = fmpy.simulate_fmu(
            str(fmu_dir),
            input=law_table(h, phi_fn=cli_law(beam_body, h)),
            start_values={"phi_extrapolation": degree},  # phi_source: the default, input
            relative_tolerance=RTOL,
            output_interval=h,
            stop_time=T_END,
            output=["v1", "theta1", "u2", "phi_applied"],
        )
    return _SIM[key]


def on_paper_grid(r, h):
    """The rows of a run at communication step h that fall on the paper's output grid k*H0."""
    step = int(round(H0 / h))
    rows = r[::step]
    assert len(rows) == 1201, f"{len(rows)} rows on the k*{H0} grid, expected 1201"
    assert np.max(np.abs(rows["time"] - np.arange(1201) * H0)) <= 1e-12
    return rows


def err(rows, ref, mask=slice(None)):
    return max(float(np.max(np.abs(rows[q][mask] - ref[q][mask]))) for q in ERR_STATES)


def orders(errors):
    return [math.log2(a / b) for a, b in zip(errors[:-1], errors[1:])]


def test_law_samples_are_the_clis(beam_body, fmu_report):
    """The input samples (the CLI's own law, fmu_util.cli_law) are the paper's pi*sin^2(pi t/(2*0.85)) to
    rounding on the finest grid, and Python's evaluation of the same expression with the platform's sin
    and cos (fmu_util.law) agrees with them to a few ulps of each column's scale: the model's sin and cos
    (the libm crate) are not glibc's, bit for bit, which is why the same-feed tests take the CLI's."""
    h = HS[-1]
    c = cli(beam_body, dt_out=h)
    t = c["t"]
    assert np.array_equal(t, comm_grid(h)[:-1].tolist() + [T_END]), "the CLI's grid is not k*h"
    model = np.array([cli_law(beam_body, h)(x) for x in comm_grid(h)])
    python = np.array([law(x) for x in t])
    # at t = t_rot the CLI's columns show the turn's one-sided derivatives; the grid does not hit it
    away = np.abs(t - T_ROT) > 1e-12
    scale = np.max(np.abs(model), axis=0)
    ulps = np.max(np.abs(python[away] - model[away]), axis=0) / (np.finfo(float).eps * scale)
    n_diff = int(np.count_nonzero(python[away] != model[away]))
    sin2 = float(np.max(np.abs(law_sin2(t) - model[:, 0])))
    fmu_report.figure(
        "input", "law_samples_python_vs_model", n_diff,
        f"of {3 * int(np.count_nonzero(away))} differ, by at most {max(ulps):.2f} eps*scale; "
        f"|model - pi sin^2| max {sin2:.1e}",
    )
    assert sin2 <= 4 * np.finfo(float).eps * math.pi
    assert max(ulps) <= 4.0, f"Python's law and the model's differ by {ulps} eps*scale (phi, phi', phi'')"


@pytest.mark.parametrize("k", range(HALVINGS))
def test_values_input_matches_cli_same_feed(fmu_unzipdir, beam_body, fmu_report, k):
    """(a) values only, communication step H: the FMU equals the CLI with phi_source=input, dt_comm=H."""
    h = HS[k]
    r = simulate_values(fmu_unzipdir, beam_body, h)
    assert len(r) == int(round(T_END / h)) + 1, f"simulate_fmu stopped early at t = {r['time'][-1]}"
    rows = on_paper_grid(r, h)
    c = cli(beam_body, rtol=RTOL, phi_source="input", dt_comm=h)
    d = {q: float(np.max(np.abs(rows[q] - c[q]))) for q in STATES}
    d_inner = max(float(np.max(np.abs(rows[q][:-1] - c[q][:-1]))) for q in STATES)
    fmu_report.figure(f"values H={h:g}", "max|FMU-CLI(values)|", max(d.values()), f"all but the last row: {d_inner:.1e}")
    assert max(d.values()) <= SAME_FEED_TOL, f"H = {h}: FMU vs CLI with the same feed differ: {d}"


@pytest.mark.parametrize("degree", [3, 2, 1, 0])
def test_values_input_converges_to_the_law(fmu_unzipdir, beam_body, fmu_report, degree):
    """(b) values only, against the exact law: error for H = H0*{1, 1/2, 1/4, 1/8}, observed orders,
    error on the turn [0, 2) and after it [2, 10.2], for phi_extrapolation = degree."""
    ref = cli(beam_body, rtol=REF_RTOL)
    t = ref["t"]
    early, late = t < 2.0, t >= 2.0
    errors, ratios = [], []
    for h in HS:
        rows = on_paper_grid(simulate_values(fmu_unzipdir, beam_body, h, degree), h)
        e, e_early, e_late = err(rows, ref), err(rows, ref, early), err(rows, ref, late)
        errors.append(e)
        ratios.append(e_late / e_early)
        fmu_report.figure(
            f"values degree={degree} H={h:g}", "err_vs_law", e, f"[0,2): {e_early:.3e}, [2,10.2]: {e_late:.3e}"
        )
    p = orders(errors)
    fmu_report.figure(f"values degree={degree}", "observed_orders", " ".join(f"{x:.2f}" for x in p))
    assert errors[0] <= DEGREE0_MAX_ERR, f"degree {degree}: error {errors[0]:.3e} at H0"
    if degree == 0:
        # bounded, and better with a smaller step at first; no convergence is claimed for degree 0
        assert errors[1] < errors[0], f"degree 0: errors {errors}"
        return
    assert all(b < a for a, b in zip(errors, errors[1:])), f"degree {degree}: errors not decreasing: {errors}"
    assert p[-1] >= MIN_ORDER_VALUES, f"degree {degree}: observed order {p[-1]:.2f} < {MIN_ORDER_VALUES} ({p})"
    assert max(ratios) <= SMOOTH_PART_RATIO, f"degree {degree}: the error grows after the turn: {ratios}"


def test_values_input_degrees_rank(fmu_unzipdir, beam_body):
    """At every H, a higher extrapolation degree is not worse: e(3) < e(1) < e(0)."""
    ref = cli(beam_body, rtol=REF_RTOL)
    for h in HS:
        e = {d: err(on_paper_grid(simulate_values(fmu_unzipdir, beam_body, h, d), h), ref) for d in (3, 1, 0)}
        assert e[3] < e[1] < e[0], f"H = {h}: errors by degree {e}"


def run_slave_derivatives(fmu_unzipdir, md, beam_body, h, name):
    s = Slave(fmu_unzipdir, md, name=name)
    phi_fn = cli_law(beam_body, h)
    try:
        s.start(tolerance=RTOL, start_time=0.0, stop_time=T_END, phi0=phi_fn(0.0)[0])
        times = comm_grid(h)
        times[-1] = T_END
        y = run_derivatives(s, times, names=STATES, phi_fn=phi_fn)
        assert not s.errors(), s.errors()
    finally:
        s.free()
    return times, y


@pytest.mark.parametrize("h", HS[:3] + [1e-3])
def test_derivatives_input_matches_cli_same_feed(fmu_unzipdir, fmu_model_description, beam_body, fmu_report, h):
    """FMU2Slave: setReal(phi), setRealInputDerivatives orders 1 and 2 (the law's), doStep(tc, H), against
    the CLI with phi_source=input, input_derivatives=true, dt_comm=H, rtol 1e-10."""
    times, y = run_slave_derivatives(fmu_unzipdir, fmu_model_description, beam_body, h, f"derivatives-{h:g}")
    c = cli(beam_body, rtol=RTOL, phi_source="input", input_derivatives="true", dt_comm=h, dt_out=h)
    assert len(c["t"]) == len(times) and np.max(np.abs(c["t"] - times)) <= 1e-12
    d = {q: float(np.max(np.abs(y[:, i] - c[q][1:]))) for i, q in enumerate(STATES)}
    fmu_report.figure(f"derivatives H={h:g}", "max|FMU-CLI(derivatives)|", max(d.values()))
    assert max(d.values()) <= DERIVATIVES_TOL, f"H = {h}: {d}"
    assert max(d.values()) <= SAME_FEED_TOL, f"H = {h}: not to rounding: {d}"


def run_slave(fmu_unzipdir, md, beam_body, h, name, rtol, interpolation="smooth", derivatives=True):
    """FMU2Slave over the paper's scene at communication step h, phi from the CLI's law samples, with
    or without phi' and phi''; the states on the communication grid (row 0: t = 0)."""
    s = Slave(fmu_unzipdir, md, name=name)
    phi_fn = cli_law(beam_body, h)
    try:
        item = {"smooth": 1, "taylor": 2}[interpolation]
        s.start(tolerance=rtol, start_time=0.0, stop_time=T_END, phi0=phi_fn(0.0)[0],
                integers={"phi_interpolation": item})
        times = comm_grid(h)
        times[-1] = T_END
        rows = []
        for a, b in zip(times[:-1], times[1:]):
            p, dp, ddp = phi_fn(a)
            s.step_input(a, b - a, p, *((dp, ddp) if derivatives else ()))
            rows.append(s.get(STATES))
        assert not s.errors(), s.errors()
    finally:
        s.free()
    return {q: np.r_[0.0, np.array(rows)[:, i]] for i, q in enumerate(STATES)}


# The derivatives feed converges fast: at rtol 1e-10 it sits on the integrator's own error (7e-8 at
# every H of the table, against the law at 1e-12). Its order is measured at rtol 1e-14 against the law
# at 1e-14 (which differs from 1e-13 by 1.1e-10): measured 4.8e-8, 6.6e-10, 2.9e-11 at H0, H0/2, H0/4,
# orders 6.2 and 4.5.
DERIV_RTOL = 1e-14
MIN_ORDER_SMOOTH = 3.0
# The bound: at H0/8 = 1.0625 ms and tolerance 1e-9, 1e-5 in v1 and theta1.
H_FINE, FINE_RTOL, FINE_MAX_ERR = H0 / 8, 1e-9, 1e-5


def test_derivatives_input_converges_to_the_law(fmu_unzipdir, fmu_model_description, beam_body, fmu_report):
    """Smooth interpolation with phi' and phi'': error against the exact law at H = H0*{1, 1/2, 1/4}
    (rtol 1e-14), observed order >= 3; at every H of the table at least as accurate as values only; at
    H0/8 with tolerance 1e-9 within 1e-5. Taylor interpolation, for comparison, is first order."""
    ref = cli(beam_body, rtol=DERIV_RTOL)
    errors = []
    for h in HS[:3]:
        rows = run_slave(fmu_unzipdir, fmu_model_description, beam_body, h, f"order-{h:g}", DERIV_RTOL)
        step = int(round(H0 / h))
        e = max(float(np.max(np.abs(rows[q][::step] - ref[q]))) for q in ERR_STATES)
        errors.append(e)
        fmu_report.figure(f"derivatives H={h:g}", "err_vs_law (rtol 1e-14)", e)
    p = orders(errors)
    fmu_report.figure("derivatives", "observed_orders (rtol 1e-14)", " ".join(f"{x:.2f}" for x in p))
    assert min(p) >= MIN_ORDER_SMOOTH, f"observed orders {p} < {MIN_ORDER_SMOOTH}: errors {errors}"

    ref10 = cli(beam_body, rtol=REF_RTOL)
    for h in HS:
        step = int(round(H0 / h))
        rows = run_slave(fmu_unzipdir, fmu_model_description, beam_body, h, f"vs-values-{h:g}", RTOL)
        e_deriv = max(float(np.max(np.abs(rows[q][::step] - ref10[q]))) for q in ERR_STATES)
        e_values = err(on_paper_grid(simulate_values(fmu_unzipdir, beam_body, h), h), ref10)
        fmu_report.figure(f"derivatives H={h:g}", "err_vs_law (rtol 1e-10)", e_deriv, f"values: {e_values:.3e}")
        assert e_deriv <= e_values, f"H = {h}: derivatives {e_deriv:.3e} > values only {e_values:.3e}"

    rows = run_slave(fmu_unzipdir, fmu_model_description, beam_body, H_FINE, "fine", FINE_RTOL)
    ref9 = cli(beam_body, rtol=REF_RTOL)
    e = max(float(np.max(np.abs(rows[q][::8] - ref9[q]))) for q in ERR_STATES)
    fmu_report.figure(f"derivatives H={H_FINE:g}", "err_vs_law (tolerance 1e-9)", e)
    assert e <= FINE_MAX_ERR, f"H = {H_FINE}, tolerance 1e-9: error {e:.3e} > {FINE_MAX_ERR}"

    taylor = []
    for h in HS[:3]:
        rows = run_slave(fmu_unzipdir, fmu_model_description, beam_body, h, f"taylor-{h:g}", RTOL, "taylor")
        step = int(round(H0 / h))
        taylor.append(max(float(np.max(np.abs(rows[q][::step] - ref10[q]))) for q in ERR_STATES))
    p = orders(taylor)
    fmu_report.figure("derivatives, phi_interpolation = taylor", "observed_orders", " ".join(f"{x:.2f}" for x in p))
    assert all(0.8 <= x <= 1.3 for x in p), f"taylor: orders {p} ({taylor}); FMI's polynomial is first order"


def test_ramp_sent_as_values_gets_no_kick(fmu_unzipdir, fmu_model_description, beam_body, fmu_report):
    """phi = 0.5 t from t = 0, sent as values only. The reference is the same ramp sent with its
    derivatives (phi' = 0.5, phi'' = 0: every interpolation is exact). With smooth interpolation the
    start's slope is added as a jump once known, and the error falls with H; with taylor (the old
    scheme: the first step holds phi, then a C1 catch-up gives the beam an impulse of the whole slope)
    it does not."""
    t_end = 2.0

    def run(h, interpolation, derivatives):
        s = Slave(fmu_unzipdir, fmu_model_description, name=f"ramp-{interpolation}-{derivatives}-{h:g}")
        try:
            item = {"smooth": 1, "taylor": 2}[interpolation]
            s.start(tolerance=1e-10, stop_time=t_end, phi0=0.0, integers={"phi_interpolation": item})
            n = int(round(t_end / h))
            rows = []
            for k in range(n):
                tc = k * h
                s.step_input(tc, h, 0.5 * tc, *((0.5, 0.0) if derivatives else ()))
                rows.append(s.get(("v1",)))
            assert not s.errors(), s.errors()
        finally:
            s.free()
        return np.array(rows)[:, 0]

    out = {}
    for h in (0.01, 0.005):
        exact = run(h, "smooth", True)
        out[h] = {i: float(np.max(np.abs(run(h, i, False) - exact))) for i in ("smooth", "taylor")}
        fmu_report.figure(f"ramp as values H={h:g}", "max|v1 - exact|", out[h]["smooth"], f"taylor: {out[h]['taylor']:.3e}")
    assert out[0.005]["smooth"] < 0.7 * out[0.01]["smooth"], f"smooth does not converge: {out}"
    assert out[0.005]["smooth"] < 0.1 * out[0.005]["taylor"], f"no better than the kick: {out}"
    assert out[0.005]["taylor"] > 0.5 * out[0.01]["taylor"], f"the kick does not stay: {out}"


@pytest.mark.parametrize("interpolation", [1, 2])
def test_input_derivatives_apply_to_one_step(fmu_unzipdir, fmu_model_description, fmu_report, interpolation):
    """canInterpolateInputs: over a step with derivatives the FMU uses the Taylor polynomial
    phi + phi' s + phi'' s^2/2 (checked through phi_applied, dphi_applied, ddphi_applied at its end);
    the next step without derivatives does not reuse them. With phi_extrapolation = 0 the values-only
    step ends on the last sample with zero slope (a hold); stale derivatives would give phi' = 0.5 + 3 H.
    Both interpolations (1 smooth, 2 taylor) do this: the first step's polynomial is the Taylor one."""
    h = 0.01
    p0, dp0, ddp0 = 0.2, 0.5, 3.0
    s = Slave(fmu_unzipdir, fmu_model_description, name=f"one-step-{interpolation}")
    try:
        ints = {"phi_extrapolation": 0, "phi_interpolation": interpolation}
        s.start(tolerance=1e-6, start_time=0.0, stop_time=T_END, integers=ints, phi0=p0)
        names = ("phi_applied", "dphi_applied", "ddphi_applied")
        s.step_input(0.0, h, p0, dp0, ddp0)
        got = s.get(names)
        want = (p0 + dp0 * h + 0.5 * ddp0 * h * h, dp0 + ddp0 * h, ddp0)
        assert np.allclose(got, want, rtol=0, atol=1e-12), f"end of the step with derivatives: {got}, Taylor: {want}"
        s.step_input(h, h, p0)  # value only
        got2 = s.get(names)
        fmu_report.figure("input", "phi,dphi after a values-only step", f"{got2[0]!r},{got2[1]!r}", "expected p0, 0")
        assert abs(got2[0] - p0) <= 1e-9 and abs(got2[1]) <= 1e-9, (
            f"after a step without derivatives: phi, phi' = {got2[:2]}; expected the hold ({p0}, 0); "
            f"the previous step's derivatives would give phi' = {dp0 + ddp0 * h}"
        )
        assert not s.errors(), s.errors()
    finally:
        s.free()
