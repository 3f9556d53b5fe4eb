"""The integrator driver: what runs one member of an integration plan (``plan.py``).

The driver owns everything around the integration: the output grid, the step budget, the
time limit, progress reports, cancellation (SIGINT, SIGTERM, or a ``cancel`` callable), the
capture of what the solvers print, partial results, opt-in restarts and the watch over
kinematic loops. A method (``methods.py``) only integrates: it is started at a state and
advanced over a few output times at a time.

A run that must be watched (a time limit, progress reports, a ``cancel`` callable, kinematic
loops, events) is handed to the method in chunks of the output grid: between chunks the driver
reads the clock and the cancel flag, reports progress and checks the loops. A chunk is sized by
the work the last one took (equation evaluations times the instructions of one evaluation) to
about ``chunks.CHUNK_WORK``: a fraction of a second on any machine, and the same chunks on every
machine, so a run's numbers never depend on how fast the machine is or how loaded.

Each chunk restarts a multistep method (order and step size begin again from one step of order
one: +33 % evaluations on a 128-link chain in 8 chunks), so a quiet run (nothing of the above
to watch, a CasADi method) goes in one call over the whole grid, up to MAX_CHUNK output
intervals. Signals still stop any run at
once: CasADi checks Python's signals at every evaluation of the equations, the driver's handler
aborts the call there, and the outputs it had reached are kept (CasADi writes them into the
driver's arrays as it goes). A quiet run and a watched one of the same model may differ at the
level of the tolerance (their restarts differ); each gives the same numbers every time.
"""

from __future__ import annotations

import _signal
import contextlib
import math
import signal
import threading
import time

import numpy as np

from ..equations.system import OVERFLOW, overflow_message
from ..errors import ModelError
from ..graph.settings import check_output, check_settings
from ..util import quote, suggest
from .capture import Section
from .chunks import MAX_CHUNK, _first_chunk, _merge, _next_chunk, _Rows, _work
from .compiled import compiled, numeric
from .events import EVENT_CHUNK
from .fallback import GaveUp, Rival, Stalled, _stalled, look_budget
from .loopwatch import Partitions, near_singular
from .methods import LOOK, METHODS, Failure, Interrupted, budget_spent
from .results import later_outputs
from .stiffness import choose
from .tolerance import step_budget

DEFAULTS = {"t_end": 10.0, "n_points": 1001, "method": "auto", "rtol": 1e-6, "atol": 1e-8,
            "step": None, "max_step": None}
#: seconds between looks at the time limit and cancel= within a compiled call
TICK = 0.1
#: restarts after a failure, with ``restart=True``, at most
MAX_RESTARTS = 3
#: a restarted run must keep the loops closed to this (m, or rotation-matrix entries)
RESTART_CLOSURE = 1e-6
#: the probe signals of a long grid are computed in chunks of about this much work (points
#: times the instructions of one evaluation: 10 ms or so), a stop served between them
OUTPUT_CHUNK_WORK = 1e7
#: after a run stopped (a signal, the time limit), the probe signals of what it reached are
#: still computed for at most this long [s] (unless stopped again), and kept
OUTPUT_GRACE = 0.5
#: a run whose states hold at most this many numbers computes its probe signals when they are
#: first read (``deferred_outputs``): the seed's 1001 points took 0.5 ms, a tenth of its run
DEFERRED_VALUES = 10**6
#: an assembly whose (dimensionless) measure of a singular position is below this at the last
#: output of a failed run is named as near its singular position there
NEAR_SINGULAR_ASSEMBLY = 1e-3


