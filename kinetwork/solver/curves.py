"""Curves events are located on (``events.py``): the cubic Hermite curve through states and
their rates (``Hermite``, or ``Steps``, made a step at a time), checked against the equations;
the roots of an indicator along one (``root``: from the cubic through its values and rates,
settled by Newton's steps; ``search``: Brent's method over a whole interval); and cubics.
"""

import bisect

import numpy as np

from .roots import brentq

#: where, as fractions of the interval, an indicator that starts at zero after a restart is
#: looked for above zero (it leaves zero rising: first right after the start)
SCAN = np.array([1e-12, 1e-9, 1e-6, 1e-3, *np.arange(1, 16) / 16])
#: how close to the solution, as a fraction of the solver's tolerances, a curve is taken as it
#: is (its states are the event's): as close as the integration's own points are, which
#: CVODES interpolates between its steps (right after a start, at order one or two, to about
#: half its tolerances on EngineV6)
FIT = 1.0
#: Newton's steps at most on an indicator along a curve's step (``curves.root``)
ROOT_STEPS = 8


def cubic(g0, g1, r0, r1):
    """The coefficients (of 1, s, s^2, s^3) of the cubic in s in [0, 1] with values g0, g1
    and slopes r0, r1 (per unit of s) at its ends."""
    return (g0, r0, 3 * (g1 - g0) - 2 * r0 - r1, 2 * (g0 - g1) + r0 + r1)


def cubic_low(T, g, rate, j):
    """The lowest value on step j of the cubic through values ``g`` and rates ``rate`` at
    the points T."""
    h = T[j + 1] - T[j]
    c = cubic(g[j], g[j + 1], rate[j] * h, rate[j + 1] * h)
    # where its slope c1 + 2 c2 u + 3 c3 u^2 is zero (numpy's roots: 0.2 ms a call)
    A, B, C = 3 * c[3], 2 * c[2], c[1]
    if A:
        disc = B * B - 4 * A * C
        inner = [] if disc < 0 else [(-B + r) / (2 * A) for r in (disc ** 0.5, -disc ** 0.5)]
    else:
        inner = [-C / B] if B else []
    return min(g[j], g[j + 1], *(c[0] + u * (c[1] + u * (c[2] + u * c[3]))
                                 for u in inner if 0 < u < 1))


def cubic_root(c, s):
    """A root in [0, 1] of the cubic of coefficients ``c`` (``cubic``), positive at 0 and
    at or below zero at 1: Newton's steps from ``s`` (the straight line's root), kept within
    the bracket that narrows as they go."""
    lo, hi = 0.0, 1.0
    for _ in range(ROOT_STEPS):
        value = c[0] + s * (c[1] + s * (c[2] + s * c[3]))
        if value > 0:
            lo = s
        else:
            hi = s
        slope = c[1] + s * (2 * c[2] + 3 * s * c[3])
        nxt = s - value / slope if slope else (lo + hi) / 2
        if not lo <= nxt <= hi:
            nxt = (lo + hi) / 2
        if abs(nxt - s) <= 1e-15:
            return nxt
        s = nxt
    return s


