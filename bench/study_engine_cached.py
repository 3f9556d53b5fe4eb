"""EngineV6 cached: where a repeated run of MSL's six-cylinder engine spends its CPU time.

``models/engine_v6/EngineV6.json`` (six kinematic loops, the gas force of each cylinder a
relation on its piston's position: 337 state events in the default 1.01 s run) compiled once
and run once beforehand, then run again in rounds, in one process: CPU time
(``time.process_time``) per run, medians, with two ways of keeping the integrators interleaved:

- ``kept``: as kinetwork keeps them now (``compiled.integrators_kept``: as many as the run
  has chunks of their own grid, one after each event);
- ``64 kept``: at most 64 per System (``compiled.INTEGRATORS_MOST = 64``), as before: every
  run built its event chunks' integrators again.

Per way, what the run spent: integrators built and the time to build them, the integrator
calls over the chunks (``_CasadiRun.call``), the locating of the events (``Events._locate``:
the curves, their checks on the equations, Brent's method, the integrations to 32 points),
the rest (indicators on the sampled rows, the loops' watch, the driver's Python), the
right-hand-side evaluations (those of the integrations that locate events included) and the
events. The event times of both ways agree (the largest
difference is printed).

And the work, the same on every machine: the model time the integrator calls go over (the
run's 1.01 s and what is integrated again after an event), and per event located the
integrations over a sampled interval (``_CasadiRun.grid``), the curves checked against the
equations (``_Hermite.fits`` through two sampled rows; ``_Steps.fits``, the one step of the
curve through the 33 points of an integration the time is read off), and the indicators
evaluated one point at a time (alone, ``Events.levels``, and with their rates,
``Events.indicators``, which read the whole equations).

And the studio's run of the same model (``studio/work.run``, what ``POST /api/run`` has a
child do): each in a child forked from this process once it is warmed as the studio's
forkserver is (``jobs.PRELOAD`` imported, which runs ``warm``) and before it compiles EngineV6
itself, so that the child has only what a studio child has; the first child fills the JIT
cache on disk and is not counted. Its CPU time by phases: checking the model, compiling it
(the C code from the cache), integrating, writing the results (the probes' signals, the 3-D
view's poses, the JSON the page reads).

And the same run through the studio as the page makes it (``studio_walls``): ``kinetwork
studio`` in a copy of models/, wall time from ``POST /api/run`` to the bytes of the answer
that says it has ended (results, 3-D poses and all).

Writes ``results/study_engine_cached.md``. Run: ``python bench/study_engine_cached.py
[--rounds R]``.
"""

import argparse
import collections
import importlib
import json
import os
import statistics
import time
from unittest import mock

import numpy as np

import common
from common import load, machine, table, write_markdown

import kinetwork as kn
from kinetwork.solver import compiled as compiled_module, curves, events, methods

NAME = "study_engine_cached"
#: what earlier rounds measured, for comparison (the same study, other code)
HISTORY = """Earlier: 2026-11-28, load 16.8: 4.46 s (kept), locating 2.11 s, integrator calls
0.89 s, rest 1.21 s. 2026-11-29 before the events' round (issue 30 item 6), load 4.2: 4.62 s,
locating 2.45 s, integrator calls 1.03 s, rest 1.40 s; per event 1.00 integration over a
sampled interval, 1.00 two-row and 1.00 33-point curves checked, 19.6 + 16.7 trial times.
2026-11-29 after that round, load 5.3: 3.88 s (kept), locating 1.85 s (339 events), integrator
calls 1.07 s (351, 72186 evaluations, the 13962 of the locating integrations not counted),
rest 0.98 s; the calls covered 2.95 s of model time (each chunk after an event went 8 output
intervals; the next event came after about 3): two thirds of the integration thrown away.
2026-11-29, last round's code, load 1.0: 1.59 s (kept), on another machine (the machine line
did not name the processor then): the same code on AMD EPYC family 26 model 2, load 3.6-4.3,
alternating processes of 7 runs, 4 each: 0.57 s (medians 0.547-0.613; 52863 evaluations, 352
integrator calls and 339 over a sampled interval), this round's 0.48 s (0.474-0.516; 38997
evaluations, 349 calls, 1 over a sampled interval: the events located on the chunks' own
points, the loops' watch compiled). The studio's child then: 1.67 s (integrating 0.97), load
4.9; its warm-up had failed since simulate moved to solver/plan.py (children started cold).
Then (idle machine, load 1.0): 0.41 s (kept), the studio's child 1.16 s (checking 0.04,
compiling 0.16, integrating 0.65, writing results 0.31), after CasADi's clock was skipped in
kinetwork's sections (solver/casadi_clock.py), the poses of the studio's answer rounded to
1e-7 of the scene and Python's collector paused while it is built (writing results 0.62 ->
0.31 s, the 11.5 MB answer 6.1 MB), the studio's 'compiling' lasting until the integration
first reports (its first chunk included). Of the child's integrating, ~0.18 s built its 349
integrators, one per chunk's output grid (a chunk after an event starts with a head of its
own step; a fresh child keeps none). In a new process (import, build, first run; Brent's
method of kinetwork's own, no scipy.optimize imported): 1.15-1.16 s of CPU, 1.46-1.59 before.
This table's round: a chunk's own grid gets an integrator on the equations with their
derivatives hidden (0.39 -> 0.14 ms of CPU each), the System is kept with its relations (0.07
s a process), the answer written by orjson from numpy arrays (0.13 -> 0.011 s) and the poses
through maps of 256 points (0.06 -> 0.015 s the first time)."""
MODEL = common.HERE.parent / "models" / "engine_v6" / "EngineV6.json"


