"""simulate(): integrate a model with CasADi's integrators or scipy's, looked up in METHODS."""

import casadi as ca
import numpy as np

from ..components.base import suggest
from ..errors import ModelError, SimulationError
from ..graph.model import check_setting
from .results import Results
from .system import System

DEFAULTS = {"t_end": 10.0, "n_points": 1001, "method": "cvodes", "rtol": 1e-6, "atol": 1e-8}


def _casadi(plugin, **options):
    """A CasADi integrator plugin: the whole integration runs in compiled code."""
    def run(system, grid, x0, p, rtol, atol):
        integ = system.integrator(plugin, grid, rtol, atol, options)
        try:
            out = integ(x0=x0, p=p)
        except RuntimeError as exc:
            X, reason = _casadi_partial(system, plugin, grid, x0, p, rtol, atol, options, exc)
            return X, reason, {}
        X = np.vstack([x0, np.asarray(out["xf"]).T])
        stats = integ.stats()
        return X, None, {"steps": int(stats["nsteps"]), "rhs_evaluations": int(stats["nfevals"]),
                         "jacobian_evaluations": int(stats["n_call_jacF"])}
    return run


def _casadi_partial(system, plugin, grid, x0, p, rtol, atol, options, exc):
    """After a failure, step interval by interval to keep everything computed before it."""
    X = [x0]
    for k in range(len(grid) - 1):
        integ = system.integrator(plugin, grid[k:k + 2], rtol, atol,
                                  {**options, "disable_internal_warnings": True}, cache=False)
        try:
            X.append(np.asarray(integ(x0=X[-1], p=p)["xf"]).ravel())
        except RuntimeError as step_exc:
            return np.array(X), _reason(str(step_exc) or str(exc))
    return np.array(X), _reason(str(exc))


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
    """A scipy solve_ivp method fed by the compiled CasADi right-hand side and Jacobian."""
    implicit = name in ("Radau", "BDF", "LSODA")

    def run(system, grid, x0, p, rtol, atol):
        from scipy.integrate import solve_ivp    # 0.4 s to import: only when asked for
        kwargs = {"jac": system.numeric(system.jacobian_function(), p)} if implicit else {}
        fun = system.numeric(system.f_rhs, p)
        with np.errstate(all="ignore"):      # a blow-up is reported below, not warned
            sol = solve_ivp(fun, (grid[0], grid[-1]), x0, method=name, t_eval=grid,
                            rtol=rtol, atol=atol, **kwargs)
        X = sol.y.T
        stats = {"rhs_evaluations": int(sol.nfev), "jacobian_evaluations": int(sol.njev)}
        good = np.all(np.isfinite(X), axis=1)
        if not good.all():
            return X[:int(np.argmin(good))], "the state became non-finite (Inf or NaN)", stats
        return X, (sol.message if sol.status < 0 else None), stats
    return run


#: method name (case-insensitive) -> runner
METHODS = {
    "cvodes": _casadi("cvodes"),
    "idas": _casadi("idas"),
    **{m.lower(): _scipy(m) for m in ("RK45", "DOP853", "Radau", "BDF", "LSODA")},
}


def simulate(model, t_end=None, n_points=None, method=None, rtol=None, atol=None,
             params=None, t_start=0.0):
    """Integrate ``model`` (a Model or a compiled System) and record its probes.

    Settings not given come from the model's ``simulation`` block, then from DEFAULTS.

    Parameters
    ----------
    model : Model or System
    t_end : float
        End time [s]; the output grid has ``n_points`` equally spaced points from ``t_start``.
    method : str
        One of METHODS: ``cvodes`` (default), ``idas``, or scipy's ``RK45``, ``DOP853``,
        ``Radau``, ``BDF``, ``LSODA``.
    rtol, atol : float
        Integrator tolerances.
    params : dict, optional
        Model parameter values for this run; no recompilation.

    Returns
    -------
    Results

    Raises
    ------
    ModelError
        Bad settings or parameters.
    SimulationError
        The integration failed; ``err.results`` holds the results up to ``err.t_reached``.
    """
    system = model if isinstance(model, System) else model.compile()
    given = {"t_end": t_end, "n_points": n_points, "method": method, "rtol": rtol,
             "atol": atol}
    settings = {**DEFAULTS, **system.model.simulation,
                **{k: v for k, v in given.items() if v is not None}}
    t_end, n_points, method, rtol, atol = (settings[k] for k in DEFAULTS)
    problems = [m for k in DEFAULTS if (m := check_setting(k, settings[k]))]
    if not problems and t_end <= t_start:
        problems.append(f"simulation.t_end: must be > t_start = {t_start}, got {t_end}")
    if problems:
        raise ModelError(problems)
    key = method.lower()
    if key not in METHODS:
        raise ModelError(f"method {method!r}: unknown{suggest(key, METHODS)}; methods are "
                         f"{', '.join(METHODS)}")
    p = system.param_vector(params)        # checks the overrides once for the whole run
    x0 = system.initial_state_p(p)
    grid = np.linspace(t_start, t_end, int(n_points))
    if system.n_states:
        X, failure, stats = METHODS[key](system, grid, x0, p, float(rtol), float(atol))
    else:                           # everything welded to the ground: nothing to integrate
        X, failure, stats = np.zeros((len(grid), 0)), None, {}
    t = grid[:len(X)]
    results = Results(t, X, system.state_names, system.outputs_p(t, X, p) if len(t) else
                      np.zeros((0, 0)), system.signal_names, system.signal_sizes,
                      system.signal_units, stats=stats,
                      state_units=system.state_units,
                      settings={"t_start": t_start, "t_end": t_end, "n_points": int(n_points),
                                "method": key, "rtol": rtol, "atol": atol,
                                "params": dict(params or {})},
                      probe_targets=system.probe_targets)
    if failure is not None:
        reached = float(t[-1]) if len(t) else float(t_start)
        raise SimulationError(f"{key} failed after t = {reached:g} s (of {t_end:g} s): "
                              f"{failure}", results=results, t_reached=reached)
    return results

