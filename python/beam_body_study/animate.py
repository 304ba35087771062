"""The beam and the body through a run, as a GIF: `beam-body-study animate SCENE.toml -o turn.gif`.

The CLI runs the scene with `columns = shape`: at every node k = 1..n, at x (or arc length s)
= k*l/n, a deflection `v_k` and an angle `theta_k`. What they are, and so how the beam is drawn
between the nodes, is the beam theory's:

- quadratic (the paper's): v_k and theta_k are the nodal coordinates. Between the nodes the
  beam is the elements' cubic Hermite v(x), and its points move axially by
  u(x) = -1/2 * integral_0^x v'^2 (inextensibility to the model's second order): the point of x
  is drawn at (x + u(x), v(x)).
- exact (the elastica): v_k is the centreline's y at arc length s_k and theta_k the section
  angle alpha_k there (src/model/exact.rs, docs/model.md). The field is alpha = w' with w the
  same cubic Hermite elements, so in an element of length h, at local tau in [0, 1],
  alpha = alpha_a (1 - 4 tau + 3 tau^2) + alpha_b (3 tau^2 - 2 tau) + c * 6 tau (1 - tau), where
  c = (w_b - w_a)/h is the element's mean angle. The columns do not give c: it is the root,
  nearest the mean of alpha_a and alpha_b, of h * integral sin(alpha) = y_b - y_a (by the
  model's own 6-point Gauss rule, so the nodes' y are the CLI's). The centreline is then
  x(s) = integral_0^s cos(alpha), y(s) = integral_0^s sin(alpha), and its end is the tip
  (l + u2, v1); no shortening formula is involved.

Both integrals are taken by Gauss-Legendre on each drawn piece (exact for the quadratic beam).
The body is drawn from the hinge at the tip to its centre of mass C, at the model's angle
theta = theta1 + phi (docs/model.md): C = tip + r (cos theta, sin theta). It is a wide pale bar
drawn under the beam, and the beam a narrow dark line on top: at phi = pi, where the body lies
back along the beam's last r metres, both stay visible. C is a red dot, its path a thin red
line, the hinge a small ring; the legend names them. Drawn in the frame of the beam's clamped
root (x along the undeformed beam), to scale. The title names the scene, the settings that
define the run (the beam theory, n_elements, t_rot, phi_end, and every other setting of the
model that differs from the CLI's default, damping among them) and the frame's time.

Speed: the figure is laid out and drawn once. Each frame then restores that background, draws
only what moves (the beam, the body, C, its path and the time) with Agg, and hands the pixels
to Pillow, mapped to one palette that every frame shares (built from three frames). A frame
costs a few milliseconds, where matplotlib's animation writer drew the whole figure twice.
"""

from __future__ import annotations

import csv
import io
import re
import subprocess
import sys
import textwrap
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import StudyError


def _gauss(points: int) -> tuple:
    """The Gauss-Legendre rule on [0, 1]: nodes and weights."""
    x, w = np.polynomial.legendre.leggauss(points)
    return (x + 1) / 2, w / 2


#: 4 points for each drawn piece (exact for the quadratic beam's quartic v'^2), and the exact
#: model's own 6 for a whole element.
_PIECE_T, _PIECE_W = _gauss(4)
_ELEMENT_T, _ELEMENT_W = _gauss(6)

#: Settings of the model that the title names when they differ from the CLI's defaults.
TITLE_SETTINGS = ("l", "EI", "m", "M2", "J_C", "r", "g", "damping_ratio", "damping_alpha",
                  "damping_beta", "beam_gravity", "phi0", "v1_0", "theta1_0", "dv1_0",
                  "dtheta1_0", "formulation", "phi_source")


