"""Units where users write numbers (issue 19, item 3): "2 kg", "30 deg", "5 mm", "1 N*m/rad"
in Python and in files, converted to the parameter's SI unit, refused with both units named
when the dimension differs, and saved as written.

The expected values are the SI definitions of the units (the metre's prefixes, the degree as
pi/180, the inch as 0.0254 m, the pound-force as 0.45359237 kg times 9.80665 m/s^2), worked
out exactly by sympy and rounded once: a conversion is right when it gives that double, to
the last bit.
"""

import json

import numpy as np
import pytest
import sympy as sp

import kinetwork as kn
from kinetwork import units
from scenes import double_pendulum

mb, rot, tr = kn.multibody, kn.rotational, kn.translational
R = sp.Rational


def exact(value):
    """The double nearest to the exact value ``value`` (sympy, 50 digits)."""
    return float(sp.N(value, 50))


# (component, parameter, text, exact SI value): SI, prefixes, degrees, compound units
CONVERTED = [
    (lambda v: mb.RigidBody("b", mass=v), "mass", "2 kg", 2),
    (lambda v: mb.RigidBody("b", mass=v), "mass", "250 g", R(1, 4)),
    (lambda v: mb.RigidBody("b", mass=v), "mass", "2kg", 2),
    (lambda v: mb.FixedTranslation("f", r=[v, 0, 0]), "r", "5 mm", R(5, 1000)),
    (lambda v: mb.FixedTranslation("f", r=[v, 0, 0]), "r", "0.1 mm", R(1, 10000)),
    (lambda v: mb.FixedTranslation("f", r=[v, 0, 0]), "r", "3 µm", R(3, 10 ** 6)),
    (lambda v: mb.FixedTranslation("f", r=[v, 0, 0]), "r", "1.5 km", 1500),
    (lambda v: mb.FixedTranslation("f", r=[v, 0, 0]), "r", "2 in", R("0.0508")),
    (lambda v: mb.FixedTranslation("f", r=[v, 0, 0]), "r", "1e3 mm", 1),
    (lambda v: mb.Revolute("j", q0=v), "q0", "30 deg", sp.pi / 6),
    (lambda v: mb.Revolute("j", q0=v), "q0", "-30°", -sp.pi / 6),
    (lambda v: mb.Revolute("j", q0=v), "q0", "0.25 revolution", sp.pi / 2),
    (lambda v: mb.Revolute("j", qd0=v), "qd0", "120 rpm", 4 * sp.pi),
    (lambda v: mb.Prismatic("p", q0=v), "q0", "25 cm", R(1, 4)),
    (lambda v: rot.SpringDamper("s", c=v, d=0), "c", "1 N*m/rad", 1),
    (lambda v: rot.SpringDamper("s", c=v, d=0), "c", "2 N*m/deg", 360 / sp.pi),
    (lambda v: rot.SpringDamper("s", c=1, d=v), "d", "1 mN*m*s/deg", R(180, 1000) / sp.pi),
    (lambda v: tr.SpringDamper("s", c=v, d=0), "c", "1 kN/mm", 10 ** 6),
    (lambda v: mb.RigidBody("b", mass=1, inertia=[v, v, v]), "inertia", "20 g*cm^2",
     R(2, 10 ** 6)),
    (lambda v: mb.RigidBody("b", mass=1, inertia=[v, v, v]), "inertia", "1e-3 kg*m^2",
     R(1, 1000)),
    (lambda v: mb.Ground("g", gravity=[0, v, 0]), "gravity", "-9.80665 m/s^2", R("-9.80665")),
    (lambda v: mb.BodyBox("b", r=[1, 0, 0], density=v), "density", "7.85 g/cm^3", 7850),
    (lambda v: mb.WorldForce("f", force=[v, 0, 0]), "force", "1 lbf",
     R("0.45359237") * R("9.80665")),
    (lambda v: kn.signals.Step("s", start_time=v), "start_time", "10 ms", R(1, 100)),
    (lambda v: mb.SpringDamper("s", c=1, d=0, length_fraction=v), "length_fraction", "50 %",
     R(1, 2)),
]


@pytest.mark.parametrize("make, key, text, value", CONVERTED,
                         ids=[f"{case[1]}={case[2]}" for case in CONVERTED])
