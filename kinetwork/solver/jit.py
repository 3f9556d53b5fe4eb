"""Just-in-time C compilation of CasADi Functions, cached on disk, in two tiers.

A Function is turned into C by CasADi's code generator, compiled with the system's C compiler
into a shared library named by the hash of the Function's serialisation (and compiler, flags,
tier and CasADi version), and loaded back with ``casadi.external``. The key is found without
generating any C: a cache hit costs the serialisation and a hash (N = 128 chain: 0.09 s
against 0.26 s for generating the C, and no Jacobian is built when the library holds one).
A long function is compiled in parts (``jit_source.split``), several compilers at once. The
library is kept in the cache folder, so a model compiled once is loaded in milliseconds by
every later run, in any process. A right-hand side compiled this way costs ~1.2 us per
evaluation at 16 links, against ~11 us in CasADi's SX virtual machine.

Tiers. gcc -O1 makes code 3-4x faster than -O0 and takes 3-4x longer to compile it: a
function of up to QUICK_STATEMENTS statements is compiled at -O1 at once (the optimised tier);
a longer one (a 3-D chain of 128 links: 57,000) gets a quick library first (-O0), which the
run uses at once, while a process of its own builds the optimised library from the same C in
the background (``jit_tiers.py``). When it is ready, the quick library's entry points are
pointed at the optimised ones, in the middle of a run if one is under way (the same numbers:
same C, no contraction of floating-point operations in either tier), and the cache keeps it
for every later run. ``KINETWORK_JIT_LEVEL``: ``tiered`` (default), ``quick`` (no optimised
build) or ``optimised`` (every function at -O1, in the foreground).

The cache folder is ``$KINETWORK_CACHE``, else ``$XDG_CACHE_HOME/kinetwork``, else
``$HOME/.cache/kinetwork``; the compiler is ``$CC``, else ``gcc``, else ``cc``.
``KINETWORK_JIT=0`` turns compilation off where ``jit`` is left to the default.

Trust model. Loading a library runs its code (constructors run on load), so the cache is a
cache, never a way for others to run code in kinetwork's process:

- a library is loaded only if kinetwork built it for this exact code. Beside
  ``<name>_<key>.so`` it writes ``.so.sha256``, the sha256 of the bytes the compiler
  produced, both moved into place atomically; a library with no record, or whose bytes differ
  from it (planted, truncated by a full disk, damaged), is rebuilt over, never loaded;
- the record proves the bytes are the ones written, not who wrote them: the folder settles
  that. It is created 0700 and used only while it, and each file loaded, is the current
  user's and not writable by group or others (whoever could write there could forge a record);
- when the cache or the compiler cannot be used, CasADi's virtual machine runs instead (same
  numbers, slower), said once per reason per process (``JitFallbackWarning``), or raised as a
  ``ModelError`` when C was required. A deadline or a cancellation falls back quietly: the run
  that set it stops itself.

One process-wide lock serialises code generation, builds and loads (CasADi's Functions and
loader are not thread-safe: four threads on a cold cache crashed); processes coordinate
through atomic renames, and a background build through its lock file. Past
``MAX_CACHE_BYTES``, the least recently loaded libraries go.
"""

import contextlib
import fcntl
import functools
import hashlib
import os
import re
import shutil
import stat
import threading
import time
import warnings

import casadi as ca

from ..errors import KinetworkWarning, ModelError
from ..equations import stored
from ..util import cache_folder, trim_least_recent
from . import jit_source, jit_tiers
from .jit_build import (BUILD_PREFIX, Unavailable as _Unavailable, build, cores as _cores,
                        os_error as _os_error, record as _record, sha256 as _sha256,
                        stop_reason as _stop, verified as _verified)

