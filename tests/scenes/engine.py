"""Modelica's V6 engine (``Modelica.Mechanics.MultiBody.Examples.Loops.EngineV6``) as a flat
kinetwork model: six slider-crank cylinders in a 60-degree V on one crankshaft, 1 degree of
freedom, six planar kinematic loops.

``python tests/scenes/engine.py [out.json]`` builds it and prints what it costs (compile and
simulate times, states, file size).

Where the numbers come from (Modelica Standard Library, read from
``modelica/ModelicaStandardLibrary``)
-----------------------------------------------------------------------------------------
* ``Modelica/Mechanics/MultiBody/Examples/Loops/EngineV6.mo`` (MSL 3.2.x, the version with
  ``Joints.Revolute bearing(useAxisFlange=true, n={1,0,0})``): the world (gravity 9.81 along
  -y, MSL's default), the main ``bearing`` about x, six ``Utilities.Cylinder`` instances with

      cylinder            1    2    3    4    5    6
      crankAngleOffset  -30   90  210  210   90  -30   [deg]
      cylinderInclination -30  30  -30   30  -30   30   [deg]

  chained crank_b -> crank_a and cylinder_b -> cylinder_a, cylinder 1 on the world; the
  ``load`` inertia J = 1 kg m^2 on the bearing's axis through a ``torqueSensor``, with
  phi(start = 0, fixed) and w(start = 10 rad/s, fixed); ``load2``, a
  QuadraticSpeedDependentTorque(tau_nominal = -100 N m, w_nominal = 200 rad/s); and
  ``filter``, a CriticalDamping(n = 2, f = 5 Hz) of the sensed engine torque. (Older
  releases, ``Mechanics/MultiBody/Examples/Loops/EngineV6.mo`` of MSL 2.x, use other crank
  offsets, -30/90/-150/-90/300/150 deg, and no load2; we follow 3.2.x.)
* ``Modelica/Mechanics/MultiBody/Examples/Loops/Utilities/Cylinder.mo``: the parameters
  (cylinderTopPosition = 0.42, pistonLength = 0.1, rodLength = 0.2, crankLength = 0.2,
  crankPinOffset = 0.1, crankPinLength = 0.1, all in m; cylinderLength =
  cylinderTopPosition - (pistonLength + rodLength - crankPinOffset) = 0.22 m) and the parts:

      piston         BodyCylinder(diameter = 0.1, r = {0, pistonLength, 0})
      connectingRod  BodyBox(r = {0, rodLength, 0}, r_shape = {0, -0.02, 0},
                             widthDirection = {1,0,0}, width = 0.02, height = 0.06)
      crank1         BodyCylinder(r = {crankLength - crankPinLength, 0, 0},
                                  r_shape = {-0.01,0,0}, length = 0.12, diameter = 0.05)
      crank2         BodyBox(r = {0, crankPinOffset, 0}, widthDirection = {1,0,0},
                             width = 0.02, height = 0.05)
      crank3         BodyCylinder(r = {crankPinLength, 0, 0}, r_shape = {-0.01,0,0},
                                  length = 0.12, diameter = 0.03)
      crank4         BodyBox(r = {0, -crankPinOffset, 0}, widthDirection = {1,0,0},
                             width = 0.02, height = 0.05)
      b1             RevolutePlanarLoopConstraint(n = {1,0,0}), after mid = FixedTranslation(
                     r = {crankPinLength/2, 0, 0}) from crank2.frame_b, to the rod
      b2             Revolute(n = {1,0,0}) between piston.frame_a and the rod's frame_b
      cylinder       Prismatic(n = {0,-1,0}, s(start = -0.3)) from cylinderTop to the piston
      cylinderTop    FixedTranslation(r = {0, cylinderTopPosition, 0})
      inclination    FixedRotation(r = {crankLength - crankPinLength/2, 0, 0}, rotated about x
                     by cylinderInclination), from cylinder_a
      mounting       FixedTranslation(r = {crankLength, 0, 0}), cylinder_a -> cylinder_b
      crankAngle1/2  FixedRotation about x by +/- crankAngleOffset around the crank parts
      gasForce       GasForce2(L = cylinderLength, d = 0.1) between the prismatic's support
                     and axis

* ``Modelica/Mechanics/MultiBody/Parts/BodyBox.mo`` and ``BodyCylinder.mo``: density 7700
  kg/m^3 by default; a box has m = rho L w h, its centre of mass at r_shape + L/2 along
  lengthDirection = unit(r - r_shape) (L = |r - r_shape| unless given), and principal moments
  m (w^2 + h^2)/12, m (L^2 + h^2)/12, m (L^2 + w^2)/12 about its length, width and height
  axes (Frames.from_nxy(r, widthDirection)); a cylinder has m = rho pi L d^2/4, the same
  centre, m d^2/8 about its axis and m (L^2 + 3 d^2/4)/12 across it. ``box`` and
  ``cylinder`` below compute exactly that; ``part_table()`` prints the resulting numbers.
* ``Modelica/Mechanics/MultiBody/Examples/Loops/Utilities/GasForce2.mo``: the pressure (bar)
  as a polynomial in x = 1 - s_rel/L, one for compression (v_rel < 0) and one for expansion,
  each with a second polynomial near the top (x > 0.986061, resp. x > 0.933); the force
  pushing the piston down the cylinder is p pi d^2/4. See ``gas_pressure``. With this
  geometry the piston's top stays 0.02 m below the cylinder top (s_rel in [0.02, 0.22],
  x <= 0.909), so only the two low-x polynomials are ever used.

What differs from MSL, and why
------------------------------
* Bodies: kinetwork has no BodyBox / BodyCylinder yet, so each part is a FixedTranslation
  (``<prefix>_<part>``, the part's frame_a -> frame_b) and a RigidBody on its frame_a
  (``<prefix>_<part>_body``) with the mass, centre and inertia computed as MSL does.
* Loop joints: MSL cuts each loop at b1 with a RevolutePlanarLoopConstraint (a revolute that
  closes only the 3 in-plane constraints of a planar loop). Here b1 is an ordinary Revolute
  marked ``cut=True``; kinetwork's closure of a cut revolute has 12 rows, and the pivoted QR
  of its ``partition`` formulation drops the out-of-plane ones as redundant at the initial
  configuration (9 of 12 per cylinder), which is what RevolutePlanarLoopConstraint does by
  hand. Nothing else had to change: no Spherical / Universal substitute was needed.
* Gas force: GasForce2 is one translational Force between the prismatic's support and axis
  whose law is MSL's own, written as one expression (``gas_force_law``) in a PositionSensor's
  and a SpeedSensor's outputs on the prismatic's axis: the pressure polynomials in
  x = 1 - s/L, compression when v < 0, and the force p pi d^2/4 pushing the piston down the
  cylinder, as ``models/engine1b.json`` writes Engine1b's. MSL switches at v = 0 with an
  event; here the switch is in the expression (``if_else``), without one: v = 0 is a dead
  centre, where the force has no lever on the crank, so the torque it drives stays
  continuous. (It was a piecewise-linear Table of each polynomial, 81 rows, blended by a
  third over v: the Tables' 160 kinks per stroke and cylinder cost CVODES 7x more steps,
  1.3 million for the 5 s default run, and each kink's search 2.5x more operations per
  evaluation; the blend cost nothing measurable.) MSL's asserts 0 <= s_rel <= L are not
  reproduced.
* The filter's initType = SteadyState (filter states start at the initial engine torque) is
  not available: the two FirstOrder stages start at 0, so ``filteredEngineTorque`` has a
  start transient of ~0.1 s that MSL's has not. It is an output only; ``filter=False``
  leaves it out.
* Initial values: the bearing carries MSL's load start values (q0 = 0, qd0 = 10 rad/s); the
  loop joints' starts are guesses computed from the closed-form slider-crank closure (MSL's
  Prismatic s(start = -0.3) is only a guess too), solved exactly by kinetwork.

Structure
---------
``add_cylinder(model, prefix, crank_frame, cylinder_frame, **params)`` adds one cylinder,
all its components named ``<prefix>_<name>``, and returns ``CylinderPorts(crank_b,
cylinder_b)``: where the next cylinder continues. Everything of a cylinder is created and
wired inside that function, and its outside is exactly four frames (``CYLINDER_PORTS``:
crank_a / crank_b on the crankshaft, cylinder_a / cylinder_b on the engine block, as MSL's
Utilities.Cylinder), so the function's content can become a subsystem definition as it is.
"""