def timed_parts():
    """Patches that add the CPU time and count of the phases of a run into a Counter pair."""
    spent, count = collections.Counter(), collections.Counter()

    def wrap(owner, name, label):
        original = getattr(owner, name)

        def timed(*args, **kwargs):
            if label == "integrate":        # the model time the call goes over
                count["covered"] += float(args[3][-1]) - args[0].t
            start = time.process_time()
            try:
                return original(*args, **kwargs)
            finally:
                spent[label] += time.process_time() - start
                count[label] += 1
        return mock.patch.object(owner, name, timed)
    patches = [wrap(methods.ca, "integrator", "build"),
               wrap(methods._CasadiRun, "call", "integrate"),
               wrap(events.Events, "_locate", "locate"),
               wrap(methods._CasadiRun, "grid", "grid"),
               wrap(events.Events, "levels", "levels"),
               wrap(events.Events, "indicators", "indicators")]
    fits, dense_fits = curves.Hermite.fits, curves.Steps.fits
    inside = []

    def counted(self, rates, tol, step=None):
        if not inside:                  # a curve through two sampled rows
            count["fits", True] += 1
        return fits(self, rates, tol, step)

    def counted_dense(self, rates, tol, step):
        count["fits", False] += 1      # a step of the curve through an integration's points
        inside.append(True)
        try:
            return dense_fits(self, rates, tol, step)
        finally:
            inside.pop()
    patches += [mock.patch.object(curves.Hermite, "fits", counted),
                mock.patch.object(curves.Steps, "fits", counted_dense)]
    return patches, spent, count


def run_once(system, most, parts=False):
    """One run with at most ``most`` integrators kept: (CPU s, Results, phases or None)."""
    with mock.patch.object(compiled_module, "INTEGRATORS_MOST", most):
        if not parts:
            start = time.process_time()
            res = kn.simulate(system)
            return time.process_time() - start, res, None
        patches, spent, count = timed_parts()
        for p in patches:
            p.start()
        try:
            start = time.process_time()
            res = kn.simulate(system)
            total = time.process_time() - start
        finally:
            for p in patches:
                p.stop()
        return total, res, (spent, count)


class _Channel:
    """What a studio child reports through (``jobs.Channel``), kept: the CPU time at which
    each phase begins."""

    def __init__(self):
        self.start, self.phases = time.process_time(), []

    def enter(self, phase):
        self.phases.append((phase, time.process_time() - self.start))

    def report(self, fraction):
        pass

    def cancelled(self):
        return False

    def ahead(self, part, data):
        """A part of the answer sent ahead (the plots' results, then the 3-D view's): when."""
        self.phases.append((f"{part} sent", time.process_time() - self.start))