class Run:
    """One call of ``simulate``: the settings every method reads, and the driver's state."""

    def __init__(self, system, p, x0, grid, settings, jit, cancel, progress, restart,
                 started=None):
        self.system, self.p, self.x0, self.grid = system, p, x0, grid
        self.compiled = compiled(system)
        self.t_start, self.t_end = float(grid[0]), float(grid[-1])
        self.spacing = float(grid[1] - grid[0])
        self.rtol, self.atol = settings["rtol"], settings["atol"]
        self.max_step = settings["max_step"]
        self.step = settings["step"]
        if self.max_step is not None and self.max_step < (self.step or self.spacing):
            self.step = self.max_step        # a fixed step is a largest step too
        self.steps_per_interval = max(1, math.ceil(self.spacing / (self.step or self.spacing)
                                                   * (1 - 1e-12)))
        self.max_steps = settings["max_steps"]
        self.started = time.perf_counter() if started is None else started
        limit = settings["time_limit"]
        self.deadline = self.started + limit if limit else None
        self.jit = jit
        self.cancel, self.progress, self.restart = cancel, progress, restart
        self.signal = None              # the signal that stopped the run, if one did
        self.signals_seen = 0           # how many arrived
        self.instructions = self.compiled.memo(
            "instructions", lambda: (system.f_rhs or system.f_dae).n_instructions())
        self.said = []                  # what the solvers printed
        self.quiet = False              # nothing to watch: one call over the grid
        self.abortable = False          # a signal now aborts the compiled call
        #: auto's fallback runs against the method it replaces: a ``Rival``, or None
        self.rival = None
        #: auto's Adams watched by a step budget per output interval (``look_budget``), and
        #: the time its budget ran out at (set by the method whose call it stopped)
        self.look_steps = None
        self.look_hit = None
        #: the time of an output interval a look found not held by stability (the run went on
        #: over it unlooked) and in which the method then failed all the same: no stiffness,
        #: so auto's BDF is not tried after it
        self.look_cleared = None
        self.events = None              # friction, stops, relations: events.Events
        #: the parameters of the equations the integrators see (``compiled.Held``): the
        #: model's, then the values the relations are held at (``switches.py``)
        self.p_solver = p
        #: integrator calls made, and the last one's (integrator, options, look budget)
        self.calls, self.called = 0, None

    # -- what methods use --------------------------------------------------------------------
    def solver_section(self, t0=0.0, descriptors=True):
        """Run compiled solver code with its printing captured (and serialised: see
        ``capture.SOLVER_LOCK``); the code integrates in the time since ``t0``, so the times it
        names are shifted back by ``t0``. Without ``descriptors``: code that prints through
        Python's streams only, CasADi's integrators (``capture.solver_output``)."""
        return Section(self, t0, descriptors)

    @contextlib.contextmanager
    def interruptible(self):
        """Within, a signal aborts the compiled call (``Interrupted``, or the solver's failure)
        at its next evaluation of the equations, instead of waiting for its end."""
        self.abortable = True
        try:
            if self.signal is not None:          # it came before the call
                raise Interrupted
            yield
        finally:
            self.abortable = False

    def budget(self, method, interval=None):
        """The steps a run of ``method`` (None: one of scipy's) may take: ``max_steps`` if
        given, else ``tolerance.step_budget`` for its length; with ``interval`` [s], an output
        interval that long (``max_steps`` again if given: the run's steps are counted by the
        driver)."""
        if self.max_steps:
            return int(self.max_steps)
        return step_budget(method, self.system, self.t_end - self.t_start, interval)

    def rhs(self):
        """The right-hand side as a fast Python callable ``(t, x) -> xdot`` of the values the
        integrators see (scipy's methods, the stiffness tests)."""
        return numeric(self.compiled.rhs(self.jit), self.p_solver, self.system.n_states)

    def rate(self, t, X):
        """d(x)/dt at a consistent full state X = (x, z), as IDAS's ``init_xdot``."""
        nx = self.system.n_states
        rate = self.compiled.held.f_dae(t, X[:nx], X[nx:], self.p_solver)[0]
        return tuple(float(v) for v in np.asarray(rate).ravel())

    def bound(self, t):
        """The time a method started at t must not step past: the next time event, or the
        end of the run."""
        return self.t_end if self.events is None else self.events.bound(t)

    def stop_reason(self):
        """Why the run must stop now (cancelled, interrupted, out of time), or None."""
        if self.signal is not None:
            return f"interrupted by {signal.Signals(self.signal).name}"
        if self.cancel is not None and self.cancel():
            return "cancelled"
        if self.deadline is not None and time.perf_counter() > self.deadline:
            return "the time limit set for the run was reached"
        return None

    def check_stop(self, states):
        """For steppers, at every step: a Failure holding ``states`` when the run must stop."""
        reason = self.stop_reason()
        if reason is not None:
            raise Failure(reason, states)


