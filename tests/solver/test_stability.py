"""Where methods fail, pinned: stiffness, long undamped runs, chaos, and the cost of big models.

These tests assert behaviour (who fails, what drifts, how cost grows), never wall time. The
references are independent of kinetwork: the seed paper's closed form (bench/reference.py).
"""

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver import stiffness as stiffness_module
from kinetwork.solver.stiffness import stiffness
from scenes import chain, double_pendulum   # chain: n uniform rods on revolute z joints
from scenes.reference import PAPER, seed_energy, seed_mvg, seed_reference


def _stiffness(system):
    """The stiffness test of ``auto`` on the system's own right-hand side, at x0."""
    rhs = lambda t, x: system.rhs(t, x)  # noqa: E731
    return stiffness(rhs, 0.0, 10.0, system.x0)


def seed(q0=(0.05, 0.05), **params):
    return double_pendulum(q0=q0, probes=False, **params).compile()


# ---------------------------------------------------------------------------------------------
# Stiffness: a shoulder spring-damper 10^4..10^6 times stiffer
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("k, stiff", [(1.0, False), (1e4, True), (1e5, True), (1e6, True)])
def test_stiffness_test_finds_the_hard_damped_spring(k, stiff):
    system = seed(c=k, d=k)
    found, sigma, omega = _stiffness(system)
    assert found is stiff
    if stiff:
        # the overdamped shoulder mode decays at about d / m_eff, the shoulder's effective
        # inertia with the elbow free being 1 / (M^-1)_11 (closed-form M of the paper)
        M = seed_mvg((0.05, 0.05), (0, 0), **{**PAPER, "c": k, "d": k})[0]
        assert sigma == pytest.approx(k * np.linalg.inv(M)[0, 0], rel=0.01)


@pytest.mark.parametrize("build", [lambda: chain(16).compile(),
                                   lambda: seed(q0=(2.5, 2.0), d=0.0)], ids=["chain16", "chaotic"])
def test_undamped_mechanisms_are_never_stiff(build):
    system = build()
    found, sigma, omega = _stiffness(system)
    assert not found
    assert sigma <= omega * (1 + 1e-6)          # eigenvalues in +-lambda pairs


def test_auto_skips_the_test_on_undamped_models(monkeypatch):
    monkeypatch.setattr(stiffness_module, "stiffness", None)     # calling it would fail
    res = kn.simulate(chain(4), t_end=1.0)
    assert res.method == "cvodes-adams"
    assert res.stats["stiff"] is False and res.stats["damped"] is False


def test_auto_solves_the_stiff_scene_with_bdf_untuned():
    k = 1e5
    system = seed(c=k, d=k)
    res = kn.simulate(system, t_end=2.0, n_points=201)
    assert res.method == "cvodes" and res.stats["stiff"] is True
    ref = seed_reference(res.t, c=k, d=k, method="Radau", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.states[:, :2], ref[:, :2], atol=1e-5)
    assert res.stats["steps"] < 2000


@pytest.mark.parametrize("method, step", [("cvodes", None), ("idas", None), ("radau", None),
                                          ("bdf", None), ("lsoda", None),
                                          ("collocation", 0.01), ("midpoint", 0.001)])
def test_implicit_methods_take_the_stiffest_scene_in_stride(method, step):
    k = 1e6
    res = kn.simulate(seed(c=k, d=k), t_end=1.0, n_points=101, method=method, step=step)
    ref = seed_reference(res.t, c=k, d=k, method="Radau", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.states[:, :2], ref[:, :2], atol=1e-4)


def test_adams_fails_on_the_stiffest_scene_and_auto_falls_back(monkeypatch):
    k = 1e6
    system = seed(c=k, d=k)
    with pytest.raises(kn.SimulationError, match="too many steps") as err:
        kn.simulate(system, t_end=0.2, n_points=21, method="cvodes-adams")
    assert err.value.t_reached < 0.2
    # were the stiffness test to miss it, the failure of Adams still hands over to BDF
    monkeypatch.setattr(stiffness_module, "stiffness", lambda *a, **k: (False, 0.0, 0.0))
    res = kn.simulate(system, t_end=0.2, n_points=21)
    assert res.method == "cvodes" and "too many steps" in res.stats["adams_failure"]


def test_explicit_fixed_step_blows_up_on_stiffness_and_keeps_what_it_had():
    system = seed(c=1e4, d=1e4)
    # RK4 is stable for h |lambda| < 2.79; here h |lambda| = 0.01 * 4e3 = 40
    with pytest.raises(kn.SimulationError, match="non-finite") as err:
        kn.simulate(system, method="rk", step=0.01)
    partial = err.value.results
    assert 0 < err.value.t_reached < 1.0 and len(partial.t) >= 1
    assert np.all(np.isfinite(partial.states))


