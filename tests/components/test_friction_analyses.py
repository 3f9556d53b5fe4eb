"""Friction in the analyses at one point: the seed's M, V, G with friction sliding
(``modes.free_terms``), and ``kn.linearize`` / ``kn.equilibrium`` in the modes the point
gives (``modes.operating_modes``), against the closed forms of a pendulum on a rough bearing."""

import numpy as np
import pytest

import kinetwork as kn

M_, L_, J_, G_ = 1.0, 0.5, 0.01, 9.81          # mass, centre of mass, inertia there, gravity
TAU_C, PEAK, D = 0.5, 1.2, 0.1


def rough_pendulum(q0=0.3, qd0=0.0):
    """A pendulum (centre of mass at L_ along x of its frame, gravity -y) whose revolute has
    bearing friction: tau_c, peak, d."""
    model = kn.Model("rough")
    ground = model.add(kn.multibody.Ground("ground", gravity=[0, -G_, 0]))
    joint = model.add(kn.multibody.Revolute("j", axis=[0, 0, 1], q0=q0, qd0=qd0))
    body = model.add(kn.multibody.RigidBody("b", mass=M_, r_cm=[L_, 0, 0],
                                            inertia=[0, 0, J_]))
    bearing = model.add(kn.rotational.BearingFriction("f", tau_c=TAU_C, peak=PEAK, d=D))
    probe = model.add(kn.Probe("p", quantities=["angle"]))
    model.connect(ground.frame, joint.frame_a)
    model.connect(joint.frame_b, body.frame_a)
    model.connect(bearing.flange, joint.axis)
    model.connect(probe.port, joint.axis)
    return model


# (J + m l^2) qdd + tau_c sign(qd) + d qd + m g l cos q = 0 while it slides
INERTIA = J_ + M_ * L_ ** 2


@pytest.mark.parametrize("q, qd", [(0.3, 1.5), (-2.0, -0.7), (1.0, 0.0)])
def test_dynamics_terms_show_friction_sliding_the_way_the_speed_goes(q, qd):
    system = rough_pendulum().compile()
    M, V, G = system.dynamics_terms([q], [qd])
    assert M[0, 0] == pytest.approx(INERTIA, rel=1e-14)
    assert V[0] == pytest.approx(TAU_C * np.sign(qd) + D * qd, rel=1e-14, abs=1e-15)
    assert G[0] == pytest.approx(M_ * G_ * L_ * np.cos(q), rel=1e-14)
    assert system.equations()["x_names"] == []          # no holding force, no mode left
    if qd:                  # the right-hand side in that sliding mode agrees
        x = np.array([q, qd, np.sign(qd)])
        assert system.rhs(0.0, x)[1] == pytest.approx(-(V[0] + G[0]) / M[0, 0], rel=1e-12)


def test_linearize_while_sliding_is_the_sliding_law_linearised():
    q, qd = 0.3, 1.5
    lin = kn.linearize(rough_pendulum(q, qd), outputs=["p.angle"])
    assert lin.state_names == ["j.q", "j.qd", "f.mode"]
    exact = np.array([[0, 1, 0], [M_ * G_ * L_ * np.sin(q) / INERTIA, -D / INERTIA, 0],
                      [0, 0, 0]])
    np.testing.assert_allclose(lin.A, exact, rtol=1e-12, atol=1e-14)


def test_linearize_at_rest_where_the_bearing_holds_is_the_stuck_pendulum():
    # hanging 0.05 rad off: gravity's torque m g l sin(0.05) = 0.245 N*m < peak tau_c = 0.6
    lin = kn.linearize(rough_pendulum(-np.pi / 2 + 0.05, 0.0))
    np.testing.assert_allclose(lin.A, [[0, 1, 0], [0, 0, 0], [0, 0, 0]], atol=1e-14)


def test_linearize_and_equilibrium_refuse_a_rest_the_bearing_cannot_hold():
    model = rough_pendulum(0.3, 0.0)           # m g l cos(0.3) = 4.69 N*m > 0.6 N*m
    for analysis in (kn.linearize, kn.equilibrium):
        with pytest.raises(kn.ModelError, match=r"f: at rest there, it would have to hold "
                                                r"4\.6859\d* beyond its static limit 0\.6"):
            analysis(model)


def test_an_equilibrium_with_friction_is_a_rest_the_bearing_holds():
    q = -np.pi / 2 + 0.1                      # holds m g l sin(0.1) = 0.49 N*m < 0.6 N*m
    eq = kn.equilibrium(rough_pendulum(q, 0.0))
    np.testing.assert_allclose(eq.X, [q, 0.0, 0.0], atol=1e-12)     # stuck where it is
    assert "j.q" in eq.undetermined           # every angle within the limit is one
