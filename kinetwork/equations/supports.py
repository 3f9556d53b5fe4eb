"""Rigid 1-D groups riding on the housing of a gear (MSL's ``useSupport``), in the network.

A gear with its support wired reads its flanges relative to the support: position(a) -
position(s) = ratio * (position(b) - position(s)). Walking a rigid group from its root, a set
beyond such a gear sits at k * theta + c (c: the lengths of the masses between, MSL's L) plus
a share of the support's position (``ride``), so
each set's position is a linear form in its own group's coordinate and in those of the groups
carrying it (``kinematics``). Groups coupled this way (``kinetwork.graph.supports`` lets free
trains ride on free rotors or on prescribed motions) have one kinetic energy: their
accelerations solve

    sum_e J_e a_e d(pos_e)/d(theta_g) = sum_s d(pos_s)/d(theta_g) * (-flow into the elements at s)

for every free coordinate g of the cluster (virtual work: the gear's reaction on its housing
is in it through the housing's share of the positions). The reaction itself, -(tau_a +
tau_b) into the support, is put on the support's set for the carrier's flows and probes,
after the rider's flows are known (``order``).
"""

import casadi as ca
import networkx as nx


def ride(builder, parent, element, a_here, scale):
    """The carriers' shares in the position of the set beyond ``element``: pos(child) =
    scale * pos(parent) + (1 - scale) * pos(support), the support's term only when its set is
    wired (a fixed one is a constant offset)."""
    out = [(c * scale, s) for c, s in builder.ride[parent]]
    group = builder.group_of[parent]
    s = group.supports.get(element.name)
    if s is not None:
        out.append((1 - scale, s))
    return out


def kinematics(builder):
    """Connection set -> (position, speed, acceleration) of every 1-D set, carriers first."""
    memo = {}

    def at(s):
        if s not in memo:
            theta, w, a = builder.coord[builder.group_of[s].index]
            k = builder.k[s]
            out = [k * theta + builder.c[s], k * w, k * a]
            for c, carrier in builder.ride[s]:
                out = [o + c * v for o, v in zip(out, at(carrier))]
            memo[s] = out
        return memo[s]
    for s in builder.group_of:
        at(s)
    return memo


def clusters(builder):
    """Free groups that ride on a moving carrier or carry a rider, as lists of groups solved
    together (connected by their gears)."""
    g = nx.Graph()
    for group in builder.topo.oned:
        for s in _carriers(group):
            carrier = builder.group_of[s]
            if carrier.kind == "fixed":
                continue
            g.add_edge(group.index, carrier.index)
    out = []
    for c in sorted(nx.connected_components(g), key=min):
        members = [builder.topo.oned[i] for i in sorted(c)]
        if any(m.kind == "free" for m in members):
            out.append(members)
    return out


def _carriers(group):
    """The sets a group's positions ride on: its gears' supports, a motion's support."""
    return [*group.supports.values(), *([] if group.base is None else [group.base])]


def solve(builder, cluster):
    """The accelerations of a cluster's free coordinates, put among the pending
    substitutions."""
    coords = [builder.coord[g.index] for g in cluster if g.kind == "free"]
    theta = ca.vertcat(*[c[0] for c in coords])
    acc = ca.vertcat(*[c[2] for c in coords])
    sets = [s for g in cluster for s, _, _ in g.sets]
    at = builder.topo.set_of
    residual = ca.SX.zeros(len(coords))
    for g in cluster:
        for e in g.rigid:
            if e.has_inertia:
                pos, _, a = builder.kin[at[e.port_ref("flange_a")]]
                residual += builder.bound[e.name].inertia() * a * ca.jacobian(pos, theta).T
    for s in sets:
        pos = builder.kin[s][0]
        residual += ca.jacobian(pos, theta).T * builder.applied(s)
    A = ca.jacobian(residual, acc)
    rest = ca.substitute(residual, acc, ca.SX.zeros(acc.shape[0]))
    solved = -rest / A if len(coords) == 1 else -ca.solve(A, rest)
    for i, c in enumerate(coords):
        builder.pending[c[2]] = solved[i]


def order(builder):
    """The groups in the order their flows are balanced: a rider before its carrier (the
    gear's reaction lands on the carrier), a motion before the group its reaction rests on,
    prescribed motions first among the rest."""
    groups = builder.topo.oned
    g = nx.DiGraph()
    g.add_nodes_from(range(len(groups)))
    for group in groups:
        for s in _carriers(group):
            g.add_edge(group.index, builder.group_of[s].index)
    for m in builder.motions:
        carrier = builder.group_of.get(builder.topo.set_of[m.source.port_ref("support")])
        if carrier is not None and carrier is not m.group:
            g.add_edge(m.group.index, carrier.index)
    return [groups[i] for i in nx.lexicographical_topological_sort(
        g, key=lambda i: (groups[i].kind != "prescribed", i))]


def reactions(builder, s):
    """The flows into the supports of gears wired at the set ``s``."""
    return sum((builder.net.flow.get(r, 0) for r in builder.topo.sets[s]
                if r.component.role == "rigid" and r.name == "support"), ca.SX(0))
