"""Multibody components: ground, joints, bodies and rigid parts, declared by geometry.

A joint gives the transform of frame_b relative to frame_a as a function of its coordinates;
the solver's Newton-Euler passes derive everything else from it. A body with a shape
(BodyBox, BodyCylinder) is a rigid part that is also a body on its frame_a: its transform is
a FixedTranslation's and its mass properties follow from its geometry and density, as in
Modelica's MultiBody.Parts. The force elements on frames (line forces, forces and torques)
are declared in ``forces.py`` and are part of this library too.
"""

import math

import casadi as ca
import numpy as np

from ..errors import ModelError
from ..spatial import cardan_quat, mat3, quat_rate, quat_rotation, rotation, unit, vec3
from .base import COORDINATES, RATES, Component, Param, Port, library_attribute

MB = "multibody"


#: gravity fields a Ground may have (MSL's World.gravityType, less NoGravity: a uniform zero)
GRAVITY_TYPES = ("uniform", "point")


class Ground(Component, library=MB):
    """The inertial world frame, with the gravity field of the model.

    The field is uniform (``gravity``), or that of a point mass at the world origin
    (``gravity_type`` "point", MSL's World with gravityType PointGravity): -mue/|r|^2 along r
    at the world point r, acting on every body at its centre of mass (so a body feels a
    torque about its frame only through its centre-of-mass offset, as in MSL; no
    gravity-gradient torque).

    Parameters
    ----------
    gravity : m/s^2, 3 values, default [0, -9.81, 0]
        Uniform gravity acceleration, in the world frame (not used by a point field).
    gravity_type : "uniform" or "point", default "uniform"
        Kind of gravity field.
    mue : m^3/s^2, >= 0, default 3.986004418e14 (the Earth's)
        Field constant of the point field, G times the central mass (MSL's mu).
    """
    role = "world"
    frame = Port("frame", "World frame", optional=True)
    gravity = Param([0.0, -9.81, 0.0], unit="m/s^2", shape=(3,),
                    doc="Gravity acceleration, resolved in the world frame")
    gravity_type = Param("uniform", kind="choice", choices=GRAVITY_TYPES,
                         doc="Gravity field: uniform (gravity), or point (a central mass at "
                             "the world origin, field constant mue)")
    mue = Param(3.986004418e14, unit="m^3/s^2", min=0.0,
                doc="Field constant of the point gravity field (G times the central mass)")

    def uniform_gravity(self):
        """The gravity vector of a uniform field, or None for a point field."""
        return vec3(self.gravity) if self.gravity_type == "uniform" else None

    def gravity_at(self, r):
        """Gravity acceleration at the world point ``r`` (CasADi)."""
        if self.gravity_type == "uniform":
            return vec3(self.gravity)
        return -self.mue * r / ca.norm_2(r) ** 3


class PartialRigidTransform(Component):
    """Two frames at a transform fixed by parameters: costs no state.

    It and the joints are the edges of the frame graph; ``cut_preference`` ranks how
    willingly the spanning tree leaves one out to cut a kinematic loop (lowest first).
    """
    role = "part"
    dof = 0
    constant_subspace = True
    regular = True
    cut_preference = 4          # a rigid part is never cut while a joint of the loop can be
    #: a part with mass is a body on its frame_a as well (``mass_properties``): a body with a
    #: shape, folded into the body before it like any rigid part
    has_mass = False
    frame_a = Port("frame", "Frame a")
    # a dangling end of a rigid part is a marker frame (for probes), as in Modelica
    frame_b = Port("frame", "Frame b, at the fixed transform from frame_a", optional=True)

    def closure(self, rel_R, rel_p, q):
        """Loop-closure residual when this part or joint is cut: zero when frame_b, at
        ``rel_R, rel_p`` in frame_a, sits where the transform at coordinates ``q`` puts it
        (3 position rows, 9 rotation-matrix rows; the redundant ones are dropped later)."""
        Rc, pc = self.transform(q)
        return ca.vertcat(rel_p - pc, ca.vec(Rc.T @ rel_R - ca.SX.eye(3)))


class FixedTranslation(PartialRigidTransform, library=MB):
    """frame_b = frame_a moved by ``r`` (resolved in frame_a)."""
    r = Param(unit="m", shape=(3,), doc="Position of frame_b in frame_a")

    def transform(self, q):
        return ca.SX.eye(3), vec3(self.r)


