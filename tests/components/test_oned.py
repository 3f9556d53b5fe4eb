"""The 1-D partials (kinetwork/components/oned.py), through both libraries that subclass them:
compliant laws, sources, rigid elements and inertias, prescribed motions."""

import numpy as np
import pytest

import kinetwork as kn

rot, tr = kn.rotational, kn.translational
LIBRARIES = {"rotational": rot, "translational": tr}
#: the library's names of: reference of Position, of Speed, initial position, source value,
#: and the state of a Speed motion called "drive"
NAMES = {"rotational": ("phi_ref", "w_ref", "phi0", "tau", "drive.phi"),
         "translational": ("s_ref", "v_ref", "s0", "f", "drive.s")}


def test_one_dimensional_domains_follow_the_library():
    assert kn.multibody.Revolute.ports["axis"].domain == "rotational"
    assert kn.multibody.Prismatic.ports["support"].domain == "translational"
    assert kn.translational.SpringDamper.ports["flange_b"].domain == "translational"
    assert kn.rotational.Torque.ports["support"].optional


def test_laws_of_compliant_elements():
    sd = kn.rotational.SpringDamper("sd", c=3.0, d=0.5, phi_rel0=0.1)
    flows = sd.flows({"flange_a": 0.2, "flange_b": 1.0}, {"flange_a": 0.0, "flange_b": 2.0}, 0)
    assert flows["flange_b"] == pytest.approx(3.0 * (0.8 - 0.1) + 0.5 * 2.0)
    assert flows["flange_a"] == -flows["flange_b"]


@pytest.mark.parametrize("lib", LIBRARIES)
@pytest.mark.parametrize("pos, vel", [((0.2, 1.0), (0.0, 2.0)), ((-1.0, 0.5), (3.0, -1.0))])
def test_spring_damper_is_spring_plus_damper(lib, pos, vel):
    L = LIBRARIES[lib]
    rel0 = {"phi_rel0" if lib == "rotational" else "s_rel0": 0.3}
    pos = dict(zip(("flange_a", "flange_b"), pos))
    vel = dict(zip(("flange_a", "flange_b"), vel))
    both = L.SpringDamper("sd", c=7.0, d=0.4, **rel0).flows(pos, vel, 0.0)
    spring = L.Spring("s", c=7.0, **rel0).flows(pos, vel, 0.0)
    damper = L.Damper("d", d=0.4).flows(pos, vel, 0.0)
    for port in ("flange_a", "flange_b"):
        assert both[port] == pytest.approx(spring[port] + damper[port])
    assert both["flange_a"] == -both["flange_b"]


@pytest.mark.parametrize("lib", LIBRARIES)
def test_a_source_applies_its_parameter_or_its_signal(lib):
    name = NAMES[lib][3]
    source = LIBRARIES[lib].Torque if lib == "rotational" else LIBRARIES[lib].Force
    constant = source("src", **{name: 2.5})
    assert constant.applied() == 2.5
    assert constant.flows({}, {}, 0.0) == {"flange": -2.5, "support": 2.5}
    assert constant.flows({}, {}, 0.0, u=-4.0) == {"flange": 4.0, "support": -4.0}
    in_time = source("src", **{name: "2*sin(3*t)"})
    assert in_time.applied() == "2*sin(3*t)"      # the expression, bound by the equations
    with pytest.raises(kn.ModelError, match="time 't' is not allowed"):
        LIBRARIES[lib].Spring("s", c="2*t")


def test_rigid_elements_and_their_inertias():
    assert rot.Inertia("J", J=0.3).inertia() == 0.3 and rot.Inertia.has_inertia
    assert tr.Mass("m", m=2.0).inertia() == 2.0 and tr.Mass.has_inertia
    sensor = rot.TorqueSensor("s")
    assert (sensor.inertia(), sensor.position_ratio(), sensor.has_inertia) == (0.0, 1.0, False)
    assert tr.ForceSensor("f").position_ratio() == 1.0
    gear = rot.IdealGear("g", ratio=50.0)
    assert gear.ratio == 50.0 and gear.position_ratio() == 50.0
    with pytest.raises(kn.ModelError, match="must not be 0"):
        rot.IdealGear("g", ratio=0)
    with pytest.raises(kn.ModelError, match=r"J\.J = -1 kg\*m\^2: must be >= 0"):
        rot.Inertia("J", J=-1)


def prescribed(lib, cls, params, t_end=1.0):
    """A prescribed motion stretching a spring to a fixed flange, probed at its flange."""
    L = LIBRARIES[lib]
    model = kn.Model("motion")
    model.add(cls("drive", **params))
    model.add(L.Spring("spring", c=3.0))
    model.add(L.Fixed("fixed"))
    model.add(kn.Probe("p"))
    model.connect("drive.flange", "spring.flange_a")
    model.connect("spring.flange_b", "fixed.flange")
    model.connect("p.port", "drive.flange")
    return kn.simulate(model, t_end=t_end, n_points=21, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("lib", LIBRARIES)
def test_a_motion_prescribes_the_derivative_its_class_says(lib):
    """Position (derivative 0) sets the position, no state; Speed (derivative 1) sets the
    speed and integrates the position from its initial value, one state."""
    L = LIBRARIES[lib]
    ref, speed_ref, start, _, state = NAMES[lib]
    assert (L.Position.derivative, L.Speed.derivative) == (0, 1)
    position = prescribed(lib, L.Position, {ref: "0.5 + sin(2*t)"})
    speed = prescribed(lib, L.Speed, {speed_ref: "2*cos(2*t)", start: 0.5})
    assert position.state_names == [] and speed.state_names == [state]
    for res in (position, speed):
        pos, vel = res[res.signal_names[0]], res[res.signal_names[1]]
        np.testing.assert_allclose(pos, 0.5 + np.sin(2 * res.t), atol=1e-8)
        np.testing.assert_allclose(vel, 2 * np.cos(2 * res.t), atol=1e-8)