import math
import pathlib
import sys
from typing import NamedTuple

import numpy as np

import kinetwork as kn

mb, rot, tr, sig = kn.multibody, kn.rotational, kn.translational, kn.signals

#: MSL's Utilities.Cylinder parameters (Cylinder.mo), lengths in m, angles in rad
CYLINDER = {
    "cylinderTopPosition": 0.42,
    "pistonLength": 0.1,
    "rodLength": 0.2,
    "crankLength": 0.2,
    "crankPinOffset": 0.1,
    "crankPinLength": 0.1,
    "cylinderInclination": 0.0,
    "crankAngleOffset": 0.0,
}
#: EngineV6.mo (MSL 3.2.x): (crankAngleOffset, cylinderInclination) per cylinder, in degrees
V6_CYLINDERS = [(-30.0, -30.0), (90.0, 30.0), (210.0, -30.0),
                (210.0, 30.0), (90.0, -30.0), (-30.0, 30.0)]
#: EngineV6.mo: load inertia and its start values, load2 (quadratic speed-dependent torque),
#: the engine-torque filter (CriticalDamping, n = 2)
ENGINE = {"J_load": 1.0, "phi0": 0.0, "w0": 10.0,
          "tau_nominal": -100.0, "w_nominal": 200.0, "filter_f": 5.0, "filter_n": 2}
