"""Component parameters by path: ``"spring.c"``, ``"cyl3.piston.mass"``, ``"body.r_cm[0]"``
or a subsystem's own parameter ``"cyl1.phi0"``, made model parameters of a twin of the model.

A MapleSim or Modelica user sweeps, fits or varies ``spring.c`` whether or not the model was
written with a parameter for it. Model parameters are symbols of a compiled System (a new
value costs no compilation); a component parameter given a number is a constant of its
equations. ``lift`` writes a twin of the model in which each named component parameter is
given a new model parameter instead (its value by default the component's, so the twin's
equations are the model's), compiles nothing itself, and keeps the twin while the model's
structure is unchanged: the twin is compiled once however many runs, members or fits use it.
The twin shares every component it does not change.
"""

from __future__ import annotations

import copy
import re
import threading
import weakref
from dataclasses import dataclass

from ..components.base import PortRef
from ..errors import ModelError
from ..expr import parse
from ..util import quote, suggest
from .model import Model, evaluate
from .subsystem import Subsystem

#: a path: component path, parameter, optional entry indices ("body.r_cm[0]", "b.inertia[1][1]")
_PATH = re.compile(r"(?P<comp>.+)\.(?P<key>[A-Za-z_][A-Za-z0-9_]*)(?P<index>(?:\[\d+\])*)\Z")
_INDEX = re.compile(r"\[(\d+)\]")

#: source model -> {(its content key, the paths): Lifted}
_TWINS = weakref.WeakKeyDictionary()
_LOCK = threading.Lock()


@dataclass
class Lifted:
    """A twin of a model with component parameters made model parameters.

    ``model`` is the twin (flat: subsystems expanded); ``names`` maps each path to the name
    of its model parameter in the twin; ``originals`` holds what each path was given in the
    model (a number, or an expression in the model's parameters), its default; ``note`` says
    what was done, for a run's statistics."""
    model: Model
    names: dict
    originals: dict
    units: dict
    note: str
    #: whether the note was logged (once per twin)
    said: bool = False

    def defaults(self, env):
        """The lifted parameters' values when not given: what the model gives each path,
        with the model parameters ``env`` (name -> value)."""
        env_t = {**env, "t": 0.0}
        out = {}
        # in the order lifted: a subsystem's parameter before the components that read it
        for path, name in self.names.items():
            value, spec = self.originals[path]
            out[name] = env_t[name] = float(evaluate(value, spec, env_t, path)) \
                if spec is not None else float(value)
        return out


def is_path(model, name):
    """Whether ``name`` names no model parameter of ``model`` but may name a component's or
    a subsystem's parameter by its path."""
    return isinstance(name, str) and "." in name and name not in model.parameters


def lift(model, paths):
    """The ``Lifted`` twin of ``model`` in which each of ``paths`` is a model parameter.

    Raises ModelError naming every path that is no parameter of a component (with the
    closest names), or one that is not a number (a name, a table, a flag)."""
    paths = tuple(dict.fromkeys(paths))
    key = (model.content_key(), paths)
    with _LOCK:
        twins = _TWINS.setdefault(model, {})
        lifted = twins.get(key)
        if lifted is None:
            twins.clear()                # twins of another structure are stale
            lifted = twins[key] = _build(model, paths)
    # parameter values are not part of the structure: always the model's current ones
    lifted.model.parameters.update(model.parameters)
    lifted.model.parameters.update(lifted.defaults(model.parameters))
    lifted.model.parameter_text = dict(model.parameter_text)
    return lifted


def _build(model, paths):
    problems, subsystem_paths, component_paths = [], [], []
    for path in paths:
        head, _, rest = path.partition(".")
        comp = model.components.get(head)
        if isinstance(comp, Subsystem) and rest in comp.definition.parameters:
            subsystem_paths.append(path)
        else:
            component_paths.append(path)
    taken = set(model.parameters)
    names, originals, units = {}, {}, {}
    source = model
    if subsystem_paths:
        source = _lift_subsystems(model, subsystem_paths, taken, names, originals, units)
    flat = source.flat()
    twin = _twin(flat, model)
    for path in component_paths:
        try:
            _lift_component(twin, flat, path, taken, names, originals, units)
        except ModelError as exc:
            problems.extend(exc.problems)
    if problems:
        raise ModelError(problems)
    shown = ", ".join(f"{p} -> {n}" for p, n in names.items())
    note = (f"component parameters made model parameters of a twin of {model.name!r}, "
            f"compiled once and kept: {shown}")
    return Lifted(twin, names, originals, units, note)


def _fresh(path, taken):
    """An identifier for the parameter of ``path`` that no other parameter has."""
    base = re.sub(r"[^A-Za-z0-9_]", "_", path).strip("_") or "p"
    if base[0].isdigit():
        base = f"p_{base}"
    name, k = base, 1
    while name in taken:
        k += 1
        name = f"{base}_{k}"
    taken.add(name)
    return name


def _twin(flat, model):
    """A flat model sharing ``flat``'s components, wiring and settings; written as ``model``
    (what its quantities are checked on, what a job sends to a Dask worker)."""
    twin = Model.__new__(Model)
    twin._init_flat(model)
    twin.parameters = dict(flat.parameters)
    twin.parameter_text = dict(flat.parameter_text)
    twin.components = dict(flat.components)
    twin.places = dict(flat.places)
    twin.connections = list(flat.connections)
    twin._wired = {frozenset(c) for c in twin.connections}
    return twin


