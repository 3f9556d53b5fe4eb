"""Events: where the law of the equations changes, found, located and applied between the
integrator's outputs. Two sources (each one class, with ``indicators``, ``start`` and
``apply``): the elements with modes (friction, gaps, stops: ``modechange.ModeChanges``) and
the relations of the equations (``if_else`` on the states or on time, a Table's breakpoints:
``switches.Switches``).

Time events are known before the run (``schedule.py``): ``Events.advance`` ends each call of
the method exactly at the next one, and the method starts afresh there with the relations'
new values. A scipy stepper is never let past it (``Run.bound``), a fixed-step method lands
on it.

State events are looked for where the indicators are looked at: the output times and
SAMPLES - 1 points between each two, or more, so that they are looked at LATTICE times a run
at least whatever its output grid. An event is an indicator going from positive to zero or
below between two of those points, or one above zero at both but falling, then rising, whose
minimum between them (where its rate is zero) reaches zero: a friction sticking for less
than the sampled interval, a contact shorter than it. It is located on the indicator along
the cubic Hermite curve through states and their rates, so that the trial times cost no
integration: by Brent's method on the curve through the two sampled rows when that is within
FIT (``curves.py``) of the solver's tolerances (its rate checked against the equations' at
three points), else on the curve through DENSE points of the interval: the run's own (CVODES
interpolates them in the chunk's call, at no evaluation more), or one integration of the
same method from the row before (other methods). The indicators' values there (one mapped
call) bracket the crossing to one step, the cubic through the indicator's values and rates
at its two points gives the root, Newton's steps along the curve settle it
(``curves.root``), and the curve is checked on that step alone. On a curve that is not
within FIT, Newton's steps on the integration from the point before take the time found to
the integration's own root (a method without that one integration, IDAS or fixed steps, and
a crossing the curve sees and the integration does not: every trial time integrated from the
row before). The time is as exact as the integration, to about 1e-14 s in the bracketing
itself; the source applies the event, and the method starts afresh there. Events are logged
(time, component, kind) for ``res.stats["events"]``; time events are counted
(``res.stats["time_events"]``).

Two crossings between two sampled points, which cancel out, are seen when the indicator has
one minimum between them, not when it also has a maximum there (right after an event, an
indicator at zero counts as positive, so a bounce within the first interval is found). Runs
with state events go in chunks of EVENT_CHUNK output intervals after an event, as what
follows an event in a chunk is computed again, twice as many after each chunk without one, up
to MAX_EVENT_CHUNK (each chunk restarts a multistep method), and no further than FORESEE
times the time the indicators' rates foresee the next crossing at (``Events.chunk``); a
fixed-step method steps each sampled interval, so its steps are SAMPLES times shorter than
without them. The integrations that locate events are counted in the run's statistics.
"""

import numpy as np

from .buffers import PointsBySize
from .compiled import numeric
from .curves import Hermite, Steps, search, search_steps
from .explicit import rk4
from .methods import Failure, _add_counts
from .modechange import ModeChanges
from .switches import Switches
from .tolerance import solver_tolerances

