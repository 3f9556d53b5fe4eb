"""Closed-form equations: CasADi SX expressions translated to sympy, as in the seed paper.

The compiled system keeps its equations as CasADi SX, which is fast to evaluate but unreadable.
This module replays a CasADi Function's instruction list with sympy operations, so the
mass matrix M and the force vectors V and G (``M qdd + V + G = 0``) can be printed in the
joint coordinates and model parameters, then simplified into the paper's form.
"""

import math
import operator
import re
from fractions import Fraction

import casadi as ca
import sympy as sp

from .errors import ModelError


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
    ca.OP_REMAINDER: lambda a, b: a - b * sp.floor(a / b + sp.Rational(1, 2)),
    ca.OP_COPYSIGN: lambda a, b: sp.Abs(a) * sp.sign(b),
    ca.OP_LT: lambda a, b: _flag(sp.Lt(a, b)), ca.OP_LE: lambda a, b: _flag(sp.Le(a, b)),
    ca.OP_EQ: lambda a, b: _flag(sp.Eq(a, b)), ca.OP_NE: lambda a, b: _flag(sp.Ne(a, b)),
    ca.OP_AND: lambda a, b: _flag(sp.And(sp.Ne(a, 0), sp.Ne(b, 0))),
    ca.OP_OR: lambda a, b: _flag(sp.Or(sp.Ne(a, 0), sp.Ne(b, 0))),
    ca.OP_IF_ELSE_ZERO: lambda c, x: sp.Piecewise((x, sp.Ne(c, 0)), (sp.Integer(0), True)),
}
_OP_NAMES = {getattr(ca, n): n for n in dir(ca) if n.startswith("OP_")}
_DENOMINATORS = (1, 2, 3, 4, 6, 8, 12, 16, 32, 64)
#: round-off floor relative to the largest coefficient of M, V or G: physical terms are never
#: this small against each other, round-off (~1e-16) always is
ROUNDOFF = 1e-13
#: CasADi operations of M, V, G above which equations_sympy does not simplify by default
SIMPLIFY_LIMIT = 1000


def number(value, rtol=0.0):
    """A float as sympy: exact for integers, simple fractions and multiples of pi.

    The Newton-Euler recursion produces halves and quarters (``L2/2``); keeping them rational
    is what lets the simplified terms read like the paper. Other floats stay 53-bit Floats
    (printed with ``full_prec=False`` they read as the user wrote them: 9.81, not 49/5).
    ``rtol`` > 0 also snaps floats within that relative distance of such a number, which
    removes round-off such as 0.9999999999999999.
    """
    value = float(value)
    if not math.isfinite(value):
        return {math.inf: sp.oo, -math.inf: -sp.oo}.get(value, sp.nan)
    for base, symbol in ((1.0, sp.Integer(1)), (math.pi, sp.pi)):
        frac = Fraction(value / base).limit_denominator(64)
        if frac.denominator in _DENOMINATORS \
                and abs(float(frac) * base - value) <= rtol * abs(value):
            return sp.Rational(frac.numerator, frac.denominator) * symbol
    return sp.Float(value)


def tidy(expr, floor=0.0, rtol=1e-12):
    """Remove floating-point round-off from an expanded expression.

    Terms whose float coefficient is below ``floor`` in magnitude are dropped (a rotation by
    90 degrees leaves 6e-17*cos(q) behind); floats within ``rtol`` of a simple fraction
    become that fraction. Exact (rational) coefficients are never dropped.
    """
    terms = []
    for term in sp.Add.make_args(expr):
        coeff, _ = term.as_coeff_Mul()
        if not (isinstance(coeff, sp.Float) and abs(coeff) < floor):
            terms.append(term)
    out = sp.Add(*terms)
    return out.xreplace({f: number(f, rtol) for f in out.atoms(sp.Float)})


def coefficient_scale(exprs):
    """Largest numeric coefficient among the terms of expanded expressions (1 if none)."""
    coeffs = [abs(float(t.as_coeff_Mul()[0])) for e in exprs for t in sp.Add.make_args(e)]
    return max([c for c in coeffs if math.isfinite(c)] or [1.0])


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
    return function_to_sympy(_function(casadi_exprs, symbols_in),
                             [syms for _, syms in symbols_in])[0]


