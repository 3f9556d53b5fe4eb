"""The JSON Schema of the model format, generated from the component declarations (it sits
on top of the layers, as the command line does: it lists the solver's methods too).

Every component type of the ``REGISTRY`` becomes one branch of ``components.items`` (its
``type`` a constant, its parameters with their shapes, units and docs, the required ones
required, no others allowed), written from the type's ``reference()`` as its docstring is, so
the schema never drifts from the code. Editors use it for
completion and first checks; ``kinetwork.load`` remains the judge (it also checks what a
schema cannot: wiring, units of expressions, physical sense).
"""

from .components.base import COLOR, REGISTRY
from .components.reference import param_line, reference
from .graph.io import DEFINITION_KEYS, FORMAT, KEYS, KEYS_V2, VERSION
from .graph.settings import SIMULATION_KEYS
from .solver.methods import METHODS
from .util import callable_module

IDENT = "^[A-Za-z_][A-Za-z0-9_]*$"
NUMBER = {"type": "number"}
EXPRESSION = {"type": "string", "minLength": 1,
              "description": "arithmetic in model parameters (and t where allowed), or a "
                             "number with a unit ('5 mm', '30 deg'), converted to SI"}
SCALAR = {"anyOf": [NUMBER, EXPRESSION]}


PORT_PATH = {"type": "string", "pattern": IDENT[:-1] + r"\.[A-Za-z_][A-Za-z0-9_]*$"}


def schema():
    """The JSON Schema (draft 2020-12) of a kinetwork model file, as a dict.

    Version 1 files hold components of kinetwork's types; version 2 files may also expose
    ``ports``, place subsystems (a ``type`` naming a definition) and keep ``definitions``,
    inline or as ``{"file": "relative/path.json"}``."""
    types = sorted(REGISTRY)
    body = {
        "description": {"type": "string"},
        "parameters": {"type": "object", "propertyNames": {"pattern": IDENT},
                       "additionalProperties": {"anyOf": [NUMBER, {
                           "type": "string", "minLength": 1,
                           "description": "a number with a unit ('500 mm'), in SI base "
                                          "units, checked where a component uses it"}]}},
        "ports": {"type": "object", "propertyNames": {"pattern": IDENT},
                  "additionalProperties": PORT_PATH,
                  "description": "ports shown when the model is placed as a subsystem: "
                                 "name -> 'component.port'"},
        "components": {"type": "array", "items": {"oneOf": [
            *(_component(t) for t in types), _subsystem(types)]}},
        "connections": {"type": "array", "items": {
            "type": "array", "minItems": 2, "maxItems": 2, "items": PORT_PATH}},
        "layout": {"type": "object"},
    }
    reference = {"type": "object", "required": ["file"], "additionalProperties": False,
                 "properties": {"file": {
                     "type": "string", "minLength": 1, "pattern": r"^(?![/\\])(?!.*://)",
                     "description": "a model file, relative to this one, inside its folder"}}}
    inline = {"type": "object", "additionalProperties": False,
              "properties": {key: body[key] for key in DEFINITION_KEYS}}
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": f"https://kinetwork.dev/schema/model-v{VERSION}.json",
        "title": "kinetwork model",
        "description": "A wiring diagram of multibody, 1-D and signal components, and of "
                       f"subsystems (format {FORMAT!r}, versions 1 to {VERSION}).",
        "type": "object",
        "required": ["format", "version", "name", "components"],
        "additionalProperties": False,
        "properties": {
            "format": {"const": FORMAT},
            "version": {"enum": list(range(1, VERSION + 1))},
            "name": {"type": "string", "minLength": 1},
            **body,
            "simulation": {"type": "object", "additionalProperties": False,
                           "properties": _simulation()},
            "initial": _initial(),
            "definitions": {"type": "object",
                            "propertyNames": {"pattern": IDENT, "not": {"enum": types}},
                            "additionalProperties": {"oneOf": [reference, inline]}},
        },
        "if": {"properties": {"version": {"const": 1}}},
        "then": {"propertyNames": {"enum": list(KEYS)}},
        "else": {"propertyNames": {"enum": list(KEYS_V2)}},
    }


def _subsystem(types):
    return {
        "type": "object", "title": "subsystem",
        "description": "A placed subsystem: its type names a definition (of this file, a "
                       "file next to it, or a library folder); params set its parameters.",
        "required": ["name", "type"], "additionalProperties": False,
        "properties": {
            "name": {"type": "string", "pattern": IDENT},
            "type": {"type": "string", "pattern": IDENT, "not": {"enum": types}},
            "params": {"type": "object", "propertyNames": {"pattern": IDENT},
                       "additionalProperties": SCALAR},
        },
    }


