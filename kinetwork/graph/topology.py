"""Topology: connection sets, the spanning tree from the ground, and what each set means.

Ports are nodes and connections edges of a networkx graph; a connection set is a connected
component (potentials equal, flows summing to zero). Frame sets are the nodes of a second
graph whose edges are joints and rigid parts. Its maximum spanning tree (weights prefer to
keep rigid parts and regular joints, and to cut joints marked ``cut``, FreeMotion and
Spherical joints) is walked breadth-first from the ground to order the Newton-Euler
recursion; every edge left out is a cut joint that closes one independent kinematic loop.
"""

import warnings
from dataclasses import dataclass, field

import networkx as nx
import numpy as np

from ..components.probe import QUANTITIES
from ..errors import IdealisedInertiaWarning, ModelError
from . import supports

ONED_DOMAINS = ("rotational", "translational")
SIGNAL_DOMAINS = ("signal_in", "signal_out")


@dataclass
class Edge:
    """A joint or rigid part of the spanning tree, traversed parent -> child."""
    component: object
    parent: int          # frame set towards the ground
    child: int           # frame set away from the ground
    reversed: bool       # True when frame_b faces the ground


@dataclass
class Cut:
    """A joint or rigid part left out of the spanning tree: it closes a kinematic loop."""
    component: object
    set_a: int           # frame set of its frame_a
    set_b: int           # frame set of its frame_b
    loop: list           # names of the loop's parts, the tree path then the cut


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


@dataclass(repr=False)
class Topology:
    """What validation learned about a model; the solver's starting point."""
    world: object
    sets: list                          # connection sets (lists of PortRef)
    set_of: dict                        # PortRef -> set index
    root: int                           # frame set of the ground
    tree: list = field(default_factory=list)      # Edge, parents before children
    joints: list = field(default_factory=list)    # joints with coordinates, model order
    bodies: list = field(default_factory=list)    # (body or part with mass, frame_a set)
    oned: list = field(default_factory=list)      # OneDGroup
    probes: list = field(default_factory=list)    # (Probe, target PortRef)
    loops: list = field(default_factory=list)     # lists of component names
    cuts: list = field(default_factory=list)      # Cut, one per independent loop
    forces: list = field(default_factory=list)    # frame force elements (line, world)
    #: frame sets only line forces meet at (massless junctions), placed by their balance
    junctions: list = field(default_factory=list)
    signal_source: dict = field(default_factory=dict)   # signal set -> its output PortRef

    @property
    def dof(self):
        """Degrees of freedom of the joints, less the coordinates prescribed by motions."""
        return sum(j.dof for j in self.joints) - sum(1 for g in self.oned if g.motion)

    def __repr__(self):
        # short: ``model.validate()`` at a prompt echoes it (the dataclass's own repr
        # spells out every connection set, kilobytes for a small model)
        counts = [(len(self.joints), "joint"), (len(self.bodies), "body"),
                  (len(self.loops), "kinematic loop"), (len(self.probes), "probe")]
        return "<Topology: " + ", ".join(
            f"{n} {word if n == 1 else ('bodies' if word == 'body' else word + 's')}"
            for n, word in counts) + ">"