class FixedRotation(PartialRigidTransform, library=MB):
    """frame_b = frame_a moved by ``r``, then rotated by ``angle`` about ``axis``."""
    r = Param([0.0, 0.0, 0.0], unit="m", shape=(3,), doc="Position of frame_b in frame_a")
    direction = Param([0.0, 0.0, 1.0], unit="1", shape=(3,), nonzero=True, name="axis",
                      doc="Rotation axis, resolved in frame_a")
    angle = Param(unit="rad", doc="Rotation angle about axis")

    def transform(self, q):
        return rotation(vec3(self.direction), self.angle), vec3(self.r)


class PartialJoint(PartialRigidTransform):
    """Degrees of freedom between frame_a and frame_b.

    A joint has ``nq`` coordinates q and ``dof`` speeds u. A *regular* joint's coordinates
    are the integrals of its speeds (qdot = u): angles and distances, which can be driven
    through 1-D flanges and solved from a kinematic loop. The motion subspace (the spatial
    velocity of frame_b relative to frame_a per unit speed, in frame_b axes) is derived from
    ``transform`` unless ``subspace`` gives it; ``rate`` gives qdot from (q, u).
    """
    role = "joint"
    dof = 1
    nq = None                 # coordinates (None: as many as speeds)
    regular = True
    constant_subspace = True
    cut_preference = 3
    frame_b = Port("frame", "Frame b, moved by the joint coordinates")
    coordinate_ports = {}
    zero_ports = ()
    cut = Param(False, kind="bool", doc="Cut the kinematic loop at this joint")
    #: unit of each coordinate
    units = ()

    @classmethod
    def n_coordinates(cls):
        return cls.nq or cls.dof

    def coordinate_labels(self):
        return ["q"] if self.dof == 1 else [f"q[{i}]" for i in range(self.dof)]

    def speed_labels(self):
        return ["qd"] if self.dof == 1 else [f"qd[{i}]" for i in range(self.dof)]

    def subspace(self, q):
        """Motion subspace (6 x dof, frame_b axes), or None to derive it from ``transform``."""
        return None

    def rate(self, q, u):
        """d(q)/dt for the speeds u."""
        return u

    def initial(self):
        """(q0, u0): lists of nq and dof values. None in q0 is solved from a loop (else 0);
        None in u0 is 0, or follows from the loop's velocity constraint."""
        q0, qd0 = self.q0, self.qd0
        if self.dof == 1:
            return [q0], [qd0]
        return ([None] * self.dof if q0 is None else list(q0),
                [None] * self.dof if qd0 is None else list(qd0))

    def guesses(self):
        """Where the search for coordinates solved from a loop starts."""
        g = self.q0_guess
        return [g] if self.dof == 1 else list(g)


class PartialAxisJoint(PartialJoint):
    """One degree of freedom along or about ``axis``, with its two 1-D flanges.

    ``axis`` (potential = q) drives the joint; ``support`` (potential 0) is its reaction side,
    taken, as in Modelica MultiBody, to rest in the world frame.
    """
    coordinate_ports = {"axis": 0}
    zero_ports = ("support",)
    axis = Port("1d", "Flange driving the joint coordinate", optional=True)
    support = Port("1d", "Reaction flange of the drive", optional=True)
    direction = Param([0.0, 0.0, 1.0], unit="1", shape=(3,), nonzero=True, name="axis",
                      doc="Joint axis, resolved in frame_a")
    q0 = Param(None, optional=True, unit=COORDINATES,
               doc="Initial coordinate (None: 0, or solved in a loop)")
    qd0 = Param(None, optional=True, unit=RATES, doc="Initial coordinate speed (None: 0)")
    q0_guess = Param(0.0, unit=COORDINATES,
                     doc="Start of the search for q0 when it is solved in a loop")


class Revolute(PartialAxisJoint, library=MB):
    """frame_b is frame_a rotated by q about ``axis`` (resolved in frame_a)."""
    domain = "rotational"
    units = ("rad",)

    def transform(self, q):
        return rotation(vec3(self.direction), q[0]), ca.SX.zeros(3)


class Prismatic(PartialAxisJoint, library=MB):
    """frame_b is frame_a moved by q along ``axis`` (resolved in frame_a)."""
    domain = "translational"
    units = ("m",)
    direction = Param([1.0, 0.0, 0.0], unit="1", shape=(3,), nonzero=True, name="axis",
                      doc="Direction of motion, resolved in frame_a")

    def transform(self, q):
        return ca.SX.eye(3), unit(vec3(self.direction)) * q[0]


def _pair(doc, unit_=COORDINATES):
    return Param(None, optional=True, shape=(2,), unit=unit_, doc=doc)


def _triple(doc, default=None, unit_=COORDINATES):
    return Param(default, optional=default is None, shape=(3,), unit=unit_, doc=doc)


