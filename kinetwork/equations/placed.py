"""The frames assemblies place in closed form (MSL's Joints.Assemblies), and what hangs from
them.

An assembly closes its loop without a closure equation: both of its ends are placed by the
tree (or by another assembly), and from frame_b's pose relative to frame_a it places its
inner frames and gives the angle or distance of its axis (``components/assemblies.py``).
Here those placements join the tree's: each inner frame set sits in the body of the
assembly's frame_a at an expression of the coordinates, and the rigid parts hanging from it
follow by their transforms. A body there is no body of the tree (it moves with both ends of
the loop): ``applied.Extra`` takes its inertia and weight by virtual work, as it takes the
point masses of line forces.

The root of the length constraint is chosen once, at the start: the one whose axis value is
nearer the assembly's guess (MSL's positiveBranch, fixed at initialisation). It is an
expression of the parameters (the start's coordinates, substituted), so a new start given as
a parameter chooses again without a new compilation.
"""

from dataclasses import dataclass, field

import casadi as ca

from ..graph.topology import Cut


@dataclass
class Placed:
    """What the assemblies of a model place: ``sets``, the inner frame sets (and those of
    parts hanging from them); ``coordinates``, each assembly's axis PortRef -> its position
    in q; ``masses``, (assembly, mass, body index, position in that body) of the point masses
    they carry; ``checks``, (expression in q, assembly, what) that stay positive away from
    a singular position; ``branches``, assembly name -> the chosen root (+1 or -1, in p)."""
    sets: set = field(default_factory=set)
    coordinates: dict = field(default_factory=dict)
    masses: list = field(default_factory=list)
    checks: list = field(default_factory=list)
    branches: dict = field(default_factory=dict)
    #: assembly name -> the choice of root as a function of q (and p), before the start
    branch_rule: dict = field(default_factory=dict)


def relative_poses(bodies, place, set_a, set_b):
    """(Ra, pa, Rb, pb, base): two frame sets placed in the nearest body both hang from, and
    that body's pose in the world."""
    def chain(k):
        out = []
        while k >= 0:
            out.append(k)
            k = bodies[k].parent
        return out
    ka, Ra, pa = place[set_a]
    kb, Rb, pb = place[set_b]
    common = set(chain(kb))
    anc = next((k for k in chain(ka) if k in common), -1)

    def up(k, R, pos, until):
        while k != until:
            b = bodies[k]
            R, pos = b.R @ R, b.p + b.R @ pos
            k = b.parent
        return R, pos
    return (*up(ka, Ra, pa, anc), *up(kb, Rb, pb, anc), up(anc, ca.SX.eye(3), ca.SX.zeros(3),
                                                            -1))


def place_assemblies(topo, bound, bodies, place, q, q_start):
    """Add every inner frame set to ``place`` ((body, R, p), as the tree's sets) and return
    the Placed; ``q_start`` (in p) is where the start chooses each assembly's root."""
    out = Placed()
    for item in topo.placements:
        if not isinstance(item, Cut):              # a rigid part hanging from a placed frame
            comp = bound[item.component.name]
            Re, re = comp.transform(ca.SX(0, 1))
            if item.reversed:
                Re, re = Re.T, -Re.T @ re
            k, Rf, pf = place[item.parent]
            place[item.child] = (k, Rf @ Re, pf + Rf @ re)
            out.sets.add(item.child)
            continue
        comp = bound[item.component.name]
        Ra, pa, Rb, pb, _ = relative_poses(bodies, place, item.set_a, item.set_b)
        rel_R, rel_p = Ra.T @ Rb, Ra.T @ (pb - pa)
        rule = _branch(comp, rel_R, rel_p)
        branch = ca.substitute(rule, q, q_start) if q.numel() else rule
        out.branches[comp.name], out.branch_rule[comp.name] = branch, rule
        placement = comp.place(rel_R, rel_p, branch)
        k, R, p = place[item.set_a]
        for port, (Rp, pp) in placement.frames.items():
            s = topo.set_of[item.component.port_ref(port)]
            place[s] = (k, R @ Rp, p + R @ pp)
            out.sets.add(s)
        if placement.coordinate is not None:
            out.coordinates[item.component.port_ref("axis")] = placement.coordinate
        out.masses += [(comp.name, m, k, p + R @ pos) for m, pos in placement.masses]
        out.checks += [(c, comp.name, what) for c, what in placement.checks]
    return out


def _branch(comp, rel_R, rel_p):
    """+1 or -1 (in q): the root whose axis value is nearer the guess."""
    choice = comp.candidates(rel_R, rel_p)
    if choice is None:
        return ca.SX(1)
    plus, minus, guess = choice
    return ca.if_else(ca.fabs(plus - guess) <= ca.fabs(minus - guess), 1, -1)