def analyze(model):
    """Validate ``model``'s wiring and return its Topology; one ModelError lists all problems."""
    problems = []
    values = None
    try:
        values = model.numeric_values()
    except ModelError as exc:
        problems.extend(exc.problems)

    graph = nx.Graph()
    for comp in model.components.values():
        for pname in comp.ports:
            graph.add_node(comp.port_ref(pname))
    stale = []
    for i, (a, b) in enumerate(model.connections):
        gone = [p for p in (a, b) if model.components.get(p.component.name) is not p.component]
        if gone:                # a component taken out of model.components by hand
            stale.append(f"connections[{i}] {a.path} - {b.path}: component "
                         f"{gone[0].component.name!r} is not in the model any more "
                         f"(remove its connections too)")
        else:
            graph.add_edge(a, b)
    for comp in model.components.values():
        # ports one node inside their component (MSL's Brake: flange_a and flange_b joined)
        for a, b in getattr(type(comp), "joined_ports", ()):
            graph.add_edge(comp.port_ref(a), comp.port_ref(b))
    if stale:
        raise ModelError(problems + stale)
    order = _order(model)                      # once: it ranks every component
    sets = [sorted(s, key=order) for s in nx.connected_components(graph)]
    sets.sort(key=lambda s: order(s[0]))
    set_of = {p: i for i, s in enumerate(sets) for p in s}

    roles = {}
    for comp in model.components.values():
        roles.setdefault(comp.role, []).append(comp)

    probes = _probes(model, graph, roles.get("probe", []), problems)
    for comp in model.components.values():
        if comp.role == "probe":
            continue
        for pname, port in comp.ports.items():
            ref = comp.port_ref(pname)
            if (not port.optional or pname in comp.required_ports()) and all(
                    p.component.role == "probe" for p in sets[set_of[ref]] if p != ref):
                problems.append(f"{model.place(comp)}: port {ref.path} ({port.domain}) "
                                f"is not connected")

    worlds = roles.get("world", [])
    frames = any(p.domain == "frame" for c in model.components.values() for p in
                 c.ports.values())
    if len(worlds) > 1 or (not worlds and frames):
        names = ", ".join(w.name for w in worlds)
        problems.append("the model needs exactly one multibody.Ground, found "
                        f"{len(worlds)}{': ' + names if names else ''}")
        if not worlds:
            raise ModelError(problems)
    world = worlds[0] if worlds else None          # a 1-D and signal model needs none
    topo = Topology(world=world, sets=sets, set_of=set_of,
                    root=set_of[world.port_ref("frame")] if world else None, probes=probes)
    if world is not None:
        _tree(model, topo, roles, problems)
    _oned(model, topo, values, problems)
    supports.check(model, topo, values, problems)
    _signals(topo, problems)
    _motions(model, topo, problems)
    supports.rings(topo, problems)
    if values is not None and topo.junctions:
        _junction_masses(model, topo, values, problems)
    if values is not None:
        _inertias(model, [c for c in model.components.values() if c.role == "body" or (
            c.role in ("joint", "part") and c.has_mass)], values, problems)
        for comp in model.components.values():
            problems.extend(comp.check_values(values[comp.name],
                                              lambda key, c=comp: model.place(c, key)))
    if problems:
        raise ModelError(problems)
    return topo


def _order(model):
    rank = {name: i for i, name in enumerate(model.components)}
    port_rank = {}

    def key(ref):
        comp = ref.component
        if comp.name not in port_rank:
            port_rank[comp.name] = {p: i for i, p in enumerate(comp.ports)}
        return rank[comp.name], port_rank[comp.name][ref.name]
    return key


def _probes(model, graph, probes, problems):
    out = []
    for probe in probes:
        ref = probe.port_ref("port")
        wired = list(graph.neighbors(ref))
        if len(wired) != 1:
            what = "nothing" if not wired else ", ".join(p.path for p in wired)
            problems.append(f"{model.place(probe)}: a probe is wired to exactly one port; "
                            f"{probe.name}.port is wired to {what}")
            continue
        target = wired[0]
        if target.component.role == "probe":
            problems.append(f"{model.place(probe)}: wired to another probe ({target.path})")
            continue
        allowed = QUANTITIES.get(target.domain)
        if allowed is None:
            problems.append(f"{model.place(probe)}: cannot measure {target.path} "
                            f"({target.domain} ports are not measured by probes)")
            continue
        asked = probe.quantities if probe.quantities is not None else list(allowed)
        for q in asked:
            if q not in allowed:
                problems.append(f"{model.place(probe, 'quantities')}: {q!r} is not a quantity "
                                f"of a {target.domain} port ({target.path}); choose from "
                                f"{', '.join(allowed)}")
        out.append((probe, target))
    return out


def _keep_weight(comp):
    """Preference for keeping a part in the spanning tree (the rest are cut): a joint marked
    ``cut`` goes first, then as its class ranks itself (``cut_preference``)."""
    return -1 if comp._values.get("cut", False) else comp.cut_preference


