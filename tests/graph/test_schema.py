"""The published JSON Schema: valid, generated from the declarations, and in step with the
loader (every example model passes it; files the loader refuses for their shape fail it)."""

import copy
import json
import pathlib

import jsonschema
import pytest

import kinetwork as kn
from kinetwork.components.base import REGISTRY

MODELS = sorted((pathlib.Path(__file__).resolve().parents[2] / "models").glob("**/*.json"))


@pytest.fixture(scope="module")
def validator():
    schema = kn.schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def test_every_component_type_has_its_branch():
    branches = kn.schema()["properties"]["components"]["items"]["oneOf"]
    assert branches[-1]["title"] == "subsystem"         # and one for placed subsystems
    branches = branches[:-1]
    assert sorted(b["properties"]["type"]["const"] for b in branches) == sorted(REGISTRY)
    revolute = next(b for b in branches if b["title"] == "multibody.Revolute")
    assert set(revolute["properties"]["params"]["properties"]) == \
        set(REGISTRY["multibody.Revolute"].params) | {"axis"}     # n's other name
    body = next(b for b in branches if b["title"] == "multibody.RigidBody")
    assert body["properties"]["params"]["required"] == ["mass"]


@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_example_models_pass(validator, path):
    assert list(validator.iter_errors(json.loads(path.read_text()))) == []


@pytest.mark.parametrize("spoil", [
    lambda d: d["components"][1]["params"].update(colour="red"),      # unknown parameter
    lambda d: d["components"][1].update(type="multibody.Revolver"),    # unknown type
    lambda d: d["components"][4]["params"].pop("mass"),                # required parameter
    lambda d: d["components"][4]["params"].update(mass=-1.0),          # below its minimum
    lambda d: d["components"][1]["params"].update(axis=[0, 1]),        # wrong shape
    lambda d: d.update(extra=1),                                       # unknown top-level key
    lambda d: d["connections"].append(["ground.frame"]),               # half a connection
])
def test_what_the_loader_refuses_for_its_shape_the_schema_refuses_too(validator, spoil):
    data = json.loads((MODELS[0].parent / "double_pendulum.json").read_text())
    broken = copy.deepcopy(data)
    spoil(broken)
    assert list(validator.iter_errors(broken))
    with pytest.raises(kn.ModelError):
        kn.loads(json.dumps(broken))


def test_schema_command_prints_it(capsys):
    from kinetwork.cli import main
    assert main(["schema"]) == 0
    assert json.loads(capsys.readouterr().out) == kn.schema()


def test_an_unknown_method_fails_the_schema_and_the_run(validator):
    data = json.loads((MODELS[0].parent / "double_pendulum.json").read_text())
    data["simulation"] = {"method": "euler"}
    assert list(validator.iter_errors(data))
    with pytest.raises(kn.ModelError, match="method 'euler': unknown"):
        kn.simulate(kn.loads(json.dumps(data)), t_end=0.1)


def test_a_joint_direction_is_n_or_axis_never_both(validator):
    def model(params):
        return {"format": "kinetwork.model", "version": 1, "name": "m",
                "components": [{"name": "j", "type": "multibody.Revolute", "params": params}],
                "connections": []}
    assert not list(validator.iter_errors(model({"n": [0, 0, 1]})))
    assert not list(validator.iter_errors(model({"axis": [0, 0, 1]})))
    assert list(validator.iter_errors(model({"n": [0, 0, 1], "axis": [0, 0, 1]})))
