"""Topology: connection sets, the spanning tree from the ground, and what each set means.

Ports are nodes and connections edges of a networkx graph; a connection set is a connected
component (potentials equal, flows summing to zero). Frame sets are the nodes of a second
graph whose edges are joints and rigid parts. Its maximum spanning tree (weights prefer to
keep rigid parts and regular joints, and to cut joints marked ``cut``, FreeMotion and
Spherical joints) is walked breadth-first from the ground to order the Newton-Euler
recursion; every edge left out is a cut joint that closes one independent kinematic loop.
"""

from dataclasses import dataclass, field

import networkx as nx

from ..components.probe import QUANTITIES
from ..errors import ModelError, Problem
from . import supports
from .inertia import check_inertias

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
    #: what was accepted with a warning (each warned of too), as Problems: the studio's
    warnings: list = field(default_factory=list)
    #: assemblies that close their loop in closed form (MSL's Joints.Assemblies), as Cuts
    #: with no closure rows, and what they place, in the order it can be placed: a Cut places
    #: its inner frames from its two ends, an Edge a rigid part hanging from a placed frame
    placements: list = field(default_factory=list)
    #: frame set -> (assembly, port) of the inner frames assemblies place
    placed_by: dict = field(default_factory=dict)

    @property
    def assemblies(self):
        """The Cuts of the assemblies that close their loops in closed form."""
        return [c for c in self.placements if isinstance(c, Cut)]

    @property
    def inner(self):
        """The frame sets assemblies place: their inner frames and what hangs from them."""
        return set(self.placed_by) | {e.child for e in self.placements if isinstance(e, Edge)}

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
            stale.append(Problem(f"connections[{i}] {a.path} - {b.path}: component "
                                 f"{gone[0].component.name!r} is not in the model any more "
                                 f"(remove its connections too)",
                                 component=gone[0].component.name, port=gone[0].name,
                                 hint="remove its connections too"))
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
                problems.append(model.problem(f"port {ref.path} ({port.domain}) is not "
                                              f"connected", comp, port=pname))

    worlds = roles.get("world", [])
    frames = any(p.domain == "frame" for c in model.components.values() for p in
                 c.ports.values())
    if len(worlds) > 1 or (not worlds and frames):
        names = ", ".join(w.name for w in worlds)
        problems.append(Problem("the model needs exactly one multibody.Ground, found "
                                f"{len(worlds)}{': ' + names if names else ''}",
                                **(model.fields(worlds[-1]) if worlds else {})))
        if not worlds:
            raise ModelError(problems)
    world = worlds[0] if worlds else None          # a 1-D and signal model needs none
    topo = Topology(world=world, sets=sets, set_of=set_of,
                    root=set_of[world.port_ref("frame")] if world else None, probes=probes)
    if world is not None:
        _tree(model, topo, roles, problems)
    _oned(model, topo, values, problems)
    supports.check(model, topo, values, problems)
    _signals(model, topo, problems)
    _motions(model, topo, problems)
    supports.rings(topo, problems)
    if values is not None and topo.junctions:
        _junction_masses(model, topo, values, problems)
    if values is not None:
        check_inertias(model, [c for c in model.components.values() if c.role == "body" or (
            c.role in ("joint", "part") and c.has_mass)], values, problems, topo.warnings)
        for comp in model.components.values():
            problems.extend(Problem.of(p, **model.fields(comp)) for p in comp.check_values(
                values[comp.name], lambda key, c=comp: model.place(c, key)))
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
            problems.append(model.problem(f"a probe is wired to exactly one port; "
                                          f"{probe.name}.port is wired to {what}", probe,
                                          port="port"))
            continue
        target = wired[0]
        if target.component.role == "probe":
            problems.append(model.problem(f"wired to another probe ({target.path})", probe,
                                          port="port"))
            continue
        allowed = QUANTITIES.get(target.domain)
        if allowed is None:
            problems.append(model.problem(f"cannot measure {target.path} ({target.domain} "
                                          f"ports are not measured by probes)", probe,
                                          port="port"))
            continue
        asked = probe.quantities if probe.quantities is not None else list(allowed)
        for q in asked:
            if q not in allowed:
                article = "an" if target.domain[0] in "aeiou" else "a"
                problems.append(model.problem(f"{q!r} is not a quantity of {article} "
                                              f"{target.domain} port ({target.path}); choose "
                                              f"from {', '.join(allowed)}", probe,
                                              "quantities"))
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
    # an assembly that closes its loop in closed form is no edge of the tree: both of its
    # ends are placed by the rest, and it places its inner frames from them
    analytic = [c for c in joints if getattr(type(c), "analytic", False)]
    for rank, comp in enumerate(joints):
        a, b = topo.set_of[comp.port_ref("frame_a")], topo.set_of[comp.port_ref("frame_b")]
        if a == b:
            problems.append(model.problem("frame_a and frame_b are connected to each other, "
                                          "which locks the part", comp, port="frame_b"))
            continue
        # ties go to the part added first: the last joint of a loop closes it (is cut)
        tie = 0.5 * (len(joints) - rank) / len(joints)
        if comp not in analytic:
            frames.add_edge(a, b, key=comp.name, component=comp,
                            weight=_keep_weight(comp) + tie)
        frames.add_nodes_from([a, b])
    for comp in [*roles.get("body", []), *roles.get("frame_force", [])]:
        for pname in comp.ports:
            frames.add_node(topo.set_of[comp.port_ref(pname)])

    for comp in joints:
        for pname in getattr(type(comp), "placed_frames", ()):
            frames.add_node(topo.set_of[comp.port_ref(pname)])
    reached = nx.node_connected_component(frames, topo.root)
    inner = _place_assemblies(model, topo, frames, analytic, reached, problems)
    topo.junctions = _junctions(model, topo, roles.get("frame_force", []), frames,
                                reached | inner, problems)
    placed = reached | inner | set(topo.junctions)
    for comp in [*joints, *roles.get("body", []), *roles.get("frame_force", [])]:
        # frames a cut joint places from where its ends are (a rod's frame_ia): for probes,
        # unless it carries loads there (an assembly)
        by_cut = getattr(type(comp), "placed_frames", ())
        for pname in by_cut if not getattr(type(comp), "carries_loads", False) else ():
            stray = [p.path for p in topo.sets[topo.set_of[comp.port_ref(pname)]]
                     if p.component is not comp and p.component.role != "probe"]
            if stray:
                problems.append(model.problem(f"{comp.name}.{pname} is for probes only, but "
                                              f"{', '.join(stray)} is wired to it", comp,
                                              port=pname))
        for pname in comp.ports:
            if comp.ports[pname].domain == "frame" and pname not in by_cut and \
                    _dangling(topo, comp, pname) and \
                    len(topo.sets[topo.set_of[comp.port_ref(pname)]]) > 1 and \
                    topo.set_of[comp.port_ref(pname)] not in reached | inner:
                problems.append(model.problem(f"{comp.name}.{pname} is not wired, so it has "
                                              f"no pose for a probe to measure", comp,
                                              port=pname))
            if comp.ports[pname].domain == "frame" and pname not in by_cut and \
                    not _dangling(topo, comp, pname) and \
                    topo.set_of[comp.port_ref(pname)] not in placed:
                problems.append(model.problem(f"{comp.name} is not connected to the ground "
                                              f"{topo.world.name!r} through joints or rigid "
                                              f"parts", comp, port=pname))
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
                problems.append(model.problem(f"{comp.name} closes no kinematic loop (or its "
                                              f"loop has another such joint): a "
                                              f"{comp.type_name} holds only the distance of "
                                              f"its frames, so it must be the one joint that "
                                              f"closes its loop", comp))
            elif comp._values.get("cut", False):
                problems.append(model.problem(f"{comp.name} is marked cut but closes no "
                                              f"kinematic loop", comp, "cut"))
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
                   if topo.set_of[b.port_ref("frame_a")] in reached | inner]
    for cut in topo.assemblies:
        # its loop: the tree's path between its ends (one placed by another assembly has
        # none: that assembly's loop and this one share it)
        path = nx.shortest_path(tree, cut.set_a, cut.set_b) if cut.set_a in tree and \
            cut.set_b in tree else []
        cut.loop = [tree.edges[x, y]["component"].name for x, y in zip(path, path[1:])] \
            + [cut.component.name]
        topo.loops.append(cut.loop)
    topo.forces = [f for f in roles.get("frame_force", [])
                   if all(topo.set_of[f.port_ref(pn)] in placed for pn, port in f.ports.items()
                          if port.domain == "frame" and not _dangling(topo, f, pn))]
    _point_masses_alone(model, topo, roles, problems)


