"""The integration methods a user can pick: one small class each, in one table (``METHODS``).

A method is started at a state and then ``advance``d by the driver (``driver.py``) over a
few output times at a time: the driver owns the output grid, budgets, time limits, progress,
cancellation, partial results and restarts, so a method only integrates. Two kinds exist:

- a whole-horizon CasADi integrator (CVODES, IDAS, RK, collocation, the midpoint rule): each
  ``advance`` runs in compiled code from the last state to the requested times;
- a scipy stepper (``OdeSolver`` subclasses): ``advance`` steps it, reading its dense output.

Adding a method is one class (or one instance of these) and one entry in ``METHODS``.
"""

import contextlib
import math
import re

import casadi as ca
import numpy as np

from ..errors import ModelError
from .compiled import numeric
from .tolerance import corrector_test, solver_tolerances


class Failure(Exception):
    """A method could not reach the times asked for; ``states`` holds the rows it did reach
    (at the first of those times), ``reason`` says why in plain words."""

    def __init__(self, reason, states=None):
        super().__init__(reason)
        self.reason = reason
        self.states = states


#: the reason of a call aborted to look whether auto's Adams stalls (``driver._stalled``)
LOOK = "looking whether the model became stiff"


def budget_spent(budget, t, steps=None):
    """The reason of a run that spent its step budget (``Run.budget``) at ``t`` (``steps``:
    how many it had taken when that was found)."""
    took = f" (it took {steps})" if steps is not None else ""
    return (f"the step budget of {budget} steps for the run ran out at t = {t:g} s{took}: "
            f"the problem may be stiff for this method, or the solution blows up")


class Interrupted(Exception):
    """Raised by the driver's signal handler to abort a compiled call (``Run.interruptible``)."""


class Method:
    """One integration method: what it can do, declared, and ``start``.

    What a method can do is declared by class attributes, which the driver and the events
    read (never the method's type or its other attributes):

    ``fixed``
        It takes a step size (``Run.step``, at most ``max_step``) instead of tolerances.
    ``newton``
        It iterates with the Jacobian (compiled with the right-hand side under JIT).
    ``dae``
        It takes the algebraic variables of loops.
    ``stepper``
        It is advanced step by step in Python (the driver reads the clock and the cancel
        flag at every step).
    ``interruptible``
        A signal can abort it within an ``advance`` (the driver then gives it long ones).
    ``events``
        The events it takes: "time" (it stops exactly at the instants ``Run.bound`` gives,
        never stepping past one, and lands on them with fixed steps) and "state" (its
        states at any trial time can be had, so state events are located on its own
        integration). A model with events of a kind a method does not take is refused.
    ``trial_states``
        Its runs have ``state_at(t)``: the state at any time after the start without
        advancing, from one integration for every trial time (else a trial time is a new
        run advanced there).

    ``start(run, t, x)`` returns a run of the method from the full state x at t, with the
    equations the integrators see (``compiled.Held``, parameters ``run.p_solver``, held at
    the values they have when it starts), never stepping past ``run.bound(t)``. A run has

    - ``advance(times, exact=False)``: the full states at ``times`` (increasing, after the
      last time reached), continuing from there. ``exact``: the times are not to be
      rounded onto the output grid. It raises ``Failure`` holding the rows it reached.
    - ``stats``: a dict of its counts so far: ``steps`` always; ``rhs_evaluations`` and
      ``jacobian_evaluations`` where the solver counts them; a fixed-step method also
      ``step``, its step size. Counters are summed over the runs a run is made of (restarts
      after events), anything else taken from the last.
    """
    fixed = False
    newton = False
    dae = False
    stepper = False
    interruptible = False
    events = ("time", "state")
    trial_states = False

    def __init__(self, doc):
        self.doc = doc

    def check(self, system):
        """Refuse (ModelError) a system this method cannot integrate."""

    def start(self, run, t, x):
        """An object with ``advance(times) -> states`` and ``stats``, starting at (t, x)."""
        raise NotImplementedError


