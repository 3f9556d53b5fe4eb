"""Tiered JIT: a long function runs first from its quick library (-O0) while its optimised
library (-O1) is built by a background process, then from the optimised code, swapped in while
the library is in use, with the same numbers; the cache keeps it for every later process.
The background build is safe: one builder per library across processes, nothing half-written
when it dies, a failure said once and not retried."""

import fcntl
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
from scenes import chains

import kinetwork as kn
from kinetwork.solver import jit, jit_tiers
from kinetwork.solver.compiled import numeric

pytestmark = pytest.mark.skipif(jit.compiler() is None, reason="no C compiler")


@pytest.fixture(autouse=True)
def tiered(monkeypatch):
    """The default tiers (the suite runs at the quick level: tests/conftest.py)."""
    monkeypatch.setenv("KINETWORK_JIT_LEVEL", "tiered")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(jit, "QUICK_STATEMENTS", 100)     # the chains below are "long"
    monkeypatch.setattr(jit, "_PENDING", {})
    monkeypatch.setattr(jit_tiers, "_WATCHERS", {})
    monkeypatch.setattr(jit_tiers, "_SWAPPED", {})
    yield tmp_path / "cache"
    jit.wait()                   # no builder of this test outlives it


@pytest.fixture(scope="module")
def system():
    return chains.chain(6).compile()


def libraries(cache, f, jacobian=False):
    names = jit._names(f.name() + ("_jac" if jacobian else ""), [f.serialize()],
                       jit.compiler(), jacobian)
    return cache / names["quick"], cache / names["optimised"]


def states(system, rng, k=5):
    return [rng.uniform(-1, 1, system.n_states) for _ in range(k)]


def test_the_quick_library_first_then_the_optimised_code_with_the_same_numbers(cache, system):
    f, p = system.f_rhs, system.param_vector()
    quick, optimised = libraries(cache, f)
    sources = jit._plan("rhs", [f], jit.compiler(), tier="quick")[0]()
    assert {flags[0] for _, flags in sources.values()} == {"-O0"}
    assert "rhs_kinetwork_swap" in sources["rhs_main.c"][0]
    stats = {}
    g = jit.external(f, stats=stats, required=True)
    assert stats["jit_tier"] == "quick" and quick.is_file()
    c, vm = numeric(g, p, system.n_states), numeric(f, p, system.n_states)
    xs = states(system, np.random.default_rng(1))
    before = [c(0.0, x) for x in xs]
    assert jit.wait() == {str(quick): "optimised"}
    assert jit._verified(optimised) and not jit_tiers.lock_path(optimised).exists()
    for x, b in zip(xs, before):
        # the same C, no contraction in either tier: the same bits, not merely close ones
        np.testing.assert_array_equal(c(0.0, x), b)
        np.testing.assert_allclose(b, vm(0.0, x), rtol=1e-13, atol=1e-13)
    # a later load (another System, another process) finds the optimised library at once
    again = {}
    g2 = jit.external(chains.chain(6).compile().f_rhs, stats=again, required=True)
    assert again == {**again, "jit_tier": "optimised", "jit_cached": True}
    np.testing.assert_array_equal(numeric(g2, p, system.n_states)(0.0, xs[0]), before[0])


def test_a_run_under_way_goes_on_in_the_optimised_code_with_the_same_answer(cache, system):
    """The swap lands in the middle of a run (its progress reports see both tiers); the
    run's answer is that of a run all in the quick code."""
    seen = []

    def report(t):
        seen.append(jit_tiers.state(quick))
        if len(seen) == 1:
            jit.wait()                             # the swap, while the run is under way

    quick, _ = libraries(cache, system.f_rhs)
    during = kn.simulate(system, t_end=4.0, n_points=401, progress=report, jit=True)
    assert seen[0] == "building" and seen[-1] == "optimised"
    assert during.stats["jit_tier"] == "quick"
    # the same run from the quick library alone: KINETWORK_JIT_LEVEL=quick in a new process
    script = textwrap.dedent(f"""
        import numpy as np, sys
        sys.path.insert(0, {os.path.dirname(os.path.dirname(__file__))!r})
        from scenes import chains
        import kinetwork as kn
        from kinetwork.solver import jit
        jit.QUICK_STATEMENTS = 100
        res = kn.simulate(chains.chain(6), t_end=4.0, n_points=401,
                          progress=lambda t: None, jit=True)
        assert res.stats["jit_tier"] == "quick"
        np.save(sys.argv[1], res.states)
    """)
    out = cache.parent / "quick.npy"
    subprocess.run([sys.executable, "-c", script, str(out)], check=True,
                   env={**os.environ, "KINETWORK_JIT_LEVEL": "quick",
                        "KINETWORK_CACHE": str(cache.parent / "other")})
    np.testing.assert_allclose(during.states, np.load(out), rtol=1e-12, atol=1e-12)


