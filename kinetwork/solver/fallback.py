"""auto's watch over a running method (``driver._auto``): the look at Adams when an output
interval takes more steps than its budget (``look_budget``), which hands the run to BDF when
the evidence says a decaying mode's stability holds the step (``Stalled``), and the rival
that a fallback runs against, which gives up past twice the work of the method it replaced
(``Rival``, ``GaveUp``).
"""

import math

import numpy as np

from .chunks import CHUNK_WORK, _work
from .stiffness import stability_held

#: Adams steps projected for a run beyond which a look asks whether they are held by stability
STALL_STEPS = 1e6
#: a fallback of auto (BDF after Adams) does at most this many times the work per simulated
#: second that the method it replaces did, or gives up (issue 30: BDF after Adams on a
#: 128-link chain took 263 s of CPU where Adams needs 3 s)
FALLBACK_SLOWER = 2.0
#: auto's Adams is stopped to look whether it stalls when one output interval takes more
#: steps than STALL_STEPS spread over the run's intervals, and at least this many (then twice
#: as many, after a look that let it go on): a step budget, so the look is where the steps
#: are, on every machine and in any thread (a sweep's mapped members, a Dask worker), never
#: where a clock says
LOOK_STEPS = 100


class _Found(str):
    """A reason a method stops (a str, as every failure's reason is) with the time ``t`` it
    was found at."""

    def __new__(cls, t, text):
        self = super().__new__(cls, text)
        self.t = float(t)
        return self


class Stalled(_Found):
    """Why auto's Adams gave way to BDF mid-run."""

    def __new__(cls, t, step, projected, rate, decay):
        return super().__new__(cls, t, (
            f"Adams stalled at t = {t:g} s: its steps ({step:.3g} s on average, "
            f"{projected:.3g} projected for the run) are held by the stability of a mode "
            f"of rate {rate:.3g}/s that decays at {decay:.3g}/s, not by accuracy; BDF took "
            f"over from the start"))


def look_budget(run):
    """The steps of one output interval after which auto's Adams is stopped to look whether
    it stalls: STALL_STEPS spread over the run's intervals, at least LOOK_STEPS."""
    intervals = max(1, len(run.grid) - 1)
    return max(LOOK_STEPS, math.ceil(STALL_STEPS / intervals))


def _stalled(run, t, x, steps):
    """After auto's Adams spent its look budget (``look_budget``) in the output interval
    that starts at ``t`` (state ``x``; ``steps`` taken before): a ``Stalled`` reason when the
    evidence says Adams cannot finish in reasonable work (more than STALL_STEPS projected
    for the run at the mean step of that interval, a step held by the stability of a fast
    mode that decays, ``stiffness.stability_held``), else None: Adams goes on, looked at again
    when an interval takes twice as many steps."""
    t, hit = float(t), run.look_hit
    budget, run.look_hit = run.look_steps, None
    run.look_steps = 2 * budget
    step = (hit - t) / budget
    if step <= 0:
        return None
    projected = steps + budget + (run.t_end - hit) / step
    if projected <= STALL_STEPS:
        return None
    held, rate, decay = stability_held(run.rhs(), t, run.t_end,
                                       np.asarray(x)[:run.system.n_states], step)
    return Stalled(hit, step, projected, rate, decay) if held else None


class Rival:
    """The method a fallback replaces, and what it did (the work ``_work`` counts, over the
    simulated time from the start to ``t``): a fallback that has done more than FALLBACK_SLOWER
    times that work per simulated second (past one chunk's, CHUNK_WORK) gives up
    (``outrun``)."""

    def __init__(self, name, work, t_start, t):
        self.name, self.work = name, float(work)
        self.rate = self.work / max(float(t) - t_start, 1e-300)

    def outrun(self, run, stats, more, t):
        """A ``GaveUp`` reason when the fallback's work to ``t`` is past its allowance."""
        work = _work(run, stats) + _work(run, more)
        allowed = FALLBACK_SLOWER * self.rate * (float(t) - run.t_start) + CHUNK_WORK
        return GaveUp(t, self.name, work, allowed) if work > allowed else None


class GaveUp(_Found):
    """Why auto gave up on a fallback: slower than the method it replaced."""

    def __new__(cls, t, rival, work, allowed):
        return super().__new__(cls, t, (
            f"gave up at t = {t:g} s: it had done {work:.3g} units of work (evaluations times "
            f"instructions, a Jacobian as one evaluation per state, a factorisation as n^3/3) "
            f"where {FALLBACK_SLOWER:g} times what {rival} did over as long a stretch "
            f"allows {allowed:.3g}"))
