"""The optimised tier of a compiled library: built in the background, swapped into the quick
library already in use, and kept in the cache for every later run.

A large function's first library is built quickly (``jit.py``: -O0, the quick tier) and its
entry points forward through pointers (``jit_source.swappable``). The optimised build of the
same C (-O1) is made by a process of its own (``jit_background.py``), at a low priority,
which outlives the process that asked for it: a script that ends before the build does still
leaves the optimised library to the next run. One process builds a given library at a time:
the builder holds an exclusive ``flock`` on ``<library>.lock`` while it works, and a process
that finds the lock taken waits for it instead of building again. The library is moved into
the cache whole with its record (``jit_build.build``), or not at all.

When the optimised library is in the cache, a thread of the process that loaded the quick
one checks its record and points each quick entry point at the optimised one
(``kinetwork_swap``). Both are compiled from the same C with the same floating-point
contract (``-ffp-contract=off``): an integration under way when the pointer changes goes on
with the same numbers, only faster.
"""

import contextlib
import ctypes
import fcntl
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import threading

from .jit_build import BUILD_PREFIX, verified

#: the background builder's priority (``nice``): it yields to the run it serves
NICE = 10
#: the background build's time limit [s]: it delays no one, so it may take long on a busy
#: machine (a 1024-link chain: 24 s of compiler time)
BACKGROUND_TIMEOUT = 1800.0

_WATCHERS = {}                     # quick library -> the thread that swaps it
_SWAPPED = {}                      # quick library -> "optimised" or why not
_KEPT = []                         # the optimised libraries loaded: never unloaded
_STATE = threading.Lock()


class Pending:
    """An optimised library that is being built: by ``process`` (ours), or by another
    process that holds ``lock``."""

    def __init__(self, lib, process=None, lock=None):
        self.lib, self.process, self.lock = lib, process, lock

    def wait(self):
        """Until the build ends (however it ends)."""
        if self.process is not None:
            self.process.wait()
        elif self.lock is not None:
            with contextlib.suppress(OSError), open(self.lock, "rb") as held:
                fcntl.flock(held, fcntl.LOCK_SH)            # released as the builder exits


def failed_marker(lib):
    """Where a background build that failed says why (no other one is tried for ``lib``)."""
    return lib.with_name(lib.name + ".failed")


def lock_path(lib):
    return lib.with_name(lib.name + ".lock")


def start(lib, name, serialised, jacobian):
    """Have the optimised library ``lib`` built in the background, from the Functions'
    serialisations; a ``Pending``, or None when it failed before (``failed_marker``)."""
    if failed_marker(lib).exists():
        return None
    fd = os.open(lock_path(lib), os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o600)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:                   # another process builds it: wait for that
            return Pending(lib, lock=lock_path(lib))
        if verified(lib):                         # it finished just now
            return Pending(lib)
        job = pathlib.Path(tempfile.mkdtemp(prefix=BUILD_PREFIX + "job-", dir=lib.parent))
        for i, text in enumerate(serialised):
            (job / f"f{i}.casadi").write_text(text)
        (job / "job.json").write_text(json.dumps({
            "name": name, "jacobian": bool(jacobian), "library": str(lib),
            "functions": len(serialised), "lock": str(lock_path(lib))}))
        # the builder imports this kinetwork, wherever it comes from
        package_root = str(pathlib.Path(__file__).resolve().parents[2])
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(
            filter(None, [package_root, os.environ.get("PYTHONPATH")]))}
        process = subprocess.Popen(
            [sys.executable, "-m", "kinetwork.solver.jit_background", str(job)],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            pass_fds=(fd,), start_new_session=True, env=env)
        return Pending(lib, process=process)
    except OSError:
        return None                               # no builder: the quick tier stays
    finally:
        os.close(fd)                              # the builder holds its own copy


def watch(quick, pending, entries):
    """Swap the optimised library into ``quick`` (loaded by CasADi) when ``pending`` is
    built; ``entries``: the entry points the library holds."""
    key = str(quick)
    with _STATE:
        if key in _WATCHERS:
            return
        thread = threading.Thread(target=_await, args=(quick, pending, entries),
                                  name="kinetwork-jit-swap", daemon=True)
        _WATCHERS[key] = thread
        _SWAPPED[key] = "building"
    thread.start()


def wait(timeout=None):
    """Wait for every optimised build this process waits for, and their swaps; return
    {quick library: "optimised" or why it was not swapped}."""
    with _STATE:
        threads = list(_WATCHERS.values())
    for thread in threads:
        thread.join(timeout)
    with _STATE:
        return dict(_SWAPPED)


def state(quick):
    """"optimised" once ``quick`` (a path) calls the optimised code, "building" before, why
    not otherwise; None if it was never tiered in this process."""
    with _STATE:
        return _SWAPPED.get(str(quick))


def _await(quick, pending, entries):
    pending.wait()
    if not verified(pending.lib):
        marker = failed_marker(pending.lib)
        why = marker.read_text().strip() if marker.exists() else "the build did not finish"
        with _STATE:
            _SWAPPED[str(quick)] = f"not swapped: {why}"
        return
    try:
        _swap(quick, pending.lib, entries)
        outcome = "optimised"
    except (OSError, AttributeError) as e:
        outcome = f"not swapped: {e}"
    with _STATE:
        _SWAPPED[str(quick)] = outcome


def _swap(quick, optimised, entries):
    """Point the entry points of the loaded library ``quick`` at those of ``optimised``:
    every one or, when one is missing, none."""
    # the handle CasADi has loaded (never load a second copy: its pointers are not CasADi's)
    handle = ctypes.CDLL(str(quick), mode=os.RTLD_NOLOAD | os.RTLD_LOCAL)
    swaps = [getattr(handle, f"{name}_kinetwork_swap") for name in entries]
    target = ctypes.CDLL(str(optimised), mode=os.RTLD_LOCAL)
    impls = [ctypes.cast(getattr(target, name), ctypes.c_void_p) for name in entries]
    _KEPT.append(target)
    for swap, impl in zip(swaps, impls):
        swap.argtypes, swap.restype = [ctypes.c_void_p], ctypes.c_int
        if swap(impl):
            raise OSError(f"{quick.name}: the swap of an entry point was refused")
