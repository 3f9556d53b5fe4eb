"""Sweeps and Monte Carlo (kn.sweep, kn.sample): every member equals its own kn.simulate run
to the integrator's tolerance, and the seed's members equal the paper's closed form
integrated by scipy; failures, refusals and interruptions keep the other members.

In CasADi's virtual machine (jit=False) and on short horizons: the compiled path is the
same code with a compiled right-hand side, measured in bench/study_sweep.py."""

import pickle

import numpy as np
import pytest
import scipy.stats
import xarray as xr
from scenes import double_pendulum
from scenes.reference import seed_reference

import kinetwork as kn
from kinetwork.analysis.sweep import Job, run_batch

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


def test_grid_equals_a_loop_of_simulate_and_the_closed_form():
    model = double_pendulum()
    tight = {"rtol": 1e-10, "atol": 1e-12, "t_end": 1.5, "n_points": 151, "jit": False}
    # 6 members in batches of 4 on 2 threads: a padded batch and two batches in one call
    ds = kn.sweep(model, {"c": [0.5, 2.0, 8.0], "d": [0.2, 1.5]}, batch=4, workers=2,
                  progress=False, **tight)
    assert dict(ds.sizes) == {"c": 3, "d": 2, "time": 151}
    assert list(ds.status.values.ravel()) == ["ok"] * 6
    assert ds["probe1.angle"].attrs["units"] == "rad"
    assert ds["probe1.torque"].attrs["units"] == "N*m"
    assert ds["time"].attrs["units"] == "s"
    assert ds["shoulder.qd"].attrs["units"] == "rad/s"
    for c in ds.c.values:
        for d in ds.d.values:
            member = ds.sel(c=c, d=d)
            res = kn.simulate(model, params={"c": c, "d": d}, **tight)
            states = np.column_stack([member[n].values for n in res.state_names])
            np.testing.assert_allclose(states, res.states, atol=1e-7)
            if d == 0.2:    # the paper's M, V, G integrated by scipy at 1e-13: independent
                ref = seed_reference(ds.time.values, c=c, d=d)
                assert np.abs(res.states - ref).max() < 1e-7          # the loop's own error
                np.testing.assert_allclose(states, ref, atol=1e-7)
            for name in res.signals:        # the loop of simulate, to the tolerance
                scale = np.abs(res[name]).max() * (10 if "acceleration" in name else 1)
                np.testing.assert_allclose(member[name].values, res[name], rtol=0,
                                           atol=1e-7 * max(1.0, scale))


def test_fixed_step_members_equal_simulate_to_rounding():
    """rk takes the same steps batched as alone: no tolerance in between."""
    model = double_pendulum()
    ds = kn.sweep(model, {"m2": [0.5, 1.0, 3.0]}, method="rk", step=0.005, batch=2,
                  workers=1, **FAST)
    for m2 in ds.m2.values:
        res = kn.simulate(model, params={"m2": m2}, method="rk", step=0.005, t_end=1.5,
                          n_points=151, jit=False)
        np.testing.assert_allclose(ds.sel(m2=m2)["probe2.angle"].values, res["probe2.angle"],
                                   atol=1e-12)
    assert set(ds.method.values) == {"rk"}