def _component(type_name):
    cls = REGISTRY[type_name]
    ref = reference(cls)
    params = {info["name"]: _param(cls.params[info["name"]], info) for info in ref["params"]}
    # a parameter's other name (a joint's "axis" for n) is read too, never with it
    params.update({alias: params[key] for alias, key in cls.aliases.items()})
    both = [{"required": [alias, key]} for alias, key in cls.aliases.items()]
    required = [info["name"] for info in ref["params"] if info["required"]]
    ports = ", ".join(f"{p['name']} ({p['domain']})" for p in ref["ports"])
    return {
        "type": "object", "title": type_name,
        "description": f"{ref['summary']} Ports: {ports}.",
        "required": ["name", "type"], "additionalProperties": False,
        "properties": {
            "name": {"type": "string", "pattern": IDENT},
            "type": {"const": type_name},
            "params": {"type": "object", "additionalProperties": False,
                       "properties": params, "required": required,
                       **({"not": {"anyOf": both}} if both else {})},
        },
    }


def _param(spec, info):
    doc = f"{info['doc']} ({param_line(info)})"
    if spec.kind == "bool":
        out = {"type": "boolean"}
    elif spec.kind == "name":
        out = {"type": "string", "pattern": IDENT}
    elif spec.kind == "choice":
        out = {"enum": list(spec.choices)}
    elif spec.kind == "color":
        out = {"type": "string", "pattern": f"^{COLOR.pattern}$"}
    elif spec.kind == "names":
        items = {"enum": list(spec.choices)} if spec.choices else {"type": "string"}
        out = {"type": "array", "items": items, "uniqueItems": True}
    elif spec.kind == "table2d":           # grids in the first row and column
        out = {"type": "array", "minItems": 3, "items": {
            "type": "array", "minItems": 3, "items": NUMBER}}
    elif spec.kind == "vector":             # one number per axis
        out = {"anyOf": [NUMBER, {"type": "array", "minItems": 1, "items": NUMBER}]}
    elif spec.kind == "table":
        out = {"type": "array", "minItems": 2, "items": {
            "type": "array", "minItems": 2, "maxItems": 2, "items": NUMBER}}
    elif spec.shape == ():
        out = _bounded(spec)
    elif len(spec.shape) == 1:
        n = spec.shape[0]
        out = {"type": "array", "minItems": n, "maxItems": n, "items": SCALAR}
    else:                                     # (3, 3), or its diagonal
        row = {"type": "array", "minItems": 3, "maxItems": 3, "items": SCALAR}
        out = {"anyOf": [{"type": "array", "minItems": 3, "maxItems": 3, "items": row}, row]}
    if spec.optional:
        out = {"anyOf": [out, {"type": "null"}]}
    if not spec.required and spec.default is not None:
        out["default"] = spec.default
    out["description"] = doc
    return out


def _bounded(spec):
    number = dict(NUMBER)
    if spec.min is not None:
        number["minimum"] = spec.min
    if spec.max is not None:
        number["maximum"] = spec.max
    if spec.positive:
        number["exclusiveMinimum"] = 0
    if spec.nonzero:
        number["not"] = {"const": 0}
    return {"anyOf": [number, EXPRESSION]}


def _initial():
    """Initial conditions as equations (``kinetwork.graph.initial``)."""
    names = {"type": "array", "items": {"type": "string", "minLength": 1},
             "uniqueItems": True}
    return {"type": "object", "additionalProperties": False,
            "description": "initial conditions as equations: a steady state, given "
                           "derivatives, states and parameters solved from them",
            "properties": {
                "steady": {"type": "boolean", "description": "every state's derivative zero"},
                "derivatives": {"type": "object", "additionalProperties": NUMBER,
                                "description": "state name -> its derivative at t = 0"},
                "fixed": {**names, "description": "states a steady state keeps"},
                "solve": {**names, "description": "model parameters (and, without steady, "
                                                  "states) solved from the equations"}}}


def _simulation():
    out = {key: {"type": "number", "exclusiveMinimum": 0} for key in SIMULATION_KEYS}
    out["n_points"] = {"type": "integer", "minimum": 2}
    out["method"] = {"type": "string", "enum": sorted(METHODS)}
    return out


callable_module(__name__, schema)
