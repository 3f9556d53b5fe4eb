"""Subsystems in Python: a model with exposed ports placed in another like a component,
flattened with names by path; parameters fed from outside; nesting; the refusals, each naming
its path. The seed's double pendulum built from one link subsystem placed twice is checked
against the paper's closed form (an independent reference)."""

import numpy as np
import pytest

import kinetwork as kn
from close import assert_same_numbers
from scenes import double_pendulum
from scenes.reference import seed_reference


def link_model():
    """One pendulum link: a revolute joint at frame_a, a point mass at mid-link, frame_b at
    the far end; its angle probed."""
    link = kn.Model("link", parameters={"L": 1.0, "m": 1.0, "q0": 0.0})
    joint = link.add(kn.multibody.Revolute("joint", axis=[0, 0, 1], q0="q0"))
    link.add(kn.multibody.FixedTranslation("rod", r=[0, "-L", 0]))
    link.add(kn.multibody.RigidBody("bob", mass="m", r_cm=[0, "-L/2", 0]))
    link.add(kn.Probe("p", quantities=["angle", "speed"]))
    for a, b in [("joint.frame_b", "rod.frame_a"), ("joint.frame_b", "bob.frame_a"),
                 ("p.port", "joint.axis")]:
        link.connect(a, b)
    link.expose("frame_a", joint.frame_a)
    link.expose("frame_b", "rod.frame_b")
    link.expose("axis", "joint.axis")
    link.expose("support", "joint.support")
    return link


def seed_of_links(link=None):
    """The seed scene with both links one subsystem: the outer parameters feed the inner."""
    link = link or link_model()
    arm = kn.Model("arm", parameters={"L1": 1.0, "L2": 1.0, "m1": 1.0, "m2": 1.0, "c": 1.0,
                                      "d": 1.0, "g": 9.8})
    arm.add(kn.multibody.Ground("ground", gravity=[0, "-g", 0]))
    upper = arm.add(kn.Subsystem("upper", link, params={"L": "L1", "m": "m1", "q0": 0.05}))
    arm.add(kn.Subsystem("lower", link, params={"L": "L2", "m": "m2", "q0": 0.05}))
    spring = arm.add(kn.rotational.SpringDamper("spring", c="c", d="d"))
    arm.connect("ground.frame", upper.frame_a)
    arm.connect("upper.frame_b", "lower.frame_a")
    arm.connect(spring.flange_a, "upper.support")
    arm.connect(spring.flange_b, upper.axis)
    return arm


def test_the_seed_of_two_link_subsystems_is_the_paper_s_pendulum():
    arm = seed_of_links()
    system = arm.compile()
    assert system.state_names == ["upper.joint.q", "lower.joint.q",
                                  "upper.joint.qd", "lower.joint.qd"]
    assert system.param_names == ["L1", "L2", "m1", "m2", "c", "d", "g"]
    t = np.linspace(0, 5, 201)
    res = kn.simulate(arm, t_end=5, n_points=201, rtol=1e-11, atol=1e-12, params={"c": 2.0})
    ref = seed_reference(t, c=2.0)
    assert np.max(np.abs(res.states - ref)) < 1e-8
    assert np.max(np.abs(res["lower.p.angle"] - ref[:, 1])) < 1e-8
    assert res.signal_names == ["upper.p.angle", "upper.p.speed", "lower.p.angle",
                                "lower.p.speed"]
    # the very equations of the seed written flat: the same numbers, step for step
    flat = kn.simulate(double_pendulum(), t_end=5, n_points=201, rtol=1e-11, atol=1e-12,
                       params={"c": 2.0})
    assert_same_numbers(res.states, flat.states)


def test_model_parameters_feed_subsystems_without_a_new_compilation():
    arm = seed_of_links()
    system = arm.compile()
    arm.set_parameter("L1", 2.0)
    assert arm.compile() is system
    assert arm.numeric_values()["upper.rod"]["r"][1] == -2.0
    res = kn.simulate(arm, t_end=1, n_points=11, params={"L1": 1.5})
    assert arm.compile() is system and res.t[-1] == 1


