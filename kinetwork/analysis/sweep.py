"""Sweeps and Monte Carlo: many runs of one compiled System, locally in parallel or on Dask.

``sweep`` runs a grid of parameter values, ``sample`` draws them from distributions; both
reuse the one System of the model (parameters are CasADi symbols there: a member costs no
compilation) and give an xarray Dataset: one variable per probe signal and state, over the
members (one dimension per swept parameter, or ``member``) and ``time``, units in attrs,
with each member's ``status`` ("ok", "failed", "interrupted") and ``reason``.

How members run (the per-run cost of ``simulate`` is mostly Python and CVODES' bookkeeping,
not the model):

- a *batch* of B members is one ODE of B x n states, whose right-hand side is the model's
  mapped over the members (one compiled C function under JIT): one CasADi integrator steps
  them all together, with the tolerances divided by sqrt(B), so that every member's own
  error test is at least as strict as in its own run (CVODES' norm is the root mean square
  over all B x n components);
- ``workers`` batches at a time run in CasADi's threads (``Function.map(..., "thread")``);
- on Dask, each batch is one task: the model travels as its JSON text, a worker compiles it
  once and keeps it.

A batch whose integration fails runs again member by member through ``simulate``: the
member that fails is marked failed with ``simulate``'s reason, the others are kept. Models
that are DAEs (loops in the ``partition`` formulation) and the methods that are not CasADi's
(scipy's, the midpoint rule, IDAS) run member by member the same way.
"""

import collections
import itertools
import math
import os
import tempfile
import threading
import time

import casadi as ca
import numpy as np

from ..equations.system import OVERFLOW, System, overflow_message
from ..errors import ModelError, SimulationError
from ..expr import parse
from ..graph.model import evaluate
from ..solver import jit as _jit
from ..solver.capture import SOLVER_LOCK, solver_output
from ..solver.compiled import compiled
from ..solver.driver import DEFAULTS, simulate
from ..solver.driver import _check as check_settings
from ..solver.methods import (
    METHODS,
    STIFF_HORIZON_STEPS,
    STIFF_RATIO,
    solver_reason,
)
from ..graph.settings import MAX_OUTPUT_BYTES
from ..outputs import check, model_files, write
from ..util import suggest

#: members per batch at most (the tolerances of a batch are divided by sqrt(B))
MAX_BATCH = 64
#: members of one sweep or sample at most, and worker threads: every input does bounded
#: work (their results must also fit MAX_OUTPUT_BYTES together)
MAX_MEMBERS, MAX_WORKERS = 1_000_000, 1024
#: members the command's summary prints a line for
SUMMARY_MEMBERS = 100
#: the methods a batch runs in one CasADi integrator; any other runs member by member
BATCHED = ("auto", "cvodes", "cvodes-adams", "rk", "collocation")


# -- distributions ----------------------------------------------------------------------------
class Distribution:
    """A distribution of one parameter for ``sample``: ``kn.normal(1, 0.05)``,
    ``kn.uniform(0.5, 2)``. Any object with scipy's ``rvs(size=, random_state=)`` (a frozen
    ``scipy.stats`` distribution) is accepted by ``sample`` as well."""

    def __init__(self, text, draw):
        self.text, self._draw = text, draw

    def rvs(self, size, random_state):
        return self._draw(np.random.default_rng(random_state), size)

    def __repr__(self):
        return self.text


def normal(mean, std):
    """Normal distribution of mean ``mean`` and standard deviation ``std`` (>= 0)."""
    mean, std = _real(mean, "normal: mean"), _real(std, "normal: std")
    if std < 0:
        raise ModelError(f"normal: std must be >= 0, got {std:g}")
    return Distribution(f"normal({mean:g}, {std:g})", lambda rng, n: rng.normal(mean, std, n))


def uniform(low, high):
    """Uniform distribution on [low, high)."""
    low, high = _real(low, "uniform: low"), _real(high, "uniform: high")
    if high < low:
        raise ModelError(f"uniform: high must be >= low, got low = {low:g}, high = {high:g}")
    return Distribution(f"uniform({low:g}, {high:g})",
                        lambda rng, n: rng.uniform(low, high, n))


def _real(value, where):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) or \
            not math.isfinite(value):
        raise ModelError(f"{where}: must be a finite number, got {value!r:.40}")
    return float(value)


