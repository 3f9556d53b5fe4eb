"""What an FMU of a model carries: its variables, and the CasADi Functions its C is made of.

The FMU runs the System ``kn.simulate`` runs (the same formulation, the same equations), with
``signals.Input`` blocks turned into inputs: each reads a parameter of a twin of the model
(``analysis.channels.driven``), which the FMU sets from its input variable. The equations'
parameter vector in the FMU is the System's: model parameters and inputs, each by its place.

Every Function has the arguments (t, x, z, p): time, the states, the algebraic variables of a
DAE formulation (none for an ODE) and that parameter vector.

- ``kn_rhs``: (xdot, alg, closure, jd): the rates, the algebraic residual and, of the
  projected loops' formulation, how far the projected coordinates are from closing the loops
  and the closure's Jacobian in the dependent speeds (``System.f_dependent``, column-major):
  the FMU stops rather than integrate a loop that no longer closes, or whose Jacobian's
  determinant changed sign or vanished (a dead point of its partition, where ``kn.simulate``
  re-partitions and the FMU cannot);
- ``kn_newton``: (z after one Newton step on the algebraic equations, its residual);
- ``kn_out``: the probe quantities, one column each, as the CSV names them;
- ``kn_start``: the initial state from the parameters, as ``System.initial_state`` gives it
  where that is a closed form (given coordinates, speeds, the blocks' and networks' starts);
  elsewhere the value at the exported parameters (a loop's assembly, a steady state), which
  ``kn_project`` then carries onto the closure of the loops for other lengths;
- ``kn_input``: what each input gives while the environment has not set it: its block's
  ``value`` (an expression in t allowed), so an FMU run without inputs is the model's own run.

A parameter the initial state depends on in a way the FMU cannot follow (checked at export by
changing each parameter a little and comparing with ``System.initial_state``) is listed in
``Content.frozen``: the FMU refuses, naming it, to start with another value of it.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..components.signals import Input
from ..equations.loops import newton
from ..errors import ModelError
from ..expr import casadi_functions, parse
from ..graph import quantities
from ..graph.model import Model
from ..solver.driver import DEFAULTS
from ..solver.methods import METHODS
from ..solver.tolerance import solver_tolerances
from ..analysis.channels import driven
from .units import state_rate_unit

#: relative change of a parameter by which the initial state's dependence on it is checked
PROBE_STEP = 1e-4
#: the initial state the FMU computes agrees with System.initial_state to this (relative)
SAME_START = 1e-9
#: the tolerance the model description proposes to an importer's integrator (FMPy's CVode
#: among them) is the one kinetwork's CVODES gets, this many times tighter, at least
#: TOLERANCE_FLOOR: another implementation of BDF and of its output interpolation then stays
#: within the model's rtol of kn.simulate's answer (fourbar: 4.1e-7 of scale at 1e-13,
#: 5.7e-8 at 1e-14; rolling_wheel: 3.1e-6 at 1e-10, 6.9e-7 at 1e-11)
IMPORTER_MARGIN = 10.0
TOLERANCE_FLOOR = 1e-14
#: Newton steps the FMU takes at most to project a loop's start, or to solve the algebraic
#: variables of a DAE formulation
NEWTON_ITERATIONS = 50


@dataclass
class Variable:
    """One ScalarVariable of the model description."""
    name: str
    causality: str                  # parameter, input, output, local
    variability: str                # tunable, continuous
    initial: str | None             # exact, calculated, or None (inputs)
    start: float | None
    unit: str = ""
    description: str = ""
    derivative: int | None = None   # index (0-based) of the state this is the rate of
    nominal: float | None = None
    min: float | None = None
    max: float | None = None
    dependencies: list | None = None   # 0-based indices of the variables it depends on
    bound_why: str = ""             # where min and max come from


@dataclass
class Content:
    """Everything an FMU of one model is made from."""
    model: Model
    system: object
    name: str
    description: str
    variables: list = field(default_factory=list)
    #: index ranges of ``variables``: states, their rates, parameters, inputs, outputs
    states: range = range(0)
    rates: range = range(0)
    params: range = range(0)
    inputs: range = range(0)
    outputs: range = range(0)
    #: position in the System's parameter vector of each parameter, then of each input
    param_index: list = field(default_factory=list)
    input_index: list = field(default_factory=list)
    p0: np.ndarray = None           # the System's parameter vector as exported
    x0: np.ndarray = None           # initial state as exported
    z0: np.ndarray = None           # algebraic variables as exported
    nominal: np.ndarray = None      # per state: atol / rtol (abstol = rtol * nominal)
    frozen: dict = field(default_factory=dict)   # parameter -> why it cannot change
    functions: dict = field(default_factory=dict)
    projected: bool = False         # kn_project is a projection onto loop closures
    n_dependent: int = 0            # dependent speeds of the loops' partition (0: none)
    clock: bool = False             # a state is time itself: runs start at t = 0
    experiment: dict = field(default_factory=dict)
    solver_rtol: float = 1e-10      # the rtol the FMU's own integrator gets by default
    tolerance: float = 1e-11        # the tolerance the model description proposes
    relations: Held = None          # the relations held between events, and their events
    positive: list = field(default_factory=list)     # per parameter: must be > 0
    nonzero: list = field(default_factory=list)      # per parameter: must not be 0

    @property
    def n_indicators(self):
        return len(self.relations.indicator_node)


@dataclass
class Held:
    """The relations of the equations as the FMU holds them: none today (all lists empty,
    as the System locates no events on its relations and kn.simulate integrates through them);
    the runtime's event handling runs on what these lists name. Each
    node k has a held value p[NP + k]; ``time_node`` lists those switching at instants known
    in closed form (``time_level``: at whole numbers of their indicator), ``indicator_node``
    those located by an event indicator (``indicator_le``: a ``<=``; ``indicator_state``: a
    relation on the states, read again at every event)."""
    n: int = 0
    time_node: list = field(default_factory=list)
    time_level: list = field(default_factory=list)
    indicator_node: list = field(default_factory=list)
    indicator_le: list = field(default_factory=list)
    indicator_state: list = field(default_factory=list)


def content(model, name=None):
    """The Content of ``model`` (a Model, or a System of one): refused with a ModelError that
    names the components and why, when an FMU cannot carry it faithfully."""
    system = None
    if not isinstance(model, Model):
        system, model = model, getattr(model, "model", None)
        if not isinstance(model, Model):
            raise ModelError(f"export_fmu: expected a kn.Model or kn.System, got "
                             f"{type(system).__name__}")
    flat = model.flat()
    loops = _loops_option(system)
    inputs = [n for n, c in flat.components.items() if isinstance(c, Input)]
    if inputs:
        twin, input_params, _ = driven(flat, inputs)
        twin.parameters.update(flat.parameters)
        system = twin.compile(loops=loops) if loops else twin.compile()
    elif system is None:
        system = model.compile()
    _refuse(system, model)
    out = Content(model=model, system=system, name=name or model.name,
                  description=model.description or "")
    sys_names = list(system.param_names)
    p0 = system.param_vector()
    own = [k for k in model.parameters if k in sys_names]
    out.param_index = [sys_names.index(k) for k in own]
    out.input_index = [sys_names.index(d) for d in input_params] if inputs else []
    out.p0 = p0
    x0, z0 = system.initial_full_p(p0)
    out.x0, out.z0 = x0, z0
    settings = {**DEFAULTS, **model.simulation}
    rtol, atol = float(settings["rtol"]), float(settings["atol"])
    out.nominal = np.full(system.n_states, atol / rtol)
    out.solver_rtol = solver_rtol(system, rtol, float(settings["t_end"]))
    out.tolerance = max(out.solver_rtol / IMPORTER_MARGIN, TOLERANCE_FLOOR)
    out.experiment = {"t_end": float(settings["t_end"]),
                      "step": float(settings["t_end"]) / max(int(settings["n_points"]) - 1, 1),
                      "rtol": rtol, "atol": atol}
    out.clock = system.eq.clock is not None
    _functions(out, system, inputs, flat)
    _variables(out, system, flat, own, inputs)
    return out


def solver_rtol(system, rtol, horizon):
    """The tolerance an integrator's error control gets for the model's ``rtol`` (a global
    error) over its experiment's ``horizon`` [s]: CVODES BDF's in ``kn.simulate``, by the same
    map (``solver.tolerance``: for a tree or for loops, and tighter for a long run)."""
    return solver_tolerances(METHODS["cvodes"], system, rtol, rtol, horizon)[0]


def _loops_option(system):
    """The ``loops=`` a System was compiled with, for its twin with inputs (None: default)."""
    if system is None:
        return None
    f = system.formulation
    return f if f in ("partition", "projected", "baumgarte") else None


def _refuse(system, model):
    """What an FMU cannot carry, refused by name."""
    problems = []
    if system.modes is not None:
        names = ", ".join(c.name for c in system.modes.comps)
        problems.append(
            f"{names}: friction and stops change mode at events that stick, release and "
            f"impact (impulses through the mechanism, chosen by kinetwork's event handling); "
            f"an FMU of this model would integrate a different law: an FMU cannot carry them")
    if system.initial_equations.solves_parameters():
        problems.append(
            f"{model.name!r}: its initial equations (Model.initial) solve parameters from the "
            f"start, which an FMU cannot carry; give those parameters their values instead")
    if problems:
        raise ModelError(problems)


# -- functions ---------------------------------------------------------------------------------
def _functions(out, system, inputs, flat):
    a, eq = system.asm, system.eq
    t, x, z, p = a.t, eq.x, eq.z, a.p
    args, names = [t, x, z, p], ["t", "x", "z", "p"]
    closure = ca.SX(0)
    if system.formulation == "projected" and eq.residual is not None:
        closure = ca.norm_inf(eq.residual)
        out.projected = True
    jd = ca.SX(0, 1)
    if out.projected and system.f_dependent is not None:
        jd = ca.vec(ca.densify(system.f_dependent(ca.vertcat(x, z), p)))
    out.n_dependent = int(round(jd.numel() ** 0.5))
    ode, alg = ca.densify(eq.ode), ca.densify(eq.alg)
    f = {}
    f["kn_rhs"] = ca.Function("kn_rhs", args, [ode, alg, closure, jd], names,
                              ["xdot", "alg", "closure", "jd"])
    if z.numel():
        step = newton(alg, z, 1)
        f["kn_newton"] = ca.Function("kn_newton", args, [ca.densify(step),
                                                         ca.norm_inf(alg)], names,
                                     ["z_next", "residual"])
    else:
        f["kn_newton"] = ca.Function("kn_newton", args, [ca.SX(0, 1), ca.SX(0)], names,
                                     ["z_next", "residual"])
    y = system.f_out(t, ca.vertcat(x, z), p)
    f["kn_out"] = ca.Function("kn_out", args, [ca.densify(y)], names, ["y"])
    start = _start(out, system)
    f["kn_start"] = ca.Function("kn_start", [p], [start], ["p"], ["x_start"])
    projection = _projection(system) if out.projected else x
    f["kn_project"] = ca.Function("kn_project", args, [ca.densify(projection)], names,
                                  ["x_projected"])
    f["kn_input"] = ca.Function("kn_input", [t, p], [_input_values(flat, inputs, system, t, p)],
                                ["t", "p"], ["u"])
    out.relations = Held()
    f["kn_select"] = ca.Function("kn_select", args, [ca.SX(0, 1)], names, ["r"])
    f["kn_indicators"] = ca.Function("kn_indicators", args, [ca.SX(0, 1)], names, ["g"])
    f["kn_times"] = ca.Function("kn_times", args, [ca.SX(0, 1), ca.SX(0, 1)], names,
                                ["g", "rate"])
    out.functions = f
    _check_start(out, system)


def _start(out, system):
    """The initial state as an expression in p: each state's start where it is one, else its
    value at the exported parameters (a constant)."""
    a, eq = system.asm, system.eq
    known = {}
    given = list(a.given)
    for i, n in enumerate(a.coordinate_names):
        known[n] = a.q_start[i] if given[i] else ca.SX(0)
    for j, n in enumerate(a.speed_names):
        known[n] = a.u_start[j]
    net = a.net
    if net is not None:
        for n, s in zip(net.names, net.start):
            known[n] = ca.SX(s)
    if eq.clock is not None:
        known[system.state_names[eq.clock]] = ca.SX(0)
    p_symbols = {v.name() for v in ca.symvar(a.p)} if a.p.numel() else set()
    f_check = {}
    entries = []
    for k, n in enumerate(system.state_names):
        e = known.get(n)
        e = None if e is None else ca.SX(e)
        if e is not None and {v.name() for v in ca.symvar(e)} <= p_symbols:
            f_check[k] = e
            entries.append(e)
        else:
            entries.append(ca.SX(out.x0[k]))
    start = ca.vertcat(*entries) if entries else ca.SX(0, 1)
    value = np.asarray(ca.Function("s", [a.p], [start])(out.p0), dtype=float).ravel()
    # a start whose closed form is not what the System started from (a loop's coordinate
    # closed by its assembly, a steady state): its value at the exported parameters
    for k, e in f_check.items():
        if not _same(value[k], out.x0[k]):
            entries[k] = ca.SX(out.x0[k])
    return ca.vertcat(*entries) if entries else ca.SX(0, 1)


def _projection(system):
    """The states with each loop coordinate carried onto the closure (three Newton steps)."""
    a, eq = system.asm, system.eq
    index = {n: i for i, n in enumerate(a.coordinate_names)}
    rows = []
    for k, n in enumerate(system.state_names):
        i = index.get(n)
        rows.append(eq.q[i] if i is not None and k < eq.x.numel() else eq.x[k])
    return ca.vertcat(*rows)


def _input_values(flat, inputs, system, t, p):
    """Each input's own value (its block's ``value``, maybe in t) over the twin's p."""
    if not inputs:
        return ca.SX(0, 1)
    env = {n: p[i] for i, n in enumerate(system.param_names)}
    env["t"] = t
    funcs = casadi_functions()
    values = []
    for n in inputs:
        v = flat.components[n]._values["value"]
        values.append(ca.SX(parse(v).evaluate(env, funcs)) if isinstance(v, str)
                      else ca.SX(float(v)))
    return ca.vertcat(*values)


