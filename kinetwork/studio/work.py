"""What the studio's child processes do (``jobs.Child`` calls these): check, lay out, write,
run, sweep and linearise a model sent by the page, through the library's own calls
(``kn.load``'s reader, ``kn.simulate``, ``kn.sweep``, ``kn.sample``, ``kn.linearize``).

Each takes the model (a file's top-level object), the folder its definitions are found in and
the library folders, and a ``jobs.Channel`` last. What a run gives the page is encoded here, in
the child, so the server never holds more than the bytes it sends.
"""

import json
import math

import numpy as np

from ..errors import ModelError, SimulationError
from ..graph.io import loads
from ..graph.writer import dumps, render_json
from ..solver import jit
from ..solver.driver import DEFAULTS
from ..solver.plan import simulate
from ..solver.results import TIME
from . import checks
from .results import animation_json, encode, results_json

#: the most numbers a run or a sweep may give the page (time and probe values): a run of
#: the seed with 111,000 points; beyond, the command line (``kinetwork run --out``)
MAX_VALUES = 1_000_000
#: the most members of a sweep from the page
MAX_MEMBERS = 64
#: frequencies of a Bode plot
BODE_POINTS = 200


def _ctx(folder, library):
    return checks.context(folder, library)


def _runnable(data, folder, library, verb):
    """The model of ``data``, validated; a subsystem definition (a model exposing ports) is
    refused: it runs only where it is placed."""
    model = checks.build(data, _ctx(folder, library), validate=True)
    if model.exposed:
        raise ModelError(f"this model is a subsystem definition (it exposes ports): place it "
                         f"in a model to {verb} it")
    return model


def check(data, folder, library, channel):
    """``checks.check`` of the model: ``{"ok", "problems", "summary", "compile"}``."""
    channel.enter("checking")
    return checks.check(data, _ctx(folder, library))


def summarize(data, folder, library, channel):
    """``checks.summarize`` of the model: its degrees of freedom and states, or problems."""
    channel.enter("compiling")
    return checks.summarize(data, _ctx(folder, library))


def render(data, text, folder, library, channel):
    """The text to write for a save: ``{"text", "problems", "canonical"}``.

    The text the page opened, byte for byte, when the model is still that text's JSON; else
    kinetwork's own text of the model (the writer of ``Model.save``); and a model the reader
    refuses (a required value still empty, an expression half typed) is written as it is,
    in the same layout, with its problems: unfinished work saves, and is checked on load.
    """
    channel.enter("checking")
    if text is not None and same(_json_or_none(text), data):
        try:
            loads(text, validate=False, library=library, folder=folder)
            return {"text": text, "problems": [], "canonical": True}
        except ModelError as exc:
            return {"text": text, "problems": checks.problems_of(exc), "canonical": False}
    try:
        model = checks.build(data, _ctx(folder, library), validate=False)
        return {"text": dumps(model, folder), "problems": [], "canonical": True}
    except ModelError as exc:
        problems = checks.problems_of(exc)
    try:
        return {"text": render_json(data), "problems": problems, "canonical": False}
    except ModelError as exc:       # not plain JSON: nothing a file can hold
        raise ModelError(exc.problems) from None


