"""Spatial loops closed by MSL's assemblies, each with its reference written apart from
kinetwork (``scenes.multiplier``: the bodies' positions and orientations in two coordinates,
the loop's length constraint with a Lagrange multiplier, DOP853).

The mechanism: a crank turning about z at the world origin (its body, its tip 0.2 along its
x axis), and the assembly from the crank's tip (frame_a) to a base frame turned 0.3 rad
about x at B = (0.8, 0.5, 0.2) (frame_b), its last joint a revolute about ``N_B`` or a
prismatic along it. Bodies with mass and inertia ride on the assembly's inner frames (the
rod 1 frame of a universal joint, frame_ib) or, for the spherical-spherical rods, a point
mass in rod 1's middle; a damper on the assembly's axis. The geometry is chosen so that the
loop is assembled at the crank angle THETA0 with the last joint at END0 (an angle or a
distance), frame_ia then parallel to frame_a.
"""

import math

import numpy as np
import sympy as sp

import kinetwork as kn
from scenes.multiplier import Mechanism, rot, unit

mb = kn.multibody
TIP = 0.2
B = (0.8, 0.5, 0.2)
BASE_TILT = 0.3                      # the base frame: turned about x
N_B = (0.2, 0.1, 1.0)                # axis of the last joint, in frame_b
N1_A = (0.0, 0.3, 1.0)               # axis 1 of a universal joint, in frame_a
#: frame_ib to the spherical joint, in frame_ib; where the loop is assembled. The crank can
#: turn all the way round: its discriminant stays above 0.7 (revolute) and 0.3 (prismatic)
#: of its scale, far from the singular positions
R_ROD2 = {"revolute": (0.5, 0.1, 0.0), "prismatic": (-0.5, 0.1, 0.0)}
THETA0, END0 = 0.4, {"revolute": 1.5, "prismatic": 0.8}
OFFSET = {"revolute": 0.2, "prismatic": -0.1}
CRANK = (1.5, (0.15, 0, 0), (0.002, 0.01, 0.012))          # mass, centre, inertia
COUPLER = (0.8, (0.001, 0.02, 0.02))                        # mass, inertia (centre: mid-rod)
END_BODY = (1.2, (0.003, 0.004, 0.005))                     # on frame_ib, centre mid-rod 2
DAMPING = 0.5


def _tilt():
    c, s = math.cos(BASE_TILT), math.sin(BASE_TILT)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _end_frame(kind, value):
    """frame_ib's orientation in frame_b and origin in frame_b at the end joint's value."""
    n = np.array(N_B) / np.linalg.norm(N_B)
    if kind == "revolute":
        K = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
        return np.eye(3) + math.sin(value) * K + (1 - math.cos(value)) * K @ K, np.zeros(3)
    return np.eye(3), n * value


def rod1_ia(kind):
    """Rod 1 from the crank's tip to the spherical joint where the loop is assembled, in
    frame_a (= frame_ia there)."""
    R, p = _end_frame(kind, END0[kind])
    S = np.array(B) + _tilt() @ (p + R @ np.array(R_ROD2[kind]))
    c, s = math.cos(THETA0), math.sin(THETA0)
    Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    return Rz.T @ (S - Rz @ np.array([TIP, 0, 0]))


def build(assembly, guess=None):
    """The kinetwork model with ``assembly`` ("JointUSR", "JointSSR", "JointUSP",
    "JointSSP"), MSL's parameters as MSL names them; probes on the crank, the assembly's axis
    and frames. ``guess``: phi_guess (s_guess), by default the axis where the loop is
    assembled (END0 less the offset)."""
    kind = "revolute" if assembly.endswith("R") else "prismatic"
    universal = assembly.startswith("JointU")
    rod = rod1_ia(kind).tolist()
    m = kn.Model(assembly.lower())
    m.add(mb.Ground("world"))
    m.add(mb.Revolute("crank", axis=[0, 0, 1], q0=THETA0, qd0=1.5))
    mass, centre, inertia = CRANK
    m.add(mb.RigidBody("crank_body", mass=mass, r_cm=list(centre), inertia=list(inertia)))
    m.add(mb.FixedTranslation("tip", r=[TIP, 0, 0]))
    m.add(mb.FixedRotation("base", r=list(B), axis=[1, 0, 0], angle=BASE_TILT))
    offset = OFFSET[kind]
    guess = END0[kind] - offset if guess is None else guess
    params = {"n_b": list(N_B), "rRod2_ib": list(R_ROD2[kind])}
    if kind == "revolute":
        params.update(phi_offset=offset, phi_guess=guess)
    else:
        params.update(s_offset=offset, s_guess=guess)
    if universal:
        params.update(n1_a=list(N1_A), rRod1_ia=rod)
    else:
        params.update(rod1Length=float(np.linalg.norm(rod)), rod1Mass=COUPLER[0])
    m.add(getattr(mb, assembly)("loop", **params))
    m.add(mb.RigidBody("end_body", mass=END_BODY[0], r_cm=[v / 2 for v in R_ROD2[kind]],
                       inertia=list(END_BODY[1])))
    damper = kn.rotational.Damper if kind == "revolute" else kn.translational.Damper
    m.add(damper("damper", d=DAMPING))
    wires = [("world.frame", "crank.frame_a"), ("crank.frame_b", "crank_body.frame_a"),
             ("crank.frame_b", "tip.frame_a"), ("tip.frame_b", "loop.frame_a"),
             ("world.frame", "base.frame_a"), ("base.frame_b", "loop.frame_b"),
             ("loop.frame_ib", "end_body.frame_a"), ("damper.flange_a", "loop.bearing"),
             ("damper.flange_b", "loop.axis")]
    if universal:
        m.add(mb.RigidBody("coupler", mass=COUPLER[0], r_cm=[v / 2 for v in rod],
                           inertia=list(COUPLER[1])))
        wires.append(("loop.frame_ia", "coupler.frame_a"))
    for probe, port, what in [("crank_p", "crank.axis", ["angle", "speed"]),
                              ("end_p", "loop.axis", None), ("middle", "loop.frame_im", None),
                              ("reaction", "tip.frame_b", ["force", "torque"])]:
        m.add(kn.Probe(probe, quantities=what))
        wires.append((f"{probe}.port", port))
    for a, b in wires:
        m.connect(a, b)
    return m


