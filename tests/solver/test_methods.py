"""Every method a user can pick reaches the seed scene's closed-form solution."""

import gc

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver.compiled import numeric
from scenes import double_pendulum
from scenes.reference import seed_reference


@pytest.fixture(scope="module")
def system():
    return double_pendulum(q0=(0.8, -0.5)).compile()


#: fixed steps small enough for 2e-6 over 3 s (rk: 4th order, collocation: 5th, midpoint: 2nd)
STEPS = {"rk": 1e-3, "collocation": 1e-2, "midpoint": 5e-5}


@pytest.mark.parametrize("jit", [False, True], ids=["vm", "jit"])
@pytest.mark.parametrize("method", sorted(kn.METHODS))
def test_method_matches_closed_form(system, method, jit):
    res = kn.simulate(system, t_end=3.0, n_points=301, method=method, rtol=1e-9, atol=1e-11,
                      step=STEPS.get(method), jit=jit)
    ref = seed_reference(res.t, x0=(0.8, -0.5, 0.0, 0.0))
    ran = "cvodes-adams" if method == "auto" else method      # not stiff: Adams
    assert res.method == ran and res.settings["method"] == ran
    assert res.settings["rtol"] == 1e-9 and res.settings["jit"] is jit
    assert res.stats["jit"] is jit
    if kn.METHODS[method].fixed:
        assert res.stats["step"] <= STEPS[method]
        assert res.stats["steps"] * res.stats["step"] == pytest.approx(3.0)
    else:
        assert res.stats["rhs_evaluations"] > 0
    np.testing.assert_allclose(res.states, ref, atol=2e-6)


def test_buffered_callable_survives_garbage_collection(system):
    p = system.param_vector()
    fast = numeric(system.f_rhs, p, system.n_states)
    jac = numeric(system.jacobian_function(), p, system.n_states)
    rng = np.random.default_rng(1)
    for _ in range(10):          # a full collection is ~0.4 s in a suite's process
        junk = [np.full(64, np.nan) for _ in range(200)]      # reuse freed memory
        del junk
        gc.collect()
        x = rng.normal(size=4)
        np.testing.assert_allclose(fast(0.3, x), system.rhs(0.3, x), rtol=1e-12)
        np.testing.assert_allclose(jac(0.3, x), np.asarray(system.jacobian_function()(0.3, x, p)),
                                   rtol=1e-12)
