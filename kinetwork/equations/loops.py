"""From the assembled tree (plus loop closures) to the equations that are integrated.

A model without loops is an ODE in all its coordinates and speeds. A model with kinematic
loops has more coordinates than degrees of freedom; three formulations are offered:

``partition``: coordinate partitioning written as a semi-explicit index-1 DAE.
    At the initial configuration the independent closure equations (rows of the loop
    Jacobian, chosen by pivoted QR so that redundant ones, such as the out-of-plane rows of
    a planar four-bar built from 3-D revolutes, drop out) split the speeds into dependent ones
    u_D (as many as independent equations) and independent ones u_I, preferring to keep
    independent the coordinates a user gave (a crank angle). The differential states are the
    independent coordinates and speeds only (a four-bar: crank angle and speed, 2 states);
    the dependent coordinates are algebraic variables fixed by the closure equations
    Phi(q) = 0, which IDAS solves by Newton at every step: they never drift from the
    constraint manifold. Dependent speeds and accelerations follow exactly from
    J u = 0 and J udot + (dJ/dt) u = 0, and the dynamics are projected on the independent
    speeds: (T^T M T) udot_I = -T^T (bias + M g), with u = T u_I, udot = T udot_I + g.
    ``simulate`` Newton-polishes the algebraic variables at the output points (IDAS holds
    them to its tolerance; the outputs hold them to round-off).

``projected`` (the default): the same partition as an ODE that any method integrates. The
    dependent coordinates are carried as states too, but only as the start of a Newton
    projection onto the closure inside every evaluation (three steps from within the
    integrator's tolerance: round-off); the dynamics and the probes see the projected
    values. More states (a four-bar: 5 for the partition's 2 and 3 algebraic variables), no
    drift, and CVODES Adams instead of IDAS: 2-4x faster to the same error on the loop
    study's mechanisms, and its error stays proportional to the tolerance down to rtol
    1e-10, where IDAS meets its floor (``bench/results/study_loops_pareto.md``,
    ``study_tolerance.md``). The linearisation still works in the partition's independent
    coordinates (``analysis.channels.plant``).

``baumgarte``: an ODE in all coordinates and speeds, index-reduced to the acceleration
    level with Baumgarte stabilisation J udot + (dJ/dt) u + 2 a J u + a^2 Phi = 0. Any ODE
    method integrates it, but it has more states and the residual is only kept small, not
    zero; it is there to compare with.

Prescribed joints (a Position, Speed or Accelerate source on a joint's axis: a rheonomic
constraint q_P = phi(t)) are eliminated, not constrained: their coordinates, speeds and
accelerations are known functions of time (and of the sources' filter states), so they are
no states. A tree becomes Featherstone's hybrid dynamics (``hybrid``): the articulated-body
algorithm with the prescribed accelerations given, M_ff udot_f = Q_f - M_fp udot_p - h_f in
O(n), and the drives by inverse dynamics, tau_p = [M udot + h - Q]_p. With loops the
prescribed speeds are neither independent nor dependent: u = T u_I + s(t), udot = T udot_I +
g with the prescribed motion in s and g, and the multipliers and the drives together solve
J^T lam + E_P tau_p = M udot + h - Q. The drives stand in the network for the sources'
torques (``Assembly.lam`` after the multipliers), so probes, sensors and cut forces read them.
Where a loop's closure then depends on time explicitly (an exact Position in a loop), time
becomes a state (``time``, rate 1): the closure, its Jacobian and the polish of the outputs
are functions of the states alone, and a mechanism left with no degree of freedom (a
four-bar whose crank is driven) is still integrated by IDAS, which solves its other joints
at every step.
"""

import casadi as ca
import numpy as np

from ..errors import ModelError
from ..util import quiet, summary
from . import loopclose, loopstart, partitioning
from .formulations import Equations, equations_of, newton, take_rows
from .loopclose import CLOSED
from .newton_euler import aba, rnea

