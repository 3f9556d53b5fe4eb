"""Many members of one integration plan: each member's answer is the run ``Plan.run`` makes
for its parameters.

A member is integrated with its own error control, never stacked with others into one ODE
(whose joint error norm would make a member's accuracy depend on its batch-mates): the
plan's own single-member integrator (the same CasADi integrator, options and tolerances a
run of ``Plan.run`` builds) is mapped over the members of a call, which CasADi's threads
share (``Function.map(n, "thread", workers)``). Calls go over the output grid in chunks
sized so that one takes a fraction of a second (``CHUNK_WORK`` per thread, from the work the
plan's first chunk takes at the model's own parameters): between calls the sweep is stopped
by Ctrl-C or its ``stop`` callable, since a mapped call itself cannot be interrupted. A model
cheap enough goes in one call over the whole grid: its members are then, to the last bit, the
runs ``kn.simulate`` makes.

Every mapped call's return status is checked (a mapped call does not raise: it sets
``buf.ret()``), and every row it wrote must be finite: when a call fails, each of its members
runs again on its own through ``Plan.run``, which gives the failing one its reason and its
results up to the failure (and ``auto`` its second method), and the others their runs.
Members that a mapped call cannot run as ``Plan.run`` would (events, loops watched for
singular partitions, IDAS, scipy's steppers, the midpoint rule, a time limit) run one after
another through ``Plan.run`` itself.
"""

import math

import casadi as ca
import numpy as np

from ..equations.system import mapped
from ..errors import ModelError, SimulationError
from ..expr import parse
from ..graph.model import evaluate
from ..util import quote, suggest
from .compiled import compiled
from .chunks import CHUNK_WORK, FIRST_CHUNK_STEPS, _work
from .driver import _finite_start
from .fallback import look_budget
from .methods import METHODS, Casadi, Failure, _CasadiRun

#: members of one mapped call at most
MAX_BATCH = 64
#: the plugins whose integrator a member can share with its batch-mates through a map (IDAS's
#: options hold each member's initial rate: it cannot)
MAPPED = ("cvodes", "rk", "collocation")


# -- what members keep ------------------------------------------------------------------------
class Keep:
    """The columns a batch keeps of each member (``outputs=[...]``): states by name and probe
    signals by name; None keeps everything."""

    def __init__(self, system, outputs=None):
        states = system.state_names + system.algebraic_names
        units = system.state_units + system.algebraic_units
        if isinstance(outputs, str):
            outputs = [outputs]
        if outputs is None:
            wanted_states, wanted_signals = list(states), list(system.signals)
        else:
            by_name = {sig.name: sig for sig in system.signals}
            problems = [f"outputs: {quote(n, 60)} is no probe signal or state"
                        f"{suggest(n, list(by_name) + states)}; probe signals: "
                        f"{', '.join(by_name) or 'none'}" for n in outputs
                        if n not in by_name and n not in states]
            if problems or not list(outputs):
                raise ModelError(problems or ["outputs: name at least one probe signal or "
                                              "state (None keeps them all)"])
            wanted_states = [n for n in states if n in outputs]
            wanted_signals = [sig for sig in system.signals if sig.name in outputs]
        self.state_names = wanted_states
        self.state_units = [units[states.index(n)] for n in wanted_states]
        self.state_index = [states.index(n) for n in wanted_states]
        self.signals = wanted_signals
        offsets, col = {}, 0
        for sig in system.signals:
            offsets[sig.name] = col
            col += sig.size
        self.signal_index = [offsets[sig.name] + k for sig in wanted_signals
                             for k in range(sig.size)]
        self.n_states, self.n_columns = len(self.state_index), len(self.signal_index)


class Members:
    """What the members of a batch gave: ``states`` (n, n_t, kept states), ``outputs`` (n,
    n_t, kept probe columns), and per member ``status`` ("ok", "failed", "pending" before it
    ran), ``reason``, ``t_reached`` and the ``method`` that ran it."""

    def __init__(self, plan, n, keep):
        m = len(plan.grid)
        self.keep = keep
        self.states = np.full((n, m, keep.n_states), np.nan)
        self.outputs = np.full((n, m, keep.n_columns), np.nan)
        self.status = ["pending"] * n
        self.reason = [""] * n
        self.t_reached = np.full(n, np.nan)
        self.method = [""] * n

    def store(self, i, X, Y, method, t_reached, status="ok", reason=""):
        """Member i's full states X and probe columns Y (its first rows of the grid)."""
        n = len(X)
        if n:
            self.states[i, :n] = np.asarray(X)[:, self.keep.state_index]
            if self.keep.n_columns:
                self.outputs[i, :n] = np.asarray(Y)[:, self.keep.signal_index]
        self.status[i], self.reason[i] = status, reason
        self.t_reached[i], self.method[i] = t_reached, method

    def refuse(self, i, reason, t):
        self.status[i], self.reason[i], self.t_reached[i] = "failed", f"refused: {reason}", t


