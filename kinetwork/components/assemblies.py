"""Joint assemblies that solve their kinematic loop analytically, as MSL's
Joints.Assemblies: JointUSR, JointSSR, JointUSP, JointSSP, JointRRP and JointUPS.

Each stands for a chain of joints between frame_a and frame_b whose coordinates follow in
closed form from where frame_b is relative to frame_a: a universal or spherical joint at
frame_a, a rod to a spherical joint, a second rod to a revolute or prismatic joint at frame_b
whose angle or distance is the root of the rod's length constraint (MSL's
RevoluteWithLengthConstraint and PrismaticWithLengthConstraint: a quadratic, of which
``phi_guess`` or ``s_guess`` picks the root at the start). An assembly has no mass, no
state and no closure equation: both of its ends are placed by the rest of the model (it
closes a loop), and it places its inner frames (``frame_ia``, ``frame_im``, ``frame_ib``)
and its 1-D ``axis`` from them. Bodies, rigid parts and force elements may sit on the inner
frames; their inertia and loads reach the mechanism by virtual work through the
assembly's kinematics (MSL computes the same forces by hand: its ``f_rod``).

MSL's ``phi_offset`` and ``phi_guess`` are in degrees; here, as every angle, in radians
(give ``"30 deg"``).
"""

from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError
from ..spatial import rotation, unit, vec3
from .base import ONED, Component, Param, Port

MB = "multibody"
#: MSL asserts that the discriminant of a length constraint stays above this: nearer, the
#: loop is at a singular position (its two roots meet, a degree of freedom is lost)
SINGULAR = 1e-10


@dataclass
class Placement:
    """Where an assembly puts what it places, from frame_b's pose in frame_a.

    ``frames``: inner port -> (orientation, origin) in frame_a; ``coordinate``: the position
    of its ``axis`` flange (an angle or a distance), or None; ``masses``: (mass, position in
    frame_a) of the point masses it carries; ``checks``: (expression, what) that must stay
    positive (a dimensionless measure, 1 far from trouble), or the assembly is at a singular
    position: ``what`` says which."""
    frames: dict
    coordinate: object = None
    masses: list = field(default_factory=list)
    checks: list = field(default_factory=list)


class PartialAssembly(Component):
    """An assembly: the cut of its kinematic loop, which it closes in closed form.

    ``place(rel_R, rel_p, branch)`` gives the Placement from frame_b's orientation and origin
    in frame_a; ``branch`` (+1 or -1) picks the root of the length constraint, and
    ``candidates(rel_R, rel_p)`` gives the two values of the axis coordinate with their
    distances from the guess, so that the start takes the nearer (MSL's positiveBranch)."""
    role = "joint"
    dof = 0
    regular = True
    constant_subspace = True
    has_mass = False
    #: it closes a loop in closed form: left in the spanning tree, it is refused
    loop_only = True
    analytic = True
    cut_preference = -3
    #: 1-D flange whose position the assembly gives (port -> None: no joint coordinate)
    derived_ports = ("axis",)
    zero_ports = ("bearing", "support")
    joined_ports = (("bearing", "support"),)
    #: frames it places from where its ends are, which may carry bodies, parts and forces
    placed_frames = ()
    carries_loads = True
    frame_a = Port("frame", "Frame a, at the first joint of the assembly")
    frame_b = Port("frame", "Frame b, at the last joint of the assembly")
    axis = Port(ONED, "Flange of the last joint's coordinate (its angle or distance)",
                optional=True)
    bearing = Port(ONED, "Flange of that joint's drive bearing (MSL's name; rests in the "
                         "world, as every joint's support)", optional=True)
    support = Port(ONED, "The bearing, by kinetwork's name for a joint's reaction flange",
                   optional=True)

    def transform(self, q):
        raise ModelError(f"{self.name}: a {self.type_name} places its frames from both of its "
                         f"ends, so it must close a kinematic loop")

    def closure(self, rel_R, rel_p, q):
        import casadi as ca
        return ca.SX(0, 1)

    def coordinate_labels(self):
        return []

    def place(self, rel_R, rel_p, branch):
        raise NotImplementedError

    def candidates(self, rel_R, rel_p):
        """(value on branch +1, value on branch -1, guess) of the axis coordinate, from which
        the start picks the branch nearer the guess; None when there is no choice."""
        return None