__all__ = ["BAUMGARTE_RATE", "FORMULATIONS", "Equations", "formulate", "newton"]

FORMULATIONS = ("partition", "projected", "baumgarte")
#: Baumgarte's stabilisation rate a [1/s] by default
BAUMGARTE_RATE = 10.0


def formulate(asm, topo, values, formulation="partition", rate=BAUMGARTE_RATE,
              partition=None):
    """The Equations of an assembled model; ``values`` are the model's parameter values,
    at which loops are analysed (rows kept, speeds partitioned). The states of the 1-D
    network and the signal blocks (free rotors, controller integrals) follow the mechanism's.
    ``partition`` (closure rows kept, dependent speeds; indices) replaces the partition
    chosen at the initial configuration: a run re-partitions where that one turns singular.
    """
    eq = _mechanism(asm, topo, values, formulation, rate, partition)
    net = asm.net
    if net is None or not (net.x or net.alg_z):
        return eq
    q = asm.q if eq.q is None else eq.q

    def in_states(exprs):
        return ca.substitute(ca.vertcat(*exprs), ca.vertcat(asm.q, asm.u, asm.udot, asm.lam),
                             ca.densify(ca.vertcat(q, eq.u, eq.udot, eq.lam)))
    z_mech = eq.z
    eq.x, eq.ode = ca.vertcat(eq.x, *net.x), ca.vertcat(eq.ode, in_states(net.rate))
    eq.state_names = eq.state_names + net.names
    eq.state_units = eq.state_units + net.units
    start = ca.Function("start_network", [asm.p], [ca.vertcat(*[ca.SX(s) for s in net.start])])
    mechanism = eq.initial
    solve_z = None
    if net.alg_z:
        # a nonlinear algebraic loop of signals: its outputs join the algebraic variables,
        # started by Newton from 0 at the initial state (t = 0)
        z_sig = ca.vertcat(*net.alg_z)
        res = ca.substitute(in_states(net.alg_res), asm.t, ca.SX(0))
        eq.z, eq.alg = ca.vertcat(eq.z, z_sig), ca.vertcat(eq.alg, in_states(net.alg_res))
        eq.algebraic_names = eq.algebraic_names + net.alg_names
        eq.algebraic_units = eq.algebraic_units + net.alg_units
        known = ca.vertcat(eq.x, z_mech, asm.p)
        solve_z = ca.rootfinder("signal_loops", "newton",
                                ca.Function("res", [z_sig, known], [res]), {"abstol": 1e-13})

    def initial(p):
        x0, z0 = mechanism(p)
        x0 = np.concatenate([x0, np.asarray(start(p), dtype=float).ravel()])
        if solve_z is None:
            return x0, z0
        with quiet() as said:
            try:
                zs = solve_z(np.zeros(len(net.alg_z)), np.concatenate([x0, z0, p]))
            except RuntimeError:
                zs = None
        if zs is None:
            chatter = summary(said["text"])
            raise ModelError("the nonlinear algebraic loop(s) through "
                             + "; ".join(", ".join(n) for n in net.loops_kept)
                             + " have no solution at the initial state (Newton from 0 "
                               "failed" + (f"; {chatter}" if chatter else "") + ")")
        return x0, np.concatenate([z0, np.asarray(zs, dtype=float).ravel()])
    eq.initial = initial
    return eq


