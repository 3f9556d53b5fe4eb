"""JSON model files (format "kinetwork.model", version 1): load, save and their refusals.

A file names component types, never code: types resolve only through the component
``REGISTRY`` and parameter strings go through the safe expression parser, so loading executes
nothing from the file. Every problem is reported with its place in the file
(``components[3] "mass1" params.mass``), all in one ``ModelError``; a model is returned only
when the whole file is sound.
"""

from __future__ import annotations

import json
import os
import pathlib
import stat
from collections.abc import Iterable

from ..components.base import _NAME, NAME_LIMIT, REGISTRY, type_suggestion
from ..errors import ModelError, Problem
from ..util import hint, quote, suggest
from .initial import check_initial
from .model import Model, model_name_problem, text_problem
from .reading import (JSONObject, at_source, attempt, cut, fill, plain_copy, read_int,
                      repeated_keys)
from .settings import check_setting, check_steps
from .subsystem import Subsystem
from .writer import (DEFINITION_KEYS, FORMAT, KEYS, KEYS_V2, VERSION, _kind, _plain, dumps,
                     model_to_dict, save)

SUPPORTED = (1, 2)
#: folders of subsystem files, after a file's own definitions and its folder
LIBRARY_ENV = "KINETWORK_LIBRARY"
__all__ = ["FORMAT", "KEYS", "VERSION", "dumps", "load", "loads", "model_from_dict",
           "model_to_dict", "save"]
REQUIRED = ("format", "version", "name", "components")
COMPONENT_KEYS = ("name", "type", "params")
#: among the names of broken components: some entry had no usable name (no identifier is "*")
UNNAMED = "*"
#: the largest model file read (bytes; text of a loads() call: characters). A model is text
#: of kilobytes to megabytes: /dev/zero or an endless pipe is refused once this much is read
MAX_FILE_SIZE = 64 * 2**20


# -- reading ----------------------------------------------------------------------------------
def load(path: str | os.PathLike, validate: bool = True,
         library: Iterable[str | os.PathLike] | None = None) -> Model:
    """Read a model file.

    Parameters
    ----------
    path : str or os.PathLike
        A model file; a path that does not exist may name an example that ships with the
        package (``"double_pendulum"``, or ``"models/double_pendulum.json"`` as in a
        checkout: see ``kn.examples``).
    validate : bool, optional
        Also check the wiring (``Model.validate``; of a subsystem definition, a model with
        exposed ports, only its values); False reads a model saved half-built.
    library : list of folders, optional
        Where subsystem definitions named by a component's ``type`` are looked for
        (``<type>.json``), after the file's own ``definitions`` and its folder. The
        environment variable ``KINETWORK_LIBRARY`` (folders separated by ``os.pathsep``)
        adds more.

    Returns
    -------
    Model

    Raises
    ------
    ModelError
        Every problem with the file, each message starting with the file name and the place.
    """
    source = os.fspath(path)
    if not os.path.exists(source):
        source = os.fspath(example_file(source) or source)
    text = _read(source)
    folder = os.path.dirname(os.path.abspath(source))
    model = loads(text, source=source, validate=validate, library=library, folder=folder)
    if model.exposed:           # a definition: placed elsewhere, it is saved as a reference
        model.origin = (os.path.realpath(source), "file", dumps(model))
    return model


def _read(source):
    """The text of a model file, refused past MAX_FILE_SIZE or when not UTF-8."""
    too_big = f"{source}: larger than {MAX_FILE_SIZE // 2**20} MiB, too large for a model file"
    try:
        with open(source, "rb") as fh:
            info = os.fstat(fh.fileno())
            if stat.S_ISREG(info.st_mode) and info.st_size > MAX_FILE_SIZE:
                raise ModelError(f"{too_big} ({info.st_size} bytes)")
            # at most one byte past the limit: a device or a pipe without end is refused by
            # size, not read until memory runs out
            raw = fh.read(MAX_FILE_SIZE + 1)
    except OSError as exc:
        raise ModelError(f"{source}: cannot read the file ({exc.strerror or exc})") from exc
    if len(raw) > MAX_FILE_SIZE:
        raise ModelError(too_big)
    try:
        return raw.decode("utf-8-sig")     # tolerate the BOM some editors write
    except UnicodeDecodeError as exc:
        raise ModelError(f"{source}: not UTF-8 text (byte {exc.start})") from None


def examples_folder():
    """Where the example models are: ``kinetwork/models`` inside the package (a link to the
    source tree's ``models/`` in a checkout), else ``models/`` next to the package; None when
    neither exists."""
    package = pathlib.Path(__file__).resolve().parent.parent
    for candidate in (package / "models", package.parent / "models"):
        if candidate.is_dir():
            return candidate.resolve()
    return None


