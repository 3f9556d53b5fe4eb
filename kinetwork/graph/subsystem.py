"""Subsystems: a model placed in another model like a component, and the flattening that turns
a model of subsystems into the flat model the equations are built from.

A model becomes a definition by exposing ports (``Model.expose("frame_a", "crank.frame_a")``);
its parameters are the subsystem's parameters. ``Subsystem("cyl1", cylinder, params={...})``
places it: numbers and expressions in the outer model's parameters feed the inner ones.

Flattening names everything by path: component ``cyl1.piston``, state ``cyl1.slide.q``, probe
signal ``cyl1.p.position``. A subsystem parameter given a number (or left at its definition's
value) is a constant of the instance, as a component's parameter is, so a model of subsystems
has the very equations of the same model written flat; one given an expression in the outer
model's parameters is that expression written in the outer names, so a model parameter
feeding it changes it without a new compilation.
"""

import copy
import re

import networkx as nx

from ..components.base import ANY, Component, Param, Port, PortRef, _NAME
from ..errors import ModelError, Problem
from ..expr import parse, rename
from ..util import hint, quote, suggest

#: how deep subsystems may nest (a cycle is refused by name long before)
DEPTH_LIMIT = 64
#: the most components a model may hold, its subsystems expanded (a 10,000-link chain is
#: 30,000): checked before anything is expanded, so a file of a few kilobytes whose
#: definitions each place two of the next cannot grow without bound
MAX_COMPONENTS = 100_000
#: the most connections, likewise
MAX_CONNECTIONS = 4 * MAX_COMPONENTS


class Subsystem(Component):
    """A model placed as a component: its exposed ports are the ports, its parameters the
    parameters.

    Parameters
    ----------
    name : str
        Instance name: the first part of every inner path (``cyl1.piston.q``).
    model : Model
        The definition, with ports declared by ``Model.expose``.
    params : dict, optional
        Values of the definition's parameters for this instance: numbers, or expressions in
        the parameters of the model the subsystem is placed in.
    """

    role = "subsystem"

    def __init__(self, name, model, params=None):
        if not hasattr(model, "exposed") or not hasattr(model, "components"):
            raise ModelError(f"Subsystem {quote(name)}: expects a kn.Model as its definition, "
                             f"got {quote(model, 60)}")
        object.__setattr__(self, "definition", model)
        if not isinstance(params, (dict, type(None))):
            raise ModelError(f"Subsystem {quote(name)} params: must be a dict, got "
                             f"{quote(params, 60)}")
        self._declare(name, dict(params or {}), None)

    @classmethod
    def from_params(cls, name, params, place=None, model=None):
        comp = cls.__new__(cls)
        object.__setattr__(comp, "definition", model)
        comp._declare(name, params, place)
        return comp

    def _type_name(self):
        """What files call the definition: its name."""
        return self.definition.name

    def _ports(self):
        """The exposed ports of the definition, each with the domain of the port it leads to."""
        return {name: Port(_domain(ref), f"{ref.path} of {self.definition.name}")
                for name, ref in self.definition.exposed.items()}

    def _params(self):
        """The definition's parameters, defaulting to its values."""
        return {name: Param(value, name=name, doc=f"parameter {name} of "
                            f"{self.definition.name}")
                for name, value in self.definition.parameters.items()}

    def __getattr__(self, key):
        if not key.startswith("_") and key in self.ports:
            return PortRef(self, key)
        if not key.startswith("_") and key in self.definition.parameters:
            return self.given.get(key, self.definition.parameters[key])
        return super().__getattr__(key)

    def port_ref(self, name):
        if name not in self.ports:
            close = suggest(name, self.ports)
            raise ModelError(f"subsystem {self.name!r} ({self.definition.name}) has no port "
                             f"{quote(name)}{close}; ports: "
                             f"{', '.join(self.ports) or 'none (expose some in the definition)'}",
                             component=self.name, hint=hint(close),
                             port=name if isinstance(name, str) else None)
        return PortRef(self, name)

    def signature(self, _memo=None):
        """What the equations of this instance depend on: its definition (the digest of its
        content), the values given and the definition's own values (numbers are constants
        of the instance)."""
        return (self.definition.fingerprint(_memo), repr(sorted(self.given.items())),
                repr(sorted(self.definition.parameters.items())))

    def __repr__(self):
        return f"<Subsystem {self.name!r} of {self.definition.name!r}>"