def test_explicit_adaptive_methods_pay_for_stiffness_in_steps():
    system = seed(c=1e4, d=1e4)
    explicit = kn.simulate(system, t_end=1.0, method="rk45")
    implicit = kn.simulate(system, t_end=1.0, method="radau")
    ref = seed_reference(explicit.t, c=1e4, d=1e4, method="Radau", rtol=1e-12, atol=1e-12)
    for res in (explicit, implicit):      # both right, ...
        np.testing.assert_allclose(res.states[:, :2], ref[:, :2], atol=1e-4)
    # ... but the explicit one only by steps of the stability limit, 2.8 / 4e3 s
    assert explicit.stats["rhs_evaluations"] > 20 * implicit.stats["rhs_evaluations"]


# ---------------------------------------------------------------------------------------------
# Long undamped runs: the symplectic midpoint rule against Runge-Kutta
# ---------------------------------------------------------------------------------------------

def relative_energy_error(res):
    E = seed_energy(res.states, d=0.0)
    return np.abs(E - E[0]) / abs(E[0])


def test_midpoint_keeps_energy_bounded_where_runge_kutta_drifts():
    system = seed(q0=(0.5, 0.3), d=0.0)
    kw = dict(t_end=300.0, n_points=601, step=0.02)
    mid = relative_energy_error(kn.simulate(system, method="midpoint", **kw))
    rk4 = relative_energy_error(kn.simulate(system, method="rk", **kw))
    t = np.linspace(0, 300, 601)
    early, late = t <= 30, t >= 200
    # bounded: the last 100 s are no worse than the first 30 s
    assert mid[late].max() < 1.2 * mid[early].max()
    assert mid.max() < 1e-4
    # drifting: the same step in RK4 loses energy steadily
    assert rk4[late].max() > 5 * rk4[early].max()
    assert np.all(np.diff(rk4[::60]) > 0)


def test_midpoint_is_second_order_and_symplectic_steps_report_failure():
    system = seed(q0=(0.8, -0.5))
    ref = seed_reference(np.linspace(0, 1, 11), x0=(0.8, -0.5, 0, 0))
    errors = [np.abs(kn.simulate(system, method="midpoint", t_end=1.0, n_points=11,
                                 step=h).states - ref).max() for h in (0.01, 0.005)]
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.15)
    # a step far too large for a violent motion: Newton cannot converge, said in plain words
    with pytest.raises(kn.SimulationError, match="smaller step") as err:
        kn.simulate(seed(q0=(1.0, 0.5), d=0.0), method="midpoint", t_end=20.0, n_points=101,
                    step=0.2)
    assert len(err.value.results.t) >= 2


# ---------------------------------------------------------------------------------------------
# Chaos: the global error grows exponentially whatever the tolerance
# ---------------------------------------------------------------------------------------------

def test_chaotic_error_grows_exponentially_at_any_tolerance():
    system = seed(q0=(2.5, 2.0), d=0.0)
    t = np.linspace(0, 20, 2001)
    ref = seed_reference(t, x0=(2.5, 2.0, 0, 0), d=0.0)
    growth = {}
    for rtol in (1e-6, 1e-10):
        res = kn.simulate(system, t_end=20.0, n_points=2001, rtol=rtol, atol=rtol * 1e-2)
        err = np.maximum.accumulate(np.abs(res.states[:, :2] - ref[:, :2]).max(axis=1))
        growth[rtol] = err
        assert err[t <= 1].max() < 1e3 * rtol          # controlled at first ...
        assert err[-1] > 1e4 * err[t <= 1].max()         # ... then amplified 10^4-fold
    # a tighter tolerance only buys time: useless (> 0.01 rad) later, but still useless
    useless = {r: t[np.argmax(e > 1e-2)] if (e > 1e-2).any() else np.inf
               for r, e in growth.items()}
    assert useless[1e-6] < useless[1e-10]


# ---------------------------------------------------------------------------------------------
# Model no more than the scene needs: O(N) equations, cheap builds
# ---------------------------------------------------------------------------------------------

def test_right_hand_side_grows_linearly_with_the_chain():
    sizes = {n: chain(n).compile().size() for n in (8, 16, 32, 64, 128)}
    ns = np.array(list(sizes))
    ops = np.array([s["operations"] for s in sizes.values()])
    slope = np.polyfit(np.log(ns), np.log(ops), 1)[0]
    assert slope <= 1.1                     # articulated-body algorithm: O(N) ...
    per_link = np.diff(ops) / np.diff(ns)
    np.testing.assert_allclose(per_link, per_link[0], rtol=0.01)   # ... exactly: a + b N
    assert all(s["states"] == 2 * n and s["algebraic"] == 0 for n, s in sizes.items())
