"""Parameter sensitivities along a trajectory: d(probe)/d(parameter) at every output time,
from the forward sensitivities CasADi's integrators (CVODES, IDAS) compute when a Function
through them is differentiated; no finite differences. The integrator is the model's
integration plan's (``kinetwork.solver.plan``): its method, its tolerances.

The initial state follows the parameters too: exactly, by its own expressions, for a model
without loops; with loops the dependent coordinates follow the closure (the implicit
function theorem through a rootfinder), the independent ones are held at their start.
"""

import casadi as ca
import numpy as np

from ..equations.system import System
from ..errors import ModelError, SimulationError
from ..solver.casadi_clock import cheap
from ..solver.plan import Plan
from ..util import suggest
from .channels import output_channels

DEFAULTS = {"t_end": 10.0, "n_points": 1001, "rtol": 1e-8, "atol": 1e-10}


class Sensitivity:
    """Outputs and their derivatives with respect to parameters on a time grid.

    ``values`` (n_t, n_outputs), ``S`` (n_t, n_outputs, n_params): S[k, i, j] =
    d output_i / d param_j at t[k]. ``sens[output, param]`` is one column of S,
    ``sens[output]`` one of values.
    """

    def __init__(self, t, outputs, units, params, values, S):
        self.t, self.output_names, self.output_units = t, outputs, units
        self.param_names, self.values, self.S = params, values, S

    def __getitem__(self, key):
        if isinstance(key, tuple):
            out, par = key
            if par not in self.param_names:
                raise KeyError(f"{par!r} is not a parameter of these sensitivities"
                               f"{suggest(par, self.param_names)}")
            return self.S[:, self._row(out), self.param_names.index(par)]
        return self.values[:, self._row(key)]

    def _row(self, name):
        if name not in self.output_names:
            raise KeyError(f"{name!r} is not an output{suggest(name, self.output_names)}")
        return self.output_names.index(name)

    def __repr__(self):
        return (f"<Sensitivity of {len(self.output_names)} outputs to "
                f"{', '.join(self.param_names)} at {len(self.t)} times>")


def sensitivity(model, params, t_end=None, n_points=None, outputs=None, values=None,
                rtol=None, atol=None, t=None, method=None, jit=None):
    """d(output)/d(parameter) along the trajectory of ``model``.

    The trajectory is integrated by the model's integration plan (``kinetwork.solver.plan``):
    the method ``kn.simulate`` would take (``auto``: Adams, or BDF when the stiffness test
    says so, BDF again when Adams fails), with the same mapping of the tolerance asked to the
    solver's, so that rtol means for the values and their sensitivities what it means for a
    run; CasADi derives the forward sensitivities of that integrator, their errors controlled
    with the states'.

    Parameters
    ----------
    model : Model or System
    params : list of str
        Parameters to differentiate with respect to: model parameters, or component
        parameters by path (``"spring.c"``, lifted to model parameters once, see
        ``kn.simulate``).
    t_end, n_points : float, int
        The output grid from 0 (default: the model's simulation settings); or ``t``, the
        output times themselves (increasing, from 0).
    outputs : list of str, optional
        Probe quantities or states (as ``kn.linearize``'s); default every probe quantity.
    values : dict, optional
        Parameter values at which to differentiate (numbers, or numbers with a unit).
    rtol, atol : float
        Tolerances (default: the model's settings, else 1e-8 and 1e-10).
    method : str, optional
        A CasADi method (``auto``, ``cvodes``, ``cvodes-adams``, ``idas``, ``rk``,
        ``collocation``): the others have no sensitivities to give.

    Returns
    -------
    Sensitivity
    """
    names = _names(params)
    plan = analysis_plan(model, names + list(values or {}), t, t_end, n_points, rtol, atol, method,
                 jit)
    system = plan.system
    out_names, units, rows = output_channels(system, outputs)
    index = param_index(plan, names)
    p = plan.vector(values)
    f = Trajectory(plan, index, rows)
    Y, J = f.evaluate(p)
    return Sensitivity(plan.grid, out_names, units, names, Y,
                       J.reshape(len(plan.grid), len(rows), len(index)))


