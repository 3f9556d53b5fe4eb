"""Stopping means stopped, in every phase of a run, keeping what was reached: a cancel or a
signal while the probe signals are computed (after the integration) ends the run there with
the rows whose signals were computed, and a run stopped during the integration still gets the
probe signals of what it reached. A long grid goes to CasADi in calls of at most MAX_CHUNK
output intervals, so that stopping never waits for a call over millions of outputs."""

import os
import signal

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.equations.system import System
from kinetwork.solver import driver


@pytest.fixture
def small_chunks(monkeypatch):
    """Probe signals in chunks of 256 points (a chunk is sized by work: the seed's are small)."""
    monkeypatch.setattr(driver, "OUTPUT_CHUNK_WORK", 1.0)


def counting(monkeypatch, then=None):
    """Count the chunks of probe signals computed; ``then(count)`` after each."""
    calls = []
    original = System.outputs_into

    def outputs_into(self, *args, **kwargs):
        out = original(self, *args, **kwargs)
        calls.append(len(args[0]))
        if then is not None:
            then(len(calls))
        return out
    monkeypatch.setattr(System, "outputs_into", outputs_into)
    return calls


def test_a_cancel_while_the_probe_signals_are_computed_keeps_those_computed(
        seed_model, small_chunks, monkeypatch):
    system = seed_model.compile()
    whole = kn.simulate(system, t_end=2.0, n_points=2001, cancel=lambda: False)
    calls = counting(monkeypatch)
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(system, t_end=2.0, n_points=2001, cancel=lambda: len(calls) >= 2)
    err = info.value
    assert calls == [256, 256]
    assert err.reason == "cancelled while the probe signals were computed: kept up to " \
                         f"t = {whole.t[511]:g} s"
    part = err.results
    assert len(part.t) == 512 and err.t_reached == pytest.approx(whole.t[511], abs=1e-15)
    assert part.partial == {"t_reached": err.t_reached, "reason": err.reason}
    # the integration had finished: the rows kept are the whole run's
    np.testing.assert_allclose(part.states, whole.states[:512], rtol=1e-13, atol=1e-15)
    for name in whole.signals:
        np.testing.assert_allclose(part[name], whole[name][:512], rtol=1e-13, atol=1e-15)


def test_sigint_while_the_probe_signals_are_computed_stops_the_run_not_the_program(
        seed_model, small_chunks, monkeypatch):
    counting(monkeypatch, then=lambda n: n == 1 and os.kill(os.getpid(), signal.SIGINT))
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(seed_model, t_end=2.0, n_points=2001)
    err = info.value
    assert err.signal == signal.SIGINT and "interrupted by SIGINT while the probe" in err.reason
    assert len(err.results.t) == 256 and np.all(np.isfinite(err.results.states))
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler   # given back


def test_a_run_stopped_while_integrating_gets_the_signals_of_what_it_reached(seed_model):
    reached = []
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(seed_model, t_end=50.0, n_points=50001, progress=reached.append,
                    cancel=lambda: bool(reached) and reached[-1] > 1.0)
    err = info.value
    part = err.results
    assert err.reason == "cancelled" and 1.0 < err.t_reached < 50.0
    assert len(part.t) == len(part.states) and part.t[-1] == err.t_reached
    reference = seed_model.compile().outputs(part.t, part.states)
    names = list(part.signals)
    got = np.column_stack([part[n].reshape(len(part.t), -1) for n in names])
    np.testing.assert_allclose(got, reference, rtol=1e-13, atol=1e-15)


def test_a_long_grid_goes_in_calls_of_at_most_max_chunk_outputs(seed_model, monkeypatch):
    from kinetwork.solver import methods
    calls = []
    advance = methods._CasadiRun.advance
    monkeypatch.setattr(methods._CasadiRun, "advance",
                        lambda self, times, exact=False, out=None: calls.append(len(times))
                        or advance(self, times, exact, out))
    monkeypatch.setattr(driver, "MAX_CHUNK", 100)
    system = seed_model.compile()
    res = kn.simulate(system, t_end=2.0, n_points=1001, method="cvodes-adams", jit=False,
                      rtol=1e-8, atol=1e-10)
    assert calls == [100] * 10
    reference = kn.simulate(system, t_end=2.0, n_points=1001, method="cvodes", jit=False,
                            rtol=1e-12, atol=1e-14)
    # restarted every 100 outputs, still within the tolerance asked for
    assert np.max(np.abs(res.states - reference.states)) < 1e-6
