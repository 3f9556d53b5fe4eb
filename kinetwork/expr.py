"""Safe arithmetic expressions for parameter values, such as ``"-L1/2"`` or ``"2*sin(3*t)"``.

Strings are parsed with :mod:`ast` and only numbers, names, arithmetic operators and a fixed
set of functions are accepted; nothing from a string is ever executed. An expression is
evaluated over any numeric type that supports arithmetic (floats, CasADi SX), so the same
parsed tree serves validation with numbers and compilation with symbols.
"""

import ast
import difflib
import math

from .errors import ModelError

# name -> (function over floats, name of the CasADi/numpy method it maps to)
FUNCTIONS = {
    "sin": math.sin, "cos": math.cos, "tan": math.tan,
    "asin": math.asin, "acos": math.acos, "atan": math.atan, "atan2": math.atan2,
    "sinh": math.sinh, "cosh": math.cosh, "tanh": math.tanh,
    "exp": math.exp, "log": math.log, "sqrt": math.sqrt, "abs": abs,
    "min": min, "max": max, "sign": lambda x: math.copysign(1.0, x) if x else 0.0,
}
CONSTANTS = {"pi": math.pi, "e": math.e}

_BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b,
           ast.Mult: lambda a, b: a * b, ast.Div: lambda a, b: a / b,
           ast.Pow: lambda a, b: a ** b}
_UNARY = {ast.USub: lambda a: -a, ast.UAdd: lambda a: a}
_MAX_LENGTH = 2000


class Expression:
    """A parsed, checked arithmetic expression; ``names`` are the free symbols it uses."""

    def __init__(self, text):
        self.text = text
        if len(text) > _MAX_LENGTH:
            raise ModelError(f"expression longer than {_MAX_LENGTH} characters")
        try:
            tree = ast.parse(text.strip(), mode="eval")
            self.names = set()
            self._check(tree.body)
        except SyntaxError as exc:
            raise ModelError(f"cannot parse expression {text!r}: {exc.msg}") from None
        except (RecursionError, MemoryError):
            raise ModelError(f"expression nested too deeply ({len(text)} characters)") from None
        self._tree = tree.body

    def _check(self, node):
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise ModelError(f"expression {self.text!r}: only numbers are allowed as "
                                 f"constants, got {node.value!r}")
        elif isinstance(node, ast.Name):
            if node.id not in CONSTANTS:
                self.names.add(node.id)
        elif isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            self._check(node.left)
            self._check(node.right)
        elif isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
            self._check(node.operand)
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
              and node.func.id in FUNCTIONS and not node.keywords):
            for arg in node.args:
                self._check(arg)
        else:
            if isinstance(node, ast.Call):
                name = getattr(node.func, "id", None)
                if name is None:
                    raise ModelError(f"expression {self.text!r}: calling anything but a named "
                                     f"function is not allowed")
                close = difflib.get_close_matches(name, FUNCTIONS, n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
                raise ModelError(f"expression {self.text!r}: call of {name!r} is not allowed"
                                 f"{hint}; functions are {', '.join(sorted(FUNCTIONS))}")
            raise ModelError(f"expression {self.text!r}: {type(node).__name__} is not allowed "
                             f"(only numbers, names, + - * / ** and functions)")

    def evaluate(self, env, functions=None):
        """Evaluate with ``env`` mapping names to values; ``functions`` overrides FUNCTIONS."""
        funcs = functions or FUNCTIONS

        def ev(node):
            if isinstance(node, ast.Constant):
                return float(node.value)
            if isinstance(node, ast.Name):
                if node.id in env:
                    return env[node.id]
                return CONSTANTS[node.id]
            if isinstance(node, ast.BinOp):
                return _BINARY[type(node.op)](ev(node.left), ev(node.right))
            if isinstance(node, ast.UnaryOp):
                return _UNARY[type(node.op)](ev(node.operand))
            return funcs[node.func.id](*[ev(a) for a in node.args])

        try:
            return ev(self._tree)
        except RecursionError:
            raise ModelError(f"expression nested too deeply ({len(self.text)} characters)") from None

    def __repr__(self):
        return f"Expression({self.text!r})"


def casadi_functions():
    """FUNCTIONS over CasADi SX (imported lazily so components stay light)."""
    import casadi as ca
    return {
        "sin": ca.sin, "cos": ca.cos, "tan": ca.tan, "asin": ca.asin, "acos": ca.acos,
        "atan": ca.atan, "atan2": ca.atan2, "sinh": ca.sinh, "cosh": ca.cosh, "tanh": ca.tanh,
        "exp": ca.exp, "log": ca.log, "sqrt": ca.sqrt, "abs": ca.fabs, "min": ca.fmin,
        "max": ca.fmax, "sign": ca.sign,
    }
