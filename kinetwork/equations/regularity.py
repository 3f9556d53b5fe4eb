"""Refusals of a System whose numbers cannot run: a mass matrix that is singular at the
start (a joint that moves no mass or inertia), and numbers beyond double precision.

The test of the mass matrix is a Cholesky factorisation with each joint's diagonal scaled to
one (``singular_directions``); ``System`` runs it once it is built (a tree), and the run's
driver names an overflow with ``overflow_message``.
"""

import casadi as ca
import numpy as np

from ..errors import ModelError


#: a joint whose articulated inertia (what it still moves with the joints beyond it free) is
#: below this fraction of its own inertia (what it moves with them locked), times the
#: number of joints, is taken as moving nothing: round-off in the factorisation is about
#: eps per joint, where a 1024-link point-mass chain's first joint keeps 3e-9 of its own
PIVOT_FLOOR = 64 * np.finfo(float).eps


def singular_directions(M):
    """The indices of the speeds that the mass matrix ``M`` cannot accelerate (empty when it
    is positive definite).

    The test is a Cholesky factorisation of M with each joint's diagonal scaled to one,
    eliminating the last joints first: on a tree whose joints come parents first, its pivots
    are the articulated inertias of the articulated-body algorithm, each relative to the
    joint's own (1 for a leaf; ~3/N^3 for the first joint of an N-link point-mass chain).
    A singular M has a zero pivot; a regular one has none, however wide its eigenvalues
    spread: the condition number of a chain's M in relative coordinates grows as N^4, and a
    bound on the smallest eigenvalue relative to the largest refused point-mass chains from
    192 links, which pinocchio and MuJoCo run. A joint with no inertia at all is named as
    it is; otherwise the directions of the scaled M's eigenvalues at the floor."""
    sym = (M + M.T) / 2
    n, d = len(sym), np.diag(sym)
    zero = [k for k in range(n) if not d[k] > 0]
    if zero:
        return zero
    s = 1 / np.sqrt(d)
    scaled = sym * s[:, None] * s[None, :]
    floor = PIVOT_FLOOR * n
    try:
        pivots = np.diag(np.linalg.cholesky(scaled[::-1, ::-1])) ** 2
        if np.min(pivots) > floor:
            return []
    except np.linalg.LinAlgError:
        pass
    values, vectors = np.linalg.eigh(scaled)
    null = vectors[:, values <= max(floor, values[0])]
    return [k for k in range(n) if np.max(np.abs(null[k])) > 1e-3]


#: a number beyond this in the state or its rate at the start is taken as an overflow to come
#: (its square is beyond double precision): no physical model has one
OVERFLOW = 1e150


def overflow_message(model, what, p, names):
    """Why a model whose numbers overflow double precision is refused, naming the largest
    parameter values."""
    big = sorted(zip(names, np.asarray(p, dtype=float)), key=lambda kv: -abs(kv[1]))[:3]
    return (f"{what} of {model.name!r} is not finite or beyond {OVERFLOW:g} at the initial "
            f"state: a number overflows double precision there (or a division by zero); check "
            f"the parameters" + (f" (largest: {', '.join(f'{k} = {v:g}' for k, v in big)})"
                                 if big else "") + " and the initial values")


def check_mass_matrix(system):
    """Refuse a mass matrix that is singular at the initial state (a joint that moves no
    mass or inertia: a chain of bodies with zero mass, a slider carrying nothing, a free
    body with no inertia about an axis), naming the joints it cannot accelerate, rather
    than integrating NaNs or, worse, zeros (``singular_directions``). Of a model with
    prescribed joints, the mass matrix of the others."""
    p = system.param_vector()
    x0 = system.initial_full_p(p)[0]
    # M column by column as inverse dynamics of unit accelerations (no speed, no
    # gravity): an O(n) expression, where CRBA's would be O(n^2) to build
    a, n = system.asm, len(system.speed_names)
    acc = ca.SX.sym("acc", n)
    f = ca.Function("M_columns", [a.q, acc, a.p], [a.mass_times(acc)])
    q0 = x0[:len(system.coordinate_names)] if system.eq.q is None else \
        np.asarray(ca.Function("q0", [a.t, system._x, a.p], [system.eq.q])(0, x0, p)).ravel()
    free = [k for k in range(n) if k not in a.prescribed]
    M = np.asarray(f.map(n)(q0, np.eye(n), p))[np.ix_(free, free)]
    if not free:
        return
    if not np.all(np.isfinite(M)):
        raise ModelError(overflow_message(system.model, "the mass matrix", p,
                                          system.param_names))
    involved = [system.speed_names[free[k]] for k in singular_directions(M)]
    if not involved:
        return
    joints = list(dict.fromkeys(n.rsplit(".", 1)[0] for n in involved))
    raise ModelError(f"the mass matrix is singular at the initial state: "
                     f"{', '.join(joints)} move(s) no mass or inertia in the direction of "
                     f"{', '.join(involved)} (give the bodies they carry mass or inertia, "
                     f"or lock the joint)", **system._fields_of(joints[0]))