def example_file(name):
    """The installed example a relative path that does not exist names, or None: the
    example's name (``"double_pendulum"``, ``"engine_v6/EngineV6"``), with ``.json`` or
    as the checkout's ``models/...json`` (so the paths of the docs and of a checkout work
    wherever the package is installed)."""
    text = os.fspath(name).replace(os.sep, "/")
    root = examples_folder()
    if root is None or os.path.isabs(text) or not text or ".." in text.split("/"):
        return None
    key = text[len("models/"):] if text.startswith("models/") else text
    key = key[:-len(".json")] if key.endswith(".json") else key
    found = root / f"{key}.json"
    return found if found.is_file() else None


def loads(text: str | bytes, source: str | None = None, validate: bool = True,
          library: Iterable[str | os.PathLike] | None = None,
          folder: str | os.PathLike | None = None) -> Model:
    """Read a model from JSON text, as :func:`load` does.

    Parameters
    ----------
    text : str
    source : str, optional
        Where the text came from, prefixed to every message.
    library : list of folders, optional
        As for :func:`load`.
    folder : str, optional
        The folder file references of ``definitions`` are relative to (and may not leave);
        without it a text may not reference files.
    """
    if not isinstance(text, (str, bytes, bytearray)):
        raise ModelError(at_source(source, f"expected JSON text, got {type(text).__name__}"))
    if len(text) > MAX_FILE_SIZE:
        raise ModelError(at_source(source, f"{len(text)} characters, more than the "
                                     f"{MAX_FILE_SIZE} a model may have"))
    return model_from_dict(_parse(text, source), source=source, validate=validate,
                           context=Context.top(folder, library))


def _parse(text, source):
    """The JSON of a model text (keys given twice remembered), or a ModelError saying where
    it stops being JSON."""
    try:
        return json.loads(text, object_pairs_hook=JSONObject.from_pairs, parse_int=read_int)
    except json.JSONDecodeError as exc:
        end = " (the text ends early: truncated?)" if exc.pos >= len(text.rstrip()) else ""
        raise ModelError(at_source(source, f"line {exc.lineno} column {exc.colno}: invalid JSON: "
                                     f"{exc.msg}{end}")) from None
    except (ValueError, RecursionError) as exc:
        raise ModelError(at_source(source, f"invalid JSON ({exc})")) from None


def model_from_dict(data, source=None, validate=True, context=None):
    """Build a Model from a file's parsed JSON, or refuse it whole.

    Parameters
    ----------
    data : dict
        The top-level object.
    source : str, optional
        File name, prefixed to every message.
    validate : bool, optional
        Also run ``Model.validate`` (wiring, loops, names used in expressions).
    context : Context, optional
        Where subsystem definitions are found (default: no folder, the library of
        ``KINETWORK_LIBRARY``).
    """
    problems = []
    context = context or Context.top(None, None)
    model = attempt(problems, "top level", _build, data, problems, context)
    if problems:
        raise ModelError([at_source(source, p) for p in problems])
    if validate:
        try:
            # a definition (a model with exposed ports) is wired where it is placed: alone,
            # only its values are checked
            model.numeric_values() if model.exposed else model.validate()
        except ModelError as exc:
            raise ModelError([at_source(source, p) for p in exc.problems]) from None
    return model


def _build(data, problems, context):
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
    _body(model, data, problems, context)
    model.simulation = _simulation(data.get("simulation", {}), problems)
    found = check_initial(data.get("initial", {}))
    problems.extend(Problem.of(p, path="initial") for p in found)
    if not found:
        model.initial = data.get("initial", {})
    return model


def _body(model, data, problems, context):
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


