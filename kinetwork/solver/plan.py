"""The one integration plan: a System and its settings, checked once; every answer goes
through it.

A ``Plan`` holds what a run of a model needs beyond its parameter values: the System (a model
is compiled once; component parameters named by path are lifted to model parameters of a twin
compiled once, ``graph/lift.py``), the output grid, the method and how ``auto`` chooses it
(the stiffness test, ``stiffness.choose``), the tolerances (mapped to the solvers' by
``tolerance.solver_tolerances`` inside the methods), JIT, events, chunking, cancellation and
the detection of failures (``driver.py``). Its ways to an answer:

- ``Plan.run``: one run, what ``kn.simulate`` returns;
- ``solver.batch.run_members``: many members, each the run ``Plan.run`` makes for its
  parameters (the same integrator with its own error control, mapped over members in
  CasADi's threads), for ``kn.sweep`` and ``kn.sample``;
- ``Plan.trajectory``: the same method and tolerances as a CasADi Function whose forward
  sensitivities CasADi derives, for ``kn.sensitivity`` and ``kn.fit``.

So a tolerance means one thing on every path (``tolerance.py``), and a setting a run takes
(``max_steps``, a ``time_limit``, events) reaches every member of a sweep.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from ..equations.system import System
from ..errors import ModelError, SimulationError
from ..graph.lift import is_path, lift
from ..graph.settings import check_output
from ..units import to_si
from ..util import quote, suggest
from . import estimate
from . import jit as _jit
from .capture import last_words
from .compiled import compiled
from .driver import (DEFAULTS, Run, _assembly_watch, _auto, _check, _check_finite_start,
                     _integrate, _probe_outputs, _running, deferred_outputs,
                     output_values)
from .events import Events
from .methods import METHODS, Casadi, _CasadiRun
from .stiffness import choose
from .progress import progress_bar
from .replay import record, replay
from .results import Results

if TYPE_CHECKING:                     # annotations only
    from ..graph.model import Model

log = logging.getLogger("kinetwork")

#: what a run takes besides the model's experiment settings (DEFAULTS), with their defaults
RUN_OPTIONS = {"t_start": 0.0, "jit": None, "max_steps": None, "time_limit": None,
               "restart": False, "repartition": True}


class Plan:
    """A System and its run settings, checked once: every run, member, sensitivity and fit of
    the model goes through one.

    Parameters
    ----------
    model : Model or System
    names : sequence of str
        The parameters that runs of this plan will be given: model parameters, or component
        parameters by path (``"spring.c"``, ``"cyl3.piston.mass"``, ``"body.r_cm[0]"``, a
        subsystem's ``"cyl1.phi0"``), which are lifted to model parameters of a twin of the
        model (compiled once, kept; ``stats["lifted"]`` says so).
    grid : array, optional
        The output times (increasing, from ``t_start``) instead of ``n_points`` equal
        intervals up to ``t_end``.
    **settings
        ``t_end``, ``n_points``, ``method``, ``rtol``, ``atol``, ``step``, ``max_step`` (not
        given: the model's ``simulation`` block, then ``DEFAULTS``), and ``t_start``, ``jit``,
        ``max_steps``, ``time_limit``, ``restart``, ``repartition`` as ``kn.simulate`` takes
        them.
    """

    def __init__(self, model: Model | System, names: Sequence[str] = (), grid=None,
                 **settings):
        unknown = [k for k in settings if k not in DEFAULTS and k not in RUN_OPTIONS]
        if unknown:
            known = [*DEFAULTS, *RUN_OPTIONS]
            raise ModelError([f"{quote(k, 40)}: no setting of a run{suggest(k, known)}; "
                              f"settings are {', '.join(known)}" for k in unknown])
        self.system, self.lifted, self.aliases = _resolve(model, names)
        system = self.system
        options = {k: settings.get(k, v) for k, v in RUN_OPTIONS.items()}
        if options["t_start"] is None:
            options["t_start"] = 0.0
        given = {k: settings.get(k) for k in DEFAULTS}
        if grid is not None:
            grid = _checked_grid(grid, options["t_start"])
            given.update(t_end=float(grid[-1]), n_points=len(grid))
        merged = {**DEFAULTS, **system.model.simulation,
                  **{k: v for k, v in given.items() if v is not None}}
        t_start = options["t_start"]
        self.key, equal, given = _checked(system, merged, t_start, options["max_steps"],
                                          options["time_limit"])
        #: the settings as a key (None: unhashable, or a grid given): what a run's recipe is
        #: kept by (``replay.py``)
        self.given = given if grid is None else None
        self.grid = grid if grid is not None else equal.copy()
        merged.update(max_steps=options["max_steps"], time_limit=options["time_limit"],
                      n_points=len(self.grid), rtol=float(merged["rtol"]),
                      atol=float(merged["atol"]))
        self.settings = merged
        self.t_start = float(t_start)
        self.jit, self.restart = options["jit"], bool(options["restart"])
        self.repartition = bool(options["repartition"])
        self.options = options
        self.jit_on = _jit.enabled(self.jit) and system.n_states > 0

    # -- parameters --------------------------------------------------------------------------
    def param_name(self, name):
        """The name in the System of parameter ``name`` (a model parameter, or a lifted
        path); a ModelError for any other."""
        if name in self.aliases:
            return self.aliases[name]
        if name in self.system.param_names:
            return name
        known = list(self.aliases) + [n for n in self.system.param_names
                                      if n not in self.aliases.values()]
        raise ModelError(f"{quote(name, 80)} is no model parameter{suggest(name, known)}; "
                         f"parameters are {', '.join(known) or 'none'}, or a component "
                         f"parameter by its path ('spring.c')")

    def vector(self, params: Mapping[str, float | str] | None = None) -> np.ndarray:
        """The parameter vector p of the System for ``params`` (name -> number, or number with
        a unit), every value and every component parameter that depends on one checked."""
        if not params:
            return self._default_vector()
        overrides = {self.param_name(k): self.si(k, v) for k, v in (params or {}).items()}
        if self.lifted is not None:
            missing = {p: n for p, n in self.lifted.names.items() if n not in overrides}
            if missing and overrides:
                # a lifted parameter not given follows what the model gives it, with the
                # model parameters given here
                env = self.system.model.parameter_values(overrides)
                defaults = self.lifted.defaults(env)
                overrides.update({n: defaults[n] for n in missing.values()})
        return self.system.param_vector(overrides)

    def _default_vector(self):
        """p of the model's own values, checked once per System and values (0.1 ms a run)."""
        system, given = self.system, self.system.model.parameters
        try:
            values = (tuple(given), tuple(given.values()), tuple(map(type, given.values())))
            hash(values)
        except TypeError:               # an unhashable value: checked, and refused, there
            return system.param_vector({})
        return compiled(system).checked(("parameters", values),
                                        lambda: system.param_vector({})).copy()

    def si(self, name, value):
        """``value`` of parameter ``name`` in SI: a lifted path's quantity text ("2 kg")
        converted to its component parameter's unit; a model parameter's kept as text (the
        model checks it against its uses)."""
        if isinstance(value, str) and self.lifted is not None and name in self.lifted.units:
            try:
                return to_si(value, self.lifted.units[name])
            except ModelError as exc:
                raise ModelError(f"params.{name} = {quote(value, 60)}: {exc}") from None
        return value

    def start(self, p):
        """The initial full state (x, then the algebraic z of loops) for p: consistent with
        the loops and the initial equations, its equations finite there. Solved once per
        parameter values."""
        system = self.system
        x0 = compiled(system).memo(("initial state", np.asarray(p, dtype=float).tobytes()),
                                   lambda: np.concatenate(system.initial_full_p(p))).copy()
        _check_finite_start(system, self.t_start, x0, p)
        return x0

    def methods(self, run, keep=True):
        """The methods a run tries in order, and why (``auto``: the stiffness test, its
        answer kept for the next run of the same parameters unless not ``keep``)."""
        if self.key != "auto":
            return [self.key], {}
        return choose(run, keep)

    # -- one run ------------------------------------------------------------------------------
    def new_run(self, p, x0, cancel=None, progress=None, started=None):
        """The driver's Run of p from x0 (its events started: modes consistent there);
        ``started``, the ``time.perf_counter()`` its time limit counts from (default: now)."""
        run = Run(self.system, p, x0, self.grid, self.settings, None, cancel, progress,
                  self.restart, started)
        run.repartition = self.repartition
        if self.system.modes is not None or self.system.relations is not None:
            # modes consistent with the start, relations' values there, before any method
            run.events = Events(run)
            run.x0 = run.events.start(float(self.grid[0]), run.x0)
        return run

    def run(self, params: Mapping[str, float | str] | None = None, *, p=None,
            cancel: Callable[[], object] | None = None,
            progress: Callable[[float], object] | None = None,
            error_estimate: bool = False, started: float | None = None) -> Results:
        """One run: what ``kn.simulate`` returns (see there). ``p`` (the checked parameter
        vector) instead of ``params`` skips their check; ``params`` is then what the results
        record. ``started``: the ``time.perf_counter()`` the time limit counts from (default:
        now)."""
        system, settings = self.system, self.settings
        if error_estimate:          # an error estimate holds three runs' results at once
            too_large = check_output(len(self.grid), output_values(system), runs=3)
            if too_large:
                raise ModelError(too_large)
        if p is None:
            p = self.vector(params)
        if cancel is None and progress is None and not error_estimate and \
                settings["time_limit"] is None:
            replayed = replay(self, p, params, started)
            if replayed is not None:
                return replayed
        x0 = self.start(p)
        stats = {}
        if self.lifted is not None:
            stats["lifted"] = self.lifted.note
        run = self.new_run(p, x0, cancel, progress, started)
        with _running(run):
            run.jit = self.jit_options(run, stats)
            if not system.n_states:   # everything welded to the ground: nothing to integrate
                X, failure, key = np.tile(x0, (len(self.grid), 1)), None, "none"
                # a mechanism that motions move all the way: its assemblies are watched all
                # the same (a driven crank can pull one past its singular position)
                X, failure = _assembly_watch(run, X[:1], X[1:], failure)
                X = np.vstack([x0[None, :], X])
            elif self.key == "auto":
                X, failure, key = _auto(run, stats)
            else:
                X, failure, method_stats = _integrate(run, METHODS[self.key])
                stats.update(method_stats)
                key = self.key
            # the probe signals, a stop served between their chunks: inside the handlers
            X, outputs, cut = self.outputs(run, X)
            if cut is not None:
                failure = f"{failure}; {cut}" if failure else cut
        if failure is None and not error_estimate:
            record(self, run, key, stats, p)
        results = self.finish(run, X, p, stats, key, params, outputs, failure)
        if error_estimate:
            estimate.attach(results, lambda **tighter: self.replaced(
                method=key if key in METHODS else None, **tighter).run(params, p=p,
                                                                        cancel=cancel))
        return results

    def jit_options(self, run, stats):
        """What ``run`` hands ``jit.external`` (its ``run.jit``: the statistics it writes
        into, the time limit and cancellation it serves), or None without JIT."""
        if not self.jit_on:
            return None
        return {"stats": stats, "required": self.jit is True, "deadline": run.deadline,
                "cancelled": lambda: run.stop_reason() is not None}

    def finish(self, run, X, p, stats, key, params, outputs, failure):
        """The Results of a run (method ``key``) that reached states X with probe signals
        ``outputs``, what the solvers said and the events in its statistics; a
        SimulationError holding them when it ended in ``failure``."""
        settings = self.settings
        if run.said:
            stats["solver_output"] = "".join(run.said)
        if run.events is not None:
            stats["events"] = run.events.log
            stats["time_events"] = run.events.time_events
        stats["jit"] = bool(run.jit) and not stats.get("jit_fallback")
        results = self.results(run, X, p, stats, key, params, outputs)
        if failure is not None:
            reached = float(results.t[-1]) if len(results.t) else self.t_start
            results.partial = {"t_reached": reached, "reason": failure}
            said = last_words(stats.get("solver_output", ""))
            # stopped when asked (a signal, cancel, the time limit), failed otherwise
            verb = "stopped at" if run.stop_reason() is not None else "failed after"
            raise SimulationError(f"{key} {verb} t = {reached:g} s (of "
                                  f"{settings['t_end']:g} s): {failure}"
                                  + (f" (the solver said: {said})" if said else ""),
                                  results=results, t_reached=reached, reason=failure,
                                  signal=run.signal)
        return results

    def outputs(self, run, X):
        """(X, outputs, why cut or None) of states X on the first rows of the grid: the
        loops' coordinates polished onto their closure, the probe signals computed, in
        chunks between which a stop is served (``driver._probe_outputs``: what was computed
        is kept); or, for a run nothing watches, ``outputs`` a callable that computes them
        when the Results first read them (``driver.deferred_outputs``)."""
        t = self.grid[:len(X)]
        parts = getattr(run, "partitions", None)
        if parts is not None and parts.events:     # re-partitioned: each part by its equations
            X, outputs = parts.finish(t, X)
            return X, outputs, None
        later = deferred_outputs(run, t, X)
        if later is not None:
            return X, later, None
        return _probe_outputs(run, t, X)

    def results(self, run, X, p, stats, key, params=None, outputs=None):
        """The Results of states X on the first rows of the grid (``outputs``: their probe
        signals, as ``outputs`` gives them with X; computed here when not given)."""
        system, settings = self.system, self.settings
        if outputs is None:
            X, outputs, _ = self.outputs(run, X)
        t = self.grid[:len(X)].copy()           # the plan's grid serves its next runs
        return Results(t, X, system.state_names + system.algebraic_names, outputs,
                       system.signals, stats=stats,
                       state_units=system.state_units + system.algebraic_units,
                       settings={"t_start": self.t_start, "t_end": settings["t_end"],
                                 "n_points": settings["n_points"], "method": key,
                                 "rtol": settings["rtol"], "atol": settings["atol"],
                                 "step": settings["step"], "max_step": settings["max_step"],
                                 "jit": stats.get("jit", False),
                                 "max_steps": settings["max_steps"],
                                 "time_limit": settings["time_limit"],
                                 "restart": self.restart, "params": dict(params or {})},
                       probe_targets=system.probe_targets, system=system)

    def differentiable(self, name):
        """The integrator of method ``name`` over the whole grid, for CasADi to differentiate
        (``kn.sensitivity``, ``kn.fit``): a run's options, tolerances (mapped as
        ``tolerance.solver_tolerances`` maps them) and step budget, on the equations in
        CasADi's SX; its parameters [p; t_start]. CVODES and IDAS control the errors of the
        forward sensitivities with the states'."""
        method = METHODS[name]
        if not isinstance(method, Casadi):
            raise ModelError(f"method {name!r}: a scipy stepper or the midpoint rule gives no "
                             f"sensitivities; use one of CasADi's: "
                             f"{', '.join(k for k, m in METHODS.items() if isinstance(m, Casadi))}"
                             f" or auto")
        system, grid = self.system, self.grid
        times = grid[1:]
        template = Run(system, system.param_vector(), np.zeros(system.n_states
                                                               + system.n_algebraic),
                       grid, self.settings, None, None, None, False)
        opts = _CasadiRun(method, template, grid[0], template.x0).options(times)
        opts["show_eval_warnings"] = False
        if method.sundials:
            opts["fsens_err_con"] = True
        taus = (times - grid[0]).tolist()
        key = ("differentiable", name, tuple(taus), tuple(sorted(opts.items())))
        return compiled(system).integrator(key, lambda: ca.integrator(
            "trajectory", method.plugin, compiled(system).dae(None, True), 0.0, taus, opts))

    def spec(self):
        """What rebuilds this plan from its model's text (a Dask worker's): its settings and
        options, its grid, and how the System was compiled."""
        loops, rate = _compiled_as(self.system)
        return {**{k: self.settings[k] for k in DEFAULTS}, **self.options,
                "grid": self.grid, "loops": loops, "baumgarte_rate": rate}

    def replaced(self, **changes):
        """The same plan with settings changed (a tighter tolerance, another method)."""
        settings = {k: self.settings[k] for k in DEFAULTS}
        settings.update(self.options)
        settings.update({k: v for k, v in changes.items()})
        grid = None if "t_end" in changes or "n_points" in changes else self.grid
        if grid is not None:
            settings.pop("t_end", None)
            settings.pop("n_points", None)
        plan = Plan(self.system, grid=grid, **settings)
        plan.lifted, plan.aliases = self.lifted, self.aliases
        return plan


def simulate(model: Model | System, t_end: float | None = None, n_points: int | None = None,
             method: str | None = None, rtol: float | None = None, atol: float | None = None,
             params: Mapping[str, float | str] | None = None, t_start: float = 0.0,
             step: float | None = None, max_step: float | None = None,
             jit: bool | None = None, max_steps: int | None = None,
             time_limit: float | None = None,
             progress: bool | Callable[[float], object] | None = None,
             cancel: Callable[[], object] | None = None, restart: bool = False,
             repartition: bool = True, error_estimate: bool = False) -> Results:
    """Integrate ``model`` (a Model or a compiled System) and record its probes.

    Settings not given come from the model's ``simulation`` block, then from DEFAULTS. The
    run goes through the model's integration plan (``kinetwork.solver.plan``), as every
    member of a sweep, sensitivity and fit does.

    Parameters
    ----------
    model : Model or System
        A Model is compiled (once: an unchanged model gives back its System).
    t_end : float
        End time [s]; the output grid has ``n_points`` equally spaced points from ``t_start``.
    method : str
        One of METHODS (``kinetwork methods`` lists them). ``auto`` (default): CVODES Adams,
        or CVODES BDF when the stiffness test finds the problem stiff at the start, or when
        Adams fails on it; IDAS for models with algebraic variables (loops compiled with
        ``loops="partition"``, massless junctions).
    rtol, atol : float
        Tolerances of the variable-step methods: rtol bounds the global error (see
        ``kinetwork.solver.tolerance``).
    step : float, optional
        Largest step [s] of the fixed-step methods (``rk``, ``collocation``, ``midpoint``);
        default: the output spacing.
    max_step : float, optional
        Largest step [s] of every method: the variable-step ones never step further (an
        input that no relation announces, a smooth pulse, cannot be stepped over), and a
        fixed step is at most this long.
    params : dict, optional
        Parameter values for this run, numbers (SI) or numbers with a unit
        (``{"c": "2 N*m/rad"}``, see ``Model.parameter_values``): model parameters (no
        recompilation), or component parameters by path (``{"spring.c": 2.0}``,
        ``{"cyl3.piston.mass": "2 kg"}``), lifted to model parameters of a twin of the model
        compiled once and kept (``stats["lifted"]`` says so).
    jit : bool, optional
        Compile the equations to C (cached on disk, see ``kinetwork.solver.jit``). True
        insists (a ModelError when it cannot be done); None (default) compiles when a C
        compiler is found and ``KINETWORK_JIT`` is not 0, and falls back to CasADi's virtual
        machine, with a warning, when compilation fails.
    max_steps : int, optional
        Step budget of the run, whatever its number of output points (default
        ``tolerance.step_budget``: 10^7 steps per 10 s of the run, more at the tighter
        tolerances the solvers are given, and at most its length's share for a stretch of
        it): a run that takes more stops with a SimulationError.
    time_limit : float, optional
        Wall-clock limit [s] of the run, compilation included.
    progress : bool or callable, optional
        True: a tqdm progress bar on stderr, drawn once the run has lasted a second (a quick
        run shows none). A callable: called with the simulated time reached, now and then.
    cancel : callable, optional
        Called now and then; a true answer stops the run (a SimulationError holding what was
        computed). SIGINT and SIGTERM stop a run in the main thread the same way.
    restart : bool, optional
        After a solver failure, start the method afresh from the last state reached (at most
        MAX_RESTARTS times), if that state is sound: finite, the loops closed, and the
        restarted run continuing it without a jump. Each restart is in ``stats["restarts"]``.
        Off by default: a failure is a SimulationError. Not with events (friction, stops,
        relations).
    repartition : bool, optional
        With kinematic loops: where the partition of the speeds into independent and
        dependent ones nears a singular configuration (a dead point of the independent
        coordinates, or a change point of the mechanism), choose another partition there and
        go on (``kinetwork.solver.loopwatch``); ``stats["repartitions"]`` counts them,
        ``stats["repartition_times"]`` says when. False: stop there with a SimulationError.
    error_estimate : bool, optional
        Run again at tighter tolerances on the same compiled System and put an estimate of
        each probe signal's and state's global error in ``stats["error_estimate"]``, with the
        time after which it means nothing on chaotic motion (``estimate.py``).

    Returns
    -------
    Results
        ``results.settings["method"]`` is the method that ran; ``results.stats`` its counts.

    Raises
    ------
    ModelError
        Bad settings or parameters.
    SimulationError
        The integration failed or was stopped; ``err.results`` holds the results up to
        ``err.t_reached``.
    """
    entered = time.perf_counter()      # the time limit counts building the equations too
    plan = _plan(model, list(params or ()), t_end=t_end, n_points=n_points, method=method,
                 rtol=rtol, atol=atol, step=step, max_step=max_step, t_start=t_start, jit=jit,
                 max_steps=max_steps, time_limit=time_limit, restart=restart,
                 repartition=repartition)
    if progress is True:
        name = getattr(model, "name", None) or "simulate"
        with progress_bar(plan.grid[0], plan.grid[-1], desc=name) as report:
            return plan.run(params, cancel=cancel, progress=report,
                            error_estimate=error_estimate, started=entered)
    return plan.run(params, cancel=cancel, progress=progress or None,
                    error_estimate=error_estimate, started=entered)


def _plan(model, names, **settings):
    """The Plan of ``simulate``'s arguments: for a System (or a Model without parameter paths:
    its System, kept by the Model while its content is unchanged), made once per names,
    settings and ``simulation`` block (the defaults; same values and types), kept with its
    checked settings (``Compiled.checked``): a plan is not changed by its runs (making one
    costs 0.06 ms; a Model's, 0.3 ms). A lifted twin's is made every time."""
    from ..graph.model import Model
    if isinstance(model, Model) and not names:
        model = model.compile()
    if not isinstance(model, System):
        return Plan(model, names=names, **settings)
    try:
        values, defaults = tuple(settings.values()), tuple(model.model.simulation.items())
        key = ("plan", tuple(names), tuple(settings), values, tuple(map(type, values)),
               defaults, tuple(type(v) for _, v in defaults))
        hash(key)
    except TypeError:               # an unhashable value: refused by the Plan
        return Plan(model, names=names, **settings)
    def made():
        plan = Plan(model, names=names, **settings)
        # kept without its System (whose table keeps it: a cycle that would keep the System
        # alive for ever); a plan of a lifted twin is not kept
        return None if plan.system is not model else \
            {k: v for k, v in plan.__dict__.items() if k != "system"}
    state = compiled(model).checked(key, made)
    if state is None:
        return Plan(model, names=names, **settings)
    plan = Plan.__new__(Plan)
    plan.__dict__.update(state)
    plan.system = model
    return plan


# -- resolving parameter names ----------------------------------------------------------------
def lifted_model(model, names):
    """(the model to work on, {path: its model parameter}) for work given parameters
    ``names``: ``model`` itself and {} when each is a model parameter; else the twin of the
    model with the component parameters named by path lifted (``graph/lift.py``), a Model
    that compiles once. For analyses that compile the model their own way (``kn.linearize``,
    ``kn.equilibrium``)."""
    from ..graph.model import Model
    if isinstance(model, System):
        source = source_of(model)
    elif isinstance(model, Model):
        source = model
    else:
        return model, {}
    paths = [n for n in names if is_path(source, n)]
    if not paths:
        return model, {}
    lifted = lift(source, paths)
    _say(lifted)
    return lifted.model, dict(lifted.names)


def _say(lifted):
    """Log, once per twin, that component parameters were lifted."""
    if not lifted.said:
        log.info("%s", lifted.note)
        lifted.said = True


def _resolve(model, names):
    """(System, Lifted or None, {path: its name in the System}) for runs given ``names``."""
    from ..graph.model import Model
    if isinstance(model, System):
        system, source = model, source_of(model)
    elif isinstance(model, Model):
        system, source = None, model
    else:
        raise ModelError(f"expected a kn.Model or a kn.System, got {type(model).__name__}")
    if isinstance(names, str):
        names = [names]
    paths = [n for n in names if is_path(source, n)]
    if not paths:
        return (system if system is not None else model.compile()), None, {}
    lifted = lift(source, paths)
    loops, rate = _compiled_as(system) if system is not None else ("projected", None)
    twin = lifted.model.compile(loops, rate)
    _say(lifted)
    return twin, lifted, dict(lifted.names)


def source_of(system):
    """The model a System was compiled from, as it was written (subsystems not expanded):
    what lifts a subsystem's parameter, and what a job sends to a Dask worker."""
    flat = system.model
    return getattr(flat, "_source", None) or flat


def _compiled_as(system):
    """(loops, baumgarte_rate) that ``system`` was compiled with."""
    for key, value in getattr(system.model, "_compiled", {}).items():
        if value is system:
            return key[1], key[2]
    loops = system.formulation
    return (loops if loops in ("partition", "projected", "baumgarte") else "projected"), None


def _checked(system, settings, t_start, max_steps, time_limit):
    """(the method's table key, the grid of equal intervals, the settings as a key or None)
    of ``settings`` on ``system``, checked (``driver._check``, the method's own ``check``) once
    per System and settings: every later run with the same values, of the same types, reuses
    the answer (a check and a grid cost 0.1 ms, 4 % of a small model's run). The grid is the
    caller's to copy."""
    def check():
        key = _check(system, settings, t_start, max_steps, time_limit)
        METHODS[key].check(system)
        grid = np.linspace(t_start, settings["t_end"], int(settings["n_points"]))
        grid.flags.writeable = False
        return key, grid
    try:
        given = tuple((k, type(v), v) for k, v in sorted(settings.items())) + tuple(
            (type(v), v) for v in (t_start, max_steps, time_limit))
        hash(given)
    except TypeError:               # an unhashable value: refused by the check
        return (*check(), None)
    return (*compiled(system).checked(given, check), given)


def _checked_grid(grid, t_start):
    out = np.asarray(grid, dtype=float).ravel()
    if len(out) < 2 or not np.all(np.isfinite(out)) or np.any(np.diff(out) <= 0) or \
            out[0] != t_start:
        raise ModelError(f"t: the output times must start at t_start = {t_start:g} and "
                         f"increase (at least two)")
    return out

