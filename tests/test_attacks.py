"""Bad input, hostile or careless: every bad value is a ModelError naming its place, quickly,
with a message of bounded length; never a traceback, a hang or a process eating memory.

Expressions with the wrong number of arguments, names that are not whole identifiers, files
that never end, tables too large to compile, settings whose cost has no bound; and the
defaults that must simply work: every signal block with only its required parameters, a PID
without derivative part, a line spring-damper of zero length.
"""

import json
import math
import subprocess
import time

import numpy as np
import pytest
from conftest import double_pendulum

import kinetwork as kn
from kinetwork.components.base import NAME_LIMIT, REGISTRY, TABLE_ROWS_LIMIT
from kinetwork.graph.io import MAX_FILE_SIZE
from kinetwork.graph.settings import MAX_POINTS, MAX_STEPS

#: no message, whatever the input, is longer than this
MESSAGE_LIMIT = 2000


def seed_data():
    return json.loads(kn.dumps(double_pendulum()))


def refused(make, *parts, bounded=True):
    """The ModelError ``make()`` raises, checked to contain ``parts`` and to be short."""
    with pytest.raises(kn.ModelError) as err:
        make()
    message = str(err.value)
    for part in parts:
        assert part in message, message[:300]
    assert not bounded or len(message) < MESSAGE_LIMIT, message[:300]
    return message


# -- expressions ----------------------------------------------------------------------------
@pytest.mark.parametrize("text, function, takes, got", [
    ("max(1,2,3)", "max", "2 arguments", 3), ("min(L)", "min", "2 arguments", 1),
    ("sin(1,2)", "sin", "1 argument", 2), ("atan2(1)", "atan2", "2 arguments", 1),
    ("sqrt()", "sqrt", "1 argument", 0), ("1 + abs(L, L)", "abs", "1 argument", 2),
])
def test_a_function_with_the_wrong_number_of_arguments_is_refused_when_parsed(
        text, function, takes, got):
    # at construction, before any model parameter is known, naming the place
    refused(lambda: kn.multibody.RigidBody("body", mass=text),
            f"body.mass: expression {text!r}: {function}() takes {takes}, got {got}")


def test_functions_with_their_number_of_arguments_still_evaluate():
    m = kn.Model("m", parameters={"L": 2.0})
    m.add(kn.multibody.Ground("ground"))
    m.add(kn.multibody.RigidBody("body", mass="max(L, 1) + min(L, 3) + atan2(0, 1)"))
    m.connect("ground.frame", "body.frame_a")
    assert m.numeric_values()["body"]["mass"] == 4.0


# -- names ----------------------------------------------------------------------------------
BAD_NAMES = ["mass1\n", "mass1\r", "ma\x00ss", "mass\x1b[31m", "\ud800", "mass 1", "",
             "1mass", "a" * (NAME_LIMIT + 1)]


@pytest.mark.parametrize("name", BAD_NAMES)
def test_component_names_are_whole_identifiers(name):
    refused(lambda: kn.multibody.RigidBody(name, mass=1.0), "must be an identifier")


@pytest.mark.parametrize("name", BAD_NAMES)
def test_parameter_names_are_whole_identifiers(name):
    refused(lambda: kn.Model("m", parameters={name: 1.0}), "must be an identifier")
    data = seed_data()
    data["parameters"][name] = 1.0
    refused(lambda: kn.loads(json.dumps(data)), "parameters: parameter name",
            "must be an identifier")


@pytest.mark.parametrize("ref", ["ground.frame\n", "ground\n.frame", "ground.fra\x00me",
                                 "ground.\ud800", "x" * 10**6 + ".frame",
                                 "ground." + "y" * 10**6])
def test_port_references_are_whole_names(ref):
    model = double_pendulum()
    # Model.port quotes a reference whole (graph/model.py): bounded in files only, so far
    refused(lambda: model.connect(ref, "shoulder.frame_a"), bounded=False)
    data = seed_data()
    data["connections"][0][0] = ref
    refused(lambda: kn.loads(json.dumps(data)), "connections[0][0]")


