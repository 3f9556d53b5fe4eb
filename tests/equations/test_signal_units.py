"""Signals carry the unit of what they stand for, spread along the wires from the parts that
fix it: a sensor's output, a source's input, through blocks that keep units."""

import pytest

import kinetwork as kn
from scenes import double_pendulum


def units(model):
    res = kn.simulate(model, t_end=0.05, n_points=3)
    return {name: sig.unit for name, sig in res.signals.items() if sig.quantity == "value"}


def test_arm_pid_reference_is_an_angle_and_command_a_torque():
    """The reference meets the measured angle at the PID (set point and measurement share a
    unit); the PID's output drives a torque source."""
    found = units(kn.load("models/arm_pid.json"))
    assert found == {"command_shoulder.value": "N*m", "reference_shoulder.value": "rad",
                     "command_elbow.value": "N*m", "reference_elbow.value": "rad"}


def wired(*blocks, connections=(), probes=()):
    m = double_pendulum()
    for block in blocks:
        m.add(block)
    for a, b in connections:
        m.connect(a, b)
    for name, port in probes:
        m.add(kn.Probe(name, quantities=["value"]))
        m.connect(f"{name}.port", port)
    return m


def test_units_pass_adders_and_limiters_but_not_gains():
    m = wired(kn.rotational.SpeedSensor("w"), kn.signals.Limiter("lim", u_max=1.0),
              kn.signals.Gain("gain", k=2.0), kn.signals.Constant("offset", k=0.1),
              kn.signals.Add("add"), kn.rotational.Torque("motor"),
              connections=[("w.flange", "elbow.axis"), ("w.y", "lim.u"), ("lim.y", "add.u1"),
                           ("offset.y", "add.u2"), ("add.y", "gain.u"), ("gain.y", "motor.u"),
                           ("motor.flange", "shoulder.axis")],
              probes=[("limited", "lim.y"), ("offset_p", "offset.y"), ("sum", "add.y"),
                      ("torque", "gain.y")])
    assert units(m) == {"limited.value": "rad/s", "offset_p.value": "rad/s",
                        "sum.value": "rad/s", "torque.value": "N*m"}


def test_a_unit_fixed_two_ways_is_not_guessed():
    """An angle added to a speed: the wires disagree, so the sum has no unit (plots say 1)."""
    m = wired(kn.rotational.AngleSensor("q"), kn.rotational.SpeedSensor("w"),
              kn.signals.Add("add"),
              connections=[("q.flange", "elbow.axis"), ("w.flange", "elbow.axis"),
                           ("q.y", "add.u1"), ("w.y", "add.u2")],
              probes=[("sum", "add.y")])
    assert units(m) == {"sum.value": ""}


@pytest.mark.parametrize("sensor, unit", [(kn.electrical.VoltageSensor, "V"),
                                          (kn.electrical.CurrentSensor, "A")])
def test_electrical_sensors(sensor, unit):
    m = kn.Model("circuit")
    m.add(kn.electrical.Ground("gnd"))
    m.add(kn.electrical.VoltageSource("src", V="sin(t)"))
    m.add(kn.electrical.Resistor("r", R=2.0))
    m.add(sensor("s"))
    m.add(kn.Probe("p", quantities=["value"]))
    m.connect("src.p", "r.p")
    if sensor is kn.electrical.VoltageSensor:
        m.connect("s.p", "r.p"); m.connect("s.n", "gnd.p"); m.connect("r.n", "gnd.p")
    else:
        m.connect("r.n", "s.p"); m.connect("s.n", "gnd.p")
    m.connect("src.n", "gnd.p")
    m.connect("p.port", "s.y")
    assert units(m) == {"p.value": unit}