# -- the members' parameters ------------------------------------------------------------------
class Varying:
    """The parameter vectors and starts of members that differ in ``names`` only: a member's
    values and every component parameter that reads them checked, as ``Plan.vector`` checks
    a run's (the others were checked once, with ``base``)."""

    def __init__(self, plan, names, base=None):
        system = plan.system
        self.plan, self.names = plan, list(names)
        self.base = dict(base or {})
        self.p = plan.vector(self.base)
        internal = [plan.param_name(n) for n in self.names]
        self.columns = [system.param_names.index(n) for n in internal]
        lifted = plan.lifted
        # found again for each member: the parameters that the initial equations solve, and
        # lifted ones whose defaults follow parameters that members change
        self.slow = system.initial_equations.solves_parameters() or (
            lifted is not None and any(path not in self.names and path not in self.base
                                       for path in lifted.names))
        self._checks = _dependent_parameters(system.model, internal)
        self._x0 = None if self.slow else _constant_start(system, self.columns, self.p)

    def vector(self, row):
        """p of the member whose values of ``names`` are ``row`` (numbers in SI)."""
        plan = self.plan
        if self.slow:
            return plan.vector({**self.base, **dict(zip(self.names, map(float, row)))})
        system = plan.system
        p = self.p.copy()
        p[self.columns] = row
        if self._checks:
            env = {**dict(zip(system.param_names, p.tolist())), "t": 0.0}
            problems = []
            for value, spec, where in self._checks:
                try:
                    evaluate(value, spec, env, where)
                except ModelError as exc:
                    problems.extend(exc.problems)
            if problems:
                raise ModelError(problems)
        return p

    def start(self, p):
        """The member's initial full state; a ModelError when its equations are not finite
        there (as ``Plan.start``, without keeping one per member)."""
        system, t = self.plan.system, self.plan.t_start
        x0 = self._x0 if self._x0 is not None else np.concatenate(system.initial_full_p(p))
        _finite_start(system, t, x0, p)
        return x0


def _dependent_parameters(model, names):
    """(value, spec, place) of every component parameter whose expression reads one of
    ``names``: what a member's values are checked against."""
    names = set(names)
    out = []
    for comp in model.flat().components.values():
        for key, spec in comp.params.items():
            value = comp._values.get(key)
            if any(names & parse(s).names for s in _strings(value)):
                out.append((value, spec, model.flat().place(comp, key)))
    return out


def _strings(value):
    if isinstance(value, str):
        yield value
    elif isinstance(value, (list, tuple)):
        for v in value:
            yield from _strings(v)


def _constant_start(system, columns, p):
    """The initial state when it is the same for every member: a tree (no loop to close, no
    prescribed motion, no algebraic loop of signals) whose start values do not depend on the
    varied parameters (CasADi's dependency test); else None (found per member)."""
    asm = system.asm
    net = asm.net
    if system.formulation != "tree" or asm.prescribed or system.n_algebraic or \
            (net is not None and net.alg_z) or system.modes is not None:
        return None
    starts = [asm.q_start, asm.u_start] + ([ca.SX(s) for s in net.start] if net else [])
    varied = ca.vertcat(*[asm.p[k] for k in columns])
    if ca.depends_on(ca.densify(ca.vertcat(*starts)), varied):
        return None
    return np.concatenate(system.initial_full_p(p))


# -- running them -------------------------------------------------------------------------------
def run_members(plan, members, out, *, workers=1, batch=None, stop=None, done=None,
                params=None):
    """Run ``members`` [(index into ``out``, p, x0)] of ``plan`` into ``out`` (a Members).

    ``workers`` threads share each mapped call of ``batch`` members (default:
    ``default_batch``); ``stop()`` is asked between calls and runs, a true answer leaves the
    members not yet run "pending" and returns; ``done(i)`` is called once member i is stored.
    ``params(i)``: what member i's results record as its parameters."""
    stop = stop or (lambda: False)
    done = done or (lambda i: None)
    params = params or (lambda i: None)
    template = _template(plan, members)
    if template is None:
        return _one_by_one(plan, members, out, stop, done, params)
    size = batch or default_batch(plan, template, len(members), workers)
    for start in range(0, len(members), size):
        if stop():
            return True
        groups = {}                     # auto may choose BDF for some members
        for i, p, x0 in members[start:start + size]:
            groups.setdefault(_method(plan, template, p, x0), []).append((i, p, x0))
        for key, call in groups.items():
            if key is None:             # auto's choice asks for a method a map cannot run
                stopped = _one_by_one(plan, call, out, stop, done, params)
            else:
                stopped = _call(plan, template, key, call, out, workers, stop, done, params)
            if stopped:
                return True
    return False


