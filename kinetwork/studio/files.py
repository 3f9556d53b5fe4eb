"""The studio's files: paths confined to its root, the model files under it, the examples.

Every path the browser sends is relative to the root, the folder the studio was started in.
A path that would leave it (``..``, an absolute path, a URL, a symbolic link pointing out) is
refused before the disk is touched, so a page (or anything else holding the token) reads and
writes model files inside that folder and nowhere else.
"""

import contextlib
import datetime
import hashlib
import json
import os
import re
import stat

from ..graph.io import FORMAT, MAX_FILE_SIZE
from ..outputs import filler
from ..util import atomic_write

#: model files are JSON: the studio opens and writes nothing else
SUFFIX = ".json"
#: how deep ``files`` looks below the root, and how many files it lists at most
MAX_DEPTH, MAX_FILES = 5, 5000
#: folders ``files`` does not look into (besides hidden ones: .git, .venv, ...)
SKIPPED = {"node_modules", "__pycache__", "site-packages"}


class StudioError(Exception):
    """A refusal answered as ``{"error": message, "problems": [...]}`` with ``status``."""

    def __init__(self, status, message, problems=()):
        super().__init__(message)
        self.status, self.message, self.problems = status, message, list(problems)


def confine(root, rel, what="path"):
    """The real absolute path of ``rel`` inside ``root``, and ``rel`` in canonical form
    (``models/a.json``).

    Raises
    ------
    StudioError
        400: not a relative path of a ``.json`` file inside the root.
    """
    if not isinstance(rel, str) or not rel.strip():
        raise StudioError(400, f"{what}: must be a path relative to the studio's folder, got "
                               f"{_shown(rel)}")
    if "\x00" in rel or len(rel) > 1024:
        raise StudioError(400, f"{what}: not a usable file name")
    if rel.startswith(("/", "\\", "~")) or os.path.isabs(rel) or "://" in rel or \
            re.match(r"[A-Za-z]:", rel):
        raise StudioError(400, f"{what} {_shown(rel)}: must be relative to the studio's "
                               f"folder (no absolute path, no URL)")
    parts = [p for p in re.split(r"[/\\]", rel) if p not in ("", ".")]
    if ".." in parts:
        raise StudioError(400, f"{what} {_shown(rel)}: '..' would leave the studio's folder")
    if not parts or not parts[-1].endswith(SUFFIX) or parts[-1] == SUFFIX:
        raise StudioError(400, f"{what} {_shown(rel)}: a model file's name ends in {SUFFIX}")
    real = os.path.realpath(os.path.join(root, *parts))
    if os.path.commonpath([real, root]) != root:
        raise StudioError(400, f"{what} {_shown(rel)}: a symbolic link leads out of the "
                               f"studio's folder")
    if not real.endswith(SUFFIX):
        raise StudioError(400, f"{what} {_shown(rel)}: a symbolic link to a file not ending "
                               f"in {SUFFIX}")
    return real, "/".join(parts)


def list_files(root):
    """The ``.json`` files under ``root``, at most MAX_DEPTH folders down, as sorted relative
    paths; hidden folders, node_modules and links leading out are left aside."""
    found = []
    for folder, dirs, names in os.walk(root):
        depth = 0 if folder == root else os.path.relpath(folder, root).count(os.sep) + 1
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in SKIPPED
                         and depth + 1 < MAX_DEPTH)
        for name in names:
            path = os.path.join(folder, name)
            if name.endswith(SUFFIX) and not name.startswith(".") and os.path.isfile(path) \
                    and os.path.commonpath([os.path.realpath(path), root]) == root:
                found.append(os.path.relpath(path, root).replace(os.sep, "/"))
                if len(found) >= MAX_FILES:
                    return sorted(found)
    return sorted(found)


