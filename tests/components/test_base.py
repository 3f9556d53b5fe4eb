"""The declaration machinery (kinetwork/components/base.py): the registry, parameters checked
at construction and on assignment, ports that are not parameters."""

import json

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.components.base import REGISTRY
from scenes import double_pendulum

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


def test_partials_are_not_file_types():
    assert all(not name.split(".")[-1].startswith("Partial") for name in REGISTRY)
    assert kn.multibody.PartialJoint.type_name is None


@pytest.mark.parametrize("name", ["1mass", "mass 1", "mass1\n", "", "x" * 201, 3])
def test_component_names_must_be_identifiers(name):
    with pytest.raises(kn.ModelError, match="must be an identifier"):
        kn.multibody.RigidBody(name, mass=1.0)


def test_construction_reports_every_problem_at_once():
    with pytest.raises(kn.ModelError) as info:
        kn.multibody.RigidBody("b", mas=1.0, r_cm=[0, 0])
    text = str(info.value)
    assert "b.mas: unknown parameter (did you mean 'mass'?)" in text
    assert "b.mass: a value is required" in text
    assert "b.r_cm: must have 3 entries" in text


# -- parameters assigned after construction ---------------------------------------------------

def test_an_out_of_bounds_assignment_names_the_place_and_the_bound():
    model = double_pendulum()
    body = model.components["mass1"]
    with pytest.raises(kn.ModelError, match=r"^mass1\.mass = -1 kg: must be >= 0"):
        body.mass = -1
    with pytest.raises(kn.ModelError, match=r"mass1\.r_cm: must have 3 entries, got 2"):
        body.r_cm = [0, 1]
    # refused: nothing changed
    assert body.mass == "m1" and body.given["mass"] == "m1"
    assert model.numeric_values()["mass1"]["mass"] == 1.0


def test_an_assignment_is_what_save_numeric_values_and_simulate_see(tmp_path):
    model = double_pendulum()
    before = kn.simulate(model, t_end=1.0, n_points=11, rtol=1e-10, atol=1e-12)
    model.components["mass1"].mass = 2

    assert model.numeric_values()["mass1"]["mass"] == 2.0
    saved = {c["name"]: c for c in json.loads(kn.dumps(model))["components"]}
    assert saved["mass1"]["params"]["mass"] == 2
    model.save(tmp_path / "m.json")
    assert kn.load(tmp_path / "m.json").components["mass1"].mass == 2

    after = kn.simulate(model, t_end=1.0, n_points=11, rtol=1e-10, atol=1e-12)
    heavier = kn.simulate(double_pendulum(m1=2.0), t_end=1.0, n_points=11, rtol=1e-10,
                          atol=1e-12)
    assert np.max(np.abs(after.states - before.states)) > 1e-4
    np.testing.assert_allclose(after.states, heavier.states, rtol=0, atol=1e-8)


def test_a_joint_direction_is_n_and_is_also_given_as_axis():
    joint = kn.multibody.Revolute("j")
    joint.n = [1, 0, 0]                         # Modelica's name; the flange is ``axis``
    assert joint.given["n"] == [1, 0, 0] and joint.written_params() == {"n": [1, 0, 0]}
    joint.set_param("axis", [0, 1, 0])          # the name files used: accepted, kept
    assert joint.n == [0, 1, 0] and joint.written_params() == {"axis": [0, 1, 0]}
    joint.set_param("n", [0, 0, 1])
    assert joint.written_params() == {"n": [0, 0, 1]}
    with pytest.raises(kn.ModelError, match=r"j\.axis is a port, not a parameter.*j\.n"):
        joint.axis = [1, 0, 0]
    with pytest.raises(kn.ModelError, match="axis and n are one parameter"):
        kn.multibody.Revolute("j", n=[1, 0, 0], axis=[1, 0, 0])
    spring = kn.rotational.SpringDamper("sd", c=1.0, d=0.0, phi_rel0=0.1)
    assert spring.phi_rel0 == 0.1
    spring.phi_rel0 = 0.2
    assert spring.phi_rel0 == 0.2 and spring.given["phi_rel0"] == 0.2


@pytest.mark.parametrize("assign, message", [
    (lambda b: setattr(b, "nosuch", 1), r"RigidBody 'mass1' has no parameter 'nosuch'"),
    (lambda b: setattr(b, "mas", 1), r"no parameter 'mas' \(did you mean 'mass'\?\)"),
    (lambda b: setattr(b, "frame_a", 1), r"mass1\.frame_a is a port, not a parameter"),
    (lambda b: setattr(b, "name", "other"), r"cannot be renamed"),
    (lambda b: delattr(b, "mass"), r"mass1\.mass: parameters and ports cannot be deleted"),
    (lambda b: b.set_param("nosuch", 1), r"has no parameter 'nosuch'"),
])
def test_assigning_anything_but_a_parameter_is_refused(assign, message):
    model = double_pendulum()
    body = model.components["mass1"]
    before = kn.dumps(model)
    with pytest.raises(kn.ModelError, match=message):
        assign(body)
    assert kn.dumps(model) == before and body.name == "mass1"


def test_a_misspelt_port_or_parameter_is_named_with_a_suggestion():
    body = kn.multibody.RigidBody("b", mass=1.0)
    with pytest.raises(kn.ModelError, match=r"has no port or parameter 'frame_b' "
                                            r"\(did you mean 'frame_a'\?\)"):
        body.frame_b
    with pytest.raises(kn.ModelError, match=r"has no port 'fram_a' \(did you mean"):
        body.port_ref("fram_a")
    # Python's own questions get Python's answers: hasattr and getattr with a default do not
    # raise (a Spherical joint has no speed_units; asking built nothing before)
    joint = kn.multibody.Spherical("j")
    assert not hasattr(joint, "speed_units") and getattr(joint, "frame_b2", None) is None


def test_bound_gives_a_copy_reading_other_values():
    body = kn.multibody.RigidBody("b", mass="m")
    twin = body.bound({"mass": 3.0, "r_cm": [1, 2, 3], "inertia": [[0] * 3] * 3})
    assert twin.mass == 3.0 and twin.r_cm == [1, 2, 3]
    assert body.mass == "m" and body.given == {"mass": "m"}
