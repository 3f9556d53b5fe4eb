"""Derived Systems kept on disk (``kinetwork.equations.stored``): a kept System answers as a
freshly derived one does; any change of the model, of kinetwork's sources or of the file
misses the cache, never answers from it."""

import os
import pathlib
import shutil
import subprocess
import sys
import warnings

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.equations import stored
from kinetwork.equations.stored import BuildCacheWarning
from kinetwork.equations.system import System

MODELS = pathlib.Path(kn.__file__).parent / "models"
#: a tree, a loop, loops in subsystems with events (EngineV6), signal blocks with time and
#: state events (a PID with a limiter), friction with stick-slip events
EXAMPLES = ["double_pendulum.json", "fourbar.json", "engine_v6/EngineV6.json", "arm_pid.json",
            "msl_friction.json"]


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A cache folder of the test's own for derived Systems (``<cache>/systems``, as a
    process given ``KINETWORK_CACHE=<cache>`` uses); compiled libraries stay in the test
    session's, where an example's are built once."""
    folder = tmp_path / "cache"
    monkeypatch.setattr(stored, "folder_path", lambda: folder / "systems")
    monkeypatch.delenv("KINETWORK_BUILD_CACHE", raising=False)
    return folder


@pytest.fixture
def derivations(monkeypatch):
    """The number of Systems derived (not loaded) since the fixture began."""
    count = [0]
    init = System.__init__

    def counted(self, *args, **kwargs):
        count[0] += 1
        init(self, *args, **kwargs)
    monkeypatch.setattr(System, "__init__", counted)
    return count


def files(cache):
    return sorted((cache / "systems").glob("*.system"))


def agree(fresh, kept, seed=0):
    """The two Systems give the same equations: names, starts, right-hand sides, outputs,
    mass matrix, frame poses and Jacobian at random states."""
    assert kept.state_names == fresh.state_names
    assert kept.algebraic_names == fresh.algebraic_names
    assert kept.param_names == fresh.param_names
    assert kept.signal_names == fresh.signal_names
    assert kept.formulation == fresh.formulation
    np.testing.assert_allclose(kept.x0, fresh.x0, rtol=1e-12, atol=1e-12)
    rng = np.random.default_rng(seed)
    p = fresh.param_vector()
    x0, z0 = fresh.initial_full_p(p)
    for _ in range(3):
        x = x0 + 1e-3 * rng.standard_normal(x0.shape)
        full = np.concatenate([x, z0])[None, :]
        np.testing.assert_allclose(kept.outputs_p([0.1], full, p),
                                   fresh.outputs_p([0.1], full, p), rtol=1e-10, atol=1e-10)
        if not fresh.n_algebraic:
            np.testing.assert_allclose(kept.rhs(0.1, x), fresh.rhs(0.1, x), rtol=1e-10,
                                       atol=1e-10)
            np.testing.assert_allclose(np.asarray(kept.jacobian_function()(0.1, x, p)),
                                       np.asarray(fresh.jacobian_function()(0.1, x, p)),
                                       rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(np.asarray(kept.f_frames(0.1, full[0], p)),
                                   np.asarray(fresh.f_frames(0.1, full[0], p)),
                                   rtol=1e-10, atol=1e-10)
    if fresh.coordinate_names and not fresh.n_algebraic:
        q = x0[:len(fresh.coordinate_names)]
        np.testing.assert_allclose(kept.mass_matrix(q), fresh.mass_matrix(q), rtol=1e-12,
                                   atol=1e-12)


@pytest.mark.parametrize("name", EXAMPLES)
def test_a_kept_system_answers_as_a_fresh_derivation(cache, derivations, name):
    fresh = kn.load(MODELS / name).compile()
    assert derivations[0] == 1 and len(files(cache)) == 1
    kept = kn.load(MODELS / name).compile()          # another Model of the same file
    assert derivations[0] == 1, "the kept System was derived again"
    assert kept is not fresh
    agree(fresh, kept)
    # long enough for the PID's step and friction's first stick; EngineV6's first 12 events
    # (its gas forces' relations) are in its first 0.15 s, and 0.6 s of it cost 4x as much
    t_end = min(float(fresh.model.simulation.get("t_end", 1.0)), 0.15 if "engine" in name
                else 0.6)
    a = kn.simulate(fresh, t_end=t_end, n_points=31, rtol=1e-8)
    b = kn.simulate(kept, t_end=t_end, n_points=31, rtol=1e-8)
    assert b.signal_names == a.signal_names
    for signal in a.signal_names:
        scale = 1.0 + np.max(np.abs(a[signal]))
        np.testing.assert_allclose(b[signal], a[signal], rtol=0, atol=1e-6 * scale,
                                   err_msg=signal)


def test_a_new_process_loads_without_deriving(cache):
    path = MODELS / "engine_v6" / "EngineV6.json"
    kn.load(path).compile()
    body = (
        "import sys, numpy as np, kinetwork as kn\n"
        "from kinetwork.equations.system import System\n"
        "def refused(*a, **k):\n"
        "    raise AssertionError('derived again')\n"
        "System.__init__ = refused\n"
        f"s = kn.load({str(path)!r}).compile()\n"
        "print(s.n_states, repr(float(np.sum(s.x0))))\n")
    done = subprocess.run([sys.executable, "-c", body], capture_output=True, text=True,
                          env={**os.environ, "KINETWORK_CACHE": str(cache)})
    assert done.returncode == 0, done.stderr[-2000:]
    fresh = kn.load(path)
    fresh_system = System(fresh.flat(), topology=None)
    n, total = done.stdout.split()
    assert int(n) == fresh_system.n_states
    assert float(total) == pytest.approx(float(np.sum(fresh_system.x0)), rel=1e-12, abs=1e-12)


def test_a_kept_system_holds_the_relations_its_runs_locate_events_on(cache, monkeypatch):
    """The relations every run reads first are found before a System is kept, and kept with
    it: a process that loads it finds none again (EngineV6: 0.07 s of CPU a process), and
    they are the fresh ones."""
    from kinetwork.equations import system as system_module
    path = MODELS / "engine_v6" / "EngineV6.json"
    fresh = kn.load(path).compile()
    assert "relations" in vars(fresh)

    def refused(*a, **k):
        raise AssertionError("relations found again")
    monkeypatch.setattr(system_module, "find_relations", refused)
    kept = kn.load(path).compile()
    assert kept is not fresh
    a, b = fresh.relations, kept.relations
    assert a.ops == b.ops and a.tables == b.tables
    monkeypatch.setattr(type(b), "_text", refused)      # the event log's words: kept too
    assert [b.text(i) for i in range(b.n)] == [a.text(i) for i in range(a.n)]
    expected = a._jacobian().n_instructions()           # their Jacobian, built afresh
    monkeypatch.setattr(type(b), "_jacobian", refused)  # its size kept, not built again
    assert b.jacobian_instructions() == expected
    for name in ("time", "state", "affine"):
        np.testing.assert_array_equal(getattr(b, name), getattr(a, name))
    p = np.append(fresh.param_vector(), np.zeros(a.p.numel() - len(fresh.param_vector())))
    x0, z0 = fresh.initial_full_p(fresh.param_vector())
    full = np.concatenate([x0, z0])
    for f in ("f_select", "f_state", "f_level"):
        np.testing.assert_allclose(np.asarray(getattr(b, f)(0.01, full, p)),
                                   np.asarray(getattr(a, f)(0.01, full, p)), rtol=1e-12,
                                   atol=1e-12, err_msg=f)
    res = kn.simulate(kept, t_end=0.05, n_points=11)        # its run reads them as they are
    assert res.stats["events"]


@pytest.mark.parametrize("change", ["component parameter", "model parameter", "connection",
                                    "loops"])
def test_a_changed_model_misses(cache, derivations, change):
    model = kn.load(MODELS / "double_pendulum.json")
    before = model.compile()
    other = kn.load(MODELS / "double_pendulum.json")
    options = {}
    if change == "component parameter":
        other.components["mass1"].set_param("mass", 2.5)
    elif change == "model parameter":
        name = next(iter(other.parameters))
        other.set_parameter(name, other.parameters[name] * 1.5)
    elif change == "connection":
        other.connections.reverse()
    else:
        options = {"loops": "baumgarte"}
    after = other.compile(**options)
    assert derivations[0] == 2, "a changed model was answered from the cache"
    assert len(files(cache)) == 2
    if change in ("component parameter", "model parameter"):
        assert not np.allclose(after.rhs(0.0, after.x0), before.rhs(0.0, before.x0))


def test_a_changed_source_misses(cache, derivations, tmp_path, monkeypatch):
    kn.load(MODELS / "fourbar.json").compile()
    copy = tmp_path / "kinetwork"
    shutil.copytree(stored._PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    stored._environment.cache_clear()
    monkeypatch.setattr(stored, "_PACKAGE", copy)
    kn.load(MODELS / "fourbar.json").compile()       # the same sources: kept
    assert derivations[0] == 1
    loops = copy / "equations" / "loops.py"
    loops.write_text(loops.read_text() + "\n# a change of the derivation\n")
    stored._environment.cache_clear()
    kn.load(MODELS / "fourbar.json").compile()
    assert derivations[0] == 2
    assert len(files(cache)) == 2
    stored._environment.cache_clear()


@pytest.mark.parametrize("damage", ["truncated", "flipped", "emptied", "foreign header"])
def test_a_damaged_file_is_rebuilt_with_a_warning(cache, derivations, damage):
    fresh = kn.load(MODELS / "fourbar.json").compile()
    (path,) = files(cache)
    data = path.read_bytes()
    if damage == "truncated":
        path.write_bytes(data[:len(data) // 2])
    elif damage == "flipped":
        middle = len(data) // 2
        path.write_bytes(data[:middle] + bytes([data[middle] ^ 0xFF]) + data[middle + 1:])
    elif damage == "emptied":
        path.write_bytes(b"")
    else:
        path.write_bytes(b"not kinetwork's\n" + data[20:])
    with pytest.warns(BuildCacheWarning, match="built again"):
        again = kn.load(MODELS / "fourbar.json").compile()
    assert derivations[0] == 2
    agree(fresh, again)
    (path,) = files(cache)                            # written whole again
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        agree(fresh, kn.load(MODELS / "fourbar.json").compile())
    assert derivations[0] == 2


def test_concurrent_writers_leave_a_whole_file(cache):
    path = MODELS / "fourbar.json"
    body = f"import kinetwork as kn; kn.load({str(path)!r}).compile()"
    env = {**os.environ, "KINETWORK_CACHE": str(cache)}
    procs = [subprocess.Popen([sys.executable, "-c", body], env=env) for _ in range(3)]
    assert all(p.wait() == 0 for p in procs)
    assert len(files(cache)) == 1
    assert not list((cache / "systems").glob(".*"))   # no temporary file left
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        agree(kn.load(path).compile(), System(kn.load(path), topology=None))


def test_an_unsafe_folder_is_not_used(cache, derivations, monkeypatch):
    (cache / "systems").mkdir(parents=True)
    os.chmod(cache / "systems", 0o777)
    monkeypatch.setattr(stored, "_warn_once", stored._warn_once.__wrapped__)
    with pytest.warns(BuildCacheWarning, match="not a private folder"):
        kn.load(MODELS / "double_pendulum.json").compile()
    with pytest.warns(BuildCacheWarning):
        kn.load(MODELS / "double_pendulum.json").compile()
    assert derivations[0] == 2 and not files(cache)


def test_the_opt_out_keeps_nothing(cache, derivations, monkeypatch):
    monkeypatch.setenv("KINETWORK_BUILD_CACHE", "0")
    kn.load(MODELS / "double_pendulum.json").compile()
    kn.load(MODELS / "double_pendulum.json").compile()
    assert derivations[0] == 2 and not files(cache)


def test_a_component_class_of_the_user_is_not_kept(cache, derivations):
    from kinetwork.components.bodies import RigidBody

    class MyBody(RigidBody):
        """A user's body: its code is not in the key."""

    model = kn.load(MODELS / "double_pendulum.json")
    model.components["mass1"].__class__ = MyBody     # as if the user had placed one
    assert stored.key_of(model, "projected", None) is None
    model.compile()
    assert not files(cache)


def test_clear_cache_removes_kept_systems(cache):
    from kinetwork.solver import jit
    kn.load(MODELS / "double_pendulum.json").compile()
    assert files(cache)
    jit.clear_cache()
    assert not files(cache)


def test_the_folder_is_bounded(cache, monkeypatch):
    monkeypatch.setattr(stored, "MAX_BYTES", 1)
    kn.load(MODELS / "double_pendulum.json").compile()
    kn.load(MODELS / "fourbar.json").compile()
    (left,) = files(cache)                            # only the one just written
    assert left.stat().st_size > 1


def test_a_build_that_warned_is_not_kept_and_its_warning_is_said(cache, monkeypatch):
    init = System.__init__

    def warning(self, *args, **kwargs):
        init(self, *args, **kwargs)
        warnings.warn("something about this model", UserWarning)
    monkeypatch.setattr(System, "__init__", warning)
    with pytest.warns(UserWarning, match="something about this model"):
        kn.load(MODELS / "double_pendulum.json").compile()
    assert not files(cache)
