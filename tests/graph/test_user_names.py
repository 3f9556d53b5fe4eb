"""User-facing names only: a composite part (a DCMotor: resistor Ra, inductor La, EMF emf and
rotor inside) is named in messages as the user placed it, with its own ports; an unknown
component type says what it may be, across libraries; REPL echoes stay short."""

import json

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.analysis.equilibria import Equilibrium
from kinetwork.analysis.modal import Mode
from kinetwork.components.base import NoSuchComponent

INTERNAL = ("Ra", "La", "emf", "rotor")


def motor_model():
    m = kn.load("double_pendulum")
    m.add(kn.electrical.DCMotor("motor", R=1.2, L=0.05, k=0.3, J=2e-3))
    m.connect("motor.flange", "shoulder.axis")
    return m


def said(err):
    return [str(p) for p in err.problems]


def test_an_unwired_motor_is_named_by_its_own_ports(tmp_path):
    m = motor_model()
    with pytest.raises(kn.ModelError) as err:
        m.validate()
    assert said(err.value) == ["motor: port motor.p (electrical) is not connected",
                               "motor: port motor.n (electrical) is not connected"]
    assert [(p.component, p.port) for p in err.value.problems] == [("motor", "p"),
                                                                    ("motor", "n")]
    with pytest.raises(kn.ModelError) as again:        # the same words on every path
        m.compile()
    assert said(again.value) == said(err.value)
    m.save(tmp_path / "m.json")
    with pytest.raises(kn.ModelError) as loaded:
        kn.load(tmp_path / "m.json")
    assert not any(f".{part}" in text or f"/{part}" in text
                   for text in said(loaded.value) for part in INTERNAL)


def test_a_probe_on_the_motor_names_the_motors_pin():
    m = motor_model()
    m.add(kn.electrical.VoltageSource("src", V=12.0))
    m.add(kn.electrical.Ground("gnd"))
    m.connect("src.p", "motor.p"); m.connect("motor.n", "src.n"); m.connect("gnd.p", "src.n")
    m.add(kn.Probe("pm", quantities=["position"]))
    m.connect("pm.port", "motor.p")
    with pytest.raises(kn.ModelError, match=r"^'position' is not a quantity of an electrical "
                       r"port \(motor\.p\)|pm\.quantities: 'position' is not a quantity of an "
                       r"electrical port \(motor\.p\)"):
        m.validate()
    m.components["pm"].quantities = ["voltage", "current"]
    res = kn.simulate(m, t_end=0.1, n_points=11)
    assert res.probe_targets["pm"] == "motor.p"
    # the descriptor the CSV's sidecar and the studio read too
    assert {res.signals[n].target for n in ("pm.voltage", "pm.current")} == {"motor.p"}
    from kinetwork.plotlayout import Panel
    assert Panel(res, "pm.voltage").title == "pm (motor.p): voltage"
    np.testing.assert_allclose(res["pm.voltage"], 12.0, rtol=1e-12)


def test_a_motor_inside_a_subsystem_is_named_by_its_path():
    part = kn.Model("drive")
    part.add(kn.electrical.DCMotor("motor", R=1.2, L=0.05, k=0.3, J=2e-3))
    part.expose("flange", "motor.flange")
    m = kn.load("double_pendulum")
    m.add(kn.Subsystem("d1", part))
    m.connect("d1.flange", "shoulder.axis")
    with pytest.raises(kn.ModelError) as err:
        m.validate()
    text = "\n".join(said(err.value))
    assert "d1.motor.p" in text and "d1.motor.n" in text
    assert not any(f".{part}." in text or f"/{part}" in text for part in INTERNAL)


@pytest.mark.parametrize("library, name, suggested", [
    ("multibody", "World", ["multibody.Ground"]),
    ("rotational", "Mass", ["translational.Mass"]),
    ("rotational", "Ground", ["rotational.Fixed", "electrical.Ground", "multibody.Ground"]),
    ("multibody", "Fixed", ["multibody.Ground", "rotational.Fixed", "translational.Fixed"]),
    ("translational", "Torque", ["multibody.Torque", "rotational.Torque"]),
    ("signals", "Sin", ["signals.Sine"])])
def test_an_unknown_component_says_what_it_may_be(library, name, suggested):
    with pytest.raises(AttributeError) as err:
        getattr(getattr(kn, library), name)
    assert isinstance(err.value, NoSuchComponent)
    assert err.value.suggestions == suggested
    assert str(err.value) == (f"kinetwork.{library} has no component {name!r} (did you mean "
                              f"{' or '.join(repr(s) for s in suggested)}?)")
    assert getattr(getattr(kn, library), name, None) is None
    data = {"format": "kinetwork.model", "version": 1, "name": "x",
            "components": [{"name": "a", "type": f"{library}.{name}"}], "connections": []}
    with pytest.raises(kn.ModelError, match=f"did you mean {suggested[0]!r}"):
        kn.loads(json.dumps(data))


def test_echoes_in_a_repl_stay_short():
    names = [f"j{k}.q" for k in range(40)]
    eq = Equilibrium(0.0, np.arange(40.0), names, {"motor.u": 1.5}, {}, 0.0, 3, [])
    assert len(repr(eq)) < 250 and repr(eq).startswith("<Equilibrium motor.u = 1.5, j0.q = 0")
    assert repr(eq).endswith("... (33 more)>")
    shape = {f"j{k}.q": complex(k / 40, 0) for k in range(40)}
    mode = Mode(1j, 1.0, 0.0, 1.0, shape)
    assert len(repr(mode)) < 200 and "j39.q: 0.975" in repr(mode) and "(36 smaller)" in repr(mode)
    m = kn.load("engine_v6/EngineV6")
    assert len(repr(m.validate())) < 120 and len(repr(m)) < 120
