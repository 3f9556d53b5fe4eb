"""Signals: what a model records, one ``Signal`` descriptor per probe quantity.

A descriptor is made where the quantity is evaluated (``probe_signals``, from the
``Quantity`` declarations of ``kinetwork.components.probe``) and travels unchanged to the
results, the CSV columns and the plots: its name, unit and shape say everything they need, so
nothing downstream guesses a shape from a size or splits names to find a probe again.

The expression of a signal is in the assembly's symbols (t, q, u, udot, lam, p): the joint
coordinates, speeds, their rates and the loop multipliers. Which values udot and lam take
depends on the formulation of the loops, so the ``System`` binds them when it builds its
output function.
"""

from dataclasses import dataclass, field, replace
from functools import cached_property
from math import prod

import casadi as ca

from ..components.probe import QUANTITIES
from ..errors import ModelError
from ..graph.signal_units import signal_units
from ..spatial import vee


@dataclass(frozen=True)
class Signal:
    """One recorded quantity: ``probe1.angle`` [rad], shape ()."""
    name: str
    unit: str
    shape: tuple          # () scalar, (3,) vector, (3, 3) matrix (row-major in the columns)
    probe: str
    quantity: str
    target: str           # the port measured, "shoulder.axis"
    expression: ca.SX = field(default=None, compare=False, repr=False)

    @property
    def size(self):
        return prod(self.shape)

    def column_names(self):
        """The CSV columns: ``name``, ``name[i]`` or ``name[i,j]``."""
        if self.shape == ():
            return [self.name]
        if len(self.shape) == 1:
            return [f"{self.name}[{i}]" for i in range(self.shape[0])]
        return [f"{self.name}[{i},{j}]" for i in range(self.shape[0])
                for j in range(self.shape[1])]

    def flat(self):
        """The expression as a column, row-major (CasADi flattens column-major)."""
        e = ca.SX(self.expression)
        return ca.vec(e.T) if len(self.shape) == 2 else ca.vec(e)

    def described(self):
        """The descriptor without its expression: what results keep."""
        return replace(self, expression=None)


def probe_signals(asm, topo, net, bound, model):
    """The Signals of every probe of the model, in model order."""
    out = []
    units = None
    # a probe on a composite part's pin reads an inner part's (a DCMotor's p is its Ra's):
    # the signal names the pin the user wired (the flattening's aliases)
    aliases = getattr(model, "aliases", None) or {}
    for probe, target in topo.probes:
        where = model.place(probe)
        unit = None
        if target.domain == "frame":
            view = FrameView(asm, topo, target, bound)
        elif target.domain in ("signal_in", "signal_out"):
            view = SignalView(net.signal.get(topo.set_of[target], ca.SX.nan()))
            units = signal_units(model, topo) if units is None else units
            unit = units.get(topo.set_of[target])
        elif target.domain == "electrical":
            view = PinView(net.pos[target], net.flow.get(target, ca.SX(0)))
        else:
            view = FlangeView(net, topo, target, where)
        for quantity in probe.asked(target.domain):
            spec = QUANTITIES[target.domain][quantity]
            out.append(Signal(f"{probe.name}.{quantity}", unit or spec.unit, spec.shape,
                              probe.name, quantity, aliases.get(target.path, target.path),
                              ca.SX(spec.formula(view))))
    return out


class SignalView:
    """A signal port as a probe formula reads it."""

    def __init__(self, value):
        self.value = value


class PinView:
    """An electrical pin as a probe formula reads it: potential v and current i."""

    def __init__(self, v, i):
        self.v, self.i = v, i


class FlangeView:
    """A 1-D flange as a probe formula reads it: pos, vel, acc and flow."""

    def __init__(self, net, topo, target, where):
        self.net, self.topo, self.target, self.where = net, topo, target, where
        self.pos, self.vel = net.pos[target], net.vel[target]
        self.flow = net.flow.get(target, ca.SX(0))

    @property
    def acc(self):
        if self.topo.set_of[self.target] in self.net.no_acceleration:
            raise ModelError(acceleration_unavailable(self.where, self.target))
        return self.net.acc[self.target]


class FrameView:
    """A frame as a probe formula reads it: world kinematics differentiated exactly by
    CasADi, and the cut wrench from the balance of everything behind the connection."""

    def __init__(self, asm, topo, target, bound):
        self.asm, self.topo, self.target, self.bound = asm, topo, target, bound
        self.R, self.r = asm.pose(topo.set_of[target])

    def der(self, expr):
        """d(expr)/dt for an expression in (q, u), with u's rate ``udot``."""
        return self.asm.rate(expr)

    @cached_property
    def w(self):
        return vee(self.der(self.R) @ self.R.T)

    @cached_property
    def _wrench(self):
        from .wrench import cut_wrench          # only models that ask for it pay for it
        return cut_wrench(self.asm, self.topo, self.target, self.bound)

    @property
    def f(self):
        return self._wrench[0]

    @property
    def t(self):
        return self._wrench[1]


def acceleration_unavailable(where, ref):
    return (f"{where}: the acceleration of {ref.path} is not available: that flange has no "
            f"inertia (a damper sets its speed); measure its speed or position instead")
