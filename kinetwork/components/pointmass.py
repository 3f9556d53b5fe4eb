"""A mass point: MSL's MultiBody.Parts.PointMass."""

from .base import Component, Param, Port

MB = "multibody"


class PointMass(Component, library=MB):
    """A rigid body whose rotation and inertia are neglected: mass ``m`` at frame_a's origin
    (MSL's Parts.PointMass).

    Fixed to a frame that other parts turn, it takes a force m (a - g) and no torque. Several
    point masses joined by rigid parts make a body with the inertia of their arrangement (MSL's
    PointGravityWithPointMasses2). Alone on a FreeMotion (nothing else on its frame_b) it
    moves without turning: the FreeMotion's orientation is then not a state, only its position
    and velocity are, as MSL's PointMass selects r_0 and v_0 (MSL's note: its rotation is not
    taken into account and cannot be computed; kinetwork holds frame_b at the FreeMotion's
    angles0, MSL's unit rotation by default).

    Parameters
    ----------
    m : kg, >= 0, required
        Mass of the mass point.
    sphereDiameter : m, >= 0, default 0.1
        Diameter of the sphere the animation draws; looks only.
    color : "#rrggbb" or None, default None
        Colour in the animation (None: its default).
    """
    role = "body"
    frame_a = Port("frame", "Frame at the mass point (MSL's frame_a)")
    m = Param(unit="kg", min=0.0, doc="Mass of the mass point")
    sphereDiameter = Param(0.1, unit="m", min=0.0, doc="Diameter of the sphere the animation "
                                                      "draws; looks only")
    color = Param(None, optional=True, kind="color",
                  doc="Colour in the animation, '#rrggbb' (None: the animation's default)")

    def mass_properties(self):
        """(mass, centre of mass, inertia about it) as CasADi values: no inertia."""
        import casadi as ca
        return self.m, ca.DM.zeros(3), ca.DM.zeros(3, 3)