#: EngineV6.mo's experiment (StopTime = 1.01 s: the engine from 10 to about 560 rad/s, 55
#: revolutions), outputs every millisecond. Each revolution costs about 390 steps at rtol
#: 1e-6 (six gas-force peaks, each over 1.4 % of the stroke), so a run's cost grows with the
#: revolutions: 5 s (470 revolutions) took 7x the CPU of these 1.01 s.
EXPERIMENT = {"t_end": 1.01, "n_points": 1011, "method": "auto", "rtol": 1e-6, "atol": 1e-8}
#: MultiBody's defaults: BodyBox / BodyCylinder density [kg/m^3], World gravity [m/s^2]
DENSITY = 7700.0
GRAVITY = [0.0, -9.81, 0.0]
#: GasForce2(d = 0.1) in Cylinder.mo: cylinder bore [m]
BORE = 0.1

#: the external frames of one cylinder (the future subsystem's ports) -> internal ports
CYLINDER_PORTS = {"crank_a": "crankAngle1.frame_a", "crank_b": "crankAngle2.frame_b",
                  "cylinder_a": "mounting.frame_a", "cylinder_b": "mounting.frame_b"}


class CylinderPorts(NamedTuple):
    """Where the next cylinder continues: its crank_a and its cylinder_a attach here."""
    crank_b: str
    cylinder_b: str


# ---------------------------------------------------------------------------------------
# Mass properties, as MSL's Parts.BodyBox and Parts.BodyCylinder compute them
# ---------------------------------------------------------------------------------------

def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def from_nxy(n_x, n_y):
    """Rows e_x, e_y, e_z of MSL's Frames.from_nxy(n_x, n_y) (the fallback for a parallel
    n_y included)."""
    e_x = _unit(n_x)
    n_y = np.asarray(n_y, dtype=float)
    if np.dot(np.cross(e_x, n_y), np.cross(e_x, n_y)) <= 1e-6:
        n_y = np.array([0.0, 1.0, 0.0]) if abs(e_x[0]) > 1e-6 else np.array([1.0, 0.0, 0.0])
    e_z = _unit(np.cross(e_x, n_y))
    return np.array([e_x, np.cross(e_z, e_x), e_z])


def box(r, width, height, r_shape=(0.0, 0.0, 0.0), width_direction=(0.0, 1.0, 0.0),
        length=None, density=DENSITY):
    """(mass, r_cm, inertia about the centre in frame_a axes) of MSL's BodyBox."""
    r, r_shape = np.asarray(r, float), np.asarray(r_shape, float)
    length = float(np.linalg.norm(r - r_shape)) if length is None else length
    m = density * length * width * height
    r_cm = r_shape + _unit(r - r_shape) * length / 2
    R = from_nxy(r, width_direction)
    D = np.diag([width ** 2 + height ** 2, length ** 2 + height ** 2,
                 length ** 2 + width ** 2]) * m / 12
    return m, r_cm, R.T @ D @ R                      # Frames.resolveDyade1(R, D)


def cylinder(r, diameter, r_shape=(0.0, 0.0, 0.0), length=None, density=DENSITY):
    """(mass, r_cm, inertia about the centre in frame_a axes) of MSL's BodyCylinder."""
    r, r_shape = np.asarray(r, float), np.asarray(r_shape, float)
    length = float(np.linalg.norm(r - r_shape)) if length is None else length
    radius = diameter / 2
    m = density * math.pi * length * radius ** 2
    r_cm = r_shape + _unit(r - r_shape) * length / 2
    I22 = m * (length ** 2 + 3 * radius ** 2) / 12
    R = from_nxy(r, [0.0, 1.0, 0.0])
    return m, r_cm, R.T @ np.diag([m * radius ** 2 / 2, I22, I22]) @ R


def cylinder_parts(rod_shape_offset=0.02, **params):
    """{part: (r, (mass, r_cm, inertia))} of one cylinder, as in Cylinder.mo: ``r`` from the
    part's frame_a to its frame_b. ``rod_shape_offset`` is the connecting rod's
    r_shape = {0, -0.02, 0} (0 puts its centre of mass at mid-length)."""
    p = {**CYLINDER, **params}
    L_crank, L_pin, off_pin = p["crankLength"], p["crankPinLength"], p["crankPinOffset"]
    parts = {
        "crank1": ([L_crank - L_pin, 0, 0], lambda r: cylinder(
            r, diameter=0.05, r_shape=[-0.01, 0, 0], length=0.12)),
        "crank2": ([0, off_pin, 0], lambda r: box(
            r, width=0.02, height=0.05, width_direction=[1, 0, 0])),
        "crank3": ([L_pin, 0, 0], lambda r: cylinder(
            r, diameter=0.03, r_shape=[-0.01, 0, 0], length=0.12)),
        "crank4": ([0, -off_pin, 0], lambda r: box(
            r, width=0.02, height=0.05, width_direction=[1, 0, 0])),
        "connectingRod": ([0, p["rodLength"], 0], lambda r: box(
            r, width=0.02, height=0.06, r_shape=[0, -rod_shape_offset, 0],
            width_direction=[1, 0, 0])),
        "piston": ([0, p["pistonLength"], 0], lambda r: cylinder(r, diameter=BORE)),
    }
    return {name: ([float(v) for v in r], props(np.asarray(r, float)))
            for name, (r, props) in parts.items()}


