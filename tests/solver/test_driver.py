"""The one integrator driver: chunks, cancellation, budgets, restarts, the watch over loops,
threads, and refusing numbers that overflow before integrating."""

import os
import sys
import threading

import numpy as np
import pytest
from close import assert_same_numbers
from scenes import double_pendulum
from scenes.reference import seed_reference

import kinetwork as kn
import kinetwork.graph.model
from kinetwork.solver import driver, methods, tolerance
from kinetwork.solver.methods import METHODS, Failure


def five_bar():
    """A planar loop of five revolutes (a ground link of 2 m, four links of 1 m, two degrees
    of freedom) falling under gravity from a pentagon until it folds flat at t ~ 0.73 s."""
    m = kn.Model("five_bar")
    m.add(kn.multibody.Ground("ground", gravity=[0, -9.81, 0]))
    m.add(kn.multibody.FixedTranslation("base", r=[2.0, 0, 0]))
    m.connect("ground.frame", "base.frame_a")
    prev = "ground.frame"
    for i, guess in enumerate([1.2, -0.9, -0.9, -0.9]):
        m.add(kn.multibody.Revolute(f"j{i}", axis=[0, 0, 1], q0=0.9 if i == 0 else None,
                                    q0_guess=guess))
        m.add(kn.multibody.FixedTranslation(f"l{i}", r=[1.0, 0, 0]))
        m.add(kn.multibody.RigidBody(f"b{i}", mass=1.0, r_cm=[0.5, 0, 0],
                                     inertia=[0, 0, 1 / 12]))
        m.connect(prev, f"j{i}.frame_a")
        m.connect(f"j{i}.frame_b", f"l{i}.frame_a")
        m.connect(f"j{i}.frame_b", f"b{i}.frame_a")
        prev = f"l{i}.frame_b"
    m.add(kn.multibody.Revolute("j4", axis=[0, 0, 1]))
    m.connect(prev, "j4.frame_a")
    m.connect("j4.frame_b", "base.frame_b")
    return m


@pytest.mark.parametrize("loops", ["partition", "projected", "baumgarte"])
def test_every_formulation_stops_where_the_loop_folds_flat(loops):
    """Before: partition stopped with a message that did not say why, projected and baumgarte
    carried on and disagreed. Now all three stop at the fold, naming it and its joints, when
    the run keeps its partition (by default it re-partitions there and goes on:
    tests/equations/test_repartition.py)."""
    system = five_bar().compile(loops=loops)
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(system, t_end=10.0, n_points=1001, repartition=False)
    err = info.value
    assert "singular configuration" in err.reason and "j2" in err.reason
    assert 0.6 < err.t_reached < 0.8
    assert err.results.t[-1] == err.t_reached and np.all(np.isfinite(err.results.states))
    # the partial results are sound up to there: the loop stays closed (Baumgarte's only
    # keeps the residual small, as it does everywhere)
    closed = 1e-4 if loops == "baumgarte" else 1e-8
    assert np.max(system.constraint_residual(err.results.states)) < closed


def test_the_same_run_gives_the_same_numbers():
    """Chunks are sized by work, not wall time: a run is repeatable (to rounding: a chunk
    boundary moved by the clock would change the numbers at the solver's tolerance, 1e-9)."""
    model = double_pendulum(q0=(1.0, -0.5))
    a = kn.simulate(model, t_end=5.0, rtol=1e-9, atol=1e-11)
    b = kn.simulate(double_pendulum(q0=(1.0, -0.5)), t_end=5.0, rtol=1e-9, atol=1e-11)
    assert_same_numbers(a.states, b.states, rtol=1e-13)
    ref = seed_reference(a.t, x0=(1.0, -0.5, 0, 0))
    assert np.max(np.abs(a.states - ref)) < 1e-6


def test_a_second_run_of_an_unchanged_model_does_not_rebuild_it(monkeypatch):
    model = double_pendulum()
    kn.simulate(model, t_end=0.5)
    system = model.compile()
    # Model.compile reaches the equations through upcall("compile"): any build now fails
    monkeypatch.setattr(kinetwork.graph.model, "upcall",
                        lambda name: lambda *a, **k: pytest.fail("compiled again"))
    assert model.compile() is system
    kn.simulate(model, t_end=0.5, params={"c": 2.0})


def test_a_changed_component_parameter_rebuilds_and_is_simulated():
    model = double_pendulum()
    first = kn.simulate(model, t_end=1.0)
    model.components["mass2"].mass = "2*m2"
    second = kn.simulate(model, t_end=1.0)
    assert not np.allclose(first["probe2.angle"], second["probe2.angle"])
    again = kn.loads(kn.dumps(model))
    np.testing.assert_allclose(kn.simulate(again, t_end=1.0).states, second.states)


def test_cancel_stops_a_casadi_run_between_chunks_with_partial_results():
    reached = []            # cancelled once a chunk has reported (asked every 0.1 s too)

    def cancel():
        return bool(reached) and reached[-1] > 0
    with pytest.raises(kn.SimulationError) as info:
        kn.simulate(double_pendulum(), t_end=1000.0, n_points=100001, cancel=cancel,
                    progress=reached.append, rtol=1e-10, atol=1e-12)
    err = info.value
    assert err.reason == "cancelled" and 0 < err.t_reached < 1000.0
    assert err.results.partial == {"t_reached": err.t_reached, "reason": "cancelled"}
    assert len(err.results.t) == round(err.t_reached / 0.01) + 1


