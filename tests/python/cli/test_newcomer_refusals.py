"""Issue 43's refusals that said nothing, or too little, to a newcomer: `residual` ignoring the settings
of a model it does not evaluate (item 3), `modes --count` above the model's modes (item 12), and a
duplicate key in a scene that the message did not name (item 13). Each test failed on the main branch
before the change it guards: the first two exited 0, the third said only "duplicate key".
"""

from __future__ import annotations

import subprocess

import pytest

from conftest import REPO

#: A state of the reduced formulation: phi dphi ddphi v1 theta1 dv1 dtheta1 ddv1 ddtheta1.
STATE = "0.3 0.5 0.1 0.01 0.02 0.0 0.1 0.2 0.3\n"


def cli(beam_body, *args, stdin=None):
    """The CLI's (exit code, stdout, stderr), whatever the exit code."""
    proc = subprocess.run([str(beam_body), *map(str, args)], input=stdin, capture_output=True, text=True,
                          timeout=120, cwd=REPO)
    return proc.returncode, proc.stdout, proc.stderr


def refused(beam_body, *args, needles=(), stdin=None):
    """Exit code 2, nothing on stdout, one `error:` line on stderr holding every needle."""
    code, out, err = cli(beam_body, *args, stdin=stdin)
    assert code == 2, f"exit {code}: {err}"
    assert out == "", out[:200]
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for n in needles:
        assert n in err, (n, err)
    return err


# ----- item 3: residual evaluates the paper's model only ------------------------------------------------

@pytest.mark.parametrize("setting", ["n_elements=4", "beam=exact", "damping_alpha=0.5", "damping_beta=0.001",
                                     "damping_ratio=0.02", "beam_gravity=true"])
def test_residual_refuses_the_settings_it_would_ignore(beam_body, setting):
    """`residual` gave the same numbers with and without these, exit 0. It evaluates the paper's
    two-coordinate equations, so now it refuses them, naming the setting and its value."""
    name, value = setting.split("=")
    refused(beam_body, "residual", "--formulation", "reduced", "--set", setting, stdin=STATE,
            needles=(f"{name} = {value}", "paper's equations", "one element of the quadratic beam"))


def test_residual_takes_the_paper_model_given_explicitly(beam_body):
    """The paper's own values are not refused, and give the numbers of the defaults."""
    code, plain, err = cli(beam_body, "residual", "--formulation", "reduced", stdin=STATE)
    assert code == 0, err
    code, explicit, err = cli(beam_body, "residual", "--formulation", "reduced", "--elements", "1",
                              "--beam", "quadratic", "--set", "damping_ratio=0", "--set", "beam_gravity=false",
                              stdin=STATE)
    assert code == 0, err
    assert explicit == plain and len(plain.split()) == 4


# ----- item 12: modes --count within the model's modes ------------------------------------------------

def test_modes_count_above_the_models_modes_is_refused(beam_body):
    """`modes --count 4` on one element printed two periods and said nothing. One element has two
    coordinates, so two modes: the message names the limit and how to get more."""
    refused(beam_body, "modes", "--count", "4",
            needles=("--count 4", "1 element has 2 coordinates", "at most 2", "--elements 2"))
    refused(beam_body, "modes", "--elements", "2", "--beam", "exact", "--count", "5",
            needles=("2 elements has 4 coordinates", "at most 4", "--elements 3"))


def test_modes_count_up_to_the_models_modes_prints_them_all(beam_body):
    code, out, err = cli(beam_body, "modes", "--elements", "2", "--count", "4")
    assert code == 0, err
    header = out.splitlines()[0].split()
    assert header[-2:] == ["T4", "[s]"], header


# ----- item 13: a duplicate key in a scene is named ---------------------------------------------------

def test_a_duplicate_key_in_a_scene_is_named_with_its_lines(beam_body, tmp_path):
    """The message was "not valid TOML: duplicate key", without the key."""
    scene = tmp_path / "dup.toml"
    scene.write_text("t_end = 2.0\nEI = 900.0\n\nt_end = 3.0\n")
    err = refused(beam_body, "simulate", scene)
    assert f"{scene}:4:1: not valid TOML: duplicate key `t_end` (first given on line 1)" in err, err


def test_a_duplicate_key_in_a_study_file_is_named(beam_body, tmp_path):
    study = tmp_path / "dup_study.toml"
    study.write_text("metrics = [\"max_v1\"]\n\n[parameters.EI]\nvalues = [900.0, 1000.0]\n"
                     "values = [800.0]\n")
    err = refused(beam_body, "study", study, "--plan")
    assert f"{study}:5:1: not valid TOML: duplicate key `values` (first given on line 4)" in err, err
