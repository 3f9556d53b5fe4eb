"""Step budgets are the run's, not an output interval's, and a fallback of ``auto`` never does
much more work than the method it replaces (issue 30, item 3).

- A run succeeds exactly when it takes no more steps than its budget, whatever its number of
  output points (before, SUNDIALS' budget was per output interval: a 128-link chain with 11
  outputs ran out of steps, and auto handed it to BDF, 263 s of CPU where Adams needs 3 s;
  with 1001 outputs it passed).
- BDF after a failed Adams gives up when it does more than twice the work Adams did per
  simulated second, and says so in ``res.stats["gave_up"]``.

References: the undamped seed's energy (a conservation law), the run on another grid."""

import numpy as np
import pytest
from scenes import chains
from scenes.reference import seed_energy

import kinetwork as kn
from kinetwork.solver import driver, methods
from kinetwork.solver import stiffness as stiffness_module

LONG = 200.0


@pytest.fixture(scope="module")
def seed():
    return chains.seed().compile()


def test_a_long_run_with_three_output_points_gets_the_steps_it_needs():
    """The undamped seed over 200 s in two output intervals: more steps in each than a budget
    per interval gave (10,000 x 100^(1/5) = 25,119); the same run as on a fine grid, and its
    energy kept (no damper: a conservation law as the reference)."""
    undamped = chains.seed(d=0.0).compile()
    kw = dict(t_end=LONG, method="cvodes-adams", rtol=1e-8, atol=1e-10)
    few = kn.simulate(undamped, n_points=3, **kw)
    fine = kn.simulate(undamped, n_points=1001, **kw)
    assert few.stats["steps"] / 2 > 25_119
    assert few.stats["steps"] == pytest.approx(fine.stats["steps"], rel=0.05)
    np.testing.assert_allclose(few.states, fine.states[::500], atol=1e-6)
    energy = seed_energy(few.states, c=1.0)
    assert np.max(np.abs(energy - energy[0])) < 1e-7         # of a motion energy ~1e-2


@pytest.mark.parametrize("n_points", [2, 11, 1001])
def test_success_within_a_budget_does_not_depend_on_the_output_points(seed, n_points):
    """max_steps a fifth short of what the run takes fails on every grid, a quarter above
    succeeds on every grid (before: 1001 outputs passed where 2 failed)."""
    steps = kn.simulate(seed, t_end=20.0, n_points=201, method="cvodes-adams").stats["steps"]
    with pytest.raises(kn.SimulationError, match="step budget|too many steps"):
        kn.simulate(seed, t_end=20.0, n_points=n_points, method="cvodes-adams",
                    max_steps=int(0.8 * steps))
    res = kn.simulate(seed, t_end=20.0, n_points=n_points, method="cvodes-adams",
                      max_steps=int(1.25 * steps))
    assert res.t[-1] == 20.0 and res.stats["steps"] <= 1.25 * steps


def test_scipy_steppers_count_the_run_too(seed):
    steps = kn.simulate(seed, t_end=5.0, n_points=11, method="rk45").stats["steps"]
    for n_points in (2, 501):
        with pytest.raises(kn.SimulationError, match="step budget of"):
            kn.simulate(seed, t_end=5.0, n_points=n_points, method="rk45",
                        max_steps=int(0.8 * steps))
        kn.simulate(seed, t_end=5.0, n_points=n_points, method="rk45",
                    max_steps=int(1.25 * steps))


def test_a_fallback_slower_than_the_method_it_replaces_gives_up(seed, monkeypatch):
    """Adams made to fail (a budget of half the steps it takes); the BDF that takes over from
    the start is made slow (each of its steps counted as a thousand evaluations): it gives
    up once past twice Adams' work per simulated second, the run ends in Adams' failure, and
    ``stats`` says why. Unslowed, the same BDF finishes."""
    steps = kn.simulate(seed, t_end=20.0, n_points=201, method="cvodes-adams").stats["steps"]
    budget, count = driver.Run.budget, methods._CasadiRun._count

    def short_for_adams(self, method, interval=None):
        if getattr(method, "options", {}).get("linear_multistep_method") == "adams":
            return steps // 2
        return budget(self, method, interval)

    def slow_bdf(self, buffer, intervals):
        before = self.stats.get("steps", 0)
        count(self, buffer, intervals)
        if self.method.options.get("linear_multistep_method") != "adams":
            self.stats["rhs_evaluations"] += 1000 * (self.stats["steps"] - before)
    monkeypatch.setattr(driver.Run, "budget", short_for_adams)
    monkeypatch.setattr(methods._CasadiRun, "_count", slow_bdf)
    # the stiffness test would not pick Adams for a damped seed it called stiff: it does not
    monkeypatch.setattr(stiffness_module, "stiffness", lambda *a, **k: (False, 0.0, 0.0))
    with pytest.raises(kn.SimulationError, match="step budget") as info:
        kn.simulate(seed, t_end=20.0, n_points=201)
    res = info.value.results
    gave_up = res.stats["gave_up"]
    assert (gave_up["method"], gave_up["for"], res.settings["method"]) == \
        ("cvodes", "cvodes-adams", "cvodes-adams")
    assert "gave up" in gave_up["why"] and 0 < gave_up["at"] <= 20.0
    monkeypatch.setattr(methods._CasadiRun, "_count", count)
    res = kn.simulate(seed, t_end=20.0, n_points=201)
    assert res.method == "cvodes" and "gave_up" not in res.stats
    assert "step budget" in res.stats["adams_failure"]
