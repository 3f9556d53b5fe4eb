"""Supports of rigid 1-D elements (MSL's ``useSupport``): a gear whose housing is wired.

MSL's IdealGear reads its flanges relative to its support, flange_a.phi - support.phi =
ratio * (flange_b.phi - support.phi), and puts the reaction -flange_a.tau - flange_b.tau on
the support. Wired to a Fixed, a joint's support or nothing, the support stands still (at
the Fixed's angle). Wired to a moving flange (a housing inertia on a spring, MSL's
ElasticBearing), the gear's rigid group rides on the group of its support: the positions of
its sets are its own coordinate plus a share of the carrier's, and the two groups' motions
are solved together (``kinetwork.equations.network``).

What the equations take: a group that rides must move freely (inertias, no joint axis, no
motion source, no lossy gear), on a carrier that moves freely or by a prescribed motion;
anything else is refused here, naming the gear and both flanges.
"""

import networkx as nx


def check(model, topo, values, problems):
    """Record each gear's wired support in its group (``OneDGroup.supports``) and refuse
    what cannot ride."""
    group_of = {s: g for g in topo.oned for s, _, _ in g.sets}
    for group in topo.oned:
        for element in group.rigid:
            if "support" not in element.ports:
                continue
            ref = element.port_ref("support")
            s = topo.set_of[ref]
            carrier = group_of.get(s)
            if carrier is None or carrier.kind == "world":
                continue
            place = model.place(element)
            if carrier is group:
                problems.append(f"{place}: {ref.path} is rigidly tied to the gear's own "
                                f"flanges (through {', '.join(_names(group))}), which locks it")
                continue
            group.supports[element.name] = s
            if carrier.kind == "fixed":
                continue                   # it stands still: an offset, no motion
            why = _refusal(element, group, carrier, values)
            if why:
                problems.append(f"{place}: {ref.path} is wired to a flange that moves "
                                f"({_what(carrier)}); {why}")
                continue


def rings(topo, problems):
    """Refuse groups that carry each other's housings in a ring (gears' supports, motions'
    supports): nothing would stand still for them to turn against."""
    group_of = {s: g for g in topo.oned for s, _, _ in g.sets}
    riding = nx.DiGraph()
    for group in topo.oned:
        for s in [*group.supports.values(), *([] if group.base is None else [group.base])]:
            if group_of[s].kind != "fixed":
                riding.add_edge(group.index, group_of[s].index)
    for cycle in sorted((sorted(c) for c in nx.simple_cycles(riding)), key=min)[:1]:
        names = sorted({*[n for g in cycle for n in topo.oned[g].supports],
                        *[topo.oned[g].definer.component.name for g in cycle
                          if topo.oned[g].base is not None]})
        problems.append(f"{', '.join(names)} carry each other's housings in a ring: one of "
                        f"them must rest on a flange that does not ride on the others")


def _refusal(element, group, carrier, values):
    """Why ``element``'s group cannot ride on ``carrier`` (empty when it can)."""
    if carrier.kind in ("joint", "massless", "assembly"):
        return (f"a gear whose housing turns with {_what(carrier)} "
                f"is not supported: give the housing an inertia of its own, or wire the "
                f"support to the joint's support flange (the joint's frame_a side)")
    if group.kind != "free":
        what = {"joint": "a joint axis", "prescribed": "a prescribed motion",
                "massless": "no inertia", "fixed": "a fixed flange",
                "assembly": "an assembly's axis"}[group.kind]
        return (f"its gear train is tied to {what}, where a moving housing is not supported: "
                f"the train riding on a housing must move freely (inertias, springs, "
                f"sources)")
    lossy = [e for e in group.rigid if getattr(type(e), "lossy", False) and values is not None
             and values[e.name].get("eta", 1.0) != 1.0]
    if lossy:
        return (f"{', '.join(e.name for e in lossy)} has a loss (eta < 1), which is taken "
                f"only on gears whose housing stands still")
    return ""


def _what(group):
    return {"free": "a free rotor", "prescribed": "a prescribed motion", "joint": "a joint "
            "axis", "massless": "a massless flange",
            "assembly": "an assembly's axis"}.get(group.kind, group.kind)


def _names(group):
    return sorted(e.name for e in group.rigid)
