"""The CLI as a newcomer meets it: run as a process, with what it must refuse, with its pipes closed,
with scene files that are TOML and ones that are not, and with its help.

Each test names the defect it guards against: a wrong answer with exit code 0, a run that never ends
or fills the disk, a panic on a closed pipe, a scene file read by something other than a TOML parser,
and messages that do not say what is wrong in the user's words.
"""

from __future__ import annotations

import math
import subprocess
import textwrap

import pytest

from conftest import HEADER, REPO, read_csv, run_cli

PAPER = REPO / "scenes" / "paper.toml"


def cli(beam_body, *args, stdin=None, timeout=120):
    """The CLI's (exit code, stdout, stderr), whatever the exit code."""
    proc = subprocess.run([str(beam_body), *map(str, args)], input=stdin, capture_output=True, text=True,
                          timeout=timeout, cwd=REPO)
    return proc.returncode, proc.stdout, proc.stderr


def refused(beam_body, *args, needles=(), **kw):
    """Asserts exit code 2, nothing on stdout, one `error:` line on stderr with every needle."""
    code, out, err = cli(beam_body, *args, **kw)
    assert code == 2, f"exit {code}: {err}"
    assert out == "", f"stdout of a refused run: {out[:200]!r}"
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for n in needles:
        assert n in err, f"{n!r} not in {err!r}"
    return err


# ----- wrong answers with exit code 0, and runs that never end ---------------------------------------

@pytest.mark.parametrize("dt_out", ["1e-300", "1e-20", "1e-19", "1e-17"])
def test_absurd_output_steps_are_refused_before_anything_runs(beam_body, dt_out):
    """dt_out = 1e-300 once wrote one row, t = 10.2 s, with exit code 0 (the row count saturated and
    wrapped); 1e-17 wrote without end. Refused now, naming dt_out, the count and the limit."""
    refused(beam_body, "simulate", PAPER, "--set", f"dt_out={dt_out}", needles=("`dt_out`", "`max_rows` = 1000000"))


def test_a_run_larger_than_max_rows_is_refused_and_the_limit_can_be_raised(beam_body):
    refused(beam_body, "simulate", PAPER, "--set", "t_end=1e9", needles=("makes 11764705882", "output rows", "--max-rows"))
    args = ["simulate", PAPER, "--set", "t_end=1", "--set", "dt_out=1e-3"]
    refused(beam_body, *args, "--max-rows", "1000", needles=("1001 output rows", "`max_rows` = 1000"))
    c = read_csv(run_cli(beam_body, [*args, "--max-rows", "1001"]))
    assert len(c["t"]) == 1001 and c["t"][0] == 0.0 and c["t"][-1] == 1.0


