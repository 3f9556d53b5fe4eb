"""A 1-D rotor mounted on a body with its gyroscopic effects, as Modelica's
MultiBody.Parts.Rotor1D (with world.driveTrainMechanics3D and exact = true).

MSL's rotor is an inertia J turning about the axis n fixed in its housing frame_a, by the
angle phi of its flanges relative to frame_a. It exerts on its carrier the torque of its
spin, cross(w_a, J n w) - n J (n . der(w_a)), and takes J (a + n . der(w_a)) = the flanges'
torque: the part of its angular momentum J n (n . w_a) that turns with the carrier is left
to the carrier, which carries the rotor's mass and whole inertia as a rigid body (MSL's
GyroscopicEffects: a BodyCylinder fixed to the mount plus a Rotor1D of its axial inertia
move exactly as the same cylinder on a revolute).

Compiled, a Rotor1D is what that amounts to: a revolute about n from frame_a (its
coordinate is phi, its axis flange both of the rotor's flanges) carrying an inertia J n n^T,
and on frame_a the inertia -J n n^T, which takes back the share the carrier already holds;
its kinetic energy is J w^2 / 2 + J w (n . w_a), MSL's. A torque on the rotor's flanges is
the revolute's generalized force, so it reacts on the carrier, as MSL's does through a
Mounting1D on frame_a with the same axis: ``support`` is that flange (wiring a source's
support to it, or leaving the source's support unwired, is the same). The cut-force probes
of frames near the rotor take the reaction to rest in the world, as for any joint's drive.
"""

import numbers

from ..spatial import unit, vec3
from .base import REGISTRY, Component, Param, Port, PortRef
from .loopjoints import Expansion

MB = "multibody"


def _axial(J, n, sign):
    """sign * J n n^T / |n|^2, in numbers when J and n are numbers, else in expressions."""
    if isinstance(J, numbers.Real) and all(isinstance(v, numbers.Real) for v in n):
        norm2 = sum(v * v for v in n)
        return [[sign * J * a * b / norm2 for b in n] for a in n]
    norm2 = " + ".join(f"({v})*({v})" for v in n)
    return [[f"{sign}*({J})*({a})*({b})/({norm2})" for b in n] for a in n]


class RotorHousing(Component):
    """The share of a rotor's inertia its carrier already holds, taken back: the inertia
    -J n n^T on frame_a (part of a compiled Rotor1D, no file type: it is never placed)."""
    role = "body"
    frame_a = Port("frame", "The rotor's housing frame")
    J = Param(unit="kg*m^2", min=0.0, doc="Moment of inertia of the rotor about its axis")
    n = Param([1.0, 0.0, 0.0], unit="1", shape=(3,), nonzero=True,
              doc="Rotor axis, in frame_a")

    def mass_properties(self):
        import casadi as ca
        e = unit(vec3(self.n))
        return 0.0, ca.DM.zeros(3), -self.J * (e @ e.T)


class Rotor1D(Component, library=MB):
    """A 1-D inertia ``J`` turning about the axis ``n`` fixed in frame_a, with its
    gyroscopic effects on the carrier (MSL's Parts.Rotor1D, exact, with
    world.driveTrainMechanics3D).

    flange_a and flange_b are the rotor: their angle phi is relative to frame_a. As in MSL,
    the carrier holds the rotor's mass and inertia as a rigid body; the rotor adds what its
    spin relative to frame_a does (the torque cross(w_a, J n w) - n J (n . der(w_a)) on
    frame_a). A torque on the flanges reacts on the carrier, as through MSL's Mounting1D with
    the same axis on frame_a; ``support`` is that flange. Its states are ``<name>.spin.q``
    and ``<name>.spin.qd`` (phi and w).

    Parameters
    ----------
    J : kg*m^2, >= 0, required
        Moment of inertia of the rotor about its axis.
    n : 3 values, default [1, 0, 0]
        Rotor axis, resolved in frame_a.
    phi0 : rad, default None
        Initial angle relative to frame_a (None: 0).
    w0 : rad/s, default None
        Initial angular speed relative to frame_a (None: 0).
    """
    role = "aggregate"
    frame_a = Port("frame", "Frame the rotor's housing is fixed in")
    flange_a = Port("rotational", "Flange of the rotor (angle relative to frame_a)",
                    optional=True)
    flange_b = Port("rotational", "Flange of the rotor (the same angle)", optional=True)
    support = Port("rotational", "Housing flange on frame_a (MSL's Mounting1D): the reaction "
                                 "of a torque on the rotor", optional=True)
    J = Param(unit="kg*m^2", min=0.0, doc="Moment of inertia of the rotor about its axis")
    n = Param([1.0, 0.0, 0.0], unit="1", shape=(3,), nonzero=True,
              doc="Rotor axis, resolved in frame_a")
    phi0 = Param(None, optional=True, unit="rad",
                 doc="Initial angle relative to frame_a (None: 0)")
    w0 = Param(None, optional=True, unit="rad/s",
               doc="Initial angular speed relative to frame_a (None: 0)")

    def expand(self):
        """A revolute about n with the inertia J n n^T, and -J n n^T on frame_a."""
        spin = REGISTRY[f"{MB}.Revolute"]("spin", n=self.n, q0=self.phi0, qd0=self.w0)
        rotor = REGISTRY[f"{MB}.RigidBody"]("rotor", mass=0.0,
                                            inertia=_axial(self.J, self.n, 1))
        housing = RotorHousing("housing", J=self.J, n=self.n)
        comps = {c.name: c for c in (spin, rotor, housing)}
        wires = [(PortRef(spin, "frame_b"), PortRef(rotor, "frame_a")),
                 (PortRef(spin, "frame_a"), PortRef(housing, "frame_a"))]
        exposed = {"frame_a": PortRef(spin, "frame_a"), "flange_a": PortRef(spin, "axis"),
                   "flange_b": PortRef(spin, "axis"), "support": PortRef(spin, "support")}
        return Expansion(self.name, comps, wires, exposed)


__all__ = ["Rotor1D"]