def _universal(n1_a, r_ia, rod_a):
    """Orientation of frame_ia in frame_a for the rod ``rod_a`` (frame_a's axes), MSL's
    UniversalSpherical: axis 1 is n1_a, axis 2 is normal to it and to the rod; frame_ia is
    parallel to frame_a where the rod lies along ``r_ia``. Also |n1_a x e|^2, which vanishes
    where the rod lies along axis 1 (the joint's singularity)."""
    import casadi as ca
    n = unit(vec3(n1_a))
    e_ia = unit(vec3(r_ia))
    e2_ia = unit(ca.cross(n, e_ia))
    e = unit(rod_a)
    n2 = ca.cross(n, e)
    e2 = n2 / ca.norm_2(n2)
    in_a = ca.horzcat(e, e2, ca.cross(e, e2))
    in_ia = ca.horzcat(e_ia, e2_ia, ca.cross(e_ia, e2_ia))
    return in_a @ in_ia.T, ca.dot(n2, n2)


def _root(discriminant):
    """The square root of a length constraint's discriminant; not a number where it is
    negative (no configuration closes the loop there), so a run that gets there stops
    rather than go on with a clamped, wrong one."""
    import casadi as ca
    return ca.sqrt(ca.if_else(discriminant > 0, discriminant, ca.SX.nan()))


def _revolute_roots(e, r_a, r_b, length, branch):
    """Angle of MSL's RevoluteWithLengthConstraint: frame_b of the joint is its frame_a
    turned by it about ``e``, and |r_b - T r_a| = length, with r_a fixed in the joint's
    frame_a and r_b in its frame_b (T resolves frame_a vectors in frame_b). A cos + B sin + C
    = 0, solved for sine and cosine apart (any angle in -pi..pi); also the discriminant
    over A^2 + B^2 (dimensionless: 1 - C^2 / (A^2 + B^2), 1 far from a singular position)."""
    import casadi as ca
    e_r_a, e_r_b = ca.dot(e, r_a), ca.dot(e, r_b)
    A = -2 * (ca.dot(r_b, r_a) - e_r_b * e_r_a)
    B = 2 * ca.dot(r_b, ca.cross(e, r_a))
    C = ca.dot(r_a, r_a) + ca.dot(r_b, r_b) - length**2 - 2 * e_r_b * e_r_a
    k1a = A * A + B * B - C * C
    k2 = _root(k1a)
    return ca.atan2(-B * C - branch * A * k2, -A * C + branch * B * k2), k1a / (A * A + B * B)


def _prismatic_roots(e, r_a, r_b, length, branch):
    """Distance of MSL's PrismaticWithLengthConstraint: frame_b of the joint is its frame_a
    moved by d along ``e``, and |d e + r_b - r_a| = length: d^2 + B d + C = 0; also the
    discriminant over length^2 (dimensionless, 1 where the rod is along ``e``)."""
    import casadi as ca
    rbra = r_b - r_a
    k1 = ca.dot(e, rbra)
    k1a = k1 * k1 - (ca.dot(rbra, rbra) - length**2)
    return -k1 + branch * _root(k1a), k1a / length**2


