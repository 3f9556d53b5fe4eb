"""The signal blocks and sensors of the 1-D network: their states, order and outputs.

Signals are causal: each block's output is an expression of its inputs, states and time. The
dependency graph (networkx) of blocks, sensors and the mechanics (sources drive it,
acceleration and flow sensors read it) is cut into its strongly connected components
(Tarjan) and those are taken in topological order: a block-lower-triangular sort. A component
of several blocks is an algebraic loop: solved symbolically when it is linear and regular,
kept as algebraic variables (IDAS solves them with the rest) when it is nonlinear, refused
with its blocks named when it is singular, and always when it runs through the mechanics.

A step of ``network.build``: each function takes its builder.
"""

import casadi as ca
import networkx as nx

from ..errors import ModelError
from .signals import acceleration_unavailable

MECHANICS = "the mechanics"


def block_states(builder):
    """The states of the signal blocks, with their starts."""
    for comp in builder.model.components.values():
        if comp.role == "block" and comp.n_states:
            b = builder.bound[comp.name]
            labels = ["x"] if comp.n_states == 1 else [f"x[{i}]" for i in
                                                      range(comp.n_states)]
            xs = [builder.add_state(f"{comp.name}.{lab}", "", 0, 0) for lab in labels]
            starts = b.initial()
            for x, s in zip(xs, starts):
                builder.net.start[builder.index_of(x)] = s
            builder.block_x[comp.name] = xs
            builder.net.block_states += len(xs)


def inputs(builder, comp):
    """Input port name -> signal value (None: an unwired optional input)."""
    out = {}
    for pname, port in comp.ports.items():
        if port.domain == "signal_in":
            s = builder.topo.set_of[comp.port_ref(pname)]
            out[pname] = builder.net.signal.get(s) if s in builder.topo.signal_source else None
    return out


def output(builder, comp):
    """Evaluate a block's or a sensor's output into its signal set."""
    if getattr(type(comp), "outputs", None):
        # a power or multi sensor: the flow into flange_a, its speed, their product
        ref = comp.port_ref("flange_a")
        read = {"flow": builder.net.flow[ref], "speed": builder.net.vel[ref]}
        read["power"] = read["flow"] * read["speed"]
        for pname, what in comp.outputs.items():
            builder.net.signal[builder.topo.set_of[comp.port_ref(pname)]] = ca.SX(read[what])
        return
    s = builder.topo.set_of[comp.port_ref("y")]
    b = builder.bound[comp.name]
    if comp.role == "block":
        value = b.evaluate(inputs(builder, comp), builder.block_x.get(comp.name, []), builder.t,
                           _Mechanics(builder))
    elif comp.role == "electrical":
        value = builder.circuit.output(comp)
    elif comp.quantity == "flow":
        value = builder.net.flow[comp.port_ref("flange_a")]
    else:
        ref = comp.port_ref("flange")
        if comp.quantity == "acceleration" and massless_at(builder, ref):
            raise ModelError(acceleration_unavailable(builder.model.place(comp), ref),
                             **builder.model.fields(comp, port="flange"))
        value = {"position": builder.net.pos, "speed": builder.net.vel,
                 "acceleration": builder.net.acc}[comp.quantity][ref]
    builder.net.signal[s] = ca.SX(value)


def algebraic_loop(builder, names):
    """Blocks whose outputs depend on each other at the same instant: with their outputs
    z as unknowns, z = f(z) is solved symbolically when it is linear and regular (gains
    and sums in a ring); otherwise it is refused."""
    comps = [builder.model.components[n] for n in names]
    sets = [builder.topo.set_of[c.port_ref("y")] for c in comps]
    z = ca.SX.sym("loop", len(comps))
    for i, s in enumerate(sets):
        builder.net.signal[s] = z[i]
    for c in comps:
        output(builder, c)
    residual = z - ca.vertcat(*[builder.net.signal[s] for s in sets])
    jac = ca.jacobian(residual, z)
    what = f"algebraic loop through {', '.join(names)}"
    if ca.sprank(jac) < len(comps):
        raise ModelError(f"{what}: its outputs are not determined (structurally "
                         f"singular); break it with a state (an Integrator, a FirstOrder "
                         f"or a filtered Derivative)")
    if ca.depends_on(jac, z):
        # nonlinear (a Limiter, a Product, a Table in it): the outputs stay unknowns,
        # algebraic variables that IDAS solves with the rest at every step
        for i, (c, s) in enumerate(zip(comps, sets)):
            builder.net.alg_z.append(z[i])
            builder.net.alg_res.append(residual[i])
            builder.net.alg_names.append(f"{c.name}.y")
            builder.net.alg_units.append("")
            builder.net.signal[s] = z[i]
        builder.net.loops_kept.append(names)
        return
    det = ca.Function("det", [builder.p], [ca.det(jac)])(builder.p_values)
    if ca.sprank(jac) < len(comps) or abs(float(det)) < 1e-12:
        raise ModelError(f"{what}: its outputs are not determined (the loop gain is 1, "
                         f"det = {float(det):g}); break it with a state (an Integrator, a "
                         f"FirstOrder or a filtered Derivative)")
    solved = -ca.solve(jac, ca.substitute(residual, z, ca.SX.zeros(len(comps))))
    builder.net.loops_solved.append(names)
    for i, s in enumerate(sets):
        builder.net.signal[s] = solved[i]


