"""Topology: connection sets, and the steps that say what each set means.

Ports are nodes and connections edges of a networkx graph; a connection set is a connected
component (potentials equal, flows summing to zero). ``analyze`` builds the sets, checks
probes, unconnected ports and signal sets here, and runs the other steps: the spanning tree
of the frames (``tree``), the 1-D rigid groups (``groups``), gear supports (``supports``)
and the inertias (``inertia``); the Topology it returns is the equations' starting point.
"""

from dataclasses import dataclass, field

import networkx as nx

from ..components.probe import QUANTITIES
from ..errors import ModelError, Problem
from . import supports
from .groups import ONED_DOMAINS, OneDGroup, domain_of, motions, oned_groups
from .inertia import check_inertias
from .tree import Cut, Edge, junction_masses, problem_at, spanning_tree

__all__ = ["Cut", "Edge", "ONED_DOMAINS", "OneDGroup", "SIGNAL_DOMAINS", "Topology", "analyze"]

SIGNAL_DOMAINS = ("signal_in", "signal_out")


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
        spanning_tree(model, topo, roles, problems)
    oned_groups(model, topo, values, problems)
    supports.check(model, topo, values, problems)
    _signals(model, topo, problems)
    motions(model, topo, problems)
    supports.rings(topo, problems)
    if values is not None and topo.junctions:
        junction_masses(model, topo, values, problems)
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


def _signals(model, topo, problems):
    """Each signal connection set has one output and any number of inputs."""
    for index, ports in enumerate(topo.sets):
        physical = [p for p in ports if p.component.role != "probe"]
        if domain_of(ports) not in SIGNAL_DOMAINS or not physical:
            continue
        outs = [p for p in physical if p.domain == "signal_out"]
        ins = [p for p in physical if p.domain == "signal_in"]
        if len(outs) > 1:
            problems.append(problem_at(
                model, outs[-1], f"signal outputs "
                f"{', '.join(p.path for p in outs)} are wired together: a "
                f"signal has exactly one source"))
        elif ins and not outs and len(physical) > 1:
            problems.append(problem_at(
                model, ins[-1], f"signal inputs "
                f"{', '.join(p.path for p in ins)} are wired to each other "
                f"but to no output"))
        if outs:
            topo.signal_source[index] = outs[0]


