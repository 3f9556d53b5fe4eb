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

The build runs in steps, each in its own module, all working on the one ``_Builder``:
this module sets up the groups' ratios and coordinates and puts the placeholders in their
place at the end; ``blockflow`` orders and evaluates the signal blocks and sensors;
``balance`` writes the flows and the balance of every group (the mechanics); ``derivatives``
gives the exact time derivatives that motion sources and circuits ask of signals; ``records``
holds what the steps hand each other.
"""

import casadi as ca

from ..errors import ModelError
from . import balance, blockflow, derivatives, starts, supports
from .circuit import Circuit
from .records import (Hybrid, Motion, Network, Prescribed, position_label, speed_label,
                      state_units)

__all__ = ["Hybrid", "Network", "Prescribed", "build"]


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


class _Builder:
    """One build of a Network: what every step (here, ``blockflow``, ``balance``,
    ``derivatives``, ``supports``, ``starts``, ``circuit``) reads and writes."""

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
        self.motions = []            # Motion, in group order

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
        blockflow.block_states(self)
        # circuits next: their currents are expressions of states and speeds, so EMF
        # torques are known before any balance (``circuit.py``)
        self.circuit = Circuit(self).build()
        self.circuit.fill(self.net)
        self.net.circuit = self.circuit.summary
        self.net.demoted.update(self.circuit.demoted)
        balance.flows(self, "compliant")               # springs and dampers need no signal
        self.passive = ca.SX.zeros(self.u.shape[0])
        for group in self.topo.oned:
            balance.add_inertia(self, group)
        for node in blockflow.order(self):
            if node == blockflow.MECHANICS:
                balance.mechanics(self)
            elif isinstance(node, list):
                blockflow.algebraic_loop(self, node)
            else:
                blockflow.output(self, self.model.components[node])
        blockflow.block_rates(self)
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
            mode = self.add_state(f"{element.name}.mode", "", 1, ca.SX(0))
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
        units = state_units(group)
        labels = list(zip((position_label(group), speed_label(group)), units))[:comp.n_states]
        x = [self.add_state(f"{comp.name}.{label}", unit, 0, 0) for label, unit in labels]
        at = self.topo.set_of[flange]
        self.motions.append(Motion(comp, flange.component, group, self.k[at], x, coord,
                                    offset=self.c[at]))

    def _free(self, group):
        """A coordinate and a speed, the position and speed of the group's first inertia
        (the group's root), named after it; their starts follow from the inertias' own
        (``starts.free``, once every position is known)."""
        first = next(e for e in group.rigid if e.has_inertia)
        pos_unit, vel_unit = state_units(group)
        at = self.topo.set_of[first.port_ref("flange_a")]
        # the coordinate is the first inertia's centre (MSL's Mass.s, between its flanges
        # L apart), in the units of its flanges divided by their ratio
        centre = self.c[at] + self.bound[first.name].length() / 2
        for s, _, _ in group.sets:
            self.c[s] = self.c[s] - self.k[s] * centre / self.k[at]
        a = ca.SX.sym(f"g{group.index}_acc")
        w = self.add_state(f"{first.name}.{speed_label(group)}", vel_unit, 0, a)
        theta = self.add_state(f"{first.name}.{position_label(group)}", pos_unit, 0, w,
                            at=len(self.net.x) - 1)
        self.coord[group.index] = (theta, w, a)

    def add_state(self, name, unit, start, rate, at=None):
        """A new state of the network (its symbol), at position ``at`` (default: last)."""
        x = ca.SX.sym(name.replace(".", "_"))
        at = len(self.net.x) if at is None else at
        self.net.x.insert(at, x)
        self.net.rate.insert(at, rate)
        self.net.start.insert(at, start)
        self.net.names.insert(at, name)
        self.net.units.insert(at, unit)
        return x

    def applied(self, s, roles=("compliant", "source"), exclude=()):
        """Flows into the non-rigid elements at a connection set (compliant, sources; with
        ``prescribed`` in ``roles``, motion sources too), but those of ``exclude``."""
        return sum((self.net.flow.get(r, 0) for r in self.topo.sets[s]
                    if r.component.role in roles and r.component.name not in exclude),
                   ca.SX(0))

    def index_of(self, x):
        """Position of the state symbol ``x`` (by identity: SX == builds an expression)."""
        return next(i for i, v in enumerate(self.net.x) if v is x)

    def _finish(self):
        net = self.net
        for placeholder, s in self.circuit.inputs.items():
            self.pending[placeholder] = net.signal[s]
        for name, read in self.reads.items():
            if self.model.components[name].role == "source":
                for placeholder, s in read.values():
                    self.pending[placeholder] = net.signal[s]
        derivatives.input_rates(self)
        for joint_ports in self._axis_ports():
            ref, u = joint_ports
            net.axis_flow[u] += net.flow.get(ref, 0)
        derivatives.motion_laws(self)
        net.claims = starts.claims(self)
        if not self.pending:
            starts.resolve(net, self.t)
            return
        sub = self.substitution()
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

    def substitution(self):
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

    def _axis_ports(self):
        for joint in self.topo.joints:
            for pname, j in joint.coordinate_ports.items():
                yield joint.port_ref(pname), self.uindex[joint.name][j]
