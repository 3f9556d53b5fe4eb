"""Derived Systems kept on disk: a model built once is loaded in any later process, not derived
again (what Modelica tools' translated models and Julia's precompilation do).

``Model.compile`` comes here (``upcalls.UPCALLS["compile"]``). The key of a System is the
sha256 of everything its derivation reads: the flat model's content (components by class and
given parameters, connections, exposed ports, model parameters with their values, initial
equations), how it is compiled (``loops``, ``baumgarte_rate``), every source file of the
kinetwork package, and the versions of Python, CasADi, NumPy, networkx, cloudpickle and the
platform. A model whose components are not all kinetwork's own (a class of the user's, whose
code the key cannot see), whose content holds something the key cannot write down, or whose
build warned is not kept. Parameter values are in the key: the derivation takes structural
decisions at them (which closure rows a loop keeps, the branch an assembly starts on).

What is kept is the System's state just after it was built: its Python objects pickled
(``cloudpickle``: the derivation keeps local functions, such as a formulation's initial
values), the model and its components by name (the model compiling is the one loaded into),
and every CasADi expression through one Function: its outputs are all the expressions, its
inputs their symbols, serialised once; loading calls it on new symbols of the same names, so
that expressions that shared nodes or symbols share them again (serialising 18,000
expressions one by one took 8 s for a 1024-link chain, this 1.4 s).

Trust. Loading a pickle runs code, so the folder is trusted as the JIT cache's is
(``solver/jit.py``): ``systems/`` inside the cache folder, created 0700, used only while it
is the current user's and not writable by group or others; a file is written to a temporary
name and renamed, so concurrent writers never tear one, and holds the sha256 of its payload:
a truncated or damaged file is ignored with a ``BuildCacheWarning``, removed and built again.
Past ``MAX_BYTES``, the least recently loaded files go. ``KINETWORK_BUILD_CACHE=0`` turns
the cache off.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import io
import math
import os
import pathlib
import pickle
import platform
import stat
import sys
import tempfile
import warnings

import casadi as ca
import numpy as np

from ..errors import KinetworkWarning
from ..graph.model import keep_topology
from ..util import cache_folder, trim_least_recent
from .system import System

#: the layout of a file: bump when what is written changes
FORMAT = b"kinetwork-system-1\n"
#: the folder's files are trimmed to this size after each write, least recently loaded first
MAX_BYTES = 256 * 2**20
#: the suffix of kinetwork's files in the folder (nothing else there is read or removed)
SUFFIX = ".system"
_PACKAGE = pathlib.Path(__file__).resolve().parent.parent
_CASADI = (ca.SX, ca.MX, ca.DM, ca.Function, ca.Sparsity)


class BuildCacheWarning(KinetworkWarning):
    """A kept System could not be used (damaged, unreadable): it is built again."""


class _Uncacheable(Exception):
    """The model holds something the key cannot write down."""


def enabled():
    """Whether derived Systems are kept (``KINETWORK_BUILD_CACHE=0``: no)."""
    value = os.environ.get("KINETWORK_BUILD_CACHE", "1").strip().lower()
    return value not in ("0", "false", "no", "off")


def compile(model, loops="projected", baumgarte_rate=None, topology=None):
    """The System of ``model`` (a flat one): loaded when kept, else built and kept."""
    key = key_of(model, loops, baumgarte_rate) if enabled() else None
    folder = _folder() if key is not None else None
    if folder is not None:
        system = _load(folder / f"{key}{SUFFIX}", model)
        if system is not None:
            return system
    said = []
    try:
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            system = System(model, loops=loops, baumgarte_rate=baumgarte_rate,
                            topology=topology)
    finally:                # said again as they came (a failed build's too), under the
        for w in said:      # caller's filters
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if folder is not None and not said:
        _found_first(system)
        _store(folder, key, system)
    return system


def _found_first(system):
    """What every run of ``system`` reads first, found before it is kept, so that it is
    kept with it: the relations its events are located on, their words in the run's log of
    events and the size of their Jacobian (EngineV6: 0.07 + 0.013 + 0.018 s of CPU in each
    process's first run). What cannot be found is left to the run, which says why (a build
    that only compiles, to count states or linearise, is not refused for it)."""
    with contextlib.suppress(Exception):
        relations = system.relations
        if relations is not None:
            for i in range(relations.n):
                relations.text(i)
            relations.jacobian_instructions()   # whether the solver compiles it


# -- the key ---------------------------------------------------------------------------------
def key_of(model, loops, baumgarte_rate):
    """The key of the System ``model`` compiles to (64 hex digits), or None when it cannot be
    kept (see the module's docstring)."""
    try:
        content = _canonical(_content(model))
        environment = _environment()
    except _Uncacheable:
        return None
    digest = hashlib.sha256(FORMAT)
    for part in (environment, content, repr((loops, baumgarte_rate))):
        digest.update(part.encode())
        digest.update(b"\0")
    return digest.hexdigest()


def _content(model):
    """What the derivation reads of ``model``, as plain values."""
    components = []
    for name, comp in model.components.items():
        cls = type(comp)
        if not cls.__module__.startswith("kinetwork."):
            raise _Uncacheable(name)          # its code is not in the sources' hash
        components.append((name, cls.__module__, cls.__qualname__,
                           sorted(comp.given.items())))
    return {"name": model.name, "components": components,
            "connections": [(a.path, b.path) for a, b in model.connections],
            "exposed": sorted((k, v.path) for k, v in model.exposed.items()),
            "parameters": list(model.parameters.items()),
            "parameter_text": sorted(model.parameter_text.items()),
            "initial": model.initial}


def _canonical(value):
    """``value`` written down exactly (floats by their repr, arrays whole), or _Uncacheable."""
    if value is None or isinstance(value, (bool, str)):
        return repr(value)
    if isinstance(value, (int, np.integer)):
        return repr(int(value))
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return repr(value) if math.isfinite(value) else f"float({value!r})"
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "biuf":
            raise _Uncacheable(value.dtype)
        return f"array{value.shape}{_canonical(value.tolist())}"
    if isinstance(value, (list, tuple)):
        return f"{type(value).__name__}[{','.join(map(_canonical, value))}]"
    if isinstance(value, dict):
        return "{" + ",".join(f"{_canonical(k)}:{_canonical(v)}"
                              for k, v in value.items()) + "}"
    raise _Uncacheable(type(value).__name__)


@functools.lru_cache(maxsize=1)
def _environment():
    """The versions and the sources' hash, once per process (_Uncacheable without sources)."""
    import cloudpickle
    import networkx
    digest = hashlib.sha256()
    sources = sorted(_PACKAGE.rglob("*.py"))
    if not any(path.name == "system.py" for path in sources):
        raise _Uncacheable("no sources")      # bytecode only: the key could not see a change
    for path in sources:
        digest.update(str(path.relative_to(_PACKAGE)).encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return repr((sys.version, sys.platform, platform.machine(), ca.__version__,
                 np.__version__, networkx.__version__, cloudpickle.__version__,
                 digest.hexdigest()))


# -- the folder -------------------------------------------------------------------------------
def folder_path():
    """Where derived Systems are kept (None without a cache folder)."""
    base = cache_folder()
    return None if base is None else base / "systems"


def _folder():
    """The folder, created private; None (said once) when it cannot be trusted or written."""
    folder = folder_path()
    if folder is None:
        return None
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        st = folder.stat()
    except OSError as e:
        _warn_once("unusable", f"derived Systems are not kept: {folder}: {e.strerror or e}")
        return None
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid() or st.st_mode & 0o022 or \
            not os.access(folder, os.W_OK | os.X_OK):
        _warn_once("unsafe", f"derived Systems are not kept: {folder} is not a private folder "
                             f"of this user (make it yours, chmod 700)")
        return None
    return folder


@functools.lru_cache(maxsize=None)
def _warn_once(kind, message):
    warnings.warn(message, BuildCacheWarning, stacklevel=4)


def kept(folder=None):
    """(path, bytes, mtime) of each System file in the folder."""
    folder = folder or folder_path()
    found = []
    if folder is None or not folder.is_dir():
        return found
    for path in folder.glob(f"*{SUFFIX}"):
        with contextlib.suppress(OSError):
            st = path.lstat()
            if stat.S_ISREG(st.st_mode):
                found.append((path, st.st_size, st.st_mtime))
    return found


def clear():
    """Remove the kept Systems (and temporary files of interrupted writes); return how many
    files were removed."""
    folder = folder_path()
    removed = 0
    if folder is None or not folder.is_dir():
        return removed
    for path in [p for p, _, _ in kept(folder)] + list(folder.glob(f".*{SUFFIX}.tmp")):
        with contextlib.suppress(OSError):
            path.unlink()
            removed += 1
    return removed


def _trim(folder, keep):
    def remove(path):
        with contextlib.suppress(OSError):
            path.unlink()
    trim_least_recent(kept(folder), MAX_BYTES, keep, remove)


# -- writing and reading ---------------------------------------------------------------------
class _Pickler:
    """The System's state as (pickle bytes, CasADi bytes): see the module's docstring."""

    def __init__(self, system):
        import cloudpickle

        outer = self
        self.model, self.system = system.model, system
        self.components = {id(c): name for name, c in system.model.components.items()}
        self.expressions, self.others, self.seen = [], [], {}

        class Pickler(cloudpickle.Pickler):
            def persistent_id(self, obj):
                return outer.reference(obj)
        self.pickler = Pickler

    def reference(self, obj):
        if obj is self.model:
            return ("model",)
        if obj is self.system:
            return ("system",)
        if isinstance(obj, _CASADI):
            if id(obj) not in self.seen:
                store = self.expressions if isinstance(obj, ca.SX) else self.others
                store.append(obj)
                self.seen[id(obj)] = (obj, ("sx" if store is self.expressions else "ca",
                                            len(store) - 1))
            return self.seen[id(obj)][1]
        name = self.components.get(id(obj))
        if name is not None and self.model.components.get(name) is obj:
            return ("component", name)
        return None

    def dump(self, state):
        buffer = io.BytesIO()
        self.pickler(buffer, protocol=pickle.HIGHEST_PROTOCOL).dump(state)
        symbols = ca.symvar(ca.veccat(*self.expressions)) if self.expressions else []
        every = ca.Function("expressions", symbols, self.expressions,
                            {"max_io": len(self.expressions) + len(symbols) + 1})
        serializer = ca.StringSerializer()
        serializer.pack(every)
        serializer.pack([s.name() for s in symbols])
        for obj in self.others:
            serializer.pack(obj)
        return buffer.getvalue(), serializer.encode(), len(self.others)


class _Unpickler(pickle.Unpickler):
    def __init__(self, data, model, system, expressions, others):
        super().__init__(io.BytesIO(data))
        self.model, self.system = model, system
        self.expressions, self.others = expressions, others

    def persistent_load(self, pid):
        kind = pid[0]
        if kind == "model":
            return self.model
        if kind == "system":
            return self.system
        if kind == "sx":
            return self.expressions[pid[1]]
        if kind == "ca":
            return self.others[pid[1]]
        if kind == "component":
            return self.model.components[pid[1]]
        raise pickle.UnpicklingError(f"unknown reference {pid!r:.60}")


def _store(folder, key, system):
    """Write ``system`` as ``<key>.system`` (nothing when its state does not pickle)."""
    try:
        state, expressions, n_others = _Pickler(system).dump(dict(vars(system)))
    except (pickle.PicklingError, TypeError, AttributeError, RuntimeError, RecursionError):
        return                  # something of the derivation that does not travel: not kept
    payload = pickle.dumps((n_others, state, expressions), protocol=pickle.HIGHEST_PROTOCOL)
    data = FORMAT + hashlib.sha256(payload).digest() + payload
    path = folder / f"{key}{SUFFIX}"
    try:
        fd, temporary = tempfile.mkstemp(prefix=f".{key[:16]}", suffix=f"{SUFFIX}.tmp",
                                         dir=folder)
        try:
            with os.fdopen(fd, "wb") as out:
                out.write(data)
            os.replace(temporary, path)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
            raise
    except OSError:
        return                  # a full disk: the System is simply not kept
    _trim(folder, keep=path)


def _load(path, model):
    """The System kept at ``path`` for ``model``, or None (missing; damaged: said, removed)."""
    try:
        st = path.lstat()
    except OSError:
        return None
    try:
        if not stat.S_ISREG(st.st_mode) or st.st_uid != os.getuid():
            raise ValueError("not a regular file of this user")
        data = path.read_bytes()
        head = len(FORMAT) + 32
        if data[:len(FORMAT)] != FORMAT or len(data) < head or \
                hashlib.sha256(data[head:]).digest() != data[len(FORMAT):head]:
            raise ValueError("damaged or truncated (its content does not match its record)")
        n_others, state, serialised = pickle.loads(data[head:])
        system = _restore(model, n_others, state, serialised)
    except Exception as exc:           # whatever is wrong with a kept file, build instead
        warnings.warn(f"the kept System {path.name[:16]}... of {model.name!r} cannot be "
                      f"used ({type(exc).__name__}: {str(exc)[:200]}); it is built again",
                      BuildCacheWarning, stacklevel=4)
        with contextlib.suppress(OSError):
            path.unlink()
        return None
    with contextlib.suppress(OSError):
        os.utime(path)                 # recently used: trimmed last
    keep_topology(model, system.topology)
    return system


def _restore(model, n_others, state, serialised):
    deserializer = ca.StringDeserializer(serialised)
    every, names = deserializer.unpack(), deserializer.unpack()
    others = [deserializer.unpack() for _ in range(n_others)]
    symbols = [ca.SX.sym(name) for name in names]
    expressions = every.call(symbols) if every.n_out() else []
    system = System.__new__(System)
    vars(system).update(_Unpickler(state, model, system, expressions, others).load())
    return system
