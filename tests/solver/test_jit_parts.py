"""JIT of long functions: compiled in parts (several translation units side by side), a long
Jacobian at -O0, and a cache hit found from the Function's serialisation without generating C.
Each checked against CasADi's virtual machine on the same Function."""

import casadi as ca
import numpy as np
import pytest
from scenes import build_kinetwork, random_mechanism

from kinetwork.solver import jit, jit_source



@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.fixture(scope="module")
def system():
    return build_kinetwork(*random_mechanism(3, 3)).compile()


def points(f, k=5, seed=0):
    rng = np.random.default_rng(seed)
    return [[rng.normal(size=f.size_in(i)) for i in range(f.n_in())] for _ in range(k)]


def test_a_long_function_in_parts_computes_what_the_virtual_machine_does(cache, monkeypatch,
                                                                         system):
    f = system.f_rhs
    # parts of 150 statements: liveness across boundaries, values read parts later
    monkeypatch.setattr(jit, "SPLIT_STATEMENTS", 200)
    monkeypatch.setattr(jit, "PART_STATEMENTS", 150)
    monkeypatch.setattr(jit, "JACOBIAN_O1_STATEMENTS", 0)       # its Jacobian at -O0
    sources = jit._plan(f.name(), [f], jit.compiler(), jacobian=True)[0]()
    parts = [name for name in sources if "_p" in name]
    assert len(parts) >= f.n_instructions() // 150 + f.jacobian().n_instructions() // 150
    assert {flags[0] for _, flags in sources.values()} == {"-O1", "-O0"}
    stats = {}
    g = jit.external(f, jacobian=True, stats=stats)
    assert stats["jit_cached"] is False and g is not f
    jac_f, jac_g = f.jacobian(), g.jacobian()
    for args in points(f):
        np.testing.assert_allclose(np.asarray(g(*args)), np.asarray(f(*args)), rtol=1e-13,
                                   atol=1e-13)
        out = f(*args)
        for a, b in zip(jac_g(*args, out), jac_f(*args, out)):
            np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-11, atol=1e-11)


def test_a_split_that_cannot_apply_leaves_the_source_whole():
    x = ca.SX.sym("x", 3)
    f = ca.Function("f", [x], [ca.sin(x) * x[0]])
    gen = ca.CodeGenerator("f.c", {"with_header": False})
    gen.add(f)
    source = gen.dump()
    assert jit_source.split(source, 1000) == {"main.c": source}          # short
    looped = source.replace("  return 0;\n}", "  for (;;) break;\n  return 0;\n}", 1)
    assert jit_source.split(looped, 2) == {"main.c": looped}                # not straight-line


def test_a_cache_hit_generates_no_c(cache, monkeypatch, system):
    f = system.f_rhs
    first = {}
    jit.external(f, jacobian=True, stats=first)

    def refuse(*args, **kwargs):
        raise AssertionError("C generated on a cache hit")
    monkeypatch.setattr(jit.ca, "CodeGenerator", refuse)
    again, stats = system.f_rhs, {}
    g = jit.external(again, jacobian=True, stats=stats)
    assert first["jit_cached"] is False and stats["jit_cached"] is True
    args = points(f, 1)[0]
    np.testing.assert_allclose(np.asarray(g(*args)), np.asarray(f(*args)), rtol=1e-13)


def test_the_key_follows_the_function_and_the_jacobian(system):
    cc = jit.compiler()
    f = system.f_rhs
    name = lambda g, jac=False: jit._plan("rhs", [g], cc, jac)[1]
    # a rebuilt model has the same serialisation: the same library
    rebuilt = build_kinetwork(*random_mechanism(3, 3)).compile().f_rhs
    assert name(f) == name(rebuilt)
    assert name(f) != name(f, True)
    assert name(f) != name(build_kinetwork(*random_mechanism(4, 3)).compile().f_rhs)


def test_entry_points_become_swappable_only_in_casadis_usual_form():
    x = ca.SX.sym("x", 3)
    f = ca.Function("f", [x], [ca.sin(x) * x[0]])
    source = jit_source.sources("f", f, ["-O0"])["f_main.c"][0]
    swapped = jit_source.swappable(source)
    assert swapped.count("f_kinetwork_swap") == 1 and "KINETWORK_LOAD(kinetwork_impl_f)" in swapped
    odd = source.replace("  return casadi_f0(arg, res, iw, w, mem);",
                         "  int r = casadi_f0(arg, res, iw, w, mem);\n  return r;")
    assert jit_source.swappable(odd) is None                 # left as it is: no tier swap