def to_sympy_shared(casadi_exprs, symbols_in, prefix="w"):
    """Like :func:`to_sympy`, with every intermediate result used twice or more named.

    Printed as trees, the expressions of a chain grow exponentially with its length (the
    CasADi graph shares them); named, they stay as long as the graph. This is CasADi's own
    common-subexpression structure, so it costs no search (sympy's cse takes minutes).

    Returns
    -------
    matrices : list of sympy.Matrix
        The expressions, in the input symbols and the names.
    shared : list of (sympy.Symbol, sympy.Expr)
        The names ``w0, w1, ...`` and their definitions, each using only earlier ones.
    """
    return function_to_sympy(_function(casadi_exprs, symbols_in),
                             [syms for _, syms in symbols_in], prefix)


def _function(casadi_exprs, symbols_in):
    inputs = []
    for sx, syms in symbols_in:
        n = len(list(syms))
        if n != sx.nnz():
            raise ValueError(f"input {sx}: {sx.nnz()} entries but {n} sympy symbols")
        inputs.append(sx)
    return ca.Function("to_sympy", inputs, [ca.SX(e) for e in casadi_exprs],
                       {"allow_free": False})


def function_to_sympy(f, replacements, prefix=None):
    """Run the instructions of a CasADi SX Function on sympy inputs.

    Parameters
    ----------
    f : casadi.Function
        An SX Function, e.g. ``system.f_rhs``.
    replacements : sequence of sequence of sympy.Expr
        For each input of ``f``, one sympy object per nonzero.
    prefix : str, optional
        Name results used twice or more (see :func:`to_sympy_shared`).

    Returns
    -------
    (list of sympy.Matrix, list of (sympy.Symbol, sympy.Expr))
        The outputs, and the named shared parts (empty without ``prefix``).
    """
    replacements = [list(syms) for syms in replacements]
    outs = [sp.zeros(*f.size_out(i)) for i in range(f.n_out())]
    places = [f.sparsity_out(i).get_triplet() for i in range(f.n_out())]
    program = [(f.instruction_id(k), f.instruction_input(k), f.instruction_output(k))
               for k in range(f.n_instructions())]
    uses = _uses(program) if prefix else {}
    names = sp.numbered_symbols(prefix or "w", real=True,
                                exclude=set().union(*replacements))
    work, shared, known = {}, [], {}
    for k, (op, arg, res) in enumerate(program):
        # instruction_input of OP_INPUT is [input index, entry]; instruction_output of
        # OP_OUTPUT is [output index, nonzero]: both checked by experiment (CasADi 3.6).
        if op == ca.OP_INPUT:
            work[res[0]] = replacements[arg[0]][arg[1]]
        elif op == ca.OP_OUTPUT:
            rows, cols = places[res[0]]
            outs[res[0]][rows[res[1]], cols[res[1]]] = work[arg[0]]
        elif op == ca.OP_CONST:
            work[res[0]] = number(f.instruction_constant(k))
        else:
            if op in _UNARY:
                value = _UNARY[op](work[arg[0]])
            elif op in _BINARY:
                value = _BINARY[op](work[arg[0]], work[arg[1]])
            else:
                raise _untranslatable(op)
            if value in known:            # CasADi's graph may hold the same node twice
                value = known[value]
            elif uses.get(k, 0) > 1 and not value.is_Atom:
                name = next(names)
                shared.append((name, value))
                known[value] = value = name
            work[res[0]] = value
    return outs, shared


def _uses(program):
    """Instruction index -> how many instructions read its result."""
    owner, uses = {}, {}
    for k, (op, arg, res) in enumerate(program):
        if op in _UNARY or op in _BINARY:
            reads = arg[:1] if op in _UNARY else arg[:2]
        elif op == ca.OP_OUTPUT:
            reads = arg[:1]
        elif op in (ca.OP_INPUT, ca.OP_CONST):
            reads = []
        else:
            raise _untranslatable(op)
        for slot in reads:
            uses[owner[slot]] = uses.get(owner[slot], 0) + 1
        if op != ca.OP_OUTPUT:
            owner[res[0]] = k
    return uses


def coordinate_symbol(state_name, prefix="q"):
    """A readable symbol name for a joint coordinate: "shoulder.q" -> "q_shoulder".

    Multi-DOF joints ("ball.q[1]") give "q_ball_1"; named parts of a coordinate keep their
    name ("free.quat[2]" -> "q_free_quat_2", "free.w[0]" with prefix qd -> "qd_free_w_0").
    """
    joint, _, coord = state_name.rpartition(".")
    label, _, rest = coord.partition("[")
    index = rest[:-1]
    named = f"_{label}" if label not in ("q", "qd") else ""
    # a joint in a subsystem is named by path: "upper.joint" -> "upper_joint"
    return f"{prefix}_{joint.replace('.', '_')}{named}" + (f"_{index}" if index else "")


