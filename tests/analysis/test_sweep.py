"""Sweeps and Monte Carlo (kn.sweep, kn.sample) run the model's integration plan: every member
is its own kn.simulate run whatever the batch (each integrated with its own error control),
its global error follows rtol as simulate's does against the paper's closed form, a failed
member is marked failed with simulate's reason and partial results while its batch-mates
keep their runs, and Ctrl-C keeps what finished.

In CasADi's virtual machine (jit=False) and on short horizons: the compiled path is the
same code with a compiled right-hand side, measured in bench/study_sweep.py."""

import os
import signal
import sys
import threading

import numpy as np
import pytest
import scipy.stats
import xarray as xr
from close import assert_same_numbers
from scenes import double_pendulum
from scenes.reference import seed_reference

import kinetwork as kn
from kinetwork.solver import batch as batch_module

FAST = {"t_end": 1.5, "n_points": 151, "jit": False, "progress": False}


def kick():
    """A pendulum kicked by a torque 1/(t - T)^2: a member with T inside the horizon blows
    up there (the integrator fails), one with T beyond it runs; a negative mass is refused."""
    m = kn.Model("kick", parameters={"T": 5.0, "mass": 1.0})
    ground = m.add(kn.multibody.Ground("ground", gravity=[0, -9.8, 0]))
    hinge = m.add(kn.multibody.Revolute("hinge", axis=[0, 0, 1], q0=0.1))
    body = m.add(kn.multibody.RigidBody("body", mass="mass", r_cm=[0, -1, 0]))
    torque = m.add(kn.rotational.Torque("kick", tau="1/(t - T)**2"))
    probe = m.add(kn.Probe("probe", quantities=["angle"]))
    m.connect(ground.frame, hinge.frame_a)
    m.connect(hinge.frame_b, body.frame_a)
    m.connect(torque.flange, hinge.axis)
    m.connect(torque.support, hinge.support)
    m.connect(probe.port, hinge.axis)
    return m


def seed_push():
    """The issue's reproduction: the seed with a torque 1/(tb - t)^2 on the shoulder."""
    m = double_pendulum()
    m.set_parameter("tb", 10.0)
    push = m.add(kn.rotational.Torque("push", tau="1/(tb - t)^2"))
    m.connect(push.flange, "shoulder.axis")
    m.connect(push.support, "shoulder.support")
    return m


def check_push(ds, model, **settings):
    """tb = 2 failed before t = 2 with simulate's reason and partial results; the others
    are simulate's runs (the same integrator: to rounding)."""
    assert ds.status.values.tolist() == ["ok", "failed", "ok", "ok"]
    failed = ds.sel(tb=2.0)
    assert failed.t_reached.item() < 2.0
    with pytest.raises(kn.SimulationError) as err:
        kn.simulate(model, params={"tb": 2.0}, **settings)
    assert failed.reason.item() == str(err.value)
    partial = err.value.results
    n = len(partial.t)
    assert failed.t_reached.item() == pytest.approx(err.value.t_reached)
    np.testing.assert_allclose(failed["shoulder.q"].values[:n], partial["shoulder.q"],
                               rtol=1e-9, atol=1e-12)
    assert np.all(np.isnan(failed["shoulder.q"].values[n:]))
    for tb in (10.0, 20.0, 30.0):
        res = kn.simulate(model, params={"tb": tb}, **settings)
        member = ds.sel(tb=tb)
        assert member.t_reached.item() == 3.0
        assert np.all(member["shoulder.q"].values != 0.0)        # never zeroed
        np.testing.assert_allclose(member["shoulder.q"].values, res["shoulder.q"],
                                   rtol=0, atol=1e-12)
        np.testing.assert_allclose(member["probe1.torque"].values, res["probe1.torque"],
                                   rtol=0, atol=1e-12)


@pytest.mark.parametrize("batch, workers", [(1, 2), (4, 2), (4, 1), (1, 1)])
def test_the_issue_reproduction_in_threads_and_serially(batch, workers):
    model = seed_push()
    settings = {"t_end": 3.0, "jit": False}
    ds = kn.sweep(model, {"tb": [10.0, 2.0, 20.0, 30.0]}, batch=batch, workers=workers,
                  progress=False, **settings)
    check_push(ds, model, **settings)