# set after the class is made: Component.__init_subclass__ gives every class plain tables
Subsystem.type_name = property(Subsystem._type_name)
Subsystem.ports = property(Subsystem._ports)
Subsystem.params = property(Subsystem._params)


def _domain(ref):
    """The domain of an exposed port, followed through nested subsystems."""
    for _ in range(DEPTH_LIMIT):
        comp = ref.component
        if not isinstance(comp, Subsystem):
            return comp.ports[ref.name].domain
        target = comp.definition.exposed.get(ref.name)
        if target is None:
            return ANY
        ref = target
    return ANY


def definitions(model):
    """Every definition placed in ``model``, nested ones included, each once, in the order
    first met (a depth-first walk); a cycle is refused naming it."""
    graph = nx.DiGraph()
    graph.add_node(id(model))
    order, stack = {}, [model]
    while stack:
        m = stack.pop()
        for comp in m.components.values():
            if isinstance(comp, Subsystem):
                d = comp.definition
                graph.add_edge(id(m), id(d))
                if id(d) not in order and d is not model:
                    order[id(d)] = d
                    stack.append(d)
    try:
        cycle = nx.find_cycle(graph, id(model))
    except nx.NetworkXNoCycle:
        return list(order.values())
    names = {id(model): model.name, **{k: d.name for k, d in order.items()}}
    path = " places ".join(names[a] for a, _ in cycle) + f" places {names[cycle[0][0]]}"
    raise ModelError(f"subsystems place each other in a cycle: {path}")


def subsystem_instances(model):
    """Each definition placed in ``model`` (nested too): name -> (Model, instance paths)."""
    out = {}

    def walk(m, prefix):
        for comp in m.components.values():
            if isinstance(comp, Subsystem):
                d = comp.definition
                out.setdefault(d.name, (d, []))[1].append(prefix + comp.name)
                walk(d, f"{prefix}{comp.name}.")
    definitions(model)              # a cycle is refused before the walk
    walk(model, "")
    return out


def check_placement(model, sub):
    """Refuse placing ``sub`` in ``model`` when its definition contains ``model``."""
    d = sub.definition
    if d is model or any(inner is model for inner in definitions(d)):
        raise ModelError(f"{sub.name}: model {model.name!r} cannot contain itself (the "
                         f"definition {d.name!r} places {model.name!r})")


def has_subsystems(model):
    """Whether ``model`` places a subsystem or an aggregate (both flatten)."""
    return any(isinstance(c, Subsystem) or _aggregate(c) for c in model.components.values())


def _aggregate(comp):
    """Whether ``comp`` is an aggregate: a component that stands for a chain of elementary
    ones (its ``expand`` hook gives them, wired, and which of their ports are its own)."""
    return getattr(type(comp), "expand", None) is not None