# -- the public functions ---------------------------------------------------------------------
def sweep(model, grid, *, params=None, t_end=None, n_points=None, method=None, rtol=None,
          atol=None, step=None, t_start=0.0, jit=None, workers=None, batch=None,
          scheduler=None, progress=True):
    """Simulate ``model`` for every combination of the values in ``grid``.

    Parameters
    ----------
    model : Model or System
    grid : dict
        Model parameter name -> the values it takes (a sequence of numbers). The members are
        the Cartesian product, in the order of the dict.
    params : dict, optional
        Values of other model parameters, the same for every member.
    t_end, n_points, method, rtol, atol, step, t_start, jit
        As for ``kn.simulate`` (settings not given come from the model's ``simulation``).
    workers : int, optional
        Batches integrated at once in CasADi's threads (default: the cores this process may
        use). Not used on Dask, whose workers are the cluster's.
    batch : int, optional
        Members integrated together in one integrator (default: the members shared evenly by
        the workers, rounded up to a power of two, at most MAX_BATCH).
    scheduler : None, "local", address or distributed.Client
        None: this process, in threads. "local": a Dask LocalCluster on this machine, made
        for the sweep and closed after it. "tcp://host:8786": the Dask scheduler there. A
        ``distributed.Client``: that client's cluster.
    progress : bool or callable
        A tqdm bar on stderr (True), none (False), or a callable ``progress(done, total)``
        called after each batch.

    Returns
    -------
    xarray.Dataset
        Dimensions: one per swept parameter (its values as coordinate), ``time``, and the
        components of vector signals. Variables: each probe signal and state, ``status``,
        ``reason`` and ``t_reached`` per member. A member that fails is kept as far as it
        got (NaN after) with its reason; an interrupted sweep (Ctrl-C) returns what
        finished, the rest marked "interrupted" and ``attrs["interrupted"]`` true.
    """
    system = _system(model)
    if not isinstance(grid, dict) or not grid:
        raise ModelError("sweep: the grid must be a non-empty dict of parameter name -> "
                         "values")
    names = _names(system, grid, "sweep")
    for name in names:
        values = grid[name]
        if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or \
                not len(values):
            raise ModelError(f"sweep: {name!r}: give a non-empty sequence of values, got "
                             f"{values!r:.60}")
    _check_members(math.prod(len(grid[name]) for name in names), "sweep: the grid")
    axes = [[_real(v, f"sweep: {name}[{i}]") for i, v in enumerate(grid[name])]
            for name in names]
    values = np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, len(names))
    layout = {"dims": list(names), "coords": {n: np.array(a) for n, a in zip(names, axes)},
              "shape": tuple(len(a) for a in axes)}
    return _run(system, names, values, layout, params, t_end, n_points, method, rtol, atol,
                step, t_start, jit, workers, batch, scheduler, progress)


def sample(model, distributions, n, *, seed=None, params=None, t_end=None, n_points=None,
           method=None, rtol=None, atol=None, step=None, t_start=0.0, jit=None,
           workers=None, batch=None, scheduler=None, progress=True):
    """Monte Carlo: simulate ``model`` for ``n`` members whose parameters are drawn from
    ``distributions``.

    ``distributions``: model parameter name -> a distribution (``kn.normal``,
    ``kn.uniform``, a frozen ``scipy.stats`` distribution) or a sequence of ``n`` values.
    ``seed`` makes the draw repeatable (the parameters are drawn in the order of the dict).
    Every other argument and the result are as for ``sweep``, with one dimension ``member``
    and the drawn values as coordinates along it.
    """
    system = _system(model)
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ModelError(f"sample: n must be a positive integer, got {n!r:.40}")
    _check_members(int(n), "sample: n")
    if not isinstance(distributions, dict) or not distributions:
        raise ModelError("sample: give a non-empty dict of parameter name -> distribution")
    names = _names(system, distributions, "sample")
    rng = np.random.default_rng(seed)
    columns = []
    for name in names:
        dist = distributions[name]
        if hasattr(dist, "rvs"):
            drawn = np.asarray(dist.rvs(size=n, random_state=rng), dtype=float).ravel()
        elif hasattr(dist, "__len__") and not isinstance(dist, (str, bytes)):
            drawn = np.array([_real(v, f"sample: {name}[{i}]") for i, v in enumerate(dist)])
        else:
            raise ModelError(f"sample: {name!r}: give a distribution (kn.normal, kn.uniform, "
                             f"a scipy.stats one) or {n} values, got {dist!r:.60}")
        if drawn.shape != (n,):
            raise ModelError(f"sample: {name!r}: {len(drawn)} values for n = {n} members")
        columns.append(drawn)
    values = np.column_stack(columns)
    layout = {"dims": ["member"], "coords": {"member": np.arange(n)}, "shape": (n,),
              "member_coords": {name: values[:, k] for k, name in enumerate(names)},
              "distributions": {name: repr(distributions[name]) for name in names}}
    return _run(system, names, values, layout, params, t_end, n_points, method, rtol, atol,
                step, t_start, jit, workers, batch, scheduler, progress)


def _system(model):
    return model if isinstance(model, System) else model.compile()


def _check_members(n, what):
    """Refuse more than MAX_MEMBERS members, before any is made."""
    if n > MAX_MEMBERS:
        raise ModelError(f"{what}: {n:.3g} members, more than the {MAX_MEMBERS} a sweep may "
                         f"run; sweep fewer values (or in parts)")


def _check_size(job, n):
    """Refuse a sweep whose results would not fit MAX_OUTPUT_BYTES, before any member runs."""
    system = job.system
    per_point = system.n_states + system.n_algebraic + sum(s.size for s in system.signals)
    need = 8 * n * len(job.grid) * per_point
    if need > MAX_OUTPUT_BYTES:
        raise ModelError(f"sweep: {n} members x {len(job.grid)} points x {per_point} values "
                         f"(states and probe signals) would need {need / 2**30:.3g} GiB, more "
                         f"than the {MAX_OUTPUT_BYTES / 2**30:g} GiB a run may keep; fewer "
                         f"members or points (n_points)")


