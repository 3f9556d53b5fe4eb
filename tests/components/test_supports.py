"""Gears whose support is wired (MSL's useSupport): the flanges turn relative to the housing
and the housing takes the reaction. Checked against a sympy Lagrangian (the issue's housing
example), against MSL's Rotational.Examples.ElasticBearing written out by hand and integrated
by scipy, and against closed forms; what cannot ride is refused by name."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import kinetwork as kn

rot = kn.rotational
TIGHT = dict(rtol=1e-11, atol=1e-12)


def housing_model(ratio=3.0, support="housing", tau=1.0):
    """Shaft, load and housing inertias (J = 1), an IdealGear between shaft and load with
    its support on the housing, 1 N*m on the shaft."""
    m = kn.Model("housing")
    for name in ("shaft", "load", "housing"):
        m.add(rot.Inertia(name, J=1.0))
    m.add(rot.IdealGear("gear", ratio=ratio))
    m.add(rot.Torque("tq", tau=tau))
    m.add(kn.Probe("reaction", quantities=["torque"]))
    for a, b in [("tq.flange", "shaft.flange_a"), ("shaft.flange_b", "gear.flange_a"),
                 ("gear.flange_b", "load.flange_a"), ("reaction.port", "gear.support")]:
        m.connect(a, b)
    if support:
        m.connect("gear.support", f"{support}.flange_a")
    return m


def lagrange_housing(ratio):
    """Constant accelerations (shaft, load, housing) under 1 N*m on the shaft, from the
    Lagrangian in (load, housing): shaft = ratio * load + (1 - ratio) * housing."""
    t = sp.symbols("t")
    b, h = sp.Function("b")(t), sp.Function("h")(t)
    a = ratio * b + (1 - ratio) * h
    T = (sp.diff(a, t) ** 2 + sp.diff(b, t) ** 2 + sp.diff(h, t) ** 2) / 2
    work = {b: sp.diff(a, b), h: sp.diff(a, h)}          # 1 N*m on the shaft: d(a)/d(q)
    eqs = [sp.diff(sp.diff(T, sp.diff(q, t)), t) - sp.diff(T, q) - work[q] for q in (b, h)]
    acc = sp.solve(eqs, [sp.diff(b, t, 2), sp.diff(h, t, 2)])
    ab, ah = float(acc[sp.diff(b, t, 2)]), float(acc[sp.diff(h, t, 2)])
    return ratio * ab + (1 - ratio) * ah, ab, ah


def test_the_issues_housing_example_on_the_lagrangian():
    res = kn.simulate(housing_model(), t_end=1.0, n_points=11, **TIGHT)
    a_shaft, a_load, a_housing = lagrange_housing(3.0)
    t = res.t
    np.testing.assert_allclose(res["shaft.phi"], a_shaft * t**2 / 2, atol=1e-10)
    np.testing.assert_allclose(res["housing.phi"], a_housing * t**2 / 2, atol=1e-10)
    # the figures of the issue: shaft 0.4643 rad, housing 0.0714 rad turned backwards
    assert res["shaft.phi"][-1] == pytest.approx(13 / 28, abs=1e-10)
    assert res["housing.phi"][-1] == pytest.approx(-1 / 14, abs=1e-10)
    # MSL's reaction: support.tau = -flange_a.tau - flange_b.tau (into the gear), the
    # opposite of what turns the housing (J = 1)
    np.testing.assert_allclose(res["reaction.torque"], -a_housing, atol=1e-10)


@pytest.mark.parametrize("ratio", [3.0, -2.0, 0.5])
def test_gear_ratios_and_the_shares_on_the_lagrangian(ratio):
    res = kn.simulate(housing_model(ratio), t_end=0.5, n_points=6, **TIGHT)
    a_shaft, a_load, a_housing = lagrange_housing(ratio)
    t = res.t
    np.testing.assert_allclose(res["housing.phi"], a_housing * t**2 / 2, atol=1e-10)
    np.testing.assert_allclose(res["shaft.phi"], a_shaft * t**2 / 2, atol=1e-10)


def test_an_unwired_support_and_one_on_a_fixed_are_the_world():
    free = kn.simulate(housing_model(support=None), t_end=1.0, n_points=3, **TIGHT)
    # 1 N*m through ratio 3 onto J = 1 + 1/9: the shaft turns 0.45 rad in 1 s
    assert free["shaft.phi"][-1] == pytest.approx(0.45, abs=1e-10)
    m = housing_model(support=None)
    m.add(rot.Fixed("base", phi0=0.3))
    m.connect("gear.support", "base.flange")
    m.components["load"].phi0 = 0.3            # the gear's flanges start at the housing
    m.components["shaft"].phi0 = 0.3
    res = kn.simulate(m, t_end=1.0, n_points=3, **TIGHT)
    # relative to the housing at 0.3: shaft - 0.3 = 3 (load - 0.3)
    assert res["shaft.phi"][-1] == pytest.approx(0.75, abs=1e-10)


def elastic_bearing(t_end=10.0):
    """MSL Rotational.Examples.ElasticBearing, its wiring and parameters: a ramp torque on the
    shaft (its support fixed), an IdealGear(ratio 3, useSupport) whose housing (J = 5) sits
    on a SpringDamper (c = 1e5, d = 5) to the ground through a torque sensor, the load
    (J = 50) behind a Spring (c = 1e3)."""
    m = kn.Model("ElasticBearing")
    m.add(rot.Inertia("shaft", J=1.0, phi0=0.0))
    m.add(rot.Inertia("load", J=50.0, w0=0.0))
    m.add(rot.Spring("spring", c=1e3))
    m.add(rot.Fixed("fixed"))
    m.add(rot.SpringDamper("springDamper", c=1e5, d=5.0))
    m.add(rot.Torque("torque"))
    m.add(kn.signals.Ramp("ramp", height=100.0, duration=5.0))
    m.add(rot.IdealGear("idealGear", ratio=3.0))
    m.add(rot.Inertia("housing", J=5.0))
    m.add(rot.TorqueSensor("multiSensor"))
    for a, b in [("torque.flange", "shaft.flange_a"), ("spring.flange_b", "load.flange_a"),
                 ("springDamper.flange_a", "fixed.flange"),
                 ("shaft.flange_b", "idealGear.flange_a"),
                 ("idealGear.flange_b", "spring.flange_a"),
                 ("idealGear.support", "housing.flange_b"), ("ramp.y", "torque.u"),
                 ("fixed.flange", "torque.support"),
                 ("housing.flange_a", "multiSensor.flange_b"),
                 ("multiSensor.flange_a", "springDamper.flange_b")]:
        m.connect(a, b)
    return m


def elastic_bearing_reference(t):
    """The same equations by hand: gear output b = shaft / 3 + 2 housing / 3."""
    Js, Jh, Jl, c, c2, d = 1.0, 5.0, 50.0, 1e3, 1e5, 5.0

    def rhs(time, x):
        s, h, l, ws, wh, wl = x
        b = s / 3 + 2 * h / 3
        tau = 100.0 * min(time, 5.0) / 5.0
        f = c * (l - b)                           # the spring's pull on flange_b
        return [ws, wh, wl, (tau + f / 3) / Js, (-c2 * h - d * wh + 2 * f / 3) / Jh,
                -f / Jl]
    sol = solve_ivp(rhs, (0, t[-1]), np.zeros(6), method="DOP853", t_eval=t, rtol=1e-12,
                    atol=1e-13, max_step=0.01)
    return sol.y


def test_elastic_bearing_housing_speed_on_the_hand_written_equations():
    res = kn.simulate(elastic_bearing(), t_end=10.0, n_points=201, **TIGHT)
    s, h, l, ws, wh, wl = elastic_bearing_reference(res.t)
    np.testing.assert_allclose(res["load.phi"], l, atol=1e-7 * np.max(np.abs(l)))
    np.testing.assert_allclose(res["shaft.w"], ws, atol=1e-7 * np.max(np.abs(ws)))
    np.testing.assert_allclose(res["housing.w"], wh, atol=1e-7 * np.max(np.abs(wh)))
    assert np.max(np.abs(wh)) > 5e-4             # the housing moves: it is no ground


def test_a_train_on_a_prescribed_housing_on_the_closed_form():
    """The housing turns h = A sin(w t) by a Position; the train (shaft J1, gear r, load
    J2) rides on it: (J1 r^2 + J2) b'' = r tau - J1 r (1 - r) h'', b the load's angle."""
    J1, J2, r, tau, A, w = 2.0, 3.0, 4.0, 1.5, 0.3, 2.0
    m = kn.Model("on_a_motion")
    m.add(rot.Inertia("shaft", J=J1))
    m.add(rot.Inertia("load", J=J2, phi0=0.0, w0=0.0))
    m.add(rot.IdealGear("gear", ratio=r))
    m.add(rot.Torque("tq", tau=tau))
    m.add(rot.Position("drive", phi_ref=f"{A}*sin({w}*t)"))
    m.add(kn.Probe("housing", quantities=["angle"]))
    m.add(kn.Probe("out", quantities=["angle"]))
    for a, b in [("tq.flange", "shaft.flange_a"), ("shaft.flange_b", "gear.flange_a"),
                 ("gear.flange_b", "load.flange_a"), ("gear.support", "drive.flange"),
                 ("housing.port", "drive.flange"), ("out.port", "load.flange_b")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=2.0, n_points=21, **TIGHT)
    t = res.t
    M = J1 * r**2 + J2
    c0, c1 = r * tau / M, J1 * r * (1 - r) * A * w**2 / M
    b = c0 * t**2 / 2 + c1 * (t - np.sin(w * t) / w) / w
    h = A * np.sin(w * t)
    np.testing.assert_allclose(res["out.angle"], b, atol=1e-9)
    np.testing.assert_allclose(res["housing.angle"], h, atol=1e-12)
    np.testing.assert_allclose(res["shaft.phi"], r * b + (1 - r) * h, atol=1e-9)


