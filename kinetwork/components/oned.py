"""Partials shared by the 1-D rotational and translational libraries.

Each law is written once here; a library subclasses with ``domain`` set and declares the
parameters with Modelica's names and its units (``phi_rel0`` in rotational, ``s_rel0`` in
translational): what ``help()``, files and attributes all use. A law reads them under one
name, a role (``rel0``), which ``named`` maps to the library's parameter. Flows are positive
into the component, as in Modelica.
"""

import math

from ..errors import ModelError
from .base import ONED, Component, Port
from .quantities import QUANTITIES

#: each 1-D library's symbols, as its parameter names use them (Modelica's phi_rel0 and
#: s_rel0, w0 and v0, tau_c and f_c), and the probe quantity of each (its unit)
SYMBOLS = {
    "rotational": {"position": "phi", "speed": "w", "acceleration": "a", "flow": "tau"},
    "translational": {"position": "s", "speed": "v", "acceleration": "a", "flow": "f"},
}
QUANTITY = {
    "rotational": {"position": "angle", "speed": "speed", "acceleration": "acceleration",
                   "flow": "torque"},
    "translational": {"position": "position", "speed": "velocity",
                      "acceleration": "acceleration", "flow": "force"},
}


def _unit(domain, which):
    """The unit of a 1-D domain's "position", "speed", "acceleration" or "flow": that of the
    quantity a probe on its flange records by that name (None outside the 1-D domains)."""
    quantity = QUANTITY.get(domain, {}).get(which)
    return None if quantity is None else QUANTITIES[domain][quantity].unit


class named:
    """A role of a partial's law (``rel0``): the parameter the library names ``template``
    with its symbols ("{position}_rel0": phi_rel0 in rotational, s_rel0 in translational).
    On an instance it reads that parameter's value; on a library's class it is that
    parameter's declaration (``Inertia.position0.name == "phi0"``). Read-only: a parameter is
    set by its own name."""

    def __init__(self, template, doc):
        self.template, self.__doc__ = template, f"{doc} (the parameter {template})"
        self.role = None

    def __set_name__(self, owner, name):
        self.role = name

    def __get__(self, instance, owner):
        if instance is None:
            if getattr(owner, "domain", None) not in SYMBOLS:
                return self                         # a partial, before a library names it
            return owner.params[parameter_name(owner, self.template)]
        return getattr(instance, parameter_name(instance, self.template))

    def __set__(self, instance, value):
        key = parameter_name(instance, self.template)
        raise ModelError(f"{instance.name}.{self.role} is {instance.name}.{key}: set it by "
                         f"that name", component=instance.name, parameter=key)


def parameter_name(comp, template):
    """The name of the parameter ``template`` ("{position}0") in the library of ``comp`` (a
    component or its class)."""
    return template.format(**SYMBOLS[comp.domain])

#: Modelica's second-order Bessel filter of a position source (Rotational.Sources.Position):
#: the coefficients af, bf of phi_ref / (1 + af s / w_crit + bf s^2 / w_crit^2)
BESSEL = (1.3617, 0.6180)


class PartialCompliant(Component):
    """Two flanges and a law giving the flow from their relative position and speed.

    The law's value f is the flow into flange_b (and -f into flange_a): it acts on what
    flange_b is wired to with -f, pulling a stretched spring back.
    """
    role = "compliant"
    flange_a = Port(ONED, "Flange a (reference side)")
    flange_b = Port(ONED, "Flange b")

    def law(self, rel, rel_d):
        raise NotImplementedError

    def flows(self, pos, vel, t, u=None):
        f = self.law(pos["flange_b"] - pos["flange_a"], vel["flange_b"] - vel["flange_a"])
        return {"flange_a": -f, "flange_b": f}


class PartialSpringDamper(PartialCompliant):
    """Linear spring and damper in parallel."""
    rel0 = named("{position}_rel0", "Unstretched relative position")

    def law(self, rel, rel_d):
        return self.c * (rel - self.rel0) + self.d * rel_d


class PartialSpring(PartialCompliant):
    """Linear spring."""
    rel0 = named("{position}_rel0", "Unstretched relative position")

    def law(self, rel, rel_d):
        return self.c * (rel - self.rel0)


class PartialDamper(PartialCompliant):
    """Linear damper."""

    def law(self, rel, rel_d):
        return self.d * rel_d


class PartialSource(Component):
    """A flow source: applies ``applied()`` (its torque or force parameter), or the signal at
    ``u`` when it is wired, to flange; its reaction goes to support, if wired."""
    role = "source"
    flange = Port(ONED, "Flange driven by the source")
    support = Port(ONED, "Reaction flange (unwired: the world)", optional=True)
    u = Port("signal_in", "Signal giving the torque or force (instead of the parameter)",
             optional=True)

    def applied(self):
        raise NotImplementedError

    def signal_unit(self, port):
        return _unit(self.domain, "flow") if port == "u" else None

    def flows(self, pos, vel, t, u=None):
        f = self.applied() if u is None else u
        return {"flange": -f, "support": f}


class PartialFixed(Component):
    """A flange held at ``position0``; it takes whatever flow the network sends it."""
    role = "fixed"
    position0 = named("{position}0", "Fixed position")
    flange = Port(ONED, "Fixed flange")

    def position(self):
        return self.position0


