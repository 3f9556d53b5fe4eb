"""The sections of a model file, read into a Model: components, connections, exposed ports,
the simulation settings, the layout and the names of the definitions.

Each section is checked as it is read; every problem is added to one list with its place
in the file (``components[3] "mass1" params.mass``), for ``io`` to raise at once. Types that
are no kinetwork component name definitions, which ``io.Context`` finds.
"""

from ..components.base import _NAME, NAME_LIMIT, REGISTRY, type_suggestion
from ..errors import ModelError, Problem
from ..util import hint, quote, suggest
from .initial import check_initial
from .model import Model, model_name_problem, text_problem
from .reading import attempt, cut, fill, plain_copy, repeated_keys
from .settings import check_setting, check_steps
from .subsystem import MAX_COMPONENTS, MAX_CONNECTIONS, Subsystem
from .writer import FORMAT, KEYS, KEYS_V2, VERSION, _kind, _plain

#: the file format versions read
SUPPORTED = (1, 2)
#: the keys every file has
REQUIRED = ("format", "version", "name", "components")
#: the keys of a component's entry
COMPONENT_KEYS = ("name", "type", "params")
#: among the names of broken components: some entry had no usable name (no identifier is "*")
UNNAMED = "*"


def build(data, problems, context):
    """The Model of a file's data (None when it cannot be read at all), its problems added
    to ``problems``; ``context`` finds the definitions its types name."""
    if not isinstance(data, dict):
        problems.append(f"top level: must be an object {{...}}, got {_kind(data)}")
        return None
    repeated_keys(data, "", problems)
    fmt, version = data.get("format", FORMAT), data.get("version", VERSION)
    keys = KEYS_V2 if version == 2 else KEYS
    problems.extend(Problem(f"{quote(key)}: unknown key{close}; keys are {', '.join(keys)}"
                            + (" (ports and definitions need version 2)"
                               if key in KEYS_V2 else ""), path=cut(str(key)),
                            hint=hint(close))
                    for key in data if key not in keys for close in [suggest(key, keys)])
    problems.extend(Problem(f"{key}: required key missing", path=key)
                    for key in REQUIRED if key not in data)
    # another format or version: whatever else looks wrong is noise, so stop here
    if fmt != FORMAT:
        problems.append(Problem(f"format: {quote(fmt)} is not a kinetwork model file "
                                f"(expected {FORMAT!r})", path="format"))
        return None
    if type(version) is not int or version not in SUPPORTED:
        problems.append(Problem(f"version: {quote(version)} is not supported; this "
                                f"kinetwork reads version {', '.join(map(str, SUPPORTED))}",
                                path="version"))
        return None
    name = data.get("name", "unnamed")
    problem = model_name_problem(name)
    if problem:
        problems.append(Problem(f"name: {problem}", path="name"))
        name = "unnamed"
    model = Model(name)
    context = context.file(attempt(problems, "definitions", _entries,
                                    data.get("definitions", {}), path="definitions") or {})
    model.definitions = context.build_all(problems)
    body(model, data, problems, context)
    model.simulation = _simulation(data.get("simulation", {}), problems)
    found = check_initial(data.get("initial", {}))
    problems.extend(Problem.of(p, path="initial") for p in found)
    if not found:
        model.initial = data.get("initial", {})
    return model


def body(model, data, problems, context):
    """Read what a model file and an inline definition share: description, parameters,
    ports, components, connections and layout."""
    model.description = data.get("description", "")
    if not isinstance(model.description, str):
        problems.append(Problem(f"description: must be a string, got "
                                f"{_kind(model.description)}", path="description"))
    elif (problem := text_problem(model.description, allowed="\t\n\r")):
        problems.append(Problem(f"description: {problem}", path="description"))
    parameters = data.get("parameters", {})
    if not isinstance(parameters, dict):
        problems.append(Problem(f"parameters: must be an object of numbers (or numbers with "
                                f"units, '500 mm'), got {_kind(parameters)}",
                                path="parameters"))
    else:
        for key, value in parameters.items():
            if not _NAME.fullmatch(key):     # said here with the name cut
                problems.append(Problem(f"parameters: parameter name {quote(key)}: must be an "
                                        f"identifier (letters, digits, underscore; not "
                                        f"starting with a digit; at most {NAME_LIMIT} "
                                        f"characters)", path="parameters"))
            else:
                attempt(problems, "parameters", model.set_parameter, key, value,
                         path=f"parameters.{key}", parameter=key)
    broken = (_components(model, data["components"], problems, context)
              if "components" in data else {UNNAMED})
    _connections(model, data.get("connections", []), broken, problems)
    _ports(model, data.get("ports", {}), broken, problems)
    before = len(problems)
    model.layout = attempt(problems, "layout", _layout, model, data.get("layout", {}),
                            broken, problems)
    fill(problems, before, path="layout")