#: what may act on a point mass alone on a FreeMotion: forces at its origin, never a torque
_FORCES_AT_A_POINT = ("multibody.Spring", "multibody.Damper", "multibody.SpringDamper",
                      "multibody.LineForceWithTwoMasses", "multibody.WorldForce")


def _point_masses_alone(model, topo, roles, problems):
    """Mark the FreeMotions of the tree whose frame_b carries only PointMasses (and forces at
    their origin): nothing they move has rotational inertia or takes a torque, so they move
    without turning and their orientation is no state (MSL's PointMass on a FreeMotion)."""
    for comp in roles.get("joint", []):
        if comp.type_name == "multibody.FreeMotion":
            object.__setattr__(comp, "_translation_only", False)
    parents = {e.parent for e in topo.tree}
    ends = {s for c in topo.cuts for s in (c.set_a, c.set_b)} | set(topo.inner)
    for edge in topo.tree:
        comp = edge.component
        if comp.type_name != "multibody.FreeMotion":
            continue
        carried = [b for b, s in topo.bodies if s == edge.child]
        forces = [f for f in roles.get("frame_force", [])
                  if any(topo.set_of[f.port_ref(pn)] == edge.child for pn, port in
                         f.ports.items() if port.domain == "frame")]
        if edge.reversed or edge.child in parents | ends or not carried or \
                any(b.type_name != "multibody.PointMass" for b in carried) or \
                any(f.type_name not in _FORCES_AT_A_POINT for f in forces):
            continue
        object.__setattr__(comp, "_translation_only", True)
        w0 = comp._values.get("w0")
        if w0 is not None and any(not isinstance(v, (int, float)) or v != 0 for v in w0):
            problems.append(f"{model.place(comp, 'w0')}: {comp.name} carries only point "
                            f"masses, which do not turn (no rotational inertia): its "
                            f"orientation is held at angles0, so w0 must be zero or None")