def part_table():
    """The mass properties of one cylinder's parts as text (for the docs and the report)."""
    lines = []
    for name, (r, (m, r_cm, I)) in cylinder_parts().items():
        lines.append(f"{name:14s} m = {m:.6f} kg  r_cm = {np.round(r_cm, 6).tolist()}  "
                     f"I_diag = {[float(f'{v:.6e}') for v in np.diag(I)]}")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------
# GasForce2
# ---------------------------------------------------------------------------------------

def gas_pressure(x, compression):
    """GasForce2's cylinder pressure [Pa] at normalised position x = 1 - s_rel/L
    (compression: v_rel < 0, else expansion), exactly as in GasForce2.mo."""
    x = np.asarray(x, dtype=float)
    if compression:
        low = 177.4132 * x**4 - 287.2189 * x**3 + 151.8252 * x**2 - 24.9973 * x + 2.4
        high = 2836360 * x**4 - 10569296 * x**3 + 14761814 * x**2 - 9158505 * x + 2129670
        bar = np.where(x < 0.986061, low, high)
    else:
        high = -3929704 * x**4 + 14748765 * x**3 - 20747000 * x**2 + 12964477 * x - 3036495
        low = 145.930 * x**4 - 131.707 * x**3 + 17.3438 * x**2 + 17.9272 * x + 2.4
        bar = np.where(x > 0.933, high, low)
    return 1e5 * bar


def gas_force(s, compression, L, d=BORE):
    """The force [N] pushing the piston down the cylinder (towards larger s)."""
    return gas_pressure(1 - np.asarray(s, float) / L, compression) * math.pi * d ** 2 / 4


def gas_force_law(s, v, L, d=BORE):
    """GasForce2's force [N] pushing the piston down the cylinder, as a kinetwork expression
    in the names ``s`` (the position sensed on the prismatic's axis) and ``v`` (its speed):
    MSL's polynomials and switches as ``gas_pressure`` has them, times pi d^2/4."""
    x = f"(1 - {s}/{L!r})"

    def poly(c):
        out = f"{c[0]!r}*{x}^4"
        for coef, power in zip(c[1:], ("^3", "^2", "", None)):
            out += (" - " if coef < 0 else " + ") + f"{abs(coef)!r}" + (
                "" if power is None else f"*{x}{power}")
        return f"({out})"
    compression = (f"if_else({x} < 0.986061, "
                   f"{poly((177.4132, -287.2189, 151.8252, -24.9973, 2.4))}, "
                   f"{poly((2836360, -10569296, 14761814, -9158505, 2129670))})")
    expansion = (f"if_else({x} > 0.933, "
                 f"{poly((-3929704, 14748765, -20747000, 12964477, -3036495))}, "
                 f"{poly((145.930, -131.707, 17.3438, 17.9272, 2.4))})")
    return f"1e5*if_else({v} < 0, {compression}, {expansion})*pi*{d!r}^2/4"


# ---------------------------------------------------------------------------------------
# One cylinder
# ---------------------------------------------------------------------------------------

def closure(phi, crankAngleOffset=0.0, cylinderInclination=0.0, **params):
    """Closed-form slider-crank closure of one cylinder at crankshaft angle ``phi``:
    dict of alpha (crank angle from the cylinder axis), beta (rod angle from the axis),
    s (the prismatic's coordinate: piston top below the cylinder top) and the joint
    coordinates b1 = beta - alpha and b2 = beta."""
    p = {**CYLINDER, **params}
    r, l = p["crankPinOffset"], p["rodLength"]
    alpha = np.asarray(phi, float) + crankAngleOffset - cylinderInclination
    beta = -np.arcsin(r / l * np.sin(alpha))
    y_pin = r * np.cos(alpha) + l * np.cos(beta)                 # the piston pin b2
    s = p["cylinderTopPosition"] - p["pistonLength"] - y_pin
    return {"alpha": alpha, "beta": beta, "s": s, "b1": beta - alpha, "b2": beta}


def closure_expressions(phi, crankAngleOffset="crankAngleOffset",
                        cylinderInclination="cylinderInclination", **params):
    """:func:`closure` as kinetwork expressions in the names ``phi``, ``crankAngleOffset`` and
    ``cylinderInclination`` (the parameters of the Cylinder definition): its loop joints'
    starting guesses follow each instance's offset and inclination."""
    p = {**CYLINDER, **params}
    r, l = p["crankPinOffset"], p["rodLength"]
    alpha = f"({phi} + {crankAngleOffset} - {cylinderInclination})"
    beta = f"(-asin({r!r}/{l!r}*sin{alpha}))"
    s = (f"{p['cylinderTopPosition'] - p['pistonLength']!r} - ({r!r}*cos{alpha} + "
         f"{l!r}*cos{beta})")
    return {"alpha": alpha, "beta": beta, "s": s, "b1": f"{beta} - {alpha}", "b2": beta}


def _negative(value):
    return f"-{value}" if isinstance(value, str) else -value


def _number(value):
    return value if isinstance(value, str) else float(value)


def cylinder_length(**params):
    """MSL's cylinderLength = cylinderTopPosition - (pistonLength + rodLength -
    crankPinOffset): the gas force's L."""
    p = {**CYLINDER, **params}
    return p["cylinderTopPosition"] - (p["pistonLength"] + p["rodLength"]
                                       - p["crankPinOffset"])