def _components(model, entries, problems, context):
    """Add each entry; return the names of the failed ones, whose wiring goes unchecked."""
    if not isinstance(entries, list):
        problems.append(Problem(f"components: must be a list, got {_kind(entries)}",
                                path="components"))
        return {UNNAMED}
    if len(entries) > MAX_COMPONENTS:           # refused before any is built
        problems.append(f"components: {len(entries)} entries, more than the "
                        f"{MAX_COMPONENTS} a model may have")
        return {UNNAMED}
    broken, seen = set(), {}
    for i, entry in enumerate(entries):
        name = entry.get("name") if isinstance(entry, dict) else None
        place = f'components[{i}] "{cut(name)}"' if isinstance(name, str) else \
            f"components[{i}]"
        at = {"path": f"components[{i}]",
              "component": cut(name) if isinstance(name, str) else None}
        if isinstance(name, str) and name in seen:
            problems.append(Problem(f"{place}: duplicate name, already used by "
                                    f"components[{seen[name]}]", **at))
            continue
        before = len(problems)
        comp = attempt(problems, place, _component, entry, place, problems, context)
        if isinstance(name, str):
            seen[name] = i
        if comp is None or len(problems) > before:
            broken.add(name if isinstance(name, str) else UNNAMED)
        else:
            attempt(problems, place, model.add, comp)
            model.places[comp.name] = context.where + place
            model.paths[comp.name] = at["path"]
        # a parameter's problem is at its own key, the others at the entry
        problems[before:] = [Problem.of(p).where(**at) if not getattr(p, "parameter", None)
                             else Problem.of(p).where(path=f"{at['path']}.params.{p.parameter}",
                                                      component=at["component"])
                             for p in problems[before:]]
    return broken


def _component(entry, place, problems, context):
    if not isinstance(entry, dict):
        problems.append(f'{place}: must be an object {{"name", "type", "params"}}, '
                        f"got {_kind(entry)}")
        return None
    problems.extend(f"{place}: unknown key {quote(key)}{suggest(key, COMPONENT_KEYS)}; keys "
                    f"are {', '.join(COMPONENT_KEYS)}" for key in entry
                    if key not in COMPONENT_KEYS)
    missing = [key for key in ("name", "type") if key not in entry]
    problems.extend(f"{place}: required key {key!r} missing" for key in missing)
    kind, params = entry.get("type"), entry.get("params", {})
    if missing:
        return None
    if not isinstance(params, dict):
        problems.append(f"{place} params: must be an object, got {_kind(params)}")
        return None
    where = (lambda key: f"{place} params.{cut(key)}")
    if isinstance(kind, str) and kind not in REGISTRY and _NAME.fullmatch(kind):
        definition = context.definition(kind, place)      # a subsystem
        return Subsystem.from_params(entry["name"], params, place=where, model=definition)
    if not isinstance(kind, str) or kind not in REGISTRY:
        # resolved only through the registry: a dotted path in a file is never imported
        close = type_suggestion(kind)
        problems.append(Problem(f"{place}: unknown type {quote(kind, 60)}{close}",
                                hint=hint(close)))
        return None
    return REGISTRY[kind].from_params(entry["name"], params, place=where)