def _place_assemblies(model, topo, frames, analytic, reached, problems):
    """Place the assemblies whose two ends are placed (by the tree, or as the inner frames
    of another assembly: MSL's PlanarLoops chains them), their inner frames and the rigid
    parts hanging from those, in an order where each is placed after what it hangs from
    (``topo.placements``). What hangs from an inner frame moves with it: a joint with degrees
    of freedom there, or a second path from there to the rest, is refused. Returns the
    frame sets placed so."""
    known, inner = set(reached), set()
    pending = list(analytic)
    while pending:
        ready = [c for c in pending if all(topo.set_of[c.port_ref(p)] in known
                                          for p in ("frame_a", "frame_b"))]
        if not ready:
            break
        for comp in ready:
            pending.remove(comp)
            a, b = (topo.set_of[comp.port_ref(p)] for p in ("frame_a", "frame_b"))
            if a == b:
                continue                 # refused with the other parts tying a to b
            topo.placements.append(Cut(comp, a, b, [comp.name]))
            for pname in comp.placed_frames:
                s = topo.set_of[comp.port_ref(pname)]
                if s in known:
                    problems.append(f"{model.place(comp)}: {comp.name}.{pname} is placed by "
                                    f"the assembly, but it is wired to a frame the rest of "
                                    f"the model places too (a loop through an assembly's "
                                    f"inner frame): wire a body, rigid parts or forces to it, "
                                    f"or build that loop from joints")
                    continue
                topo.placed_by[s] = (comp, pname)
                known.add(s)
                inner.add(s)
                _hang(model, topo, frames, s, known, inner, problems)
    for comp in pending:
        problems.append(f"{model.place(comp)}: {comp.name} closes no kinematic loop: a "
                        f"{comp.type_name} places its inner frames from where its frame_a and "
                        f"frame_b are, so the rest of the model must place both (wire each to "
                        f"the ground through joints or rigid parts)")
    return inner


