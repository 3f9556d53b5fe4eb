"""What makes large chains affordable keeps every number: the integrator without Newton hides
its equations' derivatives (CasADi builds a Jacobian at creation otherwise), large functions
compile at -O0, and the Newton-Euler passes call one Function per body."""

import casadi as ca
import numpy as np
import pytest

import kinetwork as kn
from kinetwork.equations import newton_euler
from kinetwork.solver import compiled as compiled_module, jit
from kinetwork.solver.compiled import compiled, numeric
from kinetwork.solver.methods import METHODS
from scenes import chains
from scenes.reference import seed_reference

ADAMS = {**METHODS["cvodes-adams"].options, "reltol": 1e-10, "abstol": 1e-12}


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def full_x_nnz(c, jit_opts):
    full = c.dae(jit_opts, jacobian=True)
    return full.sparsity_jac(1, 0).nnz() if isinstance(full, ca.Function) else \
        ca.jacobian(full["ode"], full["x"]).nnz()


def _run(dae, system, times):
    integ = ca.integrator("i", "cvodes", dae, 0.0, list(times), ADAMS)
    return np.asarray(integ(x0=system.x0, p=np.append(system.param_vector(), 0.0))["xf"]).T


@pytest.mark.parametrize("jit_on", [True, False])
def test_adams_without_derivatives_runs_as_with_them(cache, monkeypatch, jit_on):
    """The same Adams run on equations that hide their derivatives in x and on the full ones
    (jit: the compiled code; VM: the SX Function against the SX expressions), as a chain
    past the Jacobian limit gets them."""
    system = chains.chain(4).compile()
    monkeypatch.setattr(compiled_module, "JACOBIAN_JIT_LIMIT", 0)
    c = compiled(system)
    jit_opts = {"stats": {}} if jit_on else None
    hidden = c.dae(jit_opts, jacobian=False)
    assert isinstance(hidden, ca.Function)
    # hidden: its Jacobian in x is structurally zero, so building it costs nothing
    assert hidden.sparsity_jac(1, 0).nnz() == 0 and full_x_nnz(c, jit_opts) > 0
    full = c.dae(jit_opts, jacobian=True)
    times = np.linspace(0.1, 2.0, 20)
    np.testing.assert_allclose(_run(hidden, system, times), _run(full, system, times),
                               rtol=0, atol=1e-12)


def test_a_small_model_s_adams_hides_nothing_and_runs_the_same(cache, monkeypatch):
    """Below the Jacobian limit the equations keep their derivatives (hiding them costs each
    evaluation a node of CasADi's virtual machine, and a small Jacobian's set-up is cheap):
    the same numbers as the hidden ones a large chain gets."""
    jit_opts = {"stats": {}}
    small, large = chains.chain(4).compile(), chains.chain(4).compile()
    assert small is not large
    plain = compiled(small).dae(jit_opts, jacobian=False)
    monkeypatch.setattr(compiled_module, "JACOBIAN_JIT_LIMIT", 0)
    hidden = compiled(large).dae(jit_opts, jacobian=False)
    assert plain.sparsity_jac(1, 0).nnz() > 0 and hidden.sparsity_jac(1, 0).nnz() == 0
    times = np.linspace(0.1, 2.0, 20)
    np.testing.assert_allclose(_run(plain, small, times), _run(hidden, large, times),
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("jit_on", [True, False])
def test_a_chunk_s_own_grid_hides_the_derivatives_of_a_small_model(cache, jit_on):
    """An integrator built for one chunk's own grid (after an event) is built on the
    equations with their derivatives hidden whatever their size (CasADi builds a Jacobian at
    its creation otherwise: most of EngineV6's 349 such builds), with the same numbers; a
    grid of equal intervals, kept and met again, keeps them (each evaluation is cheaper)."""
    from kinetwork.solver.methods import _CasadiRun
    system = chains.chain(4).compile()
    c = compiled(system)
    jit_opts = {"stats": {}} if jit_on else None
    hidden = c.dae(jit_opts, jacobian=False, hidden=True)
    plain = c.dae(jit_opts, jacobian=False)
    assert isinstance(hidden, ca.Function) and hidden.sparsity_jac(1, 0).nnz() == 0
    assert full_x_nnz(c, jit_opts) > 0
    assert c.dae(jit_opts, jacobian=True, hidden=True) is c.dae(jit_opts, jacobian=True)
    times = np.concatenate([[0.03], 0.03 + np.linspace(0.1, 2.0, 20)])     # a head of its own
    np.testing.assert_allclose(_run(hidden, system, times), _run(plain, system, times),
                               rtol=0, atol=1e-12)

    class Run:                          # what _CasadiRun.recipe reads of a run
        compiled, spacing = c, 0.1
        p_solver = system.param_vector()
    Run.jit = jit_opts
    stepper = _CasadiRun(METHODS["cvodes-adams"], Run(), 0.0, system.x0)
    built = []
    for grid in (times, np.linspace(0.1, 2.0, 20)):
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(ca, "integrator", lambda *a: built.append(a[2]))
            stepper.recipe(grid, {})[1]()
    assert built[0] is hidden and built[1] is (plain if jit_on else c.dae(None, False))


def test_the_default_run_of_the_seed_still_meets_its_closed_form(cache):
    """The seed through the default method (Adams, derivatives hidden) against the
    independent reference."""
    from scenes import double_pendulum
    res = kn.simulate(double_pendulum(), t_end=5.0, n_points=101, rtol=1e-10, atol=1e-12)
    ref = seed_reference(res.t)
    assert np.max(np.abs(res.states[:, :2] - ref[:, :2])) < 1e-7


def test_the_one_call_steps_meet_the_composite_rigid_body_mass_matrix():
    """The per-body Functions of the articulated-body and inverse-dynamics passes against the
    mass matrix of the composite-rigid-body algorithm, which sums the bodies' inertias
    without them: M qdd = -(V + G) for ABA's qdd, and rnea(u, w) - rnea(u, 0) = M w."""
    system = chains.chain(5).compile()
    a = system.asm
    a0 = ca.vertcat(ca.SX.zeros(3), -a.gravity)
    w = ca.SX.sym("w", 5)
    qdd = newton_euler.aba(a.bodies, a.u, a.Q, a0)
    dtau = newton_euler.rnea(a.bodies, a.u, w, a0) - newton_euler.rnea(
        a.bodies, a.u, ca.SX.zeros(5), a0)
    f = ca.Function("f", [a.q, a.u, w, a.p], [qdd, dtau])
    p, rng = system.param_vector(), np.random.default_rng(0)
    for _ in range(3):
        q, u, acc = (rng.uniform(-1, 1, 5) for _ in range(3))
        out = [np.asarray(v).ravel() for v in f(q, u, acc, p)]
        M = system.mass_matrix(q)
        _, V, G = system.dynamics_terms(q, u)
        np.testing.assert_allclose(M @ out[0], -(V + G), atol=1e-9)
        np.testing.assert_allclose(out[1], M @ acc, atol=1e-9)
