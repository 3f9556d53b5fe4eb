"""Closed-form equations: CasADi SX expressions translated to sympy, as in the seed paper.

The compiled system keeps its equations as CasADi SX, which is fast to evaluate but unreadable.
This module replays a CasADi Function's instruction list with sympy operations, so the
mass matrix M and the force vectors V and G (``M qdd + V + G = 0``) can be printed in the
joint coordinates and model parameters, then simplified into the paper's form.
"""

import math
import operator
from fractions import Fraction

import casadi as ca
import sympy as sp


def _flag(relation):
    # CasADi comparisons are numbers (1 or 0), so they must stay usable in arithmetic.
    return sp.Piecewise((sp.Integer(1), relation), (sp.Integer(0), True))


def _trunc(x):
    return sp.sign(x) * sp.floor(sp.Abs(x))


_UNARY = {
    ca.OP_ASSIGN: lambda a: a, ca.OP_NEG: operator.neg, ca.OP_SQ: lambda a: a ** 2,
    ca.OP_TWICE: lambda a: 2 * a, ca.OP_INV: lambda a: 1 / a, ca.OP_SQRT: sp.sqrt,
    ca.OP_EXP: sp.exp, ca.OP_LOG: sp.log, ca.OP_FABS: sp.Abs, ca.OP_SIGN: sp.sign,
    ca.OP_SIN: sp.sin, ca.OP_COS: sp.cos, ca.OP_TAN: sp.tan,
    ca.OP_ASIN: sp.asin, ca.OP_ACOS: sp.acos, ca.OP_ATAN: sp.atan,
    ca.OP_SINH: sp.sinh, ca.OP_COSH: sp.cosh, ca.OP_TANH: sp.tanh,
    ca.OP_ASINH: sp.asinh, ca.OP_ACOSH: sp.acosh, ca.OP_ATANH: sp.atanh,
    ca.OP_FLOOR: sp.floor, ca.OP_CEIL: sp.ceiling, ca.OP_ERF: sp.erf,
    ca.OP_ERFINV: sp.erfinv, ca.OP_LOG1P: lambda a: sp.log(1 + a),
    ca.OP_EXPM1: lambda a: sp.exp(a) - 1, ca.OP_NOT: lambda a: _flag(sp.Eq(a, 0)),
}
_BINARY = {
    ca.OP_ADD: operator.add, ca.OP_SUB: operator.sub, ca.OP_MUL: operator.mul,
    ca.OP_DIV: operator.truediv, ca.OP_POW: operator.pow, ca.OP_CONSTPOW: operator.pow,
    ca.OP_ATAN2: sp.atan2, ca.OP_FMIN: sp.Min, ca.OP_FMAX: sp.Max,
    ca.OP_HYPOT: lambda a, b: sp.sqrt(a ** 2 + b ** 2),
    ca.OP_FMOD: lambda a, b: a - b * _trunc(a / b),
    ca.OP_COPYSIGN: lambda a, b: sp.Abs(a) * sp.sign(b),
    ca.OP_LT: lambda a, b: _flag(sp.Lt(a, b)), ca.OP_LE: lambda a, b: _flag(sp.Le(a, b)),
    ca.OP_EQ: lambda a, b: _flag(sp.Eq(a, b)), ca.OP_NE: lambda a, b: _flag(sp.Ne(a, b)),
    ca.OP_AND: lambda a, b: _flag(sp.And(sp.Ne(a, 0), sp.Ne(b, 0))),
    ca.OP_OR: lambda a, b: _flag(sp.Or(sp.Ne(a, 0), sp.Ne(b, 0))),
    ca.OP_IF_ELSE_ZERO: lambda c, x: sp.Piecewise((x, sp.Ne(c, 0)), (sp.Integer(0), True)),
}
_OP_NAMES = {getattr(ca, n): n for n in dir(ca) if n.startswith("OP_")}


def number(value):
    """A CasADi constant as sympy: exact for integers, simple fractions and multiples of pi.

    The Newton-Euler recursion produces halves and quarters (``L2/2``); keeping them rational
    is what lets the simplified terms read like the paper. Other floats stay floats, printed
    as the user wrote them (9.8, not 49/5).
    """
    value = float(value)
    if not math.isfinite(value):
        return {math.inf: sp.oo, -math.inf: -sp.oo}.get(value, sp.nan)
    if value == int(value):
        return sp.Integer(int(value))
    for base, symbol in ((1.0, sp.Integer(1)), (math.pi, sp.pi)):
        frac = Fraction(value / base).limit_denominator(64)
        if frac.denominator in (2, 3, 4, 6, 8, 12, 16, 32, 64) \
                and float(frac) * base == value:
            return sp.Rational(frac.numerator, frac.denominator) * symbol
    return sp.Float(repr(value), "")