def s_top(**params):
    """The prismatic's coordinate s at the top dead centre (its smallest: 0.02 m)."""
    p = {**CYLINDER, **params}
    return p["cylinderTopPosition"] - p["pistonLength"] - p["crankPinOffset"] - p["rodLength"]


def add_cylinder(model, prefix, crank_frame, cylinder_frame, *, phi0=0.0, gas=True,
                 probes=True, rod_shape_offset=0.02, **params):
    """Add one MSL ``Utilities.Cylinder`` to ``model``; return ``CylinderPorts``.

    ``crank_frame`` (the previous crankshaft piece, or the bearing) is wired to this
    cylinder's crank_a, ``cylinder_frame`` (the engine block: the world, or the previous
    cylinder_b) to its cylinder_a; None leaves that port unwired. Every component and
    connection of the cylinder is made here (nothing outside but those two wires), so this
    body is the future subsystem definition, its ports ``CYLINDER_PORTS``.

    ``params`` are Cylinder.mo's (``CYLINDER``; angles in rad). ``phi0`` is the crankshaft
    angle at the start: only the loop joints' starting guesses use it. ``gas`` adds
    GasForce2, ``probes`` a probe ``<prefix>_piston_probe`` (position, velocity, force) on the
    prismatic's axis; ``rod_shape_offset`` is the rod's r_shape (MSL: 0.02 m).
    """
    p = {**CYLINDER, **params}
    unknown = set(params) - set(CYLINDER)
    if unknown:
        raise TypeError(f"unknown cylinder parameter(s): {sorted(unknown)}")
    # prefix None: the cylinder alone, a subsystem definition (names as they are)
    n = (lambda local: local) if prefix is None else (lambda local: f"{prefix}_{local}")
    add = model.add
    x = [1.0, 0.0, 0.0]
    parts = cylinder_parts(rod_shape_offset=rod_shape_offset, **params)

    def body(name, frame_a):
        """A MSL BodyBox / BodyCylinder: FixedTranslation + RigidBody on its frame_a."""
        r, (m, r_cm, inertia) = parts[name]
        add(mb.FixedTranslation(n(name), r=r))
        diag = np.allclose(inertia, np.diag(np.diag(inertia)), rtol=0, atol=1e-15)
        add(mb.RigidBody(n(f"{name}_body"), mass=float(m), r_cm=[float(v) for v in r_cm],
                         inertia=[float(v) for v in np.diag(inertia)] if diag
                         else inertia.tolist()))
        model.connect(n(f"{name}_body.frame_a"), n(f"{name}.frame_a"))
        if frame_a is not None:
            model.connect(frame_a, n(f"{name}.frame_a"))
        return n(f"{name}.frame_b")

    start = closure_expressions(phi0, **p) if isinstance(phi0, str) else closure(phi0, **p)

    # -- the engine block side: cylinder_a -> mounting -> cylinder_b; inclination, top
    add(mb.FixedTranslation(n("mounting"), r=[p["crankLength"], 0, 0]))
    add(mb.FixedRotation(n("inclination"), r=[p["crankLength"] - p["crankPinLength"] / 2, 0, 0],
                         axis=x, angle=p["cylinderInclination"]))
    add(mb.FixedTranslation(n("cylinderTop"), r=[0, p["cylinderTopPosition"], 0]))
    model.connect(n("mounting.frame_a"), n("inclination.frame_a"))
    model.connect(n("inclination.frame_b"), n("cylinderTop.frame_a"))

    # -- the crankshaft piece: crank_a -> crankAngle1 -> crank1..4 -> crankAngle2 -> crank_b
    add(mb.FixedRotation(n("crankAngle1"), axis=x, angle=p["crankAngleOffset"]))
    add(mb.FixedRotation(n("crankAngle2"), axis=x, angle=_negative(p["crankAngleOffset"])))
    tip = body("crank1", n("crankAngle1.frame_b"))
    pin = body("crank2", tip)
    tip = body("crank3", pin)
    tip = body("crank4", tip)
    model.connect(tip, n("crankAngle2.frame_a"))

    # -- the loop: crank pin -> mid -> b1 (cut) -> rod -> b2 -> piston -> cylinder -> top
    add(mb.FixedTranslation(n("mid"), r=[p["crankPinLength"] / 2, 0, 0]))
    model.connect(pin, n("mid.frame_a"))
    add(mb.Revolute(n("b1"), axis=x, cut=True, q0_guess=_number(start["b1"])))
    model.connect(n("mid.frame_b"), n("b1.frame_a"))
    rod_end = body("connectingRod", n("b1.frame_b"))
    add(mb.Revolute(n("b2"), axis=x, q0_guess=_number(start["b2"])))
    model.connect(n("b2.frame_b"), rod_end)
    piston_top = body("piston", n("b2.frame_a"))
    add(mb.Prismatic(n("cylinder"), axis=[0, -1, 0], q0_guess=_number(start["s"])))
    model.connect(n("cylinderTop.frame_b"), n("cylinder.frame_a"))
    model.connect(n("cylinder.frame_b"), piston_top)

    if gas:
        # GasForce2 between the prismatic's support and axis (see the module docstring)
        add(tr.PositionSensor(n("gas_s")))
        add(tr.SpeedSensor(n("gas_v")))
        add(tr.Force(n("gasForce"), f=gas_force_law(n("gas_s") + ".y", n("gas_v") + ".y",
                                                    cylinder_length(**p))))
        for a, b in [("gas_s.flange", "cylinder.axis"), ("gas_v.flange", "cylinder.axis"),
                     ("gasForce.flange", "cylinder.axis"),
                     ("gasForce.support", "cylinder.support")]:
            model.connect(n(a), n(b))
    if probes:
        add(kn.Probe(n("piston_probe"), quantities=["position", "velocity", "force"]))
        model.connect(n("piston_probe.port"), n("cylinder.axis"))

    # -- the outside: crank_a, cylinder_a (crank_b, cylinder_b are returned); None leaves
    # a port unwired (a subsystem definition)
    if crank_frame is not None:
        model.connect(crank_frame, n(CYLINDER_PORTS["crank_a"]))
    if cylinder_frame is not None:
        model.connect(cylinder_frame, n(CYLINDER_PORTS["cylinder_a"]))
    return CylinderPorts(n(CYLINDER_PORTS["crank_b"]), n(CYLINDER_PORTS["cylinder_b"]))