# -- subsystem definitions ---------------------------------------------------------------------
class Context:
    """Where the definitions a file's components name are found, and what is being read.

    A type that is no kinetwork component names a definition: one of the file's own
    ``definitions`` (inline, or ``{"file": "parts/cylinder.json"}`` relative to the file and
    inside ``root``), else ``<type>.json`` in the file's folder, else in a library folder.
    Files are read once per load, so a definition used by many files is one Model.
    """

    def __init__(self, folder, root, library, chain, cache, where=""):
        self.folder, self.root, self.library = folder, root, library
        self.chain, self.cache, self.where = chain, cache, where
        #: the file's definitions section; name -> Model, or None for one that failed
        self.entries, self.built, self.building = {}, {}, []

    @classmethod
    def top(cls, folder, library):
        extra = [d for d in os.environ.get(LIBRARY_ENV, "").split(os.pathsep) if d]
        folders = [os.path.abspath(os.fspath(d)) for d in [*(library or []), *extra]]
        real = os.path.realpath(folder) if folder else None
        return cls(real, real, folders, [], {})

    def file(self, entries):
        """The context of one file, whose ``definitions`` section holds ``entries``."""
        ctx = Context(self.folder, self.root, self.library, self.chain, self.cache, self.where)
        ctx.entries = entries
        return ctx

    def inline(self, name):
        """The context of an inline definition: the same file, its places prefixed."""
        ctx = Context(self.folder, self.root, self.library, self.chain, self.cache,
                      f"definitions.{name}.")
        ctx.entries, ctx.built, ctx.building = self.entries, self.built, self.building
        return ctx

    def build_all(self, problems):
        """Every definition of the file (a file keeps those no component uses yet)."""
        out = {}
        for name in self.entries:
            model = attempt(problems, f"definitions.{cut(name)}", self.definition, name,
                             f"definitions.{cut(name)}", path=f"definitions.{cut(name)}")
            if model is not None:
                out[name] = model
        return out

    def definition(self, name, place):
        """The Model of definition ``name``, or a ModelError naming where it was looked for."""
        if name in self.built and name not in self.building:
            if self.built[name] is None:
                raise ModelError(f"definition {name!r} has problems (listed with it)")
            return self.built[name]
        if name in self.building:
            cycle = " places ".join(self.building[self.building.index(name):] + [name])
            raise ModelError(f"definitions place each other in a cycle: {cycle}")
        if name not in self.entries:
            model = self.built[name] = self._library(name, place)   # a miss says so each time
            return model
        self.built[name] = None
        self.building.append(name)
        try:
            model = self._entry(name, self.entries[name])
        finally:
            self.building.pop()
        self.built[name] = model
        return model

    def _entry(self, name, entry):
        where = f"definitions.{cut(name)}"
        if isinstance(entry, dict) and "file" in entry:
            extra = [k for k in entry if k != "file"]
            if extra:
                raise ModelError(f"{where}: a reference has only the key 'file', got "
                                 f"{quote(extra[0])}")
            return self._file(name, entry["file"], self.root, "file")
        if not isinstance(entry, dict):
            raise ModelError(f'{where}: must be an object (a model\'s parts) or {{"file": '
                             f'"path.json"}}, got {_kind(entry)}')
        problems = []
        problems.extend(f"{where}: unknown key {quote(key)}{suggest(key, DEFINITION_KEYS)}; "
                        f"keys are {', '.join(DEFINITION_KEYS)}"
                        for key in entry if key not in DEFINITION_KEYS)
        model = Model(name)
        inner = []
        _body(model, entry, inner, self.inline(name))
        # an inline definition's paths are in the file too, under it
        problems.extend((p if p.startswith(where) else p.where(f"{where}.")).under(where)
                        for p in map(Problem.of, inner))
        if problems:
            raise ModelError(problems)
        return model

    def _library(self, name, place):
        folders = ([self.folder] if self.folder else []) + self.library
        for folder in folders:
            path = os.path.join(folder, f"{name}.json")
            if os.path.isfile(path):
                kind = "folder" if folder == self.folder else "library"
                root = self.root if kind == "folder" else os.path.realpath(folder)
                return self._file(name, f"{name}.json", root, kind, folder)
        looked = (f"; looked for {name}.json in " + ", ".join(folders)) if folders else ""
        raise ModelError(f"unknown type {quote(name, 60)}{type_suggestion(name)}: no "
                         f"kinetwork component, nor a definition in this file{looked}")

    def _file(self, name, ref, root, kind, folder=None):
        """Read the definition file ``ref`` (relative to the file being read)."""
        where = f"definitions.{cut(name)}" if kind == "file" else f"{name}.json"
        if not isinstance(ref, str) or not ref:
            raise ModelError(f"{where}: file must be a relative path, got {quote(ref)}")
        if "://" in ref or ref.startswith(("/", "\\")) or os.path.isabs(ref) or \
                (len(ref) > 1 and ref[1] == ":"):
            raise ModelError(f"{where} file {quote(ref)}: must be a path relative to the "
                             f"model's folder (no URL, no absolute path)")
        base = folder or self.folder
        if base is None:
            raise ModelError(f"{where} file {quote(ref)}: a model read from text has no folder "
                             f"to find it in (load the file, or pass folder=)")
        path = os.path.realpath(os.path.join(base, ref))
        if os.path.commonpath([path, root]) != root:
            raise ModelError(f"{where} file {quote(ref)}: leaves the model's folder {root}; "
                             f"definitions must be inside it")
        if path in self.chain:
            files = [os.path.relpath(p, root) for p in self.chain[self.chain.index(path):]]
            raise ModelError(f"{where} file {quote(ref)}: files reference each other in a "
                             f"cycle: {' references '.join(files + [files[0]])}")
        if path not in self.cache:
            source = os.path.relpath(path, root)
            ctx = Context(os.path.dirname(path), root, self.library, [*self.chain, path],
                          self.cache)
            model = model_from_dict(_parse(_read(path), source), source=source,
                                    validate=False, context=ctx)
            model.origin = (path, kind, dumps(model))
            self.cache[path] = model
        model = self.cache[path]
        if model.name != name:
            raise ModelError(f"{where} file {quote(ref)}: holds model {quote(model.name)}, "
                             f"not {quote(name)} (a definition file's name is its type)")
        return model


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
