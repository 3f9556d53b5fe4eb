"""The units of signals, spread along the wires from the parts that fix them.

Signal blocks compute with plain numbers, but a signal usually stands for a physical quantity:
an angle sensor's output is in rad, a torque source's input in N*m, and whatever is wired to
them carries the same unit. Components say which of their signal ports they fix
(``Component.signal_unit``) and which of their ports carry one unit together
(``same_unit_ports``: an Add's inputs and output, a PID's set point and measurement). The
connection sets of signal ports joined by those relations form groups (connected components,
networkx); a group whose fixed ports agree on one unit has it, so a probe on a PID's set point
reads "rad" because the measurement is an angle. A group fixed to two different units, or to
none, stays without one: the plots then say "1" rather than guess.
"""

import networkx as nx

SIGNAL_DOMAINS = ("signal_in", "signal_out")


def signal_units(model, topo):
    """Connection set index -> unit, for the signal sets whose unit the model fixes."""
    graph = nx.Graph()
    fixed = {}
    for comp in model.components.values():
        sets = {name: topo.set_of.get(comp.port_ref(name)) for name, port in comp.ports.items()
                if port.domain in SIGNAL_DOMAINS}
        sets = {name: s for name, s in sets.items() if s is not None}
        graph.add_nodes_from(sets.values())
        for name, s in sets.items():
            unit = comp.signal_unit(name)
            if unit:
                fixed.setdefault(s, set()).add(unit)
        for group in comp.same_unit_ports:
            members = [sets[name] for name in group if name in sets]
            nx.add_path(graph, members)
    units = {}
    for group in nx.connected_components(graph):
        found = set().union(*(fixed.get(s, set()) for s in group))
        if len(found) == 1:
            unit = found.pop()
            units.update(dict.fromkeys(group, unit))
    return units
