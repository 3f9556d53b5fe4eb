"""The 1-D rigid groups: connection sets that move as one through inertias and gears.

Each group is a tree of sets over its rigid elements, rooted where its position comes from
(a joint's coordinate, a Fixed, a motion source), or free or massless when nothing gives it;
and the motion sources on the groups, checked. A step of ``topology.analyze``.
"""

from dataclasses import dataclass, field

import networkx as nx

from ..errors import Problem
from .tree import problem_at


ONED_DOMAINS = ("rotational", "translational")


@dataclass
class OneDGroup:
    """1-D connection sets moving as one through rigid elements (inertias, gears).

    ``sets`` lists (set, parent set, rigid element) breadth-first from the root, the set of
    the ``definer`` when there is one. ``kind`` says what gives the group its position:
    "joint" (a joint's coordinate), "fixed" (a Fixed or a support), "prescribed" (a motion
    source), "free" (nothing: it has inertia, so its own coordinate and speed) or
    "massless" (nothing, and no inertia: solved from the balance of its flows). A "joint"
    group may hold one motion source too (``motion``, the source's flange): the joint's
    coordinate then follows it.
    """
    index: int
    domain: str
    sets: list
    ports: list
    definer: object = None
    kind: str = "massless"
    rigid: list = field(default_factory=list)
    motion: object = None
    #: gears of the group whose support is wired (MSL's useSupport): element name -> the
    #: connection set of its support (``kinetwork.graph.supports``)
    supports: dict = field(default_factory=dict)
    #: for a prescribed motion whose support is on a free rotor: the support's set, which the
    #: motion's flange moves relative to
    base: int = None


def oned_groups(model, topo, values, problems):
    """1-D connection sets joined by rigid elements (inertias, gears, flow sensors) into rigid
    groups (networkx connected components); each group has at most one port that sets its
    position: a joint flange, a support, a Fixed or a prescribed motion."""
    tree_joints = {j.name for j in topo.joints}
    rigid = nx.MultiGraph()
    for index, ports in enumerate(topo.sets):
        if domain_of(ports) in ONED_DOMAINS:
            rigid.add_node(index)
    for comp in model.components.values():
        if comp.role == "rigid":
            a = topo.set_of[comp.port_ref("flange_a")]
            b = topo.set_of[comp.port_ref("flange_b")]
            rigid.add_edge(a, b, key=comp.name, component=comp)
    for members in sorted(nx.connected_components(rigid), key=min):
        sub = rigid.subgraph(members)
        ports = [p for s in sorted(members) for p in topo.sets[s]
                 if p.component.role != "probe"]
        domain = domain_of(topo.sets[min(members)])
        definers = [p for p in ports if _defines(p)]
        where = "{" + ", ".join(p.path for p in ports) + "}"
        elements = sorted({d["component"].name for _, _, d in sub.edges(data=True)})
        through = f" (through {', '.join(elements)})" if elements else ""
        derived = [p for p in definers
                   if p.name in getattr(type(p.component), "derived_ports", ())]
        coords = [p for p in definers if p.name in p.component.coordinate_ports]
        motions = [p for p in definers if p.component.role == "prescribed"]
        held = [p for p in definers if p not in coords + motions + derived]
        definers = derived + coords + motions + held   # the joint's flange roots its group
        inertias = [d["component"] for _, _, d in sub.edges(data=True)
                    if d["component"].has_inertia]
        if derived:
            _derived_group(model, derived, definers, inertias, ports, where, through,
                           problems)
        elif len(coords) > 1 or (coords and held):
            problems.append(problem_at(
                model, coords[-1], f"connection set {where} rigidly ties joint "
                f"flange "
                f"{coords[0].path} to "
                f"{', '.join(p.path for p in definers[1:] if p not in motions)}"
                f"{through}: this locks or couples joints, which is not "
                f"supported yet"))
        elif len(motions) > 1:
            names = ", ".join(p.path for p in motions)
            problems.append(problem_at(
                model, motions[-1],
                f"connection set {where}: joint flange {coords[0].path} is driven by "
                f"{len(motions)} prescribed motions ({names}){through}; a joint follows one "
                f"motion: remove all but one" if coords else
                f"connection set {where} rigidly ties prescribed motion {motions[0].path} to "
                f"{', '.join(p.path for p in motions[1:])}{through}: one rigid group cannot "
                f"follow two prescribed motions"))
        elif motions and held:
            problems.append(problem_at(
                model, motions[0], f"connection set {where} rigidly ties "
                f"prescribed motion {motions[0].path} to "
                f"{', '.join(p.path for p in held)}{through}: a flange held "
                f"in place cannot follow a motion"))
        elif len(held) > 1 and values is not None:
            spots = {p.path: (topo.set_of[p], _fixed_position(p, values)) for p in held}
            if len(set(spots.values())) > 1:
                problems.append(problem_at(
                    model, held[-1], f"connection set {where} holds fixed "
                    f"flanges at different positions: "
                    + str({k: v[1] for k, v in spots.items()}) + through))
        cycles = nx.cycle_basis(nx.Graph(sub)) if sub.number_of_edges() else []
        parallel = [sorted(sub.get_edge_data(u, v)) for u, v in {(u, v) for u, v, _ in
                                                                 sub.edges(keys=True)}
                    if len(sub.get_edge_data(u, v)) > 1]
        if cycles or parallel:
            names = parallel[0] if parallel else sorted({
                sub.get_edge_data(u, v)[next(iter(sub.get_edge_data(u, v)))]["component"].name
                for cyc in cycles[:1] for u, v in zip(cyc, cyc[1:] + cyc[:1])})
            problems.append(Problem(f"rigid 1-D elements {', '.join(names)} form a closed "
                                    f"loop (they tie flanges together twice): remove one",
                                    **model.fields(model.components[names[-1]])))
        for p in coords:
            if p.component.name not in tree_joints:
                problems.append(problem_at(
                    model, p, f"{p.path}: joint {p.component.name!r} has no "
                    f"coordinates here, so its flange cannot be used"))
        kind = ("assembly" if derived else "joint" if coords else
                "prescribed" if motions else
                "fixed" if definers else "free" if inertias else
                "world" if len(ports) <= 1 else "massless")
        if kind == "free" and values is not None and all(
                e.bound(values[e.name]).inertia() == 0 for e in inertias):
            problems.append(Problem(f"connection set {where}: the inertia of "
                                    f"{', '.join(e.name for e in inertias)} is zero and "
                                    f"nothing holds the flange, so its motion is not "
                                    f"determined", **model.fields(inertias[0], "J" if "J" in
                                                                  inertias[0].params else
                                                                  None)))
        if kind == "massless" and not any(p.component.role == "compliant" for p in ports):
            problems.append(problem_at(
                model, ports[0], f"connection set {where} has no defined "
                f"{domain} position: it has no inertia, spring or damper, so "
                f"the flows on it cannot balance; wire it to a joint flange, "
                f"a Fixed or an inertia"))
        # a free group's coordinate is its first inertia's position (the state named after it)
        root = (topo.set_of[definers[0]] if definers else
                topo.set_of[inertias[0].port_ref("flange_a")] if kind == "free" else
                min(members))
        topo.oned.append(OneDGroup(len(topo.oned), domain, _rooted(sub, root), ports,
                                   definers[0] if definers else None, kind,
                                   [d["component"] for _, _, d in sub.edges(data=True)],
                                   motions[0] if coords and motions else None))


