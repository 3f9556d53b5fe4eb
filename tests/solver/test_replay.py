"""A quiet run of a System again (same settings and parameter values) replays the recipe the
first run kept: one integrator call, nothing built, tested or looked up again, and the same
Results field for field. What a replay cannot serve goes the full way: a failure (auto's
fallback then runs as in any first run), a watched run, other parameters. A stop within a
replay keeps what it reached. The counts below are of work done, never of time."""

import gc
import signal
from unittest import mock

import numpy as np
import pytest
from scenes import chains, double_pendulum
from scenes.reference import seed_reference

import kinetwork as kn
from kinetwork.solver import compiled as compiled_module, methods, plan, replay, stiffness
from kinetwork.solver.compiled import compiled
from kinetwork.solver.methods import Failure, _CasadiRun

SETTINGS = {"t_end": 2.0, "n_points": 201, "rtol": 1e-8, "atol": 1e-10}


@pytest.fixture
def seed():
    """A System of its own (its recipes, integrators and plans start empty)."""
    return double_pendulum().compile()


def full(system, **settings):
    """The run made the full way (no replay), after the first (its JIT statistics)."""
    with mock.patch.object(plan, "replay", return_value=None):
        return kn.simulate(system, **settings)


def same(a, b):
    """Two Results alike: grid, states, probe signals (equal within 1e-12: one integrator
    with the same inputs), method, settings and statistics."""
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_allclose(a.states, b.states, rtol=0, atol=1e-12)
    assert list(a.signals) == list(b.signals)
    for name in a.signals:
        np.testing.assert_allclose(a[name], b[name], rtol=0, atol=1e-12)
    assert a.settings == b.settings and a.stats == b.stats


def test_a_run_again_is_one_integrator_call_and_nothing_else(seed):
    kn.simulate(seed, **SETTINGS)
    first = full(seed, **SETTINGS)
    assert len(compiled(seed)._recipes) == 1
    calls = mock.patch.object(_CasadiRun, "call", autospec=True, side_effect=_CasadiRun.call)
    with calls as call, \
            mock.patch.object(methods.ca, "integrator", wraps=methods.ca.integrator) as build, \
            mock.patch.object(stiffness, "spectrum", wraps=stiffness.spectrum) as test, \
            mock.patch.object(plan.Plan, "__init__", autospec=True,
                              side_effect=plan.Plan.__init__) as made, \
            mock.patch.object(plan.Plan, "start", autospec=True,
                              side_effect=plan.Plan.start) as started:
        again = [kn.simulate(seed, **SETTINGS) for _ in range(3)]
    assert call.call_count == 3 and build.call_count == 0 and test.call_count == 0
    assert made.call_count == 0 and started.call_count == 0
    for res in again:
        same(first, res)
    # and the answer is right: the closed-form reference, independent of kinetwork
    ref = seed_reference(again[0].t)
    assert np.max(np.abs(again[0].states[:, :2] - ref[:, :2])) < 1e-6


def test_a_damped_chain_replays_auto_s_choice_and_its_evidence():
    """auto's stiffness test is not run again: its answer and evidence (the stats) are the
    first run's."""
    system = chains.point_masses(2, planar=False).compile()
    kw = {"t_end": 10.0, "n_points": 1001, "rtol": 1e-4, "atol": 1e-6}
    kn.simulate(system, **kw)
    first = full(system, **kw)
    with mock.patch.object(stiffness, "choose", wraps=stiffness.choose) as choose:
        again = kn.simulate(system, **kw)
    assert choose.call_count == 0 and again.stats["damped"] and "rk4" in again.stats
    same(first, again)


def test_other_parameters_or_settings_make_their_own_recipe(seed):
    kn.simulate(seed, **SETTINGS)
    kn.simulate(seed, **SETTINGS, params={"g": 9.0})
    kn.simulate(seed, **{**SETTINGS, "rtol": 1e-7})
    assert len(compiled(seed)._recipes) == 3
    a = kn.simulate(seed, **SETTINGS, params={"g": 9.0})
    b = kn.simulate(seed, **SETTINGS)
    assert not np.allclose(a.states, b.states)


