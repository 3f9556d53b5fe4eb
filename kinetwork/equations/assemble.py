"""From a validated model to CasADi SX equations: no integration, no I/O.

The coordinates are those of the spanning tree's joints and of the regular joints that cut
its loops, with their speeds. Rigid parts fold into the body of the joint before them; the
1-D network and the frame forces give each speed its generalized force; each cut joint gives
its loop-closure residual (reduced to independent coordinates in ``loops.py``); probes
become output expressions.
"""

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..errors import ModelError
from ..expr import casadi_functions, parse
from ..spatial import vee
from . import applied, junctions, loopstart, network, placed
from . import starts as inertia_starts
from .newton_euler import Body, aba, crba, motion_subspace, rnea, spatial_inertia
from .signals import probe_signals


@dataclass
class Assembly:
    """Symbols and expressions of a model (all CasADi SX).

    ``q`` are the coordinates of every joint with coordinates (the tree's and those of
    regular cut joints) and ``u`` their speeds; a quaternion joint has more coordinates than
    speeds, so d(q)/dt is ``qdot`` (= u for angles and distances). ``udot`` is the symbol of
    the speeds' rates in expressions that need them (probe signals, sensors, inverse
    dynamics): the formulation of ``loops.py`` says what it equals, ``udot_tree`` for a model
    without loops. ``lam`` likewise stands for the loops' multipliers.
    """
    t: ca.SX
    q: ca.SX
    u: ca.SX
    p: ca.SX
    param_names: list
    coordinate_names: list
    coordinate_units: list
    speed_names: list
    speed_units: list
    bodies: list
    q_start: ca.SX             # initial coordinates (q0, or q0_guess where q0 is not given)
    u_start: ca.SX             # initial speeds
    given: list                # per coordinate: q0 was given (held in a loop's closure)
    u_given: list              # per speed: qd0 was given
    regular: list              # per coordinate: an angle or distance with qdot = its speed
    speed_of: dict             # regular coordinate index -> speed index
    Q: ca.SX                   # generalized forces of 1-D network and frame forces (t,q,u,p)
    udot_tree: ca.SX           # forward dynamics of the tree (t, q, u, p)
    qdot: ca.SX                # d(q)/dt in (q, u)
    gravity: ca.SX
    udot: ca.SX                # symbol: the speeds' rates, bound by the formulation
    place: dict = field(default_factory=dict)     # frame set -> (body, R, p) in the body
    cuts: list = field(default_factory=list)      # (Cut, residual SX in q)
    signals: list = field(default_factory=list)   # Signal descriptors, in (t, q, u, udot, lam, p)
    lam: ca.SX = None          # symbol: the loops' multipliers (one per closure row), then
    #                            the drives of the prescribed joints (one per prescribed speed)
    armature: ca.SX = None     # 1-D inertia geared rigidly to each speed
    net: object = None         # the 1-D network and signal blocks (network.Network)
    qindex: dict = None        # joint name -> indices of its coordinates in q
    uindex: dict = None        # joint name -> indices of its speeds in u
    Q_drive: ca.SX = None      # the part of Q that 1-D flanges apply (drives, springs)
    #: speed index -> network.Prescribed: joint coordinates that motion sources give
    prescribed: dict = field(default_factory=dict)
    _poses: dict = field(default_factory=dict)
    base: tuple = None         # world pose of the body of the last ``relative_poses``
    #: the gravity field, and what the point masses of force elements add (applied.Extra)
    applied: object = None
    #: massless junctions of line forces (junctions.Junctions), None without any
    junctions: object = None
    #: the rows a loop's cut joint's start values add to the start (loopstart.StartRows)
    start_rows: object = None
    #: what assemblies place in closed form (placed.Placed)
    placed: object = None
    #: the speeds' rates by a dense solve with the whole mass matrix: the riders (bodies on
    #: an assembly's frames) carry inertia that the tree alone lacks (a massless crank), where
    #: the articulated-body algorithm would divide by zero
    dense: bool = False

    def mass_matrix(self):
        M = crba(self.bodies, self.u.shape[0], self.armature)
        extra = self.applied.mass_matrix()
        return M if extra is None else M + extra

    def mass_times(self, w):
        """M(q) w, by inverse dynamics with no speed and no gravity: an O(n) expression in
        (q, w), where the mass matrix itself is O(n^2)."""
        zero = ca.SX.zeros(self.u.shape[0])
        Mw = ca.substitute(rnea(self.bodies, zero, w, ca.SX.zeros(6), self.armature),
                           self.u, zero)
        return Mw + self.applied.mass_times(w) if self.applied.masses else Mw

    def solve_mass(self, w):
        """M(q)^-1 w by the articulated-body algorithm (no speed, no gravity): O(n)."""
        if self.dense:
            return ca.solve(self.mass_matrix(), w)
        zero = ca.SX.zeros(self.u.shape[0])
        tree = ca.substitute(aba(self.bodies, zero, w, ca.SX.zeros(6), self.armature),
                             self.u, zero)
        return self.applied.forward(tree, self.armature)

    def start_function(self):
        """Function p -> (q_start, u_start): the initial coordinates and speeds as given."""
        return ca.Function("start", [self.p], [self.q_start, self.u_start])

    def terms(self):
        """(M, V, G) with M qdd + V + G = 0: V holds Coriolis, centripetal and -Q."""
        n = self.u.shape[0]
        a_grav = ca.vertcat(ca.SX.zeros(3), -self.gravity)
        zero = ca.SX.zeros(n)
        C = rnea(self.bodies, self.u, zero, ca.SX.zeros(6))       # udot = 0: no armature
        G = rnea(self.bodies, zero, zero, a_grav)
        # Q holds the gravity the Newton-Euler passes do not take (a point field, point
        # masses): it belongs to G
        Qg = self.applied.Q_gravity
        return self.mass_matrix(), C - self.Q + Qg, G - Qg

    def pose(self, frame_set):
        """World orientation R and position p of a frame set, in the coordinates q."""
        if self.junctions is not None and frame_set in self.junctions.position:
            return ca.SX.eye(3), self.junctions.position[frame_set]
        if frame_set not in self._poses:
            k, R, pos = self.place[frame_set]
            while k >= 0:
                b = self.bodies[k]
                R, pos = b.R @ R, b.p + b.R @ pos
                k = b.parent
            self._poses[frame_set] = (R, pos)
        return self._poses[frame_set]

    def relative_poses(self, set_a, set_b):
        """(Ra, pa, Rb, pb): two frame sets placed in the nearest body both hang from (whose
        world pose is ``base`` after the call)."""
        *poses, self.base = placed.relative_poses(self.bodies, self.place, set_a, set_b)
        return tuple(poses)

    def rate(self, expr, accelerations=True):
        """Time derivative of an expression in (q, u), with u's rate ``udot`` (or, without
        ``accelerations``, for an expression in q alone)."""
        flat = ca.vec(expr)
        out = ca.jtimes(flat, self.q, self.qdot)
        if accelerations:
            out += ca.jtimes(flat, self.u, self.udot)
        J = self.junctions
        if J is not None and ca.depends_on(flat, ca.vertcat(J.y, J.s)):
            # a junction's position and its dampers' rates follow (q, s) implicitly
            out += ca.jtimes(flat, J.y, J.ydot(self.q, self.qdot))
            if J.s.numel():
                out += ca.jtimes(flat, J.s, J.sd)
        return ca.reshape(out, *expr.shape)

    def angular_velocity(self, R, accelerations=True):
        """World angular velocity of a frame of world orientation R(q)."""
        return vee(self.rate(R, accelerations) @ R.T)


