"""Closing a model's kinematic loops at any point its independent coordinates give.

A model with loops, in the partition formulation, has differential states x (the independent
coordinates and speeds) and dependent coordinates z fixed by the closure g(x, z, p) = 0.
An analysis at a point (``kn.linearize``, ``kn.equilibrium``) names x; z must follow on the
branch of the assembly the model starts on (a four-bar crank at 1.2 rad: the coupler and
rocker where the start's assembly carries them, not the mirror image).

``close`` walks from an assembled configuration (the model's start, or one the caller has)
to the asked x along the straight line between them: at each step a predictor along the
tangent dz/dx = -g_z^-1 g_x, then Newton with a backtracking line search on |g|; a step that
does not converge fast, or lands away from its prediction (another branch), is halved. What
cannot be closed (the asked point beyond where the mechanism assembles, or a change point
where the dependent coordinates stop following) is refused naming the loop and the residual
left, and how far along the way the walk got.

The closure at given states is here too: the algebraic variables polished onto it
(``polish``), its residual, and where an assembly closed in closed form turns singular.
"""

import weakref

import casadi as ca
import numpy as np

from ..errors import ModelError
from .pointwise import mapped, pointwise

#: the closure counts as closed below this (m, and rotation-matrix entries)
CLOSED = 1e-10
#: Newton stops here
TIGHT = 1e-13
#: Newton iterations per step; beyond, the step is halved
ITERATIONS = 12
#: the walk gives up when its step falls below this fraction of the way
SMALLEST = 1e-7
#: and after this many steps (bounded work for any input)
STEPS = 2000

_CLOSERS = weakref.WeakKeyDictionary()


def closer(system):
    """The Closer of a System with algebraic variables (cached with it)."""
    if system not in _CLOSERS:
        _CLOSERS[system] = Closer(system)
    return _CLOSERS[system]


class Closer:
    """The closure of ``system``'s loops and its Jacobians, as one compiled Function."""

    def __init__(self, system):
        eq, asm = system.eq, system.asm
        self.system = system
        g = eq.alg
        self.f = ca.Function("closure_at", [eq.x, eq.z, asm.p],
                             [ca.densify(g), ca.densify(ca.jacobian(g, eq.z)),
                              ca.densify(ca.jacobian(g, eq.x))])
        loops = getattr(eq, "loops", None)
        rows = (eq.partition or [[]])[0] if loops is not None else []
        self.owner = [loops.owner[r] for r in rows] if rows else [0] * eq.alg.shape[0]
        self.loop_names = [", ".join(c.loop) for c, _ in asm.cuts] or ["the loops"]

    def _eval(self, x, z, p):
        g, gz, gx = self.f(x, z, p)
        return (np.asarray(g, dtype=float).ravel(), np.asarray(gz, dtype=float),
                np.asarray(gx, dtype=float))

    def newton(self, x, z, p):
        """(z, max |g|, converged) after Newton with a backtracking line search from z."""
        z = np.array(z, dtype=float)
        g, gz, _ = self._eval(x, z, p)
        norm = _norm(g)
        for _ in range(ITERATIONS):
            if norm <= TIGHT:
                break
            step = _solve(gz, -g)
            if step is None:
                return z, norm, False
            for scale in (1.0, 0.5, 0.25, 0.125, 0.0625):
                trial = z + scale * step
                gt, gzt, _ = self._eval(x, trial, p)
                nt = _norm(gt)
                if np.isfinite(nt) and nt < norm:
                    z, g, gz, norm = trial, gt, gzt, nt
                    break
            else:
                break
        return z, norm, norm <= CLOSED

    def close(self, x, p, start, where="at"):
        """The dependent coordinates at the differential states ``x`` on the branch of the
        assembled configuration ``start`` = (x0, z0), by continuation from it; ``where``
        names the input in a refusal."""
        x = np.asarray(x, dtype=float)
        x0, z0 = (np.asarray(v, dtype=float) for v in start)
        s, ds, z = 0.0, 1.0, z0.copy()
        for _ in range(STEPS):
            if s >= 1.0:
                return z
            ds = min(ds, 1.0 - s)
            here, there = x0 + s * (x - x0), x0 + (s + ds) * (x - x0)
            _, gz, gx = self._eval(here, z, p)
            tangent = _solve(gz, -gx @ (there - here))
            if tangent is None:
                break                           # a change point: z stops following x
            guess = z + tangent
            z_new, norm, ok = self.newton(there, guess, p)
            moved = np.max(np.abs(z_new - guess), initial=0.0)
            if ok and moved <= max(0.5 * np.max(np.abs(tangent), initial=0.0), 1e-9):
                s, z = s + ds, z_new
                ds *= 2.0
                continue
            ds /= 2.0
            if ds < SMALLEST:
                break
        self._refuse(x, x0, s, z, p, where)

    def _refuse(self, x, x0, s, z, p, where):
        """The ModelError of a walk that stalled at fraction ``s`` of the way."""
        sys = self.system
        _, gz, gx = self._eval(x0 + s * (x - x0), z, p)
        # what is left at the asked point itself, Newton from where the walk stalled
        z_end, left, _ = self.newton(x, z, p)
        g_end = self._eval(x, z_end, p)[0]
        by_loop = {}
        for i, v in zip(self.owner, np.abs(g_end)):
            by_loop[i] = max(by_loop.get(i, 0.0), v)
        bad = max(by_loop, key=by_loop.get) if by_loop else 0
        asked = ", ".join(f"{n} = {v:.6g}" for n, v, v0 in zip(sys.state_names, x, x0)
                          if v != v0)
        reached = ", ".join(f"{n} = {v0 + s * (v - v0):.6g}" for n, v, v0
                            in zip(sys.state_names, x, x0) if v != v0)
        singular = _solve(gz, -gx @ (x - x0)) is None
        raise ModelError(
            f"{where}: kinematic loop through {self.loop_names[bad]} cannot close at "
            f"{asked or 'the asked state'}: "
            f"followed from the assembled start on its branch, it closes only up to "
            f"{reached or 'the start'}"
            + (" (a change point: the dependent coordinates "
               f"{', '.join(sys.algebraic_names)} stop following there)" if singular else "")
            + f"; at the asked point a residual of {by_loop.get(bad, left):.3g} (m, or "
              f"rotation-matrix entries) is left: the mechanism does not assemble there")


