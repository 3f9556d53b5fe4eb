"""A quiet run again: what the first run of a System with the same settings and parameter
values worked out, kept beside the System, so that a repeated run only calls the integrator
and wraps the arrays.

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
same numbers, and the Results are built by the same code (``Plan.finish``). The recipe keeps
the integrator's call ready (a CasADi ``FunctionBuffer`` bound to the start and the
parameters, which are the recipe's own), so a replay only points it at a fresh array of
states and calls it. Its counts (steps, evaluations) are read from the solver once, by the
first replay, and kept with the last state it reached: a later replay that ends at that
state to the bit did the same work (the same compiled code with the same inputs), and
reading the counts from CVODES again would cost 40-70 us, more than all of a replay's own
Python; one that ends elsewhere (another build of the code swapped in, ``jit_tiers.py``)
reads them again and keeps them for the next.

What a replay does not handle it hands back, and the run is made in full from the start: a
solver failure (auto then tries another method; the full run fails or goes on exactly as a
first run would), a step budget spent. What the solver printed is reported as in any run.
A signal (SIGINT, SIGTERM) stops a replay as it stops any run: a SimulationError holding the
outputs reached.
"""

from __future__ import annotations

import io
import sys

import numpy as np

from .capture import SOLVER_LOCK
from .casadi_clock import cheap
from .chunks import MAX_CHUNK
from .compiled import compiled
from .driver import _running, budget_spent
from .methods import (INTEGRATOR_IN, INTEGRATOR_OUT, METHODS, Interrupted, _finite_rows,
                      shift_times)
from .results import Results, later_outputs

#: statistics of a run that count its work (the replay's own), not what its recipe decided
COUNTS = ("steps", "rhs_evaluations", "jacobian_evaluations", "factorisations")
#: statistics that say a run went some other way than one quiet call: not replayed
UNREPEATED = ("gave_up", "adams_failure", "switched", "restarts", "lifted", "jit_fallback",
              "solver_output", "events", "repartitions")


class Recipe:
    """What a replay needs: the method that ran, its integrator, auto's look budget it ran
    under, the run's step budget, the start, the statistics that the run's decisions wrote
    (the stiffness test's answer, jit), and the integrator's call as the last run made it
    (``call``: its buffer, bound to the start and the parameters; the counts of its last
    call and the last state it reached, as bytes), what its Results share with every replay's
    (``Results.kept``), and the function and width of its probe signals when they are
    computed on first read (``results.later_outputs``)."""

    __slots__ = ("name", "method", "integ", "look_steps", "budget", "x0", "decided",
                 "dicts", "call", "counts", "last", "results", "later")

    def __init__(self, name, integ, look_steps, budget, x0, decided):
        self.name, self.method, self.integ = name, METHODS[name], integ
        self.look_steps, self.budget, self.x0, self.decided = look_steps, budget, x0, decided
        #: the decided statistics that are dicts: each run's Results get copies
        self.dicts = tuple(k for k, v in decided.items() if isinstance(v, dict))
        self.call = self.counts = self.last = self.results = self.later = None

    def stats(self, counts):
        """The statistics of a replay that counted ``counts``, the Results' own."""
        stats = dict(self.decided)
        for k in self.dicts:
            stats[k] = dict(stats[k])
        stats.update(counts)
        return stats


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
    integ, _, look_steps = run.called
    decided = {k: v for k, v in stats.items() if k not in COUNTS and not k.startswith("jit")}
    compiled(system).recipe(key, lambda: Recipe(
        name, integ, look_steps, run.budget(method), np.array(run.x0, dtype=float), decided))