def test_a_motion_relative_to_a_free_housing():
    """A Speed source mounted on a free housing (J_h) spins its rotor (J_r) up at w_rel = a t
    relative to it: the rotor's angle is the housing's plus a t^2 / 2, and with nothing else
    acting the angular momentum J_r w_r + J_h w_h stays 0."""
    Jr, Jh, acc = 0.5, 2.0, 3.0
    m = kn.Model("motor_on_housing")
    m.add(rot.Inertia("rotor", J=Jr))
    m.add(rot.Inertia("housing", J=Jh))
    m.add(rot.Speed("motor", w_ref=f"{acc}*t"))
    m.add(kn.Probe("spin", quantities=["angle", "speed"]))
    m.connect("motor.flange", "rotor.flange_a")
    m.connect("motor.support", "housing.flange_a")
    m.connect("spin.port", "rotor.flange_b")
    res = kn.simulate(m, t_end=1.0, n_points=11, **TIGHT)
    t = res.t
    np.testing.assert_allclose(res["spin.angle"] - res["housing.phi"], acc * t**2 / 2,
                               atol=1e-10)
    np.testing.assert_allclose(Jr * res["spin.speed"] + Jh * res["housing.w"], 0, atol=1e-10)
    np.testing.assert_allclose(res["housing.w"], -Jr * acc * t / (Jr + Jh), atol=1e-10)