# -- CasADi's integrators ---------------------------------------------------------------------
#: SUNDIALS return flags, in plain words
SUNDIALS_FLAGS = {
    "TOO_MUCH_WORK": "too many steps before the next output time: the solution may blow up "
                     "there, or the problem is stiff for this method",
    "TOO_MUCH_ACC": "the tolerances asked for are below machine precision",
    "ERR_FAIL": "the error test failed repeatedly: the step size collapsed",
    "CONV_FAIL": "the corrector iteration failed to converge repeatedly: the step size "
                 "collapsed",
    "RHSFUNC_ERR": "the right-hand side became non-finite (Inf or NaN): a force or a "
                   "parameter expression blows up",
    "RHSFUNC_FAIL": "the right-hand side became non-finite (Inf or NaN): a force or a "
                    "parameter expression blows up",
    "RES_FAIL": "the residual became non-finite (Inf or NaN)",
    "REP_RES_ERR": "the equations became non-finite (Inf or NaN) again and again: with loops, "
                   "the mechanism may have reached a dead point where the independent "
                   "coordinates (those with a given q0) can no longer drive it",
    "LSETUP_FAIL": "the linear solver setup failed (singular iteration matrix)",
    "LSOLVE_FAIL": "the linear solver failed (singular iteration matrix)",
}


_TIME = re.compile(r"\b(t\s*=\s*)([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)")


def shift_times(text, t0):
    """The solvers' words with the times they name (``t = 0.0032``) moved by ``t0``: they
    integrate each chunk in the time since its start."""
    if not t0:
        return text
    return _TIME.sub(lambda m: f"{m.group(1)}{float(m.group(2)) + t0:g}", text)


def solver_words(message):
    """What a solver said in a CasADi error, without CasADi's own framing."""
    lines = [ln.strip() for ln in message.splitlines() if ln.strip()]
    last = lines[-1] if lines else ""
    if "documentation." in last:        # SUNDIALS' flag (said in plain words already) ...
        last = last.rsplit("documentation.", 1)[-1].strip()     # ... and what follows it
    return last[:300] + "\n" if last else ""


def _budget_hit(said):
    """The time at which a SUNDIALS call ran out of its step budget, from what it printed
    (``At t = ..., mxstep steps taken``), or None."""
    found = re.search(r"At t\s*=\s*([-+0-9.eE]+)", said)
    try:
        return float(found.group(1)) if found else None
    except ValueError:
        return None


def solver_reason(message):
    """A CasADi integrator's error in plain words."""
    for flag, words in SUNDIALS_FLAGS.items():
        if flag in message:
            return words
    lines = [ln.strip() for ln in message.splitlines() if ln.strip()]
    return (lines or ["integrator failed"])[-1][:300]


class Casadi(Method):
    """A CasADi integrator plugin: each ``advance`` runs in compiled code, which checks
    Python's signals at every evaluation of the equations."""
    interruptible = True
    trial_states = True

    def __init__(self, plugin, doc, newton=False, fixed=False, dae=False, **options):
        super().__init__(doc)
        self.plugin, self.options = plugin, options
        self.newton, self.fixed, self.dae = newton, fixed, dae
        self.sundials = plugin in ("cvodes", "idas")

    def start(self, run, t, x):
        return _CasadiRun(self, run, t, x)


#: an integrator over more output times than this is not kept for the next run: CasADi
#: holds about 50 bytes per output time in it
KEPT_GRID = 100_000
#: the places of an integrator's inputs and outputs by name, the same for every one of
#: CasADi's integrators (looked up once: ``Function.index_in`` costs 2 us a call)
INTEGRATOR_IN = {name: i for i, name in enumerate(ca.integrator_in())}
INTEGRATOR_OUT = {name: i for i, name in enumerate(ca.integrator_out())}


