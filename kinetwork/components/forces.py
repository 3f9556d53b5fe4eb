"""Force elements on frames, as Modelica's MultiBody.Forces: line forces between two frame
origins (with an optional point mass on the line), forces and torques between two frames
resolved in any frame, and forces and torques given in the world.

A force element declares what it applies, not how it moves anything: ``wrenches`` gives the
force and torque it exerts on each frame it is wired to, from the frames' poses and speeds
(and its signal inputs); ``point_masses`` lists the masses it carries, each at a fixed
weighted mean of its frames' origins. The solver turns both into generalized forces and
inertia, once, for all of them.
"""

from ..spatial import line_length, zero3
from .base import Component, Param, Port

MB = "multibody"
#: frames a Force, Torque or ForceAndTorque may resolve its vectors in (MSL's ResolveInFrameAB)
RESOLVE_AB = ("world", "frame_a", "frame_b", "frame_resolve")
#: frames a WorldForce or WorldTorque may resolve its vector in
RESOLVE_B = ("world", "frame_b")


class PartialFrameForce(Component):
    """A force element on frames.

    ``wrenches(frames, inputs)`` gives ``{port: (force, torque)}``: what the element applies
    on each of its frames, resolved in the world, the force acting at the frame's origin.
    ``frames[port]`` has the frame's world orientation ``R``, origin ``r``, velocity ``v`` and
    angular velocity ``w`` (None for an optional port left unwired); ``inputs[port]`` is the
    value of a signal input (None when unwired). A port left out of the result gets nothing.

    ``point_masses()`` gives ``[(mass, {port: weight})]``: point masses at sum(weight * r)
    over the frames' origins (weights summing to one) that move with the frames; the solver
    adds their inertia and weight, and splits their inertial force over the frames by the
    same weights, as MSL's LineForceWithMass does.
    """
    role = "frame_force"

    def signal_unit(self, port):
        """Force components f1..f3 in N, torque components t1..t3 in N*m."""
        return {"f": "N", "t": "N*m"}.get(port[:1]) if port[1:] in ("1", "2", "3") else None

    def wrenches(self, frames, inputs):
        raise NotImplementedError

    def point_masses(self):
        return []


def _given(param, ports, inputs):
    """A 3-vector parameter with each entry replaced by its signal input where that is wired."""
    import casadi as ca
    return ca.vertcat(*[param[i] if inputs.get(p) is None else inputs[p]
                        for i, p in enumerate(ports)])


def _signals(name, what):
    return [Port("signal_in", f"{what} {i + 1} (replaces {name}[{i}] when wired)",
                 optional=True) for i in range(3)]


def _point_mass():
    """The ``mass`` and ``length_fraction`` of a line force, declared after its law's
    parameters (so forms and files list c, d first)."""
    return (Param(0.0, unit="kg", min=0.0,
                  doc="Point mass on the line (0: none), as MSL's Spring m"),
            Param(0.5, unit="1", min=0.0, max=1.0,
                  doc="Where the point mass sits: its distance from frame_a as a fraction of "
                      "the distance from frame_a to frame_b"))


# -- line forces ---------------------------------------------------------------------------
class PartialLineForce(PartialFrameForce):
    """A force along the line between the origins of frame_a and frame_b, with an optional
    point mass on that line (MSL's Forces.Spring with m > 0, built on LineForceWithMass).

    ``law(s, s_d)`` gives the tension f from the distance s and its rate: f > 0 pulls the
    frames together (a stretched spring), as in Modelica's Forces.Spring. The point mass
    ``mass`` sits at ``length_fraction`` of the way from frame_a to frame_b; its inertial
    force and weight, m (a - g), act on frame_a with the share 1 - length_fraction and on
    frame_b with length_fraction (MSL: frame_a.f = m (1 - h) ag - e fa, frame_b.f = m h ag +
    e fa), which is exactly the virtual work of a point mass held at that spot.
    """
    frame_a = Port("frame", "Frame a")
    frame_b = Port("frame", "Frame b")

    def law(self, s, s_d):
        raise NotImplementedError

    def wrenches(self, frames, inputs):
        import casadi as ca
        a, b = frames["frame_a"], frames["frame_b"]
        d = b.r - a.r
        s = line_length(d)        # regularised: no force, and no NaN, at zero length
        e = d / s
        force = self.law(s, ca.dot(e, b.v - a.v)) * e
        return {"frame_a": (force, zero3()), "frame_b": (-force, zero3())}

    def point_masses(self):
        h = self.length_fraction
        return [(self.mass, {"frame_a": 1 - h, "frame_b": h})]


