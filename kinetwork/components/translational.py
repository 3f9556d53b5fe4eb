"""1-D translational library: position s [m] and force f [N] on flanges."""

from .base import Param
from .oned import (PartialDamper, PartialFixed, PartialSource, PartialSpring,
                   PartialSpringDamper)

LIB = "translational"


class SpringDamper(PartialSpringDamper, library=LIB):
    """Linear translational spring and damper in parallel."""
    domain = LIB
    c = Param(unit="N/m", min=0.0, doc="Spring constant")
    d = Param(unit="N*s/m", min=0.0, doc="Damping constant")
    rel0 = Param(0.0, unit="m", name="s_rel0", doc="Unstretched relative length")


class Spring(PartialSpring, library=LIB):
    """Linear translational spring."""
    domain = LIB
    c = Param(unit="N/m", min=0.0, doc="Spring constant")
    rel0 = Param(0.0, unit="m", name="s_rel0", doc="Unstretched relative length")


class Damper(PartialDamper, library=LIB):
    """Linear translational damper."""
    domain = LIB
    d = Param(unit="N*s/m", min=0.0, doc="Damping constant")


class Force(PartialSource, library=LIB):
    """Force source: a constant or an expression in time t and model parameters."""
    domain = LIB
    amount = Param(unit="N", time=True, name="f", doc="Force applied to flange")


class Fixed(PartialFixed, library=LIB):
    """Flange fixed at a position in the world."""
    domain = LIB
    position0 = Param(0.0, unit="m", name="s0", doc="Fixed position")
