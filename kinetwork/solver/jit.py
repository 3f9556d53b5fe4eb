"""Just-in-time C compilation of CasADi Functions, cached on disk.

A Function is turned into C by CasADi's code generator, compiled with the system's C compiler
into a shared library named by the hash of the Function's serialisation (and compiler, flags
and CasADi version), and loaded back with ``casadi.external``. The key is found without
generating any C: a cache hit costs the serialisation and a hash (N = 128 chain: 0.09 s
against 0.26 s for generating the C, and no Jacobian is built when the library holds one).
A long function is compiled in parts (``_split``), several compilers at once. The library is
kept in the cache folder, so a model compiled once is loaded in milliseconds by every later
run, in any process. A right-hand side compiled this way
costs ~1.2 us per evaluation at 16 links, against ~11 us in CasADi's SX virtual machine.

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
through atomic renames. Past ``MAX_CACHE_BYTES``, the least recently loaded libraries go.
"""

import contextlib
import errno
import functools
import hashlib
import hmac
import os
import pathlib
import re
import shutil
import signal
import stat
import subprocess
import tempfile
import threading
import time
import warnings

import casadi as ca

from ..errors import ModelError

#: -O1 runs as fast as -O2/-O3 on CasADi's straight-line code and compiles 30 % sooner
#: (N = 128 chain: 2.5 s against 3.6 s); -O0 compiles 4x sooner but runs 2.7x slower there
CFLAGS = ("-O1", "-fPIC", "-shared")
#: a function of more statements than SPLIT_STATEMENTS is compiled as parts of about
#: PART_STATEMENTS each, each in its own translation unit, as many compilers at once as there
#: are cores (see ``_split``). Below it, one file: the parts' calls and the values they pass
#: cost ~10 % of an evaluation at N = 128
SPLIT_STATEMENTS, PART_STATEMENTS = 20_000, 5_000
#: a Jacobian of more statements than this is compiled at -O0: it is evaluated once per
#: Newton setup, not per step, and -O0 compiles it 4x sooner (the eight-four-bar chain's,
#: 207,000 statements)
JACOBIAN_O1_STATEMENTS = 20_000
#: any function of more statements than this is compiled at -O0 too: gcc -O1 spent 18.7 s of
#: CPU on a 256-link chain's right-hand side (37,000 statements, mostly in register
#: allocation), -O0 3.2 s; the code then runs 2.8x slower (bench/results/study_scaling.md),
#: which a model that size pays on every run. Chains past ~280 links, 148,000 at 1024
O1_STATEMENTS = 40_000
#: the C a key names: bump when the generated or split code changes for the same Function
_SCHEME = "parts-1"
#: a compiler still running after this long (s) is taken to hang (N = 128 builds in 2.5 s)
COMPILE_TIMEOUT = 300.0
#: the cache is trimmed to this size after each build, least recently loaded first
MAX_CACHE_BYTES = 512 * 2**20

_BUILD_PREFIX = "kinetwork-build-"
#: how kinetwork names a library: see ``_plan``
_LIBRARY_NAME = re.compile(r"[A-Za-z0-9_]+_[0-9a-f]{20}\.so")
_POLL = 0.05                                  # s between looks at the compiler and the lock
_QUIET = ("cancelled", "deadline")            # fallbacks the caller asked for
_LOCK = threading.RLock()
_WARNED = set()                               # the reasons already warned of in this process
_WARNED_LOCK = threading.Lock()               # not _LOCK: a build may hold that for minutes


class JitFallbackWarning(UserWarning):
    """C compilation was not possible: CasADi's virtual machine runs instead (same numbers)."""


class _Unavailable(ModelError):
    """Why no compiled library can be had; ``kind`` is the reason warned of once."""

    def __init__(self, kind, message):
        super().__init__(message)
        self.kind = kind


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


def cache_dir():
    """Where compiled libraries are kept (a ``ModelError`` when there is no home to keep
    them in)."""
    if path := os.environ.get("KINETWORK_CACHE"):
        return pathlib.Path(path)
    if base := os.environ.get("XDG_CACHE_HOME"):
        return pathlib.Path(base) / "kinetwork"
    if home := os.environ.get("HOME"):
        return pathlib.Path(home) / ".cache" / "kinetwork"
    raise _Unavailable("no-home", "jit: no cache folder ($HOME is not set; set "
                                  "$KINETWORK_CACHE to a private folder)")


