"""Rolling contact, as Modelica's MultiBody.Joints.RollingWheel and Parts.RollingWheel: a
disk that rolls without slipping on the x-y plane of frame_a.

The wheel is a joint with five coordinates and three speeds. Its coordinates are MSL's: the
position x, y of the wheel centre and the angles that turn frame_a into the wheel's frame
about z, then y, then x (MSL's ``angles``, ``Frames.axesRotations({3, 2, 1}, ...)``, the
wheel axis being the wheel frame's y axis); its speeds are those angles' rates (MSL's
``der_angles``). The height of the centre is no coordinate: the wheel touches the plane (one
holonomic constraint, solved in closed form), and the two non-holonomic constraints of
rolling, no velocity of the contact point along and across the wheel, give the centre's
velocity from the angles' rates: dx/dt and dy/dt are the rates of the coordinates x, y, and
the speeds are independent. So rolling is a joint of reduced generalized speeds: its motion
subspace S(q) (the wheel's velocity per unit speed) holds the constraints, the Newton-Euler
passes over S(q) give Kane's equations of the rolling wheel, and every formulation takes it
as it takes any joint of the tree (no multiplier, no drift of the constraints). The contact
force is the joint's cut force: a probe on frame_b reads it as ``force`` (at the wheel
centre), and ``torque`` is its moment about the centre.
"""

from ..errors import ModelError
from ..spatial import rotation
from .base import REGISTRY, Component, Param, Port, PortRef
from .loopjoints import Expansion
from .multibody import PartialJoint

MB = "multibody"


def _axes():
    """The unit vectors x, y, z of frame_a, as CasADi column vectors."""
    import casadi as ca
    return ca.DM([1, 0, 0]), ca.DM([0, 1, 0]), ca.DM([0, 0, 1])


def wheel_orientation(angles):
    """The wheel frame's axes in frame_a: turned about z by angles[0], then about the new y
    by angles[1], then about the new x by angles[2] (MSL's axesRotations {3, 2, 1})."""
    ex, ey, ez = _axes()
    return rotation(ez, angles[0]) @ rotation(ey, angles[1]) @ rotation(ex, angles[2])


def contact_vector(R, radius):
    """From the wheel centre to the contact point, in frame_a: in the wheel's plane (normal
    to its axis R[:, 1]), ``radius`` long, pointing down the steepest line of that plane
    (MSL's delta_0). Singular where the wheel lies flat (axis along z)."""
    import casadi as ca
    axis = R[:, 1]
    along = ca.cross(_axes()[2], axis)         # the rolling direction (MSL's e_long)
    along = along / ca.norm_2(along)
    return radius * ca.cross(along, axis)


def angular_velocity(angles, rates):
    """The wheel's angular velocity in frame_a from the angles' rates."""
    ex, ey, ez = _axes()
    Rz = rotation(ez, angles[0])
    return rates[0] * ez + rates[1] * (Rz @ ey) + rates[2] * (Rz @ rotation(ey, angles[1]) @ ex)