def analysis_plan(model, names, t, t_end, n_points, rtol, atol, method, jit=None):
    """The integration plan of a sensitivity or a fit: the model's settings, with this
    module's DEFAULTS where it has none."""
    simulation = getattr(model.model if isinstance(model, System) else model, "simulation", {})
    settings = {**DEFAULTS, **{k: v for k, v in simulation.items() if k in DEFAULTS}}
    given = {"rtol": rtol, "atol": atol, "method": method}
    settings.update({k: v for k, v in given.items() if v is not None})
    grid = _grid(t, t_end if t_end is not None else settings["t_end"],
                 n_points if n_points is not None else settings["n_points"])
    settings.pop("t_end")
    settings.pop("n_points")
    return Plan(model, names=names, grid=grid, jit=jit, **settings)


def _grid(t, t_end, n_points):
    if t is not None:
        grid = np.asarray(t, dtype=float).ravel()
    else:
        if not (isinstance(n_points, (int, np.integer)) and n_points >= 2):
            raise ModelError(f"n_points: must be an integer >= 2, got {n_points!r}")
        grid = np.linspace(0.0, float(t_end), int(n_points))
    if len(grid) < 2 or grid[0] != 0.0 or np.any(np.diff(grid) <= 0) or \
            not np.all(np.isfinite(grid)):
        raise ModelError("t: the output times must start at 0 and increase (at least two)")
    return grid


def _refuse_events(system, grid):
    """A ModelError when the run over ``grid`` meets events (``kinetwork.solver.events``),
    which this one integration of the sensitivities does not stop at: its answer would be
    the law of one side carried past them."""
    from ..solver.schedule import Schedule
    rel = system.relations
    if rel is None:
        return
    times = Schedule(rel, system.param_vector(), grid[0], grid[-1]).times
    if len(rel.state) or len(times):
        what = f"a relation on the states, {rel.text(rel.state[0])}" if len(rel.state) \
            else f"time events at {', '.join(f'{t:g}' for t in times[:4])} s"
        raise ModelError(f"{system.model.name!r} has events in this run ({what}), which the "
                         f"integration of sensitivities does not stop at yet: differentiate "
                         f"runs of kn.simulate instead (central differences), which do")


def _names(params):
    if isinstance(params, str):
        params = [params]
    params = list(params)
    if not params:
        raise ModelError("params: name at least one parameter")
    if len(set(params)) != len(params):
        raise ModelError(f"params: named twice in {params}")
    return params


def param_index(plan, params):
    """Positions in p of the named parameters (ModelError naming unknown ones)."""
    problems, index = [], []
    for k in params:
        try:
            index.append(plan.system.param_names.index(plan.param_name(k)))
        except ModelError as exc:
            problems.extend(exc.problems)
    if problems:
        raise ModelError(problems)
    return index


class Trajectory:
    """The plan's trajectory as a Function of the parameters: (p[index], p, x0, z0) ->
    (outputs ``rows`` on the grid (n_rows, n_t), their Jacobian in p[index]), one for each
    method the plan tries in turn (``auto``: Adams, then BDF); CasADi derives the forward
    sensitivities of each integrator. x0 and z0 are the initial state at p, which a model
    without loops replaces by its start's own expressions in p (so that they are
    differentiated too)."""

    def __init__(self, plan, index, rows):
        self.plan, self.index, self.rows = plan, list(index), list(rows)
        self.functions = {}
        self.method = None              # the one that worked last

    def evaluate(self, p):
        """(outputs (n_t, n_out), Jacobian (n_t * n_out, n_params)) at the parameter
        vector p; a failed integration is the SimulationError ``kn.simulate`` raises for p,
        with its results up to the failure."""
        plan, system = self.plan, self.plan.system
        p = np.asarray(p, dtype=float)
        x0 = plan.start(p)
        nx = system.n_states
        names = [self.method] if self.method else plan.methods(plan.new_run(p, x0))[0]
        failure = None
        for name in names:
            f = self._function(name)
            try:
                with cheap():               # CasADi's clock, as in a run (casadi_clock.py)
                    Y, J = f(p[self.index], p, x0[:nx], x0[nx:])
            except RuntimeError as exc:
                failure = exc
                continue
            Y, J = np.asarray(Y, dtype=float), np.asarray(J, dtype=float)
            if np.all(np.isfinite(Y)) and np.all(np.isfinite(J)):
                self.method = name
                # Y is (n_out, n_t) column-major: rows of J follow vec(Y), time-major
                n_out, n_t = Y.shape
                return Y.T, J.reshape(n_t * n_out, -1)
            failure = RuntimeError("the outputs or their sensitivities are not finite")
        self.method = None
        self._fail(p, failure)

    def _fail(self, p, failure):
        """Raise what ``kn.simulate`` says for p, or, when it runs, that the sensitivities
        failed (its results attached)."""
        try:
            results = self.plan.run(p=p)
        except SimulationError:
            raise
        words = str(failure).strip().splitlines()[-1][:300] if str(failure).strip() else ""
        raise SimulationError(f"the integration of the sensitivities failed, though the "
                              f"trajectory itself runs: {words}", results=results,
                              t_reached=float(self.plan.grid[0]),
                              reason="integration of the sensitivities failed")

    def _function(self, name):
        if name not in self.functions:
            self.functions[name] = _trajectory(self.plan, name, self.index, self.rows)
        return self.functions[name]