#: the flags of every library; ``-ffp-contract=off``: no fused multiply-add in either tier
#: (where the target has one), so that both compute the same numbers
CFLAGS = ("-fPIC", "-ffp-contract=off")
#: the tiers' optimisation levels: -O1 runs as fast as -O2/-O3 on CasADi's straight-line
#: code and compiles sooner; -O0 compiles 3-4x sooner and runs 3-4x slower
LEVELS = {"quick": ("-O0",), "optimised": ("-O1",)}
#: a function of more statements than this gets the quick tier first (see the docstring):
#: -O1 would take it more than ~2 s of compiler time
QUICK_STATEMENTS = 20_000
#: a function of more statements than SPLIT_STATEMENTS is compiled as parts of about
#: PART_STATEMENTS each, each in its own translation unit, as many compilers at once as there
#: are cores (see ``jit_source.split``). Below it, one file: the parts' calls and the values
#: they pass cost ~10 % of an evaluation at N = 128
SPLIT_STATEMENTS, PART_STATEMENTS = 20_000, 2_500
#: a Jacobian of more statements than this is compiled at -O0 in both tiers: it is evaluated
#: once per Newton setup, not per step (the eight-four-bar chain's, 207,000 statements)
JACOBIAN_O1_STATEMENTS = 20_000
#: the C a key names: bump when the generated or split code changes for the same Function
_SCHEME = "parts-2"
#: a compiler still running after this long (s) is taken to hang (N = 128 builds in 2.5 s)
COMPILE_TIMEOUT = 300.0
#: the cache is trimmed to this size after each build, least recently loaded first
MAX_CACHE_BYTES = 512 * 2**20

#: how kinetwork names a library: see ``_names``
_LIBRARY_NAME = re.compile(r"[A-Za-z0-9_]+(-quick)?_[0-9a-f]{20}\.so")
_POLL = 0.05                                  # s between looks at the lock
_QUIET = ("cancelled", "deadline")            # fallbacks the caller asked for
_LOCK = threading.RLock()
_WARNED = set()                               # the reasons already warned of in this process
_WARNED_LOCK = threading.Lock()               # not _LOCK: a build may hold that for minutes
_PENDING = {}                                 # quick library -> jit_tiers.Pending
_WATCHERS = []                                # see ``watching``


class JitFallbackWarning(KinetworkWarning):
    """C compilation was not possible: CasADi's virtual machine runs instead (same numbers)."""


@contextlib.contextmanager
def watching(told):
    """While in it, ``told(True)`` when a C compiler is about to run for a library and
    ``told(False)`` when a library is ready to load (built, or found in the cache); nothing
    when none can be had: what the studio's run says it is doing ("compiling" or
    "integrating", ``studio/work.py``)."""
    _WATCHERS.append(told)
    try:
        yield
    finally:
        _WATCHERS.remove(told)


def _tell(building):
    for told in list(_WATCHERS):
        told(building)


def compiler():
    """The C compiler's path, or None when the machine has none."""
    return _find_compiler(os.environ.get("CC"), os.environ.get("PATH"))


@functools.lru_cache(maxsize=8)
def _find_compiler(cc, path):
    for name in (cc, "gcc", "cc"):
        if name and (found := shutil.which(name, path=path)):
            return found
    return None


def enabled(jit=None):
    """Whether to compile: ``jit`` if given, else when a compiler exists (KINETWORK_JIT=0: no)."""
    if jit is not None:
        return bool(jit)
    if os.environ.get("KINETWORK_JIT", "1").strip().lower() in ("0", "false", "no", "off"):
        return False
    return compiler() is not None


def level():
    """``KINETWORK_JIT_LEVEL``: ``tiered`` (default), ``quick`` or ``optimised``."""
    value = os.environ.get("KINETWORK_JIT_LEVEL", "tiered").strip().lower() or "tiered"
    if value not in ("tiered", "quick", "optimised"):
        raise ModelError(f"KINETWORK_JIT_LEVEL={value!r:.40}: must be tiered, quick or "
                         f"optimised")
    return value


def cache_dir():
    """Where compiled libraries are kept (a ``ModelError`` when there is no home to keep
    them in)."""
    if (folder := cache_folder()) is not None:
        return folder
    raise _Unavailable("no-home", "jit: no cache folder ($HOME is not set; set "
                                  "$KINETWORK_CACHE to a private folder)")


def compile_functions(name, functions, stats=None, deadline=None, cancelled=None,
                      jacobian=False):
    """Compile ``functions`` (CasADi Functions) into one shared library; return its path.

    With ``jacobian``, the library also holds each function's exact Jacobian (built only when
    the library is not in the cache). ``stats`` (a dict), if given, receives ``jit_seconds``
    (the key and, on a cache miss, code generation and the compiler), ``jit_cached`` and
    ``jit_tier`` (``optimised``, or ``quick`` while the optimised library is built in the
    background). The compiler is stopped when ``deadline`` (a ``time.perf_counter()`` value)
    passes or ``cancelled()`` returns True. Raises ``ModelError`` saying why when no library
    can be had.
    """
    start = time.perf_counter()
    lib, hit, tier = _library(name, functions, deadline, cancelled, jacobian)
    _tell(False)
    if stats is not None:
        stats["jit_cached"] = stats.get("jit_cached", True) and hit
        stats["jit_seconds"] = stats.get("jit_seconds", 0.0) + time.perf_counter() - start
        if stats.get("jit_tier") != "quick":
            stats["jit_tier"] = tier
    return lib


