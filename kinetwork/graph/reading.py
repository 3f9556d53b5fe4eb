"""Reading a JSON file for people: keys given twice remembered, an integer too large for a
float read as the infinity it amounts to (then refused at its place), and each problem found
recorded at its place in the file, with the fields of its ``Problem`` (``attempt``), never a
traceback from code written for well-formed values. ``io.py`` reads the model format with
these."""

import math

from ..components.base import NAME_LIMIT
from ..errors import ModelError, Problem
from ..util import QUOTE_LIMIT, quote


class JSONObject(dict):
    """A parsed JSON object that remembers keys given twice (``json`` keeps the last)."""

    @classmethod
    def from_pairs(cls, pairs):
        obj = cls()
        obj.repeated = []
        for key, value in pairs:
            if key in obj:
                obj.repeated.append(key)
            obj[key] = value
        return obj


def repeated_keys(value, where, problems):
    if isinstance(value, dict):
        problems.extend(f"{where or 'top level'}: key {quote(key)} appears more than once"
                        for key in getattr(value, "repeated", ()))
        for key, item in value.items():
            repeated_keys(item, f"{where}.{cut(key)}" if where else cut(key), problems)
    elif isinstance(value, list):
        for j, item in enumerate(value):
            repeated_keys(item, f"{where}[{j}]", problems)


def attempt(problems, place, fn, *args, **fields):
    """``fn(*args)``, or None with its failure recorded as a problem at ``place`` (its unset
    fields filled from ``fields``: ``path=``, ``parameter=``)."""
    before = len(problems)
    try:
        return fn(*args)
    except ModelError as exc:
        problems.extend(p if p.startswith(place) else p.where(f"{place}: ")
                        for p in exc.problems)
    except Exception as exc:    # noqa: BLE001
        # odd shapes in a file reach code written for well-formed values: a file may be
        # refused, but never crash the loader
        problems.append(f"{place}: cannot be read ({type(exc).__name__}: "
                        f"{cut(str(exc), QUOTE_LIMIT)})")
    finally:
        fill(problems, before, **fields)
    return None


def fill(problems, before, **fields):
    """Fill the unset fields of the problems recorded since ``before`` from ``fields``."""
    if fields:
        problems[before:] = [Problem.of(p, **fields) for p in problems[before:]]


def read_int(text):
    # an integer beyond float range would overflow in later bounds checks: read it as the
    # infinity it amounts to, then refused as non-finite at its place
    try:
        value = int(text)
        float(value)
        return value
    except (ValueError, OverflowError):
        return -math.inf if text.startswith("-") else math.inf


def plain_copy(value):
    # plain dicts and lists in the model, not the parser's JSONObject objects
    return ({k: plain_copy(v) for k, v in value.items()} if isinstance(value, dict) else
            [plain_copy(v) for v in value] if isinstance(value, list) else value)


def at_source(source, problem):
    """``problem`` (a Problem) as read from file ``source``: its message after the name."""
    return Problem.of(problem).where(f"{source}: ") if source else Problem.of(problem)


def cut(text, limit=NAME_LIMIT):
    """Text from the file for a message's place: as it is when short, else cut; characters
    that do not print (a newline, a lone surrogate) escaped as in Python."""
    text = text if len(text) <= limit else text[:limit - 3] + "..."
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