def test_a_mapped_call_that_fails_reruns_each_member_through_the_plan(monkeypatch):
    """A mapped call's failure (its return status, never an exception) sends each of its
    members through Plan.run: counted here."""
    model = seed_push()
    ran = []
    real = kn.solver.plan.Plan.run

    def counted(self, params=None, **kw):
        ran.append(dict(params or {}))
        return real(self, params, **kw)
    monkeypatch.setattr(kn.solver.plan.Plan, "run", counted)
    ds = kn.sweep(model, {"tb": [10.0, 2.0, 20.0, 30.0]}, batch=2, workers=1, t_end=3.0,
                  jit=False, progress=False)
    assert ds.status.values.tolist() == ["ok", "failed", "ok", "ok"]
    # the first call (10, 2) failed: both again on their own; the second (20, 30) did not
    assert [r["tb"] for r in ran if "tb" in r] == [10.0, 2.0]


CS = [0.5, 1.0, 2.0, 4.0, 8.0]


@pytest.fixture(scope="module")
def references():
    """The paper's closed form at large angles, integrated by scipy's DOP853 at 1e-13."""
    t = np.linspace(0.0, 5.0, 101)
    return {c: seed_reference(t, x0=(1.0, 0.5, 0.0, 0.0), c=c) for c in CS}


@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8, 1e-10])
def test_a_member_is_as_accurate_as_simulate_whatever_the_batch(rtol, references):
    """Global error against the paper's closed form (scipy DOP853 at 1e-13) follows rtol
    as simulate's does (the README's "within 100 x rtol"), at batch 1, 4 and 64; changing
    the batch changes no member by more than rtol."""
    model = double_pendulum(q0=(1.0, 0.5))
    cs, refs = CS, references
    settings = {"t_end": 5.0, "n_points": 101, "rtol": rtol, "atol": rtol / 100, "jit": False}
    runs = {}
    for size in (1, 4, 64):
        ds = kn.sweep(model, {"c": cs}, batch=size, workers=2, progress=False, **settings)
        assert set(ds.status.values) == {"ok"}
        runs[size] = ds
        for c in cs:
            states = np.column_stack([ds[n].sel(c=c).values for n in
                                      ("shoulder.q", "elbow.q", "shoulder.qd", "elbow.qd")])
            error = np.abs(states[:, :2] - refs[c][:, :2]).max()
            assert error <= 100 * rtol, (size, c, error / rtol)
    for c in cs:
        res = kn.simulate(model, params={"c": c}, **settings)
        assert np.abs(res.states[:, :2] - refs[c][:, :2]).max() <= 100 * rtol
        for ds in runs.values():
            np.testing.assert_allclose(ds["shoulder.q"].sel(c=c).values, res["shoulder.q"],
                                       rtol=0, atol=rtol)


def test_grid_equals_a_loop_of_simulate_and_the_closed_form():
    model = double_pendulum()
    tight = {"rtol": 1e-10, "atol": 1e-12, "t_end": 1.5, "n_points": 151, "jit": False}
    # 6 members in calls of 4 on 2 threads: a full call and a short one
    ds = kn.sweep(model, {"c": [0.5, 2.0, 8.0], "d": [0.2, 1.5]}, batch=4, workers=2,
                  progress=False, **tight)
    assert dict(ds.sizes) == {"c": 3, "d": 2, "t": 151}
    assert list(ds.status.values.ravel()) == ["ok"] * 6
    assert ds["probe1.angle"].attrs["units"] == "rad"
    assert ds["probe1.torque"].attrs["units"] == "N*m"
    assert ds["t"].attrs["units"] == "s"
    assert ds["shoulder.qd"].attrs["units"] == "rad/s"
    assert ds.c.attrs["units"] == "N*m/rad"
    for c in ds.c.values:
        for d in ds.d.values:
            member = ds.sel(c=c, d=d)
            res = kn.simulate(model, params={"c": c, "d": d}, **tight)
            states = np.column_stack([member[n].values for n in res.state_names])
            np.testing.assert_allclose(states, res.states, rtol=0, atol=1e-12)
            if d == 0.2:    # the paper's M, V, G integrated by scipy at 1e-13: independent
                ref = seed_reference(ds.t.values, c=c, d=d)
                np.testing.assert_allclose(states, ref, atol=1e-8)
            for name in res.signals:
                np.testing.assert_allclose(member[name].values, res[name], rtol=0,
                                           atol=1e-10 * max(1.0, np.abs(res[name]).max()))


