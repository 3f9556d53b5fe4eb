"""Capturing what the solvers print: SUNDIALS' failure chatter and CasADi's warnings go to a
file instead of the user's terminal, and reach the user in the error's words."""

import contextlib
import ctypes
import functools
import io
import os
import sys
import threading

#: the solvers print through file descriptors 1 and 2, which belong to the whole process:
#: one integration section at a time captures them
SOLVER_LOCK = threading.RLock()


@contextlib.contextmanager
def solver_output(sink):
    """What the integrators print (SUNDIALS' failure chatter, CasADi's warnings) captured
    instead of reaching the user's terminal: CasADi writes through Python's sys.stdout and
    sys.stderr, plain C code to file descriptors 1 and 2; both are caught, in the file
    ``sink`` (emptied first). The text is in the yielded dict's "text" afterwards. Callers
    hold ``SOLVER_LOCK``."""
    box = {"text": ""}
    sink.seek(0)
    sink.truncate()
    python_level = io.StringIO()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    try:
        saved = [os.dup(1), os.dup(2)]
    except OSError:                            # no file descriptors to redirect
        saved = None
    with contextlib.redirect_stdout(python_level), contextlib.redirect_stderr(python_level):
        if saved:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
        try:
            yield box
        finally:
            if saved:
                _libc().fflush(None)
                os.dup2(saved[0], 1)
                os.dup2(saved[1], 2)
                for fd in saved:
                    os.close(fd)
                sink.seek(0)
            box["text"] = python_level.getvalue() + (
                sink.read().decode("utf-8", "replace") if saved else "")


@functools.lru_cache(maxsize=1)
def _libc():
    return ctypes.CDLL(None)


def last_words(text):
    """The solver's own last line (what it said when it failed), shortened."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    if not lines:
        return ""
    line = lines[-1]
    return line if len(line) <= 200 else line[:197] + "..."
