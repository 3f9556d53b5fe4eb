"""Small helpers every layer uses: checked numbers, near-match suggestions, quoting of user
input in messages, and atomic file writes (through ``kinetwork.outputs``). The bottom layer:
it imports nothing of kinetwork but the errors and the output policy."""

import math
import os
import sys

from .errors import ModelError

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
    import stat
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
    special file at ``path`` is refused (``OutputRefused``)."""
    from .outputs import write as policy_write
    policy_write(path, write, mode=mode)


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
