"""``simulate(..., progress=True)``: a tqdm bar on stderr for a run that lasts, none for a
quick one; a callable still gets the simulated times."""

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver import progress as progress_module


def test_a_quick_run_shows_no_bar(seed_model, capfd):
    kn.simulate(seed_model, t_end=0.5, n_points=51, progress=True)
    assert "%|" not in capfd.readouterr().err


def test_a_run_past_the_delay_shows_a_bar_over_its_time_span(seed_model, capfd, monkeypatch):
    monkeypatch.setattr(progress_module, "DELAY", 0.0)
    res = kn.simulate(seed_model, t_start=1.0, t_end=3.0, n_points=201, progress=True)
    err = capfd.readouterr().err
    assert "%|" in err and "of 2 s" in err and seed_model.name in err
    assert res.t[-1] == pytest.approx(3.0)


def test_the_bar_changes_no_number(seed_model):
    plain = kn.simulate(seed_model, t_end=2.0, n_points=101, progress=None)
    shown = kn.simulate(seed_model, t_end=2.0, n_points=101, progress=True)
    np.testing.assert_allclose(shown.states, plain.states, rtol=0, atol=1e-9)


def test_a_callable_still_gets_the_times_reached(seed_model):
    reached = []
    kn.simulate(seed_model, t_end=2.0, n_points=101, progress=reached.append)
    assert reached and reached == sorted(reached) and reached[-1] == pytest.approx(2.0)


def test_a_failed_run_closes_its_bar(seed_model, capfd, monkeypatch):
    monkeypatch.setattr(progress_module, "DELAY", 0.0)
    with pytest.raises(kn.SimulationError) as err:
        kn.simulate(seed_model, t_end=50.0, n_points=5001, progress=True, max_steps=2)
    assert err.value.results is not None
    assert "%|" in capfd.readouterr().err
