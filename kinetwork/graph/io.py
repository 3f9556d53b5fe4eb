"""JSON model files (format "kinetwork.model", version 1): load, save and their refusals.

A file names component types, never code: types resolve only through the component
``REGISTRY`` and parameter strings go through the safe expression parser, so loading executes
nothing from the file. Every problem is reported with its place in the file
(``components[3] "mass1" params.mass``), all in one ``ModelError``; a model is returned only
when the whole file is sound.
"""

import json
import math
import os
import stat

from ..components.base import _NAME, NAME_LIMIT, REGISTRY
from ..errors import ModelError
from ..util import QUOTE_LIMIT, quote, suggest
from .model import Model, model_name_problem, text_problem
from .settings import check_setting, check_steps
from .writer import FORMAT, KEYS, VERSION, _kind, _plain, dumps, model_to_dict, save

SUPPORTED = (1,)
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
def load(path, validate=True):
    """Read a model file.

    Parameters
    ----------
    path : str or os.PathLike
    validate : bool, optional
        Also check the wiring (``Model.validate``); False reads a model saved half-built.

    Returns
    -------
    Model

    Raises
    ------
    ModelError
        Every problem with the file, each message starting with the file name and the place.
    """
    source = os.fspath(path)
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
        text = raw.decode("utf-8-sig")     # tolerate the BOM some editors write
    except UnicodeDecodeError as exc:
        raise ModelError(f"{source}: not UTF-8 text (byte {exc.start})") from None
    return loads(text, source=source, validate=validate)


def loads(text, source=None, validate=True):
    """Read a model from JSON text, as :func:`load` does.

    Parameters
    ----------
    text : str
    source : str, optional
        Where the text came from, prefixed to every message.
    """
    if not isinstance(text, (str, bytes, bytearray)):
        raise ModelError(_at(source, f"expected JSON text, got {type(text).__name__}"))
    if len(text) > MAX_FILE_SIZE:
        raise ModelError(_at(source, f"{len(text)} characters, more than the "
                                     f"{MAX_FILE_SIZE} a model may have"))
    try:
        data = json.loads(text, object_pairs_hook=_Object.from_pairs, parse_int=_int)
    except json.JSONDecodeError as exc:
        end = " (the text ends early: truncated?)" if exc.pos >= len(text.rstrip()) else ""
        raise ModelError(_at(source, f"line {exc.lineno} column {exc.colno}: invalid JSON: "
                                     f"{exc.msg}{end}")) from None
    except (ValueError, RecursionError) as exc:
        raise ModelError(_at(source, f"invalid JSON ({exc})")) from None
    return model_from_dict(data, source=source, validate=validate)


def model_from_dict(data, source=None, validate=True):
    """Build a Model from a file's parsed JSON, or refuse it whole.

    Parameters
    ----------
    data : dict
        The top-level object.
    source : str, optional
        File name, prefixed to every message.
    validate : bool, optional
        Also run ``Model.validate`` (wiring, loops, names used in expressions).
    """
    problems = []
    model = _attempt(problems, "top level", _build, data, problems)
    if problems:
        raise ModelError([_at(source, p) for p in problems])
    if validate:
        try:
            model.validate()
        except ModelError as exc:
            raise ModelError([_at(source, p) for p in exc.problems]) from None
    return model


def _build(data, problems):
    if not isinstance(data, dict):
        problems.append(f"top level: must be an object {{...}}, got {_kind(data)}")
        return None
    _repeated(data, "", problems)
    problems.extend(f"{quote(key)}: unknown key{suggest(key, KEYS)}; keys are "
                    f"{', '.join(KEYS)}" for key in data if key not in KEYS)
    problems.extend(f"{key}: required key missing" for key in REQUIRED if key not in data)
    # another format or version: whatever else looks wrong is noise, so stop here
    fmt, version = data.get("format", FORMAT), data.get("version", VERSION)
    if fmt != FORMAT:
        problems.append(f"format: {quote(fmt)} is not a kinetwork model file "
                        f"(expected {FORMAT!r})")
        return None
    if type(version) is not int or version not in SUPPORTED:
        problems.append(f"version: {quote(version)} is not supported; this kinetwork reads "
                        f"version "
                        f"{', '.join(map(str, SUPPORTED))}")
        return None
    name = data.get("name", "unnamed")
    problem = model_name_problem(name)
    if problem:
        problems.append(f"name: {problem}")
        name = "unnamed"
    model = Model(name)
    model.description = data.get("description", "")
    if not isinstance(model.description, str):
        problems.append(f"description: must be a string, got {_kind(model.description)}")
    elif (problem := text_problem(model.description, allowed="\t\n\r")):
        problems.append(f"description: {problem}")
    parameters = data.get("parameters", {})
    if not isinstance(parameters, dict):
        problems.append(f"parameters: must be an object of numbers, got {_kind(parameters)}")
    else:
        for key, value in parameters.items():
            if not _NAME.fullmatch(key):     # said here with the name cut
                problems.append(f"parameters: parameter name {quote(key)}: must be an "
                                f"identifier (letters, digits, underscore; not starting with a "
                                f"digit; at most {NAME_LIMIT} characters)")
            else:
                _attempt(problems, "parameters", model.set_parameter, key, value)
    broken = (_components(model, data["components"], problems) if "components" in data
              else {UNNAMED})
    _connections(model, data.get("connections", []), broken, problems)
    model.simulation = _simulation(data.get("simulation", {}), problems)
    model.layout = _attempt(problems, "layout", _layout, model, data.get("layout", {}),
                            broken, problems)
    return model