class _RodAndEndJoint(PartialAssembly):
    """A rod from frame_a's origin to a spherical joint (frame_im), and a second rod from
    there to the joint at frame_b (frame_ib, which it turns or moves): MSL's JointUSR,
    JointSSR, JointUSP and JointSSP, which differ in the joint at frame_a (universal or
    spherical) and at frame_b (revolute or prismatic)."""
    rotational_end = True

    def rod1_length(self):
        """Length of rod 1, the distance the end joint's angle or distance keeps."""
        import casadi as ca
        return ca.norm_2(vec3(self.rRod1_ia))

    def universal_axis(self):
        """Axis 1 of the universal joint at frame_a (assemblies that have one)."""
        return self.n1_a

    def _end(self, rel_R, rel_p, branch):
        """(R, p) of frame_ib in frame_b, the axis coordinate and the discriminant."""
        import casadi as ca
        e = unit(vec3(self.n_b))
        r_a = -rel_R.T @ rel_p          # frame_a's origin from frame_b, in frame_b
        r_b = vec3(self.rRod2_ib)
        if self.rotational_end:
            angle, k1a = _revolute_roots(e, r_a, r_b, self.rod1_length(), branch)
            return rotation(e, angle), ca.SX.zeros(3), angle - self.phi_offset, k1a
        distance, k1a = _prismatic_roots(e, r_a, r_b, self.rod1_length(), branch)
        return ca.SX.eye(3), e * distance, distance - self.s_offset, k1a

    def candidates(self, rel_R, rel_p):
        plus, minus = (self._end(rel_R, rel_p, s)[2] for s in (1, -1))
        guess = self.phi_guess if self.rotational_end else self.s_guess
        return plus, minus, guess

    def place(self, rel_R, rel_p, branch):
        import casadi as ca
        R_ib, p_ib, coordinate, k1a = self._end(rel_R, rel_p, branch)
        R_ib, p_ib = rel_R @ R_ib, rel_p + rel_R @ p_ib
        p_im = p_ib + R_ib @ vec3(self.rRod2_ib)
        frames = {"frame_ib": (R_ib, p_ib), "frame_im": (R_ib, p_im)}
        joint = "revolute" if self.rotational_end else "prismatic"
        checks = [(k1a - SINGULAR, f"the two positions of its {joint} joint meet (or none "
                                   f"exists): the mechanism loses a degree of freedom")]
        if "frame_ia" in self.placed_frames:
            R_ia, n2 = _universal(self.universal_axis(), self.rRod1_ia, p_im)
            frames["frame_ia"] = (R_ia, ca.SX.zeros(3))
            checks.append((n2 - SINGULAR, "its universal joint is singular: rod 1 lies along "
                                          "its axis 1"))
        masses = []
        if "rod1Mass" in self.params:
            masses.append((self.rod1Mass, p_im / 2))
        return Placement(frames, coordinate, masses, checks)


def _offset(rotational):
    if rotational:
        return (Param(0.0, unit="rad", doc="Angle offset of the revolute joint at frame_b "
                                           "(its angle is axis.phi + phi_offset)"),
                Param(0.0, unit="rad", doc="The start takes the configuration whose axis "
                                           "angle is nearest phi_guess"))
    return (Param(0.0, unit="m", doc="Distance offset of the prismatic joint at frame_b "
                                     "(frame_ib is frame_b moved by axis.s + s_offset along "
                                     "n_b)"),
            Param(0.0, unit="m", doc="The start takes the configuration whose axis distance "
                                     "is nearest s_guess"))


def _vector(default, doc, unit_="m", nonzero=False):
    return Param(default, unit=unit_, shape=(3,), nonzero=nonzero, doc=doc)


def _rod1_ia():
    return _vector([1.0, 0.0, 0.0], "Vector from frame_a's origin to the spherical joint, "
                                    "resolved in frame_ia (its length is rod 1's)",
                   nonzero=True)


def _rod2_ib(default, to="the spherical joint"):
    return _vector(default, f"Vector from frame_ib's origin to {to}, resolved in frame_ib")


def _n1_a():
    return _vector([0.0, 0.0, 1.0], "Axis 1 of the universal joint, fixed in frame_a (axis 2 "
                                    "is normal to it and to rod 1)", "1", True)


def _n_b(default, joint):
    return _vector(default, f"Axis of the {joint} joint at frame_b, fixed and resolved in "
                            f"frame_b", "1", True)


def _port_ia():
    return Port("frame", "Frame at frame_a's origin, fixed to rod 1 (turned by the universal "
                         "joint)", optional=True)


def _port_im():
    return Port("frame", "Frame at the middle spherical joint, fixed to rod 2 (parallel to "
                         "frame_ib)", optional=True)


def _port_ib(joint):
    return Port("frame", f"Frame at the {joint} joint, fixed to rod 2 (frame_b "
                         f"{'turned' if joint == 'revolute' else 'moved'} by it)",
                optional=True)


