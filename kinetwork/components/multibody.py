"""Multibody components: ground, joints, bodies and rigid parts, declared by geometry.

A joint gives the transform of frame_b relative to frame_a as a function of its coordinates;
the solver's Newton-Euler passes derive everything else from it.
"""

import casadi as ca

from ..spatial import mat3, rotation, unit, vec3
from .base import Component, Param, Port

MB = "multibody"


class Ground(Component, library=MB):
    """The inertial world frame, with the gravity field of the model."""
    role = "world"
    frame = Port("frame", "World frame")
    gravity = Param([0.0, -9.81, 0.0], unit="m/s^2", shape=(3,),
                    doc="Gravity acceleration, resolved in the world frame")


class PartialRigidTransform(Component):
    """Two frames at a transform fixed by parameters: costs no state."""
    role = "joint"
    dof = 0
    constant_subspace = True
    frame_a = Port("frame", "Frame a")
    # a dangling end of a rigid part is a marker frame (for probes), as in Modelica
    frame_b = Port("frame", "Frame b, at the fixed transform from frame_a", optional=True)


class FixedTranslation(PartialRigidTransform, library=MB):
    """frame_b = frame_a moved by ``r`` (resolved in frame_a)."""
    r = Param(unit="m", shape=(3,), doc="Position of frame_b in frame_a")

    def transform(self, q):
        return ca.SX.eye(3), vec3(self.r)


class FixedRotation(PartialRigidTransform, library=MB):
    """frame_b = frame_a moved by ``r``, then rotated by ``angle`` about ``axis``."""
    r = Param([0.0, 0.0, 0.0], unit="m", shape=(3,), doc="Position of frame_b in frame_a")
    direction = Param([0.0, 0.0, 1.0], shape=(3,), nonzero=True, name="axis",
                      doc="Rotation axis, resolved in frame_a")
    angle = Param(unit="rad", doc="Rotation angle about axis")

    def transform(self, q):
        return rotation(vec3(self.direction), self.angle), vec3(self.r)


class PartialJoint(PartialRigidTransform):
    """One degree of freedom between frame_a and frame_b, with its two 1-D flanges.

    ``axis`` (potential = q) drives the joint; ``support`` (potential 0) is its reaction side,
    taken, as in Modelica MultiBody, to rest in the world frame.
    """
    dof = 1
    frame_b = Port("frame", "Frame b, moved by the joint coordinate")
    coordinate_ports = {"axis": 0}
    zero_ports = ("support",)
    axis = Port("1d", "Flange driving the joint coordinate", optional=True)
    support = Port("1d", "Reaction flange of the drive", optional=True)
    direction = Param([0.0, 0.0, 1.0], shape=(3,), nonzero=True, name="axis",
                      doc="Joint axis, resolved in frame_a")
    q0 = Param(None, optional=True, doc="Initial coordinate (None: 0, or solved in a loop)")
    qd0 = Param(None, optional=True, doc="Initial coordinate speed (None: 0)")
    q0_guess = Param(0.0, doc="Start of the search for q0 when it is solved in a loop")
    cut = Param(False, kind="bool", doc="Cut the kinematic loop at this joint")


class Revolute(PartialJoint, library=MB):
    """frame_b is frame_a rotated by q about ``axis`` (resolved in frame_a)."""
    domain = "rotational"
    units = ("rad", "rad/s")

    def transform(self, q):
        return rotation(vec3(self.direction), q[0]), ca.SX.zeros(3)


class Prismatic(PartialJoint, library=MB):
    """frame_b is frame_a moved by q along ``axis`` (resolved in frame_a)."""
    domain = "translational"
    units = ("m", "m/s")
    direction = Param([1.0, 0.0, 0.0], shape=(3,), nonzero=True, name="axis",
                      doc="Direction of motion, resolved in frame_a")

    def transform(self, q):
        return ca.SX.eye(3), unit(vec3(self.direction)) * q[0]


class RigidBody(Component, library=MB):
    """Mass and inertia attached to frame_a."""
    role = "body"
    frame_a = Port("frame", "Frame the body is fixed to")
    mass = Param(unit="kg", min=0.0, doc="Mass")
    r_cm = Param([0.0, 0.0, 0.0], unit="m", shape=(3,),
                 doc="Centre of mass from frame_a, resolved in frame_a")
    inertia = Param([[0.0] * 3] * 3, unit="kg*m^2", shape=(3, 3),
                    doc="Inertia about the centre of mass, in frame_a axes (3x3 or diagonal)")

    def mass_properties(self):
        """(mass, centre of mass, inertia about it) as CasADi values."""
        return self.mass, vec3(self.r_cm), mat3(self.inertia)