class Universal(PartialJoint, library=MB):
    """Two revolutes in series: frame_b is frame_a rotated by q[0] about ``n_a``, then by
    q[1] about ``n_b`` (resolved in the once-rotated frame); a Cardan joint."""
    dof = 2
    constant_subspace = False
    units = ("rad", "rad")
    coordinate_ports = {"axis_a": 0, "axis_b": 1}
    zero_ports = ("support",)
    axis_a = Port("rotational", "Flange driving q[0] (about n_a)", optional=True)
    axis_b = Port("rotational", "Flange driving q[1] (about n_b)", optional=True)
    support = Port("rotational", "Reaction flange of both drives", optional=True)
    n_a = Param([1.0, 0.0, 0.0], unit="1", shape=(3,), nonzero=True,
                doc="First axis, in frame_a")
    n_b = Param([0.0, 1.0, 0.0], unit="1", shape=(3,), nonzero=True,
                doc="Second axis, in the frame rotated about n_a")
    q0 = _pair("Initial angles (None: 0, or solved in a loop)")
    qd0 = _pair("Initial angular speeds (None: 0)", RATES)
    q0_guess = Param([0.0, 0.0], shape=(2,), unit=COORDINATES,
                     doc="Start of the search for q0 in a loop")

    def transform(self, q):
        return rotation(vec3(self.n_a), q[0]) @ rotation(vec3(self.n_b), q[1]), ca.SX.zeros(3)


class Cylindrical(PartialJoint, library=MB):
    """frame_b is frame_a rotated by q[0] about ``axis`` and moved by q[1] along it."""
    dof = 2
    units = ("rad", "m")
    coordinate_ports = {"axis_phi": 0, "axis_s": 1}
    zero_ports = ("support_phi", "support_s")
    axis_phi = Port("rotational", "Flange driving the angle q[0]", optional=True)
    support_phi = Port("rotational", "Reaction flange of the rotation", optional=True)
    axis_s = Port("translational", "Flange driving the distance q[1]", optional=True)
    support_s = Port("translational", "Reaction flange of the translation", optional=True)
    direction = Param([0.0, 0.0, 1.0], unit="1", shape=(3,), nonzero=True, name="axis",
                      doc="Axis of rotation and translation, resolved in frame_a")
    q0 = _pair("Initial angle and distance (None: 0, or solved in a loop)")
    qd0 = _pair("Initial angular and linear speed (None: 0)", RATES)
    q0_guess = Param([0.0, 0.0], shape=(2,), unit=COORDINATES,
                     doc="Start of the search for q0 in a loop")

    def transform(self, q):
        n = vec3(self.direction)
        return rotation(n, q[0]), unit(n) * q[1]


class Planar(PartialJoint, library=MB):
    """frame_b moves in the plane normal to ``n``: by q[0] along ``n_x``, q[1] along
    n x n_x, and is rotated by q[2] about ``n`` (all resolved in frame_a)."""
    dof = 3
    constant_subspace = False
    units = ("m", "m", "rad")
    coordinate_ports = {"axis_x": 0, "axis_y": 1, "axis_phi": 2}
    zero_ports = ("support_s", "support_phi")
    axis_x = Port("translational", "Flange driving q[0] (along n_x)", optional=True)
    axis_y = Port("translational", "Flange driving q[1] (along n x n_x)", optional=True)
    axis_phi = Port("rotational", "Flange driving the angle q[2]", optional=True)
    support_s = Port("translational", "Reaction flange of the translations", optional=True)
    support_phi = Port("rotational", "Reaction flange of the rotation", optional=True)
    n = Param([0.0, 0.0, 1.0], unit="1", shape=(3,), nonzero=True,
              doc="Plane normal, in frame_a")
    n_x = Param([1.0, 0.0, 0.0], unit="1", shape=(3,), nonzero=True,
                doc="Direction of q[0] in the plane, in frame_a")
    q0 = _triple("Initial x, y, angle (None: 0, or solved in a loop)")
    qd0 = _triple("Initial speeds (None: 0)", unit_=RATES)
    q0_guess = Param([0.0, 0.0, 0.0], shape=(3,), unit=COORDINATES,
                     doc="Start of the search for q0 in a loop")

    def transform(self, q):
        n = unit(vec3(self.n))
        ex = vec3(self.n_x)
        ex = unit(ex - ca.dot(ex, n) * n)
        ey = ca.cross(n, ex)
        return rotation(n, q[2]), ex * q[0] + ey * q[1]