def test_a_number_given_to_a_subsystem_is_a_constant_of_the_instance():
    # as a component's parameter: set by path or on the instance, a new compilation
    arm = seed_of_links()
    system = arm.compile()
    arm.set_parameter("upper.q0", 0.2)
    assert arm.components["upper"].q0 == 0.2
    again = arm.compile()
    assert again is not system and again.x0[0] == pytest.approx(0.2)
    arm.components["lower"].q0 = 0.1
    assert arm.compile().x0[1] == pytest.approx(0.1)
    # a definition's own value reaches the instances that keep it
    link = arm.components["upper"].definition
    arm.components["lower"].given.pop("q0")
    link.set_parameter("q0", -0.3)
    assert arm.compile().x0[1] == pytest.approx(-0.3)
    with pytest.raises(kn.ModelError, match=r"'upper.q0' is a value of subsystem 'upper', a "
                                            r"constant of its equations"):
        kn.simulate(arm, t_end=1, params={"upper.q0": 1.0})
    with pytest.raises(kn.ModelError, match=r"a path names a parameter of a subsystem placed "
                                            r"in 'arm'.*subsystems here: upper, lower"):
        arm.set_parameter("spring.c", 1.0)


def test_an_edited_definition_reaches_every_instance():
    link = link_model()
    arm = seed_of_links(link)
    before = arm.compile()
    link.add(kn.Probe("p_frame", quantities=["position"]))
    link.connect("p_frame.port", "rod.frame_b")
    after = arm.compile()
    assert after is not before
    assert "lower.p_frame.position" in after.signal_names


def test_subsystems_nest_and_name_by_path():
    link = link_model()
    pair = kn.Model("pair", parameters={"La": 1.0})
    a = pair.add(kn.Subsystem("a", link, params={"L": "La"}))
    b = pair.add(kn.Subsystem("b", link, params={"L": "La/2"}))
    pair.connect(a.frame_b, b.frame_a)
    pair.expose("base", a.frame_a)
    top = kn.Model("top", parameters={"size": 1.5})
    top.add(kn.multibody.Ground("ground"))
    top.add(kn.Subsystem("left", pair, params={"La": "size"}))
    top.add(kn.Subsystem("right", pair))
    top.connect("ground.frame", "left.base")
    top.connect("ground.frame", "right.base")
    system = top.compile()
    assert system.state_names[:4] == ["left.a.joint.q", "left.b.joint.q", "right.a.joint.q",
                                      "right.b.joint.q"]
    values = top.numeric_values()
    assert values["left.b.rod"]["r"][1] == -0.75           # La/2 with La = size = 1.5
    assert values["right.b.rod"]["r"][1] == -0.5           # the definition's La = 1
    assert top.compile().param_names == ["size"]
    top.set_parameter("size", 3.0)
    assert top.numeric_values()["left.a.rod"]["r"][1] == -3.0


def test_a_cycle_of_definitions_is_refused_naming_it():
    a, b = kn.Model("A"), kn.Model("B")
    a.add(kn.Subsystem("b", b))
    with pytest.raises(kn.ModelError, match=r"model 'B' cannot contain itself \(the "
                                            r"definition 'A' places 'B'\)"):
        b.add(kn.Subsystem("a", a))
    with pytest.raises(kn.ModelError, match="cannot contain itself"):
        a.add(kn.Subsystem("me", a))