def _hang(model, topo, frames, root, known, inner, problems):
    """The rigid parts hanging from inner frame ``root``, breadth first, as Edges of
    ``topo.placements``."""
    queue = [root]
    while queue:
        node = queue.pop(0)
        for _, other, data in sorted(frames.edges(node, data=True),
                                     key=lambda e: e[2]["component"].name):
            comp = data["component"]
            if any(isinstance(e, Edge) and e.component is comp for e in topo.placements):
                continue
            if comp.dof > 0 or other in known:
                why = (f"{comp.name} is a joint with degrees of freedom" if comp.dof > 0 else
                       f"{comp.name} ties it to a frame placed otherwise (a loop through the "
                       f"assembly's inner frame)")
                comp_, pname = topo.placed_by[root]
                problems.append(f"{model.place(comp)}: {why}, hanging from {comp_.name}."
                                f"{pname}; what an assembly's inner frame carries moves "
                                f"with it: bodies, rigid parts and forces")
                continue
            rev = topo.set_of[comp.port_ref("frame_a")] != node
            topo.placements.append(Edge(comp, node, other, rev))
            known.add(other)
            inner.add(other)
            queue.append(other)


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
            problems.append(model.problem(
                f"{comp.name} acts on {where(touching[0])}, a frame no body, joint or rigid "
                f"part holds (a massless junction); only line forces (Spring, Damper, "
                f"SpringDamper) may meet there, since a {comp.type_name} needs that frame's "
                f"orientation", comp))
            refused.update(touching)
            continue
        nodes = [s if s in candidates else "placed" for s in sets]
        nx.add_path(joined, nodes)
    out = []
    for s in sorted(candidates):
        lines = [p for p in topo.sets[s] if p.component.role == "frame_force"]
        if s in refused:
            continue
        if len({p.component.name for p in topo.sets[s] if p.component.role != "probe"}) < 2:
            problems.append(_at(model, lines[0], f"{lines[0].path}: wired only to the other "
                                f"end of the same line force, with no body, joint or other "
                                f"line force there; wire it to a frame"))
        elif not nx.has_path(joined, s, "placed"):
            problems.append(_at(model, lines[0], f"massless junction {where(s)}: its line "
                                f"forces reach no frame that joints or rigid parts connect to "
                                f"the ground, so where it sits is not determined"))
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
            problems.append(_at(model, coords[-1], f"connection set {where} rigidly ties joint "
                            f"flange "
                            f"{coords[0].path} to "
                            f"{', '.join(p.path for p in definers[1:] if p not in motions)}"
                            f"{through}: this locks or couples joints, which is not "
                            f"supported yet"))
        elif len(motions) > 1:
            names = ", ".join(p.path for p in motions)
            problems.append(_at(
                model, motions[-1],
                f"connection set {where}: joint flange {coords[0].path} is driven by "
                f"{len(motions)} prescribed motions ({names}){through}; a joint follows one "
                f"motion: remove all but one" if coords else
                f"connection set {where} rigidly ties prescribed motion {motions[0].path} to "
                f"{', '.join(p.path for p in motions[1:])}{through}: one rigid group cannot "
                f"follow two prescribed motions"))
        elif motions and held:
            problems.append(_at(model, motions[0], f"connection set {where} rigidly ties "
                                f"prescribed motion {motions[0].path} to "
                                f"{', '.join(p.path for p in held)}{through}: a flange held "
                                f"in place cannot follow a motion"))
        elif len(held) > 1 and values is not None:
            spots = {p.path: (topo.set_of[p], _fixed_position(p, values)) for p in held}
            if len(set(spots.values())) > 1:
                problems.append(_at(model, held[-1], f"connection set {where} holds fixed "
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
                problems.append(_at(model, p, f"{p.path}: joint {p.component.name!r} has no "
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
            problems.append(_at(model, ports[0], f"connection set {where} has no defined "
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


def _motions(model, topo, problems):
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


def _junction_masses(model, topo, values, problems):
    """A line force at a massless junction carries no point mass: it would ride on a line
    whose end only the balance of forces places."""
    junctions = set(topo.junctions)
    for comp in topo.forces:
        if values[comp.name].get("mass", 0.0) and junctions & set(_frame_sets(topo, comp)):
            problems.append(model.problem(f"{comp.name} ends at a massless junction (a frame "
                                          f"with no body), where a point mass on the line is "
                                          f"not supported; put a body at the junction "
                                          f"instead", comp, "mass"))


def _at(model, ref, text):
    """A Problem whose message ``text`` names its place itself, about port ``ref``."""
    return Problem(text, **model.fields(ref.component, port=ref.name))


def _domain(ports):
    """The domain of a connection set: that of its first port that is not a probe's."""
    return next((p.domain for p in ports if p.component.role != "probe"), ports[0].domain)


def _signals(model, topo, problems):
    """Each signal connection set has one output and any number of inputs."""
    for index, ports in enumerate(topo.sets):
        physical = [p for p in ports if p.component.role != "probe"]
        if _domain(ports) not in SIGNAL_DOMAINS or not physical:
            continue
        outs = [p for p in physical if p.domain == "signal_out"]
        ins = [p for p in physical if p.domain == "signal_in"]
        if len(outs) > 1:
            problems.append(_at(model, outs[-1], f"signal outputs "
                                f"{', '.join(p.path for p in outs)} are wired together: a "
                                f"signal has exactly one source"))
        elif ins and not outs and len(physical) > 1:
            problems.append(_at(model, ins[-1], f"signal inputs "
                                f"{', '.join(p.path for p in ins)} are wired to each other "
                                f"but to no output"))
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
            or ref.name in getattr(type(comp), "derived_ports", ())
            or ref.name in comp.zero_ports
            or comp.role == "fixed"
            or (comp.role == "prescribed" and ref.name == "flange"))


def _fixed_position(ref, values):
    comp = ref.component
    if comp.role == "fixed":
        return comp.bound(values[comp.name]).position()
    return 0.0