def start_numeric(out, p):
    """The initial state the FMU computes for parameter vector p (as its C does)."""
    f = out.functions
    x = np.asarray(f["kn_start"](p), dtype=float).ravel()
    if out.projected:
        z = np.zeros(0)
        for _ in range(NEWTON_ITERATIONS):
            nxt = np.asarray(f["kn_project"](0.0, x, z, p), dtype=float).ravel()
            done = np.max(np.abs(nxt - x), initial=0.0) <= 1e-14 * (1 + np.max(np.abs(x),
                                                                                initial=0))
            x = nxt
            if done:
                break
    return x


def _check_start(out, system):
    """Which parameters move the initial state in a way the FMU does not follow: each is
    changed by PROBE_STEP (relative) and the FMU's start compared with the System's."""
    base = start_numeric(out, out.p0)
    if not np.allclose(base, out.x0, rtol=SAME_START, atol=SAME_START):
        worst = int(np.argmax(np.abs(base - out.x0)))
        raise ModelError(f"{out.model.name!r}: the FMU's initial state differs from the "
                         f"model's at {system.state_names[worst]} ({base[worst]!r} against "
                         f"{out.x0[worst]!r}); an FMU of it would start elsewhere")
    names = system.param_names
    for i, n in enumerate(names):
        p = out.p0.copy()
        p[i] += PROBE_STEP * max(abs(p[i]), 1.0)
        try:
            real = system.initial_full_p(p)[0]
        except (ModelError, RuntimeError, ValueError) as exc:
            out.frozen[n] = f"the model's initial state cannot be computed when it changes " \
                            f"({str(exc)[:200]})"
            continue
        mine = start_numeric(out, p)
        if not np.allclose(mine, real, rtol=SAME_START, atol=SAME_START):
            worst = int(np.argmax(np.abs(mine - real)))
            out.frozen[n] = (f"the initial state depends on it through "
                             f"{_why_frozen(system)} (at {system.state_names[worst]})")