@pytest.mark.parametrize("name", ["a\x07b", "two\nlines", "tab\there", "\ud800", "x\u2028y",
                                  "", "n" * 201])
def test_a_model_name_in_a_file_holds_no_control_characters(name):
    data = seed_data()
    data["name"] = name
    refused(lambda: kn.loads(json.dumps(data)), "name: ")


@pytest.mark.parametrize("name", ["Doppelpendel (Maple)", "двойной маятник", "arm #2 ☃",
                                  "spaces  and - dashes"])
def test_a_model_name_may_be_any_printable_text(name):
    data = seed_data()
    data["name"] = name
    assert kn.loads(json.dumps(data)).name == name


def test_a_description_holds_line_breaks_but_no_other_control_characters():
    data = seed_data()
    data["description"] = "two\nlines\tand a tab"
    assert kn.loads(json.dumps(data)).description == "two\nlines\tand a tab"
    for bad in ["escape \x1b[2J", "nul \x00", "surrogate \udc00"]:
        data["description"] = bad
        refused(lambda: kn.loads(json.dumps(data)), "description: ")


@pytest.mark.parametrize("where", ["key", "type", "name", "param", "version", "format",
                                   "layout", "table"])
def test_messages_never_echo_unbounded_input(where):
    huge = "z" * 10**6
    data = seed_data()
    comp = data["components"][3]
    if where == "key":
        data[huge] = 1
    elif where == "type":
        comp["type"] = huge
    elif where == "name":
        comp["name"] = huge
    elif where == "param":
        comp["params"][huge] = 1
    elif where == "version":
        data["version"] = [1] * 10**5
    elif where == "format":
        data["format"] = huge
    elif where == "layout":
        data["layout"] = {huge: {}}
    elif where == "table":
        comp["params"] = {"table": huge}
        comp["type"] = "signals.Table"
    refused(lambda: kn.loads(json.dumps(data)))


# -- files ----------------------------------------------------------------------------------
def test_a_device_without_end_is_refused_by_size_quickly():
    start = time.process_time()
    refused(lambda: kn.load("/dev/zero"), "/dev/zero: larger than 64 MiB")
    assert time.process_time() - start < 30


def test_an_endless_pipe_is_refused_by_size_quickly():
    writer = subprocess.Popen(["yes", "{"], stdout=subprocess.PIPE)
    try:
        start = time.process_time()
        refused(lambda: kn.load(f"/dev/fd/{writer.stdout.fileno()}"), "larger than 64 MiB")
        assert time.process_time() - start < 30
    finally:
        writer.kill()
        writer.wait()
        writer.stdout.close()


def test_a_large_file_is_refused_before_it_is_read(tmp_path):
    big = tmp_path / "big.json"
    with open(big, "wb") as fh:          # sparse: 65 MiB of nothing on disk
        fh.truncate(MAX_FILE_SIZE + 2**20)
    refused(lambda: kn.load(big), f"({MAX_FILE_SIZE + 2**20} bytes)")
    refused(lambda: kn.loads(" " * (MAX_FILE_SIZE + 1)), "more than")


# -- costs ----------------------------------------------------------------------------------
def table_model(rows, t_start=0.0):
    m = kn.Model("table")
    m.add(kn.signals.Table("tab", table=rows))
    m.add(kn.Probe("probe", quantities=["value"]))
    m.connect("probe.port", "tab.y")
    return m


def test_a_table_of_a_million_rows_is_refused_quickly():
    rows = np.column_stack([np.arange(10**6), np.zeros(10**6)]).tolist()
    start = time.process_time()
    refused(lambda: kn.signals.Table("tab", table=rows),
            f"tab.table: 1000000 rows, more than the {TABLE_ROWS_LIMIT}")
    assert time.process_time() - start < 1.0


@pytest.mark.parametrize("n", [3, 100, 101, 2000])
def test_tables_short_and_long_interpolate_and_extrapolate_linearly(n):
    x = np.sort(np.random.default_rng(n).uniform(0, 1, n))
    y = np.sin(7 * x) + x
    res = kn.simulate(table_model(np.column_stack([x, y]).tolist()), t_start=-0.5,
                      t_end=1.5, n_points=401, jit=False)
    t = res.t
    left = y[0] + (t - x[0]) * (y[1] - y[0]) / (x[1] - x[0])
    right = y[-1] + (t - x[-1]) * (y[-1] - y[-2]) / (x[-1] - x[-2])
    expected = np.where(t < x[0], left, np.where(t > x[-1], right, np.interp(t, x, y)))
    np.testing.assert_allclose(res["probe.value"], expected, atol=1e-12)


