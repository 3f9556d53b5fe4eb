"""The mechanics of the 1-D network: flows, inertias and the balance of every rigid group.

Compliant elements and sources give their flows from the positions and speeds; a group's
inertia adds to its joint's armature (or reaches the speeds by virtual work, on an assembly's
axis); the generalized force on each group then says what it does: a joint's share of Q, a
free rotor's acceleration, a massless node's speed or position solved from its balance;
last, Kirchhoff at every set gives the flow through each rigid element (the reactions).

A step of ``network.build``: each function takes its builder.
"""

import casadi as ca

from ..errors import ModelError
from . import blockflow, supports
from .records import Hybrid, position_label, state_units


def mechanics(builder):
    """The mechanics, at its place in the order of the blocks: sources' flows, motions' drives,
    the trains riding on housings, then every group's balance."""
    flows(builder, "source")
    for m in builder.motions:
        u = blockflow.inputs(builder, m.source).get("u")
        m.reference = ca.SX(m.comp.reference if u is None else u)
        if m.group.kind == "joint":
            # the torque (force) the source applies: the generalized force the joint
            # needs, found by the formulation, through the group's ratio at the source
            drive = ca.SX.sym(f"drive_{m.comp.name}")
            apply_drive(builder, m, drive / m.k)
            m.drive = drive
    for cluster in builder.riding:             # trains riding on a housing, solved together
        supports.solve(builder, cluster)
    # motions of free flanges first: the flow into their source is then known, and so
    # the reaction on their support, before the fixed groups take it; a train on a
    # housing before the housing, which takes its reaction
    for group in supports.order(builder):
        balance(builder, group)
        if group.kind == "prescribed":
            m = next(m for m in builder.motions if m.group is group)
            apply_drive(builder, m, -builder.net.flow[group.definer])


def apply_drive(builder, motion, torque):
    """The source applies ``torque`` to its flange, and its reaction to its support."""
    builder.net.flow[motion.source.port_ref("flange")] = -torque
    builder.net.flow[motion.source.port_ref("support")] = torque


def flows(builder, role):
    """The flows of every element of ``role`` (compliant, source) from its flanges' positions
    and speeds (and, for a source, its signal input)."""
    net = builder.net
    flow = net.flow
    for comp in builder.model.components.values():
        if comp.role != role:
            continue
        b = builder.bound[comp.name]
        # a source's signal input, when wired, replaces its torque or force parameter
        u = blockflow.inputs(builder, comp).get("u") if comp.role == "source" else None
        if getattr(type(comp), "converter", False):      # an EMF: driven by its current
            u = builder.circuit.converter_current(comp)
        refs = {pn: comp.port_ref(pn) for pn in comp.ports if comp.ports[pn].domain
                in ("rotational", "translational")}
        if getattr(type(comp), "hybrid", False):
            hybrid(builder, comp, b, refs)
        out = b.flows({pn: net.pos.get(r, 0) for pn, r in refs.items()},
                      {pn: net.vel.get(r, 0) for pn, r in refs.items()}, builder.t, u)
        for pn, f in out.items():
            flow[refs[pn]] = f


def hybrid(builder, comp, b, refs):
    """An element with modes (``components/friction.py``): its mode is a state that only
    events change (rate 0), and F, what it holds with while held, a symbol solved with
    the dynamics once they are known (``modes.py``)."""
    for pn, ref in refs.items():
        group = builder.group_of.get(builder.topo.set_of[ref])
        if group is not None and group.kind == "massless":
            raise ModelError(f"{builder.model.place(comp)}: {ref.path} is on a massless "
                             f"flange, which has no acceleration for {comp.name} to hold "
                             f"or stop: give it an inertia or a mass",
                             **builder.model.fields(comp, port=pn))
    b._mode = builder.add_state(f"{comp.name}.mode", "", 0, ca.SX(0))
    b._F = ca.SX.sym(f"F_{comp.name}")
    u = builder.topo.set_of[comp.port_ref("u")] if "u" in comp.ports else None
    builder.net.hybrid.append(Hybrid(comp, b, b._mode, b._F, refs[b.side_a] if b.side_a in
                                  refs else None, refs[b.side_b], u))


def generalized(builder, group, roles=("compliant", "source"), exclude=()):
    """The generalized force on the group's coordinate of the flows applied at its sets."""
    return sum((-builder.kt[s] * builder.applied(s, roles, exclude) for s, _, _ in group.sets),
               ca.SX(0))


def group_inertia(builder, group):
    """sum(J k kt) over the group's inertias: its inertia on its coordinate."""
    at = builder.topo.set_of
    return sum((builder.bound[e.name].inertia() * builder.k[at[e.port_ref("flange_a")]] *
                builder.kt[at[e.port_ref("flange_a")]] for e in group.rigid
                if e.has_inertia), ca.SX(0))


