"""JSON model files: exact round trip, atomic save, and every refusal naming its place."""

import json
import os
import pathlib

import pytest

import kinetwork as kn
from kinetwork.graph import io

QUANTITIES = ["angle", "speed", "acceleration", "torque"]


def pendulum():
    """The seed's double pendulum through the API, with every part of the file format used."""
    model = kn.Model("double_pendulum", description="Seed paper: 2-DOF arm, shoulder spring",
                     parameters={"L1": 1.0, "L2": 1.0, "m1": 1.0, "m2": 1, "c": 1.0, "d": 1.0,
                                 "g": 9.8})
    mb = kn.multibody
    ground = model.add(mb.Ground("ground", gravity=[0, "-g", 0]))
    shoulder = model.add(mb.Revolute("shoulder", axis=[0, 0, 1], q0=0.05, qd0=0.0))
    link1 = model.add(mb.FixedTranslation("link1", r=[0, "-L1", 0]))
    elbow = model.add(mb.Revolute("elbow", axis=[0, 0, 1], q0=-0.1))
    mass1 = model.add(mb.RigidBody("mass1", mass="m1", r_cm=[0, "-L1/2", 0],
                                   inertia=[[0.01, 0, 0], [0, 0.01, 0], [0, 0, 1e-3]]))
    mass2 = model.add(mb.RigidBody("mass2", mass="m2", r_cm=[0, "-L2/2", 0]))
    spring = model.add(kn.rotational.SpringDamper("spring", c="c", d="d"))
    probe1 = model.add(kn.Probe("probe1", quantities=QUANTITIES))
    probe2 = model.add(kn.Probe("probe2"))
    model.connect(ground.frame, shoulder.frame_a)
    model.connect(shoulder.frame_b, mass1.frame_a)
    model.connect("shoulder.frame_b", "link1.frame_a")
    model.connect(link1.frame_b, elbow.frame_a)
    model.connect(elbow.frame_b, mass2.frame_a)
    model.connect(spring.flange_a, shoulder.support)
    model.connect(spring.flange_b, shoulder.axis)      # attribute ``axis`` is the flange port
    model.connect(probe1.port, shoulder.axis)
    model.connect(probe2.port, elbow.axis)
    model.simulation = {"t_end": 10.0, "n_points": 1001, "method": "cvodes", "rtol": 1e-8,
                        "atol": 1e-10}
    model.layout = {"ground": {"x": 0, "y": 0}, "shoulder": {"x": 120.5, "y": -40, "flip": True}}
    return model


@pytest.fixture
def saved(tmp_path):
    path = tmp_path / "pendulum.json"
    pendulum().save(path)
    return path


# -- round trip -------------------------------------------------------------------------------
def test_round_trip_is_byte_for_byte(saved, tmp_path):
    again = tmp_path / "again.json"
    kn.load(saved).save(again)
    assert again.read_bytes() == saved.read_bytes()


def test_load_save_load_gives_equal_dicts(saved):
    first = io.model_to_dict(kn.load(saved))
    second = io.model_to_dict(io.loads(io.dumps(kn.load(saved))))
    assert first == second == io.model_to_dict(pendulum())


def test_loaded_model_is_the_built_one(saved):
    model = kn.load(saved)
    assert list(model.components) == list(pendulum().components)
    assert model.components["shoulder"].given == {"n": [0, 0, 1], "q0": 0.05, "qd0": 0.0}
    assert model.components["shoulder"].written_params()["axis"] == [0, 0, 1]   # as written
    assert model.layout["shoulder"] == {"x": 120.5, "y": -40, "flip": True}
    assert model.simulation["rtol"] == 1e-8 and isinstance(model.simulation["n_points"], int)
    assert model.places["mass1"] == 'components[4] "mass1"'
    assert model.validate().dof == 2


