"""The README's figures: the paper's Fig. 3 recomputed, and a drawing of the model.

    python bench/python/figures.py --csv target/figures/figure3.csv [--out-dir docs]

`cargo xtask figures` runs the simulations, measures what the figures show (target/figures/
figure3.txt) and calls this script, which only draws:

* <out-dir>/figure3.png: Russkikh & Shklyarchuk (2020), Fig. 3a-c: v1(tau), theta1(tau), u2(tau),
  tau = t/T, T = t_rot = 0.85 s, in the paper's line styles: solid 1 = eq. (15) (`reduced`),
  dash-dot 2 = eq. (20) with the constraint (21) differentiated twice (`dae`), dotted = the
  linearized eq. (16) (`linear`, panels a and b only, as in the paper). In panel c, line 1 is u2
  from formula (21) applied to the solution of (15), line 2 the integrated u2 of (20).
* <out-dir>/model.png: the beam-body system with the paper's parameter names (§2, Fig. 2).

The CSV's columns: tau,t,phi,v1_reduced,theta1_reduced,u2_reduced,v1_dae,theta1_dae,u2_dae,
drift_dae,v1_linear,theta1_linear.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Arc, Circle, FancyArrowPatch, FancyBboxPatch, Wedge  # noqa: E402
from matplotlib.transforms import Affine2D  # noqa: E402

# Colours: 1 and 2 differ in colour as well as dash, so that line 2 stays visible where it lies on
# top of line 1 (everywhere, to plot accuracy).
C1 = "#1f4e99"  # line 1, eq. (15)
C2 = "#e8731a"  # line 2, eq. (20)+(21)
CL = "#333333"  # dotted, eq. (16)
TURN = "#e9e9e9"  # background of the turn 0 <= tau <= 1

WIDTH_PX = 1400
DPI = 100


# --------------------------------------------------------------------------------------------------
# Fig. 3


def read_csv(path: Path) -> dict[str, np.ndarray]:
    data = np.genfromtxt(path, delimiter=",", names=True)
    return {name: data[name] for name in data.dtype.names}


def rel_diff(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| / max |a|, as bench/src/figures.rs measures it."""
    return float(np.max(np.abs(a - b)) / np.max(np.abs(a)))


def figure3(d: dict[str, np.ndarray], out: Path) -> None:
    tau = d["tau"]
    plt.rcParams.update({"font.size": 15, "axes.titlesize": 16, "legend.fontsize": 14})
    fig, axes = plt.subplots(3, 1, figsize=(WIDTH_PX / DPI, 12.5), sharex=True)
    panels = [
        ("v1", r"$v_1$ [m]", "a", "tip deflection"),
        ("theta1", r"$\vartheta_1$ [rad]", "b", "tip section rotation"),
        ("u2", r"$u_2$ [m]", "c", "axial displacement of the hinge"),
    ]
    for ax, (q, ylabel, letter, what) in zip(axes, panels):
        ax.axvspan(0.0, 1.0, color=TURN, zorder=0)
        ax.axhline(0.0, color="0.6", lw=0.8, zorder=1)
        red, dae = d[f"{q}_reduced"], d[f"{q}_dae"]
        if q == "u2":
            lab1 = r"1: eq. (15), $u_2 = u_1(v_1, \vartheta_1)$ by (21)"
            lab2 = r"2: eq. (20) + (21) differentiated twice, $u_2$ integrated"
        else:
            lab1 = "1: eq. (15), reduced"
            lab2 = "2: eq. (20) + (21) differentiated twice"
        ax.plot(tau, red, color=C1, lw=3.2, ls="-", label=lab1, zorder=3)
        ax.plot(tau, dae, color=C2, lw=1.6, ls="-.", label=lab2, zorder=4)
        note = f"max |1 − 2| = {rel_diff(red, dae):.0e} of max |1|"
        if q != "u2":
            lin = d[f"{q}_linear"]
            ax.plot(tau, lin, color=CL, lw=1.6, ls=":", label="eq. (16), linearized", zorder=2)
            note += f";  max |1 − (16)| = {rel_diff(red, lin):.2f} of max |1|"
        ax.set_ylabel(ylabel)
        ax.set_title(f"({letter}) {what}", loc="left")
        ax.set_title(note, loc="right", fontsize=13, color="0.3")
        ax.grid(True, color="0.88", lw=0.7)
        ax.set_xlim(0.0, tau[-1])
        ax.legend(loc="upper right", ncol=3 if q != "u2" else 2, framealpha=0.95)
        # Room above the curves for the legend.
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi + 0.30 * (hi - lo))
        ax.text(0.5, 0.97, "turn\n" r"$\varphi: 0 \to \pi$", transform=ax.get_xaxis_transform(),
                ha="center", va="top", fontsize=12, color="0.35")
    axes[-1].set_xlabel(r"$\tau = t/T$,  $T = t_{rot} = 0.85$ s")
    axes[-1].set_xticks(np.arange(0, tau[-1] + 0.5, 1.0))
    fig.suptitle("Russkikh & Shklyarchuk (2020), Fig. 3 recomputed: the paper's scene, rtol 1e-8",
                 fontsize=16)
    fig.tight_layout()
    fig.savefig(out, dpi=DPI)
    plt.close(fig)


