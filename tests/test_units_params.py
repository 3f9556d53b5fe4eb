"""Units on model parameters (issue 19, item 3): ``Model(parameters={"L": "500 mm"})``, a
file's "parameters" block, ``simulate(params=...)``, ``--param`` and ``set_parameter``.

A model parameter declares no unit: a quantity is taken in SI base units, and its dimension
is checked where a component parameter with a declared unit uses it (the name alone, or the
name times numbers). The expected numbers are the SI definitions worked out exactly by sympy
and rounded once (``exact``), as in test_units.py.
"""

import json
import re

import numpy as np
import pytest
import sympy as sp

import kinetwork as kn
from kinetwork.cli import main
from scenes import SEED_PARAMS, double_pendulum

mb = kn.multibody
R = sp.Rational


def exact(value):
    """The double nearest to the exact value ``value`` (sympy, 50 digits)."""
    return float(sp.N(value, 50))


# text -> exact value in SI base units
CONVERTED = [("500 mm", R(1, 2)), ("2 kg", 2), ("250 g", R(1, 4)), ("30 deg", sp.pi / 6),
             ("2 N*m/rad", 2), ("2000 N*mm/rad", 2), ("3 km/h", R(5, 6)),
             ("60 rpm", 2 * sp.pi), ("1.5 kN", 1500), ("-45 deg", -sp.pi / 4),
             ("1e-3 kg*m^2", R(1, 1000)), ("9.8 m/s^2", R(49, 5)), ("2 in", R(508, 10000))]


@pytest.mark.parametrize("text, si", CONVERTED, ids=[c[0] for c in CONVERTED])
def test_a_model_parameter_with_a_unit_is_its_si_number_exactly(text, si):
    model = kn.Model("m", parameters={"p": text})
    assert model.parameters["p"] == exact(si)
    assert model.parameter_values({"p": text})["p"] == exact(si), "an override alike"
    model.set_parameter("q", text)
    assert model.parameters["q"] == exact(si)


def _seed_in_units():
    """The seed with its lengths, masses, gravity and spring in other units."""
    return double_pendulum(L1="1000 mm", L2="100 cm", m1="1000 g", m2="1 kg",
                           g="9.8 m/s^2", c="1 N*m/rad", d="1000 N*mm*s/rad")


def test_the_seed_in_other_units_moves_as_the_seed_in_si(tmp_path):
    model = _seed_in_units()
    assert model.parameters == SEED_PARAMS
    a = kn.simulate(model, t_end=0.3, n_points=4, method="cvodes")
    b = kn.simulate(double_pendulum(), t_end=0.3, n_points=4, method="cvodes")
    np.testing.assert_array_equal(a.states, b.states)


def test_a_file_keeps_the_parameters_as_written_byte_for_byte(tmp_path):
    path, again = tmp_path / "units.json", tmp_path / "again.json"
    _seed_in_units().save(path)
    saved = json.loads(path.read_text())
    assert saved["parameters"]["L1"] == "1000 mm" and saved["parameters"]["d"] == \
        "1000 N*mm*s/rad"
    loaded = kn.load(path)
    assert loaded.parameters == SEED_PARAMS
    loaded.save(again)
    assert again.read_bytes() == path.read_bytes()
    # a new value replaces the text; a number set by hand is written as the number
    loaded.set_parameter("L1", 0.5)
    loaded.parameters["m1"] = 2.0
    loaded.set_parameter("c", "3 N*m/rad")
    params = json.loads(kn.dumps(loaded))["parameters"]
    assert (params["L1"], params["m1"], params["c"], params["L2"]) == \
        (0.5, 2.0, "3 N*m/rad", "100 cm")


