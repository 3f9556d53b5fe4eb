"""Units where users write numbers: ``"2 kg"``, ``"30 deg"``, ``"5 mm"``, ``"1 N*m/rad"``.

The rule: a parameter value is a number (SI), an expression in model parameters (SI), or a
*quantity*, one number followed by a unit (``"5 mm"``, ``"-30 deg"``, ``"1e-3 kg*m^2"``). A
quantity is converted to the SI unit the parameter declares, exactly (pint with rational
arithmetic: ``"5 mm"`` is 0.005, ``"30 deg"`` the double nearest to pi/6), and refused with
both units named when its dimension differs (``"2 m"`` for a mass). Units do not mix with
expressions (``"L/2 + 5 mm"`` is refused): model parameters are plain SI numbers, so an
expression has no units to check.

Angles are dimensionless, as in SI and Modelica (``"1 N*m"`` is a valid ``N*m/rad``). A
parameter whose unit is ``""`` (a signal block's gain or offset, in the unit of its signal)
takes any quantity, converted to SI base units unchecked; ``"1"`` means dimensionless.

pint is imported the first time a quantity is met, so models written in plain numbers never
pay for it.
"""

import functools
import re
from fractions import Fraction

from .errors import ModelError

#: one number, then a unit starting with a letter (or degree sign, percent, micro sign)
_QUANTITY = re.compile(r"\s*(?P<number>[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE](?P<exp>[+-]?\d+))?)"
                       r"\s*(?P<unit>(?:[^\W\d]|[°%µ]).*?)\s*", re.S)
#: the longest quantity read, and the largest decimal exponent of its number: exact
#: arithmetic on 1e999999999 would take forever, and no physical value needs either
MAX_LENGTH, MAX_EXPONENT = 200, 300
#: what a unit may be written with (pint's parser reads more: "#" starts a comment there)
_UNIT_TEXT = re.compile(r"[\w\s*/^().+\-°%µ]+")
#: the largest number inside a unit (a power): km**999999999 would be computed exactly
MAX_POWER = 100
#: a number directly followed by a name, somewhere in a text: a unit inside an expression
_UNIT_INSIDE = re.compile(r"(?<![\w.])\d+(?:\.\d*)?(?:[eE][+-]?\d+)?\s*[^\W\d]", re.S)


def split(text):
    """The unit text of a quantity ``"5 mm"`` (``"mm"``), or None if ``text`` is not one."""
    match = _QUANTITY.fullmatch(text)
    return match["unit"] if match else None


def hint(text):
    """Advice for an expression that failed to parse and seems to hold a unit, or ""."""
    if _UNIT_INSIDE.search(text):
        return ("; a unit goes after one number, as in '5 mm' or '30 deg' (expressions are "
                "in SI units)")
    return ""


@functools.lru_cache(maxsize=1)
def registry():
    """pint's unit registry, with exact (rational) arithmetic."""
    import pint
    ureg = pint.UnitRegistry(non_int_type=Fraction)
    ureg.define("Ohm = ohm")          # Modelica's spelling
    return ureg


def _dimension(quantity):
    """The dimension of ``quantity`` as "[mass]*[length]^2/[time]^2" (pint's own formatter
    fails on the rational exponents of an exact registry)."""
    def power(name, exp):
        exp = abs(exp)
        exp = int(exp) if exp == int(exp) else exp
        return name if exp == 1 else f"{name}^{exp}"
    dims = sorted(quantity.dimensionality.items())
    up = "*".join(power(k, e) for k, e in dims if e > 0)
    down = "*".join(power(k, e) for k, e in dims if e < 0)
    if not up and not down:
        return "dimensionless"
    return (up or "1") + (f"/{down}" if down else "")


@functools.lru_cache(maxsize=4096)
def to_si(text, unit):
    """The number of quantity ``text`` in ``unit`` (a declared SI unit; "" converts to SI
    base units, "1" to a pure number). Raises ModelError (without a place: the caller adds
    it) for an unknown unit or a wrong dimension, naming both units."""
    import pint
    written = split(text)
    if len(text) > MAX_LENGTH:
        raise ModelError(f"a quantity longer than {MAX_LENGTH} characters ({len(text)})")
    match = _QUANTITY.fullmatch(text)
    if match is None:
        raise ModelError(f"{text[:MAX_LENGTH]!r} is not a number with a unit")
    if match["exp"] and abs(int(match["exp"][:6])) > MAX_EXPONENT:
        raise ModelError(f"the number {match['number'][:40]!r} is out of range (exponent "
                         f"beyond {MAX_EXPONENT})")
    if not _UNIT_TEXT.fullmatch(written):
        raise ModelError(f"cannot read the unit {written!r} in {text!r} (a unit is names, "
                         f"numbers and * / ^ ( ))")
    if any(float(n) > MAX_POWER for n in re.findall(r"\d+(?:\.\d*)?", written)):
        raise ModelError(f"a power in the unit {written!r} is beyond {MAX_POWER}")
    check_powers(text)
    ureg = registry()
    try:
        quantity = ureg.Quantity(text.strip())
    except pint.UndefinedUnitError as exc:
        name = exc.unit_names[0] if exc.unit_names else written
        raise ModelError(f"unknown unit {name!r} in {text!r}") from None
    except pint.OffsetUnitCalculusError:
        raise ModelError(f"{written!r} is a unit with an offset (a temperature scale); "
                         f"give the value in {unit or 'SI units'}") from None
    except Exception as exc:      # pint's parser raises several kinds on malformed units
        raise ModelError(f"cannot read the unit {written!r} in {text!r} ({_why(exc)})") \
            from None
    if not isinstance(quantity, ureg.Quantity):   # "2 pi" parses to a bare number
        quantity = ureg.Quantity(quantity)
    try:
        if unit == "":
            value = quantity.to_base_units().magnitude
        else:
            value = quantity.to("dimensionless" if unit == "1" else unit).magnitude
    except pint.DimensionalityError:
        target = ureg.Quantity(1, "dimensionless" if unit == "1" else unit)
        raise ModelError(f"{written} ({_dimension(quantity)}) does not convert to {unit} "
                         f"({_dimension(target)})") from None
    except Exception as exc:      # an offset unit inside a product, and the like
        raise ModelError(f"cannot convert {text!r} to {unit or 'SI units'} ({_why(exc)})") \
            from None
    try:
        return float(value)
    except OverflowError:
        raise ModelError(f"{text!r} is out of range in {unit or 'SI units'}") from None