def _library(name, functions, deadline, cancelled, jacobian):
    """``compile_functions``' (library, whether the cache had it, its tier)."""
    with _locked(deadline, cancelled):
        cc = compiler()
        if cc is None:
            given = os.environ.get("CC")
            raise _Unavailable("no-compiler", "jit: no C compiler found " + (
                f"($CC={given} is not found, nor gcc or cc)" if given else
                "(set $CC, or install gcc)"))
        folder = _folder()
        serialised = [f.serialize() for f in functions]
        names = _names(name, serialised, cc, jacobian)
        optimised = folder / names["optimised"]
        hit, tier = _verified(optimised), "optimised"
        if hit:
            lib = optimised
            _touch(lib)
        elif _tier(functions) == "optimised":
            lib = optimised
            _tell(True)
            build(cc, _generated(functions, jacobian, "optimised", deadline, cancelled), lib,
                  deadline, cancelled, COMPILE_TIMEOUT)
            _trim(folder, keep=lib)
        else:
            tier, lib = "quick", folder / names["quick"]
            hit = _verified(lib)
            if hit:
                _touch(lib)
            else:
                _tell(True)
                build(cc, _generated(functions, jacobian, "quick", deadline, cancelled), lib,
                      deadline, cancelled, COMPILE_TIMEOUT)
                _trim(folder, keep=lib)
            if level() == "tiered" and str(lib) not in _PENDING:
                pending = jit_tiers.start(optimised, name, serialised, jacobian)
                if pending is not None:
                    _PENDING[str(lib)] = pending
    return lib, hit, tier


def build_optimised(name, functions, lib, jacobian, timeout):
    """Build the optimised library ``lib`` of ``functions`` (what the background builder of
    ``jit_tiers`` runs), unless it is in the cache already."""
    cc = compiler()
    if cc is None:
        raise _Unavailable("no-compiler", "jit: no C compiler found")
    with _LOCK:
        if not _verified(lib):
            build(cc, _generate(functions, jacobian, "optimised"), lib, timeout=timeout)
            _trim(lib.parent, keep=lib)


def external(f, jacobian=False, stats=None, required=False, deadline=None, cancelled=None):
    """``f`` compiled to C and loaded back, with the same inputs and outputs.

    With ``jacobian``, the library also holds the exact Jacobian (what Newton iterations use);
    without, derivatives fall back to finite differences of the compiled code, so that methods
    that never ask for them do not pay for compiling them (O(N^2) code for an N-link chain).
    A long ``f`` may come as its quick tier, made faster in place once its optimised build
    is in (see the module's docstring; ``wait`` waits for that).
    When no library can be had, ``f`` itself is returned (see the module's docstring), and
    ``stats["jit_fallback"]`` says why; with ``required`` that is a ``ModelError`` instead.
    """
    try:
        with _locked(deadline, cancelled):
            lib = compile_functions(f.name() + ("_jac" if jacobian else ""), [f], stats,
                                    deadline, cancelled, jacobian)
            try:
                g = ca.external(f.name(), str(lib), {"enable_fd": not jacobian})
            except RuntimeError as e:
                raise _Unavailable("load-failed", f"jit: {lib} cannot be loaded: {e}") from None
            if str(lib) in _PENDING:
                entries = [f.name()] + ([f"jac_{f.name()}"] if jacobian else [])
                jit_tiers.watch(lib, _PENDING[str(lib)], entries)
            return g
    except _Unavailable as why:
        if required and why.kind not in _QUIET:
            raise ModelError(f"{why}; run with jit=False to use CasADi's virtual "
                             "machine") from None
        if stats is not None:
            stats["jit_fallback"] = str(why)
        with _WARNED_LOCK:
            warn = why.kind not in _QUIET and why.kind not in _WARNED
            _WARNED.add(why.kind)
        if warn:
            warnings.warn(f"{why}; running in CasADi's virtual machine instead (slower, same "
                          "results)", JitFallbackWarning, stacklevel=2)
        return f


def wait(timeout=None):
    """Wait until every optimised library this process waits for is built and swapped in
    (at most ``timeout`` s each); return {quick library: ``optimised``, or why not}."""
    return jit_tiers.wait(timeout)


