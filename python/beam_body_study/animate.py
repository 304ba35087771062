"""The beam and the body through a run, as a GIF: `beam-body-study animate SCENE.toml -o turn.gif`.

The CLI runs the scene with `columns = shape` (every node's deflection v_k and slope theta_k at
x_k = k*l/n); between the nodes the beam is the elements' own cubic Hermite interpolation, and
its points move axially by u(x) = -1/2 * integral_0^x v'^2 (inextensibility, to the model's
second order). The body is drawn from the hinge at the tip to its centre of mass C, at the angle
theta = theta1 + phi of the model (model-notes.md): C = (l + u(l) + r cos theta, v1 + r sin theta).
Drawn in the frame of the beam's clamped root (x along the undeformed beam), to scale.
"""

from __future__ import annotations

import csv
import io
import math
import subprocess
from pathlib import Path

from .errors import StudyError


def cli_message(stderr: str, returncode: int) -> str:
    """What a failed CLI run says, without the CLI's own `error: ` prefix: its last `error:`
    line, else its last line."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("error:")]
    message = (errors or lines or [f"exit status {returncode}"])[-1]
    return message.removeprefix("error:").strip()


def run_shape(cli: str, scene: str, sets: list, elements: int | None, fps: float) -> dict:
    """The CLI's run of `scene` with the nodes' columns, one row a frame: {column: values}."""
    args = [cli, "simulate", scene, "--columns", "shape"]
    if elements is not None:
        args += ["--elements", str(elements)]
    for s in sets:
        args += ["--set", s]
    # The frame's step last, so that it is the one that counts.
    args += ["--set", f"dt_out={1.0 / fps!r}"]
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0:
        run = " ".join([scene] + ([f"--elements {elements}"] if elements is not None else [])
                       + [f"--set {s}" for s in sets])
        raise StudyError(f"the run of {run} failed: "
                         f"{cli_message(done.stderr, done.returncode)}")
    reader = csv.reader(io.StringIO(done.stdout))
    header = [h.split(" [")[0] for h in next(reader)]
    rows = [[float(x) for x in r] for r in reader]
    return {h: [r[k] for r in rows] for k, h in enumerate(header)}


def scene_value(cli: str, scene: str, sets: list, key: str) -> float:
    """A setting's value in the scene (after the --set options), read from the CLI."""
    for s in reversed(sets):
        name, _, value = s.partition("=")
        if name.strip() == key:
            return float(value)
    text = Path(scene).read_text()
    for line in text.splitlines():
        name, _, value = line.split("#")[0].partition("=")
        if name.strip() == key:
            return float(value)
    help_text = subprocess.run([cli, "simulate", "--help"], capture_output=True,
                               text=True).stdout
    for line in help_text.splitlines():
        words = line.split()
        if words and words[0] == key:
            return float(line.split("=")[1].split()[0])
    raise StudyError(f"no value of `{key}` in {scene} or the CLI's defaults")


def hermite(l_el: float, v0: float, t0: float, v1: float, t1: float, s: float) -> tuple:
    """The cubic of an element of length l_el with end values (v, slope) at local s in [0, 1]:
    deflection and slope."""
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    d00, d10 = (6 * s**2 - 6 * s) / l_el, 3 * s**2 - 4 * s + 1
    d01, d11 = (-6 * s**2 + 6 * s) / l_el, 3 * s**2 - 2 * s
    v = h00 * v0 + h10 * l_el * t0 + h01 * v1 + h11 * l_el * t1
    dv = d00 * v0 + d10 * t0 + d01 * v1 + d11 * t1
    return v, dv


def beam_curve(l: float, nodes: list, per_element: int = 12) -> tuple:
    """Points (x + u, v) of the beam from the nodes' [(v_k, theta_k)], the root clamped."""
    n = len(nodes)
    l_el = l / n
    ends = [(0.0, 0.0)] + nodes
    xs, vs, slopes = [], [], []
    for k in range(n):
        (va, ta), (vb, tb) = ends[k], ends[k + 1]
        for j in range(per_element + (1 if k == n - 1 else 0)):
            s = j / per_element
            v, dv = hermite(l_el, va, ta, vb, tb, s)
            xs.append((k + s) * l_el)
            vs.append(v)
            slopes.append(dv)
    # u(x) = -1/2 * integral of v'^2, by the trapezoidal rule on the points.
    u = [0.0]
    for i in range(1, len(xs)):
        u.append(u[-1] - 0.25 * (slopes[i] ** 2 + slopes[i - 1] ** 2) * (xs[i] - xs[i - 1]))
    return [x + du for x, du in zip(xs, u)], vs


def animate(cli: str, scene: str, out: str | Path, sets: list, elements: int | None = None,
            fps: float = 20.0, dpi: int = 72) -> dict:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    out = Path(out)
    if out.suffix.lower() != ".gif":
        raise StudyError(f"-o {out}: the animation is written as GIF (.gif)")
    if not (0 < fps <= 100):
        raise StudyError(f"--fps {fps}: must be in (0, 100]")
    data = run_shape(cli, scene, sets, elements, fps)
    l, r = scene_value(cli, scene, sets, "l"), scene_value(cli, scene, sets, "r")
    n = sum(1 for k in data if k.startswith("v_") and k[2:].isdigit())
    frames = len(data["t"])
    reach = l + r
    fig, ax = plt.subplots(figsize=(6, 4.2))
    ax.set_xlim(-0.1 * reach, 1.05 * reach)
    vmax = max(max(abs(v) for v in data["v1"]) + r, 0.3 * reach)
    ax.set_ylim(-vmax, vmax)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("v [m]")
    ax.plot([0, 0], [-0.15 * vmax, 0.15 * vmax], color="k", lw=4)  # the clamp
    (beam,) = ax.plot([], [], color="tab:blue", lw=2.5, zorder=3)
    # The body under the beam: turned by pi it lies back along it.
    (body,) = ax.plot([], [], color="tab:red", lw=4, alpha=0.7, solid_capstyle="round",
                      zorder=2)
    (mass,) = ax.plot([], [], "o", color="tab:red", ms=9, zorder=4)
    (trace,) = ax.plot([], [], color="tab:red", lw=0.6, alpha=0.5)
    label = ax.text(0.02, 0.96, "", transform=ax.transAxes, va="top", fontsize=9)
    ax.set_title(f"{Path(scene).name}: {n} element{'s' if n > 1 else ''}", fontsize=10)
    path_x, path_y = [], []

    def draw(i):
        nodes = [(data[f"v_{k}"][i], data[f"theta_{k}"][i]) for k in range(1, n + 1)]
        xs, vs = beam_curve(l, nodes)
        beam.set_data(xs, vs)
        theta = data["theta1"][i] + data["phi_applied"][i]
        tip = (xs[-1], vs[-1])
        c = (tip[0] + r * math.cos(theta), tip[1] + r * math.sin(theta))
        body.set_data([tip[0], c[0]], [tip[1], c[1]])
        mass.set_data([c[0]], [c[1]])
        del path_x[i:], path_y[i:]  # a frame drawn again (the first) is not traced twice
        path_x.append(c[0])
        path_y.append(c[1])
        trace.set_data(path_x, path_y)
        label.set_text(f"t = {data['t'][i]:5.2f} s   phi = {data['phi_applied'][i]:5.2f} rad"
                       f"   v1 = {data['v1'][i]:+.3f} m")
        return beam, body, mass, trace, label

    anim = FuncAnimation(fig, draw, frames=frames, blit=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    anim.save(out, writer=PillowWriter(fps=fps), dpi=dpi)
    plt.close(fig)
    return {"frames": frames, "elements": n}
