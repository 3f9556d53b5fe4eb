"""What every part between two frames is: a transform of frame_b relative to frame_a.

``PartialRigidTransform`` is the base of the rigid parts (FixedTranslation, FixedRotation,
the bodies with a shape) and of the joints (whose transform depends on their coordinates):
the edges of the frame graph. Kept apart so that ``multibody.py`` (ground, parts, joints)
and ``bodies.py`` (bodies) both build on it.
"""

from .base import Component, Port


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
        import casadi as ca
        Rc, pc = self.transform(q)
        return ca.vertcat(rel_p - pc, ca.vec(Rc.T @ rel_R - ca.SX.eye(3)))
