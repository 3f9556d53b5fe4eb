"""Sweeps and Monte Carlo: many runs of one model's integration plan, in this process or on
Dask.

``sweep`` runs a grid of parameter values, ``sample`` draws them from distributions
(``distributions.py``). Both build the model's plan once (``kinetwork.solver.plan``: one
compiled System, its parameters CasADi symbols, so a member costs no compilation; a component
parameter named by path is lifted to a model parameter once) and run each member as
``kn.simulate`` runs it: the same method (``auto``'s choice made for each member), the same
tolerances, the same failure detection (``solver/batch.py``: each member integrated with its
own error control, members mapped over CasADi's threads; ``sweep_dask.py``: blocks of
members as Dask tasks). The answer is an xarray Dataset (``sweep_results.py``).
"""

import itertools
import os
import signal
import threading
import time

import numpy as np

from ..errors import ModelError
from ..graph.settings import MAX_OUTPUT_BYTES
from ..solver.batch import MAX_BATCH, Members, run_members
from ..solver.plan import Plan
from . import sweep_dask
from .distributions import Distribution, draw, normal, real, uniform
from .sweep_job import Job, prepare
from .sweep_results import dataset, param_unit, summary, to_netcdf

#: members prepared (parameters checked, start found) and run at a time in this process
WINDOW = 4 * MAX_BATCH

__all__ = ["Distribution", "normal", "sample", "summary", "sweep", "to_netcdf", "uniform"]


def sweep(model, grid, *, params=None, outputs=None, workers=None, batch=None,
          scheduler=None, progress=True, **settings):
    """Simulate ``model`` for every combination of the values in ``grid``.

    Parameters
    ----------
    model : Model or System
    grid : dict
        Parameter -> the values it takes (numbers in SI, or numbers with a unit: "2 kg").
        A parameter is a model parameter or a component parameter by its path
        (``"spring.c"``, ``"cyl3.piston.mass"``, ``"body.r_cm[0]"``, a subsystem's
        ``"cyl1.phi0"``: lifted to a model parameter once, see ``kn.simulate``). The members
        are the Cartesian product, in the order of the dict.
    params : dict, optional
        Values of other parameters, the same for every member.
    outputs : list of str, optional
        The probe signals and states to keep (default: all): a sweep of many members keeps
        only what it is asked for.
    workers : int, optional
        Threads that share the members in this process (default: the cores this process may
        use). Not used on Dask, whose workers are the cluster's.
    batch : int, optional
        Members per mapped call here (default: as many as a call of a fraction of a second
        holds), per task on Dask. Each member is integrated with its own error control: the
        batch changes how members are grouped, not their answers (beyond the tolerance).
    scheduler : None, "local", address or distributed.Client
        None: this process, in threads. "local": a Dask LocalCluster on this machine, made
        for the sweep and closed after it. "tcp://host:8786": the Dask scheduler there. A
        ``distributed.Client``: that client's cluster.
    progress : bool or callable
        A tqdm bar on stderr (True), none (False), or a callable ``progress(done, total)``
        called as each member finishes.
    **settings
        As for ``kn.simulate``: ``t_end``, ``n_points``, ``method``, ``rtol``, ``atol``,
        ``step``, ``max_step``, ``t_start``, ``jit``, ``max_steps``, ``time_limit``, ``restart``
        (settings not given come from the model's ``simulation``).

    Returns
    -------
    xarray.Dataset
        Dimensions: one per swept parameter (its values as coordinate), ``t``, and the
        components of vector signals. Variables: each kept probe signal and state,
        ``status``, ``reason``, ``t_reached`` and ``method`` per member. A member that fails
        is kept as far as it got (NaN after) with its reason; an interrupted sweep (Ctrl-C)
        returns what finished, the rest marked "interrupted" and ``attrs["interrupted"]``
        true.
    """
    if not isinstance(grid, dict) or not grid:
        raise ModelError("sweep: the grid must be a non-empty dict of parameter name -> "
                         "values")
    names = list(grid)
    plan = _plan(model, names, params, settings)
    axes = []
    for name in names:
        values = grid[name]
        if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or \
                not len(values):
            raise ModelError(f"sweep: {name!r}: give a non-empty sequence of values, got "
                             f"{values!r:.60}")
        axes.append([_si(plan, name, v, f"sweep: {name}[{i}]") for i, v in enumerate(values)])
    values = np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, len(names))
    layout = {"dims": names, "coords": {n: np.array(a) for n, a in zip(names, axes)},
              "shape": tuple(len(a) for a in axes),
              "units": {n: param_unit(plan, n) for n in names}}
    return _run(plan, names, values, layout, params, outputs, workers, batch, scheduler,
                progress)