def assemble(model, topo, values, branch_start=None):
    """Build the Assembly of a validated model (``topo`` from ``model.validate()``);
    ``values`` are the model parameters' values, at which structural choices that depend on
    numbers (a singular algebraic loop) are checked. Every model parameter stays a symbol.
    ``branch_start`` (the start's coordinates, in p) is where assemblies choose their roots
    (by default, the joints' own starts or guesses)."""
    names = list(model.parameters)
    p = ca.SX.sym("p", len(names))
    t = ca.SX.sym("t")
    env = {name: p[i] for i, name in enumerate(names)}
    env_t = {**env, "t": t}
    funcs = casadi_functions()
    reads = _signal_reads(model, topo)
    # a value that reads signals ("-k*pos.y") holds a placeholder per signal until the
    # network has the signal's expression (``network.py`` substitutes it; frame forces are
    # bound again below)
    env_r = {**env_t, **{n: sym for r in reads.values() for n, (sym, _) in r.items()}}

    def bind(comp, env):
        twin = comp.bound({k: _symbolic(v, env, funcs) if comp.params[k].kind == "real"
                           else v for k, v in comp._values.items()})
        # the names its expressions of other variables may read (a Ground's gravity field)
        object.__setattr__(twin, "_environment", env)
        return twin
    bound = {name: bind(comp, env_r if name in reads else env_t)
             for name, comp in model.components.items()}

    coord_names, coord_units, speed_names, speed_units = [], [], [], []
    qindex, uindex, regular, speed_of = {}, {}, [], {}
    for joint in topo.joints:
        nq = joint.n_coordinates()
        qindex[joint.name] = list(range(len(coord_names), len(coord_names) + nq))
        uindex[joint.name] = list(range(len(speed_names), len(speed_names) + joint.dof))
        if joint.regular:
            speed_of.update(zip(qindex[joint.name], uindex[joint.name]))
        regular += [joint.regular] * nq
        coord_names += [f"{joint.name}.{s}" for s in joint.coordinate_labels()]
        coord_units += list(joint.units)
        speed_names += [f"{joint.name}.{s}" for s in joint.speed_labels()]
        speed_units += [f"{u}/s" if u else "rad/s" for u in joint.units[:joint.dof]] \
            if joint.regular else _speed_units(joint)
    q = _symbols(coord_names, "")
    u = _symbols(speed_names, "d")
    n = len(speed_names)
    udot = ca.SX.sym("udot", n)
    qdot = ca.SX.zeros(len(coord_names))
    for joint in topo.joints:
        qdot[qindex[joint.name]] = bound[joint.name].rate(q[qindex[joint.name]],
                                                          u[uindex[joint.name]])

    bodies, place = _bodies(topo, bound, q, u, qindex, uindex)
    own = _own_starts(topo, bound)
    placing = placed.place_assemblies(topo, bound, bodies, place, q,
                                      ca.vertcat(*own) if branch_start is None else branch_start)
    derived = {ref: _moving(pos, q, u, qdot, udot) for ref, pos in placing.coordinates.items()}
    extra = applied.Extra(topo, bound, bodies, place, q, u, qdot, placing)
    gravity = extra.uniform
    a_grav = ca.vertcat(ca.SX.zeros(3), -gravity)

    def inverse(a, armature, passive):     # M(q) a + C(q, u) u + G(q) - Q_passive
        tree = rnea(bodies, u, a, a_grav, armature) - passive
        return tree + extra.mass_times(a) - extra.Q if n else tree
    net = network.build(model, topo, bound, q, u, udot, qindex, uindex, t, inverse, p,
                        [values[k] for k in names], reads, derived)
    for name in reads:
        if model.components[name].role != "source":       # a force on frames
            bound[name] = bind(model.components[name],
                               {**env_t, **{n: net.signal[s] for n, (_, s) in
                                            reads[name].items()}})
    Q = net.Q

    starts, given, u_start, u_given = list(own), [], [], []
    for joint in topo.joints:
        q0, u0 = bound[joint.name].initial()
        given += [v is not None for v in q0]
        u_start += [0 if v is None else v for v in u0]
        u_given += [v is not None for v in u0]
    # an inertia rigidly on a joint axis gives the joint's start, unless the joint does
    for kind, i, value in net.claims:
        vals, flags = (starts, given) if kind == "q" else (u_start, u_given)
        if not flags[i]:
            vals[i], flags[i] = value, True
    if net.prescribed:
        starts, u_start = _prescribed_starts(model, net, t, q, u, starts, u_start, given,
                                             u_given, p, [values[k] for k in names])
    asm = Assembly(t, q, u, p, names, coord_names, coord_units, speed_names, speed_units,
                   bodies, ca.vertcat(*starts) if starts else ca.SX(0, 1),
                   ca.vertcat(*u_start) if u_start else ca.SX(0, 1), given, u_given, regular,
                   speed_of, Q, None, qdot, gravity, udot, place=place)
    asm.armature, asm.net = net.armature, net
    asm.applied, asm.placed = extra, placing
    asm.junctions = junctions.build(asm, topo, bound)
    asm.Q = Q + _frame_forces(asm, topo, bound, t) + extra.Q
    asm.dense = bool(n and extra.masses and placing.sets) and _tree_singular(
        bodies, n, net.armature, q, p, ca.vertcat(*starts), [values[k] for k in names])
    if asm.dense:
        asm.udot_tree = ca.solve(asm.mass_matrix(), asm.Q - rnea(bodies, u, ca.SX.zeros(n),
                                                                a_grav))
    else:
        asm.udot_tree = extra.forward(aba(bodies, u, asm.Q, a_grav, net.armature),
                                      net.armature) if n else ca.SX(0, 1)
    asm.cuts = [(cut, _closure(asm, cut, bound[cut.component.name], qindex))
                for cut in topo.cuts]
    _place_cut_frames(asm, topo, bound)
    asm.start_rows = loopstart.rows(asm, topo, bound)
    asm.prescribed = dict(sorted(net.prescribed.items()))
    asm.lam = ca.vertcat(ca.SX.sym("lambda", sum(r.shape[0] for _, r in asm.cuts)),
                         *[m.drive for m in asm.prescribed.values()])
    asm.qindex, asm.uindex, asm.Q_drive = qindex, uindex, net.axis_flow
    asm.signals = probe_signals(asm, topo, net, bound, model)
    inertia_starts.check(model, topo, asm, bound, [values[k] for k in names])
    if branch_start is None and placing.branches and _branches_differ(
            placing, q, ca.vertcat(*own), asm.q_start, p, [values[k] for k in names]):
        # an inertia on a joint axis or a motion moves the start: choose the roots there
        return assemble(model, topo, values, asm.q_start)
    return asm


