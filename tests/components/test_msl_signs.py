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


@pytest.mark.parametrize("lib, speed, flow", [(rot, "w", "tau"), (tr, "v", "f")])
def test_multi_and_power_sensors_read_flange_a_and_their_product(lib, speed, flow):
    """MSL's MultiSensor and PowerSensor in series between J1 (1) and J2 (3), J1 driven by
    +2 from the world: both move at a = 2 / 4; into flange_a flows J2 a = 1.5, and the power
    passed on is 1.5 a t, the rate of J2's kinetic energy; a reversed PowerSensor reads its
    negative."""
    body = "Inertia" if lib is rot else "Mass"
    key = "J" if lib is rot else "m"
    m = kn.Model("power")
    m.add(getattr(lib, body)("J1", **{key: 1.0}))
    m.add(getattr(lib, body)("J2", **{key: 3.0}))
    m.add(getattr(lib, "Torque" if lib is rot else "Force")(
        "push", **{"tau" if lib is rot else "f": 2.0}))
    m.add(lib.MultiSensor("multi"))
    m.add(lib.PowerSensor("power"))
    m.add(lib.PowerSensor("back"))
    wires = [("push.flange", "J1.flange_a"), ("J1.flange_b", "multi.flange_a"),
             ("multi.flange_b", "power.flange_a"), ("power.flange_b", "back.flange_b"),
             ("back.flange_a", "J2.flange_a")]
    for port in ("multi.power", f"multi.{speed}", f"multi.{flow}", "power.power",
                 "back.power"):
        name = port.replace(".", "_")
        m.add(kn.Probe(name, quantities=["value"]))
        wires.append((f"{name}.port", port))
    for a, b in wires:
        m.connect(a, b)
    res = kn.simulate(m, t_end=1.0, n_points=5, **TIGHT)
    t, a = res.t, 2.0 / 4.0
    np.testing.assert_allclose(res[f"multi_{flow}.value"], 3.0 * a, atol=1e-10)
    np.testing.assert_allclose(res[f"multi_{speed}.value"], a * t, atol=1e-10)
    for probe in ("multi_power", "power_power"):
        np.testing.assert_allclose(res[f"{probe}.value"], 3.0 * a * a * t, atol=1e-10)
    np.testing.assert_allclose(res["back_power.value"], -3.0 * a * a * t, atol=1e-10)


def test_rod_keeps_its_length_and_passes_the_force():
    """MSL's Translational Rod: +2 N on m1 (1 kg, s0 = 0.1) pushes m2 (3 kg, L = 0.2) through a
    rod of L = 0.5: m2's centre stays 0.5 + 0.1 ahead of m1, both accelerate at 2 / 4, and the
    rod passes m2 its 1.5 N; a rod from a Fixed at 1 puts a free mass's flange at 1 + L."""
    m = kn.Model("rod")
    m.add(tr.Mass("m1", m=1.0, s0=0.1))
    m.add(tr.Mass("m2", m=3.0, L=0.2))
    m.add(tr.Force("push", f=2.0))
    m.add(tr.Rod("rod", L=0.5))
    m.add(tr.ForceSensor("through"))
    m.add(tr.Fixed("wall", s0=1.0))
    m.add(tr.Rod("arm", L=-0.3))
    m.add(tr.Mass("m3", m=1.0, L=0.4))
    m.add(kn.Probe("f", quantities=["value"]))
    m.add(kn.Probe("p2", quantities=["position"]))
    m.add(kn.Probe("p3", quantities=["position"]))
    for a, b in [("push.flange", "m1.flange_a"), ("m1.flange_b", "rod.flange_a"),
                 ("rod.flange_b", "through.flange_a"), ("through.flange_b", "m2.flange_a"),
                 ("f.port", "through.y"), ("wall.flange", "arm.flange_a"),
                 ("arm.flange_b", "m3.flange_b"), ("p2.port", "m2.flange_b"),
                 ("p3.port", "m3.flange_a")]:
        m.connect(a, b)
    res = kn.simulate(m, t_end=1.0, n_points=5, **TIGHT)
    t, a = res.t, 2.0 / 4.0
    np.testing.assert_allclose(res["m1.s"], 0.1 + a * t**2 / 2, atol=1e-10)
    np.testing.assert_allclose(res["p2.position"], 0.1 + 0.5 + 0.2 + a * t**2 / 2, atol=1e-10)
    np.testing.assert_allclose(res["f.value"], 1.5, atol=1e-10)
    np.testing.assert_allclose(res["p3.position"], 1.0 - 0.3 - 0.4, atol=1e-10)