def _trajectory(plan, name, index, rows):
    """The Function of ``Trajectory`` for the method ``name``."""
    system, grid = plan.system, plan.grid
    _refuse_events(system, grid)
    eq, a = system.eq, system.asm
    w = ca.MX.sym("w", len(index))
    pm = ca.MX.sym("p", a.p.numel())
    # the full parameter vector, with the differentiated entries the symbols w
    chosen = dict(zip(index, range(len(index))))
    P = ca.vertcat(*[w[chosen[k]] if k in chosen else pm[k] for k in range(a.p.numel())])
    x0 = ca.MX.sym("x0", eq.x.numel())
    z0 = ca.MX.sym("z0", eq.z.numel())
    X0, Z0 = _start(system, P, x0, z0)
    F = plan.differentiable(name)
    pt = ca.vertcat(P, _held(system, grid, P), float(grid[0]))
    res = F(x0=X0, z0=Z0, p=pt) if system.n_algebraic else F(x0=X0, p=pt)
    XF = ca.horzcat(X0, res["xf"])
    if system.n_algebraic:
        XF = ca.vertcat(XF, ca.horzcat(Z0, res["zf"]))
    n = len(grid)
    Y = system.f_out.map(n)(ca.DM(grid).T, XF, ca.repmat(P, 1, n)) if system.signals \
        else ca.MX(0, n)
    picked = ca.vertcat(*[XF[-1 - r, :] if r < 0 else Y[r, :] for r in rows])
    return ca.Function("trajectory", [w, pm, x0, z0],
                       [picked, ca.jacobian(ca.vec(picked), w)])


def _held(system, grid, P):
    """The values the integrators' equations hold the relations at over the run, as
    expressions of P (none without relations): with no event in it (``_refuse_events``),
    the time nodes' values at its middle, nested ones read again until they agree (as
    ``kinetwork.solver.switches`` holds them over a stretch)."""
    rel = system.relations
    if rel is None:
        return ca.MX(0, 1)
    mid = float(grid[0] + grid[-1]) / 2
    state = ca.MX.zeros(system.n_states + system.n_algebraic)
    r = ca.MX.zeros(rel.n)
    for _ in range(len(rel.time) + 1):
        r = rel.f_select(mid, state, ca.vertcat(P, r))
    return r


def _start(system, P, x0, z0):
    """The initial state (X0, Z0) as expressions of the parameters P, given its values x0,
    z0 at P (symbols): a tree's start by its own expressions, a loop's dependent
    coordinates by the closure (a rootfinder, which CasADi differentiates by the implicit
    function theorem), the other states held."""
    eq, a = system.eq, system.asm
    p0 = system.param_vector()
    x_start = system.initial_full_p(p0)[0]
    X0 = x0
    if system.formulation == "tree" and not system.n_algebraic:
        net = a.net
        extra = [ca.SX(s) for s in net.start] if net is not None else []
        given = ca.DM(np.asarray(a.given, dtype=float))
        start = ca.vertcat(given * a.q_start, a.u_start, *extra)
        f = ca.Function("x0", [a.p], [ca.densify(start)])
        if start.numel() == x_start.size and np.allclose(np.asarray(f(p0)).ravel(),
                                                         x_start, rtol=0, atol=1e-12):
            X0 = f(P)
    if not system.n_algebraic:
        return X0, ca.MX(0, 1)
    z, xp = ca.SX.sym("z", system.n_algebraic), ca.SX.sym("xp", eq.x.numel() + a.p.numel())
    g = ca.substitute(eq.alg, ca.vertcat(eq.x, a.p), xp)
    g = ca.substitute(ca.substitute(g, eq.z, z), a.t, ca.SX(0))    # the start is t = 0
    closure = ca.rootfinder("closure", "newton", ca.Function("g", [z, xp], [g]),
                            {"abstol": 1e-14})
    return X0, closure(z0, ca.vertcat(X0, P))