class _CasadiRun:
    #: ``advance(times, out=rows)`` writes the states into ``rows`` when it can
    writes_in_place = True

    def __init__(self, method, run, t, x):
        self.method, self.run = method, run
        self.t, self.x = float(t), np.asarray(x, dtype=float)
        self.p = np.array(run.p_solver, dtype=float)     # the values held from here on
        self.stats = {"steps": 0}
        if method.sundials:
            self.stats.update(rhs_evaluations=0, jacobian_evaluations=0, factorisations=0)

    def options(self, times):
        m, run = self.method, self.run
        opts = dict(m.options)
        if m.sundials:      # tighter than asked: see tolerance.py
            opts.update(zip(("reltol", "abstol"), solver_tolerances(
                m, run.system, run.rtol, run.atol, run.t_end - run.t_start)))
            opts.update(corrector_test(m, run.instructions))
            # SUNDIALS' budget is per output interval: the share of the run's of an interval
            # of the grid (tolerance.step_budget); the driver counts the run's after each call
            opts["max_num_steps"] = run.budget(m, run.spacing)
            if run.max_step:
                opts["max_step_size"] = float(run.max_step)
            if run.look_steps is not None and run.look_steps < opts["max_num_steps"]:
                opts["max_num_steps"] = run.look_steps      # auto's look: driver.look_budget
        else:       # fixed steps: counted over the chunk; a blow-up is reported once, below
            opts["show_eval_warnings"] = False
            opts["number_of_finite_elements"] = run.steps_per_interval * len(times)
        return opts

    def integrator(self, times, opts, exact=False):
        """An integrator over ``times`` in the time since ``self.t``: on an output grid of
        equal intervals, the same one for every chunk of as many intervals (unless
        ``exact``: times an event is looked for at, which must not be rounded to the grid)."""
        key, build = self.recipe(times, opts, exact)
        # IDAS's options hold the state's rate: not reusable; a grid past KEPT_GRID is too
        # large to keep
        if self.method.plugin == "idas" or len(times) > KEPT_GRID:
            return build()
        return self.run.compiled.integrator(key, build)

    def recipe(self, times, opts, exact=False):
        """(the key its System keeps it by, the function that builds it) of ``integrator``:
        a batch of members maps the very integrator a run builds (``batch.py``)."""
        m, run = self.method, self.run
        n = len(times)
        step = None if exact else _equal_step(times, self.t, run.spacing)
        # a grid of its own (after an event) is seldom met again: its integrator is built
        # on the equations with their derivatives hidden (``Compiled.dae``)
        dae = run.compiled.dae(run.jit, m.newton, hidden=step is None)
        if step is not None:
            grid = ("uniform", n, step)          # equal intervals: j * step
            # an array, not a list: 8 bytes a time instead of 32 (a grid of millions)
            taus = lambda: np.arange(1, n + 1) * step  # noqa: E731
        else:
            grid = tuple((np.asarray(times, dtype=float) - self.t).tolist())
            taus = lambda: list(grid)  # noqa: E731
        key = ("integrator", m.plugin, grid, tuple(sorted(opts.items())), bool(run.jit))
        return key, lambda: ca.integrator("simulate", m.plugin, dae, 0.0, taus(), opts)

    def advance(self, times, exact=False, out=None):
        """The states at ``times`` (a row each), written into ``out`` (rows of the driver's
        array) when given and the model has no algebraic variables."""
        m, run = self.method, self.run
        if exact and len(times) == 1 and m.plugin != "idas":
            # one time off the grid (the next time event): by the integrator of any stretch
            x = self.state_at(float(times[0]))
            self.t, self.x = float(times[0]), x
            return x[None, :]
        opts = self.options(times)
        if m.plugin == "idas":
            # the consistent initial rate is f(t0, x0) (loops: z0 is consistent already):
            # IDAS's own search for it fails when it is large (a stiff spring)
            opts.update(calc_ic=False, init_xdot=run.rate(self.t, self.x))
            net = run.system.asm.net
            if net is not None and net.alg_z:
                # algebraic variables of circuits and signal loops move from the start (a
                # diode's voltage under a source in t), and IDAS starts their rates at 0:
                # its error test on them fails at every step size. Out of the test, they
                # are still solved at every step, and polished at the outputs
                opts["suppress_algebraic"] = True
        return self.call(self.integrator(times, opts, exact), opts, times, out)

    def call(self, integ, opts, times, out=None):
        """The states at ``times`` by the integrator ``integ`` built with ``opts`` for them
        (``integrator``), from where this run stands; it advances there. A run replayed
        (``replay.py``) calls its kept integrator here directly."""
        run = self.run
        nx = run.system.n_states
        run.calls += 1
        run.called = (integ, opts, run.look_steps)
        # CasADi writes each output row into these arrays as it reaches it (its buffer
        # interface): a failed or aborted call keeps the rows it reached, and no DM is
        # converted (50 ms for the 256 x 1001 states of a 128-link chain)
        x0, z0 = np.ascontiguousarray(self.x[:nx]), np.ascontiguousarray(self.x[nx:])
        p = np.append(self.p, self.t)
        nz = len(self.x) - nx
        if out is not None and not nz and out.shape == (len(times), nx) and \
                out.flags.c_contiguous:
            xf = out
            xf.fill(np.nan)
        else:
            xf = np.full((len(times), nx), np.nan)
        zf = np.full((len(times), nz), np.nan)
        buffer, evaluate = _bound(integ, x0, z0, p, xf, zf)
        try:
            with run.solver_section(self.t, descriptors=False), run.interruptible():
                evaluate()
            failed = None
        except (RuntimeError, Interrupted) as exc:
            failed = exc
        X = np.hstack([xf, zf]) if nz else xf
        reached = X[:_finite_rows(X)]
        self._count(buffer, len(reached) if failed is not None else len(times))
        if failed is not None:
            stop = run.stop_reason()
            if stop is not None:        # aborted by a signal, the time limit or cancel=
                raise Failure(stop, reached)
            if opts.get("max_num_steps") == run.look_steps and "TOO_MUCH_WORK" in str(failed):
                # auto's look budget ran out: the driver looks. Where, CVODES printed (its
                # words, not the run's); else, at most the next output time
                said = run.said.pop() if run.said and "mxstep" in run.said[-1] else ""
                hit = _budget_hit(said)
                run.look_hit = hit if hit is not None else float(times[len(reached)])
                raise Failure(LOOK, reached)
            run.said.append(shift_times(solver_words(str(failed)), self.t))
            reason = solver_reason(str(failed))
            raise Failure(reason, reached)
        if len(reached) < len(X):
            raise Failure("the state became non-finite (Inf or NaN)", reached)
        self.t, self.x = float(times[-1]), X[-1]
        return X

    def _count(self, buffer, intervals):
        """Steps and evaluations of the call just made through ``buffer`` (a fixed-step
        method: its steps over the ``intervals`` it covered)."""
        run = self.run
        if self.method.sundials:
            with contextlib.suppress(RuntimeError, KeyError):   # none if it failed at once
                st = buffer.stats()
                self.stats["steps"] += int(st["nsteps"])
                self.stats["rhs_evaluations"] += int(st["nfevals"])
                self.stats["jacobian_evaluations"] += int(st["n_call_jacF"])
                self.stats["factorisations"] += int(st.get("nlinsetups", 0))
        else:
            self.stats["steps"] += run.steps_per_interval * intervals
            self.stats["step"] = run.spacing / run.steps_per_interval

    def state_at(self, t):
        """The state at one time ``t`` after the start, not advancing: by one integrator over
        a stretch of any length (``Compiled.dae_scaled``), built once for all the times an
        event is looked for at (an integrator for each costs ~10 ms of CasADi's set-up)."""
        m, run = self.method, self.run
        if m.plugin == "idas":          # its options hold the state's rate: not reusable
            fresh = _CasadiRun(m, run, self.t, self.x)      # from the start, every time
            fresh.p = self.p
            x = fresh.advance(np.array([t]), exact=True)[0]
            _add_counts(self.stats, fresh.stats)
            return x
        return self._stretch(t, 1)[0]

    def grid(self, t, k):
        """The states at k equal steps from the start to ``t`` (k rows, the last at t), not
        advancing: one integration whatever the stretch (``state_at``'s, on a grid), or
        None for a method whose runs cannot (IDAS, fixed steps)."""
        if self.method.plugin == "idas" or self.method.fixed:
            return None
        return self._stretch(t, k)

    def _stretch(self, t, k):
        """The states at k equal steps from the start to ``t``, by one integrator over a
        stretch of any length (``Compiled.dae_scaled``) built once per k."""
        m, run = self.method, self.run
        nx = run.system.n_states
        opts = self.options([t])
        key = ("stretch", k, m.plugin, tuple(sorted(opts.items())), bool(run.jit))
        integ = run.compiled.integrator(key, lambda: ca.integrator(
            "locate", m.plugin, run.compiled.dae_scaled(run.jit, m.newton), 0.0,
            list(np.arange(1, k + 1) / k), opts))
        # through its buffer interface, as ``call``: no DM made or read (a dict call of the
        # 33-point stretch an event is located on spent a third of its time converting)
        p = np.concatenate([self.p, [self.t, t - self.t]])
        x0, z0 = np.ascontiguousarray(self.x[:nx]), np.ascontiguousarray(self.x[nx:])
        xf, zf = np.full((k, nx), np.nan), np.full((k, len(z0)), np.nan)
        buffer, evaluate = _bound(integ, x0, z0, p, xf, zf)
        try:
            with run.solver_section(self.t, descriptors=False):
                evaluate()
        except RuntimeError as exc:
            run.said.append(shift_times(solver_words(str(exc)), self.t))
            raise Failure(solver_reason(str(exc))) from None
        self._count(buffer, 1)
        rows = np.hstack([xf, zf]) if len(z0) else xf
        if not np.all(np.isfinite(rows)):
            raise Failure("the state became non-finite (Inf or NaN)")
        return rows