def _tree(model, topo, roles, problems):
    """Spanning tree of frame sets from the ground; the joints left out cut the loops."""
    frames = nx.MultiGraph()
    frames.add_node(topo.root)
    # joints and rigid parts are the edges, in model order (ties go to the part added first)
    joints = [c for c in model.components.values() if c.role in ("joint", "part")]
    for rank, comp in enumerate(joints):
        a, b = topo.set_of[comp.port_ref("frame_a")], topo.set_of[comp.port_ref("frame_b")]
        if a == b:
            problems.append(f"{model.place(comp)}: frame_a and frame_b are connected to each "
                            f"other, which locks the part")
            continue
        # ties go to the part added first: the last joint of a loop closes it (is cut)
        tie = 0.5 * (len(joints) - rank) / len(joints)
        frames.add_edge(a, b, key=comp.name, component=comp, weight=_keep_weight(comp) + tie)
    for comp in [*roles.get("body", []), *roles.get("frame_force", [])]:
        for pname in comp.ports:
            frames.add_node(topo.set_of[comp.port_ref(pname)])

    reached = nx.node_connected_component(frames, topo.root)
    topo.junctions = _junctions(model, topo, roles.get("frame_force", []), frames, reached,
                                problems)
    placed = reached | set(topo.junctions)
    for comp in [*joints, *roles.get("body", []), *roles.get("frame_force", [])]:
        # frames a cut joint places from where its ends are (a rod's frame_ia): for probes
        by_cut = getattr(type(comp), "placed_frames", ())
        for pname in by_cut:
            stray = [p.path for p in topo.sets[topo.set_of[comp.port_ref(pname)]]
                     if p.component is not comp and p.component.role != "probe"]
            if stray:
                problems.append(f"{model.place(comp)}: {comp.name}.{pname} is for probes "
                                f"only, but {', '.join(stray)} is wired to it")
        for pname in comp.ports:
            if comp.ports[pname].domain == "frame" and pname not in by_cut and \
                    _dangling(topo, comp, pname) and \
                    len(topo.sets[topo.set_of[comp.port_ref(pname)]]) > 1 and \
                    topo.set_of[comp.port_ref(pname)] not in reached:
                problems.append(f"{model.place(comp)}: {comp.name}.{pname} is not wired, so "
                                f"it has no pose for a probe to measure")
            if comp.ports[pname].domain == "frame" and pname not in by_cut and \
                    not _dangling(topo, comp, pname) and \
                    topo.set_of[comp.port_ref(pname)] not in placed:
                problems.append(f"{model.place(comp)}: {comp.name} is not connected to the "
                                f"ground {topo.world.name!r} through joints or rigid parts")
                break

    sub = frames.subgraph(reached)
    tree = nx.Graph()
    tree.add_node(topo.root)
    for u, v, _, data in nx.maximum_spanning_edges(sub, keys=True, data=True):
        tree.add_edge(u, v, component=data["component"])
    for parent, child in nx.bfs_edges(tree, topo.root):
        comp = tree.edges[parent, child]["component"]
        rev = topo.set_of[comp.port_ref("frame_a")] != parent
        topo.tree.append(Edge(comp, parent, child, rev))
    in_tree = {e.component.name for e in topo.tree}
    for _, _, data in sub.edges(data=True):
        comp = data["component"]
        if comp.name in in_tree:
            if getattr(type(comp), "loop_only", False):
                problems.append(f"{model.place(comp)}: {comp.name} closes no kinematic loop "
                                f"(or its loop has another such joint): a {comp.type_name} "
                                f"holds only the distance of its frames, so it must be the "
                                f"one joint that closes its loop")
            elif comp._values.get("cut", False):
                problems.append(f"{model.place(comp, 'cut')}: {comp.name} is marked cut but "
                                f"closes no kinematic loop")
            continue
        a, b = topo.set_of[comp.port_ref("frame_a")], topo.set_of[comp.port_ref("frame_b")]
        path = nx.shortest_path(tree, a, b)
        names = [tree.edges[x, y]["component"].name for x, y in zip(path, path[1:])]
        topo.cuts.append(Cut(comp, a, b, [*names, comp.name]))
        topo.loops.append([*names, comp.name])
    rank = {name: i for i, name in enumerate(model.components)}
    coordinated = [e.component for e in topo.tree if e.component.dof > 0]
    coordinated += [c.component for c in topo.cuts
                    if c.component.dof > 0 and c.component.regular]
    topo.joints = sorted(coordinated, key=lambda c: rank[c.name])
    # a joint or rigid part with mass (a body with a shape) is a body on its frame_a too
    massive = [c for c in model.components.values()
               if c.role == "body" or (c.role in ("joint", "part") and c.has_mass)]
    topo.bodies = [(b, topo.set_of[b.port_ref("frame_a")]) for b in massive
                   if topo.set_of[b.port_ref("frame_a")] in reached]
    topo.forces = [f for f in roles.get("frame_force", [])
                   if all(topo.set_of[f.port_ref(pn)] in placed for pn, port in f.ports.items()
                          if port.domain == "frame" and not _dangling(topo, f, pn))]


