"""Diagnostics are data: every ModelError and warning carries Problem records whose fields say
where the problem is (component, port, parameter, JSON path), beside the text for people.

The text is what it always was (other tests match on it); here the fields are checked, for
models built in Python and read from files, and the studio's code is checked to read fields
rather than parse messages.
"""

import ast
import json
import pathlib
import pickle
import warnings

import pytest

import kinetwork as kn
from kinetwork.errors import FIELDS, Problem
from scenes import double_pendulum

mb, rot = kn.multibody, kn.rotational
SEED = pathlib.Path(__file__).resolve().parents[2] / "models" / "double_pendulum.json"


def refused(action):
    with pytest.raises(kn.ModelError) as info:
        action()
    problems = info.value.problems
    assert all(isinstance(p, Problem) for p in problems)
    return problems


def only(problems, text="", **fields):
    """The one problem saying ``text`` whose fields are ``fields`` (others may be there)."""
    found = [p for p in problems if text in p
             and all(getattr(p, k) == v for k, v in fields.items())]
    assert len(found) == 1, [p.to_dict() for p in problems]
    return found[0]


def seed_data():
    return json.loads(SEED.read_text())


def test_a_problem_is_its_message_with_fields():
    p = Problem("mass1.mass = -1 kg: must be >= 0", component="mass1", parameter="mass")
    assert str(p) == p.message == "mass1.mass = -1 kg: must be >= 0"
    assert p.startswith("mass1.mass") and "must be" in p      # a string, as before
    assert p.to_dict() == {"message": p.message, "component": "mass1", "port": None,
                           "parameter": "mass", "path": None, "hint": None,
                           "severity": "error"}
    assert list(p.to_dict())[1:] == list(FIELDS)
    moved = p.where("m.json: ", path="components[2].params.mass", component="other")
    assert moved.message == "m.json: " + p.message
    assert (moved.component, moved.path) == ("mass1", "components[2].params.mass")
    err = kn.ModelError([p, "plain text"])
    again = pickle.loads(pickle.dumps(err))                 # across process pools, whole
    assert [q.to_dict() for q in again.problems] == [q.to_dict() for q in err.problems]
    assert str(again) == str(err) and json.loads(json.dumps(err.problems)) == err.problems
    with pytest.raises(ValueError, match="severity"):
        Problem("x", severity="fatal")


@pytest.mark.parametrize("make, fields", [
    (lambda: mb.RigidBody("mass1", mass=-1.0),
     {"component": "mass1", "parameter": "mass", "path": None}),
    (lambda: rot.SpringDamper("s", c=1.0, d=1.0, phi_rel=0.2),
     {"component": "s", "parameter": "phi_rel", "hint": "did you mean 'phi_rel0'?"}),
    (lambda: mb.Revolute("j", n=[0, 0, 1], axis=[0, 0, 1]),
     {"component": "j", "parameter": "axis"}),
    (lambda: mb.Revolute("j", q0="sin(t)"), {"component": "j", "parameter": "q0"}),
    (lambda: setattr(mb.RigidBody("b", mass=1.0), "mass", "2 m"),
     {"component": "b", "parameter": "mass"}),
])
def test_a_component_refusal_names_component_and_parameter(make, fields):
    problem = refused(make)[0]
    assert {k: getattr(problem, k) for k in fields} == fields


def test_python_wiring_problems_name_component_and_port():
    model = double_pendulum()
    p = refused(lambda: model.connect("shoulder.axs", "spring.flange_a"))[0]
    assert (p.component, p.port, p.hint) == ("shoulder", "axs", "did you mean 'axis'?")
    p = refused(lambda: model.connect("shoulderr.axis", "spring.flange_a"))[0]
    assert p.hint == "did you mean 'shoulder'?"
    model.add(mb.RigidBody("loose", mass=1.0))
    p = only(refused(model.validate), "(frame) is not connected", component="loose")
    assert (p.port, p.path) == ("frame_a", None)
    assert p == "loose: port loose.frame_a (frame) is not connected"   # the text as before


def test_validation_problems_of_a_file_carry_its_json_paths(tmp_path):
    data = seed_data()
    names = [c["name"] for c in data["components"]]
    mass1 = names.index("mass1")
    data["components"][mass1]["params"]["mass"] = "-m1"         # a bound, at validation
    data["components"].append({"name": "loose", "type": "multibody.RigidBody",
                               "params": {"mass": 1.0}})
    path = tmp_path / "m.json"
    path.write_text(json.dumps(data))
    problems = refused(lambda: kn.load(path))
    p = only(problems, component="mass1")
    assert (p.parameter, p.path) == ("mass", f"components[{mass1}].params.mass")
    assert p.startswith(f"{path}: components[{mass1}] \"mass1\" params.mass")
    p = only(problems, "(frame) is not connected", component="loose")
    assert (p.port, p.path) == ("frame_a", f"components[{len(names)}]")


