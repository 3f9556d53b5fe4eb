"""``auto`` takes fixed-step RK4 where stability, not accuracy, holds the step (issue 30, item 3),
and Adams or BDF where they belong; each answer within its tolerance.

The scene held by stability (``scenes/follower.py``): a slow mass carrying a fast one, whose
mode of 300 rad/s is barely excited. Adams's steps are held by that mode's stability at any
loose tolerance; RK4 is stable on it at about twice the step per evaluation. Reference: DOP853
at rtol 1e-13 on the hand-written equations of the two masses. Work is counted in evaluations,
never timed.
"""

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver import explicit, stiffness
from kinetwork.solver.compiled import compiled, numeric
from scenes import chains
from scenes.follower import follower, follower_reference

T_END, POINTS = 10.0, 101


@pytest.fixture(scope="module")
def system():
    return kn.System(follower())


@pytest.fixture(scope="module")
def ref():
    return follower_reference(np.linspace(0.0, T_END, POINTS))


def within(res, ref):
    """The largest error in units of the run's tolerance, atol + rtol |x|, over all states."""
    rtol, atol = res.settings["rtol"], res.settings["atol"]
    return float(np.max(np.abs(res.states - ref) / (atol + rtol * np.abs(ref))))


@pytest.mark.parametrize("rtol", [1e-2, 1e-3])
def test_auto_takes_rk4_where_stability_holds_the_step_and_keeps_the_tolerance(system, ref,
                                                                               rtol):
    res = kn.simulate(system, t_end=T_END, n_points=POINTS, rtol=rtol, atol=rtol * 1e-2)
    adams = kn.simulate(system, t_end=T_END, n_points=POINTS, rtol=rtol, atol=rtol * 1e-2,
                        method="cvodes-adams")
    evidence = res.stats["rk4"]
    assert res.method == "rk" and res.stats["stiff"] is False
    # the step comes from RK4's stability edge on the fast mode (2.83 / 300 rad/s), below it
    assert evidence["step"] <= explicit.SAFETY * 2.83 / 300.0 * 1.01
    assert res.stats["steps"] == pytest.approx(T_END / evidence["step"], rel=1e-9)
    # fewer evaluations than Adams, whose steps that mode holds (a few per radian of it)
    assert 4 * res.stats["steps"] + evidence["trial_evaluations"] < \
        0.9 * adams.stats["rhs_evaluations"]
    assert adams.stats["rhs_evaluations"] > 2 * 300.0 * T_END
    assert within(res, ref) < 1.0
    assert within(adams, ref) < 10.0        # Adams too, for scale


def test_auto_keeps_adams_where_accuracy_holds_the_step(system, ref):
    res = kn.simulate(system, t_end=T_END, n_points=POINTS, rtol=1e-6, atol=1e-8)
    assert res.method == "cvodes-adams"
    assert res.stats["rk4"]["predicted_error"] > explicit.ERROR_SHARE
    assert within(res, ref) < 10.0      # the tolerance map's promise on 10 s scenes


def test_auto_keeps_adams_on_a_point_mass_chain_it_is_not_held_on():
    """The 16-link planar point-mass chain with its dampers: |λ|max ~ 21/s, RK4 at its stable
    step would cost about as many evaluations as Adams's floor; the output grid (0.01 s)
    caps RK4's step anyway."""
    res = kn.simulate(chains.point_masses(16), t_end=10.0, n_points=1001, rtol=1e-4,
                      atol=1e-6)
    assert res.method == "cvodes-adams"
    assert res.stats["rk4"]["rk4_evaluations"] > explicit.MARGIN * \
        res.stats["rk4"]["adams_floor"]
    assert res.stats["rhs_evaluations"] < res.stats["rk4"]["rk4_evaluations"]


def test_auto_still_takes_bdf_on_the_stiff_seed():
    res = kn.simulate(chains.stiff(1e5), t_end=2.0, n_points=201)
    assert res.method == "cvodes" and res.stats["stiff"] is True
    assert "rk4" not in res.stats


def test_a_sweep_member_gets_the_same_choice_and_answer_as_simulate(system):
    one = kn.simulate(system, t_end=T_END, n_points=POINTS, rtol=1e-3, atol=1e-5,
                      params={"slow_spring.d": 0.02})
    swept = kn.sweep(system, {"slow_spring.d": [0.02]}, t_end=T_END, n_points=POINTS,
                     rtol=1e-3, atol=1e-5, progress=False)
    assert one.method == "rk"
    assert str(swept["method"].values.ravel()[0]) == "rk"
    for name in system.state_names:
        column = one.states[:, list(system.state_names).index(name)]
        assert np.allclose(swept[name].values.ravel(), column, rtol=0, atol=1e-12)