def cli_message(stderr: str, returncode: int) -> str:
    """What a failed CLI run says, without the CLI's own `error: ` prefix: its last `error:`
    line, else its last line."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("error:")]
    message = (errors or lines or [f"exit status {returncode}"])[-1]
    return message.removeprefix("error:").strip()


def run_shape(cli: str, scene: str, sets: list, fps: float) -> dict:
    """The CLI's run of `scene` with the nodes' columns, one row a frame: {column: array}."""
    args = [cli, "simulate", scene, "--columns", "shape"]
    for s in sets:
        args += ["--set", s]
    # The frame's step last, so that it is the one that counts.
    args += ["--set", f"dt_out={1.0 / fps!r}"]
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0:
        run = " ".join([scene] + [f"--set {s}" for s in sets])
        raise StudyError(f"the run of {run} failed: "
                         f"{cli_message(done.stderr, done.returncode)}")
    reader = csv.reader(io.StringIO(done.stdout))
    header = [h.split(" [")[0] for h in next(reader)]
    rows = np.array([[float(x) for x in r] for r in reader if r], dtype=float)
    return {h: rows[:, k] for k, h in enumerate(header)}


def cli_settings(cli: str) -> dict:
    """The CLI's settings, from `beam-body simulate --help`: {name: (default as text, unit)}."""
    help_text = subprocess.run([cli, "simulate", "--help"], capture_output=True,
                               text=True).stdout
    found = {}
    for line in help_text.splitlines():
        m = re.match(r"  (\w+)(?: \[([^\]]*)\])? = (\S+)", line)
        if m:
            found[m[1]] = (m[3], m[2] or "")
    return found


def run_settings(defaults: dict, scene: str, sets: list) -> dict:
    """Every setting of the run as text: the CLI's default, then the scene file's, then the
    `sets` (NAME=VALUE) in order, as the CLI applies them."""
    settings = {name: text for name, (text, _) in defaults.items()}
    with open(scene, "rb") as f:
        for name, value in tomllib.load(f).items():
            settings[name] = str(value).lower() if isinstance(value, bool) else str(value)
    for s in sets:
        name, _, value = s.partition("=")
        settings[name.strip()] = value.strip().strip("\"'")
    return settings


def _number(text: str):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def shown(text: str) -> str:
    """A setting's value for the title: a number to 4 digits, anything else as it is."""
    x = _number(text)
    return text if x is None else f"{x:.4g}"


def title_head(scene: str, settings: dict, defaults: dict, n: int) -> str:
    """The title's settings: scene, beam theory, elements, the turn, then what else differs from
    the defaults, wrapped to the figure's width."""
    def item(name):
        unit = defaults.get(name, ("", ""))[1]
        return f"{name} = {shown(settings.get(name, '?'))}" + (f" {unit}" if unit else "")

    others = []
    for name in TITLE_SETTINGS:
        value, default = settings.get(name), defaults.get(name, (None, ""))[0]
        if value is None or value == default:
            continue
        if _number(value) is not None and _number(value) == _number(default):
            continue
        others.append(item(name))
    head = (f"{Path(scene).name}: {settings.get('beam', 'quadratic')} beam, {n} element"
            f"{'s' if n > 1 else ''}, {item('t_rot')}, {item('phi_end')}")
    return "\n".join([head] + textwrap.wrap(", ".join(others), 80))


def frame_line(t: float, phi: float, v1: float) -> str:
    return f"t = {t:5.2f} s   phi = {phi:5.2f} rad   v1 = {v1:+.3f} m"


# ------------------------------------------------------------------------------------------
# The centreline, every frame at once: arrays (frames, n) of nodal values in, (frames,
# n * per_element + 1) points out, the root first.
# ------------------------------------------------------------------------------------------

def hermite_basis(tau: np.ndarray) -> tuple:
    """The cubic Hermite functions of an element on local tau in [0, 1], for the end values
    (v_a, h*theta_a, v_b, h*theta_b), and their derivatives in tau: two arrays (4, len)."""
    t = np.asarray(tau, dtype=float)
    values = np.stack([2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t,
                       -2 * t**3 + 3 * t**2, t**3 - t**2])
    slopes = np.stack([6 * t**2 - 6 * t, 3 * t**2 - 4 * t + 1,
                       -6 * t**2 + 6 * t, 3 * t**2 - 2 * t])
    return values, slopes


def angle_basis(tau: np.ndarray) -> np.ndarray:
    """The exact beam's section angle in an element, for (alpha_a, alpha_b, c): (3, len)."""
    t = np.asarray(tau, dtype=float)
    return np.stack([3 * t**2 - 4 * t + 1, 3 * t**2 - 2 * t, 6 * t * (1 - t)])


