"""The differential-algebraic system of a circuit, as ``structure.reduce_index`` takes it,
and the rotors and sliding masses a circuit constrains, coupled into it.

An EMF reads the speed of its flange as a known. Where a differentiated constraint reaches
that speed (two EMFs wired to each other with nothing in between, an ideal electric gear;
an EMF straight across a voltage source or a capacitor), the speed is no known any more:
the free rigid groups the EMFs turn join the system, each with its balance
J a = R + (the EMFs' torques through the group's ratios), R standing for the generalized
force of everything else on the group (springs, sources, friction: the network's, filled in
when it has them), and its speed becomes a candidate state. Index reduction then keeps or
demotes it as any capacitor voltage: two rotors tied by an electric gear share one speed
state, a rotor under a voltage source turns at V / k with no speed state at all.
"""

from dataclasses import dataclass, field

import casadi as ca

from ..errors import ModelError
from . import balance


@dataclass(eq=False)
class Candidate:
    """A candidate state: its symbol ``x``, name, the component whose start it has (for
    messages and the start's check), the parameter giving that start and its value; ``dx``
    is its derivative's symbol, an unknown of the system."""
    x: ca.SX
    name: str
    comp: object
    key: str
    start: object
    dx: ca.SX = None
    group: object = None             # the free 1-D group whose speed it is


@dataclass
class Dae:
    """Residuals and who owns each (a component, or None for Kirchhoff's law), the
    algebraic unknowns with a description each, the knowns with their derivatives, and the
    candidate states (each with its rate equation among the residuals)."""
    equations: list = field(default_factory=list)
    owners: list = field(default_factory=list)
    unknowns: list = field(default_factory=list)
    names: list = field(default_factory=list)
    knowns: list = field(default_factory=list)
    candidates: list = field(default_factory=list)

    def add(self, equation, owner):
        self.equations.append(ca.SX(equation))
        self.owners.append(owner)

    def candidate(self, cand, rate, owner):
        cand.dx = ca.SX.sym(f"der_{cand.x.name()}")
        self.candidates.append(cand)
        self.add(cand.dx - rate, owner)

    def described(self, v):
        """The description of unknown or candidate ``v`` (an index into both, in order)."""
        return self.names[v] if v < len(self.names) else \
            self.candidates[v - len(self.names)].name


@dataclass
class Coupled:
    """A free rigid group in a circuit's system: ``rest``, the symbol of the generalized
    force of everything but the circuit's EMFs (``emfs``), and ``acc``, its acceleration
    solved with the circuit (in ``rest`` and the states)."""
    rest: ca.SX
    emfs: list
    candidate: Candidate
    acc: ca.SX = None


def couple(circuit, dae, emfs):
    """``dae`` with the free groups the ``emfs`` turn coupled in (see the module)."""
    b, model = circuit.b, circuit.model
    groups = {}
    for c in emfs:
        for pn in ("flange", "support"):
            group = b.group_of.get(b.topo.set_of[c.port_ref(pn)])
            if group is None or group.kind in ("fixed", "world"):
                continue
            if group.kind != "free":
                raise ModelError(model.problem(
                    f"the circuit fixes the voltage across {c.name} (it is "
                    f"wired across a voltage source, a capacitor or another EMF with no "
                    f"resistance or inductance in between), so it constrains the speed at "
                    f"{c.name}.{pn}, which is {_what(group)}: kinetwork reduces such a "
                    f"constraint only on free rotors and masses; add the armature's "
                    f"resistance or inductance", c, port=pn))
            groups[group.index] = group
    turning = [c for c in circuit.comps if c.name in circuit.speeds and any(
        b.group_of.get(b.topo.set_of[c.port_ref(pn)]) in groups.values()
        for pn in ("flange", "support"))]
    speed = {}
    for c in turning:
        w, dw = circuit.speeds.pop(c.name)
        speed[w.element_hash()] = (w, b.net.vel[c.port_ref("flange")] -
                                   b.net.vel[c.port_ref("support")])
        dae.knowns = [(k, d) for k, d in dae.knowns if k.element_hash() != w.element_hash()]
    old = ca.vertcat(*[w for w, _ in speed.values()])
    new = ca.vertcat(*[ca.SX(v) for _, v in speed.values()])
    dae.equations = [ca.substitute(e, old, new) for e in dae.equations]
    for index in sorted(groups):
        group = groups[index]
        _, w, _ = b.coord[index]
        first = next(e for e in group.rigid if e.has_inertia)
        rest = ca.SX.sym(f"rest_g{index}")
        torque = ca.SX(0)
        for c in turning:
            flows = b.bound[c.name].flows(None, None, b.t, circuit.current[c.port_ref("p")])
            for pn, f in flows.items():
                s = b.topo.set_of[c.port_ref(pn)]
                if b.group_of.get(s) is group:
                    torque += -b.kt[s] * f
        key = type(first).speed0.name            # "w0" or "v0"
        cand = Candidate(w, b.net.names[b.index_of(w)], first, key,
                         b.net.start[b.index_of(w)], group=group)
        dae.candidate(cand, (rest + torque) / balance.group_inertia(b, group), first)
        dae.knowns.append((rest, None))
        circuit.coupled[index] = Coupled(rest, [c.name for c in turning], cand)
    return dae


def _what(group):
    return {"joint": "a joint's axis (its speed a coordinate of the mechanism)",
            "massless": "a massless flange", "prescribed": "moved by a motion source"}.get(
                group.kind, group.kind)