def test_levels_quick_and_optimised_and_a_wrong_level(cache, system, monkeypatch):
    f = system.f_rhs
    quick, optimised = libraries(cache, f)
    monkeypatch.setenv("KINETWORK_JIT_LEVEL", "quick")
    stats = {}
    jit.external(f, stats=stats, required=True)
    assert stats["jit_tier"] == "quick" and jit.wait() == {}
    assert not optimised.exists() and not jit_tiers.lock_path(optimised).exists()
    monkeypatch.setenv("KINETWORK_JIT_LEVEL", "optimised")
    stats = {}
    jit.external(f, stats=stats, required=True)
    assert stats["jit_tier"] == "optimised" and jit._verified(optimised)
    monkeypatch.setenv("KINETWORK_JIT_LEVEL", "fastest")
    with pytest.raises(kn.ModelError, match="KINETWORK_JIT_LEVEL='fastest': must be tiered"):
        jit.external(chains.chain(7).compile().f_rhs)


def gated_compiler(tmp_path, how):
    """A compiler that does -O0 builds at once and, for -O1, ``how``: waits for the file
    ``go`` (writing its process id to ``pids`` first), or fails."""
    path = tmp_path / f"cc-{how}"
    action = (f'echo $$ >> "{tmp_path / "pids"}"; while [ ! -e "{tmp_path / "go"}" ]; '
              f'do sleep 0.05; done' if how == "waits" else "echo 'no -O1 today' >&2; exit 1")
    path.write_text(textwrap.dedent(f"""\
        #!/bin/sh
        for a in "$@"; do [ "$a" = "-O1" ] && {{ {action}; }}; done
        exec {jit.compiler()} "$@"
    """))
    path.chmod(0o755)
    return path


def started_builder(cache, system, tmp_path):
    """The background builder of ``system``'s right-hand side, once its -O1 compilers run."""
    jit.external(system.f_rhs, required=True)
    quick, _ = libraries(cache, system.f_rhs)
    builder = jit._PENDING[str(quick)].process
    while not (tmp_path / "pids").exists() and builder.poll() is None:
        time.sleep(0.05)
    return builder


def lock_is_free(lib):
    if not jit_tiers.lock_path(lib).exists():          # gone with the builder
        return True
    with open(jit_tiers.lock_path(lib), "rb") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)       # raises when held
    return True


def test_a_builder_stopped_cleans_up_its_compilers_and_folder(cache, system, tmp_path,
                                                             monkeypatch):
    monkeypatch.setenv("CC", str(gated_compiler(tmp_path, "waits")))
    builder = started_builder(cache, system, tmp_path)
    builder.send_signal(signal.SIGTERM)
    builder.wait()
    for pid in map(int, (tmp_path / "pids").read_text().split()):
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)                               # its compilers went with it
    _, optimised = libraries(cache, system.f_rhs)
    assert list(jit.wait().values()) == ["not swapped: the build did not finish"]
    assert not optimised.exists() and not jit._record(optimised).exists()
    assert not list(cache.glob(jit.BUILD_PREFIX + "*")) and lock_is_free(optimised)
    assert not jit_tiers.failed_marker(optimised).exists()     # stopped is not failed


def test_a_builder_killed_leaves_no_entry_and_the_quick_code_runs_on(cache, system,
                                                                    tmp_path, monkeypatch):
    monkeypatch.setenv("CC", str(gated_compiler(tmp_path, "waits")))
    builder = started_builder(cache, system, tmp_path)
    os.kill(builder.pid, signal.SIGKILL)
    builder.wait()
    (tmp_path / "go").touch()               # its orphaned compilers finish into nothing
    _, optimised = libraries(cache, system.f_rhs)
    assert list(jit.wait().values()) == ["not swapped: the build did not finish"]
    assert not optimised.exists() and not jit._record(optimised).exists()
    assert lock_is_free(optimised)
    f, p = system.f_rhs, system.param_vector()
    g = jit.external(f, required=True)
    x = np.full(system.n_states, 0.2)
    np.testing.assert_allclose(numeric(g, p, system.n_states)(0.0, x),
                               numeric(f, p, system.n_states)(0.0, x), rtol=1e-13)