def _bound(integ, x0, z0, p, xf, zf):
    """(buffer, evaluate) of the integrator ``integ`` reading its inputs from and writing its
    outputs into these arrays (CasADi keeps raw pointers: they must outlive the call)."""
    buffer, evaluate = integ.buffer()
    for name, value in (("x0", x0), ("z0", z0), ("p", p)):
        if value.size:
            buffer.set_arg(INTEGRATOR_IN[name], memoryview(value))
    for name, value in (("xf", xf), ("zf", zf)):
        if value.size:
            buffer.set_res(INTEGRATOR_OUT[name], memoryview(value))
    return buffer, evaluate


def _equal_step(times, t0, spacing):
    """The step of ``times`` after ``t0`` when they are equal steps of the output
    ``spacing`` or of a whole fraction of it (the events' lattice), to rounding; else None.
    Such grids share one integrator whatever their start (each costs ~1 ms to build)."""
    n = len(times)
    if not n:
        return None
    step = (float(times[-1]) - t0) / n
    parts = round(spacing / step) if step > 0 else 0
    tiny = 1e-9 * max(1.0, abs(float(times[-1])))
    if parts < 1 or abs(parts * step - spacing) * n > tiny:
        return None
    step = spacing / parts
    if n > 1 and np.max(np.abs(np.asarray(times) - t0 - step * np.arange(1, n + 1))) > tiny:
        return None
    return step