def _lift_component(twin, flat, path, taken, names, originals, units):
    """Give the component parameter ``path`` of ``twin`` a new model parameter."""
    found = _PATH.match(path)
    # the twin's own: a component lifted already keeps what was lifted of it
    comp = twin.components.get(found.group("comp")) if found else None
    if comp is None:
        where = found.group("comp") if found else path
        known = _known_paths(flat)
        raise ModelError(f"{quote(path, 80)}: no model parameter, and {quote(where, 60)} is no "
                         f"component{suggest(path, known)}; a component parameter is named "
                         f"'component.parameter' ('spring.c', 'cyl3.piston.mass')")
    key = found.group("key")
    spec = comp.params.get(key)
    if spec is None:
        raise ModelError(f"{quote(path, 80)}: {comp.name} ({comp.type_name}) has no parameter "
                         f"{quote(key, 40)}{suggest(key, comp.params)}; its parameters are "
                         f"{', '.join(comp.params)}")
    index = tuple(int(i) for i in _INDEX.findall(found.group("index")))
    if spec.kind != "real":
        raise ModelError(f"{path}: a {spec.kind} parameter, not a number: only numbers can be "
                         f"varied as model parameters")
    if len(index) != len(spec.shape):
        entries = "[i]" if len(spec.shape) == 1 else "[i][j]"
        raise ModelError(f"{path}: {comp.name}.{key} has shape {spec.shape}; name one entry, "
                         f"as {comp.name}.{key}{entries}" if spec.shape else
                         f"{path}: {comp.name}.{key} is a number, it has no entries")
    value = comp._values.get(key)
    if value is None:
        raise ModelError(f"{path}: {comp.name}.{key} is not given (an optional parameter "
                         f"left out): give it a value in the model first")
    entry = value
    try:
        for i in index:
            entry = entry[i]
    except (IndexError, TypeError):
        raise ModelError(f"{path}: no such entry of {comp.name}.{key} (shape "
                         f"{spec.shape})") from None
    _check_constant(path, entry)
    name = _fresh(path, taken)
    new = _replace(value, index, name)
    twin_comp = copy.copy(comp)
    object.__setattr__(twin_comp, "_values", {**comp._values, key: new})
    object.__setattr__(twin_comp, "given", {**comp.given, key: new})
    twin.components[comp.name] = twin_comp
    twin.connections = [tuple(PortRef(twin_comp, r.name) if r.component is comp else r
                              for r in c) for c in twin.connections]
    twin._wired = {frozenset(c) for c in twin.connections}
    scalar = _Scalar(spec.unit_at(index[0] if index else None), spec)
    names[path] = name
    units[path] = scalar.unit
    originals[path] = (entry, scalar if isinstance(entry, str) else None)
    twin.parameters[name] = _default(entry, scalar, twin.parameters, path)


class _Scalar:
    """One entry of a parameter, as ``evaluate`` reads a declaration: a real scalar with the
    entry's unit and no bounds of its own (the whole parameter is checked in the twin)."""
    kind, shape, nonzero = "real", (), False

    def __init__(self, unit, spec):
        self.unit = unit
        self.signals = spec.signals

    def check_bounds(self, number, where):
        return None


def _check_constant(path, value):
    """Refuse lifting an expression in time or in signals: a model parameter is constant."""
    if isinstance(value, str):
        read = parse(value).names
        if "t" in read or any("." in n for n in read):
            raise ModelError(f"{path} = {quote(value, 60)} varies in time (it reads t or a "
                             f"signal): it cannot be a model parameter, which is constant; "
                             f"vary a parameter of the expression instead")


def _default(value, spec, parameters, path):
    if not isinstance(value, str):
        return float(value)
    return float(evaluate(value, spec, {**parameters, "t": 0.0}, path))


def _replace(value, index, name):
    """``value`` with the entry at ``index`` (none: the whole) replaced by ``name``."""
    if not index:
        return name
    out = list(value)
    out[index[0]] = _replace(out[index[0]], index[1:], name)
    return out


def _lift_subsystems(model, paths, taken, names, originals, units):
    """A twin of ``model`` (not flat) whose subsystem instances take each of ``paths``
    ("cyl1.phi0") from a new model parameter."""
    twin = Model(model.name, simulation=model.simulation)
    twin.parameters = dict(model.parameters)
    twin.parameter_text = dict(model.parameter_text)
    twin.components = dict(model.components)
    twin.places, twin.initial, twin.layout = dict(model.places), model.initial, model.layout
    twin.connections = list(model.connections)
    for path in paths:
        head, _, key = path.partition(".")
        comp = twin.components[head]
        name = _fresh(path, taken)
        # as the flattening reads it: a quantity given ("700 mm") is its SI number by now
        given = comp._values.get(key, comp.definition.parameters[key]) \
            if key in comp.given else comp.definition.parameters[key]
        _check_constant(path, given)
        copy_ = Subsystem(comp.name, comp.definition, params={**comp.given, key: name})
        twin.components[head] = copy_
        twin.connections = [tuple(PortRef(copy_, r.name) if r.component is comp else r
                                  for r in c) for c in twin.connections]
        names[path] = name
        units[path] = ""             # a definition's parameter declares no unit: SI base
        originals[path] = (given, _Scalar("", _NoSignals) if isinstance(given, str) else None)
        twin.parameters[name] = _default(given, _Scalar("", _NoSignals), twin.parameters, path)
    twin._wired = {frozenset(c) for c in twin.connections}
    return twin


class _NoSignals:
    signals = False


def _known_paths(flat):
    """Every 'component.parameter' of a flat model (for suggestions)."""
    return [f"{name}.{key}" for name, comp in flat.components.items()
            for key, spec in comp.params.items() if spec.kind == "real"]
