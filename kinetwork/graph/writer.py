"""Writing model files (format "kinetwork.model"): the model as plain JSON, saved atomically.

What ``kinetwork.graph.io`` would refuse for its form is refused here, so a saved file always
reads back.
"""

from __future__ import annotations

import copy
import json
import os
from typing import TYPE_CHECKING

from ..components.base import _NAME, REGISTRY
from ..errors import ModelError
from ..outputs import check, filler, model_files, write
from ..util import finite
from .initial import check_initial
from .settings import check_setting
from .subsystem import Subsystem

if TYPE_CHECKING:                     # annotations only: model.py imports this module
    from .model import Model

#: the newest version; a model is written in the smallest version that holds it: 1 unless it
#: has subsystems or exposed ports
FORMAT, VERSION = "kinetwork.model", 2
#: top-level keys, in the order files are written (version 1, and version 2's)
KEYS = ("format", "version", "name", "description", "parameters", "components", "connections",
        "simulation", "initial", "layout")
KEYS_V2 = ("format", "version", "name", "description", "parameters", "ports", "components",
           "connections", "simulation", "initial", "layout", "definitions")
#: what an inline definition holds
DEFINITION_KEYS = ("description", "parameters", "ports", "components", "connections", "layout")
#: a list of scalars stays on one line up to this many characters
WIDTH = 80


def model_to_dict(model, folder=None):
    """The model as a file's top-level object: plain JSON values, in file order.

    Component ``params`` hold only what was given, so a later change of a default reaches old
    files. A model may be incomplete (an editor saves work in progress), but what :func:`load`
    would refuse for its form is refused here, so a saved file always reads back.

    A model without subsystems or exposed ports is written as version 1, as before there were
    any. Otherwise (version 2) the definitions its subsystems place go in ``definitions``:
    a definition read from a file and unchanged since as a reference to that file (relative
    to ``folder``, the folder the file is written to, when it lies inside it), one read from
    a library folder not at all (found there again), any other inline.

    Raises
    ------
    ModelError
        A component type not in the registry, a bad ``simulation`` block, a layout entry for
        no component, two definitions of one name, or a value that is not plain, finite
        JSON; each with its place.
    """
    problems = []
    body = _body(model, problems, "")
    definitions = _definitions(model, folder, problems)
    v2 = bool(model.exposed or definitions or any(
        isinstance(c, Subsystem) for c in model.components.values()))
    data = {"format": FORMAT, "version": 2 if v2 else 1, "name": model.name,
            **body, "simulation": copy.deepcopy(model.simulation)}
    if getattr(model, "initial", None):           # written only when asked for
        problems.extend(check_initial(model.initial))
        data["initial"] = copy.deepcopy(model.initial)
    data["layout"] = data.pop("layout")
    if v2:
        data = {key: data[key] for key in KEYS_V2 if key in data}
        if not model.exposed:
            del data["ports"]
        if definitions:
            data["definitions"] = definitions
    else:
        del data["ports"]
    if isinstance(data["simulation"], dict):
        problems.extend(filter(None, (check_setting(k, v) for k, v in data["simulation"].items())))
    else:
        problems.append(f"simulation: must be an object, got {_kind(data['simulation'])}")
    _plain(data, "", problems)
    if problems:
        raise ModelError(problems)
    return data


def _body(model, problems, where):
    """What a file and an inline definition share, in file order."""
    components = []
    for i, comp in enumerate(model.components.values()):
        if not isinstance(comp, Subsystem) and REGISTRY.get(comp.type_name) is not type(comp):
            problems.append(f'{where}components[{i}] "{comp.name}": type '
                            f"{type(comp).__name__} is not in the component registry, so no "
                            f"file could load it")
        components.append({"name": comp.name, "type": comp.type_name,
                           "params": comp.written_params()})
    body = {"description": "" if model.description is None else model.description,
            "parameters": model.written_parameters(),     # "500 mm" as written
            "ports": {name: ref.path for name, ref in model.exposed.items()},
            "components": components,
            "connections": [[a.path, b.path] for a, b in model.connections],
            "layout": copy.deepcopy(model.layout)}
    if not isinstance(body["description"], str):
        problems.append(f"{where}description: must be a string, got "
                        f"{_kind(body['description'])}")
    if isinstance(body["layout"], dict):
        problems.extend(f"{where}layout.{key}: no component {key!r}" for key in body["layout"]
                        if key not in model.components)
    return body


def _definitions(model, folder, problems):
    """The ``definitions`` section: every definition the model keeps or places, nested ones
    of inline definitions too, by name."""
    out, seen = {}, {}

    def visit(m):
        placed = [c.definition for c in m.components.values() if isinstance(c, Subsystem)]
        for d in [*m.definitions.values(), *placed]:
            if d.name in seen:
                if seen[d.name] is not d:
                    problems.append(f"definitions.{d.name}: two different models are named "
                                    f"{d.name!r}; a file names a definition once (rename one)")
                continue
            seen[d.name] = d
            if not _NAME.fullmatch(d.name) or d.name in REGISTRY:
                problems.append(f"definitions.{d.name}: a definition's name is the type its "
                                f"instances have in a file: an identifier that names no "
                                f"kinetwork type, got {d.name!r} (rename the model)")
                continue
            entry = _reference(d, folder)
            if entry is None:
                entry = _body(d, problems, f"definitions.{d.name}.")
                entry = {k: v for k, v in entry.items() if v or k in ("components",)}
                visit(d)
            if entry:
                out[d.name] = entry
    visit(model)
    return out


