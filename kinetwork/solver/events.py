"""Events: where an element with modes (friction, stops: ``components/friction.py``) changes
mode, found, located and applied between the integrator's outputs.

The driver advances a method with ``Events.advance``: to the output times and to SAMPLES - 1
points between each two, or more, so that they are looked at LATTICE times a run at least
whatever its output grid, where the indicators (compiled with the model:
``equations/modes.py``) are looked at. An event is an indicator going from positive to zero
or below between two of those points, or one above zero at both but falling, then rising,
whose minimum between them (where its rate, a column of the same table, is zero) reaches
zero: a friction sticking for less than the sampled interval. It is located by Brent's
method on the indicator of the state integrated by the same method from the row before it
to the trial time (so the time is as exact as the integration, to about 1e-14 s in the
bracketing itself), the element says what its new mode is (``next_mode``) and whether its
relative speed jumps (an impact, a sticking: an impulse through the mechanism, along the
response of the state's rates to the element's force), modes that the change makes
inconsistent follow at the same instant, and the method starts afresh there. Events are
logged (time, component, kind) for ``res.stats["events"]``.

Two crossings between two sampled points, which cancel out, are seen when the indicator has
one minimum between them, not when it also has a maximum there (right after an event, an
indicator at zero counts as positive, so a bounce within the first interval is found). Runs
with events go in short chunks of at most EVENT_CHUNK output intervals, as what follows an
event in a chunk is computed again; a fixed-step method steps each sampled interval, so its
steps are SAMPLES times shorter than without events.
"""

import itertools
import math
from types import SimpleNamespace

import numpy as np

from ..errors import ModelError
from .compiled import numeric
from .methods import Failure

#: output intervals per chunk at most, in a run with events (what follows an event in a
#: chunk is computed again from it)
EVENT_CHUNK = 8
#: points per output interval at least where the indicators are looked at
SAMPLES = 4
#: the column of the indicator's rate in ``Modes.f_values`` (``equations/modes.py``)
RATE = 7
#: points over a run, at least, where the indicators are looked at (however sparse its
#: output grid: the events found must not depend on it)
LATTICE = 1000
#: events in one run at most: beyond, the run stops (a stop bouncing ever faster, chattering)
MAX_EVENTS = 100_000
#: mode changes at one instant at most (a cascade through coupled elements)
MAX_CASCADE = 50
#: frictions at rest at one instant whose modes are tried in every combination at most, when
#: changing the worst violation one at a time cycles (3**MAX_TOGETHER combinations)
MAX_TOGETHER = 8
#: events closer than SAME_INSTANT seconds count as at one instant; ZENO_LIMIT of them in a
#: row stop the run (modes chattering without time passing)
SAME_INSTANT = 1e-13
ZENO_LIMIT = 200
#: trial intervals shorter than this (relative to the time) are stepped by RK4 directly
SHORT = 1e-6
#: where, as fractions of the interval, an indicator that starts at zero after a restart is
#: looked for above zero (it leaves zero rising: first right after the start)
SCAN = np.array([1e-12, 1e-9, 1e-6, 1e-3, *np.arange(1, 16) / 16])


