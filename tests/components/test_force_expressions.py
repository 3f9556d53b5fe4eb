"""Force laws as expressions in signals (issue 16, item 4): a 1-D Force or Torque, or a force
on frames, whose value reads signal outputs by name ("-k*pos.y"), besides t and the model's
parameters. Checked against the same physics written with a Spring, a closed form and an
event-driven scipy reference; the Expression-block form of MSL's Engine1b gives the same run
as its one-Force form."""

import math

import numpy as np
import pytest
from scenes.test_engine1b import build as engine1b
from scipy.integrate import solve_ivp

import kinetwork as kn

K, M, S0 = 4.0, 0.5, 0.3
TOL = {"rtol": 1e-10, "atol": 1e-12, "jit": False}


def oscillator(law=True):
    """A mass on a spring to the world: the spring a Force reading a position sensor, or a
    Spring between the mass and a Fixed flange."""
    m = kn.Model("oscillator", parameters={"k": K})
    m.add(kn.translational.Mass("mass", m=M, s0=S0))
    m.add(kn.Probe("p", quantities=["position", "velocity"]))
    m.connect("p.port", "mass.flange_a")
    if law:
        m.add(kn.translational.Force("spring", f="-k*pos.y"))
        m.add(kn.translational.PositionSensor("pos"))
        m.connect("spring.flange", "mass.flange_a")
        m.connect("pos.flange", "mass.flange_a")
    else:
        m.add(kn.translational.Fixed("fix"))
        m.add(kn.translational.Spring("spring", c="k"))
        m.connect("spring.flange_a", "fix.flange")
        m.connect("spring.flange_b", "mass.flange_a")
    return m


