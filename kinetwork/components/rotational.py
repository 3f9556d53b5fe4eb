"""1-D rotational library: angle phi [rad] and torque tau [N*m] on flanges."""

from .base import Param, Port, library_attribute
from .oned import (PartialDamper, PartialFixed, PartialFlowSensor, PartialInertia,
                   PartialMotion, PartialPowerSensor, PartialRigid, PartialSensor,
                   PartialSource, PartialSpring, PartialSpringDamper)

LIB = "rotational"


class SpringDamper(PartialSpringDamper, library=LIB):
    """Linear rotational spring and damper in parallel."""
    domain = LIB
    c = Param(unit="N*m/rad", min=0.0, doc="Spring constant")
    d = Param(unit="N*m*s/rad", min=0.0, doc="Damping constant")
    phi_rel0 = Param(0.0, unit="rad", doc="Unstretched relative angle")


class Spring(PartialSpring, library=LIB):
    """Linear rotational spring."""
    domain = LIB
    c = Param(unit="N*m/rad", min=0.0, doc="Spring constant")
    phi_rel0 = Param(0.0, unit="rad", doc="Unstretched relative angle")


class Damper(PartialDamper, library=LIB):
    """Linear rotational damper."""
    domain = LIB
    d = Param(unit="N*m*s/rad", min=0.0, doc="Damping constant")


class Torque(PartialSource, library=LIB):
    """Torque source: a constant or an expression in time t, model parameters and signal
    outputs named by path (``"if_else(w.y > 0, -c, c)"`` with a speed sensor w)."""
    domain = LIB
    tau = Param(0.0, unit="N*m", time=True, signals=True, doc="Torque applied to flange (when u is not wired)")

    def applied(self):
        return self.tau


class Fixed(PartialFixed, library=LIB):
    """Flange fixed at an angle in the world."""
    domain = LIB
    phi0 = Param(0.0, unit="rad", doc="Fixed angle")


class Inertia(PartialInertia, library=LIB):
    """A rigid rotor between flange_a and flange_b. Rigidly coupled to a joint axis
    (directly or through gears) it adds to the joint's inertia and costs no state; free, it has
    its own angle and speed. Its phi0 and w0 are always used: they start a free rotor (and
    what is geared to it), or the joint it is rigidly on (MSL's Engine1a puts the engine's
    start speed on the load inertia); where something else decides its start (the joint's
    own q0, a motion, a Fixed, another inertia) they must agree, or the model is refused."""
    domain = LIB
    J = Param(unit="kg*m^2", min=0.0, doc="Moment of inertia")
    phi0 = Param(None, optional=True, unit="rad",
                 doc="Initial angle (None: from what it is tied to, else 0)")
    w0 = Param(None, optional=True, unit="rad/s",
               doc="Initial speed (None: from what it is tied to, else 0)")

    def inertia(self):
        return self.J


class AngleSensor(PartialSensor, library=LIB):
    """The angle of the flange as a signal."""
    domain = LIB
    quantity = "position"


class SpeedSensor(PartialSensor, library=LIB):
    """The speed of the flange as a signal [rad/s]."""
    domain = LIB
    quantity = "speed"


class AccSensor(PartialSensor, library=LIB):
    """The acceleration of the flange as a signal [rad/s^2]."""
    domain = LIB
    quantity = "acceleration"


class TorqueSensor(PartialFlowSensor, library=LIB):
    """The torque through the sensor (into flange_a) as a signal; wire it in series."""
    domain = LIB


class PowerSensor(PartialPowerSensor, library=LIB):
    """The power flowing from flange_a to flange_b, flange_a.tau * der(flange_a.phi), as the
    signal ``power`` (MSL's Rotational.Sensors.PowerSensor); wire it in series."""
    domain = LIB
    outputs = {"power": "power"}


class MultiSensor(PartialPowerSensor, library=LIB):
    """The torque into flange_a (``tau``), the flanges' speed (``w``) and the power flowing
    from flange_a to flange_b, tau * w (``power``), as MSL's Rotational.Sensors.MultiSensor;
    wire it in series."""
    domain = LIB
    w = Port("signal_out", "Speed of the flanges [rad/s]", optional=True)
    tau = Port("signal_out", "Torque into flange_a [N*m]", optional=True)
    outputs = {"power": "power", "w": "speed", "tau": "flow"}


class Position(PartialMotion, library=LIB):
    """Moves its flange to phi_ref: an expression in time and model parameters, or the signal at
    u; exact (differentiated exactly) or filtered (second-order Bessel filter, f_crit)."""
    domain = LIB
    phi_ref = Param(None, optional=True, unit="rad", time=True,
                    doc="Prescribed angle (when u is not wired)")
    exact = Param(True, kind="bool", doc="Differentiate the reference exactly (else filter it)")
    f_crit = Param(50.0, unit="Hz", positive=True, doc="Cut-off frequency of the filter")


class Speed(PartialMotion, library=LIB):
    """Moves its flange at w_ref (an expression in time and model parameters, or the signal
    at u) from phi0: the angle is integrated; exact or filtered (first order, f_crit)."""
    domain = LIB
    derivative = 1
    w_ref = Param(None, optional=True, unit="rad/s", time=True,
                  doc="Prescribed speed (when u is not wired)")
    exact = Param(True, kind="bool", doc="Differentiate the reference exactly (else filter it)")
    f_crit = Param(50.0, unit="Hz", positive=True, doc="Cut-off frequency of the filter")
    phi0 = Param(0.0, unit="rad", doc="Initial angle")


class Accelerate(PartialMotion, library=LIB):
    """Moves its flange with acceleration a_ref (an expression in time and model parameters,
    or the signal at u) from phi0 at w0: speed and angle are integrated."""
    domain = LIB
    derivative = 2
    a_ref = Param(None, optional=True, unit="rad/s^2", time=True,
                  doc="Prescribed acceleration (when u is not wired)")
    phi0 = Param(0.0, unit="rad", doc="Initial angle")
    w0 = Param(0.0, unit="rad/s", doc="Initial speed")


class IdealGear(PartialRigid, library=LIB):
    """A gear: flange_a turns ``ratio`` times as far as flange_b relative to the support
    (Modelica's convention, flange_a.phi - support.phi = ratio * (flange_b.phi -
    support.phi)), and flange_b's torque is ``ratio`` times flange_a's, times the efficiency
    eta when flange_a drives, divided by it when flange_b does (the driving side found by
    events). The support takes the reaction -(tau_a + tau_b) (MSL's useSupport): unwired or
    on a Fixed it stands still; on a housing inertia (MSL's ElasticBearing) the housing
    turns with it, the gear train riding on it (a train that is free, on a housing that is
    free or moved by a motion; eta = 1)."""
    domain = LIB
    lossy = True
    support = Port("1d", "Reaction flange (unwired: the world)", optional=True)
    ratio = Param(unit="1", nonzero=True, doc="flange_a angle / flange_b angle")
    eta = Param(1.0, unit="1", positive=True, max=1.0,
                doc="Efficiency (1: lossless, no mode; below 1: the loss of the driven side)")

    def position_ratio(self):
        return self.ratio


from .rotational_friction import (BearingFriction, Brake, Clutch, ElastoGap,  # noqa: E402,F401
                                  Stop)

__getattr__ = library_attribute("rotational")