class Spherical(PartialJoint, library=MB):
    """A ball joint: frame_b turns freely about the common origin of the two frames.

    Coordinates: a quaternion [w, x, y, z] of frame_b's orientation in frame_a (normalised,
    so no orientation is singular); speeds: the angular velocity of frame_b relative to
    frame_a, resolved in frame_b. In a kinematic loop a Spherical joint is best cut (three
    position constraints).
    """
    dof = 3
    nq = 4
    regular = False
    cut_preference = 1        # three position rows, and no quaternion left in a loop
    units = ("", "", "", "")
    angles0 = Param([0.0, 0.0, 0.0], shape=(3,), unit="rad",
                    doc="Initial orientation: body-fixed x-y-z (Cardan) angles")
    w0 = Param([0.0, 0.0, 0.0], shape=(3,), unit="rad/s",
               doc="Initial angular velocity of frame_b in frame_a, resolved in frame_b")

    def coordinate_labels(self):
        return [f"quat[{i}]" for i in range(4)]

    def speed_labels(self):
        return [f"w[{i}]" for i in range(3)]

    def transform(self, q):
        return quat_rotation(q), ca.SX.zeros(3)

    def subspace(self, q):
        return ca.vertcat(ca.SX.eye(3), ca.SX.zeros(3, 3))

    def rate(self, q, u):
        return quat_rate(q, u)

    def closure(self, rel_R, rel_p, q):
        return rel_p                               # cut: the origins meet

    def initial(self):
        return list(ca.vertsplit(cardan_quat(self.angles0))), list(self.w0)


class FreeMotion(PartialJoint, library=MB):
    """Six degrees of freedom: frame_b anywhere relative to frame_a (a free-flying body).

    Coordinates: the position r of frame_b in frame_a (resolved in frame_a) and a normalised
    quaternion [w, x, y, z] of its orientation; speeds: v = dr/dt (resolved in frame_a) and the
    angular velocity w of frame_b relative to frame_a, resolved in frame_b (as Modelica's
    FreeMotion). The quaternion has no singular orientation, so tumbling runs of any length
    are fine.

    Its start values (r0, v0, angles0, w0) default to None: at rest at frame_a for a free
    body. A FreeMotion that closes a kinematic loop (MSL's DoublePendulumInitTip: from the
    world to a pendulum's tip) constrains nothing while the model runs, but the start values
    given are conditions on the start: the joints of its loop without a q0 (qd0) are solved
    so that frame_b starts where r0 and angles0 put it, moving as v0 and w0 say
    (``equations/loopstart.py``); what they cannot reach is refused.
    """
    dof = 6
    nq = 7
    regular = False
    constant_subspace = False
    cut_preference = 0        # cutting it removes nothing: the first choice
    units = ("m", "m", "m", "", "", "", "")
    r0 = Param(None, optional=True, shape=(3,), unit="m",
               doc="Initial position, in frame_a (None: 0, or free in a loop)")
    v0 = Param(None, optional=True, shape=(3,), unit="m/s",
               doc="Initial velocity, in frame_a (None: 0, or free in a loop)")
    angles0 = Param(None, optional=True, shape=(3,), unit="rad",
                    doc="Initial orientation: body-fixed x-y-z (Cardan) angles (None: 0, or "
                        "free in a loop)")
    w0 = Param(None, optional=True, shape=(3,), unit="rad/s",
               doc="Initial angular velocity, resolved in frame_b (None: 0, or free in a loop)")

    def coordinate_labels(self):
        return [f"r[{i}]" for i in range(3)] + [f"quat[{i}]" for i in range(4)]

    def speed_labels(self):
        return [f"v[{i}]" for i in range(3)] + [f"w[{i}]" for i in range(3)]

    def transform(self, q):
        return quat_rotation(q[3:7]), q[0:3]

    def subspace(self, q):
        # spatial velocity of frame_b in its own axes: [w; R^T v]
        Rt = quat_rotation(q[3:7]).T
        return ca.blockcat([[ca.SX.zeros(3, 3), ca.SX.eye(3)], [Rt, ca.SX.zeros(3, 3)]])

    def rate(self, q, u):
        return ca.vertcat(u[0:3], quat_rate(q[3:7], u[3:6]))

    def closure(self, rel_R, rel_p, q):
        return ca.SX(0, 1)                         # cut: it constrains nothing

    def initial(self):
        def given(v):
            return [0.0] * 3 if v is None else list(v)
        return ([*given(self.r0), *ca.vertsplit(cardan_quat(given(self.angles0)))],
                [*given(self.v0), *given(self.w0)])

    def start_conditions(self, rel_R, rel_p, rel_v, rel_w):
        """As a loop's cut joint: the rows of its given start values, each zero when frame_b
        starts where they say (at ``rel_R``, ``rel_p`` in frame_a, moving at ``rel_v`` in
        frame_a and ``rel_w`` in frame_b): (position rows, speed rows), each a list of (SX,
        the parameter it comes from)."""
        position, speed = [], []
        if self.r0 is not None:
            position.append((rel_p - vec3(self.r0), "r0"))
        if self.angles0 is not None:
            R0 = quat_rotation(cardan_quat(self.angles0))
            position.append((ca.vec(R0.T @ rel_R - ca.SX.eye(3)), "angles0"))
        if self.v0 is not None:
            speed.append((rel_v - vec3(self.v0), "v0"))
        if self.w0 is not None:
            speed.append((rel_w - vec3(self.w0), "w0"))
        return position, speed


