"""Exact time derivatives that motion sources and circuits ask of signals.

A motion source's reference (``exact=True``) and a signal a circuit's constraint
differentiates are differentiated through t and the rates of the states they read (signal
blocks), once every signal and every rate is known; one that follows the motion of the
mechanism is refused. A step of ``network.build``: each function takes its builder.
"""

import casadi as ca

from ..errors import ModelError
from .records import Prescribed


def input_rates(builder):
    """The time derivative of each signal whose circuit constraint was differentiated (a
    voltage source's u across a capacitor): through t and the rates of the states it
    reads (signal blocks); one that follows the mechanism's motion is refused."""
    if not builder.circuit.input_rates:
        return
    sub = builder.substitution()
    moving = ca.vertcat(builder.q, builder.u, builder.udot)
    for du, s in builder.circuit.input_rates.items():
        e = sub(builder.net.signal[s])
        if ca.depends_on(e, moving):
            names = ", ".join(builder.circuit.placeholders_in(du))
            raise ModelError(f"{names}: a constraint of the circuit differentiates its "
                             f"input u, whose signal follows the motion of the mechanism; "
                             f"put a resistor or an inductor where the source meets the "
                             f"capacitors (or the inductors)")
        states = [x for x in builder.net.x if ca.depends_on(e, x)]
        rate = ca.jacobian(e, builder.t)
        if states:
            rates = [builder.net.rate[builder.index_of(x)] for x in states]
            rate += ca.jtimes(e, ca.vertcat(*states), sub(ca.vertcat(*rates)))
        builder.pending[du] = rate


def motion_laws(builder):
    """Each motion's position, speed and acceleration from its reference, once every
    signal and every state's rate is known (an exact derivative needs the rates of the
    blocks the reference comes from); in the order they were placed, so a motion read by
    a sensor feeding another is known first."""
    drives = [m.drive for m in builder.motions if m.drive is not None]
    moving = ca.vertcat(builder.q, builder.u, builder.udot, *drives,
                        *[c for m in builder.motions if m.drive is None for c in m.coord])
    for m in builder.motions:
        sub = builder.substitution()
        where = builder.model.place(m.source)

        def der(e, sub=sub, where=where, m=m):
            e = sub(e)
            if ca.depends_on(e, moving):
                raise ModelError(
                    f"{where}: exact=True differentiates the reference exactly, so it "
                    f"must follow time only (an expression in t, or signal blocks fed "
                    f"by time); the reference of {m.comp.name} depends on the motion of "
                    f"the model: set exact=False to follow it through its filter "
                    f"(f_crit)", **builder.model.fields(m.source, "exact"))
            states = [x for x in builder.net.x if ca.depends_on(e, x)]
            out = ca.jacobian(e, builder.t)
            if states:
                rates = sub(ca.vertcat(*[builder.net.rate[builder.index_of(x)] for x in states]))
                out += ca.jtimes(e, ca.vertcat(*states), rates)
            return out
        pos, vel, acc, rates = m.comp.motion(m.reference, m.x, der)
        if ca.depends_on(sub(acc), ca.vertcat(builder.udot, *drives)):
            raise ModelError(f"{where}: the acceleration {m.comp.name} prescribes depends "
                             f"on accelerations of the model at the same instant (an "
                             f"algebraic loop through the mechanics): break it with a "
                             f"state (exact=False, a FirstOrder)",
                             **builder.model.fields(m.source))
        r0 = ca.substitute(sub(m.reference), builder.t, ca.SX(0))
        for x, rate, start in zip(m.x, rates, m.comp.initial(r0)):
            builder.net.rate[builder.index_of(x)] = rate
            builder.net.start[builder.index_of(x)] = start
        if m.group.kind == "joint":
            joint = m.group.definer.component
            j = joint.coordinate_ports[m.group.definer.name]
            builder.net.prescribed[builder.uindex[joint.name][j]] = Prescribed(
                builder.qindex[joint.name][j], (pos - m.offset) / m.k, vel / m.k, acc / m.k,
                m.drive, m.comp.name, joint.name)
        else:
            builder.pending.update(zip(m.coord, (pos, vel, acc)))