# --------------------------------------------------------------------------------------------------
# The model


def draw_model(out: Path) -> None:
    """The beam-body system (paper §2) with an illustrative, moderate deflection, drawn to the
    scale of the paper's example (l = 2.5 m, r = 0.5 m)."""
    l, r = 2.5, 0.5
    v1, th1 = 0.45, 0.30  # [m], [rad]: the size of the paper's vibrations (|v1| <= 0.59 m)
    phi = math.radians(55.0)  # the body's angle relative to the tip section
    theta = th1 + phi

    # Deflected shape v(x) = v1 (3 xi^2 - 2 xi^3) + th1 l (-xi^2 + xi^3) (paper eq. 5), and the
    # axial displacement from inextensibility u(x) = -1/2 int_0^x v'^2 (eq. 6): a material point x
    # is drawn at (x + u(x), v(x)).
    xi = np.linspace(0.0, 1.0, 401)
    x = xi * l
    v = v1 * (3 * xi**2 - 2 * xi**3) + th1 * l * (-xi**2 + xi**3)
    dv = v1 * (6 * xi - 6 * xi**2) / l + th1 * (-2 * xi + 3 * xi**2)
    u = -0.5 * np.concatenate([[0.0], np.cumsum(0.5 * (dv[1:] ** 2 + dv[:-1] ** 2) * np.diff(x))])
    px, py = x + u, v
    tip = np.array([px[-1], py[-1]])
    e_tan = np.array([math.cos(th1), math.sin(th1)])
    e_body = np.array([math.cos(theta), math.sin(theta)])
    cpt = tip + r * e_body

    plt.rcParams.update({"font.size": 17, "mathtext.fontset": "dejavusans"})
    fig, ax = plt.subplots(figsize=(WIDTH_PX / DPI, 7.2))
    ax.set_aspect("equal")
    ax.axis("off")

    def arrow(p, q, style="-|>", lw=1.4, color="k", ms=16, **kw):
        ax.add_patch(FancyArrowPatch(p, q, arrowstyle=style, mutation_scale=ms, lw=lw, color=color,
                                     shrinkA=0, shrinkB=0, **kw))

    def dim(p, q, label, offset, color="0.15", **text):
        """A dimension line with arrows at both ends and its label at `offset` from the middle."""
        arrow(p, q, style="<|-|>", lw=1.1, color=color, ms=12)
        m = (np.asarray(p) + np.asarray(q)) / 2 + np.asarray(offset)
        ax.text(*m, label, ha="center", va="center", color=color, **text)

    # Clamp at x = 0: a wall with hatching.
    wall_h = 0.55
    ax.plot([0, 0], [-wall_h, wall_h], color="k", lw=2.5)
    for yy in np.linspace(-wall_h, wall_h - 0.1, 10):
        ax.plot([0, -0.1], [yy, yy + 0.1], color="k", lw=1.1)

    # Axes x (the undeformed beam) and y.
    ax.plot([0, l], [0, 0], color="0.55", lw=1.3, ls=(0, (6, 4)))
    arrow((l, 0), (l + 1.25, 0), lw=1.0, color="0.45")
    ax.text(l + 1.27, -0.02, "$x$", va="center", ha="left", color="0.3")
    arrow((0, wall_h), (0, 1.45), lw=1.0, color="0.45")
    ax.text(0.04, 1.45, "$y$", va="top", ha="left", color="0.3")

    # The beam.
    ax.plot(px, py, color=C1, lw=5, solid_capstyle="round", zorder=5)
    k = 150
    ax.text(px[k] + 0.05, py[k] + 0.09, "$EI,\\ m$", color=C1, ha="right", va="bottom", rotation=0)

    # The length l, below the undeformed axis.
    dim((0, -0.3), (l, -0.3), "$l$", (0, -0.1))
    ax.plot([l, l], [-0.36, 0.0], color="0.55", lw=0.9)

    # v1: from the axis up to the tip.
    dim((tip[0], 0.0), (tip[0], tip[1]), "$v_1$", (0.1, -0.06))
    # u2 (< 0): from x = l back to the tip; too short for arrows inside, so they point inwards
    # from outside, as on an engineering drawing.
    yu = -0.14
    for xe in (tip[0], l):
        ax.plot([xe, xe], [yu - 0.07, 0.0], color="0.55", lw=0.9)
    arrow((tip[0] - 0.28, yu), (tip[0], yu), lw=1.1, color="0.15", ms=12)
    arrow((l + 0.28, yu), (l, yu), lw=1.1, color="0.15", ms=12)
    ax.text(tip[0] - 0.31, yu, r"$u_2 = u_1(v_1, \vartheta_1)$", ha="right", va="center",
            color="0.15")

    # Tip: horizontal reference, tangent of the tip section, body axis; angles theta1, phi, theta.
    ax.plot([tip[0], tip[0] + 1.35], [tip[1], tip[1]], color="0.5", lw=1.0, ls=(0, (5, 4)))
    ax.plot(*zip(tip, tip + 1.3 * e_tan), color=C1, lw=1.2, ls=(0, (5, 4)))
    ax.text(*(tip + 1.33 * e_tan), "tip section", color=C1, fontsize=14, ha="left", va="center")
    ax.plot(*zip(tip, tip + 1.25 * e_body), color="0.25", lw=1.0, ls=(0, (2, 3)), zorder=6)

    def angle_arc(radius, a0, a1, label, label_r, color, dx=0.0, dy=0.0, ha="center"):
        ax.add_patch(Arc(tip, 2 * radius, 2 * radius, theta1=math.degrees(a0),
                         theta2=math.degrees(a1), color=color, lw=1.7, zorder=7))
        # Arrow head at the end of the arc.
        e = np.array([math.cos(a1), math.sin(a1)])
        n = np.array([-math.sin(a1), math.cos(a1)])
        head = tip + radius * e
        arrow(head - 0.02 * n, head, lw=1.7, color=color, ms=15, zorder=7)
        am = 0.5 * (a0 + a1)
        ax.text(tip[0] + label_r * math.cos(am) + dx, tip[1] + label_r * math.sin(am) + dy, label,
                color=color, ha=ha, va="center", zorder=8)

    angle_arc(0.80, 0.0, th1, r"$\vartheta_1$", 0.92, C1, dx=0.03)
    angle_arc(0.74, th1, theta, r"$\varphi$", 0.84, "#b3261e", dx=0.02)
    angle_arc(1.18, 0.0, theta, r"$\theta = \vartheta_1 + \varphi$", 1.27, "0.2", ha="left")

    # The body: a rounded rectangle along its axis, with its centre of mass C at r from the hinge.
    # Translucent, so the angles at the hinge stay readable through it.
    blen, bwid = 2.0 * r, 0.28
    body = FancyBboxPatch((-0.1, -bwid / 2), blen + 0.1, bwid,
                          boxstyle="round,pad=0,rounding_size=0.08",
                          fc="#f4d7b5", ec="#8a5a2b", lw=2.0, alpha=0.6, zorder=4)
    body.set_transform(Affine2D().rotate(theta).translate(*tip) + ax.transData)
    ax.add_patch(body)
    # Hinge.
    ax.add_patch(Circle(tip, 0.045, fc="white", ec="k", lw=2.0, zorder=9))
    ax.text(tip[0] + 0.12, tip[1] - 0.09, "hinge", fontsize=14, ha="left", va="top")
    # C: the usual centre-of-mass symbol (a circle with two black quarters).
    rc = 0.05
    ax.add_patch(Circle(cpt, rc, fc="white", ec="k", lw=1.5, zorder=10))
    for a in (0, 180):
        ax.add_patch(Wedge(cpt, rc, a, a + 90, fc="k", zorder=11))
    n_body = np.array([-math.sin(theta), math.cos(theta)])
    ax.text(*(cpt + 0.09 * n_body * -1 + 0.02 * e_body), "$C$", ha="left", va="center", zorder=11)
    # r: a dimension line on the body's far side from the angles, from the hinge to C.
    off = 0.3 * n_body
    for p in (tip, cpt):
        ax.plot(*zip(p + 0.08 * n_body, p + 1.12 * off), color="0.55", lw=0.8)
    dim(tip + off, cpt + off, "$r$", 0.09 * n_body)
    ax.text(*(tip + 0.85 * blen * e_body + 0.2 * n_body), "$M_2,\\ J_C$", color="#8a5a2b",
            ha="right", va="center")

    # Gravity along +x.
    g0 = np.array([0.55, 1.05])
    arrow(g0, g0 + np.array([0.7, 0.0]), lw=2.4, color="#2a7a2a", ms=22)
    ax.text(*(g0 + np.array([0.35, 0.09])), "$g$", color="#2a7a2a", ha="center", va="bottom")

    shown = f"v₁ = {v1} m, ϑ₁ = {th1} rad, φ = {math.degrees(phi):.0f}°"
    fig.text(0.985, 0.015, f"to scale: l = {l} m, r = {r} m;  shown: {shown}", fontsize=12,
             color="0.45", ha="right", va="bottom")
    ax.set_xlim(-0.3, l + 1.75)
    ax.set_ylim(-0.6, 1.75)
    fig.tight_layout(pad=0.2)
    fig.savefig(out, dpi=DPI)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--csv", type=Path, required=True)
    ap.add_argument("--out-dir", type=Path, default=Path("docs"))
    args = ap.parse_args()
    args.out_dir.mkdir(parents=True, exist_ok=True)
    figure3(read_csv(args.csv), args.out_dir / "figure3.png")
    draw_model(args.out_dir / "model.png")
    for name in ("figure3.png", "model.png"):
        print(f"wrote {args.out_dir / name}")


if __name__ == "__main__":
    main()
