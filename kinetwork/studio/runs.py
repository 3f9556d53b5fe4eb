"""Simulation runs of the studio: one worker thread each, polled by the page, cancellable.

A run checks the model as ``kn.load`` does and calls ``kn.simulate`` with a progress callback
and a cancel flag; the driver serves both between chunks of its integration, so a cancelled
run stops within a fraction of a second and keeps what it computed. The last few finished
runs are kept for the page to read.
"""

import collections
import itertools
import json
import logging
import math
import threading

import numpy as np

from ..errors import ModelError, SimulationError
from ..solver.driver import DEFAULTS
from ..solver.plan import simulate
from .checks import build, plain, problems_of
from .files import StudioError

log = logging.getLogger("kinetwork.studio")

#: what a run's ``settings`` may hold: simulate's arguments of the same names
SETTINGS = ("t_end", "n_points", "method", "rtol", "atol", "step", "max_steps", "time_limit")
#: finished runs kept for polling, and runs going at once (each takes a core)
KEEP, MAX_RUNNING = 8, 4
#: the most time samples of a run's 3-D animation: a denser run is resampled (the viewer
#: interpolates between samples), or the poses of a large scene would be tens of MB of JSON
MAX_FRAMES = 1000


class Run:
    """One simulation in its worker thread; ``body()`` is what ``GET /api/run/{id}``
    answers."""

    def __init__(self, run_id):
        self.id = run_id
        self.cancel = threading.Event()
        self.state, self.progress = "running", 0.0
        self.thread = None
        self._lock = threading.Lock()
        #: the JSON of the final answer, made once: the results may be megabytes, kept as
        #: text only (as Python lists they would take ten times that)
        self._final = None

    def body(self):
        """What ``GET /api/run/{id}`` answers, as JSON bytes."""
        with self._lock:
            if self._final is not None:
                return self._final
            return encode({"state": self.state, "progress": self.progress, "error": None,
                           "problems": [], "results": None})

    def finish(self, state, error=None, problems=(), results=None):
        progress = 1.0 if state == "done" else self.progress
        text = encode({"state": state, "progress": progress, "error": error,
                       "problems": list(problems), "results": results})
        with self._lock:
            self.state, self.progress, self._final = state, progress, text

    def report(self, fraction):
        with self._lock:
            if self.state == "running":
                self.progress = min(1.0, max(0.0, fraction))

    def work(self, data, settings, ctx):
        """The worker thread: check, simulate, keep the outcome (never raises)."""
        model = None
        try:
            model = build(data, ctx, validate=True)
            if model.exposed:
                raise ModelError("this model is a subsystem definition (it exposes ports): "
                                 "place it in a model to run it")
            t_end = settings.get("t_end", model.simulation.get("t_end", DEFAULTS["t_end"]))
            span = t_end if isinstance(t_end, (int, float)) and t_end > 0 else None
            results = simulate(model, **settings, cancel=self.cancel.is_set,
                               progress=(lambda t: self.report(t / span)) if span else None)
            self.finish("done", results=results_json(results, model))
        except SimulationError as exc:
            cancelled = self.cancel.is_set()
            partial = None if exc.results is None else results_json(exc.results, model)
            self.finish("cancelled" if cancelled else "failed",
                        error=None if cancelled else str(exc), results=partial)
        except ModelError as exc:
            self.finish("failed", error=str(exc), problems=problems_of(exc))
        except Exception as exc:       # noqa: BLE001 -- a run never takes the server down
            log.exception("run %s failed unexpectedly", self.id)
            self.finish("failed", error=f"internal error: {type(exc).__name__}: {exc}")


