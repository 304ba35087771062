#!/usr/bin/env python3
"""Closed-loop turn of the BeamBody FMU: turn the body by pi and leave the beam at rest.

    python examples/closed_loop.py [--fmu PATH] [--t-end SECONDS] [--plot docs/closed_loop.png]

The FMU (FMI 2.0 co-simulation, driven here through FMPy's low-level FMU2Slave) is the plant: the
cantilever of Russkikh & Shklyarchuk (2020) with a heavy body hinged at its tip. An external controller
commands the hinge angle phi (phi_source = input) and measures the FMU's outputs v1, theta1, dv1,
dtheta1, phi_applied, dphi_applied at every communication point.

Why the paper's law is a hard act to follow
-------------------------------------------
The paper's turn, phi = pi sin^2(pi t / (2T)) with T = 0.85 s, is shorter than the beam's slow period
(1.79 s at phi = 0, 1.15 s at phi = pi). It leaves a tip vibration of about 0.59 m (a quarter of the
beam's length) that the undamped model keeps for ever. Two facts shaped the design below:

* Feedback alone cannot damp that quickly. The input is the hinge acceleration phi''; the transfer
  functions phi'' -> v1 and phi'' -> theta1 of the model linearised at phi = pi have undamped zeros at
  +-3.1i and +-3.7i rad/s (motions of the body that leave v1, or theta1, at rest), and as the control is
  made cheaper the slowest pair of closed-loop poles of a linear-quadratic state feedback goes to a
  point fixed by these zeros and the state weights: with the energy-type weightings tried here it
  never got faster than about -1.4 /s. In trials, LQR feedback around the paper's law still left about
  4 cm of tip vibration 3 s after the start and kept moving phi for several seconds.
* A turn that ends at rest must be planned with the beam's dynamics, and the torque it needs rises
  steeply as the turn gets shorter than the slow period. Measured with the planner below (peak hinge
  moment |M| of the minimum-integral-of-phi''^2 turn that ends exactly at rest; the planner finds local
  minima, so the short ones are upper bounds): 0.85 s: ~1370 N m; 1.0 s: ~1280 N m; 1.2 s: ~330 N m;
  1.4 s: ~190 N m; 1.5 s: ~160 N m; 2.0 s: ~85 N m; the paper's law: 184 N m. So the default turn lasts
  1.5 s and needs less peak torque than the paper's law. Below about 2 s the optimal turn is not
  monotonic: it winds up (phi goes to about 0.3 pi and back to 0.13 pi, setting the beam swinging)
  and then swings the body over to pi as the beam swings back; at 2 s it is monotonic.
  (Zero-vibration input shaping of the paper's law, Singer & Seering 1990, does not help here: the
  modes change with phi, and the gravity moment M2 g r sin(phi) changes during the turn; shaped
  variants of the law with delays of 0.3-0.7 s still left 0.5-0.6 m.)

The controller (two degrees of freedom: a planned turn plus feedback around it)
-------------------------------------------------------------------------------
1. Internal model: the equations of motion derived here from the energies of the paper (eq. 10-13, the
   exact Lagrange equations (15) in v1, theta1 with phi prescribed), with the parameters read from the
   FMU's model description. It is integrated with RK4 over each communication step, phi'' held constant
   (exactly what the FMU receives, see 3).
2. Plan: iterative LQR (Li & Todorov 2004; Levenberg-Marquardt regularisation as in Tassa, Erez &
   Todorov 2012) finds the piecewise-constant phi''_k on the communication grid that minimises
   1/2 integral(phi''^2) + a large terminal penalty on (v1, theta1, dv1, dtheta1, phi - pi, phi'): a
   rest-to-rest turn of duration --t-turn that ends with the beam at rest in the internal model.
3. Feedback: time-varying LQR (discrete Riccati recursion along the plan; e.g. Anderson & Moore,
   "Optimal Control: Linear Quadratic Methods", 1990) with the weights below; after the plan, the
   stationary discrete LQR at phi = pi keeps the body there and damps what is left. At each
   communication point t_k = k h:
       phi''_k = phi''_plan,k - K_k (x_measured(t_k) - x_plan,k),   x = (v1, theta1, dv1, dtheta1, phi, phi')
   with x measured from the FMU's outputs. The command is integrated exactly (phi, phi' continuous,
   phi'' constant over the step) and sent as phi with its derivatives of orders 1 and 2
   (fmi2SetRealInputDerivatives) with phi_interpolation = taylor, so the FMU applies the same
   quadratic piece the controller planned and does not extrapolate (the default, smooth, would join
   the pieces C2 and extrapolate across the command's jumps of phi'', which the controller did not
   plan).

When the internal model is right, the plan alone already leaves almost nothing and the feedback has
little to correct. The loop matters when the plant differs from the model: the table therefore also
runs the FMU with a heavier (or lighter) body than the controller believes (--payload-error, both M2
and J_C scaled), with the plan alone and with the loop closed.

References: Singer N.C., Seering W.P., "Preshaping command inputs to reduce system vibration", J. Dyn.
Syst. Meas. Control 112(1), 1990, 76-82. Li W., Todorov E., "Iterative linear quadratic regulator design
for nonlinear biological movement systems", ICINCO 2004. Tassa Y., Erez T., Todorov E., "Synthesis and
stabilization of complex behaviors through online trajectory optimization", IROS 2012. Anderson B.D.O.,
Moore J.B., "Optimal Control: Linear Quadratic Methods", Prentice Hall 1990. Bryson A.E., Ho Y.-C.,
"Applied Optimal Control", 1975 (the weight scaling rule).

Figures (printed as a table): residual vibration = max |v1 - v1_eq(pi)| after the turn ends (after the
law's t_rot, or after the plan); the time after which the tip stays within 1 cm of that equilibrium;
the residual vibration energy (FMU's energy output minus that of the rest state at phi = pi, mean over
the last second); the peak hinge moment |M| (M is the FMU's output; the drive torque is -M); |phi - pi|
at the end.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.linalg import solve_discrete_are

REPO = Path(__file__).resolve().parents[1]
DEFAULT_FMU = REPO / "target" / "fmu" / "BeamBody.fmu"
PI = math.pi

OUTPUTS = ("v1", "theta1", "u2", "dv1", "dtheta1", "du2", "N", "P", "M", "drift", "energy",
           "phi_applied", "dphi_applied", "ddphi_applied")
PARAMS = ("l", "EI", "m", "M2", "J_C", "r", "g", "t_rot", "phi_end")
PHI_SOURCE_INPUT, PHI_SOURCE_LAW = 1, 2
PHI_INTERPOLATION_TAYLOR = 2  # phi_interpolation: 1 = smooth (the default), 2 = taylor
X_FINAL = np.array([0.0, 0.0, 0.0, 0.0, PI, 0.0])  # rest at phi = pi (v1_eq(pi) = theta1_eq(pi) = 0)

# --------------------------------------------------------------------------------------------------
# the controller's internal model
# --------------------------------------------------------------------------------------------------


class Model:
    """Exact Lagrange equations of the beam-body system in q = (v1, theta1) with phi prescribed.

    Beam (one Hermite element): T1 = 1/2 qd' Mb qd, Pi1 = 1/2 q' K q. Inextensibility: the tip's axial
    displacement u1 = 1/2 q' H q (u1 = -l (3/5 v^2 - 1/10 v th + 1/15 th^2), v = v1/l). Body centre
    C = (l + u1 + r cos(a), v1 + r sin(a)), a = theta1 + phi; T2 = 1/2 M2 |C'|^2 + 1/2 J_C a'^2,
    Pi2 = -M2 g (u1 + r cos a). With Jx = dCx/dq = H q - r sin(a) e2, Jy = dCy/dq = (1, r cos a):
        (Mb + M2 Jx Jx' + M2 Jy Jy' + J_C e2 e2') q'' = -(K q + M2 (bx - g) Jx + M2 by Jy + J_C phi'' e2)
    bx, by: the velocity and phi'' parts of C''. All functions broadcast over numpy arrays (the
    planner evaluates many states at once)."""

    def __init__(self, l, EI, m, M2, J_C, r, g, **_):
        self.M2, self.J_C, self.r, self.g = M2, J_C, r, g
        self.mvv, self.mvt, self.mtt = 13 * m * l / 35, -11 * m * l * l / 210, m * l**3 / 105
        self.kvv, self.kvt, self.ktt = 12 * EI / l**3, -6 * EI / l**2, 4 * EI / l
        self.h11, self.h12, self.h22 = -6 / (5 * l), 0.1, -2 * l / 15

    def accel(self, v, th, dv, dth, phi, dphi, ddphi):
        """(v1'', theta1'')."""
        M2, JC, r, g = self.M2, self.J_C, self.r, self.g
        a = th + phi
        s, c, w = np.sin(a), np.cos(a), dth + dphi
        jx0, jx1 = self.h11 * v + self.h12 * th, self.h12 * v + self.h22 * th - r * s
        jy1 = r * c
        bx = self.h11 * dv * dv + 2 * self.h12 * dv * dth + self.h22 * dth * dth - r * c * w * w - r * s * ddphi
        by = -r * s * w * w + r * c * ddphi
        a11 = self.mvv + M2 * (jx0 * jx0 + 1.0)
        a12 = self.mvt + M2 * (jx0 * jx1 + jy1)
        a22 = self.mtt + M2 * (jx1 * jx1 + jy1 * jy1) + JC
        f0 = -(self.kvv * v + self.kvt * th + M2 * (bx - g) * jx0 + M2 * by)
        f1 = -(self.kvt * v + self.ktt * th + M2 * (bx - g) * jx1 + M2 * by * jy1 + JC * ddphi)
        det = a11 * a22 - a12 * a12
        return (a22 * f0 - a12 * f1) / det, (a11 * f1 - a12 * f0) / det

    def drive_torque(self, v, th, dv, dth, phi, dphi, ddphi):
        """Torque the drive applies to the body (the body's moment equation about the hinge), = -M of
        the FMU: J2 a'' + M2 r (cos(a) v1'' - sin(a) u1'') + M2 g r sin(a)."""
        av, at = self.accel(v, th, dv, dth, phi, dphi, ddphi)
        a = th + phi
        s, c = np.sin(a), np.cos(a)
        u1dd = ((self.h11 * v + self.h12 * th) * av + (self.h12 * v + self.h22 * th) * at
                + self.h11 * dv * dv + 2 * self.h12 * dv * dth + self.h22 * dth * dth)
        j2 = self.J_C + self.M2 * self.r**2
        return j2 * (at + ddphi) + self.M2 * self.r * (c * av - s * u1dd) + self.M2 * self.g * self.r * s

    def step(self, x, u, h, substeps=4):
        """State x = (v1, theta1, dv1, dtheta1, phi, phi') after h with phi'' = u held: phi exactly
        (phi + phi' t + u t^2/2, as the FMU applies the input's Taylor polynomial), the beam by RK4."""
        x = np.asarray(x, float)
        u = np.asarray(u, float)
        y = [x[..., i] for i in range(4)]
        phi, dphi = x[..., 4], x[..., 5]
        dt = h / substeps

        def f(t, y):
            av, at = self.accel(*y, phi + dphi * t + 0.5 * u * t * t, dphi + u * t, u)
            return (y[2], y[3], av, at)

        for j in range(substeps):
            t = j * dt
            k1 = f(t, y)
            k2 = f(t + dt / 2, [a + dt / 2 * b for a, b in zip(y, k1)])
            k3 = f(t + dt / 2, [a + dt / 2 * b for a, b in zip(y, k2)])
            k4 = f(t + dt, [a + dt * b for a, b in zip(y, k3)])
            y = [a + dt / 6 * (b1 + 2 * b2 + 2 * b3 + b4) for a, b1, b2, b3, b4 in zip(y, k1, k2, k3, k4)]
        return np.stack([*y, phi + dphi * h + 0.5 * u * h * h, dphi + u * h], axis=-1)

    def jacobians(self, X, U, h, eps=1e-6):
        """A_k = d step/dx, B_k = d step/du at (X[k], U[k]) by central differences, all k at once."""
        n = len(U)
        E = np.eye(6) * eps
        Xp = np.concatenate([X[:, None, :] + E, X[:, None, :] - E], axis=1)  # (n, 12, 6)
        Y = self.step(Xp, np.repeat(U[:, None], 12, axis=1), h)
        A = ((Y[:, :6] - Y[:, 6:]) / (2 * eps)).transpose(0, 2, 1)
        Yu = self.step(np.stack([X, X], 1), np.stack([U + eps, U - eps], 1), h)
        B = (Yu[:, 0] - Yu[:, 1]) / (2 * eps)
        return A.reshape(n, 6, 6), B.reshape(n, 6)

    def vibration_metric(self):
        """(mass, stiffness) of the small oscillations about the rest state at phi = pi: the
        linearised equations A q'' + K q = 0 there (K includes the axial pull M2 g of the body through
        -M2 g H, and the body's own gravity moment M2 g r cos(pi))."""
        M2, r, g = self.M2, self.r, self.g
        mass = np.array([[self.mvv + M2, self.mvt - M2 * r], [self.mvt - M2 * r, self.mtt + self.J_C + M2 * r * r]])
        stiff = np.array([[self.kvv - M2 * g * self.h11, self.kvt - M2 * g * self.h12],
                          [self.kvt - M2 * g * self.h12, self.ktt - M2 * g * self.h22 - M2 * g * r]])
        return mass, stiff


# --------------------------------------------------------------------------------------------------
# the plan (iLQR) and the feedback gains (TVLQR)
# --------------------------------------------------------------------------------------------------


def plan_turn(model: Model, t_turn: float, h: float, iters: int = 200):
    """iLQR: phi''_k, k < N = t_turn/h, minimising 1/2 h sum(phi''_k^2) + 1/2 e' Qf e, e = x_N - X_FINAL.
    Qf is raised in stages (a penalty continuation) so that the early iterations are well conditioned;
    the last stage leaves |e| ~ 1e-6. Returns (X (N+1, 6), U (N,))."""
    n = int(round(t_turn / h))
    w = PI / (n * h)
    U = 0.5 * PI * w * w * np.cos(w * (np.arange(n) + 0.5) * h)  # first guess: the paper's law, stretched
    scales = np.array([1.0, 1.0, 1e-2, 1e-2, 1.0, 1e-1])  # m, rad, m/s, rad/s, rad, rad/s

    def rollout(U, X=None, kff=None, K=None, alpha=1.0):
        xs, us = np.zeros((n + 1, 6)), np.zeros(n)
        for k in range(n):
            us[k] = U[k] if K is None else U[k] + alpha * kff[k] + K[k] @ (xs[k] - X[k])
            xs[k + 1] = model.step(xs[k], us[k], h)
        return xs, us

    X, U = rollout(U)
    for qf in (1e6, 1e8, 1e10):
        Qf = qf * np.diag(scales)

        def cost(X, U):
            e = X[-1] - X_FINAL
            return 0.5 * h * float(U @ U) + 0.5 * float(e @ Qf @ e)

        J, mu = cost(X, U), 0.0
        for _ in range(iters):
            A, B = model.jacobians(X[:-1], U, h)
            vx, vxx = Qf @ (X[-1] - X_FINAL), Qf.copy()
            kff, K = np.zeros(n), np.zeros((n, 6))
            for k in range(n - 1, -1, -1):
                qx, qu = A[k].T @ vx, h * U[k] + B[k] @ vx
                qxx, quu, qux = A[k].T @ vxx @ A[k], h + B[k] @ vxx @ B[k] + mu, B[k] @ vxx @ A[k]
                kff[k], K[k] = -qu / quu, -qux / quu
                vx = qx + K[k] * quu * kff[k] + K[k] * qu + qux * kff[k]
                vxx = qxx + quu * np.outer(K[k], K[k]) + np.outer(K[k], qux) + np.outer(qux, K[k])
                vxx = 0.5 * (vxx + vxx.T)
            for alpha in (1.0, 0.5, 0.25, 0.1, 0.03):
                with np.errstate(all="ignore"):
                    Xn, Un = rollout(U, X, kff, K, alpha)
                    Jn = cost(Xn, Un)
                if np.isfinite(Jn) and Jn < J:
                    break
            else:  # no descent: regularise the step more (Levenberg-Marquardt on Quu)
                mu = max(10 * mu, 1e-6 * h)
                if mu > 1e6:
                    break
                continue
            dJ, (X, U, J) = J - Jn, (Xn, Un, Jn)
            mu = 0.1 * mu if mu > 1e-6 * h else 0.0
            if dJ < 1e-9 * J:
                break
    return X, U


@dataclass
class Weights:
    """LQR weights. The beam's vibration energy (1/2 qd' A qd + 1/2 q' K q about the rest state at
    phi = pi) counts with w_energy; phi and phi' errors against the plan with Bryson's rule (1/scale^2);
    phi'' with r_u. Chosen by trying: the stationary closed loop at pi (h = 0.01 s) then has the poles
    -1.23 +- 4.59i, -4.4, -10.9 +- 23.5i and -415 /s: the slowest pair sits at the limit set by the zeros
    described at the top, the fast beam mode gets a damping ratio of about 0.4, and the peak torque of
    the loop stays near the plan's."""

    w_energy: float = 10.0
    phi_scale: float = 0.05  # rad
    dphi_scale: float = 0.2  # rad/s
    r_u: float = 1e-4  # (rad/s^2)^-2

    def q_matrix(self, model: Model):
        mass, stiff = model.vibration_metric()
        Q = np.zeros((6, 6))
        Q[:2, :2], Q[2:4, 2:4] = self.w_energy * stiff, self.w_energy * mass
        Q[4, 4], Q[5, 5] = self.phi_scale**-2, self.dphi_scale**-2
        return Q


def tvlqr(model: Model, X, U, h, weights: Weights):
    """Discrete LQR gains along the plan (backward Riccati recursion from the stationary solution at
    phi = pi), and the stationary gain at pi. u = u_plan - K (x - x_plan)."""
    Q, R = weights.q_matrix(model) * h, weights.r_u * h
    Af, Bf = model.jacobians(X_FINAL[None], np.zeros(1), h)
    Af, Bf = Af[0], Bf[0][:, None]
    P = solve_discrete_are(Af, Bf, Q, np.array([[R]]))
    k_final = np.linalg.solve(R + Bf.T @ P @ Bf, Bf.T @ P @ Af)[0]
    A, B = model.jacobians(X[:-1], U, h)
    K = np.zeros((len(U), 6))
    for k in range(len(U) - 1, -1, -1):
        K[k] = (B[k] @ P @ A[k]) / (R + B[k] @ P @ B[k])
        P = Q + A[k].T @ P @ (A[k] - np.outer(B[k], K[k]))
        P = 0.5 * (P + P.T)
    return K, k_final, np.linalg.eigvals(Af - Bf @ k_final[None])


@dataclass
class Controller:
    """phi''_k from the measured state at t_k = k h (see the module docstring). feedback=False: the plan
    alone (open loop, the baseline that shows what the feedback adds)."""

    X: np.ndarray
    U: np.ndarray
    K: np.ndarray
    k_final: np.ndarray
    feedback: bool = True

    def __call__(self, k: int, x: np.ndarray) -> float:
        if k < len(self.U):
            return float(self.U[k] - (self.K[k] @ (x - self.X[k]) if self.feedback else 0.0))
        return float(-(self.k_final @ (x - X_FINAL)) if self.feedback else 0.0)


# --------------------------------------------------------------------------------------------------
# the FMU
# --------------------------------------------------------------------------------------------------


@dataclass
class Fmu:
    """The FMU, extracted once; instance() makes a fresh FMU2Slave for each run."""

    path: Path
    unzipdir: str = ""
    md: object = None
    vr: dict = field(default_factory=dict)  # name -> value reference
    start: dict = field(default_factory=dict)  # the model parameters' start values (PARAMS)
    _count: int = 0

    def __post_init__(self):
        import fmpy

        self.md = fmpy.read_model_description(str(self.path))
        self.unzipdir = fmpy.extract(str(self.path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.start = {v.name: float(v.start) for v in self.md.modelVariables if v.name in PARAMS}

    def instance(self):
        from fmpy.fmi2 import FMU2Slave

        self._count += 1
        s = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir, instanceName=f"closed_loop_{self._count}",
                      modelIdentifier=self.md.coSimulation.modelIdentifier)
        # FMPy's default callbacks: its logger is a module global, so it outlives the instance
        s.instantiate(loggingOn=False)
        return s

    def cleanup(self):
        import shutil

        shutil.rmtree(self.unzipdir, ignore_errors=True)


@dataclass
class Run:
    name: str
    t: np.ndarray
    y: dict  # output name -> array at t
    u_cmd: np.ndarray  # commanded phi'' per step (law: the FMU's ddphi_applied)
    turn_end: float  # when the reference turn ends (law: t_rot; plan: its duration)


def simulate(fmu: Fmu, t_end: float, h: float, controller=None, plant: dict | None = None, tol: float = 1e-8,
             name: str = "", turn_end: float = 0.0) -> Run:
    """One FMU run on the grid k h. controller=None: the FMU's own law (phi_source = law). Otherwise
    phi_source = input: at each t_k the outputs are read, phi''_k = controller(k, x), and phi, phi',
    phi'' are sent before doStep(t_k, h). plant: parameter values for the FMU that differ from its
    defaults (the controller does not know them)."""
    from fmpy.fmi2 import fmi2Integer, fmi2Real, fmi2ValueReference

    n = int(round(t_end / h))
    s = fmu.instance()
    vr_out = [fmu.vr[o] for o in OUTPUTS]
    # fmi2SetRealInputDerivatives through the FMU2Slave's own ctypes binding, with the arrays built once:
    # both orders in one call (vr = [phi, phi], order = [1, 2]). FMPy 0.3.32's simulate_fmu cannot send
    # derivatives to this FMU: with set_input_derivatives=True it copies them into a fixed 9-element
    # buffer (`derivatives[:] = d`), which raises "ValueError: Can only assign sequence of same size"
    # for an FMU with one input. The binding itself passes the arrays to the C function as they are.
    vr_d = (fmi2ValueReference * 2)(fmu.vr["phi"], fmu.vr["phi"])
    order_d = (fmi2Integer * 2)(1, 2)
    value_d = (fmi2Real * 2)()
    try:
        s.setupExperiment(tolerance=tol, startTime=0.0)
        s.setInteger([fmu.vr["phi_source"]], [PHI_SOURCE_LAW if controller is None else PHI_SOURCE_INPUT])
        s.setInteger([fmu.vr["phi_interpolation"]], [PHI_INTERPOLATION_TAYLOR])
        for k_, v in (plant or {}).items():
            s.setReal([fmu.vr[k_]], [float(v)])
        s.enterInitializationMode()
        s.setReal([fmu.vr["phi"]], [0.0])
        s.exitInitializationMode()
        rows, us = [s.getReal(vr_out)], []
        phi = dphi = 0.0  # the command, integrated exactly: phi and phi' are continuous
        for k in range(n):
            tc = k * h
            if controller is not None:
                y = dict(zip(OUTPUTS, rows[-1]))
                x = np.array([y["v1"], y["theta1"], y["dv1"], y["dtheta1"], y["phi_applied"], y["dphi_applied"]])
                u = controller(k, x)
                s.setReal([fmu.vr["phi"]], [phi])
                value_d[0], value_d[1] = dphi, u
                s.fmi2SetRealInputDerivatives(s.component, vr_d, 2, order_d, value_d)
                phi, dphi = phi + dphi * h + 0.5 * u * h * h, dphi + u * h
                us.append(u)
            s.doStep(currentCommunicationPoint=tc, communicationStepSize=h)
            rows.append(s.getReal(vr_out))
            if controller is None:
                us.append(rows[-1][OUTPUTS.index("ddphi_applied")])
        s.terminate()
    finally:
        s.freeInstance()
    arr = np.array(rows)
    return Run(name, np.arange(n + 1) * h, {o: arr[:, i] for i, o in enumerate(OUTPUTS)}, np.array(us), turn_end)


def rest_energy(fmu: Fmu, plant: dict | None = None) -> float:
    """The FMU's energy output in the rest state at phi = pi (zero beam state; it is the static
    equilibrium there: equilibrium_at_pi)."""
    s = fmu.instance()
    try:
        s.setupExperiment(startTime=0.0)
        for k_, v in (plant or {}).items():
            s.setReal([fmu.vr[k_]], [float(v)])
        s.enterInitializationMode()
        s.setReal([fmu.vr["phi"]], [PI])
        s.exitInitializationMode()
        e = s.getReal([fmu.vr["energy"]])[0]
        s.terminate()
    finally:
        s.freeInstance()
    return e


def equilibrium_at_pi(model: Model):
    """Static equilibrium (v1, theta1) at phi = pi by Newton's method on the model's accelerations."""
    q = np.zeros(2)
    for _ in range(50):
        f = np.array(model.accel(q[0], q[1], 0.0, 0.0, PI, 0.0, 0.0))
        J = np.column_stack([(np.array(model.accel(*(q + d), 0.0, 0.0, PI, 0.0, 0.0)) - f) / 1e-7
                             for d in np.eye(2) * 1e-7])
        dq = np.linalg.solve(J, -f)
        q = q + dq
        if np.max(np.abs(dq)) < 1e-14:
            break
    return q


# --------------------------------------------------------------------------------------------------
# figures
# --------------------------------------------------------------------------------------------------


@dataclass
class Figures:
    name: str
    turn_end: float  # s
    residual: float  # max |v1 - v1_eq| over [turn_end, t_end], m
    residual_last: float  # the same over the last second (after the turn), m
    settled: float  # s: the tip stays within SETTLE_BAND of v1_eq from then on (inf: it left it in the last second)
    residual_energy: float  # J, mean over the last second (after the turn) of energy - rest energy
    peak_torque: float  # max |M|, N m
    phi_error: float  # |phi - pi| at t_end, rad
    peak_ddphi: float  # rad/s^2
    finite: bool


SETTLE_BAND = 0.01  # m


def figures(run: Run, v1_eq: float, e_rest: float) -> Figures:
    t, y = run.t, run.y
    dev = np.abs(y["v1"] - v1_eq)
    after = t >= run.turn_end - 1e-9
    last = t >= max(t[-1] - 1.0, run.turn_end - 1e-9)  # the last second, but never before the turn ends
    outside = np.nonzero(dev > SETTLE_BAND)[0]
    settled = 0.0 if len(outside) == 0 else float(t[min(outside[-1] + 1, len(t) - 1)])
    if settled > t[-1] - 1.0:  # an oscillation may be inside the band just at the end: no claim
        settled = math.inf
    return Figures(
        name=run.name,
        turn_end=run.turn_end,
        residual=float(np.max(dev[after])),
        residual_last=float(np.max(dev[last])),
        settled=settled,
        residual_energy=float(np.mean(y["energy"][last] - e_rest)),
        peak_torque=float(np.max(np.abs(y["M"]))),
        phi_error=float(abs(y["phi_applied"][-1] - PI)),
        peak_ddphi=float(np.max(np.abs(run.u_cmd))),
        finite=bool(all(np.all(np.isfinite(a)) for a in y.values())),
    )


def table(rows: list[Figures], t_end: float) -> str:
    head = (f"{'case':<38s} {'turn':>5s} {'residual':>9s} {'last 1 s':>9s} {'within':>8s} {'E_resid':>9s} "
            f"{'peak |M|':>8s} {'peak':>6s} {'|phi-pi|':>9s}")
    units = (f"{'':<38s} {'[s]':>5s} {'[m]':>9s} {'[m]':>9s} {'1 cm [s]':>8s} {'[J]':>9s} "
             f"{'[N m]':>8s} {'phi_dd':>6s} {'end [rad]':>9s}")
    lines = [head, units]
    for f in rows:
        within = "no" if math.isinf(f.settled) else f"{f.settled:.2f}"
        lines.append(f"{f.name:<38s} {f.turn_end:5.2f} {f.residual:9.2e} {f.residual_last:9.2e} {within:>8s} "
                     f"{f.residual_energy:9.2e} {f.peak_torque:8.1f} {f.peak_ddphi:6.1f} {f.phi_error:9.1e}")
    lines += [
        f"residual: max |v1 - v1_eq(pi)| from the end of the turn to t_end = {t_end:g} s; last 1 s: the same over",
        "  the last second (never before the turn ends); within 1 cm: |v1 - v1_eq| <= 1 cm from then on ('no': it",
        "  was outside during the last second); E_resid: energy - energy at rest at pi, mean over the last second;",
        "  peak |M|: the hinge moment (the drive torque is -M); peak phi_dd: commanded phi'' [rad/s^2]",
    ]
    return "\n".join(lines)


def plot(runs: list[Run], v1_eq: float, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    styles = [dict(color="#d95f02", lw=1.6), dict(color="#1b4f9c", lw=1.8),
              dict(color="#7f7f7f", lw=1.2, ls=":"), dict(color="#1b9e77", lw=1.4, ls="--")]
    fig, ax = plt.subplots(4, 1, figsize=(8.0, 9.6), sharex=True, gridspec_kw=dict(height_ratios=[1, 1.2, 1.2, 1]))
    for run, st in zip(runs, styles):
        t, y = run.t, run.y
        ax[0].plot(t, y["phi_applied"] / PI, label=run.name, **st)
        ax[1].plot(t, y["v1"], **st)
        ax[2].semilogy(t, np.maximum(np.abs(y["v1"] - v1_eq), 1e-7), **st)
        ax[3].plot(t, y["M"], **st)
    ax[0].set_ylabel(r"$\varphi/\pi$")
    ax[0].legend(loc="lower right", fontsize=8.5, framealpha=0.95)
    ax[1].set_ylabel(r"tip deflection $v_1$ [m]")
    ax[2].set_ylabel(r"$|v_1 - v_{1,eq}(\pi)|$ [m]")
    ax[2].set_ylim(1e-6, 2)
    ax[2].axhline(SETTLE_BAND, color="k", lw=0.6, ls="-.")
    ax[2].text(1.005, SETTLE_BAND, "1 cm", transform=ax[2].get_yaxis_transform(), ha="left", va="center", fontsize=8)
    ax[3].set_ylabel(r"hinge moment $M$ [N m]")
    ax[3].set_xlabel("t [s]")
    for a in ax:
        a.grid(True, lw=0.4, alpha=0.6)
        for run, st in zip(runs[:2], styles[:2]):
            a.axvline(run.turn_end, color=st["color"], lw=0.7, alpha=0.5)
    for run, st in zip(runs[:2], styles[:2]):  # where each turn ends
        ax[0].annotate(f"{run.turn_end:g} s", (run.turn_end, 0.5), xytext=(3, 0), textcoords="offset points",
                       color=st["color"], fontsize=8, va="center")
    ax[0].set_title("BeamBody FMU: paper's law (open loop) vs planned turn + LQR feedback", fontsize=11)
    ax[3].set_xlim(0, runs[0].t[-1])
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --------------------------------------------------------------------------------------------------
# main
# --------------------------------------------------------------------------------------------------


@dataclass
class Result:
    runs: dict  # key -> Run
    figures: dict  # key -> Figures
    v1_eq: float
    closed_loop_poles: np.ndarray
    plan_seconds: float


def run_all(fmu_path: Path = DEFAULT_FMU, t_end: float = 6.0, h: float = 0.01, t_turn: float = 1.5,
            payload_error: float = 0.2, weights: Weights | None = None, tol: float = 1e-8) -> Result:
    """Plans, designs the gains and runs the FMU: the paper's law; the planned turn with the loop
    closed; and, if payload_error != 0, a plant whose body is (1 + payload_error) times heavier (M2 and
    J_C) than the controller's model, with the plan alone and with the loop closed."""
    weights = weights or Weights()
    fmu = Fmu(Path(fmu_path))
    try:
        nominal = fmu.start  # the controller's model: the FMU's default parameters
        model = Model(**nominal)
        q_eq = equilibrium_at_pi(model)
        t0 = time.perf_counter()
        X, U = plan_turn(model, t_turn, h)
        K, k_final, poles = tvlqr(model, X, U, h, weights)
        plan_seconds = time.perf_counter() - t0
        t_turn = len(U) * h
        closed = Controller(X, U, K, k_final, feedback=True)
        planned = Controller(X, U, K, k_final, feedback=False)
        t_rot = nominal["t_rot"]
        runs = {
            "law": simulate(fmu, t_end, h, None, None, tol, f"paper's law, T = {t_rot:g} s (open loop)", t_rot),
            "closed": simulate(fmu, t_end, h, closed, None, tol, f"plan {t_turn:g} s + feedback", t_turn),
            "plan": simulate(fmu, t_end, h, planned, None, tol, f"plan {t_turn:g} s alone (open loop)", t_turn),
        }
        e_rest = {"nominal": rest_energy(fmu)}
        if payload_error:
            plant = {"M2": nominal["M2"] * (1 + payload_error), "J_C": nominal["J_C"] * (1 + payload_error)}
            tag = f"body {100 * payload_error:+.0f}%"
            runs["plan_mismatch"] = simulate(fmu, t_end, h, planned, plant, tol, f"plan alone, {tag} (open loop)",
                                             t_turn)
            runs["closed_mismatch"] = simulate(fmu, t_end, h, closed, plant, tol, f"plan + feedback, {tag}", t_turn)
            e_rest["mismatch"] = rest_energy(fmu, plant)
        figs = {k: figures(r, q_eq[0], e_rest["mismatch" if k.endswith("mismatch") else "nominal"])
                for k, r in runs.items()}
    finally:
        fmu.cleanup()
    return Result(runs, figs, float(q_eq[0]), poles, plan_seconds)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fmu", type=Path, default=DEFAULT_FMU,
                    help=f"the FMU (default {DEFAULT_FMU.relative_to(REPO)})")
    ap.add_argument("--t-end", type=float, default=6.0, help="simulated time [s] (default 6)")
    ap.add_argument("--plot", type=Path, help="write the figure here (e.g. docs/closed_loop.png)")
    ap.add_argument("--t-turn", type=float, default=1.5, help="duration of the planned turn [s] (default 1.5)")
    ap.add_argument("--step", type=float, default=0.01,
                    help="communication step = control period [s] (default 0.01)")
    ap.add_argument("--payload-error", type=float, default=0.2,
                    help="relative error of the body's M2 and J_C in the plant, unknown to the controller, for the "
                         "robustness rows (default 0.2; 0 skips them)")
    args = ap.parse_args(argv)
    if not args.fmu.is_file():
        sys.exit(f"FMU not found at {args.fmu}: build it with `cargo xtask fmu` or pass --fmu")
    res = run_all(args.fmu, args.t_end, args.step, args.t_turn, args.payload_error)
    slow = max(res.closed_loop_poles, key=abs)  # discrete poles: the slowest has the largest |z|
    print(f"plan + gains: {res.plan_seconds:.1f} s; slowest stationary closed-loop pole at pi: "
          f"{np.log(complex(slow)) / args.step:.2f} /s; v1_eq(pi) = {res.v1_eq:.1e} m")
    print(table(list(res.figures.values()), args.t_end))
    if args.plot:
        order = ["law", "closed", "plan_mismatch", "closed_mismatch"]
        plot([res.runs[k] for k in order if k in res.runs], res.v1_eq, args.plot)
        print(f"figure: {args.plot}")
    return res


if __name__ == "__main__":
    main()