def _check(system, settings, t_start, max_steps, time_limit, runs=1):
    """The method's table key, once every setting is checked (one ModelError for all)."""
    if not isinstance(t_start, (int, float)) or isinstance(t_start, bool) or \
            not math.isfinite(t_start):
        raise ModelError(f"t_start: must be a finite number, got {quote(t_start, 40)}")
    problems = check_settings({k: settings[k] for k in DEFAULTS}, t_start)
    if not problems and settings["t_end"] <= t_start:
        problems.append(f"simulation.t_end: must be > t_start = {t_start}, "
                        f"got {settings['t_end']}")
    if not problems:        # what the results would hold: time, the full state, the probes
        problems += filter(None, [check_output(int(settings["n_points"]),
                                               output_values(system), runs)])
    for name, value, kind in (("max_steps", max_steps, int), ("time_limit", time_limit, float)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))
                                  or not math.isfinite(value) or value <= 0
                                  or (kind is int and int(value) != value)):
            problems.append(f"{name}: must be a positive {'integer' if kind is int else 'number'}"
                            f", got {value!r:.40}")
    if problems:
        raise ModelError(problems)
    key = settings["method"].lower()
    if key not in METHODS:
        raise ModelError(f"method {settings['method']!r:.60}: unknown{suggest(key, METHODS)}; "
                         f"methods are {', '.join(METHODS)}")
    rel = system.relations
    if "state" not in METHODS[key].events:
        located = [f"friction or stops ({', '.join(c.name for c in system.modes.comps)})"] \
            if system.modes is not None else []
        if rel is not None and len(rel.state):      # (its text reads the equations: 10 ms)
            located.append(f"a relation on the states, {rel.text(rel.state[0])}; write it in "
                           f"noEvent(...) to take it as it is")
        if located:
            raise ModelError(
                f"method {settings['method']!r} locates no state events, and "
                f"{system.model.name!r} has them: {'; '.join(located)}. Use 'auto', a "
                f"CVODES, IDAS or scipy method, 'rk' or 'collocation'")
    if system.n_algebraic and not METHODS[key].dae:
        raise ModelError(
            f"method {settings['method']!r} integrates ODEs only, and {system.model.name!r} "
            f"has algebraic variables ({', '.join(system.algebraic_names[:3])}"
            f"{', ...' if system.n_algebraic > 3 else ''}: the dependent coordinates of "
            f"kinematic loops, or the unknowns of a nonlinear circuit or signal loop); use "
            f"{', '.join(k for k, m in METHODS.items() if m.dae)}, or, for loops, compile the "
            f"model with loops='projected' or loops='baumgarte' (ODEs)")
    return key


def output_values(system):
    """Numbers a run of ``system`` keeps per output point: time, the full state and every
    probe value (``check_output`` adds what the run needs beside them)."""
    return 1 + system.n_states + system.n_algebraic + sum(sig.size for sig in system.signals)


def _check_finite_start(system, t, x0, p):
    """Refuse, before integrating, a model whose numbers overflow double precision at the
    start (g = 1e300, a length of 1e300 squared in an inertia): its state or its rates are
    not finite there, or so large that the next products will not be. Checked once per
    start and parameter values."""
    key = ("finite start", float(t), x0.tobytes(), np.asarray(p, dtype=float).tobytes())
    compiled(system).memo(key, lambda: _finite_start(system, t, x0, p))