def _derived_group(model, derived, definers, inertias, ports, where, through, problems):
    """A rigid group whose position an assembly gives (its axis: the angle or distance of
    its last joint, a function of where its ends are): it can carry springs, dampers,
    forces and sensors, whose generalized force reaches the mechanism by virtual work, but
    nothing may set its position, nor give it inertia or a stuck mode."""
    flange = derived[0]
    others = [p for p in definers if p is not flange]
    modes = sorted({p.component.name for p in ports if getattr(type(p.component), "hybrid",
                                                                 False)})
    why = None
    if others:
        why = (f"it is tied to {', '.join(p.path for p in others)}{through}, which sets a "
               f"position too")
    elif inertias:
        why = (f"{', '.join(e.name for e in inertias)} would give it inertia; put the mass on "
               f"a body at the assembly's inner frame instead")
    elif modes:
        why = f"{', '.join(modes)} would hold it with friction or a stop"
    if why:
        problems.append(f"connection set {where}: the position of {flange.path} follows from "
                        f"{flange.component.name}'s loop (the angle or distance that closes "
                        f"it), so {why}; drive or hold a joint of the tree instead")


def motions(model, topo, problems):
    """A motion source takes its reference from its parameter or from its input u, not
    both; its reaction rests in the world (unwired support, a joint's support or a Fixed:
    nothing there moves) or, for a motion that is no joint's, on a free rotor: then the
    motion is relative to it, as MSL's with useSupport."""
    group_of = {s: g for g in topo.oned for s, _, _ in g.sets}
    for comp in model.components.values():
        if comp.role != "prescribed":
            continue
        key = comp.reference_param
        wired = topo.set_of[comp.port_ref("u")] in topo.signal_source
        given = comp.reference is not None
        if wired and given:
            problems.append(model.problem(f"{comp.name}.u is wired too; the reference comes "
                                          f"from one of them: remove {key} or the wire", comp,
                                          key, hint=f"remove {key} or the wire to u"))
        elif not wired and not given:
            problems.append(model.problem(f"no reference: give {key} (an expression in time "
                                          f"t) or wire a signal to {comp.name}.u", comp, key))
        support = comp.port_ref("support")
        group = group_of.get(topo.set_of[support])
        own = group_of.get(topo.set_of[comp.port_ref("flange")])
        if group is None or group.kind in ("fixed", "world"):
            continue
        if group.kind == "free" and own is not None and own.kind == "prescribed" and \
                own is not group:
            own.base = topo.set_of[support]        # it moves relative to a free housing
            continue
        problems.append(model.problem(f"{support.path} is wired to a flange that moves "
                                      f"({group.kind}); the reaction of a prescribed motion "
                                      f"rests on a free rotor (an inertia) or in the world: "
                                      f"wire the support to an inertia of its own, a joint's "
                                      f"support or a Fixed, or leave it unwired", comp,
                                      port="support"))


def domain_of(ports):
    """The domain of a connection set: that of its first port that is not a probe's."""
    return next((p.domain for p in ports if p.component.role != "probe"), ports[0].domain)


def _rooted(sub, root):
    """The group's sets, ``root`` first, each with (parent set, rigid element) of the
    breadth-first tree over the rigid elements."""
    order = [(root, None, None)]
    for parent, child in nx.bfs_edges(nx.Graph(sub), root):
        data = next(iter(sub.get_edge_data(parent, child).values()))
        order.append((child, parent, data["component"]))
    return order


def _defines(ref):
    comp = ref.component
    return (ref.name in comp.coordinate_ports
            or ref.name in getattr(type(comp), "derived_ports", ())
            or ref.name in comp.zero_ports
            or comp.role == "fixed"
            or (comp.role == "prescribed" and ref.name == "flange"))


def _fixed_position(ref, values):
    comp = ref.component
    if comp.role == "fixed":
        return comp.bound(values[comp.name]).position()
    return 0.0