def test_the_time_dimension_is_named_as_results_name_it():
    model = double_pendulum()
    ds = kn.sweep(model, {"c": [1.0, 2.0]}, **FAST)
    one = kn.simulate(model, params={"c": 2.0}, t_end=1.5, n_points=151, jit=False).to_xarray()
    assert ds["probe1.angle"].dims == ("c",) + one["probe1.angle"].dims
    assert_same_numbers(ds["t"].values, one["t"].values)


def test_outputs_keeps_only_the_named_signals():
    model = double_pendulum()
    ds = kn.sweep(model, {"c": [1.0, 2.0]}, outputs=["probe2.angle", "elbow.qd"], **FAST)
    kept = {n for n, v in ds.data_vars.items() if v.attrs.get("kind") in ("probe", "state")}
    assert kept == {"probe2.angle", "elbow.qd"}
    res = kn.simulate(model, params={"c": 2.0}, t_end=1.5, n_points=151, jit=False)
    np.testing.assert_allclose(ds["probe2.angle"].sel(c=2.0).values, res["probe2.angle"],
                               atol=1e-12)
    with pytest.raises(kn.ModelError, match=r"'probe2.angel' is no probe signal or state.*"
                                            r"'probe2.angle'"):
        kn.sweep(model, {"c": [1.0]}, outputs=["probe2.angel"], **FAST)


def test_fixed_step_members_equal_simulate_to_rounding():
    """rk takes the same steps in a member as alone."""
    model = double_pendulum()
    ds = kn.sweep(model, {"m2": [0.5, 1.0, 3.0]}, method="rk", step=0.005, batch=2,
                  workers=1, **FAST)
    for m2 in ds.m2.values:
        res = kn.simulate(model, params={"m2": m2}, method="rk", step=0.005, t_end=1.5,
                          n_points=151, jit=False)
        np.testing.assert_allclose(ds.sel(m2=m2)["probe2.angle"].values, res["probe2.angle"],
                                   atol=1e-12)
    assert set(ds.method.values) == {"rk"}


def test_members_of_other_methods_are_simulate_runs():
    """Methods a map cannot run (scipy's) run through the plan one after another."""
    model = double_pendulum()
    ds = kn.sweep(model, {"c": [0.5, 2.0]}, method="dop853", rtol=1e-8, atol=1e-10, **FAST)
    for c in (0.5, 2.0):
        res = kn.simulate(model, params={"c": c}, method="dop853", rtol=1e-8, atol=1e-10,
                          t_end=1.5, n_points=151, jit=False)
        assert_same_numbers(ds["probe1.angle"].sel(c=c).values, res["probe1.angle"])
    assert set(ds.method.values) == {"dop853"}


def test_sample_draws_repeatably_and_each_member_is_its_own_run():
    model = double_pendulum()
    draws = {"m2": kn.normal(1.0, 0.05), "c": scipy.stats.uniform(0.5, 1.5),
             "d": [0.1, 0.5, 0.9, 1.3, "1.7 N*m*s/rad"]}
    ds = kn.sample(model, draws, n=5, seed=3, rtol=1e-10, atol=1e-12, **FAST)
    again = kn.sample(model, draws, n=5, seed=3, rtol=1e-10, atol=1e-12, **FAST)
    assert_same_numbers(ds.m2.values, again.m2.values)
    rng = np.random.default_rng(3)      # the draw, in the order of the dict
    assert_same_numbers(ds.m2.values, rng.normal(1.0, 0.05, 5))
    assert np.all((ds.c.values >= 0.5) & (ds.c.values <= 2.0))
    assert ds.d.values[-1] == 1.7
    assert ds.m2.attrs["distribution"] == "normal(1, 0.05)"
    assert dict(ds.sizes) == {"member": 5, "t": 151}
    k = 2
    params = {name: float(ds[name].values[k]) for name in ("m2", "c", "d")}
    res = kn.simulate(model, params=params, t_end=1.5, n_points=151, jit=False, rtol=1e-10,
                      atol=1e-12)
    np.testing.assert_allclose(ds["probe2.angle"].values[k], res["probe2.angle"], atol=1e-12)