def _why_frozen(system):
    if system.initial_equations.spec:
        return "the model's initial equations"
    if system.formulation in ("partition", "baumgarte", "projected"):
        return "the assembly of its kinematic loops"
    return "a start solved numerically"


def _same(a, b):
    return abs(a - b) <= SAME_START * max(1.0, abs(a), abs(b))


# -- variables ---------------------------------------------------------------------------------
def _variables(out, system, flat, own, inputs):
    v = out.variables
    nx = system.n_states
    x0 = out.x0
    moving = _start_depends(out.functions["kn_start"], out)
    for k, (n, unit) in enumerate(zip(system.state_names, system.state_units)):
        calculated = k in moving
        v.append(Variable(n, "local", "continuous", "calculated" if calculated else "exact",
                          None if calculated else float(x0[k]), unit,
                          "state", nominal=float(out.nominal[k])))
    out.states = range(0, nx)
    for k, (n, unit) in enumerate(zip(system.state_names, system.state_units)):
        v.append(Variable(f"der({n})", "local", "continuous", "calculated", None,
                          state_rate_unit(unit), f"rate of {n}", derivative=k))
    out.rates = range(nx, 2 * nx)
    info = _param_info(flat)
    for n, i in zip(own, out.param_index):
        unit, lo, hi, positive, nonzero, where = info[n]
        bound = [f"used as {where}"] if where else []
        if positive:
            bound.append("> 0")
        if nonzero:
            bound.append("not 0")
        v.append(Variable(n, "parameter", "tunable", "exact", float(out.p0[i]), unit,
                          "model parameter", min=lo, max=hi, bound_why="; ".join(bound)))
        out.positive.append(positive)
        out.nonzero.append(nonzero)
    out.params = range(2 * nx, 2 * nx + len(own))
    first = len(v)
    for n, i in zip(inputs, out.input_index):
        start = float(np.asarray(out.functions["kn_input"](0.0, out.p0)).ravel()[len(v) - first])
        v.append(Variable(n, "input", "continuous", None, start, "",
                          f"signals.Input {n!r}"))
    out.inputs = range(first, len(v))
    first = len(v)
    for sig in system.signals:
        for col in sig.column_names():
            v.append(Variable(col, "output", "continuous", "calculated", None, sig.unit,
                              f"{sig.quantity} of {sig.target}"))
    out.outputs = range(first, len(v))
    _dependencies(out, system)


