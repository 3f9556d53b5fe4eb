"""What a studio run says it is doing (issue 29 item 7, "compile progress shown"): the
equations compiled to C while the page reads "compiling", never "integrating 0 %"; a cancel
before anything was integrated keeps nothing (the page says so), one later keeps what it
reached. The child's work (studio/work.run) is called here in this process, with a channel
that records what it is told."""

import json
import pathlib

import numpy as np

from kinetwork.solver import jit, methods
from kinetwork.studio import work

SEED = pathlib.Path(__file__).resolve().parents[2] / "models" / "double_pendulum.json"
ENGINE = SEED.parent / "engine_v6" / "EngineV6.json"


class Recorder:
    """A channel (jobs.Channel) that keeps the phases entered and the progress reported,
    and says 'cancelled' once ``cancel_when(self)`` holds."""

    def __init__(self, cancel_when=lambda channel: False):
        self.phases, self.progress, self.cancel_when = [], [], cancel_when
        self.sent = []
        self.said = []              # ("phase", name) and ("progress", fraction), in order

    def enter(self, phase):
        self.phases.append(phase)
        self.said.append(("phase", phase))

    def report(self, fraction):
        self.progress.append(fraction)
        self.said.append(("progress", fraction))

    def before_first_progress(self):
        """The phases entered before the first progress report."""
        first = next(i for i, (kind, _) in enumerate(self.said) if kind == "progress")
        return [what for kind, what in self.said[:first] if kind == "phase"]

    def cancelled(self):
        return bool(self.cancel_when(self))

    def ahead(self, part, data):
        self.sent.append((part, self.phases[-1]))


def phases_at(monkeypatch, channel, owner, name):
    """The phases the run said as each call of ``owner.name`` began: ``jit.build`` (a C
    compiler run), ``methods._CasadiRun.call`` (a CasADi integrator's)."""
    seen, real = [], getattr(owner, name)

    def spied(*args, **kwargs):
        seen.append(channel.phases[-1])
        return real(*args, **kwargs)
    monkeypatch.setattr(owner, name, spied)
    return seen


def test_the_c_compile_happens_while_the_run_says_compiling(monkeypatch, tmp_path):
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path))        # a cold cache: gcc runs
    channel = Recorder()
    seen = phases_at(monkeypatch, channel, jit, "build")
    integrating = phases_at(monkeypatch, channel, methods._CasadiRun, "call")
    state, answer = work.run(json.loads(SEED.read_text()), {"t_end": 1.0, "n_points": 11},
                             None, [], channel)
    assert state == "done"
    # the equations before any integration, the probes' outputs after it: never while the
    # page reads "integrating"
    assert seen and set(seen) <= {"compiling", "writing results"}, seen
    assert channel.phases[:3] == ["checking", "compiling", "integrating"]
    # and "integrating" once the compiled code is there, not at the first chunk's end
    assert integrating and integrating[0] == "integrating", channel.said
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


def test_a_run_whose_code_is_cached_says_integrating_as_it_integrates(monkeypatch, tmp_path):
    """EngineV6 with its System and libraries cached: "compiling" ends as the library is
    loaded, not once the first chunk is integrated (a cancel the page sent while it read
    "compiling" found the run integrating, and it kept what it reached)."""
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path))
    data = json.loads(ENGINE.read_text())
    settings = {"t_end": 0.05, "n_points": 51}
    assert work.run(data, settings, ENGINE.parent, [], Recorder())[0] == "done"    # cached
    channel = Recorder()
    seen = phases_at(monkeypatch, channel, jit, "build")
    integrating = phases_at(monkeypatch, channel, methods._CasadiRun, "call")
    assert work.run(data, settings, ENGINE.parent, [], channel)[0] == "done"
    assert not seen
    assert integrating and integrating[0] == "integrating", channel.said
    assert channel.phases[:3] == ["checking", "compiling", "integrating"]


def test_a_sweep_says_compiling_while_its_code_is_compiled(monkeypatch, tmp_path):
    """A sweep's members compile the equations to C as they start: the page reads
    "compiling" through it, then "integrating" (it read "integrating 0 %" through gcc)."""
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path))
    channel = Recorder()
    seen = phases_at(monkeypatch, channel, jit, "build")
    state, answer = work.sweep(json.loads(SEED.read_text()),
                               {"kind": "grid", "grid": {"c": [0.5, 1.0, 2.0]}}, None, [],
                               channel)
    assert state == "done", answer
    assert len(json.loads(answer)["members"]) == 3
    assert seen and set(seen) <= {"compiling", "writing results"}, seen
    assert channel.before_first_progress()[:2] == ["checking", "compiling"]
    assert channel.before_first_progress()[-1] == "integrating", channel.said
    assert channel.phases[-1] == "writing results"


def test_once_progress_is_reported_a_compile_leaves_the_run_integrating():
    """Before any progress, each C compile says "compiling" and each library ready
    "integrating"; after, the run is integrating (a cancel's grace is by phase: a compile
    in the middle of a run must not cut short the keeping of what it reached)."""
    channel = Recorder()
    phase = work._Phase(channel, "checking")
    phase.enter("compiling")
    for building in (True, False, False, True, False):
        phase.compiler(building)
    assert channel.phases == ["checking", "compiling", "integrating", "compiling",
                              "integrating"]
    phase.integrating()
    phase.compiler(True)
    phase.compiler(False)
    assert channel.phases[-1] == "integrating" and len(channel.phases) == 5
    phase.enter("writing results")
    phase.compiler(True)                        # the probes' outputs compiled at the end
    assert channel.phases[-1] == "writing results"
