"""A sweep's members on a Dask cluster, surviving the loss of its workers.

The job reaches the workers as a task of its own (``client.submit`` of the job, which
pickles as the model's text and the plan's settings), never scattered: a scattered value has
no lineage, and is gone with the workers that held it; a task's result is computed again
wherever it is needed. Each block of members is a task depending on it. A worker lost while
it ran a block (killed, out of memory, its machine gone) has the block run again elsewhere by
the scheduler (``distributed.scheduler.allowed-failures`` times), and after that by the sweep
itself, up to RESUBMITS more times. A member is marked failed only with a reason that says
what happened: its run failed (``Plan.run``'s reason), its task raised, its worker was lost
again and again, its task was cancelled or timed out.
"""

import math
import time
from concurrent.futures import CancelledError

import numpy as np

from ..errors import ModelError
from ..solver.batch import MAX_BATCH
from .sweep_job import run_block, store

#: times the sweep submits a block again after Dask gave up on it (KilledWorker: its
#: workers were lost more often than the scheduler allows), or lost its result
RESUBMITS = 2
#: seconds between looks at the cancel flag (Ctrl-C) while blocks run
POLL = 0.25
#: seconds a finished block's result may take to reach this process: longer, it was lost
#: with its worker (Dask then waits for a worker to compute it again) and is submitted anew
FETCH = 60.0
#: seconds the sweep waits for a cluster that has no worker left (nannies that cannot start
#: one again) before it marks the members not yet run failed, saying so
NO_WORKERS = 300.0


def client_of(scheduler):
    """(client, what to close after the sweep) for ``scheduler``: "local" (a LocalCluster
    made for the sweep), an address, or a ``distributed.Client``."""
    from distributed import Client, LocalCluster
    if isinstance(scheduler, Client):
        return scheduler, []
    if scheduler == "local":
        cluster = LocalCluster(threads_per_worker=1, dashboard_address=":0")
        client = Client(cluster)
        return client, [client, cluster]
    if isinstance(scheduler, str) and "://" in scheduler:
        try:
            client = Client(scheduler, timeout=30)
        except OSError as exc:
            raise ModelError(f"scheduler {scheduler!r}: cannot connect ({exc})") from None
        return client, [client]
    raise ModelError(f"scheduler: None, 'local', an address (tcp://host:8786) or a "
                     f"distributed.Client, got {scheduler!r:.60}")


def check_scheduler(scheduler):
    """Refuse, before any member runs, a scheduler that cannot be used: Dask missing, or a
    value that is none of the kinds ``client_of`` takes."""
    try:
        from distributed import Client
    except ImportError:
        raise ModelError("scheduler: Dask is not installed (pip install "
                         "'kinetwork[sweep]')") from None
    if not (isinstance(scheduler, Client) or scheduler == "local" or
            (isinstance(scheduler, str) and "://" in scheduler)):
        raise ModelError(f"scheduler: None, 'local', an address (tcp://host:8786) or a "
                         f"distributed.Client, got {scheduler!r:.60}")


def run_dask(job, values, out, scheduler, batch, stop, done):
    """Run every member (rows of ``values``) on Dask into ``out``; True when stopped."""
    from distributed import wait
    client, own = client_of(scheduler)
    futures = {}
    try:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        size = batch or max(1, min(MAX_BATCH, math.ceil(len(values) / (4 * workers))))
        remote = client.submit(_job, job, pure=False)
        for start in range(0, len(values), size):
            index = np.arange(start, min(len(values), start + size))
            futures[_submit(client, remote, values[index], size)] = (index, 0)
        alone = _Workerless(client)
        while futures:
            if stop():
                return True
            if alone.too_long():
                why = (f"no Dask worker left to run it: the cluster has had none for "
                       f"{NO_WORKERS:g} s (its workers were lost, and none came back)")
                for index, _ in futures.values():
                    for i in index:
                        out.status[i], out.reason[i] = "failed", why
                        done(i)
                return False
            try:
                finished, _ = wait(list(futures), timeout=POLL, return_when="FIRST_COMPLETED")
            except TimeoutError:
                continue
            except CancelledError:      # a scheduler's restart cancels them: lost, anew
                finished = [fut for fut in futures if fut.done() or fut.cancelled()]
            for fut in finished:
                index, tries = futures.pop(fut)
                part, why, lost = _outcome(fut)
                if part is None and lost and tries < RESUBMITS:
                    if remote.status in ("cancelled", "lost", "error"):   # a restart: anew
                        remote = client.submit(_job, job, pure=False)
                    futures[_submit(client, remote, values[index], size)] = (index, tries + 1)
                    continue
                if part is None:
                    for i in index:
                        out.status[i], out.reason[i] = "failed", why
                else:
                    store(out, index, part)
                for i in index:
                    done(i)
        return False
    finally:
        for fut in futures:
            if not fut.done():
                fut.cancel()
        for thing in own:
            thing.close()


class _Workerless:
    """How long the cluster has had no worker: asked once a second at most."""

    def __init__(self, client):
        self.client, self.since, self.asked = client, None, 0.0

    def too_long(self):
        now = time.monotonic()
        if now - self.asked < 1.0:
            return False
        self.asked = now
        try:
            workers = self.client.scheduler_info().get("workers", {})
        except Exception:  # noqa: BLE001 -- the scheduler cannot say: none known
            workers = {}
        if workers:
            self.since = None
        elif self.since is None:
            self.since = now
        return self.since is not None and now - self.since > NO_WORKERS


def _job(job):
    """The job on a worker (the task whose result every block reads)."""
    return job


def _submit(client, remote, rows, size):
    return client.submit(run_block, remote, rows, size, pure=False)


def _outcome(fut):
    """(the block's arrays or None, why not, whether it was lost rather than failed)."""
    from distributed import KilledWorker
    if fut.status == "finished":
        try:
            return fut.result(timeout=FETCH), "", False
        except Exception as exc:  # noqa: BLE001 -- its result was lost with its worker
            return None, _lost(exc), True
    exc = None
    if fut.status == "error":
        try:
            exc = fut.exception()
        except Exception as error:  # noqa: BLE001 -- the scheduler cannot say: lost
            exc = error
    if isinstance(exc, KilledWorker):
        return None, (f"the Dask worker running it was lost again and again (KilledWorker: "
                      f"{exc})"), True
    if isinstance(exc, TimeoutError):
        return None, f"the Dask task timed out: {exc}", True
    if exc is None:
        return None, (f"the Dask task was {fut.status} (its worker or the scheduler went "
                      f"away before it finished)"), True
    return None, f"the Dask task failed: {type(exc).__name__}: {exc}", False


def _lost(exc):
    return f"the Dask task's result was lost with its worker ({type(exc).__name__}: {exc})"
