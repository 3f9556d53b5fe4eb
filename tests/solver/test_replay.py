"""A quiet run of a System again (same settings and parameter values) replays the recipe the
first run kept: one integrator call, nothing built, tested or looked up again, and the same
Results field for field. What a replay cannot serve goes the full way: a failure (auto's
fallback then runs as in any first run), a watched run, other parameters. A stop within a
replay keeps what it reached. The counts below are of work done, never of time."""

import gc
import signal
from unittest import mock

import casadi as ca
import numpy as np
import pytest
from scenes import chains, double_pendulum
from scenes.reference import seed_reference

import kinetwork as kn
from kinetwork.solver import compiled as compiled_module, methods, plan, replay, stiffness
from kinetwork.solver.compiled import compiled
from kinetwork.equations.system import System
from kinetwork.solver.methods import _CasadiRun
from kinetwork.solver.results import Results

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
    assert a.__dict__.keys() == b.__dict__.keys() and a.units == b.units
    assert a.state_names == b.state_names and a.probe_targets == b.probe_targets
    assert a.system is b.system and a.partial is b.partial is None


def test_a_run_again_is_one_integrator_call_and_nothing_else(seed):
    kn.simulate(seed, **SETTINGS)
    first = full(seed, **SETTINGS)
    assert len(compiled(seed)._recipes) == 1
    with mock.patch.object(replay, "_call", wraps=replay._call) as call, \
            mock.patch.object(methods.ca, "integrator", wraps=methods.ca.integrator) as build, \
            mock.patch.object(stiffness, "spectrum", wraps=stiffness.spectrum) as test, \
            mock.patch.object(_CasadiRun, "call", autospec=True,
                              side_effect=_CasadiRun.call) as stepped, \
            mock.patch.object(plan.Plan, "__init__", autospec=True,
                              side_effect=plan.Plan.__init__) as made, \
            mock.patch.object(plan.Plan, "start", autospec=True,
                              side_effect=plan.Plan.start) as started:
        again = [kn.simulate(seed, **SETTINGS) for _ in range(3)]
    assert call.call_count == 3 and build.call_count == 0 and test.call_count == 0
    assert stepped.call_count == made.call_count == started.call_count == 0
    for res in again:
        same(first, res)
    # and the answer is right: the closed-form reference, independent of kinetwork
    ref = seed_reference(again[0].t)
    assert np.max(np.abs(again[0].states[:, :2] - ref[:, :2])) < 1e-6


def counted(target, name):
    """A patch of ``target.name`` that counts its calls and does what it did."""
    return mock.patch.object(target, name, autospec=True, side_effect=getattr(target, name))


def test_a_repeated_run_converts_nothing_and_builds_nothing_again(seed):
    """After the first replay, a replay sets up no integrator call (its buffer is kept,
    bound to the recipe's start and parameters), reads no statistics from CVODES (the
    first replay's, its last state equal to the bit), converts no DM, checks no parameter
    again, and makes its Results without ``Results.__init__``; the Results are a full run's
    all the same."""
    kn.simulate(seed, **SETTINGS)
    first = full(seed, **SETTINGS)
    kn.simulate(seed, **SETTINGS)                   # the first replay: binds the buffer
    with counted(ca.Function, "buffer") as buffers, \
            counted(ca.FunctionBuffer, "set_arg") as set_arg, \
            counted(ca.FunctionBuffer, "set_res") as set_res, \
            counted(ca.FunctionBuffer, "stats") as stats, \
            counted(ca.Function, "call") as called, \
            counted(ca.DM, "full") as dms, \
            counted(System, "param_vector") as vectors, \
            counted(Results, "__init__") as made:
        again = [kn.simulate(seed, **SETTINGS) for _ in range(4)]
    assert buffers.call_count == set_arg.call_count == stats.call_count == 0
    assert called.call_count == dms.call_count == vectors.call_count == made.call_count == 0
    assert set_res.call_count == 4                  # each run's own array of states
    for res in again:
        same(first, res)
    assert len({id(r.states) for r in again}) == len({id(r.stats) for r in again}) == 4


def test_the_counts_are_read_from_the_solver_once_per_recipe(seed):
    kn.simulate(seed, **SETTINGS)
    first = full(seed, **SETTINGS)
    with counted(ca.FunctionBuffer, "stats") as stats:
        again = [kn.simulate(seed, **SETTINGS) for _ in range(3)]
    assert stats.call_count == 1
    for res in again:
        same(first, res)


def test_replayed_results_are_their_own(seed):
    """Each replay's Results own every container: writing into one changes no other."""
    kn.simulate(seed, **SETTINGS)
    a, b, c = (kn.simulate(seed, **SETTINGS) for _ in range(3))
    b.states[:] = 0.0
    b.t[:] = -1.0
    b.stats["steps"] = -1
    b.settings["rtol"] = 0.5
    b.units[b.state_names[0]] = "furlong"
    b.state_names.append("x")
    b.signals.clear()
    b.probe_targets.clear()
    same(a, c)
    assert c.units == a.units and c.state_names == a.state_names
    assert c.probe_targets == a.probe_targets and c.signals.keys() == a.signals.keys()
    name = next(iter(a.signals))
    np.testing.assert_array_equal(a[name], c[name])


def test_changed_code_reads_the_counts_again(seed):
    """A replay whose last state differs from the recorded one (another build of the code
    swapped in) reads its counts from CVODES, keeps them, and the next replay trusts them."""
    kn.simulate(seed, **SETTINGS)
    first = full(seed, **SETTINGS)
    (recipe,) = compiled(seed)._recipes.values()
    recipe.last, recipe.counts = b"another build", dict.fromkeys(replay.COUNTS, -1)
    with counted(ca.FunctionBuffer, "stats") as stats:
        same(first, kn.simulate(seed, **SETTINGS))
        same(first, kn.simulate(seed, **SETTINGS))
    assert stats.call_count == 1
    assert recipe.last == first.states[-1].tobytes()


