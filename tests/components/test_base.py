"""Component declarations: registry, ports, parameters, safe expressions."""

import math

import pytest

import kinetwork as kn
from kinetwork.components.base import REGISTRY
from kinetwork.expr import Expression

CONTRACT = ["multibody.Ground", "multibody.Revolute", "multibody.Prismatic",
            "multibody.RigidBody", "multibody.FixedTranslation", "multibody.FixedRotation",
            *[f"{lib}.{name}" for lib in ("rotational", "translational")
              for name in ("SpringDamper", "Spring", "Damper", "Fixed")],
            "rotational.Torque", "translational.Force", "Probe"]


@pytest.mark.parametrize("type_name", CONTRACT)
def test_contract_components_registered_and_documented(type_name):
    cls = REGISTRY[type_name]
    assert cls.type_name == type_name
    assert cls.__doc__ and cls.__doc__.strip()
    for spec in cls.params.values():
        assert spec.doc, f"{type_name}.{spec.name} has no doc"


def test_one_dimensional_domains_follow_the_library():
    assert kn.multibody.Revolute.ports["axis"].domain == "rotational"
    assert kn.multibody.Prismatic.ports["support"].domain == "translational"
    assert kn.translational.SpringDamper.ports["flange_b"].domain == "translational"
    assert kn.rotational.Torque.ports["support"].optional


def test_joint_axis_parameter_and_flange_share_a_name():
    joint = kn.multibody.Revolute("j", axis=[1, 0, 0])
    assert joint.axis.path == "j.axis"                 # the flange port
    assert joint.direction == [1, 0, 0]                # the direction parameter
    assert joint.given == {"axis": [1, 0, 0]}


def test_inertia_diagonal_shorthand():
    body = kn.multibody.RigidBody("b", mass=1.0, inertia=[1, 2, 3])
    assert body.inertia == [[1, 0, 0], [0, 2, 0], [0, 0, 3]]


def test_laws_of_compliant_elements():
    sd = kn.rotational.SpringDamper("sd", c=3.0, d=0.5, phi_rel0=0.1)
    flows = sd.flows({"flange_a": 0.2, "flange_b": 1.0}, {"flange_a": 0.0, "flange_b": 2.0}, 0)
    assert flows["flange_b"] == pytest.approx(3.0 * (0.8 - 0.1) + 0.5 * 2.0)
    assert flows["flange_a"] == -flows["flange_b"]


@pytest.mark.parametrize("text, value", [
    ("-L1/2", -0.75), ("2*sin(3*t)", 2 * math.sin(0.6)), ("L1**2 + pi", 2.25 + math.pi),
    ("atan2(1, L1)", math.atan2(1, 1.5)), ("max(-1, min(2, 3))", 2.0), ("1e-3", 1e-3),
])
def test_expressions(text, value):
    assert Expression(text).evaluate({"L1": 1.5, "t": 0.2}) == pytest.approx(value)


@pytest.mark.parametrize("text", [
    "__import__('os').system('true')", "L1.real", "[1, 2]", "lambda: 1", "x if y else z",
    "open('f')", "'abc'", "L1[0]", "True", "a < b", "{1: 2}", "f'{x}'", "1 +",
    "sin(x=1)", "x" * 3000,
])
def test_expressions_refuse_anything_but_arithmetic(text):
    with pytest.raises(kn.ModelError):
        Expression(text)
