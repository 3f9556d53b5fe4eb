"""The layout of the probe plots, whatever draws them: which panels, in which rows, with what
titles, labels, ticks and margins.

Two renderers draw the same figure: ``plot.py`` with matplotlib (any run, any format) and
``quickplot.py`` with Pillow (the command line's PNG, ten times faster). Both read the
decisions from here, so a figure looks the same from either; each only measures its own
texts and draws. The layout follows the seed paper's probe figures (a joint probe's angle,
speed, acceleration and torque side by side in one row); probes with fewer quantities share
rows, so a figure is not mostly empty. Nothing here imports a drawing library.
"""

import math

import numpy as np

from .errors import ModelError
from .util import suggest

#: a probe with more quantities than this wraps onto further rows (a frame probe has eight)
MAX_COLUMNS = 4
#: inches of a figure: per column and row of panels, and for what surrounds them
PANEL_WIDTH, PANEL_HEIGHT = 3.5, 2.4
BASE_WIDTH, BASE_HEIGHT = 0.4, 0.3
TITLE_HEIGHT, LEGEND_HEIGHT, NOTE_HEIGHT = 0.4, 0.3, 0.3
#: room around the measured texts [points]: between them, and at the figure's edges
GAP, EDGE = 4.0, 5.0
TIME_LABEL = "time [s]"
#: matplotlib's AutoLocator steps, and the minus sign its tick labels use
STEPS = (1.0, 2.0, 2.5, 5.0, 10.0)
MINUS = "\u2212"
_SUPERSCRIPTS = {"^-1": "\u207b\u00b9", "^2": "\u00b2", "^3": "\u00b3"}


def unit_label(unit):
    """A unit as it reads on an axis: "rad/s^2" -> "rad/s²", "N*m" -> "N·m"."""
    for plain, sup in _SUPERSCRIPTS.items():
        unit = unit.replace(plain, sup)
    return unit.replace("*", "\u00b7")


class Panel:
    """One panel: the signal it draws (a full name), its title and its axis label, read from
    the signal's descriptor (probe, quantity, the port measured, unit)."""

    def __init__(self, results, name):
        self.name = name
        probe, _, quantity = name.rpartition(".")
        sig = results.signals.get(name)
        unit = results.units.get(name, "")
        if sig is not None:
            probe, quantity = sig.probe, sig.quantity
            target = results.probe_targets.get(probe)
            where = f" ({target})" if target else ""
            self.title = f"{probe}{where}: {quantity.replace('_', ' ')}"
        else:                                   # a state
            self.title = name
            quantity = quantity or name
        self.probe = probe
        self.ylabel = quantity.replace("_", " ") + f" [{unit_label(unit) if unit else '1'}]"


def panel_names(results, selection):
    """The full names of the panels, in order: every probe's quantities by default; a probe
    name gives all of its quantities, ``probe.quantity`` (or a state's name) one panel."""
    available = results.probes
    if not available and not selection:
        raise ModelError("nothing to plot: the model has no probes (add a kn.Probe and "
                         "connect it to the port to record)")
    if not selection:
        return [f"{p}.{q}" for p, qs in available.items() for q in qs]
    names = []
    for item in selection:
        if not isinstance(item, str):
            raise ModelError(f"plot: a probe or signal is named by a string, got {item!r:.60}")
        if item in available:
            names += [f"{item}.{q}" for q in available[item]]
        elif item in results.signals or item in results.state_names:
            names.append(item)
        else:
            known = [*available, *results.signals, *results.state_names]
            raise ModelError(f"plot: no probe or signal {item!r}{suggest(item, known)}; probes "
                             f"are {', '.join(available) or 'none'}")
    return names


