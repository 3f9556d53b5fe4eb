"""An estimate of a run's global error, delivered with its answer (``simulate(...,
error_estimate=True)``).

The run is made again on the same compiled System with TIGHTER times smaller tolerances (a
fixed-step method: half the step), and again with TIGHTER^2 times smaller ones. With the
tolerance proportional to the global error (``tolerance.py``), the first repetition is about
TIGHTER times more accurate than the run, so their difference is the run's error to within
about 1 / TIGHTER: that difference, the largest over the run, is the estimate of each signal.

The repetitions step at most the output spacing (and 1 / STEPS_SEEN of the run): a run
whose steps passed over an input that nothing announced (a pulse in ``noEvent``, a smooth
bump between two steps) differs from them by what it missed, so its estimate is never 0.

The second repetition checks the first. Where the two repetitions differ by more than
1 / MARGIN of what the run and the first repetition differ by (and by a visible part of the
motion, SATURATED^2 of its range), the first one is no longer much more accurate than the run,
and the estimate means nothing from there on: the signal's ``valid_until``. On a chaotic motion every difference grows tenfold in a fixed time until it
is as large as the motion itself, so the repetitions' difference catches up with the run's
some time after the run's error has become as large as the signal; and once the run's
estimated error is SATURATED of the signal's range, it is only a lower bound (an error cannot
grow past the motion's size): from there too the estimate means nothing.
"""

import itertools

import numpy as np

from .methods import METHODS
from .tolerance import solver_tolerances

#: how many times tighter the tolerances of each repetition are (fixed steps: 2 x smaller)
TIGHTER = 10.0
#: the estimate stands while the repetitions agree MARGIN times better than run and repetition
MARGIN = 1.5
#: differences below this (relative to the signal's largest value) are round-off
NOISE = 1e-13
#: differences below this fraction of the estimate do not count against it
SMALL = 0.1
#: an error this large a fraction of the signal's range over the run has saturated (the run
#: and its repetitions have parted ways): from there the estimate is only a lower bound
SATURATED = 0.1
#: the repetitions of a variable-step run take at least this many steps over it (and step
#: at most the output spacing): they see what the run's own steps may have passed over
STEPS_SEEN = 1000


def attach(results, again):
    """Put the estimate into ``results.stats["error_estimate"]``.

    ``again(**settings)`` runs the same simulation with ``rtol`` and ``atol`` (or ``step``)
    replaced, and returns its Results. The estimate holds ``runs`` (the settings of the
    repetitions), ``signals`` (per probe signal and state: ``error``, the largest estimated
    error over the run [its unit]; ``at``, when; ``valid_until``, None or the time from which
    the estimate means nothing), ``valid_until`` (the earliest of those) and ``note``.
    """
    settings = results.settings
    if settings.get("step") is not None or settings.get("method") in ("rk", "collocation",
                                                                     "midpoint"):
        h = float(settings.get("step") or (results.t[1] - results.t[0]))
        runs = [{"step": h / 2}, {"step": h / 4}]
    else:
        t = results.t
        bound = min(float(t[1] - t[0]) if len(t) > 1 else np.inf,
                    (settings["t_end"] - settings["t_start"]) / STEPS_SEEN,
                    settings.get("max_step") or np.inf)
        runs = [{"rtol": settings["rtol"] / TIGHTER ** k, "atol": settings["atol"] / TIGHTER ** k,
                 "max_step": bound} for k in (1, 2)]
    tighter = _tighter(results, runs)
    if not tighter[0]:
        note = ("no estimate: the solver's tolerance is at its smallest already "
                "(tolerance.RTOL_FLOOR); ask a larger rtol for one")
        results.stats["error_estimate"] = {
            "runs": [], "valid_until": None, "note": note,
            "signals": {name: {"error": None, "at": None, "valid_until": None}
                        for name in [*results.signals, *results.state_names]}}
        return results.stats["error_estimate"]
    finer, finest = again(**runs[0]), again(**runs[1])
    t = results.t
    signals, earliest = {}, None
    for name in [*results.signals, *results.state_names]:
        d1 = _difference(results[name], finer[name])
        d2 = _difference(finer[name], finest[name])
        k = int(np.argmax(d1))
        # below this, differences are round-off, or too small to change the estimate
        floor = max(NOISE * max(1.0, float(np.max(np.abs(results[name])))), SMALL * d1[k])
        # running maxima: an error once made is not undone by a crossing of the curves
        m1, m2 = np.maximum.accumulate(d1), np.maximum.accumulate(d2)
        values = np.asarray(results[name], float).reshape(len(t), -1)
        spread = float(np.max(np.ptp(values, axis=0))) if len(t) else 0.0
        apart = (m2 > m1 / MARGIN) if tighter[1] else np.zeros(len(t), bool)
        # the repetitions parting only counts once it is a visible part of the motion: at
        # tight tolerances, differences near round-off part ways without meaning anything
        apart &= m2 > max(floor, SATURATED ** 2 * spread)
        bad = np.flatnonzero(apart | ((m1 > SATURATED * spread) & (m1 > floor)))
        until = float(t[bad[0]]) if len(bad) else None
        signals[name] = {"error": float(d1[k]), "at": float(t[k]), "valid_until": until}
        if until is not None and (earliest is None or until < earliest):
            earliest = until
    note = (f"the estimate means nothing after t = {earliest:g} s: the errors there are as "
            f"large as the motion, or runs at tighter tolerances no longer agree better with "
            f"each other than with this run (chaotic motion)" if earliest is not None else
            "the estimate holds over the whole run")
    if not tighter[1]:
        note += ("; unchecked: the solver's tolerance of the second repetition is at its "
                 "smallest (tolerance.RTOL_FLOOR)")
    results.stats["error_estimate"] = {"runs": runs, "signals": signals,
                                       "valid_until": earliest, "note": note}
    return results.stats["error_estimate"]


def _tighter(results, runs):
    """Whether the solver's tolerance of each repetition is TIGHTER times that of the run
    before it, or its floor (``tolerance.RTOL_FLOOR``) stopped it short."""
    method = METHODS.get(results.settings.get("method"))
    if "rtol" not in runs[0] or results.system is None or \
            not getattr(method, "sundials", False):
        return True, True
    asked = [(results.settings["rtol"], results.settings["atol"]),
             *((r["rtol"], r["atol"]) for r in runs)]
    horizon = results.settings["t_end"] - results.settings["t_start"]
    given = [solver_tolerances(method, results.system, *a, horizon)[0] for a in asked]
    return tuple(b <= a / TIGHTER * (1 + 1e-9) for a, b in itertools.pairwise(given))


def _difference(a, b):
    """|a - b| at each output time, the largest over a vector's or matrix's entries."""
    d = np.abs(np.asarray(a, float) - np.asarray(b, float))
    return d.reshape(len(d), -1).max(axis=1) if d.ndim > 1 else d


def summary(estimate, names, limit=8):
    """Lines for the command line's summary: the estimates of the signals ``names`` (the
    probes'), in their order."""
    rows = [(name, estimate["signals"][name]) for name in names
            if estimate["signals"][name]["error"] is not None]
    lines = [f"  {name}: {e['error']:.2g} (at t = {e['at']:g} s)"
             + (f", meaningless after t = {e['valid_until']:g} s" if e["valid_until"] is not None
                else "") for name, e in rows[:limit]]
    if len(rows) > limit:
        lines.append(f"  ... and {len(rows) - limit} more (results.stats['error_estimate'])")
    return ["estimated global error (max over the run):", *lines, f"  {estimate['note']}"]