def _names(system, given, what):
    names = list(given)
    known = system.param_names
    for name in names:
        if name not in known:
            raise ModelError(f"{what}: {name!r} is no model parameter{suggest(name, known)}; "
                             f"parameters are {', '.join(known) or 'none'}")
    return names


# -- the plan of a sweep ------------------------------------------------------------------------
class Job:
    """What every member shares: the System, the settings, the base parameter vector and how
    to check a member's values. Picklable as the model's text (for Dask)."""

    def __init__(self, system, names, params, settings, t_start, jit):
        self.system, self.names, self.settings = system, list(names), dict(settings)
        self.t_start, self.jit = float(t_start), jit
        self.base = dict(params or {})
        self.p = system.param_vector(self.base)      # checks the common overrides once
        self.columns = [system.param_names.index(n) for n in self.names]
        self.grid = np.linspace(self.t_start, settings["t_end"], int(settings["n_points"]))
        self._checks = _dependent_parameters(system.model, self.names)
        self._x0 = _constant_start(system, self.columns, self.p)

    def __getstate__(self):
        from ..graph.io import dumps
        state = dict(self.__dict__)
        state["system"] = (dumps(self.system.model), _formulation(self.system))
        state.pop("_checks")
        state.pop("_x0")
        return state

    def __setstate__(self, state):
        text, loops = state.pop("system")
        self.__dict__.update(state)
        self.system = _remote_system(text, loops)
        self._checks = _dependent_parameters(self.system.model, self.names)
        self._x0 = _constant_start(self.system, self.columns, self.p)

    # -- one member's numbers ------------------------------------------------------------------
    def prepare(self, values):
        """(p, x0) of the member with ``values`` of the swept parameters, or a ModelError:
        its values and every component parameter that depends on them checked, its initial
        state found (loops closed) and its equations finite there."""
        system = self.system
        overrides = {**self.base, **dict(zip(self.names, map(float, values)))}
        env = system.model.parameter_values(overrides)
        env_t = {**env, "t": 0.0}
        problems = []
        for value, spec, where in self._checks:
            try:
                evaluate(value, spec, env_t, where)
            except ModelError as exc:
                problems.extend(exc.problems)
        if problems:
            raise ModelError(problems)
        p = self.p.copy()
        p[self.columns] = values
        x0 = self._x0 if self._x0 is not None else np.concatenate(system.initial_full_p(p))
        return p, x0


def _dependent_parameters(model, names):
    """(value, spec, place) of every component parameter whose expression reads one of
    ``names``: what a member's values must be checked against (the others were checked once,
    with the model's values)."""
    flat = model.flat()
    names = set(names)
    out = []
    for comp in flat.components.values():
        for key, spec in comp.params.items():
            value = comp._values.get(key)
            if any(names & parse(s).names for s in _strings(value)):
                out.append((value, spec, flat.place(comp, key)))
    return out


def _constant_start(system, columns, p):
    """The initial state when it is the same for every member: a tree (no loop to close, no
    prescribed motion, no algebraic loop of signals) whose given start values do not depend on
    the swept parameters (CasADi's dependency test); else None (found per member)."""
    asm = system.asm
    net = asm.net
    if system.formulation != "tree" or asm.prescribed or system.n_algebraic or \
            (net is not None and net.alg_z):
        return None
    starts = [asm.q_start, asm.u_start] + ([ca.SX(s) for s in net.start] if net else [])
    swept = ca.vertcat(*[asm.p[k] for k in columns])
    if ca.depends_on(ca.densify(ca.vertcat(*starts)), swept):
        return None
    return np.concatenate(system.initial_full_p(p))


def _strings(value):
    if isinstance(value, str):
        yield value
    elif isinstance(value, (list, tuple)):
        for v in value:
            yield from _strings(v)


def _formulation(system):
    return system.formulation if system.formulation in ("partition", "projected",
                                                        "baumgarte") else "partition"


_REMOTE = collections.OrderedDict()
_REMOTE_LOCK = threading.Lock()


def _remote_system(text, loops):
    """The System of a model text, compiled once per process (a Dask worker keeps it)."""
    from ..graph.io import loads
    key = (text, loops)
    with _REMOTE_LOCK:
        if key not in _REMOTE:
            _REMOTE[key] = loads(text).compile(loops=loops)
            while len(_REMOTE) > 8:
                _REMOTE.popitem(last=False)
        _REMOTE.move_to_end(key)
        return _REMOTE[key]


# -- the outcome of members --------------------------------------------------------------------
class Outcome:
    """The rows of a batch: states (B, n_points, n_full), outputs (B, n_points, n_signals),
    status, reason, t_reached and the method of each member."""

    def __init__(self, job, n):
        system, m = job.system, len(job.grid)
        self.states = np.full((n, m, system.n_states + system.n_algebraic), np.nan)
        self.outputs = np.full((n, m, sum(s.size for s in system.signals)), np.nan)
        self.status = ["ok"] * n
        self.reason = [""] * n
        self.t_reached = np.full(n, job.grid[-1])
        self.method = [""] * n

    def fail(self, i, reason, t_reached=np.nan):
        self.status[i], self.reason[i], self.t_reached[i] = "failed", reason, t_reached


