"""What the studio tells the page about models: the palette, the checks of ``kn.load`` with
each problem placed on its block, and a layout for a diagram without one.

Nothing here is new judgement: the palette is read from the component declarations, and a
model is checked by ``kinetwork.graph.io.model_from_dict``, the checker behind ``kn.load``.
A problem goes to the page as the fields of its ``Problem`` record (``API.md``): nothing here
reads a message's text.
"""

import collections
import logging
import math
import os

import numpy as np

from ..components.base import REGISTRY
from ..errors import ModelError, Problem
from ..graph.io import Context, model_from_dict

log = logging.getLogger("kinetwork.studio")

#: the order of the libraries in the palette; any other follows, alphabetically
LIBRARY_ORDER = ("multibody", "rotational", "translational", "signals", "electrical", "probe")
#: a model is compiled to list its states only up to this many flat components: the
#: symbolic build takes about 50 ms for the seed and grows with the model
COMPILE_LIMIT = 400
#: problems sent to the page at most (a model of a million broken parts lists the first)
MAX_PROBLEMS = 200


# -- the palette -------------------------------------------------------------------------------
def palette():
    """Every type of the component REGISTRY, grouped by library (the part of the type name
    before the dot; ``Probe`` is in ``probe``), in declaration order."""
    groups = collections.defaultdict(list)
    for type_name, cls in REGISTRY.items():
        library = type_name.split(".")[0] if "." in type_name else type_name.lower()
        groups[library].append(type_info(type_name, cls))
    order = sorted(groups, key=lambda n: (LIBRARY_ORDER.index(n) if n in LIBRARY_ORDER
                                          else len(LIBRARY_ORDER), n))
    return {"libraries": [{"name": name, "types": groups[name]} for name in order]}


def type_info(type_name, cls):
    doc = (cls.__doc__ or "").strip().split("\n\n")[0]
    return {
        "type": type_name,
        "doc": " ".join(doc.split()),
        "ports": [{"name": name, "domain": port.domain, "doc": port.doc,
                   "optional": bool(port.optional)} for name, port in cls.ports.items()],
        "params": [{"name": name, "unit": spec.unit,
                    "default": None if spec.required else plain(spec.default),
                    "min": plain(spec.min), "max": plain(spec.max), "shape": list(spec.shape),
                    "kind": spec.kind,
                    "choices": None if spec.choices is None else plain(list(spec.choices)),
                    "doc": spec.doc, "required": spec.required, "time": bool(spec.time),
                    "aliases": list(spec.aliases)}
                   for name, spec in cls.params.items()],
    }


def plain(value):
    """A declaration's value as JSON: tuples and arrays as lists, non-finite numbers null."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return str(value)


# -- checking a model --------------------------------------------------------------------------
def context(folder, library):
    """Where a model's subsystem definitions are found, as ``kn.load`` of a file in
    ``folder`` finds them: its own ``definitions``, files in ``folder`` (references may not
    leave it), then the library folders."""
    return Context.top(folder, library)


def build(data, ctx, validate):
    """The Model of a file's top-level object, through the checker of ``kn.load``."""
    return model_from_dict(data, validate=validate, context=ctx)


def validate(data, ctx):
    """``{"ok", "problems", "warnings", "summary"}`` of a model file's top-level object:
    :func:`check`, then :func:`summarize` when the check passes. What the checks warn about
    (an idealised inertia) is in ``warnings``: problems of severity "warning"."""
    answer = check(data, ctx)
    if answer.pop("compile"):
        more = summarize(data, ctx)
        if more.get("problems"):
            return {**answer, "ok": False, "problems": more["problems"], "warnings": []}
        answer["summary"].update(more["summary"])
        answer["warnings"] = more["warnings"]
    return answer


def check(data, ctx):
    """The checks of ``kn.load`` on a model file's top-level object: ``{"ok", "problems",
    "warnings", "summary": {"dof", "states", "components"}, "compile"}``, ``compile`` saying
    whether :func:`summarize` has more to tell (a sound model that is not a definition)."""
    components = data.get("components")
    summary = {"dof": None, "states": None,
               "components": len(components) if isinstance(components, list) else 0}
    try:
        model = build(data, ctx, validate=True)
    except ModelError as exc:
        return {"ok": False, "problems": problems_of(exc), "warnings": [],
                "summary": summary, "compile": False}
    summary["components"] = len(model.components)
    # a definition is wired where it is placed: nothing to count alone
    return {"ok": True, "problems": [], "warnings": [], "summary": summary,
            "compile": not model.exposed}