def _frame_sets(topo, comp):
    """The frame sets a force element's wired frame ports are in."""
    return [topo.set_of[comp.port_ref(pn)] for pn, port in comp.ports.items()
            if port.domain == "frame" and not _dangling(topo, comp, pn)]


def _junctions(model, topo, forces, frames, reached, problems):
    """Massless junctions: frame sets that only line forces meet at (no body, joint or rigid
    part), as the point between springs in series of MSL's ThreeSprings. Nothing there has
    mass, so the junction sits where the line forces on it balance (the solver's
    ``equations/junctions.py``). Each needs two line forces (one end alone is an unwired
    port, refused as such) and a path of line forces to a frame the joints place; a force
    element that is no line force (its wrench would need the junction's orientation) or a
    line force with a point mass is refused there."""
    candidates = set()
    for s in frames.nodes:
        physical = [p for p in topo.sets[s] if p.component.role != "probe"]
        # one port alone is an unwired one (refused as such, or an optional one left free)
        if s not in reached and len(physical) > 1 and all(
                p.component.role == "frame_force" and p.domain == "frame" for p in physical):
            candidates.add(s)
    if not candidates:
        return []

    def where(s):
        return "{" + ", ".join(p.path for p in topo.sets[s] if p.component.role != "probe") + "}"
    joined = nx.Graph()
    joined.add_nodes_from([*candidates, "placed"])
    refused = set()
    for comp in forces:
        sets = _frame_sets(topo, comp)
        touching = [s for s in sets if s in candidates]
        if not touching:
            continue
        if not hasattr(type(comp), "law"):
            problems.append(f"{model.place(comp)}: {comp.name} acts on {where(touching[0])}, a "
                            f"frame no body, joint or rigid part holds (a massless junction); "
                            f"only line forces (Spring, Damper, SpringDamper) may meet there, "
                            f"since a {comp.type_name} needs that frame's orientation")
            refused.update(touching)
            continue
        nodes = [s if s in candidates else "placed" for s in sets]
        nx.add_path(joined, nodes)
    out = []
    for s in sorted(candidates):
        lines = [p.path for p in topo.sets[s] if p.component.role == "frame_force"]
        if s in refused:
            continue
        if len({p.component.name for p in topo.sets[s] if p.component.role != "probe"}) < 2:
            problems.append(f"{lines[0]}: wired only to the other end of the same line force, "
                            f"with no body, joint or other line force there; wire it to a frame")
        elif not nx.has_path(joined, s, "placed"):
            problems.append(f"massless junction {where(s)}: its line forces reach no frame "
                            f"that joints or rigid parts connect to the ground, so where it "
                            f"sits is not determined")
        else:
            out.append(s)
    return out


def _dangling(topo, comp, pname):
    """A force element's optional port left unwired (its frame_resolve): nothing to reach.
    (A joint's or part's unwired end is reached through the part itself.)"""
    ref = comp.port_ref(pname)
    return comp.role == "frame_force" and comp.ports[pname].optional and all(
        p.component.role == "probe" for p in topo.sets[topo.set_of[ref]] if p != ref)


