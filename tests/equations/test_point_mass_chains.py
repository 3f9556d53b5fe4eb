"""Long point-mass chains in relative coordinates: their mass matrix is positive definite with a
condition number growing as N^4, and kinetwork runs them as pinocchio does; a mass matrix that
is singular is still refused, naming the joints (``regularity.check_mass_matrix``)."""

import numpy as np
import pinocchio as pin
import pytest
from scenes import chains
from scipy.integrate import solve_ivp

import kinetwork as kn
from kinetwork.equations.regularity import singular_directions



def pinocchio_chain(spec):
    """The chain as a ``pin.Model``: joint i + 1 on ``spec.axis[i]`` at the parent's offset,
    its point mass at ``spec.r_cm[i]`` (as bench/peers/pinocchio_peer.py builds it)."""
    model = pin.Model()
    model.gravity.linear = np.asarray(spec.gravity, dtype=float)
    parent, at = 0, np.zeros(3)
    for i in range(spec.n):
        joint = pin.JointModelRevoluteUnaligned(np.asarray(spec.axis[i], dtype=float))
        parent = model.addJoint(parent, joint, pin.SE3(np.eye(3), at), f"j{i}")
        model.appendBodyToJoint(parent, pin.Inertia(float(spec.mass[i]), spec.r_cm[i].copy(),
                                                    spec.inertia[i].copy()), pin.SE3.Identity())
        at = np.asarray(spec.offset[i], dtype=float)
    return model, model.createData()


def light_tip(n):
    """A planar point-mass chain of 1 kg masses whose last one is 0.1 mg."""
    spec = chains.point_mass_spec(n)
    spec.mass[-1] = 1e-7
    return spec


@pytest.mark.parametrize("spec", [chains.point_mass_spec(200), chains.point_mass_spec(64, False),
                                  light_tip(128)], ids=["planar200", "spatial64", "light tip"])
def test_a_long_point_mass_chain_runs_and_matches_pinocchio(spec):
    """Positive definite however wide its eigenvalues spread (the light tip's smallest is
    below 1e-12 x max|M|, the bound that refused chains before), and pinocchio's
    accelerations."""
    n = spec.n
    system = chains.chain_model(spec).compile()
    values = np.linalg.eigvalsh(system.mass_matrix(spec.q0))
    assert values[0] > 0 and values[-1] / values[0] > 1e6
    model, data = pinocchio_chain(spec)
    rng = np.random.default_rng(n)
    for _ in range(3):
        q, v = rng.uniform(-0.5, 0.5, n), rng.uniform(-0.5, 0.5, n)
        ours = system.rhs(0.0, np.concatenate([q, v]))
        theirs = pin.aba(model, data, q, v, -spec.damping * v)
        np.testing.assert_allclose(ours[:n], v, rtol=0, atol=0)
        np.testing.assert_allclose(ours[n:], theirs, rtol=1e-9, atol=1e-9 * np.abs(theirs).max())


def test_the_light_tip_was_refused_by_the_bound_on_eigenvalues():
    M = chains.chain_model(light_tip(128)).compile().mass_matrix(light_tip(128).q0)
    assert np.linalg.eigvalsh(M)[0] < 1e-12 * np.abs(M).max()
    assert singular_directions(M) == []


def test_a_short_run_of_a_long_chain_matches_pinocchio_integrated_independently():
    n = 200
    spec = chains.point_mass_spec(n)
    res = kn.simulate(chains.chain_model(spec), t_end=0.2, n_points=3, rtol=1e-9, atol=1e-11)
    model, data = pinocchio_chain(spec)

    def rhs(t, x):
        q, v = x[:n], x[n:]
        return np.concatenate([v, pin.aba(model, data, q, v, -spec.damping * v)])
    x0 = np.concatenate([spec.q0, spec.qd0])
    ref = solve_ivp(rhs, (0.0, 0.2), x0, method="DOP853", rtol=1e-12, atol=1e-14, t_eval=res.t)
    assert ref.success
    np.testing.assert_allclose(res.states, ref.y.T, rtol=0, atol=1e-7)


def chain_like(n, spread):
    """A positive-definite matrix whose eigenvalues spread over ``spread`` decades."""
    rng = np.random.default_rng(n)
    Q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    return (Q * np.logspace(0, spread, n)) @ Q.T


def test_singular_directions():
    assert singular_directions(chain_like(40, 13)) == []        # wide, still regular
    M = chain_like(6, 3)
    M[2, :] = M[:, 2] = 0.0                                        # a joint moving nothing
    assert singular_directions(M) == [2]
    J = np.zeros((2, 5))
    J[0, 1] = J[0, 3] = 1.0                                       # two joints, one direction
    J[1, 0] = 1.0
    M = J.T @ J + np.diag([0, 0, 1.0, 0, 1.0])
    assert singular_directions(M) == [1, 3]


def test_a_singular_chain_is_still_refused_by_name():
    """A joint about the y axis at the start of a chain hanging along y moves nothing."""
    spec = chains.point_mass_spec(8, planar=False)
    spec.axis[3] = [0.0, 1.0, 0.0]
    with pytest.raises(kn.ModelError, match=r"singular at the initial state: j3 move\(s\) no "
                                            r"mass or inertia in the direction of j3\.qd"):
        chains.chain_model(spec).compile()
