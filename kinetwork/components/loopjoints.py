"""Joints made for closing kinematic loops, as in Modelica's MultiBody: massless rods with a
ball or universal joint at each end (Joints.SphericalSpherical, Joints.UniversalSpherical) and
the planar aggregate of three revolutes (Joints.Assemblies.JointRRR).

A rod joint holds one thing, the distance between the origins of frame_a and frame_b: cut, it
gives its loop one closure equation where a cut Revolute gives five and a cut Spherical three
(MSL: "1 constraint, no potential states"), so it is always the cut joint of its loop, and a
rod that closes no loop is refused (nothing else would fix where frame_b points). Its
constraint force, the rod force, is what a probe on frame_b reads as ``force``: along the
rod, f_rod = -force . e with e the unit vector from frame_a to frame_b (positive when the rod
is pressed, as MSL's f_rod).

JointRRR is an aggregate: compiled, it is the chain it stands for (revolute, rod, revolute,
rod, revolute, the last one cut), so bodies hang on its inner frames as on any other, and its
motion is that of three Revolutes.
"""

from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError
from ..spatial import unit, vec3
from .base import REGISTRY, Component, Param, Port, PortRef

MB = "multibody"        # their library (multibody.py imports this module at its end)


class PartialRod(Component):
    """A massless rod between the origins of frame_a and frame_b: the cut joint of a loop,
    whose one closure equation holds their distance at ``rod_length()``."""
    role = "joint"
    dof = 0
    regular = True
    constant_subspace = True
    has_mass = False
    #: it can only close a loop: left in the spanning tree, it is refused
    loop_only = True
    cut_preference = -2       # before any other joint of its loop, one marked cut too
    frame_a = Port("frame", "Frame a, at one end of the rod")
    frame_b = Port("frame", "Frame b, at the far end of the rod")

    def transform(self, q):
        raise ModelError(f"{self.name}: a {self.type_name} holds a distance only, so it must "
                         f"close a kinematic loop")

    def closure(self, rel_R, rel_p, q):
        """(|r|^2 - L^2) / (2 L): the distance error to first order, smooth everywhere."""
        import casadi as ca
        length = self.rod_length()
        return (ca.dot(rel_p, rel_p) - length**2) / (2 * length)


class SphericalSpherical(PartialRod, library=MB):
    """A massless rod with a ball joint at each end: the origins of frame_a and frame_b stay
    ``length`` apart (MSL's Joints.SphericalSpherical without its point mass). The rod's spin
    about its own axis is left out: nothing of it moves."""
    length = Param(unit="m", positive=True, doc="Length of the rod (distance held)")

    def rod_length(self):
        return self.length


class UniversalSpherical(PartialRod, library=MB):
    """A massless rod with a universal joint at frame_a and a ball joint at frame_b (MSL's
    Joints.UniversalSpherical): the origins stay |r_rod| apart.

    frame_ia sits at frame_a's origin, fixed to the rod: it turns with the universal joint,
    whose axis 1 is ``n_a`` (fixed in frame_a) and axis 2 is normal to axis 1 and to the rod;
    it is parallel to frame_a when the rod points along ``r_rod`` (then both angles are
    zero). It is there for probes: nothing with mass or a force may rest on it. The joint is
    singular where the rod lies along ``n_a``.
    """
    n_a = Param([0.0, 0.0, 1.0], unit="1", shape=(3,), nonzero=True,
                doc="Axis 1 of the universal joint, in frame_a (axis 2 is normal to it and to "
                    "the rod)")
    r_rod = Param([1.0, 0.0, 0.0], unit="m", shape=(3,), nonzero=True,
                  doc="frame_b from frame_a along the rod, resolved in frame_ia; its length is "
                      "the distance held")
    frame_ia = Port("frame", "Frame at frame_a's origin fixed to the rod (for probes)",
                    optional=True)
    #: frames placed by ``frames`` rather than by the spanning tree
    placed_frames = ("frame_ia",)

    def rod_length(self):
        import casadi as ca
        return ca.norm_2(vec3(self.r_rod))

    def frames(self, rel_R, rel_p):
        """The frames this joint places from where frame_b is (``rel_R``, ``rel_p`` in
        frame_a): port -> (orientation, origin) in frame_a. frame_ia maps the rod's axes in
        frame_ia (rod, axis 2, their normal) onto the same axes in frame_a, as MSL."""
        import casadi as ca
        n = vec3(self.n_a)
        e_ia = unit(vec3(self.r_rod))
        e2_ia = unit(ca.cross(n, e_ia))
        e = unit(rel_p)
        e2 = unit(ca.cross(n, e))
        in_a = ca.horzcat(e, e2, ca.cross(e, e2))
        in_ia = ca.horzcat(e_ia, e2_ia, ca.cross(e_ia, e2_ia))
        return {"frame_ia": (in_a @ in_ia.T, ca.SX.zeros(3))}

    def check_values(self, values, place):
        n, r = (np.asarray(values[k], dtype=float) for k in ("n_a", "r_rod"))
        if np.linalg.norm(np.cross(n, r)) <= 1e-9 * np.linalg.norm(n) * np.linalg.norm(r):
            return [f"{place('n_a')} = {n.tolist()}: lies along the rod r_rod = "
                    f"{r.tolist()} m, where the universal joint is singular; choose an axis "
                    f"normal to the rod"]
        return []


