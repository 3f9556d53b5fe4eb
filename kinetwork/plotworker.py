"""The probe plots of ``kinetwork run --plot`` in formats other than PNG (pdf, svg, ...),
drawn by a second process started with the command (a PNG is drawn by ``quickplot``).

matplotlib takes longer to import than kinetwork takes to load, build and run the seed, and
drawing takes as long again. So the command forks at its start, before it imports anything
heavy: the child imports matplotlib and warms its fonts while the parent builds and runs the
model, then draws what the parent sends it and reports back. The command ends only when the
image is written (or refused: the child's ``ModelError`` or ``OSError`` is raised in the
parent). If the child cannot be started, or dies, the parent draws the plots itself: the same
``save_plot``, only later.

Standard library only at import: this module runs before numpy is loaded.
"""

import itertools
import os
import pickle
import select
import signal
import sys
import time
from dataclasses import dataclass

#: what the child answers when it could not run ``save_plot`` at all
_NO_ANSWER = ("lost", None)


@dataclass(frozen=True)
class PlotSignal:
    """What a plot reads of a ``Signal``: no CasADi, so the child never imports the solver."""
    name: str
    unit: str
    shape: tuple
    size: int
    probe: str
    quantity: str


def wanted(argv):
    """Whether the command line ``argv`` (without the program name) runs a model with
    ``--plot`` into a file other than a PNG (PNGs are drawn by ``quickplot``, in the command's
    own process, without matplotlib): worth a drawing process. A miss only means the plots
    are drawn later."""
    if not argv or argv[0] != "run":
        return False
    files = [b for a, b in itertools.pairwise(argv[1:]) if a == "--plot"] + \
        [a.partition("=")[2] for a in argv[1:] if a.startswith("--plot=")]
    return any(not f.lower().endswith(".png") for f in files)


class PlotWorker:
    """A forked process that will draw one run's probe plots into a file."""

    def __init__(self, pid, jobs, answers):
        self.pid, self._jobs, self._answers = pid, jobs, answers

    @classmethod
    def start(cls):
        """Fork the drawing process, or None where forking is not safe or possible."""
        if not sys.platform.startswith("linux"):       # fork is unsafe on macOS, absent on Windows
            return None
        jobs_r, jobs_w = os.pipe()
        answers_r, answers_w = os.pipe()
        try:
            pid = os.fork()
        except OSError:
            for fd in (jobs_r, jobs_w, answers_r, answers_w):
                os.close(fd)
            return None
        if pid == 0:                                   # the child: never returns
            code = 1
            try:
                # Ctrl-C reaches the whole process group: the parent handles it (it writes
                # the partial run, plots included), the child must live to draw them
                signal.signal(signal.SIGINT, signal.SIG_IGN)
                os.close(jobs_w)
                os.close(answers_r)
                code = _serve(jobs_r, answers_w)
            finally:
                os._exit(code)
        os.close(jobs_r)
        os.close(answers_w)
        return cls(pid, jobs_w, answers_r)

    def save(self, results, path, *names, title=None, hide_flat=False, overwrite=False):
        """``save_plot(results, path, *names, title=, hide_flat=, overwrite=)``, drawn in the
        child; waits for it. Raises what ``save_plot`` raised there; draws here if the child
        is gone."""
        from .plot import save_plot
        job = pickle.dumps({"results": _portable(results), "path": os.fspath(path),
                            "names": list(names), "title": title, "hide_flat": hide_flat,
                            "overwrite": overwrite})
        try:
            _write_all(self._jobs, job)
        except OSError:                                # the child died: draw here
            pass
        self._close_jobs()
        status, error = self._answer()
        if status == "error":
            raise error
        if status != "done":
            save_plot(results, path, *names, title=title, hide_flat=hide_flat,
                      overwrite=overwrite)

    def close(self):
        """End the child and reap it, if it has not answered: a refused model or a usage
        error (it has written nothing yet, and waiting for its imports would delay the
        command's exit), or a command stopped while it draws. SIGTERM first, so that a
        write under way removes its temporary file (``kinetwork.outputs``); SIGKILL if it
        is still there a second later."""
        self._close_jobs()
        if self._answers is not None:
            try:
                os.kill(self.pid, signal.SIGTERM)
                for _ in range(100):
                    if os.waitpid(self.pid, os.WNOHANG)[0]:
                        break
                    time.sleep(0.01)
                else:
                    os.kill(self.pid, signal.SIGKILL)
            except (ProcessLookupError, ChildProcessError):   # already gone, or reaped
                pass
            self._answer()

    def _close_jobs(self):
        if self._jobs is not None:
            os.close(self._jobs)
            self._jobs = None

    def _answer(self):
        """The child's answer (status, exception) once it has exited."""
        data = _read_all(self._answers)
        os.close(self._answers)
        self._answers = None
        while True:
            try:
                os.waitpid(self.pid, 0)
                break
            except ChildProcessError:
                break
            except InterruptedError:                   # pragma: no cover (PEP 475 retries)
                continue
        try:
            return pickle.loads(data) if data else _NO_ANSWER
        except Exception:
            return _NO_ANSWER


def _portable(results):
    """A copy of ``results`` holding what a plot reads: values, names, units, targets and
    events; no System and no Signal (whose module imports CasADi and the model layers)."""
    import copy
    light = copy.copy(results)
    light.system = None
    light.signals = {name: PlotSignal(name, sig.unit, tuple(sig.shape), sig.size, sig.probe,
                                      sig.quantity) for name, sig in results.signals.items()}
    light.stats = {"events": list(results.stats.get("events", ()))}
    return light


def _serve(jobs, answers):
    """The child: import and warm up the plotting, wait for the job, draw, answer."""
    try:
        from .plot import save_plot, warm_up
        if not select.select([jobs], [], [], 0)[0]:     # the job is not here yet: warm up
            warm_up()
    except BaseException:           # pragma: no cover - the parent draws itself
        save_plot = None
    data = _read_all(jobs)
    if not data or save_plot is None:
        return 0                    # no job: the run was refused, or drawing is impossible
    job = pickle.loads(data)
    try:
        save_plot(job["results"], job["path"], *job["names"], title=job["title"],
                  hide_flat=job["hide_flat"], overwrite=job["overwrite"])
        answer = ("done", None)
    except Exception as exc:        # the parent raises it, as if it had drawn
        answer = ("error", exc)
    try:
        reply = pickle.dumps(answer)
    except Exception:               # an exception that does not pickle: its message does
        from .errors import ModelError
        reply = pickle.dumps(("error", ModelError(str(answer[1]))))
    _write_all(answers, reply)
    return 0


def _read_all(fd):
    chunks = []
    while True:
        chunk = os.read(fd, 1 << 16)
        if not chunk:
            return b"".join(chunks)
        chunks.append(chunk)


def _write_all(fd, data):
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]
