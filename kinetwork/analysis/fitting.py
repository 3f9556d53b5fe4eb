"""Parameter fitting: least squares of probe signals against measured columns, with the
exact Jacobian of the residuals (the integrator's forward sensitivities), bounds, and
confidence intervals from that Jacobian at the optimum.

The measured file is a CSV as ``kinetwork run --out`` writes it: a header row, ``t`` first,
then columns named as the probes' (``probe1.angle``, ``probe.position[1]``); lines starting
with ``#`` are comments.
"""

import csv
import io
import math
import pathlib

import numpy as np

from ..errors import ModelError, SimulationError
from ..util import quote, suggest
from .channels import output_channels
from .sensitivities import Trajectory, analysis_plan, param_index


class Fit:
    """The outcome of ``kn.fit``: ``params`` (name -> estimate), ``stderr``, ``interval``
    (name -> (low, high) at ``level``), ``cov`` (their covariance, in ``names`` order),
    ``rms`` (root mean square of the weighted residuals), ``n_data``, ``columns`` fitted,
    ``success`` and ``message`` of the optimiser."""

    def __init__(self, names, estimate, cov, level, interval, rms, n_data, columns,
                 success, message, nfev):
        self.names = names
        self.params = dict(zip(names, estimate.tolist()))
        self.cov = cov
        self.stderr = dict(zip(names, np.sqrt(np.diag(cov)).tolist()))
        self.level, self.interval = level, dict(zip(names, interval))
        self.rms, self.n_data, self.columns = rms, n_data, columns
        self.success, self.message, self.nfev = success, message, nfev

    def text(self):
        """The estimates with their intervals, one line each, as ``kinetwork fit`` prints."""
        pct = f"{100 * self.level:g} %"
        lines = [f"{'parameter':<14}{'estimate':>14}{'std. error':>14}   {pct} interval"]
        for k in self.names:
            lo, hi = self.interval[k]
            lines.append(f"{k:<14}{self.params[k]:>14.6g}{self.stderr[k]:>14.3g}   "
                         f"[{lo:.6g}, {hi:.6g}]")
        lines.append(f"{self.n_data} data points of {', '.join(self.columns)}; residual rms "
                     f"{self.rms:.3g} (weighted); {self.nfev} evaluations; {self.message}")
        return "\n".join(lines)

    def __repr__(self):
        shown = ", ".join(f"{k} = {v:.6g} ± {self.stderr[k]:.2g}" for k, v in self.params.items())
        return f"<Fit {shown}>"


def fit(model, data, params, columns=None, values=None, weights=None, level=0.95,
        rtol=None, atol=None, max_nfev=100):
    """Fit model parameters to measured probe signals by least squares.

    Parameters
    ----------
    model : Model or System
    data : str, path, or dict
        A CSV file (``t``, then columns named as the probes'), or {"t": times, column:
        values}.
    params : dict or list
        Parameters to fit: name -> (low, high) bounds (None for no bound on that side), or a
        list of names (unbounded): model parameters, or component parameters by path
        (``"spring.c"``, lifted to model parameters once, see ``kn.simulate``). Each starts
        at the model's value (clipped into bounds).
    columns : list of str, optional
        Measured columns to fit (default: every column the model has a probe or state for).
    values : dict, optional
        Values of the other model parameters.
    weights : dict, optional
        Column -> weight (1 / the noise's standard deviation); default 1 / the column's
        root mean square, so that columns in different units count alike.
    level : float
        Confidence level of the intervals (default 0.95), from the Jacobian at the optimum:
        covariance s^2 (J^T J)^-1 with s^2 the residual variance, Student's t quantile.
    rtol, atol : float
        Tolerances of the integrations (default: the model's settings), meaning what they
        mean for ``kn.simulate``: the trajectories are the model's integration plan's.

    Returns
    -------
    Fit
    """
    from scipy import optimize, stats
    t, table = _read(data)
    bounds = _bounds(params)
    names = list(bounds)
    # the integration starts at t = 0; data from a later time skips the first point
    grid, skip = (t, 0) if t[0] == 0.0 else (np.concatenate([[0.0], t]), 1)
    plan = analysis_plan(model, names + list(values or {}), grid, None, None, rtol, atol, None)
    system = plan.system
    index = param_index(plan, names)
    wanted = columns if columns is not None else [c for c in table if _known(system, c)]
    if isinstance(wanted, str):
        wanted = [wanted]
    missing = [c for c in wanted if c not in table]
    if missing or not wanted:
        raise ModelError([f"columns: {quote(c)} is not in the data{suggest(c, table)}"
                          for c in missing] or
                         [f"data: no column is a probe quantity or state of "
                          f"{system.model.name!r} (columns: {', '.join(table) or 'none'}; "
                          f"probe quantities: {', '.join(system.signal_names) or 'none'})"])
    cols, _, rows = output_channels(system, wanted)
    measured = np.column_stack([table[c] for c in cols])
    w = _weights(cols, measured, weights)
    p = plan.vector(values)
    lo = np.array([bounds[k][0] for k in names])
    hi = np.array([bounds[k][1] for k in names])
    start = np.clip(p[index], lo, hi)
    if len(t) * len(cols) <= len(index):
        raise ModelError(f"data: {len(t) * len(cols)} values cannot fit {len(index)} "
                         f"parameters (more data than parameters are needed)")
    f = Trajectory(plan, index, rows)
    memo = {}

    def solve(v):
        key = v.tobytes()
        if key not in memo:
            memo.clear()
            q = p.copy()
            q[index] = v
            Y, J = f.evaluate(q)
            n_out = len(rows)
            J = J.reshape(len(grid), n_out, -1)[skip:]
            memo[key] = (((Y[skip:] - measured) * w).ravel(),
                         (J * w[None, :, None]).reshape(-1, len(index)))
        return memo[key]
    try:
        out = optimize.least_squares(lambda v: solve(v)[0], start, jac=lambda v: solve(v)[1],
                                     bounds=(lo, hi), method="trf", x_scale="jac",
                                     max_nfev=max_nfev)
    except SimulationError as exc:
        raise SimulationError(f"fit: a trial of the parameters failed to integrate "
                              f"({exc})", reason=exc.reason) from None
    r, J = solve(out.x)
    m, n = r.size, len(index)
    s2 = float(r @ r) / (m - n)
    try:
        cov = s2 * np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        cov = np.full((n, n), np.inf)
    if not np.all(np.isfinite(cov)) or np.any(np.diag(cov) < 0):
        cov = np.full((n, n), np.inf)      # not identifiable from these data
    half = stats.t.ppf(0.5 + level / 2, m - n) * np.sqrt(np.diag(cov))
    interval = [(float(x - h), float(x + h)) for x, h in zip(out.x, half)]
    return Fit(names, out.x, cov, level, interval, math.sqrt(float(r @ r) / m), len(t),
               cols, bool(out.success), out.message, int(out.nfev))


