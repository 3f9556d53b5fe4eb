"""The one output policy: what kinetwork may write over, and how it writes.

Every command and function that writes a file (``run --out/--plot``, ``sweep --out``,
``import -o``, ``animate``, ``diagram -o``, ``Results.to_csv``, ``Model.save``, plots,
``examples copy``, the JIT cache, the studio) goes through :func:`write`, after refusing up
front with :func:`check` (or :func:`check_all` for several outputs at once), so that:

1. a file the command reads (the model, its definition files, the URDF, the measured data)
   is never written: compared by device and inode, so a symbolic link, a hard link or
   ``./x`` for ``x`` are the same file;
2. a special file (a device such as ``/dev/full``, a FIFO, a socket) or a folder is never
   replaced: refused by name, before any work;
3. an existing file of another kind (a model file, a CSV, a NetCDF, a PNG, a URDF, ...) is
   replaced only when asked (``--force``, ``overwrite=True``); one of the same kind (the
   last run's CSV) or an empty one is replaced;
4. every write is atomic: a temporary file in the same folder, flushed to disk, renamed over
   the target. On any failure (a full disk, an exception, SIGINT or SIGTERM) the old file is
   whole and the temporary is gone; temporaries still open at exit are removed too.

A long write can stop early and keep what it wrote (``cooperative``: the CSV writer stops
between blocks of rows and ends the file with a line saying where): see :func:`write`.

This module sits at the bottom of the layers (it imports nothing of kinetwork but the
errors), so every layer can write through it.
"""

import atexit
import contextlib
import errno
import os
import secrets
import signal
import stat
import threading
import time

from .errors import ModelError

#: the signals that stop a write (and a command): SIGINT and SIGTERM
STOPPING = (signal.SIGINT, signal.SIGTERM)
#: how much of an existing file is read to tell its kind
SNIFF_BYTES = 4096

#: kind -> how a message names it
KINDS = {
    "model": "a kinetwork model file", "json": "JSON", "csv": "a CSV table",
    "netcdf": "a NetCDF file", "png": "a PNG image", "gif": "a GIF", "mp4": "an MP4 video",
    "pdf": "a PDF", "svg": "an SVG drawing", "html": "an HTML page", "urdf": "a URDF robot",
    "meta": "a results sidecar (kinetwork.results)", "xml": "XML", "jpeg": "a JPEG image", "tiff": "a TIFF image", "webp": "a WebP image",
    "ps": "a PostScript file", "text": "text", "binary": "binary data", "library":
    "a compiled library", "empty": "nothing (an empty file)",
}
#: the kind of a plot file by its extension (what matplotlib writes)
EXTENSION_KINDS = {"png": "png", "pdf": "pdf", "svg": "svg", "jpg": "jpeg", "jpeg": "jpeg",
                   "tif": "tiff", "tiff": "tiff", "webp": "webp", "eps": "ps", "ps": "ps",
                   "gif": "gif", "html": "html", "htm": "html", "csv": "csv", "nc": "netcdf",
                   "json": "model", "mp4": "mp4"}

_MAGIC = ((b"\x89PNG\r\n\x1a\n", "png"), (b"GIF87a", "gif"), (b"GIF89a", "gif"),
          (b"%PDF", "pdf"), (b"CDF\x01", "netcdf"), (b"CDF\x02", "netcdf"),
          (b"CDF\x05", "netcdf"), (b"\x89HDF\r\n\x1a\n", "netcdf"), (b"\xff\xd8\xff", "jpeg"),
          (b"II*\x00", "tiff"), (b"MM\x00*", "tiff"), (b"%!PS", "ps"), (b"\x7fELF", "library"))

#: temporary files being written by this process: removed at exit if still there
_LIVE = set()
_LIVE_LOCK = threading.Lock()


class OutputRefused(ModelError):
    """An output that would replace what it must not: a file the command reads, another
    output of the command, or (unless forced) a file of another kind. Said before any work;
    choosing another path helps (a command exits 2). A folder or a special file at the path
    is a plain ModelError: the path cannot be written (exit 1)."""


class Stopped(KeyboardInterrupt):
    """SIGINT or SIGTERM arrived while a file was written (or, in the command line, while a
    command ran): a KeyboardInterrupt that knows its signal, which nothing on the way
    catches."""

    def __init__(self, signum):
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = int(signum)


