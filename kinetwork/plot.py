"""Probe plots drawn with matplotlib: one panel per recorded quantity, against time, units on
every axis; several runs overlay on the same panels.

Which panels, in which rows, with which titles, labels and margins is ``plotlayout``'s
(shared with the Pillow renderer of ``quickplot.py``); this module draws it. matplotlib is
imported only when a plot is asked for, so ``import kinetwork`` stays fast and never touches
a display.
"""

import os
import sys

import numpy as np

from . import plotlayout as layout
from .errors import ModelError
from .plotlayout import unit_label  # noqa: F401 -- kinetwork.plot.unit_label, as before
from .util import atomic_write, callable_module

_AXES = "xyz"


def pyplot():
    """pyplot, on the Agg backend when there is no display to open windows on."""
    import matplotlib
    headless = (sys.platform.startswith("linux") and not os.environ.get("DISPLAY")
                and not os.environ.get("WAYLAND_DISPLAY"))
    # Only choose a backend when nobody has: a notebook or the user's MPLBACKEND wins.
    if headless and "matplotlib.pyplot" not in sys.modules and not os.environ.get("MPLBACKEND"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def plot_results(results, *names, probes=None, title=None, labels=None, hide_flat=False,
                 columns=None, figsize=None, _detached=False, **kwargs):
    """Plot probe signals against time, one panel per quantity, units on every axis.

    Parameters
    ----------
    results : kinetwork.Results or sequence of Results
        One run, or several to overlay (same panels, one colour per run).
    *names : str
        What to plot, in this order: a probe (all its quantities), ``"probe1.angle"`` (one
        quantity) or a state's name. Default: every probe.
    probes : str or sequence of str, optional
        Probe names (the older spelling of ``names``).
    title : str, optional
        Figure title, e.g. the model name.
    labels : sequence of str, optional
        One label per run in the figure's legend (default: run 1, run 2, ... or the method).
    hide_flat : bool
        Leave out panels whose signal never changes (the seed's elbow torque is 0); a note
        under the figure names them and their value.
    columns : int, optional
        Panels per row (default: up to four; each probe's quantities side by side, the
        seed paper's layout, probes with few quantities sharing rows).
    figsize : (float, float), optional
        Inches; by default it grows with the number of rows and columns.
    **kwargs
        Passed to every ``Axes.plot`` call (``linewidth``, ``color``, ...).

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ModelError
        Nothing to plot, an unknown name, labels not matching the runs, or runs that do not
        all hold a signal asked for.
    """
    runs = list(results) if isinstance(results, (list, tuple)) else [results]
    if not runs:
        raise ModelError("plot: no results given")
    if probes is not None:
        names = names + ((probes,) if isinstance(probes, str) else tuple(probes))
    if len(names) == 1 and isinstance(names[0], (list, tuple)):
        names = tuple(names[0])
    wanted = layout.panel_names(runs[0], names)
    for k, run in enumerate(runs[1:], start=2):
        missing = [n for n in wanted if n not in run]
        if missing:
            raise ModelError(f"plot: run {k} has no {', '.join(missing[:3])}: overlaid runs must "
                             f"record the signals plotted")
    if labels is not None and len(labels) != len(runs):
        raise ModelError(f"plot: {len(labels)} labels for {len(runs)} runs")
    if labels is None and len(runs) > 1:
        labels = [f"run {k + 1}" for k in range(len(runs))]
    hidden = []
    if hide_flat:
        wanted, hidden = layout.drop_flat(runs, wanted)
    rows, n_cols = layout.rows(runs[0], wanted, columns)
    n_rows = len(rows)
    if figsize is None:
        figsize = layout.figure_size(n_cols, n_rows, title=bool(title), legend=len(runs) > 1,
                                     note=bool(hidden))
    if _detached:
        # for a file: no pyplot, no window, nothing to close; and no layout engine, whose
        # extra pass over every tick doubled the time to draw: margins are measured below
        from matplotlib.figure import Figure
        fig = Figure(figsize=figsize)
        axes = fig.subplots(n_rows, n_cols, sharex=True, squeeze=False)
    else:
        fig, axes = pyplot().subplots(n_rows, n_cols, figsize=figsize, sharex=True,
                                       squeeze=False, layout="constrained")
    bottom = layout.last_in_column(rows)
    placed = [(i, j, layout.Panel(runs[0], name)) for i, row in enumerate(rows)
              for j, name in enumerate(row)]
    for i, j, panel in placed:
        ax = axes[i, j]
        for r, run in enumerate(runs):
            style = dict(kwargs)
            if len(runs) > 1:
                style.setdefault("color", f"C{r}")
                style.setdefault("label", labels[r])
            _draw(ax, run.t, run[panel.name], style, legend=r == len(runs) - 1,
                  overlaid=len(runs) > 1)
        ax.set_title(panel.title, fontsize="medium")
        ax.set_ylabel(panel.ylabel)
        _event_marks(ax, runs)
    for i, row in enumerate(rows):
        for j in range(len(row), n_cols):
            axes[i, j].set_visible(False)
    for i in range(n_rows):
        for j in range(n_cols):
            # shared x: tick labels only where the column ends, which is not always the
            # last row when the last row is not full
            axes[i, j].tick_params(labelbottom=bottom.get(j) == i)
    for j, i in bottom.items():
        axes[i, j].set_xlabel(layout.TIME_LABEL)
    t = runs[0].t
    if len(t) > 1:                  # a run that failed at once has a single point
        axes[0, 0].set_xlim(min(r.t[0] for r in runs), max(r.t[-1] for r in runs))
    legend = heading = note = None
    if len(runs) > 1:
        from matplotlib.lines import Line2D
        handles = [Line2D([], [], color=f"C{r}", label=labels[r]) for r in range(len(runs))]
        legend = fig.legend(handles=handles, loc="outside upper center",
                            ncols=min(len(runs), 6), fontsize="small", frameon=False)
    if title:
        heading = fig.suptitle(title)
    if hidden:
        note = fig.text(0.01, 0.002, layout.flat_note(runs[0], hidden),
                        fontsize="x-small", color="0.35", ha="left", va="bottom")
    if _detached:
        _fit_margins(fig, axes, rows, heading, legend, note)
    return fig


def _fit_margins(fig, axes, rows, heading, legend, note):
    """Place the panels of a figure drawn without a layout engine: margins and gaps are the
    measured sizes of what surrounds the panels (titles, tick labels, axis labels, legends),
    so nothing overlaps and little space is lost, at the cost of laying out a few texts
    instead of a whole drawing pass (``plotlayout.panel_boxes`` places them)."""
    import matplotlib as mpl
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.font_manager import FontProperties

    renderer = FigureCanvasAgg(fig).get_renderer()
    points = 72.0 / fig.dpi                     # pixels of this renderer -> points

    def size(artist):
        if artist is None or not artist.get_visible() or \
                not getattr(artist, "get_text", lambda: "-")():
            return 0.0, 0.0
        box = artist.get_window_extent(renderer)
        return box.width * points, box.height * points

    def tick_labels(axis, name):
        """Width and height [points] of the widest tick label the axis will draw."""
        _ = axis.axes.viewLim                   # brings the view limits up to date
        low, high = sorted(axis.get_view_interval())
        span = (high - low) * 1e-10
        locs = [x for x in axis.get_major_locator()() if low - span <= x <= high + span]
        formatter = axis.get_major_formatter()
        font = FontProperties(size=mpl.rcParams[f"{name}.labelsize"])
        widest = (0.0, 0.0)
        for label in formatter.format_ticks(locs):
            w, h, _ = renderer.get_text_width_height_descent(label, font, ismath=False)
            widest = max(widest, (w * points, h * points))
        offset = formatter.get_offset() if hasattr(formatter, "get_offset") else ""
        return widest, offset

    tick = {name: mpl.rcParams[f"{name}.major.size"] + mpl.rcParams[f"{name}.major.pad"]
            for name in ("xtick", "ytick")}
    pad = mpl.rcParams["axes.labelpad"]
    n_rows, n_cols = axes.shape
    left = [0.0] * n_cols                       # room left of each column [points]
    right = [0.0] * n_cols                      # room right of each column
    above = [0.0] * n_rows                      # room above each row
    below = [0.0] * n_rows                      # room below each row
    for i, row in enumerate(rows):
        for j in range(len(row)):
            ax = axes[i, j]
            (label_w, label_h), offset = tick_labels(ax.yaxis, "ytick")
            left[j] = max(left[j], label_w + tick["ytick"] + pad + size(ax.yaxis.label)[0])
            offset_h = label_h if offset else 0.0
            above[i] = max(above[i], size(ax.title)[1] + mpl.rcParams["axes.titlepad"]
                           + offset_h)
            if ax.get_legend() is not None:     # x/y/z legends sit right of the panel
                width = size(ax.get_legend())[0]
                right[j] = max(right[j], width + 0.01 * _panel_width(fig, axes) * 72.0)
            under = tick["xtick"] - mpl.rcParams["xtick.major.pad"]   # the tick marks
            if ax.xaxis.get_label_text() and ax.xaxis.label.get_visible():
                (w, h), _ = tick_labels(ax.xaxis, "xtick")
                under = h + tick["xtick"] + pad + size(ax.xaxis.label)[1]
                if j == n_cols - 1 or not rows[i][j + 1:]:
                    right[j] = max(right[j], w / 2)     # the last time label overhangs
            below[i] = max(below[i], under)
    width, height = (v * 72.0 for v in fig.get_size_inches())
    boxes = layout.panel_boxes((width, height), left, right, above, below,
                               [size(t)[1] for t in (heading, legend) if t is not None],
                               [size(note)[1]] if note is not None else [])
    if boxes is None:                           # a figure too small for its texts
        return
    for i in range(n_rows):
        for j in range(n_cols):
            x0, y0, x1, y1 = boxes[i][j]        # from the top: matplotlib's y is up
            axes[i, j].set_position([x0 / width, 1.0 - y1 / height, (x1 - x0) / width,
                                     (y1 - y0) / height])
    edge = 1.0 - layout.EDGE / height
    if heading is not None:
        heading.set_y(edge)
        edge -= (size(heading)[1] + layout.GAP) / height
    if legend is not None:
        legend.set_loc("upper center")
        legend.set_bbox_to_anchor((0.5, edge), transform=fig.transFigure)
    if note is not None:
        note.set_position((layout.EDGE / width, layout.EDGE / height))


def _panel_width(fig, axes):
    """A panel's width [inches] before the margins are fitted (for a small relative gap)."""
    return fig.get_size_inches()[0] / axes.shape[1]


def plot(results, *names, **kwargs):
    """``kn.plot(res)`` or ``kn.plot([res_a, res_b], labels=["stiff", "soft"])``: probe plots
    of one run or of several overlaid (see :func:`plot_results` for the options)."""
    return plot_results(results, *names, **kwargs)


def _draw(ax, t, values, kwargs, legend=True, overlaid=False):
    """One panel: a line, three lines x/y/z, or the nine entries of an orientation. Legends
    of components sit outside the axes, right of them, so they never cover the data; with
    several runs, colour is the run and line style the component."""
    values = np.asarray(values)
    if values.ndim == 1:
        ax.plot(t, values, **kwargs)
    elif values.ndim == 2:
        styles = ("-", "--", ":")
        for k in range(values.shape[1]):
            style = {"linestyle": styles[k % 3]} if overlaid else {"color": f"C{k}"}
            ax.plot(t, values[:, k], **{**style, **kwargs, "label": _AXES[k % 3]})
        if legend:
            _outside_legend(ax, overlaid)
    else:
        # colour = column of R (the image of one body axis), line style = its component,
        # so the nine curves stay apart and read as three unit vectors
        styles = ("-", "--", ":")
        for c in range(3):
            for r in range(3):
                style = {"linestyle": styles[r], "color": f"C{c}"}
                ax.plot(t, values[:, r, c], **{**style, **kwargs, "label": f"R{r + 1}{c + 1}"})
        ax.set_ylim(-1.1, 1.1)
        if legend:
            _outside_legend(ax, overlaid)
    ax.grid(True, alpha=0.4)
    # a constant signal (the seed's elbow torque is 0) must not read as "1e-16 + offset"
    ax.ticklabel_format(axis="y", useOffset=False)


def _outside_legend(ax, overlaid):
    handles, labels = ax.get_legend_handles_labels()
    seen = {}
    for h, lab in zip(handles, labels):
        if overlaid:            # one entry per component, drawn in black
            h = type(h)([], [], linestyle=h.get_linestyle(), color="0.2")
        seen.setdefault(lab, h)
    ax.legend(list(seen.values()), list(seen), fontsize="x-small", loc="upper left",
              bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, handlelength=1.4,
              labelspacing=0.2, frameon=False)


#: formats every matplotlib since 3.6 writes: checked without importing matplotlib (half a
#: second); any other extension is asked of matplotlib itself
FORMATS = frozenset({"eps", "jpeg", "jpg", "pdf", "pgf", "png", "ps", "raw", "rgba", "svg",
                     "svgz", "tif", "tiff", "webp"})


def check_plot_path(path):
    """Refuse (ModelError) a file name whose extension is no image format matplotlib writes.

    Called before a simulation, so a typo in ``--plot`` costs nothing.
    """
    fmt = os.path.splitext(str(path))[1].lstrip(".").lower()
    if fmt in FORMATS:
        return
    from matplotlib.backend_bases import FigureCanvasBase
    supported = FigureCanvasBase.get_supported_filetypes()
    if fmt not in supported:
        what = f"as {fmt!r}" if fmt else "without a file extension"
        raise ModelError(f"{path}: cannot write a plot {what}; formats: "
                         f"{', '.join(sorted(supported))}")


def save_plot(results, path, *names, probes=None, title=None, dpi=150, **kwargs):
    """Plot ``results`` (see :func:`plot_results`) into an image file and close the figure.

    The format follows the file extension (png, pdf, svg, ...).

    Raises
    ------
    ModelError
        The extension is not an image format matplotlib writes.
    OSError
        The file cannot be written.
    """
    check_plot_path(path)
    # a figure pyplot never sees: no backend to start (the quick first answer of
    # ``kinetwork run --plot``), and nothing left open if writing fails
    fig = plot_results(results, *names, probes=probes, title=title, _detached=True, **kwargs)
    fmt = os.path.splitext(str(path))[1].lstrip(".").lower()
    # zlib level 1 instead of Pillow's 6: half the time to encode, 10 % larger (the seed's
    # 2160 x 825 plot: 0.13 s and 257 KiB against 0.24 s and 230 KiB)
    options = {"pil_kwargs": {"compress_level": 1}} if fmt == "png" else {}
    # atomically: a full disk or a signal leaves an old image whole
    atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=dpi, format=fmt, **options))


def warm_up():
    """Import what ``save_plot`` draws with and load its font, by drawing a small figure:
    done by ``kinetwork run --plot``'s drawing process while the model runs."""
    import io

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=(2.0, 1.5))
    ax = fig.subplots()
    ax.plot([0.0, 1.0], [0.0, -1.0])
    ax.set_title("probe (joint.axis): angle", fontsize="medium")
    ax.set_ylabel("angle [rad]")
    fig.suptitle("model")
    FigureCanvasAgg(fig).print_png(io.BytesIO())


def _event_marks(ax, runs):
    """The runs' events (friction sticking or slipping, impacts: ``res.stats["events"]``) as
    thin dotted vertical lines, in the run's colour when runs are overlaid."""
    for r, run in enumerate(runs):
        for event in (getattr(run, "stats", None) or {}).get("events", ()):
            ax.axvline(event["t"], color=f"C{r}" if len(runs) > 1 else "0.55",
                       linewidth=0.6, linestyle=":", gid=f"event:{event['component']}")


callable_module(__name__, plot)