def _start_depends(start_f, out):
    """The states whose start depends on a parameter or input."""
    p = ca.SX.sym("p", len(out.p0))
    e = start_f(p)
    if not e.numel():
        return set()
    rows = ca.DM(ca.jacobian(e, p).sparsity(), 1)
    return set(np.flatnonzero(np.asarray(ca.sum2(rows)).ravel() > 0)) if p.numel() else set()


def _param_info(flat):
    """Per model parameter: its unit, from the components that use it as their value (times a
    number), where they agree; and its bounds, from those that use it as it is: (unit, min,
    max, positive, nonzero, where)."""
    units, bounds = {}, {}
    for comp in flat.components.values():
        for key, spec in comp.params.items():
            value = comp._values.get(key)
            if spec.kind != "real" or value is None:
                continue
            values = value if spec.shape else [value]
            if len(spec.shape) == 2:
                values = [v for row in value for v in row]
            for i, v in enumerate(values):
                if not isinstance(v, str):
                    continue
                name = quantities.scaled_name(v)
                if name not in flat.parameters:
                    continue
                unit = spec.unit_at(i if len(spec.shape) == 1 else None)
                if unit not in ("", "1"):
                    units.setdefault(name, set()).add(unit)
                if v.strip() == name and not spec.shape and \
                        (spec.min is not None or spec.max is not None or spec.positive
                         or spec.nonzero):
                    lo, hi, pos, nz, where = bounds.get(name, (None, None, False, False, []))
                    if spec.min is not None:
                        lo = spec.min if lo is None else max(lo, spec.min)
                    if spec.max is not None:
                        hi = spec.max if hi is None else min(hi, spec.max)
                    if spec.positive:
                        lo = 0.0 if lo is None else max(lo, 0.0)
                    bounds[name] = (lo, hi, pos or spec.positive, nz or spec.nonzero,
                                    where + [flat.place(comp, key)])
    out = {}
    for name in flat.parameters:
        found = units.get(name, set())
        lo, hi, pos, nz, where = bounds.get(name, (None, None, False, False, []))
        out[name] = (found.pop() if len(found) == 1 else "", lo, hi, pos, nz,
                     ", ".join(where[:3]) + (", ..." if len(where) > 3 else ""))
    return out