def test_a_quantity_is_converted_to_si_exactly(make, key, text, value):
    comp = make(text)
    given = list(np.ravel(np.array(comp.given[key], dtype=object)))
    assert text in given, "the value is kept as written"
    got = np.ravel(np.array(comp._values[key], dtype=float))[given.index(text)]
    assert got == exact(value), "the double nearest to the exact SI value"


def test_per_entry_units_of_a_joint_with_an_angle_and_a_distance():
    # a Cylindrical joint turns and slides: q0[0] is an angle, q0[1] a distance
    joint = mb.Cylindrical("c", q0=["90 deg", "5 mm"], qd0=["60 rpm", "1 cm/s"])
    assert joint.q0 == [exact(sp.pi / 2), 0.005]
    assert joint.qd0 == [exact(2 * sp.pi), 0.01]
    with pytest.raises(kn.ModelError) as refused:
        mb.Cylindrical("c", q0=["5 mm", "90 deg"])
    assert refused.value.problems == [
        "c.q0[0] = '5 mm': mm ([length]) does not convert to rad (dimensionless)",
        "c.q0[1] = '90 deg': deg (dimensionless) does not convert to m ([length])"]


# (component, text, message): wrong dimensions name both units; bounds and unknown units
REFUSED = [
    (lambda v: mb.RigidBody("mass1", mass=v), "2 m",
     r"mass1\.mass = '2 m': m \(\[length\]\) does not convert to kg \(\[mass\]\)"),
    (lambda v: mb.Revolute("j", q0=v), "5 mm",
     r"j\.q0 = '5 mm': mm \(\[length\]\) does not convert to rad \(dimensionless\)"),
    (lambda v: mb.Prismatic("p", q0=v), "30 deg",
     r"p\.q0 = '30 deg': deg \(dimensionless\) does not convert to m \(\[length\]\)"),
    (lambda v: rot.SpringDamper("s", c=v), "1 N/m",
     r"s\.c = '1 N/m': N/m \(\[mass\]/\[time\]\^2\) does not convert to N\*m/rad "
     r"\(\[length\]\^2\*\[mass\]/\[time\]\^2\)"),
    (lambda v: mb.FixedTranslation("f", r=[0, v, 0]), "2 s",
     r"f\.r\[1\] = '2 s': s \(\[time\]\) does not convert to m \(\[length\]\)"),
    (lambda v: rot.IdealGear("g", ratio=v), "3 kg",
     r"g\.ratio = '3 kg': kg \(\[mass\]\) does not convert to 1 \(dimensionless\)"),
    (lambda v: mb.RigidBody("mass1", mass=v), "-2 kg",
     r"mass1\.mass = '-2 kg', i\.e\. -2\.0 kg: must be >= 0"),
    (lambda v: mb.RigidBody("mass1", mass=v), "2 furlongz",
     r"mass1\.mass = '2 furlongz': unknown unit 'furlongz'"),
    (lambda v: mb.RigidBody("mass1", mass=v), "20 degC",
     r"'degC' is a unit with an offset"),
    (lambda v: mb.FixedTranslation("f", r=[0, v, 0]), "L/2 + 5 mm",
     r"f\.r\[1\]: cannot parse expression 'L/2 \+ 5 mm'.*a unit goes after one number"),
    # what exact arithmetic would take forever over is refused before it starts
    (lambda v: mb.FixedTranslation("f", r=[0, v, 0]), "1e999999999 m",
     r"the number '1e999999999' is out of range"),
    (lambda v: kn.signals.Constant("k", k=v), "1 km**99999",
     r"a power in the unit 'km\*\*99999' is beyond 100"),
    (lambda v: mb.RigidBody("mass1", mass=v), "1 kg # note",
     r"cannot read the unit 'kg # note'"),
    (lambda v: mb.RigidBody("mass1", mass=v), "1e300 Tg",
     r"'1e300 Tg' is out of range in kg"),
    # pint's own refusal, whose message fails to format exact numbers, still reads well
    (lambda v: mb.RigidBody("mass1", mass=v), "1 K-H", r"cannot read the unit 'K-H'"),
]


@pytest.mark.parametrize("make, text, message", REFUSED, ids=[c[1] for c in REFUSED])
def test_a_wrong_unit_is_refused_naming_both_units_and_the_place(make, text, message):
    with pytest.raises(kn.ModelError, match=message):
        make(text)


