"""The FMU as a newcomer first meets it in FMPy: what a run with no start values does, whether warnings
reach a host that never asked for a debug trace, whether the declared ranges are true, and whether the
FMU and the CLI call the same thing by the same name and obey the same rules.
"""

from __future__ import annotations

import math

import fmpy
import numpy as np
import pytest

from conftest import COLUMNS, FORMULATIONS
from fmu_util import H0, PHI_SOURCE_LAW, install_logger_proxy

WARNING = 1


def simulate(fmu_unzipdir, stop_time=1.0, input=None, **start_values):
    """simulate_fmu with a logger and debug logging off: (result, [(status, category, message)])."""
    messages = []

    def logger(env, instance_name, status, category, message):
        messages.append((int(status), category.decode(), message.decode()))

    try:
        r = fmpy.simulate_fmu(str(fmu_unzipdir), start_values=start_values, stop_time=stop_time,
                              output_interval=H0, logger=logger, debug_logging=False, input=input)
    finally:
        install_logger_proxy()
    return r, messages


def test_a_run_with_no_start_values_says_its_input_was_never_set(fmu_unzipdir):
    """simulate_fmu with no start values returned 601 rows of zeros without a word. phi stays the FMU's
    input (phi_source = input; README: hosts such as libcosim and Ecos cannot set an enumeration), so
    the body does not turn, and the FMU says so once, as a warning that reaches FMPy's logger."""
    r, messages = simulate(fmu_unzipdir)
    assert np.all(r["v1"] == 0.0)
    warnings = [m for s, c, m in messages if s == WARNING and c == "logStatusWarning"]
    assert len(warnings) == 1 and "input `phi` has not been set" in warnings[0], messages
    assert "`phi_source` = law (2)" in warnings[0]


def test_the_paper_s_turn_warns_nothing(fmu_unzipdir):
    r, messages = simulate(fmu_unzipdir, stop_time=2.0, phi_source=PHI_SOURCE_LAW)
    assert messages == [] and np.max(np.abs(r["v1"])) > 0.1


def test_a_host_feeding_phi_to_the_law_is_told_once(fmu_unzipdir):
    """The other half of the default's choice: a host that selects the law and still feeds phi is told
    once that its phi is ignored; the law turns the body."""
    t = np.linspace(0.0, 1.0, 11)
    signal = np.array(list(zip(t, 0.5 * t)), dtype=[("time", np.float64), ("phi", np.float64)])
    r, messages = simulate(fmu_unzipdir, input=signal, phi_source=PHI_SOURCE_LAW)
    warnings = [m for s, c, m in messages if s == WARNING and c == "logStatusWarning"]
    assert len(warnings) == 1 and "`phi` is ignored" in warnings[0], messages
    assert abs(r["phi_applied"][-1] - math.pi) < 1e-12  # the law has turned the body; the host sent 0.5


def test_range_check_warn_reaches_a_host_with_logging_off(fmu_unzipdir):
    """range_check = warn with phi_end = 1000 gave theta1 = 9.3 rad and not a word, even with a logger."""
    r, messages = simulate(fmu_unzipdir, stop_time=3.0, phi_source=PHI_SOURCE_LAW, range_check=2,
                           phi_end=1000.0)
    assert np.max(np.abs(r["theta1"])) > math.pi / 2
    warnings = [m for s, c, m in messages if s == WARNING]
    assert len(warnings) == 1 and "range_check = warn" in warnings[0] and "theta1" in warnings[0], messages