def run_batch(job, values, batch=None):
    """Run the members with swept ``values`` (B, k): batches of ``batch`` members (default:
    all), each in a CasADi thread of its own. Returns an Outcome."""
    out = Outcome(job, len(values))
    prepared = []
    for i, row in enumerate(values):
        try:
            prepared.append((i,) + job.prepare(row))
        except ModelError as exc:
            out.fail(i, f"refused: {exc}", job.t_start)
    key = job.settings["method"]
    batched = key in BATCHED and not job.system.n_algebraic and job.system.n_states and \
        getattr(job.system, "modes", None) is None and \
        job.system.eq.clock is None
    if batched and prepared:
        prepared = _finite_start(job, prepared, out)
    if not batched or not prepared:
        _one_by_one(job, [i for i, _, _ in prepared], values, out)
        return out
    size = batch or len(prepared)
    groups = [prepared[k:k + size] for k in range(0, len(prepared), size)]
    _integrate(job, groups, size, values, out)
    return out


def _finite_start(job, prepared, out):
    """The members whose equations are finite and below OVERFLOW at their start; the others
    are marked failed, as ``simulate`` refuses them."""
    system = job.system
    P = np.column_stack([p for _, p, _ in prepared])
    X = np.column_stack([x for _, _, x in prepared])
    with np.errstate(all="ignore"):
        rates = np.asarray(system.f_rhs.map(len(prepared))(job.t_start, X, P))
    keep = []
    for k, (i, p, x) in enumerate(prepared):
        if np.all(np.abs(x) < OVERFLOW) and np.all(np.abs(rates[:, k]) < OVERFLOW):
            keep.append((i, p, x))
        else:
            out.fail(i, "refused: " + overflow_message(system.model, "the equations", p,
                                                       system.param_names), job.t_start)
    return keep


def _integrate(job, groups, size, values, out):
    """Integrate ``groups`` of prepared members (each at most ``size``), all at once."""
    system, settings = job.system, job.settings
    method = settings["method"]
    if method == "auto":
        everyone = [m for g in groups for m in g]
        stiff = _stiff(job, everyone)
        method = "cvodes" if stiff else "cvodes-adams"
    integ = _batched_integrator(job, method, size, len(groups))
    nx = system.n_states
    X0, P = [], []
    for g in groups:
        padded = g + [g[0]] * (size - len(g))    # same size for every batch: one integrator
        X0.append(np.concatenate([x for _, _, x in padded]))
        P.append(np.append(np.concatenate([p for _, p, _ in padded]), job.t_start))
    try:
        with SOLVER_LOCK, tempfile.TemporaryFile() as sink, solver_output(sink):
            xf = _call(integ, x0=np.column_stack(X0), p=np.column_stack(P))[integ.index_out("xf")]
    except RuntimeError as exc:
        if len(groups) > 1:            # find the batch that failed: the others are kept
            for g in groups:
                _integrate(job, [g], size, values, out)
            return
        _one_by_one(job, [i for i, _, _ in groups[0]], values, out, solver_reason(str(exc)))
        return
    m = len(job.grid)
    f_out = _outputs_function(job, size)
    for b, g in enumerate(groups):
        block = xf[:, b * (m - 1):(b + 1) * (m - 1)]            # (size * nx, m - 1)
        states = np.concatenate([X0[b][:, None], block], axis=1).reshape(size, nx, m)
        members = [i for i, _, _ in g]
        if not np.all(np.isfinite(states[:len(g)])):
            _one_by_one(job, members, values, out, "the state became non-finite")
            continue
        T = np.tile(job.grid, size)[None, :]
        Xcols = states.transpose(1, 0, 2).reshape(nx, size * m)
        Pm = np.repeat(P[b][:-1].reshape(size, -1).T, m, axis=1)
        [y] = _call(f_out, T, Xcols, Pm)                      # (n_signals, size * m)
        y = y.reshape(-1, size, m).transpose(1, 2, 0)
        for k, i in enumerate(members):
            out.states[i] = states[k].T
            out.outputs[i] = y[k]
            out.method[i] = method


def _stiff(job, members):
    """Whether ``auto`` must take BDF for these members: the stiffness test of
    ``methods.stiffness`` on each member's Jacobian at its start (exact, mapped), true when
    any one is stiff."""
    system = job.system
    if not system.damped:
        return False
    n = len(members)
    J = np.asarray(system.jacobian_function().map(n)(
        job.t_start, np.column_stack([x for _, _, x in members]),
        np.column_stack([p for _, p, _ in members])))
    nx = system.n_states
    J = J.reshape(nx, n, nx).transpose(1, 0, 2)
    with np.errstate(all="ignore"):
        if not np.all(np.isfinite(J)):
            return False
        lam = np.linalg.eigvals(J)
    sigma = np.max(np.maximum(0.0, -lam.real), axis=1)
    omega = np.maximum(np.max(np.maximum(0.0, lam.real), axis=1), np.max(np.abs(lam.imag), axis=1))
    horizon = job.grid[-1] - job.grid[0]
    return bool(np.any((sigma * horizon > STIFF_HORIZON_STEPS) & (sigma > STIFF_RATIO * omega)))