#: output intervals of a chunk after an event, in a run with state events (what follows an
#: event in a chunk is computed again from it), and at most after chunks without one
EVENT_CHUNK = 8
MAX_EVENT_CHUNK = 128
#: points per output interval at least where the indicators are looked at
SAMPLES = 4
#: points over a run, at least, where the indicators are looked at (however sparse its
#: output grid: the events found must not depend on it)
LATTICE = 1000
#: events in one run at most: beyond, the run stops (a stop bouncing ever faster, chattering)
MAX_EVENTS = 100_000
#: events closer than SAME_INSTANT seconds count as at one instant; ZENO_LIMIT of them in a
#: row stop the run (modes chattering without time passing)
SAME_INSTANT = 1e-13
ZENO_LIMIT = 200
#: trial intervals shorter than this (relative to the time) are stepped by RK4 directly
SHORT = 1e-6
#: points of the integration over a sampled interval an event is located on (between them,
#: a cubic Hermite curve): the chunk's own (``_dense_chunks``), or one integration of
#: that interval. The chunk's cost EngineV6 no evaluation more and about 0.1 us a point;
#: an integration of the interval for each event cost 13946 of its 52863 evaluations
DENSE = 32
#: a chunk gets those points from its own integration when they are at most DENSE_MOST (its
#: integrator, kept for the next run, holds ~8 bytes a point: 37 kB with 16 points, 170 kB
#: with 16000) and DENSE_VALUES numbers (the states at them); past either, an event is
#: located on an integration of its interval
DENSE_MOST = 4096
DENSE_VALUES = 1_000_000
#: Newton's steps at most from the time found on a curve not within FIT to the integration's
#: own root, on the side where it has crossed
POLISH = 4
#: a chunk reaches this many times as far as the indicators, each going on as fast as now,
#: foresee the next crossing (``Events.chunk``): most approach zero slowing down (a piston
#: nearing its dead centre). On EngineV6, rhs evaluations and integrator calls by factor:
#: 1.0: 53249, 644; 1.25: 45914, 508; 1.5: 39580, 375; 1.6: 39012, 351; 2: 43887, 351;
#: 3: 54390, 351; without: 72186, 351
FORESEE = 1.6


