"""The 1-D mechanical networks and the signal blocks, as SX expressions.

Structure first (the rigid groups of ``kinetwork.graph.topology``): every rigid group shares
one coordinate theta, and each of its connection sets sits at k * theta, k the product of
the gear ratios on the way from the group's root (alias elimination: one variable for all the
flanges a rigid chain ties together). What the group's coordinate is follows from its kind:

- "joint": the joint coordinate; the group's inertia sum(J k^2) is added to the joint's
  diagonal of the mass matrix (its armature): exact, and no state;
- "fixed" / "world": a constant; "prescribed": what its motion source gives (a Position,
  Speed or Accelerate: its reference differentiated exactly, integrated or filtered, with the
  states that takes);
- a "joint" group with a motion source in it: the joint's coordinate, speed and acceleration
  are those of the motion (divided by the group's ratio at the source), recorded in
  ``Network.prescribed`` for the formulation, which eliminates them (``loops.py``); the
  torque the source applies is a symbol, the generalized force the formulation finds the
  joint needs;
- "free": a coordinate and a speed of its own (a rotor behind a flexible coupling):
  J theta'' = the generalized force of the elements on it;
- "massless": no inertia, so the flows on it balance at every instant: solved symbolically
  for the speed (a damper on it: one first-order state) or for the position (springs only:
  no state), the balance being linear in them.

Signals are causal: each block's output is an expression of its inputs, states and time. The
dependency graph (networkx) of blocks, sensors and the mechanics (sources drive it,
acceleration and flow sensors read it) is cut into its strongly connected components
(Tarjan) and those are taken in topological order: a block-lower-triangular sort. A component
of several blocks is an algebraic loop: solved symbolically when it is linear and regular,
kept as algebraic variables (IDAS solves them with the rest) when it is nonlinear, refused
with its blocks named when it is singular, and always when it runs through the mechanics.
"""

from dataclasses import dataclass, field

import casadi as ca
import networkx as nx

from ..errors import ModelError
from . import starts, supports
from .circuit import Circuit
from .signals import acceleration_unavailable

MECHANICS = "the mechanics"


@dataclass
class Network:
    """What the 1-D network and the blocks give the Assembly."""
    pos: dict
    vel: dict
    acc: dict
    flow: dict                      # PortRef -> flow into its component
    Q: ca.SX                        # generalized forces on the joint speeds
    armature: ca.SX                 # inertia added to each joint speed
    axis_flow: ca.SX                # flow into the joint axes (drive torques, with inertia)
    x: list = field(default_factory=list)        # extra states (SX scalars)
    rate: list = field(default_factory=list)     # their rates
    start: list = field(default_factory=list)    # their initial values
    names: list = field(default_factory=list)
    units: list = field(default_factory=list)
    signal: dict = field(default_factory=dict)   # signal set -> value
    loops_solved: list = field(default_factory=list)   # algebraic loops solved symbolically
    loops_kept: list = field(default_factory=list)     # nonlinear ones: algebraic variables
    alg_z: list = field(default_factory=list)          # their outputs, unknowns ...
    alg_res: list = field(default_factory=list)        # ... and their equations z - f(z)
    alg_names: list = field(default_factory=list)
    alg_units: list = field(default_factory=list)
    block_states: int = 0
    no_acceleration: set = field(default_factory=set)  # sets of massless groups
    #: speed index -> Prescribed, for joints whose coordinate a motion source gives
    prescribed: dict = field(default_factory=dict)
    #: elements with modes (friction, stops), in the order placed: ``Hybrid`` records
    hybrid: list = field(default_factory=list)
    #: what structural analysis made of the circuits (``circuit.Circuit.summary``)
    circuit: str = ""
    #: state name -> why it is no state: index reduction found a constraint that fixes it
    demoted: dict = field(default_factory=dict)
    #: joint starts the inertias on joint axes give: (``"q"`` or ``"u"``, index, value)
    claims: list = field(default_factory=list)

    def summary(self, topo):
        """A line on what structural analysis made of the 1-D network and the blocks."""
        kinds = {}
        for g in topo.oned:
            kind = "driven" if g.motion else g.kind
            kinds[kind] = kinds.get(kind, 0) + 1
        blocks = self.block_states
        parts = [f"{kinds[k]} {what}" for k, what in (
            ("joint", "on joint axes (no state: any inertia adds to the joint's)"),
            ("driven", "moving a joint by a prescribed motion (its coordinate is no state)"),
            ("free", "free (an angle and a speed each)"),
            ("massless", "massless (solved from their balance)"),
            ("prescribed", "prescribed"), ("fixed", "fixed")) if kinds.get(k)]
        out = f"1-D rigid groups: {', '.join(parts)}" if parts else ""
        if blocks or self.loops_solved or self.loops_kept:
            out += ("; " if out else "") + f"signal block states: {blocks}" + (
                f"; algebraic loops solved symbolically: {len(self.loops_solved)}"
                if self.loops_solved else "") + (
                f"; nonlinear algebraic loops kept as algebraic variables: "
                f"{len(self.loops_kept)} ({len(self.alg_z)} variables)" if self.loops_kept
                else "")
        if self.circuit:
            out += ("; " if out else "") + self.circuit
        return out