def _own_starts(topo, bound):
    """Each joint's own start coordinates (q0, or its guess where q0 is not given)."""
    out = []
    for joint in topo.joints:
        q0, _ = bound[joint.name].initial()
        guess = bound[joint.name].guesses() if joint.regular else [0] * len(q0)
        out += [g if v is None else v for v, g in zip(q0, guess)]
    return out


def _tree_singular(bodies, n, armature, q, p, q_start, p_values):
    """Whether the tree's own mass matrix (its bodies and armature, without what rides on
    assemblies) is singular at the start, at the parameters' values."""
    f = ca.Function("M_tree", [q, p], [crba(bodies, n, armature)])
    M = np.asarray(f(ca.Function("q0", [p], [q_start])(p_values), p_values), dtype=float)
    scale = max(np.max(np.abs(M)), 1e-300)
    return not np.all(np.isfinite(M)) or np.linalg.eigvalsh((M + M.T) / 2)[0] <= 1e-12 * scale


def _moving(pos, q, u, qdot, udot):
    """(position, speed, acceleration) of an expression in q: its rates, exactly."""
    vel = ca.jtimes(pos, q, qdot)
    return pos, vel, ca.jtimes(vel, q, qdot) + ca.jtimes(vel, u, udot)


def _branches_differ(placing, q, own, start, p, p_values):
    """Whether the assemblies' roots chosen at the joints' own starts differ from those at
    the start (where inertias and motions put it), at the parameters' values."""
    rule = ca.Function("branches", [q, p], [ca.vertcat(*placing.branch_rule.values())])
    at = [ca.Function("at", [p], [where])(p_values) for where in (own, start)]
    return bool(np.any(np.asarray(rule(at[0], p_values)) != np.asarray(rule(at[1], p_values))))


