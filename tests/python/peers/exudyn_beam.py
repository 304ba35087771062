"""A peer model of the beam–body system in EXUDYN (PyPI `exudyn`), a flexible multibody code written by
others, for checking our model (see /work/shared/model-notes.md and docs/model.md).

The system, built from EXUDYN's own items (names as in EXUDYN's item reference, docs/RST/items/*.rst of
the EXUDYN repository, version 1.13.6):
- the beam: `n_elements` ObjectANCFCable2D elements (2D Euler–Bernoulli ANCF cable; nodes
  NodePoint2DSlope1 with coordinates [x, y, x', y']). It is clamped at x = 0 along +x: three
  ObjectConnectorCoordinate constraints hold x, y and the slope's y-component of the first node at zero
  (the slope's x-component stays free, so the beam may stretch axially). Axial stiffness EA is a penalty
  that approximates our inextensible beam (ObjectANCFCable2D: "N = EA (ε − ε0)", ε = |r'| − 1); its
  mass matrix is the consistent one, ∫ρA SᵀS dx, so it also has the axial inertia that our quadratic
  model leaves out (of higher order in the deflection) and our exact beam (`--beam exact`) keeps.
- the body: NodeRigidBody2D + ObjectRigidBody2D (mass M2, inertia J_C about its centre of mass C),
  with C initially at (l + r, 0).
- the driven hinge: ObjectJointGeneric between a MarkerBodyRigid at the beam's tip (local x = element
  length on the last element) and a MarkerBodyRigid on the body at the hinge (local [−r, 0]). It
  constrains the two in-plane translations and the rotation about z (constrainedAxes
  [1,1,0,0,0,1]); its offsetUserFunction adds the Tait–Bryan angles [0, 0, φ(t)] to the tip's joint
  frame (ObjectJointGeneric.rst: "the three components of UF_{3,4,5} are interpreted as Tait-Bryan
  angles that are added to the joint frame"), so the body's angle is the tip section's angle plus
  φ(t). The offset is used by the index-3 generalized-α integrator; its time derivative is given as
  offsetUserFunction_t as the same page asks ("provide both").
- or, with hinge="revolute" (the build that the project's issue asks for): the hinge is an
  ObjectJointRevolute2D (ObjectJointRevolute2D.rst: it "constrains the absolute 2D position of two
  points") between MarkerBodyPosition markers at the same two points, and the drive is a
  MarkerBodiesRelativeRotationCoordinate on the last element and the body (MarkerBodiesRelativeRotationCoordinate.rst:
  the relative rotation of two "rigid bodies or beams" about axis0 = z, φ = atan2(…) of the relative
  rotation matrix, its velocity from the two angular velocities; here the ANCF tip section's angle
  atan2(r'_y, r'_x) and the body's angle), held at φ(t) by an ObjectConnectorCoordinate against a ground
  coordinate with offsetUserFunction φ(t) and offsetUserFunction_t φ'(t) (ObjectConnectorCoordinate.rst).
  The marker's NodeGenericData (NodeGenericData.rst) carries the previous angle so that the measured
  angle continues through ±π, which φ_end = π reaches. This is EXUDYN's own pattern
  (TestModels/relativeRotationTranslationMechanism.py). The two builds are the same constraints: their
  motions agree to 4e-11 (tests/python/peers/test_exudyn_exact.py).
- gravity g along +x on the body only (LoadForceVector at C), none on the beam, as in the paper.

Consistent initial accelerations (hinge="revolute", consistent_start, on by default there). EXUDYN's
theory manual (section "Implicit trapezoidal rule-based, Newmark and Generalized-alpha solver", "Initial
accelerations") writes the start as [M Gᵀ; G 0]·[a0; λ0] = [f; −∂²g/∂t² − …] (GeneralizedAlphaSettings.
computeInitialAccelerations, on by default), but the ∂²g/∂t² of a constraint's offset user function is
not implemented: at rest in equilibrium its a0 is exactly zero although φ''(0) = φ_end·π²/(2 t_rot²)
= 21.46 rad/s² (measured). There is no setting that adds it, so `_consistent_accelerations` takes EXUDYN's
a0 and its M and G (MainSolverImplicitSecondOrder: InitializeSolver, ComputeMassMatrix,
ComputeJacobianAE) and adds Δa from [M Gᵀ; G 0]·[Δa; Δλ] = [0; γ], γ = φ''(0) on the drive's row; the
result is set as the initial configuration's accelerations (systemData.SetODE2Coordinates_tt) and the
solver told to use them (computeInitialAccelerations = False, resetAccelerations = False). What it
changes, measured: the motion by < 1e-12 (the Newton tolerance) and the drive's moment by 8e-4 N·m in
the first steps. That is the index-3 generalized-α's property: a change of the starting acceleration
along M⁻¹Gᵀ, which Δa is, is taken up by the multipliers, and the positions, fixed by g(q, t) = 0 at
each step, do not see it. So the peer's motion is the same with either start; the option is there
because the issue asks for it and for the moment's first steps.

Initial state: at rest, straight, in static equilibrium. With gravity along the axis the exact static
state of the discretised beam is a uniform stretch ε0 = M2·g/EA (axial force M2·g, no bending), which
the cubic ANCF interpolation represents exactly; the nodes start there (x_i(1 + ε0), slope
(1 + ε0, 0)) and C at l(1 + ε0) + r. Starting at the unstretched length instead would excite an axial
vibration of amplitude M2·g·l/EA at the axial frequency (~300 Hz at EA = 1e8). This is the penalty
model's counterpart of our inextensible beam's zero initial state.

Outputs (SensorBody on the last element at its end, OutputVariableType Position and Rotation, and
SensorObject on the joint, TorqueLocal):
- v1 = y of the tip;
- theta1 = the tip's "Rotation" output, atan2(r'_y, r'_x) (ObjectANCFCable2D.rst);
- u2 = x_tip − l, which includes the elastic stretch (M2·g·l/EA = 3e-6 m at φ = 0 with the paper's
  values and EA = 1e8; `static_stretch` gives it);
- M = the moment that the body exerts on the beam tip, our CLI's sign convention (docs/cli.md: "−M is
  the torque the drive applies to the body"); it is −(joint's TorqueLocal z) of the generic joint, whose
  marker 0 is the tip, and with hinge="revolute" the drive constraint's multiplier λ (SensorObject
  Force; the constraint θ_body − θ_tip − φ = 0 puts −λ on the body's angle). As an index-3 Lagrange
  multiplier it rings for a few steps after the jumps of φ'' (t = 0 and t = t_rot), damped by the
  integrator's spectral radius.

Integrator: EXUDYN's implicit generalized-α (solverType GeneralizedAlpha, index 3, constant step dt,
adaptiveStep off so that a failing step fails the run instead of shrinking the step), spectral radius
`rho_inf` (EXUDYN's default 0.9; GeneralizedAlphaSettings: "for position-level constraints (index 3),
spectralRadius must be < 1"). Newton stops on the size of its increment (NewtonSettings.residualMode =
1, tolerance `newton_tol` in m and rad): the residual test (mode 0) has a round-off floor set by the
axial penalty EA/h that relative tolerances below 1e-8 cannot reach from 32 elements on.
Everything runs headless (no renderer is started), writes no files, prints nothing, uses one thread,
and is deterministic. PeerRun.solve_s is the wall time of SolveDynamic alone (the integration, with the
φ(t) user functions called back into Python at each Newton iteration), not of building the model.

What the penalty costs (measured with tests/python/peers/test_exudyn_peer.py's cases):
- EA too small: the beam stretches (error ∝ 1/EA).
- EA too large: membrane locking. The cubic axial field of an ANCF element cannot follow the
  quartic ½v'² of the inextensible beam; the rest is strain energy ∝ EA·h⁴·κ⁴, a spurious stiffening
  ∝ EA·h⁴·amplitude². With one element (h = l) it is visible already in the small turn
  φ_end = 0.003 (a 5e-5 relative difference from our 1-element model at EA = 1e8, 5e-4 at 1e9), and it
  ruins the paper's full turn (the one-element peer is no use there). With 16 elements it is ~1e-4 of
  the peak at EA = 1e8 in the full turn.
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

import numpy as np

from paper_example import DEFAULT_PARAMS as PAPER  # noqa: E402  (the paper's example, SI)


class PeerRun(NamedTuple):
    t: np.ndarray  # s
    v1: np.ndarray  # m, y of the tip
    theta1: np.ndarray  # rad, angle of the tip's tangent
    u2: np.ndarray  # m, x_tip − l (with the elastic stretch)
    M: np.ndarray  # N·m, moment of the body on the beam tip (the CLI's convention)
    solve_s: float = math.nan  # s, wall time of SolveDynamic alone (the integration; not the model's build)


def phi_law(t: float, phi_end: float, t_rot: float) -> tuple[float, float]:
    """φ(t) = φ_end·sin²(πt/(2 t_rot)) for t ≤ t_rot, then φ_end; and φ'(t)."""
    if t >= t_rot:
        return phi_end, 0.0
    if t <= 0.0:
        return 0.0, 0.0
    w = math.pi / (2.0 * t_rot)
    return phi_end * math.sin(w * t) ** 2, phi_end * w * math.sin(2.0 * w * t)


