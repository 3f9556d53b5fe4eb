"""1-D rotational library: angle phi [rad] and torque tau [N*m] on flanges."""

from .base import Param
from .oned import PartialCompliant, PartialFixed, PartialSource

LIB = "rotational"


class PartialRotationalCompliant(PartialCompliant):
    """Rotational compliant element."""
    domain = LIB


class SpringDamper(PartialRotationalCompliant, library=LIB):
    """Linear rotational spring and damper in parallel."""
    c = Param(unit="N*m/rad", min=0.0, doc="Spring constant")
    d = Param(unit="N*m*s/rad", min=0.0, doc="Damping constant")
    phi_rel0 = Param(0.0, unit="rad", doc="Unstretched relative angle")

    def law(self, phi_rel, w_rel):
        return self.c * (phi_rel - self.phi_rel0) + self.d * w_rel


class Spring(PartialRotationalCompliant, library=LIB):
    """Linear rotational spring."""
    c = Param(unit="N*m/rad", min=0.0, doc="Spring constant")
    phi_rel0 = Param(0.0, unit="rad", doc="Unstretched relative angle")

    def law(self, phi_rel, w_rel):
        return self.c * (phi_rel - self.phi_rel0)


class Damper(PartialRotationalCompliant, library=LIB):
    """Linear rotational damper."""
    d = Param(unit="N*m*s/rad", min=0.0, doc="Damping constant")

    def law(self, phi_rel, w_rel):
        return self.d * w_rel


class Torque(PartialSource, library=LIB):
    """Torque source: a constant or an expression in time t and model parameters."""
    domain = LIB
    tau = Param(unit="N*m", time=True, doc="Torque applied to flange")

    def value(self, t):
        return self.tau


class Fixed(PartialFixed, library=LIB):
    """Flange fixed at an angle in the world."""
    domain = LIB
    phi0 = Param(0.0, unit="rad", doc="Fixed angle")

    def position(self):
        return self.phi0