def _jit_options(job):
    if not (_jit.enabled(job.jit) and job.system.n_states):
        return None
    return {"stats": {}, "required": job.jit is True, "deadline": None,
            "cancelled": lambda: False}


def _batched_integrator(job, method, size, copies):
    """One CasADi integrator of ``size`` members stacked into one ODE (tolerances divided by
    sqrt(size)), mapped over ``copies`` such batches in threads; kept per System."""
    system, settings = job.system, job.settings
    jit = _jit_options(job)
    m = METHODS[method]
    taus = (job.grid[1:] - job.t_start).tolist()
    opts = dict(m.options)
    if m.sundials:
        scale = math.sqrt(size)
        opts.update(reltol=settings["rtol"] / scale, abstol=settings["atol"] / scale)
    else:
        spacing = job.grid[1] - job.grid[0]
        per = max(1, math.ceil(spacing / (settings["step"] or spacing) * (1 - 1e-12)))
        opts.update(show_eval_warnings=False, number_of_finite_elements=per * len(taus))
    key = ("sweep", method, size, copies, tuple(taus), tuple(sorted(opts.items())),
           bool(jit))

    def build():
        dae = _batched_dae(system, size, jit, m.newton)
        integ = ca.integrator("sweep", m.plugin, dae, 0.0, taus, opts)
        return integ if copies == 1 else integ.map(copies, "thread", copies)
    return compiled(system).integrator(key, build)


def _batched_dae(system, size, jit, newton):
    """The DAE of ``size`` stacked members, as CasADi's integrators take it: states
    (size * nx), parameters (size * np, then the start time t0)."""
    nx, npar = system.n_states, len(system.param_names)

    def build():
        t, x, p = ca.MX.sym("t"), ca.MX.sym("x", nx * size), ca.MX.sym("p", npar * size)
        ode = system.f_rhs.map(size)(t, ca.reshape(x, nx, size), ca.reshape(p, npar, size))
        f = ca.Function(f"sweep_rhs_{size}", [t, x, p], [ca.reshape(ode, nx * size, 1)])
        if jit:
            f = _jit.external(f, newton, **jit)
        tau, xs = ca.MX.sym("tau"), ca.MX.sym("x", nx * size)
        pt, empty = ca.MX.sym("p", npar * size + 1), ca.MX(0, 1)
        return ca.Function("dae", [tau, xs, ca.MX.sym("z", 0), pt, ca.MX.sym("u", 0)],
                           [f(tau + pt[-1], xs, pt[:-1]), empty, empty, empty],
                           ca.dyn_in(), ca.dyn_out())
    return compiled(system).memo(("sweep dae", size, bool(jit), newton), build)


def _outputs_function(job, size):
    """The probe signals of ``size`` members at every grid time: f_out mapped over both,
    compiled as one function under JIT (a compiled f_out called per column from a map costs
    more than the integration)."""
    system, n = job.system, len(job.grid) * size
    jit = _jit_options(job)

    def build():
        f = system.f_out.map(n)
        if not (jit and system.signals):
            return f
        t, x = ca.MX.sym("t", 1, n), ca.MX.sym("x", system.n_states + system.n_algebraic, n)
        p = ca.MX.sym("p", len(system.param_names), n)
        return _jit.external(ca.Function(f"sweep_outputs_{n}", [t, x, p], [f(t, x, p)]),
                             False, **jit)
    return compiled(system).memo(("sweep outputs", n, bool(jit)), build)


def _call(f, *args, **named):
    """``f(*args, **named)``'s outputs as numpy arrays, through ``Function.buffer`` (CasADi's
    conversion of a large result to numpy costs more than computing it); inputs not given
    are zero. Outputs must be dense."""
    buf, trigger = f.buffer()
    given = dict(enumerate(args))
    given.update({f.index_in(k): v for k, v in named.items()})
    keep = {i: np.asfortranarray(a, dtype=float) for i, a in given.items()}
    for i, a in keep.items():
        buf.set_arg(i, memoryview(a.ravel(order="F")))
    outs = []
    for i in range(f.n_out()):
        rows, cols = f.size_out(i)
        outs.append(np.zeros((rows, cols), order="F"))
        buf.set_res(i, memoryview(outs[-1].ravel(order="F")))
    trigger()
    return outs


def _one_by_one(job, members, values, out, why=None):
    """Members run through ``simulate``, one at a time: a failure is marked with its reason,
    a SIGINT stops the sweep (KeyboardInterrupt) after what finished."""
    s = job.settings
    for i in members:
        overrides = {**job.base, **dict(zip(job.names, map(float, values[i])))}
        try:
            res = simulate(job.system, t_end=s["t_end"], n_points=s["n_points"],
                           method=s["method"], rtol=s["rtol"], atol=s["atol"], step=s["step"],
                           t_start=job.t_start, jit=job.jit, params=overrides)
        except SimulationError as exc:
            if exc.signal is not None:
                raise KeyboardInterrupt from None
            res = exc.results
            out.fail(i, str(exc), exc.t_reached)
        except ModelError as exc:
            out.fail(i, f"refused: {exc}", job.t_start)
            continue
        n = len(res.t)
        out.states[i, :n] = res.states
        if res.signals:
            out.outputs[i, :n] = np.column_stack(
                [res[name].reshape(n, -1) for name in res.signals])
        out.method[i] = res.method or ""


