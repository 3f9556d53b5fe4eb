"""Safe arithmetic expressions for parameter values, such as ``"-L1/2"`` or ``"2*sin(3*t)"``.

Strings are parsed with :mod:`ast` and only numbers, names, arithmetic operators and a fixed
set of functions are accepted; nothing from a string is ever executed. ``^`` is a power, as in
Modelica and Maple (``"L^2"`` is ``L**2``). Conditionals are a function, as CasADi's:
``if_else(v < 0, a, b)`` with one comparison (``< <= > >= == !=``, true is 1 and false 0) as its
condition, so a piecewise law such as MSL's GasForce2 is one expression. An expression is
evaluated over any numeric type that supports arithmetic (floats, CasADi SX), so the same
parsed tree serves validation with numbers and compilation with symbols.

Comparisons ``<``, ``<=``, ``>``, ``>=`` are events, as Modelica's relations are: the
integration stops where one changes (``kinetwork.equations.relations`` finds them in the
compiled equations). ``noEvent(e)`` takes the comparisons, ``abs``, ``sign``, ``min`` and
``max`` inside ``e`` literally, as Modelica's ``noEvent``: the integrator steps across them
without stopping. Over CasADi they are then built from ``copysign`` and logical not
(``literal_functions``), which the event detection does not read as relations.
"""

import ast
import copy
import functools
import math

from .errors import ModelError
from .util import quote, suggest

# name -> (function over floats, name of the CasADi/numpy method it maps to)
FUNCTIONS = {
    "sin": math.sin, "cos": math.cos, "tan": math.tan,
    "asin": math.asin, "acos": math.acos, "atan": math.atan, "atan2": math.atan2,
    "sinh": math.sinh, "cosh": math.cosh, "tanh": math.tanh,
    "exp": math.exp, "log": math.log, "sqrt": math.sqrt, "abs": abs,
    "min": min, "max": max, "sign": lambda x: math.copysign(1.0, x) if x else 0.0,
    "if_else": lambda cond, a, b: a if cond else b,
    "noEvent": lambda e: e,
}
CONSTANTS = {"pi": math.pi, "e": math.e}
#: how many arguments each function takes (CasADi's fmin/fmax take two, as does atan2)
ARITY = {**{name: 1 for name in FUNCTIONS}, "atan2": 2, "min": 2, "max": 2, "if_else": 3}

_BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b,
           ast.Mult: lambda a, b: a * b, ast.Div: lambda a, b: a / b,
           ast.Pow: lambda a, b: a ** b}
_UNARY = {ast.USub: lambda a: -a, ast.UAdd: lambda a: a}
#: comparisons give 1 or 0 over numbers, a CasADi comparison over symbols
_COMPARE = {ast.Lt: lambda a, b: a < b, ast.LtE: lambda a, b: a <= b,
            ast.Gt: lambda a, b: a > b, ast.GtE: lambda a, b: a >= b,
            ast.Eq: lambda a, b: a == b, ast.NotEq: lambda a, b: a != b}
#: how a refused operator is written, to name it in the message
_SYMBOLS = {ast.Mod: "%", ast.FloorDiv: "//", ast.MatMult: "@", ast.BitAnd: "&",
            ast.BitOr: "|", ast.LShift: "<<", ast.RShift: ">>", ast.Invert: "~",
            ast.Not: "not", ast.And: "and", ast.Or: "or", ast.Eq: "==", ast.NotEq: "!=",
            ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Is: "is",
            ast.IsNot: "is not", ast.In: "in", ast.NotIn: "not in"}
#: what other refused constructs are called in a message
_CONSTRUCTS = {ast.IfExp: "a conditional (x if c else y)", ast.Subscript: "indexing ([...])",
               ast.List: "a list", ast.Tuple: "a tuple (a comma)", ast.Dict: "a dict",
               ast.Set: "a set", ast.Lambda: "lambda", ast.NamedExpr: "assignment (:=)",
               ast.Starred: "unpacking (*)", ast.JoinedStr: "an f-string",
               ast.Attribute: "an attribute (.)", ast.Await: "await",
               ast.ListComp: "a comprehension", ast.GeneratorExp: "a comprehension",
               ast.SetComp: "a comprehension", ast.DictComp: "a comprehension",
               ast.Slice: "a slice"}
_ALLOWED = "numbers, parameter names, + - * / ** ^, one comparison and functions"
_MAX_LENGTH = 2000