def _ends(nodal: np.ndarray) -> tuple:
    """Each element's start and end values of a nodal array (frames, n); the root's are 0."""
    start = np.concatenate([np.zeros((nodal.shape[0], 1)), nodal[:, :-1]], axis=1)
    return start, nodal


def _piece_points(per_element: int) -> np.ndarray:
    """Local tau of each drawn piece's quadrature points: (per_element, 4)."""
    return (np.arange(per_element)[:, None] + _PIECE_T[None, :]) / per_element


def _running(step: float, f: np.ndarray) -> np.ndarray:
    """The running integral along the beam of f given at each piece's quadrature points
    (frames, n, per_element, 4): its values at the pieces' ends, the root's 0 first."""
    pieces = step * (f @ _PIECE_W)
    flat = pieces.reshape(pieces.shape[0], -1)
    return np.concatenate([np.zeros((flat.shape[0], 1)), np.cumsum(flat, axis=1)], axis=1)


def quadratic_curves(l: float, v: np.ndarray, theta: np.ndarray, per_element: int = 12) -> tuple:
    """The quadratic beam's points (x + u(x), v(x)) from its nodal (v_k, theta_k)."""
    v, theta = np.atleast_2d(v), np.atleast_2d(theta)
    n, m = v.shape[1], per_element
    h = l / n
    (va, vb), (ta, tb) = _ends(v), _ends(theta)
    coef = np.stack([va, h * ta, vb, h * tb], axis=-1)  # (frames, n, 4)
    values, _ = hermite_basis(np.arange(m) / m)
    ys = (coef @ values).reshape(v.shape[0], -1)
    ys = np.concatenate([ys, v[:, -1:]], axis=1)
    tau = _piece_points(m)
    _, slopes = hermite_basis(tau.ravel())
    slope = (coef @ slopes).reshape(*v.shape, m, tau.shape[1]) / h
    u = _running(h / m, -0.5 * slope**2)
    return np.arange(n * m + 1) * (h / m) + u, ys


def element_mean_angles(l: float, y: np.ndarray, alpha: np.ndarray,
                        iterations: int = 60) -> np.ndarray:
    """The exact beam's c of every element (its mean section angle, (w_b - w_a)/h): the root of
    h * sum_j b_j sin(alpha(tau_j)) = y_b - y_a nearest (alpha_a + alpha_b)/2, by
    Levenberg-Marquardt steps on the residual's square (which also settle where rounding
    leaves no root, at the closest c: an element that stands across the beam)."""
    y, alpha = np.atleast_2d(y), np.atleast_2d(alpha)
    h = l / y.shape[1]
    (ya, yb), (aa, ab) = _ends(y), _ends(alpha)
    basis = angle_basis(_ELEMENT_T)  # (3, 6)
    fixed = aa[..., None] * basis[0] + ab[..., None] * basis[1]
    c = 0.5 * (aa + ab)
    for _ in range(iterations):
        angle = fixed + c[..., None] * basis[2]
        f = h * (np.sin(angle) @ _ELEMENT_W) - (yb - ya)
        df = h * ((np.cos(angle) * basis[2]) @ _ELEMENT_W)
        step = np.clip(-f * df / (df**2 + 1e-30 * h**2), -0.5, 0.5)
        c = c + step
        if np.all(np.abs(step) < 1e-15 * (1 + np.abs(c))):
            break
    return c


def exact_curves(l: float, y: np.ndarray, alpha: np.ndarray, per_element: int = 12) -> tuple:
    """The exact beam's centreline (integral cos alpha, integral sin alpha) from its nodal
    (y_k, alpha_k)."""
    y, alpha = np.atleast_2d(y), np.atleast_2d(alpha)
    n, m = y.shape[1], per_element
    h = l / n
    c = element_mean_angles(l, y, alpha)
    aa, ab = _ends(alpha)
    basis = angle_basis(_piece_points(m).ravel())
    angle = (np.stack([aa, ab, c], axis=-1) @ basis).reshape(*y.shape, m, len(_PIECE_T))
    return _running(h / m, np.cos(angle)), _running(h / m, np.sin(angle))