def _call(plan, template, key, call, out, workers, stop, done, params):
    """One mapped call of ``call``'s members; its members on their own when it fails.
    Returns True when stopped."""
    ok = _mapped(plan, template, key, call, out, workers, stop)
    if ok is None:                      # stopped between chunks
        return True
    if not ok:                          # a member failed: every one on its own
        return _one_by_one(plan, call, out, stop, done, params)
    for i, _, _ in call:
        done(i)
    return False


def default_batch(plan, template, n, workers):
    """Members per mapped call: as many as a call of a fraction of a second holds (so a
    cheap model's members go in few calls, an expensive one's a few at a time and the
    progress shows each), at most MAX_BATCH and n."""
    per_member = _interval_work(plan, template) * (len(plan.grid) - 1)
    per_thread = max(1, min(MAX_BATCH // workers, int(CHUNK_WORK / max(per_member, 1.0))))
    per_thread = 1 << (per_thread.bit_length() - 1)
    return max(1, min(n, workers * per_thread))


def _template(plan, members):
    """A Run of the plan at the first member (what builds the single-member integrator and
    chooses auto's method), or None when its members must run through ``Plan.run``."""
    system, settings = plan.system, plan.settings
    if not members or not system.n_states or system.n_algebraic or system.modes is not None \
            or system.f_dependent is not None or system.eq.clock is not None \
            or settings["time_limit"] is not None:
        return None
    if plan.key != "auto" and (not isinstance(METHODS[plan.key], Casadi)
                               or METHODS[plan.key].plugin not in MAPPED):
        return None
    _, p, x0 = members[0]
    run = plan.new_run(p, x0)
    if run.events is not None:
        return None
    if plan.jit_on:
        run.jit = {"stats": {}, "required": plan.jit is True, "deadline": None,
                   "cancelled": lambda: False}
    return run


def _method(plan, template, p, x0):
    """The method of one member (auto: by the stiffness test at its start), or None when it
    is not one a map runs."""
    if plan.key != "auto":
        return plan.key
    # the member's own values, also where the stiffness test reads them (p_solver)
    template.p = template.p_solver = p
    template.x0 = x0
    names, why = plan.methods(template, keep=False)
    if why.get("rk4", {}).get("step"):     # auto's RK4 at the member's own step
        return None
    method = METHODS[names[0]]
    return names[0] if getattr(method, "plugin", None) in MAPPED else None


def _interval_work(plan, template):
    """The work of one output interval of a member (evaluations times instructions), from
    the plan's first chunk at the model's own parameters; once per plan's System and
    settings."""
    system, settings = plan.system, plan.settings
    key = ("member work", plan.key, settings["rtol"], settings["atol"], settings["step"],
           settings["max_step"], plan.grid.tobytes(), bool(template.jit))

    def measure():
        estimate = 4 * FIRST_CHUNK_STEPS * template.instructions
        k = max(1, min(len(plan.grid) - 1, int(CHUNK_WORK / estimate)))
        try:
            p = system.param_vector()
            x0 = np.concatenate(system.initial_full_p(p))
            template.p, template.x0 = p, x0
            key = _method(plan, template, p, x0) or "cvodes"
            stepper = METHODS[key].start(template, plan.grid[0], x0)
            stepper.advance(plan.grid[1:k + 1])
            return max(_work(template, stepper.stats) / k, template.instructions)
        except (Failure, ModelError, RuntimeError):
            return estimate
    return compiled(system).memo(key, measure)


def _chunk(plan, template, per_thread):
    """Output intervals per mapped call: a call's work per thread about CHUNK_WORK."""
    intervals = len(plan.grid) - 1
    fit = CHUNK_WORK / (_interval_work(plan, template) * per_thread)
    if fit >= intervals:
        return intervals
    return 1 << (max(1, int(fit)).bit_length() - 1)


def _mapped(plan, template, key, call, out, workers, stop):
    """Integrate the members of ``call`` together (each its own integrator) into ``out``:
    True when every one reached the end, False when the call failed (nothing of it is
    stored), None when ``stop`` stopped it between chunks."""
    system, grid, method = plan.system, plan.grid, METHODS[key]
    nx, b = system.n_states, len(call)
    threads = min(workers, b)
    chunk = _chunk(plan, template, math.ceil(b / threads))
    X = np.empty((b, len(grid), nx))
    X[:, 0] = np.array([x0 for _, _, x0 in call])
    P = np.array([p for _, p, _ in call])
    # auto's Adams under its look budget, as in a run: a member it stalls on fails the call
    # within that budget, and runs on its own through Plan.run, which looks and switches
    template.look_steps = look_budget(template) \
        if plan.key == "auto" and key == "cvodes-adams" else None
    k = 0
    while k < len(grid) - 1:
        if k and stop():
            return None
        times = grid[k + 1:k + 1 + chunk]
        stepper = _CasadiRun(method, template, grid[k], X[0, k])
        opts = stepper.options(times)
        single_key, build = stepper.recipe(times, opts)
        single = compiled(system).integrator(single_key, build)
        f = compiled(system).integrator(("members", single_key, b, threads),
                                        lambda one=single: one.map(b, "thread", threads))
        # CasADi reads and writes column-major (n, b) blocks: a member's row of a C-ordered
        # (b, n) array; its outputs (nx, T) side by side, a (b, T, nx) array
        x0 = np.ascontiguousarray(X[:, k])
        p = np.ascontiguousarray(np.column_stack([P, np.full(b, grid[k])]))
        rows = np.full((b, len(times), nx), np.nan)
        buffer, evaluate_ = f.buffer()
        buffer.set_arg(f.index_in("x0"), memoryview(x0.ravel()))
        buffer.set_arg(f.index_in("p"), memoryview(p.ravel()))
        buffer.set_res(f.index_out("xf"), memoryview(rows.ravel()))
        try:
            with template.solver_section(grid[k]):
                evaluate_()
        except RuntimeError:          # a map of one is the integrator itself: it raises
            return False
        if buffer.ret() != 0 or not np.all(np.isfinite(rows)):
            return False
        X[:, k + 1:k + 1 + len(times)] = rows
        k += len(times)
    Y = _outputs(system, compiled(system).outputs(template.jit), grid, X, P) \
        if out.keep.n_columns else [None] * b
    if Y is None:                       # the outputs failed: each member on its own says why
        return False
    for (i, _, _), states, signals in zip(call, X, Y):
        out.store(i, states, signals, key, float(grid[-1]))
    return True


def _outputs(system, f_out, grid, X, P):
    """The probe signals (b, n_t, n_signals) of a call's members, states X (b, n_t, nx), in
    one evaluation of the output function mapped over every member and time, read through
    ``Function.buffer`` (a DM's conversion to numpy costs more than the evaluation); None
    when that evaluation failed (its return status)."""
    b, m, nx = X.shape
    n = b * m
    f = mapped(f_out, n)
    # column-major (rows, n) blocks are C-ordered (n, rows) arrays
    t = np.tile(grid, b)
    x = np.ascontiguousarray(X.reshape(n, nx))
    p = np.ascontiguousarray(np.repeat(P, m, axis=0))
    y = np.empty((n, f.size1_out(0)))
    buffer, evaluate_ = f.buffer()
    for k, value in enumerate((t, x, p)):
        buffer.set_arg(k, memoryview(value.ravel()))
    buffer.set_res(0, memoryview(y.ravel()))
    evaluate_()
    if buffer.ret() != 0:
        return None
    return y.reshape(b, m, -1)


def _one_by_one(plan, members, out, stop, done, params):
    """Members through ``Plan.run``, one after another: a failure is stored with its
    reason and its results up to it. Returns True when stopped (``stop``, or a signal that
    stopped a run)."""
    for i, p, _ in members:
        if stop():
            return True
        try:
            res = plan.run(params(i), p=p)
            status, reason, reached = "ok", "", float(res.t[-1])
        except SimulationError as exc:
            if exc.signal is not None:
                return True
            res, status, reason, reached = exc.results, "failed", str(exc), exc.t_reached
        except ModelError as exc:
            out.refuse(i, str(exc), plan.t_start)
            done(i)
            continue
        Y = np.column_stack([res[name].reshape(len(res.t), -1) for name in res.signals]) \
            if res.signals else np.zeros((len(res.t), 0))
        out.store(i, res.states, Y, res.method or "", reached, status, reason)
        done(i)
    return False