class Events:
    """The events of one run of a System with modes (``system.modes``)."""

    def __init__(self, run):
        self.run = run
        self.modes = modes = run.system.modes
        n = run.system.n_states
        self._values = numeric(modes.f_values, run.p, n)
        self._response = numeric_pair(modes.f_response, run.p)
        self._rhs = numeric(run.system.f_rhs, run.p, n)
        self.log = []
        self._last = (None, 0)          # time of the last event, events at it

    # -- numbers ---------------------------------------------------------------------------
    def values(self, t, x):
        """(k, 6): indicator, rel, w_rel, force, value0, value1 of every element."""
        k = len(self.modes.comps)
        return np.asarray(self._values(t, x)).reshape(k, -1)

    def _numbers(self, t, x, i, table=None):
        """What element i's ``first_mode`` and ``next_mode`` read."""
        table = self.values(t, x) if table is None else table
        comp = self.modes.comps[i]
        row = table[i]
        mode = int(round(x[self.modes.mode_index[i]]))
        stuck = row[3]
        hold = getattr(type(comp), "hold_mode", None)
        if hold is not None and mode != hold:
            held = np.array(x, dtype=float)
            held[self.modes.mode_index[i]] = hold
            stuck = self.values(t, held)[i, 3]
        return SimpleNamespace(mode=mode, indicator=row[0], rel=row[1], w_rel=row[2],
                               force=row[3], values=(row[4], row[5]), stuck_force=stuck,
                               rate=row[RATE], tiny=self.run.atol)

    # -- the start -------------------------------------------------------------------------
    def start(self, t, x):
        """The initial state with every element's mode consistent with it (speeds, gaps,
        the forces that would hold)."""
        x = np.array(x, dtype=float)
        targets = {}
        for i, comp in enumerate(self.modes.comps):
            try:
                mode, after, _ = comp.first_mode(self._numbers(t, x, i))
            except ValueError as exc:
                raise ModelError(f"{comp.name}: {exc} at the start") from None
            x[self.modes.mode_index[i]] = mode
            if after is not None:
                targets[i] = after
        if targets:
            x = self._impulse(t, x, targets)
        return self._settle(t, x, None)

    # -- during the run --------------------------------------------------------------------
    def advance(self, method, stepper, times, origin, restarted):
        """``stepper`` advanced to the output ``times`` from ``origin`` = (t, x), looking for
        events at SAMPLES points in each interval: (rows at the output times up to the first
        event, the (t, x) to start again from or None). A Failure keeps its rows at the
        output times."""
        # as often over a run whatever its output grid (a sparse grid must not miss a short
        # stick that a dense one sees); a fixed-step method keeps its own steps
        spacing = None if method.fixed else (self.run.t_end - self.run.t_start) / LATTICE
        fine, output = _refined(origin[0], times, spacing)
        try:
            rows = stepper.advance(fine)
        except Failure as exc:
            states = None if exc.states is None else exc.states[output[:len(exc.states)]]
            raise Failure(exc.reason, states) from None
        rows, restart = self.check(method, fine, origin, rows, restarted)
        return rows[output[:len(rows)]], restart

    def check(self, method, times, before, rows, restarted=False):
        """The rows up to the first event among ``rows`` (at ``times``, after the state
        ``before`` = (t, x)) and, when there is one, the (t, x) to start again from.
        ``restarted``: ``before`` is where an event left the run, with indicators at zero
        (a gap just closed, a speed just zero) that count as positive: they leave zero
        rising, and one that is at or below zero at the next output fell back in between."""
        t_prev, x_prev = before
        g_prev, r_prev = self.values(t_prev, x_prev)[:, [0, RATE]].T
        if restarted:
            g_prev = np.where(g_prev <= 0, np.inf, g_prev)
        for j, (t, x) in enumerate(zip(times, rows)):
            g, r = self.values(t, x)[:, [0, RATE]].T
            crossed = np.flatnonzero((g_prev > 0) & (g <= 0))
            # above zero at both points but falling, then rising: a minimum between them,
            # which may reach zero (a friction sticking for less than the sampled interval)
            dipped = np.flatnonzero(np.isfinite(g_prev) & (g_prev > 0) & (g > 0)
                                    & (r_prev < 0) & (r > 0))
            found = self._locate(method, t_prev, x_prev, t, crossed, dipped) \
                if len(crossed) or len(dipped) else None
            if found is not None:
                t_ev, x_ev, i = found
                after = self.apply(t_ev, x_ev, i)
                if t_ev >= t:                 # at the output time itself: it shows the after
                    return np.vstack([rows[:j], after[None, :]]), (t, after)
                if j > 0 and t_ev - t_prev <= SAME_INSTANT:
                    # at the sampled point before, to rounding: that one shows the after
                    return np.vstack([rows[:j - 1], after[None, :]]), (t_ev, after)
                return rows[:j], (t_ev, after)
            t_prev, x_prev, g_prev, r_prev = t, x, g, r
        return rows, None

    def _locate(self, method, t0, x0, t1, crossed, dipped=()):
        """The earliest crossing in (t0, t1]: (time, state, element). ``dipped``: elements
        above zero at both ends with a minimum between, which cross if it reaches zero."""
        from scipy.optimize import brentq          # 0.3 s to import: only with events

        cache, from_t0 = {}, []

        def state(t):
            if t not in cache:
                if t - t0 < SHORT * max(1.0, abs(t0)):
                    # CasADi's integrators do not step over a tiny interval (they return x0)
                    cache[t] = self._rk4(t0, x0, t - t0)
                elif hasattr(method, "plugin"):        # CasADi's: one integrator for all
                    if not from_t0:
                        from_t0.append(method.start(self.run, t0, x0))
                    cache[t] = from_t0[0].state_at(t)
                else:
                    cache[t] = method.start(self.run, t0, x0).advance(np.array([t]),
                                                                      exact=True)[0]
            return cache[t]

        best = None
        for i in dipped:
            def rate(t, i=i):
                return self.values(t, state(t))[i, RATE]
            if not rate(t0) < 0 < rate(t1):     # integrated again: not quite as sampled
                continue
            t_min = brentq(rate, t0, t1, xtol=1e-15, rtol=4 * np.finfo(float).eps,
                           maxiter=200)
            if self.values(t_min, state(t_min))[i, 0] > 0:
                continue                    # a minimum above zero: no event
            t_i = brentq(lambda t, i=i: self.values(t, state(t))[i, 0], t0, t_min,
                         xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
            if self.values(t_i, state(t_i))[i, 0] > 0:
                t_i = min(t_min, t_i + max(abs(t_i), 1.0) * 4 * np.finfo(float).eps)
            if best is None or t_i < best[0]:
                best = (t_i, i)
        for i in crossed:
            def g(t, i=i):
                return self.values(t, state(t))[i, 0]
            start = t0
            if g(t0) <= 0:            # at zero after a restart: where it was above zero
                start = next((t for t in t0 + (t1 - t0) * SCAN if g(t) > 0), None)
                if start is None:     # it fell back at once: an event where it started
                    t_i = t0
                    if best is None or t_i < best[0]:
                        best = (t_i, i)
                    continue
            if g(t1) >= 0.0:
                # at t1 itself, or (integrated again from t0) just short of crossing there
                t_i = t1
            else:
                t_i = brentq(g, start, t1, xtol=1e-15, rtol=4 * np.finfo(float).eps,
                             maxiter=200)
                # the side of the root where the indicator has crossed
                if g(t_i) > 0:
                    step = max(abs(t_i), 1.0) * 4 * np.finfo(float).eps
                    t_i = min(t1, t_i + step)
            if best is None or t_i < best[0]:
                best = (t_i, i)
        if best is None:
            return None
        return best[0], state(best[0]), best[1]

    def _rk4(self, t, x, h):
        """One classical Runge-Kutta step: for intervals far below the tolerances' steps
        (error h^5 |x^(5)|)."""
        f = self._rhs
        k1 = f(t, x)
        k2 = f(t + h / 2, x + h / 2 * k1)
        k3 = f(t + h / 2, x + h / 2 * k2)
        k4 = f(t + h, x + h * k3)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    def apply(self, t, x, i):
        """The state after element i's event at (t, x): its new mode, its impulse, and the
        modes that change with it at the same instant; logged."""
        if len(self.log) >= MAX_EVENTS:
            raise Failure(f"more than {MAX_EVENTS} events: a stop bouncing ever faster or "
                          f"friction chattering (give the stop a larger v_rest)")
        last, count = self._last
        count = count + 1 if last is not None and abs(t - last) <= SAME_INSTANT else 1
        self._last = (t, count)
        if count > ZENO_LIMIT:
            raise Failure(f"{ZENO_LIMIT} events at t = {t:.15g} s without time passing: "
                          f"the modes of {self.modes.comps[i].name} chatter")
        n, before = len(self.log), np.array(x, dtype=float)[self.modes.mode_index]
        x = self._settle(t, self._change(t, np.array(x, dtype=float), i), i)
        self._tidy(n, before, x[self.modes.mode_index])
        return x

    def _tidy(self, n, before, after):
        """The log from entry n on (one instant) with one entry per friction: its last mode,
        if not the one it had (a friction's first guess that the others overruled goes)."""
        names = [c.name for c in self.modes.comps]
        entries, kept = self.log[n:], []
        for j, e in enumerate(entries):
            i = names.index(e["component"])
            if getattr(type(self.modes.comps[i]), "at_rest_modes", None):
                later = any(f["component"] == e["component"] for f in entries[j + 1:])
                if later or after[i] == before[i]:
                    continue
            kept.append(e)
        self.log[n:] = kept

    def _change(self, t, x, i):
        comp = self.modes.comps[i]
        ev = self._numbers(t, x, i)
        mode, after, kind = comp.next_mode(ev)
        x[self.modes.mode_index[i]] = mode
        if after is not None:
            x = self._impulse(t, x, {i: after})
        self.log.append({"t": float(t), "component": comp.name,
                         "kind": kind or comp.modes[mode]})
        return x

    def _settle(self, t, x, first):
        """Modes made inconsistent by a change at the same instant change too: the frictions
        at rest together (``_together``), then any other element whose indicator the change
        put below zero (a resting stop that would have to pull)."""
        for _ in range(MAX_CASCADE):
            x = self._together(t, x, first)
            g = self.values(t, x)[:, 0]
            wrong = [i for i in np.flatnonzero(g < -self.run.atol) if i != first]
            if not wrong:
                return x
            x = self._change(t, x, wrong[0])
            first = None
        names = ", ".join(c.name for c in self.modes.comps)
        raise Failure(f"the modes of {names} do not settle at t = {t:.15g} s")

    def _together(self, t, x, first):
        """The modes of all frictions at rest at t, decided as one problem (MSL's mixed-mode
        iteration): each is stuck with its holding force within its static limit, or slides
        the way its relative acceleration goes (mode * a_rel >= 0), given the others. From the
        modes they have, the worst violation is changed until none is left; a set of modes
        met twice (a cycle) falls back to trying every combination, fewest changes first.
        ``first``: the element whose event this is, whose new mode stands unless the others
        contradict it."""
        comps, index = self.modes.comps, self.modes.mode_index
        table = self.values(t, x)
        # a free clutch (no normal force) takes no part: its mode is none of these
        rest = [i for i, comp in enumerate(comps) if getattr(type(comp), "at_rest_modes", None)
                and abs(table[i, 2]) <= self.run.atol
                and int(round(x[index[i]])) in comps[i].at_rest_modes]
        if not rest:
            return x
        start = tuple(int(round(x[index[i]])) for i in rest)

        def with_modes(modes):
            y = np.array(x, dtype=float)
            y[[index[i] for i in rest]] = modes
            return y

        def violations(modes):
            """(size, position, mode it should take) of each violated condition."""
            tab = self.values(t, with_modes(modes))
            if not np.all(np.isfinite(tab[rest])):      # held redundantly: singular
                return [(np.inf, 0, modes[0])]
            a_tol = 1e-9 * (1.0 + np.max(np.abs(tab[rest, 6])))
            out = []
            for k, (i, m) in enumerate(zip(rest, modes)):
                if m == 0 and tab[i, 0] < (0.0 if i == first else -self.run.atol):
                    out.append((-tab[i, 0], k, 1 if tab[i, 3] > 0 else -1))
                elif m != 0 and m * tab[i, 6] < -a_tol:
                    out.append((-m * tab[i, 6] / a_tol * self.run.atol, k, 0))
            return out

        modes, seen = start, set()
        while modes not in seen:
            seen.add(modes)
            wrong = violations(modes)
            if not wrong:
                break
            _, k, m = max(wrong)
            modes = modes[:k] + (m,) + modes[k + 1:]
        else:
            choices = sorted(itertools.product(*[comps[i].at_rest_modes for i in rest]),
                             key=lambda c: sum(a != b for a, b in zip(c, start)))
            if len(rest) > MAX_TOGETHER:
                choices = []
            modes = next((c for c in choices if not violations(c)), None)
            if modes is None:
                names = ", ".join(comps[i].name for i in rest)
                raise Failure(f"no consistent modes for {names}, at rest together at "
                              f"t = {t:.15g} s")
        x = with_modes(modes)
        for i, old, new in zip(rest, start, modes):
            if new != old:
                self.log.append({"t": float(t), "component": comps[i].name,
                                 "kind": comps[i].modes[new]})
        if any(m == 0 for m in modes):      # the stuck ones exactly at rest
            x = self._impulse(t, x, {})
        return x

    def _impulse(self, t, x, targets):
        """The state whose relative speeds are ``targets`` (element -> speed) while the held
        elements keep theirs at zero: impulses P through the mechanism, dx = dxdot/dF P."""
        table = self.values(t, x)
        held = [i for i, comp in enumerate(self.modes.comps)
                if float(comp.held(int(round(x[self.modes.mode_index[i]])))) > 0.5]
        which = sorted(set(targets) | set(held))
        want = np.array([targets.get(i, 0.0) - table[i, 2] for i in which])
        A, Jx = self._response(t, x)
        P = np.linalg.lstsq(A[np.ix_(which, which)], want, rcond=None)[0]
        out = x + Jx[:, which] @ P
        for i, k in enumerate(self.modes.mode_index):
            out[k] = x[k]
        return out


def numeric_pair(f, p):
    """A Python callable (t, x) -> (A, B) of a two-output Function of (t, x, p)."""
    p = np.asarray(p, dtype=float)

    def call(t, x):
        A, B = f(t, x, p)
        return np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    return call


def _refined(t0, times, spacing=None):
    """The output ``times`` after ``t0`` with SAMPLES - 1 points between each and the one
    before, or more, to look at least every ``spacing`` seconds, and which of them are
    outputs."""
    edges = np.concatenate([[t0], times])
    parts, output = [], []
    for a, b in itertools.pairwise(edges):
        n = SAMPLES if not spacing else max(SAMPLES, math.ceil((b - a) / spacing - 1e-9))
        part = np.linspace(a, b, n + 1)[1:]
        part[-1] = b                        # exactly the output time, not rounded
        parts.append(part)
        output.append(np.arange(n) == n - 1)
    return np.concatenate(parts), np.concatenate(output)
