"""Declaration machinery: a component is a class of ``Port`` and ``Param`` declarations.

Ports and parameters are collected from the class body in order, so documentation, the file
format and validation are all generated from the same declarations and never drift.
"""

import copy
import functools
import inspect
import math
import re

import numpy as np

from .. import units
from ..errors import ModelError, Problem
from ..expr import parse
from ..util import check_number, hint, quote, suggest
from .reference import docstring, signature


class _Required:
    """The default of a parameter that has none: the user must give a value."""

    def __repr__(self):
        return "required"


REQUIRED = _Required()
#: placeholder units of a joint's initial values: those of its coordinates (the class's
#: ``units``) and of their rates; resolved per class, as ONED ports are
COORDINATES, RATES = "<coordinates>", "<rates>"
DOMAINS = ("frame", "rotational", "translational", "electrical", "signal_in", "signal_out")
#: placeholder domains: ONED is the class's ``domain`` (rotational or translational); ANY
#: connects to every domain (a probe)
ONED, ANY = "1d", "any"
#: a name: an ASCII identifier of at most NAME_LIMIT characters, matched whole (fullmatch:
#: "mass1\n" is refused, not matched up to its newline)
NAME_LIMIT = 200
_NAME = re.compile(rf"[A-Za-z_][A-Za-z0-9_]{{0,{NAME_LIMIT - 1}}}")
#: a colour, as a parameter of kind "color" takes it
COLOR = re.compile(r"#[0-9A-Fa-f]{6}")
#: rows a signals.Table may have: a table is data for interpolation, not a data set
TABLE_ROWS_LIMIT = 100_000

#: type name ("multibody.Revolute") -> class; files resolve types only through this table.
REGISTRY = {}


class Port:
    """A connector of one physical domain."""

    def __init__(self, domain, doc="", optional=False):
        if domain not in DOMAINS + (ONED, ANY):
            raise ValueError(f"unknown domain {domain!r}")
        self.domain, self.doc, self.optional = domain, doc, optional
        self.name = None

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, instance, owner):
        return self if instance is None else PortRef(instance, self.name)

    def __set__(self, instance, value):
        also = [key for key, spec in instance.params.items() if self.name in spec.aliases]
        where = (f"; the parameter of that name in files is {instance.name}.{also[0]}"
                 if also else "")
        raise ModelError(f"{instance.name}.{self.name} is a port, not a parameter: wire it with "
                         f"model.connect{where}", component=instance.name, port=self.name)


class PortRef:
    """One port of one component instance, as passed to ``Model.connect``."""

    __slots__ = ("component", "name")

    def __init__(self, component, name):
        self.component, self.name = component, name

    @property
    def domain(self):
        return self.component.ports[self.name].domain

    @property
    def path(self):
        return f"{self.component.name}.{self.name}"

    def __eq__(self, other):
        return (isinstance(other, PortRef) and other.component is self.component
                and other.name == self.name)

    def __hash__(self):
        return hash((id(self.component), self.name))

    def __repr__(self):
        return f"<port {self.path} ({self.domain})>"