def _components(model, entries, problems):
    """Add each entry; return the names of the failed ones, whose wiring goes unchecked."""
    if not isinstance(entries, list):
        problems.append(f"components: must be a list, got {_kind(entries)}")
        return {UNNAMED}
    broken, seen = set(), {}
    for i, entry in enumerate(entries):
        name = entry.get("name") if isinstance(entry, dict) else None
        place = f'components[{i}] "{_cut(name)}"' if isinstance(name, str) else \
            f"components[{i}]"
        if isinstance(name, str) and name in seen:
            problems.append(f"{place}: duplicate name, already used by components[{seen[name]}]")
            continue
        before = len(problems)
        comp = _attempt(problems, place, _component, entry, place, problems)
        if isinstance(name, str):
            seen[name] = i
        if comp is None or len(problems) > before:
            broken.add(name if isinstance(name, str) else UNNAMED)
        else:
            model.add(comp)
            model.places[comp.name] = place
    return broken


def _component(entry, place, problems):
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
    if not isinstance(kind, str) or kind not in REGISTRY:
        # resolved only through the registry: a dotted path in a file is never imported
        problems.append(f"{place}: unknown type {quote(kind, 60)}{suggest(kind, REGISTRY)}")
        return None
    if not isinstance(params, dict):
        problems.append(f"{place} params: must be an object, got {_kind(params)}")
        return None
    return REGISTRY[kind].from_params(entry["name"], params,
                                      place=lambda key: f"{place} params.{_cut(key)}")


def _connections(model, pairs, broken, problems):
    if not isinstance(pairs, list):
        problems.append(f"connections: must be a list of pairs, got {_kind(pairs)}")
        return
    for i, pair in enumerate(pairs):
        if not isinstance(pair, list) or len(pair) != 2:
            problems.append(f'connections[{i}]: must be a pair ["component.port", '
                            f'"component.port"], got {quote(pair, 80)}')
            continue
        refs = []
        for j, ref in enumerate(pair):
            place = f'connections[{i}][{j}] "{_cut(ref)}"' if isinstance(ref, str) else \
                f"connections[{i}][{j}]"
            refs.append(_attempt(problems, place, _port, model, ref, broken))
        if all(refs):
            _attempt(problems, f"connections[{i}]", model.connect, *refs)


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


def _simulation(settings, problems):
    """The experiment settings, checked as ``simulate`` will use them."""
    if not isinstance(settings, dict):
        problems.append(f"simulation: must be an object, got {_kind(settings)}")
        return {}
    found = [p for p in (check_setting(k, v) for k, v in settings.items()) if p]
    if not found and "step" in settings and "t_end" in settings:     # what they cost together
        found = [p for p in [check_steps(settings["t_end"], settings["step"])] if p]
    problems.extend(found)
    return dict(settings)


def _layout(model, layout, broken, problems):
    """Editor positions: any JSON per component, kept as is."""
    if not isinstance(layout, dict):
        problems.append(f"layout: must be an object keyed by component name, got {_kind(layout)}")
        return {}
    for key, value in layout.items():
        if key not in model.components and key not in broken and UNNAMED not in broken:
            problems.append(f"layout.{_cut(key)}: no component {quote(key)}"
                            f"{suggest(key, model.components)}")
        _plain(value, f"layout.{_cut(key)}", problems)
    return _copy(layout)


# -- helpers ----------------------------------------------------------------------------------
class _Object(dict):
    """A parsed JSON object that remembers keys given twice (``json`` keeps the last)."""

    @classmethod
    def from_pairs(cls, pairs):
        obj = cls()
        obj.repeated = []
        for key, value in pairs:
            if key in obj:
                obj.repeated.append(key)
            obj[key] = value
        return obj


def _repeated(value, where, problems):
    if isinstance(value, dict):
        problems.extend(f"{where or 'top level'}: key {quote(key)} appears more than once"
                        for key in getattr(value, "repeated", ()))
        for key, item in value.items():
            _repeated(item, f"{where}.{_cut(key)}" if where else _cut(key), problems)
    elif isinstance(value, list):
        for j, item in enumerate(value):
            _repeated(item, f"{where}[{j}]", problems)


def _attempt(problems, place, fn, *args):
    """``fn(*args)``, or None with its failure recorded as a problem at ``place``."""
    try:
        return fn(*args)
    except ModelError as exc:
        problems.extend(p if p.startswith(place) else f"{place}: {p}" for p in exc.problems)
    except Exception as exc:    # noqa: BLE001
        # odd shapes in a file reach code written for well-formed values: a file may be
        # refused, but never crash the loader
        problems.append(f"{place}: cannot be read ({type(exc).__name__}: "
                        f"{_cut(str(exc), QUOTE_LIMIT)})")
    return None


def _int(text):
    # an integer beyond float range would overflow in later bounds checks: read it as the
    # infinity it amounts to, then refused as non-finite at its place
    try:
        value = int(text)
        float(value)
        return value
    except (ValueError, OverflowError):
        return -math.inf if text.startswith("-") else math.inf


def _copy(value):
    # plain dicts and lists in the model, not the parser's _Object
    return ({k: _copy(v) for k, v in value.items()} if isinstance(value, dict) else
            [_copy(v) for v in value] if isinstance(value, list) else value)


def _at(source, problem):
    return f"{source}: {problem}" if source else problem


def _cut(text, limit=NAME_LIMIT):
    """Text from the file for a message's place: as it is when short, else cut; characters
    that do not print (a newline, a lone surrogate) escaped as in Python."""
    text = text if len(text) <= limit else text[:limit - 3] + "..."
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


