"""The work of a run with many state events (``solver/events.py``), counted, not timed:
EngineV6 (MSL's six-cylinder engine, six loops, 18 relations on the pistons' positions:
about 330 event instants in its 1.01 s), where each event is located on the points of the
chunk's own integration and the chunks of the run end near the next event; and its event
times against a run at a tolerance a thousand times tighter."""

import collections
from pathlib import Path

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver import events as events_module
from kinetwork.solver import methods

MODEL = Path(__file__).resolve().parents[2] / "models" / "engine_v6" / "EngineV6.json"


def instants(res):
    """The run's event times, events closer than 1e-8 s taken as one instant (two relations
    of cylinders in line cross together, and are one event or two by rounding)."""
    t = np.sort([e["t"] for e in res.stats["events"]])
    return t[np.concatenate([[True], np.diff(t) > 1e-8])]


@pytest.fixture(scope="module")
def engine():
    return kn.load(MODEL).compile()


@pytest.fixture(scope="module")
def counted(engine):
    """One run of EngineV6 with its work counted: (Results, counts)."""
    count = collections.Counter()
    patches = pytest.MonkeyPatch()
    originals = {}

    def counting(owner, name, label, covered=False):
        original = originals[label] = getattr(owner, name)

        def wrapped(self, *args, **kwargs):
            count[label] += 1
            if covered:             # the model time an integrator call goes over
                times = args[2]
                count["covered"] += float(times[-1]) - self.t
            return original(self, *args, **kwargs)
        patches.setattr(owner, name, wrapped)
    counting(methods._CasadiRun, "call", "calls", covered=True)
    counting(methods._CasadiRun, "grid", "grids")
    counting(methods._CasadiRun, "state_at", "state_at")
    counting(events_module.Events, "_locate", "located")
    counting(events_module.Events, "levels", "levels")
    counting(events_module.Events, "indicators", "indicators")
    evaluations = collections.Counter()
    for name in ("call", "grid"):           # over the chunks; over a sampled interval
        original = getattr(methods._CasadiRun, name)

        def tallied(self, *args, _original=original, _name=name, **kwargs):
            before = self.stats.get("rhs_evaluations", 0)
            try:
                return _original(self, *args, **kwargs)
            finally:
                evaluations[_name] += self.stats.get("rhs_evaluations", 0) - before
        patches.setattr(methods._CasadiRun, name, tallied)
    try:
        res = kn.simulate(engine)
    finally:
        patches.undo()
    return res, count, evaluations


def test_each_event_is_located_on_the_runs_own_points_and_a_few_indicator_values(counted):
    """Per event located: no integration of its own (the chunks after an event or cut short
    where the indicators foresee one give DENSE points in each sampled interval,
    interpolated by CVODES at no evaluation more; before, one integration over the sampled
    interval cost 41 evaluations an event, 26 % of the run's), but in the first chunk, which
    starts at no event; none from the point before (the curve fits on the step the time is
    read off), and fewer than four evaluations of the indicators (a Brent search on the
    whole interval took 19.6, and 16.7 of the indicators with their rates, which read the
    whole equations). The run's statistics count the evaluations of both kinds."""
    res, count, evaluations = counted
    located = count["located"]
    assert len(instants(res)) > 300 and located >= len(res.stats["events"]) - 10
    assert count["grids"] <= 2 and count["state_at"] == 0
    assert res.stats["rhs_evaluations"] == evaluations["call"] + evaluations["grid"]
    assert count["levels"] <= 4 * located
    # the indicators with rates: once where the run goes on after each event, and about ten
    # for each dip searched by Brent's method on its rate (one or two a run)
    assert count["indicators"] <= located + 30


def test_chunks_end_near_the_next_event(counted):
    """The chunks after each event reach about as far as the indicators foresee the next
    one: the integrator calls go over at most 1.5 times the run's 1.01 s of model time (2.9
    times when each went EVENT_CHUNK output intervals: two thirds of the work thrown away
    past an event), about one call per event."""
    res, count, _ = counted
    assert count["covered"] <= 1.5 * 1.01
    assert count["calls"] <= 1.1 * len(res.stats["events"])


def test_event_times_agree_with_a_run_a_thousand_times_tighter(counted, engine):
    """The event instants of the default run (rtol 1e-6) within 1e-8 s of those of a run at
    rtol 1e-9 (measured: 3e-9 s), the same instants."""
    res, _, _ = counted
    tight = kn.simulate(engine, rtol=1e-9, atol=1e-11)
    a, b = instants(res), instants(tight)
    assert len(a) == len(b)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-8)


def test_a_forecast_that_keeps_falling_short_does_not_cut_every_chunk():
    """An indicator nearing zero without crossing it (a tangency, a stuck friction's margin
    at rest) foresees a crossing one output interval ahead at every chunk: the chunks the
    forecast cuts short, meeting no event, double (1, 2, 4, ... up to the rule's own),
    so such a stretch costs a few integrator calls, not one per interval; after an event the
    forecast holds again."""
    ev = events_module.Events.__new__(events_module.Events)
    ev.run = type("Run", (), {"spacing": 0.01})()
    ev._chunk, ev._cut = events_module.EVENT_CHUNK, 0
    lengths, t = [], 0.0
    for _ in range(8):
        ev._foreseen = t + 0.005                 # always half an interval ahead
        lengths.append(ev.chunk(1000, False, t))
        t += lengths[-1] * 0.01
    assert lengths == [1, 2, 4, 8, 16, 32, 64, 128]
    ev._foreseen = t + 0.025
    assert ev.chunk(1000, True, t) == 3


def test_the_loops_watch_reads_the_conditioning_block_by_block(engine, monkeypatch):
    """The loops' watch reads the condition number and determinant of the Jacobian in the
    dependent speeds at every output: EngineV6's 18 x 18 is its six loops' 3 x 3 blocks,
    taken apart by their sparsity; by blocks, the same numbers as the whole matrix's (to
    1e-10 relative), at a 36th of the operations."""
    from kinetwork.equations.system import pointwise
    from kinetwork.solver import loopwatch
    assert [b.shape for b in loopwatch._blocks(engine)] == [(6, 3)]
    seen = []
    conditioning = loopwatch.Partitions._conditioning

    def both(self, rows):
        cond, det = conditioning(self, rows)
        f = self.run.system.f_dependent
        n = f.size1_out(0)
        J = pointwise(f, rows, self.run.p)[0].reshape(len(rows), n, n).transpose(0, 2, 1)
        s = np.linalg.svd(J, compute_uv=False)
        seen.append((cond, det, s[:, 0] / s[:, -1], np.linalg.det(J)))
        return cond, det
    monkeypatch.setattr(loopwatch.Partitions, "_conditioning", both)
    kn.simulate(engine, t_end=0.05, n_points=51)
    assert len(seen) > 3
    for cond, det, whole_cond, whole_det in seen:
        np.testing.assert_allclose(cond, whole_cond, rtol=1e-10)
        np.testing.assert_allclose(det, whole_det, rtol=1e-10)
