"""The spanning tree of the frames: which joints and rigid parts the recursion walks, which
close loops, and what assemblies and line forces place.

Frame sets are the nodes of a graph whose edges are joints and rigid parts. Its maximum
spanning tree (weights prefer to keep rigid parts and regular joints, and to cut joints
marked ``cut``, FreeMotion and Spherical joints) is walked breadth-first from the ground to
order the Newton-Euler recursion; every edge left out is a cut joint that closes one
independent kinematic loop. A step of ``topology.analyze``.
"""

from dataclasses import dataclass

import networkx as nx

from ..errors import Problem


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


def _keep_weight(comp):
    """Preference for keeping a part in the spanning tree (the rest are cut): a joint marked
    ``cut`` goes first, then as its class ranks itself (``cut_preference``)."""
    return -1 if comp._values.get("cut", False) else comp.cut_preference


def spanning_tree(model, topo, roles, problems):
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
                    dangling(topo, comp, pname) and \
                    len(topo.sets[topo.set_of[comp.port_ref(pname)]]) > 1 and \
                    topo.set_of[comp.port_ref(pname)] not in reached | inner:
                problems.append(model.problem(f"{comp.name}.{pname} is not wired, so it has "
                                              f"no pose for a probe to measure", comp,
                                              port=pname))
            if comp.ports[pname].domain == "frame" and pname not in by_cut and \
                    not dangling(topo, comp, pname) and \
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
                          if port.domain == "frame" and not dangling(topo, f, pn))]
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


def frame_sets(topo, comp):
    """The frame sets a force element's wired frame ports are in."""
    return [topo.set_of[comp.port_ref(pn)] for pn, port in comp.ports.items()
            if port.domain == "frame" and not dangling(topo, comp, pn)]


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
        sets = frame_sets(topo, comp)
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
            problems.append(problem_at(
                model, lines[0], f"{lines[0].path}: wired only to the other "
                f"end of the same line force, with no body, joint or other "
                f"line force there; wire it to a frame"))
        elif not nx.has_path(joined, s, "placed"):
            problems.append(problem_at(
                model, lines[0], f"massless junction {where(s)}: its line "
                f"forces reach no frame that joints or rigid parts connect to "
                f"the ground, so where it sits is not determined"))
        else:
            out.append(s)
    return out


def dangling(topo, comp, pname):
    """A force element's optional port left unwired (its frame_resolve): nothing to reach.
    (A joint's or part's unwired end is reached through the part itself.)"""
    ref = comp.port_ref(pname)
    return comp.role == "frame_force" and comp.ports[pname].optional and all(
        p.component.role == "probe" for p in topo.sets[topo.set_of[ref]] if p != ref)


def junction_masses(model, topo, values, problems):
    """A line force at a massless junction carries no point mass: it would ride on a line
    whose end only the balance of forces places."""
    junctions = set(topo.junctions)
    for comp in topo.forces:
        if values[comp.name].get("mass", 0.0) and junctions & set(frame_sets(topo, comp)):
            problems.append(model.problem(f"{comp.name} ends at a massless junction (a frame "
                                          f"with no body), where a point mass on the line is "
                                          f"not supported; put a body at the junction "
                                          f"instead", comp, "mass"))


def problem_at(model, ref, text):
    """A Problem whose message ``text`` names its place itself, about port ``ref``."""
    return Problem(text, **model.fields(ref.component, port=ref.name))