def test_file_is_canonical_and_readable(saved):
    text = saved.read_text()
    data = json.loads(text)
    assert list(data) == [k for k in io.KEYS if k != "initial"]   # initial: when asked
    assert text.endswith("}\n") and "\n\n" not in text
    assert '"gravity": [0, "-g", 0]' in text                   # vectors on one line
    assert '"quantities": ["angle", "speed", "acceleration", "torque"]' in text
    assert '\n          [0, 0.01, 0],\n' in text                  # a matrix, row by row
    assert '\n    ["spring.flange_b", "shoulder.axis"],\n' in text   # a pair per line
    assert '"params": {}' in text                              # probe2 gave nothing
    assert '"m2": 1,' in text and '"rtol": 1e-08' in text      # ints stay ints
    assert "phi_rel0" not in text                              # defaults are not written


def test_design_example_reads():
    # the (incomplete) example of DESIGN.md, as written there
    text = """{
      "format": "kinetwork.model", "version": 1,
      "name": "double_pendulum",
      "description": "free text",
      "parameters": {"L1": 1.0, "c": 1.0, "d": 1.0},
      "components": [
        {"name": "ground",   "type": "multibody.Ground",   "params": {"gravity": [0, -9.8, 0]}},
        {"name": "shoulder", "type": "multibody.Revolute", "params": {"axis": [0, 0, 1], "q0": 0.05}},
        {"name": "link1", "type": "multibody.FixedTranslation", "params": {"r": [0, "-L1", 0]}},
        {"name": "spring",   "type": "rotational.SpringDamper", "params": {"c": "c", "d": "d"}},
        {"name": "probe1",   "type": "Probe", "params": {"quantities": ["angle", "torque"]}}
      ],
      "connections": [["ground.frame", "shoulder.frame_a"], ["spring.flange_b", "shoulder.axis"]],
      "simulation": {"t_end": 10.0, "n_points": 1001, "method": "cvodes", "rtol": 1e-8, "atol": 1e-10},
      "layout": {"ground": {"x": 0, "y": 0}}
    }"""
    model = io.loads(text, validate=False)
    assert model.components["link1"].given["r"] == [0, "-L1", 0]
    assert io.loads(io.dumps(model), validate=False).layout == {"ground": {"x": 0, "y": 0}}
    with pytest.raises(kn.ModelError, match=r'components\[3\] "spring": port spring.flange_a'):
        io.loads(text)                       # the example leaves ports unwired


def test_optional_keys_may_be_left_out():
    text = json.dumps({"format": "kinetwork.model", "version": 1, "name": "lonely",
                       "components": [{"name": "ground", "type": "multibody.Ground"}]})
    model = io.loads(text, validate=False)
    assert (model.description, model.parameters, model.connections) == ("", {}, [])
    assert (model.simulation, model.layout) == ({}, {})
    assert io.dumps(io.loads(io.dumps(model), validate=False)) == io.dumps(model)


def test_incomplete_model_saves_and_reads_back_unvalidated(tmp_path):
    model = kn.Model("draft")
    model.add(kn.multibody.RigidBody("body", mass=2.0))
    path = tmp_path / "draft.json"
    model.save(path)
    with pytest.raises(kn.ModelError, match="draft.json.*Ground"):
        kn.load(path)
    assert io.dumps(kn.load(path, validate=False)) == path.read_text()


# -- refusals ---------------------------------------------------------------------------------
def edit(change):
    """A case that edits the saved file's JSON object with ``change(data)``."""
    def apply(text):
        data = json.loads(text)
        change(data)
        return json.dumps(data, indent=1)
    return apply


def comp(data, name):
    return next(c for c in data["components"] if c["name"] == name)


def drop(key):
    return lambda d: d.pop(key)


def put(key, value):
    return lambda d: d.__setitem__(key, value)


def param(name, key, value):
    return lambda d: comp(d, name)["params"].__setitem__(key, value)