def test_a_closed_stdout_stops_the_run_at_once(beam_body):
    """`simulate ... | head -2` once computed until killed (13 minutes at 100 % CPU for dt_out = 1e-17).
    The run below would take minutes; with its reader gone it stops at the first failed write, quietly,
    with status 141 (as a tool ended by SIGPIPE reports in a shell)."""
    proc = subprocess.Popen([str(beam_body), "simulate", str(PAPER), "--set", "t_end=1e6", "--set", "dt_out=0.1",
                             "--max-rows", "20000000"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=REPO)
    first = [proc.stdout.readline(), proc.stdout.readline()]
    proc.stdout.close()
    code = proc.wait(timeout=60)
    err = proc.stderr.read().decode()
    assert first[0].decode().startswith("t [s],v1 [m]")
    assert code == 141 and err == "", (code, err)
    # The same through a shell pipeline, as the issue ran it.
    sh = subprocess.run(["bash", "-c", f"set -o pipefail; '{beam_body}' simulate '{PAPER}' --set t_end=1e6 "
                         "--set dt_out=0.1 --max-rows 20000000 | head -2"], capture_output=True, text=True,
                        timeout=60, cwd=REPO)
    assert sh.returncode == 141 and len(sh.stdout.splitlines()) == 2 and sh.stderr == "", sh


def test_a_closed_stderr_is_no_panic(beam_body, tmp_path):
    """`simulate ... -o /dev/null 2>&1 | true` exited with 101 (a panic) five times out of five."""
    for redirect in ["2>&1 | true; exit ${PIPESTATUS[0]}", "2>&-"]:
        out = tmp_path / "out.csv"
        sh = subprocess.run(["bash", "-c", f"'{beam_body}' simulate '{PAPER}' -o '{out}' {redirect}"],
                            capture_output=True, text=True, timeout=120, cwd=REPO)
        assert sh.returncode == 0, (redirect, sh)
        assert len(out.read_text().splitlines()) == 1202, redirect


def test_a_study_with_a_closed_stdout_stops(beam_body, tmp_path):
    study = tmp_path / "s.toml"
    study.write_text(f'scene = "{PAPER}"\nmetrics = ["max_v1"]\n[set]\nt_end = 1.0\n'
                     "[parameters.M2]\nstart = 6\nstop = 24\ncount = 100000\n")
    sh = subprocess.run(["bash", "-c", f"set -o pipefail; '{beam_body}' study '{study}' --quiet | head -2"],
                        capture_output=True, text=True, timeout=120, cwd=REPO)
    assert sh.returncode == 141 and len(sh.stdout.splitlines()) == 2 and sh.stderr == "", sh


def test_a_study_states_its_size_and_refuses_an_absurd_one(beam_body, tmp_path):
    """`count = 100000000`, a plausible typo, started at once and wrote 2.6 GB of chunks."""
    study = tmp_path / "s.toml"
    study.write_text(f'scene = "{PAPER}"\n[parameters.M2]\nstart = 6\nstop = 24\ncount = 100000000\n')
    refused(beam_body, "study", study, needles=("100000000 cases", "--max-cases 1000000"))
    small = tmp_path / "small.toml"
    small.write_text(f'scene = "{PAPER}"\nmetrics = ["max_v1"]\n[set]\nt_end = 0.5\n'
                     "[parameters.M2]\nstart = 6\nstop = 24\ncount = 3\n")
    code, out, err = cli(beam_body, "study", small)
    assert code == 0 and err.splitlines()[0].startswith("study: 3 cases of 3 on"), err
    refused(beam_body, "study", small, "--max-cases", "2", needles=("3 cases to run",))


def test_a_study_with_too_many_rows_is_refused_not_a_wrong_number(beam_body, tmp_path):
    """`[set] dt_out = 1e-300` gave peak_M = 47.0 with status ok; the right value is 183.6."""
    study = tmp_path / "s.toml"
    study.write_text(f'scene = "{PAPER}"\nmetrics = ["peak_M"]\n[set]\ndt_out = 1e-300\n'
                     "[parameters.M2]\nvalues = [12]\n")
    refused(beam_body, "study", study, needles=("the base scene", "`dt_out` = 1e-300", "`max_rows`"))
    study.write_text(f'scene = "{PAPER}"\nmetrics = ["peak_M"]\n[parameters.M2]\nvalues = [12]\n')
    code, out, err = cli(beam_body, "study", study, "--quiet")
    header, row = out.splitlines()
    assert header == "case,M2 [kg],peak_M [N.m],status,message,steps"
    assert row.split(",")[3] == "ok" and abs(float(row.split(",")[2]) - 183.6) < 0.1, row


# ----- scene files are TOML ------------------------------------------------------------------------

def write(tmp_path, text):
    path = tmp_path / "scene.toml"
    path.write_text(textwrap.dedent(text))
    return path


def test_valid_toml_is_accepted(beam_body, tmp_path):
    scene = write(tmp_path, """\
        range_check = "warn"   # say so
        phi_source = 'law'
        EI = 1_000
        t_end = 0.1
        """)
    c = read_csv(run_cli(beam_body, ["simulate", scene]))
    assert c["t"][-1] == 0.1


@pytest.mark.parametrize("text, needles", [
    ("t_end = 0.1\nformulation = dae\n", [":2:15: not valid TOML"]),
    ("t_end = 0.1\nt_end = 0.2\n", [":2:", "not valid TOML"]),
    ("t_end = \"5\"\n", [":1: `t_end` = \"5\": must be a number, positive and finite [s], not a string"]),
    ("\nbeam_theory = \"exact\"\n", [":2: unknown setting `beam_theory`", "must be one of l, EI"]),
    ("\nbeam = \"elastica\"\n", [":2: `beam` = \"elastica\": must be one of quadratic, exact"]),
    ("formulation = \"dae-stabilized\"\n", [":1:", "one of reduced, dae, dae_stabilized, linear"]),
    ("[model]\nEI = 1.0\n", [":1: `[model]`: a scene has no tables"]),
])
def test_invalid_toml_and_wrong_types_are_refused_naming_file_line_and_key(beam_body, tmp_path, text, needles):
    scene = write(tmp_path, text)
    err = refused(beam_body, "simulate", scene, needles=needles)
    assert f"error: {scene}:" in err, err


def test_an_unknown_setting_on_the_command_line_is_named(beam_body):
    """`--set beam_theory=exact` said "not a number" instead of "unknown name"."""
    refused(beam_body, "simulate", PAPER, "--set", "beam_theory=exact", needles=("unknown setting `beam_theory`",))
    refused(beam_body, "simulate", PAPER, "--set", "t_end=soon", needles=("`t_end` = soon: must be a number",))


# ----- in the user's words -------------------------------------------------------------------------

def test_help_and_version_on_every_command(beam_body):
    code, out, _ = cli(beam_body, "--version")
    assert code == 0 and out.startswith("beam-body ") and out.count(".") == 2
    code, out, _ = cli(beam_body, "--help")
    assert code == 0 and "simulate" in out and "study" in out
    for command in ["simulate", "modes", "residual", "study"]:
        code, out, err = cli(beam_body, command, "--help")
        assert code == 0 and out.startswith(f"usage: beam-body {command}"), (command, err)
    code, out, _ = cli(beam_body, "simulate", "--help")
    for column in HEADER:
        assert column in out
    assert "max_rows = 1000000" in out and "--fixed-order VALUE" in out


def test_residual_needs_its_formulation(beam_body):
    """`residual` without --formulation silently used `reduced`."""
    refused(beam_body, "residual", stdin="0 0 0 0 0 0 0 0 0\n", needles=("--formulation",))


def test_fixed_order_without_fixed_step_names_what_the_user_typed(beam_body):
    """`--order 3` alone said "`fixed_order` needs `fixed_step`", naming settings the user had not typed."""
    refused(beam_body, "simulate", PAPER, "--fixed-order", "3", needles=("`fixed_order` = 3", "`fixed_step` > 0"))
    c = read_csv(run_cli(beam_body, ["simulate", PAPER, "--fixed-order", "3", "--fixed-step", "1e-3",
                                     "--set", "t_end=0.1"]))
    assert c["t"][-1] == 0.1


def test_a_singular_body_and_a_bad_initial_state_are_said_plainly(beam_body):
    """m = J_C = r = 0 said "parameter `m, J_C, r` = 0.0 ... (its determinant is the value shown)";
    v1_0 = 3 said "integration failed ... at t = 0.0000013757"."""
    err = refused(beam_body, "simulate", PAPER, "--set", "m=0", "--set", "J_C=0", "--set", "r=0",
                  needles=("singular at the start", "massless beam (m = 0.0)", "J_C = 0.0"))
    assert "determinant" not in err
    refused(beam_body, "simulate", PAPER, "--set", "v1_0=3",
            needles=("initial state `v1_0` = 3.0", "|v1| <= l = 2.5"))


def test_the_csv_names_its_units_and_its_numbers_read_back_exactly(beam_body):
    out = run_cli(beam_body, ["simulate", PAPER, "--set", "t_end=0.017"])
    lines = out.splitlines()
    assert lines[0].split(",") == HEADER
    t = [row.split(",")[0] for row in lines[1:]]
    assert t == ["0.0", "0.0085", "0.017"]
    for field in lines[2].split(","):
        assert repr(float(field)) == field or float(repr(float(field))) == float(field)
        assert not math.isnan(float(field))


def test_beam_columns_are_added_after_the_paper_s_and_change_nothing_else(beam_body):
    """`--columns beam` appends M_root, Q_root and the deflection at l/4, l/2, 3l/4; the paper's
    15 columns stay as they are, byte for byte, and with one element the quarter points are the
    paper's cubic through the tip's deflection and slope."""
    args = ["simulate", str(REPO / "scenes" / "paper.toml"), "--set", "t_end=1", "--set", "dt_out=0.1"]
    plain = run_cli(beam_body, args)
    beam = run_cli(beam_body, args + ["--columns", "beam"])
    p_lines, b_lines = plain.splitlines(), beam.splitlines()
    assert len(p_lines) == len(b_lines) == 12
    for p, b in zip(p_lines, b_lines):
        cells = b.split(",")
        assert ",".join(cells[:15]) == p and len(cells) == 20
    assert b_lines[0].split(",")[15:] == [
        "M_root [N.m]", "Q_root [N]", "v_quarter [m]", "v_mid [m]", "v_three_quarter [m]"]
    rows = read_csv(beam)
    l = 2.5
    for xi, name in ((0.25, "v_quarter"), (0.5, "v_mid"), (0.75, "v_three_quarter")):
        cubic = rows["v1"] * (3 * xi**2 - 2 * xi**3) + l * rows["theta1"] * (xi**3 - xi**2)
        assert max(abs(cubic - rows[name])) <= 1e-15 * max(abs(rows["v1"])) + 1e-300


def test_shape_columns_hold_every_node_and_the_last_is_the_tip(beam_body):
    """`--columns shape` appends v_k, theta_k for the nodes k = 1..n after the beam's columns;
    node n is the tip (v1, theta1), and with an elements' shape of 4 elements the middle node
    (k = 2) is the beam's deflection at l/2 (the column v_mid)."""
    args = ["simulate", str(REPO / "scenes" / "paper.toml"), "--set", "t_end=0.6", "--set", "dt_out=0.1"]
    beam = read_csv(run_cli(beam_body, args + ["--elements", "4", "--columns", "beam"]))
    text = run_cli(beam_body, args + ["--elements", "4", "--columns", "shape"])
    header = text.splitlines()[0].split(",")
    assert header[20:] == [f"{v}_{k} [{u}]" for k in range(1, 5) for v, u in (("v", "m"), ("theta", "rad"))]
    shape = read_csv(text)
    for name in beam:
        assert (shape[name] == beam[name]).all(), name
    assert (shape["v_4"] == shape["v1"]).all() and (shape["theta_4"] == shape["theta1"]).all()
    assert (shape["v_2"] == shape["v_mid"]).all()
    assert max(abs(shape["v_1"])) > 0.01 * max(abs(shape["v1"]))
    one = read_csv(run_cli(beam_body, args + ["--columns", "shape"]))
    assert (one["v_1"] == one["v1"]).all() and (one["theta_1"] == one["theta1"]).all()


@pytest.mark.parametrize("value", ["0", "33", "2.5"])
def test_an_element_count_out_of_range_is_refused_naming_the_setting(beam_body, value):
    r = subprocess.run([str(beam_body), "simulate", str(REPO / "scenes" / "paper.toml"), "--elements", value],
                       capture_output=True, text=True)
    assert r.returncode == 2
    assert "n_elements" in r.stderr and "1..=32" in r.stderr, r.stderr


def test_negative_damping_is_refused_naming_the_setting(beam_body):
    for name in ("damping_alpha", "damping_beta", "damping_ratio"):
        r = subprocess.run([str(beam_body), "simulate", str(REPO / "scenes" / "paper.toml"), "--set", f"{name}=-0.1"],
                           capture_output=True, text=True)
        assert r.returncode == 2 and name in r.stderr and "non-negative" in r.stderr, r.stderr
