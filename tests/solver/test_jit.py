"""JIT: the right-hand side compiled to C computes what the virtual machine computes, once per
model and machine (on-disk cache), and a missing or failing compiler is said in plain words."""

import numpy as np
import pytest

import kinetwork as kn
from kinetwork.solver import compiled as compiled_module, jit
from kinetwork.solver.compiled import compiled, numeric
from scenes import build_kinetwork, double_pendulum, random_mechanism
from scenes.reference import seed_reference


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.mark.parametrize("seed", [0, 1])
def test_compiled_rhs_and_jacobian_equal_the_virtual_machine(cache, seed):
    system = build_kinetwork(*random_mechanism(seed, 5)).compile()
    p = system.param_vector()
    rng = np.random.default_rng(seed)
    n, c_system = system.n_states, compiled(system)
    vm, c = numeric(system.f_rhs, p, n), numeric(c_system.rhs({"stats": {}}), p, n)
    jac_vm = numeric(system.jacobian_function(), p, n)
    jac_c = numeric(c_system.jacobian({"stats": {}}), p, n)
    for _ in range(20):
        t, x = rng.uniform(0, 5), rng.normal(size=system.n_states)
        np.testing.assert_allclose(c(t, x), vm(t, x), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(jac_c(t, x), jac_vm(t, x), rtol=1e-10, atol=1e-10)


def test_a_model_compiles_once_per_machine(cache):
    first = kn.simulate(double_pendulum(), t_end=1.0, jit=True)
    assert first.stats["jit"] is True and first.stats["jit_cached"] is False
    libraries = sorted(cache.glob("*.so"))
    assert [lib.name.split("_")[0] for lib in libraries] == ["outputs", "rhs"]
    # a new model object (as in a new process), other parameter values: same code, no compiler
    again = kn.simulate(double_pendulum(c=3.0), t_end=1.0, jit=True)
    assert again.stats["jit_cached"] is True and sorted(cache.glob("*.so")) == libraries
    # a different structure is different code
    kn.simulate(double_pendulum(inertia=(0.1, 0.2)), t_end=1.0, jit=True)
    assert len(list(cache.glob("*.so"))) == 4
    vm = kn.simulate(double_pendulum(c=3.0), t_end=1.0, jit=False)
    np.testing.assert_allclose(again.states, vm.states, rtol=1e-12, atol=1e-13)


def test_no_compiler_runs_in_the_virtual_machine_or_says_so(cache, monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler")
    monkeypatch.setenv("PATH", "")
    assert jit.compiler() is None and jit.enabled() is False
    res = kn.simulate(double_pendulum(), t_end=1.0)         # the default quietly uses the VM
    assert res.stats["jit"] is False and res.settings["jit"] is False
    with pytest.raises(kn.ModelError, match="no C compiler found"):
        kn.simulate(double_pendulum(), t_end=1.0, jit=True)


def test_a_failing_compiler_is_a_model_error_naming_it(cache, monkeypatch, tmp_path):
    broken = tmp_path / "brokencc"
    broken.write_text("#!/bin/sh\necho 'internal compiler error' >&2\nexit 1\n")
    broken.chmod(0o755)
    monkeypatch.setenv("CC", str(broken))
    with pytest.raises(kn.ModelError, match="brokencc failed.*internal compiler error"):
        kn.simulate(double_pendulum(), t_end=1.0, jit=True)
    assert not list(cache.glob("*.so"))                  # nothing half-written left behind


def test_kinetwork_jit_0_turns_the_default_off(cache, monkeypatch):
    monkeypatch.setenv("KINETWORK_JIT", "0")
    assert kn.simulate(double_pendulum(), t_end=1.0).stats["jit"] is False
    assert kn.simulate(double_pendulum(), t_end=1.0, jit=True).stats["jit"] is True


def test_large_jacobians_fall_back_to_finite_differences(cache, monkeypatch):
    monkeypatch.setattr(compiled_module, "JACOBIAN_JIT_LIMIT", 0)
    system = double_pendulum(q0=(0.8, -0.5)).compile()
    res = kn.simulate(system, t_end=3.0, n_points=301, method="cvodes", rtol=1e-9,
                      atol=1e-11, jit=True)
    ref = seed_reference(res.t, x0=(0.8, -0.5, 0, 0))
    np.testing.assert_allclose(res.states, ref, atol=1e-6)