def _finite_start(system, t, x0, p):
    _, singular = system.assembly_singular([t], x0[None, :], p)
    if singular:
        raise ModelError([f"at the start (t = {t:g} s): {m}; give other start values or "
                          f"guesses" for m in singular])
    values = [x0]
    if system.n_states:
        nx = system.n_states
        with np.errstate(all="ignore"):
            values += [np.asarray(v) for v in system.f_dae(t, x0[:nx], x0[nx:], p)]
    if all(np.all(np.abs(v) < OVERFLOW) for v in values):   # NaN fails too
        return True
    raise ModelError(overflow_message(system.model, "the equations", p, system.param_names))


def _auto(run, stats):
    """Auto's run: its methods in turn (``choose``), each after the last failed or stalled;
    a fallback slower than the method it replaces gives up (``Rival``), and that method's
    answer stands: its failure, or, had it only stalled, its run to the end unwatched."""
    names, why = choose(run)
    stats.update(why)
    before = None                       # (name, X, failure, stats) of the method replaced
    for i, name in enumerate(names):
        watch = name == "cvodes-adams" and i < len(names) - 1 and run.events is None
        run.look_steps = look_budget(run) if watch else None
        # a fixed step replaced (its step too long somewhere) sets no pace for Adams
        run.rival = None if before is None or METHODS[before[0]].fixed else \
            Rival(before[0], _work(run, before[3]), run.t_start, run.grid[len(before[1]) - 1])
        X, failure, method_stats = _integrate(run, METHODS[name])
        run.look_steps = run.rival = None
        if isinstance(failure, GaveUp) and run.stop_reason() is None:
            stats["gave_up"] = {"method": name, "for": before[0], "at": failure.t,
                                "why": f"{name} {failure}"}
            name, X, failure, method_stats = before
            if isinstance(failure, Stalled):    # it had not failed: on to the end
                X, failure, method_stats = _integrate(run, METHODS[name])
            stats.update(method_stats)
            return X, failure, name
        if failure is None or i == len(names) - 1 or run.stop_reason() is not None:
            stats.update(method_stats)
            return X, failure, name
        stats["adams_failure"] = failure
        if run.look_cleared is not None and not isinstance(failure, Stalled):
            # it failed in an interval whose step the look found not held by stability:
            # not stiffness, so BDF from the start would fail there too, at its own cost
            stats.update(method_stats)
            return X, (f"{failure}; BDF was not tried: at t = {run.look_cleared:g} s the "
                       f"stiffness test found the step not held by stability"), name
        if isinstance(failure, Stalled):
            stats["switched"] = {"from": name, "to": names[i + 1], "at": failure.t,
                                 "why": str(failure)}
        before = (name, X.copy(), failure, method_stats)
    raise AssertionError("unreachable")


