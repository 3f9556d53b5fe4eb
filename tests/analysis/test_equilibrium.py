"""kn.equilibrium against closed-form statics, and its refusals."""

import pathlib

import numpy as np
import pytest
from scipy.optimize import brentq

import kinetwork as kn
from scenes import fourbar
from scenes.reference import PAPER

from .plants import seed_with_motor

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


def pendulum(tau):
    """One link, its centre of mass 0.5 m out along x at q = 0, a torque tau at the joint."""
    m = kn.Model("pendulum", parameters={"tau": tau})
    m.add(kn.multibody.Ground("ground", gravity=[0, -9.8, 0]))
    m.add(kn.multibody.Revolute("joint", axis=[0, 0, 1]))
    m.add(kn.multibody.RigidBody("body", mass=1.0, r_cm=[0.5, 0, 0]))
    m.add(kn.rotational.Torque("motor", tau="tau"))
    for a, b in [("ground.frame", "joint.frame_a"), ("joint.frame_b", "body.frame_a"),
                 ("motor.flange", "joint.axis")]:
        m.connect(a, b)
    return m


def test_trim_holds_the_elbow_with_the_torque_the_statics_ask():
    """Elbow held at 0.3 rad by a motor: the shoulder angle and the torque from the paper's
    G and the spring (c q1), solved by brentq."""
    eq = kn.equilibrium(seed_with_motor(), inputs=["motor.u"], free=["motor.u"],
                        fix={"elbow.q": 0.3})
    g, c, q2 = PAPER["g"], PAPER["c"], 0.3
    q1 = brentq(lambda q: g * (0.5 * np.sin(q + q2) + 1.5 * np.sin(q)) + c * q, -1, 1)
    assert eq.state["shoulder.q"] == pytest.approx(q1, abs=1e-10)
    assert eq.inputs["motor.u"] == pytest.approx(0.5 * g * np.sin(q1 + q2), abs=1e-10)
    assert abs(eq.state["shoulder.qd"]) < 1e-10 and eq.residual < 1e-10
    assert eq.undetermined == []
    # linearised there, the motor's operating torque is the trim's
    lin = kn.linearize(seed_with_motor(), at=eq, inputs=["motor.u"])
    assert lin.u == pytest.approx([eq.inputs["motor.u"]])
    assert np.all(lin.eigenvalues.real < 0)        # the damped arm rests there


def test_a_parameter_can_be_solved_for():
    """Which torque parameter holds the pendulum at 1 rad: m g r cos(1)."""
    eq = kn.equilibrium(pendulum(0.0), free=["tau"], fix={"joint.q": 1.0})
    assert eq.params["tau"] == pytest.approx(9.8 * 0.5 * np.cos(1.0), abs=1e-10)


def test_the_pendulum_rests_where_torque_and_gravity_balance():
    eq = kn.equilibrium(pendulum(2.0), at={"joint.q": 0.5})
    assert eq.state["joint.q"] == pytest.approx(np.arccos(2.0 / 4.9), abs=1e-10)


def test_no_equilibrium_is_a_simulation_error():
    """A torque beyond m g r = 4.9 N m: nothing can hold it."""
    with pytest.raises(kn.SimulationError, match=r"no equilibrium of 'pendulum'.*joint\.qd"):
        kn.equilibrium(pendulum(10.0), at={"joint.q": 0.3})


def test_the_fourbar_rests_with_its_loop_closed():
    model = fourbar()
    eq = kn.equilibrium(model)
    system = model.compile(loops="partition")
    # the model's own rhs, which closes the loop by Newton: at rest there
    np.testing.assert_allclose(system.rhs(0.0, eq.X[:system.n_states]), 0, atol=1e-9)
    assert system.constraint_residual(eq.X[None, :])[0] < 1e-12
    lin = kn.linearize(model, at=eq)
    lam = lin.eigenvalues
    # undamped, so conservative: the pair is +-lambda (a centre or, here, a saddle)
    assert len(lam) == 2 and abs(lam[0] + lam[1]) < 1e-8 * np.max(np.abs(lam))
    assert np.min(np.abs(lam.imag)) < 1e-12 or np.max(np.abs(lam.real)) < 1e-8


def test_refusals_name_what_is_wrong():
    model = seed_with_motor()
    with pytest.raises(kn.ModelError, match="3 unknowns .2 states, 1 freed. for 4 equations.*fix as many"):
        kn.equilibrium(model, inputs=["motor.u"], free=["motor.u"], fix={"elbow.q": 0.3,
                                                                         "shoulder.q": 0.1})
    with pytest.raises(kn.ModelError, match="free: 'tauu' is neither.*'tau'"):
        kn.equilibrium(model, free=["tauu"], fix={"elbow.q": 0.3})
    with pytest.raises(kn.ModelError, match="fix: 'elbow' is not a state"):
        kn.equilibrium(model, fix={"elbow": 0.3}, free=["tau"])


def test_a_saturated_pid_arm_finds_its_set_point():
    """arm_pid at t = 1 s: the joints at their references (0.5 and 0.3 sin(pi) = 0 rad),
    each PID's integral holding the joint's static torque through the gear,
    I = (G + c q) / (n k) from the paper's G. Newton alone stalls there (the controllers
    start at their output limit); the trust region finds it."""
    model = kn.load(MODELS / "arm_pid.json")
    eq = kn.equilibrium(model, t=1.0, at={"shoulder.q": 0.5})
    g, c, n, k = (model.parameters[key] for key in ("g", "c", "n", "k"))
    assert eq.state["shoulder.q"] == pytest.approx(0.5, abs=1e-10)
    assert eq.state["elbow.q"] == pytest.approx(0.0, abs=1e-10)
    held = [g * 2 * np.sin(0.5) + c * 0.5, g * 0.5 * np.sin(0.5)]
    assert eq.state["pid_shoulder.x[0]"] == pytest.approx(held[0] / (n * k), rel=1e-9)
    assert eq.state["pid_elbow.x[0]"] == pytest.approx(held[1] / (n * k), rel=1e-9)
    system = model.compile()
    np.testing.assert_allclose(system.rhs(1.0, eq.X), 0, atol=1e-9)