def _known(system, column):
    try:
        output_channels(system, [column])
        return True
    except ModelError:
        return False


def _bounds(params):
    """name -> (low, high) with infinities for missing bounds."""
    if isinstance(params, str):
        params = [params]
    if not isinstance(params, dict):
        params = {k: None for k in params}
    out, problems = {}, []
    for name, b in params.items():
        lo, hi = (None, None) if b is None else tuple(b) if isinstance(b, (list, tuple)) \
            else (object(), None)
        if not isinstance(lo, (int, float, type(None))) or not isinstance(
                hi, (int, float, type(None))):
            problems.append(f"params.{name}: bounds are (low, high), numbers or None, got "
                            f"{quote(b)}")
            continue
        lo = -np.inf if lo is None else float(lo)
        hi = np.inf if hi is None else float(hi)
        if not lo < hi:
            problems.append(f"params.{name}: the low bound {lo:g} must be below the high "
                            f"bound {hi:g}")
        out[name] = (lo, hi)
    if problems:
        raise ModelError(problems)
    return out


def _weights(cols, measured, weights):
    weights = dict(weights or {})
    bad = [k for k in weights if k not in cols]
    if bad:
        raise ModelError(f"weights: {quote(bad[0])} is not a fitted column"
                         f"{suggest(bad[0], cols)}")
    rms = np.sqrt(np.mean(measured ** 2, axis=0))
    return np.array([float(weights[c]) if c in weights else 1.0 / (r if r > 0 else 1.0)
                     for c, r in zip(cols, rms)])


def _read(data):
    """(t, {column: values}) from a CSV file or a mapping."""
    if isinstance(data, dict):
        table = {str(k): np.asarray(v, dtype=float).ravel() for k, v in data.items()}
        where = "data"
    else:
        path = pathlib.Path(data)
        try:
            text = path.read_text()
        except OSError as exc:
            raise ModelError(f"data: cannot read {quote(str(data))}: {exc.strerror}") from None
        where = str(path)
        lines = [ln for ln in text.splitlines() if ln.strip() and not ln.startswith("#")]
        rows = list(csv.reader(io.StringIO("\n".join(lines))))
        if len(rows) < 2:
            raise ModelError(f"{where}: expected a header row and data rows")
        header, body = rows[0], rows[1:]
        try:
            values = np.array([[float(v) for v in row] for row in body], dtype=float)
        except ValueError as exc:
            raise ModelError(f"{where}: not a number in the data rows ({exc})") from None
        if values.ndim != 2 or values.shape[1] != len(header):
            raise ModelError(f"{where}: every row must have {len(header)} values, as the "
                             f"header")
        table = {h.strip(): values[:, k] for k, h in enumerate(header)}
    if "t" not in table:
        raise ModelError(f"{where}: no column 't' (the times)")
    t = table.pop("t")
    if any(len(v) != len(t) for v in table.values()):
        raise ModelError(f"{where}: every column must have as many values as 't'")
    if len(t) < 2 or t[0] < 0 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
        raise ModelError(f"{where}: the times 't' must increase from t >= 0")
    bad = [k for k, v in table.items() if not np.all(np.isfinite(v))]
    if bad:
        raise ModelError(f"{where}: column {bad[0]!r} holds values that are not finite")
    return t, table