def _dependencies(out, system):
    """Which states and inputs each rate and output depends on (ModelStructure)."""
    f = out.functions
    a, eq = system.asm, system.eq
    t, x, z, p = a.t, eq.x, eq.z, a.p
    u = [p[i] for i in out.input_index]

    def pattern(expr):
        rows = []
        if not expr.numel():
            return rows
        dx = np.asarray(ca.DM(ca.jacobian(expr, x).sparsity(), 1)) if x.numel() else \
            np.zeros((expr.numel(), 0))
        if z.numel():      # through the algebraic variables: on whatever they depend on
            dz = np.asarray(ca.DM(ca.jacobian(expr, z).sparsity(), 1))
            any_z = dz.any(axis=1)
            dx = dx.astype(bool) | any_z[:, None]
        du = np.asarray(ca.DM(ca.jacobian(expr, ca.vertcat(*u)).sparsity(), 1)) if u else \
            np.zeros((expr.numel(), 0))
        if z.numel() and u:
            du = du.astype(bool) | any_z[:, None]
        for r in range(expr.numel()):
            deps = [out.states[j] for j in np.flatnonzero(dx[r])]
            deps += [out.inputs[j] for j in np.flatnonzero(du[r])]
            rows.append(sorted(int(d) for d in deps))
        return rows
    xdot = f["kn_rhs"](t, x, z, p)[0]
    for k, deps in zip(out.rates, pattern(xdot)):
        out.variables[k].dependencies = deps
    y = f["kn_out"](t, x, z, p)
    for k, deps in zip(out.outputs, pattern(y)):
        out.variables[k].dependencies = deps


def guid(description, sources):
    """A GUID from what the FMU is: its description (without the GUID) and its C sources."""
    h = hashlib.sha256(description.encode())
    for text in sources:
        h.update(text.encode())
    d = h.hexdigest()
    return f"{{{d[:8]}-{d[8:12]}-{d[12:16]}-{d[16:20]}-{d[20:32]}}}"