def test_a_failed_optimised_build_is_said_and_not_tried_again(cache, system, tmp_path,
                                                              monkeypatch):
    monkeypatch.setenv("CC", str(gated_compiler(tmp_path, "fails")))
    f = system.f_rhs
    quick, optimised = libraries(cache, f)
    jit.external(f, required=True)
    (outcome,) = jit.wait().values()
    assert outcome.startswith("not swapped:") and "no -O1 today" in outcome
    assert jit_tiers.failed_marker(optimised).is_file() and not optimised.exists()
    monkeypatch.setattr(jit, "_PENDING", {})          # as a new process would
    jit.external(chains.chain(6).compile().f_rhs, required=True)
    assert jit._PENDING == {}                            # no second builder
    assert jit.clear_cache() >= 3 and not jit_tiers.failed_marker(optimised).exists()


def test_two_processes_on_a_cold_cache_build_the_optimised_library_once(cache, tmp_path):
    log = tmp_path / "builds"
    counting = tmp_path / "countingcc"
    counting.write_text(f'#!/bin/sh\nfor a in "$@"; do [ "$a" = "-O1" ] && '
                        f'echo O1 >> "{log}"; done\nexec {jit.compiler()} "$@"\n')
    counting.chmod(0o755)
    script = textwrap.dedent(f"""
        import sys, numpy as np
        sys.path.insert(0, {os.path.dirname(os.path.dirname(__file__))!r})
        from scenes import chains
        from kinetwork.solver import jit
        from kinetwork.solver.compiled import numeric
        jit.QUICK_STATEMENTS = 100
        s = chains.chain(6).compile()
        g = jit.external(s.f_rhs, required=True)
        print(list(jit.wait().values()))
        x = np.full(s.n_states, 0.3)
        p = s.param_vector()
        assert np.allclose(numeric(g, p, s.n_states)(0.0, x),
                           numeric(s.f_rhs, p, s.n_states)(0.0, x), rtol=1e-13)
    """)
    env = {**os.environ, "CC": str(counting), "KINETWORK_CACHE": str(cache)}
    runs = [subprocess.Popen([sys.executable, "-c", script], env=env, stdout=subprocess.PIPE,
                             text=True) for _ in range(2)]
    said = [run.communicate()[0].strip() for run in runs]
    assert [run.returncode for run in runs] == [0, 0]
    assert said == ["['optimised']"] * 2
    compiled_o1 = log.read_text().count("O1")
    parts = len([k for k in jit._plan("rhs", [chains.chain(6).compile().f_rhs],
                                      jit.compiler())[0]()])
    assert compiled_o1 == parts                    # one build's compiler runs, not two


def test_the_optimised_build_outlives_the_process_that_asked_for_it(cache, tmp_path):
    script = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {os.path.dirname(os.path.dirname(__file__))!r})
        from scenes import chains
        from kinetwork.solver import jit
        jit.QUICK_STATEMENTS = 100
        jit.external(chains.chain(6).compile().f_rhs, required=True)
    """)                                          # exits at once, its builder still working
    subprocess.run([sys.executable, "-c", script], check=True,
                   env={**os.environ, "KINETWORK_CACHE": str(cache)})
    f = chains.chain(6).compile().f_rhs
    _, optimised = libraries(cache, f)
    jit_tiers.Pending(optimised, lock=jit_tiers.lock_path(optimised)).wait()
    assert jit._verified(optimised)
    stats = {}
    jit.external(f, stats=stats, required=True)
    assert stats["jit_tier"] == "optimised" and stats["jit_cached"] is True


def test_a_library_with_its_jacobian_swaps_both(cache, system):
    f, p = system.f_rhs, system.param_vector()
    g = jit.external(f, jacobian=True, required=True)
    jac_g, jac_f = g.jacobian(), f.jacobian()
    x = np.linspace(-0.5, 0.5, system.n_states)
    before = [np.asarray(v) for v in jac_g(0.0, x, p, g(0.0, x, p))]
    assert list(jit.wait().values()) == ["optimised"]
    after = [np.asarray(v) for v in jac_g(0.0, x, p, g(0.0, x, p))]
    for a, b, ref in zip(after, before, jac_f(0.0, x, p, f(0.0, x, p))):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_allclose(a, np.asarray(ref), rtol=1e-11, atol=1e-11)