def test_an_assignment_with_a_unit_is_checked_and_a_refusal_changes_nothing():
    body = mb.RigidBody("mass1", mass="2 kg")
    with pytest.raises(kn.ModelError, match="does not convert to kg"):
        body.mass = "2 m"
    assert (body.mass, body.given["mass"]) == (2.0, "2 kg")
    body.mass = "500 g"
    assert (body.mass, body.given["mass"]) == (0.5, "500 g")


def test_a_file_refusal_names_the_json_place():
    text = double_pendulum().dumps() if hasattr(kn.Model, "dumps") else kn.dumps(
        double_pendulum())
    data = json.loads(text)
    index = next(i for i, c in enumerate(data["components"]) if c["name"] == "mass1")
    data["components"][index]["params"]["mass"] = "2 m"
    with pytest.raises(kn.ModelError, match=rf'components\[{index}\] "mass1" params\.mass = '
                                            r"'2 m': m \(\[length\]\) does not convert to kg"):
        kn.loads(json.dumps(data))


def _with_units(model):
    """The seed with its lengths, angle and mass written in other units."""
    model.components["mass1"].mass = "1000 g"
    model.components["shoulder"].q0 = "30 deg"
    model.components["link1"].r = [0, "-1000 mm", 0]
    return model


def test_a_file_round_trips_as_written_and_runs_as_the_si_model(tmp_path):
    model = _with_units(double_pendulum())
    path = tmp_path / "units.json"
    model.save(path)
    saved = json.loads(path.read_text())
    params = {c["name"]: c["params"] for c in saved["components"]}
    assert params["mass1"]["mass"] == "1000 g"
    assert params["shoulder"]["q0"] == "30 deg"
    assert params["link1"]["r"] == [0, "-1000 mm", 0]
    again = kn.load(path)
    again.save(tmp_path / "again.json")
    assert (tmp_path / "again.json").read_text() == path.read_text(), "saved as written"
    # the same model in SI numbers (pi/6 independently: sympy) moves the same way
    si = double_pendulum()
    si.components["mass1"].mass = 1.0
    si.components["shoulder"].q0 = exact(sp.pi / 6)
    si.components["link1"].r = [0, -1.0, 0]
    a = kn.simulate(again, t_end=0.3, n_points=4, method="cvodes")
    b = kn.simulate(si, t_end=0.3, n_points=4, method="cvodes")
    np.testing.assert_array_equal(a.states, b.states)


def test_quantities_need_no_pint_until_one_is_written():
    # plain numbers never touch the units library (a lighter import for most models)
    assert units.split("2*L") is None and units.split("1e3") == "e3"
    body = mb.RigidBody("b", mass="2*3")
    assert body.given["mass"] == "2*3" and body.mass == "2*3", "an expression stays one"


def test_a_signal_parameter_takes_any_unit_in_si():
    # a block's value is in the unit of its signal: converted to SI, not checked
    assert kn.signals.Constant("k", k="30 deg").k == exact(sp.pi / 6)
    assert kn.signals.Constant("k", k="2 kN").k == 2000.0


def test_a_subsystem_value_with_a_unit_is_taken_in_si_and_saved_as_written():
    # a definition's parameters declare no unit: a quantity given to one is converted to SI
    # base units (unchecked), as a signal block's value is
    link = kn.Model("link", parameters={"L": 1.0})
    link.add(mb.Revolute("joint"))
    link.add(mb.FixedTranslation("rod", r=["L", 0, 0]))
    link.add(mb.RigidBody("body", mass=1.0))
    link.connect("joint.frame_b", "rod.frame_a")
    link.connect("rod.frame_b", "body.frame_a")
    link.expose("frame_a", "joint.frame_a")
    arm = kn.Model("arm")
    arm.add(mb.Ground("ground"))
    arm.add(kn.Subsystem("upper", link, params={"L": "700 mm"}))
    arm.connect("ground.frame", "upper.frame_a")
    assert arm.flat().components["upper.rod"]._values["r"][0] == 0.7
    saved = json.loads(kn.dumps(arm))
    upper = next(c for c in saved["components"] if c["name"] == "upper")
    assert upper["params"] == {"L": "700 mm"}