def read_bytes(path, what):
    """A regular file's bytes, refused past MAX_FILE_SIZE. A FIFO, a device or a socket is
    refused by its kind before it is opened (opening a FIFO would wait for a writer), and
    again by what was opened (without waiting), in case it was swapped in between."""
    try:
        kind = os.stat(path).st_mode
    except FileNotFoundError:
        raise StudioError(404, f"{what}: no such file") from None
    except OSError as exc:
        raise StudioError(400, f"{what}: cannot read the file ({exc.strerror or exc})") from None
    if stat.S_ISDIR(kind):
        raise StudioError(400, f"{what}: a folder, not a model file")
    if not stat.S_ISREG(kind):
        raise StudioError(400, f"{what}: {_kind_of(kind)}, not a model file; not opened")
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise StudioError(400, f"{what}: cannot read the file ({exc.strerror or exc})") from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise StudioError(400, f"{what}: not a regular file; not read")
        with os.fdopen(fd, "rb") as fh:
            fd = None
            raw = fh.read(MAX_FILE_SIZE + 1)
    except OSError as exc:
        raise StudioError(400, f"{what}: cannot read the file ({exc.strerror or exc})") from None
    finally:
        if fd is not None:
            os.close(fd)
    if len(raw) > MAX_FILE_SIZE:
        raise StudioError(400, f"{what}: larger than {MAX_FILE_SIZE // 2**20} MiB, too large "
                               f"for a model file")
    return raw


def read_text(path, what):
    """A file's text (UTF-8, a BOM tolerated as ``kn.load`` does): see :func:`read_bytes`."""
    return decode(read_bytes(path, what), what)


def decode(raw, what):
    """A file's bytes as text: UTF-8, a BOM tolerated as ``kn.load`` does."""
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise StudioError(400, f"{what}: not UTF-8 text (byte {exc.start})") from None


def version_of(raw):
    """The version of a file's content, as saves name it: a hash of its bytes (the same text
    written again is the same version)."""
    return hashlib.sha256(raw).hexdigest()[:24]


def _kind_of(mode):
    for test, words in ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"),
                        (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device")):
        if test(mode):
            return words
    return "not a regular file"


# -- writing: versions checked, nothing overwritten that was not read ----------------------------
class Conflict(StudioError):
    """A save refused because the file is not the version it was based on; ``version`` is
    the file's now (None: there is none)."""

    def __init__(self, message, version):
        super().__init__(409, message)
        self.version = version


@contextlib.contextmanager
def _folder_lock(folder):
    """Saves into one folder one at a time, across processes (two studios on one folder):
    an exclusive lock on the folder itself, where the system has one."""
    try:
        import fcntl
    except ImportError:         # no advisory locks here: the version check alone
        yield
        return
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)           # releases the lock


#: ``write_model``'s base when the caller names none: no version check (an older client)
UNCHECKED = object()


def write_model(real, rel, text, base):
    """Write a model file's ``text`` at ``real`` if the file there is still version ``base``
    (None: no file; UNCHECKED: any model file), atomically; its new version.

    A file that is not a kinetwork model is never replaced; nor is a special file (a FIFO, a
    device). The check and the write happen under a lock on the folder, so two studios cannot
    both replace the version they read.

    Raises
    ------
    Conflict
        The file changed (or appeared, or went) since ``base``.
    StudioError
        The file is of another kind, or the disk refused (the old file stays whole).
    """
    folder = os.path.dirname(real)
    with _folder_lock(folder):
        now = None
        if os.path.lexists(real):
            raw = read_bytes(real, rel)
            _check_model(raw, rel)
            now = version_of(raw)
        if base is not UNCHECKED and now != base:
            if now is None:
                raise Conflict(f"{rel} was removed since it was opened; save it again, or "
                               f"under another name", None)
            if base is None:
                raise Conflict(f"{rel} exists already; overwrite it, or save under another "
                               f"name", now)
            raise Conflict(f"{rel} changed on disk since it was opened (another editor, or "
                           f"another studio, saved it); reload it, overwrite it, or save "
                           f"under another name", now)
        data = text.encode("utf-8")

        try:
            atomic_write(real, filler(data))
        except OSError as exc:
            raise StudioError(400, f"{rel}: not saved: {exc.strerror or exc}") from None
        return version_of(data)


