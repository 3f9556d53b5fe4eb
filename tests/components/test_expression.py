"""signals.Expression (force laws in sensor signals, as MSL Engine1b's gas force) against
solve_ivp of the same law written by hand, and signals.Table2D against scipy's
RegularGridInterpolator, its derivatives through an exact Position source against finite
differences of scipy's."""

import numpy as np
import pytest
import scipy.integrate
from scipy.interpolate import RegularGridInterpolator

import kinetwork as kn

S = kn.signals
TOL = dict(rtol=1e-10, atol=1e-12, jit=False)   # accuracy, not compiled code, is tested here


def _oscillator(law="-c*s**3 - d*v*abs(v) + F0*sin(3*t)"):
    """A sliding mass pushed by a force law in its own position and speed."""
    m = kn.Model("law", parameters={"c": 40.0, "d": 2.0, "F0": 5.0})
    for comp in (kn.translational.Mass("mass", m=0.5, s0=0.3, v0=0.0),
                 kn.translational.PositionSensor("ps"), kn.translational.SpeedSensor("vs"),
                 S.Expression("gas", expression=law, names=["s", "v"]),
                 kn.translational.Force("push"), kn.Probe("p", quantities=["position"])):
        m.add(comp)
    for a, b in [("mass.flange_a", "ps.flange"), ("mass.flange_a", "vs.flange"),
                 ("ps.y", "gas.u1"), ("vs.y", "gas.u2"), ("gas.y", "push.u"),
                 ("push.flange", "mass.flange_b"), ("p.port", "mass.flange_a")]:
        m.connect(a, b)
    return m


def _reference(c, d, F0, t):
    def rhs(t, x):
        s, v = x
        return [v, (-c * s ** 3 - d * v * abs(v) + F0 * np.sin(3 * t)) / 0.5]
    return scipy.integrate.solve_ivp(rhs, (0, t[-1]), [0.3, 0.0], t_eval=t, method="DOP853",
                                     rtol=1e-12, atol=1e-13).y[0]


def test_force_law_in_sensor_signals_matches_scipy():
    m = _oscillator()
    res = kn.simulate(m, t_end=2.0, n_points=21, **TOL)
    assert np.max(abs(res["p.position"] - _reference(40.0, 2.0, 5.0, res.t))) < 1e-7
    # model parameters stay symbols: a new value, the same compiled system
    system = m.compile()
    res = kn.simulate(m, t_end=2.0, n_points=21, **TOL, params={"c": 10.0, "F0": 0.0})
    assert m.compile() is system
    assert np.max(abs(res["p.position"] - _reference(10.0, 2.0, 0.0, res.t))) < 1e-7


def test_torque_law_on_a_revolute_joint_matches_scipy():
    """A pendulum on a joint, damped by a torque written in its angle and speed."""
    m = kn.Model("pend")
    for comp in (kn.multibody.Ground("ground", gravity=[0, -9.81, 0]),
                 kn.multibody.Revolute("joint", axis=[0, 0, 1], q0=1.0),
                 kn.multibody.RigidBody("bob", mass=1.0, r_cm=[0, -0.5, 0], inertia=[0, 0, 0]),
                 kn.rotational.AngleSensor("qs"), kn.rotational.SpeedSensor("ws"),
                 S.Expression("law", expression="-0.4*u2 - 2*sin(u1)**3"),
                 kn.rotational.Torque("motor"), kn.Probe("p", quantities=["angle"])):
        m.add(comp)
    for a, b in [("ground.frame", "joint.frame_a"), ("joint.frame_b", "bob.frame_a"),
                 ("qs.flange", "joint.axis"), ("ws.flange", "joint.axis"),
                 ("qs.y", "law.u1"), ("ws.y", "law.u2"), ("law.y", "motor.u"),
                 ("motor.flange", "joint.axis"), ("p.port", "joint.axis")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=1.5, n_points=16, **TOL)

    def rhs(t, x):
        q, w = x
        return [w, (-9.81 * 0.5 * np.sin(q) - 0.4 * w - 2 * np.sin(q) ** 3) / 0.25]
    ref = scipy.integrate.solve_ivp(rhs, (0, 1.5), [1.0, 0.0], t_eval=res.t, method="DOP853",
                                    rtol=1e-12, atol=1e-13)
    assert np.max(abs(res["p.angle"] - ref.y[0])) < 1e-7


def test_expression_refusals_name_the_block():
    with pytest.raises(kn.ModelError, match=r"gas.*unknown name 'z'"):
        _oscillator("-c*z").compile()
    m = _oscillator("u3 + s")
    with pytest.raises(kn.ModelError, match=r"gas.*'u3'.*gas.u3 is not wired"):
        m.compile()
    with pytest.raises(kn.ModelError, match=r"gas.expression.*call of 'exec'"):
        S.Expression("gas", expression="exec(1)")
    m = _oscillator()
    m.components["gas"].names = ["c", "v"]
    with pytest.raises(kn.ModelError, match=r"gas.*'c' is also a model parameter"):
        m.compile()


def test_expression_and_table2d_save_and_load(tmp_path):
    m = _oscillator()
    m.add(S.Table2D("map", table=[[0, 0, 1], [0, 1, 2], [2, 3, 5]]))
    m.connect("ps.y", "map.u1")
    m.connect("vs.y", "map.u2")
    m.save(tmp_path / "law.json")
    again = kn.load(tmp_path / "law.json")
    assert again.components["gas"].expression == m.components["gas"].expression
    assert again.components["map"].table == [[0, 0, 1], [0, 1, 2], [2, 3, 5]]
    with pytest.raises(kn.ModelError, match=r"map.table\[2\]\[0\]: the first column"):
        S.Table2D("map", table=[[0, 0, 1], [1, 1, 2], [1, 3, 5]])


