"""Probe: records quantities of the port it is wired to, adding nothing to the physics.

Each quantity a probe can record is one ``Quantity`` entry below: its unit, its shape and its
formula over a *view* of the measured port. The equations layer hands the formula a view
whose attributes are the port's variables as CasADi expressions (built only when a formula
reads them):

- 1-D flange: ``pos``, ``vel``, ``acc`` (its position and their rates) and ``flow`` (the
  torque or force the network puts through it);
- frame: ``r`` (origin, world), ``R`` (orientation, world), ``w`` (angular velocity, world),
  ``f`` and ``t`` (the cut force, and the cut torque about the world origin), and ``der(e)``,
  the exact time derivative of any expression of those;
- signal: ``value``.

A new probe quantity is one entry here: the results, the CSV columns and the plots take its
name, unit and shape from the ``Signal`` descriptor built from it.
"""

from dataclasses import dataclass
from typing import Callable

from .base import ANY, Component, Param, Port


@dataclass(frozen=True)
class Quantity:
    """What a probe records: unit, shape (() scalar, (3,) vector, (3, 3) matrix), formula."""
    unit: str
    shape: tuple
    formula: Callable


def _cross(a, b):
    import casadi as ca           # imported here: components stay free of CasADi at import
    return ca.cross(a, b)


#: quantities a probe can record, by the domain of the port it is wired to
QUANTITIES = {
    "rotational": {
        "angle": Quantity("rad", (), lambda p: p.pos),
        "speed": Quantity("rad/s", (), lambda p: p.vel),
        "acceleration": Quantity("rad/s^2", (), lambda p: p.acc),
        "torque": Quantity("N*m", (), lambda p: p.flow),
    },
    "translational": {
        "position": Quantity("m", (), lambda p: p.pos),
        "velocity": Quantity("m/s", (), lambda p: p.vel),
        "acceleration": Quantity("m/s^2", (), lambda p: p.acc),
        "force": Quantity("N", (), lambda p: p.flow),
    },
    "frame": {
        "position": Quantity("m", (3,), lambda p: p.r),
        "velocity": Quantity("m/s", (3,), lambda p: p.der(p.r)),
        "acceleration": Quantity("m/s^2", (3,), lambda p: p.der(p.der(p.r))),
        "orientation": Quantity("", (3, 3), lambda p: p.R),
        "angular_velocity": Quantity("rad/s", (3,), lambda p: p.w),
        "angular_acceleration": Quantity("rad/s^2", (3,), lambda p: p.der(p.w)),
        # the flow into the measured component, the torque taken about the frame origin
        "force": Quantity("N", (3,), lambda p: p.f),
        "torque": Quantity("N*m", (3,), lambda p: p.t - _cross(p.r, p.f)),
    },
    # an electrical pin: its potential, and the current into the component at it
    "electrical": {
        "voltage": Quantity("V", (), lambda p: p.v),
        "current": Quantity("A", (), lambda p: p.i),
    },
    "signal_in": {"value": Quantity("", (), lambda p: p.value)},
    "signal_out": {"value": Quantity("", (), lambda p: p.value)},
}
_ALL = sorted({q for qs in QUANTITIES.values() for q in qs})


class Probe(Component, library=""):
    """Measures the port it is wired to: 1-D flange or frame (see QUANTITIES)."""
    role = "probe"
    port = Port(ANY, "Wire to the port to measure")
    quantities = Param(None, optional=True, kind="names", choices=_ALL,
                       doc="What to record (default: all of the port's domain)")

    def asked(self, domain):
        """The quantity names recorded on a port of ``domain``, in order."""
        return list(QUANTITIES[domain]) if self.quantities is None else list(self.quantities)