def _reference(definition, folder):
    """How a file refers to a definition read from a file and unchanged since: ``{"file":
    relative path}``, or ``{}`` when a library (or the folder itself) finds it by name;
    None when it must be written inline."""
    if definition.origin is None:
        return None
    path, kind, text = definition.origin
    if dumps(definition) != text:
        return None                 # changed since it was read: the file keeps what it had
    if kind == "library":
        return {}
    if folder is None:
        return None
    folder = os.path.realpath(folder)
    if kind == "folder" and os.path.dirname(path) == folder:
        return {}
    rel = os.path.relpath(path, folder)
    if rel.startswith(os.pardir) or os.path.isabs(rel):
        return None
    return {"file": rel.replace(os.sep, "/")}


def dumps(model: Model, folder: str | os.PathLike | None = None) -> str:
    """The file's text for ``model`` (to be written in ``folder``: see :func:`model_to_dict`).

    Indented JSON with the keys in file order, short lists of scalars on one line (vectors,
    matrix rows, connection pairs) and a final newline; numbers keep their Python form.

    Returns
    -------
    str
    """
    return _render(model_to_dict(model, folder), 0) + "\n"


def render_json(data: dict) -> str:
    """A file's top-level object as text in the layout of :func:`dumps`, without reading it as
    a model: what an editor writes of work the reader would refuse (a required value still
    empty). Only plain, finite JSON is written.

    Raises
    ------
    ModelError
        A value that is not plain, finite JSON, with its place.
    """
    problems = []
    _plain(data, "", problems)
    if problems:
        raise ModelError(problems)
    return _render(data, 0) + "\n"


def save(model: Model, path: str | os.PathLike, overwrite: bool = False) -> None:
    """Write ``model`` to ``path`` under the output policy (``kinetwork.outputs``): atomically
    (a failed save leaves the old file whole), never over a file the model was read from
    (a definition file it references), a special file or a folder.

    Parameters
    ----------
    model : Model
    path : str or os.PathLike
    overwrite : bool
        Replace an existing file that is not a model file (a CSV, an image, other JSON...);
        a model file is replaced without it.

    Raises
    ------
    ModelError
        The model cannot be written as a file (see :func:`model_to_dict`), or the policy
        refuses the path (``OutputRefused``); nothing is written.
    OSError
        The file system refused; the old file is unchanged.
    """
    # its own file is saved over (that is what saving is); its definitions' files are read
    reads = [item for item in model_files(model) if item[0] != "the model file"]
    check(path, "model", reads=reads, force=overwrite)
    folder = os.path.dirname(os.path.abspath(os.fspath(path)))
    text = dumps(model, folder).encode("utf-8")   # every refusal before the disk is touched

    write(path, filler(text), "model", reads=reads, force=overwrite)


def _render(value, level):
    """JSON as ``indent=2`` writes it, but a short list of scalars on one line.

    So a vector, a matrix row and a connection pair each read on one line.
    """
    pad = "  " * level
    if isinstance(value, dict) and value:
        items = [f"{pad}  {json.dumps(k)}: {_render(v, level + 1)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + f"\n{pad}}}"
    if isinstance(value, (list, tuple)) and value:
        if not any(isinstance(v, (dict, list, tuple)) for v in value):
            flat = json.dumps(value, allow_nan=False)
            if len(flat) <= WIDTH:
                return flat
        items = [f"{pad}  {_render(v, level + 1)}" for v in value]
        return "[\n" + ",\n".join(items) + f"\n{pad}]"
    return json.dumps(value, allow_nan=False)


def _plain(value, where, problems):
    """Report what is not plain, finite JSON (a file holds no NaN and no Python objects)."""
    if isinstance(value, dict):
        for key, item in value.items():
            if not isinstance(key, str):
                problems.append(f"{where}: key {key!r} is not a string")
            _plain(item, f"{where}.{key}" if where else str(key), problems)
    elif isinstance(value, (list, tuple)):
        for j, item in enumerate(value):
            _plain(item, f"{where}[{j}]", problems)
    elif isinstance(value, (int, float)) and not finite(value):
        problems.append(f"{where}: must be finite, got {value!r:.40}")
    elif value is not None and not isinstance(value, (str, int, float)):
        problems.append(f"{where}: {type(value).__name__} is not a JSON value")


def _kind(value):
    kinds = ((dict, "an object"), (list, "a list"), (str, "a string"), (bool, "a boolean"),
             (type(None), "null"))
    return next((words for kind, words in kinds if isinstance(value, kind)), f"{value!r:.40}")