def test_the_default_parameters_are_checked_again_when_they_change(seed):
    kn.simulate(seed, **SETTINGS)
    a = kn.simulate(seed, **SETTINGS)
    seed.model.parameters["g"] = 5.0
    b = kn.simulate(seed, **SETTINGS)
    assert not np.allclose(a.states, b.states)
    np.testing.assert_allclose(b.states, full(seed, **SETTINGS).states, rtol=0, atol=1e-12)
    seed.model.parameters["g"] = "nine"
    with pytest.raises(kn.ModelError):
        kn.simulate(seed, **SETTINGS)


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


class Tapped:
    """A recipe's integrator call (``Recipe.call``) with ``after(states)`` run after each
    real call, on the states array the call wrote into."""

    def __init__(self, recipe, after):
        self.buffer, self.trigger, self.inputs = recipe.call
        self.after, self.out = after, None
        recipe.call = (self, self.call, self.inputs)

    def set_res(self, i, view):
        self.out = view
        self.buffer.set_res(i, view)

    def stats(self):
        return self.buffer.stats()

    def call(self):
        self.trigger()
        self.after(np.frombuffer(self.out, dtype=float).reshape(-1, 4))


def tapped(system, after):
    for _ in range(2):                  # the first run keeps the recipe, a replay binds its call
        kn.simulate(system, **SETTINGS)
    (recipe,) = compiled(system)._recipes.values()
    return Tapped(recipe, after)


def test_a_failed_replay_runs_in_full_and_gives_the_full_run_s_answer(seed):
    kn.simulate(seed, **SETTINGS)
    first = full(seed, **SETTINGS)
    failures = []

    def fail(rows):
        failures.append(rows)
        raise RuntimeError("CVODES: the solver gave up (a test)")
    tapped(seed, fail)
    with mock.patch.object(_CasadiRun, "call", autospec=True,
                           side_effect=_CasadiRun.call) as stepped:
        again = kn.simulate(seed, **SETTINGS)
    assert len(failures) == 1 and stepped.call_count == 1   # the replay, then a full run
    same(first, again)


def test_a_replay_that_reached_a_non_finite_state_runs_in_full(seed):
    """Every row is checked, not only the last (which the counts are trusted by)."""
    kn.simulate(seed, **SETTINGS)
    first = full(seed, **SETTINGS)

    def spoil(rows):
        rows[100, 0] = np.nan
    tapped(seed, spoil)
    with mock.patch.object(_CasadiRun, "call", autospec=True,
                           side_effect=_CasadiRun.call) as stepped:
        again = kn.simulate(seed, **SETTINGS)
    assert stepped.call_count == 1 and np.all(np.isfinite(again.states))
    same(first, again)


def test_what_a_replay_s_solver_says_reaches_its_results(seed):
    kn.simulate(seed, **SETTINGS)
    tapped(seed, lambda rows: print("CVODES: a word at t = 0.5 (a test)"))
    res = kn.simulate(seed, **SETTINGS)
    assert "a word at t = 0.5" in res.stats["solver_output"]
    res = kn.simulate(seed, **SETTINGS)                     # and every time
    assert "a word" in res.stats["solver_output"]


def test_a_replay_past_its_step_budget_runs_in_full(seed):
    kn.simulate(seed, **SETTINGS)
    kn.simulate(seed, **SETTINGS)
    (recipe,) = compiled(seed)._recipes.values()
    recipe.budget = recipe.counts["steps"] - 1
    with mock.patch.object(_CasadiRun, "call", autospec=True,
                           side_effect=_CasadiRun.call) as stepped:
        kn.simulate(seed, **SETTINGS)
    assert stepped.call_count == 1


def test_a_stop_within_a_replay_keeps_what_it_reached(seed):
    def interrupted(rows):
        rows[50:] = np.nan              # CasADi had reached t[50] when the signal came
        signal.raise_signal(signal.SIGINT)     # the driver's handler aborts the call
    tapped(seed, interrupted)
    with pytest.raises(kn.SimulationError) as info:
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


def test_a_model_s_run_again_goes_by_its_system_s_plan_and_recipe():
    """``kn.simulate(model)`` repeated: the Model gives back its System, whose plan and
    recipe serve the run (no Plan made again), with a full run's answer."""
    model = double_pendulum()
    kn.simulate(model, **SETTINGS)
    first = full(model.compile(), **SETTINGS)
    with mock.patch.object(plan.Plan, "__init__", autospec=True,
                           side_effect=plan.Plan.__init__) as made, \
            mock.patch.object(replay, "_call", wraps=replay._call) as call:
        again = [kn.simulate(model, **SETTINGS) for _ in range(3)]
    assert made.call_count == 0 and call.call_count == 3
    for res in again:
        same(first, res)
    model.parameters["g"] = 5.0                 # a value changed: the same System, other p
    assert not np.allclose(kn.simulate(model, **SETTINGS).states, first.states)


def test_the_model_s_simulation_block_is_read_by_every_run():
    """The block's settings are a run's defaults: changed between two runs of the same
    System, the second runs by the new ones."""
    model = double_pendulum()
    system = model.compile()
    model.simulation.update(t_end=1.0, n_points=11)
    assert kn.simulate(system).t[-1] == 1.0 and len(kn.simulate(model).t) == 11
    model.simulation.update(t_end=2.0, n_points=21)
    for res in (kn.simulate(system), kn.simulate(model)):
        assert res.t[-1] == 2.0 and len(res.t) == 21