def _oned(model, topo, values, problems):
    """1-D connection sets joined by rigid elements (inertias, gears, flow sensors) into rigid
    groups (networkx connected components); each group has at most one port that sets its
    position: a joint flange, a support, a Fixed or a prescribed motion."""
    tree_joints = {j.name for j in topo.joints}
    rigid = nx.MultiGraph()
    for index, ports in enumerate(topo.sets):
        if _domain(ports) in ONED_DOMAINS:
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
        domain = _domain(topo.sets[min(members)])
        definers = [p for p in ports if _defines(p)]
        where = "{" + ", ".join(p.path for p in ports) + "}"
        elements = sorted({d["component"].name for _, _, d in sub.edges(data=True)})
        through = f" (through {', '.join(elements)})" if elements else ""
        coords = [p for p in definers if p.name in p.component.coordinate_ports]
        motions = [p for p in definers if p.component.role == "prescribed"]
        held = [p for p in definers if p not in coords and p not in motions]
        definers = coords + motions + held        # the joint's flange roots its group
        if len(coords) > 1 or (coords and held):
            problems.append(f"connection set {where} rigidly ties joint flange "
                            f"{coords[0].path} to "
                            f"{', '.join(p.path for p in definers[1:] if p not in motions)}"
                            f"{through}: this locks or couples joints, which is not "
                            f"supported yet")
        elif len(motions) > 1:
            names = ", ".join(p.path for p in motions)
            problems.append(
                f"connection set {where}: joint flange {coords[0].path} is driven by "
                f"{len(motions)} prescribed motions ({names}){through}; a joint follows one "
                f"motion: remove all but one" if coords else
                f"connection set {where} rigidly ties prescribed motion {motions[0].path} to "
                f"{', '.join(p.path for p in motions[1:])}{through}: one rigid group cannot "
                f"follow two prescribed motions")
        elif motions and held:
            problems.append(f"connection set {where} rigidly ties prescribed motion "
                            f"{motions[0].path} to {', '.join(p.path for p in held)}"
                            f"{through}: a flange held in place cannot follow a motion")
        elif len(held) > 1 and values is not None:
            spots = {p.path: (topo.set_of[p], _fixed_position(p, values)) for p in held}
            if len(set(spots.values())) > 1:
                problems.append(f"connection set {where} holds fixed flanges at different "
                                f"positions: "
                                + str({k: v[1] for k, v in spots.items()}) + through)
        cycles = nx.cycle_basis(nx.Graph(sub)) if sub.number_of_edges() else []
        parallel = [sorted(sub.get_edge_data(u, v)) for u, v in {(u, v) for u, v, _ in
                                                                 sub.edges(keys=True)}
                    if len(sub.get_edge_data(u, v)) > 1]
        if cycles or parallel:
            names = parallel[0] if parallel else sorted({
                sub.get_edge_data(u, v)[next(iter(sub.get_edge_data(u, v)))]["component"].name
                for cyc in cycles[:1] for u, v in zip(cyc, cyc[1:] + cyc[:1])})
            problems.append(f"rigid 1-D elements {', '.join(names)} form a closed loop "
                            f"(they tie flanges together twice): remove one")
        for p in coords:
            if p.component.name not in tree_joints:
                problems.append(f"{p.path}: joint {p.component.name!r} has no coordinates "
                                f"here, so its flange cannot be used")
        inertias = [d["component"] for _, _, d in sub.edges(data=True)
                    if d["component"].has_inertia]
        kind = ("joint" if coords else "prescribed" if motions else
                "fixed" if definers else "free" if inertias else
                "world" if len(ports) <= 1 else "massless")
        if kind == "free" and values is not None and all(
                e.bound(values[e.name]).inertia() == 0 for e in inertias):
            problems.append(f"connection set {where}: the inertia of "
                            f"{', '.join(e.name for e in inertias)} is zero and nothing "
                            f"holds the flange, so its motion is not determined")
        if kind == "massless" and not any(p.component.role == "compliant" for p in ports):
            problems.append(f"connection set {where} has no defined {domain} position: it "
                            f"has no inertia, spring or damper, so the flows on it cannot "
                            f"balance; wire it to a joint flange, a Fixed or an inertia")
        # a free group's coordinate is its first inertia's position (the state named after it)
        root = (topo.set_of[definers[0]] if definers else
                topo.set_of[inertias[0].port_ref("flange_a")] if kind == "free" else
                min(members))
        topo.oned.append(OneDGroup(len(topo.oned), domain, _rooted(sub, root), ports,
                                   definers[0] if definers else None, kind,
                                   [d["component"] for _, _, d in sub.edges(data=True)],
                                   motions[0] if coords and motions else None))


