"""Model parameters written with units: ``Model("m", parameters={"L": "500 mm"})``.

A model parameter declares no unit, so a quantity given to it (``"500 mm"``, ``"30 deg"``,
``"2 N*m/rad"``) is converted to SI base units (0.5, pi/6, 2.0), exactly, as
:func:`kinetwork.units.to_si` converts; its text is kept so that a file saves it as written.
Its dimension is checked where it is used: wherever a component parameter with a declared
unit is the parameter's name, or that name times a number (``"L"``, ``"-L"``, ``"L/2"``,
``"0.5*L"``), a unit of another dimension is refused naming the parameter, both units and
the use (``parameters.m1 = '2 m' is used as mass1.mass [kg]: ...``). Through subsystems too:
a value given to a subsystem (``params={"L": "700 mm"}``, or ``{"L": "Lo"}`` with ``Lo`` a
quantity) is checked against where the definition uses its parameter. Other expressions are
not checked: a parameter given as a plain number has no dimension to combine with.
"""

import ast

from .. import units
from ..errors import ModelError, Problem
from ..expr import parse
from ..util import check_number, quote
from .subsystem import DEPTH_LIMIT, Subsystem, definitions, has_subsystems


def is_quantity(text):
    """Whether the string ``text`` reads as one number and a unit (and not as an expression)."""
    try:
        parse(text)
    except ModelError:
        return units.split(text) is not None
    return False


def to_si(value, where):
    """A model parameter's value in SI: a number as it is, a quantity in SI base units."""
    if isinstance(value, str):
        if not is_quantity(value):
            raise ModelError(f"{where}: must be a number or a number with a unit ('500 mm'), "
                             f"got {quote(value)}")
        try:
            return units.to_si(value, "")
        except ModelError as exc:
            raise ModelError(f"{where} = {quote(value)}: {exc}") from None
    return check_number(value, where, "a number or a number with a unit ('500 mm')")


def scaled_name(text):
    """The parameter name of an expression that is one name times numbers (``"L"``,
    ``"-L/2"``, ``"0.5*L"``), or None: such an expression has the dimension of its name."""
    try:
        node = parse(text)._tree
    except ModelError:
        return None
    while True:
        if isinstance(node, ast.Name):
            return node.id
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.UAdd, ast.USub)):
            node = node.operand
        elif isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
            if isinstance(node.left, ast.Constant):
                node = node.right
            elif isinstance(node.right, ast.Constant):
                node = node.left
            else:
                return None
        elif (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div)
              and isinstance(node.right, ast.Constant)):
            node = node.left
        else:
            return None


def uses(model, name, depth=0):
    """Where ``model`` uses its parameter ``name`` with a declared unit: a list of (where,
    unit), following the name into the subsystems it is given to."""
    found = []
    if depth > DEPTH_LIMIT:
        return found
    for comp in model.components.values():
        if isinstance(comp, Subsystem):
            for key, value in comp.given.items():
                if isinstance(value, str) and scaled_name(value) == name:
                    found += [(f"{comp.name}/{where}", unit)
                              for where, unit in uses(comp.definition, key, depth + 1)]
            continue
        for key, spec in comp.params.items():
            value = comp._values.get(key)
            if spec.kind != "real" or value is None:
                continue
            where = model.place(comp, key)
            if spec.shape == ():
                entries = [(where, value, spec.unit_at())]
            elif len(spec.shape) == 1:
                entries = [(f"{where}[{i}]", v, spec.unit_at(i)) for i, v in enumerate(value)]
            else:
                entries = [(f"{where}[{i}][{j}]", v, spec.unit_at())
                           for i, row in enumerate(value) for j, v in enumerate(row)]
            found += [(at, unit) for at, v, unit in entries
                      if unit and isinstance(v, str) and scaled_name(v) == name
                      and units.check_unit(unit)]
    return found


def check_use(text, uses_, what, **fields):
    """Problems of quantity ``text`` (given as ``what``) at each of ``uses_``, with the
    Problem ``fields`` of where it was given."""
    problems = []
    for where, unit in uses_:
        try:
            units.to_si(text, unit)
        except ModelError as exc:
            problems.append(Problem(f"{what} = {quote(text)} is used as {where} [{unit}]: "
                                    f"{exc}", **fields))
    return problems


def problems(model):
    """Every quantity given to a model parameter, here or in a definition placed here (or as
    a subsystem's value), whose dimension differs from a use's declared unit."""
    models = [model, *definitions(model)] if has_subsystems(model) else [model]
    found = []
    for m in models:
        label = "" if m is model else f"definition {m.name!r}: "
        for name, text in m.written_parameters().items():
            if isinstance(text, str):
                at = {"parameter": name, "path": f"parameters.{name}"} if m is model else {}
                found += check_use(text, uses(m, name), f"{label}parameters.{name}", **at)
        for comp in m.components.values():
            if isinstance(comp, Subsystem):
                for key, value in comp.given.items():
                    if isinstance(value, str) and is_quantity(value):
                        inner = [(f"{comp.name}/{where}", unit)
                                 for where, unit in uses(comp.definition, key)]
                        at = m.fields(comp, key) if m is model else {}
                        found += check_use(value, inner, f"{label}{m.place(comp, key)}", **at)
    return found