class _Flat:
    """The walk that writes a model of subsystems as one flat model."""

    def __init__(self, model, flat):
        self.model, self.flat, self.problems = model, flat, []
        self.expanded = {}           # id of an aggregate -> (it, its Expansion), made once

    def expansion(self, comp):
        """The Expansion of aggregate ``comp`` (the same object at every look), else None."""
        if not _aggregate(comp):
            return None
        if id(comp) not in self.expanded:
            self.expanded[id(comp)] = (comp, comp.expand())
        return self.expanded[id(comp)][1]

    def alias(self, inner, path, shown):
        """Record the user's names of aggregate ``path``'s parts (``flat.aliases``): its
        exposed ports (``motor.Ra.p`` is ``motor.p``) and its inner parts (``motor.Ra``, shown
        ``motor/Ra``, is ``motor``), so that no message names a part the user never placed."""
        aliases = self.flat.__dict__.setdefault("aliases", {})
        for name, ref in inner.exposed.items():
            aliases[f"{path}.{ref.path}"] = f"{path}.{name}"
        for name in inner.components:
            aliases[f"{shown}/{name}"] = shown
            aliases[f"{path}.{name}"] = path

    def walk(self, m, prefix, scope, display, depth, entry=None):
        """Add ``m``'s components under ``prefix``; ``scope`` maps m's parameter names to
        their text in flat names; ``entry`` is the file path of the top model's component
        they are inside (problems about them point there)."""
        if depth > DEPTH_LIMIT:
            raise ModelError(f"{display}: subsystems nested more than {DEPTH_LIMIT} deep")
        for comp in m.components.values():
            path, shown = prefix + comp.name, display + comp.name
            at = m.paths.get(comp.name) if not prefix else entry
            if isinstance(comp, Subsystem):
                self.walk(comp.definition, path + ".", self.scope_of(m, comp, path, scope),
                          shown + "/", depth + 1, at)
                continue
            if _aggregate(comp):          # its parts take its parameters' own words
                inner = self.expansion(comp)
                self.alias(inner, path, shown)
                self.walk(inner, path + ".", scope, shown + "/", depth + 1, at)
                continue
            if at is not None:
                self.flat.paths[path] = at
            twin = copy.copy(comp)
            object.__setattr__(twin, "name", path)
            given, values = {}, {}
            for key, spec in comp.params.items():
                value = comp._values[key]
                if spec.kind in ("real", "expression") and value is not None:
                    # signal outputs a force law reads ("pos.y") are named by path too
                    local = {**scope, **_read_signals(value, prefix)} \
                        if spec.signals and prefix else scope
                    value = self.constant(value, local, m, comp, shown, key, path)
                elif spec.kind == "name" and value is not None and prefix:
                    value = prefix + value
                values[key] = value
                if key in comp.given:
                    given[key] = value
            object.__setattr__(twin, "given", given)
            object.__setattr__(twin, "_values", values)
            self.flat.components[path] = twin
            where = m.places.get(comp.name)
            if prefix:
                self.flat.places[path] = (shown, where if isinstance(where, str) else None)
            elif where is not None:
                self.flat.places[path] = where
        for a, b in m.connections:
            pa, pb = self.port(m, prefix, a, depth), self.port(m, prefix, b, depth)
            if pa is not None and pb is not None:
                self.flat.connections.append((pa, pb))

    def constant(self, value, scope, m, comp, shown, key, flat):
        """``value`` (a parameter of a component inside a subsystem) in flat names, its
        expressions without free names as numbers; one that cannot be evaluated (a division
        by zero, a root of a negative number once the instance's numbers are in) is a
        problem naming its place, and stays as it was."""
        def place():            # only for a message: a model's every parameter passes here
            where = m.place(comp, key)
            return f"{shown}.{key}" + ("" if where == f"{comp.name}.{key}" else f" ({where})")
        try:
            return _map(value, lambda text: _constant(rename(text, scope)))
        except ModelError as exc:               # grows past a bound once renamed
            raise ModelError(f"{place()}: {exc}", component=flat, parameter=key,
                             path=self.flat.paths.get(flat)) from None
        except (ZeroDivisionError, ValueError, OverflowError, TypeError) as exc:
            self.problems.append(Problem(f"{place()} = {quote(value, 60)}: cannot be evaluated "
                                         f"with this instance's parameters ({exc})",
                                         component=flat, parameter=key,
                                         path=self.flat.paths.get(flat)))
            return value

    def scope_of(self, m, sub, path, scope):
        """The inner parameters of subsystem ``sub`` in flat names: a number becomes the flat
        parameter ``path.name``, an expression is rewritten in the outer names."""
        inner = {}
        for key, default in sub.definition.parameters.items():
            # the value in SI: a quantity given ("700 mm") is a number by now, in base units
            # (a definition's parameters declare none to check it against)
            value = sub._values.get(key, default) if key in sub.given else default
            if isinstance(value, str):
                expr = parse(value)
                unknown = sorted(expr.names - set(scope))
                if unknown:
                    where, close = m.place(sub, key), suggest(unknown[0], scope)
                    self.problems.append(Problem(
                        f"{where} = {value!r}: unknown name {unknown[0]!r}{close}; parameters "
                        f"here are {', '.join(scope) or 'none'}", component=path,
                        parameter=key, hint=hint(close),
                        path=m.fields(sub, key)["path"] if m is self.model else None))
                    inner[key] = "0"
                else:
                    try:
                        inner[key] = f"({rename(value, scope)})"
                    except ModelError as exc:     # grows past a bound: say where
                        raise ModelError(f"{path}.{key} ({m.place(sub, key)}): {exc}") \
                            from None
            else:
                inner[key] = repr(float(value))
        return inner

    def port(self, m, prefix, ref, depth):
        """The flat PortRef of ``ref`` (a port of one of ``m``'s components)."""
        for _ in range(DEPTH_LIMIT):
            comp = ref.component
            if m.components.get(comp.name) is not comp:
                self.problems.append(Problem(f"{prefix}{ref.path}: component {comp.name!r} is "
                                             f"not in model {m.name!r} any more (remove its "
                                             f"connections too)",
                                             component=prefix + comp.name, port=ref.name))
                return None
            inner = comp.definition if isinstance(comp, Subsystem) else self.expansion(comp)
            if inner is None:
                return PortRef(self.flat.components[prefix + comp.name], ref.name)
            target = inner.exposed.get(ref.name)
            if target is None:
                close = suggest(ref.name, inner.exposed)
                self.problems.append(Problem(f"{prefix}{ref.path}: {inner.name!r} exposes no "
                                             f"port {ref.name!r}{close}", hint=hint(close),
                                             component=prefix + comp.name, port=ref.name))
                return None
            m, prefix, ref = inner, f"{prefix}{comp.name}.", target
        raise ModelError(f"{prefix}{ref.path}: subsystems nested more than {DEPTH_LIMIT} deep")


