"""Equilibria and trim: a state where every rate vanishes (speeds, accelerations, the rates
of controller states), optionally solving for chosen inputs or parameters instead of chosen
states, by Newton's method on CasADi's exact Jacobian.
"""

import weakref

import casadi as ca
import numpy as np

from ..equations.modes import operating_modes
from ..equations.system import System
from ..errors import ModelError, SimulationError
from ..solver.plan import lifted_model
from ..util import quote, suggest
from .channels import plant

#: values a REPL echo of an Equilibrium shows before "... (n more)"
REPR_VALUES = 8
#: System -> {free parameter positions: the residual and its Jacobians' Function}
_RESIDUALS = weakref.WeakKeyDictionary()


class Equilibrium:
    """A state at rest: ``X`` the full state (x, then the dependent coordinates of loops),
    ``state`` the same by name, ``inputs`` the inputs' values, ``params`` the parameters
    solved for, ``residual`` the largest |rate| left, ``iterations`` the evaluations it took,
    ``undetermined`` the states the
    equilibrium leaves free (a rotor with nothing holding its angle)."""

    def __init__(self, t, X, names, inputs, params, residual, iterations, undetermined):
        self.t, self.X = t, X
        self.state = dict(zip(names, X.tolist()))
        self.inputs, self.params = inputs, params
        self.residual, self.iterations = residual, iterations
        self.undetermined = undetermined

    def __repr__(self):
        # a REPL echo stays a line or two: a robot's 42 states are summarised, not listed
        values = [*self.inputs.items(), *self.params.items(), *self.state.items()]
        shown = ", ".join(f"{k} = {v:.6g}" for k, v in values[:REPR_VALUES])
        more = f", ... ({len(values) - REPR_VALUES} more)" if len(values) > REPR_VALUES else ""
        return f"<Equilibrium {shown}{more}>"


def equilibrium(model, at=None, inputs=(), free=(), fix=None, params=None, t=0.0,
                tol=1e-10, max_iter=100):
    """A state where every rate of ``model`` vanishes: dx/dt = 0 (and the loops closed).

    Parameters
    ----------
    model : Model or System
    at : None, array, dict
        Where Newton starts (as ``kn.linearize``'s ``at``): default the initial state.
    inputs : list of str, or dict
        Input channels (open signal inputs ``"motor.u"``, ``signals.Input`` blocks), held at
        their operating values, or at the values a dict gives, unless freed.
    free : list of str
        Inputs or parameters to solve for (trim): each frees one equation, so as many states
        must be held in ``fix``. A parameter is a model parameter or a component parameter by
        path (``"spring.c"``, lifted to a model parameter once, see ``kn.simulate``).
    fix : dict, optional
        {state name: value} held; the other states are solved for.
    params : dict, optional
        Parameter values (model parameters, or component parameters by path), the starting
        values of freed ones.
    t : float
        Time at which the rates are taken (for sources given in time).
    tol : float
        Largest |rate| accepted (in the states' units per second).

    Raises
    ------
    ModelError
        Unknown names, or not as many unknowns as equations.
    SimulationError
        Newton does not converge: no equilibrium near ``at`` (or none at all), with the
        rates that stay and the state reached.
    """
    given = dict(inputs) if isinstance(inputs, dict) else {}
    names = list(inputs) if not isinstance(inputs, str) else [inputs]
    free = [free] if isinstance(free, str) else list(free)
    flat = (model.model if isinstance(model, System) else model).flat()
    # a freed input need not be listed in inputs as well; a freed or given component
    # parameter by path ("spring.c") is lifted to a model parameter
    names += [k for k in free if k not in flat.parameters and k not in names
              and (k in flat.components or _is_input(flat, k))]
    lifted = [k for k in [*free, *(params or {})] if k not in names]
    model, aliases = lifted_model(model, lifted)
    params = {aliases.get(k, k): v for k, v in (params or {}).items()}
    free = [aliases.get(k, k) for k in free]
    shown = {v: k for k, v in aliases.items()}
    pl = plant(model, names)
    s = pl.system
    p = pl.param_vector(params, given, t)
    states = s.state_names + s.algebraic_names
    fix = dict(fix or {})
    problems = [f"fix: {quote(k)} is not a state{suggest(k, states)}" for k in fix
                if k not in states]
    where = []
    for name in free:
        if name in pl.inputs:
            where.append(pl.input_index[pl.inputs.index(name)])
        elif name in s.param_names and name in pl.source.param_names:
            where.append(s.param_names.index(name))
        else:
            problems.append(f"free: {quote(name)} is neither an input nor a model parameter"
                            f"{suggest(name, pl.inputs + pl.source.param_names)}")
    if problems:
        raise ModelError(problems)
    n = len(states)
    held = [states.index(k) for k in fix]
    unknown = [k for k in range(n) if k not in held]
    if len(unknown) + len(where) != n:
        raise ModelError(f"equilibrium: {len(unknown) + len(where)} unknowns ({len(unknown)} "
                         f"states, {len(where)} freed) for {n} equations (every rate, and the "
                         f"loop closure); fix as many states as you free inputs or parameters")
    _, X = pl.operating_state(at, p)
    X = X.copy()
    for k, v in fix.items():
        X[states.index(k)] = float(v)
    X = operating_modes(s, t, X, p, check=False)     # frictions at rest: stuck
    f = _residual(s, tuple(where))
    v0 = np.concatenate([X[unknown], p[where]])

    def evaluate(v):
        X[unknown], p[where] = v[:len(unknown)], v[len(unknown):]
        R, JX, Jp = (np.asarray(a, dtype=float) for a in f(t, X, p))
        return R.ravel(), np.hstack([JX[:, unknown], Jp])

    _, R, J, norm, it = _newton(evaluate, v0, tol, max_iter)
    if norm > tol and n:
        # Newton's steps get stuck where a rate is flat in some direction (a controller's
        # output at its limit): a trust region on |R|^2 (scipy's trf) passes there
        _, R, J, norm, more = _trust_region(evaluate, v0, tol, max_iter)
        it += more
    if norm <= tol:
        operating_modes(s, t, X, p)          # a stuck friction holds within its limit
        return _done(pl, t, X, p, states, where, norm, it, J, unknown, shown)
    worst = np.argsort(-np.abs(R))[:3] if n else []
    rates = ", ".join(f"d({states[k]})/dt = {R[k]:.3g}" if k < s.n_states else
                      f"closure of {states[k]}: {R[k]:.3g}" for k in worst)
    raise SimulationError(
        f"no equilibrium of {s.model.name!r} found: Newton and a trust region stalled after "
        f"{it} evaluations with {rates} left (largest |rate| {norm:.3g}, asked {tol:g}); "
        f"there may be none (a load nothing can hold), or none near the start: give another "
        f"'at'",
        reason="no equilibrium")