def closing_angles(kind="revolute"):
    """The end joint's angles (or distances) at which rod 1 reaches the crank's tip at THETA0,
    found apart from kinetwork: sign changes of |S(x) - A| - length on a grid, refined."""
    from scipy.optimize import brentq
    A = TIP * np.array([math.cos(THETA0), math.sin(THETA0), 0.0])
    length = np.linalg.norm(rod1_ia(kind))

    def gap(x):
        R, p = _end_frame(kind, x)
        return np.linalg.norm(np.array(B) + _tilt() @ (p + R @ np.array(R_ROD2[kind])) - A) \
            - length
    xs = np.linspace(-math.pi, math.pi, 721)
    g = [gap(x) for x in xs]
    return [brentq(gap, a, b, xtol=1e-14) for a, b, ga, gb in zip(xs, xs[1:], g, g[1:])
            if ga * gb < 0]


def reference(assembly, t):
    """(theta, end, middle): the crank angle, the end joint's coordinate (axis: angle or
    distance less the offset) and the spherical joint's world position at ``t``, from the
    multiplier equations; also the constraint's largest drift."""
    kind = "revolute" if assembly.endswith("R") else "prismatic"
    universal = assembly.startswith("JointU")
    th, x = sp.symbols("theta x")
    rod = sp.Matrix(rod1_ia(kind).tolist())
    Rz = rot((0, 0, 1), th)
    A = Rz * sp.Matrix([TIP, 0, 0])
    Rb = sp.Matrix(_tilt().tolist())
    n = sp.Matrix(N_B) / sp.sqrt(sum(v**2 for v in N_B))
    R_ib = Rb * rot(N_B, x) if kind == "revolute" else Rb
    o_ib = sp.Matrix(B) + (sp.zeros(3, 1) if kind == "revolute" else Rb * n * x)
    S = o_ib + R_ib * sp.Matrix(R_ROD2[kind])
    mass, centre, inertia = CRANK
    bodies = [(mass, sp.diag(*inertia), Rz, Rz * sp.Matrix(centre)),
              (END_BODY[0], sp.diag(*END_BODY[1]), R_ib,
               o_ib + R_ib * sp.Matrix(R_ROD2[kind]) / 2)]
    if universal:
        # MSL's universal joint: rod 1's frame maps (rod, axis 2, their normal) in frame_ia
        # onto the same in frame_a, axis 2 normal to axis 1 and to the rod
        # e is the rod's direction: (S - A) / |rod|, whose length the constraint keeps (the
        # constrained motion depends only on the kinetic energy on the constraint, and this
        # keeps sympy's derivatives small)
        n1 = sp.Matrix(N1_A)
        e = Rz.T * (S - A) / sp.sqrt(rod.dot(rod))
        e2 = unit(n1.cross(e))
        e_ia = unit(rod)
        e2_ia = unit(n1.cross(e_ia))
        R_ia = Rz * sp.Matrix.hstack(e, e2, e.cross(e2)) * \
            sp.Matrix.hstack(e_ia, e2_ia, e_ia.cross(e2_ia)).T
        bodies.append((COUPLER[0], sp.diag(*COUPLER[1]), R_ia, A + R_ia * rod / 2))
    else:
        bodies.append((COUPLER[0], sp.zeros(3, 3), sp.eye(3), (A + S) / 2))
    xd = sp.Symbol("qd1")                # the speed symbol Mechanism names for x
    mech = Mechanism([th, x], bodies, [(S - A).dot(S - A) - rod.dot(rod)],
                     forces=[0, -DAMPING * xd])
    q0, qd0 = mech.start([THETA0, END0[kind] + 1e-3], [1], [1.5, 0.0], [1])
    assert abs(q0[1] - END0[kind]) < 1e-9
    Q, _ = mech.solve(q0, qd0, t)
    f_S = sp.lambdify([th, x], S, "numpy")
    middle = np.array([np.array(f_S(*q), dtype=float).ravel() for q in Q])
    return Q[:, 0], Q[:, 1] - OFFSET[kind], middle, mech.drift(Q)
