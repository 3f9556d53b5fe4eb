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
    fd = sink.fileno()
    if os.fstat(fd).st_size:            # (a seek and a truncate cost 25 us: only when needed)
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
    streams = sys.stdout, sys.stderr           # (contextlib's redirections cost 30 us)
    sys.stdout = sys.stderr = python_level
    try:
        if saved:
            os.dup2(fd, 1)
            os.dup2(fd, 2)
        yield box
    finally:
        sys.stdout, sys.stderr = streams
        caught = b""
        if saved:
            _libc().fflush(None)
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for saved_fd in saved:
                os.close(saved_fd)
            if os.fstat(fd).st_size:
                sink.seek(0)
                caught = sink.read()
        box["text"] = python_level.getvalue() + caught.decode("utf-8", "replace")


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