@pytest.mark.parametrize("spoil, fields", [
    (lambda d: d["components"][4]["params"].update(mass=-1),
     {"component": "mass1", "parameter": "mass", "path": "components[4].params.mass"}),
    (lambda d: d["components"][1]["params"].update(axs=[0, 0, 1]),
     {"component": "shoulder", "parameter": "axs", "path": "components[1].params.axs",
      "hint": "did you mean 'axis'?"}),
    (lambda d: d["components"][1].update(type="multibody.Revolut"),
     {"component": "shoulder", "path": "components[1]",
      "hint": "did you mean 'multibody.Revolute'?"}),
    (lambda d: d["connections"].__setitem__(2, ["ground.frame", "spring.flange_a"]),
     {"component": None, "port": None, "path": "connections[2]"}),
    (lambda d: d["connections"].__setitem__(2, ["ground.frame", "mass1.nope"]),
     {"component": None, "path": "connections[2][1]"}),
    (lambda d: d["parameters"].update(L1="2 kg"),
     {"component": None, "parameter": "L1", "path": "parameters.L1"}),
    (lambda d: d["simulation"].update(rtol=-1),
     {"path": "simulation.rtol"}),
    (lambda d: d.update(formt=1), {"path": "formt", "hint": "did you mean 'format'?"}),
    (lambda d: d["components"].append(dict(d["components"][0])),
     {"component": "ground", "path": "components[9]"}),
])
def test_a_file_refusal_carries_its_path(spoil, fields):
    data = seed_data()
    assert [c["name"] for c in data["components"]][1:5] == ["shoulder", "elbow", "link1",
                                                              "mass1"]
    spoil(data)
    problems = refused(lambda: kn.loads(json.dumps(data)))
    assert any({k: getattr(p, k) for k in fields} == fields for p in problems), \
        [p.to_dict() for p in problems]


def test_problems_inside_a_subsystem_point_at_its_block_and_its_definition():
    inline = seed_data()
    link = {"parameters": {"m": 1.0}, "ports": {"frame_a": "j.frame_a"},
            "components": [{"name": "j", "type": "multibody.Revolute"},
                           {"name": "b", "type": "multibody.RigidBody",
                            "params": {"mass": "m", "r_cm": [0, -1, 0]}}],
            "connections": [["j.frame_b", "b.frame_a"]]}
    data = {"format": "kinetwork.model", "version": 2, "name": "arm",
            "definitions": {"Link": link},
            "components": [{"name": "ground", "type": "multibody.Ground"},
                           {"name": "up", "type": "Link", "params": {"m": -2.0}}],
            "connections": [["ground.frame", "up.frame_a"]]}
    problems = refused(lambda: kn.loads(json.dumps(data)))
    p = only(problems, component="up.b")
    assert (p.parameter, p.path) == ("mass", "components[1]")     # the block placed
    broken = json.loads(json.dumps(data))
    broken["definitions"]["Link"]["components"][1]["params"]["mas"] = 1.0
    p = only(refused(lambda: kn.loads(json.dumps(broken))), parameter="mas")
    assert p.path == "definitions.Link.components[1].params.mas"
    assert inline                                                  # the seed untouched


def test_a_warning_carries_its_problem():
    model = double_pendulum()
    model.components["mass1"].inertia = [1.0, 0.1, 0.1]            # no rigid body has it
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        topology = model.validate()
    warned = [w.message for w in caught if isinstance(w.message, kn.IdealisedInertiaWarning)]
    assert len(warned) == 1 and isinstance(warned[0], kn.KinetworkWarning)
    problem = warned[0].problem
    assert (problem.component, problem.parameter, problem.severity) == \
        ("mass1", "inertia", "warning")
    assert str(warned[0]) == problem.message and "triangle inequality" in problem
    assert topology.warnings == [problem]                          # kept as data too


def test_the_studio_reads_fields_and_holds_no_regular_expression_over_messages():
    studio = pathlib.Path(kn.__file__).parent / "studio"
    # files.py splits paths the page sends with ``re``; none of these reads a message
    for path in [studio / "checks.py", studio / "server.py", studio / "runs.py"]:
        tree = ast.parse(path.read_text())
        imported = {a.name for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))
                    for a in n.names} | {n.module for n in ast.walk(tree)
                                         if isinstance(n, ast.ImportFrom)}
        assert "re" not in imported, f"{path.name} imports re"
    from kinetwork.studio.checks import problem
    out = problem(Problem("x", component="mass1", parameter="mass",
                          path="components[3].params.mass"))
    assert out == {"message": "x", "component": "mass1", "port": None, "parameter": "mass",
                   "path": "components[3].params.mass", "hint": None, "severity": "error",
                   "param": "mass", "connection": None, "reason": None}
    # the reason is the text after the place the fields name, in the page's words
    placed = problem(Problem('components[3] "mass1" params.mass = -1 kg: must be >= 0',
                             component="mass1", parameter="mass",
                             path="components[3].params.mass"))
    assert placed["reason"] == "must be >= 0 (got -1 kg)"
    assert problem(Problem("y", path="connections[12][1]"))["connection"] == 12
    # a message shaped like a place, with no fields, is not read for one
    assert problem('components[3] "mass1" params.mass: x')["component"] is None