GRID1 = [0.0, 0.5, 1.5, 2.0]
GRID2 = [-1.0, 0.0, 2.0]
VALUES = np.array([[1.0, 2.0, -1.0], [0.5, 3.0, 2.0], [4.0, -2.0, 0.0], [1.0, 1.0, 6.0]])
TABLE = [[0.0, *GRID2]] + [[g, *row] for g, row in zip(GRID1, VALUES.tolist())]


def _table_model(a1="1.3*t - 0.3", a2="2.5*cos(1.7*t)"):
    m = kn.Model("map")
    for comp in (S.Expression("x1", expression=a1), S.Expression("x2", expression=a2),
                 S.Table2D("map", table=TABLE), kn.rotational.Position("drive"),
                 kn.rotational.Inertia("rotor", J=1.0),
                 kn.Probe("py", quantities=["value"]),
                 kn.Probe("pr", quantities=["angle", "speed"])):
        m.add(comp)
    for a, b in [("x1.y", "map.u1"), ("x2.y", "map.u2"), ("map.y", "drive.u"),
                 ("drive.flange", "rotor.flange_a"), ("py.port", "map.y"),
                 ("pr.port", "rotor.flange_a")]:
        m.connect(a, b)
    return m


def test_table2d_is_bilinear_and_extrapolates_as_scipy():
    res = kn.simulate(_table_model(), t_end=2.0, n_points=41, method="rk45", jit=False)
    ref = RegularGridInterpolator((GRID1, GRID2), VALUES, method="linear", bounds_error=False,
                                  fill_value=None)
    pts = np.column_stack([1.3 * res.t - 0.3, 2.5 * np.cos(1.7 * res.t)])
    # the path leaves the grid on every side: extrapolation is checked too
    assert pts[:, 0].min() < GRID1[0] and pts[:, 0].max() > GRID1[-1]
    assert pts[:, 1].min() < GRID2[0] and pts[:, 1].max() > GRID2[-1]
    assert np.max(abs(res["py.value"] - ref(pts))) < 1e-12
    assert np.max(abs(res["pr.angle"] - ref(pts))) < 1e-12
    # its derivative along the path, exact (a Position differentiates its reference through
    # the blocks), against central differences of scipy's interpolant inside the cells
    h = 1e-6
    fd = (ref(np.column_stack([1.3 * (res.t + h) - 0.3, 2.5 * np.cos(1.7 * (res.t + h))]))
          - ref(np.column_stack([1.3 * (res.t - h) - 0.3, 2.5 * np.cos(1.7 * (res.t - h))])))
    fd /= 2 * h
    inside = np.array([min(abs(p[0] - g) for g in GRID1) > 1e-3 and
                       min(abs(p[1] - g) for g in GRID2) > 1e-3 for p in pts])
    assert inside.sum() > 30
    assert np.max(abs(res["pr.speed"][inside] - fd[inside])) < 1e-6


def test_a_large_table2d_is_an_interpolant_with_the_same_values():
    g1, g2 = np.linspace(0, 1, 30), np.linspace(-1, 1, 20)
    values = np.sin(3 * g1)[:, None] * np.cos(2 * g2)[None, :]
    table = [[0.0, *g2]] + [[a, *row] for a, row in zip(g1, values.tolist())]
    m = kn.Model("big")
    for comp in (S.Expression("x1", expression="0.9*t"), S.Expression("x2", expression="t - 0.5"),
                 S.Table2D("map", table=table), kn.Probe("py", quantities=["value"])):
        m.add(comp)
    for a, b in [("x1.y", "map.u1"), ("x2.y", "map.u2"), ("py.port", "map.y")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=1.0, n_points=11, method="rk45", jit=False)
    ref = RegularGridInterpolator((g1, g2), values, method="linear")
    assert np.max(abs(res["py.value"] - ref(np.column_stack([0.9 * res.t, res.t - 0.5])))) \
        < 1e-12


def test_expression_in_a_subsystem_reads_its_parameters():
    """Inside a subsystem the expression's parameters are the definition's: a constant of the
    instance, or an outer parameter that stays a symbol."""
    inner = kn.Model("law", parameters={"k": 3.0})
    inner.add(S.Expression("e", expression="k*x + t", names=["x"]))
    inner.expose("u", "e.u1")
    inner.expose("y", "e.y")
    m = kn.Model("outer", parameters={"K": 5.0})
    for comp in (S.Constant("c", k=2.0), kn.Subsystem("a", inner, params={"k": "K"}),
                 kn.Subsystem("b", inner), kn.Probe("pa", quantities=["value"]),
                 kn.Probe("pb", quantities=["value"])):
        m.add(comp)
    for a, b in [("c.y", "a.u"), ("c.y", "b.u"), ("pa.port", "a.y"), ("pb.port", "b.y")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=1.0, n_points=3, method="rk45", params={"K": 1.0}, jit=False)
    assert np.allclose(res["pa.value"], 1.0 * 2 + res.t, rtol=1e-14)
    assert np.allclose(res["pb.value"], 3.0 * 2 + res.t, rtol=1e-14)
