"""The JIT cache is a cache, not a code path for others: only libraries kinetwork built for this
exact code are loaded, a damaged one is rebuilt, and a cache or compiler that cannot be used
means CasADi's virtual machine (one warning per reason), never a crash or a hang."""

import os
import shutil
import subprocess
import sys
import threading
import time

import casadi as ca
import numpy as np
import pytest

from kinetwork.errors import ModelError
from kinetwork.solver import jit, jit_build
from kinetwork.solver.jit import JitFallbackWarning

X = np.array([0.3, -1.2])
PLANT = r"""
#include <stdio.h>
__attribute__((constructor)) static void planted(void) {
    FILE *f = fopen(MARKER, "w");
    if (f) fclose(f);
}
"""



def tiny(name="f", op=ca.sin):
    x = ca.SX.sym("x", 2)
    return ca.Function(name, [x], [op(x)])


def check(g, op=np.sin):
    np.testing.assert_allclose(g(X).full().ravel(), op(X), rtol=1e-15)


@pytest.fixture(autouse=True)
def fresh_warnings(monkeypatch):
    """Each test starts as a new process would: no reason warned of yet."""
    monkeypatch.setattr(jit, "_WARNED", set())


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def library_path(cache, f):
    """Where kinetwork keeps ``f``'s library (named through jit's own naming)."""
    return cache / jit._plan(f.name(), [f], jit.compiler())[1]


def script(tmp_path, name, body):
    path = tmp_path / name
    path.write_text("#!/bin/sh\n" + body + "\n")
    path.chmod(0o755)
    return path


# -- only what kinetwork built is loaded --------------------------------------------------------
@pytest.mark.parametrize("how", ["no record", "record of another library", "writable by others"])
def test_a_planted_library_is_never_loaded(cache, tmp_path, monkeypatch, how):
    marker = tmp_path / "planted-ran"
    planted = tmp_path / "planted.so"
    subprocess.run([jit.compiler(), "-shared", "-fPIC", f'-DMARKER="{marker}"', "-o",
                    str(planted), "-x", "c", "-"], input=PLANT, text=True, check=True)
    # the plant is live: loading it (in another process) runs its constructor
    subprocess.run([sys.executable, "-c", f"import ctypes; ctypes.CDLL({str(planted)!r})"],
                   check=True)
    assert marker.exists()
    marker.unlink()

    f = tiny()
    lib = library_path(cache, f)
    cache.mkdir(mode=0o700)
    shutil.copy(planted, lib)
    if how == "record of another library":       # the genuine library's record, elsewhere
        monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path / "genuine"))
        jit.external(f)
        shutil.copy(tmp_path / "genuine" / (lib.name + ".sha256"), jit._record(lib))
        monkeypatch.setenv("KINETWORK_CACHE", str(cache))
    elif how == "writable by others":             # a record that matches, a file others write
        jit._record(lib).write_bytes(jit._sha256(lib))
        lib.chmod(0o666)
    stats = {}
    g = jit.external(f, stats=stats)
    assert not marker.exists()
    check(g)
    assert stats["jit_cached"] is False and jit._verified(lib)   # rebuilt over the plant


