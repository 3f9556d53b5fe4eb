"""Parameters as data: ``Param``, a declaration with default, unit, bounds and doc.

A Param normalises what a user gives (a number, a quantity with its unit, an expression in
the model's parameters, a vector, a table, a colour), checks its bounds, and reports like
``mass1.mass = -1.0 kg: must be >= 0``. The constants of the declarations (domains, the
placeholder units and domains, the limits on names and tables) sit here with it; the rest
of the declaration machinery (``Port``, ``Component``) is in ``base.py``, which re-exports
them.
"""

import copy
import functools
import math
import re

import numpy as np

from .. import units
from ..errors import ModelError
from ..expr import parse
from ..util import check_number, quote, suggest


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
