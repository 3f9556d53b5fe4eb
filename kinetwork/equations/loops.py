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

import itertools
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import ModelError
from ..util import quiet, summary
from . import loopstart
from .newton_euler import aba, rnea

def _pivoted_qr(a):
    """The QR factorisation of ``a`` with column pivoting (Businger-Golub: at each step the
    column of largest remaining norm, the first of equals): (|diagonal of R|, column order).

    numpy has no pivoted QR and scipy.linalg costs 0.3 s to import in every process that
    builds a loop; the matrices here are a few dozen rows and columns.
    """
    r = np.array(a, dtype=float)
    m, n = r.shape
    order = np.arange(n)
    diag = np.zeros(min(m, n))
    for k in range(min(m, n)):
        norms = np.sqrt(np.einsum("ij,ij->j", r[k:, k:], r[k:, k:]))
        j = k + int(np.argmax(norms))
        if j != k:
            r[:, [k, j]] = r[:, [j, k]]
            order[[k, j]] = order[[j, k]]
        diag[k] = norms[j - k]
        if diag[k] == 0.0:
            break                      # what remains is zero
        v = r[k:, k].copy()
        v[0] += math.copysign(diag[k], v[0])
        v /= np.linalg.norm(v)
        r[k:, k:] -= 2.0 * np.outer(v, v @ r[k:, k:])
    return diag, order


FORMULATIONS = ("partition", "projected", "baumgarte")
#: Newton steps of the projected formulation (from a start within the integrator's tolerance
#: of the closure, two already reach round-off)
PROJECTION_STEPS = 3
#: rate [1/s] at which the projected formulation's carried starts follow the projection
PROJECTION_PULL = 1.0
#: Baumgarte's stabilisation rate a [1/s] by default
BAUMGARTE_RATE = 10.0
#: a closure residual below this (m, and rotation-matrix entries) counts as closed
CLOSED = 1e-10
#: starts of the assembly search where Gauss-Newton stalls: the guesses, then perturbed ones
SEARCH_STARTS = 24
#: singular values below this fraction of the largest mark redundant closure equations
RANK_TOL = 1e-8
#: a re-partition compares every choice of dependent speeds when there are at most this many
#: (a planar five-bar: 10); beyond, it takes the pivoted-QR choice
PARTITION_CHOICES = 200