class Events:
    """The events of one run of a System with modes (``system.modes``) or relations
    (``system.relations``)."""

    def __init__(self, run):
        self.run = run
        system = run.system
        self.log = []
        self.modes = ModeChanges(self, run) if system.modes is not None else None
        self.switches = Switches(self, run, system.relations) \
            if system.relations is not None else None
        self.sources = [s for s in (self.modes, self.switches) if s is not None]
        self._last = (None, 0)          # time of the last event, events at it
        self._held = None               # the held values of the start (``reset``)
        self._f_rhs = None
        self._chunk = EVENT_CHUNK
        #: whether the curve through the two sampled rows is tried first (``_locate_dense``),
        #: by the law in effect (the values held) and the indicators that cross: once it has
        #: not fitted under that law, the motion there is too far from a cubic over a
        #: sampled interval, and each try costs five evaluations of the equations for
        #: nothing (EngineV6: 339 tries, none fitted; a ball's falls are parabolas, which
        #: fit, its rises off the contact's spring are not)
        self._two_fit = {}
        self._points = PointsBySize()   # the rates on the curves
        #: (t, x, p) -> indicators and rates where the run goes on from, and the time the
        #: next crossing is foreseen at from there (``chunk``)
        self._at = None
        self._foreseen = None
        self._cut = 0                   # the last chunk's length, when the forecast cut it
        #: the runs of the method started to locate an event, and the counts of the work
        #: they did (``spent``: the run's statistics hold it)
        self._trials = []
        self.spent = {}

    @property
    def located(self):
        """Whether the run has state events, whose indicators are watched."""
        return self.modes is not None or (self.switches is not None and
                                          len(self.switches.relations.state) > 0)

    @property
    def time_events(self):
        return self.switches.time_events if self.switches is not None else 0

    def indicators(self, t, x):
        """(indicators, their rates) of every source at (t, x), one after the other."""
        if len(self.sources) == 1:
            return self.sources[0].indicators(t, x)
        parts = [s.indicators(t, x) for s in self.sources]
        return (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))

    def levels(self, t, x):
        """The indicators of every source at (t, x), without their rates."""
        if len(self.sources) == 1:
            return self.sources[0].levels(t, x)
        return np.concatenate([s.levels(t, x) for s in self.sources])

    def _which(self, i):
        """(source, index in it) of indicator i."""
        for source in self.sources:
            k = source.count
            if i < k:
                return source, i
            i -= k
        raise IndexError(i)

    def chunk(self, chunk, event, t=None):
        """Output intervals of the next chunk of a run with state events, at most ``chunk``:
        EVENT_CHUNK after an ``event``, else twice the last, up to MAX_EVENT_CHUNK; and, from
        the output time ``t`` the chunk starts after, no more than reach the next crossing
        the indicators foresee (``_foresee``): what a chunk integrates past its first event
        is integrated again (EngineV6: two thirds of its evaluations, when each chunk after
        an event went EVENT_CHUNK intervals and its events come every three). A chunk the
        forecast cut short that met no event makes the next one at least twice as long: an
        indicator that keeps nearing zero without crossing it (a tangency, a stuck friction's
        margin at rest) costs a few short chunks, not one per output interval."""
        self._chunk = EVENT_CHUNK if event else min(2 * self._chunk, MAX_EVENT_CHUNK)
        chunk, cut = min(chunk, self._chunk), self._cut
        self._cut = 0
        if t is not None and self._foreseen is not None and self._foreseen > t:
            reach = int(np.ceil((self._foreseen - t) / self.run.spacing - 1e-9))
            if not event:
                reach = max(reach, 2 * cut)
            if reach < chunk:
                chunk = self._cut = max(1, reach)
        return chunk

    def bound(self, t):
        """The time a method started at t must not step past: the next time event, or the
        run's end."""
        return self.switches.bound(t) if self.switches is not None else self.run.t_end

    # -- the start -------------------------------------------------------------------------
    def start(self, t, x):
        """The initial state consistent with every source (modes), and the relations'
        values there."""
        x = np.array(x, dtype=float)
        for source in self.sources:
            x = source.start(t, x)
        if self.switches is not None:
            self._held = self.switches.r.copy()
        return x

    def rebind(self, t, x):
        """The run goes on with another System of the same model from (t, x) (its loops
        re-partitioned): the relations as that System's equations hold them, read there."""
        if self.switches is None:
            return
        self._at = None                 # read by the other System's relations from here
        count = self.switches.time_events
        relations = self.run.system.relations
        self.switches = Switches(self, self.run, relations) if relations is not None else None
        self.sources = [s for s in (self.modes, self.switches) if s is not None]
        if self.switches is None:
            self.run.p_solver = self.run.p
            return
        self.switches.time_events = count
        self.switches.start(t, x)

    def reset(self):
        """Back to the start, for another method over the same run (``auto``)."""
        self.log = []
        self._last = (None, 0)
        self._chunk = EVENT_CHUNK
        self._two_fit = {}
        self._at = self._foreseen = None
        self._cut = 0
        self._trials, self.spent = [], {}
        if self.switches is not None:
            self.switches.r = self._held.copy()
            self.switches.time_events = 0
            self.switches._publish()

    # -- during the run --------------------------------------------------------------------
    def advance(self, method, stepper, times, origin, restarted):
        """``stepper`` advanced to the output ``times`` from ``origin`` = (t, x), up to the
        next time event and looking for state events at SAMPLES points in each interval:
        (rows at the output times up to the first event, the (t, x) to start again from or
        None). A Failure keeps its rows at the output times."""
        t0 = origin[0]
        stops, at, at_output = times, None, False
        nxt = self.switches.next_time(t0) if self.switches is not None else None
        if nxt is not None and nxt <= times[-1] + _gap(times[-1]):
            j = int(np.searchsorted(times, nxt - _gap(nxt)))
            # at the event's own instant, which is an output's too when one is as close as
            # rounding (0.6 and 0.6000000000000001): never a step past it
            at, at_output = nxt, j < len(times) and abs(times[j] - nxt) <= _gap(nxt)
            stops = np.append(times[:j], nxt)
        if self.located:
            # as often over a run whatever its output grid (a sparse grid must not miss a
            # short stick that a dense one sees); a fixed-step method keeps its own steps
            spacing = None if method.fixed else (self.run.t_end - self.run.t_start) / LATTICE
            fine, output = _refined(t0, stops, spacing)
        else:
            fine, output = np.asarray(stops, dtype=float), np.ones(len(stops), dtype=bool)
        if at is not None and not at_output:
            output[-1] = False               # the event's instant is no output time
        points, sampled = fine, None
        if self.located and (restarted or self._cut) and \
                _dense_chunks(self.run, method, len(fine)):
            # DENSE points in each sampled interval from the chunk's own integration: its
            # solver interpolates them (no evaluation more), and an event is located on
            # them, not on an integration of its own. Only in a chunk that is likely to meet
            # one, after an event or cut short where the indicators foresee one (EngineV6:
            # every chunk); the others' points cost more than the rare event's integration
            # saves (msl_friction: 7 events in 48 chunks, 10 % slower with them)
            points, sampled = _refined(t0, fine, parts=DENSE)
            output = _within(sampled, output)
        try:
            rows = stepper.advance(points)
        except Failure as exc:
            states = None if exc.states is None else exc.states[output[:len(exc.states)]]
            raise Failure(exc.reason, states) from None
        restart, dense = None, None
        if sampled is not None:
            dense, rows = (points, rows), rows[sampled]
            output = output[sampled]
        if self.located:
            rows, restart = self.check(method, fine, origin, rows, restarted, dense)
        if at is not None and (restart is None or restart[0] >= at - _gap(at)):
            # the time event (a state event at its instant applied first)
            restart = (at, self.switches.at_time(at, rows[-1] if restart is None
                                                 else restart[1]))
        return rows[output[:len(rows)]], restart

    def check(self, method, times, before, rows, restarted=False, dense=None):
        """The rows up to the first event among ``rows`` (at ``times``, after the state
        ``before`` = (t, x)) and, when there is one, the (t, x) to start again from.
        ``restarted``: ``before`` is where an event left the run, with indicators at zero
        (a gap just closed, a speed just zero) that count as positive: they leave zero
        rising, and one that is at or below zero at the next output fell back in between.
        ``dense``: (times, states) of the same integration at DENSE points in each interval
        of ``times`` (each interval's last the interval's end), which events are located on."""
        t_prev, x_prev = before
        g_first, r_first = self._indicators_at(t_prev, x_prev)
        if restarted:
            g_first = np.where(g_first <= 0, np.inf, g_first)
        G, R = self._rows(times, rows)
        G_prev, R_prev = np.vstack([g_first, G[:-1]]), np.vstack([r_first, R[:-1]])
        crossed = (G_prev > 0) & (G <= 0)
        # above zero at both points but falling, then rising: a minimum between them,
        # which may reach zero (a friction sticking for less than the sampled interval)
        dipped = np.isfinite(G_prev) & (G_prev > 0) & (G > 0) & (R_prev < 0) & (R > 0)
        for j in np.flatnonzero(np.any(crossed | dipped, axis=1)):
            t, t_prev = times[j], (before[0] if j == 0 else times[j - 1])
            x_prev = before[1] if j == 0 else rows[j - 1]
            points = None
            if dense is not None:
                inside = slice(j * DENSE, (j + 1) * DENSE)
                points = (np.concatenate([[t_prev], dense[0][inside]]),
                          np.vstack([np.asarray(x_prev, dtype=float)[None, :],
                                     dense[1][inside]]))
            found = self._locate(method, t_prev, x_prev, t, np.flatnonzero(crossed[j]),
                                 np.flatnonzero(dipped[j]), rows[j], points)
            if found is not None:
                t_ev, x_ev, i = found
                after = self.apply(t_ev, x_ev, i)
                if t_ev >= t:                 # at the output time itself: it shows the after
                    restart = (t, after)
                    rows = np.vstack([rows[:j], after[None, :]])
                elif j > 0 and t_ev - t_prev <= SAME_INSTANT:
                    # at the sampled point before, to rounding: that one shows the after
                    restart = (t_ev, after)
                    rows = np.vstack([rows[:j - 1], after[None, :]])
                else:
                    restart, rows = (t_ev, after), rows[:j]
                self._foresee(restart[0], *self._indicators_at(*restart))
                return rows, restart
        self._foresee(times[-1], G[-1], R[-1])
        return rows, None

    def _indicators_at(self, t, x):
        """``indicators`` at (t, x), kept for the point the run goes on from (asked for again
        when the next chunk begins there)."""
        key = (float(t), np.asarray(x, dtype=float).tobytes(), self.run.p_solver.tobytes())
        if self._at is None or self._at[0] != key:
            self._at = (key, self.indicators(t, x))
        return self._at[1]

    def _foresee(self, t, g, rate):
        """The time of the next crossing as the indicators at t (``g``, falling at ``rate``)
        foresee it, each going on as fast as now (None: none is falling). Only the chunks'
        lengths read it: events are looked for wherever it says."""
        falling = (g > 0) & (rate < 0) & np.isfinite(g)
        self._foreseen = float(t + FORESEE * np.min(g[falling] / -rate[falling])) \
            if np.any(falling) else None

    def _rows(self, times, rows):
        """(indicators, rates), (len(rows), k) each, at each row."""
        parts = [s.indicator_rows(times, rows) for s in self.sources]
        return np.hstack([p[0] for p in parts]), np.hstack([p[1] for p in parts])

    def _locate(self, method, t0, x0, t1, crossed, dipped=(), x1=None, points=None):
        """The earliest crossing in (t0, t1]: (time, state, element). ``dipped``: elements
        above zero at both ends with a minimum between, which cross if it reaches zero.
        ``x1``: the state at t1, when known; ``points``: (times, states) of the run's
        integration at DENSE + 1 points from t0 to t1, when it gave them."""
        try:
            return self._locate_by(method, t0, x0, t1, crossed, dipped, x1, points)
        finally:
            for trial in self._trials:
                _add_counts(self.spent, trial.stats)
            self._trials = []

    def _start(self, method, t, x):
        """A run of ``method`` from (t, x) for locating an event, its work counted."""
        trial = method.start(self.run, t, x)
        self._trials.append(trial)
        return trial

    def _locate_by(self, method, t0, x0, t1, crossed, dipped, x1, points):
        """``_locate``'s answer: on the curve when it can, else on integrated states."""
        if not self.run.system.n_algebraic and not method.fixed and \
                t1 - t0 >= SHORT * max(1.0, abs(t0)):
            found = self._locate_dense(method, t0, x0, t1, x1, crossed, dipped, points)
            if found is not _UNSURE:
                return found
        return self._locate_exact(method, t0, x0, t1, crossed, dipped)

    def _locate_exact(self, method, t0, x0, t1, crossed, dipped=()):
        """``_locate`` on states integrated from (t0, x0) to every trial time."""
        cache, from_t0 = {}, []

        def state(t):
            if t not in cache:
                if t - t0 < SHORT * max(1.0, abs(t0)):
                    # CasADi's integrators do not step over a tiny interval (they return x0)
                    cache[t] = self._rk4(t0, x0, t - t0)
                elif method.trial_states:       # one integration for every trial time
                    if not from_t0:
                        from_t0.append(self._start(method, t0, x0))
                    cache[t] = from_t0[0].state_at(t)
                else:
                    cache[t] = self._start(method, t0, x0).advance(np.array([t]),
                                                                   exact=True)[0]
            return cache[t]

        best = search(lambda t, i: self.levels(t, state(t))[i],
                       lambda t, i: self.indicators(t, state(t))[1][i],
                       t0, t1, crossed, dipped)
        if best is None:
            return None
        return best[0], state(best[0]), best[1]

    def _locate_dense(self, method, t0, x0, t1, x1, crossed, dipped, points=None):
        """``_locate`` on the cubic Hermite curve through the states and rates at t0 and t1
        or, where that curve is farther from the equations than FIT of the solver's
        tolerances, through those of one integration to DENSE points of (t0, t1] (the run's
        own, ``points``, when it gave them; else one from t0): the trial times cost no
        integration. On a curve that is not within FIT either, the time found
        is checked, and moved to the side where the indicator has crossed, on states
        integrated from the point before it. _UNSURE when it cannot be (a method without
        that integration, a crossing the curve sees and the integration does not):
        ``_locate_exact`` decides."""
        fun = self.run.compiled.rhs(self.run.jit, method.newton)

        def rates(T, X):            # the equations' rates at every (T[k], X[k]), one call
            return self._points(fun, T, X, self.run.p_solver)
        x0 = np.asarray(x0, dtype=float)
        tol = self._tolerance(method)
        fitted = False
        law = (tuple(crossed), tuple(dipped), self.run.p_solver.tobytes())
        if x1 is not None and self._two_fit.get(law, True):
            T, X = np.array([t0, t1]), np.vstack([x0, x1])
            curve = Hermite(T, X, rates(T, X))
            fitted = self._two_fit[law] = curve.fits(rates, tol)
        if fitted:
            best = search(lambda t, i: self.levels(t, curve(t))[i],
                           lambda t, i: self.indicators(t, curve(t))[1][i],
                           t0, t1, crossed, dipped)
        elif points is not None:
            T, X = points
        else:
            grid = getattr(self._start(method, t0, x0), "grid", None)
            rows = grid(t1, DENSE) if grid is not None else None
            if rows is None:
                return _UNSURE
            T = np.concatenate([[t0], t0 + (t1 - t0) * np.arange(1, DENSE + 1) / DENSE])
            T[-1] = t1
            X = np.vstack([x0[None, :], rows])
        if not fitted:
            curve = Steps(T, X, rates)
            best = search_steps(self, curve, T, X, crossed, dipped)
            # the curve is checked where the time found is read off it, on that step alone
            # (its points are the integration's: elsewhere it decides nothing)
            fitted = best is not None and curve.fits(rates, tol, curve.step(best[0]))
        if best is None:
            return None
        t_i, i = best
        if fitted:
            return t_i, curve(t_i), i

        return _polished(self, method, T, X, t0, t1, t_i, i)

    def _level_rows(self, times, rows):
        """The indicators alone, (len(rows), k), at each row."""
        return np.hstack([s.level_rows(times, rows) for s in self.sources])

    def _tolerance(self, method):
        """(rtol, atol) the method's solver is given for this run (``tolerance.py``)."""
        run = self.run
        if getattr(method, "sundials", False):
            return solver_tolerances(method, run.system, run.rtol, run.atol,
                                     run.t_end - run.t_start)
        return run.rtol, run.atol

    def _rk4(self, t, x, h):
        """One classical Runge-Kutta step of the equations the method integrates: for
        intervals far below the tolerances' steps (error h^5 |x^(5)|). With algebraic
        variables the state is kept (an error of h |xdot|)."""
        if self.run.system.n_algebraic:
            return np.array(x, dtype=float)
        return rk4(self._rhs(), t, x, h, 1)

    def _rhs(self):
        """The held right-hand side at the values held now, as a Python callable."""
        key = self.run.p_solver.tobytes()
        if self._f_rhs is None or self._f_rhs[0] != key:
            f = self.run.compiled.rhs(None)
            self._f_rhs = (key, numeric(f, self.run.p_solver, self.run.system.n_states))
        return self._f_rhs[1]

    def apply(self, t, x, i):
        """The state after the event of indicator i at (t, x), applied by its source."""
        source, k = self._which(i)
        if len(self.log) >= MAX_EVENTS:
            raise Failure(f"more than {MAX_EVENTS} events: a stop bouncing ever faster, "
                          f"friction or a relation chattering (give the stop a larger "
                          f"v_rest, write the relation in noEvent(...))")
        last, count = self._last
        count = count + 1 if last is not None and abs(t - last) <= SAME_INSTANT else 1
        self._last = (t, count)
        if count > ZENO_LIMIT:
            raise Failure(f"{ZENO_LIMIT} events at t = {t:.15g} s without time passing: "
                          f"{source.chatter(k)}")
        return source.apply(t, x, k)