def _prescribed_starts(model, net, t, q, u, starts, u_start, given, u_given, p, p_values):
    """Initial coordinates and speeds with those of prescribed joints from their motions
    (at t = 0), and the network's initial states as expressions in the parameters alone (a
    filter starts on its reference, which may read the mechanism's initial state).

    A joint's own q0 or qd0 that contradicts its motion is refused: the motion decides."""
    held = []                  # (joint, label, what, the joint's value, index in values)
    nq = len(starts)
    for speed, m in net.prescribed.items():
        for flag, i, label, what, value in (
                (given, m.coordinate, "q0", "coordinate", starts[m.coordinate]),
                (u_given, speed, "qd0", "speed", u_start[speed])):
            if flag[i]:
                held.append((m, label, what, value, i + (0 if label == "q0" else nq)))
            flag[i] = True
        starts[m.coordinate], u_start[speed] = m.pos, m.vel
    unknown = ca.vertcat(q, u, *net.x)
    values = ca.substitute(ca.vertcat(*[ca.SX(v) for v in [*starts, *u_start, *net.start]]),
                           t, ca.SX(0))
    for _ in range(unknown.shape[0] + 1):
        if not ca.depends_on(values, unknown):
            break
        values = ca.substitute(values, unknown, values)
    if ca.depends_on(values, unknown) or any(not ca.depends_on(p, v)
                                             for v in ca.symvar(values)):
        names = ", ".join(m.source for m in net.prescribed.values())
        raise ModelError(f"the initial state of the prescribed motion(s) {names} is not "
                         f"determined: their reference at t = 0 depends on itself (or on an "
                         f"algebraic loop); give it in time, or filter a reference that does "
                         f"not read the joint it moves")
    nu = len(u_start)
    numbers = np.asarray(ca.Function("starts", [p], [values])(p_values), dtype=float).ravel()
    problems = []
    for m, label, what, value, k in held:
        mine = float(ca.Function("held", [p], [ca.SX(value)])(p_values))
        if abs(mine - numbers[k]) > 1e-9 * (1 + abs(numbers[k])):
            joint = model.components[m.joint]
            problems.append(f"{model.place(joint, label)} = {mine:.12g}: {joint.name} is "
                            f"moved by {m.source}, which gives its {what} at t = 0 as "
                            f"{numbers[k]:.12g}: leave {label} unset (the motion decides)")
    if problems:
        raise ModelError(problems)
    net.start = ca.vertsplit(values[nq + nu:])
    return ca.vertsplit(values[:nq]), ca.vertsplit(values[nq:nq + nu])