def build(model, topo, bound, q, u, udot, qindex, uindex, t, inverse=None, p=None,
          p_values=None, reads=None, derived=None):
    """The Network of a validated model, in the symbols of the Assembly.

    ``derived``: the flanges whose position an assembly gives (its axis, the angle or
    distance that closes its loop), PortRef -> (position, speed, acceleration) in (q, u,
    udot); the generalized force on such a flange reaches the speeds by virtual work.

    ``inverse(a, armature, Q)`` is the tree's inverse dynamics (for InverseDynamics blocks):
    the generalized forces for speeds' rates ``a`` with the given armature, less ``Q``.
    ``reads``: component name -> {signal name: (placeholder, signal set)} for the values
    that read signals (a source's force law), the placeholders replaced by the signals.
    """
    builder = _Builder(model, topo, bound, q, u, udot, qindex, uindex, t, inverse, p,
                       p_values)
    builder.reads = reads or {}
    builder.derived = derived or {}
    return builder.run()


@dataclass
class Hybrid:
    """An element with modes while the network is built: the model's component, its bound
    twin, its mode state, the symbol of its holding force, its flanges a and b (their
    PortRefs) and the set of its signal input u (or None)."""
    comp: object
    bound: object
    mode: ca.SX
    F: ca.SX
    a: object
    b: object
    u: object


@dataclass
class Prescribed:
    """A joint coordinate a motion source gives: its value, speed and acceleration (in t,
    p, the network's states and, for a filtered reference, the mechanism's q and u), and
    ``drive``, the symbol of the generalized force the source applies to the joint."""
    coordinate: int
    pos: ca.SX
    vel: ca.SX
    acc: ca.SX
    drive: ca.SX
    source: str
    joint: str


@dataclass
class _Motion:
    """A motion source while the network is built: its group, ratio, states, reference."""
    comp: object                     # bound to the parameters' symbols
    source: object                   # the model's component, whose ports are wired
    group: object
    k: ca.SX
    x: list
    coord: tuple                     # placeholders (or the joint's q, u, udot)
    reference: ca.SX = None
    drive: ca.SX = None              # on a joint: the symbol of the generalized force
    offset: ca.SX = 0                # the source's flange is at k theta + offset


