"""A quiet run pays nothing per run that it need not: its settings are checked once per
System and settings, the solvers' words are caught without system calls, its probe signals
are computed when first read. Every promise stays: the same fields and numbers, failures
and solver words surfaced, bad settings refused every time."""

import os
import pickle
from unittest import mock

import numpy as np
import pytest
from scenes import double_pendulum, stiff

import kinetwork as kn
from kinetwork.equations.system import System
from kinetwork.solver import plan

SETTINGS = {"t_end": 2.0, "n_points": 201, "rtol": 1e-8, "atol": 1e-10}


@pytest.fixture
def seed():
    """A System of its own (the checks and integrators kept beside it start empty)."""
    return double_pendulum().compile()


def test_settings_are_checked_once_per_system_and_settings(seed):
    with mock.patch.object(plan, "_check", wraps=plan._check) as check:
        for _ in range(4):
            kn.simulate(seed, **SETTINGS)
        assert check.call_count == 1
        kn.simulate(seed, **{**SETTINGS, "rtol": 1e-7})       # other settings: checked
        kn.simulate(seed, **SETTINGS)
        assert check.call_count == 2
        for _ in range(2):                                     # a refusal is never kept
            with pytest.raises(kn.ModelError, match="rtol"):
                kn.simulate(seed, **{**SETTINGS, "rtol": -1.0})
        assert check.call_count == 4
        with pytest.raises(kn.ModelError, match="rtol"):      # same value, another type
            kn.simulate(seed, **{**SETTINGS, "rtol": True})


def test_a_quiet_run_makes_no_system_call_to_catch_the_solvers(seed):
    kn.simulate(seed, **SETTINGS)                 # the first: JIT, integrators, checks
    with mock.patch.object(os, "dup2", wraps=os.dup2) as dup2, \
            mock.patch.object(os, "dup", wraps=os.dup) as dup, \
            mock.patch.object(os, "fstat", wraps=os.fstat) as fstat:
        for _ in range(3):
            kn.simulate(seed, **SETTINGS)
    assert dup2.call_count == dup.call_count == fstat.call_count == 0


def test_the_solvers_words_and_failures_still_surface(capfd):
    """A quiet run that fails: the error, CVODES' words in the stats and the message, the
    partial results with their probe signals (computed when read), nothing printed."""
    for _ in range(2):                    # the second from the cached integrators and checks
        with pytest.raises(kn.SimulationError) as info:
            kn.simulate(stiff(1e5), t_end=1.0, method="cvodes-adams", max_steps=50)
        err = info.value
        assert "too many steps" in err.reason and "the solver said" in str(err)
        assert "mxstep" in err.results.stats["solver_output"]
        res = err.results
        assert 0 < len(res.t) < 1001 and res["probe1.angle"].shape == res.t.shape
        np.testing.assert_allclose(res["probe1.angle"], res.states[:, 0], rtol=0, atol=1e-12)
    out, errout = capfd.readouterr()
    assert out == "" and errout == ""


def test_probe_signals_are_computed_when_first_read_and_hold(seed):
    kn.simulate(seed, **SETTINGS)
    with mock.patch.object(System, "outputs_into", autospec=True,
                           side_effect=System.outputs_into) as outputs:
        res = kn.simulate(seed, **SETTINGS)
        assert outputs.call_count == 0
        states = res.states.copy()
        res.states[:] = 0.0                  # the user's writes do not reach the signals
        angle = res["probe1.angle"]
        res["probe2.torque"]
        assert outputs.call_count == 1
    res.states[:] = states
    np.testing.assert_allclose(angle, states[:, 0], rtol=0, atol=1e-12)
    # against independent formulas: the spring-damper's torque, the equations' rates
    c, d = 1.0, 1.0
    np.testing.assert_allclose(res["probe1.torque"], -(c * states[:, 0] + d * states[:, 2]),
                               rtol=0, atol=1e-12)
    rates = np.array([seed.rhs(t, x) for t, x in zip(res.t, states)])
    np.testing.assert_allclose(res["probe2.acceleration"], rates[:, 3], rtol=1e-9,
                               atol=1e-9)
    np.testing.assert_allclose(res["probe1.speed"], states[:, 2], rtol=0, atol=1e-12)
    assert res["probe2.torque"].shape == (201,) and np.all(res["probe2.torque"] == 0.0)


def test_results_of_a_quiet_run_equal_those_computed_at_once(seed, tmp_path):
    """Every field of a quiet run (signals computed when read) against a watched run of the
    same model (a time limit: signals computed in the run, in chunks), within the
    tolerance; pickled and written as CSV as before."""
    quiet = kn.simulate(seed, **SETTINGS)
    watched = kn.simulate(seed, **SETTINGS, time_limit=600.0)
    assert quiet.keys() == watched.keys() and quiet.units == watched.units
    assert quiet.probes == watched.probes and quiet.probe_targets == watched.probe_targets
    assert quiet.settings["method"] == watched.settings["method"]
    assert {k for k in quiet.stats if not k.startswith("jit_")} <= set(watched.stats)
    for key in quiet.keys():
        np.testing.assert_allclose(quiet[key], watched[key], rtol=1e-6, atol=1e-7)
    again = pickle.loads(pickle.dumps(kn.simulate(seed, **SETTINGS)))
    for key in quiet.keys():
        np.testing.assert_allclose(again[key], quiet[key], rtol=0, atol=1e-12)
    quiet.to_csv(tmp_path / "quiet.csv")
    header, table = quiet.columns()
    back = np.loadtxt(tmp_path / "quiet.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(back, table, rtol=1e-15, atol=0)