class Param:
    """A parameter: default, unit, bounds and a one-line doc.

    A value is a number, a quantity with a unit (``"5 mm"``, converted to ``unit``: see
    :mod:`kinetwork.units`), or a string expression in model parameters (and in time ``t``
    where ``time=True``); ``shape`` (3,) takes three of those, (3, 3) a matrix or its
    diagonal. ``kind`` "bool", "name" and "names" take a flag, a component name and a list of
    strings, "table" rows [x, y], "choice" one string of ``choices``, "color" a colour
    "#rrggbb".

    ``unit`` is the SI unit of the value ("1": dimensionless; "": any, as a signal block's
    gain, in the unit of its signal), or one unit per entry of a vector (a tuple: kept in
    ``entry_units``, while ``unit`` reads "rad, m" for whoever shows it).
    """

    def __init__(self, default=REQUIRED, *, unit="", min=None, max=None, shape=(), doc="",
                 time=False, optional=False, nonzero=False, kind="real", choices=None,
                 positive=False, signals=False, aliases=(), name=None):
        self.default, self.min, self.max = default, min, max
        # ``signals``: the expression may also read signal outputs of the model's components
        # by dotted name ("pos.y", "cyl1.pos.y"), as a force law in sensor signals
        self.signals = signals
        self._set_unit(unit)
        self.shape, self.doc, self.time, self.optional = tuple(shape), doc, time, optional
        self.nonzero, self.kind, self.choices = nonzero, kind, choices
        self.positive = positive
        # other names a keyword or a file may give it by, kept as written when saved: a
        # joint's direction ``n`` (Modelica's name; its 1-D flange is ``axis``) was "axis"
        self.aliases = tuple(aliases)
        # a declaration in a class body is named by its attribute; ``name`` names one made
        # outside a class (a subsystem's parameters)
        self.name = name
        self.__doc__ = self.describe()        # what help() shows under the attribute

    def __set_name__(self, owner, name):
        if self.name not in (None, name):
            # one name reads, writes, documents and files a parameter
            raise TypeError(f"{owner.__name__}.{name}: a parameter declared in a class is "
                            f"named by its attribute, not {self.name!r}")
        self.name = name

    def __get__(self, instance, owner):
        return self if instance is None else instance._values[self.name]

    def __set__(self, instance, value):
        # ``comp.mass = 2`` goes through the same checks as the constructor and lands in what
        # is saved and simulated: one truth for a parameter's value
        instance.set_param(self.name, value)

    @property
    def required(self):
        return self.default is REQUIRED

    def _set_unit(self, unit):
        self.entry_units = tuple(unit) if isinstance(unit, (tuple, list)) else None
        self.unit = ", ".join(unit) if self.entry_units else unit

    def unit_at(self, index=None):
        """The unit of entry ``index`` of a vector (with ``entry_units``, one per entry), or
        of the whole value."""
        if self.entry_units and index is not None:
            return self.entry_units[index]
        return self.unit

    def describe(self):
        unit = {COORDINATES: "unit of the joint coordinates",
                RATES: "unit of their rates"}.get(self.unit, self.unit)
        return f"{self.doc} [{unit}]" if unit else self.doc

    def info(self):
        """The declaration as data (JSON-ready): what the docs, the schema and the studio's
        palette show."""
        return {"name": self.name, "kind": self.kind,
                "unit": self.unit,
                "entry_units": list(self.entry_units) if self.entry_units else None,
                "shape": list(self.shape), "required": self.required,
                "default": None if self.required else _plain(self.default),
                "min": self.min, "max": self.max, "positive": self.positive,
                "nonzero": self.nonzero, "optional": self.optional, "time": self.time,
                "signals": self.signals, "aliases": list(self.aliases),
                "choices": list(self.choices) if self.choices else None, "doc": self.doc}

    def resolved(self, owner):
        """This declaration for class ``owner``: COORDINATES and RATES units read from its
        joint coordinates' ``units`` (self if there is nothing to resolve)."""
        if self.unit not in (COORDINATES, RATES) or not getattr(owner, "units", None):
            return self
        coords = tuple(owner.units)[:owner.dof]
        if self.unit == RATES:
            coords = tuple(f"{u}/s" if u else "1/s" for u in coords)
        twin = copy.copy(self)
        twin._set_unit(coords[0] if self.shape == () else coords)
        twin.__doc__ = twin.describe()
        return twin

    def si(self, value):
        """A normalized value with its quantities (``"5 mm"``) replaced by SI numbers: what
        the equations see. Expressions stay as they are."""
        if self.kind != "real" or value is None:
            return value
        if self.shape == ():
            return self._number(value)
        if len(self.shape) == 1:
            return [self._number(v, i) for i, v in enumerate(value)]
        return [[self._number(v) for v in row] for row in value]

    def _number(self, value, index=None):
        if isinstance(value, str) and _is_quantity(value):
            return units.to_si(value, self.unit_at(index))
        return value

    def normalize(self, value, where):
        """Check the structure of ``value``; return it in canonical nested-list form.

        Numbers are bounds-checked here; expressions are checked once model parameters are
        known (``check_bounds``).
        """
        if value is None:
            if self.optional:
                return None
            raise ModelError(f"{where}: a value is required")
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise ModelError(f"{where}: must be true or false, got {quote(value)}")
            return value
        if self.kind == "table":
            return _table(value, where)
        if self.kind == "name":
            if not isinstance(value, str) or not _NAME.fullmatch(value):
                raise ModelError(f"{where}: must be a component name, got {quote(value)}")
            return value
        if self.kind == "choice":
            if not isinstance(value, str) or value not in self.choices:
                raise ModelError(f"{where}: must be one of {', '.join(self.choices)}, got "
                                 f"{quote(value)}{suggest(value, self.choices)}")
            return value
        if self.kind == "color":
            if not isinstance(value, str) or not COLOR.fullmatch(value):
                raise ModelError(f"{where}: must be a colour '#rrggbb', got {quote(value)}")
            return value
        if self.kind == "names":
            if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
                raise ModelError(f"{where}: must be a list of names, got {quote(value)}")
            for v in value:
                if self.choices is not None and v not in self.choices:
                    raise ModelError(f"{where}: unknown {quote(v)}{suggest(v, self.choices)}; "
                                     f"choose from {', '.join(self.choices)}")
            if len(set(value)) != len(value):
                raise ModelError(f"{where}: names repeated in {quote(list(value))}")
            return list(value)
        if self.shape == ():
            return self._scalar(value, where)
        if isinstance(value, np.ndarray):
            value = value.tolist()
        if not isinstance(value, (list, tuple)):
            raise ModelError(f"{where}: must be a list of shape {self.shape}, "
                             f"got {quote(value)}")
        if self.shape == (3, 3) and len(value) == 3 and not any(
                isinstance(v, (list, tuple)) for v in value):
            value = [[value[0], 0, 0], [0, value[1], 0], [0, 0, value[2]]]
        if len(value) != self.shape[0]:
            raise ModelError(f"{where}: must have {self.shape[0]} entries, got {len(value)}")
        problems = []

        def scalar(v, at, index=None):      # every bad entry is reported, not only the first
            try:
                return self._scalar(v, at, bounds=False, index=index)
            except ModelError as exc:
                problems.extend(exc.problems)
        if len(self.shape) == 1:
            out = [scalar(v, f"{where}[{i}]", i) for i, v in enumerate(value)]
        else:
            out = []
            for i, row in enumerate(value):
                if not isinstance(row, (list, tuple)) or len(row) != self.shape[1]:
                    raise ModelError(f"{where}[{i}]: must be a row of {self.shape[1]} entries")
                out.append([scalar(v, f"{where}[{i}][{j}]") for j, v in enumerate(row)])
        if problems:
            raise ModelError(problems)
        if self.nonzero and all(isinstance(v, (int, float)) for v in out) and not any(out):
            raise ModelError(f"{where}: must not be the zero vector")
        return out

    def _scalar(self, value, where, bounds=True, index=None):
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, str):
            if not value.strip():
                raise ModelError(f"{where}: empty expression")
            if _is_quantity(value):
                unit = self.unit_at(index)
                try:
                    number = units.to_si(value, unit)
                except ModelError as exc:
                    raise ModelError(f"{where} = {quote(value)}: {exc}") from None
                if bounds:
                    self.check_bounds(number, f"{where} = {quote(value)}, i.e.", equals=" ")
                elif not math.isfinite(number):
                    raise ModelError(f"{where} = {quote(value)}: must be finite")
                return value
            try:
                expr = parse(value)
            except ModelError as exc:
                raise ModelError(f"{where}: {exc}{units.hint(value)}") from None
            dotted = sorted(n for n in expr.names if "." in n)
            if dotted and not self.signals:
                raise ModelError(f"{where}: {quote(dotted[0])} is not a parameter here: "
                                 f"expressions use the parameters of their own model (give a "
                                 f"subsystem's parameters with its params)")
            if "t" in expr.names and not self.time:
                raise ModelError(f"{where}: time 't' is not allowed in {quote(value)}; "
                                 f"this parameter is constant")
            return value
        value = check_number(value, where, "a number or an expression")
        if bounds:
            self.check_bounds(value, where)
        return value

    def check_bounds(self, number, where, equals=" = "):
        """Bounds check of one evaluated scalar, worded for the person at the diagram."""
        unit = self.unit_at()
        unit = f" {unit}" if unit and unit != "1" else ""
        at = f"{where}{equals}{number}{unit}"
        if not math.isfinite(number):
            raise ModelError(f"{at}: must be finite")
        if self.positive and number <= 0:
            raise ModelError(f"{at}: must be > 0")
        if self.nonzero and not self.shape and number == 0:
            raise ModelError(f"{at}: must not be 0")
        if self.min is not None and number < self.min:
            raise ModelError(f"{at}: must be >= {self.min}")
        if self.max is not None and number > self.max:
            raise ModelError(f"{at}: must be <= {self.max}")