def test_a_failing_member_is_marked_and_the_others_kept():
    model = kick()
    ds = kn.sweep(model, {"T": [5.0, 0.5, 3.0], "mass": [1.0, -1.0]}, t_end=1.0,
                  n_points=11, jit=False, progress=False, batch=2, workers=2)
    status = ds.status.values
    assert status[:, 0].tolist() == ["ok", "failed", "ok"]
    assert all(status[:, 1] == "failed")            # mass -1: refused, naming the place
    assert all("body.mass" in r and ">= 0" in r for r in ds.reason.values[:, 1])
    reason = ds.reason.sel(T=0.5, mass=1.0).item()
    assert "too many steps" in reason and "t = 0.4" in reason
    failed = ds.sel(T=0.5, mass=1.0)
    assert failed.t_reached.item() == pytest.approx(0.4)
    with pytest.raises(kn.SimulationError) as err:
        kn.simulate(model, params={"T": 0.5}, t_end=1.0, n_points=11, jit=False)
    partial = err.value.results["probe.angle"]
    assert_same_numbers(failed["probe.angle"].values[:len(partial)], partial)
    assert np.all(np.isnan(failed["probe.angle"].values[len(partial):]))
    ref = kn.simulate(model, params={"T": 3.0}, t_end=1.0, n_points=11, jit=False,
                      rtol=1e-11, atol=1e-13)["probe.angle"]
    np.testing.assert_allclose(ds.sel(T=3.0, mass=1.0)["probe.angle"].values, ref, atol=1e-6)
    assert ds.attrs["failed"] == 4


def test_progress_moves_per_member_and_an_interrupt_keeps_what_finished():
    calls = []

    def progress(done, total):          # Ctrl-C arrives after the first member
        calls.append((done, total))
        raise KeyboardInterrupt

    ds = kn.sweep(double_pendulum(), {"c": [1.0, 2.0, 3.0, 4.0]}, batch=2, workers=1,
                  t_end=0.5, n_points=51, jit=False, progress=progress)
    assert calls == [(1, 4)]
    assert ds.attrs["interrupted"] == 1
    # the call of two had finished both: both kept
    assert ds.status.values.tolist() == ["ok", "ok", "interrupted", "interrupted"]
    assert np.all(np.isfinite(ds["probe1.angle"].values[:2]))
    assert np.all(np.isnan(ds["probe1.angle"].values[2:]))
    seen = []
    kn.sweep(double_pendulum(), {"c": [1.0, 2.0, 3.0, 4.0, 5.0]}, batch=4, workers=2,
             t_end=0.5, n_points=51, jit=False, progress=lambda d, n: seen.append(d))
    assert seen == [1, 2, 3, 4, 5]


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to oneself")
def test_ctrl_c_stops_a_sweep_between_mapped_calls_and_keeps_what_finished():
    """A SIGINT while members run: the call running finishes, the sweep returns what
    finished, the rest "interrupted" (not a KeyboardInterrupt out of CasADi)."""
    model = double_pendulum()
    seen = []

    def progress(done, total):
        seen.append(done)
        if done == 1:        # the signal arrives while the next calls run
            threading.Timer(0.05, os.kill, (os.getpid(), signal.SIGINT)).start()
    ds = kn.sweep(model, {"c": np.linspace(0.5, 4.0, 400).tolist()}, batch=2, workers=1,
                  t_end=20.0, n_points=201, jit=False, progress=progress)
    assert ds.attrs["interrupted"] == 1
    status = ds.status.values
    done = status == "ok"
    assert 1 <= done.sum() < 400 and set(status[~done]) == {"interrupted"}
    assert np.all(np.isfinite(ds["probe1.angle"].values[done]))
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_mapped_call_is_chunked_to_a_fraction_of_a_second_of_work():
    """Ctrl-C waits for the call running: a call is CHUNK_WORK per thread at most,
    whatever the batch (an expensive model's call covers few output intervals)."""
    from scenes import chains

    from kinetwork.solver.plan import Plan
    for model, members in ((double_pendulum(), 64), (chains.chain(16), 64)):
        plan = Plan(model, t_end=10.0, n_points=1001, jit=False)
        p = plan.vector()
        template = batch_module._template(plan, [(0, p, plan.start(p))])
        work = batch_module._interval_work(plan, template)
        chunk = batch_module._chunk(plan, template, members)
        assert chunk == 1000 or chunk * work * members <= batch_module.CHUNK_WORK
    assert batch_module._chunk(plan, template, 64) < 1000      # the chain's: chunked