def static_stretch(params: dict | None = None, EA: float = 1e8) -> float:
    """Axial tip displacement of the straight beam in equilibrium under the body's weight, M2·g·l/EA (m)."""
    p = {**PAPER, **(params or {})}
    return p["M2"] * p["g"] * p["l"] / EA


def simulate(
    n_elements: int,
    params: dict | None = None,
    phi_end: float = math.pi,
    t_rot: float = 0.85,
    t_end: float = 10.2,
    dt: float = 2.5e-4,
    EA: float = 1e8,
    t_out=None,
    rho_inf: float = 0.9,
    newton_tol: float = 1e-12,
    hinge: str = "generic",
    consistent_start: bool | None = None,
) -> PeerRun:
    """Runs the EXUDYN model; returns PeerRun(t, v1, theta1, u2, M).

    n_elements ANCF elements of equal length; params overrides PAPER (keys l, EI, m, M2, J_C, r, g);
    the law φ(t) as in the paper with phi_end and t_rot; constant step dt up to t_end (t_end/dt must
    be an integer to 1e-9); EA the axial stiffness (penalty for inextensibility); rho_inf the
    generalized-α spectral radius (< 1); newton_tol the Newton increment tolerance. Rows at every step, or at the times t_out (those on the step grid
    are taken as computed, others are interpolated by a cubic spline through the steps).

    hinge: "generic" (ObjectJointGeneric with a Tait–Bryan offset, the default) or "revolute"
    (ObjectJointRevolute2D + MarkerBodiesRelativeRotationCoordinate + ObjectConnectorCoordinate with the
    φ(t) offset); see the module's docstring. consistent_start: start from the consistent initial
    accelerations (with φ''(0)) instead of EXUDYN's own (without it); None means True for "revolute" and
    False for "generic" (the generic joint's runs, and the figures of test_exudyn_peer.py, keep EXUDYN's
    own start).
    """
    import exudyn as exu
    from exudyn.itemInterface import (
        MarkerBodiesRelativeRotationCoordinate,
        MarkerBodyPosition,
        MarkerBodyRigid,
        MarkerNodeCoordinate,
        NodeGenericData,
        NodePoint2DSlope1,
        NodePointGround,
        NodeRigidBody2D,
        ObjectANCFCable2D,
        ObjectConnectorCoordinate,
        ObjectGround,
        ObjectJointGeneric,
        ObjectJointRevolute2D,
        ObjectRigidBody2D,
        LoadForceVector,
        SensorBody,
        SensorObject,
    )

    p = {**PAPER, **(params or {})}
    unknown = set(p) - set(PAPER)
    if unknown:
        raise ValueError(f"unknown parameters {sorted(unknown)}")
    if not 0.0 <= rho_inf < 1.0:
        raise ValueError("rho_inf must be in [0, 1) for index-3 constraints")
    if hinge not in ("generic", "revolute"):
        raise ValueError(f"hinge must be 'generic' or 'revolute', not {hinge!r}")
    if consistent_start is None:
        consistent_start = hinge == "revolute"
    if consistent_start and hinge != "revolute":
        raise ValueError("consistent_start needs hinge='revolute' (the drive as one coordinate constraint)")
    n = int(n_elements)
    if n < 1:
        raise ValueError("n_elements must be >= 1")
    steps = round(t_end / dt)
    if steps < 1 or abs(steps * dt - t_end) > 1e-9 * max(1.0, t_end):
        raise ValueError(f"t_end = {t_end} is not a whole number of steps dt = {dt}")
    l, EI, m, M2, J_C, r, g = (float(p[k]) for k in ("l", "EI", "m", "M2", "J_C", "r", "g"))
    Le = l / n
    eps0 = M2 * g / EA  # uniform static strain under the body's weight

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    mbs.AddObject(ObjectGround())
    n_ground = mbs.AddNode(NodePointGround())

    # beam (ObjectANCFCable2D.rst; node coordinates NodePoint2DSlope1.rst: [x, y, x', y'])
    nodes = [
        mbs.AddNode(
            NodePoint2DSlope1(
                referenceCoordinates=[i * Le, 0.0, 1.0, 0.0],
                initialCoordinates=[i * Le * eps0, 0.0, eps0, 0.0],
            )
        )
        for i in range(n + 1)
    ]
    elements = [
        mbs.AddObject(
            ObjectANCFCable2D(
                nodeNumbers=[nodes[i], nodes[i + 1]],
                length=Le,
                massPerLength=m,
                bendingStiffness=EI,
                axialStiffness=EA,
                visualization={"show": False, "drawHeight": 0.0, "color": [-1.0, -1.0, -1.0, -1.0]},
            )
        )
        for i in range(n)
    ]
    # clamp: x, y and y' of the first node held at zero (ObjectConnectorCoordinate.rst: it constrains
    # the coordinates themselves, not reference + coordinate; the reference is [0, 0, 1, 0])
    m_ground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n_ground, coordinate=0))
    for c in (0, 1, 3):
        m_c = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[m_ground, m_c]))

    # body (NodeRigidBody2D: [x, y, angle]; ObjectRigidBody2D: inertia about C)
    n_body = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[l + r, 0.0, 0.0], initialCoordinates=[l * eps0, 0.0, 0.0]))
    o_body = mbs.AddObject(ObjectRigidBody2D(mass=M2, inertia=J_C, nodeNumber=n_body))

    def offset_phi(t: float) -> float:
        return phi_law(t, phi_end, t_rot)[0]

    def offset_dphi(t: float) -> float:
        return phi_law(t, phi_end, t_rot)[1]

    hidden = {"show": False, "drawSize": -1.0, "color": [-1.0, -1.0, -1.0, -1.0]}
    if hinge == "generic":
        # driven hinge (ObjectJointGeneric.rst, offsetUserFunction(mbs, t, itemNumber, parameters))
        m_tip = mbs.AddMarker(MarkerBodyRigid(bodyNumber=elements[-1], localPosition=[Le, 0.0, 0.0]))
        m_hinge = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o_body, localPosition=[-r, 0.0, 0.0]))

        def offset(mbs_, t, item, par):
            return [0.0, 0.0, 0.0, 0.0, 0.0, offset_phi(t)]

        def offset_t(mbs_, t, item, par):
            return [0.0, 0.0, 0.0, 0.0, 0.0, offset_dphi(t)]

        o_joint = mbs.AddObject(
            ObjectJointGeneric(
                markerNumbers=[m_tip, m_hinge],
                constrainedAxes=[1, 1, 0, 0, 0, 1],
                offsetUserFunction=offset,
                offsetUserFunction_t=offset_t,
                visualization={"show": False, "axesRadius": 0.1, "axesLength": 0.4, "color": [-1.0, -1.0, -1.0, -1.0]},
            )
        )
        o_drive = None
    else:
        # the hinge: ObjectJointRevolute2D between two position markers (ObjectJointRevolute2D.rst)
        m_tip = mbs.AddMarker(MarkerBodyPosition(bodyNumber=elements[-1], localPosition=[Le, 0.0, 0.0]))
        m_hinge = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o_body, localPosition=[-r, 0.0, 0.0]))
        o_joint = mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[m_tip, m_hinge], visualization=hidden))
        # the drive: the body's rotation relative to the tip section about z
        # (MarkerBodiesRelativeRotationCoordinate.rst; a NodeGenericData keeps the angle continuous through
        # ±π, which φ_end = π reaches), held at φ(t) by a coordinate constraint against ground
        # (ObjectConnectorCoordinate.rst: factor1·value1 − value0 = offsetUserFunction(mbs, t, item, offset))
        n_angle = mbs.AddNode(NodeGenericData(initialCoordinates=[0.0], numberOfDataCoordinates=1))
        m_rel = mbs.AddMarker(
            MarkerBodiesRelativeRotationCoordinate(
                bodyNumbers=[elements[-1], o_body],
                nodeNumber=n_angle,
                localPosition0=[Le, 0.0, 0.0],
                localPosition1=[-r, 0.0, 0.0],
                axis0=[0.0, 0.0, 1.0],
                visualization={"show": False},
            )
        )
        o_drive = mbs.AddObject(
            ObjectConnectorCoordinate(
                markerNumbers=[m_ground, m_rel],
                offsetUserFunction=lambda mbs_, t, item, off: offset_phi(t),
                offsetUserFunction_t=lambda mbs_, t, item, off: offset_dphi(t),
                visualization=hidden,
            )
        )

    # gravity on the body only
    m_c = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o_body, localPosition=[0.0, 0.0, 0.0]))
    mbs.AddLoad(LoadForceVector(markerNumber=m_c, loadVector=[M2 * g, 0.0, 0.0]))

    # sensors, kept in memory only (SensorBody.rst / SensorObject.rst: storeInternal, writeToFile)
    OVT = exu.OutputVariableType
    keep = {"writeToFile": False, "storeInternal": True}
    s_pos = mbs.AddSensor(SensorBody(bodyNumber=elements[-1], localPosition=[Le, 0.0, 0.0], outputVariableType=OVT.Position, **keep))
    s_rot = mbs.AddSensor(SensorBody(bodyNumber=elements[-1], localPosition=[Le, 0.0, 0.0], outputVariableType=OVT.Rotation, **keep))
    if o_drive is None:
        s_torque = mbs.AddSensor(SensorObject(objectNumber=o_joint, outputVariableType=OVT.TorqueLocal, **keep))
    else:
        s_torque = mbs.AddSensor(SensorObject(objectNumber=o_drive, outputVariableType=OVT.Force, **keep))

    mbs.Assemble()

    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime = steps * dt
    ti.numberOfSteps = steps
    ti.verboseMode = 0
    ti.adaptiveStep = False  # a constant step: no step reduction on a Newton failure (it then fails)
    ti.stepInformation = 0
    ti.generalizedAlpha.spectralRadius = rho_inf
    ti.newton.residualMode = 1
    ti.newton.relativeTolerance = newton_tol
    ti.newton.absoluteTolerance = newton_tol
    s.solution.file.write = False
    s.solution.sensors.writePeriod = 0.5 * dt  # below dt: a row at every step
    s.parallel.numberOfThreads = 1
    s.show.computationTime = False
    s.show.statistics = False
    s.linearSolver.solverType = exu.LinearSolverType.EXUdense  # 4n + 7 unknowns: small

    if consistent_start:
        ti.generalizedAlpha.computeInitialAccelerations = False
        ti.generalizedAlpha.resetAccelerations = False  # take the initial accelerations set below
        mbs.systemData.SetODE2Coordinates_tt(
            _consistent_accelerations(
                exu,
                mbs,
                s,
                mbs.GetNodeODE2Index(n_body) + 2,
                mbs.systemData.GetObjectLTGAE(o_drive),
                _phi_dd0(phi_end, t_rot),
            ),
            configuration=exu.ConfigurationType.Initial,
        )

    t_solve = time.perf_counter()
    try:
        ok = mbs.SolveDynamic(s, showHints=False, showCausingItems=False)
    except exu.SolverError as e:  # printed a banner to stdout too
        raise RuntimeError(f"EXUDYN's SolveDynamic failed (n_elements={n}, dt={dt}, EA={EA}): {e}") from e
    if not ok:
        raise RuntimeError(f"EXUDYN's SolveDynamic failed (n_elements={n}, dt={dt}, EA={EA})")
    solve_s = time.perf_counter() - t_solve

    pos = np.asarray(mbs.GetSensorStoredData(s_pos))
    rot = np.asarray(mbs.GetSensorStoredData(s_rot))
    trq = np.asarray(mbs.GetSensorStoredData(s_torque))
    t = pos[:, 0]
    if len(t) != steps + 1 or np.max(np.abs(t - dt * np.arange(steps + 1))) > 1e-9 * max(1.0, t_end):
        raise RuntimeError(f"EXUDYN's sensors stored {len(t)} rows, expected one per step ({steps + 1})")
    cols = {
        "v1": pos[:, 2],
        "theta1": rot[:, 1],
        "u2": pos[:, 1] - l,
        # generic: the joint's torque on marker 0 (the tip), negated; revolute: the drive's multiplier λ
        # (its constraint is θ_body − θ_tip − φ = 0, so the drive's torque on the body is −λ = −M)
        "M": -trq[:, 3] if o_drive is None else trq[:, 1],
    }
    if t_out is None:
        return PeerRun(t=t, **cols, solve_s=solve_s)

    t_out = np.asarray(t_out, dtype=float)
    if t_out.min() < -1e-12 or t_out.max() > t[-1] + 1e-9:
        raise ValueError("t_out outside [0, t_end]")
    k = np.rint(t_out / dt).astype(int)
    on_grid = np.abs(k * dt - t_out) <= 1e-9 * max(1.0, t_end)
    if on_grid.all():
        return PeerRun(t=t_out, **{c: v[k] for c, v in cols.items()}, solve_s=solve_s)
    from scipy.interpolate import CubicSpline

    return PeerRun(t=t_out, **{c: CubicSpline(t, v)(t_out) for c, v in cols.items()}, solve_s=solve_s)


