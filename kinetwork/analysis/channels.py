"""Where an analysis drives and reads a model: its inputs, its outputs, its operating point.

An input is an open signal input (a Torque's ``u``, a Force's ``u``, a multibody force's
``f1``) or a ``signals.Input`` block, named as ``"motor.u"`` or ``"tau_in"``. Each becomes a
model parameter of a twin of the model, which the block (or a new one on the open port)
gives out: the input is a symbol of the compiled System, and CasADi differentiates with
respect to it like any parameter, exactly. Its operating value is what it stands in for (the
block's value, the torque parameter an open ``u`` replaces) at the operating time. The twin
shares the model's components and is compiled once per set of inputs.
"""

import re
import weakref
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..components.base import PortRef
from ..components.signals import Input
from ..equations.closing import closer
from ..equations.system import System
from ..errors import ModelError
from ..graph.model import Model, evaluate
from ..util import check_number, quote, suggest

#: a force element's signal port says which entry of which parameter it replaces
_REPLACES = re.compile(r"replaces (\w+)\[(\d)\]")
#: model -> {(content key, inputs): (twin model, the names of the inputs' parameters in it,
#: the inputs' operating values)}
_TWINS = weakref.WeakKeyDictionary()


@dataclass
class Plant:
    """A compiled model with named input channels: what the analysis functions work on."""
    system: System
    #: the model's own System: what runs the model up to an operating time
    source: System = None
    #: input names as given, their units, the positions of their symbols in p, and what
    #: gives their operating values (a parameter value, maybe an expression in t)
    inputs: list = field(default_factory=list)
    input_units: list = field(default_factory=list)
    input_index: list = field(default_factory=list)
    nominal: list = field(default_factory=list)

    def param_vector(self, params=None, inputs=None, t=0.0):
        """p with ``params`` overrides, the inputs at ``inputs`` (name -> value) or else at
        their operating values at time t."""
        inputs = dict(inputs or {})
        for name in inputs:
            if name not in self.inputs:
                raise ModelError(f"inputs: {quote(name)} is not an input of this analysis"
                                 f"{suggest(name, self.inputs)}; inputs are "
                                 f"{', '.join(self.inputs) or 'none'}")
        p = self.system.param_vector(params)
        env = {**dict(zip(self.system.param_names, p.tolist())), "t": float(t)}
        for name, k, value in zip(self.inputs, self.input_index, self.nominal):
            p[k] = check_number(inputs[name], f"inputs.{name}") if name in inputs else \
                evaluate(value, Input.params["value"], env, f"{name} (operating value)")
        return p

    def input_values(self, p):
        """The inputs' values in the parameter vector p, by name."""
        return {name: float(p[k]) for name, k in zip(self.inputs, self.input_index)}

    def operating_state(self, at, p):
        """(t, X): the time and the full state (x, then the algebraic z of loops, closed)
        that ``at`` names: None (the initial state), a time (the state a simulation reaches
        then), a state vector, a dict {state name: value} (the rest initial), or an object
        with ``t`` and ``X`` (an Equilibrium)."""
        s = self.system
        x0 = np.concatenate(s.initial_full_p(p))
        if at is None:
            return 0.0, x0
        if hasattr(at, "X") and hasattr(at, "t"):
            return float(at.t), self._closed(np.asarray(at.X, dtype=float), p)
        if isinstance(at, (int, float)) and not isinstance(at, bool):
            return float(at), self._reached(float(at), p)
        if isinstance(at, dict):
            names = s.state_names + s.algebraic_names
            X = x0.copy()
            for key, value in at.items():
                if key not in names:
                    raise ModelError(f"at: {quote(key)} is not a state{suggest(key, names)}; "
                                     f"states are {', '.join(s.state_names)}")
                X[names.index(key)] = float(value)
            given_z = any(k in s.algebraic_names for k in at)
            return 0.0, self._closed(X, p, given_z)
        X = np.asarray(at, dtype=float).ravel()
        given_z = X.shape == (s.n_states + s.n_algebraic,)
        if X.shape == (s.n_states,):
            X = np.concatenate([X, x0[s.n_states:]])
        if X.shape != (s.n_states + s.n_algebraic,):
            raise ModelError(f"at: expected a time, a dict of states or {s.n_states} state "
                             f"values ({', '.join(s.state_names)}), got shape {np.shape(at)}")
        return 0.0, self._closed(X, p, given_z)

    def _closed(self, X, p, given_z=True):
        """X with its algebraic variables (the dependent coordinates of loops) closing the
        loops at its independent states, on the branch the model starts on: Newton from the
        given ones when ``given_z`` (the caller chose the branch) and they converge there,
        else followed from the assembled start (``equations/closing.py``)."""
        s = self.system
        if not np.all(np.isfinite(X)):
            raise ModelError("at: the state must be finite")
        if not s.n_algebraic:
            return X
        n = s.n_states
        c = closer(s)
        x = X[:n]
        if given_z:
            z, _, ok = c.newton(x, X[n:], p)
            if ok:
                return np.concatenate([x, z])
        x0, z0 = s.initial_full_p(p)
        return np.concatenate([x, c.close(x, p, (x0, z0))])

    def _reached(self, t, p):
        """The full state a simulation (the model's settings) reaches at time t."""
        from ..solver.plan import simulate
        if t == 0.0:
            return np.concatenate(self.system.initial_full_p(p))
        if t < 0:
            raise ModelError(f"at: a time must be >= 0 (the start), got {t!r}")
        # the model itself runs there: its inputs follow their own values in time
        own = self.source.param_names
        values = dict(zip(self.system.param_names, p.tolist()))
        res = simulate(self.source, t_end=t, n_points=2,
                       params={k: values[k] for k in own})
        return self._closed(res.states[-1], p)