class Expression:
    """A parsed, checked arithmetic expression; ``names`` are the free symbols it uses."""

    def __init__(self, text):
        if not isinstance(text, str):
            raise ModelError(f"expression must be a string, got {quote(text)}")
        self.text = text
        if len(text) > _MAX_LENGTH:
            raise ModelError(f"expression longer than {_MAX_LENGTH} characters "
                             f"({len(text)}): {quote(text)}")
        try:
            text.encode("utf-8")
        except UnicodeEncodeError as exc:     # a lone surrogate, from JSON's "\ud800"
            raise ModelError(f"expression {quote(text)}: not valid text (a lone surrogate "
                             f"at character {exc.start})") from None
        try:
            # no bitwise operators are accepted, so "^" is free to mean a power
            tree = ast.parse(text.strip().replace("^", "**"), mode="eval")
            self.names = set()
            self._check(tree.body)
        except ModelError:
            raise
        except SyntaxError as exc:
            raise ModelError(f"cannot parse expression {quote(text)}: {exc.msg}") from None
        except ValueError as exc:            # a NUL character
            raise ModelError(f"cannot parse expression {quote(text)}: {exc}") from None
        except (RecursionError, MemoryError):
            raise ModelError(f"expression nested too deeply ({len(text)} characters)") from None
        self._tree = tree.body

    def _check(self, node):
        text = quote(self.text)
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise ModelError(f"expression {text}: only numbers are allowed as "
                                 f"constants, got {quote(node.value)}")
        elif isinstance(node, ast.Name):
            if node.id not in CONSTANTS:
                self.names.add(node.id)
        elif isinstance(node, ast.Attribute) and dotted(node):
            self.names.add(dotted(node))       # a parameter of a subsystem: "cyl1.L"
        elif isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            self._check(node.left)
            self._check(node.right)
        elif isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
            self._check(node.operand)
        elif (isinstance(node, ast.Compare) and len(node.ops) == 1
              and type(node.ops[0]) in _COMPARE):
            self._check(node.left)
            self._check(node.comparators[0])
        elif isinstance(node, ast.Compare) and all(type(op) in _COMPARE for op in node.ops):
            raise ModelError(f"expression {text}: a chained comparison is not allowed; "
                             f"nest if_else() with one comparison each")
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
              and node.func.id in FUNCTIONS and not node.keywords):
            name, given = node.func.id, len(node.args)
            if given != ARITY[name]:
                takes = f"{ARITY[name]} argument{'s' if ARITY[name] > 1 else ''}"
                raise ModelError(f"expression {text}: {name}() takes {takes}, got {given}")
            for arg in node.args:
                self._check(arg)
        else:
            if isinstance(node, ast.Call):
                name = getattr(node.func, "id", None)
                if name is None:
                    raise ModelError(f"expression {text}: calling anything but a named "
                                     f"function is not allowed")
                if name in FUNCTIONS:                         # with keyword arguments
                    raise ModelError(f"expression {text}: {name}() takes no keyword "
                                     f"arguments")
                raise ModelError(f"expression {text}: call of {quote(name)} is not allowed"
                                 f"{suggest(name, FUNCTIONS)}; functions are "
                                 f"{', '.join(sorted(FUNCTIONS))}")
            raise ModelError(f"expression {text}: {_refused(node)} is not allowed (only "
                             f"{_ALLOWED})")

    def evaluate(self, env, functions=None):
        """Evaluate with ``env`` mapping names to values; ``functions`` overrides FUNCTIONS.
        Within ``noEvent(...)``, comparisons and the functions that ``functions[LITERAL]``
        holds (when it has that key) are built by those instead."""
        funcs = functions or FUNCTIONS
        literal = funcs.get(LITERAL, {})

        def ev(node, plain=True):
            if isinstance(node, ast.Constant):
                return float(node.value)
            if isinstance(node, ast.Name):
                if node.id in env:
                    return env[node.id]
                return CONSTANTS[node.id]
            if isinstance(node, ast.Attribute):
                return env[dotted(node)]
            if isinstance(node, ast.BinOp):
                return _BINARY[type(node.op)](ev(node.left, plain), ev(node.right, plain))
            if isinstance(node, ast.UnaryOp):
                return _UNARY[type(node.op)](ev(node.operand, plain))
            if isinstance(node, ast.Compare):
                compare = _COMPARE if plain else literal or _COMPARE
                result = compare[type(node.ops[0])](ev(node.left, plain),
                                                    ev(node.comparators[0], plain))
                return float(result) if isinstance(result, bool) else result
            name = node.func.id
            if name == "noEvent":
                return ev(node.args[0], False)
            call = funcs[name] if plain else literal.get(name, funcs[name])
            return call(*[ev(a, plain) for a in node.args])

        try:
            return ev(self._tree)
        except RecursionError:
            raise ModelError(f"expression nested too deeply ({len(self.text)} "
                             f"characters)") from None

    def __repr__(self):
        return f"Expression({self.text!r})"