def studio_runs(rounds):
    """The studio's run of EngineV6, ``rounds`` + 1 times, each in a child forked from this
    process warmed as the studio's forkserver is: [{phase: CPU s, "total": CPU s}]."""
    from kinetwork.studio import jobs, work
    for name in jobs.PRELOAD:           # what the forkserver imports (and ``warm`` runs)
        importlib.import_module(name)
    data = json.loads(MODEL.read_text())
    spent = []
    for _ in range(rounds + 1):
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:                    # the child: one run, its phases' CPU time sent back
            code = 1
            try:
                channel = _Channel()
                state, _ = work.run(data, {}, str(MODEL.parent), [], channel)
                channel.enter("end")
                os.write(write, json.dumps([state, channel.phases]).encode())
                code = 0
            finally:
                os._exit(code)
        os.close(write)
        with os.fdopen(read, "rb") as answer:
            got = answer.read()
        _, status = os.waitpid(pid, 0)
        if status or not got:
            raise RuntimeError(f"the studio's run in a child failed (status {status})")
        state, phases = json.loads(got)
        if state != "done":
            raise RuntimeError(f"the studio's run ended {state}")
        times = dict(phases)
        by = {}
        for (name, begun), (_, ended) in zip(phases, phases[1:]):
            by[name] = by.get(name, 0.0) + ended - begun
        by["total"] = times["end"]
        by["plots' results sent at"] = times.get("results sent", times["end"])
        spent.append(by)
    return spent[1:]


def studio_walls(rounds):
    """EngineV6 through the studio as the page runs it: ``kinetwork studio`` started in a
    folder holding a copy of models/, its forkserver warmed, then ``rounds`` rounds of two
    runs, each ``POST /api/run`` and polls of ``GET /api/run/{id}?wait=2`` until it has
    ended: the page's way (``&animation=later``: the plots' results, then ``/animation``
    for the 3-D view) and the whole answer at once. Wall seconds from the POST to the bytes
    of each answer, and their sizes: {"results", "view", "whole": [(seconds, bytes)]}. A first
    run (which fills the JIT cache of this checkout, if it is empty) is left out."""
    import re
    import shutil
    import subprocess
    import sys
    import tempfile
    import urllib.request
    with tempfile.TemporaryDirectory() as root:
        shutil.copytree(common.HERE.parent / "models", os.path.join(root, "models"))
        server = subprocess.Popen([sys.executable, "-m", "kinetwork", "studio", "--no-browser"],
                                  cwd=root, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                  text=True)
        try:
            url = None
            while url is None:
                line = server.stdout.readline()
                if not line:
                    raise RuntimeError("the studio did not start")
                url = re.search(r"(http://[^/\s]+)/\?token=(\S+)", line)
            base, token = url.group(1) + "/api", url.group(2)

            def call(method, path, body=None):
                request = urllib.request.Request(
                    base + path, method=method, headers={"X-Kinetwork-Token": token,
                                                         "Content-Type": "application/json"},
                    data=None if body is None else json.dumps(body).encode())
                with urllib.request.urlopen(request) as answer:
                    return answer.read()

            def polled(path, start):
                while True:
                    body = call("GET", path)
                    if not body.startswith(b'{"state":"running"'):
                        if not body.startswith(b'{"state":"done"'):
                            raise RuntimeError(f"the studio's run ended: {body[:200]!r}")
                        return time.perf_counter() - start, len(body)
            time.sleep(3.0)                 # the forkserver's warm-up (jobs.PRELOAD)
            data = {"model": json.loads(MODEL.read_text()),
                    "path": "models/engine_v6/EngineV6.json"}
            walls = {"results": [], "view": [], "whole": []}
            for k in range(rounds + 1):
                start = time.perf_counter()
                run = json.loads(call("POST", "/run", data))["run"]
                results = polled(f"/run/{run}?wait=2&animation=later", start)
                view = polled(f"/run/{run}/animation?wait=2", start)
                start = time.perf_counter()
                run = json.loads(call("POST", "/run", data))["run"]
                whole = polled(f"/run/{run}?wait=2", start)
                if k:
                    for key, value in zip(walls, (results, view, whole)):
                        walls[key].append(value)
            return walls
        finally:
            server.terminate()
            server.wait(timeout=10)