def replay(plan, p, params, started):
    """The Results of ``plan`` at parameters ``p`` (``params``: what they record) by its
    recipe, or None when it has none or the replay hands the run back (see the module's
    docstring). Raises SimulationError when a signal stopped it."""
    key = key_of(plan, p)
    recipe = None if key is None else compiled(plan.system).recipe(key)
    if recipe is None:
        return None
    run = plan.new_run(p, recipe.x0.copy(), started=started)
    with _running(run):
        X, counts, failure = _call(recipe, run, plan.grid)
        if failure is not None and run.stop_reason() is None:
            return None                     # the full run: it fails, or goes on, in full
        stats = recipe.stats(counts)
        run.jit = plan.jit_options(run, stats)
        if failure is None and recipe.later is not None:
            # computed when first read, as the first replay's were (``deferred_outputs``)
            outputs = later_outputs(plan.system, *recipe.later, plan.grid, X, p)
        else:
            X, outputs, cut = plan.outputs(run, X)
            if cut is not None:
                failure = f"{failure}; {cut}" if failure else cut
            if failure is None and callable(outputs):
                recipe.later = (compiled(plan.system).outputs(run.jit),
                                plan.system.f_out.size1_out(0))
    if failure is None and recipe.results is not None and not run.said:
        # what Plan.finish makes of a run that said nothing and met no event, from the
        # first replay's Results
        stats["jit"] = bool(run.jit) and not stats.get("jit_fallback")
        return Results.renewed(recipe.results, plan.grid.copy(), X, outputs, stats, params,
                               plan.system)
    results = plan.finish(run, X, p, stats, recipe.name, params, outputs, failure)
    if failure is None and not run.said:
        recipe.results = results.kept()
    return results


def _call(recipe, run, grid):
    """(states, counts, failure or None) of the recipe's integrator called over ``grid``
    from its start: the rows reached (all of them unless it failed), what it counted, why
    it stopped. The call's words are caught (Python's streams: CasADi's integrators print
    only there, ``capture.solver_output``) and join ``run.said``."""
    x0 = recipe.x0
    X = np.empty((len(grid), len(x0)))
    X[0] = x0
    X[1:] = np.nan                          # the rows a failed call did not reach
    with SOLVER_LOCK:                       # the buffer is the recipe's: one call at a time
        if recipe.call is None:
            recipe.call = _bound(recipe.integ, x0, np.append(run.p_solver, grid[0]))
        buffer, trigger = recipe.call[:2]
        buffer.set_res(INTEGRATOR_OUT["xf"], memoryview(X[1:]))
        streams, said = (sys.stdout, sys.stderr), io.StringIO()
        sys.stdout = sys.stderr = said
        run.abortable = True
        try:
            if run.signal is not None:      # it came before the call
                raise Interrupted
            with cheap():                   # CasADi's clock (casadi_clock.py)
                trigger()
            failure = None
        except (RuntimeError, Interrupted):
            failure = "the solver failed"
        finally:
            run.abortable = False
            sys.stdout, sys.stderr = streams
        reached = _finite_rows(X)
        if failure is None and reached == len(X) and X[-1].tobytes() == recipe.last:
            counts = recipe.counts          # the same work to the bit (module's docstring)
        else:
            counts = _counts(buffer)
            if failure is None and reached == len(X):
                recipe.counts, recipe.last = counts, X[-1].tobytes()
    if failure is not None:
        stop = run.stop_reason()            # stopped: what it reached is kept
        return (X[:reached], counts, stop) if stop is not None else (X, counts, failure)
    if reached < len(X):
        failure = "the state became non-finite (Inf or NaN)"
    if said.getvalue().strip():             # reported as any run's words (Plan.finish)
        run.said.append(shift_times(said.getvalue(), float(grid[0])))
    if failure is None and counts["steps"] > recipe.budget:
        failure = budget_spent(recipe.budget, float(grid[-1]), counts["steps"])
    return X, counts, failure


def _bound(integ, x0, p):
    """(buffer, trigger, inputs) of a call of ``integ`` from ``x0`` at parameters ``p``:
    the buffer points at the inputs, which must live as long (they are kept with it)."""
    buffer, trigger = integ.buffer()
    inputs = (np.ascontiguousarray(x0, dtype=float), np.ascontiguousarray(p, dtype=float))
    buffer.set_arg(INTEGRATOR_IN["x0"], memoryview(inputs[0]))
    buffer.set_arg(INTEGRATOR_IN["p"], memoryview(inputs[1]))
    return buffer, trigger, inputs


def _counts(buffer):
    """The steps and evaluations of the call just made by ``buffer`` (none when it failed at
    once)."""
    try:
        st = buffer.stats()
    except RuntimeError:
        return dict.fromkeys(COUNTS, 0)
    return {"steps": int(st["nsteps"]), "rhs_evaluations": int(st["nfevals"]),
            "jacobian_evaluations": int(st["n_call_jacF"]),
            "factorisations": int(st.get("nlinsetups", 0))}