def _symbols(names, suffix):
    if not names:
        return ca.SX(0, 1)
    clean = [n.replace(".", "_").replace("[", "_").replace("]", "") + suffix for n in names]
    return ca.vertcat(*[ca.SX.sym(c) for c in clean])


def _speed_units(joint):
    if hasattr(type(joint), "speed_units"):
        return joint.speed_units()
    return ["m/s"] * 3 + ["rad/s"] * 3 if joint.dof == 6 else ["rad/s"] * joint.dof


def _bodies(topo, bound, q, u, qindex, uindex):
    """Moving bodies along the tree; rigid parts fold into the body before them.

    Returns the bodies and, for each frame set, (body index, R, p): where the set sits in
    its body (-1 is the world).
    """
    place = {topo.root: (-1, ca.SX.eye(3), ca.SX.zeros(3))}
    bodies = []
    for edge in topo.tree:
        comp = bound[edge.component.name]
        qj = q[qindex[comp.name]] if comp.dof else ca.SX(0, 1)
        Re, re = comp.transform(qj)
        if edge.reversed:
            Re, re = Re.T, -Re.T @ re
        k, Rf, pf = place[edge.parent]
        R, pos = Rf @ Re, pf + Rf @ re
        if comp.dof == 0:
            place[edge.child] = (k, R, pos)
            continue
        uj = u[uindex[comp.name]]
        S = None if edge.reversed else comp.subspace(qj)
        if S is None:
            S = motion_subspace(comp, qj, uj, Re, re)
        # screw joints: exact constants, no S-dot term (a reversed ball joint is not one)
        if comp.constant_subspace and (comp.regular or not edge.reversed):
            S, cJ = ca.substitute(S, qj, ca.DM(_zero_pose(comp))), ca.SX.zeros(6)
        else:
            cJ = ca.jtimes(S @ uj, qj, comp.rate(qj, uj))
        bodies.append(Body(comp.name, k, R, pos, S, cJ, ca.SX.zeros(6, 6), uindex[comp.name]))
        place[edge.child] = (len(bodies) - 1, ca.SX.eye(3), ca.SX.zeros(3))
    inner = topo.inner
    for body, frame_set in topo.bodies:
        if frame_set in inner:
            continue            # moves with an assembly's loop: ``applied.Extra`` takes it
        k, Rs, ps = place[frame_set]
        if k < 0:
            continue            # welded to the ground: no motion, no state
        m, c, Ic = bound[body.name].mass_properties()
        bodies[k].inertia += spatial_inertia(m, ps + Rs @ c, Rs @ Ic @ Rs.T)
    return bodies, place