def compile_functions(name, functions, stats=None, deadline=None, cancelled=None,
                      jacobian=False):
    """Compile ``functions`` (CasADi Functions) into one shared library; return its path.

    With ``jacobian``, the library also holds each function's exact Jacobian (built only when
    the library is not in the cache). ``stats`` (a dict), if given, receives ``jit_seconds``
    (the key and, on a cache miss, code generation and the compiler) and ``jit_cached``. The
    compiler is stopped when ``deadline`` (a ``time.perf_counter()`` value) passes or
    ``cancelled()`` returns True. Raises ``ModelError`` saying why when no library can be had.
    """
    start = time.perf_counter()
    with _locked(deadline, cancelled):
        cc = compiler()
        if cc is None:
            given = os.environ.get("CC")
            raise _Unavailable("no-compiler", "jit: no C compiler found " + (
                f"($CC={given} is not found, nor gcc or cc)" if given else
                "(set $CC, or install gcc)"))
        folder = _folder()
        generate, filename = _plan(name, functions, cc, jacobian)
        lib = folder / filename
        hit = _verified(lib)
        if hit:
            with contextlib.suppress(OSError):
                os.utime(lib)                   # recently used: the cache is trimmed LRU
        else:
            def check():                        # between the steps of writing the C
                if stop := _stop(deadline, cancelled):
                    raise stop
            _build(cc, name, generate(check), lib, deadline, cancelled)
            _trim(folder, keep=lib)
    if stats is not None:
        stats["jit_cached"] = stats.get("jit_cached", True) and hit
        stats["jit_seconds"] = stats.get("jit_seconds", 0.0) + time.perf_counter() - start
    return lib


def external(f, jacobian=False, stats=None, required=False, deadline=None, cancelled=None):
    """``f`` compiled to C and loaded back, with the same inputs and outputs.

    With ``jacobian``, the library also holds the exact Jacobian (what Newton iterations use);
    without, derivatives fall back to finite differences of the compiled code, so that methods
    that never ask for them do not pay for compiling them (O(N^2) code for an N-link chain).
    When no library can be had, ``f`` itself is returned (see the module's docstring), and
    ``stats["jit_fallback"]`` says why; with ``required`` that is a ``ModelError`` instead.
    """
    try:
        with _locked(deadline, cancelled):
            lib = compile_functions(f.name() + ("_jac" if jacobian else ""), [f], stats,
                                    deadline, cancelled, jacobian)
            try:
                return ca.external(f.name(), str(lib), {"enable_fd": not jacobian})
            except RuntimeError as e:
                raise _Unavailable("load-failed", f"jit: {lib} cannot be loaded: {e}") from None
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


def cache_info():
    """What the cache holds of kinetwork's own (libraries with their records, see
    :func:`recorded`): ``folder``, ``entries``, ``bytes`` and ``libraries``, a list of (file
    name, bytes, mtime), the most recently loaded first."""
    folder = cache_dir()
    libraries = [(lib.name, size, mtime) for lib, size, mtime in recorded(folder)]
    libraries.sort(key=lambda entry: -entry[2])
    return {"folder": str(folder), "entries": len(libraries),
            "bytes": sum(size for _, size, _ in libraries), "libraries": libraries}