def _add_counts(total, more):
    """The counters of ``more`` added into ``total``."""
    for key, value in more.items():
        if isinstance(value, int) and not isinstance(value, bool):
            total[key] = total.get(key, 0) + value


def _finite_rows(X):
    """How many rows of ``X`` from the first are finite (the outputs a call reached)."""
    # the sum is not finite when an entry is not (or when finite entries overflow it: then
    # the test by entries decides); one reduction, no array of flags
    if math.isfinite(X.sum()) or np.isfinite(X).all():
        return len(X)
    bad = ~np.all(np.isfinite(X), axis=1)
    return int(np.argmax(bad)) if bad.any() else len(X)


# -- scipy's steppers -------------------------------------------------------------------------
class Scipy(Method):
    """A scipy ODE solver (the stepper class ``solve_ivp`` uses) fed by the compiled CasADi
    right-hand side and Jacobian."""
    stepper = True

    def __init__(self, name, implicit=False):
        super().__init__(f"scipy solve_ivp {name}")
        self.name, self.newton = name, implicit

    def start(self, run, t, x):
        import scipy.integrate                 # 0.4 s to import: only when asked for
        system = run.system
        kwargs = {"jac": numeric(run.compiled.jacobian(run.jit), run.p_solver,
                                 system.n_states)} if self.newton else {}
        if run.max_step:
            kwargs["max_step"] = run.max_step
        fun = run.rhs()
        with np.errstate(all="ignore"):
            solver = getattr(scipy.integrate, self.name)(
                fun, t, x, run.bound(t), rtol=run.rtol, atol=run.atol, **kwargs)
        return _ScipyRun(solver, run)


