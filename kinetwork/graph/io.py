"""JSON model files (format "kinetwork.model", version 1): load, save and their refusals.

This module reads files (bounded, parsed, counted) and finds the definitions their types
name (``Context``); ``sections`` reads each section into the Model, ``writer`` writes one.

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

from ..components.base import type_suggestion
from ..errors import ModelError, Problem
from ..util import quote, read_bounded, suggest
from .model import Model
from .reading import JSONObject, TooDeep, at_source, attempt, cut, read_int
from .sections import body, build
from .subsystem import DEPTH_LIMIT, MAX_COMPONENTS, MAX_CONNECTIONS
from .writer import (DEFINITION_KEYS, FORMAT, KEYS, KEYS_V2, VERSION,  # noqa: F401
                     _kind, dumps, model_to_dict, save)

#: folders of subsystem files, after a file's own definitions and its folder
LIBRARY_ENV = "KINETWORK_LIBRARY"
__all__ = ["FORMAT", "KEYS", "VERSION", "dumps", "load", "loads", "model_from_dict",
           "model_to_dict", "save"]
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
    model.path = os.path.abspath(source)
    if model.exposed:           # a definition: placed elsewhere, it is saved as a reference
        model.origin = (os.path.realpath(source), "file", dumps(model))
    return model


def _read(source):
    """The text of a model file, refused past MAX_FILE_SIZE or when not UTF-8."""
    too_big = f"{source}: larger than {MAX_FILE_SIZE // 2**20} MiB, too large for a model file"
    try:
        info = os.stat(source)
        if stat.S_ISREG(info.st_mode) and info.st_size > MAX_FILE_SIZE:
            raise ModelError(f"{too_big} ({info.st_size} bytes)")
        # at most one byte past the limit: a device or a pipe without end is refused by
        # size, not read until memory runs out; a FIFO without a writer does not block
        raw = read_bounded(source, MAX_FILE_SIZE)
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


#: a text longer than this is first read by the JSON parser alone, its lists counted before
#: the slower reading that remembers repeated keys (1.2 M components in 39 MB: refused in
#: 0.8 s and 430 MB instead of 9 s and 1 GB)
COUNT_FIRST = 1 << 20


def _parse(text, source):
    """The JSON of a model text (keys given twice remembered), or a ModelError saying where
    it stops being JSON."""
    try:
        if len(text) > COUNT_FIRST:
            _count(json.loads(text, parse_int=read_int), source)
        return json.loads(text, object_pairs_hook=JSONObject.from_pairs, parse_int=read_int)
    except ModelError:
        raise
    except json.JSONDecodeError as exc:
        end = " (the text ends early: truncated?)" if exc.pos >= len(text.rstrip()) else ""
        raise ModelError(at_source(source, f"line {exc.lineno} column {exc.colno}: invalid JSON: "
                                     f"{exc.msg}{end}")) from None
    except (ValueError, RecursionError) as exc:
        raise ModelError(at_source(source, f"invalid JSON ({exc})")) from None


def _count(data, source):
    """Refuse a model whose lists of components or connections (at the top or in an inline
    definition) are longer than a model may have, as reading its ``sections`` would, before
    the file is read again object by object."""
    if not isinstance(data, dict):
        return
    bodies = [("", data)]
    definitions = data.get("definitions")
    if isinstance(definitions, dict):
        bodies += [(f"definitions.{cut(name)}.", body) for name, body in definitions.items()
                   if isinstance(body, dict)]
    problems = [f"{where}{key}: {len(body[key])} entries, more than the {limit} a model "
                f"may have"
                for where, body in bodies
                for key, limit in (("components", MAX_COMPONENTS),
                                   ("connections", MAX_CONNECTIONS))
                if isinstance(body.get(key), list) and len(body[key]) > limit]
    if problems:
        raise ModelError([at_source(source, p) for p in problems])


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
    model = attempt(problems, "top level", build, data, problems, context)
    if problems:
        raise ModelError([at_source(source, p) for p in problems])
    if validate:
        try:
            # a definition (a model with exposed ports) is wired where it is placed: alone,
            # only its values are checked
            model.numeric_values() if model.exposed else model.validate()
        except ModelError as exc:
            raise ModelError([at_source(source, p) for p in exc.problems], exc.count) from None
    return model


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
        if len(self.building) + len(self.chain) >= DEPTH_LIMIT:
            raise TooDeep(f"definitions nested more than {DEPTH_LIMIT} deep: "
                          f"{' places '.join(map(cut, self.building[:3]))} places ... places "
                          f"{cut(name)}")
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
        body(model, entry, inner, self.inline(name))
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