def _connections(model, pairs, broken, problems):
    if not isinstance(pairs, list):
        problems.append(Problem(f"connections: must be a list of pairs, got {_kind(pairs)}",
                                path="connections"))
        return
    if len(pairs) > MAX_CONNECTIONS:
        problems.append(f"connections: {len(pairs)} entries, more than the "
                        f"{MAX_CONNECTIONS} a model may have")
        return
    for i, pair in enumerate(pairs):
        if not isinstance(pair, list) or len(pair) != 2:
            problems.append(Problem(f'connections[{i}]: must be a pair ["component.port", '
                                    f'"component.port"], got {quote(pair, 80)}',
                                    path=f"connections[{i}]"))
            continue
        refs, before = [], len(problems)
        for j, ref in enumerate(pair):
            place = f'connections[{i}][{j}] "{cut(ref)}"' if isinstance(ref, str) else \
                f"connections[{i}][{j}]"
            refs.append(attempt(problems, place, _port, model, ref, broken,
                                 path=f"connections[{i}][{j}]"))
        if all(refs):
            attempt(problems, f"connections[{i}]", model.connect, *refs,
                     path=f"connections[{i}]")
        # a wire's problem is on the wire (its path), not on the block it names
        problems[before:] = [Problem(p.message, path=p.path, hint=p.hint)
                             for p in map(Problem.of, problems[before:])]


def _port(model, ref, broken):
    """The PortRef, or None when it belongs to a component that already failed."""
    if not isinstance(ref, str) or ref.count(".") != 1:
        raise ModelError(f"must be a string 'component.port', got {quote(ref, 80)}")
    cname, pname = ref.split(".")
    if cname in broken or (UNNAMED in broken and cname not in model.components):
        return None
    if cname not in model.components:
        raise ModelError(f"no component {quote(cname)}{suggest(cname, model.components)}")
    return model.components[cname].port_ref(pname)


def _ports(model, ports, broken, problems):
    """The exposed ports: name -> "component.port"."""
    if not isinstance(ports, dict):
        problems.append(Problem(f"ports: must be an object of \"name\": \"component.port\","
                                f" got {_kind(ports)}", path="ports"))
        return
    for name, ref in ports.items():
        place = f'ports.{cut(name)} "{cut(ref)}"' if isinstance(ref, str) else \
            f"ports.{cut(name)}"
        at = f"ports.{cut(name)}"
        target = attempt(problems, place, _port, model, ref, broken, path=at)
        if target is not None:
            attempt(problems, at, model.expose, name, target, path=at)


def _simulation(settings, problems):
    """The experiment settings, checked as ``simulate`` will use them."""
    if not isinstance(settings, dict):
        problems.append(Problem(f"simulation: must be an object, got {_kind(settings)}",
                                path="simulation"))
        return {}
    found = [Problem(p, path=f"simulation.{cut(str(k))}")
             for k, v in settings.items() if (p := check_setting(k, v))]
    for key in ("step", "max_step"):                              # what they cost together
        if not found and key in settings and "t_end" in settings:
            found = [Problem(p, path=f"simulation.{key}")
                     for p in [check_steps(settings["t_end"], settings[key], key)] if p]
    problems.extend(found)
    return dict(settings)


def _layout(model, layout, broken, problems):
    """Editor positions: any JSON per component, kept as is."""
    if not isinstance(layout, dict):
        problems.append(f"layout: must be an object keyed by component name, got {_kind(layout)}")
        return {}
    for key, value in layout.items():
        if key not in model.components and key not in broken and UNNAMED not in broken:
            problems.append(f"layout.{cut(key)}: no component {quote(key)}"
                            f"{suggest(key, model.components)}")
        _plain(value, f"layout.{cut(key)}", problems)
    return plain_copy(layout)


def _entries(definitions):
    if not isinstance(definitions, dict):
        raise ModelError(f"must be an object of definitions by name, got {_kind(definitions)}")
    problems = []
    for name in definitions:
        if not _NAME.fullmatch(name):
            problems.append(f"{quote(name)}: a definition's name must be an identifier")
        elif name in REGISTRY:
            problems.append(f"{name}: a kinetwork component type has this name; choose "
                            f"another")
    if problems:
        raise ModelError(problems)
    return dict(definitions)