@dataclass
class Expansion:
    """The elementary components an aggregate stands for, wired, and which of their ports
    are the aggregate's: read like a subsystem's definition when a model is flattened."""
    name: str
    components: dict
    connections: list
    exposed: dict
    places: dict = field(default_factory=dict)
    parameters: dict = field(default_factory=dict)


def _negated(vector):
    return [-v if isinstance(v, (int, float)) else f"-({v})" for v in vector]


class JointRRR(Component, library=MB):
    """Three revolutes with parallel axes joined by two rods, for planar loops (MSL's
    Joints.Assemblies.JointRRR).

    frame_a is the first revolute's outer side and frame_ia its inner side, fixed to rod 1;
    rod 1 runs ``r_rod1`` (in frame_ia) to the middle revolute, whose far side frame_im is
    fixed to rod 2; frame_ib is fixed to rod 2 at the third revolute, ``r_rod2`` (in frame_ib)
    from the middle one, and frame_b is that revolute's far side. ``axis`` and ``support``
    (MSL's ``bearing``, also wirable by that name) are the third revolute's flanges. As in
    MSL, the third revolute turns from frame_b to frame_ib: its angle is frame_ib's rotation
    relative to frame_b about the axis, and a torque on ``axis`` drives that angle. Compiled,
    it is that chain, its third revolute the cut joint of the loop (so it must close one):
    the same motion as three Revolutes, with bodies on frame_ia, frame_im and frame_ib as on
    any frame. Its coordinates are ``<name>.rev1.q``, ``<name>.rev2.q`` and
    ``<name>.rev3.q``.
    """
    role = "aggregate"
    frame_a = Port("frame", "Outer side of the first revolute")
    frame_b = Port("frame", "Far side of the third revolute")
    frame_ia = Port("frame", "Inner side of the first revolute, fixed to rod 1",
                    optional=True)
    frame_im = Port("frame", "Far side of the middle revolute, fixed to rod 2", optional=True)
    frame_ib = Port("frame", "Inner side of the third revolute, fixed to rod 2",
                    optional=True)
    axis = Port("rotational", "Flange driving the third revolute (angle of frame_ib "
                              "relative to frame_b)", optional=True)
    support = Port("rotational", "Reaction flange of that drive", optional=True)
    bearing = Port("rotational", "The support, by MSL's name", optional=True)
    n_a = Param([0.0, 0.0, 1.0], unit="1", shape=(3,), nonzero=True,
                doc="Axis of the three revolutes, in frame_a")
    r_rod1 = Param([1.0, 0.0, 0.0], unit="m", shape=(3,),
                   doc="Middle revolute from frame_a's origin, resolved in frame_ia (rod 1)")
    r_rod2 = Param([-1.0, 0.0, 0.0], unit="m", shape=(3,),
                   doc="Middle revolute from frame_b's origin, resolved in frame_ib (rod 2)")
    q0_guess = Param([0.0, 0.0, 0.0], shape=(3,), unit="rad",
                     doc="Start of the search for the three angles (picks the assembly)")

    def expand(self):
        """The chain rev1 - rod1 - rev2 - rod2 - rev3 (cut), and its ports as this one's.
        rev3 sits between frame_ib and frame_b about -n_a: turning frame_b by q about -n_a
        is turning frame_ib by q about n_a relative to frame_b, MSL's angle (its axis is
        n_a in frame_b too, the loop being planar)."""
        g = self.q0_guess
        revolute, rod = REGISTRY[f"{MB}.Revolute"], REGISTRY[f"{MB}.FixedTranslation"]
        parts = [revolute("rev1", n=self.n_a, q0_guess=g[0]),
                 rod("rod1", r=self.r_rod1),
                 revolute("rev2", n=self.n_a, q0_guess=g[1]),
                 rod("rod2", r=_negated(self.r_rod2)),
                 revolute("rev3", n=_negated(self.n_a), q0_guess=g[2], cut=True)]
        comps = {c.name: c for c in parts}

        def port(path):
            name, port_name = path.split(".")
            return PortRef(comps[name], port_name)
        chain = [("rev1.frame_b", "rod1.frame_a"), ("rod1.frame_b", "rev2.frame_a"),
                 ("rev2.frame_b", "rod2.frame_a"), ("rod2.frame_b", "rev3.frame_a")]
        exposed = {"frame_a": "rev1.frame_a", "frame_ia": "rev1.frame_b",
                   "frame_im": "rev2.frame_b", "frame_ib": "rev3.frame_a",
                   "frame_b": "rev3.frame_b", "axis": "rev3.axis", "support": "rev3.support",
                   "bearing": "rev3.support"}
        return Expansion(self.name, comps, [(port(a), port(b)) for a, b in chain],
                         {k: port(v) for k, v in exposed.items()})
