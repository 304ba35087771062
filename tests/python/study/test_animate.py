"""`beam-body-study animate`: the drawn beam's geometry, checked by a route of its own (scipy's
quadrature of the inextensible shortening), and a short GIF end to end."""

from __future__ import annotations

import re
import sys

import numpy as np
import pytest
from scipy.integrate import quad

from conftest import PAPER_SCENE, REPO

sys.path.insert(0, str(REPO / "python"))

from beam_body_study import __main__ as study_main  # noqa: E402
from beam_body_study import animate as an  # noqa: E402
from beam_body_study.__main__ import main  # noqa: E402
from beam_body_study.errors import StudyError  # noqa: E402


def test_the_drawn_tip_is_where_the_model_puts_it():
    """One element with the tip at (v1, theta1): the curve ends at x = l + u1 with
    u1 = -1/2 * integral of v'^2 of the cubic, here by quadrature, and at v = v1."""
    l, v1, th1 = 2.5, -0.4, -0.3
    xs, vs = an.beam_curve(l, [(v1, th1)], per_element=400)

    def slope(x):
        s = x / l
        return v1 * (6 * s - 6 * s**2) / l + th1 * (3 * s**2 - 2 * s)

    u1 = -0.5 * quad(lambda x: slope(x) ** 2, 0, l)[0]
    assert abs(vs[-1] - v1) < 1e-12
    assert abs(xs[-1] - (l + u1)) < 1e-5 * abs(u1)
    # Two elements of the same cubic draw the same curve (their nodes read off the cubic).
    mid = an.hermite(l, 0, 0, v1, th1, 0.5)
    xs2, vs2 = an.beam_curve(l, [mid, (v1, th1)], per_element=200)
    assert abs(xs2[-1] - xs[-1]) < 1e-5 * abs(u1) and abs(vs2[-1] - v1) < 1e-12


def test_a_short_animation_is_a_gif_with_a_frame_per_output(beam_body, tmp_path):
    out = tmp_path / "turn.gif"
    code = main(["animate", str(REPO / "scenes" / "paper.toml"), "--elements", "2",
                 "--set", "t_end=0.5", "--fps", "10", "--cli", str(beam_body), "-o", str(out)])
    assert code == 0
    from PIL import Image

    with Image.open(out) as im:
        assert im.format == "GIF" and im.n_frames == 6
        frames = []
        for k in (0, 5):
            im.seek(k)
            frames.append(np.asarray(im.convert("RGB"), dtype=float))
    assert np.abs(frames[0] - frames[1]).mean() > 0.1  # the beam moved


def test_a_name_that_is_not_a_gif_is_refused(beam_body, tmp_path):
    with pytest.raises(StudyError, match=r"\.gif"):
        an.animate(str(beam_body), str(REPO / "scenes" / "paper.toml"), tmp_path / "x.mp4", [])


def test_a_failed_run_says_error_once_naming_the_run(beam_body, tmp_path, capsys):
    """The quadratic beam leaves its range in the turn of 0.2 s: one `error:`, not the CLI's
    own repeated after the tool's, and the run named."""
    code = main(["animate", str(PAPER_SCENE), "--set", "t_rot=0.2", "--cli", str(beam_body),
                 "-o", str(tmp_path / "turn.gif")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("error:") == 1 and err.startswith("error: the run of "), err
    assert str(PAPER_SCENE) in err and "t_rot=0.2" in err and "outside the model's range" in err
    assert an.cli_message("beam-body: ...\nerror: no such file\n", 2) == "no such file"
    assert an.cli_message("", 101) == "exit status 101"


def test_the_usage_lists_animate(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert re.search(r"^ +beam-body-study animate SCENE\.toml -o ", out, re.M), out
    assert re.search(r"python -m beam_body_study\s+run\|plot\|animate", study_main.__doc__)
