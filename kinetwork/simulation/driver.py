"""simulate(): integrate a model with CasADi's integrators or scipy's, looked up in METHODS."""

import contextlib
import ctypes
import io
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..components.base import suggest
from ..errors import ModelError, SimulationError
from ..graph.model import check_setting
from . import jit as _jit
from .results import Results
from .system import System

DEFAULTS = {"t_end": 10.0, "n_points": 1001, "method": "auto", "rtol": 1e-6, "atol": 1e-8,
            "step": None}


@dataclass(frozen=True)
class Method:
    """One integration method a user can pick.

    ``run(system, grid, x0, p, settings)`` returns (states on the grid, failure reason or None,
    statistics); ``fixed`` methods take ``settings["step"]`` instead of tolerances; ``newton``
    methods iterate with the Jacobian (compiled with the right-hand side under JIT).
    """
    run: Callable
    doc: str
    fixed: bool = False
    newton: bool = False
    dae: bool = False          # handles algebraic variables (the loops' dependent coordinates)


def _casadi(plugin, newton, **options):
    """A CasADi integrator plugin: the whole integration runs in compiled code."""
    sundials = plugin in ("cvodes", "idas")

    def run(system, grid, x0, p, settings):
        opts = dict(options)
        nx = system.n_states
        if sundials:
            opts.update(reltol=settings["rtol"], abstol=settings["atol"])
            if plugin == "idas":
                # the consistent initial rate is f(t0, x0) (loops: z0 is consistent already):
                # IDAS's own search for it fails when it is large (a stiff spring)
                opts.update(calc_ic=False, init_xdot=_rate0(system, grid[0], x0, p))
        else:       # fixed steps: CasADi counts them over the whole horizon; a blow-up is
            opts["show_eval_warnings"] = False           # reported once, below
            opts["number_of_finite_elements"] = \
                _steps_per_interval(grid, settings["step"]) * (len(grid) - 1)
        jit = settings["jit"]
        m = None if sundials else opts["number_of_finite_elements"] // (len(grid) - 1)
        if settings.get("max_steps"):
            if sundials:
                opts["max_num_steps"] = int(settings["max_steps"])
            elif m > settings["max_steps"]:
                return x0[None, :], (f"the step budget of {settings['max_steps']} steps per "
                                     f"output interval is smaller than the {m} steps of "
                                     f"{settings['step'] or float(grid[1] - grid[0]):g} s that "
                                     f"the fixed-step method takes"), {}
        if settings.get("time_limit") or settings.get("progress"):
            # in chunks: the clock is read and the progress told between them
            chunk = max(1, (len(grid) - 1) // CHUNKS)
            limit = settings.get("time_limit")
            X, failure = _chunks(system, plugin, grid, x0, p, opts, jit, newton, chunk, m,
                                 deadline=settings["started"] + limit if limit else None,
                                 progress=settings.get("progress"))
            X, bad = _finite(X)
            return X, bad or failure, {"chunks": -(-(len(grid) - 1) // chunk)}
        integ = system.integrator(plugin, grid, opts, jit=jit, jacobian=newton,
                                  cache=plugin != "idas")       # idas: options hold x0
        try:
            out = integ(x0=x0[:nx], z0=x0[nx:], p=p)
        except RuntimeError as exc:
            X, reason = _chunks(system, plugin, grid, x0, p, opts, jit, newton, 1, m,
                                first_error=str(exc))
            return X, reason, {"restarted": "at every output time, after: " + _reason(str(exc))}
        X = np.vstack([x0, np.vstack([np.asarray(out["xf"]), np.asarray(out["zf"])]).T])
        stats = integ.stats()
        if not sundials:
            X, failure = _finite(X)
            return X, failure, {"steps": m * (len(X) - 1),
                                "step": float(grid[1] - grid[0]) / m}
        return X, None, {"steps": int(stats["nsteps"]), "rhs_evaluations": int(stats["nfevals"]),
                         "jacobian_evaluations": int(stats["n_call_jacF"])}
    return run


def _steps_per_interval(grid, step):
    """Equal steps per output interval, none longer than ``step`` (default: the spacing)."""
    dt = float(grid[1] - grid[0])
    return max(1, int(np.ceil(dt / (step or dt) * (1 - 1e-12))))


def _finite(X):
    """States up to the first non-finite one, and the reason if there is one."""
    good = np.all(np.isfinite(X), axis=1)
    if good.all():
        return X, None
    return X[:int(np.argmin(good))], "the state became non-finite (Inf or NaN)"


#: a run under a time limit or with a progress report goes in about this many chunks
CHUNKS = 50


def _chunks(system, plugin, grid, x0, p, options, jit, newton, chunk, m, deadline=None,
            first_error="", progress=None):
    """Integrate ``chunk`` output intervals at a time, each from where the last one ended:
    after a failure (``chunk`` = 1 keeps everything computed before it: a fresh start per
    output interval can even pass where the continued run failed), or to read the clock
    against ``deadline``. Returns (X, reason): reason is None when every interval went
    through."""
    X = [np.asarray(x0, dtype=float)]
    nx = system.n_states
    opts = {**options, "disable_internal_warnings": True} if plugin in ("cvodes", "idas") \
        else dict(options)
    k = 0
    while k < len(grid) - 1:
        sub = grid[k:k + chunk + 1]
        if m is not None:                      # fixed steps: counted over the chunk
            opts["number_of_finite_elements"] = m * (len(sub) - 1)
        if plugin == "idas":                   # idas starts from its consistent rate
            opts["init_xdot"] = _rate0(system, sub[0], X[-1], p)
        integ = system.integrator(plugin, sub, opts, cache=False, jit=jit, jacobian=newton)
        try:
            out = integ(x0=X[-1][:nx], z0=X[-1][nx:], p=p)
        except RuntimeError as exc:
            if len(sub) <= 2:
                return np.array(X), _reason(str(exc) or first_error)
            part, reason = _chunks(system, plugin, sub, X[-1], p, options, jit, newton, 1, m,
                                   first_error=str(exc))
            X.extend(part[1:])
            if reason is not None:
                return np.array(X), reason
        else:
            X.extend(np.vstack([np.asarray(out["xf"]), np.asarray(out["zf"])]).T)
        k += len(sub) - 1
        if progress is not None:
            progress(float(grid[k]))
        if deadline is not None and time.perf_counter() > deadline and k < len(grid) - 1:
            return np.array(X), "the time limit set for the run was reached"
    return np.array(X), None


def _rate0(system, t, X, p):
    """d(x)/dt at a consistent full state X = (x, z), as IDAS's ``init_xdot``."""
    nx = system.n_states
    rate = system.f_dae(t, X[:nx], X[nx:], p)[0]
    return tuple(float(v) for v in np.asarray(rate).ravel())


#: SUNDIALS return flags, in plain words
FLAGS = {
    "TOO_MUCH_WORK": "too many steps before the next output time: the solution may blow up "
                     "there, or the problem is stiff for this method",
    "TOO_MUCH_ACC": "the tolerances asked for are below machine precision",
    "ERR_FAIL": "the error test failed repeatedly: the step size collapsed",
    "CONV_FAIL": "the Newton iteration failed to converge repeatedly: the step size collapsed",
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


def _reason(message):
    for flag, words in FLAGS.items():
        if flag in message:
            return words
    lines = [ln.strip() for ln in message.splitlines() if ln.strip()]
    return (lines or ["integrator failed"])[-1]


def _scipy(name):
    """A scipy ODE solver (the stepper class solve_ivp uses) fed by the compiled CasADi
    right-hand side and Jacobian, stepped here so that a step budget or a time limit stops
    it with everything up to that point kept."""
    implicit = name in ("Radau", "BDF", "LSODA")

    def run(system, grid, x0, p, settings):
        import scipy.integrate                 # 0.4 s to import: only when asked for
        jit = settings["jit"]
        kwargs = {"jac": system.numeric(system.jacobian_numeric_function(jit), p)} \
            if implicit else {}
        fun = system.numeric(system.rhs_function(jit), p)
        budget, limit = settings.get("max_steps"), settings.get("time_limit")
        X, k, steps, in_interval, failure = [np.asarray(x0, dtype=float)], 1, 0, 0, None
        with np.errstate(all="ignore"):      # a blow-up is reported below, not warned
            solver = getattr(scipy.integrate, name)(
                fun, grid[0], x0, grid[-1], rtol=settings["rtol"], atol=settings["atol"],
                **kwargs)
            while k < len(grid):
                message = solver.step()
                steps, in_interval = steps + 1, in_interval + 1
                if solver.status == "failed":
                    failure = message
                    break
                if grid[k] <= solver.t:
                    dense = solver.dense_output()
                    while k < len(grid) and grid[k] <= solver.t:
                        X.append(dense(grid[k]))
                        k, in_interval = k + 1, 0
                    if settings.get("progress"):
                        settings["progress"](float(grid[k - 1]))
                if not np.all(np.isfinite(solver.y)):
                    failure = "the state became non-finite (Inf or NaN)"
                    break
                if budget and in_interval >= budget and k < len(grid):
                    failure = (f"the step budget of {budget} steps per output interval ran "
                               f"out at t = {solver.t:g} s: the problem may be stiff for "
                               f"this method, or the solution blows up")
                    break
                if limit and time.perf_counter() - settings["started"] > limit:
                    failure = "the time limit set for the run was reached"
                    break
        stats = {"steps": steps, "rhs_evaluations": int(solver.nfev),
                 "jacobian_evaluations": int(solver.njev)}
        X, bad = _finite(np.array(X))
        return X, bad or failure, stats
    return run


def _midpoint(system, grid, x0, p, settings):
    from .geometric import Midpoint
    if system.formulation != "tree" or not all(system.asm.regular):
        raise ModelError("method 'midpoint' works in canonical coordinates of a tree of "
                         "angles and distances; this model has kinematic loops or a "
                         "quaternion joint (Spherical, FreeMotion): use 'auto' or 'idas'")
    key = ("midpoint", settings["jit"])
    if key not in system._compiled:
        system._compiled[key] = Midpoint(system, settings["jit"])
    return system._compiled[key].run(grid, x0, p, _steps_per_interval(grid, settings["step"]))


#: method name (case-insensitive) -> Method
METHODS = {
    "auto": Method(None, "cvodes-adams, or cvodes (BDF) when the stiffness test says so; "
                   "idas for models with loops", dae=True),
    "cvodes-adams": Method(_casadi("cvodes", False, linear_multistep_method="adams",
                                   nonlinear_solver_iteration="functional"),
                           "SUNDIALS CVODES, variable-order Adams-Moulton with functional "
                           "iteration: non-stiff, no Jacobian"),
    "cvodes": Method(_casadi("cvodes", True), "SUNDIALS CVODES, variable-order BDF with "
                     "Newton iteration: stiff", newton=True),
    "idas": Method(_casadi("idas", True), "SUNDIALS IDAS, variable-order BDF on the residual "
                   "form: stiff, and the method of models with loops", newton=True, dae=True),
    "rk": Method(_casadi("rk", False), "CasADi's classical Runge-Kutta 4, fixed step",
                 fixed=True),
    "collocation": Method(_casadi("collocation", True),
                          "CasADi's Radau IIA collocation (order 5), fixed step: stiff",
                          fixed=True, newton=True, dae=True),
    "midpoint": Method(_midpoint, "implicit midpoint rule in canonical coordinates, fixed "
                       "step: symplectic, for long undamped runs", fixed=True, newton=True),
    **{m.lower(): Method(_scipy(m), f"scipy solve_ivp {m}", newton=m in ("Radau", "BDF", "LSODA"))
       for m in ("RK45", "DOP853", "Radau", "BDF", "LSODA")},
}


#: the stiffness test of ``auto``: see ``stiffness``
STIFF_HORIZON_STEPS = 1e3
STIFF_RATIO = 10.0


def _jacobian_fd(f, t, x):
    """Central finite differences: 2n evaluations, O(n) each; no O(n^2) symbolic Jacobian."""
    J = np.empty((len(x), len(x)))
    for i in range(len(x)):
        dx = 1e-6 * max(1.0, abs(x[i]))
        e = np.zeros(len(x))
        e[i] = dx
        J[:, i] = (f(t, x + e) - f(t, x - e)) / (2 * dx)
    return J


def stiffness(system, x0, p, t_start, t_end, jit=False):
    """The stiffness test of the ``auto`` method, on the Jacobian at the initial state.

    With λ the eigenvalues of d(xdot)/dx at (t_start, x0), the fastest decay rate is
    σ = max(-Re λ) and the fastest other motion is ω = max(max Re λ, max |Im λ|). The problem
    is stiff when σ (t_end - t_start) > STIFF_HORIZON_STEPS (an explicit or Adams method
    would need over ~10^3 steps for stability alone) and σ > STIFF_RATIO ω (that decay is
    much faster than anything the solution must follow). An undamped mechanism is never stiff by
    this test (its eigenvalues come in ±λ pairs); a hard, heavily damped spring is.

    Returns (stiff, σ, ω).
    """
    J = _jacobian_fd(system.numeric(system.rhs_function(jit), p), t_start, x0)
    lam = np.linalg.eigvals(J) if J.size else np.zeros(0)
    if not np.all(np.isfinite(lam)) or lam.size == 0:
        return False, 0.0, 0.0
    sigma = float(max(0.0, np.max(-lam.real)))
    omega = float(max(0.0, np.max(lam.real), np.max(np.abs(lam.imag))))
    stiff = sigma * (t_end - t_start) > STIFF_HORIZON_STEPS and sigma > STIFF_RATIO * omega
    return stiff, sigma, omega


@contextlib.contextmanager
def _solver_output():
    """What the integrators print (SUNDIALS' failure chatter, CasADi's warnings) captured
    instead of reaching the user's terminal: CasADi writes through Python's sys.stdout and
    sys.stderr, plain C code to file descriptors 1 and 2; both are caught. The text is in the
    yielded dict's "text" afterwards."""
    box = {"text": ""}
    python_level = io.StringIO()
    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    try:
        saved = [os.dup(1), os.dup(2)]
    except OSError:                            # no file descriptors to redirect
        saved = None
    with tempfile.TemporaryFile() as sink, contextlib.redirect_stdout(python_level), \
            contextlib.redirect_stderr(python_level):
        if saved:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
        try:
            yield box
        finally:
            if saved:
                ctypes.CDLL(None).fflush(None)
                os.dup2(saved[0], 1)
                os.dup2(saved[1], 2)
                for fd in saved:
                    os.close(fd)
                sink.seek(0)
            box["text"] = python_level.getvalue() + (
                sink.read().decode("utf-8", "replace") if saved else "")


def _last_words(text):
    """The solver's own last line (what it said when it failed), shortened."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    if not lines:
        return ""
    line = lines[-1]
    return line if len(line) <= 200 else line[:197] + "..."


def simulate(model, t_end=None, n_points=None, method=None, rtol=None, atol=None,
             params=None, t_start=0.0, step=None, jit=None, max_steps=None,
             time_limit=None, progress=None):
    """Integrate ``model`` (a Model or a compiled System) and record its probes.

    Settings not given come from the model's ``simulation`` block, then from DEFAULTS.

    Parameters
    ----------
    model : Model or System
    t_end : float
        End time [s]; the output grid has ``n_points`` equally spaced points from ``t_start``.
    method : str
        One of METHODS (``kinetwork methods`` lists them). ``auto`` (default): CVODES Adams,
        or CVODES BDF when ``stiffness`` finds the problem stiff at the start, or when Adams
        fails on it.
    rtol, atol : float
        Tolerances of the variable-step methods.
    step : float, optional
        Largest step [s] of the fixed-step methods (``rk``, ``collocation``, ``midpoint``);
        default: the output spacing.
    params : dict, optional
        Model parameter values for this run; no recompilation.
    jit : bool, optional
        Compile the right-hand side to C (cached on disk, see ``kinetwork.solver.jit``).
        Default: when a C compiler is found and ``KINETWORK_JIT`` is not 0.
    max_steps : int, optional
        Step budget per output interval of the variable-step methods (SUNDIALS' mxstep;
        counted here for scipy's): when it runs out the run stops with a SimulationError.
    time_limit : float, optional
        Wall-clock limit [s] of the integration; the run stops with a SimulationError
        holding what it computed (CasADi methods read the clock between chunks of output
        intervals, scipy's at every step; the midpoint rule ignores it).
    progress : callable, optional
        Called with the simulated time reached, now and then (CasADi methods then run in
        chunks of output intervals); ``kinetwork run`` draws a progress bar with it.

    Returns
    -------
    Results
        ``results.settings["method"]`` is the method that ran; ``results.stats`` its counts.

    Raises
    ------
    ModelError
        Bad settings or parameters.
    SimulationError
        The integration failed; ``err.results`` holds the results up to ``err.t_reached``.
    """
    system = model if isinstance(model, System) else model.compile()
    given = {"t_end": t_end, "n_points": n_points, "method": method, "rtol": rtol,
             "atol": atol, "step": step}
    settings = {**DEFAULTS, **system.model.simulation,
                **{k: v for k, v in given.items() if v is not None}}
    problems = [m for k in DEFAULTS if settings[k] is not None
                and (m := check_setting(k, settings[k]))]
    if not problems and settings["t_end"] <= t_start:
        problems.append(f"simulation.t_end: must be > t_start = {t_start}, "
                        f"got {settings['t_end']}")
    for name, value, kind in (("max_steps", max_steps, int), ("time_limit", time_limit, float)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))
                                  or value <= 0 or (kind is int and int(value) != value)):
            problems.append(f"{name}: must be a positive {'integer' if kind is int else 'number'}"
                            f", got {value!r}")
    if problems:
        raise ModelError(problems)
    key = settings["method"].lower()
    if key not in METHODS:
        raise ModelError(f"method {settings['method']!r}: unknown{suggest(key, METHODS)}; "
                         f"methods are {', '.join(METHODS)}")
    if system.n_algebraic and not METHODS[key].dae:
        raise ModelError(
            f"method {settings['method']!r} integrates ODEs only, and {system.model.name!r} "
            f"has kinematic loops whose dependent coordinates are algebraic variables; use "
            f"{', '.join(k for k, m in METHODS.items() if m.dae)}, or compile the model with "
            f"loops='projected' or loops='baumgarte' (ODEs)")
    p = system.param_vector(params)        # checks the overrides once for the whole run
    x0 = np.concatenate(system.initial_full_p(p))
    grid = np.linspace(t_start, settings["t_end"], int(settings["n_points"]))
    settings.update(max_steps=max_steps, time_limit=time_limit, progress=progress,
                    started=time.perf_counter())
    settings.update(jit=_jit.enabled(jit) and system.n_states > 0, t_start=t_start,
                    n_points=int(settings["n_points"]),
                    rtol=float(settings["rtol"]), atol=float(settings["atol"]))
    system.jit_stats.clear()
    stats = {}
    with _solver_output() as said:
        if not system.n_states:       # everything welded to the ground: nothing to integrate
            X, failure, key = np.tile(x0, (len(grid), 1)), None, "none"
        elif key == "auto":
            X, failure, stats, key = _auto(system, grid, x0, p, settings)
        else:
            X, failure, stats = METHODS[key].run(system, grid, x0, p, settings)
    if said["text"].strip():
        stats["solver_output"] = said["text"]
    stats.update(jit=settings["jit"], **system.jit_stats)
    t = grid[:len(X)]
    X = system.polish(X, p)
    t_end = settings["t_end"]
    outputs = system.outputs_p(t, X, p, settings["jit"]) if len(t) else np.zeros((0, 0))
    results = Results(t, X, system.state_names + system.algebraic_names, outputs,
                      system.signal_names, system.signal_sizes, system.signal_units, stats=stats,
                      state_units=system.state_units + system.algebraic_units,
                      settings={"t_start": t_start, "t_end": t_end,
                                "n_points": settings["n_points"], "method": key,
                                "rtol": settings["rtol"], "atol": settings["atol"],
                                "step": settings["step"], "jit": settings["jit"],
                                "max_steps": max_steps, "time_limit": time_limit,
                                "params": dict(params or {})},
                      probe_targets=system.probe_targets)
    if failure is not None:
        reached = float(t[-1]) if len(t) else float(t_start)
        said = _last_words(stats.get("solver_output", ""))
        raise SimulationError(f"{key} failed after t = {reached:g} s (of {t_end:g} s): "
                              f"{failure}" + (f" (the solver said: {said})" if said else ""),
                              results=results, t_reached=reached, reason=failure)
    return results


def _auto(system, grid, x0, p, settings):
    """The default: Adams unless the stiffness test (or a failure of Adams) says BDF.

    A model without damping (generalized forces independent of the speeds) is conservative
    up to its time-dependent drives: its eigenvalues come in ±λ pairs and it is never stiff by
    the test, so the test (an eigenvalue problem of 2n x 2n) is not run.
    """
    if system.n_algebraic:
        X, failure, stats = METHODS["idas"].run(system, grid, x0, p, settings)
        return X, failure, {**stats, "loops": system.formulation_note}, "idas"
    why = {"stiff": False, "damped": system.damped}
    if system.damped:
        stiff, sigma, omega = stiffness(system, x0, p, grid[0], grid[-1], settings["jit"])
        why.update(stiff=bool(stiff), decay_rate=sigma, motion_rate=omega)
    if not why["stiff"]:
        X, failure, stats = METHODS["cvodes-adams"].run(system, grid, x0, p, settings)
        if failure is None:
            return X, None, {**stats, **why}, "cvodes-adams"
        why["adams_failure"] = failure
    X, failure, stats = METHODS["cvodes"].run(system, grid, x0, p, settings)
    return X, failure, {**stats, **why}, "cvodes"
