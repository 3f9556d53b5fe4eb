"""CasADi -> sympy translation: the translated expressions evaluate like the CasADi ones."""

import math

import casadi as ca
import numpy as np
import pytest
import sympy as sp

import kinetwork as kn
from kinetwork.symbolic import (equations_sympy, function_to_sympy, number, tidy, to_sympy,
                                to_sympy_shared)
from scenes import SEED_PARAMS, double_pendulum
from scenes.reference import seed_mvg

X, Y = ca.SX.sym("x"), ca.SX.sym("y")
SX_, SY_ = sp.symbols("x y", real=True)

#: one expression per supported operation; x in (0.2, 0.8) and y in (1.2, 2.5) keep every
#: one of them real and away from branch cuts and discontinuities
OPERATIONS = {
    "add": X + Y, "sub": X - Y, "mul": X * Y, "div": X / Y, "neg": -X, "sq": X ** 2,
    "twice": 2 * X, "inv": 1 / Y, "pow": Y ** X, "constpow": Y ** 2.5, "sqrt": ca.sqrt(Y),
    "exp": ca.exp(X), "log": ca.log(Y), "fabs": ca.fabs(X - Y), "sign": ca.sign(X - Y),
    "sin": ca.sin(Y), "cos": ca.cos(Y), "tan": ca.tan(X), "asin": ca.asin(X),
    "acos": ca.acos(X), "atan": ca.atan(Y), "atan2": ca.atan2(X, -Y), "sinh": ca.sinh(Y),
    "cosh": ca.cosh(Y), "tanh": ca.tanh(Y), "asinh": ca.asinh(Y), "acosh": ca.acosh(Y),
    "atanh": ca.atanh(X), "floor": ca.floor(3 * Y), "ceil": ca.ceil(3 * Y),
    "erf": ca.erf(X), "erfinv": ca.erfinv(X), "log1p": ca.log1p(X), "expm1": ca.expm1(X),
    "fmin": ca.fmin(X, Y), "fmax": ca.fmax(X, Y), "hypot": ca.hypot(X, Y),
    "fmod": ca.fmod(-7 * Y, X), "remainder": ca.remainder(7 * Y, X),
    "copysign": ca.copysign(Y, -X), "lt": X < Y, "le": Y <= X, "eq": X == Y, "ne": X != Y,
    "not": ca.logic_not(X > Y), "and": ca.logic_and(X < Y, Y > 1), "or": ca.logic_or(X > Y, Y < 1),
    "if_else": ca.if_else(X < 0.5, ca.sin(Y), ca.cos(Y)), "pi": X * math.pi / 2,
}


#: CasADi 3.6's erfinv is off by up to 2.4e-6 just below 0.7 (checked against scipy)
LOOSE = {"erfinv": 1e-5}


@pytest.mark.parametrize("name", OPERATIONS)
def test_operation_evaluates_like_casadi(name):
    expr = OPERATIONS[name]
    tol = LOOSE.get(name, 1e-12)
    f = ca.Function("f", [X, Y], [expr])
    [mat] = to_sympy([expr], [(X, [SX_]), (Y, [SY_])])
    g = sp.lambdify((SX_, SY_), mat[0, 0], "mpmath")
    for x, y in np.random.default_rng(1).uniform([0.2, 1.2], [0.8, 2.5], size=(20, 2)):
        assert float(g(x, y)) == pytest.approx(float(f(x, y)), rel=tol, abs=tol)


def test_matrix_shapes_sparsity_and_input_order():
    """Entries land where CasADi stores them (column-major), structural zeros stay 0."""
    a, b = ca.SX.sym("a", 2), ca.SX.sym("b", 3)
    M = ca.SX(3, 2)
    M[0, 1], M[2, 0], M[1, 1] = a[1] * b[2], ca.sin(b[0]), a[0] - b[1]
    sa, sb = sp.symbols("a0 a1", real=True), sp.symbols("b0 b1 b2", real=True)
    [m] = to_sympy([M], [(a, sa), (b, sb)])
    assert m == sp.Matrix([[0, sa[1] * sb[2]], [0, sa[0] - sb[1]], [sp.sin(sb[0]), 0]])


def test_wrong_number_of_symbols_is_refused():
    with pytest.raises(ValueError, match="2 entries but 1 sympy symbols"):
        to_sympy([ca.SX.sym("a", 2)], [(ca.SX.sym("a", 2), [SX_])])


