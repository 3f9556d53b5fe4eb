"""CasADi's per-evaluation clock returns 0 at once while kinetwork's solver sections run
(``kinetwork/solver/casadi_clock.py``): the same numbers, libc's clock back in its slot on
every way out (a failure, a fork), nothing changed when asked not to."""

import ctypes
import os
import platform
import re
import shutil
import subprocess
import sys
import warnings

import numpy as np
import pytest
from scenes import double_pendulum, stiff
from scenes.reference import seed_reference

import kinetwork as kn
from kinetwork.solver import casadi_clock, methods
from kinetwork.solver.compiled import compiled

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux") or platform.machine() != "x86_64",
    reason="the replacement is made on Linux x86-64 only")

SETTINGS = {"t_end": 2.0, "n_points": 201, "rtol": 1e-8, "atol": 1e-10}


def found():
    import casadi  # noqa: F401 -- libcasadi loaded, as in any run
    with casadi_clock._GUARD:
        return casadi_clock._FOUND if casadi_clock._FOUND is not None else casadi_clock._find()


def slot_holds(address):
    return found()[0].value == address


def test_the_slot_is_the_one_readelf_names():
    """The parser against binutils: the offset of libcasadi's clock relocation."""
    readelf = shutil.which("readelf")
    if readelf is None:
        pytest.skip("no readelf to compare with")
    assert found()
    path = next(p for p in casadi_clock._mappings() if casadi_clock._LIBCASADI.search(p))
    out = subprocess.run([readelf, "-rW", path], capture_output=True, text=True,
                         check=True).stdout
    line = next(ln for ln in out.splitlines() if re.search(r"\sclock@", ln))
    assert casadi_clock._slot_offset(path, b"clock") == int(line.split()[0], 16)
    assert casadi_clock._slot_offset(path, b"no_such_symbol_anywhere") is None


def test_the_replacement_returns_a_clock_of_zero():
    replacement = ctypes.CFUNCTYPE(ctypes.c_long)(found()[2])
    assert replacement() == 0


def test_inside_a_section_only_and_nested():
    libc_clock, replacement = found()[1], found()[2]
    assert slot_holds(libc_clock) and not casadi_clock.active()
    with casadi_clock.cheap():
        assert slot_holds(replacement) and casadi_clock.active()
        with casadi_clock.cheap():
            assert slot_holds(replacement)
        assert slot_holds(replacement)
    assert slot_holds(libc_clock) and casadi_clock._DEPTH[0] == 0


def test_a_run_integrates_with_the_replacement_and_puts_the_clock_back(monkeypatch):
    """The first run (through ``methods._bound``'s call) and its replay (the recipe's call)
    each integrate with the replacement in place; libc's clock is back after each."""
    seen = []
    bound = methods._bound

    def watched(*args):
        buffer, evaluate = bound(*args)

        def call():
            seen.append(casadi_clock.active())
            return evaluate()
        return buffer, call
    monkeypatch.setattr(methods, "_bound", watched)
    system = double_pendulum().compile()
    kn.simulate(system, **SETTINGS)
    assert seen and all(seen)
    assert slot_holds(found()[1])
    kn.simulate(system, **SETTINGS)                     # the replay binds its call
    recipe = next(reversed(compiled(system)._recipes.values()))
    buffer, trigger, *rest = recipe.call
    replayed = []
    recipe.call = (buffer, lambda: (replayed.append(casadi_clock.active()), trigger()),
                   *rest)
    kn.simulate(system, **SETTINGS)
    assert replayed == [True] and slot_holds(found()[1])


def test_the_same_numbers_with_casadis_own_clock(monkeypatch):
    """A run with the replacement and one with CasADi's own clock agree to rounding, and
    both with the seed's closed form (DOP853 at 1e-13) within the run's tolerance."""
    with_it = kn.simulate(double_pendulum().compile(), **SETTINGS)
    monkeypatch.setattr(casadi_clock, "_FOUND", False)          # nothing changed
    own = kn.simulate(double_pendulum().compile(), **SETTINGS)
    assert not casadi_clock.active()
    np.testing.assert_allclose(with_it.states, own.states, rtol=1e-13, atol=1e-15)
    assert with_it.stats["rhs_evaluations"] == own.stats["rhs_evaluations"]
    ref = seed_reference(with_it.t)
    assert np.max(np.abs(with_it.states - ref)) < 1e-6


def test_a_failed_run_puts_the_clock_back():
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(stiff(1e5), t_end=1.0, n_points=11, method="cvodes-adams", max_steps=50)
    assert info.value.results is not None
    assert slot_holds(found()[1]) and casadi_clock._DEPTH[0] == 0


def test_nothing_is_changed_when_asked_not_to(monkeypatch):
    monkeypatch.setenv("KINETWORK_CASADI_CLOCK", "1")
    monkeypatch.setattr(casadi_clock, "_FOUND", None)
    with casadi_clock.cheap():
        assert casadi_clock._FOUND is False and not casadi_clock.active()


def test_a_child_forked_within_a_section_starts_with_libcs_clock():
    found()
    read, write = os.pipe()
    with casadi_clock.cheap(), warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)     # 3.12: fork with threads
        pid = os.fork()
        if pid == 0:                                    # the child: say what it has, go
            ok = not casadi_clock.active() and casadi_clock._DEPTH[0] == 0
            with casadi_clock.cheap():
                ok = ok and casadi_clock.active()
            ok = ok and not casadi_clock.active()
            os.write(write, b"1" if ok else b"0")
            os._exit(0)
        assert casadi_clock.active()                    # the parent's section goes on
    os.waitpid(pid, 0)
    assert os.read(read, 1) == b"1"
    os.close(read)
    os.close(write)
    assert not casadi_clock.active()


def test_a_surprise_while_looking_changes_nothing_and_the_run_goes_on(monkeypatch):
    """An ELF the parser does not expect (here: its reading fails in an unforeseen way)
    leaves CasADi's clock as it is; the run is made and correct."""
    def surprise(path, symbol):
        raise IndexError("an unexpected section table")
    monkeypatch.setattr(casadi_clock, "_slot_offset", surprise)
    monkeypatch.setattr(casadi_clock, "_FOUND", None)
    res = kn.simulate(double_pendulum().compile(), **SETTINGS)
    assert casadi_clock._FOUND is False and not casadi_clock.active()
    assert np.max(np.abs(res.states - seed_reference(res.t))) < 1e-6
