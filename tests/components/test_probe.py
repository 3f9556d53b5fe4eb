"""The probe (kinetwork/components/probe.py): the table of quantities each domain offers,
and what a probe asks of the port it is wired to."""

import pytest

import kinetwork as kn
from kinetwork.components.probe import QUANTITIES


def test_every_quantity_has_a_unit_a_shape_and_a_formula():
    for domain, quantities in QUANTITIES.items():
        for name, q in quantities.items():
            assert q.shape in ((), (3,), (3, 3)), (domain, name)
            assert callable(q.formula), (domain, name)
    assert {n: q.unit for n, q in QUANTITIES["rotational"].items()} == {
        "angle": "rad", "speed": "rad/s", "acceleration": "rad/s^2", "torque": "N*m"}
    assert {n: q.unit for n, q in QUANTITIES["translational"].items()} == {
        "position": "m", "velocity": "m/s", "acceleration": "m/s^2", "force": "N"}
    assert QUANTITIES["frame"]["orientation"].shape == (3, 3)
    assert all(q.shape == (3,) for n, q in QUANTITIES["frame"].items() if n != "orientation")


def test_a_probe_records_all_of_its_domain_unless_told():
    everything = kn.Probe("p")
    assert everything.asked("translational") == list(QUANTITIES["translational"])
    assert everything.asked("signal_out") == ["value"]
    chosen = kn.Probe("p", quantities=["torque", "angle"])
    assert chosen.asked("rotational") == ["torque", "angle"]          # in the order given


def test_a_formula_reads_the_view_of_its_port():
    class Flange:
        pos, vel, acc, flow = 1.0, 2.0, 3.0, 4.0
    assert [q.formula(Flange) for q in QUANTITIES["rotational"].values()] == [1.0, 2.0, 3.0,
                                                                           4.0]


@pytest.mark.parametrize("quantities, message", [
    (["angel"], r"unknown 'angel' \(did you mean 'angle'\?\)"),
    (["angle", "angle"], "names repeated"),
    ("angle", "must be a list of names"),
])
def test_unknown_or_repeated_quantities_are_refused(quantities, message):
    with pytest.raises(kn.ModelError, match=message):
        kn.Probe("p", quantities=quantities)


def test_a_probe_connects_to_any_domain():
    assert kn.Probe.ports["port"].domain == "any"
    assert kn.Probe.type_name == "Probe"


SENSOR_UNITS = {
    kn.rotational.AngleSensor: "rad", kn.rotational.SpeedSensor: "rad/s",
    kn.rotational.AccSensor: "rad/s^2", kn.rotational.TorqueSensor: "N*m",
    kn.translational.PositionSensor: "m", kn.translational.SpeedSensor: "m/s",
    kn.translational.AccSensor: "m/s^2", kn.translational.ForceSensor: "N",
}


def test_a_sensor_finds_its_unit_by_the_quantity_s_name(monkeypatch):
    """A quantity added to a 1-D domain's table, anywhere in it, leaves every sensor's unit
    as it was: sensors read the table by name, not by position."""
    from kinetwork.components.quantities import Quantity
    for domain in ("rotational", "translational"):
        added = {"power": Quantity("W", (), lambda p: p.flow * p.vel)}
        # first, so that every quantity after it moves one place
        monkeypatch.setitem(QUANTITIES, domain, {**added, **QUANTITIES[domain],
                                                 "jerk": Quantity("m/s^3", (), None)})
    for cls, unit in SENSOR_UNITS.items():
        assert cls("s").signal_unit("y") == unit, cls.__name__
