"""A component type's reference, generated from its declarations: the signature and docstring
that ``help()`` shows, and the same facts as data for the JSON Schema, the docs and the
studio's palette. Written once here, so the text never drifts from the code (STYLE section 2).

Nothing is imported from ``base``: it calls these while it builds each class.
"""

import inspect
import re

from .quantities import QUANTITIES

#: a numpydoc section header: a title line over a line of dashes
_SECTION = re.compile(r"^(?P<title>\S[^\n]*)\n-{3,}\s*$", re.M)
_ANNOTATIONS = {"bool": bool, "name": str, "choice": str, "color": str,
                "names": list[str], "table": list[list[float]], "vector": list[float]}


def _annotation(spec):
    if spec.kind in _ANNOTATIONS:
        kind = _ANNOTATIONS[spec.kind]
    elif spec.kind != "real":                  # a kind this table does not know yet: text
        kind = str
    elif spec.shape == ():
        kind = float | str
    elif len(spec.shape) == 1:
        kind = list[float | str]
    else:
        kind = list[list[float | str]]
    return kind | None if spec.optional else kind


def _shown(value):
    """A default as the signature shows it: tuples, so no one mutates a shared default."""
    if isinstance(value, (list, tuple)):
        return tuple(_shown(v) for v in value)
    return value


def signature(cls):
    """``RigidBody(name, *, mass, r_cm=(0.0, 0.0, 0.0), ...)``: the name, then every
    parameter by its file name, keyword-only."""
    P = inspect.Parameter
    params = [P("name", P.POSITIONAL_OR_KEYWORD, annotation=str)]
    for key, spec in cls.params.items():
        default = P.empty if spec.required else _shown(spec.default)
        params.append(P(key, P.KEYWORD_ONLY, default=default, annotation=_annotation(spec)))
    return inspect.Signature(params)


def _quantities(domain):
    return [{"name": name, "unit": q.unit, "shape": list(q.shape)}
            for name, q in QUANTITIES.get(domain, {}).items()]


def _paragraphs(doc):
    """(summary, description) of a written docstring: its first paragraph, and the rest
    without its "Parameters" section (generated instead)."""
    summary, _, body = doc.strip().partition("\n\n")
    return summary, _description(body)


def _description(body):
    headers = list(_SECTION.finditer(body))
    for i, header in enumerate(headers):
        if header["title"].strip() == "Parameters":
            end = headers[i + 1].start() if i + 1 < len(headers) else len(body)
            body = body[:header.start()] + body[end:]
            break
    return body.strip()


def reference(cls):
    """Everything the declarations say about component type ``cls`` (a class; ``REGISTRY``
    gives it for a file's type name "multibody.RigidBody"), as JSON-ready data: type,
    summary, description, signature, parameters (unit, default, bounds, doc) and ports
    (domain, doc, and what a probe wired there records). The docstring, the JSON Schema's
    descriptions, the documentation's component pages and the studio's palette are made
    from it.

    A module function, not a method: a component may call a parameter anything."""
    summary, description = _paragraphs(cls._own_doc or "")
    return {
        "type": cls.type_name,
        "summary": " ".join(summary.split()),
        "description": description,
        "signature": f"{cls.__name__}{signature(cls)}",
        "params": [spec.info() for spec in cls.params.values()],
        "ports": [{"name": name, "domain": port.domain, "doc": port.doc,
                   "optional": port.optional, "quantities": _quantities(port.domain)}
                  for name, port in cls.ports.items()],
    }


def _number(value):
    return f"{value:g}" if isinstance(value, float) else repr(value)


def _value(value):
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, float):
        return _number(value)
    return repr(value) if isinstance(value, str) else str(value)


def param_line(info):
    """The numpydoc type line of one parameter: ``kg, >= 0, required``."""
    parts = []
    unit = info["unit"]
    if info["kind"] == "real":
        parts.append(unit if unit else "unit of the signal")
        shape = info["shape"]
        if shape == [3, 3]:
            parts.append("3x3 or its diagonal")
        elif shape:
            parts.append(f"{shape[0]} values")
        if info["time"]:
            parts.append("expression in t allowed")
    elif info["kind"] == "choice":
        choices = [repr(c) for c in info["choices"]]
        parts.append(" or ".join([", ".join(choices[:-1]), choices[-1]] if len(choices) > 1
                                 else choices))
    elif info["kind"] == "names":
        parts.append("list of " + (", ".join(info["choices"]) if info["choices"] else "names"))
    elif info["kind"] == "expression" and unit:
        parts.append(f"expression in {unit}")
    else:
        parts.append({"bool": "true or false", "name": "component name",
                      "color": "colour '#rrggbb'", "table": "rows [x, y]",
                      "vector": "one number per axis"}.get(
                          info["kind"], info["kind"]))
    bounds = [f">= {_number(info['min'])}" if info["min"] is not None else "",
              f"<= {_number(info['max'])}" if info["max"] is not None else "",
              "> 0" if info["positive"] else "",
              "not zero" if info["nonzero"] else ""]
    parts += [b for b in bounds if b]
    parts.append("required" if info["required"] else f"default {_value(info['default'])}")
    return ", ".join(parts)


def docstring(cls):
    """The docstring ``help(cls)`` shows: the written one, its parameters, ports and probe
    quantities generated from the declarations."""
    ref = reference(cls)
    out = [_paragraphs(cls._own_doc or "")[0]]             # wrapped as written
    if ref["description"]:
        out += ["", ref["description"]]
    if ref["params"]:
        out += ["", "Parameters", "----------"]
        for info in ref["params"]:
            also = f" (also given as {', '.join(info['aliases'])})" if info["aliases"] else ""
            out += [f"{info['name']} : {param_line(info)}", f"    {info['doc']}{also}"]
        out += ["", "A value in another unit is written with it (\"5 mm\", \"30 deg\"): it "
                "is converted to the unit above (1: dimensionless)."]
    if ref["ports"]:
        out += ["", "Ports", "-----"]
        for port in ref["ports"]:
            optional = ", optional" if port["optional"] else ""
            out += [f"{port['name']} ({port['domain']}{optional})", f"    {port['doc']}"]
        domains = {p["domain"]: p["quantities"] for p in ref["ports"] if p["quantities"]}
        if domains:
            out += ["", "Probe quantities", "----------------",
                    "A Probe wired to a port records, by the port's domain:"]
            for domain, quantities in domains.items():
                listed = ", ".join(f"{q['name']} [{q['unit'] or '1'}]" for q in quantities)
                out += [f"{domain}", f"    {listed}"]
    return "\n".join(out) + "\n"
