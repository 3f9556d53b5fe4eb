"""Probe plots: one row per probe, one panel per recorded quantity, against time.

The layout follows the seed paper's probe figures (angle, speed, acceleration and torque of a
joint side by side). matplotlib is imported only when a plot is asked for, so ``import
kinetwork`` stays fast and never touches a display.
"""

import os
import sys

from .util import atomic_write, suggest
from .errors import ModelError
from .simulation.results import install_plotter

#: a probe with more quantities than this wraps onto further rows (a frame probe has eight)
MAX_COLUMNS = 4
_AXES = "xyz"
_SUPERSCRIPTS = {"^-1": "\u207b\u00b9", "^2": "\u00b2", "^3": "\u00b3"}


def _pyplot():
    """pyplot, on the Agg backend when there is no display to open windows on."""
    import matplotlib
    headless = (sys.platform.startswith("linux") and not os.environ.get("DISPLAY")
                and not os.environ.get("WAYLAND_DISPLAY"))
    # Only choose a backend when nobody has: a notebook or the user's MPLBACKEND wins.
    if headless and "matplotlib.pyplot" not in sys.modules and not os.environ.get("MPLBACKEND"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def unit_label(unit):
    """A unit as it reads on an axis: "rad/s^2" -> "rad/s²", "N*m" -> "N·m"."""
    for plain, sup in _SUPERSCRIPTS.items():
        unit = unit.replace(plain, sup)
    return unit.replace("*", "\u00b7")


def _panels(results, probes):
    """The rows of the figure: lists of (probe, quantity), MAX_COLUMNS at most per row."""
    available = results.probes
    if not available:
        raise ModelError("nothing to plot: the model has no probes (add a kn.Probe and "
                         "connect it to the port to record)")
    if probes is None:
        probes = list(available)
    elif isinstance(probes, str):
        probes = [probes]
    rows = []
    for name in probes:
        if name not in available:
            raise ModelError(f"plot: no probe {name!r}{suggest(name, available)}; probes are "
                             f"{', '.join(available)}")
        quantities = available[name]
        for start in range(0, len(quantities), MAX_COLUMNS):
            rows.append([(name, q) for q in quantities[start:start + MAX_COLUMNS]])
    return rows


def plot_results(results, probes=None, title=None, figsize=None, **kwargs):
    """Plot probe signals against time: one row per probe, one panel per quantity.

    Parameters
    ----------
    results : kinetwork.Results
    probes : str or sequence of str, optional
        Probe names to plot, in this order (default: every probe).
    title : str, optional
        Figure title, e.g. the model name.
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
        The results hold no probes, or a probe name is unknown.
    """
    rows = _panels(results, probes)
    n_rows, n_cols = len(rows), max(len(r) for r in rows)
    plt = _pyplot()
    if figsize is None:
        figsize = (0.4 + 3.5 * n_cols, 0.3 + 2.4 * n_rows + (0.4 if title else 0.0))
    fig, axes = plt.subplots(n_rows, n_cols, figsize=figsize, sharex=True, squeeze=False,
                             layout="constrained")
    t = results.t
    bottom = {}                     # column -> lowest row holding a panel
    for i, row in enumerate(rows):
        for j, (probe, quantity) in enumerate(row):
            name = f"{probe}.{quantity}"
            _draw(axes[i, j], t, results[name], kwargs)
            unit = results.units.get(name, "")
            target = results.probe_targets.get(probe)
            where = f" ({target})" if target else ""
            axes[i, j].set_title(f"{probe}{where}: {quantity.replace('_', ' ')}",
                                 fontsize="medium")
            axes[i, j].set_ylabel(quantity.replace("_", " ")
                                  + (f" [{unit_label(unit)}]" if unit else ""))
            bottom[j] = i
        for j in range(len(row), n_cols):
            axes[i, j].set_visible(False)
    for i in range(n_rows):
        for j in range(n_cols):
            # shared x: tick labels only where the column ends, which is not always the
            # last row when probes record different numbers of quantities
            axes[i, j].tick_params(labelbottom=bottom.get(j) == i)
    for j, i in bottom.items():
        axes[i, j].set_xlabel("time [s]")
    if len(t) > 1:                  # a run that failed at once has a single point
        axes[0, 0].set_xlim(t[0], t[-1])
    if title:
        fig.suptitle(title)
    return fig


def _draw(ax, t, values, kwargs):
    """One panel: a line, three lines x/y/z, or the nine entries of an orientation."""
    if values.ndim == 1:
        ax.plot(t, values, **kwargs)
    elif values.ndim == 2:
        for k in range(values.shape[1]):
            ax.plot(t, values[:, k], **{"label": _AXES[k], **kwargs})
        ax.legend(fontsize="x-small", ncols=3, loc="best", handlelength=1.2,
                  columnspacing=0.8, borderpad=0.3)
    else:
        # colour = column of R (the image of one body axis), line style = its component,
        # so the nine curves stay apart and read as three unit vectors
        styles = ("-", "--", ":")
        for c in range(3):
            for r in range(3):
                style = {"linestyle": styles[r], "color": f"C{c}", "label": f"R{r + 1}{c + 1}"}
                ax.plot(t, values[:, r, c], **{**style, **kwargs})
        ax.set_ylim(-1.1, 1.1)
        ax.legend(fontsize="x-small", ncols=3, loc="best", handlelength=1.6,
                  columnspacing=0.6, borderpad=0.3, labelspacing=0.2)
    ax.grid(True, alpha=0.4)
    # a constant signal (the seed's elbow torque is 0) must not read as "1e-16 + offset"
    ax.ticklabel_format(axis="y", useOffset=False)


def check_plot_path(path):
    """Refuse (ModelError) a file name whose extension is no image format matplotlib writes.

    Called before a simulation, so a typo in ``--plot`` costs nothing.
    """
    from matplotlib.backend_bases import FigureCanvasBase
    fmt = os.path.splitext(str(path))[1].lstrip(".").lower()
    supported = FigureCanvasBase.get_supported_filetypes()
    if fmt not in supported:
        what = f"as {fmt!r}" if fmt else "without a file extension"
        raise ModelError(f"{path}: cannot write a plot {what}; formats: "
                         f"{', '.join(sorted(supported))}")


def save_plot(results, path, probes=None, title=None, dpi=150, **kwargs):
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
    plt = _pyplot()
    fig = plot_results(results, probes=probes, title=title, **kwargs)
    fmt = os.path.splitext(str(path))[1].lstrip(".").lower()
    try:
        # atomically: a full disk or a signal leaves an old image whole
        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=dpi, format=fmt))
    finally:
        plt.close(fig)


install_plotter(plot_results)