def test_a_truncated_library_is_rebuilt_and_loads(cache, tmp_path, monkeypatch):
    f = tiny("g", ca.cos)
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path / "whole"))
    whole = jit.compile_functions("g", [f])
    # the truncated copy has never been loaded by this process: a trusting loader would fail
    cache.mkdir(mode=0o700)
    lib = cache / whole.name
    lib.write_bytes(whole.read_bytes()[:len(whole.read_bytes()) // 2])
    shutil.copy(jit._record(whole), jit._record(lib))
    monkeypatch.setenv("KINETWORK_CACHE", str(cache))
    stats = {}
    check(jit.external(f, stats=stats), np.cos)
    assert stats["jit_cached"] is False
    assert lib.read_bytes() == whole.read_bytes()


# -- a cache that cannot be used: the virtual machine, said once --------------------------------
def unusable(kind, tmp_path, monkeypatch):
    """Make the cache unusable in one way; return the words the fallback must say."""
    cache = tmp_path / "cache"
    if kind == "a file":
        cache.write_text("not a folder")
        return "is a file"
    if kind == "writable by others":
        cache.mkdir()
        cache.chmod(0o777)
        return r"writable by others \(mode 777\)"
    if kind == "another user's":
        if os.getuid() != 0:
            pytest.skip("only root can give a folder to another user")
        cache.mkdir(mode=0o700)
        os.chown(cache, 65534, -1)
        return "belongs to uid 65534"
    if kind == "read-only":
        cache.mkdir(mode=0o700)
        cache.chmod(0o500)
        if os.access(cache, os.W_OK):
            pytest.skip("running as root: permissions do not stop writes")
        return "read-only"
    if kind == "no home":
        for name in ("KINETWORK_CACHE", "XDG_CACHE_HOME", "HOME"):
            monkeypatch.delenv(name, raising=False)
        return r"\$HOME is not set"
    if kind == "full disk":
        def full(folder):
            raise OSError(28, "No space left on device")
        monkeypatch.setattr(jit_build, "build_folder", full)
        return "no space left"
    raise AssertionError(kind)


@pytest.mark.parametrize("kind", ["a file", "writable by others", "another user's", "read-only",
                                  "no home", "full disk"])
def test_an_unusable_cache_falls_back_to_the_virtual_machine(cache, tmp_path, monkeypatch,
                                                             kind):
    words = unusable(kind, tmp_path, monkeypatch)
    f, stats = tiny(), {}
    with pytest.warns(JitFallbackWarning, match=words) as said:
        g = jit.external(f, stats=stats)
        again = jit.external(tiny(), jacobian=True)          # the same reason: said once
    assert len(said) == 1 and g is f and again is not None
    check(g)
    assert "jit_fallback" in stats and not list(tmp_path.glob("**/*.so"))
    with pytest.raises(ModelError, match=words):
        jit.external(f, required=True)


# -- a compiler that cannot build: the same, in its own words ------------------------------------
def test_a_compiler_that_fails_missing_or_writes_nothing_falls_back(cache, tmp_path,
                                                                    monkeypatch):
    cases = [(script(tmp_path, "brokencc", "echo 'internal compiler error' >&2; exit 1"),
              "brokencc failed on the generated code: internal compiler error"),
             (shutil.which("true"), "true exited without writing a library")]
    for cc, words in cases:
        monkeypatch.setenv("CC", str(cc))
        stats = {}
        with pytest.warns(JitFallbackWarning, match=words):
            check(jit.external(tiny(), stats=stats))
        assert words in stats["jit_fallback"]
        with pytest.raises(ModelError, match=words):
            jit.external(tiny(), required=True)
    monkeypatch.setenv("CC", str(tmp_path / "missing" / "cc"))
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    words = f"no C compiler found \\(\\$CC={tmp_path / 'missing' / 'cc'} is not found"
    with pytest.warns(JitFallbackWarning, match=words):
        check(jit.external(tiny()))
    with pytest.raises(ModelError, match=words):
        jit.external(tiny(), required=True)
    assert not list(cache.glob("*"))                    # no build folder left behind


#: [s] of wall time within which a stopped build has returned: the fake compilers sleep 60 s,
#: so any bound well below that tells a stop from a wait, however loaded the machine
STOPPED = 20.0


def test_a_hanging_compiler_is_stopped(cache, tmp_path, monkeypatch):
    monkeypatch.setenv("CC", str(script(tmp_path, "slowcc", "echo thinking >&2; sleep 60")))
    # the run's deadline or its cancellation: a quiet fallback, even when C was required
    for options in [{"deadline": time.perf_counter() + 1.0},
                    {"cancelled": lambda t=time.perf_counter() + 1.0: time.perf_counter() > t}]:
        start, stats = time.perf_counter(), {}
        check(jit.external(tiny(), stats=stats, required=True, **options))
        assert time.perf_counter() - start < STOPPED
        assert "deadline" in stats["jit_fallback"] or "cancelled" in stats["jit_fallback"]
    # no deadline: COMPILE_TIMEOUT, said with the compiler's words
    monkeypatch.setattr(jit, "COMPILE_TIMEOUT", 1.0)
    start = time.perf_counter()
    with pytest.warns(JitFallbackWarning, match="slowcc was stopped after 1 s: thinking"):
        check(jit.external(tiny()))
    assert time.perf_counter() - start < STOPPED
    assert not list(cache.glob("*"))


def test_an_interrupted_build_leaves_no_build_folder(cache, tmp_path, monkeypatch):
    monkeypatch.setenv("CC", str(script(tmp_path, "slowcc", "sleep 60")))
    start = time.perf_counter()

    def interrupt():
        if time.perf_counter() > start + 0.5:
            raise KeyboardInterrupt
        return False
    with pytest.raises(KeyboardInterrupt):
        jit.external(tiny(), cancelled=interrupt)
    assert time.perf_counter() - start < STOPPED
    assert cache.is_dir() and not list(cache.glob("*"))


# -- threads ------------------------------------------------------------------------------------
def test_four_threads_on_a_cold_cache_build_once(cache, tmp_path, monkeypatch):
    log = tmp_path / "builds"
    monkeypatch.setenv("CC", str(script(tmp_path, "countingcc",
                                        f'echo build >> "{log}"; exec {jit.compiler()} "$@"')))
    f = tiny("h", ca.sin)
    start, results, errors = threading.Barrier(4), [None] * 4, []

    def work(i):
        try:
            start.wait()
            stats = {}
            g = jit.external(f, jacobian=True, stats=stats)
            results[i] = (g(X).full().ravel(), stats["jit_cached"])
        except BaseException as e:     # noqa: BLE001 (reported below, in the test's thread)
            errors.append(e)
    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    for values, _ in results:
        np.testing.assert_allclose(values, np.sin(X), rtol=1e-15)
    assert log.read_text().count("build") == 1
    assert sorted(cached for _, cached in results) == [False, True, True, True]


# -- size bound and the CLI's helpers ------------------------------------------------------------
def test_the_cache_keeps_the_most_recently_loaded_libraries(cache, monkeypatch):
    first, second = (jit.compile_functions(name, [tiny(name)]) for name in ("a", "b"))
    for lib in (first, second):
        os.utime(lib, (1e9, 1e9))                        # both long unused...
    jit.external(tiny("a"))                               # ...until a is loaded again
    # room for two and a half libraries of this size: the third build evicts b only
    monkeypatch.setattr(jit, "MAX_CACHE_BYTES", first.stat().st_size * 5 // 2)
    third = jit.compile_functions("c", [tiny("c")])
    assert sorted(p.name for p in cache.iterdir()) == sorted(
        [first.name, first.name + ".sha256", third.name, third.name + ".sha256"])


def test_cache_info_and_clear_cache(cache):
    libs = [jit.compile_functions(name, [tiny(name)]) for name in ("a", "b")]
    (cache / "notes.txt").write_text("mine")
    stale, live = cache / "kinetwork-build-old", cache / "kinetwork-build-now"
    for folder in (stale, live):
        folder.mkdir()
        (folder / "a.c").write_text("int x;")
    os.utime(stale, (1e9, 1e9))
    info = jit.cache_info()
    assert info["folder"] == str(cache) and info["entries"] == 2
    assert sorted(name for name, _, _ in info["libraries"]) == sorted(p.name for p in libs)
    assert info["bytes"] == sum(p.stat().st_size for p in libs)
    assert jit.clear_cache() == 5                 # two libraries, two records, one stale file
    assert sorted(p.name for p in cache.iterdir()) == ["kinetwork-build-now", "notes.txt"]
    assert jit.cache_info()["entries"] == 0 and jit.clear_cache() == 0
