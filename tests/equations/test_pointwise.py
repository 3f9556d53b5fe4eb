"""``pointwise``: a Function evaluated at every point of a run through its map and buffers, in
calls of POINTS_PER_CALL points, equal to evaluating it point by point."""

import casadi as ca
import numpy as np
import pytest
from scenes import double_pendulum

import kinetwork as kn
from kinetwork.equations import pointwise as pointwise_module
from kinetwork.equations.pointwise import pointwise


def function():
    t, x, p = ca.SX.sym("t"), ca.SX.sym("x", 3), ca.SX.sym("p", 2)
    column = ca.vertcat(x[0] * p[0] + t, x[2] * x[1], ca.sin(x[1]) * p[1])
    column = ca.SX(ca.Sparsity.triplet(4, 1, [0, 1, 3], [0, 0, 0]), column)    # a zero row
    matrix = ca.horzcat(ca.vertcat(x[0], t), ca.vertcat(p[1], x[2] ** 2))
    return ca.Function("f", [t, x, p], [column, matrix])


@pytest.mark.parametrize("n", [1, 5, 63, 64, 65, 200])
def test_every_point_as_one_by_one(n, monkeypatch):
    monkeypatch.setattr(pointwise_module, "POINTS_PER_CALL", 64)       # calls and a remainder
    f, rng = function(), np.random.default_rng(n)
    T, X, p = rng.normal(size=n), rng.normal(size=(n, 3)), np.array([0.5, -2.0])
    column, matrix = pointwise(f, T[:, None], X, p)
    assert column.shape == (n, 4) and matrix.shape == (n, 4)
    for k in range(n):
        a, b = f(T[k], X[k], p)
        np.testing.assert_array_equal(column[k], np.asarray(a).ravel())
        np.testing.assert_array_equal(matrix[k], np.asarray(b).ravel(order="F"))


def test_probe_outputs_of_a_long_run_are_those_of_each_point(monkeypatch):
    monkeypatch.setattr(pointwise_module, "POINTS_PER_CALL", 100)
    system = double_pendulum().compile()
    res = kn.simulate(system, t_end=2.0, n_points=1234, jit=False)
    p = system.param_vector()
    for k in (0, 99, 100, 617, 1233):
        one = np.asarray(system.f_out(res.t[k], res.states[k], p)).ravel()
        np.testing.assert_allclose(
            np.concatenate([np.ravel(res[name][k]) for name in system.signal_names]), one,
            rtol=1e-14, atol=1e-14)
