"""``kinetwork validate MODEL.json``: check a model file and summarise it (components,
connections, degrees of freedom, loops, parameters; with ``--compile`` the equations)."""

import collections
import os
import textwrap

from .common import SHOWN_ITEMS, add_library, listing, load_model, shown


def add(sub):
    """The ``validate`` subcommand's parser; {name: handler}."""
    parser = sub.add_parser(
        "validate", help="check a model and summarise it",
        description="Check MODEL.json and summarise it: components, connections, degrees of "
                    "freedom, loops, parameters. The equations are not built unless "
                    "--compile asks for them (states, equation size).")
    parser.add_argument("model", metavar="MODEL.json", help="model file")
    parser.add_argument("--compile", action="store_true",
                        help="also build the equations and summarise them: states, algebraic "
                             "variables, equation size (takes longer on large models)")
    parser.add_argument("--loops", choices=["projected", "partition", "baumgarte"],
                        default="projected",
                        help="formulation of kinematic loops: projected (default: an ODE, "
                             "CVODES Adams), partition (the fewest states: a DAE for IDAS) or "
                             "baumgarte")
    add_library(parser)
    return {"validate": validate}


def validate(args):
    model = load_model(args.model, args.library)   # reading validates: one ModelError lists all
    if model.exposed:
        print("\n".join(_definition_summary(model, args.model)))
        return 0
    topo = model.validate()             # the same Topology again, not a second analysis
    kinds = collections.Counter(c.type_name for c in model.components.values())
    groups = collections.Counter(g.kind for g in topo.oned)
    lines = [
        f"model {model.name!r} ({args.model}): valid",
        *([textwrap.fill(f"description: {shown(model.description)}", 88,
                         subsequent_indent="  ", break_on_hyphens=False)]
          if model.description else []),
        f"components: {len(model.components)} ("
        + ", ".join(f"{n} {kind}" for kind, n in kinds.most_common()) + ")",
        f"connections: {len(model.connections)}",
        *_subsystems_summary(model),
    ]
    loops = f"loops: {len(topo.loops) or 'none'}" + "".join(
        f"\n  {' - '.join(cut.loop)} (cut at {cut.component.name})"
        for cut in topo.cuts[:SHOWN_ITEMS]) + (
        f"\n  ... ({len(topo.cuts)} in all)" if len(topo.cuts) > SHOWN_ITEMS else "")
    if args.compile:
        lines += _compiled_summary(model.compile(loops=args.loops), topo, loops)
    elif any(port.domain == "electrical" for c in model.components.values()
             for port in c.ports.values()):
        # a circuit's states are chosen by its structure (index reduction): compiled to say
        # which, as validation of a circuit is about which energy stores are independent
        lines += _compiled_summary(model.compile(loops=args.loops), topo, loops)
    else:
        # the joints' degrees of freedom and the free 1-D groups' are exact without the
        # equations; loops take away as many as their independent closure equations
        dof = topo.dof + groups["free"]
        lines += [f"degrees of freedom: {dof}" if not topo.loops else
                  f"degrees of freedom: at most {dof}, less one per independent closure "
                  f"equation of the loops (--compile counts them)", loops]
    if not args.compile and groups:
        lines.append("1-D rigid groups: " + ", ".join(
            f"{groups[k]} {what}" for k, what in (
                ("joint", "on joint axes"), ("free", "free (an angle and a speed each)"),
                ("massless", "massless"), ("prescribed", "prescribed"), ("fixed", "fixed"))
            if groups[k]))
    lines.append(f"parameters: {len(model.parameters)}" + (
        " (" + listing(f"{k} = {v:g}" for k, v in model.parameters.items()) + ")"
        if model.parameters else ""))
    if model.simulation:
        lines.append("simulation: " + ", ".join(f"{k} = {v}"
                                                for k, v in model.simulation.items()))
    print("\n".join(lines))
    return 0


def _subsystems_summary(model):
    """Lines naming each subsystem definition, where it comes from and its instances by
    path; nothing for a flat model."""
    from ..graph.subsystem import subsystem_instances
    placed = subsystem_instances(model)
    if not placed:
        return []
    flat = model.flat()
    lines = [f"subsystems: {len(placed)} definition{'s' if len(placed) > 1 else ''}, "
             f"{sum(len(p) for _, p in placed.values())} instances; flat: "
             f"{len(flat.components)} components, {len(flat.connections)} connections"]
    for name, (definition, paths) in placed.items():
        origin = definition.origin
        where = "inline" if origin is None else f"{origin[1]} {os.path.relpath(origin[0])}"
        ports = ", ".join(definition.exposed)
        lines.append(f"  {name} ({where}; ports {ports or 'none'}): "
                     + listing(paths))
    return lines


def _definition_summary(model, path):
    """``validate`` of a definition file: its ports and parameters (it is wired where it is
    placed, so its wiring is checked there)."""
    kinds = collections.Counter(c.type_name for c in model.components.values())
    ports = [f"{name} -> {ref.path} ({ref.domain})" for name, ref in model.exposed.items()]
    return [
        f"subsystem definition {model.name!r} ({path}): values valid; its wiring is checked "
        f"where it is placed",
        f"ports: {listing(ports)}",
        f"components: {len(model.components)} ("
        + ", ".join(f"{n} {kind}" for kind, n in kinds.most_common()) + ")",
        f"connections: {len(model.connections)}",
        *_subsystems_summary(model)[1:],
        f"parameters: {len(model.parameters)}" + (
            " (" + listing(f"{k} = {v:g}" for k, v in model.parameters.items()) + ")"
            if model.parameters else ""),
    ]


def _compiled_summary(system, topo, loops):
    """The lines of ``validate --compile`` from the equations: degrees of freedom, states,
    algebraic variables, the ``loops`` line, formulation, 1-D network, equation size."""
    units = dict(zip(system.state_names, system.state_units))
    n_values = sum(sig.size for sig in system.signals)
    size = system.size()
    network = system.asm.net.summary(topo)
    return [
        f"degrees of freedom: {system.dof}",
        f"states: {system.n_states}"
        + (" (" + listing(f"{s} [{units[s]}]" if units[s] else s
                           for s in system.state_names) + ")" if system.n_states else ""),
        *([f"algebraic: {system.n_algebraic} ("
           + listing(f"{s} [{u}]" if u else s for s, u in
                      zip(system.algebraic_names, system.algebraic_units)) + ")"]
          if system.n_algebraic else []),
        loops,
        *([textwrap.fill(f"why these states: {system.formulation_note}", 88,
                         subsequent_indent="  ")] if system.formulation_note else []),
        *([textwrap.fill(network, 88, subsequent_indent="  ")] if network else []),
        *[textwrap.fill(f"demoted by index reduction: {name} ({why})", 88,
                        subsequent_indent="  ") for name, why in system.demoted_states.items()],
        f"equations: {size['states']} states, {size['algebraic']} algebraic variables, "
        f"{len(system.signal_names)} probe signals ({n_values} values); right-hand side "
        f"{size['operations']} operations per evaluation ("
        + {"tree": "articulated-body algorithm, O(N)",
           "hybrid": "articulated-body algorithm with the prescribed accelerations, O(N)"}.get(
            system.formulation, "mass matrix projected on the independent speeds") + ")",
    ]