def test_sample_draws_repeatably_and_each_member_is_its_own_run():
    model = double_pendulum()
    draws = {"m2": kn.normal(1.0, 0.05), "c": scipy.stats.uniform(0.5, 1.5),
             "d": [0.1, 0.5, 0.9, 1.3, 1.7]}
    ds = kn.sample(model, draws, n=5, seed=3, rtol=1e-10, atol=1e-12, **FAST)
    again = kn.sample(model, draws, n=5, seed=3, rtol=1e-10, atol=1e-12, **FAST)
    np.testing.assert_array_equal(ds.m2.values, again.m2.values)
    rng = np.random.default_rng(3)      # the draw, in the order of the dict
    np.testing.assert_array_equal(ds.m2.values, rng.normal(1.0, 0.05, 5))
    assert np.all((ds.c.values >= 0.5) & (ds.c.values <= 2.0))
    assert ds.m2.attrs["distribution"] == "normal(1, 0.05)"
    assert dict(ds.sizes) == {"member": 5, "time": 151}
    k = 2
    params = {name: float(ds[name].values[k]) for name in ("m2", "c", "d")}
    res = kn.simulate(model, params=params, t_end=1.5, n_points=151, jit=False, rtol=1e-10,
                      atol=1e-12)
    np.testing.assert_allclose(ds["probe2.angle"].values[k], res["probe2.angle"], atol=1e-8)


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
    # the failed run is kept up to where it got, as simulate's partial results
    failed = ds.sel(T=0.5, mass=1.0)
    assert failed.t_reached.item() == pytest.approx(0.4)
    with pytest.raises(kn.SimulationError) as err:
        kn.simulate(model, params={"T": 0.5}, t_end=1.0, n_points=11, jit=False)
    partial = err.value.results["probe.angle"]
    np.testing.assert_array_equal(failed["probe.angle"].values[:len(partial)], partial)
    assert np.all(np.isnan(failed["probe.angle"].values[len(partial):]))
    # a member that ran: within the tolerance (rtol 1e-6, the default) of a tight run
    ref = kn.simulate(model, params={"T": 3.0}, t_end=1.0, n_points=11, jit=False,
                      rtol=1e-11, atol=1e-13)["probe.angle"]
    np.testing.assert_allclose(ds.sel(T=3.0, mass=1.0)["probe.angle"].values, ref, atol=1e-6)
    assert ds.attrs["failed"] == 4


def test_an_interrupted_sweep_keeps_what_finished():
    calls = []

    def progress(done, total):          # Ctrl-C arrives after the first batch
        calls.append((done, total))
        raise KeyboardInterrupt

    ds = kn.sweep(double_pendulum(), {"c": [1.0, 2.0, 3.0, 4.0]}, batch=2, workers=1,
                  t_end=0.5, n_points=51, jit=False, progress=progress)
    assert calls == [(2, 4)]
    assert ds.attrs["interrupted"] == 1
    assert ds.status.values.tolist() == ["ok", "ok", "interrupted", "interrupted"]
    assert np.all(np.isfinite(ds["probe1.angle"].values[:2]))
    assert np.all(np.isnan(ds["probe1.angle"].values[2:]))


def test_bad_input_is_refused_by_name():
    model = double_pendulum()
    with pytest.raises(kn.ModelError, match=r"'cc' is no model parameter.*'c'"):
        kn.sweep(model, {"cc": [1.0]})
    with pytest.raises(kn.ModelError, match="'c': give a non-empty sequence"):
        kn.sweep(model, {"c": []})
    with pytest.raises(kn.ModelError, match=r"sweep: c\[1\]: must be a finite number"):
        kn.sweep(model, {"c": [1.0, float("nan")]})
    with pytest.raises(kn.ModelError, match="n must be a positive integer"):
        kn.sample(model, {"c": kn.normal(1, 0.1)}, n=0)
    with pytest.raises(kn.ModelError, match="'c': 2 values for n = 3"):
        kn.sample(model, {"c": [1.0, 2.0]}, n=3)
    with pytest.raises(kn.ModelError, match="std must be >= 0"):
        kn.normal(1.0, -0.1)
    with pytest.raises(kn.ModelError, match="rtol"):
        kn.sweep(model, {"c": [1.0]}, rtol=-1)
    with pytest.raises(kn.ModelError, match="workers: must be a positive integer"):
        kn.sweep(model, {"c": [1.0]}, workers=0)
    with pytest.raises(kn.ModelError, match="scheduler: None, 'local', an address"):
        kn.sweep(model, {"c": [1.0]}, scheduler="nowhere", **FAST)


