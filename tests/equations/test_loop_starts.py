"""A FreeMotion that closes a loop places the start (MSL's DoublePendulumInitTip): its r0 and
v0 are conditions on the start that the pendulum's joints are solved for, against the closed
form of a two-link arm's inverse kinematics; what no configuration reaches is refused."""

import numpy as np
import pytest

import kinetwork as kn

mb, rot = kn.multibody, kn.rotational


def init_tip(r0=(0.7, 0.3, 0.0), v0=(0.0, 0.0, 0.0)):
    """MSL Multibody.Examples.Elementary.DoublePendulumInitTip: two BodyBoxes (r = 0.5 m,
    width 0.06 m) on revolutes about z (the first damped, d = 0.1), the second's angle
    guessed at pi/2, and a FreeMotion from the world to the tip whose start position and
    speed are given."""
    m = kn.Model("DoublePendulumInitTip")
    m.add(mb.Ground("world", gravity=[0, -9.81, 0]))
    m.add(mb.Revolute("revolute1"))
    m.add(rot.Damper("damper", d=0.1))
    m.add(mb.BodyBox("boxBody1", r=[0.5, 0, 0], width=0.06))
    m.add(mb.Revolute("revolute2", q0_guess=np.pi / 2))
    m.add(mb.BodyBox("boxBody2", r=[0.5, 0, 0], width=0.06))
    m.add(mb.FreeMotion("freeMotion", r0=list(r0), v0=list(v0)))
    m.add(kn.Probe("tip", quantities=["position", "velocity"]))
    for a, b in [("damper.flange_b", "revolute1.axis"), ("revolute1.support", "damper.flange_a"),
                 ("revolute1.frame_b", "boxBody1.frame_a"),
                 ("revolute2.frame_b", "boxBody2.frame_a"),
                 ("boxBody1.frame_b", "revolute2.frame_a"), ("world.frame", "revolute1.frame_a"),
                 ("world.frame", "freeMotion.frame_a"), ("freeMotion.frame_b", "boxBody2.frame_b"),
                 ("tip.port", "boxBody2.frame_b")]:
        m.connect(a, b)
    return m


def two_link(x, y, L=0.5):
    """Inverse kinematics of two links of length L, elbow angle positive."""
    q2 = np.arccos((x * x + y * y - 2 * L * L) / (2 * L * L))
    q1 = np.arctan2(y, x) - np.arctan2(L * np.sin(q2), L + L * np.cos(q2))
    return q1, q2


def test_the_tip_starts_where_the_free_motion_says():
    system = init_tip().compile()
    x0 = dict(zip(system.state_names, system.x0))
    q1, q2 = two_link(0.7, 0.3)
    assert x0["revolute1.q"] == pytest.approx(q1, abs=1e-10)
    assert x0["revolute2.q"] == pytest.approx(q2, abs=1e-10)
    res = kn.simulate(system, t_end=0.5, n_points=6)
    np.testing.assert_allclose(res["tip.position"][0], [0.7, 0.3, 0.0], atol=1e-10)
    assert np.linalg.norm(res["tip.position"][-1] - res["tip.position"][0]) > 0.01  # it falls


def test_the_tips_start_speed_gives_the_joints_speeds():
    v = np.array([0.2, -0.4, 0.0])
    system = init_tip(v0=v).compile()
    x0 = dict(zip(system.state_names, system.x0))
    q1, q2 = two_link(0.7, 0.3)
    L = 0.5
    jac = np.array([[-L * np.sin(q1) - L * np.sin(q1 + q2), -L * np.sin(q1 + q2)],
                    [L * np.cos(q1) + L * np.cos(q1 + q2), L * np.cos(q1 + q2)]])
    qd = np.linalg.solve(jac, v[:2])
    assert x0["revolute1.qd"] == pytest.approx(qd[0], abs=1e-10)
    assert x0["revolute2.qd"] == pytest.approx(qd[1], abs=1e-10)
    res = kn.simulate(system, t_end=0.1, n_points=2)
    np.testing.assert_allclose(res["tip.velocity"][0], v, atol=1e-10)


def test_a_start_no_configuration_reaches_is_refused():
    with pytest.raises(kn.ModelError, match=r"the start values freeMotion.r0 \(off by "
                                            r"[0-9.]+\) cannot be met"):
        init_tip(r0=(2.0, 0.0, 0.0)).compile()
    with pytest.raises(kn.ModelError, match=r"freeMotion.v0 \(off by [0-9.]+\) cannot be "
                                            r"met"):
        init_tip(v0=(0.0, 0.0, 1.0)).compile()       # out of the pendulum's plane


def test_a_joint_start_given_is_held_and_the_rest_solved():
    """revolute1's q0 given: the tip's r0 must agree with it, or the start is refused."""
    q1, q2 = two_link(0.7, 0.3)
    m = init_tip()
    m.components["revolute1"].q0 = q1
    np.testing.assert_allclose(m.compile().x0[:2], [q1, q2], atol=1e-10)
    m.components["revolute1"].q0 = q1 + 0.3
    with pytest.raises(kn.ModelError, match=r"freeMotion.r0 \(off by"):
        m.compile()
