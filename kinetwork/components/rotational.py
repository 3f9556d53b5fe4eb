"""1-D rotational library: angle phi [rad] and torque tau [N*m] on flanges."""

from .base import Param
from .oned import (PartialDamper, PartialFixed, PartialSource, PartialSpring,
                   PartialSpringDamper)

LIB = "rotational"


class SpringDamper(PartialSpringDamper, library=LIB):
    """Linear rotational spring and damper in parallel."""
    domain = LIB
    c = Param(unit="N*m/rad", min=0.0, doc="Spring constant")
    d = Param(unit="N*m*s/rad", min=0.0, doc="Damping constant")
    rel0 = Param(0.0, unit="rad", name="phi_rel0", doc="Unstretched relative angle")


class Spring(PartialSpring, library=LIB):
    """Linear rotational spring."""
    domain = LIB
    c = Param(unit="N*m/rad", min=0.0, doc="Spring constant")
    rel0 = Param(0.0, unit="rad", name="phi_rel0", doc="Unstretched relative angle")


class Damper(PartialDamper, library=LIB):
    """Linear rotational damper."""
    domain = LIB
    d = Param(unit="N*m*s/rad", min=0.0, doc="Damping constant")


class Torque(PartialSource, library=LIB):
    """Torque source: a constant or an expression in time t and model parameters."""
    domain = LIB
    amount = Param(unit="N*m", time=True, name="tau", doc="Torque applied to flange")


class Fixed(PartialFixed, library=LIB):
    """Flange fixed at an angle in the world."""
    domain = LIB
    position0 = Param(0.0, unit="rad", name="phi0", doc="Fixed angle")
