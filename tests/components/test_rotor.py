"""Rotor1D (kinetwork/components/rotor.py, MSL's Parts.Rotor1D with its gyroscopic effects).

References:
- Pinocchio: a carrier on two revolutes holding a rotor on a skew axis, built there as a
  carrier of inertia I_C - J n n^T with a child revolute about n of inertia J n n^T (MSL's
  rotor leaves the carrier to hold its whole inertia as a rigid body): mass matrix and
  forward dynamics, with a torque on the rotor, to 1e-9;
- MSL's own claim in Rotational3DEffects.GyroscopicEffects (a cylinder spinning on a
  revolute and the same cylinder fixed to its mount plus a Rotor1D of its axial inertia move
  alike) is checked on models/gyroscopic_effects.json in tests/scenes/test_msl_parts.py;
- the torque on the rotor reacting on the carrier through ``support`` (MSL's Mounting1D):
  with no other load the angular momentum about the fixed axis is conserved.
"""

import numpy as np
import pinocchio as pin
import pytest

import kinetwork as kn
from scenes.random_trees import rodrigues, unit

mb = kn.multibody
N = np.array([0.3, -0.5, 0.8])            # rotor axis, in the carrier's frame
J = 0.35
R_ROTOR = np.array([0.1, 0.4, -0.2])      # rotor from the carrier's frame
I_C = np.array([[0.9, 0.05, -0.02], [0.05, 0.7, 0.03], [-0.02, 0.03, 1.1]])
M_C, C_C = 3.0, np.array([0.2, -0.1, 0.3])
GRAVITY = np.array([0.0, -9.81, 0.0])
TAU = 0.7                                  # torque on the rotor, reacting on the carrier


def carrier_with_rotor():
    model = kn.Model("gyro")
    model.add(mb.Ground("ground", gravity=GRAVITY.tolist()))
    model.add(mb.Revolute("yaw", axis=[0, 1, 0]))
    model.add(mb.Revolute("pitch", axis=[1, 0, 0.2]))
    model.add(mb.RigidBody("carrier", mass=M_C, r_cm=C_C.tolist(), inertia=I_C.tolist()))
    model.add(mb.FixedTranslation("mount", r=R_ROTOR.tolist()))
    model.add(mb.Rotor1D("rotor", J=J, n=N.tolist()))
    model.add(kn.rotational.Torque("motor", tau=TAU))
    for a, b in [("ground.frame", "yaw.frame_a"), ("yaw.frame_b", "pitch.frame_a"),
                 ("pitch.frame_b", "carrier.frame_a"), ("pitch.frame_b", "mount.frame_a"),
                 ("mount.frame_b", "rotor.frame_a"), ("motor.flange", "rotor.flange_a"),
                 ("motor.support", "rotor.support")]:
        model.connect(a, b)
    return model


def pinocchio_model():
    model = pin.Model()
    model.gravity.linear = GRAVITY
    j1 = model.addJoint(0, pin.JointModelRevoluteUnaligned(np.array([0.0, 1, 0])),
                        pin.SE3.Identity(), "yaw")
    j2 = model.addJoint(j1, pin.JointModelRevoluteUnaligned(unit([1.0, 0, 0.2])),
                        pin.SE3.Identity(), "pitch")
    e = unit(N)
    model.appendBodyToJoint(j2, pin.Inertia(M_C, C_C, I_C - J * np.outer(e, e)),
                            pin.SE3.Identity())
    j3 = model.addJoint(j2, pin.JointModelRevoluteUnaligned(e),
                        pin.SE3(np.eye(3), R_ROTOR), "rotor")
    model.appendBodyToJoint(j3, pin.Inertia(0.0, np.zeros(3), J * np.outer(e, e)),
                            pin.SE3.Identity())
    return model


def test_rotor_on_a_moving_carrier_matches_pinocchio():
    system = carrier_with_rotor().compile()
    assert system.state_names == ["yaw.q", "pitch.q", "rotor.spin.q",
                                  "yaw.qd", "pitch.qd", "rotor.spin.qd"]
    pmodel = pinocchio_model()
    rng = np.random.default_rng(5)
    for _ in range(4):
        q, qd = rng.uniform(-2, 2, 3), rng.uniform(-3, 3, 3)
        qd[2] *= 10                                  # a rotor spins fast
        M_ref = pin.crba(pmodel, pmodel.createData(), q)
        M_ref = np.triu(M_ref) + np.triu(M_ref, 1).T
        np.testing.assert_allclose(system.mass_matrix(q), M_ref, rtol=1e-9, atol=1e-12)
        tau = np.array([0.0, 0.0, TAU])              # the motor's reaction rests on the carrier
        qdd_ref = pin.aba(pmodel, pmodel.createData(), q, qd, tau)
        dx = np.asarray(system.rhs(0.0, np.concatenate([q, qd])), dtype=float).ravel()
        np.testing.assert_allclose(dx[3:], qdd_ref, rtol=1e-9,
                                   atol=1e-9 * np.abs(qdd_ref).max())


def test_a_motor_on_a_free_carrier_keeps_the_angular_momentum():
    """A carrier turning freely about a fixed axis, the rotor's axis along it, the motor
    between housing and rotor: J (w_c + w) + I_c w_c stays zero."""
    model = kn.Model("spin_up")
    model.add(mb.Ground("ground", gravity=[0, 0, 0]))
    model.add(mb.Revolute("turn", axis=[0, 0, 1]))
    model.add(mb.RigidBody("carrier", mass=1.0, inertia=[1.2, 1.2, 2.0]))
    model.add(mb.Rotor1D("rotor", J=J, n=[0, 0, 1]))
    model.add(kn.rotational.Torque("motor", tau="sin(3*t)"))
    model.add(kn.Probe("rotor_probe", quantities=["speed"]))
    for a, b in [("ground.frame", "turn.frame_a"), ("turn.frame_b", "carrier.frame_a"),
                 ("turn.frame_b", "rotor.frame_a"), ("motor.flange", "rotor.flange_b"),
                 ("motor.support", "rotor.support"), ("rotor_probe.port", "rotor.flange_a")]:
        model.connect(a, b)
    res = kn.simulate(model, t_end=1.0, n_points=21, rtol=1e-11, atol=1e-12, jit=False)
    wc, w = res["turn.qd"], res["rotor_probe.speed"]
    np.testing.assert_allclose(w, res["rotor.spin.qd"], atol=0)
    # the carrier holds the rotor's inertia J about the axis as well: I_c = 2.0 includes it
    np.testing.assert_allclose(J * (wc + w) + (2.0 - J) * wc, 0, atol=1e-10)
    # the rotor alone: J (w_c + w)' = tau, so J (w_c + w) = (1 - cos 3t) / 3
    np.testing.assert_allclose(J * (wc + w), (1 - np.cos(3 * res.t)) / 3, atol=1e-9)
