"""1-D translational library: position s [m] and force f [N] on flanges."""

from .base import Param, Port, library_attribute
from .oned import (PartialDamper, PartialFixed, PartialFlowSensor, PartialInertia,
                   PartialMotion, PartialPowerSensor, PartialRigid, PartialSensor,
                   PartialSource, PartialSpring, PartialSpringDamper)

LIB = "translational"


class SpringDamper(PartialSpringDamper, library=LIB):
    """Linear translational spring and damper in parallel."""
    domain = LIB
    c = Param(unit="N/m", min=0.0, doc="Spring constant")
    d = Param(unit="N*s/m", min=0.0, doc="Damping constant")
    s_rel0 = Param(0.0, unit="m", doc="Unstretched relative length")


class Spring(PartialSpring, library=LIB):
    """Linear translational spring."""
    domain = LIB
    c = Param(unit="N/m", min=0.0, doc="Spring constant")
    s_rel0 = Param(0.0, unit="m", doc="Unstretched relative length")


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
    s0 = Param(0.0, unit="m", doc="Fixed position")


class Rod(PartialRigid, library=LIB):
    """A rigid massless rod of length L between flange_a and flange_b, MSL's
    Translational.Components.Rod: flange_b.s = flange_a.s + L, and the force it takes at one
    flange it passes whole to the other."""
    domain = LIB
    L = Param(0.0, unit="m", doc="Length, from flange_a to flange_b (flange_b.s - flange_a.s)")

    def length(self):
        return self.L


class Mass(PartialInertia, library=LIB):
    """A rigid sliding mass of length L between flange_a and flange_b, MSL's Mass: its
    position s is its centre, flange_a at s - L/2 and flange_b at s + L/2. Rigidly coupled to
    a joint axis (directly or through gears) it adds to the joint's inertia and costs no
    state; free, it has its own position s and speed v."""
    domain = LIB
    m = Param(unit="kg", min=0.0, doc="Mass")
    L = Param(0.0, unit="m", doc="Length, from flange_a to flange_b (flange_b.s - flange_a.s)")
    s0 = Param(None, optional=True, unit="m",
               doc="Initial position of the centre (None: from what it is tied to, else 0)")
    v0 = Param(None, optional=True, unit="m/s",
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


class PowerSensor(PartialPowerSensor, library=LIB):
    """The power flowing from flange_a to flange_b, flange_a.f * der(flange_a.s), as the
    signal ``power`` (MSL's Translational.Sensors.PowerSensor); wire it in series."""
    domain = LIB
    outputs = {"power": "power"}


class MultiSensor(PartialPowerSensor, library=LIB):
    """The force into flange_a (``f``), the flanges' velocity (``v``) and the power flowing
    from flange_a to flange_b, f * v (``power``), as MSL's Translational.Sensors.MultiSensor;
    wire it in series."""
    domain = LIB
    f = Port("signal_out", "Force into flange_a [N]", optional=True)
    v = Port("signal_out", "Velocity of the flanges [m/s]", optional=True)
    outputs = {"power": "power", "f": "flow", "v": "speed"}


class Position(PartialMotion, library=LIB):
    """Moves its flange to s_ref: an expression in time and model parameters, or the signal at
    u; exact (differentiated exactly) or filtered (second-order Bessel filter, f_crit)."""
    domain = LIB
    s_ref = Param(None, optional=True, unit="m", time=True,
                  doc="Prescribed position (when u is not wired)")
    exact = Param(True, kind="bool", doc="Differentiate the reference exactly (else filter it)")
    f_crit = Param(50.0, unit="Hz", positive=True, doc="Cut-off frequency of the filter")


class Speed(PartialMotion, library=LIB):
    """Moves its flange at v_ref (an expression in time and model parameters, or the signal
    at u) from s0: the position is integrated; exact or filtered (first order, f_crit)."""
    domain = LIB
    derivative = 1
    v_ref = Param(None, optional=True, unit="m/s", time=True,
                  doc="Prescribed speed (when u is not wired)")
    exact = Param(True, kind="bool", doc="Differentiate the reference exactly (else filter it)")
    f_crit = Param(50.0, unit="Hz", positive=True, doc="Cut-off frequency of the filter")
    s0 = Param(0.0, unit="m", doc="Initial position")


class Accelerate(PartialMotion, library=LIB):
    """Moves its flange with acceleration a_ref (an expression in time and model parameters,
    or the signal at u) from s0 at v0: speed and position are integrated."""
    domain = LIB
    derivative = 2
    a_ref = Param(None, optional=True, unit="m/s^2", time=True,
                  doc="Prescribed acceleration (when u is not wired)")
    s0 = Param(0.0, unit="m", doc="Initial position")
    v0 = Param(0.0, unit="m/s", doc="Initial speed")


from .translational_friction import ElastoGap, Friction, Stop  # noqa: E402,F401

__getattr__ = library_attribute("translational")