def plant(model, inputs=()):
    """The Plant of ``model`` (a Model or a System) with the named input channels. Loops
    are always in their independent coordinates (the partition formulation): a System
    compiled with projected or Baumgarte loops would add the projection's or the
    stabilisation's own eigenvalues to the mechanism's."""
    if isinstance(model, Plant):
        return model
    if isinstance(model, System):
        base = model.model
        if model.formulation in ("projected", "baumgarte"):
            model = base.compile(loops="partition")
    elif isinstance(model, Model):
        base = model
    else:
        raise ModelError(f"expected a kn.Model or kn.System, got {type(model).__name__}")
    if isinstance(inputs, str):
        inputs = [inputs]
    inputs = list(inputs or [])
    if len(set(inputs)) != len(inputs):
        raise ModelError(f"inputs: named twice in {inputs}")
    source = model if isinstance(model, System) else base.compile(loops="partition")
    if not inputs:
        return Plant(source, source)
    flat = base.flat()
    key = (flat.content_key(), tuple(inputs))
    twins = _TWINS.setdefault(base, {})
    if key not in twins:
        twins.clear()                     # a twin of another content is stale
        twins[key] = _twin(flat, inputs)
    twin, names, nominal = twins[key]
    twin.parameters.update(flat.parameters)
    system = twin.compile(loops="partition")
    units = [_input_unit(flat, name) for name in inputs]
    return Plant(system, source, inputs, units, [system.param_names.index(d) for d in names],
                 nominal)


def driven(flat, inputs):
    """A twin of the flat model ``flat`` in which each input of ``inputs`` (a signals.Input
    block's name, or an open signal input "component.port") is the value of a new model
    parameter: (twin, the names of those parameters, the inputs' operating values). What an
    analysis and an exported FMU drive a model through."""
    return _twin(flat, list(inputs))


def _twin(flat, inputs):
    """A model sharing ``flat``'s components, each input the value of a new parameter:
    (twin, the names of those parameters, the operating values of the inputs)."""
    twin = Model(flat.name, parameters=flat.parameters, simulation=flat.simulation)
    twin.components = dict(flat.components)
    twin.places = dict(flat.places)
    twin.connections = list(flat.connections)
    twin._wired = {frozenset(c) for c in twin.connections}
    problems, names, nominal = [], [], []
    for name in inputs:
        d = _fresh(f"input_{re.sub(r'[^A-Za-z0-9_]', '_', str(name))}", twin.parameters)
        twin.set_parameter(d, 0.0)
        names.append(d)
        try:
            nominal.append(_drive(flat, twin, name, d))
        except ModelError as exc:
            problems.extend(exc.problems)
    if problems:
        raise ModelError(problems)
    return twin, names, nominal


def _drive(flat, twin, name, d):
    """Make the input ``name`` of ``twin`` the parameter d; return its operating value."""
    if not isinstance(name, str):
        raise ModelError(f"inputs: expected names, got {quote(name)}")
    # a block's name, or "component.port" (a component of a subsystem: "axis.motor.u")
    if name in flat.components or "." not in name:
        comp = flat.components.get(name)
        if not isinstance(comp, Input):
            kind = f"a {comp.type_name}" if comp is not None else "no component"
            raise ModelError(f"inputs: {quote(name)} is {kind}{suggest(name, _inputs_of(flat))}"
                             f"; an input is a signals.Input block or an open signal input "
                             f"'component.port' (inputs here: "
                             f"{', '.join(_inputs_of(flat)) or 'none'})")
        block = _input(name, d)
        twin.components[name] = block
        twin.connections = [tuple(PortRef(block, r.name) if r.component is comp else r
                                  for r in c) for c in twin.connections]
        twin._wired = {frozenset(c) for c in twin.connections}
        return comp._values["value"]
    cname, _, pname = name.rpartition(".")
    comp = flat.components.get(cname)
    if comp is None:
        raise ModelError(f"inputs: {quote(name)}: no component {quote(cname)}"
                         f"{suggest(cname, flat.components)}")
    port = comp.ports.get(pname)
    if port is None or port.domain != "signal_in":
        raise ModelError(f"inputs: {quote(name)}: {cname} has no signal input {quote(pname)}"
                         f"{suggest(pname, [p for p, s in comp.ports.items() if s.domain == 'signal_in'])}")
    ref = comp.port_ref(pname)
    wired = [b if a == ref else a for a, b in flat.connections if ref in (a, b)]
    if wired:
        raise ModelError(f"inputs: {name} is wired to {wired[0].path}: an input is an open "
                         f"signal input or a signals.Input block (place one there)")
    if comp.role == "prescribed":
        raise ModelError(f"inputs: {name} is the reference of a prescribed motion, which "
                         f"the model differentiates in time: it is no input of a "
                         f"linearisation; drive the joint with a Torque or Force instead")
    block = _input(_fresh(f"{cname}_{pname}_input".replace(".", "_"), twin.components), d)
    twin.add(block)
    twin.connect(block.y, ref)
    return _replaced(comp, pname)[0]