def _polished(events, method, T, X, t0, t1, t_i, i):
    """``Events._locate_dense``'s time t_i of indicator i, found on a curve through the
    points (T, X) that is not within FIT, taken by Newton's steps on states integrated from
    the point before it to the integration's own root, on the side where the indicator has
    crossed: (time, state, i), or _UNSURE."""
    def exact(t):
        j = max(0, int(np.searchsorted(T, t, side="right")) - 1)
        if t - T[j] < SHORT * max(1.0, abs(T[j])):
            return events._rk4(T[j], X[j], t - T[j])
        return events._start(method, T[j], X[j]).state_at(t)

    # Newton on the integration from the curve's root (off by the curve's error): to
    # the integration's own root, on the side where the indicator has crossed
    tiny = 4 * np.finfo(float).eps
    x_i, crossed_at = exact(t_i), None
    for _ in range(POLISH):
        g_i = events.levels(t_i, x_i)[i]
        if g_i <= 0:
            crossed_at = (t_i, x_i, i)
        rate = events.indicators(t_i, x_i)[1][i]
        if not rate < 0:
            break
        dt = g_i / -rate
        if g_i <= 0 and -dt <= tiny * max(1.0, abs(t_i)):
            break                       # at the root, to rounding
        t_i = min(t1, max(t0, t_i + dt + (tiny * max(1.0, abs(t_i)) if g_i > 0 else 0)))
        x_i = exact(t_i)
    return crossed_at if crossed_at is not None else _UNSURE


