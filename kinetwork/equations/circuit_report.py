"""What structural analysis says about a circuit, in words: why each demoted state is no
state, the names of the unknowns kept as algebraic variables, the summary line of what was
made of the circuits, and the refusal of one that cannot be solved.

Each function takes the ``circuit.Circuit`` it speaks about.
"""

import casadi as ca

from ..errors import ModelError


def why_demoted(circuit, dae, reduced, cand, value, kept):
    """What fixes a demoted state: the kept states and the sources its value follows
    from, and the components of the constraint (the laws differentiated in the step
    that found it, with the components of those states), grounds left out."""
    symbols = {x.element_hash() for x in ca.symvar(value)}
    reads = [c for c in kept if c.x.element_hash() in symbols]
    group = {c.comp.name for c in reads} | {cand.comp.name}
    for eqs in reduced.constraints:
        if any(ca.depends_on(dae.equations[e], cand.x) for e in eqs):
            group |= {dae.owners[e].name for e in eqs if dae.owners[e] is not None}
    group = [name for name in circuit.model.components if name in group
             and circuit.model.components[name].type_name != "electrical.Ground"]
    driven = [name for name in group if getattr(
        type(circuit.model.components[name]), "reference_key", None)]
    follows = ", ".join([c.name for c in reads] + [f"the source {n}" for n in driven])
    return f"follows from {follows or 'the sources'} through the constraint of " \
           f"{', '.join(group)}"


def label(circuit, z, unknowns):
    """A short name of an unknown kept as an algebraic variable: ``D1.p.v`` for the
    potential at a set holding pin D1.p, ``D1.p.i`` for a pin's current."""
    for s, v in zip(sorted(circuit.potential), unknowns):
        if v.element_hash() == z.element_hash():
            first = next(r for r in circuit.topo.sets[s] if r.component.role != "probe")
            return f"{first.path}.v"
    for ref, v in zip(circuit.current, unknowns[len(circuit.potential):]):
        if v.element_hash() == z.element_hash():
            return f"{ref.path}.i"
    return z.name()


def summary(circuit, dae, reduced, solved):
    """The line on what structural analysis made of the circuits (``Network.circuit``)."""
    loops = [n for n in solved.sizes if n > 1]
    out = (f"circuits: {len(circuit.potential)} node potentials and {len(circuit.current)} "
           f"pin currents in {len(solved.sizes)} blocks"
           + ("" if solved.kept else " solved symbolically")
           + (f" (linear loops of {', '.join(map(str, loops))})" if loops else "")
           + f", {len(reduced.states)} states")
    if circuit.coupled:
        out += ("; with the rotors (masses) the EMFs turn: "
                + ", ".join(c.candidate.name for c in circuit.coupled.values()))
    if reduced.demoted:
        out += (f"; index reduction (Pantelides, dummy derivatives): "
                f"{len(reduced.constraints)} constraints differentiated, "
                f"{', '.join(circuit.demoted)} demoted to algebraic")
    if solved.kept:
        out += (f"; {solved.nonlinear} nonlinear blocks, {len(solved.kept)} algebraic "
                f"variables")
    return out


def refusal(circuit, exc, dae, reduced=None):
    """The ModelError of a circuit that cannot be solved: the components whose laws
    over-determine it and the unknowns left undetermined, each sorted."""
    eqs = exc.equations if reduced is None else sorted({reduced.origin[e]
                                                        for e in exc.equations})
    comps = sorted({dae.owners[e].name for e in eqs if dae.owners[e] is not None})
    kcl = any(dae.owners[e] is None for e in eqs)
    lost = [dae.described(v if reduced is None else reduced.base[v][0])
            for v in exc.unknowns]
    what = (", ".join(comps) or "the circuit") + (
        " and Kirchhoff's current law" if kcl and comps else "")
    if exc.reason:
        reason = exc.reason
        if "rest_g" in reason:
            reason = ("it needs the derivative of the forces on a rotor the circuit "
                      "constrains (a constraint of the mechanism's accelerations)")
        return ModelError(f"circuit: the equations of {what} cannot be solved: {reason}"
                          + (f"; undetermined: {', '.join(lost)}" if lost else ""),
                          **fields_of(circuit, comps))
    return ModelError(
        f"circuit: the equations of {what} constrain their unknowns twice and leave "
        f"{', '.join(lost) or 'nothing'} undetermined: the circuit is structurally "
        f"singular (two voltage sources in parallel, a loop of voltage sources, a current "
        f"source in series with another, an open current source, an ideal op-amp with "
        f"no feedback)", **fields_of(circuit, comps))


def fields_of(circuit, names):
    """The fields of a refusal naming components ``names``: the first one's (sorted)."""
    return circuit.model.fields(circuit.model.components[names[0]]) if names else {}
