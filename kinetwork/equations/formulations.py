"""The equations of a model with kinematic loops, in each formulation, and their record.

``Equations`` is what every formulation gives the System (``loops.formulate``). For loops,
``equations_of`` builds the partition's index-1 DAE, the projected ODE (``projected``) or
Baumgarte's ODE from the closure, its independent rows and the speed partition of a _Loops:
the dependent speeds and accelerations from J u = 0 and its derivative, the dynamics
projected on the independent speeds, and the multipliers.
"""

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import ModelError
from . import loopstart
from .newton_euler import rnea

#: Newton steps of the projected formulation (from a start within the integrator's tolerance
#: of the closure, two already reach round-off)
PROJECTION_STEPS = 3
#: rate [1/s] at which the projected formulation's carried starts follow the projection
PROJECTION_PULL = 1.0


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


def projected(loops, x, zg, ode, keep_q, dep_q, ind, sub, u_full, udot, udot_i, phi, lam,
               initial, note_rows):
    """The ``projected`` formulation: an ODE whose dependent coordinates are carried as
    states only as the start of a Newton projection onto the closure in every
    evaluation; the dynamics see the projected values, so they hold the closure to
    round-off, while any ODE method (Adams, DOP853, ...) can integrate them."""
    asm = loops.asm
    q = asm.q
    zs = newton(phi, zg)
    star = lambda e: ca.substitute(e, zg, zs)        # noqa: E731
    rate_dep = star(sub(take_rows(asm.qdot, dep_q))) + PROJECTION_PULL * (zs - zg)
    x = ca.vertcat(take_rows(q, keep_q), zg, take_rows(asm.u, ind))
    ode = ca.vertcat(star(sub(take_rows(asm.qdot, keep_q))), rate_dep, star(sub(udot_i)))
    qn, un = asm.coordinate_names, asm.speed_names
    qu, uu = asm.coordinate_units, asm.speed_units
    names = [qn[k] for k in keep_q] + [qn[k] for k in dep_q] + [un[k] for k in ind]
    units = [qu[k] for k in keep_q] + [qu[k] for k in dep_q] + [uu[k] for k in ind]
    note = (f"kinematic loops, projected formulation: {x.shape[0]} states for {len(ind)} "
            f"degree{'s' * (len(ind) != 1)} of freedom; the {len(dep_q)} dependent coordinates are states only to "
            f"start a Newton projection onto {note_rows} in every evaluation (an ODE that "
            f"holds the closure to round-off)")
    out = Equations(x, ca.SX(0, 1), ode, ca.SX(0, 1), names, units, [], [],
                    star(u_full), star(sub(udot)), "projected", note, len(loops.rows),
                    loops.phi.shape[0] - len(loops.rows), initial, star(phi),
                    star(sub(lam)))
    out.q = ca.substitute(q, zg, zs)
    out.dependent_jacobian = star(loops.JD)
    out.dependent_names = [un[k] for k in loops.dep]
    return out


