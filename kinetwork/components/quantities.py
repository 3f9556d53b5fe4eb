"""What a probe can record on a port of each domain: the ``Quantity`` table.

Kept apart from ``probe.py`` (which re-exports it) so that ``reference.py`` can list, in every
component's docstring, what a probe wired to each of its ports records, without importing the
Probe component (which builds on ``base.py``). See ``probe.py`` for the views a formula reads.
"""

from dataclasses import dataclass
from typing import Callable


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