def _phi_dd0(phi_end: float, t_rot: float) -> float:
    """φ''(0+) of the sin² law: φ_end·π²/(2 t_rot²)."""
    return phi_end * math.pi**2 / (2.0 * t_rot**2)


def _consistent_accelerations(exu, mbs, settings, i_body_angle: int, drive_rows, phi_dd0: float) -> np.ndarray:
    """The initial accelerations that satisfy the drive's constraint twice differentiated in time.

    EXUDYN's own initial accelerations (computeInitialAccelerations) solve
    [M Gᵀ; G 0]·[a0; λ0] = [f; −∂²g/∂t² − …], but the −∂²g/∂t² of a constraint's offset user function is
    left out (measured: its a0 is exactly zero here, at rest in equilibrium, although φ''(0) ≠ 0). Its a0
    is taken from its solver's initialisation and corrected by Δa from [M Gᵀ; G 0]·[Δa; Δλ] = [0; γ],
    γ = φ''(0) on the drive's row (times the row's coefficient of the body's angle, which sets the
    constraint's sign) and 0 on the others (their ∂²g/∂t² is zero and all velocities are zero at t = 0).
    M and G are EXUDYN's own (its solver's ComputeMassMatrix and ComputeJacobianAE at t = 0); the drive's
    row is its one algebraic coordinate (drive_rows, from the system's LTG list)."""
    solver = exu.MainSolverImplicitSecondOrder()
    settings.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    try:
        solver.InitializeSolver(mbs, settings)
        n2, nae = solver.GetODE2size(), solver.GetAEsize()
        if solver.GetODE1size() != 0:
            raise RuntimeError("unexpected ODE1 coordinates")
        a_exu = np.array(mbs.systemData.GetODE2Coordinates_tt(), dtype=float)
        solver.ComputeMassMatrix(mbs)
        mass = np.array(solver.GetSystemMassMatrix(), dtype=float)
        solver.SetSystemJacobian(np.zeros((n2 + nae, n2 + nae)))
        solver.ComputeJacobianAE(mbs, 1.0, 0.0, 1.0)
        jac = np.array(solver.GetSystemJacobian(), dtype=float)
        solver.FinalizeSolver(mbs, settings)
    finally:
        settings.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
    G = jac[n2:, :n2]
    if len(drive_rows) != 1:
        raise RuntimeError(f"the drive has {len(drive_rows)} algebraic coordinates, expected 1")
    row = int(drive_rows[0])
    sign = G[row, i_body_angle]
    if abs(abs(sign) - 1.0) > 1e-12:
        raise RuntimeError(f"the drive's row has {sign} at the body's angle, expected ±1")
    gamma = np.zeros(nae)
    gamma[row] = sign * phi_dd0
    kkt = np.block([[mass, G.T], [G, np.zeros((nae, nae))]])
    da = np.linalg.solve(kkt, np.concatenate([np.zeros(n2), gamma]))[:n2]
    return a_exu + da