def test_friction_and_sources_on_a_free_housing_take_their_reactions():
    """A Torque with its support on the housing spins rotor and housing apart (tau / J_r and
    -tau / J_h); a Brake between them holds (stuck: they turn as one under a torque on the
    rotor) or slips (the kinetic torque on both)."""
    def scene(source_on_housing, fn):
        m = kn.Model("brake_on_housing")
        m.add(rot.Inertia("rotor", J=1.0))
        m.add(rot.Inertia("housing", J=3.0))
        m.add(rot.Torque("tq", tau=2.0))
        m.add(rot.Brake("brake", mu=0.5, fn_max=fn, f_normalized=1.0))
        for a, b in [("tq.flange", "rotor.flange_a"), ("brake.flange", "rotor.flange_b"),
                     ("brake.support", "housing.flange_a")]:
            m.connect(a, b)
        if source_on_housing:
            m.connect("tq.support", "housing.flange_b")
        return kn.simulate(m, t_end=1.0, n_points=3, **TIGHT)
    stuck = scene(False, 100.0)                    # holds up to 50 N*m: 2 / (1 + 3)
    np.testing.assert_allclose(stuck["rotor.w"], 0.5 * stuck.t, atol=1e-10)
    np.testing.assert_allclose(stuck["housing.w"], 0.5 * stuck.t, atol=1e-10)
    slip = scene(False, 1.0)                       # 0.5 N*m kinetic
    np.testing.assert_allclose(slip["rotor.w"], 1.5 * slip.t, atol=1e-9)
    np.testing.assert_allclose(slip["housing.w"], 0.5 / 3 * slip.t, atol=1e-9)
    apart = scene(True, 1.0)                       # the source's reaction on the housing
    np.testing.assert_allclose(apart["rotor.w"], 1.5 * apart.t, atol=1e-9)
    np.testing.assert_allclose(apart["housing.w"], -1.5 / 3 * apart.t, atol=1e-9)