def run(data, settings, folder, library, channel):
    """A run of the model: ``(state, JSON bytes)`` of its final state (done, failed or
    cancelled), with the results it reached."""
    model, phase = None, _Phase(channel, "checking")
    try:
        model = _runnable(data, folder, library, "run")
        sim = {**DEFAULTS, **model.simulation, **settings}
        n_points, t_end = sim.get("n_points"), sim.get("t_end")
        _check_size(n_points, 1, 1, beyond=True)
        phase.enter("compiling")
        system = model.compile()
        _check_size(n_points, 1 + sum(sig.size for sig in system.signals), 1)
        if channel.cancelled():
            return _final("cancelled", phase=phase.now)
        span = t_end if isinstance(t_end, (int, float)) and t_end > 0 else None

        def progress(t):
            phase.integrating()
            channel.report(t / span)
            if t >= span * (1 - 1e-12):
                # integrated to the end: the probes' outputs follow, results that a cancel
                # now would lose; they are finished and kept (jobs: no SIGINT in this phase)
                phase.enter("writing results")
        if span is None:                # no progress to wait for: integrating from here
            phase.enter("integrating")
        with jit.watching(phase.compiler):
            results = simulate(system, **settings, cancel=channel.cancelled,
                               progress=progress if span else None)
        phase.enter("writing results")
        # the plots' results ahead of the 3-D view's poses (EngineV6: 0.1 s of CPU and 5.6 of
        # its 6.1 MB), each sent as soon as it is made (GET /api/run/{id}?animation=later)
        plots = results_json(results, model, with_animation=False)
        channel.ahead("results", _final("done", results={**plots, "animation_pending": True},
                                        phase=phase.now)[1])
        view = animation_json(results, model)
        channel.ahead("animation", encode({"state": "done", **view}))
        return _final("done", results={**plots, **view}, phase=phase.now)
    except SimulationError as exc:
        cancelled = channel.cancelled()
        reached = exc.results is not None and len(exc.results.t) > 1
        # (a first chunk that failed reported no progress)
        said = "integrating" if reached or not cancelled else phase.now
        if cancelled and not reached:   # cancelled while the equations were compiled to C
            exc.results = None
        if cancelled and exc.results is not None and exc.results.partial:
            # stopped by the user's cancel (the signal that carried it is a detail)
            exc.results.partial = {**exc.results.partial, "reason": "cancelled"}
        partial = None if exc.results is None else results_json(exc.results, model)
        return _final("cancelled" if cancelled else "failed", error=None if cancelled else str(exc),
                      results=partial, phase=said)
    except ModelError as exc:
        return _final("failed", error=str(exc), problems=checks.problems_of(exc),
                      phase=phase.now)
    except KeyboardInterrupt:          # cancelled before the integration kept anything
        return _final("cancelled", phase=phase.now)


class _Phase:
    """What a run or sweep says it is doing (``jobs.PHASES``), told to its channel as it
    changes. From "compiling" (the equations derived, then compiled to C) it says
    "integrating" once a library of compiled code is ready, and "compiling" again while a C
    compiler runs for it (``jit.watching``), until the integration first reports progress:
    the page never reads "integrating 0 %" through a compile, nor "compiling" through an
    integration (EngineV6's cached libraries: ready in milliseconds). Once progress is
    reported, it is "integrating" (a cancel then keeps what was reached: ``jobs.CANCEL_GRACE``
    is by phase) until the results are written."""

    def __init__(self, channel, phase):
        self.channel, self.now, self.reported = channel, None, False
        self.enter(phase)

    def enter(self, phase):
        if phase != self.now:
            self.now = phase
            self.channel.enter(phase)

    def integrating(self):
        """The integration reported progress."""
        self.reported = True
        if self.now == "compiling":
            self.enter("integrating")

    def compiler(self, building):
        """``jit.watching``'s listener (called from any of a sweep's threads)."""
        if not self.reported and self.now in ("compiling", "integrating"):
            self.enter("compiling" if building else "integrating")


def _final(state, error=None, problems=(), results=None, phase=None):
    """``(state, the JSON bytes polling it answers)``."""
    return state, encode({"state": state, "progress": 1.0 if state == "done" else None,
                          "phase": phase, "error": error, "problems": list(problems),
                          "results": results})