def _check_model(raw, rel):
    """A file already there is replaced only when it is a kinetwork model file."""
    try:
        data = json.loads(raw.decode("utf-8-sig"))
    except (ValueError, RecursionError):
        data = None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise StudioError(409, f"{rel}: exists and is not a kinetwork model file; not "
                               f"overwritten (save under another name)")


# -- recovery files: the open model autosaved beside its file ------------------------------------
RECOVERY_FORMAT = "kinetwork.recovery"
#: the recovery file of a model never saved, in the root
UNTITLED = ".untitled.json.kinetwork-recovery"


def recovery_path(root, rel):
    """Where the recovery of ``rel`` (None: the unsaved model) is kept: beside the file,
    hidden (``models/.arm.json.kinetwork-recovery``)."""
    if rel is None:
        return os.path.join(root, UNTITLED)
    real = confine(root, rel)[0]
    return os.path.join(os.path.dirname(real), f".{os.path.basename(real)}.kinetwork-recovery")


def _ours(path):
    """Whether ``path`` is absent or a recovery file this studio wrote (never replace other)."""
    if not os.path.lexists(path):
        return True
    try:
        data = json.loads(read_bytes(path, "recovery").decode("utf-8"))
    except (StudioError, ValueError, RecursionError):
        return False
    return isinstance(data, dict) and data.get("format") == RECOVERY_FORMAT


def write_recovery(root, rel, model, base, session=None):
    """Keep ``model`` (the page's document, finished or not) as the recovery of ``rel``;
    ``session`` names the page that wrote it (a page does not offer its own work back)."""
    path = recovery_path(root, rel)
    if not os.path.isdir(os.path.dirname(path)):
        raise StudioError(400, f"{rel}: its folder does not exist")
    if not _ours(path):
        raise StudioError(409, f"{os.path.basename(path)}: a file of that name is there and "
                               f"is not the studio's; no recovery kept")
    record = {"format": RECOVERY_FORMAT, "path": rel, "base": base, "session": session,
              "saved": datetime.datetime.now(datetime.timezone.utc).isoformat(
                  timespec="seconds"), "model": model}
    data = json.dumps(record, allow_nan=False).encode("utf-8")
    if len(data) > MAX_FILE_SIZE:
        raise StudioError(400, "the model is too large to keep a recovery of")

    try:
        atomic_write(path, filler(data))
    except OSError as exc:
        raise StudioError(400, f"no recovery kept: {exc.strerror or exc}") from None


def read_recovery(root, rel):
    """The recovery of ``rel`` (None: the unsaved model), or None."""
    path = recovery_path(root, rel)
    if not os.path.lexists(path):
        return None
    try:
        data = json.loads(read_bytes(path, "recovery").decode("utf-8"))
    except (StudioError, ValueError, RecursionError):
        return None
    if not isinstance(data, dict) or data.get("format") != RECOVERY_FORMAT or \
            not isinstance(data.get("model"), dict):
        return None
    return {"path": rel, "base": data.get("base"), "saved": data.get("saved"),
            "session": data.get("session"), "model": data["model"]}


def discard_recovery(root, rel):
    """Remove the recovery of ``rel`` (only a file the studio wrote)."""
    path = recovery_path(root, rel)
    if os.path.lexists(path) and _ours(path):
        with contextlib.suppress(FileNotFoundError):
            os.remove(path)


def parse_model_text(text, what):
    """The top-level object of a model file's text, as written (nothing checked but JSON)."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise StudioError(400, f"{what}: line {exc.lineno} column {exc.colno}: invalid JSON: "
                               f"{exc.msg}") from None
    except (ValueError, RecursionError) as exc:
        raise StudioError(400, f"{what}: invalid JSON ({exc})") from None
    if not isinstance(data, dict):
        raise StudioError(400, f"{what}: not a model file (its JSON is not an object)")
    return data


# -- the examples -----------------------------------------------------------------------------
def examples():
    """Example name (its path in the folder, without ``.json``: ``robot/arm_axes``) -> file;
    the package's own list (``kinetwork.examples``)."""
    from .. import examples as shipped
    return shipped.names()


def _shown(value):
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."