def test_a_force_reading_a_position_sensor_is_a_spring():
    law = kn.simulate(oscillator(), t_end=2.0, n_points=21, **TOL)
    spring = kn.simulate(oscillator(law=False), t_end=2.0, n_points=21, **TOL)
    np.testing.assert_allclose(law["p.position"], spring["p.position"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(law["p.velocity"], spring["p.velocity"], rtol=0, atol=1e-12)
    omega = math.sqrt(K / M)
    np.testing.assert_allclose(law["p.position"], S0 * np.cos(omega * law.t), atol=1e-8)


def test_the_law_reads_signals_inside_a_subsystem_by_path_and_round_trips(tmp_path):
    inner = oscillator()
    inner.expose("flange", "mass.flange_b")
    outer = kn.Model("outer", parameters={"k2": 2 * K})
    outer.add(kn.Subsystem("osc", inner, params={"k": "k2"}))
    # a second force outside the subsystem reads the sensor inside it by its path
    outer.add(kn.translational.Force("extra", f="-k2*osc.pos.y"))
    outer.connect("extra.flange", "osc.flange")
    outer.save(tmp_path / "outer.json")
    loaded = kn.load(tmp_path / "outer.json")
    assert loaded.components["extra"].f == "-k2*osc.pos.y"
    res = kn.simulate(loaded, t_end=1.0, n_points=11, **TOL)
    omega = math.sqrt(2 * 2 * K / M)                 # k2 inside plus k2 outside
    np.testing.assert_allclose(res["osc.p.position"], S0 * np.cos(omega * res.t), atol=1e-8)


def test_a_world_force_reading_a_sensor_on_a_prismatic_axis_is_a_spring():
    def scene(law):
        m = kn.Model("slider", parameters={"k": K})
        m.add(kn.multibody.Ground("ground", gravity=[0, 0, 0]))
        m.add(kn.multibody.Prismatic("slide", axis=[1, 0, 0], q0=S0))
        m.add(kn.multibody.RigidBody("body", mass=M, inertia=[0.1, 0.1, 0.1]))
        m.add(kn.Probe("p", quantities=["position"]))
        m.connect("ground.frame", "slide.frame_a")
        m.connect("slide.frame_b", "body.frame_a")
        m.connect("p.port", "slide.axis")
        if law:
            m.add(kn.multibody.WorldForce("push", force=["-k*pos.y", 0, 0]))
            m.add(kn.translational.PositionSensor("pos"))
            m.connect("push.frame_b", "body.frame_a")
            m.connect("pos.flange", "slide.axis")
        else:
            m.add(kn.translational.Spring("spring", c="k"))
            m.connect("spring.flange_a", "slide.support")
            m.connect("spring.flange_b", "slide.axis")
        return m
    law = kn.simulate(scene(True), t_end=1.0, n_points=11, **TOL)
    spring = kn.simulate(scene(False), t_end=1.0, n_points=11, **TOL)
    np.testing.assert_allclose(law["p.position"], spring["p.position"], rtol=0, atol=1e-12)


J, C_SPRING, C_COULOMB, PHI0 = 0.2, 5.0, 0.4, 1.0


def test_a_coulomb_torque_law_with_if_else_matches_scipy_and_the_closed_form():
    """An inertia on a torsion spring with a Coulomb torque -c sign(w), written as
    if_else(w.y > 0, -c, c): the swing's amplitude drops by 2c/k each half-period."""
    m = kn.Model("coulomb", parameters={"c": C_COULOMB})
    m.add(kn.rotational.Fixed("fix"))
    m.add(kn.rotational.Spring("spring", c=C_SPRING))
    m.add(kn.rotational.Inertia("rotor", J=J, phi0=PHI0))
    m.add(kn.rotational.Torque("friction", tau="if_else(w.y > 0, -c, c)"))
    m.add(kn.rotational.SpeedSensor("w"))
    m.add(kn.Probe("p", quantities=["angle", "speed"]))
    for a, b in [("spring.flange_a", "fix.flange"), ("spring.flange_b", "rotor.flange_a"),
                 ("friction.flange", "rotor.flange_a"), ("w.flange", "rotor.flange_a"),
                 ("p.port", "rotor.flange_a")]:
        m.connect(a, b)
    omega = math.sqrt(C_SPRING / J)
    half = math.pi / omega
    t_end = 1.8 * half                               # well before the rotor sticks
    res = kn.simulate(m, t_end=t_end, n_points=37, rtol=1e-11, atol=1e-12, jit=False)

    # scipy: each half-swing integrated on its own, its end located as an event (w = 0)
    def rhs(t, y, tau):
        return [y[1], (-C_SPRING * y[0] + tau) / J]
    y, t0, tau, pieces = [PHI0, 0.0], 0.0, C_COULOMB, []
    while t0 < t_end:
        def stop(t, y, tau):
            return y[1]
        stop.terminal, stop.direction = True, 1 if tau > 0 else -1
        sol = solve_ivp(rhs, (t0, t_end), y, method="DOP853", rtol=1e-13, atol=1e-13,
                        args=(tau,), events=stop, dense_output=True)
        pieces.append((t0, sol.t[-1], sol.sol))
        t0, y, tau = sol.t[-1], [sol.y[0, -1], 0.0], -tau
    ref = np.array([next(s(t) for a, b, s in pieces if a <= t <= b) for t in res.t])
    np.testing.assert_allclose(res["p.angle"], ref[:, 0], atol=2e-8)
    np.testing.assert_allclose(res["p.speed"], ref[:, 1], atol=2e-7)
    # the closed form: the first half-swing about c/k, the second about -c/k
    ck = C_COULOMB / C_SPRING
    first = ck + (PHI0 - ck) * np.cos(omega * res.t)
    second = -ck + (2 * ck - PHI0 + ck) * np.cos(omega * (res.t - half))
    np.testing.assert_allclose(res["p.angle"], np.where(res.t <= half, first, second),
                               atol=2e-8)


def test_engine1b_as_one_force_equals_the_expression_block_wiring():
    one, blocks = engine1b(), engine1b(blocks=True)
    assert "gasLaw" not in one.components and "gasLaw" in blocks.components
    runs = [kn.simulate(model, t_end=0.05, n_points=11, rtol=1e-10, atol=1e-10, jit=False)
            for model in (one, blocks)]
    for key in ("crank.angle", "crank.speed", "stroke.position"):
        np.testing.assert_allclose(runs[0][key], runs[1][key], rtol=0, atol=1e-12)


def refusal(f, sensor=kn.translational.PositionSensor):
    m = oscillator(law=False)
    m.add(kn.translational.Force("law", f=f))
    m.add(sensor("pos"))
    m.connect("law.flange", "mass.flange_a")
    m.connect("pos.flange", "mass.flange_a")
    with pytest.raises(kn.ModelError) as info:
        m.compile()
    return str(info.value)


def test_a_name_that_is_no_signal_output_is_refused_naming_the_parameter():
    text = refusal("-k*pos.yy")
    assert "law.f" in text and "'pos.yy' is not a signal output" in text
    assert "pos.y" in text                           # the close name
    text = refusal("-k*mass.flange_a")
    assert "law.f" in text and "'mass.flange_a' is not a signal output" in text


def test_a_law_reading_an_acceleration_of_what_it_drives_is_an_algebraic_loop():
    text = refusal("-0.1*pos.y", sensor=kn.translational.AccSensor)
    assert "algebraic loop through pos and the mechanics" in text


def test_a_parameter_without_signals_still_refuses_a_dotted_name():
    with pytest.raises(kn.ModelError, match="is not a parameter here"):
        kn.translational.Spring("spring", c="pos.y")
