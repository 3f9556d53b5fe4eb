"""Parameter sensitivities along a trajectory: d(probe)/d(parameter) at every output time,
from the forward sensitivities CasADi's integrators (CVODES, IDAS) compute when a Function
through them is differentiated; no finite differences.

The initial state follows the parameters too: exactly, by its own expressions, for a model
without loops; with loops the dependent coordinates follow the closure (the implicit
function theorem through a rootfinder), the independent ones are held at their start.
"""

import casadi as ca
import numpy as np

from ..equations.system import System
from ..errors import ModelError, SimulationError
from ..util import quote, suggest
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
                rtol=None, atol=None, t=None):
    """d(output)/d(parameter) along the trajectory of ``model``.

    Parameters
    ----------
    model : Model or System
    params : list of str
        Model parameters to differentiate with respect to.
    t_end, n_points : float, int
        The output grid from 0 (default: the model's simulation settings); or ``t``, the
        output times themselves (increasing, from 0).
    outputs : list of str, optional
        Probe quantities or states (as ``kn.linearize``'s); default every probe quantity.
    values : dict, optional
        Model parameter values at which to differentiate.
    rtol, atol : float
        Tolerances of the integration (its sensitivities are controlled to them too).

    Returns
    -------
    Sensitivity
    """
    system = model if isinstance(model, System) else model.compile()
    settings = {**DEFAULTS, **{k: v for k, v in system.model.simulation.items()
                               if k in DEFAULTS}}
    grid = _grid(t, t_end if t_end is not None else settings["t_end"],
                 n_points if n_points is not None else settings["n_points"])
    names, units, rows = output_channels(system, outputs)
    index = param_index(system, params)
    p = system.param_vector(values)
    f = trajectory(system, index, rows, grid, rtol or settings["rtol"], atol or settings["atol"])
    Y, J = evaluate(f, system, p, index)
    return Sensitivity(grid, names, units, [system.param_names[k] for k in index], Y,
                       J.reshape(len(grid), len(rows), len(index)))


def param_index(system, params):
    """Positions in p of the named model parameters (ModelError naming unknown ones)."""
    if isinstance(params, str):
        params = [params]
    params = list(params)
    bad = [k for k in params if k not in system.param_names]
    if bad or not params:
        raise ModelError([f"params: {quote(k)} is not a model parameter"
                          f"{suggest(k, system.param_names)}; parameters are "
                          f"{', '.join(system.param_names) or 'none'}" for k in bad] or
                         ["params: name at least one model parameter"])
    if len(set(params)) != len(params):
        raise ModelError(f"params: named twice in {params}")
    return [system.param_names.index(k) for k in params]


def evaluate(f, system, p, index):
    """(outputs (n_t, n_out), Jacobian (n_t * n_out, n_params)) of a ``trajectory``
    Function at the parameter vector p."""
    p = np.asarray(p, dtype=float)
    x0, z0 = system.initial_full_p(p)
    try:
        Y, J = f(p[index], p, x0, z0)
    except RuntimeError as exc:
        raise SimulationError(f"the integration of the sensitivities failed: "
                              f"{str(exc).splitlines()[-1][:300]}",
                              reason="integration of the sensitivities failed") from None
    Y, J = np.asarray(Y, dtype=float), np.asarray(J, dtype=float)
    if not (np.all(np.isfinite(Y)) and np.all(np.isfinite(J))):
        raise SimulationError("the outputs or their sensitivities are not finite",
                              reason="not finite")
    # Y is (n_out, n_t) column-major: rows of J follow vec(Y), time-major after the .T
    n_out, n_t = Y.shape
    J = J.reshape(n_t, n_out, -1)
    return Y.T, J.reshape(n_t * n_out, -1)


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


def trajectory(system, index, rows, grid, rtol, atol):
    """The Function (p[index], p, x0, z0) -> (outputs on the grid (n_rows, n_t), their
    Jacobian in p[index]): an integrator whose forward sensitivities CasADi derives. x0 and
    z0 are the initial state at p (``System.initial_full_p``), which a model without loops
    replaces by its start's own expressions in p (so that they are differentiated too)."""
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
    dae = {"x": eq.x, "z": eq.z, "p": a.p, "t": a.t, "ode": eq.ode, "alg": eq.alg}
    if not system.n_algebraic:
        dae = {k: v for k, v in dae.items() if k not in ("z", "alg")}
    plugin = "idas" if system.n_algebraic else "cvodes"
    opts = {"abstol": atol, "reltol": rtol, "max_num_steps": 100000,
            "show_eval_warnings": False}
    F = ca.integrator("sensitivity", plugin, dae, float(grid[0]), grid[1:].tolist(), opts)
    res = F(x0=X0, z0=Z0, p=P) if system.n_algebraic else F(x0=X0, p=P)
    XF = ca.horzcat(X0, res["xf"])
    if system.n_algebraic:
        XF = ca.vertcat(XF, ca.horzcat(Z0, res["zf"]))
    n = len(grid)
    Y = system.f_out.map(n)(ca.DM(grid).T, XF, ca.repmat(P, 1, n)) if system.signals \
        else ca.MX(0, n)
    picked = ca.vertcat(*[XF[-1 - r, :] if r < 0 else Y[r, :] for r in rows])
    return ca.Function("trajectory", [w, pm, x0, z0],
                       [picked, ca.jacobian(ca.vec(picked), w)])


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
