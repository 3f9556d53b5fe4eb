"""The rotational library (kinetwork/components/rotational.py): its types, domain, names and
units; the laws are the partials' (test_oned.py)."""

import inspect

import pytest

import kinetwork as kn
from kinetwork.components.base import Component

rot = kn.rotational
CLASSES = [cls for _, cls in inspect.getmembers(rot, inspect.isclass)
           if issubclass(cls, Component) and cls.__module__ == rot.__name__]


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_every_type_is_rotational(cls):
    assert cls.type_name == f"rotational.{cls.__name__}"
    assert cls.domain == "rotational"
    one_d = [p for p in cls.ports.values() if p.domain not in ("signal_in", "signal_out")]
    assert one_d and all(p.domain == "rotational" for p in one_d)


def test_names_and_units_are_those_of_angles_and_torques():
    assert rot.SpringDamper.params["c"].unit == "N*m/rad"
    assert rot.SpringDamper.params["phi_rel0"].unit == "rad"
    assert rot.Torque.params["tau"].unit == "N*m" and rot.Torque.params["tau"].time
    assert rot.Inertia.params["J"].unit == "kg*m^2"
    assert set(rot.Position.params) == {"phi_ref", "exact", "f_crit"}
    assert set(rot.Speed.params) == {"w_ref", "exact", "f_crit", "phi0"}
    assert set(rot.Accelerate.params) == {"a_ref", "phi0", "w0"}
    assert rot.Accelerate.params["a_ref"].unit == "rad/s^2"
    assert rot.Position.params["f_crit"].unit == "Hz"
    assert rot.Fixed("f", phi0=0.4).position() == 0.4


def test_sensors_say_what_they_measure():
    assert [s.quantity for s in (rot.AngleSensor, rot.SpeedSensor, rot.AccSensor,
                                 rot.TorqueSensor)] == ["position", "speed", "acceleration",
                                                        "flow"]
    assert "support" in rot.IdealGear.ports and rot.IdealGear.ports["support"].optional