class JointUSR(_RodAndEndJoint, library=MB):
    """Universal, spherical and revolute joints aggregated, with no mass and no state (MSL's
    Joints.Assemblies.JointUSR): the loop it closes is solved in closed form.

    A universal joint at frame_a carries rod 1 (frame_ia, at frame_a's origin) to a
    spherical joint ``rRod1_ia`` away; rod 2 runs from there (frame_im) to frame_ib, which a
    revolute joint about ``n_b`` turns relative to frame_b by axis.phi + phi_offset. Of the
    two angles that give rod 1 its length, the start takes the one nearer phi_guess and the
    motion stays on that branch. The universal joint's axis 1 is ``n1_a``, its axis 2
    normal to it and to rod 1; it is singular where rod 1 lies along n1_a.
    """
    placed_frames = ("frame_ia", "frame_im", "frame_ib")
    domain = "rotational"
    frame_ia, frame_im, frame_ib = _port_ia(), _port_im(), _port_ib("revolute")
    n1_a = _n1_a()
    n_b = _n_b([0.0, 0.0, 1.0], "revolute")
    rRod1_ia = _rod1_ia()
    rRod2_ib = _rod2_ib([-1.0, 0.0, 0.0])
    phi_offset, phi_guess = _offset(True)


class JointSSR(_RodAndEndJoint, library=MB):
    """Spherical, spherical and revolute joints aggregated, with no state (MSL's
    Joints.Assemblies.JointSSR): the loop it closes is solved in closed form.

    Rod 1, of length ``rod1Length`` and a point mass ``rod1Mass`` in its middle, runs
    between spherical joints at frame_a's origin and at the middle (frame_im); rod 2 runs
    from there to frame_ib, which a revolute joint about ``n_b`` turns relative to frame_b by
    axis.phi + phi_offset. Rod 1's spin about itself moves nothing and is left out. Of the
    two angles that give rod 1 its length, the start takes the one nearer phi_guess.
    """
    placed_frames = ("frame_im", "frame_ib")
    domain = "rotational"
    frame_im, frame_ib = _port_im(), _port_ib("revolute")
    rod1Length = Param(unit="m", positive=True,
                       doc="Distance between the origins of the two spherical joints")
    rod1Mass = Param(0.0, unit="kg", min=0.0, doc="Mass of rod 1, a point mass in its middle")
    n_b = _n_b([0.0, 0.0, 1.0], "revolute")
    rRod2_ib = _rod2_ib([1.0, 0.0, 0.0], "the spherical joint in the middle")
    phi_offset, phi_guess = _offset(True)

    def rod1_length(self):
        return self.rod1Length


class JointUSP(_RodAndEndJoint, library=MB):
    """Universal, spherical and prismatic joints aggregated, with no mass and no state
    (MSL's Joints.Assemblies.JointUSP): the loop it closes is solved in closed form.

    As JointUSR, with a prismatic joint at frame_b instead: frame_ib is frame_b moved by
    axis.s + s_offset along ``n_b``. Of the two distances that give rod 1 its length, the
    start takes the one nearer s_guess.
    """
    rotational_end = False
    placed_frames = ("frame_ia", "frame_im", "frame_ib")
    domain = "translational"
    frame_ia, frame_im, frame_ib = _port_ia(), _port_im(), _port_ib("prismatic")
    n1_a = _n1_a()
    n_b = _n_b([-1.0, 0.0, 0.0], "prismatic")
    rRod1_ia = _rod1_ia()
    rRod2_ib = _rod2_ib([-1.0, 0.0, 0.0])
    s_offset, s_guess = _offset(False)