def test_optional_dependencies_are_checked_before_any_member_runs(monkeypatch):
    ran = []
    monkeypatch.setattr(kn.solver.plan.Plan, "run", lambda *a, **k: ran.append(1))
    monkeypatch.setattr(batch_module, "_mapped", lambda *a, **k: ran.append(1))
    monkeypatch.setitem(sys.modules, "xarray", None)
    with pytest.raises(kn.ModelError, match="xarray is not installed"):
        kn.sweep(double_pendulum(), {"c": [1.0, 2.0]}, **FAST)
    monkeypatch.delitem(sys.modules, "xarray")
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(kn.ModelError, match="Dask is not installed"):
        kn.sweep(double_pendulum(), {"c": [1.0, 2.0]}, scheduler="local", **FAST)
    assert ran == []


def test_bad_input_is_refused_by_name():
    model = double_pendulum()
    with pytest.raises(kn.ModelError, match=r"'cc' is no model parameter.*'c'"):
        kn.sweep(model, {"cc": [1.0]})
    with pytest.raises(kn.ModelError, match="'c': give a non-empty sequence"):
        kn.sweep(model, {"c": []})
    with pytest.raises(kn.ModelError, match=r"sweep: c\[1\]: must be a finite number"):
        kn.sweep(model, {"c": [1.0, float("nan")]})
    with pytest.raises(kn.ModelError, match=r"sweep: c\[0\]: .*does not convert"):
        kn.sweep(model, {"c": ["2 kg"]})
    with pytest.raises(kn.ModelError, match="n must be a positive integer"):
        kn.sample(model, {"c": kn.normal(1, 0.1)}, n=0)
    with pytest.raises(kn.ModelError, match="'c': 2 values for n = 3"):
        kn.sample(model, {"c": [1.0, 2.0]}, n=3)
    with pytest.raises(kn.ModelError, match="std must be >= 0"):
        kn.normal(1.0, -0.1)
    with pytest.raises(kn.ModelError, match="rtol"):
        kn.sweep(model, {"c": [1.0]}, rtol=-1)
    with pytest.raises(kn.ModelError, match="'rtool': no setting of a run.*'rtol'"):
        kn.sweep(model, {"c": [1.0]}, rtool=1e-6)
    with pytest.raises(kn.ModelError, match="workers: must be a positive integer"):
        kn.sweep(model, {"c": [1.0]}, workers=0)
    with pytest.raises(kn.ModelError, match="scheduler: None, 'local', an address"):
        kn.sweep(model, {"c": [1.0]}, scheduler="nowhere", **FAST)
    with pytest.raises(kn.ModelError, match="'c' is varied already"):
        kn.sweep(model, {"c": [1.0]}, params={"c": 2.0}, **FAST)
    with pytest.raises(kn.ModelError, match=r"would need .* GiB.*outputs=\[\.\.\.\]"):
        kn.sweep(model, {"c": np.ones(10**4).tolist()}, t_end=1.0, n_points=10**5,
                 jit=False, progress=False)