def _is_input(flat, name):
    """Whether ``name`` ("motor.u") is a signal input of a component of ``flat``."""
    comp, _, port = name.rpartition(".")
    spec = getattr(flat.components.get(comp), "ports", {}).get(port)
    return spec is not None and spec.domain == "signal_in"


def _newton(evaluate, v, tol, max_iter):
    """Newton's method, each step halved until the largest |rate| falls: (v, R, J, that
    largest |rate|, evaluations)."""
    R, J = evaluate(v)
    norm = np.max(np.abs(R)) if R.size else 0.0
    count = 1
    for _ in range(max_iter):
        if not np.isfinite(norm) or norm <= tol:
            break
        step = np.linalg.lstsq(J, -R, rcond=None)[0]
        for _ in range(30):
            trial = v + step
            with np.errstate(all="ignore"):
                Rt, Jt = evaluate(trial)
            count += 1
            nt = np.max(np.abs(Rt))
            if np.isfinite(nt) and nt < norm:
                break
            step = step / 2
        else:
            R, J = evaluate(v)           # X and p back at the best point
            break
        v, R, J, norm = trial, Rt, Jt, nt
    return v, R, J, norm, count


def _trust_region(evaluate, v0, tol, max_iter):
    """scipy's trust-region least squares on the rates, with the exact Jacobian: (v, R, J,
    largest |rate|, evaluations)."""
    from scipy.optimize import least_squares
    try:
        out = least_squares(lambda v: evaluate(v)[0], v0, jac=lambda v: evaluate(v)[1],
                            method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15,
                            max_nfev=20 * max_iter)
    except ValueError:                    # not finite at the start
        R, J = evaluate(v0)
        return v0, R, J, np.inf, 1
    R, J = evaluate(out.x)
    return out.x, R, J, float(np.max(np.abs(R))), int(out.nfev)


def _done(pl, t, X, p, states, where, norm, iterations, J, unknown, shown):
    s = pl.system
    # directions Newton leaves free: the null space of the Jacobian in the unknowns
    sv, vec = np.linalg.svd(J)[1:] if J.size else (np.zeros(0), np.zeros((0, 0)))
    scale = max(sv.max() if sv.size else 0.0, 1.0)
    null = vec[np.sum(sv > 1e-9 * scale):] if J.shape[1] else vec
    loose = sorted({unknown[k] for row in null for k in np.flatnonzero(np.abs(row[:len(unknown)])
                                                                       > 1e-6)})
    return Equilibrium(t, X.copy(), states, pl.input_values(p),
                       {shown.get(s.param_names[k], s.param_names[k]): float(p[k])
                        for k in where if k not in pl.input_index}, float(norm), iterations,
                       [states[k] for k in loose])


def _residual(system, where):
    """(t, X, p) -> (the rates and the closure, their Jacobian in X, in p[where])."""
    cache = _RESIDUALS.setdefault(system, {})
    if where not in cache:
        eq, a = system.eq, system.asm
        X = ca.vertcat(eq.x, eq.z)
        R = ca.vertcat(eq.ode, eq.alg)
        w = ca.vertcat(*[a.p[k] for k in where]) if where else ca.SX(0, 1)
        cache[where] = ca.Function("equilibrium", [a.t, X, a.p],
                                   [ca.densify(R), ca.densify(ca.jacobian(R, X)),
                                    ca.densify(ca.jacobian(R, w))])
    return cache[where]