def summarize(data, ctx):
    """What compiling a sound model tells (up to COMPILE_LIMIT flat components): its degrees
    of freedom and states and what it is accepted with, ``{"summary": {"dof", "states"},
    "warnings": [...]}``, or ``{"problems": [...]}`` for what would refuse to run (a mass
    matrix singular at the start)."""
    out = {"dof": None, "states": None}
    try:
        model = build(data, ctx, validate=True)
        flat = model.flat()
        topo = flat.validate()
        if len(flat.components) <= COMPILE_LIMIT:
            system = model.compile()
            out["dof"], out["states"] = int(system.dof), list(system.state_names)
        elif not topo.loops:
            free = sum(1 for group in topo.oned if group.kind == "free")
            out["dof"] = int(topo.dof + free)
    except ModelError as exc:
        return {"problems": problems_of(exc)}
    return {"summary": out, "warnings": [problem(p) for p in topo.warnings[:MAX_PROBLEMS]]}


def problems_of(exc):
    """The problems of a ModelError as the page reads them (:func:`problem`), the first
    MAX_PROBLEMS of them and a last one saying how many more there are."""
    listed = [problem(p) for p in exc.problems[:MAX_PROBLEMS]]
    if len(exc.problems) > MAX_PROBLEMS:
        listed.append(problem(f"... and {len(exc.problems) - MAX_PROBLEMS:,} more problems "
                              f"(the first {MAX_PROBLEMS} are listed)"))
    return listed


def problem(record):
    """A ``Problem`` as JSON (API.md): ``{"message", "component", "port", "parameter",
    "path", "hint", "severity"}``; ``reason``, what is wrong without the place, for the page
    to say it in the user's words (``mass1.mass: must be >= 0 (got -1 kg)``); and the keys
    the page read before those fields: ``param`` (the parameter of a component of the file
    itself) and ``connection`` (the index of the wire ``path`` is on). The place is read
    from the fields only; a plain string is a problem with no place."""
    out = Problem.of(record).to_dict()
    path = out["path"] or ""
    out["param"] = out["parameter"] if path.startswith("components[") else None
    out["connection"] = _index(path, "connections[")
    rest = _after_place(out)
    out["reason"] = None if rest is None else _reason(rest)
    return out


def _index(path, head):
    """The index of a path that starts ``head`` ("connections[2][0]" -> 2), else None."""
    if not path.startswith(head):
        return None
    digits = path[len(head):].partition("]")[0]
    return int(digits) if digits.isdigit() else None


def _after_place(out):
    """The message after the place its fields name, when the message names that place as
    the library writes it (``components[3] "mass1" params.mass``, ``connections[2]``,
    ``mass1.frame_a``), else None: the page then shows the whole message."""
    message, path = out["message"], out["path"] or ""
    local = path[max(path.rfind("components["), path.rfind("connections["), 0):]
    places = []
    index = _index(local, "components[")
    if index is not None and out["component"]:
        head = f'components[{index}] "{out["component"]}"'
        if out["parameter"]:
            places.append(f"{head} params.{out['parameter']}")
        places.append(head)
    wire = _index(local, "connections[")
    if wire is not None:
        places.append(f"connections[{wire}]")
    if out["component"] and out["port"]:
        places.append(f"{out['component']}.{out['port']}")
    for place in places:
        at = message.find(place)
        if at >= 0:
            return message[at + len(place):]
    return None


def _reason(rest):
    """What is wrong, from the text after a place: ``" = -1 kg: must be >= 0"`` is
    ``"must be >= 0 (got -1 kg)"``."""
    rest = rest.strip()
    if rest.startswith("= ") and ": " in rest:
        value, _, what = rest[2:].partition(": ")
        return f"{what} (got {value})"
    return rest.lstrip(":").strip() or None


def folder_of(root, real_path):
    """The folder definitions of a model at ``real_path`` (or of an unsaved one) are found in."""
    return os.path.dirname(real_path) if real_path else root