def _motions(model, topo, problems):
    """A motion source takes its reference from its parameter or from its input u, not
    both; its reaction rests in the world (unwired support, a joint's support or a Fixed:
    nothing there moves) or, for a motion that is no joint's, on a free rotor: then the
    motion is relative to it, as MSL's with useSupport."""
    group_of = {s: g for g in topo.oned for s, _, _ in g.sets}
    for comp in model.components.values():
        if comp.role != "prescribed":
            continue
        key = type(comp).reference.name
        wired = topo.set_of[comp.port_ref("u")] in topo.signal_source
        given = comp.reference is not None
        if wired and given:
            problems.append(f"{model.place(comp, key)}: {comp.name}.u is wired too; the "
                            f"reference comes from one of them: remove {key} or the wire")
        elif not wired and not given:
            problems.append(f"{model.place(comp, key)}: no reference: give {key} (an "
                            f"expression in time t) or wire a signal to {comp.name}.u")
        support = comp.port_ref("support")
        group = group_of.get(topo.set_of[support])
        own = group_of.get(topo.set_of[comp.port_ref("flange")])
        if group is None or group.kind in ("fixed", "world"):
            continue
        if group.kind == "free" and own is not None and own.kind == "prescribed" and \
                own is not group:
            own.base = topo.set_of[support]        # it moves relative to a free housing
            continue
        problems.append(f"{model.place(comp)}: {support.path} is wired to a flange that "
                        f"moves ({group.kind}); the reaction of a prescribed motion rests "
                        f"on a free rotor (an inertia) or in the world: wire the support "
                        f"to an inertia of its own, a joint's support or a Fixed, or leave "
                        f"it unwired")


def _junction_masses(model, topo, values, problems):
    """A line force at a massless junction carries no point mass: it would ride on a line
    whose end only the balance of forces places."""
    junctions = set(topo.junctions)
    for comp in topo.forces:
        if values[comp.name].get("mass", 0.0) and junctions & set(_frame_sets(topo, comp)):
            problems.append(f"{model.place(comp, 'mass')}: {comp.name} ends at a massless "
                            f"junction (a frame with no body), where a point mass on the line "
                            f"is not supported; put a body at the junction instead")


def _inertias(model, bodies, values, problems):
    """A body's inertia about its centre of mass must be symmetric and positive
    semi-definite: nothing else is possible for any use. Principal moments that break the
    triangle inequality (no rigid body has them) are an idealisation MSL's own examples use
    for parts that turn about one axis only (ActuatedDrive's diag(2, 0, 0), RobotR3's
    diag(0.001, 1.16, 0.001)): warned once per body, and simulated; a mass matrix they make
    singular is refused later, naming the joints. A tensor with a zero principal moment (a
    planar link given only its moment about the joint axis) is an idealisation too common to
    warn about."""
    for body in bodies:
        if "inertia" not in body.params:
            continue        # computed from a shape: physical by construction
        inertia = np.asarray(values[body.name]["inertia"], dtype=float)
        where = model.place(body, "inertia")
        scale = max(np.max(np.abs(inertia)), 1e-300)
        if np.max(np.abs(inertia - inertia.T)) > 1e-9 * scale:
            problems.append(f"{where}: must be symmetric, got {inertia.tolist()}")
            continue
        moments = np.linalg.eigvalsh(inertia)
        listed = ", ".join(f"{m:.6g}" for m in moments)
        if moments[0] < -1e-9 * scale:
            problems.append(f"{where}: must be positive semi-definite; its principal moments "
                            f"are {listed}")
        elif moments[0] > 1e-12 * scale and moments[0] + moments[1] < moments[2] - 1e-9 * scale:
            warnings.warn(f"{where}: its principal moments {listed} break the triangle "
                          f"inequality (the largest exceeds the sum of the other two): no "
                          f"rigid body has them; simulated as an idealisation",
                          IdealisedInertiaWarning, stacklevel=2)


def _domain(ports):
    """The domain of a connection set: that of its first port that is not a probe's."""
    return next((p.domain for p in ports if p.component.role != "probe"), ports[0].domain)


def _signals(topo, problems):
    """Each signal connection set has one output and any number of inputs."""
    for index, ports in enumerate(topo.sets):
        physical = [p for p in ports if p.component.role != "probe"]
        if _domain(ports) not in SIGNAL_DOMAINS or not physical:
            continue
        outs = [p for p in physical if p.domain == "signal_out"]
        ins = [p for p in physical if p.domain == "signal_in"]
        if len(outs) > 1:
            problems.append(f"signal outputs {', '.join(p.path for p in outs)} are wired "
                            f"together: a signal has exactly one source")
        elif ins and not outs and len(physical) > 1:
            problems.append(f"signal inputs {', '.join(p.path for p in ins)} are wired to "
                            f"each other but to no output")
        if outs:
            topo.signal_source[index] = outs[0]


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
            or ref.name in comp.zero_ports
            or comp.role == "fixed"
            or (comp.role == "prescribed" and ref.name == "flange"))


def _fixed_position(ref, values):
    comp = ref.component
    if comp.role == "fixed":
        return comp.bound(values[comp.name]).position()
    return 0.0
