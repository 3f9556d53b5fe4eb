"""Time events: the instants, known before a run, where a node of the equations that reads
time alone switches (``kinetwork.equations.relations``): a Step, the breakpoints of a Table,
the phases of a KinematicPTP, ``if_else(t < t0 + 0.1, ...)``.

A node whose indicator is affine in t (nearly all: ``t - 0.5``, ``t - t0 - d``, a
breakpoint) switches where that line crosses zero, or for ``floor``, ``ceil`` and ``fmod``
where it crosses a whole number: those instants are exact. Any other (``sin(w*t) > 0.5``) is
scanned at SCAN points over the run, and between two of them a switch is found where the
indicator changes sign, or where it has an extremum (its derivative changes sign) beyond
zero: two switches close together, a pulse shorter than the scan's spacing. An indicator at
zero over a stretch (a max of two equal values) switches nothing there, only where it leaves
zero. Each is then
located by Brent's method to about 1e-15 s. (A curved pulse so narrow that its indicator and
derivative are flat zero at the scan's points, exp(-((t - t0)/1e-6)^2), is not seen: write
such a pulse's edges as relations on t, which are exact.)
"""

import math

import numpy as np

from ..errors import ModelError
from ..equations.relations import LEVELS
from ..equations.system import mapped
from .roots import brentq

#: points over a run at which indicators not affine in t are looked at
SCAN = 4096
#: time events in one run at most (bounded work: a fmod of a period of a nanosecond)
MAX_TIME_EVENTS = 1_000_000
#: instants closer than this (relative to the time, and at least absolutely) are one
SAME_INSTANT = 1e-13


class Schedule:
    """The time events of one run: ``times``, sorted, in (t_start, t_end)."""

    def __init__(self, relations, p, t_start, t_end):
        self.t_start, self.t_end = float(t_start), float(t_end)
        found = []
        for f, affine, knots in relations.tables:
            found.extend(self._table(f, affine, knots, p))
        if len(relations.time):
            f = relations.f_time
            k = len(relations.time)
            levels = np.array([relations.ops[i] in LEVELS for i in relations.time], dtype=bool)

            def values(t):
                return np.asarray(f(t, p), dtype=float).reshape(k, 2)
            start = values(self.t_start)
            for j in np.flatnonzero(relations.affine):
                found.extend(self._affine(start[j], levels[j]))
            others = np.flatnonzero(~relations.affine)
            if len(others):
                found.extend(self._scan(f, p, k, others, levels, values, found))
        times = np.sort(np.asarray(found, dtype=float))     # (repeats: dropped below)
        times = times[(times > self.t_start + _gap(self.t_start)) &
                      (times < self.t_end - _gap(self.t_end))]
        if len(times) > 1:               # one instant, however it was reached
            keep = np.concatenate([[True], np.diff(times) > _gap(times[1:])])
            times = times[keep]
        self.times = times

    def _count(self, n):
        if n > MAX_TIME_EVENTS:
            raise ModelError(f"more than {MAX_TIME_EVENTS} time events in "
                             f"[{self.t_start:g}, {self.t_end:g}] s (a period far shorter "
                             f"than the run, or a table of that many rows): wrap the fast "
                             f"part in noEvent(...) or shorten the run")

    def _affine(self, row, level):
        """The switches of a node whose indicator is g0 + rate (t - t_start)."""
        g0, rate = row
        if rate == 0 or not np.isfinite(rate) or not np.isfinite(g0):
            return []
        if not level:
            return [self.t_start - g0 / rate]
        wholes = _wholes(g0, g0 + rate * (self.t_end - self.t_start))
        self._count(len(wholes))
        return list(self.t_start + (np.arange(wholes.start, wholes.stop) - g0) / rate)

    def _table(self, f, affine, knots, p):
        """Where the argument of a long Table read in time (``f``: (t, p) -> (argument,
        its rate)) crosses one of its knots: in closed form where the argument is affine in
        t, else on the scan's points (the knots' positions interpolated, whole numbers at
        the knots, crossed as a level)."""
        self._count(len(knots))
        a0, rate = (float(v) for v in f(self.t_start, p))
        if affine:
            if rate == 0 or not np.isfinite(rate) or not np.isfinite(a0):
                return []
            return list(self.t_start + (knots - a0) / rate)

        def at(t, shift=0.0):
            return float(_position(float(f(t, p)[0]), knots)) - shift
        grid = np.linspace(self.t_start, self.t_end, SCAN + 1)
        args = np.asarray(mapped(f, len(grid))(grid[None, :], p)[0], dtype=float).ravel()
        level = _position(args, knots)
        return self._located([(at, grid[a], grid[a + 1], level[a], level[a + 1], True)
                              for a in range(len(grid) - 1)])

    def _scan(self, f, p, k, others, levels, values, known):
        """The switches of the nodes ``others`` (not affine in t), on SCAN points and the
        instants ``known`` already (where their indicators may jump)."""
        grid = np.union1d(np.linspace(self.t_start, self.t_end, SCAN + 1),
                          [t for t in known if self.t_start < t < self.t_end])
        table = np.asarray(mapped(f, len(grid))(grid[None, :], p), dtype=float)
        table = table.reshape(k, len(grid), 2)        # (k, 2n): [g, rate] per time
        spans = []                  # (indicator, ta, tb, ga, gb, level): monotone pieces
        for j in others:
            g, rate = table[j, :, 0], table[j, :, 1]
            level = levels[j]

            def at(t, j=j, shift=0.0):
                return values(t)[j, 0] - shift

            def slope(t, j=j):
                return values(t)[j, 1]
            for a in range(len(grid) - 1):
                t0, t1, g0, g1 = grid[a], grid[a + 1], g[a], g[a + 1]
                if not (np.isfinite(g0) and np.isfinite(g1)):
                    continue
                ends = [(t0, g0)]
                if rate[a] * rate[a + 1] < 0:           # an extremum between: look at it
                    try:
                        tm = brentq(slope, t0, t1, xtol=1e-15, maxiter=200)
                        ends.append((tm, at(tm)))
                    except ValueError:              # the rate does not change sign there
                        pass
                ends.append((t1, g1))
                spans.extend((at, ta, tb, ga, gb, level)
                             for (ta, ga), (tb, gb) in zip(ends, ends[1:]))
        return self._located(spans)

    def _located(self, spans):
        """The crossings of monotone pieces ``(indicator, ta, tb, ga, gb, level)``, counted
        from their ends' values first: a count beyond MAX_TIME_EVENTS is refused before a
        single one is located (a 1e-8 s period over 1 s: at once, not after a million
        root finds)."""
        self._count(sum(_n_crossings(ga, gb, level) for _, _, _, ga, gb, level in spans))
        out = []
        for at, ta, tb, ga, gb, level in spans:
            out.extend(_crossings(at, ta, tb, ga, gb, level))
        return out

    def next(self, t):
        """The first time event after t (beyond the same instant), or None."""
        i = np.searchsorted(self.times, t + _gap(t), side="right")
        return float(self.times[i]) if i < len(self.times) else None


