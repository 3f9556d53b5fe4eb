"""kn.linearize against the paper's closed forms and finite differences of the nonlinear
model; loops in their independent coordinates; inputs by open port or Input block."""

import json
import pathlib

import numpy as np
import pytest

import kinetwork as kn
from kinetwork import cli
from scenes import build_kinetwork, fourbar, random_mechanism, random_state

from .plants import paper_A, paper_pencil, seed_with_motor

MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"
REST = np.zeros(4)
#: a state away from rest, so that every term of A, B, C, D is exercised
MOVING = {"shoulder.q": 0.4, "elbow.q": -0.7, "shoulder.qd": 0.9, "elbow.qd": -1.3}


def sorted_eig(values):
    return np.array(sorted(values, key=lambda v: (round(v.real, 6), v.imag)))


def test_seed_at_rest_has_the_eigenvalues_of_the_paper_pencil():
    seed = kn.load(MODELS / "double_pendulum.json")
    lin = kn.linearize(seed, at=REST, outputs=["probe1.angle", "probe2.angle"])
    assert lin.state_names == ["shoulder.q", "elbow.q", "shoulder.qd", "elbow.qd"]
    assert lin.state_units == ["rad", "rad", "rad/s", "rad/s"]
    ours, paper = sorted_eig(lin.eigenvalues), sorted_eig(np.linalg.eigvals(paper_A()))
    np.testing.assert_allclose(ours, paper, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(lin.A, paper_A(), atol=1e-10)
    # other parameter values need no recompilation and still agree
    lin2 = kn.linearize(seed, at=REST, params={"c": 3.0, "m2": 2.0})
    np.testing.assert_allclose(lin2.A, paper_A(c=3.0, m2=2.0), atol=1e-10)


def finite_difference(system, X, tau, h=1e-6):
    """A, B, C, D of the nonlinear model by central differences of its own rhs and
    outputs, the torque pushed through the model parameter tau."""
    def rhs(x, u):
        return system.rhs(0.0, x, params={"tau": u})

    def out(x, u):
        return system.outputs(0.0, x[None, :], params={"tau": u})[0]
    cols = lambda f, x, u: np.column_stack(  # noqa: E731
        [(f(x + h * e, u) - f(x - h * e, u)) / (2 * h) for e in np.eye(len(x))])
    A, C = cols(rhs, X, tau), cols(out, X, tau)
    B = ((rhs(X, tau + h) - rhs(X, tau - h)) / (2 * h))[:, None]
    D = ((out(X, tau + h) - out(X, tau - h)) / (2 * h))[:, None]
    return A, B, C, D


@pytest.mark.parametrize("tau", [0.0, 0.8])
def test_torque_input_matches_finite_differences_of_the_nonlinear_model(tau):
    model = seed_with_motor()
    lin = kn.linearize(model, at=MOVING, inputs=["motor.u"], params={"tau": tau},
                       outputs=["probe1.angle", "probe2.angle", "probe2.acceleration"])
    assert lin.input_names == ["motor.u"] and lin.input_units == ["N*m"]
    assert lin.output_units == ["rad", "rad", "rad/s^2"]
    assert lin.u == pytest.approx([tau])          # the operating value: the torque replaced
    system = model.compile()
    X = np.array([MOVING[n] for n in system.state_names])
    # the outputs the probes record, in the model's own signal order
    rows = [system.signal_names.index(n) for n in lin.output_names]
    A, B, C, D = finite_difference(system, X, tau)
    np.testing.assert_allclose(lin.A, A, atol=1e-6 * np.max(np.abs(A)))
    np.testing.assert_allclose(lin.B, B, atol=1e-6 * np.max(np.abs(B)))
    np.testing.assert_allclose(lin.C, C[rows], atol=1e-6 * np.max(np.abs(C[rows])))
    np.testing.assert_allclose(lin.D, D[rows], atol=1e-6 * np.max(np.abs(D[rows])))
    assert abs(lin.D[2, 0]) > 1.0       # the acceleration feels the torque at once


@pytest.mark.parametrize("seed", [3, 4])
def test_random_trees_match_pinocchios_derivatives_of_its_forward_dynamics(seed):
    """A and B of a random spatial tree (revolute and prismatic joints on skew axes, some
    reversed) against Pinocchio's analytical derivatives of the articulated-body algorithm
    (computeABADerivatives: d qdd / d q, d qdd / d qd and M^-1), another engine."""
    import pinocchio as pin
    from equations.test_pinocchio import build_pinocchio
    links, gravity = random_mechanism(seed, 4, reversed_fraction=0.3, tree=True)
    model = build_kinetwork(links, gravity)
    j = max(i for i, link in enumerate(links) if not link.reversed)
    source = kn.rotational.Torque if links[j].kind == "revolute" else kn.translational.Force
    model.add(source("motor"))
    model.connect("motor.flange", f"j{j}.axis")
    q, qd = random_state(seed, links)
    lin = kn.linearize(model, at=np.concatenate([q, qd]), inputs=["motor.u"], outputs=[])
    pmodel = build_pinocchio(links, gravity)
    data, n = pmodel.createData(), len(q)
    pin.computeABADerivatives(pmodel, data, q, qd, np.zeros(n))
    Minv = np.triu(data.Minv) + np.triu(data.Minv, 1).T     # Pinocchio fills the upper part
    A = np.block([[np.zeros((n, n)), np.eye(n)], [data.ddq_dq, data.ddq_dv]])
    B = np.concatenate([np.zeros(n), Minv[:, j]])[:, None]
    np.testing.assert_allclose(lin.A, A, atol=1e-10 * np.max(np.abs(A)))
    np.testing.assert_allclose(lin.B, B, atol=1e-10 * np.max(np.abs(B)))


def test_input_block_is_the_same_channel_as_the_open_port():
    model = seed_with_motor()
    model.add(kn.signals.Input("tau_in", value="0.8"))
    model.connect("tau_in.y", "motor.u")
    by_block = kn.linearize(model, at=MOVING, inputs=["tau_in"], outputs=["probe2.angle"])
    by_port = kn.linearize(seed_with_motor(), at=MOVING, inputs=["motor.u"],
                           outputs=["probe2.angle"], params={"tau": 0.8})
    assert by_block.input_units == ["N*m"] and by_block.u == pytest.approx([0.8])
    np.testing.assert_allclose(by_block.A, by_port.A, atol=1e-13)
    np.testing.assert_allclose(by_block.B, by_port.B, atol=1e-13)


def test_fourbar_has_one_pair_of_eigenvalues_in_its_independent_coordinates():
    model = fourbar()
    lin = kn.linearize(model, outputs=["rocker_probe.angle"])
    system = model.compile(loops="partition")
    assert system.n_algebraic > 0 and lin.A.shape == (2, 2)
    assert len(lin.eigenvalues) == 2
    # a System compiled with Baumgarte's stabilisation is linearised in the same coordinates:
    # its stabilising eigenvalues belong to the formulation, not to the mechanism
    stabilised = kn.linearize(model.compile(loops="baumgarte"), outputs=["rocker_probe.angle"])
    np.testing.assert_allclose(stabilised.A, lin.A, atol=1e-12)
    # against central differences of the nonlinear model, whose rhs closes the loop by
    # Newton at every perturbed state (no derivative of the closure involved)
    x = system.x0
    h = 1e-6
    A = np.column_stack([(system.rhs(0, x + h * e) - system.rhs(0, x - h * e)) / (2 * h)
                         for e in np.eye(2)])
    np.testing.assert_allclose(lin.A, A, atol=1e-6 * np.max(np.abs(A)))

    def rocker(xs):
        z = system.polish(np.concatenate([xs, system.z0])[None, :], system.param_vector())
        return system.outputs(0.0, z)[0][system.signal_names.index("rocker_probe.angle")]
    C = [(rocker(x + h * e) - rocker(x - h * e)) / (2 * h) for e in np.eye(2)]
    np.testing.assert_allclose(lin.C[0], C, atol=1e-6 * np.max(np.abs(C)))


def test_at_a_time_is_the_state_the_run_reaches(monkeypatch):
    monkeypatch.setenv("KINETWORK_JIT", "0")        # the run, not the C compiler, is tested
    model = seed_with_motor()
    lin = kn.linearize(model, at=0.5, inputs=["motor.u"])
    res = kn.simulate(model, t_end=0.5, n_points=2)
    np.testing.assert_allclose(lin.x, res.states[-1], atol=1e-12)
    assert lin.t == 0.5


def test_bad_channels_are_refused_by_name():
    model = seed_with_motor()
    with pytest.raises(kn.ModelError, match=r"'motr.u'.*no component 'motr'.*'motor'"):
        kn.linearize(model, inputs=["motr.u"])
    with pytest.raises(kn.ModelError, match="'spring' is a rotational.SpringDamper"):
        kn.linearize(model, inputs=["spring"])
    with pytest.raises(kn.ModelError, match="'probe1.angel' is no probe quantity.*angle"):
        kn.linearize(model, outputs=["probe1.angel"])
    with pytest.raises(kn.ModelError, match="at: 'elbow.qq' is not a state"):
        kn.linearize(model, at={"elbow.qq": 0.0})
    model.add(kn.signals.Constant("k", k=1.0))
    model.connect("k.y", "motor.u")
    with pytest.raises(kn.ModelError, match="motor.u is wired to k.y"):
        kn.linearize(model, inputs=["motor.u"])


def test_cli_prints_the_matrices(seed_file, capsys):
    assert cli.main(["linearize", str(seed_file), "--output", "probe1.angle",
                     "--at-state", "shoulder.q=0,elbow.q=0"]) == 0
    text = capsys.readouterr().out
    assert "A:" in text and "C:" in text and "probe1.angle [rad]" in text
    assert "-23.6" in text                # -(M^-1 K)[0, 0] of the paper's pencil


@pytest.mark.parametrize("t", [0.0, 0.7])
def test_computed_torque_control_linearises_to_its_error_dynamics(t, monkeypatch):
    """arm_computed_torque cancels the arm's own dynamics (signals.InverseDynamics): at any
    state of its run the closed loop is qdd = -kp q - kd qd + (the reference's terms), so
    A = [[0, I], [-kp I, -kd I]] exactly, whatever M(q), V and G are there."""
    monkeypatch.setenv("KINETWORK_JIT", "0")
    model = kn.load(MODELS / "arm_computed_torque.json")
    lin = kn.linearize(model, at=t, outputs=[])
    kp, kd = model.parameters["kp"], model.parameters["kd"]
    I = np.eye(2)
    np.testing.assert_allclose(lin.A, np.block([[0 * I, I], [-kp * I, -kd * I]]), atol=1e-9)


def test_cli_takes_inputs_and_writes_json(tmp_path, capsys):
    path = tmp_path / "motor.json"
    seed_with_motor().save(path)
    assert cli.main(["linearize", str(path), "--input", "motor.u", "--output", "elbow.q",
                     "--at-state", "shoulder.q=0,elbow.q=0", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["inputs"] == ["motor.u"] and out["input_units"] == ["N*m"]
    M, _, _ = paper_pencil()
    # d(elbow acceleration)/d(torque at the elbow) at rest: (M^-1)[1, 1] of the paper's M
    assert out["B"][3][0] == pytest.approx(np.linalg.inv(M)[1, 1], rel=1e-12)
    assert cli.main(["linearize", str(path), "--input", "motr.u"]) == 1