class _ScipyRun:
    def __init__(self, solver, run):
        self.solver, self.run = solver, run
        # a stiff problem under an explicit method would step forever
        self.budget = run.budget(None)
        self.steps = 0
        self.stats = {}

    def advance(self, times, exact=False):
        solver, run = self.solver, self.run
        out = []
        with np.errstate(all="ignore"):     # a blow-up is reported below, not warned
            while len(out) < len(times):
                if solver.t_old is not None and times[len(out)] <= solver.t:
                    # the last step, taken for an earlier call, reaches past this time
                    dense = solver.dense_output()
                    while len(out) < len(times) and times[len(out)] <= solver.t:
                        out.append(dense(times[len(out)]))
                    continue
                if solver.status == "finished":     # at its bound: the time asked is it
                    if times[len(out)] - solver.t > 1e-13 * max(1.0, abs(solver.t)):
                        raise Failure(f"asked for t = {times[len(out)]:.17g} s, past the time "
                                      f"event at {solver.t:.17g} s the method stops at",
                                      np.array(out).reshape(-1, len(solver.y)))
                    out.append(np.array(solver.y))
                    continue
                message = solver.step()
                self.steps += 1
                if solver.status == "failed":
                    raise Failure(message, np.array(out).reshape(-1, len(solver.y)))
                if not np.all(np.isfinite(solver.y)):
                    raise Failure("the state became non-finite (Inf or NaN)",
                                  np.array(out).reshape(-1, len(solver.y)))
                if times[len(out)] <= solver.t:
                    dense = solver.dense_output()
                    while len(out) < len(times) and times[len(out)] <= solver.t:
                        out.append(dense(times[len(out)]))
                    continue
                if self.steps >= self.budget:
                    raise Failure(budget_spent(self.budget, solver.t),
                                  np.array(out).reshape(-1, len(solver.y)))
                run.check_stop(np.array(out).reshape(-1, len(solver.y)))
        self.stats = {"steps": self.steps,
                      "rhs_evaluations": int(solver.nfev),
                      "jacobian_evaluations": int(solver.njev)}
        return np.array(out)


