"""Capturing what the solvers print: SUNDIALS' failure chatter and CasADi's warnings go to a
file instead of the user's terminal, and reach the user in the error's words. The machinery
is the bottom layer's (``kinetwork.util``), so that the equations' own Newton solves (initial
equations, loop closures) are as quiet as the integrators; a run's sections of solver code
(``Section``) and the file they share are here."""

import atexit
import os
import tempfile

from ..util import SOLVER_LOCK, last_words, solver_output  # noqa: F401
from .casadi_clock import cheap
from .methods import shift_times

_SINK = {}


def _sink():
    """The file that catches what the solvers print: one per process, used under SOLVER_LOCK
    (a temporary file per run cost 0.3 ms, a tenth of a small model's run)."""
    if _SINK.get("pid") != os.getpid():
        if "file" in _SINK:                    # a forked child's copy of its parent's
            _SINK["file"].close()
        _SINK.update(pid=os.getpid(), file=tempfile.TemporaryFile())  # noqa: SIM115
    return _SINK["file"]


@atexit.register
def _close_sink():
    if _SINK.get("pid") == os.getpid():
        _SINK.pop("file").close()


class Section:
    """A run's section of compiled solver code (``driver.Run.solver_section``), its printing
    captured and serialised by SOLVER_LOCK; what it said joins ``run.said`` unless the run
    was stopped. A class rather than a generator: a run enters one or two, and the
    generator's machinery cost as much as what it does."""

    def __init__(self, run, t0, descriptors):
        self.run, self.t0, self.descriptors = run, t0, descriptors
        self.capture = self.box = None
        self.clock = cheap()                    # CasADi's clock (casadi_clock.py)

    def __enter__(self):
        SOLVER_LOCK.acquire()
        try:
            self.capture = solver_output(_sink() if self.descriptors else None,
                                         self.descriptors)
            self.box = self.capture.__enter__()
        except BaseException:
            SOLVER_LOCK.release()
            raise
        self.clock.__enter__()

    def __exit__(self, *exc):
        try:
            self.clock.__exit__(*exc)
            self.capture.__exit__(*exc)
        finally:
            SOLVER_LOCK.release()
            run, box = self.run, self.box      # a failing solver's words are the ones wanted
            if box["text"].strip() and run.signal is None and run.stop_reason() is None:
                run.said.append(shift_times(box["text"], self.t0))
        return False