def _zero_pose(comp):
    """Coordinates of the joint's home pose (identity quaternion for quaternion joints)."""
    labels = comp.coordinate_labels()
    return [1.0 if label == "quat[0]" else 0.0 for label in labels]


def _frame_forces(asm, topo, bound, t):
    """Generalized forces of the force elements on frames (line forces, forces and torques):
    the wrench each applies on a frame enters as J^T f + J_w^T t (``applied.py``)."""
    return applied.element_forces(asm, topo, bound)


def _closure(asm, cut, comp, qindex):
    """Loop-closure residual of a cut joint, zero when its frames meet as the joint allows.

    Both frames are placed relative to the nearest body the two tree paths share, so a
    loop's equations hold only the coordinates of the loop itself (sparse, cheap to solve).
    """
    Ra, pa, Rb, pb = asm.relative_poses(cut.set_a, cut.set_b)
    qj = asm.q[qindex[comp.name]] if comp.dof and comp.regular else ca.SX(0, 1)
    return comp.closure(Ra.T @ Rb, Ra.T @ (pb - pa), qj)


def _place_cut_frames(asm, topo, bound):
    """Frames a cut joint places from where its two ends are (a rod's frame_ia), in the body
    of its frame_a: for probes, as validation holds (nothing there bears a load)."""
    for cut in topo.cuts:
        comp = bound[cut.component.name]
        if not getattr(type(comp), "placed_frames", ()):
            continue
        Ra, pa, Rb, pb = asm.relative_poses(cut.set_a, cut.set_b)
        k, R, pos = asm.place[cut.set_a]
        for port, (Rp, pp) in comp.frames(Ra.T @ Rb, Ra.T @ (pb - pa)).items():
            asm.place[topo.set_of[cut.component.port_ref(port)]] = (k, R @ Rp, pos + R @ pp)


def _signal_reads(model, topo):
    """Component name -> {signal it reads by name ("pos.y"): (placeholder, signal set)}, for
    the values (a force law) that read signal outputs."""
    reads = {}
    for comp in model.components.values():
        for key, spec in comp.params.items():
            value = comp._values[key]
            if not spec.signals or value is None:
                continue
            for text in value if isinstance(value, list) else [value]:
                for n in parse(text).names if isinstance(text, str) else ():
                    if "." not in n:
                        continue
                    path, port = n.rsplit(".", 1)
                    ref = model.components[path].port_ref(port)
                    sym = ca.SX.sym("signal_" + n.replace(".", "_"))
                    reads.setdefault(comp.name, {}).setdefault(n, (sym, topo.set_of[ref]))
    return reads


def _symbolic(value, env, funcs):
    """A normalized parameter value as CasADi SX (lists stay lists of SX)."""
    if isinstance(value, list):
        return [_symbolic(v, env, funcs) for v in value]
    if isinstance(value, str):
        return ca.SX(parse(value).evaluate(env, funcs))
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return ca.SX(value)
    return value