def test_a_job_travels_as_the_model_text():
    """What a Dask worker in another process gets: the job pickled as the model's text and
    the plan's settings, its plan built again there (a component path lifted again); the
    numbers are the same."""
    import pickle

    from kinetwork.analysis.sweep_job import Job, run_block
    from kinetwork.solver.plan import Plan
    plan = Plan(double_pendulum(), names=["c", "spring.d"], t_end=0.5, n_points=51,
                rtol=1e-8, atol=1e-10, jit=False)
    job = Job(plan, ["c"], {"spring.d": 0.3})
    copy = pickle.loads(pickle.dumps(job))
    assert copy.plan.system is not plan.system
    assert copy.plan.system.state_names == plan.system.state_names
    values = np.array([[0.5], [3.0]])
    a, b = run_block(job, values, 2), run_block(copy, values, 2)
    assert a["status"] == b["status"] == ["ok", "ok"]
    assert_same_numbers(a["outputs"], b["outputs"])
    res = kn.simulate(double_pendulum(), params={"c": 3.0, "d": 0.3}, t_end=0.5,
                      n_points=51, rtol=1e-8, atol=1e-10, jit=False)
    assert_same_numbers(b["states"][1], res.states)


def test_command_line_sweep_writes_netcdf(seed_file, tmp_path, capsys):
    from kinetwork.cli import main
    out = tmp_path / "sweep.nc"
    code = main(["sweep", str(seed_file), "--param", "c=1,4", "--param", "d=0.5:1.5:3",
                 "--t-end", "0.5", "--n-points", "11", "--no-jit", "--no-progress",
                 "--workers", "1", "--out", str(out)])
    assert code == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[:3] == ["c", "d", "probe1.angle"]
    assert lines[1].startswith("c=1  d=0.5  ") and len(lines) == 1 + 6 + 1
    ds = xr.open_dataset(out)
    assert ds.status.values.tolist() == [["ok"] * 3] * 2
    np.testing.assert_allclose(ds.d.values, [0.5, 1.0, 1.5])
    res = kn.simulate(kn.load(seed_file), params={"c": 4.0, "d": 1.0}, t_end=0.5,
                      n_points=11, jit=False)
    np.testing.assert_allclose(ds["probe1.angle"].sel(c=4.0, d=1.0).values,
                               res["probe1.angle"], atol=1e-12)
    assert float(lines[5].split()[2]) == pytest.approx(res["probe1.angle"][-1], abs=1e-6)
    ds.close()
    assert main(["sweep", str(seed_file), "--param", "cc=1"]) == 1     # named, not a trace
    assert "'cc' is no model parameter" in capsys.readouterr().err
    code = main(["sweep", str(seed_file), "--param", "spring.d=0.5 N*m*s/rad,1",
                 "--output", "probe1.angle", "--t-end", "0.5", "--n-points", "11",
                 "--no-jit", "--no-progress", "--out", str(tmp_path / "d.nc")])
    assert code == 0
    ds = xr.open_dataset(tmp_path / "d.nc")
    assert [n for n in ds.data_vars if ds[n].attrs.get("kind")] == ["probe1.angle"]
    np.testing.assert_allclose(ds["spring.d"].values, [0.5, 1.0])
    ds.close()


def test_a_swept_initial_angle_starts_each_member_there():
    """The start is found once when the swept parameters cannot change it (c, d) and per
    member when they do (q0 given as a parameter)."""
    model = double_pendulum()
    model.parameters["a0"] = 0.05
    model.components["shoulder"].q0 = "a0"
    tight = {"rtol": 1e-10, "atol": 1e-12, "t_end": 0.5, "n_points": 51, "jit": False}
    ds = kn.sweep(model, {"a0": [0.05, 0.3], "c": [1.0, 3.0]}, progress=False, **tight)
    assert_same_numbers(ds["shoulder.q"].values[:, :, 0], [[0.05, 0.05], [0.3, 0.3]])
    res = kn.simulate(model, params={"a0": 0.3, "c": 3.0}, **tight)
    np.testing.assert_allclose(ds["probe1.angle"].sel(a0=0.3, c=3.0).values,
                               res["probe1.angle"], atol=1e-12)
    ref = seed_reference(ds.t.values, x0=(0.3, 0.05, 0.0, 0.0), c=3.0)
    np.testing.assert_allclose(ds["elbow.q"].sel(a0=0.3, c=3.0).values, ref[:, 1], atol=1e-8)
