"""From a validated model to CasADi SX equations: no integration, no I/O.

States are the coordinates of the spanning tree's joints and their speeds (minimal
coordinates). Rigid parts fold into the body of the joint before them; the 1-D network gives
each joint coordinate its generalized force; probes become output expressions.
"""

from dataclasses import dataclass, field

import casadi as ca

from ..components.probe import QUANTITIES
from ..expr import Expression, casadi_functions
from ..spatial import vee
from .newton_euler import Body, aba, crba, rnea, spatial_inertia


@dataclass
class Assembly:
    """Symbols and expressions of a model (all CasADi SX)."""
    t: ca.SX
    q: ca.SX
    qd: ca.SX
    p: ca.SX
    param_names: list
    coordinate_names: list
    coordinate_units: list
    bodies: list
    x0: ca.SX                  # initial state, in the parameters
    Q: ca.SX                   # generalized forces of the 1-D network (t, q, qd, p)
    qdd: ca.SX                 # forward dynamics (t, q, qd, p)
    gravity: ca.SX
    signals: list = field(default_factory=list)   # (name, unit, SX expression in t,q,qd,qdd,p)
    qdd_sym: ca.SX = None      # placeholder for qdd inside signal expressions

    def mass_matrix(self):
        return crba(self.bodies, self.q.shape[0])

    def terms(self):
        """(M, V, G) with M qdd + V + G = 0: V holds Coriolis, centripetal and -Q."""
        n = self.q.shape[0]
        a_grav = ca.vertcat(ca.SX.zeros(3), -self.gravity)
        zero = ca.SX.zeros(n)
        C = rnea(self.bodies, self.qd, zero, ca.SX.zeros(6))
        G = rnea(self.bodies, zero, zero, a_grav)
        return self.mass_matrix(), C - self.Q, G


def assemble(model, topo):
    """Build the Assembly of a validated model (``topo`` from ``model.validate()``)."""
    names = list(model.parameters)
    p = ca.SX.sym("p", len(names))
    t = ca.SX.sym("t")
    env = {name: p[i] for i, name in enumerate(names)}
    env_t = {**env, "t": t}
    funcs = casadi_functions()
    bound = {name: comp.bound({k: _symbolic(v, env_t, funcs) if comp.params[k].kind == "real"
                               else v for k, v in comp._values.items()})
             for name, comp in model.components.items()}

    coord_names, coord_units, index = [], [], {}
    for joint in topo.joints:
        index[joint.name] = list(range(len(coord_names), len(coord_names) + joint.dof))
        suffix = [""] if joint.dof == 1 else [f"[{i}]" for i in range(joint.dof)]
        coord_names += [f"{joint.name}.q{s}" for s in suffix]
        coord_units += [joint.units[0]] * joint.dof
    n = len(coord_names)
    q = ca.vertcat(*[ca.SX.sym(c.replace(".", "_")) for c in coord_names]) if n else ca.SX(0, 1)
    qd = ca.vertcat(*[ca.SX.sym(c.replace(".", "_") + "d") for c in coord_names]) \
        if n else ca.SX(0, 1)
    qdd_sym = ca.SX.sym("qdd", n)

    bodies, place = _bodies(topo, bound, q, qd, index)
    pos, vel, acc, flow = _network(model, topo, bound, q, qd, qdd_sym, index, t)
    Q = ca.SX.zeros(n)
    for joint in topo.joints:
        for pname, j in joint.coordinate_ports.items():
            Q[index[joint.name][j]] = flow.get(joint.port_ref(pname), 0)

    world = bound[topo.world.name]
    gravity = ca.vertcat(*world.gravity)
    qdd = aba(bodies, qd, Q, ca.vertcat(ca.SX.zeros(3), -gravity)) if n else ca.SX(0, 1)
    x0 = ca.vertcat(*[_initial(bound[j.name].q0) for j in topo.joints],
                    *[_initial(bound[j.name].qd0) for j in topo.joints])
    asm = Assembly(t, q, qd, p, names, coord_names, coord_units, bodies, x0, Q, qdd, gravity,
                   qdd_sym=qdd_sym)
    _probes(asm, topo, place, pos, vel, acc, flow)
    return asm