def _check_size(n_points, columns, members, beyond=False):
    """Refuse, before the work, results too large for the page: ``columns`` per point and
    member (the time and the probes' values, once compiled). ``beyond``: before the model is
    compiled, refuse only what no model could fit (a point has a time at least)."""
    if not isinstance(n_points, (int, float)) or isinstance(n_points, bool) or \
            not math.isfinite(n_points) or n_points < 2:
        return                        # simulate says what is wrong with it
    values = int(n_points) * columns * members
    if beyond and values > MAX_VALUES:
        raise ModelError(f"simulation.n_points: {int(n_points):,} points are more than the "
                         f"studio plots ({MAX_VALUES:,} numbers, the time included); run it "
                         f"from the command line (kinetwork run MODEL --out results.csv)")
    if values > MAX_VALUES:
        most = max(2, MAX_VALUES // (columns * members))
        what = f"{members} members x " if members > 1 else ""
        raise ModelError(
            f"simulation.n_points: {int(n_points):,} points would give the page {what}"
            f"{values:,} numbers (about {values * 20 / 1e6:,.0f} MB of text), more than the "
            f"studio plots ({MAX_VALUES:,}); give at most {most:,} points, or run it from the "
            f"command line (kinetwork run MODEL --out results.csv)")


def sweep(data, spec, folder, library, channel):
    """A sweep (``kn.sweep``, a grid) or a Monte Carlo sample (``kn.sample``) of the model:
    ``(state, JSON bytes)`` of its members, each with the values it had and its results."""
    from ..analysis.sweep import normal, sample, uniform
    from ..analysis.sweep import sweep as grid_sweep
    model = None
    try:
        phase = _Phase(channel, "checking")
        model = _runnable(data, folder, library, "sweep")
        kind, names, members = _sweep_spec(spec)
        sim = {**DEFAULTS, **model.simulation}
        _check_size(sim.get("n_points"), 1, members, beyond=True)
        phase.enter("compiling")
        system = model.compile()
        _check_size(sim.get("n_points"), 1 + sum(sig.size for sig in system.signals), members)

        def progress(done, total):
            phase.integrating()
            channel.report(done / total)
        with jit.watching(phase.compiler):
            if kind == "grid":
                ds = grid_sweep(system, {k: spec["grid"][k] for k in names}, progress=progress)
            else:
                dists = {}
                for k in names:
                    (law, (a, b)), = spec["distributions"][k].items()
                    dists[k] = uniform(a, b) if law == "uniform" else normal(a, b)
                ds = sample(system, dists, int(spec["n"]), seed=spec.get("seed"),
                            progress=progress)
        phase.enter("writing results")
        out = _members(ds, system, names, kind)
        interrupted = bool(ds.attrs.get("interrupted"))
        state = "cancelled" if interrupted or channel.cancelled() else "done"
        return state, encode({"state": state, "progress": 1.0, "phase": "writing results",
                              "error": None, "problems": [], "members": out,
                              "parameters": names})
    except ModelError as exc:
        return "failed", encode({"state": "failed", "progress": None, "error": str(exc),
                                 "problems": checks.problems_of(exc), "members": None})
    except KeyboardInterrupt:          # cancelled before any member finished
        return "cancelled", encode({"state": "cancelled", "progress": None, "error": None,
                                    "problems": [], "members": None})


def _sweep_spec(spec):
    """(kind, parameter names, members) of a sweep request, refused with its place."""
    if not isinstance(spec, dict):
        raise ModelError("sweep: must be an object {kind, grid} or {kind, distributions, n}")
    kind = spec.get("kind")
    if kind == "grid":
        grid = spec.get("grid")
        if not isinstance(grid, dict) or not grid:
            raise ModelError("sweep.grid: give a parameter name -> [values] for each swept one")
        members = 1
        for k, values in grid.items():
            if not isinstance(values, list) or not values or not all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                    for v in values):
                raise ModelError(f"sweep.grid.{k}: a non-empty list of numbers")
            members *= len(values)
        names = list(grid)
    elif kind == "random":
        dists = spec.get("distributions")
        if not isinstance(dists, dict) or not dists:
            raise ModelError("sweep.distributions: give a parameter name -> {uniform: [low, "
                             "high]} or {normal: [mean, std]} for each")
        for k, d in dists.items():
            ok = isinstance(d, dict) and len(d) == 1 and next(iter(d)) in ("uniform", "normal")
            pair = next(iter(d.values())) if ok else None
            if not ok or not isinstance(pair, list) or len(pair) != 2 or not all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                    for v in pair):
                raise ModelError(f"sweep.distributions.{k}: {{\"uniform\": [low, high]}} or "
                                 f"{{\"normal\": [mean, std]}}, numbers")
        n = spec.get("n")
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ModelError(f"sweep.n: the number of members, a positive integer, got {n!r:.40}")
        seed = spec.get("seed")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
            raise ModelError(f"sweep.seed: a non-negative integer or null, got {seed!r:.40}")
        members, names = n, list(dists)
    else:
        raise ModelError(f"sweep.kind: \"grid\" or \"random\", got {kind!r:.40}")
    if members > MAX_MEMBERS:
        raise ModelError(f"sweep: {members} members; the studio runs at most {MAX_MEMBERS} "
                         f"(kn.sweep in Python, or kinetwork sweep, runs more)")
    return kind, names, members


