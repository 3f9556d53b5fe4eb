"""The numeric search for a configuration that closes every kinematic loop.

Gauss-Newton with least-squares steps, backtracking on the residual; where it stalls (a dead
centre), Levenberg-Marquardt from the guesses and from a fixed set of perturbed starts, the
closing assembly nearest the guesses taken; and whether one loop closes by itself, to name
the loops that cannot. ``loops._Loops.close`` drives it; each function takes the _Loops.
"""

import casadi as ca
import numpy as np

#: a closure residual below this (m, and rotation-matrix entries) counts as closed
CLOSED = 1e-10
#: starts of the assembly search where Gauss-Newton stalls: the guesses, then perturbed ones
SEARCH_STARTS = 24


def closed(r):
    """Whether a closure residual is closed to round-off."""
    return bool(np.isfinite(r).all()) and np.max(np.abs(r), initial=0.0) < CLOSED * 1e-2


def gauss_newton(loops, q, p, rows=None, free=None):
    """Gauss-Newton with least-squares steps on the closure (its ``rows``, in the ``free``
    coordinates), backtracking on |residual|: (q, residual) where it stops."""
    free = loops.free if free is None else free
    pick = (lambda r: r) if rows is None else (lambda r: r[rows])
    q = q.copy()
    r = pick(np.asarray(loops.f_phi(q, p)).ravel())
    for _ in range(100):
        if closed(r):
            break
        J = np.asarray(loops.f_jac(q, p))
        J = J[:, [loops.free.index(i) for i in free]]
        J = J if rows is None else J[rows]
        step = np.linalg.lstsq(J, -r, rcond=None)[0] if free else np.zeros(0)
        for scale in (1.0, 0.5, 0.25, 0.1, 0.01):        # backtrack on |residual|
            trial = q.copy()
            trial[free] += scale * step
            r_trial = pick(np.asarray(loops.f_phi(trial, p)).ravel())
            if np.linalg.norm(r_trial) < np.linalg.norm(r):
                q, r = trial, r_trial
                break
        else:
            break
    return q, r


def search(loops, start, p, q_best, r_best, rows=None, free=None):
    """Levenberg-Marquardt from the start and from SEARCH_STARTS perturbed starts
    (deterministic); the closing assembly nearest the start, else the best fit."""
    from scipy.optimize import least_squares
    free = loops.free if free is None else free
    if not free:
        return q_best, r_best
    pick = (lambda r: r) if rows is None else (lambda r: r[rows])
    cols = [loops.free.index(i) for i in free]

    def residual(z):
        q = start.copy()
        q[free] = z
        return pick(np.asarray(loops.f_phi(q, p)).ravel())

    def jacobian(z):
        q = start.copy()
        q[free] = z
        J = np.asarray(loops.f_jac(q, p))[:, cols]
        return J if rows is None else J[rows]
    rng = np.random.default_rng(0)
    scale = np.where(np.array(loops.asm.coordinate_units)[free] == "m",
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
        q, r = gauss_newton(loops, q, p, rows, free)          # polish to round-off
        if closed(r):
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


def alone(loops, loop, start, p):
    """Whether loop ``loop`` closes by itself (its rows, the free coordinates in it)."""
    rows = [k for k, i in enumerate(loops.owner) if i == loop]
    pattern = np.asarray(ca.DM(loops.f_jac.sparsity_out(0), 1))[rows]
    free = [i for c, i in enumerate(loops.free) if pattern[:, c].any()]
    q, r = gauss_newton(loops, start, p, rows, free)
    if not closed(r):
        q, r = search(loops, start, p, q, r, rows, free)
    return closed(r)


def _wrapped(d, scale):
    """Differences of coordinates, angles (scale pi) taken modulo 2 pi."""
    angle = scale == np.pi
    return np.where(angle, (d + np.pi) % (2 * np.pi) - np.pi, d)