def _mechanism(asm, topo, values, formulation, rate, partition=None):
    if formulation not in FORMULATIONS:
        raise ModelError(f"loops={formulation!r}: unknown formulation; choose from "
                         f"{', '.join(FORMULATIONS)}")
    q, u = asm.q, asm.u
    names = asm.coordinate_names + asm.speed_names
    units = asm.coordinate_units + asm.speed_units
    given = np.array(asm.given, dtype=bool)
    if not asm.cuts and asm.prescribed:
        return _hybrid(asm, given)
    if not asm.cuts:
        start = asm.start_function()

        def initial(p):
            q0, u0 = (np.asarray(v, dtype=float).ravel() for v in start(p))
            return np.concatenate([np.where(given, q0, 0.0), u0]), np.zeros(0)
        quaternions = q.shape[0] - u.shape[0]
        note = (f"{q.shape[0] + u.shape[0]} states for {u.shape[0]} degrees of freedom: the "
                f"quaternion of each ball or free joint has 4 coordinates for 3 speeds, so "
                f"that no orientation is singular" if quaternions else "")
        return Equations(ca.vertcat(q, u), ca.SX(0, 1), ca.vertcat(asm.qdot, asm.udot_tree),
                         ca.SX(0, 1), names, units, [], [], u, asm.udot_tree, "tree", note,
                         initial=initial, lam=ca.SX(0, 1))
    eq = _Loops(asm, topo, values, partition).equations(formulation, rate)
    return _prescribe(asm, eq, loops=True) if asm.prescribed else eq


def _hybrid(asm, given):
    """A tree with prescribed joints: Featherstone's hybrid dynamics (the articulated-body
    algorithm with the prescribed accelerations given), the drives by inverse dynamics."""
    q, u = asm.q, asm.u
    P = list(asm.prescribed)
    Pq = {m.coordinate for m in asm.prescribed.values()}
    keep_q = [k for k in range(q.shape[0]) if k not in Pq]
    ind = [k for k in range(u.shape[0]) if k not in set(P)]
    a_grav = ca.vertcat(ca.SX.zeros(3), -asm.gravity)
    acc = {s: m.acc for s, m in asm.prescribed.items()}
    extra = getattr(asm, "applied", None)
    if extra is not None and extra.masses:
        # point masses of force elements are no bodies of the tree: the mass matrix they
        # add is dense, so the free speeds are solved from it, M_ff udot_f = -(h + M_fp a_p)_f
        M = asm.mass_matrix()
        bias = rnea(asm.bodies, u, ca.SX.zeros(u.shape[0]), a_grav) - asm.Q
        udot = ca.SX.zeros(u.shape[0])
        udot[P] = ca.vertcat(*acc.values())
        if ind:
            udot[ind] = ca.solve(M[ind, ind], -(bias + M @ udot)[ind])
        drive = (M @ udot + bias)[P]
    else:
        udot = aba(asm.bodies, u, asm.Q, a_grav, asm.armature, acc)
        drive = (rnea(asm.bodies, u, udot, a_grav, asm.armature) - asm.Q)[P]
    start = asm.start_function()

    def initial(p):
        q0, u0 = (np.asarray(v, dtype=float).ravel() for v in start(p))
        return np.concatenate([np.where(given, q0, 0.0)[keep_q], u0[ind]]), np.zeros(0)
    names = [asm.coordinate_names[k] for k in keep_q] + [asm.speed_names[k] for k in ind]
    units = [asm.coordinate_units[k] for k in keep_q] + [asm.speed_units[k] for k in ind]
    eq = Equations(ca.vertcat(take_rows(q, keep_q), take_rows(u, ind)), ca.SX(0, 1),
                   ca.vertcat(take_rows(asm.qdot, keep_q), take_rows(udot, ind)), ca.SX(0, 1),
                   names, units, [], [], u, udot, "hybrid",
                   "hybrid dynamics (the articulated-body algorithm with the prescribed "
                   "accelerations given)", initial=initial, lam=drive)
    return _prescribe(asm, eq, loops=False)