def test_a_files_parameters_block_takes_units(tmp_path):
    data = json.loads(kn.dumps(double_pendulum()))
    data["parameters"].update({"L1": "500 mm", "m1": "2000 g"})
    text = json.dumps(data, indent=2) + "\n"
    model = kn.loads(text)
    assert (model.parameters["L1"], model.parameters["m1"]) == (0.5, 2.0)
    assert json.loads(kn.dumps(model))["parameters"] == data["parameters"], "as written"
    data["parameters"]["m1"] = "2000 mm"
    with pytest.raises(kn.ModelError) as err:
        kn.loads(json.dumps(data))
    message = str(err.value)
    assert "parameters.m1 = '2000 mm'" in message and "mass1" in message
    assert "mm ([length]) does not convert to kg ([mass])" in message


# (component parameter using p, text given to p): the name alone, or times numbers
REFUSED = [
    (lambda: mb.RigidBody("body", mass="p"), "2 m", "body.mass [kg]", "m ([length])"),
    (lambda: mb.FixedTranslation("rod", r=[0, "-p/2", 0]), "3 kg", "rod.r[1] [m]",
     "kg ([mass])"),
    (lambda: mb.Revolute("joint", q0="0.5*p"), "1 s", "joint.q0 [rad]", "s ([time])"),
    (lambda: kn.rotational.SpringDamper("spring", c="p", d=0.1), "2 N*m/s",
     "spring.c [N*m/rad]", "N*m/s"),
]


@pytest.mark.parametrize("make, text, use, given", REFUSED, ids=[r[1] for r in REFUSED])
def test_a_parameter_used_with_another_dimension_is_refused_naming_both_units(
        make, text, use, given):
    model = kn.Model("m", parameters={"p": text})
    model.add(make())
    with pytest.raises(kn.ModelError) as err:
        model.validate()
    message = str(err.value)
    assert f"parameters.p = {text!r} is used as {use}" in message
    assert given in message and "does not convert to" in message
    # the same text as a run's value is refused before anything runs
    model.set_parameter("p", 1.0)
    with pytest.raises(kn.ModelError, match=re.escape(f"params.p = '{text}' is used as ")):
        model.parameter_values({"p": text})
    assert model.parameters["p"] == 1.0, "the model is unchanged"


def test_uses_that_are_not_a_name_times_numbers_are_not_checked():
    # "p^2" or "p + q" have no dimension to read from p alone: taken as SI numbers
    model = kn.Model("m", parameters={"p": "2 m", "q": 1.0})
    model.add(mb.RigidBody("body", mass="p^2 + q"))
    assert model.numeric_values()["body"]["mass"] == 5.0


def test_bad_quantities_are_refused_naming_the_parameter():
    model = kn.Model("m", parameters={"L": 1.0})
    not_a_quantity = "must be a number or a number with a unit"
    for value, said in [("1 foo", "unknown unit 'foo'"), ("L/2", not_a_quantity),
                        ("1.0", not_a_quantity), ("20 degC", "offset")]:
        with pytest.raises(kn.ModelError, match="parameters.L") as err:
            model.set_parameter("L", value)
        assert said in str(err.value)
        with pytest.raises(kn.ModelError, match="params.L") as err:
            model.parameter_values({"L": value})
        assert said in str(err.value)
    assert model.parameters == {"L": 1.0} and model.parameter_text == {}


def test_simulate_takes_parameters_with_units_as_their_si_numbers():
    model = double_pendulum()
    a = kn.simulate(model, t_end=0.3, n_points=4, method="cvodes",
                    params={"c": "2 N*m/rad", "L1": "800 mm", "m2": "1500 g"})
    b = kn.simulate(model, t_end=0.3, n_points=4, method="cvodes",
                    params={"c": 2.0, "L1": 0.8, "m2": 1.5})
    np.testing.assert_array_equal(a.states, b.states)
    with pytest.raises(kn.ModelError, match=r"params.c = '2 kg' is used as spring.c "
                                            r"\[N\*m/rad\]: kg \(\[mass\]\)"):
        kn.simulate(model, t_end=0.3, n_points=4, params={"c": "2 kg"})