def sample(model, distributions, n, *, seed=None, params=None, outputs=None, workers=None,
           batch=None, scheduler=None, progress=True, **settings):
    """Monte Carlo: simulate ``model`` for ``n`` members whose parameters are drawn from
    ``distributions``.

    ``distributions``: parameter (a model parameter or a component parameter by path, as for
    ``sweep``) -> a distribution (``kn.normal``, ``kn.uniform``, a frozen ``scipy.stats``
    distribution) or a sequence of ``n`` values. ``seed`` makes the draw repeatable (the
    parameters are drawn in the order of the dict). Every other argument and the result are
    as for ``sweep``, with one dimension ``member`` and the drawn values as coordinates along
    it.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ModelError(f"sample: n must be a positive integer, got {n!r:.40}")
    if not isinstance(distributions, dict) or not distributions:
        raise ModelError("sample: give a non-empty dict of parameter name -> distribution")
    names = list(distributions)
    plan = _plan(model, names, params, settings)
    values = draw(distributions, int(n), seed,
                  lambda name, v, where: _si(plan, name, v, where))
    layout = {"dims": ["member"], "coords": {"member": np.arange(n)}, "shape": (int(n),),
              "member_coords": {name: values[:, k] for k, name in enumerate(names)},
              "distributions": {name: repr(distributions[name]) for name in names},
              "units": {name: param_unit(plan, name) for name in names}}
    return _run(plan, names, values, layout, params, outputs, workers, batch, scheduler,
                progress)


def _plan(model, names, params, settings):
    """The plan of a sweep: ``kn.simulate``'s settings, the varied and common parameters
    (paths lifted at once); optional dependencies checked before any member runs."""
    if params is not None and not isinstance(params, dict):
        raise ModelError(f"params: must be a dict, got {type(params).__name__}")
    doubled = [k for k in names if k in (params or {})]
    if doubled:
        raise ModelError(f"params: {doubled[0]!r} is varied already")
    try:
        import xarray  # noqa: F401 -- the answer's type: missing, nothing runs
    except ImportError:
        raise ModelError("sweep: xarray is not installed, and the answer is an xarray "
                         "Dataset (pip install 'kinetwork[sweep]')") from None
    return Plan(model, names=list(names) + list(params or {}), **settings)


def _si(plan, name, value, where):
    """A member's value of ``name`` in SI: a number, or a number with a unit checked against
    the parameter's uses."""
    if isinstance(value, str):
        internal = plan.param_name(name)
        try:
            converted = plan.si(name, value)
            if isinstance(converted, str):
                converted = plan.system.model.parameter_values({internal: value})[internal]
        except ModelError as exc:
            raise ModelError([f"{where}: {p}" for p in exc.problems]) from None
        return converted
    return real(value, where)