def cache_info():
    """What the cache holds of kinetwork's own (libraries with their records, see
    :func:`recorded`): ``folder``, ``entries``, ``bytes`` and ``libraries``, a list of (file
    name, bytes, mtime), the most recently loaded first; ``systems`` and ``systems_bytes``,
    the derived Systems kept (``equations.stored``)."""
    folder = cache_dir()
    libraries = [(lib.name, size, mtime) for lib, size, mtime in recorded(folder)]
    libraries.sort(key=lambda entry: -entry[2])
    systems = stored.kept()
    return {"folder": str(folder), "entries": len(libraries),
            "bytes": sum(size for _, size, _ in libraries), "libraries": libraries,
            "systems": len(systems), "systems_bytes": sum(size for _, size, _ in systems)}


def recorded(folder):
    """(path, bytes, mtime) of each library kinetwork built in ``folder``: a regular file
    named as kinetwork names libraries (``<name>[-quick]_<20 hex digits>.so``) with its
    record beside it. Nothing else in the folder is counted, trimmed or cleared."""
    found = []
    if not folder.is_dir():
        return found
    for lib in folder.glob("*.so"):
        if not _LIBRARY_NAME.fullmatch(lib.name):
            continue
        with contextlib.suppress(OSError):
            st, rec = lib.lstat(), _record(lib).lstat()
            if stat.S_ISREG(st.st_mode) and stat.S_ISREG(rec.st_mode):
                found.append((lib, st.st_size, st.st_mtime))
    return found


def clear_cache():
    """Remove what kinetwork wrote in the cache: the libraries its records name, those
    records, records left without their library, the notes of failed background builds and
    lock files no build holds (of libraries named as kinetwork names them), build folders
    left by killed processes, and the derived Systems kept (``equations.stored``); return
    the number of files removed. Anything else in the folder (a library without a record,
    any other file) is left alone."""
    folder = cache_dir()
    if not folder.is_dir():
        return 0
    removed = stored.clear()
    with _LOCK:
        for lib, _, _ in recorded(folder):
            removed += _remove(lib) + _remove(_record(lib))
        for rec in folder.glob("*.so.sha256"):
            lib = rec.with_name(rec.name[:-len(".sha256")])
            if _LIBRARY_NAME.fullmatch(lib.name) and not lib.exists() and _is_record(rec):
                removed += _remove(rec)
        for note in folder.glob("*.so.failed"):
            if _LIBRARY_NAME.fullmatch(note.name[:-len(".failed")]) and \
                    stat.S_ISREG(note.lstat().st_mode):
                removed += _remove(note)
        for lock in folder.glob("*.so.lock"):
            if _LIBRARY_NAME.fullmatch(lock.name[:-len(".lock")]):
                removed += _remove_unheld(lock)
        for old in _stale_builds(folder):
            removed += sum(1 for p in old.rglob("*") if not p.is_dir())
            shutil.rmtree(old, ignore_errors=True)
    return removed


def _is_record(path):
    """Whether ``path`` is a regular file holding what kinetwork writes in a record."""
    try:
        if not stat.S_ISREG(path.lstat().st_mode) or path.lstat().st_size != 65:
            return False
        return re.fullmatch(rb"[0-9a-f]{64}\n", path.read_bytes()) is not None
    except OSError:
        return False


# -- the cache folder --------------------------------------------------------------------------
def _folder():
    """The cache folder, created private if missing, once checked fit to load code from."""
    folder = cache_dir()
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        st = folder.stat()
    except FileExistsError:
        raise _Unavailable("not-a-folder", f"jit: the cache {folder} is a file, not a folder")
    except OSError as e:
        raise _os_error(folder, e) from None
    if st.st_uid != os.getuid() or st.st_mode & 0o022:
        whose = (f"belongs to uid {st.st_uid}" if st.st_uid != os.getuid() else
                 f"is writable by others (mode {stat.S_IMODE(st.st_mode):o})")
        raise _Unavailable("unsafe-folder", f"jit: the cache {folder} {whose}; kinetwork loads "
                           "no code from it (make it yours, chmod 700)")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise _Unavailable("read-only", f"jit: the cache {folder} is read-only")
    return folder


@contextlib.contextmanager
def _locked(deadline, cancelled):
    """The process-wide lock, waited for only as long as the caller wants the result."""
    while not _LOCK.acquire(timeout=_POLL):
        if stop := _stop(deadline, cancelled):
            raise stop
    try:
        yield
    finally:
        _LOCK.release()