class Runs:
    """The runs of one studio, by id: start, look up, cancel."""

    def __init__(self, keep=KEEP, max_running=MAX_RUNNING):
        self.keep, self.max_running = keep, max_running
        self._runs = collections.OrderedDict()
        self._ids = itertools.count(1)
        self._lock = threading.Lock()

    def start(self, data, settings, ctx):
        """A new Run of ``data`` (a file's top-level object), going in its thread."""
        with self._lock:
            going = [r for r in self._runs.values() if r.state == "running"]
            if len(going) >= self.max_running:
                raise StudioError(409, f"{len(going)} runs are going already; wait for one to "
                                       f"end or cancel one")
            self._prune()
            run = Run(f"r{next(self._ids)}")
            self._runs[run.id] = run
        run.thread = threading.Thread(target=run.work, args=(data, settings, ctx),
                                      name=f"kinetwork-studio-{run.id}", daemon=True)
        run.thread.start()
        return run

    def get(self, run_id):
        with self._lock:
            self._prune()
            run = self._runs.get(run_id)
        if run is None:
            raise StudioError(404, f"no run {run_id!r:.40} (only the last {self.keep} finished "
                                   f"runs are kept)")
        return run

    def _prune(self):
        """Forget finished runs but the last ``keep`` (under the lock)."""
        finished = [r.id for r in self._runs.values() if r.state != "running"]
        for old in finished[:max(0, len(finished) - self.keep)]:
            del self._runs[old]

    def stop_all(self, wait=2.0):
        """Cancel every run and give their threads ``wait`` seconds to end (at shutdown)."""
        with self._lock:
            runs = list(self._runs.values())
        for run in runs:
            run.cancel.set()
        for run in runs:
            if run.thread is not None:
                run.thread.join(wait / max(1, len(runs)))


def check_settings(settings):
    """The settings of ``POST /api/run``: an object of SETTINGS keys (values are checked by
    ``simulate``, whose refusal fails the run with its problems)."""
    if settings is None:
        return {}
    if not isinstance(settings, dict):
        raise StudioError(400, "settings: must be an object")
    unknown = [k for k in settings if k not in SETTINGS]
    if unknown:
        raise StudioError(400, f"settings: unknown key {unknown[0]!r:.60}; keys are "
                               f"{', '.join(SETTINGS)}")
    return {k: v for k, v in settings.items() if v is not None}


def results_json(res, model=None):
    """Results as the page reads them: the time grid and every probe signal with its
    descriptor (``Signal``: the probe, the quantity, the port measured, unit and shape: the
    page groups plots by them, never by splitting names), values nested with n_points first,
    non-finite values null; and the 3-D animation when it can be made."""
    return {
        "t": finite_list(res.t),
        "signals": [{"name": name, "probe": sig.probe, "quantity": sig.quantity,
                     "port": sig.target, "unit": sig.unit, "shape": list(sig.shape),
                     "values": finite_list(res[name])} for name, sig in res.signals.items()],
        "animation": animation(res, model),
        "partial": plain(res.partial),
    }


def finite_list(values):
    a = np.asarray(values, dtype=float)
    good = np.isfinite(a)
    if good.all():
        return a.tolist()
    out = a.astype(object)
    out[~good] = None
    return out.tolist()


def animation(res, model=None):
    """``kinetwork.animation.animation_data(res)`` of the results of ``model``, or None when
    that module is not there or the scene has nothing to show."""
    try:
        from ..animation import animation_data
    except ImportError:
        return None
    try:
        n, span = len(res.t), float(res.t[-1] - res.t[0]) if len(res.t) else 0.0
        fps = (MAX_FRAMES - 1) / span if n > MAX_FRAMES and span > 0 else None
        return animation_data(res, fps=fps, model=model)
    except Exception:      # noqa: BLE001 -- the plots are worth showing without the 3-D view
        log.warning("no animation for these results", exc_info=True)
        return None


def encode(content):
    """JSON bytes as the page reads them: compact, numpy values as lists, NaN and infinities
    null (JSON has none, and a model file or partial results may hold them)."""
    try:
        text = json.dumps(content, allow_nan=False, separators=(",", ":"), default=_numpy)
    except ValueError:
        text = json.dumps(_finite(content), allow_nan=False, separators=(",", ":"),
                          default=_numpy)
    return text.encode("utf-8")


def _numpy(value):
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON")


def _finite(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value