def test_unknown_operation_is_named():
    class Program:
        """A Function stand-in holding one instruction no translation knows."""
        def n_out(self):
            return 1

        def size_out(self, i):
            return (1, 1)

        def sparsity_out(self, i):
            return ca.Sparsity.dense(1, 1)

        def n_instructions(self):
            return 2

        def instruction_id(self, k):
            return [ca.OP_INPUT, ca.OP_MTIMES][k]

        def instruction_input(self, k):
            return [[0, 0], [0, 0]][k]

        def instruction_output(self, k):
            return [[0], [1]][k]

    with pytest.raises(ValueError, match="OP_MTIMES has no sympy translation"):
        function_to_sympy(Program(), [[SX_]])


def test_constants_stay_exact_or_as_written():
    assert number(0.5) == sp.Rational(1, 2)
    assert number(-3.0) == -3 and isinstance(number(-3.0), sp.Integer)
    assert number(math.pi / 2) == sp.pi / 2
    assert sp.sstr(number(9.81), full_prec=False) == "9.81"
    assert float(number(9.81)) == 9.81            # no precision lost on the way
    assert number(0.9999999999999999) != 1        # exact by default ...
    assert number(0.9999999999999999, rtol=1e-12) == 1   # ... snapped on request


def test_tidy_removes_roundoff_only():
    L, q = sp.symbols("L q", real=True)
    noisy = 6.7e-17 * L * sp.cos(q) + 0.9999999999999999 * L ** 2 + sp.Rational(1, 10 ** 20) * q
    assert tidy(noisy, floor=1e-13) == L ** 2 + sp.Rational(1, 10 ** 20) * q


def _paper(sym):
    """The seed's closed forms (bench/reference.py), with DESIGN's two corrections to V."""
    params = {k: sym["params"][k] for k in SEED_PARAMS}
    return seed_mvg(sym["q"], sym["qd"], **params, sin=sp.sin, cos=sp.cos, array=sp.Matrix)


def test_seed_equations_are_the_papers():
    """Symbolically equal to the paper's M, V, G, and printed in its form."""
    eq = equations_sympy(double_pendulum().compile())
    assert eq["simplified"] and eq["shared"] == []
    assert [s.name for s in eq["q"] + eq["qd"]] == [
        "q_shoulder", "q_elbow", "qd_shoulder", "qd_elbow"]
    for ours, paper in zip((eq["M"], eq["V"], eq["G"]), _paper(eq)):
        assert sp.simplify(ours - paper) == sp.zeros(*paper.shape)
    assert str(eq["M"][1, 1]) == "L2**2*m2/4"
    assert str(eq["M"][0, 0]) == "L1**2*m1/4 + L1**2*m2 + L1*L2*m2*cos(q_elbow) + L2**2*m2/4"
    assert str(eq["G"][1]) == "L2*g*m2*sin(q_elbow + q_shoulder)/2"


def _numeric(eq, system, q, qd, params, t=0.0):
    """Evaluate the sympy M, V, G (substituting shared names in order) with numbers."""
    values = {**dict(zip(eq["q"], q)), **dict(zip(eq["qd"], qd)), eq["t"]: t,
              **{eq["params"][k]: v for k, v in params.items()}}
    for name, expr in eq["shared"]:
        values[name] = float(expr.xreplace(values))
    return [np.array(eq[k].xreplace(values), dtype=float).squeeze() for k in ("M", "V", "G")]


@pytest.mark.parametrize("simplified", [True, False])
def test_seed_equations_evaluate_like_the_system(simplified):
    system = double_pendulum().compile()
    eq = equations_sympy(system, simplified=simplified)
    rng = np.random.default_rng(7)
    for _ in range(5):
        q, qd = rng.uniform(-3, 3, 2), rng.uniform(-3, 3, 2)
        params = {k: float(v) for k, v in zip(SEED_PARAMS, rng.uniform(0.5, 2, 7))}
        expected = system.dynamics_terms(q, qd, params)
        for ours, ref in zip(_numeric(eq, system, q, qd, params), expected):
            np.testing.assert_allclose(ours, ref.squeeze(), rtol=1e-12, atol=1e-12)