@pytest.mark.parametrize("method", ["dop853", "midpoint", "rk"])
def test_every_kind_of_method_honours_cancel_and_time_limit(method):
    with pytest.raises(kn.SimulationError, match="cancelled"):
        kn.simulate(double_pendulum(), t_end=100.0, n_points=10001, method=method,
                    cancel=lambda: True)
    with pytest.raises(kn.SimulationError, match="time limit"):
        kn.simulate(double_pendulum(), t_end=1e5, n_points=100001, method=method,
                    time_limit=0.5, step=1e-3)


def test_scipy_methods_have_a_default_step_budget(monkeypatch):
    monkeypatch.setattr(tolerance, "RUN_STEPS", 30)
    with pytest.raises(kn.SimulationError, match="step budget of 30 steps for the run"):
        kn.simulate(double_pendulum(), t_end=10.0, n_points=3, method="rk45")


class _FailOnce(methods.Casadi):
    """CVODES, but its first run fails once at ``t_fail`` (a transient solver failure), and,
    with ``jump``, a restarted run lands somewhere else (a state that is not continuous)."""

    def __init__(self, t_fail, jump=False):
        base = METHODS["cvodes-adams"]
        super().__init__(base.plugin, "test", **base.options)
        self.t_fail, self.jump, self.failed = t_fail, jump, False

    def start(self, run, t, x):
        inner = super().start(run, t, x)
        outer = self

        class Stepper:
            stats = inner.stats

            def advance(self, times):
                if not outer.failed and times[-1] > outer.t_fail:
                    outer.failed = True
                    keep = times[times <= outer.t_fail]
                    raise Failure("a transient failure", inner.advance(keep) if len(keep)
                                  else None)
                out = inner.advance(times)
                return out + 1.0 if outer.jump and outer.failed else out
        return Stepper()


def test_restarts_are_opt_in_and_checked(monkeypatch):
    model = double_pendulum(q0=(0.8, -0.5))
    grid_ref = lambda t: seed_reference(t, x0=(0.8, -0.5, 0, 0))  # noqa: E731
    monkeypatch.setitem(METHODS, "flaky", _FailOnce(0.5))
    with pytest.raises(kn.SimulationError, match="a transient failure") as info:
        kn.simulate(model, t_end=2.0, n_points=201, method="flaky", rtol=1e-9, atol=1e-11)
    assert info.value.t_reached == pytest.approx(0.5)
    monkeypatch.setitem(METHODS, "flaky", _FailOnce(0.5))
    res = kn.simulate(model, t_end=2.0, n_points=201, method="flaky", rtol=1e-9, atol=1e-11,
                      restart=True)
    assert [r["t"] for r in res.stats["restarts"]] == [pytest.approx(0.5)]
    assert np.max(np.abs(res.states - grid_ref(res.t))) < 1e-6
    monkeypatch.setitem(METHODS, "flaky", _FailOnce(0.5, jump=True))
    with pytest.raises(kn.SimulationError, match="a transient failure"):
        kn.simulate(model, t_end=2.0, n_points=201, method="flaky", restart=True)


def test_numbers_that_overflow_are_refused_before_integrating():
    """Before: g = 1e300 returned states frozen at x0 with no error."""
    with pytest.raises(kn.ModelError, match="overflows double precision.*g = 1e\\+300"):
        kn.simulate(double_pendulum(), t_end=1.0, params={"g": 1e300})
    with pytest.raises(kn.ModelError, match="mass matrix.*overflows.*L1 = 1e\\+300"):
        kn.simulate(double_pendulum(L1=1e300), t_end=1.0)


@pytest.mark.parametrize("cache", ["cold", "warm"])
def test_four_threads_simulate_one_system_at_once(tmp_path, monkeypatch, cache):
    """Threads share one System: right numbers in each, and stdout and stderr left where they
    were (the solvers' words are captured one section at a time)."""
    monkeypatch.setenv("KINETWORK_CACHE", str(tmp_path / "cache"))
    system = double_pendulum(q0=(0.8, -0.5)).compile()
    if cache == "warm":
        kn.simulate(system, t_end=0.1, jit=True)
    before = [os.fstat(fd) for fd in (1, 2)]
    results, errors = {}, []

    def work(i):
        try:
            results[i] = kn.simulate(system, t_end=2.0, n_points=201, rtol=1e-9, atol=1e-11,
                                     jit=True, params={"c": 1.0 + i})
        except Exception as exc:      # noqa: BLE001  (reported below)
            errors.append(exc)
    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join(120)
    assert not errors and len(results) == 4
    after = [os.fstat(fd) for fd in (1, 2)]
    assert [(s.st_dev, s.st_ino) for s in before] == [(s.st_dev, s.st_ino) for s in after]
    for i, res in results.items():
        alone = kn.simulate(system, t_end=2.0, n_points=201, rtol=1e-9, atol=1e-11, jit=True,
                            params={"c": 1.0 + i})
        np.testing.assert_allclose(res.states, alone.states, rtol=0, atol=1e-12)
    print("still printing", file=sys.stderr)


