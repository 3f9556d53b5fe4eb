"""Running the C compiler for ``jit.py``: sources into one shared library, moved into the cache
whole with the record of its bytes, or nothing.

Compilers run as many at once as there are cores, each in its own session so that it can be
stopped with its children; a build is stopped when the caller's deadline passes, when it is
cancelled, or when it runs past its time limit. Every build happens in a folder of its own
(``BUILD_PREFIX``...), so that processes building the same library at once never see each
other's files; the library and its record are moved into place by ``os.replace``.
"""

import contextlib
import errno
import hashlib
import hmac
import os
import pathlib
import signal
import stat
import subprocess
import sys
import tempfile
import time

from ..errors import ModelError

BUILD_PREFIX = "kinetwork-build-"
_POLL = 0.05                                  # s between looks at the compilers


class Unavailable(ModelError):
    """Why no compiled library can be had; ``kind`` is the reason warned of once."""

    def __init__(self, kind, message):
        super().__init__(message)
        self.kind = kind


class _Starting:
    """Whether a compiler is being started and recorded now, and the stop signal that came
    meanwhile: a builder's exit (``exit_on``) waits for the record, so no compiler it started
    outlives it unstopped."""
    active = False
    pending = None


@contextlib.contextmanager
def _starting():
    _Starting.active = True
    try:
        yield
    finally:
        _Starting.active = False
        if _Starting.pending is not None:
            signum, _Starting.pending = _Starting.pending, None
            sys.exit(128 + signum)


def exit_on(signum, frame):
    """A stop signal's handler in a builder process: exit (its compilers stopped and its
    folder removed on the way out), once the compiler being started, if one is, is recorded."""
    if _Starting.active:
        _Starting.pending = signum
    else:
        sys.exit(128 + signum)


def stop_reason(deadline, cancelled):
    """Why the caller no longer wants the library, if it does not."""
    if cancelled is not None and cancelled():
        return Unavailable("cancelled", "jit: compilation cancelled")
    if deadline is not None and time.perf_counter() >= deadline:
        return Unavailable("deadline", "jit: the run's deadline passed during compilation")
    return None


def os_error(folder, e):
    """An OSError met in the cache folder, as the reason no library can be had."""
    if e.errno in (errno.ENOSPC, errno.EDQUOT):
        return Unavailable("disk-full", f"jit: no space left for the cache {folder}")
    if e.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
        return Unavailable("read-only", f"jit: the cache {folder} is read-only ({e.strerror})")
    if e.errno == errno.ENOTDIR:
        return Unavailable("not-a-folder", f"jit: the cache {folder} is inside a file")
    return Unavailable("cache-error", f"jit: the cache {folder} cannot be used: {e}")


def record(lib):
    """Where the sha256 of ``lib``'s bytes is kept."""
    return lib.with_name(lib.name + ".sha256")


def sha256(path):
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        while chunk := file.read(1 << 20):
            digest.update(chunk)
    return digest.hexdigest().encode()


def build_folder(folder):
    """A folder of one build's own in ``folder``, removed with what is in it on the way out."""
    return tempfile.TemporaryDirectory(prefix=BUILD_PREFIX, dir=folder)