# -- one library ---------------------------------------------------------------------------------
def _tier(functions):
    """The tier a library of ``functions`` gets first (``level``, and their length)."""
    if level() == "optimised" or \
            max(f.n_instructions() for f in functions) <= QUICK_STATEMENTS:
        return "optimised"
    return "quick"


def _names(name, serialised, cc, jacobian):
    """{tier: the library's file name}. A name is the hash of what the library is built from
    (the Functions' serialisations, whether it holds their Jacobians, the compiler, its flags,
    the tier, CasADi and the way the C is laid out), so that another model, compiler or
    CasADi never finds it; no C is generated to find it."""
    common = hashlib.sha256("\0".join([*serialised, str(bool(jacobian)), cc, *CFLAGS, _SCHEME,
                                        str((SPLIT_STATEMENTS, PART_STATEMENTS,
                                             JACOBIAN_O1_STATEMENTS)),
                                        ca.__version__]).encode())
    out = {}
    for tier, suffix in (("optimised", ""), ("quick", "-quick")):
        key = common.copy()
        key.update(f"\0{tier}\0{' '.join(LEVELS[tier])}".encode())
        out[tier] = f"{name}{suffix}_{key.hexdigest()[:20]}.so"
    return out


def _plan(name, functions, cc, jacobian=False, tier="optimised"):
    """(a callable giving the C sources, the library's file name) of ``tier``."""
    names = _names(name, [f.serialize() for f in functions], cc, jacobian)
    return (lambda: _generate(functions, jacobian, tier)), names[tier]


def _generate(functions, jacobian, tier):
    """{file name: (C, compiler flags)} of the library of ``functions`` in ``tier``; the
    quick tier's entry points are swappable (``jit_source.swappable``)."""
    sources = {}
    for f in functions:
        sources.update(_sources(f.name(), f, tier, tier == "quick"))
        if jacobian:
            j = f.jacobian()
            small = j.n_instructions() <= JACOBIAN_O1_STATEMENTS
            sources.update(_sources(j.name(), j, tier if small else "quick",
                                    tier == "quick"))
    return sources


def _generated(functions, jacobian, tier, deadline, cancelled):
    """``_generate``, unless the caller no longer wants the library (``deadline`` passed,
    ``cancelled()``): asked before and after writing the C, which takes seconds for a long
    model."""
    if stop := _stop(deadline, cancelled):
        raise stop
    sources = _generate(functions, jacobian, tier)
    if stop := _stop(deadline, cancelled):
        raise stop
    return sources


def _sources(name, f, tier, swappable):
    part = PART_STATEMENTS if f.n_instructions() > SPLIT_STATEMENTS else None
    files = jit_source.sources(name, f, [*LEVELS[tier], *CFLAGS], part)
    main = f"{name}_main.c"
    if swappable:
        text, flags = files[main]
        files[main] = (jit_source.swappable(text) or text, flags)
    return files


# -- the size bound -------------------------------------------------------------------------------
def _touch(lib):
    with contextlib.suppress(OSError):
        os.utime(lib)                   # recently used: the cache is trimmed LRU


def _trim(folder, keep):
    """Remove the least recently loaded libraries until kinetwork's own (:func:`recorded`)
    fit in MAX_CACHE_BYTES (never ``keep``, just built), and build folders left by killed
    processes. Files without a record are neither counted nor removed."""
    def remove(lib):
        _remove(lib)
        _remove(_record(lib))
    trim_least_recent(recorded(folder), MAX_CACHE_BYTES, keep, remove)
    for old in _stale_builds(folder):
        shutil.rmtree(old, ignore_errors=True)


def _stale_builds(folder):
    """Build folders no live build can own: a build touches its folder while its compilers
    run, and a compiler runs at most COMPILE_TIMEOUT (the background one's job folder lives
    only until it has read it)."""
    old, stale = time.time() - COMPILE_TIMEOUT - 60, []
    for path in folder.glob(BUILD_PREFIX + "*"):
        with contextlib.suppress(OSError):            # gone meanwhile: another process's
            if stat.S_ISDIR((st := path.lstat()).st_mode) and st.st_mtime < old:
                stale.append(path)
    return stale


def _remove(path):
    try:
        path.unlink()
        return 1
    except OSError:
        return 0


def _remove_unheld(lock):
    """Remove a lock file if no build holds it."""
    try:
        with open(lock, "rb") as held:
            fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return _remove(lock)
    except OSError:
        return 0