def recorded(folder):
    """(path, bytes, mtime) of each library kinetwork built in ``folder``: a regular file
    named as kinetwork names libraries (``<name>_<20 hex digits>.so``) with its record
    beside it. Nothing else in the folder is counted, trimmed or cleared."""
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
    records, records left without their library, and build folders left by killed
    processes; return the number of files removed. Anything else in the folder (a library
    without a record, any other file) is left alone."""
    folder = cache_dir()
    if not folder.is_dir():
        return 0
    removed = 0
    with _LOCK:
        for lib, _, _ in recorded(folder):
            removed += _remove(lib) + _remove(_record(lib))
        for rec in folder.glob("*.so.sha256"):
            lib = rec.with_name(rec.name[:-len(".sha256")])
            if _LIBRARY_NAME.fullmatch(lib.name) and not lib.exists() and _is_record(rec):
                removed += _remove(rec)
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


def _os_error(folder, e):
    if e.errno in (errno.ENOSPC, errno.EDQUOT):
        return _Unavailable("disk-full", f"jit: no space left for the cache {folder}")
    if e.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
        return _Unavailable("read-only", f"jit: the cache {folder} is read-only ({e.strerror})")
    if e.errno == errno.ENOTDIR:
        return _Unavailable("not-a-folder", f"jit: the cache {folder} is inside a file")
    return _Unavailable("cache-error", f"jit: the cache {folder} cannot be used: {e}")


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
def _plan(name, functions, cc, jacobian=False):
    """(a callable giving the C sources, the library's file name). The name is the hash of
    what the library is built from (the Functions' serialisations, whether it holds their
    Jacobians, the compiler, its flags, CasADi and the way the C is laid out), so that another
    model, compiler or CasADi never finds it; no C is generated to find it."""
    parts = [f.serialize() for f in functions]
    key = hashlib.sha256("\0".join([*parts, str(bool(jacobian)), cc, *CFLAGS, _SCHEME,
                                     str((SPLIT_STATEMENTS, PART_STATEMENTS,
                                          JACOBIAN_O1_STATEMENTS, O1_STATEMENTS)),
                                     ca.__version__]).encode())

    def generate(check=lambda: None):
        sources = {}
        for f in functions:
            check()
            sources.update(_sources(f.name(), f, optimise=True, check=check))
            if jacobian:
                check()
                j = f.jacobian()
                sources.update(_sources(
                    j.name(), j, optimise=j.n_instructions() <= JACOBIAN_O1_STATEMENTS,
                    check=check))
        return sources
    return generate, f"{name}_{key.hexdigest()[:20]}.so"


def _sources(name, f, optimise, check=lambda: None):
    """{file name: (C, compiler flags)} of ``f``, in parts when it is long (``_split``);
    ``check()`` between the steps raises when the caller no longer wants them."""
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    gen.add(f)
    check()
    optimise = optimise and f.n_instructions() <= O1_STATEMENTS
    flags = [*(("-O1",) if optimise else ("-O0",)), *(c for c in CFLAGS if c != "-O1")]
    size = PART_STATEMENTS if f.n_instructions() > SPLIT_STATEMENTS else None
    text = gen.dump()
    check()
    files = _split(text, size, check) if size else {"main.c": text}
    return {f"{name}_{k}" if k == "main.c" else k: (text, flags) for k, text in files.items()}


# -- long functions in parts ---------------------------------------------------------------------
_HEAD = re.compile(r"^static int (casadi_f\d+)\(const casadi_real\*\* arg, casadi_real\*\* res, "
                   r"casadi_int\* iw, casadi_real\* w, int mem\) \{\n", re.MULTILINE)
_END = "\n  return 0;\n}\n"
_DECLARE = re.compile(r"  casadi_real (a\d+(?:, a\d+)*);\Z")
_STATEMENT = re.compile(r"  (?:(a\d+)=([^;{}]*);|if \(res\[\d+\]!=0\) res\[\d+\]\[\d+\]=(a\d+);)\Z")
_VARIABLE = re.compile(r"\ba\d+\b")
_PREFIX = re.compile(r"#define CASADI_PREFIX\(ID\) (\w+)_ ## ID")


def _split(source, size, check=lambda: None):
    """The C ``source`` as {file name: text}: itself, or, when it holds a function of more
    than ``size`` statements, a main file and one file per part of that function.

    CasADi writes an SX Function as straight-line code on local scalars (``a12=(a3*a7);``,
    outputs ``if (res[0]!=0) res[0][5]=a12;``). A part is a run of ``size`` of those
    statements in a function of its own, on its own scalars: it loads the values it reads
    before writing them from a small array of the caller's, and stores there those it writes
    that a later part reads before writing (liveness, found by one backward pass). The caller
    keeps the array on its stack and calls the parts in order. A function holding anything
    else (a call, a loop) is left whole.
    """
    prefix = _PREFIX.search(source)
    config = source.find("/* Configuration this file was compiled with */")
    if not prefix or config < 0:
        return {"main.c": source}
    preamble = source[:config]
    files, out, declarations, pos = {}, [], [], 0
    for head in _HEAD.finditer(source):
        check()
        end = source.find(_END, head.end())
        lines = source[head.end():end].split("\n") if end > 0 else []
        k = 0
        while k < len(lines) and _DECLARE.match(lines[k]):
            k += 1
        body = [_STATEMENT.match(line) for line in lines[k:]]
        if len(body) <= size or not all(body):
            continue
        parts = [body[i:i + size] for i in range(0, len(body), size)]
        live, after = set(), [None] * len(parts)        # after[j]: live past part j
        for j in range(len(parts) - 1, -1, -1):
            after[j] = set(live)
            for m in reversed(parts[j]):
                if m.group(3):
                    live.add(m.group(3))
                else:
                    live.discard(m.group(1))
                    live.update(_VARIABLE.findall(m.group(2)))
        slots = {}
        calls = []
        for j, part in enumerate(parts):
            check()
            loads, written = [], set()
            for m in part:
                reads = [m.group(3)] if m.group(3) else _VARIABLE.findall(m.group(2))
                for v in reads:
                    if v not in written and v not in loads:
                        loads.append(v)
                if m.group(1):
                    written.add(m.group(1))
            stores = sorted(written & after[j])
            for v in loads + stores:
                slots.setdefault(v, len(slots))
            names = sorted(set(loads) | written)
            fn = f"{prefix.group(1)}_{head.group(1)}_p{j}"
            calls.append(fn)
            files[f"{fn}.c"] = "".join([
                preamble.replace(prefix.group(0),
                                 f"#define CASADI_PREFIX(ID) {fn}_ ## ID"),
                (f"\n__attribute__((visibility(\"hidden\")))\n"
                 f"void {fn}(const casadi_real** arg, casadi_real** res, casadi_real* s) {{\n"),
                "".join(f"  casadi_real {', '.join(names[i:i + 12])};\n"
                        for i in range(0, len(names), 12)),
                "".join(f"  {v}=s[{slots[v]}];\n" for v in loads),
                "\n".join(m.group(0) for m in part), "\n",
                "".join(f"  s[{slots[v]}]={v};\n" for v in stores), "}\n"])
        declarations += calls
        out += [source[pos:head.end()],
                f"  casadi_real s[{max(len(slots), 1)}];\n",
                "".join(f"  {fn}(arg, res, s);\n" for fn in calls)]
        pos = end
    if not files:
        return {"main.c": source}
    first = _HEAD.search(source).start()
    main = "".join(out + [source[pos:]])
    main = main[:first] + "".join(
        f"void {fn}(const casadi_real** arg, casadi_real** res, casadi_real* s);\n"
        for fn in declarations) + main[first:]
    return {"main.c": main, **files}


def _record(lib):
    return lib.with_name(lib.name + ".sha256")


def _sha256(path):
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        while chunk := file.read(1 << 20):
            digest.update(chunk)
    return digest.hexdigest().encode()


def _verified(lib):
    """Whether ``lib`` holds exactly the bytes kinetwork recorded when it built it."""
    try:
        for path in (lib, _record(lib)):
            st = path.lstat()
            if not stat.S_ISREG(st.st_mode) or st.st_uid != os.getuid() or st.st_mode & 0o022:
                return False
        return hmac.compare_digest(_record(lib).read_bytes().strip(), _sha256(lib))
    except OSError:
        return False


def _build_folder(folder):
    return tempfile.TemporaryDirectory(prefix=_BUILD_PREFIX, dir=folder)


def _build(cc, name, sources, lib, deadline, cancelled):
    """Compile ``sources`` ({file name: (C, flags)}) into ``lib`` and write its record, both
    moved into place whole."""
    try:
        # the build folder goes on every way out (a KeyboardInterrupt included): the
        # compilers are stopped first, then the folder removed
        with _build_folder(lib.parent) as tmp:
            work = pathlib.Path(tmp)
            if all(flags == list(CFLAGS) for _, flags in sources.values()) and \
                    all(src.endswith("_main.c") for src in sources):
                # short functions: one compiler run
                for src, (text, _) in sources.items():
                    (work / src).write_text(text)
                _compile([[cc, *CFLAGS, "-o", "lib.so", *sources, "-lm"]], work, deadline,
                         cancelled)
            else:           # side by side, then one link
                jobs = []
                for src, (text, flags) in sources.items():
                    (work / src).write_text(text)
                    jobs.append([cc, *(f for f in flags if f != "-shared"), "-c", src, "-o",
                                 src[:-2] + ".o"])
                # the longest first, so that the last to finish is short
                jobs.sort(key=lambda job: -len(sources[job[-3]][0]))
                _compile(jobs, work, deadline, cancelled)
                _compile([[cc, "-shared", "-o", "lib.so",
                           *(src[:-2] + ".o" for src in sources), "-lm"]],
                         work, deadline, cancelled)
            out = work / "lib.so"
            if not out.is_file():
                raise _Unavailable("compiler-silent", f"jit: {pathlib.Path(cc).name} exited "
                                   "without writing a library" + _words(work))
            out.chmod(0o700)                      # private whatever the umask
            for target in (lib, _record(lib)):    # a FIFO, a folder planted there: left be
                with contextlib.suppress(FileNotFoundError):
                    if not stat.S_ISREG(target.lstat().st_mode):
                        raise _Unavailable("cache-error", f"jit: {target} is not a regular "
                                           f"file; kinetwork replaces only its own files")
            record = work / "record"
            record.write_bytes(_sha256(out) + b"\n")
            record.chmod(0o600)
            os.replace(record, _record(lib))
            os.replace(out, lib)
    except OSError as e:
        raise _os_error(lib.parent, e) from None


def _cores():
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def _words(work):
    """The compilers' last words, for a message."""
    text = b"".join(p.read_bytes() for p in sorted(work.glob("stderr*")))
    words = text.decode(errors="replace").strip()[-400:]
    return f": {words}" if words else ""


def _compile(jobs, work, deadline, cancelled):
    """Run the compiler commands ``jobs`` in ``work``, as many at once as there are cores
    (relative names, so the output does not depend on the folder); stop them, with their
    children, on ``deadline``, ``cancelled()`` or COMPILE_TIMEOUT."""
    compiler_name = pathlib.Path(jobs[0][0]).name
    limit = time.perf_counter() + COMPILE_TIMEOUT
    waiting, running, failed = list(enumerate(jobs)), [], None
    stop = hung = None
    try:
        while (waiting or running) and failed is None:
            while waiting and len(running) < _cores():
                i, command = waiting.pop(0)
                with open(work / f"stderr{i:05d}", "wb") as said:
                    try:
                        running.append(subprocess.Popen(
                            command, cwd=work, stdin=subprocess.DEVNULL, stdout=said,
                            stderr=said, start_new_session=True))
                    except OSError as e:
                        raise _Unavailable("no-compiler", f"jit: the C compiler {command[0]} "
                                           f"cannot be run: {e.strerror}") from None
            for proc in [p for p in running if p.poll() is not None]:
                running.remove(proc)
                if proc.returncode:
                    failed = proc
            stop, hung = _stop(deadline, cancelled), time.perf_counter() > limit
            if stop or hung:
                break
            if running and failed is None:
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
        raise _Unavailable("compiler-hangs", f"jit: {compiler_name} was stopped after "
                           f"{COMPILE_TIMEOUT:g} s" + _words(work))
    if failed is not None:
        raise _Unavailable("compiler-failed", f"jit: {compiler_name} failed on the generated "
                           f"code" + (_words(work) or ": "))


def _stop(deadline, cancelled):
    """Why the caller no longer wants the library, if it does not."""
    if cancelled is not None and cancelled():
        return _Unavailable("cancelled", "jit: compilation cancelled")
    if deadline is not None and time.perf_counter() >= deadline:
        return _Unavailable("deadline", "jit: the run's deadline passed during compilation")
    return None


# -- the size bound -------------------------------------------------------------------------------
def _trim(folder, keep):
    """Remove the least recently loaded libraries until kinetwork's own (:func:`recorded`)
    fit in MAX_CACHE_BYTES (never ``keep``, just built), and build folders left by killed
    processes. Files without a record are neither counted nor removed."""
    libraries = sorted((mtime, size, lib) for lib, size, mtime in recorded(folder))
    total = sum(size for _, size, _ in libraries)
    for _, size, lib in libraries:
        if total <= MAX_CACHE_BYTES:
            break
        if lib != keep:
            _remove(lib)
            _remove(_record(lib))
            total -= size
    for old in _stale_builds(folder):
        shutil.rmtree(old, ignore_errors=True)


def _stale_builds(folder):
    """Build folders no live build can own (a build lasts at most COMPILE_TIMEOUT)."""
    old, stale = time.time() - COMPILE_TIMEOUT - 60, []
    for path in folder.glob(_BUILD_PREFIX + "*"):
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