def check_powers(text):
    """Refuse (ModelError) a quantity whose powers would take unbounded work to compute.

    pint evaluates a unit exactly: ``kg^100^100^100`` is kg to the power 100^(100^100), and
    ``(km/m)^(100*100*100*100)`` is 1000^(10^8), whose digits alone would not fit in memory.
    So the expression pint would evaluate (the same preprocessing, tokens and tree) is
    walked first, bottom-up, without evaluating a unit: an exponent must be a number of at
    most MAX_POWER in size, the number a power computes at most MAX_DIGITS digits, and the
    total power of the units (``kg^2*m^3`` is 5) at most MAX_DEGREE."""
    from pint import pint_eval
    from pint.util import string_preprocessor
    try:
        tree = pint_eval.build_eval_tree(pint_eval.tokenizer(string_preprocessor(text)))
    except Exception:        # pint says what is wrong when it reads it: nothing to bound
        return
    _bounds(tree, text)


#: the largest total power of the units in a quantity, and the most digits a number computed
#: inside it may have (1000^100 is 300 digits): bounded work whatever the text
MAX_DEGREE, MAX_DIGITS = 1000, 1000


def _bounds(node, text):
    """(number or None, degree) of a node of pint's tree: its value when it is a plain
    number, and the total power of the units in it (see :func:`check_powers`)."""
    import tokenize
    from fractions import Fraction
    if node.right is None and node.operator is None:          # a token
        token = node.left
        if token.type == tokenize.NUMBER:
            try:
                return Fraction(token.string), 0
            except (ValueError, ZeroDivisionError):
                return None, 0
        return None, 1
    if node.right is None:                                    # unary + or -
        value, degree = _bounds(node.left, text)
        return (-value if value is not None and node.operator.string == "-" else value), degree
    (a, da), (b, db) = _bounds(node.left, text), _bounds(node.right, text)
    op = node.operator.string if node.operator else "*"
    if op in ("**", "^"):
        if b is None or db:
            raise ModelError("an exponent in the unit must be a number")
        if abs(b) > MAX_POWER:
            raise ModelError(f"an exponent of {_size(b)} in the unit is beyond {MAX_POWER}")
        degree = da * abs(b)
        value = None
        if a is not None:
            digits = abs(b) * (len(str(a.numerator)) + len(str(a.denominator)))
            if digits > MAX_DIGITS:
                raise ModelError(f"a power in the unit has more than {MAX_DIGITS} digits")
            value = a ** b if b.denominator == 1 else None
    elif op in ("*", "/", ""):
        degree = da + db
        value = None
        if a is not None and b is not None:
            if len(str(a.numerator)) + len(str(b.numerator)) + len(str(a.denominator)) + \
                    len(str(b.denominator)) > MAX_DIGITS:
                raise ModelError(f"a number in the unit has more than {MAX_DIGITS} digits")
            value = a * b if op != "/" else (a / b if b else None)
    elif op in ("+", "-"):
        degree = max(da, db)
        value = a + b if op == "+" and a is not None and b is not None else \
            a - b if a is not None and b is not None else None
    else:
        raise ModelError(f"cannot read the unit in {text[:MAX_LENGTH]!r} (the operator "
                         f"{op!r:.20})")
    if degree > MAX_DEGREE:
        raise ModelError(f"units to a total power of {_size(degree)} in the unit, beyond "
                         f"{MAX_DEGREE}")
    return value, degree


def _size(number):
    """A number for a message, however large."""
    return f"{float(number):g}" if abs(number) < 10**300 else "more than 1e300"


def _why(exc):
    """pint's own words for a refusal; some of its messages fail to format exact numbers."""
    try:
        return str(exc) or type(exc).__name__
    except Exception:
        return type(exc).__name__


def check_unit(unit):
    """Whether pint reads the declared unit ``unit`` ("" and "1" included)."""
    if unit in ("", "1"):
        return True
    try:
        registry().Quantity(1, unit)
    except Exception:
        return False
    return True