def _input(name, d):
    """An Input block giving the parameter d, named ``name`` (a path in a flat model, as the
    flattening names the components of subsystems)."""
    block = Input("input", value=d)
    object.__setattr__(block, "name", name)
    return block


def _replaced(comp, pname):
    """(value, unit) of what the open signal input ``pname`` stands in for: a source's
    torque or force parameter, the entry of a force vector it replaces; else (0, "")."""
    if comp.role == "source" and pname == "u":
        timed = [k for k, s in comp.params.items() if s.time and s.shape == ()]
        if len(timed) == 1:
            return comp._values[timed[0]], comp.params[timed[0]].unit
    found = _REPLACES.search(comp.ports[pname].doc)
    if found and found.group(1) in comp.params:
        key, i = found.group(1), int(found.group(2))
        return comp._values[key][i], comp.params[key].unit
    return 0.0, ""


def _input_unit(flat, name):
    """The unit of an input: of what it replaces; an Input block's, of what it feeds."""
    if name not in flat.components:
        cname, _, pname = name.rpartition(".")
        return _replaced(flat.components[cname], pname)[1]
    block = flat.components[name]
    units = {_replaced(r.component, r.name)[1] for c in flat.connections for r in c
             if block.port_ref("y") in c and r.component is not block
             and r.domain == "signal_in"}
    return units.pop() if len(units) == 1 else ""


def _inputs_of(flat):
    """Names a model offers as inputs: its Input blocks and open signal inputs of sources."""
    wired = {r for c in flat.connections for r in c}
    out = [n for n, c in flat.components.items() if isinstance(c, Input)]
    for n, c in flat.components.items():
        if c.role in ("source", "frame_force"):
            out += [f"{n}.{p}" for p, s in c.ports.items()
                    if s.domain == "signal_in" and c.port_ref(p) not in wired]
    return out


def _fresh(name, taken):
    out, k = name, 1
    while out in taken:
        k += 1
        out = f"{name}{k}"
    return out


def output_channels(system, outputs):
    """(names, units, rows): the output columns ``outputs`` names, their units and their
    rows among the System's flattened outputs (the probe signals), or -1 - k for the state
    k. A signal name stands for all its columns (``probe.position``: three); None: every
    probe signal."""
    columns, offset = {}, 0
    for sig in system.signals:
        names = sig.column_names()
        for i, col in enumerate(names):
            columns[col] = (sig.unit, offset + i)
        offset += sig.size
    states = system.state_names + system.algebraic_names
    units = system.state_units + system.algebraic_units
    if outputs is None:
        outputs = [sig.name for sig in system.signals]
    elif isinstance(outputs, str):
        outputs = [outputs]
    names, out_units, rows, problems = [], [], [], []
    for name in outputs:
        sig = next((s for s in system.signals if s.name == name), None)
        expanded = sig.column_names() if sig is not None else [name]
        for col in expanded:
            if col in columns:
                unit, row = columns[col]
            elif col in states:
                unit, row = units[states.index(col)], -1 - states.index(col)
            else:
                problems.append(f"outputs: {quote(col)} is no probe quantity or state"
                                f"{suggest(col, list(columns) + states)}; probe quantities: "
                                f"{', '.join(columns) or 'none (add a Probe)'}")
                continue
            names.append(col)
            out_units.append(unit)
            rows.append(row)
    if problems:
        raise ModelError(problems)
    return names, out_units, rows


def output_expression(system, rows, t, X, p):
    """The outputs ``rows`` (from ``output_channels``) as CasADi expressions of t, the full
    state X and the parameters p (symbols of any kind)."""
    if not rows:
        return type(X)(0, 1)
    y = system.f_out(t, X, p) if system.signals else None
    return ca.vertcat(*[X[-1 - r] if r < 0 else y[r] for r in rows])