def test_declared_ranges_are_what_the_fmu_takes(fmu_unzipdir):
    """l, EI, M2 and t_rot were declared min = 0, which the FMU refuses: their min is now the smallest
    positive double, so FMPy's and any host's range check refuses 0 as the FMU does."""
    md = fmpy.read_model_description(str(fmu_unzipdir))
    by_name = {v.name: v for v in md.modelVariables}
    for name in ["l", "EI", "M2", "t_rot"]:
        v = by_name[name]
        assert float(v.min) > 0.0 and float(v.min) == np.finfo(float).tiny, (name, v.min)
        with pytest.raises(Exception):
            simulate(fmu_unzipdir, stop_time=0.01, **{name: 0.0})
    for name in ["m", "J_C", "r", "atol", "fixed_step"]:
        assert float(by_name[name].min) == 0.0
    r, _ = simulate(fmu_unzipdir, stop_time=0.01, phi_source=PHI_SOURCE_LAW, m=0.0, r=0.5, J_C=0.5)
    assert len(r) > 1


def test_fixed_order_needs_fixed_step_as_in_the_cli(fmu_unzipdir):
    """fixed_order = 3 without fixed_step ran the adaptive integrator in silence, where the CLI refused."""
    messages = []
    with pytest.raises(Exception):
        _, messages = simulate(fmu_unzipdir, stop_time=0.1, phi_source=PHI_SOURCE_LAW, fixed_order=3)
    r, messages = simulate(fmu_unzipdir, stop_time=0.1, phi_source=PHI_SOURCE_LAW, fixed_order=3,
                           fixed_step=1e-3)
    assert len(r) > 1 and messages == []


def test_the_start_angle_and_initial_state_are_parameters_as_in_the_cli(fmu_unzipdir, beam_body):
    """The FMU lacked phi0 and the initial state that the CLI and the studies have. With the same
    values, the FMU (law) and the CLI start from the same state and follow the same motion."""
    from fmu_util import cli

    start = dict(phi0=0.4, v1_0=0.05, theta1_0=-0.02, dv1_0=0.1, dtheta1_0=-0.3)
    r, messages = simulate(fmu_unzipdir, stop_time=1.7, phi_source=PHI_SOURCE_LAW, **start)
    c = cli(beam_body, t_end=1.7, **start)
    assert messages == []
    assert (r["v1"][0], r["phi_applied"][0]) == (0.05, 0.4)
    assert np.max(np.abs(r["v1"] - c["v1"])) < 1e-4 * np.max(np.abs(c["v1"]))
    assert abs(r["phi_applied"][-1] - (0.4 + math.pi)) < 1e-12


def test_the_fmu_and_the_cli_use_one_name_for_each_thing(fmu_unzipdir, beam_body):
    """phi_feed against phi_source, dae-stabilized against dae_stabilized, phi/dphi/ddphi against
    phi_applied and its rates: one name each now."""
    md = fmpy.read_model_description(str(fmu_unzipdir))
    by_name = {v.name: v for v in md.modelVariables}
    assert [i.name for i in by_name["formulation"].declaredType.items] == list(FORMULATIONS)
    assert [i.name for i in by_name["phi_source"].declaredType.items] == ["input", "law"]
    outputs = {v.name: v.unit for v in md.modelVariables if v.causality == "output"}
    for column in COLUMNS[1:]:
        assert column in outputs, column
    # The CLI takes the FMU's names for the same settings.
    from conftest import run_cli

    for name in ["phi_source=input", "formulation=dae_stabilized", "range_check=warn", "phi_interpolation=taylor"]:
        run_cli(beam_body, ["simulate", "scenes/paper.toml", "--set", name, "--set", "t_end=0.02"])


def test_a_failed_step_says_integration_failed_once(fmu_unzipdir):
    """The Discard message said "fmi2DoStep: integration failed: integration failed: ...". The step:
    the paper's fixed-step BDF5 at h = 0.5 s on a beam 10^4 times stiffer; Newton fails at once."""
    r, messages = simulate(fmu_unzipdir, stop_time=1.0, phi_source=PHI_SOURCE_LAW, EI=1e7, fixed_step=0.5,
                           fixed_order=5)
    failed = [m for s, c, m in messages if c == "logStatusDiscard"]
    assert len(failed) == 1 and failed[0].count("integration failed") == 1, messages
    assert failed[0].startswith("fmi2DoStep: integration failed: ")