# -- running all members -----------------------------------------------------------------------
def _run(system, names, values, layout, params, t_end, n_points, method, rtol, atol, step,
         t_start, jit, workers, batch, scheduler, progress):
    given = {"t_end": t_end, "n_points": n_points, "method": method, "rtol": rtol,
             "atol": atol, "step": step}
    settings = {**DEFAULTS, **system.model.simulation,
                **{k: v for k, v in given.items() if v is not None}}
    settings["method"] = check_settings(system, settings, t_start, None, None)
    settings.update(rtol=float(settings["rtol"]), atol=float(settings["atol"]),
                    n_points=int(settings["n_points"]))
    job = Job(system, names, params, settings, t_start, jit)
    n = len(values)
    _check_size(job, n)
    if workers is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else \
            (os.cpu_count() or 1)
    for what, v in (("workers", workers), ("batch", batch)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, np.integer))
                              or v < 1):
            raise ModelError(f"{what}: must be a positive integer, got {v!r:.40}")
    if workers > MAX_WORKERS:
        raise ModelError(f"workers: at most {MAX_WORKERS} threads, got {workers}")
    if batch is not None and batch > MAX_BATCH:
        raise ModelError(f"batch: at most {MAX_BATCH} members integrated together (their "
                         f"tolerances are divided by sqrt(batch)), got {batch}")
    if batch is None:       # a power of two: sweeps of other sizes reuse the compiled batch
        batch = min(MAX_BATCH, 1 << max(0, math.ceil(n / workers) - 1).bit_length())
    outcome = Outcome(job, n)
    done = np.zeros(n, dtype=bool)
    started = time.perf_counter()
    report = _progress(progress, n)
    interrupted = False
    try:
        if scheduler is None:
            _local(job, values, batch, workers, outcome, done, report)
        else:
            _dask(job, values, batch, scheduler, outcome, done, report)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        report(None)
    for i in np.flatnonzero(~done):
        outcome.status[i], outcome.reason[i] = "interrupted", "the sweep was interrupted"
        outcome.t_reached[i] = np.nan
    seconds = time.perf_counter() - started
    return _dataset(job, layout, outcome, {
        "interrupted": int(interrupted), "seconds": seconds,
        "scheduler": _scheduler_name(scheduler),
        "workers": workers if scheduler is None else 0, "batch": batch})


def _local(job, values, batch, workers, outcome, done, report):
    """Batches of ``batch`` members, ``workers`` batches at a time in CasADi's threads."""
    n = len(values)
    chunk = batch * workers
    for start in range(0, n, chunk):
        idx = np.arange(start, min(n, start + chunk))
        part = run_batch(job, values[idx], batch)
        _store(outcome, done, idx, part)
        report(len(idx))


def _store(outcome, done, idx, part):
    outcome.states[idx] = part.states
    outcome.outputs[idx] = part.outputs
    outcome.t_reached[idx] = part.t_reached
    for k, i in enumerate(idx):
        outcome.status[i], outcome.reason[i] = part.status[k], part.reason[k]
        outcome.method[i] = part.method[k]
    done[idx] = True


def _dask(job, values, batch, scheduler, outcome, done, report):
    """Each batch one Dask task; results gathered as they complete."""
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise ModelError("scheduler: Dask is not installed (pip install "
                         "'kinetwork[sweep]')") from None
    own = []
    if isinstance(scheduler, Client):
        client = scheduler
    elif scheduler == "local":
        cluster = LocalCluster(threads_per_worker=1, dashboard_address=":0")
        client = Client(cluster)
        own = [client, cluster]
    elif isinstance(scheduler, str) and "://" in scheduler:
        try:
            client = Client(scheduler, timeout=30)
        except OSError as exc:
            raise ModelError(f"scheduler {scheduler!r}: cannot connect ({exc})") from None
        own = [client]
    else:
        raise ModelError(f"scheduler: None, 'local', an address (tcp://host:8786) or a "
                         f"distributed.Client, got {scheduler!r:.60}")
    futures = {}
    try:
        [remote_job] = client.scatter([job], broadcast=True)
        for start in range(0, len(values), batch):
            idx = np.arange(start, min(len(values), start + batch))
            fut = client.submit(run_batch, remote_job, values[idx], batch, pure=False)
            futures[fut] = idx
        # results fetched in the background as tasks finish (a fetch per future, one after
        # another, waited a round trip each)
        for fut, part in as_completed(list(futures), with_results=True, raise_errors=False):
            idx = futures[fut]
            if fut.status != "finished":       # a worker lost, a task failed: say so
                exc = fut.exception()
                part = Outcome(job, len(idx))
                for k in range(len(idx)):
                    part.fail(k, f"the Dask task failed: {type(exc).__name__}: {exc}")
            _store(outcome, done, idx, part)
            report(len(idx))
    finally:
        for fut in futures:
            if not fut.done():
                fut.cancel()
        for thing in own:
            thing.close()