def root(level, T, g, rate, j):
    """The time an indicator, ``level(t)`` along a curve through points at times T, crosses
    zero on the step j (above zero at T[j], at or below at T[j + 1]; its values ``g`` and
    rates ``rate`` at the points), on the side where it has crossed: from the root of the
    cubic through those values and rates (off the indicator's own by about h^4 times its
    fourth derivative, on a step of h), Newton's steps on the indicator along the curve with
    that cubic's slope, bracketed; Brent's method if they do not settle."""
    a, b = float(T[j]), float(T[j + 1])
    h = b - a
    c = cubic(g[j], g[j + 1], rate[j] * h, rate[j + 1] * h)
    t = a + h * cubic_root(c, g[j] / (g[j] - g[j + 1]))
    tiny = 4 * np.finfo(float).eps * max(1.0, abs(b))
    for _ in range(ROOT_STEPS):
        value = level(t)
        if value <= 0:
            b = t
        else:
            a = t
        if b - a <= 2 * tiny:
            return b
        u = (t - T[j]) / h
        slope = (c[1] + u * (2 * c[2] + 3 * u * c[3])) / h
        step = -value / slope if slope < 0 else np.nan
        if value <= 0 and -step <= tiny:
            return b                        # at the root, to rounding
        t = t + step + (tiny if value > 0 else 0.0)
        if not a < t < b:
            t = (a + b) / 2
    if not level(a) > 0 >= level(b):
        return b
    t = brentq(level, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    return t if level(t) <= 0 else min(b, t + tiny)


def search_steps(events, curve, T, X, crossed, dipped):
    """``search`` for ``events`` (an ``events.Events``) along ``curve`` through the points
    (T, X) of one integration, each indicator on the step its values at the points (one
    mapped call of the indicators alone) bracket: a crossing on the step where it is first at or below zero, from the
    root of the cubic through its values and rates there (``curves.root``); a dip, where
    it is lowest, only when that cubic reaches zero there (else it stays above). The
    rates, which read the whole equations, at those steps' points alone (one more call).
    An indicator at or below zero at T[0] (a restart's) is searched over the whole."""
    G = events._level_rows(T, X)
    windows = []                            # (indicator, a dip, first point, last point)
    for i, dip in [*((i, False) for i in crossed), *((i, True) for i in dipped)]:
        below = np.flatnonzero(G[1:, i] <= 0)
        if G[0, i] <= 0:
            windows.append((i, dip, 0, len(T) - 1))
        elif len(below):
            windows.append((i, False, below[0], below[0] + 1))
        elif dip:
            low = int(np.argmin(G[:, i]))
            windows.append((i, True, max(low - 1, 0), min(low + 1, len(T) - 1)))
    steps = [w for w in windows if w[3] - w[2] <= 2]
    points = sorted({k for w in steps for k in range(w[2], w[3] + 1)})
    R = np.full(G.shape, np.nan)
    if points:
        R[points] = events._rows(T[points], X[points])[1]
    best = None
    for i, dip, a, b in sorted(windows, key=lambda w: w[2]):
        if best is not None and T[a] >= best[0]:
            break
        got = None
        if b - a > 2:                       # the whole interval, after a restart
            got = search(lambda t, k: events.levels(t, curve(t))[k],
                         lambda t, k: events.indicators(t, curve(t))[1][k], T[a], T[b],
                         *(([], [i]) if dip else ([i], [])))
        elif not dip:
            got = (root(lambda t, i=i: events.levels(t, curve(t))[i], T, G[:, i], R[:, i],
                        a), i)
        elif min(cubic_low(T, G[:, i], R[:, i], j) for j in range(a, b)) <= 0:
            got = search(lambda t, k: events.levels(t, curve(t))[k],
                         lambda t, k: events.indicators(t, curve(t))[1][k],
                         T[a], T[b], [], [i])
        if got is not None and (best is None or got[0] < best[0]):
            best = got
    return best


def search(g, rate, t0, t1, crossed, dipped):
    """The earliest crossing in (t0, t1] of the indicators ``g(t, i)``, with rates
    ``rate(t, i)``: (time, element) or None. ``crossed``: elements at or below zero at t1;
    ``dipped``: above zero at both ends with a minimum between, which cross if it reaches
    zero. The time is on the side of the root where the indicator has crossed."""
    tight = dict(xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    best = None
    for i in dipped:
        if not rate(t0, i) < 0 < rate(t1, i):     # integrated again: not quite as sampled
            continue
        t_min = brentq(rate, t0, t1, args=(i,), **tight)
        if g(t_min, i) > 0:
            continue                    # a minimum above zero: no event
        t_i = brentq(g, t0, t_min, args=(i,), **tight)
        if g(t_i, i) > 0:
            t_i = min(t_min, t_i + max(abs(t_i), 1.0) * 4 * np.finfo(float).eps)
        if best is None or t_i < best[0]:
            best = (t_i, i)
    for i in crossed:
        start = t0
        if g(t0, i) <= 0:         # at zero after a restart: where it was above zero
            start = next((t for t in t0 + (t1 - t0) * SCAN if g(t, i) > 0), None)
            if start is None:     # it fell back at once: an event where it started
                if best is None or t0 < best[0]:
                    best = (t0, i)
                continue
        if g(t1, i) >= 0.0:
            # at t1 itself, or (integrated again from t0) just short of crossing there
            t_i = t1
        else:
            t_i = brentq(g, start, t1, args=(i,), **tight)
            # the side of the root where the indicator has crossed
            if g(t_i, i) > 0:
                t_i = min(t1, t_i + max(abs(t_i), 1.0) * 4 * np.finfo(float).eps)
        if best is None or t_i < best[0]:
            best = (t_i, i)
    return best


class Steps:
    """The cubic Hermite curve through states X at times T (the points of one integration),
    made a step at a time where it is read: each step's two rates in one call of
    ``rates(T, X)``, not those of every point."""

    def __init__(self, T, X, rates):
        self.T, self.X, self.rates = [float(t) for t in T], X, rates
        self._made = {}

    def piece(self, j):
        """The curve's step j, as a ``Hermite``."""
        if j not in self._made:
            T, X = np.asarray(self.T[j:j + 2]), self.X[j:j + 2]
            self._made[j] = Hermite(T, X, self.rates(T, X))
        return self._made[j]

    def step(self, t):
        """The step the curve's time ``t`` is on."""
        return min(max(bisect.bisect_right(self.T, t) - 1, 0), len(self.T) - 2)

    def __call__(self, t):
        return self.piece(self.step(t))(t)

    def fits(self, rates, tol, step):
        """``Hermite.fits`` on the one ``step``."""
        return self.piece(step).fits(rates, tol)


class Hermite:
    """The cubic Hermite curve through states X at times T with rates F, as a cubic in
    s = (t - T[j]) / h on each step h. Its error, h^4/384 |d4x/dt4| at most, is read off
    the equations: the curve's rate less the equations' at points of each step."""

    def __init__(self, T, X, F):
        self.T = [float(t) for t in T]
        h = np.diff(T)[:, None]
        x0, x1, f0, f1 = X[:-1], X[1:], h * F[:-1], h * F[1:]
        self.cubic = (x0, f0, 3 * (x1 - x0) - 2 * f0 - f1, 2 * (x0 - x1) + f0 + f1)
        self.scale = np.max(np.abs(X), axis=0)

    def step(self, t):
        """The step the curve's time ``t`` is on."""
        return min(max(bisect.bisect_right(self.T, t) - 1, 0), len(self.T) - 2)

    def _step(self, t):
        j = self.step(t)
        return j, (t - self.T[j]) / (self.T[j + 1] - self.T[j])

    def __call__(self, t):
        j, s = self._step(t)
        a, b, c, d = (k[j] for k in self.cubic)
        return a + s * (b + s * (c + s * d))

    def fits(self, rates, tol, step=None):
        """Whether the curve is within FIT of the tolerances ``tol`` = (rtol, atol) of the
        solution through its points: its error at most h/6 times its rate's distance from
        the equations' (``rates(T, X)``, at many points at once) at a quarter, half and three
        quarters of each step (a quartic error's, largest at the middle, is h/6 times its
        rate's at the quarters); of the one ``step`` when given."""
        rtol, atol = tol
        a, b, c, d = self.cubic
        T = np.asarray(self.T)
        if step is not None:
            a, b, c, d = (k[step:step + 1] for k in self.cubic)
            T = T[step:step + 2]
        h = np.diff(T)[:, None]
        points, defects = [], []
        for s in (0.25, 0.5, 0.75):
            points.append((T[:-1] + s * h[:, 0], a + s * (b + s * (c + s * d))))
            defects.append((b + s * (2 * c + 3 * s * d)) / h)
        times = np.concatenate([p[0] for p in points])
        states = np.vstack([p[1] for p in points])
        defect = np.vstack(defects) - rates(times, states)
        error = np.abs(defect) * np.tile(h, (3, 1)) / 6
        return bool(np.all(error <= FIT * (atol + rtol * self.scale)))