def _integrate(run, method):
    """States on the grid from ``method``, chunk by chunk: (X, failure or None, stats)."""
    grid, n = run.grid, len(run.grid)
    X = _Rows(run.x0, n)
    parts = Partitions(run)            # the loops' partitions the run goes through
    stats, restarts = {}, []           # stats: of the steppers replaced by restarts
    if method.fixed and run.max_steps and run.steps_per_interval * (n - 1) > run.max_steps:
        return X.array(), (f"the step budget of {run.max_steps} steps for the run is smaller "
                             f"than the {run.steps_per_interval * (n - 1)} steps of "
                             f"{run.step or run.spacing:g} s that the fixed-step method "
                             f"takes"), stats
    if run.events is not None:
        # as at the start, with the values held there (auto may try another method after
        # one that failed, later in the run)
        run.events.reset()
    try:
        stepper = method.start(run, grid[0], X[0])
    except Failure as failure:
        return X.array(), failure.reason, stats
    # (time events alone: each call goes to the next of them, the method restarts there)
    run.quiet = method.interruptible and (run.events is None or not run.events.located) and \
        run.system.f_dependent is None and run.progress is None and run.cancel is None \
        and run.deadline is None and run.rival is None
    chunk = n - 1 if method.stepper or run.quiet else _first_chunk(run, method, n - 1)
    if not method.stepper:
        chunk = min(chunk, MAX_CHUNK)
    if run.events is not None and run.events.located:
        chunk = min(chunk, EVENT_CHUNK)
    k, failure = 0, None
    restart_at = None                   # with events: where the last one left the run
    unlooked = None                     # auto's look budget, off over one interval
    while k < n - 1:
        failure = run.stop_reason()
        if failure is not None:
            break
        m = min(chunk, n - 1 - k)
        times = grid[k + 1:k + 1 + m]
        work_before = _work(run, stepper.stats)
        # with events: from where the method started last (an event between outputs)
        origin, restarted = restart_at or (grid[k], X[-1]), restart_at is not None
        restart_at = None
        try:
            if run.events is None and getattr(stepper, "writes_in_place", False):
                new = stepper.advance(times, out=X.slot(m))
            elif run.events is None:
                new = stepper.advance(times)
            else:
                new, restart_at = run.events.advance(method, stepper, times, origin, restarted)
        except Failure as exc:
            new = exc.states if exc.states is not None else np.zeros((0, len(X[0])))
            # (a CasADi call keeps every output it reached before it failed: CasADi writes
            # each into the rows as it gets there, so no output is integrated again)
            failure = exc.reason
        if unlooked is not None:
            run.look_steps, unlooked = unlooked, None
            if failure is not None and run.stop_reason() is None:
                run.look_cleared = float(grid[k])
        if restart_at is not None:            # an event: the method starts afresh there
            stats = _merge(stats, stepper.stats)
            try:
                stepper = method.start(run, *restart_at)
            except Failure as exc:
                failure = exc.reason
        turn = None
        new, failure = _assembly_watch(run, X, new, failure)
        if run.system.f_dependent is not None:
            new, failure, turn = parts.watch(X, new, failure)
        X.extend(new)
        k = len(X) - 1
        if run.progress is not None and len(new):
            run.progress(float(grid[k]))
        if failure == LOOK:          # auto's Adams ran long: stalled? (else it goes on)
            failure = _stalled(run, grid[k], X[-1],
                               stats.get("steps", 0) + stepper.stats.get("steps", 0))
            if failure is None and k < n - 1:
                stats = _merge(stats, stepper.stats)
                try:
                    stepper = method.start(run, grid[k], X[-1])
                except Failure as exc:
                    failure = exc.reason
                else:
                    # the interval over with the run's own budget, unlooked: a look again in
                    # it would begin it again from the same state, whose stability the
                    # look has just found does not hold the step (a method crawling to a
                    # dead point would take each doubled budget from there, in turn)
                    unlooked, run.look_steps, chunk = run.look_steps, None, 1
                    continue
        if turn is not None and run.stop_reason() is None:
            switched = parts.switch(method, X, turn)
            if switched is not None:       # the loops re-partitioned: on from there
                stats = _merge(stats, stepper.stats)
                stepper, failure, chunk = switched, None, 1
                continue
        if failure is None and not method.fixed:
            if run.rival is not None:
                failure = run.rival.outrun(run, stats, stepper.stats, grid[k])
            failure = failure or _spent(run, method, stats, stepper.stats, grid[k])
            if failure is not None:
                break
        if failure is not None:
            if run.stop_reason() is None and _restart(run, method, X, restarts, failure):
                stats = _merge(stats, stepper.stats)
                stepper, failure = restarts[-1]["stepper"], None
                k, chunk = len(X) - 1, 1
                continue
            break
        if run.quiet:                   # the rest at once (after a restart's first output)
            chunk = min(n - 1 - k, MAX_CHUNK)
        elif not method.stepper:
            chunk = min(_next_chunk(run, m, _work(run, stepper.stats) - work_before,
                                    n - 1 - k), MAX_CHUNK)
            if run.events is not None and run.events.located:
                chunk = run.events.chunk(chunk, restart_at is not None, grid[k])
            chunk = parts.limit(chunk)
        elif run.events is not None and run.events.located:
            # a stepper goes on between chunks: they bound what an event makes it do again
            chunk = run.events.chunk(n - 1 - k, restart_at is not None)
    if failure is not None and run.system.f_dependent is not None and \
            run.stop_reason() is None and "singular" not in failure:
        failure += near_singular(run, X.array(), grid)
    stats = _merge(stats, stepper.stats)
    if run.events is not None:              # the integrations that located its events
        stats = _merge(stats, run.events.spent)
    if restarts:
        stats["restarts"] = [{"t": r["t"], "after": r["after"]} for r in restarts]
    stats.update(parts.done())
    return X.array(), failure, stats