# ------------------------------------------------------------------------------------------
# The run and its picture
# ------------------------------------------------------------------------------------------

@dataclass
class Run:
    """A run as drawn: its columns, its settings and every frame's geometry."""
    scene: str
    data: dict        # the CLI's columns, {name: array over the frames}
    settings: dict    # every setting as text (run_settings)
    defaults: dict    # the CLI's settings (cli_settings)
    n: int            # elements
    x: np.ndarray     # the centreline, (frames, points), the root first and the tip last
    y: np.ndarray
    cx: np.ndarray    # the body's centre of mass C, (frames,)
    cy: np.ndarray

    @property
    def frames(self) -> int:
        return len(self.data["t"])

    def head(self) -> str:
        return title_head(self.scene, self.settings, self.defaults, self.n)

    def clock(self, i: int) -> str:
        d = self.data
        return frame_line(d["t"][i], d["phi_applied"][i], d["v1"][i])


def load(cli: str, scene: str, sets: list, fps: float) -> Run:
    """The CLI's run of the scene at `fps` frames a second, and its geometry."""
    data = run_shape(cli, scene, sets, fps)
    defaults = cli_settings(cli)
    settings = run_settings(defaults, scene, sets)
    l, r = float(settings["l"]), float(settings["r"])
    n = sum(1 for k in data if k.startswith("v_") and k[2:].isdigit())
    v = np.stack([data[f"v_{k}"] for k in range(1, n + 1)], axis=1)
    theta = np.stack([data[f"theta_{k}"] for k in range(1, n + 1)], axis=1)
    curves = exact_curves if settings.get("beam") == "exact" else quadratic_curves
    x, y = curves(l, v, theta)
    angle = data["theta1"] + data["phi_applied"]
    cx, cy = x[:, -1] + r * np.cos(angle), y[:, -1] + r * np.sin(angle)
    return Run(scene, data, settings, defaults, n, x, y, cx, cy)


class Picture:
    """The figure of a run, laid out and drawn once; `frame(i)` draws what moves at frame i
    over that background and returns the pixels (height, width, 3)."""

    def __init__(self, run: Run, dpi: int = 72):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.run = run
        l, r = float(run.settings["l"]), float(run.settings["r"])
        reach = l + r
        margin = 0.05 * reach
        xs = np.concatenate([run.x.ravel(), run.cx])
        ys = np.concatenate([run.y.ravel(), run.cy])
        vmax = max(np.abs(ys).max() + margin, 0.3 * reach)
        fig = Figure(figsize=(6, 4.4), dpi=dpi, layout="constrained")
        self.canvas = FigureCanvasAgg(fig)
        ax = fig.add_subplot()
        ax.set_xlim(min(-0.1 * reach, xs.min() - margin), max(1.05 * reach, xs.max() + margin))
        ax.set_ylim(-vmax, vmax)
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("v [m]")
        ax.plot([0, 0], [-0.15 * vmax, 0.15 * vmax], color="k", lw=4)  # the clamp
        # Under the beam, wide and pale: at phi = pi it lies back along the beam's end.
        (self.body,) = ax.plot([], [], color="tab:red", lw=9, alpha=0.3,
                               solid_capstyle="round", zorder=2, label="body, hinge to C")
        (self.beam,) = ax.plot([], [], color="tab:blue", lw=2.2, zorder=3, label="beam")
        (self.trace,) = ax.plot([], [], color="tab:red", lw=0.7, alpha=0.6, zorder=2.5,
                                label="path of C")
        (self.hinge,) = ax.plot([], [], "o", mfc="white", mec="k", ms=4, zorder=4,
                                label="hinge")
        (self.mass,) = ax.plot([], [], "o", color="tab:red", ms=8, zorder=5,
                               label="centre of mass C")
        self.legend = ax.legend(handles=[self.beam, self.body, self.hinge, self.mass,
                                         self.trace],
                                loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3,
                                fontsize=8, frameon=False)
        # The title: the settings, drawn once, over the frame's time, drawn every frame.
        self.title = ax.set_title(run.head(), fontsize=9, pad=16)
        self.clock = ax.text(0.5, 1.015, run.clock(0), transform=ax.transAxes, ha="center",
                             va="bottom", fontsize=9)
        self.moving = [self.body, self.trace, self.beam, self.hinge, self.mass, self.clock]
        for artist in self.moving:
            artist.set_animated(True)
        self.fig, self.ax = fig, ax
        self.canvas.draw()
        fig.set_layout_engine("none")  # the layout stays that of the first draw
        self.background = self.canvas.copy_from_bbox(fig.bbox)

    def heading(self) -> str:
        """The title as shown: the settings, then the time of the frame last drawn."""
        return self.title.get_text() + "\n" + self.clock.get_text()

    def frame(self, i: int) -> np.ndarray:
        run = self.run
        tip = (run.x[i, -1], run.y[i, -1])
        c = (run.cx[i], run.cy[i])
        self.beam.set_data(run.x[i], run.y[i])
        self.body.set_data([tip[0], c[0]], [tip[1], c[1]])
        self.hinge.set_data([tip[0]], [tip[1]])
        self.mass.set_data([c[0]], [c[1]])
        self.trace.set_data(run.cx[:i + 1], run.cy[:i + 1])
        self.clock.set_text(run.clock(i))
        self.canvas.restore_region(self.background)
        for artist in self.moving:
            self.fig.draw_artist(artist)
        return np.asarray(self.canvas.buffer_rgba())[..., :3].copy()


