"""Units as an FMU's model description writes them: Modelica's syntax for the name
(``"N.m/rad"``, ``"m/s2"``, as FMI 2.0 asks), SI base-unit exponents for what it means.

The units kinetwork's components declare are SI units and their products, read here from a
table; pint (slow to start: seconds on a loaded machine) reads only what the table lacks.
"""

import math
import re
from fractions import Fraction

#: FMI's BaseUnit attributes, in order
BASE = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
#: unit -> (factor, exponents of BASE)
TABLE = {
    "kg": (1.0, (1, 0, 0, 0, 0, 0, 0, 0)), "g": (1e-3, (1, 0, 0, 0, 0, 0, 0, 0)),
    "m": (1.0, (0, 1, 0, 0, 0, 0, 0, 0)), "mm": (1e-3, (0, 1, 0, 0, 0, 0, 0, 0)),
    "s": (1.0, (0, 0, 1, 0, 0, 0, 0, 0)), "A": (1.0, (0, 0, 0, 1, 0, 0, 0, 0)),
    "K": (1.0, (0, 0, 0, 0, 1, 0, 0, 0)), "mol": (1.0, (0, 0, 0, 0, 0, 1, 0, 0)),
    "cd": (1.0, (0, 0, 0, 0, 0, 0, 1, 0)), "rad": (1.0, (0, 0, 0, 0, 0, 0, 0, 1)),
    "deg": (math.pi / 180, (0, 0, 0, 0, 0, 0, 0, 1)),
    "N": (1.0, (1, 1, -2, 0, 0, 0, 0, 0)), "J": (1.0, (1, 2, -2, 0, 0, 0, 0, 0)),
    "W": (1.0, (1, 2, -3, 0, 0, 0, 0, 0)), "Pa": (1.0, (1, -1, -2, 0, 0, 0, 0, 0)),
    "Hz": (1.0, (0, 0, -1, 0, 0, 0, 0, 0)), "C": (1.0, (0, 0, 1, 1, 0, 0, 0, 0)),
    "V": (1.0, (1, 2, -3, -1, 0, 0, 0, 0)), "Ohm": (1.0, (1, 2, -3, -2, 0, 0, 0, 0)),
    "ohm": (1.0, (1, 2, -3, -2, 0, 0, 0, 0)), "S": (1.0, (-1, -2, 3, 2, 0, 0, 0, 0)),
    "F": (1.0, (-1, -2, 4, 2, 0, 0, 0, 0)), "H": (1.0, (1, 2, -2, -2, 0, 0, 0, 0)),
    "Wb": (1.0, (1, 2, -2, -1, 0, 0, 0, 0)), "T": (1.0, (1, 0, -2, -1, 0, 0, 0, 0)),
    "1": (1.0, (0,) * 8),
}
_TOKEN = re.compile(r"\s*(?:(?P<name>[A-Za-z_]\w*|1)(?:\s*\^\s*(?P<power>[+-]?\d+))?"
                    r"|(?P<op>[*/])|(?P<open>\()|(?P<close>\)))")


def fmi_name(unit):
    """A kinetwork unit (``"N*m/rad"``, ``"m/s^2"``) in Modelica's syntax (``"N.m/rad"``,
    ``"m/s2"``); "" stays "" (no unit)."""
    if not unit:
        return ""
    text = unit.replace(" ", "").replace("**", "^").replace("*", ".")
    return re.sub(r"\^\(?(-?\d+)\)?", r"\1", text)


def state_rate_unit(unit):
    """The unit of the rate of a quantity in ``unit``: per second (``"rad"`` -> ``"rad/s"``,
    ``"m/s^2"`` -> ``"m/s^3"``, ``"N*m/rad"`` -> ``"N*m/(rad*s)"``)."""
    if not unit or unit == "1":
        return "1/s"
    found = re.fullmatch(r"(.*)/s(?:\^(\d+))?", unit)
    if found and "/" not in found[1]:
        return f"{found[1]}/s^{int(found[2] or 1) + 1}"
    top, _, bottom = unit.partition("/")
    return f"{unit}/s" if not bottom else f"{top}/({bottom}*s)"


def definition(unit):
    """(factor, {BaseUnit attribute: exponent}) of ``unit`` in SI base units, or None when it
    cannot be read or its exponents are not whole numbers."""
    found = _table(unit)
    if found is None:
        found = _pint(unit)
    if found is None:
        return None
    factor, exponents = found
    return factor, {k: e for k, e in zip(BASE, exponents) if e}


def _table(unit):
    """``unit`` read from TABLE: names with powers, * and /, parentheses; or None."""
    pos, stack, factor, exps = 0, [], 1.0, [0] * 8
    sign, signs = 1, []
    text = unit.strip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m or m.end() == pos:
            return None
        pos = m.end()
        if m["name"]:
            entry = TABLE.get(m["name"])
            if entry is None:
                return None
            power = int(m["power"] or 1) * sign
            factor *= entry[0] ** power
            exps = [e + power * b for e, b in zip(exps, entry[1])]
            sign = signs[-1] if signs else 1
        elif m["op"]:
            sign = (signs[-1] if signs else 1) * (-1 if m["op"] == "/" else 1)
        elif m["open"]:
            signs.append(sign)
            stack.append(sign)
        else:
            if not stack:
                return None
            stack.pop()
            signs.pop()
            sign = signs[-1] if signs else 1
    return (factor, tuple(exps)) if not stack else None


def _pint(unit):
    """``unit`` read by pint (whatever TABLE lacks), or None."""
    from ..units import registry
    names = {"kilogram": "kg", "meter": "m", "second": "s", "ampere": "A", "kelvin": "K",
             "mole": "mol", "candela": "cd", "radian": "rad"}
    try:
        base = registry().Quantity(1, unit).to_base_units()
    except Exception:       # pint raises several kinds on what it cannot read
        return None
    exps = dict.fromkeys(BASE, 0)
    for name, power in base.units._units.items():
        if name not in names or Fraction(power).denominator != 1:
            return None
        exps[names[name]] = int(power)
    return float(base.magnitude), tuple(exps[k] for k in BASE)