def _probe_outputs(run, t, X):
    """The full states polished (loops closed to machine precision) and the probe signals,
    computed in chunks of the grid into arrays allocated once: (X, outputs, why cut or
    None). Between chunks a stop is served (a signal, ``cancel``, the time limit): what was
    computed is kept, cut at the last whole chunk. A run already stopped before this phase
    gets OUTPUT_GRACE seconds for it (the outputs of what it reached), unless stopped again.
    """
    system, p, n = run.system, run.p, len(t)
    f_out = compiled(system).outputs(run.jit)
    width = system.f_out.size1_out(0)
    outputs = np.empty((n, width))
    if not n:
        return X, outputs, None
    size = _output_layout(system)[0]
    started, earlier, seen = time.perf_counter(), run.stop_reason(), run.signals_seen

    def stopped():
        if earlier is None or run.signals_seen != seen:
            why = run.stop_reason()
            return None if why is None else f"{why} while the probe signals were computed"
        if time.perf_counter() - started > OUTPUT_GRACE:
            return f"the probe signals were computed for {OUTPUT_GRACE:g} s after the stop"
        return None

    polished = X if not system.n_algebraic else np.array(X, dtype=float)
    for k in range(0, n, size):
        if k and (why := stopped()) is not None:
            return polished[:k], outputs[:k], f"{why}: kept up to t = {t[k - 1]:g} s"
        rows = slice(k, min(n, k + size))
        if system.n_algebraic:
            polished[rows] = system.polish(polished[rows], p, t[rows])
        system.outputs_into(t[rows], polished[rows], p, outputs[rows], f_out)
    return polished, outputs, None


def _output_layout(system):
    """(points per chunk of the probe signals: about OUTPUT_CHUNK_WORK of work, a power of
    two, few sizes, each a mapped Function; their columns), found once per System."""
    def layout():
        most = int(min(max(OUTPUT_CHUNK_WORK / max(system.f_out.n_instructions(), 1), 256),
                       2**16))
        return 2 ** int(np.log2(most)), system.f_out.size1_out(0)
    return compiled(system).memo("output layout", layout)


def deferred_outputs(run, t, X):
    """The probe signals of states X at times t as a callable that computes them when the
    Results first read them (``Results``), or None where they must be computed at once: a
    run the time limit, ``cancel`` or a progress report watches (their stops are served
    between chunks of the outputs too), signals of more than one chunk (a signal stops
    the run between them), loops to polish, a clock to check, or states of over
    DEFERRED_VALUES numbers (they are copied, so that writes into ``res.states`` do not
    change the signals)."""
    system = run.system
    size, width = _output_layout(system)
    if system.n_algebraic or system.eq.clock is not None or X.size > DEFERRED_VALUES or \
            run.deadline is not None or run.cancel is not None or run.progress is not None \
            or len(t) > size:
        return None
    return later_outputs(system, compiled(system).outputs(run.jit), width, t, X, run.p)


def _assembly_watch(run, X, new, failure):
    """(rows, failure): the new rows before an assembly that closes its loop in closed form
    reaches a singular position (its two solutions meet, MSL's assertion), and the failure
    that stops the run there; for a run that failed, the last row's singular positions
    appended to its reason."""
    system = run.system
    if system.f_assembly_checks is None:
        return new, failure
    times = run.grid[len(X):len(X) + len(new)]
    i, singular = system.assembly_singular(times, new, run.p)
    if i is not None:
        return new[:i], f"at t = {times[i]:g} s, " + "; ".join(singular)
    if failure is not None:
        last, t = (new[-1], times[-1]) if len(new) else (X[-1], run.grid[len(X) - 1])
        _, near = system.assembly_singular([t], np.atleast_2d(last), run.p,
                                           NEAR_SINGULAR_ASSEMBLY)
        if near:
            failure += f"; at the last output (t = {t:g} s) " + "; ".join(near)
    return new, failure