class RollingWheelJoint(PartialJoint, library=MB):
    """A wheel rolling without slipping on the x-y plane of frame_a (MSL's
    Joints.RollingWheel): frame_b sits at the wheel centre, its y axis along the wheel axis.

    Coordinates: x, y of the wheel centre in frame_a and the angles turning frame_a into
    frame_b about z, y, x (MSL's ``angles``); speeds: the angles' rates (MSL's
    ``der_angles``). The centre's height follows from the contact and its velocity from
    rolling (two non-holonomic constraints held by the joint's motion subspace), so the wheel
    has 5 positional and 3 velocity degrees of freedom. A probe on frame_b reads the contact
    force as ``force``. Massless: wire a body to frame_b (or take ``RollingWheel``). The wheel
    cannot lift off; lying flat (axis normal to the plane) is singular. It must belong to the
    spanning tree: it cannot close a kinematic loop.

    Parameters
    ----------
    radius : m, > 0, required
        Wheel radius.
    x0, y0 : m, default 0
        Initial position of the wheel centre in frame_a.
    angles0 : rad, 3 values, default [0, 0, 0]
        Initial angles about z, y, x (MSL's angles start values).
    der_angles0 : rad/s, 3 values, default [0, 0, 0]
        Initial rates of those angles (MSL's der_angles start values).
    """
    dof = 3
    nq = 5
    regular = False
    constant_subspace = False
    cut_preference = 9                   # never the cut joint while another one can be
    units = ("m", "m", "rad", "rad", "rad")
    frame_a = Port("frame", "Frame whose x-y plane the wheel rolls on (z up, towards the "
                            "wheel)")
    frame_b = Port("frame", "Wheel centre, fixed in the wheel; its y axis is the wheel axis")
    radius = Param(unit="m", positive=True, doc="Wheel radius")
    x0 = Param(0.0, unit="m", doc="Initial x of the wheel centre, in frame_a")
    y0 = Param(0.0, unit="m", doc="Initial y of the wheel centre, in frame_a")
    angles0 = Param([0.0, 0.0, 0.0], shape=(3,), unit="rad",
                    doc="Initial angles turning frame_a into the wheel frame about z, y, x "
                        "(MSL's angles)")
    der_angles0 = Param([0.0, 0.0, 0.0], shape=(3,), unit="rad/s",
                        doc="Initial rates of those angles (MSL's der_angles)")

    def coordinate_labels(self):
        return ["x", "y"] + [f"angles[{i}]" for i in range(3)]

    def speed_labels(self):
        return [f"der_angles[{i}]" for i in range(3)]

    def transform(self, q):
        import casadi as ca
        R = wheel_orientation(q[2:5])
        centre = -contact_vector(R, self.radius)
        return R, ca.vertcat(q[0], q[1], centre[2])

    def rate(self, q, u):
        """dx/dt, dy/dt from rolling (the contact point at rest: v = -w x delta), then the
        angles' rates (the speeds)."""
        import casadi as ca
        R = wheel_orientation(q[2:5])
        v = -ca.cross(angular_velocity(q[2:5], u), contact_vector(R, self.radius))
        return ca.vertcat(v[0], v[1], u)

    def closure(self, rel_R, rel_p, q):
        raise ModelError(f"{self.name}: a rolling wheel cannot close a kinematic loop; build "
                         f"the model so that it belongs to the spanning tree (its frame_a on "
                         f"the ground or on the body it rolls on)")

    def initial(self):
        return [self.x0, self.y0, *self.angles0], list(self.der_angles0)


class RollingWheel(Component, library=MB):
    """A wheel with mass rolling without slipping on the x-y plane of frame_a (MSL's
    Parts.RollingWheel): a RollingWheelJoint with a body of mass ``m`` at its centre,
    inertia ``I_axis`` about the wheel axis (frame_b's y) and ``I_long`` about any
    diameter. frame_b is the wheel centre; the wheel's states are
    ``<name>.joint.x``, ``.y``, ``.angles[i]`` and ``.der_angles[i]``.

    Parameters
    ----------
    radius : m, > 0, required
        Wheel radius.
    m : kg, >= 0, required
        Mass of the wheel.
    I_axis : kg*m^2, >= 0, required
        Inertia about the wheel axis.
    I_long : kg*m^2, >= 0, required
        Inertia about a diameter (normal to the axis).
    x0, y0 : m, default 0
        Initial position of the wheel centre in frame_a.
    angles0 : rad, 3 values, default [0, 0, 0]
        Initial angles about z, y, x (MSL's angles start values).
    der_angles0 : rad/s, 3 values, default [0, 0, 0]
        Initial rates of those angles (MSL's der_angles start values).
    """
    role = "aggregate"
    frame_a = Port("frame", "Frame whose x-y plane the wheel rolls on (z up)")
    frame_b = Port("frame", "Wheel centre, fixed in the wheel; its y axis is the wheel axis",
                   optional=True)
    radius = RollingWheelJoint.params["radius"]
    m = Param(unit="kg", min=0.0, doc="Mass of the wheel")
    I_axis = Param(unit="kg*m^2", min=0.0, doc="Inertia about the wheel axis")
    I_long = Param(unit="kg*m^2", min=0.0, doc="Inertia about a diameter of the wheel")
    x0 = RollingWheelJoint.params["x0"]
    y0 = RollingWheelJoint.params["y0"]
    angles0 = RollingWheelJoint.params["angles0"]
    der_angles0 = RollingWheelJoint.params["der_angles0"]

    def expand(self):
        """The joint and the wheel's body on its frame_b."""
        joint = RollingWheelJoint("joint", radius=self.radius, x0=self.x0, y0=self.y0,
                                  angles0=self.angles0, der_angles0=self.der_angles0)
        body = REGISTRY[f"{MB}.RigidBody"]("body", mass=self.m,
                                           inertia=[self.I_long, self.I_axis, self.I_long])
        comps = {"joint": joint, "body": body}
        return Expansion(self.name, comps,
                         [(PortRef(joint, "frame_b"), PortRef(body, "frame_a"))],
                         {"frame_a": PortRef(joint, "frame_a"),
                          "frame_b": PortRef(joint, "frame_b")})


__all__ = ["RollingWheel", "RollingWheelJoint"]
