"""Multibody components: the ground, the rigid parts and the joints, declared by geometry.

A joint gives the transform of frame_b relative to frame_a as a function of its coordinates;
the solver's Newton-Euler passes derive everything else from it. The library's bodies
(``bodies.py``), force elements on frames (``forces.py``), loop joints (``loopjoints.py``)
and rotor (``rotor.py``) are declared in modules of their own and are part of it too
(``kn.multibody.RigidBody``).
"""

import math

import numpy as np

from ..errors import ModelError
from ..expr import casadi_functions, parse
from ..spatial import (cardan_quat, eye3, mat3, quat_rate, quat_rotation, rotation, unit, vec3,
                       zero3)
from .base import COORDINATES, RATES, Component, Param, Port, library_attribute
from .frames import PartialRigidTransform

MB = "multibody"


#: gravity fields a Ground may have (MSL's World.gravityType, less NoGravity: a uniform zero;
#: "expression" is MSL's redeclared gravityAcceleration function)
GRAVITY_TYPES = ("uniform", "point", "expression")
#: names a gravity field's expressions read for the world point (besides t and parameters)
FIELD_NAMES = ("x", "y", "z")


class FieldParam(Param):
    """Three expressions of the world point (x, y, z), time t and the model's parameters:
    parsed and checked for form here, their names where the model is compiled."""

    def __init__(self, doc=""):
        super().__init__(None, optional=True, shape=(3,), unit="m/s^2", kind="expression",
                         doc=doc)

    def normalize(self, value, where):
        if value is None:
            return None
        if isinstance(value, np.ndarray):
            value = value.tolist()
        if not isinstance(value, (list, tuple)) or len(value) != 3:
            raise ModelError(f"{where}: must be 3 expressions in x, y, z (the world point), "
                             f"t and the model's parameters, got {value!r}")
        out = []
        for i, v in enumerate(value):
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                out.append(float(v))
                continue
            if not isinstance(v, str) or not v.strip():
                raise ModelError(f"{where}[{i}]: must be a number or an expression, got "
                                 f"{v!r}")
            try:
                parse(v)
            except ModelError as exc:
                raise ModelError(f"{where}[{i}]: {exc}") from None
            out.append(v)
        return out