# ---------------------------------------------------------------------------------------
# The engine
# ---------------------------------------------------------------------------------------

def _add_crankshaft(model, phi0, w0, J_load, load2=True, filter=True, gravity=GRAVITY,
                    engine=ENGINE):
    """World, main bearing about x with MSL's start values, the load inertia behind a torque
    sensor, load2 and the torque filter; probes on the crankshaft."""
    model.add(mb.Ground("world", gravity=list(gravity)))
    model.add(mb.Revolute("bearing", axis=[1, 0, 0], q0=phi0, qd0=w0))
    model.connect("world.frame", "bearing.frame_a")
    model.add(kn.Probe("crankshaft", quantities=["angle", "speed"]))
    model.connect("crankshaft.port", "bearing.axis")
    if J_load is None:
        return
    model.add(rot.TorqueSensor("torqueSensor"))
    model.add(rot.Inertia("load", J=J_load))
    model.connect("bearing.axis", "torqueSensor.flange_a")
    model.connect("torqueSensor.flange_b", "load.flange_a")
    model.add(kn.Probe("engineTorque", quantities=["value"]))
    model.connect("engineTorque.port", "torqueSensor.y")
    if load2:
        # QuadraticSpeedDependentTorque: tau = tau_nominal (w / w_nominal)^2 accelerates the
        # flange (TorqueDirection = true: the same sign for either direction of w)
        model.add(rot.SpeedSensor("load2_w"))
        model.add(sig.Product("load2_w2"))
        model.add(sig.Gain("load2_gain", k=engine["tau_nominal"] / engine["w_nominal"] ** 2))
        model.add(rot.Torque("load2"))
        for a, b in [("load2_w.flange", "load.flange_b"), ("load2_w.y", "load2_w2.u1"),
                     ("load2_w.y", "load2_w2.u2"), ("load2_w2.y", "load2_gain.u"),
                     ("load2_gain.y", "load2.u"), ("load2.flange", "load.flange_b")]:
            model.connect(a, b)
    if filter:
        # CriticalDamping(n, f): n first-order stages of time constant alpha / (2 pi f),
        # alpha = sqrt(2^(1/n) - 1) (Blocks.Continuous.CriticalDamping)
        n_f = engine["filter_n"]
        T = math.sqrt(2 ** (1 / n_f) - 1) / (2 * math.pi * engine["filter_f"])
        prev = "torqueSensor.y"
        for i in range(n_f):
            model.add(sig.FirstOrder(f"filter{i + 1}", k=1.0, T=T))
            model.connect(prev, f"filter{i + 1}.u")
            prev = f"filter{i + 1}.y"
        model.add(kn.Probe("filteredEngineTorque", quantities=["value"]))
        model.connect("filteredEngineTorque.port", prev)


def build_engine_v6(cylinders=V6_CYLINDERS, phi0=ENGINE["phi0"], w0=ENGINE["w0"],
                    J_load=ENGINE["J_load"], load2=True, filter=True, gas=True, probes=True,
                    **cylinder_params):
    """MSL's EngineV6 as a flat kn.Model: ``cylinders`` lists (crankAngleOffset,
    cylinderInclination) in degrees per cylinder (``V6_CYLINDERS``), named cyl1, cyl2, ...
    ``J_load=None`` leaves out the load, torque sensor, load2 and filter."""
    model = kn.Model(
        "EngineV6",
        description=(
            "Modelica.Mechanics.MultiBody.Examples.Loops.EngineV6 (MSL 3.2.x) built flat from "
            "kinetwork components: six cylinders in a 60-degree V on one crankshaft (6 planar "
            "loops, each cut at the crank-pin revolute b1; 1 degree of freedom), GasForce2 "
            "as MSL's polynomials, a 1 kg m^2 load started at 10 rad/s, load2 = "
            "-100 N m (w/200)^2. See tests/scenes/engine.py."),
        simulation=dict(EXPERIMENT))
    _add_crankshaft(model, phi0, w0, J_load, load2=load2 and J_load is not None,
                    filter=filter and J_load is not None)
    crank, block = "bearing.frame_b", "world.frame"
    for i, (offset, inclination) in enumerate(cylinders, start=1):
        crank, block = add_cylinder(
            model, f"cyl{i}", crank, block, phi0=phi0, gas=gas, probes=probes,
            crankAngleOffset=math.radians(offset),
            cylinderInclination=math.radians(inclination), **cylinder_params)
    return model