# -- the midpoint rule ------------------------------------------------------------------------
class MidpointRule(Method):
    """The implicit midpoint rule in canonical coordinates (``midpoint.py``). It evaluates
    the equations at the middle of each step only, so it lands on time events with the
    equations as they are (no value held), and locates no state event."""
    fixed = True
    newton = True
    events = ("time",)

    def check(self, system):
        if system.asm.prescribed:
            raise ModelError("method 'midpoint' integrates a conservative tree in canonical "
                             "coordinates; this model has joints whose motion is prescribed "
                             "(a Position, Speed or Accelerate on a joint axis): use 'auto' "
                             "or 'idas'")
        if system.formulation != "tree" or not all(system.asm.regular):
            raise ModelError("method 'midpoint' works in canonical coordinates of a tree of "
                             "angles and distances; this model has kinematic loops or a "
                             "quaternion joint (Spherical, FreeMotion): use 'auto' or 'idas'")
        tree = [*system.coordinate_names, *system.speed_names]
        if list(system.state_names) != tree:
            others = [n for n in system.state_names if n not in tree]
            raise ModelError(f"method 'midpoint' integrates the joint coordinates and speeds "
                             f"of a multibody tree; this model has other states too "
                             f"({', '.join(others[:4])}{', ...' if len(others) > 4 else ''}: "
                             f"1-D masses and rotors, filters, signal blocks): use 'auto', "
                             f"'rk' or 'collocation'")

    def start(self, run, t, x):
        from .midpoint import Midpoint
        stepper = run.compiled.memo(("midpoint", bool(run.jit)),
                                    lambda: Midpoint(run.system, run.jit))
        return _MidpointRun(stepper, run, t, x)


class _MidpointRun:
    def __init__(self, stepper, run, t, x):
        self.stepper, self.run = stepper, run
        self.t, self.x = float(t), np.asarray(x, dtype=float)
        self.stats = {"steps": 0}

    def advance(self, times):
        grid = np.concatenate([[self.t], times])
        with self.run.solver_section():
            X, failure, stats = self.stepper.run(grid, self.x, self.run.p,
                                                 self.run.steps_per_interval)
        self.stats["steps"] += stats["steps"]
        self.stats.update(step=self.run.spacing / self.run.steps_per_interval,
                          residual=max(stats["residual"], self.stats.get("residual", 0.0)))
        if failure is not None:
            raise Failure(failure, X[1:])
        self.t, self.x = float(times[-1]), X[-1]
        return X[1:]


class Auto(Method):
    """The default, chosen per model by the driver (``choose``)."""
    dae = True

    def __init__(self):
        super().__init__("cvodes-adams, or cvodes (BDF) when the stiffness test says so; "
                         "idas for models with loops")


#: method name (case-insensitive) -> Method
METHODS = {
    "auto": Auto(),
    "cvodes-adams": Casadi("cvodes", "SUNDIALS CVODES, variable-order Adams-Moulton with "
                           "functional iteration: non-stiff, no Jacobian",
                           linear_multistep_method="adams",
                           nonlinear_solver_iteration="functional"),
    "cvodes": Casadi("cvodes", "SUNDIALS CVODES, variable-order BDF with Newton iteration: "
                     "stiff", newton=True),
    "idas": Casadi("idas", "SUNDIALS IDAS, variable-order BDF on the residual form: stiff, "
                   "and the method of models with loops", newton=True, dae=True),
    "rk": Casadi("rk", "CasADi's classical Runge-Kutta 4, fixed step", fixed=True),
    "collocation": Casadi("collocation", "CasADi's Radau IIA collocation (order 5), fixed "
                          "step: stiff", newton=True, fixed=True, dae=True),
    "midpoint": MidpointRule("implicit midpoint rule in canonical coordinates, fixed step: "
                             "symplectic, for long undamped runs"),
    "rk45": Scipy("RK45"),
    "dop853": Scipy("DOP853"),
    "radau": Scipy("Radau", implicit=True),
    "bdf": Scipy("BDF", implicit=True),
    "lsoda": Scipy("LSODA", implicit=True),
}