class JointSSP(_RodAndEndJoint, library=MB):
    """Spherical, spherical and prismatic joints aggregated, with no state (MSL's
    Joints.Assemblies.JointSSP): the loop it closes is solved in closed form.

    As JointSSR, with a prismatic joint at frame_b: frame_ib is frame_b moved by axis.s +
    s_offset along ``n_b``. Of the two distances that give rod 1 its length, the start
    takes the one nearer s_guess.
    """
    rotational_end = False
    placed_frames = ("frame_im", "frame_ib")
    domain = "translational"
    frame_im, frame_ib = _port_im(), _port_ib("prismatic")
    rod1Length = JointSSR.params["rod1Length"]
    rod1Mass = JointSSR.params["rod1Mass"]
    n_b = _n_b([0.0, 0.0, 1.0], "prismatic")
    rRod2_ib = _rod2_ib([1.0, 0.0, 0.0], "the spherical joint in the middle")
    s_offset, s_guess = _offset(False)

    def rod1_length(self):
        return self.rod1Length


class JointRRP(_RodAndEndJoint, library=MB):
    """Two revolute joints and a prismatic joint for planar loops (MSL's
    Joints.Assemblies.JointRRP), solved in closed form.

    MSL builds it as a JointUSP whose universal joint's axis 1 is ``n_a``, the axis of the
    two revolutes: rod 1 (frame_ia, at frame_a's origin) reaches the middle revolute at
    ``rRod1_ia``, rod 2 runs from there (frame_im) to frame_ib, which the prismatic joint
    moves by axis.s + s_offset along ``n_b`` from frame_b. In a planar loop (n_b normal to
    n_a) the universal's second angle and the spherical joint stay at rest; out of the
    plane they give way instead of constraining.
    """
    rotational_end = False
    placed_frames = ("frame_ia", "frame_im", "frame_ib")
    domain = "translational"
    frame_ia, frame_im, frame_ib = _port_ia(), _port_im(), _port_ib("prismatic")
    n_a = _vector([0.0, 0.0, 1.0], "Axis of the two revolute joints, fixed and resolved in "
                                   "frame_a", "1", True)
    n_b = _n_b([-1.0, 0.0, 0.0], "prismatic")
    rRod1_ia = _vector([1.0, 0.0, 0.0], "Vector from frame_a's origin to the middle revolute "
                                        "joint, resolved in frame_ia", nonzero=True)
    rRod2_ib = _rod2_ib([-1.0, 0.0, 0.0], "the middle revolute joint")
    s_offset, s_guess = _offset(False)

    def universal_axis(self):
        return self.n_a


class JointUPS(PartialAssembly, library=MB):
    """Universal, prismatic and spherical joints aggregated, with no mass and no state
    (MSL's Joints.Assemblies.JointUPS): a leg of variable length, as a hydraulic cylinder.

    A universal joint at frame_a turns frame_ia so that its ``nAxis_ia`` points to frame_b's
    origin; frame_ib, parallel to frame_ia, sits at frame_b's origin (behind the spherical
    joint there). The prismatic joint's distance is the length of the leg: |r_ab| =
    axis.s + s_offset. The universal joint's axis 1 is ``n1_a``, its axis 2 normal to it and
    to the leg; it is singular where the leg lies along n1_a.
    """
    placed_frames = ("frame_ia", "frame_ib")
    domain = "translational"
    frame_ia = Port("frame", "Frame at frame_a's origin, fixed to the cylinder (turned by the "
                             "universal joint)", optional=True)
    frame_ib = Port("frame", "Frame at frame_b's origin, fixed to the piston (parallel to "
                             "frame_ia)", optional=True)
    n1_a = _n1_a()
    nAxis_ia = Param([1.0, 0.0, 0.0], unit="1", shape=(3,), nonzero=True,
                     doc="Direction from frame_a's origin to frame_b's, resolved in frame_ia")
    s_offset = Param(0.0, unit="m", doc="Distance offset (|r_ab| = axis.s + s_offset)")

    def place(self, rel_R, rel_p, branch):
        import casadi as ca
        length = ca.norm_2(rel_p)
        R_ia, n2 = _universal(self.n1_a, self.nAxis_ia, rel_p)
        frames = {"frame_ia": (R_ia, ca.SX.zeros(3)), "frame_ib": (R_ia, rel_p)}
        checks = [(length - 1e-15, "frame_a and frame_b meet, where the leg has no "
                                   "direction"),
                  (n2 - SINGULAR, "its universal joint is singular: the leg lies along its "
                                  "axis 1")]
        return Placement(frames, length - self.s_offset, [], checks)