def test_the_command_line_takes_parameters_with_units(seed_file, tmp_path, capsys):
    runs = {}
    for label, value in [("units", "c=2000 N*mm/rad"), ("si", "c=2")]:
        out = tmp_path / f"{label}.csv"
        assert main(["run", str(seed_file), "--t-end", "0.3", "--n-points", "4", "--param",
                     value, "--param", "L1=80 cm", "--out", str(out), "--quiet"]) == 0
        runs[label] = out.read_text()
    # c in N*mm/rad and in SI (both with L1 in cm): the same numbers, the same file
    assert runs["units"] == runs["si"]
    reference = kn.simulate(double_pendulum(), t_end=0.3, n_points=4,
                            params={"c": 2.0, "L1": 0.8})
    data = np.loadtxt(tmp_path / "si.csv", delimiter=",", skiprows=1, comments="#")
    np.testing.assert_allclose(data[:, 1], reference["probe1.angle"], rtol=1e-6, atol=1e-9)
    assert main(["run", str(seed_file), "--t-end", "0.3", "--param", "c=2 kg"]) != 0
    err = capsys.readouterr().err
    assert "params.c = '2 kg'" in err and "N*m/rad" in err
    with pytest.raises(SystemExit):
        main(["run", str(seed_file), "--param", "c=two"])
    assert "a number with a unit" in capsys.readouterr().err


def _link(L=1.0, mass=1.0):
    link = kn.Model("link", parameters={"L": L, "mass": mass})
    link.add(mb.Revolute("joint"))
    link.add(mb.FixedTranslation("rod", r=["L", 0, 0]))
    link.add(mb.RigidBody("body", mass="mass"))
    link.connect("joint.frame_b", "rod.frame_a")
    link.connect("rod.frame_b", "body.frame_a")
    link.expose("frame_a", "joint.frame_a")
    return link


def _arm(link, params, parameters=None):
    arm = kn.Model("arm", parameters=parameters)
    arm.add(mb.Ground("ground"))
    arm.add(kn.Subsystem("upper", link, params=params))
    arm.connect("ground.frame", "upper.frame_a")
    return arm


def test_subsystems_take_and_check_quantities_at_every_level():
    # the definition's own value, a value given to the instance, and an outer parameter
    # passed down by name: each in SI, each checked where the definition uses it
    arm = _arm(_link(L="500 mm"), {"mass": "2000 g"})
    flat = arm.flat().components
    assert (flat["upper.rod"]._values["r"][0], flat["upper.body"]._values["mass"]) == \
        (0.5, 2.0)
    arm.validate()
    arm = _arm(_link(), {"L": "Lo"}, parameters={"Lo": "700 mm"})
    assert kn.simulate(arm, t_end=0.05, n_points=2).states.shape == (2, 2)
    saved = json.loads(kn.dumps(arm))
    assert saved["parameters"] == {"Lo": "700 mm"}
    for arm, said in [
            (_arm(_link(L="2 kg"), {}),
             "definition 'link': parameters.L = '2 kg' is used as rod.r[0] [m]"),
            (_arm(_link(), {"L": "700 g"}), "upper.L = '700 g' is used as upper/rod.r[0] [m]"),
            (_arm(_link(), {"L": "-Lo/2"}, parameters={"Lo": "1 s"}),
             "parameters.Lo = '1 s' is used as upper/rod.r[0] [m]")]:
        with pytest.raises(kn.ModelError, match="does not convert to m") as err:
            arm.validate()
        assert said in str(err.value)
    arm = _arm(_link(), {"L": "Lo"}, parameters={"Lo": 0.7})
    with pytest.raises(kn.ModelError, match=r"params.Lo = '2 kg' is used as upper/rod.r\[0\] \[m\]"):
        kn.simulate(arm, t_end=0.05, n_points=2, params={"Lo": "2 kg"})