def test_a_run_in_a_thread_cannot_install_signal_handlers_but_still_runs():
    out = {}
    th = threading.Thread(target=lambda: out.update(r=kn.simulate(double_pendulum(),
                                                                  t_end=0.5)))
    th.start()
    th.join(60)
    assert len(out["r"].t) == 1001
    assert driver.signal.getsignal(driver.signal.SIGINT) is not None


def test_a_quiet_run_is_one_call_of_its_integrator_and_a_watched_one_goes_in_chunks(monkeypatch):
    """Each chunk restarts a multistep method (order and step size from scratch): a run that
    nothing watches (no progress, cancel, time limit, loops or events) goes in one CVODES call
    over the whole grid, and its states and evaluations are those of one CVODES Adams call
    built here by hand from the System's right-hand side at the solver's tolerances."""
    import casadi as ca
    from scenes.chains import chain

    from kinetwork.solver.tolerance import solver_tolerances, step_budget
    system = chain(8).compile()
    calls = []
    advance = methods._CasadiRun.advance
    monkeypatch.setattr(methods._CasadiRun, "advance",
                        lambda self, times, exact=False, out=None: calls.append(len(times))
                        or advance(self, times, exact, out))
    quiet = kn.simulate(system, t_end=10.0, n_points=1001, method="cvodes-adams", jit=False)
    assert calls == [1000]
    rtol, atol = solver_tolerances(METHODS["cvodes-adams"], system, 1e-6, 1e-8)
    steps = step_budget(METHODS["cvodes-adams"], system, 10.0, 0.01)
    p0 = system.param_vector()
    t, x, p = ca.SX.sym("t"), ca.SX.sym("x", system.n_states), ca.SX.sym("p", len(p0))
    one = ca.integrator("one", "cvodes", {"t": t, "x": x, "p": p, "ode": system.f_rhs(t, x, p)},
                        0.0, quiet.t[1:].tolist(),
                        {"linear_multistep_method": "adams", "reltol": rtol, "abstol": atol,
                         "nonlinear_solver_iteration": "functional", "max_num_steps": steps})
    by_hand = np.asarray(one(x0=system.x0, p=p0)["xf"]).T
    np.testing.assert_allclose(quiet.states[1:], by_hand, rtol=0, atol=1e-12)
    assert quiet.stats["rhs_evaluations"] == one.stats()["nfevals"]

    calls.clear()
    watched = kn.simulate(system, t_end=10.0, n_points=1001, method="cvodes-adams", jit=False,
                          progress=lambda t: None)
    assert len(calls) >= 2 and sum(calls) == 1000
    assert watched.stats["rhs_evaluations"] > quiet.stats["rhs_evaluations"]
    np.testing.assert_allclose(watched.states, quiet.states, rtol=0, atol=1e-5)


def test_a_signal_stops_a_quiet_run_within_its_one_call_and_keeps_the_rows_it_reached():
    """CasADi checks Python's signals at every evaluation of the equations: the driver's
    handler aborts the call there, and the rows CasADi had written stay (they are the
    seed's motion: the closed form agrees)."""
    import signal
    import time
    system = double_pendulum(q0=(1.0, -0.5)).compile()
    kn.simulate(system, t_end=0.1, jit=False)                 # built: the run starts at once
    sent = []

    done = threading.Event()

    def interrupt():
        # after 0.5 s of the process's CPU time, not of the clock: a loaded machine gives
        # the run less of it, and it must have reached rows by then
        start = time.process_time()
        while not done.wait(0.02):
            if time.process_time() - start >= 0.5:
                sent.append(time.process_time())
                os.kill(os.getpid(), signal.SIGINT)
                return
    timer = threading.Thread(target=interrupt)
    timer.start()
    try:
        with pytest.raises(kn.SimulationError) as info:
            # a run far longer than 0.5 s of CPU (1e4 s of it ended sooner once CasADi's
            # clock was made cheap, casadi_clock.py)
            kn.simulate(system, t_end=1e5, n_points=10**6 + 1, rtol=1e-10, atol=1e-12,
                        jit=False)
    finally:
        done.set()
        timer.join()
    # CPU time from the signal (other processes' load does not count): the run stopped
    took = time.process_time() - sent[0]
    err = info.value
    assert err.reason == "interrupted by SIGINT" and err.signal == signal.SIGINT
    assert took < 2.0 and 0 < err.t_reached < 1e5
    res = err.results
    assert len(res.t) == round(err.t_reached / 0.1) + 1 > 101 and res.t[-1] == err.t_reached
    assert "solver_output" not in res.stats          # no solver failure to speak of
    assert np.all(np.isfinite(res.states)) and np.all(np.isfinite(res["probe1.angle"]))
    ref = seed_reference(res.t[:101], x0=(1.0, -0.5, 0, 0))      # the first 10 s
    assert np.max(np.abs(res.states[:101] - ref)) < 1e-6