class Progress:
    """Frames drawn of the total, on stderr: one line rewritten in place on a terminal, else a
    line at every tenth of the frames."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stderr
        self.terminal = self.stream.isatty()
        self.last = 0.0
        self.shown = -1
        self.open = False  # a terminal's line rewritten in place, not yet ended

    def say(self, text: str) -> None:
        end = "\x1b[K" if self.terminal else "\n"
        print(("\r" + text) if self.terminal else text, end=end, file=self.stream, flush=True)
        self.open = self.terminal

    def frame(self, done: int, total: int) -> None:
        now = time.perf_counter()
        tenth = 10 * done // total
        if self.terminal and (now - self.last >= 0.1 or done == total):
            self.last = now
            self.say(f"animate: {done}/{total} frames drawn")
        elif not self.terminal and tenth > self.shown:
            self.shown = tenth
            self.say(f"animate: {done}/{total} frames drawn")

    def finish(self) -> None:
        """Ends the line rewritten in place, so that what follows (an error too) has its own."""
        if self.open:
            print(file=self.stream, flush=True)
            self.open = False


def write_gif(picture: Picture, out: Path, fps: float, progress: Progress | None = None) -> None:
    """Every frame of the picture as one GIF, all frames on one palette."""
    from PIL import Image

    total = picture.run.frames
    sample = np.concatenate([picture.frame(k) for k in sorted({0, total // 2, total - 1})])
    palette = Image.fromarray(sample).quantize(colors=128, method=Image.Quantize.MEDIANCUT)
    images = []
    for i in range(total):
        rgb = Image.fromarray(picture.frame(i))
        images.append(rgb.quantize(palette=palette, dither=Image.Dither.NONE))
        if progress:
            progress.frame(i + 1, total)
    out.parent.mkdir(parents=True, exist_ok=True)
    images[0].save(out, save_all=True, append_images=images[1:],
                   duration=int(1000 / fps), loop=0)


def animate(cli: str, scene: str, out: str | Path, sets: list, elements: int | None = None,
            fps: float = 20.0, dpi: int = 72, beam: str | None = None,
            progress: Progress | None = None) -> dict:
    out = Path(out)
    if out.suffix.lower() != ".gif":
        raise StudyError(f"-o {out}: the animation is written as GIF (.gif)")
    if not (0 < fps <= 100):
        raise StudyError(f"--fps {fps}: must be in (0, 100]")
    # --elements and --beam last: they win over a --set of the same setting.
    sets = list(sets) + ([f"n_elements={elements}"] if elements is not None else []) \
        + ([f"beam={beam}"] if beam is not None else [])
    try:
        if progress:
            progress.say(f"animate: running {scene}")
        run = load(cli, scene, sets, fps)
        write_gif(Picture(run, dpi), out, fps, progress)
    finally:
        if progress:
            progress.finish()
    return {"frames": run.frames, "elements": run.n}