# -- what is at a path ---------------------------------------------------------------------------
def kind_of(path):
    """The kind (a key of KINDS) of the regular file at ``path``, from its first bytes; None
    when nothing is there."""
    try:
        with open(path, "rb") as fh:
            if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):
                return None
            head = fh.read(SNIFF_BYTES)
    except FileNotFoundError:
        return None
    except OSError:
        return "binary"             # there, but unreadable: nothing to compare with
    return sniff(head)


def sniff(head):
    """The kind of a file starting with the bytes ``head``."""
    if not head:
        return "empty"
    for magic, kind in _MAGIC:
        if head.startswith(magic):
            return kind
    if head[4:8] == b"ftyp":
        return "mp4"
    if head.startswith(b"RIFF") and head[8:12] == b"WEBP":
        return "webp"
    try:
        text = head.decode("utf-8-sig")
    except UnicodeDecodeError as exc:       # text cut inside a character at the end is text
        if exc.start < len(head) - 4:
            return "binary"
        text = head[:exc.start].decode("utf-8-sig", errors="replace")
    if "\x00" in text:
        return "binary"
    stripped = text.lstrip()
    lower = stripped[:400].lower()
    if stripped.startswith(("{", "[")):
        if '"kinetwork.model"' in text:
            return "model"
        return "meta" if '"kinetwork.results"' in text else "json"
    if stripped.startswith("<"):
        if lower.startswith(("<!doctype html", "<html")):
            return "html"
        if "<svg" in lower:
            return "svg"
        if "<robot" in text:
            return "urdf"
        return "xml"
    lines = [ln for ln in stripped.split("\n") if ln.strip()]
    if len(head) == SNIFF_BYTES and len(lines) > 1:
        lines = lines[:-1]                      # the last may be cut short
    first = lines[0].split(",", 1)[0].strip().strip('"') if lines else ""
    commas = {ln.count(",") for ln in lines}
    # a table: kinetwork's (time first), or rows of one count of commas
    if first == "t" or (len(lines) > 1 and len(commas) == 1 and commas != {0}):
        return "csv"
    return "text"