#: what other tools (Modelica's MSL, Simscape, MapleSim) call a component kinetwork has under
#: another name, looked up by the name after the library
#: what other tools call a kinetwork type: a name, or "lib.Name" where the library decides
#: (MSL's MultiBody ``Fixed`` is a fixed frame, its Rotational ``Fixed`` a fixed flange)
ELSEWHERE = {"World": ["multibody.Ground"], "Body": ["multibody.RigidBody"],
             "RigidTransform": ["multibody.FixedRotation"],
             "Translation": ["multibody.FixedTranslation"],
             "Rotation": ["multibody.FixedRotation"], "RevoluteJoint": ["multibody.Revolute"],
             "PrismaticJoint": ["multibody.Prismatic"], "SphericalJoint": ["multibody.Spherical"],
             "Gear": ["rotational.IdealGear"], "Motor": ["electrical.DCMotor"],
             "Capacitance": ["electrical.Capacitor"], "Inductance": ["electrical.Inductor"],
             "Resistance": ["electrical.Resistor"], "Source": ["signals.Constant"],
             "PointGravity": ["multibody.Ground"], "Fixed": ["multibody.Ground"],
             "multibody.Fixed": ["multibody.Ground"],
             "rotational.Ground": ["rotational.Fixed"],
             "translational.Ground": ["translational.Fixed"],
             "multibody.Mass": ["multibody.PointMass", "translational.Mass"],
             "multibody.Inertia": ["multibody.RigidBody", "rotational.Inertia"],
             "ConstantTorque": ["rotational.Torque"], "TorqueSource": ["rotational.Torque"],
             "ForceSource": ["translational.Force"], "ConstantForce": ["translational.Force"],
             "ConstantVoltage": ["electrical.VoltageSource"],
             "SineVoltage": ["electrical.VoltageSource"],
             "StepVoltage": ["electrical.VoltageSource"],
             "ConstantCurrent": ["electrical.CurrentSource"],
             "LimPID": ["signals.PID"], "PI": ["signals.PID"], "Feedback": ["signals.Add"],
             "Sensor": ["Probe"], "PositionSensor": ["translational.PositionSensor"]}


