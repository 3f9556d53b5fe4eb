"""Probe: records quantities of the port it is wired to, adding nothing to the physics."""

from .base import ANY, Component, Param, Port

#: quantities a probe can record, with units, by the domain of the port it is wired to
QUANTITIES = {
    "rotational": {"angle": "rad", "speed": "rad/s", "acceleration": "rad/s^2",
                   "torque": "N*m"},
    "translational": {"position": "m", "velocity": "m/s", "acceleration": "m/s^2",
                      "force": "N"},
    "frame": {"position": "m", "velocity": "m/s", "acceleration": "m/s^2",
              "orientation": "", "angular_velocity": "rad/s",
              "angular_acceleration": "rad/s^2", "force": "N", "torque": "N*m"},
    "signal_in": {"value": ""},
    "signal_out": {"value": ""},
}
_ALL = sorted({q for qs in QUANTITIES.values() for q in qs})


class Probe(Component, library=""):
    """Measures the port it is wired to: 1-D flange or frame (see QUANTITIES)."""
    role = "probe"
    port = Port(ANY, "Wire to the port to measure")
    quantities = Param(None, optional=True, kind="names", choices=_ALL,
                       doc="What to record (default: all of the port's domain)")