def test_a_table_at_the_limit_builds_in_linear_time():
    x = np.linspace(0, 1, TABLE_ROWS_LIMIT)
    model = table_model(np.column_stack([x, x**2]).tolist())
    start = time.process_time()
    system = model.compile()
    assert time.process_time() - start < 60      # 340 s with an expression of the rows
    res = kn.simulate(system, t_end=1.0, n_points=11, jit=False)
    np.testing.assert_allclose(res["probe.value"], res.t**2, atol=1e-9)


def test_settings_whose_cost_has_no_bound_are_refused():
    refused(lambda: kn.simulate(double_pendulum(), n_points=MAX_POINTS + 1),
            "simulation.n_points", "GiB")
    refused(lambda: kn.simulate(double_pendulum(), n_points=10**400), "about 1e+400")
    data = seed_data()
    data["simulation"] = {"t_end": 10.0, "step": 1e-300}
    refused(lambda: kn.loads(json.dumps(data)), "simulation.step = 1e-300: 1e+301 steps",
            f"more than the {MAX_STEPS}")
    for key in ("rtol", "atol", "t_end"):
        data["simulation"] = {key: math.nan}
        refused(lambda: kn.loads(json.dumps(data)), f"simulation.{key}: must be a finite")


# -- defaults that work ---------------------------------------------------------------------
SIGNAL_BLOCKS = sorted(name for name in REGISTRY if name.startswith("signals."))


def required_value(spec):
    return {"table": [[0.0, 0.0], [1.0, 2.0]], "name": "joint", "bool": False,
            "names": [], "table2d": [[0.0, 0.0, 1.0], [0.0, 1.0, 2.0], [1.0, 3.0, 4.0]],
            "expression": "2*t"}.get(spec.kind, 1.0)


@pytest.mark.parametrize("type_name", SIGNAL_BLOCKS)
def test_every_signal_block_simulates_with_only_its_required_parameters(type_name):
    cls = REGISTRY[type_name]
    block = cls("block", **{key: required_value(spec) for key, spec in cls.params.items()
                            if spec.required})
    m = kn.Model("defaults")
    m.add(block)
    m.add(kn.signals.Sine("source"))
    m.add(kn.Probe("probe", quantities=["value"]))
    m.connect("probe.port", "block.y")
    for port, spec in cls.ports.items():
        if spec.domain == "signal_in" and not spec.optional:
            m.connect("source.y", f"block.{port}")
    if any(spec.kind == "name" for spec in cls.params.values()):
        # a block of the model's own dynamics: a pendulum for it to know
        m.add(kn.multibody.Ground("ground"))
        m.add(kn.multibody.Revolute("joint", axis=[0, 0, 1], q0=0.3))
        m.add(kn.multibody.RigidBody("body", mass=1.0, r_cm=[0, -0.5, 0]))
        m.connect("ground.frame", "joint.frame_a")
        m.connect("joint.frame_b", "body.frame_a")
    res = kn.simulate(m, t_end=1.0, n_points=51)
    assert np.all(np.isfinite(res["probe.value"])) and np.all(np.isfinite(res.states))


def pid_model(**pid):
    """A PID holding a damped pendulum's angle at 0.2 rad through a torque."""
    m = kn.Model("pid", parameters={"Td": 0.0})
    m.add(kn.multibody.Ground("ground"))
    m.add(kn.multibody.Revolute("joint", axis=[0, 0, 1]))
    m.add(kn.multibody.RigidBody("body", mass=1.0, r_cm=[0, -0.5, 0]))
    m.add(kn.rotational.AngleSensor("angle"))
    m.add(kn.signals.Constant("set", k=0.2))
    m.add(kn.signals.PID("pid", k=20.0, Ti=0.5, **pid))
    m.add(kn.rotational.Torque("motor"))
    m.add(kn.Probe("probe", quantities=["value"]))
    for a, b in [("ground.frame", "joint.frame_a"), ("joint.frame_b", "body.frame_a"),
                 ("angle.flange", "joint.axis"), ("set.y", "pid.u_s"), ("angle.y", "pid.u_m"),
                 ("pid.y", "motor.u"), ("motor.flange", "joint.axis"),
                 ("probe.port", "pid.y")]:
        m.connect(a, b)
    return m