def simplify(expr, floor=0.0):
    """Sums of products like the paper's M: expanded, round-off removed, trig-simplified."""
    # expand first so the rotation products (sin a cos b + cos a sin b) meet each other;
    # trigsimp then folds them into sin(a + b) and sin^2 + cos^2 into 1, which it can only
    # do once round-off (0.9999999999999999*sin^2) is gone.
    expr = tidy(sp.expand(expr), floor)
    expr = tidy(sp.expand(sp.trigsimp(expr)), floor)
    # expand also multiplies out denominators (1/(1 - t)**3 -> 1/(-t**3 + 3*t**2 ...)):
    # factor them back
    return expr.replace(lambda e: e.is_Pow and e.exp.is_negative and e.base.is_Add,
                        lambda e: sp.factor(e.base) ** e.exp)


def equations_sympy(system, simplified=None):
    """The seed paper's M, V, G (``M qdd + V + G = 0``) of a compiled system, in sympy.

    Parameters
    ----------
    system : kinetwork.System
    simplified : bool, optional
        True: every entry through :func:`simplify`, the paper's form. False: the equations
        as the Newton-Euler recursion built them, with shared parts named (see
        :func:`to_sympy_shared`). Default: simplified when M, V, G have at most
        SIMPLIFY_LIMIT CasADi operations (trigsimp takes seconds for two spatial links,
        hours for four).

    Returns
    -------
    dict
        ``M`` (n x n), ``V`` and ``G`` (n x 1) sympy Matrices; ``shared``, the named parts
        they use (empty when simplified); the symbols ``q``, ``qd`` (lists, in the order of
        ``system.coordinate_names``), ``params`` (name -> Symbol) and ``t``; ``size``
        (CasADi operations of M, V, G) and ``simplified``.
    """
    eq = system.equations()
    params = {name: sp.Symbol(name, real=True) for name in eq["param_names"]}
    taken = set(params) | {"t"}
    q, qd = [], []
    # a speed of an angle or distance reads as its coordinate's rate (qd_shoulder); the
    # speeds of quaternion joints have names of their own (qd_free_w_1)
    coordinate_of = {u: system.coordinate_names[k] for k, u in system.asm.speed_of.items()}
    rates = [coordinate_of.get(i, name) for i, name in enumerate(system.speed_names)]
    for names, prefix, out in ((system.coordinate_names, "q", q), (rates, "qd", qd)):
        for coord in names:
            name = coordinate_symbol(coord, prefix)
            while name in taken:          # a model parameter may already be called q_shoulder
                name += "_"
            taken.add(name)
            out.append(sp.Symbol(name, real=True))
    t = sp.Symbol("t", real=True)
    # states of signal blocks and 1-D networks a force depends on (a PID's integral)
    x = []
    for label in eq["x_names"]:
        name = "x_" + re.sub(r"\W+", "_", label).strip("_")
        while name in taken:
            name += "_"
        taken.add(name)
        x.append(sp.Symbol(name, real=True))
    symbols_in = [(eq["q"], q), (eq["qd"], qd), (eq["p"], list(params.values())),
                  (eq["t"], [t]), (eq["x"], x)]
    terms = [eq["M"], eq["V"], eq["G"]]
    f = _function(terms, symbols_in)
    size = f.n_instructions()
    if simplified is None:
        simplified = size <= SIMPLIFY_LIMIT
    if simplified:
        mats, shared = [], []
        for mat in function_to_sympy(f, [syms for _, syms in symbols_in])[0]:
            mat = mat.applyfunc(sp.expand)
            floor = ROUNDOFF * coefficient_scale(mat)
            mats.append(mat.applyfunc(lambda e, floor=floor: simplify(e, floor)))
    else:
        mats, shared = function_to_sympy(f, [syms for _, syms in symbols_in], prefix="w")
    M, V, G = mats
    return {"M": M, "V": V, "G": G, "shared": shared, "q": q, "qd": qd, "params": params,
            "t": t, "x": x, "size": size, "simplified": simplified}


def _untranslatable(op):
    """The error for a CasADi operation with no sympy counterpart: a ModelError for a call of
    a function (the interpolant of a long ``signals.Table``), which a user can meet."""
    if op == ca.OP_CALL:
        return ModelError("the equations call a function (the interpolant of a signals.Table "
                          "of many rows): they cannot be printed in closed form")
    return ValueError(f"CasADi operation {_OP_NAMES.get(op, op)} has no sympy translation")