def flat_size(model):
    """(components, connections) of ``model`` once every subsystem is expanded, counted once
    per definition (nothing is expanded: a definition placed a million times is counted
    once); exact however large."""
    definitions(model)              # a cycle is refused before it is counted
    return _counter()(model)


def _counter():
    """A function giving (components, connections) of a model flat, remembering each
    definition's count."""
    memo = {}

    def count(m):
        if id(m) not in memo:
            comps, conns = 0, len(m.connections)
            for comp in m.components.values():
                if isinstance(comp, Subsystem):
                    a, b = count(comp.definition)
                elif _aggregate(comp):
                    inner = comp.expand()
                    a, b = len(inner.components), len(inner.connections)
                else:
                    a, b = 1, 0
                comps, conns = comps + a, conns + b
            memo[id(m)] = (comps, conns)
        return memo[id(m)]
    return count


def check_size(model):
    """Refuse (ModelError) a model whose flat form would have more than MAX_COMPONENTS
    components or MAX_CONNECTIONS connections, naming the instances, by path, through which
    it grows; before anything is expanded."""
    definitions(model)
    count = _counter()
    comps, conns = count(model)
    if comps <= MAX_COMPONENTS and conns <= MAX_CONNECTIONS:
        return
    path, names, m = [], [], model
    while len(path) < DEPTH_LIMIT:       # down the heaviest instance at each level
        subs = [c for c in m.components.values() if isinstance(c, Subsystem)]
        if not subs:
            break
        heaviest = max(subs, key=lambda c: count(c.definition))
        names.append(heaviest.name)
        path.append(f"{'.'.join(names)} ({heaviest.definition.name}, "
                    f"{_many(count(heaviest.definition)[0])} components)")
        m = heaviest.definition
    shown = ", ".join(path[:6]) + (f", ..., {path[-1]}" if len(path) > 6 else "")
    over = comps > MAX_COMPONENTS
    what = f"{_many(comps)} components" if over else f"{_many(conns)} connections"
    limit = f"{MAX_COMPONENTS} components" if over else f"{MAX_CONNECTIONS} connections"
    raise ModelError(f"model {model.name!r}: {what} once its subsystems are expanded, more "
                     f"than the {limit} a model may have"
                     + (f"; it grows through {shown}" if path else "")
                     + " (nothing was expanded)")