def build(cc, sources, lib, deadline=None, cancelled=None, timeout=300.0, libraries=("-lm",)):
    """Compile ``sources`` ({file name: (C, flags)}) into ``lib`` and write its record, both
    moved into place whole; raise ``Unavailable`` saying why when that cannot be done."""
    try:
        # the build folder goes on every way out (a KeyboardInterrupt included): the
        # compilers are stopped first, then the folder removed
        with build_folder(lib.parent) as tmp:
            work = pathlib.Path(tmp)
            for src, (text, _) in sources.items():
                (work / src).write_text(text)
            limit = (time.perf_counter(), timeout)
            flags = {tuple(f) for _, f in sources.values()}
            if len(flags) == 1 and all(src.endswith("_main.c") for src in sources):
                # short functions (no parts), at one level: one compiler run
                _compile([[cc, *flags.pop(), "-shared", "-o", "lib.so", *sources,
                           *libraries]], work, deadline, cancelled, limit)
            else:           # side by side, the longest first (the last to finish is short)
                order = sorted(sources, key=lambda src: -len(sources[src][0]))
                _compile([[cc, *sources[src][1], "-c", src, "-o", src[:-2] + ".o"]
                          for src in order], work, deadline, cancelled, limit)
                _compile([[cc, "-shared", "-o", "lib.so", *(src[:-2] + ".o" for src in sources),
                           *libraries]], work, deadline, cancelled, limit)
            out = work / "lib.so"
            if not out.is_file():
                raise Unavailable("compiler-silent", f"jit: {pathlib.Path(cc).name} exited "
                                  "without writing a library" + _words(work))
            out.chmod(0o700)                      # private whatever the umask
            for target in (lib, record(lib)):     # a FIFO, a folder planted there: left be
                with contextlib.suppress(FileNotFoundError):
                    if not stat.S_ISREG(target.lstat().st_mode):
                        raise Unavailable("cache-error", f"jit: {target} is not a regular "
                                          f"file; kinetwork replaces only its own files")
            said = work / "record"
            said.write_bytes(sha256(out) + b"\n")
            said.chmod(0o600)
            os.replace(said, record(lib))
            os.replace(out, lib)
    except OSError as e:
        raise os_error(lib.parent, e) from None


def cores():
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def _words(work):
    """The compilers' last words, for a message."""
    text = b"".join(p.read_bytes() for p in sorted(work.glob("stderr*")))
    words = text.decode(errors="replace").strip()[-400:]
    return f": {words}" if words else ""


def _compile(jobs, work, deadline, cancelled, limit):
    """Run the compiler commands ``jobs`` in ``work``, as many at once as there are cores
    (relative names, so the output does not depend on the folder); stop them, with their
    children, on ``deadline``, ``cancelled()`` or past ``limit`` (the build's start, as a
    perf_counter value, and its time limit in s)."""
    compiler_name = pathlib.Path(jobs[0][0]).name
    waiting, running, failed = list(enumerate(jobs)), [], None
    stop = hung = None
    try:
        while (waiting or running) and failed is None:
            while waiting and len(running) < cores():
                i, command = waiting.pop(0)
                with open(work / f"stderr{i:05d}", "wb") as said, _starting():
                    try:
                        running.append(subprocess.Popen(
                            command, cwd=work, stdin=subprocess.DEVNULL, stdout=said,
                            stderr=said, start_new_session=True))
                    except OSError as e:
                        raise Unavailable("no-compiler", f"jit: the C compiler {command[0]} "
                                          f"cannot be run: {e.strerror}") from None
            for proc in [p for p in running if p.poll() is not None]:
                running.remove(proc)
                if proc.returncode:
                    failed = proc
            stop, hung = stop_reason(deadline, cancelled), time.perf_counter() > sum(limit)
            if stop or hung:
                break
            if running and failed is None:
                with contextlib.suppress(OSError):   # a live build: never taken for stale
                    os.utime(work)
                time.sleep(_POLL if len(jobs) == 1 else _POLL / 10)
    finally:
        for proc in running:
            if proc.poll() is None:
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    if stop:
        raise stop
    if hung:
        raise Unavailable("compiler-hangs", f"jit: {compiler_name} was stopped after "
                          f"{limit[1]:g} s" + _words(work))
    if failed is not None:
        raise Unavailable("compiler-failed", f"jit: {compiler_name} failed on the generated "
                          f"code" + (_words(work) or ": "))


def verified(lib):
    """Whether ``lib`` holds exactly the bytes kinetwork recorded when it built it, in files
    of the current user's that no one else may write."""
    try:
        for path in (lib, record(lib)):
            st = path.lstat()
            if not stat.S_ISREG(st.st_mode) or st.st_uid != os.getuid() or st.st_mode & 0o022:
                return False
        return hmac.compare_digest(record(lib).read_bytes().strip(), sha256(lib))
    except OSError:
        return False
