"""Integration failures end in a SimulationError that says when and why in plain words and
keeps everything computed up to then, which matches a correct run; the solvers' own chatter
is captured, not printed."""

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver import methods
from scenes import chain, spatial_fourbar, stiff


@pytest.fixture(scope="module")
def stiff_reference():
    """The stiff seed (c = d = 1e5) by Radau at tight tolerances: a correct run."""
    return kn.simulate(stiff(1e5), t_end=1.0, n_points=101, method="radau", rtol=1e-10,
                       atol=1e-12)


@pytest.mark.parametrize("method", ["rk45", "dop853", "cvodes-adams"])
def test_a_stiff_model_under_an_explicit_method_runs_out_of_steps(method, stiff_reference,
                                                                    capfd):
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(stiff(1e5), t_end=1.0, n_points=101, method=method, max_steps=50,
                    rtol=1e-8, atol=1e-10)
    err = info.value
    assert err.t_reached < 1.0 and f"failed after t = {err.t_reached:g} s" in str(err)
    assert "step" in err.reason
    res = err.results
    assert len(res.t) >= 1 and res.t[-1] == pytest.approx(err.t_reached)
    ref = stiff_reference.states[:len(res.t)]
    assert np.max(np.abs(res.states - ref)) < 1e-5
    out, errout = capfd.readouterr()
    assert out == "" and errout == ""          # nothing printed by the solvers


def test_the_step_budget_is_generous_enough_for_a_well_posed_run():
    """BDF takes ~550 steps here: a budget of 1000 for the run is enough, on any grid."""
    for n_points in (2, 11, 1001):
        res = kn.simulate(stiff(1e5), t_end=1.0, n_points=n_points, method="auto",
                          max_steps=1000)
        assert res.method == "cvodes" and res.t[-1] == 1.0


@pytest.mark.parametrize("method", ["cvodes-adams", "rk45"])
def test_a_time_limit_stops_the_run_and_keeps_what_it_computed(method):
    model = chain(32)
    full = kn.simulate(model, t_end=2.0, n_points=201, method=method)
    with pytest.raises(kn.SimulationError, match="time limit") as info:
        kn.simulate(model, t_end=2000.0, n_points=200001, method=method, time_limit=0.3)
    res = info.value.results
    assert 0 < res.t[-1] < 2000.0
    n = min(len(res.t), len(full.t))
    assert np.max(np.abs(res.states[:n] - full.states[:n])) < 1e-4


def test_a_dead_point_stops_the_run_by_name(capfd):
    """IDAS on the spatial four-bar with a rocker too short to go round: it reaches a dead
    point at t ~ 0.32 s. With its partition kept (``repartition=False``; by default the run
    re-partitions there and goes on) the run stops there, with the loop named, on every
    machine (the chunks of a run do not depend on its speed), and never "succeeds" past
    it."""
    for _ in range(2):                       # the same answer again (cached integrators)
        with pytest.raises(kn.SimulationError) as info:
            kn.simulate(spatial_fourbar(c=0.3), t_end=2.0, n_points=201,
                        rtol=1e-8, atol=1e-10, repartition=False)
        err = info.value
        assert "dead point" in err.reason and "singular configuration" in err.reason
        assert "rocker" in err.reason and "crank" in err.reason
        assert 0.2 < err.t_reached < 0.5
        assert len(err.results.t) == round(err.t_reached / 0.01) + 1
    out, errout = capfd.readouterr()
    assert out == "" and errout == ""


def test_a_dead_point_fails_in_one_step_budget(monkeypatch):
    """The run that ends at the four-bar's dead point (t ~ 0.3232 s, Adams crawling towards
    it in ever shorter steps) fails after one budget of steps in the interval where it
    crawls, not after several: the look that finds the step not held by stability lets that
    interval go on unlooked once (not again and again with twice the budget from the same
    state), no output is integrated again after the failure, and BDF is not tried from the
    start where stiffness is not the cause. Counted in integrator calls and their step
    budgets (before: 7 calls, 264,285 steps of budget; now 2 calls, 68,095)."""
    calls = []
    call = methods._CasadiRun.call

    def counted(self, integ, opts, times, out=None):
        calls.append((self.method.plugin, opts.get("linear_multistep_method"),
                      opts.get("max_num_steps")))
        return call(self, integ, opts, times, out)
    monkeypatch.setattr(methods._CasadiRun, "call", counted)
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(spatial_fourbar(c=0.3), t_end=2.0, n_points=201, rtol=1e-8, atol=1e-10,
                    repartition=False)
    err = info.value
    assert "dead point" in err.reason and "BDF was not tried" in err.reason
    assert err.results.method == "cvodes-adams" and 0.3 < err.t_reached < 0.33
    assert len(calls) == 2 and all(c[1] == "adams" for c in calls)
    assert calls[1][2] > calls[0][2]            # the look's budget, then the run's own
    assert sum(c[2] for c in calls) < 1.2 * calls[1][2]


def _blow_up():
    """x' = x^2 from x = 1: the solution ends at t = 1 (x = 1 / (1 - t))."""
    m = kn.Model("blowup")
    for c in (kn.signals.Integrator("x", y_start=1.0), kn.signals.Product("sq")):
        m.add(c)
    for a, b in [("x.y", "sq.u1"), ("x.y", "sq.u2"), ("sq.y", "x.u")]:
        m.connect(a, b)
    return m


def test_a_solution_that_ends_costs_auto_one_step_budget(monkeypatch, capfd):
    """x' = x^2 ends at t = 1: auto's Adams crawls towards it; the look finds its step not
    held by stability, lets the interval go on unlooked once, and the run fails there
    after one budget of steps, without BDF from the start (before: the doubled look
    budgets from the same state, the interval again output by output, then BDF: five
    calls more). The outputs up to then are kept and right."""
    calls = []
    call = methods._CasadiRun.call

    def counted(self, integ, opts, times, out=None):
        calls.append(opts.get("max_num_steps"))
        return call(self, integ, opts, times, out)
    monkeypatch.setattr(methods._CasadiRun, "call", counted)
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(_blow_up(), t_end=2.0, n_points=201)
    err = info.value
    assert "too many steps" in err.reason and "BDF was not tried" in err.reason
    assert err.results.method == "cvodes-adams" and len(calls) == 2
    res = err.results
    assert 0.98 < res.t[-1] < 1.0
    # (the global error grows as the solution does: 5e-5 at x = 100, rtol 1e-6)
    np.testing.assert_allclose(res.states[:, 0], 1 / (1 - res.t), rtol=2e-4)
    out, errout = capfd.readouterr()
    assert out == "" and errout == ""


def test_the_solvers_own_words_join_the_message(capfd):
    """Adams on a stiff spring with a small step budget: CVODES says what ran out."""
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(stiff(1e5), t_end=1.0, method="cvodes-adams", max_steps=50)
    err = info.value
    assert "too many steps" in err.reason and "the solver said" in str(err)
    assert "mxstep" in err.results.stats["solver_output"]
    out, errout = capfd.readouterr()
    assert out == "" and errout == ""


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "10"])
def test_bad_budgets_are_refused(bad):
    with pytest.raises(kn.ModelError, match="max_steps: must be a positive integer"):
        kn.simulate(stiff(1e5), t_end=0.1, max_steps=bad)
    if bad not in (2.5,):
        with pytest.raises(kn.ModelError, match="time_limit: must be a positive number"):
            kn.simulate(stiff(1e5), t_end=0.1, time_limit=bad if bad != 2.5 else -1)