def _dense_chunks(run, method, n):
    """Whether ``method``'s run over ``n`` sampled points gives the states at DENSE points in
    each sampled interval in the same call, interpolated by its solver (CVODES: its steps
    are the same whatever the output grid), for ``Events._locate_dense``'s curve: while they
    are few enough (DENSE_MOST, DENSE_VALUES)."""
    points = n * DENSE
    return getattr(method, "plugin", None) == "cvodes" and not method.fixed and \
        not run.system.n_algebraic and points <= DENSE_MOST and \
        points * run.system.n_states <= DENSE_VALUES


def _gap(t):
    """The width of one instant at t."""
    return SAME_INSTANT * max(1.0, abs(t))


def _refined(t0, times, spacing=None, parts=SAMPLES):
    """The output ``times`` after ``t0`` with ``parts`` - 1 points between each and the one
    before, or more, to look at least every ``spacing`` seconds, and which of them are
    outputs."""
    times = np.asarray(times, dtype=float)
    edges = np.concatenate([[t0], times])
    widths = np.diff(edges)
    n = np.full(len(widths), parts)
    if spacing:
        n = np.maximum(SAMPLES, np.ceil(widths / spacing - 1e-9)).astype(int)
    ends = np.cumsum(n) - 1
    which = np.repeat(np.arange(len(widths)), n)
    k = np.arange(ends[-1] + 1) - np.repeat(ends - n + 1, n) + 1     # 1..n in each interval
    fine = edges[which] + widths[which] * (k / n[which])
    fine[ends] = times                       # exactly the output times, not rounded
    output = np.zeros(len(fine), dtype=bool)
    output[ends] = True
    return fine, output


def _within(chosen, mask):
    """``mask`` (over the points ``chosen`` marks) over all the points: False elsewhere."""
    whole = np.zeros(len(chosen), dtype=bool)
    whole[chosen] = mask
    return whole


#: what ``_locate_dense`` answers when the exact search must decide
_UNSURE = object()