def _spent(run, method, stats, more, t):
    """After a call that reached ``t``: why the run stops when it has taken more steps than
    its budget (those of the runs restarts and events replaced counted too), else None.

    SUNDIALS bounds the steps of each output interval, not of a call over many (a quiet run
    is one call): no interval takes more than the run's budget, and a call that took more in
    all fails here, done or not. So a run succeeds exactly when it takes no more steps than
    its budget, however many output points it has."""
    budget = run.budget(method)
    steps = stats.get("steps", 0) + more.get("steps", 0)
    return budget_spent(budget, t, steps) if steps > budget else None


def _restart(run, method, X, restarts, failure):
    """With ``restart=True``: start ``method`` afresh from the last state, if it is sound and
    the restarted run continues it without a jump. Returns whether the run goes on."""
    if not run.restart or len(restarts) >= MAX_RESTARTS or len(X) < 2 or len(X) >= len(run.grid):
        return False
    if run.events is not None:      # its trial interval would not look for them
        return False
    system, last, before = run.system, X[-1], X[-2]
    if not np.all(np.isfinite(last)) or \
            system.constraint_residual_p(last[None, :], run.p)[0] > RESTART_CLOSURE:
        return False
    k = len(X) - 1
    try:
        stepper = method.start(run, run.grid[k], last)
        nxt = stepper.advance(run.grid[k + 1:k + 2])
    except Failure:
        return False
    # continuity: the first restarted interval moves about as much as the last good one did
    scale = run.atol + run.rtol * np.abs(last)
    if np.any(np.abs(nxt[0] - last) > 10 * np.abs(last - before) + 100 * scale):
        return False
    if system.constraint_residual_p(nxt, run.p)[0] > RESTART_CLOSURE:
        return False
    X.append(nxt[0])
    restarts.append({"t": float(run.grid[k]), "after": failure, "stepper": stepper})
    return True


@contextlib.contextmanager
def _running(run):
    """While a run goes: SIGINT and SIGTERM stop it (main thread only: Python delivers
    signals there), within a CasADi call or between chunks, instead of a KeyboardInterrupt
    inside CasADi or a kill."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def stop(signum, frame):
        run.signal = signum
        run.signals_seen += 1
        if run.abortable:           # raised in CasADi's check for signals: the call stops
            run.abortable = False
            raise Interrupted

    def tick(signum, frame):
        if not run.abortable:
            return
        # not abortable while it looks: a tick arriving within this one (cancel= may wait on
        # a lock, as the studio's Event does) returns at once instead of taking it again
        run.abortable = False
        if run.stop_reason() is not None:
            raise Interrupted
        run.abortable = True
    saved, timer = {}, None
    # through the C module under ``signal``: its Python wrapper turns each handler into an
    # enum at 60 us a call (0.25 ms of a run that takes 3 ms)
    for sig, handler in ((signal.SIGINT, stop), (signal.SIGTERM, stop)):
        try:
            saved[sig] = _signal.signal(sig, handler)
        except (ValueError, OSError):     # not settable here (an embedded interpreter)
            pass
    if run.deadline is not None or run.cancel is not None:
        # the time limit and cancel= are looked at every TICK s within a compiled call as
        # well: a chunk sized for a fraction of a second can take minutes (a stiff model
        # under Adams takes 100x the steps the chunk was sized for)
        with contextlib.suppress(ValueError, OSError):
            saved[signal.SIGALRM] = _signal.signal(signal.SIGALRM, tick)
            timer = signal.setitimer(signal.ITIMER_REAL, TICK, TICK)
    try:
        yield
    finally:
        if timer is not None:             # the caller's own timer, as it was
            signal.setitimer(signal.ITIMER_REAL, *timer)
        for sig, handler in saved.items():
            _signal.signal(sig, handler)