def test_recipes_are_bounded(seed, monkeypatch):
    monkeypatch.setattr(compiled_module, "RECIPES_KEPT", 2)
    for g in (9.0, 9.1, 9.2, 9.3):
        kn.simulate(seed, **SETTINGS, params={"g": g})
    assert len(compiled(seed)._recipes) == 2


def test_watched_runs_are_never_replayed(seed):
    kn.simulate(seed, **SETTINGS)
    with mock.patch.object(replay, "compiled", wraps=replay.compiled) as looked:
        kn.simulate(seed, **SETTINGS, cancel=lambda: False)
        kn.simulate(seed, **SETTINGS, progress=lambda t: None)
        kn.simulate(seed, **SETTINGS, time_limit=100.0)
        kn.simulate(seed, **SETTINGS, error_estimate=True)
    assert looked.call_count == 0


def test_a_failed_replay_runs_in_full_and_gives_the_full_run_s_answer(seed):
    kn.simulate(seed, **SETTINGS)
    first = full(seed, **SETTINGS)
    original, seen = _CasadiRun.call, []

    def failing_once(self, *args, **kwargs):
        seen.append(self.run)
        if len(seen) == 1:
            raise Failure("the solver gave up (a test)", np.zeros((0, 4)))
        return original(self, *args, **kwargs)
    with mock.patch.object(_CasadiRun, "call", autospec=True, side_effect=failing_once):
        again = kn.simulate(seed, **SETTINGS)
    assert len(seen) == 2 and seen[0] is not seen[1]        # the replay, then a full run
    same(first, again)


def test_a_stop_within_a_replay_keeps_what_it_reached(seed):
    kn.simulate(seed, **SETTINGS)
    original = _CasadiRun.call

    def interrupted(self, integ, opts, times, out=None):
        rows = original(self, integ, opts, times, out)
        self.run.signal = signal.SIGINT          # as the driver's handler records one
        raise Failure(self.run.stop_reason(), rows[:50])
    with mock.patch.object(_CasadiRun, "call", autospec=True, side_effect=interrupted), \
            pytest.raises(kn.SimulationError) as info:
        kn.simulate(seed, **SETTINGS)
    err = info.value
    assert err.signal == signal.SIGINT and "interrupted by SIGINT" in err.reason
    part = err.results
    assert len(part.t) == len(part.states) == 51 and err.t_reached == pytest.approx(part.t[-1])
    ref = seed_reference(part.t)
    assert np.max(np.abs(part.states[:, :2] - ref[:, :2])) < 1e-6
    assert part[next(iter(part.signals))].shape[0] == 51


def test_results_own_their_grid(seed):
    a = kn.simulate(seed, **SETTINGS)
    a.t[:] = -1.0
    b = kn.simulate(seed, **SETTINGS)
    assert b.t[0] == 0.0 and b.t[-1] == SETTINGS["t_end"]


def reaches(start, target, depth=6):
    """Whether ``target`` is reachable from ``start`` by references, within ``depth``."""
    seen, frontier = set(), [start]
    for _ in range(depth):
        following = []
        for obj in frontier:
            if obj is target:
                return True
            if id(obj) in seen or isinstance(obj, type):
                continue
            seen.add(id(obj))
            following.extend(gc.get_referents(obj))
        frontier = following
    return any(obj is target for obj in frontier)


def test_kept_plans_and_recipes_hold_no_reference_to_their_system(seed):
    """They live in the System's own table (``compiled``), whose keys are weak: a reference
    back would keep every System alive."""
    kn.simulate(seed, **SETTINGS)
    kn.simulate(seed, **SETTINGS)
    table = compiled(seed)
    kept = list(table._checked.values()) + list(table._recipes.values())
    assert any(isinstance(v, dict) and "grid" in v for v in kept)      # a plan is among them
    assert len(table._recipes) == 1
    assert not any(reaches(v, seed) for v in kept)