def _refused(node):
    """What the refused node ``node`` is, in the words its writer used."""
    op = getattr(node, "op", None)
    if isinstance(node, ast.Compare):
        op = node.ops[0]
    if op is not None and type(op) in _SYMBOLS:
        return f"the operator {_SYMBOLS[type(op)]!r}"
    return _CONSTRUCTS.get(type(node), type(node).__name__)


def dotted(node):
    """The path of a name like ``cyl1.piston.m`` (names of subsystem parameters are paths),
    or None for any other attribute access."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    return ".".join([node.id, *reversed(parts)])


def rename(text, names):
    """``text`` with each free name in ``names`` (name -> expression text) replaced by its
    expression, parenthesised as needed: how a subsystem's parameter expressions are written
    in the names of the model it is placed in."""
    tree = parse(text)._tree

    class Renamer(ast.NodeTransformer):
        def visit_Call(self, node):          # a function's name is not a free name
            node.args = [self.visit(arg) for arg in node.args]
            return node

        def visit_Attribute(self, node):
            path = dotted(node)
            return _replacement(names[path]) if path in names else node

        def visit_Name(self, node):
            return _replacement(names[node.id]) if node.id in names else node
    return ast.unparse(Renamer().visit(copy.deepcopy(tree)))


def _replacement(text):
    return ast.parse(text, mode="eval").body


def casadi_functions():
    """FUNCTIONS over CasADi SX (imported lazily so components stay light), with the
    literal builds of ``noEvent`` under LITERAL."""
    import casadi as ca
    return {
        "sin": ca.sin, "cos": ca.cos, "tan": ca.tan, "asin": ca.asin, "acos": ca.acos,
        "atan": ca.atan, "atan2": ca.atan2, "sinh": ca.sinh, "cosh": ca.cosh, "tanh": ca.tanh,
        "exp": ca.exp, "log": ca.log, "sqrt": ca.sqrt, "abs": ca.fabs, "min": ca.fmin,
        "max": ca.fmax, "sign": ca.sign, "if_else": ca.if_else, "noEvent": lambda e: e,
        LITERAL: literal_functions(),
    }


#: the key of ``casadi_functions`` holding what noEvent builds comparisons and kinks with
LITERAL = "literal"


def literal_functions():
    """Comparisons (by their ``ast`` operator type), ``abs``, ``sign``, ``min`` and ``max``
    over CasADi SX, built without CasADi's relations or kinked operations (from
    ``copysign`` and logical not): the same numbers and derivatives, but nothing that
    ``kinetwork.equations.relations`` takes for an event. What ``noEvent(...)`` means, and
    what a component uses for a guard that must never stop the integration (a direction
    whose length may pass zero)."""
    import casadi as ca

    def positive(d):
        """1 where d > 0, else 0 (also at d = -0 and +0)."""
        return (ca.copysign(1, d) + 1) / 2 * (1 - ca.logic_not(d))

    def sign(v):
        return positive(v) - positive(-v)
    return {ast.Lt: lambda a, b: positive(b - a), ast.Gt: lambda a, b: positive(a - b),
            ast.LtE: lambda a, b: 1 - positive(a - b), ast.GtE: lambda a, b: 1 - positive(b - a),
            ast.Eq: lambda a, b: ca.logic_not(a - b),
            ast.NotEq: lambda a, b: 1 - ca.logic_not(a - b),
            "abs": lambda v: v * sign(v), "sign": sign,
            "min": lambda a, b: a + positive(a - b) * (b - a),
            "max": lambda a, b: a + positive(b - a) * (b - a)}


@functools.lru_cache(maxsize=4096)
def parse(text):
    """The Expression of ``text``, parsed once per process however often it is asked for:
    a parameter is checked at construction, evaluated at validation and bound to symbols at
    compilation from the same parsed tree."""
    return Expression(text)
