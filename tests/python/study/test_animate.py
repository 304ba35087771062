"""`beam-body-study animate`: the drawn beam's geometry, checked by routes of its own (scipy's
quadrature of the inextensible shortening, of the exact beam's section angle) and against the
CLI's own columns (the tip, the quarter points); the picture (title, legend, the body at
phi = pi); progress and errors on stderr; and a short GIF end to end."""

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
    xs, vs = an.quadratic_curves(l, [[v1]], [[th1]], per_element=4)

    def slope(x):
        s = x / l
        return v1 * (6 * s - 6 * s**2) / l + th1 * (3 * s**2 - 2 * s)

    u1 = -0.5 * quad(lambda x: slope(x) ** 2, 0, l)[0]
    assert abs(vs[0, -1] - v1) < 1e-12
    assert abs(xs[0, -1] - (l + u1)) < 1e-12 * l
    # Two elements of the same cubic draw the same curve (their nodes read off the cubic).
    values, slopes = an.hermite_basis([0.5])
    ends = np.array([0, 0, v1, l * th1])
    mid = (ends @ values[:, 0], ends @ slopes[:, 0] / l)
    xs2, vs2 = an.quadratic_curves(l, [[mid[0], v1]], [[mid[1], th1]], per_element=2)
    assert np.allclose(xs2, xs, rtol=0, atol=1e-12) and np.allclose(vs2, vs, rtol=0, atol=1e-12)


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


def test_the_exact_beams_mean_angles_are_found_from_the_nodes():
    """Section angles of three elements (one standing across the beam) with known mean angles
    c: the nodes' y by scipy's quadrature of sin(alpha), and c found back from them."""
    l, n = 2.5, 3
    h = l / n
    alpha = np.array([0.4, 1.3, 2.2])
    c = np.array([0.25, 0.9, 1.75])
    ends = np.concatenate([[0.0], alpha])
    y = [0.0]
    for k in range(n):
        def angle(s, k=k):
            return an.angle_basis([s / h]).T[0] @ [ends[k], ends[k + 1], c[k]]

        y.append(y[-1] + quad(lambda s: np.sin(angle(s)), 0, h, epsabs=1e-14)[0])
    found = an.element_mean_angles(l, [y[1:]], [alpha])
    assert np.allclose(found, c, rtol=0, atol=1e-9), found


def cli_run(beam_body, *sets, fps=10.0):
    """A short run of the paper's scene in 2 elements, loaded as `animate` draws it."""
    return an.load(str(beam_body), str(PAPER_SCENE),
                   ["n_elements=2", "t_end=1.0", *sets], fps)


@pytest.mark.parametrize("beam", ["quadratic", "exact"])
def test_the_drawn_beam_ends_at_the_clis_tip_and_passes_its_quarter_points(beam_body, beam):
    """The drawn centreline's tip is the CLI's (l + u2, v1); the exact beam's passes through the
    CLI's points at arc length l/4, l/2, 3l/4 (drawn from its section angle, where the
    quadratic model's shortening u = -1/2 * integral v'^2 would miss its tip by 2 mm here), and
    the body hangs at that tip."""
    run = cli_run(beam_body, f"beam={beam}")
    d, l = run.data, 2.5
    assert np.abs(run.x[:, -1] - (l + d["u2"])).max() < 1e-9
    assert np.abs(run.y[:, -1] - d["v1"]).max() < 1e-12
    if beam == "exact":
        points = run.x.shape[1] - 1
        for k, column in ((1, "v_quarter"), (2, "v_mid"), (3, "v_three_quarter")):
            assert np.abs(run.y[:, k * points // 4] - d[column]).max() < 1e-9, column
        nodal = [np.stack([d[f"{c}_{k}"] for k in (1, 2)], axis=1) for c in ("v", "theta")]
        shortened, _ = an.quadratic_curves(l, *nodal)
        assert np.abs(shortened[:, -1] - (l + d["u2"])).max() > 1e-3
    picture = an.Picture(run)
    picture.frame(run.frames - 1)
    hinge = np.ravel(picture.hinge.get_data())
    assert np.allclose(hinge, [l + d["u2"][-1], d["v1"][-1]], rtol=0, atol=1e-9)


@pytest.fixture(scope="module")
def damped(beam_body):
    """The picture of a damped run, its last frame (t = 1 s, phi = pi) drawn."""
    picture = an.Picture(cli_run(beam_body, "damping_ratio=0.02"))
    return picture, picture.frame(picture.run.frames - 1)


def test_the_title_names_the_runs_settings_and_the_frames_time(damped):
    heading = damped[0].heading()
    for said in ("paper.toml", "quadratic beam", "2 elements", "t_rot = 0.85 s",
                 "phi_end = 3.142 rad", "damping_ratio = 0.02"):
        assert said in heading, heading
    assert re.search(r"t = +1\.00 s", heading), heading
    assert "M2 =" not in heading  # a setting left at its default is not named


def test_the_legend_names_the_centre_of_mass_and_its_path(damped):
    picture = damped[0]
    names = [t.get_text() for t in picture.legend.get_texts()]
    assert "centre of mass C" in names and "path of C" in names, names
    handles = dict(zip(names, picture.legend.legend_handles))
    assert handles["centre of mass C"].get_marker() == picture.mass.get_marker() == "o"
    assert handles["path of C"].get_color() == picture.trace.get_color()


def test_at_phi_pi_the_body_lies_along_the_beam_and_both_show(damped):
    """At phi = pi the body lies back along the beam's end: halfway along the body the beam's
    point is the beam's blue, and on the body's other side of its axis, 3 px off, the pixel is
    the body's pale red."""
    picture, pixels = damped
    run = picture.run
    assert abs(run.data["phi_applied"][-1] - np.pi) < 1e-12
    tip = np.array([run.x[-1, -1], run.y[-1, -1]])
    c = np.array([run.cx[-1], run.cy[-1]])
    to_pixels = picture.ax.transData.transform
    middle, toward_c = to_pixels(0.5 * (tip + c)), to_pixels(c) - to_pixels(tip)
    across = np.array([-toward_c[1], toward_c[0]]) / np.hypot(*toward_c)
    at = round((1 - 0.25 / 2.5) * (run.x.shape[1] - 1))  # the beam at s = l - r/2
    on_beam = to_pixels([run.x[-1, at], run.y[-1, at]])
    side = -1.0 if np.dot(on_beam - middle, across) > 0 else 1.0

    def colour(at):
        column, row = int(round(at[0])), pixels.shape[0] - 1 - int(round(at[1]))
        return pixels[row, column].astype(int)

    beam, body = colour(on_beam), colour(middle + 3 * side * across)
    assert beam[2] > 150 and beam[0] < 90, beam  # tab:blue (31, 119, 180)
    assert body[0] > 200 and body[1] < 220 and body[0] - body[2] > 20, body  # pale red


def test_progress_is_shown_when_asked_and_only_then(beam_body, tmp_path, capsys):
    args = ["animate", str(PAPER_SCENE), "--elements", "2", "--set", "t_end=0.5", "--fps", "10",
            "--cli", str(beam_body), "-o", str(tmp_path / "turn.gif")]
    assert main(args + ["--progress"]) == 0
    err = capsys.readouterr().err
    assert "animate: 6/6 frames drawn" in err and "animate: 1/6 frames drawn" in err, err
    assert main(args) == 0  # stderr is no terminal here: no progress
    err = capsys.readouterr().err
    assert "frames drawn" not in err and "6 frames of 2 element(s)" in err, err
    assert main(args + ["--quiet"]) == 0
    assert capsys.readouterr().err == ""
