"""The relations of a run (``kinetwork.equations.relations``) as events: the values they are
held at, where those change, and what a change does.

The integrators see the equations with every relation held at a value r (``run.p_solver`` =
[p; r]). Between time events the nodes on time alone are held at the values they take in
that stretch of time (read at its middle); the relations on the states are held at the values
they have where the stretch began. A time event (``schedule.Schedule``) ends a stretch
exactly at its instant; a state event is where a relation on the states no longer holds the
value it is held at: its indicator, oriented so that it is positive while the value holds,
crosses zero (``events.Events`` locates it). At either, the relations are read again there,
each with the others held, until none changes (Modelica's event iteration), the one whose
indicator crossed taking its other value; the method starts afresh with the new values. The
state itself does not jump.
"""

import numpy as np

from .buffers import Call, PointsBySize
from .methods import Failure
from .schedule import Schedule

#: rounds of the event iteration at most (each relation read with the others held)
MAX_ITERATIONS = 50


class Switches:
    """The relations of one run as one source of events of ``events.Events``."""

    def __init__(self, events, run, relations):
        self.events, self.run, self.relations = events, run, relations
        self.nx = run.system.n_states
        self.schedule = Schedule(relations, run.p, run.t_start, run.t_end)
        self.r = np.zeros(relations.n)
        self.time_events = 0
        self._calls = {}
        self._rows = PointsBySize()
        self._level_maps = PointsBySize()   # the indicators alone, at many points
        self._signs = None

    # -- numbers ---------------------------------------------------------------------------
    def _numeric(self, name):
        """The Function ``name`` of the relations as a fast callable of (t, full state) at the
        values held now: made once per run, the values written into its parameters in
        place (not made again at each event)."""
        call = self._calls.get(name)
        if call is None:
            f = self._function(name)
            call = self._calls[name] = Call(f, np.concatenate([self.run.p, self.r]))
        else:
            call.p[len(call.p) - len(self.r):] = self.r
        return call

    def _function(self, name):
        """The relations' Function ``name``, compiled as the run's equations are."""
        if self.relations is self.run.system.relations:
            return self.run.compiled.relations(name, self.run.jit)
        return getattr(self.relations, name)          # another System's (re-partitioned)

    def select(self, t, x):
        """The value each node takes at (t, x), the others held at r."""
        return self._numeric("f_select")(t, x).ravel()

    def indicators(self, t, x):
        """(indicator, its rate) of each relation on the states at (t, x): positive while the
        value it is held at is the one it has."""
        if not len(self.relations.state):
            return np.zeros(0), np.zeros(0)
        table = self._numeric("f_state")(t, x)           # (k, 2), column-major
        g, rate = table[:len(table) // 2], table[len(table) // 2:]
        sign = self._sign()
        # held true, a relation ends where g reaches zero (< : g <= 0; <= : g < 0); held
        # false, where g rises above zero (<: g > 0; <=: g >= 0): all crossings of zero
        return sign * g, sign * rate

    def levels(self, t, x):
        """The indicators of ``indicators`` alone, without their rates (which read the whole
        equations): what locating a crossing evaluates."""
        if not len(self.relations.state):
            return np.zeros(0)
        return self._sign() * self._numeric("f_level")(t, x)

    def _sign(self):
        """+1 for each relation on the states held true, -1 held false: kept until the
        values change (each change of ``r`` ends in ``_publish``, which drops it)."""
        if self._signs is None:
            self._signs = np.where(self.r[self.relations.state] > 0.5, 1.0, -1.0)
        return self._signs

    @property
    def count(self):
        """How many indicators: one per relation on the states."""
        return len(self.relations.state)

    def indicator_rows(self, times, rows):
        """``indicators`` at each of ``rows`` (at ``times``): two (len(rows), k) arrays."""
        k = len(self.relations.state)
        if not k or not len(rows):
            return np.zeros((len(rows), k)), np.zeros((len(rows), k))
        # a row per point, (k, 2) column-major each
        table = self._rows(self._numeric("f_state").f, np.asarray(times, dtype=float),
                           rows, np.concatenate([self.run.p, self.r]))
        sign = self._sign()[None, :]
        return sign * table[:, :k], sign * table[:, k:]

    def level_rows(self, times, rows):
        """``levels`` at each of ``rows`` (at ``times``): a (len(rows), k) array."""
        k = len(self.relations.state)
        if not k or not len(rows):
            return np.zeros((len(rows), k))
        table = self._level_maps(self._numeric("f_level").f, np.asarray(times, dtype=float),
                           rows, np.concatenate([self.run.p, self.r]))
        return self._sign()[None, :] * table

    def chatter(self, i):
        """Why events of relation i pile up at one instant, in words."""
        return (f"the relation {self.relations.text(self.relations.state[i])} chatters: the "
                f"motion crosses it back at once each time (a Coulomb law written as if_else "
                f"on a speed, at rest); use a friction element, which sticks, or write the "
                f"relation in noEvent(...) to integrate it as it is")

    # -- the held values -------------------------------------------------------------------
    def start(self, t, x):
        """The values at the start: the time nodes' over the first stretch, the relations'
        on the states where the run starts."""
        self._hold_time(t)
        self._iterate(t, x, None)
        self._publish()
        return x

    def bound(self, t):
        """The first time event after t, or the run's end."""
        nxt = self.schedule.next(t)
        return self.run.t_end if nxt is None else nxt

    def next_time(self, t):
        return self.schedule.next(t)

    def at_time(self, t, x):
        """At the time event t: the values of the stretch that begins there."""
        self.time_events += 1
        self._hold_time(t)
        self._iterate(t, x, None)
        self._publish()
        return x

    def apply(self, t, x, i):
        """The state relation i (of ``relations.state``) crossed at (t, x): its other value,
        the others read again there; logged."""
        k = self.relations.state[i]
        self.r[k] = 1.0 - self.r[k]
        self._iterate(t, x, k)
        self._publish()
        self.events.log.append({"t": float(t), "component": None,
                                "kind": "relation true" if self.r[k] > 0.5 else
                                "relation false", "relation": self.relations.text(k)})
        return np.asarray(x, dtype=float)

    def _hold_time(self, t):
        """The time nodes held at their values in the stretch after t (read at its middle,
        nested ones read again until they agree)."""
        time = self.relations.time
        if not len(time):
            return
        mid = (t + self.bound(t)) / 2
        x = np.zeros(self.nx + self.run.system.n_algebraic)
        for _ in range(len(time) + 1):
            new = self.select(mid, x)[time]
            if np.array_equal(new, self.r[time]):
                return
            self.r[time] = new

    def _iterate(self, t, x, fixed):
        """The relations on the states read at (t, x) with the others held, until none
        changes; ``fixed``: the one that crossed, whose new value stands."""
        state = self.relations.state
        if not len(state):
            return
        for _ in range(MAX_ITERATIONS):
            new = self.select(t, x)[state]
            if fixed is not None:
                new[list(state).index(fixed)] = self.r[fixed]
            if np.array_equal(new, self.r[state]):
                return
            self.r[state] = new
        raise Failure(f"the relations do not settle at t = {t:.15g} s (their values change "
                      f"each other's without end)")

    def _publish(self):
        """The integrators' parameters with the values now held."""
        self.run.p_solver = np.concatenate([self.run.p, self.r])
        self._signs = None

