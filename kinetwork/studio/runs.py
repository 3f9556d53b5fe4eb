"""Runs and sweeps of the studio: each in a child process (``jobs``), polled by the page,
cancellable at once in every phase.

Cancel asks the child to stop: a run in its integration stops at its next chunk and keeps what
it computed (``simulate(..., cancel=)``), a sweep keeps the members that finished. A child
that cannot stop by itself in ``jobs.CANCEL_GRACE`` seconds (compiling, inside one CasADi
call) is ended, and the run is cancelled with what it had sent: nothing, at that point. The
answer of a finished run is kept whole, as the bytes the page reads; the last few are kept.
"""

import collections
import itertools
import logging
import threading
import time

from . import jobs, work
from .files import StudioError
from .results import encode

log = logging.getLogger("kinetwork.studio")

#: what a run's ``settings`` may hold: simulate's arguments of the same names
SETTINGS = ("t_end", "n_points", "method", "rtol", "atol", "step", "max_step", "max_steps",
            "time_limit")
#: finished runs kept for polling, and runs going at once (each takes a core)
KEEP, MAX_RUNNING = 8, 4


class Job:
    """One run or sweep in its child process; ``body()`` is what polling it answers."""

    def __init__(self, job_id, kind, fn, args):
        self.id, self.kind = job_id, kind
        self.state = "running"
        self.cancel_at = None
        self._lock = threading.Lock()
        self._final = None
        self.child = jobs.Child(fn, args)
        self.thread = threading.Thread(target=self._follow, name=f"kinetwork-studio-{job_id}",
                                       daemon=True)
        self.thread.start()

    def _follow(self):
        """Wait for the child's answer (the final JSON), or its end."""
        try:
            state, final = self.child.answer()
        except jobs.ChildError as exc:
            if self.cancel_at is not None:
                state, final = "cancelled", self._stopped()
            else:
                log.error("studio %s %s: the worker failed: %s", self.kind, self.id, exc)
                state = "failed"
                final = encode({"state": "failed", "progress": None, "phase": self.child.phase,
                                "error": f"internal error: {exc.kind}: {exc.text}",
                                "problems": [], "results": None, "members": None})
        with self._lock:
            self._final = final
            self.state = state

    def _stopped(self):
        # (a run says "compiling" again while a C compiler runs for it: whether anything had
        # been computed is what it reported, not its phase)
        phase = self.child.phase
        return encode({"state": "cancelled", "progress": None, "phase": phase, "error": None,
                       "problems": [], "results": None, "members": None,
                       "note": f"stopped while {phase}: nothing had been computed yet"
                               if not self.child.progress else
                               f"stopped while {phase}: what it had computed could not be "
                               f"kept"})

    def ahead(self, part):
        """The part of the answer the child sent ahead of it (``jobs.AHEAD``), or None."""
        return self.child.ahead.get(part)

    def body(self, later=False):
        """What ``GET /api/run/{id}`` answers, as JSON bytes; with ``later``, the results for
        the plots as soon as the child sent them, the 3-D view's to be asked for apart
        (``animation``)."""
        with self._lock:
            if self._final is not None:
                return self._final
        if later and self.cancel_at is None:
            ahead = self.ahead("results")
            if ahead is not None:
                return ahead
        return encode({"state": "running", "progress": self.child.progress,
                       "phase": self.child.phase, "cancelling": self.cancel_at is not None,
                       "error": None, "problems": [], "results": None})

    def animation(self):
        """What ``GET /api/run/{id}/animation`` answers, as JSON bytes: ``{"state": "done",
        "animation", "animation_note"}`` once the child has sent the 3-D view's poses;
        ``{"state": "running"}`` until then; once the run has ended without them (failed,
        cancelled, its worker gone), its state and why there is no view."""
        part = self.ahead("animation")
        if part is not None:
            return part
        with self._lock:
            if self._final is None:
                return encode({"state": "running"})
            state = self.state
        return encode({"state": state, "animation": None, "animation_note":
                       f"The run ended {state} before its 3-D view was made."})

    def cancel(self):
        """Stop: asked at once, ended after the grace if it does not stop by itself."""
        with self._lock:
            if self._final is not None or self.cancel_at is not None:
                return
            self.cancel_at = time.monotonic()
        threading.Thread(target=self.child.stop, name=f"kinetwork-studio-stop-{self.id}",
                         daemon=True).start()

    def kill(self):
        self.child.kill()


class Runs:
    """The runs and sweeps of one studio, by id: start, look up, cancel."""

    def __init__(self, keep=KEEP, max_running=MAX_RUNNING):
        self.keep, self.max_running = keep, max_running
        self._jobs = collections.OrderedDict()
        self._ids = itertools.count(1)
        self._lock = threading.Lock()

    def start(self, kind, data, extra, folder, library):
        """A new run (``extra``: its settings) or sweep (``extra``: its spec) of ``data``."""
        with self._lock:
            going = [j for j in self._jobs.values() if j.state == "running"]
            if len(going) >= self.max_running:
                raise StudioError(409, f"{len(going)} runs are going already; wait for one to "
                                       f"end or cancel one")
            self._prune()
            job_id = f"{'r' if kind == 'run' else 's'}{next(self._ids)}"
            fn = work.run if kind == "run" else work.sweep
            job = Job(job_id, kind, fn, (data, extra, folder, library))
            self._jobs[job.id] = job
        return job

    def get(self, job_id, kind=None):
        with self._lock:
            self._prune()
            job = self._jobs.get(job_id)
        if job is None or (kind is not None and job.kind != kind):
            raise StudioError(404, f"no {kind or 'run'} {job_id!r:.40} (only the last "
                                   f"{self.keep} finished are kept)")
        return job

    def _prune(self):
        """Forget finished jobs but the last ``keep`` (under the lock)."""
        finished = [j.id for j in self._jobs.values() if j.state != "running"]
        for old in finished[:max(0, len(finished) - self.keep)]:
            del self._jobs[old]

    def stop_all(self):
        """End every job now (the server stops)."""
        with self._lock:
            going = list(self._jobs.values())
        for job in going:
            job.kill()


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