@pytest.mark.parametrize("lam, reach", [(-1.0, 2.7853), (1j, 2.8284), (-1 + 1j, 2.5)])
def test_rk4_stable_step_is_the_edge_of_its_stability_region(lam, reach):
    h = explicit.rk4_stable_step([lam])
    z = h * lam
    assert abs(explicit._rk4_gain(z)) <= 1 + 1e-12
    assert abs(explicit._rk4_gain(z * 1.01)) > 1
    if lam in (-1.0, 1j):                   # the closed forms on the axes
        assert h == pytest.approx(reach, abs=0.01)


def test_the_matrix_free_spectrum_finds_the_dense_ones_extremes(monkeypatch):
    """Arnoldi on Jacobian-vector products (used above DENSE_STATES) against every eigenvalue
    of the dense finite-difference Jacobian, on a 32-link 3-D point-mass chain (64 states)."""
    s = kn.System(chains.point_masses(32, planar=False))
    f = numeric(compiled(s).rhs(None), s.param_vector(), s.n_states)
    x0 = np.concatenate(s.initial_full_p(s.param_vector()))
    dense = stiffness.spectrum(f, 0.0, x0)
    assert len(dense) == s.n_states
    monkeypatch.setattr(stiffness, "DENSE_STATES", 8)
    extreme = stiffness.spectrum(f, 0.0, x0)
    assert 1 <= len(extreme) <= stiffness.EXTREME
    assert np.max(np.abs(extreme)) == pytest.approx(np.max(np.abs(dense)), rel=1e-3)
    fastest = dense[np.argmax(np.abs(dense))]
    assert np.min(np.abs(extreme - fastest)) < 1e-3 * abs(fastest) or \
        np.min(np.abs(extreme - fastest.conjugate())) < 1e-3 * abs(fastest)


def test_rk4_that_blows_up_hands_the_run_to_adams(monkeypatch, ref):
    """Were the step past RK4's stability edge (here forced: 1.5 times it), the run would blow
    up: auto then runs Adams from the start, and the answer keeps its tolerance."""
    monkeypatch.setattr(explicit, "SAFETY", 1.5)
    monkeypatch.setattr(explicit, "trial_error", lambda *a: (0.0, 0))     # the trial misled
    res = kn.simulate(kn.System(follower()), t_end=T_END, n_points=POINTS, rtol=1e-3,
                      atol=1e-5)
    assert res.method == "cvodes-adams"
    assert "non-finite" in str(res.stats["adams_failure"])
    assert within(res, ref) < 10.0


def test_above_dense_states_the_spectrum_costs_fewer_evaluations_than_a_jacobian():
    """A 128-link planar point-mass chain (256 states, past DENSE_STATES): Arnoldi finds the
    fastest mode of the dense Jacobian's eigenvalues with fewer evaluations than the 2n of a
    finite-difference Jacobian (on 1024 links: 160 evaluations, where the dense eigenvalue
    problem of 2048 x 2048 took most of 44 s)."""
    s = kn.System(chains.point_masses(128))
    f = numeric(compiled(s).rhs(None), s.param_vector(), s.n_states)
    x0 = np.concatenate(s.initial_full_p(s.param_vector()))
    calls = []

    def counted(t, x):
        calls.append(1)
        return f(t, x)

    assert s.n_states > stiffness.DENSE_STATES
    extreme = stiffness.spectrum(counted, 0.0, x0)
    assert 0 < len(calls) < 2 * s.n_states
    dense = np.linalg.eigvals(stiffness._jacobian_fd(f, 0.0, x0))
    assert np.max(np.abs(extreme)) == pytest.approx(np.max(np.abs(dense)), rel=1e-3)


def test_a_mode_rate_near_overflow_gives_an_infinite_adams_floor_without_a_warning():
    """A scene about to blow up can have eigenvalues near the float's limit: the evidence says
    inf (Adams cannot keep up), and no numpy RuntimeWarning reaches the user's output (the
    suite turns warnings into errors)."""
    rate, adams = explicit.adams_floor(np.array([1e300 + 1e299j]), np.float64(1e10))
    assert rate == pytest.approx(np.hypot(1e300, 1e299))
    assert adams == np.inf