def _prescribe(asm, eq, loops):
    """The prescribed coordinates and speeds put in the formulation's equations as the
    motions give them; with a loop whose closure then reads time, time as a state."""
    recs = list(asm.prescribed.values())
    known = ca.vertcat(*[asm.q[m.coordinate] for m in recs], asm.u[list(asm.prescribed)])
    pos = ca.vertcat(*[m.pos for m in recs])
    vel = ca.vertcat(*[m.vel for m in recs])
    clock = None
    if loops and ca.depends_on(ca.substitute(eq.residual, known[:len(recs)], pos), asm.t):
        clock = ca.SX.sym("time")
        pos = ca.substitute(pos, asm.t, clock)

    def sub(e):
        return None if e is None else ca.substitute(e, known, ca.vertcat(pos, vel))
    eq.ode, eq.alg, eq.u, eq.udot = sub(eq.ode), sub(eq.alg), sub(eq.u), sub(eq.udot)
    eq.q = sub(asm.q if eq.q is None else eq.q)
    eq.residual, eq.dependent_jacobian = sub(eq.residual), sub(eq.dependent_jacobian)
    lam = eq.lam if eq.lam is not None else ca.SX(0, 1)
    eq.lam = sub(lam)
    eq.prescribed = len(recs)
    which = ", ".join(f"{m.joint} by {m.source}" for m in recs)
    eq.note = (f"{len(recs)} joint coordinate(s) prescribed ({which}): known functions of "
               f"time, not states; " + eq.note)
    if clock is not None:
        eq.clock = eq.x.shape[0]
        eq.x, eq.ode = ca.vertcat(eq.x, clock), ca.vertcat(eq.ode, 1)
        eq.state_names, eq.state_units = eq.state_names + ["time"], eq.state_units + ["s"]
        mechanism = eq.initial

        def initial(p):
            x0, z0 = mechanism(p)
            return np.concatenate([x0, [0.0]]), z0
        eq.initial = initial
        eq.note += ("; time is a state (rate 1, from 0 at the start) because the loop "
                    "closure follows the prescribed angle in time")
    return eq