def _many(n):
    """A count for a message: as it is below a trillion, else 1.23e+45."""
    return str(n) if n < 10**12 else f"{float(n):.3g}" if n < 10**300 else "more than 1e300"


def flatten(model):
    """The flat model of ``model`` (``model`` itself when it places no subsystem): components
    and parameters named by path, connections through exposed ports resolved to the inner
    ports. Refuses cycles, unknown exposed ports and unknown names, naming the path, and a
    model too large once expanded (``check_size``), before expanding anything."""
    if not has_subsystems(model):
        return model
    check_size(model)
    flat = type(model).__new__(type(model))
    flat._init_flat(model)
    walker = _Flat(model, flat)
    walker.walk(model, "", {k: k for k in model.parameters}, "", 0)
    if walker.problems:
        raise ModelError(walker.problems)
    return flat


def user_names(error, flat):
    """``error`` (a ModelError about the flat model ``flat``) in the user's names: the
    exposed ports and inner parts of aggregates (a ``DCMotor``'s resistor ``Ra``) named as the
    aggregate and its own ports (``flat.aliases``); the error itself when there are none."""
    aliases = getattr(flat, "aliases", None)
    if not aliases or not isinstance(error, ModelError):
        return error
    pattern = re.compile(r"(?<![\w./])(" + "|".join(
        re.escape(k) for k in sorted(aliases, key=len, reverse=True)) + r")(?![\w/])")

    def words(text):
        return pattern.sub(lambda m: aliases[m.group(1)], text) if text else text

    problems = []
    for problem in error.problems:
        fields = {k: getattr(problem, k, None) for k in ("component", "port", "parameter",
                                                         "path", "hint", "severity")}
        component, port = fields["component"], fields["port"]
        if component in aliases:
            exposed = aliases.get(f"{component}.{port}") if port else None
            fields["component"] = aliases[component]
            fields["port"] = exposed.rpartition(".")[2] if exposed else port
        fields["hint"] = words(fields["hint"])
        problems.append(Problem(words(problem.message), **{
            k: v for k, v in fields.items() if v is not None}))
    renamed = type(error).__new__(type(error))
    renamed.__dict__.update(error.__dict__)
    ModelError.__init__(renamed, problems, count=error.count)
    return renamed


def _read_signals(value, prefix):
    """Dotted name -> its flat path, for the signal outputs ("pos.y") that ``value`` (an
    expression or a vector of them) reads inside a subsystem placed at ``prefix``."""
    texts = [value] if isinstance(value, str) else [
        v for v in value if isinstance(v, str)] if isinstance(value, list) else []
    return {n: prefix + n for text in texts for n in parse(text).names if "." in n}


def _constant(text):
    """An expression without free names as its number (a subsystem's parameter given a
    number is a constant of the instance, as a component's is: the flat model's equations
    are those of the same model written flat), any other as it is."""
    expr = parse(text)
    return float(expr.evaluate({})) if not expr.names else text


def _map(value, fn):
    """``fn`` applied to every expression string in a parameter value (nested lists)."""
    if isinstance(value, str):
        return fn(value)
    if isinstance(value, list):
        return [_map(v, fn) for v in value]
    return value


def check_port_name(name):
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise ModelError(f"port name {quote(name, 60)}: must be an identifier")