def _wholes(a, b):
    """The whole numbers strictly between a and b (in either order), as a range: counted
    without being listed."""
    low, high = sorted((a, b))
    return range(math.floor(low) + 1, math.ceil(high))


def _n_crossings(ga, gb, level):
    """How many crossings ``_crossings`` finds between ends of values ga and gb."""
    if not level:
        return int((ga == 0.0 and gb != 0.0) or ga * gb < 0)
    if not (np.isfinite(ga) and np.isfinite(gb)):
        return 0
    return len(_wholes(ga, gb))


def _crossings(at, ta, tb, ga, gb, level):
    """Where the indicator ``at`` crosses zero (a level: a whole number) between ta and tb,
    monotone there, with values ga and gb at the ends."""
    if not level:
        if ga == 0.0:
            # zero all along (a max of two equal values: a Brake's normal force before it
            # is applied) switches nothing; else where it leaves zero
            return [_leaves_zero(at, ta, tb)] if gb != 0.0 else []
        if ga * gb < 0:
            return [brentq(at, ta, tb, xtol=1e-15, rtol=4 * np.finfo(float).eps,
                           maxiter=200)]
        return []
    found = []
    for whole in _wholes(ga, gb):
        found.append(brentq(lambda t, w=whole: at(t, shift=w), ta, tb, xtol=1e-15,
                            rtol=4 * np.finfo(float).eps, maxiter=200))
    return found


def _leaves_zero(at, ta, tb):
    """Where the indicator ``at``, zero at ta and not at tb, leaves zero: at ta itself when
    it rises from there, later when it holds at zero first (it then jumps, at an instant of
    another node's)."""
    low, high = ta, tb
    while high - low > 4 * np.finfo(float).eps * max(1.0, abs(high)):
        mid = low + (high - low) / 2
        if mid <= low or mid >= high:
            break
        if at(mid) == 0.0:
            low = mid
        else:
            high = mid
    return high


def _position(a, knots):
    """Where ``a`` lies among ``knots`` (at least two): i at knot i, linear between them,
    and beyond the ends rising on within half a knot (crossing no other whole number)."""
    n = len(knots)
    inside = np.interp(a, knots, np.arange(n, dtype=float))
    with np.errstate(over="ignore"):
        below = -0.5 * -np.expm1((a - knots[0]) / (knots[1] - knots[0]))
        above = n - 1 + 0.5 * -np.expm1(-(a - knots[-1]) / (knots[-1] - knots[-2]))
    return np.where(a < knots[0], below, np.where(a > knots[-1], above, inside))


def _gap(t):
    """The width of one instant at t."""
    return SAME_INSTANT * np.maximum(1.0, np.abs(t))