def cylinder_definition(gas=True, probes=True, **params):
    """MSL's ``Loops.Utilities.Cylinder`` as a subsystem definition: the content of
    :func:`add_cylinder`, its four frames exposed (``CYLINDER_PORTS``). Its parameters are
    what differs between the cylinders of an engine: ``crankAngleOffset`` and
    ``cylinderInclination`` [rad], and ``phi0``, the crankshaft angle at the start (the loop
    joints' starting guesses)."""
    model = kn.Model("Cylinder", parameters={"crankAngleOffset": 0.0,
                                             "cylinderInclination": 0.0, "phi0": 0.0},
                     description=(
        "Modelica.Mechanics.MultiBody.Examples.Loops.Utilities.Cylinder: a piece of "
        "crankshaft (crank_a to crank_b), the crank pin, connecting rod and piston in a "
        "cylinder of the engine block (cylinder_a to cylinder_b), a planar loop cut at the "
        "crank-pin revolute b1, and GasForce2 (MSL's pressure polynomials, the law of one "
        "Force in the sensed piston position and speed). Parameters: crankAngleOffset and "
        "cylinderInclination [rad], phi0 the crankshaft angle at the start."))
    add_cylinder(model, None, None, None, phi0="phi0", gas=gas, probes=probes,
                 crankAngleOffset="crankAngleOffset",
                 cylinderInclination="cylinderInclination", **params)
    for port, inner in CYLINDER_PORTS.items():
        model.expose(port, inner)
    return model


def build_engine_v6_subsystems(cylinders=V6_CYLINDERS, phi0=ENGINE["phi0"], w0=ENGINE["w0"],
                               J_load=ENGINE["J_load"], load2=True, filter=True, gas=True,
                               probes=True, definition=None):
    """:func:`build_engine_v6` with each cylinder one instance of :func:`cylinder_definition`
    (or ``definition``): ``cyl1`` ... ``cyl6``, their parts named by path
    (``cyl3.piston``)."""
    model = kn.Model("EngineV6", description=(
        "Modelica.Mechanics.MultiBody.Examples.Loops.EngineV6 (MSL 3.2.x): six instances of "
        "one Cylinder subsystem in a 60-degree V on one crankshaft (6 planar loops, 1 degree "
        "of freedom), a 1 kg m^2 load started at 10 rad/s, load2 = -100 N m (w/200)^2 and "
        "the engine torque filtered. See tests/scenes/engine.py."),
        simulation=dict(EXPERIMENT))
    _add_crankshaft(model, phi0, w0, J_load, load2=load2 and J_load is not None,
                    filter=filter and J_load is not None)
    cylinder = definition or cylinder_definition(gas=gas, probes=probes)
    crank, block = "bearing.frame_b", "world.frame"
    for i, (offset, inclination) in enumerate(cylinders, start=1):
        model.add(kn.Subsystem(f"cyl{i}", cylinder, params={
            "crankAngleOffset": math.radians(offset),
            "cylinderInclination": math.radians(inclination), "phi0": phi0}))
        model.connect(crank, f"cyl{i}.crank_a")
        model.connect(block, f"cyl{i}.cylinder_a")
        crank, block = f"cyl{i}.crank_b", f"cyl{i}.cylinder_b"
    return model


