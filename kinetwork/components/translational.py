"""1-D translational library: position s [m] and force f [N] on flanges."""

from .base import Param
from .oned import PartialCompliant, PartialFixed, PartialSource

LIB = "translational"


class PartialTranslationalCompliant(PartialCompliant):
    """Translational compliant element."""
    domain = LIB


class SpringDamper(PartialTranslationalCompliant, library=LIB):
    """Linear translational spring and damper in parallel."""
    c = Param(unit="N/m", min=0.0, doc="Spring constant")
    d = Param(unit="N*s/m", min=0.0, doc="Damping constant")
    s_rel0 = Param(0.0, unit="m", doc="Unstretched relative length")

    def law(self, s_rel, v_rel):
        return self.c * (s_rel - self.s_rel0) + self.d * v_rel


class Spring(PartialTranslationalCompliant, library=LIB):
    """Linear translational spring."""
    c = Param(unit="N/m", min=0.0, doc="Spring constant")
    s_rel0 = Param(0.0, unit="m", doc="Unstretched relative length")

    def law(self, s_rel, v_rel):
        return self.c * (s_rel - self.s_rel0)


class Damper(PartialTranslationalCompliant, library=LIB):
    """Linear translational damper."""
    d = Param(unit="N*s/m", min=0.0, doc="Damping constant")

    def law(self, s_rel, v_rel):
        return self.d * v_rel


class Force(PartialSource, library=LIB):
    """Force source: a constant or an expression in time t and model parameters."""
    domain = LIB
    f = Param(unit="N", time=True, doc="Force applied to flange")

    def value(self, t):
        return self.f


class Fixed(PartialFixed, library=LIB):
    """Flange fixed at a position in the world."""
    domain = LIB
    s0 = Param(0.0, unit="m", doc="Fixed position")

    def position(self):
        return self.s0