def _run(plan, names, values, layout, params, outputs, workers, batch, scheduler, progress):
    """Run every member and give the Dataset."""
    for what, v in (("workers", workers), ("batch", batch)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, np.integer))
                              or v < 1):
            raise ModelError(f"{what}: must be a positive integer, got {v!r:.40}")
    if scheduler is not None:
        sweep_dask.check_scheduler(scheduler)
    if workers is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else \
            (os.cpu_count() or 1)
    job = Job(plan, names, params, outputs)
    n = len(values)
    _check_size(n, len(plan.grid), job.keep)
    out = Members(plan, n, job.keep)
    report = _progress(progress, n)
    started = time.perf_counter()
    interrupted = False
    with _stop_flag() as stop:
        try:
            if scheduler is None:
                interrupted = _local(job, values, out, workers, batch, stop, report)
            else:
                interrupted = sweep_dask.run_dask(job, values, out, scheduler, batch, stop,
                                                  report)
        except KeyboardInterrupt:
            interrupted = True
        finally:
            report(None)
    for i, status in enumerate(out.status):
        if status == "pending":
            out.status[i], out.reason[i] = "interrupted", "the sweep was interrupted"
    return dataset(plan, layout, out, {
        "interrupted": int(interrupted), "seconds": time.perf_counter() - started,
        "scheduler": _scheduler_name(scheduler),
        "workers": workers if scheduler is None else 0, "batch": batch or 0})


def _check_size(members, points, keep):
    """Refuse, before any member runs, a sweep whose results would not fit the memory a run
    may keep (``graph.settings.MAX_OUTPUT_BYTES``)."""
    need = 8 * members * points * (keep.n_states + keep.n_columns)
    if need > MAX_OUTPUT_BYTES:
        raise ModelError(f"sweep: {members} members of {points} points of "
                         f"{keep.n_states + keep.n_columns} values would need "
                         f"{need / 2**30:.1f} GiB, more than the "
                         f"{MAX_OUTPUT_BYTES / 2**30:.0f} GiB a sweep may keep: keep fewer "
                         f"signals (outputs=[...]), fewer points (n_points) or fewer members")


def _local(job, values, out, workers, batch, stop, report):
    """The members in this process, ``workers`` threads sharing each mapped call, WINDOW at
    a time (each member's parameters and start are found just before it runs: a large sweep
    starts at once and stops at once); True when stopped."""
    names, base = job.names, job.base
    for start in range(0, len(values), WINDOW):
        if stop():
            return True
        index = range(start, min(len(values), start + WINDOW))
        members = prepare(job, values[index], out, index)
        for i in index:
            if out.status[i] == "failed":          # refused: said at once
                report(i)
        if run_members(job.plan, members, out, workers=workers, batch=batch, stop=stop,
                       done=report, params=lambda i: {**base, **dict(zip(
                           names, map(float, values[i])))}):
            return True
    return False


class _stop_flag:
    """A callable true once Ctrl-C (SIGINT) came, while a sweep runs in the main thread: the
    members running finish their current call, the rest are left."""

    def __enter__(self):
        self.flag = threading.Event()
        self.saved = None
        if threading.current_thread() is threading.main_thread():
            try:
                self.saved = signal.signal(signal.SIGINT, lambda *_: self.flag.set())
            except (ValueError, OSError):       # not settable here (an embedded interpreter)
                self.saved = None
        return self.flag.is_set

    def __exit__(self, *exc):
        if self.saved is not None:
            signal.signal(signal.SIGINT, self.saved)
        return False


def _scheduler_name(scheduler):
    if scheduler is None:
        return "threads"
    if isinstance(scheduler, str):
        return "dask LocalCluster" if scheduler == "local" else f"dask {scheduler}"
    return f"dask {getattr(getattr(scheduler, 'scheduler', None), 'address', scheduler)}"


def _progress(progress, total):
    """A callable taking the member just finished (None: the end)."""
    if callable(progress):
        count = [0]

        def call(i):
            if i is not None:
                count[0] += 1
                progress(count[0], total)
        return call
    if not progress:
        return lambda i: None
    from tqdm import tqdm
    bar = tqdm(total=total, unit="run", desc="sweep", leave=False)

    def update(i):
        if i is None:
            bar.close()
        else:
            bar.update(1)
    return update