class _Loops:
    """Closure equations of every cut joint, their independent rows and the partition."""

    def __init__(self, asm, topo, values, partition=None):
        self.asm, self.topo = asm, topo
        p_nom = np.array([values[k] for k in asm.param_names], dtype=float)
        self.phi = ca.vertcat(*[r for _, r in asm.cuts])
        self.owner = [i for i, (_, r) in enumerate(asm.cuts) for _ in range(r.shape[0])]
        q, u = asm.q, asm.u
        # velocity-level Jacobian: d(phi)/dt = J(q) u
        self.J = ca.jacobian(ca.jtimes(self.phi, q, asm.qdot), u) if u.shape[0] \
            else ca.SX(self.phi.shape[0], 0)
        loop_coords = set(np.nonzero(np.asarray(
            ca.DM(ca.jacobian(self.phi, q).sparsity(), 1)).any(axis=0))[0])
        quaternion = sorted({asm.coordinate_names[i].rsplit(".", 1)[0] for i in loop_coords
                             if not asm.regular[i]})
        if quaternion:
            loops = "; ".join(", ".join(c.loop) for c, _ in asm.cuts)
            raise ModelError(
                f"kinematic loop through {loops}: the ball or free joint(s) "
                f"{', '.join(quaternion)} would stay in the loop's tree, where their "
                f"quaternions cannot follow the closure; let one of them be the cut joint "
                f"(mark it cut=True), or replace it by a Universal joint (a coupler between "
                f"two ball joints spins freely about its own axis)")
        # the start values of a cut joint (a FreeMotion's r0) are rows of the start's
        # assembly too, after the closures (``loopstart.py``)
        start = asm.start_rows
        phi_start = self.phi if start is None else ca.vertcat(self.phi, start.position)
        start_coords = set(np.nonzero(np.asarray(
            ca.DM(ca.jacobian(phi_start, q).sparsity(), 1)).any(axis=0))[0])
        self.free = [i for i in sorted(loop_coords | start_coords)
                     if asm.regular[i] and not asm.given[i]]
        self.f_phi = ca.Function("closure", [q, asm.p], [phi_start])
        self.f_jac = ca.Function("closure_jacobian", [q, asm.p],
                                 [ca.jacobian(phi_start, q)[:, self.free]])
        self.f_speed = None if start is None or not start.speed.numel() else ca.Function(
            "start_speeds", [q, u, asm.p], [ca.densify(start.speed),
                                            ca.densify(ca.jacobian(start.speed, u))])
        self.f_start = asm.start_function()
        self.f_J = ca.Function("J", [q, asm.p], [ca.densify(self.J)])
        self.loop_coords = loop_coords
        if partition is not None:        # a run re-partitions: no initial configuration
            self.rows, self.dep = (sorted(int(i) for i in part) for part in partition)
            return
        q0 = self.close(p_nom)
        self.rows, self.dep = partitioning.choose(self, np.asarray(self.f_J(q0, p_nom)),
                                                   loop_coords)
        loopstart.branch(self, q0, p_nom)

    # -- consistent initial configuration ---------------------------------------------------
    def close(self, p):
        """Coordinates that close every loop, holding the given ones.

        Gauss-Newton with least-squares steps from q0 (given) and q0_guess (not given). Where
        that stalls, as at a dead centre (a slider-crank started with its crank at pi: the
        closure's Jacobian is singular there and the start sits in a local minimum of the
        residual), a Levenberg-Marquardt search from the guesses and from a fixed set of
        perturbed starts; of the assemblies found, the one nearest the guesses (the branch
        they choose). A loop is named as unable to close only when it cannot close by
        itself."""
        q0, _ = self.f_start(p)
        start = np.asarray(q0, dtype=float).ravel()
        q, r = loopclose.gauss_newton(self, start, p)
        if not loopclose.closed(r):
            q, r = loopclose.search(self, start, p, q, r)
        worst = np.max(np.abs(r), initial=0.0)
        n_closure = self.phi.shape[0]
        if np.isfinite(worst) and worst > CLOSED and \
                np.max(np.abs(r[:n_closure]), initial=0.0) <= CLOSED:
            raise loopstart.unmet(self.asm.start_rows.position_labels, r[n_closure:],
                                  "configuration")
        if not np.isfinite(worst) or worst > CLOSED:
            by_loop = {}
            for i, v in zip(self.owner, np.abs(r)):
                by_loop[i] = max(by_loop.get(i, 0.0), v)
            # a loop stalled with a failing one is not blamed: only those that cannot
            # close even alone (or, if each closes alone, those left open together)
            alone = {i: loopclose.alone(self, i, start, p) for i, v in by_loop.items()
                     if v > CLOSED}
            bad = [i for i, ok in alone.items() if not ok] or list(alone)
            # the coordinates each loop's closure depends on, for the given ones it names
            uses = np.asarray(ca.DM(ca.jacobian(self.phi, self.asm.q).sparsity(), 1))
            msgs = []
            for i in bad:
                rows = [k for k, owner in enumerate(self.owner) if owner == i]
                held = [n for k, (n, g) in enumerate(zip(self.asm.coordinate_names,
                                                          self.asm.given))
                        if g and uses[rows, k].any()]
                msgs.append(
                    f"kinematic loop through {', '.join(self.asm.cuts[i][0].loop)} cannot "
                    f"close: at the best fit found its closure is off by {by_loop[i]:.3g} "
                    f"(m, or rotation-matrix entries); check the link lengths and axes"
                    + (f", the given q0 ({', '.join(held)})" if held else "")
                    + ", or start the search nearer an assembly with q0_guess")
            raise ModelError(msgs)
        return q

    def partitions_at(self, q, p):
        """The partitions possible at the configuration ``q`` (``partitioning``)."""
        return partitioning.partitions_at(self, q, p)

    def equations(self, formulation, rate):
        """The Equations of the loops in ``formulation`` (``formulations.equations_of``),
        with the partition they were built on."""
        eq = equations_of(self, formulation, rate)
        eq.partition, eq.loops, eq.rate = (list(self.rows), list(self.dep)), self, rate
        return eq