def test_a_pid_without_derivative_time_simulates_whatever_gives_it():
    run = dict(t_end=1.0, n_points=101, rtol=1e-10, atol=1e-12)
    default = kn.simulate(pid_model(), **run)        # Td = 0, the default
    number = kn.simulate(pid_model(Td=0.0), **run)
    symbol = kn.simulate(pid_model(Td="Td"), **run)  # a model parameter, 0
    for res in (default, number, symbol):
        assert np.all(np.isfinite(res.states)) and np.all(np.isfinite(res["probe.value"]))
    np.testing.assert_allclose(number.states, default.states, atol=1e-12)
    np.testing.assert_allclose(symbol.states, default.states, atol=1e-8)
    # Td = 0.1 set per run through the parameter, and given as a number: the D part acts
    with_d = kn.simulate(pid_model(Td="Td"), params={"Td": 0.1}, **run)
    with_d_number = kn.simulate(pid_model(Td=0.1), **run)
    np.testing.assert_allclose(with_d.states, with_d_number.states, atol=1e-8)
    assert np.all(np.isfinite(with_d.states))
    assert np.max(np.abs(with_d.states - default.states)) > 1e-4


def line_scene(r0, v0=(0.0, 0.0, 0.0), s0=0.0, g=0.0):
    """A free body on a line spring-damper to the world origin."""
    m = kn.Model("line")
    mb = kn.multibody
    m.add(mb.Ground("ground", gravity=[0, -g, 0]))
    m.add(mb.FreeMotion("free", r0=list(r0), v0=list(v0)))
    m.add(mb.RigidBody("body", mass=2.0, inertia=[0.1, 0.2, 0.3]))
    m.add(mb.SpringDamper("sd", c=50.0, d=0.5, s_unstretched=s0))
    m.add(kn.Probe("probe", quantities=["force", "position"]))
    for a, b in [("ground.frame", "free.frame_a"), ("free.frame_b", "body.frame_a"),
                 ("ground.frame", "sd.frame_a"), ("free.frame_b", "sd.frame_b"),
                 ("probe.port", "sd.frame_b")]:
        m.connect(a, b)
    return m


@pytest.mark.parametrize("v0, s0", [((0, 0, 0), 0.0), ((0.1, 0, 0), 0.2), ((0, 0, 0), 0.3)])
def test_a_line_force_of_zero_length_is_finite_and_zero_there(v0, s0):
    res = kn.simulate(line_scene((0, 0, 0), v0, s0), t_end=1.0, n_points=101)
    assert np.all(np.isfinite(res.states)) and np.all(np.isfinite(res["probe.force"]))
    np.testing.assert_array_equal(res["probe.force"][0], 0.0)
    if v0 == (0, 0, 0):                  # at rest at the origin: nothing moves it
        np.testing.assert_array_equal(res["probe.position"], 0.0)


def test_a_line_force_of_normal_length_is_unchanged(monkeypatch):
    run = dict(t_end=1.0, n_points=101, rtol=1e-10, atol=1e-12, jit=False)
    scene = ((0.3, 0.1, -0.2), (0.0, 1.0, 0.5), 0.1, 9.8)
    regular = kn.simulate(line_scene(*scene), **run)
    monkeypatch.setattr("kinetwork.spatial.S_SMALL", 0.0)   # the plain |d|
    plain = kn.simulate(line_scene(*scene), **run)
    np.testing.assert_allclose(regular.states, plain.states, rtol=0, atol=1e-12)
    np.testing.assert_allclose(regular["probe.force"], plain["probe.force"], rtol=0,
                               atol=1e-12)
