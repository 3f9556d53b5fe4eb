"""The watch over kinematic loops: where the Jacobian of the closure in the dependent speeds
turns singular (a dead point: a four-bar that cannot go round, links folding flat), the
partition of the speeds no longer holds, and every formulation must stop there, saying so."""

import numpy as np

from ..equations.system import mapped

#: a kinematic loop whose Jacobian in the dependent speeds has a larger condition number is
#: at a singular configuration
SINGULAR_CONDITION = 1e8
#: ... and near one, for the message of a failure, beyond this
NEAR_SINGULAR_CONDITION = 1e4


def conditioning(run, X):
    """(condition number, sign of the determinant) of the loops' Jacobian in the
    dependent speeds at each full state in X; None for a model without such loops."""
    f = run.system.f_dependent
    if f is None or not len(X):
        return None
    n = f.size1_out(0)
    J = np.asarray(mapped(f, len(X))(np.asarray(X).T, run.p)).reshape(n, len(X), n)
    J = np.transpose(J, (1, 0, 2))
    with np.errstate(all="ignore"):
        s = np.linalg.svd(J, compute_uv=False)
        cond = np.where(s[:, -1] > 0, s[:, 0] / s[:, -1], np.inf)
        sign = np.linalg.slogdet(J)[0]
    return cond, sign


def singular(run, X, before):
    """Index of the first row of X at which the loops pass a singular configuration (the
    dependent Jacobian turns singular, or its determinant changes sign from the row
    ``before``), or None."""
    both = conditioning(run, np.vstack([before[None, :], X]))
    if both is None:
        return None
    cond, sign = both
    for i in range(1, len(cond)):
        if not np.isfinite(cond[i]) or cond[i] > SINGULAR_CONDITION or \
                (sign[i] * sign[i - 1] < 0):
            return i - 1
    return None


def singular_words(run, t):
    system = run.system
    loops = "; ".join(" - ".join(c.loop) for c in system.topology.cuts)
    return (f"the kinematic loop ({loops}) reaches a singular configuration (a dead "
            f"point) at about t = {t:g} s: the closure no longer fixes the dependent speeds "
            f"({', '.join(system.dependent_names)}), so the mechanism folds flat, locks or "
            f"branches there; choose other independent coordinates (give q0 of the joints "
            f"that drive it, or mark another joint cut), or stop before it")


def watch(run, X, new, failure):
    """(rows, failure): the new rows up to a singular configuration of the loops, and the
    failure that stops the run there, if any."""
    if not len(new):
        return new, failure
    i = singular(run, new, X[-1])
    if i is None:
        return new, failure
    return new[:i], singular_words(run, float(run.grid[len(X) + i]))


def near_singular(run, X, grid):
    """A note for a failure of a model with loops that ended at a singular configuration: the
    Jacobian in the dependent speeds is ill-conditioned at the last output, or its
    determinant, extrapolated from the last two outputs, vanishes before the next one (a
    dead point that the integrator could not pass)."""
    both = conditioning(run, X[-2:])
    if both is None:
        return ""
    cond, _ = both
    f, n = run.system.f_dependent, run.system.f_dependent.size1_out(0)
    det = [float(np.linalg.det(np.asarray(f(row, run.p)).reshape(n, n))) for row in X[-2:]]
    folding = len(det) == 2 and det[0] * det[1] > 0 and abs(det[1]) < abs(det[0]) and \
        abs(det[1]) < abs(det[0] - det[1])
    if cond[-1] < NEAR_SINGULAR_CONDITION and not folding:
        return ""
    loops = "; ".join(" - ".join(c.loop) for c in run.system.topology.cuts)
    return (f"; there (t = {grid[len(X) - 1]:g} s) the kinematic loop ({loops}) is at a "
            f"singular configuration, a dead point: its Jacobian in the dependent speeds "
            f"({', '.join(run.system.dependent_names)}) has condition number "
            f"{cond[-1]:.2g} and its determinant goes to zero, so the mechanism folds flat, "
            f"locks or branches")
