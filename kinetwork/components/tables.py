"""Signal blocks that interpolate tables: ``signals.Table`` (1-D, in u or in time) and
``signals.Table2D``, and the piecewise-linear interpolation they share.

Part of the ``signals`` library (``kn.signals.Table``): a library's parts may live in modules
of their own (``components/__init__.py``). A table's breakpoints are recorded by the name of
its interpolant (``interpolant_knots``), so the equations can find where its time events are.
"""

import hashlib

import numpy as np

from ..errors import ModelError
from ..expr import literal_functions
from ..util import check_number, quote
from .base import TABLE_ROWS_LIMIT, Param, Port
from .signals import LIB, PartialBlock


class Table(PartialBlock, library=LIB):
    """y interpolated linearly in ``table`` rows [x, y] at u (or at time t when u is not
    wired), extrapolated linearly from the end rows. Two rows with the same x are a step,
    as in MSL's CombiTimeTable: the first row's y up to x, the second's from x on.

    Read in time, every breakpoint is a time event (the integration stops there, as MSL's
    CombiTimeTable's do by default), however long the table; with ``time_events="steps"``
    only its steps are (MSL's AtDiscontinuities: a long, finely sampled smooth signal,
    whose kinks the integrator's error control follows, without a restart at each row).
    Read at a signal of the states, its kinks are taken as they are (as MSL's CombiTable1D)
    and its steps are state events."""
    u = Port("signal_in", "Abscissa (unwired: time)", optional=True)
    table = Param(kind="table", doc="Rows [x, y], x increasing; two rows with the same x "
                                    "are a step (at most 100 000 rows)")
    time_events = Param("always", kind="choice", choices=("always", "steps"),
                        doc="Read in time, the rows that are time events: every one "
                            "(always) or the steps only (steps)")
    #: a table of up to this many rows is an expression (``kinetwork equations`` prints it);
    #: a longer one a CasADi interpolant, which costs time linear in the rows to build and
    #: compile to C, where the expression's cost grows with their square (10 000 rows:
    #: 5 s to build, 100 000: 6 min)
    expression_rows = 100

    def output(self, u, x, t):
        import casadi as ca
        at = t if u["u"] is None else u["u"]
        xs = [row[0] for row in self.table]
        ys = [row[1] for row in self.table]
        kinks = self.time_events == "always"
        if len(xs) <= self.expression_rows:
            return piecewise_linear(at, xs, ys, kinks)
        knots, left, jumps = _steps(xs, ys)
        # the table less its steps is continuous: an interpolant, the steps added to it
        name = _interpolant_name(self.name, knots) if kinks else f"{self.name}_table"
        smooth = ca.interpolant(name, "linear", [knots], left)(at)
        return smooth + sum((j * (k <= at) for k, j in zip(knots, jumps) if j), ca.SX(0))


#: the knots of each long Table's interpolant by its name: read in time, every knot is a
#: time event (``kinetwork.equations.relations`` finds the interpolant's call in the
#: equations, and its knots here), as each breakpoint of MSL's CombiTimeTable is
_KNOTS = {}


def _interpolant_name(name, knots):
    """A name for the interpolant of ``knots`` that no other table's shares (their digest in
    it), its knots recorded for ``interpolant_knots``."""
    digest = hashlib.sha1(np.asarray(knots, dtype=float).tobytes()).hexdigest()[:16]
    full = f"{name}_table_{digest}"
    _KNOTS[full] = tuple(knots)
    return full


def interpolant_knots(name):
    """The knots of the Table interpolant called ``name``, or None for any other function."""
    return _KNOTS.get(name)