def _arm():
    m = kn.Model("arm")
    m.add(kn.multibody.Ground("ground"))
    m.add(kn.multibody.Revolute("joint"))
    m.add(kn.multibody.RigidBody("body", mass=1.0, r_cm=[0.5, 0, 0]))
    m.connect("ground.frame", "joint.frame_a")
    m.connect("joint.frame_b", "body.frame_a")
    m.add(rot.Inertia("motor", J=0.1))
    m.add(rot.IdealGear("gear", ratio=10.0))
    m.add(rot.Inertia("housing", J=1.0))
    m.connect("motor.flange_b", "gear.flange_a")
    return m


REFUSED = [
    ("a housing on a joint axis",
     lambda m: (m.connect("gear.flange_b", "housing.flange_a"),
                m.connect("gear.support", "joint.axis")),
     r"gear.support is wired to a flange that moves \(a joint axis\); a gear whose housing "
     r"turns with a joint axis is not supported"),
    ("a train on a joint axis riding on a free housing",
     lambda m: (m.connect("gear.flange_b", "joint.axis"),
                m.connect("gear.support", "housing.flange_a")),
     r"gear.support is wired to a flange that moves \(a free rotor\); its gear train is "
     r"tied to a joint axis"),
    ("a support on the gear's own flange",
     lambda m: (m.connect("gear.flange_b", "housing.flange_a"),
                m.connect("gear.support", "motor.flange_a")),
     r"gear.support is rigidly tied to the gear's own flanges"),
    ("a lossy gear on a moving housing",
     lambda m: (m.connect("gear.flange_b", "housing.flange_a"),
                m.add(rot.Inertia("case", J=1.0)), m.connect("gear.support", "case.flange_a"),
                setattr(m.components["gear"], "eta", 0.9)),
     r"gear has a loss \(eta < 1\), which is taken only on gears whose housing stands still"),
]


@pytest.mark.parametrize("what, edit, message", REFUSED, ids=[w for w, _, _ in REFUSED])
def test_what_cannot_ride_is_refused_by_name(what, edit, message):
    m = _arm()
    edit(m)
    with pytest.raises(kn.ModelError, match=message):
        m.compile()


def test_two_housings_carrying_each_other_are_refused():
    m = kn.Model("ring")
    for name in ("a1", "b1", "a2", "b2"):
        m.add(rot.Inertia(name, J=1.0))
    m.add(rot.IdealGear("g1", ratio=2.0))
    m.add(rot.IdealGear("g2", ratio=2.0))
    for a, b in [("a1.flange_b", "g1.flange_a"), ("g1.flange_b", "b1.flange_a"),
                 ("a2.flange_b", "g2.flange_a"), ("g2.flange_b", "b2.flange_a"),
                 ("g1.support", "a2.flange_a"), ("g2.support", "a1.flange_a")]:
        m.connect(a, b)
    with pytest.raises(kn.ModelError, match=r"g1, g2 carry each other's housings in a ring"):
        m.compile()