def massless_at(builder, ref):
    """Whether the port ``ref`` is on a massless group (no acceleration there)."""
    group = builder.group_of.get(builder.topo.set_of[ref])
    return group is not None and group.kind == "massless"


def block_rates(builder):
    """The rates of the signal blocks' states, once every signal is known."""
    for name, xs in builder.block_x.items():
        comp = builder.model.components[name]
        rates = builder.bound[name].rates(inputs(builder, comp), xs, builder.t)
        for x, r in zip(xs, rates):
            builder.net.rate[builder.index_of(x)] = r


def order(builder):
    """Blocks, sensors and the mechanics in an order where everything an output needs at
    the same instant comes first; algebraic loops refused."""
    g = nx.DiGraph()
    g.add_node(MECHANICS)
    for comp in builder.model.components.values():
        if comp.role == "block" or _measures(comp):
            g.add_node(comp.name)
    for comp in builder.model.components.values():
        if _measures(comp) in ("acceleration", "flow"):
            g.add_edge(MECHANICS, comp.name)
        if comp.role == "sensor":
            group = builder.group_of.get(builder.topo.set_of[comp.port_ref("flange")])
            if group is not None and group.kind == "massless":
                g.add_edge(MECHANICS, comp.name)   # flows set its position at once
        for pname, port in comp.ports.items():
            if port.domain != "signal_in":
                continue
            s = builder.topo.set_of[comp.port_ref(pname)]
            if s not in builder.topo.signal_source:
                continue
            source = builder.topo.signal_source[s].component.name
            if comp.role == "block" and comp.feedthrough:
                g.add_edge(source, comp.name)
            elif comp.role in ("source", "prescribed"):
                g.add_edge(source, MECHANICS)
    for read in builder.reads.values():
        # a law reading signals is part of the mechanics (a source's flow, or a force
        # on frames: its generalized force), needing the signals first
        for _, s in read.values():
            g.add_edge(builder.topo.signal_source[s].component.name, MECHANICS)
    circuit_edges(builder, g)
    # block-lower-triangular order: the strongly connected components (Tarjan) of the
    # graph, each solved as one block, in topological order of the condensation
    dag = nx.condensation(g)
    blocks = [sorted(dag.nodes[c]["members"]) for c in
              nx.lexicographical_topological_sort(dag, key=lambda c: min(
                  dag.nodes[c]["members"]))]
    loops = [c for c in blocks if MECHANICS in c and len(c) > 1]
    if loops:
        raise ModelError([
            f"algebraic loop through {', '.join(n for n in c if n != MECHANICS)} and "
            f"the mechanics (an acceleration or force measured and fed back without delay "
            f"to a source): break it with a state (an Integrator, a FirstOrder or a "
            f"filtered Derivative)" for c in loops])
    return [c[0] if len(c) == 1 else c for c in blocks]


def circuit_edges(builder, g):
    """A signal into an electrical source reaches, at the same instant, the sensors
    and EMF torques whose circuit it drives (an algebraic loop when fed back)."""
    feeder = {name: builder.topo.signal_source[s].component.name for name, s in (
        (name, builder.circuit.inputs[ph]) for name, ph in builder.circuit.sources.items())}
    if not feeder:
        return
    for comp in builder.circuit.comps:
        if getattr(type(comp), "quantity", None):
            reads = builder.circuit.output(comp)
            for name in builder.circuit.placeholders_in(reads):
                g.add_edge(feeder[name], comp.name)
        if getattr(type(comp), "converter", False):
            for name in builder.circuit.placeholders_in(builder.circuit.converter_current(comp)):
                g.add_edge(feeder[name], MECHANICS)


class _Mechanics:
    """What a block that uses the model's own dynamics (``signals.InverseDynamics``) is
    handed: the number of speeds, a joint's speed index, and the inverse dynamics."""

    def __init__(self, builder):
        self._b = builder
        self.n_speeds = builder.u.shape[0]

    @property
    def parameters(self):
        """The model's parameters by name, as the symbols they stay in the System."""
        return {name: self._b.p[i] for i, name in enumerate(self._b.model.parameters)}

    def speed_of(self, joint_name):
        """Index of the speed of a one-degree-of-freedom joint of the model, or None."""
        joint = self._b.model.components.get(joint_name)
        if joint is None or joint.name not in self._b.uindex or joint.dof != 1:
            return None
        return self._b.uindex[joint.name][0]

    def inverse(self, a):
        """M(q) a + C(q, u) u + G(q) - Q_passive for the speeds' rates ``a`` (a list)."""
        b = self._b
        return b.inverse(ca.vertcat(*[ca.SX(v) for v in a]), b.net.armature, b.passive)

    def refuse(self, comp, key, message):
        return ModelError(f"{self._b.model.place(comp, key)}: {message}")


def _measures(comp):
    """What a sensor measures ("position", "speed", "acceleration", "flow"), or None."""
    return getattr(type(comp), "quantity", None)