def study(rounds):
    ways = {"kept": compiled_module.INTEGRATORS_MOST, "64 kept": 64}
    # a System each (each keeps its own integrators); the C code is the same, cached on disk
    systems = {way: kn.load(MODEL).compile() for way in ways}
    for way, most in ways.items():
        run_once(systems[way], most)            # JIT, checks, the first integrators
    spent = {w: [] for w in ways}
    results = {}
    for _ in range(rounds):
        for way, most in ways.items():
            cpu, results[way], _ = run_once(systems[way], most)
            spent[way].append(cpu)
    rows, work = [], []
    for way, most in ways.items():
        total, res, (parts, count) = run_once(systems[way], most, parts=True)
        rest = total - parts["build"] - parts["integrate"] - parts["locate"]
        rows.append([way, f"{statistics.median(spent[way]):.2f}", f"{total:.2f}",
                     f"{count['build']}: {parts['build']:.2f}",
                     f"{count['integrate']}: {parts['integrate']:.2f}",
                     f"{count['locate']}: {parts['locate']:.2f}", f"{rest:.2f}",
                     res.stats["rhs_evaluations"], len(res.stats["events"])])
        n = max(count["locate"], 1)
        work.append([way, count["locate"], f"{count['covered']:.2f}", f"{count['grid'] / n:.2f}",
                     f"{count['fits', True] / n:.2f}", f"{count['fits', False] / n:.2f}",
                     f"{count['levels'] / n:.1f}", f"{count['indicators'] / n:.1f}"])
        print("  ", rows[-1], work[-1], flush=True)
    a, b = ([e["t"] for e in results[w].stats["events"]] for w in ways)
    apart = float(np.max(np.abs(np.subtract(a, b)))) if len(a) == len(b) else float("nan")
    return rows, work, apart


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5, help="interleaved rounds")
    args = parser.parse_args()
    start = time.perf_counter()
    studio = studio_runs(args.rounds)   # first: this process has not compiled EngineV6 yet
    # the phases of the child: "writing results" up to the plots' results sent ahead, then
    # the 3-D view's poses made and sent, then the whole answer written (jobs.AHEAD)
    phases = ["checking", "compiling", "integrating", "writing results", "results sent",
              "animation sent", "total", "plots' results sent at"]
    studio_row = [[f"{statistics.median(r.get(p, 0.0) for r in studio):.2f}"
                   for p in phases]]
    print("   studio", studio_row, flush=True)
    walls = studio_walls(args.rounds)

    def median(key):
        return f"{statistics.median(w for w, _ in walls[key]):.2f} s"
    wall_line = (f"Through the studio's server (``kinetwork studio``, ``POST /api/run``, then "
                 f"polls "
                 f"with ``wait=2``), wall time, medians of {args.rounds} runs each way, load "
                 f"{os.getloadavg()[0]:.1f}: the page's way, the plots' results "
                 f"(``?animation=later``, {walls['results'][0][1] / 1e6:.1f} MB) at "
                 f"{median('results')}, the 3-D view's poses (``/animation``, "
                 f"{walls['view'][0][1] / 1e6:.1f} MB) at {median('view')}; the whole "
                 f"answer at once ({walls['whole'][0][1] / 1e6:.1f} MB) at {median('whole')}.")
    print("  ", wall_line, flush=True)
    rows, work, apart = study(args.rounds)
    text = "\n".join([
        "# EngineV6 cached: where a repeated run spends its CPU time", "",
        f"{machine()}; {load()}; {args.rounds} interleaved rounds, CPU time, medians; study "
        f"wall time {time.perf_counter() - start:.0f} s. See ``bench/study_engine_cached.py`` "
        "for what each column is. Phases from one more run per way, timed by parts (the "
        "timers add a little).", "",
        table(["integrators", "run [s] (median)", "timed run [s]", "built: [s]",
               "integrator calls: [s]", "events located: [s]", "rest [s]",
               "rhs evaluations", "events"], rows), "",
        f"Event times of the two ways: largest difference {apart:.1e} s.", "",
        "The work of locating, per event located (counts: the same on every machine):", "",
        table(["integrators", "events located", "model time the integrator calls cover [s]",
               "integrations over a sampled interval", "two-row curves checked",
               "steps of 33-point curves checked", "indicators at trial times",
               "indicators with rates"], work),
        "", f"The studio's run (``studio/work.run``) in a child warmed as the studio's are, "
        f"CPU time by phases [s], medians of {args.rounds} children (the plots' results are "
        f"sent ahead of the 3-D view's poses, ``jobs.AHEAD``):", "",
        table(["checking", "compiling", "integrating", "writing the plots' results",
               "the 3-D view's poses", "the whole answer", "total",
               "plots' results sent at"], studio_row), "", wall_line, "", HISTORY])
    write_markdown(NAME, text)
    print(f"done in {time.perf_counter() - start:.0f} s", flush=True)


if __name__ == "__main__":
    main()