@dataclass
class Equations:
    """What is integrated: differential states x, algebraic variables z, and how the joint
    coordinates q, speeds u and accelerations udot read from them (all SX in x, z, t, p)."""
    x: ca.SX
    z: ca.SX
    ode: ca.SX
    alg: ca.SX
    state_names: list
    state_units: list
    algebraic_names: list
    algebraic_units: list
    u: ca.SX
    udot: ca.SX
    formulation: str
    note: str = ""
    loop_rows: int = 0              # independent closure equations kept
    loop_redundant: int = 0         # closure equations dropped as redundant
    initial: object = None          # p -> (x0, z0) numpy
    residual: ca.SX = None          # kept closure equations, in q
    lam: ca.SX = None               # multiplier of every closure row (0 for dropped ones)
    q: ca.SX = None                 # coordinates, where they are not the states themselves
    #: the closure's Jacobian in the dependent speeds (in q): the partition holds while it is
    #: regular; where it turns singular the mechanism folds flat or locks
    dependent_jacobian: ca.SX = None
    dependent_names: list = None    # the dependent speeds, by name
    prescribed: int = 0             # joint speeds a motion source gives (no states)
    clock: int = None               # index of the state ``time``, when there is one
    #: the kept closure rows and the dependent speeds, by index (``_Loops.partitions_at``
    #: chooses others where this partition turns singular)
    partition: tuple = None
    loops: object = None            # the _Loops that made these equations
    rate: float = None              # Baumgarte's rate, as the formulation was built


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
    eq = Equations(ca.vertcat(_rows(q, keep_q), _rows(u, ind)), ca.SX(0, 1),
                   ca.vertcat(_rows(asm.qdot, keep_q), _rows(udot, ind)), ca.SX(0, 1), names,
                   units, [], [], u, udot, "hybrid",
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
        self.rows, self.dep = self._partition(np.asarray(self.f_J(q0, p_nom)), loop_coords)
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
        q, r = self._gauss_newton(start, p)
        if not self._closed(r):
            q, r = self._search(start, p, q, r)
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
            alone = {i: self._alone(i, start, p) for i, v in by_loop.items() if v > CLOSED}
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

    def _closed(self, r):
        return bool(np.isfinite(r).all()) and np.max(np.abs(r), initial=0.0) < CLOSED * 1e-2

    def _gauss_newton(self, q, p, rows=None, free=None):
        free = self.free if free is None else free
        pick = (lambda r: r) if rows is None else (lambda r: r[rows])
        q = q.copy()
        r = pick(np.asarray(self.f_phi(q, p)).ravel())
        for _ in range(100):
            if self._closed(r):
                break
            J = np.asarray(self.f_jac(q, p))
            J = J[:, [self.free.index(i) for i in free]]
            J = J if rows is None else J[rows]
            step = np.linalg.lstsq(J, -r, rcond=None)[0] if free else np.zeros(0)
            for scale in (1.0, 0.5, 0.25, 0.1, 0.01):        # backtrack on |residual|
                trial = q.copy()
                trial[free] += scale * step
                r_trial = pick(np.asarray(self.f_phi(trial, p)).ravel())
                if np.linalg.norm(r_trial) < np.linalg.norm(r):
                    q, r = trial, r_trial
                    break
            else:
                break
        return q, r

    def _search(self, start, p, q_best, r_best, rows=None, free=None):
        """Levenberg-Marquardt from the start and from SEARCH_STARTS perturbed starts
        (deterministic); the closing assembly nearest the start, else the best fit."""
        from scipy.optimize import least_squares
        free = self.free if free is None else free
        if not free:
            return q_best, r_best
        pick = (lambda r: r) if rows is None else (lambda r: r[rows])
        cols = [self.free.index(i) for i in free]

        def residual(z):
            q = start.copy()
            q[free] = z
            return pick(np.asarray(self.f_phi(q, p)).ravel())

        def jacobian(z):
            q = start.copy()
            q[free] = z
            J = np.asarray(self.f_jac(q, p))[:, cols]
            return J if rows is None else J[rows]
        rng = np.random.default_rng(0)
        scale = np.where(np.array(self.asm.coordinate_units)[free] == "m",
                         max(1.0, np.max(np.abs(start[free]), initial=0.0)), np.pi)
        found = []
        for k in range(SEARCH_STARTS):
            z0 = start[free] + (0 if k == 0 else rng.uniform(-1, 1, len(free)) * scale)
            try:
                fit = least_squares(residual, z0, jac=jacobian, method="lm", xtol=1e-15,
                                    ftol=1e-15, gtol=1e-15, max_nfev=200 * (len(free) + 1))
            except (ValueError, np.linalg.LinAlgError):
                continue
            q = start.copy()
            q[free] = fit.x
            q, r = self._gauss_newton(q, p, rows, free)          # polish to round-off
            if self._closed(r):
                # an angle as the turn nearest its guess (q0_guess 0: in (-pi, pi])
                q[free] = start[free] + _wrapped(q[free] - start[free], scale)
                found.append((np.linalg.norm(q[free] - start[free]), k, q, r))
                if k == 0:
                    break
            elif np.linalg.norm(r) < np.linalg.norm(r_best):
                q_best, r_best = q, r
        if found:
            _, _, q, r = min(found, key=lambda f: f[:2])
            return q, r
        return q_best, r_best

    def _alone(self, loop, start, p):
        """Whether loop ``loop`` closes by itself (its rows, the free coordinates in it)."""
        rows = [k for k, i in enumerate(self.owner) if i == loop]
        pattern = np.asarray(ca.DM(self.f_jac.sparsity_out(0), 1))[rows]
        free = [i for c, i in enumerate(self.free) if pattern[:, c].any()]
        q, r = self._gauss_newton(start, p, rows, free)
        if not self._closed(r):
            q, r = self._search(start, p, q, r, rows, free)
        return self._closed(r)

    # -- independent equations and the speed partition ------------------------------------------
    def _partition(self, J, loop_coords):
        asm = self.asm
        names = self.asm.coordinate_names
        if J.size == 0:
            return [], []
        s = np.linalg.svd(J, compute_uv=False)
        rank = int(np.sum(s > RANK_TOL * max(s[0], 1.0)))
        _, piv = _pivoted_qr(J.T)
        rows = sorted(piv[:rank].tolist())
        Jr = J[rows]
        # speeds that may be dependent: of regular loop coordinates; preference tiers
        cut_joints = {c.component.name for c, _ in asm.cuts}
        tiers = [[], [], []]
        for k in sorted(loop_coords):
            if not asm.regular[k]:
                continue
            speed = asm.speed_of[k]
            if speed in asm.prescribed:      # its motion is given: neither kind
                continue
            if asm.given[k] or asm.u_given[speed]:
                tiers[2].append(speed)
            elif names[k].rsplit(".", 1)[0] in cut_joints:
                tiers[0].append(speed)
            else:
                tiers[1].append(speed)
        dep = []
        basis = np.zeros((rank, 0))
        for tier in tiers:
            if len(dep) == rank or not tier:
                continue
            cols = Jr[:, tier]
            if basis.shape[1]:                 # what the chosen columns do not reach yet
                Qb, _ = np.linalg.qr(basis)
                cols = cols - Qb @ (Qb.T @ cols)
            diag, piv = _pivoted_qr(cols)
            for j, d in zip(piv, diag):
                if len(dep) == rank or d <= RANK_TOL * max(np.abs(Jr).max(), 1.0):
                    break
                dep.append(tier[j])
                basis = np.column_stack([basis, Jr[:, tier[j]]])
        if len(dep) < rank:
            quaternion = sorted({n.rsplit(".", 1)[0] for k, n in enumerate(names)
                                 if k in loop_coords and not asm.regular[k]})
            loops = "; ".join(", ".join(c.loop) for c, _ in asm.cuts)
            driven = sorted({f"{m.joint} (by {m.source})" for m in asm.prescribed.values()
                             if m.coordinate in loop_coords})
            raise ModelError(
                f"kinematic loop through {loops}: its closure fixes {rank} speeds but only "
                f"{len(dep)} joint angles or distances on the loop can follow it"
                + (f"; the ball or free joint(s) {', '.join(quaternion)} on the loop must be "
                   f"the cut joint (mark one cut=True), or be replaced by a Universal joint"
                   if quaternion else "")
                + (f"; the prescribed joint(s) {', '.join(driven)} cannot follow it: "
                   f"their motions fight each other through the loop (drive fewer joints)"
                   if driven else ""))
        return rows, sorted(dep)

    def candidates(self):
        """The speeds that may be dependent: of the regular coordinates on a loop, less the
        prescribed ones."""
        asm = self.asm
        return sorted(asm.speed_of[k] for k in self.loop_coords
                      if asm.regular[k] and asm.speed_of[k] not in asm.prescribed)

    def partitions_at(self, q, p):
        """The partitions possible at the configuration ``q``: (health, choices), or None
        where the closure has lost rank.

        ``health`` is the ratio of the smallest to the largest singular value of the kept
        closure rows' Jacobian in the candidate speeds: it goes to zero at a change point,
        where two branches of the mechanism's configurations cross (a rhombus folding
        flat) and no partition is regular. ``choices`` are (rows, dependent speeds,
        condition number of the Jacobian in them, quality): the rows by pivoted QR as at
        the start, every choice of as many candidate speeds as rows (or, beyond
        PARTITION_CHOICES of them, the pivoted-QR one); quality is the smallest singular
        value of the rows of the independent speeds in an orthonormal basis of the
        closure's null space (the tangent of the configurations): how well the independent
        coordinates describe the motion, through a change point too."""
        J = np.asarray(self.f_J(q, p), dtype=float)
        if not np.all(np.isfinite(J)):
            return None
        s = np.linalg.svd(J, compute_uv=False)
        rank = int(np.sum(s > RANK_TOL * max(s[0], 1.0))) if s.size else 0
        if rank < len(self.rows):
            return None
        _, piv = _pivoted_qr(J.T)
        rows = sorted(piv[:rank].tolist())
        cand = self.candidates()
        Jc = J[rows][:, cand]
        _, sc, vt = np.linalg.svd(Jc)
        health = float(sc[-1] / sc[0]) if sc.size and sc[0] > 0 else 0.0
        N = vt[rank:].T                              # null space, one row per candidate
        if math.comb(len(cand), rank) <= PARTITION_CHOICES:
            choices = itertools.combinations(range(len(cand)), rank)
        else:
            _, piv = _pivoted_qr(Jc)
            choices = [sorted(piv[:rank].tolist())]
        out = []
        for dep in choices:
            ind = [j for j in range(len(cand)) if j not in dep]
            quality = np.linalg.svd(N[ind], compute_uv=False)[-1] if ind else 1.0
            out.append((rows, [cand[j] for j in dep], condition(Jc[:, list(dep)]),
                        float(quality)))
        return health, out

    # -- the equations --------------------------------------------------------------------------
    def _projected(self, x, zg, ode, keep_q, dep_q, ind, sub, u_full, udot, udot_i, phi, lam,
                   initial, note_rows):
        """The ``projected`` formulation: an ODE whose dependent coordinates are carried as
        states only as the start of a Newton projection onto the closure in every
        evaluation; the dynamics see the projected values, so they hold the closure to
        round-off, while any ODE method (Adams, DOP853, ...) can integrate them."""
        asm = self.asm
        q = asm.q
        zs = newton(phi, zg)
        star = lambda e: ca.substitute(e, zg, zs)        # noqa: E731
        rate_dep = star(sub(_rows(asm.qdot, dep_q))) + PROJECTION_PULL * (zs - zg)
        x = ca.vertcat(_rows(q, keep_q), zg, _rows(asm.u, ind))
        ode = ca.vertcat(star(sub(_rows(asm.qdot, keep_q))), rate_dep, star(sub(udot_i)))
        qn, un = asm.coordinate_names, asm.speed_names
        qu, uu = asm.coordinate_units, asm.speed_units
        names = [qn[k] for k in keep_q] + [qn[k] for k in dep_q] + [un[k] for k in ind]
        units = [qu[k] for k in keep_q] + [qu[k] for k in dep_q] + [uu[k] for k in ind]
        note = (f"kinematic loops, projected formulation: {x.shape[0]} states for {len(ind)} "
                f"degree{'s' * (len(ind) != 1)} of freedom; the {len(dep_q)} dependent coordinates are states only to "
                f"start a Newton projection onto {note_rows} in every evaluation (an ODE that "
                f"holds the closure to round-off)")
        out = Equations(x, ca.SX(0, 1), ode, ca.SX(0, 1), names, units, [], [],
                        star(u_full), star(sub(udot)), "projected", note, len(self.rows),
                        self.phi.shape[0] - len(self.rows), initial, star(phi),
                        star(sub(lam)))
        out.q = ca.substitute(q, zg, zs)
        out.dependent_jacobian = star(self.JD)
        out.dependent_names = [un[k] for k in self.dep]
        return out


    def equations(self, formulation, rate):
        eq = self._equations(formulation, rate)
        eq.partition, eq.loops, eq.rate = (list(self.rows), list(self.dep)), self, rate
        return eq

    def _equations(self, formulation, rate):
        asm = self.asm
        q, u = asm.q, asm.u
        nv = u.shape[0]
        dep = self.dep
        # prescribed speeds P are neither independent nor dependent: their motion is given
        P = list(asm.prescribed)
        ind = [k for k in range(nv) if k not in set(dep) | set(P)]
        phi = _rows(self.phi, self.rows)
        J = _rows(self.J, self.rows)
        JD, JI, JP = _cols(J, dep), _cols(J, ind), _cols(J, P)
        self.JD = JD
        T = ca.SX.zeros(nv, len(ind))
        T[ind, :] = ca.SX.eye(len(ind))
        if dep:
            T[dep, :] = -ca.solve(JD, JI)
        # u = T u_I + s: the prescribed speeds (symbols until ``_prescribe``) and what the
        # dependent ones do to follow them
        s_vel = ca.SX.zeros(nv)
        acc_P = ca.vertcat(*[m.acc for m in asm.prescribed.values()])
        if P:
            s_vel[P] = u[P]
            if dep:
                s_vel[dep] = -ca.solve(JD, JP @ u[P])
        c = ca.jtimes(J @ u, q, asm.qdot)             # (dJ/dt) u
        if formulation == "baumgarte":
            c = c + 2 * rate * (J @ u) + rate ** 2 * phi
        g = ca.SX.zeros(nv)
        if P:
            g[P] = acc_P
        if dep:
            g[dep] = -ca.solve(JD, c + JP @ acc_P if P else c)
        a_grav = ca.vertcat(ca.SX.zeros(3), -asm.gravity)
        M = asm.mass_matrix()
        bias = rnea(asm.bodies, u, ca.SX.zeros(nv), a_grav) - asm.Q
        Mr = T.T @ M @ T
        udot_i = ca.solve(Mr, -T.T @ (bias + M @ g))
        udot = T @ udot_i + g
        # multipliers: J^T lam = M udot + bias, exactly solvable as J has independent rows;
        # with prescribed speeds, J^T lam + E_P drive = M udot + bias (E_P: their columns of
        # the identity), as exactly: no combination of closure rows acts on them alone, or
        # the partition would have failed
        lam = ca.SX.zeros(self.phi.shape[0])
        if P:
            A = ca.horzcat(J.T, ca.SX.eye(nv)[:, P])
            both = ca.solve(A.T @ A, A.T @ (M @ udot + bias))
            if self.rows:
                lam[self.rows] = both[:len(self.rows)]
            lam = ca.vertcat(lam, both[len(self.rows):])
        elif self.rows:
            lam[self.rows] = ca.solve(J @ J.T, J @ (M @ udot + bias))
        dep_q = [k for k, v in asm.speed_of.items() if v in set(dep)]
        Pq = {m.coordinate for m in asm.prescribed.values()}
        qnames, unames = asm.coordinate_names, asm.speed_names
        qunits, uunits = asm.coordinate_units, asm.speed_units
        note_rows = (f"{len(self.rows)} independent closure equations"
                     + (f" ({self.phi.shape[0] - len(self.rows)} redundant dropped)"
                        if self.phi.shape[0] > len(self.rows) else ""))
        start = self.f_start
        rows = self.rows
        if formulation == "baumgarte":
            u_i = ca.SX.sym("u_i", len(ind))
            f_u = ca.Function("u_start", [q, u_i, asm.p], [ca.substitute(
                T @ u_i + s_vel, _rows(u, P), _rows(asm.u_start, P))])
            all_q = [k for k in range(q.shape[0]) if k not in Pq]
            all_u = [k for k in range(nv) if k not in set(P)]

            def initial(p):
                qc = self.close(p)
                _, u0 = start(p)
                u0 = loopstart.speeds(self, qc, np.asarray(u0, dtype=float).ravel(), p)
                un = np.asarray(f_u(qc, u0[ind], p))
                return np.concatenate([qc[all_q], un.ravel()[all_u]]), np.zeros(0)
            note = (f"kinematic loops, Baumgarte formulation: all {len(all_q)} coordinates "
                    f"and {len(all_u)} speeds are states ({len(ind)} degrees of freedom; "
                    f"{note_rows}, stabilised at rate {rate:g}/s)")
            return Equations(ca.vertcat(_rows(q, all_q), _rows(u, all_u)), ca.SX(0, 1),
                             ca.vertcat(_rows(asm.qdot, all_q), _rows(udot, all_u)),
                             ca.SX(0, 1), [qnames[k] for k in all_q] + [unames[k] for k in all_u],
                             [qunits[k] for k in all_q] + [uunits[k] for k in all_u], [], [], u,
                             udot, "baumgarte", note, len(rows), self.phi.shape[0] - len(rows),
                             initial, phi, lam, dependent_jacobian=JD,
                             dependent_names=[unames[k] for k in dep])
        keep_q = [k for k in range(q.shape[0]) if k not in set(dep_q) | Pq]
        u_full = ca.densify(T @ _rows(u, ind) + s_vel)
        sub = lambda e: ca.substitute(e, u, u_full)     # noqa: E731
        x = ca.vertcat(_rows(q, keep_q), _rows(u, ind))
        z = _rows(q, dep_q)
        ode = ca.vertcat(sub(_rows(asm.qdot, keep_q)), sub(udot_i))

        def initial(p, projected=False):
            qc = self.close(p)
            _, u0 = start(p)
            u0 = np.asarray(u0, dtype=float).ravel()
            u_dep_given = [k for k in dep if asm.u_given[k] and u0[k] != 0]
            if u_dep_given:
                raise ModelError(
                    f"qd0 of {', '.join(unames[k] for k in u_dep_given)}: this speed is "
                    f"fixed by the loop closure (it is a dependent coordinate); give the "
                    f"initial speed of an independent coordinate "
                    f"({', '.join(unames[k] for k in ind)}) instead")
            u0 = loopstart.speeds(self, qc, u0, p)
            if projected:
                return np.concatenate([qc[keep_q], qc[dep_q], u0[ind]]), np.zeros(0)
            return np.concatenate([qc[keep_q], u0[ind]]), qc[dep_q]
        if formulation == "projected" and dep:
            return self._projected(x, z, ode, keep_q, dep_q, ind, sub, u_full, udot, udot_i,
                                   phi, lam, lambda p: initial(p, True), note_rows)
        if not dep:
            note = ("kinematic loops closed by rigid parts or by a free joint: they fix no "
                    "coordinate, so the states are those of the tree")
        else:
            note = ""
        note = note or (f"kinematic loops, coordinate partitioning: {len(keep_q) + len(ind)} "
                f"differential states for {len(ind)} degrees of freedom"
                + (" (a quaternion has 4 coordinates for 3 speeds)"
                   if len(keep_q) > len(ind) else "")
                + f"; {len(dep_q)} dependent coordinates ({', '.join(qnames[k] for k in dep_q)})"
                f" are algebraic variables solved from {note_rows} at every step")
        return Equations(x, z, ode, phi, [qnames[k] for k in keep_q] + [unames[k] for k in ind],
                         [qunits[k] for k in keep_q] + [uunits[k] for k in ind],
                         [qnames[k] for k in dep_q], [qunits[k] for k in dep_q],
                         u_full, sub(udot), "partition", note, len(rows),
                         self.phi.shape[0] - len(rows), initial, phi, sub(lam),
                         dependent_jacobian=JD if dep else None,
                         dependent_names=[unames[k] for k in dep])



def condition(A):
    """The 2-norm condition number of a square matrix (inf when singular)."""
    if not A.size:
        return 1.0
    s = np.linalg.svd(A, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else np.inf


def _wrapped(d, scale):
    """Differences of coordinates, angles (scale pi) taken modulo 2 pi."""
    angle = scale == np.pi
    return np.where(angle, (d + np.pi) % (2 * np.pi) - np.pi, d)


def newton(residual, z, steps=PROJECTION_STEPS):
    """``z`` after ``steps`` Newton steps on ``residual(z) = 0``, written out in SX."""
    jac = ca.jacobian(residual, z)
    out = z
    for _ in range(steps):
        out = out - ca.solve(ca.substitute(jac, z, out), ca.substitute(residual, z, out))
    return out


def _rows(m, index):
    """Rows ``index`` of an SX matrix: SX(0, columns) when there are none (CasADi's own
    indexing of a 1 x 1 matrix by an empty list gives 1 x 0)."""
    return m[index, :] if index else ca.SX(0, m.shape[1])


def _cols(m, index):
    return m[:, index] if index else ca.SX(m.shape[0], 0)
