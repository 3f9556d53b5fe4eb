"""The example models that ship inside the package: find one by name, list them, copy one out.

An example's name is its path in the examples folder without ``.json``
(``double_pendulum``, ``engine_v6/EngineV6``). Subsystem definitions (files with exposed
``ports``) are parts of other examples, not examples of their own; copying an example copies
the definition files it places with it.

>>> import kinetwork as kn
>>> model = kn.load(kn.examples.path("double_pendulum"))
"""

import difflib
import functools
import json
import os
import pathlib

from .components import REGISTRY
from .errors import ModelError
from .graph.io import examples_folder
from .outputs import write

SUFFIX = ".json"
#: folders the listing does not look into
_SKIPPED = {"__pycache__", "node_modules"}


def folder():
    """Where the example models are (``kinetwork/models`` inside the package), or None."""
    return examples_folder()


@functools.lru_cache(maxsize=1)
def _catalogue():
    root = folder()
    if root is None:
        return {}
    found = {}
    for dirpath, dirs, names in os.walk(root):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in _SKIPPED)
        for name in sorted(names):
            if not name.endswith(SUFFIX) or name.startswith("."):
                continue
            file = pathlib.Path(dirpath) / name
            data = _read(file)
            if isinstance(data, dict) and data.get("format") == "kinetwork.model" and \
                    not data.get("ports"):
                rel = file.relative_to(root).as_posix()[:-len(SUFFIX)]
                found[rel] = (file, _summary(data))
    return dict(sorted(found.items()))


def names():
    """Example name -> its file (a ``pathlib.Path``), sorted by name."""
    return {name: file for name, (file, _) in _catalogue().items()}


def summaries():
    """Example name -> its one-line summary (the first sentence of its description)."""
    return {name: line for name, (_, line) in _catalogue().items()}


def path(name):
    """The file of the example ``name`` (``"double_pendulum"``; ``.json`` may be given).

    Raises
    ------
    ModelError
        No example of that name; the message lists the closest names.
    """
    key = str(name)[:-len(SUFFIX)] if str(name).endswith(SUFFIX) else str(name)
    known = names()
    if key in known:
        return known[key]
    raise ModelError(f"{name}: no such example ({_suggest(key, known)})")


def data(name):
    """The file ``name`` shipped beside the examples that is no model: a robot's URDF
    (``"robots/industrial_arm.urdf"``), for the docs and a first try of ``kn.from_urdf``.

    Raises
    ------
    ModelError
        No such file there; the message lists the files that are.
    """
    root = folder()
    shipped = {} if root is None else {
        f.relative_to(root).as_posix(): f for f in sorted(root.rglob("*"))
        if f.is_file() and f.suffix != SUFFIX and not any(
            part.startswith(".") or part in _SKIPPED for part in f.relative_to(root).parts)}
    if str(name) in shipped:
        return shipped[str(name)]
    close = difflib.get_close_matches(str(name), shipped, n=3, cutoff=0.5)
    hint = f"did you mean {' or '.join(close)}?" if close else \
        f"there are: {', '.join(shipped) or 'none'}"
    raise ModelError(f"{name}: no such file beside the examples ({hint})")


def copy(name, destination="."):
    """Copy the example ``name`` and the definition files it places into the folder
    ``destination`` (made if missing); returns the paths written, the model's first.

    Nothing is overwritten: if any of the files already exists there, nothing is copied.

    Raises
    ------
    ModelError
        No such example, a file that would be overwritten, or a folder that cannot be written.
    """
    source = path(name)
    root = source.parent
    files = [source] + _placed_definitions(source)
    dest = pathlib.Path(destination)
    targets = [dest / f.relative_to(root) for f in files]
    existing = [str(t) for t in targets if t.exists() or t.is_symlink()]
    if existing:
        raise ModelError(f"copying example {name!r}: {', '.join(existing)} already exist"
                         f"{'s' if len(existing) == 1 else ''}; nothing was copied (choose "
                         f"another folder, or move the file{'s' if len(existing) > 1 else ''}"
                         f" away)")
    try:
        for src, target in zip(files, targets):
            target.parent.mkdir(parents=True, exist_ok=True)
            data = src.read_bytes()
            write(target, lambda tmp, data=data: pathlib.Path(tmp).write_bytes(data), "model")
    except OSError as exc:
        raise ModelError(f"copying example {name!r} to {destination}: "
                         f"{exc.strerror or exc}") from None
    return targets


# -- helpers ------------------------------------------------------------------------------------
def _read(file):
    try:
        return json.loads(file.read_text(encoding="utf-8-sig"))
    except (OSError, ValueError):
        return None


def _summary(data):
    text = " ".join(str(data.get("description") or data.get("name") or "").split())
    for end in (". ", ": "):
        if end in text:
            text = text.split(end, 1)[0] + ("." if end == ". " else "")
            break
    return text if len(text) <= 100 else text[:97].rstrip() + "..."


def _placed_definitions(source):
    """The definition files next to ``source`` that it places (by ``{"file": ...}`` or as
    ``TYPE.json`` beside it), and theirs in turn, each once."""
    seen, out, todo = {source.resolve()}, [], [source]
    while todo:
        data = _read(todo.pop())
        if not isinstance(data, dict):
            continue
        for file in _references(data, source.parent):
            real = file.resolve()
            if real not in seen and file.is_file():
                seen.add(real)
                out.append(file)
                todo.append(file)
    return out


def _references(data, here):
    definitions = data.get("definitions") or {}
    inline = [d for d in definitions.values() if isinstance(d, dict) and "file" not in d]
    for d in definitions.values():
        if isinstance(d, dict) and isinstance(d.get("file"), str):
            yield here / d["file"]
    for body in [data] + inline:
        for comp in body.get("components") or []:
            kind = comp.get("type") if isinstance(comp, dict) else None
            if isinstance(kind, str) and kind not in REGISTRY and kind not in definitions:
                yield here / f"{kind}{SUFFIX}"


def close_names(name):
    """Up to three example names close to ``name`` (a typo's likely meaning), best first."""
    import difflib
    key = str(name)[:-len(SUFFIX)] if str(name).endswith(SUFFIX) else str(name)
    return difflib.get_close_matches(key, list(names()), n=3, cutoff=0.5)


def _suggest(key, known):
    close = close_names(key)
    if close:
        return "did you mean " + " or ".join(close) + "?"
    return ("'kinetwork examples' lists them" if known else
            "no examples are installed with this copy of kinetwork")
