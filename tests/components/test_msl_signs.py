"""The sign conventions of MSL-named 1-D sources and sensors, each checked on a scene with a
closed form: Torque and Force drive their flange with +tau (+f) and put -tau on their
support (MSL: flange.tau = -tau, support.tau = tau); TorqueSensor and ForceSensor read
flange_a.tau, the torque the flange_a side passes on (MSL); the motion sensors read their
flange; Speed and Accelerate integrate from phi0 (w0)."""

import numpy as np
import pytest

import kinetwork as kn

rot, tr = kn.rotational, kn.translational
TIGHT = dict(rtol=1e-11, atol=1e-12)


@pytest.mark.parametrize("lib, source, sensor, inertia", [
    (rot, "Torque", "TorqueSensor", "J"), (tr, "Force", "ForceSensor", "m")])
def test_sources_drive_with_plus_and_sensors_read_flange_a(lib, source, sensor, inertia):
    """+2 on J1 (1) through the sensor into J2 (3), the source's support on a housing J0 (4):
    both accelerate at 2 / 4, the housing at -2 / 4; the sensor reads J2 a = 1.5; the angle,
    speed and acceleration sensors read J2's."""
    m = kn.Model("signs")
    m.add(getattr(lib, "Inertia" if lib is rot else "Mass")("J1", **{inertia: 1.0}))
    m.add(getattr(lib, "Inertia" if lib is rot else "Mass")("J2", **{inertia: 3.0}))
    m.add(getattr(lib, "Inertia" if lib is rot else "Mass")("J0", **{inertia: 4.0}))
    m.add(getattr(lib, source)("push", **{"tau" if lib is rot else "f": 2.0}))
    m.add(getattr(lib, sensor)("through"))
    names = ("AngleSensor", "SpeedSensor", "AccSensor") if lib is rot else \
        ("PositionSensor", "SpeedSensor", "AccSensor")
    for n in names:
        m.add(getattr(lib, n)(n))
        m.connect(f"{n}.flange", "J2.flange_b")
    m.add(kn.Probe("out", quantities=["value"]))
    for a, b in [("push.flange", "J1.flange_a"), ("push.support", "J0.flange_a"),
                 ("J1.flange_b", "through.flange_a"), ("through.flange_b", "J2.flange_a"),
                 ("out.port", "through.y")]:
        m.connect(a, b)
    for n in names:
        m.add(kn.Probe(f"p_{n}", quantities=["value"]))
        m.connect(f"p_{n}.port", f"{n}.y")
    res = kn.simulate(m, t_end=1.0, n_points=5, **TIGHT)
    t, a = res.t, 2.0 / 4.0
    np.testing.assert_allclose(res["out.value"], 3.0 * a, atol=1e-10)
    np.testing.assert_allclose(res[f"p_{names[0]}.value"], a * t**2 / 2, atol=1e-10)
    np.testing.assert_allclose(res[f"p_{names[1]}.value"], a * t, atol=1e-10)
    np.testing.assert_allclose(res[f"p_{names[2]}.value"], a, atol=1e-10)
    housing = "J0.phi" if lib is rot else "J0.s"
    np.testing.assert_allclose(res[housing], -2.0 / 4.0 * t**2 / 2, atol=1e-10)


def test_speed_and_accelerate_integrate_from_their_start_values():
    m = kn.Model("motions")
    m.add(rot.Speed("speed", w_ref="2*t", phi0=0.5))
    m.add(rot.Accelerate("acc", a_ref=1.0, phi0=-0.2, w0=3.0))
    m.add(rot.Inertia("a", J=1.0))
    m.add(rot.Inertia("b", J=1.0))
    m.add(kn.Probe("pa", quantities=["angle", "speed"]))
    m.add(kn.Probe("pb", quantities=["angle", "speed"]))
    for x, y in [("speed.flange", "a.flange_a"), ("acc.flange", "b.flange_a"),
                 ("pa.port", "a.flange_b"), ("pb.port", "b.flange_b")]:
        m.connect(x, y)
    res = kn.simulate(m, t_end=1.0, n_points=5, **TIGHT)
    t = res.t
    np.testing.assert_allclose(res["pa.angle"], 0.5 + t**2, atol=1e-10)
    np.testing.assert_allclose(res["pb.angle"], -0.2 + 3 * t + t**2 / 2, atol=1e-10)
    np.testing.assert_allclose(res["pb.speed"], 3 + t, atol=1e-10)
