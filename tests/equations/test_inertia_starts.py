"""The start values of 1-D inertias (phi0, w0; s0, v0 of a Mass) are used or refused with
the reason, never dropped: on a joint axis they start the joint (MSL's Engine1a puts the
start speed on the load inertia), in a free train the train, and where something else
decides the start (a joint's own q0, a motion, a Fixed, another inertia) they must agree."""

import numpy as np
import pytest

import kinetwork as kn
import scenes.loops
from scenes import reference_loops as ref

rot, mb = kn.rotational, kn.multibody


def pendulum(**joint):
    """A pendulum with a motor inertia geared (ratio 10) onto its axis."""
    m = kn.Model("pendulum")
    m.add(mb.Ground("ground", gravity=[0, -9.81, 0]))
    m.add(mb.Revolute("joint", **joint))
    m.add(mb.RigidBody("bob", mass=1.0, r_cm=[1.0, 0, 0]))
    m.add(rot.IdealGear("gear", ratio=10.0))
    m.add(rot.Inertia("motor", J=1e-3))
    m.add(rot.Inertia("load", J=0.5))
    for a, b in [("ground.frame", "joint.frame_a"), ("joint.frame_b", "bob.frame_a"),
                 ("motor.flange_b", "gear.flange_a"), ("gear.flange_b", "joint.axis"),
                 ("load.flange_a", "joint.axis")]:
        m.connect(a, b)
    return m


def test_an_inertia_on_a_joint_axis_starts_the_joint():
    m = pendulum()
    m.components["load"].w0 = 2.0
    m.components["load"].phi0 = 0.3
    system = m.compile()
    np.testing.assert_allclose(system.x0, [0.3, 2.0])


def test_through_a_gear_the_joint_starts_at_the_inertias_angle_over_the_ratio():
    m = pendulum()
    m.components["motor"].w0 = 10.0               # motor = 10 * joint
    m.components["motor"].phi0 = 5.0
    np.testing.assert_allclose(m.compile().x0, [0.5, 1.0])


def test_a_joint_start_that_agrees_is_accepted_one_that_does_not_is_refused():
    m = pendulum(qd0=1.0)
    m.components["motor"].w0 = 10.0
    np.testing.assert_allclose(m.compile().x0, [0.0, 1.0])
    m.components["motor"].w0 = 20.0
    with pytest.raises(kn.ModelError, match=r"motor.w0 = 20: joint joint's qd0 \(rigidly, "
                                            r"through gear\) puts motor at 10 at the start"):
        m.compile()


def test_two_inertias_of_one_joint_axis_must_agree():
    m = pendulum()
    m.components["load"].w0 = 2.0
    m.components["motor"].w0 = 30.0
    with pytest.raises(kn.ModelError, match=r"motor.w0 = 30: load's start on joint joint "
                                            r"\(rigidly, through gear\) puts motor at 20 at "
                                            r"the start"):
        m.compile()


def test_a_free_train_starts_where_any_of_its_inertias_says():
    m = kn.Model("train")
    m.add(rot.Inertia("a", J=1.0))
    m.add(rot.IdealGear("gear", ratio=3.0))
    m.add(rot.Inertia("b", J=1.0, phi0=0.5, w0=1.0))
    m.connect("a.flange_b", "gear.flange_a")
    m.connect("gear.flange_b", "b.flange_a")
    system = m.compile()
    assert system.state_names == ["a.phi", "a.w"]
    np.testing.assert_allclose(system.x0, [1.5, 3.0])
    res = kn.simulate(system, t_end=1.0, n_points=3)
    np.testing.assert_allclose(res["a.phi"], 1.5 + 3.0 * res.t, atol=1e-9)
    m.components["a"].w0 = 2.0
    with pytest.raises(kn.ModelError, match=r"b.w0 = 1: a's start \(rigidly, through gear\) "
                                            r"puts b at 0.666666666667"):
        m.compile()


def test_a_fixed_or_moved_flange_decides_and_an_inertia_must_agree():
    m = kn.Model("held")
    m.add(rot.Fixed("base", phi0=0.2))
    m.add(rot.Inertia("a", J=1.0, phi0=0.2, w0=0.0))
    m.connect("base.flange", "a.flange_a")
    m.compile()
    m.components["a"].w0 = 1.0
    with pytest.raises(kn.ModelError, match=r"a.w0 = 1: base.flange, which holds the flange,"
                                            r" puts a at 0 at the start"):
        m.compile()
    m = kn.Model("moved")
    m.add(rot.Position("drive", phi_ref="0.1 + sin(t)"))
    m.add(rot.Inertia("a", J=1.0, phi0=0.1, w0=1.0))
    m.connect("drive.flange", "a.flange_a")
    m.compile()
    m.components["a"].phi0 = 0.0
    with pytest.raises(kn.ModelError, match=r"a.phi0 = 0: the motion drive puts a at 0.1"):
        m.compile()


def test_a_start_speed_on_a_loops_crank_inertia_starts_the_loop():
    """A four-bar's crank with a flywheel whose w0 is given: the crank starts at that speed
    and angle, the loop closes around it (the reference: the four-bar's own closure)."""
    m = scenes.loops.fourbar(theta0=None, thetad0=None,
                             guesses=scenes.loops.fourbar_guesses(0.8))
    m.add(rot.Inertia("flywheel", J=0.01, phi0=0.8, w0=1.5))
    m.connect("flywheel.flange_a", "A.axis")
    system = m.compile()
    x0 = dict(zip(system.state_names, system.x0))
    assert x0["A.q"] == pytest.approx(0.8) and x0["A.qd"] == pytest.approx(1.5)
    phi, psi = ref.fourbar_closure(0.8)
    assert x0["B.q"] == pytest.approx(float(phi) - 0.8, abs=1e-9)


def test_a_translational_mass_on_a_prismatic_axis_starts_it():
    m = kn.Model("slider")
    m.add(mb.Ground("ground", gravity=[0, 0, 0]))
    m.add(mb.Prismatic("slide", axis=[1, 0, 0]))
    m.add(mb.RigidBody("cart", mass=1.0))
    m.add(kn.translational.Mass("extra", m=2.0, s0=0.25, v0=-1.0))
    m.connect("ground.frame", "slide.frame_a")
    m.connect("slide.frame_b", "cart.frame_a")
    m.connect("extra.flange_a", "slide.axis")
    np.testing.assert_allclose(m.compile().x0, [0.25, -1.0])