class Ground(Component, library=MB):
    """The inertial world frame, with the gravity field of the model.

    The field is uniform (``gravity``), or that of a point mass at the world origin
    (``gravity_type`` "point", MSL's World with gravityType PointGravity): -mue/|r|^2 along r
    at the world point r, or any field the user writes (``gravity_type`` "expression", MSL's
    redeclared world.gravityAcceleration: ``field``, three expressions in the world point x,
    y, z, the time t and the model's parameters, such as MSL's WGS84 normal gravity in
    UserDefinedGravityField). A field acts on every body at its centre of mass (so a body
    feels a torque about its frame only through its centre-of-mass offset, as in MSL; no
    gravity-gradient torque).

    Parameters
    ----------
    gravity : m/s^2, 3 values, default [0, -9.81, 0]
        Uniform gravity acceleration, in the world frame (not used by a point field).
    gravity_type : "uniform", "point" or "expression", default "uniform"
        Kind of gravity field.
    mue : m^3/s^2, >= 0, default 3.986004418e14 (the Earth's)
        Field constant of the point field, G times the central mass (MSL's mu).
    field : m/s^2, 3 expressions, default None
        The gravity acceleration at the world point (x, y, z), in the world frame, for
        ``gravity_type`` "expression": e.g. ["0", "-9.81*(1 - 2*y/6.371e6)", "0"].
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
    field = FieldParam(doc="Gravity acceleration at the world point (x, y, z), in the world "
                           "frame: 3 expressions in x, y, z, t and the model's parameters "
                           "(gravity_type 'expression')")
    #: the model's parameters and t, as the compiler binds them (names a field may read)
    _environment = {}

    def uniform_gravity(self):
        """The gravity vector of a uniform field, or None for a point field."""
        return vec3(self.gravity) if self.gravity_type == "uniform" else None

    def gravity_at(self, r):
        """Gravity acceleration at the world point ``r`` (CasADi)."""
        import casadi as ca
        if self.gravity_type == "uniform":
            return vec3(self.gravity)
        if self.gravity_type == "point":
            return -self.mue * r / ca.norm_2(r) ** 3
        env = {**self._environment, **dict(zip(FIELD_NAMES, ca.vertsplit(r)))}
        out = []
        for i, v in enumerate(self.field):
            if isinstance(v, float):
                out.append(ca.SX(v))
                continue
            expr = parse(v)
            unknown = sorted(expr.names - set(env))
            if unknown:
                raise ModelError(f"{self.name}.field[{i}]: unknown name {unknown[0]!r}: a "
                                 f"gravity field reads x, y, z (the world point), t and the "
                                 f"model's parameters")
            out.append(ca.SX(expr.evaluate(env, casadi_functions())))
        return ca.vertcat(*out)

    def check_values(self, values, place):
        expression = values.get("gravity_type") == "expression"
        if expression and values.get("field") is None:
            return [f"{place('field')}: gravity_type 'expression' needs the field, three "
                    f"expressions in x, y, z"]
        if not expression and values.get("field") is not None:
            return [f"{place('field')}: a field is used with gravity_type 'expression' "
                    f"only (here {values.get('gravity_type')!r})"]
        return []


class FixedTranslation(PartialRigidTransform, library=MB):
    """frame_b = frame_a moved by ``r`` (resolved in frame_a)."""
    r = Param(unit="m", shape=(3,), doc="Position of frame_b in frame_a")

    def transform(self, q):
        return eye3(), vec3(self.r)


class FixedRotation(PartialRigidTransform, library=MB):
    """frame_b = frame_a moved by ``r``, then rotated by ``angle`` about ``axis``."""
    r = Param([0.0, 0.0, 0.0], unit="m", shape=(3,), doc="Position of frame_b in frame_a")
    axis = Param([0.0, 0.0, 1.0], unit="1", shape=(3,), nonzero=True,
                 doc="Rotation axis, resolved in frame_a")
    angle = Param(unit="rad", doc="Rotation angle about axis")

    def transform(self, q):
        return rotation(vec3(self.axis), self.angle), vec3(self.r)


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
    """One degree of freedom along or about the direction ``n``, with two 1-D flanges.

    As in Modelica MultiBody, ``n`` is the direction and ``axis`` the flange: ``axis``
    (potential = q) drives the joint; ``support`` (potential 0) is its reaction side, taken
    to rest in the world frame. ``n`` is also given as ``axis=[...]`` (its name in files
    before, still read, and saved as written).
    """
    coordinate_ports = {"axis": 0}
    zero_ports = ("support",)
    axis = Port("1d", "Flange driving the joint coordinate", optional=True)
    support = Port("1d", "Reaction flange of the drive", optional=True)
    n = Param([0.0, 0.0, 1.0], unit="1", shape=(3,), nonzero=True, aliases=("axis",),
              doc="Joint axis, resolved in frame_a")
    q0 = Param(None, optional=True, unit=COORDINATES,
               doc="Initial coordinate (None: 0, or solved in a loop)")
    qd0 = Param(None, optional=True, unit=RATES, doc="Initial coordinate speed (None: 0)")
    q0_guess = Param(0.0, unit=COORDINATES,
                     doc="Start of the search for q0 when it is solved in a loop")


class Revolute(PartialAxisJoint, library=MB):
    """frame_b is frame_a rotated by q about ``n`` (resolved in frame_a)."""
    domain = "rotational"
    units = ("rad",)

    def transform(self, q):
        return rotation(vec3(self.n), q[0]), zero3()


class Prismatic(PartialAxisJoint, library=MB):
    """frame_b is frame_a moved by q along ``n`` (resolved in frame_a)."""
    domain = "translational"
    units = ("m",)
    n = Param([1.0, 0.0, 0.0], unit="1", shape=(3,), nonzero=True, aliases=("axis",),
              doc="Direction of motion, resolved in frame_a")

    def transform(self, q):
        return eye3(), unit(vec3(self.n)) * q[0]


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
        return rotation(vec3(self.n_a), q[0]) @ rotation(vec3(self.n_b), q[1]), zero3()


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
    axis = Param([0.0, 0.0, 1.0], unit="1", shape=(3,), nonzero=True,
                 doc="Axis of rotation and translation, resolved in frame_a")
    q0 = _pair("Initial angle and distance (None: 0, or solved in a loop)")
    qd0 = _pair("Initial angular and linear speed (None: 0)", RATES)
    q0_guess = Param([0.0, 0.0], shape=(2,), unit=COORDINATES,
                     doc="Start of the search for q0 in a loop")

    def transform(self, q):
        n = vec3(self.axis)
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
        import casadi as ca
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
        return quat_rotation(q), zero3()

    def subspace(self, q):
        import casadi as ca
        return ca.vertcat(ca.SX.eye(3), ca.SX.zeros(3, 3))

    def rate(self, q, u):
        return quat_rate(q, u)

    def closure(self, rel_R, rel_p, q):
        return rel_p                               # cut: the origins meet

    def initial(self):
        import casadi as ca
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

    A FreeMotion whose frame_b carries nothing but PointMasses (MSL's PointMass alone on a
    FreeMotion) moves them without turning: no body it carries has rotational inertia, so its
    orientation is not a state. Its coordinates are then r only, its speeds v, frame_b keeps
    the orientation angles0 gives (MSL's unit rotation by default) and w0, if given, must be
    zero (``graph/tree.py`` finds it).
    """
    nq = 7
    #: True while frame_b carries only point masses (set with each model's topology)
    _translation_only = False
    regular = False
    constant_subspace = False
    cut_preference = 0        # cutting it removes nothing: the first choice
    r0 = Param(None, optional=True, shape=(3,), unit="m",
               doc="Initial position, in frame_a (None: 0, or free in a loop)")
    v0 = Param(None, optional=True, shape=(3,), unit="m/s",
               doc="Initial velocity, in frame_a (None: 0, or free in a loop)")
    angles0 = Param(None, optional=True, shape=(3,), unit="rad",
                    doc="Initial orientation: body-fixed x-y-z (Cardan) angles (None: 0, or "
                        "free in a loop)")
    w0 = Param(None, optional=True, shape=(3,), unit="rad/s",
               doc="Initial angular velocity, resolved in frame_b (None: 0, or free in a loop)")

    @property
    def dof(self):
        return 3 if self._translation_only else 6

    def n_coordinates(self):
        return 3 if self._translation_only else 7

    @property
    def units(self):
        return ("m",) * 3 + (() if self._translation_only else ("",) * 4)

    def speed_units(self):
        return ["m/s"] * 3 + ([] if self._translation_only else ["rad/s"] * 3)

    def coordinate_labels(self):
        return [f"r[{i}]" for i in range(3)] + \
            ([] if self._translation_only else [f"quat[{i}]" for i in range(4)])

    def speed_labels(self):
        return [f"v[{i}]" for i in range(3)] + \
            ([] if self._translation_only else [f"w[{i}]" for i in range(3)])

    def _held(self):
        """frame_b's orientation where it does not turn: angles0's (else none)."""
        return quat_rotation(cardan_quat([0.0] * 3 if self.angles0 is None else self.angles0))

    def transform(self, q):
        if self._translation_only:
            return self._held(), q[0:3]
        return quat_rotation(q[3:7]), q[0:3]

    def subspace(self, q):
        # spatial velocity of frame_b in its own axes: [w; R^T v]
        import casadi as ca
        if self._translation_only:
            return ca.vertcat(ca.SX.zeros(3, 3), ca.SX(self._held().T))
        Rt = quat_rotation(q[3:7]).T
        return ca.blockcat([[ca.SX.zeros(3, 3), ca.SX.eye(3)], [Rt, ca.SX.zeros(3, 3)]])

    def rate(self, q, u):
        import casadi as ca
        if self._translation_only:
            return u
        return ca.vertcat(u[0:3], quat_rate(q[3:7], u[3:6]))

    def closure(self, rel_R, rel_p, q):
        import casadi as ca
        return ca.SX(0, 1)                         # cut: it constrains nothing

    def initial(self):
        import casadi as ca

        def given(v):
            return [0.0] * 3 if v is None else list(v)
        if self._translation_only:
            return given(self.r0), given(self.v0)
        return ([*given(self.r0), *ca.vertsplit(cardan_quat(given(self.angles0)))],
                [*given(self.v0), *given(self.w0)])

    def start_conditions(self, rel_R, rel_p, rel_v, rel_w):
        """As a loop's cut joint: the rows of its given start values, each zero when frame_b
        starts where they say (at ``rel_R``, ``rel_p`` in frame_a, moving at ``rel_v`` in
        frame_a and ``rel_w`` in frame_b): (position rows, speed rows), each a list of (SX,
        the parameter it comes from)."""
        import casadi as ca
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


from .bodies import (BodyBox, BodyCylinder, BodyShape, BodySphere,  # noqa: E402,F401
                     RigidBody)
from .loopjoints import JointRRR, SphericalSpherical, UniversalSpherical  # noqa: E402,F401
from .pointmass import PointMass  # noqa: E402,F401
from .assemblies import (JointRRP, JointSSP, JointSSR, JointUPS, JointUSP,  # noqa: E402,F401
                         JointUSR)
from .forces import (Damper, Force, ForceAndTorque, LineForceWithTwoMasses,  # noqa: E402,F401
                     Spring, SpringDamper, Torque, WorldForce, WorldTorque)
from .rotor import Rotor1D  # noqa: E402,F401

__getattr__ = library_attribute("multibody")