def _bodies(topo, bound, q, qd, index):
    """Moving bodies along the tree; rigid parts fold into the body before them.

    Returns the bodies and, for each frame set, (body index, R, p): where the set sits in
    its body (-1 is the world).
    """
    place = {topo.root: (-1, ca.SX.eye(3), ca.SX.zeros(3))}
    bodies = []
    for edge in topo.tree:
        comp = bound[edge.component.name]
        qj = q[index[comp.name]] if comp.dof else ca.SX(0, 1)
        Re, re = comp.transform(qj)
        if edge.reversed:
            Re, re = Re.T, -Re.T @ re
        k, Rf, pf = place[edge.parent]
        R, pos = Rf @ Re, pf + Rf @ re
        if comp.dof == 0:
            place[edge.child] = (k, R, pos)
            continue
        # motion subspace in the child frame, from derivatives of the joint's transform
        S = ca.horzcat(*[
            ca.vertcat(vee(Re.T @ ca.reshape(ca.jacobian(ca.vec(Re), qj[j]), 3, 3)),
                       Re.T @ ca.jacobian(re, qj[j]))
            for j in range(comp.dof)])
        if comp.constant_subspace:       # screw joints: exact constants, no S-dot term
            S, cJ = ca.substitute(S, qj, ca.SX.zeros(comp.dof)), ca.SX.zeros(6)
        else:
            qdj = qd[index[comp.name]]
            cJ = ca.jtimes(S @ qdj, qj, qdj)
        bodies.append(Body(comp.name, k, R, pos, S, cJ, ca.SX.zeros(6, 6), index[comp.name]))
        place[edge.child] = (len(bodies) - 1, ca.SX.eye(3), ca.SX.zeros(3))
    for body, frame_set in topo.bodies:
        k, Rs, ps = place[frame_set]
        if k < 0:
            continue            # welded to the ground: no motion, no state
        m, c, Ic = bound[body.name].mass_properties()
        bodies[k].inertia += spatial_inertia(m, ps + Rs @ c, Rs @ Ic @ Rs.T)
    return bodies, place


def _network(model, topo, bound, q, qd, qdd_sym, index, t):
    """1-D network: position, speed, acceleration of every port, and the flow into it."""
    pos, vel, acc = {}, {}, {}
    for s in topo.oned:
        triple = (0, 0, 0)                     # an optional flange wired to nothing: world
        if s.definer is not None:
            comp = bound[s.definer.component.name]
            if s.definer.name in comp.coordinate_ports:
                i = index[comp.name][comp.coordinate_ports[s.definer.name]]
                triple = (q[i], qd[i], qdd_sym[i])
            elif comp.role == "fixed":
                triple = (comp.position(), 0, 0)
        for ref in topo.sets[s.index]:
            pos[ref], vel[ref], acc[ref] = triple
    flow = {}
    for comp in model.components.values():
        if comp.role in ("compliant", "source"):
            refs = {pn: comp.port_ref(pn) for pn in comp.ports}
            out = bound[comp.name].flows({pn: pos.get(r, 0) for pn, r in refs.items()},
                                         {pn: vel.get(r, 0) for pn, r in refs.items()}, t)
            for pn, f in out.items():
                flow[refs[pn]] = f
    for s in topo.oned:        # the defining port takes what the rest sends (sum is zero)
        if s.definer is not None:
            flow[s.definer] = -sum((flow.get(r, 0) for r in s.ports if r != s.definer),
                                   ca.SX(0))
    return pos, vel, acc, flow


def _symbolic(value, env, funcs):
    """A normalized parameter value as CasADi SX (lists stay lists of SX)."""
    if isinstance(value, list):
        return [_symbolic(v, env, funcs) for v in value]
    if isinstance(value, str):
        return ca.SX(Expression(value).evaluate(env, funcs))
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return ca.SX(value)
    return value


def _initial(value):
    return ca.SX.zeros(1) if value is None else value


def _probes(asm, topo, place, pos, vel, acc, flow):
    for probe, target in topo.probes:
        units = QUANTITIES[target.domain]
        asked = probe.quantities if probe.quantities is not None else list(units)
        if target.domain == "frame":
            values = _frame_kinematics(asm, place[topo.set_of[target]], asked)
        else:
            potential = dict(zip(list(units)[:3], (pos[target], vel[target], acc[target])))
            values = {**potential, list(units)[3]: flow.get(target, 0)}
        for quantity in asked:
            asm.signals.append((f"{probe.name}.{quantity}", units[quantity],
                                ca.SX(values[quantity])))


def _frame_kinematics(asm, where, asked):
    """World-frame kinematics of a frame, differentiated exactly by CasADi."""
    k, Rs, ps = where
    R, pos = Rs, ps
    while k >= 0:
        b = asm.bodies[k]
        R, pos = b.R @ R, b.p + b.R @ pos
        k = b.parent
    q, qd, qdd = asm.q, asm.qd, asm.qdd_sym

    def rate(expr):          # time derivative of an expression in (q, qd)
        flat = ca.vec(expr)
        return ca.reshape(ca.jtimes(flat, q, qd) + ca.jtimes(flat, qd, qdd), *expr.shape)

    out = {"position": pos, "orientation": ca.reshape(R.T, 9, 1)}
    if {"velocity", "acceleration"} & set(asked):
        out["velocity"] = rate(pos)
        out["acceleration"] = rate(out["velocity"])
    if {"angular_velocity", "angular_acceleration"} & set(asked):
        out["angular_velocity"] = vee(rate(R) @ R.T)
        out["angular_acceleration"] = rate(out["angular_velocity"])
    return out