def write_models(folder):
    """``folder``/EngineV6.json placing ``folder``/Cylinder.json six times (the example in
    ``models/engine_v6``)."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    cylinder_definition().save(folder / "Cylinder.json")
    cylinder = kn.load(folder / "Cylinder.json")
    build_engine_v6_subsystems(definition=cylinder).save(folder / "EngineV6.json")
    return folder / "EngineV6.json"


def build_single_cylinder(phi0=0.5, w0=3.0, gravity=(0.0, 0.0, -9.81), J_load=None,
                          gas=False, rod_shape_offset=0.0, **params):
    """One upright cylinder (offset and inclination 0 unless given) on the bearing: the
    slider-crank of ``reference_loops`` once its masses are mapped (see the tests). By default
    without gas force, load or the rod's r_shape (its centre at mid-length, as the reference
    assumes), gravity along -z (in the plane of the loop)."""
    model = kn.Model("EngineV6_cylinder",
                     description="One cylinder of tests/scenes/engine.py on its bearing.")
    _add_crankshaft(model, phi0, w0, J_load, load2=False, filter=False, gravity=gravity)
    add_cylinder(model, "cyl1", "bearing.frame_b", "world.frame", phi0=phi0, gas=gas,
                 rod_shape_offset=rod_shape_offset, **params)
    return model


if __name__ == "__main__":
    import time
    print(part_table())
    t0 = time.perf_counter()
    engine = build_engine_v6()
    topo = engine.validate()
    t1 = time.perf_counter()
    system = engine.compile()
    t2 = time.perf_counter()
    print(f"{len(engine.components)} components, {len(engine.connections)} connections, "
          f"{len(topo.loops)} loops; build+validate {t1 - t0:.2f} s, compile {t2 - t1:.2f} s; "
          f"dof {system.dof}, states {system.state_names}")
    res = kn.simulate(system, t_end=0.5, n_points=501, rtol=1e-6, atol=1e-8, jit=False)
    t3 = time.perf_counter()
    print(f"simulate 0.5 s: {t3 - t2:.2f} s; speed {res['crankshaft.speed'][0]:.3f} -> "
          f"{res['crankshaft.speed'][-1]:.3f} rad/s")
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "EngineV6.json")
    engine.save(out)
    print(f"wrote {out}: {out.stat().st_size} bytes")


def build_engine1a():
    """MSL's ``Examples.Loops.Engine1a`` (MSL 3.2, Engine1a.mo) as written there, part for
    part: the mechanical part of one cylinder (no combustion), the output inertia J = 1
    started at phi = 0, w = 10 rad/s. At phi = 0 the crank pin points up the cylinder: the
    engine starts at its top dead centre, the loop's Jacobian singular. The loop joints start
    from MSL's values (B1, B2 at 0, the slider at s = 0.15, none fixed); B1 is MSL's
    RevolutePlanarLoopConstraint, here the cut revolute (its redundant rows dropped)."""
    x = [1, 0, 0]
    model = kn.Model("Engine1a", description=(
        "Modelica.Mechanics.MultiBody.Examples.Loops.Engine1a (MSL 3.2): one cylinder's "
        "mechanism, crank, rod and piston as BodyBox/BodyCylinder, started at its top dead "
        "centre (phi = 0) with the output inertia (J = 1) at 10 rad/s; no combustion, no "
        "friction: the energy is conserved. See tests/scenes/engine.py. MSL's figure is the "
        "animation of the engine; reproduced here through its dead centres as the piston's "
        "position (probe piston) on the slider-crank's closed form s(phi) = 0.35 - 0.1 cos(phi) "
        "- sqrt(0.2^2 - 0.1^2 sin(phi)^2) at the crank angle (probe crank), checked in "
        "tests/scenes/test_engine1a.py."),
        simulation={"t_end": 5.0, "n_points": 501, "method": "auto", "rtol": 1e-8,
                    "atol": 1e-10})
    parts = [
        mb.Ground("world", gravity=[0, -9.81, 0]),
        mb.Revolute("Bearing", axis=x, q0=0.0, qd0=10.0),
        rot.Inertia("Inertia", J=1.0),
        mb.BodyCylinder("Crank1", r=[0.1, 0, 0], diameter=0.05),
        mb.BodyBox("Crank2", r=[0, 0.1, 0], height=0.05, width_direction=x, width=0.02),
        mb.BodyCylinder("Crank3", r=[0.1, 0, 0], diameter=0.03),
        mb.BodyBox("Crank4", r=[0, -0.1, 0], height=0.05, width_direction=x, width=0.02),
        mb.FixedTranslation("Mid", r=[0.05, 0, 0]),
        mb.Revolute("B1", axis=x, cut=True),
        mb.BodyBox("Rod", r=[0, -0.2, 0], width_direction=x, width=0.02, height=0.06),
        mb.Revolute("B2", axis=x),
        mb.BodyCylinder("Piston", r=[0, -0.1, 0], diameter=0.1),
        mb.Prismatic("Cylinder", axis=[0, -1, 0], q0_guess=0.15),
        mb.FixedTranslation("cylPosition", r=[0.15, 0.45, 0]),
        kn.Probe("crank", quantities=["angle", "speed"]),
        kn.Probe("piston", quantities=["position", "velocity"]),
    ]
    for part in parts:
        model.add(part)
    for a, b in [("world.frame", "Bearing.frame_a"), ("Crank2.frame_a", "Crank1.frame_b"),
                 ("Crank2.frame_b", "Crank3.frame_a"), ("Bearing.frame_b", "Crank1.frame_a"),
                 ("cylPosition.frame_b", "Cylinder.frame_a"),
                 ("world.frame", "cylPosition.frame_a"), ("Crank3.frame_b", "Crank4.frame_a"),
                 ("B1.frame_a", "Mid.frame_b"), ("B1.frame_b", "Rod.frame_b"),
                 ("Rod.frame_a", "B2.frame_b"), ("B2.frame_a", "Piston.frame_b"),
                 ("Inertia.flange_b", "Bearing.axis"), ("Mid.frame_a", "Crank2.frame_b"),
                 ("Cylinder.frame_b", "Piston.frame_a"), ("crank.port", "Bearing.axis"),
                 ("piston.port", "Cylinder.axis")]:
        model.connect(a, b)
    return model
