"""Sweeps on Dask: the numbers of this process's, the issue's failing member marked as in
threads, a task that raises marks its members with its reason, and a sweep survives losing
every worker (the job is a task with lineage, never scattered)."""

import gc
import os
import signal
import warnings

import distributed
import numpy as np
import pytest
from close import assert_same_numbers
from scenes import double_pendulum

import kinetwork as kn

from .test_sweep import check_push, seed_push


@pytest.fixture
def inproc():
    """A cluster in this process: one worker, one thread."""
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        yield client


def test_dask_gives_the_local_numbers_and_marks_the_failing_member(inproc):
    model = seed_push()
    settings = {"t_end": 3.0, "jit": False}
    ds = kn.sweep(model, {"tb": [10.0, 2.0, 20.0, 30.0]}, batch=2, scheduler=inproc,
                  progress=False, **settings)
    assert ds.attrs["scheduler"].startswith("dask inproc://")
    check_push(ds, model, **settings)
    local = kn.sweep(model, {"tb": [10.0, 2.0, 20.0, 30.0]}, batch=2, workers=1,
                     progress=False, **settings)
    assert_same_numbers(ds["probe1.angle"].values, local["probe1.angle"].values)


def test_a_task_that_raises_marks_its_members_and_keeps_the_others(inproc, monkeypatch):
    from kinetwork.analysis import sweep_dask
    real = sweep_dask.run_block

    def exploding(job, values, batch):
        if values[0][0] == 2.0:
            raise RuntimeError("worker exploded")
        return real(job, values, batch)
    monkeypatch.setattr(sweep_dask, "run_block", exploding)
    ds = kn.sweep(double_pendulum(), {"c": [1.0, 2.0, 3.0]}, batch=1, scheduler=inproc,
                  t_end=0.5, n_points=11, jit=False, progress=False)
    assert ds.status.values.tolist() == ["ok", "failed", "ok"]
    assert ds.reason.values[1] == "the Dask task failed: RuntimeError: worker exploded"
    assert np.all(np.isfinite(ds["probe1.angle"].values[[0, 2]]))


def test_a_sweep_survives_losing_every_worker():
    """Two worker processes under nannies; after the first member is in, every worker is
    killed (SIGKILL): the nannies start new ones, the job and the lost blocks run again
    there, and every member is ok and equal to this process's run."""
    model = double_pendulum()
    grid = {"c": np.linspace(0.5, 4.0, 12).tolist()}
    settings = {"t_end": 2.0, "n_points": 101, "jit": False}
    killed = []
    ds, after = _sweep_losing_every_worker(model, grid, settings, killed)
    assert killed and not set(after) & set(killed)         # new workers did the rest
    assert ds.status.values.tolist() == ["ok"] * 12, ds.reason.values
    local = kn.sweep(model, grid, workers=1, progress=False, **settings)
    assert_same_numbers(ds["probe1.angle"].values, local["probe1.angle"].values)


def _sweep_losing_every_worker(model, grid, settings, killed):
    """The sweep of ``grid`` on a cluster of two workers, every worker killed after the
    first member: (the dataset, the workers' pids after). distributed's close can trip over
    a worker its nannies replaced (a KeyError in its status watcher): the cluster is then
    collected here, where its warning about it is not another test's."""
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=":0")
    try:
        with distributed.Client(cluster) as client:
            pids = list(client.run(os.getpid).values())

            def progress(done, total):
                if done == 1 and not killed:
                    for pid in pids:
                        os.kill(pid, signal.SIGKILL)
                    killed.extend(pids)
                    # nannies that cannot start a worker again (a machine out of
                    # processes) would leave the sweep waiting for one: say so instead
                    client.wait_for_workers(1, timeout=600)
            ds = kn.sweep(model, grid, batch=1, scheduler=client, progress=progress,
                          **settings)
            return ds, list(client.run(os.getpid).values())
    finally:
        tripped = False
        try:
            cluster.close()
        except KeyError:
            tripped = True
        if tripped:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                del cluster
                gc.collect()


def test_a_cluster_left_without_workers_fails_its_members_saying_so(monkeypatch):
    """Nannies that cannot start a worker again leave a cluster with none: the sweep waits
    NO_WORKERS seconds for one, then marks its members failed with that reason (it never
    waits for ever)."""
    from kinetwork.analysis import sweep_dask
    monkeypatch.setattr(sweep_dask, "NO_WORKERS", 1.0)
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=":0") \
            as cluster, distributed.Client(cluster) as client:
        ds = kn.sweep(double_pendulum(), {"c": [1.0, 2.0]}, batch=1, scheduler=client,
                      t_end=0.5, n_points=11, jit=False, progress=False)
    assert ds.status.values.tolist() == ["failed", "failed"]
    assert all(r.startswith("no Dask worker left to run it") for r in ds.reason.values)