class SpringDamper(PartialLineForce, library=MB):
    """Linear spring and damper in parallel between two frame origins; optionally with a
    point mass on the line (``mass``, ``length_fraction``)."""
    c = Param(unit="N/m", min=0.0, doc="Spring constant")
    d = Param(unit="N*s/m", min=0.0, doc="Damping constant")
    s_unstretched = Param(0.0, unit="m", min=0.0, doc="Unstretched length")
    mass, length_fraction = _point_mass()

    def law(self, s, s_d):
        return self.c * (s - self.s_unstretched) + self.d * s_d


class Spring(PartialLineForce, library=MB):
    """Linear spring between two frame origins (MSL's Forces.Spring); optionally with a point
    mass on the line (``mass``, ``length_fraction``)."""
    c = Param(unit="N/m", min=0.0, doc="Spring constant")
    s_unstretched = Param(0.0, unit="m", min=0.0, doc="Unstretched length")
    mass, length_fraction = _point_mass()

    def law(self, s, s_d):
        return self.c * (s - self.s_unstretched)


class Damper(PartialLineForce, library=MB):
    """Linear damper between two frame origins; optionally with a point mass on the line
    (``mass``, ``length_fraction``)."""
    d = Param(unit="N*s/m", min=0.0, doc="Damping constant")
    mass, length_fraction = _point_mass()

    def law(self, s, s_d):
        return self.d * s_d


class AlongLine(dict):
    """Where a point mass sits on the line from frame_a's origin to frame_b's: ``distance``
    from the origin of ``port`` towards the other one (MSL's LineForceWithTwoMasses: L_a
    from frame_a, L_b from frame_b). Its keys are the two ports; ``position(origins)`` places
    it, and the solver shares its inertial force over the frames by d(position)/d(origin)."""

    def __init__(self, port, distance):
        super().__init__(frame_a=None, frame_b=None)
        self.port, self.distance = port, distance

    def position(self, origins):
        d = origins["frame_b"] - origins["frame_a"]
        e = d / line_length(d)
        return (origins["frame_a"] + self.distance * e if self.port == "frame_a"
                else origins["frame_b"] - self.distance * e)


class LineForceWithTwoMasses(PartialLineForce, library=MB):
    """A spring and damper between two frame origins with two point masses on their line
    (MSL's Forces.LineForceWithTwoMasses): ``m_a`` at distance ``L_a`` from frame_a towards
    frame_b and ``m_b`` at ``L_b`` from frame_b towards frame_a, as the two halves of a
    hydraulic cylinder. The masses move with the line; their inertial force and weight act
    on the two frames by virtual work (MSL's f1, f2 with aux2). MSL's 1-D flanges are given
    here by the law's ``c``, ``d`` and ``s_unstretched`` (a Translational SpringDamper
    between them: tension c (s - s_unstretched) + d ds/dt).

    Parameters
    ----------
    m_a, m_b : kg, >= 0, default 0
        Point masses near frame_a and near frame_b.
    L_a : m, default 0
        Distance of m_a from frame_a, towards frame_b.
    L_b : m, default None
        Distance of m_b from frame_b, towards frame_a (None: L_a, as MSL).
    c : N/m, >= 0, default 0
        Spring constant of the line force.
    d : N*s/m, >= 0, default 0
        Damping constant of the line force.
    s_unstretched : m, >= 0, default 0
        Unstretched length of the spring.
    """
    m_a = Param(0.0, unit="kg", min=0.0, doc="Point mass at L_a from frame_a")
    m_b = Param(0.0, unit="kg", min=0.0, doc="Point mass at L_b from frame_b")
    L_a = Param(0.0, unit="m", doc="Distance of m_a from frame_a, towards frame_b")
    L_b = Param(None, optional=True, unit="m",
                doc="Distance of m_b from frame_b, towards frame_a (None: L_a)")
    c = Param(0.0, unit="N/m", min=0.0, doc="Spring constant of the line force")
    d = Param(0.0, unit="N*s/m", min=0.0, doc="Damping constant of the line force")
    s_unstretched = Param(0.0, unit="m", min=0.0, doc="Unstretched length of the spring")

    def law(self, s, s_d):
        return self.c * (s - self.s_unstretched) + self.d * s_d

    def point_masses(self):
        L_b = self.L_a if self.L_b is None else self.L_b
        return [(self.m_a, AlongLine("frame_a", self.L_a)),
                (self.m_b, AlongLine("frame_b", L_b))]