def _members(ds, system, names, kind):
    """Each member of a sweep's Dataset: its parameter values, status and results."""
    shape = [ds.sizes[d] for d in (names if kind == "grid" else ["member"])]
    count = int(np.prod(shape))
    t = ds[TIME].values
    columns = {}
    for sig in system.signals:
        block = ds[sig.name].values
        columns[sig.name] = block.reshape(count, len(t), *sig.shape)
    status = np.asarray(ds["status"].values).reshape(count)
    reason = np.asarray(ds["reason"].values).reshape(count)
    reached = np.asarray(ds["t_reached"].values, dtype=float).reshape(count)
    if kind == "grid":
        grids = np.meshgrid(*[ds[n].values for n in names], indexing="ij")
        params = [{n: float(g.reshape(count)[i]) for n, g in zip(names, grids)} for i in range(count)]
    else:
        params = [{n: float(ds[n].values[i]) for n in names} for i in range(count)]
    out = []
    for i in range(count):
        if status[i] == "interrupted":
            out.append({"index": i, "params": params[i], "status": "interrupted", "reason": str(reason[i]),
                        "results": None})
            continue
        keep = len(t) if status[i] == "ok" else int(np.searchsorted(t, reached[i], side="right"))
        signals = [{"name": sig.name, "unit": sig.unit, "shape": list(sig.shape),
                    "probe": sig.probe, "quantity": sig.quantity, "port": sig.target,
                    "values": _finite(columns[sig.name][i][:keep])} for sig in system.signals]
        out.append({"index": i, "params": params[i], "status": str(status[i]),
                    "reason": str(reason[i]) if status[i] != "ok" else None,
                    "results": {"t": _finite(t[:keep]), "signals": signals, "animation": None,
                                "partial": None if status[i] == "ok" else
                                {"t_reached": float(reached[i]), "reason": str(reason[i])}}})
    return out


def _finite(a):
    a = np.asarray(a, dtype=float)
    if np.isfinite(a).all():
        return a.tolist()
    out = a.astype(object)
    out[~np.isfinite(a)] = None
    return out.tolist()


def linearize(data, spec, folder, library, channel):
    """``kn.linearize`` of the model at a time of its run: poles, the matrices, and the
    frequency response of every input to every output (a Bode plot)."""
    from ..analysis.linear import linearize as linearise
    channel.enter("checking")
    model = _runnable(data, folder, library, "linearise")
    at = spec.get("at")
    if at is not None and (isinstance(at, bool) or not isinstance(at, (int, float))
                           or not math.isfinite(at) or at < 0):
        raise ModelError(f"at: a time >= 0 [s], or null for the start, got {at!r:.40}")
    inputs = spec.get("inputs") or []
    outputs = spec.get("outputs") or None
    for what, names in (("inputs", inputs), ("outputs", outputs or [])):
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            raise ModelError(f"{what}: a list of names")
    channel.enter("compiling")
    lin = linearise(model, at=None if not at else float(at), inputs=inputs, outputs=outputs)
    poles = sorted((complex(p) for p in lin.eigenvalues), key=lambda p: (p.real, p.imag))
    answer = {"t": float(lin.t), "state_names": list(lin.state_names),
              "input_names": list(lin.input_names), "output_names": list(lin.output_names),
              "A": lin.A, "B": lin.B, "C": lin.C, "D": lin.D,
              "poles": [[p.real, p.imag] for p in poles], "bode": None}
    if lin.input_names and lin.output_names:
        answer["bode"] = _bode(lin, poles)
    return json.loads(encode(answer))


def _bode(lin, poles):
    """Magnitude (dB) and phase (degrees, unwrapped) of every input-output pair (at most 16)
    over frequencies two decades around the poles'."""
    mags = [abs(p) for p in poles if abs(p) > 1e-9]
    low = max(1e-3, min(mags) / 100) if mags else 1e-2
    high = min(1e7, max(mags) * 100) if mags else 1e3
    omega = np.logspace(np.log10(low), np.log10(max(high, low * 10)), BODE_POINTS)
    H = lin.frequency_response(omega)
    pairs = []
    for i, out in enumerate(lin.output_names):
        for j, inp in enumerate(lin.input_names):
            h = H[i, j, :]
            with np.errstate(divide="ignore"):
                mag = 20 * np.log10(np.abs(h))
            pairs.append({"input": inp, "output": out, "mag_db": mag,
                          "phase_deg": np.degrees(np.unwrap(np.angle(h)))})
            if len(pairs) >= 16:
                return {"omega": omega, "pairs": pairs}
    return {"omega": omega, "pairs": pairs}


def same(a, b):
    """JSON values equal as the page sees them: 1 and 1.0 alike (JavaScript has one number
    type), but true and 1 not, nor "1" and 1."""
    if isinstance(a, bool) or isinstance(b, bool):
        return type(a) is type(b) and a == b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return a == b
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b


def _json_or_none(text):
    try:
        return json.loads(text)
    except (ValueError, RecursionError):
        return None
