"""The contract of System (kinetwork/equations/system.py) on the seed scene, against the paper's
closed form: names, initial state, rhs, M, V, G, the symbolic equations; and when a model
gives the same System back and when a new one."""

import casadi as ca
import numpy as np
import pytest

import kinetwork as kn
from kinetwork.equations.system import System
from kinetwork.equations import stored
import kinetwork.graph.model
import kinetwork.upcalls
from scenes import double_pendulum
from scenes.reference import PAPER, seed_mvg

Q, QD = np.array([0.4, -1.1]), np.array([0.7, 2.0])


def test_state_names_units_and_initial_state():
    system = double_pendulum(q0=("a", 0.1), a=0.3).compile()
    assert system.state_names == ["shoulder.q", "elbow.q", "shoulder.qd", "elbow.qd"]
    assert system.state_units == ["rad", "rad", "rad/s", "rad/s"]
    assert (system.n_states, system.dof, system.n_algebraic) == (4, 2, 0)
    assert system.coordinate_names == ["shoulder.q", "elbow.q"]
    assert system.speed_names == ["shoulder.qd", "elbow.qd"]
    np.testing.assert_array_equal(system.x0, [0.3, 0.1, 0.0, 0.0])
    np.testing.assert_array_equal(system.initial_state({"a": -0.5}), [-0.5, 0.1, 0.0, 0.0])
    assert system.formulation == "tree"
    assert sorted(system.param_names) == sorted([*PAPER, "a"])


@pytest.mark.parametrize("params", [None, {"c": 5.0, "m2": 2.5, "g": 3.0}])
def test_rhs_mass_matrix_and_dynamics_terms_are_the_papers(params):
    system = double_pendulum().compile()
    p = {**PAPER, **(params or {})}
    M, V, G = seed_mvg(Q, QD, **p)
    np.testing.assert_allclose(system.mass_matrix(Q, params), M, rtol=1e-13, atol=1e-14)
    for ours, paper in zip(system.dynamics_terms(Q, QD, params), (M, V, G)):
        np.testing.assert_allclose(ours, paper, rtol=1e-13, atol=1e-14)
    xdot = system.rhs(0.0, np.concatenate([Q, QD]), params)
    assert xdot.shape == (4,)
    np.testing.assert_array_equal(xdot[:2], QD)
    np.testing.assert_allclose(xdot[2:], np.linalg.solve(M, -(V + G)), rtol=1e-12)


def test_equations_are_the_symbolic_terms():
    system = double_pendulum().compile()
    eq = system.equations()
    assert set(eq) == {"M", "V", "G", "q", "qd", "p", "t", "x", "param_names", "x_names"}
    assert all(isinstance(eq[k], ca.SX) for k in ("M", "V", "G", "q", "qd", "p", "t", "x"))
    assert eq["x_names"] == [] and eq["x"].numel() == 0    # no controller states here
    assert eq["M"].shape == (2, 2) and eq["V"].shape == eq["G"].shape == (2, 1)
    f = ca.Function("terms", [eq["t"], eq["q"], eq["qd"], eq["p"]], [eq["M"], eq["V"], eq["G"]])
    p = [PAPER[name] for name in eq["param_names"]]
    for symbolic, numeric in zip(f(0.0, Q, QD, p), system.dynamics_terms(Q, QD)):
        np.testing.assert_allclose(np.array(symbolic).squeeze(), numeric, rtol=1e-14)


def test_a_vector_of_the_wrong_size_is_refused():
    system = double_pendulum().compile()
    with pytest.raises(kn.ModelError, match=r"x: expected 4 values, got shape \(3,\)"):
        system.rhs(0.0, [0.0, 0.0, 0.0])
    with pytest.raises(kn.ModelError, match="q: expected 2 values"):
        system.mass_matrix([0.0])
    with pytest.raises(kn.ModelError, match="unknown model parameter 'cc'"):
        system.rhs(0.0, np.zeros(4), {"cc": 1.0})


def test_outputs_are_the_probe_signals():
    system = double_pendulum().compile()
    assert system.signal_names == [f"probe{i}.{q}" for i in (1, 2)
                                   for q in ("angle", "speed", "acceleration", "torque")]
    x = np.concatenate([Q, QD])
    out = system.outputs([0.0], x[None, :])
    assert out.shape == (1, 8)
    M, V, G = seed_mvg(Q, QD, **PAPER)
    qdd = np.linalg.solve(M, -(V + G))
    np.testing.assert_allclose(out[0, :3], [Q[0], QD[0], qdd[0]], rtol=1e-12)
    np.testing.assert_allclose(out[0, 3], -(PAPER["c"] * Q[0] + PAPER["d"] * QD[0]))


# -- one System per model content -------------------------------------------------------------

def test_compiling_an_unchanged_model_gives_the_same_system():
    model = double_pendulum()
    system = model.compile()
    assert model.compile() is system
    model.set_parameter("c", 4.0)        # a value: parameters stay symbols in the System
    assert model.compile() is system
    np.testing.assert_allclose(system.dynamics_terms(Q, QD)[1],
                               seed_mvg(Q, QD, **{**PAPER, "c": 4.0})[1], rtol=1e-13)


def test_a_changed_component_parameter_gives_a_new_system():
    model = double_pendulum()
    system = model.compile()
    model.components["mass1"].mass = 2.0
    changed = model.compile()
    assert changed is not system
    np.testing.assert_allclose(changed.mass_matrix(Q), seed_mvg(Q, QD, **{**PAPER, "m1": 2.0})[0],
                               rtol=1e-13)
    np.testing.assert_allclose(system.mass_matrix(Q), seed_mvg(Q, QD, **PAPER)[0], rtol=1e-13)


@pytest.fixture
def compilations(monkeypatch):
    """The Systems built while the test runs (Model.compile's upcall("compile"), counted)."""
    built = []

    def counting(*args, **kwargs):
        built.append(stored.compile(*args, **kwargs))
        return built[-1]
    assert kinetwork.upcalls.UPCALLS["compile"] == ("kinetwork.equations.stored", "compile")
    monkeypatch.setattr(kinetwork.graph.model, "upcall", lambda name: counting)
    yield built


def test_simulating_a_model_twice_compiles_it_once(compilations):
    model = double_pendulum()
    first = kn.simulate(model, t_end=0.2, n_points=3)
    second = kn.simulate(model, t_end=0.2, n_points=3, params={"c": 2.0})
    assert len(compilations) == 1 and model.compile() is compilations[0]
    assert not np.allclose(first["probe1.torque"][1:], second["probe1.torque"][1:])
    model.components["spring"].d = 0.5
    kn.simulate(model, t_end=0.2, n_points=3)
    assert len(compilations) == 2
