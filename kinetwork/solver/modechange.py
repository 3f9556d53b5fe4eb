"""Mode changes of the elements with modes (friction, gaps, stops: ``components/friction.py``)
at their events: what each element's event does to the state, and the modes that change
with it at the same instant. ``events.Events`` finds and locates the events.

An element says what its new mode is (``next_mode``) and whether its relative speed jumps
(an impact, a sticking: an impulse through the mechanism, along the response of the state's
rates to the element's force); modes that the change makes inconsistent follow at the same
instant; frictions at rest together decide their modes as one problem (``_together``).
"""

import itertools
from types import SimpleNamespace

import numpy as np

from ..errors import ModelError
from ..equations.system import mapped
from .compiled import numeric
from .methods import Failure

#: mode changes at one instant at most (a cascade through coupled elements)
MAX_CASCADE = 50
#: frictions at rest at one instant whose modes are tried in every combination at most, when
#: changing the worst violation one at a time cycles (3**MAX_TOGETHER combinations)
MAX_TOGETHER = 8
#: the column of the indicator's rate in ``Modes.f_values`` (``equations/modes.py``)
RATE = 7


class ModeChanges:
    """The elements with modes of one run (``system.modes``), as one source of events of
    ``events.Events``: their indicators, and what their events do."""

    def __init__(self, events, run):
        self.events, self.run = events, run
        self.modes = modes = run.system.modes
        n = run.system.n_states
        self._values = numeric(modes.f_values, run.p, n)
        self._response = numeric_pair(modes.f_response, run.p)

    @property
    def count(self):
        """How many indicators: one per element."""
        return len(self.modes.comps)

    @property
    def log(self):
        return self.events.log

    def indicators(self, t, x):
        """(indicator, its rate) of every element at (t, x)."""
        table = self.values(t, x)
        return table[:, 0], table[:, RATE]

    def levels(self, t, x):
        """The indicators of ``indicators`` alone."""
        return self.values(t, x)[:, 0]

    def indicator_rows(self, times, rows):
        """``indicators`` at each of ``rows`` (at ``times``): two (len(rows), k) arrays."""
        k = len(self.modes.comps)
        if not len(rows):
            return np.zeros((0, k)), np.zeros((0, k))
        table = np.asarray(mapped(self.modes.f_values, len(rows))(
            np.asarray(times, dtype=float)[None, :], np.asarray(rows, dtype=float).T,
            self.run.p)).reshape(k, len(rows), -1)
        return table[:, :, 0].T, table[:, :, RATE].T

    def level_rows(self, times, rows):
        """``levels`` at each of ``rows`` (at ``times``): a (len(rows), k) array."""
        return self.indicator_rows(times, rows)[0]

    def chatter(self, i):
        """Why events of element i pile up at one instant, in words."""
        return f"the modes of {self.modes.comps[i].name} chatter"

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

    def apply(self, t, x, i):
        """The state after element i's event at (t, x): its new mode, its impulse, and the
        modes that change with it at the same instant; logged."""
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