def _special(mode):
    """What a non-regular file is, in words; None for a regular file."""
    for test, words in ((stat.S_ISDIR, "a folder"), (stat.S_ISCHR, "a character device"),
                        (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                        (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return words
    return None if stat.S_ISREG(mode) else "not a regular file"


def _identity(path):
    """(device, inode) of the file at ``path`` (links followed), or None."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return st.st_dev, st.st_ino


def same_file(a, b):
    """Whether two paths name one file: by device and inode when both exist (a symbolic or
    hard link, ``./x`` and ``x``), else by their resolved paths."""
    ia, ib = _identity(a), _identity(b)
    if ia is not None and ib is not None:
        return ia == ib
    try:
        return os.path.realpath(a) == os.path.realpath(b)
    except (OSError, ValueError):
        return False


# -- the checks ----------------------------------------------------------------------------------
def _name(path, what):
    shown = repr(os.fspath(path)) if len(os.fspath(path)) <= 200 else \
        repr(os.fspath(path)[:197] + "...")
    return f"{what} {shown}" if what else shown


def check(path, kind=None, *, what=None, reads=(), force=False):
    """Refuse writing ``kind`` at ``path``, before any work; return the path to write (links
    resolved: a symbolic link to a regular file is followed, not replaced).

    Parameters
    ----------
    path : str or os.PathLike
    kind : str, optional
        What will be written (a key of KINDS); None skips the kind check.
    what : str, optional
        How messages name the output (``"--out"``).
    reads : iterable
        The files the command reads, never written: paths, or (words, path) pairs whose
        words say what the file is ("the model file").
    force : bool
        Replace an existing file of another kind.

    Raises
    ------
    OutputRefused
        The path is a file the command reads, or (without ``force``) a file of another
        kind: choose another path.
    ModelError
        The path cannot be written: a folder, a special file (a device, a FIFO, a socket),
        not a usable file name, a part of it is a file.
    """
    try:
        text = os.fspath(path)
    except TypeError:
        raise ModelError(f"{what or 'output'}: expected a file path, got "
                         f"{type(path).__name__}") from None
    if isinstance(text, bytes):
        text = os.fsdecode(text)
    if not text or "\x00" in text:
        raise ModelError(f"{what or 'output'}: {text!r:.60} is not a usable file name")
    label = _name(text, what)
    try:
        st = os.stat(text)
    except FileNotFoundError:
        st = None
    except NotADirectoryError:
        raise ModelError(f"cannot write {text}: a part of the path is a file, not a "
                         f"folder") from None
    except OSError as exc:
        raise ModelError(f"cannot write {text}: {exc.strerror or exc}") from None
    if st is not None:
        special = _special(st.st_mode)
        if special == "a folder":
            raise ModelError(f"cannot write {text}: it is a folder; name a file (in it, or "
                             f"elsewhere)")
        if special:
            raise ModelError(f"cannot write {text}: it is {special}, and kinetwork writes "
                             f"only regular files: it replaces no device, pipe or socket")
        for source, words in _inputs(reads):
            if _identity(source) == (st.st_dev, st.st_ino):
                same = words if os.fspath(source) == text else \
                    f"{words} {os.fspath(source)!r:.200}"
                raise OutputRefused(f"{label} is an input here ({same}): choose another "
                                    f"path")
        existing = kind_of(text)
        if kind is not None and not force and existing not in (None, "empty", kind):
            raise OutputRefused(
                f"{label} holds {KINDS.get(existing, existing)}, and this writes "
                f"{KINDS.get(kind, kind)}: choose another path, or replace it with --force "
                f"(overwrite=True in Python)")
    real = os.path.realpath(text)
    folder = os.path.dirname(real)
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise ModelError(f"cannot write {text}: {folder!r:.200} is a file, not a folder")
    return real


def _inputs(reads):
    """(path, words) of each input: ``reads`` holds paths, or (words, path) pairs."""
    for item in reads:
        words, source = item if isinstance(item, tuple) else ("a file read", item)
        if source is not None:
            yield source, words


def model_files(model):
    """(words, path) of the files ``model`` was read from (``Model.files``), for ``reads``."""
    if model is None:
        return []
    own = getattr(getattr(model, "_source", None) or model, "path", None)
    return [("the model file" if f == own else "a definition file the model places", f)
            for f in model.files()]


def check_all(outputs, reads=(), force=False):
    """:func:`check` of several outputs of one command (``(what, path, kind)`` each, a None
    path skipped), and none the same file as another. Returns the resolved paths."""
    named = [(what, path, kind) for what, path, kind in outputs if path is not None]
    for i, (what_a, a, _) in enumerate(named):
        for what_b, b, _ in named[i + 1:]:
            if same_file(a, b):
                raise OutputRefused(f"{_name(b, what_b)} is the same file as "
                                    f"{_name(a, what_a)}: choose another path")
    return [check(path, kind, what=what, reads=reads, force=force)
            for what, path, kind in named]


# -- stopping ------------------------------------------------------------------------------------
class StopFlag:
    """Why a write (or a command's outputs) should stop: a signal caught, the caller's
    ``cancel()``, or the ``deadline`` (a ``time.monotonic()`` value) passed (said as
    ``late``). Call it: the reason in words, or None."""

    def __init__(self, cancel=None, deadline=None, late="the time limit was reached"):
        self.cancel, self.deadline, self.late = cancel, deadline, late
        self.signum = None
        #: whether a signal raises Stopped at once (a write that cannot stop halfway)
        self.raising = True

    def __call__(self):
        if self.signum is not None:
            return f"interrupted by {signal.Signals(self.signum).name}"
        if self.cancel is not None and self.cancel():
            return "cancelled"
        if self.deadline is not None and time.monotonic() > self.deadline:
            return self.late
        return None


@contextlib.contextmanager
def catching_signals(flag):
    """Within (in the main thread), SIGINT and SIGTERM set ``flag.signum`` instead of killing
    the process, and raise :class:`Stopped` when ``flag.raising``. Elsewhere: nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return

    def caught(signum, frame):
        if flag.signum is None:
            flag.signum = signum
        if flag.raising:
            raise Stopped(signum)
    saved = {}
    for sig in STOPPING:
        try:
            if signal.getsignal(sig) is not signal.SIG_IGN:     # ignored stays ignored
                saved[sig] = signal.signal(sig, caught)
        except (ValueError, OSError):       # not settable here (an embedded interpreter)
            pass
    try:
        yield flag
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, handler)


# -- writing -------------------------------------------------------------------------------------
def filler(data):
    """The ``fill`` of :func:`write` (and ``util.atomic_write``) that writes the bytes
    ``data``."""
    def fill(tmp):
        with open(tmp, "wb") as fh:
            fh.write(data)
    return fill


def write(path, fill, kind=None, *, what=None, reads=(), force=False, stop=None,
          cooperative=False, mode=0o666):
    """Write a file under the policy: :func:`check`, then ``fill`` writes a temporary file
    in the same folder, which is flushed to disk and renamed over ``path``.

    Parameters
    ----------
    path : str or os.PathLike
    fill : callable
        ``fill(tmp_path)`` writes the file's content into ``tmp_path`` (which exists, empty);
        with ``cooperative``, ``fill(tmp_path, stop)`` and it calls ``stop()`` between blocks:
        when that gives a reason it ends the file as it sees fit (a line saying so) and
        returns.
    kind, what, reads, force
        As for :func:`check`.
    stop : StopFlag, optional
        The caller's: a signal it has caught, its cancel and deadline (a command passes one
        for all its outputs). Without, the write has its own, catching SIGINT and SIGTERM.
    cooperative : bool
        ``fill`` stops itself when told: a signal then only sets the flag. Otherwise a signal
        stops the write at once (the temporary removed, the old file whole) with
        :class:`Stopped`.
    mode : int
        Permissions of a new file, before the umask (an existing file's are kept).

    Returns
    -------
    str or None
        Why a cooperative ``fill`` was told to stop (it wrote what it could), else None.

    Raises
    ------
    OutputRefused
        See :func:`check`; nothing is written.
    Stopped
        A signal stopped a write that was not cooperative; the old file is whole.
    OSError
        The file system refused (a full disk, no permission); the old file is whole.
    """
    real = check(path, kind, what=what, reads=reads, force=force)
    own = stop is None
    flag = StopFlag() if own else stop
    context = catching_signals(flag) if own else contextlib.nullcontext(flag)
    with context:
        before = flag.raising
        flag.raising = not cooperative
        try:
            if flag.raising and flag.signum is not None:
                raise Stopped(flag.signum)
            reason = _atomic(real, fill, mode, flag if cooperative else None)
        finally:
            flag.raising = before
    return reason


def _atomic(real, fill, mode, flag):
    """The write itself: temporary, fill, fsync, rename (see :func:`write`)."""
    folder, base = os.path.split(real)
    tmp = os.path.join(folder, f".{base[:200]}.{secrets.token_hex(4)}.tmp")
    reason = None
    with _LIVE_LOCK:
        _LIVE.add(tmp)
    try:
        # 0o666 lets the umask apply, as to any new file (mkstemp would force 0o600);
        # O_EXCL|O_NOFOLLOW: a name planted meanwhile is not written through
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0),
                     mode)
        os.close(fd)
        if flag is not None:
            fill(tmp, flag)
            reason = flag()
        else:
            fill(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        try:
            st = os.lstat(real)
        except FileNotFoundError:
            st = None
        if st is not None:
            special = _special(st.st_mode)
            if special and not stat.S_ISLNK(st.st_mode):
                # made there while this was written: still never replaced
                raise OutputRefused(f"{real!r:.200} became {special} while it was written; "
                                    f"nothing was written")
            os.chmod(tmp, stat.S_IMODE(st.st_mode))
        os.replace(tmp, real)
        _sync_folder(folder)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    finally:
        with _LIVE_LOCK:
            _LIVE.discard(tmp)
    return reason


def _sync_folder(folder):
    """Flush the rename to disk (where the file system allows opening a folder)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError as exc:
        if exc.errno not in (errno.EINVAL, errno.EBADF, errno.EROFS):
            raise
    finally:
        os.close(fd)


@atexit.register
def _remove_live():
    """Temporaries of writes that never finished (an exit from another thread)."""
    with _LIVE_LOCK:
        for tmp in list(_LIVE):
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        _LIVE.clear()


def plot_kind(path):
    """The kind of a plot (or other output named by its extension), or None when unknown."""
    ext = os.path.splitext(os.fspath(path))[1].lstrip(".").lower()
    return EXTENSION_KINDS.get(ext)
