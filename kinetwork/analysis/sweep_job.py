"""The job of a sweep: what every member shares (the model's plan, the varied names, the
common parameters, the kept outputs), and running a block of members of it, here or on a
Dask worker.

A job travels as the model's JSON text and the plan's settings, never as a compiled System:
a worker builds the plan once (``_PLANS``: compiled once per process) and keeps it for the
next blocks of the same job.
"""

import collections
import threading

import numpy as np

from ..errors import ModelError
from ..solver.batch import Keep, Members, Varying, run_members
from ..solver.plan import Plan, source_of

#: plans a worker keeps (the most recent jobs)
PLANS_KEPT = 8
_PLANS = collections.OrderedDict()
_PLANS_LOCK = threading.Lock()


class Job:
    """What every member of a sweep shares: the plan, the names of the varied parameters,
    the common parameter values (``base``) and the outputs kept. Pickles as the model's text
    and the plan's settings."""

    def __init__(self, plan, names, base=None, outputs=None):
        self.plan, self.names = plan, list(names)
        self.base, self.outputs = dict(base or {}), outputs
        self.varying = Varying(plan, self.names, self.base)
        self.keep = Keep(plan.system, outputs)

    def __getstate__(self):
        from ..graph.io import dumps
        return {"text": dumps(source_of(self.plan.system)), "spec": self.plan.spec(),
                "names": self.names, "base": self.base, "outputs": self.outputs}

    def __setstate__(self, state):
        key = (state["text"], repr(sorted(state["spec"].items())), tuple(state["names"]),
               repr(sorted(state["base"].items())), repr(state["outputs"]))
        with _PLANS_LOCK:
            job = _PLANS.get(key)
        if job is None:
            job = _build(state)
            with _PLANS_LOCK:
                _PLANS[key] = job
                while len(_PLANS) > PLANS_KEPT:
                    _PLANS.popitem(last=False)
        with _PLANS_LOCK:
            _PLANS.move_to_end(key)
        self.__dict__.update(job.__dict__)


def _build(state):
    from ..graph.io import loads
    spec = dict(state["spec"])
    loops, rate = spec.pop("loops"), spec.pop("baumgarte_rate")
    grid = spec.pop("grid")
    system = loads(state["text"]).compile(loops, rate)
    job = Job.__new__(Job)
    Job.__init__(job, Plan(system, names=state["names"] + list(state["base"]), grid=grid,
                           **spec), state["names"], state["base"], state["outputs"])
    return job


def prepare(job, rows, out, index):
    """[(i, p, x0)] of the members ``index`` whose varied values are ``rows`` (SI numbers);
    a member whose values or start are refused is marked failed in ``out`` instead."""
    members = []
    for i, row in zip(index, rows):
        try:
            p = job.varying.vector(row)
            members.append((i, p, job.varying.start(p)))
        except ModelError as exc:
            out.refuse(i, str(exc), job.plan.t_start)
    return members


def run_block(job, rows, batch=None):
    """Run the members whose varied values are ``rows`` (a Dask task): their states,
    outputs and outcome as plain arrays."""
    out = Members(job.plan, len(rows), job.keep)
    members = prepare(job, rows, out, range(len(rows)))
    names = job.names
    run_members(job.plan, members, out, workers=1, batch=batch,
                params=lambda i: {**job.base, **dict(zip(names, map(float, rows[i])))})
    return {"states": out.states, "outputs": out.outputs, "status": out.status,
            "reason": out.reason, "t_reached": out.t_reached, "method": out.method}


def store(out, index, part):
    """Put a block's arrays (``run_block``'s) into ``out`` at ``index``."""
    index = np.asarray(index)
    out.states[index] = part["states"]
    out.outputs[index] = part["outputs"]
    out.t_reached[index] = part["t_reached"]
    for k, i in enumerate(index):
        out.status[i], out.reason[i] = part["status"][k], part["reason"][k]
        out.method[i] = part["method"][k]