def test_time_dependent_source_and_rotated_frame():
    """A torque in t and a 90-degree fixed rotation: no round-off terms, t kept symbolic."""
    m = double_pendulum()
    m.add(kn.rotational.Torque("drive", tau="1/(1-t)**3 + sin(3*t)"))
    m.connect("drive.flange", "elbow.axis")
    m.add(kn.multibody.FixedRotation("turn", axis=[0, 0, 1], angle=math.pi / 2))
    m.add(kn.multibody.RigidBody("tip", mass=0.3, r_cm=[0.2, 0, 0]))
    m.connect("elbow.frame_b", "turn.frame_a")
    m.connect("turn.frame_b", "tip.frame_a")
    system = m.compile()
    eq = equations_sympy(system, simplified=True)
    t = eq["t"]
    assert t in eq["V"][1].free_symbols
    floats = set().union(*(eq[k].atoms(sp.Float) for k in ("M", "V", "G")))
    assert all(abs(f) > 1e-10 for f in floats), floats
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, qd, tt = rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2), rng.uniform(0, 0.9)
        expected = system.dynamics_terms(q, qd, t=tt)
        for ours, ref in zip(_numeric(eq, system, q, qd, SEED_PARAMS, tt), expected):
            np.testing.assert_allclose(ours, ref.squeeze(), rtol=1e-9, atol=1e-9)


def test_shared_names_do_not_collide_with_parameters():
    """A parameter called w0, or q_shoulder, keeps its name; the generated ones move aside."""
    m = double_pendulum(w0=2.0, q_shoulder=1.5)
    eq = equations_sympy(m.compile(), simplified=False)
    names = [s.name for s, _ in eq["shared"]]
    assert "w0" not in names and len(set(names)) == len(names)
    assert eq["q"][0].name == "q_shoulder_"
    assert {"w0", "q_shoulder"} <= {s.name for s in eq["params"].values()}


def test_shared_form_stays_small_for_long_chains():
    """Four spatial links: the named form is linear in the CasADi graph, not exponential."""
    m = kn.Model("chain")
    m.add(kn.multibody.Ground("ground", gravity=[0, -9.81, 0]))
    prev = "ground.frame"
    for i, axis in enumerate(([0, 0, 1], [1, 0, 0], [0, 1, 1], [1, 1, 0])):
        m.add(kn.multibody.Revolute(f"j{i}", axis=axis))
        m.add(kn.multibody.FixedTranslation(f"l{i}", r=[0.3, -0.5, 0.1]))
        m.add(kn.multibody.RigidBody(f"b{i}", mass=1.0, r_cm=[0, -0.25, 0],
                                     inertia=[0.1, 0.2, 0.3]))
        for a, b in ((prev, f"j{i}.frame_a"), (f"j{i}.frame_b", f"l{i}.frame_a"),
                     (f"j{i}.frame_b", f"b{i}.frame_a")):
            m.connect(a, b)
        prev = f"l{i}.frame_b"
    system = m.compile()
    eq = equations_sympy(system)
    assert not eq["simplified"] and eq["size"] > 1000
    text = "\n".join(str(e) for _, e in eq["shared"]) + str(eq["M"]) + str(eq["V"])
    assert len(text) < 40 * eq["size"]
    q, qd = np.full(4, 0.3), np.full(4, -0.2)
    for ours, ref in zip(_numeric(eq, system, q, qd, {}), system.dynamics_terms(q, qd)):
        np.testing.assert_allclose(ours, ref.squeeze(), rtol=1e-10, atol=1e-12)


def test_to_sympy_shared_names_repeated_results():
    a = ca.SX.sym("a")
    s = ca.sin(a) * 2
    [m], shared = to_sympy_shared([ca.vertcat(s + 1, s * s)], [(a, [SX_])])
    [(w, definition)] = shared
    assert definition == 2 * sp.sin(SX_)
    assert list(m) == [w + 1, w ** 2]


def test_equations_of_a_model_with_controller_states_name_them():
    # a PID's states enter V; in subsystems their symbols carry the instance path
    import pathlib
    root = pathlib.Path(__file__).resolve().parents[1] / "models"
    eq = equations_sympy(kn.load(root / "robot" / "arm_axes.json").compile())
    names = {s.name for s in eq["x"]}
    assert names == {"x_shoulder_axis_pid_x_0", "x_shoulder_axis_pid_x_1",
                     "x_elbow_axis_pid_x_0", "x_elbow_axis_pid_x_1"}
    J_m, n = eq["params"]["J_m"], eq["params"]["n"]
    assert sp.simplify(eq["M"][1, 1] - eq["M"][1, 1].subs(J_m, 0) - J_m * n**2) == 0
    assert {s.name for s in eq["V"][0].free_symbols} >= {"x_shoulder_axis_pid_x_0"}
