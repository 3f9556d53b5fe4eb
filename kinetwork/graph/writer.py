"""Writing model files (format "kinetwork.model"): the model as plain JSON, saved atomically.

What ``kinetwork.graph.io`` would refuse for its form is refused here, so a saved file always
reads back.
"""

import copy
import json

from ..components.base import REGISTRY
from ..errors import ModelError
from ..util import atomic_write, finite
from .settings import check_setting

FORMAT, VERSION = "kinetwork.model", 1
#: top-level keys, in the order files are written
KEYS = ("format", "version", "name", "description", "parameters", "components", "connections",
        "simulation", "layout")
#: a list of scalars stays on one line up to this many characters
WIDTH = 80


def model_to_dict(model):
    """The model as a file's top-level object: plain JSON values, in file order.

    Component ``params`` hold only what was given, so a later change of a default reaches old
    files. A model may be incomplete (an editor saves work in progress), but what :func:`load`
    would refuse for its form is refused here, so a saved file always reads back.

    Raises
    ------
    ModelError
        A component type not in the registry, a bad ``simulation`` block, a layout entry for
        no component, or a value that is not plain, finite JSON; each with its place.
    """
    problems, components = [], []
    for i, comp in enumerate(model.components.values()):
        if REGISTRY.get(comp.type_name) is not type(comp):
            problems.append(f'components[{i}] "{comp.name}": type {type(comp).__name__} is not '
                            f"in the component registry, so no file could load it")
        components.append({"name": comp.name, "type": comp.type_name,
                           "params": copy.deepcopy(comp.given)})
    data = {"format": FORMAT, "version": VERSION, "name": model.name,
            "description": "" if model.description is None else model.description,
            "parameters": dict(model.parameters), "components": components,
            "connections": [[a.path, b.path] for a, b in model.connections],
            "simulation": copy.deepcopy(model.simulation), "layout": copy.deepcopy(model.layout)}
    if not isinstance(data["description"], str):
        problems.append(f"description: must be a string, got {_kind(data['description'])}")
    if isinstance(data["simulation"], dict):
        problems.extend(filter(None, (check_setting(k, v) for k, v in data["simulation"].items())))
    else:
        problems.append(f"simulation: must be an object, got {_kind(data['simulation'])}")
    if isinstance(data["layout"], dict):
        problems.extend(f"layout.{key}: no component {key!r}" for key in data["layout"]
                        if key not in model.components)
    _plain(data, "", problems)
    if problems:
        raise ModelError(problems)
    return data


def dumps(model):
    """The file's text for ``model``.

    Indented JSON with the keys in file order, short lists of scalars on one line (vectors,
    matrix rows, connection pairs) and a final newline; numbers keep their Python form.

    Returns
    -------
    str
    """
    return _render(model_to_dict(model), 0) + "\n"


def save(model, path):
    """Write ``model`` to ``path`` atomically: a failed save leaves the old file whole.

    The text goes to a temporary file in the same folder, is flushed to disk, then replaces
    ``path`` in one step; on any failure the temporary file is removed.

    Parameters
    ----------
    model : Model
    path : str or os.PathLike

    Raises
    ------
    ModelError
        The model cannot be written as a file (see :func:`model_to_dict`); nothing is written.
    OSError
        The file system refused; the old file is unchanged.
    """
    text = dumps(model).encode("utf-8")       # every refusal comes before the disk is touched

    def write(tmp):
        with open(tmp, "wb") as fh:
            fh.write(text)
    atomic_write(path, write)


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