# -- forces and torques between two frames ---------------------------------------------------
def _resolve_in():
    return Param("frame_b", kind="choice", choices=RESOLVE_AB,
                 doc="Frame the vectors are resolved in: world, frame_a, frame_b or "
                     "frame_resolve")


class PartialResolved(PartialFrameForce):
    """A force and/or torque acting on frame_b, its reaction on frame_a (MSL's
    Forces.Force, Torque and ForceAndTorque).

    The vectors are given in the frame ``resolve_in`` names: the world, frame_a, frame_b, or
    the frame wired to ``frame_resolve`` (which then must be wired; it takes no force). On
    frame_b act the force f at its origin and the torque t; on frame_a act -f at its origin
    and -t - r_ab x f, r_ab from frame_a's origin to frame_b's (MSL's PartialForce balance:
    the element as a whole exerts no net force or moment).
    """
    frame_a = Port("frame", "Frame the reaction acts on")
    frame_b = Port("frame", "Frame the force and torque act on")
    frame_resolve = Port("frame", "Frame the vectors are resolved in when resolve_in is "
                                  "frame_resolve; takes no force", optional=True)

    def required_ports(self):
        return ("frame_resolve",) if self.resolve_in == "frame_resolve" else ()

    def force(self, inputs):
        """The force as given (resolved in ``resolve_in``)."""
        return zero3()

    def torque(self, inputs):
        """The torque as given (resolved in ``resolve_in``)."""
        return zero3()

    def wrenches(self, frames, inputs):
        import casadi as ca
        a, b = frames["frame_a"], frames["frame_b"]
        R = ca.DM.eye(3) if self.resolve_in == "world" else frames[self.resolve_in].R
        f, t = R @ self.force(inputs), R @ self.torque(inputs)
        return {"frame_b": (f, t), "frame_a": (-f, -t - ca.cross(b.r - a.r, f))}


class Force(PartialResolved, library=MB):
    """A force on frame_b's origin and its reaction on frame_a, resolved in ``resolve_in``
    (MSL's Forces.Force); entries given by ``f`` (expressions in t allowed) or by the
    signals f1, f2, f3.

    Parameters
    ----------
    f : N, 3 values, default [0, 0, 0]
        Force, resolved in ``resolve_in``; expressions in t and in signal outputs by dotted
        name ("pos.y") allowed; a wired f1, f2, f3 replaces its entry.
    resolve_in : "world", "frame_a", "frame_b" or "frame_resolve", default "frame_b"
        Frame the force is resolved in.
    """
    f = Param([0.0, 0.0, 0.0], unit="N", shape=(3,), time=True, signals=True,
              doc="Force on frame_b, resolved in resolve_in (a wired f1, f2, f3 replaces "
                  "its entry)")
    f1, f2, f3 = _signals("f", "Force component")
    resolve_in = _resolve_in()

    def force(self, inputs):
        return _given(self.f, ("f1", "f2", "f3"), inputs)


