"""The start values of 1-D inertias (``phi0``, ``w0``; a Mass's ``s0``, ``v0``): used, or
refused with the reason, never dropped.

An inertia's start is where its flange is at t = 0. What that is depends on its rigid group:

- free: the group's own coordinate and speed start where the first inertia giving them puts
  them (through the gears between, and the share of a housing it rides on);
- on a joint axis: the joint's coordinate and speed start there (MSL's Engine1a puts the
  engine's start speed on the load inertia), unless the joint's own q0 / qd0 is given;
- anything else (a joint whose q0 is given, a prescribed motion, a fixed flange, a second
  inertia of the same group) decides the start itself: a value that agrees is accepted, one
  that does not is refused naming what decides it (``check``).
"""

import casadi as ca
import numpy as np

from ..errors import ModelError

#: (attribute, index in a set's (position, speed, acceleration))
QUANTITIES = (("position0", 0), ("speed0", 1))


def _given(group, attr):
    """The group's inertias that give ``attr``, in the group's order."""
    return [e for e in group.rigid if e.has_inertia and getattr(e, attr) is not None]


def _solved_for(builder, e, which, symbol, attr):
    """The value of ``symbol`` that puts inertia ``e`` at its given start: the inverse of
    the linear form of its position (or speed)."""
    expr = builder.kin[builder.topo.set_of[e.port_ref("flange_a")]][which] + \
        _centre(builder.bound[e.name], which)
    k = ca.jacobian(expr, symbol)
    rest = ca.substitute(expr, symbol, ca.SX(0))
    return (getattr(builder.bound[e.name], attr) - rest) / k


def _centre(bound, which):
    """From an inertia's flange_a to where its start is given: a Mass's position is its
    centre, L/2 beyond flange_a (MSL's Mass.s); a speed is the same at both."""
    return bound.length() / 2 if which == 0 else 0


def free(builder):
    """The starts of every free group's coordinate and speed."""
    for group in builder.topo.oned:
        if group.kind != "free":
            continue
        coord = builder.coord[group.index]
        for attr, which in QUANTITIES:
            given = _given(group, attr)
            if given:
                symbol = coord[which]
                builder.net.start[builder.index_of(symbol)] = _solved_for(builder, given[0], which,
                                                                     symbol, attr)


def claims(builder):
    """The joint starts that inertias on joint axes give: (``"q"`` or ``"u"``, the
    coordinate's or speed's index, its value as SX in the parameters)."""
    out = []
    for group in builder.topo.oned:
        if group.kind != "joint" or group.motion is not None:
            continue
        joint = group.definer.component
        j = joint.coordinate_ports[group.definer.name]
        qi, ui = builder.qindex[joint.name][j], builder.uindex[joint.name][j]
        for (attr, which), (kind, index, symbol) in zip(QUANTITIES, (
                ("q", qi, builder.q[qi]), ("u", ui, builder.u[ui]))):
            given = _given(group, attr)
            if given:
                out.append((kind, index, _solved_for(builder, given[0], which, symbol, attr)))
    return out


def resolve(net, t):
    """The network's starts in the parameters alone: time at 0, and a start that reads
    another state (a train riding on a housing) that state's start."""
    if not net.x:
        return
    x = ca.vertcat(t, *net.x)
    values = ca.densify(ca.vertcat(*[ca.SX(v) for v in net.start]))
    for _ in range(len(net.x) + 1):
        if not ca.depends_on(values, x):
            break
        values = ca.substitute(values, x, ca.vertcat(ca.SX(0), values))
    net.start = ca.vertsplit(values)


def check(model, topo, asm, bound, p_values):
    """Refuse an inertia's start that the model's start does not give, naming what decides
    it; accept every other."""
    net = asm.net
    rows = []
    for group in topo.oned:
        for attr, which in QUANTITIES:
            for e in _given(group, attr):
                ref = e.port_ref("flange_a")
                actual = (net.pos if which == 0 else net.vel).get(ref)
                if actual is not None:
                    rows.append((e, attr, group, getattr(bound[e.name], attr),
                                 actual + _centre(bound[e.name], which)))
    if not rows:
        return
    known = ca.vertcat(asm.t, asm.q, asm.u, *net.x)
    at_start = ca.densify(ca.vertcat(ca.SX(0), asm.q_start, asm.u_start,
                                     *[ca.SX(v) for v in net.start]))
    actual = ca.densify(ca.vertcat(*[ca.SX(r[4]) for r in rows]))
    for _ in range(known.shape[0] + 1):
        if not ca.depends_on(actual, known):
            break
        actual = ca.substitute(actual, known, at_start)
    if ca.depends_on(actual, known):
        return              # a start read through the mechanism's own motion: not checked
    given = ca.vertcat(*[ca.SX(r[3]) for r in rows])
    f = ca.Function("inertia_starts", [asm.p], [given, actual])
    want, have = (np.asarray(v, dtype=float).ravel() for v in f(p_values))
    problems = []
    for (e, attr, group, _, _), a, b in zip(rows, want, have):
        if abs(a - b) > 1e-9 * (1 + abs(b)):
            key = getattr(type(e), attr).name
            problems.append(f"{model.place(e, key)} = {a:.12g}: "
                            f"{_decided_by(e, group, attr, topo.set_of)} "
                            f"puts {e.name} at {b:.12g} at the start; "
                            f"give values that agree, or leave {key} unset")
    if problems:
        raise ModelError(problems)


def _decided_by(e, group, attr, set_of):
    """What decides the start of inertia ``e``'s flange, for a message."""
    first = _given(group, attr)[0]
    parent = {s: (up, element) for s, up, element in group.sets}

    def path(x):
        out, s = [], set_of[x.port_ref("flange_a")]
        while parent[s][0] is not None:
            s, element = parent[s]
            out.append(element.name)
        return out
    mine = path(e)
    theirs = path(first) if first is not e and group.kind not in ("joint", "fixed",
                                                                     "prescribed") else []
    through = sorted((set(mine) ^ set(theirs)) - {e.name, first.name})
    rigid = f" (rigidly, through {', '.join(through)})" if through else ""
    if group.kind == "joint" and group.motion is not None:
        return f"the motion {group.motion.component.name}, which moves joint " \
               f"{group.definer.component.name}{rigid},"
    if group.kind == "joint":
        label = "q0" if attr == "position0" else "qd0"
        owner = (f"joint {group.definer.component.name}'s {label}" if first is e else
                 f"{first.name}'s start on joint {group.definer.component.name}")
        return f"{owner}{rigid}"
    if group.kind == "prescribed":
        return f"the motion {group.definer.component.name}{rigid}"
    if group.kind == "fixed":
        return f"{group.definer.path}, which holds the flange{rigid},"
    return f"{first.name}'s start{rigid}"