TEXT_CASES = {
    # the text itself
    "truncated": (lambda t: t[:len(t) // 2], ["line ", "truncated"]),
    "not json": (lambda t: "{'format': 1}", ["line 1 column 2", "invalid JSON"]),
    "empty": (lambda t: "", ["line 1 column 1", "truncated"]),
    "too deep": (lambda t: "[" * 100000, ["invalid JSON"]),
    "top level list": (lambda t: f"[{t}]", ["top level: must be an object"]),
    "repeated key": (lambda t: t.replace('"mass": "m1",', '"mass": "m1", "mass": 2,'),
                     ["components[4].params: key 'mass' appears more than once"]),
    "NaN parameter": (lambda t: t.replace('"c": 1.0', '"c": NaN'),
                      ["parameters.c: must be finite"]),
    "NaN in params": (lambda t: t.replace('"q0": 0.05', '"q0": NaN'),
                      ['components[1] "shoulder" params.q0: must be finite']),
    "Infinity in vector": (lambda t: t.replace('"axis": [0, 0, 1]', '"axis": [0, 0, -Infinity]'),
                           ['components[1] "shoulder" params.axis[2]: must be finite']),
    "overflowing float": (lambda t: t.replace('"q0": -0.1', '"q0": 1e400'),
                          ['components[3] "elbow" params.q0: must be finite']),
    "overflowing int": (lambda t: t.replace('"q0": -0.1', '"q0": ' + "9" * 400),
                        ['components[3] "elbow" params.q0: must be finite']),
    "huge int parameter": (lambda t: t.replace('"m2": 1', '"m2": 1' + "0" * 5000),
                           ["parameters.m2: must be finite"]),
    "NaN in layout": (lambda t: t.replace('"y": -40', '"y": NaN'),
                      ["layout.shoulder.y: must be finite"]),
    "NaN in simulation": (lambda t: t.replace('"t_end": 10.0', '"t_end": NaN'),
                          ["simulation.t_end: must be a finite number > 0, got nan"]),
}
DATA_CASES = {
    # the top level
    "wrong format": (put("format", "bdsim"), ["format: 'bdsim' is not a kinetwork model"]),
    "newer version": (put("version", 3), ["version: 3 is not supported", "version 1, 2"]),
    "version as text": (put("version", "1"), ["version: '1' is not supported"]),
    "version as bool": (put("version", True), ["version: True is not supported"]),
    "missing format": (drop("format"), ["format: required key missing"]),
    "missing name": (drop("name"), ["name: required key missing"]),
    "missing components": (drop("components"), ["components: required key missing"]),
    "unknown key": (put("componets", []), ["'componets': unknown key (did you mean "
                                           "'components'?)"]),
    "name not text": (put("name", 5), ["name: must be a non-empty string"]),
    "description not text": (put("description", ["a"]), ["description: must be a string"]),
    "parameters a list": (put("parameters", [1.0]), ["parameters: must be an object"]),
    "parameter as text": (lambda d: d["parameters"].__setitem__("c", "1.0"),
                          ["parameters.c: must be a number"]),
    "parameter reserved": (lambda d: d["parameters"].__setitem__("pi", 3.0),
                           ["parameters: parameter name 'pi' is reserved"]),
    # components
    "components an object": (put("components", {}), ["components: must be a list"]),
    "entry not object": (lambda d: d["components"].__setitem__(1, "shoulder"),
                         ["components[1]: must be an object"]),
    "entry unknown key": (lambda d: comp(d, "link1").__setitem__("prams", {}),
                          ['components[2] "link1": unknown key \'prams\' (did you mean '
                           "'params'?)"]),
    "entry without type": (lambda d: comp(d, "link1").pop("type"),
                           ['components[2] "link1": required key \'type\' missing']),
    "entry without name": (lambda d: d["components"][2].pop("name"),
                           ["components[2]: required key 'name' missing"]),
    "unknown type": (lambda d: comp(d, "elbow").__setitem__("type", "multibody.Revolut"),
                     ['components[3] "elbow": unknown type', "did you mean 'multibody.Revolute'"]),
    "type of another library": (lambda d: comp(d, "elbow").__setitem__("type",
                                                                        "rotational.Mass"),
                                ["did you mean 'translational.Mass'"]),
    "type by another tool's name": (lambda d: comp(d, "elbow").__setitem__("type",
                                                                           "multibody.World"),
                                    ["did you mean 'multibody.Ground'"]),
    "dotted path as type": (lambda d: comp(d, "elbow").__setitem__("type", "os.system"),
                            ['components[3] "elbow": unknown type \'os.system\'']),
    "duplicate name": (lambda d: comp(d, "mass2").__setitem__("name", "mass1"),
                       ['components[5] "mass1": duplicate name, already used by components[4]']),
    "bad name": (lambda d: comp(d, "mass2").__setitem__("name", "2nd"),
                 ['components[5] "2nd": RigidBody name \'2nd\': must be an identifier']),
    "params a list": (lambda d: comp(d, "link1").__setitem__("params", [0, 1]),
                      ['components[2] "link1" params: must be an object']),
    "unknown param": (param("mass1", "mas", 1.0),
                      ['components[4] "mass1" params.mas: unknown parameter (did you mean '
                       "'mass'?)"]),
    "param called name": (param("mass1", "name", "x"),
                          ['components[4] "mass1" params.name: unknown parameter']),
    "negative mass": (param("mass1", "mass", -1),
                      ['components[4] "mass1" params.mass = -1 kg: must be >= 0.0']),
    "missing required": (lambda d: comp(d, "link1")["params"].pop("r"),
                         ['components[2] "link1" params.r: a value is required']),
    "short vector": (param("link1", "r", [0, 1]),
                     ['components[2] "link1" params.r: must have 3 entries']),
    "bool in vector": (param("ground", "gravity", [0, True, 0]),
                       ['components[0] "ground" params.gravity[1]: must be a number']),
    "zero axis": (param("elbow", "axis", [0, 0, 0]),
                  ['components[3] "elbow" params.axis: must not be the zero vector']),
    "smuggled code": (param("mass1", "mass", "__import__('os').system('x')"),
                      ['components[4] "mass1" params.mass: expression', "is not allowed"]),
    "smuggled in vector": (param("link1", "r", [0, "().__class__", 0]),
                           ['components[2] "link1" params.r[1]: expression', "not allowed"]),
    "expression too deep": (param("spring", "c", "-" * 1900 + "1"),
                            ['components[6] "spring" params.c: expression nested too deeply']),
    "expression syntax": (param("spring", "c", "c +"),
                          ['components[6] "spring" params.c: cannot parse expression']),
    "time in constant": (param("spring", "d", "sin(t)"),
                         ['components[6] "spring" params.d: time \'t\' is not allowed']),
    "unknown name in expression": (param("link1", "r", [0, "-L11", 0]),
                                   ['components[2] "link1" params.r[1] = \'-L11\': unknown name',
                                    "did you mean 'L1'"]),
    "bad probe quantity": (param("probe1", "quantities", ["angel"]),
                           ['components[7] "probe1" params.quantities: unknown \'angel\'']),
    # connections
    "connections an object": (put("connections", {}), ["connections: must be a list of pairs"]),
    "connection of three": (lambda d: d["connections"][0].append("mass1.frame_a"),
                            ["connections[0]: must be a pair"]),
    "connection not text": (lambda d: d["connections"][1].__setitem__(1, 7),
                            ["connections[1][1]: must be a string 'component.port', got 7"]),
    "unknown component": (lambda d: d["connections"][1].__setitem__(1, "mss1.frame_a"),
                          ['connections[1][1] "mss1.frame_a": no component \'mss1\' (did you '
                           "mean 'mass1'?)"]),
    "unknown port": (lambda d: d["connections"][1].__setitem__(1, "mass1.frame_x"),
                     ['connections[1][1] "mass1.frame_x": RigidBody \'mass1\' has no port',
                      "did you mean 'frame_a'"]),
    "cross domain": (lambda d: d["connections"][1].__setitem__(1, "spring.flange_a"),
                     ["connections[1]: cannot connect", "different domains"]),
    "port to itself": (lambda d: d["connections"].append(["mass1.frame_a", "mass1.frame_a"]),
                       ["connections[9]: cannot connect mass1.frame_a to itself"]),
    "connected twice": (lambda d: d["connections"].append(["shoulder.frame_a", "ground.frame"]),
                        ["connections[9]: shoulder.frame_a and ground.frame are already"]),
    "unconnected port": (lambda d: d["connections"].pop(4),
                         ['components[5] "mass2": port mass2.frame_a (frame) is not connected']),
    "two grounds": (lambda d: d["components"].append(
        {"name": "ground2", "type": "multibody.Ground"}), ["exactly one multibody.Ground"]),
    # simulation and layout
    "simulation a list": (put("simulation", [10.0]), ["simulation: must be an object"]),
    "unknown setting": (lambda d: d["simulation"].__setitem__("tend", 5.0),
                        ["simulation.tend: unknown setting (did you mean 't_end'?)"]),
    "fractional n_points": (lambda d: d["simulation"].__setitem__("n_points", 10.5),
                            ["simulation.n_points: must be an integer >= 2"]),
    "one point": (lambda d: d["simulation"].__setitem__("n_points", 1),
                  ["simulation.n_points: must be an integer >= 2"]),
    "method a number": (lambda d: d["simulation"].__setitem__("method", 4),
                        ["simulation.method: must be a method name"]),
    "negative tolerance": (lambda d: d["simulation"].__setitem__("rtol", -1e-6),
                           ["simulation.rtol: must be a finite number > 0"]),
    "layout a list": (put("layout", []), ["layout: must be an object"]),
    "layout of nothing": (lambda d: d["layout"].__setitem__("shoulderr", {}),
                          ["layout.shoulderr: no component 'shoulderr' (did you mean "
                           "'shoulder'?)"]),
}
CASES = {**TEXT_CASES, **{key: (edit(change), expected)
                          for key, (change, expected) in DATA_CASES.items()}}


@pytest.mark.parametrize("change, expected", CASES.values(), ids=CASES.keys())
def test_malformed_file_refused_with_its_place(saved, change, expected):
    saved.write_text(change(saved.read_text()))
    with pytest.raises(kn.ModelError) as err:
        kn.load(saved)
    message = str(err.value)
    for part in expected:
        assert part in message
    assert all(p.startswith(f"{saved}: ") for p in err.value.problems)


def test_every_problem_reported_at_once(saved):
    data = json.loads(saved.read_text())
    comp(data, "mass1")["params"]["mass"] = -1
    comp(data, "link1")["params"]["r"] = [0, 1]
    data["connections"][0][1] = "shoulder.frame_x"
    data["simulation"]["n_points"] = 0
    saved.write_text(json.dumps(data))
    with pytest.raises(kn.ModelError) as err:
        kn.load(saved)
    assert len(err.value.problems) == 4
    places = ['components[2] "link1"', 'components[4] "mass1"', "connections[0][1]",
              "simulation.n_points"]
    for place, problem in zip(places, err.value.problems):
        assert place in problem


@pytest.mark.parametrize("case", ["negative mass", "unknown type", "entry not object",
                                  "entry without name", "components an object",
                                  "missing components", "smuggled code"])
def test_refused_component_is_reported_once(saved, case):
    # not again by every wire or layout entry that names it
    saved.write_text(CASES[case][0](saved.read_text()))
    with pytest.raises(kn.ModelError) as err:
        kn.load(saved)
    assert len(err.value.problems) == 1


def test_missing_and_undecodable_files(tmp_path):
    with pytest.raises(kn.ModelError, match="nowhere.json: cannot read the file"):
        kn.load(tmp_path / "nowhere.json")
    binary = tmp_path / "binary.json"
    binary.write_bytes(b"\xff\xfe{}")
    with pytest.raises(kn.ModelError, match="binary.json: not UTF-8"):
        kn.load(binary)


def test_odd_shapes_from_python_are_refused_not_crashed():
    data = io.model_to_dict(pendulum())
    data["components"][1]["params"]["q0"] = object()
    data["layout"]["ground"] = {"x": 10 ** 400}
    data["parameters"]["c"] = 10 ** 400
    with pytest.raises(kn.ModelError) as err:
        io.model_from_dict(data, source="mem")
    assert len(err.value.problems) == 3
    assert all(p.startswith("mem: ") for p in err.value.problems)


# -- saving -----------------------------------------------------------------------------------
def files(folder):
    return sorted(p.name for p in folder.iterdir())


@pytest.mark.parametrize("target", ["replace", "fsync"])
def test_failed_save_leaves_old_file_whole(saved, monkeypatch, target):
    old = saved.read_bytes()
    model = kn.load(saved)
    model.description = "changed"

    def fail(*args):
        raise OSError("disk full")
    monkeypatch.setattr(io.os, target, fail)
    with pytest.raises(OSError, match="disk full"):
        model.save(saved)
    monkeypatch.undo()
    assert saved.read_bytes() == old
    assert files(saved.parent) == ["pendulum.json"]
    assert kn.load(saved).description == pendulum().description


@pytest.mark.parametrize("spoil, place", [
    (lambda m: m.layout.__setitem__("ground", {"x": object()}), "layout.ground.x: object"),
    (lambda m: m.layout.__setitem__("ground", {"x": float("nan")}), "layout.ground.x: must be"),
    (lambda m: m.layout.__setitem__("ghost", {}), "layout.ghost: no component"),
    (lambda m: m.simulation.__setitem__("n_points", 2.5), "simulation.n_points"),
    (lambda m: setattr(m, "description", 3), "description: must be a string"),
])
def test_unwritable_model_refused_before_touching_the_file(saved, spoil, place):
    old = saved.read_bytes()
    model = kn.load(saved)
    spoil(model)
    with pytest.raises(kn.ModelError, match=place):
        model.save(saved)
    assert saved.read_bytes() == old
    assert files(saved.parent) == ["pendulum.json"]


def test_unregistered_component_type_refused():
    class Local(kn.multibody.RigidBody):
        pass
    model = kn.Model("m")
    model.add(Local("body", mass=1.0))
    with pytest.raises(kn.ModelError, match=r'components\[0\] "body": type Local is not'):
        io.dumps(model)


def test_new_file_gets_ordinary_permissions(tmp_path):
    umask = os.umask(0)
    os.umask(umask)
    path = tmp_path / "new.json"
    pendulum().save(str(path))
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_save_through_a_symlink_keeps_the_link(saved, tmp_path):
    link = tmp_path / "link.json"
    link.symlink_to(saved)
    model = kn.load(link)
    model.description = "through the link"
    model.save(link)
    assert link.is_symlink() and kn.load(saved).description == "through the link"


def test_killing_a_save_halfway_leaves_the_old_file_whole(tmp_path):
    """A child process saves a large model over and over onto the same file and is killed
    with SIGKILL mid-way, several times: the file always loads, whole, as one of the two."""
    import signal
    import subprocess
    import sys
    import time

    from scenes import chain
    path = tmp_path / "model.json"
    small = chain(2)
    small.save(path)
    script = (
        "import sys; sys.path.insert(0, %r)\n"
        "from scenes import chain\n"
        "m = chain(400)\n"
        "print('ready', flush=True)\n"
        "while True:\n"
        "    m.save(%r)\n") % (str(pathlib.Path(__file__).resolve().parents[1]),
                            str(path))
    names = set()
    for delay in (0.05, 0.13, 0.21, 0.34):
        child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                                 text=True)
        assert child.stdout.readline().strip() == "ready"
        time.sleep(delay)
        child.send_signal(signal.SIGKILL)
        child.wait()
        child.stdout.close()
        model = kn.load(path)                    # whole: it parses and validates
        names.add(len(model.components))
    assert names <= {len(small.components), 1201}


@pytest.mark.parametrize("written, meant", [
    ("multibody.World", "multibody.Ground"), ("rotational.Mass", "translational.Mass"),
    ("translational.Inertia", "rotational.Inertia"), ("multibody.Revolut", "multibody.Revolute"),
    ("electrical.Capacitance", "electrical.Capacitor"), ("multibody.Body", "multibody.RigidBody")])
def test_a_component_looked_up_by_another_name_says_which_it_may_be(written, meant):
    library, name = written.split(".")
    with pytest.raises(AttributeError, match=f"did you mean '{meant}'"):
        getattr(getattr(kn, library), name)
    assert getattr(getattr(kn, meant.split(".")[0]), meant.split(".")[1])     # it exists


def test_what_validate_returns_prints_short():
    # at a prompt, model.validate() echoes its result: a line, not the connection sets
    shown = repr(kn.load("models/fourbar.json").validate())
    assert shown == "<Topology: 4 joints, 3 bodies, 1 kinematic loop, 4 probes>"
