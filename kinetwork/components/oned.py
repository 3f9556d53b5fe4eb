"""Partials shared by the 1-D rotational and translational libraries.

A library subclasses these with ``domain`` set; its components then only declare parameters
and a law. Flows are positive into the component, as in Modelica.
"""

from .base import ONED, Component, Port


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

    def flows(self, pos, vel, t):
        f = self.law(pos["flange_b"] - pos["flange_a"], vel["flange_b"] - vel["flange_a"])
        return {"flange_a": -f, "flange_b": f}


class PartialSource(Component):
    """A flow source: applies ``value(t)`` to flange; its reaction goes to support, if wired."""
    role = "source"
    flange = Port(ONED, "Flange driven by the source")
    support = Port(ONED, "Reaction flange (unwired: the world)", optional=True)

    def value(self, t):
        raise NotImplementedError

    def flows(self, pos, vel, t):
        f = self.value(t)
        return {"flange": -f, "support": f}


class PartialFixed(Component):
    """A flange held at a fixed position; it takes whatever flow the network sends it."""
    role = "fixed"
    flange = Port(ONED, "Fixed flange")

    def position(self):
        raise NotImplementedError