#: MSL's world.defaultWidthFraction: a shape's default width (or diameter) is its length / 20
WIDTH_FRACTION = 20
#: what RigidBody's ``shape`` may draw
SHAPES = ("box", "cylinder", "sphere")


def _color():
    return Param(None, optional=True, kind="color",
                 doc="Colour in the animation, '#rrggbb' (None: the animation's default)")


def _density():
    return Param(7700.0, unit="kg/m^3", min=0.0,
                 doc="Density (steel 7700 to 7900, aluminium 2700, wood 400 to 800)")


def _numbers(value):
    """``value`` with its numbers as floats (lists of them), or None when it holds an
    expression: sizes are compared once every one of them is known."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, list):
        items = [_numbers(v) for v in value]
        return None if any(v is None for v in items) else items
    if isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
        return float(value)
    return None


def _direction(n, fallback):
    """``n`` made a unit vector, or ``fallback`` when it is (nearly) zero, as MSL's
    Frames.from_nxy does (CasADi's if_else: it works on symbols as on numbers)."""
    size = ca.norm_2(n)
    return ca.if_else(size < 1e-10, ca.DM(fallback), n / size)


def _axes(n_x, n_y):
    """Columns e_x, e_y, e_z of the frame whose x axis is along ``n_x`` and whose x-y plane
    holds ``n_y``: MSL's Frames.from_nxy (transposed: MSL returns the rows), robust as it is
    to a zero n_x and to an n_y parallel to n_x."""
    ex = _direction(n_x, [1.0, 0.0, 0.0])
    ey = _direction(n_y, [0.0, 1.0, 0.0])
    nz = ca.cross(ex, ey)
    ey = ca.if_else(ca.dot(nz, nz) > 1e-6, ey,
                    ca.if_else(ca.fabs(ex[0]) > 1e-6, ca.DM([0.0, 1.0, 0.0]),
                               ca.DM([1.0, 0.0, 0.0])))
    ez = unit(ca.cross(ex, ey))
    return ca.horzcat(ex, ca.cross(ez, ex), ez)


class _CheckedTogether:
    """Parameters that are checked together as well as one by one (a hole no wider than its
    body): numbers at construction and assignment, expressions once the model's parameters
    give them values (``check_values``, called by the validation)."""

    def check_values(self, values, place):
        """Problems of the evaluated parameters ``values`` taken together, as messages naming
        their place (``place(key)``); none while one of them is an expression."""
        return []

    def _declare(self, name, params, place):
        super()._declare(name, params, place)
        problems = self.check_values(self._values, place or (lambda key: f"{name}.{key}"))
        if problems:
            raise ModelError(problems)

    def set_param(self, key, value):
        given, values = dict(self.given), dict(self._values)
        super().set_param(key, value)
        problems = self.check_values(self._values, lambda k: f"{self.name}.{k}")
        if problems:              # refused: the component is left as it was
            self.given.clear()
            self.given.update(given)
            self._values.clear()
            self._values.update(values)
            raise ModelError(problems)

    def _known(self, values):
        """The real parameters of ``values`` as numbers, or None while one is an expression."""
        known = {}
        for key, value in values.items():
            if self.params[key].kind != "real":
                known[key] = value
            elif value is None:
                known[key] = None
            else:
                known[key] = _numbers(value)
                if known[key] is None:
                    return None
        return known


class RigidBody(_CheckedTogether, Component, library=MB):
    """Mass and inertia attached to frame_a.

    ``shape``, ``shape_size`` and ``color`` are looks only: they tell the animation what to
    draw and change nothing in the physics.

    Parameters
    ----------
    mass : kg, >= 0, required
        Mass.
    r_cm : m, 3 values, default [0, 0, 0]
        Centre of mass from frame_a, resolved in frame_a.
    inertia : kg*m^2, 3x3 or its diagonal, default zero
        Inertia about the centre of mass, in frame_a axes.
    shape : "box", "cylinder", "sphere" or None, default None
        What the animation draws, centred at r_cm (None: a small sphere).
    shape_size : m, 3 values >= 0, default None
        Size of the shape: a box's extents along frame_a's x, y, z; a cylinder's length
        (along frame_a's x) and diameter, the third unused; a sphere's diameter, the other two
        unused.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    role = "body"
    frame_a = Port("frame", "Frame the body is fixed to")
    mass = Param(unit="kg", min=0.0, doc="Mass")
    r_cm = Param([0.0, 0.0, 0.0], unit="m", shape=(3,),
                 doc="Centre of mass from frame_a, resolved in frame_a")
    inertia = Param([[0.0] * 3] * 3, unit="kg*m^2", shape=(3, 3),
                    doc="Inertia about the centre of mass, in frame_a axes (3x3 or diagonal)")
    shape = Param(None, optional=True, kind="choice", choices=SHAPES,
                  doc="What the animation draws at r_cm (None: a small sphere); looks only")
    shape_size = Param(None, optional=True, unit="m", shape=(3,),
                       doc="Box: extents along x, y, z of frame_a; cylinder: length along x, "
                           "diameter; sphere: diameter; looks only")
    color = _color()

    def mass_properties(self):
        """(mass, centre of mass, inertia about it) as CasADi values."""
        return self.mass, vec3(self.r_cm), mat3(self.inertia)

    def check_values(self, values, place):
        size = values.get("shape_size")
        size = [] if size is None else list(size)
        return [f"{place('shape_size')}[{i}] = {v} m: must be >= 0"
                for i, v in enumerate(size) if _numbers(v) is not None and v < 0]


class BodyShape(_CheckedTogether, PartialRigidTransform, library=MB):
    """A rigid body between two frames (MSL's Parts.BodyShape): frame_b is frame_a moved by
    ``r`` (a FixedTranslation), and the mass, centre of mass and inertia are given as a
    RigidBody's on frame_a. A rigid part with mass: it folds into the body before it and
    costs no state, so it hangs from either end alike.

    ``shape``, ``shape_size`` and ``color`` are looks only (MSL's shapeType, length and
    width, color): what an animation draws from frame_a towards frame_b.

    Parameters
    ----------
    r : m, 3 values, required
        Position of frame_b in frame_a.
    mass : kg, >= 0, required
        Mass.
    r_cm : m, 3 values, default [0, 0, 0]
        Centre of mass from frame_a, resolved in frame_a.
    inertia : kg*m^2, 3x3 or its diagonal, default zero
        Inertia about the centre of mass, in frame_a axes.
    shape : "box", "cylinder", "sphere", default "cylinder"
        What the animation draws from frame_a along r; looks only.
    shape_size : m, 3 values >= 0, default None
        Length, width and height of the shape (None: |r|, |r| / 20, |r| / 20); looks only.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    has_mass = True
    frame_a = Port("frame", "Frame a, the body's own (may be left unwired when the body hangs "
                            "from frame_b)", optional=True)
    r = Param(unit="m", shape=(3,), doc="Position of frame_b in frame_a")
    mass = RigidBody.params["mass"]
    r_cm = RigidBody.params["r_cm"]
    inertia = RigidBody.params["inertia"]
    shape = Param("cylinder", kind="choice", choices=SHAPES,
                  doc="What the animation draws from frame_a along r; looks only")
    shape_size = Param(None, optional=True, unit="m", shape=(3,),
                       doc="Length, width, height of the shape (None: |r|, |r|/20, |r|/20); "
                           "looks only")
    color = _color()

    def transform(self, q):
        return ca.SX.eye(3), vec3(self.r)

    mass_properties = RigidBody.mass_properties
    check_values = RigidBody.check_values


class PartialBodyShape(_CheckedTogether, PartialRigidTransform):
    """A solid between two frames: frame_b is frame_a moved by ``r`` (a FixedTranslation),
    and the solid's mass, centre of mass and inertia sit on frame_a (a RigidBody) as MSL's
    Parts.BodyBox and BodyCylinder compute them. A rigid part with mass: it folds into the
    body before it and costs no state.

    The solid starts at ``r_shape`` and extends ``length`` along ``length_direction``; its
    inertia is resolved along these axes of the shape. (MSL's BodyBox and BodyCylinder
    resolve it along ``r`` instead, which differs only when the length direction is not that
    of ``r``: there MSL's inertia is not that of the solid it draws.)
    """
    has_mass = True
    frame_a = Port("frame", "Frame a, the body's own (may be left unwired when the body hangs "
                            "from frame_b)", optional=True)
    r = Param(unit="m", shape=(3,), doc="Position of frame_b in frame_a")
    r_shape = Param([0.0, 0.0, 0.0], unit="m", shape=(3,),
                    doc="Start of the shape from frame_a, resolved in frame_a")
    length_direction = Param(None, optional=True, unit="1", shape=(3,), nonzero=True,
                             doc="Direction of the length, in frame_a (None: r - r_shape)")
    length = Param(None, optional=True, unit="m", min=0.0,
                   doc="Length (None: |r - r_shape|)")

    def transform(self, q):
        return ca.SX.eye(3), vec3(self.r)

    def _length(self):
        if self.length is not None:
            return self.length
        return ca.norm_2(vec3(self.r) - vec3(self.r_shape))

    def _length_axis(self):
        """The length direction as given (not yet of length one)."""
        if self.length_direction is None:
            return vec3(self.r) - vec3(self.r_shape)
        return vec3(self.length_direction)

    def check_values(self, values, place):
        known = self._known(values)
        if known is None:
            return []
        sizes = {k: float(ca.DM(v)) for k, v in self.bound(known).sizes().items()}
        # a pair both left to their defaults (a box's inner_height and height) repeats the
        # pair they follow: it is not reported twice
        return [f"{place(inner)} = {sizes[inner]:.6g} m: must be <= {outer} "
                f"({sizes[outer]:.6g} m)" for inner, outer in self.holes
                if sizes[inner] > sizes[outer]
                and not (known[inner] is None and known[outer] is None)]


class BodyBox(PartialBodyShape, library=MB):
    """A box between frame_a and frame_b, solid or hollow, its mass from its density (MSL's
    Parts.BodyBox).

    frame_b is frame_a moved by ``r``. The box starts at ``r_shape`` and runs ``length``
    along ``length_direction``; ``width`` is measured along ``width_direction`` made
    orthogonal to it and ``height`` along the third axis. A hollow box (``inner_width`` > 0)
    has a hole of ``inner_width`` by ``inner_height`` along its whole length.

    Mass and inertia, as MSL: mo = density*length*width*height, mi =
    density*length*inner_width*inner_height, m = mo - mi, centre of mass r_shape +
    length/2 along the length, and about it, along the box's axes,
    diag(mo*(w^2 + h^2) - mi*(wi^2 + hi^2), mo*(l^2 + h^2) - mi*(l^2 + hi^2),
    mo*(l^2 + w^2) - mi*(l^2 + wi^2)) / 12, resolved in frame_a.

    Parameters
    ----------
    r : m, 3 values, required
        Position of frame_b in frame_a.
    r_shape : m, 3 values, default [0, 0, 0]
        Where the box starts, from frame_a, resolved in frame_a.
    length_direction : 3 values, not zero, default None
        Direction of the length, in frame_a (None: r - r_shape).
    length : m, >= 0, default None
        Length of the box (None: |r - r_shape|).
    width_direction : 3 values, not zero, default [0, 1, 0]
        Direction of the width, in frame_a; its part orthogonal to the length is used.
    width : m, >= 0, default None
        Width (None: length / 20, MSL's world.defaultWidthFraction).
    height : m, >= 0, default None
        Height (None: the width).
    inner_width : m, >= 0 and <= width, default 0
        Width of the hole (0: a solid box).
    inner_height : m, >= 0 and <= height, default None
        Height of the hole (None: inner_width).
    density : kg/m^3, >= 0, default 7700
        Density of the material.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    holes = (("inner_width", "width"), ("inner_height", "height"))
    width_direction = Param([0.0, 1.0, 0.0], unit="1", shape=(3,), nonzero=True,
                            doc="Direction of the width, in frame_a (made orthogonal to the "
                                "length)")
    width = Param(None, optional=True, unit="m", min=0.0,
                  doc="Width (None: length / 20)")
    height = Param(None, optional=True, unit="m", min=0.0, doc="Height (None: width)")
    inner_width = Param(0.0, unit="m", min=0.0, doc="Width of the hole (0: solid)")
    inner_height = Param(None, optional=True, unit="m", min=0.0,
                         doc="Height of the hole (None: inner_width)")
    density = _density()
    color = _color()

    def sizes(self):
        """Length, width, height and those of the hole, defaults filled in."""
        length = self._length()
        width = length / WIDTH_FRACTION if self.width is None else self.width
        height = width if self.height is None else self.height
        inner_height = self.inner_width if self.inner_height is None else self.inner_height
        return {"length": length, "width": width, "height": height,
                "inner_width": self.inner_width, "inner_height": inner_height}

    def mass_properties(self):
        """(mass, centre of mass, inertia about it, in frame_a axes) as CasADi values."""
        s = self.sizes()
        ln, w, h, wi, hi = (s[k] for k in ("length", "width", "height", "inner_width",
                                           "inner_height"))
        mo = self.density * ln * w * h
        mi = self.density * ln * wi * hi
        axes = _axes(self._length_axis(), vec3(self.width_direction))
        moments = ca.vertcat(mo * (w**2 + h**2) - mi * (wi**2 + hi**2),
                             mo * (ln**2 + h**2) - mi * (ln**2 + hi**2),
                             mo * (ln**2 + w**2) - mi * (ln**2 + wi**2)) / 12
        centre = vec3(self.r_shape) + axes[:, 0] * ln / 2
        return mo - mi, centre, axes @ ca.diag(moments) @ axes.T


class BodyCylinder(PartialBodyShape, library=MB):
    """A cylinder between frame_a and frame_b, solid or a tube, its mass from its density
    (MSL's Parts.BodyCylinder).

    frame_b is frame_a moved by ``r``. The cylinder starts at ``r_shape`` and runs
    ``length`` along ``length_direction``.

    Mass and inertia, as MSL, with R = diameter/2 and Ri = inner_diameter/2: mo =
    density*pi*length*R^2, mi = density*pi*length*Ri^2, m = mo - mi, centre of mass r_shape +
    length/2 along the axis; about it, (mo*R^2 - mi*Ri^2)/2 about the axis and
    (mo*(l^2 + 3*R^2) - mi*(l^2 + 3*Ri^2))/12 about any line across it.

    Parameters
    ----------
    r : m, 3 values, required
        Position of frame_b in frame_a.
    r_shape : m, 3 values, default [0, 0, 0]
        Where the cylinder starts, from frame_a, resolved in frame_a.
    length_direction : 3 values, not zero, default None
        Direction of the axis, in frame_a (None: r - r_shape).
    length : m, >= 0, default None
        Length of the cylinder (None: |r - r_shape|).
    diameter : m, >= 0, default None
        Outer diameter (None: length / 20, MSL's world.defaultWidthFraction).
    inner_diameter : m, >= 0 and <= diameter, default 0
        Inner diameter (0: a solid cylinder).
    density : kg/m^3, >= 0, default 7700
        Density of the material.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    holes = (("inner_diameter", "diameter"),)
    diameter = Param(None, optional=True, unit="m", min=0.0,
                     doc="Diameter (None: length / 20)")
    inner_diameter = Param(0.0, unit="m", min=0.0, doc="Inner diameter (0: solid)")
    density = _density()
    color = _color()

    def sizes(self):
        """Length, diameter and inner diameter, defaults filled in."""
        length = self._length()
        diameter = length / WIDTH_FRACTION if self.diameter is None else self.diameter
        return {"length": length, "diameter": diameter,
                "inner_diameter": self.inner_diameter}

    def mass_properties(self):
        """(mass, centre of mass, inertia about it, in frame_a axes) as CasADi values."""
        s = self.sizes()
        ln, ro, ri = s["length"], s["diameter"] / 2, s["inner_diameter"] / 2
        mo = self.density * math.pi * ln * ro**2
        mi = self.density * math.pi * ln * ri**2
        along = (mo * ro**2 - mi * ri**2) / 2
        across = (mo * (ln**2 + 3 * ro**2) - mi * (ln**2 + 3 * ri**2)) / 12
        e = _direction(self._length_axis(), [1.0, 0.0, 0.0])
        # diag(along, across, across) in any axes whose x is e: only e matters
        inertia = across * ca.DM.eye(3) + (along - across) * (e @ e.T)
        return mo - mi, vec3(self.r_shape) + e * ln / 2, inertia


class BodySphere(Component, library=MB):
    """A solid sphere with frame_a at its centre, its mass from its density.

    m = density*pi*d^3/6, centre of mass at frame_a, inertia 2/5*m*(d/2)^2 about every axis.

    Parameters
    ----------
    diameter : m, >= 0, required
        Diameter.
    density : kg/m^3, >= 0, default 7700
        Density of the material.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    role = "body"
    frame_a = Port("frame", "Frame at the centre of the sphere")
    diameter = Param(unit="m", min=0.0, doc="Diameter")
    density = _density()
    color = _color()

    def mass_properties(self):
        """(mass, centre of mass, inertia about it) as CasADi values."""
        mass = self.density * math.pi * self.diameter**3 / 6
        return mass, ca.DM.zeros(3), mass * self.diameter**2 / 10 * ca.DM.eye(3)


from .loopjoints import JointRRR, SphericalSpherical, UniversalSpherical  # noqa: E402,F401
from .forces import (Damper, Force, ForceAndTorque, LineForceWithTwoMasses,  # noqa: E402,F401
                     Spring, SpringDamper, Torque, WorldForce, WorldTorque)
from .rotor import Rotor1D  # noqa: E402,F401

__getattr__ = library_attribute("multibody")