def _scheduler_name(scheduler):
    if scheduler is None:
        return "threads"
    if isinstance(scheduler, str):
        return "dask LocalCluster" if scheduler == "local" else f"dask {scheduler}"
    return f"dask {getattr(getattr(scheduler, 'scheduler', None), 'address', scheduler)}"


def _progress(progress, total):
    """A callable taking the members just finished (None: the end)."""
    if callable(progress):
        count = [0]

        def call(k):
            if k is not None:
                count[0] += k
                progress(count[0], total)
        return call
    if not progress:
        return lambda k: None
    from tqdm import tqdm
    bar = tqdm(total=total, unit="run", desc="sweep", leave=False)

    def update(k):
        if k is None:
            bar.close()
        else:
            bar.update(k)
    return update


# -- the Dataset -------------------------------------------------------------------------------
def _dataset(job, layout, outcome, attrs):
    import xarray as xr
    system = job.system
    dims, shape = layout["dims"], layout["shape"]
    time_ = job.grid
    data = {}
    names = system.state_names + system.algebraic_names
    units = system.state_units + system.algebraic_units
    for k, (name, unit) in enumerate(zip(names, units)):
        data[name] = (dims + ["time"], outcome.states[:, :, k].reshape(*shape, len(time_)),
                      {"units": unit, "kind": "state"})
    col = 0
    for sig in system.signals:
        block = outcome.outputs[:, :, col:col + sig.size]
        col += sig.size
        extra = _component_dims(sig.shape)
        data[sig.name] = (dims + ["time"] + extra,
                          block.reshape(*shape, len(time_), *sig.shape),
                          {"units": sig.unit, "kind": "probe", "probe": sig.probe,
                           "quantity": sig.quantity, "port": sig.target})
    data["status"] = (dims, np.array(outcome.status, dtype=object).reshape(shape),
                      {"doc": "ok, failed (see reason) or interrupted"})
    data["reason"] = (dims, np.array(outcome.reason, dtype=object).reshape(shape),
                      {"doc": "why a member failed"})
    data["t_reached"] = (dims, outcome.t_reached.reshape(shape),
                         {"units": "s", "doc": "the time a member's run reached"})
    data["method"] = (dims, np.array(outcome.method, dtype=object).reshape(shape),
                      {"doc": "the integration method that ran the member"})
    coords = {"time": ("time", time_, {"units": "s"})}
    for name, vals in layout["coords"].items():
        coords[name] = (name, vals, {"units": _param_unit(system, name)})
    for name, vals in layout.get("member_coords", {}).items():
        coords[name] = ("member", vals, {"units": _param_unit(system, name),
                                         "distribution": layout["distributions"][name]})
    s = job.settings
    ds = xr.Dataset(data, coords=coords, attrs={
        "model": system.model.name, "method": s["method"], "rtol": s["rtol"],
        "atol": s["atol"], "t_start": job.t_start, "t_end": float(s["t_end"]),
        "n_points": s["n_points"], "members": len(outcome.status),
        "failed": outcome.status.count("failed"), **attrs})
    return ds


def _component_dims(shape):
    if shape == ():
        return []
    if shape == (3,):
        return ["xyz"]
    if shape == (3, 3):
        return ["row", "col"]
    return [f"component{k}_{n}" for k, n in enumerate(shape)]


def _param_unit(system, name):
    """A model parameter's unit: that of the component parameters it is given to as it is
    (``c`` given to a SpringDamper's ``c``: N.m/rad), when they agree; else ""."""
    units = set()
    for comp in system.model.flat().components.values():
        for key, spec in comp.params.items():
            if comp._values.get(key) == name and isinstance(spec.unit, str):
                units.add(spec.unit)
    return units.pop() if len(units) == 1 else ""


# -- the command line --------------------------------------------------------------------------
def _values(text):
    """argparse type of ``--param NAME=V1,V2,...`` or ``NAME=START:STOP:COUNT``."""
    import argparse
    name, sep, rest = text.partition("=")
    try:
        if not sep or not name.strip():
            raise ValueError
        if rest.count(":") == 2:
            start, stop, count = rest.split(":")
            if not 1 <= int(count) <= MAX_MEMBERS:
                raise argparse.ArgumentTypeError(
                    f"{name.strip()!r:.60}: COUNT must be 1 to {MAX_MEMBERS}, got "
                    f"{count.strip()[:20]}")
            values = np.linspace(float(start), float(stop), int(count)).tolist()
        elif rest.count(",") >= MAX_MEMBERS:
            raise argparse.ArgumentTypeError(f"{name.strip()!r:.60}: more than {MAX_MEMBERS} "
                                             f"values")
        else:
            values = [float(v) for v in rest.split(",")]
        if not values or not all(math.isfinite(v) for v in values):
            raise ValueError
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected NAME=V1,V2,... or NAME=START:STOP:COUNT with finite numbers, got "
            f"{text!r:.60}") from None
    return name.strip(), values