def test_wrong_ports_and_parameters_are_refused_naming_the_path():
    link = link_model()
    with pytest.raises(kn.ModelError, match=r"link port 'tip': FixedTranslation 'rod' has "
                                            r"no port 'frame_c' \(did you mean 'frame_b'"):
        link.expose("tip", "rod.frame_c")
    with pytest.raises(kn.ModelError, match=r"link port 'tip': 'tube.frame_b': no component"):
        link.expose("tip", "tube.frame_b")
    with pytest.raises(kn.ModelError, match="port 'axis' is already exposed"):
        link.expose("axis", "joint.axis")
    arm = kn.Model("arm", parameters={"g": 9.8})
    upper = arm.add(kn.Subsystem("upper", link))
    with pytest.raises(kn.ModelError, match=r"subsystem 'upper' \(link\) has no port 'frame_c' "
                                            r"\(did you mean 'frame_b'"):
        arm.connect("upper.frame_c", "upper.frame_a")
    with pytest.raises(kn.ModelError, match=r"lower.mass: unknown parameter; link has L, m, "
                                            r"q0"):
        kn.Subsystem("lower", link, params={"mass": 2.0})
    with pytest.raises(kn.ModelError, match="expects a kn.Model"):
        kn.Subsystem("lower", "link")
    # a value that breaks a part inside: the path to the part and its parameter
    upper.m = -1
    arm.add(kn.multibody.Ground("ground"))
    arm.connect("ground.frame", "upper.frame_a")
    with pytest.raises(kn.ModelError, match=r"upper/bob.mass = -1.0 kg: must be >= 0"):
        arm.validate()
    upper.m = "2*gg"
    with pytest.raises(kn.ModelError, match=r"upper.m = '2\*gg': unknown name 'gg' \(did you "
                                            r"mean 'g'\?\); parameters here are g"):
        arm.validate()


def test_an_unwired_exposed_port_is_reported_by_its_inner_path():
    arm = kn.Model("arm")
    arm.add(kn.multibody.Ground("ground"))
    arm.add(kn.Subsystem("upper", link_model()))
    with pytest.raises(kn.ModelError, match=r"upper\.joint"):
        arm.validate()


def test_references_to_components_inside_follow_the_path():
    # an InverseDynamics block names its joint: inside a subsystem, the joint of the instance
    held = kn.Model("held", parameters={"q0": 0.0})
    held.add(kn.multibody.Revolute("joint", axis=[0, 0, 1], q0="q0"))
    held.add(kn.multibody.FixedTranslation("rod", r=[1, 0, 0]))
    held.add(kn.multibody.RigidBody("bob", mass=2.0, r_cm=[0, 0, 0]))
    held.add(kn.signals.Constant("zero", k=0.0))
    held.add(kn.signals.InverseDynamics("inverse", joint="joint"))
    held.add(kn.rotational.Torque("motor"))
    for a, b in [("joint.frame_b", "rod.frame_a"), ("rod.frame_b", "bob.frame_a"),
                 ("zero.y", "inverse.a1"), ("inverse.y", "motor.u"),
                 ("motor.flange", "joint.axis"), ("motor.support", "joint.support")]:
        held.connect(a, b)
    held.expose("frame_a", "joint.frame_a")
    held.expose("axis", "joint.axis")
    scene = kn.Model("scene")
    scene.add(kn.multibody.Ground("ground", gravity=[0, -9.81, 0]))
    scene.add(kn.Subsystem("one", held, params={"q0": 0.3}))
    scene.add(kn.Subsystem("two", held, params={"q0": -0.2}))
    scene.add(kn.Probe("outside", quantities=["angle", "torque"]))  # a probe on a port inside
    scene.connect("ground.frame", "one.frame_a")
    scene.connect("ground.frame", "two.frame_a")
    scene.connect("outside.port", "one.axis")
    res = kn.simulate(scene, t_end=1.0, n_points=11, rtol=1e-10, atol=1e-12)
    # each motor holds its own arm against gravity: the angles stay where they started
    assert np.max(np.abs(res.states[:, 0] - 0.3)) < 1e-8
    assert np.max(np.abs(res.states[:, 1] + 0.2)) < 1e-8
    assert res["outside.torque"][0] == pytest.approx(2.0 * 9.81 * np.cos(0.3), rel=1e-9)