def rows(results, names, columns=None):
    """The panels' names row by row, and the number of columns. Each probe's quantities stay
    together, left to right (one row per joint probe); probes with fewer quantities than a
    row holds share rows, in order, so a figure is not mostly empty; one with more wraps."""
    groups = []                                  # consecutive names of one probe
    for name in names:
        sig = results.signals.get(name)
        key = sig.probe if sig is not None else name
        if groups and groups[-1][0] == key:
            groups[-1][1].append(name)
        else:
            groups.append((key, [name]))
    n = len(names)
    widest = max(len(g) for _, g in groups)
    n_cols = columns or min(MAX_COLUMNS, max(widest, -(-n // -(-n // MAX_COLUMNS))))
    out = [[]]
    for _, group in groups:
        if len(group) > n_cols - len(out[-1]) and out[-1]:
            out.append([])
        for name in group:
            if len(out[-1]) == n_cols:
                out.append([])
            out[-1].append(name)
    return out, n_cols


def is_flat(values):
    """Whether a signal never changes over the run (to the last bits): a dead panel."""
    values = np.asarray(values, dtype=float)
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return False
    return float(np.ptp(finite)) <= 1e-12 * (1.0 + float(np.max(np.abs(finite))))


def drop_flat(runs, wanted):
    """(kept, hidden): the names of signals that change in some run, and of those that do
    not (``hide_flat``); a ModelError when nothing would be left to draw."""
    kept = [n for n in wanted if not all(is_flat(run[n]) for run in runs)]
    if not kept:
        raise ModelError(f"plot: every signal asked for is constant ({', '.join(wanted[:4])}"
                         f"{', ...' if len(wanted) > 4 else ''}); plot without hide_flat")
    return kept, [n for n in wanted if n not in kept]


def flat_note(results, hidden):
    """The line under a figure naming the constant signals left out, and their value."""
    if not hidden:
        return ""
    shown = [f"{n} = {float(np.ravel(results[n])[0]):.4g}" for n in hidden[:6]]
    more = f" and {len(hidden) - 6} more" if len(hidden) > 6 else ""
    return "constant, not drawn: " + ", ".join(shown) + more


def figure_size(n_cols, n_rows, title=False, legend=False, note=False):
    """(width, height) in inches: the panels, and room for a title, a legend of runs and a
    note when there are."""
    extra = (TITLE_HEIGHT if title else 0.0) + (LEGEND_HEIGHT if legend else 0.0) + \
        (NOTE_HEIGHT if note else 0.0)
    return BASE_WIDTH + PANEL_WIDTH * n_cols, BASE_HEIGHT + PANEL_HEIGHT * n_rows + extra


def panel_boxes(size, left, right, above, below, headings=(), notes=()):
    """Where each panel goes: rows of (x0, y0, x1, y1) [points from the figure's top left,
    y down], every panel one size, each gap as wide as what it holds; None when the figure
    is too small for its texts.

    Parameters
    ----------
    size : (float, float)
        The figure's width and height [points].
    left, right : list of float
        Room each column needs left and right of its panels (tick labels and the axis
        label; a legend, the last time label's overhang) [points].
    above, below : list of float
        Room each row needs above and below its panels (the titles; the time axis) [points].
    headings, notes : sequence of float
        Heights of the texts over the panels (the figure's title, the legend of runs) and
        under them (the note of constant signals) [points].
    """
    width, height = size
    n_rows, n_cols = len(above), len(left)
    top = EDGE + sum(h + GAP for h in headings)
    bottom = EDGE + sum(h + GAP for h in notes)
    x0, x1 = left[0] + EDGE, width - right[-1] - EDGE
    y0, y1 = top + above[0], height - bottom - below[-1]
    wgaps = [right[j] + left[j + 1] + GAP for j in range(n_cols - 1)] + [0.0]
    hgaps = [below[i] + above[i + 1] + GAP for i in range(n_rows - 1)] + [0.0]
    panel_w = (x1 - x0 - sum(wgaps)) / n_cols
    panel_h = (y1 - y0 - sum(hgaps)) / n_rows
    if panel_w <= 0 or panel_h <= 0:
        return None
    lefts = [x0 + j * panel_w + sum(wgaps[:j]) for j in range(n_cols)]
    tops = [y0 + i * panel_h + sum(hgaps[:i]) for i in range(n_rows)]
    return [[(x, y, x + panel_w, y + panel_h) for x in lefts] for y in tops]


def last_in_column(rows_):
    """Column -> the row of its lowest panel: where the time axis is labelled (not always
    the last row, when that is not full)."""
    return {j: i for i, row in enumerate(rows_) for j in range(len(row))}


# -- ticks: matplotlib's defaults, for a renderer that has no locator of its own -------------

def nonsingular(low, high, expander=0.05):
    """matplotlib's ``nonsingular``: a range of zero width widened around its value."""
    if not (math.isfinite(low) and math.isfinite(high)):
        return -expander, expander
    biggest = max(abs(low), abs(high))
    if biggest < 1e-300 or high - low <= biggest * 1e-15:
        if low == 0 and high == 0 or biggest < 1e-300:
            return -expander, expander
        return low - expander * abs(low), high + expander * abs(high)
    return low, high


def time_limits(t):
    """The time axis's view limits: the run's span."""
    t = np.asarray(t, dtype=float)
    if len(t) > 1:
        return float(t[0]), float(t[-1])
    return padded(t)


def padded(values):
    """Autoscaled view limits: the finite data, widened by 5 % on each side."""
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    low, high = nonsingular(low, high)
    margin = 0.05 * (high - low)
    return nonsingular(low - margin, high + margin)


def nice_ticks(low, high, length, label_size, per_label):
    """matplotlib's AutoLocator (MaxNLocator, steps 1, 2, 2.5, 5, 10) on an axis ``length``
    points long: as many ticks as labels of ``label_size`` points fit, ``per_label`` sizes
    apart (3 on a time axis, 2 on a value axis), at most 10. Ticks may overhang the range."""
    n_bins = max(1, min(9, int(length // (label_size * per_label))))
    span = high - low
    mean = (low + high) / 2
    offset = 0.0
    if span > 0 and abs(mean) / span >= 100:
        offset = math.copysign(10 ** (math.log10(abs(mean)) // 1), mean)
    scale = 10 ** (math.log10(span / n_bins) // 1)
    lo, hi = low - offset, high - offset
    steps = [s * scale for s in (0.1, 0.2, 0.25, 0.5, *STEPS[:-1], 10.0, 20.0)]
    raw = (hi - lo) / n_bins
    first = next(k for k, s in enumerate(steps) if s >= raw)
    for step in reversed(steps[:first + 1]):
        base = (lo // step) * step
        tol = max(1e-10, abs(offset / step) * 1e-10 if offset else 1e-10)   # _Edge_integer
        k_low = _edge((lo - base) / step, tol, floor=True)
        k_high = _edge((hi - base) / step, tol, floor=False)
        ticks = np.arange(k_low, k_high + 1) * step + base
        if ((ticks <= hi) & (ticks >= lo)).sum() >= 2:
            break
    return ticks + offset


def _edge(x, tol, floor):
    near = round(x)
    if abs(x - near) < tol:
        return near
    return math.floor(x) if floor else math.ceil(x)


def tick_labels(ticks, low, high):
    """matplotlib's ScalarFormatter without offset: the labels of ``ticks`` (one number of
    decimals for all), and the "1e−6" written above the axis when they are scaled."""
    inside = [x for x in ticks if low - 1e-10 * (high - low) <= x <= high + 1e-10 * (high - low)]
    biggest = max((abs(x) for x in inside), default=0.0)
    oom = math.floor(math.log10(biggest)) if biggest else 0
    power = oom if oom <= -5 or oom >= 6 else 0
    locs = np.asarray(ticks if len(ticks) >= 2 else [*ticks, low, high], dtype=float)
    locs = locs / 10.0 ** power
    spread = float(np.ptp(locs)) or float(np.max(np.abs(locs))) or 1.0
    spread_oom = math.floor(math.log10(spread))
    decimals, thresh = max(0, 3 - spread_oom), 1e-3 * 10 ** spread_oom
    while decimals >= 0 and np.abs(locs - np.round(locs, decimals)).max() < thresh:
        decimals -= 1
    decimals += 1
    labels = []
    for x in np.asarray(ticks, dtype=float) / 10.0 ** power:
        text = f"{0.0 if abs(x) < 1e-8 else x:.{decimals}f}"
        labels.append(text.replace("-", MINUS))
    return labels, (f"1e{power}".replace("-", MINUS) if power else "")


class Axis:
    """One axis of a panel: view limits, the ticks inside them and their labels, for labels
    of ``label_size`` points on an axis ``length`` points long."""

    def __init__(self, low, high, length, per_label, label_size):
        self.low, self.high = low, high
        ticks = nice_ticks(low, high, length, label_size, per_label)
        labels, self.offset = tick_labels(ticks, low, high)
        span = 1e-10 * (high - low)
        kept = [(x, s) for x, s in zip(ticks, labels) if low - span <= x <= high + span]
        self.ticks = [x for x, _ in kept]
        self.labels = [s for _, s in kept]