class _Builder:
    def __init__(self, model, topo, bound, q, u, udot, qindex, uindex, t, inverse, p,
                 p_values):
        self.model, self.topo, self.bound = model, topo, bound
        self.inverse, self.p, self.p_values = inverse, p, p_values
        self.q, self.u, self.udot, self.t = q, u, udot, t
        self.qindex, self.uindex = qindex, uindex
        n = u.shape[0]
        self.net = Network({}, {}, {}, {}, ca.SX.zeros(n), ca.SX.zeros(n), ca.SX.zeros(n))
        self.k = {}                  # connection set -> ratio to its group's coordinate
        self.c = {}                  # ... and offset: position = k theta + c (a Mass's L)
        self.ride = {}               # ... and the shares of its carriers (``supports.ride``)
        self.kin = {}                # connection set -> (position, speed, acceleration)
        self.kt = {}                 # ... and of its torques (differs through gear losses)
        self.losses = {}             # gear with a loss -> eta^mode
        self.group_of = {}           # connection set -> group
        self.coord = {}              # group index -> (theta, theta', theta'')
        self.pending = {}            # placeholder symbol -> expression, substituted at the end
        self.block_x = {}
        self.inertia = {}            # group index -> sum of J k^2
        self.motions = []            # _Motion, in group order

    # -- the steps ------------------------------------------------------------------------
    def run(self):
        for group in self.topo.oned:
            self._ratios(group)
        for group in self.topo.oned:
            self._coordinate(group)
        self.kin = supports.kinematics(self)
        for s, (pos, vel, acc) in self.kin.items():
            for ref in self.topo.sets[s]:
                self.net.pos[ref], self.net.vel[ref], self.net.acc[ref] = pos, vel, acc
        self.riding = supports.clusters(self)
        starts.free(self)
        self._block_states()
        # circuits next: their currents are expressions of states and speeds, so EMF
        # torques are known before any balance (``circuit.py``)
        self.circuit = Circuit(self).build()
        self.circuit.fill(self.net)
        self.net.circuit = self.circuit.summary
        self.net.demoted.update(self.circuit.demoted)
        self._flows("compliant")               # springs and dampers need no signal
        self._passive = ca.SX.zeros(self.u.shape[0])
        for group in self.topo.oned:
            self._inertia(group)
        for node in self._order():
            if node == MECHANICS:
                self._mechanics()
            elif isinstance(node, list):
                self._algebraic_loop(node)
            else:
                self._output(self.model.components[node])
        self._block_rates()
        self._finish()
        return self.net

    def _ratios(self, group):
        for s, parent, element in group.sets:
            self.group_of[s] = group
            if parent is None:
                self.k[s] = self.kt[s] = ca.SX(1)
                self.c[s] = ca.SX(0)
                self.ride[s] = [] if group.base is None else [(ca.SX(1), group.base)]
                continue
            r = self.bound[element.name].position_ratio()
            length = self.bound[element.name].length()
            a_here = self.topo.set_of[element.port_ref("flange_a")] == s
            # position(flange_a) = r * (position(flange_b) - length), relative to the
            # gear's support
            self.k[s] = self.k[parent] * r if a_here else self.k[parent] / r
            self.c[s] = r * (self.c[parent] - length) if a_here else \
                self.c[parent] / r + length
            self.ride[s] = supports.ride(self, parent, element, a_here, r if a_here else 1 / r)
            # torques pass a gear with efficiency eta as torque_b = -r eta^m torque_a, m = +1
            # while flange_a drives (power from a to b), -1 while flange_b does
            loss = self._loss(element, group)
            self.kt[s] = self.kt[parent] * r * loss if a_here else self.kt[parent] / (r * loss)

    def _loss(self, element, group):
        """eta^m of a gear with a loss (its mode m a state, changed at events where the power
        through it turns: ``components/friction.py``), else 1."""
        b = self.bound[element.name]
        if not getattr(type(element), "lossy", False) or element.eta == 1:
            return ca.SX(1)
        if group.kind != "free" or group.motion is not None:
            # on a joint the inertia it reflects, which depends on the driving side, would
            # enter the mass matrix, which is a function of the coordinates alone
            raise ModelError(f"{self.model.place(element, 'eta')}: a gear with a loss is "
                             f"taken between rotors that move freely (a drive train of "
                             f"inertias), not yet on a joint's axis or a prescribed motion; "
                             f"set eta = 1 there, or put the loss in a BearingFriction",
                             **self.model.fields(element, "eta"))
        if element.name not in self.losses:
            from ..components.friction import GearModes
            mode = self._state(f"{element.name}.mode", "", 1, ca.SX(0))
            refs = (element.port_ref("flange_a"), element.port_ref("flange_b"))
            self.net.hybrid.append(Hybrid(GearModes(element), GearModes(b), mode,
                                          ca.SX.sym(f"F_{element.name}"), *refs, None))
            self.losses[element.name] = (1 + mode) / 2 * b.eta + (1 - mode) / 2 / b.eta
        return self.losses[element.name]

    def _coordinate(self, group):
        kind = group.kind
        zero = (ca.SX(0), ca.SX(0), ca.SX(0))
        if kind == "joint":
            joint = group.definer.component
            j = joint.coordinate_ports[group.definer.name]
            i, u = self.qindex[joint.name][j], self.uindex[joint.name][j]
            self.coord[group.index] = (self.q[i], self.u[u], self.udot[u])
            if group.motion is not None:
                self._motion(group, group.motion, self.coord[group.index])
        elif kind == "fixed":
            comp = self.bound[group.definer.component.name]
            position = comp.position() if comp.role == "fixed" else 0
            self.coord[group.index] = (ca.SX(position), ca.SX(0), ca.SX(0))
        elif kind == "prescribed":
            # placeholders until the reference (perhaps a signal) is known: ``_finish``
            placeholders = tuple(ca.SX.sym(f"g{group.index}_{what}")
                                 for what in ("pos", "vel", "acc"))
            self.coord[group.index] = placeholders
            self._motion(group, group.definer, placeholders)
        elif kind == "free":
            self._free(group)
        elif kind == "assembly":
            self.coord[group.index] = tuple(ca.SX(v) for v in self.derived[group.definer])
        elif kind == "massless":
            theta, w = ca.SX.sym(f"g{group.index}_pos"), ca.SX.sym(f"g{group.index}_vel")
            a = ca.SX.sym(f"g{group.index}_acc")
            self.coord[group.index] = (theta, w, a)
        else:
            self.coord[group.index] = zero

    def _motion(self, group, flange, coord):
        """A motion source on ``group``: its states (position, then speed), named as the
        source's (``drive.phi``, ``drive.w``)."""
        comp = self.bound[flange.component.name]
        units = _units(group)
        labels = list(zip((_pos(group), _vel(group)), units))[:comp.n_states]
        x = [self._state(f"{comp.name}.{label}", unit, 0, 0) for label, unit in labels]
        at = self.topo.set_of[flange]
        self.motions.append(_Motion(comp, flange.component, group, self.k[at], x, coord,
                                    offset=self.c[at]))

    def _free(self, group):
        """A coordinate and a speed, the position and speed of the group's first inertia
        (the group's root), named after it; their starts follow from the inertias' own
        (``starts.free``, once every position is known)."""
        first = next(e for e in group.rigid if e.has_inertia)
        pos_unit, vel_unit = _units(group)
        at = self.topo.set_of[first.port_ref("flange_a")]
        # the coordinate is the first inertia's centre (MSL's Mass.s, between its flanges
        # L apart), in the units of its flanges divided by their ratio
        centre = self.c[at] + self.bound[first.name].length() / 2
        for s, _, _ in group.sets:
            self.c[s] = self.c[s] - self.k[s] * centre / self.k[at]
        a = ca.SX.sym(f"g{group.index}_acc")
        w = self._state(f"{first.name}.{_vel(group)}", vel_unit, 0, a)
        theta = self._state(f"{first.name}.{_pos(group)}", pos_unit, 0, w,
                            at=len(self.net.x) - 1)
        self.coord[group.index] = (theta, w, a)

    def _state(self, name, unit, start, rate, at=None):
        x = ca.SX.sym(name.replace(".", "_"))
        at = len(self.net.x) if at is None else at
        self.net.x.insert(at, x)
        self.net.rate.insert(at, rate)
        self.net.start.insert(at, start)
        self.net.names.insert(at, name)
        self.net.units.insert(at, unit)
        return x

    def _at(self, x):
        """Position of the state symbol ``x`` (by identity: SX == builds an expression)."""
        return next(i for i, v in enumerate(self.net.x) if v is x)

    # -- signals ----------------------------------------------------------------------------
    def _block_states(self):
        for comp in self.model.components.values():
            if comp.role == "block" and comp.n_states:
                b = self.bound[comp.name]
                labels = ["x"] if comp.n_states == 1 else [f"x[{i}]" for i in
                                                          range(comp.n_states)]
                xs = [self._state(f"{comp.name}.{lab}", "", 0, 0) for lab in labels]
                starts = b.initial()
                for x, s in zip(xs, starts):
                    self.net.start[self._at(x)] = s
                self.block_x[comp.name] = xs
                self.net.block_states += len(xs)

    def _inputs(self, comp):
        """Input port name -> signal value (None: an unwired optional input)."""
        out = {}
        for pname, port in comp.ports.items():
            if port.domain == "signal_in":
                s = self.topo.set_of[comp.port_ref(pname)]
                out[pname] = self.net.signal.get(s) if s in self.topo.signal_source else None
        return out

    def _output(self, comp):
        """Evaluate a block's or a sensor's output into its signal set."""
        if getattr(type(comp), "outputs", None):
            # a power or multi sensor: the flow into flange_a, its speed, their product
            ref = comp.port_ref("flange_a")
            read = {"flow": self.net.flow[ref], "speed": self.net.vel[ref]}
            read["power"] = read["flow"] * read["speed"]
            for pname, what in comp.outputs.items():
                self.net.signal[self.topo.set_of[comp.port_ref(pname)]] = ca.SX(read[what])
            return
        s = self.topo.set_of[comp.port_ref("y")]
        b = self.bound[comp.name]
        if comp.role == "block":
            value = b.evaluate(self._inputs(comp), self.block_x.get(comp.name, []), self.t,
                               _Mechanics(self))
        elif comp.role == "electrical":
            value = self.circuit.output(comp)
        elif comp.quantity == "flow":
            value = self.net.flow[comp.port_ref("flange_a")]
        else:
            ref = comp.port_ref("flange")
            if comp.quantity == "acceleration" and self._massless_at(ref):
                raise ModelError(acceleration_unavailable(self.model.place(comp), ref),
                                 **self.model.fields(comp, port="flange"))
            value = {"position": self.net.pos, "speed": self.net.vel,
                     "acceleration": self.net.acc}[comp.quantity][ref]
        self.net.signal[s] = ca.SX(value)

    def _algebraic_loop(self, names):
        """Blocks whose outputs depend on each other at the same instant: with their outputs
        z as unknowns, z = f(z) is solved symbolically when it is linear and regular (gains
        and sums in a ring); otherwise it is refused."""
        comps = [self.model.components[n] for n in names]
        sets = [self.topo.set_of[c.port_ref("y")] for c in comps]
        z = ca.SX.sym("loop", len(comps))
        for i, s in enumerate(sets):
            self.net.signal[s] = z[i]
        for c in comps:
            self._output(c)
        residual = z - ca.vertcat(*[self.net.signal[s] for s in sets])
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
                self.net.alg_z.append(z[i])
                self.net.alg_res.append(residual[i])
                self.net.alg_names.append(f"{c.name}.y")
                self.net.alg_units.append("")
                self.net.signal[s] = z[i]
            self.net.loops_kept.append(names)
            return
        det = ca.Function("det", [self.p], [ca.det(jac)])(self.p_values)
        if ca.sprank(jac) < len(comps) or abs(float(det)) < 1e-12:
            raise ModelError(f"{what}: its outputs are not determined (the loop gain is 1, "
                             f"det = {float(det):g}); break it with a state (an Integrator, a "
                             f"FirstOrder or a filtered Derivative)")
        solved = -ca.solve(jac, ca.substitute(residual, z, ca.SX.zeros(len(comps))))
        self.net.loops_solved.append(names)
        for i, s in enumerate(sets):
            self.net.signal[s] = solved[i]

    def _massless_at(self, ref):
        group = self.group_of.get(self.topo.set_of[ref])
        return group is not None and group.kind == "massless"

    def _block_rates(self):
        for name, xs in self.block_x.items():
            comp = self.model.components[name]
            rates = self.bound[name].rates(self._inputs(comp), xs, self.t)
            for x, r in zip(xs, rates):
                self.net.rate[self._at(x)] = r

    def _order(self):
        """Blocks, sensors and the mechanics in an order where everything an output needs at
        the same instant comes first; algebraic loops refused."""
        g = nx.DiGraph()
        g.add_node(MECHANICS)
        for comp in self.model.components.values():
            if comp.role == "block" or _measures(comp):
                g.add_node(comp.name)
        for comp in self.model.components.values():
            if _measures(comp) in ("acceleration", "flow"):
                g.add_edge(MECHANICS, comp.name)
            if comp.role == "sensor":
                group = self.group_of.get(self.topo.set_of[comp.port_ref("flange")])
                if group is not None and group.kind == "massless":
                    g.add_edge(MECHANICS, comp.name)   # flows set its position at once
            for pname, port in comp.ports.items():
                if port.domain != "signal_in":
                    continue
                s = self.topo.set_of[comp.port_ref(pname)]
                if s not in self.topo.signal_source:
                    continue
                source = self.topo.signal_source[s].component.name
                if comp.role == "block" and comp.feedthrough:
                    g.add_edge(source, comp.name)
                elif comp.role in ("source", "prescribed"):
                    g.add_edge(source, MECHANICS)
        for read in self.reads.values():
            # a law reading signals is part of the mechanics (a source's flow, or a force
            # on frames: its generalized force), needing the signals first
            for _, s in read.values():
                g.add_edge(self.topo.signal_source[s].component.name, MECHANICS)
        self._circuit_edges(g)
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

    def _circuit_edges(self, g):
        """A signal into an electrical source reaches, at the same instant, the sensors
        and EMF torques whose circuit it drives (an algebraic loop when fed back)."""
        feeder = {name: self.topo.signal_source[s].component.name for name, s in (
            (name, self.circuit.inputs[ph]) for name, ph in self.circuit.sources.items())}
        if not feeder:
            return
        for comp in self.circuit.comps:
            if getattr(type(comp), "quantity", None):
                reads = self.circuit.output(comp)
                for name in self.circuit.placeholders_in(reads):
                    g.add_edge(feeder[name], comp.name)
            if getattr(type(comp), "converter", False):
                for name in self.circuit.placeholders_in(self.circuit.converter_current(comp)):
                    g.add_edge(feeder[name], MECHANICS)

    # -- the mechanics ------------------------------------------------------------------
    def _mechanics(self):
        self._flows("source")
        for m in self.motions:
            u = self._inputs(m.source).get("u")
            m.reference = ca.SX(m.comp.reference if u is None else u)
            if m.group.kind == "joint":
                # the torque (force) the source applies: the generalized force the joint
                # needs, found by the formulation, through the group's ratio at the source
                drive = ca.SX.sym(f"drive_{m.comp.name}")
                self._drive(m, drive / m.k)
                m.drive = drive
        for cluster in self.riding:             # trains riding on a housing, solved together
            supports.solve(self, cluster)
        # motions of free flanges first: the flow into their source is then known, and so
        # the reaction on their support, before the fixed groups take it; a train on a
        # housing before the housing, which takes its reaction
        for group in supports.order(self):
            self._balance(group)
            if group.kind == "prescribed":
                m = next(m for m in self.motions if m.group is group)
                self._drive(m, -self.net.flow[group.definer])

    def _drive(self, motion, torque):
        """The source applies ``torque`` to its flange, and its reaction to its support."""
        self.net.flow[motion.source.port_ref("flange")] = -torque
        self.net.flow[motion.source.port_ref("support")] = torque

    def _flows(self, role):
        net = self.net
        flow = net.flow
        for comp in self.model.components.values():
            if comp.role != role:
                continue
            b = self.bound[comp.name]
            # a source's signal input, when wired, replaces its torque or force parameter
            u = self._inputs(comp).get("u") if comp.role == "source" else None
            if getattr(type(comp), "converter", False):      # an EMF: driven by its current
                u = self.circuit.converter_current(comp)
            refs = {pn: comp.port_ref(pn) for pn in comp.ports if comp.ports[pn].domain
                    in ("rotational", "translational")}
            if getattr(type(comp), "hybrid", False):
                self._hybrid(comp, b, refs)
            out = b.flows({pn: net.pos.get(r, 0) for pn, r in refs.items()},
                          {pn: net.vel.get(r, 0) for pn, r in refs.items()}, self.t, u)
            for pn, f in out.items():
                flow[refs[pn]] = f

    def _hybrid(self, comp, b, refs):
        """An element with modes (``components/friction.py``): its mode is a state that only
        events change (rate 0), and F, what it holds with while held, a symbol solved with
        the dynamics once they are known (``modes.py``)."""
        for pn, ref in refs.items():
            group = self.group_of.get(self.topo.set_of[ref])
            if group is not None and group.kind == "massless":
                raise ModelError(f"{self.model.place(comp)}: {ref.path} is on a massless "
                                 f"flange, which has no acceleration for {comp.name} to hold "
                                 f"or stop: give it an inertia or a mass",
                                 **self.model.fields(comp, port=pn))
        b._mode = self._state(f"{comp.name}.mode", "", 0, ca.SX(0))
        b._F = ca.SX.sym(f"F_{comp.name}")
        u = self.topo.set_of[comp.port_ref("u")] if "u" in comp.ports else None
        self.net.hybrid.append(Hybrid(comp, b, b._mode, b._F, refs[b.side_a] if b.side_a in
                                      refs else None, refs[b.side_b], u))

    def _applied(self, s, roles=("compliant", "source"), exclude=()):
        """Flows into the non-rigid elements at a connection set (compliant, sources; with
        ``prescribed`` in ``roles``, motion sources too), but those of ``exclude``."""
        return sum((self.net.flow.get(r, 0) for r in self.topo.sets[s]
                    if r.component.role in roles and r.component.name not in exclude),
                   ca.SX(0))

    def _generalized(self, group, roles=("compliant", "source"), exclude=()):
        return sum((-self.kt[s] * self._applied(s, roles, exclude) for s, _, _ in group.sets),
                   ca.SX(0))

    def group_inertia(self, group):
        """sum(J k kt) over the group's inertias: its inertia on its coordinate."""
        at = self.topo.set_of
        return sum((self.bound[e.name].inertia() * self.k[at[e.port_ref("flange_a")]] *
                    self.kt[at[e.port_ref("flange_a")]] for e in group.rigid
                    if e.has_inertia), ca.SX(0))

    def _inertia(self, group):
        """The group's inertia; on a joint, its armature, and the passive generalized force
        (springs and dampers) that an InverseDynamics block compensates."""
        inertia = self.group_inertia(group)
        self.inertia[group.index] = inertia
        if group.kind == "joint":
            u = self._speed(group)
            self.net.armature[u] += inertia
            self._passive[u] += self._generalized(group, ("compliant",))
        elif group.kind == "assembly":
            self._passive += self._virtual(group, self._generalized(group, ("compliant",)))

    def _virtual(self, group, gen):
        """The generalized forces on the speeds of a force ``gen`` on an assembly's axis:
        (d(speed of the axis)/du)^T gen, by virtual work."""
        return ca.jtimes(self.coord[group.index][1], self.u, ca.SX(gen), True)

    def _speed(self, group):
        joint = group.definer.component
        return self.uindex[joint.name][joint.coordinate_ports[group.definer.name]]

    def _balance(self, group):
        """The generalized force on the group's coordinate, what it does with it, and the
        flow through every rigid element and into the defining port."""
        gen = self._generalized(group)
        theta, w, a = self.coord[group.index]
        if group.kind == "joint":
            self.net.Q[self._speed(group)] += gen
        elif group.kind == "assembly":
            self.net.Q += self._virtual(group, gen)
        elif group.kind == "free" and group.index in self.circuit.coupled:
            # a rotor a circuit's constraint holds: its acceleration came with the circuit's
            # solution, in the generalized force of all but the circuit's EMFs
            coupled = self.circuit.coupled[group.index]
            self.pending[coupled.rest] = self._generalized(group, exclude=coupled.emfs)
            self.pending[a] = coupled.acc
        elif group.kind == "free" and not any(group in c for c in self.riding):
            self.pending[a] = gen / self.inertia[group.index]
        elif group.kind == "massless":
            self._massless(group, gen)
        self._rigid_flows(group)

    def _massless(self, group, gen):
        theta, w, a = self.coord[group.index]
        self.net.no_acceleration.update(s for s, _, _ in group.sets)
        where = ", ".join(r.path for s, _, _ in group.sets for r in self.topo.sets[s])
        dw = ca.jacobian(gen, w)
        if ca.depends_on(gen, w):
            if ca.depends_on(dw, w) or ca.depends_on(dw, theta):
                raise ModelError(f"connection set {{{where}}}: its balance is not linear "
                                 f"in its speed, which kinetwork solves only when it is")
            speed = -ca.substitute(gen, w, ca.SX(0)) / dw
            x = self._state(f"{group.ports[0].path}.{_pos(group)}", _units(group)[0], 0, speed)
            self.pending[theta] = x
            self.pending[w] = speed
            self.pending[a] = ca.SX.nan()
            return
        dp = ca.jacobian(gen, theta)
        if not ca.depends_on(gen, theta) or ca.depends_on(dp, theta):
            raise ModelError(f"connection set {{{where}}} has no defined position: nothing "
                             f"on it depends on where it is (or not linearly)")
        position = -ca.substitute(gen, theta, ca.SX(0)) / dp
        self.pending[theta] = position
        self.pending[w] = ca.jtimes(position, self.q, self.u) + ca.jacobian(position, self.t)
        self.pending[a] = ca.SX.nan()

    def _rigid_flows(self, group):
        """Kirchhoff at every set of the group, leaves first: the flow into a rigid element at
        its far side balances what is beyond; its law gives the near side."""
        flow = self.net.flow
        beyond = {s: self._applied(s, ("compliant", "source", "prescribed"))
                  + supports.reactions(self, s) for s, _, _ in group.sets}
        for s, parent, element in reversed(group.sets):
            if parent is None:
                if group.definer is not None:
                    flow[group.definer] = -beyond[s]
                continue
            far = element.port_ref("flange_a" if self.topo.set_of[element.port_ref(
                "flange_a")] == s else "flange_b")
            near = element.port_ref("flange_b" if far.name == "flange_a" else "flange_a")
            flow[far] = -beyond[s]
            b = self.bound[element.name]
            if element.has_inertia:
                flow[near] = b.inertia() * self.kin[s][2] - flow[far]
            elif far.name == "flange_a":          # torque_b = -ratio * torque_a
                flow[near] = -b.position_ratio() * self.losses.get(element.name, 1) * flow[far]
            else:
                flow[near] = -flow[far] / (b.position_ratio() * self.losses.get(element.name, 1))
            if "support" in element.ports:        # MSL: support.tau = -flange_a.tau - flange_b.tau
                flow[element.port_ref("support")] = -(flow[far] + flow[near])
            beyond[parent] = beyond[parent] + flow[near]

    def _finish(self):
        net = self.net
        for placeholder, s in self.circuit.inputs.items():
            self.pending[placeholder] = net.signal[s]
        for name, read in self.reads.items():
            if self.model.components[name].role == "source":
                for placeholder, s in read.values():
                    self.pending[placeholder] = net.signal[s]
        self._input_rates()
        for joint_ports in self._axis_ports():
            ref, u = joint_ports
            net.axis_flow[u] += net.flow.get(ref, 0)
        self._motion_laws()
        net.claims = starts.claims(self)
        if not self.pending:
            starts.resolve(net, self.t)
            return
        sub = self._substitution()
        for d in (net.pos, net.vel, net.acc, net.flow, net.signal):
            for key in d:
                d[key] = sub(d[key])
        net.Q, net.armature, net.axis_flow = sub(net.Q), sub(net.armature), sub(net.axis_flow)
        net.rate = [sub(r) for r in net.rate]
        net.start = [sub(r) for r in net.start]
        net.alg_res = [sub(r) for r in net.alg_res]
        for rec in net.prescribed.values():
            rec.pos, rec.vel, rec.acc = sub(rec.pos), sub(rec.vel), sub(rec.acc)
        starts.resolve(net, self.t)

    def _input_rates(self):
        """The time derivative of each signal whose circuit constraint was differentiated (a
        voltage source's u across a capacitor): through t and the rates of the states it
        reads (signal blocks); one that follows the mechanism's motion is refused."""
        if not self.circuit.input_rates:
            return
        sub = self._substitution()
        moving = ca.vertcat(self.q, self.u, self.udot)
        for du, s in self.circuit.input_rates.items():
            e = sub(self.net.signal[s])
            if ca.depends_on(e, moving):
                names = ", ".join(self.circuit.placeholders_in(du))
                raise ModelError(f"{names}: a constraint of the circuit differentiates its "
                                 f"input u, whose signal follows the motion of the mechanism; "
                                 f"put a resistor or an inductor where the source meets the "
                                 f"capacitors (or the inductors)")
            states = [x for x in self.net.x if ca.depends_on(e, x)]
            rate = ca.jacobian(e, self.t)
            if states:
                rate += ca.jtimes(e, ca.vertcat(*states),
                                  sub(ca.vertcat(*[self.net.rate[self._at(x)] for x in states])))
            self.pending[du] = rate

    def _substitution(self):
        """The function putting every placeholder's expression in its place."""
        if not self.pending:
            return lambda e: ca.SX(e)
        keys = list(self.pending)
        # dense: a structural zero (the exact acceleration of a constant speed) must not
        # make the sparsities of the placeholders and their values differ
        old = ca.vertcat(*keys)
        new = ca.densify(ca.vertcat(*[ca.SX(self.pending[k]) for k in keys]))
        # placeholders may refer to each other (a free rotor's acceleration to a massless
        # node's position): substitute until none is left
        for _ in range(len(keys) + 1):
            if not ca.depends_on(new, old):
                break
            new = ca.densify(ca.substitute(new, old, new))
        return lambda e: ca.substitute(ca.SX(e), old, new)

    def _motion_laws(self):
        """Each motion's position, speed and acceleration from its reference, once every
        signal and every state's rate is known (an exact derivative needs the rates of the
        blocks the reference comes from); in the order they were placed, so a motion read by
        a sensor feeding another is known first."""
        drives = [m.drive for m in self.motions if m.drive is not None]
        moving = ca.vertcat(self.q, self.u, self.udot, *drives,
                            *[c for m in self.motions if m.drive is None for c in m.coord])
        for m in self.motions:
            sub = self._substitution()
            where = self.model.place(m.source)

            def der(e, sub=sub, where=where, m=m):
                e = sub(e)
                if ca.depends_on(e, moving):
                    raise ModelError(
                        f"{where}: exact=True differentiates the reference exactly, so it "
                        f"must follow time only (an expression in t, or signal blocks fed "
                        f"by time); the reference of {m.comp.name} depends on the motion of "
                        f"the model: set exact=False to follow it through its filter "
                        f"(f_crit)", **self.model.fields(m.source, "exact"))
                states = [x for x in self.net.x if ca.depends_on(e, x)]
                out = ca.jacobian(e, self.t)
                if states:
                    rates = sub(ca.vertcat(*[self.net.rate[self._at(x)] for x in states]))
                    out += ca.jtimes(e, ca.vertcat(*states), rates)
                return out
            pos, vel, acc, rates = m.comp.motion(m.reference, m.x, der)
            if ca.depends_on(sub(acc), ca.vertcat(self.udot, *drives)):
                raise ModelError(f"{where}: the acceleration {m.comp.name} prescribes depends "
                                 f"on accelerations of the model at the same instant (an "
                                 f"algebraic loop through the mechanics): break it with a "
                                 f"state (exact=False, a FirstOrder)",
                                 **self.model.fields(m.source))
            r0 = ca.substitute(sub(m.reference), self.t, ca.SX(0))
            for x, rate, start in zip(m.x, rates, m.comp.initial(r0)):
                self.net.rate[self._at(x)] = rate
                self.net.start[self._at(x)] = start
            if m.group.kind == "joint":
                joint = m.group.definer.component
                j = joint.coordinate_ports[m.group.definer.name]
                self.net.prescribed[self.uindex[joint.name][j]] = Prescribed(
                    self.qindex[joint.name][j], (pos - m.offset) / m.k, vel / m.k, acc / m.k,
                    m.drive, m.comp.name, joint.name)
            else:
                self.pending.update(zip(m.coord, (pos, vel, acc)))

    def _axis_ports(self):
        for joint in self.topo.joints:
            for pname, j in joint.coordinate_ports.items():
                yield joint.port_ref(pname), self.uindex[joint.name][j]


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
        return b.inverse(ca.vertcat(*[ca.SX(v) for v in a]), b.net.armature, b._passive)

    def refuse(self, comp, key, message):
        return ModelError(f"{self._b.model.place(comp, key)}: {message}")


def _measures(comp):
    """What a sensor measures ("position", "speed", "acceleration", "flow"), or None."""
    return getattr(type(comp), "quantity", None)


def _pos(group):
    return "phi" if group.domain == "rotational" else "s"


def _vel(group):
    return "w" if group.domain == "rotational" else "v"


def _units(group):
    return ("rad", "rad/s") if group.domain == "rotational" else ("m", "m/s")
