"""How the driver (``driver.py``) cuts a run into chunks of the output grid and keeps what
they reach: a chunk is sized by the work the last one took (evaluations of the equations times
the instructions of one), the same on every machine, so a run's numbers never depend on its
speed; the states go into one array of the grid's size, which CasADi writes into.
"""

import numpy as np

#: a chunk of a CasADi integration is sized to about this much work (evaluations of the
#: equations times their instructions: ~1 ns an instruction compiled, ~10 in CasADi's virtual
#: machine, so 0.1 to 1 s): cancellation, time limits and progress are served between
#: chunks, and each chunk restarts the method (a BDF method recomputes its Jacobian). The same
#: with and without C, so that both give the same numbers
CHUNK_WORK = 1e8
#: the first chunk is sized as if each output interval took this many steps (how many it
#: takes is not known before); later ones from the work the last took, growing at most
#: CHUNK_GROWTH-fold (each chunk restarts a multistep method: few chunks for a fast run)
FIRST_CHUNK_STEPS = 100
CHUNK_GROWTH = 16
#: output intervals of one CasADi call at most, quiet runs included: building an integrator
#: over 6e6 output times took 4 s and stopping it only comes between calls (a signal aborts
#: a call, not the building), and work counts miss the cost of the outputs themselves
MAX_CHUNK = 2**16


def _first_chunk(run, method, intervals):
    """Output intervals of the first chunk, before any work is known: as many as fit a chunk's
    work if each takes FIRST_CHUNK_STEPS steps (a fixed-step method: its own), so a cheap run
    goes in one call; a power of two otherwise."""
    steps = run.steps_per_interval if method.fixed else FIRST_CHUNK_STEPS
    per_interval = 4 * steps * run.instructions
    fit = CHUNK_WORK / per_interval
    if fit >= intervals:
        return intervals
    return 2 ** int(np.log2(max(1.0, fit)))


class _Rows:
    """The states reached, in one array of the grid's size allocated at the start (a list of
    10^5 rows costs more to build and join than the integration of a small model, and
    joining blocks at the end would hold the states twice): a CasADi method writes its
    outputs straight into the rows reserved for them (``slot``)."""

    def __init__(self, x0, n):
        x0 = np.asarray(x0, dtype=float)
        self.data = np.empty((max(n, 1), len(x0)))
        self.data[0] = x0
        self.n = 1
        self._slot = None                   # the rows last handed out by ``slot``

    def __len__(self):
        return self.n

    def __getitem__(self, i):
        return self.data[:self.n][i]

    def slot(self, m):
        """The next ``m`` rows, for a method to write into (then ``extend`` with them)."""
        self._slot = self.data[self.n:self.n + m]
        return self._slot

    def extend(self, rows):
        slot, self._slot = self._slot, None
        if slot is not None and rows is slot:       # written in place, all of it
            self.n += len(rows)
            return
        rows = np.asarray(rows, dtype=float).reshape(-1, self.data.shape[1])
        m = len(rows)
        if not m:
            return
        if self.n + m > len(self.data):             # a restart's row past the grid: grow
            self.data = np.concatenate([self.data[:self.n], rows])
            self.n += m
            return
        target = self.data[self.n:self.n + m]
        if rows.ctypes.data != target.ctypes.data or rows.strides != target.strides:
            target[...] = rows                      # not written in place by the method
        self.n += m

    def append(self, row):
        self.extend(np.asarray(row)[None, :])

    def replace_last(self, row):
        self.data[self.n - 1] = row

    def array(self):
        """The rows reached (a view, not a copy)."""
        return self.data[:self.n]

    def __array__(self, dtype=None, copy=None):
        out = self.array()
        return out if dtype is None else out.astype(dtype)


def _next_chunk(run, m, work, remaining):
    """Output intervals of the next chunk, from the work the last one (``m`` intervals) took:
    the rest at once when even sixteen times its estimate is within a chunk's work (a fast
    run goes in two calls), else a power of two (each length's integrator is kept) sized to
    a chunk's work, at most CHUNK_GROWTH times the last."""
    per_interval = max(work, 1.0) / m
    if CHUNK_GROWTH * per_interval * remaining <= CHUNK_WORK:
        return remaining
    return 2 ** int(np.log2(max(1, min(CHUNK_GROWTH * m, CHUNK_WORK / per_interval))))


def _work(run, stats):
    """The work a method has done so far: evaluations of the equations (a Jacobian counted as
    one per state) times the instructions of one evaluation, and n^3/3 for each factorisation
    of an implicit method's matrix."""
    n = run.system.n_states + run.system.n_algebraic
    evaluations = stats.get("rhs_evaluations", stats.get("steps", 0) * 4) + \
        stats.get("jacobian_evaluations", 0) * n
    return evaluations * run.instructions + stats.get("factorisations", 0) * n ** 3 / 3


def _merge(total, more):
    """The statistics of a stepper and of the one that replaced it (a restart): counters
    added, anything else (a step size, a residual) as the later one says."""
    out = {**total, **more}
    for key in total.keys() & more.keys():
        if isinstance(more[key], int) and not isinstance(more[key], bool):
            out[key] = total[key] + more[key]
    return out