class PartialRigid(Component):
    """A rigid 1-D element: its two flanges move together,
    position(a) = ratio * (position(b) - length).

    Rigid elements join connection sets into rigid groups that share one coordinate
    (``kinetwork.graph.topology``); an inertia adds ``inertia()`` to its group.
    """
    role = "rigid"
    flange_a = Port(ONED, "Flange a")
    flange_b = Port(ONED, "Flange b")
    has_inertia = False

    def position_ratio(self):
        """position(flange_a) / position(flange_b)."""
        return 1.0

    def length(self):
        """position(flange_b) - position(flange_a) / ratio: a translational Mass's L."""
        return 0.0

    def inertia(self):
        return 0.0


class PartialInertia(PartialRigid):
    """A rigid 1-D inertia (rotor or sliding mass) between two flanges; either may stay
    unwired."""
    flange_a = Port(ONED, "Flange a", optional=True)
    flange_b = Port(ONED, "Flange b", optional=True)
    has_inertia = True
    position0 = named("{position}0", "Initial position when it moves freely (None: 0)")
    speed0 = named("{speed}0", "Initial speed when it moves freely (None: 0)")

    def inertia(self):
        raise NotImplementedError


class PartialSensor(Component):
    """Turns a quantity of the flange it is wired to into a signal ``y``."""
    role = "sensor"
    flange = Port(ONED, "Flange measured")
    y = Port("signal_out", "Measured quantity", optional=True)
    quantity = None           # "position", "speed" or "acceleration"

    def signal_unit(self, port):
        return _unit(self.domain, self.quantity) if port == "y" else None


class PartialFlowSensor(PartialRigid):
    """Measures the flow through it (into flange_a) as a signal ``y``; rigid, massless."""
    y = Port("signal_out", "Flow through the sensor, into flange_a", optional=True)
    quantity = "flow"

    def signal_unit(self, port):
        return _unit(self.domain, "flow") if port == "y" else None


class PartialPowerSensor(PartialRigid):
    """MSL's PowerSensor and MultiSensor: rigid and massless, wired in series; at flange_a it
    reads the flow into it, its speed and their product, the power flowing from flange_a to
    flange_b, each on the output port ``outputs`` names for it."""
    quantity = "flow"
    power = Port("signal_out", "Power from flange_a to flange_b [W]", optional=True)
    #: output port -> what it carries: "flow", "speed" or "power"
    outputs = {}

    def signal_unit(self, port):
        what = self.outputs.get(port)
        if what == "power":
            return "W"
        return None if what is None else _unit(self.domain, 3 if what == "flow" else 1)


class PartialMotion(Component):
    """Prescribes the motion of its flange: ``reference`` (or the signal at ``u``, when wired)
    is the ``derivative``-th time derivative of the flange's position (0: the position, 1: the
    speed, 2: the acceleration), as Modelica's Position, Speed and Accelerate.

    The flange follows it rigidly, whatever it drives: a rotor, or a joint's axis (then the
    joint's coordinate is a known function of time and the torque the motion needs is its
    flow). With ``exact`` the reference is differentiated exactly (CasADi's derivatives of
    its expression and of the signal blocks feeding it); otherwise it is filtered, with the
    filter's states giving the position, speed and acceleration: Modelica's second-order
    Bessel filter of cut-off ``f_crit`` for a position, first-order for a speed. The
    reaction, through the optional support, rests in the world; wired to a free rotor (an
    inertia), the support takes it and the motion is relative to the rotor (MSL's
    useSupport).
    """
    role = "prescribed"
    derivative = 0
    exact = True
    flange = Port(ONED, "Flange moved")
    support = Port(ONED, "Reaction flange (unwired: the world)", optional=True)
    u = Port("signal_in", "Reference signal (instead of the parameter)", optional=True)

    #: what the reference prescribes, by ``derivative``
    prescribed = ("position", "speed", "acceleration")
    position0 = named("{position}0", "Initial position")
    speed0 = named("{speed}0", "Initial speed")

    @property
    def reference_param(self):
        """The name of the reference parameter: phi_ref, w_ref, a_ref; s_ref, v_ref."""
        return parameter_name(self, f"{{{self.prescribed[self.derivative]}}}_ref")

    @property
    def reference(self):
        """The reference (the parameter ``reference_param``), or None."""
        return getattr(self, self.reference_param)

    def signal_unit(self, port):
        return _unit(self.domain, self.prescribed[self.derivative]) if port == "u" else None

    @property
    def n_states(self):
        """States of the motion: its position (and speed), integrated or filtered."""
        return self.derivative if self.exact else 2

    def motion(self, r, x, der):
        """(position, speed, acceleration, rates of the states ``x``) for the reference
        ``r``; ``der(e)`` is the exact time derivative of an expression."""
        if self.exact:
            chain = [*x, r]              # Position [r], Speed [phi, r], Accelerate [phi, w, r]
            while len(chain) < 3:
                chain.append(der(chain[-1]))
            pos, vel, acc = chain
            return pos, vel, acc, [vel, acc][:len(x)]
        pos, vel = x
        w_crit = 2 * math.pi * self.f_crit
        if self.derivative == 0:
            af, bf = BESSEL
            acc = ((r - pos) * w_crit - af * vel) * w_crit / bf
        else:
            acc = (r - vel) * w_crit
        return pos, vel, acc, [vel, acc]

    def initial(self, r0):
        """Initial values of the states, ``r0`` the reference at the start: a filter starts
        at rest on the reference (a Position) or at its speed (a Speed)."""
        if self.exact and self.derivative == 0:
            return []
        if self.exact:
            return [self.position0, self.speed0] if self.derivative == 2 else [self.position0]
        return [r0, 0.0] if self.derivative == 0 else [self.position0, r0]