def add_inertia(builder, group):
    """The group's inertia; on a joint, its armature, and the passive generalized force
    (springs and dampers) that an InverseDynamics block compensates."""
    inertia = group_inertia(builder, group)
    builder.inertia[group.index] = inertia
    if group.kind == "joint":
        u = speed_index(builder, group)
        builder.net.armature[u] += inertia
        builder.passive[u] += generalized(builder, group, ("compliant",))
    elif group.kind == "assembly":
        builder.passive += virtual(builder, group, generalized(builder, group, ("compliant",)))


def virtual(builder, group, gen):
    """The generalized forces on the speeds of a force ``gen`` on an assembly's axis:
    (d(speed of the axis)/du)^T gen, by virtual work."""
    return ca.jtimes(builder.coord[group.index][1], builder.u, ca.SX(gen), True)


def speed_index(builder, group):
    """The index of the speed of the joint whose coordinate a "joint" group follows."""
    joint = group.definer.component
    return builder.uindex[joint.name][joint.coordinate_ports[group.definer.name]]


def balance(builder, group):
    """The generalized force on the group's coordinate, what it does with it, and the
    flow through every rigid element and into the defining port."""
    gen = generalized(builder, group)
    theta, w, a = builder.coord[group.index]
    if group.kind == "joint":
        builder.net.Q[speed_index(builder, group)] += gen
    elif group.kind == "assembly":
        builder.net.Q += virtual(builder, group, gen)
    elif group.kind == "free" and group.index in builder.circuit.coupled:
        # a rotor a circuit's constraint holds: its acceleration came with the circuit's
        # solution, in the generalized force of all but the circuit's EMFs
        coupled = builder.circuit.coupled[group.index]
        builder.pending[coupled.rest] = generalized(builder, group, exclude=coupled.emfs)
        builder.pending[a] = coupled.acc
    elif group.kind == "free" and not any(group in c for c in builder.riding):
        builder.pending[a] = gen / builder.inertia[group.index]
    elif group.kind == "massless":
        massless(builder, group, gen)
    rigid_flows(builder, group)


def massless(builder, group, gen):
    """A massless group's speed (one first-order state, a damper on it) or position (springs
    only) solved from its balance ``gen`` = 0, linear in them."""
    theta, w, a = builder.coord[group.index]
    builder.net.no_acceleration.update(s for s, _, _ in group.sets)
    where = ", ".join(r.path for s, _, _ in group.sets for r in builder.topo.sets[s])
    dw = ca.jacobian(gen, w)
    if ca.depends_on(gen, w):
        if ca.depends_on(dw, w) or ca.depends_on(dw, theta):
            raise ModelError(f"connection set {{{where}}}: its balance is not linear "
                             f"in its speed, which kinetwork solves only when it is")
        speed = -ca.substitute(gen, w, ca.SX(0)) / dw
        x = builder.add_state(f"{group.ports[0].path}.{position_label(group)}",
                              state_units(group)[0], 0, speed)
        builder.pending[theta] = x
        builder.pending[w] = speed
        builder.pending[a] = ca.SX.nan()
        return
    dp = ca.jacobian(gen, theta)
    if not ca.depends_on(gen, theta) or ca.depends_on(dp, theta):
        raise ModelError(f"connection set {{{where}}} has no defined position: nothing "
                         f"on it depends on where it is (or not linearly)")
    position = -ca.substitute(gen, theta, ca.SX(0)) / dp
    builder.pending[theta] = position
    builder.pending[w] = (ca.jtimes(position, builder.q, builder.u)
                          + ca.jacobian(position, builder.t))
    builder.pending[a] = ca.SX.nan()


def rigid_flows(builder, group):
    """Kirchhoff at every set of the group, leaves first: the flow into a rigid element at
    its far side balances what is beyond; its law gives the near side."""
    flow = builder.net.flow
    beyond = {s: builder.applied(s, ("compliant", "source", "prescribed"))
              + supports.reactions(builder, s) for s, _, _ in group.sets}
    for s, parent, element in reversed(group.sets):
        if parent is None:
            if group.definer is not None:
                flow[group.definer] = -beyond[s]
            continue
        far = element.port_ref("flange_a" if builder.topo.set_of[element.port_ref(
            "flange_a")] == s else "flange_b")
        near = element.port_ref("flange_b" if far.name == "flange_a" else "flange_a")
        flow[far] = -beyond[s]
        b = builder.bound[element.name]
        if element.has_inertia:
            flow[near] = b.inertia() * builder.kin[s][2] - flow[far]
        elif far.name == "flange_a":          # torque_b = -ratio * torque_a
            flow[near] = -b.position_ratio() * builder.losses.get(element.name, 1) * flow[far]
        else:
            flow[near] = -flow[far] / (b.position_ratio() * builder.losses.get(element.name, 1))
        if "support" in element.ports:        # MSL: support.tau = -flange_a.tau - flange_b.tau
            flow[element.port_ref("support")] = -(flow[far] + flow[near])
        beyond[parent] = beyond[parent] + flow[near]
