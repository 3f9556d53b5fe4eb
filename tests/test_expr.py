"""Safe expressions (kinetwork/expr.py): what parses, what is refused, evaluation over numbers
and over CasADi symbols, and the parse cache."""

import math

import casadi as ca
import pytest

import kinetwork as kn
from kinetwork.expr import ARITY, FUNCTIONS, LITERAL, Expression, casadi_functions, parse


@pytest.mark.parametrize("text, value", [
    ("-L1/2", -0.75), ("2*sin(3*t)", 2 * math.sin(0.6)), ("L1**2 + pi", 2.25 + math.pi),
    ("atan2(1, L1)", math.atan2(1, 1.5)), ("max(-1, min(2, 3))", 2.0), ("1e-3", 1e-3),
])
def test_expressions(text, value):
    assert Expression(text).evaluate({"L1": 1.5, "t": 0.2}) == pytest.approx(value)


@pytest.mark.parametrize("text", [
    "__import__('os').system('true')", "L1.real()", "L1[0].real", "[1, 2]", "lambda: 1", "x if y else z",
    "open('f')", "'abc'", "L1[0]", "True", "a < b < c", "{1: 2}", "f'{x}'", "1 +",
    "sin(x=1)", "x" * 3000,
])
def test_expressions_refuse_anything_but_arithmetic(text):
    with pytest.raises(kn.ModelError):
        Expression(text)


def test_a_dotted_name_is_a_path_never_an_attribute():
    # the flat model of subsystems names parameters by path ("cyl1.L"): a dotted name is
    # looked up whole, never as an attribute of anything
    expr = Expression("-L1.real/2 + cyl1.piston.m")
    assert expr.names == {"L1.real", "cyl1.piston.m"}
    assert expr.evaluate({"L1.real": 4.0, "cyl1.piston.m": 1.0}) == -1.0
    with pytest.raises(KeyError):
        expr.evaluate({"L1": 4.0, "cyl1.piston.m": 1.0})
    # in what a user writes, a path is refused: expressions use their own model's parameters
    with pytest.raises(kn.ModelError, match=r"'L1.real' is not a parameter here"):
        kn.multibody.RigidBody("b", mass="L1.real")


@pytest.mark.parametrize("text, message", [
    ("open('f')", r"call of 'open' is not allowed"),
    ("sine(t)", r"call of 'sine' is not allowed \(did you mean 'sin'\?\)"),
    ("L1[0].real", r"an attribute \(\.\) is not allowed"),
    # the refused operator is named, and the message lists what is allowed (issue 19)
    ("L % 2", r"the operator '%' is not allowed \(only numbers, parameter names, \+ - \* / "
              r"\*\* \^, one comparison and functions\)"),
    ("L // 2", r"the operator '//' is not allowed"),
    ("a < b <= c", r"a chained comparison is not allowed; nest if_else\(\)"),
    ("a is b", r"the operator 'is' is not allowed"),
    ("a and b", r"the operator 'and' is not allowed"),
    ("a if b else c", r"a conditional \(x if c else y\) is not allowed"),
    ("L[1]", r"indexing \(\[\.\.\.\]\) is not allowed"),
    ("(lambda: 1)()", r"calling anything but a named function"),
    ("sin(x=1)", r"sin\(\) takes no keyword arguments"),
    ("'abc'", r"only numbers are allowed as constants"),
    ("1 +", r"cannot parse expression"),
    ("1\x00", r"cannot parse expression"),
    ("\ud800", r"lone surrogate"),
    ("x" * 2001, r"longer than 2000 characters"),
    (3.0, r"expression must be a string"),
])
def test_refusals_say_why(text, message):
    with pytest.raises(kn.ModelError, match=message):
        Expression(text)


@pytest.mark.parametrize("text, expected", [
    ("L^2", 9.0), ("2*L^2/3", 6.0), ("-L^2", -9.0), ("L^0.5^2", 3.0 ** 0.25), ("(L+1)^-1", 0.25),
])
def test_a_caret_is_a_power_as_in_modelica(text, expected):
    # Modelica's and Maple's habit: "^" is exponentiation (Python's bitwise xor is refused
    # anyway); it binds as "**" does, so "-L^2" is -(L^2) as in Modelica
    assert Expression(text).evaluate({"L": 3.0}) == pytest.approx(expected, rel=1e-15)


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_every_function_takes_its_arity_and_no_other(name):
    n = ARITY[name]
    Expression(f"{name}({', '.join(['0.5'] * n)})")
    for wrong in (n - 1, n + 1):
        takes = f"{n} argument{'s' if n > 1 else ''}"
        with pytest.raises(kn.ModelError, match=rf"{name}\(\) takes {takes}, got {wrong}"):
            Expression(f"{name}({', '.join(['0.5'] * wrong)})")


def test_names_are_the_free_symbols_constants_excluded():
    assert Expression("a*sin(b*t) + pi - e").names == {"a", "b", "t"}
    assert Expression("2.5").names == set()