class Torque(PartialResolved, library=MB):
    """A torque on frame_b and its reaction on frame_a, resolved in ``resolve_in`` (MSL's
    Forces.Torque); entries given by ``t`` (expressions in time and in signal outputs
    allowed) or by the signals t1, t2, t3.

    Parameters
    ----------
    t : N*m, 3 values, default [0, 0, 0]
        Torque, resolved in ``resolve_in``; expressions in time and in signal outputs by
        dotted name ("pos.y") allowed; a wired t1, t2, t3 replaces its entry.
    resolve_in : "world", "frame_a", "frame_b" or "frame_resolve", default "frame_b"
        Frame the torque is resolved in.
    """
    t = Param([0.0, 0.0, 0.0], unit="N*m", shape=(3,), time=True, signals=True,
              doc="Torque on frame_b, resolved in resolve_in (a wired t1, t2, t3 replaces "
                  "its entry)")
    t1, t2, t3 = _signals("t", "Torque component")
    resolve_in = _resolve_in()

    def torque(self, inputs):
        return _given(self.t, ("t1", "t2", "t3"), inputs)


class ForceAndTorque(PartialResolved, library=MB):
    """A force at frame_b's origin and a torque on frame_b, their reaction on frame_a, both
    resolved in ``resolve_in`` (MSL's Forces.ForceAndTorque).

    Parameters
    ----------
    f : N, 3 values, default [0, 0, 0]
        Force, resolved in ``resolve_in``; expressions in t and in signal outputs by dotted
        name ("pos.y") allowed; a wired f1, f2, f3 replaces its entry.
    t : N*m, 3 values, default [0, 0, 0]
        Torque, resolved in ``resolve_in``; expressions in time and in signal outputs by
        dotted name ("pos.y") allowed; a wired t1, t2, t3 replaces its entry.
    resolve_in : "world", "frame_a", "frame_b" or "frame_resolve", default "frame_b"
        Frame both vectors are resolved in.
    """
    f = Force.params["f"]
    t = Torque.params["t"]
    f1, f2, f3 = _signals("f", "Force component")
    t1, t2, t3 = _signals("t", "Torque component")
    resolve_in = _resolve_in()
    force, torque = Force.force, Torque.torque


# -- forces and torques given in the world ---------------------------------------------------
class WorldForce(PartialFrameForce, library=MB):
    """A force at the origin of frame_b, resolved in the world (default) or in frame_b
    (MSL's Forces.WorldForce); expressions in t allowed, or the signals f1, f2, f3."""
    frame_b = Port("frame", "Frame the force acts on")
    force = Param(unit="N", shape=(3,), time=True, signals=True,
                  doc="Force, resolved in resolve_in (a wired f1, f2, f3 replaces its entry)")
    resolve_in = Param("world", kind="choice", choices=RESOLVE_B,
                       doc="Frame the force is resolved in: world or frame_b")
    f1, f2, f3 = _signals("force", "Force component")

    def wrenches(self, frames, inputs):
        f = _given(self.force, ("f1", "f2", "f3"), inputs)
        if self.resolve_in == "frame_b":
            f = frames["frame_b"].R @ f
        return {"frame_b": (f, zero3())}


class WorldTorque(PartialFrameForce, library=MB):
    """A torque on frame_b, resolved in the world (default) or in frame_b (MSL's
    Forces.WorldTorque); expressions in t allowed, or the signals t1, t2, t3."""
    frame_b = Port("frame", "Frame the torque acts on")
    torque = Param(unit="N*m", shape=(3,), time=True, signals=True,
                   doc="Torque, resolved in resolve_in (a wired t1, t2, t3 replaces its "
                       "entry)")
    resolve_in = Param("world", kind="choice", choices=RESOLVE_B,
                       doc="Frame the torque is resolved in: world or frame_b")
    t1, t2, t3 = _signals("torque", "Torque component")

    def wrenches(self, frames, inputs):
        t = _given(self.torque, ("t1", "t2", "t3"), inputs)
        if self.resolve_in == "frame_b":
            t = frames["frame_b"].R @ t
        return {"frame_b": (zero3(), t)}


__all__ = ["Damper", "Force", "ForceAndTorque", "LineForceWithTwoMasses", "Spring",
           "SpringDamper", "Torque", "WorldForce", "WorldTorque"]