def to_sympy(casadi_exprs, symbols_in):
    """Translate CasADi SX expressions into sympy matrices.

    Parameters
    ----------
    casadi_exprs : sequence of casadi.SX
        Expressions to translate.
    symbols_in : sequence of (casadi.SX, sequence of sympy.Expr)
        Every purely symbolic SX the expressions depend on, each paired with the sympy
        objects that replace its entries (one per entry, column-major as CasADi stores them).

    Returns
    -------
    list of sympy.Matrix
        One per expression, with the expression's shape.

    Raises
    ------
    ValueError
        An input has the wrong number of replacements, or an operation has no sympy form.
    """
    inputs, replacements = [], []
    for sx, syms in symbols_in:
        syms = list(syms)
        if len(syms) != sx.nnz():
            raise ValueError(f"input {sx}: {sx.nnz()} entries but {len(syms)} sympy symbols")
        inputs.append(sx)
        replacements.append(syms)
    f = ca.Function("to_sympy", inputs, [ca.SX(e) for e in casadi_exprs],
                    {"allow_free": False})
    return function_to_sympy(f, replacements)


def function_to_sympy(f, replacements):
    """Replay the instructions of an SX Function ``f`` on sympy inputs ``replacements``."""
    outs = [sp.zeros(*f.size_out(i)) for i in range(f.n_out())]
    places = [f.sparsity_out(i).get_triplet() for i in range(f.n_out())]
    work = {}
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        arg = f.instruction_input(k)
        res = f.instruction_output(k)
        # instruction_input of OP_INPUT is [input index, entry]; instruction_output of
        # OP_OUTPUT is [output index, nonzero]: both checked by experiment (CasADi 3.6).
        if op == ca.OP_INPUT:
            work[res[0]] = replacements[arg[0]][arg[1]]
        elif op == ca.OP_OUTPUT:
            rows, cols = places[res[0]]
            outs[res[0]][rows[res[1]], cols[res[1]]] = work[arg[0]]
        elif op == ca.OP_CONST:
            work[res[0]] = number(f.instruction_constant(k))
        elif op in _UNARY:
            work[res[0]] = _UNARY[op](work[arg[0]])
        elif op in _BINARY:
            work[res[0]] = _BINARY[op](work[arg[0]], work[arg[1]])
        else:
            raise ValueError(f"CasADi operation {_OP_NAMES.get(op, op)} has no sympy "
                             f"translation")
    return outs


def coordinate_symbol(state_name, prefix="q"):
    """A readable symbol name for a joint coordinate: "shoulder.q" -> "q_shoulder".

    Multi-DOF joints ("ball.q[1]") give "q_ball_1".
    """
    joint, _, coord = state_name.partition(".")
    index = coord[coord.find("[") + 1:-1] if "[" in coord else ""
    return f"{prefix}_{joint}" + (f"_{index}" if index else "")


def simplify(expr):
    """Expanded, trig-simplified, expanded again: sums of products like the paper's M."""
    # expand first so the rotation products (sin a cos b + cos a sin b) meet each other;
    # trigsimp then folds them into sin(a + b) and sin^2 + cos^2 into 1.
    return sp.expand(sp.trigsimp(sp.expand(expr)))


def equations_sympy(system, simplified=True):
    """The seed paper's M, V, G (``M qdd + V + G = 0``) of a compiled system, in sympy.

    Parameters
    ----------
    system : kinetwork.System
    simplified : bool
        Apply :func:`simplify` to every entry (slow for long chains).

    Returns
    -------
    dict
        ``M`` (n x n), ``V`` and ``G`` (n x 1) sympy Matrices; the symbols ``q``, ``qd``
        (lists, in the order of ``system.coordinate_names``), ``params`` (name -> Symbol)
        and ``t``.
    """
    eq = system.equations()
    params = {name: sp.Symbol(name, real=True) for name in eq["param_names"]}
    taken = set(params) | {"t"}
    q, qd = [], []
    for coord in system.coordinate_names:
        for prefix, out in (("q", q), ("qd", qd)):
            name = coordinate_symbol(coord, prefix)
            while name in taken:          # a model parameter may already be called q_shoulder
                name += "_"
            taken.add(name)
            out.append(sp.Symbol(name, real=True))
    t = sp.Symbol("t", real=True)
    M, V, G = to_sympy([eq["M"], eq["V"], eq["G"]],
                       [(eq["q"], q), (eq["qd"], qd), (eq["p"], params.values()),
                        (eq["t"], [t])])
    if simplified:
        M, V, G = (m.applyfunc(simplify) for m in (M, V, G))
    return {"M": M, "V": V, "G": G, "q": q, "qd": qd, "params": params, "t": t}