def equations_of(loops, formulation, rate):
    """The Equations of a model with loops in ``formulation`` (partition, projected,
    baumgarte at ``rate``), on the closure rows and speed partition of ``loops``."""
    asm = loops.asm
    q, u = asm.q, asm.u
    nv = u.shape[0]
    dep = loops.dep
    # prescribed speeds P are neither independent nor dependent: their motion is given
    P = list(asm.prescribed)
    ind = [k for k in range(nv) if k not in set(dep) | set(P)]
    phi = take_rows(loops.phi, loops.rows)
    J = take_rows(loops.J, loops.rows)
    JD, JI, JP = take_cols(J, dep), take_cols(J, ind), take_cols(J, P)
    loops.JD = JD
    T = ca.SX.zeros(nv, len(ind))
    T[ind, :] = ca.SX.eye(len(ind))
    if dep:
        T[dep, :] = -ca.solve(JD, JI)
    # u = T u_I + s: the prescribed speeds (symbols until ``loops._prescribe``) and what the
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
    lam = ca.SX.zeros(loops.phi.shape[0])
    if P:
        A = ca.horzcat(J.T, ca.SX.eye(nv)[:, P])
        both = ca.solve(A.T @ A, A.T @ (M @ udot + bias))
        if loops.rows:
            lam[loops.rows] = both[:len(loops.rows)]
        lam = ca.vertcat(lam, both[len(loops.rows):])
    elif loops.rows:
        lam[loops.rows] = ca.solve(J @ J.T, J @ (M @ udot + bias))
    dep_q = [k for k, v in asm.speed_of.items() if v in set(dep)]
    Pq = {m.coordinate for m in asm.prescribed.values()}
    qnames, unames = asm.coordinate_names, asm.speed_names
    qunits, uunits = asm.coordinate_units, asm.speed_units
    note_rows = (f"{len(loops.rows)} independent closure equations"
                 + (f" ({loops.phi.shape[0] - len(loops.rows)} redundant dropped)"
                    if loops.phi.shape[0] > len(loops.rows) else ""))
    start = loops.f_start
    rows = loops.rows
    if formulation == "baumgarte":
        u_i = ca.SX.sym("u_i", len(ind))
        f_u = ca.Function("u_start", [q, u_i, asm.p], [ca.substitute(
            T @ u_i + s_vel, take_rows(u, P), take_rows(asm.u_start, P))])
        all_q = [k for k in range(q.shape[0]) if k not in Pq]
        all_u = [k for k in range(nv) if k not in set(P)]

        def initial(p):
            qc = loops.close(p)
            _, u0 = start(p)
            u0 = loopstart.speeds(loops, qc, np.asarray(u0, dtype=float).ravel(), p)
            un = np.asarray(f_u(qc, u0[ind], p))
            return np.concatenate([qc[all_q], un.ravel()[all_u]]), np.zeros(0)
        note = (f"kinematic loops, Baumgarte formulation: all {len(all_q)} coordinates "
                f"and {len(all_u)} speeds are states ({len(ind)} degrees of freedom; "
                f"{note_rows}, stabilised at rate {rate:g}/s)")
        return Equations(ca.vertcat(take_rows(q, all_q), take_rows(u, all_u)), ca.SX(0, 1),
                         ca.vertcat(take_rows(asm.qdot, all_q), take_rows(udot, all_u)),
                         ca.SX(0, 1), [qnames[k] for k in all_q] + [unames[k] for k in all_u],
                         [qunits[k] for k in all_q] + [uunits[k] for k in all_u], [], [], u,
                         udot, "baumgarte", note, len(rows), loops.phi.shape[0] - len(rows),
                         initial, phi, lam, dependent_jacobian=JD,
                         dependent_names=[unames[k] for k in dep])
    keep_q = [k for k in range(q.shape[0]) if k not in set(dep_q) | Pq]
    u_full = ca.densify(T @ take_rows(u, ind) + s_vel)
    sub = lambda e: ca.substitute(e, u, u_full)     # noqa: E731
    x = ca.vertcat(take_rows(q, keep_q), take_rows(u, ind))
    z = take_rows(q, dep_q)
    ode = ca.vertcat(sub(take_rows(asm.qdot, keep_q)), sub(udot_i))

    def initial(p, projected=False):
        qc = loops.close(p)
        _, u0 = start(p)
        u0 = np.asarray(u0, dtype=float).ravel()
        u_dep_given = [k for k in dep if asm.u_given[k] and u0[k] != 0]
        if u_dep_given:
            raise ModelError(
                f"qd0 of {', '.join(unames[k] for k in u_dep_given)}: this speed is "
                f"fixed by the loop closure (it is a dependent coordinate); give the "
                f"initial speed of an independent coordinate "
                f"({', '.join(unames[k] for k in ind)}) instead")
        u0 = loopstart.speeds(loops, qc, u0, p)
        if projected:
            return np.concatenate([qc[keep_q], qc[dep_q], u0[ind]]), np.zeros(0)
        return np.concatenate([qc[keep_q], u0[ind]]), qc[dep_q]
    if formulation == "projected" and dep:
        return projected(loops, x, z, ode, keep_q, dep_q, ind, sub, u_full, udot, udot_i,
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
                     loops.phi.shape[0] - len(rows), initial, phi, sub(lam),
                     dependent_jacobian=JD if dep else None,
                     dependent_names=[unames[k] for k in dep])


def newton(residual, z, steps=PROJECTION_STEPS):
    """``z`` after ``steps`` Newton steps on ``residual(z) = 0``, written out in SX."""
    jac = ca.jacobian(residual, z)
    out = z
    for _ in range(steps):
        out = out - ca.solve(ca.substitute(jac, z, out), ca.substitute(residual, z, out))
    return out


def take_rows(m, index):
    """Rows ``index`` of an SX matrix: SX(0, columns) when there are none (CasADi's own
    indexing of a 1 x 1 matrix by an empty list gives 1 x 0)."""
    return m[index, :] if index else ca.SX(0, m.shape[1])


def take_cols(m, index):
    """Columns ``index`` of an SX matrix: SX(rows, 0) when there are none."""
    return m[:, index] if index else ca.SX(m.shape[0], 0)
