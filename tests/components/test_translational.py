"""The translational library (kinetwork/components/translational.py): its types, domain, names
and units; the laws are the partials' (test_oned.py)."""

import inspect

import pytest

import kinetwork as kn
from kinetwork.components.base import Component

tr = kn.translational
CLASSES = [cls for _, cls in inspect.getmembers(tr, inspect.isclass)
           if issubclass(cls, Component) and cls.__module__ == tr.__name__]


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_every_type_is_translational(cls):
    assert cls.type_name == f"translational.{cls.__name__}"
    assert cls.domain == "translational"
    one_d = [p for p in cls.ports.values() if p.domain not in ("signal_in", "signal_out")]
    assert one_d and all(p.domain == "translational" for p in one_d)


def test_names_and_units_are_those_of_positions_and_forces():
    assert tr.SpringDamper.params["c"].unit == "N/m"
    assert tr.SpringDamper.params["s_rel0"].unit == "m"
    assert tr.Force.params["f"].unit == "N" and tr.Force.params["f"].time
    assert tr.Mass.params["m"].unit == "kg"
    assert set(tr.Position.params) == {"s_ref", "exact", "f_crit"}
    assert set(tr.Speed.params) == {"v_ref", "exact", "f_crit", "s0"}
    assert set(tr.Accelerate.params) == {"a_ref", "s0", "v0"}
    assert tr.Accelerate.params["a_ref"].unit == "m/s^2"
    assert tr.Fixed("f", s0=-0.2).position() == -0.2


def test_sensors_say_what_they_measure():
    assert [s.quantity for s in (tr.PositionSensor, tr.SpeedSensor, tr.AccSensor,
                                 tr.ForceSensor)] == ["position", "speed", "acceleration",
                                                      "flow"]
