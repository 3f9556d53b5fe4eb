"""What a studio run says it is doing (issue 29 item 7, "compile progress shown"): the
equations compiled to C while the page reads "compiling", never "integrating 0 %"; a cancel
before anything was integrated keeps nothing (the page says so), one later keeps what it
reached. The child's work (studio/work.run) is called here in this process, with a channel
that records what it is told."""

import json
import pathlib

import numpy as np

from kinetwork.solver import jit
from kinetwork.studio import work

SEED = pathlib.Path(__file__).resolve().parents[2] / "models" / "double_pendulum.json"


class Recorder:
    """A channel (jobs.Channel) that keeps the phases entered and the progress reported,
    and says 'cancelled' once ``cancel_when(self)`` holds."""

    def __init__(self, cancel_when=lambda channel: False):
        self.phases, self.progress, self.cancel_when = [], [], cancel_when
        self.sent = []

    def enter(self, phase):
        self.phases.append(phase)

    def report(self, fraction):
        self.progress.append(fraction)

    def cancelled(self):
        return bool(self.cancel_when(self))

    def ahead(self, part, data):
        self.sent.append((part, self.phases[-1]))


def test_the_c_compile_happens_while_the_run_says_compiling(monkeypatch, tmp_path):
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path))        # a cold cache: gcc runs
    channel, seen = Recorder(), []
    real = jit.compile_functions

    def spied(*args, **kwargs):
        seen.append(channel.phases[-1])
        return real(*args, **kwargs)
    monkeypatch.setattr(jit, "compile_functions", spied)
    state, answer = work.run(json.loads(SEED.read_text()), {"t_end": 1.0, "n_points": 11},
                             None, [], channel)
    assert state == "done"
    # the equations before any integration, the probes' outputs after it: never while the
    # page reads "integrating"
    assert seen and seen[0] == "compiling" and "integrating" not in seen, seen
    assert channel.phases[:3] == ["checking", "compiling", "integrating"]
    assert channel.phases[-1] == "writing results"
    assert channel.progress and channel.progress[-1] == 1.0
    assert json.loads(answer)["results"]["t"][-1] == 1.0


def test_a_cancel_before_anything_is_integrated_keeps_nothing(monkeypatch, tmp_path):
    """Cancelled once the C compile has begun: the run ends cancelled with no results."""
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path))
    calls = []
    channel = Recorder(cancel_when=lambda c: bool(calls))
    real = jit.compile_functions

    def spied(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)
    monkeypatch.setattr(jit, "compile_functions", spied)
    state, answer = work.run(json.loads(SEED.read_text()), {"t_end": 1.0, "n_points": 11},
                             None, [], channel)
    out = json.loads(answer)
    assert calls and state == "cancelled"
    assert out["results"] is None                  # nothing integrated: nothing to plot
    assert "integrating" not in channel.phases


def test_a_cancel_while_integrating_keeps_what_it_reached():
    channel = Recorder(cancel_when=lambda c: len(c.progress) >= 2)
    state, answer = work.run(json.loads(SEED.read_text()), {"t_end": 2000.0, "n_points": 2001},
                             None, [], channel)
    out = json.loads(answer)
    assert state == "cancelled"
    t = np.asarray(out["results"]["t"], dtype=float)
    assert 1 < len(t) < 2001 and t[-1] < 2000.0
    assert out["results"]["partial"]["reason"] == "cancelled"
    assert "integrating" in channel.phases
