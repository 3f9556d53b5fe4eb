"""A quiet run again: what the first run of a System with the same settings and parameter
values worked out, kept beside the System, so that a repeated run only sets its inputs, calls
the integrator and wraps the arrays.

A run of a small model spends most of its own time (beside the integration) working out
again what the last run worked out: the settings merged and checked, the start solved and
checked, the stiffness test's answer looked up, the method's options, tolerances, step budget
and integrator found, the chunking decided. That is 0.8-1 ms of Python a run, a third of the
seed's run at rtol 1e-4 (``bench/results/study_overhead.md``). A ``Recipe`` holds all of it for
one (System, settings, parameter values), taken from a run that made exactly what a replay
makes: one call of one CVODES integrator over the whole grid, nothing watched (no time
limit, ``cancel``, progress, events, loops or assemblies), auto's first choice, no fallback
or restart.

A replay is that run and nothing else: the same integrator with the same inputs gives the
same numbers, and the Results are built by the same code (``Plan.finish``). What a replay does
not handle it hands back, and the run is made in full from the start: a solver failure (auto
then tries another method; the full run fails or goes on exactly as a first run would), a
stalled Adams, a step budget spent. A signal (SIGINT, SIGTERM) stops a replay as it stops any
run: a SimulationError holding the outputs reached.
"""

from __future__ import annotations

import numpy as np

from .chunks import MAX_CHUNK, _Rows
from .compiled import compiled
from .driver import _running, _spent
from .methods import METHODS, Failure, _CasadiRun

#: statistics of a run that count its work (the replay's own), not what its recipe decided
COUNTS = ("steps", "rhs_evaluations", "jacobian_evaluations", "factorisations")
#: statistics that say a run went some other way than one quiet call: not replayed
UNREPEATED = ("gave_up", "adams_failure", "switched", "restarts", "lifted", "jit_fallback",
              "solver_output", "events", "repartitions")


class Recipe:
    """What a replay needs: the method that ran, its integrator and that integrator's options,
    auto's look budget it ran under, the run's step budget, the start, and the statistics
    that the run's decisions wrote (the stiffness test's answer, jit)."""

    __slots__ = ("name", "method", "integ", "opts", "look_steps", "budget", "x0", "decided")

    def __init__(self, name, integ, opts, look_steps, budget, x0, decided):
        self.name, self.method, self.integ, self.opts = name, METHODS[name], integ, opts
        self.look_steps, self.budget, self.x0, self.decided = look_steps, budget, x0, decided


def key_of(plan, p):
    """The key a recipe of ``plan`` at parameters ``p`` is kept by, or None: a plan whose
    settings could not be keyed (``plan.given``) has none."""
    if plan.given is None:
        return None
    return plan.given, plan.jit, np.asarray(p, dtype=float).tobytes()


def record(plan, run, name, stats, p):
    """After a run (``run``, method ``name``) that succeeded with statistics ``stats``: keep
    its recipe when a replay would make the very same run (see the module's docstring)."""
    system, method = plan.system, METHODS.get(name)
    key = key_of(plan, p)
    if key is None or method is None or not getattr(method, "sundials", False) or method.dae \
            or not run.quiet or run.calls != 1 or run.events is not None \
            or run.signal is not None or system.n_algebraic or system.f_dependent is not None \
            or system.f_assembly_checks is not None or plan.lifted is not None \
            or len(plan.grid) - 1 > MAX_CHUNK or any(k in stats for k in UNREPEATED):
        return
    integ, opts, look_steps = run.called
    decided = {k: v for k, v in stats.items() if k not in COUNTS and not k.startswith("jit")}
    compiled(system).recipe(key, lambda: Recipe(
        name, integ, opts, look_steps, run.budget(method), np.array(run.x0, dtype=float),
        decided))


def replay(plan, p, params, started):
    """The Results of ``plan`` at parameters ``p`` (``params``: what they record) by its
    recipe, or None when it has none or the replay hands the run back (see the module's
    docstring). Raises SimulationError when a signal stopped it."""
    key = key_of(plan, p)
    recipe = None if key is None else compiled(plan.system).recipe(key)
    if recipe is None:
        return None
    grid, n, method = plan.grid, len(plan.grid), recipe.method
    run = plan.new_run(p, recipe.x0.copy(), started=started)
    stats = {k: (dict(v) if isinstance(v, dict) else v) for k, v in recipe.decided.items()}
    with _running(run):
        run.jit = plan.jit_options(run, stats)
        run.quiet, run.look_steps = True, recipe.look_steps
        stepper = _CasadiRun(method, run, grid[0], run.x0)
        X = _Rows(run.x0, n)
        try:
            X.extend(stepper.call(recipe.integ, recipe.opts, grid[1:], X.slot(n - 1)))
            steps = stepper.stats["steps"]
            failure = _spent(run, method, {}, stepper.stats, grid[-1]) \
                if steps > recipe.budget else None
        except Failure as exc:
            if exc.states is not None:
                X.extend(exc.states)
            failure = exc.reason
        if failure is not None and run.stop_reason() is None:
            return None                     # the full run: it fails, or goes on, in full
        stats.update(stepper.stats)
        X, outputs, cut = plan.outputs(run, X.array())
        if cut is not None:
            failure = f"{failure}; {cut}" if failure else cut
    return plan.finish(run, X, p, stats, recipe.name, params, outputs, failure)