def test_a_job_travels_as_the_model_text():
    """What a Dask worker in another process gets: the job pickled, its System compiled
    again from the model's text; the numbers are the same."""
    model = double_pendulum()
    system = model.compile()
    settings = {"t_end": 0.5, "n_points": 51, "method": "auto", "rtol": 1e-8, "atol": 1e-10,
                "step": None}
    job = Job(system, ["c"], None, settings, 0.0, False)
    copy = pickle.loads(pickle.dumps(job))
    assert copy.system is not system and copy.system.state_names == system.state_names
    values = np.array([[0.5], [3.0]])
    a, b = run_batch(job, values, 2), run_batch(copy, values, 2)
    np.testing.assert_array_equal(a.outputs, b.outputs)


def test_dask_cluster_gives_the_local_numbers():
    import distributed
    model = double_pendulum()
    grid = {"c": [0.5, 2.0, 4.0]}
    local = kn.sweep(model, grid, batch=2, workers=1, t_end=0.5, n_points=51, jit=False,
                     progress=False)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        ds = kn.sweep(model, grid, batch=2, scheduler=client, t_end=0.5, n_points=51,
                      jit=False, progress=False)
    assert ds.attrs["scheduler"].startswith("dask inproc://")
    assert ds.status.values.tolist() == ["ok"] * 3
    np.testing.assert_array_equal(ds["probe1.angle"].values, local["probe1.angle"].values)


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
                               res["probe1.angle"], atol=1e-7)
    assert float(lines[5].split()[2]) == pytest.approx(res["probe1.angle"][-1], abs=1e-6)
    ds.close()
    assert main(["sweep", str(seed_file), "--param", "cc=1"]) == 1     # named, not a trace
    assert "'cc' is no model parameter" in capsys.readouterr().err


def test_a_swept_initial_angle_starts_each_member_there():
    """The start is found once when the swept parameters cannot change it (c, d) and per
    member when they do (q0 given as a parameter)."""
    model = double_pendulum()
    model.parameters["a0"] = 0.05
    model.components["shoulder"].q0 = "a0"
    tight = {"rtol": 1e-10, "atol": 1e-12, "t_end": 0.5, "n_points": 51, "jit": False}
    ds = kn.sweep(model, {"a0": [0.05, 0.3], "c": [1.0, 3.0]}, progress=False, **tight)
    np.testing.assert_array_equal(ds["shoulder.q"].values[:, :, 0], [[0.05, 0.05], [0.3, 0.3]])
    res = kn.simulate(model, params={"a0": 0.3, "c": 3.0}, **tight)
    np.testing.assert_allclose(ds["probe1.angle"].sel(a0=0.3, c=3.0).values,
                               res["probe1.angle"], atol=1e-8)
    ref = seed_reference(ds.time.values, x0=(0.3, 0.05, 0.0, 0.0), c=3.0)
    np.testing.assert_allclose(ds["elbow.q"].sel(a0=0.3, c=3.0).values, ref[:, 1], atol=1e-8)


def test_a_lost_dask_task_marks_its_members_and_keeps_the_others(monkeypatch):
    import distributed
    module = __import__("sys").modules["kinetwork.analysis.sweep"]
    real = module.run_batch

    def exploding(job, values, batch):
        if values[0][0] == 2.0:
            raise RuntimeError("worker exploded")
        return real(job, values, batch)
    monkeypatch.setattr(module, "run_batch", exploding)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        ds = kn.sweep(double_pendulum(), {"c": [1.0, 2.0, 3.0]}, batch=1, scheduler=client,
                      t_end=0.5, n_points=11, jit=False, progress=False)
    assert ds.status.values.tolist() == ["ok", "failed", "ok"]
    assert ds.reason.values[1] == "the Dask task failed: RuntimeError: worker exploded"
    assert np.all(np.isfinite(ds["probe1.angle"].values[[0, 2]]))