def polish(system, X, p, t=None):
    """Full states X (n_points, n_states + n_algebraic) with the algebraic variables
    (dependent coordinates) Newton-corrected onto the closure to machine precision: the
    integrator solves them only to its tolerance. Equations that read time (a diode's
    circuit driven by a source in t) are polished at the times ``t`` of the rows, and
    not at all without them."""
    if not system.n_algebraic or not len(X):
        return X
    timed = ca.depends_on(system.eq.alg, system.asm.t)
    if timed and t is None:
        return X
    times = np.zeros(len(X)) if t is None else np.asarray(t, dtype=float)
    Z = pointwise(system._f_polish, X, p, times[:, None])[0]
    out = np.array(X, dtype=float)
    ok = np.all(np.isfinite(Z), axis=1)
    out[ok, system.n_states:] = Z[ok]
    return out


def closure_residual(system, X, p):
    """Largest |closure residual| of the kept loop equations at each row of full states X
    (``System.constraint_residual_p``); zeros for a model without loops."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    if system.eq.residual is None:
        return np.zeros(len(X))
    return pointwise(system._f_residual, X, p)[0].ravel()


def assembly_singular(system, times, X, p, margin=0.0):
    """(row, messages): the first row of full states X (at ``times``) at which an
    assembly that closes its loop in closed form is at (or past, or within ``margin``
    of) a singular position, and what is singular there; (None, []) where none is."""
    if system.f_assembly_checks is None or not len(X):
        return None, []
    X = np.atleast_2d(np.asarray(X, dtype=float))
    values = np.asarray(mapped(system.f_assembly_checks, len(X))(
        np.atleast_1d(times)[None, :], X.T, p)).T
    with np.errstate(invalid="ignore"):
        bad = ~(values > margin)
    rows = np.nonzero(bad.any(axis=1))[0]
    if not len(rows):
        return None, []
    return int(rows[0]), [f"{name} {'is at' if not margin else 'nears'} a singular "
                          f"position of its loop: {what}" for (name, what), b in
                          zip(system.assembly_check_names, bad[rows[0]]) if b]


def _norm(g):
    return float(np.max(np.abs(g), initial=0.0))


def _solve(A, b):
    """A^-1 b, or None where A is singular (to working precision)."""
    if A.size == 0:
        return np.zeros(0)
    try:
        s = np.linalg.svd(A, compute_uv=False)
        if not np.all(np.isfinite(A)) or s[-1] <= 1e-12 * max(s[0], 1.0):
            return None
        return np.linalg.solve(A, b)
    except np.linalg.LinAlgError:
        return None