def type_suggestions(kind):
    """The types the unknown component type ``kind`` ("lib.Name") may stand for, best first:
    what other tools call it (``multibody.World``: multibody.Ground), the same name in the
    other libraries (``rotational.Mass``: translational.Mass), else the closest names."""
    name = str(kind).rpartition(".")[2]
    found = [k for k in ELSEWHERE.get(str(kind), []) + ELSEWHERE.get(name, [])
             if k in REGISTRY and k != kind]
    found += sorted(k for k in REGISTRY if k.rpartition(".")[2].lower() == name.lower()
                    and k != kind)
    found = list(dict.fromkeys(found))
    if not found:
        import difflib                  # here: the command line starts without it
        found = difflib.get_close_matches(str(kind)[:100], list(REGISTRY), n=1)
    return found[:3]


def type_suggestion(kind):
    """' (did you mean ...?)' for the unknown component type ``kind`` (see
    ``type_suggestions``); '' if none."""
    found = type_suggestions(kind)
    return f" (did you mean {' or '.join(repr(k) for k in found)}?)" if found else ""


class NoSuchComponent(AttributeError):
    """``kn.multibody.World``: no such component type in that library. An AttributeError
    (``hasattr`` and ``getattr`` with a default keep working) whose message says what it may
    be, across libraries; ``library``, ``name`` and ``suggestions`` hold the same as data."""

    def __init__(self, library, name):
        self.library, self.name = library, name
        self.suggestions = type_suggestions(f"{library}.{name}")
        close = f" (did you mean {' or '.join(repr(k) for k in self.suggestions)}?)" \
            if self.suggestions else ""
        super().__init__(f"kinetwork.{library} has no component {quote(name)}{close}")


