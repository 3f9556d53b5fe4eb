"""Small helpers every layer uses: checked numbers, near-match suggestions, quoting of user
input in messages, bounded reads, atomic file writes (through ``kinetwork.outputs``), and
capturing what the solvers print. The bottom layer: it imports nothing of kinetwork but the
errors and the output policy."""

import contextlib
import ctypes
import functools
import io
import math
import os
import re
import stat
import sys
import tempfile
import threading

from .errors import ModelError

#: a CasADi warning line: its message, without the time stamp and the C++ source place
_WARNING = re.compile(r'^CasADi - [^W]*WARNING\("(.*)"\)\s*(\[.*\])?$')

#: user input quoted in a message is cut to this many characters
QUOTE_LIMIT = 200


def finite(value):
    """math.isfinite that says False, not OverflowError, for a huge int."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def check_number(value, where, what="a number"):
    """A finite real number, or a ModelError naming ``where``."""
    numpy = sys.modules.get("numpy")        # a numpy scalar exists only once numpy is loaded
    if numpy is not None and isinstance(value, numpy.generic):
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ModelError(f"{where}: must be {what}, got {quote(value)}")
    if not finite(value):
        got = (f"an integer of {len(str(value))} digits" if isinstance(value, int)
               else repr(value))
        raise ModelError(f"{where}: must be finite, got {got}")
    return value


def suggest(name, choices):
    """' (did you mean 'x'?)' for the closest of ``choices``, or ''."""
    import difflib                      # here: the command line starts without it
    close = difflib.get_close_matches(str(name)[:QUOTE_LIMIT], list(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def hint(suggestion):
    """The hint of a Problem from ``suggest``'s text: "did you mean 'x'?" (None for '')."""
    return suggestion.strip()[1:-1] or None if suggestion else None


def quote(value, limit=QUOTE_LIMIT):
    """``repr(value)``, cut to ``limit`` characters: messages never echo unbounded input."""
    try:
        text = repr(value)
    except Exception:                 # a hostile __repr__: say what it is, not what it says
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[:limit - 3] + "..."


#: seconds a read from a pipe or a device may wait for its next bytes
READ_IDLE = 10.0


def read_bounded(path, limit, special=True, idle=READ_IDLE, inspect=None):
    """The bytes of the file at ``path``: at most ``limit`` + 1 of them (a caller refuses
    more), so /dev/zero or an endless pipe costs a bounded read.

    Opening never blocks (a FIFO without a writer reads as empty), and a pipe or a device
    that sends nothing for ``idle`` seconds is refused. ``special=False`` refuses anything
    but a regular file (a FIFO, a device, a socket) before reading a byte: what a server
    that must never block uses. ``inspect(first_bytes)``, if given, sees the first block
    read (up to 1 MiB) and may refuse the rest by raising.

    Raises
    ------
    ModelError
        A special file refused, or one that went silent.
    OSError
        The file cannot be opened or read (a folder: IsADirectoryError).
    """
    import errno
    import select
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), path)
        regular = stat.S_ISREG(st.st_mode)
        if not regular and not special:
            raise ModelError(f"{quote(os.fspath(path))}: not a regular file (a pipe, a device "
                             f"or a socket): refused without reading it")
        if regular:
            os.set_blocking(fd, True)
        chunks, size = [], 0
        while size <= limit:
            try:
                chunk = os.read(fd, min(1 << 20, limit + 1 - size))
            except BlockingIOError:         # a pipe or a device with nothing yet: wait
                if not select.select([fd], [], [], idle)[0]:
                    raise ModelError(f"{quote(os.fspath(path))}: nothing came from it for "
                                     f"{idle:g} s") from None
                continue
            if not chunk:
                break
            if inspect is not None and not chunks:
                inspect(chunk)
            chunks.append(chunk)
            size += len(chunk)
        return b"".join(chunks)
    finally:
        os.close(fd)


def atomic_write(path, write, mode=0o666):
    """Write a file in one step under the output policy (``kinetwork.outputs.write``, no
    check of what kind of file is replaced): ``write(tmp_path)`` fills a temporary file in
    the same folder, which is flushed to disk and then replaces ``path``. A failure (a full
    disk, a signal) leaves the old file whole and removes the temporary one; a folder or a
    special file at ``path`` is refused (``ModelError``)."""
    from .outputs import write as policy_write
    policy_write(path, write, mode=mode)