class Table2DParam(Param):
    """A 2-D table as MSL's CombiTable2D: the first row holds the u2 grid (after a corner
    entry that is ignored), the first column the u1 grid, the rest the values."""

    def __init__(self, *, doc=""):
        super().__init__(kind="table2d", doc=doc)

    def normalize(self, value, where):
        if isinstance(value, np.ndarray):
            value = value.tolist()
        if not isinstance(value, (list, tuple)) or len(value) < 3 or not all(
                isinstance(r, (list, tuple)) for r in value):
            raise ModelError(f"{where}: must be a matrix of at least 3 x 3 (grids in the "
                             f"first row and column), got {quote(value)}")
        if len(value) * len(value[0]) > TABLE_ROWS_LIMIT:
            raise ModelError(f"{where}: more than {TABLE_ROWS_LIMIT} entries; resample it")
        width = len(value[0])
        rows = []
        for i, row in enumerate(value):
            if len(row) != width or width < 3:
                raise ModelError(f"{where}[{i}]: every row must have the first row's "
                                 f"{width} entries (at least 3), got {len(row)}")
            rows.append([float(check_number(v, f"{where}[{i}][{j}]")) for j, v in
                         enumerate(row)])
        for label, grid, at in (("first column (u1)", [r[0] for r in rows[1:]], "[{}][0]"),
                                ("first row (u2)", rows[0][1:], "[0][{}]")):
            for k in range(1, len(grid)):
                if grid[k] <= grid[k - 1]:
                    raise ModelError(f"{where}{at.format(k + 1)}: the {label} must increase, "
                                     f"got {grid[k]} after {grid[k - 1]}")
        return rows


class Table2D(PartialBlock, library=LIB):
    """y interpolated bilinearly in a 2-D ``table`` at (u1, u2) (MSL's CombiTable2D with
    linear segments), extrapolated linearly from the boundary cells; differentiable
    everywhere but on the grid lines (CasADi's derivatives are exact inside each cell)."""
    u1 = Port("signal_in", "Abscissa along the first column")
    u2 = Port("signal_in", "Abscissa along the first row")
    table = Table2DParam(doc="[[ignored, u2 grid...], [u1, values...], ...], grids "
                             "increasing")
    #: up to this many values, an SX expression (hat functions of pw_lin on each axis);
    #: beyond, a CasADi interpolant
    expression_cells = 400

    def output(self, u, x, t):
        import casadi as ca
        grid1 = [r[0] for r in self.table[1:]]
        grid2 = self.table[0][1:]
        values = np.array([r[1:] for r in self.table[1:]])
        if values.size > self.expression_cells:
            return ca.interpolant(f"{self.name}_table", "linear", [grid1, grid2],
                                  values.ravel(order="F"))(ca.vertcat(u["u1"], u["u2"]))
        return ca.dot(_hats(u["u1"], grid1), ca.mtimes(ca.DM(values), _hats(u["u2"], grid2)))


def _hats(at, grid):
    """The piecewise-linear hat functions of ``grid`` at ``at``, extrapolated linearly (they
    sum to one): a linear interpolant is their product with the values."""
    import casadi as ca
    eye = np.eye(len(grid))
    return ca.vertcat(*[piecewise_linear(at, grid, eye[k]) for k in range(len(grid))])


def _steps(xs, ys):
    """(knots, values, jumps) of a table whose equal x's are steps: at each distinct x, the
    value of the table less the steps before it (continuous), and the step there (0:
    none)."""
    knots, left, jumps = [], [], []
    total = 0.0
    i = 0
    while i < len(xs):
        equal = i + 1 < len(xs) and xs[i + 1] == xs[i]
        step = ys[i + 1] - ys[i] if equal else 0.0
        knots.append(xs[i])
        left.append(ys[i] - total)
        jumps.append(step)
        total += step
        i += 2 if equal else 1
    return knots, left, jumps


def piecewise_linear(at, xs, ys, kinks=True):
    """The linear interpolation of the rows (xs, ys) at ``at`` (extrapolated linearly from
    the end segments; two equal x's a step to the second y), as kinks ``fmax(at - x, 0)``
    and steps ``x <= at``: on time both are time events, on the states the kinks are taken
    as they are and the steps are state events (``kinetwork.equations.relations``).
    ``kinks`` False: the kinks built as ``noEvent`` builds them, never events."""
    import casadi as ca
    knots, left, jumps = _steps(list(xs), list(ys))
    fmax = ca.fmax if kinks else literal_functions()["max"]
    if len(knots) == 1:
        return ca.SX(left[0]) + jumps[0] * (knots[0] <= at)
    slopes = [(left[j + 1] - left[j]) / (knots[j + 1] - knots[j]) for j in range(len(knots) - 1)]
    y = left[0] + slopes[0] * (at - knots[0])
    for j in range(1, len(knots) - 1):
        if slopes[j] != slopes[j - 1]:
            y = y + (slopes[j] - slopes[j - 1]) * fmax(at - knots[j], 0)
    for k, jump in zip(knots, jumps):
        if jump:
            y = y + jump * (k <= at)
    return y