def library_attribute(library):
    """The ``__getattr__`` of a library's module: an unknown component is a
    ``NoSuchComponent`` that says what it may be (``kn.multibody.World``: did you mean
    'multibody.Ground'?)."""
    def __getattr__(name):
        if name.startswith("__"):
            raise AttributeError(name)
        raise NoSuchComponent(library, name)
    return __getattr__


class NoSuchAttribute(ModelError, AttributeError):
    """A component's misspelt port or parameter: a ModelError for the user, and an
    AttributeError for Python's protocol (``hasattr``, ``getattr`` with a default), so that
    asking whether a component has something never raises."""


@functools.lru_cache(maxsize=4096)
def _is_quantity(text):
    """Whether ``text`` is a quantity ("5 mm") rather than an expression ("L/2"): it does not
    parse as an expression and reads as one number and a unit."""
    try:
        parse(text)
    except ModelError:
        return units.split(text) is not None
    return False


def _plain(value):
    """A default as JSON data (nested lists; REQUIRED has none)."""
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    return value


def _table(value, where):
    """Rows [x, y] of numbers, x increasing (two equal in a row: a step), at least two and
    at most TABLE_ROWS_LIMIT."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, (list, tuple)) or len(value) < 2:
        raise ModelError(f"{where}: must be a table of at least two rows [x, y], "
                         f"got {quote(value)}")
    if len(value) > TABLE_ROWS_LIMIT:
        # refused before any row is read: the cost of a table grows with its rows all the
        # way to the compiled code
        raise ModelError(f"{where}: {len(value)} rows, more than the {TABLE_ROWS_LIMIT} a "
                         f"table may have; resample it")
    rows = []
    for i, row in enumerate(value):
        if not isinstance(row, (list, tuple)) or len(row) != 2:
            raise ModelError(f"{where}[{i}]: must be a row [x, y], got {quote(row)}")
        rows.append([check_number(v, f"{where}[{i}][{j}]") for j, v in enumerate(row)])
    for i in range(1, len(rows)):
        if rows[i][0] < rows[i - 1][0]:
            raise ModelError(f"{where}[{i}]: x must increase, got {rows[i][0]} after "
                             f"{rows[i - 1][0]}")
        if i >= 2 and rows[i][0] == rows[i - 1][0] == rows[i - 2][0]:
            raise ModelError(f"{where}[{i}]: x = {rows[i][0]} a third time in a row; two "
                             f"equal x's are a step, three are not a table")
    return rows


def _cut(key):
    """A parameter key as given, cut for messages (a file may hold any text as a key)."""
    return key if isinstance(key, str) and len(key) <= NAME_LIMIT else quote(key, NAME_LIMIT)


class Component:
    """Base of every component: a name, declared ports and declared parameters."""

    #: library path used in files, e.g. "multibody.Revolute"; set by ``library=`` on subclasses
    type_name = None
    ports = {}
    params = {}
    #: what the component is to the solver: world, joint, body, compliant, source, fixed, probe
    role = None
    #: the class's docstring as written (``__doc__`` is generated from the declarations)
    _own_doc = ""
    #: 1-D ports whose position is a joint coordinate (port -> coordinate index) or zero
    coordinate_ports = {}
    zero_ports = ()
    #: another name a parameter is given by -> its name (``Param(aliases=...)``)
    aliases = {}
    #: parameter -> the alias it was given by, kept for the file it is saved to
    _spelling = {}
    #: groups of signal ports that carry signals of one unit (an Add's inputs and output, a
    #: PID's set point and measurement): how units spread along signal wires to the plots
    same_unit_ports = ()

    def signal_unit(self, port):
        """The unit of the signal at signal port ``port`` when this component fixes it (an
        angle sensor's output: "rad"; a torque source's input: "N*m"), else None."""
        return None

    def __init_subclass__(cls, library=None, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.ports = {}
        cls.params = {}
        cls.aliases = {}
        for klass in reversed(cls.__mro__):
            for key, val in vars(klass).items():
                if isinstance(val, Port):
                    if val.domain == ONED and getattr(cls, "domain", None):
                        val = copy.copy(val)
                        val.domain = cls.domain
                    cls.ports[key] = val
                elif isinstance(val, Param):
                    cls.params[val.name] = val.resolved(cls)
        cls.aliases = {alias: key for key, spec in cls.params.items() for alias in spec.aliases}
        # a subclass declared without ``library=`` is not a file type (not its parent's either)
        cls.type_name = None
        cls._own_doc = inspect.cleandoc(vars(cls).get("__doc__") or "") or cls._own_doc
        if library is not None and not cls.__name__.startswith("Partial"):
            cls.type_name = f"{library}.{cls.__name__}" if library else cls.__name__
            REGISTRY[cls.type_name] = cls
            # help(), IDEs and the docs read what the declarations say
            cls.__signature__ = signature(cls)
            cls.__doc__ = docstring(cls)

    def __init__(self, name, **params):
        self._declare(name, params, None)

    @classmethod
    def from_params(cls, name, params, place=None):
        """Build from a dict of parameters, as a file gives them (any key, even "name").

        ``place(key)`` locates a parameter in messages (files pass their JSON path).
        """
        comp = cls.__new__(cls)
        comp._declare(name, params, place)
        return comp

    def _declare(self, name, params, place):
        place = place or (lambda key: f"{name}.{_cut(key)}")
        if not isinstance(name, str) or not _NAME.fullmatch(name):
            size = (f"; at most {NAME_LIMIT} characters, got {len(name)}"
                    if isinstance(name, str) and len(name) > NAME_LIMIT else "")
            raise ModelError(f"{type(self).__name__} name {quote(name)}: must be an identifier "
                             f"(letters, digits, underscore; not starting with a digit{size})")
        object.__setattr__(self, "name", name)
        kind = self.type_name or type(self).__name__
        problems = [Problem(f"{place(key)}: unknown parameter{close}; {kind} has "
                            f"{self._listed()}", component=name, parameter=_cut(key),
                            hint=hint(close))
                    for key in params if key not in self.params and key not in self.aliases
                    for close in [suggest(key, [*self.params, *self.aliases])]]
        object.__setattr__(self, "_spelling", {})
        for alias, key in self.aliases.items():
            if alias in params and key in params:
                problems.append(Problem(f"{place(alias)}: {alias} and {key} are one "
                                        f"parameter; give {key} alone", component=name,
                                        parameter=alias, hint=f"remove {alias}"))
            elif alias in params:
                params = {key if k == alias else k: v for k, v in params.items()}
                self._spelling[key] = alias
        object.__setattr__(self, "given", {})
        object.__setattr__(self, "_values", {})
        for key, spec in self.params.items():
            written = self._spelling.get(key, key)
            try:
                if key in params:
                    self.given[key] = spec.normalize(params[key], place(written))
                    self._values[key] = spec.si(self.given[key])
                elif spec.required:
                    problems.append(Problem(f"{place(key)}: a value is required "
                                            f"({spec.describe()})", parameter=key))
                else:
                    self._values[key] = spec.si(spec.normalize(spec.default, place(key)))
            except ModelError as exc:
                problems.extend(p.where(parameter=written) for p in exc.problems)
        if problems:
            raise ModelError(problems, component=name)

    def _listed(self):
        """The parameters, each with its other names: "cut, n (or axis), q0"."""
        also = {key: [a for a, k in self.aliases.items() if k == key] for key in self.params}
        return ", ".join(f"{key} (or {', '.join(also[key])})" if also[key] else key
                         for key in self.params) or "none"

    def check_values(self, values, place):
        """Problems of the evaluated parameters ``values`` taken together (a hole no wider than
        its body), as messages naming ``place(key)``; the validation calls it. None here."""
        return []

    def required_ports(self):
        """Optional ports that this instance's parameters make required (a force resolved in
        the frame wired to its frame_resolve); none here."""
        return ()

    def set_param(self, key, value):
        """Change parameter ``key`` (its file name) to ``value``, checked as at construction.

        The new value is what ``Model.save``, ``numeric_values`` and ``simulate`` see; a
        compiled System of a model holding this component is rebuilt on its next use.
        """
        if key in self.aliases:
            self._spelling = {**self._spelling, self.aliases[key]: key}
            key = self.aliases[key]
        elif key not in self.params:
            close = suggest(key, self.params)
            raise ModelError(f"{type(self).__name__} {self.name!r} has no parameter "
                             f"{quote(key)}{close}; parameters: {self._listed()}",
                             component=self.name, hint=hint(close),
                             parameter=_cut(key) if isinstance(key, str) else None)
        elif key in self._spelling:
            self._spelling = {k: v for k, v in self._spelling.items() if k != key}
        try:
            value = self.params[key].normalize(value, f"{self.name}.{key}")
        except ModelError as exc:
            raise ModelError(exc.problems, component=self.name, parameter=key) from None
        self.given[key] = value
        self._values[key] = self.params[key].si(value)

    def written_params(self):
        """The given parameters as a file holds them: each by the name it was given by (a
        joint's ``n`` given as ``axis`` is saved as ``axis``)."""
        return {self._spelling.get(key, key): copy.deepcopy(value)
                for key, value in self.given.items()}

    def __setattr__(self, key, value):
        declared = getattr(type(self), key, None)
        if isinstance(declared, (Param, Port)) or key.startswith("_"):
            object.__setattr__(self, key, value)
            return
        if key == "name":
            raise ModelError(f"{self.name!r}: a component cannot be renamed; build a new one "
                             f"(a model refers to its components by name)",
                             component=self.name)
        if key in self.params or key in self.aliases:     # a subsystem's, or another name
            self.set_param(key, value)
            return
        close = suggest(key, [*self.params, *self.ports])
        raise ModelError(f"{type(self).__name__} {self.name!r} has no parameter "
                         f"{quote(key)}{close}; change a parameter with comp.<parameter> = "
                         f"value or comp.set_param(name, value); parameters: "
                         f"{self._listed()}", component=self.name, hint=hint(close))

    def __delattr__(self, key):
        raise ModelError(f"{self.name}.{key}: parameters and ports cannot be deleted",
                         component=self.name)

    def __getattr__(self, key):
        # reached only when normal lookup fails: a misspelt port or parameter
        if key.startswith("_"):
            raise AttributeError(key)
        close = suggest(key, [*self.ports, *self.params])
        raise NoSuchAttribute(f"{type(self).__name__} {self.name!r} has no port or parameter "
                              f"{key!r}{close}; ports: {', '.join(self.ports)}",
                              component=self.name, hint=hint(close))

    def port_ref(self, name):
        """The ``PortRef`` called ``name``; a ModelError suggesting close names otherwise."""
        if name not in self.ports:
            close = suggest(name, self.ports)
            raise ModelError(f"{type(self).__name__} {self.name!r} has no port {quote(name)}"
                             f"{close}; ports: {', '.join(self.ports)}", component=self.name,
                             port=_cut(name) if isinstance(name, str) else None,
                             hint=hint(close))
        return PortRef(self, name)

    def bound(self, values):
        """A copy whose parameters read as ``values`` (numbers or CasADi symbols)."""
        twin = copy.copy(self)
        object.__setattr__(twin, "_values", dict(values))
        return twin

    def __repr__(self):
        return f"<{self.type_name} {self.name!r}>"