def test_deep_nesting_is_refused_not_crashed():
    with pytest.raises(kn.ModelError, match="nested too deeply"):
        Expression("-" * 1999 + "1").evaluate({})          # 2000 characters: not too long
    assert Expression("-(-(-(1)))").evaluate({}) == -1.0


def test_the_same_tree_evaluates_over_casadi_symbols():
    expr = parse("a*sin(t) + max(a, 2) + atan2(t, 1) + sign(-a)")
    a, t = ca.SX.sym("a"), ca.SX.sym("t")
    f = ca.Function("f", [a, t], [expr.evaluate({"a": a, "t": t}, casadi_functions())])
    assert float(f(3.0, 0.5)) == pytest.approx(expr.evaluate({"a": 3.0, "t": 0.5}))
    assert set(casadi_functions()) - {LITERAL} == set(FUNCTIONS)


@pytest.mark.parametrize("v, x", [(-1.0, 0.5), (-1.0, 0.99), (0.0, 0.5), (2.0, 0.95)])
def test_conditionals_pick_their_branch_over_numbers_and_symbols(v, x):
    """MSL GasForce2's nested conditional, against Python's own if/else."""
    text = ("if_else(v < 0, if_else(x < 0.986061, 1 + x, 2 + x), "
            "if_else(x > 0.933, 3 + x, 4 + x))")
    if v < 0:
        expected = 1 + x if x < 0.986061 else 2 + x
    else:
        expected = 3 + x if x > 0.933 else 4 + x
    expr = parse(text)
    assert expr.evaluate({"v": v, "x": x}) == expected
    sv, sx = ca.SX.sym("v"), ca.SX.sym("x")
    f = ca.Function("f", [sv, sx], [expr.evaluate({"v": sv, "x": sx}, casadi_functions())])
    assert float(f(v, x)) == expected


@pytest.mark.parametrize("text, true", [("a < b", 1.0), ("a <= b", 1.0), ("a > b", 0.0),
                                        ("a >= b", 0.0), ("a == b", 0.0), ("a != b", 1.0)])
def test_a_comparison_is_one_or_zero(text, true):
    assert parse(text).evaluate({"a": 1.0, "b": 2.0}) == true
    assert parse(f"2*({text})").evaluate({"a": 1.0, "b": 2.0}) == 2 * true


def test_parse_is_cached_per_text():
    assert parse("L1/2 + c") is parse("L1/2 + c")
    assert parse("L1/2 + c") is not parse("L1/2 + d")
    with pytest.raises(kn.ModelError):        # a refusal is not cached as a value
        parse("open('f')")
    with pytest.raises(kn.ModelError):
        parse("open('f')")


@pytest.mark.parametrize("text", ["if_else(a < t, a, t)", "if_else(a <= t, 1, 2)",
                                  "if_else(a > t, a*t, 0)", "if_else(a >= t, 1, -1)",
                                  "if_else(a == t, 3, 4)", "if_else(a != t, 3, 4)",
                                  "abs(a - t)", "sign(a - t)", "min(a, t)", "max(a, 2*t)"])
@pytest.mark.parametrize("a, t", [(-1.5, 0.5), (0.5, 0.5), (2.0, 0.5), (0.0, 0.0),
                                  (-0.0, 0.0), (1e-300, 0.0), (-3.0, -4.0)])
def test_noevent_takes_the_same_values_and_derivatives_literally(text, a, t):
    # noEvent builds comparisons and kinks from copysign and logical not: the numbers and the
    # derivatives are the plain ones, and no relation or kink is left for the events to see
    sa, st = ca.SX.sym("a"), ca.SX.sym("t")
    plain = parse(text).evaluate({"a": sa, "t": st}, casadi_functions())
    literal = parse(f"noEvent({text})").evaluate({"a": sa, "t": st}, casadi_functions())
    f = ca.Function("f", [sa, st], [plain, literal, ca.gradient(plain, sa),
                                    ca.gradient(literal, sa)])
    value, value_literal, grad, grad_literal = (float(v) for v in f(a, t))
    assert value_literal == value == parse(text).evaluate({"a": a, "t": t})
    if a not in (t, 2 * t):        # at a tie CasADi's fmin and fmax take the mean slope
        assert grad_literal == grad
    g = ca.Function("g", [sa, st], [literal])
    ops = {g.instruction_id(k) for k in range(g.n_instructions())}
    assert not ops & {ca.OP_LT, ca.OP_LE, ca.OP_EQ, ca.OP_NE, ca.OP_FABS, ca.OP_SIGN,
                      ca.OP_FMIN, ca.OP_FMAX}


def test_noevent_is_a_function_of_one_argument_and_a_reserved_name():
    assert parse("noEvent(if_else(t < 1, 2, 3))").evaluate({"t": 0.5}) == 2.0
    with pytest.raises(kn.ModelError, match="noEvent\\(\\) takes 1 argument, got 2"):
        parse("noEvent(t, 1)")
    with pytest.raises(kn.ModelError, match="noEvent"):
        kn.Model("m", parameters={"noEvent": 1.0})
