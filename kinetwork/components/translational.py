"""1-D translational library: position s [m] and force f [N] on flanges."""

from .base import Param, library_attribute
from .oned import (PartialDamper, PartialFixed, PartialFlowSensor, PartialInertia,
                   PartialMotion, PartialSensor, PartialSource, PartialSpring,
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
    """Force source: a constant or an expression in time t, model parameters and signal
    outputs named by path (``"-k*pos.y"`` with a position sensor pos)."""
    domain = LIB
    f = Param(0.0, unit="N", time=True, signals=True, doc="Force applied to flange (when u is not wired)")

    def applied(self):
        return self.f


class Fixed(PartialFixed, library=LIB):
    """Flange fixed at a position in the world."""
    domain = LIB
    position0 = Param(0.0, unit="m", name="s0", doc="Fixed position")


class Mass(PartialInertia, library=LIB):
    """A rigid sliding mass of length L between flange_a and flange_b, MSL's Mass: its
    position s is its centre, flange_a at s - L/2 and flange_b at s + L/2. Rigidly coupled to
    a joint axis (directly or through gears) it adds to the joint's inertia and costs no
    state; free, it has its own position s and speed v."""
    domain = LIB
    m = Param(unit="kg", min=0.0, doc="Mass")
    L = Param(0.0, unit="m", doc="Length, from flange_a to flange_b (flange_b.s - flange_a.s)")
    position0 = Param(None, optional=True, unit="m", name="s0",
                      doc="Initial position of the centre (None: from what it is tied to, "
                          "else 0)")
    speed0 = Param(None, optional=True, unit="m/s", name="v0",
                   doc="Initial speed (None: from what it is tied to, else 0)")

    def inertia(self):
        return self.m

    def length(self):
        return self.L


class PositionSensor(PartialSensor, library=LIB):
    """The position of the flange as a signal."""
    domain = LIB
    quantity = "position"


class SpeedSensor(PartialSensor, library=LIB):
    """The speed of the flange as a signal [m/s]."""
    domain = LIB
    quantity = "speed"


class AccSensor(PartialSensor, library=LIB):
    """The acceleration of the flange as a signal [m/s^2]."""
    domain = LIB
    quantity = "acceleration"


class ForceSensor(PartialFlowSensor, library=LIB):
    """The force through the sensor (into flange_a) as a signal; wire it in series."""
    domain = LIB


class Position(PartialMotion, library=LIB):
    """Moves its flange to s_ref: an expression in time and model parameters, or the signal at
    u; exact (differentiated exactly) or filtered (second-order Bessel filter, f_crit)."""
    domain = LIB
    reference = Param(None, optional=True, unit="m", time=True, name="s_ref",
                      doc="Prescribed position (when u is not wired)")
    exact = Param(True, kind="bool", doc="Differentiate the reference exactly (else filter it)")
    f_crit = Param(50.0, unit="Hz", positive=True, doc="Cut-off frequency of the filter")


class Speed(PartialMotion, library=LIB):
    """Moves its flange at v_ref (an expression in time and model parameters, or the signal
    at u) from s0: the position is integrated; exact or filtered (first order, f_crit)."""
    domain = LIB
    derivative = 1
    reference = Param(None, optional=True, unit="m/s", time=True, name="v_ref",
                      doc="Prescribed speed (when u is not wired)")
    exact = Param(True, kind="bool", doc="Differentiate the reference exactly (else filter it)")
    f_crit = Param(50.0, unit="Hz", positive=True, doc="Cut-off frequency of the filter")
    position0 = Param(0.0, unit="m", name="s0", doc="Initial position")


class Accelerate(PartialMotion, library=LIB):
    """Moves its flange with acceleration a_ref (an expression in time and model parameters,
    or the signal at u) from s0 at v0: speed and position are integrated."""
    domain = LIB
    derivative = 2
    reference = Param(None, optional=True, unit="m/s^2", time=True, name="a_ref",
                      doc="Prescribed acceleration (when u is not wired)")
    position0 = Param(0.0, unit="m", name="s0", doc="Initial position")
    speed0 = Param(0.0, unit="m/s", name="v0", doc="Initial speed")


from .translational_friction import ElastoGap, Friction, Stop  # noqa: E402,F401

__getattr__ = library_attribute("translational")