def cache_folder():
    """The folder of kinetwork's caches (compiled libraries, derived Systems):
    ``$KINETWORK_CACHE``, else ``$XDG_CACHE_HOME/kinetwork``, else ``$HOME/.cache/kinetwork``;
    None without a home to keep them in."""
    import pathlib
    if path := os.environ.get("KINETWORK_CACHE"):
        return pathlib.Path(path)
    if base := os.environ.get("XDG_CACHE_HOME"):
        return pathlib.Path(base) / "kinetwork"
    if home := os.environ.get("HOME"):
        return pathlib.Path(home) / ".cache" / "kinetwork"
    return None


def trim_least_recent(entries, limit, keep, remove):
    """Remove the least recently used of ``entries`` ((path, bytes, mtime) of a cache's
    files) until the rest fit in ``limit`` bytes, never ``keep`` (just written):
    ``remove(path)`` removes one. The JIT's libraries and the kept Systems are trimmed so."""
    ordered = sorted((mtime, size, path) for path, size, mtime in entries)
    total = sum(size for _, size, _ in ordered)
    for _, size, path in ordered:
        if total <= limit:
            break
        if path != keep:
            remove(path)
            total -= size


def callable_module(name, function):
    """Make the module ``name`` callable as ``function``: ``kn.plot(...)`` and ``kn.schema()``
    are functions named like their modules, and once a submodule is imported the package's
    attribute of that name is the module, so the module itself is made the function (its
    other names stay reachable: ``kinetwork.plot.save_plot``)."""
    import types

    class CallableModule(types.ModuleType):
        __call__ = staticmethod(function)
        __doc__ = function.__doc__

    sys.modules[name].__class__ = CallableModule


#: the solvers print through file descriptors 1 and 2, which belong to the whole process:
#: one integration section at a time captures them
SOLVER_LOCK = threading.RLock()


@contextlib.contextmanager
def solver_output(sink, descriptors=True):
    """What the integrators print (SUNDIALS' failure chatter, CasADi's warnings) captured
    instead of reaching the user's terminal: CasADi writes through Python's sys.stdout and
    sys.stderr, plain C code to file descriptors 1 and 2; both are caught, in the file
    ``sink`` (emptied first). The text is in the yielded dict's "text" afterwards. Callers
    hold ``SOLVER_LOCK``.

    Without ``descriptors``, only Python's streams are swapped (no system call): for calls
    of CasADi's own integrators, whose every word (SUNDIALS' through the error handler
    CasADi installs) reaches Python's streams; ten system calls a run were 1 % of a small
    model's."""
    box = {"text": ""}
    python_level = io.StringIO()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    if not descriptors:
        streams = sys.stdout, sys.stderr
        sys.stdout = sys.stderr = python_level
        try:
            yield box
        finally:
            sys.stdout, sys.stderr = streams
            box["text"] = python_level.getvalue()
        return
    fd = sink.fileno()
    if os.fstat(fd).st_size:            # (a seek and a truncate cost 25 us: only when needed)
        sink.seek(0)
        sink.truncate()
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


@contextlib.contextmanager
def quiet():
    """What CasADi and the C code under it print while the block runs, captured (never on
    the user's terminal): the yielded dict's "text" holds it afterwards, for a summary in
    the error or warning that follows."""
    with SOLVER_LOCK, tempfile.TemporaryFile() as sink, solver_output(sink) as box:
        yield box


def summary(text, limit=3):
    """A short account of captured solver output: how many lines, and the distinct ones
    first (up to ``limit``), for a message."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    if not lines:
        return ""
    # CasADi's lines differ in their time stamps and source places only
    distinct = list(dict.fromkeys(_WARNING.sub(r"\1", ln) for ln in lines))
    shown = "; ".join(ln if len(ln) <= 160 else ln[:157] + "..." for ln in distinct[:limit])
    more = f" (and {len(distinct) - limit} more kinds)" if len(distinct) > limit else ""
    return f"the solver said {len(lines)} line{'s' * (len(lines) != 1)}: {shown}{more}"