def add_command(sub):
    """The ``kinetwork sweep`` subcommand."""
    import argparse
    cmd = sub.add_parser(
        "sweep", help="simulate a model over a grid of parameter values",
        description="Simulate MODEL.json for every combination of the --param values (one "
                    "compiled system; batches in parallel threads, or on a Dask cluster), "
                    "print a line per member (its final probe values, or why it failed) "
                    "and write the whole sweep as NetCDF (xarray).")
    cmd.add_argument("model", metavar="MODEL.json",
                     help="model file, or the name of an example (kinetwork examples)")
    cmd.add_argument("--param", type=_values, action="append", default=[], required=True,
                     metavar="NAME=V1,V2,...",
                     help="a swept model parameter and its values (or START:STOP:COUNT); "
                          "repeat for a grid")
    cmd.add_argument("--t-end", type=float, metavar="T", help="end time [s]")
    cmd.add_argument("--n-points", type=int, metavar="N", help="points on the output grid")
    cmd.add_argument("--method", type=str.lower, choices=list(METHODS), metavar="M",
                     help=f"integrator: {', '.join(METHODS)}")
    cmd.add_argument("--rtol", type=float, metavar="R", help="relative tolerance")
    cmd.add_argument("--atol", type=float, metavar="A", help="absolute tolerance")
    cmd.add_argument("--jit", action=argparse.BooleanOptionalAction,
                     help="compile the equations to C (default: when a compiler is found)")
    cmd.add_argument("--workers", type=int, metavar="N",
                     help="batches integrated at once in threads (default: the cores)")
    cmd.add_argument("--batch", type=int, metavar="B", help="members per batch")
    cmd.add_argument("--scheduler", metavar="ADDRESS",
                     help="run on Dask: 'local' (a LocalCluster on this machine) or a "
                          "scheduler's address, tcp://host:8786")
    cmd.add_argument("--out", metavar="FILE.nc", help="write the sweep as NetCDF")
    cmd.add_argument("--force", action="store_true",
                     help="replace an existing file of another kind at --out (never the "
                          "model, nor a device, pipe or folder)")
    cmd.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                     help="a progress bar on stderr (default: when stderr is a terminal)")
    cmd.add_argument("--library", action="append", default=[], metavar="DIR",
                     help="a folder of subsystem files (TYPE.json)")
    return cmd


def run_command(args, model):
    """Run ``kinetwork sweep``; returns the exit code (3 when a member failed)."""
    import sys
    grid = dict(args.param)
    if len(grid) != len(args.param):
        raise ModelError("--param: a parameter is given twice")
    if args.out:                        # before any member runs
        check(args.out, "netcdf", what="--out", reads=model_files(model), force=args.force)
    progress = args.progress if args.progress is not None else sys.stderr.isatty()
    ds = sweep(model, grid, t_end=args.t_end, n_points=args.n_points, method=args.method,
               rtol=args.rtol, atol=args.atol, jit=args.jit, workers=args.workers,
               batch=args.batch, scheduler=args.scheduler, progress=progress)
    print(summary(ds))
    if args.out:
        try:
            to_netcdf(ds, args.out, overwrite=args.force, reads=model_files(model))
        except OSError as exc:
            raise ModelError(f"cannot write {args.out}: {exc.strerror or exc}") from None
        print(f"wrote {ds.attrs['members']} members to {args.out}")
    return 3 if ds.attrs["failed"] or ds.attrs["interrupted"] else 0


def summary(ds):
    """A line per member: its parameter values, then the last value of each scalar probe
    signal, or its status and reason."""
    dims = list(ds.status.dims)
    probes = [n for n, v in ds.data_vars.items()
              if v.attrs.get("kind") == "probe" and v.dims == tuple(dims) + ("time",)]
    lines = ["  ".join(dims + probes)]
    members = int(np.prod(ds.status.shape))
    for k, index in enumerate(np.ndindex(*ds.status.shape)):
        if k == SUMMARY_MEMBERS and members > SUMMARY_MEMBERS:
            failed = sum(1 for v in np.ravel(ds.status.values) if v != "ok")
            lines.append(f"... ({members} members in all, {failed} not ok; every one is in "
                         f"the Dataset, and in the NetCDF file of --out)")
            break
        at = dict(zip(dims, index))
        member = ds.isel(at)
        head = [f"{d}={member[d].item():g}" for d in dims]
        if member.status.item() == "ok":
            lines.append("  ".join(head + [f"{member[p].values[-1]:.6g}" for p in probes]))
        else:
            why = f"{member.status.item()}: {member.reason.item()}"
            lines.append("  ".join([*head, why]))
    return "\n".join(lines)


def to_netcdf(ds, path, overwrite=False, reads=()):
    """The Dataset as NetCDF (strings as fixed text, so that scipy's writer takes them),
    under the output policy (``kinetwork.outputs``): atomically, never over ``reads`` (the
    model's files), a special file or a folder, nor over a file that is not NetCDF unless
    ``overwrite``."""
    out = ds.copy()
    for name in ("status", "reason", "method"):
        out[name] = out[name].astype(str)
    write(path, out.to_netcdf, "netcdf", reads=reads, force=overwrite)
